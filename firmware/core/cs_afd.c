/* cs_afd: adaptive forward differences (see cs_afd.h and docs/fixed-point.md). The state is the
 * position and the forward differences D^j at the current step h, all exact integers
 * x 2^(guard + n*lmax).
 * Halving and doubling are exact changes of basis: with E = 1 + D the shift by h, the shift by 2h
 * is E^2, so the doubled difference operator is D2 = 2D + D^2 and
 *   D2^m = D^m (2 + D)^m = sum_i C(m,i) 2^(m-i) D^(m+i)          (doubling, integer weights)
 * and halving solves the same triangular system for the half-step differences:
 *   D^m = sum_i C(m,i) 2^(m-i) Dh^(m+i)  =>  Dh^m = (D^m - sum_{i>=1} ...) / 2^m   (exact). */
#include "cs_afd.h"
#include "cs_fd.h"

#define AFD_LIM ((int64_t)1 << 62)

CS_STATIC_ASSERT(28 + CS_AFD_GUARD_BITS + 4 <= 62, afd_headroom);


/* b_j = max over u in [0,1] of |d^2/du^2 C(u, j)| (Newton basis), rounded up, in 1/64:
 * 1, 1, 11/12, 5/6, 137/180, 7/10 (all at u = 0) -> 64, 64, 59, 54, 49, 45, plus 1 of margin. */
static const uint8_t newton_b64[8] = {0, 0, 65, 65, 60, 55, 50, 46};

static bool in_lim(int64_t v)
{
    return v <= AFD_LIM && v >= -AFD_LIM;
}

/* *out = v * k, refused (false) unless |v| < 2^(62 - cs_fixed_bitlen64(k)). */
static bool mul_chk(int64_t v, uint32_t k, int64_t *out)
{
    uint64_t m = v < 0 ? (uint64_t)0 - (uint64_t)v : (uint64_t)v;
    if (m >= ((uint64_t)1 << (62 - cs_fixed_bitlen64(k))))
        return false;
    *out = v * (int64_t)k;
    return true;
}

/* a + b for |a|, |b| <= 2^62 (cannot wrap int64), refused if the sum leaves +-2^62. */
static bool add_chk(int64_t a, int64_t b, int64_t *out)
{
    int64_t s = a + b;
    if (!in_lim(s))
        return false;
    *out = s;
    return true;
}

/* Differences at step 2h from those at step h (orders 1..n; position unchanged). */
static bool afd_double(const int64_t *d, unsigned n, int64_t *out)
{
    out[0] = d[0];
    for (unsigned m = 1; m <= n; m++) {
        int64_t acc = 0;
        for (unsigned i = 0; i <= m && m + i <= n; i++) {
            int64_t term;
            if (!mul_chk(d[m + i], (uint32_t)cs_fixed_binom(m, i) << (m - i), &term) ||
                !add_chk(acc, term, &acc))
                return false;
        }
        out[m] = acc;
    }
    return true;
}

/* Differences at step h/2 from those at step h; false if not exact (format too short) or out
 * of range. */
static bool afd_halve(const int64_t *d, unsigned n, int64_t *out)
{
    out[0] = d[0];
    for (unsigned m = n; m >= 1; m--) {
        int64_t acc = d[m];
        for (unsigned i = 1; i <= m && m + i <= n; i++) {
            int64_t term;
            if (!mul_chk(out[m + i], (uint32_t)cs_fixed_binom(m, i) << (m - i), &term) ||
                !add_chk(acc, -term, &acc))
                return false;
        }
        uint64_t mask = ((uint64_t)1 << m) - 1u;
        if (((uint64_t)acc & mask) != 0)
            return false;
        /* Exact division by 2^m as a shift of the magnitude (no divide on small targets). */
        uint64_t mag = acc < 0 ? (uint64_t)0 - (uint64_t)acc : (uint64_t)acc;
        out[m] = acc < 0 ? -(int64_t)(mag >> m) : (int64_t)(mag >> m);
    }
    return true;
}

/* Upper bound of |v| (v one difference order, three axes) in units of 2^sh, saturated at 2^50. */
static uint64_t norm_up(int64_t x, int64_t y, int64_t z, unsigned sh)
{
    uint64_t a[3] = {x < 0 ? (uint64_t)0 - (uint64_t)x : (uint64_t)x,
                     y < 0 ? (uint64_t)0 - (uint64_t)y : (uint64_t)y,
                     z < 0 ? (uint64_t)0 - (uint64_t)z : (uint64_t)z};
    uint64_t mx = a[0] > a[1] ? a[0] : a[1];
    mx = mx > a[2] ? mx : a[2];
    if (mx == 0)
        return 0;
    unsigned k = 0;
    while ((mx >> k) >= ((uint64_t)1 << 30))
        k++;
    uint64_t s2 = 0;
    for (unsigned i = 0; i < 3; i++) {
        uint64_t v = (a[i] >> k) + (k ? 1u : 0u);
        s2 += v * v;
    }
    uint64_t r = (uint64_t)cs_fixed_isqrt64(s2) + 1u; /* |v| <= r * 2^k */
    if (k >= sh) {
        unsigned up = k - sh;
        if (up >= 50 || r >= ((uint64_t)1 << (50 - up)))
            return (uint64_t)1 << 50;
        return r << up;
    }
    return (r >> (sh - k)) + 1u;
}

/* Chord over the current step within tol_eff: |q''| <= sum_j b_j |D^j| on the step (Newton
 * form), and a chord deviates at most max|q''| / 8 from its polynomial piece. */
static bool afd_flat(const cs_afd_t *a, int64_t d[3][CS_BEZIER_MAX_POINTS])
{
    unsigned n = a->degree, g = a->guard + n * a->lmax;
    unsigned sh = g > 8 ? g - 8 : 0; /* work in units of 2^(g-8): LSB / 256 */
    uint64_t sum = 0;
    for (unsigned j = 2; j <= n; j++)
        sum += newton_b64[j] * norm_up(d[0][j], d[1][j], d[2][j], sh);
    /* sum / 64 <= 8 * tol  <=>  sum <= 512 tol (in units 2^sh, tol scaled by 2^(g - sh)). */
    uint64_t lim = ((uint64_t)a->tol_eff * 512u) << (g - sh);
    return sum <= lim;
}

static bool afd_step(const cs_afd_t *a, int64_t out[3][CS_BEZIER_MAX_POINTS])
{
    unsigned n = a->degree;
    for (unsigned ax = 0; ax < 3; ax++) {
        for (unsigned j = 0; j < n; j++)
            if (!add_chk(a->d[ax][j], a->d[ax][j + 1], &out[ax][j]))
                return false;
        out[ax][n] = a->d[ax][n];
    }
    return true;
}

static cs_err_t start_piece(cs_afd_t *a)
{
    cs_fd_pt_t q[CS_BEZIER_MAX_POINTS];
    unsigned n = a->degree;
    cs_fd_piece(&a->curve, a->split, a->piece, a->guard, q);
    unsigned k = cs_fd_wang_k(q, n, a->guard, a->tol_eff);
    unsigned kmin = 0;
    while (((unsigned)1 << kmin) < n)
        kmin++; /* every order up to n must be initialised: 2^k >= n */
    if (k < kmin)
        k = kmin;
    for (; k <= a->lmax; k++) {
        /* Exact differences at step 2^-k, rescaled from 2^(n k) to 2^(n lmax); a coarse start
         * whose values would leave the format is refused and a finer one tried. */
        int64_t d[3][CS_BEZIER_MAX_POINTS];
        cs_fd_init_diffs(q, n, k, d);
        unsigned up = n * (a->lmax - k);
        bool ok = true;
        for (unsigned ax = 0; ax < 3 && ok; ax++)
            for (unsigned j = 0; j <= n && ok; j++) {
                uint64_t m = d[ax][j] < 0 ? (uint64_t)0 - (uint64_t)d[ax][j] : (uint64_t)d[ax][j];
                ok = m == 0 || (up < 62 && m < ((uint64_t)1 << (62 - up)));
            }
        if (!ok)
            continue;
        for (unsigned ax = 0; ax < 3; ax++)
            for (unsigned j = 0; j <= n; j++)
                a->d[ax][j] = d[ax][j] == 0 ? 0 : d[ax][j] * ((int64_t)1 << up);
        a->level = (uint8_t)k;
        a->t = 0;
        return CS_OK;
    }
    return CS_ERR_OVERFLOW;
}

cs_err_t cs_afd_begin(cs_afd_t *a, const cs_bezier_t *c, cs_pos_t tol)
{
    a->done = true;
    cs_err_t ce = cs_bezier_check(c);
    if (ce != CS_OK)
        return ce;
    if (c->rational)
        return CS_ERR_UNSUPPORTED;
    if (tol < 1 || tol > CS_POS_LIMIT)
        return CS_ERR_TOLERANCE;
    a->degree = c->degree;
    a->lmin = 0;
    unsigned s;
    cs_err_t e = cs_fd_plan(c, tol, CS_AFD_GUARD_BITS, 1, &s, &a->tol_eff);
    if (e != CS_OK)
        return e;
    a->split = (uint8_t)s;
    a->guard = (uint8_t)(s ? CS_FD_PIECE_GUARD : 0);
    a->lmax = (uint8_t)cs_fd_kmax(c->degree, CS_AFD_GUARD_BITS, a->guard);
    a->piece = 0;
    a->curve = *c;
    e = start_piece(a);
    if (e != CS_OK)
        return e;
    a->done = false;
    return CS_OK;
}

static cs_err_t fail(cs_afd_t *a, cs_err_t e)
{
    a->done = true;
    return e;
}

/* Replace the state by its half-step form: CS_ERR_DEPTH when already at lmax, CS_ERR_OVERFLOW
 * when a value would leave its format. */
static cs_err_t halve_state(cs_afd_t *a)
{
    if (a->level >= a->lmax)
        return CS_ERR_DEPTH;
    int64_t h[CS_BEZIER_MAX_POINTS];
    for (unsigned ax = 0; ax < 3; ax++) {
        if (!afd_halve(a->d[ax], a->degree, h))
            return CS_ERR_OVERFLOW;
        for (unsigned j = 0; j <= a->degree; j++)
            a->d[ax][j] = h[j];
    }
    a->level++;
    return CS_OK;
}

/* Double while the doubled step still fits the piece, its format, and the tolerance: the chord
 * is then no shorter than it needs to be (to within the factor 2 of a dyadic step). */
static void try_double(cs_afd_t *a)
{
    unsigned n = a->degree;
    uint32_t one = (uint32_t)1 << a->lmax;
    int64_t nd[3][CS_BEZIER_MAX_POINTS];
    while (a->level > a->lmin) {
        uint32_t h2 = (uint32_t)2 << (a->lmax - a->level);
        if (a->t + h2 > one)
            break;
        bool ok = true;
        for (unsigned ax = 0; ax < 3 && ok; ax++)
            ok = afd_double(a->d[ax], n, nd[ax]);
        if (!ok || !afd_flat(a, nd))
            break;
        for (unsigned ax = 0; ax < 3; ax++)
            for (unsigned j = 0; j <= n; j++)
                a->d[ax][j] = nd[ax][j];
        a->level--;
    }
}

cs_err_t cs_afd_next(cs_afd_t *a, cs_vec3_t *pt)
{
    if (a->done)
        return CS_END;
    unsigned n = a->degree;
    uint32_t one = (uint32_t)1 << a->lmax;
    int64_t nd[3][CS_BEZIER_MAX_POINTS];
    try_double(a);
    for (;;) {
        uint32_t h = (uint32_t)1 << (a->lmax - a->level);
        if (a->t + h > one || !afd_flat(a, a->d)) {
            cs_err_t e = halve_state(a);
            if (e != CS_OK)
                return fail(a, e);
            continue;
        }
        if (!afd_step(a, nd)) { /* a difference past t = 1 grew too large: smaller step */
            cs_err_t e = halve_state(a);
            if (e != CS_OK)
                return fail(a, e == CS_ERR_DEPTH ? CS_ERR_OVERFLOW : e);
            continue;
        }
        a->t += h;
        break;
    }
    for (unsigned ax = 0; ax < 3; ax++)
        for (unsigned j = 0; j <= n; j++)
            a->d[ax][j] = nd[ax][j];
    unsigned g = a->guard + n * a->lmax;
    pt->x = (cs_pos_t)cs_fixed_round_shift64(a->d[0][0], g);
    pt->y = (cs_pos_t)cs_fixed_round_shift64(a->d[1][0], g);
    pt->z = (cs_pos_t)cs_fixed_round_shift64(a->d[2][0], g);
    if (a->t == one) {
        if (a->piece + 1 == ((uint32_t)1 << a->split)) {
            a->done = true;
            return CS_OK;
        }
        a->piece++;
        cs_err_t e = start_piece(a);
        if (e != CS_OK)
            return fail(a, e);
    }
    return CS_OK;
}
