/* Unit tests for cs_arclen: lengths and the s -> t table against a double reference (adaptive
 * Gauss-Legendre integration of |B'(t)|, tests/support/ref_bezier) on random curves, cusps, a
 * straight line with uneven control-point spacing, a zero-length curve and a circle arc. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include <cmocka.h>

#include "cs_arclen.h"
#include "ref_bezier.h"

#define MM     CS_POS_ONE_MM
#define UM_TOL ((cs_pos_t)66) /* 1 um = 65.5 LSB */

static cs_bezier_t mk(unsigned deg, const double (*mm)[3])
{
    cs_vec3_t p[CS_BEZIER_MAX_POINTS];
    for (unsigned i = 0; i <= deg; i++)
        p[i] = cs_fixed_vec((cs_pos_t)lround(mm[i][0] * MM), (cs_pos_t)lround(mm[i][1] * MM),
                            (cs_pos_t)lround(mm[i][2] * MM));
    cs_bezier_t c;
    assert_int_equal(cs_bezier_init(&c, deg, p), CS_OK);
    return c;
}

/* largest lookup error seen, as a fraction of the table's stated err */
static double worst_used;

static double ref_len(const cs_bezier_t *c, double t0, double t1)
{
    ref_bezier_t r;
    ref_bezier_from(c, &r);
    return ref_bezier_length(&r, t0, t1);
}

/* length within tol, and the table: s[] against the reference at t = k / N, and lookups at
 * many s against the reference arc length up to the returned t, within tab.err */
static void check_curve(const cs_bezier_t *c, cs_pos_t tol, double *worst_err_ratio)
{
    cs_pos_t len;
    double L = ref_len(c, 0, 1);
    assert_int_equal(cs_arclen_length(c, tol, &len), CS_OK);
    if (fabs(len - L) > tol)
        fail_msg("length %d LSB, reference %.3f, error %.3f > tol %d", len, L, len - L, tol);
    cs_arclen_table_t tab;
    assert_int_equal(cs_arclen_table_build(&tab, c, tol), CS_OK);
    assert_int_equal(tab.s[0], 0);
    assert_true(fabs(tab.length - L) <= tol + 0.5);
    for (int k = 0; k < CS_ARCLEN_TABLE_N; k++)
        assert_true(tab.s[k] <= tab.s[k + 1]);
    for (int k = 1; k <= CS_ARCLEN_TABLE_N; k++) {
        double sk = ref_len(c, 0, (double)k / CS_ARCLEN_TABLE_N);
        assert_true(fabs(tab.s[k] - sk) <= tol + 0.5);
    }
    double worst = 0;
    for (int j = 0; j <= 60; j++) {
        cs_pos_t s = (cs_pos_t)(((int64_t)tab.length * j) / 60);
        cs_param_t t;
        assert_int_equal(cs_arclen_lookup(&tab, s, &t), CS_OK);
        assert_true(t >= 0 && t <= CS_PARAM_ONE);
        double st = ref_len(c, 0, ldexp((double)t, -30));
        double e = fabs(st - s);
        worst = fmax(worst, e);
        if (e > tab.err)
            fail_msg("lookup s = %d: arc length at t is %.3f, error %.3f > err %d", s, st, e,
                     tab.err);
    }
    if (worst_err_ratio)
        *worst_err_ratio = fmax(*worst_err_ratio, tab.err / fmax(L, 1.0));
    worst_used = fmax(worst_used, worst / fmax(tab.err, 1.0));
    cs_param_t t;
    assert_int_equal(cs_arclen_lookup(&tab, -1, &t), CS_ERR_RANGE);
    assert_int_equal(cs_arclen_lookup(&tab, tab.length + 1, &t), CS_ERR_RANGE);
    assert_int_equal(cs_arclen_lookup(&tab, 0, &t), CS_OK);
    assert_int_equal(t, 0);
}

static void test_random_curves(void **state)
{
    (void)state;
    ref_rng_t g;
    ref_rng_seed(&g, 0xA5C1);
    double ratio = 0;
    for (unsigned deg = 1; deg <= 7; deg++) {
        for (int k = 0; k < 6; k++) {
            double p[8][3];
            for (unsigned i = 0; i <= deg; i++)
                for (int a = 0; a < 3; a++)
                    p[i][a] = (ref_rng_unit(&g) - 0.5) * 400.0;
            cs_bezier_t c = mk(deg, (const double(*)[3])p);
            check_curve(&c, UM_TOL, &ratio);
        }
    }
    print_message("random curves: worst table err / length = %.5f; lookups used at most %.3f of "
                  "err\n",
                  ratio, worst_used);
}

static void test_tight_tolerance(void **state)
{
    (void)state;
    /* 1 LSB on a 60 mm cubic: either met (and then within 1 LSB) or CS_ERR_DEPTH */
    const double p[4][3] = {{0, 0, 0}, {20, 30, 0}, {40, -30, 5}, {60, 0, 0}};
    cs_bezier_t c = mk(3, p);
    cs_pos_t len;
    cs_err_t e = cs_arclen_length(&c, 1, &len);
    double L = ref_len(&c, 0, 1);
    print_message("60 mm cubic, tol 1 LSB: %s, length %d, reference %.3f\n",
                  e == CS_OK ? "ok" : "depth", len, L);
    assert_true(e == CS_OK || e == CS_ERR_DEPTH);
    if (e == CS_OK)
        assert_true(fabs(len - L) <= 1.0);
    assert_int_equal(cs_arclen_length(&c, 0, &len), CS_ERR_TOLERANCE);
    /* a loose tolerance is met at once and still right */
    assert_int_equal(cs_arclen_length(&c, MM, &len), CS_OK);
    assert_true(fabs(len - L) <= MM);
}

static void test_cusps(void **state)
{
    (void)state;
    /* P1 = P2 with P1 - P0 and P3 - P2 opposite: B' = 0 at (1-t)/t = sqrt(70/100), the curve
     * runs out to x ~ 58 mm and back */
    const double p1[4][3] = {{0, 0, 0}, {100, 0, 0}, {100, 0, 0}, {30, 0, 0}};
    /* the classic planar cusp: B'(1/2) = 0 */
    const double p2[4][3] = {{0, 0, 0}, {100, 50, 0}, {0, 50, 0}, {100, 0, 0}};
    cs_bezier_t a = mk(3, p1), b = mk(3, p2);
    ref_bezier_t r;
    double d[3];
    ref_bezier_from(&b, &r);
    ref_bezier_deriv(&r, 0.5, d);
    assert_true(fabs(d[0]) < 1e-6 && fabs(d[1]) < 1e-6);
    check_curve(&a, UM_TOL, NULL);
    check_curve(&b, UM_TOL, NULL);
    /* the turning curve: length = out + back, known in closed form from x(t) */
    double tc = 1.0 / (1.0 + sqrt(0.7)), xmax;
    {
        double q[3];
        ref_bezier_from(&a, &r);
        ref_bezier_eval(&r, tc, q);
        xmax = q[0];
    }
    cs_pos_t len;
    assert_int_equal(cs_arclen_length(&a, UM_TOL, &len), CS_OK);
    assert_true(fabs(len - (xmax + (xmax - 30 * MM))) <= UM_TOL);
}

static void test_uneven_line(void **state)
{
    (void)state;
    const double p[4][3] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {100, 0, 0}};
    cs_bezier_t c = mk(3, p);
    cs_pos_t len;
    assert_int_equal(cs_arclen_length(&c, UM_TOL, &len), CS_OK);
    assert_true(labs(len - 100 * MM) <= UM_TOL);
    double ratio = 0;
    check_curve(&c, UM_TOL, &ratio);
    print_message("uneven line: table err / length = %.5f\n", ratio);
    /* in 3D, diagonal */
    const double q[3][3] = {{-50, -50, -50}, {49, 49, 49}, {50, 50, 50}};
    cs_bezier_t d = mk(2, q);
    assert_int_equal(cs_arclen_length(&d, UM_TOL, &len), CS_OK);
    assert_true(fabs(len - 100 * sqrt(3.0) * MM) <= UM_TOL + 1);
    check_curve(&d, UM_TOL, NULL);
}

static void test_zero_length(void **state)
{
    (void)state;
    const double p[4][3] = {{7, 8, 9}, {7, 8, 9}, {7, 8, 9}, {7, 8, 9}};
    cs_bezier_t c = mk(3, p);
    cs_pos_t len = -1;
    assert_int_equal(cs_arclen_length(&c, 1, &len), CS_OK);
    assert_int_equal(len, 0);
    cs_arclen_table_t tab;
    assert_int_equal(cs_arclen_table_build(&tab, &c, 1), CS_OK);
    assert_int_equal(tab.length, 0);
    cs_param_t t;
    assert_int_equal(cs_arclen_lookup(&tab, 0, &t), CS_OK);
    assert_int_equal(t, 0);
    assert_int_equal(cs_arclen_lookup(&tab, 1, &t), CS_ERR_RANGE);
}

static void test_rational_arc(void **state)
{
    (void)state;
    const int32_t R = 80 * MM;
    cs_vec3_t p[3] = {{R, 0, 0}, {R, R, 0}, {0, R, 0}};
    cs_weight_t w[3] = {CS_WEIGHT_ONE, (cs_weight_t)lround(ldexp(sqrt(0.5), 30)), CS_WEIGHT_ONE};
    cs_bezier_t c;
    assert_int_equal(cs_bezier_init_rational(&c, 2, p, w), CS_OK);
    cs_pos_t len;
    assert_int_equal(cs_arclen_length(&c, UM_TOL, &len), CS_OK);
    /* a quarter circle: pi R / 2 (w1 rounded to Q30 moves the curve by < R 2^-30) */
    assert_true(fabs(len - M_PI * R / 2) <= UM_TOL);
    double ratio = 0;
    check_curve(&c, UM_TOL, &ratio);
    print_message("quarter circle (rational): table err / length = %.5f\n", ratio);
}

static void test_bad_args(void **state)
{
    (void)state;
    const double p[2][3] = {{0, 0, 0}, {1, 0, 0}};
    cs_bezier_t c = mk(1, p);
    cs_pos_t len;
    cs_arclen_table_t tab;
    assert_int_equal(cs_arclen_length(&c, -5, &len), CS_ERR_TOLERANCE);
    assert_int_equal(cs_arclen_table_build(&tab, &c, 0), CS_ERR_TOLERANCE);
    c.degree = 0;
    assert_int_equal(cs_arclen_length(&c, 10, &len), CS_ERR_DEGREE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random_curves), cmocka_unit_test(test_tight_tolerance),
        cmocka_unit_test(test_cusps),         cmocka_unit_test(test_uneven_line),
        cmocka_unit_test(test_zero_length),   cmocka_unit_test(test_rational_arc),
        cmocka_unit_test(test_bad_args),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
