/* cs_coons: Coons, ruled and extruded patches as exact Bézier nets (seed 000).
 *
 * Every boundary curve is first elevated to degree 3 with its points scaled by 3 so the
 * elevation is exact in integers (line a, b -> 3a, 2a + b, a + 2b, 3b; quadratic a, b, c ->
 * 3a, a + 2b, 2b + c, 3c). In the Bernstein basis the linear blend (1 - v) = B0 + 2/3 B1 +
 * 1/3 B2 and the Hermite blends h0 = B0 + B1, h1 = B2 + B3, h2 = B1 / 3, h3 = -B2 / 3, so
 * 9 x (every control point of S1 + S2 - S3) is an integer combination of the inputs, computed
 * exactly in int64 (|inputs| < 2^31, weights < 2^7) and divided by 9 once. */
#include "cs_coons.h"

#include <stddef.h>

typedef int64_t e3_t[4][3]; /* 3 x the control points of a curve elevated to degree 3 */

static cs_err_t check_curve(const cs_bezier_t *c, bool in_range)
{
    if (!c)
        return CS_ERR_ARG;
    if (c->rational)
        return CS_ERR_UNSUPPORTED;
    if (c->degree < 1 || c->degree > 3)
        return CS_ERR_DEGREE;
    if (in_range)
        for (unsigned i = 0; i <= c->degree; i++)
            if (!cs_fixed_vec_ok(&c->p[i]))
                return CS_ERR_RANGE;
    return CS_OK;
}

static void elev3x(const cs_bezier_t *c, e3_t out)
{
    for (unsigned a = 0; a < 3; a++) {
        int64_t p0 = cs_fixed_vec_get(&c->p[0], a), p1 = cs_fixed_vec_get(&c->p[1], a);
        if (c->degree == 1) {
            out[0][a] = 3 * p0;
            out[1][a] = 2 * p0 + p1;
            out[2][a] = p0 + 2 * p1;
            out[3][a] = 3 * p1;
        } else if (c->degree == 2) {
            int64_t p2 = cs_fixed_vec_get(&c->p[2], a);
            out[0][a] = 3 * p0;
            out[1][a] = p0 + 2 * p1;
            out[2][a] = 2 * p1 + p2;
            out[3][a] = 3 * p2;
        } else {
            for (unsigned i = 0; i < 4; i++)
                out[i][a] = 3 * (int64_t)cs_fixed_vec_get(&c->p[i], a);
        }
    }
}

static bool same(const cs_vec3_t *a, const cs_vec3_t *b)
{
    return a->x == b->x && a->y == b->y && a->z == b->z;
}

static cs_err_t check_boundary(const cs_bezier_t *p1, const cs_bezier_t *p2, const cs_bezier_t *q1,
                               const cs_bezier_t *q2)
{
    cs_err_t e = check_curve(p1, true);
    if (e == CS_OK)
        e = check_curve(p2, true);
    if (e == CS_OK)
        e = check_curve(q1, true);
    if (e == CS_OK)
        e = check_curve(q2, true);
    if (e != CS_OK)
        return e;
    if (!same(&p1->p[0], &q1->p[0]) || !same(&p1->p[p1->degree], &q2->p[0]) ||
        !same(&p2->p[p2->degree], &q2->p[q2->degree]) || !same(&p2->p[0], &q1->p[q1->degree]))
        return CS_ERR_DEGENERATE;
    return CS_OK;
}

/* net9 / 9, each rounded once, into out (bicubic). */
static cs_err_t finish9(const int64_t net9[4][4][3], cs_patch_t *out)
{
    cs_patch_t r = {0};
    r.deg_u = 3;
    r.deg_v = 3;
    for (unsigned i = 0; i < 4; i++)
        for (unsigned j = 0; j < 4; j++)
            for (unsigned a = 0; a < 3; a++) {
                int64_t q;
                if (cs_fixed_muldiv64(net9[i][j][a], 1, 9, &q) != CS_OK || !cs_fixed_pos_ok(q))
                    return CS_ERR_RANGE;
                cs_fixed_vec_set(&r.p[i][j], a, (int32_t)q);
            }
    *out = r;
    return CS_OK;
}

cs_err_t cs_coons_bilinear(const cs_bezier_t *p1, const cs_bezier_t *p2, const cs_bezier_t *q1,
                           const cs_bezier_t *q2, cs_patch_t *out)
{
    cs_err_t e = check_boundary(p1, p2, q1, q2);
    if (e != CS_OK)
        return e;
    if (!out)
        return CS_ERR_ARG;
    e3_t e1, e2, f1, f2;
    elev3x(p1, e1);
    elev3x(p2, e2);
    elev3x(q1, f1);
    elev3x(q2, f2);
    const cs_vec3_t *ca = &p1->p[0], *cb = &p1->p[p1->degree];
    const cs_vec3_t *cc = &p2->p[p2->degree], *cd = &p2->p[0];
    int64_t net9[4][4][3];
    for (int64_t i = 0; i < 4; i++)
        for (int64_t j = 0; j < 4; j++)
            for (unsigned a = 0; a < 3; a++) {
                /* S1: (1 - v) p1 + v p2; S2: (1 - u) q1 + u q2; S3: bilinear in the corners. */
                int64_t s1 = (3 - j) * e1[i][a] + j * e2[i][a];
                int64_t s2 = (3 - i) * f1[j][a] + i * f2[j][a];
                int64_t s3 = (3 - i) * (3 - j) * cs_fixed_vec_get(ca, a) + i * (3 - j) * cs_fixed_vec_get(cb, a) +
                             (3 - i) * j * cs_fixed_vec_get(cd, a) + i * j * cs_fixed_vec_get(cc, a);
                net9[i][j][a] = s1 + s2 - s3;
            }
    return finish9(net9, out);
}

/* Derivative of a curve at its start (end = false) or end, mm per unit parameter. */
static int64_t end_tangent(const cs_bezier_t *c, bool end, unsigned a)
{
    unsigned n = c->degree;
    return end ? (int64_t)n * ((int64_t)cs_fixed_vec_get(&c->p[n], a) - cs_fixed_vec_get(&c->p[n - 1], a))
               : (int64_t)n * ((int64_t)cs_fixed_vec_get(&c->p[1], a) - cs_fixed_vec_get(&c->p[0], a));
}

cs_err_t cs_coons_bicubic(const cs_bezier_t *p1, const cs_bezier_t *p2, const cs_bezier_t *q1,
                          const cs_bezier_t *q2, const cs_bezier_t *p1v, const cs_bezier_t *p2v,
                          const cs_bezier_t *q1u, const cs_bezier_t *q2u, cs_patch_t *out)
{
    return cs_coons_bicubic_twist(p1, p2, q1, q2, p1v, p2v, q1u, q2u, NULL, out);
}

cs_err_t cs_coons_bicubic_twist(const cs_bezier_t *p1, const cs_bezier_t *p2, const cs_bezier_t *q1,
                                const cs_bezier_t *q2, const cs_bezier_t *p1v,
                                const cs_bezier_t *p2v, const cs_bezier_t *q1u,
                                const cs_bezier_t *q2u, const cs_vec3_t twist[2][2],
                                cs_patch_t *out)
{
    cs_err_t e = check_boundary(p1, p2, q1, q2);
    if (e != CS_OK)
        return e;
    const cs_bezier_t *der[4] = {p1v, p2v, q1u, q2u};
    /* Defaults: the Hermite cubic between the corner tangents of the crossing curves (p1v from
     * q1'(0) to q2'(0), ...) with the twists as its end slopes, 3 x Bézier (3a, 3a + s0,
     * 3b - s1, 3b): compatible with the corners and the twists (zero twists: (a, a, b, b)).
     * End slopes: p1v (tw00, tw10), p2v (tw01, tw11), q1u (tw00, tw01), q2u (tw10, tw11). */
    const cs_bezier_t *from[4] = {q1, q1, p1, p1}, *to[4] = {q2, q2, p2, p2};
    const bool at_end[4] = {false, true, false, true};
    static const unsigned slope[4][2][2] = {
        {{0, 0}, {1, 0}}, {{0, 1}, {1, 1}}, {{0, 0}, {0, 1}}, {{1, 0}, {1, 1}}};
    e3_t g[4];
    for (unsigned k = 0; k < 4; k++) {
        if (!der[k]) {
            for (unsigned a = 0; a < 3; a++) {
                int64_t ta = end_tangent(from[k], at_end[k], a),
                        tb = end_tangent(to[k], at_end[k], a);
                int64_t s0 = twist ? cs_fixed_vec_get(&twist[slope[k][0][0]][slope[k][0][1]], a) : 0;
                int64_t s1 = twist ? cs_fixed_vec_get(&twist[slope[k][1][0]][slope[k][1][1]], a) : 0;
                g[k][0][a] = 3 * ta;
                g[k][1][a] = 3 * ta + s0;
                g[k][2][a] = 3 * tb - s1;
                g[k][3][a] = 3 * tb;
            }
            continue;
        }
        e = check_curve(der[k], false);
        if (e != CS_OK)
            return e;
        elev3x(der[k], g[k]);
    }
    if (!out)
        return CS_ERR_ARG;
    e3_t e1, e2, f1, f2;
    elev3x(p1, e1);
    elev3x(p2, e2);
    elev3x(q1, f1);
    elev3x(q2, f2);
    /* 3 x (Hermite -> Bézier) in order (P0, P1, T0, T1), as cs_patch_from_hermite. */
    static const int64_t h3[4][4] = {{3, 0, 0, 0}, {3, 0, 1, 0}, {0, 3, 0, -1}, {0, 3, 0, 0}};
    int64_t net9[4][4][3];
    for (unsigned a = 0; a < 3; a++) {
        /* S3's B matrix (seed 000): corners, u-tangents of p1 / p2, v-tangents of q1 / q2,
         * the twists A^uv (zero unless given). Rows (A(0,.), A(1,.), A^u(0,.), A^u(1,.)),
         * columns (v = 0, v = 1, d/dv at 0, d/dv at 1). */
        int64_t bm[4][4] = {
            {cs_fixed_vec_get(&p1->p[0], a), cs_fixed_vec_get(&p2->p[0], a), end_tangent(q1, false, a),
             end_tangent(q1, true, a)},
            {cs_fixed_vec_get(&p1->p[p1->degree], a), cs_fixed_vec_get(&p2->p[p2->degree], a), end_tangent(q2, false, a),
             end_tangent(q2, true, a)},
            {end_tangent(p1, false, a), end_tangent(p2, false, a),
             twist ? cs_fixed_vec_get(&twist[0][0], a) : 0, twist ? cs_fixed_vec_get(&twist[0][1], a) : 0},
            {end_tangent(p1, true, a), end_tangent(p2, true, a), twist ? cs_fixed_vec_get(&twist[1][0], a) : 0,
             twist ? cs_fixed_vec_get(&twist[1][1], a) : 0},
        };
        for (unsigned i = 0; i < 4; i++) {
            for (unsigned j = 0; j < 4; j++) {
                int64_t s3 = 0;
                for (unsigned k = 0; k < 4; k++)
                    for (unsigned l = 0; l < 4; l++)
                        s3 += h3[i][k] * h3[j][l] * bm[k][l];
                /* S1 row j (Hermite blend in v of p1, p2, p1v, p2v), times 9. */
                int64_t s1 = j == 0   ? 3 * e1[i][a]
                             : j == 1 ? 3 * e1[i][a] + g[0][i][a]
                             : j == 2 ? 3 * e2[i][a] - g[1][i][a]
                                      : 3 * e2[i][a];
                int64_t s2 = i == 0   ? 3 * f1[j][a]
                             : i == 1 ? 3 * f1[j][a] + g[2][j][a]
                             : i == 2 ? 3 * f2[j][a] - g[3][j][a]
                                      : 3 * f2[j][a];
                net9[i][j][a] = s1 + s2 - s3;
            }
        }
    }
    return finish9(net9, out);
}

static cs_err_t elevate_to(const cs_bezier_t *c, unsigned n, cs_bezier_t *out)
{
    cs_bezier_t t = *c;
    while (t.degree < n) {
        cs_err_t e = cs_bezier_elevate(&t, &t);
        if (e != CS_OK)
            return e;
    }
    *out = t;
    return CS_OK;
}

cs_err_t cs_coons_ruled(const cs_bezier_t *p, const cs_bezier_t *q, cs_patch_t *out)
{
    cs_err_t e = check_curve(p, true);
    if (e == CS_OK)
        e = check_curve(q, true);
    if (e != CS_OK)
        return e;
    if (!out)
        return CS_ERR_ARG;
    unsigned n = p->degree > q->degree ? p->degree : q->degree;
    cs_bezier_t pe, qe;
    e = elevate_to(p, n, &pe);
    if (e == CS_OK)
        e = elevate_to(q, n, &qe);
    if (e != CS_OK)
        return e;
    cs_patch_t r = {0};
    r.deg_u = (uint8_t)n;
    r.deg_v = 1;
    for (unsigned i = 0; i <= n; i++) {
        r.p[i][0] = pe.p[i];
        r.p[i][1] = qe.p[i];
    }
    *out = r;
    return CS_OK;
}

cs_err_t cs_coons_extrude(const cs_bezier_t *p, const cs_vec3_t *d, cs_patch_t *out)
{
    cs_err_t e = check_curve(p, true);
    if (e != CS_OK)
        return e;
    if (!d || !out)
        return CS_ERR_ARG;
    cs_patch_t r = {0};
    r.deg_u = p->degree;
    r.deg_v = 1;
    for (unsigned i = 0; i <= p->degree; i++) {
        r.p[i][0] = p->p[i];
        for (unsigned a = 0; a < 3; a++) {
            int64_t s = (int64_t)cs_fixed_vec_get(&p->p[i], a) + cs_fixed_vec_get(d, a);
            if (!cs_fixed_pos_ok(s))
                return CS_ERR_RANGE;
            cs_fixed_vec_set(&r.p[i][1], a, (int32_t)s);
        }
    }
    *out = r;
    return CS_OK;
}
