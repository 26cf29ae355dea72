/* test_proto: every message's byte layout against the offsets of docs/protocol.md, written out
 * here by hand (little-endian, two's complement), round trips with random fields (fixed-seed
 * xorshift), and every malformed payload answered with its documented error code. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "cs_proto.h"

static uint64_t rng_state = 0xB7E151628AED2A6Bull;
static uint64_t rng(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return rng_state;
}

/* Little-endian writers of the reference layouts. */
static void le16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}
static void le32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (uint8_t)(v >> (8 * i));
}

static void expect_range(const cs_proto_msg_t *bad, const uint8_t *raw, size_t n);

static void expect_encoding(const cs_proto_msg_t *m, const uint8_t *want, size_t n)
{
    uint8_t buf[CS_PROTO_LEN_MAX + 8];
    size_t len = 0;
    assert_int_equal(cs_proto_encode(m, buf, sizeof buf, &len), CS_OK);
    assert_int_equal(len, n);
    assert_memory_equal(buf, want, n);
    cs_proto_msg_t back;
    assert_int_equal(cs_proto_decode(want, n, &back), CS_OK);
    uint8_t again[CS_PROTO_LEN_MAX];
    size_t len2 = 0;
    assert_int_equal(cs_proto_encode(&back, again, sizeof again, &len2), CS_OK);
    assert_int_equal(len2, n);
    assert_memory_equal(again, want, n);
    /* One byte short and one byte long are malformed; so is a too-small output buffer. */
    assert_int_equal(cs_proto_decode(want, n - 1, &back), CS_ERR_FRAME);
    uint8_t longer[CS_PROTO_LEN_MAX + 1];
    memcpy(longer, want, n);
    longer[n] = 0;
    assert_int_equal(cs_proto_decode(longer, n + 1, &back), CS_ERR_FRAME);
    assert_int_equal(cs_proto_encode(m, buf, n - 1, &len), CS_ERR_FULL);
}

static void test_ack_and_ping_layout(void **state)
{
    (void)state;
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_ACK;
    m.u.ack = (cs_proto_ack_t){CS_PROTO_ACK_NAK, 0xA1B2, 0x0304, 0xDEADBEEFu, 0x11223344u};
    uint8_t w[CS_PROTO_LEN_ACK] = {0x01, 0x01};
    le16(w + 2, 0xA1B2);
    le16(w + 4, 0x0304);
    le32(w + 6, 0xDEADBEEFu);
    le32(w + 10, 0x11223344u);
    expect_encoding(&m, w, sizeof w);

    m.type = CS_PROTO_PING;
    m.u.ping.nonce = 0xCAFEBABEu;
    uint8_t p[CS_PROTO_LEN_PING] = {0x02};
    le32(p + 1, 0xCAFEBABEu);
    expect_encoding(&m, p, sizeof p);
}

static void test_hello_layout(void **state)
{
    (void)state;
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_HELLO;
    m.u.hello = (cs_proto_hello_t){CS_PROTO_VERSION,
                                   0x01020304u,
                                   3,
                                   64,
                                   1000000u,
                                   CS_PROTO_CAP_SEGMENTS | CS_PROTO_CAP_CURVES};
    uint8_t w[CS_PROTO_LEN_HELLO] = {0x10, CS_PROTO_VERSION};
    le32(w + 2, 0x01020304u);
    w[6] = 3;
    le16(w + 7, 64);
    le32(w + 9, 1000000u);
    le16(w + 13, 3);
    expect_encoding(&m, w, sizeof w);
}

static void test_status_layout_every_axis_count(void **state)
{
    (void)state;
    for (uint8_t axes = 1; axes <= CS_PROTO_AXES_MAX; axes++) {
        cs_proto_msg_t m = {0};
        m.type = CS_PROTO_STATUS;
        m.u.status = (cs_proto_status_t){CS_PROTO_STATE_HELD,
                                         0x89ABCDEFu,
                                         7,
                                         0xFFFE,
                                         axes,
                                         {INT32_MIN, -1, INT32_MAX, 123456},
                                         CS_PROTO_STATUS_JOB | CS_PROTO_STATUS_POS,
                                         0xCAFEF00Du,
                                         70000u,
                                         70016u,
                                         0};
        uint8_t w[CS_PROTO_LEN_STATUS(CS_PROTO_AXES_MAX)] = {0x11, CS_PROTO_STATE_HELD};
        le32(w + 2, 0x89ABCDEFu);
        le16(w + 6, 7);
        le16(w + 8, 0xFFFE);
        w[10] = axes;
        const uint32_t raw[4] = {0x80000000u, 0xFFFFFFFFu, 0x7FFFFFFFu, 123456u};
        for (unsigned i = 0; i < axes; i++)
            le32(w + 11 + 4 * i, raw[i]);
        /* after the positions: flags, job id, last finished, last received */
        w[11 + 4 * axes] = 0x03;
        le32(w + 12 + 4 * axes, 0xCAFEF00Du);
        le32(w + 16 + 4 * axes, 70000u);
        le32(w + 20 + 4 * axes, 70016u);
        /* protocol 2's STATUS: 24 + 4n bytes, no tick */
        assert_int_equal(CS_PROTO_LEN_STATUS2(axes), 24 + 4 * axes);
        expect_encoding(&m, w, (size_t)CS_PROTO_LEN_STATUS2(axes));
        /* protocol 3's: flag bit 2, then the tick (0xFFFFFFF0: near the wrap) after recv */
        m.u.status.flags |= CS_PROTO_STATUS_TICK;
        m.u.status.tick = 0xFFFFFFF0u;
        w[11 + 4 * axes] = 0x07;
        le32(w + 24 + 4 * axes, 0xFFFFFFF0u);
        assert_int_equal(CS_PROTO_LEN_STATUS(axes), 28 + 4 * axes);
        expect_encoding(&m, w, (size_t)CS_PROTO_LEN_STATUS(axes));
        /* the flag and the length disagree: malformed (a tick promised and missing, or four
         * bytes nobody named) */
        cs_proto_msg_t back;
        assert_int_equal(cs_proto_decode(w, (size_t)CS_PROTO_LEN_STATUS2(axes), &back),
                         CS_ERR_FRAME);
        w[11 + 4 * axes] = 0x03;
        assert_int_equal(cs_proto_decode(w, (size_t)CS_PROTO_LEN_STATUS(axes), &back),
                         CS_ERR_FRAME);
        /* an unknown flag bit is refused both ways */
        m.u.status.flags = 0x08 | CS_PROTO_STATUS_TICK;
        w[11 + 4 * axes] = 0x0C;
        expect_range(&m, w, (size_t)CS_PROTO_LEN_STATUS(axes));
    }
    /* the example of docs/protocol.md: 3 axes, held, tick 0x00BC614E = 12345678 */
    static const uint8_t doc[] = {0x11, 0x02, 0xEF, 0xCD, 0xAB, 0x89, 0x07, 0x00, 0xFE, 0xFF,
                                  0x03, 0x00, 0x00, 0x00, 0x80, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF,
                                  0xFF, 0xFF, 0x7F, 0x07, 0x0D, 0xF0, 0xFE, 0xCA, 0x70, 0x11,
                                  0x01, 0x00, 0x80, 0x11, 0x01, 0x00, 0x4E, 0x61, 0xBC, 0x00};
    cs_proto_msg_t d;
    assert_int_equal(sizeof doc, CS_PROTO_LEN_STATUS(3));
    assert_int_equal(cs_proto_decode(doc, sizeof doc, &d), CS_OK);
    assert_int_equal(d.u.status.tick, 12345678u);
    assert_int_equal(d.u.status.pos[2], INT32_MAX);
    assert_int_equal(d.u.status.recv, 70016u);
}

static void test_error_segment_curve_control_layout(void **state)
{
    (void)state;
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_ERROR;
    m.u.error = (cs_proto_error_t){CS_ERR_LIMIT, 0x1234};
    uint8_t e[CS_PROTO_LEN_ERROR] = {0x12, 14, 0x34, 0x12};
    expect_encoding(&m, e, sizeof e);

    memset(&m, 0, sizeof m);
    m.type = CS_PROTO_SEGMENT;
    m.u.segment = (cs_segment_t){5000, {5000, -5000, 0, -1}};
    uint8_t s[CS_PROTO_LEN_SEGMENT] = {0x20};
    le32(s + 1, 5000);
    le32(s + 5, 5000);
    le32(s + 9, (uint32_t)-5000);
    le32(s + 13, 0);
    le32(s + 17, 0xFFFFFFFFu);
    expect_encoding(&m, s, sizeof s);

    memset(&m, 0, sizeof m);
    m.type = CS_PROTO_CURVE;
    uint8_t c[CS_PROTO_LEN_CURVE] = {0x21};
    for (int i = 0; i < 4; i++) {
        m.u.curve.p[i] = (cs_vec3_t){(i - 2) * 65536 * 100, CS_POS_LIMIT - i, -CS_POS_LIMIT + i};
        le32(c + 1 + 12 * i, (uint32_t)m.u.curve.p[i].x);
        le32(c + 5 + 12 * i, (uint32_t)m.u.curve.p[i].y);
        le32(c + 9 + 12 * i, (uint32_t)m.u.curve.p[i].z);
    }
    m.u.curve.feed = 25 * 65536 + 32768; /* 25.5 mm/s */
    le32(c + 49, 25 * 65536 + 32768);
    expect_encoding(&m, c, sizeof c);

    const uint8_t types[] = {CS_PROTO_HOLD, CS_PROTO_RESUME, CS_PROTO_ABORT};
    const uint8_t bytes[] = {0x22, 0x23, 0x24};
    for (int i = 0; i < 3; i++) {
        memset(&m, 0, sizeof m);
        m.type = types[i];
        uint8_t b[1] = {bytes[i]};
        uint8_t buf[4];
        size_t len = 0;
        assert_int_equal(cs_proto_encode(&m, buf, sizeof buf, &len), CS_OK);
        assert_int_equal(len, 1);
        assert_int_equal(buf[0], b[0]);
        cs_proto_msg_t back;
        assert_int_equal(cs_proto_decode(b, 1, &back), CS_OK);
        assert_int_equal(back.type, types[i]);
        uint8_t two[2] = {bytes[i], 0};
        assert_int_equal(cs_proto_decode(two, 2, &back), CS_ERR_FRAME);
    }
}

static void test_unknown_types_and_empty_payload(void **state)
{
    (void)state;
    const uint8_t known[] = {0x01, 0x02, 0x10, 0x11, 0x12, 0x13, 0x20, 0x21, 0x22, 0x23, 0x24,
                             0x25, 0x26, 0x27, 0x28, 0x29, 0x2A, 0x2B, 0x2C, 0x2D, 0x2E};
    uint8_t buf[CS_PROTO_LEN_MAX] = {0};
    cs_proto_msg_t m;
    unsigned unknown = 0;
    for (unsigned t = 0; t < 256; t++) {
        bool is_known = memchr(known, (int)t, sizeof known) != NULL;
        buf[0] = (uint8_t)t;
        for (size_t n = 1; n <= sizeof buf; n++) {
            cs_err_t e = cs_proto_decode(buf, n, &m);
            if (!is_known)
                assert_int_equal(e, CS_ERR_UNSUPPORTED);
        }
        if (!is_known) {
            unknown++;
            memset(&m, 0, sizeof m);
            m.type = (uint8_t)t;
            size_t len;
            assert_int_equal(cs_proto_encode(&m, buf, sizeof buf, &len), CS_ERR_UNSUPPORTED);
            buf[0] = (uint8_t)t;
        }
    }
    assert_int_equal(unknown, 256 - sizeof known);
    assert_int_equal(cs_proto_decode(buf, 0, &m), CS_ERR_FRAME);
    assert_int_equal(cs_proto_decode(NULL, 3, &m), CS_ERR_ARG);
}

/* Each out-of-range field: refused by the encoder and, written raw, by the decoder. */
static void expect_range(const cs_proto_msg_t *bad, const uint8_t *raw, size_t n)
{
    uint8_t buf[CS_PROTO_LEN_MAX];
    size_t len;
    cs_proto_msg_t m;
    assert_int_equal(cs_proto_encode(bad, buf, sizeof buf, &len), CS_ERR_RANGE);
    assert_int_equal(cs_proto_decode(raw, n, &m), CS_ERR_RANGE);
}

static void test_out_of_range_fields(void **state)
{
    (void)state;
    uint8_t buf[CS_PROTO_LEN_MAX];
    size_t len;
    cs_proto_msg_t good = {0}, bad;
    uint8_t raw[CS_PROTO_LEN_MAX];

    good.type = CS_PROTO_SEGMENT;
    good.u.segment = (cs_segment_t){100, {100, -100, 3, 0}};
    assert_int_equal(cs_proto_encode(&good, raw, sizeof raw, &len), CS_OK);
    bad = good;
    bad.u.segment.ticks = 0;
    le32(raw + 1, 0);
    expect_range(&bad, raw, len);
    bad = good;
    bad.u.segment.ticks = CS_PROTO_SEGMENT_MAX_TICKS + 1;
    bad.u.segment.steps[0] = 0;
    assert_int_equal(cs_proto_encode(&good, raw, sizeof raw, &len), CS_OK);
    le32(raw + 1, CS_PROTO_SEGMENT_MAX_TICKS + 1);
    le32(raw + 5, 0);
    expect_range(&bad, raw, len);
    for (int axis = 0; axis < 4; axis++) { /* |steps| > ticks, both signs, INT32_MIN */
        for (int k = 0; k < 3; k++) {
            int32_t v = k == 0 ? 101 : k == 1 ? -101 : INT32_MIN;
            bad = good;
            bad.u.segment.steps[axis] = v;
            assert_int_equal(cs_proto_encode(&good, raw, sizeof raw, &len), CS_OK);
            le32(raw + 5 + 4 * axis, (uint32_t)v);
            expect_range(&bad, raw, len);
        }
    }

    memset(&good, 0, sizeof good);
    good.type = CS_PROTO_CURVE;
    good.u.curve.feed = 65536;
    assert_int_equal(cs_proto_encode(&good, raw, sizeof raw, &len), CS_OK);
    for (int i = 0; i < 12; i++) { /* every coordinate just outside CS_POS_LIMIT */
        bad = good;
        int32_t *coord = &bad.u.curve.p[i / 3].x + i % 3;
        *coord = (i & 1) ? CS_POS_LIMIT + 1 : -CS_POS_LIMIT - 1;
        uint8_t r2[CS_PROTO_LEN_CURVE];
        memcpy(r2, raw, sizeof r2);
        le32(r2 + 1 + 4 * i, (uint32_t)*coord);
        expect_range(&bad, r2, len);
    }
    for (int k = 0; k < 2; k++) { /* feed 0 and negative */
        bad = good;
        bad.u.curve.feed = k == 0 ? 0 : -65536;
        uint8_t r2[CS_PROTO_LEN_CURVE];
        memcpy(r2, raw, sizeof r2);
        le32(r2 + 49, (uint32_t)bad.u.curve.feed);
        expect_range(&bad, r2, len);
    }

    memset(&good, 0, sizeof good);
    good.type = CS_PROTO_HELLO;
    good.u.hello = (cs_proto_hello_t){1, 5, 4, 16, 1000, CS_PROTO_CAP_SEGMENTS};
    assert_int_equal(cs_proto_encode(&good, raw, sizeof raw, &len), CS_OK);
    struct {
        size_t off, width;
        uint32_t v;
    } hello_bad[] = {{1, 1, 0}, {6, 1, 0},  {6, 1, 5},      {7, 2, 0},
                     {9, 4, 0}, {13, 2, 0x10}, {13, 2, 0x8000}};
    for (size_t i = 0; i < sizeof hello_bad / sizeof hello_bad[0]; i++) {
        uint8_t r2[CS_PROTO_LEN_HELLO];
        memcpy(r2, raw, sizeof r2);
        for (size_t b = 0; b < hello_bad[i].width; b++)
            r2[hello_bad[i].off + b] = (uint8_t)(hello_bad[i].v >> (8 * b));
        assert_int_equal(cs_proto_decode(r2, len, &bad), CS_ERR_RANGE);
    }
    bad = good;
    bad.u.hello.caps = 0x0010; /* the first bit past CS_PROTO_CAP_SPINDLE */
    assert_int_equal(cs_proto_encode(&bad, buf, sizeof buf, &len), CS_ERR_RANGE);

    memset(&good, 0, sizeof good);
    good.type = CS_PROTO_STATUS;
    good.u.status.axes = 2;
    assert_int_equal(cs_proto_encode(&good, raw, sizeof raw, &len), CS_OK);
    bad = good;
    bad.u.status.state = CS_PROTO_STATE_COUNT_;
    raw[1] = CS_PROTO_STATE_COUNT_;
    expect_range(&bad, raw, len);
    raw[1] = 0;
    bad = good;
    bad.u.status.axes = 0;
    raw[10] = 0;
    expect_range(&bad, raw, len);
    bad.u.status.axes = 5;
    raw[10] = 5;
    expect_range(&bad, raw, len);

    memset(&good, 0, sizeof good);
    good.type = CS_PROTO_ERROR;
    good.u.error.code = CS_ERR_CRC;
    assert_int_equal(cs_proto_encode(&good, raw, sizeof raw, &len), CS_OK);
    const uint8_t codes[] = {CS_OK, CS_END, CS_ERR_COUNT_, 255};
    for (int i = 0; i < 4; i++) {
        bad = good;
        bad.u.error.code = codes[i];
        raw[1] = codes[i];
        expect_range(&bad, raw, len);
    }

    memset(&good, 0, sizeof good);
    good.type = CS_PROTO_ACK;
    assert_int_equal(cs_proto_encode(&good, raw, sizeof raw, &len), CS_OK);
    bad = good;
    bad.u.ack.flags = 0x02;
    raw[1] = 0x02;
    expect_range(&bad, raw, len);
}

static void test_random_round_trips(void **state)
{
    (void)state;
    const uint8_t types[] = {CS_PROTO_ACK,    CS_PROTO_PING,    CS_PROTO_HELLO, CS_PROTO_STATUS,
                             CS_PROTO_ERROR,  CS_PROTO_SEGMENT, CS_PROTO_CURVE, CS_PROTO_HOLD,
                             CS_PROTO_RESUME, CS_PROTO_ABORT,   CS_PROTO_PEN,   CS_PROTO_QUERY,
                             CS_PROTO_SETPOS};
    for (int t = 0; t < 20000; t++) {
        cs_proto_msg_t m;
        memset(&m, 0, sizeof m);
        m.type = types[rng() % sizeof types];
        switch (m.type) {
        case CS_PROTO_ACK:
            m.u.ack = (cs_proto_ack_t){(uint8_t)(rng() & 1), (uint16_t)rng(), (uint16_t)rng(),
                                       (uint32_t)rng(), (uint32_t)rng()};
            break;
        case CS_PROTO_PING:
            m.u.ping.nonce = (uint32_t)rng();
            break;
        case CS_PROTO_HELLO:
            m.u.hello = (cs_proto_hello_t){(uint8_t)(1 + rng() % 255),
                                           (uint32_t)rng(),
                                           (uint8_t)(1 + rng() % 4),
                                           (uint16_t)(1 + rng() % 65535),
                                           (uint32_t)(1 + rng() % 0xFFFFFFFEu),
                                           (uint16_t)(rng() % 4)};
            break;
        case CS_PROTO_STATUS:
            m.u.status.state = (uint8_t)(rng() % CS_PROTO_STATE_COUNT_);
            m.u.status.boot_id = (uint32_t)rng();
            m.u.status.queue_fill = (uint16_t)rng();
            m.u.status.last_seq = (uint16_t)rng();
            m.u.status.axes = (uint8_t)(1 + rng() % 4);
            for (unsigned i = 0; i < m.u.status.axes; i++)
                m.u.status.pos[i] = (int32_t)(uint32_t)rng();
            m.u.status.flags = (uint8_t)(rng() % 8);
            m.u.status.job_id = (uint32_t)rng();
            m.u.status.done = (uint32_t)rng();
            m.u.status.recv = (uint32_t)rng();
            /* not on the wire without the flag: decodes as 0 */
            m.u.status.tick = (m.u.status.flags & CS_PROTO_STATUS_TICK) ? (uint32_t)rng() : 0;
            break;
        case CS_PROTO_SETPOS:
            m.u.setpos.flags = (uint8_t)(rng() % 2);
            m.u.setpos.job_id = (uint32_t)rng();
            m.u.setpos.base = (uint32_t)rng();
            for (unsigned i = 0; i < 4; i++)
                m.u.setpos.pos[i] = (int32_t)(uint32_t)rng();
            break;
        case CS_PROTO_ERROR:
            m.u.error.code = (uint8_t)(CS_ERR_ARG + rng() % (CS_ERR_COUNT_ - CS_ERR_ARG));
            m.u.error.seq = (uint16_t)rng();
            break;
        case CS_PROTO_SEGMENT:
            m.u.segment.ticks = (uint32_t)(1 + rng() % CS_PROTO_SEGMENT_MAX_TICKS);
            for (int i = 0; i < 4; i++)
                m.u.segment.steps[i] = (int32_t)(rng() % (2 * (uint64_t)m.u.segment.ticks + 1)) -
                                       (int32_t)m.u.segment.ticks;
            break;
        case CS_PROTO_CURVE:
            for (int i = 0; i < 4; i++) {
                m.u.curve.p[i].x =
                    (int32_t)(rng() % (2 * (uint64_t)CS_POS_LIMIT + 1)) - CS_POS_LIMIT;
                m.u.curve.p[i].y =
                    (int32_t)(rng() % (2 * (uint64_t)CS_POS_LIMIT + 1)) - CS_POS_LIMIT;
                m.u.curve.p[i].z =
                    (int32_t)(rng() % (2 * (uint64_t)CS_POS_LIMIT + 1)) - CS_POS_LIMIT;
            }
            m.u.curve.feed = (int32_t)(1 + rng() % INT32_MAX);
            break;
        case CS_PROTO_PEN:
            m.u.pen.pulse_us = (uint16_t)(400 + rng() % 2201);
            break;
        default:
            break;
        }
        uint8_t buf[CS_PROTO_LEN_MAX];
        size_t len = 0;
        assert_int_equal(cs_proto_encode(&m, buf, sizeof buf, &len), CS_OK);
        cs_proto_msg_t back;
        memset(&back, 0x5A, sizeof back);
        assert_int_equal(cs_proto_decode(buf, len, &back), CS_OK);
        assert_int_equal(back.type, m.type);
        /* Both were zeroed before filling, so the whole union compares. */
        assert_memory_equal(&back.u, &m.u, sizeof m.u);
    }
}

/* Random bytes: only documented answers, and whatever decodes re-encodes to the same bytes. */
static void test_random_bytes_get_documented_answers(void **state)
{
    (void)state;
    uint8_t buf[CS_PROTO_LEN_MAX + 4];
    const uint8_t types[] = {0x01, 0x02, 0x10, 0x11, 0x12, 0x20, 0x21};
    unsigned ok = 0;
    for (int t = 0; t < 200000; t++) {
        size_t n = (size_t)(rng() % sizeof buf);
        for (size_t i = 0; i < n; i++)
            buf[i] = (uint8_t)rng();
        if (n > 0 && rng() % 2)
            buf[0] = types[rng() % sizeof types];
        if (n > 10 && rng() % 2)
            buf[10] = (uint8_t)(1 + rng() % 4); /* plausible status axes */
        cs_proto_msg_t m;
        cs_err_t e = cs_proto_decode(buf, n, &m);
        assert_true(e == CS_OK || e == CS_ERR_FRAME || e == CS_ERR_RANGE ||
                    e == CS_ERR_UNSUPPORTED);
        if (e == CS_OK) {
            ok++;
            uint8_t again[CS_PROTO_LEN_MAX];
            size_t len = 0;
            assert_int_equal(cs_proto_encode(&m, again, sizeof again, &len), CS_OK);
            assert_int_equal(len, n);
            assert_memory_equal(again, buf, n);
        }
    }
    assert_true(ok > 0); /* the generator does hit valid messages (acks, pings, statuses) */
}

static void test_classification_and_boot_peek(void **state)
{
    (void)state;
    assert_false(cs_proto_sequenced(CS_PROTO_ACK));
    assert_false(cs_proto_sequenced(CS_PROTO_PING));
    const uint8_t seqd[] = {0x10, 0x11, 0x12, 0x20, 0x21, 0x22, 0x23, 0x24, 0x25, 0x2C, 0x2D};
    for (size_t i = 0; i < sizeof seqd; i++) {
        assert_true(cs_proto_sequenced(seqd[i]));
        assert_int_equal(cs_proto_uses_slot(seqd[i]),
                         seqd[i] == 0x20 || seqd[i] == 0x21 || seqd[i] == 0x25);
    }
    cs_proto_msg_t m = {0};
    uint8_t buf[CS_PROTO_LEN_MAX];
    size_t len;
    uint32_t boot = 0;
    m.type = CS_PROTO_STATUS;
    m.u.status.axes = 3;
    m.u.status.boot_id = 0x5150AA55u;
    assert_int_equal(cs_proto_encode(&m, buf, sizeof buf, &len), CS_OK);
    assert_true(cs_proto_peek_boot(buf, len, &boot));
    assert_int_equal(boot, 0x5150AA55u);
    assert_false(cs_proto_peek_boot(buf, len - 1, &boot));
    m.type = CS_PROTO_ERROR;
    m.u.error.code = CS_ERR_ARG;
    assert_int_equal(cs_proto_encode(&m, buf, sizeof buf, &len), CS_OK);
    assert_false(cs_proto_peek_boot(buf, len, &boot));
}

/* PEN (docs/protocol.md): 0x25, then the pulse width in us, u16 little-endian. 1500 us =
 * 0x05DC -> DC 05 (by hand); the range ends 400 = 0x0190 and 2600 = 0x0A28 are accepted, one
 * past each (399 = 0x018F, 2601 = 0x0A29) refused both ways. */
static void test_pen_layout_and_range(void **state)
{
    (void)state;
    static const struct {
        uint16_t us;
        uint8_t bytes[CS_PROTO_LEN_PEN];
        bool ok;
    } cases[] = {
        {1500, {0x25, 0xDC, 0x05}, true},  {400, {0x25, 0x90, 0x01}, true},
        {2600, {0x25, 0x28, 0x0A}, true},  {399, {0x25, 0x8F, 0x01}, false},
        {2601, {0x25, 0x29, 0x0A}, false},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        cs_proto_msg_t m = {0};
        m.type = CS_PROTO_PEN;
        m.u.pen.pulse_us = cases[i].us;
        if (cases[i].ok)
            expect_encoding(&m, cases[i].bytes, sizeof cases[i].bytes);
        else
            expect_range(&m, cases[i].bytes, sizeof cases[i].bytes);
    }
}

/* QUERY (0x2C) is its type byte; SETPOS (0x2D): flags, job id, base (u32 each but flags), four
 * i32 positions in steps, written out by hand; an unknown flag bit is refused both ways. */
static void test_query_and_setpos_layout(void **state)
{
    (void)state;
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_QUERY;
    const uint8_t q[1] = {0x2C};
    expect_encoding(&m, q, sizeof q);
    m.type = CS_PROTO_SETPOS;
    m.u.setpos = (cs_proto_setpos_t){CS_PROTO_SETPOS_POS, 0x01020304u, 54081u, {-1, 800, 0, 7}};
    uint8_t w[CS_PROTO_LEN_SETPOS] = {0x2D, 0x01, 0x04, 0x03, 0x02, 0x01, 0x41, 0xD3, 0x00, 0x00,
                                      0xFF, 0xFF, 0xFF, 0xFF, 0x20, 0x03, 0x00, 0x00, 0x00, 0x00,
                                      0x00, 0x00, 0x07, 0x00, 0x00, 0x00};
    assert_int_equal(sizeof w, 26);
    expect_encoding(&m, w, sizeof w);
    m.u.setpos.flags = 0x02;
    w[1] = 0x02;
    expect_range(&m, w, sizeof w);
}

/* The machine-control messages (docs/protocol.md, "Machine control"): every byte of EVENT,
 * HOME, JOG, JOG_CANCEL, PROBE, SPINDLE and UNLOCK written out by hand from the tables, the range
 * checks both ways, which use a slot. */
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
    expect_encoding(&m, w, sizeof w);
    /* kind 0 and 5, an input bit past the e-stop (0x0400), axes 0 */
    uint8_t r[sizeof w];
    memcpy(r, w, sizeof w);
    cs_proto_msg_t bad = m;
    bad.u.event.kind = 0;
    r[1] = 0;
    expect_range(&bad, r, sizeof r);
    bad.u.event.kind = CS_PROTO_EVENT_COUNT_;
    r[1] = CS_PROTO_EVENT_COUNT_;
    expect_range(&bad, r, sizeof r);
    bad = m;
    memcpy(r, w, sizeof w);
    bad.u.event.inputs = 0x0400;
    r[3] = 0x00;
    r[4] = 0x04;
    expect_range(&bad, r, sizeof r);
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
    expect_encoding(&m, w, sizeof w);
    uint8_t r[sizeof w];
    cs_proto_msg_t bad = m;
    memcpy(r, w, sizeof w);
    bad.u.home.axis = 4;
    r[1] = 4;
    expect_range(&bad, r, sizeof r);
    bad = m;
    memcpy(r, w, sizeof w);
    bad.u.home.flags = 2;
    r[2] = 2;
    expect_range(&bad, r, sizeof r);
    bad = m;
    memcpy(r, w, sizeof w);
    bad.u.home.seek = 0;
    r[5] = 0;
    expect_range(&bad, r, sizeof r);
    bad = m;
    memcpy(r, w, sizeof w);
    bad.u.home.search = 0;
    r[17] = r[18] = 0;
    expect_range(&bad, r, sizeof r);
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
    expect_encoding(&m, j, sizeof j);
    cs_proto_msg_t bad = m;
    uint8_t r[sizeof j];
    memcpy(r, j, sizeof j);
    bad.u.jog.feed = 0;
    r[15] = 0;
    expect_range(&bad, r, sizeof r);

    memset(&m, 0, sizeof m);
    m.type = CS_PROTO_PROBE;
    m.u.probe.target = (cs_vec3_t){0, 0, -(10 << 16)};
    m.u.probe.feed = 2 << 16;
    m.u.probe.flags = CS_PROTO_PROBE_NO_ERROR;
    const uint8_t p[] = {0x29, 0, 0, 0, 0, 0, 0, 0, 0, 0x00, 0x00, 0xF6, 0xFF,
                         0x00, 0x00, 0x02, 0x00, 0x02};
    assert_int_equal(sizeof p, CS_PROTO_LEN_PROBE);
    expect_encoding(&m, p, sizeof p);
    uint8_t r2[sizeof p];
    memcpy(r2, p, sizeof p);
    bad = m;
    bad.u.probe.flags = 4;
    r2[17] = 4;
    expect_range(&bad, r2, sizeof r2);
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
    expect_encoding(&m, w, sizeof w);
    uint8_t r[sizeof w];
    memcpy(r, w, sizeof w);
    cs_proto_msg_t bad = m;
    bad.u.spindle.power = 1001;
    r[3] = 0xE9;
    r[4] = 0x03;
    expect_range(&bad, r, sizeof r);
    memcpy(r, w, sizeof w);
    bad = m;
    bad.u.spindle.mode = 3;
    r[1] = 3;
    expect_range(&bad, r, sizeof r);
    memcpy(r, w, sizeof w);
    bad = m;
    bad.u.spindle.feed = -1;
    r[5] = r[6] = r[7] = r[8] = 0xFF;
    expect_range(&bad, r, sizeof r);
    const uint8_t types[] = {CS_PROTO_JOG_CANCEL, CS_PROTO_UNLOCK};
    for (size_t i = 0; i < sizeof types; i++) {
        cs_proto_msg_t c = {.type = types[i]};
        expect_encoding(&c, &types[i], 1);
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

/* OVERRIDE feed 1100/1000 (0x044C), rapid 500 (0x01F4), spindle 20000 (0x4E20); 0 and 20001
 * refused; no queue slot. */
static void test_override_layout(void **state)
{
    (void)state;
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_OVERRIDE;
    m.u.override = (cs_proto_override_t){1100, 500, 20000};
    const uint8_t w[] = {0x2E, 0x4C, 0x04, 0xF4, 0x01, 0x20, 0x4E};
    assert_int_equal(sizeof w, CS_PROTO_LEN_OVERRIDE);
    expect_encoding(&m, w, sizeof w);
    assert_false(cs_proto_uses_slot(CS_PROTO_OVERRIDE));
    assert_true(cs_proto_sequenced(CS_PROTO_OVERRIDE));
    for (unsigned f = 0; f < 3; f++) {
        for (unsigned k = 0; k < 2; k++) {
            uint8_t r[sizeof w];
            memcpy(r, w, sizeof w);
            cs_proto_msg_t bad = m;
            uint16_t v = k == 0 ? 0 : (uint16_t)(CS_PROTO_OVERRIDE_MAX + 1u);
            uint16_t *field = f == 0 ? &bad.u.override.feed
                              : f == 1 ? &bad.u.override.rapid
                                       : &bad.u.override.spindle;
            *field = v;
            r[1 + 2 * f] = (uint8_t)(v & 0xFFu);
            r[2 + 2 * f] = (uint8_t)(v >> 8);
            expect_range(&bad, r, sizeof r);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ack_and_ping_layout),
        cmocka_unit_test(test_hello_layout),
        cmocka_unit_test(test_status_layout_every_axis_count),
        cmocka_unit_test(test_error_segment_curve_control_layout),
        cmocka_unit_test(test_unknown_types_and_empty_payload),
        cmocka_unit_test(test_out_of_range_fields),
        cmocka_unit_test(test_random_round_trips),
        cmocka_unit_test(test_random_bytes_get_documented_answers),
        cmocka_unit_test(test_classification_and_boot_peek),
        cmocka_unit_test(test_pen_layout_and_range),
        cmocka_unit_test(test_query_and_setpos_layout),
        cmocka_unit_test(test_event_layout),
        cmocka_unit_test(test_home_layout),
        cmocka_unit_test(test_jog_probe_layout),
        cmocka_unit_test(test_spindle_and_short_layout),
        cmocka_unit_test(test_override_layout),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
