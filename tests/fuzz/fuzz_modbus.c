/* libFuzzer target: arbitrary bytes into the core's Modbus RTU server (byte by byte, with timing
 * gaps and silences taken from the input) and straight into the PDU handler, behind a fake
 * application with a small motion queue that the input also drains, flushes and makes fail.
 * Asserts (abort = finding): no out-of-bounds access or UB (ASan, UBSan); every RTU reply is a
 * well-formed frame (CRC right, our unit id) answering a frame that was addressed to us, that
 * ended where the framing rules say (length rule or t3.5 silence), with its function code (or
 * it | 0x80 and exception 1..4 or 6) and the documented shape (byte count = 2 x quantity, FC06 /
 * FC16 echo); broadcasts and other units are never answered; the sequence rule: the k-th
 * message queued carries first_seq + k, so no sequence is queued twice (a bitmap of the
 * sequences queued is checked too), a normal FC16 answer to the mailbox means queued once or a
 * repeat, an exception means nothing queued; a full queue is exception 6; the registers read
 * back equal the message queued (re-encoded); the status block is consistent (VERSION, FREE
 * <= QUEUE_SIZE, NEXT_SEQ = first_seq + writes accepted, REFUSED a documented code and 0 after a
 * RESET with no refusal since, LEASE = a lease held). With the writer lease (configuration bit
 * 0x80): while a token holds it, no mailbox write that does not carry that token is taken, and
 * every refusal by the lease is exception 1 with REFUSED = CS_ERR_LEASED.
 * Input: byte 0 = configuration (baud, queue size, first sequence, start time), then records:
 *   00gggggg L b[L]  L bytes on the RTU line, gggggg x 64 us between bytes (the first byte
 *                    after the previous record's last byte by the same gap)
 *   01...... S       S x 32 us of silence, then cs_modbus_rtu_idle
 *   10...... L b[L]  L bytes as one PDU to cs_modbus_pdu
 *   11xxxxxx         application: x&3 = 0 execute (x>>2)+1 queued messages, 1 fail the next
 *                    submit with CS_ERR_LIMIT, 2 queue stays full until the next execute,
 *                    3 the lease expires (its holder went silent)
 * Configuration bit 0x80: the application has the writer lease hook (a holder without a clock:
 * it ends by release or by record 11xxxx11).
 * Built and run by scripts/fuzz.sh; -DCS_FUZZ_SEED_MAIN builds the seed writer instead. */
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#define FUZZ_NAME "fuzz_modbus"
#include "fuzz_common.h"

#include "cs_modbus.h"

#define UNIT 17

/* --- the fake application ------------------------------------------------------------------ */

typedef struct {
    uint16_t queue_size, pending;
    bool fail_next, stuck_full;
    uint16_t first_seq;
    uint32_t queued;                                   /* messages queued since the start */
    uint8_t seen[65536 / 8];                           /* sequences queued */
    uint32_t distinct;                                 /* distinct sequences queued */
    uint32_t submits_ok, submits_full, submits_failed; /* in the current request */
    cs_proto_msg_t last_msg;
    uint16_t last_seq;
    uint16_t last_cmd;
    uint32_t refused_at_reset; /* map refusals counted at the last RESET */
    bool reset_seen;           /* a RESET was obeyed since the start */
    bool reset_now;            /* ... during the current request */
    bool lease_hook;           /* the map has the lease (configuration bit 0x80) */
    uint16_t refused_now;      /* the map's REFUSED after the current request */
    uint16_t holder;           /* the lease's token, 0: free */
    uint16_t holder_before;    /* ... when the current request began */
    uint32_t lease_refusals;   /* in the current request */
} app_t;

/* The writer lease without a clock (cs_fw_modbus's expiry is unit-tested): one token at a time. */
static cs_err_t app_lease(void *ctx, uint8_t op, uint16_t token)
{
    app_t *a = ctx;
    FUZZ_CHECK(op == CS_MODBUS_LEASE_WRITE || token != 0); /* the map refuses token 0 itself */
    if (a->holder != 0 && token != a->holder) {
        a->lease_refusals++;
        return CS_ERR_LEASED;
    }
    if (op == CS_MODBUS_LEASE_CLAIM)
        a->holder = token;
    else if (op == CS_MODBUS_LEASE_RELEASE)
        a->holder = 0;
    return CS_OK;
}

static cs_err_t app_submit(void *ctx, const cs_proto_msg_t *m, uint16_t seq)
{
    app_t *a = ctx;
    FUZZ_CHECK(m->type == CS_PROTO_SEGMENT || m->type == CS_PROTO_CURVE || m->type == CS_PROTO_PEN);
    if (a->fail_next) {
        a->fail_next = false;
        a->submits_failed++;
        return CS_ERR_LIMIT;
    }
    if (a->stuck_full || a->pending >= a->queue_size) {
        a->submits_full++;
        return CS_ERR_FULL;
    }
    /* the sequence rule: the k-th message queued carries first_seq + k (mod 65536) */
    FUZZ_CHECK(seq == (uint16_t)(a->first_seq + a->queued));
    if (!(a->seen[seq >> 3] & (1u << (seq & 7)))) {
        a->seen[seq >> 3] = (uint8_t)(a->seen[seq >> 3] | (1u << (seq & 7)));
        a->distinct++;
    }
    a->queued++;
    /* fewer than 65536 messages fit one input: every sequence queued is a new one */
    FUZZ_CHECK(a->queued == a->distinct);
    a->pending++;
    a->submits_ok++;
    a->last_msg = *m;
    a->last_seq = seq;
    return CS_OK;
}

static void app_command(void *ctx, uint16_t cmd)
{
    app_t *a = ctx;
    FUZZ_CHECK(cmd >= CS_MODBUS_CMD_HOLD && cmd <= CS_MODBUS_CMD_RESET);
    if (cmd == CS_MODBUS_CMD_ABORT || cmd == CS_MODBUS_CMD_RESET)
        a->pending = 0;
    if (cmd == CS_MODBUS_CMD_RESET)
        a->reset_now = true;
    a->last_cmd = cmd;
}

static void app_status(void *ctx, cs_modbus_status_t *st)
{
    app_t *a = ctx;
    st->caps = CS_PROTO_CAP_ALL;
    st->axes = 4;
    st->queue_size = a->queue_size;
    st->tick_hz = 1000000;
    st->boot_id = 0xB0070001u;
    st->state = a->pending ? CS_PROTO_STATE_RUNNING : CS_PROTO_STATE_IDLE;
    st->free_slots = (uint16_t)(a->queue_size - a->pending);
    st->last_exec = (uint16_t)(a->first_seq + a->queued - a->pending - 1u);
    st->pos[0] = -7;
    st->pos[3] = INT32_MIN;
    st->lease = a->holder != 0;
    st->lease_left_ms = a->holder != 0 ? 5000 : 0;
}

/* --- checks --------------------------------------------------------------------------------- */

static uint16_t rd16(const uint8_t *p)
{
    return (uint16_t)((p[0] << 8) | p[1]);
}

static bool refused_code_ok(uint16_t c)
{
    return c == 0 || c == CS_ERR_SEQ || c == CS_ERR_RANGE || c == CS_ERR_FRAME ||
           c == CS_ERR_UNSUPPORTED || c == CS_ERR_FULL || c == CS_ERR_LIMIT || c == CS_ERR_LEASED;
}

/* The state of the map and the application agree; a full FC04 read shows it consistently. */
static void check_state(cs_modbus_map_t *mp, app_t *a)
{
    FUZZ_CHECK(mp->next_seq == (uint16_t)(a->first_seq + a->queued));
    FUZZ_CHECK(mp->stats.accepted == a->queued);
    FUZZ_CHECK(mp->last_n == 0 || mp->last_n == CS_MODBUS_MAILBOX_SEGMENT_REGS ||
               mp->last_n == CS_MODBUS_MAILBOX_CURVE_REGS ||
               mp->last_n == CS_MODBUS_MAILBOX_PEN_REGS);
    FUZZ_CHECK(refused_code_ok(mp->refused));
    if (a->reset_seen && mp->stats.refused == a->refused_at_reset)
        FUZZ_CHECK(mp->refused == 0 && mp->refused_seq == 0);
    /* the mailbox reads back the registers of the last message queued, re-encoded */
    if (a->queued > 0) {
        uint16_t regs[CS_MODBUS_MAILBOX_REGS];
        size_t n = 0;
        FUZZ_CHECK(cs_modbus_mailbox_encode(&a->last_msg, a->last_seq, regs, CS_MODBUS_MAILBOX_REGS,
                                            &n) == CS_OK);
        FUZZ_CHECK(n == mp->last_n);
        uint8_t req[5] = {CS_MODBUS_FC_READ_HOLDING, 0x01, 0x00, 0, (uint8_t)n}, rsp[256];
        size_t rn = 0;
        FUZZ_CHECK(cs_modbus_pdu(mp, req, 5, rsp, sizeof rsp, &rn) == CS_OK);
        FUZZ_CHECK(rn == 2 + 2 * n && rsp[0] == CS_MODBUS_FC_READ_HOLDING && rsp[1] == 2 * n);
        for (size_t k = 0; k < n; k++)
            FUZZ_CHECK(rd16(rsp + 2 + 2 * k) == regs[k]);
    }
    uint8_t req[5] = {CS_MODBUS_FC_READ_INPUT, 0, 0, 0, CS_MODBUS_IR_COUNT}, rsp[256];
    size_t rn = 0;
    FUZZ_CHECK(cs_modbus_pdu(mp, req, 5, rsp, sizeof rsp, &rn) == CS_OK);
    FUZZ_CHECK(rn == 2 + 2 * CS_MODBUS_IR_COUNT && rsp[1] == 2 * CS_MODBUS_IR_COUNT);
    const uint8_t *ir = rsp + 2;
#define IR(i) rd16(ir + 2 * (i))
    FUZZ_CHECK(IR(CS_MODBUS_IR_VERSION) == CS_MODBUS_MAP_VERSION);
    FUZZ_CHECK(IR(CS_MODBUS_IR_QUEUE_SIZE) == a->queue_size);
    FUZZ_CHECK(IR(CS_MODBUS_IR_FREE) <= IR(CS_MODBUS_IR_QUEUE_SIZE));
    FUZZ_CHECK(IR(CS_MODBUS_IR_FREE) == a->queue_size - a->pending);
    FUZZ_CHECK(IR(CS_MODBUS_IR_STATE) < CS_PROTO_STATE_COUNT_);
    FUZZ_CHECK(IR(CS_MODBUS_IR_NEXT_SEQ) == (uint16_t)(a->first_seq + a->queued));
    FUZZ_CHECK(IR(CS_MODBUS_IR_REFUSED) == mp->refused);
    FUZZ_CHECK(IR(CS_MODBUS_IR_REFUSED_SEQ) == mp->refused_seq);
    FUZZ_CHECK(IR(CS_MODBUS_IR_POS + 6) == 0x8000 && IR(CS_MODBUS_IR_POS + 7) == 0);
    FUZZ_CHECK(IR(CS_MODBUS_IR_LEASE) == (a->holder != 0));
#undef IR
    uint8_t hreq[5] = {CS_MODBUS_FC_READ_HOLDING, 0, 0, 0, 1};
    FUZZ_CHECK(cs_modbus_pdu(mp, hreq, 5, rsp, sizeof rsp, &rn) == CS_OK);
    FUZZ_CHECK(rn == 4 && rd16(rsp + 2) == a->last_cmd);
}

/* A one-register write answered normally: a command obeyed, or the lease claimed (then held
 * by that token) or released (then free). */
static void check_one_write(uint16_t addr, uint16_t v, const app_t *a)
{
    if (addr == CS_MODBUS_HR_COMMAND) {
        FUZZ_CHECK(a->last_cmd == v);
        return;
    }
    FUZZ_CHECK(a->lease_hook && v != 0);
    FUZZ_CHECK(addr == CS_MODBUS_HR_LEASE || addr == CS_MODBUS_HR_RELEASE);
    FUZZ_CHECK(a->holder == (addr == CS_MODBUS_HR_LEASE ? v : 0));
    FUZZ_CHECK(a->holder_before == 0 || a->holder_before == v);
}

static bool exception_code_ok(uint8_t c)
{
    return c >= 1 && c <= 4 ? true : c == 6;
}

/* A reply PDU p[0..n) to the request PDU q[0..qn), with what the application saw meanwhile
 * (submits_* of *a, map stats before: acc0, rep0). */
static void check_reply(const uint8_t *q, size_t qn, const uint8_t *p, size_t n, const app_t *a,
                        const cs_modbus_stats_t *before, const cs_modbus_stats_t *after)
{
    uint8_t fc = qn > 0 ? q[0] : 0;
    FUZZ_CHECK(n >= 2);
    FUZZ_CHECK(a->submits_ok + a->submits_full + a->submits_failed <= 1);
    FUZZ_CHECK(after->requests == before->requests + 1);
    if (p[0] & 0x80) {
        FUZZ_CHECK(p[0] == (fc | 0x80) && n == 2 && exception_code_ok(p[1]));
        FUZZ_CHECK(after->exceptions == before->exceptions + 1);
        FUZZ_CHECK(a->submits_ok == 0); /* an exception: nothing queued */
        FUZZ_CHECK(a->submits_full == 0 || p[1] == CS_MODBUS_EX_DEVICE_BUSY);
        FUZZ_CHECK(a->submits_failed == 0 || p[1] == CS_MODBUS_EX_DEVICE_FAILURE);
        /* the lease refused it: exception 1, and REFUSED says why */
        FUZZ_CHECK(a->lease_refusals == 0 ||
                   (p[1] == CS_MODBUS_EX_ILLEGAL_FUNCTION && a->refused_now == CS_ERR_LEASED));
        return;
    }
    FUZZ_CHECK(a->lease_refusals == 0);
    FUZZ_CHECK(p[0] == fc && qn >= 5);
    FUZZ_CHECK(after->exceptions == before->exceptions);
    FUZZ_CHECK(a->submits_full == 0 && a->submits_failed == 0);
    uint16_t addr = rd16(q + 1), qty = rd16(q + 3);
    switch (fc) {
    case CS_MODBUS_FC_READ_HOLDING:
    case CS_MODBUS_FC_READ_INPUT:
        FUZZ_CHECK(qn == 5 && qty >= 1 && qty <= 125 && n == 2 + 2 * (size_t)qty &&
                   p[1] == 2 * qty);
        FUZZ_CHECK(a->submits_ok == 0);
        break;
    case CS_MODBUS_FC_WRITE_SINGLE:
        FUZZ_CHECK(qn == 5 && n == 5 && memcmp(p, q, 5) == 0 && a->submits_ok == 0);
        check_one_write(addr, qty, a);
        break;
    case CS_MODBUS_FC_WRITE_MULTI:
        FUZZ_CHECK(n == 5 && memcmp(p, q, 5) == 0 && qn == 6 + 2 * (size_t)qty && q[5] == 2 * qty);
        if (addr == CS_MODBUS_HR_MAILBOX || addr == CS_MODBUS_HR_TOKEN) {
            /* with a lease held, only its holder's token is taken */
            bool token = addr == CS_MODBUS_HR_TOKEN;
            FUZZ_CHECK(!token || a->lease_hook);
            FUZZ_CHECK(a->holder_before == 0 || (token && rd16(q + 6) == a->holder_before));
            qty = (uint16_t)(qty - token);
            /* queued once, or the repeat of the last write answered without queueing */
            bool queued = a->submits_ok == 1 && after->accepted == before->accepted + 1 &&
                          after->repeats == before->repeats;
            bool repeat = a->submits_ok == 0 && after->accepted == before->accepted &&
                          after->repeats == before->repeats + 1;
            FUZZ_CHECK(queued || repeat);
            FUZZ_CHECK(qty == CS_MODBUS_MAILBOX_SEGMENT_REGS ||
                       qty == CS_MODBUS_MAILBOX_CURVE_REGS || qty == CS_MODBUS_MAILBOX_PEN_REGS);
            FUZZ_CHECK(rd16(q + 4 + 2 * (qty + token)) ==
                       (uint16_t)(a->first_seq + a->queued - 1u));
        } else {
            FUZZ_CHECK(qty == 1 && a->submits_ok == 0);
            check_one_write(addr, rd16(q + 6), a);
        }
        break;
    default:
        FUZZ_CHECK(false); /* a normal answer to a function not served */
    }
}

/* --- the run -------------------------------------------------------------------------------- */

static app_t app;
static cs_modbus_map_t map;
static cs_modbus_rtu_t rtu;

/* The line as the server should see it: bytes since the current frame began. */
static uint8_t line[4096];
static size_t line_start, line_n; /* frame = line[line_start..line_n) */
static bool skipping;             /* after an overrun: until the next silence */
static uint32_t now, last_byte;
static bool any_byte;

static void before_request(cs_modbus_stats_t *s)
{
    app.submits_ok = app.submits_full = app.submits_failed = 0;
    app.lease_refusals = 0;
    app.holder_before = app.holder;
    app.reset_now = false;
    *s = map.stats;
}

/* A RESET obeyed during this request cleared REFUSED and REFUSED_SEQ (a request that is a
 * command refuses no mailbox write); check_state then holds them at 0 until a refusal. */
static void after_command_reset(const cs_modbus_stats_t *before)
{
    if (!app.reset_now)
        return;
    FUZZ_CHECK(map.stats.refused == before->refused);
    FUZZ_CHECK(map.refused == 0 && map.refused_seq == 0);
    app.reset_seen = true;
    app.refused_at_reset = map.stats.refused;
}

/* A reply frame from the RTU server for the frame line[line_start..end). */
static void check_rtu_reply(size_t end, const uint8_t *reply, size_t len,
                            const cs_modbus_stats_t *before)
{
    FUZZ_CHECK(!skipping && end > line_start);
    const uint8_t *q = line + line_start;
    size_t qn = end - line_start;
    FUZZ_CHECK(qn >= 4 && qn <= CS_MODBUS_RTU_MAX && q[0] == UNIT);
    FUZZ_CHECK(cs_modbus_crc(CS_MODBUS_CRC_INIT, q, qn) == 0);
    FUZZ_CHECK(len >= 5 && len <= CS_MODBUS_RTU_MAX && reply[0] == UNIT);
    FUZZ_CHECK(cs_modbus_crc(CS_MODBUS_CRC_INIT, reply, len) == 0);
    app.refused_now = map.refused;
    check_reply(q + 1, qn - 3, reply + 1, len - 3, &app, before, &map.stats);
}

/* A frame ended without a reply: dropped (CRC, length), another unit, or a broadcast. */
static void check_rtu_silent(const cs_modbus_rtu_stats_t *r0)
{
    uint32_t ended = (rtu.stats.crc_errs - r0->crc_errs) + (rtu.stats.other_unit - r0->other_unit) +
                     (rtu.stats.broadcasts - r0->broadcasts);
    FUZZ_CHECK(ended <= 1 && rtu.stats.frames == r0->frames);
    if (rtu.stats.broadcasts != r0->broadcasts)
        FUZZ_CHECK(line_n > line_start && line[line_start] == 0);
    if (rtu.stats.other_unit != r0->other_unit)
        FUZZ_CHECK(line_n > line_start && line[line_start] != 0 && line[line_start] != UNIT);
}

static void frame_ended_at(size_t end)
{
    line_start = end;
}

static void silence_idle(uint32_t us)
{
    now += us;
    cs_modbus_stats_t before;
    before_request(&before);
    cs_modbus_rtu_stats_t r0 = rtu.stats;
    const uint8_t *reply = NULL;
    size_t len = 0;
    cs_err_t e = cs_modbus_rtu_idle(&rtu, now, &reply, &len);
    FUZZ_CHECK(e == CS_OK || e == CS_ERR_EMPTY);
    bool silent = any_byte && (uint32_t)(now - last_byte) >= rtu.gap_us;
    if (e == CS_OK) {
        FUZZ_CHECK(silent);
        check_rtu_reply(line_n, reply, len, &before);
        FUZZ_CHECK(rtu.stats.frames == r0.frames + 1);
    } else {
        check_rtu_silent(&r0);
        FUZZ_CHECK(app.submits_ok == 0 || rtu.stats.broadcasts == r0.broadcasts + 1);
        if (!silent) /* before t3.5 nothing ends */
            FUZZ_CHECK(memcmp(&rtu.stats, &r0, sizeof r0) == 0);
    }
    after_command_reset(&before);
    if (silent) {
        skipping = false;
        frame_ended_at(line_n);
    }
}

static void feed(uint8_t b, uint32_t gap)
{
    now += gap;
    bool silent = any_byte && (uint32_t)(now - last_byte) >= rtu.gap_us;
    if (line_n == sizeof line) { /* the model's buffer: keep the current frame only */
        size_t keep = line_n - line_start;
        memmove(line, line + line_start, keep);
        line_start = 0;
        line_n = keep;
    }
    if (silent) {
        skipping = false;
        /* the frame before this byte ends here (checked below) */
    }
    cs_modbus_stats_t before;
    before_request(&before);
    cs_modbus_rtu_stats_t r0 = rtu.stats;
    const uint8_t *reply = NULL;
    size_t len = 0;
    cs_err_t e = cs_modbus_rtu_feed(&rtu, b, now, &reply, &len);
    FUZZ_CHECK(e == CS_OK || e == CS_ERR_EMPTY);
    any_byte = true;
    last_byte = now;
    line[line_n++] = b;
    if (silent) {
        /* the previous frame ended at the silence; this byte starts the next one */
        if (e == CS_OK)
            check_rtu_reply(line_n - 1, reply, len, &before);
        else
            check_rtu_silent(&r0);
        frame_ended_at(line_n - 1);
        FUZZ_CHECK(rtu.stats.overruns == r0.overruns);
    } else if (rtu.stats.overruns != r0.overruns) {
        /* longer than any frame: dropped, skipped to the next silence */
        FUZZ_CHECK(e == CS_ERR_EMPTY && !skipping && line_n - line_start > CS_MODBUS_RTU_MAX);
        skipping = true;
    } else if (e == CS_OK) {
        /* the length rule ended the frame with this byte */
        check_rtu_reply(line_n, reply, len, &before);
        frame_ended_at(line_n);
    } else if (rtu.stats.other_unit != r0.other_unit || rtu.stats.broadcasts != r0.broadcasts) {
        check_rtu_silent(&r0);
        frame_ended_at(line_n);
    } else {
        FUZZ_CHECK(rtu.stats.crc_errs == r0.crc_errs);
    }
    if (e != CS_OK)
        FUZZ_CHECK(app.submits_ok == 0 || rtu.stats.broadcasts == r0.broadcasts + 1);
    after_command_reset(&before);
}

static void pdu(const uint8_t *q, size_t qn)
{
    cs_modbus_stats_t before;
    before_request(&before);
    uint8_t rsp[CS_MODBUS_PDU_MAX + 8];
    memset(rsp, 0xA5, sizeof rsp);
    size_t rn = 0;
    FUZZ_CHECK(cs_modbus_pdu(&map, q, qn, rsp, CS_MODBUS_PDU_MAX, &rn) == CS_OK);
    FUZZ_CHECK(rn >= 2 && rn <= CS_MODBUS_PDU_MAX);
    for (size_t k = CS_MODBUS_PDU_MAX; k < sizeof rsp; k++)
        FUZZ_CHECK(rsp[k] == 0xA5); /* nothing written past cap */
    app.refused_now = map.refused;
    check_reply(q, qn, rsp, rn, &app, &before, &map.stats);
    after_command_reset(&before);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    static const uint16_t firsts[4] = {0, 0xFFFE, 0x8000, 1};
    uint8_t cfg = data[0];
    memset(&app, 0, sizeof app);
    app.queue_size = (uint16_t)(1 + (cfg & 7));
    app.first_seq = firsts[(cfg >> 3) & 3];
    app.lease_hook = (cfg & 0x80) != 0;
    cs_modbus_app_t hooks = {app_submit, app_command, app_status, app.lease_hook ? app_lease : NULL,
                             &app};
    FUZZ_CHECK(cs_modbus_map_init(&map, &hooks, app.first_seq) == CS_OK);
    uint32_t baud = (cfg & 0x20) ? 9600 : 115200;
    FUZZ_CHECK(cs_modbus_rtu_init(&rtu, &map, UNIT, baud) == CS_OK);
    FUZZ_CHECK(rtu.gap_us == (baud == 9600 ? 4011u : 1750u));
    /* start near the wrap of the microsecond clock, or at 0 */
    now = (cfg & 0x40) ? 0xFFFFF000u : 0;
    last_byte = now;
    any_byte = false;
    line_start = line_n = 0;
    skipping = false;
    check_state(&map, &app);

    size_t i = 1;
    while (i < size) {
        uint8_t op = data[i++];
        switch (op >> 6) {
        case 0: {
            if (i >= size)
                return 0;
            size_t n = data[i++];
            uint32_t gap = 64u * (op & 0x3Fu);
            for (size_t k = 0; k < n && i < size; k++)
                feed(data[i++], gap);
            break;
        }
        case 1:
            if (i >= size)
                return 0;
            silence_idle(32u * data[i++]);
            break;
        case 2: {
            if (i >= size)
                return 0;
            size_t n = data[i++];
            if (n > size - i)
                n = size - i;
            pdu(data + i, n);
            i += n;
            break;
        }
        default:
            switch (op & 3) {
            case 0: {
                unsigned k = ((op >> 2) & 15u) + 1;
                app.pending = (uint16_t)(app.pending > k ? app.pending - k : 0);
                app.stuck_full = false;
                break;
            }
            case 1:
                app.fail_next = true;
                break;
            case 2:
                app.stuck_full = true;
                break;
            default:
                app.holder = 0; /* the lease expired */
                break;
            }
        }
        check_state(&map, &app);
    }
    /* the end of the input is a long silence: whatever is pending is checked */
    silence_idle(100000);
    check_state(&map, &app);
    return 0;
}

#ifdef CS_FUZZ_SEED_MAIN
/* Seed builder: appends records to buf. */
typedef struct {
    uint8_t b[4096];
    size_t n;
} seed_t;

static void put(seed_t *s, uint8_t v)
{
    if (s->n >= sizeof s->b) {
        fprintf(stderr, "fuzz_modbus seed: too long\n");
        exit(1);
    }
    s->b[s->n++] = v;
}

/* An RTU frame (unit, PDU, CRC) with gap64 x 64 us between bytes; then 4 ms of silence. */
static void rtu_rec(seed_t *s, uint8_t unit, const uint8_t *p, size_t n, unsigned gap64, bool bad)
{
    uint8_t f[CS_MODBUS_RTU_MAX];
    size_t len = 0;
    if (cs_modbus_rtu_frame(unit, p, n, f, sizeof f, &len) != CS_OK) {
        fprintf(stderr, "fuzz_modbus seed: frame\n");
        exit(1);
    }
    if (bad)
        f[len - 1] ^= 0x55;
    put(s, (uint8_t)(gap64 & 0x3F));
    put(s, (uint8_t)len);
    for (size_t k = 0; k < len; k++)
        put(s, f[k]);
    put(s, 0x40);
    put(s, 125); /* 4 ms */
}

static void pdu_rec(seed_t *s, const uint8_t *p, size_t n)
{
    put(s, 0x80);
    put(s, (uint8_t)n);
    for (size_t k = 0; k < n; k++)
        put(s, p[k]);
}

static size_t rd(uint8_t *p, uint8_t fc, uint16_t addr, uint16_t qty)
{
    p[0] = fc;
    p[1] = (uint8_t)(addr >> 8), p[2] = (uint8_t)addr;
    p[3] = (uint8_t)(qty >> 8), p[4] = (uint8_t)qty;
    return 5;
}

static size_t wr_regs(uint8_t *p, uint16_t addr, const uint16_t *r, size_t n)
{
    p[0] = CS_MODBUS_FC_WRITE_MULTI;
    p[1] = (uint8_t)(addr >> 8), p[2] = (uint8_t)addr;
    p[3] = 0, p[4] = (uint8_t)n, p[5] = (uint8_t)(2 * n);
    for (size_t k = 0; k < n; k++) {
        p[6 + 2 * k] = (uint8_t)(r[k] >> 8);
        p[7 + 2 * k] = (uint8_t)r[k];
    }
    return 6 + 2 * n;
}

static size_t segment(uint8_t *p, uint16_t seq)
{
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_SEGMENT;
    m.u.segment = (cs_segment_t){1000, {250, -100, -1000, 7}};
    uint16_t r[CS_MODBUS_MAILBOX_REGS];
    size_t n = 0;
    if (cs_modbus_mailbox_encode(&m, seq, r, CS_MODBUS_MAILBOX_REGS, &n) != CS_OK)
        exit(1);
    return wr_regs(p, CS_MODBUS_HR_MAILBOX, r, n);
}

static size_t curve(uint8_t *p, uint16_t seq)
{
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_CURVE;
    for (int k = 0; k < 4; k++)
        m.u.curve.p[k] = (cs_vec3_t){k * 65536, -k * 1000, 5};
    m.u.curve.feed = 20 * 65536;
    uint16_t r[CS_MODBUS_MAILBOX_REGS];
    size_t n = 0;
    if (cs_modbus_mailbox_encode(&m, seq, r, CS_MODBUS_MAILBOX_REGS, &n) != CS_OK)
        exit(1);
    return wr_regs(p, CS_MODBUS_HR_MAILBOX, r, n);
}

static void emit(const char *dir, const char *name, seed_t *s)
{
    fuzz_write_file(dir, name, s->b, s->n);
    LLVMFuzzerTestOneInput(s->b, s->n);
    s->n = 0;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s corpus-dir\n", argv[0]);
        return 2;
    }
    const char *d = argv[1];
    seed_t s = {{0}, 0};
    uint8_t p[CS_MODBUS_PDU_MAX];
    size_t n;
    const uint8_t cfg = 3; /* 115200 baud, queue 4, first sequence 0 */

    /* every function code and register range, over RTU */
    put(&s, cfg);
    rtu_rec(&s, UNIT, p, rd(p, CS_MODBUS_FC_READ_INPUT, 0, CS_MODBUS_IR_COUNT), 1, false);
    rtu_rec(&s, UNIT, p, rd(p, CS_MODBUS_FC_READ_INPUT, 8, 4), 1, false);
    rtu_rec(&s, UNIT, p, rd(p, CS_MODBUS_FC_READ_INPUT, 22, 5), 1, false); /* past the end */
    rtu_rec(&s, UNIT, p, rd(p, CS_MODBUS_FC_READ_HOLDING, 0, 1), 1, false);
    rtu_rec(&s, UNIT, p, rd(p, CS_MODBUS_FC_READ_HOLDING, 0x100, 28), 1, false);
    rtu_rec(&s, UNIT, p, rd(p, CS_MODBUS_FC_READ_HOLDING, 0x1, 1), 1, false);
    rtu_rec(&s, UNIT, p, rd(p, CS_MODBUS_FC_READ_HOLDING, 0, 126), 1, false);
    rtu_rec(&s, UNIT, p, rd(p, CS_MODBUS_FC_WRITE_SINGLE, 0, CS_MODBUS_CMD_HOLD), 1, false);
    rtu_rec(&s, UNIT, p, rd(p, CS_MODBUS_FC_WRITE_SINGLE, 0, CS_MODBUS_CMD_RESUME), 1, false);
    rtu_rec(&s, UNIT, p, rd(p, CS_MODBUS_FC_WRITE_SINGLE, 0, 9), 1, false);
    rtu_rec(&s, UNIT, p, rd(p, CS_MODBUS_FC_WRITE_SINGLE, 0x100, 1), 1, false);
    uint16_t cmd = CS_MODBUS_CMD_ABORT;
    rtu_rec(&s, UNIT, p, wr_regs(p, CS_MODBUS_HR_COMMAND, &cmd, 1), 1, false);
    p[0] = 0x2B, p[1] = 0x0E, p[2] = 0x01, p[3] = 0x00; /* FC43, not served: ends at t3.5 */
    rtu_rec(&s, UNIT, p, 4, 1, false);
    emit(d, "seed-functions", &s);

    /* mailbox: SEGMENT, its retry, CURVE, a gap, a full queue, then RESET */
    put(&s, cfg);
    n = segment(p, 0);
    rtu_rec(&s, UNIT, p, n, 0, false);
    rtu_rec(&s, UNIT, p, n, 0, false); /* the retry: answered, not queued */
    n = curve(p, 1);
    rtu_rec(&s, UNIT, p, n, 2, false);
    n = segment(p, 5);
    rtu_rec(&s, UNIT, p, n, 0, false); /* a gap: exception 3 */
    put(&s, 0xC2);                     /* queue full */
    n = segment(p, 2);
    rtu_rec(&s, UNIT, p, n, 0, false); /* exception 6 */
    put(&s, 0xC0);
    rtu_rec(&s, UNIT, p, n, 0, false); /* now taken */
    put(&s, 0xC1);
    n = curve(p, 3);
    rtu_rec(&s, UNIT, p, n, 0, false); /* exception 4 */
    rtu_rec(&s, UNIT, p, rd(p, CS_MODBUS_FC_WRITE_SINGLE, 0, CS_MODBUS_CMD_RESET), 0, false);
    emit(d, "seed-mailbox", &s);

    /* a wrong unit, a broadcast write, a bad CRC, a truncated frame, noise */
    put(&s, cfg | 0x20); /* 9600 baud */
    n = segment(p, 0);
    rtu_rec(&s, 5, p, n, 1, false);
    rtu_rec(&s, 0, p, n, 1, false);
    n = segment(p, 1);
    rtu_rec(&s, UNIT, p, n, 1, true);
    rtu_rec(&s, UNIT, p, rd(p, CS_MODBUS_FC_READ_INPUT, 0, 24), 1, false);
    put(&s, 0x01), put(&s, 5);
    put(&s, UNIT), put(&s, 0x03), put(&s, 0), put(&s, 0), put(&s, 0); /* truncated */
    put(&s, 0x40), put(&s, 200);
    put(&s, 0x00), put(&s, 200);
    for (int k = 0; k < 200; k++)
        put(&s, (uint8_t)(k * 37));
    /* noise longer than any frame: dropped at the next silence, then a good request */
    for (int r = 0; r < 2; r++) {
        put(&s, 0x00), put(&s, 200);
        for (int k = 0; k < 200; k++)
            put(&s, (uint8_t)(UNIT + k * 11));
    }
    put(&s, 0x40), put(&s, 200);
    rtu_rec(&s, UNIT, p, rd(p, CS_MODBUS_FC_READ_HOLDING, 0, 1), 1, false);
    emit(d, "seed-units", &s);

    /* two frames back to back (no gap: the length rule splits them), near the clock's wrap */
    put(&s, cfg | 0x40);
    {
        uint8_t f[2 * CS_MODBUS_RTU_MAX];
        size_t l1 = 0, l2 = 0;
        n = rd(p, CS_MODBUS_FC_READ_INPUT, 0, 24);
        cs_modbus_rtu_frame(UNIT, p, n, f, CS_MODBUS_RTU_MAX, &l1);
        n = segment(p, 0);
        cs_modbus_rtu_frame(UNIT, p, n, f + l1, CS_MODBUS_RTU_MAX, &l2);
        put(&s, 0x01);
        put(&s, (uint8_t)(l1 + l2));
        for (size_t k = 0; k < l1 + l2; k++)
            put(&s, f[k]);
    }
    emit(d, "seed-wrap", &s);

    /* the PDU handler directly: every function, the mailbox, bad lengths */
    put(&s, 7 | 0x08); /* queue 8, first sequence 0xFFFE: the wrap of the sequence */
    pdu_rec(&s, p, rd(p, CS_MODBUS_FC_READ_INPUT, 0, 24));
    pdu_rec(&s, p, rd(p, CS_MODBUS_FC_READ_HOLDING, 0x100, 12));
    pdu_rec(&s, p, segment(p, 0xFFFE));
    pdu_rec(&s, p, curve(p, 0xFFFF));
    pdu_rec(&s, p, segment(p, 0));
    pdu_rec(&s, p, segment(p, 0));
    pdu_rec(&s, p, rd(p, CS_MODBUS_FC_WRITE_SINGLE, 0, CS_MODBUS_CMD_RESET));
    pdu_rec(&s, p, 4);
    pdu_rec(&s, p, 0);
    emit(d, "seed-pdu", &s);

    /* the writer lease: a claim, the holder's write with its token, a foreign write with the
     * next sequence (refused), a foreign claim, the lease expiring, a release */
    put(&s, cfg | 0x80);
    pdu_rec(&s, p, rd(p, CS_MODBUS_FC_WRITE_SINGLE, CS_MODBUS_HR_LEASE, 0x1234));
    {
        uint16_t r[1 + CS_MODBUS_MAILBOX_REGS];
        n = segment(p, 0);
        r[0] = 0x1234;
        for (size_t k = 0; k < CS_MODBUS_MAILBOX_SEGMENT_REGS; k++)
            r[1 + k] = (uint16_t)((p[6 + 2 * k] << 8) | p[7 + 2 * k]);
        pdu_rec(&s, p, wr_regs(p, CS_MODBUS_HR_TOKEN, r, 1 + CS_MODBUS_MAILBOX_SEGMENT_REGS));
        pdu_rec(&s, p, segment(p, 1)); /* no token: refused */
        r[0] = 0x9999;
        r[CS_MODBUS_MAILBOX_SEGMENT_REGS] = 1;
        pdu_rec(&s, p, wr_regs(p, CS_MODBUS_HR_TOKEN, r, 1 + CS_MODBUS_MAILBOX_SEGMENT_REGS));
    }
    pdu_rec(&s, p, rd(p, CS_MODBUS_FC_WRITE_SINGLE, CS_MODBUS_HR_LEASE, 0x9999));
    pdu_rec(&s, p, rd(p, CS_MODBUS_FC_READ_HOLDING, CS_MODBUS_HR_TOKEN, 29));
    put(&s, 0xC3); /* expires */
    pdu_rec(&s, p, rd(p, CS_MODBUS_FC_WRITE_SINGLE, CS_MODBUS_HR_LEASE, 0x9999));
    pdu_rec(&s, p, rd(p, CS_MODBUS_FC_WRITE_SINGLE, CS_MODBUS_HR_RELEASE, 0x9999));
    rtu_rec(&s, UNIT, p, segment(p, 1), 0, false);
    emit(d, "seed-lease", &s);
    return 0;
}
#endif
