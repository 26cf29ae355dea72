/* cs_planner: look-ahead over a ring of straight blocks, after Grbl's planner (reverse pass from
 * a full stop at the last block, forward pass from the frozen entry of the first one) with
 * junction speeds from the junction deviation and from the path's curvature (docs/motion.md). */
#include "cs_planner.h"

#include <stddef.h>

CS_STATIC_ASSERT((CS_PLANNER_RING & (CS_PLANNER_RING - 1)) == 0, planner_ring_power_of_two);
CS_STATIC_ASSERT(CS_PLANNER_RING >= 32 && CS_PLANNER_RING <= 32768, planner_ring_size);
CS_STATIC_ASSERT(sizeof(int64_t) == 8, int64_is_8_bytes);

#define RING_MASK ((uint16_t)(CS_PLANNER_RING - 1))
#define Q30_ONE   ((int64_t)1 << 30)
/* "No junction limit" (straight continuation): larger than any nominal speed squared. */
#define V2_UNLIMITED INT64_MAX

static uint16_t ring_index(const cs_planner_t *pl, unsigned i)
{
    return (uint16_t)((pl->head + i) & RING_MASK);
}

static cs_block_t *blk(cs_planner_t *pl, unsigned i)
{
    return &pl->ring[ring_index(pl, i)];
}

static int64_t min64(int64_t a, int64_t b)
{
    return a < b ? a : b;
}

int32_t cs_planner_speed(int64_t v2)
{
    if (v2 <= 0)
        return 0;
    uint32_t v = cs_fixed_isqrt64((uint64_t)v2);
    return v > (uint32_t)INT32_MAX ? INT32_MAX : (int32_t)v;
}

/* Speed squared that lets a block of length len decelerate at accel to exit speed^2 v2:
 * v2 + 2 a L (Q16 * Q16 = Q32). Both factors are < 2^31, so 2 a L < 2^63. */
static int64_t reach_v2(int64_t v2, int32_t accel, cs_pos_t len)
{
    int64_t d = 2 * (int64_t)accel * len;
    return v2 > INT64_MAX - d ? INT64_MAX : v2 + d;
}

int64_t cs_planner_scurve_time(int32_t accel, int32_t jerk, int64_t dv)
{
    if (dv <= 0)
        return 0;
    int64_t ta, tj;
    /* 1.5 dv / a: dv / a is a plain ratio of two Q16 values, times 3 * 2^31 gives Q32 s. */
    if (cs_fixed_muldiv64(3 * dv, (int64_t)1 << 31, accel, &ta) != CS_OK)
        ta = INT64_MAX;
    /* sqrt(6 dv / j): 6 dv / j is Q16 s^2; times 2^32 -> Q48, its square root is Q24 s. */
    int64_t q48;
    if (cs_fixed_muldiv64(6 * dv, (int64_t)1 << 32, jerk, &q48) != CS_OK)
        return INT64_MAX;
    tj = (int64_t)cs_fixed_isqrt64((uint64_t)q48) << 8;
    return ta > tj ? ta : tj;
}

/* Distance (Q16 mm) of an S-curve speed change between v and v + dv: (2 v + dv) / 2 * T(dv)
 * compared with len: true when it fits. Exact 128-bit comparison (T is Q32 s). */
static bool scurve_fits(int32_t accel, int32_t jerk, int64_t v, int64_t dv, cs_pos_t len)
{
    int64_t t = cs_planner_scurve_time(accel, jerk, dv);
    if (t == INT64_MAX)
        return false;
    return cs_fixed_cmp_prod_u64((uint64_t)(2 * v + dv), (uint64_t)t, (uint64_t)len * 2u,
                                 (uint64_t)1 << 32) <= 0;
}

/* Highest speed squared reachable from speed squared v2 over block b (either direction: the
 * profiles are symmetric). Trapezoid: v2 + 2 a L. S-curve: the change takes
 * max(1.5 dv / a, sqrt(6 dv / j)) at mean speed v + dv / 2, so when acceleration limits it
 * v^2 = v2 + (4/3) a L, and when jerk limits it dv is found by bisection. */
static int64_t reach(const cs_machine_t *m, int64_t v2, const cs_block_t *b)
{
    if (m->profile != CS_PROFILE_SCURVE)
        return reach_v2(v2, b->accel, b->length);
    int64_t d = 2 * (int64_t)b->accel * b->length;
    d = d / 3 * 2;
    int64_t va2 = v2 > INT64_MAX - d ? INT64_MAX : v2 + d;
    int64_t vk = cs_planner_speed(v2), hi = cs_planner_speed(va2) - vk;
    if (hi <= 0 || scurve_fits(b->accel, m->max_jerk, vk, hi, b->length))
        return va2;
    int64_t lo = 0; /* fits; hi does not */
    while (hi - lo > 1) {
        int64_t mid = lo + (hi - lo) / 2;
        if (scurve_fits(b->accel, m->max_jerk, vk, mid, b->length))
            lo = mid;
        else
            hi = mid;
    }
    int64_t v = vk + lo;
    return v2 > v * v ? v2 : v * v;
}

static bool axis_cfg_ok(const cs_axis_cfg_t *a, uint32_t tick_hz)
{
    if (a->steps_per_mm < (CS_MOTION_ONE >> 4) || a->steps_per_mm > ((int32_t)4096 << 16))
        return false;
    if (a->max_rate <= 0 || a->max_accel <= 0 || a->pulse_ticks == 0)
        return false;
    if (!cs_fixed_pos_ok(a->travel_min) || !cs_fixed_pos_ok(a->travel_max) ||
        a->travel_min > a->travel_max)
        return false;
    /* Highest step rate (steps/s, Q32 product >> 32) must leave at least two ticks per step, and
     * the pulse must fit in half of that step period (the executor makes at most one step per
     * axis per call). */
    uint64_t rate = ((uint64_t)a->max_rate * (uint64_t)a->steps_per_mm) >> 32;
    if (rate * 2 > tick_hz)
        return false;
    if (rate * 2 * a->pulse_ticks > tick_hz)
        return false;
    return true;
}

cs_err_t cs_planner_init(cs_planner_t *pl, const cs_machine_t *m)
{
    if (pl == NULL || m == NULL)
        return CS_ERR_ARG;
    if (m->n_axes < 3 || m->n_axes > CS_AXES)
        return CS_ERR_ARG;
    if (m->tick_hz < 1000u || m->tick_hz > 16000000u)
        return CS_ERR_RANGE;
    if (m->segment_ticks == 0 || m->segment_ticks > m->tick_hz)
        return CS_ERR_RANGE;
    if (m->tolerance <= 0 || m->junction_deviation < 0 || m->default_feed <= 0)
        return CS_ERR_RANGE;
    if (m->profile != CS_PROFILE_TRAPEZOID && m->profile != CS_PROFILE_SCURVE)
        return CS_ERR_ARG;
    if (m->profile == CS_PROFILE_SCURVE && m->max_jerk <= 0)
        return CS_ERR_RANGE;
    for (unsigned i = 0; i < m->n_axes; i++)
        if (!axis_cfg_ok(&m->axis[i], m->tick_hz))
            return CS_ERR_RANGE;
    pl->m = m;
    pl->head = 0;
    pl->count = 0;
    pl->busy = false;
    pl->start_v2 = 0;
    for (unsigned i = 0; i < CS_AXES; i++) {
        pl->pos[i] = 0;
        pl->steps[i] = 0;
    }
    return CS_OK;
}

/* round(pos * steps_per_mm): Q16 * Q16 = Q32, |product| < 2^28 * 2^28. */
static int32_t pos_to_steps(cs_pos_t pos, int32_t spm)
{
    return (int32_t)cs_fixed_round_shift64((int64_t)pos * spm, 32);
}

static bool inside_travel(const cs_machine_t *m, const cs_pos_t pos[CS_AXES])
{
    for (unsigned i = 0; i < m->n_axes; i++)
        if (pos[i] < m->axis[i].travel_min || pos[i] > m->axis[i].travel_max)
            return false;
    return true;
}

cs_err_t cs_planner_set_position(cs_planner_t *pl, const cs_pos_t pos[CS_AXES])
{
    if (pl->count != 0)
        return CS_ERR_STATE;
    if (!inside_travel(pl->m, pos))
        return CS_ERR_LIMIT;
    for (unsigned i = 0; i < CS_AXES; i++) {
        cs_pos_t p = i < pl->m->n_axes ? pos[i] : 0;
        pl->pos[i] = p;
        pl->steps[i] = i < pl->m->n_axes ? pos_to_steps(p, pl->m->axis[i].steps_per_mm) : 0;
    }
    pl->start_v2 = 0;
    return CS_OK;
}

bool cs_planner_full(const cs_planner_t *pl)
{
    return pl->count >= CS_PLANNER_RING;
}

unsigned cs_planner_count(const cs_planner_t *pl)
{
    return pl->count;
}

const cs_block_t *cs_planner_block(const cs_planner_t *pl, unsigned i)
{
    if (i >= pl->count)
        return NULL;
    return &pl->ring[ring_index(pl, i)];
}

/* Reverse pass (each block can stop, or reach the next block's entry, within its length) then
 * forward pass (each entry reachable from the previous block's entry). The first block's entry
 * is fixed: the executing block's frozen exit, or start_v2 when nothing executes. */
static void replan(cs_planner_t *pl)
{
    unsigned n = pl->count;
    unsigned first = pl->busy ? 1u : 0u;
    if (first >= n)
        return;
    /* Reverse pass. Only the last two blocks changed (the new one, and its predecessor's
     * acceleration); once an older block's reverse value comes out unchanged, every block before
     * it is unchanged too (its value depends on the next one only), and so are their forward
     * values: both passes resume from there (Grbl's "planned" pointer, found on the fly). */
    int64_t next = 0; /* exit of the last block: a full stop */
    unsigned from = first;
    for (unsigned k = n; k-- > first;) {
        cs_block_t *b = blk(pl, k);
        int64_t rev = min64(b->max_entry_v2, reach(pl->m, next, b));
        if (k + 2 < n && rev == b->rev_v2) {
            from = k + 1;
            break;
        }
        b->rev_v2 = rev;
        next = rev;
    }
    cs_block_t *prev;
    if (from == first) {
        prev = blk(pl, first);
        prev->entry_v2 = pl->busy ? blk(pl, 0)->exit_v2 : pl->start_v2;
        from = first + 1;
    } else {
        prev = blk(pl, from - 1);
    }
    for (unsigned k = from; k < n; k++) {
        cs_block_t *b = blk(pl, k);
        b->entry_v2 = min64(b->rev_v2, reach(pl->m, prev->entry_v2, prev));
        prev = b;
    }
}

/* |v| for a vector of CS_AXES int64 components each < 2^31 in magnitude. */
static int64_t len_n(const int64_t *v, unsigned n)
{
    uint64_t s = 0;
    for (unsigned i = 0; i < n; i++)
        s += (uint64_t)(v[i] * v[i]);
    return (int64_t)cs_fixed_isqrt64(s);
}

/* Lowers the block's tangential acceleration to num/den of limit (never raises it). */
static void cut_accel(cs_block_t *b, int64_t limit, int64_t num, int64_t den)
{
    int64_t cut = limit * num / den;
    if (cut < 1)
        cut = 1;
    if (cut < b->accel)
        b->accel = (int32_t)cut;
}

/* Caps v^2 so that no axis's velocity jumps by more than its acceleration times num/den
 * segment times: v |u2_i - u1_i| <= a_i T num / den. */
static int64_t jump_cap(const cs_machine_t *m, const int64_t *diff, int64_t v2, int64_t num,
                        int64_t den)
{
    for (unsigned i = 0; i < m->n_axes && v2 > 0; i++) {
        int64_t di = diff[i] < 0 ? -diff[i] : diff[i];
        if (di == 0)
            continue;
        int64_t dv = (int64_t)m->axis[i].max_accel * m->segment_ticks * num /
                     ((int64_t)m->tick_hz * den); /* Q16 mm/s */
        int64_t vmax;
        if (cs_fixed_muldiv64(dv, Q30_ONE, di, &vmax) != CS_OK || vmax > INT32_MAX)
            continue;
        v2 = min64(v2, vmax * vmax);
    }
    return v2;
}

/* Smallest max_accel of the axes a unit vector moves: an acceleration of that magnitude in any
 * direction of the plane of motion keeps every axis within its limit. */
static int64_t iso_accel(const cs_machine_t *m, const int32_t *u1, const int32_t *u2)
{
    int64_t a = INT32_MAX;
    for (unsigned i = 0; i < m->n_axes; i++)
        if ((u1[i] != 0 || (u2 != NULL && u2[i] != 0)) && m->axis[i].max_accel < a)
            a = m->axis[i].max_accel;
    return a;
}

/* Highest junction speed squared between blocks p and b (b follows p). A vertex of a flattened
 * curve gets the curvature rule; any other turn gets Grbl's junction deviation. Both cap each
 * axis's velocity jump and cut the two blocks' tangential acceleration so that the jump (and on
 * curves the normal acceleration) fits the axes' limits: the budget is in cs_planner.h and
 * docs/motion.md. */
static int64_t junction_v2(const cs_machine_t *m, cs_block_t *p, cs_block_t *b, bool p_frozen)
{
    unsigned n = m->n_axes;
    int64_t sum[CS_AXES], diff[CS_AXES];
    for (unsigned i = 0; i < n; i++) {
        sum[i] = (int64_t)p->unit[i] + b->unit[i];
        diff[i] = (int64_t)b->unit[i] - p->unit[i];
    }
    /* |u1 + u2| = 2 cos(phi/2) and |u1 - u2| = 2 sin(phi/2), phi = deflection angle (0 = straight):
     * Grbl's sin(theta/2) with theta the angle between the reversed incoming and the outgoing
     * direction is cos(phi/2). Q30. */
    int64_t s = len_n(sum, n) / 2;
    int64_t d = len_n(diff, n);
    if (d == 0 || s >= Q30_ONE)
        return V2_UNLIMITED; /* straight on: no junction limit, no acceleration cut */
    if (p_frozen)
        return 0; /* p cannot share its acceleration any more: stop */
    int32_t acc = p->accel_axes < b->accel_axes ? p->accel_axes : b->accel_axes;
    cs_pos_t lmin = p->length < b->length ? p->length : b->length;
    int64_t v2 = 0;
    if (d <= CS_PLANNER_CURVE_MAX_TURN &&
        (int64_t)lmin * d <= ((int64_t)CS_PLANNER_CURVE_SAGITTA * m->tolerance) << 30) {
        /* Curvature rule: a vertex of a flattened curve turns by phi ~ L / r; v^2 = 0.51 a r
         * with a the isotropic limit of the plane of motion, so that the normal (0.51 a) and
         * tangential (0.68 a) accelerations together use at most 0.85 of every axis's limit
         * (|0.68 u_i| + |0.51 n_i| <= 0.85 for orthonormal u, n); the vertex's velocity jump,
         * capped at 1.5 segment times of acceleration, takes the rest (cs_planner.h). */
        int64_t iso = iso_accel(m, p->unit, b->unit), ar;
        if (cs_fixed_muldiv64(iso * lmin, Q30_ONE, d, &ar) != CS_OK ||
            ar > V2_UNLIMITED / CS_PLANNER_CURVE_NUM)
            ar = V2_UNLIMITED / CS_PLANNER_CURVE_NUM;
        v2 = ar * CS_PLANNER_CURVE_NUM / CS_PLANNER_CURVE_DEN;
        v2 = jump_cap(m, diff, v2, CS_PLANNER_CURVE_JUMP_NUM, CS_PLANNER_CURVE_JUMP_DEN);
        if (v2 > 0) {
            cut_accel(p, iso_accel(m, p->unit, NULL), CS_PLANNER_CURVE_TANG_NUM,
                      CS_PLANNER_CURVE_TANG_DEN);
            cut_accel(b, iso_accel(m, b->unit, NULL), CS_PLANNER_CURVE_TANG_NUM,
                      CS_PLANNER_CURVE_TANG_DEN);
        }
    } else {
        /* Junction deviation: v^2 = a delta s / (1 - s) (Grbl), Q16 * Q16 = Q32. */
        int64_t ad = (int64_t)acc * m->junction_deviation;
        if (ad > 0 && s > 0 && cs_fixed_muldiv64(ad, s, Q30_ONE - s, &v2) != CS_OK)
            v2 = V2_UNLIMITED;
        v2 = jump_cap(m, diff, v2, 1, 1);
        if (v2 > 0) {
            /* The jump takes the spare fifth of the axes' acceleration. */
            cut_accel(p, p->accel_axes, CS_PLANNER_TANG_NUM, CS_PLANNER_TANG_DEN);
            cut_accel(b, b->accel_axes, CS_PLANNER_TANG_NUM, CS_PLANNER_TANG_DEN);
        }
    }
    return v2;
}

cs_err_t cs_planner_line(cs_planner_t *pl, const cs_pos_t target[CS_AXES], int32_t feed,
                         uint32_t line)
{
    const cs_machine_t *m = pl->m;
    unsigned n = m->n_axes;
    if (cs_planner_full(pl))
        return CS_ERR_FULL;
    if (!inside_travel(m, target))
        return CS_ERR_LIMIT;
    int32_t tsteps[CS_AXES] = {0, 0, 0, 0};
    int64_t geo[CS_AXES] = {0, 0, 0, 0};
    bool moves = false;
    for (unsigned i = 0; i < n; i++) {
        tsteps[i] = pos_to_steps(target[i], m->axis[i].steps_per_mm);
        geo[i] = (int64_t)target[i] - pl->pos[i];
        if (tsteps[i] != pl->steps[i])
            moves = true;
    }
    if (!moves)
        return CS_OK; /* under one step everywhere: carried into the next move */
    int64_t len = len_n(geo, n);
    if (len < 1)
        len = 1;
    if (len > INT32_MAX)
        return CS_ERR_RANGE;

    cs_block_t *b = &pl->ring[ring_index(pl, pl->count)];
    int64_t nominal = feed > 0 ? feed : INT32_MAX;
    int64_t accel = INT32_MAX;
    for (unsigned i = 0; i < CS_AXES; i++) {
        b->steps[i] = 0;
        b->unit[i] = 0;
        b->frac0[i] = 0;
        b->exact[i] = 0;
    }
    for (unsigned i = 0; i < n; i++) {
        const cs_axis_cfg_t *a = &m->axis[i];
        b->steps[i] = tsteps[i] - pl->steps[i];
        b->unit[i] = (int32_t)((geo[i] * Q30_ONE) / len);
        /* The chord in steps, exactly (Q16 mm * Q16 steps/mm = Q32, kept as Q16): the segment
         * generator rounds points of the chord itself, not of the line between rounded ends. */
        b->frac0[i] = (int32_t)(cs_fixed_round_shift64((int64_t)pl->pos[i] * a->steps_per_mm, 16) -
                                (int64_t)pl->steps[i] * 65536);
        b->exact[i] = cs_fixed_round_shift64(geo[i] * a->steps_per_mm, 16);
        if (b->steps[i] == 0)
            continue;
        /* The axis travels what its steps make: |steps| / steps_per_mm (Q16). Its rate is
         * v * that / len, so v <= max_rate * len / that (same for the acceleration). */
        int64_t exec_mm =
            ((int64_t)(b->steps[i] < 0 ? -b->steps[i] : b->steps[i]) << 32) / a->steps_per_mm;
        if (exec_mm < 1)
            exec_mm = 1;
        int64_t lim;
        if (cs_fixed_muldiv64(a->max_rate, len, exec_mm, &lim) == CS_OK)
            nominal = min64(nominal, lim);
        if (cs_fixed_muldiv64(a->max_accel, len, exec_mm, &lim) == CS_OK)
            accel = min64(accel, lim);
    }
    b->length = (cs_pos_t)len;
    b->nominal = (int32_t)(nominal < 1 ? 1 : nominal);
    b->accel = (int32_t)(accel < 1 ? 1 : accel);
    b->accel_axes = b->accel;
    b->line = line;
    b->exit_v2 = 0;
    int64_t nom2 = (int64_t)b->nominal * b->nominal;
    if (pl->count == 0) {
        b->max_entry_v2 = min64(pl->start_v2, nom2); /* from rest */
    } else {
        cs_block_t *p = blk(pl, pl->count - 1u);
        /* p's acceleration may be cut by the junction; not when p executes, nor when p is the
         * first block after it with an entry speed already fixed above rest (its deceleration
         * from that entry was planned with the full acceleration). Then the turn is from rest. */
        unsigned first = pl->busy ? 1u : 0u;
        int64_t fixed = pl->busy ? blk(pl, 0)->exit_v2 : pl->start_v2;
        bool p_frozen = (pl->busy && pl->count == 1) || (pl->count - 1u == first && fixed > 0);
        int64_t v2 = junction_v2(m, p, b, p_frozen);
        int64_t pnom2 = (int64_t)p->nominal * p->nominal;
        b->max_entry_v2 = min64(v2, min64(nom2, pnom2));
    }
    b->entry_v2 = 0;
    b->rev_v2 = -1; /* never equal to a computed value: the pass always visits it */
    for (unsigned i = 0; i < n; i++) {
        pl->pos[i] = target[i];
        pl->steps[i] = tsteps[i];
    }
    pl->count++;
    replan(pl);
    return CS_OK;
}

cs_err_t cs_planner_line3(cs_planner_t *pl, const cs_vec3_t *p, int32_t feed, uint32_t line)
{
    cs_pos_t t[CS_AXES] = {p->x, p->y, p->z, pl->pos[CS_AXIS_A]};
    return cs_planner_line(pl, t, feed, line);
}

const cs_block_t *cs_planner_begin_head(cs_planner_t *pl)
{
    if (pl->count == 0)
        return NULL;
    cs_block_t *b = blk(pl, 0);
    if (!pl->busy) {
        b->entry_v2 = pl->start_v2;
        b->exit_v2 = pl->count > 1 ? blk(pl, 1)->entry_v2 : 0;
        pl->busy = true;
    }
    return b;
}

void cs_planner_end_head(cs_planner_t *pl)
{
    if (pl->count == 0)
        return;
    pl->start_v2 = pl->busy ? blk(pl, 0)->exit_v2 : 0;
    pl->busy = false;
    pl->head = (uint16_t)((pl->head + 1u) & RING_MASK);
    pl->count--;
}
