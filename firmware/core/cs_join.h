/* cs_join: continuity at the join of two Bézier segments (seed 003, "Continuité").
 * Reports which of C0 (= G0), G1, C1, G2, C2 hold where segment a ends and segment b starts,
 * from the end control points only (no evaluation), within caller-given tolerances.
 * Owns the tolerance struct and the flag bits; holds no state. */
#ifndef CS_JOIN_H
#define CS_JOIN_H

#include "cs_bezier.h"

/* Flag bits of cs_join_classify. Each parametric level implies the ones below it
 * (C2 => C1 => C0), each geometric one too (G2 => G1 => G0). C1 does not imply G1 when the
 * tangent is zero (seed 003): with P_n = P_{n-1} both derivatives can be equal (zero) while the
 * curve turns a corner. */
#define CS_JOIN_C0 0x01u
#define CS_JOIN_G0 CS_JOIN_C0 /* a common point: the same test */
#define CS_JOIN_G1 0x02u
#define CS_JOIN_C1 0x04u
#define CS_JOIN_G2 0x08u
#define CS_JOIN_C2 0x10u

/* Tolerances.
 *  pos:       C0 holds when |a(1) - b(0)| <= pos (mm, cs_pos_t, >= 0). It is also the absolute
 *             floor for derivative comparisons (in mm per unit t and per unit t^2) and the
 *             length below which a control-polygon leg counts as zero.
 *  sin_angle: G1 holds when the angle between the end tangents has a sine <= sin_angle and
 *             a positive cosine (same sense, A = k B with k > 0), Q1.30 in [0, 1].
 *  rel:       two derivative vectors u, v (C1, C2) agree when
 *             |u - v| <= rel * max(|u|, |v|) + pos; two curvature vectors agree (G2) when
 *             |ka - kb| <= rel * max(|ka|, |kb|) + 2 pos / h^2, h = the longer of the two end
 *             legs |P_n - P_{n-1}|, |Q_1 - Q_0| (a curvature difference that bends a leg-long
 *             stretch by at most pos). Q1.30 in [0, 1].
 * With non-zero tangents, C1 within rel implies an angle with sine <= rel + pos / |B'|, so
 * choose sin_angle >= rel to keep "C1 => G1" for regular joins. */
typedef struct {
    cs_pos_t pos;
    cs_param_t sin_angle;
    cs_param_t rel;
} cs_join_tol_t;

/* Classify the join of a (its end, t = 1) to b (its start, t = 0); degrees 1..7 each, any mix.
 * End derivatives: B'(1) = n (P_n - P_{n-1}), B''(1) = n (n-1) (P_n - 2 P_{n-1} + P_{n-2});
 * rational: B'(1) = n w_{n-1} / w_n (P_n - P_{n-1}). The tangent direction is that of the first
 * non-zero leg P_n - P_{n-k} (resp. Q_k - Q_0), the geometric tangent even where B' = 0.
 * Rational segments: C0, G1 and C1 are decided; G2 and C2 are never reported.
 * G2 needs non-zero end tangents on both sides (|leg| > pos).
 * CS_ERR_TOLERANCE for tolerances outside their ranges, CS_ERR_DEGREE / CS_ERR_WEIGHT /
 * CS_ERR_RANGE for malformed segments, CS_ERR_OVERFLOW when a curvature does not fit
 * (radius below ~2^-29 mm). Pure, not recursive; ISR-safe but not cheap (64-bit divisions). */
cs_err_t cs_join_classify(const cs_bezier_t *a, const cs_bezier_t *b, const cs_join_tol_t *tol,
                          unsigned *flags);

#endif
