/* cs_modbus: register map, mailbox codec, PDU handler and RTU server. See cs_modbus.h and
 * docs/modbus.md; the Modbus layouts cited are from "MODBUS Application Protocol Specification
 * V1.1b3" (PDU formats, section 6; exceptions, section 7) and "MODBUS over Serial Line V1.02"
 * (RTU framing, CRC, t3.5). */
#include "cs_modbus.h"

#include "cs_machine.h"

CS_STATIC_ASSERT(CS_MODBUS_MAILBOX_REGS <= 123, mailbox_fits_one_fc16);
CS_STATIC_ASSERT(CS_MODBUS_IR_COUNT <= 125, status_fits_one_fc04);
CS_STATIC_ASSERT(CS_MODBUS_MAILBOX_SEGMENT_REGS <= CS_MODBUS_MAILBOX_REGS, segment_fits);

/* --- CRC-16/MODBUS ------------------------------------------------------------------------- */

uint16_t cs_modbus_crc(uint16_t crc, const uint8_t *data, size_t len)
{
    for (size_t i = 0; i < len; i++) {
        crc = (uint16_t)(crc ^ data[i]);
        for (unsigned k = 0; k < 8; k++)
            crc = (crc & 1u) ? (uint16_t)((crc >> 1) ^ 0xA001u) : (uint16_t)(crc >> 1);
    }
    return crc;
}

/* --- mailbox codec ------------------------------------------------------------------------- */

/* Signed values come in converted to uint32_t (two's complement, well defined). */
static void put32(uint16_t *r, uint32_t u)
{
    r[0] = (uint16_t)(u >> 16);
    r[1] = (uint16_t)(u & 0xFFFFu);
}

static int32_t get32(const uint16_t *r)
{
    uint32_t u = ((uint32_t)r[0] << 16) | r[1];
    /* two's complement without implementation-defined conversion of large values */
    return u <= 0x7FFFFFFFu ? (int32_t)u : -(int32_t)(0xFFFFFFFFu - u) - 1;
}

/* The same range checks as the wire protocol: run the message through cs_proto's encoder. */
static cs_err_t check_msg(const cs_proto_msg_t *m)
{
    uint8_t buf[CS_PROTO_LEN_MAX];
    size_t len;
    return cs_proto_encode(m, buf, sizeof buf, &len);
}

cs_err_t cs_modbus_mailbox_encode(const cs_proto_msg_t *m, uint16_t seq, uint16_t *regs, size_t cap,
                                  size_t *n)
{
    if (m == NULL || regs == NULL || n == NULL)
        return CS_ERR_ARG;
    size_t need;
    if (m->type == CS_PROTO_SEGMENT)
        need = CS_MODBUS_MAILBOX_SEGMENT_REGS;
    else if (m->type == CS_PROTO_CURVE)
        need = CS_MODBUS_MAILBOX_CURVE_REGS;
    else if (m->type == CS_PROTO_PEN)
        need = CS_MODBUS_MAILBOX_PEN_REGS;
    else
        return CS_ERR_UNSUPPORTED;
    if (cap < need)
        return CS_ERR_FULL;
    cs_err_t e = check_msg(m);
    if (e != CS_OK)
        return e;
    regs[0] = m->type;
    if (m->type == CS_PROTO_SEGMENT) {
        put32(regs + 1, m->u.segment.ticks);
        for (unsigned i = 0; i < CS_AXES; i++)
            put32(regs + 3 + 2 * i, (uint32_t)m->u.segment.steps[i]);
    } else if (m->type == CS_PROTO_PEN) {
        regs[1] = m->u.pen.pulse_us;
    } else {
        for (unsigned k = 0; k < 4; k++) {
            put32(regs + 1 + 6 * k, (uint32_t)m->u.curve.p[k].x);
            put32(regs + 3 + 6 * k, (uint32_t)m->u.curve.p[k].y);
            put32(regs + 5 + 6 * k, (uint32_t)m->u.curve.p[k].z);
        }
        put32(regs + 25, (uint32_t)m->u.curve.feed);
    }
    regs[need - 1] = seq;
    *n = need;
    return CS_OK;
}

cs_err_t cs_modbus_mailbox_decode(const uint16_t *regs, size_t n, cs_proto_msg_t *m, uint16_t *seq)
{
    if (regs == NULL || m == NULL || seq == NULL)
        return CS_ERR_ARG;
    if (n == 0)
        return CS_ERR_FRAME;
    if (regs[0] == CS_PROTO_SEGMENT) {
        if (n != CS_MODBUS_MAILBOX_SEGMENT_REGS)
            return CS_ERR_FRAME;
        m->type = CS_PROTO_SEGMENT;
        m->u.segment.ticks = ((uint32_t)regs[1] << 16) | regs[2];
        for (unsigned i = 0; i < CS_AXES; i++)
            m->u.segment.steps[i] = get32(regs + 3 + 2 * i);
    } else if (regs[0] == CS_PROTO_CURVE) {
        if (n != CS_MODBUS_MAILBOX_CURVE_REGS)
            return CS_ERR_FRAME;
        m->type = CS_PROTO_CURVE;
        for (unsigned k = 0; k < 4; k++) {
            m->u.curve.p[k].x = get32(regs + 1 + 6 * k);
            m->u.curve.p[k].y = get32(regs + 3 + 6 * k);
            m->u.curve.p[k].z = get32(regs + 5 + 6 * k);
        }
        m->u.curve.feed = get32(regs + 25);
    } else if (regs[0] == CS_PROTO_PEN) {
        if (n != CS_MODBUS_MAILBOX_PEN_REGS)
            return CS_ERR_FRAME;
        m->type = CS_PROTO_PEN;
        m->u.pen.pulse_us = regs[1];
    } else {
        return CS_ERR_UNSUPPORTED;
    }
    *seq = regs[n - 1];
    return check_msg(m);
}

/* --- the register map ---------------------------------------------------------------------- */

cs_err_t cs_modbus_map_init(cs_modbus_map_t *mp, const cs_modbus_app_t *app, uint16_t first_seq)
{
    if (mp == NULL || app == NULL || app->submit == NULL || app->command == NULL ||
        app->status == NULL) /* app->lease is optional */
        return CS_ERR_ARG;
    *mp = (cs_modbus_map_t){0};
    mp->app = *app;
    mp->next_seq = first_seq;
    return CS_OK;
}

static uint16_t rd16(const uint8_t *p)
{
    return (uint16_t)(((unsigned)p[0] << 8) | p[1]);
}

static void wr16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)(v >> 8);
    p[1] = (uint8_t)(v & 0xFFu);
}

static size_t exception(cs_modbus_map_t *mp, uint8_t fc, uint8_t code, uint8_t *rsp)
{
    mp->stats.exceptions++;
    rsp[0] = (uint8_t)(fc | 0x80u);
    rsp[1] = code;
    return 2;
}

static void input_regs(cs_modbus_map_t *mp, uint16_t *ir)
{
    cs_modbus_status_t st = {0};
    mp->app.status(mp->app.ctx, &st);
    ir[CS_MODBUS_IR_VERSION] = CS_MODBUS_MAP_VERSION;
    ir[CS_MODBUS_IR_CAPS] = st.caps;
    ir[CS_MODBUS_IR_AXES] = st.axes;
    ir[CS_MODBUS_IR_QUEUE_SIZE] = st.queue_size;
    put32(ir + CS_MODBUS_IR_TICK_HZ, st.tick_hz);
    put32(ir + CS_MODBUS_IR_BOOT_ID, st.boot_id);
    ir[CS_MODBUS_IR_STATE] = st.state;
    ir[CS_MODBUS_IR_FREE] = st.free_slots;
    ir[CS_MODBUS_IR_LAST_EXEC] = st.last_exec;
    ir[CS_MODBUS_IR_NEXT_SEQ] = mp->next_seq;
    ir[CS_MODBUS_IR_ERROR] = st.error;
    ir[CS_MODBUS_IR_ERROR_SEQ] = st.error_seq;
    ir[CS_MODBUS_IR_REFUSED] = mp->refused;
    ir[CS_MODBUS_IR_REFUSED_SEQ] = mp->refused_seq;
    for (unsigned i = 0; i < CS_AXES; i++)
        put32(ir + CS_MODBUS_IR_POS + 2 * i, (uint32_t)st.pos[i]);
    ir[CS_MODBUS_IR_LEASE] = st.lease ? 1u : 0u;
    ir[CS_MODBUS_IR_LEASE_LEFT] = st.lease ? st.lease_left_ms : 0u;
}

/* Holding register value; false when addr is not in the map. */
static bool holding(const cs_modbus_map_t *mp, uint16_t addr, uint16_t *v)
{
    if (addr == CS_MODBUS_HR_COMMAND) {
        *v = mp->last_cmd;
        return true;
    }
    if (mp->app.lease != NULL && (addr == CS_MODBUS_HR_LEASE || addr == CS_MODBUS_HR_RELEASE ||
                                  addr == CS_MODBUS_HR_TOKEN)) {
        *v = 0; /* the token is never shown: input register LEASE says whether one is held */
        return true;
    }
    if (addr >= CS_MODBUS_HR_MAILBOX && addr < CS_MODBUS_HR_MAILBOX + CS_MODBUS_MAILBOX_REGS) {
        unsigned k = (unsigned)(addr - CS_MODBUS_HR_MAILBOX);
        *v = k < mp->last_n ? mp->last[k] : 0;
        return true;
    }
    return false;
}

static uint8_t refuse(cs_modbus_map_t *mp, cs_err_t why, uint16_t seq, uint8_t ex)
{
    mp->refused = (uint16_t)why;
    mp->refused_seq = seq;
    mp->stats.refused++;
    return ex;
}

/* The mailbox rule (docs/modbus.md, "The writer lease" then "Sequence numbers"): returns 0
 * (accepted or a repeat of the last accepted write) or the exception code. token: the writer's
 * (0: the write carried none). The lease comes first: a write from another client is refused
 * whatever its sequence, so it can neither queue a message nor take the holder's number. */
static uint8_t mailbox_write(cs_modbus_map_t *mp, uint16_t token, const uint16_t *regs, size_t n)
{
    cs_proto_msg_t m;
    uint16_t seq = n > 0 ? regs[n - 1] : 0;
    if (mp->app.lease != NULL) {
        cs_err_t le = mp->app.lease(mp->app.ctx, CS_MODBUS_LEASE_WRITE, token);
        if (le != CS_OK)
            return refuse(mp, le, seq, CS_MODBUS_EX_ILLEGAL_FUNCTION);
    }
    if (seq == (uint16_t)(mp->next_seq - 1u) && mp->last_n != 0) {
        /* the retry of a write whose answer was lost: same registers = the same message,
         * already queued: answer OK, do not queue it again */
        bool same = n == mp->last_n;
        for (size_t k = 0; same && k < n; k++)
            same = regs[k] == mp->last[k];
        if (same) {
            mp->stats.repeats++;
            return 0;
        }
        return refuse(mp, CS_ERR_SEQ, seq, CS_MODBUS_EX_ILLEGAL_VALUE);
    }
    if (seq != mp->next_seq) /* a gap (a write was lost) or a stale sequence */
        return refuse(mp, CS_ERR_SEQ, seq, CS_MODBUS_EX_ILLEGAL_VALUE);
    cs_err_t e = cs_modbus_mailbox_decode(regs, n, &m, &seq);
    if (e != CS_OK)
        return refuse(mp, e, seq, CS_MODBUS_EX_ILLEGAL_VALUE);
    e = mp->app.submit(mp->app.ctx, &m, seq);
    if (e == CS_ERR_FULL)
        return refuse(mp, e, seq, CS_MODBUS_EX_DEVICE_BUSY);
    if (e != CS_OK)
        return refuse(mp, e, seq, CS_MODBUS_EX_DEVICE_FAILURE);
    for (size_t k = 0; k < n; k++)
        mp->last[k] = regs[k];
    mp->last_n = (uint8_t)n;
    mp->next_seq++;
    mp->stats.accepted++;
    return 0;
}

/* A write to LEASE (claim or renew) or RELEASE: 0 or the exception code. */
static uint8_t lease_op(cs_modbus_map_t *mp, uint8_t op, uint16_t token)
{
    if (mp->app.lease == NULL)
        return CS_MODBUS_EX_ILLEGAL_ADDRESS; /* a map without a lease */
    if (token == 0)
        return CS_MODBUS_EX_ILLEGAL_VALUE;
    cs_err_t e = mp->app.lease(mp->app.ctx, op, token);
    return e == CS_OK ? 0 : refuse(mp, e, 0, CS_MODBUS_EX_ILLEGAL_FUNCTION);
}

/* A one-register write (FC06, or FC16 of one register): COMMAND, LEASE or RELEASE. */
static uint8_t write_one(cs_modbus_map_t *mp, uint16_t addr, uint16_t val);

static uint8_t command(cs_modbus_map_t *mp, uint16_t cmd)
{
    if (cmd < CS_MODBUS_CMD_HOLD || cmd > CS_MODBUS_CMD_RESET)
        return CS_MODBUS_EX_ILLEGAL_VALUE;
    if (cmd == CS_MODBUS_CMD_RESET) {
        mp->refused = 0;
        mp->refused_seq = 0;
    }
    mp->app.command(mp->app.ctx, cmd);
    mp->last_cmd = cmd;
    return 0;
}

static uint8_t write_one(cs_modbus_map_t *mp, uint16_t addr, uint16_t val)
{
    if (addr == CS_MODBUS_HR_COMMAND)
        return command(mp, val);
    if (addr == CS_MODBUS_HR_LEASE)
        return lease_op(mp, CS_MODBUS_LEASE_CLAIM, val);
    if (addr == CS_MODBUS_HR_RELEASE)
        return lease_op(mp, CS_MODBUS_LEASE_RELEASE, val);
    /* a one-register mailbox write cannot carry a message: outside the writable map */
    return CS_MODBUS_EX_ILLEGAL_ADDRESS;
}

/* FC03 / FC04 (spec 6.3, 6.4): the values go straight into the answer (no second buffer:
 * small stacks). Returns the answer's length or 0 with *ex set. */
static size_t read_regs(cs_modbus_map_t *mp, const uint8_t *req, size_t n, uint8_t *rsp,
                        uint8_t *ex)
{
    uint8_t fc = req[0];
    uint16_t addr = n == 5 ? rd16(req + 1) : 0, qty = n == 5 ? rd16(req + 3) : 0;
    if (n != 5 || qty < 1 || qty > 125) { /* spec 6.3 / 6.4: exception 03 */
        *ex = CS_MODBUS_EX_ILLEGAL_VALUE;
        return 0;
    }
    bool ok;
    if (fc == CS_MODBUS_FC_READ_INPUT) {
        uint16_t ir[CS_MODBUS_IR_COUNT];
        ok = (uint32_t)addr + qty <= CS_MODBUS_IR_COUNT;
        if (ok) {
            input_regs(mp, ir);
            for (unsigned k = 0; k < qty; k++)
                wr16(rsp + 2 + 2 * k, ir[addr + k]);
        }
    } else {
        ok = true;
        for (unsigned k = 0; ok && k < qty; k++) {
            uint16_t v = 0;
            ok = (uint32_t)addr + k <= 0xFFFFu && holding(mp, (uint16_t)(addr + k), &v);
            wr16(rsp + 2 + 2 * k, v);
        }
    }
    if (!ok) {
        *ex = CS_MODBUS_EX_ILLEGAL_ADDRESS;
        return 0;
    }
    rsp[0] = fc;
    rsp[1] = (uint8_t)(2 * qty);
    return 2 + 2 * (size_t)qty;
}

/* FC16 (spec 6.12): one register to COMMAND, LEASE or RELEASE; a message to the mailbox, from
 * 0x0100 (no token) or from 0x00FF (the writer's token first). 0 or the exception code. */
static uint8_t write_multi(cs_modbus_map_t *mp, const uint8_t *req, size_t n)
{
    if (n < 6)
        return CS_MODBUS_EX_ILLEGAL_VALUE;
    uint16_t addr = rd16(req + 1), qty = rd16(req + 3);
    uint8_t bytes = req[5];
    if (qty < 1 || qty > 123 || bytes != 2 * qty || n != 6 + (size_t)bytes)
        return CS_MODBUS_EX_ILLEGAL_VALUE;
    uint16_t regs[1 + CS_MODBUS_MAILBOX_REGS];
    for (unsigned k = 0; k < qty && k < 1 + CS_MODBUS_MAILBOX_REGS; k++)
        regs[k] = rd16(req + 6 + 2 * k);
    if (qty == 1 && addr != CS_MODBUS_HR_MAILBOX && addr != CS_MODBUS_HR_TOKEN)
        return write_one(mp, addr, regs[0]);
    if (addr == CS_MODBUS_HR_MAILBOX && qty <= CS_MODBUS_MAILBOX_REGS)
        return mailbox_write(mp, 0, regs, qty);
    if (addr == CS_MODBUS_HR_TOKEN && mp->app.lease != NULL && qty >= 2 &&
        qty <= 1 + CS_MODBUS_MAILBOX_REGS)
        return mailbox_write(mp, regs[0], regs + 1, (size_t)qty - 1u);
    return CS_MODBUS_EX_ILLEGAL_ADDRESS;
}

cs_err_t cs_modbus_pdu(cs_modbus_map_t *mp, const uint8_t *req, size_t n, uint8_t *rsp, size_t cap,
                       size_t *rn)
{
    if (mp == NULL || req == NULL || rsp == NULL || rn == NULL || cap < CS_MODBUS_PDU_MAX)
        return CS_ERR_ARG;
    mp->stats.requests++;
    uint8_t fc = n > 0 ? req[0] : 0;
    uint8_t ex = CS_MODBUS_EX_ILLEGAL_FUNCTION;
    if (n == 0 || n > CS_MODBUS_PDU_MAX) {
        /* no function code to answer to (or more than a PDU holds): exception 1 */
    } else if (fc == CS_MODBUS_FC_READ_HOLDING || fc == CS_MODBUS_FC_READ_INPUT) {
        *rn = read_regs(mp, req, n, rsp, &ex);
        if (*rn > 0)
            return CS_OK;
    } else if (fc == CS_MODBUS_FC_WRITE_SINGLE || fc == CS_MODBUS_FC_WRITE_MULTI) {
        if (fc == CS_MODBUS_FC_WRITE_SINGLE)
            ex = n != 5 ? CS_MODBUS_EX_ILLEGAL_VALUE : write_one(mp, rd16(req + 1), rd16(req + 3));
        else
            ex = write_multi(mp, req, n);
        if (ex == 0) {
            /* FC06 echoes the request; FC16 answers function, address, quantity */
            for (unsigned k = 0; k < 5; k++)
                rsp[k] = req[k];
            *rn = 5;
            return CS_OK;
        }
    }
    /* an unknown function code: fc | 0x80 with exception 1 (spec 7), as for every exception */
    *rn = exception(mp, fc, ex, rsp);
    return CS_OK;
}

/* --- Modbus TCP ----------------------------------------------------------------------------- */

cs_err_t cs_modbus_mbap_parse(const uint8_t *b, size_t n, cs_modbus_mbap_t *h)
{
    if (b == NULL || h == NULL)
        return CS_ERR_ARG;
    if (n < CS_MODBUS_MBAP_LEN)
        return CS_ERR_EMPTY;
    uint16_t len = rd16(b + 4); /* unit id + PDU */
    if (len < 2 || len > 1 + CS_MODBUS_PDU_MAX)
        return CS_ERR_FRAME;
    h->tid = rd16(b);
    h->proto = rd16(b + 2);
    h->unit = b[6];
    h->pdu_len = (size_t)len - 1u;
    if (n < CS_MODBUS_MBAP_LEN + h->pdu_len)
        return CS_ERR_EMPTY;
    return h->proto == 0 ? CS_OK : CS_ERR_UNSUPPORTED;
}

cs_err_t cs_modbus_mbap_frame(const cs_modbus_mbap_t *h, const uint8_t *pdu, size_t n, uint8_t *out,
                              size_t cap, size_t *len)
{
    if (h == NULL || pdu == NULL || out == NULL || len == NULL)
        return CS_ERR_ARG;
    if (n == 0 || n > CS_MODBUS_PDU_MAX || CS_MODBUS_MBAP_LEN + n > cap)
        return CS_ERR_FULL;
    wr16(out, h->tid);
    wr16(out + 2, 0);
    wr16(out + 4, (uint16_t)(n + 1u));
    out[6] = h->unit;
    for (size_t k = 0; k < n; k++)
        out[CS_MODBUS_MBAP_LEN + k] = pdu[k];
    *len = CS_MODBUS_MBAP_LEN + n;
    return CS_OK;
}

/* --- RTU ------------------------------------------------------------------------------------ */

cs_err_t cs_modbus_rtu_init(cs_modbus_rtu_t *r, cs_modbus_map_t *map, uint8_t unit, uint32_t baud)
{
    if (r == NULL || map == NULL || unit < 1 || unit > 247 || baud == 0)
        return CS_ERR_ARG;
    *r = (cs_modbus_rtu_t){0};
    r->map = map;
    r->unit = unit;
    /* 3.5 characters of 11 bits (start, 8 data, parity or second stop, stop); the spec fixes
     * 1750 us above 19200 baud, where the timer would be too short to keep */
    r->gap_us = baud > 19200u ? 1750u : (uint32_t)((38500000ull + baud - 1u) / baud);
    return CS_OK;
}

cs_err_t cs_modbus_rtu_frame(uint8_t unit, const uint8_t *pdu, size_t n, uint8_t *out, size_t cap,
                             size_t *len)
{
    if (pdu == NULL || out == NULL || len == NULL)
        return CS_ERR_ARG;
    if (n + 3 > cap || n > CS_MODBUS_PDU_MAX)
        return CS_ERR_FULL;
    out[0] = unit;
    for (size_t k = 0; k < n; k++)
        out[1 + k] = pdu[k];
    uint16_t crc = cs_modbus_crc(CS_MODBUS_CRC_INIT, out, n + 1);
    out[n + 1] = (uint8_t)(crc & 0xFFu);
    out[n + 2] = (uint8_t)(crc >> 8);
    *len = n + 3;
    return CS_OK;
}

/* Length of the request frame in r->in once enough of it arrived: 0 = not known yet (or not a
 * request format this server knows: the frame then ends at t3.5). */
static size_t request_len(const cs_modbus_rtu_t *r)
{
    if (r->n < 2)
        return 0;
    switch (r->in[1]) {
    case CS_MODBUS_FC_READ_HOLDING:
    case CS_MODBUS_FC_READ_INPUT:
    case CS_MODBUS_FC_WRITE_SINGLE:
        return 8; /* unit, fc, address, quantity or value, CRC */
    case CS_MODBUS_FC_WRITE_MULTI:
        return r->n >= 7 ? 9u + r->in[6] : 0; /* + byte count, data */
    default:
        return 0;
    }
}

/* A whole frame is in r->in[0..n): check, handle, answer. */
static cs_err_t handle_frame(cs_modbus_rtu_t *r, const uint8_t **reply, size_t *len)
{
    size_t n = r->n;
    r->n = 0;
    if (n < 4 || cs_modbus_crc(CS_MODBUS_CRC_INIT, r->in, n) != 0) {
        /* a frame followed by its CRC (low byte first) has a CRC register of 0 */
        r->stats.crc_errs++;
        return CS_ERR_EMPTY;
    }
    uint8_t unit = r->in[0];
    if (unit != r->unit && unit != 0) {
        r->stats.other_unit++;
        return CS_ERR_EMPTY;
    }
    /* the answer's PDU is built in place, after the unit byte (no second buffer) */
    size_t pn;
    if (cs_modbus_pdu(r->map, r->in + 1, n - 3, r->out + 1, sizeof r->out - 1, &pn) != CS_OK)
        return CS_ERR_EMPTY;
    if (unit == 0) { /* broadcast: writes act, nobody answers (serial line spec 2.1) */
        r->stats.broadcasts++;
        return CS_ERR_EMPTY;
    }
    r->out[0] = r->unit;
    uint16_t crc = cs_modbus_crc(CS_MODBUS_CRC_INIT, r->out, pn + 1);
    r->out[pn + 1] = (uint8_t)(crc & 0xFFu);
    r->out[pn + 2] = (uint8_t)(crc >> 8);
    *len = pn + 3;
    r->stats.frames++;
    *reply = r->out;
    return CS_OK;
}

cs_err_t cs_modbus_rtu_idle(cs_modbus_rtu_t *r, uint32_t now_us, const uint8_t **reply, size_t *len)
{
    if (r == NULL || reply == NULL || len == NULL)
        return CS_ERR_ARG;
    if ((r->n == 0 && !r->overrun) || (uint32_t)(now_us - r->last_us) < r->gap_us)
        return CS_ERR_EMPTY;
    if (r->overrun) {
        r->overrun = false;
        r->n = 0;
        return CS_ERR_EMPTY;
    }
    return handle_frame(r, reply, len);
}

cs_err_t cs_modbus_rtu_feed(cs_modbus_rtu_t *r, uint8_t byte, uint32_t now_us,
                            const uint8_t **reply, size_t *len)
{
    if (r == NULL || reply == NULL || len == NULL)
        return CS_ERR_ARG;
    /* silence since the last byte: whatever came before was a frame of its own */
    cs_err_t e = CS_ERR_EMPTY;
    if (r->n > 0 || r->overrun)
        e = cs_modbus_rtu_idle(r, now_us, reply, len);
    r->last_us = now_us;
    if (e == CS_OK) {
        /* a reply is due for the previous frame; this byte starts the next one */
        r->in[0] = byte;
        r->n = 1;
        return CS_OK;
    }
    if (r->overrun)
        return CS_ERR_EMPTY;
    if (r->n >= sizeof r->in) {
        r->overrun = true;
        r->stats.overruns++;
        r->n = 0;
        return CS_ERR_EMPTY;
    }
    r->in[r->n++] = byte;
    size_t want = request_len(r);
    if (want == 0 || r->n < want)
        return CS_ERR_EMPTY;
    if (want > sizeof r->in) {
        r->overrun = true;
        r->stats.overruns++;
        r->n = 0;
        return CS_ERR_EMPTY;
    }
    if (cs_modbus_crc(CS_MODBUS_CRC_INIT, r->in, r->n) != 0)
        return CS_ERR_EMPTY; /* not a frame of that length after all: wait for the silence */
    return handle_frame(r, reply, len);
}
