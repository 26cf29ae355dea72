/* cs_patch: tensor-product Bézier patches (seed 003 "Surfaces bicubiques": Q(s, t) =
 * S M G M^T T^T; seed 004: Hermite bicubic, B-matrix, 9-way split, normal Pu x Pv), of any
 * degree up to 7 x 7.
 *
 * Precision. Evaluation runs de Casteljau in v on each row, then in u, on int64 values carrying
 * GUARD = 26 guard bits (|coordinate| <= 2^28 LSB, so values < 2^54, differences < 2^55). Each
 * lerp adds at most 1/2 guard unit and convex combinations do not grow earlier errors: after
 * du + dv <= 14 levels a point is within 7 * 2^-26 < 2^-23 LSB before the final rounding. A
 * derivative multiplies a difference of two such values by the degree (Pu, Pv: <= 7 * 2 * 7 *
 * 2^-26 < 2^-19 LSB; Puv: 49 * 4 * 7 * 2^-26 < 2^-15 LSB). The largest intermediate, Puv =
 * du dv (second difference), stays below 2 * 7 * 7 * 2^(GUARD + 29) < 2^62, inside
 * cs_fixed_mul64_q30's domain: GUARD + 29 + log2(2 * 7^2) <= 62 gives GUARD <= 26 (it was 28
 * while patches were at most bicubic: 28 + 29 + log2(2 * 9) < 62).
 *
 * The Hermite path (9-way split) evaluates the exact Bézier form of the Hermite patch scaled by
 * 9 (integer control points 9 b = 9 P + 3 Pu + 3 Pv + Puv) with HGUARD = 22 guard bits
 * (|9 b| <= 16 * 2^28 = 2^32 -> values < 2^54) and divides by 9 * 2^22 once at the end.
 *
 * No recursion; stack is a few 8 x 8 x 3 int64 arrays (<= 2 KiB in cs_patch_continuity). */
#include "cs_patch.h"

#define GUARD  26
#define HGUARD 22
#define NPTS   CS_PATCH_MAX_POINTS

CS_STATIC_ASSERT(CS_PATCH_MAX_DEGREE <= CS_FIXED_BINOM_MAX, binomials_up_to_the_degree);
CS_STATIC_ASSERT(2 * CS_PATCH_MAX_DEGREE * CS_PATCH_MAX_DEGREE < (1 << (62 - GUARD - 29)),
                 twist_below_2_62);
/* Raster: m (shift + 1) + 29 <= 63 at m = 3 and the largest shift (see cs_patch_raster_t). */
CS_STATIC_ASSERT(3 * (CS_PATCH_RASTER_MAX_SHIFT + 1) + 29 <= 63, cubic_raster_full_shift);

typedef int64_t wnet_t[NPTS][NPTS][3];

static bool param_ok(cs_param_t t)
{
    return t >= 0 && t <= CS_PARAM_ONE;
}

static bool degrees_ok(unsigned du, unsigned dv)
{
    return du >= 1 && du <= CS_PATCH_MAX_DEGREE && dv >= 1 && dv <= CS_PATCH_MAX_DEGREE;
}

/* Reduce w[0..n] by de Casteljau at t down to two points w[0], w[1]; returns the point
 * cs_fixed_lerp64(w0, w1, t) and stores the derivative n (w1 - w0) in *d. */
static int64_t decast_pd(int64_t *w, unsigned n, cs_param_t t, int64_t *d)
{
    for (unsigned m = n; m > 1; m--)
        for (unsigned j = 0; j < m; j++)
            w[j] = cs_fixed_lerp64(w[j], w[j + 1], t);
    *d = (int64_t)n * (w[1] - w[0]);
    return cs_fixed_lerp64(w[0], w[1], t);
}

/* P, Pu, Pv, Puv (out[0..3]) of the guarded net at (u, v), in the net's units. */
static void eval_wide(const wnet_t net, unsigned du, unsigned dv, cs_param_t u, cs_param_t v,
                      int64_t out[4][3])
{
    for (unsigned a = 0; a < 3; a++) {
        int64_t r[NPTS], d[NPTS], w[NPTS];
        for (unsigned i = 0; i <= du; i++) {
            for (unsigned j = 0; j <= dv; j++)
                w[j] = net[i][j][a];
            r[i] = decast_pd(w, dv, v, &d[i]);
        }
        out[0][a] = decast_pd(r, du, u, &out[1][a]);
        out[2][a] = decast_pd(d, du, u, &out[3][a]);
    }
}

static void load_net(const cs_patch_t *p, wnet_t net)
{
    for (unsigned i = 0; i <= p->deg_u; i++)
        for (unsigned j = 0; j <= p->deg_v; j++)
            for (unsigned a = 0; a < 3; a++)
                net[i][j][a] = (int64_t)cs_fixed_vec_get(&p->p[i][j], a) * ((int64_t)1 << GUARD);
}

static cs_err_t narrow_vec(const int64_t w[3], unsigned shift, cs_vec3_t *out)
{
    cs_vec3_t r;
    for (unsigned a = 0; a < 3; a++) {
        int32_t c;
        if (cs_fixed_narrow(cs_fixed_round_shift64(w[a], shift), &c) != CS_OK)
            return CS_ERR_OVERFLOW;
        cs_fixed_vec_set(&r, a, c);
    }
    *out = r;
    return CS_OK;
}

cs_err_t cs_patch_init(cs_patch_t *p, unsigned deg_u, unsigned deg_v, const cs_vec3_t *pts)
{
    if (!p || !pts)
        return CS_ERR_ARG;
    if (!degrees_ok(deg_u, deg_v))
        return CS_ERR_DEGREE;
    for (unsigned k = 0; k < (deg_u + 1) * (deg_v + 1); k++)
        if (!cs_fixed_vec_ok(&pts[k]))
            return CS_ERR_RANGE;
    cs_patch_t r = {0};
    r.deg_u = (uint8_t)deg_u;
    r.deg_v = (uint8_t)deg_v;
    for (unsigned i = 0; i <= deg_u; i++)
        for (unsigned j = 0; j <= deg_v; j++)
            r.p[i][j] = pts[i * (deg_v + 1) + j];
    *p = r;
    return CS_OK;
}

static cs_err_t check_patch(const cs_patch_t *p)
{
    if (!p)
        return CS_ERR_ARG;
    if (!degrees_ok(p->deg_u, p->deg_v))
        return CS_ERR_DEGREE;
    return CS_OK;
}

/* What cs_patch_derivs, _eval and _normal share: the checks (out: the caller's output, which
 * must be set), then P, Pu, Pv, Puv of p at (u, v) into w, in GUARD units. */
static cs_err_t eval_checked(const cs_patch_t *p, cs_param_t u, cs_param_t v, const void *out,
                             int64_t w[4][3])
{
    cs_err_t e = check_patch(p);
    if (e != CS_OK)
        return e;
    if (!out || !param_ok(u) || !param_ok(v))
        return CS_ERR_ARG;
    wnet_t net;
    load_net(p, net);
    eval_wide(net, p->deg_u, p->deg_v, u, v, w);
    return CS_OK;
}

cs_err_t cs_patch_derivs(const cs_patch_t *p, cs_param_t u, cs_param_t v, cs_patch_derivs_t *out)
{
    int64_t w[4][3];
    cs_err_t e = eval_checked(p, u, v, out, w);
    if (e != CS_OK)
        return e;
    cs_patch_derivs_t r;
    if (narrow_vec(w[0], GUARD, &r.p) != CS_OK || narrow_vec(w[1], GUARD, &r.pu) != CS_OK ||
        narrow_vec(w[2], GUARD, &r.pv) != CS_OK || narrow_vec(w[3], GUARD, &r.puv) != CS_OK)
        return CS_ERR_OVERFLOW;
    *out = r;
    return CS_OK;
}

cs_err_t cs_patch_eval(const cs_patch_t *p, cs_param_t u, cs_param_t v, cs_vec3_t *out)
{
    int64_t w[4][3];
    cs_err_t e = eval_checked(p, u, v, out, w);
    if (e != CS_OK)
        return e;
    return narrow_vec(w[0], GUARD, out);
}

/* --- normal ------------------------------------------------------------------------------- */

static uint64_t mag64(int64_t x)
{
    return x < 0 ? (uint64_t)0 - (uint64_t)x : (uint64_t)x;
}

static uint64_t maxabs3(const int64_t v[3])
{
    uint64_t m = mag64(v[0]);
    if (mag64(v[1]) > m)
        m = mag64(v[1]);
    if (mag64(v[2]) > m)
        m = mag64(v[2]);
    return m;
}

/* Scale v by a power of two (rounding when shrinking) so that its largest component lies in
 * [2^(bits-1), 2^bits); false for the zero vector. Only the direction matters to the callers. */
static bool scale_dir(const int64_t v[3], unsigned bits, int64_t out[3])
{
    uint64_t m = maxabs3(v);
    if (m == 0)
        return false;
    unsigned up = 0, down = 0;
    while ((m >> down) >= ((uint64_t)1 << bits))
        down++;
    while ((m << up) < ((uint64_t)1 << (bits - 1)))
        up++;
    for (unsigned a = 0; a < 3; a++)
        out[a] = down ? cs_fixed_round_shift64(v[a], down) : v[a] * ((int64_t)1 << up);
    return true;
}

static void cross(const int64_t a[3], const int64_t b[3], int64_t c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* Unit (a x b) into *n: CS_ERR_DEGENERATE when a or b is zero or the sine of their angle is
 * below about 2^-23 (|a'| |b'| >= 2^58 after scaling, |a' x b'| < 2^35). */
static cs_err_t unit_cross(const int64_t a[3], const int64_t b[3], cs_patch_unit_t *n)
{
    int64_t sa[3], sb[3], c[3];
    if (!scale_dir(a, 30, sa) || !scale_dir(b, 30, sb))
        return CS_ERR_DEGENERATE;
    cross(sa, sb, c); /* each product < 2^60, each component < 2^61 */
    uint64_t len = cs_fixed_vec_len64(c[0], c[1], c[2]);
    if (len < ((uint64_t)1 << 35))
        return CS_ERR_DEGENERATE;
    int64_t q[3];
    for (unsigned k = 0; k < 3; k++)
        if (cs_fixed_muldiv64(c[k], CS_PARAM_ONE, (int64_t)len, &q[k]) != CS_OK)
            return CS_ERR_OVERFLOW;
    /* |q| <= 2^30 (1 + 3 * 2^-30): clamp the rounding excess of a unit component. */
    for (unsigned k = 0; k < 3; k++) {
        if (q[k] > CS_PARAM_ONE)
            q[k] = CS_PARAM_ONE;
        if (q[k] < -CS_PARAM_ONE)
            q[k] = -CS_PARAM_ONE;
    }
    n->x = (int32_t)q[0];
    n->y = (int32_t)q[1];
    n->z = (int32_t)q[2];
    return CS_OK;
}

cs_err_t cs_patch_normal(const cs_patch_t *p, cs_param_t u, cs_param_t v, cs_patch_unit_t *n)
{
    int64_t w[4][3];
    cs_err_t e = eval_checked(p, u, v, n, w);
    if (e != CS_OK)
        return e;
    e = unit_cross(w[1], w[2], n);
    if (e != CS_ERR_DEGENERATE)
        return e;
    /* Limit from inside the patch (seed 004's normal is undefined at a collapsed edge): on
     * v = v0 with Pu = 0, Pu(u, v) = (v - v0) Puv + O((v - v0)^2), so the normal's direction
     * tends to sign(v - v0) Puv x Pv; likewise on u = u0 with Pv = 0. */
    uint64_t mu = maxabs3(w[1]), mv = maxabs3(w[2]);
    int64_t t[3];
    if ((v == 0 || v == CS_PARAM_ONE) && mu <= mv) {
        for (unsigned a = 0; a < 3; a++)
            t[a] = v == 0 ? w[3][a] : -w[3][a];
        return unit_cross(t, w[2], n);
    }
    if ((u == 0 || u == CS_PARAM_ONE) && mv <= mu) {
        for (unsigned a = 0; a < 3; a++)
            t[a] = u == 0 ? w[3][a] : -w[3][a];
        return unit_cross(w[1], t, n);
    }
    return CS_ERR_DEGENERATE;
}

/* --- splits and iso-curves ---------------------------------------------------------------- */

/* Row (dir ISO_V: fixed i = idx, points along v) or column (ISO_U: fixed j = idx, along u)
 * of the net as a curve. */
static void net_line(const cs_patch_t *p, cs_patch_iso_t along, unsigned idx, cs_bezier_t *c)
{
    unsigned n = along == CS_PATCH_ISO_U ? p->deg_u : p->deg_v;
    c->degree = (uint8_t)n;
    c->rational = false;
    for (unsigned k = 0; k <= n; k++) {
        c->p[k] = along == CS_PATCH_ISO_U ? p->p[k][idx] : p->p[idx][k];
        c->w[k] = CS_WEIGHT_ONE;
    }
}

static cs_err_t split_dir(const cs_patch_t *p, cs_patch_iso_t along, cs_param_t t, cs_patch_t *lo,
                          cs_patch_t *hi)
{
    cs_err_t e = check_patch(p);
    if (e != CS_OK)
        return e;
    if (t <= 0 || t >= CS_PARAM_ONE || (lo && lo == hi))
        return CS_ERR_ARG;
    cs_patch_t l = *p, h = *p;
    unsigned lines = along == CS_PATCH_ISO_U ? p->deg_v : p->deg_u;
    for (unsigned idx = 0; idx <= lines; idx++) {
        cs_bezier_t c, cl, ch;
        net_line(p, along, idx, &c);
        e = cs_bezier_split(&c, t, &cl, &ch);
        if (e != CS_OK)
            return e;
        for (unsigned k = 0; k <= c.degree; k++) {
            if (along == CS_PATCH_ISO_U) {
                l.p[k][idx] = cl.p[k];
                h.p[k][idx] = ch.p[k];
            } else {
                l.p[idx][k] = cl.p[k];
                h.p[idx][k] = ch.p[k];
            }
        }
    }
    if (lo)
        *lo = l;
    if (hi)
        *hi = h;
    return CS_OK;
}

cs_err_t cs_patch_split_u(const cs_patch_t *p, cs_param_t u, cs_patch_t *lo, cs_patch_t *hi)
{
    return split_dir(p, CS_PATCH_ISO_U, u, lo, hi);
}

cs_err_t cs_patch_split_v(const cs_patch_t *p, cs_param_t v, cs_patch_t *lo, cs_patch_t *hi)
{
    return split_dir(p, CS_PATCH_ISO_V, v, lo, hi);
}

cs_err_t cs_patch_iso(const cs_patch_t *p, cs_patch_iso_t dir, cs_param_t t, cs_bezier_t *out)
{
    cs_err_t e = check_patch(p);
    if (e != CS_OK)
        return e;
    if (!out || !param_ok(t) || (dir != CS_PATCH_ISO_U && dir != CS_PATCH_ISO_V))
        return CS_ERR_ARG;
    /* The iso-curve along u at v = t has control points c_i = column i's curve in v at t. */
    cs_patch_iso_t other = dir == CS_PATCH_ISO_U ? CS_PATCH_ISO_V : CS_PATCH_ISO_U;
    unsigned n = dir == CS_PATCH_ISO_U ? p->deg_u : p->deg_v;
    cs_bezier_t r = {0};
    r.degree = (uint8_t)n;
    for (unsigned k = 0; k <= n; k++) {
        cs_bezier_t c;
        net_line(p, other, k, &c);
        e = cs_bezier_eval(&c, t, &r.p[k]);
        if (e != CS_OK)
            return e;
        r.w[k] = CS_WEIGHT_ONE;
    }
    *out = r;
    return CS_OK;
}

/* --- raster by forward differences ------------------------------------------------------- */

unsigned cs_patch_raster_max_shift(unsigned m)
{
    if (m == 0)
        return CS_PATCH_RASTER_MAX_SHIFT;
    unsigned s = (34u - m) / m; /* m (s + 1) + 29 <= 63 */
    return s < CS_PATCH_RASTER_MAX_SHIFT ? s : CS_PATCH_RASTER_MAX_SHIFT;
}

/* F(k) = N^m c(k / N) = sum_j C(m, j) k^j (N - k)^(m - j) c_j for one coordinate of the curve
 * c of degree m: an integer polynomial in k. For k <= m <= N each term is below
 * C(m, j) N^m 2^28; for N < m (shift < 3), below C(m, j) m^m 2^28 < 2^(3 m + 28 + m). */
static int64_t raster_value(const cs_bezier_t *c, unsigned a, int64_t big_n, int64_t k)
{
    int64_t s = 0;
    for (unsigned j = 0; j <= c->degree; j++) {
        int64_t b = (int64_t)cs_fixed_binom(c->degree, j);
        for (unsigned q = 0; q < j; q++)
            b *= k;
        for (unsigned q = j; q < c->degree; q++)
            b *= big_n - k;
        s += b * cs_fixed_vec_get(&c->p[j], a);
    }
    return s;
}

cs_err_t cs_patch_raster_begin(cs_patch_raster_t *r, const cs_patch_t *p, cs_patch_iso_t dir,
                               unsigned shift)
{
    cs_err_t e = check_patch(p);
    if (e != CS_OK)
        return e;
    if (!r || (dir != CS_PATCH_ISO_U && dir != CS_PATCH_ISO_V))
        return CS_ERR_ARG;
    cs_patch_iso_t other = dir == CS_PATCH_ISO_U ? CS_PATCH_ISO_V : CS_PATCH_ISO_U;
    unsigned n = dir == CS_PATCH_ISO_U ? p->deg_u : p->deg_v;
    unsigned m = dir == CS_PATCH_ISO_U ? p->deg_v : p->deg_u;
    if (shift > cs_patch_raster_max_shift(m))
        return CS_ERR_ARG;
    int64_t big_n = (int64_t)1 << shift;
    r->degree = (uint8_t)n;
    r->order = (uint8_t)m;
    r->shift = (uint8_t)shift;
    r->k = 0;
    for (unsigned i = 0; i <= n; i++) {
        cs_bezier_t c;
        net_line(p, other, i, &c);
        for (unsigned a = 0; a < 3; a++) {
            /* F(0..m), then its forward differences in place: f[d] = Delta^d F(0). */
            int64_t *f = r->f[i][a];
            for (unsigned k = 0; k <= m; k++)
                f[k] = raster_value(&c, a, big_n, (int64_t)k);
            for (unsigned d = 1; d <= m; d++)
                for (unsigned k = m; k >= d; k--)
                    f[k] -= f[k - 1];
        }
    }
    return CS_OK;
}

cs_err_t cs_patch_raster_next(cs_patch_raster_t *r, cs_bezier_t *out, cs_param_t *t)
{
    if (!r || !out || r->degree < 1 || r->degree > CS_PATCH_MAX_DEGREE ||
        r->order > CS_PATCH_MAX_DEGREE || r->shift > cs_patch_raster_max_shift(r->order))
        return CS_ERR_ARG;
    uint32_t big_n = (uint32_t)1 << r->shift;
    if (r->k > big_n)
        return CS_END;
    cs_bezier_t c = {0};
    c.degree = r->degree;
    for (unsigned i = 0; i <= r->degree; i++) {
        for (unsigned a = 0; a < 3; a++) {
            int32_t v;
            if (cs_fixed_narrow(
                    cs_fixed_round_shift64(r->f[i][a][0], (unsigned)r->order * r->shift), &v) !=
                CS_OK)
                return CS_ERR_OVERFLOW;
            cs_fixed_vec_set(&c.p[i], a, v);
        }
        c.w[i] = CS_WEIGHT_ONE;
    }
    if (t)
        *t = (cs_param_t)((int64_t)r->k << (CS_PARAM_FRAC_BITS - r->shift));
    if (r->k < big_n)
        for (unsigned i = 0; i <= r->degree; i++)
            for (unsigned a = 0; a < 3; a++)
                for (unsigned d = 0; d < r->order; d++)
                    r->f[i][a][d] += r->f[i][a][d + 1];
    r->k++;
    *out = c;
    return CS_OK;
}

/* --- algebraic and Hermite forms ---------------------------------------------------------- */

/* 3 x (power -> Bézier) for a cubic: b_k = sum_i T[k][i] c_i / 3, c_i the coefficient of t^i. */
static const int64_t pow2bez3[4][4] = {{3, 0, 0, 0}, {3, 1, 0, 0}, {3, 2, 1, 0}, {3, 3, 3, 3}};
/* 3 x (Hermite -> Bézier), Hermite order (P0, P1, T0, T1): P0, P0 + T0/3, P1 - T1/3, P1. */
static const int64_t her2bez3[4][4] = {{3, 0, 0, 0}, {3, 0, 1, 0}, {0, 3, 0, -1}, {0, 3, 0, 0}};

/* out[i][j] = 9 b_ij = sum_k sum_l m[i][k] m[j][l] g[k][l] (exact, |g| < 2^31). */
static void tensor9(const int64_t m[4][4], const cs_vec3_t g[4][4], wnet_t out)
{
    for (unsigned i = 0; i < 4; i++)
        for (unsigned j = 0; j < 4; j++)
            for (unsigned a = 0; a < 3; a++) {
                int64_t s = 0;
                for (unsigned k = 0; k < 4; k++)
                    for (unsigned l = 0; l < 4; l++)
                        s += m[i][k] * m[j][l] * cs_fixed_vec_get(&g[k][l], a);
                out[i][j][a] = s;
            }
}

/* Rounded w / d (d > 0) into a cs_pos_t coordinate inside CS_POS_LIMIT. */
static cs_err_t div_pos(int64_t w, int64_t d, cs_pos_t *out)
{
    int64_t q;
    if (cs_fixed_muldiv64(w, 1, d, &q) != CS_OK || !cs_fixed_pos_ok(q))
        return CS_ERR_RANGE;
    *out = (cs_pos_t)q;
    return CS_OK;
}

/* Rounded w / d (d > 0) into any int32 (tangents, twists); CS_ERR_OVERFLOW if it does not fit. */
static cs_err_t div_i32(int64_t w, int64_t d, int32_t *out)
{
    int64_t q;
    if (cs_fixed_muldiv64(w, 1, d, &q) != CS_OK || cs_fixed_narrow(q, out) != CS_OK)
        return CS_ERR_OVERFLOW;
    return CS_OK;
}

static cs_err_t net9_to_patch(const wnet_t n9, cs_patch_t *p)
{
    cs_patch_t r = {0};
    r.deg_u = 3;
    r.deg_v = 3;
    for (unsigned i = 0; i < 4; i++)
        for (unsigned j = 0; j < 4; j++)
            for (unsigned a = 0; a < 3; a++) {
                cs_pos_t c;
                if (div_pos(n9[i][j][a], 9, &c) != CS_OK)
                    return CS_ERR_RANGE;
                cs_fixed_vec_set(&r.p[i][j], a, c);
            }
    *p = r;
    return CS_OK;
}

cs_err_t cs_patch_from_power(cs_patch_t *p, const cs_vec3_t a[4][4])
{
    if (!p || !a)
        return CS_ERR_ARG;
    wnet_t n9;
    tensor9(pow2bez3, a, n9);
    return net9_to_patch(n9, p);
}

/* Mortenson's B matrix: rows (P(0,.), P(1,.), Pu(0,.), Pu(1,.)), columns (v=0, v=1, d/dv at 0,
 * d/dv at 1). */
static void hermite_b(const cs_patch_hermite_t *h, cs_vec3_t g[4][4])
{
    for (unsigned a = 0; a < 2; a++) {
        for (unsigned b = 0; b < 2; b++) {
            g[a][b] = h->p[a][b];
            g[a][2 + b] = h->pv[a][b];
            g[2 + a][b] = h->pu[a][b];
            g[2 + a][2 + b] = h->puv[a][b];
        }
    }
}

cs_err_t cs_patch_from_hermite(cs_patch_t *p, const cs_patch_hermite_t *h)
{
    if (!p || !h)
        return CS_ERR_ARG;
    cs_vec3_t g[4][4];
    wnet_t n9;
    hermite_b(h, g);
    tensor9(her2bez3, g, n9);
    return net9_to_patch(n9, p);
}

cs_err_t cs_patch_to_hermite(const cs_patch_t *p, cs_patch_hermite_t *h)
{
    cs_err_t e = check_patch(p);
    if (e != CS_OK)
        return e;
    if (!h)
        return CS_ERR_ARG;
    if (p->deg_u != 3 || p->deg_v != 3)
        return CS_ERR_DEGREE;
    cs_patch_hermite_t r;
    for (unsigned ca = 0; ca < 2; ca++) {
        for (unsigned cb = 0; cb < 2; cb++) {
            /* Corner (i0, j0) of the net and the neighbours inward (i1, j1); the derivative
             * at the corner is 3 (outer - inner) oriented along +u / +v. */
            unsigned i0 = 3 * ca, j0 = 3 * cb, i1 = ca ? 2 : 1, j1 = cb ? 2 : 1;
            int64_t su = ca ? 1 : -1, sv = cb ? 1 : -1;
            r.p[ca][cb] = p->p[i0][j0];
            for (unsigned a = 0; a < 3; a++) {
                int64_t c00 = cs_fixed_vec_get(&p->p[i0][j0], a), c10 = cs_fixed_vec_get(&p->p[i1][j0], a);
                int64_t c01 = cs_fixed_vec_get(&p->p[i0][j1], a), c11 = cs_fixed_vec_get(&p->p[i1][j1], a);
                int32_t vu, vv, vuv;
                if (cs_fixed_narrow(3 * su * (c00 - c10), &vu) != CS_OK ||
                    cs_fixed_narrow(3 * sv * (c00 - c01), &vv) != CS_OK ||
                    cs_fixed_narrow(9 * su * sv * (c00 - c10 - c01 + c11), &vuv) != CS_OK)
                    return CS_ERR_OVERFLOW;
                cs_fixed_vec_set(&r.pu[ca][cb], a, vu);
                cs_fixed_vec_set(&r.pv[ca][cb], a, vv);
                cs_fixed_vec_set(&r.puv[ca][cb], a, vuv);
            }
        }
    }
    *h = r;
    return CS_OK;
}

cs_err_t cs_patch_hermite_split9(const cs_patch_hermite_t *h, const cs_param_t us[2],
                                 const cs_param_t vs[2], cs_patch_hermite_t out[3][3])
{
    if (!h || !us || !vs || !out)
        return CS_ERR_ARG;
    if (us[0] <= 0 || us[0] >= us[1] || us[1] >= CS_PARAM_ONE || vs[0] <= 0 || vs[0] >= vs[1] ||
        vs[1] >= CS_PARAM_ONE)
        return CS_ERR_ARG;
    cs_vec3_t g[4][4];
    hermite_b(h, g);
    for (unsigned k = 0; k < 4; k++)
        for (unsigned l = 0; l < 4; l++)
            if (!cs_fixed_vec_ok(&g[k][l]))
                return CS_ERR_RANGE;
    wnet_t n9;
    tensor9(her2bez3, g, n9);
    for (unsigned i = 0; i < 4; i++)
        for (unsigned j = 0; j < 4; j++)
            for (unsigned a = 0; a < 3; a++)
                n9[i][j][a] *= (int64_t)1 << HGUARD;
    const cs_param_t ub[4] = {0, us[0], us[1], CS_PARAM_ONE};
    const cs_param_t vb[4] = {0, vs[0], vs[1], CS_PARAM_ONE};
    const int64_t den = (int64_t)9 << HGUARD;
    /* P, Pu, Pv, Puv at the 16 grid points, still scaled by 9 * 2^HGUARD. */
    int64_t grid[4][4][4][3];
    for (unsigned a = 0; a < 4; a++)
        for (unsigned b = 0; b < 4; b++)
            eval_wide(n9, 3, 3, ub[a], vb[b], grid[a][b]);
    for (unsigned a = 0; a < 3; a++) {
        for (unsigned b = 0; b < 3; b++) {
            cs_param_t lu = ub[a + 1] - ub[a], lv = vb[b + 1] - vb[b];
            cs_patch_hermite_t q;
            for (unsigned ca = 0; ca < 2; ca++) {
                for (unsigned cb = 0; cb < 2; cb++) {
                    const int64_t(*w)[3] = grid[a + ca][b + cb];
                    for (unsigned x = 0; x < 3; x++) {
                        int32_t vp, vu, vv, vuv;
                        int64_t tu = cs_fixed_mul64_q30(w[1][x], lu);
                        int64_t tv = cs_fixed_mul64_q30(w[2][x], lv);
                        int64_t tuv = cs_fixed_mul64_q30(cs_fixed_mul64_q30(w[3][x], lu), lv);
                        if (div_pos(w[0][x], den, &vp) != CS_OK)
                            return CS_ERR_RANGE;
                        if (div_i32(tu, den, &vu) != CS_OK || div_i32(tv, den, &vv) != CS_OK ||
                            div_i32(tuv, den, &vuv) != CS_OK)
                            return CS_ERR_OVERFLOW;
                        cs_fixed_vec_set(&q.p[ca][cb], x, vp);
                        cs_fixed_vec_set(&q.pu[ca][cb], x, vu);
                        cs_fixed_vec_set(&q.pv[ca][cb], x, vv);
                        cs_fixed_vec_set(&q.puv[ca][cb], x, vuv);
                    }
                }
            }
            out[a][b] = q;
        }
    }
    return CS_OK;
}

cs_err_t cs_patch_transpose(const cs_patch_t *p, cs_patch_t *out)
{
    cs_err_t e = check_patch(p);
    if (e != CS_OK)
        return e;
    if (!out)
        return CS_ERR_ARG;
    cs_patch_t r = {0};
    r.deg_u = p->deg_v;
    r.deg_v = p->deg_u;
    for (unsigned i = 0; i <= p->deg_u; i++)
        for (unsigned j = 0; j <= p->deg_v; j++)
            r.p[j][i] = p->p[i][j];
    *out = r;
    return CS_OK;
}

/* --- continuity --------------------------------------------------------------------------- */

static bool close_vec(const cs_vec3_t *a, const cs_vec3_t *b, int64_t tol)
{
    for (unsigned k = 0; k < 3; k++) {
        int64_t d = (int64_t)cs_fixed_vec_get(a, k) - cs_fixed_vec_get(b, k);
        if (d > tol || d < -tol)
            return false;
    }
    return true;
}

/* Exact cross-boundary derivative control vector n (p[n][j] - p[n-1][j]) (a's far edge) or
 * n (p[1][j] - p[0][j]) (b's near edge). */
static cs_vec3_t cross_ctrl(const cs_patch_t *p, unsigned j, bool far, bool *ok)
{
    unsigned n = p->deg_u;
    const cs_vec3_t *hi = far ? &p->p[n][j] : &p->p[1][j];
    const cs_vec3_t *lo = far ? &p->p[n - 1][j] : &p->p[0][j];
    cs_vec3_t r = {0, 0, 0};
    for (unsigned a = 0; a < 3; a++) {
        int32_t v;
        if (cs_fixed_narrow((int64_t)n * ((int64_t)cs_fixed_vec_get(hi, a) - cs_fixed_vec_get(lo, a)), &v) != CS_OK)
            *ok = false;
        else
            cs_fixed_vec_set(&r, a, v);
    }
    return r;
}

/* Second cross-boundary derivative control vector of column j, n (n - 1) (P_n - 2 P_(n-1) +
 * P_(n-2)) at a's far edge (far) or n (n - 1) (P_0 - 2 P_1 + P_2) at b's near edge, axis a:
 * exact (|.| < 42 * 4 * 2^28 < 2^36). */
static int64_t second_ctrl(const cs_patch_t *p, unsigned j, bool far, unsigned a)
{
    unsigned n = p->deg_u;
    if (n < 2)
        return 0;
    const cs_vec3_t *e = far ? &p->p[n][j] : &p->p[0][j];
    const cs_vec3_t *m = far ? &p->p[n - 1][j] : &p->p[1][j];
    const cs_vec3_t *f = far ? &p->p[n - 2][j] : &p->p[2][j];
    return (int64_t)n * (n - 1) * ((int64_t)cs_fixed_vec_get(e, a) - 2 * (int64_t)cs_fixed_vec_get(m, a) + cs_fixed_vec_get(f, a));
}

/* The second cross-boundary derivatives of a (u = 1) and b (u = 0) agree within tol. */
static bool second_agree(const cs_patch_t *a, const cs_patch_t *b, int64_t tol)
{
    for (unsigned j = 0; j <= a->deg_v; j++)
        for (unsigned x = 0; x < 3; x++) {
            int64_t d = second_ctrl(a, j, true, x) - second_ctrl(b, j, false, x);
            if (d > tol || d < -tol)
                return false;
        }
    return true;
}

cs_err_t cs_patch_continuity(const cs_patch_t *a, const cs_patch_t *b, cs_pos_t tol,
                             cs_param_t sin_tol, cs_patch_cont_t *out)
{
    cs_err_t e = check_patch(a);
    if (e == CS_OK)
        e = check_patch(b);
    if (e != CS_OK)
        return e;
    if (!out || tol < 0 || sin_tol < 0)
        return CS_ERR_ARG;
    if (a->deg_v != b->deg_v)
        return CS_ERR_DEGREE;
    unsigned dv = a->deg_v;
    *out = CS_PATCH_CONT_NONE;
    for (unsigned j = 0; j <= dv; j++)
        if (!close_vec(&a->p[a->deg_u][j], &b->p[0][j], tol))
            return CS_OK;
    *out = CS_PATCH_CONT_C0;
    bool ok = true, c1 = true;
    for (unsigned j = 0; j <= dv; j++) {
        cs_vec3_t da = cross_ctrl(a, j, true, &ok), db = cross_ctrl(b, j, false, &ok);
        if (!close_vec(&da, &db, tol))
            c1 = false;
    }
    if (ok && c1) {
        *out = second_agree(a, b, tol) ? CS_PATCH_CONT_C2 : CS_PATCH_CONT_C1;
        return CS_OK;
    }
    /* G1: Pu_a(1, v), Pu_b(0, v) and the edge tangent Pv coplanar, the two Pu on the same side
     * of the edge, at 3 dv + 1 parameters (exact test of a degree 3 dv - 1 polynomial). */
    wnet_t na, nb;
    load_net(a, na);
    load_net(b, nb);
    unsigned samples = 3 * dv + 1;
    for (unsigned s = 0; s < samples; s++) {
        cs_param_t v = (cs_param_t)(((int64_t)CS_PARAM_ONE * s) / (samples - 1));
        int64_t wa[4][3], wb[4][3], xa[3], xb[3], xv[3], c[3];
        eval_wide(na, a->deg_u, dv, CS_PARAM_ONE, v, wa);
        eval_wide(nb, b->deg_u, dv, 0, v, wb);
        if (!scale_dir(wa[2], 19, xv))
            continue; /* collapsed edge point: any tangent plane contains a zero tangent */
        if (!scale_dir(wa[1], 19, xa) || !scale_dir(wb[1], 19, xb))
            return CS_OK; /* a vanishing cross derivative: no tangent plane to compare */
        /* All components < 2^19: the triple product is below 6 * 2^57. */
        cross(xa, xv, c);
        int64_t det = c[0] * xb[0] + c[1] * xb[1] + c[2] * xb[2];
        uint64_t la = cs_fixed_vec_len64(xa[0], xa[1], xa[2]);
        uint64_t lb = cs_fixed_vec_len64(xb[0], xb[1], xb[2]);
        uint64_t lv = cs_fixed_vec_len64(xv[0], xv[1], xv[2]);
        /* |det| <= sin_tol |a| |b| |v|: compare |det| 2^30 with sin_tol (|a| |v|) |b| exactly. */
        if (cs_fixed_cmp_prod_u64(mag64(det), (uint64_t)1 << 30, (uint64_t)sin_tol * la, lv * lb) >
            0)
            return CS_OK;
        /* Same side: the normals (Pu_a x Pv) and (Pu_b x Pv) point the same way. */
        int64_t cb[3];
        cross(xb, xv, cb);
        int64_t sgn = 0;
        for (unsigned k = 0; k < 3; k++)
            sgn += (c[k] >> 12) * (cb[k] >> 12); /* < 2^54 each */
        if (sgn <= 0)
            return CS_OK;
    }
    *out = CS_PATCH_CONT_G1;
    return CS_OK;
}
