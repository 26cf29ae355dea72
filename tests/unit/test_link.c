/* test_link: the reliable link between two in-memory endpoints. The big tests put a simulated
 * serial line between them (fixed-seed xorshift): finite speed (bytes per tick), latency, 1 % of
 * bytes corrupted, 1 % of frames dropped, some frames duplicated and some delayed past later ones.
 * The host end streams 100,000 step segments (each derived from its index by a hash, so the
 * device can check every one), the device end queues them in a small motion queue drained at a
 * varying rate with stalls. Asserted: every segment delivered exactly once, in order, unchanged;
 * the step sums per axis exact; the queue never overflows (credits never exceeded); a device
 * reset mid-job and a dead line are reported. Smaller tests pin each rule on its own. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "cs_link.h"
#include "cs_linktime.h"

static uint64_t rng_state;
static uint64_t rng(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return rng_state;
}
/* True with probability ppm / 1e6. */
static int chance(uint32_t ppm)
{
    return (uint32_t)(rng() % 1000000u) < ppm;
}

/* --- the segment stream: content is a function of the index -------------------------------- */
static uint64_t mix(uint64_t x)
{
    x ^= x >> 33;
    x *= 0xFF51AFD7ED558CCDull;
    x ^= x >> 33;
    x *= 0xC4CEB9FE1A85EC53ull;
    x ^= x >> 33;
    return x;
}

static cs_segment_t segment_of(uint32_t index)
{
    cs_segment_t s;
    s.ticks = 50 + (uint32_t)(mix(index) % 2000);
    for (int a = 0; a < CS_AXES; a++)
        s.steps[a] =
            (int32_t)(mix(index * 8u + (uint32_t)a + 1u) % (2u * s.ticks + 1u)) - (int32_t)s.ticks;
    return s;
}

/* --- the simulated line ---------------------------------------------------------------------- */
#define CHAN_CAP 256
typedef struct {
    uint64_t due;
    uint64_t order;
    uint16_t len;
    uint8_t bytes[CS_FRAME_WIRE_MAX];
} chunk_t;

typedef struct {
    chunk_t q[CHAN_CAP];
    int n;
    uint64_t busy_until; /* the line is sending until then */
    uint64_t order;
    uint32_t bytes_per_tick, latency;
    uint32_t corrupt_ppm, drop_ppm, dup_ppm, delay_ppm, delay_max;
    int cut;
    uint64_t frames, dropped, corrupted, duplicated, delayed;
} chan_t;

static void chan_init(chan_t *c, uint32_t corrupt_ppm, uint32_t drop_ppm)
{
    memset(c, 0, sizeof *c);
    c->bytes_per_tick = 2;
    c->latency = 20;
    c->corrupt_ppm = corrupt_ppm;
    c->drop_ppm = drop_ppm;
    c->dup_ppm = drop_ppm / 2;
    c->delay_ppm = drop_ppm * 2;
    c->delay_max = 150;
}

static int chan_ready(const chan_t *c, uint64_t now)
{
    return c->busy_until <= now && c->n < CHAN_CAP - 2;
}

static void chan_push(chan_t *c, const uint8_t *b, size_t len, uint64_t due)
{
    chunk_t *k = &c->q[c->n++];
    k->due = due;
    k->order = c->order++;
    k->len = (uint16_t)len;
    for (size_t i = 0; i < len; i++) {
        k->bytes[i] = b[i];
        if (chance(c->corrupt_ppm)) {
            k->bytes[i] ^= (uint8_t)(1 + rng() % 255);
            c->corrupted++;
        }
    }
}

static void chan_send(chan_t *c, const uint8_t *b, size_t len, uint64_t now)
{
    assert_true(len <= CS_FRAME_WIRE_MAX);
    uint64_t start = c->busy_until > now ? c->busy_until : now;
    c->busy_until = start + (len + c->bytes_per_tick - 1) / c->bytes_per_tick;
    c->frames++;
    if (c->cut)
        return;
    if (chance(c->drop_ppm)) {
        c->dropped++;
        return;
    }
    uint64_t due = c->busy_until + c->latency;
    if (chance(c->delay_ppm)) {
        due += 1 + rng() % c->delay_max;
        c->delayed++;
    }
    chan_push(c, b, len, due);
    if (chance(c->dup_ppm)) {
        chan_push(c, b, len, due + rng() % c->delay_max);
        c->duplicated++;
    }
}

/* Next chunk due at `now` (earliest due, then first sent), or NULL. Removed from the line. */
static int chan_take(chan_t *c, uint64_t now, chunk_t *out)
{
    int best = -1;
    for (int i = 0; i < c->n; i++)
        if (c->q[i].due <= now &&
            (best < 0 || c->q[i].due < c->q[best].due ||
             (c->q[i].due == c->q[best].due && c->q[i].order < c->q[best].order)))
            best = i;
    if (best < 0)
        return 0;
    *out = c->q[best];
    c->q[best] = c->q[--c->n];
    return 1;
}

/* --- the two ends ---------------------------------------------------------------------------- */
#define QUEUE 12

typedef struct {
    cs_link_t link;
    /* device side */
    cs_segment_t queue[QUEUE];
    int head, fill, max_fill;
    uint32_t delivered;   /* segments delivered (index of the next expected) */
    uint16_t first_seq;   /* sequence of index 0 for this boot */
    uint32_t first_index; /* index the stream restarts at after a reset */
    int64_t executed[CS_AXES];
    uint64_t executed_count;
    uint64_t next_exec; /* tick the executor may take the next segment */
    uint32_t statuses_sent;
    /* host side */
    uint32_t statuses_got;
    uint16_t status_seq_next;
    int opened, resets;
    cs_link_event_t reset_ev;
    uint64_t blocked;
} end_t;

/* rto: a window of 8 segment frames (8 x 15 ticks) + a round trip (~70 ticks) + margin.
 * give_up: with 1 % of bytes corrupted a 29-byte frame is lost 25 % of the time, so a lone
 * frame and its ACK get through 60 % of the time; timeouts of 400, 800, 1600, 1600 ... ticks
 * (rto_max = 4 rto) give 9 tries in 12000 ticks, failing together with p = 0.4^9 = 3e-4. */
static const cs_link_cfg_t cfg = {
    .rto = 400, .rto_max = 1600, .give_up = 12000, .nak_holdoff = 80, .keepalive = 3000};

static uint16_t free_slots(const end_t *e)
{
    return (uint16_t)(QUEUE - e->fill);
}

/* The device: take every byte from the line, queue delivered segments. */
static void device_rx(end_t *d, chan_t *in, uint64_t now)
{
    chunk_t k;
    while (chan_take(in, now, &k)) {
        for (int i = 0; i < k.len; i++) {
            cs_link_event_t ev;
            cs_err_t e = cs_link_feed(&d->link, k.bytes[i], (uint32_t)now, free_slots(d), &ev);
            assert_true(e == CS_OK || e == CS_ERR_CRC || e == CS_ERR_FRAME);
            if (!(ev.what & CS_LINK_EV_DELIVER))
                continue;
            cs_proto_msg_t m;
            assert_int_equal(cs_proto_decode(ev.payload, ev.len, &m), CS_OK);
            assert_int_equal(m.type, CS_PROTO_SEGMENT);
            uint32_t index = d->first_index + d->delivered;
            assert_int_equal(ev.seq, (uint16_t)(d->first_seq + d->delivered));
            cs_segment_t want = segment_of(index);
            assert_memory_equal(&m.u.segment, &want, sizeof want);
            assert_true(d->fill < QUEUE); /* the link promised room */
            d->queue[(d->head + d->fill) % QUEUE] = m.u.segment;
            d->fill++;
            if (d->fill > d->max_fill)
                d->max_fill = d->fill;
            d->delivered++;
        }
    }
}

/* The executor: one segment every `period` ticks on average, stalls now and then. */
static void device_exec(end_t *d, uint64_t now)
{
    if (d->fill == 0 || now < d->next_exec)
        return;
    cs_segment_t s = d->queue[d->head];
    d->head = (d->head + 1) % QUEUE;
    d->fill--;
    for (int a = 0; a < CS_AXES; a++)
        d->executed[a] += s.steps[a];
    d->executed_count++;
    d->next_exec = now + 8 + rng() % 12;
    if (chance(500)) /* a stall (dwell, hold): the queue fills up, credits run out */
        d->next_exec += 2000 + rng() % 4000;
}

static void device_status(end_t *d, uint64_t now)
{
    if (now % 2500 != 0 || !cs_link_can_send(&d->link, CS_PROTO_STATUS))
        return;
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_STATUS;
    m.u.status.state = CS_PROTO_STATE_RUNNING;
    m.u.status.boot_id = d->link.boot_id;
    m.u.status.queue_fill = (uint16_t)d->fill;
    m.u.status.last_seq = (uint16_t)(d->first_seq + d->delivered - 1u);
    m.u.status.axes = 4;
    for (int a = 0; a < 4; a++)
        m.u.status.pos[a] = (int32_t)d->executed[a];
    assert_int_equal(cs_link_send_msg(&d->link, &m, NULL), CS_OK);
    d->statuses_sent++;
}

static void host_rx(end_t *h, chan_t *in, uint64_t now)
{
    chunk_t k;
    while (chan_take(in, now, &k)) {
        for (int i = 0; i < k.len; i++) {
            cs_link_event_t ev;
            cs_err_t e = cs_link_feed(&h->link, k.bytes[i], (uint32_t)now, 4, &ev);
            assert_true(e == CS_OK || e == CS_ERR_CRC || e == CS_ERR_FRAME);
            if (ev.what & CS_LINK_EV_OPEN)
                h->opened++;
            if (ev.what & CS_LINK_EV_RESET) {
                h->resets++;
                h->reset_ev = ev;
            }
            if (ev.what & CS_LINK_EV_DELIVER) {
                cs_proto_msg_t m;
                assert_int_equal(cs_proto_decode(ev.payload, ev.len, &m), CS_OK);
                assert_int_equal(m.type, CS_PROTO_STATUS);
                if (h->statuses_got > 0)
                    assert_int_equal(ev.seq, h->status_seq_next);
                h->status_seq_next = (uint16_t)(ev.seq + 1u);
                h->statuses_got++;
            }
        }
    }
}

/* Push up to `total` segments (from *next_index) while the link takes them. */
static void host_send(end_t *h, uint32_t *next_index, uint32_t total)
{
    while (*next_index < total) {
        cs_proto_msg_t m = {0};
        m.type = CS_PROTO_SEGMENT;
        m.u.segment = segment_of(*next_index);
        cs_err_t e = cs_link_send_msg(&h->link, &m, NULL);
        if (e == CS_ERR_FULL || e == CS_ERR_STATE) {
            if (e == CS_ERR_FULL && h->link.blocked)
                h->blocked++;
            return;
        }
        assert_int_equal(e, CS_OK);
        (*next_index)++;
    }
}

/* Poll an end onto its outgoing line while the line is free; returns the poll's last error. */
static cs_err_t pump_out(end_t *e, chan_t *out, uint64_t now, uint16_t slots)
{
    while (chan_ready(out, now)) {
        const uint8_t *b;
        size_t n;
        cs_err_t r = cs_link_poll(&e->link, (uint32_t)now, slots, &b, &n);
        if (r != CS_OK)
            return r;
        chan_send(out, b, n, now);
    }
    return CS_OK;
}

typedef struct {
    end_t host, dev;
    chan_t h2d, d2h;
} sim_t;

static sim_t sim; /* large: static, not on the stack */

static void sim_init(uint64_t seed, uint32_t corrupt_ppm, uint32_t drop_ppm, uint16_t dev_first)
{
    rng_state = seed;
    memset(&sim, 0, sizeof sim);
    chan_init(&sim.h2d, corrupt_ppm, drop_ppm);
    chan_init(&sim.d2h, corrupt_ppm, drop_ppm);
    assert_int_equal(cs_link_init(&sim.host.link, &cfg, 0x40570001u, 0x1111u, 0, 0), CS_OK);
    assert_int_equal(cs_link_init(&sim.dev.link, &cfg, 0xDE000001u, 0x2222u, dev_first, 0), CS_OK);
    sim.dev.first_seq = dev_first;
}

/* One tick of the whole system. Returns the host poll's result (CS_ERR_TIMEOUT = closed). */
static cs_err_t sim_tick(uint64_t t, uint32_t *next_index, uint32_t total)
{
    host_rx(&sim.host, &sim.d2h, t);
    host_send(&sim.host, next_index, total);
    cs_err_t hr = pump_out(&sim.host, &sim.h2d, t, 4);
    device_rx(&sim.dev, &sim.h2d, t);
    device_exec(&sim.dev, t);
    device_status(&sim.dev, t);
    cs_err_t dr = pump_out(&sim.dev, &sim.d2h, t, free_slots(&sim.dev));
    if (dr != CS_OK && dr != CS_END)
        fail_msg("device poll: %d at tick %llu, state %d (base %u next %u heard_at %u timeouts %u"
                 " d2h frames %llu dropped %llu; delivered %u)",
                 dr, (unsigned long long)t, cs_link_state(&sim.dev.link), sim.dev.link.base,
                 sim.dev.link.next, sim.dev.link.heard_at, sim.dev.link.stats.timeouts,
                 (unsigned long long)sim.d2h.frames, (unsigned long long)sim.d2h.dropped,
                 sim.dev.delivered);
    return hr;
}

static void test_100k_segments_over_lossy_line(void **state)
{
    (void)state;
    enum { TOTAL = 100000 };
    /* The device's sequence starts 300 before the 16-bit wrap, and 100,000 > 65,536 wraps again. */
    sim_init(0x5EED0001ull, 10000, 10000, (uint16_t)(65536 - 300));
    uint32_t next_index = 0;
    uint64_t t = 0;
    int64_t sent_sum[CS_AXES] = {0};
    for (uint32_t i = 0; i < TOTAL; i++) {
        cs_segment_t s = segment_of(i);
        for (int a = 0; a < CS_AXES; a++)
            sent_sum[a] += s.steps[a];
    }
    for (; t < 20000000; t++) {
        cs_err_t hr = sim_tick(t, &next_index, TOTAL);
        assert_true(hr == CS_OK || hr == CS_END);
        if (next_index == TOTAL && cs_link_unacked(&sim.host.link) == 0 && sim.dev.fill == 0)
            break;
    }
    assert_true(t < 20000000);
    assert_int_equal(sim.host.opened, 1);
    assert_int_equal(sim.host.resets, 0);
    assert_int_equal(sim.dev.delivered, TOTAL);
    assert_int_equal(sim.dev.executed_count, TOTAL);
    for (int a = 0; a < CS_AXES; a++)
        assert_true(sim.dev.executed[a] == sent_sum[a]);
    /* Flow control: the queue filled up completely (stalls) but never overflowed, and the
     * device never had to refuse a segment for want of room. */
    assert_int_equal(sim.dev.max_fill, QUEUE);
    assert_int_equal(sim.dev.link.stats.refused, 0);
    assert_true(sim.host.blocked > 0);
    /* The line really was bad, and every recovery path ran. */
    const cs_link_stats_t *hs = &sim.host.link.stats, *ds = &sim.dev.link.stats;
    assert_true(sim.h2d.dropped > 500 && sim.h2d.corrupted > 10000 && sim.h2d.duplicated > 100 &&
                sim.h2d.delayed > 1000);
    assert_true(sim.dev.link.dec.stats.crc_errs + sim.dev.link.dec.stats.bad > 10000);
    assert_true(ds->duplicates > 0 && ds->out_of_order > 0);
    assert_true(hs->retransmits > 0 && hs->timeouts > 0 && hs->naks > 0 && hs->stale_acks > 0);
    /* Statuses flowed the other way, in order (checked as they arrived). */
    assert_true(sim.host.statuses_got > 100);
    print_message("100k: %llu ticks, h2d %llu frames (%llu dropped, %llu bytes corrupted, %llu dup,"
                  " %llu delayed); host retransmits %u timeouts %u naks %u stale acks %u; device"
                  " dups %u out-of-order %u crc %u bad %u; blocked %llu; statuses %u\n",
                  (unsigned long long)t, (unsigned long long)sim.h2d.frames,
                  (unsigned long long)sim.h2d.dropped, (unsigned long long)sim.h2d.corrupted,
                  (unsigned long long)sim.h2d.duplicated, (unsigned long long)sim.h2d.delayed,
                  hs->retransmits, hs->timeouts, hs->naks, hs->stale_acks, ds->duplicates,
                  ds->out_of_order, sim.dev.link.dec.stats.crc_errs, sim.dev.link.dec.stats.bad,
                  (unsigned long long)sim.host.blocked, sim.host.statuses_got);
}

/* The device reboots mid-job (its link re-initialised with a new boot id, its queue lost). The
 * host must report it, with the last sequence the old device acknowledged, and after a restart
 * stream on to the new device. */
static void test_device_reset_mid_stream(void **state)
{
    (void)state;
    enum { TOTAL = 20000, RESET_AFTER = 5000 };
    sim_init(0x5EED0002ull, 10000, 10000, 1000);
    uint32_t next_index = 0;
    uint64_t t = 0;
    uint32_t delivered_before_reset = 0;
    int reset_done = 0, restarted = 0;
    for (; t < 5000000; t++) {
        cs_err_t hr = sim_tick(t, &next_index, TOTAL);
        assert_true(hr == CS_OK || hr == CS_END);
        if (!reset_done && sim.dev.delivered >= RESET_AFTER) {
            delivered_before_reset = sim.dev.delivered;
            assert_int_equal(
                cs_link_init(&sim.dev.link, &cfg, 0xDE000002u, 0x3333u, 0, (uint32_t)t), CS_OK);
            sim.dev.fill = 0;
            sim.dev.delivered = 0;
            sim.dev.first_seq = 0;
            reset_done = 1;
        }
        if (reset_done && !restarted && sim.host.resets == 1) {
            const cs_link_event_t *ev = &sim.host.reset_ev;
            assert_int_equal(ev->old_boot, 0xDE000001u);
            assert_int_equal(ev->new_boot, 0xDE000002u);
            /* Everything up to last_acked was delivered by the old device; the acked count is at
             * most what it delivered and at most one window behind it. */
            uint32_t acked = (uint16_t)(ev->last_acked - 1000u + 1u);
            assert_true(acked <= delivered_before_reset);
            assert_true(delivered_before_reset - acked <= CS_LINK_WINDOW);
            assert_int_equal(ev->unacked, next_index - acked);
            assert_int_equal(cs_link_state(&sim.host.link), CS_LINK_RESET);
            uint8_t hold = CS_PROTO_HOLD;
            assert_int_equal(cs_link_send(&sim.host.link, &hold, 1, NULL), CS_ERR_STATE);
            /* The host resumes after the last acknowledged segment on the new device. */
            assert_int_equal(cs_link_restart(&sim.host.link, 0x4444u, (uint32_t)t), CS_OK);
            next_index = acked;
            sim.dev.first_index = acked;
            restarted = 1;
        }
        if (restarted && next_index == TOTAL && cs_link_unacked(&sim.host.link) == 0 &&
            sim.dev.fill == 0)
            break;
    }
    assert_true(t < 5000000);
    assert_int_equal(sim.host.resets, 1);
    assert_int_equal(sim.host.opened, 2);
    assert_int_equal(sim.dev.delivered, TOTAL - sim.dev.first_index); /* checked in order */
}

/* The line goes dead: the sender reports CS_ERR_TIMEOUT give_up after the last ACK it heard
 * (at most the line's latency before the cut), within one capped timeout; an idle end finds out
 * through its keepalive probes. */
static void test_dead_line_is_reported(void **state)
{
    (void)state;
    sim_init(0x5EED0003ull, 0, 0, 0);
    uint32_t next_index = 0;
    uint64_t t = 0, cut_at = 0, host_closed = 0, dev_closed = 0;
    for (; t < 200000; t++) {
        if (t == 20000) {
            sim.h2d.cut = sim.d2h.cut = 1;
            cut_at = t;
        }
        host_rx(&sim.host, &sim.d2h, t);
        host_send(&sim.host, &next_index, 1000000);
        cs_err_t hr = pump_out(&sim.host, &sim.h2d, t, 4);
        if (hr == CS_ERR_TIMEOUT) {
            assert_int_equal(host_closed, 0);
            host_closed = t;
        } else {
            assert_true(hr == CS_OK || hr == CS_END);
        }
        device_rx(&sim.dev, &sim.h2d, t);
        device_exec(&sim.dev, t);
        cs_err_t dr = pump_out(&sim.dev, &sim.d2h, t, free_slots(&sim.dev));
        if (dr == CS_ERR_TIMEOUT) {
            assert_int_equal(dev_closed, 0);
            dev_closed = t;
        }
        if (host_closed && dev_closed)
            break;
    }
    print_message("dead line: cut at %llu, host closed %llu ticks later, device %llu\n",
                  (unsigned long long)cut_at, (unsigned long long)(host_closed - cut_at),
                  (unsigned long long)(dev_closed - cut_at));
    assert_true(host_closed > cut_at && dev_closed > cut_at);
    assert_true(sim.dev.delivered > 500); /* it was working before the cut */
    assert_true(host_closed - cut_at + cfg.rto >= cfg.give_up);
    assert_true(host_closed - cut_at <= (uint64_t)cfg.give_up + cfg.rto_max);
    assert_true(dev_closed - cut_at <= (uint64_t)cfg.keepalive + cfg.give_up + cfg.rto_max);
    assert_int_equal(cs_link_state(&sim.host.link), CS_LINK_CLOSED);
    assert_int_equal(cs_link_state(&sim.dev.link), CS_LINK_CLOSED);
    uint8_t abort_msg = CS_PROTO_ABORT;
    assert_int_equal(cs_link_send(&sim.host.link, &abort_msg, 1, NULL), CS_ERR_STATE);
    /* Nothing more comes out of a closed sender (acks from its receiver side still would). */
    const uint8_t *b;
    size_t len;
    assert_int_equal(cs_link_poll(&sim.host.link, (uint32_t)t + 100000, 4, &b, &len), CS_END);
}

/* --- deterministic rules, lossless and step by step ----------------------------------------- */
static cs_link_t la, lb;

/* Move everything a has to say into b (and b's events into *ev_b, last one wins). */
static int move(cs_link_t *a, cs_link_t *b, uint32_t now, uint16_t a_slots, uint16_t b_slots,
                cs_link_event_t *ev_b, int *delivered)
{
    int frames = 0;
    const uint8_t *bytes;
    size_t n;
    while (cs_link_poll(a, now, a_slots, &bytes, &n) == CS_OK) {
        frames++;
        for (size_t i = 0; i < n; i++) {
            cs_link_event_t ev;
            cs_err_t e = cs_link_feed(b, bytes[i], now, b_slots, &ev);
            assert_true(e == CS_OK || e == CS_ERR_FULL);
            if (ev.what) {
                if (ev_b)
                    *ev_b = ev;
                if ((ev.what & CS_LINK_EV_DELIVER) && delivered)
                    (*delivered)++;
            }
        }
    }
    return frames;
}

static void connect_pair(uint16_t b_first, uint16_t b_slots)
{
    const cs_link_cfg_t c = {.rto = 100, .rto_max = 400, .give_up = 1500, .nak_holdoff = 10, .keepalive = 0};
    assert_int_equal(cs_link_init(&la, &c, 0xAAAA0001u, 77, 5, 0), CS_OK);
    assert_int_equal(cs_link_init(&lb, &c, 0xBBBB0001u, 88, b_first, 0), CS_OK);
    assert_int_equal(cs_link_state(&la), CS_LINK_CONNECTING);
    cs_link_event_t ev = {0};
    assert_int_equal(move(&la, &lb, 1, 0, b_slots, NULL, NULL), 1); /* the PING */
    assert_int_equal(move(&lb, &la, 2, b_slots, 0, &ev, NULL), 2);  /* ACK + b's own PING */
    assert_true(ev.what & CS_LINK_EV_OPEN);
    assert_int_equal(ev.new_boot, 0xBBBB0001u);
    assert_int_equal(cs_link_state(&la), CS_LINK_OPEN);
    assert_int_equal(cs_link_last_acked(&la), (uint16_t)(b_first - 1u));
    move(&la, &lb, 3, 0, b_slots, NULL, NULL); /* a's ACK to b's PING */
    assert_int_equal(cs_link_state(&lb), CS_LINK_OPEN);
}

static cs_err_t send_seg(cs_link_t *l)
{
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_SEGMENT;
    m.u.segment = segment_of(1);
    return cs_link_send_msg(l, &m, NULL);
}

static void test_seq_compare_wraps(void **state)
{
    (void)state;
    assert_true(cs_link_seq_before(0xFFFF, 0));
    assert_true(cs_link_seq_before(0xFFF0, 0x0010));
    assert_false(cs_link_seq_before(0x0010, 0xFFF0));
    assert_false(cs_link_seq_before(5, 5));
    assert_true(cs_link_seq_before(0, 0x7FFF));
    assert_false(cs_link_seq_before(0, 0x8001));
}

static void test_init_refuses_bad_config(void **state)
{
    (void)state;
    cs_link_cfg_t c = {.rto = 0, .rto_max = 10, .give_up = 1};
    assert_int_equal(cs_link_init(&la, &c, 1, 1, 0, 0), CS_ERR_ARG);
    c.rto = 10;
    c.give_up = 0;
    assert_int_equal(cs_link_init(&la, &c, 1, 1, 0, 0), CS_ERR_ARG);
    c.give_up = 1;
    c.rto_max = 9; /* a cap below the first timeout */
    assert_int_equal(cs_link_init(&la, &c, 1, 1, 0, 0), CS_ERR_ARG);
    c.rto_max = 10;
    assert_int_equal(cs_link_init(&la, &c, 1, 0, 0, 0), CS_ERR_ARG); /* nonce 0 */
    assert_int_equal(cs_link_init(&la, &c, 1, 1, 0, 0), CS_OK);
    /* Not open yet: nothing can be queued; ACK and PING are never user messages. */
    uint8_t hold = CS_PROTO_HOLD, ack = CS_PROTO_ACK;
    assert_int_equal(cs_link_send(&la, &hold, 1, NULL), CS_ERR_STATE);
    assert_int_equal(cs_link_send(&la, &ack, 1, NULL), CS_ERR_ARG);
    assert_int_equal(cs_link_send(&la, &hold, 0, NULL), CS_ERR_ARG);
}

/* An ACK that does not echo the PING's nonce (left over from an older session) is ignored. */
static void test_connect_ignores_foreign_ack(void **state)
{
    (void)state;
    const cs_link_cfg_t c = {.rto = 100, .rto_max = 400, .give_up = 1500, .nak_holdoff = 10, .keepalive = 0};
    assert_int_equal(cs_link_init(&la, &c, 1, 1234, 0, 0), CS_OK);
    const uint8_t *b;
    size_t n;
    assert_int_equal(cs_link_poll(&la, 0, 0, &b, &n), CS_OK); /* PING 1234 */
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_ACK;
    m.u.ack = (cs_proto_ack_t){0, 40, 5, 0xB007, 999};
    uint8_t p[CS_PROTO_LEN_ACK], w[CS_FRAME_WIRE_MAX];
    size_t pl, wl;
    assert_int_equal(cs_proto_encode(&m, p, sizeof p, &pl), CS_OK);
    assert_int_equal(cs_frame_encode(0, p, pl, w, sizeof w, &wl), CS_OK);
    cs_link_event_t ev;
    for (size_t i = 0; i < wl; i++)
        assert_int_equal(cs_link_feed(&la, w[i], 1, 0, &ev), CS_OK);
    assert_int_equal(cs_link_state(&la), CS_LINK_CONNECTING);
    m.u.ack.echo = 1234;
    assert_int_equal(cs_proto_encode(&m, p, sizeof p, &pl), CS_OK);
    assert_int_equal(cs_frame_encode(0, p, pl, w, sizeof w, &wl), CS_OK);
    for (size_t i = 0; i < wl; i++)
        assert_int_equal(cs_link_feed(&la, w[i], 2, 0, &ev), CS_OK);
    assert_int_equal(cs_link_state(&la), CS_LINK_OPEN);
    assert_int_equal(cs_link_last_acked(&la), 39);
    /* An ACK for a sequence never sent is a protocol error, reported and ignored. */
    m.u.ack.next_expected = 45;
    assert_int_equal(cs_proto_encode(&m, p, sizeof p, &pl), CS_OK);
    assert_int_equal(cs_frame_encode(0, p, pl, w, sizeof w, &wl), CS_OK);
    cs_err_t last = CS_OK;
    for (size_t i = 0; i < wl; i++)
        last = cs_link_feed(&la, w[i], 3, 0, &ev);
    assert_int_equal(last, CS_ERR_SEQ);
    assert_int_equal(cs_link_last_acked(&la), 39);
}

/* Credits bound slot-using messages, the window bounds everything. */
static void test_credits_and_window(void **state)
{
    (void)state;
    if (CS_LINK_WINDOW < 4)
        skip(); /* written for a window of at least 4 frames */
    connect_pair(0xFFFE, 3);
    for (int i = 0; i < 3; i++)
        assert_int_equal(send_seg(&la), CS_OK);
    assert_false(cs_link_can_send(&la, CS_PROTO_SEGMENT));
    assert_int_equal(send_seg(&la), CS_ERR_FULL);
    /* Control messages spend no credit, only window space. */
    uint8_t hold = CS_PROTO_HOLD;
    int extra = 0;
    while (cs_link_send(&la, &hold, 1, NULL) == CS_OK)
        extra++;
    assert_int_equal(extra, CS_LINK_WINDOW - 3);
    assert_int_equal(cs_link_unacked(&la), CS_LINK_WINDOW);
    /* Deliver them all; the device queues the 3 segments: 0 slots left. */
    int delivered = 0;
    move(&la, &lb, 10, 0, 3, NULL, &delivered);
    assert_int_equal(delivered, CS_LINK_WINDOW);
    move(&lb, &la, 11, 0, 0, NULL, NULL); /* ACK with 0 credits */
    assert_int_equal(cs_link_unacked(&la), 0);
    assert_int_equal(cs_link_last_acked(&la), (uint16_t)(0xFFFE + CS_LINK_WINDOW - 1));
    assert_int_equal(send_seg(&la), CS_ERR_FULL);
    /* The device's queue drains: its receiver volunteers a window update. */
    move(&lb, &la, 12, 2, 0, NULL, NULL);
    assert_true(cs_link_can_send(&la, CS_PROTO_SEGMENT));
    assert_int_equal(send_seg(&la), CS_OK);
    assert_int_equal(send_seg(&la), CS_OK);
    assert_int_equal(send_seg(&la), CS_ERR_FULL);
}

/* --- backoff (docs/protocol.md 3.3) ------------------------------------------------------- */
enum { BACKOFF_MAX = 64 };

/* The rule as the protocol states it: the peer was last heard at `heard`, the first frame goes
 * out at s0; the k-th timeout in a row fires min(rto * 2^k, rto_max) after the last send and
 * sends again, unless the peer has been silent for give_up: then the link closes there. at[]:
 * the sends; returns their number. */
static int backoff_expected(const cs_link_cfg_t *c, uint64_t heard, uint64_t s0, uint64_t *at,
                            uint64_t *closed)
{
    int n = 0;
    uint64_t s = s0, d = c->rto;
    at[n++] = s0;
    for (int k = 1;; k++) {
        uint64_t t = s + d;
        if (t - heard >= c->give_up) {
            *closed = t;
            return n;
        }
        assert_true(n < BACKOFF_MAX);
        at[n++] = s = t;
        d = (uint64_t)c->rto << (k < 32 ? k : 32);
        if (d > c->rto_max)
            d = c->rto_max;
    }
}

/* Polls l every step ticks from t0 with nobody answering: the ticks it wrote at, *closed = the
 * tick of CS_ERR_TIMEOUT. Returns the number of writes. */
static int backoff_observed(cs_link_t *l, uint64_t t0, uint64_t step, uint64_t *at,
                            uint64_t *closed)
{
    int n = 0;
    for (uint64_t t = t0;; t += step) {
        const uint8_t *b;
        size_t len;
        cs_err_t e = cs_link_poll(l, (uint32_t)t, 0, &b, &len);
        if (e == CS_ERR_TIMEOUT) {
            *closed = t;
            return n;
        }
        if (e == CS_OK) {
            assert_true(n < BACKOFF_MAX);
            at[n++] = t;
        }
        assert_true(t - t0 < 100000000u);
    }
}

static void assert_backoff(const cs_link_cfg_t *c, cs_link_t *l, uint64_t heard, uint64_t t0,
                           uint64_t step)
{
    uint64_t want[BACKOFF_MAX], got[BACKOFF_MAX], want_closed = 0, got_closed = 0;
    int nw = backoff_expected(c, heard, t0, want, &want_closed);
    int ng = backoff_observed(l, t0, step, got, &got_closed);
    assert_int_equal(ng, nw);
    for (int i = 0; i < nw; i++)
        assert_int_equal(got[i], want[i]);
    assert_int_equal(got_closed, want_closed);
    assert_int_equal(cs_link_state(l), CS_LINK_CLOSED);
}

/* A silent peer: the data frame's retransmissions and the connecting PINGs back off by doubling,
 * and the link closes when give_up has passed, not after a count. */
static void test_backoff_doubles_then_gives_up(void **state)
{
    (void)state;
    connect_pair(0, 8);
    assert_int_equal(send_seg(&la), CS_OK);
    cs_link_cfg_t c = la.cfg;
    /* last ACK at 2 (the connection); sends at 10, 110, 310, 710, 1110; closed at 1510 */
    assert_backoff(&c, &la, 2, 10, 1);
    assert_int_equal(la.stats.timeouts, 5);
    /* Connecting to nobody: the PINGs follow the same rule. */
    assert_int_equal(cs_link_init(&la, &c, 1, 99, 0, 0), CS_OK);
    assert_backoff(&c, &la, 0, 0, 1);
    /* The timing every end uses at memory speed, in microseconds: 5 ms doubling to 1 s, closed
     * 30 s after the silence began (tens of seconds of a starved peer survive). */
    assert_int_equal(cs_linktime_link(&c, 0, 1000000u), CS_OK);
    assert_int_equal(cs_link_init(&la, &c, 1, 99, 0, 0), CS_OK);
    uint64_t at[BACKOFF_MAX], closed = 0;
    int n = backoff_expected(&c, 0, 0, at, &closed);
    assert_true(closed >= 30000000u && closed <= 31000000u);
    print_message("memory speed: %d PINGs, closed %.3f s after the first\n", n, closed / 1e6);
    assert_backoff(&c, &la, 0, 0, 1000); /* every timeout is a whole number of ms */
}

/* The first good ACK after timeouts starts the backoff over at rto. */
static void test_backoff_resets_on_progress(void **state)
{
    (void)state;
    connect_pair(0, 8);
    assert_int_equal(send_seg(&la), CS_OK);
    const uint8_t *b;
    size_t n;
    uint64_t at[BACKOFF_MAX];
    int sends = 0;
    /* lost three times: sent at 10, then timeouts at 110 (+100), 310 (+200), 710 (+400) */
    for (uint32_t t = 10; t <= 710; t++)
        if (cs_link_poll(&la, t, 0, &b, &n) == CS_OK)
            at[sends++] = t;
    assert_int_equal(sends, 4);
    assert_int_equal(at[1], 110);
    assert_int_equal(at[2], 310);
    assert_int_equal(at[3], 710);
    /* the copy of 710 gets through, its ACK comes back */
    int delivered = 0;
    for (size_t i = 0; i < n; i++) {
        cs_link_event_t ev;
        assert_int_equal(cs_link_feed(&lb, b[i], 711, 8, &ev), CS_OK);
        delivered += (ev.what & CS_LINK_EV_DELIVER) != 0;
    }
    assert_int_equal(delivered, 1);
    move(&lb, &la, 712, 7, 0, NULL, NULL);
    assert_int_equal(cs_link_unacked(&la), 0);
    /* the next frame, lost: its first timeout is rto again (100), not 800 */
    assert_int_equal(send_seg(&la), CS_OK);
    sends = 0;
    for (uint32_t t = 800; t <= 1000 && sends < 2; t++)
        if (cs_link_poll(&la, t, 0, &b, &n) == CS_OK)
            at[sends++] = t;
    assert_int_equal(sends, 2);
    assert_int_equal(at[0], 800);
    assert_int_equal(at[1], 900);
}

/* Duplicates are dropped, a gap gets one NAK, the NAK rewinds the sender. */
static void test_duplicates_gaps_and_nak(void **state)
{
    (void)state;
    if (CS_LINK_WINDOW < 4)
        skip(); /* written for a window of at least 4 frames */
    connect_pair(100, 10);
    for (int i = 0; i < 4; i++)
        assert_int_equal(send_seg(&la), CS_OK);
    const uint8_t *b;
    size_t n;
    uint8_t frames[4][CS_FRAME_WIRE_MAX];
    size_t lens[4];
    for (int i = 0; i < 4; i++) {
        assert_int_equal(cs_link_poll(&la, 20, 0, &b, &n), CS_OK);
        memcpy(frames[i], b, n);
        lens[i] = n;
    }
    cs_link_event_t ev;
    int delivered = 0;
    /* Frame 0 twice, then 2 and 3 (1 lost). */
    const int order[] = {0, 0, 2, 3};
    for (int k = 0; k < 4; k++)
        for (size_t i = 0; i < lens[order[k]]; i++) {
            assert_int_equal(cs_link_feed(&lb, frames[order[k]][i], 21, 10, &ev), CS_OK);
            if (ev.what & CS_LINK_EV_DELIVER) {
                delivered++;
                assert_int_equal(ev.seq, 100);
            }
        }
    assert_int_equal(delivered, 1);
    assert_int_equal(lb.stats.duplicates, 1);
    assert_int_equal(lb.stats.out_of_order, 2);
    /* b's ACK: next expected 101, NAK set (one NAK for the gap, not two). */
    assert_int_equal(cs_link_poll(&lb, 22, 9, &b, &n), CS_OK);
    cs_frame_dec_t d;
    cs_frame_dec_init(&d);
    cs_frame_t f;
    cs_err_t e = CS_ERR_EMPTY;
    for (size_t i = 0; i < n; i++)
        e = cs_frame_dec_feed(&d, b[i], &f);
    assert_int_equal(e, CS_OK);
    cs_proto_msg_t m;
    assert_int_equal(cs_proto_decode(f.payload, f.len, &m), CS_OK);
    assert_int_equal(m.type, CS_PROTO_ACK);
    assert_int_equal(m.u.ack.next_expected, 101);
    assert_int_equal(m.u.ack.flags, CS_PROTO_ACK_NAK);
    assert_int_equal(m.u.ack.credits, 9);
    assert_int_equal(m.u.ack.boot_id, 0xBBBB0001u);
    /* a takes it at t = 40 (>= nak_holdoff after sending): rewinds to 101 and resends 1, 2, 3. */
    for (size_t i = 0; i < n; i++)
        assert_int_equal(cs_link_feed(&la, b[i], 40, 0, &ev), CS_OK);
    assert_int_equal(la.stats.naks, 1);
    delivered = 0;
    move(&la, &lb, 41, 0, 9, NULL, &delivered);
    assert_int_equal(delivered, 3);
    assert_int_equal(la.stats.retransmits, 3);
    move(&lb, &la, 42, 6, 0, NULL, NULL);
    assert_int_equal(cs_link_unacked(&la), 0);
}

/* A slot-using message that finds no room is refused (not delivered, not acknowledged) and
 * arrives with the retransmission once there is room. */
static void test_no_room_refuses_then_retransmits(void **state)
{
    (void)state;
    connect_pair(0, 1);
    /* a believes it has 1 credit; b's queue fills by other means before the segment arrives. */
    assert_int_equal(send_seg(&la), CS_OK);
    int delivered = 0;
    move(&la, &lb, 10, 0, 0, NULL, &delivered);
    assert_int_equal(delivered, 0);
    assert_int_equal(lb.stats.refused, 1);
    move(&lb, &la, 11, 0, 0, NULL, NULL);
    assert_int_equal(cs_link_unacked(&la), 1);
    /* rto later the segment goes again; now there is room. */
    move(&la, &lb, 10 + 100, 0, 1, NULL, &delivered);
    assert_int_equal(delivered, 1);
    assert_int_equal(la.stats.timeouts, 1);
}

/* A HELLO or STATUS with a new boot id tells the sender the peer restarted. */
static void test_new_boot_in_status_is_a_reset(void **state)
{
    (void)state;
    connect_pair(0, 4);
    for (int i = 0; i < 2; i++)
        assert_int_equal(send_seg(&la), CS_OK);
    move(&la, &lb, 10, 0, 4, NULL, NULL);
    move(&lb, &la, 11, 2, 0, NULL, NULL);
    assert_int_equal(send_seg(&la), CS_OK); /* in flight when the news arrives */
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_STATUS;
    m.u.status.axes = 3;
    m.u.status.boot_id = 0xBBBB0001u; /* same boot: nothing */
    assert_int_equal(cs_link_send_msg(&lb, &m, NULL), CS_OK);
    cs_link_event_t ev = {0};
    move(&lb, &la, 12, 2, 0, &ev, NULL);
    assert_int_equal(ev.what, CS_LINK_EV_DELIVER);
    m.u.status.boot_id = 0xBBBB0002u;
    assert_int_equal(cs_link_send_msg(&lb, &m, NULL), CS_OK);
    move(&lb, &la, 13, 2, 0, &ev, NULL);
    assert_int_equal(ev.what, CS_LINK_EV_DELIVER | CS_LINK_EV_RESET);
    assert_int_equal(ev.old_boot, 0xBBBB0001u);
    assert_int_equal(ev.new_boot, 0xBBBB0002u);
    assert_int_equal(ev.last_acked, 1);
    assert_int_equal(ev.unacked, 1);
    assert_int_equal(cs_link_state(&la), CS_LINK_RESET);
}

/* A restarted sender (host program restarted, device untouched) joins the receiver's sequence
 * where it stands: nothing delivered twice, nothing skipped. */
static void test_sender_restart_continues_sequence(void **state)
{
    (void)state;
    if (CS_LINK_WINDOW < 4)
        skip(); /* written for a window of at least 4 frames */
    connect_pair(500, 8);
    int delivered = 0;
    for (int i = 0; i < 3; i++)
        assert_int_equal(send_seg(&la), CS_OK);
    move(&la, &lb, 10, 0, 8, NULL, &delivered);
    move(&lb, &la, 11, 5, 0, NULL, NULL);
    assert_int_equal(delivered, 3);
    assert_int_equal(cs_link_restart(&la, 0, 12), CS_ERR_ARG);
    assert_int_equal(cs_link_restart(&la, 99, 12), CS_OK);
    assert_int_equal(cs_link_state(&la), CS_LINK_CONNECTING);
    assert_int_equal(cs_link_unacked(&la), 0);
    cs_link_event_t ev = {0};
    move(&la, &lb, 13, 0, 5, NULL, NULL); /* PING 99 */
    move(&lb, &la, 14, 5, 0, &ev, NULL);
    assert_true(ev.what & CS_LINK_EV_OPEN);
    assert_int_equal(ev.last_acked, 502);
    uint16_t seq = 0;
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_SEGMENT;
    m.u.segment = segment_of(7);
    assert_int_equal(cs_link_send_msg(&la, &m, &seq), CS_OK);
    assert_int_equal(seq, 503);
    move(&la, &lb, 15, 0, 5, &ev, &delivered);
    assert_int_equal(delivered, 4);
    assert_int_equal(ev.seq, 503);
    assert_int_equal(lb.stats.duplicates, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_seq_compare_wraps),
        cmocka_unit_test(test_init_refuses_bad_config),
        cmocka_unit_test(test_connect_ignores_foreign_ack),
        cmocka_unit_test(test_credits_and_window),
        cmocka_unit_test(test_duplicates_gaps_and_nak),
        cmocka_unit_test(test_no_room_refuses_then_retransmits),
        cmocka_unit_test(test_new_boot_in_status_is_a_reset),
        cmocka_unit_test(test_sender_restart_continues_sequence),
        cmocka_unit_test(test_backoff_doubles_then_gives_up),
        cmocka_unit_test(test_backoff_resets_on_progress),
        cmocka_unit_test(test_dead_line_is_reported),
        cmocka_unit_test(test_device_reset_mid_stream),
        cmocka_unit_test(test_100k_segments_over_lossy_line),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
