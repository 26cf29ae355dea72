/* cs_fd3: planar polynomial FD with an exact step count per piece (see cs_fd3.h; error bound in
 * docs/fixed-point.md, "Planar cubic FD"). */
#include "cs_fd3.h"

#include "cs_fd.h"

#define GUARD CS_FD_PIECE_GUARD /* fraction bits of the pieces' control points (cs_fd_piece) */
#define FRAC  CS_FD3_FRAC
/* Added to the positions: 2^31 rounds the high word to nearest, 2^62 keeps the value positive
 * (|x| < 2^60 units) so the vertex is a plain shift of a non-negative number. */
#define POS_BIAS (((uint64_t)1 << (FRAC - 1)) + ((uint64_t)1 << 62))
#define POS_UNBIAS ((int64_t)1 << (62 - FRAC))

CS_STATIC_ASSERT(CS_FD3_MAX_SPLIT <= CS_FD_MAX_SPLIT, fd3_split_within_fd);
CS_STATIC_ASSERT(CS_FD3_TRY_SPLIT <= CS_FD3_MAX_SPLIT, fd3_try_within_max);

bool cs_fd3_accepts(const cs_bezier_t *c)
{
    if (c->rational || c->degree < 1 || c->degree > 3)
        return false;
    for (unsigned i = 1; i <= c->degree; i++)
        if (c->p[i].z != c->p[0].z)
            return false;
    return true;
}

/* |v| in whole LSB rounded up, for v with GUARD fraction bits. */
static uint64_t ceil_lsb(int64_t v)
{
    uint64_t m = v < 0 ? (uint64_t)0 - (uint64_t)v : (uint64_t)v;
    return (m + ((uint64_t)1 << GUARD) - 1u) >> GUARD;
}

/* Steps for N^2 >= n(n-1) m / (8 tol) (m in LSB, rounded up): Wang's bound solved for N. */
static uint64_t wang_steps(uint64_t m, unsigned n, cs_pos_t tol)
{
    if (m == 0)
        return 1;
    uint64_t need = (uint64_t)n * (n - 1u) * m; /* < 2^35 */
    uint64_t den = 8u * (uint64_t)tol, q2 = (need + den - 1u) / den;
    uint64_t steps = cs_fixed_isqrt64(q2);
    return steps * steps < q2 ? steps + 1u : steps;
}

/* Total steps of the 2^s pieces of c, or UINT64_MAX when one needs more than CS_FD3_MAX_STEPS,
 * planned without splitting: a piece [a, b] of a cubic has second differences
 * (b - a)^2 L(a), (b - a)^2 L(b), L(t) = (1 - t) D0 + t D1 (D_i those of c; B'' is linear), and
 * of a quadratic (b - a)^2 D0; so its M is 4^-s max |L| at its ends, each a rational
 * ((2^s - j) D0 + j D1) / 2^s computed exactly and rounded up. The pieces traced later get
 * their own exact count from their rounded control points (start_piece), at most this one plus
 * the rounding (docs/fixed-point.md). */
static uint64_t plan_steps(const cs_bezier_t *c, unsigned s, cs_pos_t tol)
{
    unsigned n = c->degree;
    int64_t d[2][2] = {{0, 0}, {0, 0}};
    for (unsigned i = 0; i + 2 <= n; i++) {
        d[i][0] = (int64_t)c->p[i].x - 2 * (int64_t)c->p[i + 1].x + c->p[i + 2].x;
        d[i][1] = (int64_t)c->p[i].y - 2 * (int64_t)c->p[i + 1].y + c->p[i + 2].y;
    }
    if (n < 3) { /* constant second difference */
        d[1][0] = d[0][0];
        d[1][1] = d[0][1];
    }
    uint32_t pieces = (uint32_t)1 << s;
    uint64_t total = 0, prev = 0;
    for (uint32_t j = 0; j <= pieces; j++) {
        /* |L(j / 2^s)| 4^-s in LSB, rounded up: components (2^s - j) D0 + j D1 < 2^(30+s),
         * divided by 2^(3s) (2^s for L, 4^s for the piece) rounded up. */
        uint64_t m2 = 0;
        for (unsigned k = 0; k < 2; k++) {
            int64_t v = (int64_t)(pieces - j) * d[0][k] + (int64_t)j * d[1][k];
            uint64_t a = v < 0 ? (uint64_t)0 - (uint64_t)v : (uint64_t)v;
            a = (a + ((uint64_t)1 << (3 * s)) - 1u) >> (3 * s);
            m2 += a * a;
        }
        uint64_t m = m2 == 0 ? 0 : (uint64_t)cs_fixed_isqrt64(m2) + 1u;
        if (j > 0) {
            uint64_t steps = wang_steps(m > prev ? m : prev, n, tol);
            if (steps > CS_FD3_MAX_STEPS)
                return UINT64_MAX;
            total += steps;
        }
        prev = m;
    }
    return total;
}

/* Steps for one piece q (GUARD fraction bits): the least N with Wang's bound
 * n(n-1)/8 M / N^2 <= tol, M = max |q_i - 2 q_{i+1} + q_{i+2}| rounded up (seed 003). */
static uint64_t piece_steps(const cs_fd_pt_t *q, unsigned n, cs_pos_t tol)
{
    uint64_t m2 = 0;
    for (unsigned i = 0; i + 2 <= n; i++) {
        uint64_t ax = ceil_lsb(q[i].x - 2 * q[i + 1].x + q[i + 2].x); /* <= 2^30 */
        uint64_t ay = ceil_lsb(q[i].y - 2 * q[i + 1].y + q[i + 2].y);
        uint64_t sq = ax * ax + ay * ay;
        if (sq > m2)
            m2 = sq;
    }
    /* The plan allowed CS_FD3_MAX_STEPS from the exact ends; the rounded points (<= 6 * 2^-9
     * LSB off) can add one step, within the error bound's N <= CS_FD3_MAX_STEPS + 1. */
    return wang_steps(m2 == 0 ? 0 : (uint64_t)cs_fixed_isqrt64(m2) + 1u, n, tol);
}

/* round(num 2^(FRAC - GUARD) / den) (half away from zero) modulo 2^64, den <= 2^30,
 * |num| < 2^62: the quotient and the remainder's fraction by two 64-bit divisions
 * (remainder * 2^24 < 2^54). */
static uint64_t scaled_div(int64_t num, uint64_t den)
{
    uint64_t m = num < 0 ? (uint64_t)0 - (uint64_t)num : (uint64_t)num;
    uint64_t q = m / den, r = m - q * den;
    uint64_t v = (q << (FRAC - GUARD)) + ((r << (FRAC - GUARD)) + den / 2u) / den;
    return num < 0 ? (uint64_t)0 - v : v;
}

/* Initial differences of one axis of a piece: power basis b1 t + b2 t^2 + b3 t^3 (exact, GUARD
 * bits), step h = 1/N: d1 = (b1 N^2 + b2 N + b3) / N^3, d2 = (2 b2 N + 6 b3) / N^3,
 * d3 = 6 b3 / N^3, each rounded once to 2^-FRAC LSB. */
static void axis_diffs(const int64_t *q, unsigned n, uint64_t steps, uint64_t d[3])
{
    int64_t b1, b2 = 0, b3 = 0, N = (int64_t)steps;
    if (n == 1) {
        b1 = q[1] - q[0];
    } else if (n == 2) {
        b1 = 2 * (q[1] - q[0]);
        b2 = q[0] - 2 * q[1] + q[2];
    } else {
        b1 = 3 * (q[1] - q[0]);
        b2 = 3 * (q[0] - 2 * q[1] + q[2]);
        b3 = q[3] - q[0] + 3 * (q[1] - q[2]);
    }
    uint64_t n3 = steps * steps * steps;
    d[0] = scaled_div(b1 * N * N + b2 * N + b3, n3);
    d[1] = scaled_div(2 * b2 * N + 6 * b3, n3);
    d[2] = scaled_div(6 * b3, n3);
}

static void start_piece(cs_fd3_t *f)
{
    cs_fd_pt_t q[4];
    unsigned n = f->curve.degree;
    cs_fd_piece(&f->curve, f->split, f->piece, GUARD, q);
    uint64_t steps = piece_steps(q, n, f->tol_eff);
    int64_t qx[4], qy[4];
    uint64_t d[3];
    for (unsigned i = 0; i <= n; i++) {
        qx[i] = q[i].x;
        qy[i] = q[i].y;
    }
    axis_diffs(qx, n, steps, d);
    f->dx1 = d[0];
    f->dx2 = d[1];
    f->dx3 = d[2];
    axis_diffs(qy, n, steps, d);
    f->dy1 = d[0];
    f->dy2 = d[1];
    f->dy3 = d[2];
    f->x = (uint64_t)(q[0].x * ((int64_t)1 << (FRAC - GUARD))) + POS_BIAS;
    f->y = (uint64_t)(q[0].y * ((int64_t)1 << (FRAC - GUARD))) + POS_BIAS;
    f->left = (uint32_t)steps;
}

cs_err_t cs_fd3_begin(cs_fd3_t *f, const cs_bezier_t *c, cs_pos_t tol)
{
    f->done = true;
    if (!cs_fd3_accepts(c))
        return CS_ERR_UNSUPPORTED;
    if (tol <= CS_FD3_SLACK_LSB || tol > CS_POS_LIMIT)
        return CS_ERR_TOLERANCE;
    for (unsigned i = 0; i <= c->degree; i++)
        if (!cs_fixed_vec_ok(&c->p[i]))
            return CS_ERR_RANGE;
    cs_pos_t te = tol - CS_FD3_SLACK_LSB;
    /* The split level with the fewest chords among the first few; deeper only if needed. */
    uint64_t best = UINT64_MAX;
    unsigned split = 0;
    for (unsigned s = 0; s <= CS_FD3_MAX_SPLIT; s++) {
        if (s > CS_FD3_TRY_SPLIT && best != UINT64_MAX)
            break;
        uint64_t total = plan_steps(c, s, te);
        if (total < best) {
            best = total;
            split = s;
        }
    }
    if (best == UINT64_MAX)
        return CS_ERR_UNSUPPORTED;
    f->curve = *c;
    f->tol_eff = te;
    f->z = c->p[0].z;
    f->split = (uint8_t)split;
    f->piece = 0;
    start_piece(f);
    f->done = false;
    return CS_OK;
}

size_t cs_fd3_fill(cs_fd3_t *f, cs_vec3_t *out, size_t max)
{
    if (f->done || max == 0)
        return 0;
    /* Inside the piece: one pass per axis, so each recurrence (8 words) stays in registers on a
     * 32-bit core; the piece's last step by cs_fd3_next (next piece, or P_n). */
    uint32_t inner = f->left - 1u;
    size_t k = inner < max ? (size_t)inner : max;
    uint64_t v = f->x, d1 = f->dx1, d2 = f->dx2, d3 = f->dx3;
    for (size_t i = 0; i < k; i++) {
        v += d1;
        d1 += d2;
        d2 += d3;
        out[i].x = (cs_pos_t)((int64_t)(v >> FRAC) - POS_UNBIAS);
    }
    f->x = v;
    f->dx1 = d1;
    f->dx2 = d2;
    v = f->y, d1 = f->dy1, d2 = f->dy2, d3 = f->dy3;
    cs_pos_t z = f->z;
    for (size_t i = 0; i < k; i++) {
        v += d1;
        d1 += d2;
        d2 += d3;
        out[i].y = (cs_pos_t)((int64_t)(v >> FRAC) - POS_UNBIAS);
        out[i].z = z;
    }
    f->y = v;
    f->dy1 = d1;
    f->dy2 = d2;
    f->left -= (uint32_t)k;
    if (k < max && cs_fd3_next(f, &out[k]) == CS_OK)
        k++;
    return k;
}

cs_err_t cs_fd3_next(cs_fd3_t *f, cs_vec3_t *pt)
{
    if (f->done)
        return CS_END;
    f->x += f->dx1;
    f->dx1 += f->dx2;
    f->dx2 += f->dx3;
    f->y += f->dy1;
    f->dy1 += f->dy2;
    f->dy2 += f->dy3;
    pt->x = (cs_pos_t)((int64_t)(f->x >> FRAC) - POS_UNBIAS);
    pt->y = (cs_pos_t)((int64_t)(f->y >> FRAC) - POS_UNBIAS);
    pt->z = f->z;
    if (--f->left == 0) {
        if (++f->piece >> f->split) {
            *pt = f->curve.p[f->curve.degree]; /* P_n exactly */
            f->done = true;
        } else {
            start_piece(f);
        }
    }
    return CS_OK;
}
