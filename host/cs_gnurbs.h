/* cs_gnurbs: the NURBS blocks of G-code (G5.2/G5.3 and G6.2, read by cs_gcode) turned into path
 * curves. Owns a block's control points (machine mm, in 3D: G5.2 works in any plane), weights
 * and knots; converts them to Bézier segments with the core's cs_nurbs (knots rescaled to its
 * Q15.16, weights normalised to Q1.30). Host only. */
#ifndef CS_GNURBS_H
#define CS_GNURBS_H

#include <stddef.h>

#include "cs_bezier.h"
#include "cs_nurbs.h"

#define CS_GNURBS_MAX_POINTS 10000u /* control points in one block */
#define CS_GNURBS_MAX_ORDER  (CS_NURBS_MAX_DEGREE + 1)

typedef struct {
    double p[3]; /* machine mm */
    double w;    /* weight, > 0 */
} cs_gnurbs_cp_t;

typedef struct {
    cs_gnurbs_cp_t *cps;
    size_t n, cap;
    double *knots; /* G6.2: the block's knots; G5.2: none (uniform clamped) */
    size_t nknots, capknots;
    unsigned order;
} cs_gnurbs_t;

/* Receives each segment, in order, its ends already shared with its neighbours. */
typedef cs_err_t (*cs_gnurbs_emit_fn)(void *ctx, const cs_bezier_t *seg);

/* Empties the block (keeps its memory) and sets its order (2..CS_GNURBS_MAX_ORDER). */
void cs_gnurbs_begin(cs_gnurbs_t *nb, unsigned order);
/* Appends a control point; CS_ERR_FULL past CS_GNURBS_MAX_POINTS or without memory. */
cs_err_t cs_gnurbs_push(cs_gnurbs_t *nb, const double p[3], double w);
/* Appends a knot; CS_ERR_FULL past CS_GNURBS_MAX_POINTS + order or without memory. */
cs_err_t cs_gnurbs_knot(cs_gnurbs_t *nb, double k);
/* Converts the block: with no knots, LinuxCNC's G5.2 knot vector (order k over n+1 points: k
 * zeros, 1 .. n-k+1, k times n-k+2); else the knots given (n + order of them, non-decreasing,
 * clamped: the first and last order knots equal, so the curve starts and ends on the end control
 * points). emit gets each segment. Errors: CS_ERR_PARSE (point or knot count), CS_ERR_WEIGHT,
 * CS_ERR_RANGE (a point outside +/-4096 mm), CS_ERR_FULL, the core's or emit's; why (whylen bytes)
 * says which. */
cs_err_t cs_gnurbs_build(const cs_gnurbs_t *nb, cs_gnurbs_emit_fn emit, void *ctx, char *why,
                         size_t whylen);
void cs_gnurbs_free(cs_gnurbs_t *nb);
/* *dst becomes an independent copy of *src. CS_ERR_FULL without memory (dst then empty). */
cs_err_t cs_gnurbs_copy(cs_gnurbs_t *dst, const cs_gnurbs_t *src);

#endif
