/* test_grbl_gc: G-code one line at a time (host/cs_grbl_gc.c) for the Grbl front end. A program
 * fed line by line must give exactly the elements cs_gcode_read gives for the whole file (same
 * control points to the LSB, feeds, rapid flags): the modal state carried across lines (inches,
 * G91, modal G2 with its feed, G92, G5.2 blocks) is what is tested. Hand-computed positions for
 * G92 and G20/G91; a refused line leaves the state as it was; M2 ends the program. Run from the
 * repository root. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_conv.h"
#include "cs_grbl_gc.h"

#define PT_TOL (0.5 / 65536.0 + 1e-9)

/* Feeds the '\n'-separated lines of text to a fresh reader; out gets the elements. Returns the
 * number of refused lines. */
static int feed_lines(const char *text, cs_grbl_gc_t *g, cs_path_t *out)
{
    assert_int_equal(cs_grbl_gc_init(g, NULL), CS_OK);
    cs_path_init(out);
    int bad = 0;
    unsigned no = 0;
    const char *s = text;
    while (*s) {
        const char *e = strchr(s, '\n');
        size_t n = e ? (size_t)(e - s) : strlen(s);
        char line[CS_GRBL_GC_LINE_MAX];
        assert_true(n < sizeof line);
        memcpy(line, s, n);
        line[n] = '\0';
        cs_path_diag_t d;
        bool end;
        if (cs_grbl_gc_line(g, line, ++no, out, &d, &end) != CS_OK)
            bad++;
        s += n + (e != NULL);
    }
    return bad;
}

static void same_as_whole(const char *text)
{
    cs_path_t whole, lines;
    cs_path_diag_t d;
    cs_gcode_opts_t o;
    cs_gcode_opts_init(&o);
    cs_path_init(&whole);
    assert_int_equal(cs_gcode_read("t", text, strlen(text), &o, &whole, &d, NULL), CS_OK);
    cs_grbl_gc_t g;
    assert_int_equal(feed_lines(text, &g, &lines), 0);
    assert_int_equal(lines.n, whole.n);
    for (size_t k = 0; k < whole.n; k++) {
        const cs_path_elem_t *a = &whole.elems[k], *b = &lines.elems[k];
        assert_int_equal(a->curve.degree, b->curve.degree);
        assert_int_equal(a->curve.rational, b->curve.rational);
        for (int i = 0; i <= a->curve.degree; i++) {
            assert_int_equal(a->curve.p[i].x, b->curve.p[i].x);
            assert_int_equal(a->curve.p[i].y, b->curve.p[i].y);
            assert_int_equal(a->curve.p[i].z, b->curve.p[i].z);
            if (a->curve.rational)
                assert_int_equal(a->curve.w[i], b->curve.w[i]);
        }
        assert_true(fabs(a->feed_mm_s - b->feed_mm_s) < 1e-12);
        assert_int_equal(a->rapid, b->rapid);
    }
    cs_path_free(&whole);
    cs_path_free(&lines);
    cs_grbl_gc_free(&g);
}

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    static char buf[65536];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    return buf;
}

/* Inches, modal G02 with I/J, F changes, N words: the cncjs fixture. */
static void test_one_inch_circle(void **state)
{
    (void)state;
    same_as_whole(slurp("tests/data/gcode/one-inch-circle.nc"));
}

/* Each plane's arcs (modal plane across lines). */
static void test_planes(void **state)
{
    (void)state;
    same_as_whole(slurp("tests/data/gcode/arc-yz-plane.nc"));
    same_as_whole(slurp("tests/data/gcode/arc-zx-plane.nc"));
}

/* G91, G90.1, G92, G5 and a G5.2 NURBS block split over lines. */
static void test_modes_and_blocks(void **state)
{
    (void)state;
    same_as_whole("G0 X10 Y10\nG92 X0 Y0\nG1 X5 F300\nG91 G1 Y2\nY2\nG90.1 G90\n"
                  "G2 X15 Y4 I10 J4\nG5 I1 J1 P-1 Q-1 X20 Y20\n"
                  "G5.2 X20 Y20 L4 P1\nX25 Y30 P1\nX30 Y20 P1\nX35 Y25 P1\nG5.3\nG1 X0 Y0\n");
}

static void assert_end_at(const cs_path_t *p, double x, double y, double z)
{
    double e[3];
    assert_true(p->n > 0);
    cs_path_eval_mm(&p->elems[p->n - 1].curve, 1.0, e);
    assert_true(fabs(e[0] - x) <= PT_TOL);
    assert_true(fabs(e[1] - y) <= PT_TOL);
    assert_true(fabs(e[2] - z) <= PT_TOL);
}

/* G92 then a move, by hand: machine = program + offset (10 + 5 = 15); inches: 0.5 in more in
 * G91 = 12.7 mm more. */
static void test_g92_and_inches_by_hand(void **state)
{
    (void)state;
    cs_grbl_gc_t g;
    cs_path_t p;
    assert_int_equal(feed_lines("G0 X10 Y10\nG92 X0 Y0\nG1 X5 Y-2 F300", &g, &p), 0);
    assert_end_at(&p, 15, 8, 0);
    assert_true(fabs(cs_grbl_gc_work(&g, 0) - 5) < 1e-12);
    assert_true(fabs(g.off[0] - 10) < 1e-12);
    cs_path_free(&p);
    cs_grbl_gc_free(&g);
    assert_int_equal(feed_lines("G20 G91\nG1 X0.5 F10\nX0.5 Z-0.1", &g, &p), 0);
    assert_end_at(&p, 25.4, 0, -2.54);
    assert_true(fabs(p.elems[0].feed_mm_s - 10 * 25.4 / 60) < 1e-12);
    cs_path_free(&p);
    cs_grbl_gc_free(&g);
}

/* A refused line changes nothing: the next line runs from the state before it. */
static void test_refused_line(void **state)
{
    (void)state;
    cs_grbl_gc_t g;
    cs_path_t p;
    assert_int_equal(feed_lines("G1 X5 F100\nG91 G1 X1 Q\nY5", &g, &p), 1);
    assert_int_equal(p.n, 2);
    assert_end_at(&p, 5, 5, 0); /* still G90: the G91 of the refused line did not stick */
    assert_false(g.incr);
    cs_path_free(&p);
    cs_grbl_gc_free(&g);
}

/* M2 ends the program (the caller resets the modes); the diagnostic names the client's line. */
static void test_end_and_diag(void **state)
{
    (void)state;
    cs_grbl_gc_t g;
    cs_path_t p;
    cs_path_diag_t d;
    bool end;
    assert_int_equal(cs_grbl_gc_init(&g, NULL), CS_OK);
    cs_path_init(&p);
    assert_int_equal(cs_grbl_gc_line(&g, "G1 X1 F60 M2", 7, &p, &d, &end), CS_OK);
    assert_true(end);
    assert_int_not_equal(cs_grbl_gc_line(&g, "G1 X1 Y", 9, &p, &d, &end), CS_OK);
    assert_int_equal(d.loc.line, 9);
    assert_string_equal(d.loc.file, "grbl");
    assert_int_equal(d.loc.col, 7);
    cs_path_free(&p);
    cs_grbl_gc_free(&g);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_one_inch_circle),
        cmocka_unit_test(test_planes),
        cmocka_unit_test(test_modes_and_blocks),
        cmocka_unit_test(test_g92_and_inches_by_hand),
        cmocka_unit_test(test_refused_line),
        cmocka_unit_test(test_end_and_diag),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
