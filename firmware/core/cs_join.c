/* cs_join: continuity at a join (seed 003, "Continuité"). All comparisons are exact integer
 * arithmetic on the control points, with lengths by integer square root (cs_fixed_vec_len64)
 * and unit vectors in Q1.30. Vectors are int64_t[3] handled by small loops through pointers
 * (struct values of int64 cost kilobytes of code on AVR). */
#include "cs_join.h"

typedef int64_t v3_t[3];

/* What one side contributes, all measured pointing "forward" along the joined path. */
typedef struct {
    v3_t p;   /* the join point, LSB */
    v3_t d1;  /* first leg P_n - P_{n-1} (a) or Q_1 - Q_0 (b), LSB */
    v3_t d2;  /* second difference P_n - 2P_{n-1} + P_{n-2} (a) or Q_2 - 2Q_1 + Q_0 (b) */
    v3_t dir; /* first non-zero leg (geometric tangent), LSB; zero if none */
    v3_t D1;  /* B' at the join, LSB per unit t */
    v3_t D2;  /* B'' at the join (polynomial only), LSB per unit t^2 */
    unsigned n;
} side_t;

/* Coordinate a of control point k counted from a's end (k = 0: P_n), or from b's start. */
static int64_t pt(const cs_bezier_t *c, bool end, unsigned k, unsigned a)
{
    const cs_vec3_t *p = &c->p[end ? c->degree - k : k];
    return a == 0 ? p->x : a == 1 ? p->y : p->z;
}

static void vsub(const int64_t *a, const int64_t *b, int64_t *out)
{
    for (unsigned i = 0; i < 3; i++)
        out[i] = a[i] - b[i];
}

static uint64_t vlen(const int64_t *a)
{
    return cs_fixed_vec_len64(a[0], a[1], a[2]);
}

/* |a|^2 for legs (components < 2^30, exact). */
static uint64_t vlen2(const int64_t *a)
{
    uint64_t s = 0;
    for (unsigned i = 0; i < 3; i++)
        s += (uint64_t)(a[i] * a[i]);
    return s;
}

static bool is_zero(const int64_t *a, cs_pos_t pos)
{
    return vlen2(a) <= (uint64_t)pos * (uint64_t)pos;
}

static void side_init(const cs_bezier_t *c, bool end, cs_pos_t pos, side_t *s)
{
    unsigned n = c->degree;
    s->n = n;
    /* a: legs P_n - P_{n-k}; b: Q_k - Q_0 (both point forward) */
    int64_t sg = end ? 1 : -1;
    for (unsigned a = 0; a < 3; a++) {
        int64_t p0 = pt(c, end, 0, a), p1 = pt(c, end, 1, a);
        s->p[a] = p0;
        s->d1[a] = sg * (p0 - p1);
        s->d2[a] = n >= 2 ? p0 - 2 * p1 + pt(c, end, 2, a) : 0;
        s->dir[a] = 0;
    }
    for (unsigned k = 1; k <= n; k++) {
        v3_t d;
        for (unsigned a = 0; a < 3; a++)
            d[a] = sg * (pt(c, end, 0, a) - pt(c, end, k, a));
        if (!is_zero(d, pos)) {
            for (unsigned a = 0; a < 3; a++)
                s->dir[a] = d[a];
            break;
        }
    }
    /* Polynomial: B' = n d1, B'' = n (n-1) d2. Rational: B' = n w_{n-1} / w_n (P_n - P_{n-1})
     * (resp. n w_1 / w_0 (Q_1 - Q_0)): |n w d| < 7 * 2^30 * 2^29 < 2^62, the quotient < 2^52;
     * B'' is not used for rational segments. */
    int64_t wn = c->w[end ? n : 0], wn1 = c->w[end ? n - 1 : 1];
    for (unsigned a = 0; a < 3; a++) {
        if (c->rational) {
            s->D1[a] = cs_fixed_div_round((int64_t)n * wn1 * s->d1[a], wn);
            s->D2[a] = 0;
        } else {
            s->D1[a] = (int64_t)n * s->d1[a];
            s->D2[a] = (int64_t)n * ((int64_t)n - 1) * s->d2[a];
        }
    }
}

/* |u - v| <= rel * max(|u|, |v|) + abs */
static bool agree(const int64_t *u, const int64_t *v, cs_param_t rel, uint64_t abs)
{
    v3_t d;
    uint64_t lu = vlen(u), lv = vlen(v), m = lu > lv ? lu : lv;
    vsub(u, v, d);
    return vlen(d) <= (uint64_t)cs_fixed_mul64_q30((int64_t)m, rel) + abs;
}

/* Unit vector in Q1.30 (|d| > 0, components < 2^31). */
static void unit(const int64_t *d, int64_t *u)
{
    int64_t l = (int64_t)vlen(d);
    for (unsigned i = 0; i < 3; i++)
        u[i] = cs_fixed_div_round(d[i] * ((int64_t)1 << 30), l);
}

/* G1 test on the two tangent directions (Q30 unit vectors): |ua x ub| <= s and ua . ub > 0. */
static bool same_direction(const int64_t *ua, const int64_t *ub, cs_param_t s)
{
    int64_t dot = 0;
    uint64_t c2 = 0;
    for (unsigned i = 0; i < 3; i++) {
        unsigned j = (i + 1) % 3, k = (i + 2) % 3;
        int64_t c = cs_fixed_round_shift64(ua[j] * ub[k] - ua[k] * ub[j], 30);
        c2 += (uint64_t)(c * c);
        dot += ua[i] * ub[i];
    }
    return dot > 0 && c2 <= (uint64_t)((int64_t)s * s);
}

/* Curvature vector at the join, 1/mm in Q32: ((n-1)/n) d2perp / |d1|^2, d2perp = the part of
 * d2 normal to the tangent (Bézier end curvature, from B' = n d1 and B'' = n(n-1) d2). */
static cs_err_t curvature(const side_t *s, int64_t *k)
{
    v3_t T;
    unit(s->d1, T);
    /* d2 . T: |d2| < 2^31, so each product < 2^61 and the sum fits int64 */
    int64_t dt = 0;
    for (unsigned i = 0; i < 3; i++)
        dt += s->d2[i] * T[i];
    dt = cs_fixed_round_shift64(dt, 30);
    uint64_t den = (uint64_t)s->n * vlen2(s->d1); /* < 7 * 3 * 2^58 < 2^63 */
    for (unsigned i = 0; i < 3; i++) {
        int64_t c = s->d2[i] - cs_fixed_mul64_q30(dt, (int32_t)T[i]);
        uint64_t m = (uint64_t)(c < 0 ? -c : c) * (s->n - 1u), hi, lo, q;
        cs_fixed_mul_u64(m, (uint64_t)1 << 48, &hi, &lo);
        cs_err_t e = cs_fixed_div_u128(hi, lo, den, &q);
        if (e != CS_OK)
            return e;
        if (q >= ((uint64_t)1 << 61))
            return CS_ERR_OVERFLOW;
        k[i] = c < 0 ? -(int64_t)q : (int64_t)q;
    }
    return CS_OK;
}

cs_err_t cs_join_classify(const cs_bezier_t *a, const cs_bezier_t *b, const cs_join_tol_t *tol,
                          unsigned *flags)
{
    cs_err_t e;
    if (tol->pos < 0 || tol->sin_angle < 0 || tol->sin_angle > CS_PARAM_ONE || tol->rel < 0 ||
        tol->rel > CS_PARAM_ONE)
        return CS_ERR_TOLERANCE;
    if ((e = cs_bezier_check(a)) != CS_OK || (e = cs_bezier_check(b)) != CS_OK)
        return e;
    side_t sa, sb;
    v3_t u, v;
    side_init(a, true, tol->pos, &sa);
    side_init(b, false, tol->pos, &sb);
    *flags = 0;
    vsub(sa.p, sb.p, u);
    if (!is_zero(u, tol->pos))
        return CS_OK;
    unsigned f = CS_JOIN_C0;
    /* side_init leaves dir zero when every leg is within pos of zero */
    if (!is_zero(sa.dir, tol->pos) && !is_zero(sb.dir, tol->pos)) {
        unit(sa.dir, u);
        unit(sb.dir, v);
        if (same_direction(u, v, tol->sin_angle))
            f |= CS_JOIN_G1;
    }
    if (agree(sa.D1, sb.D1, tol->rel, (uint64_t)tol->pos))
        f |= CS_JOIN_C1;
    bool poly = !a->rational && !b->rational;
    if (poly && (f & CS_JOIN_C1) && agree(sa.D2, sb.D2, tol->rel, (uint64_t)tol->pos))
        f |= CS_JOIN_C2;
    if (poly && (f & CS_JOIN_G1) && !is_zero(sa.d1, tol->pos) && !is_zero(sb.d1, tol->pos)) {
        if ((e = curvature(&sa, u)) != CS_OK || (e = curvature(&sb, v)) != CS_OK)
            return e;
        uint64_t ha = vlen2(sa.d1), hb = vlen2(sb.d1), h2 = ha > hb ? ha : hb, hi, lo, fl;
        /* 2 pos / h^2 in 1/mm Q32 = 2 pos 2^48 / h^2 (LSB units); h > pos here (regular
         * ends), so the quotient < 2^49 always fits */
        cs_fixed_mul_u64(2u * (uint64_t)tol->pos, (uint64_t)1 << 48, &hi, &lo);
        if ((e = cs_fixed_div_u128(hi, lo, h2, &fl)) != CS_OK)
            return e;
        if (agree(u, v, tol->rel, fl))
            f |= CS_JOIN_G2;
    }
    *flags = f;
    return CS_OK;
}
