/* cs_stream: streaming a planned job to a device over cs_link (see cs_stream.h and
 * docs/streaming.md). */
#include "cs_stream.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cs_conv.h"
#include "cs_err_text.h"
#include "cs_exlog.h"
#include "cs_linktime.h"
#include "cs_motion.h"

/* --- the job ------------------------------------------------------------------------------ */

void cs_stream_job_init(cs_stream_job_t *j, cs_stream_mode_t mode)
{
    memset(j, 0, sizeof *j);
    j->mode = mode;
}

void cs_stream_job_free(cs_stream_job_t *j)
{
    free(j->v);
    j->v = NULL;
    j->n = j->cap = 0;
}

static cs_err_t job_push(cs_stream_job_t *j, const cs_proto_msg_t *m)
{
    uint8_t buf[CS_PROTO_LEN_MAX];
    size_t len;
    cs_err_t e = cs_proto_encode(m, buf, sizeof buf, &len); /* refuse now what cannot be sent */
    if (e != CS_OK)
        return e;
    if (j->n == j->cap) {
        size_t cap = j->cap ? j->cap * 2 : 1024;
        cs_proto_msg_t *p = realloc(j->v, cap * sizeof *p);
        if (p == NULL)
            return CS_ERR_FULL;
        j->v = p;
        j->cap = cap;
    }
    j->v[j->n++] = *m;
    return CS_OK;
}

cs_err_t cs_stream_job_add_msg(cs_stream_job_t *j, const cs_proto_msg_t *m)
{
    return job_push(j, m);
}

cs_err_t cs_stream_job_add_segments(cs_stream_job_t *j, const cs_segment_t *s, size_t n)
{
    for (size_t k = 0; k < n; k++) {
        cs_proto_msg_t m = {.type = CS_PROTO_SEGMENT};
        m.u.segment = s[k];
        cs_err_t e = job_push(j, &m);
        if (e != CS_OK)
            return e;
    }
    return CS_OK;
}

cs_err_t cs_stream_job_add_motion(cs_stream_job_t *j, const cs_motion_segs_t *s)
{
    size_t p = 0;
    cs_err_t e = CS_OK;
    for (size_t k = 0; k <= s->n && e == CS_OK; k++) {
        for (; p < s->npens && s->pens[p].seg <= k && e == CS_OK; p++) {
            cs_proto_msg_t m = {.type = CS_PROTO_PEN};
            m.u.pen.pulse_us = s->pens[p].pulse_us;
            e = job_push(j, &m);
        }
        if (k < s->n && e == CS_OK)
            e = cs_stream_job_add_segments(j, &s->v[k], 1);
    }
    return e;
}

static cs_err_t push_curve(cs_stream_job_t *j, const cs_vec3_t p[4], int32_t feed)
{
    cs_proto_msg_t m = {.type = CS_PROTO_CURVE};
    memcpy(m.u.curve.p, p, 4 * sizeof p[0]);
    m.u.curve.feed = feed;
    return job_push(j, &m);
}

/* Derivative of the exact element at t, one-sided second-order differences inside [0, 1]. */
static void deriv(const cs_bezier_t *c, double t, double d[3])
{
    const double h = 1e-5;
    double a[3], b[3], e[3];
    if (t + 2 * h <= 1.0) {
        cs_path_eval_mm(c, t, a);
        cs_path_eval_mm(c, t + h, b);
        cs_path_eval_mm(c, t + 2 * h, e);
        for (int i = 0; i < 3; i++)
            d[i] = (-3 * a[i] + 4 * b[i] - e[i]) / (2 * h);
    } else {
        cs_path_eval_mm(c, t, a);
        cs_path_eval_mm(c, t - h, b);
        cs_path_eval_mm(c, t - 2 * h, e);
        for (int i = 0; i < 3; i++)
            d[i] = (3 * a[i] - 4 * b[i] + e[i]) / (2 * h);
    }
}

/* Hermite cubic of the exact element on [t0, t1] (end points given in fixed point), and its
 * largest parametric distance to the element over 64 samples, mm. */
static double hermite(const cs_bezier_t *c, double t0, double t1, const cs_vec3_t *a,
                      const cs_vec3_t *b, cs_vec3_t out[4], bool *ok)
{
    double p0[3] = {cs_conv_pos_to_mm(a->x), cs_conv_pos_to_mm(a->y), cs_conv_pos_to_mm(a->z)};
    double p3[3] = {cs_conv_pos_to_mm(b->x), cs_conv_pos_to_mm(b->y), cs_conv_pos_to_mm(b->z)};
    double d0[3], d1[3], p1[3], p2[3];
    deriv(c, t0, d0);
    deriv(c, t1, d1);
    double h = t1 - t0;
    for (int i = 0; i < 3; i++) {
        p1[i] = p0[i] + d0[i] * h / 3;
        p2[i] = p3[i] - d1[i] * h / 3;
    }
    out[0] = *a;
    out[3] = *b;
    *ok = cs_conv_mm_to_vec(p1[0], p1[1], p1[2], &out[1]) == CS_OK &&
          cs_conv_mm_to_vec(p2[0], p2[1], p2[2], &out[2]) == CS_OK;
    /* measure with the rounded control points: what the device will trace */
    double q[4][3];
    for (int k = 0; k < 4; k++) {
        q[k][0] = cs_conv_pos_to_mm(out[k].x);
        q[k][1] = cs_conv_pos_to_mm(out[k].y);
        q[k][2] = cs_conv_pos_to_mm(out[k].z);
    }
    double worst = 0;
    for (int s = 1; s < 64; s++) {
        double u = s / 64.0, v = 1 - u;
        double bz[3], ex[3];
        for (int i = 0; i < 3; i++)
            bz[i] = v * v * v * q[0][i] + 3 * v * v * u * q[1][i] + 3 * v * u * u * q[2][i] +
                    u * u * u * q[3][i];
        cs_path_eval_mm(c, t0 + u * h, ex);
        double dd = sqrt((bz[0] - ex[0]) * (bz[0] - ex[0]) + (bz[1] - ex[1]) * (bz[1] - ex[1]) +
                         (bz[2] - ex[2]) * (bz[2] - ex[2]));
        if (dd > worst)
            worst = dd;
    }
    return worst;
}

typedef struct {
    double t0, t1;
    cs_vec3_t a, b;
    int depth;
} piece_t;

static cs_err_t approximate(cs_stream_job_t *j, const cs_path_elem_t *el, int32_t feed,
                            cs_pos_t tol, cs_path_diag_t *diag)
{
    const cs_bezier_t *c = &el->curve;
    double limit = cs_conv_pos_to_mm(tol) / 4;
    if (limit < 2.0 / 65536)
        limit = 2.0 / 65536;
    enum { DEPTH = 16 };
    piece_t stack[DEPTH + 2];
    int sp = 0;
    stack[sp++] = (piece_t){0.0, 1.0, c->p[0], c->p[c->degree], 0};
    while (sp > 0) {
        piece_t it = stack[--sp];
        cs_vec3_t cub[4];
        bool ok;
        double err = hermite(c, it.t0, it.t1, &it.a, &it.b, cub, &ok);
        if (!ok)
            return cs_path_diag_set(diag, CS_ERR_RANGE, el->loc,
                                    "cubic approximation leaves the coordinate range");
        if (err <= limit || it.depth >= DEPTH) {
            if (err > limit)
                return cs_path_diag_set(diag, CS_ERR_DEPTH, el->loc,
                                        "cannot approximate this curve by cubics within %g mm",
                                        limit);
            cs_err_t e = push_curve(j, cub, feed);
            if (e != CS_OK)
                return cs_path_diag_set(diag, e, el->loc, "%s", cs_err_text(e));
            continue;
        }
        double tm = 0.5 * (it.t0 + it.t1), pm[3];
        cs_path_eval_mm(c, tm, pm);
        cs_vec3_t m;
        if (cs_conv_mm_to_vec(pm[0], pm[1], pm[2], &m) != CS_OK)
            return cs_path_diag_set(diag, CS_ERR_RANGE, el->loc, "point outside the range");
        /* right half below the left one: the left is emitted first */
        stack[sp++] = (piece_t){tm, it.t1, m, it.b, it.depth + 1};
        stack[sp++] = (piece_t){it.t0, tm, it.a, m, it.depth + 1};
    }
    j->approximated++;
    return CS_OK;
}

cs_err_t cs_stream_job_add_path(cs_stream_job_t *j, const cs_path_t *path, int32_t feed,
                                cs_pos_t tol, cs_path_diag_t *diag)
{
    for (size_t k = 0; k < path->n; k++) {
        const cs_path_elem_t *el = &path->elems[k];
        const cs_bezier_t *c = &el->curve;
        cs_err_t e = CS_OK;
        /* the element's own feed (G-code F) wins; a rapid (G0) asks for the largest feed, which
         * the device's planner limits to each axis's max rate, as it does for its own rapids */
        int32_t f = el->rapid           ? INT32_MAX
                    : el->feed_mm_s > 0 ? cs_motion_speed(el->feed_mm_s)
                                        : feed;
        if (c->rational || c->degree > 3) {
            e = approximate(j, el, f, tol, diag);
            if (e != CS_OK)
                return e;
            continue;
        }
        cs_bezier_t b = *c;
        while (e == CS_OK && b.degree < 3) {
            cs_bezier_t up;
            e = cs_bezier_elevate(&b, &up);
            b = up;
        }
        if (e == CS_OK)
            e = push_curve(j, b.p, f);
        if (e != CS_OK)
            return cs_path_diag_set(diag, e, el->loc, "cannot send as a curve: %s", cs_err_text(e));
        j->exact++;
    }
    return CS_OK;
}

/* --- streaming ------------------------------------------------------------------------------ */

const char *cs_stream_outcome_text(cs_stream_outcome_t oc)
{
    switch (oc) {
    case CS_STREAM_DONE:
        return "job executed";
    case CS_STREAM_NO_DEVICE:
        return "no device answered";
    case CS_STREAM_INCOMPATIBLE:
        return "device incompatible with the job";
    case CS_STREAM_RESET:
        return "device reset mid-job";
    case CS_STREAM_CLOSED:
        return "link closed";
    case CS_STREAM_DEVICE_ERROR:
        return "device reported an error";
    case CS_STREAM_INTERRUPTED:
        return "interrupted: held, then aborted";
    }
    return "?";
}

const char *cs_stream_result_text(const cs_stream_result_t *r)
{
    return r->what != NULL ? r->what : cs_stream_outcome_text(r->outcome);
}

void cs_stream_opts_default(cs_stream_opts_t *o, cs_serial_t *ser, uint8_t axes, uint32_t tick_hz)
{
    memset(o, 0, sizeof *o);
    o->ser = ser;
    o->axes = axes;
    o->tick_hz = tick_hz;
    o->link.keepalive = 500000;
    cs_stream_link_timing(&o->link, 0);
    /* as long as the link's own give-up (30 s of silence): a device starved of the CPU on a
     * loaded machine is late, not gone (the link's backoff keeps probing it meanwhile) */
    o->hello_ms = CS_LINKTIME_GIVE_UP_S * 1000u;
    o->status_ms = CS_LINKTIME_GIVE_UP_S * 1000u;
}

void cs_stream_link_timing(cs_link_cfg_t *c, uint32_t bits_per_s)
{
    (void)cs_linktime_link(c, bits_per_s, 1000000u); /* CS_ERR_RANGE below 5 bits/s: c kept */
}

typedef struct {
    const cs_stream_job_t *job;
    const cs_stream_opts_t *o;
    cs_stream_result_t *r;
    cs_link_t link;
    bool open, have_hello;
    size_t next;        /* job index of the next message to send (0-based) */
    bool stop;          /* outcome decided */
    bool held;          /* HOLD sent for o->pause, RESUME not yet */
    /* STATUS messages received with nothing of ours unacknowledged: the device sent them after
     * it had taken everything we sent (its ACK goes out before them), so they answer it */
    unsigned fresh;
    cs_proto_status_t last; /* the last STATUS */
    cs_proto_override_t ov_dev; /* the OVERRIDE the device took ({0}: none sent yet) */
    double t0, t_first;
    cs_stream_progress_t prog;
} run_t;

static void finish(run_t *s, cs_stream_outcome_t oc)
{
    if (!s->stop) {
        s->r->outcome = oc;
        s->stop = true;
    }
}

/* The device's STATUS: state and position; once the device numbers this job (SETPOS, or
 * found on --resume), its last finished message is what counts as executed: no guess from link
 * sequences, so HOLD / RESUME / QUERY never count and a reconnect loses nothing. */
static void on_status(run_t *s, const cs_proto_status_t *st)
{
    s->last = *st;
    s->r->dev_state = st->state;
    for (unsigned i = 0; i < CS_PROTO_AXES_MAX; i++)
        s->r->dev_pos[i] = i < st->axes ? st->pos[i] : 0;
    s->r->dev_timed = (st->flags & CS_PROTO_STATUS_TICK) != 0;
    s->r->dev_tick = st->tick;
    if (!s->open)
        return;
    if (cs_link_unacked(&s->link) == 0)
        s->fresh++;
    if (s->r->numbered && (st->flags & CS_PROTO_STATUS_JOB) && st->job_id == s->r->job_id &&
        st->done <= s->r->sent && st->recv <= s->r->sent) {
        s->r->executed = st->done;
        s->r->dev_recv = st->recv;
    }
}

static void on_deliver(run_t *s, const cs_link_event_t *ev)
{
    cs_proto_msg_t m;
    if (cs_proto_decode(ev->payload, ev->len, &m) != CS_OK)
        return;
    if (m.type == CS_PROTO_HELLO) {
        s->r->hello = m.u.hello;
        s->have_hello = true;
    } else if (m.type == CS_PROTO_STATUS) {
        on_status(s, &m.u.status);
    } else if (m.type == CS_PROTO_EVENT) {
        if (m.u.event.kind == CS_PROTO_EVENT_ALARM) {
            s->r->alarm = true;
            s->r->alarm_ev = m.u.event;
            s->r->alarm_msg = s->r->executed + 1;
        }
        if (s->o->on_event != NULL)
            s->o->on_event(s->o->event_ctx, &m.u.event);
    } else if (m.type == CS_PROTO_ERROR) {
        s->r->dev_error = m.u.error;
        /* counted back from the last sequence queued, never forward from the session's first
         * one: 16-bit sequences wrap after 65,536 messages */
        uint16_t last = (uint16_t)(cs_link_last_acked(&s->link) + cs_link_unacked(&s->link));
        uint16_t back = (uint16_t)(last - m.u.error.seq);
        s->r->dev_error_msg =
            s->open && back < s->r->sent - s->r->resume_from ? s->r->sent - back : 0;
        finish(s, CS_STREAM_DEVICE_ERROR);
    }
}

static int pump_out(run_t *s, uint32_t now)
{
    for (int k = 0; k < 64; k++) {
        const uint8_t *b;
        size_t n;
        cs_err_t e = cs_link_poll(&s->link, now, 0, &b, &n);
        if (e == CS_END)
            return 0;
        if (e == CS_ERR_TIMEOUT) {
            snprintf(s->r->why, sizeof s->r->why,
                     "the device stopped answering (silent for %u s: %u retransmission timeouts, "
                     "%u ms doubling up to %u ms)",
                     (unsigned)(s->o->link.give_up / 1000000u), (unsigned)s->link.retries + 1u,
                     (unsigned)s->o->link.rto / 1000u, (unsigned)s->o->link.rto_max / 1000u);
            finish(s, s->open ? CS_STREAM_CLOSED : CS_STREAM_NO_DEVICE);
            return 0;
        }
        if (e == CS_OK && cs_serial_write(s->o->ser, b, n) != 0) {
            /* a hung-up line (the device closed it, a USB adapter pulled) fails the write with
             * EIO, ENXIO or EPIPE before a read sees the hang-up: the same event, one text */
            bool hup = errno == EIO || errno == ENXIO || errno == EPIPE;
            snprintf(s->r->why, sizeof s->r->why, "%s: %s",
                     hup ? "the line closed (write)" : "write failed", strerror(errno));
            finish(s, s->open ? CS_STREAM_CLOSED : CS_STREAM_NO_DEVICE);
            return -1;
        }
    }
    return 0;
}

/* Reads what arrived (waiting up to wait_ms) and feeds it to the link. */
static void pump_in(run_t *s, int wait_ms)
{
    uint8_t buf[2048];
    ssize_t n = cs_serial_read(s->o->ser, buf, sizeof buf, wait_ms);
    if (n < 0) {
        snprintf(s->r->why, sizeof s->r->why, "the line closed (%s)", strerror(errno));
        finish(s, s->open ? CS_STREAM_CLOSED : CS_STREAM_NO_DEVICE);
        return;
    }
    uint32_t now = cs_serial_now_us();
    for (ssize_t k = 0; k < n; k++) {
        cs_link_event_t ev;
        if (cs_link_feed(&s->link, buf[k], now, 0, &ev) != CS_OK)
            continue;
        if (ev.what & CS_LINK_EV_OPEN)
            s->open = true;
        if (ev.what & CS_LINK_EV_RESET) {
            s->r->old_boot = ev.old_boot;
            s->r->new_boot = ev.new_boot;
            s->r->unacked = ev.unacked;
            finish(s, CS_STREAM_RESET);
        }
        if (ev.what & CS_LINK_EV_DELIVER)
            on_deliver(s, &ev);
    }
    if (s->open) {
        /* sent minus what the link still holds unacknowledged (a window, far below 65,536):
         * no 16-bit sequence arithmetic, so no wrap on long jobs */
        size_t in_session = s->r->sent - s->r->resume_from;
        size_t unacked = cs_link_unacked(&s->link);
        s->r->delivered = s->r->sent - (unacked < in_session ? unacked : in_session);
    }
}

void cs_stream_progress(cs_stream_progress_t *p, FILE *f, bool tty, bool final, size_t n, size_t ex,
                        size_t sent, size_t resume_from, unsigned retx, const char *what)
{
    if (f == NULL)
        return;
    double now = cs_serial_now_s();
    double period = tty ? 0.1 : 1.0;
    if (!final && now - p->last < period)
        return;
    p->last = now;
    if (now - p->rate_t >= 0.5) { /* speed over the last half second or more */
        if (p->rate_t > 0)
            p->rate = ((double)ex - p->rate_ex) / (now - p->rate_t);
        p->rate_t = now;
        p->rate_ex = (double)ex;
    }
    if (final && now > p->t_first) /* the summary: the average over the whole stream */
        p->rate = (double)(ex - resume_from) / (now - p->t_first);
    double pct = n ? 100.0 * (double)ex / (double)n : 100.0;
    double eta = ex >= n ? 0 : p->rate > 0 ? (double)(n - ex) / p->rate : -1;
    if (tty) {
        char bar[31];
        int fill = (int)(pct * 30 / 100);
        for (int i = 0; i < 30; i++)
            bar[i] = i < fill ? '#' : '-';
        bar[30] = '\0';
        char etas[32];
        if (eta >= 0)
            snprintf(etas, sizeof etas, "%d:%02d", (int)eta / 60, (int)eta % 60);
        else
            snprintf(etas, sizeof etas, "--:--");
        fprintf(f, "\r[%s] %5.1f%% %zu/%zu %s  ETA %s  %.0f %s/s  retx %u ", bar, pct, ex, n, what,
                etas, p->rate, what, retx);
        if (final)
            fputc('\n', f);
    } else {
        fprintf(f,
                "stream: %zu/%zu %s executed (%.1f %%), %zu sent, %.0f/s, ETA %s%.0f s, "
                "%u retransmissions\n",
                ex, n, what, pct, sent, p->rate, eta >= 0 ? "" : "~", eta >= 0 ? eta : 0, retx);
    }
    fflush(f);
}

void cs_stream_progress_held(FILE *f, size_t ex, size_t n, const char *what)
{
    if (f == NULL)
        return;
    fprintf(f, "stream: device held at %zu of %zu %s\n", ex, n, what);
    fflush(f);
}

static void progress(run_t *s, bool final)
{
    s->prog.t_first = s->t_first;
    cs_stream_progress(&s->prog, s->o->progress, s->o->progress_tty, final, s->job->n,
                       s->r->executed, s->r->sent, s->r->resume_from, s->link.stats.retransmits,
                       s->job->mode == CS_STREAM_CURVES ? "curves" : "segments");
}

#define ANY_STATE 0xFFu

/* Sends m and waits until the device took it and answered with a STATUS whose state is want_a
 * or want_b (ANY_STATE: any), or wait_ms passed: true when it answered so. */
static bool exchange(run_t *s, const cs_proto_msg_t *m, uint8_t want_a, uint8_t want_b,
                     uint32_t wait_ms)
{
    double t_end = cs_serial_now_s() + wait_ms / 1000.0;
    bool sent = false;
    unsigned mark = 0;
    while (cs_serial_now_s() < t_end) {
        if (!sent && cs_link_can_send(&s->link, m->type)) {
            sent = cs_link_send_msg(&s->link, m, NULL) == CS_OK;
            mark = s->fresh;
        }
        if (pump_out(s, cs_serial_now_us()) != 0)
            return false;
        pump_in(s, 5);
        if (sent && s->fresh != mark &&
            (want_a == ANY_STATE || s->r->dev_state == want_a || s->r->dev_state == want_b))
            return true;
        if (cs_link_state(&s->link) != CS_LINK_OPEN)
            return false;
        if (s->o->interrupt != NULL && *s->o->interrupt >= 2)
            return false;
    }
    return false;
}

/* Sends one control message (HOLD, RESUME or ABORT) and waits until the device says it obeyed
 * (state in want_a or want_b) or wait_ms passed. */
static void control(run_t *s, uint8_t type, uint8_t want_a, uint8_t want_b, uint32_t wait_ms)
{
    cs_proto_msg_t m = {.type = type};
    (void)exchange(s, &m, want_a, want_b, wait_ms);
}

static cs_err_t run_init(run_t *s, const cs_stream_job_t *job, const cs_stream_opts_t *o,
                         cs_stream_result_t *r)
{
    s->job = job;
    s->o = o;
    s->r = r;
    /* a line that takes no more bytes (the peer stopped reading) must not block the loop: what
     * the driver refuses is lost, and the link resends it or declares the peer gone */
    cs_serial_set_lossy(o->ser, true);
    r->sent = r->delivered = r->executed = r->resume_from = o->resume_from;
    s->next = o->resume_from;
    r->job_id = cs_stream_job_id(job);
    s->t0 = cs_serial_now_s();
    uint32_t seed = (uint32_t)getpid() * 2654435761u ^ (uint32_t)(s->t0 * 1e6);
    uint32_t boot = seed ? seed : 1u;
    uint32_t nonce = seed * 1664525u + 1013904223u;
    cs_err_t e = cs_link_init(&s->link, &o->link, boot, nonce ? nonce : 1u, 0, cs_serial_now_us());
    return e == CS_OK ? CS_OK : CS_ERR_ARG;
}

/* Phase 1: connects and waits for the HELLO (o->hello_ms). */
static void run_connect(run_t *s)
{
    const cs_stream_opts_t *o = s->o;
    double t_hello = s->t0 + o->hello_ms / 1000.0;
    while (!s->stop && !(s->open && s->have_hello)) {
        if (cs_serial_now_s() > t_hello) {
            snprintf(s->r->why, sizeof s->r->why, "%s within %u ms",
                     s->open ? "connected, but no HELLO" : "no answer to the connection",
                     (unsigned)o->hello_ms);
            finish(s, CS_STREAM_NO_DEVICE);
            break;
        }
        if (o->interrupt != NULL && *o->interrupt) {
            finish(s, CS_STREAM_INTERRUPTED);
            break;
        }
        pump_out(s, cs_serial_now_us());
        pump_in(s, 5);
    }
}

bool cs_stream_hello_mismatch(const cs_proto_hello_t *h, uint8_t axes, uint32_t tick_hz,
                              cs_stream_mode_t mode, char *why, size_t cap)
{
    bool curves = mode == CS_STREAM_CURVES;
    uint16_t need = curves ? CS_PROTO_CAP_CURVES : CS_PROTO_CAP_SEGMENTS;
    if (h->axes != axes)
        snprintf(why, cap, "the device has %u axes, the machine file %u", (unsigned)h->axes,
                 (unsigned)axes);
    else if (!curves && h->tick_hz != tick_hz)
        snprintf(why, cap, "the device ticks at %u Hz, the segments were planned for %u Hz",
                 (unsigned)h->tick_hz, (unsigned)tick_hz);
    else if (!(h->caps & need))
        snprintf(why, cap, "the device cannot take %s", curves ? "curves" : "step segments");
    else
        return false;
    return true;
}

/* A job of device-planned control messages only (HOME, JOG, PROBE, SPINDLE: `curvestep home`
 * and the like, sent in curves mode so that the tick rate need not match) needs no CURVE
 * capability: a segments-only device (the ATmega328p's) runs them too. */
static bool control_only(const cs_stream_job_t *j)
{
    if (j->mode != CS_STREAM_CURVES)
        return false;
    for (size_t i = 0; i < j->n; i++)
        if (j->v[i].type == CS_PROTO_CURVE || j->v[i].type == CS_PROTO_SEGMENT)
            return false;
    return true;
}

/* The HELLO against the machine and the job: INCOMPATIBLE with the reason in r->why. */
static void check_hello(run_t *s)
{
    cs_stream_result_t *r = s->r;
    const cs_proto_hello_t *h = &r->hello;
    if (h->version < CS_PROTO_VERSION_MIN || h->version > CS_PROTO_VERSION)
        snprintf(r->why, sizeof r->why, "protocol version %u, this host speaks %u..%u",
                 (unsigned)h->version, (unsigned)CS_PROTO_VERSION_MIN,
                 (unsigned)CS_PROTO_VERSION);
    else if (control_only(s->job)) {
        if (h->axes != s->o->axes)
            snprintf(r->why, sizeof r->why, "the device has %u axes, the machine file %u",
                     (unsigned)h->axes, (unsigned)s->o->axes);
    } else
        (void)cs_stream_hello_mismatch(h, s->o->axes, s->o->tick_hz, s->job->mode, r->why,
                                       sizeof r->why);
    if (r->why[0] != '\0')
        finish(s, CS_STREAM_INCOMPATIBLE);
}

/* The user's interrupt (HOLD then ABORT; at once on a second one) and pause (HOLD / RESUME).
 * Returns true when the run must stop. */
static bool run_controls(run_t *s, double *t_last_ack)
{
    const cs_stream_opts_t *o = s->o;
    if (o->interrupt != NULL && *o->interrupt) {
        if (*o->interrupt < 2 && o->jog_cancel) {
            control(s, CS_PROTO_JOG_CANCEL, CS_PROTO_STATE_IDLE, CS_PROTO_STATE_ALARM, 5000);
        } else if (*o->interrupt < 2) {
            control(s, CS_PROTO_HOLD, CS_PROTO_STATE_HELD, CS_PROTO_STATE_IDLE, 2000);
            control(s, CS_PROTO_ABORT, CS_PROTO_STATE_ABORTED, CS_PROTO_STATE_IDLE, 2000);
        }
        finish(s, CS_STREAM_INTERRUPTED);
        return true;
    }
    if (o->override != NULL && memcmp(o->override, &s->ov_dev, sizeof s->ov_dev) != 0) {
        /* what the device has after the SETPOS (a fresh job: as planned) or a resume: sent */
        cs_proto_msg_t m = {.type = CS_PROTO_OVERRIDE};
        m.u.override = *o->override;
        if (exchange(s, &m, ANY_STATE, ANY_STATE, 2000))
            s->ov_dev = m.u.override;
    }
    if (o->pause != NULL && (*o->pause != 0) != s->held) {
        s->held = !s->held;
        if (s->held) {
            control(s, CS_PROTO_HOLD, CS_PROTO_STATE_HELD, CS_PROTO_STATE_IDLE, 2000);
            if (s->r->dev_state == CS_PROTO_STATE_HELD || s->r->dev_state == CS_PROTO_STATE_IDLE)
                cs_stream_progress_held(o->progress, s->r->executed, s->job->n,
                                        s->job->mode == CS_STREAM_CURVES ? "curves" : "segments");
        } else
            control(s, CS_PROTO_RESUME, CS_PROTO_STATE_RUNNING, CS_PROTO_STATE_IDLE, 2000);
        *t_last_ack = 0;
    }
    return false;
}

/* Once everything is acknowledged: DONE when the device reports the last message executed and
 * is no longer running, CLOSED when it stays silent about it for o->status_ms. */
static void check_end(run_t *s, double *t_last_ack)
{
    cs_stream_result_t *r = s->r;
    if (r->sent != s->job->n || cs_link_unacked(&s->link) != 0)
        return;
    if (*t_last_ack == 0)
        *t_last_ack = cs_serial_now_s();
    if (r->executed == s->job->n && !cs_proto_state_busy(r->dev_state)) {
        finish(s, CS_STREAM_DONE);
        return;
    }
    /* the device reports its progress at least every 250 ms; a job whose last messages are
     * still executing keeps sending STATUS while running */
    if (!cs_proto_state_busy(r->dev_state) && !s->held &&
        cs_serial_now_s() - *t_last_ack > s->o->status_ms / 1000.0) {
        snprintf(r->why, sizeof r->why,
                 "everything was delivered but the device reports %zu executed", r->executed);
        finish(s, CS_STREAM_CLOSED);
    }
}

uint32_t cs_stream_job_id(const cs_stream_job_t *job)
{
    uint32_t h = CS_EXLOG_HASH0; /* FNV-1a 32 (Fowler/Noll/Vo, public domain), as cs_exlog */
    for (size_t k = 0; k < job->n; k++) {
        uint8_t buf[CS_PROTO_LEN_MAX];
        size_t len = 0;
        if (cs_proto_encode(&job->v[k], buf, sizeof buf, &len) != CS_OK)
            len = 0; /* cannot happen: the job was encoded when it was built (job_push) */
        for (size_t i = 0; i < len; i++)
            h = (h ^ buf[i]) * 16777619u;
    }
    return h != 0 ? h : 1u;
}

/* Sends SETPOS: the device numbers the job's messages from base + 1 (and with o->set_pos takes
 * the stated position); true when it took it (a STATUS saying so came back). */
static bool send_setpos(run_t *s, size_t base, bool with_pos)
{
    cs_proto_msg_t m = {.type = CS_PROTO_SETPOS};
    m.u.setpos.flags = with_pos ? CS_PROTO_SETPOS_POS : 0;
    m.u.setpos.job_id = s->r->job_id;
    m.u.setpos.base = (uint32_t)base;
    for (unsigned i = 0; i < CS_AXES; i++)
        m.u.setpos.pos[i] = with_pos ? s->o->pos[i] : 0;
    s->r->numbered = true;
    if (!with_pos) /* a fresh job: its numbers are checked by every STATUS that follows */
        return cs_link_send_msg(&s->link, &m, NULL) == CS_OK;
    return exchange(s, &m, ANY_STATE, ANY_STATE, s->o->hello_ms) &&
           (s->last.flags & CS_PROTO_STATUS_POS) && s->last.job_id == s->r->job_id;
}

/* The start of a resumed run: what the device says about the job decides where to go on from
 * (docs/streaming.md, "Resume"). Refusals say why in r->why and what to do. */
static void resume_point(run_t *s)
{
    cs_stream_result_t *r = s->r;
    const cs_stream_opts_t *o = s->o;
    const cs_proto_status_t *st = &s->last;
    bool knows = (st->flags & CS_PROTO_STATUS_JOB) != 0, same = knows && st->job_id == r->job_id;
    if (same && o->set_pos) {
        snprintf(r->why, sizeof r->why,
                 "the device did not reset and still numbers this job (it finished %lu, received "
                 "%lu): --position is for a device that reset; use --resume",
                 (unsigned long)st->done, (unsigned long)st->recv);
        finish(s, CS_STREAM_INCOMPATIBLE);
    } else if (same && (o->resume_ask || o->resume_from == st->recv) && st->recv <= s->job->n) {
        r->numbered = true; /* go on after the last message it received (its queue runs on) */
        r->resume_from = r->sent = r->delivered = s->next = st->recv;
        r->executed = r->resume_done = st->done;
        r->dev_recv = st->recv;
    } else if (same) {
        snprintf(r->why, sizeof r->why,
                 "--resume-from %zu, but the device received messages 1..%lu of this job and "
                 "finished %lu: use --resume",
                 o->resume_from, (unsigned long)st->recv, (unsigned long)st->done);
        finish(s, CS_STREAM_INCOMPATIBLE);
    } else if (knows) {
        snprintf(r->why, sizeof r->why,
                 "the device's job is another one (id %08lx, this file's is %08lx): not resumed",
                 (unsigned long)st->job_id, (unsigned long)r->job_id);
        finish(s, CS_STREAM_INCOMPATIBLE);
    } else if (!o->resume_ask && o->set_pos) {
        if (!send_setpos(s, o->resume_from, true) && !s->stop) {
            snprintf(r->why, sizeof r->why, "the device did not take the stated position");
            finish(s, CS_STREAM_NO_DEVICE);
        }
    } else {
        snprintf(r->why, sizeof r->why,
                 "the device reset since it ran this job (it knows no job since its boot): the "
                 "machine's position is unknown. Home it and run the job again, or state where "
                 "it is: --resume-from N --position X,Y,Z");
        r->refused = true;
        finish(s, CS_STREAM_RESET);
    }
}

/* Phase 1b: a fresh job is numbered from 1 (SETPOS); a resumed one asks the device first
 * (QUERY) and goes on from what it says. */
static void run_begin(run_t *s)
{
    const cs_stream_opts_t *o = s->o;
    if (!o->resume_ask && o->resume_from == 0 && !o->set_pos) {
        if (!send_setpos(s, 0, false))
            finish(s, CS_STREAM_CLOSED);
        return;
    }
    cs_proto_msg_t q = {.type = CS_PROTO_QUERY};
    if (!exchange(s, &q, ANY_STATE, ANY_STATE, o->hello_ms)) {
        if (!s->stop) {
            snprintf(s->r->why, sizeof s->r->why, "no STATUS in answer to QUERY within %u ms",
                     (unsigned)o->hello_ms);
            finish(s, CS_STREAM_NO_DEVICE);
        }
        return;
    }
    resume_point(s);
}

/* Phase 2: keeps the window and the credits full until an outcome. */
static void run_stream(run_t *s)
{
    const cs_stream_job_t *job = s->job;
    double t_last_ack = 0;
    s->t_first = cs_serial_now_s();
    while (!s->stop) {
        uint32_t now = cs_serial_now_us();
        if (run_controls(s, &t_last_ack))
            break;
        while (s->next < job->n && cs_link_can_send(&s->link, job->v[s->next].type)) {
            if (cs_link_send_msg(&s->link, &job->v[s->next], NULL) != CS_OK)
                break;
            s->next++;
            s->r->sent = s->next;
        }
        if (pump_out(s, now) != 0)
            break;
        pump_in(s, 2);
        if (s->stop)
            break;
        progress(s, false);
        check_end(s, &t_last_ack);
    }
}

/* Phase 3: aborts after a device error, flushes the ACKs still due, fills the counters. */
static void run_finish(run_t *s)
{
    cs_stream_result_t *r = s->r;
    const cs_stream_opts_t *o = s->o;
    if (r->outcome == CS_STREAM_DEVICE_ERROR && cs_link_state(&s->link) == CS_LINK_OPEN)
        control(s, CS_PROTO_ABORT, CS_PROTO_STATE_ABORTED, CS_PROTO_STATE_IDLE, 2000);
    double t_end = cs_serial_now_s();
    /* the ACKs still due (the device's last STATUS) go out before we leave */
    pump_out(s, cs_serial_now_us());
    progress(s, true);
    r->link = s->link.stats;
    r->bytes_out = o->ser->bytes_out;
    r->bytes_in = o->ser->bytes_in;
    r->wall_s = t_end - s->t0;
    r->stream_s = t_end - s->t_first;
}

cs_err_t cs_stream_run(const cs_stream_job_t *job, const cs_stream_opts_t *o, cs_stream_result_t *r)
{
    memset(r, 0, sizeof *r);
    r->dev_state = 0xFF;
    if (job == NULL || o == NULL || o->ser == NULL || o->resume_from > job->n)
        return CS_ERR_ARG;
    run_t *s = calloc(1, sizeof *s);
    if (s == NULL)
        return CS_ERR_FULL;
    if (run_init(s, job, o, r) != CS_OK) {
        free(s);
        return CS_ERR_ARG;
    }
    run_connect(s);
    if (!s->stop)
        check_hello(s);
    if (!s->stop)
        run_begin(s);
    run_stream(s);
    run_finish(s);
    free(s);
    return CS_OK;
}
