/* cs_predict: predicted-step tracer (see cs_predict.h; derivation and error bound in
 * docs/fixed-point.md, "Predicted-step tracer"). */
#include "cs_predict.h"

#include <stddef.h>

/* The test's threshold T is below 2^THR_BITS = 2^14 units, at least 2^13 - 2 when it sets the
 * shift (what the smallest tolerance, 4 LSB, has at s = 0): the shift is then the threshold's on
 * most chords, not the chord's length, and changes rarely (docs/fixed-point.md). */
#define F               CS_PREDICT_FRAC
#define UNIT_BITS       26 /* sub-curve vectors scaled below 2^26 units: cross products < 2^53 */
#define THR_BITS        14 /* threshold below 2^14 units: (3072 T)^2 < 2^64 */
#define CONIC_UNIT_BITS 24 /* conic vectors below 2^24 units: cross * 2^9 < 2^58 */
/* The room a test leaves, (bound allowed) / (bound found), is carried as its base-2 logarithm
 * in Q8 (ROOM_ONE = 1.0 in the log, i.e. a factor 2): products and square roots of rooms are
 * then sums and halvings, and no division is needed anywhere in the predictor. */
#define ROOM_ONE  256
#define ROOM_CAP  (4 * ROOM_ONE)   /* room 16: at most 4x growth of the step per test */
#define ROOM_FAIL (-2 * ROOM_ONE)  /* room 1/4: what a failing hull test or T <= 0 reports */
#define ROOM_MIN  (-30 * ROOM_ONE) /* room 2^-30: the step shrinks at most 2^15 times */
#define ROOM_HULL 0                /* room 1: a passing hull test (says nothing of the trend) */
/* Accept a passing step whose deviation bound is within 1/1.35 of the threshold (log2(1.347) =
 * 0.430, 110/256): the step is then within about 14 % of the largest that passes. Against 1.15
 * (52/256): 1.0 % more chords at 0.1 mm (bench_peers' random set), 10 % fewer tests a chord
 * there, 9 % less host time a curve (docs/fixed-point.md, Predictor). */
#define ROOM_ACCEPT 110

/* The small helpers of the hot path (mul_t, dot, uabs64): inline on cores with a 32x32 -> 64
 * multiply instruction (about 8 instructions a call saved on the M3, 32 calls a chord); one
 * out-of-line copy where each would be libgcc calls or a 64-bit sequence (M0+, AVR): there the
 * flash matters more (issue 18: the M0+ curve core <= 3 KB). */
#if defined(__GNUC__) &&                                                                           \
    (defined(__SIZEOF_INT128__) || (defined(__ARM_ARCH_ISA_THUMB) && __ARM_ARCH_ISA_THUMB >= 2))
#define HOT_INLINE __attribute__((always_inline)) inline
#elif defined(__GNUC__)
#define HOT_INLINE __attribute__((noinline))
#else
#define HOT_INLINE
#endif

/* Speed builds (the host, -O2): the step search specialised for each flatness test (the test
 * inlined into it, no call through a pointer) and the test's helpers inline; size builds (-Os:
 * every firmware image) keep one out-of-line copy of each. The same source either way, the same
 * vertices (tests/unit/test_predict_same.c builds the size build's code with CS_PREDICT_SPEED 0
 * and compares). */
#ifndef CS_PREDICT_SPEED
#if defined(__GNUC__) && !defined(__OPTIMIZE_SIZE__)
#define CS_PREDICT_SPEED 1
#else
#define CS_PREDICT_SPEED 0
#endif
#endif
#if CS_PREDICT_SPEED
#define SPEED_BUILD  1
#define SPEED_INLINE __attribute__((always_inline)) inline
#define SPEED_UNROLL _Pragma("GCC unroll 8") /* the fixed-count loops of the test unrolled */
#else
#define SPEED_BUILD 0
#define SPEED_INLINE
#define SPEED_UNROLL
#endif
/* 64-bit hosts (HOST_WIDE): mul_t by one 128-bit product and, in speed builds, log2_q8 by a
 * table and the test's shift guessed from the last test (cs_predict.h, guess), so that the
 * test's products do not wait for the shift of its own components (below). The same values as
 * the portable code, which every firmware image runs; CS_PREDICT_PORTABLE 1 builds the portable
 * code on a 64-bit host too (tests/unit/test_predict_portable.c runs test_predict on it). */
#ifndef CS_PREDICT_PORTABLE
#define CS_PREDICT_PORTABLE 0
#endif
#if defined(__SIZEOF_INT128__) && !CS_PREDICT_PORTABLE
#define HOST_WIDE 1
#else
#define HOST_WIDE 0
#endif
#if SPEED_BUILD && HOST_WIDE
#define HOST_GUESS 1
#else
#define HOST_GUESS 0
#endif

static HOT_INLINE uint64_t uabs64(int64_t v)
{
    return v < 0 ? (uint64_t)0 - (uint64_t)v : (uint64_t)v;
}

/* Piecewise-linear majorant of m(a, b) = max_{t in [0,1]} |3t(1-t)((1-t) a + t b)|, in 1/1024,
 * for p = max(|a|, |b|), q = min(|a|, |b|): m is convex and positively homogeneous in (a, b)
 * (a maximum of linear functions), so on each segment between the sampled ratios
 * q/p = 0, 1/2, 1 (same and opposite signs) it lies below the chord through the samples
 * m(1,0) = 4/9, m(1,+-1/2) = 1/sqrt(3), 0.35210, m(1,1) = 3/4, m(1,-1) = sqrt(3)/6, each rounded
 * up to 1/1024. Worst overestimate 1.3 %. */
#define MAJ_SCALE     1024
#define MAX_U64(a, b) ((a) > (b) ? (a) : (b))
static const int16_t maj_coef[4][2] = {/* p, q coefficients: q/p <= 1/2 then > 1/2, same sign */
                                       {456, 272},
                                       {456, -190},
                                       {416, 352},
                                       {426, -130}};
static SPEED_INLINE uint64_t majorant(int64_t c1, int64_t c2)
{
    uint64_t p = uabs64(c1), q = uabs64(c2);
    if (p < q) { /* p = max, q = min */
        uint64_t x = p;
        p = q;
        q = x;
    }
    /* Signs compared on the top bits; a zero c1 or c2 counts as either sign (q = 0 then, and
     * both rows of the first segment give 456 p). */
    bool same = (((uint64_t)c1 ^ (uint64_t)c2) >> 63) == 0;
#if SPEED_BUILD
    /* The interpolant of a convex function is convex: each sign's bound is the larger of its two
     * rows (they meet at q = p/2), the same value as the row chosen below, without a load whose
     * address is data (host cores: about 3 % of the wall clock at 0.1 mm). */
    if (same)
        return MAX_U64(p * 456 + q * 272, p * 416 + q * 352);
    return MAX_U64(p * 456 - q * 190, p * 426 - q * 130);
#endif
    const int16_t *cf = maj_coef[(2 * q <= p ? 0 : 2) + (same ? 0 : 1)];
    /* modulo 2^64 with the negative coefficient: the true value is >= 0 (q <= p) and < 2^63 */
    return p * (uint64_t)cf[0] + q * (uint64_t)(int64_t)cf[1];
}

/* a b for |a|, |b| < 2^31: one 32x32 -> 64 multiply (SMULL on a Cortex-M3, one call of the
 * 32x32 product on the M0+) where int64 operands would take a 64x64 product. */
static int64_t mul32(int32_t a, int32_t b)
{
    return (int64_t)a * b;
}

/* a . b of two planar vectors with components below 2^28 in magnitude (< 2^57): every product
 * of the flatness test is one of these (a cross product is a dot with the normal (-y, x)), so
 * the M0+ carries one copy of the two 32x32 -> 64 calls; inline where they are instructions. */
static HOT_INLINE int64_t dot(const int32_t a[2], const int32_t b[2])
{
    return mul32(a[0], b[0]) + mul32(a[1], b[1]);
}

/* Smallest k with v >> k < 2^bits. */
static SPEED_INLINE unsigned shift_below(uint64_t v, unsigned bits)
{
    unsigned n = cs_fixed_bitlen64(v);
    return n > bits ? n - bits : 0;
}

#define CONIC_W_MIN (CS_WEIGHT_ONE / 16) /* keeps the division by the weight's errors small */

static bool conic_ok(const cs_bezier_t *c)
{
    if (c->degree != 2)
        return false;
    for (unsigned i = 0; i <= 2; i++)
        if (c->w[i] < CONIC_W_MIN || c->w[i] > CS_WEIGHT_ONE)
            return false;
    return (int64_t)c->w[1] * c->w[1] <= (int64_t)c->w[0] * c->w[2];
}

/* Degree 1..3 and every control point at the first one's z (what both kinds share). */
static bool planar_ok(const cs_bezier_t *c)
{
    if (c->degree < 1 || c->degree > 3)
        return false;
    for (unsigned i = 1; i <= c->degree; i++)
        if (c->p[i].z != c->p[0].z)
            return false;
    return true;
}

bool cs_predict_accepts(const cs_bezier_t *c)
{
    return planar_ok(c) && (!c->rational || conic_ok(c));
}

/* cs_fixed_vec_ok: every coordinate within CS_POS_LIMIT. Speed builds inline, by one unsigned
 * compare each (|v| <= L as v + L <= 2 L; L = 2^28: no overflow) and no call. */
static SPEED_INLINE bool point_ok(const cs_vec3_t *v)
{
#if SPEED_BUILD
    uint32_t lim = (uint32_t)CS_POS_LIMIT;
    return ((uint32_t)v->x + lim <= 2 * lim) & ((uint32_t)v->y + lim <= 2 * lim) &
           ((uint32_t)v->z + lim <= 2 * lim);
#else
    return cs_fixed_vec_ok(v);
#endif
}

/* What both begins share: the checks (tolerance, then the curve: ok is the caller's verdict on
 * it, so that the polynomial begin links no conic check, then its range) and the tracing state. */
static SPEED_INLINE cs_err_t begin_common(cs_predict_t *p, const cs_bezier_t *c, cs_pos_t tol,
                                          bool ok)
{
    p->done = true;
    if (tol < CS_PREDICT_TOL_MIN || tol > CS_PREDICT_TOL_MAX)
        return CS_ERR_TOLERANCE;
    if (!ok)
        return CS_ERR_UNSUPPORTED;
    for (unsigned i = 0; i <= c->degree; i++)
        if (!point_ok(&c->p[i]))
            return CS_ERR_RANGE;
    p->t = 0;
    p->h_next = CS_PARAM_ONE; /* first try the whole curve as one chord */
    p->h_ideal = 0;
    p->thr = tol - CS_PREDICT_SLACK_LSB;
    /* the least shift of thr 2^F below 2^THR_BITS, from thr alone (no 64-bit shift on the M0+) */
    p->thr_shift = (uint8_t)shift_below((uint32_t)p->thr, THR_BITS - F);
    p->z = c->p[0].z;
    p->end = c->p[c->degree];
    return CS_OK;
}

static void eval_poly(cs_predict_t *p, cs_vec3_t *pt);
static cs_param_t first_step_w(const cs_predict_t *p, int32_t w[6]);
#if !SPEED_BUILD
static cs_param_t first_step(const cs_predict_t *p);
#endif
static cs_err_t next_poly(cs_predict_t *p, cs_vec3_t *pt);
static cs_err_t next_conic(cs_predict_t *p, cs_vec3_t *pt);
#if HOST_GUESS
static void guess_set(cs_predict_t *q, unsigned s);
#endif

#if SPEED_BUILD
/* Speed builds: the power basis of the loops below in closed form, the same exact integers
 * (a_i = C(n, i) times the i-th forward difference): a1 = n (P1 - P0), a2 = 3 (P2 - 2 P1 + P0)
 * for a cubic, P2 - 2 P1 + P0 for a quadratic, a3 = P3 - 3 P2 + 3 P1 - P0; B'(0) = a1 and
 * B''(0) / 2 = a2 written straight into p->d (eval_poly at t = 0 multiplies by 0: the same
 * values), and first_step's w (a1, a2 in units of 4 LSB, floored: a >> 2, GCC shifts a negative
 * value arithmetically) in registers, not loaded back from p->a (whose two 8-byte stores the
 * vectorised load waited for). */
static SPEED_INLINE void power_basis(cs_predict_t *p, const cs_bezier_t *c, int32_t w[4])
{
    unsigned n = c->degree;
    SPEED_UNROLL
    for (unsigned k = 0; k < 2; k++) {
        int64_t x0 = cs_fixed_vec_get(&c->p[0], k), x1 = cs_fixed_vec_get(&c->p[1], k);
        int64_t a1 = x1 - x0, a2 = 0, a3 = 0;
        if (n >= 2) {
            int64_t x2 = cs_fixed_vec_get(&c->p[2], k);
            a2 = x2 - 2 * x1 + x0;
            if (n == 3) {
                a3 = cs_fixed_vec_get(&c->p[3], k) - 3 * x2 + 3 * x1 - x0;
                a2 *= 3;
            }
        }
        a1 *= n;
        const int64_t one = (int64_t)1 << F;
        p->a[0][k] = x0 * one;
        p->a[1][k] = p->d[0][k] = a1 * one;
        p->a[2][k] = p->d[1][k] = a2 * one;
        p->a[3][k] = a3 * one;
        w[k] = (int32_t)(a1 >> 2);
        w[2 + k] = (int32_t)(a2 >> 2);
    }
}

/* Speed builds: a curve that is one chord for certain, known before its first test. When the
 * first step is the whole curve (first_step gives 1), that test is of the sub-curve [0, 1],
 * whose vectors V_i = 3 (Q_i - Q0) (sub_curve at h = 1, every product exact) are, without the
 * 2^F, v0 = a1, v1 = 2 a1 + a2, v2 = 3 (a1 + a2 + a3) (|v| < 2^31: exact products). If V0 and
 * V1 are lambda V2 with 0 <= lambda <= 1 (the control points on one line, the inner ones
 * projecting onto the chord) and the test's T > 0, the test passes (docs/fixed-point.md,
 * "One-chord curves"): the curve is the one chord to P_n, traced without that test. Out of line
 * (the a_i from p->a, exact multiples of 2^F: an exact arithmetic shift, GCC's for a negative
 * value): the other curves' begin keeps its registers. */
static __attribute__((noinline)) bool straight(const cs_predict_t *p)
{
    int64_t v[3][2];
    uint64_t m = 0;
    SPEED_UNROLL
    for (unsigned k = 0; k < 2; k++) {
        int64_t a1 = p->a[1][k] >> F, a2 = p->a[2][k] >> F, a3 = p->a[3][k] >> F;
        v[0][k] = a1;
        v[1][k] = 2 * a1 + a2;
        v[2][k] = 3 * (a1 + a2 + a3);
        m |= uabs64(v[0][k]) | uabs64(v[1][k]) | uabs64(v[2][k]);
    }
    unsigned s = shift_below(m << F, UNIT_BITS); /* the test's shift and T (test_step) */
    if (s < p->thr_shift)
        s = p->thr_shift;
    bool ok = (((int64_t)p->thr << F) >> s) - 2 > 0;
    int64_t dd = v[2][0] * v[2][0] + v[2][1] * v[2][1];
    SPEED_UNROLL
    for (unsigned i = 0; i < 2; i++) {
        int64_t cr = v[2][0] * v[i][1] - v[2][1] * v[i][0];
        int64_t dt = v[i][0] * v[2][0] + v[i][1] * v[2][1];
        int64_t vv = v[i][0] * v[i][0] + v[i][1] * v[i][1]; /* V2 = 0: V_i = 0 */
        ok &= cr == 0 && dt >= 0 && dt <= dd && vv <= dd;
    }
    return ok;
}

/* The vertex after a curve that straight() found one chord: P_n, as step_to leaves it. */
static cs_err_t next_last(cs_predict_t *p, cs_vec3_t *pt)
{
    p->t = CS_PARAM_ONE;
    p->done = true;
    *pt = p->end;
    return CS_OK;
}
#endif

cs_err_t cs_predict_begin(cs_predict_t *p, const cs_bezier_t *c, cs_pos_t tol)
{
    cs_err_t e = begin_common(p, c, tol, !c->rational && planar_ok(c));
    if (e != CS_OK)
        return e;
#if !SPEED_BUILD
    unsigned n = c->degree;
    for (unsigned k = 0; k < 2; k++) {
        /* Power basis from the Bernstein points: a_i = C(n, i) (i-th forward difference of the
         * points), exact integers (|a_i| < 2^32 LSB); a_i = 0 above the degree. */
        int64_t q[4];
        for (unsigned i = 0; i < 4; i++)
            q[i] = i > n ? 0 : k == 0 ? c->p[i].x : c->p[i].y;
        for (unsigned j = 1; j <= n; j++)
            for (unsigned i = n; i >= j; i--)
                q[i] -= q[i - 1];
        for (unsigned i = 0; i < 4; i++) {
            /* C(n, i) is n for 0 < i < n when n <= 3, else 1: C(n, i) q_i by additions (no
             * 64-bit multiply call on the M0+) */
            int64_t a = 0;
            for (unsigned r = i > 0 && i < n ? n : 1; r > 0; r--)
                a += q[i];
            p->a[i][k] = a * ((int64_t)1 << F);
        }
    }
    cs_vec3_t p0;
    eval_poly(p, &p0); /* B'(0), B''(0) / 2 (p0 = P_0 is not needed: one routine, no branch) */
    p->h_next = first_step(p);
#else
    int32_t w[6];
    power_basis(p, c, w);
    p->h_next = first_step_w(p, w);
#endif
#if SPEED_BUILD
    p->next = p->h_next == CS_PARAM_ONE && straight(p) ? next_last : next_poly;
#else
    p->next = next_poly;
#endif
#if HOST_GUESS
    /* the shift of most tests (THR_BITS) as the first one's guess; a one-chord curve runs none */
    if (p->next == next_poly)
        guess_set(p, p->thr_shift);
#endif
    p->done = false;
    return CS_OK;
}

cs_err_t cs_predict_begin_conic(cs_predict_t *p, const cs_bezier_t *c, cs_pos_t tol)
{
    cs_err_t e = begin_common(p, c, tol, c->rational && cs_predict_accepts(c));
    if (e != CS_OK)
        return e;
    for (unsigned i = 0; i <= 2; i++) {
        int64_t w = c->w[i]; /* exact products: |w x| < 2^58 */
        p->h[i][0] = w * c->p[i].x;
        p->h[i][1] = w * c->p[i].y;
        p->h[i][2] = w;
    }
    p->next = next_conic;
    p->done = false;
    return CS_OK;
}

/* x t / 2^30 rounded half up (floor(x t / 2^30 + 1/2), <= 1/2 unit off), for 0 <= t <= 2^30
 * (every parameter and step of the tracer) and |x| < 2^61 (the 64-bit path below), inline.
 * With x = xh 2^32 + xl (xh the signed top half, -2^30 <= xh < 2^30; xl the unsigned low half)
 * the product is 4 xh t + floor((xl t + 2^29) / 2^30) (the first term is a multiple of 2^30
 * before the shift, so only the second rounds, and it is >= 0): one signed and one unsigned
 * 32x32 -> 64 product (SMULL and UMULL on a Cortex-M3), no absolute value and no branch on the
 * sign, which is data (a mispredicted branch costs a host core some 15 cycles). */
static HOT_INLINE int64_t mul_t(int64_t x, cs_param_t t)
{
#if HOST_WIDE
    /* 64-bit hosts: the same value from one 64x64 -> 128 product, (4 x)(t 2^32) = x t 2^34, as
     * floor((x t 2^34 + 2^63) / 2^64), the top half of a 128-bit sum (4 x fits: every caller's
     * |x| is below 2^60; t 2^32 <= 2^62, shared by a test's 12 products). Five instructions a
     * product against seven (about 6 % of a chord at 0.001 mm); written as that sum, not as the
     * top half plus the low half's top bit, GCC 12 keeps the nested products in registers. */
    __int128 pr = (__int128)(x * 4) * ((int64_t)t << 32);
    return (int64_t)((pr + ((__int128)1 << 63)) >> 64);
#endif
    uint32_t ut = (uint32_t)t;
    uint32_t hi = (uint32_t)((uint64_t)x >> 32); /* the two's complement top half, as int32: */
    int32_t xh = hi <= INT32_MAX ? (int32_t)hi : -(int32_t)(~hi) - 1; /* (a no-op, defined) */
    uint64_t lo = (uint64_t)(uint32_t)x * ut;
    return (int64_t)xh * ut * 4 + (int64_t)((lo + ((uint64_t)1 << 29)) >> 30);
}

/* v / 2^s rounded half up, for 0 <= s < 32 and a result that fits int32: the result's bits are
 * bits s..s+31 of v + floor(2^(s-1)) in two's complement (a logical and an arithmetic shift
 * differ only in bits 64 - s and up, above those), so it is taken from the two 32-bit halves by
 * 32-bit shifts, not a variable 64-bit shift (about 17 instructions on a Cortex-M3), and no
 * negative value is shifted (implementation-defined in C99). hi << (32 - s) is written
 * (hi << 1) << (31 - s), 0 for s = 0 with no shift by 32 (undefined): no branch for s = 0. */
static SPEED_INLINE int32_t rsh_round32(int64_t v, unsigned s)
{
    uint64_t u = (uint64_t)v + ((1u << s) >> 1); /* 32-bit shifts: s < 32 */
#if defined(__SIZEOF_INT128__)                   /* a 64-bit core: one shift */
    uint32_t r = (uint32_t)(u >> s);
#else
    uint32_t lo = (uint32_t)u, hi = (uint32_t)(u >> 32);
    uint32_t r = (lo >> s) | ((hi << 1) << (31 - s));
#endif
    return r <= INT32_MAX ? (int32_t)r : -(int32_t)(~r) - 1;
}

/* At the vertex t: B(t) rounded to the LSB into *pt, and B'(t), B''(t) / 2
 * for the chords from t into p->d (per axis, LSB * 2^F). One Horner scheme shares a3 t:
 * B''/2 = a2 + 3 (a3 t), B' = a1 + (2 a2 + 3 (a3 t)) t, B = a0 + (a1 + (a2 + a3 t) t) t, each
 * product rounded once (<= 1/2 unit): <= 3/2 units off in B''/2, 2 in B', 3/2 in B before its
 * rounding to the LSB (docs/fixed-point.md). */
static SPEED_INLINE void eval_poly(cs_predict_t *p, cs_vec3_t *pt)
{
    cs_param_t t = p->t;
    SPEED_UNROLL
    for (unsigned k = 0; k < 2; k++) {
        int64_t a3t = mul_t(p->a[3][k], t), a2 = p->a[2][k];
        p->d[1][k] = a2 + 3 * a3t;
        p->d[0][k] = p->a[1][k] + mul_t(2 * a2 + 3 * a3t, t);
        int64_t acc = p->a[1][k] + mul_t(a2 + a3t, t);
        /* |B(t)| <= CS_POS_LIMIT + 1: in the convex hull of valid points, plus rounding. */
        cs_fixed_vec_set(pt, k, rsh_round32(p->a[0][k] + mul_t(acc, t), F));
    }
    pt->z = p->z;
}

/* The test's shift s is below 32: its components are below 8 CS_POS_LIMIT 2^F (3 (Q_i - Q0),
 * Q_i in the hull of points inside CS_POS_LIMIT), so shift_below(., UNIT_BITS) <= 17, and the
 * threshold's own shift is at most bitlen(CS_PREDICT_TOL_MAX 2^F) - THR_BITS = 26. */
CS_STATIC_ASSERT(((int64_t)8 * CS_POS_LIMIT << F) < ((int64_t)1 << (UNIT_BITS + 31)),
                 predict_unit_shift_below_32);
CS_STATIC_ASSERT(((int64_t)CS_PREDICT_TOL_MAX << F) < ((int64_t)1 << (THR_BITS + 31)),
                 predict_thr_shift_below_32);

/* The sub-curve [t, t + h] relative to B(t), as 3 (Q1 - Q0), 3 (Q2 - Q0), 3 (Q3 - Q0) in
 * LSB * 2^F: from the Taylor coefficients c1 = B'(t) h, c2 = B''(t) h^2 / 2, c3 = a3 h^3,
 * Q1 - Q0 = c1 / 3, Q2 - Q0 = (2 c1 + c2) / 3, Q3 - Q0 = c1 + c2 + c3 (the blossom of the
 * piece, computed directly; each product rounded once, docs/fixed-point.md). */
static SPEED_INLINE void sub_curve(const cs_predict_t *p, const int64_t d[2][2], cs_param_t h,
                                   int64_t v[3][2])
{
    SPEED_UNROLL
    for (unsigned k = 0; k < 2; k++) {
        /* Nested products (not h^2, h^3 rounded to Q30 first, whose rounding would be scaled
         * by |d2| up to 2^44 units): <= 1/2 unit per product. */
        int64_t c1 = mul_t(d[0][k], h);
        int64_t c2 = mul_t(mul_t(d[1][k], h), h);
        int64_t c3 = mul_t(mul_t(mul_t(p->a[3][k], h), h), h);
        v[0][k] = c1;
        v[1][k] = 2 * c1 + c2;
        int64_t q3 = c1 + c2 + c3;
        v[2][k] = q3 + q3 + q3; /* 3 (Q3 - Q0) by additions: no 64-bit multiply call on the M0+ */
    }
}

#if SPEED_BUILD && HOST_WIDE
/* 64-bit speed builds: the fraction below, l >> 7, for each of the 2^15 mantissas x, the same
 * formula evaluated by the compiler (32 KB of table: one load, within L1 on the host, instead
 * of two dependent multiplies on the path from the deviation found to the next step; 5 % of
 * a chord at 0.01 mm). */
#define LG_X(x)   (uint8_t)(((x) + (((((x) * (32768u - (x))) >> 15) * 89u) >> 8)) >> 7)
#define LG_4(j)   LG_X(j), LG_X((j) + 1), LG_X((j) + 2), LG_X((j) + 3)
#define LG_16(j)  LG_4(j), LG_4((j) + 4), LG_4((j) + 8), LG_4((j) + 12)
#define LG_64(j)  LG_16(j), LG_16((j) + 16), LG_16((j) + 32), LG_16((j) + 48)
#define LG_256(j) LG_64(j), LG_64((j) + 64), LG_64((j) + 128), LG_64((j) + 192)
#define LG_1K(j)  LG_256(j), LG_256((j) + 256), LG_256((j) + 512), LG_256((j) + 768)
#define LG_4K(j)  LG_1K(j), LG_1K((j) + 1024), LG_1K((j) + 2048), LG_1K((j) + 3072)
#define LG_16K(j) LG_4K(j), LG_4K((j) + 4096), LG_4K((j) + 8192), LG_4K((j) + 12288)
static const uint8_t lg_frac[32768] = {LG_16K(0u), LG_16K(16384u)};
#endif

/* log2(v) in Q8 for v > 0: the bit length gives the integer part, the next 15 bits x
 * (v = 2^e (1 + x), 0 <= x < 1) the fraction by log2(1 + x) ~ x + c x (1 - x), c = 89/256;
 * within [-0.0115, +0.0079] of the exact log2 v (checked on all 2^15 mantissas, the truncation
 * to 16 bits and to Q8 included). The predictor's only logarithm. */
static SPEED_INLINE int32_t log2_q8(uint64_t v)
{
#if SPEED_BUILD && HOST_WIDE
    /* 64-bit hosts: v normalised by one shift (its leading 1 to bit 63) gives the same 16 bits,
     * zeros below a short v's last bit, as the two shifts and the select below */
    unsigned c = (unsigned)__builtin_clzll(v), n = 64 - c;
    uint32_t m = (uint32_t)((v << c) >> 48);
#else
    unsigned n = cs_fixed_bitlen64(v); /* m below: the top 16 bits, in [2^15, 2^16) */
    uint32_t m = n > 16 ? (uint32_t)(v >> (n - 16)) : (uint32_t)v << (16 - n);
#endif
    uint32_t x = m - (1u << 15); /* Q15 */
#if SPEED_BUILD && HOST_WIDE
    return (int32_t)((n - 1) * ROOM_ONE + lg_frac[x]);
#endif
    uint32_t l = x + ((((x * ((1u << 15) - x)) >> 15) * 89u) >> 8);
    return (int32_t)((n - 1) * ROOM_ONE + (l >> 7));
}

/* log2 of the room k sqrt(dd) / found (Q8), clamped to [ROOM_MIN, ROOM_CAP]; dd, k > 0. Each
 * log2_q8 is within [-0.0115, +0.0079] of the exact logarithm of its integer (checked on all
 * 2^15 mantissas), the halving truncates by < 1/512: the result is within [-6.9, +6.0] / 256
 * of the exact log2 of the room. */
static SPEED_INLINE int32_t room_log(uint64_t k, uint64_t dd, uint64_t found)
{
    if (found == 0)
        return ROOM_CAP;
    int32_t r = log2_q8(k) + log2_q8(dd) / 2 - log2_q8(found);
    return r > ROOM_CAP ? ROOM_CAP : r < ROOM_MIN ? ROOM_MIN : r;
}

/* found <= k sqrt(dd), i.e. found^2 <= k^2 dd (k < 2^32), with *room = its log: decided on the
 * log when it is clear (|room| >= ROOM_SURE = 8/256 > the log's error, so its sign is the exact
 * comparison's), otherwise exactly in 128 bits. */
#define ROOM_SURE 8
static SPEED_INLINE bool room_ok(uint64_t k, uint64_t dd, uint64_t found, int32_t *room)
{
    int32_t r = room_log(k, dd, found);
    *room = r;
    if (r >= ROOM_SURE || r <= -ROOM_SURE)
        return r > 0;
    return cs_fixed_cmp_prod_u64(found, found, k * k, dd) <= 0;
}

/* dist(V, segment 0-D) <= r, decided exactly as cs_subdiv_dist_ok decides it, planar and on the
 * test's 32-bit components (below 2^27: |V - D|^2 below 2^57), with vd = V . D, cr = D x V and
 * dd = |D|^2 already computed; r2 = r^2. */
static bool seg_dist_ok(const int32_t v[2], const int32_t d[2], int64_t vd, int64_t cr, int64_t dd,
                        uint64_t r2)
{
    if (dd == 0 || vd <= 0 || vd >= dd) { /* nearest point is an end: 0 (also D = 0) or D */
        int32_t e[2];
        for (unsigned k = 0; k < 2; k++)
            e[k] = vd <= 0 ? v[k] : v[k] - d[k];
        return (uint64_t)dot(e, e) <= r2;
    }
    uint64_t c = uabs64(cr); /* |D x V| <= r |D| */
    return cs_fixed_cmp_prod_u64(c, c, r2, (uint64_t)dd) <= 0;
}

/* The products of the test: dd = D . D, V1 . D, V2 . D, D x V1, D x V2 (D = V3; w[3] is D's
 * normal (-D.y, D.x), so D x V = w[3] . V), as pairs of rows of w: one loop, one product. */
enum { P_DD, P_DOT1, P_DOT2, P_CR1, P_CR2, P_N };
static const uint8_t prod_rows[P_N][2] = {{2, 2}, {0, 2}, {1, 2}, {3, 0}, {3, 1}};

/* Convex-hull test for short chords and pieces whose inner points project outside the chord:
 * max deviation <= 3/4 max dist(Q_i, chord) (interior Bernstein weights sum to <= 3/4), so
 * dist(V_i, D) <= 4 T in the 3x-scaled units; r2 = (4 T)^2. */
static bool hull_flat(const int32_t w[4][2], const int64_t pr[P_N], uint64_t r2)
{
    for (unsigned i = 0; i < 2; i++) /* V1, then V2 */
        if (!seg_dist_ok(w[i], w[2], pr[P_DOT1 + i], pr[P_CR1 + i], pr[P_DD], r2))
            return false;
    return true;
}

/* One flatness test of [t, t + h]: true when the sub-curve is proven within thr of its chord;
 * *room = log2 of how much larger the deviation bound could be (Q8), for the step predictor. */
static SPEED_INLINE bool test_step(const cs_predict_t *p, void *ctx, cs_param_t h, int32_t *room)
{
    const int64_t(*d)[2] = ctx; /* B'(t), B''(t) / 2 */
    int64_t v[3][2];
    sub_curve(p, d, h, v);
    uint64_t m = 0;
    SPEED_UNROLL
    for (unsigned i = 0; i < 3; i++)
        SPEED_UNROLL
    for (unsigned k = 0; k < 2; k++)
        m |= uabs64(v[i][k]);
    unsigned s = shift_below(m, UNIT_BITS); /* components >> s < 2^UNIT_BITS */
    if (s < p->thr_shift)
        s = p->thr_shift; /* thr 2^F >> s < 2^THR_BITS */
    /* thr 2^F >> s in 32 bits (thr > 0; no 64-bit shift), less 2 units for the rounding of the
     * shift below */
    int32_t T = (s >= F ? p->thr >> (s - F) : p->thr << (F - s)) - 2;
    /* Rounded (half up: <= 1/2 unit), inline: this is the hot path. After the shift every
     * component is below 2^UNIT_BITS + 1 < 2^31, so each cross and dot product below is one
     * 32x32 -> 64 multiply (SMULL on a Cortex-M3), a sum of two below 2^53. */
    int32_t w[4][2];
    SPEED_UNROLL
    for (unsigned i = 0; i < 3; i++)
        SPEED_UNROLL
    for (unsigned k = 0; k < 2; k++)
        w[i][k] = rsh_round32(v[i][k], s);
    w[3][0] = -w[2][1];
    w[3][1] = w[2][0];
    int64_t pr[P_N];
    SPEED_UNROLL
    for (unsigned i = 0; i < P_N; i++)
        pr[i] = dot(w[prod_rows[i][0]], w[prod_rows[i][1]]);
    int64_t tt = mul32(T, T), dd = pr[P_DD];
    /* dd >= 0: as unsigned, a negative V . D is above dd too (one compare for 0 <= dot <= dd) */
    if (T <= 0 || dd < 64 * tt || (uint64_t)pr[P_DOT1] > (uint64_t)dd ||
        (uint64_t)pr[P_DOT2] > (uint64_t)dd) { /* T <= 0 fails here: no room for the rounding */
        bool ok = T > 0 && hull_flat((const int32_t(*)[2])w, pr, (uint64_t)(16 * tt));
        *room = ok ? ROOM_HULL : ROOM_FAIL;
        return ok;
    }
    uint64_t found = majorant(pr[P_CR1], pr[P_CR2]);
    /* Deviation bound m(c1, c2) / (1024 * 3 |D|) <= T, i.e. found <= 3072 T |D|. */
    uint64_t k = (uint32_t)(3 * MAJ_SCALE) * (uint32_t)T; /* T < 2^14: < 2^26, a 32-bit product */
    return room_ok(k, (uint64_t)dd, found, room);
}

#if HOST_GUESS
/* --- the test on 64-bit hosts (HOST_GUESS) -------------------------------------------------
 * The same verdict and room as test_step, with nothing on the path from the step to the room
 * (which the next step waits for: host cores are latency-bound here) that the products do not
 * need: the shift and what follows from it are the last test's (p->guess), set anew out of
 * line when the test's own shift differs (bench_peers' random set: about one test in 230 at
 * 0.01 mm, one in 70 at 0.001, none at 0.1: THR_BITS); the convex-hull fallback and T <= 0 go to
 * test_step itself, a room clamped or too close to 1 for its log to room_ok (up to 2 % of the
 * tests), each out of line after a branch, which the core predicts instead of waiting for its
 * operands. */
/* The guess: s, k = 3072 T, 64 T^2, log2_q8(k) (T > 0; else k = 0), and the m (host_bits) whose
 * shift is s, LO <= m < LO + SPAN. */
enum { G_S, G_K, G_TT, G_LK, G_LO, G_SPAN, G_N };
CS_STATIC_ASSERT(sizeof(((cs_predict_t *)0)->guess) == G_N * sizeof(int64_t), predict_guess_n);

static __attribute__((noinline, cold)) void guess_set(cs_predict_t *q, unsigned s)
{
    int64_t T = (((int64_t)q->thr << F) >> s) - 2; /* test_step's T for this s */
    /* test_step's shift of m is s exactly for LO <= m < LO + SPAN: m < 2^(UNIT_BITS + s) when
     * s is the threshold's, else the bit length of m is UNIT_BITS + s (s < 32: below 2^58) */
    int64_t lo = s > q->thr_shift ? (int64_t)1 << (UNIT_BITS - 1 + s) : 0;
    q->guess[G_LO] = lo;
    q->guess[G_SPAN] = ((int64_t)1 << (UNIT_BITS + s)) - lo;
    q->guess[G_S] = s;
    q->guess[G_K] = T > 0 ? 3 * MAJ_SCALE * T : 0;
    q->guess[G_TT] = 64 * T * T;
    q->guess[G_LK] = T > 0 ? log2_q8((uint64_t)(3 * MAJ_SCALE * T)) : 0;
}

/* test_step and room_ok out of line, verdict and room packed as 2 room + verdict: no address
 * of the caller's room leaves the inline path (a room whose address is passed out lives in
 * memory). */
static __attribute__((noinline, cold)) int32_t test_slow(cs_predict_t *q, cs_param_t h)
{
    int32_t room;
    bool ok = test_step(q, q->d, h, &room);
    return 2 * room + ok;
}

/* test_step's convex-hull fallback on test_fast's rounded components w (V1, V2, D: below
 * 2^26 + 1, int32) and tt64 = 64 T^2 (T > 0), packed as test_slow's: the sub-curve and its
 * shift are not computed again. */
static __attribute__((noinline, cold)) int32_t hull_slow(const int64_t w[3][2], int64_t tt64)
{
    int32_t v[4][2];
    int64_t pr[P_N];
    for (unsigned i = 0; i < 6; i++)
        v[i / 2][i % 2] = (int32_t)w[i / 2][i % 2];
    v[3][0] = -v[2][1];
    v[3][1] = v[2][0];
    for (unsigned i = 0; i < P_N; i++)
        pr[i] = dot(v[prod_rows[i][0]], v[prod_rows[i][1]]);
    bool ok = hull_flat((const int32_t(*)[2])v, pr, (uint64_t)(tt64 / 4)); /* (4 T)^2 */
    return 2 * (ok ? ROOM_HULL : ROOM_FAIL) + ok;
}

static __attribute__((noinline, cold)) int32_t room_slow(uint64_t k, uint64_t dd, uint64_t found)
{
    int32_t room;
    bool ok = room_ok(k, dd, found, &room);
    return 2 * room + ok;
}

/* Unpacks test_slow's or room_slow's answer: room, ROOM_MIN .. ROOM_CAP, and the verdict. */
static SPEED_INLINE bool unpack(int32_t x, int32_t *room)
{
    *room = (x - (x & 1)) / 2; /* exact: no negative value shifted */
    return (x & 1) != 0;
}

/* The or of the test's |components| (test_step's m), without a branch on their signs. */
static SPEED_INLINE uint64_t host_bits(const int64_t v[3][2])
{
    uint64_t m = 0;
    SPEED_UNROLL
    for (unsigned i = 0; i < 6; i++) {
        uint64_t x = (uint64_t)v[i / 2][i % 2], sg = (uint64_t)(v[i / 2][i % 2] >> 63);
        m |= (x ^ sg) - sg;
    }
    return m;
}

/* The test's shift for m = host_bits, out of line: the guess's is checked on m itself. */
static __attribute__((noinline, cold)) void guess_miss(cs_predict_t *q, uint64_t m)
{
    unsigned s = shift_below(m, UNIT_BITS);
    guess_set(q, s < q->thr_shift ? q->thr_shift : s);
}

/* test_step on the guess (ctx: the state itself, which the guess is set in). Each component
 * rounded by one arithmetic shift of its 64-bit sum with the half (GCC shifts a negative int
 * arithmetically), the value rsh_round32 gives (it fits 32 bits), with no sign extension. */
static SPEED_INLINE bool test_fast(const cs_predict_t *p, void *ctx, cs_param_t h, int32_t *room)
{
    const int64_t *g = p->guess;
    int64_t v[3][2], w[3][2];
    sub_curve(p, p->d, h, v);
    uint64_t m = host_bits(v);
    if (m - (uint64_t)g[G_LO] >= (uint64_t)g[G_SPAN])
        guess_miss(ctx, m);
    if (g[G_K] == 0) /* T <= 0 */
        return unpack(test_slow(ctx, h), room);
    unsigned s = (unsigned)g[G_S]; /* what follows does not wait for m */
    int64_t half = ((int64_t)1 << s) >> 1;
    SPEED_UNROLL
    for (unsigned i = 0; i < 6; i++)
        w[i / 2][i % 2] = (v[i / 2][i % 2] + half) >> s;
    int64_t dd = w[2][0] * w[2][0] + w[2][1] * w[2][1];
    int64_t dot1 = w[0][0] * w[2][0] + w[0][1] * w[2][1];
    int64_t dot2 = w[1][0] * w[2][0] + w[1][1] * w[2][1];
    if (dd < g[G_TT] || (uint64_t)dot1 > (uint64_t)dd || (uint64_t)dot2 > (uint64_t)dd)
        return unpack(hull_slow(w, g[G_TT]), room);
    uint64_t found =
        majorant(w[2][0] * w[0][1] - w[2][1] * w[0][0], w[2][0] * w[1][1] - w[2][1] * w[1][0]);
    /* room_log without its clamps (a clamped room is room_slow's: the log of a positive dd is
     * >= 0, its halving a shift) and room_ok's decision: on the log when it is clear, else
     * exactly, found^2 <= k^2 dd in 128 bits (k < 2^32: k^2 < 2^64, found^2 < 2^128), inline:
     * 7.5 % of the tests at 0.1 mm on bench_peers' random set, 18 % on the teapot, land within
     * 8/256 of 1 (a well predicted step's room is 1/64 above it). As || of the two, not a
     * branch-free | and &, which puts the 128-bit products on the path to the verdict. */
    if (found == 0)
        return unpack(room_slow((uint64_t)g[G_K], (uint64_t)dd, found), room);
    uint64_t k = (uint64_t)g[G_K];
    bool exact = (unsigned __int128)found * found <= (unsigned __int128)(k * k) * (uint64_t)dd;
    int32_t r = (int32_t)g[G_LK] + (int32_t)((uint32_t)log2_q8((uint64_t)dd) >> 1);
    r -= log2_q8(found);
    if (r > ROOM_CAP || r < ROOM_MIN)
        return unpack(room_slow(k, (uint64_t)dd, found), room);
    *room = r;
    return r >= ROOM_SURE || (r > -ROOM_SURE && exact);
}
#endif

/* Step predicted from a tested one: deviation ~ h^2, so h sqrt(room), 1.6 % short. sqrt(room)
 * = 2^(r/2) (r = log2 room in Q8, so r itself is log2 sqrt(room) in Q9): 2^i (1 + f) with
 * 2^f ~ 1 + f - c f (1 - f), c = 88/256 (within 0.3 %). At most cap (0 <= cap <= 2^30). */
#define EXP2_Q15(f) ((1u << 15) + (f) - (((((f) * ((1u << 15) - (f))) >> 15) * 88u) >> 8))
#if SPEED_BUILD
/* Speed builds: 2^f for the 512 fractions f = j / 512, the same formula evaluated by the
 * compiler (1 KB of table; a load instead of two dependent multiplies on the path from one test
 * to the next). */
#define EXP2_J(j)  (uint16_t) EXP2_Q15((uint32_t)(j) << 6)
#define EXP2_4(j)  EXP2_J(j), EXP2_J((j) + 1), EXP2_J((j) + 2), EXP2_J((j) + 3)
#define EXP2_16(j) EXP2_4(j), EXP2_4((j) + 4), EXP2_4((j) + 8), EXP2_4((j) + 12)
#define EXP2_64(j) EXP2_16(j), EXP2_16((j) + 16), EXP2_16((j) + 32), EXP2_16((j) + 48)
static const uint16_t exp2_q15[512] = {EXP2_64(0),   EXP2_64(64),  EXP2_64(128), EXP2_64(192),
                                       EXP2_64(256), EXP2_64(320), EXP2_64(384), EXP2_64(448)};
#endif
static SPEED_INLINE cs_param_t predict(cs_param_t h, int32_t room, cs_param_t cap)
{
    int32_t e = room - ROOM_MIN;             /* >= 0: no negative value is shifted */
    int32_t i = (e >> 9) - (-ROOM_MIN >> 9); /* floor(room / 512), -15 .. 2 */
#if SPEED_BUILD
    uint32_t m = exp2_q15[(uint32_t)e & 511u];
#else
    uint32_t f = ((uint32_t)e & 511u) << 6; /* Q15 */
    uint32_t m = EXP2_Q15(f);
#endif
    uint64_t nh = (uint64_t)(uint32_t)h * m; /* h 2^f in Q15, < 2^46 */
    nh >>= 15 - i; /* = (nh 2^i) >> 15 for i >= 0 (no overflow: < 2^48), floors nest for i < 0 */
    nh -= nh / 64;
    return nh > (uint64_t)cap ? cap : (cs_param_t)nh; /* both callers cap it: once, here */
}

/* The first chord's step, from the curvature at t = 0: a piece [0, h] deviates from its chord
 * by about h^2 |B' x B''/2| / (4 |B'|) (the sagitta of its osculating parabola), so the room of
 * h = 1 is thr |w1| / |w1 x w2| with w1, w2 = B'(0), B''(0)/2 = a1, a2 in units of 4 LSB
 * (4 thr |B'| / |B' x B''/2| = 4 thr 4 |w1| / (16 |w1 x w2|)), and predict turns it into the
 * step that would just fill the tolerance (1/64 short). a1, a2 are exact multiples of 2^F below
 * 2^32 LSB (begin), so w1, w2 < 2^30 (products < 2^61), floored: a guess the tests verify as
 * any other step. A straight start (w1 x w2 = 0) tries the whole curve. */
static SPEED_INLINE cs_param_t first_step_w(const cs_predict_t *p, int32_t w[6])
{
    w[4] = -w[1]; /* w1's normal (-y, x): w1 x w2 = w[4..5] . w[2..3] */
    w[5] = w[0];
    int32_t r; /* room_ok for its room (one routine on the M0+: its verdict is not needed) */
    (void)room_ok((uint32_t)p->thr, (uint64_t)dot(w, w), uabs64(dot(w + 4, w + 2)), &r);
    return predict(CS_PARAM_ONE, r, CS_PARAM_ONE);
}

#if !SPEED_BUILD /* speed builds: w from power_basis */
static cs_param_t first_step(const cs_predict_t *p)
{
    const int64_t *a = &p->a[1][0]; /* a1x, a1y, a2x, a2y */
    int32_t w[6];
    for (unsigned i = 0; i < 4; i++) {
        uint32_t u = (uint32_t)((uint64_t)a[i] >> (F + 2)); /* floor(a / 2^(F+2)), two's compl. */
        w[i] = u <= INT32_MAX ? (int32_t)u : -(int32_t)(~u) - 1;
    }
    return first_step_w(p, w);
}
#endif

/* The ideal step a of this chord extrapolated linearly from the last one's, b: 2a - b (the
 * ideal step changes smoothly along the curve), at least a/2; a alone when there is no last
 * one (b = 0). 0 <= a <= 2^30 and 0 < b <= 2^30: 2a - b < 2^31, taken as a + (a - b) (2a alone
 * is 2^31 for a = 2^30: a signed overflow, UBSan's, on a curve's whole step). (Selects and
 * unsigned halvings: 4 bytes less on the M0+ than a branch and signed divisions.) */
static cs_param_t trend(cs_param_t a, cs_param_t b)
{
    cs_param_t n = b == 0 ? a : a + (a - b), half = (cs_param_t)((uint32_t)a >> 1); /* a >= 0 */
    return n < half ? half : n;
}

#if HOST_GUESS
/* predict before its last step (nh - nh / 64) and its cap (< 2^34): for next_step below. */
static SPEED_INLINE uint64_t predict_raw(cs_param_t h, int32_t room)
{
    int32_t e = room - ROOM_MIN, i = (e >> 9) - (-ROOM_MIN >> 9);
    return ((uint64_t)(uint32_t)h * exp2_q15[(uint32_t)e & 511u]) >> (15 - i);
}

/* The next chord's step as step_to computes it below (predict, trend, clamp to 1 .. 2^30), at
 * most rem = 1 - t, out of line: the host's rare case. */
static __attribute__((noinline, cold)) cs_param_t next_step_slow(cs_param_t h, int32_t room,
                                                                 cs_param_t b, cs_param_t rem)
{
    cs_param_t nh = trend(predict(h, room, CS_PARAM_ONE), b);
    nh = nh < 1 ? 1 : nh > CS_PARAM_ONE ? CS_PARAM_ONE : nh;
    return nh < rem ? nh : rem;
}

/* The same value: 2 a - b (a = predict_raw) when no cap, select or clamp of next_step_slow acts
 * (a <= 2^30, b != 0, 2 a - b >= a / 2, 1 <= 2 a - b <= rem), else next_step_slow. The test of
 * that is a branch, predicted, where the five selects were a chain of dependent instructions
 * from the test's room to the next test's step (which waits for it: host cores, 64-bit). */
static SPEED_INLINE cs_param_t next_step(cs_param_t h, int32_t room, cs_param_t b, cs_param_t rem)
{
    uint64_t u = predict_raw(h, room), a = u - u / 64;
    /* 2 a - b as (2 u - b) - 2 (u / 64): one instruction less between u and the step */
    int64_t n = (2 * (int64_t)u - b) - (int64_t)((u >> 5) & ~(uint64_t)1);
    if (a > CS_PARAM_ONE || b == 0 || n < (int64_t)(a >> 1) || n < 1 || n > rem)
        return next_step_slow(h, room, b, rem);
    return (cs_param_t)n;
}
#endif

/* --- conic arcs ------------------------------------------------------------------------- */
/* a + (b - a) u, u in Q30 (|b - a| < 2^60: one rounding of 1/2 unit). */
static int64_t lerp(int64_t a, int64_t b, cs_param_t u)
{
    return a + mul_t(b - a, u);
}

/* Homogeneous blossom b(u, v) of the conic (x, y, w), by two levels of lerps. */
static void blossom(const cs_predict_t *p, cs_param_t u, cs_param_t v, int64_t out[3])
{
    for (unsigned k = 0; k < 3; k++)
        out[k] = lerp(lerp(p->h[0][k], p->h[1][k], u), lerp(p->h[1][k], p->h[2][k], u), v);
}

/* Cartesian x, y of a homogeneous point, in LSB * 2^frac (frac <= 12), truncated: the quotient
 * and the remainder's fraction by two int64 divisions (|x| < 2^59, 2^26 <= w <= 2^30 for
 * weights >= 1/16, so remainder * 2^frac < 2^42), error < 2^-frac LSB. */
static void project(const int64_t hp[3], unsigned frac, int64_t q[2])
{
    for (unsigned k = 0; k < 2; k++) {
        int64_t whole = hp[k] / hp[2], rem = hp[k] % hp[2];
        q[k] = whole * ((int64_t)1 << frac) + rem * ((int64_t)1 << frac) / hp[2];
    }
}

/* What every trial piece of a conic from t shares: the blossom's first level at t (lerps of
 * the homogeneous points), Q0 = b(t, t), its projection and its weight W0. */
typedef struct {
    int64_t l01[3], l12[3], q0[2], w0;
} conic_start_t;

static void conic_start(const cs_predict_t *p, conic_start_t *c0)
{
    int64_t b0[3];
    for (unsigned k = 0; k < 3; k++) {
        c0->l01[k] = lerp(p->h[0][k], p->h[1][k], p->t);
        c0->l12[k] = lerp(p->h[1][k], p->h[2][k], p->t);
        b0[k] = lerp(c0->l01[k], c0->l12[k], p->t); /* = blossom(p, t, t) */
    }
    project(b0, F, c0->q0);
    c0->w0 = b0[2];
}

/* Flatness test of the conic piece [t, t + h] with control points Q0, Q1, Q2 and weights W0,
 * W1, W2: its farthest point from the chord is the shoulder, at omega/(1 + omega) of Q1's
 * distance (omega = W1 / sqrt(W0 W2) <= 1), and by convexity no point is farther from the chord
 * segment than that factor times dist(Q1, segment). Decided exactly on squares, with the factor
 * rounded up to 1/256. */
static bool test_conic(const cs_predict_t *p, void *ctx, cs_param_t h, int32_t *room)
{
    const conic_start_t *c0 = ctx;
    int64_t b1[3], b2[3], q1[2], q2[2], v[2], d[2];
    const int64_t *q0 = c0->q0;
    cs_param_t t1 = p->t + h;
    for (unsigned k = 0; k < 3; k++) /* b(t, t + h): the first level at t is shared */
        b1[k] = lerp(c0->l01[k], c0->l12[k], t1);
    blossom(p, t1, t1, b2);
    project(b1, F, q1);
    project(b2, F, q2);
    uint64_t m = 0;
    for (unsigned k = 0; k < 2; k++) {
        v[k] = q1[k] - q0[k];
        d[k] = q2[k] - q0[k];
        m |= uabs64(v[k]) | uabs64(d[k]);
    }
    unsigned s = shift_below(m, CONIC_UNIT_BITS);
    if (s < p->thr_shift)
        s = p->thr_shift;
    int64_t T = (((int64_t)p->thr << F) >> s) - 2;
    if (T <= 0) {
        *room = ROOM_FAIL;
        return false;
    }
    for (unsigned k = 0; k < 2 && s > 0; k++) {
        v[k] = cs_fixed_round_shift64(v[k], s);
        d[k] = cs_fixed_round_shift64(d[k], s);
    }
    /* phi = W1 / (W1 + sqrt(W0 W2)) rounded up to 1/256 (sqrt rounded down). */
    uint64_t sq = cs_fixed_isqrt64((uint64_t)c0->w0 * (uint64_t)b2[2]);
    uint64_t w1 = (uint64_t)b1[2], phi = ((w1 << 8) + w1 + sq - 1) / (w1 + sq);
    uint64_t lim = (uint64_t)T << 8, lim2 = lim * lim; /* T < 2^20: lim^2 < 2^56 */
    int64_t dd = d[0] * d[0] + d[1] * d[1], dot = v[0] * d[0] + v[1] * d[1];
    if (dot <= 0 || dot >= dd) { /* nearest chord point is an end: distance to it */
        int64_t ex = dot <= 0 ? v[0] : v[0] - d[0], ey = dot <= 0 ? v[1] : v[1] - d[1];
        bool ok = cs_fixed_cmp_prod_u64((uint64_t)(ex * ex + ey * ey), phi * phi, lim2, 1) <= 0;
        *room = ok ? ROOM_HULL : ROOM_FAIL;
        return ok;
    }
    uint64_t found = uabs64(d[0] * v[1] - d[1] * v[0]) * phi; /* < 2^49 * 2^9 */
    return room_ok(lim, (uint64_t)dd, found, room);
}

/* The vertex at p->t: the conic's blossom b(t, t) divided once, rounded to the nearest LSB. */
static void eval_conic(const cs_predict_t *p, cs_vec3_t *pt)
{
    int64_t b[3], q[2];
    blossom(p, p->t, p->t, b);
    for (unsigned k = 0; k < 2; k++)
        q[k] = (2 * b[k] + (b[k] < 0 ? -b[2] : b[2])) / (2 * b[2]);
    pt->x = (cs_pos_t)q[0];
    pt->y = (cs_pos_t)q[1];
    pt->z = p->z;
}

/* One flatness test of the piece [t, t + h]; ctx is what every trial piece from t shares
 * (B'(t) and B''(t)/2, or the conic's start). */
typedef bool (*test_fn)(const cs_predict_t *p, void *ctx, cs_param_t h, int32_t *room);

/* The largest step found passing: predicted, corrected by the room each test leaves, bracketed
 * between the largest passing and the smallest failing step. 0 when none passes. */
static SPEED_INLINE cs_param_t find_step(const cs_predict_t *p, test_fn test, void *ctx,
                                         int32_t *lo_room)
{
    /* 0 <= lo, h <= rem <= 2^30 and hi <= rem + 1: int32 throughout (no 64-bit compares) */
    cs_param_t rem = CS_PARAM_ONE - p->t;
#if HOST_GUESS
    int32_t lo = 0, hi = rem + 1, h = p->h_next; /* <= rem already (step_to, HOST_GUESS) */
#else
    int32_t lo = 0, hi = rem + 1, h = p->h_next < rem ? p->h_next : rem;
#endif
    for (unsigned k = 0; k < CS_PREDICT_MAX_TESTS; k++) {
        int32_t room;
        if (test(p, ctx, h, &room)) {
            lo = h;
            *lo_room = room;
            if (h == rem || room <= ROOM_ACCEPT)
                break;
        } else {
            hi = h;
        }
        int32_t nh = predict(h, room, rem);
        if (nh <= lo || nh >= hi)
            nh = lo + (int32_t)((uint32_t)(hi - lo) >> 1); /* hi > lo: no signed halving */
        if (nh == h || hi - lo <= 1) /* (nh <= lo only when bisected with hi - lo <= 1) */
            break;
        h = nh;
    }
    for (unsigned k = 0; lo == 0 && k < CS_PARAM_FRAC_BITS + 1; k++) {
        h = (int32_t)((uint32_t)hi >> 1); /* the predictor gave up: halve until a step passes */
        if (h == 0)
            break;
        int32_t room;
        if (test(p, ctx, h, &room)) {
            lo = h;
            *lo_room = room;
        }
        hi = h;
    }
    return (cs_param_t)lo;
}

/* Moves to the next vertex by the step find_step gave: CS_OK and *eval when the caller
 * computes the vertex at p->t, CS_OK and *pt = P_n at the end, CS_ERR_DEPTH for no step. */
static SPEED_INLINE cs_err_t step_to(cs_predict_t *p, cs_param_t h, int32_t room, cs_vec3_t *pt,
                                     bool *eval)
{
    *eval = false;
    p->done = true;
    if (h == 0)
        return CS_ERR_DEPTH;
    p->t += h;
    if (p->t == CS_PARAM_ONE) {
        *pt = p->end;
        return CS_OK;
    }
    /* Next chord: the step this one would have needed to fill the tolerance (its step
     * corrected by its room), extrapolated by the trend of that ideal step (trend above). */
    cs_param_t ideal = predict(h, room, CS_PARAM_ONE);
#if HOST_GUESS
    /* at most the rest of the curve: find_step takes it as it is (no select on the path) */
    p->h_next = next_step(h, room, p->h_ideal, CS_PARAM_ONE - p->t);
    p->h_ideal = room == ROOM_HULL ? 0 : ideal; /* a hull test says nothing of the trend */
#else
    cs_param_t nh = trend(ideal, p->h_ideal);   /* < 2^31 (trend above) */
    p->h_ideal = room == ROOM_HULL ? 0 : ideal; /* a hull test says nothing of the trend */
    p->h_next = nh < 1 ? 1 : nh > CS_PARAM_ONE ? CS_PARAM_ONE : nh;
#endif
    p->done = false;
    *eval = true;
    return CS_OK;
}

static cs_err_t next_poly(cs_predict_t *p, cs_vec3_t *pt)
{
    int32_t room = ROOM_HULL;
    bool eval;
#if HOST_GUESS
    cs_param_t h = find_step(p, test_fast, p, &room); /* sets room: before step_to reads it */
#else
    cs_param_t h = find_step(p, test_step, p->d, &room); /* sets room: before step_to reads it */
#endif
    cs_err_t e = step_to(p, h, room, pt, &eval);
    if (eval)
        eval_poly(p, pt);
    return e;
}

static cs_err_t next_conic(cs_predict_t *p, cs_vec3_t *pt)
{
    conic_start_t c0;
    conic_start(p, &c0);
    int32_t room = ROOM_HULL;
    bool eval;
    cs_param_t h = find_step(p, test_conic, &c0, &room); /* sets room: before step_to reads it */
    cs_err_t e = step_to(p, h, room, pt, &eval);
    if (eval)
        eval_conic(p, pt);
    return e;
}

cs_err_t cs_predict_next(cs_predict_t *p, cs_vec3_t *pt)
{
    return p->done ? CS_END : p->next(p, pt);
}
