/* cs_tripatch: barycentric de Casteljau (seed 000): level r + 1 point (i, j, k) is
 * u b(i+1, j, k) + v b(i, j+1, k) + w b(i, j, k+1). Values carry GUARD = 28 bits (|.| < 2^56,
 * convex combinations never leave the control points' range; the three products are formed
 * separately, each < 2^56); each of the three products is rounded by cs_fixed_mul64_q30 (1/2
 * guard unit each), and the weights sum to exactly 2^30, so n <= 7 levels add at most 10.5
 * guard units: < 2^-24 LSB (it was 4.5 units, 2^-25 LSB, while n <= 3).
 * The blossom runs the same levels with a different barycentric point per level. */
#include "cs_tripatch.h"

#define GUARD 28

CS_STATIC_ASSERT(CS_TRIPATCH_MAX_POINTS == 36, degree_7_has_36_points);

unsigned cs_tripatch_index(unsigned n, unsigned i, unsigned j)
{
    /* Rows i' < i hold n - i' + 1 points each. */
    return i * (n + 1) - (i * (i - 1)) / 2 + j;
}

cs_err_t cs_tripatch_init(cs_tripatch_t *t, unsigned degree, const cs_vec3_t *pts)
{
    if (!t || !pts)
        return CS_ERR_ARG;
    if (degree < 1 || degree > CS_TRIPATCH_MAX_DEGREE)
        return CS_ERR_DEGREE;
    unsigned np = (degree + 1) * (degree + 2) / 2;
    for (unsigned k = 0; k < np; k++)
        if (!cs_fixed_vec_ok(&pts[k]))
            return CS_ERR_RANGE;
    cs_tripatch_t r = {0};
    r.degree = (uint8_t)degree;
    for (unsigned k = 0; k < np; k++)
        r.p[k] = pts[k];
    *t = r;
    return CS_OK;
}

static bool bary_ok(cs_param_t u, cs_param_t v)
{
    return u >= 0 && v >= 0 && (int64_t)u + v <= CS_PARAM_ONE;
}

/* Blossom b(pts[0], ..., pts[n-1]) of axis a, each pts a barycentric (u, v) pair, in guarded
 * units. */
static int64_t blossom(const cs_tripatch_t *t, unsigned a, const cs_param_t (*uv)[2])
{
    unsigned n = t->degree;
    int64_t b[CS_TRIPATCH_MAX_POINTS];
    for (unsigned k = 0; k < (n + 1) * (n + 2) / 2; k++)
        b[k] = (int64_t)cs_fixed_vec_get(&t->p[k], a) * ((int64_t)1 << GUARD);
    for (unsigned r = 0; r < n; r++) {
        unsigned m = n - r; /* current degree */
        cs_param_t u = uv[r][0], v = uv[r][1];
        cs_param_t w = (cs_param_t)(CS_PARAM_ONE - u - v);
        int64_t nb[CS_TRIPATCH_MAX_POINTS];
        for (unsigned i = 0; i + 1 <= m; i++)
            for (unsigned j = 0; i + j + 1 <= m; j++)
                nb[cs_tripatch_index(m - 1, i, j)] =
                    cs_fixed_mul64_q30(b[cs_tripatch_index(m, i + 1, j)], u) +
                    cs_fixed_mul64_q30(b[cs_tripatch_index(m, i, j + 1)], v) +
                    cs_fixed_mul64_q30(b[cs_tripatch_index(m, i, j)], w);
        for (unsigned k = 0; k < m * (m + 1) / 2; k++)
            b[k] = nb[k];
    }
    return b[0];
}

static cs_err_t to_point(const cs_tripatch_t *t, const cs_param_t (*uv)[2], cs_vec3_t *out)
{
    cs_vec3_t r;
    for (unsigned a = 0; a < 3; a++) {
        int32_t c;
        if (cs_fixed_narrow(cs_fixed_round_shift64(blossom(t, a, uv), GUARD), &c) != CS_OK)
            return CS_ERR_OVERFLOW;
        cs_fixed_vec_set(&r, a, c);
    }
    *out = r;
    return CS_OK;
}

cs_err_t cs_tripatch_eval(const cs_tripatch_t *t, cs_param_t u, cs_param_t v, cs_vec3_t *out)
{
    if (!t || !out || !bary_ok(u, v))
        return CS_ERR_ARG;
    if (t->degree < 1 || t->degree > CS_TRIPATCH_MAX_DEGREE)
        return CS_ERR_DEGREE;
    cs_param_t uv[CS_TRIPATCH_MAX_DEGREE][2];
    for (unsigned r = 0; r < t->degree; r++) {
        uv[r][0] = u;
        uv[r][1] = v;
    }
    return to_point(t, (const cs_param_t(*)[2])uv, out);
}

cs_err_t cs_tripatch_line(const cs_tripatch_t *t, cs_param_t ua, cs_param_t va, cs_param_t ub,
                          cs_param_t vb, cs_bezier_t *out)
{
    if (!t || !out || !bary_ok(ua, va) || !bary_ok(ub, vb))
        return CS_ERR_ARG;
    if (t->degree < 1 || t->degree > CS_TRIPATCH_MAX_DEGREE)
        return CS_ERR_DEGREE;
    unsigned n = t->degree;
    cs_bezier_t c = {0};
    c.degree = (uint8_t)n;
    for (unsigned m = 0; m <= n; m++) {
        cs_param_t uv[CS_TRIPATCH_MAX_DEGREE][2];
        for (unsigned r = 0; r < n; r++) {
            uv[r][0] = r < n - m ? ua : ub;
            uv[r][1] = r < n - m ? va : vb;
        }
        cs_err_t e = to_point(t, (const cs_param_t(*)[2])uv, &c.p[m]);
        if (e != CS_OK)
            return e;
        c.w[m] = CS_WEIGHT_ONE;
    }
    *out = c;
    return CS_OK;
}
