/* test_feedrate: the Grbl front end's FS: speed (host/cs_feedrate.c) from timed position samples.
 * The reference is a straight cut at F1200 (20 mm/s) along (3, 4)/5 with a trapezoid start at
 * 1000 mm/s^2, worked out in double and rounded to steps (80 and 100 steps/mm) at each sample
 * time; the device samples every 50 ms of its 1 MHz clock, which starts just below 2^32 (the
 * counter wraps mid-cut), and the host sees only some of the samples (every second one, with
 * runs of up to 5 missing: a front end starved of the CPU). Past the ramp every speed is
 * 1200 mm/min within the step rounding (1 step per axis over the 0.2 s window: computed below)
 * and so within the 2 % the Grbl front end promises (docs/controller.md, "FS"). Also: a clock
 * that goes back (a reboot) or jumps (a long gap) restarts the window; host-timed samples use
 * the longer window and only positions that changed. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "cs_feedrate.h"

#define HZ       1000000u
#define V_MM_S   20.0
#define ACCEL    1000.0
#define PERIOD_S 0.05
#define TICK0    0xFFF00000u /* 1.05 s before the wrap */

static const double spmm[CS_PROTO_AXES_MAX] = {80.0, 100.0, 80.0, 80.0};

/* Distance along the cut at time t (s): v t - v^2/2a past the ramp, a t^2 / 2 on it. */
static double ref_s(double t)
{
    double ta = V_MM_S / ACCEL;
    return t < ta ? 0.5 * ACCEL * t * t : V_MM_S * t - V_MM_S * V_MM_S / (2 * ACCEL);
}

static void ref_pos(double t, int32_t pos[CS_PROTO_AXES_MAX])
{
    double s = ref_s(t);
    pos[0] = (int32_t)lround(s * 0.6 * spmm[0]);
    pos[1] = (int32_t)lround(s * 0.8 * spmm[1]);
    pos[2] = pos[3] = 0;
}

static unsigned rng_state = 12345u;
static unsigned rng(void)
{
    rng_state = rng_state * 1103515245u + 12345u;
    return (rng_state >> 16) & 0x7FFFu;
}

static void test_device_timed_straight_cut(void **state)
{
    (void)state;
    cs_feedrate_t f;
    cs_feedrate_reset(&f);
    /* the longest window the host can see: W plus the samples it missed (5) and one period */
    const double w_max = CS_FEEDRATE_WINDOW_DEV_S + 6 * PERIOD_S;
    /* rounding: each sample within 1/2 step per axis of the reference, so the distance over
     * the window within one step per axis; over at least W at v */
    const double tol = hypot(1 / spmm[0], 1 / spmm[1]) / (V_MM_S * CS_FEEDRATE_WINDOW_DEV_S);
    assert_true(tol < 0.02);
    unsigned checked = 0, skip = 0;
    for (unsigned k = 0; k <= 80; k++) { /* 4 s */
        double t = k * PERIOD_S;
        if (skip > 0) { /* the host missed this STATUS */
            skip--;
            continue;
        }
        skip = rng() % 4 == 0 ? 1 + rng() % 5 : 1;
        int32_t pos[CS_PROTO_AXES_MAX];
        ref_pos(t, pos);
        uint32_t tick = TICK0 + (uint32_t)lround(t * HZ);
        cs_feedrate_add_tick(&f, tick, HZ, pos);
        cs_feedrate_add_tick(&f, tick, HZ, pos); /* the same STATUS seen twice: nothing */
        double v;
        if (!cs_feedrate_mm_min(&f, 2, spmm, &v)) {
            assert_int_equal(k, 0);
            continue;
        }
        if (t >= V_MM_S / ACCEL + w_max) {
            assert_true(fabs(v / (V_MM_S * 60) - 1) <= tol);
            checked++;
        }
    }
    assert_true(checked >= 10);
}

static void test_clock_restarts(void **state)
{
    (void)state;
    cs_feedrate_t f;
    cs_feedrate_reset(&f);
    int32_t a[CS_PROTO_AXES_MAX] = {0}, b[CS_PROTO_AXES_MAX] = {800};
    double v = -1;
    cs_feedrate_add_tick(&f, 5000000u, HZ, a);
    cs_feedrate_add_tick(&f, 5500000u, HZ, b); /* 10 mm in 0.5 s: 1200 mm/min */
    assert_true(cs_feedrate_mm_min(&f, 1, spmm, &v));
    assert_true(fabs(v - 1200) < 1e-9);
    /* a reboot: the clock went back; one sample, no speed */
    cs_feedrate_add_tick(&f, 1000u, HZ, a);
    assert_false(cs_feedrate_mm_min(&f, 1, spmm, &v));
    /* a jump past CS_FEEDRATE_GAP_S: a new window too */
    cs_feedrate_add_tick(&f, 1000u + (uint32_t)(CS_FEEDRATE_GAP_S * HZ) + 1u, HZ, b);
    assert_false(cs_feedrate_mm_min(&f, 1, spmm, &v));
    assert_int_equal(f.n, 1);
}

/* Host-timed (Modbus): a position is timed when first seen, repeats are dropped until the
 * window passed (a stop then reads 0), and the window is CS_FEEDRATE_WINDOW_HOST_S. */
static void test_host_timed(void **state)
{
    (void)state;
    cs_feedrate_t f;
    cs_feedrate_reset(&f);
    int32_t p[CS_PROTO_AXES_MAX] = {0};
    double v;
    for (unsigned k = 0; k <= 10; k++) { /* 8 steps (0.1 mm) every 0.05 s: 120 mm/min */
        p[0] = (int32_t)(8 * k);
        cs_feedrate_add_host(&f, 100.0 + 0.05 * k, p);
        cs_feedrate_add_host(&f, 100.0 + 0.05 * k + 0.01, p); /* seen again: dropped */
    }
    assert_int_equal(f.n, 11);
    assert_true(cs_feedrate_mm_min(&f, 1, spmm, &v));
    /* newest at 0.50 s, the first at least 0.25 s older: 0.25 s (5 samples, 0.5 mm) */
    assert_true(fabs(v - 0.5 / 0.25 * 60) < 1e-6);
    /* stopped: the same position after the window reads 0 */
    cs_feedrate_add_host(&f, 100.5 + CS_FEEDRATE_WINDOW_HOST_S, p);
    assert_true(cs_feedrate_mm_min(&f, 1, spmm, &v));
    assert_true(fabs(v) < 1e-9);
    /* a device-timed sample after host-timed ones: a new window */
    cs_feedrate_add_tick(&f, 7u, HZ, p);
    assert_false(cs_feedrate_mm_min(&f, 1, spmm, &v));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_device_timed_straight_cut),
        cmocka_unit_test(test_clock_restarts),
        cmocka_unit_test(test_host_timed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
