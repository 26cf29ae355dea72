/* cs_hold: the feed-hold ramp (see cs_hold.h for the model and its acceleration bound). */
#include "cs_hold.h"

cs_err_t cs_hold_init(cs_hold_t *h, const cs_machine_t *m)
{
    if (h == 0 || m == 0 || m->n_axes == 0 || m->n_axes > CS_AXES || m->tick_hz == 0)
        return CS_ERR_ARG;
    uint64_t t = 0;
    for (unsigned i = 0; i < m->n_axes; i++) {
        const cs_axis_cfg_t *a = &m->axis[i];
        if (a->max_rate <= 0 || a->max_accel <= 0)
            return CS_ERR_ARG;
        /* T_i = max_rate / max_accel seconds (both Q16: the scales cancel), in ticks, rounded up
         * so that the ramp never asks for more than max_accel */
        uint64_t ti = ((uint64_t)a->max_rate * m->tick_hz + (uint64_t)a->max_accel - 1u) /
                      (uint64_t)a->max_accel;
        if (ti > t)
            t = ti;
    }
    h->ramp_ticks = t == 0 ? 1u : t > UINT32_MAX ? UINT32_MAX : (uint32_t)t;
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

bool cs_hold_stopped(const cs_hold_t *h)
{
    return h->hold && h->stopped;
}

bool cs_hold_active(const cs_hold_t *h)
{
    return h->hold || h->scale < CS_HOLD_SCALE_ONE;
}

bool cs_hold_admit(cs_hold_t *h, cs_segment_t *s)
{
    if (h->hold) {
        if (h->stopped || h->scale <= CS_HOLD_SCALE_MIN) {
            h->stopped = true;
            return false;
        }
    } else if (h->scale >= CS_HOLD_SCALE_ONE) {
        return true;
    }
    /* ticks' = ticks / s, rounded up (never shorter: |steps| <= ticks still holds) */
    uint64_t t = (((uint64_t)s->ticks << 16) + h->scale - 1u) / h->scale;
    if (t > CS_HOLD_MAX_TICKS)
        t = CS_HOLD_MAX_TICKS > s->ticks ? CS_HOLD_MAX_TICKS : s->ticks;
    s->ticks = (uint32_t)t;
    /* ds = ticks' / T (Q16), at least one LSB so that the ramp always ends */
    uint64_t ds = (t << 16) / h->ramp_ticks;
    uint32_t d = ds == 0 ? 1u : ds > CS_HOLD_SCALE_ONE ? CS_HOLD_SCALE_ONE : (uint32_t)ds;
    if (h->hold)
        h->scale = h->scale > CS_HOLD_SCALE_MIN + d ? h->scale - d : CS_HOLD_SCALE_MIN;
    else
        h->scale = h->scale + d < CS_HOLD_SCALE_ONE ? h->scale + d : CS_HOLD_SCALE_ONE;
    return true;
}
