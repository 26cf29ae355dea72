/* cs_segment: the velocity profile of one block (trapezoid, or S-curve speed changes) sampled
 * every segment_ticks. The distance reached at time t is computed in closed form from the phase
 * it falls in (never accumulated), and each axis's step position is the block's exact chord at
 * that distance, rounded: the difference between two consecutive samples is the segment's steps,
 * so rounding carries from segment to segment and the last sample (d = L) lands exactly on the
 * block's target (docs/motion.md). */
#include "cs_segment.h"

#include <stddef.h>

CS_STATIC_ASSERT(sizeof(cs_segment_t) == 4 + 4 * CS_AXES, segment_is_packed);

cs_err_t cs_segment_init(cs_segment_gen_t *g, const cs_machine_t *m)
{
    if (g == NULL || m == NULL || m->tick_hz == 0 || m->segment_ticks == 0)
        return CS_ERR_ARG;
    g->m = m;
    g->active = false;
    g->block_end = false;
    return CS_OK;
}

bool cs_segment_block_end(const cs_segment_gen_t *g)
{
    return g->block_end;
}

uint32_t cs_segment_block_ticks(const cs_segment_gen_t *g)
{
    return g->ta + g->tc + g->td;
}

/* Speed change a * t / hz (Q16 mm/s) after t ticks at accel (Q16 mm/s^2). */
static int64_t dv_at(int32_t accel, uint32_t t, uint32_t hz)
{
    return cs_fixed_div_round((int64_t)accel * t, hz);
}

/* Distance (Q16 mm) covered in t ticks starting at speed v (Q16) while the speed changes by
 * +/- accel: t * (2 v +/- a t / hz) / (2 hz) -- the mean speed times the time. */
static int64_t dist_at(int32_t v, int32_t accel, int sign, uint32_t t, uint32_t hz)
{
    int64_t vsum = 2 * (int64_t)v + sign * dv_at(accel, t, hz);
    return cs_fixed_div_round(vsum * t, 2 * (int64_t)hz);
}

/* S-curve phase of T ticks changing the speed by dv from v: ticks = ceil(T_seconds * hz). */
static int64_t scurve_ticks(const cs_segment_gen_t *g, int64_t dv)
{
    int64_t t = cs_planner_scurve_time(g->accel, g->m->max_jerk, dv);
    if (t == INT64_MAX)
        return INT64_MAX;
    int64_t ticks;
    if (cs_fixed_muldiv64(t, g->m->tick_hz, (int64_t)1 << 32, &ticks) != CS_OK)
        return INT64_MAX;
    return ticks + 1; /* rounding up keeps the peak acceleration and jerk within the limits */
}

/* Distance (Q16 mm) t ticks into an S-curve phase of T ticks starting at speed v and changing
 * it by sign * dv: v t + sign dv T S(t / T), S(x) = x^3 - x^4 / 2 (the integral of the
 * smoothstep 3x^2 - 2x^3). */
static int64_t scurve_dist(int64_t v, int64_t dv, int sign, uint32_t t, uint32_t T, uint32_t hz)
{
    if (T == 0)
        return 0;
    int64_t x = ((int64_t)t << 30) / T; /* Q30 */
    int64_t x2 = (x * x) >> 30, x3 = (x2 * x) >> 30, x4 = (x2 * x2) >> 30;
    int64_t S = x3 - x4 / 2, part;
    if (cs_fixed_muldiv64(dv * T, S, (int64_t)hz << 30, &part) != CS_OK)
        part = 0; /* unreachable: dv * T < 2^61, S <= 2^30 */
    return cs_fixed_div_round(v * t, hz) + sign * part;
}

/* Length (Q16 mm) of an S-curve block's two speed changes with peak vp; ticks in *ta, *td. */
static int64_t scurve_changes(const cs_segment_gen_t *g, int64_t v0, int64_t vp, int64_t v1,
                              int64_t *ta, int64_t *td)
{
    int64_t hz2 = 2 * (int64_t)g->m->tick_hz;
    *ta = scurve_ticks(g, vp - v0);
    *td = scurve_ticks(g, vp - v1);
    if (*ta >= (int64_t)CS_SEGMENT_MAX_BLOCK_TICKS || *td >= (int64_t)CS_SEGMENT_MAX_BLOCK_TICKS)
        return INT64_MAX;
    return cs_fixed_div_round((v0 + vp) * *ta, hz2) + cs_fixed_div_round((vp + v1) * *td, hz2);
}

/* The cruise phase of a block whose ramps (ta, td, da) are set: dc mm at vp, its time rounded
 * up so the block never ends before its distance is covered, and at least one tick per block. */
static cs_err_t set_cruise(cs_segment_gen_t *g, int64_t dc, int64_t vp, uint32_t hz)
{
    if (dc < 0)
        dc = 0;
    int64_t tc = vp > 0 ? (dc * hz + vp - 1) / vp : 0;
    if (tc + (int64_t)g->ta + (int64_t)g->td >= (int64_t)CS_SEGMENT_MAX_BLOCK_TICKS)
        return CS_ERR_RANGE;
    g->tc = (uint32_t)tc;
    if (g->ta + g->tc + g->td == 0)
        g->tc = 1;
    g->dc = cs_fixed_div_round(vp * (int64_t)g->tc, hz);
    return CS_OK;
}

/* S-curve block: peak vp = the nominal speed when both speed changes fit the block, else the
 * highest that fits, by bisection from max(v0, v1) (which the planner guarantees fits). */
static cs_err_t load_scurve(cs_segment_gen_t *g, int64_t v0, int64_t v1, int64_t vc, int64_t len)
{
    uint32_t hz = g->m->tick_hz;
    int64_t ta, td, vp = vc;
    if (scurve_changes(g, v0, vc, v1, &ta, &td) > len) {
        int64_t lo = v0 > v1 ? v0 : v1, hi = vc;
        while (hi - lo > 1) {
            int64_t mid = lo + (hi - lo) / 2;
            if (scurve_changes(g, v0, mid, v1, &ta, &td) <= len)
                lo = mid;
            else
                hi = mid;
        }
        vp = lo;
    }
    int64_t both = scurve_changes(g, v0, vp, v1, &ta, &td);
    if (both == INT64_MAX)
        return CS_ERR_RANGE;
    g->vp = (int32_t)vp;
    g->ta = (uint32_t)ta;
    g->td = (uint32_t)td;
    g->da = cs_fixed_div_round((v0 + vp) * ta, 2 * (int64_t)hz);
    return set_cruise(g, len - both, vp, hz);
}

static cs_err_t load_block(cs_segment_gen_t *g, const cs_block_t *b)
{
    uint32_t hz = g->m->tick_hz;
    int64_t vc = b->nominal;
    int64_t v0 = cs_planner_speed(b->entry_v2), v1 = cs_planner_speed(b->exit_v2);
    if (v0 > vc)
        v0 = vc;
    if (v1 > vc)
        v1 = vc;
    int64_t a = b->accel, len = b->length;
    g->scurve = g->m->profile == CS_PROFILE_SCURVE;
    if (g->scurve) {
        g->v0 = (int32_t)v0;
        g->v1 = (int32_t)v1;
        g->accel = (int32_t)a;
        cs_err_t e = load_scurve(g, v0, v1, vc, len);
        if (e != CS_OK)
            return e;
        goto loaded;
    }
    /* Distances to accelerate from v0 and decelerate to v1 at a: (vc^2 - v^2) / (2 a), Q32/Q16. */
    int64_t d_acc = (vc * vc - v0 * v0) / (2 * a);
    int64_t d_dec = (vc * vc - v1 * v1) / (2 * a);
    int64_t vp = vc;
    if (d_acc + d_dec > len) {
        /* Triangle: the peak where both meet, vp^2 = a L + (v0^2 + v1^2) / 2 (each term < 2^62). */
        int64_t vp2 = a * len + v0 * v0 / 2 + v1 * v1 / 2;
        vp = cs_planner_speed(vp2);
        if (vp < v0)
            vp = v0;
        if (vp < v1)
            vp = v1;
        if (vp > vc)
            vp = vc;
    }
    /* Phase times floored so the speed reached never passes vp (accelerating) nor drops under v1
     * (decelerating): the profile's distance is then monotonic. */
    int64_t ta = (vp - v0) * hz / a, td = (vp - v1) * hz / a;
    if (ta >= (int64_t)CS_SEGMENT_MAX_BLOCK_TICKS || td >= (int64_t)CS_SEGMENT_MAX_BLOCK_TICKS)
        return CS_ERR_RANGE;
    g->v0 = (int32_t)v0;
    g->vp = (int32_t)vp;
    g->v1 = (int32_t)v1;
    g->accel = (int32_t)a;
    g->ta = (uint32_t)ta;
    g->td = (uint32_t)td;
    g->da = dist_at(g->v0, g->accel, 1, g->ta, hz);
    int64_t dd = dist_at(g->vp, g->accel, -1, g->td, hz);
    cs_err_t e = set_cruise(g, len - g->da - dd, vp, hz);
    if (e != CS_OK)
        return e;
loaded:
    g->length = len;
    for (unsigned i = 0; i < CS_AXES; i++) {
        g->steps[i] = b->steps[i];
        g->frac0[i] = b->frac0[i];
        g->exact[i] = b->exact[i];
        g->done[i] = 0;
    }
    g->t = 0;
    g->d = 0;
    g->line = b->line;
    g->active = true;
    return CS_OK;
}

/* Distance along the block at t ticks (Q16 mm), clamped to [0, L]; exactly L at the end. */
static int64_t dist_of(const cs_segment_gen_t *g, uint32_t t)
{
    uint32_t hz = g->m->tick_hz;
    int64_t d;
    if (t >= g->ta + g->tc + g->td)
        return g->length;
    if (t <= g->ta)
        d = g->scurve ? scurve_dist(g->v0, g->vp - g->v0, 1, t, g->ta, hz)
                      : dist_at(g->v0, g->accel, 1, t, hz);
    else if (t <= g->ta + g->tc)
        d = g->da + cs_fixed_div_round((int64_t)g->vp * (t - g->ta), hz);
    else if (g->scurve)
        d = g->da + g->dc + scurve_dist(g->vp, g->vp - g->v1, -1, t - g->ta - g->tc, g->td, hz);
    else
        d = g->da + g->dc + dist_at(g->vp, g->accel, -1, t - g->ta - g->tc, hz);
    return d > g->length ? g->length : d;
}

/* Steps from the block's (rounded) start to the chord's point at distance d: round(frac0 +
 * exact * d / L), within 1/2 step of the chord; kept between 0 and the block's total. */
static int32_t chord_steps(const cs_segment_gen_t *g, unsigned i, int64_t d)
{
    int64_t x;
    if (g->steps[i] == 0)
        return 0;
    if (cs_fixed_muldiv64(g->exact[i], d, g->length, &x) != CS_OK)
        return (int32_t)cs_fixed_div_round((int64_t)g->steps[i] * d, g->length);
    int64_t n = cs_fixed_round_shift64(g->frac0[i] + x, 16);
    int64_t lo = g->steps[i] < 0 ? g->steps[i] : 0, hi = g->steps[i] < 0 ? 0 : g->steps[i];
    return (int32_t)(n < lo ? lo : n > hi ? hi : n);
}

cs_err_t cs_segment_next(cs_segment_gen_t *g, cs_planner_t *pl, cs_segment_t *out)
{
    g->block_end = false;
    if (!g->active) {
        const cs_block_t *b = cs_planner_begin_head(pl);
        if (b == NULL)
            return CS_ERR_EMPTY;
        cs_err_t e = load_block(g, b);
        if (e != CS_OK)
            return e;
    }
    uint32_t total = g->ta + g->tc + g->td;
    uint32_t t1 = total - g->t > g->m->segment_ticks ? g->t + g->m->segment_ticks : total;
    int64_t d1 = dist_of(g, t1);
    if (d1 < g->d)
        d1 = g->d; /* rounding never walks backwards */
    uint32_t ticks = t1 - g->t;
    int64_t most = 0;
    for (unsigned i = 0; i < CS_AXES; i++) {
        int32_t target = t1 == total ? g->steps[i] : chord_steps(g, i, d1);
        int32_t n = target - g->done[i];
        out->steps[i] = n;
        g->done[i] = target;
        int64_t mag = n < 0 ? -(int64_t)n : n;
        if (mag > most)
            most = mag;
    }
    /* At most one step per axis per tick: only a rounding remainder in a block's last, short
     * segment can ask for more; it then takes one tick per step. */
    out->ticks = (int64_t)ticks < most ? (uint32_t)most : ticks;
    g->t = t1;
    g->d = d1;
    if (t1 == total) {
        g->active = false;
        g->block_end = true;
        cs_planner_end_head(pl);
    }
    return CS_OK;
}
