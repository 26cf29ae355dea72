/* Tests of the OVERRIDE message on the device (cs_fw_motion_override: cs_hold's ramp towards the
 * override's scale, the rule above 100 % in cs_fw_motion, the spindle in cs_fw_ctl) on the POSIX
 * port: the x axis's step edges are counted in windows of real (simulated) time and compared
 * with a speed profile computed here in double from the segments, the override and the
 * machine's acceleration (ramp time T = 5/4 x max_rate / max_accel, docs/controller.md). The
 * default machine's x and y get max_accel 1000 mm/s^2 (T = 0.625 s) so that the ramps are long
 * enough to measure. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "cs_fw_app.h"
#include "cs_fw_motion.h"
#include "fw_test.h"
#include "port_posix.h"

#define SPM    80.0   /* steps/mm of cs_fw_machine_default */
#define HZ     100000 /* fw_test_motion's tick rate */
#define SEG    500u   /* 5 ms segments */
#define ACCEL  1000.0 /* mm/s^2, x and y */
#define WIN    2500u  /* 25 ms windows */
#define Q16(v) ((int32_t)((v) * 65536.0))

static cs_machine_t machine;
static cs_fw_motion_t mo;

static int setup(void **state)
{
    (void)state;
    if (fw_test_motion(&machine, &mo, 256) != 0)
        return -1;
    machine.axis[0].max_accel = machine.axis[1].max_accel = Q16(ACCEL);
    return cs_hold_init(&mo.hold, &machine) == CS_OK ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    port_stepper_attach(NULL);
    port_posix_reset(machine.tick_hz, 0);
    return 0;
}

/* T, s: the ramp time from the machine, in double (x/y: 500 / 1000, z: 50 / 500). */
static double ramp_s(void)
{
    double t = 0;
    for (unsigned i = 0; i < machine.n_axes; i++)
        t = fmax(t, 1.25 * machine.axis[i].max_rate / (double)machine.axis[i].max_accel);
    return t;
}

static void queue_x(int32_t steps, uint16_t seq)
{
    cs_proto_msg_t m = {.type = CS_PROTO_SEGMENT};
    m.u.segment.ticks = SEG;
    m.u.segment.steps[0] = steps;
    assert_int_equal(cs_fw_motion_queue(&mo, &m, seq), CS_OK);
}

static void set_override(uint16_t feed, uint16_t spindle)
{
    cs_proto_override_t ov = {feed, CS_PROTO_OVERRIDE_ONE, spindle};
    cs_fw_motion_override(&mo, &ov);
}

/* The main loop and the step interrupt until simulated time `until` or the job's end. */
static void run_until(uint64_t until)
{
    while (port_posix_now() < until && !cs_fw_motion_done(&mo)) {
        cs_fw_motion_poll(&mo);
        port_posix_run(port_posix_now() + 50 < until ? port_posix_now() + 50 : until);
    }
    cs_fw_motion_poll(&mo);
}

/* x speed, mm/s, in windows [k WIN, (k+1) WIN) of ticks; returns the window count. */
static size_t speeds(double *v, size_t cap)
{
    size_t n, w = 0;
    const port_posix_edge_t *ed = port_posix_edges(&n);
    for (size_t k = 0; k < cap; k++)
        v[k] = 0;
    for (size_t i = 0; i < n; i++) {
        if (ed[i].axis != 0)
            continue;
        size_t k = (size_t)(ed[i].t / WIN);
        if (k < cap) {
            v[k] += 1.0 / SPM / (WIN / (double)HZ);
            w = k + 1;
        }
    }
    return w;
}

/* The largest speed change between neighbouring windows, mm/s^2, over windows [k0, k1). */
static double max_accel(const double *v, size_t k0, size_t k1)
{
    double a = 0;
    for (size_t k = k0 + 1; k < k1; k++)
        a = fmax(a, fabs(v[k] - v[k - 1]) / (WIN / (double)HZ));
    return a;
}

/* A cruise at 300 mm/s (120 x-steps a 5 ms segment), feed override 50 % after 100 ms. The
 * device reacts after the ring it holds (CS_STEPPER_RING + 1 segments at most), then the speed
 * falls along s(t) = 1 - t / T to 150 mm/s: reached between 100 ms + T/2 and that plus the
 * ring's time (+ a window either side), and kept to the end within a step a window; no window
 * to window change exceeds the machine's 1000 mm/s^2 (the ramp's is 300 / T = 480); the
 * position is the segments' sum. */
static void test_feed_override_mid_job(void **state)
{
    (void)state;
    enum { N = 240 };
    for (uint16_t k = 0; k < N; k++)
        queue_x(120, k);
    run_until(10000); /* 100 ms */
    set_override(500, CS_PROTO_OVERRIDE_ONE);
    run_until(UINT64_MAX);
    assert_true(cs_fw_motion_done(&mo));
    assert_int_equal(port_posix_position(0), 120 * N);
    static double v[4096];
    size_t nw = speeds(v, 4096);
    double T = ramp_s(), v0 = 120 / SPM / 0.005, v1 = v0 / 2;
    double ring = (CS_STEPPER_RING + 1) * 0.005, lsb = 1 / SPM / (WIN / (double)HZ);
    assert_true(fabs(v[1] - v0) <= lsb); /* full speed before the override */
    size_t k_half = 0;
    while (k_half < nw && v[k_half] > v1 + lsb)
        k_half++;
    double t_half = (k_half + 1) * (WIN / (double)HZ); /* the end of the first slow window */
    double lo = 0.1 + T / 2 - WIN / (double)HZ, hi = 0.1 + ring + T / 2 + 2 * WIN / (double)HZ;
    assert_true(t_half >= lo && t_half <= hi);
    for (size_t k = k_half + 1; k + 1 < nw; k++)
        assert_true(fabs(v[k] - v1) <= lsb);
    assert_true(max_accel(v, 0, nw - 1) <= ACCEL);
}

/* A trapezoid planned at the machine's acceleration (1000 mm/s^2 up to 200 mm/s, a 0.5 s
 * cruise, 1000 mm/s^2 down, exact step positions x(t) rounded a segment at a time) under a
 * 150 % feed override from the start. The device rises above 100 % only in the cruise and
 * brakes back to 1 before it ends, so no window-to-window change exceeds the machine's
 * acceleration by more than the windows' step rounding (2 steps a window); the cruise's peak is
 * 200 x sqrt(1 + R / T) with R the cruise's job time after its first segment (the look-ahead
 * rule: s^2 rises and falls by 2 tau / T, meeting in the middle), within 3 %; the position is
 * exact. */
static void test_feed_over_100_keeps_accel(void **state)
{
    (void)state;
    const double a = ACCEL, vc = 200, tau = 0.005;
    const int n_acc = 40, n_cruise = 100;
    /* x(t) in steps along the trapezoid, at segment ends */
    double t_acc = n_acc * tau, x_acc = 0.5 * a * t_acc * t_acc;
    int32_t done = 0;
    uint16_t seq = 0;
    for (int k = 1; k <= 2 * n_acc + n_cruise; k++) {
        double t = k * tau, x;
        if (k <= n_acc)
            x = 0.5 * a * t * t;
        else if (k <= n_acc + n_cruise)
            x = x_acc + vc * (t - t_acc);
        else {
            double u = t - (n_acc + n_cruise) * tau;
            x = x_acc + vc * n_cruise * tau + vc * u - 0.5 * a * u * u;
        }
        int32_t s = (int32_t)lround(x * SPM);
        queue_x(s - done, seq++);
        done = s;
    }
    set_override(1500, CS_PROTO_OVERRIDE_ONE);
    run_until(UINT64_MAX);
    assert_true(cs_fw_motion_done(&mo));
    assert_int_equal(port_posix_position(0), done);
    static double v[4096];
    size_t nw = speeds(v, 4096);
    double peak = 0;
    for (size_t k = 0; k < nw; k++)
        peak = fmax(peak, v[k]);
    double T = ramp_s(), R = (n_cruise - 1) * tau;
    double want = vc * sqrt(1 + R / T), lsb = 1 / SPM / (WIN / (double)HZ);
    assert_true(max_accel(v, 0, nw - 1) <= a + 2 * lsb / (WIN / (double)HZ));
    assert_true(fabs(peak - want) <= 0.03 * want);
    /* the job without the override: 0.9 s; with it, shorter */
    assert_true(port_posix_now() < (uint64_t)(0.9 * HZ));
}

/* Spindle override: M3 at 500/1000; 150 % sets 750 at once (no motion needed), 300 % is capped
 * at full power, back to 100 % gives 500 again; an ABORT puts the scales back to 100 %. */
static void test_spindle_override(void **state)
{
    (void)state;
    cs_proto_msg_t sp = {.type = CS_PROTO_SPINDLE};
    sp.u.spindle = (cs_proto_spindle_t){CS_PROTO_SPINDLE_CW, 0, 500, 0};
    assert_int_equal(cs_fw_motion_queue(&mo, &sp, 0), CS_OK);
    run_until(1000);
    const uint16_t ov[] = {1500, 3000, 1000};
    const double want[] = {750, 1000, 500};
    for (unsigned i = 0; i < 3; i++) {
        set_override(CS_PROTO_OVERRIDE_ONE, ov[i]);
        size_t n;
        const port_posix_spindle_t *r = port_posix_spindles(&n);
        assert_int_equal(n, 2 + i);
        assert_true(fabs(r[n - 1].duty - fmin(500.0 * ov[i] / 1000, 1000)) <= 0.5);
        assert_true(fabs(r[n - 1].duty - want[i]) <= 0.5);
        assert_int_equal(r[n - 1].mode, CS_PROTO_SPINDLE_CW);
    }
    set_override(CS_PROTO_OVERRIDE_ONE, 2000);
    cs_fw_motion_abort(&mo);
    assert_int_equal(mo.hold.target, CS_HOLD_SCALE_ONE);
    assert_int_equal(mo.ctl.sp_ov, CS_PROTO_OVERRIDE_ONE);
}

/* Laser (power 800, full power from 50 mm/s) on 100 mm/s segments, spindle override 50 %
 * before the job: every segment's duty is 800 x 0.5 = 400; a feed override of 50 % on the same
 * kind of job keeps the laser's power following the real speed: 800 x min(1, 50 / 50) = 800 at
 * 50 mm/s, and a 25 % feed gives 800 x 25 / 50 = 400. */
static void test_laser_under_overrides(void **state)
{
    (void)state;
    cs_proto_msg_t sp = {.type = CS_PROTO_SPINDLE};
    sp.u.spindle = (cs_proto_spindle_t){CS_PROTO_SPINDLE_CW, CS_PROTO_SPINDLE_LASER, 800, Q16(50)};
    const uint16_t feed[] = {1000, 250};
    const uint16_t spin[] = {500, 1000};
    const double want[] = {800 * 0.5, 800 * (100 * 0.25 / 50)};
    for (unsigned c = 0; c < 2; c++) {
        set_override(feed[c], spin[c]);
        assert_int_equal(cs_fw_motion_queue(&mo, &sp, 0), CS_OK);
        for (uint16_t k = 0; k < 200; k++)
            queue_x(40, (uint16_t)(k + 1)); /* 0.5 mm a 5 ms: 100 mm/s */
        uint64_t t0 = port_posix_now();
        run_until(UINT64_MAX);
        size_t n;
        const port_posix_spindle_t *r = port_posix_spindles(&n);
        /* the duty once the scale has settled (the last setting while moving) */
        double last = -1;
        for (size_t i = 0; i < n; i++)
            if (r[i].t > t0 && r[i].duty != 0)
                last = r[i].duty;
        assert_true(fabs(last - want[c]) <= 1.0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_feed_override_mid_job, setup, teardown),
        cmocka_unit_test_setup_teardown(test_feed_over_100_keeps_accel, setup, teardown),
        cmocka_unit_test_setup_teardown(test_spindle_override, setup, teardown),
        cmocka_unit_test_setup_teardown(test_laser_under_overrides, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
