/* test_ellarc: the promise of the arc tracer (cs_ellarc, what cs_trace runs for the circle and
 * ellipse pieces of cs_arc) against the double-precision reference (cs_ref): every chord within
 * tol of the exact piece (cs_ref_measure, both ways), every vertex within 1 LSB of it, the last
 * vertex exactly Q2, and the chord count of each whole arc within 1.10x of a greedy over the
 * whole arc computed here in double (bisection on the angle, chord deviation by golden-section
 * search, as bench_peers counts it). Corpora: circles and ellipses (1:1, 1:2, 1:20, rotated,
 * non-perpendicular conjugate axes) of radius 0.5 mm .. 2 m at 0.1, 0.01, 0.001 mm and at the
 * least tolerance, random ellipse arcs, tiny pieces (w1 close to 1) and 90-degree ones; what the
 * tracer refuses and cs_trace's dispatch. */
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
#include "cs_ellarc.h"
#include "cs_ref.h"
#include "cs_trace.h"
#include "ref_ellarc.h"

#define MM(v)     ((cs_pos_t)lround((v)*65536.0))
#define MAX_VERTS 200000
#define LSB       CS_REF_LSB_MM

static cs_vec3_t verts[MAX_VERTS];
static uint64_t rng = 0x9E3779B97F4A7C15ull;

static double urand(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

typedef ref_ellarc_t ell_t; /* the arc in mm, and the double reference (tests/support) */

/* The promise for one piece by cs_trace's default (the arc tracer when it takes the piece);
 * returns the chord count, *arc = whether cs_ellarc ran. */
static size_t check_piece(const cs_bezier_t *c, cs_pos_t tol, bool *arc)
{
    static cs_trace_t tr;
    assert_int_equal(cs_trace_begin(&tr, c, tol, CS_TRACE_DEFAULT), CS_OK);
    *arc = tr.impl == CS_TRACE_IMPL_ELLARC;
    size_t n = 0;
    cs_err_t e;
    while (n < MAX_VERTS && (e = cs_trace_next(&tr, &verts[n])) == CS_OK)
        n++;
    assert_int_equal(e, CS_END);
    assert_true(n >= 1);
    assert_memory_equal(&verts[n - 1], &c->p[2], sizeof(cs_vec3_t));
    double dev, verr;
    cs_ref_measure(c, verts, n, &dev, &verr);
    if (!(dev <= tol * LSB) || !(verr <= LSB)) {
        print_error("piece (%d %d) (%d %d) (%d %d) w1 %d: tol %d LSB: deviation %.4f LSB, vertex "
                    "error %.3f LSB (%zu chords, %s)\n",
                    (int)c->p[0].x, (int)c->p[0].y, (int)c->p[1].x, (int)c->p[1].y,
                    (int)c->p[2].x, (int)c->p[2].y, (int)c->w[1], (int)tol, dev / LSB, verr / LSB,
                    n, *arc ? "arc" : "other");
        fail();
    }
    return n;
}

/* Builds the arc e (quantised to LSB) by cs_arc_build, checks every piece at tol; returns the
 * chords, adds to *taken / *pieces the pieces the arc tracer ran / all pieces. */
static size_t check_arc(ell_t *e, cs_pos_t tol, unsigned *taken, unsigned *pieces)
{
    cs_vec3_t C = {MM(e->c[0]), MM(e->c[1]), MM(3)}, U = {MM(e->u[0]), MM(e->u[1]), 0},
              V = {MM(e->v[0]), MM(e->v[1]), 0};
    for (int i = 0; i < 2; i++) /* the reference uses the quantised ellipse */
        e->c[i] = MM(e->c[i]) * LSB, e->u[i] = MM(e->u[i]) * LSB, e->v[i] = MM(e->v[i]) * LSB;
    cs_param_t c1 = (cs_param_t)lround(cos(e->sweep) * CS_PARAM_ONE);
    cs_param_t s1 = (cs_param_t)lround(sin(e->sweep) * CS_PARAM_ONE);
    if (e->sweep >= 2 * M_PI - 1e-12)
        c1 = CS_PARAM_ONE, s1 = 0;
    else /* the reference ends where cs_arc_build does: the quantised direction */
        e->sweep = atan2(s1, c1) + (s1 < 0 ? 2 * M_PI : 0);
    cs_bezier_t seg[CS_ARC_MAX_SEGMENTS];
    unsigned n = 0;
    assert_int_equal(cs_arc_build(&C, &U, &V, CS_PARAM_ONE, 0, c1, s1, true, seg, &n), CS_OK);
    size_t chords = 0;
    for (unsigned k = 0; k < n; k++) {
        bool arc;
        chords += check_piece(&seg[k], tol, &arc);
        *taken += arc;
        (*pieces)++;
    }
    return chords;
}

static const double tols_mm[3] = {0.1, 0.01, 0.001};

/* Circles and ellipses, radius 0.5 mm .. 2 m, aspect 1, 1:2, 1:20, sweeps 30 .. 360 degrees:
 * the promise, chords <= 1.10x the whole-arc greedy over the circles and 1:2 ellipses of each
 * tolerance (<= 1.5x over the 1:20 ones, see docs/fixed-point.md), and the arc tracer running nearly every piece. */
static void test_arcs(void **state)
{
    (void)state;
    static const double radii[] = {0.5, 2, 10, 50, 200, 1000, 2000};
    static const double aspect[] = {1, 0.5, 0.05};
    static const double sweeps[] = {30, 90, 200, 360};
    for (int ti = 0; ti < 3; ti++) {
        size_t chords[3] = {0, 0, 0}, gr[3] = {0, 0, 0};
        unsigned taken = 0, pieces = 0;
        for (size_t ri = 0; ri < sizeof radii / sizeof *radii; ri++)
            for (size_t ai = 0; ai < 3; ai++)
                for (size_t si = 0; si < 4; si++) {
                    double r = radii[ri], q = aspect[ai], rot = 0.3 * (double)si;
                    if (r > 200 && ti > 0 && si > 0)
                        continue; /* keep the double greedy short */
                    ell_t e = {{-r * 0.5, 7}, {r * cos(rot), r * sin(rot)},
                               {-r * q * sin(rot), r * q * cos(rot)}, sweeps[si] * M_PI / 180};
                    chords[ai] += check_arc(&e, MM(tols_mm[ti]), &taken, &pieces);
                    gr[ai] += ref_ellarc_greedy(&e, tols_mm[ti]);
                }
        double ratio = (double)(chords[0] + chords[1]) / (double)(gr[0] + gr[1]);
        double flat = (double)chords[2] / (double)gr[2];
        print_message("tol %g: circles and 1:2 ellipses %zu chords, whole-arc greedy %zu (%.4f); "
                      "1:20 %zu vs %zu (%.4f); arc tracer %u/%u pieces\n",
                      tols_mm[ti], chords[0] + chords[1], gr[0] + gr[1], ratio, chords[2], gr[2],
                      flat, taken, pieces);
        assert_true(ratio <= 1.10);
        assert_true(flat <= 1.5); /* the global overshoot cap (docs/fixed-point.md) costs these */
        assert_true(taken * 10 >= pieces * 9);
    }
}

/* Random ellipse arcs (non-perpendicular conjugate axes, any sweep) at random tolerances down to
 * the least one, 2 m coordinates included: the promise. */
static void test_random(void **state)
{
    (void)state;
    unsigned taken = 0, pieces = 0;
    for (int k = 0; k < 200; k++) {
        double r = exp(log(0.05) + urand() * log(2000 / 0.05)), a = urand() * 6.2832;
        double b = a + 0.3 + urand() * 2.5, q = 0.05 + urand();
        ell_t e = {{(urand() - 0.5) * 1000, (urand() - 0.5) * 1000},
                   {r * cos(a), r * sin(a)},
                   {r * q * cos(b), r * q * sin(b)},
                   0.01 + urand() * 6.27};
        cs_pos_t tol = k % 4 == 0 ? CS_TRACE_TOL_MIN + (cs_pos_t)(k % 3)
                                  : (cs_pos_t)(4 + urand() * MM(0.2));
        check_arc(&e, tol, &taken, &pieces);
    }
    print_message("random: arc tracer %u/%u pieces\n", taken, pieces);
    assert_true(taken * 2 >= pieces);
}

/* Tiny sweeps (w1 within a few units of 2^30, one or two chords), 90-degree pieces and flat
 * ellipses at the least tolerance. */
static void test_tiny(void **state)
{
    (void)state;
    unsigned taken = 0, pieces = 0;
    static const double sweeps[] = {1e-6, 1e-4, 3e-3, 0.05, M_PI / 2};
    for (size_t si = 0; si < 5; si++)
        for (int ri = 0; ri < 4; ri++) {
            double r = ri == 0 ? 0.5 : ri == 1 ? 40 : ri == 2 ? 600 : 2000;
            for (int qi = 0; qi < 2; qi++) {
                ell_t e = {{0, 0}, {r, 0}, {0, qi ? r / 20 : r}, sweeps[si]};
                for (int ti = 0; ti < 3; ti++)
                    check_arc(&e, ti == 0 ? CS_TRACE_TOL_MIN : MM(tols_mm[ti]), &taken, &pieces);
            }
        }
    assert_true(taken > 0);
}

/* What the arc tracer refuses (cs_trace then runs the conic predictor), and the dispatch. */
static void test_refuse(void **state)
{
    (void)state;
    cs_vec3_t C = {0, 0, 0}, U = {MM(10), 0, 0}, V = {0, MM(10), 0};
    cs_bezier_t seg[CS_ARC_MAX_SEGMENTS];
    unsigned n;
    assert_int_equal(cs_arc_build(&C, &U, &V, CS_PARAM_ONE, 0, 0, CS_PARAM_ONE, true, seg, &n),
                     CS_OK);
    assert_int_equal(n, 1u);
    cs_ellarc_t a;
    assert_int_equal(cs_ellarc_begin(&a, &seg[0], MM(0.01)), CS_OK);
    assert_int_equal(cs_ellarc_begin(&a, &seg[0], CS_ELLARC_TOL_MIN - 1), CS_ERR_UNSUPPORTED);
    cs_bezier_t b = seg[0];
    b.p[1].z = 1; /* not planar */
    assert_int_equal(cs_ellarc_begin(&a, &b, MM(0.01)), CS_ERR_UNSUPPORTED);
    b = seg[0];
    b.w[0] = CS_WEIGHT_ONE / 2; /* not in standard form */
    assert_int_equal(cs_ellarc_begin(&a, &b, MM(0.01)), CS_ERR_UNSUPPORTED);
    b = seg[0];
    b.w[1] = CS_WEIGHT_ONE / 2; /* a 120-degree piece */
    assert_int_equal(cs_ellarc_begin(&a, &b, MM(0.01)), CS_ERR_UNSUPPORTED);
    b = seg[0];
    b.rational = false;
    assert_int_equal(cs_ellarc_begin(&a, &b, MM(0.01)), CS_ERR_UNSUPPORTED);
    static cs_trace_t tr;
    assert_int_equal(cs_trace_begin(&tr, &seg[0], MM(0.01), CS_TRACE_DEFAULT), CS_OK);
    assert_int_equal(tr.impl, CS_TRACE_IMPL_ELLARC);
    assert_int_equal(cs_trace_begin(&tr, &b, MM(0.01), CS_TRACE_DEFAULT), CS_OK);
    assert_int_not_equal(tr.impl, CS_TRACE_IMPL_ELLARC);
    /* a full circle of 4 m at the least tolerance needs more than CS_ELLARC_MAX_CHORDS a piece */
    cs_vec3_t U2 = {MM(4000), 0, 0}, V2 = {0, MM(4000), 0};
    assert_int_equal(cs_arc_build(&C, &U2, &V2, CS_PARAM_ONE, 0, 0, CS_PARAM_ONE, true, seg, &n),
                     CS_OK);
    assert_int_equal(cs_ellarc_begin(&a, &seg[0], CS_TRACE_TOL_MIN), CS_ERR_UNSUPPORTED);
    bool arc;
    check_piece(&seg[0], CS_TRACE_TOL_MIN, &arc);
    assert_false(arc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_arcs),
        cmocka_unit_test(test_random),
        cmocka_unit_test(test_tiny),
        cmocka_unit_test(test_refuse),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
