/* test_modbus: the core's Modbus register map and RTU server (firmware/core/cs_modbus) and the
 * host's Modbus link (host/cs_modbus_stream). Checked against independent references: the
 * CRC-16/MODBUS check value of the catalogue and the worked frame of the Modbus over serial line
 * spec, a bitwise CRC written here from the polynomial, libmodbus's own RTU client (over a real
 * pseudo-terminal, the server in a child process) and the sequence rule of docs/modbus.md:
 * a retry of the last accepted write is answered OK and not queued again, a gap is refused with
 * exception 3 and REFUSED = CS_ERR_SEQ, a full queue with exception 6. End to end: a job streamed
 * with cs_mb_stream_run through a server that loses every 7th answer (after acting on it) is
 * queued exactly once and in order (FNV-1a chain equals the host's). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <errno.h>
#include <modbus/modbus.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cs_modbus.h"
#include "cs_modbus_stream.h"
#include "cs_serial.h"
#include "cs_sim_device.h"
#include "cs_stream.h"
#include "fw_test.h"

/* --- a fake application behind the map ------------------------------------------------------ */

#define FAKE_QUEUE 16

typedef struct {
    unsigned submitted;
    uint64_t hash; /* FNV-1a chain of the SEGMENTs queued, as the device logs them (fw_test_hash) */
    uint16_t last_seq;
    unsigned pending; /* queued, not yet "executed" (the test drains by hand) */
    bool instant;     /* executed as soon as queued */
    uint16_t cmds[8];
    unsigned ncmd;
    cs_proto_msg_t last;
} fake_t;

static cs_err_t fake_submit(void *ctx, const cs_proto_msg_t *m, uint16_t seq)
{
    fake_t *f = ctx;
    if (f->pending >= FAKE_QUEUE)
        return CS_ERR_FULL;
    f->submitted++;
    f->last = *m;
    f->last_seq = seq;
    if (m->type == CS_PROTO_SEGMENT)
        f->hash = fw_test_hash(f->hash, &m->u.segment);
    if (!f->instant)
        f->pending++;
    return CS_OK;
}

static void fake_command(void *ctx, uint16_t cmd)
{
    fake_t *f = ctx;
    if (f->ncmd < 8)
        f->cmds[f->ncmd++] = cmd;
}

static void fake_status(void *ctx, cs_modbus_status_t *st)
{
    fake_t *f = ctx;
    st->caps = CS_PROTO_CAP_ALL;
    st->axes = 3;
    st->queue_size = FAKE_QUEUE;
    st->tick_hz = 100000;
    st->boot_id = 0xDEADBEEFu;
    st->state = f->pending ? CS_PROTO_STATE_RUNNING : CS_PROTO_STATE_IDLE;
    st->free_slots = (uint16_t)(FAKE_QUEUE - f->pending);
    st->last_exec = f->submitted ? f->last_seq : 0xFFFFu;
    st->pos[0] = -123456789;
    st->pos[1] = 42;
    st->pos[2] = 0x7FFFFFFF;
    st->pos[3] = -1;
}

static void fake_map(cs_modbus_map_t *mp, fake_t *f)
{
    memset(f, 0, sizeof *f);
    f->hash = FW_TEST_HASH0;
    cs_modbus_app_t app = {fake_submit, fake_command, fake_status, NULL, f};
    assert_int_equal(cs_modbus_map_init(mp, &app, 0), CS_OK);
}

/* A lease without a clock (cs_fw_modbus's expiry is tested in test_fw_modbus): one holder at a
 * time, every call recorded. */
typedef struct {
    fake_t f;
    uint16_t holder;
    uint8_t ops[16];
    uint16_t tokens[16];
    unsigned nops;
} fake_lease_t;

static cs_err_t fake_lease(void *ctx, uint8_t op, uint16_t token)
{
    fake_lease_t *l = (fake_lease_t *)ctx; /* f first: the other hooks see the fake_t */
    if (l->nops < 16) {
        l->ops[l->nops] = op;
        l->tokens[l->nops++] = token;
    }
    if (l->holder != 0 && token != l->holder)
        return CS_ERR_LEASED;
    if (op == CS_MODBUS_LEASE_CLAIM)
        l->holder = token;
    else if (op == CS_MODBUS_LEASE_RELEASE)
        l->holder = 0;
    return CS_OK;
}

static void fake_lease_map(cs_modbus_map_t *mp, fake_lease_t *l)
{
    memset(l, 0, sizeof *l);
    l->f.hash = FW_TEST_HASH0;
    cs_modbus_app_t app = {fake_submit, fake_command, fake_status, fake_lease, l};
    assert_int_equal(cs_modbus_map_init(mp, &app, 0), CS_OK);
}

/* --- PDU helpers ---------------------------------------------------------------------------- */

static size_t pdu_read(uint8_t *p, uint8_t fc, uint16_t addr, uint16_t qty)
{
    p[0] = fc;
    p[1] = (uint8_t)(addr >> 8), p[2] = (uint8_t)addr;
    p[3] = (uint8_t)(qty >> 8), p[4] = (uint8_t)qty;
    return 5;
}

static size_t pdu_write_multi(uint8_t *p, uint16_t addr, const uint16_t *regs, size_t n)
{
    p[0] = 0x10;
    p[1] = (uint8_t)(addr >> 8), p[2] = (uint8_t)addr;
    p[3] = 0, p[4] = (uint8_t)n;
    p[5] = (uint8_t)(2 * n);
    for (size_t k = 0; k < n; k++)
        p[6 + 2 * k] = (uint8_t)(regs[k] >> 8), p[7 + 2 * k] = (uint8_t)regs[k];
    return 6 + 2 * n;
}

/* Handles req and returns the exception code (0: a normal answer). */
static int call(cs_modbus_map_t *mp, const uint8_t *req, size_t n, uint8_t *rsp, size_t *rn)
{
    assert_int_equal(cs_modbus_pdu(mp, req, n, rsp, CS_MODBUS_PDU_MAX, rn), CS_OK);
    if (rsp[0] & 0x80u) {
        assert_int_equal(*rn, 2);
        assert_int_equal(rsp[0], req[0] | 0x80u);
        return rsp[1];
    }
    return 0;
}

static cs_proto_msg_t segment(uint32_t ticks, int32_t x, int32_t y, int32_t z)
{
    cs_proto_msg_t m = {.type = CS_PROTO_SEGMENT};
    m.u.segment.ticks = ticks;
    m.u.segment.steps[0] = x;
    m.u.segment.steps[1] = y;
    m.u.segment.steps[2] = z;
    return m;
}

static int write_msg(cs_modbus_map_t *mp, const cs_proto_msg_t *m, uint16_t seq)
{
    uint16_t regs[CS_MODBUS_MAILBOX_REGS];
    size_t n;
    assert_int_equal(cs_modbus_mailbox_encode(m, seq, regs, CS_MODBUS_MAILBOX_REGS, &n), CS_OK);
    uint8_t req[260], rsp[260];
    size_t rn;
    size_t qn = pdu_write_multi(req, CS_MODBUS_HR_MAILBOX, regs, n);
    int ex = call(mp, req, qn, rsp, &rn);
    if (ex == 0) { /* the answer to FC16 repeats function, address and quantity */
        assert_int_equal(rn, 5);
        assert_memory_equal(rsp, req, 5);
    }
    return ex;
}

static uint16_t ir(cs_modbus_map_t *mp, unsigned k)
{
    uint8_t req[8], rsp[260];
    size_t rn;
    assert_int_equal(call(mp, req, pdu_read(req, 0x04, (uint16_t)k, 1), rsp, &rn), 0);
    assert_int_equal(rn, 4);
    return (uint16_t)((rsp[2] << 8) | rsp[3]);
}

/* --- CRC ------------------------------------------------------------------------------------ */

/* Bitwise, from the polynomial x^16 + x^15 + x^2 + 1 (0x8005) unreflected, MSB first on
 * reflected bytes: an implementation independent of the reflected-table-less one in the core. */
static uint16_t ref_crc(const uint8_t *d, size_t n)
{
    uint16_t reg = 0xFFFF; /* reflected register: compute on bit-reversed data instead */
    uint32_t r = 0;
    for (int b = 0; b < 16; b++)
        r |= ((reg >> b) & 1u) << (15 - b);
    for (size_t i = 0; i < n; i++) {
        for (int b = 0; b < 8; b++) { /* bits of each byte LSB first */
            unsigned in = (d[i] >> b) & 1u;
            unsigned top = (r >> 15) & 1u;
            r = (r << 1) & 0xFFFFu;
            if (top ^ in)
                r ^= 0x8005u;
        }
    }
    uint16_t out = 0;
    for (int b = 0; b < 16; b++)
        out = (uint16_t)(out | (((r >> b) & 1u) << (15 - b)));
    return out;
}

static void test_crc(void **state)
{
    (void)state;
    /* catalogue check value of CRC-16/MODBUS */
    assert_int_equal(cs_modbus_crc(CS_MODBUS_CRC_INIT, (const uint8_t *)"123456789", 9), 0x4B37);
    /* the spec's example frame: 01 03 00 00 00 0A, CRC C5 CD on the wire (low byte first) */
    const uint8_t f[] = {0x01, 0x03, 0x00, 0x00, 0x00, 0x0A};
    uint16_t c = cs_modbus_crc(CS_MODBUS_CRC_INIT, f, sizeof f);
    assert_int_equal(c & 0xFF, 0xC5);
    assert_int_equal(c >> 8, 0xCD);
    /* random data against the bitwise reference, and the zero residue used for checking */
    uint8_t buf[300];
    uint32_t x = 12345;
    for (int t = 0; t < 200; t++) {
        size_t n = (size_t)(t % 250) + 1;
        for (size_t i = 0; i < n; i++)
            x = x * 1103515245u + 12345u, buf[i] = (uint8_t)(x >> 16);
        uint16_t got = cs_modbus_crc(CS_MODBUS_CRC_INIT, buf, n);
        assert_int_equal(got, ref_crc(buf, n));
        buf[n] = (uint8_t)got, buf[n + 1] = (uint8_t)(got >> 8);
        assert_int_equal(cs_modbus_crc(CS_MODBUS_CRC_INIT, buf, n + 2), 0);
    }
}

/* --- mailbox codec -------------------------------------------------------------------------- */

static void test_mailbox_codec(void **state)
{
    (void)state;
    cs_proto_msg_t s = segment(1000, 250, -100, -1000), d;
    s.u.segment.steps[3] = 7;
    uint16_t regs[CS_MODBUS_MAILBOX_REGS], seq;
    size_t n;
    assert_int_equal(cs_modbus_mailbox_encode(&s, 0xBEEF, regs, 28, &n), CS_OK);
    assert_int_equal(n, 12);
    /* the layout of docs/modbus.md: type, ticks hi lo, x hi lo, ..., seq */
    const uint16_t want[12] = {0x0020, 0,      1000,   0, 250, 0xFFFF,
                               0xFF9C, 0xFFFF, 0xFC18, 0, 7,   0xBEEF};
    assert_memory_equal(regs, want, sizeof want);
    assert_int_equal(cs_modbus_mailbox_decode(regs, n, &d, &seq), CS_OK);
    assert_int_equal(seq, 0xBEEF);
    assert_memory_equal(&d.u.segment, &s.u.segment, sizeof s.u.segment);

    cs_proto_msg_t c = {.type = CS_PROTO_CURVE};
    for (int k = 0; k < 4; k++)
        c.u.curve.p[k] = (cs_vec3_t){-65536 * (k + 1), 65536 * 3 * k + 5, -7 * k};
    c.u.curve.feed = 50 * 65536;
    assert_int_equal(cs_modbus_mailbox_encode(&c, 3, regs, 28, &n), CS_OK);
    assert_int_equal(n, 28);
    assert_int_equal(regs[0], 0x21);
    assert_int_equal(regs[1], 0xFFFF); /* P0.x = -65536 */
    assert_int_equal(regs[2], 0x0000);
    assert_int_equal(regs[25], 50); /* feed 50 mm/s Q16: 0x00320000 */
    assert_int_equal(regs[26], 0);
    assert_int_equal(regs[27], 3);
    assert_int_equal(cs_modbus_mailbox_decode(regs, n, &d, &seq), CS_OK);
    assert_memory_equal(&d.u.curve, &c.u.curve, sizeof c.u.curve);

    /* refusals: lengths that do not match the type, unknown types, fields out of range */
    assert_int_equal(cs_modbus_mailbox_decode(regs, 27, &d, &seq), CS_ERR_FRAME);
    regs[0] = 0x22;
    assert_int_equal(cs_modbus_mailbox_decode(regs, 28, &d, &seq), CS_ERR_UNSUPPORTED);
    cs_proto_msg_t bad = segment(10, 11, 0, 0); /* |steps| > ticks */
    assert_int_equal(cs_modbus_mailbox_encode(&bad, 0, regs, 28, &n), CS_ERR_RANGE);
    assert_int_equal(cs_modbus_mailbox_encode(&s, 0, regs, 11, &n), CS_ERR_FULL);
    cs_proto_msg_t hold = {.type = CS_PROTO_HOLD};
    assert_int_equal(cs_modbus_mailbox_encode(&hold, 0, regs, 28, &n), CS_ERR_UNSUPPORTED);
}

/* --- the map: sequence rule, commands, status, exceptions ----------------------------------- */

/* The PEN layout (docs/modbus.md): type 0x25, the width in us, the sequence; its range is the
 * wire protocol's (400..2600 us), a wrong length is a frame error. Values by hand. */
static void test_mailbox_pen(void **state)
{
    (void)state;
    cs_proto_msg_t p = {.type = CS_PROTO_PEN}, d;
    p.u.pen.pulse_us = 1500;
    uint16_t regs[CS_MODBUS_MAILBOX_REGS], seq;
    size_t n;
    assert_int_equal(cs_modbus_mailbox_encode(&p, 0x1234, regs, 28, &n), CS_OK);
    assert_int_equal(n, 3);
    const uint16_t want[3] = {0x0025, 1500, 0x1234};
    assert_memory_equal(regs, want, sizeof want);
    assert_int_equal(cs_modbus_mailbox_decode(regs, n, &d, &seq), CS_OK);
    assert_int_equal(d.type, CS_PROTO_PEN);
    assert_int_equal(d.u.pen.pulse_us, 1500);
    assert_int_equal(seq, 0x1234);
    assert_int_equal(cs_modbus_mailbox_decode(regs, 4, &d, &seq), CS_ERR_FRAME);
    regs[1] = 300; /* below 400 us */
    assert_int_equal(cs_modbus_mailbox_decode(regs, 3, &d, &seq), CS_ERR_RANGE);
    p.u.pen.pulse_us = 2700;
    assert_int_equal(cs_modbus_mailbox_encode(&p, 1, regs, 28, &n), CS_ERR_RANGE);
}

static void test_sequence_rule(void **state)
{
    (void)state;
    cs_modbus_map_t mp;
    fake_t f;
    fake_map(&mp, &f);
    cs_proto_msg_t a = segment(100, 10, 0, 0), b = segment(100, 0, 20, 0);
    assert_int_equal(write_msg(&mp, &a, 0), 0);
    assert_int_equal(f.submitted, 1);
    /* the retry of seq 0 (its answer was lost): OK, not queued again */
    assert_int_equal(write_msg(&mp, &a, 0), 0);
    assert_int_equal(f.submitted, 1);
    assert_int_equal(mp.stats.repeats, 1);
    /* seq 0 again with other contents: refused, it cannot be the same write */
    assert_int_equal(write_msg(&mp, &b, 0), CS_MODBUS_EX_ILLEGAL_VALUE);
    assert_int_equal(ir(&mp, CS_MODBUS_IR_REFUSED), CS_ERR_SEQ);
    /* a gap: seq 2 while 1 is expected */
    assert_int_equal(write_msg(&mp, &b, 2), CS_MODBUS_EX_ILLEGAL_VALUE);
    assert_int_equal(ir(&mp, CS_MODBUS_IR_REFUSED), CS_ERR_SEQ);
    assert_int_equal(ir(&mp, CS_MODBUS_IR_REFUSED_SEQ), 2);
    assert_int_equal(ir(&mp, CS_MODBUS_IR_NEXT_SEQ), 1);
    assert_int_equal(f.submitted, 1);
    /* the right one */
    assert_int_equal(write_msg(&mp, &b, 1), 0);
    assert_int_equal(f.submitted, 2);
    assert_int_equal(ir(&mp, CS_MODBUS_IR_NEXT_SEQ), 2);
    /* contents out of range: exception 3, REFUSED says why, nothing taken */
    cs_proto_msg_t bad = segment(10, 0, 0, 0);
    uint16_t regs[28];
    size_t n;
    assert_int_equal(cs_modbus_mailbox_encode(&bad, 2, regs, 28, &n), CS_OK);
    regs[4] = 11; /* x = 11 steps in 10 ticks */
    uint8_t req[260], rsp[260];
    size_t rn;
    assert_int_equal(call(&mp, req, pdu_write_multi(req, CS_MODBUS_HR_MAILBOX, regs, n), rsp, &rn),
                     CS_MODBUS_EX_ILLEGAL_VALUE);
    assert_int_equal(ir(&mp, CS_MODBUS_IR_REFUSED), CS_ERR_RANGE);
    assert_int_equal(f.submitted, 2);
    /* the queue full: exception 6, sequence not consumed; then taken once room is back */
    for (uint16_t s = 2; s < 2 + FAKE_QUEUE - 2; s++)
        assert_int_equal(write_msg(&mp, &a, s), 0);
    assert_int_equal(f.pending, FAKE_QUEUE);
    uint16_t s_full = 2 + FAKE_QUEUE - 2;
    assert_int_equal(write_msg(&mp, &b, s_full), CS_MODBUS_EX_DEVICE_BUSY);
    assert_int_equal(ir(&mp, CS_MODBUS_IR_REFUSED), CS_ERR_FULL);
    assert_int_equal(ir(&mp, CS_MODBUS_IR_NEXT_SEQ), s_full);
    f.pending = 0;
    assert_int_equal(write_msg(&mp, &b, s_full), 0);
    assert_int_equal(ir(&mp, CS_MODBUS_IR_NEXT_SEQ), (uint16_t)(s_full + 1));
    /* sequence numbers wrap at 16 bits */
    cs_modbus_map_t w;
    fake_t fw;
    fake_map(&w, &fw);
    w.next_seq = 0xFFFF;
    assert_int_equal(write_msg(&w, &a, 0xFFFF), 0);
    assert_int_equal(write_msg(&w, &a, 0xFFFF), 0); /* retry across the wrap */
    assert_int_equal(write_msg(&w, &b, 0), 0);
    assert_int_equal(fw.submitted, 2);
}

static void test_commands_status_exceptions(void **state)
{
    (void)state;
    cs_modbus_map_t mp;
    fake_t f;
    fake_map(&mp, &f);
    uint8_t req[260], rsp[260];
    size_t rn;
    /* FC06 commands */
    const uint8_t hold[] = {0x06, 0x00, 0x00, 0x00, CS_MODBUS_CMD_HOLD};
    assert_int_equal(call(&mp, hold, 5, rsp, &rn), 0);
    assert_int_equal(rn, 5);
    assert_memory_equal(rsp, hold, 5); /* FC06 echoes the request */
    assert_int_equal(f.ncmd, 1);
    assert_int_equal(f.cmds[0], CS_MODBUS_CMD_HOLD);
    const uint8_t bad_cmd[] = {0x06, 0x00, 0x00, 0x00, 9};
    assert_int_equal(call(&mp, bad_cmd, 5, rsp, &rn), CS_MODBUS_EX_ILLEGAL_VALUE);
    assert_int_equal(f.ncmd, 1);
    const uint8_t to_mailbox[] = {0x06, 0x01, 0x00, 0x00, 0x20};
    assert_int_equal(call(&mp, to_mailbox, 5, rsp, &rn), CS_MODBUS_EX_ILLEGAL_ADDRESS);
    /* FC16 of one register to COMMAND works too; FC03 reads the last command back */
    uint16_t abort_cmd = CS_MODBUS_CMD_ABORT;
    assert_int_equal(call(&mp, req, pdu_write_multi(req, 0, &abort_cmd, 1), rsp, &rn), 0);
    assert_int_equal(f.cmds[1], CS_MODBUS_CMD_ABORT);
    assert_int_equal(call(&mp, req, pdu_read(req, 0x03, 0, 1), rsp, &rn), 0);
    assert_int_equal(rn, 4);
    assert_int_equal(rsp[1], 2);
    assert_int_equal(rsp[3], CS_MODBUS_CMD_ABORT);
    /* the whole status block in one FC04 read */
    assert_int_equal(call(&mp, req, pdu_read(req, 0x04, 0, CS_MODBUS_IR_COUNT), rsp, &rn), 0);
    assert_int_equal(rn, 2 + 2 * CS_MODBUS_IR_COUNT);
    assert_int_equal(rsp[1], 2 * CS_MODBUS_IR_COUNT);
    uint16_t v[CS_MODBUS_IR_COUNT];
    for (int k = 0; k < CS_MODBUS_IR_COUNT; k++)
        v[k] = (uint16_t)((rsp[2 + 2 * k] << 8) | rsp[3 + 2 * k]);
    assert_int_equal(v[CS_MODBUS_IR_VERSION], CS_MODBUS_MAP_VERSION);
    assert_int_equal(v[CS_MODBUS_IR_AXES], 3);
    assert_int_equal(v[CS_MODBUS_IR_QUEUE_SIZE], FAKE_QUEUE);
    assert_int_equal(((uint32_t)v[4] << 16) | v[5], 100000);
    assert_int_equal(((uint32_t)v[6] << 16) | v[7], 0xDEADBEEFu);
    assert_int_equal(v[CS_MODBUS_IR_FREE], FAKE_QUEUE);
    assert_int_equal(v[CS_MODBUS_IR_LAST_EXEC], 0xFFFF);
    assert_int_equal((int32_t)(((uint32_t)v[16] << 16) | v[17]), -123456789);
    assert_int_equal((int32_t)(((uint32_t)v[18] << 16) | v[19]), 42);
    assert_int_equal((int32_t)(((uint32_t)v[20] << 16) | v[21]), 0x7FFFFFFF);
    assert_int_equal((int32_t)(((uint32_t)v[22] << 16) | v[23]), -1);
    /* exceptions: outside the map, bad quantities, unknown function, malformed writes */
    assert_int_equal(call(&mp, req, pdu_read(req, 0x04, CS_MODBUS_IR_COUNT - 4, 5), rsp, &rn),
                     CS_MODBUS_EX_ILLEGAL_ADDRESS);
    assert_int_equal(call(&mp, req, pdu_read(req, 0x04, 0, 0), rsp, &rn),
                     CS_MODBUS_EX_ILLEGAL_VALUE);
    assert_int_equal(call(&mp, req, pdu_read(req, 0x03, 0, 126), rsp, &rn),
                     CS_MODBUS_EX_ILLEGAL_VALUE);
    assert_int_equal(call(&mp, req, pdu_read(req, 0x03, 0, 2), rsp, &rn),
                     CS_MODBUS_EX_ILLEGAL_ADDRESS); /* 0x0001 is not in the map */
    assert_int_equal(call(&mp, req, pdu_read(req, 0x03, CS_MODBUS_HR_MAILBOX, 28), rsp, &rn), 0);
    assert_int_equal(call(&mp, req, pdu_read(req, 0x03, CS_MODBUS_HR_MAILBOX, 29), rsp, &rn),
                     CS_MODBUS_EX_ILLEGAL_ADDRESS);
    const uint8_t unknown[] = {0x2B, 0x0E, 0x01, 0x00};
    assert_int_equal(call(&mp, unknown, sizeof unknown, rsp, &rn), CS_MODBUS_EX_ILLEGAL_FUNCTION);
    uint16_t regs[12] = {0x20};
    size_t qn = pdu_write_multi(req, CS_MODBUS_HR_MAILBOX, regs, 12);
    req[5] = 22; /* byte count disagrees with the quantity */
    assert_int_equal(call(&mp, req, qn, rsp, &rn), CS_MODBUS_EX_ILLEGAL_VALUE);
    qn = pdu_write_multi(req, CS_MODBUS_HR_MAILBOX + 1, regs, 12); /* not at the mailbox start */
    assert_int_equal(call(&mp, req, qn, rsp, &rn), CS_MODBUS_EX_ILLEGAL_ADDRESS);
    assert_int_equal(f.submitted, 0);
    /* RESET clears the refusal register */
    cs_proto_msg_t s = segment(10, 1, 0, 0);
    assert_int_equal(write_msg(&mp, &s, 5), CS_MODBUS_EX_ILLEGAL_VALUE);
    assert_int_equal(ir(&mp, CS_MODBUS_IR_REFUSED), CS_ERR_SEQ);
    const uint8_t reset[] = {0x06, 0x00, 0x00, 0x00, CS_MODBUS_CMD_RESET};
    assert_int_equal(call(&mp, reset, 5, rsp, &rn), 0);
    assert_int_equal(ir(&mp, CS_MODBUS_IR_REFUSED), 0);
}

/* --- the writer lease ----------------------------------------------------------------------- */

/* FC16 of a SEGMENT with a token first, at CS_MODBUS_HR_TOKEN: the exception (0: taken). */
static int write_with_token(cs_modbus_map_t *mp, uint16_t token, const cs_proto_msg_t *m,
                            uint16_t seq)
{
    uint16_t regs[1 + CS_MODBUS_MAILBOX_REGS];
    size_t n;
    regs[0] = token;
    assert_int_equal(cs_modbus_mailbox_encode(m, seq, regs + 1, CS_MODBUS_MAILBOX_REGS, &n), CS_OK);
    uint8_t req[260], rsp[260];
    size_t rn;
    return call(mp, req, pdu_write_multi(req, CS_MODBUS_HR_TOKEN, regs, n + 1), rsp, &rn);
}

static int write_reg(cs_modbus_map_t *mp, uint16_t addr, uint16_t v)
{
    uint8_t req[5] = {0x06, (uint8_t)(addr >> 8), (uint8_t)addr, (uint8_t)(v >> 8), (uint8_t)v};
    uint8_t rsp[260];
    size_t rn;
    return call(mp, req, 5, rsp, &rn);
}

/* docs/modbus.md "The writer lease": the holder's writes (with its token) are taken; a write
 * from anyone else, with the right sequence or as a repeat of the holder's last write, is
 * refused with exception 1 and REFUSED = 23, and queues nothing nor moves NEXT_SEQ. */
static void test_lease(void **state)
{
    (void)state;
    cs_modbus_map_t mp;
    fake_lease_t l;
    fake_lease_map(&mp, &l);
    cs_proto_msg_t s = segment(100, 3, -4, 5);
    /* no lease held: a write without a token is taken, as before leases */
    assert_int_equal(write_msg(&mp, &s, 0), 0);
    assert_int_equal(l.nops, 1);
    assert_int_equal(l.ops[0], CS_MODBUS_LEASE_WRITE);
    assert_int_equal(l.tokens[0], 0);
    /* claim with token 0x1234 (FC06 to LEASE); token 0 is not a token */
    assert_int_equal(write_reg(&mp, CS_MODBUS_HR_LEASE, 0), CS_MODBUS_EX_ILLEGAL_VALUE);
    assert_int_equal(write_reg(&mp, CS_MODBUS_HR_LEASE, 0x1234), 0);
    assert_int_equal(l.holder, 0x1234);
    /* another client claims: exception 1, REFUSED says leased */
    assert_int_equal(write_reg(&mp, CS_MODBUS_HR_LEASE, 0x9999), CS_MODBUS_EX_ILLEGAL_FUNCTION);
    assert_int_equal(ir(&mp, CS_MODBUS_IR_REFUSED), CS_ERR_LEASED);
    /* another client writes the mailbox with the current sequence, without a token or with a
     * wrong one, or repeats the holder's last write: refused, nothing queued */
    assert_int_equal(write_msg(&mp, &s, 1), CS_MODBUS_EX_ILLEGAL_FUNCTION);
    assert_int_equal(ir(&mp, CS_MODBUS_IR_REFUSED), CS_ERR_LEASED);
    assert_int_equal(ir(&mp, CS_MODBUS_IR_REFUSED_SEQ), 1);
    assert_int_equal(write_with_token(&mp, 0x4321, &s, 1), CS_MODBUS_EX_ILLEGAL_FUNCTION);
    assert_int_equal(write_msg(&mp, &s, 0), CS_MODBUS_EX_ILLEGAL_FUNCTION); /* the repeat */
    assert_int_equal(l.f.submitted, 1);
    assert_int_equal(ir(&mp, CS_MODBUS_IR_NEXT_SEQ), 1);
    assert_int_equal(mp.stats.repeats, 0);
    /* the holder's write (token first) is taken, its repeat answered without queueing */
    assert_int_equal(write_with_token(&mp, 0x1234, &s, 1), 0);
    assert_int_equal(write_with_token(&mp, 0x1234, &s, 1), 0);
    assert_int_equal(l.f.submitted, 2);
    assert_int_equal(mp.stats.repeats, 1);
    assert_int_equal(ir(&mp, CS_MODBUS_IR_NEXT_SEQ), 2);
    /* the token is never read back */
    uint8_t req[260], rsp[260];
    size_t rn;
    assert_int_equal(call(&mp, req, pdu_read(req, 0x03, CS_MODBUS_HR_TOKEN, 1), rsp, &rn), 0);
    assert_int_equal((rsp[2] << 8) | rsp[3], 0);
    assert_int_equal(call(&mp, req, pdu_read(req, 0x03, CS_MODBUS_HR_LEASE, 2), rsp, &rn), 0);
    assert_int_equal(rsp[2] | rsp[3] | rsp[4] | rsp[5], 0);
    /* release by another: refused; by the holder (FC16 of one register): done */
    assert_int_equal(write_reg(&mp, CS_MODBUS_HR_RELEASE, 0x9999), CS_MODBUS_EX_ILLEGAL_FUNCTION);
    uint16_t tok = 0x1234;
    assert_int_equal(call(&mp, req, pdu_write_multi(req, CS_MODBUS_HR_RELEASE, &tok, 1), rsp, &rn),
                     0);
    assert_int_equal(l.holder, 0);
    /* a token write to anything but the mailbox, or too long for it: illegal address */
    uint16_t big[2 + CS_MODBUS_MAILBOX_REGS] = {0x1234, 0x20};
    assert_int_equal(call(&mp, req, pdu_write_multi(req, CS_MODBUS_HR_TOKEN, big, 30), rsp, &rn),
                     CS_MODBUS_EX_ILLEGAL_ADDRESS);
    assert_int_equal(call(&mp, req, pdu_write_multi(req, CS_MODBUS_HR_TOKEN, big, 1), rsp, &rn),
                     CS_MODBUS_EX_ILLEGAL_ADDRESS);
    /* a map whose application has no lease: LEASE, RELEASE and TOKEN are outside it */
    cs_modbus_map_t plain;
    fake_t f;
    fake_map(&plain, &f);
    assert_int_equal(write_reg(&plain, CS_MODBUS_HR_LEASE, 7), CS_MODBUS_EX_ILLEGAL_ADDRESS);
    assert_int_equal(write_with_token(&plain, 7, &s, 0), CS_MODBUS_EX_ILLEGAL_ADDRESS);
    assert_int_equal(call(&plain, req, pdu_read(req, 0x03, CS_MODBUS_HR_LEASE, 1), rsp, &rn),
                     CS_MODBUS_EX_ILLEGAL_ADDRESS);
}

/* Function codes the map does not serve, and PDUs with no function code at all: fc | 0x80 and
 * exception 1 (MODBUS Application Protocol V1.1b3, section 7), never a normal answer. */
static void test_unknown_functions(void **state)
{
    (void)state;
    cs_modbus_map_t mp;
    fake_t f;
    fake_map(&mp, &f);
    const uint8_t fcs[] = {0x01, 0x02, 0x05, 0x07, 0x0F, 0x11, 0x14, 0x16, 0x17, 0x2B, 0x41, 0x7F};
    for (size_t k = 0; k < sizeof fcs; k++) {
        uint8_t req[5] = {fcs[k], 0, 0, 0, 1}, rsp[260];
        size_t rn = 0;
        assert_int_equal(cs_modbus_pdu(&mp, req, 5, rsp, CS_MODBUS_PDU_MAX, &rn), CS_OK);
        assert_int_equal(rn, 2);
        assert_int_equal(rsp[0], fcs[k] | 0x80);
        assert_int_equal(rsp[1], CS_MODBUS_EX_ILLEGAL_FUNCTION);
    }
    uint8_t req[1] = {0}, rsp[260];
    size_t rn = 0;
    assert_int_equal(cs_modbus_pdu(&mp, req, 0, rsp, CS_MODBUS_PDU_MAX, &rn), CS_OK);
    assert_int_equal(rn, 2);
    assert_int_equal(rsp[0], 0x80);
    assert_int_equal(rsp[1], CS_MODBUS_EX_ILLEGAL_FUNCTION);
    assert_int_equal(f.submitted + f.ncmd, 0);
}

/* The MBAP header (Modbus Messaging on TCP/IP Implementation Guide V1.0b, 3.1.3), bytes
 * written out by hand. */
static void test_mbap(void **state)
{
    (void)state;
    cs_modbus_mbap_t h;
    /* transaction 0x0102, protocol 0, length 6, unit 7, FC04 0x0000 x 24 */
    const uint8_t ok[] = {0x01, 0x02, 0x00, 0x00, 0x00, 0x06, 0x07, 0x04, 0x00, 0x00, 0x00, 0x18};
    for (size_t n = 0; n < sizeof ok; n++) /* incomplete: wait for more */
        assert_int_equal(cs_modbus_mbap_parse(ok, n, &h), CS_ERR_EMPTY);
    assert_int_equal(cs_modbus_mbap_parse(ok, sizeof ok, &h), CS_OK);
    assert_int_equal(h.tid, 0x0102);
    assert_int_equal(h.unit, 7);
    assert_int_equal(h.pdu_len, 5);
    uint8_t two[2 * sizeof ok]; /* two frames back to back: the first one's length only */
    memcpy(two, ok, sizeof ok);
    memcpy(two + sizeof ok, ok, sizeof ok);
    assert_int_equal(cs_modbus_mbap_parse(two, sizeof two, &h), CS_OK);
    assert_int_equal(h.pdu_len, 5);
    /* protocol id 1: a whole frame, not Modbus */
    uint8_t b[300];
    memcpy(b, ok, sizeof ok);
    b[3] = 1;
    assert_int_equal(cs_modbus_mbap_parse(b, sizeof ok, &h), CS_ERR_UNSUPPORTED);
    assert_int_equal(h.pdu_len, 5);
    /* lengths 0, 1 (no function code) and 255 (longer than any PDU): the stream is lost */
    const uint16_t bad[] = {0, 1, 255, 0xFFFF};
    for (size_t k = 0; k < 4; k++) {
        memcpy(b, ok, sizeof ok);
        b[4] = (uint8_t)(bad[k] >> 8);
        b[5] = (uint8_t)bad[k];
        assert_int_equal(cs_modbus_mbap_parse(b, 7, &h), CS_ERR_FRAME);
    }
    /* length 254: the largest PDU (253 bytes), complete only with all of it */
    memset(b, 0, sizeof b);
    b[5] = 254;
    assert_int_equal(cs_modbus_mbap_parse(b, 7 + 252, &h), CS_ERR_EMPTY);
    assert_int_equal(cs_modbus_mbap_parse(b, 7 + 253, &h), CS_OK);
    /* the answer's header: same transaction and unit, protocol 0, length = 1 + PDU */
    const uint8_t pdu[] = {0x84, 0x02};
    size_t len = 0;
    h = (cs_modbus_mbap_t){.tid = 0xBEEF, .proto = 5, .unit = 9};
    assert_int_equal(cs_modbus_mbap_frame(&h, pdu, 2, b, sizeof b, &len), CS_OK);
    const uint8_t want[] = {0xBE, 0xEF, 0x00, 0x00, 0x00, 0x03, 0x09, 0x84, 0x02};
    assert_int_equal(len, sizeof want);
    assert_memory_equal(b, want, sizeof want);
    assert_int_equal(cs_modbus_mbap_frame(&h, pdu, 2, b, 8, &len), CS_ERR_FULL);
}

/* --- RTU framing ------------------------------------------------------------------------------ */

/* Feeds a frame byte by byte at 10 us a byte; returns the reply length (0: none). */
static size_t feed_frame(cs_modbus_rtu_t *r, const uint8_t *b, size_t n, uint32_t *t,
                         uint8_t *reply)
{
    size_t got = 0;
    for (size_t k = 0; k < n; k++) {
        const uint8_t *out;
        size_t len;
        *t += 10;
        if (cs_modbus_rtu_feed(r, b[k], *t, &out, &len) == CS_OK) {
            memcpy(reply, out, len);
            got = len;
        }
    }
    return got;
}

static void test_rtu_framing(void **state)
{
    (void)state;
    cs_modbus_map_t mp;
    fake_t f;
    fake_map(&mp, &f);
    f.instant = true;
    cs_modbus_rtu_t r;
    assert_int_equal(cs_modbus_rtu_init(&r, &mp, 5, 115200), CS_OK);
    assert_int_equal(r.gap_us, 1750); /* fixed above 19200 baud */
    cs_modbus_rtu_t slow;
    assert_int_equal(cs_modbus_rtu_init(&slow, &mp, 5, 9600), CS_OK);
    assert_int_equal(slow.gap_us, 4011); /* 3.5 x 11 bits / 9600 = 4.0104 ms, rounded up */
    assert_int_equal(cs_modbus_rtu_init(&slow, &mp, 0, 9600), CS_ERR_ARG);
    assert_int_equal(cs_modbus_rtu_init(&slow, &mp, 248, 9600), CS_ERR_ARG);

    uint32_t t = 1000;
    uint8_t pdu[260], frame[260], reply[260];
    size_t fl;
    /* a status read: answered as soon as its 8 bytes are in (length known from FC04) */
    assert_int_equal(cs_modbus_rtu_frame(5, pdu, pdu_read(pdu, 0x04, CS_MODBUS_IR_AXES, 2), frame,
                                         sizeof frame, &fl),
                     CS_OK);
    assert_int_equal(fl, 8);
    size_t rl = feed_frame(&r, frame, fl, &t, reply);
    assert_int_equal(rl, 3 + 2 + 4);
    assert_int_equal(reply[0], 5);
    assert_int_equal(reply[1], 0x04);
    assert_int_equal(reply[2], 4);
    assert_int_equal((reply[3] << 8) | reply[4], 3);
    assert_int_equal((reply[5] << 8) | reply[6], FAKE_QUEUE);
    assert_int_equal(cs_modbus_crc(CS_MODBUS_CRC_INIT, reply, rl), 0);
    /* another unit's request: not answered, counted */
    assert_int_equal(
        cs_modbus_rtu_frame(6, pdu, pdu_read(pdu, 0x04, 0, 1), frame, sizeof frame, &fl), CS_OK);
    t += 5000;
    assert_int_equal(feed_frame(&r, frame, fl, &t, reply), 0);
    assert_int_equal(r.stats.other_unit, 1);
    /* a damaged frame: dropped at the silence, then the next good one is answered */
    assert_int_equal(
        cs_modbus_rtu_frame(5, pdu, pdu_read(pdu, 0x04, 0, 1), frame, sizeof frame, &fl), CS_OK);
    frame[3] ^= 0x10;
    t += 5000;
    assert_int_equal(feed_frame(&r, frame, fl, &t, reply), 0);
    const uint8_t *out;
    size_t len;
    t += 2000;
    assert_int_equal(cs_modbus_rtu_idle(&r, t, &out, &len), CS_ERR_EMPTY);
    assert_int_equal(r.stats.crc_errs, 1);
    frame[3] ^= 0x10;
    t += 5000;
    assert_int_equal(feed_frame(&r, frame, fl, &t, reply), 7);
    /* a mailbox write (FC16, length from its byte count) and a broadcast one (acted on, not
     * answered) */
    cs_proto_msg_t s = segment(100, 3, 4, 5);
    uint16_t regs[28];
    size_t n;
    assert_int_equal(cs_modbus_mailbox_encode(&s, 0, regs, 28, &n), CS_OK);
    assert_int_equal(cs_modbus_rtu_frame(5, pdu,
                                         pdu_write_multi(pdu, CS_MODBUS_HR_MAILBOX, regs, n), frame,
                                         sizeof frame, &fl),
                     CS_OK);
    t += 5000;
    assert_int_equal(feed_frame(&r, frame, fl, &t, reply), 8);
    assert_int_equal(f.submitted, 1);
    assert_int_equal(cs_modbus_mailbox_encode(&s, 1, regs, 28, &n), CS_OK);
    assert_int_equal(cs_modbus_rtu_frame(0, pdu,
                                         pdu_write_multi(pdu, CS_MODBUS_HR_MAILBOX, regs, n), frame,
                                         sizeof frame, &fl),
                     CS_OK);
    t += 5000;
    assert_int_equal(feed_frame(&r, frame, fl, &t, reply), 0);
    assert_int_equal(f.submitted, 2);
    assert_int_equal(r.stats.broadcasts, 1);
    /* an unknown function: its length is unknown, so it ends at t3.5 and gets exception 1 */
    const uint8_t odd[] = {0x2B, 0x0E, 0x01, 0x00};
    assert_int_equal(cs_modbus_rtu_frame(5, odd, sizeof odd, frame, sizeof frame, &fl), CS_OK);
    t += 5000;
    assert_int_equal(feed_frame(&r, frame, fl, &t, reply), 0);
    assert_int_equal(cs_modbus_rtu_idle(&r, t + 1000, &out, &len), CS_ERR_EMPTY); /* < t3.5 */
    assert_int_equal(cs_modbus_rtu_idle(&r, t + 1750, &out, &len), CS_OK);
    assert_int_equal(len, 5);
    assert_int_equal(out[1], 0x2B | 0x80);
    assert_int_equal(out[2], CS_MODBUS_EX_ILLEGAL_FUNCTION);
    /* line noise longer than any frame: skipped up to the silence, no answer, no crash */
    t += 5000;
    uint8_t noise[600];
    for (size_t k = 0; k < sizeof noise; k++)
        noise[k] = (uint8_t)(k * 37u + 1u);
    assert_int_equal(feed_frame(&r, noise, sizeof noise, &t, reply), 0);
    assert_true(r.stats.overruns >= 1);
    t += 5000;
    assert_int_equal(
        cs_modbus_rtu_frame(5, pdu, pdu_read(pdu, 0x04, 0, 1), frame, sizeof frame, &fl), CS_OK);
    assert_int_equal(feed_frame(&r, frame, fl, &t, reply), 7);
}

/* --- against libmodbus's RTU client over a pty ---------------------------------------------- */

/* The server in a child process on the master end of a pty: the core's RTU server for unit 3,
 * a fake application executing instantly, every drop_every-th answer not sent (0: none). At
 * SIGTERM it writes "submitted hash" to the pipe. */
static volatile sig_atomic_t child_stop;
static void on_term(int sig)
{
    (void)sig;
    child_stop = 1;
}

static pid_t start_server(int *slave_fd, char *path, size_t cap, int *result_fd,
                          unsigned drop_every)
{
    int master, slave, pfd[2];
    assert_int_equal(cs_serial_openpty(&master, &slave, path, cap), 0);
    assert_int_equal(pipe(pfd), 0);
    fflush(NULL);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        close(pfd[0]);
        alarm(60);
        signal(SIGTERM, on_term);
        cs_modbus_map_t mp;
        fake_t f;
        memset(&f, 0, sizeof f);
        f.hash = FW_TEST_HASH0;
        f.instant = true;
        cs_modbus_app_t app = {fake_submit, fake_command, fake_status, NULL, &f};
        cs_modbus_map_init(&mp, &app, 0);
        cs_modbus_rtu_t r;
        cs_modbus_rtu_init(&r, &mp, 3, 115200);
        cs_serial_t ser;
        cs_serial_attach(&ser, master);
        unsigned answers = 0;
        while (!child_stop) {
            uint8_t buf[512];
            ssize_t n = cs_serial_read(&ser, buf, sizeof buf, 2);
            uint32_t now = cs_serial_now_us();
            for (ssize_t k = 0; k <= n; k++) {
                const uint8_t *out;
                size_t len;
                cs_err_t e = k < n ? cs_modbus_rtu_feed(&r, buf[k], now, &out, &len)
                                   : cs_modbus_rtu_idle(&r, cs_serial_now_us(), &out, &len);
                if (e != CS_OK)
                    continue;
                answers++;
                if (drop_every != 0 && answers % drop_every == 0)
                    continue; /* acted on, answer lost */
                cs_serial_write(&ser, out, len);
            }
        }
        char line[64];
        int ln =
            snprintf(line, sizeof line, "%u %016llx\n", f.submitted, (unsigned long long)f.hash);
        if (write(pfd[1], line, (size_t)ln) != ln)
            _exit(3);
        _exit(0);
    }
    close(master);
    close(pfd[1]);
    *slave_fd = slave; /* kept open so the master never sees a hang-up */
    *result_fd = pfd[0];
    return pid;
}

static void stop_server(pid_t pid, int slave_fd, int result_fd, unsigned *submitted, uint64_t *hash)
{
    kill(pid, SIGTERM);
    char buf[64] = {0};
    ssize_t n = read(result_fd, buf, sizeof buf - 1);
    int st;
    waitpid(pid, &st, 0);
    close(slave_fd);
    close(result_fd);
    assert_true(n > 0);
    unsigned long long h = 0;
    assert_int_equal(sscanf(buf, "%u %llx", submitted, &h), 2);
    *hash = h;
}

static void test_libmodbus_client(void **state)
{
    (void)state;
    char path[256];
    int slave, res;
    pid_t pid = start_server(&slave, path, sizeof path, &res, 0);
    modbus_t *ctx = modbus_new_rtu(path, 115200, 'N', 8, 1);
    assert_non_null(ctx);
    modbus_set_slave(ctx, 3);
    modbus_set_response_timeout(ctx, 5, 0); /* an answer is expected: a generous deadline */
    assert_int_equal(modbus_connect(ctx), 0);
    uint16_t v[CS_MODBUS_IR_COUNT];
    assert_int_equal(modbus_read_input_registers(ctx, 0, CS_MODBUS_IR_COUNT, v),
                     CS_MODBUS_IR_COUNT);
    assert_int_equal(v[CS_MODBUS_IR_VERSION], CS_MODBUS_MAP_VERSION);
    assert_int_equal(v[CS_MODBUS_IR_NEXT_SEQ], 0);
    assert_int_equal((int32_t)(((uint32_t)v[CS_MODBUS_IR_POS] << 16) | v[CS_MODBUS_IR_POS + 1]),
                     -123456789);
    /* a mailbox write, its retry (answered OK, not queued twice), a gap (exception 3) */
    cs_proto_msg_t s = segment(500, 100, -200, 3);
    uint16_t regs[28];
    size_t n;
    assert_int_equal(cs_modbus_mailbox_encode(&s, 0, regs, 28, &n), CS_OK);
    assert_int_equal(modbus_write_registers(ctx, CS_MODBUS_HR_MAILBOX, (int)n, regs), (int)n);
    assert_int_equal(modbus_write_registers(ctx, CS_MODBUS_HR_MAILBOX, (int)n, regs), (int)n);
    assert_int_equal(cs_modbus_mailbox_encode(&s, 5, regs, 28, &n), CS_OK);
    errno = 0;
    assert_int_equal(modbus_write_registers(ctx, CS_MODBUS_HR_MAILBOX, (int)n, regs), -1);
    assert_int_equal(errno, EMBXILVAL);
    /* a command, a read outside the map (exception 2), an unknown register for FC06 */
    assert_int_equal(modbus_write_register(ctx, CS_MODBUS_HR_COMMAND, CS_MODBUS_CMD_HOLD), 1);
    uint16_t one;
    assert_int_equal(modbus_read_registers(ctx, CS_MODBUS_HR_COMMAND, 1, &one), 1);
    assert_int_equal(one, CS_MODBUS_CMD_HOLD);
    errno = 0;
    assert_int_equal(modbus_read_input_registers(ctx, 100, 2, v), -1);
    assert_int_equal(errno, EMBXILADD);
    errno = 0;
    assert_int_equal(modbus_write_register(ctx, 0x0050, 1), -1);
    assert_int_equal(errno, EMBXILADD);
    /* a wrong unit id: the server stays silent, the client times out */
    modbus_set_slave(ctx, 4);
    modbus_set_response_timeout(ctx, 0, 100000);
    errno = 0;
    assert_int_equal(modbus_read_input_registers(ctx, 0, 1, v), -1);
    assert_int_equal(errno, ETIMEDOUT);
    modbus_close(ctx);
    modbus_free(ctx);
    unsigned submitted;
    uint64_t hash;
    stop_server(pid, slave, res, &submitted, &hash);
    assert_int_equal(submitted, 1);
    assert_int_equal(hash, fw_test_hash(FW_TEST_HASH0, &s.u.segment));
}

/* --- the host's link end to end, answers lost ------------------------------------------------ */

static void test_stream_lost_answers(void **state)
{
    (void)state;
    char path[256];
    int slave, res;
    pid_t pid = start_server(&slave, path, sizeof path, &res, 7);
    const size_t n = 400;
    cs_stream_job_t job;
    cs_stream_job_init(&job, CS_STREAM_SEGMENTS);
    uint64_t want = FW_TEST_HASH0;
    uint32_t x = 777;
    for (size_t k = 0; k < n; k++) {
        x = x * 1103515245u + 12345u;
        cs_segment_t sg = {.ticks = 50 + (x >> 28)};
        sg.steps[0] = (int32_t)((x >> 8) % 41) - 20;
        sg.steps[1] = (int32_t)((x >> 16) % 41) - 20;
        assert_int_equal(cs_stream_job_add_segments(&job, &sg, 1), CS_OK);
        want = fw_test_hash(want, &sg);
    }
    cs_mb_client_t c;
    char why[200];
    /* 40 ms a try: the server answers within a few ms on a pty */
    assert_int_equal(cs_mb_open_rtu(&c, path, 115200, 'E', 3, 40, 6, why, sizeof why), 0);
    cs_mb_stream_opts_t o;
    cs_mb_stream_opts_default(&o, &c, 3, 100000);
    cs_stream_result_t r;
    assert_int_equal(cs_mb_stream_run(&job, &o, &r), CS_OK);
    cs_mb_close(&c);
    unsigned submitted;
    uint64_t hash;
    stop_server(pid, slave, res, &submitted, &hash);
    assert_int_equal(r.outcome, CS_STREAM_DONE);
    assert_int_equal(r.executed, n);
    assert_true(r.link.timeouts > 0); /* answers were lost, and retried */
    assert_int_equal(submitted, n);   /* ... and nothing was queued twice or skipped */
    assert_int_equal(hash, want);
    cs_stream_job_free(&job);
}

/* A wrong unit id: no device, and the sentence says to check --unit. */
static void test_stream_wrong_unit(void **state)
{
    (void)state;
    char path[256];
    int slave, res;
    pid_t pid = start_server(&slave, path, sizeof path, &res, 0);
    cs_stream_job_t job;
    cs_stream_job_init(&job, CS_STREAM_SEGMENTS);
    cs_segment_t sg = {.ticks = 10};
    assert_int_equal(cs_stream_job_add_segments(&job, &sg, 1), CS_OK);
    cs_mb_client_t c;
    char why[200];
    assert_int_equal(cs_mb_open_rtu(&c, path, 115200, 'E', 9, 40, 2, why, sizeof why), 0);
    cs_mb_stream_opts_t o;
    cs_mb_stream_opts_default(&o, &c, 3, 100000);
    o.hello_ms = 300;
    cs_stream_result_t r;
    assert_int_equal(cs_mb_stream_run(&job, &o, &r), CS_OK);
    cs_mb_close(&c);
    unsigned submitted;
    uint64_t hash;
    stop_server(pid, slave, res, &submitted, &hash);
    assert_int_equal(r.outcome, CS_STREAM_NO_DEVICE);
    assert_non_null(strstr(r.why, "no answer from unit 9"));
    assert_non_null(strstr(r.why, "--unit"));
    assert_int_equal(submitted, 0);
    cs_stream_job_free(&job);
}

int main(void)
{
    signal(SIGPIPE, SIG_IGN);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crc),
        cmocka_unit_test(test_mailbox_codec),
        cmocka_unit_test(test_mailbox_pen),
        cmocka_unit_test(test_sequence_rule),
        cmocka_unit_test(test_commands_status_exceptions),
        cmocka_unit_test(test_lease),
        cmocka_unit_test(test_unknown_functions),
        cmocka_unit_test(test_mbap),
        cmocka_unit_test(test_rtu_framing),
        cmocka_unit_test(test_libmodbus_client),
        cmocka_unit_test(test_stream_lost_answers),
        cmocka_unit_test(test_stream_wrong_unit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
