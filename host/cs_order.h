/* cs_order: line merging and travel sorting of a drawing (--merge, --sort; docs/plotting.md,
 * "Merge and sort"). Owns the strokes of a path (runs of continuous elements of one subpath),
 * their joining where ends meet within the tolerance (reversing where needed, a bridging line of
 * at most the tolerance where the ends are not exactly equal), and the drawing order that
 * shortens pen-up travel: nearest neighbour over a 2-d tree of entry points (both ends of an
 * open stroke, every element boundary of a closed one), then windowed 2-opt passes bounded in
 * count (deterministic: no clock decides anything). Drawn geometry is unchanged: elements are
 * only reordered, reversed exactly (control points and weights in reverse order) or rotated
 * within a closed stroke. Host only. */
#ifndef CS_ORDER_H
#define CS_ORDER_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_path.h"

/* 2-opt: each pass tries every reversal of up to CS_ORDER_WINDOW consecutive strokes; at most
 * CS_ORDER_PASSES passes (fewer when a pass improves nothing). */
#define CS_ORDER_WINDOW 24
#define CS_ORDER_PASSES 4

typedef struct {
    bool merge;    /* join strokes whose ends meet within tol_mm */
    bool sort;     /* reorder (and reverse / rotate) strokes to shorten pen-up travel */
    double tol_mm; /* merge distance: the chord tolerance, mm */
} cs_order_opts_t;

typedef struct {
    double travel_before_mm, travel_after_mm; /* pen-up travel in x y from the origin, mm */
    size_t lifts_before, lifts_after;         /* pen lifts: strokes drawn (cs_order_travel) */
    size_t bridges;                           /* gaps (<= tol_mm) closed by a bridging line */
    bool skipped; /* the path holds travel moves of its own (G-code G0): order kept */
} cs_order_stats_t;

/* Pen-up travel of p as the planner moves (mm, in x y): from the origin to the first element,
 * then every jump from an element's end to the next one's start; *lifts (may be NULL) = the
 * number of strokes (elements that start a subpath or do not start where the last one ended). */
double cs_order_travel(const cs_path_t *p, size_t *lifts);

/* Merges and/or sorts p in place per o, filling *st. A path with rapid (G0) elements is left
 * as it is (st->skipped). CS_ERR_FULL when out of memory (p unchanged then). */
cs_err_t cs_order_apply(cs_path_t *p, const cs_order_opts_t *o, cs_order_stats_t *st);

#endif
