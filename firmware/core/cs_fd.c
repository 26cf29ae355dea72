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

#if CS_FD_RATIONAL
/* --- rational curves: exact homogeneous differences in 128 bits ------------------------- */

/* round(x / w) for w > 0: both are normalised so w < 2^62 (relative error <= 2^-61, i.e. far
 * below 2^-30 LSB here), then 31 restoring-division steps (|x / w| < 2^31 LSB). */
static cs_err_t rat_project(cs_i128_t x, cs_i128_t w, cs_pos_t *out)
{
    bool neg = cs_fixed_i128_is_neg(x);
    cs_i128_t m = neg ? cs_fixed_i128_neg(x) : x;
    unsigned bl = w.hi ? 64 + cs_fixed_bitlen64(w.hi) : cs_fixed_bitlen64(w.lo);
    if (bl > 62) {
        m = cs_fixed_u128_shr(m, bl - 62);
        w = cs_fixed_u128_shr(w, bl - 62);
    }
    uint64_t wd = w.lo;
    if (wd == 0)
        return CS_ERR_OVERFLOW;
    uint64_t q = 0;
    for (unsigned b = 31; b-- > 0;) {
        cs_i128_t t;
        t.lo = wd << b;
        t.hi = b ? wd >> (64 - b) : 0u;
        if (m.hi > t.hi || (m.hi == t.hi && m.lo >= t.lo)) {
            m = cs_fixed_i128_sub(m, t);
            q |= (uint64_t)1 << b;
        }
    }
    if (m.hi != 0 || m.lo >= wd)
        return CS_ERR_OVERFLOW; /* remainder still >= w: |x / w| >= 2^31, not a cs_pos_t */
    if ((m.lo << 1) >= wd)
        q++;
    return cs_fixed_narrow(neg ? -(int64_t)q : (int64_t)q, out);
}

static uint64_t sat_mul(uint64_t a, uint64_t b)
{
    uint64_t h, l;
    cs_fixed_mul_u64(a, b, &h, &l);
    return h ? UINT64_MAX : l;
}

static uint64_t sat_add(uint64_t a, uint64_t b)
{
    uint64_t r = a + b;
    return r < a ? UINT64_MAX : r;
}

/* Upper bound of |(x, y, z)| >> 31 (components |.| <= 2^61). */
static uint64_t norm_up_shr31(int64_t x, int64_t y, int64_t z)
{
    uint64_t a = mag_ceil_shift(x, 31), b = mag_ceil_shift(y, 31), c = mag_ceil_shift(z, 31);
    return (uint64_t)cs_fixed_isqrt64(a * a + b * b + c * c) + 1u;
}

unsigned cs_fd_rational_k(const cs_bezier_t *c, cs_pos_t tol)
{
    unsigned n = c->degree;
    /* R = C + Y / W with C = P0, Y_i = w_i (P_i - P0) (units LSB x Q30, |.| <= 2^59), W >= wmin.
     * R' = (Y' - (R - C) W') / W and R'' = (Y'' - 2 R' W' - (R - C) W'') / W, with hodograph
     * bounds |Y'| <= n max|dY|, |Y''| <= n(n-1) max|d2Y| (same for W), |R - C| <= rho. */
    int64_t y[CS_BEZIER_MAX_POINTS][3];
    uint64_t rho = 0, wmin = UINT64_MAX, b = 0, a = 0, om1 = 0, om2 = 0;
    for (unsigned i = 0; i <= n; i++) {
        int64_t dx = (int64_t)c->p[i].x - c->p[0].x, dy = (int64_t)c->p[i].y - c->p[0].y,
                dz = (int64_t)c->p[i].z - c->p[0].z;
        uint64_t r2 = (uint64_t)(dx * dx) + (uint64_t)(dy * dy) + (uint64_t)(dz * dz);
        uint64_t r = (uint64_t)cs_fixed_isqrt64(r2) + 1u;
        rho = r > rho ? r : rho;
        uint64_t w = (uint64_t)c->w[i];
        wmin = w < wmin ? w : wmin;
        y[i][0] = dx * c->w[i];
        y[i][1] = dy * c->w[i];
        y[i][2] = dz * c->w[i];
    }
    for (unsigned i = 0; i < n; i++) {
        uint64_t v = 2u * norm_up_shr31(y[i + 1][0] - y[i][0], y[i + 1][1] - y[i][1],
                                        y[i + 1][2] - y[i][2]); /* LSB */
        b = v > b ? v : b;
        int64_t dw = (int64_t)c->w[i + 1] - c->w[i];
        uint64_t adw = (uint64_t)(dw < 0 ? -dw : dw);
        om1 = adw > om1 ? adw : om1;
    }
    for (unsigned i = 0; i + 2 <= n; i++) {
        uint64_t v = 2u * norm_up_shr31(y[i][0] - 2 * y[i + 1][0] + y[i + 2][0],
                                        y[i][1] - 2 * y[i + 1][1] + y[i + 2][1],
                                        y[i][2] - 2 * y[i + 1][2] + y[i + 2][2]);
        a = v > a ? v : a;
        int64_t d2w = (int64_t)c->w[i] - 2 * (int64_t)c->w[i + 1] + c->w[i + 2];
        uint64_t ad2w = (uint64_t)(d2w < 0 ? -d2w : d2w);
        om2 = ad2w > om2 ? ad2w : om2;
    }
    /* 1/W <= 2^(30-e) with 2^e <= wmin (weights in Q30). */
    unsigned e = cs_fixed_bitlen64(wmin) - 1u, f = CS_WEIGHT_FRAC_BITS - e;
    uint64_t r1 = sat_add(sat_mul(sat_mul(n, b), (uint64_t)1 << f),
                          (sat_mul(sat_mul(rho, n), om1) >> e) + 1u);
    uint64_t t = sat_add(sat_mul(sat_mul(2u * n, r1), om1),
                         sat_mul(sat_mul(rho, (uint64_t)n * (n - 1u)), om2));
    uint64_t r2 = sat_add(sat_mul(sat_mul((uint64_t)n * (n - 1u), a), (uint64_t)1 << f),
                          (t == UINT64_MAX ? t : t >> e) + 1u);
    /* Chords over steps h = 2^-K deviate at most h^2 / 8 max|R''|. */
    uint64_t rhs = (uint64_t)tol * 8u;
    unsigned k = 0;
    while (rhs < r2) {
        if (rhs > (UINT64_MAX >> 2) || k >= 60)
            return 255;
        rhs <<= 2;
        k++;
    }
    return k;
}

/* Exact homogeneous differences (x, y, z = w P in LSB x Q30; w in Q30) at step 2^-k, x 2^(n k). */
static void rat_init_diffs(const cs_bezier_t *c, unsigned k,
                           cs_i128_t d[4][CS_BEZIER_MAX_POINTS])
{
    unsigned n = c->degree;
    uint64_t steps = (uint64_t)1 << k;
    unsigned m = steps < n ? (unsigned)steps : n;
    for (unsigned a = 0; a < 4; a++) {
        cs_i128_t x[CS_BEZIER_MAX_POINTS];
        for (unsigned i = 0; i <= m; i++) {
            cs_i128_t v[CS_BEZIER_MAX_POINTS];
            for (unsigned q = 0; q <= n; q++) {
                int64_t w = c->w[q];
                v[q] = cs_fixed_i128_from64(a == 0   ? w * c->p[q].x
                                   : a == 1 ? w * c->p[q].y
                                   : a == 2 ? w * c->p[q].z
                                            : w);
            }
            for (unsigned r = 1; r <= n; r++)
                for (unsigned q = 0; q + r <= n; q++)
                    v[q] = cs_fixed_i128_add(cs_fixed_i128_mul_u64(v[q], steps - i), cs_fixed_i128_mul_u64(v[q + 1], i));
            x[i] = v[0];
        }
        for (unsigned r = 1; r <= m; r++)
            for (unsigned i = m; i >= r; i--)
                x[i] = cs_fixed_i128_sub(x[i], x[i - 1]);
        for (unsigned j = 0; j < CS_BEZIER_MAX_POINTS; j++)
            d[a][j] = j <= m ? x[j] : cs_fixed_i128_from64(0);
    }
}
#endif /* CS_FD_RATIONAL */

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
    cs_err_t ce = cs_bezier_check(c);
    if (ce != CS_OK)
        return ce;
    if (tol < 1 || tol > CS_POS_LIMIT)
        return CS_ERR_TOLERANCE;
    f->rational = c->rational;
#if !CS_FD_RATIONAL
    if (c->rational)
        return CS_ERR_UNSUPPORTED;
#else
    if (c->rational) {
        /* Output rounding (<= sqrt(3)/2 LSB, the normalised division adds < 2^-30) charged as
         * 1 LSB; no pre-split: a curve needing more than 2^(60/n) steps is handed back. */
        if (tol < 2)
            return CS_ERR_TOLERANCE;
        unsigned k = cs_fd_rational_k(c, tol - 1);
        unsigned kmax = cs_fd_kmax(c->degree, CS_FD_RAT_GUARD_BITS, 0);
        if (k > kmax)
            return CS_ERR_UNSUPPORTED;
        f->degree = c->degree;
        f->k = (uint8_t)k;
        f->split = 0;
        f->guard = 0;
        f->piece = 0;
        f->step = 0;
        f->tol_eff = tol - 1;
        f->curve = *c;
        rat_init_diffs(c, k, f->rd);
        f->done = false;
        return CS_OK;
    }
#endif
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
#if CS_FD_RATIONAL
    if (f->rational) {
        for (unsigned a = 0; a < 4; a++) {
            cs_i128_t *d = f->rd[a];
            d[0] = cs_fixed_i128_add(d[0], d[1]);
            for (unsigned j = 1; j <= top; j++)
                d[j] = cs_fixed_i128_add(d[j], d[j + 1]);
        }
        f->step++;
        cs_err_t e = rat_project(f->rd[0][0], f->rd[3][0], &pt->x);
        if (e == CS_OK)
            e = rat_project(f->rd[1][0], f->rd[3][0], &pt->y);
        if (e == CS_OK)
            e = rat_project(f->rd[2][0], f->rd[3][0], &pt->z);
        if (e != CS_OK || f->step == steps)
            f->done = true;
        return e;
    }
#endif
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
