/* cs_subdiv: flatness subdivision in homogeneous space (see cs_subdiv.h and docs/fixed-point.md,
 * "Forward differences" -> "Flatness test"). No recursion: the dyadic tracer keeps the right
 * halves on an explicit stack of CS_SUBDIV_MAX_DEPTH entries; the reach tracer keeps only the
 * remaining curve. */
#include "cs_subdiv.h"

#include <stddef.h>

#define W_ONE   ((int64_t)1 << 61) /* homogeneous weight 1.0 (Q61) */
#define X_SHIFT 30                 /* x = w * p * 2^30: 30 bits below the LSB */
#define T_HALF  (CS_PARAM_ONE / 2)

CS_STATIC_ASSERT(CS_SUBDIV_MAX_DEPTH >= 1 && CS_SUBDIV_MAX_DEPTH <= 60, subdiv_depth_sane);
CS_STATIC_ASSERT(sizeof(cs_subdiv_hcurve_t) == 32 * CS_BEZIER_MAX_POINTS, hcurve_size);
/* thr <= 2 * CS_SUBDIV_TOL_MAX keeps thr^2 < 2^62 (see cs_subdiv_dist_ok). */
CS_STATIC_ASSERT(CS_SUBDIV_TOL_MAX <= ((int32_t)1 << 29), tol_max_fits_thr_squared);

void cs_subdiv_to_homogeneous(const cs_bezier_t *c, cs_subdiv_hcurve_t *h)
{
    for (unsigned i = 0; i <= c->degree; i++) {
        /* Products of a Q1.30 weight and a 29-bit coordinate: exact in int64 (|.| <= 2^58). */
        int64_t w = c->rational ? (int64_t)c->w[i] : (int64_t)CS_WEIGHT_ONE;
        h->p[i].x = w * c->p[i].x;
        h->p[i].y = w * c->p[i].y;
        h->p[i].z = w * c->p[i].z;
        h->p[i].w = w * ((int64_t)1 << (61 - CS_WEIGHT_FRAC_BITS));
    }
}

/* a + round((b - a) * t / 2^30), t in [0, 2^30]. |b - a| < 2^63 for every caller (x: 2^59,
 * w: 2^61), and the result lies between a and b. */
static int64_t lerp(int64_t a, int64_t b, cs_param_t t)
{
    if (t == T_HALF)
        return cs_fixed_round_shift64(a + b, 1);
    int64_t d = b - a;
    uint64_t m = d < 0 ? (uint64_t)0 - (uint64_t)d : (uint64_t)d;
    uint64_t hi, lo;
    cs_fixed_mul_u64(m, (uint64_t)t, &hi, &lo);
    uint64_t q = (hi << (64 - CS_PARAM_FRAC_BITS)) | (lo >> CS_PARAM_FRAC_BITS);
    q += (lo >> (CS_PARAM_FRAC_BITS - 1)) & 1u;
    return d < 0 ? a - (int64_t)q : a + (int64_t)q;
}

static cs_subdiv_hpt_t hlerp(const cs_subdiv_hpt_t *a, const cs_subdiv_hpt_t *b, cs_param_t t)
{
    cs_subdiv_hpt_t r;
    r.x = lerp(a->x, b->x, t);
    r.y = lerp(a->y, b->y, t);
    r.z = lerp(a->z, b->z, t);
    r.w = a->w == b->w ? a->w : lerp(a->w, b->w, t);
    return r;
}

void cs_subdiv_split(const cs_subdiv_hcurve_t *h, unsigned n, cs_param_t t,
                     cs_subdiv_hcurve_t *left, cs_subdiv_hcurve_t *right)
{
    cs_subdiv_hpt_t tmp[CS_BEZIER_MAX_POINTS], l[CS_BEZIER_MAX_POINTS], r[CS_BEZIER_MAX_POINTS];
    for (unsigned i = 0; i <= n; i++)
        tmp[i] = h->p[i];
    l[0] = tmp[0];
    r[n] = tmp[n];
    for (unsigned k = 1; k <= n; k++) {
        for (unsigned i = 0; i + k <= n; i++)
            tmp[i] = hlerp(&tmp[i], &tmp[i + 1], t);
        l[k] = tmp[0];
        r[n - k] = tmp[n - k];
    }
    for (unsigned i = 0; i <= n; i++) {
        if (left)
            left->p[i] = l[i];
        if (right)
            right->p[i] = r[i];
    }
}

/* round(x * 2^31 / w) for 0 < w <= 2^62, by restoring division (no hardware divide). */
static cs_err_t proj_coord(int64_t x, int64_t w, cs_pos_t *out)
{
    uint64_t m = x < 0 ? (uint64_t)0 - (uint64_t)x : (uint64_t)x;
    uint64_t uw = (uint64_t)w;
    if (w <= 0 || m >= uw) /* |p| >= 2^31 LSB: cannot come from valid control points */
        return CS_ERR_OVERFLOW;
    uint64_t q = 0, r = m;
    for (unsigned i = 0; i < 31; i++) {
        r <<= 1;
        q <<= 1;
        if (r >= uw) {
            r -= uw;
            q |= 1u;
        }
    }
    if ((r << 1) >= uw)
        q++;
    return cs_fixed_narrow(x < 0 ? -(int64_t)q : (int64_t)q, out);
}

cs_err_t cs_subdiv_project(const cs_subdiv_hpt_t *h, bool rational, cs_vec3_t *out)
{
    if (!rational) {
        cs_err_t e = cs_fixed_narrow(cs_fixed_round_shift64(h->x, X_SHIFT), &out->x);
        if (e == CS_OK)
            e = cs_fixed_narrow(cs_fixed_round_shift64(h->y, X_SHIFT), &out->y);
        if (e == CS_OK)
            e = cs_fixed_narrow(cs_fixed_round_shift64(h->z, X_SHIFT), &out->z);
        return e;
    }
    cs_err_t e = proj_coord(h->x, h->w, &out->x);
    if (e == CS_OK)
        e = proj_coord(h->y, h->w, &out->y);
    if (e == CS_OK)
        e = proj_coord(h->z, h->w, &out->z);
    return e;
}

static uint64_t sq_mag(int64_t v)
{
    uint64_t m = v < 0 ? (uint64_t)0 - (uint64_t)v : (uint64_t)v;
    return m * m; /* callers keep |v| < 2^31 */
}

/* dist(P, segment AB) <= thr, exactly. Coordinates are projected control points (|.| <= 2^28
 * plus rounding), so differences are < 2^30 and cross-product components < 2^60. */
bool cs_subdiv_dist_ok(const cs_vec3_t *p, const cs_vec3_t *a, const cs_vec3_t *b, uint32_t thr)
{
    int64_t dx = (int64_t)b->x - a->x, dy = (int64_t)b->y - a->y, dz = (int64_t)b->z - a->z;
    int64_t vx = (int64_t)p->x - a->x, vy = (int64_t)p->y - a->y, vz = (int64_t)p->z - a->z;
    uint64_t t2 = (uint64_t)thr * thr;
    int64_t dot = vx * dx + vy * dy + vz * dz;
    int64_t dd = dx * dx + dy * dy + dz * dz;
    if (dd == 0 || dot <= 0) /* nearest point is A (also the zero-length chord: loops, cusps) */
        return sq_mag(vx) + sq_mag(vy) + sq_mag(vz) <= t2;
    if (dot >= dd) { /* nearest point is B */
        int64_t wx = (int64_t)p->x - b->x, wy = (int64_t)p->y - b->y, wz = (int64_t)p->z - b->z;
        return sq_mag(wx) + sq_mag(wy) + sq_mag(wz) <= t2;
    }
    /* Inside: |d x v|^2 <= thr^2 |d|^2, both sides exact in 128 bits. */
    int64_t cx = vy * dz - vz * dy, cy = vz * dx - vx * dz, cz = vx * dy - vy * dx;
    uint64_t hi = 0, lo = 0;
    const int64_t cc[3] = {cx, cy, cz};
    for (unsigned k = 0; k < 3; k++) {
        uint64_t m = cc[k] < 0 ? (uint64_t)0 - (uint64_t)cc[k] : (uint64_t)cc[k];
        uint64_t h1, l1;
        cs_fixed_mul_u64(m, m, &h1, &l1);
        lo += l1;
        hi += h1 + (lo < l1 ? 1u : 0u);
    }
    uint64_t rh, rl;
    cs_fixed_mul_u64(t2, (uint64_t)dd, &rh, &rl);
    return hi < rh || (hi == rh && lo <= rl);
}

/* The proven flatness test: every interior projected control point within thr of the chord
 * between the projected end points (dist(B(t), S) <= sum B_i(t) dist(P_i, S), S convex). */
static cs_err_t is_flat(const cs_subdiv_hcurve_t *h, unsigned n, bool rational, uint32_t thr,
                        bool *flat)
{
    cs_vec3_t p[CS_BEZIER_MAX_POINTS];
    for (unsigned i = 0; i <= n; i++) {
        cs_err_t e = cs_subdiv_project(&h->p[i], rational, &p[i]);
        if (e != CS_OK)
            return e;
    }
    *flat = true;
    for (unsigned i = 1; i < n && *flat; i++)
        *flat = cs_subdiv_dist_ok(&p[i], &p[0], &p[n], thr);
    return CS_OK;
}

/* Distance limit for interior control points: (tol - slack) / c_n with c_n = 1 - 2^(1-n) for
 * polynomial curves (Bernstein interior weights sum to <= c_n) and 1 for rational ones. */
static uint32_t threshold(cs_pos_t tol, unsigned n, bool rational)
{
    uint32_t base = (uint32_t)(tol - CS_SUBDIV_SLACK_LSB);
    if (rational || n < 2)
        return base;
    uint32_t m = ((uint32_t)1 << (n - 1)) - 1u; /* base * 2^(n-1) / (2^(n-1) - 1), floored */
    return base + base / m;
}

cs_err_t cs_subdiv_reach_begin(cs_subdiv_reach_t *s, const cs_bezier_t *c, cs_pos_t tol)
{
    s->done = true;
    if (tol < CS_SUBDIV_TOL_MIN || tol > CS_SUBDIV_TOL_MAX)
        return CS_ERR_TOLERANCE;
    cs_err_t e = cs_bezier_check(c);
    if (e != CS_OK)
        return e;
    s->degree = c->degree;
    s->rational = c->rational;
    s->reach = true;
    s->sp = 0;
    s->cur_depth = 0;
    s->thr = threshold(tol, c->degree, c->rational);
    s->reach_prev = T_HALF;
    s->end = c->p[c->degree];
    cs_subdiv_to_homogeneous(c, &s->cur);
    s->done = false;
    return CS_OK;
}

cs_err_t cs_subdiv_begin(cs_subdiv_t *s, const cs_bezier_t *c, cs_pos_t tol, bool reach)
{
    cs_err_t e = cs_subdiv_reach_begin(&s->b, c, tol);
    s->b.reach = reach;
    return e;
}

static cs_err_t finish(cs_subdiv_reach_t *s, cs_err_t e)
{
    s->done = true;
    return e;
}

static cs_err_t dyadic_next(cs_subdiv_t *s, cs_vec3_t *pt)
{
    unsigned n = s->b.degree;
    for (;;) {
        bool flat;
        cs_err_t e = is_flat(&s->b.cur, n, s->b.rational, s->b.thr, &flat);
        if (e != CS_OK)
            return finish(&s->b, e);
        if (flat)
            break;
        if (s->b.cur_depth >= CS_SUBDIV_MAX_DEPTH)
            return finish(&s->b, CS_ERR_DEPTH);
        /* Push the right half, continue with the left one (depth-first, in curve order). */
        cs_subdiv_split(&s->b.cur, n, T_HALF, &s->b.cur, &s->stack[s->b.sp]);
        s->b.cur_depth++;
        s->depth[s->b.sp] = s->b.cur_depth;
        s->b.sp++;
    }
    if (s->b.sp == 0) {
        *pt = s->b.end;
        s->b.done = true;
        return CS_OK;
    }
    cs_err_t e = cs_subdiv_project(&s->b.cur.p[n], s->b.rational, pt);
    if (e != CS_OK)
        return finish(&s->b, e);
    s->b.sp--;
    s->b.cur = s->stack[s->b.sp];
    s->b.cur_depth = s->depth[s->b.sp];
    return CS_OK;
}

static cs_err_t reach_test(const cs_subdiv_reach_t *s, cs_param_t t, bool *flat)
{
    cs_subdiv_hcurve_t left;
    cs_subdiv_split(&s->cur, s->degree, t, &left, NULL);
    return is_flat(&left, s->degree, s->rational, s->thr, flat);
}

cs_err_t cs_subdiv_reach_next(cs_subdiv_reach_t *s, cs_vec3_t *pt)
{
    if (s->done)
        return CS_END;
    bool flat;
    cs_err_t e = is_flat(&s->cur, s->degree, s->rational, s->thr, &flat);
    if (e != CS_OK)
        return finish(s, e);
    if (flat) {
        *pt = s->end;
        s->done = true;
        return CS_OK;
    }
    /* Bracket the farthest flat parameter of the remaining curve: lo flat, hi not flat, starting
     * from the previous chord's share (neighbouring chords are about the same length). */
    cs_param_t lo = 0, hi = CS_PARAM_ONE, t = s->reach_prev;
    if ((e = reach_test(s, t, &flat)) != CS_OK)
        return finish(s, e);
    if (flat) {
        lo = t;
        while (lo < T_HALF) {
            cs_param_t cand = lo * 2;
            if ((e = reach_test(s, cand, &flat)) != CS_OK)
                return finish(s, e);
            if (!flat) {
                hi = cand;
                break;
            }
            lo = cand;
        }
    } else {
        hi = t;
        for (;;) {
            t >>= 1;
            if (t == 0)
                return finish(s, CS_ERR_DEPTH);
            if ((e = reach_test(s, t, &flat)) != CS_OK)
                return finish(s, e);
            if (flat) {
                lo = t;
                break;
            }
            hi = t;
        }
    }
    for (unsigned k = 0; k < CS_SUBDIV_REACH_STEPS && hi - lo > 1; k++) {
        cs_param_t mid = lo + (hi - lo) / 2;
        if ((e = reach_test(s, mid, &flat)) != CS_OK)
            return finish(s, e);
        if (flat)
            lo = mid;
        else
            hi = mid;
    }
    cs_subdiv_hcurve_t left;
    cs_subdiv_split(&s->cur, s->degree, lo, &left, &s->cur);
    if ((e = cs_subdiv_project(&left.p[s->degree], s->rational, pt)) != CS_OK)
        return finish(s, e);
    s->reach_prev = lo;
    return CS_OK;
}

cs_err_t cs_subdiv_next(cs_subdiv_t *s, cs_vec3_t *pt)
{
    if (s->b.done)
        return CS_END;
    return s->b.reach ? cs_subdiv_reach_next(&s->b, pt) : dyadic_next(s, pt);
}

bool cs_subdiv_is_flat(const cs_bezier_t *c, cs_pos_t tol)
{
    if (tol < CS_SUBDIV_TOL_MIN || tol > CS_SUBDIV_TOL_MAX || cs_bezier_check(c) != CS_OK)
        return false;
    cs_subdiv_hcurve_t h;
    cs_subdiv_to_homogeneous(c, &h);
    bool flat = false;
    if (is_flat(&h, c->degree, c->rational, threshold(tol, c->degree, c->rational), &flat) != CS_OK)
        return false;
    return flat;
}
