/* cs_sim_grid: a uniform grid over line segments in mm (2D: x y, or 3D), for the simulator's
 * checks: the distance from a point to the nearest segment without scanning them all. Each
 * segment is listed in every cell that pieces of it no longer than one cell touch (so a long
 * travel costs a few cells per cell length, not its whole box); a query searches rings of cells
 * outwards from the point's cell and stops as soon as nothing unvisited can be nearer, or as
 * soon as the caller's threshold is met (the check only needs to know "within worst so far").
 * Owns its cell lists; the points stay the caller's. Host only (double, malloc). */
#ifndef CS_SIM_GRID_H
#define CS_SIM_GRID_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_err.h"

typedef struct {
    const double *pts; /* 3 per point (the caller's) */
    const size_t *seg; /* 2 point indices per segment (a == b: a point) (owned: copied) */
    size_t nseg;
    unsigned dims; /* 2: x y only; 3: x y z */
    double lo[3], cell;
    size_t n[3];  /* cells per axis (n[2] = 1 in 2D) */
    size_t *head; /* per cell, its first entry in idx (n cells + 1) */
    size_t *idx;  /* segment numbers, cell by cell */
    size_t last;  /* the segment the previous query found nearest (tried first) */
} cs_sim_grid_t;

/* Builds the grid over nseg segments seg[2k], seg[2k+1] of pts, in dims (2 or 3) dimensions,
 * with cells sized so that about two segments share one (never below min_cell mm, and at most
 * CS_SIM_GRID_MAX_CELLS cells). CS_ERR_FULL when out of memory, CS_ERR_ARG when nseg is 0. */
cs_err_t cs_sim_grid_build(cs_sim_grid_t *g, const double *pts, const size_t *seg, size_t nseg,
                           unsigned dims, double min_cell);
void cs_sim_grid_free(cs_sim_grid_t *g);

/* Distance (mm, in the grid's dims) from p to the nearest segment, and its number in *which
 * (may be NULL); but as soon as one within enough (mm) is seen, that one is returned instead
 * (enough < 0: the exact nearest). */
double cs_sim_grid_nearest(cs_sim_grid_t *g, const double p[3], double enough, size_t *which);

/* Distance from p to the segment a-b in the first dims coordinates (a == b: to the point). */
double cs_sim_grid_dist(const double *p, const double *a, const double *b, unsigned dims);

enum { CS_SIM_GRID_MAX_CELLS = 1 << 22 };

#endif
