/* cs_predict: the predicted-step tracer for planar polynomial curves of degree 1..3 (lines,
 * quadratics, cubics: what SVG, G5 and G5.1 give) and planar conic arcs (rational quadratics
 * with w1^2 <= w0 w2: the circles and ellipses of cs_arc, SVG 'A', G2/G3). Each chord's parameter
 * step is predicted from the last one, the room the last flatness test left (deviation ~ h^2) and
 * the trend of that over the last two chords (no division: rooms are carried as logarithms; a
 * polynomial curve's first step from its curvature at the start), then
 * VERIFIED by one flatness test on the sub-curve [t, t + h], whose control points are
 * computed directly from the power-basis Taylor expansion at t (no chain of de Casteljau splits).
 * The test bounds the exact deviation of the sub-curve from its chord by a piecewise-linear
 * majorant of max_t |B1(t) d1 + B2(t) d2| (d1, d2 the signed distances of the inner control
 * points), within 1.3 % of the exact maximum, so chords come within a few per cent of the greedy
 * optimum. Owns the power-basis state, the test and the step predictor; derivation and error bound
 * in docs/fixed-point.md, "Predicted-step tracer". */
#ifndef CS_PREDICT_H
#define CS_PREDICT_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_bezier.h"

/* Guard bits below the LSB carried by the power-basis coefficients and the sub-curve points. */
#define CS_PREDICT_FRAC 12
/* Rounding budget (LSB) charged against the tolerance: both chord ends rounded to the LSB
 * (<= 0.5 + 2^-10 each) plus the sub-curve points' own rounding (docs/fixed-point.md). */
#define CS_PREDICT_SLACK_LSB 2
/* Accepted tolerance range, in cs_pos_t LSB. */
#define CS_PREDICT_TOL_MIN (CS_PREDICT_SLACK_LSB + 2)
#define CS_PREDICT_TOL_MAX CS_POS_LIMIT
/* Flatness tests allowed per chord before the step is only halved (predictor gave up). */
#define CS_PREDICT_MAX_TESTS 12

/* Tracer state: the curve in power basis (x, y: LSB * 2^CS_PREDICT_FRAC) or the conic's
 * homogeneous points, the parameter reached, the last accepted step, and the vertex routine its
 * begin chose (so an image that never calls cs_predict_begin_conic links no conic code). */
typedef struct cs_predict cs_predict_t;
struct cs_predict {
    int64_t a[4][2]; /* B(t) = a0 + a1 t + a2 t^2 + a3 t^3, per axis x, y */
    int64_t d[2][2]; /* B'(t), B''(t) / 2 at the last vertex (per axis x, y) */
    int64_t h[3][3]; /* conic: homogeneous points w_i x_i, w_i y_i (LSB * 2^30), w_i (Q30) */
    cs_err_t (*next)(cs_predict_t *p, cs_vec3_t *pt);
    cs_param_t t;       /* parameter of the last vertex returned */
    cs_param_t h_next;  /* the step predicted for the next chord */
    cs_param_t h_ideal; /* the step the last chord would have needed (0: none known) */
    cs_pos_t thr;       /* tol - slack, LSB */
    uint8_t thr_shift;  /* least shift of thr * 2^F below 2^14 (the test's unit) */
    cs_pos_t z;         /* the plane's z (every control point has it) */
    cs_vec3_t end;      /* P_n, returned exactly as the last vertex */
    bool done;
#if defined(__SIZEOF_INT128__)
    /* 64-bit hosts: the last test's shift and what follows from it (its threshold, that
     * threshold's log), the next test's guess (cs_predict.c, HOST_GUESS; begin guesses the
     * threshold's shift) */
    int64_t guess[6];
#endif
};

/* True when cs_predict takes c: every control point at the same z, and polynomial of degree
 * 1..3, or rational of degree 2 with every weight >= 1/16 and w1^2 <= w0 w2 (an ellipse or
 * parabola arc: the conic's shoulder is then its farthest point from the chord). */
bool cs_predict_accepts(const cs_bezier_t *c);
/* Start tracing the polynomial curve c with chord tolerance tol (LSB). CS_ERR_TOLERANCE outside
 * CS_PREDICT_TOL_MIN..MAX, CS_ERR_UNSUPPORTED when !cs_predict_accepts(c) or c is rational,
 * CS_ERR_RANGE for a point outside CS_POS_LIMIT. ISR-safe (pure). */
cs_err_t cs_predict_begin(cs_predict_t *p, const cs_bezier_t *c, cs_pos_t tol);
/* The same for a conic arc (rational c with cs_predict_accepts(c); CS_ERR_UNSUPPORTED for a
 * polynomial one). A separate entry so that only images that trace arcs link the conic path.
 * ISR-safe (pure). */
cs_err_t cs_predict_begin_conic(cs_predict_t *p, const cs_bezier_t *c, cs_pos_t tol);
/* Next vertex (see cs_trace_next): CS_OK with *pt, CS_END after P_n, CS_ERR_DEPTH if no step
 * of 2^-30 passes (cannot happen for a valid curve). Bounded work: at most
 * CS_PREDICT_MAX_TESTS + 30 tests a vertex, typically one or two. */
cs_err_t cs_predict_next(cs_predict_t *p, cs_vec3_t *pt);

#endif
