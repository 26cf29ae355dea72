/* test_sphere: the exact sphere (host/cs_sphere, seed 000's S(u, w) = C + r (cos u cos w,
 * cos u sin w, sin u)): every parallel and meridian piece lies on the implicit sphere
 * |X - C|^2 = (r + off)^2 within the arcs' 2 LSB (cs_arc.h), at its latitude / longitude, with
 * the expected ends; the closed-form scallop against a brute-force scan of the two balls along
 * the bisecting ray; the pass step against its definition; the surfaces file's keyword. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_ref.h"
#include "cs_sphere.h"
#include "cs_surffile.h"

#define LSB       CS_REF_LSB_MM
#define ON_SPHERE (2 * LSB + 1e-9) /* cs_arc_build: every point within 2 LSB of the ellipse */

static const cs_sphere_t S = {{10, -20, 5}, 25};

static double dist_c(cs_ref_vec_t p)
{
    return sqrt((p.x - S.c[0]) * (p.x - S.c[0]) + (p.y - S.c[1]) * (p.y - S.c[1]) +
                (p.z - S.c[2]) * (p.z - S.c[2]));
}

static void test_parallels_meridians(void **state)
{
    (void)state;
    double worst = 0;
    cs_bezier_t a[CS_ARC_MAX_SEGMENTS];
    unsigned n = 0;
    for (int k = -8; k <= 8; k++) {
        double lat = k * 10.5, off = k % 2 ? 3 : 0, rho = S.r + off;
        assert_int_equal(cs_sphere_parallel(&S, off, lat, a, &n), CS_OK);
        assert_int_equal(n, 4);
        for (unsigned i = 0; i < n; i++)
            for (int s = 0; s <= 16; s++) {
                cs_ref_vec_t p = cs_ref_eval(&a[i], s / 16.0);
                worst = fmax(worst, fabs(dist_c(p) - rho));
                assert_true(fabs(dist_c(p) - rho) <= ON_SPHERE);
                /* latitude: z = c_z + rho sin(lat) */
                assert_true(fabs(p.z - S.c[2] - rho * sin(lat * M_PI / 180)) <= ON_SPHERE);
            }
        /* starts at longitude 0 and closes */
        cs_ref_vec_t p0 = cs_ref_eval(&a[0], 0), p1 = cs_ref_eval(&a[3], 1);
        assert_true(fabs(p0.y - S.c[1]) <= LSB && p0.x > S.c[0]);
        assert_true(cs_ref_dist(p0, p1) <= LSB);
        double lon = k * 40.0, lat0 = -90 + (k + 8) * 5.0, lat1 = 90 - (k + 8) * 3.0;
        if (lat0 == lat1)
            continue;
        assert_int_equal(cs_sphere_meridian(&S, off, lon, lat0, lat1, a, &n), CS_OK);
        for (unsigned i = 0; i < n; i++)
            for (int s = 0; s <= 16; s++) {
                cs_ref_vec_t p = cs_ref_eval(&a[i], s / 16.0);
                assert_true(fabs(dist_c(p) - rho) <= ON_SPHERE);
                /* in the meridian plane: (p - c) . (-sin lon, cos lon, 0) = 0 */
                double lr = lon * M_PI / 180;
                assert_true(fabs(-(p.x - S.c[0]) * sin(lr) + (p.y - S.c[1]) * cos(lr)) <=
                            ON_SPHERE);
            }
        cs_ref_vec_t e0 = cs_ref_eval(&a[0], 0), e1 = cs_ref_eval(&a[n - 1], 1);
        assert_true(fabs(e0.z - S.c[2] - rho * sin(lat0 * M_PI / 180)) <= ON_SPHERE);
        assert_true(fabs(e1.z - S.c[2] - rho * sin(lat1 * M_PI / 180)) <= ON_SPHERE);
    }
    if (getenv("CS_TEST_VERBOSE"))
        printf("sphere iso-curves: worst %.3f LSB off the sphere\n", worst / LSB);
    assert_int_equal(cs_sphere_parallel(&S, 0, 90, a, &n), CS_ERR_RANGE);
    assert_int_equal(cs_sphere_meridian(&S, 0, 0, 10, 10, a, &n), CS_ERR_RANGE);
    cs_sphere_t big = {{4000, 0, 0}, 200};
    assert_int_equal(cs_sphere_parallel(&big, 0, 0, a, &n), CS_ERR_RANGE);
}

/* Brute force: going out along the bisecting ray from the sphere (r) in steps of 1e-6 mm, the
 * first point inside either ball (centres on r + R, dtheta apart). */
static double scan_scallop(double r, double ball, double dtheta)
{
    double big = r + ball;
    double c[2] = {big * sin(dtheta / 2), big * cos(dtheta / 2)}; /* the other is (-c0, c1) */
    for (double t = r; t < r + ball; t += 1e-6)
        if (hypot(c[0], t - c[1]) <= ball)
            return t - r;
    return HUGE_VAL;
}

static void test_scallop(void **state)
{
    (void)state;
    static const double cases[][3] = {{25, 3, 0.05}, {25, 3, 0.2}, {5, 1, 0.3}, {100, 6, 0.02}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        double r = cases[i][0], R = cases[i][1], d = cases[i][2];
        double h = cs_sphere_scallop(r, R, d), b = scan_scallop(r, R, d);
        assert_true(fabs(h - b) <= 2e-6);
        double step = cs_sphere_step(r, R, 0.01);
        assert_true(cs_sphere_scallop(r, R, step) <= 0.01 + 1e-12);
        assert_true(cs_sphere_scallop(r, R, step * 1.001) > 0.01);
    }
    assert_true(cs_sphere_scallop(25, 3, 0) == 0);
    assert_true(isinf(cs_sphere_scallop(25, 1, 1.0))); /* passes too far apart to meet */
}

static void test_keyword(void **state)
{
    (void)state;
    const char *ok = "curvestep-surfaces 1\n# ball\nsphere 1 2 3 4\n";
    cs_surffile_t sf;
    cs_path_diag_t d;
    assert_int_equal(cs_surffile_parse(ok, strlen(ok), "s", 2.0, 0.01, &sf, &d), CS_OK);
    assert_int_equal(sf.n, 1);
    assert_true(sf.items[0].sphere);
    assert_int_equal(sf.items[0].line, 3);
    assert_true(sf.items[0].sph.c[0] == 2 && sf.items[0].sph.c[2] == 6 && sf.items[0].sph.r == 8);
    cs_surffile_free(&sf);
    const char *bad = "curvestep-surfaces 1\nsphere 1 2 3 0\n";
    assert_int_equal(cs_surffile_parse(bad, strlen(bad), "s", 1, 0.01, &sf, &d), CS_ERR_RANGE);
    assert_int_equal(d.loc.line, 2);
    assert_int_equal(d.loc.col, 14); /* the radius */
    cs_surffile_free(&sf);
    const char *far = "curvestep-surfaces 1\nsphere 4000 0 0 100\n";
    assert_int_equal(cs_surffile_parse(far, strlen(far), "s", 1, 0.01, &sf, &d), CS_ERR_RANGE);
    assert_non_null(strstr(d.reason, "inside"));
    cs_surffile_free(&sf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parallels_meridians),
        cmocka_unit_test(test_scallop),
        cmocka_unit_test(test_keyword),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
