/* cs_fd: uniform forward differences, exact in int64 (see cs_fd.h and docs/fixed-point.md,
 * "Forward differences"). With step 2^-K and n*K fractional guard bits every initial difference
 * is an integer, so the recurrence adds integers exactly; the only rounding is the output. */
#include "cs_fd.h"

CS_STATIC_ASSERT(28 + CS_FD_GUARD_BITS <= 61, fd_accumulator_headroom);
CS_STATIC_ASSERT(CS_FD_MAX_SPLIT <= 31, fd_piece_index_fits);
/* Piece rounding: sqrt(3) (1/2 + CS_FD_MAX_SPLIT 2^-(guard+1)) < 1 LSB per vertex. */
CS_STATIC_ASSERT(CS_FD_MAX_SPLIT * 1000L < (1L << CS_FD_PIECE_GUARD) * 154L, fd_piece_guard_enough);

unsigned cs_fd_kmax(unsigned degree, unsigned bits, unsigned guard)
{
    unsigned k = degree && bits > guard ? (bits - guard) / degree : 0;
    return k > 30 ? 30 : k;
}

static uint64_t mag_ceil_shift(int64_t v, unsigned g)
{
    uint64_t m = v < 0 ? (uint64_t)0 - (uint64_t)v : (uint64_t)v;
    return g ? (m >> g) + ((m & (((uint64_t)1 << g) - 1u)) != 0 ? 1u : 0u) : m;
}

unsigned cs_fd_wang_k(const cs_fd_pt_t *p, unsigned degree, unsigned guard, cs_pos_t tol)
{
    if (degree < 2)
        return 0;
    uint64_t m2 = 0;
    for (unsigned i = 0; i + 2 <= degree; i++) {
        /* |second difference| <= 4 * 2^28 = 2^30 LSB per axis (rounded up to whole LSB):
         * squares sum below 2^62. */
        uint64_t ax = mag_ceil_shift(p[i].x - 2 * p[i + 1].x + p[i + 2].x, guard);
        uint64_t ay = mag_ceil_shift(p[i].y - 2 * p[i + 1].y + p[i + 2].y, guard);
        uint64_t az = mag_ceil_shift(p[i].z - 2 * p[i + 1].z + p[i + 2].z, guard);
        uint64_t q = ax * ax + ay * ay + az * az;
        if (q > m2)
            m2 = q;
    }
    if (m2 == 0)
        return 0;
    /* Need n(n-1) * M <= 8 * tol * 4^K, with M rounded up. Left side < 42 * 2^32. */
    uint64_t lhs = (uint64_t)degree * (degree - 1u) * ((uint64_t)cs_fixed_isqrt64(m2) + 1u);
    uint64_t rhs = (uint64_t)tol * 8u;
    unsigned k = 0;
    while (rhs < lhs) {
        rhs <<= 2;
        k++;
    }
    return k;
}

void cs_fd_piece(const cs_bezier_t *c, unsigned s, uint32_t j, unsigned guard, cs_fd_pt_t *out)
{
    unsigned n = c->degree;
    int64_t g = (int64_t)1 << guard;
    for (unsigned i = 0; i <= n; i++) {
        out[i].x = c->p[i].x * g;
        out[i].y = c->p[i].y * g;
        out[i].z = c->p[i].z * g;
    }
    for (unsigned level = s; level-- > 0;) {
        bool right = ((j >> level) & 1u) != 0;
        /* de Casteljau at 1/2 on values scaled by 2^n: every halving is exact, then one
         * rounding back to the guard bits. |values| <= 2^(28 + guard + n) < 2^44. */
        int64_t v[3][CS_BEZIER_MAX_POINTS], h[3][CS_BEZIER_MAX_POINTS];
        for (unsigned i = 0; i <= n; i++) {
            v[0][i] = out[i].x * ((int64_t)1 << n);
            v[1][i] = out[i].y * ((int64_t)1 << n);
            v[2][i] = out[i].z * ((int64_t)1 << n);
        }
        for (unsigned a = 0; a < 3; a++) {
            if (right)
                h[a][n] = v[a][n];
            else
                h[a][0] = v[a][0];
            for (unsigned k = 1; k <= n; k++) {
                for (unsigned i = 0; i + k <= n; i++)
                    v[a][i] = (v[a][i] + v[a][i + 1]) / 2; /* exact: both even at this level */
                if (right)
                    h[a][n - k] = v[a][n - k];
                else
                    h[a][k] = v[a][0];
            }
        }
        for (unsigned i = 0; i <= n; i++) {
            out[i].x = cs_fixed_round_shift64(h[0][i], n);
            out[i].y = cs_fixed_round_shift64(h[1][i], n);
            out[i].z = cs_fixed_round_shift64(h[2][i], n);
        }
    }
}

cs_err_t cs_fd_plan(const cs_bezier_t *c, cs_pos_t tol, unsigned bits, unsigned margin, unsigned *s,
                    cs_pos_t *tol_eff)
{
    cs_fd_pt_t p[CS_BEZIER_MAX_POINTS];
    cs_fd_piece(c, 0, 0, 0, p);
    for (unsigned split = 0; split <= CS_FD_MAX_SPLIT; split++) {
        /* Rounding budget: output <= sqrt(3)/2 LSB; split pieces add < 0.2 LSB (3 s sqrt(3)/2
         * 2^-(guard+1) for s <= 20), charged as one more LSB (fixed-point.md). */
        cs_pos_t slack = split ? 2 : 1;
        if (tol <= slack)
            return CS_ERR_TOLERANCE;
        cs_pos_t te = tol - slack;
        if ((te >> margin) < 1)
            return CS_ERR_TOLERANCE;
        unsigned k = cs_fd_wang_k(p, c->degree, 0, te >> margin);
        unsigned kmax = cs_fd_kmax(c->degree, bits, split ? CS_FD_PIECE_GUARD : 0);
        /* Halving a polynomial divides its second differences by 4: one level of K per split
         * level, one more kept as margin for the pieces' rounding. */
        if (k <= kmax + split - (split ? 1u : 0u)) {
            *s = split;
            *tol_eff = te;
            return CS_OK;
        }
    }
    return CS_ERR_TOLERANCE;
}

void cs_fd_init_diffs(const cs_fd_pt_t *p, unsigned degree, unsigned k,
                      int64_t d[3][CS_BEZIER_MAX_POINTS])
{
    unsigned n = degree;
    uint64_t steps = (uint64_t)1 << k;
    unsigned m = steps < n ? (unsigned)steps : n; /* points x(0) .. x(m delta) are needed */
    int64_t one = (int64_t)1 << k;
    for (unsigned a = 0; a < 3; a++) {
        int64_t x[CS_BEZIER_MAX_POINTS];
        for (unsigned i = 0; i <= m; i++) {
            /* x(i / 2^k) * 2^(n k) by integer de Casteljau: each level multiplies by 2^k
             * instead of dividing, so it is exact; values stay <= 2^(28 + guard + n k). */
            int64_t v[CS_BEZIER_MAX_POINTS];
            for (unsigned q = 0; q <= n; q++)
                v[q] = a == 0 ? p[q].x : a == 1 ? p[q].y : p[q].z;
            for (unsigned r = 1; r <= n; r++)
                for (unsigned q = 0; q + r <= n; q++)
                    v[q] = (one - (int64_t)i) * v[q] + (int64_t)i * v[q + 1];
            x[i] = v[0];
        }
        /* Difference table in place: afterwards x[j] = j-th forward difference at t = 0. */
        for (unsigned r = 1; r <= m; r++)
            for (unsigned i = m; i >= r; i--)
                x[i] -= x[i - 1];
        for (unsigned j = 0; j < CS_BEZIER_MAX_POINTS; j++)
            d[a][j] = j <= m ? x[j] : 0;
    }
}

static void start_piece(cs_fd_t *f)
{
    cs_fd_pt_t q[CS_BEZIER_MAX_POINTS];
    cs_fd_piece(&f->curve, f->split, f->piece, f->guard, q);
    unsigned k = cs_fd_wang_k(q, f->degree, f->guard, f->tol_eff);
    f->k = (uint8_t)k;
    f->step = 0;
    if (k <= cs_fd_kmax(f->degree, CS_FD_GUARD_BITS, f->guard))
        cs_fd_init_diffs(q, f->degree, k, f->d);
}

static bool piece_ok(const cs_fd_t *f)
{
    return f->k <= cs_fd_kmax(f->degree, CS_FD_GUARD_BITS, f->guard);
}

cs_err_t cs_fd_begin(cs_fd_t *f, const cs_bezier_t *c, cs_pos_t tol)
{
    f->done = true;
    if (c->degree < 1 || c->degree > CS_BEZIER_MAX_DEGREE)
        return CS_ERR_DEGREE;
    if (c->rational)
        return CS_ERR_UNSUPPORTED;
    for (unsigned i = 0; i <= c->degree; i++)
        if (!cs_fixed_vec_ok(&c->p[i]))
            return CS_ERR_RANGE;
    if (tol < 1 || tol > CS_POS_LIMIT)
        return CS_ERR_TOLERANCE;
    unsigned s;
    cs_err_t e = cs_fd_plan(c, tol, CS_FD_GUARD_BITS, 0, &s, &f->tol_eff);
    if (e != CS_OK)
        return e;
    f->degree = c->degree;
    f->split = (uint8_t)s;
    f->guard = (uint8_t)(s ? CS_FD_PIECE_GUARD : 0);
    f->piece = 0;
    f->curve = *c;
    start_piece(f);
    if (!piece_ok(f))
        return CS_ERR_TOLERANCE; /* rounding of a piece pushed K over: refuse, never wrap */
    f->done = false;
    return CS_OK;
}

cs_err_t cs_fd_next(cs_fd_t *f, cs_vec3_t *pt)
{
    if (f->done)
        return CS_END;
    uint64_t steps = (uint64_t)1 << f->k;
    if (f->step == steps) {
        /* Piece finished: the next one starts where it ended (its own P0 is not emitted). */
        f->piece++;
        start_piece(f);
        if (!piece_ok(f)) {
            f->done = true;
            return CS_ERR_TOLERANCE;
        }
        steps = (uint64_t)1 << f->k;
    }
    /* Differences of order j are needed only while step + 1 + j <= steps: stopping their
     * update there keeps every value a forward difference inside [0, 1] (bounded). */
    uint64_t left = steps - 1 - f->step;
    unsigned top = left < (uint64_t)f->degree - 1u ? (unsigned)left : f->degree - 1u;
    for (unsigned a = 0; a < 3; a++) {
        int64_t *d = f->d[a];
        d[0] += d[1];
        for (unsigned j = 1; j <= top; j++)
            d[j] += d[j + 1];
    }
    f->step++;
    unsigned sh = f->guard + (unsigned)f->degree * f->k;
    pt->x = (cs_pos_t)cs_fixed_round_shift64(f->d[0][0], sh);
    pt->y = (cs_pos_t)cs_fixed_round_shift64(f->d[1][0], sh);
    pt->z = (cs_pos_t)cs_fixed_round_shift64(f->d[2][0], sh);
    if (f->step == steps && f->piece + 1 == ((uint32_t)1 << f->split))
        f->done = true;
    return CS_OK;
}
