/* Tests of cs_hold, the feed-hold ramp, against a double-precision model of a linear speed ramp:
 * a job of constant segments (5 ms, full speed) is held from full speed. The ramp must take as
 * much job time as the area under s(t) from 1 to 0 over T (T / 2 of job time, T = 5/4 max_rate /
 * max_accel), each segment's speed must fall and lie on the line of the ramp (slope 0.8 max_accel)
 * at its midpoint, within the rounding to whole ticks, the stop must come at rest (the last
 * segment at most the mean speed of a ramp through one segment), the steps are never touched;
 * then the resume mirrors it up to full speed. Plus the no-hold path (segments untouched), an
 * override's goal above and below full speed, and the machine checks. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

#include "cs_hold.h"
#include "cs_machine_ini.h"

#define SEG_TICKS 500 /* 5 ms at 100 kHz */
#define SEG_STEPS 80  /* 1 mm at 80 steps/mm: 200 mm/s */

static cs_machine_t machine;

static int setup(void **state)
{
    (void)state;
    cs_machine_ini_default(&machine); /* x/y 200 mm/s, 1000 mm/s^2; z 50, 500 */
    machine.axis[0].steps_per_mm = 80 * CS_MOTION_ONE;
    return 0;
}

static cs_segment_t seg(void)
{
    cs_segment_t s = {SEG_TICKS, {SEG_STEPS, 0, 0, 0}};
    return s;
}

/* speed of a segment, mm/s */
static double speed(const cs_segment_t *s)
{
    return (double)s->steps[0] / 80.0 / ((double)s->ticks / machine.tick_hz);
}

static void test_no_hold_untouched(void **state)
{
    (void)state;
    cs_hold_t h;
    assert_int_equal(cs_hold_init(&h, &machine), CS_OK);
    for (int k = 0; k < 10; k++) {
        cs_segment_t s = seg();
        assert_true(cs_hold_admit(&h, &s));
        assert_int_equal(s.ticks, SEG_TICKS);
        assert_int_equal(s.steps[0], SEG_STEPS);
    }
    assert_false(cs_hold_active(&h));
    assert_false(cs_hold_stopped(&h));
}

/* Runs segments through the ramp until it refuses (hold) or is back to full speed (resume);
 * checks monotony and the midpoint slope; returns the count admitted, *job_s the job time they
 * carry, *last the last speed. Starts from full speed (down) or rest (up) at time 0. */
static int ramp(cs_hold_t *h, bool down, double *job_s, double *last)
{
    double T = 1.25 * 200.0 / 1000.0; /* the slowest axis ratio: x/y 0.2 s, z 0.1 s */
    double slope = 200.0 / T;         /* mm/s^2 at full speed 200 mm/s */
    double prev_v = down ? 200.0 : 0.0, t = 0;
    int n = 0;
    *job_s = 0;
    for (int k = 0; k < 10000; k++) {
        cs_segment_t s = seg();
        if (!cs_hold_admit(h, &s))
            break;
        assert_int_equal(s.steps[0], SEG_STEPS); /* the steps are never touched */
        assert_true(s.ticks >= SEG_TICKS);
        double d = (double)s.ticks / machine.tick_hz, v = speed(&s), mid = t + d / 2;
        if (n > 0)
            assert_true(down ? v <= prev_v + 1e-9 : v >= prev_v - 1e-9);
        /* on the ramp's line at the segment's midpoint (the mean of a linear ramp), within the
         * rounding of ticks to whole ticks (v / ticks) and 0.5 mm/s; the last segment of a
         * hold runs longer than the line (it ends at rest) and is checked by the caller */
        double ideal = down ? 200.0 - slope * mid : slope * mid;
        bool last_down = down && h->scale == 0;
        if (!last_down && ideal <= 200.0)
            assert_true(fabs(v - ideal) <= v / (double)s.ticks + 0.5);
        prev_v = v;
        t += d;
        *job_s += (double)SEG_TICKS / machine.tick_hz;
        n++;
        if (!down && s.ticks == SEG_TICKS)
            break; /* back to full speed */
    }
    *last = prev_v;
    return n;
}

static void test_hold_then_resume(void **state)
{
    (void)state;
    cs_hold_t h;
    assert_int_equal(cs_hold_init(&h, &machine), CS_OK);
    cs_hold_set(&h, true);
    double job_s, last;
    int n = ramp(&h, true, &job_s, &last);
    /* the area under the ramp: T / 2 of job time, within one segment */
    double T = 1.25 * 0.2;
    assert_true(fabs(job_s - T / 2) <= 0.005 + 1e-9);
    assert_true(n > 10);
    /* at rest: the last segment runs at most at the mean speed of a ramp through one segment
     * from rest, sqrt(2 tau / T) / 2 of full speed */
    assert_true(last <= 200.0 * sqrt(2 * 0.005 / T) / 2 * 1.01);
    assert_true(cs_hold_stopped(&h));
    cs_segment_t s = seg();
    assert_false(cs_hold_admit(&h, &s)); /* stays stopped */
    assert_int_equal(s.ticks, SEG_TICKS);
    cs_hold_set(&h, false);
    assert_false(cs_hold_stopped(&h));
    int m = ramp(&h, false, &job_s, &last);
    assert_true(m > 10);
    assert_true(fabs(job_s - T / 2) <= 0.01 + 1e-9);
    assert_true(fabs(last - 200.0) < 1e-9);
    assert_false(cs_hold_active(&h));
}

/* An override's goal (cs_hold_admit_to, no hold): from full speed up to 1.5 then down to 0.5,
 * each segment's speed on the ramp's line (slope 200 mm/s / T) at its midpoint within the tick
 * rounding, then steady at 300 and 100 mm/s (ticks 500 / 1.5 and 500 / 0.5, rounded up); the
 * ramp to 1.5 takes (1.5^2 - 1) T / 2 of job time (the area under s). A goal of 20 stops at one
 * step a tick (the executor's invariant). */
static void test_override_goal(void **state)
{
    (void)state;
    cs_hold_t h;
    assert_int_equal(cs_hold_init(&h, &machine), CS_OK);
    const double T = 1.25 * 0.2, slope = 200.0 / T;
    const double goal[] = {1.5, 0.5};
    double v0 = 200.0;
    for (int g = 0; g < 2; g++) {
        uint32_t q = (uint32_t)lround(goal[g] * CS_HOLD_SCALE_ONE);
        double t = 0, job = 0, v = 0, v1 = 200.0 * goal[g];
        int k = 0;
        for (; k < 1000; k++) {
            cs_segment_t s = seg();
            assert_true(cs_hold_admit_to(&h, &s, q));
            assert_int_equal(s.steps[0], SEG_STEPS);
            double d = (double)s.ticks / machine.tick_hz, mid = t + d / 2;
            v = speed(&s);
            double ideal = v0 + (v1 > v0 ? slope : -slope) * mid;
            if (v1 > v0 ? ideal < v1 : ideal > v1)
                assert_true(fabs(v - ideal) <= v / (double)s.ticks + 0.5);
            t += d;
            job += (double)SEG_TICKS / machine.tick_hz;
            if (h.scale == q)
                break;
        }
        if (g == 0) /* (s1^2 - s0^2) T / 2 of job time, within one segment */
            assert_true(fabs(job - (1.5 * 1.5 - 1) * T / 2) <= 0.005 + 1e-9);
        cs_segment_t s = seg();
        assert_true(cs_hold_admit_to(&h, &s, q));
        assert_int_equal(s.ticks, (uint32_t)ceil(SEG_TICKS / goal[g] - 1e-9));
        v0 = v1;
    }
    for (int k = 0; k < 2000; k++) {
        cs_segment_t s = seg();
        assert_true(cs_hold_admit_to(&h, &s, CS_HOLD_SCALE_MAX));
        assert_true(s.ticks >= SEG_STEPS);
    }
    cs_segment_t s = seg();
    assert_true(cs_hold_admit_to(&h, &s, CS_HOLD_SCALE_MAX));
    assert_int_equal(s.ticks, SEG_STEPS);
}

static void test_reset_and_bad_machine(void **state)
{
    (void)state;
    cs_hold_t h;
    assert_int_equal(cs_hold_init(&h, &machine), CS_OK);
    cs_hold_set(&h, true);
    cs_segment_t s = seg();
    assert_true(cs_hold_admit(&h, &s));
    assert_true(s.ticks > SEG_TICKS);
    cs_hold_reset(&h); /* an abort: full speed, no hold */
    s = seg();
    assert_true(cs_hold_admit(&h, &s));
    assert_int_equal(s.ticks, SEG_TICKS);
    cs_machine_t bad = machine;
    bad.axis[1].max_accel = 0;
    assert_int_equal(cs_hold_init(&h, &bad), CS_ERR_ARG);
    assert_int_equal(cs_hold_init(NULL, &machine), CS_ERR_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_no_hold_untouched, setup),
        cmocka_unit_test_setup(test_hold_then_resume, setup),
        cmocka_unit_test_setup(test_override_goal, setup),
        cmocka_unit_test_setup(test_reset_and_bad_machine, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
