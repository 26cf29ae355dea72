/* Tests of the device's Modbus front end (firmware/app/cs_fw_modbus.c) over the motion side on
 * the POSIX port: the identity and status registers' source (queue size, axes, tick rate, boot
 * id, free slots, last executed, position: compared with what was queued), a mailbox write that
 * finds no slot (CS_ERR_FULL: exception DEVICE_BUSY), HOLD/RESUME/ABORT through the command
 * hook, the execution error latch (FAULT until RESET, the motion aborted), and the writer
 * lease's clock: it ends CS_FW_MODBUS_LEASE_MS after the holder's last claim or write, not a
 * millisecond before, across the wrap of the millisecond counter. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "cs_fw_app.h"
#include "cs_fw_modbus.h"
#include "fw_test.h"
#include "port_posix.h"

static cs_machine_t machine;
static cs_fw_motion_t mo;
static cs_fw_modbus_t fm;
static cs_modbus_app_t app;

static int setup(void **state)
{
    (void)state;
    if (fw_test_motion(&machine, &mo, 4) != 0)
        return -1;
    cs_fw_modbus_init(&fm, &mo, 0x1234u, &app);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    port_stepper_attach(NULL);
    return 0;
}

static cs_proto_msg_t seg(int32_t x)
{
    cs_proto_msg_t m = {.type = CS_PROTO_SEGMENT};
    m.u.segment.ticks = 500;
    m.u.segment.steps[0] = x;
    return m;
}

static void run_all(void)
{
    for (int k = 0; k < 1000; k++) {
        cs_fw_modbus_poll(&fm);
        if (cs_stepper_idle(&mo.st))
            break;
        port_posix_run(UINT64_MAX);
    }
    cs_fw_modbus_poll(&fm);
}

static void test_status_and_queue(void **state)
{
    (void)state;
    cs_modbus_status_t st;
    app.status(app.ctx, &st);
    assert_int_equal(st.queue_size, 4);
    assert_int_equal(st.free_slots, 4);
    assert_int_equal(st.axes, 3);
    assert_int_equal(st.tick_hz, 100000);
    assert_int_equal(st.boot_id, 0x1234u);
    assert_int_equal(st.caps, CS_PROTO_CAP_ALL);
    assert_int_equal(st.state, CS_PROTO_STATE_IDLE);
    for (uint16_t k = 0; k < 4; k++) {
        cs_proto_msg_t m = seg(10 + k);
        assert_int_equal(app.submit(app.ctx, &m, k), CS_OK);
    }
    cs_proto_msg_t m = seg(1);
    assert_int_equal(app.submit(app.ctx, &m, 4), CS_ERR_FULL);
    app.status(app.ctx, &st);
    assert_int_equal(st.free_slots, 0);
    run_all();
    app.status(app.ctx, &st);
    assert_int_equal(st.last_exec, 3);
    assert_int_equal(st.pos[0], 10 + 11 + 12 + 13);
    assert_int_equal(st.free_slots, 4);
    m.type = CS_PROTO_HOLD;
    assert_int_equal(app.submit(app.ctx, &m, 5), CS_ERR_UNSUPPORTED);
}

static void test_commands_and_error_latch(void **state)
{
    (void)state;
    cs_modbus_status_t st;
    cs_proto_msg_t m = seg(50);
    assert_int_equal(app.submit(app.ctx, &m, 0), CS_OK);
    app.command(app.ctx, CS_MODBUS_CMD_HOLD);
    cs_fw_modbus_poll(&fm);
    port_posix_run(UINT64_MAX); /* the executor meets the hold: refuses the segment, at rest */
    cs_fw_modbus_poll(&fm);
    app.status(app.ctx, &st);
    assert_int_equal(st.state, CS_PROTO_STATE_HELD);
    app.command(app.ctx, CS_MODBUS_CMD_RESUME);
    run_all();
    app.status(app.ctx, &st);
    assert_int_equal(st.state, CS_PROTO_STATE_IDLE);
    assert_int_equal(st.pos[0], 50);
    /* an execution error: latched, the queue aborted, FAULT until RESET */
    assert_int_equal(app.submit(app.ctx, &m, 1), CS_OK);
    assert_int_equal(app.submit(app.ctx, &m, 2), CS_OK);
    cs_fw_motion_error(&mo, CS_ERR_RANGE, 1);
    cs_fw_motion_error(&mo, CS_ERR_FRAME, 2);
    cs_fw_modbus_collect(&fm); /* before the motion took them: both are dropped */
    run_all();
    app.status(app.ctx, &st);
    assert_int_equal(st.state, CS_PROTO_STATE_FAULT);
    assert_int_equal(st.error, CS_ERR_RANGE); /* the first one stays */
    assert_int_equal(st.error_seq, 1);
    assert_int_equal(st.pos[0], 50); /* the abort dropped what was queued */
    assert_int_equal(st.free_slots, 4);
    app.command(app.ctx, CS_MODBUS_CMD_RESET);
    app.status(app.ctx, &st);
    assert_int_equal(st.error, 0);
    assert_int_equal(st.state, CS_PROTO_STATE_ABORTED);
}

/* At start ms: the holder 0xA1 claims; another token (0xB2) is refused until the lease ends,
 * 5000 ms after the holder's last claim or write, when it may take it. */
static void lease_run(uint32_t start)
{
    cs_modbus_status_t st;
    cs_fw_modbus_clock(&fm, start);
    app.status(app.ctx, &st);
    assert_int_equal(st.lease, 0);
    assert_int_equal(app.lease(app.ctx, CS_MODBUS_LEASE_CLAIM, 0xA1), CS_OK);
    app.status(app.ctx, &st);
    assert_int_equal(st.lease, 1);
    assert_int_equal(st.lease_left_ms, CS_FW_MODBUS_LEASE_MS);
    assert_int_equal(app.lease(app.ctx, CS_MODBUS_LEASE_CLAIM, 0xB2), CS_ERR_LEASED);
    assert_int_equal(app.lease(app.ctx, CS_MODBUS_LEASE_WRITE, 0xB2), CS_ERR_LEASED);
    assert_int_equal(app.lease(app.ctx, CS_MODBUS_LEASE_WRITE, 0), CS_ERR_LEASED);
    assert_int_equal(app.lease(app.ctx, CS_MODBUS_LEASE_RELEASE, 0xB2), CS_ERR_LEASED);
    /* the holder's write at +3000 renews it: +7999 still held, +8000 over */
    cs_fw_modbus_clock(&fm, start + 3000u);
    assert_int_equal(app.lease(app.ctx, CS_MODBUS_LEASE_WRITE, 0xA1), CS_OK);
    cs_fw_modbus_clock(&fm, start + 7999u);
    app.status(app.ctx, &st);
    assert_int_equal(st.lease_left_ms, 1);
    assert_int_equal(app.lease(app.ctx, CS_MODBUS_LEASE_CLAIM, 0xB2), CS_ERR_LEASED);
    cs_fw_modbus_clock(&fm, start + 8000u);
    app.status(app.ctx, &st);
    assert_int_equal(st.lease, 0);
    assert_int_equal(st.lease_left_ms, 0);
    assert_int_equal(app.lease(app.ctx, CS_MODBUS_LEASE_CLAIM, 0xB2), CS_OK);
    /* now the old holder is the other client; the new one releases and anyone may write */
    assert_int_equal(app.lease(app.ctx, CS_MODBUS_LEASE_WRITE, 0xA1), CS_ERR_LEASED);
    assert_int_equal(app.lease(app.ctx, CS_MODBUS_LEASE_RELEASE, 0xB2), CS_OK);
    assert_int_equal(app.lease(app.ctx, CS_MODBUS_LEASE_WRITE, 0), CS_OK);
    app.status(app.ctx, &st);
    assert_int_equal(st.lease, 0); /* a write with no lease held claims nothing */
}

static void test_lease_expiry(void **state)
{
    (void)state;
    lease_run(1000u);
    lease_run(0xFFFFFFFFu - 4000u); /* the clock wraps between the claim and the end */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_status_and_queue, setup, teardown),
        cmocka_unit_test_setup_teardown(test_commands_and_error_latch, setup, teardown),
        cmocka_unit_test_setup_teardown(test_lease_expiry, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
