/* test_input: the one input loader (host/cs_input.c). Format detection by extension (any case)
 * and by content (SVG document, bare path data, G-code, HP-GL); loading each kind of file gives
 * exactly what its own reader gives (same elements, point for point); options reach the
 * readers (--lenient, a forced format); errors keep the reader's file:line:col, and a file that
 * cannot be read is CS_ERR_IO. Run from the repository root. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "cs_gcode.h"
#include "cs_hpgl.h"
#include "cs_hershey.h"
#include "cs_input.h"
#include "cs_svgdoc.h"

static int nwarn;

static void on_warn(void *ctx, const cs_path_diag_t *w)
{
    (void)ctx;
    (void)w;
    nwarn++;
}

static cs_input_format_t det(const char *name, const char *text)
{
    return cs_input_detect(name, text, strlen(text));
}

static void test_detect_by_extension(void **state)
{
    (void)state;
    assert_int_equal(det("a.nc", ""), CS_INPUT_GCODE);
    assert_int_equal(det("dir/A.GCODE", "<svg/>"), CS_INPUT_GCODE);
    assert_int_equal(det("x.ngc", ""), CS_INPUT_GCODE);
    assert_int_equal(det("x.g", ""), CS_INPUT_GCODE);
    assert_int_equal(det("x.tap", ""), CS_INPUT_GCODE);
    assert_int_equal(det("x.svg", "G1 X1"), CS_INPUT_SVG);
    assert_int_equal(det("x.txt", "G1 X1"), CS_INPUT_SVG);
    assert_int_equal(det("x.d", ""), CS_INPUT_SVG);
    assert_int_equal(det("x.plt", "G1 X1"), CS_INPUT_HPGL);
    assert_int_equal(det("x.HPGL", ""), CS_INPUT_HPGL);
    assert_int_equal(det("x.hgl", ""), CS_INPUT_HPGL);
    /* No extension (a dot in a folder name does not count), or an unknown one: content. */
    assert_int_equal(det("dir.nc/job", "IN;PU0,0;"), CS_INPUT_HPGL);
    assert_int_equal(det("job.dat", "G1 X1"), CS_INPUT_GCODE);
    assert_int_equal(det(".nc", "M 0 0 L 1 1"), CS_INPUT_SVG);
    assert_int_equal(det(NULL, "G1 X1"), CS_INPUT_GCODE);
    assert_int_equal(det("-", "<svg/>"), CS_INPUT_SVG);
}

static void test_detect_by_content(void **state)
{
    (void)state;
    assert_int_equal(det(NULL, "  \n<?xml version=\"1.0\"?><svg/>"), CS_INPUT_SVG);
    assert_int_equal(det(NULL, "\xEF\xBB\xBF<svg/>"), CS_INPUT_SVG);
    assert_int_equal(det(NULL, "IN;SP1;PU0,0;PD100,100;"), CS_INPUT_HPGL);
    assert_int_equal(det(NULL, "IN\nSP1\n"), CS_INPUT_HPGL);
    assert_int_equal(det(NULL, "G21 G90\nG1 X1\n"), CS_INPUT_GCODE);
    assert_int_equal(det(NULL, "N10 G1 X1\n"), CS_INPUT_GCODE);
    assert_int_equal(det(NULL, "(header)\nG1 X1\n"), CS_INPUT_GCODE);
    assert_int_equal(det(NULL, "; slicer\nG1 X1\n"), CS_INPUT_GCODE);
    assert_int_equal(det(NULL, "%\nG1 X1\n%\n"), CS_INPUT_GCODE);
    assert_int_equal(det(NULL, "M3 S1000\nG1 X1\n"), CS_INPUT_GCODE);
    assert_int_equal(det(NULL, "M30\n"), CS_INPUT_GCODE);
    assert_int_equal(det(NULL, "x10 y10\n"), CS_INPUT_GCODE);
    assert_int_equal(det(NULL, "O1000\nG1 X1\n"), CS_INPUT_GCODE);
    assert_int_equal(det(NULL, "M 0 0 L 10 10"), CS_INPUT_SVG);
    assert_int_equal(det(NULL, "M0,0 L10,10"), CS_INPUT_SVG);
    assert_int_equal(det(NULL, "m10 20 l5 5z"), CS_INPUT_SVG);
    assert_int_equal(det(NULL, "M.5.5"), CS_INPUT_SVG);
    assert_int_equal(det(NULL, ""), CS_INPUT_SVG);
    assert_string_equal(cs_input_format_name(CS_INPUT_GCODE), "gcode");
    assert_string_equal(cs_input_format_name(CS_INPUT_HPGL), "hpgl");
    assert_string_equal(cs_input_format_name(CS_INPUT_SVG), "svg");
}

/* Same elements, point for point, in the same subpaths. */
static void assert_same_path(const cs_path_t *a, const cs_path_t *b)
{
    assert_int_equal(a->n, b->n);
    assert_int_equal(a->nsubpaths, b->nsubpaths);
    for (size_t i = 0; i < a->n; i++) {
        const cs_bezier_t *p = &a->elems[i].curve, *q = &b->elems[i].curve;
        assert_int_equal(p->degree, q->degree);
        assert_int_equal(p->rational, q->rational);
        for (unsigned k = 0; k <= p->degree; k++) {
            assert_int_equal(p->p[k].x, q->p[k].x);
            assert_int_equal(p->p[k].y, q->p[k].y);
            assert_int_equal(p->p[k].z, q->p[k].z);
            if (p->rational)
                assert_int_equal(p->w[k], q->w[k]);
        }
        assert_int_equal(a->elems[i].subpath, b->elems[i].subpath);
        assert_int_equal(a->elems[i].loc.line, b->elems[i].loc.line);
        assert_int_equal(a->elems[i].loc.col, b->elems[i].loc.col);
        assert_true(a->elems[i].feed_mm_s == b->elems[i].feed_mm_s);
        assert_int_equal(a->elems[i].rapid, b->elems[i].rapid);
    }
}

static char *slurp(const char *name, size_t *len)
{
    FILE *f = fopen(name, "rb");
    assert_non_null(f);
    char *b = malloc(1 << 20);
    assert_non_null(b);
    *len = fread(b, 1, 1 << 20, f);
    fclose(f);
    return b;
}

static cs_err_t load(const char *name, bool lenient, cs_path_t *p, cs_path_diag_t *d)
{
    cs_input_opts_t o;
    cs_input_opts_init(&o);
    o.lenient = lenient;
    o.warn = on_warn;
    cs_path_init(p);
    memset(d, 0, sizeof *d);
    return cs_input_load(name, &o, p, d);
}

static void test_load_gcode_same_as_reader(void **state)
{
    (void)state;
    const char *name = "tests/data/gcode/one-inch-circle.nc";
    cs_path_t a, b;
    cs_path_diag_t d;
    assert_int_equal(load(name, false, &a, &d), CS_OK);
    size_t len;
    char *buf = slurp(name, &len);
    cs_path_init(&b);
    assert_int_equal(cs_gcode_read(name, buf, len, NULL, &b, &d, NULL), CS_OK);
    assert_true(a.n > 4);
    assert_same_path(&a, &b);
    free(buf);
    cs_path_free(&a);
    cs_path_free(&b);
}

/* The stroke font cs_input uses when none is named: the shipped default if it is found from this
 * program's folder (text drawn), else none (text skipped): the reader gets the same. */
static const cs_hershey_font_t *default_font(cs_hershey_font_t *f)
{
    char path[4096];
    cs_path_diag_t d;
    if (!cs_hershey_default_path(path, sizeof path) || cs_hershey_load(path, f, &d) != CS_OK)
        return NULL;
    return f;
}

static void test_load_svg_same_as_reader(void **state)
{
    (void)state;
    const char *name = "tests/data/svg/w3c/paths-data-01-t.svg";
    cs_path_t a, b;
    cs_path_diag_t d;
    assert_int_equal(load(name, false, &a, &d), CS_OK);
    cs_svgdoc_opts_t so;
    cs_svgdoc_opts_init(&so);
    so.warn = on_warn;
    cs_hershey_font_t font;
    so.font = default_font(&font);
    cs_path_init(&b);
    assert_int_equal(cs_svgdoc_read_file(name, &so, &b, &d, NULL), CS_OK);
    assert_true(a.n > 0);
    assert_same_path(&a, &b);
    if (so.font)
        cs_hershey_free(&font);
    cs_path_free(&a);
    cs_path_free(&b);
}

static void test_load_hpgl_same_as_reader(void **state)
{
    (void)state;
    const char *name = "tests/data/hpgl/feature-exercise.plt";
    cs_path_t a, b;
    cs_path_diag_t d, d2;
    cs_err_t e = load(name, false, &a, &d);
    size_t len;
    char *buf = slurp(name, &len);
    cs_hpgl_opts_t ho;
    cs_hpgl_opts_init(&ho);
    ho.warn = on_warn;
    cs_hershey_font_t font;
    ho.font = default_font(&font);
    cs_path_init(&b);
    memset(&d2, 0, sizeof d2);
    assert_int_equal(cs_hpgl_read(name, buf, len, &ho, &b, &d2), e);
    assert_int_equal(e, CS_OK);
    assert_true(a.n > 0);
    assert_same_path(&a, &b);
    if (ho.font)
        cs_hershey_free(&font);
    free(buf);
    cs_path_free(&a);
    cs_path_free(&b);
}

static void test_unknown_extension_by_content(void **state)
{
    (void)state;
    char name[] = "/tmp/cs_test_input_XXXXXX";
    int fd = mkstemp(name);
    assert_true(fd >= 0);
    const char *text = "G21\nG1 X10 Y0 F600\nG3 X0 Y10 I-10 J0\n";
    assert_int_equal(write(fd, text, strlen(text)), (ssize_t)strlen(text));
    close(fd);
    cs_path_t a;
    cs_path_diag_t d;
    assert_int_equal(load(name, false, &a, &d), CS_OK);
    assert_true(a.n >= 2);
    assert_int_equal(a.elems[1].kind, CS_PATH_ARC);
    assert_true(a.elems[0].feed_mm_s == 10.0);
    cs_path_free(&a);
    /* The same text forced to be read as SVG path data fails where SVG says so. */
    cs_input_opts_t o;
    cs_input_opts_init(&o);
    o.format = CS_INPUT_SVG;
    cs_path_init(&a);
    assert_int_not_equal(cs_input_load(name, &o, &a, &d), CS_OK);
    assert_string_equal(d.loc.file, name);
    assert_int_equal(d.loc.line, 1);
    cs_path_free(&a);
    unlink(name);
}

static void test_lenient_and_errors_reach_the_caller(void **state)
{
    (void)state;
    const char *name = "tests/data/gcode/helical-thread-milling.nc";
    cs_path_t a;
    cs_path_diag_t d;
    nwarn = 0;
    assert_int_equal(load(name, false, &a, &d), CS_ERR_UNSUPPORTED);
    assert_string_equal(d.loc.file, name);
    assert_int_equal(d.loc.line, 2);
    assert_int_equal(d.loc.col, 9);
    cs_path_free(&a);
    assert_int_equal(load(name, true, &a, &d), CS_OK);
    assert_int_equal(nwarn, 2); /* through the loader's warning callback */
    assert_true(a.n > 10);
    cs_path_free(&a);
    assert_int_equal(load("tests/data/gcode/no-such-file.nc", false, &a, &d), CS_ERR_IO);
    assert_int_equal(d.loc.line, 0);
    cs_path_free(&a);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_detect_by_extension),
        cmocka_unit_test(test_detect_by_content),
        cmocka_unit_test(test_load_gcode_same_as_reader),
        cmocka_unit_test(test_load_svg_same_as_reader),
        cmocka_unit_test(test_load_hpgl_same_as_reader),
        cmocka_unit_test(test_unknown_extension_by_content),
        cmocka_unit_test(test_lenient_and_errors_reach_the_caller),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
