/* test_curvefile: every statement of the curves file (host/cs_curvefile) against a
 * double-precision evaluation of its basis written here from the seed's formulas (seed 003), not
 * by calling the core: Bernstein sums, the Hermite basis, the uniform B-spline and Catmull-Rom
 * matrices of seed 003, Barsky's beta-spline matrix (Foley, van Dam, Feiner, Hughes, "Computer
 * Graphics: Principles and Practice", 2nd ed., section 11.2.4, eq. 11.49), Cox-de Boor
 * recursion for B-splines and NURBS, the natural spline's tridiagonal system solved in double,
 * and the ellipse's implicit equation for arcs. Every point is compared within a few LSB. Also:
 * located errors, and cs_input picking the format by extension and by header. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_curvefile.h"
#include "cs_input.h"
#include "cs_ref.h"

/* Control points are written on the 2^-16 mm grid, so only the conversions' own roundings
 * (<= 1 LSB per Bézier point, cs_basis.h / cs_nurbs.h / cs_spline.h) separate core and
 * reference; 4 LSB leaves room for the sum of a few. */
#define TOL_MM   (4 * CS_REF_LSB_MM)
#define NSAMPLES 17

typedef struct {
    double x, y, z;
} v3;

static v3 add(v3 a, v3 b, double s)
{
    v3 r = {a.x + s * b.x, a.y + s * b.y, a.z + s * b.z};
    return r;
}

static v3 zero(void)
{
    v3 r = {0, 0, 0};
    return r;
}

static void parse_ok(const char *text, cs_path_t *p)
{
    cs_path_diag_t d;
    cs_path_init(p);
    cs_err_t e = cs_curvefile_parse("t.curves", text, strlen(text), p, &d);
    if (e != CS_OK)
        cs_path_diag_print(stderr, &d);
    assert_int_equal(e, CS_OK);
}

/* Largest distance between segment seg of p at t and want(t), over NSAMPLES t. */
static double worst(const cs_path_t *p, size_t seg, v3 (*want)(size_t seg, double t))
{
    double w = 0;
    for (int k = 0; k < NSAMPLES; k++) {
        double t = (double)k / (NSAMPLES - 1);
        cs_ref_vec_t got = cs_ref_eval(&p->elems[seg].curve, t);
        v3 r = want(seg, t);
        cs_ref_vec_t rr = {r.x, r.y, r.z};
        w = fmax(w, cs_ref_dist(got, rr));
    }
    return w;
}

static void check_all(const cs_path_t *p, size_t nseg, v3 (*want)(size_t, double))
{
    assert_int_equal(p->n, nseg);
    for (size_t s = 0; s < nseg; s++) {
        double w = worst(p, s, want);
        if (w > TOL_MM)
            fprintf(stderr, "segment %zu: %.3g LSB from the reference\n", s, w / CS_REF_LSB_MM);
        assert_true(w <= TOL_MM);
    }
}

/* ---- bezier: B(t) = sum C(n,i) t^i (1-t)^(n-i) P_i */
static const v3 BZ[6] = {{0, 0, 0},   {5, 10, 1},   {10, -10, 2},
                         {15, 10, 3}, {20, -10, 4}, {25, 0, 5}};
static v3 ref_bezier(size_t seg, double t)
{
    (void)seg;
    v3 r = zero();
    double c = 1;
    for (int i = 0; i <= 5; i++) {
        r = add(r, BZ[i], c * pow(t, i) * pow(1 - t, 5 - i));
        c = c * (5 - i) / (i + 1);
    }
    return r;
}

static void test_bezier(void **state)
{
    (void)state;
    cs_path_t p;
    parse_ok("curvestep-curves 1\nbezier 5 0 0 0  5 10 1  10 -10 2  15 10 3  20 -10 4  25 0 5\n",
             &p);
    check_all(&p, 1, ref_bezier);
    assert_int_equal(p.elems[0].curve.degree, 5);
    assert_int_equal(p.elems[0].kind, CS_PATH_BEZIER);
    cs_path_free(&p);
    /* the core's largest degree, 7, is accepted */
    parse_ok("curvestep-curves 1 bezier 7 0 0 0 1 1 0 2 0 0 3 1 0 4 0 0 5 1 0 6 0 0 7 1 0", &p);
    assert_int_equal(p.elems[0].curve.degree, 7);
    cs_path_free(&p);
}

/* ---- hermite: H(t) = (2t^3-3t^2+1) P0 + (t^3-2t^2+t) T0 + (-2t^3+3t^2) P1 + (t^3-t^2) T1 */
static const v3 HP[3] = {{0, 0, 0}, {30, 10, 0}, {50, 0, 2}};
static const v3 HT[3] = {{20, 20, 0}, {20, 0, 1}, {10, -20, 0}};
static v3 hermite_at(v3 p0, v3 t0, v3 p1, v3 t1, double t)
{
    double t2 = t * t, t3 = t2 * t;
    v3 r = add(zero(), p0, 2 * t3 - 3 * t2 + 1);
    r = add(r, t0, t3 - 2 * t2 + t);
    r = add(r, p1, -2 * t3 + 3 * t2);
    return add(r, t1, t3 - t2);
}

static v3 ref_hermite(size_t i, double t)
{
    return hermite_at(HP[i], HT[i], HP[i + 1], HT[i + 1], t);
}

static void test_hermite(void **state)
{
    (void)state;
    cs_path_t p;
    parse_ok("curvestep-curves 1\nhermite 3  0 0 0 20 20 0  30 10 0 20 0 1  50 0 2 10 -20 0\n", &p);
    check_all(&p, 2, ref_hermite);
    cs_path_free(&p);
}

/* ---- the 4x4 cubic bases of seed 003: Q_i(t) = [t^3 t^2 t 1] M G, G = P(i-3) .. P(i) */
static const v3 G[6] = {{0, 0, 0}, {10, 20, 0}, {20, 0, 3}, {30, 20, 0}, {40, 0, -2}, {50, 20, 0}};
static v3 apply(const double m[4][4], double scale, size_t seg, double t)
{
    double tt[4] = {t * t * t, t * t, t, 1};
    v3 r = zero();
    for (int j = 0; j < 4; j++) {
        double b = 0;
        for (int i = 0; i < 4; i++)
            b += tt[i] * m[i][j];
        r = add(r, G[seg + (size_t)j], b / scale);
    }
    return r;
}

static v3 ref_bspline(size_t seg, double t)
{
    static const double m[4][4] = {{-1, 3, -3, 1}, {3, -6, 3, 0}, {-3, 0, 3, 0}, {1, 4, 1, 0}};
    return apply(m, 6, seg, t);
}

static v3 ref_catmull_rom(size_t seg, double t)
{
    static const double m[4][4] = {{-1, 3, -3, 1}, {2, -5, 4, -1}, {-1, 0, 1, 0}, {0, 2, 0, 0}};
    return apply(m, 2, seg, t);
}

/* Barsky's matrix (Foley et al. eq. 11.49), delta = b2 + 2 b1^3 + 4 b1^2 + 4 b1 + 2. */
static const double B1 = 1.5, B2 = 4;
static v3 ref_beta(size_t seg, double t)
{
    double b1 = B1, b2 = B2, q = b1 * b1, c = q * b1;
    double m[4][4] = {
        {-2 * c, 2 * (b2 + c + q + b1), -2 * (b2 + q + b1 + 1), 2},
        {6 * c, -3 * (b2 + 2 * c + 2 * q), 3 * (b2 + 2 * q), 0},
        {-6 * c, 6 * (c - b1), 6 * b1, 0},
        {2 * c, b2 + 4 * (q + b1), 2, 0},
    };
    return apply(m, b2 + 2 * c + 4 * q + 4 * b1 + 2, seg, t);
}

#define SIX_POINTS "0 0 0  10 20 0  20 0 3  30 20 0  40 0 -2  50 20 0"

static void test_cubic_bases(void **state)
{
    (void)state;
    cs_path_t p;
    parse_ok("curvestep-curves 1\nbspline 6 " SIX_POINTS "\n", &p);
    check_all(&p, 3, ref_bspline);
    cs_path_free(&p);
    parse_ok("curvestep-curves 1\ncatmull-rom 6 " SIX_POINTS "\n", &p);
    check_all(&p, 3, ref_catmull_rom);
    cs_path_free(&p);
    parse_ok("curvestep-curves 1\nbeta 1.5 4 6 " SIX_POINTS "\n", &p);
    check_all(&p, 3, ref_beta);
    cs_path_free(&p);
}

/* ---- Cox-de Boor: N(i,1)(u) = [k_i <= u < k_(i+1)], N(i,k) = (u - k_i)/(k_(i+k-1) - k_i)
 * N(i,k-1) + (k_(i+k) - u)/(k_(i+k) - k_(i+1)) N(i+1,k-1); C(u) = sum w_i N_i P_i / sum w_i N_i.
 * span is the knot interval [k_span, k_(span+1)) the point falls in (closed at the domain's
 * end). */
static double cox_de_boor(const double *k, int i, int order, double u, int span)
{
    if (order == 1)
        return i == span ? 1 : 0;
    double a = 0, b = 0;
    if (k[i + order - 1] > k[i])
        a = (u - k[i]) / (k[i + order - 1] - k[i]) * cox_de_boor(k, i, order - 1, u, span);
    if (k[i + order] > k[i + 1])
        b = (k[i + order] - u) / (k[i + order] - k[i + 1]) *
            cox_de_boor(k, i + 1, order - 1, u, span);
    return a + b;
}

static const v3 NP[5] = {{0, 0, 0}, {10, 20, 0}, {20, 0, 4}, {30, 20, 0}, {40, 0, 0}};
static const double NW[5] = {1, 2, 0.5, 1, 1};
static const double NK[9] = {0, 0, 0, 0, 1, 3, 3, 3, 3}; /* order 4, spans [0,1] and [1,3] */
static bool rational;
static v3 ref_nurbs(size_t seg, double t)
{
    int span = seg == 0 ? 3 : 4;
    double u = NK[span] + t * (NK[span + 1] - NK[span]);
    v3 r = zero();
    double den = 0;
    for (int i = 0; i < 5; i++) {
        double n = cox_de_boor(NK, i, 4, u, span) * (rational ? NW[i] : 1);
        r = add(r, NP[i], n);
        den += n;
    }
    v3 out = {r.x / den, r.y / den, r.z / den};
    return out;
}

static void test_nurbs(void **state)
{
    (void)state;
    cs_path_t p;
    rational = false;
    parse_ok("curvestep-curves 1\nbspline 5  0 0 0  10 20 0  20 0 4  30 20 0  40 0 0\n"
             "  knots 4  0 0 0 0 1 3 3 3 3\n",
             &p);
    check_all(&p, 2, ref_nurbs);
    cs_path_free(&p);
    rational = true;
    parse_ok("curvestep-curves 1\nnurbs 5  0 0 0 1  10 20 0 2  20 0 4 0.5  30 20 0 1  40 0 0 1\n"
             "  knots 4  0 0 0 0 1 3 3 3 3\n",
             &p);
    check_all(&p, 2, ref_nurbs);
    cs_path_free(&p);
}

/* ---- natural spline, uniform parameter: tangents D from 2 D0 + D1 = 3 (P1 - P0),
 * D(i-1) + 4 D(i) + D(i+1) = 3 (P(i+1) - P(i-1)), D(n-2) + 2 D(n-1) = 3 (P(n-1) - P(n-2))
 * (second derivative continuous inside, zero at both ends), then Hermite segments. */
static v3 NAT_D[5];
static const v3 NAT_P[5] = {{0, 0, 0}, {10, 20, 0}, {25, 5, 2}, {30, 25, 0}, {50, 10, 0}};
static void solve_natural(void)
{
    const int n = 5;
    double a[5], b[5], c[5];
    v3 r[5];
    for (int i = 0; i < n; i++) {
        a[i] = i > 0 ? 1 : 0;
        c[i] = i < n - 1 ? 1 : 0;
        b[i] = (i == 0 || i == n - 1) ? 2 : 4;
        v3 hi = NAT_P[i < n - 1 ? i + 1 : i], lo = NAT_P[i > 0 ? i - 1 : i];
        r[i] = add(zero(), add(hi, lo, -1), 3);
    }
    for (int i = 1; i < n; i++) { /* Thomas elimination */
        double m = a[i] / b[i - 1];
        b[i] -= m * c[i - 1];
        r[i] = add(r[i], r[i - 1], -m);
    }
    NAT_D[n - 1] = add(zero(), r[n - 1], 1 / b[n - 1]);
    for (int i = n - 2; i >= 0; i--)
        NAT_D[i] = add(zero(), add(r[i], NAT_D[i + 1], -c[i]), 1 / b[i]);
}

static v3 ref_natural(size_t i, double t)
{
    return hermite_at(NAT_P[i], NAT_D[i], NAT_P[i + 1], NAT_D[i + 1], t);
}

static void test_natural(void **state)
{
    (void)state;
    cs_path_t p;
    solve_natural();
    parse_ok("curvestep-curves 1\nnatural 5  0 0 0  10 20 0  25 5 2  30 25 0  50 10 0\n", &p);
    check_all(&p, 4, ref_natural);
    cs_path_free(&p);
}

/* ---- natural ... clamped T0 T1: the clamped spline's defining conditions, checked on the
 * segments from their control points in double (not by re-solving): it passes through the
 * points, starts and ends with the given tangents, and is C1 and C2 at every inner point, with
 * derivatives per unit of the global parameter (segment i spans h_i: 1, or the chord length). */
static void check_clamped(const char *text, const v3 *P, int n, v3 t0, v3 t1, bool chord)
{
    cs_path_t p;
    parse_ok(text, &p);
    assert_int_equal(p.n, (size_t)n - 1);
    double h[8], tol1 = 4 * CS_REF_LSB_MM, tol2 = 16 * CS_REF_LSB_MM;
    for (int i = 0; i + 1 < n; i++)
        h[i] = chord ? sqrt(pow(P[i + 1].x - P[i].x, 2) + pow(P[i + 1].y - P[i].y, 2) +
                            pow(P[i + 1].z - P[i].z, 2))
                     : 1;
    for (int i = 0; i + 1 < n; i++) {
        const cs_bezier_t *b = &p.elems[i].curve;
        cs_ref_vec_t q[4];
        for (int k = 0; k < 4; k++)
            q[k] = cs_ref_from_pos(&b->p[k]);
        cs_ref_vec_t want0 = {P[i].x, P[i].y, P[i].z}, want1 = {P[i + 1].x, P[i + 1].y, P[i + 1].z};
        assert_true(cs_ref_dist(q[0], want0) <= CS_REF_LSB_MM &&
                    cs_ref_dist(q[3], want1) <= CS_REF_LSB_MM);
        if (i == 0) {
            cs_ref_vec_t d = {3 * (q[1].x - q[0].x) / h[0], 3 * (q[1].y - q[0].y) / h[0],
                              3 * (q[1].z - q[0].z) / h[0]};
            cs_ref_vec_t w = {t0.x, t0.y, t0.z};
            assert_true(cs_ref_dist(d, w) <= tol1 / h[0]);
        }
        if (i + 2 == n) {
            cs_ref_vec_t d = {3 * (q[3].x - q[2].x) / h[i], 3 * (q[3].y - q[2].y) / h[i],
                              3 * (q[3].z - q[2].z) / h[i]};
            cs_ref_vec_t w = {t1.x, t1.y, t1.z};
            assert_true(cs_ref_dist(d, w) <= tol1 / h[i]);
            continue;
        }
        const cs_bezier_t *nb = &p.elems[i + 1].curve;
        cs_ref_vec_t r[3];
        for (int k = 0; k < 3; k++)
            r[k] = cs_ref_from_pos(&nb->p[k]);
        double hi = h[i], hn = h[i + 1];
        cs_ref_vec_t d1a = {3 * (q[3].x - q[2].x) / hi, 3 * (q[3].y - q[2].y) / hi,
                            3 * (q[3].z - q[2].z) / hi};
        cs_ref_vec_t d1b = {3 * (r[1].x - r[0].x) / hn, 3 * (r[1].y - r[0].y) / hn,
                            3 * (r[1].z - r[0].z) / hn};
        assert_true(cs_ref_dist(d1a, d1b) <= tol1 * (1 / hi + 1 / hn));
        cs_ref_vec_t d2a = {6 * (q[3].x - 2 * q[2].x + q[1].x) / (hi * hi),
                            6 * (q[3].y - 2 * q[2].y + q[1].y) / (hi * hi),
                            6 * (q[3].z - 2 * q[2].z + q[1].z) / (hi * hi)};
        cs_ref_vec_t d2b = {6 * (r[0].x - 2 * r[1].x + r[2].x) / (hn * hn),
                            6 * (r[0].y - 2 * r[1].y + r[2].y) / (hn * hn),
                            6 * (r[0].z - 2 * r[1].z + r[2].z) / (hn * hn)};
        assert_true(cs_ref_dist(d2a, d2b) <= tol2 * (1 / (hi * hi) + 1 / (hn * hn)));
    }
    cs_path_free(&p);
}

static void test_natural_clamped(void **state)
{
    (void)state;
    static const v3 P[5] = {{0, 0, 0}, {10, 20, 0}, {25, 5, 2}, {30, 25, 0}, {50, 10, 0}};
    v3 t0 = {10, 0, 0}, t1 = {0, -15, 5}, u0 = {1, 0, 0}, u1 = {0, -1, 0};
    check_clamped("curvestep-curves 1\nnatural 5  0 0 0  10 20 0  25 5 2  30 25 0  50 10 0\n"
                  "  clamped 10 0 0  0 -15 5\n",
                  P, 5, t0, t1, false);
    check_clamped("curvestep-curves 1\nnatural 5  0 0 0  10 20 0  25 5 2  30 25 0  50 10 0\n"
                  "  chord clamped 1 0 0  0 -1 0\n",
                  P, 5, u0, u1, true);
}

/* ---- arc C U V a0 a1: every point is C + U cos(a) + V sin(a) for some a in [a0, a1] (U, V
 * orthogonal here, so cos(a) = (X - C).U / |U|^2, sin(a) = (X - C).V / |V|^2), and the ends are
 * at a0 and a1. */
static void test_arc(void **state)
{
    (void)state;
    cs_path_t p;
    parse_ok("curvestep-curves 1\narc  10 20 5  30 0 0  0 0 15  -30 200\n", &p);
    assert_int_equal(p.n, 4); /* a sweep over 180 degrees: four equal pieces */
    double worst_r = 0;
    for (size_t s = 0; s < p.n; s++)
        for (int k = 0; k < NSAMPLES; k++) {
            cs_ref_vec_t x = cs_ref_eval(&p.elems[s].curve, (double)k / (NSAMPLES - 1));
            double cu = (x.x - 10) / 30, sv = (x.z - 5) / 15;
            assert_true(fabs(x.y - 20) <= TOL_MM);
            /* distance along the normal of the ellipse ~ |1 - (cu^2 + sv^2)| * radius / 2 */
            worst_r = fmax(worst_r, fabs(1 - (cu * cu + sv * sv)) * 30 / 2);
            double a = atan2(sv, cu) * 180 / M_PI;
            if (a < -90) /* atan2 gives (-180, 180]: 180..200 degrees come out negative */
                a += 360;
            assert_true(a >= -30 - 1e-4 && a <= 200 + 1e-4);
        }
    assert_true(worst_r <= TOL_MM);
    cs_ref_vec_t s0 = cs_ref_eval(&p.elems[0].curve, 0), s1 = cs_ref_eval(&p.elems[3].curve, 1);
    double r0 = -30 * M_PI / 180, r1 = 200 * M_PI / 180;
    cs_ref_vec_t w0 = {10 + 30 * cos(r0), 20, 5 + 15 * sin(r0)};
    cs_ref_vec_t w1 = {10 + 30 * cos(r1), 20, 5 + 15 * sin(r1)};
    assert_true(cs_ref_dist(s0, w0) <= TOL_MM && cs_ref_dist(s1, w1) <= TOL_MM);
    cs_path_free(&p);
}

/* Lines, subpaths: a statement starting away from the last end lifts the pen. */
static void test_line_and_subpaths(void **state)
{
    (void)state;
    cs_path_t p;
    parse_ok("curvestep-curves 1\nline 0 0 0 10 0 0\nline 10 0 0 10 10 0\nline 20 0 0 30 0 0\n",
             &p);
    assert_int_equal(p.n, 3);
    assert_int_equal(p.elems[1].subpath, 0);
    assert_int_equal(p.elems[2].subpath, 1);
    assert_int_equal(p.elems[2].loc.line, 4);
    assert_int_equal(p.elems[2].kind, CS_PATH_LINE);
    cs_path_free(&p);
}

static void expect_error(const char *text, cs_err_t code, unsigned line, unsigned col,
                         const char *needle)
{
    cs_path_t p;
    cs_path_diag_t d;
    cs_path_init(&p);
    assert_int_equal(cs_curvefile_parse("bad.curves", text, strlen(text), &p, &d), code);
    if (d.loc.line != line || d.loc.col != col || !strstr(d.reason, needle))
        cs_path_diag_print(stderr, &d);
    assert_string_equal(d.loc.file, "bad.curves");
    assert_int_equal(d.loc.line, line);
    assert_int_equal(d.loc.col, col);
    assert_non_null(strstr(d.reason, needle));
    cs_path_free(&p);
}

static void test_errors(void **state)
{
    (void)state;
    expect_error("curvestep-curves 2\n", CS_ERR_RANGE, 1, 18, "format version");
    expect_error("curves 1\n", CS_ERR_PARSE, 1, 1, "header");
    expect_error("curvestep-curves 1\n", CS_ERR_EMPTY, 2, 1, "no curves");
    expect_error("curvestep-curves 1\n  spiral 3\n", CS_ERR_PARSE, 2, 3, "unknown curve 'spiral'");
    expect_error("curvestep-curves 1\nbezier 8 0 0 0\n", CS_ERR_RANGE, 2, 8, "degree");
    expect_error("curvestep-curves 1\nline 0 0 0 1 x 0\n", CS_ERR_PARSE, 2, 14, "'x': point");
    expect_error("curvestep-curves 1\nline 0 0 0 5000 0 0\n", CS_ERR_RANGE, 2, 12, "outside");
    expect_error("curvestep-curves 1\nbspline 3 0 0 0 1 1 0 2 0 0\n", CS_ERR_DEGENERATE, 2, 1,
                 "bspline");
    expect_error("curvestep-curves 1\nnurbs 2 0 0 0 1 1 1 0 0 knots 2 0 0 1 1\n", CS_ERR_WEIGHT, 2,
                 23, "weight 0 must be > 0");
    expect_error("curvestep-curves 1\nnurbs 2 0 0 0 1 1 1 0 1 2 0 0 1 1\n", CS_ERR_PARSE, 2, 25,
                 "'knots' expected");
    expect_error("curvestep-curves 1\nbspline 4 0 0 0 1 1 0 2 0 0 3 1 0\nknots 4 0 0 0 0 2 1 1 1\n",
                 CS_ERR_KNOTS, 3, 19, "below");
    expect_error("curvestep-curves 1\nbeta 0 1 4 0 0 0 1 1 0 2 0 0 3 1 0\n", CS_ERR_RANGE, 2, 6,
                 "bias");
    expect_error("curvestep-curves 1\narc 0 0 0 1 0 0 0 1 0 10 10\n", CS_ERR_RANGE, 2, 26, "sweep");
}

/* cs_input reads curves files by extension and, under any other name, by their header. */
static void test_input(void **state)
{
    (void)state;
    const char *t = "curvestep-curves 1\nline 0 0 0 1 0 0\n";
    assert_int_equal(cs_input_detect("a.curves", "", 0), CS_INPUT_CURVES);
    assert_int_equal(cs_input_detect("a.CURVES", "", 0), CS_INPUT_CURVES);
    assert_int_equal(cs_input_detect(NULL, t, strlen(t)), CS_INPUT_CURVES);
    assert_int_equal(cs_input_detect("x.dat", t, strlen(t)), CS_INPUT_CURVES);
    assert_string_equal(cs_input_format_name(CS_INPUT_CURVES), "curves");
    cs_path_t p;
    cs_path_diag_t d;
    cs_path_init(&p);
    assert_int_equal(cs_input_parse("x.dat", t, strlen(t), NULL, &p, &d), CS_OK);
    assert_int_equal(p.n, 1);
    cs_path_free(&p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bezier),      cmocka_unit_test(test_hermite),
        cmocka_unit_test(test_cubic_bases), cmocka_unit_test(test_nurbs),
        cmocka_unit_test(test_natural),     cmocka_unit_test(test_natural_clamped),
        cmocka_unit_test(test_arc),         cmocka_unit_test(test_line_and_subpaths),
        cmocka_unit_test(test_errors),      cmocka_unit_test(test_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
