/* test_arc: cs_arc_build against the exact ellipse, in double precision. Every piece is evaluated
 * as a rational quadratic in double from its fixed-point control points and weights, and every
 * sampled point must lie on the ellipse C + U cos(phi) + V sin(phi) within 2 LSB (2/65536 mm).
 * The sweep is measured back from the pieces (signed angle summed along the samples). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "cs_arc.h"

#define LSB     (1.0 / 65536.0) /* mm */
#define SAMPLES 64
#define PI      3.14159265358979323846

typedef struct {
    double x, y, z;
} d3;

static d3 d3_of(const cs_vec3_t *p)
{
    d3 r = {p->x * LSB, p->y * LSB, p->z * LSB};
    return r;
}
static d3 d3_add(d3 a, d3 b)
{
    d3 r = {a.x + b.x, a.y + b.y, a.z + b.z};
    return r;
}
static d3 d3_sub(d3 a, d3 b)
{
    d3 r = {a.x - b.x, a.y - b.y, a.z - b.z};
    return r;
}
static d3 d3_scale(d3 a, double s)
{
    d3 r = {a.x * s, a.y * s, a.z * s};
    return r;
}
static double d3_dot(d3 a, d3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static double d3_len(d3 a)
{
    return sqrt(d3_dot(a, a));
}

/* The rational quadratic sum(B_i w_i P_i) / sum(B_i w_i), from the fixed-point data. */
static d3 eval_rq(const cs_bezier_t *b, double t)
{
    double s = 1.0 - t;
    double bw[3] = {s * s * b->w[0], 2 * s * t * b->w[1], t * t * b->w[2]};
    d3 num = {0, 0, 0};
    double den = 0;
    for (int i = 0; i < 3; i++) {
        num = d3_add(num, d3_scale(d3_of(&b->p[i]), bw[i]));
        den += bw[i];
    }
    return d3_scale(num, 1.0 / den);
}

typedef struct {
    d3 c, u, v;
} ellipse;

static d3 ell_at(const ellipse *e, double phi)
{
    return d3_add(e->c, d3_add(d3_scale(e->u, cos(phi)), d3_scale(e->v, sin(phi))));
}

/* Parameter angle of X: solve [U V](c, s) = X - C in the plane (Gram system), atan2. */
static double ell_angle(const ellipse *e, d3 x)
{
    d3 r = d3_sub(x, e->c);
    double uu = d3_dot(e->u, e->u), uv = d3_dot(e->u, e->v), vv = d3_dot(e->v, e->v);
    double ru = d3_dot(r, e->u), rv = d3_dot(r, e->v);
    double det = uu * vv - uv * uv;
    double c = (ru * vv - rv * uv) / det, s = (rv * uu - ru * uv) / det;
    return atan2(s, c);
}

/* Distance from X to the ellipse: Newton on (E(phi) - X).E'(phi) = 0 from the angle above. */
static double ell_dist(const ellipse *e, d3 x)
{
    double phi = ell_angle(e, x);
    for (int it = 0; it < 20; it++) {
        d3 p = ell_at(e, phi);
        d3 d1 = d3_add(d3_scale(e->u, -sin(phi)), d3_scale(e->v, cos(phi)));
        d3 d2 = d3_sub(e->c, p); /* E'' = -(E - C) */
        d3 r = d3_sub(p, x);
        double g = d3_dot(r, d1), gp = d3_dot(d1, d1) + d3_dot(r, d2);
        if (gp <= 0)
            break;
        double step = g / gp;
        phi -= step;
        if (fabs(step) < 1e-15)
            break;
    }
    return d3_len(d3_sub(ell_at(e, phi), x));
}

static cs_param_t q30(double v)
{
    return (cs_param_t)lround(v * 1073741824.0);
}

static cs_vec3_t vmm(double x, double y, double z)
{
    return cs_fixed_vec((cs_pos_t)lround(x * 65536.0), (cs_pos_t)lround(y * 65536.0),
                        (cs_pos_t)lround(z * 65536.0));
}

static double wrap_pi(double a)
{
    while (a > PI)
        a -= 2 * PI;
    while (a <= -PI)
        a += 2 * PI;
    return a;
}

/* Build the arc and check everything a user would: pieces are rational quadratics <= 90 deg,
 * weights are cos(half-sweep), every point is on the ellipse within tol_lsb, endpoints are the
 * requested ones within 1 LSB, joins are exact and the measured sweep is the requested one. */
static void check_arc(cs_vec3_t c, cs_vec3_t u, cs_vec3_t v, double a0_deg, double sweep_deg,
                      bool ccw, double tol_lsb)
{
    double a0 = a0_deg * PI / 180, a1 = (a0_deg + (ccw ? sweep_deg : -sweep_deg)) * PI / 180;
    cs_param_t c0 = q30(cos(a0)), s0 = q30(sin(a0)), c1 = q30(cos(a1)), s1 = q30(sin(a1));
    if (sweep_deg == 360.0) {
        c1 = c0;
        s1 = s0;
    }
    cs_bezier_t out[CS_ARC_MAX_SEGMENTS];
    unsigned n = 99;
    assert_int_equal(cs_arc_build(&c, &u, &v, c0, s0, c1, s1, ccw, out, &n), CS_OK);
    assert_true(n >= 1 && n <= CS_ARC_MAX_SEGMENTS);

    ellipse e = {d3_of(&c), d3_of(&u), d3_of(&v)};
    /* Requested endpoints from the quantised directions, normalised in double. */
    double l0 = hypot(c0, s0), l1 = hypot(c1, s1);
    d3 want0 = d3_add(e.c, d3_add(d3_scale(e.u, c0 / l0), d3_scale(e.v, s0 / l0)));
    d3 want1 = d3_add(e.c, d3_add(d3_scale(e.u, c1 / l1), d3_scale(e.v, s1 / l1)));
    d3 got0 = d3_of(&out[0].p[0]), got1 = d3_of(&out[n - 1].p[2]);
    assert_true(fabs(got0.x - want0.x) <= LSB && fabs(got0.y - want0.y) <= LSB &&
                fabs(got0.z - want0.z) <= LSB);
    assert_true(fabs(got1.x - want1.x) <= LSB && fabs(got1.y - want1.y) <= LSB &&
                fabs(got1.z - want1.z) <= LSB);

    /* Angles measured from points carry their LSB errors: up to (2 LSB / smallest radius) rad,
     * the smallest radius being the smaller singular value of [U V]. */
    double uu = d3_dot(e.u, e.u), uvd = d3_dot(e.u, e.v), vvd = d3_dot(e.v, e.v);
    double rmin = sqrt((uu + vvd - sqrt((uu - vvd) * (uu - vvd) + 4 * uvd * uvd)) / 2);
    double ang_tol = 1e-6 + 4 * LSB / rmin;
    double total = 0, worst = 0;
    for (unsigned i = 0; i < n; i++) {
        const cs_bezier_t *b = &out[i];
        assert_int_equal(b->degree, 2);
        assert_true(b->rational);
        assert_int_equal(b->w[0], CS_WEIGHT_ONE);
        assert_int_equal(b->w[2], CS_WEIGHT_ONE);
        assert_true(b->w[1] >= CS_WEIGHT_MIN && b->w[1] <= CS_WEIGHT_ONE);
        if (i > 0) /* C0 joins, exactly */
            assert_memory_equal(&out[i - 1].p[2], &b->p[0], sizeof(cs_vec3_t));
        double piece = 0, prev = ell_angle(&e, eval_rq(b, 0.0));
        for (int k = 0; k <= SAMPLES; k++) {
            d3 x = eval_rq(b, (double)k / SAMPLES);
            double dist = ell_dist(&e, x) / LSB;
            if (dist > worst)
                worst = dist;
            double ang = ell_angle(&e, x);
            piece += wrap_pi(ang - prev);
            prev = ang;
        }
        /* Each piece spans at most 90 degrees, turning the requested way; its middle weight is
         * cos(half its sweep) (w is a property of the unit-circle piece, measured here). */
        assert_true(fabs(piece) <= PI / 2 + ang_tol);
        if (sweep_deg > 0)
            assert_true(ccw ? piece > 0 : piece < 0);
        double w = b->w[1] / 1073741824.0;
        assert_true(fabs(w - cos(piece / 2)) < ang_tol);
        total += piece;
    }
    if (getenv("CS_TEST_VERBOSE"))
        printf("arc sweep %6.1f %s: %u pieces, worst distance %.3f LSB\n", sweep_deg,
               ccw ? "ccw" : "cw ", n, worst);
    assert_true(worst <= tol_lsb);
    double want_sweep = (ccw ? 1 : -1) * sweep_deg * PI / 180;
    /* The directions are quantised to Q1.30 (2^-30 rad), far below ang_tol. */
    assert_true(fabs(total - want_sweep) < ang_tol);
}

static const double sweeps[] = {1, 89, 90, 91, 180, 270, 359, 360};

static void test_circle_all_sweeps(void **state)
{
    (void)state;
    cs_vec3_t c = vmm(10, -20, 0), u = vmm(50, 0, 0), v = vmm(0, 50, 0);
    for (size_t i = 0; i < sizeof sweeps / sizeof sweeps[0]; i++) {
        for (int dir = 0; dir < 2; dir++) {
            check_arc(c, u, v, 0, sweeps[i], dir == 0, 2.0);
            check_arc(c, u, v, 37.5, sweeps[i], dir == 0, 2.0);
            check_arc(c, u, v, -123, sweeps[i], dir == 0, 2.0);
        }
    }
}

static void test_piece_counts(void **state)
{
    (void)state;
    cs_vec3_t c = vmm(0, 0, 0), u = vmm(10, 0, 0), v = vmm(0, 10, 0);
    /* Sweep -> pieces: bisection gives 1 (<= 90), 2 (<= 180) or 4 (> 180) pieces. */
    const struct {
        double deg;
        unsigned n;
    } cases[] = {{1, 1}, {90, 1}, {91, 2}, {180, 2}, {181, 4}, {270, 4}, {360, 4}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        double a1 = cases[i].deg * PI / 180;
        cs_bezier_t out[CS_ARC_MAX_SEGMENTS];
        unsigned n = 0;
        cs_param_t c1 = q30(cos(a1)), s1 = q30(sin(a1));
        if (cases[i].deg == 360) {
            c1 = q30(1);
            s1 = 0;
        }
        assert_int_equal(cs_arc_build(&c, &u, &v, q30(1), 0, c1, s1, true, out, &n), CS_OK);
        assert_int_equal(n, cases[i].n);
    }
}

static void test_tiny_and_large(void **state)
{
    (void)state;
    /* 1 um radius: the whole circle is 65 LSB across; every point still within 2 LSB. */
    cs_vec3_t c = vmm(-1234.5, 999.25, 3), u = vmm(0.001, 0, 0), v = vmm(0, 0.001, 0);
    for (size_t i = 0; i < sizeof sweeps / sizeof sweeps[0]; i++) {
        check_arc(c, u, v, 10, sweeps[i], true, 2.0);
        check_arc(c, u, v, 10, sweeps[i], false, 2.0);
    }
    /* 2 m radius centred near the origin: control points reach 2000 * sqrt(2) mm. */
    c = vmm(100, -50, 0);
    u = vmm(2000, 0, 0);
    v = vmm(0, 2000, 0);
    for (size_t i = 0; i < sizeof sweeps / sizeof sweeps[0]; i++) {
        check_arc(c, u, v, 45, sweeps[i], true, 2.0);
        check_arc(c, u, v, 200, sweeps[i], false, 2.0);
    }
}

static void test_rotated_ellipse_3d(void **state)
{
    (void)state;
    /* Conjugate semi-axes, neither axis-aligned nor perpendicular, in a tilted plane. */
    cs_vec3_t c = vmm(12.5, -7.25, 30), u = vmm(80, 35, -20), v = vmm(-10, 40, 25);
    for (size_t i = 0; i < sizeof sweeps / sizeof sweeps[0]; i++) {
        check_arc(c, u, v, 0, sweeps[i], true, 2.0);
        check_arc(c, u, v, 71, sweeps[i], false, 2.0);
        check_arc(c, u, v, -170, sweeps[i], true, 2.0);
    }
    /* SVG-style rotated ellipse in XY: rx = 300, ry = 120, rotated 30 degrees. */
    double r = 30 * PI / 180;
    u = vmm(300 * cos(r), 300 * sin(r), 0);
    v = vmm(-120 * sin(r), 120 * cos(r), 0);
    for (size_t i = 0; i < sizeof sweeps / sizeof sweeps[0]; i++) {
        check_arc(c, u, v, 15, sweeps[i], true, 2.0);
        check_arc(c, u, v, 15, sweeps[i], false, 2.0);
    }
}

/* Circles in each G-code plane (G17 XY, G18 ZX, G19 YZ): U, V along the plane's axes. */
static void test_planes(void **state)
{
    (void)state;
    cs_vec3_t c = vmm(5, 6, 7);
    cs_vec3_t uv[3][2] = {{vmm(25, 0, 0), vmm(0, 25, 0)},
                          {vmm(0, 0, 25), vmm(25, 0, 0)},
                          {vmm(0, 25, 0), vmm(0, 0, 25)}};
    for (int p = 0; p < 3; p++) {
        check_arc(c, uv[p][0], uv[p][1], 30, 120, true, 2.0);
        check_arc(c, uv[p][0], uv[p][1], 30, 300, false, 2.0);
        check_arc(c, uv[p][0], uv[p][1], 30, 360, true, 2.0);
    }
}

/* Random arcs (fixed-seed xorshift): random centre, axes, start and sweep. */
static uint64_t rng = 0x9E3779B97F4A7C15u;
static double rnd(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

static void test_random_arcs(void **state)
{
    (void)state;
    for (int i = 0; i < 300; i++) {
        double rad = 0.01 + rnd() * 900;
        cs_vec3_t c = vmm((rnd() - 0.5) * 2000, (rnd() - 0.5) * 2000, (rnd() - 0.5) * 200);
        cs_vec3_t u = vmm((rnd() - 0.5) * rad, (rnd() - 0.5) * rad, (rnd() - 0.5) * rad);
        cs_vec3_t v = vmm((rnd() - 0.5) * rad, (rnd() - 0.5) * rad, (rnd() - 0.5) * rad);
        /* skip nearly parallel axes: the ellipse degenerates and the angle is ill-defined */
        d3 du = d3_of(&u), dv = d3_of(&v);
        double cosang = d3_dot(du, dv) / (d3_len(du) * d3_len(dv));
        if (fabs(cosang) > 0.95)
            continue;
        double sweep = 0.5 + rnd() * 359;
        check_arc(c, u, v, rnd() * 360 - 180, sweep, rnd() < 0.5, 2.0);
    }
}

/* Extreme inputs (directions of any int32 length, axes and centre anywhere in range): either a
 * clean error or pieces whose every control point and weight is in range, with exact joins.
 * Run under UBSan this also shows that no intermediate overflows. */
static void test_extreme_inputs(void **state)
{
    (void)state;
    int built = 0;
    for (int i = 0; i < 20000; i++) {
        int32_t d[4];
        for (int k = 0; k < 4; k++) {
            int sh = (int)(rnd() * 32); /* lengths from 1 to 2^31 */
            d[k] = (int32_t)((rnd() - 0.5) * 2 * ldexp(1.0, sh));
        }
        cs_vec3_t c = {(cs_pos_t)((rnd() - 0.5) * 2 * CS_POS_LIMIT), 0, 0};
        cs_vec3_t u = {(cs_pos_t)((rnd() - 0.5) * 2 * CS_POS_LIMIT),
                       (cs_pos_t)((rnd() - 0.5) * 2 * CS_POS_LIMIT), 0};
        cs_vec3_t v = {(cs_pos_t)((rnd() - 0.5) * 2 * CS_POS_LIMIT), 0,
                       (cs_pos_t)((rnd() - 0.5) * 2 * CS_POS_LIMIT)};
        if (i % 3 == 0) { /* small arcs near the middle: mostly successes */
            c = cs_fixed_vec(0, 0, 0);
            u.x /= 4, u.y /= 4, v.x /= 4, v.z /= 4;
        }
        cs_bezier_t out[CS_ARC_MAX_SEGMENTS];
        unsigned n = 0;
        cs_err_t e = cs_arc_build(&c, &u, &v, d[0], d[1], d[2], d[3], rnd() < 0.5, out, &n);
        if (e != CS_OK) {
            assert_true(e == CS_ERR_RANGE || e == CS_ERR_DEGENERATE || e == CS_ERR_OVERFLOW);
            continue;
        }
        assert_true(n >= 1 && n <= CS_ARC_MAX_SEGMENTS);
        built++;
        for (unsigned j = 0; j < n; j++) {
            for (int k = 0; k < 3; k++)
                assert_true(cs_fixed_vec_ok(&out[j].p[k]));
            assert_true(out[j].w[1] >= CS_WEIGHT_MIN && out[j].w[1] <= CS_WEIGHT_ONE);
            if (j > 0)
                assert_memory_equal(&out[j - 1].p[2], &out[j].p[0], sizeof(cs_vec3_t));
        }
    }
    if (getenv("CS_TEST_VERBOSE"))
        printf("extreme inputs: %d of 20000 built\n", built);
    assert_true(built >= 2000); /* the check above is not vacuous */
}

static void test_errors(void **state)
{
    (void)state;
    cs_vec3_t c = vmm(0, 0, 0), u = vmm(10, 0, 0), v = vmm(0, 10, 0);
    cs_bezier_t out[CS_ARC_MAX_SEGMENTS];
    unsigned n = 0;
    assert_int_equal(cs_arc_build(&c, &u, &v, 0, 0, q30(1), 0, true, out, &n), CS_ERR_DEGENERATE);
    assert_int_equal(cs_arc_build(&c, &u, &v, q30(1), 0, 0, 0, true, out, &n), CS_ERR_DEGENERATE);
    assert_int_equal(cs_arc_build(NULL, &u, &v, q30(1), 0, 0, q30(1), true, out, &n), CS_ERR_ARG);
    assert_int_equal(cs_arc_build(&c, &u, &v, q30(1), 0, 0, q30(1), true, NULL, &n), CS_ERR_ARG);
    assert_int_equal(cs_arc_build(&c, &u, &v, q30(1), 0, 0, q30(1), true, out, NULL), CS_ERR_ARG);
    /* Centre or axes outside the coordinate range. */
    cs_vec3_t far = cs_fixed_vec(CS_POS_LIMIT + 1, 0, 0);
    assert_int_equal(cs_arc_build(&far, &u, &v, q30(1), 0, 0, q30(1), true, out, &n), CS_ERR_RANGE);
    assert_int_equal(cs_arc_build(&c, &far, &v, q30(1), 0, 0, q30(1), true, out, &n), CS_ERR_RANGE);
    /* The arc (x <= 4000 mm) fits but its middle control point, at r / cos 45 = 707 mm from
     * the centre, does not (x = 4207 mm > 4096 mm). */
    cs_vec3_t c2 = vmm(3500, 0, 0), u2 = vmm(500, 0, 0), v2 = vmm(0, 500, 0);
    double h = sqrt(0.5);
    assert_int_equal(cs_arc_build(&c2, &u2, &v2, q30(h), q30(-h), q30(h), q30(h), true, out, &n),
                     CS_ERR_RANGE);
    /* The same circle from 45 to 135 degrees stays inside. */
    assert_int_equal(cs_arc_build(&c2, &u2, &v2, q30(h), q30(h), q30(-h), q30(h), true, out, &n),
                     CS_OK);
    /* Inputs of any length are renormalised: a direction given with length 0.001 works. */
    assert_int_equal(cs_arc_build(&c, &u, &v, q30(0.001), 0, 0, q30(0.001), true, out, &n), CS_OK);
    assert_int_equal(n, 1);
    d3 end = d3_of(&out[0].p[2]);
    assert_true(fabs(end.x) <= LSB && fabs(end.y - 10) <= LSB);
}

/* G2/G3 in G17/G18/G19 through cs_arc_gcode: radius from the start, direction of the end, the
 * turning sense seen from the plane's normal, the third coordinate kept. */
static void check_gcode(cs_arc_plane_t plane, double a0_deg, double a1_deg, bool ccw,
                        double want_sweep_deg)
{
    const double r = 37.25, cc1 = 12.5, cc2 = -40, h = 7.75;
    /* (first, second, normal) -> (x, y, z) for each plane */
    int ax1 = plane == CS_ARC_PLANE_XY ? 0 : plane == CS_ARC_PLANE_ZX ? 2 : 1;
    int ax2 = plane == CS_ARC_PLANE_XY ? 1 : plane == CS_ARC_PLANE_ZX ? 0 : 2;
    int axn = 3 - ax1 - ax2;
    double cv[3], sv[3], ev[3];
    cv[ax1] = cc1, cv[ax2] = cc2, cv[axn] = -3; /* the centre's third coordinate is ignored */
    sv[ax1] = cc1 + r * cos(a0_deg * PI / 180), sv[ax2] = cc2 + r * sin(a0_deg * PI / 180);
    ev[ax1] = cc1 + 2 * r * cos(a1_deg * PI / 180), ev[ax2] = cc2 + 2 * r * sin(a1_deg * PI / 180);
    sv[axn] = ev[axn] = h;
    cs_vec3_t c = vmm(cv[0], cv[1], cv[2]), s = vmm(sv[0], sv[1], sv[2]),
              e = vmm(ev[0], ev[1], ev[2]);
    cs_bezier_t out[CS_ARC_MAX_SEGMENTS];
    unsigned n = 0;
    assert_int_equal(cs_arc_gcode(&c, &s, &e, plane, ccw, out, &n), CS_OK);
    /* The exact circle of the quantised data, in double. */
    d3 C = d3_of(&c), S = d3_of(&s), E = d3_of(&e);
    double Ca[3] = {C.x, C.y, C.z}, Sa[3] = {S.x, S.y, S.z}, Ea[3] = {E.x, E.y, E.z};
    Ca[axn] = Sa[axn];
    double U[3] = {0, 0, 0}, V[3] = {0, 0, 0};
    U[ax1] = Sa[ax1] - Ca[ax1], U[ax2] = Sa[ax2] - Ca[ax2];
    V[ax1] = -U[ax2], V[ax2] = U[ax1];
    ellipse el = {{Ca[0], Ca[1], Ca[2]}, {U[0], U[1], U[2]}, {V[0], V[1], V[2]}};
    double rad = hypot(U[ax1], U[ax2]);
    double ed1 = Ea[ax1] - Ca[ax1], ed2 = Ea[ax2] - Ca[ax2], el2 = hypot(ed1, ed2);
    double want_end[3];
    want_end[ax1] = Ca[ax1] + rad * ed1 / el2, want_end[ax2] = Ca[ax2] + rad * ed2 / el2;
    want_end[axn] = Sa[axn];
    d3 got0 = d3_of(&out[0].p[0]), got1 = d3_of(&out[n - 1].p[2]);
    assert_true(d3_len(d3_sub(got0, S)) <= LSB);
    d3 we = {want_end[0], want_end[1], want_end[2]};
    assert_true(d3_len(d3_sub(got1, we)) <= 2 * LSB);
    double total = 0;
    for (unsigned i = 0; i < n; i++) {
        double prev = ell_angle(&el, eval_rq(&out[i], 0));
        for (int k = 0; k < 3; k++) /* every control point at the start's height */
            assert_int_equal(axn == 0   ? out[i].p[k].x
                             : axn == 1 ? out[i].p[k].y
                                        : out[i].p[k].z,
                             axn == 0   ? s.x
                             : axn == 1 ? s.y
                                        : s.z);
        for (int k = 0; k <= SAMPLES; k++) {
            d3 x = eval_rq(&out[i], (double)k / SAMPLES);
            assert_true(ell_dist(&el, x) <= 2 * LSB);
            double ang = ell_angle(&el, x);
            total += wrap_pi(ang - prev);
            prev = ang;
        }
    }
    /* V = U turned +90 degrees about the normal, so the angle measured in (U, V) is the
     * right-handed angle about the normal: positive for G3. */
    assert_true(fabs(total - want_sweep_deg * PI / 180) < 1e-6);
}

static void test_gcode_planes(void **state)
{
    (void)state;
    const cs_arc_plane_t planes[3] = {CS_ARC_PLANE_XY, CS_ARC_PLANE_ZX, CS_ARC_PLANE_YZ};
    for (int p = 0; p < 3; p++) {
        check_gcode(planes[p], 0, 90, true, 90);    /* G3 quarter: first axis to second */
        check_gcode(planes[p], 0, 90, false, -270); /* G2 the long way round */
        check_gcode(planes[p], 30, 30, true, 360);  /* full circle */
        check_gcode(planes[p], 30, 30, false, -360);
        check_gcode(planes[p], -100, 45, true, 145);
        check_gcode(planes[p], -100, 45, false, -215);
        check_gcode(planes[p], 10, 11, true, 1);
        check_gcode(planes[p], 179, -179, true, 2);
    }
    /* G17, the textbook case: from (10, 0) around the origin to (0, 10). G3 is one quarter
     * piece through (7.07, 7.07); G2 goes through (0, -10). */
    cs_vec3_t c = vmm(0, 0, 0), s = vmm(10, 0, 1), e = vmm(0, 10, 1);
    cs_bezier_t out[CS_ARC_MAX_SEGMENTS];
    unsigned n = 0;
    assert_int_equal(cs_arc_gcode(&c, &s, &e, CS_ARC_PLANE_XY, true, out, &n), CS_OK);
    assert_int_equal(n, 1);
    d3 mid = eval_rq(&out[0], 0.5);
    assert_true(fabs(mid.x - sqrt(50)) <= LSB && fabs(mid.y - sqrt(50)) <= LSB);
    assert_int_equal(cs_arc_gcode(&c, &s, &e, CS_ARC_PLANE_XY, false, out, &n), CS_OK);
    assert_int_equal(n, 4);
    /* After two of the four 67.5-degree pieces: 135 degrees clockwise, at (-7.07, -7.07). */
    d3 q = d3_of(&out[1].p[2]);
    assert_true(fabs(q.x + sqrt(50)) <= LSB && fabs(q.y + sqrt(50)) <= LSB);
}

static void test_gcode_errors(void **state)
{
    (void)state;
    cs_vec3_t c = vmm(0, 0, 0), s = vmm(10, 0, 1), e = vmm(0, 10, 2);
    cs_bezier_t out[CS_ARC_MAX_SEGMENTS];
    unsigned n = 0;
    assert_int_equal(cs_arc_gcode(&c, &s, &e, CS_ARC_PLANE_XY, true, out, &n), CS_ERR_ARG);
    e.z = s.z;
    assert_int_equal(cs_arc_gcode(&c, &s, &e, (cs_arc_plane_t)20, true, out, &n), CS_ERR_ARG);
    cs_vec3_t on = vmm(0, 0, 1);
    assert_int_equal(cs_arc_gcode(&c, &on, &e, CS_ARC_PLANE_XY, true, out, &n), CS_ERR_DEGENERATE);
    assert_int_equal(cs_arc_gcode(&c, &s, &on, CS_ARC_PLANE_XY, true, out, &n), CS_ERR_DEGENERATE);
    /* In G18 the Z offset is in plane: start and end heights are their Y. */
    cs_vec3_t s18 = vmm(0, 5, 10), e18 = vmm(10, 5, 0);
    assert_int_equal(cs_arc_gcode(&c, &s18, &e18, CS_ARC_PLANE_ZX, true, out, &n), CS_OK);
    assert_int_equal(n, 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_circle_all_sweeps),
        cmocka_unit_test(test_piece_counts),
        cmocka_unit_test(test_tiny_and_large),
        cmocka_unit_test(test_rotated_ellipse_3d),
        cmocka_unit_test(test_planes),
        cmocka_unit_test(test_random_arcs),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_extreme_inputs),
        cmocka_unit_test(test_gcode_planes),
        cmocka_unit_test(test_gcode_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
