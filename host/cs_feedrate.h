/* cs_feedrate: the speed a front end reports (Grbl's FS: feed) from timed position samples of
 * the device: the straight-line distance between the newest sample and the newest one at least
 * a window older, over their time difference (docs/controller.md, "FS"). Device-timed samples
 * (protocol 3's STATUS tick, the GPIO step thread's clock) give the device's own speed, however
 * late each report reaches the host; host-timed samples (Modbus, a protocol 2 device) are the
 * fallback, over a longer window. A short ring of samples, no allocation. Not thread-safe. */
#ifndef CS_FEEDRATE_H
#define CS_FEEDRATE_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_proto.h"

/* Samples kept: a STATUS every 50 ms over the longest window with room to spare. */
#define CS_FEEDRATE_RING 32
/* Window over device time, s: 1 step in 0.2 s at 20 mm/s and 80 steps/mm is 0.3 % */
#define CS_FEEDRATE_WINDOW_DEV_S 0.2
/* Window over host time, s: a sample's arrival jitter (a poll, a scheduler slice) over it */
#define CS_FEEDRATE_WINDOW_HOST_S 0.25
/* A device-clock step longer than this (s), or backwards: a new timeline (a reboot, an idle
 * executor), the window starts again */
#define CS_FEEDRATE_GAP_S 5.0

typedef struct {
    double t[CS_FEEDRATE_RING]; /* s: device time (unwrapped ticks) or host time */
    int32_t pos[CS_FEEDRATE_RING][CS_PROTO_AXES_MAX]; /* steps */
    unsigned n, head;                                 /* samples held; index of the newest */
    bool timed;                                       /* the samples are device-timed */
    uint32_t tick;                                    /* timed: the newest sample's tick */
} cs_feedrate_t;

/* Forgets every sample (a new timeline: device stopped, restarted, another link). */
void cs_feedrate_reset(cs_feedrate_t *f);
/* A device-timed sample: pos (steps) at tick (tick_hz a second, wraps at 2^32, >= 1 Hz). A
 * repeated tick adds nothing; a mix with host-timed samples restarts the ring. */
void cs_feedrate_add_tick(cs_feedrate_t *f, uint32_t tick, uint32_t tick_hz,
                          const int32_t pos[CS_PROTO_AXES_MAX]);
/* A host-timed sample: pos first seen at host time t_s (s). Kept only when pos changed or the
 * window passed without a change (so a stop reads 0). */
void cs_feedrate_add_host(cs_feedrate_t *f, double t_s, const int32_t pos[CS_PROTO_AXES_MAX]);
/* The speed in mm/min over the window, axes 0..axes-1 at steps_mm[i] steps/mm (> 0),
 * Euclidean; false (nothing written) while fewer than two samples of different time are held. */
bool cs_feedrate_mm_min(const cs_feedrate_t *f, unsigned axes, const double *steps_mm,
                        double *mm_min);

#endif
