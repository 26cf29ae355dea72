/* cs_segment: cuts planned blocks into step segments, the unit the executor consumes. Owns the
 * segment struct, the velocity profile of the block being cut (trapezoid, sampled in closed
 * form every segment) and the rounding carry that makes every block end exactly on its target
 * step on every axis. Time is in executor ticks (cs_machine_t.tick_hz). */
#ifndef CS_SEGMENT_H
#define CS_SEGMENT_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_err.h"
#include "cs_machine.h"
#include "cs_planner.h"

/* A step segment: for `ticks` executor ticks, axis i makes steps[i] steps (sign = direction),
 * evenly spread (constant rate inside a segment). Invariant: 1 <= ticks <= 2^24 and
 * |steps[i]| <= ticks (at most one step per axis per tick). Axes beyond n_axes carry 0. */
typedef struct {
    uint32_t ticks;
    int32_t steps[CS_AXES];
} cs_segment_t;

/* Longest time one block may take, in ticks (keeps every product of the profile in int64). */
#define CS_SEGMENT_MAX_BLOCK_TICKS ((uint32_t)1 << 30)

typedef struct {
    const cs_machine_t *m;
    bool active;            /* a block is being cut */
    bool block_end;         /* the last segment returned ended a block */
    int32_t steps[CS_AXES]; /* the block's step totals */
    int32_t done[CS_AXES];  /* steps emitted so far in the block */
    int32_t frac0[CS_AXES]; /* the block's exact chord: start offset and delta, steps Q16 */
    int64_t exact[CS_AXES];
    int64_t length;      /* block length, Q16 mm */
    int32_t v0, vp, v1;  /* entry, peak, exit speed, mm/s Q16 */
    int32_t accel;       /* mm/s^2 Q16 */
    bool scurve;         /* speed changes follow the smoothstep S-curve (cs_planner.h) */
    uint32_t ta, tc, td; /* phase durations, ticks: accelerate, cruise, decelerate */
    int64_t da, dc;      /* distance at the end of the acceleration, of the cruise, Q16 mm */
    uint32_t t;          /* ticks elapsed in the block */
    int64_t d;           /* distance reached at t, Q16 mm */
    uint32_t line;       /* input line of the block (diagnostics) */
} cs_segment_gen_t;

/* Prepares g for machine *m (validated by cs_planner_init). Not ISR-safe. */
cs_err_t cs_segment_init(cs_segment_gen_t *g, const cs_machine_t *m);
/* Next segment of the planner's oldest block (begun with cs_planner_begin_head, ended with
 * cs_planner_end_head after its last segment). CS_OK with *out set; CS_ERR_EMPTY when the planner
 * has no block; CS_ERR_RANGE when a block would last more than CS_SEGMENT_MAX_BLOCK_TICKS.
 * After the last segment of a block, cs_segment_block_end is true and the block's segments sum
 * to its exact step totals. Not ISR-safe (main loop). */
cs_err_t cs_segment_next(cs_segment_gen_t *g, cs_planner_t *pl, cs_segment_t *out);
/* True when the segment last returned by cs_segment_next finished its block. */
bool cs_segment_block_end(const cs_segment_gen_t *g);
/* Duration of the block being cut (ticks), valid while a block is active. */
uint32_t cs_segment_block_ticks(const cs_segment_gen_t *g);

#endif
