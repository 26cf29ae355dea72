/* Unit tests for cs_fixed: every checked operation against an exact __int128 / long double
 * reference (fine in tests), with overflow detection at the edges, rounding half away from
 * zero, isqrt64 exhaustively near squares, around powers of two and at UINT64_MAX, and the
 * 128-bit helpers. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "cs_fixed.h"
#include "ref_bezier.h"

typedef __int128 i128;
typedef unsigned __int128 u128;

/* round(n / 2^s) half away from zero, exact */
static i128 ref_round_shift(i128 n, unsigned s)
{
    if (s == 0)
        return n;
    i128 m = n < 0 ? -n : n;
    m = (m + ((i128)1 << (s - 1))) >> s;
    return n < 0 ? -m : m;
}

/* round(n / d) half away from zero, d != 0, exact */
static i128 ref_div_round(i128 n, i128 d)
{
    int neg = (n < 0) != (d < 0);
    u128 m = (u128)(n < 0 ? -n : n), dd = (u128)(d < 0 ? -d : d);
    u128 q = m / dd, r = m % dd;
    if (2 * r >= dd)
        q++;
    return neg ? -(i128)q : (i128)q;
}

static int32_t rand_i32(ref_rng_t *g)
{
    /* mix full-range values with small ones and the edges */
    switch (ref_rng_next(g) % 6) {
    case 0:
        return INT32_MAX - (int32_t)(ref_rng_next(g) % 3);
    case 1:
        return INT32_MIN + (int32_t)(ref_rng_next(g) % 3);
    case 2:
        return (int32_t)ref_rng_range(g, -1000, 1000);
    default:
        return (int32_t)(uint32_t)ref_rng_next(g);
    }
}

static void test_add_sub(void **state)
{
    (void)state;
    int32_t out = 12345;
    assert_int_equal(cs_fixed_add(INT32_MAX, 1, &out), CS_ERR_OVERFLOW);
    assert_int_equal(out, 12345); /* untouched on failure */
    assert_int_equal(cs_fixed_add(INT32_MIN, -1, &out), CS_ERR_OVERFLOW);
    assert_int_equal(cs_fixed_sub(INT32_MIN, 1, &out), CS_ERR_OVERFLOW);
    assert_int_equal(cs_fixed_sub(0, INT32_MIN, &out), CS_ERR_OVERFLOW);
    assert_int_equal(cs_fixed_sub(-1, INT32_MIN, &out), CS_OK);
    assert_int_equal(out, INT32_MAX);
    assert_int_equal(cs_fixed_add(INT32_MAX, INT32_MIN, &out), CS_OK);
    assert_int_equal(out, -1);
    ref_rng_t g;
    ref_rng_seed(&g, 1);
    for (int i = 0; i < 200000; i++) {
        int32_t a = rand_i32(&g), b = rand_i32(&g);
        int64_t s = (int64_t)a + b, d = (int64_t)a - b;
        cs_err_t e = cs_fixed_add(a, b, &out);
        assert_int_equal(e, (s > INT32_MAX || s < INT32_MIN) ? CS_ERR_OVERFLOW : CS_OK);
        if (e == CS_OK)
            assert_int_equal(out, s);
        e = cs_fixed_sub(a, b, &out);
        assert_int_equal(e, (d > INT32_MAX || d < INT32_MIN) ? CS_ERR_OVERFLOW : CS_OK);
        if (e == CS_OK)
            assert_int_equal(out, d);
        /* saturating: the clamped exact value */
        int64_t ss = s > INT32_MAX ? INT32_MAX : s < INT32_MIN ? INT32_MIN : s;
        int64_t sd = d > INT32_MAX ? INT32_MAX : d < INT32_MIN ? INT32_MIN : d;
        assert_int_equal(cs_fixed_add_sat(a, b), ss);
        assert_int_equal(cs_fixed_sub_sat(a, b), sd);
    }
}

static void test_narrow(void **state)
{
    (void)state;
    int32_t out = 7;
    assert_int_equal(cs_fixed_narrow((int64_t)INT32_MAX + 1, &out), CS_ERR_OVERFLOW);
    assert_int_equal(cs_fixed_narrow((int64_t)INT32_MIN - 1, &out), CS_ERR_OVERFLOW);
    assert_int_equal(out, 7);
    assert_int_equal(cs_fixed_narrow(INT32_MIN, &out), CS_OK);
    assert_int_equal(out, INT32_MIN);
    assert_int_equal(cs_fixed_narrow(INT64_MAX, &out), CS_ERR_OVERFLOW);
    assert_true(cs_fixed_pos_ok(CS_POS_LIMIT) && cs_fixed_pos_ok(-CS_POS_LIMIT));
    assert_false(cs_fixed_pos_ok(CS_POS_LIMIT + 1) || cs_fixed_pos_ok(-CS_POS_LIMIT - 1));
    cs_vec3_t v = cs_fixed_vec(1, CS_POS_LIMIT + 1, 3);
    assert_false(cs_fixed_vec_ok(&v));
    v.y = -CS_POS_LIMIT;
    assert_true(cs_fixed_vec_ok(&v));
}

static void test_round_shift(void **state)
{
    (void)state;
    assert_int_equal(cs_fixed_round_shift64(3, 1), 2);   /* 1.5 -> 2 */
    assert_int_equal(cs_fixed_round_shift64(-3, 1), -2); /* -1.5 -> -2 (symmetric) */
    assert_int_equal(cs_fixed_round_shift64(-5, 2), -1); /* -1.25 -> -1 */
    assert_int_equal(cs_fixed_round_shift64(-6, 2), -2); /* -1.5 -> -2 */
    assert_int_equal(cs_fixed_round_shift64(INT64_MAX, 0), INT64_MAX);
    ref_rng_t g;
    ref_rng_seed(&g, 2);
    for (int i = 0; i < 200000; i++) {
        int64_t v = (int64_t)(ref_rng_next(&g) >> (ref_rng_next(&g) % 40 + 1));
        if (ref_rng_next(&g) & 1)
            v = -v;
        unsigned n = (unsigned)(ref_rng_next(&g) % 63);
        assert_true(cs_fixed_round_shift64(v, n) == (int64_t)ref_round_shift(v, n));
    }
}

static void test_mul_shift(void **state)
{
    (void)state;
    int32_t out = 0;
    assert_int_equal(cs_fixed_mul_shift(3, 1, 1, &out), CS_OK);
    assert_int_equal(out, 2);
    assert_int_equal(cs_fixed_mul_shift(-3, 1, 1, &out), CS_OK);
    assert_int_equal(out, -2);
    assert_int_equal(cs_fixed_mul_shift(INT32_MIN, INT32_MIN, 0, &out), CS_ERR_OVERFLOW);
    assert_int_equal(cs_fixed_mul_shift(INT32_MIN, INT32_MIN, 31, &out), CS_ERR_OVERFLOW);
    assert_int_equal(cs_fixed_mul_shift(INT32_MIN, INT32_MIN, 32, &out), CS_OK);
    assert_int_equal(out, 1 << 30);
    assert_int_equal(cs_fixed_mul_shift(1, 1, 63, &out), CS_ERR_ARG);
    ref_rng_t g;
    ref_rng_seed(&g, 3);
    for (int i = 0; i < 300000; i++) {
        int32_t a = rand_i32(&g), b = rand_i32(&g);
        unsigned s = (unsigned)(ref_rng_next(&g) % 63);
        i128 r = ref_round_shift((i128)a * b, s);
        cs_err_t e = cs_fixed_mul_shift(a, b, s, &out);
        if (r > INT32_MAX || r < INT32_MIN) {
            assert_int_equal(e, CS_ERR_OVERFLOW);
        } else {
            assert_int_equal(e, CS_OK);
            assert_true(out == (int64_t)r);
        }
    }
}

static void test_div_shift(void **state)
{
    (void)state;
    int32_t out = 0;
    assert_int_equal(cs_fixed_div_shift(1, 0, 0, &out), CS_ERR_ARG);
    assert_int_equal(cs_fixed_div_shift(1, 1, 31, &out), CS_ERR_ARG);
    assert_int_equal(cs_fixed_div_shift(1, 2, 0, &out), CS_OK); /* 0.5 -> 1 */
    assert_int_equal(out, 1);
    assert_int_equal(cs_fixed_div_shift(-1, 2, 0, &out), CS_OK); /* -0.5 -> -1 */
    assert_int_equal(out, -1);
    assert_int_equal(cs_fixed_div_shift(INT32_MIN, -1, 0, &out), CS_ERR_OVERFLOW);
    assert_int_equal(cs_fixed_div_shift(INT32_MIN, INT32_MIN, 30, &out), CS_OK);
    assert_int_equal(out, 1 << 30);
    ref_rng_t g;
    ref_rng_seed(&g, 4);
    for (int i = 0; i < 300000; i++) {
        int32_t a = rand_i32(&g), b = rand_i32(&g);
        if (b == 0)
            continue;
        unsigned s = (unsigned)(ref_rng_next(&g) % 31);
        i128 r = ref_div_round((i128)a * ((i128)1 << s), b);
        cs_err_t e = cs_fixed_div_shift(a, b, s, &out);
        if (r > INT32_MAX || r < INT32_MIN) {
            assert_int_equal(e, CS_ERR_OVERFLOW);
        } else {
            assert_int_equal(e, CS_OK);
            assert_true(out == (int64_t)r);
        }
    }
}

static void check_isqrt(uint64_t v)
{
    uint64_t r = cs_fixed_isqrt64(v);
    if (!((u128)r * r <= v && (u128)(r + 1) * (r + 1) > v))
        fail_msg("isqrt64(%llu) = %llu", (unsigned long long)v, (unsigned long long)r);
}

static void test_isqrt64(void **state)
{
    (void)state;
    assert_int_equal(cs_fixed_isqrt64(UINT64_MAX), 4294967295u);
    assert_int_equal(cs_fixed_isqrt64(0), 0);
    assert_int_equal(cs_fixed_isqrt64(1), 1);
    assert_int_equal(cs_fixed_isqrt64(3), 1);
    assert_int_equal(cs_fixed_isqrt64(4), 2);
    for (uint64_t v = 0; v < (1u << 20); v++)
        check_isqrt(v);
    /* near every square k^2 for k near powers of two, near 2^32 and at random k */
    ref_rng_t g;
    ref_rng_seed(&g, 5);
    for (int i = 0; i < 200000; i++) {
        uint64_t k;
        if (i < 64 * 64) {
            unsigned p = (unsigned)(i / 64) % 33;
            k = ((uint64_t)1 << (p > 32 ? 32 : p)) + (uint64_t)(i % 64) - 32;
        } else {
            k = ref_rng_next(&g) >> 32;
        }
        if (k > 0xFFFFFFFFull)
            k = 0xFFFFFFFFull;
        uint64_t sq = k * k;
        check_isqrt(sq);
        if (sq > 0)
            check_isqrt(sq - 1);
        if (sq < UINT64_MAX)
            check_isqrt(sq + 1);
        if (k < 0xFFFFFFFFull)
            check_isqrt((k + 1) * (k + 1) - 1);
        check_isqrt(ref_rng_next(&g));
    }
    check_isqrt(UINT64_MAX - 1);
    check_isqrt(0xFFFFFFFE00000001ull); /* (2^32 - 1)^2 */
    check_isqrt(0xFFFFFFFE00000000ull);
    /* the 64-bit hosts' Newton seed (a tangent of sqrt) is tightest where the normalised v is
     * 2^63 (X = 2): around 2^(2j+1) and 2^(2j) at every bit length, and random bit lengths */
    for (unsigned j = 0; j < 32; j++)
        for (uint64_t d = 0; d < 64; d++) {
            uint64_t a = (uint64_t)1 << (2 * j + 1), b = (uint64_t)1 << (2 * j);
            check_isqrt(a + d);
            check_isqrt(b + d);
            if (d < b) {
                check_isqrt(a - d - 1);
                check_isqrt(b - d);
            }
        }
    for (int i = 0; i < 100000; i++)
        check_isqrt(ref_rng_next(&g) >> (ref_rng_next(&g) % 64));
}

static void test_vec_len(void **state)
{
    (void)state;
    ref_rng_t g;
    ref_rng_seed(&g, 6);
    assert_int_equal(cs_fixed_vec_len(3, -4, 0), 5);
    assert_int_equal(cs_fixed_vec_len(1 << 30, 1 << 30, 1 << 30),
                     1859775393u); /* floor(2^30 sqrt 3) */
    for (int i = 0; i < 100000; i++) {
        int64_t x = ref_rng_range(&g, -(1 << 30), 1 << 30),
                y = ref_rng_range(&g, -(1 << 30), 1 << 30),
                z = ref_rng_range(&g, -(1 << 30), 1 << 30);
        u128 s = (u128)(x * x) + (u128)(y * y) + (u128)(z * z);
        uint64_t r = cs_fixed_vec_len(x, y, z);
        assert_true((u128)r * r <= s && (u128)(r + 1) * (r + 1) > s);
        /* vec_len64: exact below 2^31, within 3 * 2^-30 relative above */
        int sh = (int)(ref_rng_next(&g) % 33);
        int64_t X = x * ((int64_t)1 << sh), Y = y * ((int64_t)1 << sh), Z = z * ((int64_t)1 << sh);
        uint64_t R = cs_fixed_vec_len64(X, Y, Z);
        long double exact = sqrtl((long double)X * X + (long double)Y * Y + (long double)Z * Z);
        assert_true((long double)R <= exact + 1e-6L);
        if (sh == 0)
            assert_true(R == r);
        else
            assert_true(exact - R <= 3.0L * exact / 1073741824.0L + 1.0L);
    }
}

static void test_mul_u64_cmp(void **state)
{
    (void)state;
    ref_rng_t g;
    ref_rng_seed(&g, 7);
    uint64_t hi, lo;
    cs_fixed_mul_u64(UINT64_MAX, UINT64_MAX, &hi, &lo);
    assert_true(hi == UINT64_MAX - 1 && lo == 1);
    for (int i = 0; i < 200000; i++) {
        uint64_t a = ref_rng_next(&g) >> (ref_rng_next(&g) % 64);
        uint64_t b = ref_rng_next(&g) >> (ref_rng_next(&g) % 64);
        if (i % 7 == 0)
            a = UINT64_MAX - (ref_rng_next(&g) % 4);
        cs_fixed_mul_u64(a, b, &hi, &lo);
        u128 p = (u128)a * b;
        assert_true(hi == (uint64_t)(p >> 64) && lo == (uint64_t)p);
        uint64_t c = ref_rng_next(&g), d = i % 3 ? ref_rng_next(&g) : b;
        if (i % 5 == 0) { /* equal products by swapping */
            c = b;
            d = a;
        }
        u128 q = (u128)c * d;
        int want = p < q ? -1 : p > q ? 1 : 0;
        assert_int_equal(cs_fixed_cmp_prod_u64(a, b, c, d), want);
    }
}

static void test_muldiv64(void **state)
{
    (void)state;
    int64_t out = 0;
    assert_int_equal(cs_fixed_muldiv64(1, 1, 0, &out), CS_ERR_ARG);
    assert_int_equal(cs_fixed_muldiv64(INT64_MIN, 1, 1, &out), CS_ERR_ARG);
    assert_int_equal(cs_fixed_muldiv64(3, 1, 2, &out), CS_OK);
    assert_int_equal(out, 2);
    assert_int_equal(cs_fixed_muldiv64(-3, 1, 2, &out), CS_OK);
    assert_int_equal(out, -2);
    assert_int_equal(cs_fixed_muldiv64(INT64_MAX, INT64_MAX, INT64_MAX, &out), CS_OK);
    assert_true(out == INT64_MAX);
    /* exact value 2^64 - 1/2: the floor is UINT64_MAX, rounding must not wrap it to 0 */
    int64_t b = (int64_t)((((u128)1 << 65) - 1) / 31);
    assert_true((u128)31 * (u128)b == ((u128)1 << 65) - 1);
    out = 12345;
    assert_int_equal(cs_fixed_muldiv64(31, b, 2, &out), CS_ERR_OVERFLOW);
    /* exact value (2^64 - 1) / 2 = INT64_MAX + 1/2 rounds to 2^63: overflow */
    assert_true((u128)65535 * 281479271743489ull == (u128)UINT64_MAX);
    assert_int_equal(cs_fixed_muldiv64(65535, 281479271743489ll, 2, &out), CS_ERR_OVERFLOW);
    assert_int_equal(cs_fixed_muldiv64(-65535, 281479271743489ll, 2, &out), CS_ERR_OVERFLOW);
    assert_int_equal(cs_fixed_muldiv64(INT64_MAX, 2, 2, &out), CS_OK);
    assert_true(out == INT64_MAX);
    ref_rng_t g;
    ref_rng_seed(&g, 8);
    for (int i = 0; i < 200000; i++) {
        int64_t x = (int64_t)(ref_rng_next(&g) >> (ref_rng_next(&g) % 63 + 1));
        int64_t y = (int64_t)(ref_rng_next(&g) >> (ref_rng_next(&g) % 63 + 1));
        int64_t z = (int64_t)(ref_rng_next(&g) >> (ref_rng_next(&g) % 63 + 1));
        if (z == 0)
            continue;
        if (ref_rng_next(&g) & 1)
            x = -x;
        if (ref_rng_next(&g) & 1)
            z = -z;
        i128 r = ref_div_round((i128)x * y, z);
        cs_err_t e = cs_fixed_muldiv64(x, y, z, &out);
        if (r > INT64_MAX || r < -INT64_MAX) {
            assert_int_equal(e, CS_ERR_OVERFLOW);
        } else {
            assert_int_equal(e, CS_OK);
            assert_true(out == (int64_t)r);
        }
    }
}

static void test_mul64_q30(void **state)
{
    (void)state;
    ref_rng_t g;
    ref_rng_seed(&g, 9);
    assert_true(cs_fixed_mul64_q30(3, 1 << 29) == 2);   /* 1.5 -> 2 */
    assert_true(cs_fixed_mul64_q30(-3, 1 << 29) == -2); /* -1.5 -> -2 */
    assert_true(cs_fixed_mul64_q30(((int64_t)1 << 62) - 1, 1 << 30) == ((int64_t)1 << 62) - 1);
    for (int i = 0; i < 300000; i++) {
        int64_t x = (int64_t)(ref_rng_next(&g) >> (ref_rng_next(&g) % 62 + 2)); /* < 2^62 */
        if (ref_rng_next(&g) & 1)
            x = -x;
        int32_t t = (int32_t)ref_rng_range(&g, -(1 << 30), 1 << 30);
        i128 r = ref_round_shift((i128)x * t, 30);
        assert_true(cs_fixed_mul64_q30(x, t) == (int64_t)r);
    }
}

static void test_div_u128(void **state)
{
    (void)state;
    uint64_t q = 5;
    assert_int_equal(cs_fixed_div_u128(0, 1, 0, &q), CS_ERR_ARG);
    assert_int_equal(cs_fixed_div_u128(0, 1, (uint64_t)1 << 63, &q), CS_ERR_ARG);
    assert_int_equal(cs_fixed_div_u128(3, 0, 3, &q), CS_ERR_OVERFLOW);
    assert_int_equal(q, 5);
    /* (2^64 * 2 + 2^64 - 1) / 3 = 2^64 - 1/3 -> floor UINT64_MAX, remainder 2 rounds up: overflow
     */
    assert_int_equal(cs_fixed_div_u128(2, UINT64_MAX, 3, &q), CS_ERR_OVERFLOW);
    assert_int_equal(cs_fixed_div_u128(0, 1, 2, &q), CS_OK); /* 0.5 -> 1 (half up) */
    assert_true(q == 1);
    ref_rng_t g;
    ref_rng_seed(&g, 10);
    for (int i = 0; i < 200000; i++) {
        uint64_t d = ref_rng_next(&g) >> (ref_rng_next(&g) % 63 + 1);
        if (d == 0)
            continue;
        uint64_t hi = ref_rng_next(&g) % d, lo = ref_rng_next(&g);
        if (i % 3 == 0)
            hi = 0;
        u128 n = ((u128)hi << 64) | lo;
        u128 want = n / d + ((n % d) * 2 >= d ? 1 : 0);
        cs_err_t e = cs_fixed_div_u128(hi, lo, d, &q);
        if (want > UINT64_MAX) {
            assert_int_equal(e, CS_ERR_OVERFLOW);
        } else {
            assert_int_equal(e, CS_OK);
            assert_true(q == (uint64_t)want);
        }
    }
}

/* The one binomial table against n! / (k! (n - k)!) computed here, and 0 outside it. */
static void test_binom(void **state)
{
    (void)state;
    for (unsigned n = 0; n <= CS_FIXED_BINOM_MAX; n++)
        for (unsigned k = 0; k <= n + 1; k++) {
            unsigned long long f[9] = {1, 1, 2, 6, 24, 120, 720, 5040, 40320};
            unsigned long long want = k <= n ? f[n] / (f[k] * f[n - k]) : 0;
            assert_int_equal(cs_fixed_binom(n, k), want);
        }
    assert_int_equal(cs_fixed_binom(CS_FIXED_BINOM_MAX + 1, 1), 0);
}

/* cs_fixed_div_round against long double rounding half away from zero (ties built exactly). */
static void test_div_round(void **state)
{
    (void)state;
    uint64_t r = 0x9e3779b97f4a7c15ull;
    for (int i = 0; i < 20000; i++) {
        r = r * 6364136223846793005ull + 1442695040888963407ull;
        int64_t n = (int64_t)(r >> 3) >> (r & 31);
        if (r & 64)
            n = -n;
        int64_t d = (int64_t)((r >> 40) % 100000u) + 1;
        i128 q = (i128)n / d, rem = (i128)n % d; /* truncated */
        i128 twice = rem < 0 ? -2 * rem : 2 * rem;
        if (twice >= d)
            q += n < 0 ? -1 : 1;
        assert_true(cs_fixed_div_round(n, d) == (int64_t)q);
    }
    assert_int_equal(cs_fixed_div_round(5, 2), 3);
    assert_int_equal(cs_fixed_div_round(-5, 2), -3);
    assert_int_equal(cs_fixed_div_round(-4, 3), -1);
    assert_int_equal(cs_fixed_div_round(7, 1), 7);
}

/* Bit length against the position of the highest set bit, every power of two and its neighbours. */
static void test_bitlen64(void **state)
{
    (void)state;
    assert_int_equal(cs_fixed_bitlen64(0), 0);
    for (unsigned b = 0; b < 64; b++) {
        uint64_t v = (uint64_t)1 << b;
        assert_int_equal(cs_fixed_bitlen64(v), b + 1);
        assert_int_equal(cs_fixed_bitlen64(v | (v - 1)), b + 1);
        if (b > 0)
            assert_int_equal(cs_fixed_bitlen64(v - 1), b);
    }
}

/* The 3-vector accessor reads and writes the named field and no other. */
static void test_vec_access(void **state)
{
    (void)state;
    cs_vec3_t p = {1, -2, 3};
    assert_int_equal(cs_fixed_vec_get(&p, 0), 1);
    assert_int_equal(cs_fixed_vec_get(&p, 1), -2);
    assert_int_equal(cs_fixed_vec_get(&p, 2), 3);
    cs_fixed_vec_set(&p, 1, 77);
    assert_int_equal(p.x, 1);
    assert_int_equal(p.y, 77);
    assert_int_equal(p.z, 3);
    cs_fixed_vec_set(&p, 2, -9);
    cs_fixed_vec_set(&p, 0, 5);
    assert_int_equal(p.x, 5);
    assert_int_equal(p.z, -9);
}

static i128 from_pair(cs_i128_t a)
{
    return (i128)(((u128)a.hi << 64) | a.lo);
}

/* 128-bit add/sub/neg/mul/shift against __int128 on random values below 2^120. */
static void test_i128(void **state)
{
    (void)state;
    uint64_t r = 12345;
    for (int i = 0; i < 20000; i++) {
        r = r * 6364136223846793005ull + 1442695040888963407ull;
        int64_t a64 = (int64_t)r;
        r = r * 6364136223846793005ull + 1442695040888963407ull;
        int64_t b64 = (int64_t)r >> (r & 15);
        cs_i128_t a = cs_fixed_i128_from64(a64), b = cs_fixed_i128_from64(b64);
        assert_true(from_pair(a) == (i128)a64);
        assert_true(from_pair(cs_fixed_i128_add(a, b)) == (i128)a64 + b64);
        assert_true(from_pair(cs_fixed_i128_sub(a, b)) == (i128)a64 - b64);
        assert_true(from_pair(cs_fixed_i128_neg(a)) == -(i128)a64);
        assert_true(cs_fixed_i128_is_neg(a) == (a64 < 0));
        uint64_t m = (r >> 8) & 0xffffffffffffull; /* < 2^48: |a * m| < 2^111 */
        assert_true(from_pair(cs_fixed_i128_mul_u64(a, m)) == (i128)a64 * (i128)m);
        cs_i128_t big = cs_fixed_i128_mul_u64(cs_fixed_i128_from64(a64 < 0 ? -(a64 / 2) : a64), m);
        unsigned s = 1u + (unsigned)(r % 127u);
        assert_true((u128)from_pair(cs_fixed_u128_shr(big, s)) == ((u128)from_pair(big) >> s));
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_binom),       cmocka_unit_test(test_div_round),
        cmocka_unit_test(test_bitlen64),    cmocka_unit_test(test_vec_access),
        cmocka_unit_test(test_i128),
        cmocka_unit_test(test_add_sub),     cmocka_unit_test(test_narrow),
        cmocka_unit_test(test_round_shift), cmocka_unit_test(test_mul_shift),
        cmocka_unit_test(test_div_shift),   cmocka_unit_test(test_isqrt64),
        cmocka_unit_test(test_vec_len),     cmocka_unit_test(test_mul_u64_cmp),
        cmocka_unit_test(test_muldiv64),    cmocka_unit_test(test_mul64_q30),
        cmocka_unit_test(test_div_u128),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
