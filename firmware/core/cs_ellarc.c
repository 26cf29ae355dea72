/* cs_ellarc: equal-angle chords of a conic piece by the rotation recurrence (see cs_ellarc.h;
 * derivation and error bound in docs/fixed-point.md, "Arc tracer").
 * Scalars of the set-up are unsigned Q62 (value * 2^62); the recurrence runs on int64 in units
 * of 2^-28 LSB. The piece in standard form (w0 = w2 = 1, w1 = w = cos alpha, s = sin alpha):
 *   M = (Q0 + Q2)/2, U = (Q1 - M) w / s^2, V = (Q2 - Q0) / (2 s), C = M - U w,
 * and with phi measured from Q0 (theta = phi + alpha) the point is
 *   y(theta) = x - C = y0 cos theta + V'' sin theta,  y0 = Q0 - C,  V'' = (w / s)(Q1 - Q0). */
#include "cs_ellarc.h"

#include <stddef.h>

#define FR       CS_ELLARC_FRAC
#define Q62_ONE  ((uint64_t)1 << 62)
#define W_MIN    759250125 /* ceil(cos(45deg) 2^30): pieces of at most 90 degrees */
#define STATE_LIM ((int64_t)1 << 58) /* |y| and |C| in 2^-28 LSB: kmul's halves stay in int64 */

/* (a b) / 2^62 for unsigned Q62 a, b (truncated). */
static uint64_t mulq(uint64_t a, uint64_t b)
{
#if CS_FIXED_WIDE /* a 64-bit host: one multiply, inline */
    return (uint64_t)(((unsigned __int128)a * b) >> 62);
#else
    uint64_t hi, lo;
    cs_fixed_mul_u64(a, b, &hi, &lo);
    return (hi << 2) | (lo >> 62);
#endif
}

/* sqrt(v) for unsigned Q62 v (< 4), Q62, within 2^-58 relative: isqrt64 gives 31 bits, one
 * Newton correction rem / (2 r0) the next 31 (its own error rem^2 / (8 r0^3) <= 2^-29 of an
 * r0 unit). v = 0 gives 0. */
static uint64_t sqrt_q62(uint64_t v)
{
    if (v == 0)
        return 0;
    unsigned b = cs_fixed_bitlen64(v); /* even shift e bringing v into [2^60, 2^62) */
    unsigned e = b >= 61 ? 0 : (62 - b) & ~1u;
    uint64_t m = v << e;
    uint64_t r0 = cs_fixed_isqrt64(m); /* [2^30, 2^31) */
    uint64_t rem = m - r0 * r0;        /* <= 2 r0 <= 2^32 */
    uint64_t r = (r0 << 31) + (rem << 30) / r0; /* sqrt(m) 2^31 = sqrt(v 2^62) 2^(e/2) */
    return r >> (e / 2);
}

/* asin(z) for z (Q62) with z2 = z^2 <= sin^2(22.5deg): z (1 + z2/6 + 3 z2^2/40 + ...), twelve
 * terms at most by Horner (tail < 2^-40 relative, all terms positive so it is an underestimate
 * charged to the set-up margin, docs/fixed-point.md). */
static uint64_t asin_z(uint64_t z, uint64_t z2)
{
    static const uint64_t c[12] = {
        4611686018427387904u, 768614336404564651u, 345876451382054093u, 205878840108365531u,
        140111988407082098u,  103173373281578636u, 80025501070968044u,  64401474671398093u,
        53273278680384452u,   45017478183131891u,  38693594343120506u,  33723073330664314u};
    /* terms past z2^k with z2^k < 2^-44 dropped: k = 44 / log2(1/z2) (z2 >= 2^-40 here) */
    unsigned lg = 62 - cs_fixed_bitlen64(z2 | 1), k = lg == 0 ? 11 : 44 / lg + 1;
    k = k > 11 ? 11 : k;
    uint64_t p = c[k];
    while (k-- > 0)
        p = c[k] + mulq(p, z2);
    return mulq(z, p);
}

/* sin(h) for h unsigned Q62 <= 0.4: h (1 - h^2/6 + h^4/120 - ...), eight terms (tail < 2^-59),
 * the alternating terms grouped as differences of non-negative Horner steps. */
static uint64_t sin_q62(uint64_t h)
{
    static const uint64_t c[8] = {4611686018427387904u, 768614336404564651u, 38430716820228233u,
                                  915017067148291u,     12708570377060u,     115532457973u,
                                  740592679u,           3526632u};
    uint64_t v = mulq(h, h), p = c[7];
    for (unsigned k = 7; k-- > 0;)
        p = c[k] - mulq(p, v); /* c[k] > c[k+1] v: every partial sum stays positive */
    return mulq(h, p);
}

/* floor(v K) with K = km 2^-ks, ks >= 32, |v| < 2^62: the 64x32 product in two halves (two
 * 32x32 -> 64 multiplies), floor of a floor being the floor. */
static inline int64_t kmul(int64_t v, uint32_t km, unsigned ks)
{
    int64_t hi = v >> 32; /* arithmetic shift: floor(v / 2^32) */
    uint64_t lo = (uint64_t)v & 0xFFFFFFFFu;
    int64_t s = hi * (int64_t)km + (int64_t)((lo * km) >> 32); /* floor(v K 2^(ks-32)) */
    return s >> (ks - 32);
}

static uint64_t uabs(int64_t v)
{
    return v < 0 ? (uint64_t)0 - (uint64_t)v : (uint64_t)v;
}

/* (|v| c) / 2^62 with v's sign, c unsigned Q62 (or any scale 2^62 divides out): |v| c < 2^126. */
static int64_t mul_sq(int64_t v, uint64_t c)
{
    int64_t t = (int64_t)mulq(uabs(v), c); /* inline on 64-bit hosts (the set-up's most used) */
    return v < 0 ? -t : t;
}

/* K = hi:lo / 2^scale rounded down to km 2^-ks (km in [2^31, 2^32)); false when ks leaves
 * 32..60 (a step of more than 60 degrees or under 2^-14 rad: not taken). */
static bool norm_k(uint64_t hi, uint64_t lo, unsigned scale, uint32_t *km, unsigned *ks)
{
    if (hi == 0)
        return false;
    unsigned sh = 32 + cs_fixed_bitlen64(hi); /* hi:lo >> sh in [2^31, 2^32) */
    uint64_t k = sh >= 64 ? hi >> (sh - 64) : (hi << (64 - sh)) | (lo >> sh);
    if (sh > scale || scale - sh < 32 || scale - sh > 60)
        return false;
    *km = (uint32_t)k;
    *ks = scale - sh;
    return true;
}

/* The shape of |A t(theta)|^2 = P + Q cos 2theta + R sin 2theta (theta from Q0, A t the tangent)
 * in units shifted right by sh from y0, V'' (2^-28 LSB): P, Q, R, L = sqrt(Q^2 + R^2), det. */
typedef struct {
    int64_t yy, vv, yv; /* |y0|^2, |V''|^2, y0.V'' (scaled) */
    int64_t p, q, r;
    uint64_t l, det;
    unsigned sh;
} shape_t;

static bool shape(const int64_t y0[2], const int64_t v0[2], shape_t *f)
{
    uint64_t m = uabs(y0[0]) | uabs(y0[1]) | uabs(v0[0]) | uabs(v0[1]);
    unsigned b = cs_fixed_bitlen64(m), sh = b > 30 ? b - 30 : 0; /* the least: m >> sh < 2^30 */
    int64_t y[2] = {y0[0] >> sh, y0[1] >> sh}, v[2] = {v0[0] >> sh, v0[1] >> sh};
    f->sh = sh;
    f->yy = y[0] * y[0] + y[1] * y[1];
    f->vv = v[0] * v[0] + v[1] * v[1];
    f->yv = y[0] * v[0] + y[1] * v[1];
    f->p = (f->yy + f->vv) / 2;
    f->q = (f->vv - f->yy) / 2;
    f->r = -f->yv;
    f->l = cs_fixed_vec_len64(f->q, f->r, 0);
    f->det = uabs(y[0] * v[1] - y[1] * v[0]);
    return f->det != 0;
}

/* |A t|^2 at theta with (cos, sin) theta = (c, s), Q62 >= 0: |y0|^2 s^2 - 2 y0.V'' s c +
 * |V''|^2 c^2. */
static int64_t shape_at(const shape_t *f, uint64_t c, uint64_t s)
{
    return mul_sq(mul_sq(f->yy, s), s) - 2 * mul_sq(mul_sq(f->yv, s), c) +
           mul_sq(mul_sq(f->vv, c), c);
}

/* Is the least |A t| direction, (cos, sin) 2theta* = -(Q, R)/L, between 2a and 2b (the double
 * angles of the range, (cos, sin) a = (ca, sa), b = (cb, sb), b - a <= 90 degrees)? */
static bool shape_min_inside(const shape_t *f, uint64_t ca, uint64_t sa, uint64_t cb, uint64_t sb)
{
    if (f->l == 0)
        return false;
    /* (cos, sin) 2a = (ca^2 - sa^2, 2 ca sa), Q62 signed; |Q|, |R| < 2^62 */
    int64_t a2c = (int64_t)mulq(ca, ca) - (int64_t)mulq(sa, sa), a2s = 2 * (int64_t)mulq(ca, sa);
    int64_t b2c = (int64_t)mulq(cb, cb) - (int64_t)mulq(sb, sb), b2s = 2 * (int64_t)mulq(cb, sb);
    int64_t mq = -f->q, mr = -f->r;
    /* cross(a2, m) >= 0 and cross(m, b2) >= 0: a2c mr - a2s mq, mq b2s - mr b2c (>> 62) */
    int64_t x1 = mul_sq(mr, uabs(a2c)) * (a2c < 0 ? -1 : 1) - mul_sq(mq, uabs(a2s));
    int64_t x2 = mul_sq(mq, uabs(b2s)) - mul_sq(mr, uabs(b2c)) * (b2c < 0 ? -1 : 1);
    return x1 >= 0 && x2 >= 0;
}

/* x = thr |A t|_min / |det A| in Q60 for the least scaled |A t|^2 fmin: the units cancel to
 * thr sqrt(fmin) 2^(28 - sh) / det. UINT64_MAX when it does not fit. */
static uint64_t x_of(const shape_t *f, int64_t fmin, uint64_t thr)
{
    /* sqrt(fmin) to 20 bits (fmin shifted below 2^40: half the digit steps), rounded down */
    uint64_t fm = fmin > 0 ? (uint64_t)fmin : 0;
    unsigned h = cs_fixed_bitlen64(fm) > 40 ? (cs_fixed_bitlen64(fm) - 39) / 2 : 0;
    uint64_t num = thr * ((uint64_t)cs_fixed_isqrt64(fm >> (2 * h)) << h); /* < 2^60 */
    unsigned k = 88 - f->sh; /* num 2^k as hi:lo, k in 60..88 */
    uint64_t hi, lo, x;
    if (k >= 64) {
        if (k > 64 && (num >> (128 - k)) != 0)
            return UINT64_MAX;
        hi = num << (k - 64);
        lo = 0;
    } else {
        hi = num >> (64 - k);
        lo = num << k;
    }
    return cs_fixed_div_u128(hi, lo, f->det, &x) == CS_OK ? x : UINT64_MAX;
}

/* x for the range [a, b] of theta ((cos, sin) given, fa, fb = |A t|^2 there): at the ends or at
 * the least point. */
static uint64_t x_range(const shape_t *f, uint64_t thr, uint64_t ca, uint64_t sa, uint64_t cb,
                        uint64_t sb, int64_t fa, int64_t fb)
{
    int64_t fmin = fa < fb ? fa : fb;
    if (shape_min_inside(f, ca, sa, cb, sb))
        fmin = f->p - (int64_t)f->l - 2;
    return x_of(f, fmin, thr);
}

/* True when the arc tracer takes c (planar rational quadratic, w0 = w2 = 1, W_MIN <= w1 < 1). */
static bool ellarc_accepts(const cs_bezier_t *c)
{
    return c->rational && c->degree == 2 && c->w[0] == CS_WEIGHT_ONE &&
           c->w[2] == CS_WEIGHT_ONE && c->w[1] >= W_MIN && c->w[1] < CS_WEIGHT_ONE &&
           c->p[0].z == c->p[1].z && c->p[1].z == c->p[2].z;
}

#define X22 87760923908463872u /* 1 - cos(22.5 deg), Q60, down: the asin series' range */

/* Step of a sub-range from its x (Q60, capped): K = 4 x (2 - x) (cos(delta/2) = 1 - x) rounded
 * down, its angle delta = 2 asin(sqrt(K)/2) and sin(delta) = sqrt(K) sqrt(1 - K/4), Q62. */
static bool sub_step(uint64_t x, cs_ellarc_sub_t *sub, uint64_t *sind)
{
    uint64_t hi, lo;
    unsigned ks;
    x -= x >> 12; /* margin for the approximations of the set-up (docs/fixed-point.md) */
    cs_fixed_mul_u64(x, ((uint64_t)1 << 61) - x, &hi, &lo); /* x (2 - x) 2^120 = K 2^118 */
    if (!norm_k(hi, lo, 118, &sub->km, &ks))
        return false;
    sub->ks = (uint8_t)ks;
    uint64_t k4 = (uint64_t)sub->km << (60 - ks); /* K/4 = sin^2(delta/2), Q62 */
    uint64_t z = sqrt_q62(k4);                     /* sin(delta/2) */
    sub->delta = 2 * asin_z(z, k4);
    *sind = 2 * mulq(z, sqrt_q62(Q62_ONE - k4));
    return true;
}

/* The sub-ranges: m = 1 (a circle, or too few chords to gain), else 4 or 8 equal ones, each with
 * the step its worst |A t| over itself and the next allows (a chord started in it ends at most
 * half a step beyond, and the step is capped to two sub-range widths). sind[i] = sin(delta_i).
 * cw, sw: cos and sin of 2 alpha (Q62, sw >= 0, cw >= 0 for 2 alpha <= 90 deg). */
static cs_err_t plan(cs_ellarc_t *a, const shape_t *f, uint64_t alpha2, uint64_t thr,
                     uint64_t cw, uint64_t sw, uint64_t sind[CS_ELLARC_MAX_SUB])
{
    /* the overshoot cap x <= 2 b^2/(a^2 + b^2) = (P - L)/P and the series' range */
    int64_t capv;
    uint64_t cap = X22; /* (P - L)/P >= X22 while L <= P/2: nothing to compute */
    if (f->l > (uint64_t)f->p / 2 &&
        cs_fixed_muldiv64(f->p - (int64_t)f->l, (int64_t)1 << 60, f->p, &capv) == CS_OK &&
        capv >= 0) {
        uint64_t c = (uint64_t)capv;
        c -= (c >> 20) + (c > 64 ? 64 : c);
        cap = c < cap ? c : cap;
    }
    /* a circle to 2^-16 (L <= P/2^16): the least |A t|^2, P - L, is everywhere */
    bool round = f->l <= (uint64_t)f->p >> 16;
    uint64_t x = round ? x_of(f, f->p - (int64_t)f->l - 2, thr)
                       : x_range(f, thr, Q62_ONE, 0, cw, sw, shape_at(f, Q62_ONE, 0),
                                 shape_at(f, cw, sw));
    unsigned m = 1;
    /* an eccentric piece of many chords (n ~ 2 alpha / sqrt(8 x) at the worst step): 8
     * sub-ranges from 24 chords, 4 from 8 (fewer chords do not repay the set-up) */
    if (!round && f->l > (uint64_t)f->p / 32 && x != UINT64_MAX) {
        uint64_t a2 = mulq(alpha2, alpha2), x62 = (x < cap ? x : cap) << 2;
        m = a2 / (8 * 24 * 24) >= x62 ? 8 : a2 / (8 * 8 * 8) >= x62 ? 4 : 1;
    }
    a->m = (uint8_t)m;
    if (m == 1) {
        x = x < cap ? x : cap;
        if (x == 0 || !sub_step(x, &a->sub[0], &sind[0]))
            return CS_ERR_UNSUPPORTED;
        a->sub[0].bound = alpha2;
        return CS_OK;
    }
    /* boundaries theta_i = i W, W = 2 alpha / m <= 22.5 deg: (cos, sin) by rotation in Q62 */
    uint64_t wq = alpha2 / m, sW = sin_q62(wq), cW = sqrt_q62(Q62_ONE - mulq(sW, sW));
    uint64_t cb[CS_ELLARC_MAX_SUB + 1], sb[CS_ELLARC_MAX_SUB + 1];
    int64_t fb[CS_ELLARC_MAX_SUB + 1];
    cb[0] = Q62_ONE;
    sb[0] = 0;
    for (unsigned i = 1; i <= m; i++) {
        cb[i] = mulq(cb[i - 1], cW) - mulq(sb[i - 1], sW);
        sb[i] = mulq(sb[i - 1], cW) + mulq(cb[i - 1], sW);
    }
    for (unsigned i = 0; i <= m; i++)
        fb[i] = shape_at(f, cb[i], sb[i]);
    uint64_t capw = (Q62_ONE - cW) >> 2; /* 1 - cos W, Q60: delta/2 <= W */
    cap = capw < cap ? capw : cap;
    for (unsigned i = 0; i < m; i++) {
        unsigned j = i + 2 > m ? m : i + 2;
        uint64_t xi = x_range(f, thr, cb[i], sb[i], cb[j], sb[j], fb[i], fb[j]);
        xi = xi < cap ? xi : cap;
        if (xi == 0 || !sub_step(xi, &a->sub[i], &sind[i]))
            return CS_ERR_UNSUPPORTED;
        a->sub[i].bound = alpha2 - wq * i; /* entered when the angle left is at most this */
    }
    return CS_OK;
}

/* Chord count (estimate from above) and the error bound's condition n^2 delta_max / delta_min
 * <= 15 2^20 (docs/fixed-point.md): false when the piece needs more. */
static bool count_ok(const cs_ellarc_t *a, uint64_t alpha2)
{
    uint64_t n = 0, dmax = 0, dmin = UINT64_MAX, wq = alpha2 / a->m;
    for (unsigned i = 0; i < a->m; i++) {
        uint64_t d = a->sub[i].delta;
        if (d == 0)
            return false;
        n += wq / d + 1;
        dmax = d > dmax ? d : dmax;
        dmin = d < dmin ? d : dmin;
    }
    return n <= CS_ELLARC_MAX_CHORDS && cs_fixed_cmp_prod_u64(n * n, dmax, (uint64_t)15 << 20, dmin) <= 0;
}

cs_err_t cs_ellarc_begin(cs_ellarc_t *a, const cs_bezier_t *c, cs_pos_t tol)
{
    a->done = true;
    if (!ellarc_accepts(c) || tol < CS_ELLARC_TOL_MIN)
        return CS_ERR_UNSUPPORTED;
    const cs_vec3_t *q = c->p;
    int64_t d01[2] = {(int64_t)q[1].x - q[0].x, (int64_t)q[1].y - q[0].y};
    int64_t d12[2] = {(int64_t)q[2].x - q[1].x, (int64_t)q[2].y - q[1].y};
    int64_t d02[2] = {d01[0] + d12[0], d01[1] + d12[1]};
    int64_t crs = d01[0] * d02[1] - d01[1] * d02[0];
    if (crs == 0)
        return CS_ERR_UNSUPPORTED; /* straight: the polygon is the curve */
    uint64_t cr = uabs(crs), w = (uint64_t)c->w[1], thr = (uint64_t)(tol - CS_ELLARC_SLACK_LSB);
    a->end = q[2];
    a->done = false;
    a->rem = 0;
    /* One chord when the shoulder, w/(1+w) of the way to Q1, is within thr of the chord line,
     * w |cr| <= thr (1 + w) |Q2 - Q0| (length rounded down: conservative), and both end
     * tangents are at an acute angle to the chord (the arc then stays beside the segment). */
    uint64_t l02 = cs_fixed_vec_len64(d02[0], d02[1], 0);
    if (cs_fixed_cmp_prod_u64(w, cr, thr * (((uint64_t)1 << 30) + w), l02) <= 0 &&
        d01[0] * d02[0] + d01[1] * d02[1] >= 0 && d12[0] * d02[0] + d12[1] * d02[1] >= 0)
        return CS_OK;
    uint64_t s2 = ((uint64_t)1 << 60) - w * w; /* sin^2 alpha, Q60, exact */
    uint64_t s = sqrt_q62(s2 << 2), wq = w << 32;
    /* 2 alpha = 4 asin(sqrt((1 - w)/2)); cos 2alpha = 2 w^2 - 1, sin 2alpha = 2 w s (Q62) */
    uint64_t za2 = (((uint64_t)1 << 30) - w) << 31, alpha2 = 4 * asin_z(sqrt_q62(za2), za2);
    uint64_t w2 = 2 * mulq(wq, wq), sw = 2 * mulq(wq, s);
    uint64_t cw = w2 > Q62_ONE ? w2 - Q62_ONE : 0; /* >= 0 up to rounding (w >= cos 45) */
    const int64_t qx[3][2] = {{q[0].x, q[0].y}, {q[1].x, q[1].y}, {q[2].x, q[2].y}};
    int64_t y0[2], v0[2];
    for (unsigned i = 0; i < 2; i++) {
        /* C = M - (Q1 - M) w^2 / s^2; V'' = (w / s)(Q1 - Q0), the tangent at Q0 */
        int64_t off;
        if (cs_fixed_muldiv64((d01[i] - d12[i]) * ((int64_t)1 << (FR - 1)), (int64_t)(w * w),
                              (int64_t)s2, &off) != CS_OK ||
            cs_fixed_muldiv64(d01[i] * ((int64_t)1 << FR), (int64_t)wq, (int64_t)s, &v0[i]) !=
                CS_OK)
            return CS_ERR_UNSUPPORTED;
        a->c[i] = (qx[0][i] + qx[2][i]) * ((int64_t)1 << (FR - 1)) - off;
        y0[i] = qx[0][i] * ((int64_t)1 << FR) - a->c[i];
        if (a->c[i] >= STATE_LIM || a->c[i] <= -STATE_LIM || y0[i] >= STATE_LIM ||
            y0[i] <= -STATE_LIM || v0[i] >= STATE_LIM || v0[i] <= -STATE_LIM)
            return CS_ERR_UNSUPPORTED;
    }
    shape_t f;
    uint64_t sind[CS_ELLARC_MAX_SUB];
    if (!shape(y0, v0, &f) || plan(a, &f, alpha2, thr, cw, sw, sind) != CS_OK ||
        !count_ok(a, alpha2))
        return CS_ERR_UNSUPPORTED;
    for (unsigned i = 1; i < a->m; i++) {
        uint64_t hi = sind[i] >> 4, lo = sind[i] << 60, r; /* sin ratio, Q60 */
        if (cs_fixed_div_u128(hi, lo, sind[i - 1], &r) != CS_OK || r >> 62 != 0)
            return CS_ERR_UNSUPPORTED;
        a->sub[i].ratio = r;
    }
    const cs_ellarc_sub_t *s0 = &a->sub[0];
    for (unsigned i = 0; i < 2; i++) {
        /* D1 = y1 - y0 = -(K/2) y0 + sin(delta) V'' */
        a->d[i] = mul_sq(v0[i], sind[0]) - kmul(y0[i], s0->km, s0->ks) / 2;
        a->x[i] = qx[0][i] * ((int64_t)1 << FR);
    }
    a->cur = 0;
    a->rem = alpha2;
    return CS_OK;
}

cs_err_t cs_ellarc_next(cs_ellarc_t *a, cs_vec3_t *pt)
{
    if (a->done)
        return CS_END;
    const cs_ellarc_sub_t *s = &a->sub[a->cur];
    if (a->rem <= s->delta) { /* the rest of the piece is one chord of at most this step */
        a->done = true;
        *pt = a->end;
        return CS_OK;
    }
    a->rem -= s->delta;
    int64_t ky[2];
    for (unsigned i = 0; i < 2; i++) {
        a->x[i] += a->d[i];
        ky[i] = kmul(a->x[i] - a->c[i], s->km, s->ks);
        a->d[i] -= ky[i];
    }
    while (a->cur + 1u < a->m && a->rem <= a->sub[a->cur + 1].bound) {
        /* next sub-range: D' = -(K'/2) y + (D + (K/2) y) sin(delta')/sin(delta) */
        const cs_ellarc_sub_t *n = &a->sub[++a->cur];
        for (unsigned i = 0; i < 2; i++) {
            int64_t t = a->d[i] + ky[i] / 2, ta = (int64_t)mulq(uabs(t), n->ratio << 2);
            ky[i] = kmul(a->x[i] - a->c[i], n->km, n->ks);
            a->d[i] = (t < 0 ? -ta : ta) - ky[i] / 2;
        }
    }
    /* rounded to the nearest LSB (half up: floor(x + 1/2), arithmetic shift) */
    pt->x = (cs_pos_t)((a->x[0] + ((int64_t)1 << (FR - 1))) >> FR);
    pt->y = (cs_pos_t)((a->x[1] + ((int64_t)1 << (FR - 1))) >> FR);
    pt->z = a->end.z;
    return CS_OK;
}
