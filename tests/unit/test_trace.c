/* test_trace: the promise of cs_trace, for every method (FD, AFD, SUBDIV) at 0.1, 0.01 and
 * 0.001 mm: every chord of the polyline P0, v1 .. vn lies within tol of the exact curve, measured
 * both ways in double by cs_ref_max_deviation; every vertex is within 1 LSB of the curve; the
 * last vertex is exactly P_n; the vertex count is bounded; bad input is refused with its code.
 * Curves: 200 random cubics (xorshift, fixed seed) and the hard cases (coincident points, cusp,
 * loop, inflection, zero length, collinear and folded, 2 m, 1 um, degrees 1/5/7, rational
 * quadratic quarter circle, rational cubic, worst-case coordinates). */
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
#include "cs_trace.h"

#define MM(v)     ((cs_pos_t)lround((v)*65536.0))
#define MAX_VERTS 200000
#define N_RANDOM  200
#define LSB       CS_REF_LSB_MM
#define N_TOLS    3
#define N_METHODS 3

static const double tols_mm[N_TOLS] = {0.1, 0.01, 0.001};
static const cs_trace_method_t methods[N_METHODS] = {CS_TRACE_FD, CS_TRACE_AFD, CS_TRACE_SUBDIV};
static const char *method_name[N_METHODS] = {"FD", "AFD", "SUBDIV"};

static cs_vec3_t verts[MAX_VERTS];

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static uint64_t xorshift(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}
static double unit(void)
{
    return (double)(xorshift() >> 11) * (1.0 / 9007199254740992.0);
}

static cs_bezier_t make(unsigned degree, const double (*p)[3], const double *w)
{
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = (uint8_t)degree;
    c.rational = w != NULL;
    for (unsigned i = 0; i <= degree; i++) {
        c.p[i] = cs_fixed_vec(MM(p[i][0]), MM(p[i][1]), MM(p[i][2]));
        c.w[i] = w ? (cs_weight_t)lround(w[i] * CS_WEIGHT_ONE) : CS_WEIGHT_ONE;
    }
    return c;
}

/* Runs the tracer to the end; returns the final code (CS_END on success), *n vertices. */
static cs_err_t run(const cs_bezier_t *c, cs_pos_t tol, cs_trace_method_t m, size_t *n)
{
    static cs_trace_t tr;
    *n = 0;
    cs_err_t e = cs_trace_begin(&tr, c, tol, m);
    if (e != CS_OK)
        return e;
    while (*n < MAX_VERTS && (e = cs_trace_next(&tr, &verts[*n])) == CS_OK)
        (*n)++;
    if (e == CS_END) {
        cs_vec3_t dummy;
        assert_int_equal(cs_trace_next(&tr, &dummy), CS_END); /* stays finished */
    }
    return e;
}

/* The promise for one curve, one method, one tolerance. Returns the measured deviation. */
static double check_promise(const cs_bezier_t *c, double tol_mm, int mi, const char *what)
{
    size_t n;
    cs_pos_t tol = MM(tol_mm);
    cs_err_t e = run(c, tol, methods[mi], &n);
    if (e != CS_END)
        fail_msg("%s: %s tol %g: ended with code %d after %zu vertices", what, method_name[mi],
                 tol_mm, (int)e, n);
    assert_true(n >= 1);
    const cs_vec3_t *last = &verts[n - 1], *pn = &c->p[c->degree];
    if (last->x != pn->x || last->y != pn->y || last->z != pn->z)
        fail_msg("%s: %s: last vertex (%d,%d,%d) != P_n (%d,%d,%d)", what, method_name[mi], last->x,
                 last->y, last->z, pn->x, pn->y, pn->z);
    double dev, verr;
    cs_ref_measure(c, verts, n, &dev, &verr);
    if (!(dev <= tol_mm))
        fail_msg("%s: %s tol %g mm: deviation %.9g mm (%zu vertices)", what, method_name[mi],
                 tol_mm, dev, n);
    if (!(verr <= 1.0 * LSB))
        fail_msg("%s: %s tol %g: a vertex is %.3f LSB off the curve", what, method_name[mi], tol_mm,
                 verr / LSB);
    return dev;
}

static void check_all(const cs_bezier_t *c, const char *what)
{
    for (int mi = 0; mi < N_METHODS; mi++)
        for (int ti = 0; ti < N_TOLS; ti++)
            check_promise(c, tols_mm[ti], mi, what);
}

static void test_random_cubics(void **state)
{
    (void)state;
    rng = 0x9E3779B97F4A7C15ull;
    double worst[N_METHODS][N_TOLS] = {{0}};
    for (int k = 0; k < N_RANDOM; k++) {
        double p[4][3];
        double scale = k % 4 == 0 ? 10.0 : 100.0; /* some small, most mid-size */
        for (int i = 0; i < 4; i++)
            for (int a = 0; a < 3; a++)
                p[i][a] = (a == 2 && k % 2) ? 0.0 : (unit() * 2.0 - 1.0) * scale;
        cs_bezier_t c = make(3, p, NULL);
        for (int mi = 0; mi < N_METHODS; mi++)
            for (int ti = 0; ti < N_TOLS; ti++) {
                double d = check_promise(&c, tols_mm[ti], mi, "random cubic");
                if (d > worst[mi][ti])
                    worst[mi][ti] = d;
            }
    }
    for (int mi = 0; mi < N_METHODS; mi++)
        for (int ti = 0; ti < N_TOLS; ti++)
            print_message("  %-6s tol %-6g worst deviation %.3g tol\n", method_name[mi],
                          tols_mm[ti], worst[mi][ti] / tols_mm[ti]);
}

static void test_coincident_points(void **state)
{
    (void)state;
    const double a[4][3] = {{0, 0, 0}, {0, 0, 0}, {50, 20, 0}, {50, 20, 0}};
    const double b[4][3] = {{0, 0, 0}, {30, 40, 5}, {30, 40, 5}, {60, 0, 0}};
    const double c3[4][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {40, 10, 0}};
    cs_bezier_t c = make(3, a, NULL);
    check_all(&c, "P0=P1, P2=P3");
    c = make(3, b, NULL);
    check_all(&c, "P1=P2");
    c = make(3, c3, NULL);
    check_all(&c, "P0=P1=P2");
}

static void test_cusp_loop_inflection(void **state)
{
    (void)state;
    /* B'(1/2) = 3/4 [(P1-P0) + 2(P2-P1) + (P3-P2)] = 0 for this "X" arrangement: a cusp. */
    const double cusp[4][3] = {{0, 0, 0}, {100, 100, 0}, {0, 100, 0}, {100, 0, 0}};
    const double loop[4][3] = {{0, 0, 0}, {150, 100, 0}, {-50, 100, 0}, {100, 0, 0}};
    const double infl[4][3] = {{0, 0, 0}, {33, 50, 0}, {66, -50, 0}, {100, 0, 0}};
    const double closed[4][3] = {{0, 0, 0}, {80, 60, 0}, {-80, 60, 0}, {0, 0, 0}};
    cs_bezier_t c = make(3, cusp, NULL);
    check_all(&c, "cusp");
    c = make(3, loop, NULL);
    check_all(&c, "loop");
    c = make(3, infl, NULL);
    check_all(&c, "inflection");
    c = make(3, closed, NULL);
    check_all(&c, "closed loop P0 = P3");
}

static void test_degenerate(void **state)
{
    (void)state;
    const double zero[4][3] = {{10, 10, 10}, {10, 10, 10}, {10, 10, 10}, {10, 10, 10}};
    const double col[4][3] = {{0, 0, 0}, {30, 0, 0}, {60, 0, 0}, {100, 0, 0}};
    const double fold[4][3] = {{0, 0, 0}, {100, 0, 0}, {20, 0, 0}, {60, 0, 0}};
    const double fold3d[4][3] = {{0, 0, 0}, {90, 90, 90}, {-30, -30, -30}, {40, 40, 40}};
    cs_bezier_t c = make(3, zero, NULL);
    for (int mi = 0; mi < N_METHODS; mi++) {
        size_t n;
        assert_int_equal(run(&c, MM(0.01), methods[mi], &n), CS_END);
        assert_true(n <= 2); /* nothing to trace: one chord of length zero, not thousands */
    }
    check_all(&c, "zero length");
    c = make(3, col, NULL);
    check_all(&c, "collinear");
    c = make(3, fold, NULL);
    check_all(&c, "collinear folding back (P1 beyond P3)");
    c = make(3, fold3d, NULL);
    check_all(&c, "collinear 3D fold");
}

static void test_sizes(void **state)
{
    (void)state;
    const double big[4][3] = {{-1000, -500, 0}, {-300, 900, 50}, {400, -900, -50}, {1000, 500, 0}};
    const double tiny[4][3] = {{5, 5, 0}, {5.0006, 5.0009, 0}, {5.0003, 4.9995, 0}, {5.001, 5, 0}};
    const double worst[4][3] = {
        {-4096, -4096, -4096}, {4096, 4096, 4096}, {-4096, 4096, -4096}, {4096, -4096, 4096}};
    cs_bezier_t c = make(3, big, NULL);
    check_all(&c, "2 m long");
    c = make(3, tiny, NULL);
    check_all(&c, "1 um long");
    c = make(3, worst, NULL);
    check_all(&c, "worst-case coordinates");
}

static void test_degrees(void **state)
{
    (void)state;
    const double line[2][3] = {{-20, 5, 1}, {70, 40, -3}};
    const double d2[3][3] = {{0, 0, 0}, {50, 80, 0}, {100, 0, 10}};
    const double d5[6][3] = {{0, 0, 0},    {20, 60, 5},  {40, -40, 0},
                             {60, 70, -5}, {80, -20, 0}, {100, 10, 0}};
    const double d7[8][3] = {{0, 0, 0},    {10, 80, 0},   {25, -60, 10}, {40, 90, 0},
                             {55, -70, 0}, {70, 60, -10}, {85, -30, 0},  {100, 0, 0}};
    cs_bezier_t c = make(1, line, NULL);
    check_all(&c, "degree 1");
    for (int mi = 0; mi < N_METHODS; mi++) {
        size_t n;
        assert_int_equal(run(&c, MM(0.001), methods[mi], &n), CS_END);
        assert_int_equal(n, 1); /* a line is one chord */
    }
    c = make(2, d2, NULL);
    check_all(&c, "degree 2");
    c = make(5, d5, NULL);
    check_all(&c, "degree 5");
    c = make(7, d7, NULL);
    check_all(&c, "degree 7");
}

static void test_rational(void **state)
{
    (void)state;
    const double quarter[3][3] = {{50, 0, 0}, {50, 50, 0}, {0, 50, 0}};
    const double wq[3] = {1.0, 0.70710678118654752, 1.0};
    const double cub[4][3] = {{0, 0, 0}, {20, 60, 0}, {80, 60, 10}, {100, 0, 0}};
    const double wc[4] = {1.0, 0.4, 0.8, 0.9};
    const double big[3][3] = {{2000, 0, 0}, {2000, 2000, 0}, {0, 2000, 0}};
    cs_bezier_t c = make(2, quarter, wq);
    check_all(&c, "rational quarter circle r = 50 mm");
    /* The quarter circle: every vertex within 1 LSB of radius 50 (the curve really is a
     * circle, so this checks the reference too). */
    size_t n;
    assert_int_equal(run(&c, MM(0.001), CS_TRACE_SUBDIV, &n), CS_END);
    for (size_t i = 0; i < n; i++) {
        double r = hypot(verts[i].x * LSB, verts[i].y * LSB);
        assert_true(fabs(r - 50.0) <= 1.0 * LSB);
    }
    c = make(3, cub, wc);
    check_all(&c, "rational cubic");
    c = make(2, big, wq);
    check_all(&c, "rational quarter circle r = 2 m");
}

static void test_errors(void **state)
{
    (void)state;
    static cs_trace_t tr;
    const double p[4][3] = {{0, 0, 0}, {1, 2, 0}, {2, 2, 0}, {3, 0, 0}};
    cs_bezier_t c = make(3, p, NULL);
    cs_vec3_t v;
    for (int mi = 0; mi < N_METHODS; mi++) {
        cs_trace_method_t m = methods[mi];
        assert_int_equal(cs_trace_begin(&tr, &c, 0, m), CS_ERR_TOLERANCE);
        assert_int_equal(cs_trace_begin(&tr, &c, -5, m), CS_ERR_TOLERANCE);
        assert_int_equal(cs_trace_begin(&tr, &c, CS_TRACE_TOL_MIN - 1, m), CS_ERR_TOLERANCE);
        assert_int_equal(cs_trace_begin(&tr, &c, CS_TRACE_TOL_MAX + 1, m), CS_ERR_TOLERANCE);
        assert_int_equal(cs_trace_next(&tr, &v), CS_END); /* a refused begin leaves it finished */
        cs_bezier_t bad = c;
        bad.degree = 0;
        assert_int_equal(cs_trace_begin(&tr, &bad, MM(0.01), m), CS_ERR_DEGREE);
        bad.degree = 8;
        assert_int_equal(cs_trace_begin(&tr, &bad, MM(0.01), m), CS_ERR_DEGREE);
        bad = c;
        bad.p[2].x = CS_POS_LIMIT + 1;
        assert_int_equal(cs_trace_begin(&tr, &bad, MM(0.01), m), CS_ERR_RANGE);
        bad = c;
        bad.rational = true;
        for (int i = 0; i < 4; i++)
            bad.w[i] = CS_WEIGHT_ONE;
        bad.w[1] = 0;
        assert_int_equal(cs_trace_begin(&tr, &bad, MM(0.01), m), CS_ERR_WEIGHT);
        bad.w[1] = CS_WEIGHT_ONE + 1;
        assert_int_equal(cs_trace_begin(&tr, &bad, MM(0.01), m), CS_ERR_WEIGHT);
    }
    assert_int_equal(cs_trace_begin(&tr, &c, MM(0.01), (cs_trace_method_t)7), CS_ERR_ARG);
    /* The largest accepted tolerance: one chord each (the curve is 3 mm across). */
    for (int mi = 0; mi < N_METHODS; mi++) {
        size_t n;
        assert_int_equal(run(&c, CS_TRACE_TOL_MAX, methods[mi], &n), CS_END);
        assert_int_equal(n, 1);
    }
    /* The smallest accepted tolerance works for every method on a small curve. */
    for (int mi = 0; mi < N_METHODS; mi++) {
        size_t n;
        assert_int_equal(run(&c, CS_TRACE_TOL_MIN * 4, methods[mi], &n), CS_END);
        assert_true(cs_ref_max_deviation(&c, verts, n) <= CS_TRACE_TOL_MIN * 4 * LSB);
    }
}

/* Bounded iteration: the vertex count stays within a proven bound for each method (FD: 2^K from
 * Wang's formula; the adaptive ones never exceed FD's count by more than 2x on these curves). */
static void test_bounded(void **state)
{
    (void)state;
    rng = 12345;
    for (int k = 0; k < 40; k++) {
        double p[4][3];
        for (int i = 0; i < 4; i++)
            for (int a = 0; a < 3; a++)
                p[i][a] = (unit() * 2.0 - 1.0) * 200.0;
        cs_bezier_t c = make(3, p, NULL);
        size_t nfd, nafd, nsd;
        cs_pos_t tol = MM(0.01);
        assert_int_equal(run(&c, tol, CS_TRACE_FD, &nfd), CS_END);
        /* Wang: N = 2^K with K the smallest such that 3/4 M / 4^K <= tol - 1 LSB. */
        double m = 0;
        for (int i = 0; i < 2; i++) {
            double dx = p[i][0] - 2 * p[i + 1][0] + p[i + 2][0];
            double dy = p[i][1] - 2 * p[i + 1][1] + p[i + 2][1];
            double dz = p[i][2] - 2 * p[i + 1][2] + p[i + 2][2];
            m = fmax(m, sqrt(dx * dx + dy * dy + dz * dz));
        }
        double nwang = sqrt(0.75 * m / (0.01 - 16 * LSB));
        assert_true((double)nfd <= 2.0 * nwang + 2.0);
        assert_int_equal(run(&c, tol, CS_TRACE_AFD, &nafd), CS_END);
        assert_int_equal(run(&c, tol, CS_TRACE_SUBDIV, &nsd), CS_END);
        assert_true(nafd <= 2 * nfd);
        assert_true(nsd <= nfd);
    }
}

/* The reference itself, on a case with a closed form: chords of a circle of radius r spanning
 * angle a deviate by the sagitta r (1 - cos(a/2)), and the greedy count for tol is
 * ceil((pi/2) / a_max) with a_max = 2 acos(1 - tol/r). */
static void test_reference(void **state)
{
    (void)state;
    const double r = 50.0;
    const double quarter[3][3] = {{r, 0, 0}, {r, r, 0}, {0, r, 0}};
    const double wq[3] = {1.0, 0.70710678118654752, 1.0};
    cs_bezier_t c = make(2, quarter, wq);
    for (int k = 4; k <= 64; k *= 2) {
        double a = (M_PI / 2) / k;
        for (int i = 1; i <= k; i++)
            verts[i - 1] = cs_fixed_vec(MM(r * cos(i * a)), MM(r * sin(i * a)), 0);
        double dev = cs_ref_max_deviation(&c, verts, (size_t)k);
        double sag = r * (1 - cos(a / 2));
        assert_true(fabs(dev - sag) <= 2 * LSB);
    }
    for (int ti = 0; ti < N_TOLS; ti++) {
        double amax = 2 * acos(1 - tols_mm[ti] / r);
        size_t expect = (size_t)ceil((M_PI / 2) / amax);
        size_t got = cs_ref_greedy_count(&c, tols_mm[ti]);
        assert_true(got == expect || got == expect + 1); /* + 1: the bisection stops short */
    }
    /* A vertex off the curve is caught. */
    verts[0] = cs_fixed_vec(MM(r), MM(1.0), 0);
    verts[1] = c.p[2];
    assert_true(cs_ref_max_deviation(&c, verts, 2) == HUGE_VAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random_cubics),
        cmocka_unit_test(test_coincident_points),
        cmocka_unit_test(test_cusp_loop_inflection),
        cmocka_unit_test(test_degenerate),
        cmocka_unit_test(test_sizes),
        cmocka_unit_test(test_degrees),
        cmocka_unit_test(test_rational),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_bounded),
        cmocka_unit_test(test_reference),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
