/* cs_machine: the machine description the motion modules (planner, segments, stepper) read.
 * Owns the per-axis limits and the motion formats: speeds in mm/s, accelerations in mm/s^2 and
 * steps per mm, all signed Q15.16 in int32 like positions, plus the executor's tick rate.
 * The host fills it from an INI file (host/cs_machine_ini.c); firmware can fill it by hand. */
#ifndef CS_MACHINE_H
#define CS_MACHINE_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_fixed.h"

/* Axes the motion modules carry: x, y, z and an optional a (n_axes = 3 or 4). */
#define CS_AXES 4
enum { CS_AXIS_X = 0, CS_AXIS_Y = 1, CS_AXIS_Z = 2, CS_AXIS_A = 3 };

/* Speed (mm/s), acceleration (mm/s^2) and steps per mm: Q15.16 in int32, 1.0 = CS_MOTION_ONE.
 * Accepted ranges are checked by cs_planner_init (see docs/motion.md). */
#define CS_MOTION_FRAC_BITS 16
#define CS_MOTION_ONE       ((int32_t)1 << CS_MOTION_FRAC_BITS)

typedef enum {
    CS_PROFILE_TRAPEZOID = 0, /* constant acceleration phases (Grbl) */
    CS_PROFILE_SCURVE = 1,    /* jerk-limited velocity transitions (see docs/motion.md) */
} cs_profile_t;

typedef struct {
    int32_t steps_per_mm; /* Q15.16 steps per mm, 1/16 .. 4096 */
    int32_t max_rate;     /* Q15.16 mm/s, > 0 */
    int32_t max_accel;    /* Q15.16 mm/s^2, > 0 */
    cs_pos_t travel_min;  /* soft limits, mm (Q15.16); a target outside is CS_ERR_LIMIT */
    cs_pos_t travel_max;
    bool invert_dir;      /* the port drives DIR low for positive motion */
    uint16_t pulse_ticks; /* step pulse width in executor ticks (>= 1) */
} cs_axis_cfg_t;

typedef struct {
    uint8_t n_axes;              /* 3 (x, y, z) or 4 (x, y, z, a) */
    cs_axis_cfg_t axis[CS_AXES]; /* axis[3] is ignored when n_axes == 3 */
    cs_pos_t tolerance;          /* chord tolerance for flattening, mm (Q15.16) */
    cs_pos_t junction_deviation; /* Grbl junction deviation delta, mm (Q15.16) */
    uint32_t tick_hz;            /* executor timer ticks per second, 1 kHz .. 16 MHz */
    uint32_t segment_ticks;      /* nominal step-segment duration, ticks (a few ms) */
    int32_t default_feed;        /* mm/s Q15.16, used when the job gives no F */
    cs_profile_t profile;        /* velocity profile of every block */
    int32_t max_jerk;            /* mm/s^3 (plain integer), used by CS_PROFILE_SCURVE */
} cs_machine_t;

#endif
