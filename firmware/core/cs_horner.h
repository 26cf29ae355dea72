/* cs_horner: a polynomial Bézier segment in the power basis, evaluated by Horner's rule (seed
 * 003, "Traçage de courbe": x(t) = ((a t + b) t + c) t + d, 9 multiplications and 10 additions
 * for a cubic in 3D against the naive 11). Owns the exact conversion to power coefficients
 * a_k = C(n, k) sum_i (-1)^(k-i) C(k, i) P_i and the guarded evaluation. The alternative to
 * de Casteljau (cs_bezier_eval) where seed 003 compares them: `flatten --eval horner`. */
#ifndef CS_HORNER_H
#define CS_HORNER_H

#include <stdint.h>

#include "cs_bezier.h"

/* Guard bits of the coefficients: |a_k| < 3^7 2^28 < 2^40 LSB, times 2^16 < 2^56, and every
 * Horner partial sum below 8 * 2^56 = 2^59, inside cs_fixed_mul64_q30's 2^62. */
#define CS_HORNER_GUARD 16

/* a[k][axis] = coefficient of t^k, LSB * 2^CS_HORNER_GUARD (exact). */
typedef struct {
    uint8_t degree;
    int64_t a[CS_BEZIER_MAX_POINTS][3];
} cs_horner_t;

/* Power form of polynomial segment c (degree 1..7). CS_ERR_UNSUPPORTED for a rational segment,
 * CS_ERR_DEGREE / CS_ERR_ARG for a malformed one. Exact (integers). ISR-safe (pure). */
cs_err_t cs_horner_init(cs_horner_t *h, const cs_bezier_t *c);
/* Point at t in [0, CS_PARAM_ONE] (else CS_ERR_ARG) by Horner's rule: n multiplications per
 * axis, each rounded by 1/2 guard unit, so the result is within 0.5 + n 2^-17 LSB of the exact
 * polynomial (de Casteljau: 0.5 + 2^-25). ISR-safe (pure, bounded). */
cs_err_t cs_horner_eval(const cs_horner_t *h, cs_param_t t, cs_vec3_t *out);

#endif
