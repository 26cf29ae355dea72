/* cs_gpio_ctl: home, probe, jog and unlock over the GPIO link (see cs_gpio_ctl.h). The phases
 * and alarm codes are the device's (firmware/app/cs_fw_ctl.c: seek, back-off, latch 2 x pull-off
 * + 1 mm, pull-off; Grbl's limits_go_home and mc_probe_cycle); each move is planned here with the
 * host planner (cs_motion) and run on the step thread, which stops on the step where the watched
 * input changes. */
#include "cs_gpio_ctl.h"

#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>

#include "cs_cmd.h"
#include "cs_conv.h"
#include "cs_gpio_link.h"
#include "cs_motion.h"
#include "cs_stream_cmd.h"
#include "cs_proto.h"

enum { PH_SEEK, PH_BACKOFF, PH_LATCH, PH_PULLOFF };
/* the latch searches 2 x pull-off + this (mm): the switch is pulloff away after the back-off */
#define LATCH_MARGIN_MM 1.0

static volatile sig_atomic_t interrupted;

static void on_sigint(int sig)
{
    (void)sig;
    interrupted = 1;
}

typedef struct {
    const cs_gpio_ctl_args_t *a;
    cs_joblink_t l;
    cs_gpio_link_t *g;
    FILE *out;                   /* a->out, else stdout */
    volatile sig_atomic_t *stop; /* a->stop, else the SIGINT flag */
} sess_t;

static double steps_mm(const cs_machine_t *m, unsigned i, int64_t steps)
{
    return (double)steps * CS_MOTION_ONE / (double)m->axis[i].steps_per_mm;
}

/* "WHO: WHAT X Y Z mm" at the machine position. */
static void say_pos(const sess_t *s, const char *what)
{
    const cs_machine_t *m = s->a->m;
    fprintf(s->out, "%s: %s", s->a->who, what);
    for (unsigned i = 0; i < m->n_axes; i++)
        fprintf(s->out, "%s%.4f", i ? " " : "", steps_mm(m, i, s->g->st.pos[i]));
    fprintf(s->out, " mm\n");
    fflush(s->out);
}

/* Opens the link for a command moving the axes of mask `axes`, with room for `cap` recorded set
 * calls. -1, or an exit status (said). */
static int sess_open(sess_t *s, const cs_gpio_ctl_args_t *a, unsigned axes, size_t cap)
{
    memset(s, 0, sizeof *s);
    s->a = a;
    cs_joblink_cfg_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.gpio = a->chip;
    cfg.machine_file = a->machine_file;
    int rc = cs_joblink_select(&s->l, &cfg);
    if (rc == CS_EXIT_OK)
        rc = cs_gpio_link_open_ctl(&s->l, a->m, axes, cap);
    if (rc != CS_EXIT_OK) {
        fprintf(stderr, "curvestep %s: %s\n", a->who, s->l.why);
        return s->l.ops ? cs_joblink_close(&s->l, rc) : rc;
    }
    s->g = cs_gpio_link_of(&s->l);
    s->out = a->out != NULL ? a->out : stdout;
    s->stop = a->stop != NULL ? a->stop : &interrupted;
    if (a->stop == NULL) { /* the caller steers otherwise (and owns its signals) */
        interrupted = 0;
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_sigint;
        sigaction(SIGINT, &sa, NULL);
    }
    return -1;
}

static int sess_close(sess_t *s, int rc)
{
    if (s->a->stop == NULL)
        signal(SIGINT, SIG_DFL);
    cs_gpio_ctl_result_t *res = s->a->res;
    if (res != NULL && s->g != NULL && s->g->st_loaded) {
        res->have_state = true;
        memcpy(res->pos, s->g->st.pos, sizeof res->pos);
        res->alarm = s->g->st.alarm;
        res->inputs = s->g->st.inputs;
    }
    return cs_joblink_close(&s->l, rc);
}

static uint16_t inputs_now(const sess_t *s)
{
    cs_gpio_in_poll(&s->g->in);
    return cs_gpio_in_read(&s->g->in, s->g->st.pos);
}

/* Enters the alarm (kept in the state file) and says so: exit 7. */
static int alarm(sess_t *s, uint8_t code, uint16_t bits)
{
    char what[160];
    s->g->st.alarm = code;
    s->g->st.inputs = bits;
    snprintf(what, sizeof what, "ALARM:%u (%s), inputs 0x%03x, stopped at ", (unsigned)code,
             cs_ctlcfg_alarm_text(code), (unsigned)bits);
    say_pos(s, what);
    fprintf(s->out,
            "%s: the machine is in alarm: `curvestep unlock --gpio %s` (or `curvestep home --gpio "
            "%s`) clears it\n",
            s->a->who, s->a->chip, s->a->chip);
    return CS_EXIT_DEV_ERROR;
}

/* Motion refused in alarm (as the device refuses it): exit 7; -1 when not in alarm. */
static int refuse_alarm(sess_t *s)
{
    uint8_t c = s->g->st.alarm;
    if (c == 0)
        return -1;
    fprintf(s->out,
            "%s: refused: the machine is in alarm (ALARM:%u, %s): `curvestep unlock --gpio %s` (or "
            "`curvestep home --gpio %s`) clears it\n",
            s->a->who, (unsigned)c, cs_ctlcfg_alarm_text(c), s->a->chip, s->a->chip);
    return CS_EXIT_DEV_ERROR;
}

/* A straight move on machine pm (the real one: its travel checked; or the opened-up one for
 * homing) from the machine position to `to` (mm) at feed mm/s, watching the inputs. -1 when it
 * ran to its end or to the watched input (*hit), else the exit status (said). */
static int move(sess_t *s, const cs_machine_t *pm, const double to[CS_AXES], double feed,
                uint16_t watch, uint16_t release, bool *hit)
{
    const cs_machine_t *m = s->a->m;
    cs_motion_t mo;
    cs_pos_t p[CS_AXES] = {0}, t[CS_AXES] = {0};
    cs_err_t e = cs_motion_init(&mo, pm);
    if (e != CS_OK)
        return CS_EXIT_INTERNAL;
    for (unsigned i = 0; i < m->n_axes && e == CS_OK; i++)
        if (cs_conv_mm_to_pos(steps_mm(m, i, s->g->st.pos[i]), &p[i]) != CS_OK ||
            cs_conv_mm_to_pos(to[i], &t[i]) != CS_OK)
            e = CS_ERR_RANGE;
    if (e == CS_OK)
        e = cs_planner_set_position(&mo.pl, p);
    if (e == CS_OK)
        e = cs_motion_line(&mo, t, cs_motion_speed(feed), 1);
    if (e == CS_OK)
        e = cs_motion_finish(&mo);
    int rc = -1;
    if (e != CS_OK) {
        fprintf(s->out, "%s: refused: %s\n", s->a->who,
                e == CS_ERR_LIMIT ? "the target is outside the machine's travel (soft limits)"
                                  : "the move cannot be planned");
        rc = e == CS_ERR_LIMIT ? CS_EXIT_DEV_ERROR : CS_EXIT_USAGE;
    } else if (cs_gpio_link_move(&s->l, mo.segs.v, mo.segs.n, watch, release, true, s->stop) != 0) {
        fprintf(stderr, "curvestep %s: cannot start the step thread\n", s->a->who);
        rc = CS_EXIT_INTERNAL;
    }
    cs_motion_free(&mo);
    if (rc >= 0)
        return rc;
    const cs_gpio_run_t *r = &s->g->run;
    *hit = r->outcome == CS_GPIO_RUN_TRIPPED && r->trip_code == 0;
    switch (r->outcome) {
    case CS_GPIO_RUN_DONE:
        return -1;
    case CS_GPIO_RUN_TRIPPED:
        return *hit ? -1 : alarm(s, r->trip_code, r->trip_inputs);
    case CS_GPIO_RUN_HELD:
    case CS_GPIO_RUN_STOPPED:
        say_pos(s, "interrupted: stopped at once (STEP low, ENABLE off) at ");
        return CS_EXIT_INTERRUPTED;
    case CS_GPIO_RUN_IO_ERROR:
        fprintf(stderr, "curvestep %s: setting the lines failed: %s\n", s->a->who,
                strerror(r->io_errno));
        return CS_EXIT_CLOSED;
    case CS_GPIO_RUN_BAD_SEGMENT:
        break;
    }
    fprintf(stderr, "curvestep %s: the executor refused a segment\n", s->a->who);
    return CS_EXIT_DEV_ERROR;
}

/* The machine position in mm, one axis moved by d. */
static void target_along(const sess_t *s, unsigned ax, double d, double to[CS_AXES])
{
    for (unsigned i = 0; i < CS_AXES; i++)
        to[i] = i < s->a->m->n_axes ? steps_mm(s->a->m, i, s->g->st.pos[i]) : 0;
    to[ax] += d;
}

/* True when the switch `bit` can ever be active: a [gpio] line, or the recorder's [limits]. */
static bool has_input(const sess_t *s, unsigned ax, bool at_max, uint16_t bit)
{
    const cs_gpio_link_t *g = s->g;
    if (g->record)
        return bit == CS_PROTO_IN_PROBE ? g->ctl.has_probe
                                        : (at_max ? g->ctl.has_max[ax] : g->ctl.has_min[ax]);
    return bit == CS_PROTO_IN_PROBE ? g->cfg.probe >= 0
                                    : (at_max ? g->cfg.lim_max[ax] : g->cfg.lim_min[ax]) >= 0;
}

/* One axis's homing cycle (the k-th of the order): -1 when homed, else the exit status. */
static int home_axis(sess_t *s, const cs_machine_t *wide, const cs_proto_home_t *h)
{
    static const char names[] = "xyza";
    const cs_machine_t *m = s->a->m;
    unsigned ax = h->axis;
    bool at_max = (h->flags & CS_PROTO_HOME_MAX) != 0;
    double sign = at_max ? 1.0 : -1.0;
    uint16_t bit = at_max ? CS_PROTO_IN_MAX(ax) : CS_PROTO_IN_MIN(ax);
    double seek = (double)h->seek / CS_MOTION_ONE, latch = (double)h->latch / CS_MOTION_ONE;
    double pull = (double)h->pulloff / CS_POS_ONE_MM, search = (double)h->search / CS_POS_ONE_MM;
    int ph = (inputs_now(s) & bit) ? PH_BACKOFF : PH_SEEK;
    for (;;) {
        double to[CS_AXES];
        bool seeking = ph == PH_SEEK || ph == PH_LATCH, hit = false;
        double d = ph == PH_SEEK ? search : ph == PH_LATCH ? 2 * pull + LATCH_MARGIN_MM : -pull;
        target_along(s, ax, sign * d, to);
        int rc = move(s, wide, to, ph == PH_LATCH ? latch : seek, seeking ? bit : 0, 0, &hit);
        if (rc >= 0)
            return rc;
        uint16_t in = s->g->run.inputs;
        if (seeking && !hit)
            return alarm(s, CS_PROTO_ALARM_HOMING_APPROACH, in);
        if (!seeking && (in & bit))
            return alarm(s, CS_PROTO_ALARM_HOMING_PULLOFF, in);
        if (ph == PH_PULLOFF)
            break;
        ph = ph == PH_SEEK ? PH_BACKOFF : ph == PH_BACKOFF ? PH_LATCH : PH_PULLOFF;
    }
    /* the position set: home_pos (mm) in steps, rounded; the switches stay where they are */
    int32_t p = (int32_t)llround((double)h->home_pos / CS_POS_ONE_MM *
                                 ((double)m->axis[ax].steps_per_mm / CS_MOTION_ONE));
    cs_gpio_link_t *g = s->g;
    g->st.off[ax] += (int64_t)g->st.pos[ax] - p;
    g->in.off[ax] = g->st.off[ax];
    g->st.pos[ax] = p;
    g->st.homed = (uint16_t)(g->st.homed | (1u << ax));
    char what[40];
    snprintf(what, sizeof what, "%c homed; machine position ", names[ax]);
    say_pos(s, what);
    return -1;
}

/* Set calls a recorder keeps for moves of `mm` in all (two per step at the finest axis
 * resolution, one DIR change per segment, generous room for the segments). */
static size_t record_cap(const cs_machine_t *m, double mm)
{
    double spm = 0;
    for (unsigned i = 0; i < m->n_axes; i++)
        if ((double)m->axis[i].steps_per_mm / CS_MOTION_ONE > spm)
            spm = (double)m->axis[i].steps_per_mm / CS_MOTION_ONE;
    return (size_t)(2.0 * mm * spm * m->n_axes) + 200000u;
}

int cs_gpio_ctl_home(const cs_gpio_ctl_args_t *a)
{
    const cs_ctlcfg_t *c = a->ctl;
    cs_proto_msg_t msg[CS_AXES];
    double total = 0;
    for (unsigned k = 0; k < c->n_order; k++) {
        if (cs_ctlcfg_home_msg(c, a->m, k, &msg[k]) != CS_OK) {
            fprintf(stderr, "%s:0: [homing]: a value does not fit the HOME message\n",
                    a->machine_file ? a->machine_file : "the built-in machine");
            return CS_EXIT_INPUT;
        }
        const cs_proto_home_t *h = &msg[k].u.home;
        total += ((double)h->search + 5.0 * h->pulloff) / CS_POS_ONE_MM + LATCH_MARGIN_MM;
    }
    unsigned axes = 0;
    for (unsigned k = 0; k < c->n_order; k++)
        axes |= 1u << c->order[k];
    sess_t s;
    int rc = sess_open(&s, a, axes, record_cap(a->m, total));
    if (rc >= 0)
        return rc;
    for (unsigned k = 0; k < c->n_order && rc < 0; k++) {
        const cs_proto_home_t *h = &msg[k].u.home;
        bool at_max = (h->flags & CS_PROTO_HOME_MAX) != 0;
        if (!has_input(&s, h->axis, at_max, at_max ? CS_PROTO_IN_MAX(h->axis)
                                                   : CS_PROTO_IN_MIN(h->axis))) {
            fprintf(stderr, "%s:0: [gpio] wires no %c_%s: the switch [homing] seeks on that axis\n",
                    a->machine_file ? a->machine_file : "the built-in machine", "xyza"[h->axis],
                    at_max ? "max" : "min");
            rc = CS_EXIT_INPUT;
        }
    }
    uint16_t in = rc < 0 ? inputs_now(&s) : 0;
    if (rc < 0 && (in & CS_PROTO_IN_ESTOP))
        rc = alarm(&s, CS_PROTO_ALARM_ESTOP, in);
    if (rc < 0)
        s.g->st.alarm = 0; /* homing clears an alarm */
    cs_machine_t wide = *a->m; /* homing moves are not held to the travel */
    for (unsigned i = 0; i < CS_AXES; i++) {
        wide.axis[i].travel_min = -CS_POS_LIMIT;
        wide.axis[i].travel_max = CS_POS_LIMIT;
    }
    for (unsigned k = 0; k < c->n_order && rc < 0; k++)
        rc = home_axis(&s, &wide, &msg[k].u.home);
    if (rc < 0) {
        say_pos(&s, "machine position ");
        rc = CS_EXIT_OK;
    }
    return sess_close(&s, rc);
}

/* probe and jog: the target of the command line, the 4th axis where it is. */
static void target_of(const sess_t *s, double to[CS_AXES])
{
    target_along(s, 0, 0, to);
    for (unsigned i = 0; i < 3 && i < s->a->m->n_axes; i++)
        to[i] = s->a->xyz[i];
}

/* probe (G38.2..G38.5: the probe input watched) or jog (nothing watched) to the target. */
static int run_target(const cs_gpio_ctl_args_t *a, bool probe)
{
    sess_t s;
    double mm = fabs(a->xyz[0]) + fabs(a->xyz[1]) + fabs(a->xyz[2]) + 8192.0;
    int rc = sess_open(&s, a, 7u, record_cap(a->m, mm)); /* x, y, z */
    if (rc >= 0)
        return rc;
    if (probe && !has_input(&s, 0, false, CS_PROTO_IN_PROBE)) {
        fprintf(stderr, "%s:0: [gpio] wires no probe input (probe = OFFSET)\n",
                a->machine_file ? a->machine_file : "the built-in machine");
        return sess_close(&s, CS_EXIT_INPUT);
    }
    rc = refuse_alarm(&s);
    uint16_t in = rc < 0 ? inputs_now(&s) : 0;
    if (rc < 0 && (in & CS_PROTO_IN_ESTOP))
        rc = alarm(&s, CS_PROTO_ALARM_ESTOP, in);
    if (rc < 0 && probe && ((in & CS_PROTO_IN_PROBE) != 0) != a->away)
        rc = alarm(&s, CS_PROTO_ALARM_PROBE_INITIAL, in);
    bool hit = false;
    if (rc < 0) {
        double to[CS_AXES];
        target_of(&s, to);
        uint16_t p = probe ? CS_PROTO_IN_PROBE : 0;
        rc = move(&s, a->m, to, a->feed, a->away ? 0 : p, a->away ? p : 0, &hit);
    }
    if (rc < 0 && probe) {
        if (a->res != NULL)
            a->res->contact = hit;
        say_pos(&s, hit ? "contact at " : "no contact; ended at ");
        if (!hit && !a->no_error)
            rc = alarm(&s, CS_PROTO_ALARM_PROBE_CONTACT, s.g->run.inputs);
    }
    if (rc < 0) {
        say_pos(&s, "machine position ");
        rc = CS_EXIT_OK;
    }
    return sess_close(&s, rc);
}

int cs_gpio_ctl_probe(const cs_gpio_ctl_args_t *a)
{
    return run_target(a, true);
}

int cs_gpio_ctl_jog(const cs_gpio_ctl_args_t *a)
{
    return run_target(a, false);
}

int cs_gpio_ctl_unlock(const cs_gpio_ctl_args_t *a)
{
    sess_t s;
    int rc = sess_open(&s, a, 0, 16);
    if (rc >= 0)
        return rc;
    uint16_t in = inputs_now(&s);
    if (in & CS_PROTO_IN_ESTOP) {
        fprintf(s.out, "unlock: refused: the e-stop is pressed (inputs 0x%03x); release it first\n",
                (unsigned)in);
        if (s.g->st.alarm == 0)
            s.g->st.alarm = CS_PROTO_ALARM_ESTOP;
        return sess_close(&s, CS_EXIT_DEV_ERROR);
    }
    s.g->st.alarm = 0;
    s.g->st.inputs = in;
    say_pos(&s, "machine position ");
    return sess_close(&s, CS_EXIT_OK);
}
