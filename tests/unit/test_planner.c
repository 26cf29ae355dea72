/* Tests of cs_planner: ring capacity, soft limits, per-axis feed limits, junction speeds (Grbl's
 * junction deviation at a corner, no slow-down on collinear chords, the curvature rule on a
 * flattened circle) and the reverse/forward pass invariants, each against a double reference. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

#include "cs_machine_ini.h"
#include "cs_planner.h"

#define Q16 65536.0
#define Q32 4294967296.0

static cs_machine_t machine;

static int setup(void **state)
{
    (void)state;
    cs_machine_ini_default(&machine);
    return 0;
}

static cs_err_t line_mm(cs_planner_t *pl, double x, double y, double z, double feed)
{
    cs_pos_t t[CS_AXES] = {(cs_pos_t)lround(x * Q16), (cs_pos_t)lround(y * Q16),
                           (cs_pos_t)lround(z * Q16), 0};
    return cs_planner_line(pl, t, (int32_t)lround(feed * Q16), 1);
}

static void test_ring_full_is_defined_error(void **state)
{
    (void)state;
    cs_planner_t pl;
    assert_int_equal(cs_planner_init(&pl, &machine), CS_OK);
    for (int i = 1; i <= CS_PLANNER_RING; i++)
        assert_int_equal(line_mm(&pl, i, 0, 0, 50), CS_OK);
    assert_true(cs_planner_full(&pl));
    assert_int_equal(line_mm(&pl, 100, 0, 0, 50), CS_ERR_FULL);
    assert_int_equal(cs_planner_count(&pl), CS_PLANNER_RING);
    /* Nothing moved: the planned position is still the 32nd target. */
    assert_int_equal(pl.pos[0], CS_PLANNER_RING * 65536);
    const cs_block_t *b = cs_planner_begin_head(&pl);
    assert_non_null(b);
    cs_planner_end_head(&pl);
    assert_false(cs_planner_full(&pl));
    assert_int_equal(line_mm(&pl, 100, 0, 0, 50), CS_OK);
}

static void test_soft_limit_refused_before_queueing(void **state)
{
    (void)state;
    cs_planner_t pl;
    assert_int_equal(cs_planner_init(&pl, &machine), CS_OK);
    assert_int_equal(line_mm(&pl, 10, 10, 0, 50), CS_OK);
    assert_int_equal(line_mm(&pl, 1000.5, 10, 0, 50), CS_ERR_LIMIT);
    assert_int_equal(line_mm(&pl, 10, 10, -100.01, 50), CS_ERR_LIMIT);
    assert_int_equal(cs_planner_count(&pl), 1);
    assert_int_equal(pl.pos[0], 10 * 65536);
}

static void test_feed_limited_by_each_axis(void **state)
{
    (void)state;
    cs_planner_t pl;
    assert_int_equal(cs_planner_init(&pl, &machine), CS_OK);
    /* 3-4-5 move at 1000 mm/s asked: y (4/5 of the speed) caps at 200 mm/s -> v = 250. */
    assert_int_equal(line_mm(&pl, 30, 40, 0, 1000), CS_OK);
    const cs_block_t *b = cs_planner_block(&pl, 0);
    /* The exact rates use the executed steps (2400, 3200 at 80/mm) and the chord length 50. */
    double want = 200.0 * 50.0 / 40.0;
    assert_true(fabs(b->nominal / Q16 - want) <= 2.0 / Q16);
    double want_a = 1000.0 * 50.0 / 40.0;
    assert_true(fabs(b->accel / Q16 - want_a) <= 2.0 / Q16);
    /* z moves slower: a pure z move at rapid runs at z's rate. */
    assert_int_equal(line_mm(&pl, 30, 40, 10, 0), CS_OK);
    b = cs_planner_block(&pl, 1);
    assert_true(fabs(b->nominal / Q16 - 50.0) <= 1.0 / Q16);
}

/* Grbl's junction deviation speed in double for a deflection angle phi between chords. */
static double jd_v2(double a, double delta, double phi)
{
    double s = cos(phi / 2); /* sin(theta/2), theta = pi - phi */
    return a * delta * s / (1 - s);
}

static void test_corner_slows_per_junction_deviation(void **state)
{
    (void)state;
    cs_planner_t pl;
    assert_int_equal(cs_planner_init(&pl, &machine), CS_OK);
    assert_int_equal(line_mm(&pl, 100, 0, 0, 100), CS_OK);
    assert_int_equal(line_mm(&pl, 100, 100, 0, 100), CS_OK);
    const cs_block_t *b = cs_planner_block(&pl, 1);
    /* The machine's 0.01 mm is 655 LSB once in Q16: the reference uses that exact delta. */
    double delta = machine.junction_deviation / Q16;
    double want = jd_v2(1000.0, delta, M_PI / 2);
    double got = b->max_entry_v2 / Q32;
    /* Q30 direction vectors and Q16 inputs: 1e-6 relative. */
    assert_true(fabs(got - want) <= 1e-6 * want);
    /* Planned entry is that limit (long blocks can reach and leave it). */
    assert_true(fabs(b->entry_v2 / Q32 - want) <= 1e-6 * want);
    /* 135 degree turn (deflection 3pi/4) is slower still; a reversal stops. */
    assert_int_equal(line_mm(&pl, 0, 0, 0, 100), CS_OK);
    b = cs_planner_block(&pl, 2);
    want = jd_v2(1000.0, delta, 3 * M_PI / 4);
    assert_true(fabs(b->max_entry_v2 / Q32 - want) <= 1e-5 * want + 1e-9);
    assert_int_equal(line_mm(&pl, 100, 100, 0, 100), CS_OK);
    b = cs_planner_block(&pl, 3);
    assert_true(b->max_entry_v2 >= 0);
    assert_true(b->max_entry_v2 / Q32 < 1e-3);
}

static void test_collinear_chords_do_not_slow(void **state)
{
    (void)state;
    cs_planner_t pl;
    assert_int_equal(cs_planner_init(&pl, &machine), CS_OK);
    for (int i = 1; i <= 30; i++)
        assert_int_equal(line_mm(&pl, 0.5 * i, 0.25 * i, 0, 60), CS_OK);
    double nom = cs_planner_block(&pl, 0)->nominal / Q16;
    for (unsigned i = 1; i < 30; i++) {
        const cs_block_t *b = cs_planner_block(&pl, i);
        assert_true(b->max_entry_v2 / Q32 >= nom * nom * (1 - 1e-9));
    }
    /* 15 mm of 1000 mm/s^2 ramps reach 60 mm/s (needs 1.8 mm) from both ends: the middle block
     * enters at full speed. */
    const cs_block_t *mid = cs_planner_block(&pl, 15);
    assert_true(fabs(sqrt(mid->entry_v2 / Q32) - 60.0) <= 1e-3);
}

static void test_curvature_rule_on_flattened_circle(void **state)
{
    (void)state;
    cs_planner_t pl;
    /* Junction deviation far below the tolerance: the a*r rule is what lets the circle run. */
    cs_machine_t m = machine;
    m.junction_deviation = 65536 / 10000; /* 0.0001 mm */
    m.tolerance = 65536 / 100;
    assert_int_equal(cs_planner_init(&pl, &m), CS_OK);
    double R = 50, tol = 0.01;
    int n = (int)ceil(M_PI / acos(1 - tol / R)); /* chords within tol of the circle */
    double cx = 0, cy = 0;
    cs_pos_t start[CS_AXES] = {(cs_pos_t)lround((cx + R) * Q16), 0, 0, 0};
    assert_int_equal(cs_planner_set_position(&pl, start), CS_OK);
    for (int k = 1; k <= 20; k++) {
        double t = 2 * M_PI * k / n;
        assert_int_equal(line_mm(&pl, cx + R * cos(t), cy + R * sin(t), 0, 1000), CS_OK);
    }
    for (unsigned i = 2; i < 19; i++) {
        const cs_block_t *b = cs_planner_block(&pl, i);
        const cs_block_t *p = cs_planner_block(&pl, i - 1);
        double L = fmin(b->length, p->length) / Q16;
        double phi = 2 * M_PI / n;
        double r = L / (2 * sin(phi / 2));
        /* Acceleration along a chord before any cut: the axis limit over the largest direction
         * cosine (the planner uses executed steps: within 1 %). */
        double ux = fabs(b->unit[0] / 1073741824.0), uy = fabs(b->unit[1] / 1073741824.0);
        assert_true(fabs(b->accel_axes / Q16 - 1000.0 / fmax(ux, uy)) <=
                    0.01 * 1000.0 / fmax(ux, uy));
        /* The curve's plane moves x and y, both limited to 1000 mm/s^2: the normal acceleration
         * at the junction speed is 0.51 of that, the chords' tangential one 0.68 (the velocity
         * jump at a vertex, 1.5 segment times of acceleration = 7.5 mm/s, does not bind here:
         * v |u1 - u2| = sqrt(0.51 a r) phi ~ 6.4 mm/s). */
        double want = 0.51 * 1000.0 * r;
        assert_true(sqrt(want) * 2 * sin(phi / 2) < 7.5);
        double got = b->max_entry_v2 / Q32;
        assert_true(fabs(got - want) <= 2e-3 * want);
        assert_true(fabs(b->accel / Q16 - 680.0) <= 1.0 / Q16);
        /* Far above what the junction deviation alone allows. */
        assert_true(got > 10 * jd_v2(1000.0, 0.0001, phi));
    }
}

/* Invariants after every replan: entries reachable both ways, last block ends at rest. */
static void check_passes(const cs_planner_t *pl)
{
    unsigned n = cs_planner_count(pl);
    for (unsigned i = 0; i < n; i++) {
        const cs_block_t *b = cs_planner_block(pl, i);
        double e2 = b->entry_v2 / Q32;
        double next = i + 1 < n ? cs_planner_block(pl, i + 1)->entry_v2 / Q32 : 0;
        double two_al = 2 * (b->accel / Q16) * (b->length / Q16);
        assert_true(e2 <= next + two_al + 1e-6); /* can slow down to the next entry */
        assert_true(next <= e2 + two_al + 1e-6); /* can speed up to it */
        assert_true(e2 <= b->max_entry_v2 / Q32 + 1e-9);
        assert_true(e2 <= (b->nominal / Q16) * (b->nominal / Q16) + 1e-6);
    }
}

static uint32_t rng = 12345;
static uint32_t xorshift(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return rng;
}
static double urand(double lo, double hi)
{
    return lo + (hi - lo) * (xorshift() / 4294967296.0);
}

static void test_passes_keep_every_block_reachable(void **state)
{
    (void)state;
    cs_planner_t pl;
    assert_int_equal(cs_planner_init(&pl, &machine), CS_OK);
    double x = 0, y = 0;
    for (int k = 0; k < 2000; k++) {
        if (cs_planner_full(&pl)) {
            assert_non_null(cs_planner_begin_head(&pl));
            cs_planner_end_head(&pl);
        }
        double len = urand(0.01, 20), ang = urand(-M_PI, M_PI);
        if (k % 7 < 4)
            ang = 0.3 * sin(k * 0.2); /* long runs of gentle turns */
        x = fmin(fmax(x + len * cos(ang), -900), 900);
        y = fmin(fmax(y + len * sin(ang), -900), 900);
        assert_int_equal(line_mm(&pl, x, y, 0, urand(5, 300)), CS_OK);
        check_passes(&pl);
    }
}

/* S-curve planning: every change between consecutive entry speeds (and to the final stop) fits
 * its block: (v1 + v2) / 2 * max(1.5 |dv| / a, sqrt(6 |dv| / j)) <= L, in double. */
static void test_scurve_passes_fit_every_change(void **state)
{
    (void)state;
    cs_machine_t m = machine;
    m.profile = CS_PROFILE_SCURVE;
    m.max_jerk = 20000;
    cs_planner_t pl;
    assert_int_equal(cs_planner_init(&pl, &m), CS_OK);
    rng = 777;
    double x = 0, y = 0;
    for (int k = 0; k < 600; k++) {
        if (cs_planner_full(&pl)) {
            assert_non_null(cs_planner_begin_head(&pl));
            cs_planner_end_head(&pl);
        }
        double len = urand(0.05, 15), ang = k % 3 ? 0.05 * sin(0.3 * k) : urand(-M_PI, M_PI);
        x = fmin(fmax(x + len * cos(ang), -900), 900);
        y = fmin(fmax(y + len * sin(ang), -900), 900);
        assert_int_equal(line_mm(&pl, x, y, 0, urand(5, 200)), CS_OK);
        unsigned n = cs_planner_count(&pl);
        for (unsigned i = pl.busy ? 1 : 0; i < n; i++) {
            const cs_block_t *b = cs_planner_block(&pl, i);
            double v1 = sqrt(b->entry_v2 / Q32);
            double v2 = i + 1 < n ? sqrt(cs_planner_block(&pl, i + 1)->entry_v2 / Q32) : 0;
            double a = b->accel / Q16, dv = fabs(v2 - v1), L = b->length / Q16;
            double T = fmax(1.5 * dv / a, sqrt(6 * dv / m.max_jerk));
            assert_true((v1 + v2) / 2 * T <= L * (1 + 1e-6) + 1e-6);
            assert_true(v1 <= b->nominal / Q16 + 1e-6);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_ring_full_is_defined_error, setup),
        cmocka_unit_test_setup(test_soft_limit_refused_before_queueing, setup),
        cmocka_unit_test_setup(test_feed_limited_by_each_axis, setup),
        cmocka_unit_test_setup(test_corner_slows_per_junction_deviation, setup),
        cmocka_unit_test_setup(test_collinear_chords_do_not_slow, setup),
        cmocka_unit_test_setup(test_curvature_rule_on_flattened_circle, setup),
        cmocka_unit_test_setup(test_passes_keep_every_block_reachable, setup),
        cmocka_unit_test_setup(test_scurve_passes_fit_every_change, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
