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

/* floor(sqrt(v)) for any uint64, exact, no float (CS_FIXED_WIDE: Newton by native 64-bit
 * division from a tangent seed, 4 or 5 divisions; else bitwise digit steps, no division). */
uint32_t cs_fixed_isqrt64(uint64_t v);
/* Euclidean length of a vector, in cs_pos_t units (rounded down): exact integer sqrt of the
 * 64-bit sum of squares (|component| <= 2^30 keeps the sum inside uint64). */
uint32_t cs_fixed_vec_len(int64_t dx, int64_t dy, int64_t dz);

/* CS_FIXED_WIDE 1: the compiler has a 128-bit integer (64-bit hosts), so cs_fixed_mul_u64 is one
 * multiply and, in hosted builds only (libgcc's divide: a freestanding core calls nothing outside
 * itself), cs_fixed_muldiv64 and cs_fixed_div_u128 divide natively, and cs_fixed_isqrt64 is
 * Newton's iteration on 64-bit divisions; same results. 0: the portable loops every MCU runs
 * (tests/unit/test_fixed_narrow runs test_fixed on them). */
#ifndef CS_FIXED_WIDE
#if defined(__SIZEOF_INT128__)
#define CS_FIXED_WIDE 1
#else
#define CS_FIXED_WIDE 0
#endif
#endif

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
/* a + round((b - a) * t / 2^30): the de Casteljau step between two int64 values, |b - a| < 2^62,
 * t a Q1.30 parameter. ISR-safe (pure). */
static inline int64_t cs_fixed_lerp64(int64_t a, int64_t b, int32_t t)
{
    return a + cs_fixed_mul64_q30(b - a, t);
}
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


/* --- primitives every module shares, each with its rounding rule stated here once --- */
/* round(n / d) for d > 0, half away from zero (-2.5 -> -3); |n| + d/2 must not overflow int64.
 * ISR-safe (pure). */
int64_t cs_fixed_div_round(int64_t n, int64_t d);
/* Number of significant bits of v (0 for 0, 64 for 2^63..). ISR-safe (pure). Inline where the
 * core counts leading zeros in one instruction (64-bit hosts, Thumb-2): the predicted-step
 * tracer asks for it four times a flatness test (a call was 5 % of its host instructions). */
#if defined(__GNUC__) &&                                                                           \
    (defined(__SIZEOF_INT128__) || (defined(__ARM_ARCH_ISA_THUMB) && __ARM_ARCH_ISA_THUMB >= 2))
#define CS_FIXED_BITLEN_INLINE 1
static inline unsigned cs_fixed_bitlen64(uint64_t v)
{
    return v == 0 ? 0u : 64u - (unsigned)__builtin_clzll(v);
}
#else
unsigned cs_fixed_bitlen64(uint64_t v);
#endif

/* Coordinate `axis` (0 = x, 1 = y, 2 = z) of a vector: the one accessor the per-axis loops of
 * the curve, surface and basis code share. axis must be < 3. */
static inline cs_pos_t cs_fixed_vec_get(const cs_vec3_t *p, unsigned axis)
{
    return axis == 0 ? p->x : axis == 1 ? p->y : p->z;
}
/* Sets coordinate `axis` (0..2) of *p to v. */
static inline void cs_fixed_vec_set(cs_vec3_t *p, unsigned axis, cs_pos_t v)
{
    if (axis == 0)
        p->x = v;
    else if (axis == 1)
        p->y = v;
    else
        p->z = v;
}

/* Two's-complement 128-bit integer as two words (no __int128 on the 8- and 32-bit targets).
 * Add, subtract and negate wrap modulo 2^128 like unsigned C arithmetic; callers bound their
 * values (cs_fd keeps rational accumulators below 2^126). All ISR-safe (pure). */
typedef struct {
    uint64_t lo, hi;
} cs_i128_t;

static inline cs_i128_t cs_fixed_i128_from64(int64_t v)
{
    cs_i128_t r;
    r.lo = (uint64_t)v;
    r.hi = v < 0 ? UINT64_MAX : 0u;
    return r;
}
static inline cs_i128_t cs_fixed_i128_add(cs_i128_t a, cs_i128_t b)
{
    cs_i128_t r;
    r.lo = a.lo + b.lo;
    r.hi = a.hi + b.hi + (r.lo < a.lo ? 1u : 0u);
    return r;
}
static inline cs_i128_t cs_fixed_i128_sub(cs_i128_t a, cs_i128_t b)
{
    cs_i128_t r;
    r.lo = a.lo - b.lo;
    r.hi = a.hi - b.hi - (a.lo < b.lo ? 1u : 0u);
    return r;
}
static inline bool cs_fixed_i128_is_neg(cs_i128_t a)
{
    return (a.hi >> 63) != 0;
}
static inline cs_i128_t cs_fixed_i128_neg(cs_i128_t a)
{
    cs_i128_t zero = {0u, 0u};
    return cs_fixed_i128_sub(zero, a);
}
/* a * m, exact while |a * m| < 2^127 (the caller's bound), sign kept. */
cs_i128_t cs_fixed_i128_mul_u64(cs_i128_t a, uint64_t m);
/* Logical a >> s of a non-negative (magnitude) value, 0 < s < 128. */
cs_i128_t cs_fixed_u128_shr(cs_i128_t a, unsigned s);

#endif
