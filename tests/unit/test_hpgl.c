/* test_hpgl: HP-GL / HP-GL/2 files (host/cs_hpgl.c) -> path elements. Every instruction is
 * checked against geometry worked out in double from its parameters (1 plotter unit = 0.025 mm,
 * Y up, nothing flipped): line ends to 0.5 LSB (a point is its exact value rounded once), arc
 * points to 4 LSB of the exact circle (cs_arc_build promises 2 LSB from its quantised centre
 * and axes, each rounded once more), arc sweeps to 1e-6 rad. Malformed inputs must give
 * CS_ERR_PARSE / CS_ERR_RANGE at the right line:col. The real file tests/data/hpgl/
 * feature-exercise.plt (from ../shared/data, see tests/data/SOURCES.md) must read and trace.
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

#include "cs_hpgl.h"
#include "cs_ref.h"
#include "cs_trace.h"

#define LSB     (1.0 / 65536.0)
#define PT_TOL  (0.5 * LSB + 1e-9)
#define ARC_TOL (4.0 * LSB)
#define PLU     (1.0 / 40.0) /* mm per plotter unit */

static cs_path_t P;
static cs_path_diag_t D;
static int nwarn;
static char warns[4096];

static void on_warn(void *ctx, const cs_path_diag_t *w)
{
    (void)ctx;
    nwarn++;
    size_t n = strlen(warns);
    snprintf(warns + n, sizeof warns - n, "%u:%u: %s\n", w->loc.line, w->loc.col, w->reason);
}

static cs_err_t rd(const char *text)
{
    cs_path_free(&P);
    cs_path_init(&P);
    memset(&D, 0, sizeof D);
    nwarn = 0;
    warns[0] = '\0';
    cs_hpgl_opts_t o;
    cs_hpgl_opts_init(&o);
    o.warn = on_warn;
    return cs_hpgl_read("t.plt", text, strlen(text), &o, &P, &D);
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

/* Point p equals (x, y) plotter units. */
static void expect_plu(const cs_vec3_t *p, double x, double y)
{
    if (fabs(p->x * LSB - x * PLU) > PT_TOL || fabs(p->y * LSB - y * PLU) > PT_TOL || p->z != 0)
        fail_msg("point (%.9f, %.9f) mm, expected (%.9f, %.9f)", p->x * LSB, p->y * LSB, x * PLU,
                 y * PLU);
}

static void expect_line(size_t i, double x0, double y0, double x1, double y1)
{
    assert_true(i < P.n);
    assert_int_equal(P.elems[i].kind, CS_PATH_LINE);
    assert_int_equal(P.elems[i].curve.degree, 1);
    expect_plu(&P.elems[i].curve.p[0], x0, y0);
    expect_plu(&P.elems[i].curve.p[1], x1, y1);
}

/* Elements [from, to) are arc pieces of the circle about (cx, cy) plotter units, radius r,
 * starting at angle a0 (degrees) and sweeping `sweep` degrees in total (sign = direction). */
static void expect_arc(size_t from, size_t to, double cx, double cy, double r, double a0,
                       double sweep)
{
    assert_true(from < to && to <= P.n);
    double mx = cx * PLU, my = cy * PLU, rm = r * PLU;
    double prev = a0 * M_PI / 180.0, total = 0.0;
    cs_ref_vec_t s = cs_ref_eval(&P.elems[from].curve, 0.0);
    assert_true(fabs(s.x - (mx + rm * cos(prev))) <= ARC_TOL);
    assert_true(fabs(s.y - (my + rm * sin(prev))) <= ARC_TOL);
    for (size_t i = from; i < to; i++) {
        assert_int_equal(P.elems[i].kind, CS_PATH_ARC);
        assert_int_equal(P.elems[i].subpath, P.elems[from].subpath);
        for (int k = 1; k <= 64; k++) {
            cs_ref_vec_t q = cs_ref_eval(&P.elems[i].curve, k / 64.0);
            double d = hypot(q.x - mx, q.y - my);
            if (fabs(d - rm) > ARC_TOL)
                fail_msg("arc piece %zu at t=%g: radius %.9f, expected %.9f", i, k / 64.0, d, rm);
            double a = atan2(q.y - my, q.x - mx), da = a - prev;
            while (da > M_PI)
                da -= 2 * M_PI;
            while (da < -M_PI)
                da += 2 * M_PI;
            assert_true(sweep > 0 ? da >= -1e-9 : da <= 1e-9); /* never turns back */
            total += da;
            prev = a;
        }
    }
    if (fabs(total - sweep * M_PI / 180.0) > 1e-6)
        fail_msg("arc sweeps %.9f degrees, expected %.9f", total * 180.0 / M_PI, sweep);
}

/* --- instructions ------------------------------------------------------------------------- */

static void test_pu_pd_pa_pr(void **state)
{
    (void)state;
    /* Coordinate lists, pen up between, absolute then relative. */
    assert_int_equal(rd("IN;SP1;PU100,200;PD500,200,500,600;PU;PA800,800;PD;PR100,0,0,-300;"
                        "PU-50,0;PD0,10;"),
                     CS_OK);
    assert_int_equal(P.n, 5);
    expect_line(0, 100, 200, 500, 200);
    expect_line(1, 500, 200, 500, 600);
    expect_line(2, 800, 800, 900, 800); /* PR: relative to the current point */
    expect_line(3, 900, 800, 900, 500);
    expect_line(4, 850, 500, 850, 510); /* PU moves relatively too, PD stays relative */
    assert_int_equal(P.elems[0].subpath, 0);
    assert_int_equal(P.elems[1].subpath, 0);
    assert_int_equal(P.elems[2].subpath, 1);
    assert_int_equal(P.elems[3].subpath, 1);
    assert_int_equal(P.elems[4].subpath, 2);
    assert_int_equal(nwarn, 0);
    /* PU/PD take the pen state; PA/PR keep it and move with it. Decimal coordinates
     * (HP-GL/2), lowercase, blanks as separators, no ';' before the next mnemonic. */
    assert_int_equal(rd("in pu 10.5 20.25pd -30 40 pa 1 2 pr 3 4"), CS_OK);
    assert_int_equal(P.n, 3);
    expect_line(0, 10.5, 20.25, -30, 40);
    expect_line(1, -30, 40, 1, 2);
    expect_line(2, 1, 2, 4, 6);
    /* IN resets: absolute, pen up, back at the origin. */
    assert_int_equal(rd("PR;PD100,100;IN;PD5,5;PU;PD;PA10,0"), CS_OK);
    assert_int_equal(P.n, 3);
    expect_line(0, 0, 0, 100, 100);
    expect_line(1, 0, 0, 5, 5);
    expect_line(2, 5, 5, 10, 0);
    assert_int_equal(P.elems[1].subpath, 1);
    /* A pen-down move to where the pen is draws nothing; Y is not flipped. */
    assert_int_equal(rd("IN;PD0,0;PD0,-4000;"), CS_OK);
    assert_int_equal(P.n, 1);
    expect_line(0, 0, 0, 0, -4000);
    assert_true(P.elems[0].curve.p[1].y == -100 * 65536); /* -4000 plu = -100 mm exactly */
}

static void test_sp(void **state)
{
    (void)state;
    /* A pen change breaks the path even without a pen lift; SP0 (no pen) draws nothing. */
    assert_int_equal(rd("IN;PD100,0;SP2;PD200,0;SP0;PD300,0;SP1;PD400,0;SP;PD500,0;"), CS_OK);
    assert_int_equal(P.n, 3);
    expect_line(0, 0, 0, 100, 0);
    expect_line(1, 100, 0, 200, 0);
    expect_line(2, 300, 0, 400, 0);
    assert_int_equal(P.elems[1].subpath, 1);
    assert_int_equal(P.elems[2].subpath, 2);
    assert_int_equal(nwarn, 1); /* "no pen selected", once */
    assert_non_null(strstr(warns, "SP0"));
}

static void test_ci(void **state)
{
    (void)state;
    /* CI 400 at (1000, 1000): a full circle of 10 mm radius from angle 0, counter-clockwise,
     * drawn with the pen up; the pen comes back to the centre, still up. */
    assert_int_equal(rd("IN;PU1000,1000;CI400;PD1000,1200;"), CS_OK);
    assert_int_equal(P.n, 5);
    expect_arc(0, 4, 1000, 1000, 400, 0, 360);
    expect_plu(&P.elems[3].curve.p[2], 1400, 1000); /* closed, exactly */
    expect_line(4, 1000, 1000, 1000, 1200);
    assert_int_equal(P.elems[4].subpath, P.elems[0].subpath + 1);
    /* Negative radius: starts at 180 degrees; the chord angle is accepted and ignored. */
    assert_int_equal(rd("IN;PU400,0;PD;CI-200,5;PD400,100"), CS_OK);
    assert_int_equal(P.n, 5);
    expect_arc(0, 4, 400, 0, 200, 180, 360);
    expect_line(4, 400, 0, 400, 100); /* pen was down: it stays down, from the centre */
    assert_int_equal(rd("IN;CI0;"), CS_OK);
    assert_int_equal(P.n, 0);
}

static void test_aa_ar(void **state)
{
    (void)state;
    /* AA: centre (1000, 1000), from (1400, 1000), 90 degrees counter-clockwise: ends at
     * (1000, 1400), then a line on from there. */
    assert_int_equal(rd("IN;PU1400,1000;PD;AA1000,1000,90;PD1000,1500;"), CS_OK);
    assert_int_equal(P.n, 2);
    expect_arc(0, 1, 1000, 1000, 400, 0, 90);
    expect_plu(&P.elems[0].curve.p[2], 1000, 1400);
    expect_line(1, 1000, 1400, 1000, 1500);
    assert_int_equal(P.elems[1].subpath, P.elems[0].subpath);
    /* Negative sweep: clockwise. 200 degrees: 4 pieces. */
    assert_int_equal(rd("IN;PU1400,1000;PD;AA1000,1000,-200,5;"), CS_OK);
    expect_arc(0, P.n, 1000, 1000, 400, 0, -200);
    double e = -200 * M_PI / 180;
    expect_plu(&P.elems[P.n - 1].curve.p[2], 1000 + 400 * cos(e), 1000 + 400 * sin(e));
    /* AR: the centre relative to the current point; a 45-degree arc from (0, 0) about
     * (-300, 400) (radius 500). */
    assert_int_equal(rd("IN;PD;AR-300,400,45;"), CS_OK);
    double a0 = atan2(-400, 300) * 180 / M_PI;
    expect_arc(0, P.n, -300, 400, 500, a0, 45);
    /* Pen up: the arc is not drawn, but the pen goes to its end. */
    assert_int_equal(rd("IN;PU1400,1000;AA1000,1000,90;PD1000,1500;"), CS_OK);
    assert_int_equal(P.n, 1);
    expect_line(0, 1000, 1400, 1000, 1500);
    /* A sweep of 360 or more is one full turn; the pen ends where it began. */
    assert_int_equal(rd("IN;PU1400,1000;PD;AA1000,1000,720;PD1400,0"), CS_OK);
    expect_arc(0, 4, 1000, 1000, 400, 0, 360);
    expect_line(4, 1400, 1000, 1400, 0);
    assert_int_equal(nwarn, 1);
    /* Zero radius (pen on the centre) or zero sweep: nothing drawn. */
    assert_int_equal(rd("IN;PD;AA0,0,90;AA100,0,0;PD0,100"), CS_OK);
    assert_int_equal(P.n, 1);
    expect_line(0, 0, 0, 0, 100);
    /* A tiny sweep is its chord, not a full turn. */
    assert_int_equal(rd("IN;PU100,0;PD;AA0,0,0.0000001;"), CS_OK);
    assert_true(P.n <= 1);
}

static void test_bz_br(void **state)
{
    (void)state;
    /* BZ: two cubics from the current point; control points as given. */
    assert_int_equal(
        rd("IN;PU0,0;PD;BZ100,0,200,100,300,300,400,400,500,400,600,300;PU;BZ1,1,2,2,3,3;"), CS_OK);
    assert_int_equal(P.n, 2);
    static const double z[2][4][2] = {{{0, 0}, {100, 0}, {200, 100}, {300, 300}},
                                      {{300, 300}, {400, 400}, {500, 400}, {600, 300}}};
    for (size_t i = 0; i < 2; i++) {
        assert_int_equal(P.elems[i].kind, CS_PATH_CUBIC);
        for (int k = 0; k < 4; k++)
            expect_plu(&P.elems[i].curve.p[k], z[i][k][0], z[i][k][1]);
    }
    /* BR: each curve's points relative to that curve's own start. */
    assert_int_equal(rd("IN;PU100,100;PD;BR10,0,20,10,30,30,0,10,5,20,-10,20;"), CS_OK);
    assert_int_equal(P.n, 2);
    static const double r[2][4][2] = {{{100, 100}, {110, 100}, {120, 110}, {130, 130}},
                                      {{130, 130}, {130, 140}, {135, 150}, {120, 150}}};
    for (size_t i = 0; i < 2; i++)
        for (int k = 0; k < 4; k++)
            expect_plu(&P.elems[i].curve.p[k], r[i][k][0], r[i][k][1]);
    /* The pen ends on the last point (PA mode is unchanged). */
    assert_int_equal(rd("IN;PD;BR1,1,2,2,3,3;PD10,10"), CS_OK);
    expect_line(1, 3, 3, 10, 10);
}

/* PE reference encoder: value v (already scaled) in base 64, 8-bit mode. */
static size_t pe_enc(char *out, long v)
{
    unsigned long u = v < 0 ? (unsigned long)(-v) * 2 + 1 : (unsigned long)v * 2;
    size_t n = 0;
    while (u >= 64) {
        out[n++] = (char)(63 + (u & 63));
        u >>= 6;
    }
    out[n++] = (char)(191 + u);
    return n;
}

static void test_pe(void **state)
{
    (void)state;
    /* PE with a pen-up relative move (<), then two relative pen-down moves, then an absolute
     * point (=), with pen 2 selected (:). */
    char buf[256] = "IN;PE:";
    size_t n = strlen(buf);
    n += pe_enc(buf + n, 2);
    buf[n++] = '<';
    n += pe_enc(buf + n, 1000);
    n += pe_enc(buf + n, -500);
    n += pe_enc(buf + n, 300);
    n += pe_enc(buf + n, 0);
    n += pe_enc(buf + n, -4000);
    n += pe_enc(buf + n, 70000);
    buf[n++] = '=';
    n += pe_enc(buf + n, 10);
    n += pe_enc(buf + n, 20);
    buf[n++] = ';';
    buf[n] = '\0';
    assert_int_equal(rd(buf), CS_OK);
    assert_int_equal(P.n, 3);
    expect_line(0, 1000, -500, 1300, -500);
    expect_line(1, 1300, -500, -2700, 69500);
    expect_line(2, -2700, 69500, 10, 20);
    /* Fractional bits (>): 3 bits, so 12 -> 1.5. */
    strcpy(buf, "IN;PE>");
    n = strlen(buf);
    n += pe_enc(buf + n, 3);
    n += pe_enc(buf + n, 12);
    n += pe_enc(buf + n, -4);
    buf[n++] = ';';
    buf[n] = '\0';
    assert_int_equal(rd(buf), CS_OK);
    assert_int_equal(P.n, 1);
    expect_line(0, 0, 0, 1.5, -0.5);
    /* 7-bit mode: 63..94 continue, 95..126 end (base 32): 40 -> 80 = 16 + 2*32 -> 'O' 'a'. */
    assert_int_equal(rd("IN;PE7Oa?_;"), CS_OK);
    assert_int_equal(P.n, 1);
    expect_line(0, 0, 0, 40, 0);
    assert_int_equal(rd("IN;PE\x41;"), CS_ERR_PARSE); /* not terminated */
    assert_int_equal(D.loc.col, 6);
}

static void test_terminators_and_skipped(void **state)
{
    (void)state;
    /* Unknown and unsupported instructions: one warning per mnemonic, parameters skipped; the
     * geometry around them is drawn. Labels are skipped up to ETX (letters and ';' inside);
     * DT changes the terminator; SM takes the next character; CO skips its string. */
    assert_int_equal(rd("IN;LT2;PD100,0;LT;ZZ1,2,3;ZZ;LBtext; PD9,9\x03PD200,0;DT#;LBa;b#"
                        "SM*;PD300,0;SM;CO\"PD 1,1;\";PD400,0;"),
                     CS_OK);
    assert_int_equal(P.n, 4);
    expect_line(0, 0, 0, 100, 0);
    expect_line(3, 300, 0, 400, 0);
    assert_int_equal(nwarn, 4); /* LT, ZZ, LB, SM */
    assert_non_null(strstr(warns, "1:4: LT: line types ignored"));
    assert_non_null(strstr(warns, "ZZ: not supported"));
    /* Geometry the reader does not draw says so; RO, IW and SC are carried out (no warning). */
    assert_int_equal(rd("IN;EA10,10;RO90;IW0,0,5,5;SC0,100,0,100;"), CS_OK);
    assert_int_equal(nwarn, 1);
    assert_non_null(strstr(warns, "geometry is missing"));
    /* Escape sequences are skipped (one warning). */
    assert_int_equal(rd("\x1b.(\x1b.I81;;17:\x1b%-1BIN;PD10,10;\x1b"
                        "E"),
                     CS_OK);
    assert_int_equal(P.n, 1);
    assert_int_equal(nwarn, 1);
}

static void test_errors(void **state)
{
    (void)state;
    /* Odd coordinate count: at the lone x, line 2 column 3. */
    assert_int_equal(rd("IN;\nPD10;"), CS_ERR_PARSE);
    assert_string_equal(D.loc.file, "t.plt");
    assert_int_equal(D.loc.line, 2);
    assert_int_equal(D.loc.col, 3);
    assert_non_null(strstr(D.reason, "pairs"));
    /* A stray character in the parameters: at it. */
    assert_int_equal(rd("IN;PD10,10@;"), CS_ERR_PARSE);
    assert_int_equal(D.loc.col, 11);
    /* Outside +/-4096 mm (163840 plotter units): a range error at the pair. */
    assert_int_equal(rd("IN;PD 163840,0 163841,0;"), CS_ERR_RANGE);
    assert_int_equal(D.loc.col, 16);
    assert_int_equal(P.n, 1);
    assert_int_equal(rd("IN;PR100000,0,100000,0;"), CS_ERR_RANGE);
    /* No exponents in HP-GL: said at the number (it read as a digit then an "e1" mnemonic). */
    assert_int_equal(rd("IN;PD1e5,0;"), CS_ERR_PARSE);
    assert_int_equal(D.loc.col, 6);
    assert_non_null(strstr(D.reason, "PD: number in exponent form"));
    assert_int_equal(rd("IN;PU10,0;PD;AA0,0,1E-3;"), CS_ERR_PARSE);
    assert_int_equal(D.loc.col, 20);
    /* ... while a letter pair after a number is the next instruction, E or not. */
    assert_int_equal(rd("IN;PA10,10EA20,20;"), CS_OK);
    assert_int_equal(rd("IN;PD99999999999,0;"), CS_ERR_RANGE);
    /* Parameter counts. */
    assert_int_equal(rd("IN;AA0,0;"), CS_ERR_PARSE);
    assert_int_equal(D.loc.col, 4);
    assert_int_equal(rd("IN;CI1,2,3;"), CS_ERR_PARSE);
    assert_int_equal(D.loc.col, 10);
    assert_int_equal(rd("IN;BZ1,2,3,4,5;"), CS_ERR_PARSE);
    assert_int_equal(D.loc.col, 6);
    assert_non_null(strstr(D.reason, "groups of"));
    /* Not an instruction. */
    assert_int_equal(rd("IN;\n 12;"), CS_ERR_PARSE);
    assert_int_equal(D.loc.line, 2);
    assert_int_equal(D.loc.col, 2);
    assert_int_equal(rd("IN;P"), CS_ERR_PARSE);
    assert_int_equal(rd("CO\"open"), CS_ERR_PARSE);
    assert_int_equal(rd("\x1bQ"), CS_ERR_PARSE);
    /* The CI's circle out of range: the whole circle must fit. */
    assert_int_equal(rd("IN;PU160000,0;CI5000;"), CS_ERR_RANGE);
}

/* --- the real file ------------------------------------------------------------------------ */

/* --- scaling, rotation, window (HP-GL/2 reference: SC, IP, IR, PS, RO, IW) ---------------- */

static void test_sc_ip_ir_ps(void **state)
{
    (void)state;
    /* SC type 0: user (0,0) -> P1, (100,50) -> P2. */
    assert_int_equal(rd("IN;IP1000,1000,5000,3000;SC0,100,0,50;PU0,0;PD100,50;"), CS_OK);
    expect_line(0, 1000, 1000, 5000, 3000);
    /* Type 1, isotropic: factor min(4000/100, 2000/100) = 20; the extra 2000 in x split 50 %. */
    assert_int_equal(rd("IN;IP0,0,4000,2000;SC0,100,0,100,1;PU0,0;PD100,100;"), CS_OK);
    expect_line(0, 1000, 0, 3000, 2000);
    assert_int_equal(rd("IN;IP0,0,4000,2000;SC0,100,0,100,1,0,0;PU0,0;PD100,100;"), CS_OK);
    expect_line(0, 0, 0, 2000, 2000);
    assert_int_equal(rd("IN;IP0,0,4000,2000;SC0,100,0,100,1,100,100;PU0,0;PD100,100;"), CS_OK);
    expect_line(0, 2000, 0, 4000, 2000);
    /* Type 2, point factor: user 0 at P1 = (500, 500), 2 and 3 plotter units per user unit. */
    assert_int_equal(rd("IN;IP500,500;SC0,2,0,3,2;PU0,0;PD10,10;"), CS_OK);
    expect_line(0, 500, 500, 520, 530);
    /* IR: percentages of the default frame, 11880 x 8400 (A4 landscape). */
    assert_int_equal(rd("IN;IR10,20,60,70;SC0,1,0,1;PU0,0;PD1,1;"), CS_OK);
    expect_line(0, 1188, 1680, 7128, 5880);
    /* PS sets the frame that IR refers to. */
    assert_int_equal(rd("IN;PS8000,6000;IR0,0,50,50;SC0,1,0,1;PU0,0;PD1,1;"), CS_OK);
    expect_line(0, 0, 0, 4000, 3000);
    /* SC; ends scaling: plotter units again. */
    assert_int_equal(rd("IN;IP0,0,100,100;SC0,1,0,1;SC;PU0,0;PD10,10;"), CS_OK);
    expect_line(0, 0, 0, 10, 10);
    /* DF ends scaling too (P1, P2 stay): 10,10 is plotter units again. */
    assert_int_equal(rd("IN;IP0,0,400,400;SC0,10,0,10;DF;PU0,0;PD10,10;"), CS_OK);
    expect_line(0, 0, 0, 10, 10);
    /* Arcs under anisotropic scaling become ellipses: CI 10 with x 40, y 20 plu per unit. */
    assert_int_equal(rd("IN;IP0,0,400,200;SC0,10,0,10;PU0,0;CI10;"), CS_OK);
    for (size_t i = 0; i < P.n; i++)
        for (int k = 0; k <= 16; k++) {
            cs_ref_vec_t q = cs_ref_eval(&P.elems[i].curve, k / 16.0);
            double ex = q.x / (400 * PLU), ey = q.y / (200 * PLU); /* back to unit circle */
            assert_true(fabs(hypot(ex, ey) - 1.0) < 1e-5);
        }
    assert_int_equal(rd("IN;SC0,0,0,1;"), CS_ERR_PARSE);
    assert_int_equal(rd("IN;SC0,1,0,1,3;"), CS_ERR_PARSE);
    assert_int_equal(rd("IN;IP1,2,3;"), CS_ERR_PARSE);
}

static void test_ro(void **state)
{
    (void)state;
    /* RO turns the system counter-clockwise about the frame (11880 x 8400):
     * 90: X = W - y, Y = x; 180: X = W - x, Y = H - y; 270: X = y, Y = H - x. */
    assert_int_equal(rd("IN;RO90;PU100,200;PD300,200;"), CS_OK);
    expect_line(0, 11680, 100, 11680, 300);
    assert_int_equal(rd("IN;RO180;PU100,200;PD300,200;"), CS_OK);
    expect_line(0, 11780, 8200, 11580, 8200);
    assert_int_equal(rd("IN;RO270;PU100,200;PD300,200;"), CS_OK);
    expect_line(0, 200, 8300, 200, 8100);
    /* The pen does not move on the paper; a relative +x move after RO90 goes up the page. */
    assert_int_equal(rd("IN;PU100,200;RO90;PR;PD10,0;"), CS_OK);
    expect_line(0, 100, 200, 100, 210);
    assert_int_equal(rd("IN;RO45;"), CS_ERR_PARSE);
}

static void test_iw(void **state)
{
    (void)state;
    /* A line across the window keeps its inside part; one outside is dropped. */
    assert_int_equal(rd("IN;IW1000,1000,2000,2000;PU0,1500;PD3000,1500;PU1500,0;PD1500,500;"),
                     CS_OK);
    assert_int_equal(P.n, 1);
    expect_line(0, 1000, 1500, 2000, 1500);
    /* The window is in user units when SC is on: 2..8 of 0..10 on 0..1000 plu. IW; ends it. */
    assert_int_equal(rd("IN;IP0,0,1000,1000;SC0,10,0,10;IW2,2,8,8;PU0,5;PD10,5;IW;PU0,6;PD10,6;"),
                     CS_OK);
    assert_int_equal(P.n, 2);
    expect_line(0, 200, 500, 800, 500);
    expect_line(1, 0, 600, 1000, 600);
    /* The pen left the window; with the window gone the next line starts a new stroke where
     * the pen is (found by the fuzzer: the two were once one subpath with a gap). */
    assert_int_equal(rd("IN;IW1000,1000,2000,2000;PU0,1500;PD3000,1500;IW;PD3000,2500;"), CS_OK);
    assert_int_equal(P.n, 2);
    expect_line(0, 1000, 1500, 2000, 1500);
    expect_line(1, 3000, 1500, 3000, 2500);
    assert_true(P.elems[0].subpath != P.elems[1].subpath);
    /* A polyline leaving and re-entering: two strokes. */
    assert_int_equal(rd("IN;IW0,0,1000,1000;PU500,500;PD1500,500,1500,700,500,700;"), CS_OK);
    assert_int_equal(P.n, 2);
    expect_line(0, 500, 500, 1000, 500);
    expect_line(1, 1000, 700, 500, 700);
    assert_true(P.elems[0].subpath != P.elems[1].subpath);
}

static void test_pe_next_instruction(void **state)
{
    (void)state;
    /* AutoCAD ends PE with the next instruction. 7-bit values (base 32, sign in the low bit,
     * continuation 63..94, last digit 95..126): "_" = 0, "?x" = 400, "@x" = -400. */
    assert_int_equal(rd("IN;SP1;PE7<=__?x__?x@x_PU0,0;PD0,-400;"), CS_OK);
    assert_int_equal(P.n, 4);
    expect_line(0, 0, 0, 400, 0);
    expect_line(1, 400, 0, 400, 400);
    expect_line(2, 400, 400, 0, 400);
    expect_line(3, 0, 0, 0, -400);
    /* 8-bit: 0 = 0xBF, 400 = '_' 0xCB (800 = 32 + 12 * 64), ended by SP. */
    assert_int_equal(rd("IN;SP1;PE<=\xbf\xbf_\xcb\xbfSP2;PD0,0;"), CS_OK);
    assert_int_equal(P.n, 2);
    expect_line(0, 0, 0, 400, 0);
    expect_line(1, 400, 0, 0, 0);
}

static void test_feature_exercise(void **state)
{
    (void)state;
    FILE *f = fopen("tests/data/hpgl/feature-exercise.plt", "rb");
    assert_non_null(f);
    static char buf[1 << 16];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    cs_path_free(&P);
    cs_path_init(&P);
    nwarn = 0;
    warns[0] = '\0';
    cs_hpgl_opts_t o;
    cs_hpgl_opts_init(&o);
    o.warn = on_warn;
    cs_err_t e = cs_hpgl_read("feature-exercise.plt", buf, n, &o, &P, &D);
    if (e != CS_OK)
        fail_msg("%u:%u: %s", D.loc.line, D.loc.col, D.reason);
    /* The frame: PU0,0;PD10000,0;PD10000,7000;PD0,7000;PD0,0 (250 x 175 mm). */
    expect_line(0, 0, 0, 10000, 0);
    expect_line(1, 10000, 0, 10000, 7000);
    expect_line(2, 10000, 7000, 0, 7000);
    expect_line(3, 0, 7000, 0, 0);
    /* Seven line-type samples PU900,y;PD2600,y for y = 5950 - 150 k (drawn solid). */
    for (int k = 0; k < 7; k++)
        expect_line(4 + (size_t)k, 900, 5950 - 150 * k, 2600, 5950 - 150 * k);
    /* PU3500,5500;CI420: a circle; PU4700,5500;AA4200,5500,180: a half circle not drawn (the
     * pen is up: the file lifts it before AA), so the next element is the IW-clipped circle:
     * PU3550,1100;CI500. */
    expect_arc(11, 15, 3500, 5500, 420, 0, 360);
    /* PM polygon: PU7300,3300;PM0;PD9000,3300;PD9000,4500;PD7300,4500;PD7300,3300 and the hole
     * are drawn as outlines. */
    expect_line(15, 7300, 3300, 9000, 3300);
    expect_line(18, 7300, 4500, 7300, 3300);
    expect_line(19, 7700, 3650, 8600, 3650);
    expect_line(22, 7700, 4150, 7700, 3650);
    /* SM* then PA moves with the pen up: symbols only, no lines. Then the clip demo. */
    /* IW3000,700,4100,1500 clips the circle at y = 1500 and y = 700: sin(a) = +-400/500, so
     * a = 53.13, 126.87, 233.13, 306.87 degrees; three runs, each its own stroke. */
    double a = atan2(400.0, 300.0) * 180.0 / M_PI;
    expect_arc(23, 24, 3550, 1100, 500, 0, a);
    expect_arc(24, 26, 3550, 1100, 500, 180 - a, 2 * a);
    expect_arc(26, 27, 3550, 1100, 500, 360 - a, a);
    assert_true(P.elems[24].subpath != P.elems[23].subpath);
    assert_true(P.elems[26].subpath != P.elems[25].subpath);
    /* IW4400,700,5600,1500: the line (4200,700)-(5800,1500), slope 1/2, enters at x = 4400
     * (y = 800) and leaves at x = 5600 (y = 1400); the top edge y = 1500 keeps 4400..5600. */
    expect_line(27, 4400, 800, 5600, 1400);
    expect_line(28, 5600, 1500, 4400, 1500);
    assert_int_equal(P.n, 29);
    /* Each skipped instruction that changes the drawing is reported, once each. */
    static const char *const must[] = {
        "LB:", "LT:", "EW:", "WG:", "EA:", "RA:", "RR:", "PM:", "FP:", "EP:", "SM:"};
    for (size_t i = 0; i < sizeof must / sizeof must[0]; i++)
        if (!strstr(warns, must[i]))
            fail_msg("no warning for %s", must[i]);
    assert_null(strstr(strstr(warns, "LT:") + 3, "LT:"));
    /* Every element traces (0.01 mm) and ends on its last control point. */
    for (size_t i = 0; i < P.n; i++) {
        cs_trace_t tr;
        assert_int_equal(
            cs_trace_begin(&tr, &P.elems[i].curve, CS_POS_ONE_MM / 100, CS_TRACE_SUBDIV), CS_OK);
        cs_vec3_t pt, last = P.elems[i].curve.p[0];
        while ((e = cs_trace_next(&tr, &pt)) == CS_OK)
            last = pt;
        assert_int_equal(e, CS_END);
        const cs_vec3_t *end = &P.elems[i].curve.p[P.elems[i].curve.degree];
        assert_true(last.x == end->x && last.y == end->y);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_pu_pd_pa_pr, setup, teardown),
        cmocka_unit_test_setup_teardown(test_sp, setup, teardown),
        cmocka_unit_test_setup_teardown(test_ci, setup, teardown),
        cmocka_unit_test_setup_teardown(test_aa_ar, setup, teardown),
        cmocka_unit_test_setup_teardown(test_bz_br, setup, teardown),
        cmocka_unit_test_setup_teardown(test_pe, setup, teardown),
        cmocka_unit_test_setup_teardown(test_terminators_and_skipped, setup, teardown),
        cmocka_unit_test_setup_teardown(test_errors, setup, teardown),
        cmocka_unit_test_setup_teardown(test_sc_ip_ir_ps, setup, teardown),
        cmocka_unit_test_setup_teardown(test_ro, setup, teardown),
        cmocka_unit_test_setup_teardown(test_iw, setup, teardown),
        cmocka_unit_test_setup_teardown(test_pe_next_instruction, setup, teardown),
        cmocka_unit_test_setup_teardown(test_feature_exercise, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
