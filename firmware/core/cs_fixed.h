/* cs_fixed: the fixed-point formats of the core and checked arithmetic on them.
 * Owns the scalar types (positions, curve parameter, rational weights), the 3-vector, the
 * compile-time assert, and the overflow-checked / saturating operations every other module uses.
 * Formats, ranges and error bounds are written down in docs/fixed-point.md. */
#ifndef CS_FIXED_H
#define CS_FIXED_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_err.h"

/* C99 static assert: a negative array size is a compile error. */
#define CS_STATIC_ASSERT(cond, name) typedef char cs_static_assert_##name[(cond) ? 1 : -1]

/* Position / length: millimetres, signed Q15.16 in int32 (1 LSB = 1/65536 mm = 15.26 nm). */
typedef int32_t cs_pos_t;
#define CS_POS_FRAC_BITS 16
#define CS_POS_ONE_MM ((cs_pos_t)1 << CS_POS_FRAC_BITS)
/* Accepted coordinate range: |coordinate| <= 4096 mm (2^28 LSB). The format holds +/-32768 mm;
 * the 3 spare bits are headroom for control-point differences and sums (see docs/fixed-point.md). */
#define CS_POS_LIMIT_MM 4096
#define CS_POS_LIMIT ((cs_pos_t)CS_POS_LIMIT_MM << CS_POS_FRAC_BITS)

/* Curve parameter t: signed, 30 fractional bits in int32 ("Q1.30"), 1.0 = CS_PARAM_ONE. */
typedef int32_t cs_param_t;
#define CS_PARAM_FRAC_BITS 30
#define CS_PARAM_ONE ((cs_param_t)1 << CS_PARAM_FRAC_BITS)

/* Rational weight: Q1.30 like the parameter, accepted range CS_WEIGHT_MIN..CS_WEIGHT_ONE
 * (a rational curve is unchanged when all its weights are scaled, so the host normalises the
 * largest weight to 1). */
typedef int32_t cs_weight_t;
#define CS_WEIGHT_FRAC_BITS 30
#define CS_WEIGHT_ONE ((cs_weight_t)1 << CS_WEIGHT_FRAC_BITS)
#define CS_WEIGHT_MIN ((cs_weight_t)1 << 10) /* 2^-20 */

/* A point or vector in machine space, each coordinate a cs_pos_t. */
typedef struct {
    cs_pos_t x, y, z;
} cs_vec3_t;

/* True when |v| <= CS_POS_LIMIT. */
bool cs_fixed_pos_ok(int64_t v);
/* True when every coordinate of *p passes cs_fixed_pos_ok. */
bool cs_fixed_vec_ok(const cs_vec3_t *p);

/* *out = a + b; CS_ERR_OVERFLOW (and *out untouched) when the int32 sum does not fit. */
cs_err_t cs_fixed_add(int32_t a, int32_t b, int32_t *out);
/* *out = a - b; CS_ERR_OVERFLOW when it does not fit int32. */
cs_err_t cs_fixed_sub(int32_t a, int32_t b, int32_t *out);
/* *out = round(a * b / 2^shift) (round half away from zero); CS_ERR_OVERFLOW if it leaves int32.
 * shift in 0..62. */
cs_err_t cs_fixed_mul_shift(int32_t a, int32_t b, unsigned shift, int32_t *out);
/* *out = round(a * 2^shift / b), b != 0 (CS_ERR_ARG), CS_ERR_OVERFLOW if it leaves int32.
 * shift in 0..30. */
cs_err_t cs_fixed_div_shift(int32_t a, int32_t b, unsigned shift, int32_t *out);
/* Saturating variants (libfixmath style): clamp to INT32_MIN/INT32_MAX instead of failing.
 * Only for values whose clamping is harmless by construction (documented at each use). */
int32_t cs_fixed_add_sat(int32_t a, int32_t b);
int32_t cs_fixed_sub_sat(int32_t a, int32_t b);

/* Narrow an int64 to int32; CS_ERR_OVERFLOW when it does not fit. */
cs_err_t cs_fixed_narrow(int64_t v, int32_t *out);
/* Arithmetic shift right with rounding half away from zero, n in 0..62. Exact for n = 0. */
int64_t cs_fixed_round_shift64(int64_t v, unsigned n);

/* floor(sqrt(v)) for any uint64 (bitwise, no division, no float). */
uint32_t cs_fixed_isqrt64(uint64_t v);
/* Euclidean length of a vector, in cs_pos_t units (rounded down): exact integer sqrt of the
 * 64-bit sum of squares (|component| <= 2^30 keeps the sum inside uint64). */
uint32_t cs_fixed_vec_len(int64_t dx, int64_t dy, int64_t dz);

/* Unsigned 64x64 -> 128 multiply, result as hi:lo (for exact comparisons of squared
 * distances; the core has no __int128 on 32-bit and 8-bit targets). */
void cs_fixed_mul_u64(uint64_t a, uint64_t b, uint64_t *hi, uint64_t *lo);
/* Compare a*b with c*d exactly (all unsigned 64-bit): returns -1, 0 or 1. */
int cs_fixed_cmp_prod_u64(uint64_t a, uint64_t b, uint64_t c, uint64_t d);

/* Conversions between vectors. */
cs_vec3_t cs_fixed_vec(cs_pos_t x, cs_pos_t y, cs_pos_t z);

/* *out = round(a * b / c) (half away from zero) with a 128-bit intermediate product, so change
 * of basis and linear solves can scale by exact rationals with one rounding; c != 0 (CS_ERR_ARG),
 * CS_ERR_OVERFLOW when the quotient leaves int64. a, b, c must not be INT64_MIN (CS_ERR_ARG). */
cs_err_t cs_fixed_muldiv64(int64_t a, int64_t b, int64_t c, int64_t *out);

/* --- wide helpers (added with cs_bezier / cs_join / cs_arclen, which all need them) --- */
/* round(x * t / 2^30) (half away from zero) for |x| < 2^62 and |t| <= 2^30, with no
 * intermediate overflow (64x32 product done in two halves): the de Casteljau step on int64
 * values that carry guard bits. ISR-safe (pure). */
int64_t cs_fixed_mul64_q30(int64_t x, int32_t t);
/* *q = round((hi * 2^64 + lo) / d) (half up), by restoring long division (no libc, no 128-bit
 * type). CS_ERR_ARG when d == 0 or d >= 2^63; CS_ERR_OVERFLOW when the quotient needs more
 * than 64 bits. ISR-safe (pure). */
cs_err_t cs_fixed_div_u128(uint64_t hi, uint64_t lo, uint64_t d, uint64_t *q);
/* Euclidean length of an int64 vector (|components| <= 2^62), rounded down. Exact (floor of the
 * true length) while every |component| < 2^31; above that the components are shifted right
 * until they fit, and the result is below the true length by less than 3 * 2^-30 of it. */
uint64_t cs_fixed_vec_len64(int64_t x, int64_t y, int64_t z);
/* The binomial coefficient C(n, k) for n <= CS_FIXED_BINOM_MAX (0 when k > n or n is beyond it):
 * the one table the Bernstein, power-basis and forward-difference code shares. ISR-safe. */
#define CS_FIXED_BINOM_MAX 7
uint8_t cs_fixed_binom(unsigned n, unsigned k);


#endif
