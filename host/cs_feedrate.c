/* cs_feedrate: speed from timed position samples (see cs_feedrate.h). */
#include "cs_feedrate.h"

#include <math.h>
#include <string.h>

void cs_feedrate_reset(cs_feedrate_t *f)
{
    memset(f, 0, sizeof *f);
}

static void push(cs_feedrate_t *f, double t, const int32_t pos[CS_PROTO_AXES_MAX])
{
    f->head = f->n == 0 ? 0 : (f->head + 1) % CS_FEEDRATE_RING;
    f->t[f->head] = t;
    memcpy(f->pos[f->head], pos, sizeof f->pos[0]);
    if (f->n < CS_FEEDRATE_RING)
        f->n++;
}

void cs_feedrate_add_tick(cs_feedrate_t *f, uint32_t tick, uint32_t tick_hz,
                          const int32_t pos[CS_PROTO_AXES_MAX])
{
    if (tick_hz == 0)
        return;
    if (f->n > 0 && !f->timed)
        cs_feedrate_reset(f);
    double t = 0;
    if (f->n > 0) {
        /* unsigned difference: right across the counter's wrap */
        uint32_t d = tick - f->tick;
        if (d == 0)
            return;
        double dt = (double)d / tick_hz;
        if (d >= 0x80000000u || dt > CS_FEEDRATE_GAP_S)
            cs_feedrate_reset(f);
        else
            t = f->t[f->head] + dt;
    }
    f->timed = true;
    f->tick = tick;
    push(f, t, pos);
}

void cs_feedrate_add_host(cs_feedrate_t *f, double t_s, const int32_t pos[CS_PROTO_AXES_MAX])
{
    if (f->n > 0 && f->timed)
        cs_feedrate_reset(f);
    if (f->n > 0) {
        double age = t_s - f->t[f->head];
        bool same = memcmp(pos, f->pos[f->head], sizeof f->pos[0]) == 0;
        if (age <= 0 || (same && age < CS_FEEDRATE_WINDOW_HOST_S))
            return;
    }
    push(f, t_s, pos);
}

bool cs_feedrate_mm_min(const cs_feedrate_t *f, unsigned axes, const double *steps_mm,
                        double *mm_min)
{
    if (f->n < 2)
        return false;
    double w = f->timed ? CS_FEEDRATE_WINDOW_DEV_S : CS_FEEDRATE_WINDOW_HOST_S;
    unsigned h = f->head, o = h;
    /* back from the newest to the first sample at least w older (else the oldest held) */
    for (unsigned k = 1; k < f->n; k++) {
        o = (h + CS_FEEDRATE_RING - k) % CS_FEEDRATE_RING;
        if (f->t[h] - f->t[o] >= w)
            break;
    }
    double dt = f->t[h] - f->t[o];
    if (dt <= 0)
        return false;
    double d2 = 0;
    for (unsigned i = 0; i < axes && i < CS_PROTO_AXES_MAX; i++) {
        double mm = ((double)f->pos[h][i] - (double)f->pos[o][i]) / steps_mm[i];
        d2 += mm * mm;
    }
    *mm_min = sqrt(d2) / dt * 60.0;
    return true;
}
