/* test_dxf: AutoCAD DXF drawings (host/cs_dxf.c) -> path elements. Every entity is checked
 * against geometry worked out here in double from the DXF Reference's definitions, not from the
 * reader: line ends to 0.5 LSB (a point is its exact value rounded once), arc and ellipse points
 * to 4 LSB of the exact conic (cs_arc_build promises 2 LSB from its quantised centre and axes),
 * bulge arcs from the inscribed-angle construction (radius c / (2 sin(theta/2)), bulge =
 * tan(theta/4)), mirrored extrusion from the arbitrary axis algorithm worked by hand ((0,0,-1):
 * x -> -x), INSERT as ins + R(rot) S (p - base), splines by de Boor's algorithm at the knots'
 * own parameters (rational: homogeneous), to 8 LSB. Errors must be located at the group's value
 * line and column. Run from the repository root (the stroke font share/fonts/futural.jhf). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_dxf.h"
#include "cs_input.h"
#include "cs_ref.h"

#define LSB     (1.0 / 65536.0)
#define PT_TOL  (0.5 * LSB + 1e-9)
#define ARC_TOL (4.0 * LSB)
#define SPL_TOL (8.0 * LSB)

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static cs_path_t P;
static cs_path_diag_t D;
static int nwarn;
static char warns[8192];
static cs_hershey_font_t font;
static bool have_font;

static void on_warn(void *ctx, const cs_path_diag_t *w)
{
    (void)ctx;
    nwarn++;
    size_t n = strlen(warns);
    snprintf(warns + n, sizeof warns - n, "%u:%u: %s\n", w->loc.line, w->loc.col, w->reason);
}

static cs_err_t rd_opts(const char *text, bool with_font, double unit_mm)
{
    cs_path_free(&P);
    cs_path_init(&P);
    memset(&D, 0, sizeof D);
    nwarn = 0;
    warns[0] = '\0';
    cs_dxf_opts_t o;
    cs_dxf_opts_init(&o);
    o.warn = on_warn;
    o.font = with_font && have_font ? &font : NULL;
    o.unit_mm = unit_mm;
    return cs_dxf_read("t.dxf", text, strlen(text), &o, &P, &D);
}

static cs_err_t rd(const char *text)
{
    return rd_opts(text, false, 0);
}

/* The entities wrapped in a file with $INSUNITS = 4 (mm). */
static cs_err_t rde(const char *ents)
{
    static char buf[16384];
    snprintf(buf, sizeof buf,
             "0\nSECTION\n2\nHEADER\n9\n$INSUNITS\n70\n4\n0\nENDSEC\n0\nSECTION\n2\nENTITIES\n%s"
             "0\nENDSEC\n0\nEOF\n",
             ents);
    return rd(buf);
}

static int setup(void **state)
{
    (void)state;
    cs_path_init(&P);
    cs_path_diag_t d;
    have_font = cs_hershey_load("share/fonts/futural.jhf", &font, &d) == CS_OK;
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    cs_path_free(&P);
    if (have_font)
        cs_hershey_free(&font);
    return 0;
}

static void near_pt(cs_ref_vec_t p, double x, double y, double tol)
{
    if (fabs(p.x - x) > tol || fabs(p.y - y) > tol)
        fail_msg("point (%.9f, %.9f), expected (%.9f, %.9f)", p.x, p.y, x, y);
}

static cs_ref_vec_t start_of(size_t i)
{
    return cs_ref_eval(&P.elems[i].curve, 0.0);
}

static cs_ref_vec_t end_of(size_t i)
{
    return cs_ref_eval(&P.elems[i].curve, 1.0);
}

/* Elements [a, b) join end to start exactly. */
static void joined(size_t a, size_t b)
{
    for (size_t i = a + 1; i < b; i++) {
        const cs_bezier_t *p = &P.elems[i - 1].curve, *q = &P.elems[i].curve;
        assert_true(p->p[p->degree].x == q->p[0].x && p->p[p->degree].y == q->p[0].y);
    }
}

/* Every point of elements [a, b) at distance r (ARC_TOL) from (cx, cy); returns the sum of the
 * signed turning angles (radians, + counter-clockwise) of the sampled points about it. */
static double on_circle(size_t a, size_t b, double cx, double cy, double r)
{
    double turn = 0, prev = NAN;
    for (size_t i = a; i < b; i++)
        for (int k = 0; k <= 64; k++) {
            cs_ref_vec_t q = cs_ref_eval(&P.elems[i].curve, k / 64.0);
            double d = hypot(q.x - cx, q.y - cy);
            if (fabs(d - r) > ARC_TOL)
                fail_msg("element %zu t=%d/64: distance %.9f from the centre, radius %.9f", i, k, d,
                         r);
            double ang = atan2(q.y - cy, q.x - cx);
            if (!isnan(prev)) {
                double da = ang - prev;
                while (da > M_PI)
                    da -= 2 * M_PI;
                while (da < -M_PI)
                    da += 2 * M_PI;
                turn += da;
            }
            prev = ang;
        }
    return turn;
}

/* --- entities ----------------------------------------------------------------------------------
 */

static void test_line(void **state)
{
    (void)state;
    assert_int_equal(rde("0\nLINE\n8\n0\n10\n1.5\n20\n2.25\n30\n7\n11\n-3\n21\n4\n31\n-2\n"),
                     CS_OK);
    assert_int_equal(P.n, 1);
    assert_int_equal(P.elems[0].kind, CS_PATH_LINE);
    near_pt(start_of(0), 1.5, 2.25, PT_TOL);
    near_pt(end_of(0), -3, 4, PT_TOL);
    assert_int_equal(P.elems[0].curve.p[0].z, 0); /* drawn from above */
    assert_int_equal(P.elems[0].loc.line, 16);    /* the value line of "0 LINE" */
    assert_int_equal(nwarn, 0);
}

static void test_circle_arc(void **state)
{
    (void)state;
    assert_int_equal(rde("0\nCIRCLE\n10\n20\n20\n-7\n40\n5\n"), CS_OK);
    assert_int_equal(P.n, 4);
    near_pt(start_of(0), 25, -7, PT_TOL); /* angle 0, counter-clockwise */
    joined(0, 4);
    near_pt(end_of(3), 25, -7, PT_TOL);
    assert_true(fabs(on_circle(0, 4, 20, -7, 5) - 2 * M_PI) < 1e-3);

    /* ARC 30 -> 300 degrees, counter-clockwise: 270 degrees of turn. */
    assert_int_equal(rde("0\nARC\n10\n1\n20\n2\n40\n3\n50\n30\n51\n300\n"), CS_OK);
    double a0 = 30 * M_PI / 180, a1 = 300 * M_PI / 180;
    near_pt(start_of(0), 1 + 3 * cos(a0), 2 + 3 * sin(a0), PT_TOL);
    near_pt(end_of(P.n - 1), 1 + 3 * cos(a1), 2 + 3 * sin(a1), PT_TOL);
    joined(0, P.n);
    assert_true(fabs(on_circle(0, P.n, 1, 2, 3) - (a1 - a0)) < 1e-3);

    /* End before start: through 0 degrees (300 -> 30 is 90 degrees). */
    assert_int_equal(rde("0\nARC\n10\n0\n20\n0\n40\n10\n50\n300\n51\n30\n"), CS_OK);
    assert_true(fabs(on_circle(0, P.n, 0, 0, 10) - M_PI / 2) < 1e-3);
    near_pt(start_of(0), 10 * cos(a1), 10 * sin(a1), PT_TOL);
}

static void test_ellipse(void **state)
{
    (void)state;
    /* centre (60, 20), major (8, 3), ratio 0.5: minor = 0.5 (Z x major) = (-1.5, 4);
     * parameters 0.3 .. 4.0. */
    assert_int_equal(rde("0\nELLIPSE\n10\n60\n20\n20\n11\n8\n21\n3\n40\n0.5\n41\n0.3\n42\n4.0\n"),
                     CS_OK);
    double ux = 8, uy = 3, vx = -1.5, vy = 4;
    near_pt(start_of(0), 60 + ux * cos(0.3) + vx * sin(0.3), 20 + uy * cos(0.3) + vy * sin(0.3),
            PT_TOL);
    near_pt(end_of(P.n - 1), 60 + ux * cos(4.0) + vx * sin(4.0), 20 + uy * cos(4.0) + vy * sin(4.0),
            PT_TOL);
    joined(0, P.n);
    double u2 = ux * ux + uy * uy, v2 = vx * vx + vy * vy;
    for (size_t i = 0; i < P.n; i++)
        for (int k = 0; k <= 32; k++) {
            cs_ref_vec_t q = cs_ref_eval(&P.elems[i].curve, k / 32.0);
            double dx = q.x - 60, dy = q.y - 20;
            double c = (dx * ux + dy * uy) / u2, s = (dx * vx + dy * vy) / v2; /* U, V orthogonal */
            /* on the ellipse: |(c, s)| = 1 within ARC_TOL over the minor semi-axis */
            assert_true(fabs(hypot(c, s) - 1) < ARC_TOL / sqrt(v2));
            double t = atan2(s, c);
            if (t < 0)
                t += 2 * M_PI;
            assert_true(t > 0.3 - 1e-6 && t < 4.0 + 1e-6);
        }
    /* Full ellipse, normal (0,0,-1): minor = 0.25 ((0,0,-1) x (0,2)) = (0.5, 0): a closed curve
     * running the other way (clockwise seen from above). */
    assert_int_equal(
        rde("0\nELLIPSE\n10\n0\n20\n0\n11\n0\n21\n2\n40\n0.25\n210\n0\n220\n0\n230\n-1\n"), CS_OK);
    assert_int_equal(P.n, 4);
    near_pt(start_of(0), 0, 2, PT_TOL);
    near_pt(cs_ref_eval(&P.elems[0].curve, 1.0), 0.5, 0, PT_TOL); /* a quarter: +90 degrees */
    near_pt(end_of(3), 0, 2, PT_TOL);
    /* ratio 0: an error at the ratio */
    assert_int_equal(rde("0\nELLIPSE\n10\n0\n20\n0\n11\n1\n21\n0\n40\n0\n"), CS_ERR_PARSE);
    assert_int_equal(D.loc.line, 26);
}

/* LWPOLYLINE bulges: the arc from P to Q of included angle theta = 4 atan(bulge) (+ counter-
 * clockwise) has radius c / (2 sin(theta/2)) and its centre on the chord's bisector at
 * c / (2 tan(theta/2)) to the left (theta > 0) of P -> Q. */
static void test_bulge(void **state)
{
    (void)state;
    double th = 120 * M_PI / 180, b = tan(th / 4);
    char ent[512];
    snprintf(ent, sizeof ent,
             "0\nLWPOLYLINE\n90\n3\n70\n0\n10\n0\n20\n0\n42\n%.17g\n10\n10\n20\n0\n42\n%.17g\n"
             "10\n20\n20\n0\n",
             b, -1.0);
    assert_int_equal(rde(ent), CS_OK);
    double r = 10 / (2 * sin(th / 2)), h = 10 / (2 * tan(th / 2));
    size_t first_arc_end = 0;
    while (first_arc_end < P.n && (end_of(first_arc_end).x < 10 - 1e-6))
        first_arc_end++;
    first_arc_end++;
    double turn = on_circle(0, first_arc_end, 5, h, r);
    assert_true(fabs(turn - th) < 1e-3);
    for (size_t i = 0; i < first_arc_end; i++) /* the arc bulges below the chord */
        assert_true(cs_ref_eval(&P.elems[i].curve, 0.5).y < 1e-9);
    /* bulge -1: a clockwise semicircle from (10, 0) to (20, 0) about (15, 0), above the chord */
    turn = on_circle(first_arc_end, P.n, 15, 0, 5);
    assert_true(fabs(turn + M_PI) < 1e-3);
    assert_true(cs_ref_eval(&P.elems[first_arc_end].curve, 0.5).y > 0);
    near_pt(end_of(P.n - 1), 20, 0, PT_TOL);
    joined(0, P.n);

    /* Closed (70 bit 1): the last vertex's bulge runs back to the first; no bulge: lines. */
    assert_int_equal(rde("0\nLWPOLYLINE\n90\n3\n70\n1\n10\n0\n20\n0\n10\n4\n20\n0\n10\n4\n20\n3\n"),
                     CS_OK);
    assert_int_equal(P.n, 3);
    near_pt(end_of(2), 0, 0, PT_TOL);
    assert_int_equal(P.elems[0].curve.degree, 1);
    assert_int_equal(P.elems[2].loc.line, 30); /* the segment's first vertex (its 10 group) */
}

static void test_polyline(void **state)
{
    (void)state;
    /* 2-D POLYLINE: bulge 1 (semicircle counter-clockwise from (0,0) to (4,0), centre (2,0),
     * below the chord), closed back to (0, 0) from (4, 3); a spline frame vertex (70 = 16) is
     * not drawn. */
    assert_int_equal(rde("0\nPOLYLINE\n66\n1\n70\n1\n10\n0\n20\n0\n30\n0\n"
                         "0\nVERTEX\n10\n0\n20\n0\n42\n1\n"
                         "0\nVERTEX\n10\n4\n20\n0\n"
                         "0\nVERTEX\n10\n99\n20\n99\n70\n16\n"
                         "0\nVERTEX\n10\n4\n20\n3\n"
                         "0\nSEQEND\n"
                         "0\nLINE\n10\n0\n20\n0\n11\n1\n21\n1\n"),
                     CS_OK);
    size_t k = 0;
    while (k < P.n && P.elems[k].kind == CS_PATH_ARC)
        k++;
    assert_true(k >= 2);
    assert_true(fabs(on_circle(0, k, 2, 0, 2) - M_PI) < 1e-3);
    assert_true(cs_ref_eval(&P.elems[0].curve, 0.5).y < 0);
    assert_int_equal(P.n, k + 3); /* (4,0)-(4,3), (4,3)-(0,0), and the LINE after SEQEND */
    near_pt(end_of(k + 1), 0, 0, PT_TOL);
    joined(0, k + 2);
    /* 3-D polyline (70 = 8): world coordinates, z dropped; a polyface mesh: warned, skipped. */
    assert_int_equal(
        rde("0\nPOLYLINE\n70\n8\n0\nVERTEX\n10\n1\n20\n2\n30\n3\n0\nVERTEX\n10\n4\n20\n6\n30\n-5\n"
            "0\nSEQEND\n0\nPOLYLINE\n70\n64\n0\nVERTEX\n10\n1\n20\n1\n0\nSEQEND\n"),
        CS_OK);
    assert_int_equal(P.n, 1);
    near_pt(end_of(0), 4, 6, PT_TOL);
    assert_int_equal(nwarn, 1);
    assert_non_null(strstr(warns, "meshes are not drawn"));
}

/* Extrusion (0,0,-1): by the arbitrary axis algorithm Ax = Wy x N = (-1, 0, 0), Ay = N x Ax =
 * (0, 1, 0): an OCS point (x, y) is the world point (-x, y), and counter-clockwise in the OCS is
 * clockwise in the world. */
static void test_extrusion(void **state)
{
    (void)state;
    assert_int_equal(
        rde("0\nARC\n10\n10\n20\n0\n30\n0\n40\n2\n210\n0\n220\n0\n230\n-1\n50\n0\n51\n90\n"),
        CS_OK);
    near_pt(start_of(0), -12, 0, PT_TOL);
    near_pt(end_of(P.n - 1), -10, 2, PT_TOL);
    assert_true(fabs(on_circle(0, P.n, -10, 0, 2) + M_PI / 2) < 1e-3);
    /* LWPOLYLINE with elevation and the same normal: z along N moves nothing in x, y. */
    assert_int_equal(
        rde("0\nLWPOLYLINE\n90\n2\n38\n5\n210\n0\n220\n0\n230\n-1\n10\n1\n20\n2\n10\n3\n20\n-4\n"),
        CS_OK);
    near_pt(start_of(0), -1, 2, PT_TOL);
    near_pt(end_of(0), -3, -4, PT_TOL);
    /* A tilted normal (1, 0, 0) sees the plane edge-on: warned, not drawn. A normal (0, 1, 1)
     * is drawn projected: Ax = Wz x N / |.| = (-1, 0, 0), Ay = N x Ax = (0, -1, 1)/sqrt 2 ->
     * (x, y) -> (-x, -y/sqrt 2). */
    assert_int_equal(rde("0\nLINE\n10\n0\n20\n0\n11\n1\n21\n0\n"
                         "0\nCIRCLE\n10\n0\n20\n0\n40\n1\n210\n1\n220\n0\n230\n0\n"
                         "0\nLWPOLYLINE\n10\n2\n20\n4\n10\n0\n20\n0\n210\n0\n220\n1\n230\n1\n"),
                     CS_OK);
    assert_int_equal(P.n, 2);
    near_pt(start_of(1), -2, -4 / sqrt(2), PT_TOL);
    assert_int_equal(nwarn, 2);
    assert_non_null(strstr(warns, "edge-on"));
    assert_non_null(strstr(warns, "projected onto XY"));
}

/* A block B (base (1, 1)): a line (1,1)-(5,1). */
#define BLOCK_B                                                                                    \
    "0\nSECTION\n2\nBLOCKS\n0\nBLOCK\n2\nB\n10\n1\n20\n1\n0\nLINE\n10\n1\n20\n1\n11\n5\n21\n1\n"   \
    "0\nENDBLK\n0\nBLOCK\n2\nN\n10\n0\n20\n0\n0\nINSERT\n2\nb\n10\n10\n20\n10\n50\n90\n41\n0.5\n"  \
    "42\n0.5\n0\nENDBLK\n0\nENDSEC\n"

static void xform(double ix, double iy, double sx, double sy, double rot, double bx, double by,
                  double x, double y, double *ox, double *oy)
{
    double r = rot * M_PI / 180, px = (x - bx) * sx, py = (y - by) * sy;
    *ox = ix + cos(r) * px - sin(r) * py;
    *oy = iy + sin(r) * px + cos(r) * py;
}

static void test_insert(void **state)
{
    (void)state;
    const char *f = "0\nSECTION\n2\nHEADER\n9\n$INSUNITS\n70\n4\n0\nENDSEC\n" BLOCK_B
                    "0\nSECTION\n2\nENTITIES\n"
                    "0\nINSERT\n2\nB\n10\n100\n20\n0\n41\n2\n42\n1.5\n50\n30\n"
                    "0\nINSERT\n2\nB\n10\n0\n20\n0\n50\n10\n70\n2\n71\n3\n44\n10\n45\n20\n"
                    "0\nINSERT\n2\nN\n10\n-30\n20\n-30\n41\n3\n42\n3\n50\n-20\n"
                    "0\nINSERT\n2\nB\n10\n40\n20\n-40\n210\n0\n220\n0\n230\n-1\n"
                    "0\nENDSEC\n0\nEOF\n";
    assert_int_equal(rd(f), CS_OK);
    assert_int_equal(P.n, 1 + 6 + 1 + 1);
    double x, y;
    xform(100, 0, 2, 1.5, 30, 1, 1, 1, 1, &x, &y);
    near_pt(start_of(0), x, y, PT_TOL);
    xform(100, 0, 2, 1.5, 30, 1, 1, 5, 1, &x, &y);
    near_pt(end_of(0), x, y, PT_TOL);
    /* the array: column c, row r offset by R(10 deg) (10 c, 20 r), rows outer */
    for (int r = 0, k = 1; r < 3; r++)
        for (int c = 0; c < 2; c++, k++) {
            double a = 10 * M_PI / 180, ox = 10.0 * c, oy = 20.0 * r;
            xform(cos(a) * ox - sin(a) * oy, sin(a) * ox + cos(a) * oy, 1, 1, 10, 1, 1, 5, 1, &x,
                  &y);
            near_pt(end_of((size_t)k), x, y, PT_TOL);
        }
    /* nested: N inserts b (names are case-insensitive) at (10,10), 90 deg, x0.5; N at (-30,-30),
     * -20 deg, x3 */
    double ix, iy;
    xform(10, 10, 0.5, 0.5, 90, 1, 1, 5, 1, &ix, &iy);
    xform(-30, -30, 3, 3, -20, 0, 0, ix, iy, &x, &y);
    near_pt(end_of(7), x, y, PT_TOL);
    /* mirrored insert: (40, -40) is OCS, world (-40, -40); the line runs to -x */
    near_pt(start_of(8), -40, -40, PT_TOL);
    near_pt(end_of(8), -44, -40, PT_TOL);
}

static void test_insert_errors(void **state)
{
    (void)state;
    /* A inserts B inserts A: at the inner INSERT (its value line, 20). */
    const char *rec = "0\nSECTION\n2\nBLOCKS\n0\nBLOCK\n2\nA\n0\nINSERT\n2\nB\n0\nENDBLK\n"
                      "0\nBLOCK\n2\nB\n0\nINSERT\n2\nA\n0\nENDBLK\n0\nENDSEC\n"
                      "0\nSECTION\n2\nENTITIES\n0\nINSERT\n2\nA\n0\nENDSEC\n";
    assert_int_equal(rd(rec), CS_ERR_RANGE);
    assert_int_equal(D.loc.line, 20);
    assert_non_null(strstr(D.reason, "block 'A' inserts itself"));
    /* 17 nested blocks: deeper than CS_DXF_MAX_DEPTH */
    char buf[8192];
    size_t n = (size_t)snprintf(buf, sizeof buf, "0\nSECTION\n2\nBLOCKS\n");
    for (int i = 0; i <= CS_DXF_MAX_DEPTH; i++)
        n += (size_t)snprintf(buf + n, sizeof buf - n,
                              "0\nBLOCK\n2\nK%d\n0\nINSERT\n2\nK%d\n0\nENDBLK\n", i, i + 1);
    n += (size_t)snprintf(buf + n, sizeof buf - n,
                          "0\nBLOCK\n2\nK%d\n0\nLINE\n11\n1\n0\nENDBLK\n0\nENDSEC\n"
                          "0\nSECTION\n2\nENTITIES\n0\nINSERT\n2\nK0\n0\nENDSEC\n",
                          CS_DXF_MAX_DEPTH + 1);
    assert_int_equal(rd(buf), CS_ERR_RANGE);
    assert_non_null(strstr(D.reason, "nested deeper"));
    /* undefined block: at its name */
    assert_int_equal(rde("0\nINSERT\n2\nNOPE\n"), CS_ERR_PARSE);
    assert_int_equal(D.loc.line, 18);
    assert_non_null(strstr(D.reason, "'NOPE'"));
}

/* --- splines: de Boor in double -------------------------------------------------------------- */

/* The NURBS of degree p (n points x, y, weights w or NULL, knots kn) at u, in the span s with
 * kn[s] <= u <= kn[s+1] (The NURBS Book, A2.2 / de Boor, in homogeneous coordinates). */
static void de_boor(unsigned p, const double (*pt)[2], const double *w, const double *kn, size_t s,
                    double u, double *ox, double *oy)
{
    double d[4][3];
    for (unsigned j = 0; j <= p; j++) {
        size_t i = s - p + j;
        double wi = w ? w[i] : 1;
        d[j][0] = pt[i][0] * wi;
        d[j][1] = pt[i][1] * wi;
        d[j][2] = wi;
    }
    for (unsigned r = 1; r <= p; r++)
        for (unsigned j = p; j >= r; j--) {
            size_t i = s - p + j;
            double a = (u - kn[i]) / (kn[i + p + 1 - r] - kn[i]);
            for (int c = 0; c < 3; c++)
                d[j][c] = (1 - a) * d[j - 1][c] + a * d[j][c];
        }
    *ox = d[p][0] / d[p][2];
    *oy = d[p][1] / d[p][2];
}

/* Writes a SPLINE entity; checks every segment against de Boor over the non-empty spans of the
 * domain [kn[p], kn[n]] in order. */
static void spline_case(unsigned p, size_t n, const double (*pt)[2], const double *w,
                        const double *kn)
{
    char ent[8192];
    size_t o = (size_t)snprintf(ent, sizeof ent, "0\nSPLINE\n70\n%d\n71\n%u\n72\n%zu\n73\n%zu\n",
                                w ? 4 : 0, p, n + p + 1, n);
    for (size_t i = 0; i < n + p + 1; i++)
        o += (size_t)snprintf(ent + o, sizeof ent - o, "40\n%.17g\n", kn[i]);
    for (size_t i = 0; w && i < n; i++)
        o += (size_t)snprintf(ent + o, sizeof ent - o, "41\n%.17g\n", w[i]);
    for (size_t i = 0; i < n; i++)
        o += (size_t)snprintf(ent + o, sizeof ent - o, "10\n%.17g\n20\n%.17g\n30\n0\n", pt[i][0],
                              pt[i][1]);
    assert_int_equal(rde(ent), CS_OK);
    size_t seg = 0;
    for (size_t s = p; s < n; s++) {
        if (!(kn[s + 1] > kn[s]))
            continue;
        assert_true(seg < P.n);
        for (int k = 0; k <= 16; k++) {
            double u = kn[s] + (kn[s + 1] - kn[s]) * k / 16.0, x, y;
            de_boor(p, pt, w, kn, s, u, &x, &y);
            near_pt(cs_ref_eval(&P.elems[seg].curve, k / 16.0), x, y, SPL_TOL);
        }
        seg++;
    }
    assert_int_equal(P.n, seg);
    joined(0, P.n);
}

static void test_spline(void **state)
{
    (void)state;
    static const double pt[7][2] = {{50, 40}, {55, 50}, {60, 40}, {65, 50},
                                    {70, 40}, {72, 47}, {75, 41}};
    /* clamped, non-uniform, degree 3 */
    static const double k1[] = {0, 0, 0, 0, 1, 3, 3, 3, 3};
    spline_case(3, 5, pt, NULL, k1);
    assert_int_equal(P.elems[0].kind, CS_PATH_BSPLINE);
    /* rational, degree 2 */
    static const double w2[] = {1, 2, 0.5, 1};
    static const double k2[] = {0, 0, 0, 1, 2, 2, 2};
    spline_case(2, 4, pt, w2, k2);
    assert_true(P.elems[0].curve.rational);
    /* unclamped (uniform, as AutoCAD writes periodic splines): the domain [3, 5] */
    static const double k3[] = {0, 1, 2, 3, 4, 5, 6, 7, 8};
    spline_case(3, 5, pt, NULL, k3);
    /* closed periodic: the first 3 points repeated at the end, knots 0 .. 10: a closed curve */
    static const double pc[7][2] = {{40, 60}, {50, 70}, {60, 60}, {50, 55},
                                    {40, 60}, {50, 70}, {60, 60}};
    static const double k4[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
    spline_case(3, 7, pc, NULL, k4);
    assert_true(P.elems[0].curve.p[0].x == P.elems[P.n - 1].curve.p[3].x &&
                P.elems[0].curve.p[0].y == P.elems[P.n - 1].curve.p[3].y);
    /* degree 1; degree 2 with a double interior knot (a corner); an unclamped rational
     * degree 2 */
    static const double k5[] = {0, 0, 1, 2, 3, 4, 4};
    spline_case(1, 5, pt, NULL, k5);
    static const double k7[] = {0, 0, 0, 1, 1, 2, 2, 2};
    spline_case(2, 5, pt, NULL, k7);
    static const double w6[] = {1, 3, 1, 0.5, 2};
    static const double k6[] = {0, 0.5, 1, 2, 3, 4, 4.5, 5};
    spline_case(2, 5, pt, w6, k6);
}

static void test_spline_fit_and_errors(void **state)
{
    (void)state;
    /* Fit points only: the natural spline through them, chord-length parameter (cs_spline):
     * each segment ends on its fit point. */
    assert_int_equal(rde("0\nSPLINE\n71\n3\n74\n4\n11\n0\n21\n0\n11\n10\n21\n5\n11\n20\n21\n-"
                         "3\n11\n30\n21\n2\n"),
                     CS_OK);
    assert_int_equal(P.n, 3);
    near_pt(end_of(0), 10, 5, PT_TOL);
    near_pt(end_of(1), 20, -3, PT_TOL);
    near_pt(end_of(2), 30, 2, PT_TOL);
    /* a knot count that does not fit: at the first knot */
    assert_int_equal(
        rde("0\nSPLINE\n71\n2\n40\n0\n40\n1\n10\n0\n20\n0\n10\n1\n20\n1\n10\n2\n20\n0\n"),
        CS_ERR_PARSE);
    assert_int_equal(D.loc.line, 20);
    assert_non_null(strstr(D.reason, "need 6 knots"));
    /* decreasing knots: at the knot */
    assert_int_equal(
        rde("0\nSPLINE\n71\n1\n40\n0\n40\n0\n40\n2\n40\n1\n10\n0\n20\n0\n10\n1\n20\n1\n"),
        CS_ERR_PARSE);
    assert_int_equal(D.loc.line, 26);
    /* an interior knot p + 1 times: the curve would break there */
    assert_int_equal(rde("0\nSPLINE\n71\n1\n40\n0\n40\n0\n40\n1\n40\n1\n40\n2\n40\n2\n"
                         "10\n0\n20\n0\n10\n1\n20\n1\n10\n2\n20\n0\n10\n3\n20\n1\n"),
                     CS_ERR_PARSE);
    assert_int_equal(D.loc.line, 26); /* the knot that repeats */
    assert_non_null(strstr(D.reason, "discontinuous"));
    /* degree 5: warned, skipped */
    assert_int_equal(rde("0\nSPLINE\n71\n5\n10\n0\n20\n0\n0\nLINE\n11\n1\n"), CS_OK);
    assert_int_equal(P.n, 1);
    assert_non_null(strstr(warns, "degree 5"));
}

/* --- file-level ------------------------------------------------------------------------------- */

static void test_units(void **state)
{
    (void)state;
    static const struct {
        int code;
        double mm;
    } u[] = {{1, 25.4}, {2, 304.8}, {4, 1}, {5, 10}, {6, 1000}, {9, 0.0254}, {14, 100}};
    char f[512];
    for (size_t i = 0; i < sizeof u / sizeof u[0]; i++) {
        snprintf(f, sizeof f,
                 "0\nSECTION\n2\nHEADER\n9\n$ACADVER\n1\nAC1015\n9\n$INSUNITS\n70\n%d\n0\nENDSEC\n"
                 "0\nSECTION\n2\nENTITIES\n0\nLINE\n10\n0\n20\n0\n11\n1.5\n21\n-1\n0\nENDSEC\n",
                 u[i].code);
        assert_int_equal(rd(f), CS_OK);
        near_pt(end_of(0), 1.5 * u[i].mm, -u[i].mm, PT_TOL);
        assert_int_equal(nwarn, 0);
    }
    /* no header: unitless, warned once, read as mm; the caller's override wins */
    const char *g = "0\nSECTION\n2\nENTITIES\n0\nLINE\n11\n2\n0\nLINE\n11\n3\n0\nENDSEC\n";
    assert_int_equal(rd(g), CS_OK);
    assert_int_equal(nwarn, 1);
    assert_non_null(strstr(warns, "1:1: the drawing has no units"));
    near_pt(end_of(0), 2, 0, PT_TOL);
    assert_int_equal(rd_opts(g, false, 25.4), CS_OK);
    assert_int_equal(nwarn, 0);
    near_pt(end_of(1), 3 * 25.4, 0, PT_TOL);
    /* CRLF reads the same */
    assert_int_equal(
        rd("0\r\nSECTION\r\n2\r\nENTITIES\r\n0\r\nLINE\r\n 11\r\n 2.5 \r\n0\r\nENDSEC\r\n"), CS_OK);
    near_pt(end_of(0), 2.5, 0, PT_TOL);
}

static void test_layers_and_skipped(void **state)
{
    (void)state;
    const char *f = "0\nSECTION\n2\nHEADER\n9\n$INSUNITS\n70\n4\n0\nENDSEC\n"
                    "0\nSECTION\n2\nTABLES\n0\nTABLE\n2\nLAYER\n70\n3\n"
                    "0\nLAYER\n2\nOFF\n70\n0\n62\n-7\n0\nLAYER\n2\nFROZEN\n70\n1\n62\n7\n"
                    "0\nLAYER\n2\nON\n70\n0\n62\n1\n0\nENDTAB\n0\nENDSEC\n"
                    "0\nSECTION\n2\nENTITIES\n"
                    "0\nLINE\n8\noff\n11\n1\n0\nLINE\n8\nOFF\n11\n2\n0\nLINE\n8\nFROZEN\n11\n3\n"
                    "0\nLINE\n8\nON\n11\n4\n0\nHATCH\n8\nON\n0\nHATCH\n0\nIMAGE\n0\nPOINT\n"
                    "0\nLINE\n67\n1\n11\n5\n0\nLINE\n60\n1\n11\n6\n0\nWHATEVER\n0\nENDSEC\n";
    assert_int_equal(rd(f), CS_OK);
    assert_int_equal(P.n, 1);
    near_pt(end_of(0), 4, 0, PT_TOL);
    /* layers off and frozen once each; HATCH, IMAGE, POINT, paper space, the unknown once */
    assert_int_equal(nwarn, 7);
    assert_non_null(strstr(warns, "layer 'OFF' is off"));
    assert_non_null(strstr(warns, "layer 'FROZEN' is frozen"));
    assert_non_null(strstr(warns, "HATCH: hatches and fills are not drawn"));
    assert_non_null(strstr(warns, "paper-space"));
    assert_non_null(strstr(warns, "WHATEVER: not supported"));
    /* SOLID: the outline in the order 1 2 4 3 (the bow tie), in its OCS (here mirrored);
     * a triangle (no 13); 3DFACE: edges 1 2 3 4, edge 2 hidden (70 = 2) */
    assert_int_equal(rde("0\nSOLID\n10\n0\n20\n0\n11\n4\n21\n0\n12\n0\n22\n3\n13\n4\n23\n3\n"
                         "230\n-1\n0\nTRACE\n10\n0\n20\n0\n11\n1\n21\n0\n12\n0\n22\n1\n"
                         "0\n3DFACE\n10\n0\n20\n0\n11\n5\n21\n0\n12\n5\n22\n5\n13\n0\n23\n5\n"
                         "70\n2\n"),
                     CS_OK);
    assert_int_equal(P.n, 4 + 3 + 3);
    static const double sq[5][2] = {{0, 0}, {-4, 0}, {-4, 3}, {0, 3}, {0, 0}};
    for (int k = 0; k < 4; k++) {
        near_pt(start_of((size_t)k), sq[k][0], sq[k][1], PT_TOL);
        near_pt(end_of((size_t)k), sq[k + 1][0], sq[k + 1][1], PT_TOL);
    }
    near_pt(end_of(4), 1, 0, PT_TOL);
    near_pt(end_of(5), 0, 1, PT_TOL); /* the triangle: 1 2 3(=4) 3 */
    near_pt(end_of(6), 0, 0, PT_TOL);
    near_pt(start_of(8), 5, 5, PT_TOL); /* edge 2 (5,0)-(5,5) hidden */
    assert_true(P.elems[8].subpath != P.elems[7].subpath);
    assert_int_equal(nwarn, 1);
    assert_non_null(strstr(warns, "their outline is"));
    /* DIMENSION draws its block; LEADER its line */
    const char *g =
        "0\nSECTION\n2\nBLOCKS\n0\nBLOCK\n2\n*D1\n0\nLINE\n10\n0\n20\n-10\n11\n50\n21\n-10\n"
        "0\nENDBLK\n0\nENDSEC\n0\nSECTION\n2\nENTITIES\n0\nDIMENSION\n2\n*D1\n"
        "0\nLEADER\n10\n0\n20\n0\n10\n5\n20\n5\n10\n9\n20\n5\n0\nENDSEC\n";
    assert_int_equal(rd_opts(g, false, 1), CS_OK);
    assert_int_equal(P.n, 3);
    near_pt(end_of(0), 50, -10, PT_TOL);
    near_pt(end_of(2), 9, 5, PT_TOL);
}

static void test_text(void **state)
{
    (void)state;
    if (!have_font)
        skip();
    /* "L" of cap height 10 at (5, 5): its stem from y = 15 down to the baseline y = 5 */
    const char *f = "0\nSECTION\n2\nENTITIES\n0\nTEXT\n10\n5\n20\n5\n40\n10\n1\nL\n0\nENDSEC\n";
    assert_int_equal(rd_opts(f, true, 1), CS_OK);
    assert_true(P.n >= 2);
    double lo = 1e9, hi = -1e9, xlo = 1e9;
    for (size_t i = 0; i < P.n; i++)
        for (int k = 0; k <= 1; k++) {
            cs_ref_vec_t q = cs_ref_eval(&P.elems[i].curve, k);
            lo = fmin(lo, q.y);
            hi = fmax(hi, q.y);
            xlo = fmin(xlo, q.x);
        }
    assert_true(fabs(lo - 5) < 1e-3 && fabs(hi - 15) < 1e-3 && xlo >= 5);
    /* rotated 90 degrees: the stem lies along -x from the point */
    const char *g =
        "0\nSECTION\n2\nENTITIES\n0\nTEXT\n10\n5\n20\n5\n40\n10\n50\n90\n1\nL\n0\nENDSEC\n";
    assert_int_equal(rd_opts(g, true, 1), CS_OK);
    double xmin = 1e9, xmax = -1e9;
    for (size_t i = 0; i < P.n; i++)
        for (int k = 0; k <= 1; k++) {
            cs_ref_vec_t q = cs_ref_eval(&P.elems[i].curve, k);
            xmin = fmin(xmin, q.x);
            xmax = fmax(xmax, q.x);
        }
    assert_true(fabs(xmin + 5) < 1e-3 && fabs(xmax - 5) < 1e-3);
    /* MTEXT: two lines (\P), top-left attached: the first cap top at y = 0, the second
     * baseline 5/3 h below the first (-h - 5/3 h) */
    const char *m = "0\nSECTION\n2\nENTITIES\n0\nMTEXT\n10\n0\n20\n0\n40\n3\n71\n1\n"
                    "1\n{\\fArial|b0;L}\\PL\n0\nENDSEC\n";
    assert_int_equal(rd_opts(m, true, 1), CS_OK);
    lo = 1e9;
    hi = -1e9;
    for (size_t i = 0; i < P.n; i++)
        for (int k = 0; k <= 1; k++) {
            cs_ref_vec_t q = cs_ref_eval(&P.elems[i].curve, k);
            lo = fmin(lo, q.y);
            hi = fmax(hi, q.y);
        }
    assert_true(fabs(hi - 0) < 1e-3 && fabs(lo - (-3 - 5.0)) < 1e-3);
    /* control codes: %%d and \U+00B0 are both the degree sign 'o', \U+0041 is 'A': the same
     * strokes as "1o1oA" */
    const char *c1 =
        "0\nSECTION\n2\nENTITIES\n0\nTEXT\n40\n5\n1\n1%%d1\\U+00B0\\U+0041\n0\nENDSEC\n";
    const char *c2 = "0\nSECTION\n2\nENTITIES\n0\nTEXT\n40\n5\n1\n1o1oA\n0\nENDSEC\n";
    assert_int_equal(rd_opts(c2, true, 1), CS_OK);
    size_t n2 = P.n;
    cs_ref_vec_t last2 = end_of(n2 - 1);
    assert_int_equal(rd_opts(c1, true, 1), CS_OK);
    assert_int_equal(P.n, n2);
    near_pt(end_of(P.n - 1), last2.x, last2.y, PT_TOL);
    /* no font: skipped with one warning */
    assert_int_equal(rd_opts(f, false, 1), CS_OK);
    assert_int_equal(P.n, 0);
    assert_int_equal(nwarn, 1);
    assert_non_null(strstr(warns, "text is not drawn (no stroke font"));
}

static void test_errors(void **state)
{
    (void)state;
    /* a code line that is no integer: its line */
    assert_int_equal(rd("0\nSECTION\n2\nENTITIES\n0\nLINE\nten\n1\n"), CS_ERR_PARSE);
    assert_int_equal(D.loc.line, 7);
    /* a value that is no number: its line and column */
    assert_int_equal(rd("0\nSECTION\n2\nENTITIES\n0\nLINE\n10\n   1.5x\n"), CS_ERR_PARSE);
    assert_int_equal(D.loc.line, 8);
    assert_int_equal(D.loc.col, 4);
    /* the file ends after a code */
    assert_int_equal(rd("0\nSECTION\n2\nENTITIES\n0\nLINE\n10"), CS_ERR_PARSE);
    assert_int_equal(D.loc.line, 7);
    /* binary DXF */
    assert_int_equal(cs_dxf_read("b.dxf", "AutoCAD Binary DXF\r\n\x1a", 21, NULL, &P, &D),
                     CS_ERR_PARSE);
    assert_int_equal(D.loc.line, 1);
    assert_non_null(strstr(D.reason, "binary DXF"));
    /* negative radius; a point beyond the range */
    assert_int_equal(rde("0\nCIRCLE\n10\n0\n20\n0\n40\n-1\n"), CS_ERR_PARSE);
    assert_int_equal(D.loc.line, 22);
    assert_int_equal(rde("0\nLINE\n10\n0\n20\n0\n11\n5000\n21\n0\n"), CS_ERR_RANGE);
}

static void test_detect(void **state)
{
    (void)state;
    const char *f = "  0\r\nSECTION\r\n  2\r\nHEADER\r\n";
    assert_int_equal(cs_input_detect("a.DXF", "", 0), CS_INPUT_DXF);
    assert_int_equal(cs_input_detect(NULL, f, strlen(f)), CS_INPUT_DXF);
    const char *lc = "  999\ndxfrw 0.6.3\n  0\nSECTION\n";
    assert_int_equal(cs_input_detect(NULL, lc, strlen(lc)), CS_INPUT_DXF); /* LibreCAD's start */
    assert_int_equal(cs_input_detect(NULL, "0\nSECTION\n", 10), CS_INPUT_DXF);
    assert_int_equal(cs_input_detect(NULL, "0\nSECTIONS\n", 11), CS_INPUT_SVG);
    assert_int_equal(cs_input_detect(NULL, "0 0 L 1 1", 9), CS_INPUT_SVG);
    assert_true(cs_dxf_is("AutoCAD Binary DXF\r\n", 20));
    assert_string_equal(cs_input_format_name(CS_INPUT_DXF), "dxf");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_line),     cmocka_unit_test(test_circle_arc),
        cmocka_unit_test(test_ellipse),  cmocka_unit_test(test_bulge),
        cmocka_unit_test(test_polyline), cmocka_unit_test(test_extrusion),
        cmocka_unit_test(test_insert),   cmocka_unit_test(test_insert_errors),
        cmocka_unit_test(test_spline),   cmocka_unit_test(test_spline_fit_and_errors),
        cmocka_unit_test(test_units),    cmocka_unit_test(test_layers_and_skipped),
        cmocka_unit_test(test_text),     cmocka_unit_test(test_errors),
        cmocka_unit_test(test_detect),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
