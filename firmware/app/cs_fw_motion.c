/* cs_fw_motion: the device's motion side over port.h and the core. See cs_fw_motion.h; the
 * protocol is docs/protocol.md. */
#include "cs_fw_motion.h"

#include <stddef.h>

#include "port.h"

#define SEQ_MASK ((uint32_t)CS_FW_SEQMAP - 1u)
#define TAG_MASK ((uint8_t)(CS_FW_TAGS - 1))
/* next_segment's work budget a pass (blocks cut, points traced, items taken) */
#define NEXT_GUARD 64u

void cs_fw_motion_error(cs_fw_motion_t *a, cs_err_t code, uint16_t seq)
{
    a->stats.errors++;
    if (a->nerr < CS_FW_ERRQ) {
        a->errs[a->nerr].code = (uint8_t)code;
        a->errs[a->nerr].seq = seq;
        a->nerr++;
    }
}

int32_t cs_fw_motion_position(const cs_fw_motion_t *a, unsigned axis)
{
    /* a 32-bit read is not atomic on the AVR: mask the step interrupt */
    uint32_t s = port_irq_save();
    int32_t p = cs_stepper_position(&a->st, axis);
    port_irq_restore(s);
    return p;
}

bool cs_fw_motion_still(const cs_fw_motion_t *a)
{
#if CS_FW_CURVES
    if (a->tracing || a->gen_busy || cs_planner_count(&a->pl) != 0)
        return false;
#endif
    if (cs_fw_ctl_line_busy(a))
        return false;
    uint32_t s = port_irq_save();
    bool idle = cs_stepper_idle(&a->st);
    port_irq_restore(s);
    return !a->has_pend && idle;
}

bool cs_fw_motion_drained(const cs_fw_motion_t *a)
{
    return !a->pen_wait && !cs_fw_ctl_blocking(a) && cs_fw_motion_still(a);
}

bool cs_fw_motion_done(const cs_fw_motion_t *a)
{
    return a->qcount == 0 && cs_fw_motion_drained(a);
}

static bool item_after(uint32_t x, uint32_t y)
{
    return (int32_t)(x - y) > 0;
}

/* The item an 8-bit tag names: the one within 2^7 of the last executed (items in flight are
 * fewer than CS_FW_SEQMAP <= 128). */
static uint32_t tag_item(const cs_fw_motion_t *a, uint8_t tag)
{
    uint8_t d = (uint8_t)(tag - (uint8_t)a->exec_item);
    return d < 0x80u ? a->exec_item + d : a->exec_item - (uint32_t)(0x100u - d);
}

bool cs_fw_motion_executed(const cs_fw_motion_t *a, uint32_t n)
{
    return !item_after(n, a->exec_item);
}

uint16_t cs_fw_motion_current_seq(const cs_fw_motion_t *a)
{
    if (item_after(a->popped, a->exec_item))
        return a->item_seq[(a->exec_item + 1u) & SEQ_MASK];
    return a->exec_seq;
}

void cs_fw_motion_mark(cs_fw_motion_t *a, uint32_t item)
{
    if (item_after(item, a->exec_item)) {
        a->stats.executed += item - a->exec_item;
        a->exec_item = item;
        a->exec_seq = a->item_seq[item & SEQ_MASK];
    }
}

/* Segments the executor has finished: pushed - (queued in the ring) - (the running one). */
static void note_completed(cs_fw_motion_t *a)
{
    uint32_t s = port_irq_save();
    uint8_t inring = (uint8_t)(a->st.tail - a->st.head);
    uint8_t running = a->st.running ? 1u : 0u;
    port_irq_restore(s);
    uint8_t done = (uint8_t)(a->pushed - inring - running);
    while (a->completed != done) {
        cs_fw_motion_mark(a, tag_item(a, a->tag[a->completed & TAG_MASK]));
        a->completed++;
    }
    if (cs_fw_motion_drained(a))
        cs_fw_motion_mark(a, a->popped); /* items that made no segment (zero moves, errors) */
}

uint16_t cs_fw_motion_halted(cs_fw_motion_t *a, uint8_t done)
{
    while (a->completed != done) {
        cs_fw_motion_mark(a, tag_item(a, a->tag[a->completed & TAG_MASK]));
        a->completed++;
    }
    /* (the low 8 bits of a tag index the sequence map: CS_FW_SEQMAP <= 128) */
    uint16_t seq = a->pushed != done ? a->item_seq[a->tag[done & TAG_MASK] & SEQ_MASK]
                                     : cs_fw_motion_current_seq(a);
    a->completed = a->pushed;
    return seq;
}

static void pop_item(cs_fw_motion_t *a, cs_fw_item_t *out)
{
    *out = a->q[a->qhead];
    a->qhead = (uint16_t)((a->qhead + 1u) % CS_FW_QUEUE);
    a->qcount--;
    a->popped++;
    a->item_seq[a->popped & SEQ_MASK] = out->seq;
}

static bool may_take_item(const cs_fw_motion_t *a)
{
    return a->qcount > 0 && !cs_fw_ctl_blocking(a) &&
           (a->take_max == 0 || item_after(a->take_max, a->popped));
}

#if CS_FW_CURVES
/* SEGMENT messages moved the machine behind the planner's back: start it from there. */
static void refresh_planner(cs_fw_motion_t *a)
{
    if (!a->pl_stale || cs_planner_count(&a->pl) != 0)
        return;
    cs_pos_t p[CS_AXES] = {0};
    for (unsigned i = 0; i < a->m->n_axes; i++)
        p[i] = cs_fw_ctl_steps_to_pos(a->steps_pos[i], a->m->axis[i].steps_per_mm);
    (void)cs_planner_set_position(&a->pl, p);
    a->pl_stale = false;
}

void cs_fw_motion_plan_line(cs_fw_motion_t *a, const cs_vec3_t *target, int32_t feed, uint32_t n)
{
    refresh_planner(a);
    cs_err_t e = cs_planner_line3(&a->pl, target, feed, n);
    if (e != CS_OK)
        cs_fw_motion_error(a, e, a->item_seq[n & SEQ_MASK]);
}

static void start_curve(cs_fw_motion_t *a, const cs_fw_item_t *it)
{
    refresh_planner(a);
    cs_bezier_t c;
    cs_err_t e = cs_bezier_init(&c, 3, it->u.curve.p);
    if (e == CS_OK)
        e = cs_trace_begin(&a->tr, &c, a->cfg.tol, (cs_trace_method_t)a->cfg.method);
    if (e != CS_OK) {
        cs_fw_motion_error(a, e, it->seq);
        return;
    }
    a->tracing = true;
    a->tr_feed = it->u.curve.feed;
    a->tr_item = a->popped;
    const cs_vec3_t *p0 = &it->u.curve.p[0];
    a->rapid_pending = p0->x != a->pl.pos[0] || p0->y != a->pl.pos[1] || p0->z != a->pl.pos[2];
    a->rapid_to = *p0;
    a->stats.curves++;
}

/* The next segment of the planned blocks: 1 with *s, *done set; 0 when the block ended (go on);
 * -1 on an error (the planner is reset). */
static int cut_block(cs_fw_motion_t *a, cs_segment_t *s, uint32_t *done)
{
    cs_err_t e = cs_segment_next(&a->gen, &a->pl, s);
    if (e == CS_ERR_EMPTY) {
        a->gen_busy = false;
        return 0;
    }
    if (e != CS_OK) {
        cs_fw_motion_error(a, e, a->item_seq[a->gen.line & SEQ_MASK]);
        a->gen_busy = false;
        (void)cs_planner_init(&a->pl, a->m);
        a->pl_stale = true;
        return -1;
    }
    a->gen_busy = !cs_segment_block_end(&a->gen);
    /* the block's "line" is its item: the item before it is done when this ends */
    *done = a->gen.line - 1u;
    return 1;
}

/* One traced point (or the travel to the curve's start) into the planner. */
static void trace_step(cs_fw_motion_t *a)
{
    cs_vec3_t pt;
    cs_err_t e;
    if (a->rapid_pending) {
        pt = a->rapid_to;
        e = cs_planner_line3(&a->pl, &pt, 0, a->tr_item);
        a->rapid_pending = false;
    } else {
        e = cs_trace_next(&a->tr, &pt);
        if (e == CS_END) {
            a->tracing = false;
            return;
        }
        if (e == CS_OK)
            e = cs_planner_line3(&a->pl, &pt, a->tr_feed, a->tr_item);
    }
    if (e != CS_OK) {
        cs_fw_motion_error(a, e, a->item_seq[a->tr_item & SEQ_MASK]);
        a->tracing = false;
    }
}
#endif

/* Next step segment for the executor: true with *s and *done (the item executed once it has
 * run) set, false when nothing is ready now (a->more: the work budget of this pass ran out
 * first). Bounded work. */
static bool next_segment(cs_fw_motion_t *a, cs_segment_t *s, uint32_t *done)
{
    for (unsigned guard = 0; guard < NEXT_GUARD; guard++) {
#if CS_FW_CURVES
        uint8_t head = a->q[a->qhead].type;
        bool feeding = a->tracing || (may_take_item(a) && (head == CS_PROTO_CURVE ||
                                                           head == CS_PROTO_JOG));
        /* Cut when the look-ahead is full or nothing more can be added now (the planner always
         * plans its last block to end at rest, so cutting early is safe). */
        if (a->gen_busy ||
            (cs_planner_count(&a->pl) > 0 && (cs_planner_full(&a->pl) || !feeding))) {
            int r = cut_block(a, s, done);
            if (r < 0)
                return false;
            if (r > 0)
                return true;
            continue;
        }
        if (a->tracing) {
            trace_step(a);
            continue;
        }
#endif
        if (cs_fw_ctl_line_next(a, s, done)) /* HOME, PROBE, JOG without the planner */
            return true;
        if (!may_take_item(a))
            return false;
        cs_fw_item_t it;
        pop_item(a, &it);
        if (it.type == CS_PROTO_PEN) { /* applied by feed once the executor stopped */
            a->pen_wait = true;
            a->pen_us = it.u.pen_us;
            a->pen_item = a->popped;
            return false;
        }
        if (it.type != CS_PROTO_SEGMENT && it.type != CS_PROTO_CURVE) {
            if (!cs_fw_ctl_take(a, &it, a->popped))
                return false; /* HOME, PROBE, a synchronous SPINDLE: cs_fw_ctl starts them */
            continue;
        }
#if CS_FW_CURVES
        if (it.type == CS_PROTO_CURVE) {
            start_curve(a, &it);
            continue;
        }
        a->pl_stale = true;
#endif
        *s = it.u.seg;
        *done = a->popped;
        return true;
    }
    a->more = true;
    return false;
}

/* Hands one segment to the executor, starting the step timer when it was idle (the step
 * interrupt stops it when the ring runs dry: idle <=> stopped, checked with interrupts masked).
 * The log gets the segment as planned (orig: before a hold re-timed it), so that a job logs the
 * same segments whether it was held or not. */
static void push_segment(cs_fw_motion_t *a, const cs_segment_t *s, const cs_segment_t *orig,
                         uint32_t done)
{
    uint16_t aux = cs_fw_ctl_aux(a, s);
    uint32_t irq = port_irq_save();
    if (a->ctl.trip != CS_FW_TRIP_NONE) { /* halted by an input: cs_fw_ctl drops the rest */
        port_irq_restore(irq);
        return;
    }
    bool was_idle = cs_stepper_idle(&a->st);
    cs_err_t e = cs_stepper_push_aux(&a->st, s, aux);
    if (e == CS_OK) {
        a->tag[a->pushed & TAG_MASK] = (uint8_t)done;
        a->pushed++;
        if (was_idle)
            port_timer_arm(1);
    }
    port_irq_restore(irq);
    if (e != CS_OK) { /* cs_proto checked the invariant already */
        cs_fw_motion_error(a, e, a->item_seq[done & SEQ_MASK]);
        return;
    }
    a->stats.segments++;
    cs_exlog_segment(&a->log, orig);
#if CS_FW_SIM_HOOKS
    if (a->pushed_hook != NULL)
        a->pushed_hook(a->hook_ctx, orig, cs_fw_motion_job_no(a, done));
#endif
    for (unsigned i = 0; i < CS_AXES; i++)
        a->steps_pos[i] += s->steps[i];
}

/* The PEN taken from the queue, set once everything before it has run (the executor stopped:
 * exactly between its neighbours) and not while held; true when it was set. */
static bool apply_pen(cs_fw_motion_t *a)
{
    if (a->hold.hold)
        return false;
    uint32_t irq = port_irq_save();
    bool idle = cs_stepper_idle(&a->st);
    port_irq_restore(irq);
    if (!idle)
        return false;
    port_pen_set(a->pen_us);
    a->pen_wait = false;
    a->stats.pens++;
    a->stats.pen_us = a->pen_us;
    cs_fw_motion_mark(a, a->pen_item);
    return true;
}

/* --- overrides above 100 % ------------------------------------------------------------------
 * The rule: the scale s may exceed 1 only inside a stretch of segments of one constant speed
 * (every axis's rate within one step of the stretch's first segment: a cruise, up to the
 * segments' rounding), never in the first segment of a stretch, and at the end of a segment no
 * higher than sqrt(1 + 2 R / T), R the job ticks of the same stretch already queued after it:
 * s can then ramp back to 1 (at cs_hold's slope, s^2 falling 2 tau / T per segment) before the
 * stretch ends, so the job's own accelerations and junctions always run at s <= 1 (their
 * planned acceleration or less) and inside the stretch only the ramp accelerates: <= 0.8
 * max_accel (cs_hold.h). Each axis also stays within its max rate (and one step a tick). */
#if CS_FW_OV_UP
/* b runs at a's per-axis rates within one step over b's duration, and both move:
 * |b_i / b_t - a_i / a_t| <= 1 / b_t, i.e. |b_i a_t - a_i b_t| <= a_t. */
static bool same_speed(const cs_segment_t *a, const cs_segment_t *b)
{
    bool ma = false, mb = false;
    for (unsigned i = 0; i < CS_AXES; i++) {
        int64_t x = (int64_t)b->steps[i] * a->ticks - (int64_t)a->steps[i] * b->ticks;
        if (x > (int64_t)a->ticks || x < -(int64_t)a->ticks)
            return false;
        ma = ma || a->steps[i] != 0;
        mb = mb || b->steps[i] != 0;
    }
    return ma && mb;
}

/* The highest scale at which every axis of s stays within its max rate and one step a tick:
 * min over axes of r_i x ticks / |steps_i|, r_i = max_rate x steps_per_mm / tick_hz steps a
 * tick (Q16, at most 1). */
static uint64_t rate_cap(const cs_fw_motion_t *a, const cs_segment_t *s)
{
    uint64_t cap = (uint64_t)CS_HOLD_SCALE_MAX;
    for (unsigned i = 0; i < a->m->n_axes; i++) {
        if (s->steps[i] == 0)
            continue;
        const cs_axis_cfg_t *ax = &a->m->axis[i];
        uint64_t r = ((uint64_t)ax->max_rate * (uint64_t)ax->steps_per_mm >> 16) / a->m->tick_hz;
        if (r > CS_HOLD_SCALE_ONE)
            r = CS_HOLD_SCALE_ONE;
        uint64_t n = s->steps[i] < 0 ? (uint64_t)(-(int64_t)s->steps[i]) : (uint64_t)s->steps[i];
        uint64_t c = r * s->ticks / n;
        if (c < cap)
            cap = c;
    }
    return cap;
}

/* R: job ticks of the anchor's stretch queued after the pending segment, counted until they
 * allow the target (need) or the stretch ends; 0 while the next segments come from the
 * device's own planner or line generator. */
static uint64_t stretch_room(const cs_fw_motion_t *a, uint64_t need)
{
#if CS_FW_CURVES
    if (a->tracing || a->gen_busy || cs_planner_count(&a->pl) != 0)
        return 0;
#endif
    uint64_t r = 0;
    for (uint16_t k = 0; k < a->qcount && r < need; k++) {
        const cs_fw_item_t *it = &a->q[(a->qhead + k) % CS_FW_QUEUE];
        if (it->type != CS_PROTO_SEGMENT || !same_speed(&a->ov_anchor, &it->u.seg))
            break;
        r += it->u.seg.ticks;
    }
    return r;
}

/* The cap above 1 for the pending segment (>= 1, Q16); *fresh: it starts a new stretch. */
static uint32_t ov_cap(const cs_fw_motion_t *a, bool *fresh)
{
    *fresh = !a->ov_has_anchor || !same_speed(&a->ov_anchor, &a->pend);
    uint64_t t = a->hold.target;
    if (*fresh || t <= CS_HOLD_SCALE_ONE)
        return CS_HOLD_SCALE_ONE;
    /* ramping from the target down to 1 takes job time T (target^2 - 1) / 2 (cs_hold) */
    uint64_t one2 = (uint64_t)CS_HOLD_SCALE_ONE * CS_HOLD_SCALE_ONE;
    uint64_t T = a->hold.ramp_ticks;
    uint64_t need = (((t * t - one2) >> 16) * T >> 17) + 1u;
    uint64_t room = stretch_room(a, need);
    uint64_t brake = cs_fixed_isqrt64(one2 + (room << 33) / T); /* sqrt(1 + 2 R / T), Q16 */
    uint64_t c = rate_cap(a, &a->pend);
    if (brake < c)
        c = brake;
    return c < CS_HOLD_SCALE_ONE ? CS_HOLD_SCALE_ONE : (uint32_t)c;
}
#endif

/* The scale the pending segment aims at (cs_hold_admit_to's goal); *fresh as ov_cap. */
static uint32_t ov_goal(const cs_fw_motion_t *a, bool *fresh)
{
    bool ov = cs_fw_ctl_overridable(a);
#if CS_FW_OV_UP
    return cs_hold_goal(&a->hold, ov, ov_cap(a, fresh));
#else
    *fresh = false;
    return cs_hold_goal(&a->hold, ov, CS_HOLD_SCALE_ONE);
#endif
}

/* Keeps the executor's ring full; a hold or an override re-times what it hands over and, at
 * rest, keeps the next segment back (cs_hold). A PEN stops the feeding until it is set. */
static void feed(cs_fw_motion_t *a)
{
    a->more = false;
    while (cs_stepper_free(&a->st) > 0) {
        if (a->pen_wait && !apply_pen(a))
            break;
        if (!a->has_pend) {
            if (!next_segment(a, &a->pend, &a->pend_done))
                break;
            a->has_pend = true;
        }
        cs_segment_t orig = a->pend;
        bool fresh;
        if (!cs_hold_admit_to(&a->hold, &a->pend, ov_goal(a, &fresh)))
            break;
#if CS_FW_OV_UP
        if (fresh) {
            a->ov_anchor = orig;
            a->ov_has_anchor = true;
        }
#endif
        a->has_pend = false;
        push_segment(a, &a->pend, &orig, a->pend_done);
    }
}

/* HELD only once the hold's ramp has ended (the executor refused the next segment at rest, or
 * there was nothing left to run): a sender that waits for HELD (Grbl's Hold:0, the host's
 * ABORT after HOLD) must not act while the axes still decelerate. Until then: RUNNING. */
static bool held_at_rest(const cs_fw_motion_t *a)
{
    return cs_hold_stopped(&a->hold) || cs_fw_motion_done(a);
}

static void update_state(cs_fw_motion_t *a)
{
    uint8_t ctl = cs_fw_ctl_state(a);
    uint8_t st = ctl == CS_PROTO_STATE_ALARM ? ctl
                 : a->hold.hold && !a->ctl.cancel && held_at_rest(a) ? CS_PROTO_STATE_HELD
                 : a->hold.hold && !a->ctl.cancel                    ? CS_PROTO_STATE_RUNNING
                 : ctl != 0xFFu                   ? ctl
                 : !cs_fw_motion_done(a) ? CS_PROTO_STATE_RUNNING
                 : a->aborted            ? CS_PROTO_STATE_ABORTED
                                         : CS_PROTO_STATE_IDLE;
    if (st != a->state) {
        a->state = st;
        a->news = true;
    }
}

/* --- the API ------------------------------------------------------------------------------- */

void cs_fw_motion_zero(void *p, size_t n)
{
    uint8_t *b = p;
    for (size_t i = 0; i < n; i++)
        b[i] = 0;
}

void cs_fw_motion_cfg_default(cs_fw_motion_cfg_t *c, const cs_machine_t *m)
{
    c->queue_size = CS_FW_QUEUE;
    c->tol = m->tolerance;
#if CS_FW_CURVES
    c->method = (uint8_t)CS_FW_TRACE;
#else
    c->method = 0;
#endif
}

cs_err_t cs_fw_motion_init(cs_fw_motion_t *mo, const cs_machine_t *m, const cs_fw_motion_cfg_t *c)
{
    if (mo == NULL || m == NULL || c == NULL || c->queue_size < 1 || c->queue_size > CS_FW_QUEUE ||
        c->tol <= 0)
        return CS_ERR_ARG;
    cs_fw_motion_zero(mo, sizeof *mo);
    mo->m = m;
    mo->cfg = *c;
    cs_err_t e = cs_stepper_init(&mo->st, m);
    if (e == CS_OK)
        e = cs_hold_init(&mo->hold, m);
#if CS_FW_CURVES
    if (e == CS_OK)
        e = cs_planner_init(&mo->pl, m);
    if (e == CS_OK)
        e = cs_segment_init(&mo->gen, m);
#endif
    if (e != CS_OK)
        return CS_ERR_ARG;
    cs_exlog_segs_init(&mo->log);
    /* nothing executed yet: the last executed sequence is the one before the receiver's first
     * (a host reads STATUS.last_seq against its own first sequence) */
    mo->exec_seq = 0xFFFFu;
    mo->item_seq[0] = 0xFFFFu;
    mo->state = CS_PROTO_STATE_IDLE;
    mo->news = true;
    port_stepper_attach(&mo->st);
    cs_fw_ctl_init(mo);
    return CS_OK;
}

cs_err_t cs_fw_motion_queue(cs_fw_motion_t *a, const cs_proto_msg_t *msg, uint16_t seq)
{
    if (!cs_proto_uses_slot(msg->type) || (!CS_FW_CURVES && msg->type == CS_PROTO_CURVE))
        return CS_ERR_UNSUPPORTED;
    cs_err_t e = cs_fw_ctl_admit(a, msg->type);
    if (e != CS_OK)
        return e;
    if (a->qcount >= a->cfg.queue_size)
        return CS_ERR_FULL;
    cs_fw_item_t *it = &a->q[(a->qhead + a->qcount) % CS_FW_QUEUE];
    it->type = msg->type;
    it->seq = seq;
    if (msg->type == CS_PROTO_PEN)
        it->u.pen_us = msg->u.pen.pulse_us;
    else if (msg->type == CS_PROTO_SEGMENT)
        it->u.seg = msg->u.segment;
    else if (msg->type == CS_PROTO_SPINDLE)
        it->u.spindle = msg->u.spindle;
#if CS_FW_CURVES
    else if (msg->type == CS_PROTO_CURVE)
        it->u.curve = msg->u.curve;
#endif
#if CS_FW_CTL
    else if (msg->type == CS_PROTO_HOME)
        it->u.home = msg->u.home;
    else if (msg->type == CS_PROTO_JOG)
        it->u.jog = msg->u.jog;
    else
        it->u.probe = msg->u.probe;
#endif
    a->qcount++;
    a->aborted = false;
    return CS_OK;
}

void cs_fw_motion_hold(cs_fw_motion_t *a, bool on)
{
    if (on && !a->hold.hold)
        a->stats.holds++;
    cs_hold_set(&a->hold, on);
    a->news = true;
}

void cs_fw_motion_override(cs_fw_motion_t *a, const cs_proto_override_t *ov)
{
    /* Q16 = per-mille x 65536 / 1000, rounded (below 2^31: feed <= CS_PROTO_OVERRIDE_MAX) */
    cs_hold_override(&a->hold, ((uint32_t)ov->feed * CS_HOLD_SCALE_ONE + 500u) /
                                   CS_PROTO_OVERRIDE_ONE);
    cs_fw_ctl_override(a, ov->spindle);
}

void cs_fw_motion_flush(cs_fw_motion_t *a)
{
    a->has_pend = false;
#if CS_FW_OV_UP
    a->ov_has_anchor = false;
#endif
    a->pen_wait = false;
    cs_fw_ctl_line_stop(a);
#if CS_FW_CURVES
    a->tracing = false;
    a->rapid_pending = false;
    /* the executor's ring finishes (at most CS_STEPPER_RING segments), the rest is dropped */
    if (a->gen_busy || cs_planner_count(&a->pl) > 0) {
        (void)cs_planner_init(&a->pl, a->m);
        (void)cs_segment_init(&a->gen, a->m);
        a->gen_busy = false;
    }
    a->pl_stale = true;
#endif
}

void cs_fw_motion_drop(cs_fw_motion_t *a)
{
    a->qcount = 0;
    a->qhead = 0;
    cs_fw_motion_flush(a);
    cs_hold_reset(&a->hold);
    a->news = true;
}

void cs_fw_motion_give_back(cs_fw_motion_t *a)
{
    /* ABORT: items taken from the queue but not wholly handed to the executor (the segment held
     * back, a PEN waiting, a curve being traced or planned) are dropped unexecuted: they are
     * given back their numbers, so "executed" and the job's numbers (STATUS done/recv) stay the
     * truth and a resume sends them again. The ring's segments finish; the last one's tag is
     * the last item they complete. (Only here: the machine-control paths that flush mid-item,
     * homing and probing, keep their item taken.) */
    uint32_t keep = a->pushed != a->completed
                        ? tag_item(a, a->tag[(uint8_t)(a->pushed - 1u) & TAG_MASK])
                        : a->exec_item;
    if (item_after(a->popped, keep))
        a->popped = keep;
}

/* ABORT, a reboot: no override. */
static void override_reset(cs_fw_motion_t *a)
{
    cs_hold_override(&a->hold, CS_HOLD_SCALE_ONE);
    cs_fw_ctl_override(a, CS_PROTO_OVERRIDE_ONE);
}

void cs_fw_motion_abort(cs_fw_motion_t *a)
{
    override_reset(a);
    cs_fw_ctl_abort(a);
    cs_fw_motion_drop(a);
    a->aborted = true;
    a->stats.aborts++;
}

void cs_fw_motion_poll(cs_fw_motion_t *a)
{
    cs_fw_ctl_poll(a);
    feed(a);
    note_completed(a);
    update_state(a);
}

void cs_fw_motion_reboot(cs_fw_motion_t *a)
{
    a->qcount = 0;
    a->qhead = 0;
    a->exec_seq = 0xFFFFu;
    a->item_seq[a->popped & SEQ_MASK] = 0xFFFFu;
    cs_hold_reset(&a->hold);
    a->aborted = false;
    a->nerr = 0;
    a->news = true;
    /* a rebooted device knows neither the job nor where the machine is */
    a->job_flags = 0;
    a->job_id = a->job_base = 0;
    override_reset(a);
}

uint32_t cs_fw_motion_job_no(const cs_fw_motion_t *a, uint32_t item)
{
    if (!(a->job_flags & CS_PROTO_STATUS_JOB))
        return 0;
    /* items before the SETPOS belong to the previous job: nothing of this one */
    return item_after(item, a->job_item0) ? a->job_base + (item - a->job_item0) : a->job_base;
}

void cs_fw_motion_count_immediate(cs_fw_motion_t *a)
{
    /* numbered after everything before it: only when nothing is queued or running (an UNLOCK
     * comes in the alarm state, whose stop emptied the queue), else it would count as done an
     * item still waiting */
    if ((a->job_flags & CS_PROTO_STATUS_JOB) && cs_fw_motion_done(a)) {
        a->job_base++;
        a->news = true;
    }
}

cs_err_t cs_fw_motion_setpos(cs_fw_motion_t *a, const cs_proto_setpos_t *sp)
{
    if (sp->flags & CS_PROTO_SETPOS_POS) {
        if (!cs_fw_motion_done(a))
            return CS_ERR_STATE;
        for (unsigned i = 0; i < CS_AXES; i++) { /* idle: cannot fail (done above) */
            uint32_t irq = port_irq_save();
            (void)cs_stepper_set_position(&a->st, i, sp->pos[i]);
            port_irq_restore(irq);
#if CS_FW_SIM_HOOKS
            a->set_delta[i] += sp->pos[i] - a->steps_pos[i];
#endif
            a->steps_pos[i] = sp->pos[i];
        }
#if CS_FW_CURVES
        a->pl_stale = true;
#endif
        a->job_flags |= CS_PROTO_STATUS_POS;
    }
    a->job_id = sp->job_id;
    a->job_base = sp->base;
    a->job_item0 = a->popped + a->qcount; /* the next item received is base + 1 */
    /* a new job runs as planned (the spindle's override stays: a running spindle keeps its
     * power from one job to the next) */
    cs_hold_override(&a->hold, CS_HOLD_SCALE_ONE);
    a->job_flags |= CS_PROTO_STATUS_JOB;
    a->news = true;
    return CS_OK;
}

void cs_fw_motion_take_limit(cs_fw_motion_t *a, uint32_t n)
{
    a->take_max = n;
}

uint16_t cs_fw_motion_free(const cs_fw_motion_t *a)
{
    return (uint16_t)(a->cfg.queue_size - a->qcount);
}

bool cs_fw_motion_news(cs_fw_motion_t *a)
{
    bool n = a->news;
    a->news = false;
    return n;
}

void cs_fw_motion_status(const cs_fw_motion_t *a, cs_proto_status_t *st)
{
    st->state = a->state;
    st->queue_fill = a->qcount;
    st->last_seq = a->exec_seq;
    st->axes = a->m->n_axes;
    /* one snapshot: the step interrupt masked while the counters and the clock are read, so
     * tick is the executor's time of this very position (a host divides position differences
     * by tick differences: the device's speed, whatever the line's delays; docs/protocol.md) */
    uint32_t s = port_irq_save();
    st->tick = port_ticks_now();
    for (unsigned i = 0; i < CS_PROTO_AXES_MAX; i++)
        st->pos[i] = i < a->m->n_axes ? cs_stepper_position(&a->st, i) : 0;
    port_irq_restore(s);
    st->flags = (uint8_t)(a->job_flags | CS_PROTO_STATUS_TICK);
    st->job_id = a->job_id;
    st->done = cs_fw_motion_job_no(a, a->exec_item);
    st->recv = cs_fw_motion_job_no(a, a->popped + a->qcount);
}

bool cs_fw_motion_peek_error(const cs_fw_motion_t *a, cs_proto_error_t *e)
{
    if (a->nerr == 0)
        return false;
    *e = a->errs[0];
    return true;
}

void cs_fw_motion_drop_error(cs_fw_motion_t *a)
{
    if (a->nerr == 0)
        return;
    for (uint8_t i = 1; i < a->nerr; i++)
        a->errs[i - 1] = a->errs[i];
    a->nerr--;
    a->stats.errors_sent++;
}

bool cs_fw_motion_pop_error(cs_fw_motion_t *a, cs_proto_error_t *e)
{
    if (!cs_fw_motion_peek_error(a, e))
        return false;
    cs_fw_motion_drop_error(a);
    return true;
}
