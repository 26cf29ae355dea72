/* cs_bezier: de Casteljau evaluation, splitting, pieces, degree elevation, hodograph and
 * bounding box of cs_bezier_t segments (seed 003, "Bézier", "subdivision").
 *
 * Precision. Every de Casteljau pass runs on int64 values that carry guard bits:
 *   polynomial: coordinate << CS_BEZIER_GUARD (28), so |value| < 2^59 for any int32 input;
 *   rational:   homogeneous w*P (Q30 weight times LSB, |.| <= 2^58) and w << 28 (Q58).
 * One lerp a + round((b - a) t / 2^30) (cs_fixed_mul64_q30) adds at most 1/2 guard unit of
 * error and the convex combination does not grow earlier errors, so after n <= 7 levels a
 * polynomial value is within 7/2 * 2^-28 LSB of the exact polynomial of the fixed-point control
 * points at the given t; the final rounding to the nearest LSB makes the result within
 * 0.5 + 2^-25 LSB of the exact value (the "1 LSB" bound of the header, with room to spare).
 * Rational: the numerator error is at most 7/2 units of 2^-30 LSB*weight and the denominator
 * (Q58) error 7/2 * 2^-58; with the weight sum >= 2^-20 the quotient is within 0.5 + 2^-8 LSB.
 *
 * Stack: one axis at a time, 8 int64 (64 bytes) per working array, so AVR stays modest. */
#include "cs_bezier.h"

#define GUARD  CS_BEZIER_GUARD
#define RGUARD 28 /* extra bits on rational weights: w (Q30) << 28 = Q58 */

CS_STATIC_ASSERT(CS_BEZIER_MAX_POINTS == 8, max_points_is_8);
CS_STATIC_ASSERT(GUARD + 31 <= 59, guarded_values_below_2_59);
CS_STATIC_ASSERT(CS_BEZIER_MAX_FRAC <= GUARD, frac_within_guard);

static bool weights_ok(const cs_weight_t *w, unsigned n)
{
    for (unsigned i = 0; i <= n; i++)
        if (w[i] < CS_WEIGHT_MIN || w[i] > CS_WEIGHT_ONE)
            return false;
    return true;
}

/* Load axis 0..2 (coordinates) or 3 (weights) of c into v[0..n] in the guarded format above. */
static void load_axis(const cs_bezier_t *c, unsigned axis, int64_t *v)
{
    for (unsigned i = 0; i <= c->degree; i++) {
        if (axis == 3)
            v[i] = (int64_t)c->w[i] << RGUARD;
        else if (c->rational)
            v[i] = (int64_t)c->w[i] * cs_fixed_vec_get(&c->p[i], axis);
        else
            v[i] = (int64_t)cs_fixed_vec_get(&c->p[i], axis) * ((int64_t)1 << GUARD);
    }
}

/* Blossom b(ts[0], ..., ts[n-1]) of one axis, in place (the result is v[0]). */
static int64_t blossom_axis(int64_t *v, unsigned n, const cs_param_t *ts)
{
    for (unsigned r = 1; r <= n; r++)
        for (unsigned i = 0; i + r <= n; i++)
            v[i] = cs_fixed_lerp64(v[i], v[i + 1], ts[r - 1]);
    return v[0];
}

/* Rational point from homogeneous h (Q30 * LSB) and weight W (Q58), with frac extra fraction
 * bits (0..24): round(h * 2^(28 + frac) / W). W > 0. h = w P with |P| <= 2^28 LSB, so
 * |h| * 2^(28+frac) / W = |P| 2^frac < 2^52 and the 128-bit quotient always fits. */
static cs_err_t rat_div(int64_t h, int64_t W, unsigned frac, int64_t *out)
{
    uint64_t m = h < 0 ? (uint64_t)0 - (uint64_t)h : (uint64_t)h, q;
    unsigned s = RGUARD + frac;
    cs_err_t e = cs_fixed_div_u128(m >> (64 - s), m << s, (uint64_t)W, &q);
    if (e != CS_OK)
        return e;
    if (q > (uint64_t)INT64_MAX)
        return CS_ERR_OVERFLOW;
    *out = h < 0 ? -(int64_t)q : (int64_t)q;
    return CS_OK;
}

/* Normalised Q30 weight W * 2^30 / Wmax (W <= Wmax, both Q58 > 0). The exact value is at least
 * CS_WEIGHT_MIN whenever the source weights were in range (a convex combination of weights lies
 * between their minimum and maximum), so raising a rounded CS_WEIGHT_MIN - 1 back to the
 * minimum only undoes rounding, it never hides an out-of-range weight. */
static cs_err_t norm_weight(int64_t W, int64_t Wmax, cs_weight_t *out)
{
    uint64_t q;
    cs_err_t e = cs_fixed_div_u128((uint64_t)W >> 34, (uint64_t)W << 30, (uint64_t)Wmax, &q);
    if (e != CS_OK)
        return e;
    if (q > (uint64_t)CS_WEIGHT_ONE)
        return CS_ERR_WEIGHT;
    *out = q < (uint64_t)CS_WEIGHT_MIN ? CS_WEIGHT_MIN : (cs_weight_t)q;
    return CS_OK;
}

cs_err_t cs_bezier_init(cs_bezier_t *c, unsigned degree, const cs_vec3_t *pts)
{
    if (degree < 1 || degree > CS_BEZIER_MAX_DEGREE)
        return CS_ERR_DEGREE;
    for (unsigned i = 0; i <= degree; i++)
        if (!cs_fixed_vec_ok(&pts[i]))
            return CS_ERR_RANGE;
    c->degree = (uint8_t)degree;
    c->rational = false;
    for (unsigned i = 0; i < CS_BEZIER_MAX_POINTS; i++) {
        c->p[i] = i <= degree ? pts[i] : cs_fixed_vec(0, 0, 0);
        c->w[i] = CS_WEIGHT_ONE;
    }
    return CS_OK;
}

cs_err_t cs_bezier_init_rational(cs_bezier_t *c, unsigned degree, const cs_vec3_t *pts,
                                 const cs_weight_t *w)
{
    if (degree < 1 || degree > CS_BEZIER_MAX_DEGREE)
        return CS_ERR_DEGREE;
    if (!weights_ok(w, degree))
        return CS_ERR_WEIGHT;
    cs_err_t e = cs_bezier_init(c, degree, pts);
    if (e != CS_OK)
        return e;
    c->rational = true;
    for (unsigned i = 0; i <= degree; i++)
        c->w[i] = w[i];
    return CS_OK;
}

/* Structural checks shared by every operation on an existing segment. Polynomial segments may
 * hold any int32 coordinates (a hodograph can leave CS_POS_LIMIT); rational ones must be inside
 * the accepted range so that w*P fits the guarded format. */
static cs_err_t check(const cs_bezier_t *c)
{
    if (c->degree > CS_BEZIER_MAX_DEGREE)
        return CS_ERR_DEGREE;
    if (!c->rational)
        return CS_OK;
    if (!weights_ok(c->w, c->degree))
        return CS_ERR_WEIGHT;
    for (unsigned i = 0; i <= c->degree; i++)
        if (!cs_fixed_vec_ok(&c->p[i]))
            return CS_ERR_RANGE;
    return CS_OK;
}

cs_err_t cs_bezier_check(const cs_bezier_t *c)
{
    if (c->degree < 1 || c->degree > CS_BEZIER_MAX_DEGREE)
        return CS_ERR_DEGREE;
    for (unsigned i = 0; i <= c->degree; i++)
        if (!cs_fixed_vec_ok(&c->p[i]))
            return CS_ERR_RANGE;
    if (c->rational && !weights_ok(c->w, c->degree))
        return CS_ERR_WEIGHT;
    return CS_OK;
}

cs_err_t cs_bezier_blossom(const cs_bezier_t *c, const cs_param_t *ts, unsigned frac,
                           cs_vec3w_t *out)
{
    cs_err_t e = check(c);
    if (e != CS_OK)
        return e;
    if (frac > CS_BEZIER_MAX_FRAC)
        return CS_ERR_ARG;
    unsigned n = c->degree;
    for (unsigned i = 0; i < n; i++)
        if (ts[i] < 0 || ts[i] > CS_PARAM_ONE)
            return CS_ERR_ARG;
    int64_t v[CS_BEZIER_MAX_POINTS], W = 0, r[3];
    if (c->rational) {
        load_axis(c, 3, v);
        W = blossom_axis(v, n, ts);
    }
    for (unsigned a = 0; a < 3; a++) {
        load_axis(c, a, v);
        int64_t h = blossom_axis(v, n, ts);
        if (c->rational) {
            e = rat_div(h, W, frac, &r[a]);
            if (e != CS_OK)
                return e;
        } else {
            r[a] = cs_fixed_round_shift64(h, GUARD - frac);
        }
    }
    out->x = r[0];
    out->y = r[1];
    out->z = r[2];
    return CS_OK;
}

cs_err_t cs_bezier_eval(const cs_bezier_t *c, cs_param_t t, cs_vec3_t *out)
{
    cs_param_t ts[CS_BEZIER_MAX_DEGREE];
    cs_vec3w_t r;
    if (t < 0 || t > CS_PARAM_ONE)
        return CS_ERR_ARG;
    for (unsigned i = 0; i < CS_BEZIER_MAX_DEGREE; i++)
        ts[i] = t;
    cs_err_t e = cs_bezier_blossom(c, ts, 0, &r);
    if (e != CS_OK)
        return e;
    cs_vec3_t p;
    if (cs_fixed_narrow(r.x, &p.x) != CS_OK || cs_fixed_narrow(r.y, &p.y) != CS_OK ||
        cs_fixed_narrow(r.z, &p.z) != CS_OK)
        return CS_ERR_OVERFLOW;
    *out = p;
    return CS_OK;
}

cs_err_t cs_bezier_piece(const cs_bezier_t *c, cs_param_t t0, cs_param_t t1, unsigned frac,
                         cs_vec3w_t *pts)
{
    cs_param_t ts[CS_BEZIER_MAX_DEGREE];
    unsigned n = c->degree;
    if (n > CS_BEZIER_MAX_DEGREE)
        return CS_ERR_DEGREE;
    /* Control point i of the piece is the blossom b(t0^(n-i), t1^i) (seed 003: the
     * de Casteljau construction evaluated with different parameters at each level). */
    for (unsigned i = 0; i <= n; i++) {
        for (unsigned k = 0; k < n; k++)
            ts[k] = k < n - i ? t0 : t1;
        cs_err_t e = cs_bezier_blossom(c, ts, frac, &pts[i]);
        if (e != CS_OK)
            return e;
    }
    return CS_OK;
}

/* Write the split halves of one axis: in-place de Casteljau at t, L[r] = first point of level
 * r, R[n - r] = last point of level r. */
static void split_axis(int64_t *v, unsigned n, cs_param_t t, int64_t *L, int64_t *R)
{
    L[0] = v[0];
    R[n] = v[n];
    for (unsigned r = 1; r <= n; r++) {
        for (unsigned i = 0; i + r <= n; i++)
            v[i] = cs_fixed_lerp64(v[i], v[i + 1], t);
        L[r] = v[0];
        R[n - r] = v[n - r];
    }
}

/* Write the fields of a split half other than its coordinates (weights from Q58 values). */
static cs_err_t finish_half(cs_bezier_t *h, const cs_bezier_t *c, const int64_t *W)
{
    unsigned n = c->degree;
    int64_t m = 0;
    for (unsigned i = 0; i <= n && c->rational; i++)
        m = W[i] > m ? W[i] : m;
    for (unsigned i = 0; i < CS_BEZIER_MAX_POINTS; i++) {
        if (i > n) {
            h->p[i] = cs_fixed_vec(0, 0, 0);
            h->w[i] = CS_WEIGHT_ONE;
        } else if (!c->rational) {
            h->w[i] = CS_WEIGHT_ONE;
        } else {
            /* Renormalise so the half's largest weight is 1 (a common factor on all weights
             * leaves a rational curve unchanged) and keep the most precision in Q30. */
            cs_err_t e = norm_weight(W[i], m, &h->w[i]);
            if (e != CS_OK)
                return e;
        }
    }
    h->degree = (uint8_t)n;
    h->rational = c->rational;
    return CS_OK;
}

cs_err_t cs_bezier_split(const cs_bezier_t *c, cs_param_t t, cs_bezier_t *left, cs_bezier_t *right)
{
    cs_err_t e = check(c);
    if (e != CS_OK)
        return e;
    if (t <= 0 || t >= CS_PARAM_ONE)
        return CS_ERR_ARG;
    unsigned n = c->degree;
    /* No copy of the halves (stack on AVR): each output is written axis by axis after that
     * axis of c has been loaded, and the weights (which the rational coordinates need) last,
     * so left or right may be c itself. */
    int64_t v[CS_BEZIER_MAX_POINTS], L[CS_BEZIER_MAX_POINTS], R[CS_BEZIER_MAX_POINTS];
    int64_t WL[CS_BEZIER_MAX_POINTS], WR[CS_BEZIER_MAX_POINTS];
    if (c->rational) {
        load_axis(c, 3, v);
        split_axis(v, n, t, WL, WR);
    }
    for (unsigned a = 0; a < 3; a++) {
        load_axis(c, a, v);
        split_axis(v, n, t, L, R);
        for (unsigned i = 0; i <= n; i++) {
            int64_t pl, pr;
            if (c->rational) {
                if ((e = rat_div(L[i], WL[i], 0, &pl)) != CS_OK ||
                    (e = rat_div(R[i], WR[i], 0, &pr)) != CS_OK)
                    return e;
            } else {
                pl = cs_fixed_round_shift64(L[i], GUARD);
                pr = cs_fixed_round_shift64(R[i], GUARD);
            }
            /* Both lie in the convex hull of c's points, so they fit int32; checked anyway. */
            int32_t xl, xr;
            if (cs_fixed_narrow(pl, &xl) != CS_OK || cs_fixed_narrow(pr, &xr) != CS_OK)
                return CS_ERR_OVERFLOW;
            if (left)
                cs_fixed_vec_set(&left->p[i], a, xl);
            if (right)
                cs_fixed_vec_set(&right->p[i], a, xr);
        }
    }
    if (left && (e = finish_half(left, c, WL)) != CS_OK)
        return e;
    if (right && (e = finish_half(right, c, WR)) != CS_OK)
        return e;
    return CS_OK;
}

cs_err_t cs_bezier_elevate(const cs_bezier_t *c, cs_bezier_t *out)
{
    cs_err_t e = check(c);
    if (e != CS_OK)
        return e;
    unsigned n = c->degree;
    if (n >= CS_BEZIER_MAX_DEGREE)
        return CS_ERR_DEGREE;
    cs_bezier_t r = *c;
    int64_t Wn[CS_BEZIER_MAX_POINTS], Wmax = 0;
    r.degree = (uint8_t)(n + 1);
    /* P'_i = i/(n+1) P_{i-1} + (1 - i/(n+1)) P_i, on homogeneous points for a rational curve
     * (weights: the same formula; |numerators| <= 8 * 2^58 fit int64). */
    for (unsigned i = 0; i <= n + 1; i++) {
        int64_t a = (int64_t)i, b = (int64_t)(n + 1 - i);
        int64_t wa = i > 0 ? c->w[i - 1] : 0, wb = i <= n ? c->w[i] : 0;
        if (!c->rational)
            wa = wb = 1;
        Wn[i] = a * wa + b * wb;
        Wmax = Wn[i] > Wmax ? Wn[i] : Wmax;
        for (unsigned ax = 0; ax < 3; ax++) {
            int64_t pa = i > 0 ? cs_fixed_vec_get(&c->p[i - 1], ax) : 0;
            int64_t pb = i <= n ? cs_fixed_vec_get(&c->p[i], ax) : 0;
            int64_t v = cs_fixed_div_round(a * wa * pa + b * wb * pb, Wn[i]);
            int32_t x;
            if (cs_fixed_narrow(v, &x) != CS_OK)
                return CS_ERR_OVERFLOW;
            cs_fixed_vec_set(&r.p[i], ax, x);
        }
    }
    for (unsigned i = 0; i <= n + 1; i++) {
        if (!c->rational) {
            r.w[i] = CS_WEIGHT_ONE;
            continue;
        }
        /* Normalised so the largest weight is 1; Wn * 2^30 < 2^64 as unsigned. */
        uint64_t q = (((uint64_t)Wn[i] << 30) + (uint64_t)Wmax / 2) / (uint64_t)Wmax;
        r.w[i] = q < (uint64_t)CS_WEIGHT_MIN ? CS_WEIGHT_MIN : (cs_weight_t)q;
    }
    *out = r;
    return CS_OK;
}

cs_err_t cs_bezier_hodograph(const cs_bezier_t *c, cs_bezier_t *out)
{
    cs_err_t e = check(c);
    if (e != CS_OK)
        return e;
    if (c->rational)
        return CS_ERR_UNSUPPORTED;
    unsigned n = c->degree;
    if (n == 0)
        return CS_ERR_DEGREE;
    cs_bezier_t r;
    r.degree = (uint8_t)(n - 1);
    r.rational = false;
    for (unsigned i = 0; i < CS_BEZIER_MAX_POINTS; i++) {
        r.p[i] = cs_fixed_vec(0, 0, 0);
        r.w[i] = CS_WEIGHT_ONE;
    }
    for (unsigned i = 0; i < n; i++)
        for (unsigned a = 0; a < 3; a++) {
            int64_t d = (int64_t)n * ((int64_t)cs_fixed_vec_get(&c->p[i + 1], a) - cs_fixed_vec_get(&c->p[i], a));
            int32_t x;
            if (cs_fixed_narrow(d, &x) != CS_OK)
                return CS_ERR_OVERFLOW;
            cs_fixed_vec_set(&r.p[i], a, x);
        }
    *out = r;
    return CS_OK;
}

/* --- bounding box ------------------------------------------------------------------------ */

/* Value of a 1-D Bernstein polynomial (coefficients already scaled, |.| < 2^60) at t. */
static int64_t bern1(const int64_t *coef, unsigned n, cs_param_t t)
{
    int64_t v[CS_BEZIER_MAX_POINTS];
    for (unsigned i = 0; i <= n; i++)
        v[i] = coef[i];
    for (unsigned r = 1; r <= n; r++)
        for (unsigned i = 0; i + r <= n; i++)
            v[i] = cs_fixed_lerp64(v[i], v[i + 1], t);
    return v[0];
}

static int sgn(int64_t v)
{
    return (v > 0) - (v < 0);
}

/* f (Bernstein, degree n) changes sign on [lo, hi]: shrink the bracket to width 1 (in Q30 t)
 * by bisection; *lo and *hi bracket the sign change on return. f is only ever a derivative of
 * degree <= 2 that is monotone on [lo, hi], so the change is unique. */
static void bisect(const int64_t *f, unsigned n, cs_param_t *lo, cs_param_t *hi)
{
    int slo = sgn(bern1(f, n, *lo));
    while (*hi - *lo > 1) {
        cs_param_t mid = *lo + (*hi - *lo) / 2;
        if (sgn(bern1(f, n, mid)) == slo)
            *lo = mid;
        else
            *hi = mid;
    }
}

static int64_t floor_shift(int64_t v, unsigned s)
{
    int64_t one = (int64_t)1 << s;
    return v >= 0 ? v / one : -((-v + one - 1) / one);
}

/* Tight extent of one axis of a polynomial of degree 2 or 3. Candidates are the end points
 * and both ends of the width-1 brackets around each root of B' (for a cubic, B' is split at the
 * root of B'' into two monotone pieces first). The value at a bracket end differs from the
 * extremum by less than max|B'| over the bracket times 2^-30 <= |B''| 2^-60 < 2^-24 LSB
 * (|B''| < 2^36 LSB for int32 points); the guard-bit evaluation error is below 2^-25 LSB, and
 * a sign misjudged by bisection (|B'| below its own rounding) moves the value by less still.
 * Adding a 2^-20 LSB margin before rounding outwards makes the box certain to contain the
 * curve and loose by less than 1 + 2^-20 LSB on each side. */
static cs_err_t axis_extent(const cs_bezier_t *c, unsigned axis, int32_t *mn, int32_t *mx)
{
    unsigned n = c->degree;
    int64_t p[CS_BEZIER_MAX_POINTS], d1[3], d2[2];
    cs_param_t cand[8];
    unsigned nc = 0;
    load_axis(c, axis, p); /* polynomial: coordinate << GUARD */
    for (unsigned i = 0; i < n; i++)
        d1[i] = (int64_t)n * ((int64_t)cs_fixed_vec_get(&c->p[i + 1], axis) - cs_fixed_vec_get(&c->p[i], axis)) *
                ((int64_t)1 << 24);
    cs_param_t pieces[4] = {0, CS_PARAM_ONE, 0, 0};
    unsigned np = 1;
    if (n == 3) {
        for (unsigned i = 0; i < 2; i++)
            d2[i] = (int64_t)6 *
                    ((int64_t)cs_fixed_vec_get(&c->p[i + 2], axis) - 2 * (int64_t)cs_fixed_vec_get(&c->p[i + 1], axis) +
                     cs_fixed_vec_get(&c->p[i], axis)) *
                    ((int64_t)1 << 24);
        if (sgn(d2[0]) * sgn(d2[1]) < 0) {
            cs_param_t lo = 0, hi = CS_PARAM_ONE;
            bisect(d2, 1, &lo, &hi);
            pieces[0] = 0;
            pieces[1] = lo;
            pieces[2] = hi;
            pieces[3] = CS_PARAM_ONE;
            np = 2;
            cand[nc++] = lo;
            cand[nc++] = hi;
        }
    }
    for (unsigned k = 0; k < np; k++) {
        cs_param_t lo = pieces[2 * k], hi = pieces[2 * k + 1];
        if (hi <= lo)
            continue;
        if (sgn(bern1(d1, n - 1, lo)) * sgn(bern1(d1, n - 1, hi)) < 0) {
            bisect(d1, n - 1, &lo, &hi);
            cand[nc++] = lo;
            cand[nc++] = hi;
        }
    }
    int64_t vmin = p[0] < p[n] ? p[0] : p[n], vmax = p[0] < p[n] ? p[n] : p[0];
    int64_t margin = (int64_t)1 << (GUARD - 20);
    for (unsigned k = 0; k < nc; k++) {
        cs_param_t ts[CS_BEZIER_MAX_DEGREE];
        int64_t v[CS_BEZIER_MAX_POINTS];
        for (unsigned i = 0; i < n; i++)
            ts[i] = cand[k];
        load_axis(c, axis, v);
        int64_t val = blossom_axis(v, n, ts);
        vmin = val - margin < vmin ? val - margin : vmin;
        vmax = val + margin > vmax ? val + margin : vmax;
    }
    /* End points are exact (multiples of 2^GUARD); inner extrema are rounded outwards. */
    int64_t lo = floor_shift(vmin, GUARD), hi = -floor_shift(-vmax, GUARD);
    if (cs_fixed_narrow(lo, mn) != CS_OK || cs_fixed_narrow(hi, mx) != CS_OK)
        return CS_ERR_OVERFLOW;
    return CS_OK;
}

cs_err_t cs_bezier_bbox(const cs_bezier_t *c, cs_vec3_t *min, cs_vec3_t *max)
{
    cs_err_t e = check(c);
    if (e != CS_OK)
        return e;
    unsigned n = c->degree;
    cs_vec3_t lo = c->p[0], hi = c->p[0];
    if (!c->rational && n >= 2 && n <= 3) {
        for (unsigned a = 0; a < 3; a++) {
            int32_t mn, mx;
            if ((e = axis_extent(c, a, &mn, &mx)) != CS_OK)
                return e;
            cs_fixed_vec_set(&lo, a, mn);
            cs_fixed_vec_set(&hi, a, mx);
        }
    } else {
        /* Convex-hull property (positive weights for rational curves): the box of the control
         * points contains the curve. */
        for (unsigned i = 1; i <= n; i++)
            for (unsigned a = 0; a < 3; a++) {
                int32_t v = cs_fixed_vec_get(&c->p[i], a);
                if (v < cs_fixed_vec_get(&lo, a))
                    cs_fixed_vec_set(&lo, a, v);
                if (v > cs_fixed_vec_get(&hi, a))
                    cs_fixed_vec_set(&hi, a, v);
            }
    }
    *min = lo;
    *max = hi;
    return CS_OK;
}
