/* cs_grbl_link: the Grbl front end's items over Modbus and GPIO (see cs_grbl_link.h). */
#include "cs_grbl_link.h"

#include <stdio.h>
#include <string.h>

#include "cs_cmd.h"
#include "cs_stream_cmd.h"
#include "cs_conv.h"
#include "cs_gpio_ctl.h"
#include "cs_gpio_link.h"
#include "cs_modbus_stream.h"
#include "cs_motion.h"

/* The GPIO link's state (position, alarm) as it opens for a job: opened on an empty job and
 * closed again (nothing runs, nothing is recorded). rc as cs_joblink_open. */
static int gpio_peek(cs_grbl_link_t *k, int32_t pos[CS_PROTO_AXES_MAX], uint8_t *alarm)
{
    cs_stream_job_t empty;
    cs_stream_job_init(&empty, CS_STREAM_SEGMENTS);
    cs_joblink_job_t j = {.m = k->m, .job = &empty};
    int rc = cs_joblink_open(&k->l, &j);
    const cs_gpio_link_t *g = cs_gpio_link_of(&k->l);
    if (g != NULL && g->st_loaded) { /* read before the alarm check that may refuse the job */
        for (unsigned i = 0; i < CS_PROTO_AXES_MAX && i < CS_AXES; i++)
            pos[i] = g->st.pos[i];
        *alarm = g->st.alarm;
        rc = rc == CS_EXIT_DEV_ERROR ? CS_EXIT_OK : rc;
    }
    char why[sizeof k->l.why];
    memcpy(why, k->l.why, sizeof why);
    cs_joblink_close(&k->l, rc);
    memcpy(k->l.why, why, sizeof why);
    cs_stream_job_free(&empty);
    return rc;
}

/* Modbus: where the device's registers say the machine stands. */
static int modbus_peek(cs_grbl_link_t *k, int32_t pos[CS_PROTO_AXES_MAX])
{
    const cs_joblink_cfg_t *c = &k->l.cfg;
    cs_mb_client_t mb;
    if (cs_mb_open_link(&mb, c->modbus_tcp, c->modbus_rtu, c->baud, c->parity, c->unit,
                        c->mb_timeout_ms, k->l.why, sizeof k->l.why) != 0)
        return CS_EXIT_NO_DEVICE;
    cs_mb_status_t st;
    cs_mb_rc_t rc = cs_mb_read_status(&mb, &st);
    cs_mb_close(&mb);
    if (rc != CS_MB_OK) {
        snprintf(k->l.why, sizeof k->l.why, "%s: the device does not answer its status", k->l.name);
        return CS_EXIT_NO_DEVICE;
    }
    for (unsigned i = 0; i < CS_PROTO_AXES_MAX; i++)
        pos[i] = i < st.axes && i < CS_AXES ? st.pos[i] : 0;
    return CS_EXIT_OK;
}

int cs_grbl_link_start(cs_grbl_link_t *k, const cs_joblink_cfg_t *cfg, const cs_machine_t *m,
                       const cs_ctlcfg_t *ctl, volatile sig_atomic_t *stop,
                       int32_t pos[CS_PROTO_AXES_MAX], uint8_t *alarm, char *why, size_t cap)
{
    memset(k, 0, sizeof *k);
    memset(pos, 0, CS_PROTO_AXES_MAX * sizeof *pos);
    *alarm = 0;
    int rc = cs_joblink_select(&k->l, cfg);
    k->m = m;
    k->ctl = ctl;
    k->stop = stop;
    k->gpio = cfg->gpio != NULL;
    if (rc == CS_EXIT_OK && k->l.ops->check != NULL)
        rc = k->l.ops->check(&k->l, m);
    if (rc == CS_EXIT_OK)
        rc = k->gpio ? gpio_peek(k, pos, alarm) : modbus_peek(k, pos);
    if (rc != CS_EXIT_OK)
        snprintf(why, cap, "%s", k->l.why);
    return rc;
}

bool cs_grbl_link_can(const cs_grbl_link_t *k, uint8_t t)
{
    switch (t) {
    case CS_PROTO_SEGMENT:
    case CS_PROTO_JOG: /* planned here as a straight move */
    case CS_PROTO_UNLOCK:
        return true;
    case CS_PROTO_HOME: /* the GPIO link's switches (cs_gpio_ctl); Modbus has no such message */
    case CS_PROTO_PROBE:
        return k->gpio;
    default: /* SPINDLE: neither link drives one */
        return false;
    }
}

const char *cs_grbl_link_kind(const cs_grbl_link_t *k)
{
    return k->l.ops->kind;
}

/* A refused item: the device error outcome with its sentence. */
static void refuse(cs_stream_result_t *r, const char *fmt, const char *a)
{
    r->outcome = CS_STREAM_DEVICE_ERROR;
    snprintf(r->why, sizeof r->why, fmt, a);
}

/* After a GPIO chunk (or its refusal): the alarm the machine is in when it is new (a hard
 * limit or the e-stop tripped, or the state refused the job), and the inputs. */
static void gpio_after(const cs_gpio_link_t *g, bool refused, const cs_stream_result_t *r,
                       cs_grbl_link_event_fn ev, void *ctx)
{
    if (g == NULL || !g->has_in)
        return;
    bool tripped = !refused && g->run.outcome == CS_GPIO_RUN_TRIPPED && g->run.trip_code != 0;
    cs_proto_event_t e = {
        .kind = CS_PROTO_EVENT_INPUTS, .inputs = g->st.inputs, .axes = CS_PROTO_AXES_MAX};
    memcpy(e.pos, r->dev_pos, sizeof e.pos);
    if (tripped || (refused && g->st.alarm != 0)) {
        e.kind = CS_PROTO_EVENT_ALARM;
        e.code = tripped ? g->run.trip_code : g->st.alarm;
    }
    ev(ctx, &e);
}

/* A chunk of segments through cs_joblink (opened for it), from pos. */
static cs_err_t run_segments(cs_grbl_link_t *k, const cs_stream_job_t *job,
                             const int32_t pos[CS_PROTO_AXES_MAX], const cs_joblink_ctl_t *c,
                             cs_stream_result_t *r, cs_grbl_link_event_fn ev, void *ev_ctx)
{
    int32_t start[CS_PROTO_AXES_MAX];
    memcpy(start, pos, sizeof start);
    cs_joblink_job_t j = {.m = k->m, .job = job, .start_pos = start};
    int rc = cs_joblink_open(&k->l, &j);
    const cs_gpio_link_t *g = k->gpio ? cs_gpio_link_of(&k->l) : NULL;
    if (g != NULL && g->st_loaded) /* the position the GPIO state keeps (homing set it) */
        for (unsigned i = 0; i < CS_PROTO_AXES_MAX && i < CS_AXES; i++)
            start[i] = g->st.pos[i];
    cs_err_t e = CS_OK;
    if (rc != CS_EXIT_OK) {
        refuse(r, "%.300s", k->l.why);
        memcpy(r->dev_pos, start, sizeof r->dev_pos);
        gpio_after(g, true, r, ev, ev_ctx);
    } else {
        memcpy(k->sum, start, sizeof k->sum);
        k->sum_k = g != NULL ? g->first : 0;
        k->running = true;
        e = cs_joblink_run(&k->l, &j, c, r);
        k->running = false;
        gpio_after(g, false, r, ev, ev_ctx);
    }
    cs_joblink_close(&k->l, rc);
    return e;
}

/* $J=: a straight move from pos to the JOG's target at its feed, planned here. */
static cs_err_t run_jog(cs_grbl_link_t *k, const cs_proto_jog_t *jog,
                        const int32_t pos[CS_PROTO_AXES_MAX], const cs_joblink_ctl_t *c,
                        cs_stream_result_t *r, cs_grbl_link_event_fn ev, void *ev_ctx)
{
    cs_motion_t mo;
    cs_pos_t p[CS_AXES] = {0}, t[CS_AXES] = {0};
    cs_err_t e = cs_motion_init(&mo, k->m);
    if (e != CS_OK)
        return e;
    for (unsigned i = 0; i < k->m->n_axes && i < CS_PROTO_AXES_MAX; i++)
        e = e != CS_OK
                ? e
                : cs_conv_mm_to_pos((double)pos[i] * 65536.0 / k->m->axis[i].steps_per_mm, &p[i]);
    memcpy(t, p, sizeof t);
    t[0] = jog->target.x;
    t[1] = jog->target.y;
    t[2] = k->m->n_axes > 2 ? jog->target.z : 0;
    e = e != CS_OK ? e : cs_planner_set_position(&mo.pl, p);
    e = e != CS_OK ? e : cs_motion_line(&mo, t, jog->feed, 1);
    e = e != CS_OK ? e : cs_motion_finish(&mo);
    cs_stream_job_t job;
    cs_stream_job_init(&job, CS_STREAM_SEGMENTS);
    e = e != CS_OK ? e : cs_stream_job_add_segments(&job, mo.segs.v, mo.segs.n);
    cs_motion_free(&mo);
    if (e == CS_OK)
        e = run_segments(k, &job, pos, c, r, ev, ev_ctx);
    else
        refuse(r, "the jog cannot be planned: %s",
               e == CS_ERR_LIMIT ? "its target is outside the travel" : "out of range or memory");
    cs_stream_job_free(&job);
    return CS_OK;
}

/* What the serial device says in EVENTs, from a GPIO command's result: the alarm it entered
 * (new since was), the probe's contact, the inputs. */
static void gpio_events(const cs_gpio_ctl_result_t *res, uint8_t was, bool probe,
                        cs_grbl_link_event_fn ev, void *ctx)
{
    cs_proto_event_t e = {
        .kind = CS_PROTO_EVENT_INPUTS, .inputs = res->inputs, .axes = CS_PROTO_AXES_MAX};
    memcpy(e.pos, res->pos, sizeof e.pos);
    if (probe) {
        e.kind = CS_PROTO_EVENT_PROBE;
        e.code = res->contact;
        ev(ctx, &e);
    }
    e.kind = res->alarm != 0 && res->alarm != was ? CS_PROTO_EVENT_ALARM : CS_PROTO_EVENT_INPUTS;
    e.code = e.kind == CS_PROTO_EVENT_ALARM ? res->alarm : 0;
    ev(ctx, &e);
}

/* $H, G38.x, $X on GPIO: cs_gpio_ctl's command, its lines in the log (stderr). */
static cs_err_t run_gpio_ctl(cs_grbl_link_t *k, const cs_proto_msg_t *m,
                             const int32_t pos[CS_PROTO_AXES_MAX], cs_stream_result_t *r,
                             cs_grbl_link_event_fn ev, void *ctx)
{
    cs_gpio_ctl_result_t res = {0};
    cs_gpio_ctl_args_t a = {.chip = k->l.cfg.gpio,
                            .machine_file = k->l.cfg.machine_file,
                            .m = k->m,
                            .ctl = k->ctl,
                            .out = stderr,
                            .stop = k->stop,
                            .res = &res};
    uint8_t was = 0;
    int rc;
    if (m->type == CS_PROTO_HOME) {
        a.who = "home";
        rc = cs_gpio_ctl_home(&a);
    } else if (m->type == CS_PROTO_PROBE) {
        a.who = "probe";
        a.feed = (double)m->u.probe.feed / 65536.0;
        a.xyz[0] = cs_conv_pos_to_mm(m->u.probe.target.x);
        a.xyz[1] = cs_conv_pos_to_mm(m->u.probe.target.y);
        a.xyz[2] = cs_conv_pos_to_mm(m->u.probe.target.z);
        a.away = (m->u.probe.flags & CS_PROTO_PROBE_AWAY) != 0;
        a.no_error = (m->u.probe.flags & CS_PROTO_PROBE_NO_ERROR) != 0;
        rc = cs_gpio_ctl_probe(&a);
    } else {
        a.who = "unlock";
        was = 0xFF; /* an e-stop that keeps the alarm is said again */
        rc = cs_gpio_ctl_unlock(&a);
    }
    r->dev_state = CS_PROTO_STATE_IDLE;
    for (unsigned i = 0; i < CS_PROTO_AXES_MAX; i++)
        r->dev_pos[i] = res.have_state && i < CS_AXES ? res.pos[i] : pos[i];
    if (res.have_state) {
        memcpy(res.pos, r->dev_pos, sizeof res.pos);
        gpio_events(&res, was, m->type == CS_PROTO_PROBE, ev, ctx);
    }
    /* an alarm is said by its event, as the serial device's */
    bool alarmed = rc == CS_EXIT_DEV_ERROR && res.alarm != 0;
    r->outcome = rc == CS_EXIT_INTERRUPTED     ? CS_STREAM_INTERRUPTED
                 : rc == CS_EXIT_OK || alarmed ? CS_STREAM_DONE
                                               : CS_STREAM_DEVICE_ERROR;
    if (r->outcome == CS_STREAM_DEVICE_ERROR)
        snprintf(r->why, sizeof r->why, "%s over GPIO failed (exit %d; the log says why)", a.who,
                 rc);
    return CS_OK;
}

cs_err_t cs_grbl_link_run(cs_grbl_link_t *k, const cs_stream_job_t *job,
                          const int32_t pos[CS_PROTO_AXES_MAX], const cs_joblink_ctl_t *c,
                          cs_stream_result_t *r, cs_grbl_link_event_fn ev, void *ev_ctx)
{
    memset(r, 0, sizeof *r);
    r->dev_state = 0xFF;
    const cs_proto_msg_t *m = job->n > 0 ? &job->v[0] : NULL;
    uint8_t t = m != NULL ? m->type : CS_PROTO_SEGMENT;
    if (t == CS_PROTO_SEGMENT || t == CS_PROTO_PEN)
        return run_segments(k, job, pos, c, r, ev, ev_ctx);
    if (t == CS_PROTO_JOG)
        return run_jog(k, &m->u.jog, pos, c, r, ev, ev_ctx);
    if (t == CS_PROTO_SPINDLE && m->u.spindle.mode == CS_PROTO_SPINDLE_OFF && job->n == 1) {
        r->outcome = CS_STREAM_DONE; /* M5 with no spindle: off already */
        return CS_OK;
    }
    if (t == CS_PROTO_UNLOCK && !k->gpio) {
        r->outcome = CS_STREAM_DONE; /* Modbus: no alarm on the device to leave */
        return CS_OK;
    }
    if (!cs_grbl_link_can(k, t) || !k->gpio) {
        refuse(r, "the %.20s link does not carry this command", cs_grbl_link_kind(k));
        return CS_OK;
    }
    /* HOME x n (the whole [homing] order), PROBE, UNLOCK (+ SPINDLE off): one command */
    return run_gpio_ctl(k, m, pos, r, ev, ev_ctx);
}

void cs_grbl_link_where(cs_grbl_link_t *k, cs_stream_result_t *r)
{
    if (!k->gpio || !k->running)
        return;
    const cs_gpio_link_t *g = cs_gpio_link_of(&k->l);
    size_t ex = cs_gpio_run_executed(&g->run);
    for (; k->sum_k < ex && k->sum_k < g->nsegs; k->sum_k++) {
        for (unsigned i = 0; i < CS_PROTO_AXES_MAX && i < CS_AXES; i++)
            k->sum[i] += g->segs[k->sum_k].steps[i];
        k->ticks += g->segs[k->sum_k].ticks;
    }
    memcpy(r->dev_pos, k->sum, sizeof r->dev_pos);
    r->dev_timed = true;
    r->dev_tick = k->ticks;
    r->dev_state = cs_gpio_run_paused(&g->run) ? CS_PROTO_STATE_HELD : CS_PROTO_STATE_RUNNING;
}
