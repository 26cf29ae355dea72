/* test_dropcut: the drop-cutter (host/cs_dropcut) against hand formulas and a brute-force
 * reference written here.
 *  - facet contact on a horizontal and a tilted plane for ball, flat and bull-nose cutters:
 *    ball tip = m x0 + R (sqrt(1 + m^2) - 1); flat tip = m (x0 + R); bull tip =
 *    m (x0 + R - r) + r (sqrt(1 + m^2) - 1) (the torus's tube circle meets the rising direction);
 *  - vertex and edge contact: tip = z - h(d), h the profile at distance d; on a sloped edge (the
 *    top of a vertical blade) against the maximum of z - h(d) along it by golden-section search
 *    written here (200 steps);
 *  - the mesh bound: sampled |S - L| of a bicubic and its triangulation below cs_dropcut_grid_eps;
 *  - gouge-free and tight on random bicubic bumps: the drop is never below the brute-force drop
 *    on dense samples of the exact patch (evaluated here by Bernstein sums), and at most
 *    2 eps + the sampling's own error above it;
 *  - exact on a random triangle soup (small and large, gentle, steep and vertical triangles, the
 *    grid's pyramid several levels deep): a ball's drop against the highest centre height at
 *    which the ball still meets a triangle (bisection on the 3-D point-triangle distance), a flat
 *    end's against the highest point of the triangle within R (vertices, edge-circle crossings,
 *    the rim point up the plane's gradient), both to 1e-7 mm;
 *  - the rest-material fill-in (cs_dcpath_fill) beside a step: a floor, a vertical wall 4 mm
 *    high, a plateau; the ball's drop jumps from 0 to 4 - R at R from the wall. Every chord of
 *    every fill-in pass, sampled 64 times, stays within tol of the drop height written here
 *    (4 - R + sqrt(R^2 - d^2) within R of the wall, 4 over the plateau, 0 beyond), and some pass
 *    stands within tol / 2 of the jump (else the test proves nothing). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_dcpath.h"
#include "cs_dropcut.h"
#include "cs_surffile.h"

/* A triangle big enough to hold any cutter here: the plane z = m x + c over [-100, 100]^2. */
static void plane_mesh(cs_dropcut_mesh_t *ms, double m, double c)
{
    cs_dropcut_init(ms);
    double a[3] = {-100, -100, -100 * m + c}, b[3] = {100, -100, 100 * m + c};
    double d[3] = {100, 100, 100 * m + c}, e[3] = {-100, 100, -100 * m + c};
    assert_int_equal(cs_dropcut_add(ms, a, b, d), CS_OK);
    assert_int_equal(cs_dropcut_add(ms, a, d, e), CS_OK);
    assert_int_equal(cs_dropcut_index(ms, 10), CS_OK);
}

static void test_planes(void **state)
{
    (void)state;
    const double slopes[] = {0, 0.3, 1.0, 2.5};
    const cs_dropcut_tool_t tools[] = {{2, 2}, {3, 0}, {3, 1}, {5, 0.5}};
    for (size_t i = 0; i < sizeof slopes / sizeof slopes[0]; i++) {
        double m = slopes[i];
        cs_dropcut_mesh_t ms;
        plane_mesh(&ms, m, 7);
        for (size_t k = 0; k < sizeof tools / sizeof tools[0]; k++) {
            const cs_dropcut_tool_t *t = &tools[k];
            double x0 = 3.25, y0 = -4.5;
            double want = m * (x0 + t->r_mm - t->c_mm) + 7 + t->c_mm * (sqrt(1 + m * m) - 1);
            bool hit;
            double got = cs_dropcut_drop_exact(&ms, t, x0, y0, &hit);
            assert_true(hit);
            if (fabs(got - want) > 1e-9) {
                printf("slope %g tool R %g r %g: %.12f, want %.12f\n", m, t->r_mm, t->c_mm, got,
                       want);
                fail();
            }
        }
        cs_dropcut_free(&ms);
    }
}

/* A spike (its top vertex at (0, 0, 10), falling 1 mm per mm towards -x) and a ridge along x at
 * z = 10 falling 2 mm per mm on both sides: the cutter beside them rests on the vertex or the
 * edge, tip = 10 - h(d). */
static void test_vertex_edge(void **state)
{
    (void)state;
    const cs_dropcut_tool_t tools[] = {{2, 2}, {3, 0}, {3, 1}};
    for (size_t k = 0; k < 3; k++) {
        const cs_dropcut_tool_t *t = &tools[k];
        cs_dropcut_mesh_t ms;
        cs_dropcut_init(&ms);
        double v[3] = {0, 0, 10}, a[3] = {-10, 5, 0}, b[3] = {-10, -5, 0};
        assert_int_equal(cs_dropcut_add(&ms, v, a, b), CS_OK);
        assert_int_equal(cs_dropcut_index(&ms, 5), CS_OK);
        for (double d = 0.25; d < t->r_mm; d += 0.5) {
            bool hit;
            double got = cs_dropcut_drop_exact(&ms, t, d, 0, &hit);
            double h = d <= t->r_mm - t->c_mm
                           ? 0
                           : t->c_mm - sqrt(t->c_mm * t->c_mm -
                                            (d - t->r_mm + t->c_mm) * (d - t->r_mm + t->c_mm));
            assert_true(hit);
            assert_true(fabs(got - (10 - h)) < 1e-9);
        }
        cs_dropcut_free(&ms);

        cs_dropcut_init(&ms);
        double r0[3] = {-50, 0, 10}, r1[3] = {50, 0, 10};
        double l0[3] = {-50, 5, 0}, l1[3] = {50, 5, 0}, q0[3] = {-50, -5, 0}, q1[3] = {50, -5, 0};
        assert_int_equal(cs_dropcut_add(&ms, r0, r1, l1), CS_OK);
        assert_int_equal(cs_dropcut_add(&ms, r0, l1, l0), CS_OK);
        assert_int_equal(cs_dropcut_add(&ms, r0, q1, r1), CS_OK);
        assert_int_equal(cs_dropcut_add(&ms, r0, q0, q1), CS_OK);
        assert_int_equal(cs_dropcut_index(&ms, 5), CS_OK);
        /* Beside the ridge, beyond where the 2:1 flank could hold the cutter higher. */
        double d = t->r_mm * 0.9;
        bool hit;
        double got = cs_dropcut_drop_exact(&ms, t, 1.5, d, &hit);
        double e = d - t->r_mm + t->c_mm;
        double h = e <= 0 ? 0 : t->c_mm - sqrt(t->c_mm * t->c_mm - e * e);
        assert_true(hit);
        /* The flank may hold the cutter higher than the ridge alone: never lower. */
        assert_true(got >= 10 - h - 1e-9);
        cs_dropcut_free(&ms);
    }
}

/* A vertical blade whose top edge rises m mm per mm along x through (0, 0, 0): the cutter beside
 * it at lateral distance w rests on that edge (the blade's face is vertical, its other edges
 * lower or beyond R), so the drop is the maximum over the edge of z - h(d). */
static double blade_ref(const cs_dropcut_tool_t *t, double m, double x0, double w)
{
    double lo = x0 - sqrt(t->r_mm * t->r_mm - w * w), hi = x0 + sqrt(t->r_mm * t->r_mm - w * w);
    const double g = 0.61803398874989484820;
    for (int k = 0; k < 200; k++) {
        double a = hi - g * (hi - lo), b = lo + g * (hi - lo);
        double fa = m * a - cs_dropcut_profile(t, fmin(hypot(a - x0, w), t->r_mm));
        double fb = m * b - cs_dropcut_profile(t, fmin(hypot(b - x0, w), t->r_mm));
        if (fa < fb)
            lo = a;
        else
            hi = b;
    }
    double s = (lo + hi) / 2;
    return m * s - cs_dropcut_profile(t, fmin(hypot(s - x0, w), t->r_mm));
}

static void test_blade_edge(void **state)
{
    (void)state;
    const cs_dropcut_tool_t tools[] = {{3, 1}, {2, 0.5}, {2, 2}, {3, 0}};
    const double slopes[] = {0.5, 2}, offs[] = {0.5, 1.5, 1.9, 2.6};
    for (size_t i = 0; i < 2; i++) {
        double m = slopes[i];
        cs_dropcut_mesh_t ms;
        cs_dropcut_init(&ms);
        double a[3] = {-50, 0, -50 * m}, b[3] = {50, 0, 50 * m}, c[3] = {50, 0, -50 * m - 100};
        assert_int_equal(cs_dropcut_add(&ms, a, b, c), CS_OK);
        assert_int_equal(cs_dropcut_index(&ms, 5), CS_OK);
        for (size_t k = 0; k < sizeof tools / sizeof tools[0]; k++)
            for (size_t j = 0; j < 4; j++) {
                const cs_dropcut_tool_t *t = &tools[k];
                double x0 = 1.25, w = offs[j] * t->r_mm / 3;
                bool hit;
                double got = cs_dropcut_drop_exact(&ms, t, x0, w, &hit);
                double want = blade_ref(t, m, x0, w);
                assert_true(hit);
                if (fabs(got - want) > 1e-9) {
                    printf("slope %g tool R %g r %g offset %g: %.12f, want %.12f\n", m, t->r_mm,
                           t->c_mm, w, got, want);
                    fail();
                }
            }
        cs_dropcut_free(&ms);
    }
}

/* --- a bicubic in double, independent of the code under test ------------------------------- */

static double bern(int i, double t)
{
    static const double c[4] = {1, 3, 3, 1};
    return c[i] * pow(t, i) * pow(1 - t, 3 - i);
}

static void bicubic(const double p[4][4][3], double u, double v, double out[3])
{
    out[0] = out[1] = out[2] = 0;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            for (int k = 0; k < 3; k++)
                out[k] += bern(i, u) * bern(j, v) * p[i][j][k];
}

static uint32_t rng = 12345;
static double rnd(void)
{
    rng = rng * 1664525u + 1013904223u;
    return (rng >> 8) / 16777216.0;
}

/* A random bump over [0, 30]^2: control points on a grid, heights random in [0, 12]. */
static void random_bump(double p[4][4][3], char *text, size_t cap)
{
    size_t n = (size_t)snprintf(text, cap, "curvestep-surfaces 1\nbezier 3 3\n");
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            p[i][j][0] = 10.0 * i;
            p[i][j][1] = 10.0 * j;
            p[i][j][2] = (i == 0 || i == 3 || j == 0 || j == 3) ? 4 * rnd() : 12 * rnd();
            n += (size_t)snprintf(text + n, cap - n, "%.6f %.6f %.6f\n", p[i][j][0], p[i][j][1],
                                  p[i][j][2]);
        }
}

static void test_grid_eps(void **state)
{
    (void)state;
    for (int trial = 0; trial < 5; trial++) {
        double p[4][4][3], flat[48];
        char text[2048];
        random_bump(p, text, sizeof text);
        memcpy(flat, p, sizeof flat);
        int nu = 7, nv = 5;
        double bound = cs_dropcut_grid_eps(flat, 3, 3, nu, nv), worst = 0;
        /* The two triangles of every cell, sampled at barycentric points. */
        for (int a = 0; a < nu; a++)
            for (int b = 0; b < nv; b++)
                for (int s = 0; s <= 8; s++)
                    for (int q = 0; q <= 8 - s; q++) {
                        double l1 = s / 8.0, l2 = q / 8.0, l0 = 1 - l1 - l2;
                        double u0 = (double)a / nu, u1 = (double)(a + 1) / nu;
                        double v0 = (double)b / nv, v1 = (double)(b + 1) / nv;
                        /* triangle (u0,v0) (u1,v0) (u1,v1) */
                        double u = l0 * u0 + l1 * u1 + l2 * u1, v = l0 * v0 + l1 * v0 + l2 * v1;
                        double S[3], A[3], B[3], C[3];
                        bicubic(p, u, v, S);
                        bicubic(p, u0, v0, A);
                        bicubic(p, u1, v0, B);
                        bicubic(p, u1, v1, C);
                        double d2 = 0;
                        for (int k = 0; k < 3; k++) {
                            double L = l0 * A[k] + l1 * B[k] + l2 * C[k];
                            d2 += (S[k] - L) * (S[k] - L);
                        }
                        worst = fmax(worst, sqrt(d2));
                    }
        if (worst > bound) {
            printf("mesh bound %.6f mm, sampled %.6f mm\n", bound, worst);
            fail();
        }
        assert_true(worst > bound / 20); /* a bound, not a wild overestimate */
    }
}

#define BRUTE_N 600 /* samples a direction: 0.05 mm apart over 30 mm */

/* Dense samples of the exact patch, (BRUTE_N + 1)^2 points. */
static double (*brute_samples(const double p[4][4][3]))[3]
{
    double(*s)[3] = malloc((BRUTE_N + 1) * (BRUTE_N + 1) * sizeof *s);
    assert_non_null(s);
    for (int i = 0; i <= BRUTE_N; i++)
        for (int j = 0; j <= BRUTE_N; j++)
            bicubic(p, (double)i / BRUTE_N, (double)j / BRUTE_N, s[i * (BRUTE_N + 1) + j]);
    return s;
}

/* Brute force: the cutter dropped onto the samples. */
static double brute_drop(const double (*s)[3], const cs_dropcut_tool_t *t, double x, double y)
{
    double best = -HUGE_VAL;
    for (size_t i = 0; i < (BRUTE_N + 1) * (BRUTE_N + 1); i++) {
        double d = hypot(s[i][0] - x, s[i][1] - y);
        if (d <= t->r_mm)
            best = fmax(best, s[i][2] - cs_dropcut_profile(t, d));
    }
    return best;
}

static void test_gouge_free(void **state)
{
    (void)state;
    const cs_dropcut_tool_t tools[] = {{2, 2}, {3, 0}, {3, 1}};
    for (int trial = 0; trial < 3; trial++) {
        double p[4][4][3];
        char text[2048];
        random_bump(p, text, sizeof text);
        cs_surffile_t sf;
        cs_path_diag_t d;
        assert_int_equal(cs_surffile_parse(text, strlen(text), "bump", 1, 0.01, &sf, &d), CS_OK);
        cs_dropcut_mesh_t ms;
        assert_int_equal(cs_dropcut_build(&ms, &sf, 0.005, 0.002, 3), CS_OK);
        assert_true(ms.eps <= 0.005);
        double(*smp)[3] = brute_samples(p);
        for (int k = 0; k < 3; k++)
            for (int q = 0; q < 12; q++) {
                double x = 3 + 24 * rnd(), y = 3 + 24 * rnd();
                bool hit;
                double got = cs_dropcut_drop(&ms, &tools[k], x, y, &hit);
                /* samples 0.05 mm apart: one within 0.035 mm of any point of the patch */
                double want = brute_drop(smp, &tools[k], x, y);
                assert_true(hit);
                if (got < want - 1e-9 || got > want + 2 * ms.eps + 0.05) {
                    printf("tool R %g r %g at (%g, %g): drop %.6f, brute force %.6f, eps %g\n",
                           tools[k].r_mm, tools[k].c_mm, x, y, got, want, ms.eps);
                    fail();
                }
            }
        free(smp);
        cs_dropcut_free(&ms);
        cs_surffile_free(&sf);
    }
}


/* --- a random triangle soup against independent references ---------------------------------- */

#define SOUP_N 3000 /* triangles over [0, 40]^2 */

static void sub3(const double a[3], const double b[3], double o[3])
{
    for (int k = 0; k < 3; k++)
        o[k] = a[k] - b[k];
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Closest point of triangle a b c to p (Ericson, Real-Time Collision Detection, 5.1.5). */
static void closest_on_tri(const double p[3], const double a[3], const double b[3],
                           const double c[3], double q[3])
{
    double ab[3], ac[3], ap[3], bp[3], cp[3];
    sub3(b, a, ab);
    sub3(c, a, ac);
    sub3(p, a, ap);
    double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
    if (d1 <= 0 && d2 <= 0) {
        memcpy(q, a, 3 * sizeof *q);
        return;
    }
    sub3(p, b, bp);
    double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
    if (d3 >= 0 && d4 <= d3) {
        memcpy(q, b, 3 * sizeof *q);
        return;
    }
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        double v = d1 / (d1 - d3);
        for (int k = 0; k < 3; k++)
            q[k] = a[k] + v * ab[k];
        return;
    }
    sub3(p, c, cp);
    double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
    if (d6 >= 0 && d5 <= d6) {
        memcpy(q, c, 3 * sizeof *q);
        return;
    }
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        double w = d2 / (d2 - d6);
        for (int k = 0; k < 3; k++)
            q[k] = a[k] + w * ac[k];
        return;
    }
    double va = d3 * d6 - d5 * d4;
    if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
        double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        for (int k = 0; k < 3; k++)
            q[k] = b[k] + w * (c[k] - b[k]);
        return;
    }
    double den = 1 / (va + vb + vc), v = vb * den, w = vc * den;
    for (int k = 0; k < 3; k++)
        q[k] = a[k] + ab[k] * v + ac[k] * w;
}

static double dist_to_tri(const double p[3], const double t[3][3])
{
    double q[3], d[3];
    closest_on_tri(p, t[0], t[1], t[2], q);
    sub3(p, q, d);
    return sqrt(dot3(d, d));
}

/* The point of the triangle's xy projection nearest (x, y), with the triangle's highest z over
 * it: inside the projection (a non-vertical triangle) its plane's z, else the nearest point of an
 * edge. *d gets the horizontal distance. */
static void nearest_xy(const double t[3][3], double x, double y, double *d, double *z)
{
    double s[3];
    for (int i = 0; i < 3; i++) {
        const double *a = t[i], *b = t[(i + 1) % 3];
        s[i] = (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0]);
    }
    double det =
        (t[1][0] - t[0][0]) * (t[2][1] - t[0][1]) - (t[2][0] - t[0][0]) * (t[1][1] - t[0][1]);
    if (fabs(det) > 1e-9 &&
        ((s[0] >= 0 && s[1] >= 0 && s[2] >= 0) || (s[0] <= 0 && s[1] <= 0 && s[2] <= 0))) {
        double u =
            ((x - t[0][0]) * (t[2][1] - t[0][1]) - (t[2][0] - t[0][0]) * (y - t[0][1])) / det;
        double v =
            ((t[1][0] - t[0][0]) * (y - t[0][1]) - (x - t[0][0]) * (t[1][1] - t[0][1])) / det;
        *d = 0;
        *z = t[0][2] + u * (t[1][2] - t[0][2]) + v * (t[2][2] - t[0][2]);
        return;
    }
    *d = HUGE_VAL;
    for (int i = 0; i < 3; i++) {
        const double *a = t[i], *b = t[(i + 1) % 3];
        double bx = b[0] - a[0], by = b[1] - a[1], l2 = bx * bx + by * by;
        double f = l2 > 0 ? ((x - a[0]) * bx + (y - a[1]) * by) / l2 : 0;
        f = f < 0 ? 0 : f > 1 ? 1 : f;
        double e = hypot(a[0] + f * bx - x, a[1] + f * by - y), ez = a[2] + f * (b[2] - a[2]);
        if (e < *d - 1e-12 || (e <= *d + 1e-12 && ez > *z)) {
            *d = fmin(e, *d);
            *z = ez;
        }
    }
}

/* A ball of radius r dropped at (x, y): for each triangle the vertical line of centres meets the
 * triangle swept by the ball in an interval; its top, found by bisection on the 3-D distance
 * from a centre inside it (over the nearest point in xy) up to one above every vertex. */
static double ref_ball(const double (*tri)[3][3], size_t n, double r, double x, double y)
{
    double best = -HUGE_VAL;
    for (size_t i = 0; i < n; i++) {
        double d, z;
        nearest_xy(tri[i], x, y, &d, &z);
        if (d > r)
            continue;
        double lo = z + sqrt(r * r - d * d);
        double hi = fmax(fmax(tri[i][0][2], tri[i][1][2]), tri[i][2][2]) + r + 1;
        for (int k = 0; k < 200 && hi - lo > 1e-11; k++) {
            double m = (lo + hi) / 2, c[3] = {x, y, m};
            if (dist_to_tri(c, tri[i]) <= r)
                lo = m;
            else
                hi = m;
        }
        best = fmax(best, lo - r);
    }
    return best;
}

/* A flat end of radius r: the highest point of each triangle within r of the axis. z is linear,
 * the region (triangle and disk) convex: the maximum lies at a vertex inside the disk, where an
 * edge crosses the circle, or at the rim point up the plane's gradient when inside the triangle. */
static double ref_flat(const double (*tri)[3][3], size_t n, double r, double x, double y)
{
    double best = -HUGE_VAL;
    for (size_t i = 0; i < n; i++) {
        const double(*t)[3] = tri[i];
        for (int e = 0; e < 3; e++) {
            const double *a = t[e], *b = t[(e + 1) % 3];
            if (hypot(a[0] - x, a[1] - y) <= r)
                best = fmax(best, a[2]);
            double ax = a[0] - x, ay = a[1] - y, bx = b[0] - a[0], by = b[1] - a[1];
            double qa = bx * bx + by * by, qb = 2 * (ax * bx + ay * by),
                   qc = ax * ax + ay * ay - r * r;
            double disc = qb * qb - 4 * qa * qc;
            for (int sg = -1; qa > 0 && disc >= 0 && sg <= 1; sg += 2) {
                double f = (-qb + sg * sqrt(disc)) / (2 * qa);
                if (f >= 0 && f <= 1)
                    best = fmax(best, a[2] + f * (b[2] - a[2]));
            }
        }
        double u[3], v[3];
        sub3(t[1], t[0], u);
        sub3(t[2], t[0], v);
        double nrm[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                         u[0] * v[1] - u[1] * v[0]};
        if (fabs(nrm[2]) < 1e-9 * sqrt(dot3(nrm, nrm)))
            continue; /* vertical: its edges hold the maximum */
        double gx = -nrm[0] / nrm[2], gy = -nrm[1] / nrm[2], gl = hypot(gx, gy), d, z;
        double px = gl > 0 ? x + r * gx / gl : x, py = gl > 0 ? y + r * gy / gl : y;
        nearest_xy(t, px, py, &d, &z);
        if (d == 0)
            best = fmax(best, z);
    }
    return best;
}

static void random_soup(double (*tri)[3][3], size_t n)
{
    for (size_t i = 0; i < n; i++) {
        double cx = 40 * rnd(), cy = 40 * rnd(), s = 0.2 + 2.8 * rnd() * rnd();
        double base = 5 * sin(cx / 5) * cos(cy / 7);
        for (int v = 0; v < 3; v++) {
            tri[i][v][0] = cx + s * (2 * rnd() - 1);
            tri[i][v][1] = cy + s * (2 * rnd() - 1);
            tri[i][v][2] = base + 3 * s * (2 * rnd() - 1);
        }
        if (i % 20 == 0) { /* vertical: the third vertex straight above the first */
            tri[i][2][0] = tri[i][0][0];
            tri[i][2][1] = tri[i][0][1];
            tri[i][2][2] = tri[i][0][2] + s;
        }
    }
}

static void test_soup(void **state)
{
    (void)state;
    double(*tri)[3][3] = malloc(SOUP_N * sizeof *tri);
    assert_non_null(tri);
    random_soup(tri, SOUP_N);
    cs_dropcut_mesh_t ms;
    cs_dropcut_init(&ms);
    for (size_t i = 0; i < SOUP_N; i++)
        assert_int_equal(cs_dropcut_add(&ms, tri[i][0], tri[i][1], tri[i][2]), CS_OK);
    assert_int_equal(cs_dropcut_index(&ms, 0.5), CS_OK);
    assert_true(ms.lev >= 4); /* the branch and bound descends a pyramid, not one level */
    const cs_dropcut_tool_t tools[] = {{2, 2}, {0.5, 0.5}, {1.5, 0}};
    int hits = 0;
    for (size_t k = 0; k < sizeof tools / sizeof tools[0]; k++)
        for (int q = 0; q < 400; q++) {
            const cs_dropcut_tool_t *t = &tools[k];
            double x = -2 + 44 * rnd(), y = -2 + 44 * rnd();
            bool hit;
            double got = cs_dropcut_drop_exact(&ms, t, x, y, &hit);
            double want = t->c_mm > 0 ? ref_ball((const double(*)[3][3])tri, SOUP_N, t->r_mm, x, y)
                                      : ref_flat((const double(*)[3][3])tri, SOUP_N, t->r_mm, x, y);
            hits += hit;
            if (hit != (want > -HUGE_VAL) || (hit && fabs(got - want) > 1e-7)) {
                printf("tool R %g r %g at (%.6f, %.6f): drop %.9f (hit %d), reference %.9f\n",
                       t->r_mm, t->c_mm, x, y, got, hit, want);
                fail();
            }
        }
    assert_true(hits > 1000); /* most queries land on triangles */
    cs_dropcut_free(&ms);
    free(tri);
}

/* --- the fill-in beside a jump of the drop height ------------------------------------------ */

#define STEP_XW 10.0 /* the wall's x; floor z 0 before it, plateau z STEP_H after */
#define STEP_H  4.0

/* The ball's tip dropped onto the step at axis x (written here from the geometry). */
static double step_drop(double r, double x)
{
    double d = STEP_XW - x;
    if (d <= 0)
        return STEP_H;
    return d < r ? STEP_H - r + sqrt(r * r - d * d) : 0;
}

static void test_fill_step(void **state)
{
    (void)state;
    static const char text[] = "curvestep-surfaces 1\n"
                               "bezier 1 1\n 4 2 0  4 8 0\n 10 2 0  10 8 0\n"
                               "bezier 1 1\n 10 2 0  10 8 0\n 10 2 4  10 8 4\n"
                               "bezier 1 1\n 10 2 4  10 8 4\n 14 2 4  14 8 4\n";
    cs_surffile_t sf;
    cs_path_diag_t d;
    assert_int_equal(cs_surffile_parse(text, strlen(text), "step", 1, 0.01, &sf, &d), CS_OK);
    const cs_dropcut_tool_t t = {2, 2};
    const double tol = 0.01, step = 0.05;
    cs_dropcut_mesh_t ms;
    assert_int_equal(cs_dropcut_build(&ms, &sf, tol / 4, tol / 8, t.r_mm), CS_OK);
    assert_true(ms.eps < tol / 4);
    /* The ideal cutter (R + eps) nearest the foot of the wall stands on the floor at the last
     * position of the fill-in's lattice (the region's corner plus multiples of step) short of
     * R + eps from the wall: put one tol / 4 short of it, so that the pass's next drop, tol / 2
     * on, lands past the jump. The region reaches R beyond the window all round (the measure's
     * interior). */
    double x0 = STEP_XW - t.r_mm - ms.eps - tol / 4 - 60 * step;
    cs_dcpath_opts_t o = {.scallop_mm = 0.05, .tol_mm = tol, .box = {x0, 2.2, 12.2, 7.8}, .min_z = 0};
    cs_dcpath_t p;
    cs_dcpath_init(&p);
    /* flagged at the foot of the wall: the fill-in looks within R / 4 of it */
    p.flag = malloc(sizeof *p.flag);
    assert_non_null(p.flag);
    p.flag[0][0] = STEP_XW - 0.6, p.flag[0][1] = 5, p.nflag = p.flagcap = 1;
    size_t added = 0;
    assert_int_equal(cs_dcpath_fill(&p, &ms, &t, &sf, &o, step, true, 1, &added), CS_OK);
    assert_true(added > 0 && p.npass == added);
    double worst = 0;
    size_t beside = 0;
    for (size_t k = 0; k < p.npass; k++) {
        for (size_t i = p.start[k]; i < p.start[k + 1]; i++) {
            const double *a = p.pt[i];
            double z0 = step_drop(t.r_mm, a[0]);
            beside += fabs(step_drop(t.r_mm, a[0] - tol / 2) - z0) > 1 ||
                      fabs(step_drop(t.r_mm, a[0] + tol / 2) - z0) > 1;
            if (i + 1 == p.start[k + 1])
                continue;
            const double *b = p.pt[i + 1];
            for (int j = 0; j <= 64; j++) {
                double f = j / 64.0;
                worst = fmax(worst, step_drop(t.r_mm, a[0] + f * (b[0] - a[0])) -
                                        (a[2] + f * (b[2] - a[2])));
            }
        }
    }
    printf("fill-in beside a step: %zu passes, %zu points within tol / 2 of the jump, deepest "
           "chord %.6f mm under the drop height (tol %g)\n", p.npass, beside, worst, tol);
    assert_true(beside > 0);
    assert_true(worst <= tol);
    cs_dcpath_free(&p);
    cs_dropcut_free(&ms);
    cs_surffile_free(&sf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_planes),
        cmocka_unit_test(test_vertex_edge),
        cmocka_unit_test(test_blade_edge),
        cmocka_unit_test(test_grid_eps),
        cmocka_unit_test(test_gouge_free),
        cmocka_unit_test(test_soup),
        cmocka_unit_test(test_fill_step),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
