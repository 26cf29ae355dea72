/* test_subdiv: the flatness test and the two subdivision tracers. The test is sound (whenever
 * it says flat, the chord P0-Pn is within tol of the curve, measured in double both ways) and
 * tight (a symmetric arch deviates exactly 3/4 of its control points' distance: the test accepts
 * within the rounding budget above that and refuses anything below); interior points that
 * project outside the chord and zero-length chords (loops) are handled; the homogeneous split
 * matches double de Casteljau; the dyadic tracer keeps every chord within tol (0.1, 0.01,
 * 0.001 mm) on random, rational and high-degree curves, and the reach tracer never needs more
 * chords than the dyadic one. */
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
#include "cs_subdiv.h"

#define LSB       CS_REF_LSB_MM
#define MAX_VERTS 100000

static cs_vec3_t verts[MAX_VERTS];
static const double tols_mm[3] = {0.1, 0.01, 0.001};

static uint64_t rng = 0x2545F4914F6CDD1Dull;
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

static cs_bezier_t random_curve(unsigned n, double scale, bool rational)
{
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = (uint8_t)n;
    c.rational = rational;
    for (unsigned i = 0; i <= n; i++) {
        c.p[i].x = (cs_pos_t)lround((unit() * 2 - 1) * scale * 65536);
        c.p[i].y = (cs_pos_t)lround((unit() * 2 - 1) * scale * 65536);
        c.p[i].z = (cs_pos_t)lround((unit() * 2 - 1) * scale * 6553.6);
        c.w[i] =
            rational ? (cs_weight_t)lround((0.05 + 0.95 * unit()) * CS_WEIGHT_ONE) : CS_WEIGHT_ONE;
    }
    return c;
}

static double chord_dev(const cs_bezier_t *c)
{
    return cs_ref_chord_piece_deviation(c, 0.0, 1.0, cs_ref_from_pos(&c->p[0]),
                                        cs_ref_from_pos(&c->p[c->degree]));
}

static void test_flat_sound(void **state)
{
    (void)state;
    rng = 31337;
    int flats = 0;
    for (int k = 0; k < 3000; k++) {
        unsigned n = 2 + (unsigned)(k % 6);
        cs_bezier_t c = random_curve(n, 0.01 + unit(), k % 4 == 3);
        cs_pos_t tol = (cs_pos_t)(CS_SUBDIV_TOL_MIN + (xorshift() % 40000));
        if (cs_subdiv_is_flat(&c, tol)) {
            flats++;
            double d = chord_dev(&c);
            if (!(d <= tol * LSB))
                fail_msg("said flat at tol %d LSB, deviation %.3f LSB (degree %u%s)", tol, d / LSB,
                         n, c.rational ? ", rational" : "");
        }
    }
    print_message("  %d of 3000 random curves flat, all within tol\n", flats);
    assert_true(flats > 300); /* the test is not vacuous */
}

static void test_flat_tight(void **state)
{
    (void)state;
    /* Symmetric arch: B(1/2) is 3/4 d from the chord, and that is the maximum. */
    for (cs_pos_t d = 100; d < 2000000; d = d * 3 + 7) {
        cs_bezier_t c;
        memset(&c, 0, sizeof c);
        c.degree = 3;
        c.p[1] = cs_fixed_vec(20 * 65536, d, 0);
        c.p[2] = cs_fixed_vec(80 * 65536, d, 0);
        c.p[3] = cs_fixed_vec(100 * 65536, 0, 0);
        double dev = chord_dev(&c) / LSB;
        assert_true(fabs(dev - 0.75 * d) <= 0.01);
        cs_pos_t below = (cs_pos_t)floor(dev) - 1;
        cs_pos_t above = (cs_pos_t)ceil(dev) + CS_SUBDIV_SLACK_LSB + 1;
        assert_false(cs_subdiv_is_flat(&c, below));
        assert_true(cs_subdiv_is_flat(&c, above));
    }
}

static void test_flat_outside_and_loops(void **state)
{
    (void)state;
    /* Collinear, folding: the curve overshoots P3 and starts back behind P0; its distance to the
     * chord's line is 0 everywhere, but not to the chord. */
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = 3;
    c.p[1] = cs_fixed_vec(100 * 65536, 0, 0);
    c.p[2] = cs_fixed_vec(-50 * 65536, 0, 0);
    c.p[3] = cs_fixed_vec(10 * 65536, 0, 0);
    double dev = chord_dev(&c) / LSB;
    assert_true(dev > 65536.0); /* it really overshoots by millimetres */
    assert_false(cs_subdiv_is_flat(&c, (cs_pos_t)(dev * 0.999)));
    assert_true(cs_subdiv_is_flat(&c, 80 * 65536)); /* 3/4 of the farthest point, 100-10 mm */
    /* Closed loop: P0 = P3; the chord is a point, the distance is to P0. */
    memset(&c, 0, sizeof c);
    c.degree = 3;
    c.p[1] = cs_fixed_vec(3000, 4000, 0); /* 5000 LSB from P0 */
    c.p[2] = cs_fixed_vec(-3000, 4000, 0);
    dev = chord_dev(&c) / LSB;
    assert_false(cs_subdiv_is_flat(&c, (cs_pos_t)(dev * 0.999)));
    assert_true(cs_subdiv_is_flat(&c, 5000 * 3 / 4 + CS_SUBDIV_SLACK_LSB + 2));
    /* All points equal: flat at any tolerance. */
    memset(&c, 0, sizeof c);
    c.degree = 5;
    assert_true(cs_subdiv_is_flat(&c, CS_SUBDIV_TOL_MIN));
}

/* Homogeneous split against double de Casteljau on the weighted points. */
static void test_split(void **state)
{
    (void)state;
    rng = 5;
    for (int k = 0; k < 200; k++) {
        cs_bezier_t c = random_curve(1 + (unsigned)(k % 7), 4000.0, k % 2 == 0);
        cs_param_t t = (cs_param_t)(xorshift() % (uint64_t)CS_PARAM_ONE);
        double td = t / (double)CS_PARAM_ONE;
        cs_subdiv_hcurve_t h, l, r;
        cs_subdiv_to_homogeneous(&c, &h);
        cs_subdiv_split(&h, c.degree, t, &l, &r);
        /* The left piece's last point and the right piece's first are the curve at t. */
        cs_ref_vec_t e = cs_ref_eval(&c, td);
        cs_vec3_t pl, pr;
        assert_int_equal(cs_subdiv_project(&l.p[c.degree], c.rational, &pl), CS_OK);
        assert_int_equal(cs_subdiv_project(&r.p[0], c.rational, &pr), CS_OK);
        assert_true(pl.x == pr.x && pl.y == pr.y && pl.z == pr.z);
        assert_true(fabs(pl.x - e.x / LSB) <= 0.5 + 1e-3);
        assert_true(fabs(pl.y - e.y / LSB) <= 0.5 + 1e-3);
        assert_true(fabs(pl.z - e.z / LSB) <= 0.5 + 1e-3);
        /* End points survive exactly. */
        cs_vec3_t p0, pn;
        assert_int_equal(cs_subdiv_project(&l.p[0], c.rational, &p0), CS_OK);
        assert_int_equal(cs_subdiv_project(&r.p[c.degree], c.rational, &pn), CS_OK);
        assert_true(p0.x == c.p[0].x && p0.y == c.p[0].y && p0.z == c.p[0].z);
        assert_true(pn.x == c.p[c.degree].x && pn.y == c.p[c.degree].y && pn.z == c.p[c.degree].z);
    }
}

static size_t trace(const cs_bezier_t *c, cs_pos_t tol, bool reach)
{
    static cs_subdiv_t s;
    cs_err_t e = cs_subdiv_begin(&s, c, tol, reach);
    if (e != CS_OK)
        fail_msg("begin: code %d", (int)e);
    size_t n = 0;
    while (n < MAX_VERTS && (e = cs_subdiv_next(&s, &verts[n])) == CS_OK)
        n++;
    if (e != CS_END)
        fail_msg("next: code %d after %zu vertices", (int)e, n);
    assert_true(n <= ((size_t)1 << CS_SUBDIV_MAX_DEPTH));
    const cs_vec3_t *pn = &c->p[c->degree];
    assert_true(verts[n - 1].x == pn->x && verts[n - 1].y == pn->y && verts[n - 1].z == pn->z);
    return n;
}

static void test_tracers(void **state)
{
    (void)state;
    rng = 777;
    size_t total_dyadic = 0, total_reach = 0;
    for (int k = 0; k < 60; k++) {
        unsigned n = k < 30 ? 3 : 1 + (unsigned)(k % 7);
        cs_bezier_t c = random_curve(n, 80.0, k % 3 == 2);
        for (int ti = 0; ti < 3; ti++) {
            cs_pos_t tol = (cs_pos_t)lround(tols_mm[ti] * 65536);
            for (int reach = 0; reach < 2; reach++) {
                size_t nv = trace(&c, tol, reach != 0);
                double dev = cs_ref_max_deviation(&c, verts, nv);
                if (!(dev <= tols_mm[ti]))
                    fail_msg("%s degree %u%s tol %g: deviation %.9g", reach ? "reach" : "dyadic", n,
                             c.rational ? " rational" : "", tols_mm[ti], dev);
                if (reach)
                    total_reach += nv;
                else
                    total_dyadic += nv;
            }
        }
    }
    print_message("  chords: dyadic %zu, reach %zu\n", total_dyadic, total_reach);
    assert_true(total_reach <= total_dyadic);
}

static void test_errors(void **state)
{
    (void)state;
    static cs_subdiv_t s;
    cs_vec3_t v;
    cs_bezier_t c = random_curve(3, 10, false);
    assert_int_equal(cs_subdiv_begin(&s, &c, CS_SUBDIV_TOL_MIN - 1, false), CS_ERR_TOLERANCE);
    assert_int_equal(cs_subdiv_next(&s, &v), CS_END);
    assert_int_equal(cs_subdiv_begin(&s, &c, CS_SUBDIV_TOL_MAX + 1, true), CS_ERR_TOLERANCE);
    c.degree = 0;
    assert_int_equal(cs_subdiv_begin(&s, &c, 100, false), CS_ERR_DEGREE);
    c.degree = 3;
    c.rational = true;
    c.w[2] = CS_WEIGHT_MIN - 1;
    assert_int_equal(cs_subdiv_begin(&s, &c, 100, false), CS_ERR_WEIGHT);
    assert_false(cs_subdiv_is_flat(&c, 100));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flat_sound),
        cmocka_unit_test(test_flat_tight),
        cmocka_unit_test(test_flat_outside_and_loops),
        cmocka_unit_test(test_split),
        cmocka_unit_test(test_tracers),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
