/* cs_proto's machine-control messages (docs/protocol.md, "Machine control"): every byte of
 * EVENT, HOME, JOG, JOG_CANCEL, PROBE, SPINDLE and UNLOCK written out by hand from the tables,
 * compared with the encoder and decoded back; the range checks both ways; which use a slot. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "cs_proto.h"

static void expect_bytes(const cs_proto_msg_t *m, const uint8_t *want, size_t n)
{
    uint8_t buf[CS_PROTO_LEN_MAX];
    size_t len = 0;
    assert_int_equal(cs_proto_encode(m, buf, sizeof buf, &len), CS_OK);
    assert_int_equal(len, n);
    assert_memory_equal(buf, want, n);
    cs_proto_msg_t back;
    assert_int_equal(cs_proto_decode(want, n, &back), CS_OK);
    assert_int_equal(back.type, m->type);
    uint8_t again[CS_PROTO_LEN_MAX];
    assert_int_equal(cs_proto_encode(&back, again, sizeof again, &len), CS_OK);
    assert_memory_equal(again, want, n);
    assert_int_equal(cs_proto_decode(want, n - 1, &back), CS_ERR_FRAME);
}

static void expect_refused(const cs_proto_msg_t *m, const uint8_t *raw, size_t n)
{
    uint8_t buf[CS_PROTO_LEN_MAX];
    size_t len;
    cs_proto_msg_t back;
    assert_int_equal(cs_proto_encode(m, buf, sizeof buf, &len), CS_ERR_RANGE);
    assert_int_equal(cs_proto_decode(raw, n, &back), CS_ERR_RANGE);
}

/* EVENT ALARM hard limit, inputs = x max switch (bit 4 = 0x0010), 2 axes at (-1, 256):
 * 13 01 01 10 00 02 | FF FF FF FF | 00 01 00 00. */
static void test_event_layout(void **state)
{
    (void)state;
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_EVENT;
    m.u.event = (cs_proto_event_t){CS_PROTO_EVENT_ALARM, CS_PROTO_ALARM_HARD_LIMIT,
                                   CS_PROTO_IN_MAX(0), 2, {-1, 256, 0, 0}};
    const uint8_t w[] = {0x13, 0x01, 0x01, 0x10, 0x00, 0x02, 0xFF, 0xFF,
                         0xFF, 0xFF, 0x00, 0x01, 0x00, 0x00};
    assert_int_equal(sizeof w, CS_PROTO_LEN_EVENT(2));
    expect_bytes(&m, w, sizeof w);
    /* kind 0 and 5, an input bit past the e-stop (0x0400), axes 0 */
    uint8_t r[sizeof w];
    memcpy(r, w, sizeof w);
    cs_proto_msg_t bad = m;
    bad.u.event.kind = 0;
    r[1] = 0;
    expect_refused(&bad, r, sizeof r);
    bad.u.event.kind = CS_PROTO_EVENT_COUNT_;
    r[1] = CS_PROTO_EVENT_COUNT_;
    expect_refused(&bad, r, sizeof r);
    bad = m;
    memcpy(r, w, sizeof w);
    bad.u.event.inputs = 0x0400;
    r[3] = 0x00;
    r[4] = 0x04;
    expect_refused(&bad, r, sizeof r);
    memcpy(r, w, sizeof w);
    r[5] = 0;
    cs_proto_msg_t back;
    assert_int_equal(cs_proto_decode(r, CS_PROTO_LEN_EVENT(1), &back), CS_ERR_RANGE);
}

/* HOME axis z (2) at the max end, seek 10 mm/s (0x000A0000), latch 0.5 mm/s (0x00008000),
 * pull-off 1 mm (0x00010000), search 300 mm (0x012C0000), home -2.5 mm (0xFFFD8000). */
static void test_home_layout(void **state)
{
    (void)state;
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_HOME;
    m.u.home = (cs_proto_home_t){2, CS_PROTO_HOME_MAX, 10 << 16, 1 << 15, 1 << 16, 300 << 16,
                                 -(5 << 15)};
    const uint8_t w[] = {0x26, 0x02, 0x01, 0x00, 0x00, 0x0A, 0x00, 0x00, 0x80, 0x00, 0x00, 0x00,
                         0x00, 0x01, 0x00, 0x00, 0x00, 0x2C, 0x01, 0x00, 0x80, 0xFD, 0xFF};
    assert_int_equal(sizeof w, CS_PROTO_LEN_HOME);
    expect_bytes(&m, w, sizeof w);
    uint8_t r[sizeof w];
    cs_proto_msg_t bad = m;
    memcpy(r, w, sizeof w);
    bad.u.home.axis = 4;
    r[1] = 4;
    expect_refused(&bad, r, sizeof r);
    bad = m;
    memcpy(r, w, sizeof w);
    bad.u.home.flags = 2;
    r[2] = 2;
    expect_refused(&bad, r, sizeof r);
    bad = m;
    memcpy(r, w, sizeof w);
    bad.u.home.seek = 0;
    r[5] = 0;
    expect_refused(&bad, r, sizeof r);
    bad = m;
    memcpy(r, w, sizeof w);
    bad.u.home.search = 0;
    r[17] = r[18] = 0;
    expect_refused(&bad, r, sizeof r);
}

/* JOG to (1, -1, 0.5) mm at 20 mm/s; PROBE to (0, 0, -10) at 2 mm/s, G38.3 (no error). */
static void test_jog_probe_layout(void **state)
{
    (void)state;
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_JOG;
    m.u.jog.target = (cs_vec3_t){1 << 16, -(1 << 16), 1 << 15};
    m.u.jog.feed = 20 << 16;
    const uint8_t j[] = {0x27, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0xFF, 0xFF, 0x00,
                         0x80, 0x00, 0x00, 0x00, 0x00, 0x14, 0x00};
    assert_int_equal(sizeof j, CS_PROTO_LEN_JOG);
    expect_bytes(&m, j, sizeof j);
    cs_proto_msg_t bad = m;
    uint8_t r[sizeof j];
    memcpy(r, j, sizeof j);
    bad.u.jog.feed = 0;
    r[15] = 0;
    expect_refused(&bad, r, sizeof r);

    memset(&m, 0, sizeof m);
    m.type = CS_PROTO_PROBE;
    m.u.probe.target = (cs_vec3_t){0, 0, -(10 << 16)};
    m.u.probe.feed = 2 << 16;
    m.u.probe.flags = CS_PROTO_PROBE_NO_ERROR;
    const uint8_t p[] = {0x29, 0, 0, 0, 0, 0, 0, 0, 0, 0x00, 0x00, 0xF6, 0xFF,
                         0x00, 0x00, 0x02, 0x00, 0x02};
    assert_int_equal(sizeof p, CS_PROTO_LEN_PROBE);
    expect_bytes(&m, p, sizeof p);
    uint8_t r2[sizeof p];
    memcpy(r2, p, sizeof p);
    bad = m;
    bad.u.probe.flags = 4;
    r2[17] = 4;
    expect_refused(&bad, r2, sizeof r2);
}

/* SPINDLE CCW, laser, power 750/1000 (0x02EE), feed 25 mm/s; power 1001 refused. */
static void test_spindle_and_short_layout(void **state)
{
    (void)state;
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_SPINDLE;
    m.u.spindle = (cs_proto_spindle_t){CS_PROTO_SPINDLE_CCW, CS_PROTO_SPINDLE_LASER, 750,
                                       25 << 16};
    const uint8_t w[] = {0x2A, 0x02, 0x01, 0xEE, 0x02, 0x00, 0x00, 0x19, 0x00};
    assert_int_equal(sizeof w, CS_PROTO_LEN_SPINDLE);
    expect_bytes(&m, w, sizeof w);
    uint8_t r[sizeof w];
    memcpy(r, w, sizeof w);
    cs_proto_msg_t bad = m;
    bad.u.spindle.power = 1001;
    r[3] = 0xE9;
    r[4] = 0x03;
    expect_refused(&bad, r, sizeof r);
    memcpy(r, w, sizeof w);
    bad = m;
    bad.u.spindle.mode = 3;
    r[1] = 3;
    expect_refused(&bad, r, sizeof r);
    memcpy(r, w, sizeof w);
    bad = m;
    bad.u.spindle.feed = -1;
    r[5] = r[6] = r[7] = r[8] = 0xFF;
    expect_refused(&bad, r, sizeof r);
    const uint8_t types[] = {CS_PROTO_JOG_CANCEL, CS_PROTO_UNLOCK};
    for (size_t i = 0; i < sizeof types; i++) {
        cs_proto_msg_t c = {.type = types[i]};
        expect_bytes(&c, &types[i], 1);
        assert_false(cs_proto_uses_slot(types[i]));
    }
    const uint8_t slot[] = {CS_PROTO_HOME, CS_PROTO_JOG, CS_PROTO_PROBE, CS_PROTO_SPINDLE};
    for (size_t i = 0; i < sizeof slot; i++)
        assert_true(cs_proto_uses_slot(slot[i]));
    assert_false(cs_proto_uses_slot(CS_PROTO_EVENT));
    assert_true(cs_proto_state_busy(CS_PROTO_STATE_HOMING));
    assert_true(cs_proto_state_busy(CS_PROTO_STATE_JOG));
    assert_true(cs_proto_state_busy(CS_PROTO_STATE_RUNNING));
    assert_false(cs_proto_state_busy(CS_PROTO_STATE_ALARM));
    assert_false(cs_proto_state_busy(CS_PROTO_STATE_IDLE));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_event_layout),
        cmocka_unit_test(test_home_layout),
        cmocka_unit_test(test_jog_probe_layout),
        cmocka_unit_test(test_spindle_and_short_layout),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
