/* Tests of cs_hold, the feed-hold ramp, against a double-precision model of a linear speed ramp:
 * a job of constant segments (5 ms, full speed) is held from full speed. The ramp must take as
 * much job time as the area under s(t) from 1 to 0 over T (T / 2 of job time, T = 5/4 max_rate /
 * max_accel), each segment's speed must fall and lie on the line of the ramp (slope 0.8 max_accel)
 * at its midpoint, within the rounding to whole ticks, the stop must come at rest (the last
 * segment at most the mean speed of a ramp through one segment), the steps are never touched;
 * then the resume mirrors it up to full speed. Plus the no-hold path (segments untouched) and the
 * machine checks. */
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
        cmocka_unit_test_setup(test_reset_and_bad_machine, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
