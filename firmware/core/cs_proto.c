/* cs_proto: message <-> bytes. Little-endian, fixed offsets (docs/protocol.md gives every byte).
 * Encode and decode apply the same range checks, so whatever one side can send the other
 * accepts, and a decoded message is always one the encoder could have produced. */
#include "cs_proto.h"

#include "cs_frame.h"

CS_STATIC_ASSERT(CS_PROTO_AXES_MAX == CS_AXES, proto_axes_match_machine);
CS_STATIC_ASSERT(CS_PROTO_LEN_STATUS(CS_PROTO_AXES_MAX) <= CS_PROTO_LEN_MAX, status_fits);
CS_STATIC_ASSERT(CS_PROTO_LEN_SEGMENT <= CS_PROTO_LEN_MAX, segment_fits);
CS_STATIC_ASSERT(CS_PROTO_LEN_SETPOS <= CS_PROTO_LEN_MAX, setpos_fits);
/* The link must at least carry its own control messages, a three-axis status and segments in
 * every build (a 4-axis STATUS needs 44 bytes: cs_fw_app_init refuses a machine whose STATUS the
 * build's frames cannot carry); a build whose CS_FRAME_PAYLOAD_MAX is below CS_PROTO_LEN_CURVE
 * cannot carry curves (the link then refuses them with CS_ERR_ARG). */
CS_STATIC_ASSERT(CS_FRAME_PAYLOAD_MAX >= CS_PROTO_LEN_STATUS(3), frame_fits_status);
CS_STATIC_ASSERT(CS_FRAME_PAYLOAD_MAX >= CS_PROTO_LEN_SEGMENT, frame_fits_seg);
CS_STATIC_ASSERT(CS_FRAME_PAYLOAD_MAX >= CS_PROTO_LEN_ACK, frame_fits_ack);

/* --- little-endian field access --------------------------------------------------------- */
static void put16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)(v & 0xFFu);
    p[1] = (uint8_t)(v >> 8);
}

static void put32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v & 0xFFu);
    p[1] = (uint8_t)((v >> 8) & 0xFFu);
    p[2] = (uint8_t)((v >> 16) & 0xFFu);
    p[3] = (uint8_t)(v >> 24);
}

static uint16_t get16(const uint8_t *p)
{
    return (uint16_t)(p[0] | (unsigned)p[1] << 8);
}

static uint32_t get32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* int32 travels as its two's complement bit pattern (int -> unsigned is modular in C99); back by
 * arithmetic, not by a cast of an out-of-range value, which C99 leaves implementation-defined. */
static void puti32(uint8_t *p, int32_t v)
{
    put32(p, (uint32_t)v);
}

static int32_t geti32(const uint8_t *p)
{
    uint32_t u = get32(p);
    if (u <= (uint32_t)INT32_MAX)
        return (int32_t)u;
    return (int32_t)(u - (uint32_t)INT32_MAX - 1u) + INT32_MIN;
}

/* --- field checks shared by encode and decode --------------------------------------------- */
static bool axes_ok(uint8_t n)
{
    return n >= 1 && n <= CS_PROTO_AXES_MAX;
}

static bool speed_ok(int32_t v)
{
    return v > 0;
}

/* The machine-control messages (docs/protocol.md, "Machine control"). */
static cs_err_t check_ctl(const cs_proto_msg_t *m)
{
    switch (m->type) {
    case CS_PROTO_EVENT: {
        const cs_proto_event_t *e = &m->u.event;
        bool ok = e->kind >= CS_PROTO_EVENT_ALARM && e->kind < CS_PROTO_EVENT_COUNT_ &&
                  !(e->inputs & (uint16_t)~CS_PROTO_IN_ALL) && axes_ok(e->axes);
        return ok ? CS_OK : CS_ERR_RANGE;
    }
    case CS_PROTO_HOME: {
        const cs_proto_home_t *h = &m->u.home;
        bool ok = h->axis < CS_PROTO_AXES_MAX && !(h->flags & (uint8_t)~CS_PROTO_HOME_MAX) &&
                  speed_ok(h->seek) && speed_ok(h->latch) && h->pulloff >= 0 &&
                  h->pulloff <= CS_POS_LIMIT && h->search > 0 && h->search <= CS_POS_LIMIT &&
                  cs_fixed_pos_ok(h->home_pos);
        return ok ? CS_OK : CS_ERR_RANGE;
    }
    case CS_PROTO_JOG:
        return cs_fixed_vec_ok(&m->u.jog.target) && speed_ok(m->u.jog.feed) ? CS_OK : CS_ERR_RANGE;
    case CS_PROTO_PROBE:
        return cs_fixed_vec_ok(&m->u.probe.target) && speed_ok(m->u.probe.feed) &&
                       !(m->u.probe.flags &
                         (uint8_t) ~(CS_PROTO_PROBE_AWAY | CS_PROTO_PROBE_NO_ERROR))
                   ? CS_OK
                   : CS_ERR_RANGE;
    case CS_PROTO_SPINDLE: {
        const cs_proto_spindle_t *p = &m->u.spindle;
        bool ok = p->mode < CS_PROTO_SPINDLE_MODE_COUNT_ &&
                  !(p->flags & (uint8_t)~CS_PROTO_SPINDLE_LASER) &&
                  p->power <= CS_PROTO_SPINDLE_FULL && p->feed >= 0;
        return ok ? CS_OK : CS_ERR_RANGE;
    }
    case CS_PROTO_OVERRIDE: {
        const cs_proto_override_t *o = &m->u.override;
        bool ok = o->feed >= 1 && o->feed <= CS_PROTO_OVERRIDE_MAX && o->rapid >= 1 &&
                  o->rapid <= CS_PROTO_OVERRIDE_MAX && o->spindle >= 1 &&
                  o->spindle <= CS_PROTO_OVERRIDE_MAX;
        return ok ? CS_OK : CS_ERR_RANGE;
    }
    case CS_PROTO_JOG_CANCEL:
    case CS_PROTO_UNLOCK:
        return CS_OK;
    default:
        return CS_ERR_UNSUPPORTED;
    }
}

static cs_err_t check(const cs_proto_msg_t *m)
{
    switch (m->type) {
    case CS_PROTO_ACK:
        return (m->u.ack.flags & (uint8_t)~CS_PROTO_ACK_NAK) ? CS_ERR_RANGE : CS_OK;
    case CS_PROTO_HELLO: {
        const cs_proto_hello_t *h = &m->u.hello;
        if (h->version == 0 || !axes_ok(h->axes) || h->queue_size == 0 || h->tick_hz == 0 ||
            (h->caps & (uint16_t)~CS_PROTO_CAP_ALL))
            return CS_ERR_RANGE;
        return CS_OK;
    }
    case CS_PROTO_STATUS:
        return (m->u.status.state >= CS_PROTO_STATE_COUNT_ || !axes_ok(m->u.status.axes) ||
                (m->u.status.flags & (uint8_t)~CS_PROTO_STATUS_ALL))
                   ? CS_ERR_RANGE
                   : CS_OK;
    case CS_PROTO_SETPOS:
        return (m->u.setpos.flags & (uint8_t)~CS_PROTO_SETPOS_POS) ? CS_ERR_RANGE : CS_OK;
    case CS_PROTO_ERROR:
        return (m->u.error.code < CS_ERR_ARG || m->u.error.code >= CS_ERR_COUNT_) ? CS_ERR_RANGE
                                                                                  : CS_OK;
    case CS_PROTO_SEGMENT: {
        const cs_segment_t *g = &m->u.segment;
        if (g->ticks == 0 || g->ticks > CS_PROTO_SEGMENT_MAX_TICKS)
            return CS_ERR_RANGE;
        for (unsigned i = 0; i < CS_AXES; i++) {
            /* |steps| <= ticks, computed in int64 so INT32_MIN has a magnitude. */
            int64_t s = g->steps[i];
            if ((s < 0 ? -s : s) > (int64_t)g->ticks)
                return CS_ERR_RANGE;
        }
        return CS_OK;
    }
    case CS_PROTO_CURVE:
        for (unsigned i = 0; i < 4; i++)
            if (!cs_fixed_vec_ok(&m->u.curve.p[i]))
                return CS_ERR_RANGE;
        return m->u.curve.feed > 0 ? CS_OK : CS_ERR_RANGE;
    case CS_PROTO_PEN:
        return (m->u.pen.pulse_us < CS_PROTO_PEN_MIN_US || m->u.pen.pulse_us > CS_PROTO_PEN_MAX_US)
                   ? CS_ERR_RANGE
                   : CS_OK;
    case CS_PROTO_PING:
    case CS_PROTO_HOLD:
    case CS_PROTO_RESUME:
    case CS_PROTO_ABORT:
    case CS_PROTO_QUERY:
        return CS_OK;
    default:
        return check_ctl(m);
    }
}

/* Payload length of a message of this type (axes from the message), 0 for an unknown type. */
static size_t msg_len(uint8_t type, uint8_t axes)
{
    switch (type) {
    case CS_PROTO_ACK:
        return CS_PROTO_LEN_ACK;
    case CS_PROTO_PING:
        return CS_PROTO_LEN_PING;
    case CS_PROTO_HELLO:
        return CS_PROTO_LEN_HELLO;
    case CS_PROTO_STATUS:
        return (size_t)CS_PROTO_LEN_STATUS(axes);
    case CS_PROTO_ERROR:
        return CS_PROTO_LEN_ERROR;
    case CS_PROTO_SEGMENT:
        return CS_PROTO_LEN_SEGMENT;
    case CS_PROTO_CURVE:
        return CS_PROTO_LEN_CURVE;
    case CS_PROTO_PEN:
        return CS_PROTO_LEN_PEN;
    case CS_PROTO_SETPOS:
        return CS_PROTO_LEN_SETPOS;
    case CS_PROTO_HOLD:
    case CS_PROTO_RESUME:
    case CS_PROTO_ABORT:
    case CS_PROTO_QUERY:
    case CS_PROTO_JOG_CANCEL:
    case CS_PROTO_UNLOCK:
        return CS_PROTO_LEN_CONTROL;
    case CS_PROTO_EVENT:
        return (size_t)CS_PROTO_LEN_EVENT(axes);
    case CS_PROTO_HOME:
        return CS_PROTO_LEN_HOME;
    case CS_PROTO_JOG:
        return CS_PROTO_LEN_JOG;
    case CS_PROTO_PROBE:
        return CS_PROTO_LEN_PROBE;
    case CS_PROTO_SPINDLE:
        return CS_PROTO_LEN_SPINDLE;
    case CS_PROTO_OVERRIDE:
        return CS_PROTO_LEN_OVERRIDE;
    default:
        return 0;
    }
}

bool cs_proto_sequenced(uint8_t type)
{
    return type != CS_PROTO_ACK && type != CS_PROTO_PING;
}

bool cs_proto_uses_slot(uint8_t type)
{
    switch (type) {
    case CS_PROTO_SEGMENT:
    case CS_PROTO_CURVE:
    case CS_PROTO_PEN:
    case CS_PROTO_HOME:
    case CS_PROTO_JOG:
    case CS_PROTO_PROBE:
    case CS_PROTO_SPINDLE:
        return true;
    default:
        return false;
    }
}

bool cs_proto_state_busy(uint8_t state)
{
    return state == CS_PROTO_STATE_RUNNING || state == CS_PROTO_STATE_HOMING ||
           state == CS_PROTO_STATE_JOG;
}

static void put_vec(uint8_t *p, const cs_vec3_t *v)
{
    puti32(p, v->x);
    puti32(p + 4, v->y);
    puti32(p + 8, v->z);
}

static void get_vec(const uint8_t *p, cs_vec3_t *v)
{
    v->x = geti32(p);
    v->y = geti32(p + 4);
    v->z = geti32(p + 8);
}

/* The machine-control messages' bytes (docs/protocol.md); the type byte is written already. */
static void encode_ctl(const cs_proto_msg_t *m, uint8_t *buf)
{
    switch (m->type) {
    case CS_PROTO_EVENT:
        buf[1] = m->u.event.kind;
        buf[2] = m->u.event.code;
        put16(buf + 3, m->u.event.inputs);
        buf[5] = m->u.event.axes;
        for (unsigned i = 0; i < m->u.event.axes; i++)
            puti32(buf + 6 + 4 * i, m->u.event.pos[i]);
        break;
    case CS_PROTO_HOME:
        buf[1] = m->u.home.axis;
        buf[2] = m->u.home.flags;
        puti32(buf + 3, m->u.home.seek);
        puti32(buf + 7, m->u.home.latch);
        puti32(buf + 11, m->u.home.pulloff);
        puti32(buf + 15, m->u.home.search);
        puti32(buf + 19, m->u.home.home_pos);
        break;
    case CS_PROTO_JOG:
        put_vec(buf + 1, &m->u.jog.target);
        puti32(buf + 13, m->u.jog.feed);
        break;
    case CS_PROTO_PROBE:
        put_vec(buf + 1, &m->u.probe.target);
        puti32(buf + 13, m->u.probe.feed);
        buf[17] = m->u.probe.flags;
        break;
    case CS_PROTO_SPINDLE:
        buf[1] = m->u.spindle.mode;
        buf[2] = m->u.spindle.flags;
        put16(buf + 3, m->u.spindle.power);
        puti32(buf + 5, m->u.spindle.feed);
        break;
    case CS_PROTO_OVERRIDE:
        put16(buf + 1, m->u.override.feed);
        put16(buf + 3, m->u.override.rapid);
        put16(buf + 5, m->u.override.spindle);
        break;
    default: /* JOG_CANCEL, UNLOCK: the type byte is the whole message */
        break;
    }
}

static void decode_ctl(const uint8_t *buf, cs_proto_msg_t *m)
{
    switch (m->type) {
    case CS_PROTO_EVENT:
        m->u.event.kind = buf[1];
        m->u.event.code = buf[2];
        m->u.event.inputs = get16(buf + 3);
        m->u.event.axes = buf[5];
        for (unsigned i = 0; i < m->u.event.axes; i++)
            m->u.event.pos[i] = geti32(buf + 6 + 4 * i);
        break;
    case CS_PROTO_HOME:
        m->u.home.axis = buf[1];
        m->u.home.flags = buf[2];
        m->u.home.seek = geti32(buf + 3);
        m->u.home.latch = geti32(buf + 7);
        m->u.home.pulloff = geti32(buf + 11);
        m->u.home.search = geti32(buf + 15);
        m->u.home.home_pos = geti32(buf + 19);
        break;
    case CS_PROTO_JOG:
        get_vec(buf + 1, &m->u.jog.target);
        m->u.jog.feed = geti32(buf + 13);
        break;
    case CS_PROTO_PROBE:
        get_vec(buf + 1, &m->u.probe.target);
        m->u.probe.feed = geti32(buf + 13);
        m->u.probe.flags = buf[17];
        break;
    case CS_PROTO_SPINDLE:
        m->u.spindle.mode = buf[1];
        m->u.spindle.flags = buf[2];
        m->u.spindle.power = get16(buf + 3);
        m->u.spindle.feed = geti32(buf + 5);
        break;
    case CS_PROTO_OVERRIDE:
        m->u.override.feed = get16(buf + 1);
        m->u.override.rapid = get16(buf + 3);
        m->u.override.spindle = get16(buf + 5);
        break;
    default:
        break;
    }
}

cs_err_t cs_proto_encode(const cs_proto_msg_t *m, uint8_t *buf, size_t cap, size_t *len)
{
    if (m == NULL || buf == NULL || len == NULL)
        return CS_ERR_ARG;
    cs_err_t e = check(m);
    if (e != CS_OK)
        return e;
    uint8_t axes = m->type == CS_PROTO_STATUS  ? m->u.status.axes
                   : m->type == CS_PROTO_EVENT ? m->u.event.axes
                                               : 0;
    size_t n = msg_len(m->type, axes);
    bool tick = m->type == CS_PROTO_STATUS && (m->u.status.flags & CS_PROTO_STATUS_TICK);
    if (m->type == CS_PROTO_STATUS && !tick)
        n = (size_t)CS_PROTO_LEN_STATUS2(axes);
    if (cap < n)
        return CS_ERR_FULL;
    buf[0] = m->type;
    switch (m->type) {
    case CS_PROTO_ACK:
        buf[1] = m->u.ack.flags;
        put16(buf + 2, m->u.ack.next_expected);
        put16(buf + 4, m->u.ack.credits);
        put32(buf + 6, m->u.ack.boot_id);
        put32(buf + 10, m->u.ack.echo);
        break;
    case CS_PROTO_PING:
        put32(buf + 1, m->u.ping.nonce);
        break;
    case CS_PROTO_HELLO:
        buf[1] = m->u.hello.version;
        put32(buf + 2, m->u.hello.boot_id);
        buf[6] = m->u.hello.axes;
        put16(buf + 7, m->u.hello.queue_size);
        put32(buf + 9, m->u.hello.tick_hz);
        put16(buf + 13, m->u.hello.caps);
        break;
    case CS_PROTO_STATUS:
        buf[1] = m->u.status.state;
        put32(buf + 2, m->u.status.boot_id);
        put16(buf + 6, m->u.status.queue_fill);
        put16(buf + 8, m->u.status.last_seq);
        buf[10] = axes;
        for (unsigned i = 0; i < axes; i++)
            puti32(buf + 11 + 4 * i, m->u.status.pos[i]);
        buf[11 + 4 * axes] = m->u.status.flags;
        put32(buf + 12 + 4 * axes, m->u.status.job_id);
        put32(buf + 16 + 4 * axes, m->u.status.done);
        put32(buf + 20 + 4 * axes, m->u.status.recv);
        if (tick)
            put32(buf + 24 + 4 * axes, m->u.status.tick);
        break;
    case CS_PROTO_SETPOS:
        buf[1] = m->u.setpos.flags;
        put32(buf + 2, m->u.setpos.job_id);
        put32(buf + 6, m->u.setpos.base);
        for (unsigned i = 0; i < CS_AXES; i++)
            puti32(buf + 10 + 4 * i, m->u.setpos.pos[i]);
        break;
    case CS_PROTO_ERROR:
        buf[1] = m->u.error.code;
        put16(buf + 2, m->u.error.seq);
        break;
    case CS_PROTO_SEGMENT:
        put32(buf + 1, m->u.segment.ticks);
        for (unsigned i = 0; i < CS_AXES; i++)
            puti32(buf + 5 + 4 * i, m->u.segment.steps[i]);
        break;
    case CS_PROTO_CURVE:
        for (unsigned i = 0; i < 4; i++) {
            puti32(buf + 1 + 12 * i, m->u.curve.p[i].x);
            puti32(buf + 5 + 12 * i, m->u.curve.p[i].y);
            puti32(buf + 9 + 12 * i, m->u.curve.p[i].z);
        }
        puti32(buf + 49, m->u.curve.feed);
        break;
    case CS_PROTO_PEN:
        put16(buf + 1, m->u.pen.pulse_us);
        break;
    default: /* HOLD, RESUME, ABORT, QUERY: the type byte is the whole message; the rest */
        encode_ctl(m, buf);
        break;
    }
    *len = n;
    return CS_OK;
}

cs_err_t cs_proto_decode(const uint8_t *buf, size_t len, cs_proto_msg_t *m)
{
    if (buf == NULL || m == NULL)
        return CS_ERR_ARG;
    if (len == 0)
        return CS_ERR_FRAME;
    uint8_t type = buf[0];
    uint8_t axes = 0;
    if (type == CS_PROTO_STATUS || type == CS_PROTO_EVENT) {
        size_t at = type == CS_PROTO_STATUS ? 10u : 5u; /* the axes byte */
        if (len <= at)
            return CS_ERR_FRAME;
        axes = buf[at];
        if (!axes_ok(axes))
            return CS_ERR_RANGE;
    }
    size_t n = msg_len(type, axes);
    if (n == 0)
        return CS_ERR_UNSUPPORTED;
    /* a protocol 2 STATUS: no tick, and its flags must say so (checked below) */
    bool short_status = type == CS_PROTO_STATUS && len == (size_t)CS_PROTO_LEN_STATUS2(axes);
    if (len != n && !short_status)
        return CS_ERR_FRAME;
    *m = (cs_proto_msg_t){0};
    m->type = type;
    switch (type) {
    case CS_PROTO_ACK:
        m->u.ack.flags = buf[1];
        m->u.ack.next_expected = get16(buf + 2);
        m->u.ack.credits = get16(buf + 4);
        m->u.ack.boot_id = get32(buf + 6);
        m->u.ack.echo = get32(buf + 10);
        break;
    case CS_PROTO_PING:
        m->u.ping.nonce = get32(buf + 1);
        break;
    case CS_PROTO_HELLO:
        m->u.hello.version = buf[1];
        m->u.hello.boot_id = get32(buf + 2);
        m->u.hello.axes = buf[6];
        m->u.hello.queue_size = get16(buf + 7);
        m->u.hello.tick_hz = get32(buf + 9);
        m->u.hello.caps = get16(buf + 13);
        break;
    case CS_PROTO_STATUS:
        m->u.status.state = buf[1];
        m->u.status.boot_id = get32(buf + 2);
        m->u.status.queue_fill = get16(buf + 6);
        m->u.status.last_seq = get16(buf + 8);
        m->u.status.axes = axes;
        for (unsigned i = 0; i < axes; i++)
            m->u.status.pos[i] = geti32(buf + 11 + 4 * i);
        m->u.status.flags = buf[11 + 4 * axes];
        m->u.status.job_id = get32(buf + 12 + 4 * axes);
        m->u.status.done = get32(buf + 16 + 4 * axes);
        m->u.status.recv = get32(buf + 20 + 4 * axes);
        if ((m->u.status.flags & CS_PROTO_STATUS_TICK) != 0 && short_status)
            return CS_ERR_FRAME; /* the flag promises a tick the length lacks */
        if ((m->u.status.flags & CS_PROTO_STATUS_TICK) == 0 && !short_status)
            return CS_ERR_FRAME; /* 4 bytes nobody named */
        if (!short_status)
            m->u.status.tick = get32(buf + 24 + 4 * axes);
        break;
    case CS_PROTO_SETPOS:
        m->u.setpos.flags = buf[1];
        m->u.setpos.job_id = get32(buf + 2);
        m->u.setpos.base = get32(buf + 6);
        for (unsigned i = 0; i < CS_AXES; i++)
            m->u.setpos.pos[i] = geti32(buf + 10 + 4 * i);
        break;
    case CS_PROTO_ERROR:
        m->u.error.code = buf[1];
        m->u.error.seq = get16(buf + 2);
        break;
    case CS_PROTO_SEGMENT:
        m->u.segment.ticks = get32(buf + 1);
        for (unsigned i = 0; i < CS_AXES; i++)
            m->u.segment.steps[i] = geti32(buf + 5 + 4 * i);
        break;
    case CS_PROTO_CURVE:
        for (unsigned i = 0; i < 4; i++) {
            m->u.curve.p[i].x = geti32(buf + 1 + 12 * i);
            m->u.curve.p[i].y = geti32(buf + 5 + 12 * i);
            m->u.curve.p[i].z = geti32(buf + 9 + 12 * i);
        }
        m->u.curve.feed = geti32(buf + 49);
        break;
    case CS_PROTO_PEN:
        m->u.pen.pulse_us = get16(buf + 1);
        break;
    default:
        decode_ctl(buf, m);
        break;
    }
    return check(m);
}

bool cs_proto_peek_boot(const uint8_t *buf, size_t len, uint32_t *boot_id)
{
    cs_proto_msg_t m;
    if (boot_id == NULL || cs_proto_decode(buf, len, &m) != CS_OK)
        return false;
    if (m.type == CS_PROTO_ACK)
        *boot_id = m.u.ack.boot_id;
    else if (m.type == CS_PROTO_HELLO)
        *boot_id = m.u.hello.boot_id;
    else if (m.type == CS_PROTO_STATUS)
        *boot_id = m.u.status.boot_id;
    else
        return false;
    return true;
}
