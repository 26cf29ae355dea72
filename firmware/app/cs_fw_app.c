/* cs_fw_app: the device's framed-serial front end over port.h, the core link and the motion side
 * (cs_fw_motion). See cs_fw_app.h; the protocol is docs/protocol.md. The simulator runs this very
 * code (sim/cs_sim_device.c), so a job gives the same steps on the simulator and on a board. */
#include "cs_fw_app.h"

#include <stddef.h>

#include "port.h"

#ifndef CS_FW_XY_RATE
#define CS_FW_XY_RATE 500 /* mm/s */
#endif
#ifndef CS_FW_XY_ACCEL
#define CS_FW_XY_ACCEL 5000 /* mm/s^2 */
#endif
/* link polls a pass: frames sent, restarts taken */
#define FLUSH_PASSES 8u

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

static uint32_t ms_ticks(const cs_fw_app_t *a, uint32_t ms)
{
    return (a->cfg.clock_hz / 1000u) * ms;
}

static uint32_t new_nonce(cs_fw_app_t *a)
{
    /* Numerical Recipes LCG: nonces only need to differ between starts of this device */
    a->nonce = a->nonce * 1664525u + 1013904223u;
    return a->nonce != 0 ? a->nonce : 1u;
}

static void send_hello(cs_fw_app_t *a)
{
    cs_proto_msg_t h;
    h.type = CS_PROTO_HELLO;
    h.u.hello.version = CS_PROTO_VERSION;
    h.u.hello.boot_id = a->boot;
    h.u.hello.axes = a->m->n_axes;
    h.u.hello.queue_size = a->cfg.motion.queue_size;
    h.u.hello.tick_hz = a->m->tick_hz;
    /* HOME, JOG, PROBE: planned on board, or without the planner by cs_fw_ctl's line generator */
    uint16_t ctl = CS_FW_CTL ? (uint16_t)(CS_PROTO_CAP_SPINDLE | CS_PROTO_CAP_CONTROL) : 0u;
    h.u.hello.caps =
        (uint16_t)(CS_PROTO_CAP_SEGMENTS | (CS_FW_CURVES ? CS_PROTO_CAP_CURVES : 0u) | ctl);
    /* the first message of a freshly opened sender: the window has room */
    (void)cs_link_send_msg(&a->link, &h, NULL);
    a->status_due = true;
}

bool cs_fw_app_send_status(cs_fw_app_t *a)
{
    if (!cs_link_can_send(&a->link, CS_PROTO_STATUS))
        return false;
    cs_proto_msg_t s;
    s.type = CS_PROTO_STATUS;
    cs_fw_motion_status(&a->mo, &s.u.status);
    s.u.status.boot_id = a->boot;
    if (cs_link_send_msg(&a->link, &s, NULL) != CS_OK)
        return false;
    a->status_due = false;
    a->status_at = a->cfg.clock();
    a->sent_state = a->mo.state;
    return true;
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
    for (unsigned k = 0; k < FLUSH_PASSES; k++) {
        if (!tx_drain(a))
            return;
        const uint8_t *b;
        size_t n;
        cs_err_t e = cs_link_poll(&a->link, now, cs_fw_motion_free(&a->mo), &b, &n);
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

static void on_deliver(cs_fw_app_t *a, const cs_link_event_t *ev)
{
    if (a->have_prev && ev->seq != (uint16_t)(a->prev_seq + 1u))
        a->out_of_order++;
    a->have_prev = true;
    a->prev_seq = ev->seq;
    cs_proto_msg_t m;
    cs_err_t e = cs_proto_decode(ev->payload, ev->len, &m);
    if (e != CS_OK) {
        cs_fw_motion_error(&a->mo, e == CS_ERR_ARG ? CS_ERR_FRAME : e, ev->seq);
        return;
    }
    switch (m.type) {
    case CS_PROTO_HOLD:
    case CS_PROTO_RESUME:
        cs_fw_motion_hold(&a->mo, m.type == CS_PROTO_HOLD);
        break;
    case CS_PROTO_ABORT:
        cs_fw_motion_give_back(&a->mo);
        cs_fw_motion_abort(&a->mo);
        break;
    case CS_PROTO_QUERY: /* a host that (re)connected asks where the job stands */
        a->status_due = true;
        break;
    case CS_PROTO_SETPOS:
        e = cs_fw_motion_setpos(&a->mo, &m.u.setpos);
        if (e != CS_OK)
            cs_fw_motion_error(&a->mo, e, ev->seq);
        a->status_due = true;
        break;
    case CS_PROTO_JOG_CANCEL:
        cs_fw_ctl_jog_cancel(&a->mo);
        break;
    case CS_PROTO_OVERRIDE: /* acts on the running motion at once (no queue slot) */
        cs_fw_motion_override(&a->mo, &m.u.override);
        a->status_due = true; /* the host waits for the answer, as to HOLD */
        break;
    case CS_PROTO_UNLOCK:
        e = cs_fw_ctl_unlock(&a->mo);
        if (e != CS_OK)
            cs_fw_motion_error(&a->mo, e, ev->seq);
        else
            cs_fw_motion_count_immediate(&a->mo);
        a->status_due = true;
        break;
    default: /* SEGMENT, CURVE; CURVE without curves or a device-to-host type is refused */
        e = cs_fw_motion_queue(&a->mo, &m, ev->seq);
        if (e != CS_OK) /* CS_ERR_FULL: cs_link refuses it first; belt and braces */
            cs_fw_motion_error(&a->mo, e, ev->seq);
        break;
    }
}

static void send_events(cs_fw_app_t *a)
{
    cs_proto_msg_t em;
    em.type = CS_PROTO_EVENT;
    while (cs_link_can_send(&a->link, CS_PROTO_EVENT) && cs_fw_ctl_peek_event(&a->mo, &em.u.event)) {
        if (cs_link_send_msg(&a->link, &em, NULL) != CS_OK)
            break;
        cs_fw_ctl_drop_event(&a->mo);
    }
}

static void send_errors(cs_fw_app_t *a)
{
    cs_proto_msg_t em;
    em.type = CS_PROTO_ERROR;
    while (cs_link_can_send(&a->link, CS_PROTO_ERROR) &&
           cs_fw_motion_peek_error(&a->mo, &em.u.error)) {
        if (cs_link_send_msg(&a->link, &em, NULL) != CS_OK)
            break;
        cs_fw_motion_drop_error(&a->mo);
    }
}

/* A (re)boot of the link: boot id, the receiver back at sequence 0, the queue lost. */
static cs_err_t link_boot(cs_fw_app_t *a, uint32_t boot_id)
{
    a->boot = boot_id != 0 ? boot_id : 1u;
    cs_err_t e = cs_link_init(&a->link, &a->cfg.link, a->boot, new_nonce(a), 0, a->cfg.clock());
    cs_fw_motion_reboot(&a->mo);
    a->have_prev = false;
    a->txp_len = a->txp_off = 0;
    a->status_due = true;
    return e;
}

/* --- the API ------------------------------------------------------------------------------- */

void cs_fw_app_cfg_default(cs_fw_app_cfg_t *c, const cs_machine_t *m)
{
    cs_fw_motion_cfg_default(&c->motion, m);
    c->clock = port_ticks_now;
    c->clock_hz = port_tick_hz();
    /* the timing every end of the link computes the same way (cs_linktime, protocol.md 3.6) */
    c->link.keepalive = 0;
    (void)cs_linktime_link(&c->link, CS_FW_LINE_BPS, c->clock_hz);
    c->status_ms = 50;
}

cs_err_t cs_fw_app_init(cs_fw_app_t *app, const cs_machine_t *m, uint32_t boot_id)
{
    if (app == NULL || m == NULL)
        return CS_ERR_ARG;
    cs_fw_app_cfg_t c;
    cs_fw_app_cfg_default(&c, m);
    return cs_fw_app_init_cfg(app, m, boot_id, &c);
}

cs_err_t cs_fw_app_init_cfg(cs_fw_app_t *app, const cs_machine_t *m, uint32_t boot_id,
                            const cs_fw_app_cfg_t *c)
{
    if (app == NULL || m == NULL || c == NULL || c->clock == NULL || c->clock_hz < 1000u)
        return CS_ERR_ARG;
    /* a STATUS this build's frames cannot carry (4 axes need CS_FRAME_PAYLOAD_MAX >= 44) */
    if (m->n_axes > CS_PROTO_AXES_MAX || CS_PROTO_LEN_STATUS(m->n_axes) > CS_FRAME_PAYLOAD_MAX)
        return CS_ERR_RANGE;
    cs_fw_motion_zero(app, sizeof *app);
    app->m = m;
    app->cfg = *c;
    app->nonce = boot_id ^ 0x9E3779B9u;
    cs_err_t e = cs_fw_motion_init(&app->mo, m, &c->motion);
    if (e != CS_OK)
        return e;
    app->last_rx = c->clock();
    return link_boot(app, boot_id);
}

void cs_fw_app_reboot(cs_fw_app_t *a, uint32_t boot_id)
{
    (void)link_boot(a, boot_id); /* the configuration was accepted at init */
}

void cs_fw_app_poll(cs_fw_app_t *a)
{
    uint8_t buf[CS_FW_RX_CHUNK];
    size_t n = port_uart_read(buf, sizeof buf);
    uint32_t now = a->cfg.clock();
    if (n > 0) {
        a->last_rx = now;
        a->mo.stats.rx_bytes += (uint32_t)n;
    }
    for (size_t k = 0; k < n; k++) {
        cs_link_event_t ev;
        if (cs_link_feed(&a->link, buf[k], now, cs_fw_motion_free(&a->mo), &ev) != CS_OK)
            continue;
        if (ev.what & CS_LINK_EV_DELIVER)
            on_deliver(a, &ev);
        if (ev.what & CS_LINK_EV_RESET) /* the host restarted: join the new one */
            (void)cs_link_restart(&a->link, new_nonce(a), now);
        if (ev.what & CS_LINK_EV_OPEN)
            send_hello(a);
    }
    cs_fw_motion_poll(&a->mo);
    if (cs_fw_motion_news(&a->mo))
        a->status_due = true;
    /* an alarm's EVENT before its ERROR: a host that stops on the error has seen why */
    if (cs_link_state(&a->link) == CS_LINK_OPEN)
        send_events(a);
    send_errors(a);
    now = a->cfg.clock();
    uint8_t st = a->mo.state;
    uint32_t period = ms_ticks(
        a, (cs_proto_state_busy(st) || st == CS_PROTO_STATE_HELD) ? a->cfg.status_ms : 250u);
    if (cs_link_state(&a->link) == CS_LINK_OPEN &&
        (a->status_due || (uint32_t)(now - a->status_at) >= period))
        (void)cs_fw_app_send_status(a);
    flush_link(a, now);
}

bool cs_fw_app_can_sleep(const cs_fw_app_t *app)
{
    bool open = cs_link_state(&app->link) == CS_LINK_OPEN;
    return !app->mo.more && app->txp_off >= app->txp_len &&
           !(open && (app->status_due || app->mo.nerr || app->mo.ctl.nev)) &&
           app->mo.ctl.trip == CS_FW_TRIP_NONE;
}

bool cs_fw_app_idle(const cs_fw_app_t *app)
{
    return cs_fw_motion_done(&app->mo);
}

uint32_t cs_fw_app_last_rx(const cs_fw_app_t *app)
{
    return app->last_rx;
}

void cs_fw_app_report(const cs_fw_app_t *app, cs_fw_report_t *r)
{
    r->n_axes = app->m->n_axes;
    r->state = app->mo.state;
    for (unsigned i = 0; i < CS_AXES; i++)
        r->pos[i] = cs_fw_motion_position(&app->mo, i);
    uint32_t s = port_irq_save();
    r->steps = app->mo.st.steps_done;
    port_irq_restore(s);
    r->stats = app->mo.stats;
    r->link = app->link.stats;
    r->rx = app->link.dec.stats;
    r->log = app->mo.log;
}
