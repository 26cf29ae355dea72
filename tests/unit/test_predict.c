/* test_predict: the promise of the predicted-step tracer (cs_predict, CS_TRACE_PREDICT) against
 * the double-precision reference (cs_ref), at 0.1, 0.01 and 0.001 mm and at the smallest
 * tolerance it takes: every chord within tol of the exact curve (cs_ref_max_deviation, both
 * ways), every vertex within 1 LSB of the curve, the last vertex exactly P_n, and a chord count
 * near the greedy optimum (cs_ref_greedy_count). Corpora: 200 random cubics and 100 random
 * quadratics (xorshift, fixed seed, 200 mm box), the hard cases (cusp, loop, collinear fold,
 * near-equal end points, coincident points, inflection, 2 m curves, worst-case coordinates) and
 * the circular and elliptical arcs of cs_arc (rational quadratics: the conic path). Also: what
 * cs_predict refuses and cs_trace's fallback. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_arc.h"
#include "cs_predict.h"
#include "cs_ref.h"
#include "curve_cases.h"
#include "cs_trace.h"

#define MM(v)     ((cs_pos_t)lround((v)*65536.0))
#define MAX_VERTS 400000
#define LSB       CS_REF_LSB_MM
#define N_TOLS    3

static const double tols_mm[N_TOLS] = {0.1, 0.01, 0.001};
static cs_vec3_t verts[MAX_VERTS];

static uint64_t rng = 0x2545F4914F6CDD1Dull;

/* Traces c with cs_predict directly; returns the final code, *n vertices. */
static cs_err_t run(const cs_bezier_t *c, cs_pos_t tol, size_t *n)
{
    static cs_predict_t p;
    *n = 0;
    cs_err_t e = c->rational ? cs_predict_begin_conic(&p, c, tol) : cs_predict_begin(&p, c, tol);
    if (e != CS_OK)
        return e;
    while (*n < MAX_VERTS && (e = cs_predict_next(&p, &verts[*n])) == CS_OK)
        (*n)++;
    if (e == CS_END) {
        cs_vec3_t dummy;
        assert_int_equal(cs_predict_next(&p, &dummy), CS_END);
    }
    return e;
}

/* Largest distance (mm) of a vertex from the nearest point of the whole curve (4096 samples,
 * then golden-section refinement around the best): the vertex promise without an order.
 * cs_ref_measure places each vertex on the first piece of curve within 2 LSB after the previous
 * one, which near a cusp (the curve retraces itself) may be the other branch; this runs only
 * when that placement reports more than 1 LSB. */
static double nearest_vertex_error(const cs_bezier_t *c, const cs_vec3_t *v, size_t n)
{
    enum { SAMPLES = 4096 };
    double worst = 0;
    for (size_t i = 0; i < n; i++) {
        cs_ref_vec_t p = cs_ref_from_pos(&v[i]);
        double best = HUGE_VAL, bt = 0;
        for (int k = 0; k <= SAMPLES; k++) {
            double d = cs_ref_dist(cs_ref_eval(c, (double)k / SAMPLES), p);
            if (d < best) {
                best = d;
                bt = (double)k / SAMPLES;
            }
        }
        double lo = fmax(0, bt - 1.0 / SAMPLES), hi = fmin(1, bt + 1.0 / SAMPLES);
        for (int k = 0; k < 60; k++) {
            double m1 = lo + (hi - lo) * 0.381966, m2 = hi - (hi - lo) * 0.381966;
            if (cs_ref_dist(cs_ref_eval(c, m1), p) < cs_ref_dist(cs_ref_eval(c, m2), p))
                hi = m2;
            else
                lo = m1;
        }
        best = fmin(best, cs_ref_dist(cs_ref_eval(c, 0.5 * (lo + hi)), p));
        worst = fmax(worst, best);
    }
    return worst;
}

/* The promise for one curve at one tolerance; returns the chord count. */
static size_t check(const cs_bezier_t *c, cs_pos_t tol, const char *what)
{
    size_t n;
    assert_int_equal(run(c, tol, &n), CS_END);
    assert_true(n >= 1);
    assert_memory_equal(&verts[n - 1], &c->p[c->degree], sizeof(cs_vec3_t));
    double dev, verr;
    cs_ref_measure(c, verts, n, &dev, &verr);
    if (cs_ref_collinear_x(c))
        verr = cs_ref_fold_vertex_error(c, verts, n);
    else if (verr > LSB)
        verr = nearest_vertex_error(c, verts, n);
    double tol_mm = tol * LSB;
    if (!(dev <= tol_mm) || !(verr <= LSB)) {
        print_error("%s: tol %g mm: deviation %.9g mm, vertex error %.3g LSB (%zu chords)\n", what,
                    tol_mm, dev, verr / LSB, n);
        fail();
    }
    return n;
}

/* Random cubics and quadratics: the promise, and chords within 1.05x greedy over the set. */
static void test_random(void **state)
{
    (void)state;
    for (unsigned degree = 2; degree <= 3; degree++) {
        size_t nc = degree == 3 ? 200 : 100;
        for (int ti = 0; ti < N_TOLS; ti++) {
            size_t chords = 0, greedy = 0;
            for (size_t k = 0; k < nc; k++) {
                cs_bezier_t c = curve_cases_random(&rng, degree, 100);
                chords += check(&c, MM(tols_mm[ti]), degree == 3 ? "random cubic" : "quadratic");
                greedy += cs_ref_greedy_count(&c, tols_mm[ti]);
            }
            double ratio = (double)chords / (double)greedy;
            if (ratio > 1.05) {
                print_error("degree %u tol %g: %zu chords, greedy %zu (%.3f)\n", degree,
                            tols_mm[ti], chords, greedy, ratio);
                fail();
            }
        }
    }
}

static void test_hard(void **state)
{
    (void)state;
    for (size_t i = 0; i < curve_cases_hard_n; i++) {
        cs_bezier_t c = curve_cases_planar(curve_cases_hard[i].degree, curve_cases_hard[i].p, 3);
        for (int ti = 0; ti < N_TOLS; ti++)
            check(&c, MM(tols_mm[ti]), curve_cases_hard[i].name);
        check(&c, CS_PREDICT_TOL_MIN, curve_cases_hard[i].name);
    }
}

/* Tiny random curves near the LSB grid at the smallest tolerance: the rounding budget. */
static void test_small_tol(void **state)
{
    (void)state;
    for (int k = 0; k < 200; k++) {
        cs_bezier_t c = curve_cases_random(&rng, 3, k < 100 ? 0.05 : 5);
        check(&c, CS_PREDICT_TOL_MIN + (cs_pos_t)(k % 3), "small tolerance");
    }
}

/* Circles and ellipses from cs_arc (rational quadratic pieces: the conic path), at every
 * tolerance: the promise, and chords within 1.05x greedy over the set; the same arcs' cubic
 * approximations (kappa = 0.5523) by the polynomial path. */
static void test_arcs(void **state)
{
    (void)state;
    static const double radii[] = {0.3, 2, 5, 50, 500, 2000};
    static const double aspect[] = {1.0, 0.6, 0.1};
    for (int ti = 0; ti < N_TOLS; ti++) {
        size_t chords = 0, greedy = 0;
        for (size_t ri = 0; ri < sizeof radii / sizeof radii[0]; ri++)
            for (size_t ai = 0; ai < sizeof aspect / sizeof aspect[0]; ai++) {
                double r = radii[ri], q = aspect[ai];
                cs_vec3_t C = {MM(10), MM(-20), MM(1)}, U = {MM(r * 0.8), MM(r * 0.6), 0},
                          V = {MM(-r * 0.6 * q), MM(r * 0.8 * q), 0};
                cs_bezier_t seg[CS_ARC_MAX_SEGMENTS];
                unsigned n = 0;
                /* from 0 to 300 degrees, counter-clockwise: 4 pieces */
                assert_int_equal(cs_arc_build(&C, &U, &V, CS_PARAM_ONE, 0, CS_PARAM_ONE / 2,
                                              -(cs_param_t)(0.8660254 * CS_PARAM_ONE), true, seg,
                                              &n),
                                 CS_OK);
                for (unsigned k = 0; k < n; k++) {
                    assert_true(cs_predict_accepts(&seg[k]));
                    chords += check(&seg[k], MM(tols_mm[ti]), "arc piece");
                    greedy += cs_ref_greedy_count(&seg[k], tols_mm[ti]);
                }
                const double kap = 0.5522847498;
                double p[4][2] = {{r, 0}, {r, kap * r * q}, {kap * r, r * q}, {0, r * q}};
                cs_bezier_t c = curve_cases_planar(3, (const double(*)[2])p, 0);
                check(&c, MM(tols_mm[ti]), "cubic quarter ellipse");
            }
        if ((double)chords > 1.05 * (double)greedy) {
            print_error("arcs tol %g: %zu chords, greedy %zu\n", tols_mm[ti], chords, greedy);
            fail();
        }
    }
}

/* What cs_predict refuses, and cs_trace's fallback to the reach tracer for it. */
static void test_refuse(void **state)
{
    (void)state;
    cs_predict_t p;
    cs_bezier_t c = curve_cases_planar(3, curve_cases_hard[4].p, 0);
    assert_int_equal(cs_predict_begin(&p, &c, CS_PREDICT_TOL_MIN - 1), CS_ERR_TOLERANCE);
    assert_int_equal(cs_predict_begin(&p, &c, CS_PREDICT_TOL_MAX + 1), CS_ERR_TOLERANCE);
    cs_bezier_t d = c;
    d.p[2].z = 5; /* not planar */
    assert_false(cs_predict_accepts(&d));
    assert_int_equal(cs_predict_begin(&p, &d, MM(0.01)), CS_ERR_UNSUPPORTED);
    cs_bezier_t r = c;
    r.rational = true; /* a rational cubic */
    assert_false(cs_predict_accepts(&r));
    static const double hyp[3][2] = {{0, 0}, {10, 10}, {20, 0}};
    cs_bezier_t h = curve_cases_planar(2, hyp, 0);
    h.rational = true;
    h.w[0] = h.w[2] = CS_WEIGHT_ONE / 2; /* w1^2 > w0 w2: a hyperbola arc */
    assert_false(cs_predict_accepts(&h));
    h.w[0] = CS_WEIGHT_ONE / 32; /* a weight below 1/16 */
    h.w[1] = CS_WEIGHT_ONE / 64;
    assert_false(cs_predict_accepts(&h));
    /* A conic goes to cs_predict_begin_conic only, a polynomial curve to cs_predict_begin. */
    cs_bezier_t q = curve_cases_planar(2, hyp, 0);
    q.rational = true;
    q.w[0] = q.w[2] = CS_WEIGHT_ONE;
    q.w[1] = CS_WEIGHT_ONE / 2; /* w1^2 <= w0 w2: an ellipse arc */
    assert_true(cs_predict_accepts(&q));
    assert_int_equal(cs_predict_begin(&p, &q, MM(0.01)), CS_ERR_UNSUPPORTED);
    assert_int_equal(cs_predict_begin_conic(&p, &c, MM(0.01)), CS_ERR_UNSUPPORTED);
    assert_int_equal(cs_predict_begin_conic(&p, &q, MM(0.01)), CS_OK);
    cs_bezier_t big = c;
    big.p[1].x = CS_POS_LIMIT + 1;
    assert_int_equal(cs_predict_begin(&p, &big, MM(0.01)), CS_ERR_RANGE);
    /* cs_trace runs the non-planar curve by the reach tracer, within its promise. */
    static cs_trace_t tr;
    assert_int_equal(cs_trace_begin(&tr, &d, MM(0.01), CS_TRACE_PREDICT), CS_OK);
    assert_int_equal(tr.impl, CS_TRACE_IMPL_SUBDIV_REACH);
    size_t nv = 0;
    cs_err_t e;
    while (nv < MAX_VERTS && (e = cs_trace_next(&tr, &verts[nv])) == CS_OK)
        nv++;
    assert_int_equal(e, CS_END);
    assert_true(cs_ref_max_deviation(&d, verts, nv) <= 0.01);
    assert_int_equal(cs_trace_begin(&tr, &c, MM(0.01), CS_TRACE_DEFAULT), CS_OK);
    assert_int_equal(tr.impl, CS_TRACE_IMPL_PREDICT);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random),    cmocka_unit_test(test_hard),
        cmocka_unit_test(test_small_tol), cmocka_unit_test(test_arcs),
        cmocka_unit_test(test_refuse),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
