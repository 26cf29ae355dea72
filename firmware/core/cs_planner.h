/* cs_planner: the look-ahead motion planner. Owns a ring of CS_PLANNER_RING straight blocks
 * (chords), their feed and acceleration limits, the junction speeds between them (Grbl's junction
 * deviation and the curvature rule v^2 = a r) and the reverse/forward passes that make every
 * block's entry speed reachable and the whole queue stoppable within its own length.
 * Formats: speeds Q15.16 mm/s, squared speeds Q31.32 (mm/s)^2 in int64, lengths cs_pos_t. */
#ifndef CS_PLANNER_H
#define CS_PLANNER_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_err.h"
#include "cs_fixed.h"
#include "cs_machine.h"

/* Look-ahead depth in blocks: a power of two (index masking). The host plans with the ring full,
 * so 31 blocks of look-ahead sit behind the one being executed. */
#ifndef CS_PLANNER_RING
#define CS_PLANNER_RING 32
#endif

/* Junction budget (docs/motion.md). A junction is a vertex of a flattened curve when it turns
 * by less than ~0.5 rad (|u1 - u2| = 2 sin(phi/2) <= CS_PLANNER_CURVE_MAX_TURN, Q30) and
 * min(L1, L2) * |u1 - u2| <= CS_PLANNER_CURVE_SAGITTA * tolerance (a chord of a curve traced
 * within tol turns by phi ~ L / r with L * phi ~ 8 * sagitta <= 8 tol; factor 2 for uneven
 * chords). There v^2 = (51/100) a r, r = min(L1, L2) / |u1 - u2|, a = the smallest acceleration
 * of the moving axes, and the blocks touching it accelerate tangentially at most at (68/100) a:
 * with sqrt(0.51^2 + 0.68^2) = 0.85 every axis keeps 15 % for the velocity jump at the vertex,
 * itself capped at CS_PLANNER_CURVE_JUMP_NUM/DEN segment times of each axis's acceleration.
 * Any other turn is a corner: Grbl's junction deviation, each axis's velocity jump capped at one
 * segment time of its acceleration, and the two blocks keep (4/5) of their acceleration. */
#define CS_PLANNER_CURVE_SAGITTA  16
#define CS_PLANNER_CURVE_MAX_TURN ((int64_t)1 << 29)
#define CS_PLANNER_CURVE_NUM      51
#define CS_PLANNER_CURVE_DEN      100
#define CS_PLANNER_CURVE_TANG_NUM 68
#define CS_PLANNER_CURVE_TANG_DEN 100
#define CS_PLANNER_CURVE_JUMP_NUM 3
#define CS_PLANNER_CURVE_JUMP_DEN 2
#define CS_PLANNER_TANG_NUM       4
#define CS_PLANNER_TANG_DEN       5

/* One straight move. Speeds squared are Q31.32 (mm/s)^2 (int64). */
typedef struct {
    int32_t steps[CS_AXES]; /* signed steps each axis makes over the block (exact target) */
    int32_t unit[CS_AXES];  /* direction of the geometric chord, Q1.30 unit vector */
    int32_t frac0[CS_AXES]; /* exact start minus rounded start, steps Q16 (|.| <= 1/2 step) */
    int64_t exact[CS_AXES]; /* exact chord delta, steps Q16 (steps follow the chord itself) */
    cs_pos_t length;        /* geometric chord length, mm (Q15.16), > 0 */
    int32_t nominal;        /* cruise speed, mm/s Q15.16 (feed limited by every axis's rate) */
    int32_t accel;          /* acceleration along the chord, mm/s^2 Q15.16 (every axis's limit) */
    int32_t accel_axes;     /* the same before any junction's cut (junction speeds) */
    int64_t max_entry_v2;   /* junction limit with the previous block */
    int64_t entry_v2;       /* planned entry speed squared */
    int64_t rev_v2;         /* entry after the reverse pass alone (lets replanning stop early) */
    int64_t exit_v2;        /* exit speed squared, frozen when the block starts executing */
    uint32_t line;          /* input line that asked for the move (diagnostics) */
} cs_block_t;

typedef struct {
    const cs_machine_t *m;
    cs_block_t ring[CS_PLANNER_RING];
    uint16_t head;          /* index of the oldest block */
    uint16_t count;         /* blocks queued, including the executing one */
    bool busy;              /* ring[head] is being executed: its entry and exit are frozen */
    int64_t start_v2;       /* entry speed squared of ring[head] when not busy (exit of the last) */
    cs_pos_t pos[CS_AXES];  /* planned position, mm: end of the last queued move */
    int32_t steps[CS_AXES]; /* planned position in steps: round(pos * steps_per_mm) */
} cs_planner_t;

/* Checks *m (CS_ERR_ARG/CS_ERR_RANGE for values outside the documented ranges, e.g. a rate the
 * executor cannot step at one step per two ticks) and empties the planner at position 0. Keeps
 * the pointer m: the machine must outlive the planner. Not ISR-safe. */
cs_err_t cs_planner_init(cs_planner_t *pl, const cs_machine_t *m);
/* Sets the current position (mm) when nothing is queued; CS_ERR_STATE otherwise, CS_ERR_LIMIT
 * outside the travel. Not ISR-safe. */
cs_err_t cs_planner_set_position(cs_planner_t *pl, const cs_pos_t pos[CS_AXES]);
/* Queues a straight move to target (mm, every axis of the machine) at feed (mm/s Q15.16; <= 0:
 * rapid, each axis's max rate). CS_ERR_FULL when the ring is full (nothing queued),
 * CS_ERR_LIMIT when target leaves the travel (checked before anything is queued), CS_ERR_RANGE /
 * CS_ERR_OVERFLOW when a value leaves its format. A move shorter than one step on every axis
 * queues nothing (its distance is carried into the next move). Then replans. Not ISR-safe. */
cs_err_t cs_planner_line(cs_planner_t *pl, const cs_pos_t target[CS_AXES], int32_t feed,
                         uint32_t line);
/* As cs_planner_line with x, y, z from *p and a unchanged. */
cs_err_t cs_planner_line3(cs_planner_t *pl, const cs_vec3_t *p, int32_t feed, uint32_t line);
/* True when no further block can be queued. */
bool cs_planner_full(const cs_planner_t *pl);
/* Number of blocks queued (the executing one included). */
unsigned cs_planner_count(const cs_planner_t *pl);
/* Block i counted from the oldest (0 = head), NULL past the end. For inspection and tests. */
const cs_block_t *cs_planner_block(const cs_planner_t *pl, unsigned i);
/* Starts executing the oldest block: freezes its entry and exit speeds and returns it; NULL when
 * the ring is empty. Calling it again before cs_planner_end_head returns the same block. */
const cs_block_t *cs_planner_begin_head(cs_planner_t *pl);
/* The executing block is finished: frees its slot; its exit speed becomes the next entry. */
void cs_planner_end_head(cs_planner_t *pl);

/* S-curve (CS_PROFILE_SCURVE): duration of a speed change dv (Q16 mm/s, >= 0) with peak
 * acceleration accel (Q16 mm/s^2) and jerk (mm/s^3): max(1.5 dv / a, sqrt(6 dv / j)) seconds,
 * as Q31.32 (INT64_MAX when out of range). The change follows v = v0 + dv (3x^2 - 2x^3),
 * x = t / T: peak acceleration 1.5 dv / T, peak jerk 6 dv / T^2. */
int64_t cs_planner_scurve_time(int32_t accel, int32_t jerk, int64_t dv);
/* Integer square root of a Q31.32 speed squared, as Q15.16 mm/s (rounded down). */
int32_t cs_planner_speed(int64_t v2);

#endif
