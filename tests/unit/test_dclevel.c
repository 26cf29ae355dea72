/* test_dclevel: the waterline's level step by slope (host/cs_dclevel) against the closed forms
 * written here, in the vertical section across two contours dz apart on a plane of slope theta:
 *  - ball R: contacts s = dz / sin(theta) apart along the plane, cusp R - sqrt(R^2 - (s / 2)^2);
 *  - flat end R: a terrace whose corner lies dz cos(theta) from the plane while the xy gap
 *    dz / tan(theta) is at most 2R, nothing cuts between the two beyond it;
 *  - bull-nose (R, r) on steep ground with close levels: both contacts and the cusp on the
 *    corner arcs, so the ball r's cusp;
 *  - the table: the ball's entries within 10 % of sin(theta) 2 sqrt(2RH - H^2) and at most it
 *    up to 70 degrees (steeper, the shank above the ball's centre, part of the cutter's solid as
 *    in the check, cuts the top of the cusp: the section allows more than the formula),
 *    non-decreasing, 0 on level ground.
 * The section's own errors: the normal is stepped in cap / 96, the gap sampled at 49 points. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "cs_dclevel.h"

#define RAD(d) ((d) * M_PI / 180)

static double cusp(double r, double s)
{
    return r - sqrt(r * r - s * s / 4);
}

static void test_ball(void **state)
{
    (void)state;
    cs_dropcut_tool_t t = {1.5, 1.5};
    const double th[3] = {20, 45, 70}, dz[3] = {0.2, 0.5, 0.8}, cap = 0.2;
    for (int a = 0; a < 3; a++)
        for (int k = 0; k < 3; k++) {
            double want = cusp(1.5, dz[k] / sin(RAD(th[a])));
            double got = cs_dclevel_left(&t, RAD(th[a]), dz[k], cap);
            assert_true(got >= fmin(want, cap) - 1e-3 && got <= fmin(want, cap) + 2 * cap / 96);
        }
}

static void test_flat(void **state)
{
    (void)state;
    cs_dropcut_tool_t t = {1.5, 0};
    double cap = 0.2;
    for (int a = 1; a <= 8; a++) {
        double th = RAD(10 * a), dz = 0.05 + 0.01 * a, got = cs_dclevel_left(&t, th, dz, cap);
        double want = dz / tan(th) <= 3 ? dz * cos(th) : cap;
        assert_true(got >= want - 1e-3 && got <= want + 2 * cap / 96);
    }
    /* 2 degrees, dz 0.2: 5.7 mm apart in xy, more than the diameter: uncut */
    assert_true(cs_dclevel_left(&t, RAD(2), 0.2, cap) == cap);
}

static void test_bull(void **state)
{
    (void)state;
    cs_dropcut_tool_t t = {1.5, 0.5};
    double th = RAD(80), dz = 0.2, cap = 0.1;
    double want = cusp(0.5, dz / sin(th)), got = cs_dclevel_left(&t, th, dz, cap);
    assert_true(got >= want - 1e-3 && got <= want + 2 * cap / 96);
}

static void test_table(void **state)
{
    (void)state;
    cs_dropcut_tool_t t = {2, 2};
    double h = 0.05, w = 2 * sqrt(2 * 2 * h - h * h);
    cs_dclevel_t tab;
    cs_dclevel_table(&tab, &t, h, w);
    assert_true(tab.dz[0] == 0);
    for (int a = 1; a < CS_DCLEVEL_NANG; a++) {
        double f = w * sin(RAD(fmin(2.0 * a, 89.5)));
        assert_true(tab.dz[a] >= tab.dz[a - 1]);
        assert_true((2 * a > 70 || tab.dz[a] <= f + 1e-9) && tab.dz[a] >= 0.9 * f);
    }
    /* the lookup rounds the angle down: 31 degrees reads the 30-degree entry */
    assert_true(cs_dclevel_at(&tab, tan(RAD(31))) == tab.dz[15]);
    assert_true(cs_dclevel_at(&tab, 0) == 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ball),
        cmocka_unit_test(test_flat),
        cmocka_unit_test(test_bull),
        cmocka_unit_test(test_table),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
