/* cs_nurbs: non-uniform B-splines and NURBS of degree 1..3 cut into Bézier segments, by Boehm
 * knot insertion until every interior knot has multiplicity = degree (done locally per knot span,
 * so one segment at a time needs no storage). Rational curves work in homogeneous coordinates;
 * each segment's weights are renormalised into cs_weight_t's range (largest = CS_WEIGHT_ONE).
 * Owns the knot format and the validation of knot vectors. */
#ifndef CS_NURBS_H
#define CS_NURBS_H

#include <stddef.h>
#include <stdint.h>

#include "cs_bezier.h"
#include "cs_err.h"
#include "cs_fixed.h"

#define CS_NURBS_MAX_DEGREE 3

/* Knot value: signed Q15.16 in int32 (1.0 = CS_NURBS_KNOT_ONE, range +/-32768). A B-spline is
 * unchanged by an affine change of its parameter, so only ratios of knot differences matter: any
 * common scale gives the same segments (knots 0, 0.33, 0.66, 1 may be given exactly as 0, 33,
 * 66, 100). Differences are formed in int64, so the whole int32 range is usable. */
typedef int32_t cs_nurbs_knot_t;
#define CS_NURBS_KNOT_FRAC_BITS 16
#define CS_NURBS_KNOT_ONE       ((cs_nurbs_knot_t)1 << CS_NURBS_KNOT_FRAC_BITS)

/* A curve: borrows the caller's arrays (they must outlive it). count control points, weights
 * (NULL for a polynomial B-spline; otherwise each > 0 in any common scale, e.g. Q1.30), and
 * count + degree + 1 knots. The curve is defined over [knots[degree], knots[count]]. */
typedef struct {
    unsigned degree;
    size_t count;
    const cs_vec3_t *pts;
    const int32_t *weights;
    const cs_nurbs_knot_t *knots;
} cs_nurbs_t;

/* Iterator state over the segments (one per non-empty knot span of the domain). */
typedef struct {
    size_t span;
} cs_nurbs_iter_t;

/* Validate and wrap a curve. CS_ERR_ARG (NULL arrays), CS_ERR_DEGREE (degree outside 1..3),
 * CS_ERR_KNOTS (n_knots != count + degree + 1, count < degree + 1, knots decreasing, a knot
 * repeated more than degree + 1 times, or an empty domain), CS_ERR_RANGE (a point outside
 * CS_POS_LIMIT), CS_ERR_WEIGHT (a weight <= 0). Not ISR-safe (O(count) scan). */
cs_err_t cs_nurbs_init(cs_nurbs_t *c, unsigned degree, const cs_vec3_t *pts, const int32_t *weights,
                       size_t count, const cs_nurbs_knot_t *knots, size_t n_knots);
/* Number of Bézier segments (non-empty knot spans inside the domain). O(count). */
size_t cs_nurbs_segments(const cs_nurbs_t *c);
/* Start iterating at the first segment. ISR-safe. */
void cs_nurbs_iter_begin(const cs_nurbs_t *c, cs_nurbs_iter_t *it);
/* Next segment as a Bézier of the curve's degree (rational when the curve has weights that are
 * not all equal on this span), with its knot interval [*u0, *u1] (either pointer may be NULL):
 * the curve at knot u is the segment at t = (u - u0) / (u1 - u0). Control points within 0.5 LSB
 * of the exact ones; weights within 2^-31 (absolute, Q1.30 rounding), which moves a rational
 * curve by at most 2^-31 * (control hull size) / (smallest weight) more. CS_END after the last
 * segment; CS_ERR_WEIGHT when a normalised weight falls below CS_WEIGHT_MIN; CS_ERR_RANGE if a
 * point leaves CS_POS_LIMIT. Not ISR-safe (O(degree^3) 128-bit mul-divs per segment). */
cs_err_t cs_nurbs_next(const cs_nurbs_t *c, cs_nurbs_iter_t *it, cs_bezier_t *out,
                       cs_nurbs_knot_t *u0, cs_nurbs_knot_t *u1);
/* All segments into out[0..cap-1], *n set to their number; CS_ERR_FULL (nothing promised in
 * out) when cap < cs_nurbs_segments(c). Not ISR-safe (see cs_nurbs_next). */
cs_err_t cs_nurbs_to_bezier(const cs_nurbs_t *c, cs_bezier_t *out, size_t cap, size_t *n);

#endif
