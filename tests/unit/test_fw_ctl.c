/* Tests of the device's machine control (firmware/app/cs_fw_ctl.c) on the POSIX port with a
 * simulated machine: switches and a probe surface at fixed physical positions (the step count on
 * the STEP/DIR lines), checked against positions computed here by hand from the firmware
 * images' default machine (80 steps/mm): homing ends pull-off past the switch with the position
 * set; a hard limit stops a job on the very step that reached the switch, reports it and refuses
 * motion until UNLOCK; the e-stop likewise, UNLOCK refused while pressed; a jog cancel
 * decelerates and keeps the position exact; a probe reports the step of contact; a laser's
 * recorded power follows each segment's speed; a synchronous spindle is set between segments. */
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

#define SPM     80   /* steps/mm of cs_fw_machine_default */
#define X_MIN   -400 /* x min switch: active at x <= -5 mm */
#define X_MAX   800  /* x max switch: active at x >= 10 mm */
#define Z_PROBE -240 /* probe surface: touching at z <= -3 mm */
#define Q16(mm) ((int32_t)((mm) * 65536.0))

static cs_machine_t machine;
static cs_fw_motion_t mo;

static uint16_t model(void *ctx, const int64_t *pos)
{
    (void)ctx;
    uint16_t b = 0;
    if (pos[0] <= X_MIN)
        b |= CS_PROTO_IN_MIN(0);
    if (pos[0] >= X_MAX)
        b |= CS_PROTO_IN_MAX(0);
    if (pos[2] <= Z_PROBE)
        b |= CS_PROTO_IN_PROBE;
    return b;
}

static int setup(void **state)
{
    (void)state;
    port_posix_inputs_force(0, 0);
    port_posix_inputs_model(model, NULL);
    return fw_test_motion(&machine, &mo, 64);
}

/* The main loop and the step interrupt until the device is done (not busy, nothing queued) and
 * still, with a generous bound on simulated time (60 s). */
static void run_done(void)
{
    uint64_t end = port_posix_now() + 60u * machine.tick_hz;
    while (port_posix_now() < end) {
        cs_fw_motion_poll(&mo);
        if (cs_fw_motion_done(&mo) && !mo.ctl.cancel && mo.ctl.trip == CS_FW_TRIP_NONE)
            break;
        if (!port_posix_run(port_posix_now() + 50))
            break;
        port_posix_idle_until(port_posix_now() + 50);
    }
    cs_fw_motion_poll(&mo);
}

static void queue(const cs_proto_msg_t *m, uint16_t seq)
{
    assert_int_equal(cs_fw_motion_queue(&mo, m, seq), CS_OK);
}

static bool pop_event(uint8_t kind, cs_proto_event_t *e)
{
    while (cs_fw_ctl_peek_event(&mo, e)) {
        cs_fw_ctl_drop_event(&mo);
        if (e->kind == kind)
            return true;
    }
    return false;
}

static cs_proto_msg_t seg(uint32_t ticks, int32_t x, int32_t z)
{
    cs_proto_msg_t m = {.type = CS_PROTO_SEGMENT};
    m.u.segment.ticks = ticks;
    m.u.segment.steps[0] = x;
    m.u.segment.steps[2] = z;
    return m;
}

/* HOME x on its min switch: seek 20 mm/s up to 50 mm, latch 1 mm/s, pull-off 2 mm, position
 * set to 1.5 mm. The switch is active from step -400 on, so the latch stops at -400 and the
 * pull-off ends at -400 + 2 x 80 = -240 physical steps; the device then reads 1.5 x 80 = 120. */
static void test_home(void **state)
{
    (void)state;
    cs_proto_msg_t m = {.type = CS_PROTO_HOME};
    m.u.home = (cs_proto_home_t){0, 0, Q16(20), Q16(1), Q16(2), Q16(50), Q16(1.5)};
    queue(&m, 7);
    cs_fw_motion_poll(&mo);
    assert_int_equal(mo.state, CS_PROTO_STATE_HOMING);
    run_done();
    assert_int_equal(mo.state, CS_PROTO_STATE_IDLE);
    assert_int_equal(port_posix_position(0), -240);
    assert_int_equal(cs_fw_motion_position(&mo, 0), 120);
    assert_int_equal(mo.exec_seq, 7);
    cs_proto_event_t e;
    assert_true(pop_event(CS_PROTO_EVENT_HOMED, &e));
    assert_int_equal(e.code, 0);
    assert_int_equal(e.pos[0], 120);
    assert_int_equal(mo.ctl.homed, 1);
    /* a job after homing runs in the new coordinates: +80 steps lands on 200 */
    cs_proto_msg_t s = seg(1000, 80, 0);
    queue(&s, 8);
    run_done();
    assert_int_equal(cs_fw_motion_position(&mo, 0), 200);
}

/* Homing with no switch within the search distance: ALARM 9 (approach). */
static void test_home_no_switch(void **state)
{
    (void)state;
    cs_proto_msg_t m = {.type = CS_PROTO_HOME};
    m.u.home = (cs_proto_home_t){1, 0, Q16(20), Q16(1), Q16(1), Q16(5), 0};
    queue(&m, 3);
    run_done();
    assert_int_equal(mo.state, CS_PROTO_STATE_ALARM);
    cs_proto_event_t e;
    assert_true(pop_event(CS_PROTO_EVENT_ALARM, &e));
    assert_int_equal(e.code, CS_PROTO_ALARM_HOMING_APPROACH);
    assert_int_equal(port_posix_position(1), -5 * SPM);
}

/* A job of 40 segments of +50 x steps runs into the max switch at step 800: it stops on that
 * very step (no deceleration), ALARM 1 names the switch, an ERROR LIMIT goes to the host, the
 * queue is gone, new motion is refused until UNLOCK, and motion runs again after it. */
static void test_hard_limit(void **state)
{
    (void)state;
    for (uint16_t k = 0; k < 40; k++) {
        cs_proto_msg_t s = seg(500, 50, 0);
        queue(&s, k);
    }
    run_done();
    assert_int_equal(mo.state, CS_PROTO_STATE_ALARM);
    assert_int_equal(port_posix_position(0), X_MAX);
    assert_int_equal(cs_fw_motion_position(&mo, 0), X_MAX);
    cs_proto_event_t e;
    assert_true(pop_event(CS_PROTO_EVENT_ALARM, &e));
    assert_int_equal(e.code, CS_PROTO_ALARM_HARD_LIMIT);
    assert_int_equal(e.inputs, CS_PROTO_IN_MAX(0));
    assert_int_equal(e.pos[0], X_MAX);
    cs_proto_error_t er;
    assert_true(cs_fw_motion_pop_error(&mo, &er));
    assert_int_equal(er.code, CS_ERR_LIMIT);
    assert_int_equal(er.seq, 800 / 50 - 1); /* the segment that made step 800 */
    assert_int_equal(mo.qcount, 0);
    cs_proto_msg_t back = seg(500, -50, 0);
    assert_int_equal(cs_fw_motion_queue(&mo, &back, 50), CS_ERR_STATE);
    assert_int_equal(cs_fw_ctl_unlock(&mo), CS_OK);
    cs_fw_motion_poll(&mo);
    assert_int_equal(mo.state, CS_PROTO_STATE_IDLE);
    queue(&back, 51);
    run_done();
    assert_int_equal(port_posix_position(0), X_MAX - 50);
    assert_int_equal(mo.state, CS_PROTO_STATE_IDLE);
}

/* The e-stop mid-job: ALARM 10 at once, UNLOCK refused while it is pressed. */
static void test_estop(void **state)
{
    (void)state;
    for (uint16_t k = 0; k < 10; k++) {
        cs_proto_msg_t s = seg(500, 0, 10);
        queue(&s, k);
    }
    cs_fw_motion_poll(&mo);
    port_posix_run(port_posix_now() + 1234);
    int64_t at = port_posix_position(2);
    port_posix_inputs_force(CS_PROTO_IN_ESTOP, CS_PROTO_IN_ESTOP);
    run_done();
    assert_int_equal(port_posix_position(2), at);
    assert_int_equal(mo.state, CS_PROTO_STATE_ALARM);
    cs_proto_event_t e;
    assert_true(pop_event(CS_PROTO_EVENT_ALARM, &e));
    assert_int_equal(e.code, CS_PROTO_ALARM_ESTOP);
    assert_int_equal(cs_fw_ctl_unlock(&mo), CS_ERR_STATE);
    port_posix_inputs_force(0, 0);
    assert_int_equal(cs_fw_ctl_unlock(&mo), CS_OK);
    cs_fw_motion_poll(&mo);
    assert_int_equal(mo.state, CS_PROTO_STATE_IDLE);
}

/* The step times of axis 0 since edge k0: the interval between the last two, in ticks. */
static double last_interval(size_t *n_out)
{
    size_t n;
    const port_posix_edge_t *ed = port_posix_edges(&n);
    *n_out = n;
    double prev = -1, last = 0;
    for (size_t i = 0; i < n; i++) {
        if (ed[i].axis != 0)
            continue;
        if (prev >= 0)
            last = (double)ed[i].t - prev;
        prev = (double)ed[i].t;
    }
    return last;
}

/* A jog to x = 50 mm at 100 mm/s, cancelled after 30 ms (cruising): the device decelerates (the
 * last step interval is well over the cruise's 100 us = 1 / (100 mm/s x 80 steps/mm)), stops
 * short of the target, goes back to IDLE (not ABORTED) with its position equal to the steps on
 * the lines, and a new jog then reaches its target exactly. */
static void test_jog_cancel(void **state)
{
    (void)state;
    port_posix_inputs_model(NULL, NULL);
    cs_proto_msg_t j = {.type = CS_PROTO_JOG};
    j.u.jog.target = (cs_vec3_t){Q16(50), 0, 0};
    j.u.jog.feed = Q16(100);
    queue(&j, 1);
    cs_fw_motion_poll(&mo);
    assert_int_equal(mo.state, CS_PROTO_STATE_JOG);
    uint64_t until = port_posix_now() + 3000; /* 30 ms */
    while (port_posix_now() < until) {
        cs_fw_motion_poll(&mo);
        port_posix_run(port_posix_now() + 50);
    }
    cs_fw_ctl_jog_cancel(&mo);
    run_done();
    size_t n;
    double iv = last_interval(&n);
    assert_true(iv > 4 * 12.5); /* below a quarter of the cruise speed at the end */
    assert_int_equal(mo.state, CS_PROTO_STATE_IDLE);
    int64_t x = port_posix_position(0);
    assert_true(x > 0 && x < 50 * SPM);
    assert_int_equal(cs_fw_motion_position(&mo, 0), x);
    queue(&j, 2);
    run_done();
    assert_int_equal(port_posix_position(0), 50 * SPM);
    assert_int_equal(mo.state, CS_PROTO_STATE_IDLE);
}

/* PROBE towards z = -10 mm at 2 mm/s: contact at step -240 exactly, EVENT PROBE code 1 there.
 * Again from there: already touching, ALARM 4. */
static void test_probe(void **state)
{
    (void)state;
    cs_proto_msg_t p = {.type = CS_PROTO_PROBE};
    p.u.probe.target = (cs_vec3_t){0, 0, Q16(-10)};
    p.u.probe.feed = Q16(2);
    queue(&p, 1);
    run_done();
    cs_proto_event_t e;
    assert_true(pop_event(CS_PROTO_EVENT_PROBE, &e));
    assert_int_equal(e.code, 1);
    assert_int_equal(e.pos[2], Z_PROBE);
    assert_int_equal(port_posix_position(2), Z_PROBE);
    assert_int_equal(mo.state, CS_PROTO_STATE_IDLE);
    assert_int_equal(mo.exec_seq, 1);
    queue(&p, 2);
    run_done();
    assert_true(pop_event(CS_PROTO_EVENT_ALARM, &e));
    assert_int_equal(e.code, CS_PROTO_ALARM_PROBE_INITIAL);
    /* away (G38.4): from contact, up until the probe lets go at -239 */
    assert_int_equal(cs_fw_ctl_unlock(&mo), CS_OK);
    p.u.probe.target = (cs_vec3_t){0, 0, Q16(0)};
    p.u.probe.flags = CS_PROTO_PROBE_AWAY;
    queue(&p, 3);
    run_done();
    assert_true(pop_event(CS_PROTO_EVENT_PROBE, &e));
    assert_int_equal(e.code, 1);
    assert_int_equal(e.pos[2], Z_PROBE + 1);
}

/* A probe that ends without contact: G38.3 (no error) says so and stays IDLE, G38.2 alarms. */
static void test_probe_no_contact(void **state)
{
    (void)state;
    cs_proto_msg_t p = {.type = CS_PROTO_PROBE};
    p.u.probe.target = (cs_vec3_t){0, 0, Q16(-1)};
    p.u.probe.feed = Q16(5);
    p.u.probe.flags = CS_PROTO_PROBE_NO_ERROR;
    queue(&p, 1);
    run_done();
    cs_proto_event_t e;
    assert_true(pop_event(CS_PROTO_EVENT_PROBE, &e));
    assert_int_equal(e.code, 0);
    assert_int_equal(mo.state, CS_PROTO_STATE_IDLE);
    assert_int_equal(port_posix_position(2), -SPM);
    p.u.probe.target = (cs_vec3_t){0, 0, Q16(-2)};
    p.u.probe.flags = 0;
    queue(&p, 2);
    run_done();
    assert_true(pop_event(CS_PROTO_EVENT_ALARM, &e));
    assert_int_equal(e.code, CS_PROTO_ALARM_PROBE_CONTACT);
    assert_int_equal(mo.state, CS_PROTO_STATE_ALARM);
}

/* Laser mode, power 800/1000 at 50 mm/s: segments of 5 ms with k x 5 x-steps (k = 0..39, v =
 * k x 5 / 80 / 0.005 = 12.5 k mm/s) and a 3-4 diagonal. Each segment's recorded duty, set when it
 * starts, is 800 x min(1, v / 50), here in double (the device rounds down: within 1); a segment
 * without steps has the beam off, and so has the executor when the job ended. */
static void test_laser_power(void **state)
{
    (void)state;
    port_posix_inputs_model(NULL, NULL); /* the job goes past the x max switch */
    cs_proto_msg_t sp = {.type = CS_PROTO_SPINDLE};
    sp.u.spindle = (cs_proto_spindle_t){CS_PROTO_SPINDLE_CW, CS_PROTO_SPINDLE_LASER, 800,
                                        Q16(50)};
    queue(&sp, 0);
    enum { N = 41 };
    double want[N];
    for (uint16_t k = 0; k < N - 1; k++) {
        cs_proto_msg_t s = seg(500, (int32_t)(5 * k), 0);
        queue(&s, (uint16_t)(k + 1));
        double v = 5.0 * k / SPM / 0.005;
        want[k] = 800.0 * (v < 50 ? v / 50 : 1);
    }
    cs_proto_msg_t d = seg(500, 24, 0); /* 3-4-5: x 24, z 32 steps = 0.3, 0.4 mm: 100 mm/s */
    d.u.segment.steps[2] = 32;
    queue(&d, N);
    want[N - 1] = 800.0;
    uint64_t t0 = port_posix_now();
    run_done();
    size_t n;
    const port_posix_spindle_t *r = port_posix_spindles(&n);
    /* the duty in force at the start of segment k (segments run back to back from t0 + 1) */
    for (unsigned k = 0; k < N; k++) {
        uint64_t t = t0 + 1 + 500u * k;
        int duty = 0; /* the output is off from reset on */
        for (size_t i = 0; i < n; i++)
            if (r[i].t <= t)
                duty = r[i].duty;
        assert_true(fabs(duty - want[k]) <= 1.0);
    }
    assert_int_equal(r[n - 1].duty, 0);
    assert_true(r[n - 1].t >= t0 + 500u * N);
    assert_int_equal(r[1].mode, CS_PROTO_SPINDLE_CW);
}

/* M3 S500 between two segments, not laser: set once the first has run, before the second. */
static void test_spindle_sync(void **state)
{
    (void)state;
    cs_proto_msg_t a = seg(1000, 100, 0), b = seg(1000, 100, 0);
    cs_proto_msg_t sp = {.type = CS_PROTO_SPINDLE};
    sp.u.spindle = (cs_proto_spindle_t){CS_PROTO_SPINDLE_CCW, 0, 500, 0};
    uint64_t t0 = port_posix_now();
    queue(&a, 0);
    queue(&sp, 1);
    queue(&b, 2);
    run_done();
    size_t n, ne;
    const port_posix_spindle_t *r = port_posix_spindles(&n);
    assert_int_equal(n, 1);
    assert_int_equal(r[0].duty, 500);
    assert_int_equal(r[0].mode, CS_PROTO_SPINDLE_CCW);
    assert_true(r[0].t >= t0 + 1000);
    const port_posix_edge_t *ed = port_posix_edges(&ne);
    unsigned before = 0;
    for (size_t i = 0; i < ne; i++)
        before += ed[i].t <= r[0].t;
    assert_int_equal(before, 100);
    assert_int_equal(port_posix_position(0), 200);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_home, setup),
        cmocka_unit_test_setup(test_home_no_switch, setup),
        cmocka_unit_test_setup(test_hard_limit, setup),
        cmocka_unit_test_setup(test_estop, setup),
        cmocka_unit_test_setup(test_jog_cancel, setup),
        cmocka_unit_test_setup(test_probe, setup),
        cmocka_unit_test_setup(test_probe_no_contact, setup),
        cmocka_unit_test_setup(test_laser_power, setup),
        cmocka_unit_test_setup(test_spindle_sync, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
