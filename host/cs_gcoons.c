/* cs_gcoons: generalised Coons patches with cubic blends (see cs_gcoons.h). */
#include "cs_gcoons.h"

#include <math.h>
#include <string.h>

#include "cs_conv.h"

cs_gcoons_blend_t cs_gcoons_linear(void)
{
    cs_gcoons_blend_t b = {{1, 2.0 / 3, 1.0 / 3, 0}};
    return b;
}

cs_gcoons_blend_t cs_gcoons_hermite(void)
{
    cs_gcoons_blend_t b = {{1, 1, 0, 0}};
    return b;
}

/* The curve elevated to degree 3, in mm: degree elevation P'_i = i/(n+1) P_(i-1) + (1 - i/(n+1))
 * P_i applied until cubic. */
static void cubic_mm(const cs_bezier_t *c, double out[4][3])
{
    double p[4][3];
    unsigned n = c->degree;
    for (unsigned i = 0; i <= n; i++) {
        p[i][0] = cs_conv_pos_to_mm(c->p[i].x);
        p[i][1] = cs_conv_pos_to_mm(c->p[i].y);
        p[i][2] = cs_conv_pos_to_mm(c->p[i].z);
    }
    for (; n < 3; n++) {
        double q[4][3];
        for (unsigned i = 0; i <= n + 1; i++)
            for (int a = 0; a < 3; a++) {
                double w = (double)i / (n + 1);
                q[i][a] = (i > 0 ? w * p[i - 1][a] : 0) + (i <= n ? (1 - w) * p[i][a] : 0);
            }
        memcpy(p, q, sizeof p);
    }
    memcpy(out, p, sizeof p);
}

static bool curve_ok(const cs_bezier_t *c, cs_err_t *e)
{
    if (!c)
        *e = CS_ERR_ARG;
    else if (c->rational)
        *e = CS_ERR_UNSUPPORTED;
    else if (c->degree < 1 || c->degree > 3)
        *e = CS_ERR_DEGREE;
    else
        return true;
    return false;
}

static bool blend_ok(const cs_gcoons_blend_t *f)
{
    if (!f || f->b[0] != 1 || f->b[3] != 0)
        return false;
    return isfinite(f->b[1]) && isfinite(f->b[2]);
}

static bool same(const cs_vec3_t *a, const cs_vec3_t *b)
{
    return a->x == b->x && a->y == b->y && a->z == b->z;
}

cs_err_t cs_gcoons_build(const cs_bezier_t *p1, const cs_bezier_t *p2, const cs_bezier_t *q1,
                         const cs_bezier_t *q2, const cs_gcoons_blend_t *f1,
                         const cs_gcoons_blend_t *g1, cs_patch_t *out)
{
    cs_err_t e = CS_OK;
    if (!curve_ok(p1, &e) || !curve_ok(p2, &e) || !curve_ok(q1, &e) || !curve_ok(q2, &e))
        return e;
    if (!out || !blend_ok(f1) || !blend_ok(g1))
        return CS_ERR_ARG;
    if (!same(&p1->p[0], &q1->p[0]) || !same(&p1->p[p1->degree], &q2->p[0]) ||
        !same(&p2->p[0], &q1->p[q1->degree]) || !same(&p2->p[p2->degree], &q2->p[q2->degree]))
        return CS_ERR_DEGENERATE;
    double a[4][3], b[4][3], c[4][3], d[4][3];
    cubic_mm(p1, a);
    cubic_mm(p2, b);
    cubic_mm(q1, c);
    cubic_mm(q2, d);
    /* Corners S(0,0) = a[0], S(1,0) = a[3], S(0,1) = b[0], S(1,1) = b[3]. */
    cs_vec3_t pts[16];
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double F = f1->b[i], G = g1->b[j], x[3];
            for (int k = 0; k < 3; k++)
                x[k] = F * c[j][k] + (1 - F) * d[j][k] + G * a[i][k] + (1 - G) * b[i][k] -
                       (F * G * a[0][k] + F * (1 - G) * b[0][k] + (1 - F) * G * a[3][k] +
                        (1 - F) * (1 - G) * b[3][k]);
            if (cs_conv_mm_to_vec(x[0], x[1], x[2], &pts[i * 4 + j]) != CS_OK)
                return CS_ERR_RANGE;
        }
    return cs_patch_init(out, 3, 3, pts);
}
