/* cs_arclen: arc length by chord / control-polygon bracketing on dyadic pieces, and the s -> t
 * feed table. The pieces are visited depth first without recursion and without a stack of
 * curves: a piece is named by (depth d, index j) and its control points are recomputed from the
 * original segment by blossoming (cs_bezier_piece), which also keeps the rounding of every
 * piece independent of its depth (no error accumulates through repeated splitting) and makes
 * adjacent pieces share their end points exactly. */
#include "cs_arclen.h"

#include <stddef.h>

#define FRAC CS_ARCLEN_FRAC
#define UNIT ((uint64_t)1 << FRAC) /* one LSB in internal units */

CS_STATIC_ASSERT(FRAC <= CS_BEZIER_MAX_FRAC, frac_supported_by_blossom);
CS_STATIC_ASSERT(sizeof(cs_arclen_table_t) == (CS_ARCLEN_TABLE_N + 3) * sizeof(cs_pos_t),
                 table_is_35_words);
CS_STATIC_ASSERT((CS_PARAM_ONE / CS_ARCLEN_TABLE_N) % ((int32_t)1 << CS_ARCLEN_MAX_DEPTH) == 0,
                 table_intervals_split_exactly);

static uint64_t dist(const cs_vec3w_t *a, const cs_vec3w_t *b)
{
    return cs_fixed_vec_len64(b->x - a->x, b->y - a->y, b->z - a->z);
}

/* Rounding allowance of one piece in internal units: every control point is off by at most
 * e_p per coordinate (blossom rounding, 2^-(FRAC+1) LSB, plus the rational division error
 * 7 * 2^-31 / wmin LSB), each leg by 2 sqrt(3) e_p, each length floor by 1 unit or by
 * 3 * 2^-30 of itself (cs_fixed_vec_len64), so |estimate - length| exceeds polygon - chord by
 * at most (n + 1) (4 e_p + 1) + polygon / 2^28. */
static uint64_t noise(const cs_bezier_t *c, uint64_t poly)
{
    uint64_t ep = 1;
    if (c->rational) {
        cs_weight_t wmin = CS_WEIGHT_ONE;
        for (unsigned i = 0; i <= c->degree; i++)
            wmin = c->w[i] < wmin ? c->w[i] : wmin;
        ep += ((uint64_t)4 << FRAC) / (uint64_t)wmin; /* 3.5 * 2^-30 / w LSB, rounded up */
    }
    return ((uint64_t)c->degree + 1u) * (4u * ep + 1u) + (poly >> 28);
}

typedef struct {
    uint64_t chord, poly;
    cs_vec3w_t q[CS_BEZIER_MAX_POINTS];
} piece_t;

static cs_err_t piece(const cs_bezier_t *c, cs_param_t t0, cs_param_t t1, piece_t *p)
{
    cs_err_t e = cs_bezier_piece(c, t0, t1, FRAC, p->q);
    if (e != CS_OK)
        return e;
    unsigned n = c->degree;
    p->chord = dist(&p->q[0], &p->q[n]);
    p->poly = 0;
    for (unsigned i = 0; i < n; i++)
        p->poly += dist(&p->q[i], &p->q[i + 1]);
    return CS_OK;
}

/* tol_u * num / den, den > 0 and num <= den (a share of the tolerance) */
static uint64_t share(uint64_t tol_u, uint64_t num, uint64_t den)
{
    uint64_t hi, lo, q;
    cs_fixed_mul_u64(tol_u, num, &hi, &lo);
    if (cs_fixed_div_u128(hi, lo, den, &q) != CS_OK)
        return 0;
    return q;
}

/* Optional probe of a length traversal (feed table): pieces are split to at least min_depth,
 * and for each accepted piece [u0, u1] (offsets from t0) with partial lengths s0 <= s1 the
 * bound max(s1 - lin(u0), lin(u1) - s0) on |s(u) - lin(u)| inside it is collected, lin being
 * the straight line from 0 to total over the interval. s is monotone, so this bounds the
 * linear interpolation error of the whole interval. */
typedef struct {
    unsigned min_depth;
    uint64_t total; /* interval length from a previous identical traversal (units) */
    uint64_t worst; /* out: the bound (units) */
} probe_t;

/* Length of c between t0 < t1 (t1 - t0 divisible by 2^CS_ARCLEN_MAX_DEPTH), within tol_u
 * internal units; *len in internal units. pr may be NULL. */
static cs_err_t length_between(const cs_bezier_t *c, cs_param_t t0, cs_param_t t1, uint64_t tol_u,
                               uint64_t *len, probe_t *pr)
{
    piece_t p;
    cs_err_t e = piece(c, t0, t1, &p);
    if (e != CS_OK)
        return e;
    uint64_t proot = p.poly, sum = 0;
    unsigned n = c->degree, d = 0;
    uint32_t j = 0;
    cs_param_t span = t1 - t0;
    if (proot == 0) { /* every control point of the piece equal: a point */
        *len = 0;
        if (pr)
            pr->worst = 0;
        return CS_OK;
    }
    if (proot >= ((uint64_t)1 << 62))
        return CS_ERR_OVERFLOW;
    for (;;) {
        cs_param_t w = span >> d, a = t0 + w * (cs_param_t)j;
        if (d > 0 && (e = piece(c, a, a + w, &p)) != CS_OK)
            return e;
        /* Half of tol in proportion to the polygon length (the pieces' polygons sum to at most
         * the root's), half in proportion to the width in t. */
        uint64_t budget =
            share(tol_u / 2, p.poly < proot ? p.poly : proot, proot) + ((tol_u / 2) >> d);
        uint64_t gap = p.poly > p.chord ? p.poly - p.chord : 0;
        if (gap + noise(c, p.poly) <= budget && (!pr || d >= pr->min_depth)) {
            uint64_t est = (2u * p.chord + ((uint64_t)n - 1u) * p.poly) / ((uint64_t)n + 1u);
            if (pr) {
                uint64_t u0 = (uint64_t)(a - t0), u1 = u0 + (uint64_t)w;
                int64_t l0 = (int64_t)share(pr->total, u0, (uint64_t)span);
                int64_t l1 = (int64_t)share(pr->total, u1, (uint64_t)span);
                int64_t b0 = (int64_t)(sum + est) - l0, b1 = l1 - (int64_t)sum;
                int64_t b = b0 > b1 ? b0 : b1;
                if (b > 0 && (uint64_t)b > pr->worst)
                    pr->worst = (uint64_t)b;
            }
            sum += est;
            j++;
            while (d > 0 && (j & 1u) == 0) {
                j >>= 1;
                d--;
            }
            if (d == 0)
                break;
        } else {
            if (d == CS_ARCLEN_MAX_DEPTH)
                return CS_ERR_DEPTH;
            d++;
            j <<= 1;
        }
    }
    *len = sum;
    return CS_OK;
}

static cs_err_t check_tol(cs_pos_t tol, uint64_t *tol_u)
{
    if (tol < 1)
        return CS_ERR_TOLERANCE;
    /* keep half an LSB for the final rounding to cs_pos_t */
    *tol_u = (uint64_t)tol * UNIT - UNIT / 2;
    return CS_OK;
}

static cs_err_t to_pos(uint64_t units, cs_pos_t *out)
{
    uint64_t v = (units + UNIT / 2) >> FRAC;
    if (v > (uint64_t)INT32_MAX)
        return CS_ERR_OVERFLOW;
    *out = (cs_pos_t)v;
    return CS_OK;
}

cs_err_t cs_arclen_length(const cs_bezier_t *c, cs_pos_t tol, cs_pos_t *len)
{
    uint64_t tol_u, l;
    cs_err_t e = check_tol(tol, &tol_u);
    if (e != CS_OK)
        return e;
    if (c->degree < 1 || c->degree > CS_BEZIER_MAX_DEGREE)
        return CS_ERR_DEGREE;
    if ((e = length_between(c, 0, CS_PARAM_ONE, tol_u, &l, NULL)) != CS_OK)
        return e;
    return to_pos(l, len);
}

/* Bound (internal units) on |s(t) - linear interpolation| over one table interval of a
 * polynomial piece q (control points in units): the hodograph H_i = n (q_{i+1} - q_i) holds
 * ds/du for the piece parameter u in [0, 1] inside its convex hull, so
 * vmax <= max |H_i| and vmin >= |m| - max |H_i - m| (m = the mean of the H_i); with
 * f(u) = s(u) - linear(u), f(0) = f(1) = 0 and vmin - v <= f' <= vmax - v, |f| <= (vmax-vmin)/4.
 * The rounding of t adds at most vmax * N * 2^-31 (one half-ulp of t at speed vmax * N). */
static uint64_t interp_err(const cs_bezier_t *c, const piece_t *p)
{
    unsigned n = c->degree;
    int64_t h[CS_BEZIER_MAX_DEGREE][3], m[3] = {0, 0, 0};
    uint64_t vmax = 0, spread = 0;
    for (unsigned i = 0; i < n; i++) {
        h[i][0] = (int64_t)n * (p->q[i + 1].x - p->q[i].x);
        h[i][1] = (int64_t)n * (p->q[i + 1].y - p->q[i].y);
        h[i][2] = (int64_t)n * (p->q[i + 1].z - p->q[i].z);
        for (unsigned a = 0; a < 3; a++)
            m[a] += h[i][a];
        uint64_t v = cs_fixed_vec_len64(h[i][0], h[i][1], h[i][2]) + 1u;
        vmax = v > vmax ? v : vmax;
    }
    for (unsigned a = 0; a < 3; a++)
        m[a] /= (int64_t)n; /* truncation: |m - mean| < 1 unit per axis, covered below */
    for (unsigned i = 0; i < n; i++) {
        uint64_t v = cs_fixed_vec_len64(h[i][0] - m[0], h[i][1] - m[1], h[i][2] - m[2]) + 2u;
        spread = v > spread ? v : spread;
    }
    uint64_t lm = cs_fixed_vec_len64(m[0], m[1], m[2]);
    uint64_t vmin = lm > spread ? lm - spread : 0;
    /* the points themselves are off by < 1 unit: each H_i by < 2 n sqrt(3) units */
    uint64_t slack = 4u * (uint64_t)n + 1u;
    return (vmax - vmin) / 4u + slack + ((vmax * CS_ARCLEN_TABLE_N) >> 31) + 1u;
}

cs_err_t cs_arclen_table_build(cs_arclen_table_t *tab, const cs_bezier_t *c, cs_pos_t tol)
{
    uint64_t tol_u;
    cs_err_t e = check_tol(tol, &tol_u);
    if (e != CS_OK)
        return e;
    if (c->degree < 1 || c->degree > CS_BEZIER_MAX_DEGREE)
        return CS_ERR_DEGREE;
    const cs_param_t dt = CS_PARAM_ONE / CS_ARCLEN_TABLE_N;
    uint64_t acc = 0, worst = 0, each = tol_u / CS_ARCLEN_TABLE_N;
    cs_arclen_table_t *t = tab; /* filled in place (stack on AVR); unspecified on error */
    t->s[0] = 0;
    for (unsigned k = 0; k < CS_ARCLEN_TABLE_N; k++) {
        cs_param_t a = dt * (cs_param_t)k;
        uint64_t l, ie;
        probe_t pr = {CS_ARCLEN_TABLE_MIN_DEPTH, 0, 0};
        if ((e = length_between(c, a, a + dt, each, &l, &pr)) != CS_OK)
            return e;
        /* the same traversal again, now that the interval's length is known */
        pr.total = l;
        pr.worst = 0;
        if ((e = length_between(c, a, a + dt, each, &l, &pr)) != CS_OK)
            return e;
        /* leaf bound: + the partial sums' own tolerance + the rounding of t (lin moves by
         * l * N * 2^-31 per half-ulp of t) */
        uint64_t leaf = pr.worst + each + (l >> 26) + 1u;
        acc += l;
        if ((e = to_pos(acc, &t->s[k + 1])) != CS_OK)
            return e;
        ie = leaf < l + UNIT ? leaf : l + UNIT; /* s(t) and lin(t) both lie in [s_k, s_k+1] */
        if (!c->rational) {
            piece_t p;
            if ((e = piece(c, a, a + dt, &p)) != CS_OK)
                return e;
            uint64_t h = interp_err(c, &p);
            ie = h < ie ? h : ie;
        }
        worst = ie > worst ? ie : worst;
    }
    t->length = t->s[CS_ARCLEN_TABLE_N];
    /* total: interpolation + the lengths' tolerance + the rounding of each s[k] (1/2 LSB),
     * rounded up to whole LSB (to_pos rounds to nearest, hence the extra half) */
    return to_pos(worst + tol_u + UNIT + UNIT / 2, &t->err);
}

cs_err_t cs_arclen_lookup(const cs_arclen_table_t *tab, cs_pos_t s, cs_param_t *t)
{
    if (s < 0 || s > tab->length)
        return CS_ERR_RANGE;
    /* first k with s <= s[k+1] (s[] non-decreasing) */
    unsigned lo = 0, hi = CS_ARCLEN_TABLE_N - 1;
    while (lo < hi) {
        unsigned mid = (lo + hi) / 2;
        if (s <= tab->s[mid + 1])
            hi = mid;
        else
            lo = mid + 1;
    }
    const cs_param_t dt = CS_PARAM_ONE / CS_ARCLEN_TABLE_N;
    int64_t ds = (int64_t)tab->s[lo + 1] - tab->s[lo], off = (int64_t)s - tab->s[lo];
    int64_t frac = ds > 0 ? (off * dt + ds / 2) / ds : 0;
    *t = dt * (cs_param_t)lo + (cs_param_t)frac;
    return CS_OK;
}
