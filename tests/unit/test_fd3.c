/* test_fd3: the planar polynomial FD path (cs_fd3: pieces with an exact, not power-of-two, step
 * count) against the double-precision reference (cs_ref), at 0.1, 0.01 and 0.001 mm and at the
 * smallest tolerances: every chord within tol of the exact curve (cs_ref_measure, both ways),
 * every vertex within 0.76 LSB of the curve (the bound of docs/fixed-point.md, "Planar cubic
 * FD"), the last vertex exactly P_n, and the chord count at most the whole curve's exact Wang
 * count (computed here in double; plus one a piece when the curve must be split, each piece's
 * own count being at most its share rounded up) and at most the general FD's power of two. Corpora: 200
 * random cubics, 100 quadratics, lines (xorshift, fixed seed), the hard cases (cusp, loop,
 * collinear folds, near-equal end points, 2 m curves, worst-case coordinates). Also the block
 * loop (cs_fd3_fill gives cs_fd3_next's vertices) and cs_trace's
 * routing: CS_TRACE_FD runs cs_fd3 for planar polynomial curves and cs_fd for the rest. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_fd3.h"
#include "cs_ref.h"
#include "curve_cases.h"
#include "cs_trace.h"

#define MM(v)     ((cs_pos_t)lround((v)*65536.0))
#define MAX_VERTS 200000
#define LSB       CS_REF_LSB_MM
#define N_TOLS    3
/* Vertex bound: 0.5 (rounding) + 0.021 (recurrence, N <= 1024) + 6 * 2^-9 (pieces) per axis. */
#define VERTEX_BOUND_LSB 0.76

static const double tols_mm[N_TOLS] = {0.1, 0.01, 0.001};
static cs_vec3_t verts[MAX_VERTS];

static uint64_t rng = 0x9E3779B97F4A7C15ull;


/* Whole-curve Wang count in double from the control points as stored (LSB):
 * ceil(sqrt(n(n-1)/8 M / (tol - slack))). */
static double wang_count(const cs_bezier_t *c, cs_pos_t tol)
{
    unsigned n = c->degree;
    double m = 0;
    for (unsigned i = 0; i + 2 <= n; i++) {
        double dx = (double)c->p[i].x - 2.0 * c->p[i + 1].x + c->p[i + 2].x;
        double dy = (double)c->p[i].y - 2.0 * c->p[i + 1].y + c->p[i + 2].y;
        m = fmax(m, hypot(dx, dy));
    }
    return ceil(sqrt(n * (n - 1.0) / 8.0 * m / (double)(tol - CS_FD3_SLACK_LSB)));
}

/* The promise for one curve at one tolerance; returns the chord count (0 when cs_fd3 hands
 * the curve back: then it must be one a piece cannot take in CS_FD3_MAX_STEPS). */
static size_t check(const cs_bezier_t *c, cs_pos_t tol, const char *what)
{
    static cs_fd3_t f;
    cs_err_t e = cs_fd3_begin(&f, c, tol);
    if (e == CS_ERR_UNSUPPORTED) {
        /* 2^6 pieces of at most 1024 steps: refused only past 2^16 chords' worth of Wang. */
        assert_true(wang_count(c, tol) > 1024.0 * 8);
        return 0;
    }
    assert_int_equal(e, CS_OK);
    size_t n = 0;
    while (n < MAX_VERTS && (e = cs_fd3_next(&f, &verts[n])) == CS_OK)
        n++;
    assert_int_equal(e, CS_END);
    assert_true(n >= 1);
    assert_memory_equal(&verts[n - 1], &c->p[c->degree], sizeof(cs_vec3_t));
    double dev, verr;
    cs_ref_measure(c, verts, n, &dev, &verr);
    if (cs_ref_collinear_x(c))
        verr = cs_ref_fold_vertex_error(c, verts, n);
    double tol_mm = tol * LSB;
    double wang = wang_count(c, tol);
    if (!(dev <= tol_mm) || !(verr <= VERTEX_BOUND_LSB * LSB) || (double)n > fmax(wang, 1.0) + (1u << CS_FD3_MAX_SPLIT)) {
        print_error("%s: tol %g mm: deviation %.9g mm, vertex error %.3g LSB, %zu chords "
                    "(whole-curve Wang %.0f)\n",
                    what, tol_mm, dev, verr / LSB, n, wang);
        fail();
    }
    return n;
}

static void test_random(void **state)
{
    (void)state;
    for (unsigned degree = 1; degree <= 3; degree++) {
        size_t nc = degree == 3 ? 200 : degree == 2 ? 100 : 20;
        for (int ti = 0; ti < N_TOLS; ti++)
            for (size_t k = 0; k < nc; k++) {
                cs_bezier_t c = curve_cases_random(&rng, degree, 100);
                assert_true(check(&c, MM(tols_mm[ti]), "random") > 0);
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
        check(&c, CS_FD3_SLACK_LSB + 3, curve_cases_hard[i].name);
    }
}

/* Tiny curves near the LSB grid at the smallest tolerances: the rounding budget. */
static void test_small_tol(void **state)
{
    (void)state;
    for (int k = 0; k < 200; k++) {
        cs_bezier_t c = curve_cases_random(&rng, 3, k < 100 ? 0.05 : 5);
        check(&c, CS_TRACE_TOL_MIN + (cs_pos_t)(k % 3), "small tolerance");
    }
}

/* cs_trace's FD: cs_fd3 for planar polynomial curves (never more chords than the general FD's
 * power of two), cs_fd for 3D, rational, and what cs_fd3 refuses; refusals of cs_fd3 itself. */
static void test_routing(void **state)
{
    (void)state;
    static cs_trace_t tr;
    static cs_fd_t g;
    cs_bezier_t c = curve_cases_planar(3, curve_cases_hard[3].p, 0);
    assert_int_equal(cs_trace_begin(&tr, &c, MM(0.01), CS_TRACE_FD), CS_OK);
    assert_int_equal(tr.impl, CS_TRACE_IMPL_FD3);
    size_t n = 0, m = 0;
    cs_vec3_t p;
    while (cs_trace_next(&tr, &p) == CS_OK)
        n++;
    assert_int_equal(cs_fd_begin(&g, &c, MM(0.01)), CS_OK);
    while (cs_fd_next(&g, &p) == CS_OK)
        m++;
    assert_true(n <= m);
    cs_bezier_t d = c;
    d.p[2].z = 5; /* not planar */
    assert_false(cs_fd3_accepts(&d));
    static cs_fd3_t f;
    assert_int_equal(cs_fd3_begin(&f, &d, MM(0.01)), CS_ERR_UNSUPPORTED);
    assert_int_equal(cs_trace_begin(&tr, &d, MM(0.01), CS_TRACE_FD), CS_OK);
    assert_int_equal(tr.impl, CS_TRACE_IMPL_FD);
    cs_bezier_t r = c;
    r.rational = true;
    assert_false(cs_fd3_accepts(&r));
    assert_int_equal(cs_fd3_begin(&f, &c, CS_FD3_SLACK_LSB), CS_ERR_TOLERANCE);
    cs_bezier_t big = c;
    big.p[1].x = CS_POS_LIMIT + 1;
    assert_int_equal(cs_fd3_begin(&f, &big, MM(0.01)), CS_ERR_RANGE);
}

/* cs_fd3_fill (the block loop) yields exactly cs_fd3_next's vertices, whatever the block size. */
static void test_fill(void **state)
{
    (void)state;
    static cs_fd3_t a, b;
    static cs_vec3_t blk[MAX_VERTS];
    for (int k = 0; k < 40; k++) {
        cs_bezier_t c = curve_cases_random(&rng, k % 3 + 1, 100);
        cs_pos_t tol = MM(tols_mm[k % N_TOLS]);
        assert_int_equal(cs_fd3_begin(&a, &c, tol), CS_OK);
        assert_int_equal(cs_fd3_begin(&b, &c, tol), CS_OK);
        size_t n = 0, m = 0, got, max = (size_t)(k % 7) * 5 + 1;
        while (n < MAX_VERTS && cs_fd3_next(&a, &verts[n]) == CS_OK)
            n++;
        while (m + max <= MAX_VERTS && (got = cs_fd3_fill(&b, &blk[m], max)) != 0)
            m += got;
        assert_int_equal(m, n);
        assert_memory_equal(blk, verts, n * sizeof verts[0]);
        assert_int_equal(cs_fd3_fill(&b, blk, max), 0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random),
        cmocka_unit_test(test_hard),
        cmocka_unit_test(test_small_tol),
        cmocka_unit_test(test_routing),
        cmocka_unit_test(test_fill),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
