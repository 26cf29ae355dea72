/* cs_link: reliable, flow-controlled delivery over a lossy byte stream (docs/protocol.md).
 * Go-back-N like Klipper's host link: every sequenced frame stays in the sender's ring until an
 * ACK's next_expected passes it; a timeout on the oldest frame, or a NAK, rewinds the send
 * position to the oldest unacknowledged frame. The receiver delivers only next_expected, so a
 * lost frame costs the window behind it, never an out-of-order or duplicate delivery.
 * Sequence numbers and times wrap; every comparison is on the modular difference. */
#include "cs_link.h"

CS_STATIC_ASSERT(CS_LINK_WINDOW <= 0x8000, window_below_half_sequence_space);
CS_STATIC_ASSERT(CS_FRAME_WIRE_MAX <= 255, slot_len_fits_u8);
CS_STATIC_ASSERT(CS_LINK_CTL_WIRE >= CS_FRAME_WIRE_LEN(CS_PROTO_LEN_PING), ctl_fits_ping);

static void inc(uint32_t *c)
{
    if (*c != UINT32_MAX)
        (*c)++;
}

static uint16_t seq_diff(uint16_t a, uint16_t b)
{
    return (uint16_t)(a - b);
}

bool cs_link_seq_before(uint16_t a, uint16_t b)
{
    return seq_diff(a, b) >= 0x8000u;
}

static bool elapsed(uint32_t now, uint32_t since, uint32_t span)
{
    return (uint32_t)(now - since) >= span;
}

/* Progress (the peer answered): the next timeout is rto again. */
static void progress(cs_link_t *l)
{
    l->retries = 0;
}

/* The timeout after `retries` timeouts in a row: min(rto * 2^retries, rto_max), doubled step by
 * step (no shift past 32 bits; at most 32 steps before the cap). */
static uint32_t rto_now(const cs_link_t *l)
{
    uint32_t t = l->cfg.rto;
    for (unsigned k = 0; k < l->retries && t < l->cfg.rto_max; k++)
        t = t > l->cfg.rto_max / 2u ? l->cfg.rto_max : 2u * t;
    return t;
}

static void tx_reset_ring(cs_link_t *l, uint32_t nonce, uint32_t now)
{
    for (unsigned i = 0; i < CS_LINK_WINDOW; i++) {
        l->ring[i].wire_len = 0;
        l->ring[i].uses_slot = false;
        l->ring[i].sent = false;
    }
    l->state = CS_LINK_CONNECTING;
    l->base = l->next = l->send_pos = 0;
    l->credits = 0;
    l->slots_out = 0;
    l->peer_boot = 0;
    l->nonce = nonce;
    l->ping_out = false;
    l->blocked = false;
    progress(l);
    l->timer_at = l->ping_at = l->heard_at = now;
}

cs_err_t cs_link_init(cs_link_t *l, const cs_link_cfg_t *cfg, uint32_t boot_id, uint32_t nonce,
                      uint16_t rx_first_seq, uint32_t now)
{
    if (l == NULL || cfg == NULL || cfg->rto == 0 || cfg->rto_max < cfg->rto ||
        cfg->give_up == 0 || nonce == 0)
        return CS_ERR_ARG;
    *l = (cs_link_t){0};
    l->cfg = *cfg;
    cs_frame_dec_init(&l->dec);
    tx_reset_ring(l, nonce, now);
    l->boot_id = boot_id;
    l->next_expected = rx_first_seq;
    return CS_OK;
}

cs_err_t cs_link_restart(cs_link_t *l, uint32_t nonce, uint32_t now)
{
    if (l == NULL || nonce == 0)
        return CS_ERR_ARG;
    tx_reset_ring(l, nonce, now);
    return CS_OK;
}

cs_link_state_t cs_link_state(const cs_link_t *l)
{
    return (cs_link_state_t)l->state;
}

uint16_t cs_link_last_acked(const cs_link_t *l)
{
    return (uint16_t)(l->base - 1u);
}

uint16_t cs_link_unacked(const cs_link_t *l)
{
    return seq_diff(l->next, l->base);
}

/* The peer announced boot id `boot` (ACK, HELLO or STATUS): a change while open is a reset. */
static void note_peer_boot(cs_link_t *l, uint32_t boot, cs_link_event_t *ev)
{
    if (l->state != CS_LINK_OPEN || boot == l->peer_boot)
        return;
    ev->what |= CS_LINK_EV_RESET;
    ev->old_boot = l->peer_boot;
    ev->new_boot = boot;
    ev->last_acked = cs_link_last_acked(l);
    ev->unacked = cs_link_unacked(l);
    l->state = CS_LINK_RESET;
}

static cs_err_t tx_on_ack(cs_link_t *l, const cs_proto_ack_t *a, uint32_t now, cs_link_event_t *ev)
{
    if (l->state == CS_LINK_CONNECTING) {
        /* Only the answer to our own PING tells the peer's current next_expected; anything else
         * may be left over from an earlier session. */
        if (!l->ping_out || a->echo != l->nonce)
            return CS_OK;
        l->base = l->next = l->send_pos = a->next_expected;
        l->credits = a->credits;
        l->peer_boot = a->boot_id;
        l->state = CS_LINK_OPEN;
        l->ping_out = false;
        progress(l);
        l->timer_at = l->heard_at = now;
        ev->what |= CS_LINK_EV_OPEN;
        ev->new_boot = a->boot_id;
        ev->last_acked = cs_link_last_acked(l);
        return CS_OK;
    }
    if (l->state != CS_LINK_OPEN)
        return CS_OK;
    note_peer_boot(l, a->boot_id, ev);
    if (l->state != CS_LINK_OPEN)
        return CS_OK;
    l->heard_at = now;
    if (l->ping_out && a->echo == l->nonce) {
        l->ping_out = false;
        progress(l);
    }
    uint16_t adv = seq_diff(a->next_expected, l->base);
    uint16_t out = seq_diff(l->next, l->base);
    if (adv > out) {
        if (cs_link_seq_before(a->next_expected, l->base)) {
            inc(&l->stats.stale_acks); /* overtaken by a later ACK: nothing to learn */
            return CS_OK;
        }
        inc(&l->stats.bad);
        return CS_ERR_SEQ;
    }
    if (adv > 0) {
        for (uint16_t s = l->base; s != a->next_expected; s++) {
            cs_link_slot_t *sl = &l->ring[s & CS_LINK_WINDOW_MASK];
            if (sl->uses_slot)
                l->slots_out--;
            sl->uses_slot = false;
            sl->sent = false;
            sl->wire_len = 0;
        }
        if (seq_diff(l->send_pos, l->base) < adv)
            l->send_pos = a->next_expected; /* a rewind had not got that far yet */
        l->base = a->next_expected;
        l->credits = a->credits;
        progress(l);
        l->ping_out = false; /* the peer is alive: any probe is answered */
        l->timer_at = now;
    } else if (a->credits > l->credits) {
        /* Same next_expected: the peer's free room for it can only have grown since (the
         * receiver only frees slots while nothing new is accepted), so an older duplicate ACK
         * must not shrink it. */
        l->credits = a->credits;
    }
    if (l->slots_out < l->credits)
        l->blocked = false; /* room again: no need to probe for a window update */
    /* NAK: the peer saw a gap right after next_expected, so that frame was lost; resend from it
     * now unless it went out less than nak_holdoff ago (then the NAK is about an older copy). */
    if ((a->flags & CS_PROTO_ACK_NAK) && seq_diff(l->send_pos, l->base) > 0 &&
        elapsed(now, l->ring[l->base & CS_LINK_WINDOW_MASK].sent_at, l->cfg.nak_holdoff)) {
        l->send_pos = l->base;
        inc(&l->stats.naks);
    }
    return CS_OK;
}

static cs_err_t rx_on_seq(cs_link_t *l, const cs_frame_t *f, uint16_t free_slots,
                          cs_link_event_t *ev)
{
    uint16_t d = seq_diff(f->seq, l->next_expected);
    l->ack_due = true;
    if (d == 0) {
        bool slot = cs_proto_uses_slot(f->payload[0]);
        if (slot && free_slots == 0) {
            inc(&l->stats.refused);
            return CS_ERR_FULL;
        }
        l->next_expected++;
        if (slot && l->adv_credits > 0)
            l->adv_credits--;
        inc(&l->stats.delivered);
        ev->what |= CS_LINK_EV_DELIVER;
        ev->seq = f->seq;
        ev->len = f->len;
        ev->payload = f->payload;
        uint32_t boot;
        if ((f->payload[0] == CS_PROTO_HELLO || f->payload[0] == CS_PROTO_STATUS) &&
            cs_proto_peek_boot(f->payload, f->len, &boot))
            note_peer_boot(l, boot, ev);
        return CS_OK;
    }
    if (d >= 0x8000u) {
        inc(&l->stats.duplicates); /* already delivered: the ACK we owe tells the sender */
        return CS_OK;
    }
    /* A gap: every frame beyond it repeats the NAK (the ACK is owed anyway), so one lost NAK
     * costs nothing; the sender's nak_holdoff keeps the repeats from rewinding it twice. */
    inc(&l->stats.out_of_order);
    l->nak_due = true;
    return CS_OK;
}

cs_err_t cs_link_on_frame(cs_link_t *l, const cs_frame_t *f, uint32_t now, uint16_t free_slots,
                          cs_link_event_t *ev)
{
    if (l == NULL || f == NULL || ev == NULL || f->payload == NULL || f->len == 0)
        return CS_ERR_ARG;
    *ev = (cs_link_event_t){0};
    uint8_t type = f->payload[0];
    if (cs_proto_sequenced(type)) {
        l->heard = true;
        return rx_on_seq(l, f, free_slots, ev);
    }
    cs_proto_msg_t m;
    cs_err_t e = cs_proto_decode(f->payload, f->len, &m);
    if (e != CS_OK) {
        inc(&l->stats.bad);
        return e;
    }
    if (m.type == CS_PROTO_PING) {
        l->heard = true;
        l->echo = m.u.ping.nonce;
        l->ack_due = true;
        return CS_OK;
    }
    return tx_on_ack(l, &m.u.ack, now, ev);
}

cs_err_t cs_link_feed(cs_link_t *l, uint8_t byte, uint32_t now, uint16_t free_slots,
                      cs_link_event_t *ev)
{
    if (l == NULL || ev == NULL)
        return CS_ERR_ARG;
    *ev = (cs_link_event_t){0};
    cs_frame_t f;
    cs_err_t e = cs_frame_dec_feed(&l->dec, byte, &f);
    if (e == CS_ERR_EMPTY)
        return CS_OK;
    if (e != CS_OK)
        return e;
    return cs_link_on_frame(l, &f, now, free_slots, ev);
}

bool cs_link_can_send(const cs_link_t *l, uint8_t type)
{
    if (l->state != CS_LINK_OPEN || seq_diff(l->next, l->base) >= CS_LINK_WINDOW)
        return false;
    return !cs_proto_uses_slot(type) || l->slots_out < l->credits;
}

cs_err_t cs_link_send(cs_link_t *l, const uint8_t *payload, size_t len, uint16_t *seq)
{
    if (l == NULL || payload == NULL || len == 0 || len > CS_FRAME_PAYLOAD_MAX ||
        !cs_proto_sequenced(payload[0]))
        return CS_ERR_ARG;
    if (l->state != CS_LINK_OPEN)
        return CS_ERR_STATE;
    if (!cs_link_can_send(l, payload[0])) {
        l->blocked = seq_diff(l->next, l->base) < CS_LINK_WINDOW;
        return CS_ERR_FULL;
    }
    cs_link_slot_t *sl = &l->ring[l->next & CS_LINK_WINDOW_MASK];
    size_t wl = 0;
    cs_err_t e = cs_frame_encode(l->next, payload, len, sl->wire, sizeof sl->wire, &wl);
    if (e != CS_OK)
        return e;
    sl->wire_len = (uint8_t)wl;
    sl->uses_slot = cs_proto_uses_slot(payload[0]);
    sl->sent = false;
    if (sl->uses_slot)
        l->slots_out++;
    l->blocked = false;
    if (seq != NULL)
        *seq = l->next;
    l->next++;
    return CS_OK;
}

cs_err_t cs_link_send_msg(cs_link_t *l, const cs_proto_msg_t *m, uint16_t *seq)
{
    uint8_t buf[CS_PROTO_LEN_MAX];
    size_t n = 0;
    cs_err_t e = cs_proto_encode(m, buf, sizeof buf, &n);
    if (e != CS_OK)
        return e;
    return cs_link_send(l, buf, n, seq);
}

static cs_err_t emit_ctl(cs_link_t *l, const cs_proto_msg_t *m, const uint8_t **bytes, size_t *len)
{
    uint8_t p[CS_PROTO_LEN_ACK];
    size_t n = 0;
    cs_err_t e = cs_proto_encode(m, p, sizeof p, &n);
    if (e == CS_OK)
        e = cs_frame_encode(0, p, n, l->ctl, sizeof l->ctl, len);
    if (e == CS_OK)
        *bytes = l->ctl;
    return e;
}

static cs_err_t emit_ping(cs_link_t *l, uint32_t now, const uint8_t **bytes, size_t *len)
{
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_PING;
    m.u.ping.nonce = l->nonce;
    l->ping_out = true;
    l->ping_at = now;
    return emit_ctl(l, &m, bytes, len);
}

/* One more timeout without progress: false (and CLOSED) once the peer has been silent for
 * give_up; else the next timeout doubles, capped at rto_max (exponential backoff: a peer starved
 * of the CPU for seconds finds the link still open, and a dead one costs a few frames a second,
 * not 200). */
static bool retry(cs_link_t *l, uint32_t now)
{
    inc(&l->stats.timeouts);
    if (elapsed(now, l->heard_at, l->cfg.give_up)) {
        l->state = CS_LINK_CLOSED;
        l->ping_out = false;
        return false;
    }
    if (l->retries != UINT8_MAX)
        l->retries++;
    return true;
}

cs_err_t cs_link_poll(cs_link_t *l, uint32_t now, uint16_t free_slots, const uint8_t **bytes,
                      size_t *len)
{
    if (l == NULL || bytes == NULL || len == NULL)
        return CS_ERR_ARG;
    /* Receiver first: an ACK is due for every sequenced frame or PING received, and unasked when
     * the peer's idea of our free room has fallen below half of the truth (window update). */
    if (l->ack_due || (l->heard && free_slots > l->adv_credits &&
                       (l->adv_credits == 0 || l->adv_credits < free_slots / 2u))) {
        cs_proto_msg_t m = {0};
        m.type = CS_PROTO_ACK;
        m.u.ack.flags = l->nak_due ? CS_PROTO_ACK_NAK : 0;
        m.u.ack.next_expected = l->next_expected;
        m.u.ack.credits = free_slots;
        m.u.ack.boot_id = l->boot_id;
        m.u.ack.echo = l->echo;
        l->ack_due = l->nak_due = false;
        l->adv_credits = free_slots;
        return emit_ctl(l, &m, bytes, len);
    }
    if (l->state == CS_LINK_CONNECTING) {
        if (l->ping_out && !elapsed(now, l->ping_at, rto_now(l)))
            return CS_END;
        if (l->ping_out && !retry(l, now))
            return CS_ERR_TIMEOUT;
        return emit_ping(l, now, bytes, len);
    }
    if (l->state != CS_LINK_OPEN)
        return CS_END;
    if (l->base != l->next) {
        /* Data outstanding: its retransmissions are the probe (no PING, one timer, one count). */
        if (l->send_pos != l->base && elapsed(now, l->timer_at, rto_now(l))) {
            if (!retry(l, now))
                return CS_ERR_TIMEOUT;
            l->send_pos = l->base; /* go back N */
        }
        if (l->send_pos == l->next)
            return CS_END;
        cs_link_slot_t *sl = &l->ring[l->send_pos & CS_LINK_WINDOW_MASK];
        if (l->send_pos == l->base)
            l->timer_at = now;
        if (sl->sent)
            inc(&l->stats.retransmits);
        sl->sent = true;
        sl->sent_at = now;
        l->send_pos++;
        *bytes = sl->wire;
        *len = sl->wire_len;
        return CS_OK;
    }
    /* Nothing to send: probe a silent peer when we wait for credits (the window update may have
     * been lost) or when keepalive says so; unanswered probes count as timeouts. */
    if (l->ping_out) {
        if (!elapsed(now, l->ping_at, rto_now(l)))
            return CS_END;
        if (!retry(l, now))
            return CS_ERR_TIMEOUT;
        return emit_ping(l, now, bytes, len);
    }
    if ((l->blocked && elapsed(now, l->heard_at, l->cfg.rto)) ||
        (l->cfg.keepalive != 0 && elapsed(now, l->heard_at, l->cfg.keepalive))) {
        l->nonce = l->nonce + 1u == 0 ? 1u : l->nonce + 1u;
        return emit_ping(l, now, bytes, len);
    }
    return CS_END;
}
