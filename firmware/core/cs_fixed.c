/* cs_fixed: checked fixed-point arithmetic. Every narrowing goes through cs_fixed_narrow so an
 * overflow is a reported error, never a wrap (DESIGN.md, "Rules for firmware/core"). */
#include "cs_fixed.h"

CS_STATIC_ASSERT(sizeof(cs_pos_t) == 4, pos_is_32_bit);
CS_STATIC_ASSERT(((int64_t)CS_POS_LIMIT * 8) <= INT32_MAX + 1LL, limit_leaves_3_bits_headroom);

bool cs_fixed_pos_ok(int64_t v)
{
    return v >= -(int64_t)CS_POS_LIMIT && v <= (int64_t)CS_POS_LIMIT;
}

bool cs_fixed_vec_ok(const cs_vec3_t *p)
{
    return cs_fixed_pos_ok(p->x) && cs_fixed_pos_ok(p->y) && cs_fixed_pos_ok(p->z);
}

cs_err_t cs_fixed_narrow(int64_t v, int32_t *out)
{
    if (v > INT32_MAX || v < INT32_MIN)
        return CS_ERR_OVERFLOW;
    *out = (int32_t)v;
    return CS_OK;
}

cs_err_t cs_fixed_add(int32_t a, int32_t b, int32_t *out)
{
    return cs_fixed_narrow((int64_t)a + b, out);
}

cs_err_t cs_fixed_sub(int32_t a, int32_t b, int32_t *out)
{
    return cs_fixed_narrow((int64_t)a - b, out);
}

int64_t cs_fixed_round_shift64(int64_t v, unsigned n)
{
    if (n == 0)
        return v;
    /* Work on the magnitude so rounding is symmetric (half away from zero); INT64_MIN has no
     * magnitude in int64, but no caller can produce it (products of two int32 are > -2^62). */
    uint64_t m = v < 0 ? (uint64_t)0 - (uint64_t)v : (uint64_t)v;
    m = ((m >> (n - 1)) + 1) >> 1; /* = (m + 2^(n-1)) >> n: floors nest; no 64-bit left shift */
    return v < 0 ? -(int64_t)m : (int64_t)m;
}

cs_err_t cs_fixed_mul_shift(int32_t a, int32_t b, unsigned shift, int32_t *out)
{
    if (shift > 62)
        return CS_ERR_ARG;
    return cs_fixed_narrow(cs_fixed_round_shift64((int64_t)a * b, shift), out);
}

cs_err_t cs_fixed_div_shift(int32_t a, int32_t b, unsigned shift, int32_t *out)
{
    if (b == 0 || shift > 30)
        return CS_ERR_ARG;
    /* |a| * 2^30 < 2^62: the numerator always fits int64. */
    uint64_t num = (uint64_t)(a < 0 ? -(int64_t)a : (int64_t)a) << shift;
    uint64_t den = (uint64_t)(b < 0 ? -(int64_t)b : (int64_t)b);
    uint64_t q = (num + den / 2) / den;
    int64_t s = ((a < 0) != (b < 0)) ? -(int64_t)q : (int64_t)q;
    return cs_fixed_narrow(s, out);
}

int32_t cs_fixed_add_sat(int32_t a, int32_t b)
{
    int64_t s = (int64_t)a + b;
    return s > INT32_MAX ? INT32_MAX : s < INT32_MIN ? INT32_MIN : (int32_t)s;
}

int32_t cs_fixed_sub_sat(int32_t a, int32_t b)
{
    int64_t s = (int64_t)a - b;
    return s > INT32_MAX ? INT32_MAX : s < INT32_MIN ? INT32_MIN : (int32_t)s;
}

uint32_t cs_fixed_isqrt64(uint64_t v)
{
#if CS_FIXED_WIDE /* a 64-bit host: 64-bit division is one instruction (no libgcc call) */
    /* Newton from above, x' = floor((x + floor(v/x)) / 2), stops at floor(sqrt(v)) exactly (the
     * integer iteration never goes below it and decreases while x > floor(sqrt v)). Seed: v
     * shifted by an even e into [2^62, 2^64), t = its top 32 bits = X 2^30 (X in [1, 4)); the
     * tangent of sqrt at X = 2, (X + 2) / (2 sqrt 2), lies above sqrt (concave), at most 6.1 %:
     * 4 divisions to the floor instead of 32 digit steps (the arc tracer's set-up). */
    if (v < 2)
        return (uint32_t)v;
    unsigned e = (64u - cs_fixed_bitlen64(v)) & ~1u;
    uint64_t m = v << e, u = (m >> 34) + ((uint64_t)1 << 29); /* (t + 2^31) / 4 */
    uint64_t x = ((u * 3037000500u) >> 30) + 4; /* (t + 2^31) / sqrt 2, + 4 for the floors */
    for (uint64_t y = (x + m / x) >> 1; y < x; y = (x + m / x) >> 1)
        x = y;
    return (uint32_t)(x >> (e / 2));
#else
    /* Digit-by-digit (base 4) square root: 32 iterations of shift, compare, subtract. */
    uint64_t rem = v, root = 0, bit = (uint64_t)1 << 62;
    while (bit > rem)
        bit >>= 2;
    while (bit != 0) {
        if (rem >= root + bit) {
            rem -= root + bit;
            root = (root >> 1) + bit;
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    return (uint32_t)root;
#endif
}

uint32_t cs_fixed_vec_len(int64_t dx, int64_t dy, int64_t dz)
{
    uint64_t ax = (uint64_t)(dx < 0 ? -dx : dx), ay = (uint64_t)(dy < 0 ? -dy : dy),
             az = (uint64_t)(dz < 0 ? -dz : dz);
    return cs_fixed_isqrt64(ax * ax + ay * ay + az * az);
}

void cs_fixed_mul_u64(uint64_t a, uint64_t b, uint64_t *hi, uint64_t *lo)
{
#if CS_FIXED_WIDE /* a 64-bit host: one multiply instruction */
    unsigned __int128 p = (unsigned __int128)a * b;
    *hi = (uint64_t)(p >> 64);
    *lo = (uint64_t)p;
#else
    /* Schoolbook on 32-bit halves; the carries are summed in 64 bits so none is lost. */
    uint64_t a0 = a & 0xFFFFFFFFu, a1 = a >> 32, b0 = b & 0xFFFFFFFFu, b1 = b >> 32;
    uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
    uint64_t mid = (p00 >> 32) + (p01 & 0xFFFFFFFFu) + (p10 & 0xFFFFFFFFu);
    *lo = (p00 & 0xFFFFFFFFu) | (mid << 32);
    *hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
#endif
}

int cs_fixed_cmp_prod_u64(uint64_t a, uint64_t b, uint64_t c, uint64_t d)
{
    uint64_t h1, l1, h2, l2;
    cs_fixed_mul_u64(a, b, &h1, &l1);
    cs_fixed_mul_u64(c, d, &h2, &l2);
    if (h1 != h2)
        return h1 < h2 ? -1 : 1;
    if (l1 != l2)
        return l1 < l2 ? -1 : 1;
    return 0;
}

cs_vec3_t cs_fixed_vec(cs_pos_t x, cs_pos_t y, cs_pos_t z)
{
    cs_vec3_t v = {x, y, z};
    return v;
}

cs_err_t cs_fixed_muldiv64(int64_t a, int64_t b, int64_t c, int64_t *out)
{
    if (c == 0 || a == INT64_MIN || b == INT64_MIN || c == INT64_MIN)
        return CS_ERR_ARG;
    bool neg = (a < 0) != (b < 0);
    if (c < 0)
        neg = !neg;
    uint64_t ua = (uint64_t)(a < 0 ? -a : a), ub = (uint64_t)(b < 0 ? -b : b),
             uc = (uint64_t)(c < 0 ? -c : c);
    uint64_t hi, lo;
    cs_fixed_mul_u64(ua, ub, &hi, &lo);
    /* The quotient fits 64 bits only when hi < c; then restoring long division over the 64 low
     * bits, starting from the remainder hi (bit-serial: no 128-bit type on 8/32-bit targets). */
    if (hi >= uc)
        return CS_ERR_OVERFLOW;
    uint64_t rem = hi, q = 0;
#if CS_FIXED_WIDE && __STDC_HOSTED__ /* 64-bit host: natively (libgcc's divide) */
    unsigned __int128 n = ((unsigned __int128)hi << 64) | lo;
    q = (uint64_t)(n / uc);
    rem = (uint64_t)(n % uc);
#else
    for (int i = 63; i >= 0; i--) {
        uint64_t carry = rem >> 63;
        rem = (rem << 1) | ((lo >> i) & 1u);
        q <<= 1;
        if (carry != 0 || rem >= uc) {
            rem -= uc;
            q |= 1u;
        }
    }
#endif
    /* Round half away from zero: rem >= c - rem (no overflow of 2 * rem). Check the range
     * before the increment too: q = UINT64_MAX would wrap to 0 and pass the check. */
    if (q > (uint64_t)INT64_MAX)
        return CS_ERR_OVERFLOW;
    if (rem >= uc - rem)
        q++;
    if (q > (uint64_t)INT64_MAX)
        return CS_ERR_OVERFLOW;
    *out = neg ? -(int64_t)q : (int64_t)q;
    return CS_OK;
}

int64_t cs_fixed_mul64_q30(int64_t x, int32_t t)
{
    /* |x| = xh * 2^32 + xl: |x| * |t| / 2^30 = xh * |t| * 4 + xl * |t| / 2^30, and only the
     * second term needs rounding. Each partial product stays below 2^62. */
    uint64_t m = x < 0 ? (uint64_t)0 - (uint64_t)x : (uint64_t)x;
    /* |t| <= 2^31 and both halves of m fit 32 bits: two 32x32 -> 64 products (UMULL on a
     * Cortex-M3), not 64x64 ones. */
    uint32_t at = t < 0 ? 0u - (uint32_t)t : (uint32_t)t;
    uint64_t hi = (uint64_t)(uint32_t)(m >> 32) * at, lo = (uint64_t)(uint32_t)m * at;
    uint64_t r = (hi << 2) + ((lo + ((uint64_t)1 << 29)) >> 30);
    return ((x < 0) != (t < 0)) ? -(int64_t)r : (int64_t)r;
}

cs_err_t cs_fixed_div_u128(uint64_t hi, uint64_t lo, uint64_t d, uint64_t *q)
{
    if (d == 0 || (d >> 63) != 0)
        return CS_ERR_ARG;
    if (hi >= d)
        return CS_ERR_OVERFLOW;
    /* rem < d < 2^63 throughout, so rem << 1 never loses a bit. */
    uint64_t rem = hi, quo = 0;
#if CS_FIXED_WIDE && __STDC_HOSTED__ /* 64-bit host: natively (libgcc's divide) */
    unsigned __int128 n = ((unsigned __int128)hi << 64) | lo;
    quo = (uint64_t)(n / d);
    rem = (uint64_t)(n % d);
#else
    for (unsigned i = 64; i-- > 0;) {
        rem = (rem << 1) | ((lo >> i) & 1u);
        quo <<= 1;
        if (rem >= d) {
            rem -= d;
            quo |= 1u;
        }
    }
#endif
    if (rem >= d - rem) { /* 2 * rem >= d: round half up */
        if (quo == UINT64_MAX)
            return CS_ERR_OVERFLOW;
        quo++;
    }
    *q = quo;
    return CS_OK;
}

uint64_t cs_fixed_vec_len64(int64_t x, int64_t y, int64_t z)
{
    uint64_t ax = x < 0 ? (uint64_t)0 - (uint64_t)x : (uint64_t)x;
    uint64_t ay = y < 0 ? (uint64_t)0 - (uint64_t)y : (uint64_t)y;
    uint64_t az = z < 0 ? (uint64_t)0 - (uint64_t)z : (uint64_t)z;
    uint64_t mx = ax | ay | az;
    /* Components below 2^31 keep the sum of squares below 3 * 2^62 < 2^64: the least such s. */
    unsigned b = cs_fixed_bitlen64(mx), s = b > 31 ? b - 31 : 0;
    ax >>= s;
    ay >>= s;
    az >>= s;
    return (uint64_t)cs_fixed_isqrt64(ax * ax + ay * ay + az * az) << s;
}

/* Pascal's triangle up to row CS_FIXED_BINOM_MAX (the core's highest degree); C(7, 3) = 35 fits
 * a byte. */
static const uint8_t binom_table[CS_FIXED_BINOM_MAX + 1][CS_FIXED_BINOM_MAX + 1] = {
    {1},
    {1, 1},
    {1, 2, 1},
    {1, 3, 3, 1},
    {1, 4, 6, 4, 1},
    {1, 5, 10, 10, 5, 1},
    {1, 6, 15, 20, 15, 6, 1},
    {1, 7, 21, 35, 35, 21, 7, 1},
};

uint8_t cs_fixed_binom(unsigned n, unsigned k)
{
    return n <= CS_FIXED_BINOM_MAX && k <= n ? binom_table[n][k] : 0;
}

int64_t cs_fixed_div_round(int64_t n, int64_t d)
{
    int64_t m = n < 0 ? -n : n, q = (m + d / 2) / d;
    return n < 0 ? -q : q;
}

#if !defined(CS_FIXED_BITLEN_INLINE) /* else inline in cs_fixed.h */
unsigned cs_fixed_bitlen64(uint64_t v)
{
#if defined(__GNUC__) && !(defined(__ARM_ARCH_ISA_THUMB) && __ARM_ARCH_ISA_THUMB == 1)
    /* one count-leading-zeros call (AVR: libgcc's) */
    return v == 0 ? 0u : 64u - (unsigned)__builtin_clzll(v);
#else
    /* Thumb-1 (Cortex-M0+) has no CLZ and libgcc's takes 84 bytes: halving on the 32-bit half
     * that holds the top bit, 5 steps */
    uint32_t x = (uint32_t)(v >> 32);
    unsigned b = 32;
    if (x == 0) {
        x = (uint32_t)v;
        b = 0;
    }
    for (unsigned step = 16; step != 0; step >>= 1)
        if ((x >> step) != 0) {
            x >>= step;
            b += step;
        }
    return b + (unsigned)x; /* x is now 0 or 1 */
#endif
}
#endif

cs_i128_t cs_fixed_i128_mul_u64(cs_i128_t a, uint64_t m)
{
    bool neg = cs_fixed_i128_is_neg(a);
    cs_i128_t mag = neg ? cs_fixed_i128_neg(a) : a, r;
    uint64_t h;
    cs_fixed_mul_u64(mag.lo, m, &h, &r.lo);
    r.hi = mag.hi * m + h;
    return neg ? cs_fixed_i128_neg(r) : r;
}

cs_i128_t cs_fixed_u128_shr(cs_i128_t a, unsigned s)
{
    cs_i128_t r;
    if (s >= 64) {
        r.lo = a.hi >> (s - 64);
        r.hi = 0u;
    } else {
        r.lo = (a.lo >> s) | (a.hi << (64 - s));
        r.hi = a.hi >> s;
    }
    return r;
}
