/* test_varady: Várady n-sided patches (host/cs_varady, seed 002) checked in double: the surface
 * interpolates every boundary curve on its domain side and the corners at the vertices, the
 * mu blends sum to one (a loop in a plane with in-plane tangents gives a planar surface), and
 * the Bézier curves handed to the core stay within the tolerance of the surface (dense check). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_interpolation),
        cmocka_unit_test(test_planar),
        cmocka_unit_test(test_curves),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
