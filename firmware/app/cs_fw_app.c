/* cs_fw_app: the device main loop over port.h and the core. See cs_fw_app.h; the protocol is
 * docs/protocol.md and the behaviour mirrors sim/cs_sim_device.c (the simulator's device), so a
 * job gives the same steps on the simulator and on a board. */
#include "cs_fw_app.h"

#include <stddef.h>

#include "port.h"

#define SEQ_MASK ((uint32_t)CS_FW_SEQMAP - 1u)
#define TAG_MASK ((uint8_t)(CS_STEPPER_RING - 1))

#ifndef CS_FW_XY_RATE
#define CS_FW_XY_RATE 500 /* mm/s */
#endif
#ifndef CS_FW_XY_ACCEL
#define CS_FW_XY_ACCEL 5000 /* mm/s^2 */
#endif

void cs_fw_machine_default(cs_machine_t *m, uint32_t tick_hz)
{
    m->n_axes = 3;
    for (unsigned i = 0; i < CS_AXES; i++) {
        cs_axis_cfg_t *a = &m->axis[i];
        bool z = i == CS_AXIS_Z;
        a->steps_per_mm = 80 * CS_MOTION_ONE;
        a->max_rate = (z ? 50 : CS_FW_XY_RATE) * CS_MOTION_ONE;
        a->max_accel = (z ? 500 : CS_FW_XY_ACCEL) * CS_MOTION_ONE;
        a->travel_min = (z ? -100 : -1000) * CS_POS_ONE_MM;
        a->travel_max = (z ? 100 : 1000) * CS_POS_ONE_MM;
        a->invert_dir = false;
        /* 2 us, rounded up to whole ticks (the host's pulse_us = 2) */
        uint32_t pt = (tick_hz * 2u + 999999u) / 1000000u;
        a->pulse_ticks = (uint16_t)(pt == 0 ? 1u : pt);
    }
    m->tick_hz = tick_hz;
    m->segment_ticks = tick_hz / 200u; /* 5 ms */
    m->tolerance = CS_POS_ONE_MM / 100;
    m->junction_deviation = CS_POS_ONE_MM / 100;
    m->default_feed = 50 * CS_MOTION_ONE;
    m->profile = CS_PROFILE_TRAPEZOID;
    m->max_jerk = 100000;
}

/* --- small helpers ------------------------------------------------------------------------- */

static uint16_t free_slots(const cs_fw_app_t *a)
{
    return (uint16_t)(CS_FW_QUEUE - a->qcount);
}

static uint32_t ms_ticks(const cs_fw_app_t *a, uint32_t ms)
{
    return (a->hz / 1000u) * ms;
}

static uint32_t new_nonce(cs_fw_app_t *a)
{
    /* Numerical Recipes LCG: nonces only need to differ between starts of this device */
    a->nonce = a->nonce * 1664525u + 1013904223u;
    return a->nonce != 0 ? a->nonce : 1u;
}

static void push_error(cs_fw_app_t *a, cs_err_t code, uint16_t seq)
{
    a->stats.errors++;
    if (a->nerr < CS_FW_ERRQ) {
        a->errs[a->nerr].code = (uint8_t)code;
        a->errs[a->nerr].seq = seq;
        a->nerr++;
    }
}

static void send_hello(cs_fw_app_t *a)
{
    cs_proto_msg_t h;
    h.type = CS_PROTO_HELLO;
    h.u.hello.version = CS_PROTO_VERSION;
    h.u.hello.boot_id = a->boot;
    h.u.hello.axes = a->m->n_axes;
    h.u.hello.queue_size = CS_FW_QUEUE;
    h.u.hello.tick_hz = a->m->tick_hz;
    h.u.hello.caps = CS_FW_CURVES ? CS_PROTO_CAP_ALL : CS_PROTO_CAP_SEGMENTS;
    /* the first message of a freshly opened sender: the window has room */
    (void)cs_link_send_msg(&a->link, &h, NULL);
    a->status_due = true;
}

static int32_t position(const cs_fw_app_t *a, unsigned axis)
{
    /* a 32-bit read is not atomic on the AVR: mask the step interrupt */
    uint32_t s = port_irq_save();
    int32_t p = cs_stepper_position(&a->st, axis);
    port_irq_restore(s);
    return p;
}

static void send_status(cs_fw_app_t *a, uint32_t now)
{
    if (!cs_link_can_send(&a->link, CS_PROTO_STATUS))
        return;
    cs_proto_msg_t s;
    s.type = CS_PROTO_STATUS;
    s.u.status.state = a->state;
    s.u.status.boot_id = a->boot;
    s.u.status.queue_fill = a->qcount;
    s.u.status.last_seq = a->exec_seq;
    s.u.status.axes = a->m->n_axes;
    for (unsigned i = 0; i < CS_PROTO_AXES_MAX; i++)
        s.u.status.pos[i] = i < a->m->n_axes ? position(a, i) : 0;
    if (cs_link_send_msg(&a->link, &s, NULL) == CS_OK) {
        a->status_due = false;
        a->status_at = now;
        a->sent_state = a->state;
    }
}

/* Writes what the UART takes; keeps the rest in txp (the link's bytes are only valid until its
 * next poll). Returns true when nothing is left pending. */
static bool tx_drain(cs_fw_app_t *a)
{
    while (a->txp_off < a->txp_len) {
        size_t n = port_uart_write(a->txp + a->txp_off, (size_t)(a->txp_len - a->txp_off));
        if (n == 0)
            return false;
        a->txp_off = (uint8_t)(a->txp_off + n);
    }
    return true;
}

static void flush_link(cs_fw_app_t *a, uint32_t now)
{
    for (unsigned k = 0; k < 8u; k++) {
        if (!tx_drain(a))
            return;
        const uint8_t *b;
        size_t n;
        cs_err_t e = cs_link_poll(&a->link, now, free_slots(a), &b, &n);
        if (e == CS_END)
            return;
        if (e == CS_ERR_TIMEOUT) { /* the host went away: wait for the next one */
            (void)cs_link_restart(&a->link, new_nonce(a), now);
            continue;
        }
        if (e != CS_OK || n > sizeof a->txp)
            continue;
        size_t w = port_uart_write(b, n);
        if (w < n) {
            for (size_t i = w; i < n; i++)
                a->txp[i - w] = b[i];
            a->txp_len = (uint8_t)(n - w);
            a->txp_off = 0;
        }
    }
}

/* --- motion -------------------------------------------------------------------------------- */

/* Everything taken from the queue has been executed (the queue itself may hold more). */
static bool drained(const cs_fw_app_t *a)
{
#if CS_FW_CURVES
    if (a->tracing || a->gen_busy || cs_planner_count(&a->pl) != 0)
        return false;
#endif
    return cs_stepper_idle(&a->st);
}

static bool everything_done(const cs_fw_app_t *a)
{
    return a->qcount == 0 && drained(a);
}

static bool item_after(uint32_t x, uint32_t y)
{
    return (int32_t)(x - y) > 0;
}

static void mark_executed(cs_fw_app_t *a, uint32_t item)
{
    if (item_after(item, a->exec_item)) {
        a->stats.executed += item - a->exec_item;
        a->exec_item = item;
        a->exec_seq = a->item_seq[item & SEQ_MASK];
    }
}

/* Segments the executor has finished: pushed - (queued in the ring) - (the running one). */
static void note_completed(cs_fw_app_t *a)
{
    uint32_t s = port_irq_save();
    uint8_t inring = (uint8_t)(a->st.tail - a->st.head);
    uint8_t running = a->st.running ? 1u : 0u;
    port_irq_restore(s);
    uint8_t done = (uint8_t)(a->pushed - inring - running);
    while (a->completed != done) {
        mark_executed(a, a->tag[a->completed & TAG_MASK]);
        a->completed++;
    }
    if (drained(a))
        mark_executed(a, a->popped); /* items that made no segment (zero moves, errors) */
}

static void pop_item(cs_fw_app_t *a, cs_fw_item_t *out)
{
    *out = a->q[a->qhead];
    a->qhead = (uint8_t)((a->qhead + 1u) % CS_FW_QUEUE);
    a->qcount--;
    a->popped++;
    a->item_seq[a->popped & SEQ_MASK] = out->seq;
}

#if CS_FW_CURVES
static cs_pos_t steps_to_pos(int32_t steps, int32_t spm)
{
    /* mm Q16 = steps * 2^32 / spm(Q16), rounded to nearest (as the simulator does) */
    int64_t num = (int64_t)steps * ((int64_t)1 << 32);
    int64_t q = num >= 0 ? (num + spm / 2) / spm : -((-num + spm / 2) / spm);
    return (cs_pos_t)q;
}

/* SEGMENT messages moved the machine behind the planner's back: start it from there. */
static void refresh_planner(cs_fw_app_t *a)
{
    if (!a->pl_stale || cs_planner_count(&a->pl) != 0)
        return;
    cs_pos_t p[CS_AXES] = {0, 0, 0, 0};
    for (unsigned i = 0; i < a->m->n_axes; i++)
        p[i] = steps_to_pos(a->steps_pos[i], a->m->axis[i].steps_per_mm);
    (void)cs_planner_set_position(&a->pl, p);
    a->pl_stale = false;
}

static void start_curve(cs_fw_app_t *a, const cs_fw_item_t *it)
{
    refresh_planner(a);
    cs_bezier_t c;
    cs_err_t e = cs_bezier_init(&c, 3, it->u.curve.p);
    if (e == CS_OK)
        e = cs_trace_begin(&a->tr, &c, a->m->tolerance, (cs_trace_method_t)CS_FW_TRACE);
    if (e != CS_OK) {
        push_error(a, e, it->seq);
        return;
    }
    a->tracing = true;
    a->tr_feed = it->u.curve.feed;
    a->tr_item = a->popped;
    const cs_vec3_t *p0 = &it->u.curve.p[0];
    a->rapid_pending = p0->x != a->pl.pos[0] || p0->y != a->pl.pos[1] || p0->z != a->pl.pos[2];
    a->rapid_to = *p0;
    a->stats.curves++;
}
#endif

static bool may_take_item(const cs_fw_app_t *a)
{
    return !a->held && a->qcount > 0;
}

/* Next step segment for the executor: true with *s and *done (the item executed once it has
 * run) set, false when nothing is ready now (a->more: the work budget of this pass ran out
 * first). Bounded work. */
static bool next_segment(cs_fw_app_t *a, cs_segment_t *s, uint32_t *done)
{
    for (unsigned guard = 0; guard < 64u; guard++) {
#if CS_FW_CURVES
        bool feeding = a->tracing || (may_take_item(a) && a->q[a->qhead].type == CS_PROTO_CURVE);
        /* Cut when the look-ahead is full or nothing more can be added now (the planner always
         * plans its last block to end at rest, so cutting early is safe). */
        if (a->gen_busy ||
            (cs_planner_count(&a->pl) > 0 && (cs_planner_full(&a->pl) || !feeding))) {
            if (a->held)
                return false;
            cs_err_t e = cs_segment_next(&a->gen, &a->pl, s);
            if (e == CS_ERR_EMPTY) {
                a->gen_busy = false;
                continue;
            }
            if (e != CS_OK) {
                push_error(a, e, a->item_seq[a->gen.line & SEQ_MASK]);
                a->gen_busy = false;
                (void)cs_planner_init(&a->pl, a->m);
                a->pl_stale = true;
                return false;
            }
            a->gen_busy = !cs_segment_block_end(&a->gen);
            /* the block's "line" is its item: the item before it is done when this ends */
            *done = a->gen.line - 1u;
            return true;
        }
        if (a->tracing) {
            cs_vec3_t pt;
            cs_err_t e;
            if (a->rapid_pending) {
                pt = a->rapid_to;
                e = cs_planner_line3(&a->pl, &pt, 0, a->tr_item);
                a->rapid_pending = false;
            } else {
                e = cs_trace_next(&a->tr, &pt);
                if (e == CS_END) {
                    a->tracing = false;
                    continue;
                }
                if (e == CS_OK)
                    e = cs_planner_line3(&a->pl, &pt, a->tr_feed, a->tr_item);
            }
            if (e != CS_OK) {
                push_error(a, e, a->item_seq[a->tr_item & SEQ_MASK]);
                a->tracing = false;
            }
            continue;
        }
#endif
        if (!may_take_item(a))
            return false;
        cs_fw_item_t it;
        pop_item(a, &it);
#if CS_FW_CURVES
        if (it.type == CS_PROTO_CURVE) {
            start_curve(a, &it);
            continue;
        }
        a->pl_stale = true;
        for (unsigned i = 0; i < CS_AXES; i++)
            a->steps_pos[i] += it.u.seg.steps[i];
#endif
        *s = it.u.seg;
        *done = a->popped;
        return true;
    }
    a->more = true;
    return false;
}

/* Keeps the executor's ring full and the step timer running. */
static void feed(cs_fw_app_t *a)
{
    a->more = false;
    while (cs_stepper_free(&a->st) > 0) {
        cs_segment_t s;
        uint32_t done;
        if (!next_segment(a, &s, &done))
            break;
        /* Start the timer when the executor was idle: the step interrupt stops it when the
         * ring runs dry (next_ticks 0), so idle <=> stopped, checked with interrupts masked. */
        uint32_t irq = port_irq_save();
        bool was_idle = cs_stepper_idle(&a->st);
        cs_err_t e = cs_stepper_push(&a->st, &s);
        if (e == CS_OK) {
            a->tag[a->pushed & TAG_MASK] = done;
            a->pushed++;
            if (was_idle)
                port_timer_arm(1);
        }
        port_irq_restore(irq);
        if (e != CS_OK) { /* cs_proto checked the invariant already */
            push_error(a, e, a->item_seq[done & SEQ_MASK]);
            continue;
        }
        a->stats.segments++;
    }
}

static void update_state(cs_fw_app_t *a)
{
    uint8_t st = a->held               ? CS_PROTO_STATE_HELD
                 : !everything_done(a) ? CS_PROTO_STATE_RUNNING
                 : a->aborted          ? CS_PROTO_STATE_ABORTED
                                       : CS_PROTO_STATE_IDLE;
    if (st != a->state) {
        a->state = st;
        a->status_due = true;
    }
}

static void do_abort(cs_fw_app_t *a)
{
    a->qcount = 0;
    a->qhead = 0;
#if CS_FW_CURVES
    a->tracing = false;
    a->rapid_pending = false;
    /* the executor's ring finishes (at most CS_STEPPER_RING segments), the rest is dropped */
    if (a->gen_busy || cs_planner_count(&a->pl) > 0) {
        (void)cs_planner_init(&a->pl, a->m);
        (void)cs_segment_init(&a->gen, a->m);
        a->gen_busy = false;
    }
    a->pl_stale = true;
#endif
    a->held = false;
    a->aborted = true;
    a->stats.aborts++;
}

static void on_deliver(cs_fw_app_t *a, const cs_link_event_t *ev)
{
    cs_proto_msg_t m;
    cs_err_t e = cs_proto_decode(ev->payload, ev->len, &m);
    if (e != CS_OK) {
        push_error(a, e == CS_ERR_ARG ? CS_ERR_FRAME : e, ev->seq);
        return;
    }
    switch (m.type) {
    case CS_PROTO_SEGMENT:
#if CS_FW_CURVES
    case CS_PROTO_CURVE:
#endif
    {
        if (a->qcount >= CS_FW_QUEUE) { /* cs_link refuses it first; belt and braces */
            push_error(a, CS_ERR_FULL, ev->seq);
            return;
        }
        cs_fw_item_t *it = &a->q[(a->qhead + a->qcount) % CS_FW_QUEUE];
        it->type = m.type;
        it->seq = ev->seq;
#if CS_FW_CURVES
        if (m.type == CS_PROTO_CURVE)
            it->u.curve = m.u.curve;
        else
#endif
            it->u.seg = m.u.segment;
        a->qcount++;
        a->aborted = false;
        break;
    }
    case CS_PROTO_HOLD:
        a->held = true;
        a->stats.holds++;
        a->status_due = true;
        break;
    case CS_PROTO_RESUME:
        a->held = false;
        a->status_due = true;
        break;
    case CS_PROTO_ABORT:
        do_abort(a);
        a->status_due = true;
        break;
    default: /* CURVE without curves, or a device-to-host type */
        push_error(a, CS_ERR_UNSUPPORTED, ev->seq);
        break;
    }
}

/* --- the API ------------------------------------------------------------------------------- */

cs_err_t cs_fw_app_init(cs_fw_app_t *app, const cs_machine_t *m, uint32_t boot_id)
{
    if (app == NULL || m == NULL)
        return CS_ERR_ARG;
    /* zero everything without memset (freestanding: the compiler may still call it) */
    uint8_t *p = (uint8_t *)app;
    for (size_t i = 0; i < sizeof *app; i++)
        p[i] = 0;
    app->m = m;
    app->hz = port_tick_hz();
    app->boot = boot_id != 0 ? boot_id : 1u;
    app->nonce = boot_id ^ 0x9E3779B9u;
    cs_err_t e = cs_stepper_init(&app->st, m);
#if CS_FW_CURVES
    if (e == CS_OK)
        e = cs_planner_init(&app->pl, m);
    if (e == CS_OK)
        e = cs_segment_init(&app->gen, m);
#endif
    if (e != CS_OK)
        return CS_ERR_ARG;
    uint32_t now = port_ticks_now();
    cs_link_cfg_t lc;
    lc.rto = ms_ticks(app, CS_FW_RTO_MS);
    lc.nak_holdoff = ms_ticks(app, CS_FW_NAK_MS);
    lc.keepalive = 0;
    lc.max_retries = 20;
    e = cs_link_init(&app->link, &lc, app->boot, new_nonce(app), 0, now);
    if (e != CS_OK)
        return e;
    /* nothing executed yet: the last executed sequence is the one before the receiver's first
     * (a host reads STATUS.last_seq against its own first sequence) */
    app->exec_seq = 0xFFFFu;
    app->item_seq[0] = 0xFFFFu;
    app->state = CS_PROTO_STATE_IDLE;
    app->status_due = true;
    app->last_rx = now;
    port_stepper_attach(&app->st);
    return CS_OK;
}

void cs_fw_app_poll(cs_fw_app_t *a)
{
    uint8_t buf[CS_FW_RX_CHUNK];
    size_t n = port_uart_read(buf, sizeof buf);
    uint32_t now = port_ticks_now();
    if (n > 0) {
        a->last_rx = now;
        a->stats.rx_bytes += (uint32_t)n;
    }
    for (size_t k = 0; k < n; k++) {
        cs_link_event_t ev;
        if (cs_link_feed(&a->link, buf[k], now, free_slots(a), &ev) != CS_OK)
            continue;
        if (ev.what & CS_LINK_EV_DELIVER)
            on_deliver(a, &ev);
        if (ev.what & CS_LINK_EV_RESET) /* the host restarted: join the new one */
            (void)cs_link_restart(&a->link, new_nonce(a), now);
        if (ev.what & CS_LINK_EV_OPEN)
            send_hello(a);
    }
    feed(a);
    note_completed(a);
    update_state(a);
    while (a->nerr > 0 && cs_link_can_send(&a->link, CS_PROTO_ERROR)) {
        cs_proto_msg_t em;
        em.type = CS_PROTO_ERROR;
        em.u.error = a->errs[0];
        if (cs_link_send_msg(&a->link, &em, NULL) != CS_OK)
            break;
        for (uint8_t i = 1; i < a->nerr; i++)
            a->errs[i - 1] = a->errs[i];
        a->nerr--;
    }
    now = port_ticks_now();
    uint32_t period = ms_ticks(
        a, (a->state == CS_PROTO_STATE_RUNNING || a->state == CS_PROTO_STATE_HELD) ? 50u : 250u);
    if (cs_link_state(&a->link) == CS_LINK_OPEN &&
        (a->status_due || (uint32_t)(now - a->status_at) >= period))
        send_status(a, now);
    flush_link(a, now);
}

bool cs_fw_app_can_sleep(const cs_fw_app_t *app)
{
    bool open = cs_link_state(&app->link) == CS_LINK_OPEN;
    return !app->more && app->txp_off >= app->txp_len && !(open && (app->status_due || app->nerr));
}

bool cs_fw_app_idle(const cs_fw_app_t *app)
{
    return everything_done(app);
}

uint32_t cs_fw_app_last_rx(const cs_fw_app_t *app)
{
    return app->last_rx;
}

void cs_fw_app_report(const cs_fw_app_t *app, cs_fw_report_t *r)
{
    r->n_axes = app->m->n_axes;
    r->state = app->state;
    for (unsigned i = 0; i < CS_AXES; i++)
        r->pos[i] = position(app, i);
    uint32_t s = port_irq_save();
    r->steps = app->st.steps_done;
    port_irq_restore(s);
    r->stats = app->stats;
    r->link = app->link.stats;
    r->rx = app->link.dec.stats;
}
