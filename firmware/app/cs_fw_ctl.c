/* cs_fw_ctl: hard limits, e-stop and the alarm state; homing, jog cancel, probing; the spindle
 * and the laser's power per segment. See cs_fw_ctl.h; the messages are docs/protocol.md,
 * "Machine control". The homing cycle is Grbl 1.1's (seek, back off, latch, pull off: Grbl's
 * limits.c, limits_go_home), the probe's checks Grbl's mc_probe_cycle, the alarm codes Grbl's. */
#include "cs_fw_ctl.h"

#include <stddef.h>

#include "cs_fw_motion.h"
#include "port.h"

enum { PH_SEEK, PH_BACKOFF, PH_LATCH, PH_PULLOFF };
/* the latch searches 2 x pull-off + this (mm Q16): the switch is pulloff away after the back-off */
#define LATCH_MARGIN ((cs_pos_t)CS_POS_ONE_MM)
#define NO_STATE     0xFFu
/* Keeps a function out of line (GCC and Clang; elsewhere a hint the compiler may ignore). */
#if defined(__GNUC__)
#define CS_FW_CTL_NOINLINE __attribute__((noinline))
#else
#define CS_FW_CTL_NOINLINE
#endif

CS_FW_CTL_NOINLINE cs_pos_t cs_fw_ctl_steps_to_pos(int32_t steps, int32_t spm)
{
    /* mm Q16 = steps * 2^32 / spm(Q16), rounded to nearest */
    return (cs_pos_t)cs_fixed_div_round((int64_t)steps * ((int64_t)1 << 32), spm);
}

#if CS_FW_CTL
/* |(x, y, z)| (mm Q16), one copy for the laser's speed and the line generator: the 64-bit square
 * root is large on an 8-bit target. */
static CS_FW_CTL_NOINLINE uint64_t path_len(const int64_t d[3])
{
    return cs_fixed_vec_len64(d[0], d[1], d[2]);
}

/* --- the input interrupt and the executor's load hook --------------------------------------- */

/* The one change detector of every port: the port's edge hook only says "a pin may have
 * changed" (port.h); the bits are read here and compared with the last ones seen. */
void cs_fw_ctl_inputs_isr(void *ctx)
{
    cs_fw_motion_t *mo = ctx;
    cs_fw_ctl_t *c = &mo->ctl;
    uint16_t bits = port_inputs_read();
    uint16_t prev = c->inputs;
    if (bits == prev)
        return; /* a spurious edge, a bounce already settled, or a step with no switch crossed */
    c->inputs = bits;
    uint16_t on = (uint16_t)(bits & ~prev), off = (uint16_t)(prev & ~bits);
    if (c->trip != CS_FW_TRIP_NONE)
        return; /* halted already; the main loop has not seen it yet */
    uint8_t t = CS_FW_TRIP_NONE, code = 0;
    if (on & CS_PROTO_IN_ESTOP) {
        t = CS_FW_TRIP_ALARM;
        code = CS_PROTO_ALARM_ESTOP;
    } else if ((on & c->watch) || (off & c->release)) {
        t = CS_FW_TRIP_WATCH;
    } else if (c->armed && (on & CS_PROTO_IN_LIMITS)) {
        t = CS_FW_TRIP_ALARM;
        code = CS_PROTO_ALARM_HARD_LIMIT;
    }
    if (t == CS_FW_TRIP_NONE)
        return;
    /* Grbl's hard limit: no deceleration, the steps issued are all counted */
    /* segments the executor finished (cs_fw_motion's count): the one after them was cut */
    uint8_t inring = (uint8_t)(mo->st.tail - mo->st.head);
    uint8_t running = mo->st.running ? 1u : 0u;
    c->trip_done = (uint8_t)(mo->pushed - inring - running);
    cs_stepper_halt(&mo->st);
    port_timer_stop();
    c->trip_code = code;
    c->trip_inputs = bits;
    c->trip = t;
}

static void on_load(void *ctx, uint16_t aux)
{
    cs_fw_ctl_t *c = &((cs_fw_motion_t *)ctx)->ctl;
    if (!c->laser || aux == c->duty_set)
        return;
    c->duty_set = aux;
    port_spindle_set(aux, c->sp_mode);
}

/* --- events, alarm -------------------------------------------------------------------------- */

static void push_event(cs_fw_motion_t *mo, uint8_t kind, uint8_t code, uint16_t bits)
{
    cs_fw_ctl_t *c = &mo->ctl;
    if (c->nev >= CS_FW_EVQ)
        return; /* the STATUS still tells the state; only the detail is lost */
    cs_proto_event_t *e = &c->ev[c->nev++];
    e->kind = kind;
    e->code = code;
    e->inputs = (uint16_t)(bits & CS_PROTO_IN_ALL);
    e->axes = mo->m->n_axes;
    for (unsigned i = 0; i < CS_PROTO_AXES_MAX; i++)
        e->pos[i] = i < mo->m->n_axes ? cs_fw_motion_position(mo, i) : 0;
    mo->news = true;
}

static void spindle_out(cs_fw_ctl_t *c, uint16_t duty, uint8_t mode, bool laser)
{
    uint32_t s = port_irq_save();
    c->laser = laser;
    c->sp_mode = mode;
    c->duty_set = duty;
    port_irq_restore(s);
    port_spindle_set(duty, mode);
}

/* The programmed power (1/1000) at the spindle override, at most full. */
static uint16_t sp_scaled(const cs_fw_ctl_t *c, uint16_t power)
{
    uint32_t d = (uint32_t)power * c->sp_ov / CS_PROTO_OVERRIDE_ONE;
    return d > CS_PROTO_SPINDLE_FULL ? (uint16_t)CS_PROTO_SPINDLE_FULL : (uint16_t)d;
}

static void set_watch(cs_fw_ctl_t *c, uint16_t watch, uint16_t release)
{
    uint32_t s = port_irq_save();
    c->watch = watch;
    c->release = release;
    port_irq_restore(s);
}

/* The alarm: everything stopped and dropped, the spindle off, an EVENT and an ERROR about what
 * was executing (a streaming host stops as on any device error). */
static void alarm_about(cs_fw_motion_t *mo, uint8_t code, uint16_t bits, uint16_t seq, bool busy)
{
    cs_fw_ctl_t *c = &mo->ctl;
    c->op = CS_FW_OP_NONE;
    c->op_wait = c->op_move = c->sp_wait = c->jogging = c->cancel = false;
    set_watch(c, 0, 0);
    c->armed = false;
    c->alarm = code;
    c->alarms++;
    cs_fw_motion_drop(mo);
    spindle_out(c, 0, CS_PROTO_SPINDLE_OFF, false);
    push_event(mo, CS_PROTO_EVENT_ALARM, code, bits);
    if (busy)
        cs_fw_motion_error(mo, code == CS_PROTO_ALARM_ESTOP ? CS_ERR_STATE : CS_ERR_LIMIT, seq);
}

/* The same about the operation, or the item executing. */
static void enter_alarm(cs_fw_motion_t *mo, uint8_t code, uint16_t bits)
{
    const cs_fw_ctl_t *c = &mo->ctl;
    bool op = c->op != CS_FW_OP_NONE;
    alarm_about(mo, code, bits, op ? c->op_seq : cs_fw_motion_current_seq(mo),
                op || !cs_fw_motion_done(mo));
}

/* --- operations: moves planned on the device ------------------------------------------------ */

static CS_FW_CTL_NOINLINE int32_t pos_to_steps(cs_pos_t p, int32_t spm)
{
    /* round(p * spm): Q16 x Q16 = Q32 (|p| <= 2^28, spm <= 2^28) */
    return (int32_t)cs_fixed_round_shift64((int64_t)p * spm, 32);
}

#if CS_FW_CURVES

/* A straight move of the operation from where the executor is to target (mm), planned on the
 * wide machine (homing) or the real one (probe: the travel is checked), watching the inputs. */
static cs_err_t op_move_to(cs_fw_motion_t *mo, const cs_pos_t target[CS_AXES], int32_t feed,
                           bool wide, uint16_t watch, uint16_t release)
{
    cs_fw_ctl_t *c = &mo->ctl;
    const cs_machine_t *m = wide ? &c->wide : mo->m;
    cs_pos_t p[CS_AXES] = {0};
    for (unsigned i = 0; i < mo->m->n_axes; i++)
        p[i] = cs_fw_ctl_steps_to_pos(mo->steps_pos[i], mo->m->axis[i].steps_per_mm);
    cs_err_t e = cs_planner_init(&mo->pl, m);
    if (e == CS_OK)
        e = cs_planner_set_position(&mo->pl, p);
    cs_vec3_t t = cs_fixed_vec(target[0], target[1], target[2]);
    if (e == CS_OK)
        e = cs_planner_line3(&mo->pl, &t, feed, c->op_item);
    mo->pl_stale = false;
    if (e != CS_OK)
        return e;
    set_watch(c, watch, release);
    c->op_move = true;
    return CS_OK;
}
#else
/* The line generator: a straight move from steps_pos (where everything pushed ends) to target
 * (mm) at feed (mm/s Q16), capped at the max_rate of the slowest moving axis and at a step every
 * 2 ticks (the planner's rule), at constant speed (no planner: no ramp). Soft limits unless
 * wide. Item n; mark: its last segment executes it. Out of line: its 64-bit arithmetic is large
 * on an 8-bit target and must not be copied into every caller. */
static CS_FW_CTL_NOINLINE cs_err_t line_start(cs_fw_motion_t *mo, const cs_pos_t target[CS_AXES],
                                              int32_t feed, bool wide, uint32_t n, bool mark)
{
    cs_fw_ctl_t *c = &mo->ctl;
    const cs_machine_t *m = mo->m;
    int32_t d[CS_AXES] = {0};
    int64_t mm[3] = {0, 0, 0};
    uint32_t most = 0;
    for (unsigned i = 0; i < m->n_axes; i++) {
        const cs_axis_cfg_t *ax = &m->axis[i];
        if (!wide && (target[i] < ax->travel_min || target[i] > ax->travel_max))
            return CS_ERR_LIMIT;
        d[i] = pos_to_steps(target[i], ax->steps_per_mm) - mo->steps_pos[i];
        uint32_t a = (uint32_t)(d[i] < 0 ? -d[i] : d[i]);
        if (a != 0 && ax->max_rate < feed)
            feed = ax->max_rate;
        most = a > most ? a : most;
        if (i < 3)
            mm[i] = (int64_t)target[i] - cs_fw_ctl_steps_to_pos(mo->steps_pos[i], ax->steps_per_mm);
    }
    if (feed <= 0)
        return CS_ERR_ARG;
    /* ticks = length (mm Q16) / feed (mm/s Q16) x tick_hz */
    uint64_t ticks = path_len(mm) * m->tick_hz / (uint64_t)feed;
    if (ticks < 2u * (uint64_t)most)
        ticks = 2u * (uint64_t)most;
    if (ticks > CS_FW_CTL_LINE_TICKS_MAX)
        return CS_ERR_ARG;
    for (unsigned i = 0; i < CS_AXES; i++)
        c->ln_left[i] = d[i];
    c->ln_ticks = (uint32_t)ticks;
    c->ln_item = n;
    c->ln_mark = mark;
    return CS_OK;
}

static cs_err_t op_move_to(cs_fw_motion_t *mo, const cs_pos_t target[CS_AXES], int32_t feed,
                           bool wide, uint16_t watch, uint16_t release)
{
    cs_fw_ctl_t *c = &mo->ctl;
    cs_err_t e = line_start(mo, target, feed, wide, c->op_item, false);
    if (e != CS_OK)
        return e;
    set_watch(c, watch, release);
    c->op_move = true;
    return CS_OK;
}

/* round(k x t / left), |k| <= left / 2 + 1, t <= left < 2^31: the line's steps in t of its
 * remaining ticks. */
static CS_FW_CTL_NOINLINE int32_t share(int32_t k, uint32_t t, uint32_t left)
{
    return (int32_t)cs_fixed_div_round((int64_t)k * t, left);
}

bool cs_fw_ctl_line_next(cs_fw_motion_t *mo, cs_segment_t *s, uint32_t *done)
{
    cs_fw_ctl_t *c = &mo->ctl;
    uint32_t left = c->ln_ticks;
    if (left == 0)
        return false;
    uint32_t seg = mo->m->segment_ticks > 0 ? mo->m->segment_ticks : 1u;
    /* the last piece is whatever remains; before it, equal pieces (a short tail joins them) */
    uint32_t t = left < 2u * seg ? left : seg;
    s->ticks = t;
    for (unsigned i = 0; i < CS_AXES; i++) {
        /* round(left_i x t / left): the pieces add up to the line exactly (the last is all) */
        int32_t k = t == left ? c->ln_left[i] : share(c->ln_left[i], t, left);
        s->steps[i] = k;
        c->ln_left[i] -= k;
    }
    c->ln_ticks = left - t;
    *done = c->ln_ticks == 0 && c->ln_mark ? c->ln_item : c->ln_item - 1u;
    return true;
}

bool cs_fw_ctl_line_busy(const cs_fw_motion_t *mo)
{
    return mo->ctl.ln_ticks != 0;
}

void cs_fw_ctl_line_stop(cs_fw_motion_t *mo)
{
    mo->ctl.ln_ticks = 0;
}
#endif

static uint16_t home_bit(const cs_proto_home_t *h)
{
    return (uint16_t)((h->flags & CS_PROTO_HOME_MAX) ? CS_PROTO_IN_MAX(h->axis)
                                                     : CS_PROTO_IN_MIN(h->axis));
}

/* A homing move of d mm towards the switch (d > 0) or away from it (d < 0). */
static cs_err_t home_move(cs_fw_motion_t *mo, cs_pos_t d, int32_t feed, uint16_t watch)
{
    const cs_proto_home_t *h = &mo->ctl.u.home;
    cs_pos_t t[CS_AXES] = {0};
    for (unsigned i = 0; i < mo->m->n_axes; i++)
        t[i] = cs_fw_ctl_steps_to_pos(mo->steps_pos[i], mo->m->axis[i].steps_per_mm);
    int64_t v = (int64_t)t[h->axis] + ((h->flags & CS_PROTO_HOME_MAX) ? d : -(int64_t)d);
    t[h->axis] = (cs_pos_t)(v > CS_POS_LIMIT ? CS_POS_LIMIT : v < -CS_POS_LIMIT ? -CS_POS_LIMIT : v);
    return op_move_to(mo, t, feed, true, watch, 0);
}

static void home_phase(cs_fw_motion_t *mo, uint8_t ph)
{
    cs_fw_ctl_t *c = &mo->ctl;
    const cs_proto_home_t *h = &c->u.home;
    c->phase = ph;
    cs_err_t e;
    if (ph == PH_SEEK)
        e = home_move(mo, h->search, h->seek, home_bit(h));
    else if (ph == PH_LATCH)
        e = home_move(mo, 2 * h->pulloff + LATCH_MARGIN, h->latch, home_bit(h));
    else
        e = home_move(mo, -h->pulloff, h->seek, 0);
    if (e != CS_OK)
        enter_alarm(mo, CS_PROTO_ALARM_HOMING_RESET, c->inputs);
}

/* The operation is over: its item counts as executed, the planner goes back to the machine. */
static void op_finish(cs_fw_motion_t *mo)
{
    cs_fw_ctl_t *c = &mo->ctl;
    c->op = CS_FW_OP_NONE;
    c->op_move = false;
    set_watch(c, 0, 0);
#if CS_FW_CURVES
    (void)cs_planner_init(&mo->pl, mo->m);
    mo->pl_stale = true;
#endif
    cs_fw_motion_mark(mo, c->op_item);
    mo->news = true;
}

static void home_done(cs_fw_motion_t *mo)
{
    cs_fw_ctl_t *c = &mo->ctl;
    const cs_proto_home_t *h = &c->u.home;
    int32_t s = pos_to_steps(h->home_pos, mo->m->axis[h->axis].steps_per_mm);
    uint32_t irq = port_irq_save();
    cs_err_t e = cs_stepper_set_position(&mo->st, h->axis, s);
    port_irq_restore(irq);
    if (e != CS_OK) {
        enter_alarm(mo, CS_PROTO_ALARM_HOMING_RESET, c->inputs);
        return;
    }
    mo->steps_pos[h->axis] = s;
    c->homed = (uint16_t)(c->homed | (1u << h->axis));
    c->homings++;
    push_event(mo, CS_PROTO_EVENT_HOMED, h->axis, c->inputs);
    op_finish(mo);
}

/* The executor stopped after everything before the operation: start it. */
static void op_start(cs_fw_motion_t *mo)
{
    cs_fw_ctl_t *c = &mo->ctl;
    c->op_wait = false;
    uint16_t in = c->inputs;
    if (c->op == CS_FW_OP_HOME) {
        const cs_proto_home_t *h = &c->u.home;
        if (h->axis >= mo->m->n_axes || h->axis >= 3) { /* the planner moves x, y, z */
            cs_fw_motion_error(mo, CS_ERR_ARG, c->op_seq);
            op_finish(mo);
            return;
        }
        home_phase(mo, (in & home_bit(h)) ? PH_BACKOFF : PH_SEEK);
        return;
    }
    const cs_proto_probe_t *p = &c->u.probe;
    bool away = (p->flags & CS_PROTO_PROBE_AWAY) != 0;
    if (((in & CS_PROTO_IN_PROBE) != 0) != away) {
        enter_alarm(mo, CS_PROTO_ALARM_PROBE_INITIAL, in);
        return;
    }
    cs_pos_t t[CS_AXES] = {p->target.x, p->target.y, p->target.z};
    if (mo->m->n_axes > 3)
        t[3] = cs_fw_ctl_steps_to_pos(mo->steps_pos[3], mo->m->axis[3].steps_per_mm);
    cs_err_t e = op_move_to(mo, t, p->feed, false, away ? 0 : CS_PROTO_IN_PROBE,
                            away ? CS_PROTO_IN_PROBE : 0);
    if (e != CS_OK) {
        cs_fw_motion_error(mo, e, c->op_seq);
        op_finish(mo);
    }
}

/* The operation's move ended: tripped (the input it watched) or run to its end. */
static void op_moved(cs_fw_motion_t *mo, bool tripped, uint16_t bits)
{
    cs_fw_ctl_t *c = &mo->ctl;
    c->op_move = false;
    set_watch(c, 0, 0);
    if (c->op == CS_FW_OP_PROBE) {
        c->probes++;
        push_event(mo, CS_PROTO_EVENT_PROBE, tripped ? 1u : 0u, bits);
        if (!tripped && !(c->u.probe.flags & CS_PROTO_PROBE_NO_ERROR))
            enter_alarm(mo, CS_PROTO_ALARM_PROBE_CONTACT, bits);
        else
            op_finish(mo);
        return;
    }
    bool on = (bits & home_bit(&c->u.home)) != 0;
    switch (c->phase) {
    case PH_SEEK:
    case PH_LATCH:
        if (!tripped)
            enter_alarm(mo, CS_PROTO_ALARM_HOMING_APPROACH, bits);
        else
            home_phase(mo, c->phase == PH_SEEK ? PH_BACKOFF : PH_PULLOFF);
        break;
    default:
        if (on)
            enter_alarm(mo, CS_PROTO_ALARM_HOMING_PULLOFF, bits);
        else if (c->phase == PH_BACKOFF)
            home_phase(mo, PH_LATCH);
        else
            home_done(mo);
        break;
    }
}

/* The input interrupt halted the executor: drop what was planned, restart from where it is. */
static void handle_trip(cs_fw_motion_t *mo)
{
    cs_fw_ctl_t *c = &mo->ctl;
    uint32_t s = port_irq_save();
    uint8_t t = c->trip, code = c->trip_code;
    uint16_t bits = c->trip_inputs;
    uint8_t done = c->trip_done;
    c->trip = CS_FW_TRIP_NONE;
    port_irq_restore(s);
    bool busy = c->op != CS_FW_OP_NONE || !cs_fw_motion_done(mo);
    uint16_t seq = cs_fw_motion_halted(mo, done);
    cs_fw_motion_flush(mo);
    for (unsigned i = 0; i < CS_AXES; i++)
        mo->steps_pos[i] = cs_fw_motion_position(mo, i);
    if (t == CS_FW_TRIP_ALARM) {
        alarm_about(mo, code, bits, c->op != CS_FW_OP_NONE ? c->op_seq : seq, busy);
        return;
    }
    if (c->op_move)
        op_moved(mo, true, bits);
}

/* --- the API -------------------------------------------------------------------------------- */

void cs_fw_ctl_init(cs_fw_motion_t *mo)
{
    cs_fw_ctl_t *c = &mo->ctl;
    cs_fw_motion_zero(c, sizeof *c);
#if CS_FW_CURVES
    c->wide = *mo->m;
    for (unsigned i = 0; i < CS_AXES; i++) {
        c->wide.axis[i].travel_min = -CS_POS_LIMIT;
        c->wide.axis[i].travel_max = CS_POS_LIMIT;
    }
#endif
    c->armed = true;
    c->inputs_sent = 0;
    c->sp_ov = CS_PROTO_OVERRIDE_ONE;
    uint32_t s = port_irq_save();
    cs_stepper_on_load(&mo->st, on_load, mo);
    port_irq_restore(s);
    port_inputs_attach(cs_fw_ctl_inputs_isr, mo);
    /* what is active already is a change from nothing (an e-stop pressed at boot: the alarm) */
    s = port_irq_save();
    cs_fw_ctl_inputs_isr(mo);
    port_irq_restore(s);
}

cs_err_t cs_fw_ctl_admit(cs_fw_motion_t *mo, uint8_t type)
{
    /* homing is the way out of an alarm (Grbl's $H in the alarm state): an implicit UNLOCK */
    if (mo->ctl.alarm != 0 && type == CS_PROTO_HOME && cs_fw_ctl_unlock(mo) != CS_OK)
        return CS_ERR_STATE;
    if (mo->ctl.alarm != 0)
        return CS_ERR_STATE;
    return CS_OK;
}

bool cs_fw_ctl_take(cs_fw_motion_t *mo, const void *item, uint32_t n)
{
    const cs_fw_item_t *it = item;
    cs_fw_ctl_t *c = &mo->ctl;
    c->op_item = n;
    c->op_seq = it->seq;
    if (it->type == CS_PROTO_SPINDLE) {
        c->u.spindle = it->u.spindle;
        bool live = (it->u.spindle.flags & CS_PROTO_SPINDLE_LASER) &&
                    it->u.spindle.mode != CS_PROTO_SPINDLE_OFF;
        if (!live) { /* M3/M4/M5: synchronous, like a PEN */
            c->sp_wait = true;
            return false;
        }
        uint32_t s = port_irq_save();
        c->power = it->u.spindle.power;
        c->sp_feed = it->u.spindle.feed;
        c->sp_mode = it->u.spindle.mode;
        c->laser = true;
        port_irq_restore(s);
        return true;
    }
    if (it->type == CS_PROTO_JOG) {
#if CS_FW_CURVES
        cs_fw_motion_plan_line(mo, &it->u.jog.target, it->u.jog.feed, n);
#else
        const cs_vec3_t *g = &it->u.jog.target;
        cs_pos_t t[CS_AXES] = {g->x, g->y, g->z, 0};
        if (mo->m->n_axes > 3) /* a stays */
            t[3] = cs_fw_ctl_steps_to_pos(mo->steps_pos[3], mo->m->axis[3].steps_per_mm);
        cs_err_t e = line_start(mo, t, it->u.jog.feed, false, n, true);
        if (e != CS_OK)
            cs_fw_motion_error(mo, e, it->seq);
#endif
        c->jogging = true;
        c->jog_last = n;
        return true;
    }
    c->op = it->type == CS_PROTO_HOME ? CS_FW_OP_HOME : CS_FW_OP_PROBE;
    if (c->op == CS_FW_OP_HOME)
        c->u.home = it->u.home;
    else
        c->u.probe = it->u.probe;
    c->op_wait = true;
    return false;
}

bool cs_fw_ctl_blocking(const cs_fw_motion_t *mo)
{
    const cs_fw_ctl_t *c = &mo->ctl;
    return c->op != CS_FW_OP_NONE || c->sp_wait || c->cancel;
}

/* The executor has stopped after everything taken (and no hold keeps it): an operation may
 * start, a synchronous SPINDLE be set. */
static bool at_rest(const cs_fw_motion_t *mo)
{
    return !mo->hold.hold && cs_fw_motion_still(mo);
}

static void poll_spindle(cs_fw_motion_t *mo)
{
    cs_fw_ctl_t *c = &mo->ctl;
    if (!c->sp_wait || !at_rest(mo))
        return;
    const cs_proto_spindle_t *p = &c->u.spindle;
    c->power = p->power;
    c->sp_feed = p->feed;
    spindle_out(c, p->mode == CS_PROTO_SPINDLE_OFF ? 0 : sp_scaled(c, p->power), p->mode, false);
    c->sp_wait = false;
    cs_fw_motion_mark(mo, c->op_item);
}

/* JOG_CANCEL: once the hold has brought the jog to rest (or it ended), drop the rest. */
static void poll_cancel(cs_fw_motion_t *mo)
{
    cs_fw_ctl_t *c = &mo->ctl;
    if (!c->cancel)
        return;
    uint32_t s = port_irq_save();
    bool idle = cs_stepper_idle(&mo->st);
    port_irq_restore(s);
    if (!idle || !(cs_hold_stopped(&mo->hold) || cs_fw_motion_still(mo)))
        return;
    cs_fw_motion_drop(mo);
    c->cancel = false;
    c->jogging = false;
    mo->news = true;
}

void cs_fw_ctl_poll(cs_fw_motion_t *mo)
{
    cs_fw_ctl_t *c = &mo->ctl;
    if (c->trip != CS_FW_TRIP_NONE)
        handle_trip(mo);
    poll_cancel(mo);
    if (c->op_wait && at_rest(mo))
        op_start(mo);
    else if (c->op_move && !mo->hold.hold && cs_fw_motion_still(mo) &&
             c->trip == CS_FW_TRIP_NONE) /* a hold at rest is no end of the move */
        op_moved(mo, false, c->inputs);
    poll_spindle(mo);
    if (c->jogging && !c->cancel && cs_fw_motion_executed(mo, c->jog_last))
        c->jogging = false;
    uint16_t in = c->inputs;
    /* INPUTS while idle only, into an empty queue (never crowding out an alarm or a contact) */
    if (in != c->inputs_sent && c->nev == 0 && c->op == CS_FW_OP_NONE && cs_fw_motion_done(mo)) {
        c->inputs_sent = in;
        push_event(mo, CS_PROTO_EVENT_INPUTS, 0, in);
    }
}

uint16_t cs_fw_ctl_aux(const cs_fw_motion_t *mo, const cs_segment_t *s)
{
    const cs_fw_ctl_t *c = &mo->ctl;
    if (!c->laser || c->sp_mode == CS_PROTO_SPINDLE_OFF)
        return 0;
    /* the segment's path length over x, y, z (mm Q16) and speed v = len x tick_hz / ticks */
    int64_t d[3] = {0, 0, 0};
    for (unsigned i = 0; i < mo->m->n_axes && i < 3; i++)
        d[i] = cs_fw_ctl_steps_to_pos(s->steps[i], mo->m->axis[i].steps_per_mm);
    uint64_t len = path_len(d);
    if (len == 0)
        return 0; /* a dwell or a pen's settle: the beam is off while nothing moves */
    uint16_t power = sp_scaled(c, c->power);
    if (c->sp_feed <= 0)
        return power;
    uint64_t v = len * mo->m->tick_hz / s->ticks; /* mm/s Q16; len < 2^31, tick_hz < 2^24 */
    if (v >= (uint64_t)c->sp_feed)
        return power;
    return (uint16_t)((uint64_t)power * v / (uint64_t)c->sp_feed);
}

bool cs_fw_ctl_overridable(const cs_fw_motion_t *mo)
{
    const cs_fw_ctl_t *c = &mo->ctl;
    return c->op == CS_FW_OP_NONE && !c->jogging && !c->cancel;
}

void cs_fw_ctl_override(cs_fw_motion_t *mo, uint16_t spindle)
{
    cs_fw_ctl_t *c = &mo->ctl;
    if (spindle == c->sp_ov)
        return;
    c->sp_ov = spindle;
    /* a running spindle (M3/M4, not the laser: its power goes with each segment) at once */
    if (!c->laser && c->sp_mode != CS_PROTO_SPINDLE_OFF)
        spindle_out(c, sp_scaled(c, c->power), c->sp_mode, false);
}

cs_err_t cs_fw_ctl_unlock(cs_fw_motion_t *mo)
{
    cs_fw_ctl_t *c = &mo->ctl;
    if (port_inputs_read() & CS_PROTO_IN_ESTOP)
        return CS_ERR_STATE;
    uint32_t s = port_irq_save();
    c->inputs = port_inputs_read(); /* a switch still pressed is no new edge */
    c->armed = true;
    port_irq_restore(s);
    c->alarm = 0;
    mo->aborted = false;
    mo->news = true;
    return CS_OK;
}

void cs_fw_ctl_jog_cancel(cs_fw_motion_t *mo)
{
    cs_fw_ctl_t *c = &mo->ctl;
    if (!c->jogging || c->cancel)
        return;
    c->cancel = true;
    cs_fw_motion_hold(mo, true); /* the feed-hold ramp (counted as a hold) */
}

void cs_fw_ctl_abort(cs_fw_motion_t *mo)
{
    cs_fw_ctl_t *c = &mo->ctl;
    if (c->op == CS_FW_OP_HOME) {
        enter_alarm(mo, CS_PROTO_ALARM_HOMING_RESET, c->inputs);
        return;
    }
    c->op = CS_FW_OP_NONE;
    c->op_wait = c->op_move = c->sp_wait = c->jogging = c->cancel = false;
    set_watch(c, 0, 0);
}

uint8_t cs_fw_ctl_state(const cs_fw_motion_t *mo)
{
    const cs_fw_ctl_t *c = &mo->ctl;
    if (c->alarm != 0)
        return CS_PROTO_STATE_ALARM;
    if (c->op == CS_FW_OP_HOME)
        return CS_PROTO_STATE_HOMING;
    if (c->jogging)
        return CS_PROTO_STATE_JOG;
    return NO_STATE;
}

bool cs_fw_ctl_peek_event(const cs_fw_motion_t *mo, cs_proto_event_t *e)
{
    if (mo->ctl.nev == 0)
        return false;
    *e = mo->ctl.ev[0];
    return true;
}

void cs_fw_ctl_drop_event(cs_fw_motion_t *mo)
{
    cs_fw_ctl_t *c = &mo->ctl;
    if (c->nev == 0)
        return;
    for (uint8_t i = 1; i < c->nev; i++)
        c->ev[i - 1] = c->ev[i];
    c->nev--;
}
#else /* CS_FW_CTL = 0: the API answers "not here" */

void cs_fw_ctl_init(cs_fw_motion_t *mo)
{
    cs_fw_motion_zero(&mo->ctl, sizeof mo->ctl);
}

void cs_fw_ctl_inputs_isr(void *ctx)
{
    (void)ctx;
}

cs_err_t cs_fw_ctl_admit(cs_fw_motion_t *mo, uint8_t type)
{
    (void)mo;
    return type == CS_PROTO_HOME || type == CS_PROTO_JOG || type == CS_PROTO_PROBE ||
                   type == CS_PROTO_SPINDLE
               ? CS_ERR_UNSUPPORTED
               : CS_OK;
}

bool cs_fw_ctl_take(cs_fw_motion_t *mo, const void *item, uint32_t n)
{
    (void)mo;
    (void)item;
    (void)n;
    return true;
}

bool cs_fw_ctl_blocking(const cs_fw_motion_t *mo)
{
    (void)mo;
    return false;
}

void cs_fw_ctl_poll(cs_fw_motion_t *mo)
{
    (void)mo;
}

uint16_t cs_fw_ctl_aux(const cs_fw_motion_t *mo, const cs_segment_t *s)
{
    (void)mo;
    (void)s;
    return 0;
}

bool cs_fw_ctl_overridable(const cs_fw_motion_t *mo)
{
    (void)mo;
    return true;
}

void cs_fw_ctl_override(cs_fw_motion_t *mo, uint16_t spindle)
{
    (void)mo;
    (void)spindle;
}

cs_err_t cs_fw_ctl_unlock(cs_fw_motion_t *mo)
{
    (void)mo;
    return CS_ERR_UNSUPPORTED;
}

void cs_fw_ctl_jog_cancel(cs_fw_motion_t *mo)
{
    (void)mo;
}

void cs_fw_ctl_abort(cs_fw_motion_t *mo)
{
    (void)mo;
}

uint8_t cs_fw_ctl_state(const cs_fw_motion_t *mo)
{
    (void)mo;
    return NO_STATE;
}

bool cs_fw_ctl_peek_event(const cs_fw_motion_t *mo, cs_proto_event_t *e)
{
    (void)mo;
    (void)e;
    return false;
}

void cs_fw_ctl_drop_event(cs_fw_motion_t *mo)
{
    (void)mo;
}
#endif

#if !CS_FW_CTL || CS_FW_CURVES
/* No line generator: the planner moves the operations, or there are none. */
bool cs_fw_ctl_line_next(cs_fw_motion_t *mo, cs_segment_t *s, uint32_t *done)
{
    (void)mo;
    (void)s;
    (void)done;
    return false;
}

bool cs_fw_ctl_line_busy(const cs_fw_motion_t *mo)
{
    (void)mo;
    return false;
}

void cs_fw_ctl_line_stop(cs_fw_motion_t *mo)
{
    (void)mo;
}
#endif
