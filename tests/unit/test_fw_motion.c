/* Tests of the device's motion side (firmware/app/cs_fw_motion.c) running on the POSIX port, as
 * in the simulator: queued SEGMENT messages execute in order, once each, with the last executed
 * sequence and the position as their sums say (computed here from the messages); the queue's
 * credits and its full case; feed hold mid-job reports RUNNING while it ramps down, then HELD
 * at rest with work left and the position of
 * the executed segments, resume finishes with the same segment log as a run without a hold;
 * abort drops what is queued; the take limit; refused message types; a PEN is set exactly
 * between the segments queued around it and the settle segment after it makes no step; SETPOS
 * numbers the job (STATUS done and recv as counted here), states a position only when idle, a
 * reboot forgets both, and an abort gives back the numbers of what it dropped unexecuted. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "cs_fw_app.h"
#include "cs_fw_motion.h"
#include "fw_test.h"
#include "port_posix.h"

#define NSEG 120

static cs_machine_t machine;
static cs_fw_motion_t mo;

/* segment k of the test job: 5 ms, x at 160..200 mm/s, y back and forth */
static cs_proto_msg_t job_msg(unsigned k)
{
    cs_proto_msg_t m = {.type = CS_PROTO_SEGMENT};
    m.u.segment.ticks = 500;
    m.u.segment.steps[0] = 64 + (int32_t)(k % 17);
    m.u.segment.steps[1] = (k / 10) % 2 ? -20 : 20;
    return m;
}

static int setup(void **state)
{
    (void)state;
    return fw_test_motion(&machine, &mo, NSEG);
}

static void queue_job(unsigned n)
{
    for (unsigned k = 0; k < n; k++) {
        cs_proto_msg_t m = job_msg(k);
        assert_int_equal(cs_fw_motion_queue(&mo, &m, (uint16_t)k), CS_OK);
    }
}

/* The main loop and the step interrupt, alternately, until the time `until` or until nothing
 * moves any more. */
static void run_until(uint64_t until)
{
    for (int k = 0; k < 100000; k++) {
        cs_fw_motion_poll(&mo);
        if (cs_stepper_idle(&mo.st) || port_posix_now() >= until)
            break;
        port_posix_run(port_posix_now() + 100 < until ? port_posix_now() + 100 : until);
    }
    cs_fw_motion_poll(&mo);
}

static void sum_steps(unsigned n, int64_t out[2])
{
    out[0] = out[1] = 0;
    for (unsigned k = 0; k < n; k++) {
        cs_proto_msg_t m = job_msg(k);
        out[0] += m.u.segment.steps[0];
        out[1] += m.u.segment.steps[1];
    }
}

static void test_segments_in_order(void **state)
{
    (void)state;
    assert_int_equal(cs_fw_motion_free(&mo), NSEG);
    queue_job(NSEG);
    assert_int_equal(cs_fw_motion_free(&mo), 0);
    cs_proto_msg_t extra = job_msg(0);
    assert_int_equal(cs_fw_motion_queue(&mo, &extra, 999), CS_ERR_FULL);
    run_until(UINT64_MAX);
    assert_true(cs_fw_motion_done(&mo));
    int64_t want[2];
    sum_steps(NSEG, want);
    assert_int_equal(mo.stats.executed, NSEG);
    assert_int_equal(mo.log.n, NSEG);
    cs_proto_status_t st;
    cs_fw_motion_status(&mo, &st);
    assert_int_equal(st.last_seq, NSEG - 1);
    assert_int_equal(st.state, CS_PROTO_STATE_IDLE);
    assert_int_equal(st.pos[0], want[0]);
    assert_int_equal(st.pos[1], want[1]);
    assert_int_equal(port_posix_position(0), want[0]);
    assert_int_equal(port_posix_position(1), want[1]);
    assert_int_equal(port_posix_now(), 500u * NSEG + 1u); /* never ran dry: one kick tick */
    /* protocol 3: the executor's clock when pos was read */
    assert_true(st.flags & CS_PROTO_STATUS_TICK);
    assert_int_equal(st.tick, 500u * NSEG + 1u);
}

static void test_hold_resume(void **state)
{
    (void)state;
    queue_job(NSEG);
    run_until(500u * 30); /* mid-job, at full speed */
    cs_proto_status_t mid; /* moving: the position and the clock of one instant */
    cs_fw_motion_status(&mo, &mid);
    assert_int_equal(mid.tick, (uint32_t)port_posix_now());
    assert_int_equal(mid.pos[0], port_posix_position(0));
    assert_int_equal(mid.pos[1], port_posix_position(1));
    assert_true(mid.pos[0] != 0 || mid.pos[1] != 0);
    cs_fw_motion_hold(&mo, true);
    /* ramping down: RUNNING, not yet HELD (a sender that waits for HELD must not act while the
     * axes still move); a quarter of the ramp later the position has moved on */
    cs_proto_status_t ramp;
    cs_fw_motion_poll(&mo);
    cs_fw_motion_status(&mo, &ramp);
    assert_int_equal(ramp.state, CS_PROTO_STATE_RUNNING);
    assert_true(mo.hold.ramp_ticks > 4);
    run_until(port_posix_now() + mo.hold.ramp_ticks / 4);
    cs_proto_status_t later;
    cs_fw_motion_status(&mo, &later);
    assert_int_equal(later.state, CS_PROTO_STATE_RUNNING);
    assert_true(later.pos[0] != ramp.pos[0] || later.pos[1] != ramp.pos[1]);
    run_until(UINT64_MAX);
    cs_proto_status_t st;
    cs_fw_motion_status(&mo, &st);
    assert_int_equal(st.state, CS_PROTO_STATE_HELD);
    assert_true(cs_hold_stopped(&mo.hold));
    assert_true(cs_stepper_idle(&mo.st));
    assert_false(cs_fw_motion_done(&mo));
    uint32_t ran = mo.stats.executed;
    assert_true(ran > 30 && ran < NSEG);
    int64_t want[2];
    sum_steps(ran, want); /* stopped at a segment end: the executed segments exactly */
    assert_int_equal(st.pos[0], want[0]);
    assert_int_equal(st.pos[1], want[1]);
    assert_int_equal(st.last_seq, ran - 1);
    /* held at rest: time passes, nothing moves */
    run_until(port_posix_now() + 100000);
    assert_int_equal(mo.stats.executed, ran);
    cs_fw_motion_hold(&mo, false);
    run_until(UINT64_MAX);
    assert_true(cs_fw_motion_done(&mo));
    sum_steps(NSEG, want);
    assert_int_equal(mo.stats.executed, NSEG);
    assert_int_equal(port_posix_position(0), want[0]);
    assert_int_equal(port_posix_position(1), want[1]);
    assert_int_equal(mo.stats.holds, 1);
    /* the same segments as a run without a hold: each once, in order */
    cs_exlog_segs_t held = mo.log;
    assert_int_equal(setup(NULL), 0);
    queue_job(NSEG);
    run_until(UINT64_MAX);
    assert_int_equal(held.n, mo.log.n);
    assert_int_equal(held.hash, mo.log.hash);
}

static void test_abort_and_limit(void **state)
{
    (void)state;
    cs_fw_motion_take_limit(&mo, 10);
    queue_job(40);
    run_until(UINT64_MAX);
    assert_int_equal(mo.stats.executed, 10); /* stopped taking after item 10 */
    assert_true(cs_fw_motion_drained(&mo));
    assert_false(cs_fw_motion_done(&mo));
    cs_fw_motion_take_limit(&mo, 0);
    run_until(500u * 5 + port_posix_now());
    cs_fw_motion_abort(&mo);
    run_until(UINT64_MAX);
    cs_proto_status_t st;
    cs_fw_motion_status(&mo, &st);
    assert_int_equal(st.state, CS_PROTO_STATE_ABORTED);
    assert_true(cs_fw_motion_done(&mo));
    uint32_t ran = mo.stats.executed;
    assert_true(ran > 10 && ran < 40);
    int64_t want[2];
    sum_steps(ran, want);
    assert_int_equal(port_posix_position(0), want[0]);
    assert_int_equal(cs_fw_motion_free(&mo), NSEG);
}

static void test_refused_types(void **state)
{
    (void)state;
    cs_proto_msg_t m = {.type = CS_PROTO_STATUS};
    assert_int_equal(cs_fw_motion_queue(&mo, &m, 1), CS_ERR_UNSUPPORTED);
    cs_fw_motion_error(&mo, CS_ERR_RANGE, 7);
    cs_proto_error_t e;
    assert_true(cs_fw_motion_pop_error(&mo, &e));
    assert_int_equal(e.code, CS_ERR_RANGE);
    assert_int_equal(e.seq, 7);
    assert_false(cs_fw_motion_pop_error(&mo, &e));
    assert_int_equal(mo.stats.errors_sent, 1);
    cs_fw_motion_cfg_t c;
    cs_fw_motion_cfg_default(&c, &machine);
    c.queue_size = CS_FW_QUEUE + 1;
    cs_fw_motion_t other;
    assert_int_equal(cs_fw_motion_init(&other, &machine, &c), CS_ERR_ARG);
}

/* Step edges the job's segments k0..k1-1 make (|x| + |y| steps, from job_msg by hand). */
static size_t job_edges(unsigned k0, unsigned k1)
{
    size_t n = 0;
    for (unsigned k = k0; k < k1; k++) {
        cs_proto_msg_t m = job_msg(k);
        n += (size_t)(m.u.segment.steps[0] + (m.u.segment.steps[1] < 0 ? -m.u.segment.steps[1]
                                                                          : m.u.segment.steps[1]));
    }
    return n;
}

/* Edges recorded in the time window (t0, t1]. */
static size_t edges_in(uint64_t t0, uint64_t t1)
{
    size_t n, c = 0;
    const port_posix_edge_t *e = port_posix_edges(&n);
    for (size_t i = 0; i < n; i++)
        c += e[i].t > t0 && e[i].t <= t1;
    return c;
}

/* Segments 0..9, PEN 800 us, settle 15000 ticks (no steps), segments 10..19, PEN 1700 us,
 * settle, segments 20..29: each PEN is set after every step of the segments before it and
 * before any step after it, the settle windows have no steps, and the PENs count as executed. */
static void test_pen_between_segments(void **state)
{
    (void)state;
    const uint32_t settle = 15000;
    const uint16_t pulse[2] = {800, 1700};
    uint16_t seq = 0;
    for (unsigned part = 0; part < 3; part++) {
        for (unsigned k = 10 * part; k < 10 * part + 10; k++) {
            cs_proto_msg_t m = job_msg(k);
            assert_int_equal(cs_fw_motion_queue(&mo, &m, seq++), CS_OK);
        }
        if (part == 2)
            break;
        cs_proto_msg_t p = {.type = CS_PROTO_PEN};
        p.u.pen.pulse_us = pulse[part];
        assert_int_equal(cs_fw_motion_queue(&mo, &p, seq++), CS_OK);
        cs_proto_msg_t w = {.type = CS_PROTO_SEGMENT};
        w.u.segment.ticks = settle;
        assert_int_equal(cs_fw_motion_queue(&mo, &w, seq++), CS_OK);
    }
    run_until(UINT64_MAX);
    assert_true(cs_fw_motion_done(&mo));
    size_t np, ne;
    const port_posix_pen_t *pe = port_posix_pens(&np);
    (void)port_posix_edges(&ne);
    assert_int_equal(np, 2);
    assert_int_equal(mo.stats.pens, 2);
    assert_int_equal(mo.stats.pen_us, 1700);
    assert_int_equal(mo.stats.executed, seq);
    for (unsigned i = 0; i < 2; i++) {
        assert_int_equal(pe[i].pulse_us, pulse[i]);
        /* everything before the PEN has stepped by then, nothing after it has */
        assert_int_equal(edges_in(0, pe[i].t), job_edges(0, 10 * (i + 1)));
        assert_int_equal(edges_in(pe[i].t, pe[i].t + settle), 0);
    }
    /* the settle waits are whole: the next steps come after them */
    assert_true(pe[1].t >= pe[0].t + settle + 500u * 10);
    assert_int_equal(ne, job_edges(0, 30));
    cs_proto_status_t st;
    cs_fw_motion_status(&mo, &st);
    assert_int_equal(st.last_seq, seq - 1);
    /* the log holds the segments (settle ones included), not the PENs */
    assert_int_equal(mo.log.n, 32);
}

/* A PEN waiting for the executor is not set while held, and is dropped by ABORT. */
static void test_pen_hold_and_abort(void **state)
{
    (void)state;
    for (unsigned k = 0; k < 4; k++) {
        cs_proto_msg_t m = job_msg(k);
        assert_int_equal(cs_fw_motion_queue(&mo, &m, (uint16_t)k), CS_OK);
    }
    cs_proto_msg_t p = {.type = CS_PROTO_PEN};
    p.u.pen.pulse_us = 1000;
    assert_int_equal(cs_fw_motion_queue(&mo, &p, 4), CS_OK);
    cs_fw_motion_hold(&mo, true);
    run_until(UINT64_MAX);
    run_until(port_posix_now() + 100000);
    size_t np;
    (void)port_posix_pens(&np);
    assert_int_equal(np, 0);
    cs_fw_motion_abort(&mo);
    cs_fw_motion_hold(&mo, false);
    run_until(UINT64_MAX);
    (void)port_posix_pens(&np);
    assert_int_equal(np, 0);
    assert_true(cs_fw_motion_done(&mo));
}

static int teardown(void **state)
{
    (void)state;
    port_stepper_attach(NULL);
    port_posix_reset(machine.tick_hz, 0);
    return 0;
}

/* SETPOS and the job's numbers (docs/protocol.md, SETPOS; STATUS flags, done, recv). */
static void test_setpos_numbers_the_job(void **state)
{
    (void)state;
    cs_proto_status_t st;
    cs_fw_motion_status(&mo, &st);
    assert_int_equal(st.flags, CS_PROTO_STATUS_TICK); /* after boot: no job, position not stated */
    assert_int_equal(st.done, 0);
    assert_int_equal(st.recv, 0);
    /* a resumed job: messages 1..1000 ran before; the machine is at (800, -80) steps */
    cs_proto_setpos_t sp = {CS_PROTO_SETPOS_POS, 0xABCD1234u, 1000u, {800, -80, 0, 0}};
    assert_int_equal(cs_fw_motion_setpos(&mo, &sp), CS_OK);
    cs_fw_motion_status(&mo, &st);
    assert_int_equal(st.flags, CS_PROTO_STATUS_JOB | CS_PROTO_STATUS_POS | CS_PROTO_STATUS_TICK);
    assert_int_equal(st.job_id, 0xABCD1234u);
    assert_int_equal(st.done, 1000);
    assert_int_equal(st.recv, 1000);
    assert_int_equal(st.pos[0], 800);
    assert_int_equal(st.pos[1], -80);
    queue_job(40);
    cs_fw_motion_status(&mo, &st);
    assert_int_equal(st.recv, 1040); /* received, not executed */
    assert_int_equal(st.done, 1000);
    /* a position can only be stated at rest with nothing queued */
    assert_int_equal(cs_fw_motion_setpos(&mo, &sp), CS_ERR_STATE);
    /* Ctrl-C: hold (the next segment is kept back at rest), then abort */
    run_until(500u * 2 + port_posix_now());
    /* exactly what finished, at any moment (the segments in flight are one more than the
     * ring) */
    assert_int_equal(mo.stats.executed, mo.completed);
    cs_fw_motion_hold(&mo, true);
    run_until(UINT64_MAX);
    assert_true(mo.has_pend);
    cs_fw_motion_give_back(&mo); /* as the ABORT message does (cs_fw_app) */
    cs_fw_motion_abort(&mo);
    run_until(UINT64_MAX);
    cs_fw_motion_status(&mo, &st);
    uint32_t ran = mo.stats.executed;
    assert_true(ran > 0 && ran < 40);
    /* what ran, exactly: the numbers given back by the abort are sent again on a resume */
    assert_int_equal(st.done, 1000 + ran);
    assert_int_equal(st.recv, 1000 + ran);
    int64_t want[2];
    sum_steps(ran, want);
    assert_int_equal(st.pos[0], 800 + want[0]);
    assert_int_equal(st.pos[1], -80 + want[1]);
    /* the lines moved only by what ran; SETPOS's change is kept apart */
    assert_int_equal(port_posix_position(0) + mo.set_delta[0], st.pos[0]);
    /* a reboot forgets the job and the stated position */
    cs_fw_motion_reboot(&mo);
    cs_fw_motion_status(&mo, &st);
    assert_int_equal(st.flags, CS_PROTO_STATUS_TICK);
    assert_int_equal(st.done, 0);
}

/* An UNLOCK the host numbers as a job item counts as received and finished at once, at rest
 * only (never ahead of a queued item). */
static void test_immediate_item_numbered(void **state)
{
    (void)state;
    cs_proto_status_t st;
    cs_fw_motion_count_immediate(&mo); /* no job numbered yet: nothing to count */
    cs_fw_motion_status(&mo, &st);
    assert_int_equal(st.done, 0);
    cs_proto_setpos_t sp = {0, 7u, 5u, {0, 0, 0, 0}};
    assert_int_equal(cs_fw_motion_setpos(&mo, &sp), CS_OK);
    cs_fw_motion_count_immediate(&mo);
    cs_fw_motion_status(&mo, &st);
    assert_int_equal(st.done, 6);
    assert_int_equal(st.recv, 6);
    queue_job(3); /* items 7..9 queued: an immediate message now is not counted */
    cs_fw_motion_count_immediate(&mo);
    cs_fw_motion_status(&mo, &st);
    assert_int_equal(st.recv, 9);
    assert_int_equal(st.done, 6);
    run_until(UINT64_MAX);
    cs_fw_motion_status(&mo, &st);
    assert_int_equal(st.done, 9);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_segments_in_order, setup, teardown),
        cmocka_unit_test_setup_teardown(test_hold_resume, setup, teardown),
        cmocka_unit_test_setup_teardown(test_abort_and_limit, setup, teardown),
        cmocka_unit_test_setup_teardown(test_refused_types, setup, teardown),
        cmocka_unit_test_setup_teardown(test_pen_between_segments, setup, teardown),
        cmocka_unit_test_setup_teardown(test_pen_hold_and_abort, setup, teardown),
        cmocka_unit_test_setup_teardown(test_setpos_numbers_the_job, setup, teardown),
        cmocka_unit_test_setup_teardown(test_immediate_item_numbered, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
