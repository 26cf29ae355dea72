/* cs_sim_device: the simulated device behind a serial line or Modbus. The device itself is the
 * firmware's application (firmware/app: cs_fw_app, the framed-serial front end, over cs_fw_motion,
 * the motion side) running on the POSIX port (firmware/ports/posix); this file adds only what a
 * simulator is for: pacing simulated time against the wall clock (--speed, --instant), fault
 * injection on the line and scheduled resets/hangs/closes, and the results for the report. See
 * cs_sim_device.h and docs/streaming.md ("The device's pacing"). */
#include "cs_sim_device.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cs_fw_app.h"
#include "cs_jobplan.h"
#include "cs_path.h"
#include "cs_sim_exlog.h"
#include "cs_stream.h"
#include "port_posix.h"

/* bytes read from the line a pass, handed to the application CS_FW_RX_CHUNK at a time */
#define RX_BUF 4096

enum { FAULT_NONE, FAULT_RESET, FAULT_HANG, FAULT_CLOSE };

struct cs_sim_motion {
    const cs_sim_device_cfg_t *cfg;
    const cs_machine_t *m;
    cs_sim_device_result_t *res;
    cs_fw_app_t app; /* the device (the Modbus device uses its motion side only) */
    cs_serial_t ser;
    /* what the line gave and the application has not read yet */
    uint8_t rx[RX_BUF];
    size_t rx_len, rx_off;
    /* fault at N: stop taking items after N, drain, report, then act */
    uint64_t fault_at;
    int fault_kind;
    int fault_phase; /* 0 waiting, 1 status sent */
    uint32_t fault_status_at;
    bool hung;
    /* pacing */
    double anchor_wall;
    uint64_t anchor_ticks;
    double last_wall; /* wall time of the last advance, 0 before the first */
    bool dry; /* the executor ran dry after executing something */
    double dry_since;
    uint8_t inv; /* DIR lines inverted (port_posix_reset) */
    cs_sim_exlog_t xl; /* cfg->exlog: the executed log on disk (xl.fd < 0: none) */
    uint32_t seen[3]; /* alarms, probe cycles, homings already marked (note_marks) */
};
typedef struct cs_sim_motion sim_dev_t;

static void note_marks(sim_dev_t *d);

void cs_sim_device_cfg_default(cs_sim_device_cfg_t *cfg, const cs_machine_t *m)
{
    memset(cfg, 0, sizeof *cfg);
    cfg->m = m;
    cfg->queue_size = 32;
    cfg->speed = 1.0;
    cfg->method = CS_TRACE_DEFAULT;
    cfg->status_ms = 50;
}

/* --- the POSIX port's UART, through the simulated line -------------------------------------- */

static size_t uart_read(void *ctx, uint8_t *buf, size_t max)
{
    sim_dev_t *d = ctx;
    size_t n = d->rx_len - d->rx_off;
    if (n > max)
        n = max;
    memcpy(buf, d->rx + d->rx_off, n);
    d->rx_off += n;
    return n;
}

static size_t uart_write(void *ctx, const uint8_t *buf, size_t n)
{
    sim_dev_t *d = ctx;
    /* the executed log first: whatever a STATUS about to go out says finished is on disk, even
     * if the process is killed right after (a log never behind what the host was told) */
    if (d->xl.fd >= 0)
        (void)cs_sim_exlog_flush(&d->xl, &d->app.mo);
    if (cs_serial_write(&d->ser, buf, n) != 0)
        d->ser.lost += n; /* a device UART never blocks: bytes nobody takes are gone */
    return n;
}

/* The same xorshift as the write side (cs_serial): corrupts what arrives too. */
static void corrupt_in(sim_dev_t *d)
{
    for (size_t k = d->rx_off; k < d->rx_len; k++) {
        uint64_t x = d->ser.rng;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        d->ser.rng = x;
        if ((double)(x >> 11) * (1.0 / 9007199254740992.0) < d->cfg->corrupt_in) {
            d->rx[k] ^= (uint8_t)(1u + (uint8_t)((x >> 3) % 255u));
            d->ser.corrupted++;
        }
    }
}

/* --- pacing ---------------------------------------------------------------------------------- */

static void sync_res(sim_dev_t *d)
{
    const cs_fw_stats_t *s = &d->app.mo.stats;
    cs_sim_device_result_t *r = d->res;
    const cs_fw_ctl_t *c = &d->app.mo.ctl;
    r->homings = c->homings;
    r->alarms = c->alarms;
    r->probes = c->probes;
    if (c->alarm != 0)
        r->last_alarm = c->alarm;
    r->executed = s->executed;
    r->segments = s->segments;
    r->curves = s->curves;
    r->holds = s->holds;
    r->aborts = s->aborts;
    r->errors_sent = s->errors_sent;
    r->seg_hash = d->app.mo.log.hash;
    r->out_of_order = d->app.out_of_order;
}

#define SIM_STALL_S 0.05

/* Runs the executor up to wall time `wall` (simulated time = speed x wall time since the executor
 * last started), feeding it from the motion side between runs as the main loop would. */
static void advance(sim_dev_t *d, double wall)
{
    cs_fw_motion_t *mo = &d->app.mo;
    uint32_t seg0 = mo->stats.segments;
    uint64_t target = UINT64_MAX;
    int passes = 256; /* instant: a bounded amount of work a call */
    /* held at rest mid-job: simulated time goes on (the trace shows the pause); otherwise an
     * idle executor restarts the clock's anchor (time spent waiting for the host is skipped) */
    bool held_rest = cs_stepper_idle(&mo->st) && mo->hold.hold && !cs_fw_motion_done(mo);
    if (d->cfg->speed > 0) {
        /* A simulator not scheduled for a while (a loaded machine) is a device whose clock stood
         * still meanwhile: wall time beyond SIM_STALL_S between two passes (the main loop waits
         * at most 5 ms) is skipped, so a starved simulator neither runs its executor ahead of
         * the link nor moves its trace. A host starved meanwhile still lets the queue run dry,
         * and that is reported. */
        if (d->last_wall > 0 && wall - d->last_wall > SIM_STALL_S && !held_rest)
            d->anchor_wall += wall - d->last_wall - SIM_STALL_S;
        d->last_wall = wall;
        if (cs_stepper_idle(&mo->st) && !held_rest) {
            d->anchor_wall = wall;
            d->anchor_ticks = port_posix_now();
        }
        double t = (double)d->anchor_ticks +
                   (wall - d->anchor_wall) * d->cfg->speed * (double)d->m->tick_hz;
        target = t >= 1.8e19 ? UINT64_MAX : (uint64_t)t;
        passes = 4096;
        if (held_rest)
            port_posix_idle_until(target);
    }
    /* At speed, in steps of 1 ms of simulated time with the motion side polled between them, as
     * a device's main loop keeps the executor's ring fed: a simulator starved of the CPU for a
     * while catches up without draining the ring while its queue holds segments (which would
     * restart the executor a tick late, moving every later edge, with no gap to report). */
    uint64_t chunk = d->m->tick_hz / 1000u > 0 ? d->m->tick_hz / 1000u : 1u;
    for (int k = 0; k < passes; k++) {
        cs_fw_motion_poll(mo);
        if (cs_stepper_idle(&mo->st))
            break;
        uint64_t now = port_posix_now();
        port_posix_run(d->cfg->speed > 0 && target > now + chunk ? now + chunk : target);
        if (port_posix_now() >= target)
            break;
    }
    cs_fw_motion_poll(mo);
    note_marks(d);
    if (mo->stats.segments != seg0 && d->dry) {
        d->res->exec_gaps++;
        d->res->gap_wall_s += wall - d->dry_since;
        d->dry = false;
    }
    if (cs_stepper_idle(&mo->st) && !d->dry && mo->stats.executed > 0 && !mo->hold.hold) {
        d->dry = true;
        d->dry_since = wall;
    }
    sync_res(d);
}

/* --- faults: after item N is executed and reported, act ------------------------------------- */

static uint32_t next_boot_id(uint32_t boot)
{
    uint32_t id = boot * 2654435761u + 0x9E3779B9u;
    return id == 0 || id == boot ? boot + 1u : id;
}

/* Returns true when serve must return (close). */
static bool run_fault(sim_dev_t *d, uint32_t now)
{
    cs_fw_motion_t *mo = &d->app.mo;
    if (d->fault_kind == FAULT_NONE || mo->popped < d->fault_at || !cs_fw_motion_drained(mo))
        return false;
    if (d->fault_phase == 0) {
        if (cs_fw_app_send_status(&d->app)) {
            d->fault_phase = 1;
            d->fault_status_at = now;
        }
        return false;
    }
    /* wait until the STATUS saying so was acknowledged (or 500 ms; times in us) */
    if (cs_link_unacked(&d->app.link) != 0 && (uint32_t)(now - d->fault_status_at) < 500000u)
        return false;
    int kind = d->fault_kind;
    d->fault_kind = FAULT_NONE;
    d->fault_phase = 0;
    cs_fw_motion_take_limit(mo, 0);
    if (kind == FAULT_RESET) {
        d->res->resets++;
        cs_fw_app_reboot(&d->app, next_boot_id(d->app.boot));
        d->res->boot_id = d->app.boot;
    } else if (kind == FAULT_HANG) {
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

static void arm_faults(sim_dev_t *d)
{
    const cs_sim_device_cfg_t *cfg = d->cfg;
    d->fault_kind = cfg->reset_after   ? FAULT_RESET
                    : cfg->hang_after  ? FAULT_HANG
                    : cfg->close_after ? FAULT_CLOSE
                                       : FAULT_NONE;
    d->fault_at = cfg->reset_after  ? cfg->reset_after
                  : cfg->hang_after ? cfg->hang_after
                                    : cfg->close_after;
    if (d->fault_kind != FAULT_NONE)
        cs_fw_motion_take_limit(&d->app.mo, (uint32_t)d->fault_at);
}

/* Reads what the line has (waiting up to wait_ms); -1 when the line is gone. */
static int read_line(sim_dev_t *d, int wait_ms)
{
    ssize_t n = cs_serial_read(&d->ser, d->rx, sizeof d->rx, wait_ms);
    if (n < 0) {
        if (errno == EIO || errno == EBADF)
            return -1;
        sleep_ms(5);
        n = 0;
    }
    d->rx_len = (size_t)n;
    d->rx_off = 0;
    if (n > 0 && d->cfg->corrupt_in > 0)
        corrupt_in(d);
    return 0;
}

/* One pass of the device: the line read, the application run over it, time advanced. */
/* A machine-control event happened (a counter moved): note where the machine is. */
static void note_marks(sim_dev_t *d)
{
    const cs_fw_ctl_t *c = &d->app.mo.ctl;
    if (!d->cfg->keep_edges) /* the marks go with the edges (cs_sim_exec_free) */
        return;
    uint32_t now[3] = {c->alarms, c->probes, c->homings};
    cs_sim_exec_t *ex = &d->res->ex;
    for (unsigned k = 0; k < 3; k++) {
        for (; d->seen[k] < now[k]; d->seen[k]++) {
            void *b = ex->marks;
            size_t cap = ex->nmarks;
            if (!cs_path_grow(&b, &cap, ex->nmarks + 1, sizeof *ex->marks))
                return;
            ex->marks = b;
            cs_sim_mark_t *mk = &ex->marks[ex->nmarks++];
            mk->t = port_posix_now();
            mk->kind = (uint8_t)(k == 0 ? CS_SIM_MARK_ALARM : k == 1 ? CS_SIM_MARK_PROBE
                                                                      : CS_SIM_MARK_HOMED);
            for (unsigned i = 0; i < 3; i++)
                mk->p[i] = i < d->m->n_axes ? (double)port_posix_position(i) * CS_MOTION_ONE /
                                                  (double)d->m->axis[i].steps_per_mm
                                            : 0;
        }
    }
}

static volatile sig_atomic_t g_estop, g_estop_seen;

void cs_sim_device_estop(bool pressed)
{
    g_estop = pressed ? 1 : 0;
}

/* The simulated machine's inputs: [limits] and [probe] at the physical position (the steps on
 * the STEP/DIR lines since start, in mm). */
static uint16_t sim_inputs(void *ctx, const int64_t *pos)
{
    const sim_dev_t *d = ctx;
    double mm[CS_AXES] = {0};
    for (unsigned i = 0; i < d->m->n_axes; i++)
        mm[i] = (double)pos[i] * CS_MOTION_ONE / (double)d->m->axis[i].steps_per_mm;
    return cs_ctlcfg_inputs(d->cfg->ctl, mm);
}

static cs_err_t serve_pass(sim_dev_t *d, double *last_rx_s)
{
    cs_fw_motion_t *mo = &d->app.mo;
    if (g_estop != g_estop_seen) { /* the pin interrupt of the e-stop */
        g_estop_seen = g_estop;
        port_posix_inputs_force(CS_PROTO_IN_ESTOP, g_estop ? CS_PROTO_IN_ESTOP : 0);
    }
    bool busy = !cs_fw_motion_done(mo) && !mo->hold.hold;
    if (read_line(d, busy ? 1 : 5) != 0)
        return CS_ERR_IO;
    if (d->rx_len > 0)
        *last_rx_s = cs_serial_now_s();
    do /* the application reads CS_FW_RX_CHUNK bytes a poll */
        cs_fw_app_poll(&d->app);
    while (d->rx_off < d->rx_len);
    advance(d, cs_serial_now_s());
    cs_fw_app_poll(&d->app); /* STATUS, ERROR and acknowledgements after the motion moved */
    if (d->xl.fd >= 0 && cs_sim_exlog_flush(&d->xl, &d->app.mo) != CS_OK)
        return CS_ERR_IO;
    return CS_OK;
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
    port_posix_uart_hooks(uart_read, uart_write, d);
    double start = cs_serial_now_s();
    uint32_t seed = (uint32_t)getpid() ^ (uint32_t)(start * 1e6);
    cs_fw_app_reboot(&d->app, cfg->boot_id != 0 ? cfg->boot_id : seed ^ 0xA5A5A5A5u);
    res->boot_id = d->app.boot;
    arm_faults(d);
    double last_rx_s = start;
    cs_err_t rc = CS_OK;
    while (stop == NULL || !*stop) {
        if (d->hung) {
            sleep_ms(10);
            continue;
        }
        rc = serve_pass(d, &last_rx_s);
        if (rc != CS_OK)
            break;
        if (run_fault(d, cs_serial_now_us()))
            break;
        if (cfg->idle_exit_s > 0 && d->app.mo.stats.executed > 0 && cs_fw_motion_done(&d->app.mo) &&
            cs_serial_now_s() - last_rx_s > cfg->idle_exit_s)
            break;
    }
    port_posix_uart_hooks(NULL, NULL, NULL);
    res->link = d->app.link.stats;
    res->frames = d->app.link.dec.stats;
    res->bytes_in = d->ser.bytes_in;
    res->bytes_out = d->ser.bytes_out;
    res->wall_s = cs_serial_now_s() - start;
    cs_err_t ce = cs_sim_motion_close(d);
    return rc != CS_OK ? rc : ce;
}

/* --- the motion side, shared with the Modbus device ---------------------------------------- */

static uint32_t clock_us(void)
{
    return cs_serial_now_us();
}

cs_err_t cs_sim_motion_open(sim_dev_t **out, const cs_sim_device_cfg_t *cfg,
                            cs_sim_device_result_t *res)
{
    *out = NULL;
    memset(res, 0, sizeof *res);
    if (cfg == NULL || cfg->m == NULL || cfg->queue_size < 1 ||
        cfg->queue_size > CS_SIM_DEVICE_QUEUE_MAX)
        return CS_ERR_ARG;
    sim_dev_t *d = calloc(1, sizeof *d);
    if (d == NULL)
        return CS_ERR_FULL;
    d->cfg = cfg;
    d->m = cfg->m;
    d->res = res;
    for (unsigned i = 0; i < d->m->n_axes; i++)
        if (d->m->axis[i].invert_dir)
            d->inv = (uint8_t)(d->inv | (1u << i));
    port_posix_reset(d->m->tick_hz, d->inv);
    port_posix_record(true);
    port_posix_inputs_force(0, 0);
    g_estop = g_estop_seen = 0;
    bool model = cfg->ctl != NULL && cs_ctlcfg_has_inputs(cfg->ctl);
    port_posix_inputs_model(model ? sim_inputs : NULL, d);
    /* the application on the POSIX port, its link on the wall clock in microseconds with the
     * timing of the simulated line (cs_linktime_link, as the host computes it) */
    cs_fw_app_cfg_t ac;
    cs_fw_app_cfg_default(&ac, d->m);
    ac.motion.queue_size = cfg->queue_size;
    ac.motion.tol = cfg->tol > 0 ? cfg->tol : d->m->tolerance;
    ac.motion.method = (uint8_t)cfg->method;
    ac.clock = clock_us;
    ac.clock_hz = 1000000u;
    ac.link.keepalive = 0;
    if (cs_linktime_link(&ac.link, (uint32_t)cfg->line_rate, ac.clock_hz) != CS_OK) {
        port_stepper_attach(NULL);
        free(d);
        return CS_ERR_ARG;
    }
    ac.status_ms = cfg->status_ms ? cfg->status_ms : 50;
    cs_err_t e = cs_fw_app_init_cfg(&d->app, d->m, cfg->boot_id ? cfg->boot_id : 1u, &ac);
    if (e != CS_OK) {
        port_stepper_attach(NULL);
        free(d);
        return CS_ERR_ARG;
    }
    res->seg_hash = d->app.mo.log.hash;
    d->xl.fd = -1;
    if (cfg->exlog != NULL && cs_sim_exlog_open(&d->xl, cfg->exlog, &d->app.mo) != CS_OK) {
        port_stepper_attach(NULL);
        free(d);
        return CS_ERR_IO;
    }
    *out = d;
    return CS_OK;
}

cs_fw_motion_t *cs_sim_motion_fw(sim_dev_t *d)
{
    return &d->app.mo;
}

cs_err_t cs_sim_motion_queue(sim_dev_t *d, const cs_proto_msg_t *m, uint16_t seq)
{
    return cs_fw_motion_queue(&d->app.mo, m, seq);
}

void cs_sim_motion_hold(sim_dev_t *d, bool on)
{
    cs_fw_motion_hold(&d->app.mo, on);
    sync_res(d);
}

void cs_sim_motion_abort(sim_dev_t *d)
{
    cs_fw_motion_abort(&d->app.mo);
    sync_res(d);
}

void cs_sim_motion_advance(sim_dev_t *d, double wall_s)
{
    advance(d, wall_s);
}

uint16_t cs_sim_motion_free_slots(const sim_dev_t *d)
{
    return cs_fw_motion_free(&d->app.mo);
}

void cs_sim_motion_status(const sim_dev_t *d, cs_proto_status_t *st)
{
    cs_fw_motion_status(&d->app.mo, st);
    st->boot_id = d->app.boot;
}

bool cs_sim_motion_pop_error(sim_dev_t *d, cs_proto_error_t *e)
{
    bool got = cs_fw_motion_pop_error(&d->app.mo, e);
    sync_res(d);
    return got;
}

bool cs_sim_motion_done(const sim_dev_t *d)
{
    return cs_fw_motion_done(&d->app.mo);
}

bool cs_sim_motion_started(const sim_dev_t *d)
{
    return d->app.mo.stats.executed > 0;
}

bool cs_sim_motion_busy(const sim_dev_t *d)
{
    return !cs_fw_motion_done(&d->app.mo) && !d->app.mo.hold.hold;
}

/* Appends a pseudo-segment of `ticks` ticks (split below 2^31 ticks each) to s. */
static cs_err_t pen_span(cs_motion_segs_t *s, uint64_t ticks)
{
    do {
        uint64_t t = ticks > ((uint64_t)1 << 31) ? (uint64_t)1 << 31 : ticks;
        void *b = s->v;
        if (!cs_path_grow(&b, &s->cap, s->n + 1, sizeof *s->v))
            return CS_ERR_FULL;
        s->v = b;
        s->v[s->n++] = (cs_segment_t){(uint32_t)t, {0, 0, 0, 0}};
        ticks -= t;
    } while (ticks > 0);
    return CS_OK;
}

/* The device's pen settings as res->pen_segs (see cs_sim_device.h). */
static cs_err_t keep_pens(cs_sim_device_result_t *res)
{
    size_t np;
    const port_posix_pen_t *p = port_posix_pens(&np);
    cs_motion_segs_t *s = &res->pen_segs;
    uint64_t at = 0;
    cs_err_t e = CS_OK;
    for (size_t i = 0; i < np && e == CS_OK; i++) {
        e = pen_span(s, p[i].t - at);
        at = p[i].t;
        void *b = s->pens;
        if (e == CS_OK && !cs_path_grow(&b, &s->cappens, s->npens + 1, sizeof *s->pens))
            e = CS_ERR_FULL;
        s->pens = b;
        if (e == CS_OK)
            s->pens[s->npens++] = (cs_motion_pen_t){s->n, p[i].pulse_us};
    }
    return e == CS_OK && np > 0 ? pen_span(s, port_posix_now() - at + 1) : e;
}

/* Copies the port's recorded edges into res->ex (keep_edges). */
static cs_err_t keep_edges(sim_dev_t *d)
{
    cs_sim_device_result_t *res = d->res;
    cs_err_t rc = CS_OK;
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
    size_t ns;
    const port_posix_spindle_t *sp = port_posix_spindles(&ns);
    if (rc == CS_OK && ns > 0) {
        res->ex.spins = malloc(ns * sizeof *sp);
        if (res->ex.spins == NULL)
            rc = CS_ERR_FULL;
        else
            memcpy(res->ex.spins, sp, ns * sizeof *sp);
        res->ex.nspins = res->ex.spins != NULL ? ns : 0;
    }
    for (unsigned i = 0; i < CS_AXES; i++) {
        res->ex.pos[i] = port_posix_position(i);
        res->ex.exec_pos[i] = cs_stepper_position(&d->app.mo.st, i);
    }
    return rc;
}

cs_err_t cs_sim_motion_close(sim_dev_t *d)
{
    cs_sim_device_result_t *res = d->res;
    cs_err_t rc = CS_OK;
    /* what the executor still holds is executed (a stop request finishes the ring) */
    port_posix_run(UINT64_MAX);
    cs_fw_motion_poll(&d->app.mo);
    sync_res(d);
    if (d->xl.fd >= 0) {
        if (cs_sim_exlog_flush(&d->xl, &d->app.mo) != CS_OK)
            rc = CS_ERR_IO;
        cs_sim_exlog_close(&d->xl, &d->app.mo);
    }
    res->ticks = port_posix_now();
    /* the lines' count, plus what SETPOS stated (the lines did not move for that) */
    for (unsigned i = 0; i < CS_AXES; i++)
        res->pos[i] = port_posix_position(i) + d->app.mo.set_delta[i];
    res->log_segs = d->app.mo.log;
    res->log_edges = port_posix_edge_log();
    if (d->cfg->keep_edges)
        rc = keep_edges(d);
    (void)port_posix_pens(&res->pens);
    if (rc == CS_OK && d->cfg->keep_edges)
        rc = keep_pens(res);
    const port_posix_spindle_t *sp = port_posix_spindles(&res->spindles);
    for (size_t i = 0; i < res->spindles; i++)
        if (sp[i].duty > res->max_duty)
            res->max_duty = sp[i].duty;
    port_posix_inputs_model(NULL, NULL);
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
#include "cs_sim_check.h"
#include "cs_sim_draw.h"

static volatile sig_atomic_t g_stop;

static void on_signal(int sig)
{
    (void)sig;
    g_stop = 1;
}

static void on_estop(int sig)
{
    cs_sim_device_estop(sig == SIGUSR1);
}

static void device_usage(FILE *f)
{
    fputs("usage: curvestep-sim --pty | --port DEV [--baud N] [--machine FILE.ini] [--queue N]\n"
          "                     [--speed X | --instant] [--line-rate BPS] [--faults SPEC]\n"
          "                     [--tol MM] [--idle-exit S] [--reference JOB] [--check]\n"
          "                     [--svg OUT.svg] [--png OUT.png] [--trace OUT.csv]\n"
          "                     [--exlog FILE]\n"
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
          "  --reference JOB   the job: measure the deviation and the final position; give it\n"
          "                    the input and layout options given to stream (--lenient,\n"
          "                    --fit, --merge ...: curvestep-sim --help lists them)\n"
          "  --check           exit 4 when a check of the report fails\n"
          "  --exlog FILE      append a line `JOB_NO TICKS X Y Z A` for every step segment the\n"
          "                    executor finished (written as they finish: a killed device\n"
          "                    leaves what it did; restarts append to the same file)\n"
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
    cs_jobopts_init(&o->in);
}

int cs_sim_device_opt(int argc, char **argv, int *i, cs_sim_device_opts_t *o)
{
    int r = cs_jobopts_option("sim", argc, argv, i, &o->in);
    if (r != 0)
        return r;
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

enum { DEV_OK = 0, DEV_INPUT = 1, DEV_USAGE = 2, DEV_INTERNAL = 3 };

/* One run of the device program: its options, machine, configuration, reference, line. */
typedef struct {
    cs_sim_device_opts_t o;
    const char *port;
    const char *exlog; /* --exlog FILE (cs_sim_exlog) */
    bool pty;
    long line_rate;
    cs_machine_t m;
    cs_machine_pen_t pen; /* mode servo: the check follows the device's pen settings */
    cs_sim_device_cfg_t cfg;
    cs_ctlcfg_t ctl; /* [limits], [probe]: the simulated switches and probe surface */
    cs_sim_ref_t ref;
    double end_mm[3];
    int fd, keep;
} device_run_t;

/* Parses argv into d: -1 to go on, else the exit status (--help, a usage error). */
static int device_parse(int argc, char **argv, device_run_t *d)
{
    cs_sim_device_opts_default(&d->o);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        bool has = i + 1 < argc;
        char *end = NULL;
        int took = cs_sim_device_opt(argc, argv, &i, &d->o);
        if (took < 0)
            return DEV_USAGE;
        if (took > 0)
            continue;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            device_usage(stdout);
            return DEV_OK;
        } else if (strcmp(a, "--pty") == 0) {
            d->pty = true;
        } else if (strcmp(a, "--port") == 0 && has) {
            d->port = argv[++i];
        } else if (strcmp(a, "--exlog") == 0 && has) {
            d->exlog = argv[++i];
        } else if (strcmp(a, "--line-rate") == 0 && has) {
            d->line_rate = strtol(argv[++i], &end, 10);
            if (*end != '\0' || d->line_rate < 0) {
                fprintf(stderr, "curvestep-sim: %s wants a number\n", a);
                return DEV_USAGE;
            }
        } else {
            fprintf(stderr, "curvestep-sim: unknown or incomplete option %s\n", a);
            device_usage(stderr);
            return DEV_USAGE;
        }
    }
    if (d->pty == (d->port != NULL)) {
        fprintf(stderr, "curvestep-sim: give exactly one of --pty and --port DEV\n");
        return DEV_USAGE;
    }
    if (d->o.queue < 1 || d->o.queue > CS_SIM_DEVICE_QUEUE_MAX) {
        fprintf(stderr, "curvestep-sim: --queue wants 1..%d\n", CS_SIM_DEVICE_QUEUE_MAX);
        return DEV_USAGE;
    }
    if (d->port != NULL && !cs_serial_baud_ok((uint32_t)d->o.baud)) {
        fprintf(stderr, "curvestep-sim: --baud %ld is not a termios rate\n", d->o.baud);
        return DEV_USAGE;
    }
    return -1;
}

/* The machine, the device's configuration and the reference job (loaded first: a bad job is
 * reported before anything is served). DEV_OK or the exit status. */
static int device_setup(device_run_t *d)
{
    const cs_sim_device_opts_t *o = &d->o;
    cs_machine_ini_pen_default(&d->pen);
    char err[512];
    if (o->machine_file) {
        if (cs_machine_ini_load_pen(o->machine_file, &d->m, &d->pen, err, sizeof err) != 0) {
            fprintf(stderr, "%s\n", err);
            return DEV_INPUT;
        }
    } else {
        cs_machine_ini_default(&d->m);
    }
    if (cs_ctlcfg_load(o->machine_file, &d->m, &d->ctl, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return DEV_INPUT;
    }
    cs_sim_device_cfg_t *cfg = &d->cfg;
    cs_sim_device_cfg_default(cfg, &d->m);
    cfg->ctl = &d->ctl;
    cfg->queue_size = (uint16_t)o->queue;
    cfg->speed = o->instant ? 0 : o->speed;
    cfg->line_rate = (uint32_t)d->line_rate;
    cfg->idle_exit_s = o->idle_exit;
    cfg->keep_edges = true;
    cfg->exlog = d->exlog;
    if (d->exlog != NULL) { /* said now when the log cannot be written, not as a closed line */
        int xfd = open(d->exlog, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
        if (xfd < 0) {
            fprintf(stderr, "curvestep-sim: --exlog %s: %s\n", d->exlog, strerror(errno));
            return DEV_INPUT;
        }
        close(xfd);
    }
    if (o->tol_mm > 0 && cs_conv_tol_to_pos(o->tol_mm, &cfg->tol) != CS_OK) {
        fprintf(stderr, "curvestep-sim: --tol %g mm is outside the accepted range\n", o->tol_mm);
        return DEV_USAGE;
    }
    if (o->faults != NULL && parse_faults(o->faults, cfg) != 0) {
        fprintf(stderr, "curvestep-sim: --faults: bad list '%s' (see --help)\n", o->faults);
        return DEV_USAGE;
    }
    if (o->out.reference == NULL)
        return DEV_OK;
    cs_jobplan_t jp; /* read and laid out as plan / stream do (cs_jobopts) */
    cs_jobplan_init(&jp);
    cs_err_t e = cs_jobplan_reference(&jp, o->out.reference, &o->in, o->machine_file, &d->m);
    if (e == CS_OK)
        e = cs_sim_ref_from_path(&d->ref, &jp.path, d->end_mm);
    else
        cs_path_diag_print(stderr, &jp.diag);
    cs_jobplan_free(&jp);
    return e == CS_OK ? DEV_OK : DEV_INPUT;
}

/* The line: a new pseudo-terminal (its path printed) or the --port tty. DEV_OK or the status. */
static int device_line(device_run_t *d)
{
    if (d->pty) {
        char name[256];
        if (cs_serial_openpty(&d->fd, &d->keep, name, sizeof name) != 0) {
            perror("curvestep-sim: openpty");
            return DEV_INTERNAL;
        }
        /* keep our own slave fd open: the master never sees a hang-up between two hosts, and
         * a host that opens the path flushes what piled up meanwhile */
        printf("%s\n", name);
        fflush(stdout);
        return DEV_OK;
    }
    cs_serial_t ser;
    if (cs_serial_open(&ser, d->port, (uint32_t)d->o.baud) != 0) {
        fprintf(stderr, "curvestep-sim: %s: %s\n", d->port, cs_serial_strerror(errno));
        return DEV_INPUT;
    }
    d->fd = ser.fd;
    return DEV_OK;
}

/* Serves until the line closes or a signal, then the device's and the link's lines and the
 * report (checks, pictures). The exit status. */
static int device_serve(device_run_t *d)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    sa.sa_handler = on_estop;
    sigaction(SIGUSR1, &sa, NULL);
    sigaction(SIGUSR2, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);
    cs_sim_device_result_t res;
    cs_err_t e = cs_sim_device_serve(d->fd, &d->cfg, &g_stop, &res);
    close(d->fd);
    if (d->keep >= 0)
        close(d->keep);
    int rc = DEV_OK;
    if (e != CS_OK && e != CS_ERR_IO) {
        fprintf(stderr, "curvestep-sim: device failed: %s\n", cs_err_text(e));
        rc = DEV_INTERNAL;
    }
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
    if (res.homings || res.alarms || res.probes || res.spindles) {
        char last[32] = "";
        if (res.alarms)
            snprintf(last, sizeof last, " (last ALARM:%u)", (unsigned)res.last_alarm);
        printf("control: %u axes homed, %u alarms%s, %u probe cycles; spindle: %zu settings, "
               "largest duty %u/1000\n",
               (unsigned)res.homings, (unsigned)res.alarms, last, (unsigned)res.probes,
               res.spindles, (unsigned)res.max_duty);
    }
    const cs_sim_device_opts_t *o = &d->o;
    cs_sim_device_out_t out = {o->out.reference, o->out.trace, o->out.svg, o->out.png,
                               o->out.check,     &d->ref,      {0, 0, 0},  NULL};
    memcpy(out.end_mm, d->end_mm, sizeof d->end_mm);
    if (d->pen.mode == CS_MACHINE_PEN_SERVO)
        out.pen = &d->pen;
    rc = cs_sim_device_report(&d->m, &d->cfg, &res, &out, true, rc);
    fflush(stdout);
    cs_sim_exec_free(&res.ex);
    cs_motion_segs_free(&res.pen_segs);
    return rc;
}

int cs_sim_device_main(int argc, char **argv)
{
    device_run_t *d = calloc(1, sizeof *d);
    if (d == NULL)
        return DEV_INTERNAL;
    d->fd = d->keep = -1;
    cs_sim_ref_init(&d->ref);
    int rc = device_parse(argc, argv, d); /* >= 0: --help or a usage error, nothing to run */
    if (rc < 0) {
        rc = device_setup(d);
        if (rc == DEV_OK)
            rc = device_line(d);
        if (rc == DEV_OK)
            rc = device_serve(d);
    }
    cs_sim_ref_free(&d->ref);
    free(d);
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
    printf("executed step segments' hash (FNV-1a 32, in order): %08llx\n",
           (unsigned long long)res.seg_hash);
    /* the execution log in the words of the Cortex-M3 image's report (main_m3.c) */
    printf("log: %u segments hash %u, %u step edges hash %u at executor tick %u\n",
           (unsigned)res.log_segs.n, (unsigned)res.log_segs.hash, (unsigned)res.log_edges.n,
           (unsigned)res.log_edges.hash, (unsigned)res.log_edges.clock);
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
    if (res.pens > 0)
        printf("pen: the device set the servo pen %zu times (PEN messages)\n", res.pens);
    if (reference && o->pen != NULL) { /* the plotter check, by the device's pen settings */
        ok = cs_sim_check_print(&m, &res.pen_segs, &res.ex, &ref, o->pen, end_mm) && ok;
    } else if (reference) {
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
