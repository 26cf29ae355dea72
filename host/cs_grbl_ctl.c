/* cs_grbl_ctl: the Grbl front end's machine control through the device's messages
 * (docs/protocol.md, "Machine control"): $H as one HOME per axis of the machine file's [homing]
 * order, $X as UNLOCK, G38.x as PROBE with the contact from the device's EVENT, M3/M4/M5 and S
 * as SPINDLE in queue order (laser mode: off in rapids, M4's power scaled by speed on the
 * device, as Grbl's $32=1), ALARM:N from the device's alarm EVENT and Pn: from its inputs.
 * Grbl 1.1 semantics from the grbl wiki ("Interface": alarm codes, Pn; "Laser Mode"). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cs_conv.h"
#include "cs_gcode_words.h"
#include "cs_grbl_int.h"
#include "cs_motion.h"

/* True when the device's link carries messages of type t; else false, with why (what: the
 * command) said to the client and in the log (docs/controller.md, "Links"). */
static bool link_can(grbl_t *g, uint8_t t, const char *what)
{
    if (cs_grbl_dev_can(&g->dev, t))
        return true;
    const char *kind = cs_grbl_dev_kind(&g->dev);
    cs_grbl_say(g, "[MSG:line %u: %s: the %s link cannot do it (%s can; docs/controller.md)]",
                g->lineno, what, kind, t == CS_PROTO_SPINDLE ? "--port" : "--port or --gpio");
    fprintf(stderr, "curvestep grbl: line %u: %s refused: the %s link cannot do it\n", g->lineno,
            what, kind);
    return false;
}

void cs_grbl_watch_alarm(grbl_t *g)
{
    cs_grbl_dev_snap_t s;
    cs_grbl_dev_snap(&g->dev, &s);
    if (s.alarms == g->alarms_seen)
        return;
    g->alarms_seen = s.alarms;
    /* the device's alarm codes are Grbl's ALARM:N (cs_proto_alarm_t) */
    cs_grbl_say(g, "ALARM:%u", (unsigned)s.alarm_code);
    g->alarm = true;
}

void cs_grbl_home(grbl_t *g)
{
    if (g->ctl.n_order == 0) {
        cs_grbl_say(g, "[MSG:homing is not configured: no [homing] order in the machine file]");
        cs_grbl_say(g, "error:%d", ERR_HOMING);
        return;
    }
    if (!link_can(g, CS_PROTO_HOME, "$H (homing)")) {
        cs_grbl_say(g, "error:%d", ERR_HOMING);
        return;
    }
    cs_proto_msg_t m[CS_AXES];
    for (unsigned k = 0; k < g->ctl.n_order; k++)
        if (cs_ctlcfg_home_msg(&g->ctl, &g->m, k, &m[k]) != CS_OK) {
            cs_grbl_say(g, "[MSG:[homing] of the machine file does not fit a HOME message]");
            cs_grbl_say(g, "error:%d", ERR_HOMING);
            return;
        }
    /* Grbl: $H is how an alarm is left after a limit trip; the device's HOME unlocks too */
    g->alarm = false;
    cs_grbl_dev_clear(&g->dev);
    g->homing = true;
    bool ok = cs_grbl_run_msgs(g, m, g->ctl.n_order, true);
    g->homing = false;
    cs_grbl_watch_alarm(g);
    cs_grbl_sync(g);
    if (!ok || g->alarm) {
        g->alarm = true;
        cs_grbl_say(g, "error:%d", ERR_LOCKED);
        return;
    }
    cs_grbl_say(g, "ok");
}

void cs_grbl_unlock(grbl_t *g)
{
    cs_grbl_dev_snap_t s;
    cs_grbl_dev_snap(&g->dev, &s);
    if (g->alarm || s.failed)
        cs_grbl_say(g, "[MSG:Caution: Unlocked]");
    bool dev_alarm = s.alarms > 0 && g->alarm;
    g->alarm = false;
    cs_grbl_dev_clear(&g->dev);
    if (dev_alarm) {
        /* UNLOCK takes no queue slot, so nothing would report it executed: the spindle off
         * behind it (what the alarm left anyway) does */
        cs_proto_msg_t m[2] = {{.type = CS_PROTO_UNLOCK}, {.type = CS_PROTO_SPINDLE}};
        if (!cs_grbl_run_msgs(g, m, 2, true)) {
            cs_grbl_dev_snap(&g->dev, &s);
            cs_grbl_say(g, "[MSG:the device stays locked: %s]", s.why);
            g->alarm = true;
            cs_grbl_dev_clear(&g->dev);
        }
        g->sp_code = GC_M5;
    }
    cs_grbl_sync(g);
    cs_grbl_say(g, "ok");
}

cs_err_t cs_grbl_probe(void *ctx, int code, const double from[3], const double to[3],
                       double feed_mm_s, bool *contact, double hit[3])
{
    grbl_t *g = ctx;
    (void)from;
    memcpy(hit, to, 3 * sizeof *hit);
    *contact = true;
    if (g->check_mode) /* $C: checked, nothing moves; the contact is taken at the target */
        return CS_OK;
    if (!link_can(g, CS_PROTO_PROBE, "G38.x (probing)"))
        return CS_ERR_UNSUPPORTED;
    cs_grbl_flush(g); /* the moves before the probe run first */
    cs_proto_msg_t m = {.type = CS_PROTO_PROBE};
    if (cs_conv_mm_to_vec(to[0], to[1], to[2], &m.u.probe.target) != CS_OK)
        return CS_ERR_RANGE;
    m.u.probe.feed = cs_motion_speed(feed_mm_s);
    m.u.probe.flags = (uint8_t)((code == GC_G38_4 || code == GC_G38_5 ? CS_PROTO_PROBE_AWAY : 0) |
                                (code == GC_G38_3 || code == GC_G38_5 ? CS_PROTO_PROBE_NO_ERROR
                                                                       : 0));
    cs_grbl_dev_snap_t s0, s;
    cs_grbl_dev_snap(&g->dev, &s0);
    cs_grbl_run_msgs(g, &m, 1, true);
    cs_grbl_dev_snap(&g->dev, &s);
    cs_grbl_sync(g);
    *contact = s.probes > s0.probes && s.probe_contact;
    for (int a = 0; a < 3 && a < g->m.n_axes; a++)
        hit[a] = cs_grbl_steps_mm(g, a, s.probes > s0.probes ? s.probe_pos[a] : s.pos[a]);
    /* Grbl reports every probe cycle: [PRB:x,y,z:ok], machine coordinates */
    memcpy(g->prb, hit, sizeof g->prb);
    g->prb_ok = *contact;
    /* Grbl 1.1's mc_probe_cycle on no contact: the alarm (ALARM:5, from the realtime check) is
     * reported first, then [PRB:..:0], then the line's own "ok" (gc_execute_line returns
     * STATUS_OK; the alarm locks what follows): cs_grbl probe_failed answers ok for the line */
    cs_grbl_watch_alarm(g);
    g->probe_failed = !*contact && g->alarm;
    cs_grbl_say(g, "[PRB:%.3f,%.3f,%.3f:%d]", hit[0], hit[1], hit[2], *contact ? 1 : 0);
    return CS_OK;
}

/* The SPINDLE message for code (M3/M4/M5) at s; in a laser's rapid run (rapid) the power is 0,
 * and M4's full power is at feed_mm_s (the run's F: the device scales by speed). */
static cs_proto_msg_t spindle_msg(const grbl_t *g, int code, double s, bool rapid,
                                  double feed_mm_s)
{
    cs_proto_msg_t m = {.type = CS_PROTO_SPINDLE};
    m.u.spindle.mode = code == GC_M3   ? CS_PROTO_SPINDLE_CW
                       : code == GC_M4 ? CS_PROTO_SPINDLE_CCW
                                       : CS_PROTO_SPINDLE_OFF;
    /* the spindle override is the device's (OVERRIDE, cs_grbl_dev_override): S as programmed */
    double duty = g->ctl.s_max > 0 ? s / g->ctl.s_max : 0;
    duty = fmin(fmax(duty, 0.0), 1.0) * CS_PROTO_SPINDLE_FULL;
    m.u.spindle.power = code == GC_M5 || rapid ? 0 : (uint16_t)lround(duty);
    if (g->ctl.laser) {
        m.u.spindle.flags = CS_PROTO_SPINDLE_LASER;
        /* Grbl's laser mode: M4 dynamic (power x speed / F), M3 constant */
        m.u.spindle.feed = code == GC_M4 ? cs_motion_speed(feed_mm_s) : 0;
    }
    return m;
}

cs_err_t cs_grbl_spindle(void *ctx, int code, double s)
{
    grbl_t *g = ctx;
    if (g->check_mode)
        return CS_OK;
    if (code != GC_M5 &&
        !link_can(g, CS_PROTO_SPINDLE, code == GC_M3 ? "M3 (spindle)" : "M4 (spindle)"))
        return CS_ERR_UNSUPPORTED; /* M5: off, as a machine without one is */
    if (g->ctl.laser && code == g->sp_code && code != GC_M5) {
        /* Grbl's laser mode: an S change takes effect with the next move, without a stop;
         * the moves carry their S (cs_path_elem_t) into the plan's power marks */
        g->sp_s = s;
        return CS_OK;
    }
    /* M3/M4/M5 are synchronous, in laser mode too (Grbl's gc_execute_block: spindle_sync) */
    cs_grbl_flush(g); /* the moves before the change run with the state before it */
    g->sp_code = code;
    g->sp_s = s;
    if (g->ctl.laser && code != GC_M5)
        return CS_OK; /* the power goes with the moves (cs_grbl_laser_job) */
    cs_proto_msg_t m = spindle_msg(g, code, s, false, 0);
    return cs_grbl_run_msgs(g, &m, 1, false) ? CS_OK : CS_ERR_STATE;
}

void cs_grbl_flush(grbl_t *g)
{
    cs_grbl_queue_path(g, &g->pending);
}

cs_err_t cs_grbl_laser_job(const grbl_t *g, const cs_motion_segs_t *sg, cs_stream_job_t *job)
{
    /* each power mark of the plan becomes a SPINDLE right before its first SEGMENT: the device
     * takes it from the queue in order and sets it with that segment, without stopping
     * (cs_fw_ctl_take: a laser SPINDLE that is not M5 is "live") */
    size_t k0 = 0;
    cs_err_t e = CS_OK;
    for (size_t p = 0; p <= sg->npowers && e == CS_OK; p++) {
        size_t k1 = p < sg->npowers ? sg->powers[p].seg : sg->n;
        if (k1 > k0)
            e = cs_stream_job_add_segments(job, sg->v + k0, k1 - k0);
        k0 = k1 > k0 ? k1 : k0;
        if (e != CS_OK || p == sg->npowers)
            continue;
        const cs_motion_power_t *pw = &sg->powers[p];
        if (pw->spindle != 3 && pw->spindle != 4)
            continue; /* M5 moves: the synchronous M5 before them turned it off */
        double feed = pw->feed_mm_s > 0 ? pw->feed_mm_s
                                        : (g->feed > 0 ? g->feed : g->m.default_feed) / 65536.0;
        cs_proto_msg_t m = spindle_msg(g, pw->spindle == 4 ? GC_M4 : GC_M3, pw->s, pw->rapid,
                                       feed);
        e = cs_stream_job_add_msg(job, &m);
    }
    return e;
}

void cs_grbl_pins(const grbl_t *g, const cs_grbl_dev_snap_t *s, char *out, size_t cap)
{
    (void)g;
    out[0] = '\0';
    if (!s->have_inputs || s->inputs == 0 || cap < 16)
        return;
    /* Grbl 1.1 "Pn:": X Y Z limit pins, P probe; R (reset/abort) stands for the e-stop */
    size_t n = (size_t)snprintf(out, cap, "|Pn:");
    for (unsigned a = 0; a < 3; a++)
        if (s->inputs & (CS_PROTO_IN_MIN(a) | CS_PROTO_IN_MAX(a)))
            out[n++] = (char)('X' + a);
    if (s->inputs & CS_PROTO_IN_PROBE)
        out[n++] = 'P';
    if (s->inputs & CS_PROTO_IN_ESTOP)
        out[n++] = 'R';
    out[n] = '\0';
    if (n == 4)
        out[0] = '\0';
}
