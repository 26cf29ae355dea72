/* cs_spline: natural cubic spline in Hermite form. Unknowns are the tangents m_i at the points
 * (derivative with respect to the spline parameter); on span i of length h_i each segment is the
 * Hermite cubic (P_i, P_i+1, h_i m_i, h_i m_i+1), i.e. the Bézier (P_i, P_i + h_i m_i / 3,
 * P_i+1 - h_i m_i+1 / 3, P_i+1) (seed 003, "De Hermite à Bézier"). With slopes s_i = (P_i+1 -
 * P_i) / h_i, C2 at point i and zero curvature at the ends give (de Boor, "A Practical Guide to
 * Splines", ch. IV), each interior row divided by h_i-1 + h_i:
 *   2 m_0 + m_1                         = 3 s_0
 *   lam_i m_i-1 + 2 m_i + mu_i m_i+1    = 3 (lam_i s_i-1 + mu_i s_i),
 *                  lam_i = h_i / (h_i-1 + h_i), mu_i = h_i-1 / (h_i-1 + h_i) = 1 - lam_i
 *   m_n-1 + 2 m_n                       = 3 s_n-1.
 * The matrix is strictly diagonally dominant (2 > lam + mu = 1), so Thomas' elimination needs no
 * pivoting and every pivot stays in [1, 2]: it is stable and cannot divide by zero.
 *
 * Fixed point: coefficients and pivots scaled by 2^40 (COEF), slopes by 2^20 LSB (uniform,
 * |s| < 2^49) or 2^40 mm/mm (chord, |s| <= 1). Every product goes through cs_fixed_muldiv64
 * (128-bit intermediate, one rounding), so the solve adds far less than 1 LSB; the Bézier inner
 * points are rounded once (<= 0.5 LSB). Bounds: |rhs| < 3 * 2^49 and |d_i| < 2 |rhs|max < 2^53. */
#include "cs_spline.h"

#define COEF_BITS          40
#define COEF               ((int64_t)1 << COEF_BITS)
#define SLOPE_BITS_UNIFORM 20
#define SLOPE_BITS_CHORD   40
#define H_FRAC_BITS        16 /* chord lengths: LSB with 16 fractional bits (< 2^46) */

CS_STATIC_ASSERT(CS_SPLINE_MAX_POINTS >= 2, spline_holds_one_segment);

/* Row i's off-diagonal coefficients (scaled by COEF): a multiplies m_i-1, c multiplies m_i+1. */
static cs_err_t spline_row(const cs_spline_t *s, size_t i, int64_t *a, int64_t *c)
{
    size_t n = s->count - 1;
    if (i == 0) {
        *a = 0;
        *c = COEF;
        return CS_OK;
    }
    if (i == n) {
        *a = COEF;
        *c = 0;
        return CS_OK;
    }
    if (s->param == CS_SPLINE_UNIFORM) {
        *a = COEF / 2;
        *c = COEF / 2;
        return CS_OK;
    }
    int64_t sum = (int64_t)(s->h[i - 1] + s->h[i]);
    cs_err_t e = cs_fixed_muldiv64((int64_t)s->h[i], COEF, sum, a);
    if (e == CS_OK)
        *c = COEF - *a; /* mu = 1 - lam exactly, so each row keeps its exact sum */
    return e;
}

/* Slope of span i along axis, scaled (see the file comment). */
static cs_err_t spline_slope(const cs_spline_t *s, size_t i, unsigned axis, int64_t *out)
{
    int64_t d = cs_fixed_vec_get(&s->pts[i + 1], axis) - cs_fixed_vec_get(&s->pts[i], axis);
    if (s->param == CS_SPLINE_UNIFORM) {
        *out = d * ((int64_t)1 << SLOPE_BITS_UNIFORM);
        return CS_OK;
    }
    return cs_fixed_muldiv64(d, (int64_t)1 << (SLOPE_BITS_CHORD + H_FRAC_BITS), (int64_t)s->h[i],
                             out);
}

/* Span lengths h_i: 1 (uniform) or the chord |P_i+1 - P_i| with H_FRAC_BITS fraction bits. */
static cs_err_t spline_spans(cs_spline_t *s)
{
    const cs_vec3_t *pts = s->pts;
    for (size_t i = 0; i + 1 < s->count; i++) {
        if (s->param == CS_SPLINE_UNIFORM) {
            s->h[i] = 1;
            continue;
        }
        /* Coordinates within 2^28 LSB: differences < 2^29, the sum of squares < 2^60. */
        int64_t dx = (int64_t)pts[i + 1].x - pts[i].x, dy = (int64_t)pts[i + 1].y - pts[i].y,
                dz = (int64_t)pts[i + 1].z - pts[i].z;
        uint64_t sq = (uint64_t)(dx * dx + dy * dy + dz * dz);
        if (sq == 0)
            return CS_ERR_DEGENERATE;
        /* |d| in LSB with H_FRAC_BITS fraction bits: scale sq by 4^k as far as 64 bits allow
         * (k <= 16), so the root keeps >= 31 significant bits whenever |d| >= 2^15 LSB; a
         * rounding of h changes the slope by the same relative amount, which the neighbouring
         * spans multiply by their own length (why an integer h is not enough). */
        unsigned k = 0;
        while (k < H_FRAC_BITS && (sq >> (62 - 2 * k)) == 0)
            k++;
        uint64_t sc = sq << (2 * k);
        uint64_t r = cs_fixed_isqrt64(sc);
        if (sc - r * r > r) /* round to nearest */
            r++;
        s->h[i] = r << (H_FRAC_BITS - k);
    }
    return CS_OK;
}

/* Right-hand sides of the tridiagonal system, per axis, into m[][]. */
static cs_err_t spline_rhs(cs_spline_t *s, size_t n)
{
    cs_err_t e = CS_OK;
    for (unsigned axis = 0; axis < 3 && e == CS_OK; axis++) {
        int64_t prev = 0, cur = 0;
        for (size_t i = 0; i <= n && e == CS_OK; i++) {
            if (i < n)
                e = spline_slope(s, i, axis, &cur);
            if (e != CS_OK)
                break;
            if (i == 0) {
                s->m[0][axis] = 3 * cur;
            } else if (i == n) {
                s->m[n][axis] = 3 * prev;
            } else {
                int64_t a, c, ta, tc;
                e = spline_row(s, i, &a, &c);
                if (e == CS_OK)
                    e = cs_fixed_muldiv64(prev, 3 * a, COEF, &ta);
                if (e == CS_OK)
                    e = cs_fixed_muldiv64(cur, 3 * c, COEF, &tc);
                if (e == CS_OK)
                    s->m[i][axis] = ta + tc;
            }
            prev = cur;
        }
    }
    return e;
}

/* Forward elimination: piv_i = 2 - a_i c_i-1 / piv_i-1, d_i -= a_i d_i-1 / piv_i-1. */
static cs_err_t spline_eliminate(cs_spline_t *s, size_t n)
{
    cs_err_t e = CS_OK;
    s->piv[0] = 2 * COEF;
    int64_t c_prev = COEF;
    for (size_t i = 1; i <= n && e == CS_OK; i++) {
        int64_t a, c, t;
        e = spline_row(s, i, &a, &c);
        if (e == CS_OK)
            e = cs_fixed_muldiv64(a, c_prev, s->piv[i - 1], &t);
        if (e != CS_OK)
            break;
        s->piv[i] = 2 * COEF - t;
        for (unsigned axis = 0; axis < 3 && e == CS_OK; axis++) {
            e = cs_fixed_muldiv64(s->m[i - 1][axis], a, s->piv[i - 1], &t);
            if (e == CS_OK)
                s->m[i][axis] -= t;
        }
        c_prev = c;
    }
    return e;
}

/* Back substitution: m_n = d_n / piv_n, m_i = (d_i - c_i m_i+1) / piv_i. */
static cs_err_t spline_back(cs_spline_t *s, size_t n)
{
    cs_err_t e = CS_OK;
    for (unsigned axis = 0; axis < 3 && e == CS_OK; axis++) {
        e = cs_fixed_muldiv64(s->m[n][axis], COEF, s->piv[n], &s->m[n][axis]);
        for (size_t k = n; k-- > 0 && e == CS_OK;) {
            int64_t a, c, t;
            e = spline_row(s, k, &a, &c);
            if (e == CS_OK)
                e = cs_fixed_muldiv64(s->m[k + 1][axis], c, COEF, &t);
            if (e == CS_OK)
                e = cs_fixed_muldiv64(s->m[k][axis] - t, COEF, s->piv[k], &s->m[k][axis]);
        }
    }
    return e;
}

cs_err_t cs_spline_solve(cs_spline_t *s, const cs_vec3_t *pts, size_t count,
                         cs_spline_param_t param)
{
    if (s == NULL || pts == NULL)
        return CS_ERR_ARG;
    if (param != CS_SPLINE_UNIFORM && param != CS_SPLINE_CHORD)
        return CS_ERR_ARG;
    s->count = 0;
    if (count < 2)
        return CS_ERR_DEGENERATE;
    if (count > CS_SPLINE_MAX_POINTS)
        return CS_ERR_FULL;
    for (size_t i = 0; i < count; i++)
        if (!cs_fixed_vec_ok(&pts[i]))
            return CS_ERR_RANGE;
    s->pts = pts;
    s->count = count;
    s->param = param;
    cs_err_t e = spline_spans(s);
    if (e == CS_OK)
        e = spline_rhs(s, count - 1);
    if (e == CS_OK)
        e = spline_eliminate(s, count - 1);
    if (e == CS_OK)
        e = spline_back(s, count - 1);
    if (e != CS_OK)
        s->count = 0; /* degenerate span, or (never within the stated bounds) an overflow */
    return e;
}

size_t cs_spline_segments(const cs_spline_t *s)
{
    return s != NULL && s->count >= 2 ? s->count - 1 : 0;
}

cs_err_t cs_spline_segment(const cs_spline_t *s, size_t index, cs_bezier_t *out)
{
    if (s == NULL || out == NULL)
        return CS_ERR_ARG;
    if (index >= cs_spline_segments(s))
        return CS_END;
    /* Inner points P_i + h m_i / 3 and P_i+1 - h m_i+1 / 3, h in the slope's own scale. */
    int64_t h = s->param == CS_SPLINE_UNIFORM ? 1 : (int64_t)s->h[index];
    int64_t div = (int64_t)3 << (s->param == CS_SPLINE_UNIFORM ? SLOPE_BITS_UNIFORM
                                                               : SLOPE_BITS_CHORD + H_FRAC_BITS);
    cs_bezier_t b;
    b.p[0] = s->pts[index];
    b.p[3] = s->pts[index + 1];
    int32_t in1[3], in2[3];
    for (unsigned axis = 0; axis < 3; axis++) {
        int64_t t1, t2;
        cs_err_t e = cs_fixed_muldiv64(s->m[index][axis], h, div, &t1);
        if (e == CS_OK)
            e = cs_fixed_muldiv64(s->m[index + 1][axis], h, div, &t2);
        if (e != CS_OK)
            return e;
        int64_t v1 = cs_fixed_vec_get(&s->pts[index], axis) + t1;
        int64_t v2 = cs_fixed_vec_get(&s->pts[index + 1], axis) - t2;
        if (!cs_fixed_pos_ok(v1) || !cs_fixed_pos_ok(v2))
            return CS_ERR_RANGE;
        in1[axis] = (int32_t)v1;
        in2[axis] = (int32_t)v2;
    }
    b.p[1] = cs_fixed_vec(in1[0], in1[1], in1[2]);
    b.p[2] = cs_fixed_vec(in2[0], in2[1], in2[2]);
    for (unsigned i = 0; i < CS_BEZIER_MAX_POINTS; i++) {
        if (i >= 4)
            b.p[i] = cs_fixed_vec(0, 0, 0);
        b.w[i] = CS_WEIGHT_ONE;
    }
    b.degree = 3;
    b.rational = false;
    *out = b;
    return CS_OK;
}

cs_err_t cs_spline_to_bezier(const cs_spline_t *s, cs_bezier_t *out, size_t cap, size_t *n)
{
    if (s == NULL || out == NULL || n == NULL)
        return CS_ERR_ARG;
    size_t segs = cs_spline_segments(s);
    if (segs > cap)
        return CS_ERR_FULL;
    for (size_t i = 0; i < segs; i++) {
        cs_err_t e = cs_spline_segment(s, i, &out[i]);
        if (e != CS_OK)
            return e;
    }
    *n = segs;
    return CS_OK;
}
