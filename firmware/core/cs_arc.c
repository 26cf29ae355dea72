/* cs_arc: arcs of ellipses as rational quadratic Bézier pieces, without trigonometry.
 * Work happens on the unit circle in Q1.30 (directions a, b of length 1), then the affine map
 * X = C + U d.x + V d.y carries each piece to the ellipse: rational Bézier curves are affine
 * invariant, so the weights found on the circle stay exact for any U, V (even non-perpendicular).
 *
 * Unit-circle piece from a to b (sweep 2 phi <= 90 degrees): the middle control point is the
 * intersection of the tangents at a and b, q = (a + b) / (1 + a.b) (|q| = 1/cos phi), and the
 * middle weight is w = cos phi = sqrt((1 + a.b) / 2). With exactly these two values the point at
 * t = 1/2, (a + 2 w q + b) / (2 + 2 w), has length 1 (so both come from the one product a.b). */
#include "cs_arc.h"

#include <stddef.h>

#define ARC_ONE ((int64_t)1 << 30) /* 1.0 in Q1.30 */

typedef struct {
    int64_t x, y; /* Q1.30 */
} arc_dir_t;

/* Unit vector along (x, y) in Q1.30 (error <= 1 LSB of Q1.30 per component).
 * CS_ERR_DEGENERATE for the zero vector. |x|, |y| < 2^33. */
static cs_err_t arc_normalise(int64_t x, int64_t y, arc_dir_t *out)
{
    if (x == 0 && y == 0)
        return CS_ERR_DEGENERATE;
    /* Bring the larger component into [2^30, 2^31) so the length has 31 significant bits and
     * x^2 + y^2 < 2^63. Shifting left is exact; shifting right only happens for inputs longer
     * than 2^31, which carry more bits than Q1.30 keeps anyway. */
    uint64_t mx = (uint64_t)(x < 0 ? -x : x), my = (uint64_t)(y < 0 ? -y : y);
    uint64_t big = mx > my ? mx : my;
    while (big < ((uint64_t)1 << 30)) {
        x *= 2;
        y *= 2;
        big <<= 1;
    }
    while (big >= ((uint64_t)1 << 31)) {
        x = cs_fixed_round_shift64(x, 1);
        y = cs_fixed_round_shift64(y, 1);
        big >>= 1;
    }
    uint64_t s = (uint64_t)(x * x) + (uint64_t)(y * y);
    uint64_t len = cs_fixed_isqrt64(s);
    if (s - len * len > len) /* round to nearest: sqrt(s) >= len + 1/2 */
        len++;
    cs_err_t e = cs_fixed_muldiv64(x, ARC_ONE, (int64_t)len, &out->x);
    if (e == CS_OK)
        e = cs_fixed_muldiv64(y, ARC_ONE, (int64_t)len, &out->y);
    return e;
}

/* a.b and a x b in Q2.60 (|.| <= 2^61: components are <= 2^30 + 1). */
static int64_t arc_dot(const arc_dir_t *a, const arc_dir_t *b)
{
    return a->x * b->x + a->y * b->y;
}

/* Direction halfway along the counter-clockwise arc from a to b; `big` when that arc is longer
 * than 180 degrees. Each case uses the sum that is long there (>= sqrt(2)), so the bisector is
 * well conditioned:
 *   sweep in [0, 90]:    a + b;
 *   sweep in (90, 270):  rot90(a) + rot-90(b) = (b.y - a.y, a.x - b.x);
 *   sweep in [270, 360]: -(a + b)  (a full turn, b = a, gives -a). */
static cs_err_t arc_mid(const arc_dir_t *a, const arc_dir_t *b, bool big, arc_dir_t *m)
{
    if (arc_dot(a, b) < 0)
        return arc_normalise(b->y - a->y, a->x - b->x, m);
    if (!big)
        return arc_normalise(a->x + b->x, a->y + b->y, m);
    return arc_normalise(-(a->x + b->x), -(a->y + b->y), m);
}

/* C + U d.x + V d.y, rounded once; CS_ERR_RANGE outside CS_POS_LIMIT. */
static cs_err_t arc_map(const cs_vec3_t *c, const cs_vec3_t *u, const cs_vec3_t *v,
                        const arc_dir_t *d, cs_vec3_t *out)
{
    /* |U|, |V| <= 2^28 and |d| <= 2^30.6: each sum stays below 2^60. */
    int64_t x = c->x + cs_fixed_round_shift64(u->x * d->x + v->x * d->y, 30);
    int64_t y = c->y + cs_fixed_round_shift64(u->y * d->x + v->y * d->y, 30);
    int64_t z = c->z + cs_fixed_round_shift64(u->z * d->x + v->z * d->y, 30);
    if (!cs_fixed_pos_ok(x) || !cs_fixed_pos_ok(y) || !cs_fixed_pos_ok(z))
        return CS_ERR_RANGE;
    *out = cs_fixed_vec((cs_pos_t)x, (cs_pos_t)y, (cs_pos_t)z);
    return CS_OK;
}

/* One piece from a to b (counter-clockwise, at most 90 degrees). */
static cs_err_t arc_piece(const cs_vec3_t *c, const cs_vec3_t *u, const cs_vec3_t *v,
                          const arc_dir_t *a, const arc_dir_t *b, cs_bezier_t *out)
{
    int64_t dot = arc_dot(a, b); /* cos(2 phi) in Q2.60, >= ~0 for pieces <= 90 degrees */
    int64_t one_plus = ((int64_t)1 << 60) + dot;
    if (one_plus <= 0)
        return CS_ERR_DEGENERATE; /* cannot happen for pieces <= 90 degrees */
    arc_dir_t q;
    cs_err_t e = cs_fixed_muldiv64(a->x + b->x, (int64_t)1 << 60, one_plus, &q.x);
    if (e == CS_OK)
        e = cs_fixed_muldiv64(a->y + b->y, (int64_t)1 << 60, one_plus, &q.y);
    if (e != CS_OK)
        return e;
    /* w = sqrt((1 + cos 2phi) / 2): Q2.60 / 2 under the root gives Q1.30. */
    uint64_t half = (uint64_t)one_plus >> 1;
    uint64_t w = cs_fixed_isqrt64(half);
    if (half - w * w > w)
        w++;
    /* a, b carry <= 1 LSB of rounding each, so a.b may exceed 1 by a few 2^-30 for tiny
     * pieces; w is then 1 up to that rounding, and 1 is the exact value. */
    if (w > (uint64_t)CS_WEIGHT_ONE)
        w = (uint64_t)CS_WEIGHT_ONE;
    cs_bezier_t bz;
    e = arc_map(c, u, v, a, &bz.p[0]);
    if (e == CS_OK)
        e = arc_map(c, u, v, &q, &bz.p[1]);
    if (e == CS_OK)
        e = arc_map(c, u, v, b, &bz.p[2]);
    if (e != CS_OK)
        return e;
    for (unsigned i = 3; i < CS_BEZIER_MAX_POINTS; i++) {
        bz.p[i] = cs_fixed_vec(0, 0, 0);
        bz.w[i] = CS_WEIGHT_ONE;
    }
    bz.w[0] = CS_WEIGHT_ONE;
    bz.w[1] = (cs_weight_t)w;
    bz.w[2] = CS_WEIGHT_ONE;
    bz.degree = 2;
    bz.rational = true;
    *out = bz;
    return CS_OK;
}

cs_err_t cs_arc_build(const cs_vec3_t *c, const cs_vec3_t *u, const cs_vec3_t *v, cs_param_t cos0,
                      cs_param_t sin0, cs_param_t cos1, cs_param_t sin1, bool ccw,
                      cs_bezier_t out[CS_ARC_MAX_SEGMENTS], unsigned *n)
{
    if (c == NULL || u == NULL || v == NULL || out == NULL || n == NULL)
        return CS_ERR_ARG;
    if (!cs_fixed_vec_ok(c) || !cs_fixed_vec_ok(u) || !cs_fixed_vec_ok(v))
        return CS_ERR_RANGE;
    if (cos0 == INT32_MIN || sin0 == INT32_MIN || cos1 == INT32_MIN || sin1 == INT32_MIN)
        return CS_ERR_RANGE;
    /* Clockwise from U towards -V is counter-clockwise in the frame (U, -V) with the sines
     * negated: X = C + U cos + (-V)(-sin). Both negations are exact. */
    cs_vec3_t vv = *v;
    int64_t s0 = sin0, s1 = sin1;
    if (!ccw) {
        vv = cs_fixed_vec(-v->x, -v->y, -v->z);
        s0 = -s0;
        s1 = -s1;
    }
    /* Classify the sweep on the exact input products (normalising could flip the sign of a
     * tiny cross product): |products| < 2^62, so the sums fit int64. */
    int64_t cross = (int64_t)cos0 * s1 - s0 * (int64_t)cos1;
    int64_t dot = (int64_t)cos0 * cos1 + s0 * s1;
    arc_dir_t a, b;
    cs_err_t e = arc_normalise(cos0, s0, &a);
    if (e == CS_OK)
        e = arc_normalise(cos1, s1, &b);
    if (e != CS_OK)
        return e;
    bool full = cross == 0 && dot > 0;
    if (full)
        b = a; /* same direction: one full turn, ending exactly where it started */
    unsigned pieces;
    if (!full && cross >= 0 && dot >= 0)
        pieces = 1; /* sweep in [0, 90] */
    else if (!full && cross >= 0)
        pieces = 2; /* (90, 180] */
    else
        pieces = 4; /* (180, 360] */
    arc_dir_t d[5];
    d[0] = a;
    d[pieces] = b;
    if (pieces == 2) {
        e = arc_mid(&a, &b, false, &d[1]);
    } else if (pieces == 4) {
        e = arc_mid(&a, &b, true, &d[2]);
        if (e == CS_OK)
            e = arc_mid(&d[0], &d[2], false, &d[1]);
        if (e == CS_OK)
            e = arc_mid(&d[2], &d[4], false, &d[3]);
    }
    if (e != CS_OK)
        return e;
    cs_bezier_t tmp[CS_ARC_MAX_SEGMENTS];
    for (unsigned i = 0; i < pieces; i++) {
        e = arc_piece(c, u, &vv, &d[i], &d[i + 1], &tmp[i]);
        if (e != CS_OK)
            return e;
    }
    for (unsigned i = 0; i < pieces; i++)
        out[i] = tmp[i];
    *n = pieces;
    return CS_OK;
}

/* Pointers to a vector's (first, second, normal) coordinates for a plane. */
static bool arc_plane_axes(cs_arc_plane_t plane, cs_vec3_t *v, cs_pos_t **a1, cs_pos_t **a2,
                           cs_pos_t **an)
{
    switch (plane) {
    case CS_ARC_PLANE_XY:
        *a1 = &v->x, *a2 = &v->y, *an = &v->z;
        return true;
    case CS_ARC_PLANE_ZX:
        *a1 = &v->z, *a2 = &v->x, *an = &v->y;
        return true;
    case CS_ARC_PLANE_YZ:
        *a1 = &v->y, *a2 = &v->z, *an = &v->x;
        return true;
    default:
        return false;
    }
}

cs_err_t cs_arc_gcode(const cs_vec3_t *centre, const cs_vec3_t *start, const cs_vec3_t *end,
                      cs_arc_plane_t plane, bool ccw, cs_bezier_t out[CS_ARC_MAX_SEGMENTS],
                      unsigned *n)
{
    if (centre == NULL || start == NULL || end == NULL || out == NULL || n == NULL)
        return CS_ERR_ARG;
    if (!cs_fixed_vec_ok(centre) || !cs_fixed_vec_ok(start) || !cs_fixed_vec_ok(end))
        return CS_ERR_RANGE;
    cs_vec3_t c = *centre, s = *start, e = *end, u = {0, 0, 0}, v = {0, 0, 0};
    cs_pos_t *c1, *c2, *cn, *s1, *s2, *sn, *e1, *e2, *en, *u1, *u2, *un, *v1, *v2, *vn;
    if (!arc_plane_axes(plane, &c, &c1, &c2, &cn) || !arc_plane_axes(plane, &s, &s1, &s2, &sn) ||
        !arc_plane_axes(plane, &e, &e1, &e2, &en) || !arc_plane_axes(plane, &u, &u1, &u2, &un) ||
        !arc_plane_axes(plane, &v, &v1, &v2, &vn))
        return CS_ERR_ARG;
    if (*sn != *en)
        return CS_ERR_ARG;
    (void)un;
    (void)vn;
    *cn = *sn;
    /* In-plane radius vector U = start - centre and V = U turned +90 degrees in the plane
     * (|coordinates| <= 2^28, so differences fit in 2^29; cs_arc_build checks the range). */
    int64_t du1 = (int64_t)*s1 - *c1, du2 = (int64_t)*s2 - *c2;
    int64_t de1 = (int64_t)*e1 - *c1, de2 = (int64_t)*e2 - *c2;
    if ((du1 == 0 && du2 == 0) || (de1 == 0 && de2 == 0))
        return CS_ERR_DEGENERATE;
    if (!cs_fixed_pos_ok(du1) || !cs_fixed_pos_ok(du2))
        return CS_ERR_RANGE;
    *u1 = (cs_pos_t)du1;
    *u2 = (cs_pos_t)du2;
    *v1 = (cs_pos_t)-du2;
    *v2 = (cs_pos_t)du1;
    /* End direction in the (U, V) frame: (e.U, e.V), exact in int64 (< 2^59), then scaled down
     * into cs_arc_build's int32 inputs (it renormalises; only the direction matters). */
    int64_t ec = de1 * du1 + de2 * du2, es = de2 * du1 - de1 * du2;
    while (ec >= ((int64_t)1 << 30) || ec <= -((int64_t)1 << 30) || es >= ((int64_t)1 << 30) ||
           es <= -((int64_t)1 << 30)) {
        ec = cs_fixed_round_shift64(ec, 1);
        es = cs_fixed_round_shift64(es, 1);
    }
    return cs_arc_build(&c, &u, &v, CS_PARAM_ONE, 0, (cs_param_t)ec, (cs_param_t)es, ccw, out, n);
}
