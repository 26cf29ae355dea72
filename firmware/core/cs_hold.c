/* cs_hold: the feed-hold ramp (see cs_hold.h for the model and its acceleration bound). */
#include "cs_hold.h"

#include "cs_fixed.h"

cs_err_t cs_hold_init(cs_hold_t *h, const cs_machine_t *m)
{
    if (h == 0 || m == 0 || m->n_axes == 0 || m->n_axes > CS_AXES || m->tick_hz == 0)
        return CS_ERR_ARG;
    uint64_t t = 0;
    for (unsigned i = 0; i < m->n_axes; i++) {
        const cs_axis_cfg_t *a = &m->axis[i];
        if (a->max_rate <= 0 || a->max_accel <= 0)
            return CS_ERR_ARG;
        /* T_i = CS_HOLD_RAMP_MARGIN x max_rate / max_accel seconds (both Q16: the scales
         * cancel), in ticks, rounded up */
        uint64_t num = (uint64_t)a->max_rate * m->tick_hz * CS_HOLD_RAMP_MARGIN_NUM;
        uint64_t den = (uint64_t)a->max_accel * CS_HOLD_RAMP_MARGIN_DEN;
        uint64_t ti = (num + den - 1u) / den;
        if (ti > t)
            t = ti;
    }
    h->ramp_ticks = t == 0 ? 1u : t > UINT32_MAX ? UINT32_MAX : (uint32_t)t;
    h->target = CS_HOLD_SCALE_ONE;
    cs_hold_reset(h);
    return CS_OK;
}

void cs_hold_set(cs_hold_t *h, bool on)
{
    h->hold = on;
    if (!on)
        h->stopped = false;
}

void cs_hold_reset(cs_hold_t *h)
{
    h->scale = CS_HOLD_SCALE_ONE;
    h->hold = false;
    h->stopped = false;
}

void cs_hold_override(cs_hold_t *h, uint32_t target)
{
    h->target = target < 1u ? 1u : target > CS_HOLD_SCALE_MAX ? CS_HOLD_SCALE_MAX : target;
}

uint32_t cs_hold_goal(const cs_hold_t *h, bool ov, uint32_t cap)
{
    if (!ov)
        return CS_HOLD_SCALE_ONE;
    return h->target < cap ? h->target : cap;
}

bool cs_hold_stopped(const cs_hold_t *h)
{
    return h->hold && h->stopped;
}

bool cs_hold_active(const cs_hold_t *h)
{
    return h->hold || h->scale < CS_HOLD_SCALE_ONE;
}

/* The segment's real duration for a mean scale (s0 + s1) / 2: t = 2 tau / (s0 + s1), rounded
 * up, never longer than the executor takes nor shorter than its largest |steps| (one step a
 * tick at most: only a scale above 1 can come near it). */
static uint32_t retime(const cs_segment_t *s, uint32_t s0, uint32_t s1)
{
    uint64_t sum = (uint64_t)s0 + s1;
    uint64_t t = sum == 0 ? CS_HOLD_MAX_TICKS : (((uint64_t)s->ticks << 17) + sum - 1u) / sum;
    if (t > CS_HOLD_MAX_TICKS)
        t = CS_HOLD_MAX_TICKS > s->ticks ? CS_HOLD_MAX_TICKS : s->ticks;
    uint32_t r = (uint32_t)t;
    for (unsigned i = 0; i < CS_AXES; i++) {
        uint32_t a = s->steps[i] < 0 ? 0u - (uint32_t)s->steps[i] : (uint32_t)s->steps[i];
        if (a > r)
            r = a;
    }
    return r;
}

bool cs_hold_admit_to(cs_hold_t *h, cs_segment_t *s, uint32_t goal)
{
    if (h->hold) {
        if (h->stopped || h->scale == 0) {
            h->stopped = true;
            return false;
        }
        goal = 0;
    } else if (h->scale == CS_HOLD_SCALE_ONE && goal == CS_HOLD_SCALE_ONE) {
        return true;
    }
    /* s moves linearly in real time t at 1/T towards the goal (falls in a hold, rises on a
     * resume, either way for an override). A segment of job time tau then takes real time t
     * with tau = integral of s dt = t (s0 + s1) / 2, and s1^2 = s0^2 -+ 2 tau / T
     * (eliminating t): s1 from the integer square root, clamped at the goal, then
     * t = 2 tau / (s0 + s1). A hold whose ramp ends inside a segment runs that segment as if
     * it ended at rest (s1 = 0: t = 2 tau / s0, a deceleration of at most v s0^2 / (2 tau) <=
     * v / T) and stops after it. Q32 squares of Q16 scales (below 2^41: CS_HOLD_SCALE_MAX). */
    uint32_t s0 = h->scale, s1;
    uint64_t sq = (uint64_t)s0 * s0;
    uint64_t d = ((uint64_t)s->ticks << 33) / h->ramp_ticks;
    if (s0 > goal) {
        s1 = sq > d ? cs_fixed_isqrt64(sq - d) : 0;
        if (s1 < goal)
            s1 = goal;
    } else {
        s1 = cs_fixed_isqrt64(sq + d);
        if (s1 > goal)
            s1 = goal;
    }
    s->ticks = retime(s, s0, s1);
    h->scale = s1;
    return true;
}

bool cs_hold_admit(cs_hold_t *h, cs_segment_t *s)
{
    return cs_hold_admit_to(h, s, CS_HOLD_SCALE_ONE);
}
