/* test_varady: Várady n-sided patches (host/cs_varady, seed 002) checked in double: the surface
 * interpolates every boundary curve on its domain side and the corners at the vertices, the
 * mu blends sum to one (a loop in a plane with in-plane tangents gives a planar surface), and
 * the Bézier curves handed to the core stay within the tolerance of the surface (dense check).
 * The lambda / kappa scheme: the blends against the seed's written-out n = 4 formulas and its
 * worked values, partition of unity (sum lambda = 2, sum kappa = 1), the whole surface against
 * an independent implementation of the seed's formula in this file, boundary and corner
 * interpolation with each of the three parametrisations (side, radial, central line), whose
 * defining properties are checked against the domain geometry recomputed here, and the bicubic
 * cells handed to the ball-end finishing (within the tolerance, tiling the quads, oriented). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_ref.h"
#include "cs_varady.h"

static void report(const char *what, double v)
{
    if (getenv("CS_TEST_VERBOSE"))
        printf("%s: %.3g mm\n", what, v);
}

static cs_vec3_t mm(double x, double y, double z)
{
    return cs_fixed_vec((int32_t)lround(x * 65536), (int32_t)lround(y * 65536),
                        (int32_t)lround(z * 65536));
}

/* A closed loop of n cubic sides through points on a wavy circle; planar when amp = 0. */
static void loop(size_t n, double amp, cs_bezier_t *sides)
{
    const double pi = 3.14159265358979323846;
    cs_vec3_t c[CS_VARADY_MAX_SIDES];
    for (size_t i = 0; i < n; i++) {
        double a = 2 * pi * (double)i / (double)n;
        c[i] = mm(20 * cos(a), 20 * sin(a), amp * ((i % 2) ? 1 : -1));
    }
    for (size_t i = 0; i < n; i++) {
        cs_vec3_t p0 = c[i], p3 = c[(i + 1) % n];
        /* Inner points bulge outwards (and up in z for the non-planar case). */
        double mx = (p0.x + p3.x) / 2.0, my = (p0.y + p3.y) / 2.0, l = sqrt(mx * mx + my * my);
        cs_vec3_t pts[4] = {
            p0,
            cs_fixed_vec((int32_t)((2 * p0.x + p3.x) / 3 + 0.15 * mx / l * 65536 * 5),
                         (int32_t)((2 * p0.y + p3.y) / 3 + 0.15 * my / l * 65536 * 5),
                         (int32_t)(p0.z + amp * 65536 * 0.5)),
            cs_fixed_vec((int32_t)((p0.x + 2 * p3.x) / 3 + 0.15 * mx / l * 65536 * 5),
                         (int32_t)((p0.y + 2 * p3.y) / 3 + 0.15 * my / l * 65536 * 5),
                         (int32_t)(p3.z - amp * 65536 * 0.5)),
            p3};
        assert_int_equal(cs_bezier_init(&sides[i], 3, pts), CS_OK);
    }
}

static double dist_line(const double a[2], const double b[2], double x, double y)
{
    double ex = b[0] - a[0], ey = b[1] - a[1];
    return (ex * (y - a[1]) - ey * (x - a[0])) / sqrt(ex * ex + ey * ey);
}

static void test_interpolation(void **state)
{
    (void)state;
    for (size_t n = 3; n <= 6; n++) {
        cs_bezier_t sides[CS_VARADY_MAX_SIDES];
        loop(n, 4, sides);
        cs_varady_t v;
        assert_int_equal(cs_varady_init(&v, sides, n), CS_OK);
        double worst = 0;
        for (size_t i = 0; i < n; i++) {
            double a[2], b[2], q[3];
            cs_varady_vertex(&v, i, a);
            cs_varady_vertex(&v, (i + 1) % n, b);
            /* The vertex is the corner. */
            cs_varady_eval(&v, a[0], a[1], q);
            cs_ref_vec_t c = cs_ref_from_pos(&sides[i].p[0]);
            worst = fmax(worst, fabs(q[0] - c.x) + fabs(q[1] - c.y) + fabs(q[2] - c.z));
            /* Points on side i: the boundary curve at s = d_{i-1} / (d_{i-1} + d_{i+1}). */
            double pa[2], pb[2], na[2], nb[2];
            cs_varady_vertex(&v, (i + n - 1) % n, pa);
            cs_varady_vertex(&v, i, pb);
            cs_varady_vertex(&v, (i + 1) % n, na);
            cs_varady_vertex(&v, (i + 2) % n, nb);
            for (int k = 1; k < 16; k++) {
                double t = k / 16.0, x = a[0] + t * (b[0] - a[0]), y = a[1] + t * (b[1] - a[1]);
                double dp = dist_line(pa, pb, x, y), dn = dist_line(na, nb, x, y);
                cs_varady_eval(&v, x, y, q);
                cs_ref_vec_t r = cs_ref_eval(&sides[i], dp / (dp + dn));
                worst = fmax(worst, fabs(q[0] - r.x) + fabs(q[1] - r.y) + fabs(q[2] - r.z));
            }
        }
        char what[64];
        snprintf(what, sizeof what, "%zu-sided: boundary interpolation", n);
        report(what, worst);
        assert_true(worst < 1e-9);
    }
}

static void test_planar(void **state)
{
    (void)state;
    cs_bezier_t sides[CS_VARADY_MAX_SIDES];
    loop(5, 0, sides);
    cs_varady_t v;
    assert_int_equal(cs_varady_init(&v, sides, 5), CS_OK);
    double worst = 0;
    for (int i = -10; i <= 10; i++)
        for (int j = -10; j <= 10; j++) {
            double q[3];
            cs_varady_eval(&v, i * 1.5, j * 1.5, q);
            worst = fmax(worst, fabs(q[2]));
        }
    assert_true(worst < 1e-9); /* the mu_i sum to 1: an affine combination of planar ribbons */
}

static void test_curves(void **state)
{
    (void)state;
    cs_bezier_t sides[CS_VARADY_MAX_SIDES];
    loop(5, 4, sides);
    cs_varady_t v;
    assert_int_equal(cs_varady_init(&v, sides, 5), CS_OK);
    double worst = 0;
    size_t total = 0;
    for (size_t i = 0; i < 5; i++) {
        double c[2] = {0, 0}, p[2];
        cs_varady_vertex(&v, i, p);
        /* A ray from near the centre to the vertex, and a chord across the domain. */
        double rays[2][2][2] = {{{0.1, 0.2}, {p[0], p[1]}}, {{p[0] * 0.8, p[1] * 0.8}, {0, 0}}};
        (void)c;
        cs_varady_vertex(&v, (i + 2) % 5, rays[1][1]);
        rays[1][1][0] *= 0.8;
        rays[1][1][1] *= 0.8;
        for (int r = 0; r < 2; r++) {
            cs_bezier_t out[64];
            size_t cnt = 0;
            assert_int_equal(cs_varady_curve(&v, rays[r][0], rays[r][1], 0.002, out, 64, &cnt),
                             CS_OK);
            total += cnt;
            for (size_t k = 0; k < cnt; k++) {
                if (k > 0)
                    assert_memory_equal(&out[k].p[0], &out[k - 1].p[3], sizeof(cs_vec3_t));
                for (int s = 0; s <= 64; s++) {
                    double u = s / 64.0, t = ((double)k + u) / (double)cnt, q[3];
                    cs_varady_eval(&v, rays[r][0][0] + t * (rays[r][1][0] - rays[r][0][0]),
                                   rays[r][0][1] + t * (rays[r][1][1] - rays[r][0][1]), q);
                    cs_ref_vec_t b = cs_ref_eval(&out[k], u);
                    double d = sqrt((b.x - q[0]) * (b.x - q[0]) + (b.y - q[1]) * (b.y - q[1]) +
                                    (b.z - q[2]) * (b.z - q[2]));
                    worst = fmax(worst, d);
                }
            }
        }
    }
    char what[64];
    snprintf(what, sizeof what, "curves to the core (%zu pieces), tol 0.002", total);
    report(what, worst);
    assert_true(worst <= 0.002);
}

static void test_errors(void **state)
{
    (void)state;
    cs_bezier_t sides[CS_VARADY_MAX_SIDES];
    loop(4, 1, sides);
    cs_varady_t v;
    assert_int_equal(cs_varady_init(&v, sides, 2), CS_ERR_ARG);
    sides[2].p[3].x += 1; /* the loop no longer closes */
    assert_int_equal(cs_varady_init(&v, sides, 4), CS_ERR_DEGENERATE);
}

/* --- lambda / kappa blends and the other parametrisations --------------------------------- */

static const char *const param_name[] = {"side", "radial", "centre"};

static void test_blends_seed(void **state)
{
    (void)state;
    /* Seed 002's n = 4, i = 1 formulas (its indices 1..4 are 0..3 here). */
    double d[4] = {1.3, 0.7, 2.1, 0.4}, q[4];
    for (int k = 0; k < 4; k++)
        q[k] = d[k] * d[k];
    double lambda[4], kappa[4], mu[4];
    cs_varady_blends(4, d, lambda, kappa, mu);
    double den = q[0] * q[1] + q[1] * q[2] + q[2] * q[3] + q[3] * q[0];
    assert_true(fabs(lambda[0] - (q[1] * q[2] + q[2] * q[3]) / den) < 1e-14);
    assert_true(fabs(kappa[0] - q[1] * q[2] / den) < 1e-14);
    double dmu = q[0] * q[1] * q[2] + q[1] * q[2] * q[3] + q[2] * q[3] * q[0] + q[3] * q[0] * q[1];
    assert_true(fabs(mu[0] - q[1] * q[2] * q[3] / dmu) < 1e-14);
    /* The seed's worked values: d1 = 0 => lambda_1 = 1; d3 = 0 => lambda_1 = 0; d2 = d4 -> 0 and
     * d1 = d3 => lambda_1 = 1/2; (d1, d4) = (0, 0) => kappa_1 = 1; d2 = 0 => kappa_1 = 0;
     * d1 = 0 and d4 = d2 => kappa_1 = 1/2; d1 = 0 => mu_1 = 1. */
    double a[4] = {0, 0.7, 2.1, 0.4};
    cs_varady_blends(4, a, lambda, kappa, mu);
    assert_true(fabs(lambda[0] - 1) < 1e-15 && fabs(mu[0] - 1) < 1e-15);
    double b[4] = {1.3, 0.7, 0, 0.4};
    cs_varady_blends(4, b, lambda, NULL, NULL);
    assert_true(fabs(lambda[0]) < 1e-15);
    double c[4] = {1.1, 1e-3, 1.1, 1e-3}; /* d2 = d4 = 0 is 0 / 0: its limit */
    cs_varady_blends(4, c, lambda, NULL, NULL);
    assert_true(fabs(lambda[0] - 0.5) < 1e-15);
    double e[4] = {0, 0.7, 2.1, 0};
    cs_varady_blends(4, e, NULL, kappa, NULL);
    assert_true(fabs(kappa[0] - 1) < 1e-15);
    double f[4] = {1.3, 0, 2.1, 0.4};
    cs_varady_blends(4, f, NULL, kappa, NULL);
    assert_true(fabs(kappa[0]) < 1e-15);
    double g[4] = {0, 0.9, 2.1, 0.9};
    cs_varady_blends(4, g, NULL, kappa, NULL);
    assert_true(fabs(kappa[0] - 0.5) < 1e-15);
}

static void test_blends_unity(void **state)
{
    (void)state;
    srand(5);
    double worst = 0;
    for (size_t n = 3; n <= CS_VARADY_MAX_SIDES; n++)
        for (int trial = 0; trial < 200; trial++) {
            double d[CS_VARADY_MAX_SIDES], lambda[CS_VARADY_MAX_SIDES];
            double kappa[CS_VARADY_MAX_SIDES], mu[CS_VARADY_MAX_SIDES];
            for (size_t i = 0; i < n; i++)
                d[i] = 0.01 + 50.0 * rand() / RAND_MAX;
            if (trial % 4 == 1)
                d[(size_t)trial % n] = 0; /* on a side */
            cs_varady_blends(n, d, lambda, kappa, mu);
            double sl = 0, sk = 0, sm = 0;
            for (size_t i = 0; i < n; i++) {
                sl += lambda[i];
                sk += kappa[i];
                sm += mu[i];
                assert_true(lambda[i] >= 0 && kappa[i] >= 0 && mu[i] >= 0);
            }
            worst = fmax(worst, fmax(fabs(sl - 2), fmax(fabs(sk - 1), fabs(sm - 1))));
            if (trial % 4 == 1) {
                /* On side i: lambda_i = mu_i = 1; kappa only at its two corners; lambda_j = 0
                 * on the sides that do not touch side i. */
                size_t i = (size_t)trial % n;
                assert_true(fabs(lambda[i] - 1) < 1e-14 && fabs(mu[i] - 1) < 1e-14);
                for (size_t j = 0; j < n; j++) {
                    bool touch = j == i || j == (i + 1) % n || j == (i + n - 1) % n;
                    bool corner = j == i || j == (i + 1) % n;
                    if (!touch)
                        assert_true(lambda[j] == 0);
                    if (!corner)
                        assert_true(kappa[j] == 0);
                }
            }
        }
    report("partition of unity (|sum lambda - 2|, |sum kappa - 1|, |sum mu - 1|)", worst);
    assert_true(worst < 1e-13);
}

/* The seed's lambda / kappa surface with the side-based parametrisation, written out here from
 * the domain vertices and the boundary curves alone. */
/* User tangent curves (NULL: the defaults) and corner twists (NULL: zero) of the reference. */
static const cs_bezier_t *ref_tan;
static const double (*ref_twist)[3];

static void lk_reference(const cs_varady_t *v, const cs_bezier_t *sides, size_t n, double x,
                         double y, double out[3])
{
    double vert[CS_VARADY_MAX_SIDES][2], d[CS_VARADY_MAX_SIDES], t0[CS_VARADY_MAX_SIDES][3],
        t1[CS_VARADY_MAX_SIDES][3];
    for (size_t i = 0; i < n; i++)
        cs_varady_vertex(v, i, vert[i]);
    for (size_t i = 0; i < n; i++)
        d[i] = dist_line(vert[i], vert[(i + 1) % n], x, y);
    for (size_t i = 0; i < n; i++) {
        /* unit tangents leading away from corners i and i + 1 along the neighbouring sides */
        const cs_bezier_t *pv = &sides[(i + n - 1) % n], *nx = &sides[(i + 1) % n];
        cs_ref_vec_t a = cs_ref_from_pos(&pv->p[pv->degree - 1]);
        cs_ref_vec_t b = cs_ref_from_pos(&pv->p[pv->degree]);
        cs_ref_vec_t c = cs_ref_from_pos(&nx->p[0]), e = cs_ref_from_pos(&nx->p[1]);
        double la = cs_ref_dist(a, b), lb = cs_ref_dist(c, e);
        t0[i][0] = (a.x - b.x) / la, t0[i][1] = (a.y - b.y) / la, t0[i][2] = (a.z - b.z) / la;
        t1[i][0] = (e.x - c.x) / lb, t1[i][1] = (e.y - c.y) / lb, t1[i][2] = (e.z - c.z) / lb;
    }
    double Dc[CS_VARADY_MAX_SIDES], sum = 0;
    for (size_t i = 0; i < n; i++) {
        Dc[i] = 1;
        for (size_t j = 0; j < n; j++)
            if (j != i && j != (i + n - 1) % n)
                Dc[i] *= d[j] * d[j];
        sum += Dc[i];
    }
    out[0] = out[1] = out[2] = 0;
    for (size_t i = 0; i < n; i++) {
        size_t im = (i + n - 1) % n, ip = (i + 1) % n;
        double lambda = (Dc[i] + Dc[ip]) / sum, kappa = Dc[i] / sum;
        double s = d[im] / (d[im] + d[ip]);
        cs_ref_vec_t p = cs_ref_eval(&sides[i], s), c = cs_ref_from_pos(&sides[i].p[0]);
        double pp[3] = {p.x, p.y, p.z}, cc[3] = {c.x, c.y, c.z};
        /* T_i(s), T_(i-1)(1), T_i(0): the user's curves or the linear default */
        double ts[3], ta[3], tb[3];
        for (int k = 0; k < 3; k++) {
            ts[k] = (1 - s) * t0[i][k] + s * t1[i][k];
            ta[k] = t1[im][k];
            tb[k] = t0[i][k];
        }
        if (ref_tan) {
            cs_ref_vec_t a = cs_ref_eval(&ref_tan[i], s), b = cs_ref_eval(&ref_tan[im], 1);
            cs_ref_vec_t c = cs_ref_eval(&ref_tan[i], 0);
            ts[0] = a.x, ts[1] = a.y, ts[2] = a.z;
            ta[0] = b.x, ta[1] = b.y, ta[2] = b.z;
            tb[0] = c.x, tb[1] = c.y, tb[2] = c.z;
        }
        for (int k = 0; k < 3; k++) {
            double r = pp[k] + d[i] * ts[k];
            double qc = cc[k] + d[im] * ta[k] + d[i] * tb[k] +
                        (ref_twist ? d[im] * d[i] * ref_twist[i][k] : 0);
            out[k] += lambda * r - kappa * qc;
        }
    }
}

/* A random point inside the domain polygon: a convex combination of its vertices. */
static void rnd_inside(const cs_varady_t *v, double *x, double *y)
{
    double w[CS_VARADY_MAX_SIDES], sw = 0;
    *x = *y = 0;
    for (size_t i = 0; i < v->n; i++)
        sw += (w[i] = 0.05 + (double)rand() / RAND_MAX);
    for (size_t i = 0; i < v->n; i++) {
        double p[2];
        cs_varady_vertex(v, i, p);
        *x += w[i] / sw * p[0];
        *y += w[i] / sw * p[1];
    }
}

static void test_lk_reference(void **state)
{
    (void)state;
    srand(11);
    double worst = 0;
    for (size_t n = 3; n <= 7; n++) {
        cs_bezier_t sides[CS_VARADY_MAX_SIDES];
        loop(n, 4, sides);
        cs_varady_t v;
        assert_int_equal(cs_varady_init(&v, sides, n), CS_OK);
        assert_int_equal(cs_varady_set_scheme(&v, CS_VARADY_LAMBDA_KAPPA, CS_VARADY_SIDE), CS_OK);
        for (int k = 0; k < 300; k++) {
            /* random points in the polygon: convex combinations of the vertices */
            double x, y, q[3], r[3];
            rnd_inside(&v, &x, &y);
            cs_varady_eval(&v, x, y, q);
            lk_reference(&v, sides, n, x, y, r);
            worst =
                fmax(worst, fmax(fabs(q[0] - r[0]), fmax(fabs(q[1] - r[1]), fabs(q[2] - r[2]))));
        }
    }
    report("lambda/kappa surface vs the seed's formula written out", worst);
    assert_true(worst < 1e-9);
    /* User-given cross-boundary tangent curves and non-zero twists (seed 002's T_i(s_i) and
     * W_i): the same formula with them, and the boundary still interpolated. */
    worst = 0;
    for (size_t n = 3; n <= 7; n++) {
        cs_bezier_t sides[CS_VARADY_MAX_SIDES], tan[CS_VARADY_MAX_SIDES];
        double tw[CS_VARADY_MAX_SIDES][3];
        loop(n, 4, sides);
        cs_varady_t v;
        assert_int_equal(cs_varady_init(&v, sides, n), CS_OK);
        assert_int_equal(cs_varady_set_scheme(&v, CS_VARADY_LAMBDA_KAPPA, CS_VARADY_SIDE), CS_OK);
        for (size_t i = 0; i < n; i++) {
            cs_vec3_t q[3] = {mm(0.2 * (double)i, 0.5, 1), mm(-0.3, 0.4, 0.8 + 0.1 * (double)i),
                              mm(0.1, -0.2, 1.2)};
            assert_int_equal(cs_bezier_init(&tan[i], 2, q), CS_OK);
            tw[i][0] = 0.01 * (double)i, tw[i][1] = -0.02, tw[i][2] = 0.03;
        }
        assert_int_equal(cs_varady_set_tangents(&v, tan), CS_OK);
        cs_varady_set_twists(&v, (const double(*)[3])tw);
        ref_tan = tan;
        ref_twist = (const double(*)[3])tw;
        for (int k = 0; k < 200; k++) {
            double x, y, q[3], r[3];
            rnd_inside(&v, &x, &y);
            cs_varady_eval(&v, x, y, q);
            lk_reference(&v, sides, n, x, y, r);
            worst =
                fmax(worst, fmax(fabs(q[0] - r[0]), fmax(fabs(q[1] - r[1]), fabs(q[2] - r[2]))));
        }
        for (size_t i = 0; i < n; i++) { /* midpoint of domain side i: P_i(1/2) by symmetry */
            double a[2], b[2], q[3];
            cs_varady_vertex(&v, i, a);
            cs_varady_vertex(&v, (i + 1) % n, b);
            cs_varady_eval(&v, (a[0] + b[0]) / 2, (a[1] + b[1]) / 2, q);
            double s = 0, dd = 0, ss[CS_VARADY_MAX_SIDES], ds[CS_VARADY_MAX_SIDES];
            cs_varady_params(&v, (a[0] + b[0]) / 2, (a[1] + b[1]) / 2, ss, ds);
            s = ss[i];
            dd = ds[i];
            cs_ref_vec_t pc = cs_ref_eval(&sides[i], s);
            assert_true(fabs(dd) < 1e-9);
            assert_true(fabs(q[0] - pc.x) + fabs(q[1] - pc.y) + fabs(q[2] - pc.z) < 1e-9);
        }
        ref_tan = NULL;
        ref_twist = NULL;
    }
    report("lambda/kappa with user tangents and twists vs the seed's formula", worst);
    assert_true(worst < 1e-9);
}

/* The line through a and b meets the line through c and d at *out; false when parallel. */
static bool meet(const double a[2], const double b[2], const double c[2], const double d[2],
                 double out[2])
{
    double r[2] = {b[0] - a[0], b[1] - a[1]}, t[2] = {d[0] - c[0], d[1] - c[1]};
    double den = r[0] * t[1] - r[1] * t[0];
    if (fabs(den) < 1e-9 * (fabs(r[0]) + fabs(r[1])) * (fabs(t[0]) + fabs(t[1])))
        return false;
    double k = ((c[0] - a[0]) * t[1] - (c[1] - a[1]) * t[0]) / den;
    out[0] = a[0] + k * r[0];
    out[1] = a[1] + k * r[1];
    return true;
}

/* The defining property of each parametrisation at interior points, recomputed from the domain
 * polygon: side: d_i is the distance to side i's line; radial: the point, the point e_i at s_i on
 * side i and the meeting point of the lines of sides i - 1 and i + 1 are collinear and
 * |point - e_i| = d_i; central line: r(s_i, d_i) built from the seed's formula is the point, and
 * r(1/2, d_c) is the centre of the vertices. */
static void test_params(void **state)
{
    (void)state;
    double worst[3] = {0, 0, 0};
    for (size_t n = 3; n <= 8; n++) {
        cs_bezier_t sides[CS_VARADY_MAX_SIDES];
        loop(n, 2, sides);
        cs_varady_t v;
        assert_int_equal(cs_varady_init(&v, sides, n), CS_OK);
        double vert[CS_VARADY_MAX_SIDES][2], cen[2] = {0, 0};
        for (size_t i = 0; i < n; i++) {
            cs_varady_vertex(&v, i, vert[i]);
            cen[0] += vert[i][0] / (double)n;
            cen[1] += vert[i][1] / (double)n;
        }
        for (int par = 0; par < 3; par++) {
            assert_int_equal(cs_varady_set_scheme(&v, CS_VARADY_MU, (cs_varady_param_t)par), CS_OK);
            for (int k = 0; k < 40; k++) {
                /* points on rays from the centre towards each vertex and edge midpoint */
                size_t j = (size_t)k % n;
                double f = 0.05 + 0.9 * (k / (double)n) / (40.0 / (double)n + 1);
                const double *a = vert[j], *b = vert[(j + 1) % n];
                double tgt[2] = {k % 2 ? a[0] : 0.5 * (a[0] + b[0]),
                                 k % 2 ? a[1] : 0.5 * (a[1] + b[1])};
                double x = cen[0] + f * (tgt[0] - cen[0]), y = cen[1] + f * (tgt[1] - cen[1]);
                double s[CS_VARADY_MAX_SIDES], d[CS_VARADY_MAX_SIDES];
                cs_varady_params(&v, x, y, s, d);
                for (size_t i = 0; i < n; i++) {
                    const double *p0 = vert[i], *p1 = vert[(i + 1) % n];
                    const double *pm = vert[(i + n - 1) % n], *pn = vert[(i + 2) % n];
                    double e[2] = {p0[0] + s[i] * (p1[0] - p0[0]), p0[1] + s[i] * (p1[1] - p0[1])};
                    double err = 0;
                    assert_true(d[i] > 0);
                    if (par == CS_VARADY_SIDE) {
                        err = fabs(d[i] - dist_line(p0, p1, x, y));
                    } else if (par == CS_VARADY_RADIAL) {
                        double c[2], dir[2];
                        if (meet(pm, p0, p1, pn, c)) {
                            dir[0] = c[0] - e[0], dir[1] = c[1] - e[1];
                        } else {
                            dir[0] = pm[0] - p0[0], dir[1] = pm[1] - p0[1];
                        }
                        double l = sqrt(dir[0] * dir[0] + dir[1] * dir[1]);
                        double off = ((x - e[0]) * dir[1] - (y - e[1]) * dir[0]) / l;
                        double len = sqrt((x - e[0]) * (x - e[0]) + (y - e[1]) * (y - e[1]));
                        err = fmax(fabs(off), fabs(len - d[i]));
                    } else {
                        double w1[2] = {pm[0] - p0[0], pm[1] - p0[1]};
                        double w2[2] = {pn[0] - p1[0], pn[1] - p1[1]};
                        double l1 = sqrt(w1[0] * w1[0] + w1[1] * w1[1]);
                        double l2 = sqrt(w2[0] * w2[0] + w2[1] * w2[1]);
                        for (int c = 0; c < 2; c++)
                            w1[c] /= l1, w2[c] /= l2;
                        /* local frame of side i: u along it, v inwards */
                        double ex[2] = {p1[0] - p0[0], p1[1] - p0[1]};
                        double L = sqrt(ex[0] * ex[0] + ex[1] * ex[1]);
                        ex[0] /= L, ex[1] /= L;
                        double ey[2] = {-ex[1], ex[0]};
                        double w1u = w1[0] * ex[0] + w1[1] * ex[1],
                               w1v = w1[0] * ey[0] + w1[1] * ey[1];
                        double w2u = w2[0] * ex[0] + w2[1] * ex[1],
                               w2v = w2[0] * ey[0] + w2[1] * ey[1];
                        double cu = (cen[0] - p0[0]) * ex[0] + (cen[1] - p0[1]) * ex[1];
                        double cv = (cen[0] - p0[0]) * ey[0] + (cen[1] - p0[1]) * ey[1];
                        /* seed: w12v = (w1v + w2v) / 2, dc = 2 cv / (w1v + w2v), w12u from cu */
                        double w12v = 0.5 * (w1v + w2v), dc = 2 * cv / (w1v + w2v);
                        double w12u = (4 * (cu - 0.5 * L) / dc - w1u - w2u) / 2;
                        double S = s[i], m = 1 - S;
                        double ru = L * S + (w1u * m * m + 2 * w12u * m * S + w2u * S * S) * d[i];
                        double rv = (w1v * m * m + 2 * w12v * m * S + w2v * S * S) * d[i];
                        double pu = (x - p0[0]) * ex[0] + (y - p0[1]) * ex[1];
                        double pv = (x - p0[0]) * ey[0] + (y - p0[1]) * ey[1];
                        err = fmax(fabs(ru - pu), fabs(rv - pv));
                        /* and the centre is on the line s = 1/2 */
                        double hu = 0.5 * L + 0.25 * (w1u + 2 * w12u + w2u) * dc;
                        double hv = 0.25 * (w1v + 2 * w12v + w2v) * dc;
                        err = fmax(err, fmax(fabs(hu - cu), fabs(hv - cv)));
                    }
                    worst[par] = fmax(worst[par], err);
                }
            }
        }
    }
    for (int par = 0; par < 3; par++) {
        char what[64];
        snprintf(what, sizeof what, "parametrisation %s: defining property", param_name[par]);
        report(what, worst[par]);
        assert_true(worst[par] < 1e-9);
    }
}

/* Boundary and corner interpolation for every blend x parametrisation, n = 3..8. On side i the
 * surface must be P_i at the side's own parameter: linear along the side for radial and
 * central line, d_{i-1} / (d_{i-1} + d_{i+1}) for the side-based one. */
static void test_schemes_interpolate(void **state)
{
    (void)state;
    for (int blend = 0; blend < 2; blend++)
        for (int par = 0; par < 3; par++) {
            double worst = 0, planar = 0;
            for (size_t n = 3; n <= 8; n++) {
                cs_bezier_t sides[CS_VARADY_MAX_SIDES];
                loop(n, 4, sides);
                cs_varady_t v;
                assert_int_equal(cs_varady_init(&v, sides, n), CS_OK);
                assert_int_equal(
                    cs_varady_set_scheme(&v, (cs_varady_blend_t)blend, (cs_varady_param_t)par),
                    CS_OK);
                for (size_t i = 0; i < n; i++) {
                    double a[2], b[2], q[3], pa[2], na[2], nb[2];
                    cs_varady_vertex(&v, i, a);
                    cs_varady_vertex(&v, (i + 1) % n, b);
                    cs_varady_vertex(&v, (i + n - 1) % n, pa);
                    cs_varady_vertex(&v, (i + 2) % n, nb);
                    memcpy(na, b, sizeof na);
                    cs_varady_eval(&v, a[0], a[1], q);
                    cs_ref_vec_t c = cs_ref_from_pos(&sides[i].p[0]);
                    worst = fmax(worst, fabs(q[0] - c.x) + fabs(q[1] - c.y) + fabs(q[2] - c.z));
                    for (int k = 1; k < 32; k++) {
                        double t = k / 32.0, x = a[0] + t * (b[0] - a[0]);
                        double y = a[1] + t * (b[1] - a[1]), s = t;
                        if (par == CS_VARADY_SIDE) {
                            double dp = dist_line(pa, a, x, y), dn = dist_line(na, nb, x, y);
                            s = dp / (dp + dn);
                        }
                        cs_varady_eval(&v, x, y, q);
                        cs_ref_vec_t r = cs_ref_eval(&sides[i], s);
                        worst = fmax(worst, fabs(q[0] - r.x) + fabs(q[1] - r.y) + fabs(q[2] - r.z));
                    }
                }
                /* planar loop, in-plane tangents: the blends are affine (sum lambda - sum
                 * kappa = 1, sum mu = 1), so the surface stays in the plane */
                loop(n, 0, sides);
                assert_int_equal(cs_varady_init(&v, sides, n), CS_OK);
                cs_varady_set_scheme(&v, (cs_varady_blend_t)blend, (cs_varady_param_t)par);
                for (int k = 0; k < 64; k++) {
                    double p0[2], p1[2], q[3], f = (k % 8 + 0.5) / 8.5;
                    cs_varady_vertex(&v, (size_t)k % n, p0);
                    cs_varady_vertex(&v, ((size_t)k + 1) % n, p1);
                    double g = (k / 8 + 0.5) / 8.0;
                    cs_varady_eval(&v, f * (g * p0[0] + (1 - g) * p1[0]),
                                   f * (g * p0[1] + (1 - g) * p1[1]), q);
                    planar = fmax(planar, fabs(q[2]));
                }
            }
            char what[96];
            snprintf(what, sizeof what, "%s + %s: boundary/corner interpolation",
                     blend ? "lambda/kappa" : "mu", param_name[par]);
            report(what, worst);
            assert_true(worst < 1e-9);
            snprintf(what, sizeof what, "%s + %s: planar loop, |z|", blend ? "lambda/kappa" : "mu",
                     param_name[par]);
            report(what, planar);
            assert_true(planar < 1e-9);
        }
}

static void test_schemes_curves(void **state)
{
    (void)state;
    cs_bezier_t sides[CS_VARADY_MAX_SIDES];
    loop(5, 4, sides);
    cs_varady_t v;
    assert_int_equal(cs_varady_init(&v, sides, 5), CS_OK);
    assert_int_equal(cs_varady_set_scheme(&v, (cs_varady_blend_t)7, CS_VARADY_SIDE), CS_ERR_ARG);
    for (int par = 0; par < 3; par++) {
        assert_int_equal(cs_varady_set_scheme(&v, CS_VARADY_LAMBDA_KAPPA, (cs_varady_param_t)par),
                         CS_OK);
        double worst = 0, a[2] = {0.3, -0.2}, b[2];
        cs_varady_vertex(&v, 2, b);
        cs_bezier_t out[64];
        size_t cnt = 0;
        assert_int_equal(cs_varady_curve(&v, a, b, 0.002, out, 64, &cnt), CS_OK);
        for (size_t k = 0; k < cnt; k++)
            for (int s = 0; s <= 64; s++) {
                double u = s / 64.0, t = ((double)k + u) / (double)cnt, q[3];
                cs_varady_eval(&v, a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), q);
                cs_ref_vec_t r = cs_ref_eval(&out[k], u);
                worst = fmax(worst, sqrt((r.x - q[0]) * (r.x - q[0]) + (r.y - q[1]) * (r.y - q[1]) +
                                         (r.z - q[2]) * (r.z - q[2])));
            }
        char what[64];
        snprintf(what, sizeof what, "lambda/kappa + %s: curve to the core (%zu pieces)",
                 param_name[par], cnt);
        report(what, worst);
        assert_true(worst <= 0.002);
    }
}

/* Forward maps (s, d) -> domain point of side i for each parametrisation, written from the seed
 * here (the library only inverts them): side-based: the point at distance d from side i's line
 * where (1 - s) d_{i-1} = s d_{i+1} (two linear equations); radial: e = p_i + s (p_{i+1} - p_i)
 * moved d towards the meeting point of the lines of sides i - 1, i + 1 (along side i - 1 when
 * parallel); central line: r(s, d) of the seed. */
static void forward(const cs_varady_t *v, int par, size_t i, double s, double d, double out[2])
{
    size_t n = v->n;
    double p0[2], p1[2], pm[2], pn[2], cen[2] = {0, 0};
    cs_varady_vertex(v, i, p0);
    cs_varady_vertex(v, (i + 1) % n, p1);
    cs_varady_vertex(v, (i + n - 1) % n, pm);
    cs_varady_vertex(v, (i + 2) % n, pn);
    for (size_t k = 0; k < n; k++) {
        double q[2];
        cs_varady_vertex(v, k, q);
        cen[0] += q[0] / (double)n;
        cen[1] += q[1] / (double)n;
    }
    double ex[2] = {p1[0] - p0[0], p1[1] - p0[1]}, L = sqrt(ex[0] * ex[0] + ex[1] * ex[1]);
    ex[0] /= L, ex[1] /= L;
    double ey[2] = {-ex[1], ex[0]};
    if (par == CS_VARADY_SIDE) {
        /* unit normals (inward) and offsets of the three lines: dist(x) = n . x - c */
        double nm[2], nn[2], cm, cn;
        double a[2] = {p0[0] - pm[0], p0[1] - pm[1]}, la = sqrt(a[0] * a[0] + a[1] * a[1]);
        nm[0] = -a[1] / la, nm[1] = a[0] / la, cm = nm[0] * pm[0] + nm[1] * pm[1];
        double b[2] = {pn[0] - p1[0], pn[1] - p1[1]}, lb = sqrt(b[0] * b[0] + b[1] * b[1]);
        nn[0] = -b[1] / lb, nn[1] = b[0] / lb, cn = nn[0] * p1[0] + nn[1] * p1[1];
        double ci = ey[0] * p0[0] + ey[1] * p0[1];
        /* ey . x = ci + d; ((1 - s) nm - s nn) . x = (1 - s) cm - s cn */
        double r0[2] = {ey[0], ey[1]},
               r1[2] = {(1 - s) * nm[0] - s * nn[0], (1 - s) * nm[1] - s * nn[1]};
        double b0 = ci + d, b1 = (1 - s) * cm - s * cn, det = r0[0] * r1[1] - r0[1] * r1[0];
        out[0] = (b0 * r1[1] - r0[1] * b1) / det;
        out[1] = (r0[0] * b1 - b0 * r1[0]) / det;
    } else if (par == CS_VARADY_RADIAL) {
        double e[2] = {p0[0] + s * (p1[0] - p0[0]), p0[1] + s * (p1[1] - p0[1])}, c[2], dir[2];
        if (meet(pm, p0, p1, pn, c)) {
            dir[0] = c[0] - e[0], dir[1] = c[1] - e[1];
            if (dir[0] * ey[0] + dir[1] * ey[1] < 0) /* the centre lies outside, beyond side i */
                dir[0] = -dir[0], dir[1] = -dir[1];
        } else {
            dir[0] = pm[0] - p0[0], dir[1] = pm[1] - p0[1];
        }
        double l = sqrt(dir[0] * dir[0] + dir[1] * dir[1]);
        out[0] = e[0] + d * dir[0] / l;
        out[1] = e[1] + d * dir[1] / l;
    } else {
        double w1[2] = {pm[0] - p0[0], pm[1] - p0[1]}, w2[2] = {pn[0] - p1[0], pn[1] - p1[1]};
        double l1 = sqrt(w1[0] * w1[0] + w1[1] * w1[1]), l2 = sqrt(w2[0] * w2[0] + w2[1] * w2[1]);
        double w1u = (w1[0] * ex[0] + w1[1] * ex[1]) / l1,
               w1v = (w1[0] * ey[0] + w1[1] * ey[1]) / l1;
        double w2u = (w2[0] * ex[0] + w2[1] * ex[1]) / l2,
               w2v = (w2[0] * ey[0] + w2[1] * ey[1]) / l2;
        double cu = (cen[0] - p0[0]) * ex[0] + (cen[1] - p0[1]) * ex[1];
        double cv = (cen[0] - p0[0]) * ey[0] + (cen[1] - p0[1]) * ey[1];
        double w12v = 0.5 * (w1v + w2v), dc = 2 * cv / (w1v + w2v);
        double w12u = (4 * (cu - 0.5 * L) / dc - w1u - w2u) / 2, m = 1 - s;
        double ru = L * s + (w1u * m * m + 2 * w12u * m * s + w2u * s * s) * d;
        double rv = (w1v * m * m + 2 * w12v * m * s + w2v * s * s) * d;
        out[0] = p0[0] + ru * ex[0] + rv * ey[0];
        out[1] = p0[1] + ru * ex[1] + rv * ey[1];
    }
}

/* Inside the convex polygon (all side distances > margin)? */
static bool inside_by(const cs_varady_t *v, const double x[2], double margin)
{
    for (size_t i = 0; i < v->n; i++) {
        double a[2], b[2];
        cs_varady_vertex(v, i, a);
        cs_varady_vertex(v, (i + 1) % v->n, b);
        if (dist_line(a, b, x[0], x[1]) <= margin)
            return false;
    }
    return true;
}

static bool inside(const cs_varady_t *v, const double x[2])
{
    return inside_by(v, x, 1e-9);
}

/* (s, d) -> point by the forward map -> cs_varady_params -> (s, d) again, for interior points. */
static void test_params_roundtrip(void **state)
{
    (void)state;
    double worst = 0;
    size_t count = 0;
    for (size_t n = 3; n <= 8; n++) {
        cs_bezier_t sides[CS_VARADY_MAX_SIDES];
        loop(n, 2, sides);
        cs_varady_t v;
        assert_int_equal(cs_varady_init(&v, sides, n), CS_OK);
        for (int par = 0; par < 3; par++) {
            cs_varady_set_scheme(&v, CS_VARADY_LAMBDA_KAPPA, (cs_varady_param_t)par);
            for (size_t i = 0; i < n; i++)
                for (int a = 1; a < 16; a++)
                    for (int b = 1; b < 16; b++) {
                        double x[2], s[CS_VARADY_MAX_SIDES], d[CS_VARADY_MAX_SIDES];
                        forward(&v, par, i, a / 16.0, b * 1.5, x);
                        if (!inside(&v, x))
                            continue;
                        cs_varady_params(&v, x[0], x[1], s, d);
                        worst = fmax(worst, fmax(fabs(s[i] - a / 16.0), fabs(d[i] - b * 1.5) / 20));
                        count++;
                    }
        }
    }
    char what[80];
    snprintf(what, sizeof what, "(s, d) round trip through the forward maps, %zu points", count);
    report(what, worst);
    assert_true(count > 2000);
    assert_true(worst < 1e-9);
}

/* CS_SURF_PICTURES=DIR: DIR/varady_params.svg, the domain of tests/data/surfaces/pentagon.txt
 * with side 0's lines of constant s (k / 8) and constant d for the three parametrisations, drawn
 * with the forward maps above. Not a check. */
static void write_param_picture(const char *dir)
{
    static const double pent[5][4][3] = {
        {{20, 0, -4}, {20, 6, -2}, {10, 18, 2}, {6.18, 19.02, 4}},
        {{6.18, 19.02, 4}, {2, 22, 6}, {-12, 14, -2}, {-16.18, 11.76, -4}},
        {{-16.18, 11.76, -4}, {-20, 8, -6}, {-20, -8, 2}, {-16.18, -11.76, 4}},
        {{-16.18, -11.76, 4}, {-12, -14, 6}, {2, -22, -2}, {6.18, -19.02, -4}},
        {{6.18, -19.02, -4}, {10, -18, -6}, {20, -6, -2}, {20, 0, -4}}};
    cs_bezier_t sides[5];
    for (int i = 0; i < 5; i++) {
        cs_vec3_t p[4];
        for (int k = 0; k < 4; k++)
            p[k] = mm(pent[i][k][0], pent[i][k][1], pent[i][k][2]);
        if (cs_bezier_init(&sides[i], 3, p) != CS_OK)
            return;
    }
    cs_varady_t v;
    if (cs_varady_init(&v, sides, 5) != CS_OK)
        return;
    char path[512];
    snprintf(path, sizeof path, "%s/varady_params.svg", dir);
    FILE *f = fopen(path, "w");
    if (!f)
        return;
    double R = 0;
    for (size_t i = 0; i < 5; i++) {
        double p[2];
        cs_varady_vertex(&v, i, p);
        R = fmax(R, sqrt(p[0] * p[0] + p[1] * p[1]));
    }
    double W = 2.3 * R;
    fprintf(f,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"900\" height=\"330\" "
            "viewBox=\"%.3f %.3f %.3f %.3f\">\n<rect x=\"%.3f\" y=\"%.3f\" width=\"%.3f\" "
            "height=\"%.3f\" fill=\"white\"/>\n",
            -1.15 * R, -1.15 * R - 0.25 * R, 3 * W, W + 0.25 * R, -1.15 * R, -1.4 * R, 3 * W,
            W + 0.25 * R);
    for (int par = 0; par < 3; par++) {
        double ox = par * W;
        fprintf(f,
                "<text x=\"%.3f\" y=\"%.3f\" font-size=\"%.3f\" text-anchor=\"middle\">%s</text>\n",
                ox, -1.2 * R, 0.12 * R, param_name[par]);
        fprintf(f, "<polygon fill=\"none\" stroke=\"black\" stroke-width=\"%.3f\" points=\"",
                0.01 * R);
        for (size_t i = 0; i < 5; i++) {
            double p[2];
            cs_varady_vertex(&v, i, p);
            fprintf(f, "%.3f,%.3f ", ox + p[0], -p[1]);
        }
        fprintf(f, "\"/>\n");
        for (int fam = 0; fam < 2; fam++)
            for (int k = 0; k <= 8; k++) {
                fprintf(f, "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"%.3f\" points=\"",
                        fam ? "#c0392b" : "#1f4e9a", 0.008 * R);
                for (int j = 0; j <= 64; j++) {
                    double s = fam ? j / 64.0 : k / 8.0, d = fam ? k * 0.1 * R : j / 64.0 * 1.2 * R;
                    double x[2];
                    forward(&v, par, 0, s, d, x);
                    if (!inside_by(&v, x, -1e-9))
                        break;
                    fprintf(f, "%.3f,%.3f ", ox + x[0], -x[1]);
                }
                fprintf(f, "\"/>\n");
            }
    }
    fprintf(f, "</svg>\n");
    fclose(f);
}

/* Bicubic cells for the ball-end finishing: each patch against the surface at the same
 * parameters (the 9 x 9 samples of the contract, and 33 x 33 reported), the cells tile each quad
 * (areas sum to 1), and each patch's normal Pu x Pv points like the surface's Sx x Sy. */
static double bez3(const cs_patch_t *p, double u, double w, int c)
{
    static const double k[4] = {1, 3, 3, 1};
    double r = 0;
    for (int i = 0; i <= 3; i++)
        for (int j = 0; j <= 3; j++) {
            const cs_vec3_t *q = &p->p[i][j];
            double val = c == 0 ? q->x : c == 1 ? q->y : q->z;
            r += k[i] * pow(u, i) * pow(1 - u, 3 - i) * k[j] * pow(w, j) * pow(1 - w, 3 - j) * val /
                 65536.0;
        }
    return r;
}

static void test_cells(void **state)
{
    (void)state;
    static cs_patch_t out[CS_VARADY_MAX_PATCHES];
    static cs_varady_cell_t cells[CS_VARADY_MAX_PATCHES];
    for (int blend = 0; blend < 2; blend++) {
        cs_bezier_t sides[CS_VARADY_MAX_SIDES];
        loop(5, 4, sides);
        cs_varady_t v;
        assert_int_equal(cs_varady_init(&v, sides, 5), CS_OK);
        cs_varady_set_scheme(&v, (cs_varady_blend_t)blend, CS_VARADY_SIDE);
        size_t count = 0;
        double err = 0, tol = 0.005;
        assert_int_equal(
            cs_varady_patches(&v, tol, out, cells, CS_VARADY_MAX_PATCHES, &count, &err), CS_OK);
        double area[CS_VARADY_MAX_SIDES] = {0}, sampled = 0, dense = 0, worst_dot = 1;
        for (size_t c = 0; c < count; c++) {
            const cs_varady_cell_t *k = &cells[c];
            area[k->quad] += k->w * k->w;
            for (int n = 9; n <= 33; n += 24)
                for (int i = 0; i < n; i++)
                    for (int j = 0; j < n; j++) {
                        double u = i / (n - 1.0), w = j / (n - 1.0), x[2], q[3];
                        cs_varady_quad_point(&v, k->quad, k->a + k->w * u, k->b + k->w * w, x);
                        cs_varady_eval(&v, x[0], x[1], q);
                        double d = sqrt(pow(bez3(&out[c], u, w, 0) - q[0], 2) +
                                        pow(bez3(&out[c], u, w, 1) - q[1], 2) +
                                        pow(bez3(&out[c], u, w, 2) - q[2], 2));
                        if (n == 9)
                            sampled = fmax(sampled, d);
                        else
                            dense = fmax(dense, d);
                    }
            /* orientation at the cell's centre: patch normal vs Sx x Sy (central differences) */
            double x[2], e = 1e-4, px[3], mx[3], py[3], my[3], pu[3], pv[3];
            cs_varady_quad_point(&v, k->quad, k->a + k->w / 2, k->b + k->w / 2, x);
            cs_varady_eval(&v, x[0] + e, x[1], px);
            cs_varady_eval(&v, x[0] - e, x[1], mx);
            cs_varady_eval(&v, x[0], x[1] + e, py);
            cs_varady_eval(&v, x[0], x[1] - e, my);
            for (int a = 0; a < 3; a++) {
                pu[a] = (bez3(&out[c], 0.5 + e, 0.5, a) - bez3(&out[c], 0.5 - e, 0.5, a));
                pv[a] = (bez3(&out[c], 0.5, 0.5 + e, a) - bez3(&out[c], 0.5, 0.5 - e, a));
            }
            double sx[3] = {px[0] - mx[0], px[1] - mx[1], px[2] - mx[2]};
            double sy[3] = {py[0] - my[0], py[1] - my[1], py[2] - my[2]};
            double n1[3] = {pu[1] * pv[2] - pu[2] * pv[1], pu[2] * pv[0] - pu[0] * pv[2],
                            pu[0] * pv[1] - pu[1] * pv[0]};
            double n2[3] = {sx[1] * sy[2] - sx[2] * sy[1], sx[2] * sy[0] - sx[0] * sy[2],
                            sx[0] * sy[1] - sx[1] * sy[0]};
            double dd = (n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2]) /
                        sqrt((n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2]) *
                             (n2[0] * n2[0] + n2[1] * n2[1] + n2[2] * n2[2]));
            worst_dot = fmin(worst_dot, dd);
        }
        char what[96];
        snprintf(what, sizeof what, "%s: %zu cells, 9 x 9 samples (tol %g)",
                 blend ? "lambda/kappa" : "mu", count, tol);
        report(what, sampled);
        snprintf(what, sizeof what, "%s: cells, 33 x 33 samples", blend ? "lambda/kappa" : "mu");
        report(what, dense);
        snprintf(what, sizeof what, "%s: smallest cos(patch normal, surface normal)",
                 blend ? "lambda/kappa" : "mu");
        report(what, worst_dot);
        assert_true(sampled <= tol);
        assert_true(fabs(sampled - err) < 1e-12);
        assert_true(worst_dot > 0);
        for (size_t i = 0; i < 5; i++)
            assert_true(fabs(area[i] - 1) < 1e-12);
    }
    size_t count = 0;
    cs_bezier_t sides[CS_VARADY_MAX_SIDES];
    loop(5, 4, sides);
    cs_varady_t v;
    assert_int_equal(cs_varady_init(&v, sides, 5), CS_OK);
    assert_int_equal(cs_varady_patches(&v, 0.005, out, NULL, 4, &count, NULL), CS_ERR_FULL);
}

/* An uneven pentagon (corners at 0, 50, 150, 200, 290 degrees, alternating heights), so
 * the domain constructions of seed 002 differ. */
static void uneven(cs_bezier_t *sides)
{
    static const double ang[5] = {0, 50, 150, 200, 290};
    const double pi = 3.14159265358979323846;
    cs_vec3_t c[5];
    for (int i = 0; i < 5; i++)
        c[i] = mm(20 * cos(ang[i] * pi / 180), 20 * sin(ang[i] * pi / 180), i % 2 ? 3 : -2);
    for (int i = 0; i < 5; i++) {
        cs_vec3_t p0 = c[i], p3 = c[(i + 1) % 5];
        cs_vec3_t pts[4] = {
            p0, cs_fixed_vec((2 * p0.x + p3.x) / 3, (2 * p0.y + p3.y) / 3, p0.z + 65536),
            cs_fixed_vec((p0.x + 2 * p3.x) / 3, (p0.y + 2 * p3.y) / 3, p3.z - 65536), p3};
        assert_int_equal(cs_bezier_init(&sides[i], 3, pts), CS_OK);
    }
}

/* Side lengths l and interior angles alpha (at vertex i, the start of side i) of a polygon. */
static void shape(size_t n, const double p[][2], double l[], double alpha[])
{
    for (size_t i = 0; i < n; i++) {
        const double *a = p[(i + n - 1) % n], *b = p[i], *c = p[(i + 1) % n];
        l[i] = hypot(c[0] - b[0], c[1] - b[1]);
        double u[2] = {a[0] - b[0], a[1] - b[1]}, w[2] = {c[0] - b[0], c[1] - b[1]};
        alpha[i] = acos((u[0] * w[0] + u[1] * w[1]) / (hypot(u[0], u[1]) * hypot(w[0], w[1])));
    }
}

/* Seed 002's phi_i from the control points: the angle between -(P3 - P2) of side i - 1 and
 * (P1 - P0) of side i (cubic end tangents). */
static double phi(const cs_bezier_t *sides, size_t n, size_t i)
{
    const cs_bezier_t *a = &sides[(i + n - 1) % n], *b = &sides[i];
    double u[3] = {-(double)(a->p[3].x - a->p[2].x), -(double)(a->p[3].y - a->p[2].y),
                   -(double)(a->p[3].z - a->p[2].z)};
    double w[3] = {(double)(b->p[1].x - b->p[0].x), (double)(b->p[1].y - b->p[0].y),
                   (double)(b->p[1].z - b->p[0].z)};
    double d = u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
    return acos(d / (sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]) *
                     sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])));
}

static void test_domains(void **state)
{
    (void)state;
    const double pi = 3.14159265358979323846;
    const size_t n = 5;
    cs_bezier_t sides[5];
    uneven(sides);
    cs_varady_t v;
    assert_int_equal(cs_varady_init(&v, sides, n), CS_OK);
    double p[5][2], l[5], al[5], ca = 0, L[5], target[5];
    for (size_t i = 0; i < n; i++) {
        ca += phi(sides, n, i);
        assert_true(fabs(cs_varady_corner_angle(&v, i) - phi(sides, n, i)) < 1e-12);
        L[i] = v.len[i];
    }
    ca = (double)(n - 2) * pi / ca;
    for (size_t i = 0; i < n; i++)
        target[i] = ca * phi(sides, n, i);
    /* Solution 2: every vertex on one circle, chord i = L_i. */
    assert_int_equal(cs_varady_set_domain(&v, CS_VARADY_DOMAIN_CHORDS), CS_OK);
    for (size_t i = 0; i < n; i++)
        cs_varady_vertex(&v, i, p[i]);
    shape(n, (const double(*)[2])p, l, al);
    double r0 = hypot(p[0][0], p[0][1]);
    for (size_t i = 0; i < n; i++) {
        assert_true(fabs(l[i] - L[i]) < 1e-9 * L[i]);
        assert_true(fabs(hypot(p[i][0], p[i][1]) - r0) < 1e-9 * r0); /* centred on 0 */
    }
    /* Solution 3, transcribed: turtle along L_i turning by pi - c_angle phi_i, the gap e
     * spread as (i / n) e. */
    double q[6][2] = {{0, 0}}, th = 0;
    for (size_t i = 0; i < n; i++) {
        if (i > 0)
            th += pi - target[i];
        q[i + 1][0] = q[i][0] + L[i] * cos(th);
        q[i + 1][1] = q[i][1] + L[i] * sin(th);
    }
    double e[2] = {q[0][0] - q[n][0], q[0][1] - q[n][1]};
    assert_int_equal(cs_varady_set_domain(&v, CS_VARADY_DOMAIN_ANGLES), CS_OK);
    double l3[5], a3[5], f3 = 0;
    for (size_t i = 0; i < n; i++) {
        cs_varady_vertex(&v, i, p[i]);
        assert_true(fabs(p[i][0] - (q[i][0] + (double)i / n * e[0])) < 1e-9);
        assert_true(fabs(p[i][1] - (q[i][1] + (double)i / n * e[1])) < 1e-9);
    }
    shape(n, (const double(*)[2])p, l3, a3);
    for (size_t i = 0; i < n; i++)
        f3 += (l3[i] - L[i]) * (l3[i] - L[i]) + (a3[i] - target[i]) * (a3[i] - target[i]);
    /* Least squares: closed (the polygon's own angles sum to (n - 2) pi), and no worse than
     * solution 3's polygon, which is one of the closed polygons it minimises over. */
    assert_int_equal(cs_varady_set_domain(&v, CS_VARADY_DOMAIN_LSQ), CS_OK);
    for (size_t i = 0; i < n; i++)
        cs_varady_vertex(&v, i, p[i]);
    shape(n, (const double(*)[2])p, l, al);
    double fl = 0, sum = 0;
    for (size_t i = 0; i < n; i++) {
        fl += (l[i] - L[i]) * (l[i] - L[i]) + (al[i] - target[i]) * (al[i] - target[i]);
        sum += al[i];
    }
    assert_true(fabs(sum - 3 * pi) < 1e-9);
    assert_true(fl <= f3 + 1e-12);
    if (getenv("CS_TEST_VERBOSE"))
        printf("domain objective: solution 3 %.6g, least squares %.6g\n", f3, fl);
    /* Every domain interpolates the boundary at the vertices. */
    static const cs_varady_domain_t doms[4] = {CS_VARADY_DOMAIN_ARC, CS_VARADY_DOMAIN_CHORDS,
                                               CS_VARADY_DOMAIN_ANGLES, CS_VARADY_DOMAIN_LSQ};
    for (int k = 0; k < 4; k++) {
        assert_int_equal(cs_varady_set_domain(&v, doms[k]), CS_OK);
        for (size_t i = 0; i < n; i++) {
            double a[2], out[3];
            cs_varady_vertex(&v, i, a);
            cs_varady_eval(&v, a[0], a[1], out);
            cs_ref_vec_t c = cs_ref_from_pos(&sides[i].p[0]);
            assert_true(fabs(out[0] - c.x) + fabs(out[1] - c.y) + fabs(out[2] - c.z) < 1e-9);
        }
    }
    assert_int_equal(cs_varady_set_domain(&v, (cs_varady_domain_t)9), CS_ERR_ARG);
}

/* Seed 002's biquadratic mapping, transcribed: the net of side i (rows t = 0: p_i, midpoint,
 * p_(i+1); t = 2: p_(i-1), centroid (a triangle: its apex), p_(i+2); t = 1: the columns'
 * midpoints), evaluated by
 * Bernstein sums. cs_varady_params' (s_i, d_i / h_i) must map back to the point (the Newton
 * inversion), s = const lines are straight, and the surface still interpolates the boundary. */
static void biq_forward(const double vert[][2], size_t n, size_t i, double s, double t,
                        double out[2])
{
    double c[3][3][2], ce[2] = {0, 0};
    for (size_t k = 0; k < n; k++)
        ce[0] += vert[k][0] / (double)n, ce[1] += vert[k][1] / (double)n;
    const double *rows[2][3] = {
        {vert[i], NULL, vert[(i + 1) % n]},
        {vert[(i + n - 1) % n], n == 3 ? vert[(i + 2) % n] : ce, vert[(i + 2) % n]}};
    for (int x = 0; x < 2; x++) {
        c[0][0][x] = rows[0][0][x], c[2][0][x] = rows[0][2][x];
        c[1][0][x] = (rows[0][0][x] + rows[0][2][x]) / 2;
        for (int a = 0; a < 3; a++) {
            c[a][2][x] = rows[1][a][x];
            c[a][1][x] = (c[a][0][x] + c[a][2][x]) / 2;
        }
    }
    double bs[3] = {(1 - s) * (1 - s), 2 * s * (1 - s), s * s};
    double bt[3] = {(1 - t) * (1 - t), 2 * t * (1 - t), t * t};
    out[0] = out[1] = 0;
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++)
            for (int x = 0; x < 2; x++)
                out[x] += bs[a] * bt[b] * c[a][b][x];
}

static void test_biquadratic(void **state)
{
    (void)state;
    srand(5);
    double worst = 0;
    for (size_t n = 3; n <= 7; n++) {
        cs_bezier_t sides[CS_VARADY_MAX_SIDES];
        loop(n, 4, sides);
        cs_varady_t v;
        assert_int_equal(cs_varady_init(&v, sides, n), CS_OK);
        assert_int_equal(cs_varady_set_scheme(&v, CS_VARADY_LAMBDA_KAPPA, CS_VARADY_BIQUADRATIC),
                         CS_OK);
        double vert[CS_VARADY_MAX_SIDES][2], ce[2] = {0, 0};
        for (size_t i = 0; i < n; i++) {
            cs_varady_vertex(&v, i, vert[i]);
            ce[0] += vert[i][0] / (double)n, ce[1] += vert[i][1] / (double)n;
        }
        for (int k = 0; k < 200; k++) {
            double w[CS_VARADY_MAX_SIDES], sw = 0, x = 0, y = 0;
            for (size_t i = 0; i < n; i++)
                sw += (w[i] = 0.05 + (double)rand() / RAND_MAX);
            for (size_t i = 0; i < n; i++)
                x += w[i] / sw * vert[i][0], y += w[i] / sw * vert[i][1];
            double s[CS_VARADY_MAX_SIDES], d[CS_VARADY_MAX_SIDES];
            cs_varady_params(&v, x, y, s, d);
            for (size_t i = 0; i < n; i++) {
                double h = dist_line(vert[i], vert[(i + 1) % n], ce[0], ce[1]), m[2];
                biq_forward((const double(*)[2])vert, n, i, s[i], d[i] / h, m);
                worst = fmax(worst, hypot(m[0] - x, m[1] - y));
            }
        }
        if (getenv("CS_TEST_VERBOSE"))
            printf("n %zu: worst %g\n", n, worst);
        /* s = const: the straight segment from C(s, 0) to C(s, 1) keeps its s. */
        double a[2], b[2], s[CS_VARADY_MAX_SIDES], d[CS_VARADY_MAX_SIDES];
        biq_forward((const double(*)[2])vert, n, 0, 0.3, 0, a);
        biq_forward((const double(*)[2])vert, n, 0, 0.3, 1, b);
        for (int k = 1; k < 8; k++) {
            double t = k / 8.0 * 0.6;
            cs_varady_params(&v, a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), s, d);
            assert_true(fabs(s[0] - 0.3) < 1e-9);
        }
        /* The boundary: on side i, s is the linear fraction and S the boundary curve. */
        for (size_t i = 0; i < n; i++)
            for (int k = 1; k < 8; k++) {
                double t = k / 8.0, x = vert[i][0] + t * (vert[(i + 1) % n][0] - vert[i][0]);
                double y = vert[i][1] + t * (vert[(i + 1) % n][1] - vert[i][1]), q[3];
                cs_varady_params(&v, x, y, s, d);
                assert_true(fabs(s[i] - t) < 1e-9 && fabs(d[i]) < 1e-9);
                cs_varady_eval(&v, x, y, q);
                cs_ref_vec_t r = cs_ref_eval(&sides[i], t);
                assert_true(fabs(q[0] - r.x) + fabs(q[1] - r.y) + fabs(q[2] - r.z) < 1e-9);
            }
    }
    report("biquadratic mapping: Newton inversion maps back within", worst);
    assert_true(worst < 1e-9);
}

int main(void)
{
    if (getenv("CS_SURF_PICTURES"))
        write_param_picture(getenv("CS_SURF_PICTURES"));
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_interpolation),
        cmocka_unit_test(test_planar),
        cmocka_unit_test(test_curves),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_blends_seed),
        cmocka_unit_test(test_blends_unity),
        cmocka_unit_test(test_lk_reference),
        cmocka_unit_test(test_params),
        cmocka_unit_test(test_schemes_interpolate),
        cmocka_unit_test(test_schemes_curves),
        cmocka_unit_test(test_params_roundtrip),
        cmocka_unit_test(test_cells),
        cmocka_unit_test(test_domains),
        cmocka_unit_test(test_biquadratic),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
