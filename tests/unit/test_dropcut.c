/* test_dropcut: the drop-cutter (host/cs_dropcut) against hand formulas and a brute-force
 * reference written here.
 *  - facet contact on a horizontal and a tilted plane for ball, flat and bull-nose cutters:
 *    ball tip = m x0 + R (sqrt(1 + m^2) - 1); flat tip = m (x0 + R); bull tip =
 *    m (x0 + R - r) + r (sqrt(1 + m^2) - 1) (the torus's tube circle meets the rising direction);
 *  - vertex and edge contact: tip = z - h(d), h the profile at distance d;
 *  - the mesh bound: sampled |S - L| of a bicubic and its triangulation below cs_dropcut_grid_eps;
 *  - gouge-free and tight on random bicubic bumps: the drop is never below the brute-force drop
 *    on dense samples of the exact patch (evaluated here by Bernstein sums), and at most
 *    2 eps + the sampling's own error above it. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_planes),
        cmocka_unit_test(test_vertex_edge),
        cmocka_unit_test(test_grid_eps),
        cmocka_unit_test(test_gouge_free),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
