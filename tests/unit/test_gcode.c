/* test_gcode: G-code text (host/cs_gcode.c) -> path elements, compared with geometry computed
 * here in double: line end points, points on arcs (radius, centre, direction of turn, sweep),
 * helix pitch, LinuxCNC's published G5 facts, the G5.1 parabola y = x^2, G5.2 against a double
 * Cox-de Boor NURBS evaluation; units, G91, G90.1, G92, feed, subpaths; every error with its
 * file:line:col; the cncjs fixtures in tests/data/gcode. Tolerances: points given in the file
 * are rounded once (0.5 LSB); arc pieces stay within 2 LSB of the exact circle (cs_arc.h) plus
 * 2 LSB for the end snapping (4 LSB); helices add the stated helix tolerance (0.001 mm).
 * Run from the repository root. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_gcode.h"

#define LSB     (1.0 / 65536.0)
#define PT_TOL  (0.5 * LSB + 1e-9)
#define ARC_TOL (4 * LSB)
#define DATA    "tests/data/gcode/"

static cs_path_t P;
static cs_path_diag_t D;
static cs_gcode_stats_t S;
static int nwarn;
static char last_warn[600];

static void on_warn(void *ctx, const cs_path_diag_t *w)
{
    (void)ctx;
    nwarn++;
    snprintf(last_warn, sizeof last_warn, "%s:%u:%u: %s", w->loc.file, w->loc.line, w->loc.col,
             w->reason);
}

/* Reads text with options o (its warn set here). */
static cs_err_t parse_with(const char *text, cs_gcode_opts_t *o)
{
    cs_path_free(&P);
    cs_path_init(&P);
    memset(&D, 0, sizeof D);
    nwarn = 0;
    last_warn[0] = '\0';
    o->warn = on_warn;
    return cs_gcode_read("t.nc", text, strlen(text), o, &P, &D, &S);
}

static cs_err_t parse_opts(const char *text, bool lenient)
{
    cs_gcode_opts_t o;
    cs_gcode_opts_init(&o);
    o.lenient = lenient;
    return parse_with(text, &o);
}

static cs_err_t parse_dialect(const char *text, cs_gcode_dialect_t d)
{
    cs_gcode_opts_t o;
    cs_gcode_opts_init(&o);
    o.dialect = d;
    return parse_with(text, &o);
}

static cs_err_t parse(const char *text)
{
    return parse_opts(text, false);
}

static char *slurp(const char *name, size_t *len)
{
    FILE *f = fopen(name, "rb");
    assert_non_null(f);
    char *b = malloc(1 << 16);
    assert_non_null(b);
    *len = fread(b, 1, 1 << 16, f);
    fclose(f);
    return b;
}

static cs_err_t parse_file(const char *name, bool lenient)
{
    size_t len;
    char *b = slurp(name, &len);
    cs_path_free(&P);
    cs_path_init(&P);
    nwarn = 0;
    cs_gcode_opts_t o;
    cs_gcode_opts_init(&o);
    o.lenient = lenient;
    o.warn = on_warn;
    cs_err_t e = cs_gcode_read(name, b, len, &o, &P, &D, &S);
    free(b);
    return e;
}

/* The diagnostic must be exactly at line:col with code. */
static void expect_diag(cs_err_t e, cs_err_t code, unsigned line, unsigned col)
{
    if (e != code || D.loc.line != line || D.loc.col != col)
        print_error("got %d at %u:%u (%s), expected %d at %u:%u\n", e, D.loc.line, D.loc.col,
                    D.reason, code, line, col);
    assert_int_equal(e, code);
    assert_int_equal(D.loc.line, line);
    assert_int_equal(D.loc.col, col);
    assert_true(strlen(D.reason) > 0);
}

static void pt(size_t el, unsigned i, double out[3])
{
    const cs_vec3_t *p = &P.elems[el].curve.p[i];
    out[0] = p->x * LSB;
    out[1] = p->y * LSB;
    out[2] = p->z * LSB;
}

static void expect_pt(size_t el, unsigned i, double x, double y, double z, double tol)
{
    double p[3];
    pt(el, i, p);
    if (fabs(p[0] - x) > tol || fabs(p[1] - y) > tol || fabs(p[2] - z) > tol)
        print_error("elem %zu point %u = (%.9f, %.9f, %.9f), expected (%.9f, %.9f, %.9f)\n", el, i,
                    p[0], p[1], p[2], x, y, z);
    assert_true(fabs(p[0] - x) <= tol && fabs(p[1] - y) <= tol && fabs(p[2] - z) <= tol);
}

static void end_of(size_t el, double out[3])
{
    pt(el, P.elems[el].curve.degree, out);
}

/* Every element starts exactly where the previous one of its subpath ended. */
static void expect_continuous(void)
{
    for (size_t i = 1; i < P.n; i++) {
        const cs_bezier_t *a = &P.elems[i - 1].curve, *b = &P.elems[i].curve;
        const cs_vec3_t *e = &a->p[a->degree];
        assert_true(e->x == b->p[0].x && e->y == b->p[0].y && e->z == b->p[0].z);
    }
}

/* Samples every element from `first` on (n points each) and checks they lie on the circle of
 * radius r around (cx, cy) in the plane axes (i0, i1), within tol; the third axis must equal
 * z0 + pitch_per_rad * (turned angle) within ztol. Returns the signed total angle turned. */
static double check_circle(size_t first, int i0, int i1, double cx, double cy, double r, double tol,
                           double z0, double pitch_per_rad, double ztol)
{
    int in = 3 - i0 - i1;
    double turned = 0, prev = 0;
    bool have = false;
    for (size_t k = first; k < P.n; k++) {
        for (int s = 0; s <= 64; s++) {
            double q[3];
            cs_path_eval_mm(&P.elems[k].curve, s / 64.0, q);
            double dx = q[i0] - cx, dy = q[i1] - cy;
            double rr = hypot(dx, dy);
            if (fabs(rr - r) > tol)
                print_error("elem %zu t=%g: radius %.9f, expected %.9f\n", k, s / 64.0, rr, r);
            assert_true(fabs(rr - r) <= tol);
            double a = atan2(dy, dx);
            if (have) {
                double d = a - prev;
                while (d > M_PI)
                    d -= 2 * M_PI;
                while (d < -M_PI)
                    d += 2 * M_PI;
                turned += d;
            }
            prev = a;
            have = true;
            double zexp = z0 + pitch_per_rad * fabs(turned);
            if (fabs(q[in] - zexp) > ztol)
                print_error("elem %zu t=%g: third axis %.9f, expected %.9f\n", k, s / 64.0, q[in],
                            zexp);
            assert_true(fabs(q[in] - zexp) <= ztol);
        }
    }
    return turned;
}

/* ---- lines, units, modes ----------------------------------------------------------------- */

static void test_g0_g1_lines_feed_rapid(void **state)
{
    (void)state;
    assert_int_equal(parse("G0 X1 Y2\nG1 X3 Y4 Z5 F600\n"), CS_OK);
    assert_int_equal(P.n, 2);
    assert_int_equal(P.elems[0].curve.degree, 1);
    expect_pt(0, 0, 0, 0, 0, PT_TOL);
    expect_pt(0, 1, 1, 2, 0, PT_TOL);
    assert_true(P.elems[0].rapid);
    assert_true(P.elems[0].feed_mm_s == 0.0);
    expect_pt(1, 1, 3, 4, 5, PT_TOL);
    assert_false(P.elems[1].rapid);
    assert_true(fabs(P.elems[1].feed_mm_s - 600.0 / 60.0) < 1e-12);
    /* A rapid and a feed move are different subpaths (the travel is not drawn). */
    assert_int_not_equal(P.elems[0].subpath, P.elems[1].subpath);
    assert_int_equal(P.elems[1].loc.line, 2);
    assert_int_equal(P.elems[1].loc.col, 1);
}

static void test_modal_motion_and_lowercase(void **state)
{
    (void)state;
    assert_int_equal(parse("g1 x1 f60\ny1\nX0\n"), CS_OK);
    assert_int_equal(P.n, 3);
    expect_pt(1, 1, 1, 1, 0, PT_TOL);
    expect_pt(2, 1, 0, 1, 0, PT_TOL);
    assert_true(fabs(P.elems[2].feed_mm_s - 1.0) < 1e-12);
    expect_continuous();
}

static void test_units_inch_and_incremental(void **state)
{
    (void)state;
    assert_int_equal(parse("G20 G91 G1 X1 Y1 F60\nX1\nG21 Y-10\n"), CS_OK);
    assert_int_equal(P.n, 3);
    expect_pt(0, 1, 25.4, 25.4, 0, PT_TOL);
    expect_pt(1, 1, 50.8, 25.4, 0, PT_TOL);
    expect_pt(2, 1, 50.8, 15.4, 0, PT_TOL);
    /* F60 in inches per minute = 25.4 mm/s; after G21 the same F60 means 1 mm/s. */
    assert_true(fabs(P.elems[0].feed_mm_s - 25.4) < 1e-12);
    assert_true(fabs(P.elems[2].feed_mm_s - 1.0) < 1e-12);
}

static void test_g92_offsets(void **state)
{
    (void)state;
    assert_int_equal(parse("G1 X5 Y5 F60\nG92 X10 Y10\nG1 X11 Y12\nG92.1\nG1 X0 Y0\n"), CS_OK);
    assert_int_equal(P.n, 3);
    /* (5,5) is now (10,10): X11 Y12 is (6,7) in machine coordinates. */
    expect_pt(1, 1, 6, 7, 0, PT_TOL);
    expect_pt(2, 1, 0, 0, 0, PT_TOL);
}

static void test_subpaths_pen_and_program_end(void **state)
{
    (void)state;
    assert_int_equal(parse("M3 S1000\nG1 X1 F60\nM5\nG1 X2\nM3\nG1 X3\nM2\nG1 X9\n"), CS_OK);
    assert_int_equal(P.n, 3); /* nothing after M2 */
    assert_int_equal(P.nsubpaths, 3);
    assert_int_equal(P.elems[2].subpath, 2);
    assert_int_equal(parse("G1 X1 F60\nM30\nG1 X9\n"), CS_OK);
    assert_int_equal(P.n, 1);
}

static void test_pen_z_moves(void **state)
{
    (void)state;
    cs_path_free(&P);
    cs_path_init(&P);
    cs_gcode_opts_t o;
    cs_gcode_opts_init(&o);
    o.pen_z = true;
    o.pen_down_z_mm = -1;
    o.pen_up_z_mm = 2.5;
    const char *t = "G0 X5\nM3\nG1 X10 F60\nM5\nG0 X0\n";
    assert_int_equal(cs_gcode_read("t.nc", t, strlen(t), &o, &P, &D, NULL), CS_OK);
    assert_int_equal(P.n, 5);
    expect_pt(0, 0, 0, 0, 2.5, PT_TOL); /* the program starts pen up: G0 X5 travels at Z2.5 */
    expect_pt(1, 0, 5, 0, 2.5, PT_TOL);
    expect_pt(1, 1, 5, 0, -1, PT_TOL); /* M3: down to Z-1, rapid */
    assert_true(P.elems[1].rapid);
    expect_pt(2, 1, 10, 0, -1, PT_TOL);
    assert_false(P.elems[2].rapid);
    expect_pt(3, 1, 10, 0, 2.5, PT_TOL); /* M5: up to Z2.5 */
    assert_true(P.elems[3].rapid);
    expect_pt(4, 1, 0, 0, 2.5, PT_TOL);
    expect_continuous();
    assert_int_equal(P.elems[3].loc.line, 4);
    assert_int_equal(P.elems[3].loc.col, 1);
}

static void test_comments_line_numbers_block_delete(void **state)
{
    (void)state;
    assert_int_equal(parse("%\n(header ; with a semicolon)\nN10 G1 X1 (mid) Y2 F60 ; tail (x\n"
                           "/G1 X100\n  \nN20 G1 X3\n%\n"),
                     CS_OK);
    assert_int_equal(P.n, 2);
    expect_pt(0, 1, 1, 2, 0, PT_TOL);
    expect_pt(1, 1, 3, 2, 0, PT_TOL);
    assert_int_equal(P.elems[1].loc.line, 6);
    assert_int_equal(P.elems[1].loc.col, 5);
    expect_diag(parse("G1 X1 F1\nG1 (open\n"), CS_ERR_PARSE, 2, 4);
}

/* XOR of the bytes of s, as RepRap firmware computes it. */
static unsigned xor_of(const char *s)
{
    unsigned x = 0;
    while (*s)
        x ^= (unsigned char)*s++;
    return x;
}

static void test_checksums(void **state)
{
    (void)state;
    char text[200];
    snprintf(text, sizeof text, "N1 G1 X1 F60*%u\nN2 G1 X2*%u ; ok\n", xor_of("N1 G1 X1 F60"),
             xor_of("N2 G1 X2"));
    assert_int_equal(parse(text), CS_OK);
    assert_int_equal(P.n, 2);
    snprintf(text, sizeof text, "N1 G1 X1 F60\nN2 G1 X2*%u\n", (xor_of("N2 G1 X2") + 1) & 255);
    expect_diag(parse(text), CS_ERR_PARSE, 2, 9);
    assert_non_null(strstr(D.reason, "checksum"));
    expect_diag(parse("G1 X1 F60*\n"), CS_ERR_PARSE, 1, 10);
    expect_diag(parse("G1 X1 F60*300\n"), CS_ERR_PARSE, 1, 10);
}

static void test_unsupported_strict_and_lenient(void **state)
{
    (void)state;
    expect_diag(parse("G1 X1 F60\nG4 P1\n"), CS_ERR_UNSUPPORTED, 2, 1);
    /* A dwell of no time is nothing to do, in both dialects; any other stays unsupported. */
    assert_int_equal(parse("G1 X1 F60\nG4 P0\nG1 X2\n"), CS_OK);
    assert_int_equal(P.n, 2);
    assert_int_equal(parse_dialect("G1 X1 F60\nG4 P0.000\n", CS_GCODE_GRBL), CS_OK);
    expect_diag(parse("G1 X1 F60\nG4 P0.01\n"), CS_ERR_UNSUPPORTED, 2, 1);
    expect_diag(parse("G1 X1 F60\nG4\n"), CS_ERR_UNSUPPORTED, 2, 1);
    expect_diag(parse("G1 X1 F60\nG4 P0 X3\n"), CS_ERR_UNSUPPORTED, 2, 1);
    expect_diag(parse("G1 X1 F60 M6\n"), CS_ERR_UNSUPPORTED, 1, 11);
    expect_diag(parse("G1 X1 A3 F60\n"), CS_ERR_UNSUPPORTED, 1, 7);
    assert_int_equal(parse_opts("G1 X1 F60\nG4 P1\nG1 X2 A3\n", true), CS_OK);
    assert_int_equal(P.n, 2);
    expect_pt(1, 1, 2, 0, 0, PT_TOL);
    assert_true(nwarn >= 2);
}

/* --lenient drops a canned cycle with its moves, and G52/G33 with their axis words: executing
 * those words as ordinary moves could drive the tool into the work. */
static void test_lenient_drops_words_of_dropped_codes(void **state)
{
    (void)state;
    const char *t = "G0 Z5\nG85 X1 Y1 Z-1 R1 Q0.5 F100\nX2 Y2\nG80\nG0 X3\nG52 X0 Y0\nG33 Z0 K1\n"
                    "G1 X4 F60\n";
    expect_diag(parse(t), CS_ERR_UNSUPPORTED, 2, 1);
    assert_int_equal(parse_opts(t, true), CS_OK);
    assert_int_equal(P.n, 3);
    expect_pt(0, 1, 0, 0, 5, PT_TOL);
    expect_pt(1, 1, 3, 0, 5, PT_TOL);
    expect_pt(2, 1, 4, 0, 5, PT_TOL);
    expect_continuous();
    /* One warning per skipped block, naming the code and every word skipped with it: the G85
     * line, its modal repeat "X2 Y2", G52, G33. */
    assert_int_equal(nwarn, 4);
    assert_non_null(strstr(last_warn, "t.nc:7:1: G33 is not supported: its block skipped, with "
                                      "its words Z0 K1"));
}

static void test_syntax_errors(void **state)
{
    (void)state;
    expect_diag(parse("G1 X1 X2 F1\n"), CS_ERR_PARSE, 1, 7);
    expect_diag(parse("G1 X F1\n"), CS_ERR_PARSE, 1, 4);
    expect_diag(parse("G1 X1 F1\nG1 X2 $\n"), CS_ERR_PARSE, 2, 7);
    /* A Fanuc-style program number line: refused at its O, saying what it is. */
    expect_diag(parse("%\nO1001 (PART)\nG0 X1\n"), CS_ERR_PARSE, 2, 1);
    assert_non_null(strstr(D.reason, "program number"));
    /* A UTF-8 byte order mark is skipped (in both dialects), columns counted after it. */
    assert_int_equal(parse("\xef\xbb\xbfG1 X1 F60\n"), CS_OK);
    expect_pt(0, 1, 1, 0, 0, PT_TOL);
    assert_int_equal(parse_dialect("\xef\xbb\xbfG1 X1 F60\n", CS_GCODE_GRBL), CS_OK);
    expect_diag(parse("\xef\xbb\xbfG1 X1 $\n"), CS_ERR_PARSE, 1, 7);
    expect_diag(parse("G1 X1\xef\xbb\xbf\n"), CS_ERR_PARSE, 1, 6); /* elsewhere: a stray byte */
    expect_diag(parse("G0 G1 X1\n"), CS_ERR_PARSE, 1, 4);
    expect_diag(parse("X1 Y1\n"), CS_ERR_PARSE, 1, 1);
    expect_diag(parse("G1 X1 I2 F1\n"), CS_ERR_PARSE, 1, 7);
    expect_diag(parse("G1 X1 F0\n"), CS_ERR_PARSE, 1, 7);
    expect_diag(parse("G1 X5000 F1\n"), CS_ERR_RANGE, 1, 1);
    expect_diag(parse("G1.5 X1\n"), CS_ERR_UNSUPPORTED, 1, 1);
}

/* LinuxCNC "Polar Coordinates": @ distance, ^ angle (degrees) of X Y about the program origin;
 * G91 adds them to the current point's. The reference's own square: "F100 G1 @.5 ^90 / G91
 * ^90 / ^90 / ^90 / ^90" visits (0, .5) (-.5, 0) (0, -.5) (.5, 0) (0, .5). */
static void test_polar_coordinates(void **state)
{
    (void)state;
    assert_int_equal(parse("F100 G1 @.5 ^90\nG91 ^90\n^90\n^90\n^90\n"), CS_OK);
    const double sq[5][2] = {{0, .5}, {-.5, 0}, {0, -.5}, {.5, 0}, {0, .5}};
    assert_int_equal(P.n, 5);
    for (size_t k = 0; k < 5; k++)
        expect_pt(k, 1, sq[k][0], sq[k][1], 0, PT_TOL);
    /* G90 with one of them: the other kept from the current point (5 at 53.13 deg). */
    assert_int_equal(parse("G0 X3 Y4\nG0 ^0\nG0 X3 Y4\nG0 @10\n"), CS_OK);
    expect_pt(1, 1, 5, 0, 0, PT_TOL);
    expect_pt(3, 1, 6, 8, 0, PT_TOL);
    /* About the program origin: work offsets apply (G54 X 10). */
    assert_int_equal(parse("G10 L2 P1 X10\nG0 @2 ^90\n"), CS_OK);
    expect_pt(0, 1, 10, 2, 0, PT_TOL);
    /* An arc's end: a quarter circle from (1, 0) to (0, 1). */
    assert_int_equal(parse("G0 X1 Y0\nG3 @1 ^90 I-1 J0 F60\n"), CS_OK);
    double e[3];
    end_of(P.n - 1, e);
    assert_true(fabs(e[0]) <= PT_TOL && fabs(e[1] - 1) <= PT_TOL);
    /* LinuxCNC's nc_files/hole-circle.ngc, in short: G91 G81 with ^60 L6 drills six holes 60
     * degrees apart on its 1.5 in circle, R and Z incremental. */
    assert_int_equal(parse("G20 G0 X1.5 Y0 Z0\nG91 G81 R.1 Z-.5 ^60 L6 F10\n"), CS_OK);
    assert_int_equal(P.n, 20);
    expect_pt(1, 1, 38.1, 0, 2.54, PT_TOL);
    for (int k = 0; k < 6; k++) {
        double th = (k + 1) * M_PI / 3;
        expect_pt((size_t)(3 + 3 * k), 1, 38.1 * cos(th), 38.1 * sin(th), -10.16, PT_TOL);
        expect_pt((size_t)(4 + 3 * k), 1, 38.1 * cos(th), 38.1 * sin(th), 2.54, PT_TOL);
    }
    expect_continuous();
    /* Errors: G91 at the origin (no angle), X or Y with them, unused, twice, Grbl. */
    expect_diag(parse("G91 G0 ^90\n"), CS_ERR_PARSE, 1, 8);
    expect_diag(parse("G0 X1 @1\n"), CS_ERR_PARSE, 1, 4);
    expect_diag(parse("G10 L2 P1 @1\n"), CS_ERR_PARSE, 1, 11);
    expect_diag(parse("G0 @1 @2\n"), CS_ERR_PARSE, 1, 7);
    expect_diag(parse_dialect("G0 @1\n", CS_GCODE_GRBL), CS_ERR_UNSUPPORTED, 1, 4);
}

/* ---- arcs -------------------------------------------------------------------------------- */

static void test_arc_ijk_quarter_both_directions(void **state)
{
    (void)state;
    assert_int_equal(parse("G1 X10 Y0 F60\nG3 X0 Y10 I-10 J0\n"), CS_OK);
    assert_int_equal(S.arcs, 1);
    expect_pt(1, 0, 10, 0, 0, 0);
    double e[3];
    end_of(P.n - 1, e);
    assert_true(fabs(e[0]) <= PT_TOL && fabs(e[1] - 10) <= PT_TOL);
    double turned = check_circle(1, 0, 1, 0, 0, 10, ARC_TOL, 0, 0, PT_TOL);
    assert_true(fabs(turned - M_PI / 2) < 1e-6);
    assert_int_equal(P.elems[1].kind, CS_PATH_ARC);
    expect_continuous();
    /* G2 between the same points goes the long way round, clockwise. */
    assert_int_equal(parse("G1 X10 Y0 F60\nG2 X0 Y10 I-10 J0\n"), CS_OK);
    turned = check_circle(1, 0, 1, 0, 0, 10, ARC_TOL, 0, 0, PT_TOL);
    assert_true(fabs(turned + 3 * M_PI / 2) < 1e-6);
    expect_continuous();
    /* G90.1: the centre is given absolutely. */
    assert_int_equal(parse("G90.1 G1 X12 Y2 F60\nG3 X2 Y12 I2 J2\n"), CS_OK);
    turned = check_circle(1, 0, 1, 2, 2, 10, ARC_TOL, 0, 0, PT_TOL);
    assert_true(fabs(turned - M_PI / 2) < 1e-6);
}

static void test_arc_planes(void **state)
{
    (void)state;
    /* G18: Z then X, counter-clockwise about +Y; G2 from Z20 to X20 about the origin turns
     * clockwise (through X-20): three quarters. */
    assert_int_equal(parse("G18\nG1 X0 Z20 F200\nG2 X20 Z0 I0 K-20.0\n"), CS_OK);
    double turned = check_circle(1, 2, 0, 0, 0, 20, ARC_TOL, 0, 0, PT_TOL);
    assert_true(fabs(turned + 3 * M_PI / 2) < 1e-6);
    assert_int_equal(parse("G18\nG1 X0 Z20 F200\nG3 X20 Z0 I0 K-20.0\n"), CS_OK);
    turned = check_circle(1, 2, 0, 0, 0, 20, ARC_TOL, 0, 0, PT_TOL);
    assert_true(fabs(turned - M_PI / 2) < 1e-6);
    /* G19: Y then Z. */
    assert_int_equal(parse("G19\nG1 Y0 Z20 F200\nG2 Y20 Z0 J0 K-20.0\n"), CS_OK);
    turned = check_circle(1, 1, 2, 0, 0, 20, ARC_TOL, 0, 0, PT_TOL);
    assert_true(fabs(turned + M_PI / 2) < 1e-6);
    /* An offset word of the wrong plane is refused. */
    expect_diag(parse("G1 X10 F60\nG2 X0 Y10 I-10 K1\n"), CS_ERR_PARSE, 2, 16);
}

static void test_arc_full_circle_and_turns(void **state)
{
    (void)state;
    assert_int_equal(parse("G1 X10 Y0 F60\nG2 X10 Y0 I-10 J0\n"), CS_OK);
    double turned = check_circle(1, 0, 1, 0, 0, 10, ARC_TOL, 0, 0, PT_TOL);
    assert_true(fabs(turned + 2 * M_PI) < 1e-6);
    assert_int_equal(parse("G1 X10 Y0 F60\nG3 X10 Y0 I-10 J0 P3\n"), CS_OK);
    turned = check_circle(1, 0, 1, 0, 0, 10, ARC_TOL, 0, 0, PT_TOL);
    assert_true(fabs(turned - 6 * M_PI) < 1e-6);
    /* A full circle from the current point with only I (LinuxCNC allows no axis words). */
    assert_int_equal(parse("G1 X5 F60\nG3 I5\n"), CS_OK);
    turned = check_circle(1, 0, 1, 10, 0, 5, ARC_TOL, 0, 0, PT_TOL);
    assert_true(fabs(turned - 2 * M_PI) < 1e-6);
}

static void test_arc_r_form(void **state)
{
    (void)state;
    /* G2 R10 from (0,0) to (10,10): centre right of the chord, (10,0): the short quarter. */
    assert_int_equal(parse("G1 X0 Y0 F60\nG2 X10 Y10 R10\n"), CS_OK);
    double turned = check_circle(0, 0, 1, 10, 0, 10, ARC_TOL, 0, 0, PT_TOL);
    assert_true(fabs(turned + M_PI / 2) < 1e-6);
    /* the long way, centre (0,10). */
    assert_int_equal(parse("G1 X0 Y0 F60\nG2 X10 Y10 R-10\n"), CS_OK);
    turned = check_circle(0, 0, 1, 0, 10, 10, ARC_TOL, 0, 0, PT_TOL);
    assert_true(fabs(turned + 3 * M_PI / 2) < 1e-6);
    /* G3 R10: centre (0,10), short, counter-clockwise. */
    assert_int_equal(parse("G1 X0 Y0 F60\nG3 X10 Y10 R10\n"), CS_OK);
    turned = check_circle(0, 0, 1, 0, 10, 10, ARC_TOL, 0, 0, PT_TOL);
    assert_true(fabs(turned - M_PI / 2) < 1e-6);
    /* Semicircle: chord = 2R. */
    assert_int_equal(parse("G1 X0 Y0 F60\nG2 X20 Y0 R10\n"), CS_OK);
    turned = check_circle(0, 0, 1, 10, 0, 10, ARC_TOL, 0, 0, PT_TOL);
    assert_true(fabs(turned + M_PI) < 1e-6);
}

/* The offset along the plane's normal (FreeCAD's posts write "G2 X.. Y.. I.. J.. K0.000" on
 * every arc): LinuxCNC refuses it at the word, Grbl ignores it, --lenient ignores it with one
 * warning for the whole program. The arc is the one drawn without it in every case. */
static void test_arc_off_plane_offset(void **state)
{
    (void)state;
    const char *t = "G17 G1 X10 Y0 F60\nG3 X0 Y10 I-10 J0 K0.000\nG3 X-10 Y0 I0 J-10 K0.000\n";
    expect_diag(parse(t), CS_ERR_PARSE, 2, 19);
    assert_non_null(strstr(D.reason, "--dialect grbl"));
    /* Grbl: silently, as Grbl does for K0; a non-zero K is warned (once) and ignored too. */
    assert_int_equal(parse_dialect(t, CS_GCODE_GRBL), CS_OK);
    assert_int_equal(nwarn, 0);
    double turned = check_circle(1, 0, 1, 0, 0, 10, ARC_TOL, 0, 0, PT_TOL);
    assert_true(fabs(turned - M_PI) < 1e-6);
    assert_int_equal(parse_dialect("G1 X10 F60\nG3 X0 Y10 I-10 K5\n", CS_GCODE_GRBL), CS_OK);
    assert_int_equal(nwarn, 1);
    turned = check_circle(1, 0, 1, 0, 0, 10, ARC_TOL, 0, 0, PT_TOL);
    assert_true(fabs(turned - M_PI / 2) < 1e-6);
    /* --lenient: both arcs drawn, one warning printed, both counted. */
    assert_int_equal(parse_opts(t, true), CS_OK);
    assert_int_equal(nwarn, 1);
    assert_int_equal(S.warnings, 2);
    assert_non_null(strstr(last_warn, "t.nc:2:19: K word in a G17-plane arc: ignored"));
    assert_non_null(strstr(last_warn, "(reported once)"));
    turned = check_circle(1, 0, 1, 0, 0, 10, ARC_TOL, 0, 0, PT_TOL);
    assert_true(fabs(turned - M_PI) < 1e-6);
    expect_continuous();
    /* G18 (Z-X, I/K): J is the normal's word. */
    expect_diag(parse("G18 G1 X10 F60\nG3 X0 Z-10 I-10 J0\n"), CS_ERR_PARSE, 2, 17);
    assert_int_equal(parse_dialect("G18 G1 X10 F60\nG3 X0 Z-10 I-10 J0\n", CS_GCODE_GRBL),
                     CS_OK);
}

/* A word --lenient ignores (nothing moves for it) is reported once per program, at its first
 * place, however often the CAM file repeats it; each is still counted. A skipped block (it
 * would have moved) is reported every time. */
static void test_lenient_ignored_words_reported_once(void **state)
{
    (void)state;
    const char *t = "T1 M6 G43 H1\nG1 X1 F60\nT2 M6 G43 H2\nG1 X2\nT3 M6 G43 H3\n"
                    "G85 X5 Y5 Z-1 R1 Q1\nG85 X6 Y5 Z-1 R1 Q1\nG80\nG1 X3\n";
    assert_int_equal(parse_opts(t, true), CS_OK);
    /* T, M6, G43, H once each (4 printed of 12), plus the two skipped G85 blocks. */
    assert_int_equal(nwarn, 6);
    assert_int_equal(S.warnings, 14);
    assert_non_null(strstr(last_warn, "t.nc:7:1: G85 is not supported: its block skipped"));
    expect_pt(P.n - 1, 1, 3, 0, 0, PT_TOL);
}

/* Expected moves of a canned cycle, worked out by hand from LinuxCNC's G81 description: each
 * row one element, its end point and whether it is a rapid; the elements run on from each
 * other (expect_continuous). */
typedef struct {
    double x, y, z;
    bool rapid;
} move_t;

static void expect_moves(size_t first, const move_t *m, size_t n)
{
    assert_int_equal(P.n, first + n);
    for (size_t k = 0; k < n; k++) {
        expect_pt(first + k, 1, m[k].x, m[k].y, m[k].z, PT_TOL);
        assert_int_equal(P.elems[first + k].rapid, m[k].rapid);
    }
    expect_continuous();
}

/* G81 (LinuxCNC "G81 Drilling Cycle"): rapid over the hole, rapid to R, feed to Z, rapid out to
 * the higher of R and the starting Z (G98, the start mode) or to R (G99); R and Z stick on the
 * modal lines that follow (Fusion 360 and FreeCAD write one hole per line). */
static void test_g81_drilling_cycle(void **state)
{
    (void)state;
    assert_int_equal(parse("G0 X0 Y0 Z10\nG98 G81 X5 Y6 Z-2 R3 F100\nX15\nG99 Y20\nG80\n"
                           "G0 Z12\n"),
                     CS_OK);
    const move_t a[] = {
        {5, 6, 10, true},   {5, 6, 3, true},   {5, 6, -2, false},  {5, 6, 10, true},
        {15, 6, 10, true},  {15, 6, 3, true},  {15, 6, -2, false}, {15, 6, 10, true},
        {15, 20, 10, true}, {15, 20, 3, true}, {15, 20, -2, false}, {15, 20, 3, true},
        {15, 20, 12, true},
    };
    expect_moves(1, a, sizeof a / sizeof a[0]);
    assert_int_equal(P.elems[3].loc.line, 2);
    assert_int_equal(P.elems[7].loc.line, 3);
    /* G91 with L3: X Y add up at each repeat, R is from the starting Z (1 + -0.5), Z from R;
     * a move that goes nowhere (R after the first hole, under G99) adds no element. */
    assert_int_equal(parse("G0 X1 Y1 Z1\nG91 G99 G81 X2 Y0 R-0.5 Z-1 L3 F100\n"), CS_OK);
    const move_t b[] = {
        {3, 1, 1, true}, {3, 1, 0.5, true}, {3, 1, -0.5, false}, {3, 1, 0.5, true},
        {5, 1, 0.5, true}, {5, 1, -0.5, false}, {5, 1, 0.5, true},
        {7, 1, 0.5, true}, {7, 1, -0.5, false}, {7, 1, 0.5, true},
    };
    expect_moves(1, b, sizeof b / sizeof b[0]);
    /* Below R at the start: first up to R (once), and G98 then retracts to R, the higher. */
    assert_int_equal(parse("G0 Z-1\nG81 X2 R1 Z-3 F100\n"), CS_OK);
    const move_t c[] = {{0, 0, 1, true}, {2, 0, 1, true}, {2, 0, -3, false}, {2, 0, 1, true}};
    expect_moves(1, c, sizeof c / sizeof c[0]);
    /* Work offsets apply as to any move (G54 X offset 10). */
    assert_int_equal(parse("G10 L2 P1 X10\nG0 X0 Y0 Z5\nG81 X1 R2 Z0 F60\n"), CS_OK);
    const move_t d[] = {{11, 0, 5, true}, {11, 0, 2, true}, {11, 0, 0, false}, {11, 0, 5, true}};
    expect_moves(1, d, sizeof d / sizeof d[0]);
}

/* G83 and G73 (LinuxCNC 2.9 convert_cycle_g83 / g73): pecks of Q from R while above the
 * bottom; G83 rapids out to R after each and back down to 0.254 mm (0.010 in) above the peck,
 * G73 only backs off those 0.254 mm; then a feed to Z and the rapid out. Q sticks like R and Z. */
static void test_g83_g73_pecking(void **state)
{
    (void)state;
    const double u = 0.254;
    assert_int_equal(parse("G0 X0 Y0 Z5\nG99 G83 X1 Y2 Z-3 R1 Q1.5 F100\n"), CS_OK);
    const move_t a[] = {
        {1, 2, 5, true},  {1, 2, 1, true},        {1, 2, -0.5, false}, {1, 2, 1, true},
        {1, 2, -0.5 + u, true}, {1, 2, -2, false}, {1, 2, 1, true},     {1, 2, -2 + u, true},
        {1, 2, -3, false}, {1, 2, 1, true},
    };
    expect_moves(1, a, sizeof a / sizeof a[0]);
    assert_int_equal(parse("G0 X0 Y0 Z5\nG73 X1 Y2 Z-3 R1 Q1.5 F100\n"), CS_OK);
    const move_t b[] = {
        {1, 2, 5, true},         {1, 2, 1, true},   {1, 2, -0.5, false}, {1, 2, -0.5 + u, true},
        {1, 2, -2, false},       {1, 2, -2 + u, true}, {1, 2, -3, false}, {1, 2, 5, true},
    };
    expect_moves(1, b, sizeof b / sizeof b[0]);
    /* A peck that would end on the bottom is the final feed; R, Z and Q stick on "X3". */
    assert_int_equal(parse("G0 X0 Y0 Z5\nG99 G83 X1 Y2 Z-1 R1 Q1 F100\nX3\n"), CS_OK);
    const move_t c[] = {
        {1, 2, 5, true},  {1, 2, 1, true},  {1, 2, 0, false}, {1, 2, 1, true},
        {1, 2, u, true},  {1, 2, -1, false}, {1, 2, 1, true},
        {3, 2, 1, true},  {3, 2, 0, false}, {3, 2, 1, true},  {3, 2, u, true},
        {3, 2, -1, false}, {3, 2, 1, true},
    };
    expect_moves(1, c, sizeof c / sizeof c[0]);
    expect_diag(parse("G83 X1 R1 Z-1 F60\n"), CS_ERR_PARSE, 1, 1);     /* no Q */
    expect_diag(parse("G83 X1 R1 Z-1 Q0 F60\n"), CS_ERR_PARSE, 1, 15); /* Q not positive */
    /* A Q so small that the pecks would never end (d - Q == d in double): refused. */
    expect_diag(parse("G73 X1 R4000 Z-4000 Q0.00000000001 F60\n"), CS_ERR_RANGE, 1, 21);
    expect_diag(parse("G73 X1 R4000 Z-4000 Q0.0799 F60\n"), CS_ERR_RANGE, 1, 21); /* 100 125 */
    /* Another cycle's R, Z do not carry over. */
    expect_diag(parse("G81 X1 R1 Z0 F60\nG83 X2 Q1\n"), CS_ERR_PARSE, 2, 1);
}

static void test_g81_errors(void **state)
{
    (void)state;
    expect_diag(parse("G81 X1 Z-1 F60\n"), CS_ERR_PARSE, 1, 1);            /* no R */
    expect_diag(parse("G81 X1 R1 F60\n"), CS_ERR_PARSE, 1, 1);             /* no Z */
    expect_diag(parse("G0 Z5\nG81 X1 R-2 Z-1 F60\n"), CS_ERR_PARSE, 2, 1); /* R below Z */
    expect_diag(parse("G18\nG81 X1 R1 Z0 F60\n"), CS_ERR_UNSUPPORTED, 2, 1);
    expect_diag(parse("G81 X1 R1 Z0 L0 F60\n"), CS_ERR_PARSE, 1, 14);
    /* R and Z stick only while the same cycle goes on. */
    expect_diag(parse("G81 X1 R1 Z0 F60\nG0 Z5\nG81 X2\n"), CS_ERR_PARSE, 3, 1);
    /* Grbl 1.1 has no canned cycles (error:20). */
    expect_diag(parse_dialect("G81 X1 R1 Z0 F60\n", CS_GCODE_GRBL), CS_ERR_UNSUPPORTED, 1, 1);
    assert_non_null(strstr(D.reason, "Grbl"));
    expect_diag(parse_dialect("G98\n", CS_GCODE_GRBL), CS_ERR_UNSUPPORTED, 1, 1);
}

static void test_arc_errors(void **state)
{
    (void)state;
    expect_diag(parse("G1 X1 F60\nG2 X2 Y0 R0\n"), CS_ERR_DEGENERATE, 2, 10);
    expect_diag(parse("G1 X1 F60\nG2 X1 Y0 R5\n"), CS_ERR_DEGENERATE, 2, 10);
    expect_diag(parse("G1 X1 F60\nG2 X3 Y0 R0.5\n"), CS_ERR_DEGENERATE, 2, 10);
    expect_diag(parse("G1 X1 F60\nG2 X1 Y1\n"), CS_ERR_PARSE, 2, 1);
    expect_diag(parse("G1 X1 F60\nG2 X0 Y1 R1 I-1\n"), CS_ERR_PARSE, 2, 10);
    /* End radius 11 against start radius 10: 1 mm and 10 % apart. */
    expect_diag(parse("G1 X10 F60\nG2 X0 Y11 I-10\n"), CS_ERR_DEGENERATE, 2, 1);
    /* Zero radius: the centre on the start point. */
    expect_diag(parse("G1 X10 F60\nG2 X0 Y10 I0 J0\n"), CS_ERR_DEGENERATE, 2, 1);
    /* LinuxCNC's limits (test_arc_radius_rules has every region): 0.002 mm is under the
     * absolute tolerance 2 * 0.01 * sqrt(2) = 0.0283 mm, so accepted although 0.2 % apart. */
    assert_int_equal(parse("G1 X1 F60\nG3 X0 Y1.002 I-1\n"), CS_OK);
    /* 0.008 mm and 0.08 % apart: accepted, and the arc ends exactly on the programmed point. */
    assert_int_equal(parse("G1 X10 F60\nG3 X0 Y10.008 I-10\n"), CS_OK);
    double e[3];
    end_of(P.n - 1, e);
    assert_true(fabs(e[0]) <= PT_TOL && fabs(e[1] - 10.008) <= PT_TOL);
    for (size_t k = 1; k < P.n; k++)
        for (int s = 0; s <= 32; s++) {
            double q[3];
            cs_path_eval_mm(&P.elems[k].curve, s / 32.0, q);
            double r = hypot(q[0], q[1]);
            assert_true(r >= 10 - ARC_TOL && r <= 10.008 + ARC_TOL);
        }
    /* Inch mode: 2 * 0.001 * sqrt(2) = 0.00283 in; on a 1 in radius 0.0029 in (0.29 %) is
     * refused, 0.0028 in accepted. */
    expect_diag(parse("G20 G1 X1 F1\nG3 X0 Y1.0029 I-1\n"), CS_ERR_DEGENERATE, 2, 1);
    assert_int_equal(parse("G20 G1 X1 F1\nG3 X0 Y1.0028 I-1\n"), CS_OK);
    /* The R form reaches a half chord up to |R| + 0.00005 in = 0.00127 mm (a semicircle). */
    assert_int_equal(parse("G1 X0 F60\nG2 X20.003 Y0 R10\n"), CS_ERR_DEGENERATE);
    assert_int_equal(parse("G1 X0 F60\nG2 X20.002 Y0 R10\n"), CS_OK);
}

/* Arcs whose chord is a few LSB on a huge radius: the end directions are nearly equal, and must
 * never be read as a full turn: every point stays next to the short arc. */
static void test_arc_tiny_pieces(void **state)
{
    (void)state;
    static const char *const t[] = {
        "G1 X4000 Y0 F1\nG3 X3999.99999 Y0.0001 I-4000\n",
        "G1 X4000 Y0 F1\nG2 X4000 Y-0.00002 I-4000\n",
        "G1 X2000 Y0 F1\nG3 X2000 Y0.00003 R2000\n",
        "G1 X2000 Y0 F1\nG3 X2000 Y0.1 Z0.00001 R2000\n",
    };
    for (size_t k = 0; k < sizeof t / sizeof t[0]; k++) {
        assert_int_equal(parse(t[k]), CS_OK);
        expect_continuous();
        double s0[3];
        pt(0, 1, s0);
        for (size_t e = 1; e < P.n; e++)
            for (int i = 0; i <= P.elems[e].curve.degree; i++) {
                double q[3];
                pt(e, (unsigned)i, q);
                assert_true(fabs(q[0] - s0[0]) < 0.2 && fabs(q[1] - s0[1]) < 0.2);
            }
    }
}

/* Radius 0.0015 mm (98 LSB), sweeps just under 90 degrees at 90 start angles: rounding the ends
 * to the LSB may push a piece over 90 degrees; the result must still be the short arc, on the
 * circle (within the 4 LSB of the pieces plus 1 LSB for the rounded ends), ending on its end. */
static void test_arc_small_radius_near_quarter(void **state)
{
    (void)state;
    const double r = 0.0015;
    for (int k = 0; k < 90; k++) {
        double a0 = k * 4 * M_PI / 180, a1 = a0 + 89.95 * M_PI / 180;
        char t[200];
        snprintf(t, sizeof t, "G1 X%.9f Y%.9f F60\nG3 X%.9f Y%.9f I%.9f J%.9f\n", r * cos(a0),
                 r * sin(a0), r * cos(a1), r * sin(a1), -r * cos(a0), -r * sin(a0));
        assert_int_equal(parse(t), CS_OK);
        expect_continuous();
        double turned = check_circle(1, 0, 1, 0, 0, r, 5 * LSB, 0, 0, PT_TOL);
        assert_true(fabs(turned - 89.95 * M_PI / 180) < 0.02);
    }
}

/* Found by a search: small arcs just under 90 degrees whose centre is off the LSB grid, where
 * the rounded ends make the arc builder halve the piece. Still the short arc, on its circle. */
static void test_arc_piece_halved_by_rounding(void **state)
{
    (void)state;
    static const double a[3][6] = {
        {0.300754270, 0.699119086, 0.301910305, 0.701317731, -0.000524680, 0.001679114},
        {0.300463779, 0.699287247, 0.301619155, 0.701124398, -0.000344829, 0.001498743},
        {0.298643171, 0.701349843, 0.299366081, 0.698762904, 0.001657399, -0.000931323},
    };
    for (int k = 0; k < 3; k++) {
        char t[200];
        snprintf(t, sizeof t, "G1 X%.9f Y%.9f F60\nG3 X%.9f Y%.9f I%.9f J%.9f\n", a[k][0], a[k][1],
                 a[k][2], a[k][3], a[k][4], a[k][5]);
        assert_int_equal(parse(t), CS_OK);
        expect_continuous();
        double cx = a[k][0] + a[k][4], cy = a[k][1] + a[k][5];
        double r = hypot(a[k][4], a[k][5]);
        double sweep = atan2(a[k][3] - cy, a[k][2] - cx) - atan2(a[k][1] - cy, a[k][0] - cx);
        while (sweep <= 0)
            sweep += 2 * M_PI;
        double turned = check_circle(1, 0, 1, cx, cy, r, 5 * LSB, 0, 0, PT_TOL);
        assert_true(fabs(turned - sweep) < 0.01);
        double e[3];
        end_of(P.n - 1, e);
        assert_true(fabs(e[0] - a[k][2]) <= PT_TOL && fabs(e[1] - a[k][3]) <= PT_TOL);
    }
}

static void test_helix(void **state)
{
    (void)state;
    /* Two turns of radius 10 climbing 5 mm: pitch 2.5 mm per turn. */
    assert_int_equal(parse("G1 X10 Y0 Z0 F60\nG3 X10 Y0 Z5 I-10 J0 P2\n"), CS_OK);
    assert_int_equal(S.helices, 1);
    double pitch = 2.5 / (2 * M_PI);
    double turned =
        check_circle(1, 0, 1, 0, 0, 10, ARC_TOL, 0, pitch, CS_GCODE_HELIX_TOL_MM + ARC_TOL);
    assert_true(fabs(turned - 4 * M_PI) < 1e-6);
    double e[3];
    end_of(P.n - 1, e);
    assert_true(fabs(e[2] - 5) <= PT_TOL);
    expect_continuous();
    /* A steep helix in G19 (axis X), clockwise, with a coarser tolerance. */
    cs_path_free(&P);
    cs_path_init(&P);
    cs_gcode_opts_t o;
    cs_gcode_opts_init(&o);
    o.helix_tol_mm = 0.01;
    const char *t = "G19 G1 Y3 F60\nG2 Y3 Z0 X-40 J-3 K0\n";
    assert_int_equal(cs_gcode_read("t.nc", t, strlen(t), &o, &P, &D, NULL), CS_OK);
    /* Clockwise: the third axis (X) goes down by 40 over a full turn, in G19's Y-Z plane. */
    for (size_t k = 1; k < P.n; k++)
        for (int s = 0; s <= 64; s++) {
            double q[3];
            cs_path_eval_mm(&P.elems[k].curve, s / 64.0, q);
            assert_true(fabs(hypot(q[1], q[2]) - 3) <= ARC_TOL);
        }
    double turned2 = 0, prev = 0;
    for (size_t k = 1; k < P.n; k++)
        for (int s = 0; s <= 64; s++) {
            double q[3];
            cs_path_eval_mm(&P.elems[k].curve, s / 64.0, q);
            double a = atan2(q[2], q[1]);
            if (k > 1 || s > 0) {
                double d = a - prev;
                while (d > M_PI)
                    d -= 2 * M_PI;
                while (d < -M_PI)
                    d += 2 * M_PI;
                turned2 += d;
            }
            prev = a;
            double xexp = -40 * fabs(turned2) / (2 * M_PI);
            assert_true(fabs(q[0] - xexp) <= 0.01 + ARC_TOL);
        }
    assert_true(fabs(turned2 + 2 * M_PI) < 1e-6);
}

/* ---- splines ----------------------------------------------------------------------------- */

static void test_g5_linuxcnc_facts(void **state)
{
    (void)state;
    /* LinuxCNC's documentation: G5 I0 J3 P0 Q-3 X1 Y1 from (0,0) passes through (0.5, 0.5) at
     * t = 0.5; the continuation G5 P0 Q-3 X2 Y2 passes through (1.5, 1.5). */
    assert_int_equal(parse("G1 X0 Y0 F60\nG5 I0 J3 P0 Q-3 X1 Y1\nG5 P0 Q-3 X2 Y2\n"), CS_OK);
    assert_int_equal(P.n, 2);
    assert_int_equal(P.elems[0].kind, CS_PATH_CUBIC);
    double q[3];
    cs_path_eval_mm(&P.elems[0].curve, 0.5, q);
    assert_true(fabs(q[0] - 0.5) <= PT_TOL && fabs(q[1] - 0.5) <= PT_TOL);
    cs_path_eval_mm(&P.elems[1].curve, 0.5, q);
    assert_true(fabs(q[0] - 1.5) <= PT_TOL && fabs(q[1] - 1.5) <= PT_TOL);
    /* Control points: P1 = P0 + (I,J), P2 = P3 + (P,Q); the continuation's I,J = -(P,Q). */
    expect_pt(0, 1, 0, 3, 0, PT_TOL);
    expect_pt(0, 2, 1, -2, 0, PT_TOL);
    expect_pt(1, 1, 1, 4, 0, PT_TOL);
    expect_pt(1, 2, 2, -1, 0, PT_TOL);
    expect_continuous();
    /* Inches: offsets scale too. */
    assert_int_equal(parse("G20 G5 I0 J3 P0 Q-3 X1 Y1\n"), CS_OK);
    expect_pt(0, 1, 0, 3 * 25.4, 0, PT_TOL);
}

static void test_g5_errors(void **state)
{
    (void)state;
    expect_diag(parse("G5 P0 Q-3 X1 Y1\n"), CS_ERR_PARSE, 1, 1);
    expect_diag(parse("G1 X1 F1\nG5 P0 Q-3 X1 Y1\n"), CS_ERR_PARSE, 2, 1);
    expect_diag(parse("G5 I1 P0 Q-3 X1 Y1\n"), CS_ERR_PARSE, 1, 4);
    expect_diag(parse("G5 I1 J1 X1 Y1\n"), CS_ERR_PARSE, 1, 1);
    expect_diag(parse("G18 G5 I1 J1 P1 Q1 X1 Y1\n"), CS_ERR_UNSUPPORTED, 1, 5);
    expect_diag(parse("G5 I1 J1 P1 Q1 X1 Y1 Z1\n"), CS_ERR_PARSE, 1, 22);
    expect_diag(parse("G5.1 X1 Y1\n"), CS_ERR_PARSE, 1, 1);
}

static void test_g51_parabola(void **state)
{
    (void)state;
    /* LinuxCNC: G5.1 X2 I2 J-8 from (-2, 4) traces y = x^2 exactly. */
    assert_int_equal(parse("G0 X-2 Y4\nG5.1 X2 I2 J-8\n"), CS_OK);
    assert_int_equal(P.n, 2);
    assert_int_equal(P.elems[1].kind, CS_PATH_QUAD);
    for (int s = 0; s <= 100; s++) {
        double q[3];
        cs_path_eval_mm(&P.elems[1].curve, s / 100.0, q);
        assert_true(fabs(q[1] - q[0] * q[0]) <= 1e-9);
    }
    double e[3];
    end_of(1, e);
    assert_true(e[0] == 2 && e[1] == 4);
}

/* Cox-de Boor basis N_{i,p}(u) over knots kn (u in the last span counts as inside). */
static double basis(int i, int p, double u, const double *kn, int nk)
{
    if (p == 0) {
        if (u >= kn[i] && u < kn[i + 1])
            return 1;
        if (u == kn[nk - 1] && kn[i] < kn[i + 1] && kn[i + 1] == kn[nk - 1])
            return 1;
        return 0;
    }
    double a = 0, b = 0;
    if (kn[i + p] > kn[i])
        a = (u - kn[i]) / (kn[i + p] - kn[i]) * basis(i, p - 1, u, kn, nk);
    if (kn[i + p + 1] > kn[i + 1])
        b = (kn[i + p + 1] - u) / (kn[i + p + 1] - kn[i + 1]) * basis(i + 1, p - 1, u, kn, nk);
    return a + b;
}

/* The curve at u; knots NULL: LinuxCNC's G5.2 knot vector (0 x order, 1, 2, ..., clamped). */
static void nurbs_eval_k(const double (*cp)[3], int n, int order, const double *knots, double u,
                         double out[2])
{
    double kn[32];
    int nk = n + order;
    for (int i = 0; i < nk; i++)
        kn[i] = knots ? knots[i] : i < order ? 0 : i <= n - 1 ? i - order + 1 : n - order + 1;
    double x = 0, y = 0, w = 0;
    for (int i = 0; i < n; i++) {
        double b = basis(i, order - 1, u, kn, nk) * cp[i][2];
        x += b * cp[i][0];
        y += b * cp[i][1];
        w += b;
    }
    out[0] = x / w;
    out[1] = y / w;
}

static void nurbs_eval(const double (*cp)[3], int n, int order, double u, double out[2])
{
    nurbs_eval_k(cp, n, order, NULL, u, out);
}

static void check_nurbs(const char *text, const double (*cp)[3], int n, int order, double tol)
{
    assert_int_equal(parse(text), CS_OK);
    int spans = n - order + 1;
    /* Two elements before the block (the G0 and the G1), then one per knot span. */
    assert_int_equal((int)P.n, 2 + spans);
    for (int s = 0; s < spans; s++) {
        assert_int_equal(P.elems[2 + s].curve.degree, order - 1);
        for (int k = 0; k <= 50; k++) {
            double t = k / 50.0, q[3], r[2];
            cs_path_eval_mm(&P.elems[2 + s].curve, t, q);
            nurbs_eval(cp, n, order, s + t, r);
            if (fabs(q[0] - r[0]) > tol || fabs(q[1] - r[1]) > tol)
                print_error("span %d t %g: (%.9f, %.9f) vs (%.9f, %.9f)\n", s, t, q[0], q[1], r[0],
                            r[1]);
            assert_true(fabs(q[0] - r[0]) <= tol && fabs(q[1] - r[1]) <= tol);
        }
    }
    expect_continuous();
}

static void test_g52_nurbs(void **state)
{
    (void)state;
    /* LinuxCNC's example block: the current point is the first control point (weight 1). */
    static const double cp[5][3] = {{0, 0, 1}, {0, 1, 1}, {2, 2, 1}, {2, 0, 1}, {0, 0, 2}};
    check_nurbs("G0 X0 Y0.0001\nG1 X0 Y0 F10\nG5.2 X0 Y1 P1 L3\nX2 Y2 P1\nX2 Y0 P1\nX0 Y0 P2\n"
                "G5.3\n",
                cp, 5, 3, 2 * LSB);
    /* Order 4 (cubic), weights of several sizes. */
    static const double cq[6][3] = {{1, 1, 1},   {2, 5, 0.5}, {6, 6, 3},
                                    {9, 2, 1.5}, {12, 4, 1},  {14, 0, 2}};
    check_nurbs("G0 X1 Y1.5\nG1 Y1 F10\nG5.2 X2 Y5 P0.5 L4\nX6 Y6 P3\nX9 Y2 P1.5\nX12 Y4 P1\n"
                "X14 Y0 P2\nG5.3\n",
                cq, 6, 4, 2 * LSB);
}

static void test_g52_errors(void **state)
{
    (void)state;
    expect_diag(parse("G5.2 X1 Y1 P1\nX2 Y2\nG5.3\n"), CS_ERR_WEIGHT, 2, 1);
    expect_diag(parse("G5.2 X1 Y1 P1\nX2 Y2 P1\n"), CS_ERR_PARSE, 1, 1);
    expect_diag(parse("G5.2 X1 Y1 P1\nG5.3\n"), CS_ERR_PARSE, 1, 1);
    expect_diag(parse("G5.2 X1 Y1 P1 L5\nX2 Y2 P1\nX3 Y3 P1\nG5.3\n"), CS_ERR_UNSUPPORTED, 1, 15);
    expect_diag(parse("G5.3\n"), CS_ERR_PARSE, 1, 1);
    expect_diag(parse("G5.2 X1 Y1 P1\nG1 X2\n"), CS_ERR_PARSE, 2, 1);
    expect_diag(parse("G5.2 X1 P1\n"), CS_ERR_PARSE, 1, 6);
    /* Found by fuzz_gcode: with the pen heights on, M4 between the control points moved Z away
     * from the block's first point, so the curve did not start where the path was. A pen or
     * spindle change inside a block is refused, at the M word. */
    cs_gcode_opts_t o;
    cs_gcode_opts_init(&o);
    o.pen_z = true;
    o.pen_down_z_mm = -1;
    o.pen_up_z_mm = 2;
    expect_diag(parse_with("G5.2 X0 Y10 P1 L3\nX20 Y20 P1\nM4 X20 Y0 P1\nX0 Y0 P2\nG5.3\n", &o),
                CS_ERR_PARSE, 3, 1);
    assert_int_equal(parse_with("M3\nG5.2 X0 Y10 P1 L3\nX20 Y20 P1\nX0 Y0 P2\nG5.3\nM5\n", &o),
                     CS_OK);
    expect_continuous();
}

/* ---- the cncjs fixtures ------------------------------------------------------------------ */

static void test_cncjs_plane_arcs(void **state)
{
    (void)state;
    static const struct {
        const char *file;
        int i0, i1;
    } f[] = {{DATA "arc-xy-plane.nc", 0, 1},
             {DATA "arc-zx-plane.nc", 2, 0},
             {DATA "arc-yz-plane.nc", 1, 2}};
    for (size_t k = 0; k < 3; k++) {
        assert_int_equal(parse_file(f[k].file, false), CS_OK);
        expect_continuous();
        /* Every arc piece lies on the radius-20 circle around the origin of its plane. */
        for (size_t e = 0; e < P.n; e++) {
            if (P.elems[e].kind != CS_PATH_ARC)
                continue;
            for (int s = 0; s <= 32; s++) {
                double q[3];
                cs_path_eval_mm(&P.elems[e].curve, s / 32.0, q);
                assert_true(fabs(hypot(q[f[k].i0], q[f[k].i1]) - 20) <= ARC_TOL);
                assert_true(fabs(q[3 - f[k].i0 - f[k].i1]) <= PT_TOL);
            }
        }
        assert_true(fabs(P.elems[1].feed_mm_s - 200.0 / 60.0) < 1e-12);
    }
}

static void test_cncjs_one_inch_circle(void **state)
{
    (void)state;
    assert_int_equal(parse_file(DATA "one-inch-circle.nc", false), CS_OK);
    expect_continuous();
    /* G20: the circle of diameter 1 in around the origin, at Z0, four G2 quarters. */
    double turned = 0;
    size_t first = 0;
    while (P.elems[first].kind != CS_PATH_ARC)
        first++;
    size_t last = first;
    while (last < P.n && P.elems[last].kind == CS_PATH_ARC)
        last++;
    for (size_t e = first; e < last; e++)
        for (int s = 0; s <= 32; s++) {
            double q[3];
            cs_path_eval_mm(&P.elems[e].curve, s / 32.0, q);
            assert_true(fabs(hypot(q[0], q[1]) - 12.7) <= ARC_TOL);
            assert_true(fabs(q[2]) <= PT_TOL);
        }
    double a0[3], a1[3];
    pt(first, 0, a0);
    end_of(last - 1, a1);
    assert_true(fabs(a0[0] + 12.7) <= PT_TOL && fabs(a1[0] + 12.7) <= PT_TOL);
    (void)turned;
    /* F2.5 in/min on the arcs. */
    assert_true(fabs(P.elems[first].feed_mm_s - 2.5 * 25.4 / 60) < 1e-12);
}

static void test_cncjs_helical_thread(void **state)
{
    (void)state;
    /* G42 D08 (cutter compensation) is not carried out: an error, a warning when lenient. */
    expect_diag(parse_file(DATA "helical-thread-milling.nc", false), CS_ERR_UNSUPPORTED, 2, 9);
    assert_int_equal(parse_file(DATA "helical-thread-milling.nc", true), CS_OK);
    assert_int_equal(nwarn, 2);
    expect_continuous();
    assert_int_equal(S.helices, 10);
    /* G91: ten arcs each climbing 0.0179 from -0.6533: the end is at 10 * 0.0179 - 0.6533. */
    double e[3];
    end_of(P.n - 1, e);
    assert_true(fabs(e[2] - (10 * 0.0179 - 0.6533)) <= 10 * PT_TOL);
}

static void test_cncjs_bad_files(void **state)
{
    (void)state;
    /* By default each is refused where LinuxCNC refuses it. "X0Y20" in G2 mode without R or
     * I/J. */
    expect_diag(parse_file(DATA "arc-r.nc", false), CS_ERR_PARSE, 3, 1);
    /* A bare G92; lenient: G2 X0Y0 R0 from (0,0) has no centre. */
    expect_diag(parse_file(DATA "motion.nc", false), CS_ERR_PARSE, 1, 1);
    /* T0 is refused; lenient reads on to the bad checksum of line 8 (column of the '*'): a
     * corrupted line stays an error. */
    expect_diag(parse_file(DATA "special-fields.gcode", false), CS_ERR_UNSUPPORTED, 3, 4);
    expect_diag(parse_file(DATA "special-fields.gcode", true), CS_ERR_PARSE, 8, 16);
    assert_non_null(strstr(D.reason, "checksum"));
    assert_int_equal(P.n, 1); /* N7 G1 X2.0 Y2.0 (inches) was read before */
    expect_pt(0, 1, 50.8, 50.8, 0, PT_TOL);
}

/* Centre (double reference) of the short arc of radius r from a to b: right of the chord for a
 * clockwise arc, left for a counter-clockwise one. */
static void short_arc_centre(const double a[2], const double b[2], double r, bool ccw, double c[2])
{
    double dx = b[0] - a[0], dy = b[1] - a[1], len = hypot(dx, dy);
    double d = sqrt(r * r - len * len / 4), nx = -dy / len, ny = dx / len; /* left normal */
    double sgn = ccw ? 1.0 : -1.0;
    c[0] = (a[0] + b[0]) / 2 + sgn * d * nx;
    c[1] = (a[1] + b[1]) / 2 + sgn * d * ny;
}

/* --lenient reads arc-r.nc: each arc without R or I/J becomes a straight feed move to its end,
 * so the R20 arcs after them start where the program says and keep their true centres. */
static void test_cncjs_arc_r_lenient(void **state)
{
    (void)state;
    assert_int_equal(parse_file(DATA "arc-r.nc", true), CS_OK);
    assert_int_equal(nwarn, 2); /* one per arc without R or I/J (lines 3 and 7) */
    assert_non_null(strstr(last_warn, "arc-r.nc:7:1: G3 without R or I/J"));
    assert_non_null(strstr(last_warn, "straight line"));
    /* Line 3: (0,0) -> (0,20), a feed move. */
    assert_int_equal(P.elems[0].kind, CS_PATH_LINE);
    assert_false(P.elems[0].rapid);
    expect_pt(0, 0, 0, 0, 0, PT_TOL);
    expect_pt(0, 1, 0, 20, 0, PT_TOL);
    const double a[2] = {0, 20}, b[2] = {10, 0};
    double cw[2], ccw[2];
    short_arc_centre(a, b, 20, false, cw);
    short_arc_centre(a, b, 20, true, ccw);
    unsigned arcs[2] = {0, 0}, lines = 0, rapids = 0;
    for (size_t i = 1; i < P.n; i++) {
        const cs_path_elem_t *el = &P.elems[i];
        if (el->rapid) {
            rapids++; /* line 5: G0 X0Y0 from (10,0) */
            expect_pt(i, 0, 10, 0, 0, PT_TOL);
            expect_pt(i, 1, 0, 0, 0, PT_TOL);
            continue;
        }
        if (el->loc.line == 7) {
            lines++;
            expect_pt(i, 0, 0, 0, 0, PT_TOL);
            expect_pt(i, 1, 0, 20, 0, PT_TOL);
            continue;
        }
        assert_int_equal(el->kind, CS_PATH_ARC);
        bool is_ccw = el->loc.line == 8;
        assert_true(is_ccw || el->loc.line == 4);
        arcs[is_ccw]++;
        const double *c = is_ccw ? ccw : cw;
        for (int k = 0; k <= 32; k++) {
            double q[3];
            cs_path_eval_mm(&el->curve, k / 32.0, q);
            assert_true(fabs(hypot(q[0] - c[0], q[1] - c[1]) - 20) <= ARC_TOL);
        }
    }
    assert_int_equal(rapids, 1);
    assert_int_equal(lines, 1);
    assert_true(arcs[0] >= 1 && arcs[1] >= 1);
    expect_pt(P.n - 1, P.elems[P.n - 1].curve.degree, 10, 0, 0, PT_TOL);
}

/* --lenient reads motion.nc: bare G92 ignored, the R0 arcs that end where they start draw
 * nothing, the probing moves are dropped; nothing moves at all. */
static void test_cncjs_motion_lenient(void **state)
{
    (void)state;
    assert_int_equal(parse_file(DATA "motion.nc", true), CS_OK);
    /* G92, two R0 arcs, G38.2 .. G38.5: one warning each. */
    assert_int_equal(nwarn, 7);
    assert_int_equal(P.n, 0);
    /* An R arc that ends on its start but moves along the plane's normal: the straight move. */
    assert_int_equal(parse_opts("G1 X5 F60\nG2 X5 Y0 Z-2 R3\nG1 X6\n", true), CS_OK);
    assert_int_equal(nwarn, 1);
    assert_non_null(strstr(last_warn, "t.nc:2:14: R-form arc ends where it starts"));
    assert_int_equal(P.n, 3);
    expect_pt(1, 0, 5, 0, 0, PT_TOL);
    expect_pt(1, 1, 5, 0, -2, PT_TOL);
    expect_pt(2, 1, 6, 0, -2, PT_TOL);
    /* Strict: the same is an error at the R word. */
    expect_diag(parse("G1 X5 F60\nG2 X5 Y0 Z-2 R3\n"), CS_ERR_DEGENERATE, 2, 14);
    /* An R0 arc that does go somewhere is still refused, lenient or not. */
    expect_diag(parse_opts("G2 X1 Y0 R0\n", true), CS_ERR_DEGENERATE, 1, 10);
}

/* --lenient reads special-fields.gcode up to its corrupted line 8: T0 ignored (no tool changer),
 * "G92 E0" ignored (E dropped, then a bare G92); G28 is carried out (to the G28 home, 0 0 0). */
static void test_cncjs_special_fields_lenient(void **state)
{
    (void)state;
    const char *txt = "N3 T0*57\n";
    assert_int_equal(parse_opts(txt, true), CS_OK);
    assert_int_equal(nwarn, 1);
    assert_non_null(strstr(last_warn, "t.nc:1:4: T (tool select): ignored"));
    assert_int_equal(P.n, 0);
    expect_diag(parse(txt), CS_ERR_UNSUPPORTED, 1, 4);
    /* The file itself, lenient: T0, E, bare G92 warned once each before the line-8 error. */
    expect_diag(parse_file(DATA "special-fields.gcode", true), CS_ERR_PARSE, 8, 16);
    assert_int_equal(nwarn, 3);
}

/* ---- LinuxCNC parameters, expressions and O-words (cs_gexpr, cs_gflow) ----------------------- */

/* LinuxCNC G-code reference, "Parameter Setting": "A parameter setting does not take effect
 * until after all parameter values on the same line have been found. For example, if parameter 3
 * has been previously set to 15 and the line #3=6 G1 x#3 is interpreted, a straight move to a
 * point where x equals 15 will occur and the value of parameter 3 will be 6." */
static void test_params_take_effect_at_end_of_line(void **state)
{
    (void)state;
    assert_int_equal(parse("#3=15\n#3=6 G1 x#3 F60\nG1 Y#3\n"), CS_OK);
    assert_int_equal(P.n, 2);
    expect_pt(0, 1, 15, 0, 0, PT_TOL);
    expect_pt(1, 1, 15, 6, 0, PT_TOL);
    /* "If a parameter setting of the same parameter is repeated on a line, #3=15 #3=6, ...
     * only the last setting will take effect." */
    assert_int_equal(parse("#3=15 #3=6\nG1 X#3 F60\n"), CS_OK);
    expect_pt(0, 1, 6, 0, 0, PT_TOL);
    /* "#1+2 means the number found by adding 2 to the value of parameter 1"; "##2 means the value
     * of the parameter whose index is the (integer) value of parameter 2". */
    assert_int_equal(parse("#1=4\n#2=1\n#3=9\nG1 X[#1+2] Y##2 Z#[1+2] F60\n"), CS_OK);
    expect_pt(0, 1, 6, 4, 9, PT_TOL);
}

/* Named parameters ("Named Parameters Reference"): #<name> is local to the subroutine that sets
 * it, #<_name> is global; names are lower-cased with blanks removed. */
static void test_params_named_scope(void **state)
{
    (void)state;
    assert_int_equal(parse("#<_Global Off>=2\n#<loc>=3\no1 sub\n#<loc>=7\n"
                           "G1 X[#<_globaloff>+#<loc>] F60\n#<_globaloff>=5\no1 endsub\n"
                           "o1 call\nG1 Y[#<_globaloff>+#<LOC>]\n"),
                     CS_OK);
    expect_pt(0, 1, 9, 0, 0, PT_TOL); /* 2 + the sub's own 7 */
    expect_pt(1, 1, 9, 8, 0, PT_TOL); /* 5 + the main program's 3 */
    /* The caller's local is not visible inside the sub: an error there, located. */
    expect_diag(parse("#<loc>=3\no1 sub\nG1 X#<loc> F60\no1 endsub\no1 call\n"), CS_ERR_PARSE, 3,
                5);
    assert_non_null(strstr(D.reason, "#<loc> is not defined"));
    /* EXISTS[#<name>] */
    assert_int_equal(parse("#<a>=1\nG1 X[EXISTS[#<a>]*10+EXISTS[#<b>]] F60\n"), CS_OK);
    expect_pt(0, 1, 10, 0, 0, PT_TOL);
}

static void test_params_errors(void **state)
{
    (void)state;
    /* "a real value which evaluates to an integer between 1 and 5399" */
    expect_diag(parse("G1 X#5400 F1\n"), CS_ERR_PARSE, 1, 6);
    expect_diag(parse("#0=1\n"), CS_ERR_PARSE, 1, 2);
    expect_diag(parse("G1 X#<nope> F1\n"), CS_ERR_PARSE, 1, 5);
    expect_diag(parse("G1 X[1/0] F1\n"), CS_ERR_RANGE, 1, 7);
    expect_diag(parse("G1 X[SQRT[-1]] F1\n"), CS_ERR_RANGE, 1, 6);
    expect_diag(parse("G1 X[1+2 F1\n"), CS_ERR_PARSE, 1, 10);
    expect_diag(parse("#1\n"), CS_ERR_PARSE, 1, 1);
    expect_diag(parse("G1 [1] F1\n"), CS_ERR_PARSE, 1, 4);
}

/* Inside [...] a '*' multiplies; the RepRap checksum '*' is only outside brackets. */
static void test_expression_star_is_not_a_checksum(void **state)
{
    (void)state;
    assert_int_equal(parse("G1 X[2*3] Y[2**3] F60\n"), CS_OK);
    expect_pt(0, 1, 6, 8, 0, PT_TOL);
}

/* "1e3" is not G-code: an error in every mode, saying so (never X1 and an E word). */
static void test_exponent_is_an_error(void **state)
{
    (void)state;
    expect_diag(parse("G1 X1e3 F60\n"), CS_ERR_PARSE, 1, 6);
    assert_non_null(strstr(D.reason, "exponent"));
    expect_diag(parse_opts("G1 X2.5E-2 F60\n", true), CS_ERR_PARSE, 1, 8);
    expect_diag(parse_dialect("G1 X1E3 F60\n", CS_GCODE_GRBL), CS_ERR_PARSE, 1, 6);
    /* A letter after a number with a blank is a word: X1 E3 stays an (unsupported) E word. */
    expect_diag(parse("G1 X1 E3 F60\n"), CS_ERR_UNSUPPORTED, 1, 7);
}

/* "O Codes": sub/endsub/call with arguments. "o~ call takes up to 30 optional arguments, which
 * are passed to the subroutine as #1, #2, ..., #N. Unused parameters from #N+1 to #30 have the
 * same value as in the calling context." "On return from the subroutine, the values of
 * parameters #1 through #30 (regardless of the number of arguments) are restored". */
static void test_oword_sub_call(void **state)
{
    (void)state;
    const char *sq = "o<square> sub\nG1 X#1 Y0\nG1 X#1 Y#1\nG1 X0 Y#1\nG1 X0 Y0\no<square> endsub\n"
                     "F60\no<square> call [10]\no<SQUARE> call [5]\n";
    assert_int_equal(parse(sq), CS_OK);
    static const double want[8][2] = {{10, 0}, {10, 10}, {0, 10}, {0, 0},
                                      {5, 0},  {5, 5},   {0, 5},  {0, 0}};
    assert_int_equal(P.n, 8);
    for (size_t k = 0; k < 8; k++)
        expect_pt(k, 1, want[k][0], want[k][1], 0, PT_TOL);
    assert_int_equal(parse("#1=7\n#2=4\no1 sub\nG1 X#2 F60\n#1=9\no1 endsub\no1 call [3]\n"
                           "G1 Y#1\n"),
                     CS_OK);
    expect_pt(0, 1, 4, 0, 0, PT_TOL); /* #2 not passed: the caller's 4 */
    expect_pt(1, 1, 4, 7, 0, PT_TOL); /* #1 restored to 7 */
    /* Nested and recursive calls; return with a value in #<_value>. */
    assert_int_equal(parse("o2 sub\no3 if [#1 GT 0]\nG91 G1 X1 F60\no2 call [#1-1]\no3 endif\n"
                           "o2 return [#1*2]\no2 endsub\no2 call [4]\nG90 G1 Y#<_value>\n"),
                     CS_OK);
    assert_int_equal(P.n, 5);
    expect_pt(3, 1, 4, 0, 0, PT_TOL);
    expect_pt(4, 1, 4, 8, 0, PT_TOL); /* the outermost call returned 4*2 */
}

/* while/endwhile, do/while, repeat/endrepeat, break/continue, if/elseif/else/endif: the O Codes
 * examples' patterns, the resulting X positions listed by hand. */
static void test_oword_loops_and_ifs(void **state)
{
    (void)state;
    assert_int_equal(
        parse("F60\n#1=1\no101 while [#1 LT 4]\nG1 X#1\n#1=[#1+1]\no101 endwhile\n"
              "o102 repeat [2]\nG91 G1 X10\no102 endrepeat\nG90\n"
              "#2=0\no103 do\n#2=[#2+1]\no104 if [#2 EQ 2]\no103 continue\no104 endif\n"
              "G1 X[100+#2]\no105 if [#2 GE 4]\no103 break\no105 endif\n"
              "o103 while [#2 LT 10]\n"
              "o106 repeat [0]\nG1 X999\no106 endrepeat\n"
              "o107 while [0]\nG1 X999\no107 endwhile\n"),
        CS_OK);
    static const double xs[] = {1, 2, 3, 13, 23, 101, 103, 104};
    assert_int_equal(P.n, 8);
    for (size_t k = 0; k < 8; k++)
        expect_pt(k, 1, xs[k], 0, 0, PT_TOL);
    /* "If no elseif keywords are present, or if all elseif arguments evaluate to false, than the
     * code following the else keyword is executed." */
    for (int v = 0; v < 4; v++) {
        char t[256];
        snprintf(t, sizeof t,
                 "#2=%d\no102 if [#2 GT 2]\nG1 X1 F1\no102 elseif [#2 LT 1]\nG1 X2 F1\n"
                 "o102 elseif [#2 EQ 1]\nG1 X3 F1\no102 else\nG1 X4 F1\no102 endif\n",
                 v);
        assert_int_equal(parse(t), CS_OK);
        assert_int_equal(P.n, 1);
        expect_pt(0, 1, v == 3 ? 1 : v == 0 ? 2 : v == 1 ? 3 : 4, 0, 0, PT_TOL);
    }
}

static void test_oword_errors(void **state)
{
    (void)state;
    expect_diag(parse("G1 X1 F1\no1 endif\n"), CS_ERR_PARSE, 2, 1);
    expect_diag(parse("o1 if [1]\no2 endif\n"), CS_ERR_PARSE, 2, 1);
    expect_diag(parse("o1 sub\nG1 X1 F1\n"), CS_ERR_PARSE, 1, 1);
    expect_diag(parse("N10 o5 while [1]\n"), CS_ERR_PARSE, 1, 5);
    expect_diag(parse("o1 break\n"), CS_ERR_PARSE, 1, 1);
    expect_diag(parse("o1 frobnicate\n"), CS_ERR_PARSE, 1, 4);
    expect_diag(parse("G1 X1 F1 o1 call\n"), CS_ERR_PARSE, 1, 10);
    /* "If the subroutine is defined in the same file as the main program that calls the
     * subroutine, it must be defined before the call statement." */
    expect_diag(parse("o1 call\no1 sub\no1 endsub\n"), CS_ERR_PARSE, 1, 1);
    expect_diag(parse("o9 call\n"), CS_ERR_PARSE, 1, 1);
    expect_diag(parse("o1 if\no1 endif\n"), CS_ERR_PARSE, 1, 1);
    /* "The maximum subroutine nesting level is 10." */
    expect_diag(parse("o1 sub\no1 call\no1 endsub\no1 call\n"), CS_ERR_RANGE, 2, 1);
    /* A runaway loop: bounded, located at the line that loops back. */
    cs_gcode_opts_t o;
    cs_gcode_opts_init(&o);
    o.max_loops = 100;
    expect_diag(parse_with("o1 while [1]\nG91 G1 X0.001 F1\no1 endwhile\n", &o), CS_ERR_RANGE, 3,
                1);
    assert_non_null(strstr(D.reason, "more than 100 loop passes"));
    o.max_loops = 0; /* the default bound ends an endless do loop too */
    expect_diag(parse_with("o1 do\no1 while [1]\n", &o), CS_ERR_RANGE, 2, 1);
}

/* ---- dialects, units, G64 ------------------------------------------------------------------ */

/* Grbl 1.1 starts in G0 (its $G report after reset: "G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0");
 * LinuxCNC starts with no motion mode. */
static void test_grbl_dialect(void **state)
{
    (void)state;
    expect_diag(parse("X10 Y5\n"), CS_ERR_PARSE, 1, 1);
    assert_int_equal(parse_dialect("X10 Y5\nG1 X0 F100\nT1\nM8\nM9\n", CS_GCODE_GRBL), CS_OK);
    assert_int_equal(P.n, 2);
    assert_true(P.elems[0].rapid && !P.elems[1].rapid);
    expect_pt(0, 1, 10, 5, 0, PT_TOL);
    /* What Grbl 1.1 does not have is refused in its dialect, located. */
    expect_diag(parse_dialect("G1 X#1 F1\n", CS_GCODE_GRBL), CS_ERR_UNSUPPORTED, 1, 5);
    expect_diag(parse_dialect("o1 sub\n", CS_GCODE_GRBL), CS_ERR_UNSUPPORTED, 1, 1);
    expect_diag(parse_dialect("G5.2 X1 Y1 P1\n", CS_GCODE_GRBL), CS_ERR_UNSUPPORTED, 1, 1);
    assert_non_null(strstr(D.reason, "not in Grbl 1.1"));
    expect_diag(parse_dialect("G64 P0.1\n", CS_GCODE_GRBL), CS_ERR_UNSUPPORTED, 1, 1);
}

/* The arc radius rules, each region from both sides. LinuxCNC (interp_arc.cc, whose error reads
 * "Radius to end of arc differs from radius to start"; abs = CENTER_ARC_RADIUS_TOLERANCE_MM =
 * 2 * 0.01 * sqrt 2 = 0.028284 mm, relative = SPIRAL_RELATIVE_TOLERANCE = 0.1 %): refused if
 * |r1 - r0| > 100 abs = 2.8284 mm, or > abs while > 0.1 % of the larger radius. Grbl 1.1: refused if > 0.005 mm and (> 0.5 mm or > 0.1 % of the start radius). */
static void test_arc_radius_rules(void **state)
{
    (void)state;
    static const struct {
        double r0, r1;
        bool linuxcnc_ok, grbl_ok;
    } c[] = {
        {10, 10.028, true, false},    /* 0.028 mm <= abs; 0.28 %: Grbl refuses */
        {10, 10.029, false, false},   /* 0.029 mm > abs and 0.29 % */
        {10, 10.004, true, true},     /* under both absolute tolerances */
        {10, 10.006, true, true},     /* 0.06 %: within Grbl's 0.1 % */
        {100, 100.09, true, true},    /* 0.0899 % */
        {100, 100.11, false, false},  /* 0.1099 % */
        {1000, 1000.6, true, false},  /* 0.06 %; over Grbl's 0.5 mm */
        {1000, 1000.4, true, true},   /* 0.04 %, under 0.5 mm */
        {4000, 4002.8, true, false},  /* 2.8 mm < 100 abs, 0.07 % */
        {4000, 4002.9, false, false}, /* 2.9 mm > 100 abs although only 0.0725 % */
    };
    for (size_t k = 0; k < sizeof c / sizeof c[0]; k++) {
        char t[128];
        snprintf(t, sizeof t, "G0 X%g\nG3 X0 Y%g I-%g F100\n", c[k].r0, c[k].r1, c[k].r0);
        for (int d = 0; d < 2; d++) {
            bool ok = d ? c[k].grbl_ok : c[k].linuxcnc_ok;
            cs_err_t e = parse_dialect(t, d ? CS_GCODE_GRBL : CS_GCODE_LINUXCNC);
            if (ok != (e == CS_OK))
                print_error("r0 %g r1 %g %s: %s\n", c[k].r0, c[k].r1, d ? "grbl" : "linuxcnc",
                            D.reason);
            if (ok) {
                assert_int_equal(e, CS_OK);
                double q[3];
                end_of(P.n - 1, q);
                assert_true(fabs(q[0]) <= PT_TOL && fabs(q[1] - c[k].r1) <= PT_TOL);
                /* The spiral: every point within the two radii (plus the helix tolerance the
                 * pieces keep to, and rounding). */
                for (size_t e2 = 1; e2 < P.n; e2++)
                    for (int s = 0; s <= 8; s++) {
                        cs_path_eval_mm(&P.elems[e2].curve, s / 8.0, q);
                        double r = hypot(q[0], q[1]);
                        assert_true(r >= c[k].r0 - 0.001 - ARC_TOL &&
                                    r <= c[k].r1 + 0.001 + ARC_TOL);
                    }
            } else {
                expect_diag(e, CS_ERR_DEGENERATE, 2, 1);
            }
        }
    }
}

static void test_units_start_and_g64(void **state)
{
    (void)state;
    cs_gcode_opts_t o;
    cs_gcode_opts_init(&o);
    o.start_inch = true;
    assert_int_equal(parse_with("G1 X1.25 F1\nG21 X2\n", &o), CS_OK);
    expect_pt(0, 1, 31.75, 0, 0, PT_TOL);
    expect_pt(1, 1, 2, 0, 0, PT_TOL);
    /* G64 P: the smallest path tolerance the program gives, in mm; Q accepted. */
    assert_int_equal(parse("G64 P0.01 Q0.005\nG1 X1 F60\nG64 P0.002\nG64\nG61\nG61.1\n"), CS_OK);
    assert_true(fabs(P.blend_tol_mm - 0.002) < 1e-12);
    assert_int_equal(parse("G20 G64 P0.001\n"), CS_OK);
    assert_true(fabs(P.blend_tol_mm - 0.0254) < 1e-12);
    assert_int_equal(parse("G64 P0\n"), CS_OK);
    assert_true(P.blend_tol_mm == 0);
    expect_diag(parse("G64 P-1\n"), CS_ERR_PARSE, 1, 5);
}

/* --lenient skips an unsupported motion word's whole block, axis words included, and says so. */
static void test_lenient_skips_motion_block(void **state)
{
    (void)state;
    const char *t = "G1 X1 F60\nG38.2 Z-5 F10\nG1 X2\n";
    expect_diag(parse(t), CS_ERR_UNSUPPORTED, 2, 1);
    assert_int_equal(parse_opts(t, true), CS_OK);
    assert_int_equal(P.n, 2);
    expect_pt(1, 1, 2, 0, 0, PT_TOL); /* Z never moved */
    assert_int_equal(nwarn, 1);
    assert_non_null(strstr(last_warn, "t.nc:2:1: G38.2 is not supported: its block skipped, with "
                                      "its words Z-5"));
}

/* ---- NURBS in every plane; G6.2 ------------------------------------------------------------ */

/* G5.2 in G18 (Z, X) and G19 (Y, Z): the G17 block's curve with its axes renamed. */
static void test_g52_planes(void **state)
{
    (void)state;
    static const double cp[5][3] = {{0, 0, 1}, {0, 1, 1}, {2, 2, 1}, {2, 0, 1}, {0, 0, 2}};
    static const struct {
        const char *text;
        int a0, a1; /* the coordinates of q that carry the plane's first and second axis */
    } pl[] = {{"G18 G0 Z0 X0\nF10\nG5.2 Z0 X1 P1 L3\nZ2 X2 P1\nZ2 X0 P1\nZ0 X0 P2\nG5.3\n", 2, 0},
              {"G19 G0 Y0 Z0\nF10\nG5.2 Y0 Z1 P1 L3\nY2 Z2 P1\nY2 Z0 P1\nY0 Z0 P2\nG5.3\n", 1, 2}};
    for (size_t k = 0; k < 2; k++) {
        assert_int_equal(parse(pl[k].text), CS_OK);
        assert_int_equal((int)P.n, 3);
        for (int s = 0; s < 3; s++)
            for (int j = 0; j <= 20; j++) {
                double t = j / 20.0, q[3], r[2];
                cs_path_eval_mm(&P.elems[s].curve, t, q);
                nurbs_eval(cp, 5, 3, s + t, r);
                assert_true(fabs(q[pl[k].a0] - r[0]) <= 2 * LSB &&
                            fabs(q[pl[k].a1] - r[1]) <= 2 * LSB);
                assert_true(fabs(q[3 - pl[k].a0 - pl[k].a1]) <= PT_TOL);
            }
    }
    expect_diag(parse("G18\nG5.2 Z0 X1 Y3 P1\n"), CS_ERR_PARSE, 2, 12);
    /* G5 and G5.1 stay XY-only, as in LinuxCNC. */
    expect_diag(parse("G18 G5.1 X1 I1 J1\n"), CS_ERR_UNSUPPORTED, 1, 5);
    assert_non_null(strstr(D.reason, "G17 (XY) plane only"));
}

/* G6.2 (Fanuc's G06.2 block form): P order, K one knot per line, R weights, then the last order
 * knots alone. Knots 0 0 0 1 1 1 over three points: one quadratic Bézier, its middle point by
 * hand; R2 on the middle point: (0.25 P0 + 0.5*2 P1 + 0.25 P2) / 1.5 at t = 1/2. */
static void test_g62(void **state)
{
    (void)state;
    assert_int_equal(parse("F60\nG6.2 P3 K0 X0 Y0 R1\nK0 X0 Y5 R1\nK0 X5 Y5\nK1\nK1\nK1\n"
                           "G1 X10\n"),
                     CS_OK);
    assert_int_equal(P.n, 2);
    assert_int_equal(P.elems[0].curve.degree, 2);
    double q[3];
    cs_path_eval_mm(&P.elems[0].curve, 0.5, q);
    assert_true(fabs(q[0] - 1.25) <= 2 * LSB && fabs(q[1] - 3.75) <= 2 * LSB);
    expect_pt(1, 1, 10, 5, 0, PT_TOL);
    assert_int_equal(parse("F60\nG6.2 P3 K0 X0 Y0\nK0 X0 Y5 R2\nK0 X5 Y5\nK1\nK1\nK1\n"), CS_OK);
    cs_path_eval_mm(&P.elems[0].curve, 0.5, q);
    assert_true(fabs(q[0] - 1.25 / 1.5) <= 2 * LSB && fabs(q[1] - 6.25 / 1.5) <= 2 * LSB);
    /* Cubic, uneven knots 0 0 0 0 1 3 3 3 3 over five points: two spans against Cox-de Boor. */
    static const double cp[5][3] = {{0, 0, 1}, {1, 4, 2}, {5, 5, 1}, {8, 1, 0.5}, {9, 3, 1}};
    static const double kn[9] = {0, 0, 0, 0, 1, 3, 3, 3, 3};
    assert_int_equal(parse("F60\nG6.2 P4 K0 X0 Y0\nK0 X1 Y4 R2\nK0 X5 Y5\nK0 X8 Y1 R0.5\n"
                           "K1 X9 Y3\nK3\nK3\nK3\nK3\n"),
                     CS_OK);
    assert_int_equal(P.n, 2);
    for (int s = 0; s < 2; s++)
        for (int j = 0; j <= 20; j++) {
            double t = j / 20.0, r[2];
            double u = s == 0 ? t : 1 + 2 * t;
            cs_path_eval_mm(&P.elems[s].curve, t, q);
            nurbs_eval_k(cp, 5, 4, kn, u, r);
            assert_true(fabs(q[0] - r[0]) <= 4 * LSB && fabs(q[1] - r[1]) <= 4 * LSB);
        }
    /* Errors: the first point away from the tool; knots that do not add up; order 5. */
    expect_diag(parse("G6.2 P3 K0 X1 Y0\n"), CS_ERR_PARSE, 1, 1);
    expect_diag(parse("G6.2 P3 K0 X0 Y0\nK0 X0 Y5\nK0 X5 Y5\nK1\nK1\nG1 X1 F1\n"), CS_ERR_PARSE, 1,
                1);
    expect_diag(parse("G6.2 P5 K0 X0 Y0\n"), CS_ERR_UNSUPPORTED, 1, 6);
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_g0_g1_lines_feed_rapid),
        cmocka_unit_test(test_modal_motion_and_lowercase),
        cmocka_unit_test(test_units_inch_and_incremental),
        cmocka_unit_test(test_g92_offsets),
        cmocka_unit_test(test_subpaths_pen_and_program_end),
        cmocka_unit_test(test_pen_z_moves),
        cmocka_unit_test(test_comments_line_numbers_block_delete),
        cmocka_unit_test(test_checksums),
        cmocka_unit_test(test_unsupported_strict_and_lenient),
        cmocka_unit_test(test_lenient_drops_words_of_dropped_codes),
        cmocka_unit_test(test_syntax_errors),
        cmocka_unit_test(test_polar_coordinates),
        cmocka_unit_test(test_arc_ijk_quarter_both_directions),
        cmocka_unit_test(test_arc_planes),
        cmocka_unit_test(test_arc_full_circle_and_turns),
        cmocka_unit_test(test_arc_r_form),
        cmocka_unit_test(test_arc_errors),
        cmocka_unit_test(test_g81_drilling_cycle),
        cmocka_unit_test(test_g81_errors),
        cmocka_unit_test(test_g83_g73_pecking),
        cmocka_unit_test(test_arc_off_plane_offset),
        cmocka_unit_test(test_lenient_ignored_words_reported_once),
        cmocka_unit_test(test_arc_tiny_pieces),
        cmocka_unit_test(test_arc_small_radius_near_quarter),
        cmocka_unit_test(test_arc_piece_halved_by_rounding),
        cmocka_unit_test(test_helix),
        cmocka_unit_test(test_g5_linuxcnc_facts),
        cmocka_unit_test(test_g5_errors),
        cmocka_unit_test(test_g51_parabola),
        cmocka_unit_test(test_g52_nurbs),
        cmocka_unit_test(test_g52_errors),
        cmocka_unit_test(test_params_take_effect_at_end_of_line),
        cmocka_unit_test(test_params_named_scope),
        cmocka_unit_test(test_params_errors),
        cmocka_unit_test(test_expression_star_is_not_a_checksum),
        cmocka_unit_test(test_exponent_is_an_error),
        cmocka_unit_test(test_oword_sub_call),
        cmocka_unit_test(test_oword_loops_and_ifs),
        cmocka_unit_test(test_oword_errors),
        cmocka_unit_test(test_grbl_dialect),
        cmocka_unit_test(test_arc_radius_rules),
        cmocka_unit_test(test_units_start_and_g64),
        cmocka_unit_test(test_lenient_skips_motion_block),
        cmocka_unit_test(test_g52_planes),
        cmocka_unit_test(test_g62),
        cmocka_unit_test(test_cncjs_plane_arcs),
        cmocka_unit_test(test_cncjs_one_inch_circle),
        cmocka_unit_test(test_cncjs_helical_thread),
        cmocka_unit_test(test_cncjs_bad_files),
        cmocka_unit_test(test_cncjs_arc_r_lenient),
        cmocka_unit_test(test_cncjs_motion_lenient),
        cmocka_unit_test(test_cncjs_special_fields_lenient),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
