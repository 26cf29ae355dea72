/* cs_grbl_dev: the worker that runs the Grbl front end's chunks on the device (see
 * cs_grbl_dev.h). cs_stream_run (or on Modbus and GPIO cs_grbl_link's run) owns the link while a
 * chunk runs; it draws its progress bar on a FILE at most ten times a second, and that FILE is a
 * cookie stream whose write function (called on the worker thread, inside the run) copies the
 * device's last report into the shared snapshot: the position `?` reports is what the device
 * said (serial: its STATUS; Modbus: its status registers; GPIO: the segments the step thread
 * has executed), never an estimate. */
#define _GNU_SOURCE /* fopencookie */
#include "cs_grbl_dev.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <termios.h>
#include <time.h>

/* Called with the lock held: takes the device's report from the running chunk's result. The
 * feed (FS:) is the device's speed over its own clock when the report carries it (protocol 3's
 * STATUS tick, the GPIO step thread's), else over the host's time of seeing each new position
 * (Modbus) over a longer window (cs_feedrate; docs/controller.md "FS"). At rest: 0. */
static void take_status(cs_grbl_dev_t *d, const cs_stream_result_t *r)
{
    if (r->dev_state == 0xFF)
        return;
    if (r->dev_timed)
        cs_feedrate_add_tick(&d->fr, r->dev_tick, d->tick_hz, r->dev_pos);
    else
        cs_feedrate_add_host(&d->fr, cs_serial_now_s(), r->dev_pos);
    double spmm[CS_PROTO_AXES_MAX], v;
    for (unsigned i = 0; i < CS_PROTO_AXES_MAX; i++)
        spmm[i] = d->steps_per_mm[i] > 0 ? d->steps_per_mm[i] / 65536.0 : 1.0;
    if (!cs_proto_state_busy(r->dev_state) && r->dev_state != CS_PROTO_STATE_HELD) {
        d->s.speed_mm_min = 0; /* at rest; the next motion starts a new window */
        cs_feedrate_reset(&d->fr);
    } else if (cs_feedrate_mm_min(&d->fr, d->axes, spmm, &v))
        d->s.speed_mm_min = v;
    memcpy(d->s.pos, r->dev_pos, sizeof d->s.pos);
    d->s.have_pos = true;
    d->s.dev_state = r->dev_state;
}

/* Called with the lock held: the OVERRIDE for the running job (docs/protocol.md: feed and
 * rapid relative to the job's plan, spindle absolute; 1/1000). */
static void take_override(cs_grbl_dev_t *d)
{
    uint16_t v[3];
    for (int k = 0; k < 3; k++) {
        double base = k < 2 && d->cur_ov[k] > 0 ? d->cur_ov[k] : 100;
        double r = 1000.0 * d->req_ov[k] / base;
        v[k] = (uint16_t)lround(fmin(fmax(r, 1), CS_PROTO_OVERRIDE_MAX));
    }
    d->run_ov = (cs_proto_override_t){v[0], v[1], v[2]};
}

/* The progress FILE's write: the text itself is not needed, only the moment. */
static ssize_t progress_write(void *cookie, const char *buf, size_t len)
{
    (void)buf;
    cs_grbl_dev_t *d = cookie;
    pthread_mutex_lock(&d->mu);
    if (d->cur != NULL && d->link != NULL)
        cs_grbl_link_where(d->link, d->cur); /* GPIO: the step thread's */
    if (d->cur != NULL)
        take_status(d, d->cur);
    d->run_interrupt = d->req_cancel;
    d->run_pause = d->req_hold;
    take_override(d);
    pthread_mutex_unlock(&d->mu);
    return (ssize_t)len;
}

/* cs_stream's on_event (worker thread): what the device said about alarms, probes, inputs. */
static void on_event(void *ctx, const cs_proto_event_t *ev)
{
    cs_grbl_dev_t *d = ctx;
    pthread_mutex_lock(&d->mu);
    d->s.have_inputs = true;
    d->s.inputs = ev->inputs;
    if (ev->kind == CS_PROTO_EVENT_ALARM) {
        d->s.alarms++;
        d->s.alarm_code = ev->code;
    } else if (ev->kind == CS_PROTO_EVENT_PROBE) {
        d->s.probes++;
        d->s.probe_contact = ev->code != 0;
        for (unsigned i = 0; i < CS_PROTO_AXES_MAX; i++)
            d->s.probe_pos[i] = i < ev->axes ? ev->pos[i] : 0;
    }
    pthread_mutex_unlock(&d->mu);
}

/* The progress FILE whose writes copy the running item's position (ten a second). */
static FILE *open_progress(cs_grbl_dev_t *d)
{
    cookie_io_functions_t io = {.write = progress_write};
    FILE *f = fopencookie(d, "w", io);
    if (f != NULL)
        setvbuf(f, NULL, _IONBF, 0);
    return f;
}

/* The item's run starts: its result shared with the progress FILE, the flags as asked. */
static void begin_run(cs_grbl_dev_t *d, cs_stream_result_t *r)
{
    pthread_mutex_lock(&d->mu);
    d->cur = r;
    d->run_interrupt = d->req_cancel;
    d->run_pause = d->req_hold;
    pthread_mutex_unlock(&d->mu);
}

/* The item's run ended (e, *r): the device's last word kept, a failure noted. */
static void end_run(cs_grbl_dev_t *d, cs_err_t e, const cs_stream_result_t *r, FILE *progress)
{
    pthread_mutex_lock(&d->mu);
    d->cur = NULL;
    take_status(d, r);
    if (e != CS_OK || (r->outcome != CS_STREAM_DONE && r->outcome != CS_STREAM_INTERRUPTED)) {
        d->s.failed = true;
        snprintf(d->s.why, sizeof d->s.why, "%s%s%.150s", cs_stream_outcome_text(r->outcome),
                 r->why[0] ? ": " : "", r->why);
    }
    if (r->outcome == CS_STREAM_INTERRUPTED)
        d->s.cancelled++;
    pthread_mutex_unlock(&d->mu);
    if (progress != NULL)
        fclose(progress);
}

static void run_job(cs_grbl_dev_t *d, const cs_grbl_item_t *it)
{
    cs_stream_opts_t o;
    cs_stream_opts_default(&o, d->ser, d->axes, d->tick_hz);
    cs_stream_link_timing(&o.link, d->bits_per_s);
    o.interrupt = &d->run_interrupt;
    o.pause = &d->run_pause;
    o.quiet_hello = true;
    o.on_event = on_event;
    o.jog_cancel = it->jog; /* Grbl's 0x85 on the device's JOG: JOG_CANCEL */
    o.event_ctx = d;
    o.override = &d->run_ov;
    o.progress = open_progress(d);
    o.progress_tty = true; /* ten updates a second */
    cs_stream_result_t r;
    begin_run(d, &r);
    pthread_mutex_lock(&d->mu);
    d->cur_ov[0] = it->ov_feed;
    d->cur_ov[1] = it->ov_rapid;
    take_override(d);
    pthread_mutex_unlock(&d->mu);
    tcflush(d->ser->fd, TCIFLUSH); /* what the device said between chunks */
    cs_err_t e = cs_stream_run(&it->job, &o, &r);
    end_run(d, e, &r, o.progress);
}

/* An item over Modbus or GPIO (cs_grbl_link), from the position last reported. */
static void run_link(cs_grbl_dev_t *d, const cs_grbl_item_t *it)
{
    cs_joblink_ctl_t c = {&d->run_interrupt, &d->run_pause, open_progress(d), true};
    cs_stream_result_t r;
    memset(&r, 0, sizeof r);
    r.dev_state = 0xFF;
    int32_t pos[CS_PROTO_AXES_MAX];
    begin_run(d, &r);
    pthread_mutex_lock(&d->mu);
    memcpy(pos, d->s.pos, sizeof pos);
    d->link_stop = d->req_cancel;
    pthread_mutex_unlock(&d->mu);
    cs_err_t e = cs_grbl_link_run(d->link, &it->job, pos, &c, &r, on_event, d);
    if (e != CS_OK || (r.outcome != CS_STREAM_DONE && r.outcome != CS_STREAM_INTERRUPTED))
        fprintf(stderr, "curvestep grbl: %s: %s%s%s\n", d->link->l.name,
                cs_stream_outcome_text(r.outcome), r.why[0] ? ": " : "", r.why); /* the log */
    end_run(d, e, &r, c.progress);
}

/* G4: waits, in 10 ms steps, while held or until cancelled. */
static void run_dwell(cs_grbl_dev_t *d, double s)
{
    double end = cs_serial_now_s() + s;
    for (;;) {
        pthread_mutex_lock(&d->mu);
        bool stop = d->req_cancel || d->quit, held = d->req_hold;
        pthread_mutex_unlock(&d->mu);
        if (stop || (!held && cs_serial_now_s() >= end))
            return;
        if (held)
            end += 0.01;
        struct timespec ts = {0, 10 * 1000 * 1000};
        nanosleep(&ts, NULL);
    }
}

static void *worker(void *arg)
{
    cs_grbl_dev_t *d = arg;
    pthread_mutex_lock(&d->mu);
    for (;;) {
        while (!d->quit && (d->n == 0 || d->s.failed))
            pthread_cond_wait(&d->cv, &d->mu);
        if (d->quit)
            break;
        cs_grbl_item_t it = d->q[d->head];
        d->head = (d->head + 1) % CS_GRBL_DEV_QUEUE;
        d->n--;
        d->s.queued = d->n;
        d->s.busy = true;
        d->s.busy_jog = it.jog;
        pthread_mutex_unlock(&d->mu);
        if (it.dwell)
            run_dwell(d, it.dwell_s);
        else if (d->link != NULL)
            run_link(d, &it);
        else
            run_job(d, &it);
        cs_stream_job_free(&it.job);
        pthread_mutex_lock(&d->mu);
        d->req_cancel = false;
        d->s.busy = d->s.busy_jog = false;
        pthread_cond_broadcast(&d->cv);
    }
    pthread_mutex_unlock(&d->mu);
    return NULL;
}

/* The worker's state for machine m, and its thread. */
static cs_err_t start_worker(cs_grbl_dev_t *d, const cs_machine_t *m)
{
    d->axes = m->n_axes;
    d->tick_hz = m->tick_hz;
    for (unsigned i = 0; i < m->n_axes && i < CS_PROTO_AXES_MAX; i++)
        d->steps_per_mm[i] = m->axis[i].steps_per_mm;
    d->req_ov[0] = d->req_ov[1] = d->req_ov[2] = 100;
    pthread_mutex_init(&d->mu, NULL);
    pthread_cond_init(&d->cv, NULL);
    if (pthread_create(&d->th, NULL, worker, d) != 0)
        return CS_ERR_STATE;
    d->started = true;
    return CS_OK;
}

int cs_grbl_dev_start_link(cs_grbl_dev_t *d, const cs_joblink_cfg_t *cfg, const cs_machine_t *m,
                           const cs_ctlcfg_t *ctl, char *why, size_t cap)
{
    memset(d, 0, sizeof *d);
    d->s.dev_state = 0xFF;
    uint8_t alarm;
    int rc = cs_grbl_link_start(&d->lk, cfg, m, ctl, &d->link_stop, d->s.pos, &alarm, why, cap);
    if (rc != 0)
        return rc;
    d->link = &d->lk;
    d->s.have_pos = true; /* the device's registers, the GPIO state (or its origin) */
    d->s.dev_state = CS_PROTO_STATE_IDLE;
    if (alarm != 0) { /* the GPIO state keeps an alarm: said as the device's */
        d->s.alarms = 1;
        d->s.alarm_code = alarm;
    }
    if (start_worker(d, m) != CS_OK) {
        snprintf(why, cap, "cannot start the device thread");
        return 3; /* CS_EXIT_INTERNAL */
    }
    return 0;
}

bool cs_grbl_dev_can(const cs_grbl_dev_t *d, uint8_t t)
{
    return d->link == NULL || cs_grbl_link_can(d->link, t);
}

const char *cs_grbl_dev_kind(const cs_grbl_dev_t *d)
{
    return d->link == NULL ? "serial" : cs_grbl_link_kind(d->link);
}

cs_err_t cs_grbl_dev_start(cs_grbl_dev_t *d, cs_serial_t *ser, const cs_machine_t *m,
                           uint32_t bits_per_s)
{
    memset(d, 0, sizeof *d);
    d->ser = ser;
    d->bits_per_s = bits_per_s;
    d->s.dev_state = 0xFF;
    return start_worker(d, m);
}

bool cs_grbl_dev_room(cs_grbl_dev_t *d, size_t need)
{
    pthread_mutex_lock(&d->mu);
    bool room = d->n + need <= CS_GRBL_DEV_QUEUE;
    pthread_mutex_unlock(&d->mu);
    return room;
}

bool cs_grbl_dev_push(cs_grbl_dev_t *d, cs_grbl_item_t *it)
{
    pthread_mutex_lock(&d->mu);
    bool room = d->n < CS_GRBL_DEV_QUEUE;
    if (room) {
        d->q[(d->head + d->n) % CS_GRBL_DEV_QUEUE] = *it;
        d->n++;
        d->s.queued = d->n;
        pthread_cond_broadcast(&d->cv);
    }
    pthread_mutex_unlock(&d->mu);
    return room;
}

bool cs_grbl_dev_cancel(cs_grbl_dev_t *d, bool only_jogs)
{
    pthread_mutex_lock(&d->mu);
    bool all_jogs = !d->s.busy || d->s.busy_jog;
    for (size_t k = 0; k < d->n; k++)
        all_jogs = all_jogs && d->q[(d->head + k) % CS_GRBL_DEV_QUEUE].jog;
    if (only_jogs && !all_jogs) {
        pthread_mutex_unlock(&d->mu);
        return false;
    }
    for (size_t k = 0; k < d->n; k++)
        cs_stream_job_free(&d->q[(d->head + k) % CS_GRBL_DEV_QUEUE].job);
    d->n = 0;
    d->s.queued = 0;
    d->req_cancel = d->s.busy;
    d->link_stop = d->s.busy; /* a GPIO $H, G38.x: stopped at once (it polls no other flag) */
    while (d->s.busy)
        pthread_cond_wait(&d->cv, &d->mu);
    d->req_hold = false; /* a cancelled hold is over (Grbl: the hold ends with the flush) */
    pthread_mutex_unlock(&d->mu);
    return true;
}

void cs_grbl_dev_override(cs_grbl_dev_t *d, int feed, int rapid, int spindle)
{
    pthread_mutex_lock(&d->mu);
    d->req_ov[0] = feed;
    d->req_ov[1] = rapid;
    d->req_ov[2] = spindle;
    pthread_mutex_unlock(&d->mu);
}

void cs_grbl_dev_hold(cs_grbl_dev_t *d, bool on)
{
    pthread_mutex_lock(&d->mu);
    d->req_hold = on;
    pthread_mutex_unlock(&d->mu);
}

void cs_grbl_dev_clear(cs_grbl_dev_t *d)
{
    pthread_mutex_lock(&d->mu);
    d->s.failed = false;
    d->s.why[0] = '\0';
    pthread_cond_broadcast(&d->cv);
    pthread_mutex_unlock(&d->mu);
}

bool cs_grbl_dev_idle(cs_grbl_dev_t *d)
{
    pthread_mutex_lock(&d->mu);
    bool idle = d->n == 0 && !d->s.busy;
    pthread_mutex_unlock(&d->mu);
    return idle;
}

void cs_grbl_dev_snap(cs_grbl_dev_t *d, cs_grbl_dev_snap_t *s)
{
    pthread_mutex_lock(&d->mu);
    *s = d->s;
    pthread_mutex_unlock(&d->mu);
}

void cs_grbl_dev_stop(cs_grbl_dev_t *d)
{
    if (!d->started)
        return;
    cs_grbl_dev_cancel(d, false);
    pthread_mutex_lock(&d->mu);
    d->quit = true;
    pthread_cond_broadcast(&d->cv);
    pthread_mutex_unlock(&d->mu);
    pthread_join(d->th, NULL);
    pthread_mutex_destroy(&d->mu);
    pthread_cond_destroy(&d->cv);
    d->started = false;
}
