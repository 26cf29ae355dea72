/* cs_gcoons: the generalised Coons patch of seed 002 ("Patch de Coons généralisé", fonctions de
 * mélange quelconques):
 *   S(u, v) = [f1(u) f2(u)] [S(0, v) S(1, v)]^T + [S(u, 0) S(u, 1)] [g1(v) g2(v)]^T
 *             - [f1(u) f2(u)] [[S(0,0) S(0,1)] [S(1,0) S(1,1)]] [g1(v) g2(v)]^T
 * with f1 + f2 = g1 + g2 = 1, f1(0) = g1(0) = 1, f1(1) = g1(1) = 0. Blends that are cubic
 * polynomials (given by their Bernstein coefficients) keep S an exact bicubic patch: in the
 * Bernstein basis, f1(u) Q1(v) has the net F_i q1_j, and so on. Built in double on the host from
 * the fixed-point boundaries, each control point rounded once. Linear blends give the bilinear
 * Coons patch, the cubic Hermite h0 = B0 + B1 the seed's Hermite-blended one. */
#ifndef CS_GCOONS_H
#define CS_GCOONS_H

#include "cs_bezier.h"
#include "cs_patch.h"

/* A blend f1 (f2 = 1 - f1) as a cubic in Bernstein form: b[0] = 1, b[3] = 0 required. */
typedef struct {
    double b[4];
} cs_gcoons_blend_t;

/* The linear blend 1 - t (Bernstein 1, 2/3, 1/3, 0) and the cubic Hermite 1 - 3t^2 + 2t^3
 * (1, 1, 0, 0). */
cs_gcoons_blend_t cs_gcoons_linear(void);
cs_gcoons_blend_t cs_gcoons_hermite(void);

/* The patch from boundaries p1 = S(u, 0), p2 = S(u, 1), q1 = S(0, v), q2 = S(1, v) (polynomial,
 * degree 1..3, corners meeting exactly: CS_ERR_DEGENERATE, CS_ERR_DEGREE, CS_ERR_UNSUPPORTED for
 * rational) and blends f1 (in u) and g1 (in v). CS_ERR_ARG for a blend with b[0] != 1 or
 * b[3] != 0, or a coefficient not finite; CS_ERR_RANGE when a control point leaves the range. */
cs_err_t cs_gcoons_build(const cs_bezier_t *p1, const cs_bezier_t *p2, const cs_bezier_t *q1,
                         const cs_bezier_t *q2, const cs_gcoons_blend_t *f1,
                         const cs_gcoons_blend_t *g1, cs_patch_t *out);

#endif
