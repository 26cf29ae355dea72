/* cs_nurbs: Bézier extraction of a B-spline / NURBS, one knot span at a time.
 *
 * Inserting the knots k_j and k_{j+1} until each has multiplicity p (Boehm) turns the p+1
 * control points P_{j-p}..P_j that act on span [k_j, k_{j+1}) into the span's Bézier points.
 * Done locally, Bézier point i is the blossom f(k_j^(p-i), k_{j+1}^i) (Ramshaw): the de Boor
 * triangle with argument u_l at level l,
 *   d_r^l = ((k_{r+p-l+1} - u_l) d_{r-1}^(l-1) + (u_l - k_r) d_r^(l-1)) / (k_{r+p-l+1} - k_r),
 * which is exactly the sequence of affine combinations Boehm's insertion performs (Piegl &
 * Tiller A5.1 / A5.6). Every denominator is > 0 inside a non-empty span (k_r <= k_j < k_{j+1} <=
 * k_{r+p-l+1}), and every step is a convex combination (0 <= u_l - k_r <= denominator).
 *
 * Arithmetic: homogeneous points (w x, w y, w z, w) in int64, with the span's largest weight
 * scaled to [2^30, 2^31) (polynomial curves use w = 2^30), so w x < 2^59; each combination is
 * d_{r-1} + (d_r - d_{r-1}) (u - k_r) / den with a 128-bit intermediate (cs_fixed_muldiv64), a
 * rounding of 2^-31 relative at most. One final rounding to cs_pos_t gives <= 0.5 LSB. */
#include "cs_nurbs.h"

#define NURBS_W_SHIFT 30

CS_STATIC_ASSERT(CS_NURBS_MAX_DEGREE + 1 <= CS_BEZIER_MAX_POINTS, nurbs_degree_fits_bezier);

cs_err_t cs_nurbs_init(cs_nurbs_t *c, unsigned degree, const cs_vec3_t *pts, const int32_t *weights,
                       size_t count, const cs_nurbs_knot_t *knots, size_t n_knots)
{
    if (c == NULL || pts == NULL || knots == NULL)
        return CS_ERR_ARG;
    if (degree < 1 || degree > CS_NURBS_MAX_DEGREE)
        return CS_ERR_DEGREE;
    if (count < degree + 1 || n_knots != count + degree + 1)
        return CS_ERR_KNOTS;
    size_t run = 1;
    for (size_t i = 1; i < n_knots; i++) {
        if (knots[i] < knots[i - 1])
            return CS_ERR_KNOTS;
        run = knots[i] == knots[i - 1] ? run + 1 : 1;
        if (run > degree + 1)
            return CS_ERR_KNOTS;
    }
    if (knots[degree] >= knots[count]) /* empty domain [k_p, k_n+1] */
        return CS_ERR_KNOTS;
    for (size_t i = 0; i < count; i++) {
        if (!cs_fixed_vec_ok(&pts[i]))
            return CS_ERR_RANGE;
        if (weights != NULL && weights[i] <= 0)
            return CS_ERR_WEIGHT;
    }
    c->degree = degree;
    c->count = count;
    c->pts = pts;
    c->weights = weights;
    c->knots = knots;
    return CS_OK;
}

size_t cs_nurbs_segments(const cs_nurbs_t *c)
{
    size_t n = 0;
    if (c == NULL)
        return 0;
    for (size_t j = c->degree; j < c->count; j++)
        if (c->knots[j] < c->knots[j + 1])
            n++;
    return n;
}

void cs_nurbs_iter_begin(const cs_nurbs_t *c, cs_nurbs_iter_t *it)
{
    if (it != NULL)
        it->span = c != NULL ? c->degree : 0;
}

/* Bézier segment of the non-empty span j (degree <= j < count). */
static cs_err_t nurbs_span(const cs_nurbs_t *c, size_t j, cs_bezier_t *out)
{
    const unsigned p = c->degree;
    const cs_nurbs_knot_t *k = c->knots;
    /* Scale this span's weights so the largest is in [2^30, 2^31): ratios are kept exactly. */
    unsigned shift = NURBS_W_SHIFT;
    if (c->weights != NULL) {
        int32_t wmax = 0;
        for (unsigned r = 0; r <= p; r++)
            if (c->weights[j - p + r] > wmax)
                wmax = c->weights[j - p + r];
        shift = 0;
        while (((int64_t)wmax << shift) < ((int64_t)1 << NURBS_W_SHIFT))
            shift++;
    }
    int64_t hw[CS_NURBS_MAX_DEGREE + 1][4]; /* homogeneous Bézier points */
    for (unsigned i = 0; i <= p; i++) {
        int64_t d[CS_NURBS_MAX_DEGREE + 1][4];
        for (unsigned r = 0; r <= p; r++) {
            size_t idx = j - p + r;
            int64_t w = (int64_t)(c->weights != NULL ? c->weights[idx] : 1) << shift;
            for (unsigned axis = 0; axis < 3; axis++)
                d[r][axis] = w * cs_fixed_vec_get(&c->pts[idx], axis); /* |.| < 2^59 */
            d[r][3] = w;
        }
        /* Blossom f(k_j^(p-i), k_{j+1}^i): the first p-i levels insert k_j, the rest k_{j+1}. */
        for (unsigned l = 1; l <= p; l++) {
            int64_t u = l <= p - i ? k[j] : k[j + 1];
            for (unsigned r = p; r >= l; r--) {
                size_t idx = j - p + r;
                int64_t num = u - k[idx], den = (int64_t)k[idx + p - l + 1] - k[idx];
                for (unsigned a = 0; a < 4; a++) {
                    int64_t delta;
                    cs_err_t e = cs_fixed_muldiv64(d[r][a] - d[r - 1][a], num, den, &delta);
                    if (e != CS_OK)
                        return e; /* cannot happen: |num| <= den, |diff| < 2^60 */
                    d[r][a] = d[r - 1][a] + delta;
                }
            }
        }
        for (unsigned a = 0; a < 4; a++)
            hw[i][a] = d[p][a];
    }
    cs_bezier_t b;
    int64_t wmax = 0;
    for (unsigned i = 0; i <= p; i++) {
        if (hw[i][3] <= 0)
            return CS_ERR_WEIGHT; /* a weight ratio beyond 2^30 rounded away */
        if (hw[i][3] > wmax)
            wmax = hw[i][3];
    }
    bool rational = false;
    for (unsigned i = 0; i <= p; i++) {
        int64_t xyz[3], w;
        for (unsigned axis = 0; axis < 3; axis++) {
            cs_err_t e = cs_fixed_muldiv64(hw[i][axis], 1, hw[i][3], &xyz[axis]);
            if (e != CS_OK)
                return e;
            if (!cs_fixed_pos_ok(xyz[axis]))
                return CS_ERR_RANGE;
        }
        cs_err_t e = cs_fixed_muldiv64(hw[i][3], CS_WEIGHT_ONE, wmax, &w);
        if (e != CS_OK)
            return e;
        if (w < CS_WEIGHT_MIN)
            return CS_ERR_WEIGHT;
        if (w != CS_WEIGHT_ONE)
            rational = true;
        b.p[i] = cs_fixed_vec((cs_pos_t)xyz[0], (cs_pos_t)xyz[1], (cs_pos_t)xyz[2]);
        b.w[i] = (cs_weight_t)w;
    }
    for (unsigned i = p + 1; i < CS_BEZIER_MAX_POINTS; i++) {
        b.p[i] = cs_fixed_vec(0, 0, 0);
        b.w[i] = CS_WEIGHT_ONE;
    }
    b.degree = (uint8_t)p;
    b.rational = rational;
    *out = b;
    return CS_OK;
}

cs_err_t cs_nurbs_next(const cs_nurbs_t *c, cs_nurbs_iter_t *it, cs_bezier_t *out,
                       cs_nurbs_knot_t *u0, cs_nurbs_knot_t *u1)
{
    if (c == NULL || it == NULL || out == NULL)
        return CS_ERR_ARG;
    size_t j = it->span < c->degree ? c->degree : it->span;
    while (j < c->count && c->knots[j] == c->knots[j + 1])
        j++;
    if (j >= c->count) {
        it->span = j;
        return CS_END;
    }
    cs_err_t e = nurbs_span(c, j, out);
    if (e != CS_OK)
        return e;
    if (u0 != NULL)
        *u0 = c->knots[j];
    if (u1 != NULL)
        *u1 = c->knots[j + 1];
    it->span = j + 1;
    return CS_OK;
}

cs_err_t cs_nurbs_to_bezier(const cs_nurbs_t *c, cs_bezier_t *out, size_t cap, size_t *n)
{
    if (c == NULL || out == NULL || n == NULL)
        return CS_ERR_ARG;
    if (cs_nurbs_segments(c) > cap)
        return CS_ERR_FULL;
    cs_nurbs_iter_t it;
    cs_nurbs_iter_begin(c, &it);
    size_t i = 0;
    for (;;) {
        cs_bezier_t seg;
        cs_err_t e = cs_nurbs_next(c, &it, &seg, NULL, NULL);
        if (e == CS_END)
            break;
        if (e != CS_OK)
            return e;
        out[i++] = seg;
    }
    *n = i;
    return CS_OK;
}
