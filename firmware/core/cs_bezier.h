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

/* Polynomial segment from degree+1 points; CS_ERR_DEGREE (degree outside 1..7) or
 * CS_ERR_RANGE (a point outside CS_POS_LIMIT). Not ISR-safe (no reason to call it there). */
cs_err_t cs_bezier_init(cs_bezier_t *c, unsigned degree, const cs_vec3_t *pts);
/* Rational segment: as cs_bezier_init plus weights (CS_ERR_WEIGHT outside the accepted range). */
cs_err_t cs_bezier_init_rational(cs_bezier_t *c, unsigned degree, const cs_vec3_t *pts,
                                 const cs_weight_t *w);
/* Point at t in [0, CS_PARAM_ONE] by de Casteljau (rational: in homogeneous space, then
 * divided); CS_ERR_ARG for t outside [0, 1]. Result rounded to the nearest LSB. */
cs_err_t cs_bezier_eval(const cs_bezier_t *c, cs_param_t t, cs_vec3_t *out);
/* Split at t in (0, 1) into left [0, t] and right [t, 1] (either may be NULL). */
cs_err_t cs_bezier_split(const cs_bezier_t *c, cs_param_t t, cs_bezier_t *left, cs_bezier_t *right);
/* Same curve one degree higher (CS_ERR_DEGREE when already at CS_BEZIER_MAX_DEGREE). */
cs_err_t cs_bezier_elevate(const cs_bezier_t *c, cs_bezier_t *out);
/* Derivative dB/dt as a Bézier of degree n-1 with points n(P_{i+1}-P_i), in mm per unit t.
 * Polynomial curves only (CS_ERR_UNSUPPORTED for rational); CS_ERR_OVERFLOW if it leaves the
 * cs_pos_t format. */
cs_err_t cs_bezier_hodograph(const cs_bezier_t *c, cs_bezier_t *out);
/* Axis-aligned box that contains the whole curve (tight at the curve's extrema for degree <= 3,
 * the control hull's box otherwise). */
cs_err_t cs_bezier_bbox(const cs_bezier_t *c, cs_vec3_t *min, cs_vec3_t *max);

#endif
