/* test_svgpath: the SVG path data parser (host/cs_svgpath.c) against geometry worked out by hand
 * from each path string and, for arcs, against the SVG 1.1 F.6.5 reference conversion written
 * here in double with the spec's own angle formulas.
 * Tolerances: a parsed control point is the exact value rounded once to the nearest LSB, so it
 * must be within 0.5 LSB (2^-17 mm) of the expected value. Arc points: centre and both semi-axes
 * are rounded once (<= 0.5 LSB per coordinate: <= 1.71 LSB on the curve) and cs_arc_build adds
 * <= 2 LSB, so every point of every arc piece must lie within 4 LSB of the exact ellipse. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_ref.h"
#include "cs_svgpath.h"

#define LSB     (1.0 / 65536.0)
#define PT_TOL  (0.5 * LSB + 1e-12)
#define ARC_TOL (4.0 * LSB)
#define PI      3.14159265358979323846

static cs_path_t P;
static cs_path_diag_t D;

static cs_err_t parse_with(const char *d, const cs_path_affine_t *m)
{
    cs_path_free(&P);
    cs_path_init(&P);
    memset(&D, 0, sizeof D);
    cs_svgpath_opts_t o;
    cs_svgpath_opts_init(&o, "t.path");
    if (m)
        o.xform = *m;
    return cs_svgpath_parse(d, strlen(d), &o, &P, &D);
}

static cs_err_t parse(const char *d)
{
    return parse_with(d, NULL);
}

static int setup(void **state)
{
    (void)state;
    cs_path_init(&P);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    cs_path_free(&P);
    return 0;
}

static void near_pt(const cs_vec3_t *p, double x, double y, double tol)
{
    double px = p->x * LSB, py = p->y * LSB;
    if (fabs(px - x) > tol || fabs(py - y) > tol || p->z != 0)
        fail_msg("point (%.9f, %.9f) expected (%.9f, %.9f) within %.3g mm", px, py, x, y, tol);
}

/* Element i is of kind/degree with the given control points (x0 y0 x1 y1 ...). */
static void expect_elem(size_t i, cs_path_kind_t kind, unsigned degree, unsigned subpath,
                        const double *xy)
{
    assert_true(i < P.n);
    const cs_path_elem_t *e = &P.elems[i];
    assert_int_equal(e->kind, kind);
    assert_int_equal(e->curve.degree, degree);
    assert_int_equal(e->subpath, subpath);
    assert_false(e->curve.rational);
    for (unsigned k = 0; k <= degree; k++)
        near_pt(&e->curve.p[k], xy[2 * k], xy[2 * k + 1], PT_TOL);
}

#define ELEM(i, kind, deg, sub, ...)                                                               \
    do {                                                                                           \
        const double xy_[] = {__VA_ARGS__};                                                        \
        assert_int_equal(sizeof xy_ / sizeof xy_[0], 2 * ((deg) + 1));                             \
        expect_elem((i), (kind), (deg), (sub), xy_);                                               \
    } while (0)

/* Every element starts exactly (to the LSB) where the previous one of its subpath ended. */
static void check_continuity(void)
{
    for (size_t i = 1; i < P.n; i++) {
        const cs_path_elem_t *a = &P.elems[i - 1], *b = &P.elems[i];
        if (a->subpath != b->subpath)
            continue;
        const cs_vec3_t *e = &a->curve.p[a->curve.degree];
        if (e->x != b->curve.p[0].x || e->y != b->curve.p[0].y)
            fail_msg("gap between elements %zu and %zu", i - 1, i);
    }
}

static void test_move_line(void **state)
{
    (void)state;
    assert_int_equal(parse("M10 20 L30 40 l5 -5"), CS_OK);
    assert_int_equal(P.n, 2);
    ELEM(0, CS_PATH_LINE, 1, 0, 10, 20, 30, 40);
    ELEM(1, CS_PATH_LINE, 1, 0, 30, 40, 35, 35);
    /* Implicit lineto after moveto, absolute and relative (resvg M-L-L-implicit, m (m) (m)). */
    assert_int_equal(parse("M 30 40 L 150 160 100 50"), CS_OK);
    assert_int_equal(P.n, 2);
    ELEM(1, CS_PATH_LINE, 1, 0, 150, 160, 100, 50);
    assert_int_equal(parse("M1 2 3 4 5 6"), CS_OK);
    assert_int_equal(P.n, 2);
    ELEM(0, CS_PATH_LINE, 1, 0, 1, 2, 3, 4);
    ELEM(1, CS_PATH_LINE, 1, 0, 3, 4, 5, 6);
    assert_int_equal(parse("m 30 40 110 120 -20 -130"), CS_OK);
    assert_int_equal(P.n, 2);
    ELEM(0, CS_PATH_LINE, 1, 0, 30, 40, 140, 160);
    ELEM(1, CS_PATH_LINE, 1, 0, 140, 160, 120, 30);
    /* H and V, absolute, relative and repeated. */
    assert_int_equal(parse("M 30 40 H 50 150 V 10 v 5 h -20"), CS_OK);
    assert_int_equal(P.n, 5);
    ELEM(0, CS_PATH_LINE, 1, 0, 30, 40, 50, 40);
    ELEM(1, CS_PATH_LINE, 1, 0, 50, 40, 150, 40);
    ELEM(2, CS_PATH_LINE, 1, 0, 150, 40, 150, 10);
    ELEM(3, CS_PATH_LINE, 1, 0, 150, 10, 150, 15);
    ELEM(4, CS_PATH_LINE, 1, 0, 150, 15, 130, 15);
    check_continuity();
}

static void test_numbers(void **state)
{
    (void)state;
    /* Exponents, leading dot, ".5.5" = .5 .5, "-1-2" = -1 -2, '+' signs, trailing dot. */
    assert_int_equal(parse("M1e1-2e-1L.5.5l+1.5E+1-.25 L1. 2.,3e0,4E-0"), CS_OK);
    assert_int_equal(P.n, 4);
    ELEM(0, CS_PATH_LINE, 1, 0, 10, -0.2, 0.5, 0.5);
    ELEM(1, CS_PATH_LINE, 1, 0, 0.5, 0.5, 15.5, 0.25);
    ELEM(2, CS_PATH_LINE, 1, 0, 15.5, 0.25, 1, 2);
    ELEM(3, CS_PATH_LINE, 1, 0, 1, 2, 3, 4);
    assert_int_equal(parse("M-1-2L-3-4"), CS_OK);
    ELEM(0, CS_PATH_LINE, 1, 0, -1, -2, -3, -4);
    /* Commas and every kind of white space; L's second pair repeats after a comma. */
    assert_int_equal(parse(" \t\r\nM 0,0 L 1 , 2,3\t4\n"), CS_OK);
    assert_int_equal(P.n, 2);
    ELEM(1, CS_PATH_LINE, 1, 0, 1, 2, 3, 4);
    /* A value that is not a whole number of LSB is rounded to the nearest. */
    assert_int_equal(parse("M 0.1 0 L 1e-5 0"), CS_OK);
    ELEM(0, CS_PATH_LINE, 1, 0, 0.1, 0, 1e-5, 0);
    /* Exactly the limit is accepted. */
    assert_int_equal(parse("M -4096 4096 L 4096 -4096"), CS_OK);
    ELEM(0, CS_PATH_LINE, 1, 0, -4096, 4096, 4096, -4096);
}

static void test_cubic(void **state)
{
    (void)state;
    /* resvg M-C-S: S reflects the previous C's second control point about the current point:
     * 2 (100, 90) - (171, 45) = (29, 135). */
    assert_int_equal(parse("M 30 40 C 16 137 171 45 100 90 S 171 45 180 155"), CS_OK);
    assert_int_equal(P.n, 2);
    ELEM(0, CS_PATH_CUBIC, 3, 0, 30, 40, 16, 137, 171, 45, 100, 90);
    ELEM(1, CS_PATH_CUBIC, 3, 0, 100, 90, 29, 135, 171, 45, 180, 155);
    /* S with no C before it: the first control point is the current point (resvg M-S). */
    assert_int_equal(parse("M 30 40 S 171 45 180 155"), CS_OK);
    ELEM(0, CS_PATH_CUBIC, 3, 0, 30, 40, 30, 40, 171, 45, 180, 155);
    /* S S: the second S reflects the first S's control (160, 45)... about (160, 140). */
    assert_int_equal(parse("M 30 40 S 160 45 160 140 S 45 160 50 60"), CS_OK);
    ELEM(1, CS_PATH_CUBIC, 3, 0, 160, 140, 160, 235, 45, 160, 50, 60);
    /* Relative c and s (W3C paths-data-01 "Remembrance ribbon": m 200 260 c 50 -40 50 -100
     * 25 -100 s -25 60 25 100): s's control is 2 (225, 160) - (250, 160) = (200, 160). */
    assert_int_equal(parse("m 200 260 c 50 -40 50 -100 25 -100 s -25 60 25 100"), CS_OK);
    ELEM(0, CS_PATH_CUBIC, 3, 0, 200, 260, 250, 220, 250, 160, 225, 160);
    ELEM(1, CS_PATH_CUBIC, 3, 0, 225, 160, 200, 160, 200, 220, 250, 260);
    /* Implicit repeated C (poly-Bézier). */
    assert_int_equal(parse("M0 0 C1 1 2 1 3 0 4 -1 5 -1 6 0"), CS_OK);
    assert_int_equal(P.n, 2);
    ELEM(1, CS_PATH_CUBIC, 3, 0, 3, 0, 4, -1, 5, -1, 6, 0);
    /* S after Q is not a reflection: the first control point is the current point. */
    assert_int_equal(parse("M0 0 Q 5 5 10 0 S 15 5 20 0"), CS_OK);
    ELEM(1, CS_PATH_CUBIC, 3, 0, 10, 0, 10, 0, 15, 5, 20, 0);
    check_continuity();
}

static void test_quadratic(void **state)
{
    (void)state;
    /* resvg M-Q-T: T control = 2 (100, 90) - (171, 45) = (29, 135). */
    assert_int_equal(parse("M 30 40 Q 171 45 100 90 T 160 180"), CS_OK);
    assert_int_equal(P.n, 2);
    ELEM(0, CS_PATH_QUAD, 2, 0, 30, 40, 171, 45, 100, 90);
    ELEM(1, CS_PATH_QUAD, 2, 0, 100, 90, 29, 135, 160, 180);
    /* resvg M-Q-rel-T-rel: q 171 45 50 40 from (30, 40) = control (201, 85), end (80, 80);
     * t 60 80: control 2 (80, 80) - (201, 85) = (-41, 75), end (140, 160). */
    assert_int_equal(parse("M 30 40 q 171 45 50 40 t 60 80"), CS_OK);
    ELEM(0, CS_PATH_QUAD, 2, 0, 30, 40, 201, 85, 80, 80);
    ELEM(1, CS_PATH_QUAD, 2, 0, 80, 80, -41, 75, 140, 160);
    /* resvg M-T-T: a T with no Q before it uses the current point as control; the next T then
     * reflects that control: 2 (40, 140) - (30, 30) = (50, 250). */
    assert_int_equal(parse("M 30 30 T 40 140 T 170 30"), CS_OK);
    ELEM(0, CS_PATH_QUAD, 2, 0, 30, 30, 30, 30, 40, 140);
    ELEM(1, CS_PATH_QUAD, 2, 0, 40, 140, 50, 250, 170, 30);
    /* W3C paths-data-02 sine: q25-100 47 0 then t47 0 repeated. Each control is the previous
     * one reflected about the shared end point: x = x0 + 25, x0 + 22, x0 + 25...; y alternates
     * 196, 396 about the axis y = 296. */
    assert_int_equal(parse("M240 296q25-100 47 0t47 0t47 0t47 0t47 0z"), CS_OK);
    assert_int_equal(P.n, 6);
    for (unsigned k = 0; k < 5; k++) {
        double x0 = 240 + 47.0 * k;
        near_pt(&P.elems[k].curve.p[1], x0 + ((k % 2) ? 22 : 25), (k % 2) ? 396 : 196, PT_TOL);
        near_pt(&P.elems[k].curve.p[2], x0 + 47, 296, PT_TOL);
    }
    ELEM(5, CS_PATH_LINE, 1, 0, 475, 296, 240, 296);
    /* T after a C: no reflection. */
    assert_int_equal(parse("M0 0 C 1 1 2 1 3 0 T 6 0"), CS_OK);
    ELEM(1, CS_PATH_QUAD, 2, 0, 3, 0, 3, 0, 6, 0);
    check_continuity();
}

static void test_close_and_subpaths(void **state)
{
    (void)state;
    /* resvg M-L-Z-L-L: z draws back to (10, 10); the next L starts a new subpath there. */
    assert_int_equal(parse("M 10 10 L 10 20 L 20 10 z L 100 100 L 120 100"), CS_OK);
    assert_int_equal(P.n, 5);
    ELEM(2, CS_PATH_LINE, 1, 0, 20, 10, 10, 10);
    ELEM(3, CS_PATH_LINE, 1, 1, 10, 10, 100, 100);
    ELEM(4, CS_PATH_LINE, 1, 1, 100, 100, 120, 100);
    assert_int_equal(P.nsubpaths, 2);
    /* Z when already at the start draws nothing; Z alone after M draws nothing (resvg M-Z). */
    assert_int_equal(parse("M 0 0 L 10 0 L 0 0 Z"), CS_OK);
    assert_int_equal(P.n, 2);
    assert_int_equal(parse("M 30 40 Z"), CS_OK);
    assert_int_equal(P.n, 0);
    /* resvg M-L-M-Z, M-L-M: the trailing moveto (and its Z) add nothing. */
    assert_int_equal(parse("M 30 40 L 100 150 M 180 30 Z"), CS_OK);
    assert_int_equal(P.n, 1);
    assert_int_equal(parse("M 30 40 L 100 150 M 180 30"), CS_OK);
    assert_int_equal(P.n, 1);
    /* resvg M-L-M-L: two subpaths. */
    assert_int_equal(parse("M 30 40 L 100 150 M 180 30 L 120 140"), CS_OK);
    assert_int_equal(P.n, 2);
    ELEM(1, CS_PATH_LINE, 1, 1, 180, 30, 120, 140);
    /* M M, m M, M m: nothing drawn; m after M is relative to the previous point. */
    assert_int_equal(parse("M 30 40 M 50 60"), CS_OK);
    assert_int_equal(P.n, 0);
    assert_int_equal(parse("m 30 40 M 50 60"), CS_OK);
    assert_int_equal(P.n, 0);
    assert_int_equal(parse("M 10 10 m 5 5 l 1 0"), CS_OK);
    ELEM(0, CS_PATH_LINE, 1, 0, 15, 15, 16, 15);
    /* m after z is relative to the subpath start (W3C paths-data-02: ...z m70 0 ...). */
    assert_int_equal(parse("M372 130Q272 50 422 10zm70 0q50-150-80-90z"), CS_OK);
    assert_int_equal(P.n, 4);
    ELEM(1, CS_PATH_LINE, 1, 0, 422, 10, 372, 130);
    ELEM(2, CS_PATH_QUAD, 2, 1, 442, 130, 492, -20, 362, 40);
    ELEM(3, CS_PATH_LINE, 1, 1, 362, 40, 442, 130);
    /* Empty data and white space only are valid and draw nothing. */
    assert_int_equal(parse(""), CS_OK);
    assert_int_equal(P.n, 0);
    assert_int_equal(parse("  \n\t "), CS_OK);
    assert_int_equal(P.n, 0);
    check_continuity();
}

/* --- arcs ------------------------------------------------------------------------------ */

typedef struct {
    double cx, cy, rx, ry, phi, th1, dth; /* radians */
    bool line, omit;
} ref_arc_t;

/* angle(u, v) of F.6.5.4: sign(ux vy - uy vx) * arccos(u.v / (|u| |v|)). */
static double vangle(double ux, double uy, double vx, double vy)
{
    double c = (ux * vx + uy * vy) / (hypot(ux, uy) * hypot(vx, vy));
    c = c > 1 ? 1 : c < -1 ? -1 : c;
    double a = acos(c);
    return (ux * vy - uy * vx) < 0 ? -a : a;
}

/* SVG 1.1 F.6.5 / F.6.6 exactly as written in the spec. */
static ref_arc_t ref_arc(double x1, double y1, double rx, double ry, double phi_deg, int fa, int fs,
                         double x2, double y2)
{
    ref_arc_t r;
    memset(&r, 0, sizeof r);
    if (x1 == x2 && y1 == y2) {
        r.omit = true;
        return r;
    }
    if (rx == 0 || ry == 0) {
        r.line = true;
        return r;
    }
    rx = fabs(rx);
    ry = fabs(ry);
    double phi = fmod(phi_deg, 360.0) * PI / 180.0, c = cos(phi), s = sin(phi);
    double x1p = c * (x1 - x2) / 2 + s * (y1 - y2) / 2;
    double y1p = -s * (x1 - x2) / 2 + c * (y1 - y2) / 2;
    double lam = x1p * x1p / (rx * rx) + y1p * y1p / (ry * ry);
    if (lam > 1) {
        rx *= sqrt(lam);
        ry *= sqrt(lam);
    }
    double num = rx * rx * ry * ry - rx * rx * y1p * y1p - ry * ry * x1p * x1p;
    double den = rx * rx * y1p * y1p + ry * ry * x1p * x1p;
    double k = num > 0 ? sqrt(num / den) : 0.0;
    if (fa == fs)
        k = -k;
    double cxp = k * rx * y1p / ry, cyp = -k * ry * x1p / rx;
    r.cx = c * cxp - s * cyp + (x1 + x2) / 2;
    r.cy = s * cxp + c * cyp + (y1 + y2) / 2;
    r.rx = rx;
    r.ry = ry;
    r.phi = phi;
    r.th1 = vangle(1, 0, (x1p - cxp) / rx, (y1p - cyp) / ry);
    double dth = vangle((x1p - cxp) / rx, (y1p - cyp) / ry, (-x1p - cxp) / rx, (-y1p - cyp) / ry);
    dth = fmod(dth, 2 * PI);
    if (!fs && dth > 0)
        dth -= 2 * PI;
    else if (fs && dth < 0)
        dth += 2 * PI;
    r.dth = dth;
    return r;
}

/* Distance from (x, y) to the reference ellipse, and the point's own parametric angle. The
 * nearest parameter is searched near that angle: a scan (the distance can have two minima there
 * on a very eccentric ellipse), then golden section around the best sample. */
static double ellipse_dist(const ref_arc_t *a, double x, double y, double *theta)
{
    double c = cos(a->phi), s = sin(a->phi);
    double xp = c * (x - a->cx) + s * (y - a->cy), yp = -s * (x - a->cx) + c * (y - a->cy);
    double th = atan2(yp / a->ry, xp / a->rx);
    const int n = 64;
    const double w = 0.2, step = 2 * w / n;
    double best = HUGE_VAL, bt = th;
    for (int i = 0; i <= n; i++) {
        double t = th - w + step * i;
        double d = hypot(xp - a->rx * cos(t), yp - a->ry * sin(t));
        if (d < best) {
            best = d;
            bt = t;
        }
    }
    double lo = bt - step, hi = bt + step, g = 0.6180339887498949;
    for (int i = 0; i < 80; i++) {
        double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo);
        double d1 = hypot(xp - a->rx * cos(m1), yp - a->ry * sin(m1));
        double d2 = hypot(xp - a->rx * cos(m2), yp - a->ry * sin(m2));
        if (d1 < d2)
            hi = m2;
        else
            lo = m1;
    }
    double t = (lo + hi) / 2;
    if (theta)
        *theta = th;
    return fmin(best, hypot(xp - a->rx * cos(t), yp - a->ry * sin(t)));
}

/* The elements from `first` on are the arc (x1,y1) -> (x2,y2) of the reference: rational
 * quadratic pieces, ends exact, every sampled point on the ellipse within tol, and the
 * parametric angle swept (summed along the samples) equal to the reference's delta-theta. */
static void check_arc(size_t first, size_t count, const ref_arc_t *a, double x1, double y1,
                      double x2, double y2, double tol)
{
    assert_true(first + count <= P.n);
    assert_true(count >= 1 && count <= 4);
    near_pt(&P.elems[first].curve.p[0], x1, y1, PT_TOL);
    near_pt(&P.elems[first + count - 1].curve.p[2], x2, y2, PT_TOL);
    double swept = 0, prev = 0;
    bool have = false;
    for (size_t i = first; i < first + count; i++) {
        const cs_bezier_t *c = &P.elems[i].curve;
        assert_int_equal(P.elems[i].kind, CS_PATH_ARC);
        assert_int_equal(c->degree, 2);
        assert_true(c->rational);
        for (int k = 0; k <= 32; k++) {
            cs_ref_vec_t q = cs_ref_eval(c, k / 32.0);
            double th;
            double d = ellipse_dist(a, q.x, q.y, &th);
            if (d > tol)
                fail_msg("arc piece %zu at t=%d/32: %.3f LSB off the ellipse", i - first, k,
                         d / LSB);
            if (have) {
                double step = remainder(th - prev, 2 * PI);
                swept += step;
            }
            prev = th;
            have = true;
        }
    }
    if (fabs(swept - a->dth) > 1e-3)
        fail_msg("arc sweeps %.6f rad, expected %.6f", swept, a->dth);
}

static void test_arc_basic(void **state)
{
    (void)state;
    /* Flags without separators: rx=1 ry=1 rot=0 large=0 sweep=0 to (1, 1); the circle of
     * radius 1 through (0,0) and (1,1) swept clockwise in angle is centred at (1, 0). */
    assert_int_equal(parse("M0 0 a1 1 0 00 1 1"), CS_OK);
    ref_arc_t a = ref_arc(0, 0, 1, 1, 0, 0, 0, 1, 1);
    assert_true(fabs(a.cx - 1) < 1e-12 && fabs(a.cy) < 1e-12);
    check_arc(0, P.n, &a, 0, 0, 1, 1, ARC_TOL);
    assert_true(fabs(a.dth + PI / 2) < 1e-12);
    /* Sweep 1: centre (0, 1), +90 degrees. */
    assert_int_equal(parse("M0 0 a1 1 0 01 1 1"), CS_OK);
    a = ref_arc(0, 0, 1, 1, 0, 0, 1, 1, 1);
    assert_true(fabs(a.cx) < 1e-12 && fabs(a.cy - 1) < 1e-12);
    check_arc(0, P.n, &a, 0, 0, 1, 1, ARC_TOL);
    /* Large arc, sweep 0: 270 degrees around (0, 1), at least 3 pieces of <= 90 degrees. */
    assert_int_equal(parse("M0,0A1,1,0,1,0,1,1"), CS_OK);
    a = ref_arc(0, 0, 1, 1, 0, 1, 0, 1, 1);
    assert_true(fabs(a.dth + 1.5 * PI) < 1e-12);
    assert_true(P.n >= 3);
    check_arc(0, P.n, &a, 0, 0, 1, 1, ARC_TOL);
    /* A point on the arc: the 270-degree arc passes through (-1, 1), the far side. */
    bool passes = false;
    for (size_t i = 0; i < P.n; i++)
        for (int k = 0; k <= 64; k++) {
            cs_ref_vec_t q = cs_ref_eval(&P.elems[i].curve, k / 64.0);
            if (hypot(q.x + 1, q.y - 1) < 0.05)
                passes = true;
        }
    assert_true(passes);
}

static void test_arc_resvg(void **state)
{
    (void)state;
    /* resvg M-A: radii too small (40, 30) for the chord: scaled up (F.6.6), half ellipse. */
    assert_int_equal(parse("M 30 40 A 40 30 20 1 1 150 100"), CS_OK);
    ref_arc_t a = ref_arc(30, 40, 40, 30, 20, 1, 1, 150, 100);
    assert_true(a.rx > 40);
    assert_true(fabs(fabs(a.dth) - PI) < 1e-6);
    check_arc(0, P.n, &a, 30, 40, 150, 100, ARC_TOL);
    /* resvg M-A-s: the s after an arc has no cubic to reflect: first control = current point. */
    assert_int_equal(parse("M 30 40 A 40 30 20 1 1 150 100 s 20 30 -80 50"), CS_OK);
    ELEM(P.n - 1, CS_PATH_CUBIC, 3, 0, 150, 100, 150, 100, 170, 130, 70, 150);
    /* resvg M-A-t: same for t. */
    assert_int_equal(parse("M 30 40 A 40 30 20 1 1 150 100 t -80 50"), CS_OK);
    ELEM(P.n - 1, CS_PATH_QUAD, 2, 0, 150, 100, 150, 100, 70, 150);
    /* resvg M-L-Z-A: after z the arc starts at the subpath start (10, 50); radius 5 is far too
     * small: a half circle on the chord to (150, 150), centre (80, 100). */
    assert_int_equal(parse("M 10 50 L 10 10 L 50 10 z A 5 5 0 0 1 150 150"), CS_OK);
    a = ref_arc(10, 50, 5, 5, 0, 0, 1, 150, 150);
    /* (The reference's own rounding: F.6.5.2's radicand is ~0 here, its sqrt amplifies.) */
    assert_true(fabs(a.cx - 80) < 1e-5 && fabs(a.cy - 100) < 1e-5);
    assert_true(fabs(a.rx - hypot(140, 100) / 2) < 1e-9);
    assert_int_equal(P.elems[3].subpath, 1);
    check_arc(3, P.n - 3, &a, 10, 50, 150, 150, ARC_TOL);
    check_continuity();
}

static void test_arc_degenerate(void **state)
{
    (void)state;
    /* Zero radius: a straight line (F.6.2). */
    assert_int_equal(parse("M 0 0 A 0 5 0 0 1 10 10"), CS_OK);
    assert_int_equal(P.n, 1);
    ELEM(0, CS_PATH_LINE, 1, 0, 0, 0, 10, 10);
    /* Same end points: the arc is omitted. */
    assert_int_equal(parse("M 5 5 A 10 10 0 1 1 5 5"), CS_OK);
    assert_int_equal(P.n, 0);
    /* Negative radii are taken as absolute values. */
    assert_int_equal(parse("M0 0 A-1 -1 0 0 0 1 1"), CS_OK);
    ref_arc_t a = ref_arc(0, 0, 1, 1, 0, 0, 0, 1, 1);
    check_arc(0, P.n, &a, 0, 0, 1, 1, ARC_TOL);
    /* A huge radius over a short chord: the sagitta is below half an LSB, the arc is its
     * chord (its centre, 1e9 mm away, could not be represented anyway). */
    assert_int_equal(parse("M 0 0 A 1e9 1e9 0 0 1 1 0"), CS_OK);
    assert_int_equal(P.n, 1);
    ELEM(0, CS_PATH_LINE, 1, 0, 0, 0, 1, 0);
    /* Centre outside the range (x = 4156.14) but the arc inside it (down to x = 4056.14):
     * accepted (built without cs_arc_build, which needs the centre in range). */
    assert_int_equal(parse("M 4090 0 A 100 100 0 0 0 4090 150"), CS_OK);
    a = ref_arc(4090, 0, 100, 100, 0, 0, 0, 4090, 150);
    assert_true(a.cx > 4096);
    check_arc(0, P.n, &a, 4090, 0, 4090, 150, ARC_TOL);
    /* A long flat arc of a huge ellipse whose semi-axis (5000 mm) is beyond the range. */
    assert_int_equal(parse("M 0 0 A 5000 100 0 0 1 100 10"), CS_OK);
    a = ref_arc(0, 0, 5000, 100, 0, 0, 1, 100, 10);
    assert_true(a.rx >= 5000);
    check_arc(0, P.n, &a, 0, 0, 100, 10, ARC_TOL);
}

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;

static uint64_t xorshift64(void)
{
    uint64_t x = rng_state;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    return rng_state = x;
}

static double urand(double lo, double hi)
{
    return lo + (hi - lo) * (double)(xorshift64() >> 11) / 9007199254740992.0;
}

/* Largest |coordinate| reached by the reference arc (mm), sampled every 0.1 degree. */
static double ref_extent(const ref_arc_t *a)
{
    double c = cos(a->phi), s = sin(a->phi), e = 0;
    for (int k = 0; k <= 3600; k++) {
        double th = a->th1 + a->dth * k / 3600.0;
        double x = a->cx + a->rx * cos(th) * c - a->ry * sin(th) * s;
        double y = a->cy + a->rx * cos(th) * s + a->ry * sin(th) * c;
        e = fmax(e, fmax(fabs(x), fabs(y)));
    }
    return e;
}

/* Random arcs (fixed seed): in range they match the reference; an arc that itself leaves
 * +/-4096 mm (a long half-ellipse after F.6.6 scaling) must be refused with CS_ERR_RANGE. */
static void test_arc_random(void **state)
{
    (void)state;
    rng_state = 0x243F6A8885A308D3ull;
    char d[256];
    int checked = 0, refused = 0;
    for (int n = 0; n < 400; n++) {
        double x1 = urand(-200, 200), y1 = urand(-200, 200), x2 = urand(-200, 200),
               y2 = urand(-200, 200);
        double rx = urand(0.5, 300), ry = urand(0.5, 300), rot = urand(-360, 360);
        int fa = (int)(xorshift64() & 1), fs = (int)(xorshift64() & 1);
        snprintf(d, sizeof d, "M %.17g %.17g A %.17g %.17g %.17g %d %d %.17g %.17g", x1, y1, rx, ry,
                 rot, fa, fs, x2, y2);
        ref_arc_t a = ref_arc(x1, y1, rx, ry, rot, fa, fs, x2, y2);
        double ext = ref_extent(&a);
        cs_err_t e = parse(d);
        if (ext < 2000) {
            if (e != CS_OK)
                fail_msg("%s: %s", d, D.reason);
            check_arc(0, P.n, &a, x1, y1, x2, y2, ARC_TOL);
            check_continuity();
            checked++;
        } else if (ext > 4100) {
            if (e != CS_ERR_RANGE || D.loc.col != 1 + (unsigned)(strchr(d, 'A') - d))
                fail_msg("%s (reaches %.1f mm): got %d \"%s\"", d, ext, e, D.reason);
            refused++;
        }
    }
    /* The seed exercises both outcomes. */
    assert_true(checked > 300);
    assert_true(refused > 0);
}

/* The caller's transform is applied in double before conversion; arcs stay exact ellipses. */
static void test_transform(void **state)
{
    (void)state;
    cs_path_affine_t m = {2, 0, 0, 0.5, 10, 20}; /* x' = 2x + 10, y' = 0.5y + 20 */
    assert_int_equal(parse_with("M1 2 L3 4 Q 5 6 7 8", &m), CS_OK);
    ELEM(0, CS_PATH_LINE, 1, 0, 12, 21, 16, 22);
    ELEM(1, CS_PATH_QUAD, 2, 0, 16, 22, 20, 23, 24, 24);
    /* An arc under a rotation + non-uniform scale: map the pieces back with the inverse and
     * they must lie on the user-space ellipse (the inverse stretches errors by at most 2: the
     * smallest singular value is 0.5, so 2 * ARC_TOL). */
    double c = cos(0.3), s = sin(0.3);
    cs_path_affine_t r = {c, s, -s, c, 5, -7};
    cs_path_affine_t sc = {2, 0, 0, 0.5, 0, 0};
    cs_path_affine_t mm = cs_path_affine_mul(r, sc);
    assert_int_equal(parse_with("M 10 20 A 30 15 25 1 0 60 40", &mm), CS_OK);
    ref_arc_t a = ref_arc(10, 20, 30, 15, 25, 1, 0, 60, 40);
    double det = mm.a * mm.d - mm.b * mm.c;
    for (size_t i = 0; i < P.n; i++) {
        for (int k = 0; k <= 32; k++) {
            cs_ref_vec_t q = cs_ref_eval(&P.elems[i].curve, k / 32.0);
            double x = q.x - mm.e, y = q.y - mm.f;
            double ux = (mm.d * x - mm.c * y) / det, uy = (-mm.b * x + mm.a * y) / det;
            double dd = ellipse_dist(&a, ux, uy, NULL);
            if (dd > 2 * ARC_TOL)
                fail_msg("transformed arc: %.3f LSB off", dd / LSB);
        }
    }
    double ex, ey;
    cs_path_affine_point(&mm, 60, 40, &ex, &ey);
    near_pt(&P.elems[P.n - 1].curve.p[2], ex, ey, PT_TOL);
}

/* --- errors ------------------------------------------------------------------------------ */

typedef struct {
    const char *d;
    cs_err_t code;
    unsigned line, col;
    const char *says;
} err_case_t;

static void test_errors(void **state)
{
    (void)state;
    static const err_case_t cases[] = {
        /* resvg A.svg: "MoveTo is required." */
        {"A 5 5 0 0 1 50 50", CS_ERR_PARSE, 1, 1, "must begin with a moveto"},
        {"  L 1 2", CS_ERR_PARSE, 1, 3, "must begin with a moveto"},
        /* Missing argument at the end of data: column just past the last character. */
        {"M 10 10 L 20", CS_ERR_PARSE, 1, 13, "end of data"},
        {"M 10 10 L 20 x", CS_ERR_PARSE, 1, 14, "'x'"},
        /* Exponent without digits: the offending character is the one after 'e'. */
        {"M 10 10\n  L 1e 5", CS_ERR_PARSE, 2, 7, "digit"},
        {"M 0 0 L 1e+ 5", CS_ERR_PARSE, 1, 12, "digit"},
        {"M 0 0 L - 5", CS_ERR_PARSE, 1, 10, "digit"},
        {"M 0 0 L . 5", CS_ERR_PARSE, 1, 10, "digit"},
        /* A flag must be 0 or 1. */
        {"M 0 0 a1 1 0 2 1 1 1", CS_ERR_PARSE, 1, 14, "flag"},
        /* Trailing comma, double comma, comma right after a command letter. */
        {"M 10 10 L 20 20,", CS_ERR_PARSE, 1, 17, "after ','"},
        {"M 10,, 10", CS_ERR_PARSE, 1, 6, "','"},
        {"M 10 10 L, 20 20", CS_ERR_PARSE, 1, 10, "','"},
        /* closepath takes no arguments. */
        {"M 10 10 L 20 20 Z 5", CS_ERR_PARSE, 1, 19, "no arguments"},
        /* Unknown command letters. */
        {"M 10 10 X 5", CS_ERR_PARSE, 1, 9, "'X'"},
        {"M 10 10 L 5 5 e", CS_ERR_PARSE, 1, 15, "'e'"},
        /* Line and column after tabs, CR LF and a two-byte UTF-8 character (one column). */
        {"M 0 0\r\n\tL 1 2\n\xc3\xa9 L 3 4 #", CS_ERR_PARSE, 3, 1, "byte 0xC3"},
        {"M 0 0 L 1 2 \xc3\xa9", CS_ERR_PARSE, 1, 13, "byte 0xC3"},
        /* Out of range: refused where the offending number is. */
        {"M 5000 0", CS_ERR_RANGE, 1, 3, "outside the accepted range"},
        {"M 0 0 L 4096.0001 0", CS_ERR_RANGE, 1, 9, "outside"},
        {"M 4000 0\nl 50 0 l 50 0", CS_ERR_RANGE, 2, 10, "outside"},
        {"M 0 0 C 1 1 5000 1 3 3", CS_ERR_RANGE, 1, 13, "outside"},
        {"M 0 0 H -4097", CS_ERR_RANGE, 1, 9, "outside"},
        {"M 1e400 0", CS_ERR_RANGE, 1, 3, "too large"},
        /* Arcs that leave the range although their ends do not: radius 100 on a vertical
         * chord of 150 at x = 4090 has its centre at x = 4090 -/+ 66.14; sweeping to the
         * right (flags 0 1) it reaches x = 4023.86 + 100 = 4123.86. */
        {"M 4090 0 A 100 100 0 0 1 4090 150", CS_ERR_RANGE, 1, 10, "arc"},
        {"M 4090 0 A 100 100 0 1 1 4090 150", CS_ERR_RANGE, 1, 10, "arc leaves"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const err_case_t *c = &cases[i];
        cs_err_t e = parse(c->d);
        if (e != c->code || D.loc.line != c->line || D.loc.col != c->col ||
            strstr(D.reason, c->says) == NULL || strcmp(D.loc.file, "t.path") != 0)
            fail_msg("case %zu \"%s\": got %d at %s:%u:%u \"%s\", expected %d at %u:%u \"%s\"", i,
                     c->d, e, D.loc.file, D.loc.line, D.loc.col, D.reason, c->code, c->line, c->col,
                     c->says);
    }
}

/* Elements carry where they come from: the command letter, or the first number of an
 * implicitly repeated argument set. */
static void test_locations(void **state)
{
    (void)state;
    assert_int_equal(parse("M 0 0 L 1 1 2 2\n  C 1 1 2 2 3 3 Z"), CS_OK);
    assert_int_equal(P.n, 4);
    unsigned want[4][2] = {{1, 7}, {1, 13}, {2, 3}, {2, 17}};
    for (size_t i = 0; i < 4; i++) {
        assert_int_equal(P.elems[i].loc.line, want[i][0]);
        assert_int_equal(P.elems[i].loc.col, want[i][1]);
        assert_string_equal(P.elems[i].loc.file, "t.path");
    }
}

/* A long path: many elements, all continuous, parsed in linear time (locations are tracked
 * incrementally). */
static void test_long_path(void **state)
{
    (void)state;
    size_t n = 20000, cap = n * 40 + 32, len = 0;
    char *d = malloc(cap);
    assert_non_null(d);
    len += (size_t)snprintf(d + len, cap - len, "M0 0");
    for (size_t i = 0; i < n; i++)
        len += (size_t)snprintf(d + len, cap - len, "\nq 0.05 %d 0.1 0", (i % 2) ? 1 : -1);
    assert_int_equal(parse(d), CS_OK);
    assert_int_equal(P.n, n);
    check_continuity();
    ELEM(n - 1, CS_PATH_QUAD, 2, 0, (n - 1) * 0.1, 0, (n - 1) * 0.1 + 0.05, 1, n * 0.1, 0);
    assert_int_equal(P.elems[n - 1].loc.line, n + 1);
    assert_int_equal(P.elems[n - 1].loc.col, 1);
    free(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_move_line, setup, teardown),
        cmocka_unit_test_setup_teardown(test_numbers, setup, teardown),
        cmocka_unit_test_setup_teardown(test_cubic, setup, teardown),
        cmocka_unit_test_setup_teardown(test_quadratic, setup, teardown),
        cmocka_unit_test_setup_teardown(test_close_and_subpaths, setup, teardown),
        cmocka_unit_test_setup_teardown(test_arc_basic, setup, teardown),
        cmocka_unit_test_setup_teardown(test_arc_resvg, setup, teardown),
        cmocka_unit_test_setup_teardown(test_arc_degenerate, setup, teardown),
        cmocka_unit_test_setup_teardown(test_arc_random, setup, teardown),
        cmocka_unit_test_setup_teardown(test_transform, setup, teardown),
        cmocka_unit_test_setup_teardown(test_errors, setup, teardown),
        cmocka_unit_test_setup_teardown(test_locations, setup, teardown),
        cmocka_unit_test_setup_teardown(test_long_path, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
