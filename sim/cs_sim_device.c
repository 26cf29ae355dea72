/* cs_sim_device: the simulated device behind a serial line. See cs_sim_device.h and
 * docs/streaming.md ("The device's pacing"). */
#include "cs_sim_device.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cs_planner.h"
#include "cs_segment.h"
#include "cs_stepper.h"
#include "cs_stream.h"
#include "cs_trace.h"
#include "port_posix.h"

/* Items whose sequence is remembered between leaving the queue and being executed: more than
 * the planner ring + the executor ring + the curve being traced. */
#define SEQ_MAP   1024
#define SEQ_MASK  (SEQ_MAP - 1)
#define ERR_QUEUE 8

typedef struct {
    cs_proto_msg_t msg;
    uint16_t seq;
} qitem_t;

typedef struct {
    uint64_t item; /* device item number (1-based) the segment belongs to */
    bool item_end; /* last segment of that item (SEGMENT messages: always) */
} tag_t;

struct cs_sim_motion {
    const cs_sim_device_cfg_t *cfg;
    const cs_machine_t *m;
    cs_sim_device_result_t *res;
    cs_serial_t ser;
    cs_link_t link;
    uint32_t boot;
    uint32_t nonce;
    /* motion queue */
    qitem_t q[CS_SIM_DEVICE_QUEUE_MAX];
    unsigned qhead, qcount;
    /* executor */
    cs_stepper_t st;
    tag_t tags[CS_STEPPER_RING];
    uint64_t pushed, completed;
    /* curves */
    cs_planner_t pl;
    cs_segment_gen_t gen;
    bool gen_busy; /* a block is being cut */
    bool tracing;
    bool rapid_pending; /* travel to the curve's P0 still to queue */
    cs_vec3_t rapid_to;
    cs_trace_t tr;
    int32_t tr_feed;
    uint64_t tr_item;
    bool pl_stale; /* SEGMENT messages moved the machine: planner position to refresh */
    int64_t steps_pos[CS_AXES]; /* position after everything pushed, steps */
    /* items */
    uint64_t popped;            /* items taken from the queue since serve started */
    uint16_t item_seq[SEQ_MAP]; /* sequence of item k at [k & SEQ_MASK] */
    uint64_t exec_item;         /* items executed */
    uint16_t exec_seq;          /* sequence of the last item executed */
    bool have_prev;
    uint16_t prev_seq;
    /* state */
    uint8_t state; /* cs_proto_state_t */
    bool held, aborted;
    uint8_t sent_state;
    bool status_due;
    uint32_t status_at;
    /* fault at N: stop taking items after N, drain, report, then act */
    uint64_t fault_at;
    int fault_kind;  /* 0 none, 1 reset, 2 hang, 3 close */
    int fault_phase; /* 0 waiting, 1 draining, 2 status sent */
    uint32_t fault_status_at;
    bool hung;
    /* errors to send */
    cs_proto_error_t errs[ERR_QUEUE];
    unsigned nerr;
    /* pacing */
    double anchor_wall;
    uint64_t anchor_ticks;
    bool dry; /* the executor ran dry after executing something */
    double dry_since;
    double last_rx_s;
    uint8_t inv; /* DIR lines inverted (port_posix_reset) */
};
typedef struct cs_sim_motion sim_dev_t;

uint64_t cs_sim_device_hash(uint64_t h, const cs_segment_t *s)
{
    uint8_t b[4 + 4 * CS_AXES];
    uint32_t v = s->ticks;
    for (unsigned k = 0; k < 4; k++)
        b[k] = (uint8_t)(v >> (8 * k));
    for (unsigned i = 0; i < CS_AXES; i++) {
        uint32_t u = (uint32_t)s->steps[i];
        for (unsigned k = 0; k < 4; k++)
            b[4 + 4 * i + k] = (uint8_t)(u >> (8 * k));
    }
    for (size_t k = 0; k < sizeof b; k++) {
        h ^= b[k];
        h *= 0x100000001b3ull;
    }
    return h;
}

void cs_sim_device_cfg_default(cs_sim_device_cfg_t *cfg, const cs_machine_t *m)
{
    memset(cfg, 0, sizeof *cfg);
    cfg->m = m;
    cfg->queue_size = 32;
    cfg->speed = 1.0;
    cfg->method = CS_TRACE_DEFAULT;
    cfg->status_ms = 50;
}

/* --- link plumbing ------------------------------------------------------------------------ */

static uint16_t free_slots(const sim_dev_t *d)
{
    return (uint16_t)(d->cfg->queue_size - d->qcount);
}

static uint32_t new_nonce(sim_dev_t *d)
{
    d->nonce = d->nonce * 1664525u + 1013904223u;
    return d->nonce ? d->nonce : 1u;
}

static void push_error(sim_dev_t *d, cs_err_t code, uint16_t seq)
{
    if (d->nerr < ERR_QUEUE)
        d->errs[d->nerr++] = (cs_proto_error_t){(uint8_t)code, seq};
}

static void send_hello(sim_dev_t *d)
{
    cs_proto_msg_t h = {.type = CS_PROTO_HELLO};
    h.u.hello.version = CS_PROTO_VERSION;
    h.u.hello.boot_id = d->boot;
    h.u.hello.axes = d->m->n_axes;
    h.u.hello.queue_size = d->cfg->queue_size;
    h.u.hello.tick_hz = d->m->tick_hz;
    h.u.hello.caps = CS_PROTO_CAP_ALL;
    cs_link_send_msg(&d->link, &h, NULL); /* first message of a fresh sender: room is there */
    d->status_due = true;
}

static void send_status(sim_dev_t *d, uint32_t now)
{
    if (!cs_link_can_send(&d->link, CS_PROTO_STATUS))
        return;
    cs_proto_msg_t s = {.type = CS_PROTO_STATUS};
    s.u.status.state = d->state;
    s.u.status.boot_id = d->boot;
    s.u.status.queue_fill = (uint16_t)d->qcount;
    s.u.status.last_seq = d->exec_seq;
    s.u.status.axes = d->m->n_axes;
    for (unsigned i = 0; i < d->m->n_axes; i++)
        s.u.status.pos[i] = cs_stepper_position(&d->st, i);
    if (cs_link_send_msg(&d->link, &s, NULL) == CS_OK) {
        d->status_due = false;
        d->status_at = now;
        d->sent_state = d->state;
    }
}

static void write_out(sim_dev_t *d, const uint8_t *b, size_t n)
{
    if (cs_serial_write(&d->ser, b, n) != 0)
        d->ser.lost += n; /* a device UART never blocks: bytes nobody takes are gone */
}

static void flush_link(sim_dev_t *d, uint32_t now)
{
    for (int k = 0; k < 64; k++) {
        const uint8_t *b;
        size_t n;
        cs_err_t e = cs_link_poll(&d->link, now, free_slots(d), &b, &n);
        if (e == CS_END)
            return;
        if (e == CS_ERR_TIMEOUT) { /* the host went away: wait for the next one */
            cs_link_restart(&d->link, new_nonce(d), now);
            continue;
        }
        if (e == CS_OK)
            write_out(d, b, n);
    }
}

/* --- motion -------------------------------------------------------------------------------- */

/* Everything taken from the queue has been executed (the queue itself may hold more). */
static bool drained(const sim_dev_t *d)
{
    return !d->tracing && !d->gen_busy && cs_planner_count(&d->pl) == 0 && cs_stepper_idle(&d->st);
}

static bool everything_done(const sim_dev_t *d)
{
    return d->qcount == 0 && drained(d);
}

static bool may_take_item(const sim_dev_t *d)
{
    if (d->held || d->hung)
        return false;
    if (d->fault_kind != 0 && d->popped >= d->fault_at)
        return false;
    return true;
}

static void note_completed(sim_dev_t *d)
{
    uint8_t inring = (uint8_t)(d->st.tail - d->st.head);
    uint64_t done = d->pushed - inring - (d->st.running ? 1u : 0u);
    while (d->completed < done) {
        const tag_t *t = &d->tags[d->completed & (CS_STEPPER_RING - 1)];
        uint64_t item = t->item_end ? t->item : t->item - 1;
        if (item > d->exec_item) {
            d->res->executed += item - d->exec_item;
            d->exec_item = item;
            d->exec_seq = d->item_seq[item & SEQ_MASK];
        }
        d->completed++;
    }
    if (drained(d) && d->exec_item < d->popped) {
        d->res->executed += d->popped - d->exec_item;
        d->exec_item = d->popped;
        d->exec_seq = d->item_seq[d->popped & SEQ_MASK];
    }
}

static cs_pos_t steps_to_pos(int64_t steps, int32_t spm)
{
    /* mm Q16 = steps * 2^16 / (spm Q16 / 2^16), rounded to nearest */
    int64_t num = steps * ((int64_t)1 << 32);
    int64_t q = num >= 0 ? (num + spm / 2) / spm : -((-num + spm / 2) / spm);
    return (cs_pos_t)q;
}

static void refresh_planner(sim_dev_t *d)
{
    if (!d->pl_stale || cs_planner_count(&d->pl) != 0)
        return;
    cs_pos_t p[CS_AXES] = {0, 0, 0, 0};
    for (unsigned i = 0; i < d->m->n_axes; i++)
        p[i] = steps_to_pos(d->steps_pos[i], d->m->axis[i].steps_per_mm);
    cs_planner_set_position(&d->pl, p);
    d->pl_stale = false;
}

static void pop_item(sim_dev_t *d, qitem_t *out)
{
    *out = d->q[d->qhead];
    d->qhead = (d->qhead + 1) % CS_SIM_DEVICE_QUEUE_MAX;
    d->qcount--;
    d->popped++;
    d->item_seq[d->popped & SEQ_MASK] = out->seq;
}

static void start_curve(sim_dev_t *d, const qitem_t *it)
{
    refresh_planner(d);
    cs_bezier_t c;
    cs_err_t e = cs_bezier_init(&c, 3, it->msg.u.curve.p);
    cs_pos_t tol = d->cfg->tol > 0 ? d->cfg->tol : d->m->tolerance;
    if (e == CS_OK)
        e = cs_trace_begin(&d->tr, &c, tol, (cs_trace_method_t)d->cfg->method);
    if (e != CS_OK) {
        push_error(d, e, it->seq);
        return;
    }
    d->tracing = true;
    d->tr_feed = it->msg.u.curve.feed;
    d->tr_item = d->popped;
    const cs_vec3_t *p0 = &it->msg.u.curve.p[0];
    d->rapid_pending = p0->x != d->pl.pos[0] || p0->y != d->pl.pos[1] || p0->z != d->pl.pos[2];
    d->rapid_to = *p0;
    d->res->curves++;
}

/* Next step segment for the executor: 1 with *s and *t set, 0 when nothing is ready. */
static int next_segment(sim_dev_t *d, cs_segment_t *s, tag_t *t)
{
    for (int guard = 0; guard < 4096; guard++) {
        bool feeding = d->tracing || (d->qcount > 0 && may_take_item(d) &&
                                      d->q[d->qhead].msg.type == CS_PROTO_CURVE);
        /* Cut when the look-ahead is full or nothing more can be added now (the planner
         * always plans its last block to end at rest, so cutting early is safe). */
        if (d->gen_busy ||
            (cs_planner_count(&d->pl) > 0 && (cs_planner_full(&d->pl) || !feeding))) {
            if (d->held)
                return 0;
            cs_err_t e = cs_segment_next(&d->gen, &d->pl, s);
            if (e == CS_ERR_EMPTY) {
                d->gen_busy = false;
                continue;
            }
            if (e != CS_OK) {
                push_error(d, e, d->item_seq[d->gen.line & SEQ_MASK]);
                d->gen_busy = false;
                cs_planner_init(&d->pl, d->m);
                d->pl_stale = true;
                return 0;
            }
            d->gen_busy = !cs_segment_block_end(&d->gen);
            /* blocks carry their item number as "line" (32-bit): rebuild the 64-bit one */
            *t = (tag_t){(d->popped & ~(uint64_t)0xFFFFFFFFu) | d->gen.line, false};
            if (t->item > d->popped)
                t->item -= (uint64_t)1 << 32;
            return 1;
        }
        if (d->tracing) {
            cs_vec3_t pt;
            cs_err_t e;
            if (d->rapid_pending) {
                pt = d->rapid_to;
                e = cs_planner_line3(&d->pl, &pt, 0, (uint32_t)d->tr_item);
                d->rapid_pending = false;
            } else {
                e = cs_trace_next(&d->tr, &pt);
                if (e == CS_END) {
                    d->tracing = false;
                    continue;
                }
                if (e == CS_OK)
                    e = cs_planner_line3(&d->pl, &pt, d->tr_feed, (uint32_t)d->tr_item);
            }
            if (e != CS_OK) {
                push_error(d, e, d->item_seq[d->tr_item & SEQ_MASK]);
                d->tracing = false;
            }
            continue;
        }
        if (d->qcount == 0 || !may_take_item(d))
            return 0;
        if (d->q[d->qhead].msg.type == CS_PROTO_CURVE) {
            qitem_t it;
            pop_item(d, &it);
            start_curve(d, &it);
            continue;
        }
        qitem_t it;
        pop_item(d, &it);
        *s = it.msg.u.segment;
        *t = (tag_t){d->popped, true};
        d->pl_stale = true;
        return 1;
    }
    return 0;
}

/* Keeps the executor's ring full. Returns segments pushed. */
static unsigned feed(sim_dev_t *d)
{
    unsigned n = 0;
    while (cs_stepper_free(&d->st) > 0) {
        cs_segment_t s;
        tag_t t;
        if (next_segment(d, &s, &t) != 1)
            break;
        cs_err_t e = cs_stepper_push(&d->st, &s);
        if (e != CS_OK) { /* cs_proto checked the invariant already; keep going */
            push_error(d, e, d->item_seq[t.item & SEQ_MASK]);
            continue;
        }
        d->tags[d->pushed & (CS_STEPPER_RING - 1)] = t;
        d->pushed++;
        n++;
        d->res->segments++;
        if (t.item_end)
            d->res->seg_hash = cs_sim_device_hash(d->res->seg_hash, &s);
        for (unsigned i = 0; i < CS_AXES; i++)
            d->steps_pos[i] += s.steps[i];
    }
    return n;
}

static void advance(sim_dev_t *d, double wall)
{
    double hz = (double)d->m->tick_hz;
    unsigned pushed_now = 0;
    if (d->cfg->speed <= 0) {
        /* instant: run everything available, a bounded amount per call */
        for (int k = 0; k < 256; k++) {
            pushed_now += feed(d);
            if (cs_stepper_idle(&d->st))
                break;
            port_posix_run(UINT64_MAX);
            note_completed(d);
        }
    } else {
        if (cs_stepper_idle(&d->st)) {
            d->anchor_wall = wall;
            d->anchor_ticks = port_posix_now();
        }
        double t = (double)d->anchor_ticks + (wall - d->anchor_wall) * d->cfg->speed * hz;
        uint64_t target = t >= 1.8e19 ? UINT64_MAX : (uint64_t)t;
        for (int k = 0; k < 4096; k++) {
            pushed_now += feed(d);
            if (cs_stepper_idle(&d->st))
                break;
            port_posix_run(target);
            note_completed(d);
            if (port_posix_now() >= target)
                break;
        }
    }
    note_completed(d);
    if (pushed_now > 0 && d->dry) {
        d->res->exec_gaps++;
        d->res->gap_wall_s += wall - d->dry_since;
        d->dry = false;
    }
    if (cs_stepper_idle(&d->st) && !d->dry && d->exec_item > 0 && !d->held) {
        d->dry = true;
        d->dry_since = wall;
    }
    uint8_t st = d->held               ? CS_PROTO_STATE_HELD
                 : !everything_done(d) ? CS_PROTO_STATE_RUNNING
                 : d->aborted          ? CS_PROTO_STATE_ABORTED
                                       : CS_PROTO_STATE_IDLE;
    if (st != d->state) {
        d->state = st;
        d->status_due = true;
    }
}

static void do_abort(sim_dev_t *d)
{
    d->qcount = 0;
    d->tracing = false;
    d->rapid_pending = false;
    /* the executor's ring finishes (at most CS_STEPPER_RING segments), the rest is dropped */
    if (d->gen_busy || cs_planner_count(&d->pl) > 0) {
        cs_planner_init(&d->pl, d->m);
        cs_segment_init(&d->gen, d->m);
        d->gen_busy = false;
    }
    d->pl_stale = true;
    /* items taken and dropped count as done for the executed sequence */
    d->held = false;
    d->aborted = true;
    d->res->aborts++;
}

static void on_deliver(sim_dev_t *d, const cs_link_event_t *ev)
{
    if (d->have_prev && ev->seq != (uint16_t)(d->prev_seq + 1u))
        d->res->out_of_order++;
    d->have_prev = true;
    d->prev_seq = ev->seq;
    cs_proto_msg_t m;
    cs_err_t e = cs_proto_decode(ev->payload, ev->len, &m);
    if (e != CS_OK) {
        push_error(d, e == CS_ERR_ARG ? CS_ERR_FRAME : e, ev->seq);
        return;
    }
    switch (m.type) {
    case CS_PROTO_SEGMENT:
    case CS_PROTO_CURVE:
        if (cs_sim_motion_queue(d, &m, ev->seq) != CS_OK) /* cs_link refuses it first */
            push_error(d, CS_ERR_FULL, ev->seq);
        break;
    case CS_PROTO_HOLD:
        d->held = true;
        d->res->holds++;
        d->status_due = true;
        break;
    case CS_PROTO_RESUME:
        d->held = false;
        d->status_due = true;
        break;
    case CS_PROTO_ABORT:
        do_abort(d);
        d->status_due = true;
        break;
    default:
        push_error(d, CS_ERR_UNSUPPORTED, ev->seq);
        break;
    }
}

/* (Re)boots the device's link: a new boot id (id, or a fresh one when 0), the receiver back at
 * sequence 0, the queue lost. The executor and its position are kept (a machine that homes). */
static void boot(sim_dev_t *d, uint32_t now, uint32_t id)
{
    if (id == 0) {
        id = d->boot * 2654435761u + 0x9E3779B9u + new_nonce(d);
        if (id == 0 || id == d->boot)
            id = d->boot + 1u;
    }
    d->boot = id;
    /* link timing in microseconds for the device's line rate (cs_stream_link_timing): the NAK
     * hold-off must stay below a round trip, a fraction of a millisecond on a pty */
    cs_link_cfg_t lc = {.keepalive = 0, .max_retries = 20};
    cs_stream_link_timing(&lc, d->cfg->line_rate);
    cs_link_init(&d->link, &lc, d->boot, new_nonce(d), 0, now);
    d->qcount = 0;
    d->qhead = 0;
    /* nothing of this boot executed yet: the last executed sequence is the one before the
     * receiver's first (a host reads STATUS.last_seq against its own first sequence) */
    d->exec_seq = 0xFFFFu;
    d->item_seq[d->popped & SEQ_MASK] = 0xFFFFu;
    d->have_prev = false;
    d->held = false;
    d->aborted = false;
    d->nerr = 0;
    d->res->boot_id = d->boot;
}

/* The fault scheduled at item N: after item N is executed and reported, act. Returns true when
 * serve must return (close). */
static bool run_fault(sim_dev_t *d, uint32_t now)
{
    if (d->fault_kind == 0 || d->popped < d->fault_at || !drained(d))
        return false;
    if (d->fault_phase == 0) {
        d->status_due = true;
        send_status(d, now);
        if (!d->status_due) {
            d->fault_phase = 1;
            d->fault_status_at = now;
        }
        return false;
    }
    /* wait until the STATUS saying so was acknowledged (or 500 ms; times in us) */
    if (cs_link_unacked(&d->link) != 0 && (uint32_t)(now - d->fault_status_at) < 500000u)
        return false;
    int kind = d->fault_kind;
    d->fault_kind = 0;
    d->fault_phase = 0;
    if (kind == 1) {
        d->res->resets++;
        boot(d, now, 0);
    } else if (kind == 2) {
        d->hung = true;
    } else {
        return true;
    }
    return false;
}

static void sleep_ms(int ms)
{
    struct timespec ts = {0, (long)ms * 1000000L};
    nanosleep(&ts, NULL);
}

cs_err_t cs_sim_device_serve(int fd, const cs_sim_device_cfg_t *cfg, volatile sig_atomic_t *stop,
                             cs_sim_device_result_t *res)
{
    sim_dev_t *d;
    cs_err_t e = cs_sim_motion_open(&d, cfg, res);
    if (e != CS_OK)
        return e;
    cs_serial_attach(&d->ser, fd);
    cs_serial_set_lossy(&d->ser, true);
    cs_serial_set_line_rate(&d->ser, cfg->line_rate);
    cs_serial_set_faults(&d->ser, &cfg->faults);
    double start = cs_serial_now_s();
    d->nonce = (uint32_t)getpid() ^ (uint32_t)(start * 1e6);
    d->boot = d->nonce ^ 0xA5A5A5A5u;
    uint32_t now = cs_serial_now_us();
    boot(d, now, cfg->boot_id);
    if (cfg->reset_after) {
        d->fault_kind = 1;
        d->fault_at = cfg->reset_after;
    } else if (cfg->hang_after) {
        d->fault_kind = 2;
        d->fault_at = cfg->hang_after;
    } else if (cfg->close_after) {
        d->fault_kind = 3;
        d->fault_at = cfg->close_after;
    }
    d->state = CS_PROTO_STATE_IDLE;
    d->status_due = true;
    d->last_rx_s = start;
    uint32_t status_period = cfg->status_ms ? cfg->status_ms : 50;
    cs_err_t rc = CS_OK;
    uint8_t buf[4096];
    while (stop == NULL || !*stop) {
        double wall = cs_serial_now_s();
        now = cs_serial_now_us();
        if (d->hung) {
            sleep_ms(10);
            continue;
        }
        bool busy = !everything_done(d) && !d->held;
        ssize_t n = cs_serial_read(&d->ser, buf, sizeof buf, busy ? 1 : 5);
        if (n < 0) {
            if (errno == EIO || errno == EBADF) { /* the line is gone */
                rc = CS_ERR_IO;
                break;
            }
            sleep_ms(5);
            n = 0;
        }
        if (n > 0)
            d->last_rx_s = wall;
        now = cs_serial_now_us();
        for (ssize_t k = 0; k < n; k++) {
            uint8_t b = buf[k];
            if (cfg->corrupt_in > 0) {
                /* the same xorshift as the write side: corrupt what arrives too */
                uint64_t x = d->ser.rng;
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                d->ser.rng = x;
                if ((double)(x >> 11) * (1.0 / 9007199254740992.0) < cfg->corrupt_in) {
                    b ^= (uint8_t)(1u + (uint8_t)((x >> 3) % 255u));
                    d->ser.corrupted++;
                }
            }
            cs_link_event_t ev;
            cs_err_t fe = cs_link_feed(&d->link, b, now, free_slots(d), &ev);
            if (fe != CS_OK)
                continue;
            if (ev.what & CS_LINK_EV_DELIVER)
                on_deliver(d, &ev);
            if (ev.what & CS_LINK_EV_RESET) /* the host restarted: join the new one */
                cs_link_restart(&d->link, new_nonce(d), now);
            if (ev.what & CS_LINK_EV_OPEN)
                send_hello(d);
        }
        advance(d, cs_serial_now_s());
        now = cs_serial_now_us();
        while (d->nerr > 0 && cs_link_can_send(&d->link, CS_PROTO_ERROR)) {
            cs_proto_msg_t em = {.type = CS_PROTO_ERROR};
            em.u.error = d->errs[0];
            if (cs_link_send_msg(&d->link, &em, NULL) != CS_OK)
                break;
            memmove(d->errs, d->errs + 1, (d->nerr - 1) * sizeof d->errs[0]);
            d->nerr--;
            res->errors_sent++;
        }
        uint32_t period = (d->state == CS_PROTO_STATE_RUNNING || d->state == CS_PROTO_STATE_HELD)
                              ? status_period
                              : 250u;
        if (cs_link_state(&d->link) == CS_LINK_OPEN &&
            (d->status_due || (uint32_t)(now - d->status_at) >= period * 1000u))
            send_status(d, now);
        if (run_fault(d, now))
            break;
        flush_link(d, now);
        if (cfg->idle_exit_s > 0 && d->exec_item > 0 && everything_done(d) &&
            wall - d->last_rx_s > cfg->idle_exit_s)
            break;
    }
    res->link = d->link.stats;
    res->frames = d->link.dec.stats;
    res->bytes_in = d->ser.bytes_in;
    res->bytes_out = d->ser.bytes_out;
    res->wall_s = cs_serial_now_s() - start;
    cs_err_t ce = cs_sim_motion_close(d);
    return rc != CS_OK ? rc : ce;
}

/* --- the motion side, shared with the Modbus device ---------------------------------------- */

cs_err_t cs_sim_motion_open(sim_dev_t **out, const cs_sim_device_cfg_t *cfg,
                            cs_sim_device_result_t *res)
{
    *out = NULL;
    memset(res, 0, sizeof *res);
    res->seg_hash = CS_SIM_DEVICE_HASH0;
    if (cfg == NULL || cfg->m == NULL || cfg->queue_size < 1 ||
        cfg->queue_size > CS_SIM_DEVICE_QUEUE_MAX)
        return CS_ERR_ARG;
    sim_dev_t *d = calloc(1, sizeof *d);
    if (d == NULL)
        return CS_ERR_FULL;
    d->cfg = cfg;
    d->m = cfg->m;
    d->res = res;
    cs_err_t e = cs_stepper_init(&d->st, d->m);
    if (e == CS_OK)
        e = cs_planner_init(&d->pl, d->m);
    if (e == CS_OK)
        e = cs_segment_init(&d->gen, d->m);
    if (e != CS_OK) {
        free(d);
        return CS_ERR_ARG;
    }
    for (unsigned i = 0; i < d->m->n_axes; i++)
        if (d->m->axis[i].invert_dir)
            d->inv = (uint8_t)(d->inv | (1u << i));
    port_posix_reset(d->m->tick_hz, d->inv);
    port_posix_record(true);
    port_stepper_attach(&d->st);
    d->exec_seq = 0xFFFFu;
    d->item_seq[0] = 0xFFFFu;
    d->state = CS_PROTO_STATE_IDLE;
    *out = d;
    return CS_OK;
}

cs_err_t cs_sim_motion_queue(sim_dev_t *d, const cs_proto_msg_t *m, uint16_t seq)
{
    if (m->type != CS_PROTO_SEGMENT && m->type != CS_PROTO_CURVE)
        return CS_ERR_UNSUPPORTED;
    if (d->qcount >= d->cfg->queue_size)
        return CS_ERR_FULL;
    d->q[(d->qhead + d->qcount) % CS_SIM_DEVICE_QUEUE_MAX] = (qitem_t){*m, seq};
    d->qcount++;
    d->aborted = false;
    return CS_OK;
}

void cs_sim_motion_hold(sim_dev_t *d, bool on)
{
    if (on && !d->held)
        d->res->holds++;
    d->held = on;
    d->status_due = true;
}

void cs_sim_motion_abort(sim_dev_t *d)
{
    do_abort(d);
    d->status_due = true;
}

void cs_sim_motion_advance(sim_dev_t *d, double wall_s)
{
    advance(d, wall_s);
}

uint16_t cs_sim_motion_free_slots(const sim_dev_t *d)
{
    return free_slots(d);
}

void cs_sim_motion_status(const sim_dev_t *d, cs_proto_status_t *st)
{
    st->state = d->state;
    st->boot_id = d->boot;
    st->queue_fill = (uint16_t)d->qcount;
    st->last_seq = d->exec_seq;
    st->axes = d->m->n_axes;
    for (unsigned i = 0; i < CS_PROTO_AXES_MAX; i++)
        st->pos[i] = i < d->m->n_axes ? cs_stepper_position(&d->st, i) : 0;
}

bool cs_sim_motion_pop_error(sim_dev_t *d, cs_proto_error_t *e)
{
    if (d->nerr == 0)
        return false;
    *e = d->errs[0];
    memmove(d->errs, d->errs + 1, (d->nerr - 1) * sizeof d->errs[0]);
    d->nerr--;
    d->res->errors_sent++;
    return true;
}

bool cs_sim_motion_done(const sim_dev_t *d)
{
    return everything_done(d);
}

bool cs_sim_motion_started(const sim_dev_t *d)
{
    return d->exec_item > 0;
}

bool cs_sim_motion_busy(const sim_dev_t *d)
{
    return !everything_done(d) && !d->held;
}

cs_err_t cs_sim_motion_close(sim_dev_t *d)
{
    cs_sim_device_result_t *res = d->res;
    cs_err_t rc = CS_OK;
    /* what the executor still holds is executed (a stop request finishes the ring) */
    port_posix_run(UINT64_MAX);
    note_completed(d);
    res->ticks = port_posix_now();
    for (unsigned i = 0; i < CS_AXES; i++)
        res->pos[i] = port_posix_position(i);
    if (d->cfg->keep_edges) {
        size_t ne;
        const port_posix_edge_t *edges = port_posix_edges(&ne);
        if (!port_posix_record_ok()) {
            rc = CS_ERR_FULL;
        } else if (ne > 0) {
            res->ex.edges = malloc(ne * sizeof *edges);
            if (res->ex.edges == NULL)
                rc = CS_ERR_FULL;
            else
                memcpy(res->ex.edges, edges, ne * sizeof *edges);
        }
        if (res->ex.edges != NULL || ne == 0)
            res->ex.n = ne;
        res->ex.end_tick = port_posix_now();
        for (unsigned i = 0; i < CS_AXES; i++) {
            res->ex.pos[i] = port_posix_position(i);
            res->ex.exec_pos[i] = cs_stepper_position(&d->st, i);
        }
    }
    port_posix_reset(d->m->tick_hz, d->inv); /* frees the port's copy of the edges */
    port_stepper_attach(NULL);
    free(d);
    return rc;
}

/* --- the command line: curvestep-sim --pty | --port DEV ------------------------------------ */

#include <fcntl.h>
#include <stdio.h>

#include "cs_conv.h"
#include "cs_err_text.h"
#include "cs_machine_ini.h"
#include "cs_motion.h"
#include "cs_sim_draw.h"

static volatile sig_atomic_t g_stop;

static void on_signal(int sig)
{
    (void)sig;
    g_stop = 1;
}

static void device_usage(FILE *f)
{
    fputs("usage: curvestep-sim --pty | --port DEV [--baud N] [--machine FILE.ini] [--queue N]\n"
          "                     [--speed X | --instant] [--line-rate BPS] [--faults SPEC]\n"
          "                     [--tol MM] [--idle-exit S] [--reference JOB] [--check]\n"
          "                     [--svg OUT.svg] [--png OUT.png] [--trace OUT.csv]\n"
          "Runs the simulator as the device at the far end of a serial line, speaking the wire\n"
          "protocol (docs/protocol.md): `curvestep stream --port ...` streams to it.\n"
          "  --pty             create a pseudo-terminal pair, print the slave's path on the first\n"
          "                    line of standard output, and serve the master end\n"
          "  --port DEV        serve an existing tty (opened raw at --baud, default 115200)\n"
          "  --machine FILE    machine description (default: the built-in plotter)\n"
          "  --queue N         motion-queue slots announced in HELLO, 1..256 (default 32)\n"
          "  --speed X         simulated seconds per wall second (default 1: real time)\n"
          "  --instant         execute everything as soon as it arrives (the queue never fills)\n"
          "  --line-rate BPS   pace what the device sends as a real line would (10 bits a byte)\n"
          "  --faults SPEC     comma-separated: drop=P (a frame written is lost), corrupt=P (a\n"
          "                    byte written is changed), corrupt-in=P (a byte read is changed),\n"
          "                    dup=P (a frame written twice),\n"
          "                    seed=N, and at most one of reset-after=N (reboot with a new boot\n"
          "                    id after executing N messages, position kept), hang-after=N\n"
          "                    (then stop answering), close-after=N (then close the line)\n"
          "  --tol MM          chord tolerance for CURVE messages (default: the machine's)\n"
          "  --idle-exit S     stop S seconds after the last byte received, once something was\n"
          "                    executed and the queue is empty (default: run until a signal)\n"
          "  --reference JOB   the job (SVG): measure the deviation and the final position\n"
          "  --check           exit 4 when a check of the report fails\n"
          "  --svg/--png/--trace  drawings and the CSV of every step edge, as with --replay\n"
          "SIGINT or SIGTERM ends the service: what the executor holds is finished, then the\n"
          "report goes to standard output: messages executed, link counters, retransmissions,\n"
          "simulated job time, final position, per-axis peaks, deviation against --reference.\n"
          "Exit status: 0 ok, 1 bad input, 2 bad command line, 3 internal or line error,\n"
          "4 a check failed (with --check).\n",
          f);
}

static int parse_faults(const char *spec, cs_sim_device_cfg_t *c)
{
    char buf[256];
    if (strlen(spec) >= sizeof buf)
        return -1;
    strcpy(buf, spec);
    for (char *tok = strtok(buf, ","); tok != NULL; tok = strtok(NULL, ",")) {
        char *eq = strchr(tok, '=');
        if (eq == NULL)
            return -1;
        *eq = '\0';
        char *end;
        double v = strtod(eq + 1, &end);
        if (*end != '\0' || !(v >= 0))
            return -1;
        if (strcmp(tok, "drop") == 0 && v <= 1)
            c->faults.drop = v;
        else if (strcmp(tok, "corrupt") == 0 && v <= 1)
            c->faults.corrupt = v;
        else if (strcmp(tok, "corrupt-in") == 0 && v <= 1)
            c->corrupt_in = v;
        else if (strcmp(tok, "dup") == 0 && v <= 1)
            c->faults.dup = v;
        else if (strcmp(tok, "seed") == 0)
            c->faults.seed = (uint64_t)v;
        else if (strcmp(tok, "reset-after") == 0 && v >= 1)
            c->reset_after = (uint64_t)v;
        else if (strcmp(tok, "hang-after") == 0 && v >= 1)
            c->hang_after = (uint64_t)v;
        else if (strcmp(tok, "close-after") == 0 && v >= 1)
            c->close_after = (uint64_t)v;
        else
            return -1;
    }
    return (c->reset_after != 0) + (c->hang_after != 0) + (c->close_after != 0) <= 1 ? 0 : -1;
}

void cs_sim_device_opts_default(cs_sim_device_opts_t *o)
{
    memset(o, 0, sizeof *o);
    o->speed = 1;
    o->queue = 32;
    o->baud = 115200;
}

int cs_sim_device_opt(int argc, char **argv, int *i, cs_sim_device_opts_t *o)
{
    const char *a = argv[*i];
    bool has = *i + 1 < argc;
    char *end = NULL;
    const char **str = strcmp(a, "--machine") == 0     ? &o->machine_file
                       : strcmp(a, "--reference") == 0 ? &o->out.reference
                       : strcmp(a, "--svg") == 0       ? &o->out.svg
                       : strcmp(a, "--png") == 0       ? &o->out.png
                       : strcmp(a, "--trace") == 0     ? &o->out.trace
                       : strcmp(a, "--faults") == 0    ? &o->faults
                                                       : NULL;
    if (str != NULL && has) {
        *str = argv[++*i];
    } else if (strcmp(a, "--check") == 0) {
        o->out.check = true;
    } else if (strcmp(a, "--instant") == 0) {
        o->instant = true;
    } else if (strcmp(a, "--speed") == 0 && has) {
        o->speed = strtod(argv[++*i], &end);
        if (*end != '\0' || !(o->speed > 0) || o->speed > 1e6) {
            fprintf(stderr, "curvestep-sim: --speed wants a factor in (0, 1e6]\n");
            return -1;
        }
    } else if (strcmp(a, "--idle-exit") == 0 && has) {
        o->idle_exit = strtod(argv[++*i], &end);
        if (*end != '\0' || !(o->idle_exit > 0)) {
            fprintf(stderr, "curvestep-sim: --idle-exit wants seconds > 0\n");
            return -1;
        }
    } else if (strcmp(a, "--tol") == 0 && has) {
        o->tol_mm = strtod(argv[++*i], &end);
        if (*end != '\0' || !(o->tol_mm > 0)) {
            fprintf(stderr, "curvestep-sim: --tol wants a positive number of mm\n");
            return -1;
        }
    } else if ((strcmp(a, "--queue") == 0 || strcmp(a, "--baud") == 0) && has) {
        long v = strtol(argv[++*i], &end, 10);
        if (*end != '\0' || v < 0) {
            fprintf(stderr, "curvestep-sim: %s wants a number\n", a);
            return -1;
        }
        *(a[2] == 'q' ? &o->queue : &o->baud) = v;
    } else {
        return 0;
    }
    return 1;
}

int cs_sim_device_main(int argc, char **argv)
{
    enum { OK = 0, INPUT = 1, USAGE = 2, INTERNAL = 3, CHECK = 4 };
    const char *port = NULL;
    bool pty = false;
    long line_rate = 0;
    cs_sim_device_opts_t o;
    cs_sim_device_opts_default(&o);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        bool has = i + 1 < argc;
        char *end = NULL;
        int took = cs_sim_device_opt(argc, argv, &i, &o);
        if (took < 0)
            return USAGE;
        if (took > 0)
            continue;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            device_usage(stdout);
            return OK;
        } else if (strcmp(a, "--pty") == 0) {
            pty = true;
        } else if (strcmp(a, "--port") == 0 && has) {
            port = argv[++i];
        } else if (strcmp(a, "--line-rate") == 0 && has) {
            line_rate = strtol(argv[++i], &end, 10);
            if (*end != '\0' || line_rate < 0) {
                fprintf(stderr, "curvestep-sim: %s wants a number\n", a);
                return USAGE;
            }
        } else {
            fprintf(stderr, "curvestep-sim: unknown or incomplete option %s\n", a);
            device_usage(stderr);
            return USAGE;
        }
    }
    const char *machine_file = o.machine_file, *reference = o.out.reference, *svg = o.out.svg,
               *png = o.out.png, *trace = o.out.trace, *faults = o.faults;
    bool check = o.out.check, instant = o.instant;
    double speed = o.speed, idle_exit = o.idle_exit, tol_mm = o.tol_mm;
    long queue = o.queue, baud = o.baud;
    if (pty == (port != NULL)) {
        fprintf(stderr, "curvestep-sim: give exactly one of --pty and --port DEV\n");
        return USAGE;
    }
    if (queue < 1 || queue > CS_SIM_DEVICE_QUEUE_MAX) {
        fprintf(stderr, "curvestep-sim: --queue wants 1..%d\n", CS_SIM_DEVICE_QUEUE_MAX);
        return USAGE;
    }
    if (port != NULL && !cs_serial_baud_ok((uint32_t)baud)) {
        fprintf(stderr, "curvestep-sim: --baud %ld is not a termios rate\n", baud);
        return USAGE;
    }
    cs_machine_t m;
    char err[512];
    if (machine_file) {
        if (cs_machine_ini_load(machine_file, &m, err, sizeof err) != 0) {
            fprintf(stderr, "%s\n", err);
            return INPUT;
        }
    } else {
        cs_machine_ini_default(&m);
    }
    cs_sim_device_cfg_t cfg;
    cs_sim_device_cfg_default(&cfg, &m);
    cfg.queue_size = (uint16_t)queue;
    cfg.speed = instant ? 0 : speed;
    cfg.line_rate = (uint32_t)line_rate;
    cfg.idle_exit_s = idle_exit;
    cfg.keep_edges = true;
    if (tol_mm > 0 && cs_conv_tol_to_pos(tol_mm, &cfg.tol) != CS_OK) {
        fprintf(stderr, "curvestep-sim: --tol %g mm is outside the accepted range\n", tol_mm);
        return USAGE;
    }
    if (faults != NULL && parse_faults(faults, &cfg) != 0) {
        fprintf(stderr, "curvestep-sim: --faults: bad list '%s' (see --help)\n", faults);
        return USAGE;
    }
    /* load the reference first: a bad job is reported before anything is served */
    cs_sim_ref_t ref;
    cs_sim_ref_init(&ref);
    double end_mm[3] = {0, 0, 0};
    if (reference) {
        cs_path_t path;
        cs_path_init(&path);
        cs_path_diag_t diag;
        cs_err_t e = cs_motion_read_job(reference, &path, &diag);
        if (e == CS_OK)
            e = cs_sim_ref_from_path(&ref, &path, end_mm);
        else
            cs_path_diag_print(stderr, &diag);
        cs_path_free(&path);
        if (e != CS_OK) {
            cs_sim_ref_free(&ref);
            return INPUT;
        }
    }
    int fd = -1, keep = -1;
    cs_serial_t ser;
    if (pty) {
        char name[256];
        if (cs_serial_openpty(&fd, &keep, name, sizeof name) != 0) {
            perror("curvestep-sim: openpty");
            cs_sim_ref_free(&ref);
            return INTERNAL;
        }
        /* keep our own slave fd open: the master never sees a hang-up between two hosts, and
         * a host that opens the path flushes what piled up meanwhile */
        printf("%s\n", name);
        fflush(stdout);
    } else {
        if (cs_serial_open(&ser, port, (uint32_t)baud) != 0) {
            fprintf(stderr, "curvestep-sim: %s: %s\n", port, strerror(errno));
            cs_sim_ref_free(&ref);
            return INPUT;
        }
        fd = ser.fd;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);
    cs_sim_device_result_t res;
    cs_err_t e = cs_sim_device_serve(fd, &cfg, &g_stop, &res);
    close(fd);
    if (keep >= 0)
        close(keep);
    int rc = OK;
    if (e != CS_OK && e != CS_ERR_IO) {
        fprintf(stderr, "curvestep-sim: device failed: %s\n", cs_err_text(e));
        rc = INTERNAL;
    }
    bool ok = true;
    printf("device: served %.2f s; %llu messages executed (%llu step segments, %llu curves); "
           "%u resets, %u holds, %u aborts, %u errors sent%s\n",
           res.wall_s, (unsigned long long)res.executed, (unsigned long long)res.segments,
           (unsigned long long)res.curves, (unsigned)res.resets, (unsigned)res.holds,
           (unsigned)res.aborts, (unsigned)res.errors_sent,
           e == CS_ERR_IO ? "; the line closed" : "");
    printf("link: %llu bytes in, %llu bytes out; %u frames, %u CRC errors, %u malformed; "
           "retransmissions seen %u (duplicates) + %u (out of order); device resent %u\n",
           (unsigned long long)res.bytes_in, (unsigned long long)res.bytes_out,
           (unsigned)res.frames.frames, (unsigned)res.frames.crc_errs, (unsigned)res.frames.bad,
           (unsigned)res.link.duplicates, (unsigned)res.link.out_of_order,
           (unsigned)res.link.retransmits);
    cs_sim_device_out_t out = {reference, trace, svg, png, check, &ref, {0, 0, 0}};
    memcpy(out.end_mm, end_mm, sizeof end_mm);
    rc = cs_sim_device_report(&m, &cfg, &res, &out, ok, rc);
    fflush(stdout);
    cs_sim_ref_free(&ref);
    cs_sim_exec_free(&res.ex);
    return rc;
}

int cs_sim_device_report(const cs_machine_t *mp, const cs_sim_device_cfg_t *cfg,
                         const cs_sim_device_result_t *resp, const cs_sim_device_out_t *o, bool ok,
                         int rc)
{
    enum { OK = 0, INTERNAL = 3, CHECK = 4 };
    static const char names[] = "xyza";
    const cs_machine_t m = *mp;
    const cs_sim_device_result_t res = *resp;
    const char *reference = o->reference, *trace = o->trace, *svg = o->svg, *png = o->png;
    const cs_sim_ref_t ref = *o->ref;
    const double *end_mm = o->end_mm;
    bool check = o->check;
    printf("executor ran dry %u times mid-job (%.3f s of wall time)\n", (unsigned)res.exec_gaps,
           res.gap_wall_s);
    printf("executed step segments' hash (FNV-1a 64, in order): %016llx\n",
           (unsigned long long)res.seg_hash);
    printf("job time: %.4f s simulated, %zu steps\n", (double)res.ticks / m.tick_hz, res.ex.n);
    printf("final position:");
    for (unsigned i = 0; i < m.n_axes; i++)
        printf(" %c=%lld steps (%.4f mm)", names[i], (long long)res.pos[i],
               (double)res.pos[i] * CS_MOTION_ONE / m.axis[i].steps_per_mm);
    printf("\n");
    if (res.out_of_order != 0) {
        printf("order: %llu deliveries out of sequence: BROKEN\n",
               (unsigned long long)res.out_of_order);
        ok = false;
    }
    cs_sim_dyn_t dyn;
    cs_sim_dynamics(&m, &res.ex, 0.05, &dyn);
    for (unsigned i = 0; i < m.n_axes; i++) {
        printf("axis %c: peak velocity %.3f mm/s (limit %.3f + %.3f) %s; peak acceleration "
               "%.1f mm/s^2 (limit %.1f + %.1f) %s\n",
               names[i], dyn.peak_rate[i], cs_machine_ini_to_double(m.axis[i].max_rate),
               dyn.rate_allow[i], dyn.rate_ok[i] ? "ok" : "OVER", dyn.peak_accel[i],
               cs_machine_ini_to_double(m.axis[i].max_accel), dyn.accel_allow[i],
               dyn.accel_ok[i] ? "ok" : "OVER");
        ok = ok && dyn.rate_ok[i] && dyn.accel_ok[i];
    }
    if (reference) {
        double where[3];
        double dev = cs_sim_deviation(&m, &res.ex, &ref, where);
        double tol = cs_conv_pos_to_mm(cfg->tol > 0 ? cfg->tol : m.tolerance);
        double bound = tol + cs_sim_step_mm(&m);
        bool dev_ok = dev <= bound;
        printf("max deviation: %.5f mm at (%.4f, %.4f, %.4f) (tolerance + one step = %.5f mm) "
               "%s\n",
               dev, where[0], where[1], where[2], bound, dev_ok ? "ok" : "OVER");
        bool end_ok = true;
        for (unsigned i = 0; i < 3; i++) {
            double spm = (double)m.axis[i].steps_per_mm / CS_MOTION_ONE;
            long long want = llround((double)llround(end_mm[i] * 65536.0) / 65536.0 * spm);
            if (want != res.pos[i])
                end_ok = false;
        }
        printf("final position vs job end (%.4f, %.4f, %.4f) rounded to steps: %s\n", end_mm[0],
               end_mm[1], end_mm[2], end_ok ? "exact" : "DIFFERENT");
        ok = ok && dev_ok && end_ok;
    }
    if (rc == OK && trace && cs_sim_write_trace(trace, &m, &res.ex) != 0) {
        perror(trace);
        rc = INTERNAL;
    }
    if (rc == OK && svg && cs_sim_draw_svg(svg, &m, &res.ex, reference ? &ref : NULL) != 0) {
        perror(svg);
        rc = INTERNAL;
    }
    if (rc == OK && png && cs_sim_draw_png(png, &m, &res.ex, reference ? &ref : NULL, 1600) != 0)
        rc = INTERNAL;
    if (svg)
        printf("picture: %s\n", svg);
    if (png)
        printf("picture: %s\n", png);
    if (rc == OK && check) {
        ok = ok && res.executed > 0;
        printf("check: %s\n", ok ? "ok" : "FAILED");
        if (!ok)
            rc = CHECK;
    }
    fflush(stdout);
    return rc;
}
