/* Tests of cs_segment: exact block totals and final position on random jobs (rounding carried),
 * the segment invariant, the profile against the ideal trapezoid (a long straight move takes the
 * ideal time within 1 %; a short one peaks where the triangle says) and no segment faster than
 * the block's nominal speed. References in double. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdlib.h>

#include "cs_machine_ini.h"
#include "cs_motion.h"
#include "cs_planner.h"
#include "cs_segment.h"
#include "ref_xorshift32.h"

#define Q16 65536.0

static cs_machine_t machine;

static int setup(void **state)
{
    (void)state;
    cs_machine_ini_default(&machine);
    return 0;
}

static ref_xorshift32_t rng;

static cs_pos_t mm(double v)
{
    return (cs_pos_t)lround(v * Q16);
}

static void test_block_totals_exact_on_random_jobs(void **state)
{
    (void)state;
    rng.s = 0x9e3779b9u;
    for (int job = 0; job < 20; job++) {
        cs_machine_t m = machine;
        /* Uneven resolutions so rounding differs per axis. */
        m.axis[0].steps_per_mm = (int32_t)lround(ref_xorshift32_uniform(&rng, 5, 160) * Q16);
        m.axis[1].steps_per_mm = (int32_t)lround(ref_xorshift32_uniform(&rng, 5, 160) * Q16);
        m.axis[2].steps_per_mm = (int32_t)lround(ref_xorshift32_uniform(&rng, 5, 160) * Q16);
        cs_planner_t pl;
        cs_segment_gen_t g;
        assert_int_equal(cs_planner_init(&pl, &m), CS_OK);
        assert_int_equal(cs_segment_init(&g, &m), CS_OK);
        int64_t sum[CS_AXES] = {0, 0, 0, 0}, blk[CS_AXES] = {0, 0, 0, 0};
        double tx = 0, ty = 0, tz = 0;
        int moves = 200 + (int)(ref_xorshift32_next(&rng) % 200);
        int blocks_checked = 0;
        for (int k = 0; k <= moves; k++) {
            if (k < moves) {
                double len = ref_xorshift32_uniform(&rng, 0.001, 30);
                double ang = ref_xorshift32_uniform(&rng, -M_PI, M_PI);
                tx = fmin(fmax(tx + len * cos(ang), -990), 990);
                ty = fmin(fmax(ty + len * sin(ang), -990), 990);
                tz = fmin(fmax(tz + ref_xorshift32_uniform(&rng, -1, 1), -99), 99);
                cs_pos_t t[CS_AXES] = {mm(tx), mm(ty), mm(tz), 0};
                assert_int_equal(
                    cs_planner_line(&pl, t,
                                    (int32_t)lround(ref_xorshift32_uniform(&rng, 1, 400) * Q16), 1),
                    CS_OK);
            }
            /* Keep the ring full while moves remain, then drain. */
            while (cs_planner_full(&pl) || (k == moves && cs_planner_count(&pl) > 0)) {
                const cs_block_t *b = cs_planner_begin_head(&pl);
                int32_t want[CS_AXES];
                for (unsigned i = 0; i < CS_AXES; i++)
                    want[i] = b->steps[i];
                cs_segment_t s;
                do {
                    assert_int_equal(cs_segment_next(&g, &pl, &s), CS_OK);
                    assert_true(s.ticks >= 1 && s.ticks <= m.segment_ticks);
                    for (unsigned i = 0; i < CS_AXES; i++) {
                        assert_true(llabs(s.steps[i]) <= (long long)s.ticks);
                        blk[i] += s.steps[i];
                        sum[i] += s.steps[i];
                    }
                } while (!cs_segment_block_end(&g));
                for (unsigned i = 0; i < CS_AXES; i++) {
                    assert_int_equal(blk[i], want[i]);
                    blk[i] = 0;
                }
                blocks_checked++;
            }
        }
        assert_true(blocks_checked > 100);
        /* Final position = round(target * steps/mm), computed in double from the Q16 values. */
        double tgt[3] = {mm(tx) / Q16, mm(ty) / Q16, mm(tz) / Q16};
        for (unsigned i = 0; i < 3; i++) {
            double spm = m.axis[i].steps_per_mm / Q16;
            assert_int_equal(sum[i], (int64_t)llround(tgt[i] * spm));
        }
        cs_segment_t s;
        assert_int_equal(cs_segment_next(&g, &pl, &s), CS_ERR_EMPTY);
    }
}

/* Ideal duration of one straight move from rest to rest: trapezoid or triangle. */
static double ideal_time(double L, double v, double a)
{
    double d_acc = v * v / (2 * a);
    if (2 * d_acc <= L)
        return 2 * v / a + (L - 2 * d_acc) / v;
    return 2 * sqrt(L / a);
}

static double run_single(const cs_machine_t *m, double L, double feed, double *peak)
{
    cs_motion_t mo;
    assert_int_equal(cs_motion_init(&mo, m), CS_OK);
    assert_int_equal(cs_motion_line_mm(&mo, L, 0, 0, feed, 1), CS_OK);
    assert_int_equal(cs_motion_finish(&mo), CS_OK);
    double spm = m->axis[0].steps_per_mm / Q16;
    *peak = 0;
    for (size_t k = 0; k < mo.segs.n; k++) {
        double v = mo.segs.v[k].steps[0] / spm / (mo.segs.v[k].ticks / (double)m->tick_hz);
        *peak = fmax(*peak, v);
    }
    assert_int_equal(mo.pos[0], llround(L * spm));
    double t = (double)mo.ticks / m->tick_hz;
    cs_motion_free(&mo);
    return t;
}

static void test_long_move_takes_ideal_trapezoid_time(void **state)
{
    (void)state;
    double peak;
    /* 800 mm at 150 mm/s, 1000 mm/s^2: 5.4833 s. */
    double t = run_single(&machine, 800, 150, &peak);
    double want = ideal_time(800, 150, 1000);
    assert_true(fabs(t - want) <= 0.01 * want);
    /* In fact within a few ticks: the profile is sampled in closed form. */
    assert_true(fabs(t - want) <= 1e-3);
    /* One segment's mean speed can exceed the cruise speed only by step rounding (1 step). */
    assert_true(peak <= 150 + 1.0 / 80 / 0.005 + 1e-9);
    /* A 2 mm move never reaches 150 mm/s: triangle, peak sqrt(a L) = 44.7 mm/s. */
    t = run_single(&machine, 2, 150, &peak);
    want = ideal_time(2, 150, 1000);
    assert_true(fabs(t - want) <= 0.01 * want);
    assert_true(peak <= sqrt(1000.0 * 2) + 1.0 / 80 / 0.005);
    assert_true(peak >= 0.9 * sqrt(1000.0 * 2));
}

static void test_segment_speeds_follow_the_profile(void **state)
{
    (void)state;
    /* One 300 mm block: every segment's mean speed matches the ideal trapezoid's mean speed over
     * the same interval to within one step per segment. */
    cs_motion_t mo;
    double a = 1000, v = 120, L = 300;
    assert_int_equal(cs_motion_init(&mo, &machine), CS_OK);
    assert_int_equal(cs_motion_line_mm(&mo, L, 0, 0, v, 1), CS_OK);
    assert_int_equal(cs_motion_finish(&mo), CS_OK);
    double hz = machine.tick_hz, spm = 80, t = 0, T = ideal_time(L, v, a);
    for (size_t k = 0; k < mo.segs.n; k++) {
        double dt = mo.segs.v[k].ticks / hz;
        /* Ideal distance covered in [t, t + dt]. */
        double ta = v / a;
#define POS(u)                                                                                     \
    ((u) <= ta       ? 0.5 * a * (u) * (u)                                                         \
     : (u) <= T - ta ? 0.5 * a * ta * ta + v * ((u)-ta)                                            \
                     : L - 0.5 * a * (T - (u)) * (T - (u)))
        double u1 = fmin(t + dt, T);
        double want = (POS(u1) - POS(t)) * spm;
        assert_true(fabs(mo.segs.v[k].steps[0] - want) <= 1.5);
        t += dt;
    }
    cs_motion_free(&mo);
}

static void test_empty_planner(void **state)
{
    (void)state;
    cs_planner_t pl;
    cs_segment_gen_t g;
    cs_segment_t s;
    assert_int_equal(cs_planner_init(&pl, &machine), CS_OK);
    assert_int_equal(cs_segment_init(&g, &machine), CS_OK);
    assert_int_equal(cs_segment_next(&g, &pl, &s), CS_ERR_EMPTY);
    /* A move under one step queues nothing and is carried: then 1 step appears. */
    cs_pos_t t[CS_AXES] = {mm(0.005), 0, 0, 0};
    assert_int_equal(cs_planner_line(&pl, t, 50 * 65536, 1), CS_OK);
    assert_int_equal(cs_planner_count(&pl), 0);
    t[0] = mm(0.010);
    assert_int_equal(cs_planner_line(&pl, t, 50 * 65536, 1), CS_OK);
    assert_int_equal(cs_planner_count(&pl), 1);
    assert_int_equal(cs_planner_block(&pl, 0)->steps[0], 1);
}

/* S-curve machine with fine steps so that finite differences of the step positions resolve
 * the jerk: 1000 steps/mm, 1 MHz ticks, 5 ms segments, 1000 mm/s^2, 100000 mm/s^3. */
static void scurve_machine(cs_machine_t *m)
{
    cs_machine_ini_default(m);
    m->tick_hz = 1000000;
    m->segment_ticks = 5000;
    for (unsigned i = 0; i < 3; i++)
        m->axis[i].steps_per_mm = 1000 * 65536;
    m->profile = CS_PROFILE_SCURVE;
    m->max_jerk = 100000;
}

/* Runs the planner and generator over moves along x and records, after every segment, its
 * duration and the distance travelled (mm) from the generator's own profile (Q16 mm: 15 nm, so
 * finite differences resolve the jerk). Returns the number of samples. */
static size_t profile_samples(const cs_machine_t *m, const double *x, const double *feed,
                              int nmoves, uint32_t *ticks, double *dist, size_t cap)
{
    cs_planner_t pl;
    cs_segment_gen_t g;
    assert_int_equal(cs_planner_init(&pl, m), CS_OK);
    assert_int_equal(cs_segment_init(&g, m), CS_OK);
    for (int k = 0; k < nmoves; k++) {
        cs_pos_t t[CS_AXES] = {mm(x[k]), 0, 0, 0};
        assert_int_equal(cs_planner_line(&pl, t, (int32_t)lround(feed[k] * Q16), 1), CS_OK);
    }
    size_t n = 0;
    double base = 0;
    int32_t steps = 0;
    cs_segment_t s;
    while (cs_segment_next(&g, &pl, &s) == CS_OK) {
        assert_true(n < cap);
        steps += s.steps[0];
        ticks[n] = s.ticks;
        dist[n] = base + g.d / Q16;
        if (cs_segment_block_end(&g))
            base += g.length / Q16;
        n++;
    }
    assert_int_equal(steps, lround(x[nmoves - 1] * m->axis[0].steps_per_mm / Q16));
    return n;
}

/* Third and second finite differences over windows of one full segment (5 ms) bound the jerk and
 * the acceleration; the Q16 rounding of the samples adds at most 8 * 2^-17 mm / W^3 and
 * 4 * 2^-17 mm / W^2. */
static void check_scurve_derivatives(const uint32_t *ticks, const double *d, size_t n, double a,
                                     double j, double *jmax_out)
{
    double W = 0.005, jmax = 0, amax = 0, lsb = 1.0 / 131072;
    for (size_t k = 0; k + 3 < n; k++) {
        if (ticks[k + 1] != 5000 || ticks[k + 2] != 5000 || ticks[k + 3] != 5000)
            continue;
        jmax = fmax(jmax, fabs(d[k + 3] - 3 * d[k + 2] + 3 * d[k + 1] - d[k]) / (W * W * W));
        amax = fmax(amax, fabs(d[k + 2] - 2 * d[k + 1] + d[k]) / (W * W));
    }
    print_message("s-curve: peak jerk %.0f mm/s^3, peak accel %.1f mm/s^2\n", jmax, amax);
    assert_true(jmax <= j + 8 * lsb / (W * W * W));
    assert_true(amax <= a + 4 * lsb / (W * W));
    *jmax_out = jmax;
}

static void test_scurve_bounded_jerk_and_time(void **state)
{
    (void)state;
    cs_machine_t m;
    scurve_machine(&m);
    static uint32_t ticks[4096];
    static double d[4096];
    double x = 300, f = 150, jmax;
    size_t n = profile_samples(&m, &x, &f, 1, ticks, d, 4096);
    uint64_t total = 0;
    for (size_t k = 0; k < n; k++)
        total += ticks[k];
    /* Ideal: each change takes max(1.5 v / a, sqrt(6 v / j)) = 0.225 s at mean speed v / 2. */
    double v = 150, a = 1000, j = 100000, T = fmax(1.5 * v / a, sqrt(6 * v / j));
    double want = 2 * T + (300 - v * T) / v;
    double got = (double)total / m.tick_hz;
    assert_true(fabs(got - want) <= 0.001 * want);
    check_scurve_derivatives(ticks, d, n, a, j, &jmax);
    /* Accelerating from rest to 150 mm/s in 0.225 s: jerk 6 v / T^2 (1 - 2 t / T) from 17778
     * mm/s^3 at t = 0; a third difference over [0, 3W] averages it to (1 - 3 W / T) of that. */
    double peak = 6 * v / (T * T) * (1 - 3 * 0.005 / T);
    assert_true(fabs(jmax - peak) <= 0.01 * peak);
}

static void test_scurve_jerk_limited_small_changes(void **state)
{
    (void)state;
    /* Collinear blocks whose feeds alternate 100 / 110 mm/s: 10 mm/s changes are jerk-limited
     * (sqrt(6 * 10 / j) = 24.5 ms > 1.5 * 10 / a = 15 ms): their jerk peaks at j itself. */
    cs_machine_t m;
    scurve_machine(&m);
    static uint32_t ticks[8192];
    static double d[8192];
    double x[20], f[20], jmax;
    for (int k = 0; k < 20; k++) {
        x[k] = 15.0 * (k + 1);
        f[k] = k % 2 ? 110 : 100;
    }
    size_t n = profile_samples(&m, x, f, 20, ticks, d, 8192);
    check_scurve_derivatives(ticks, d, n, 1000, 100000, &jmax);
    /* Windows at a transition's edge see at least (1 - 3 W / T) = 39 % of j. */
    assert_true(jmax >= 0.39 * 100000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_block_totals_exact_on_random_jobs, setup),
        cmocka_unit_test_setup(test_long_move_takes_ideal_trapezoid_time, setup),
        cmocka_unit_test_setup(test_segment_speeds_follow_the_profile, setup),
        cmocka_unit_test_setup(test_empty_planner, setup),
        cmocka_unit_test(test_scurve_bounded_jerk_and_time),
        cmocka_unit_test(test_scurve_jerk_limited_small_changes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
