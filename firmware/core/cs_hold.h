/* cs_hold: feed hold along the path, the one implementation every device uses (the firmware
 * application, hence the simulator, and the host's GPIO runner). A hold does not change a single
 * step: it re-times the step segments still to be handed to the executor, stretching each by
 * 1/s, where the speed scale s falls linearly in real time from 1 to 0 over the ramp time
 * T = 5/4 x the longest max_rate / max_accel of the axes, each segment run at its mean scale; the
 * device stops after the segment in which s reaches 0 (the rest waits, untouched). RESUME ramps s
 * back up from 0 to 1 at the same slope. Every axis moves at s times the job's speed, so the
 * ramp itself decelerates an axis by at most v ds/dt <= max_rate / T = 0.8 max_accel: the 20 %
 * left covers the staircase of constant-speed segments around the ramp's line, whose steps grow
 * as the segments stretch near rest (measured over 50 ms windows in tests/cli/test_hold.sh:
 * 1080 mm/s^2 for a 1000 mm/s^2 axis without the margin). The job's
 * own acceleration is scaled by s^2; both add when a hold lands while the job itself
 * decelerates hardest). Inside a segment the speed is constant: a start from rest jumps to the
 * first segment's mean speed, sqrt(2 tau / T) / 2 of the job's (about 1/10 for 5 ms segments and
 * T = 0.25 s). The position is exact: the segments' steps are never touched, each segment runs
 * once. What the executor's ring already holds runs at full speed first (CS_STEPPER_RING
 * segments: the hold's reaction time).
 * Overrides (OVERRIDE message, Grbl's feed override): outside a hold s ramps, at the same slope
 * 1/T, to a goal the caller gives per segment: the override's target (cs_hold_override) where it
 * applies, capped by the caller's feasibility limit above 1 (cs_fw_motion: only inside a stretch
 * of constant speed, braking back to 1 before its end; docs/controller.md "Overrides"), and 1
 * where it does not apply (jogs, homing, probing). Below 1 the bound is the hold's (the ramp's
 * 0.8 max_accel plus s^2 x the job's own); above 1 the job's own acceleration is 0 inside the
 * stretch, so the ramp's 0.8 max_accel is the whole bound.
 * Owns cs_hold_t; no heap, integer only. */
#ifndef CS_HOLD_H
#define CS_HOLD_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_err.h"
#include "cs_machine.h"
#include "cs_segment.h"

/* The speed scale, Q16: CS_HOLD_SCALE_ONE is full speed, 0 rest. */
#define CS_HOLD_SCALE_ONE ((uint32_t)1 << 16)
/* T = NUM / DEN x max_rate / max_accel (see above). */
#define CS_HOLD_RAMP_MARGIN_NUM 5u
#define CS_HOLD_RAMP_MARGIN_DEN 4u
/* Longest segment the executor takes (cs_segment_t invariant), ticks. */
#define CS_HOLD_MAX_TICKS ((uint32_t)1 << 24)
/* Highest override target, Q16 (20 x: CS_PROTO_OVERRIDE_MAX / CS_PROTO_OVERRIDE_ONE; the squares
 * stay below 2^41). */
#define CS_HOLD_SCALE_MAX ((uint32_t)20 << 16)

typedef struct {
    uint32_t ramp_ticks; /* T, ticks: time from full speed to rest */
    uint32_t scale;      /* s, Q16 */
    uint32_t target;     /* the override's s, Q16 (CS_HOLD_SCALE_ONE: none) */
    bool hold;           /* a hold is requested */
    bool stopped;        /* held at rest: segments are refused until the hold is released */
} cs_hold_t;

/* Full speed, no hold, the ramp time from the machine's axes. CS_ERR_ARG for a machine with no
 * axes or a zero limit. Not ISR-safe. */
cs_err_t cs_hold_init(cs_hold_t *h, const cs_machine_t *m);
/* Requests (on) or releases (off) the hold. Main loop. */
void cs_hold_set(cs_hold_t *h, bool on);
/* The override's target scale, Q16, clamped to 1..CS_HOLD_SCALE_MAX LSB. Main loop. */
void cs_hold_override(cs_hold_t *h, uint32_t target);
/* The goal of the next segment outside a hold: the target where the override applies (ov),
 * capped by cap (Q16, the caller's feasibility limit, >= CS_HOLD_SCALE_ONE), else full speed. */
uint32_t cs_hold_goal(const cs_hold_t *h, bool ov, uint32_t cap);
/* Forgets the hold and the scale (not the override's target): full speed (after an abort). */
void cs_hold_reset(cs_hold_t *h);
/* True when a hold is requested and the device has come to rest. */
bool cs_hold_stopped(const cs_hold_t *h);
/* True when s is below full speed (ramping down, stopped, or ramping up). */
bool cs_hold_active(const cs_hold_t *h);
/* Asks to hand *s to the executor now: true with s->ticks re-timed for the scale's ramp over
 * the segment (run at its mean scale; the scale advanced to the segment's end, moving towards
 * 0 in a hold, else towards goal (Q16) by at most the ramp's slope), false when the hold has
 * brought the device to rest (keep *s, untouched, for after the resume). The ticks never fall
 * below the largest |steps| (the executor's invariant). Main loop. */
bool cs_hold_admit_to(cs_hold_t *h, cs_segment_t *s, uint32_t goal);
/* cs_hold_admit_to with the goal full speed (no override). Main loop. */
bool cs_hold_admit(cs_hold_t *h, cs_segment_t *s);

#endif
