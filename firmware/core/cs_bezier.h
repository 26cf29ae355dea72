/* cs_bezier: the one curve representation of the core. Every polynomial or rational curve
 * (Hermite, B-spline, Catmull-Rom, NURBS, arcs...) is converted to cs_bezier_t segments
 * (G2 = M2^-1 . M1 . G1, seed 003) so one evaluator and one set of tracers serve them all.
 * Owns de Casteljau evaluation, splitting, degree elevation, hodograph and bounding box. */
#ifndef CS_BEZIER_H
#define CS_BEZIER_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_err.h"
#include "cs_fixed.h"

#define CS_BEZIER_MAX_DEGREE 7
#define CS_BEZIER_MAX_POINTS (CS_BEZIER_MAX_DEGREE + 1)
/* Guard bits carried by polynomial de Casteljau passes (coordinate << 28 in int64). */
#define CS_BEZIER_GUARD 28
/* Most extra fraction bits cs_bezier_blossom / cs_bezier_piece can return. */
#define CS_BEZIER_MAX_FRAC 24

/* A point with extra fraction bits: each coordinate is LSB * 2^frac in int64 (frac given by the
 * call that fills it). Used where sub-LSB precision matters (arc length, bounds). */
typedef struct {
    int64_t x, y, z;
} cs_vec3w_t;

/* A Bézier segment of degree 1..7 over t in [0, 1]. Control points are real (not weighted)
 * coordinates inside CS_POS_LIMIT. When rational is false, w[] is ignored (all weights 1);
 * when true, every w[i] is in CS_WEIGHT_MIN..CS_WEIGHT_ONE and the curve is
 * sum(B_i w_i P_i) / sum(B_i w_i). */
typedef struct {
    uint8_t degree;
    bool rational;
    cs_vec3_t p[CS_BEZIER_MAX_POINTS];
    cs_weight_t w[CS_BEZIER_MAX_POINTS];
} cs_bezier_t;

/* Every operation below also accepts degree 0 (a constant: what the hodograph of a line is)
 * and, for polynomial segments, any int32 coordinates (a hodograph may leave CS_POS_LIMIT);
 * rational segments must keep their points in CS_POS_LIMIT and weights in range
 * (CS_ERR_RANGE / CS_ERR_WEIGHT). None of them is recursive; stack use is a few 8 x int64
 * arrays. All are pure functions of their inputs (ISR-safe, but eval costs O(n^2) 64-bit
 * multiplies). */

/* Polynomial segment from degree+1 points; CS_ERR_DEGREE (degree outside 1..7) or
 * CS_ERR_RANGE (a point outside CS_POS_LIMIT). Not ISR-safe (no reason to call it there). */
cs_err_t cs_bezier_init(cs_bezier_t *c, unsigned degree, const cs_vec3_t *pts);
/* Rational segment: as cs_bezier_init plus weights (CS_ERR_WEIGHT outside the accepted range). */
cs_err_t cs_bezier_init_rational(cs_bezier_t *c, unsigned degree, const cs_vec3_t *pts,
                                 const cs_weight_t *w);
/* The check every tracer makes before it starts (cs_fd, cs_afd, cs_subdiv, cs_join): degree in
 * 1..7 (CS_ERR_DEGREE), every point inside CS_POS_LIMIT (CS_ERR_RANGE), rational weights in
 * CS_WEIGHT_MIN..CS_WEIGHT_ONE (CS_ERR_WEIGHT), checked in that order. ISR-safe (pure). */
cs_err_t cs_bezier_check(const cs_bezier_t *c);
/* Point at t in [0, CS_PARAM_ONE] by de Casteljau (rational: in homogeneous space, then
 * divided); CS_ERR_ARG for t outside [0, 1]. Result rounded to the nearest LSB: within
 * 0.5 + 2^-25 LSB of the exact polynomial of the fixed-point control points at t (rational:
 * within 0.5 + 2^-8 LSB of the exact rational curve). */
cs_err_t cs_bezier_eval(const cs_bezier_t *c, cs_param_t t, cs_vec3_t *out);
/* Split at t in (0, 1) into left [0, t] and right [t, 1] (either may be NULL; either may be c,
 * but not both the same struct). Arguments are checked before anything is written; after that
 * no error can occur for a segment that passed cs_bezier_init*.
 * Each new control point is the exact de Casteljau point rounded once (<= 0.5 + 2^-25 LSB), so
 * left(s) = c(t s) and right(s) = c(t + (1 - t) s) within that bound. Rational: the new weights
 * are rescaled so each half's largest weight is CS_WEIGHT_ONE, rounded to Q30; the extra error
 * is at most max_i(2^-31 / w'_i) times the half's control-polygon diameter. CS_ERR_ARG for t
 * outside (0, 1). */
cs_err_t cs_bezier_split(const cs_bezier_t *c, cs_param_t t, cs_bezier_t *left, cs_bezier_t *right);
/* Same curve one degree higher: P'_i = i/(n+1) P_{i-1} + (1 - i/(n+1)) P_i, each rounded once
 * (<= 0.5 LSB; rational: on homogeneous points, weights renormalised to a largest weight of 1).
 * CS_ERR_DEGREE when already at CS_BEZIER_MAX_DEGREE. */
cs_err_t cs_bezier_elevate(const cs_bezier_t *c, cs_bezier_t *out);
/* Derivative dB/dt as a Bézier of degree n-1 with points n(P_{i+1}-P_i), in mm per unit t.
 * Polynomial curves only (CS_ERR_UNSUPPORTED for rational); CS_ERR_OVERFLOW if it leaves the
 * cs_pos_t format. */
cs_err_t cs_bezier_hodograph(const cs_bezier_t *c, cs_bezier_t *out);
/* Axis-aligned box that contains the whole curve (tight at the curve's extrema for degree <= 3,
 * the control hull's box otherwise). */
cs_err_t cs_bezier_bbox(const cs_bezier_t *c, cs_vec3_t *min, cs_vec3_t *max);
/* Box of a polynomial degree 2..3 segment: the roots of B' (B'' for the split of a cubic's B')
 * bracketed by bisection on t, extrema rounded outwards, so the box contains the exact curve
 * and is less than 1 + 2^-20 LSB larger than the exact extent on each side.
 * Rational, or degree >= 4: the control points' box (convex-hull property, positive weights). */

/* Blossom (polar form) b(ts[0], ..., ts[n-1]) of c (n = degree; each ts in [0, 1], else
 * CS_ERR_ARG), with frac (0..CS_BEZIER_MAX_FRAC) extra fraction bits: rounded to 2^-frac LSB,
 * so within 2^-(frac+1) + 2^-25 LSB of the exact blossom (rational: + 7 * 2^-31 / min(w) LSB).
 * b(t, ..., t) = c(t). */
cs_err_t cs_bezier_blossom(const cs_bezier_t *c, const cs_param_t *ts, unsigned frac,
                           cs_vec3w_t *out);
/* Control points (degree + 1 of them, frac extra fraction bits) of the piece of c between t0
 * and t1 (any order, each in [0, 1]): point i = b(t0^(n-i), t1^i). Each is rounded once and
 * independently of t1 - t0, so adjacent pieces share their end point exactly. For a rational c
 * these are the piece's points (its weights are the blossoms of the weights, not returned). */
cs_err_t cs_bezier_piece(const cs_bezier_t *c, cs_param_t t0, cs_param_t t1, unsigned frac,
                         cs_vec3w_t *pts);

#endif
