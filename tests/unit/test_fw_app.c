/* Tests of the device's framed-serial front end (firmware/app/cs_fw_app.c) on the POSIX port,
 * talked to by a host end of the core link (cs_link) through the port's UART hooks, on a test
 * clock: the link opens and HELLO says what the build offers (queue size, tick rate, curves);
 * SEGMENT messages are executed and STATUS reports the last executed sequence (the host's own)
 * and the position they add up to; HOLD is reported as HELD; a device-to-host type is refused
 * with an ERROR naming its sequence; a reboot announces a new boot id. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <string.h>

#include "cs_fw_app.h"
#include "port_posix.h"

#define BUF 8192

static cs_machine_t machine;
static cs_fw_app_t app;
static cs_link_t host;
static uint32_t now_us;
static uint8_t to_dev[BUF], to_host[BUF];
static size_t to_dev_n, to_dev_off, to_host_n;
/* what the host received */
static cs_proto_hello_t hello;
static bool have_hello;
static cs_proto_status_t status;
static int statuses;
static cs_proto_error_t error;
static int errors;

static uint32_t clock_us(void)
{
    return now_us;
}

static size_t dev_read(void *ctx, uint8_t *buf, size_t max)
{
    (void)ctx;
    size_t n = to_dev_n - to_dev_off < max ? to_dev_n - to_dev_off : max;
    memcpy(buf, to_dev + to_dev_off, n);
    to_dev_off += n;
    return n;
}

static size_t dev_write(void *ctx, const uint8_t *buf, size_t n)
{
    (void)ctx;
    assert_true(to_host_n + n <= BUF);
    memcpy(to_host + to_host_n, buf, n);
    to_host_n += n;
    return n;
}

static void host_receive(void)
{
    for (size_t k = 0; k < to_host_n; k++) {
        cs_link_event_t ev;
        if (cs_link_feed(&host, to_host[k], now_us, 0, &ev) != CS_OK ||
            !(ev.what & CS_LINK_EV_DELIVER))
            continue;
        cs_proto_msg_t m;
        assert_int_equal(cs_proto_decode(ev.payload, ev.len, &m), CS_OK);
        if (m.type == CS_PROTO_HELLO) {
            hello = m.u.hello;
            have_hello = true;
        } else if (m.type == CS_PROTO_STATUS) {
            status = m.u.status;
            statuses++;
        } else if (m.type == CS_PROTO_ERROR) {
            error = m.u.error;
            errors++;
        }
    }
    to_host_n = 0;
}

/* One millisecond of both ends: the host's bytes, the device's pass, the step timer, back. */
static void pump(int ms)
{
    for (int k = 0; k < ms; k++) {
        const uint8_t *b;
        size_t n;
        to_dev_n = to_dev_off = 0;
        while (cs_link_poll(&host, now_us, 0, &b, &n) == CS_OK && to_dev_n + n <= BUF) {
            memcpy(to_dev + to_dev_n, b, n);
            to_dev_n += n;
        }
        do
            cs_fw_app_poll(&app);
        while (to_dev_off < to_dev_n);
        port_posix_run(port_posix_now() + 100); /* 1 ms at 100 kHz */
        cs_fw_app_poll(&app);
        host_receive();
        now_us += 1000;
    }
}

static int setup(void **state)
{
    (void)state;
    cs_fw_machine_default(&machine, 100000);
    port_posix_reset(machine.tick_hz, 0);
    port_posix_uart_hooks(dev_read, dev_write, NULL);
    now_us = 1000;
    have_hello = false;
    statuses = errors = 0;
    to_host_n = 0;
    cs_fw_app_cfg_t c;
    cs_fw_app_cfg_default(&c, &machine);
    c.clock = clock_us;
    c.clock_hz = 1000000;
    c.link.rto = 50000;
    c.link.nak_holdoff = 2000;
    c.motion.queue_size = 16;
    if (cs_fw_app_init_cfg(&app, &machine, 0xB007u, &c) != CS_OK)
        return -1;
    cs_link_cfg_t hc = c.link;
    return cs_link_init(&host, &hc, 0x4057u, 77u, 0, now_us) == CS_OK ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    port_posix_uart_hooks(NULL, NULL, NULL);
    port_stepper_attach(NULL);
    return 0;
}

static void test_hello_segments_status(void **state)
{
    (void)state;
    pump(200);
    assert_int_equal(cs_link_state(&host), CS_LINK_OPEN);
    assert_true(have_hello);
    assert_int_equal(hello.version, CS_PROTO_VERSION);
    assert_int_equal(hello.boot_id, 0xB007u);
    assert_int_equal(hello.queue_size, 16);
    assert_int_equal(hello.tick_hz, 100000);
    assert_int_equal(hello.axes, 3);
    assert_int_equal(hello.caps, CS_PROTO_CAP_ALL);
    uint16_t seq[6];
    int32_t x = 0;
    for (int k = 0; k < 6; k++) {
        cs_proto_msg_t m = {.type = CS_PROTO_SEGMENT};
        m.u.segment.ticks = 500;
        m.u.segment.steps[0] = 40 + k;
        x += 40 + k;
        assert_int_equal(cs_link_send_msg(&host, &m, &seq[k]), CS_OK);
    }
    pump(300);
    assert_true(statuses > 0);
    assert_int_equal(status.state, CS_PROTO_STATE_IDLE);
    assert_int_equal(status.last_seq, seq[5]);
    assert_int_equal(status.pos[0], x);
    assert_int_equal(port_posix_position(0), x);
    assert_int_equal(app.out_of_order, 0);
    cs_proto_msg_t h = {.type = CS_PROTO_HOLD};
    assert_int_equal(cs_link_send_msg(&host, &h, NULL), CS_OK);
    pump(100);
    assert_int_equal(status.state, CS_PROTO_STATE_HELD);
}

static void test_refused_and_reboot(void **state)
{
    (void)state;
    pump(200);
    cs_proto_msg_t m = {.type = CS_PROTO_HELLO}; /* a device-to-host message */
    m.u.hello = hello;
    uint16_t seq;
    assert_int_equal(cs_link_send_msg(&host, &m, &seq), CS_OK);
    pump(100);
    assert_int_equal(errors, 1);
    assert_int_equal(error.code, CS_ERR_UNSUPPORTED);
    assert_int_equal(error.seq, seq);
    have_hello = false;
    cs_fw_app_reboot(&app, 0xB008u);
    (void)cs_link_restart(&host, 78u, now_us);
    pump(400);
    assert_true(have_hello);
    assert_int_equal(hello.boot_id, 0xB008u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_hello_segments_status, setup, teardown),
        cmocka_unit_test_setup_teardown(test_refused_and_reboot, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
