/* test_hershey: Hershey stroke fonts (host/cs_hershey.c) and the text they draw. The shipped
 * font share/fonts/futural.jhf is read (96 glyphs; 'H' and 'A' decoded by hand from their
 * records: "G]KFK[ RYFY[ RKPYP" and "I[RFJ[ RRFZ[ RMTWT", value = character - 'R'); files that
 * are not fonts fail with file:line:col; SVG <text> (x, y, font-size, text-anchor, transform,
 * tspan) and HP-GL LB (SI, DT) land where the layout rule puts each glyph vertex, computed here
 * by hand: point (gx, gy) of a glyph at advance a -> (x + s (a + gx - left), y + s (gy - 9)),
 * s = font-size / 32 (SVG) or SI height / 21 per font unit (HP-GL, y up). Tolerance: 1 LSB of
 * the Q16.16 coordinates (1.6e-5 mm) plus the conversion's rounding. Run from the repo root. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "cs_hershey.h"
#include "cs_input.h"

#define FONT "share/fonts/futural.jhf"
#define TOL  (2.0 / 65536.0)

static void quiet(void *ctx, const cs_path_diag_t *w)
{
    (void)ctx;
    (void)w;
}

static void test_reads_shipped_font(void **state)
{
    (void)state;
    cs_hershey_font_t f;
    cs_path_diag_t d;
    assert_int_equal(cs_hershey_load(FONT, &f, &d), CS_OK);
    assert_int_equal(f.nglyphs, 96);
    const cs_hershey_glyph_t *h = &f.glyph['H' - 32];
    assert_int_equal(h->left, -11);
    assert_int_equal(h->right, 11);
    assert_int_equal(h->n, 6);
    static const int want[6][3] = {{-7, -12, 1}, {-7, 9, 0},  {7, -12, 1},
                                   {7, 9, 0},    {-7, -2, 1}, {7, -2, 0}};
    for (size_t k = 0; k < 6; k++) {
        const cs_hershey_vertex_t *v = &f.v[h->first + k];
        assert_int_equal(v->x, want[k][0]);
        assert_int_equal(v->y, want[k][1]);
        assert_int_equal(v->move, want[k][2]);
    }
    assert_int_equal(f.glyph[0].n, 0); /* space: bearings only */
    assert_true(cs_hershey_width(&f, "HA", 2) == 22 + 18);
    cs_hershey_free(&f);
}

/* A bad font: the error's code and its line:col. */
static void bad_font(const char *text, unsigned line, unsigned col)
{
    cs_hershey_font_t f;
    cs_path_diag_t d;
    memset(&d, 0, sizeof d);
    assert_int_equal(cs_hershey_parse("bad.jhf", text, strlen(text), &f, &d), CS_ERR_PARSE);
    if (d.loc.line != line || d.loc.col != col)
        print_error("'%s': got %u:%u (%s), expected %u:%u\n", text, d.loc.line, d.loc.col, d.reason,
                    line, col);
    assert_int_equal(d.loc.line, line);
    assert_int_equal(d.loc.col, col);
    assert_string_equal(d.loc.file, "bad.jhf");
    assert_non_null(strstr(d.reason, "not a Hershey font"));
}

static void test_bad_fonts_located(void **state)
{
    (void)state;
    bad_font("<svg/>\n", 1, 1);                            /* not a number in columns 1-5 */
    bad_font("12345  9G]KFK[ RYFY[ RKPYP\nhello\n", 2, 1); /* second record not a record */
    bad_font("12345  0G]\n", 1, 8);                        /* no pairs at all */
    bad_font("12345  9G]KFK[\n", 2, 1);                    /* ends before its 9 pairs */
    bad_font("12345  2]GKF\n", 1, 12);                     /* right bearing left of left */
    bad_font("", 1, 1);                                    /* empty: no glyph */
    cs_hershey_font_t f;
    cs_path_diag_t d;
    assert_int_equal(cs_hershey_load("tests/data/nonexistent.jhf", &f, &d), CS_ERR_IO);
}

static cs_path_t P;

static cs_err_t parse(const char *name, const char *text, const char *font)
{
    cs_path_free(&P);
    cs_path_init(&P);
    cs_input_opts_t o;
    cs_input_opts_init(&o);
    o.font_file = font;
    o.warn = quiet;
    cs_path_diag_t d;
    return cs_input_parse(name, text, strlen(text), &o, &P, &d);
}

/* Element k is the line (x0, y0) - (x1, y1) in mm. */
static void expect_line(size_t k, double x0, double y0, double x1, double y1)
{
    assert_true(k < P.n);
    const cs_bezier_t *c = &P.elems[k].curve;
    double got[4] = {c->p[0].x / 65536.0, c->p[0].y / 65536.0, c->p[1].x / 65536.0,
                     c->p[1].y / 65536.0};
    double want[4] = {x0, y0, x1, y1};
    for (int i = 0; i < 4; i++) {
        if (fabs(got[i] - want[i]) > TOL)
            print_error("elem %zu coord %d: %.6f, expected %.6f\n", k, i, got[i], want[i]);
        assert_true(fabs(got[i] - want[i]) <= TOL);
    }
}

/* 'H' at pen x, baseline y, scale s (mm per font unit), sy = +-1 (y down / up). */
static void expect_h(size_t k, double x, double y, double s, double sx, double sy)
{
    double l = 11; /* -left */
    expect_line(k, x + sx * (-7 + l), y + sy * s * (-12 - 9), x + sx * (-7 + l), y);
    expect_line(k + 1, x + sx * (7 + l), y + sy * s * (-12 - 9), x + sx * (7 + l), y);
    expect_line(k + 2, x + sx * (-7 + l), y + sy * s * (-2 - 9), x + sx * (7 + l),
                y + sy * s * (-2 - 9));
}

#define SVG_HEAD                                                                                   \
    "<svg xmlns='http://www.w3.org/2000/svg' width='100mm' height='50mm' "                         \
    "viewBox='0 0 100 50'>"

static void test_svg_text_positions(void **state)
{
    (void)state;
    /* font-size 16 user units = 16 mm here: s = 0.5 mm per font unit */
    assert_int_equal(
        parse("t.svg", SVG_HEAD "<text x='10' y='30' font-size='16'>H</text></svg>", FONT), CS_OK);
    assert_int_equal(P.n, 3);
    assert_int_equal(P.nsubpaths, 3); /* three strokes: each its own subpath */
    expect_h(0, 10, 30, 0.5, 0.5, 1);
    /* text-anchor middle: the 22-unit advance (11 mm) centred on x */
    assert_int_equal(parse("t.svg",
                           SVG_HEAD "<text x='10' y='30' font-size='16' "
                                    "text-anchor='middle'>H</text></svg>",
                           FONT),
                     CS_OK);
    expect_h(0, 10 - 5.5, 30, 0.5, 0.5, 1);
    /* end, in a style attribute, under a translate */
    assert_int_equal(parse("t.svg",
                           SVG_HEAD "<g transform='translate(5,2)'><text x='20' y='30' "
                                    "style='font-size:16px;text-anchor:end'>H</text></g></svg>",
                           FONT),
                     CS_OK);
    expect_h(0, 25 - 11, 32, 0.5, 0.5, 1);
    /* "HA": A's first stroke starts at advance 22: (x + s (22 + 0 + 9), y + s (-12 - 9)) */
    assert_int_equal(parse("t.svg",
                           SVG_HEAD "<text x='10' y='30' font-size='16'>  H\n A</text>"
                                    "</svg>",
                           FONT),
                     CS_OK);
    /* white space collapsed: "H A", the space's advance is 16 units (futural " ": J Z) */
    expect_line(3, 10 + 0.5 * (22 + 16 + 9), 30 - 10.5, 10 + 0.5 * (22 + 16 + 1), 30);
    /* a tspan with its own x, y and size: 'H' at 40, 45 with s = 8 / 32 */
    assert_int_equal(parse("t.svg",
                           SVG_HEAD "<text x='10' y='30' font-size='16'>H<tspan x='40' "
                                    "y='45' font-size='8'>H</tspan></text></svg>",
                           FONT),
                     CS_OK);
    assert_int_equal(P.n, 6);
    expect_h(3, 40, 45, 0.25, 0.25, 1);
}

static void test_svg_text_without_font_or_bad_font(void **state)
{
    (void)state;
    assert_int_equal(
        parse("t.svg", SVG_HEAD "<text x='1' y='1'>H</text></svg>", "tests/data/SOURCES.md"),
        CS_ERR_PARSE);
}

static void test_hpgl_label(void **state)
{
    (void)state;
    /* 400 plu = 10 mm; SI 0.5 x 0.7 cm: cap height 7 mm, s = 7 / 21 mm per unit; x scaled by
     * the width's ratio to the default 0.19 x 0.27 cm cell */
    double s = 7.0 / 21.0, sx = s * (0.5 / 0.7) / (0.19 / 0.27);
    assert_int_equal(parse("l.plt", "IN;SP1;PU400,400;SI0.5,0.7;LBH\003;PD800,400;", FONT), CS_OK);
    assert_int_equal(P.n, 4);
    expect_h(0, 10, 10, s, sx, -1);
    /* the pen continues from the label's end: x + 22 sx */
    expect_line(3, 10 + 22 * sx, 10, 20, 10);
    /* no pen (SP0): nothing drawn, but the label still moves the current point */
    assert_int_equal(parse("l.plt", "IN;SP1;PU400,400;SI0.5,0.7;SP0;LBH\003;SP1;PD800,400;", FONT),
                     CS_OK);
    assert_int_equal(P.n, 1);
    expect_line(0, 10 + 22 * sx, 10, 20, 10);
    /* DT: another terminator; default size 0.19 x 0.27 cm: s = 2.7 / 21, sx = s */
    assert_int_equal(parse("l.plt", "IN;SP1;DT#;PU0,0;LBH#;", FONT), CS_OK);
    assert_int_equal(P.n, 3);
    expect_h(0, 0, 0, 2.7 / 21, 2.7 / 21, -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reads_shipped_font),
        cmocka_unit_test(test_bad_fonts_located),
        cmocka_unit_test(test_svg_text_positions),
        cmocka_unit_test(test_svg_text_without_font_or_bad_font),
        cmocka_unit_test(test_hpgl_label),
    };
    int r = cmocka_run_group_tests(tests, NULL, NULL);
    cs_path_free(&P);
    return r;
}
