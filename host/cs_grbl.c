/* cs_grbl: the Grbl 1.1 front end (see cs_grbl.h). Protocol: the Grbl 1.1 "Interface",
 * "Commands" and "Jogging" pages of the grbl wiki (gnea/grbl): responses ok / error:N, push
 * messages in brackets, status reports <State|MPos:...|FS:...>, real-time bytes picked out of the
 * stream as they arrive, a 128-byte receive buffer that character-counting senders fill. */
#define _GNU_SOURCE
#include "cs_grbl_int.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "cs_cmd.h"
#include "cs_conv.h"
#include "cs_grbl_dev.h"
#include "cs_gcode_words.h"
#include "cs_grbl_gc.h"
#include "cs_grbl_ov.h"
#include "cs_serial.h"
#include "cs_stream_cmd.h"
#include "cs_trace.h"

#define GRBL_WELCOME "Grbl 1.1h ['$' for help]"

/* a whole receive buffer is one line for the line reader (and is_dwell's copy) */
CS_STATIC_ASSERT(CS_GRBL_RX_SIZE < CS_GRBL_GC_LINE_MAX, rx_line_fits_reader);


static volatile sig_atomic_t stop_flag;
static void on_stop(int sig)
{
    (void)sig;
    stop_flag = 1;
}

/* ---- output ---- */

void cs_grbl_say(grbl_t *g, const char *fmt, ...)
{
    if (g->fd < 0)
        return;
    char buf[512];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(buf, sizeof buf - 2, fmt, ap);
    va_end(ap);
    if (n < 0)
        return;
    if ((size_t)n > sizeof buf - 3)
        n = (int)sizeof buf - 3;
    buf[n++] = '\r';
    buf[n++] = '\n';
    for (int off = 0, tries = 0; off < n && tries < 200;) {
        ssize_t w = write(g->fd, buf + off, (size_t)(n - off));
        if (w > 0) {
            off += (int)w;
        } else if (w < 0 && (errno == EAGAIN || errno == EINTR)) {
            struct pollfd p = {g->fd, POLLOUT, 0};
            poll(&p, 1, 10);
            tries++;
        } else {
            return;
        }
    }
}

double cs_grbl_steps_mm(const grbl_t *g, int a, int32_t steps)
{
    return (double)steps * 65536.0 / g->m.axis[a].steps_per_mm;
}

/* ---- the device's position back into the reader and the planner ---- */

/* After a cancel: the reader and the next chunk start where the device stopped. */
void cs_grbl_sync(grbl_t *g)
{
    cs_grbl_dev_snap_t s;
    cs_grbl_dev_snap(&g->dev, &s);
    if (!s.have_pos)
        return;
    double mm[3];
    memcpy(mm, g->gc.pos, sizeof mm);
    for (int a = 0; a < 3 && a < g->m.n_axes; a++) {
        mm[a] = cs_grbl_steps_mm(g, a, s.pos[a]);
        g->plan_pos[a] = (cs_pos_t)llround((double)s.pos[a] * 65536.0 * 65536.0 /
                                           (double)g->m.axis[a].steps_per_mm);
    }
    cs_grbl_gc_set_pos(&g->gc, mm);
    g->cancelled_seen = s.cancelled;
}

/* Everything not yet executed is dropped; the device stops (decelerating) where it is. */
static void drop_all(grbl_t *g)
{
    cs_grbl_dev_cancel(&g->dev, false);
    g->held = false;
    cs_path_free(&g->pending);
    cs_grbl_sync(g);
}

/* ---- chunks ---- */

/* Plans path (emptied) from plan_pos into it->job. CS_OK, or an error with diag. */
static cs_err_t plan_chunk(grbl_t *g, cs_path_t *path, cs_grbl_item_t *it, cs_path_diag_t *diag)
{
    cs_jobplan_t jp;
    cs_jobplan_init(&jp);
    jp.path = *path;
    cs_path_init(path);
    jp.read_ok = true;
    cs_stream_job_init(&it->job, CS_STREAM_SEGMENTS);
    cs_err_t e = cs_jobplan_plan(&jp, "grbl", &g->m, g->plan_pos, g->tol, CS_TRACE_SUBDIV, g->feed);
    if (e == CS_OK && g->ctl.laser)
        e = cs_grbl_laser_job(g, &jp.mo.segs, &it->job);
    else if (e == CS_OK)
        e = cs_stream_job_add_segments(&it->job, jp.mo.segs.v, jp.mo.segs.n);
    if (e == CS_OK)
        memcpy(g->plan_pos, jp.mo.pl.pos, sizeof g->plan_pos);
    else
        cs_stream_job_free(&it->job);
    *diag = jp.diag;
    diag->code = e;
    diag->loc.file = "grbl";
    cs_jobplan_free(&jp);
    return e;
}

/* A soft-limit style stop (Grbl ALARM:2): the planner refused what was already answered ok. */
static void alarm_planner(grbl_t *g, const cs_path_diag_t *d)
{
    cs_grbl_say(g, "[MSG:line %u: %s]", d->loc.line, d->reason[0] ? d->reason : "cannot plan");
    cs_grbl_say(g, "ALARM:2");
    g->alarm = true;
    drop_all(g);
}

/* The overrides in force now, on moves not planned yet (Grbl applies them to what is not yet
 * executed; curvestep to what is not yet planned: a chunk already on the device keeps its feed). */
static void apply_overrides(grbl_t *g, cs_path_t *path)
{
    for (size_t k = 0; g->ctl.laser && k < path->n; k++)
        if (path->elems[k].rapid) /* a rapid slowed into a feed move keeps the laser off */
            path->elems[k].spindle_s = 0;
    double rapid = INFINITY;
    for (int a = 0; a < 3 && a < g->m.n_axes; a++)
        rapid = fmin(rapid, g->m.axis[a].max_rate / 65536.0);
    double dflt = (g->feed > 0 ? g->feed : g->m.default_feed) / 65536.0;
    cs_grbl_ov_apply(&g->ov, path, 0, dflt, rapid);
}

static void take_bytes(grbl_t *g, const unsigned char *b, size_t n);

/* Reads the client's bytes for up to 5 ms while a step waits on the device: real-time bytes act
 * (? is answered, ! holds), the rest waits in the receive buffer. */
static void pump(grbl_t *g)
{
    struct pollfd p = {g->fd, POLLIN, 0};
    if (g->fd < 0 || poll(&p, 1, 5) <= 0) {
        if (g->fd < 0)
            poll(NULL, 0, 5);
        return;
    }
    unsigned char buf[256];
    ssize_t n = read(g->fd, buf, sizeof buf);
    if (n > 0)
        take_bytes(g, buf, (size_t)n);
}

/* Waits until the queue has room for one more item (or the device failed). */
static bool wait_room(grbl_t *g)
{
    cs_grbl_dev_snap_t s;
    for (;;) {
        cs_grbl_dev_snap(&g->dev, &s);
        if (s.failed || stop_flag)
            return false;
        if (cs_grbl_dev_room(&g->dev, 1))
            return true;
        pump(g);
    }
}

bool cs_grbl_queue_path(grbl_t *g, cs_path_t *path)
{
    if (path->n == 0)
        return true;
    apply_overrides(g, path);
    cs_grbl_item_t it = {0};
    cs_path_diag_t d;
    if (plan_chunk(g, path, &it, &d) != CS_OK) {
        alarm_planner(g, &d);
        return false;
    }
    it.ov_feed = g->ov.feed; /* the device scales it by the override now / this */
    it.ov_rapid = g->ov.rapid;
    if (!wait_room(g) || !cs_grbl_dev_push(&g->dev, &it)) {
        cs_stream_job_free(&it.job);
        return false;
    }
    g->last_push_jog = false;
    return true;
}

bool cs_grbl_run_msgs(grbl_t *g, const cs_proto_msg_t *m, size_t n, bool wait)
{
    cs_grbl_item_t it = {0};
    cs_stream_job_init(&it.job, CS_STREAM_SEGMENTS);
    cs_err_t e = CS_OK;
    for (size_t k = 0; k < n && e == CS_OK; k++)
        e = cs_stream_job_add_msg(&it.job, &m[k]);
    if (e != CS_OK || !wait_room(g) || !cs_grbl_dev_push(&g->dev, &it)) {
        cs_stream_job_free(&it.job);
        return false;
    }
    g->last_push_jog = false;
    cs_grbl_dev_snap_t s;
    for (;;) {
        cs_grbl_dev_snap(&g->dev, &s);
        if (s.failed || stop_flag)
            return false;
        if (!wait || cs_grbl_dev_idle(&g->dev))
            return true;
        pump(g);
    }
}

/* True when elements n0.. of path stay inside the machine's travel (32 samples each). */
static bool inside_travel(const grbl_t *g, const cs_path_t *path, size_t n0)
{
    for (size_t k = n0; k < path->n; k++)
        for (int s = 0; s <= 32; s++) {
            double p[3];
            cs_path_eval_mm(&path->elems[k].curve, s / 32.0, p);
            for (int a = 0; a < 3 && a < g->m.n_axes; a++)
                if (p[a] < cs_conv_pos_to_mm(g->m.axis[a].travel_min) - 1e-9 ||
                    p[a] > cs_conv_pos_to_mm(g->m.axis[a].travel_max) + 1e-9)
                    return false;
        }
    return true;
}

/* ---- G-code lines ---- */

static int gcode_error(const cs_path_diag_t *d)
{
    const char *r = d->reason;
    if (d->code == CS_ERR_UNSUPPORTED)
        return ERR_UNSUPPORTED;
    if (d->code == CS_ERR_DEGENERATE || d->code == CS_ERR_RANGE)
        return ERR_TARGET;
    if (strstr(r, "number") != NULL)
        return ERR_NUMBER;
    if (strstr(r, "two ") != NULL || strstr(r, "on one line") != NULL)
        return ERR_MODAL;
    if (strstr(r, "not used by anything") != NULL)
        return ERR_UNUSED;
    if (strstr(r, "no motion mode") != NULL)
        return ERR_NO_COMMAND;
    return ERR_UNSUPPORTED;
}

static void reply_error(grbl_t *g, const cs_path_diag_t *d)
{
    cs_grbl_say(g, "[MSG:line %u col %u: %s]", d->loc.line, d->loc.col, d->reason);
    cs_grbl_say(g, "error:%d", gcode_error(d));
}

/* "G4 P<seconds>" alone on a line (Grbl: P in seconds): true with *s. */
static bool is_dwell(const char *line, double *s)
{
    char c[CS_GRBL_GC_LINE_MAX];
    size_t n = 0;
    for (const char *p = line; *p && n + 1 < sizeof c; p++)
        if (*p != ' ' && *p != '\t')
            c[n++] = (char)(*p >= 'a' && *p <= 'z' ? *p - 32 : *p);
    c[n] = '\0';
    int used = 0;
    if ((sscanf(c, "G4P%lf%n", s, &used) == 1 || sscanf(c, "G04P%lf%n", s, &used) == 1) &&
        (size_t)used == n && *s >= 0)
        return true;
    return false;
}

/* Appends the moves of from to to (their locations named in to). False without memory. */
static bool append_moves(cs_path_t *to, const cs_path_t *from)
{
    if (from->n == 0)
        return true;
    const char *name = cs_path_intern(to, "grbl");
    if (name == NULL || !cs_path_grow((void **)&to->elems, &to->cap, to->n + from->n,
                                      sizeof *to->elems))
        return false;
    for (size_t k = 0; k < from->n; k++) {
        to->elems[to->n] = from->elems[k];
        to->elems[to->n].loc.file = name;
        to->n++;
    }
    if (from->blend_tol_mm > 0 && (to->blend_tol_mm == 0 || from->blend_tol_mm < to->blend_tol_mm))
        to->blend_tol_mm = from->blend_tol_mm; /* G64 P: the smallest asked for */
    return true;
}

static void gcode_line(grbl_t *g, const char *line)
{
    double dwell;
    if (g->alarm) {
        cs_grbl_say(g, "error:%d", ERR_LOCKED);
        return;
    }
    if (!g->check_mode && is_dwell(line, &dwell)) {
        cs_grbl_flush(g);
        cs_grbl_item_t it = {.dwell = true, .dwell_s = dwell};
        cs_grbl_dev_push(&g->dev, &it);
        g->last_push_jog = false;
        cs_grbl_say(g, "ok");
        return;
    }
    /* the line's moves go to a path of their own: a probe or a spindle change inside the line
     * queues the lines before it (pending) while the reader appends to this one */
    cs_path_t lp;
    cs_path_init(&lp);
    cs_path_diag_t d;
    bool end;
    g->in_reader = true; /* a G38.x waits on the device inside the reader */
    g->probe_failed = false;
    cs_err_t e = cs_grbl_gc_line(&g->gc, line, g->lineno, &lp, &d, &end);
    g->in_reader = false;
    bool ok = e == CS_OK;
    if (!ok && g->probe_failed) {
        cs_path_free(&lp); /* Grbl: ALARM:5 and [PRB:..:0] (said), then ok for the line */
        drop_all(g);
        cs_grbl_say(g, "ok");
        return;
    }
    if (!ok) {
        reply_error(g, &d);
    } else if (!inside_travel(g, &lp, 0)) {
        ok = false;
        cs_grbl_gc_undo(&g->gc);
        cs_grbl_say(g, "[MSG:line %u: the move leaves the machine's travel]", g->lineno);
        cs_grbl_say(g, "error:%d", ERR_TARGET);
    } else if (!g->check_mode && !append_moves(&g->pending, &lp)) { /* $C: never run */
        ok = false;
        cs_grbl_gc_undo(&g->gc);
        cs_grbl_say(g, "[MSG:line %u: out of memory]", g->lineno);
        cs_grbl_say(g, "error:%d", ERR_UNSUPPORTED);
    }
    cs_path_free(&lp);
    if (!ok)
        return;
    if (end) {
        cs_grbl_flush(g); /* the reader is back in its start modes (M2 / M30) */
    } else if (g->pending.n >= CS_GRBL_CHUNK_ELEMS) {
        cs_grbl_flush(g);
    }
    cs_grbl_say(g, "ok");
}

/* ---- jogging ($J=) ---- */

/* Checks a jog line's words (Grbl: G20 G21 G90 G91 G53, X Y Z, F; F required). */
static int jog_words(const char *s)
{
    bool f = false, axis = false;
    while (*s) {
        char c = (char)(*s >= 'a' && *s <= 'z' ? *s - 32 : *s);
        if (c == ' ') {
            s++;
            continue;
        }
        char *e;
        double v = strtod(s + 1, &e);
        if (e == s + 1)
            return c >= 'A' && c <= 'Z' ? ERR_NUMBER : ERR_LETTER;
        s = e;
        long gx = lround(v * 10);
        bool mode = c == 'G' && (gx == GC_G20 || gx == GC_G21 || gx == GC_G90 || gx == GC_G91 ||
                                 gx == GC_G53);
        axis = axis || c == 'X' || c == 'Y' || c == 'Z';
        f = f || c == 'F';
        if (!mode && c != 'X' && c != 'Y' && c != 'Z' && c != 'F')
            return ERR_JOG;
    }
    return !f ? ERR_NO_FEED : !axis ? ERR_NO_AXIS : 0;
}

static void jog_line(grbl_t *g, const char *words)
{
    cs_grbl_dev_snap_t s;
    cs_grbl_dev_snap(&g->dev, &s);
    if (g->alarm || s.failed) {
        cs_grbl_say(g, "error:%d", ERR_LOCKED);
        return;
    }
    if (g->pending.n > 0 || (s.busy && !s.busy_jog) || (s.queued > 0 && !g->last_push_jog)) {
        cs_grbl_say(g, "error:%d", ERR_NOT_IDLE);
        return;
    }
    int bad = jog_words(words);
    if (bad) {
        cs_grbl_say(g, "error:%d", bad);
        return;
    }
    /* a jog leaves the parser's modes alone: read, then taken back (its end position kept);
     * G53 is the reader's own (machine coordinates for the line) */
    char line[CS_GRBL_GC_LINE_MAX + 8];
    snprintf(line, sizeof line, "G1 %s", words);
    cs_path_t path;
    cs_path_init(&path);
    cs_path_diag_t d;
    bool end;
    cs_err_t e = cs_grbl_gc_line(&g->gc, line, g->lineno, &path, &d, &end);
    double jog_end[3];
    memcpy(jog_end, g->gc.pos, sizeof jog_end);
    if (e == CS_OK)
        cs_grbl_gc_undo(&g->gc);
    if (e != CS_OK || !inside_travel(g, &path, 0)) {
        cs_path_free(&path);
        cs_grbl_say(g, "error:%d", e != CS_OK ? ERR_JOG : ERR_JOG_TRAVEL);
        return;
    }
    /* the device plans the jog itself (JOG: a straight move at F with its acceleration,
     * docs/protocol.md); 0x85 then stops it decelerating, like any item (HOLD, ABORT) */
    double feed_mm_s = path.n > 0 ? path.elems[path.n - 1].feed_mm_s : 0;
    size_t moves = path.n;
    cs_path_free(&path);
    if (moves == 0) { /* a jog to where the machine is: nothing to do */
        cs_grbl_say(g, "ok");
        return;
    }
    cs_grbl_item_t it = {.jog = true};
    cs_proto_msg_t m = {.type = CS_PROTO_JOG};
    m.u.jog.feed = cs_motion_speed(feed_mm_s);
    cs_stream_job_init(&it.job, CS_STREAM_SEGMENTS);
    if (cs_conv_mm_to_vec(jog_end[0], jog_end[1], jog_end[2], &m.u.jog.target) != CS_OK ||
        cs_stream_job_add_msg(&it.job, &m) != CS_OK || !cs_grbl_dev_push(&g->dev, &it)) {
        cs_stream_job_free(&it.job);
        cs_grbl_say(g, "error:%d", ERR_JOG_TRAVEL);
        return;
    }
    g->last_push_jog = true;
    g->plan_pos[0] = m.u.jog.target.x; /* the next chunk starts where the jog ends */
    g->plan_pos[1] = m.u.jog.target.y;
    g->plan_pos[2] = m.u.jog.target.z;
    cs_grbl_gc_set_pos(&g->gc, jog_end);
    cs_grbl_say(g, "ok");
}

/* ---- status report ('?') ---- */

static const char *state_name(const grbl_t *g, const cs_grbl_dev_snap_t *s)
{
    if (g->alarm || s->failed)
        return "Alarm";
    if (g->check_mode)
        return "Check";
    if (g->homing)
        return "Home";
    if (g->held)
        return s->busy && s->dev_state != CS_PROTO_STATE_HELD ? "Hold:1" : "Hold:0";
    if (s->busy_jog)
        return "Jog";
    if (s->busy || s->queued > 0 || g->pending.n > 0)
        return "Run";
    return "Idle";
}

static void status_report(grbl_t *g)
{
    cs_grbl_dev_snap_t s;
    cs_grbl_dev_snap(&g->dev, &s);
    double mpos[3] = {0, 0, 0};
    for (int a = 0; a < 3 && a < g->m.n_axes; a++)
        mpos[a] = s.have_pos ? cs_grbl_steps_mm(g, a, s.pos[a]) : 0;
    bool wpos = (g->report_mask & 1) == 0;
    char buf[320];
    int n = snprintf(buf, sizeof buf, "<%s|%s:%.3f,%.3f,%.3f", state_name(g, &s),
                     wpos ? "WPos" : "MPos", mpos[0] - (wpos ? g->gc.off[0] : 0),
                     mpos[1] - (wpos ? g->gc.off[1] : 0), mpos[2] - (wpos ? g->gc.off[2] : 0));
    if (g->report_mask & 2)
        n += snprintf(buf + n, sizeof buf - (size_t)n, "|Bf:%zu,%zu", CS_GRBL_DEV_QUEUE - s.queued,
                      CS_GRBL_RX_SIZE - g->rxn);
    n += snprintf(buf + n, sizeof buf - (size_t)n, "|FS:%.0f,%.0f",
                  s.busy && !g->held ? s.speed_mm_min : 0.0,
                  g->sp_code == GC_M5 ? 0.0 : g->sp_s * g->ov.spindle / 100.0);
    char pins[24];
    cs_grbl_pins(g, &s, pins, sizeof pins);
    n += snprintf(buf + n, sizeof buf - (size_t)n, "%s", pins);
    /* Grbl sends WCO every 10 to 30 reports and when it changes, Ov now and then */
    bool wco = g->reports % 10 == 0 || memcmp(g->wco_sent, g->gc.off, sizeof g->wco_sent) != 0;
    if (wco) {
        n += snprintf(buf + n, sizeof buf - (size_t)n, "|WCO:%.3f,%.3f,%.3f", g->gc.off[0],
                      g->gc.off[1], g->gc.off[2]);
        memcpy(g->wco_sent, g->gc.off, sizeof g->wco_sent);
    }
    if (wco || g->ov_changed)
        n += snprintf(buf + n, sizeof buf - (size_t)n, "|Ov:%d,%d,%d", g->ov.feed, g->ov.rapid,
                      g->ov.spindle);
    g->ov_changed = false;
    g->reports++;
    cs_grbl_say(g, "%s>", buf);
}

/* ---- $ commands ---- */

static double mm_min(int32_t q16_mm_s)
{
    return q16_mm_s / 65536.0 * 60.0;
}

static void dollar_settings(grbl_t *g)
{
    const cs_machine_t *m = &g->m;
    int dirmask = 0;
    for (int a = 0; a < 3 && a < m->n_axes; a++)
        dirmask |= m->axis[a].invert_dir ? 1 << a : 0;
    cs_grbl_say(g, "$0=%.0f", m->axis[0].pulse_ticks * 1e6 / m->tick_hz);
    cs_grbl_say(g, "$1=25");
    cs_grbl_say(g, "$2=0");
    cs_grbl_say(g, "$3=%d", dirmask);
    cs_grbl_say(g, "$4=0");
    cs_grbl_say(g, "$5=0");
    cs_grbl_say(g, "$6=0");
    cs_grbl_say(g, "$10=%d", g->report_mask);
    cs_grbl_say(g, "$11=%.3f", cs_conv_pos_to_mm(m->junction_deviation));
    cs_grbl_say(g, "$12=%.3f", cs_conv_pos_to_mm(g->tol));
    cs_grbl_say(g, "$13=0");
    cs_grbl_say(g, "$20=1"); /* the planner always refuses moves outside the travel */
    const cs_ctlcfg_t *c = &g->ctl; /* [homing], [spindle] */
    int homedir = 0; /* Grbl $23: a set bit homes that axis towards its minimum */
    for (int a = 0; a < 3; a++)
        homedir |= c->at_max[a] ? 0 : 1 << a;
    cs_grbl_say(g, "$21=1"); /* the device stops on any limit switch that trips (ALARM:1) */
    cs_grbl_say(g, "$22=%d", c->n_order > 0);
    cs_grbl_say(g, "$23=%d", homedir);
    cs_grbl_say(g, "$24=%.3f", c->latch * 60.0);
    cs_grbl_say(g, "$25=%.3f", c->seek * 60.0);
    cs_grbl_say(g, "$26=0");
    cs_grbl_say(g, "$27=%.3f", c->pulloff);
    cs_grbl_say(g, "$30=%.0f", c->s_max);
    cs_grbl_say(g, "$31=0");
    cs_grbl_say(g, "$32=%d", c->laser);
    for (int a = 0; a < 3; a++)
        cs_grbl_say(g, "$%d=%.3f", 100 + a, m->axis[a].steps_per_mm / 65536.0);
    for (int a = 0; a < 3; a++)
        cs_grbl_say(g, "$%d=%.3f", 110 + a, mm_min(m->axis[a].max_rate));
    for (int a = 0; a < 3; a++)
        cs_grbl_say(g, "$%d=%.3f", 120 + a, m->axis[a].max_accel / 65536.0);
    for (int a = 0; a < 3; a++)
        cs_grbl_say(g, "$%d=%.3f", 130 + a,
            cs_conv_pos_to_mm(m->axis[a].travel_max) - cs_conv_pos_to_mm(m->axis[a].travel_min));
    cs_grbl_say(g, "ok");
}

/* "[NAME:x,y,z]" from parameters #first.. (mm). */
static void say_param3(grbl_t *g, const char *name, int first)
{
    cs_grbl_say(g, "[%s:%.3f,%.3f,%.3f]", name, cs_grbl_gc_param(&g->gc, first),
        cs_grbl_gc_param(&g->gc, first + 1), cs_grbl_gc_param(&g->gc, first + 2));
}

/* $#: the reader's parameters, where LinuxCNC keeps them (G54 #5221.., 20 apart; G28 #5161..;
 * G30 #5181..; G92 #5211.. when #5210 says they apply); PRB in machine coordinates. */
static void dollar_params(grbl_t *g)
{
    for (int k = 0; k < 6; k++) {
        char name[16];
        snprintf(name, sizeof name, "G%d", 54 + k);
        say_param3(g, name, 5221 + 20 * k);
    }
    say_param3(g, "G28", 5161);
    say_param3(g, "G30", 5181);
    if (cs_grbl_gc_param(&g->gc, 5210) != 0)
        say_param3(g, "G92", 5211);
    else
        cs_grbl_say(g, "[G92:0.000,0.000,0.000]");
    cs_grbl_say(g, "[TLO:0.000]");
    cs_grbl_say(g, "[PRB:%.3f,%.3f,%.3f:%d]", g->prb[0], g->prb[1], g->prb[2], g->prb_ok ? 1 : 0);
    cs_grbl_say(g, "ok");
}

static void dollar_modes(grbl_t *g)
{
    const cs_grbl_gc_t *c = &g->gc;
    char motion[24], wcs[16];
    if (c->motion < 0)
        snprintf(motion, sizeof motion, "G80");
    else
        cs_gcode_code_name(motion, sizeof motion, 'G', c->motion);
    static const int systems[] = {GC_G54, GC_G55,   GC_G56,   GC_G57,  GC_G58,
                                  GC_G59, GC_G59_1, GC_G59_2, GC_G59_3};
    cs_gcode_code_name(wcs, sizeof wcs, 'G', systems[c->wcs >= 1 && c->wcs <= 9 ? c->wcs - 1 : 0]);
    char spindle[8];
    cs_gcode_code_name(spindle, sizeof spindle, 'M', c->spindle);
    cs_grbl_say(g, "[GC:%s %s G%d %s %s G94 %s M9 T0 F%g S%g]", motion, wcs, c->plane,
        c->inch ? "G20" : "G21", c->incr ? "G91" : "G90", spindle, c->feed, c->speed);
    cs_grbl_say(g, "ok");
}

/* $N=value: $10 (status report mask) is ours, in memory; the machine's settings are not. */
static void dollar_set(grbl_t *g, const char *s)
{
    char *e;
    long n = strtol(s, &e, 10);
    if (e == s || *e != '=') {
        cs_grbl_say(g, "error:%d", ERR_DOLLAR);
        return;
    }
    char *e2;
    double v = strtod(e + 1, &e2);
    if (e2 == e + 1 || *e2 != '\0') {
        cs_grbl_say(g, "error:%d", ERR_NUMBER);
        return;
    }
    if (n == 10 && v >= 0 && v <= 3 && v == floor(v)) {
        g->report_mask = (int)v;
        cs_grbl_say(g, "ok");
        return;
    }
    cs_grbl_say(g, "[MSG:$%ld is read-only here: the machine file (%s) owns the machine's settings; edit "
           "it and restart curvestep grbl]",
        n, g->cfg->job.machine_file ? g->cfg->job.machine_file : "built-in machine");
    cs_grbl_say(g, "error:%d", ERR_DOLLAR);
}

static void dollar_check(grbl_t *g)
{
    g->check_mode = !g->check_mode;
    cs_grbl_say(g, "[MSG:%s]", g->check_mode ? "Enabled" : "Disabled");
    if (!g->check_mode) { /* Grbl soft-resets when check mode ends */
        cs_grbl_gc_reset_modal(&g->gc, true);
        cs_grbl_sync(g);
        cs_grbl_say(g, "ok");
        cs_grbl_say(g, "%s", GRBL_WELCOME);
        return;
    }
    cs_grbl_say(g, "ok");
}

static void dollar(grbl_t *g, const char *s)
{
    cs_grbl_dev_snap_t st;
    cs_grbl_dev_snap(&g->dev, &st);
    if (strcmp(s, "$") == 0) {
        cs_grbl_say(g, "[HLP:$$ $# $G $I $N $x=val $J=line $C $X $H ~ ! ? ctrl-x]");
        cs_grbl_say(g, "ok");
    } else if (strcmp(s, "$$") == 0) {
        dollar_settings(g);
    } else if (strcmp(s, "$#") == 0) {
        dollar_params(g);
    } else if (strcmp(s, "$G") == 0) {
        dollar_modes(g);
    } else if (strcmp(s, "$I") == 0) {
        cs_grbl_say(g, "[VER:1.1h.20190825:curvestep %s]", CS_VERSION);
        cs_grbl_say(g, "[OPT:,%d,%d]", CS_GRBL_DEV_QUEUE, CS_GRBL_RX_SIZE);
        cs_grbl_say(g, "ok");
    } else if (strcmp(s, "$N") == 0) {
        cs_grbl_say(g, "$N0=");
        cs_grbl_say(g, "$N1=");
        cs_grbl_say(g, "ok");
    } else if (strcmp(s, "$X") == 0) {
        cs_grbl_unlock(g);
    } else if (strcmp(s, "$C") == 0) {
        dollar_check(g);
    } else if (strcmp(s, "$H") == 0) {
        if (g->pending.n > 0 || !cs_grbl_dev_idle(&g->dev))
            cs_grbl_say(g, "error:%d", ERR_NOT_IDLE);
        else
            cs_grbl_home(g);
    } else if (strncmp(s, "$J=", 3) == 0) {
        jog_line(g, s + 3);
    } else if (s[1] >= '0' && s[1] <= '9') {
        dollar_set(g, s + 1);
    } else {
        cs_grbl_say(g, "error:%d", ERR_DOLLAR);
    }
}

/* ---- input ---- */

static void soft_reset(grbl_t *g);

/* One complete line from the receive buffer (no newline). Grbl drops spaces and upper-cases
 * outside comments; cs_gcode takes either, so the line goes as it came. */
static void do_line(grbl_t *g, char *line)
{
    size_t n = strlen(line);
    while (n > 0 && (line[n - 1] == ' ' || line[n - 1] == '\t' || line[n - 1] == '\r'))
        line[--n] = '\0';
    while (*line == ' ' || *line == '\t')
        line++;
    g->lineno++;
    g->t_last_line = cs_serial_now_s();
    if (*line == '\0') {
        cs_grbl_say(g, "ok");
    } else if (*line == '$') {
        for (char *p = line; *p && *p != '='; p++) /* "$j=" as "$J=", "$x" as "$X" */
            *p = (char)(*p >= 'a' && *p <= 'z' ? *p - 32 : *p);
        dollar(g, line);
    } else {
        gcode_line(g, line);
    }
    if (g->reset_pending) {
        g->reset_pending = false;
        soft_reset(g);
    }
}

static void soft_reset(grbl_t *g)
{
    drop_all(g);
    g->rxn = 0;
    g->rx_overflow = false;
    g->held = false;
    g->check_mode = false;
    cs_grbl_gc_reset_modal(&g->gc, true);
    cs_grbl_ov_init(&g->ov); /* Grbl's reset puts the overrides back at 100 % */
    g->ov_changed = true;
    cs_grbl_dev_override(&g->dev, g->ov.feed, g->ov.rapid, g->ov.spindle);
    cs_grbl_say(g, "%s", "");
    cs_grbl_say(g, "%s", GRBL_WELCOME);
}

/* An override byte changed g->ov: the running chunk gets it on the device within ~0.1 s
 * (cs_grbl_dev_override: OVERRIDE), what is planned next is planned at it (apply_overrides).
 * A spindle override while nothing runs goes to the device at once in a job of no messages
 * (its session sends the OVERRIDE), as Grbl changes a running spindle at once. */
static void override_byte(grbl_t *g, unsigned char b)
{
    g->ov_changed = true;
    cs_grbl_dev_override(&g->dev, g->ov.feed, g->ov.rapid, g->ov.spindle);
    if (b >= 0x99 && b <= 0x9D && g->sp_code != GC_M5 && !g->ctl.laser && !g->check_mode &&
        cs_grbl_dev_idle(&g->dev))
        (void)cs_grbl_run_msgs(g, NULL, 0, false);
}

/* A real-time byte (grbl wiki "Interface": picked out of the stream wherever it comes). True
 * when b was one. The overrides 0x90..0x9D act on the running motion and what is planned next
 * (override_byte); safety
 * door 0x84 and the toggles 0x9E..0xA1 are accepted and ignored (docs/controller.md). */
static bool realtime(grbl_t *g, unsigned char b)
{
    cs_grbl_dev_snap_t s;
    switch (b) {
    case '?':
        status_report(g);
        return true;
    case '!':
        cs_grbl_dev_snap(&g->dev, &s);
        if (s.busy || s.queued > 0 || g->pending.n > 0) {
            g->held = true;
            cs_grbl_dev_hold(&g->dev, true);
        }
        return true;
    case '~':
        if (g->held) {
            g->held = false;
            cs_grbl_dev_hold(&g->dev, false);
        }
        return true;
    case 0x18:
        if (g->in_reader) { /* the reader is mid-line (a probe): reset once it is out */
            g->reset_pending = true;
            cs_grbl_dev_cancel(&g->dev, false);
        } else {
            soft_reset(g);
        }
        return true;
    case 0x85: /* jog cancel: hold, then flush the jogs (nothing when not jogging) */
        if (cs_grbl_dev_cancel(&g->dev, true)) {
            g->held = false;
            cs_grbl_sync(g);
        }
        return true;
    default:
        if (cs_grbl_ov_byte(&g->ov, b)) {
            override_byte(g, b);
            return true;
        }
        return b >= 0x80;
    }
}

/* Bytes from the client: real-time ones at once, the rest into the 128-byte buffer. */
static void take_bytes(grbl_t *g, const unsigned char *b, size_t n)
{
    for (size_t k = 0; k < n; k++) {
        if (realtime(g, b[k]))
            continue;
        if (g->rx_overflow) {
            if (b[k] == '\n') {
                g->rx_overflow = false;
                g->lineno++;
                cs_grbl_say(g, "error:%d", ERR_OVERFLOW);
            }
            continue;
        }
        if (g->rxn == sizeof g->rx) { /* a sender that overfills: Grbl loses the byte too */
            g->rx_overflow = memchr(g->rx, '\n', g->rxn) == NULL;
            if (g->rx_overflow)
                g->rxn = 0;
            continue;
        }
        g->rx[g->rxn++] = (char)b[k];
    }
}

/* Reads the complete lines in the buffer while the queue has room. */
static void take_lines(grbl_t *g)
{
    /* room for two items: a line may close the pending chunk and queue a dwell or a jog */
    while (g->rxn > 0 && cs_grbl_dev_room(&g->dev, 2)) {
        char *nl = memchr(g->rx, '\n', g->rxn);
        char *cr = memchr(g->rx, '\r', g->rxn);
        if (nl == NULL || (cr != NULL && cr < nl))
            nl = cr; /* Grbl ends a line at either */
        if (nl == NULL)
            return;
        size_t len = (size_t)(nl - g->rx);
        char line[CS_GRBL_RX_SIZE + 1];
        memcpy(line, g->rx, len);
        line[len] = '\0';
        memmove(g->rx, nl + 1, g->rxn - len - 1);
        g->rxn -= len + 1;
        bool lf_after_cr = len == 0 && nl != cr && g->after_cr; /* "\r\n": one line */
        g->after_cr = nl == cr;
        if (!lf_after_cr)
            do_line(g, line);
    }
}

/* ---- the session ---- */

/* A device run that failed (link closed, device error): Alarm until $X, everything dropped. */
static void watch_device(grbl_t *g)
{
    cs_grbl_dev_snap_t s;
    bool was = g->alarm;
    cs_grbl_watch_alarm(g); /* a device alarm: ALARM:N */
    cs_grbl_dev_snap(&g->dev, &s);
    if (g->alarm && !was) {
        drop_all(g);
    } else if (s.failed && !g->alarm) {
        cs_grbl_say(g, "[MSG:device: %s]", s.why);
        g->alarm = true;
        drop_all(g);
    }
}

bool cs_grbl_listen_parse(const char *spec, struct sockaddr_in *sa)
{
    char addr[64] = "127.0.0.1";
    const char *colon = strrchr(spec, ':');
    const char *port = spec;
    if (colon != NULL) {
        size_t n = (size_t)(colon - spec);
        if (n == 0 || n >= sizeof addr)
            return false;
        memcpy(addr, spec, n);
        addr[n] = '\0';
        port = colon + 1;
    }
    char *e;
    long p = strtol(port, &e, 10);
    memset(sa, 0, sizeof *sa);
    sa->sin_family = AF_INET;
    sa->sin_port = htons((uint16_t)p);
    return *port != '\0' && *e == '\0' && p >= 0 && p <= 65535 &&
           inet_pton(AF_INET, addr, &sa->sin_addr) == 1;
}

/* --listen [ADDR:]PORT: a socket listening there; its address in shown. -1: bad spec, -2: the
 * socket failed (errno). */
static int listen_on(const char *spec, char *shown, size_t cap)
{
    struct sockaddr_in sa;
    if (!cs_grbl_listen_parse(spec, &sa))
        return -1;
    int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    int one = 1;
    if (fd < 0)
        return -2;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    socklen_t len = sizeof sa;
    if (bind(fd, (struct sockaddr *)&sa, sizeof sa) != 0 || listen(fd, 1) != 0 ||
        getsockname(fd, (struct sockaddr *)&sa, &len) != 0) {
        close(fd);
        return -2;
    }
    char addr[INET_ADDRSTRLEN];
    inet_ntop(AF_INET, &sa.sin_addr, addr, sizeof addr);
    snprintf(shown, cap, "%s:%u", addr, (unsigned)ntohs(sa.sin_port));
    return fd;
}

/* Accepts a client on the listening socket (one at a time: a second waits for the first). */
static void accept_client(grbl_t *g, int lfd)
{
    int c = accept4(lfd, NULL, NULL, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (c < 0)
        return;
    g->fd = c;
    g->rxn = 0;
    cs_grbl_say(g, "%s", "");
    cs_grbl_say(g, "%s", GRBL_WELCOME);
}

/* The loop: client bytes, lines while there is room, chunks when the sender pauses. */
static void serve_loop(grbl_t *g, int lfd)
{
    while (!stop_flag) {
        struct pollfd p = {g->fd >= 0 ? g->fd : lfd, POLLIN, 0};
        int r = poll(&p, 1, 5);
        if (r > 0 && g->fd < 0) {
            accept_client(g, lfd);
        } else if (r > 0) {
            unsigned char buf[256];
            ssize_t n = read(g->fd, buf, sizeof buf);
            if (n > 0) {
                take_bytes(g, buf, (size_t)n);
            } else if (lfd >= 0 && (n == 0 || (errno != EAGAIN && errno != EINTR))) {
                close(g->fd); /* the TCP client left: the machine finishes what it was given */
                g->fd = -1;
            }
        }
        take_lines(g);
        if (g->pending.n > 0 && cs_serial_now_s() - g->t_last_line > CS_GRBL_CHUNK_IDLE_MS / 1e3 &&
            cs_grbl_dev_room(&g->dev, 1))
            cs_grbl_flush(g);
        watch_device(g);
    }
}

/* Opens the client side: a pty (path on stdout, optional symlink) or a listening socket. */
static int open_front(grbl_t *g, int *lfd, int *slave)
{
    char shown[300];
    *lfd = *slave = -1;
    if (g->cfg->listen != NULL) {
        *lfd = listen_on(g->cfg->listen, shown, sizeof shown);
        if (*lfd == -1) {
            fprintf(stderr, "curvestep grbl: --listen wants [ADDR:]PORT (an IPv4 address), got "
                            "'%s'\n", g->cfg->listen);
            return CS_EXIT_USAGE;
        }
        if (*lfd < 0) {
            fprintf(stderr, "curvestep grbl: cannot listen on %s: %s\n", g->cfg->listen,
                    strerror(errno));
            return CS_EXIT_INTERNAL;
        }
    } else {
        if (cs_serial_openpty(&g->fd, slave, shown, sizeof shown) != 0) {
            fprintf(stderr, "curvestep grbl: cannot create a pseudo-terminal: %s\n",
                    strerror(errno));
            return CS_EXIT_INTERNAL;
        }
        if (g->cfg->link != NULL && (unlink(g->cfg->link), symlink(shown, g->cfg->link)) != 0) {
            fprintf(stderr, "curvestep grbl: cannot link %s to %s: %s\n", g->cfg->link, shown,
                    strerror(errno));
            return CS_EXIT_INTERNAL;
        }
        cs_grbl_say(g, "%s", GRBL_WELCOME);
    }
    printf("%s\n", shown);
    fflush(stdout);
    return CS_EXIT_OK;
}

static int start(grbl_t *g)
{
    cs_machine_pen_t pen;
    int rc = cs_jobplan_machine("grbl", &g->cfg->job, &g->m, &pen, &g->tol);
    if (rc != CS_EXIT_OK)
        return rc;
    g->feed = cs_motion_speed(g->cfg->job.feed_mm_s);
    char err[512];
    if (cs_ctlcfg_load(g->cfg->job.machine_file, &g->m, &g->ctl, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return CS_EXIT_INPUT;
    }
    cs_gcode_opts_t o;
    cs_gcode_opts_init(&o);
    o.probe = cs_grbl_probe; /* G38.x on the device (PROBE) */
    o.probe_ctx = g;
    o.spindle = cs_grbl_spindle; /* M3/M4/M5 S on the device (SPINDLE) */
    o.spindle_ctx = g;
    if (cs_grbl_gc_init(&g->gc, &o) != CS_OK) {
        fprintf(stderr, "curvestep grbl: out of memory\n");
        return CS_EXIT_INTERNAL;
    }
    cs_path_diag_t d;
    if (g->cfg->state != NULL && cs_grbl_gc_load(&g->gc, g->cfg->state, &d) != CS_OK) {
        fprintf(stderr, "%s:%u:%u: %s (curvestep grbl --state)\n", d.loc.file, d.loc.line,
                d.loc.col, d.reason);
        return CS_EXIT_INPUT;
    }
    const cs_joblink_cfg_t *dc = &g->cfg->dev; /* serial: cs_stream; else cs_grbl_link */
    if (dc->port != NULL && cs_serial_open(&g->ser, dc->port, dc->baud) != 0) {
        fprintf(stderr, "curvestep grbl: cannot open %s: %s\n", dc->port, cs_serial_strerror(errno));
        return CS_EXIT_NO_DEVICE;
    }
    if (dc->port != NULL)
        cs_serial_set_line_rate(&g->ser, dc->line_rate);
    /* the worker takes no signals: SIGINT and SIGTERM stop the main loop */
    sigset_t set, old;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set, &old);
    char why[640] = "cannot start the device thread";
    if (dc->port == NULL)
        rc = cs_grbl_dev_start_link(&g->dev, dc, &g->m, &g->ctl, why, sizeof why);
    else if (cs_grbl_dev_start(&g->dev, &g->ser, &g->m,
                               cs_joblink_line_bps(dc->port, dc->baud, dc->line_rate)) != CS_OK)
        rc = CS_EXIT_INTERNAL;
    pthread_sigmask(SIG_SETMASK, &old, NULL);
    if (rc != CS_EXIT_OK) {
        fprintf(stderr, "curvestep grbl: %s\n", why);
        if (dc->port != NULL)
            cs_serial_close(&g->ser);
        return rc;
    }
    cs_grbl_sync(g); /* Modbus, GPIO: the reader starts where the link says the machine is */
    return CS_EXIT_OK;
}

int cs_grbl_serve(const cs_grbl_cfg_t *cfg)
{
    grbl_t *g = calloc(1, sizeof *g);
    if (g == NULL)
        return CS_EXIT_INTERNAL;
    g->cfg = cfg;
    g->fd = -1;
    g->report_mask = 1; /* Grbl's default $10=1: MPos */
    cs_grbl_ov_init(&g->ov);
    g->sp_code = GC_M5;
    cs_path_init(&g->pending);
    int rc = start(g);
    if (rc != CS_EXIT_OK) {
        cs_grbl_gc_free(&g->gc);
        free(g);
        return rc;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);
    int lfd, slave;
    rc = open_front(g, &lfd, &slave);
    if (rc == CS_EXIT_OK) {
        fprintf(stderr, "curvestep grbl: serving Grbl 1.1 on %s for the %s device on %s\n",
                cfg->listen ? "TCP" : "a pseudo-terminal", cs_grbl_dev_kind(&g->dev),
                g->dev.link ? g->dev.link->l.name : cfg->dev.port);
        serve_loop(g, lfd);
    }
    cs_grbl_dev_stop(&g->dev);
    if (cfg->dev.port != NULL)
        cs_serial_close(&g->ser);
    if (rc == CS_EXIT_OK && cfg->state != NULL && cs_grbl_gc_save(&g->gc, cfg->state) != CS_OK)
        fprintf(stderr, "curvestep grbl: cannot write %s: %s\n", cfg->state, strerror(errno));
    if (cfg->link != NULL && cfg->listen == NULL)
        unlink(cfg->link);
    if (g->fd >= 0)
        close(g->fd);
    if (lfd >= 0)
        close(lfd);
    if (slave >= 0)
        close(slave);
    cs_path_free(&g->pending);
    cs_grbl_gc_free(&g->gc);
    free(g);
    return rc;
}
