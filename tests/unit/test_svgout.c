/* test_svgout: the flattening picture (host/cs_svgout.c). The picture is read back: with expat
 * (one <polyline> per chord polyline, one dot per vertex, every vertex inside the viewBox) and
 * the curves path's data with the project's own path reader (the picture's width/height are in
 * px, so the whole document read by cs_svgdoc comes back scaled to that size; the data itself
 * is in the viewBox's millimetres): the exact curves come back as the same Béziers, to within
 * 1 LSB since coordinates are written with 6 decimals, i.e. within 5e-7 mm; rational arcs come
 * back as dense polylines whose vertices lie on the arc within 5e-7 mm of printing plus the
 * half LSB of reading them back into fixed point). */
#include <expat.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "cs_ref.h"
#include "cs_svgdoc.h"
#include "cs_svgout.h"
#include "cs_svgpath.h"

#define LSB (1.0 / 65536.0)

typedef struct {
    int polylines, circles, svg;
    char curves_d[1 << 16]; /* the d of <path id="curves"> */
    double vb[4];
    double drawing[6]; /* the transform of <g id="drawing"> */
    char legend[2048];
    bool in_text;
} pic_t;

static void XMLCALL pic_start(void *ud, const XML_Char *el, const XML_Char **atts)
{
    pic_t *p = ud;
    if (!strcmp(el, "polyline"))
        p->polylines++;
    if (!strcmp(el, "circle"))
        p->circles++;
    if (!strcmp(el, "text"))
        p->in_text = true;
    if (!strcmp(el, "path")) {
        const char *id = NULL, *d = NULL;
        for (int i = 0; atts[i]; i += 2) {
            if (!strcmp(atts[i], "id"))
                id = atts[i + 1];
            if (!strcmp(atts[i], "d"))
                d = atts[i + 1];
        }
        if (id && d && !strcmp(id, "curves"))
            snprintf(p->curves_d, sizeof p->curves_d, "%s", d);
    }
    if (!strcmp(el, "g")) {
        const char *id = NULL, *tr = NULL;
        for (int i = 0; atts[i]; i += 2) {
            if (!strcmp(atts[i], "id"))
                id = atts[i + 1];
            if (!strcmp(atts[i], "transform"))
                tr = atts[i + 1];
        }
        if (id && tr && !strcmp(id, "drawing"))
            assert_int_equal(sscanf(tr, "matrix(%lf %lf %lf %lf %lf %lf)", &p->drawing[0],
                                    &p->drawing[1], &p->drawing[2], &p->drawing[3],
                                    &p->drawing[4], &p->drawing[5]),
                             6);
    }
    if (!strcmp(el, "svg")) {
        p->svg++;
        for (int i = 0; atts[i]; i += 2)
            if (!strcmp(atts[i], "viewBox"))
                assert_int_equal(sscanf(atts[i + 1], "%lf %lf %lf %lf", &p->vb[0], &p->vb[1],
                                        &p->vb[2], &p->vb[3]),
                                 4);
    }
}

static void XMLCALL pic_end(void *ud, const XML_Char *el)
{
    pic_t *p = ud;
    if (!strcmp(el, "text")) {
        p->in_text = false;
        strncat(p->legend, "|", sizeof p->legend - strlen(p->legend) - 1);
    }
}

static void XMLCALL pic_chars(void *ud, const XML_Char *s, int len)
{
    pic_t *p = ud;
    if (p->in_text)
        strncat(p->legend, s,
                (size_t)len < sizeof p->legend - strlen(p->legend) - 1
                    ? (size_t)len
                    : sizeof p->legend - strlen(p->legend) - 1);
}

static void read_picture(const char *file, pic_t *p)
{
    memset(p, 0, sizeof *p);
    FILE *f = fopen(file, "rb");
    assert_non_null(f);
    static char buf[1 << 20];
    size_t n = fread(buf, 1, sizeof buf, f);
    fclose(f);
    XML_Parser xp = XML_ParserCreate(NULL);
    XML_SetUserData(xp, p);
    XML_SetElementHandler(xp, pic_start, pic_end);
    XML_SetCharacterDataHandler(xp, pic_chars);
    assert_int_equal(XML_Parse(xp, buf, (int)n, 1), XML_STATUS_OK);
    XML_ParserFree(xp);
    assert_int_equal(p->svg, 1);
}

static void test_picture_round_trip(void **state)
{
    (void)state;
    const char *d = "M 10 10 L 50 10 Q 70 10 70 30 C 70 50 40 60 30 40 "
                    "M 100 100 A 20 10 30 1 1 140 120 z";
    cs_path_t path;
    cs_path_init(&path);
    cs_svgpath_opts_t po;
    cs_svgpath_opts_init(&po, "t");
    cs_path_diag_t diag;
    assert_int_equal(cs_svgpath_parse(d, strlen(d), &po, &path, &diag), CS_OK);
    size_t npoly = 0;
    for (size_t i = 0; i < path.n; i++)
        if (path.elems[i].kind != CS_PATH_ARC)
            npoly++;
    /* Chords: two polylines of a few vertices. */
    cs_path_poly_t ch;
    cs_path_poly_init(&ch);
    cs_path_poly_move(&ch, 10, 10);
    cs_path_poly_line(&ch, 50, 10);
    cs_path_poly_line(&ch, 70, 30);
    cs_path_poly_move(&ch, 100, 100);
    cs_path_poly_line(&ch, 140, 120);
    cs_path_poly_line(&ch, 100, 100);
    cs_svgout_opts_t o;
    cs_svgout_opts_init(&o);
    o.title = "a <title> & more";
    o.method = "subdiv";
    o.tol_mm = 0.25;
    o.max_dev_mm = 0.125;
    char file[] = "/tmp/cs_test_svgout_XXXXXX";
    int fd = mkstemp(file);
    assert_true(fd >= 0);
    close(fd);
    assert_int_equal(cs_svgout_write(file, &path, &ch, &o, &diag), CS_OK);

    pic_t pic;
    read_picture(file, &pic);
    assert_int_equal(pic.polylines, 2);
    assert_int_equal(pic.circles, 6 + 1); /* one dot per vertex, plus the legend's */
    assert_non_null(strstr(pic.legend, "a <title> & more"));
    assert_non_null(strstr(pic.legend, "tolerance 0.25 mm"));
    assert_non_null(strstr(pic.legend, "subdiv"));
    assert_non_null(strstr(pic.legend, "0.125"));
    assert_non_null(strstr(pic.legend, "chords: 4 (6 vertices, 2 polylines)"));
    /* The drawing is y-up (the machine's frame) in a y-down picture: mirrored, x kept, and
     * every vertex, as drawn, inside the viewBox above the legend. */
    const double *m = pic.drawing;
    assert_true(m[0] == 1 && m[1] == 0 && m[2] == 0 && m[3] == -1 && m[4] == 0);
    for (size_t i = 0; i < ch.n; i++) {
        double y = m[5] - ch.pts[i].y;
        assert_true(ch.pts[i].x > pic.vb[0] && ch.pts[i].x < pic.vb[0] + pic.vb[2] &&
                    y > pic.vb[1] && y < pic.vb[1] + pic.vb[3]);
    }

    /* The curves, read back by the path reader. */
    cs_path_t back;
    cs_path_init(&back);
    assert_int_equal(cs_svgpath_parse(pic.curves_d, strlen(pic.curves_d), &po, &back, &diag),
                     CS_OK);
    size_t k = 0;
    for (size_t i = 0; i < path.n; i++) {
        const cs_bezier_t *c = &path.elems[i].curve;
        if (path.elems[i].kind != CS_PATH_ARC) {
            assert_true(k < back.n);
            const cs_bezier_t *b = &back.elems[k++].curve;
            assert_int_equal(b->degree, c->degree);
            for (unsigned j = 0; j <= c->degree; j++)
                assert_true(abs(b->p[j].x - c->p[j].x) <= 1 && abs(b->p[j].y - c->p[j].y) <= 1);
            continue;
        }
        /* An arc piece: 64 chords whose vertices are on it (dense sample of the piece). */
        for (int j = 0; j < 64; j++) {
            assert_true(k < back.n);
            const cs_bezier_t *b = &back.elems[k++].curve;
            assert_int_equal(b->degree, 1);
            cs_ref_vec_t q = cs_ref_eval(c, (j + 1) / 64.0);
            double tol = 0.5 * LSB + 5e-7;
            assert_true(fabs(b->p[1].x * LSB - q.x) <= tol && fabs(b->p[1].y * LSB - q.y) <= tol);
        }
    }
    assert_true(npoly > 0 && k == back.n);
    cs_path_free(&back);
    remove(file);
    cs_path_poly_free(&ch);
    cs_path_free(&path);
}

static void test_empty_and_errors(void **state)
{
    (void)state;
    cs_path_t path;
    cs_path_init(&path);
    char file[] = "/tmp/cs_test_svgout_XXXXXX";
    int fd = mkstemp(file);
    assert_true(fd >= 0);
    close(fd);
    cs_path_diag_t diag;
    /* Nothing to draw: reported, but the file is still a valid picture. */
    assert_int_equal(cs_svgout_write(file, &path, NULL, NULL, &diag), CS_ERR_EMPTY);
    pic_t pic;
    read_picture(file, &pic);
    assert_int_equal(pic.polylines, 0);
    remove(file);
    assert_int_equal(cs_svgout_write("/nonexistent-dir/x.svg", &path, NULL, NULL, &diag),
                     CS_ERR_IO);
    assert_string_equal(diag.loc.file, "/nonexistent-dir/x.svg");
    cs_path_free(&path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_picture_round_trip),
        cmocka_unit_test(test_empty_and_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
