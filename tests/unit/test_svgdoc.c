/* test_svgdoc: SVG documents (host/cs_svgdoc.c) -> path elements. Every file in
 * tests/data/svg (resvg path tests, W3C SVG 1.1 paths-data) is read; the expected geometry is
 * worked out by hand from each file's path data and checked against what the file's own
 * description says (W3C: the blue marker squares sit on the on-curve points; "nothing should be
 * rendered"; "MoveTo is required"...). Diagnostics must point at the right line:col of the file.
 * Tolerance: a point is the exact user value rounded once to the nearest LSB, so within 0.5 LSB
 * (plus 1e-9 mm for the double transform arithmetic). Run from the repository root. */
#include <expat.h>
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
#include "cs_svgdoc.h"
#include "cs_trace.h"

#define LSB    (1.0 / 65536.0)
#define PT_TOL (0.5 * LSB + 1e-9)
/* Arc points: cs_arc_build keeps within 2 LSB of the ellipse its quantised centre and axes
 * describe; each of those is rounded once more (up to 1 LSB per coordinate): 4 LSB in all. */
#define ARC_TOL (4.0 * LSB)
#define DATA    "tests/data/svg/"

static cs_path_t P;
static cs_path_diag_t D;
static cs_svgdoc_stats_t S;
static int nwarn;
static char last_warn[600];

static void on_warn(void *ctx, const cs_path_diag_t *w)
{
    (void)ctx;
    nwarn++;
    snprintf(last_warn, sizeof last_warn, "%s:%u:%u: %s", w->loc.file, w->loc.line, w->loc.col,
             w->reason);
}

static void reset(void)
{
    cs_path_free(&P);
    cs_path_init(&P);
    memset(&D, 0, sizeof D);
    memset(&S, 0, sizeof S);
    nwarn = 0;
    last_warn[0] = '\0';
}

static cs_err_t read_file(const char *name)
{
    reset();
    cs_svgdoc_opts_t o;
    cs_svgdoc_opts_init(&o);
    o.warn = on_warn;
    return cs_svgdoc_read_file(name, &o, &P, &D, &S);
}

static cs_err_t read_text(const char *text)
{
    reset();
    cs_svgdoc_opts_t o;
    cs_svgdoc_opts_init(&o);
    o.warn = on_warn;
    return cs_svgdoc_read(text, strlen(text), "doc.svg", &o, &P, &D, &S);
}

/* A path data error handled as SVG 2 does (section 9.5.4): the read succeeds, one warning is
 * given at the place of the error (D keeps the error, so its position can be checked), and the
 * valid prefix of the path is kept. */
static void assert_path_warning(cs_err_t e)
{
    assert_int_equal(e, CS_OK);
    assert_true(nwarn >= 1);
    char at[300];
    snprintf(at, sizeof at, "%s:%u:%u: ", D.loc.file, D.loc.line, D.loc.col);
    assert_true(strncmp(last_warn, at, strlen(at)) == 0);
    assert_non_null(strstr(last_warn, "drawn up to the command before it"));
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

static bool pt_is(const cs_vec3_t *p, double x, double y)
{
    return fabs(p->x * LSB - x) <= PT_TOL && fabs(p->y * LSB - y) <= PT_TOL && p->z == 0;
}

static void expect_pt(const cs_vec3_t *p, double x, double y)
{
    if (!pt_is(p, x, y))
        fail_msg("point (%.9f, %.9f), expected (%.9f, %.9f)", p->x * LSB, p->y * LSB, x, y);
}

static const cs_vec3_t *first_pt(void)
{
    return &P.elems[0].curve.p[0];
}

static const cs_vec3_t *last_pt(void)
{
    const cs_bezier_t *c = &P.elems[P.n - 1].curve;
    return &c->p[c->degree];
}

/* Keeps only the elements that come from <path> data: a shape's elements carry the position of
 * its start tag ('<' in the file), a path's the position of a command inside its 'd'. Subpaths
 * are renumbered. Returns how many elements were dropped. */
static size_t drop_shapes(const char *file)
{
    FILE *f = fopen(file, "rb");
    assert_non_null(f);
    static char buf[1 << 16];
    size_t len = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[len] = '\0';
    size_t k = 0, dropped = 0;
    unsigned last_in = (unsigned)-1, sub = (unsigned)-1;
    for (size_t i = 0; i < P.n; i++) {
        /* Byte offset of (line, col): columns count characters (UTF-8 lead bytes). */
        unsigned line = 1, col = 1;
        size_t off = 0;
        while (off < len && (line < P.elems[i].loc.line || col < P.elems[i].loc.col)) {
            if (buf[off] == '\n') {
                line++;
                col = 1;
            } else if (((unsigned char)buf[off] & 0xC0) != 0x80 && buf[off] != '\r') {
                col++;
            }
            off++;
            while (off < len && ((unsigned char)buf[off] & 0xC0) == 0x80)
                off++;
        }
        if (buf[off] == '<') {
            dropped++;
            continue;
        }
        if (P.elems[i].subpath != last_in) {
            last_in = P.elems[i].subpath;
            sub++;
        }
        P.elems[k] = P.elems[i];
        P.elems[k++].subpath = sub;
    }
    P.n = k;
    P.nsubpaths = sub + 1;
    return dropped;
}

/* --- the resvg path tests -------------------------------------------------------------- */

typedef struct {
    const char *file;
    unsigned lines, quads, cubics; /* elements of each kind */
    bool arcs;                     /* at least one arc piece */
    unsigned subpaths;
    double x0, y0, x1, y1; /* first and last point (when there are elements) */
} resvg_case_t;

/* Worked out from each file's d attribute (see the files in tests/data/svg/resvg). */
static const resvg_case_t resvg_cases[] = {
    {"M-A-s.svg", 0, 0, 1, true, 1, 30, 40, 70, 150},
    {"M-A-t.svg", 0, 1, 0, true, 1, 30, 40, 70, 150},
    {"M-A.svg", 0, 0, 0, true, 1, 30, 40, 150, 100},
    {"M-C-S.svg", 0, 0, 2, false, 1, 30, 40, 180, 155},
    {"M-C.svg", 0, 0, 1, false, 1, 30, 40, 180, 155},
    {"M-H-H-implicit.svg", 2, 0, 0, false, 1, 30, 40, 150, 40},
    {"M-H-H.svg", 2, 0, 0, false, 1, 30, 40, 150, 40},
    {"M-H.svg", 1, 0, 0, false, 1, 30, 40, 150, 40},
    {"M-L-L-Z-rel.svg", 3, 0, 0, false, 1, 30, 40, 30, 40},
    {"M-L-L-Z.svg", 3, 0, 0, false, 1, 30, 40, 30, 40},
    {"M-L-L-implicit.svg", 2, 0, 0, false, 1, 30, 40, 100, 50},
    {"M-L-M-L.svg", 2, 0, 0, false, 2, 30, 40, 120, 140},
    {"M-L-M-Z.svg", 1, 0, 0, false, 1, 30, 40, 100, 150},
    {"M-L-M.svg", 1, 0, 0, false, 1, 30, 40, 100, 150},
    {"M-L-Z-A.svg", 3, 0, 0, true, 2, 10, 50, 150, 150},
    {"M-L-Z-L-L.svg", 5, 0, 0, false, 2, 10, 10, 120, 100},
    {"M-L.svg", 1, 0, 0, false, 1, 30, 40, 150, 160},
    {"M-M-implicit-M-implicit.svg", 2, 0, 0, false, 1, 30, 40, 150, 60},
    {"M-M-rel.svg", 0, 0, 0, false, 0, 0, 0, 0, 0},
    {"M-M.svg", 0, 0, 0, false, 0, 0, 0, 0, 0},
    {"M-Q-T-rel.svg", 0, 2, 0, false, 1, 30, 40, 160, 170},
    {"M-Q-T.svg", 0, 2, 0, false, 1, 30, 40, 160, 180},
    {"M-Q-rel-T-rel.svg", 0, 2, 0, false, 1, 30, 40, 140, 160},
    {"M-Q.svg", 0, 1, 0, false, 1, 30, 40, 180, 155},
    {"M-S-S.svg", 0, 0, 2, false, 1, 30, 40, 50, 60},
    {"M-S.svg", 0, 0, 1, false, 1, 30, 40, 180, 155},
    {"M-T-T-rel.svg", 0, 2, 0, false, 1, 30, 30, 140, 110},
    {"M-T-T.svg", 0, 2, 0, false, 1, 30, 30, 170, 30},
    {"M-T.svg", 0, 1, 0, false, 1, 30, 40, 180, 155},
    {"M-V-V-implicit.svg", 2, 0, 0, false, 1, 30, 40, 30, 150},
    {"M-V-V.svg", 2, 0, 0, false, 1, 30, 40, 30, 150},
    {"M-V.svg", 1, 0, 0, false, 1, 30, 40, 30, 150},
    {"M-Z.svg", 0, 0, 0, false, 0, 0, 0, 0, 0},
    {"M-rel-M-rel-implicit-M-rel-implicit.svg", 2, 0, 0, false, 1, 30, 40, 120, 30},
    {"M-rel-M.svg", 0, 0, 0, false, 0, 0, 0, 0, 0},
    {"M.svg", 0, 0, 0, false, 0, 0, 0, 0, 0},
    {"empty.svg", 0, 0, 0, false, 0, 0, 0, 0, 0},
};

static void test_resvg_files(void **state)
{
    (void)state;
    char name[256];
    for (size_t i = 0; i < sizeof resvg_cases / sizeof resvg_cases[0]; i++) {
        const resvg_case_t *c = &resvg_cases[i];
        snprintf(name, sizeof name, DATA "resvg/%s", c->file);
        cs_err_t e = read_file(name);
        if (e != CS_OK)
            fail_msg("%s: %d %s", c->file, e, D.reason);
        /* Each file ends with the frame <rect x=1 y=1 width=198 height=198 fill=none
         * stroke=black>: drawn as 4 lines, a subpath of its own. */
        assert_true(P.n >= 4);
        static const double fr[5][2] = {{1, 1}, {199, 1}, {199, 199}, {1, 199}, {1, 1}};
        for (size_t j = 0; j < 4; j++) {
            const cs_path_elem_t *el = &P.elems[P.n - 4 + j];
            assert_int_equal(el->kind, CS_PATH_LINE);
            assert_int_equal(el->subpath, P.nsubpaths - 1);
            expect_pt(&el->curve.p[0], fr[j][0], fr[j][1]);
            expect_pt(&el->curve.p[1], fr[j + 1][0], fr[j + 1][1]);
        }
        assert_int_equal(drop_shapes(name), 4);
        unsigned k[5] = {0, 0, 0, 0, 0};
        for (size_t j = 0; j < P.n; j++)
            k[P.elems[j].kind]++;
        if (k[CS_PATH_LINE] != c->lines || k[CS_PATH_QUAD] != c->quads ||
            k[CS_PATH_CUBIC] != c->cubics || (k[CS_PATH_ARC] > 0) != c->arcs ||
            P.nsubpaths != c->subpaths)
            fail_msg("%s: %u lines %u quads %u cubics %u arcs %u subpaths", c->file,
                     k[CS_PATH_LINE], k[CS_PATH_QUAD], k[CS_PATH_CUBIC], k[CS_PATH_ARC],
                     P.nsubpaths);
        if (P.n > 0) {
            expect_pt(first_pt(), c->x0, c->y0);
            expect_pt(last_pt(), c->x1, c->y1);
        }
        /* One <path> and one shape each, both drawn; a filled path says fills are drawn as
         * outlines (the only warning). */
        assert_int_equal(S.paths, 1);
        assert_int_equal(S.shapes, 1);
        assert_int_equal(S.ignored, 0);
        assert_true(nwarn <= 1);
        if (nwarn == 1)
            assert_non_null(strstr(last_warn, "fills are not drawn"));
    }
}

/* resvg A.svg: "MoveTo is required." The error points at the 'A' inside the attribute. */
static void test_resvg_moveto_required(void **state)
{
    (void)state;
    assert_path_warning(read_file(DATA "resvg/A.svg"));
    assert_int_equal(P.n, 4); /* nothing before the error in the path; the frame is drawn */
    /* Line 5: `    <path id="path1" fill="green" d="A 5 5 0 0 1 50 50"/>`: 'A' is column 38. */
    assert_string_equal(D.loc.file, DATA "resvg/A.svg");
    assert_int_equal(D.loc.line, 5);
    assert_int_equal(D.loc.col, 38);
    assert_non_null(strstr(D.reason, "moveto"));
}

/* --- W3C files: markers ------------------------------------------------------------------- */

typedef struct {
    double x[64], y[64];
    int n;
    bool centre; /* markers drawn centred on the point (x+2, y+2) or with their corner on it */
} markers_t;

static void XMLCALL marker_start(void *ud, const XML_Char *el, const XML_Char **atts)
{
    markers_t *m = ud;
    if (strcmp(el, "rect") != 0)
        return;
    const char *x = NULL, *y = NULL, *w = NULL, *h = NULL;
    for (int i = 0; atts[i]; i += 2) {
        if (!strcmp(atts[i], "x"))
            x = atts[i + 1];
        else if (!strcmp(atts[i], "y"))
            y = atts[i + 1];
        else if (!strcmp(atts[i], "width"))
            w = atts[i + 1];
        else if (!strcmp(atts[i], "height"))
            h = atts[i + 1];
    }
    if (x && y && w && h && !strcmp(w, "4") && !strcmp(h, "4") && m->n < 64) {
        double off = m->centre ? 2.0 : 0.0;
        m->x[m->n] = atof(x) + off;
        m->y[m->n] = atof(y) + off;
        m->n++;
    }
}

/* The 4x4 marker squares of a W3C test file. */
static void read_markers(const char *file, bool centre, markers_t *m)
{
    memset(m, 0, sizeof *m);
    m->centre = centre;
    FILE *f = fopen(file, "rb");
    assert_non_null(f);
    static char buf[1 << 16];
    size_t n = fread(buf, 1, sizeof buf, f);
    fclose(f);
    XML_Parser xp = XML_ParserCreate(NULL);
    XML_SetUserData(xp, m);
    XML_SetElementHandler(xp, marker_start, NULL);
    assert_int_equal(XML_Parse(xp, buf, (int)n, 1), XML_STATUS_OK);
    XML_ParserFree(xp);
    assert_true(m->n > 0);
}

static bool is_marker(const markers_t *m, const cs_vec3_t *p)
{
    for (int i = 0; i < m->n; i++)
        if (pt_is(p, m->x[i], m->y[i]))
            return true;
    return false;
}

/* On-curve points: every element's first and last control point. */
static bool is_on_curve(const cs_path_t *p, double x, double y)
{
    for (size_t i = 0; i < p->n; i++) {
        const cs_bezier_t *c = &p->elems[i].curve;
        if (pt_is(&c->p[0], x, y) || pt_is(&c->p[c->degree], x, y))
            return true;
    }
    return false;
}

/* paths-data-01: "On-curve control points (i.e., the curve position) are marked by small blue
 * squares": the set of end points equals the set of marker centres. */
static void test_w3c_01_cubics(void **state)
{
    (void)state;
    const char *file = DATA "w3c/paths-data-01-t.svg";
    assert_int_equal(read_file(file), CS_OK);
    markers_t m;
    read_markers(file, true, &m);
    /* Every 4x4 marker square (filled, not stroked) is drawn as its outline: a closed
     * 4-line subpath from its corner (x, y) = centre - (2, 2), clockwise on the page. */
    for (int i = 0; i < m.n; i++) {
        bool found = false;
        for (size_t j = 0; j + 3 < P.n && !found; j++) {
            const cs_path_elem_t *el = &P.elems[j];
            if (el->kind != CS_PATH_LINE || !pt_is(&el->curve.p[0], m.x[i] - 2, m.y[i] - 2))
                continue;
            found = pt_is(&el[0].curve.p[1], m.x[i] + 2, m.y[i] - 2) &&
                    pt_is(&el[1].curve.p[1], m.x[i] + 2, m.y[i] + 2) &&
                    pt_is(&el[2].curve.p[1], m.x[i] - 2, m.y[i] + 2) &&
                    pt_is(&el[3].curve.p[1], m.x[i] - 2, m.y[i] - 2) &&
                    el[3].subpath == el[0].subpath;
        }
        if (!found)
            fail_msg("marker (%g, %g) is not drawn as a square", m.x[i], m.y[i]);
    }
    assert_true(drop_shapes(file) >= 4 * (size_t)m.n);
    assert_int_equal(S.paths, 8);
    for (size_t i = 0; i < P.n; i++) {
        const cs_bezier_t *c = &P.elems[i].curve;
        assert_true(P.elems[i].kind == CS_PATH_CUBIC || P.elems[i].kind == CS_PATH_LINE);
        if (!is_marker(&m, &c->p[0]) || !is_marker(&m, &c->p[c->degree]))
            fail_msg("element %zu (%u:%u): an end point has no marker", i, P.elems[i].loc.line,
                     P.elems[i].loc.col);
    }
    for (int i = 0; i < m.n; i++)
        if (!is_on_curve(&P, m.x[i], m.y[i]))
            fail_msg("marker (%g, %g) is on no curve", m.x[i], m.y[i]);
    /* 8 paths; "X" has 2 subpaths (M ... m ...): 9 subpaths. The circle (M c s s s z) is 4
     * cubics ending where it started, so its z adds nothing. */
    assert_int_equal(P.nsubpaths, 9);
}

/* paths-data-02 (Q, q, T, t): every on-curve point is marked; one square of the "M, Q, T, Q, z"
 * triangle, at (208, 208), marks no curve point (a quirk of the test file, checked by hand:
 * the triangle's points are (208,168), (308,168), (258,118)). */
static void test_w3c_02_quadratics(void **state)
{
    (void)state;
    const char *file = DATA "w3c/paths-data-02-t.svg";
    assert_int_equal(read_file(file), CS_OK);
    drop_shapes(file);
    markers_t m;
    read_markers(file, true, &m);
    for (size_t i = 0; i < P.n; i++) {
        const cs_bezier_t *c = &P.elems[i].curve;
        assert_true(P.elems[i].kind == CS_PATH_QUAD || P.elems[i].kind == CS_PATH_LINE);
        if (!is_marker(&m, &c->p[0]) || !is_marker(&m, &c->p[c->degree]))
            fail_msg("element %zu (%u:%u): an end point has no marker", i, P.elems[i].loc.line,
                     P.elems[i].loc.col);
    }
    int off = 0;
    for (int i = 0; i < m.n; i++)
        if (!is_on_curve(&P, m.x[i], m.y[i])) {
            off++;
            assert_true(m.x[i] == 208 && m.y[i] == 208);
        }
    assert_int_equal(off, 1);
}

/* paths-data-12: "multiple coord sets to build a polybezier, and implicit values for initial
 * S": the first path's markers are its on-curve points; the second path's markers (drawn with
 * their corner on the point) are all its control points, including the implicit ones: the first
 * S's control point "coincident with the current point" and the reflected one (200, 300). */
static void test_w3c_12_polybezier(void **state)
{
    (void)state;
    const char *file = DATA "w3c/paths-data-12-t.svg";
    assert_int_equal(read_file(file), CS_OK);
    drop_shapes(file);
    markers_t m;
    read_markers(file, false, &m);
    assert_int_equal(P.n, 4);
    assert_int_equal(P.nsubpaths, 2);
    for (size_t i = 0; i < 2; i++) {
        assert_true(is_marker(&m, &P.elems[i].curve.p[0]));
        assert_true(is_marker(&m, &P.elems[i].curve.p[3]));
    }
    for (size_t i = 2; i < 4; i++)
        for (int k = 0; k < 4; k++)
            if (!is_marker(&m, &P.elems[i].curve.p[k]))
                fail_msg("path 2, cubic %zu, control point %d has no marker", i - 2, k);
    expect_pt(&P.elems[2].curve.p[1], 100, 250); /* = current point */
    expect_pt(&P.elems[3].curve.p[1], 200, 300); /* reflection of (200,200) about (200,250) */
    /* Every marker of the second path's area is used. */
    for (int i = 0; i < m.n; i++) {
        bool used = false;
        for (size_t e = 0; e < P.n; e++)
            for (int k = 0; k < 4; k++)
                used = used || pt_is(&P.elems[e].curve.p[k], m.x[i], m.y[i]);
        if (!used)
            fail_msg("marker (%g, %g) unused", m.x[i], m.y[i]);
    }
}

/* paths-data-14: "If the first command is 'm' it should be taken as an absolute moveto, plus
 * implicit lineto", inside <g transform="scale(1.8)">; "two concentric triangles" on the left
 * (relative data), another pair on the right (absolute data). Vertices worked out from the
 * data by hand. The left inner triangle does not close in the file's own numbers
 * (38.97114 * 2 != 77.91228: it ends 0.03 user units right of its start), so its 'z' adds a
 * 0.03 * 1.8 = 0.054 mm closing line; every other subpath ends on its start and 'z' adds nothing.
 */
static void test_w3c_14_initial_relative_moveto(void **state)
{
    (void)state;
    assert_int_equal(read_file(DATA "w3c/paths-data-14-t.svg"), CS_OK);
    assert_int_equal(drop_shapes(DATA "w3c/paths-data-14-t.svg"), 4); /* the test frame */
    static const double lines[13][5] = {
        /* subpath, x0, y0, x1, y1 (user units) */
        {0, 62, 56, 113.96152, 146},
        {0, 113.96152, 146, 10.03848, 146},
        {0, 10.03848, 146, 62, 56},
        {1, 62, 71, 100.97114, 138.5},
        {1, 100.97114, 138.5, 23.05886, 138.5},
        {1, 23.05886, 138.5, 62.03, 71},
        {1, 62.03, 71, 62, 71},
        {2, 177, 56, 228.96152, 146},
        {2, 228.96152, 146, 125.03848, 146},
        {2, 125.03848, 146, 177, 56},
        {3, 177, 71, 215.97114, 138.5},
        {3, 215.97114, 138.5, 138.02886, 138.5},
        {3, 138.02886, 138.5, 177, 71},
    };
    const double k = 1.8;
    assert_int_equal(P.n, 13);
    assert_int_equal(P.nsubpaths, 4);
    for (size_t i = 0; i < 13; i++) {
        assert_int_equal(P.elems[i].kind, CS_PATH_LINE);
        assert_int_equal(P.elems[i].subpath, (unsigned)lines[i][0]);
        expect_pt(&P.elems[i].curve.p[0], lines[i][1] * k, lines[i][2] * k);
        expect_pt(&P.elems[i].curve.p[1], lines[i][3] * k, lines[i][4] * k);
    }
    /* Concentric: both left triangles' vertices average to x = 62 (to the 0.01 of the data's
     * imprecision), y = 116; both right ones to (177, 116). */
    for (unsigned sp = 0; sp < 4; sp++) {
        double cx = 0, cy = 0;
        for (size_t i = 0, n = 0; i < 13 && n < 3; i++)
            if (P.elems[i].subpath == sp) {
                cx += P.elems[i].curve.p[0].x * LSB / 3;
                cy += P.elems[i].curve.p[0].y * LSB / 3;
                n++;
            }
        assert_true(fabs(cx - (sp < 2 ? 62 : 177) * k) < 0.011 * k);
        assert_true(fabs(cy - 116 * k) <= PT_TOL);
    }
}

/* --- positions in the file ---------------------------------------------------------------- */

static void test_error_positions(void **state)
{
    (void)state;
    /* Attribute on its own line, after a character reference: the error is at the '&' of
     * "&#x41;" (decoded 'A'), line 4 column 14. */
    const char *doc1 = "<svg xmlns=\"http://www.w3.org/2000/svg\">\n"
                       "  <title>\xc3\xa9t\xc3\xa9</title><path\n"
                       "     d=\"M 10 10\n"
                       "        L 20 &#x41; 30\"/>\n"
                       "</svg>\n";
    assert_path_warning(read_text(doc1));
    assert_string_equal(D.loc.file, "doc.svg");
    assert_int_equal(D.loc.line, 4);
    assert_int_equal(D.loc.col, 14);
    assert_non_null(strstr(D.reason, "'A'"));
    /* Columns count characters: two 2-byte characters before the attribute count as two. */
    const char *doc2 = "<svg><path id='\xc3\xa9\xc3\xa9' d='M 0 0 L x'/></svg>";
    assert_path_warning(read_text(doc2));
    assert_int_equal(D.loc.line, 1);
    /* <svg><path id='éé' d='M 0 0 L x'/>: 'x' is character 31. */
    assert_int_equal(D.loc.col, 31);
    /* d written before another attribute, single quotes, entity &amp; elsewhere. */
    const char *doc3 = "<svg>\n<path d='M 0 0 L 1 1 @' id='a&amp;b'/></svg>";
    assert_path_warning(read_text(doc3));
    assert_int_equal(D.loc.line, 2);
    assert_int_equal(D.loc.col, 22);
    /* Out of range in a document: at the number, as a range error. */
    const char *doc4 = "<svg>\n  <path d=\"M 0 0 L 5000 0\"/>\n</svg>";
    assert_int_equal(read_text(doc4), CS_ERR_RANGE);
    assert_int_equal(D.loc.line, 2);
    assert_int_equal(D.loc.col, 20);
    /* XML errors: expat's position, "XML error". */
    const char *doc5 = "<svg>\n<path d='M0 0 L 1 1'>\n</svg>";
    assert_int_equal(read_text(doc5), CS_ERR_PARSE);
    assert_int_equal(D.loc.line, 3);
    assert_non_null(strstr(D.reason, "XML error"));
    /* Elements keep their own position: the second path's L on line 3. */
    const char *doc6 = "<svg>\n<path d='M0 0 L1 1'/>\n<path d='M5 5\nL6 6'/></svg>";
    assert_int_equal(read_text(doc6), CS_OK);
    assert_int_equal(P.n, 2);
    assert_int_equal(P.elems[0].loc.line, 2);
    assert_int_equal(P.elems[0].loc.col, 15);
    assert_int_equal(P.elems[1].loc.line, 4);
    assert_int_equal(P.elems[1].loc.col, 1);
    assert_int_equal(P.elems[1].subpath, 1);
}

/* --- transforms ----------------------------------------------------------------------------- */

static void test_transforms(void **state)
{
    (void)state;
    assert_int_equal(read_text("<svg><g transform='translate(10,20)'>"
                               "<path transform='scale(2)' d='M1 1 L2 3'/></g>"
                               "<path d='M1 1 L2 2'/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 2);
    expect_pt(&P.elems[0].curve.p[0], 12, 22);
    expect_pt(&P.elems[0].curve.p[1], 14, 26);
    expect_pt(&P.elems[1].curve.p[0], 1, 1); /* outside the group: untouched */
    /* rotate(90 10 10): (20, 10) -> (10, 20). */
    assert_int_equal(read_text("<svg><path transform='rotate(90 10 10)' d='M20 10 L10 10'/></svg>"),
                     CS_OK);
    expect_pt(&P.elems[0].curve.p[0], 10, 20);
    expect_pt(&P.elems[0].curve.p[1], 10, 10);
    /* skewX(45): x' = x + y; skewY(45): y' = y + x; matrix(1 2 3 4 5 6): (1,1) -> (9, 12). */
    assert_int_equal(read_text("<svg><path transform='skewX(45)' d='M0 10 L0 0'/>"
                               "<path transform='skewY(45)' d='M10 0 L0 0'/>"
                               "<path transform='matrix(1 2 3 4 5 6)' d='M1 1 L0 0'/></svg>"),
                     CS_OK);
    expect_pt(&P.elems[0].curve.p[0], 10, 10);
    expect_pt(&P.elems[1].curve.p[0], 10, 10);
    expect_pt(&P.elems[2].curve.p[0], 9, 12);
    expect_pt(&P.elems[2].curve.p[1], 5, 6);
    /* A list applies right to left: translate(5) scale(2): (1,1) -> (2,2) -> (7,2). Commas,
     * no separator between transforms, scale with one argument. */
    assert_int_equal(read_text("<svg><path transform=' translate(5) ,scale(2)rotate(0)' "
                               "d='M1 1 L0 0'/></svg>"),
                     CS_OK);
    expect_pt(&P.elems[0].curve.p[0], 7, 2);
    /* An arc under a transform stays on the transformed circle: circle r=10 about (0,0) under
     * scale(2) translate... every piece's ends at radius 20 from (100, 100). */
    assert_int_equal(read_text("<svg><g transform='translate(100 100)'><path transform='scale(2)' "
                               "d='M10 0 A10 10 0 0 1 -10 0'/></g></svg>"),
                     CS_OK);
    assert_true(P.n >= 2);
    expect_pt(&P.elems[0].curve.p[0], 120, 100);
    expect_pt(&P.elems[P.n - 1].curve.p[2], 80, 100);
    for (size_t i = 0; i < P.n; i++) {
        const cs_vec3_t *q = &P.elems[i].curve.p[2];
        assert_true(fabs(hypot(q->x * LSB - 100, q->y * LSB - 100) - 20) < 4 * LSB);
    }
    /* Errors inside the transform attribute point into it. */
    assert_int_equal(read_text("<svg><path transform='scale(2' d='M0 0 L1 1'/></svg>"),
                     CS_ERR_PARSE);
    assert_int_equal(D.loc.col, 30); /* just past "scale(2" (characters 23..29) */
    assert_non_null(strstr(D.reason, "transform"));
    assert_int_equal(read_text("<svg><path transform='scale(2) foo(1)' d='M0 0'/></svg>"),
                     CS_ERR_PARSE);
    assert_int_equal(D.loc.col, 32);
    assert_int_equal(read_text("<svg><path transform='rotate(1 2)' d='M0 0'/></svg>"),
                     CS_ERR_PARSE);
    /* Direct use of the transform parser. */
    cs_path_affine_t m;
    size_t bad = 0;
    const char *why = NULL;
    assert_int_equal(cs_svgdoc_parse_transform("", 0, &m, &bad, &why), CS_OK);
    assert_true(cs_path_affine_is_identity(&m));
    assert_int_equal(cs_svgdoc_parse_transform("matrix(1,2,3,4,5)", 17, &m, &bad, &why),
                     CS_ERR_PARSE);
    assert_int_equal(bad, 16);
}

/* --- what is read and what is not -------------------------------------------------------- */

static void test_skipped_content(void **state)
{
    (void)state;
    /* Paths in <defs> are not drawn where they stand; shapes without a size draw nothing; a path
     * without d draws nothing; foreign-namespace elements are ignored; svg-prefixed elements
     * are read; the drawn path is filled (the default paint): said once. */
    const char *doc = "<svg xmlns='http://www.w3.org/2000/svg' xmlns:x='urn:x'>"
                      "<defs><path d='M0 0 L1 1'/></defs>"
                      "<rect/><rect/><circle/>"
                      "<path/>"
                      "<x:path d='M0 0 L9 9'/>"
                      "<path d='M0 0 L2 2'/>"
                      "</svg>";
    assert_int_equal(read_text(doc), CS_OK);
    assert_int_equal(P.n, 1);
    expect_pt(&P.elems[0].curve.p[1], 2, 2);
    assert_int_equal(S.paths, 3); /* defs path, empty path, drawn path */
    assert_int_equal(S.shapes, 3);
    assert_int_equal(nwarn, 1); /* fill (a <defs> path is silently drawn only through <use>) */
    assert_non_null(strstr(last_warn, "fills are not drawn"));
    assert_int_equal(S.ignored, 1);
    assert_int_equal(read_text("<s:svg xmlns:s='http://www.w3.org/2000/svg'>"
                               "<s:path d='M0 0 L1 1'/></s:svg>"),
                     CS_OK);
    assert_int_equal(P.n, 1);
    /* Bare path data (no '<'): read as a 'd' value, with a UTF-8 BOM allowed. */
    assert_int_equal(read_text("\xef\xbb\xbf M0 0 L3 4"), CS_OK);
    assert_int_equal(P.n, 1);
    expect_pt(&P.elems[0].curve.p[1], 3, 4);
    assert_int_equal(read_text("M0 0 L3 ?"), CS_ERR_PARSE);
    assert_int_equal(D.loc.col, 9);
    /* A missing file is an I/O error naming it. */
    assert_int_equal(read_file(DATA "no-such-file.svg"), CS_ERR_IO);
    assert_string_equal(D.loc.file, DATA "no-such-file.svg");
}

/* --- basic shapes ----------------------------------------------------------------------------- */

/* Distance from (px, py) to the ellipse (cx, cy, rx, ry) (axis-aligned), in double: the best of
 * 720 parameters, refined by golden section. */
static double ellipse_dist(double px, double py, double cx, double cy, double rx, double ry)
{
    double best = HUGE_VAL, bt = 0.0;
    for (int i = 0; i < 720; i++) {
        double t = i * (2 * M_PI / 720);
        double d = hypot(cx + rx * cos(t) - px, cy + ry * sin(t) - py);
        if (d < best) {
            best = d;
            bt = t;
        }
    }
    double a = bt - 2 * M_PI / 720, b = bt + 2 * M_PI / 720, g = (sqrt(5.0) - 1) / 2;
    for (int i = 0; i < 80; i++) {
        double t1 = b - g * (b - a), t2 = a + g * (b - a);
        double d1 = hypot(cx + rx * cos(t1) - px, cy + ry * sin(t1) - py);
        double d2 = hypot(cx + rx * cos(t2) - px, cy + ry * sin(t2) - py);
        if (d1 < d2)
            b = t2;
        else
            a = t1;
    }
    double t = (a + b) / 2, d = hypot(cx + rx * cos(t) - px, cy + ry * sin(t) - py);
    return d < best ? d : best;
}

/* Distance from (px, py) to the outline of the rounded rectangle (x, y, w, h, rx, ry). */
static double rrect_dist(double px, double py, double x, double y, double w, double h, double rx,
                         double ry)
{
    double best = HUGE_VAL;
    /* The four straight sides (between the corners). */
    double sx[4][4] = {{x + rx, y, x + w - rx, y},
                       {x + w, y + ry, x + w, y + h - ry},
                       {x + rx, y + h, x + w - rx, y + h},
                       {x, y + ry, x, y + h - ry}};
    for (int i = 0; i < 4; i++) {
        cs_ref_vec_t p = {px, py, 0}, a = {sx[i][0], sx[i][1], 0}, b = {sx[i][2], sx[i][3], 0};
        double d = cs_ref_dist_point_segment(p, a, b);
        best = d < best ? d : best;
    }
    /* The corners: the quarter of each corner ellipse facing out. */
    double cc[4][2] = {
        {x + rx, y + ry}, {x + w - rx, y + ry}, {x + w - rx, y + h - ry}, {x + rx, y + h - ry}};
    for (int i = 0; i < 4; i++) {
        bool right = i == 1 || i == 2, below = i >= 2;
        if ((px >= cc[i][0]) == right && (py >= cc[i][1]) == below) {
            double d = ellipse_dist(px, py, cc[i][0], cc[i][1], rx, ry);
            best = d < best ? d : best;
        }
    }
    return best;
}

/* Every element samples (33 per element) within tol of the outline `dist` describes, the
 * elements chained end to start in one subpath that closes. */
static void expect_closed_outline(double (*dist)(double, double, const double *), const double *a,
                                  double tol)
{
    assert_true(P.n > 0);
    for (size_t i = 0; i < P.n; i++) {
        assert_int_equal(P.elems[i].subpath, P.elems[0].subpath);
        const cs_bezier_t *c = &P.elems[i].curve;
        if (i + 1 < P.n) {
            const cs_vec3_t *e = &c->p[c->degree], *n = &P.elems[i + 1].curve.p[0];
            assert_true(e->x == n->x && e->y == n->y);
        }
        for (int k = 0; k <= 32; k++) {
            cs_ref_vec_t q = cs_ref_eval(c, k / 32.0);
            double d = dist(q.x, q.y, a);
            if (d > tol)
                fail_msg("element %zu at t=%g: (%.9f, %.9f) is %.3g mm off the outline", i,
                         k / 32.0, q.x, q.y, d);
        }
    }
    const cs_bezier_t *l = &P.elems[P.n - 1].curve;
    assert_true(l->p[l->degree].x == first_pt()->x && l->p[l->degree].y == first_pt()->y);
}

static double rrect_fn(double x, double y, const double *a)
{
    return rrect_dist(x, y, a[0], a[1], a[2], a[3], a[4], a[5]);
}

static double ellipse_fn(double x, double y, const double *a)
{
    return ellipse_dist(x, y, a[0], a[1], a[2], a[3]);
}

static void test_rect(void **state)
{
    (void)state;
    /* Plain: 4 lines clockwise on the page from (x, y). Stroked, not filled: no warning. */
    assert_int_equal(read_text("<svg><rect x='10' y='20' width='30' height='40' stroke='black' "
                               "fill='none'/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 4);
    static const double v[5][2] = {{10, 20}, {40, 20}, {40, 60}, {10, 60}, {10, 20}};
    for (size_t i = 0; i < 4; i++) {
        assert_int_equal(P.elems[i].kind, CS_PATH_LINE);
        expect_pt(&P.elems[i].curve.p[0], v[i][0], v[i][1]);
        expect_pt(&P.elems[i].curve.p[1], v[i + 1][0], v[i + 1][1]);
    }
    assert_int_equal(S.shapes, 1);
    assert_int_equal(nwarn, 0);
    /* Rounded, rx only: ry = rx ("auto"); 4 sides and 4 quarter-circle corners. */
    assert_int_equal(read_text("<svg><rect x='5' y='7' width='100' height='50' rx='10'/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 8);
    const double a1[6] = {5, 7, 100, 50, 10, 10};
    expect_closed_outline(rrect_fn, a1, ARC_TOL);
    expect_pt(first_pt(), 15, 7);
    assert_int_equal(nwarn, 1); /* filled (the default), drawn as its outline: said once */
    /* ry only, and different radii. */
    assert_int_equal(read_text("<svg><rect width='40' height='30' ry='6'/>"
                               "<rect x='50' width='40' height='30' rx='8' ry='3'/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 16);
    assert_int_equal(nwarn, 1);
    size_t n = P.n;
    P.n = 8;
    const double a2[6] = {0, 0, 40, 30, 6, 6};
    expect_closed_outline(rrect_fn, a2, ARC_TOL);
    memmove(P.elems, P.elems + 8, 8 * sizeof *P.elems);
    P.n = n - 8;
    const double a3[6] = {50, 0, 40, 30, 8, 3};
    expect_closed_outline(rrect_fn, a3, ARC_TOL);
    /* Radii clamped to half the width / height: rx 15 -> 10, so no top and bottom sides
     * (2 sides + 4 corners); ry 30 alone: rx = ry = 30 first, then clamped to 20 and 5: the
     * ellipse inscribed in the rectangle (4 corners, no sides). */
    assert_int_equal(read_text("<svg><rect width='20' height='10' rx='15' ry='3'/></svg>"), CS_OK);
    assert_int_equal(P.n, 6);
    const double a4[6] = {0, 0, 20, 10, 10, 3};
    expect_closed_outline(rrect_fn, a4, ARC_TOL);
    assert_int_equal(read_text("<svg><rect width='40' height='10' ry='30'/></svg>"), CS_OK);
    assert_int_equal(P.n, 4);
    const double a5[6] = {0, 0, 40, 10, 20, 5};
    expect_closed_outline(rrect_fn, a5, ARC_TOL);
    /* Zero width or height: nothing; negative: an error at the value. */
    assert_int_equal(read_text("<svg><rect width='0' height='10'/><rect width='5'/></svg>"), CS_OK);
    assert_int_equal(P.n, 0);
    assert_int_equal(read_text("<svg>\n<rect width='-5' height='1'/></svg>"), CS_ERR_PARSE);
    assert_int_equal(D.loc.line, 2);
    assert_int_equal(D.loc.col, 14);
    assert_non_null(strstr(D.reason, "width"));
    assert_int_equal(read_text("<svg><rect width='5' height='1' rx='-1'/></svg>"), CS_ERR_PARSE);
    assert_int_equal(read_text("<svg><rect width='5x' height='1'/></svg>"), CS_ERR_PARSE);
    assert_int_equal(D.loc.col, 20); /* at the unit */
    assert_int_equal(read_text("<svg><rect width='5em' height='1'/></svg>"), CS_ERR_PARSE);
}

static void test_circle_ellipse(void **state)
{
    (void)state;
    /* Circle: 4 quarter pieces from (cx + r, cy), in the positive angle direction (towards +y),
     * through (cx, cy + r) after the first quarter. */
    assert_int_equal(read_text("<svg><circle cx='50' cy='40' r='20'/></svg>"), CS_OK);
    assert_int_equal(P.n, 4);
    for (size_t i = 0; i < 4; i++)
        assert_int_equal(P.elems[i].kind, CS_PATH_ARC);
    expect_pt(first_pt(), 70, 40);
    assert_true(fabs(P.elems[0].curve.p[2].x * LSB - 50) <= ARC_TOL + PT_TOL);
    assert_true(fabs(P.elems[0].curve.p[2].y * LSB - 60) <= ARC_TOL + PT_TOL);
    const double c1[4] = {50, 40, 20, 20};
    expect_closed_outline(ellipse_fn, c1, ARC_TOL);
    /* Ellipse; one radius alone stands for both; zero draws nothing. */
    assert_int_equal(read_text("<svg><ellipse cx='100' cy='50' rx='30' ry='10'/></svg>"), CS_OK);
    assert_int_equal(P.n, 4);
    expect_pt(first_pt(), 130, 50);
    const double e1[4] = {100, 50, 30, 10};
    expect_closed_outline(ellipse_fn, e1, ARC_TOL);
    assert_int_equal(read_text("<svg><ellipse cx='1' cy='2' ry='3'/></svg>"), CS_OK);
    const double e2[4] = {1, 2, 3, 3};
    expect_closed_outline(ellipse_fn, e2, ARC_TOL);
    assert_int_equal(read_text("<svg><circle r='0'/><circle cx='5'/><ellipse rx='0' ry='4'/>"
                               "</svg>"),
                     CS_OK);
    assert_int_equal(P.n, 0);
    assert_int_equal(read_text("<svg><circle r='-2'/></svg>"), CS_ERR_PARSE);
    assert_int_equal(D.loc.col, 17);
    /* A circle leaving the +/-4096 mm range: a range error at the element. */
    assert_int_equal(read_text("<svg>\n  <circle cx='4000' r='100'/></svg>"), CS_ERR_RANGE);
    assert_int_equal(D.loc.line, 2);
    assert_int_equal(D.loc.col, 3);
}

static void test_line_poly(void **state)
{
    (void)state;
    assert_int_equal(read_text("<svg><line x1='1' y1='2' x2='3' y2='4' stroke='black'/>"
                               "<line x1='9' y1='9' x2='8' y2='8'/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 1); /* the second one has no stroke: a line has nothing to fill */
    expect_pt(&P.elems[0].curve.p[0], 1, 2);
    expect_pt(&P.elems[0].curve.p[1], 3, 4);
    assert_int_equal(S.ignored, 1);
    assert_int_equal(nwarn, 0);
    /* Polyline open, polygon closed; numbers in every form. */
    assert_int_equal(read_text("<svg fill='none' stroke='red'>"
                               "<polyline points='0,0 10,0 10,10'/>"
                               "<polygon points=' 1e1,-2 +3 .5,7-1 '/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 5);
    assert_int_equal(P.nsubpaths, 2);
    expect_pt(&P.elems[1].curve.p[0], 10, 0);
    expect_pt(&P.elems[1].curve.p[1], 10, 10);
    static const double g[4][2] = {{10, -2}, {3, 0.5}, {7, -1}, {10, -2}};
    for (size_t i = 0; i < 3; i++) {
        expect_pt(&P.elems[2 + i].curve.p[0], g[i][0], g[i][1]);
        expect_pt(&P.elems[2 + i].curve.p[1], g[i + 1][0], g[i + 1][1]);
        assert_int_equal(P.elems[2 + i].subpath, 1);
    }
    /* One point draws nothing. */
    assert_int_equal(read_text("<svg stroke='red'><polyline points='5 5'/></svg>"), CS_OK);
    assert_int_equal(P.n, 0);
    /* An odd number of coordinates: at the end of the list (the closing quote, column 28). */
    assert_path_warning(read_text("<svg><polygon points='1 2 3'/></svg>"));
    assert_int_equal(D.loc.line, 1);
    assert_int_equal(D.loc.col, 28);
    /* Path commands are not allowed in a points list: at the 'L' (column 28). */
    assert_path_warning(read_text("<svg><polyline points='1 2 L 3 4'/></svg>"));
    assert_int_equal(D.loc.col, 28);
}

/* Every transform on a circle: each traced point, mapped back by the inverse transform
 * (computed here in double), lies on the original circle, to the arc tolerance stretched by the
 * inverse's largest singular value. */
static void test_shape_transforms(void **state)
{
    (void)state;
    static const struct {
        const char *t;
        double m[6];
    } cases[] = {
        {"matrix(1 2 3 4 5 6)", {1, 2, 3, 4, 5, 6}}, {"translate(5 6)", {1, 0, 0, 1, 5, 6}},
        {"translate(7)", {1, 0, 0, 1, 7, 0}},        {"scale(2 3)", {2, 0, 0, 3, 0, 0}},
        {"scale(-1.5)", {-1.5, 0, 0, -1.5, 0, 0}},   {"rotate(30)", {0, 0, 0, 0, 0, 0}},
        {"rotate(30 10 20)", {0, 0, 0, 0, 0, 0}},    {"skewX(20)", {1, 0, 0, 1, 0, 0}},
        {"skewY(-15)", {1, 0, 0, 1, 0, 0}},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        double m[6];
        memcpy(m, cases[i].m, sizeof m);
        double r = 30 * M_PI / 180;
        if (i == 5 || i == 6) {
            m[0] = cos(r);
            m[1] = sin(r);
            m[2] = -sin(r);
            m[3] = cos(r);
            if (i == 6) { /* about (10, 20) */
                m[4] = 10 - m[0] * 10 - m[2] * 20;
                m[5] = 20 - m[1] * 10 - m[3] * 20;
            }
        } else if (i == 7) {
            m[2] = tan(20 * M_PI / 180);
        } else if (i == 8) {
            m[1] = tan(-15 * M_PI / 180);
        }
        char doc[256];
        snprintf(doc, sizeof doc,
                 "<svg><g transform='translate(100 100)'><circle cx='10' cy='20' r='5' "
                 "transform='%s'/></g></svg>",
                 cases[i].t);
        if (read_text(doc) != CS_OK)
            fail_msg("%s: %s", cases[i].t, D.reason);
        assert_int_equal(P.n, 4);
        double det = m[0] * m[3] - m[1] * m[2];
        double ia = m[3] / det, ib = -m[1] / det, ic = -m[2] / det, id = m[0] / det;
        /* Largest singular value of the inverse's linear part. */
        double s1 = ia * ia + ib * ib + ic * ic + id * id;
        double s2 = sqrt(s1 * s1 - 4 * (ia * id - ib * ic) * (ia * id - ib * ic));
        double norm = sqrt((s1 + s2) / 2);
        for (size_t e = 0; e < P.n; e++)
            for (int k = 0; k <= 32; k++) {
                cs_ref_vec_t q = cs_ref_eval(&P.elems[e].curve, k / 32.0);
                double x = q.x - 100 - m[4], y = q.y - 100 - m[5];
                double ux = ia * x + ic * y, uy = ib * x + id * y;
                double d = fabs(hypot(ux - 10, uy - 20) - 5);
                if (d > ARC_TOL * norm)
                    fail_msg("%s: point off the circle by %.3g user units", cases[i].t, d);
            }
    }
    /* Nested groups compose parent * child: scale(2) inside translate(100, 0). */
    assert_int_equal(read_text("<svg><g transform='translate(100,0)'><g transform='scale(2)'>"
                               "<rect x='1' y='2' width='3' height='4' transform='translate(1 1)'/>"
                               "</g></g></svg>"),
                     CS_OK);
    expect_pt(&P.elems[0].curve.p[0], 104, 6);
    expect_pt(&P.elems[1].curve.p[1], 110, 14);
}

static void test_units_viewbox(void **state)
{
    (void)state;
    /* viewBox 200 x 100 on 100 mm x 50 mm: half a millimetre per user unit. */
    assert_int_equal(read_text("<svg width='100mm' height='50mm' viewBox='0 0 200 100'>"
                               "<path d='M0 0 L200 100'/></svg>"),
                     CS_OK);
    expect_pt(&P.elems[0].curve.p[0], 0, 0);
    expect_pt(&P.elems[0].curve.p[1], 100, 50);
    /* Units: a 1-unit viewBox on one inch written in each unit. */
    static const char *const inch[] = {"25.4mm", "2.54cm", "1in", "72pt", "6pc", "96px", "96"};
    for (size_t i = 0; i < sizeof inch / sizeof inch[0]; i++) {
        char doc[200];
        snprintf(doc, sizeof doc,
                 "<svg width='%s' height='%s' viewBox='0 0 1 1'><path d='M0 0 L1 1'/></svg>",
                 inch[i], inch[i]);
        assert_int_equal(read_text(doc), CS_OK);
        expect_pt(&P.elems[0].curve.p[1], 25.4, 25.4);
    }
    /* Size without viewBox: user units are px (96 per inch). */
    assert_int_equal(read_text("<svg width='4in' height='2in'><path d='M96 0 L0 192'/></svg>"),
                     CS_OK);
    expect_pt(&P.elems[0].curve.p[0], 25.4, 0);
    expect_pt(&P.elems[0].curve.p[1], 0, 50.8);
    /* preserveAspectRatio: viewBox 100 x 100 on 100 mm x 50 mm; the point (100, 100). */
    static const struct {
        const char *par;
        double x, y, ox, oy; /* image of (100, 100) and of (0, 0) */
    } par[] = {
        {NULL, 75, 50, 25, 0}, /* default xMidYMid meet: 0.5, centred in x */
        {"xMinYMin", 50, 50, 0, 0},
        {"xMaxYMax meet", 100, 50, 50, 0},
        {"xMidYMid slice", 100, 75, 0, -25},
        {"xMinYMax slice", 100, 50, 0, -50},
        {"none", 100, 50, 0, 0},
        {"defer xMaxYMid", 100, 50, 50, 0},
    };
    for (size_t i = 0; i < sizeof par / sizeof par[0]; i++) {
        char doc[256];
        snprintf(doc, sizeof doc,
                 "<svg width='100mm' height='50mm' viewBox='0 0 100 100' %s%s%s>"
                 "<path d='M0 0 L100 100'/></svg>",
                 par[i].par ? "preserveAspectRatio='" : "", par[i].par ? par[i].par : "",
                 par[i].par ? "'" : "");
        assert_int_equal(read_text(doc), CS_OK);
        expect_pt(&P.elems[0].curve.p[0], par[i].ox, par[i].oy);
        expect_pt(&P.elems[0].curve.p[1], par[i].x, par[i].y);
    }
    /* viewBox origin; one size given (the other from the viewBox's ratio). */
    assert_int_equal(read_text("<svg width='100mm' height='100mm' viewBox='-10 -20 100 100'>"
                               "<path d='M0 0 L1 1'/></svg>"),
                     CS_OK);
    expect_pt(&P.elems[0].curve.p[0], 10, 20);
    assert_int_equal(read_text("<svg width='50mm' viewBox='0 0 100 200'><path d='M100 200 L0 0'/>"
                               "</svg>"),
                     CS_OK);
    expect_pt(&P.elems[0].curve.p[0], 50, 100);
    /* No size, or a percentage: one user unit is one millimetre, viewBox or not. */
    assert_int_equal(read_text("<svg viewBox='10 10 100 100'><path d='M12 34 L0 0'/></svg>"),
                     CS_OK);
    expect_pt(&P.elems[0].curve.p[0], 12, 34);
    assert_int_equal(read_text("<svg width='100%' height='100%' viewBox='0 0 480 360'>"
                               "<path d='M12 34 L0 0'/></svg>"),
                     CS_OK);
    expect_pt(&P.elems[0].curve.p[0], 12, 34);
    /* Lengths with units inside user space (px-based); percentages of the viewport. */
    assert_int_equal(read_text("<svg width='210mm' height='297mm'><rect x='1cm' y='72pt' "
                               "width='1in' height='10mm'/></svg>"),
                     CS_OK);
    expect_pt(&P.elems[0].curve.p[0], 10, 25.4);
    expect_pt(&P.elems[1].curve.p[1], 10 + 25.4, 25.4 + 10);
    assert_int_equal(read_text("<svg width='100mm' height='50mm' viewBox='0 0 200 100'>"
                               "<rect width='50%' height='50%'/></svg>"),
                     CS_OK);
    expect_pt(&P.elems[1].curve.p[1], 50, 25);
    assert_int_equal(read_text("<svg><rect width='50%' height='1'/></svg>"), CS_ERR_PARSE);
    /* Nested <svg>: a viewport at (10, 20), 50 x 50 (or 50% of 100), viewBox 10 x 10. */
    static const char *const nested[] = {"width='50' height='50'", "width='50%' height='50%'"};
    for (size_t i = 0; i < 2; i++) {
        char doc[300];
        snprintf(doc, sizeof doc,
                 "<svg width='100mm' height='100mm' viewBox='0 0 100 100'>"
                 "<svg x='10' y='20' %s viewBox='0 0 10 10'><path d='M1 1 L10 10'/></svg>"
                 "<path d='M1 1 L2 2'/></svg>",
                 nested[i]);
        assert_int_equal(read_text(doc), CS_OK);
        expect_pt(&P.elems[0].curve.p[0], 15, 25);
        expect_pt(&P.elems[0].curve.p[1], 60, 70);
        expect_pt(&P.elems[1].curve.p[0], 1, 1); /* back in the outer viewport */
    }
    /* Without viewBox a nested <svg> only moves the origin. */
    assert_int_equal(read_text("<svg><svg x='3' y='4'><path d='M1 1 L0 0'/></svg></svg>"), CS_OK);
    expect_pt(&P.elems[0].curve.p[0], 4, 5);
    /* Zero size disables rendering. */
    assert_int_equal(read_text("<svg width='0' height='10'><path d='M1 1 L0 0'/></svg>"), CS_OK);
    assert_int_equal(P.n, 0);
    /* Errors point into the attribute. */
    assert_int_equal(read_text("<svg viewBox='0 0 -1 5'/>"), CS_ERR_PARSE);
    assert_non_null(strstr(D.reason, "viewBox"));
    assert_int_equal(read_text("<svg viewBox='0 0 1'/>"), CS_ERR_PARSE);
    assert_int_equal(D.loc.col, 20);
    assert_int_equal(read_text("<svg viewBox='0 0 1 1' preserveAspectRatio='xMidYMad'/>"),
                     CS_ERR_PARSE);
    assert_int_equal(D.loc.col, 45);
    assert_int_equal(read_text("<svg width='10qq' height='1'/>"), CS_ERR_PARSE);
    assert_int_equal(D.loc.col, 15);
}

static void test_style_display(void **state)
{
    (void)state;
    /* display none (attribute or style) hides the element and everything below it. */
    assert_int_equal(read_text("<svg><g display='none'><rect width='1' height='1'/></g>"
                               "<g style='display:none'><g><circle r='1'/></g></g>"
                               "<path display='none' d='M0 0 L1 1'/>"
                               "<path d='M0 0 L2 2' stroke='red' fill='none'/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 1);
    expect_pt(&P.elems[0].curve.p[1], 2, 2);
    assert_int_equal(nwarn, 0);
    /* Visibility is inherited, and a child may show itself again. */
    assert_int_equal(read_text("<svg><g visibility='hidden'><rect width='1' height='1'/>"
                               "<rect width='3' height='3' visibility='visible'/></g></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 4);
    expect_pt(&P.elems[1].curve.p[0], 3, 0);
    /* Neither stroke nor fill: nothing shows. style wins over the attribute. */
    assert_int_equal(read_text("<svg><rect width='1' height='1' fill='none'/>"
                               "<rect width='1' height='1' stroke='black' fill='none' "
                               "style='stroke:none'/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 0);
    assert_int_equal(S.ignored, 2);
    /* Stroke inherited from a group; "!important" and blanks in style; no fill, no warning. */
    assert_int_equal(read_text("<svg><g stroke='black' style=' fill : none ; '>"
                               "<rect width='1' height='1'/></g>"
                               "<circle r='1' style='fill:none;stroke: red !important'/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 8);
    assert_int_equal(nwarn, 0);
    /* Filled without stroke: drawn as outlines, said once for the document. */
    assert_int_equal(read_text("<svg><rect width='1' height='1' fill='blue'/>"
                               "<circle r='1' style='fill:#00f'/><path d='M0 0 L5 5'/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 9);
    assert_int_equal(nwarn, 1);
    assert_non_null(strstr(last_warn, "fills are not drawn"));
    assert_non_null(strstr(last_warn, "doc.svg:1:6:"));
}

/* Every SVG file of tests/data (copies of ../shared/data/svg) reads, or fails only as the file
 * itself says (resvg A.svg: "MoveTo is required"), and every element traces at 0.01 mm, ending
 * exactly on its last control point. */
static void test_all_files_flatten(void **state)
{
    (void)state;
    static const char *const w3c[] = {"paths-data-01-t.svg", "paths-data-02-t.svg",
                                      "paths-data-12-t.svg", "paths-data-14-t.svg"};
    char name[256];
    size_t files = 0, elems = 0;
    for (size_t i = 0; i < sizeof resvg_cases / sizeof resvg_cases[0] + 5; i++) {
        size_t nr = sizeof resvg_cases / sizeof resvg_cases[0];
        if (i < nr)
            snprintf(name, sizeof name, DATA "resvg/%s", resvg_cases[i].file);
        else if (i < nr + 4)
            snprintf(name, sizeof name, DATA "w3c/%s", w3c[i - nr]);
        else
            snprintf(name, sizeof name, DATA "resvg/A.svg");
        cs_err_t e = read_file(name);
        if (i == nr + 4) { /* drawn up to its error: nothing, with a warning */
            assert_path_warning(e);
            assert_int_equal(P.n, 4); /* the frame <rect> */
            continue;
        }
        if (e != CS_OK)
            fail_msg("%s: %s", name, D.reason);
        files++;
        for (size_t j = 0; j < P.n; j++) {
            cs_trace_t tr;
            const cs_bezier_t *c = &P.elems[j].curve;
            assert_int_equal(cs_trace_begin(&tr, c, CS_POS_ONE_MM / 100, CS_TRACE_SUBDIV), CS_OK);
            cs_vec3_t pt, last = c->p[0];
            while ((e = cs_trace_next(&tr, &pt)) == CS_OK)
                last = pt;
            assert_int_equal(e, CS_END);
            assert_true(last.x == c->p[c->degree].x && last.y == c->p[c->degree].y);
            elems++;
        }
    }
    assert_int_equal(files, 41);
    assert_true(elems > 41 * 4);
}

/* SVG 2 section 9.5.4: "render a path element up to (but not including) the path command
 * containing the first error"; the other elements are drawn (issue 15 item 9). Expected points
 * by hand: user units are mm (no width/height). */
static void test_drawn_up_to_error(void **state)
{
    (void)state;
    /* 'X' is no command: the first path keeps its two lines, the second path is drawn. */
    assert_path_warning(read_text("<svg fill='none' stroke='red'>"
                                  "<path d='M 0 0 L 10 0 L 10 10 X 5 5'/>"
                                  "<path d='M 20 0 L 30 0'/></svg>"));
    assert_int_equal(nwarn, 1);
    assert_int_equal(D.loc.col, 61); /* the 'X' */
    assert_int_equal(P.n, 3);
    expect_pt(&P.elems[0].curve.p[0], 0, 0);
    expect_pt(&P.elems[0].curve.p[1], 10, 0);
    expect_pt(&P.elems[1].curve.p[1], 10, 10);
    expect_pt(&P.elems[2].curve.p[0], 20, 0);
    expect_pt(&P.elems[2].curve.p[1], 30, 0);
    /* An implicit repeat is a command of its own: "L 1 1 2" keeps L 1 1 and drops the "2". */
    assert_path_warning(read_text("<svg><path fill='none' stroke='red' d='M 0 0 L 1 1 2'/></svg>"));
    assert_int_equal(P.n, 1);
    expect_pt(&P.elems[0].curve.p[1], 1, 1);
    /* Bare path data is no document (no browser draws it): an error stays an error. */
    reset();
    cs_svgdoc_opts_t o;
    cs_svgdoc_opts_init(&o);
    o.warn = on_warn;
    const char *bare = "M 0 0 L 4 0 Q";
    assert_int_equal(cs_svgdoc_read(bare, strlen(bare), "doc.txt", &o, &P, &D, &S), CS_ERR_PARSE);
    assert_int_equal(nwarn, 0);
    /* A range error stays an error: it is not a grammar error, the geometry would be wrong. */
    assert_int_equal(read_text("<svg><path d='M 0 0 L 5000 0'/></svg>"), CS_ERR_RANGE);
}

/* --- <use>, <symbol> and style sheets ----------------------------------------------------- */

/* A 2-D affine map x' = a x + c y + e, y' = b x + d y + f (SVG 1.1 §7.4), for expected values
 * worked out here, independently of cs_path_affine. */
typedef struct {
    double a, b, c, d, e, f;
} aff_t;

static aff_t aff(double a, double b, double c, double d, double e, double f)
{
    aff_t m = {a, b, c, d, e, f};
    return m;
}

static aff_t aff_mul(aff_t m, aff_t n) /* m then n in m's space: the matrix product m n */
{
    return aff(m.a * n.a + m.c * n.b, m.b * n.a + m.d * n.b, m.a * n.c + m.c * n.d,
               m.b * n.c + m.d * n.d, m.a * n.e + m.c * n.f + m.e, m.b * n.e + m.d * n.f + m.f);
}

static void expect_map(const cs_vec3_t *p, aff_t m, double x, double y)
{
    expect_pt(p, m.a * x + m.c * y + m.e, m.b * x + m.d * y + m.f);
}

/* Whether some element starts at (x, y). */
static bool starts_at(double x, double y)
{
    for (size_t i = 0; i < P.n; i++)
        if (pt_is(&P.elems[i].curve.p[0], x, y))
            return true;
    return false;
}

static void expect_warning(const char *where, const char *what)
{
    if (!strstr(last_warn, where) || !strstr(last_warn, what))
        fail_msg("warning '%s', expected '%s' ... '%s'", last_warn, where, what);
}

/* Inkscape 0.x flowed text: <flowRoot> holds a <flowRegion> shape (the frame the text flows
 * in, not shown by Inkscape) and <flowPara> text. Neither is drawn; one warning at the first
 * <flowRoot>; the stroked line after it is drawn. */
static void test_flowroot_not_drawn(void **state)
{
    (void)state;
    const char *doc = "<svg xmlns='http://www.w3.org/2000/svg'>\n"
                      "<flowRoot style='font-size:40px'><flowRegion><rect width='200' "
                      "height='100' x='50' y='60'/></flowRegion><flowPara>Flowed</flowPara>"
                      "</flowRoot>\n"
                      "<flowRoot><flowRegion><path d='M0 0 L5 5'/></flowRegion></flowRoot>\n"
                      "<line x1='1' y1='2' x2='3' y2='4' stroke='black'/></svg>";
    assert_int_equal(read_text(doc), CS_OK);
    assert_int_equal(P.n, 1);
    expect_pt(&P.elems[0].curve.p[0], 1, 2);
    expect_pt(&P.elems[0].curve.p[1], 3, 4);
    assert_int_equal(nwarn, 1);
    expect_warning(":2:1:", "ignoring <flowRoot> (Inkscape flowed text)");
    assert_int_equal(S.ignored, 4); /* the two flowRoots and the two frame shapes */
}

/* <switch>: only the first child whose conditions hold; a foreignObject is passed over for
 * its SVG fallback (draw.io's labels), an empty first <g> hides the rest (draw.io's "Text is
 * not SVG - cannot display" footer), systemLanguage holds for English, requiredExtensions never. */
static void test_switch(void **state)
{
    (void)state;
    const char *doc =
        "<svg xmlns='http://www.w3.org/2000/svg'>"
        "<switch><foreignObject requiredFeatures='http://www.w3.org/TR/SVG11/feature#"
        "Extensibility'><p xmlns='http://www.w3.org/1999/xhtml'>x</p></foreignObject>"
        "<line x1='1' y1='1' x2='2' y2='2' stroke='black'/>"
        "<line x1='3' y1='3' x2='4' y2='4' stroke='black'/></switch>"
        "<switch><g requiredFeatures='http://www.w3.org/TR/SVG11/feature#Extensibility'/>"
        "<line x1='5' y1='5' x2='6' y2='6' stroke='black'/></switch>"
        "<switch><line systemLanguage='fr' x1='7' y1='7' x2='8' y2='8' stroke='black'/>"
        "<line systemLanguage='en-GB, de' x1='9' y1='9' x2='10' y2='10' stroke='black'/>"
        "<line x1='11' y1='11' x2='12' y2='12' stroke='black'/></switch>"
        "<switch><line requiredExtensions='http://example.org/ext' x1='12' y1='0' x2='0' y2='0' "
        "stroke='black'/><line x1='13' y1='13' x2='14' y2='14' stroke='black'/></switch>"
        "<line x1='15' y1='15' x2='16' y2='16' stroke='black'/></svg>";
    assert_int_equal(read_text(doc), CS_OK);
    assert_int_equal(P.n, 4);
    expect_pt(&P.elems[0].curve.p[0], 1, 1);
    expect_pt(&P.elems[1].curve.p[0], 9, 9);
    expect_pt(&P.elems[2].curve.p[0], 13, 13);
    expect_pt(&P.elems[3].curve.p[1], 16, 16);
}

static void test_use_elements(void **state)
{
    (void)state;
    /* The use's transform, then translate(x, y) (SVG 1.1 §5.6); the original is drawn too. */
    assert_int_equal(read_text("<svg><path id='p' d='M1 2 L3 4' stroke='black'/>"
                               "<use href='#p' x='10' y='20' transform='scale(2)'/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 2);
    aff_t m = aff_mul(aff(2, 0, 0, 2, 0, 0), aff(1, 0, 0, 1, 10, 20));
    expect_pt(&P.elems[0].curve.p[0], 1, 2);
    expect_map(&P.elems[1].curve.p[0], m, 1, 2);
    expect_map(&P.elems[1].curve.p[1], m, 3, 4);
    assert_int_equal(S.uses, 1);
    /* A forward reference by xlink:href to a group with its own transform: the instance comes
     * first, in document order. */
    assert_int_equal(read_text("<svg xmlns:xlink='http://www.w3.org/1999/xlink'>"
                               "<use xlink:href='#g' x='5'/><g id='g' transform='rotate(90)'>"
                               "<line x2='1' stroke='red'/></g></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 2);
    m = aff_mul(aff(1, 0, 0, 1, 5, 0), aff(0, 1, -1, 0, 0, 0)); /* rotate(90): (1,0) -> (0,1) */
    expect_map(&P.elems[0].curve.p[1], m, 1, 0);
    expect_pt(&P.elems[1].curve.p[1], 0, 1);
    /* href wins over xlink:href (SVG 2). */
    assert_int_equal(read_text("<svg xmlns:xlink='http://www.w3.org/1999/xlink'><defs>"
                               "<line id='a' x2='1' stroke='red'/><line id='b' x2='7' "
                               "stroke='red'/></defs><use xlink:href='#a' href='#b'/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 1);
    expect_pt(&P.elems[0].curve.p[1], 7, 0);
    /* Properties come from the use, not from where the element stands: stroke none and fill
     * none around the <defs> do not hide it; a stroke around them does not show it. */
    assert_int_equal(read_text("<svg><g stroke='none' fill='none'><defs><path id='r' "
                               "d='M0 0 L1 0'/></defs></g><use href='#r' stroke='black' "
                               "fill='none'/><g stroke='black'><defs><path id='s' d='M0 0 L2 "
                               "0'/></defs></g><use href='#s' fill='none'/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 1);
    expect_pt(&P.elems[0].curve.p[1], 1, 0);
    assert_int_equal(nwarn, 0);
    /* A use inside <defs> is drawn only through what holds it; a nested use composes. */
    assert_int_equal(read_text("<svg><defs><line id='l' x2='1' stroke='red'/>"
                               "<g id='two'><use href='#l'/><use href='#l' y='3'/></g></defs>"
                               "<use href='#two' x='10'/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 2);
    expect_pt(&P.elems[0].curve.p[0], 10, 0);
    expect_pt(&P.elems[1].curve.p[1], 11, 3);
    assert_int_equal(S.uses, 3);
}

static void test_use_symbol_viewbox(void **state)
{
    (void)state;
    /* Viewport 40 x 40 at (100, 50) for viewBox 5 0 10 20 (SVG 1.1 §7.8): meet scales by
     * min(40/10, 40/20) = 2 and centres the 20 x 40 result: x + (40 - 10 * 2) / 2. */
    static const struct {
        const char *par;
        double sx, sy, tx, ty;
    } cases[] = {
        {"", 2, 2, 100 + (40 - 10 * 2) / 2.0 - 5 * 2, 50},
        {" preserveAspectRatio='xMinYMax slice'", 4, 4, 100 - 5 * 4, 50 + (40 - 20 * 4)},
        {" preserveAspectRatio='none'", 4, 2, 100 - 5 * 4, 50},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char doc[400];
        snprintf(doc, sizeof doc,
                 "<svg><use href='#s' x='100' y='50' width='40' height='40'/>"
                 "<symbol id='s' viewBox='5 0 10 20'%s><path d='M5 0 L15 20' stroke='red'/>"
                 "</symbol></svg>",
                 cases[i].par);
        assert_int_equal(read_text(doc), CS_OK);
        assert_int_equal(P.n, 1);
        aff_t m = aff(cases[i].sx, 0, 0, cases[i].sy, cases[i].tx, cases[i].ty);
        expect_map(&P.elems[0].curve.p[0], m, 5, 0);
        expect_map(&P.elems[0].curve.p[1], m, 15, 20);
    }
    /* No width/height on the use: 100% of the viewport (viewBox 200 x 100, no size: user
     * units are mm), meet: min(200/10, 100/20) = 5, centred in x. A symbol by itself is not
     * drawn; a zero width draws nothing. */
    assert_int_equal(read_text("<svg viewBox='0 0 200 100'><symbol id='s' viewBox='0 0 10 20'>"
                               "<path d='M0 0 L10 20' stroke='red'/></symbol><use href='#s'/>"
                               "<use href='#s' width='0'/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 1);
    expect_pt(&P.elems[0].curve.p[0], (200 - 10 * 5) / 2.0, 0);
    expect_pt(&P.elems[0].curve.p[1], (200 - 10 * 5) / 2.0 + 50, 100);
    /* A nested <svg>: the use's width/height replace its own (20 x 40, meet: 20, centred in
     * y), at the use's x. */
    assert_int_equal(read_text("<svg><defs><svg id='n' width='10' height='10' "
                               "viewBox='0 0 1 1'><path d='M0 0 L1 1' stroke='red'/></svg>"
                               "</defs><use href='#n' x='1' width='20' height='40'/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 1);
    expect_pt(&P.elems[0].curve.p[0], 1, (40 - 20) / 2.0);
    expect_pt(&P.elems[0].curve.p[1], 21, (40 - 20) / 2.0 + 20);
}

static void test_use_refused(void **state)
{
    (void)state;
    /* A missing id: a warning at the use, nothing drawn for it, the rest drawn. */
    assert_int_equal(read_text("<svg>\n  <use href='#nope'/><line x2='1' stroke='red'/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 1);
    assert_int_equal(nwarn, 1);
    expect_warning("doc.svg:2:3:", "no element has this id");
    assert_int_equal(S.ignored, 1);
    /* A use's own children are not drawn, whether it draws or not. */
    assert_int_equal(read_text("<svg><use href='#nope'><line x2='1' stroke='red'/></use><use>"
                               "<line x2='2' stroke='red'/></use><use href='#l'><line x2='3' "
                               "stroke='red'/></use><line id='l' x2='4' stroke='red'/></svg>"),
                     CS_OK);
    assert_int_equal(P.n, 2);
    expect_pt(&P.elems[0].curve.p[1], 4, 0);
    /* Another file: a warning. */
    assert_int_equal(read_text("<svg><use href='other.svg#a'/></svg>"), CS_OK);
    expect_warning("doc.svg:1:6:", "another file");
    /* Cycles: a use of itself, of its own group, and two groups using each other: a warning,
     * the rest drawn once each. */
    assert_int_equal(read_text("<svg><use id='u' href='#u'/></svg>"), CS_OK);
    expect_warning("doc.svg:1:6:", "cycle");
    assert_int_equal(read_text("<svg><g id='a'><line x2='1' stroke='red'/><use href='#a'/></g>"
                               "</svg>"),
                     CS_OK);
    assert_int_equal(P.n, 1);
    expect_warning("doc.svg:1:43:", "cycle");
    assert_int_equal(read_text("<svg><g id='a'><line x2='1' stroke='red'/><use href='#b'/></g>"
                               "<g id='b'><line x2='2' stroke='red'/><use href='#a'/></g></svg>"),
                     CS_OK);
    /* a, b through a's use, b, a through b's use; each repeat refused */
    assert_int_equal(P.n, 4);
    assert_int_equal(nwarn, 1);
    /* Nesting: 10 levels are drawn; past CS_SVGDOC_MAX_USE_DEPTH, a warning and nothing. */
    for (int levels = 10; levels <= CS_SVGDOC_MAX_USE_DEPTH + 8;
         levels += CS_SVGDOC_MAX_USE_DEPTH - 2) {
        char doc[8000];
        int n = snprintf(doc, sizeof doc, "<svg><defs><line id='g0' x2='1' stroke='red'/>");
        for (int i = 1; i <= levels; i++)
            n += snprintf(doc + n, sizeof doc - (size_t)n, "<g id='g%d'><use href='#g%d'/></g>", i,
                          i - 1);
        snprintf(doc + n, sizeof doc - (size_t)n, "</defs><use href='#g%d'/></svg>", levels);
        assert_int_equal(read_text(doc), CS_OK);
        assert_int_equal(P.n, levels <= CS_SVGDOC_MAX_USE_DEPTH ? 1 : 0);
        assert_int_equal(nwarn, levels <= CS_SVGDOC_MAX_USE_DEPTH ? 0 : 1);
    }
    /* Uses that multiply (10 per level, 7 levels: 10^7 lines) stop at
     * CS_SVGDOC_MAX_USE_ELEMENTS with a range error at the element past it. */
    char doc[4000];
    int n = snprintf(doc, sizeof doc, "<svg><defs><line id='g0'/>");
    for (int i = 1; i <= 7; i++) {
        n += snprintf(doc + n, sizeof doc - (size_t)n, "<g id='g%d'>", i);
        for (int k = 0; k < 10; k++)
            n += snprintf(doc + n, sizeof doc - (size_t)n, "<use href='#g%d'/>", i - 1);
        n += snprintf(doc + n, sizeof doc - (size_t)n, "</g>");
    }
    snprintf(doc + n, sizeof doc - (size_t)n, "</defs><use href='#g7'/></svg>");
    assert_int_equal(read_text(doc), CS_ERR_RANGE);
    assert_non_null(strstr(D.reason, "CS_SVGDOC_MAX_USE_ELEMENTS"));
    assert_int_equal(D.loc.line, 1);
}

/* Whether each of the lines x2 = 1, 2, 3... of a document is drawn: a bit mask. */
static unsigned drawn_lines(const char *doc)
{
    if (read_text(doc) != CS_OK)
        fail_msg("%s: %s", doc, D.reason);
    unsigned mask = 0;
    for (size_t i = 0; i < P.n; i++)
        mask |= 1u << (unsigned)lround(P.elems[i].curve.p[1].x * LSB);
    return mask >> 1;
}

static void test_style_sheets(void **state)
{
    (void)state;
    /* Classes (several per element), later rules over earlier ones of equal specificity. */
    assert_int_equal(drawn_lines("<svg><style>.a{stroke:none;fill:none} .b{stroke:black}"
                                 "</style><line class='a' x2='1'/><line class='a b' x2='2'/>"
                                 "<line class=' b ' x2='3'/></svg>"),
                     2 | 4);
    assert_int_equal(nwarn, 0);
    /* display:none from a class hides a group; visibility from a class. */
    assert_int_equal(drawn_lines("<svg><style>.h{display:none} .v{visibility:hidden}</style>"
                                 "<g class='h'><line x2='1' stroke='red'/></g>"
                                 "<line class='v' x2='2' stroke='red'/>"
                                 "<line x2='3' stroke='red'/></svg>"),
                     4);
    /* Specificity (CSS 2.1 §6.4.3): #id over .class over type, whatever the order; a compound
     * line.c over .c; the universal selector counts nothing. */
    assert_int_equal(
        drawn_lines("<svg><style>#x{stroke:none} .c{stroke:red} line.d{stroke:none}"
                    " .d{stroke:red} *{stroke:red} line{stroke:none}</style>"
                    "<line id='x' class='c' x2='1'/><line class='d' x2='2'/>"
                    "<line x2='3'/><rect x='20' width='1' height='1' fill='none'/></svg>"),
        1u << 19 | 1u << 20); /* the rect, by '*': x 20 and 21 */
    assert_int_equal(P.n, 4); /* the rect: '*' */
    /* Sheet over presentation attributes; style="" over the sheet; !important in the sheet over
     * style=""; !important in style="" over all. */
    assert_int_equal(drawn_lines("<svg><style>.n{stroke:none} .i{stroke:none !important}"
                                 "</style><line class='n' stroke='red' x2='1'/>"
                                 "<line class='n' style='stroke:red' x2='2'/>"
                                 "<line class='i' style='stroke:red' x2='3'/>"
                                 "<line class='i' style='stroke:red!important' x2='4'/></svg>"),
                     2 | 8);
    /* Comma groups, descendant and child combinators, a sheet after the elements, in CDATA. */
    assert_int_equal(drawn_lines("<svg><g class='k'><g><line x2='1'/></g></g><line x2='2'/>"
                                 "<g id='q'><line x2='3'/></g><line id='r' x2='4'/>"
                                 "<style><![CDATA[ g.k line, #r {stroke:red} svg > g > line"
                                 "{stroke:blue} ]]></style></svg>"),
                     1 | 4 | 8);
    /* Selectors match in the document: a class on an element in <defs> applies to its use. */
    assert_int_equal(drawn_lines("<svg><style>.s{stroke:red}</style><defs><line id='l' "
                                 "class='s' x2='1'/></defs><use href='#l'/></svg>"),
                     1);
    /* At-rules: skipped with one warning, the rules after them read. */
    assert_int_equal(drawn_lines("<svg><style>@import url(x.css); @media print { line{stroke:"
                                 "none} } @font-face{font-family:x} line{stroke:red}</style>"
                                 "<line x2='1'/></svg>"),
                     1);
    assert_int_equal(nwarn, 1);
    expect_warning("doc.svg:1:13:", "at-rules");
    /* Keywords in any case (CSS: ASCII case-insensitive), from a sheet or an attribute. */
    assert_int_equal(drawn_lines("<svg><style>.u{stroke:NONE}</style><line class='u' "
                                 "stroke='red' x2='1'/><line stroke='None' x2='2'/>"
                                 "<line stroke='red' x2='3' display='NONE'/>"
                                 "<line stroke='RED' x2='4'/></svg>"),
                     8);
    /* Another type of sheet: ignored with a warning. */
    assert_int_equal(drawn_lines("<svg><style type='text/xsl'>line{stroke:red}</style>"
                                 "<line x2='1'/></svg>"),
                     0);
    expect_warning("doc.svg:1:6:", "text/xsl");
}

static void test_style_sheet_errors(void **state)
{
    (void)state;
    /* A malformed declaration: a warning at its place in the file, the others kept. */
    assert_int_equal(drawn_lines("<svg>\n<style>\nline{stroke red; fill:none}\n"
                                 "rect{stroke:red}\n</style><line x2='1' stroke='red'/>"
                                 "<rect width='2' height='2' fill='none'/></svg>"),
                     1 | 2);
    assert_int_equal(nwarn, 1);
    expect_warning("doc.svg:3:6:", "malformed declaration");
    /* An invalid selector drops its whole rule (CSS), an unsupported one only itself. */
    assert_int_equal(drawn_lines("<svg><style>li%ne, line{stroke:red}</style><line x2='1'/>"
                                 "</svg>"),
                     0);
    expect_warning("doc.svg:1:15:", "invalid selector");
    assert_int_equal(drawn_lines("<svg><style>line:hover, #b{stroke:red}</style>"
                                 "<line x2='1'/><line id='b' x2='2'/></svg>"),
                     2);
    expect_warning("doc.svg:1:17:", "unsupported selector");
    /* The end of the sheet closes an open block; a selector without a block is a warning. */
    assert_int_equal(drawn_lines("<svg><style>line{stroke:red</style><line x2='1'/></svg>"), 1);
    assert_int_equal(nwarn, 0);
    assert_int_equal(drawn_lines("<svg><style>line{stroke:red} rect</style><line x2='1'/>"
                                 "</svg>"),
                     1);
    expect_warning("doc.svg:1:30:", "without a { declaration block");
    /* Comments, HTML comment tokens, strings with braces, an empty sheet. */
    assert_int_equal(drawn_lines("<svg><style>&lt;!-- /* x{stroke:none} */ line{font-family:'a}b';"
                                 "stroke:red} --&gt;</style><style/><line x2='1'/></svg>"),
                     1);
    assert_int_equal(nwarn, 0);
}

/* Real and realistic files: matplotlib's text as glyph paths in <defs> placed by <use>,
 * Illustrator's class sheet, Inkscape's clones and symbols, cairo's glyph symbols. Expected points
 * from the files' numbers and transforms by hand. */
static void test_use_style_files(void **state)
{
    (void)state;
    /* matplotlib: 576 pt (768 px = 203.2 mm) over viewBox 576: k mm per user unit. */
    assert_int_equal(read_file(DATA "use/matplotlib-multi-font-aspath.svg"), CS_OK);
    double k = 203.2 / 576;
    assert_int_equal(S.uses, 26);
    assert_int_equal(nwarn, 1);                    /* fills drawn as outlines */
    expect_pt(&P.elems[0].curve.p[0], 0, 432 * k); /* the white background patch */
    /* 'T' (use without x), then 'h' at x = 61.083984, glyph units scaled by 0.015625, all in
     * translate(86.4 226.8) scale(0.27 -0.27). */
    aff_t text = aff_mul(aff(k, 0, 0, k, 0, 0), aff(0.27, 0, 0, -0.27, 86.4, 226.8));
    aff_t glyph = aff(0.015625, 0, 0, 0.015625, 0, 0);
    expect_map(&P.elems[4].curve.p[0], aff_mul(text, glyph), -19, 4666);
    aff_t h = aff_mul(aff_mul(text, aff(1, 0, 0, 1, 61.083984, 0)), glyph);
    assert_true(starts_at(h.a * 3513 + h.e, h.d * 2113 + h.f));
    aff_t bang = aff_mul(aff_mul(text, aff(1, 0, 0, 1, 1503.208984, 0)), glyph);
    expect_map(&P.elems[P.n - 1].curve.p[0], bang, 966, 2619); /* '!' ends ...L 966 2619 */
    for (size_t i = 0; i < P.n; i++) {
        const cs_vec3_t *p = &P.elems[i].curve.p[0];
        assert_true(p->x * LSB >= -PT_TOL && p->x * LSB <= 203.2 + PT_TOL);
        assert_true(p->y * LSB >= -PT_TOL && p->y * LSB <= 152.4 + PT_TOL);
    }
    /* Illustrator: viewBox 200 x 100 on 100 mm x 50 mm (0.5 mm per unit). Drawn: the .st0
     * rect (4 lines), the .st3 line, the .st4 polyline (2), the white-filled .st5 circle
     * (4 arcs), the line stroked by its second class; not drawn: .st1 (no paint), .st2
     * (display none, alone or as a second class). */
    assert_int_equal(read_file(DATA "use/illustrator-style.svg"), CS_OK);
    assert_int_equal(P.n, 4 + 1 + 2 + 4 + 1);
    expect_pt(&P.elems[0].curve.p[0], 5, 5);
    expect_pt(&P.elems[4].curve.p[0], 5, 45);
    expect_pt(&P.elems[4].curve.p[1], 95, 45);
    expect_pt(&P.elems[5].curve.p[0], 65, 5);
    expect_pt(&P.elems[11].curve.p[0], 10, 25);
    expect_pt(&P.elems[11].curve.p[1], 20, 25);
    assert_int_equal(nwarn, 1); /* the circle's fill */
    /* Inkscape: 1 mm per unit. The clone (before its original) at translate(50, 0), the
     * original, the symbol's cross (viewBox 10 x 10 in 20 x 10 at (10, 60): scale 1, centred:
     * x + 5); the hidden layer's clone not drawn. */
    assert_int_equal(read_file(DATA "use/inkscape-clones.svg"), CS_OK);
    assert_int_equal(P.n, 4 + 4 + 2);
    expect_pt(&P.elems[0].curve.p[0], 60, 10);
    expect_pt(&P.elems[4].curve.p[0], 10, 10);
    expect_pt(&P.elems[8].curve.p[0], 15, 60);
    expect_pt(&P.elems[8].curve.p[1], 25, 70);
    expect_pt(&P.elems[9].curve.p[0], 25, 60);
    expect_pt(&P.elems[9].curve.p[1], 15, 70);
    assert_int_equal(nwarn, 0);
    assert_int_equal(S.uses, 2);
    /* cairo (1.16, cairo_show_text): each glyph a <symbol> without viewBox (so only the use's
     * x, y place it), filled through the enclosing <g style="fill:...">; 200 pt over viewBox
     * 200: 25.4 / 72 mm per unit. 'H' at (10, 50) starts M 2.9375 -21.875 L 5.90625 -21.875;
     * the stroked frame M 5 5 ... L 5 95 Z comes last. */
    assert_int_equal(read_file(DATA "use/cairo-text.svg"), CS_OK);
    double pt = 25.4 / 72;
    assert_int_equal(S.uses, 8);
    assert_int_equal(nwarn, 1); /* fills drawn as outlines */
    expect_pt(&P.elems[0].curve.p[0], (10 + 2.9375) * pt, (50 - 21.875) * pt);
    expect_pt(&P.elems[0].curve.p[1], (10 + 5.90625) * pt, (50 - 21.875) * pt);
    expect_pt(&P.elems[P.n - 1].curve.p[0], 5 * pt, 95 * pt);
    expect_pt(&P.elems[P.n - 1].curve.p[1], 5 * pt, 5 * pt);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_resvg_files, setup, teardown),
        cmocka_unit_test_setup_teardown(test_resvg_moveto_required, setup, teardown),
        cmocka_unit_test_setup_teardown(test_w3c_01_cubics, setup, teardown),
        cmocka_unit_test_setup_teardown(test_w3c_02_quadratics, setup, teardown),
        cmocka_unit_test_setup_teardown(test_w3c_12_polybezier, setup, teardown),
        cmocka_unit_test_setup_teardown(test_w3c_14_initial_relative_moveto, setup, teardown),
        cmocka_unit_test_setup_teardown(test_error_positions, setup, teardown),
        cmocka_unit_test_setup_teardown(test_transforms, setup, teardown),
        cmocka_unit_test_setup_teardown(test_skipped_content, setup, teardown),
        cmocka_unit_test_setup_teardown(test_rect, setup, teardown),
        cmocka_unit_test_setup_teardown(test_circle_ellipse, setup, teardown),
        cmocka_unit_test_setup_teardown(test_line_poly, setup, teardown),
        cmocka_unit_test_setup_teardown(test_shape_transforms, setup, teardown),
        cmocka_unit_test_setup_teardown(test_units_viewbox, setup, teardown),
        cmocka_unit_test_setup_teardown(test_style_display, setup, teardown),
        cmocka_unit_test_setup_teardown(test_all_files_flatten, setup, teardown),
        cmocka_unit_test_setup_teardown(test_drawn_up_to_error, setup, teardown),
        cmocka_unit_test_setup_teardown(test_flowroot_not_drawn, setup, teardown),
        cmocka_unit_test_setup_teardown(test_switch, setup, teardown),
        cmocka_unit_test_setup_teardown(test_use_elements, setup, teardown),
        cmocka_unit_test_setup_teardown(test_use_symbol_viewbox, setup, teardown),
        cmocka_unit_test_setup_teardown(test_use_refused, setup, teardown),
        cmocka_unit_test_setup_teardown(test_style_sheets, setup, teardown),
        cmocka_unit_test_setup_teardown(test_style_sheet_errors, setup, teardown),
        cmocka_unit_test_setup_teardown(test_use_style_files, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
