/* test_surffile: the native surface format and the Newell fallback of host/cs_surffile. Each
 * statement of tests/data/surfaces/all_kinds.txt must give exactly (bit for bit) what the core
 * constructor gives for the same data built here; errors carry file:line:col. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_coons.h"
#include "cs_revolve.h"
#include "cs_surffile.h"

#define ALL    "tests/data/surfaces/all_kinds.txt"
#define TEAPOT "tests/data/teapot/newell_teapot.txt"

static cs_vec3_t mm(double x, double y, double z)
{
    return cs_fixed_vec((int32_t)lround(x * 65536), (int32_t)lround(y * 65536),
                        (int32_t)lround(z * 65536));
}
static cs_bezier_t bz(unsigned n, const cs_vec3_t *p)
{
    cs_bezier_t c;
    assert_int_equal(cs_bezier_init(&c, n, p), CS_OK);
    return c;
}

static void test_all_kinds(void **state)
{
    (void)state;
    cs_surffile_t sf;
    cs_path_diag_t d;
    assert_int_equal(cs_surffile_read(ALL, 1.0, 0.0025, &sf, &d), CS_OK);
    assert_true(sf.native);
    /* coons, tri, revolve (n arcs), extrude, ruled, bezier, hermite, power */
    size_t nrev = 0;
    cs_patch_t rev[CS_REVOLVE_MAX_ARCS];
    cs_vec3_t prof[4] = {mm(8, 0, 0), mm(30, 10, 0), mm(0, 30, 0), mm(10, 40, 0)};
    cs_bezier_t pc = bz(3, prof);
    double o[3] = {100, 15, 0}, z[3] = {0, 0, 1}, x[3] = {1, 0, 0};
    assert_int_equal(cs_revolve(&pc, o, z, x, 360, 0.0025, rev, CS_REVOLVE_MAX_ARCS, &nrev, NULL),
                     CS_OK);
    assert_int_equal(sf.n, 7 + nrev);
    /* 1: bicubic Coons of the same curves. */
    cs_vec3_t a[4] = {mm(0, 0, 0), mm(10, 0, 12), mm(20, 0, -6), mm(30, 0, 0)};
    cs_vec3_t b[3] = {mm(0, 30, 5), mm(15, 30, 20), mm(30, 30, 5)};
    cs_vec3_t c[2] = {mm(0, 0, 0), mm(0, 30, 5)};
    cs_vec3_t e[4] = {mm(30, 0, 0), mm(30, 10, -10), mm(30, 20, 15), mm(30, 30, 5)};
    cs_bezier_t p1 = bz(3, a), p2 = bz(2, b), q1 = bz(1, c), q2 = bz(3, e);
    cs_patch_t want;
    assert_int_equal(cs_coons_bicubic(&p1, &p2, &q1, &q2, NULL, NULL, NULL, NULL, &want), CS_OK);
    assert_false(sf.items[0].tri);
    assert_memory_equal(&sf.items[0].quad, &want, sizeof want);
    assert_int_equal(sf.items[0].line, 3);
    /* 2: the cubic triangle, in file order. */
    assert_true(sf.items[1].tri);
    assert_int_equal(sf.items[1].trip.degree, 3);
    cs_vec3_t first = mm(40, 0, 0), last = mm(55, 30, 0);
    assert_memory_equal(&sf.items[1].trip.p[0], &first, sizeof first);
    assert_memory_equal(&sf.items[1].trip.p[9], &last, sizeof last);
    assert_int_equal(sf.items[1].line, 8);
    /* 3..: the revolution's arcs. */
    for (size_t k = 0; k < nrev; k++)
        assert_memory_equal(&sf.items[2 + k].quad, &rev[k], sizeof rev[k]);
    size_t i = 2 + nrev;
    /* extrude */
    cs_vec3_t s[3] = {mm(0, 40, 0), mm(15, 60, 0), mm(30, 40, 0)};
    cs_bezier_t sc = bz(2, s);
    cs_vec3_t dir = mm(0, 0, 10);
    assert_int_equal(cs_coons_extrude(&sc, &dir, &want), CS_OK);
    assert_memory_equal(&sf.items[i++].quad, &want, sizeof want);
    /* ruled */
    cs_vec3_t r1[2] = {mm(40, 40, 0), mm(70, 40, 0)};
    cs_vec3_t r2[4] = {mm(40, 70, 10), mm(50, 50, 20), mm(60, 80, 0), mm(70, 70, 10)};
    cs_bezier_t c1 = bz(1, r1), c2 = bz(3, r2);
    assert_int_equal(cs_coons_ruled(&c1, &c2, &want), CS_OK);
    assert_memory_equal(&sf.items[i++].quad, &want, sizeof want);
    /* bezier 1 x 1 */
    cs_vec3_t bl[4] = {mm(80, -20, 0), mm(80, 0, 0), mm(100, -20, 0), mm(100, 0, 5)};
    assert_int_equal(cs_patch_init(&want, 1, 1, bl), CS_OK);
    assert_memory_equal(&sf.items[i++].quad, &want, sizeof want);
    /* hermite: P00 P10 P01 P11, Pu.., Pv.., Puv.. */
    cs_patch_hermite_t h;
    cs_vec3_t hp[4] = {mm(0, 50, 0), mm(20, 50, 0), mm(0, 70, 0), mm(20, 70, 0)};
    for (int k = 0; k < 4; k++) {
        h.p[k % 2][k / 2] = hp[k];
        h.pu[k % 2][k / 2] = mm(20, 0, 0);
        h.pv[k % 2][k / 2] = mm(0, 20, 0);
        h.puv[k % 2][k / 2] = mm(0, 0, 0);
    }
    h.puv[0][0] = mm(0, 0, 30);
    h.puv[1][1] = mm(0, 0, -30);
    assert_int_equal(cs_patch_from_hermite(&want, &h), CS_OK);
    assert_memory_equal(&sf.items[i++].quad, &want, sizeof want);
    /* power: a00 = (-40,0,0), a01 = (0,20,0), a10 = (20,0,0), a20 = (0,0,10), a21 = (0,0,-10) */
    cs_vec3_t pw[4][4];
    memset(pw, 0, sizeof pw);
    pw[0][0] = mm(-40, 0, 0);
    pw[0][1] = mm(0, 20, 0);
    pw[1][0] = mm(20, 0, 0);
    pw[2][0] = mm(0, 0, 10);
    pw[2][1] = mm(0, 0, -10);
    assert_int_equal(cs_patch_from_power(&want, pw), CS_OK);
    assert_memory_equal(&sf.items[i++].quad, &want, sizeof want);
    assert_int_equal(i, sf.n);
    cs_surffile_free(&sf);
}

/* The pentagon example: one n-sided item equal to cs_varady_init on the same loop. */
static void test_varady(void **state)
{
    (void)state;
    cs_surffile_t sf;
    cs_path_diag_t d;
    assert_int_equal(cs_surffile_read("tests/data/surfaces/pentagon.txt", 1.0, 0.01, &sf, &d),
                     CS_OK);
    assert_int_equal(sf.n, 1);
    assert_true(sf.items[0].varady);
    assert_int_equal(sf.items[0].line, 3);
    const double c[5][4][3] = {
        {{20, 0, -4}, {20, 6, -2}, {10, 18, 2}, {6.18, 19.02, 4}},
        {{6.18, 19.02, 4}, {2, 22, 6}, {-12, 14, -2}, {-16.18, 11.76, -4}},
        {{-16.18, 11.76, -4}, {-20, 8, -6}, {-20, -8, 2}, {-16.18, -11.76, 4}},
        {{-16.18, -11.76, 4}, {-12, -14, 6}, {2, -22, -2}, {6.18, -19.02, -4}},
        {{6.18, -19.02, -4}, {10, -18, -6}, {20, -6, -2}, {20, 0, -4}},
    };
    cs_bezier_t sides[5];
    for (int i = 0; i < 5; i++) {
        cs_vec3_t p[4];
        for (int j = 0; j < 4; j++)
            p[j] = mm(c[i][j][0], c[i][j][1], c[i][j][2]);
        sides[i] = bz(3, p);
    }
    cs_varady_t v;
    assert_int_equal(cs_varady_init(&v, sides, 5), CS_OK);
    const cs_varady_t *got = &sf.items[0].nside;
    assert_int_equal(got->n, 5);
    for (int i = 0; i < 5; i++)
        assert_memory_equal(got->side[i].p, v.side[i].p, sizeof v.side[i].p);
    assert_memory_equal(got->vert, v.vert, sizeof v.vert);
    assert_memory_equal(got->t0, v.t0, sizeof v.t0);
    assert_memory_equal(got->t1, v.t1, sizeof v.t1);
    cs_surffile_free(&sf);
    /* A loop that does not close: reported at the keyword. */
    const char *open_loop = "curvestep-surfaces 1\nvarady 3  1 0 0 0 1 0 0  1 1 0 0 0 1 0  "
                            "1 0 1 0 0 0 0.5\n";
    assert_int_equal(cs_surffile_parse(open_loop, strlen(open_loop), "o.txt", 1.0, 0.01, &sf, &d),
                     CS_ERR_DEGENERATE);
    assert_int_equal(d.loc.line, 2);
    assert_int_equal(d.loc.col, 1);
    cs_surffile_free(&sf);
}

static void test_newell_fallback(void **state)
{
    (void)state;
    cs_surffile_t sf;
    cs_path_diag_t d;
    assert_int_equal(cs_surffile_read(TEAPOT, 10.0, 0.01, &sf, &d), CS_OK);
    assert_false(sf.native);
    assert_int_equal(sf.n, 32);
    assert_int_equal(sf.items[0].line, 2);
    assert_int_equal(sf.items[0].quad.p[0][0].x, (int32_t)lround(14 * 65536));
    cs_surffile_free(&sf);
}

static void expect(const char *text, cs_err_t code, unsigned line, unsigned col, const char *words)
{
    cs_surffile_t sf;
    cs_path_diag_t d;
    cs_err_t e = cs_surffile_parse(text, strlen(text), "s.txt", 1.0, 0.01, &sf, &d);
    if (e != code || d.loc.line != line || d.loc.col != col || !strstr(d.reason, words))
        fprintf(stderr, "got %d %s:%u:%u: %s\n", e, d.loc.file, d.loc.line, d.loc.col, d.reason);
    assert_int_equal(e, code);
    assert_string_equal(d.loc.file, "s.txt");
    assert_int_equal(d.loc.line, line);
    assert_int_equal(d.loc.col, col);
    assert_non_null(strstr(d.reason, words));
    cs_surffile_free(&sf);
}

static void test_errors(void **state)
{
    (void)state;
    expect("curvestep-surfaces 2\n", CS_ERR_RANGE, 1, 20, "format version");
    expect("curvestep-surfaces 1\n# nothing\n", CS_ERR_EMPTY, 3, 1, "no surfaces");
    expect("curvestep-surfaces 1\ntorus 3\n", CS_ERR_PARSE, 2, 1, "unknown surface 'torus'");
    expect("curvestep-surfaces 1\nbezier 8 1\n", CS_ERR_RANGE, 2, 8, "degree in u");
    expect("curvestep-surfaces 1\nbezier 1 1 0 0 0  1 0 0  0 1 x\n", CS_ERR_PARSE, 2, 30,
           "'x': control point expected");
    expect("curvestep-surfaces 1\nbezier 1 1 0 0 0  1 0 0  0 1 0\n", CS_ERR_PARSE, 3, 1,
           "end of file");
    expect("curvestep-surfaces 1\nbezier 1 1 0 0 0  5000 0 0  0 1 0 1 1 1\n", CS_ERR_RANGE, 2, 19,
           "outside");
    /* Coons corners that do not meet: reported at the keyword. */
    expect("curvestep-surfaces 1\n\n  coons-bilinear 1 0 0 0 1 0 0  1 0 1 0 1 1 0  "
           "1 0 0 0 0 1 0  1 1 0 0 1 1 1\n",
           CS_ERR_DEGENERATE, 3, 3, "coons-bilinear: degenerate");
    expect("curvestep-surfaces 1\nrevolve 0 0 0 0 0 1 0 0 1 90 1 1 0 0 2 0 0\n", CS_ERR_DEGENERATE,
           2, 1, "revolve");
    /* Not native: read as Newell, whose errors come back. */
    expect("bezier 1 1\n", CS_ERR_PARSE, 1, 1, "not a finite number");
}

/* coons-bicubic with its optional derivative curves and twists gives bit for bit what
 * cs_coons_bicubic_twist gives for the same data (the formula itself: test_coons). */
static void test_coons_derivatives_twists(void **state)
{
    (void)state;
    const char *text = "curvestep-surfaces 1\ncoons-bicubic\n"
                       " 3 0 0 0 10 0 5 20 0 5 30 0 0\n 3 0 30 0 10 30 -5 20 30 -5 30 30 0\n"
                       " 3 0 0 0 0 10 2 0 20 2 0 30 0\n 3 30 0 0 30 10 2 30 20 2 30 30 0\n"
                       " derivatives 1 0 30 6 0 30 6  1 0 30 6 0 30 6  1 30 0 6 30 0 -6\n"
                       "   2 30 0 6 30 0 0 30 0 -6\n"
                       " twists 0 0 5  0 0 -5  0 0 5  0 0 -4\n"
                       "coons-bicubic\n"
                       " 3 0 0 0 10 0 5 20 0 5 30 0 0\n 3 0 30 0 10 30 -5 20 30 -5 30 30 0\n"
                       " 3 0 0 0 0 10 2 0 20 2 0 30 0\n 3 30 0 0 30 10 2 30 20 2 30 30 0\n"
                       " twists 0 0 5  0 0 -5  0 0 5  0 0 -4\n";
    cs_surffile_t sf;
    cs_path_diag_t d;
    assert_int_equal(cs_surffile_parse(text, strlen(text), "c", 1, 0.01, &sf, &d), CS_OK);
    assert_int_equal(sf.n, 2);
    cs_vec3_t a[4] = {mm(0, 0, 0), mm(10, 0, 5), mm(20, 0, 5), mm(30, 0, 0)};
    cs_vec3_t b[4] = {mm(0, 30, 0), mm(10, 30, -5), mm(20, 30, -5), mm(30, 30, 0)};
    cs_vec3_t c[4] = {mm(0, 0, 0), mm(0, 10, 2), mm(0, 20, 2), mm(0, 30, 0)};
    cs_vec3_t e[4] = {mm(30, 0, 0), mm(30, 10, 2), mm(30, 20, 2), mm(30, 30, 0)};
    cs_vec3_t d0[2] = {mm(0, 30, 6), mm(0, 30, 6)}, d2[2] = {mm(30, 0, 6), mm(30, 0, -6)};
    cs_vec3_t d3[3] = {mm(30, 0, 6), mm(30, 0, 0), mm(30, 0, -6)};
    cs_bezier_t p1 = bz(3, a), p2 = bz(3, b), q1 = bz(3, c), q2 = bz(3, e);
    cs_bezier_t p1v = bz(1, d0), p2v = bz(1, d0), q1u = bz(1, d2), q2u = bz(2, d3);
    cs_vec3_t tw[2][2] = {{mm(0, 0, 5), mm(0, 0, 5)}, {mm(0, 0, -5), mm(0, 0, -4)}};
    cs_patch_t want;
    assert_int_equal(cs_coons_bicubic_twist(&p1, &p2, &q1, &q2, &p1v, &p2v, &q1u, &q2u,
                                            (const cs_vec3_t(*)[2])tw, &want),
                     CS_OK);
    assert_memory_equal(&sf.items[0].quad, &want, sizeof want);
    assert_int_equal(cs_coons_bicubic_twist(&p1, &p2, &q1, &q2, NULL, NULL, NULL, NULL,
                                            (const cs_vec3_t(*)[2])tw, &want),
                     CS_OK);
    assert_memory_equal(&sf.items[1].quad, &want, sizeof want);
    cs_surffile_free(&sf);
}

/* varady-scheme with a domain, user tangents and twists: the item carries them as given. */
static void test_varady_extras(void **state)
{
    (void)state;
    const char *text = "curvestep-surfaces 1\nvarady-scheme lambda-kappa side domain angles 3\n"
                       " 1 0 0 0 30 0 0\n 1 30 0 0 15 25 4\n 1 15 25 4 0 0 0\n"
                       " tangents 1 0 1 0 0 1 0.5  1 -1 0 0 -1 -1 0  1 1 -1 0 1 0 0\n"
                       " twists 0 0 0.1  0 0 -0.2  0.05 0 0\n";
    cs_surffile_t sf;
    cs_path_diag_t d;
    cs_err_t e = cs_surffile_parse(text, strlen(text), "v", 2.0, 0.01, &sf, &d);
    if (e != CS_OK)
        cs_path_diag_print(stderr, &d);
    assert_int_equal(e, CS_OK);
    const cs_varady_t *v = &sf.items[0].nside;
    assert_int_equal(v->domain, CS_VARADY_DOMAIN_ANGLES);
    assert_int_equal(v->blend, CS_VARADY_LAMBDA_KAPPA);
    assert_true(v->user_tan);
    assert_int_equal(v->tan[0].p[1].z, 32768); /* 0.5, not scaled */
    assert_true(v->twist[1][2] == -0.2 && v->twist[2][0] == 0.05);
    cs_surffile_free(&sf);
}

/* The keyword table (cs_surffile_keyword) is what the parser accepts and what docs/surfaces.md
 * lists in its "Native surface format" block, both ways (toolpath --help prints the table; the
 * CLI test test_inspect.sh compares it with the docs too). */
static void test_keywords(void **state)
{
    (void)state;
    size_t n = 0;
    for (; cs_surffile_keyword(n); n++) {
        char text[128];
        snprintf(text, sizeof text, "curvestep-surfaces 1\n%s x\n", cs_surffile_keyword(n));
        cs_surffile_t sf;
        cs_path_diag_t d;
        assert_int_not_equal(cs_surffile_parse(text, strlen(text), "k", 1, 0.01, &sf, &d), CS_OK);
        if (strstr(d.reason, "unknown surface"))
            fprintf(stderr, "'%s' is in the table but the parser refuses it\n",
                    cs_surffile_keyword(n));
        assert_null(strstr(d.reason, "unknown surface"));
        cs_surffile_free(&sf);
    }
    FILE *f = fopen("docs/surfaces.md", "r");
    assert_non_null(f);
    char line[256];
    bool in_section = false, in_block = false;
    size_t seen = 0;
    while (fgets(line, sizeof line, f)) {
        if (strncmp(line, "## ", 3) == 0)
            in_section = strncmp(line, "## Native surface format", 24) == 0;
        if (!in_section)
            continue;
        if (strncmp(line, "```", 3) == 0) {
            if (in_block)
                break;
            in_block = true;
            continue;
        }
        if (!in_block || line[0] == ' ' || line[0] == '#' ||
            strncmp(line, "curvestep-surfaces", 18) == 0)
            continue;
        char word[64];
        assert_int_equal(sscanf(line, "%63s", word), 1);
        size_t k = 0;
        while (cs_surffile_keyword(k) && strcmp(cs_surffile_keyword(k), word) != 0)
            k++;
        if (!cs_surffile_keyword(k))
            fprintf(stderr, "docs/surfaces.md lists '%s', the parser's table does not\n", word);
        assert_non_null(cs_surffile_keyword(k));
        assert_int_equal(k, seen); /* same order */
        seen++;
    }
    fclose(f);
    if (seen != n)
        fprintf(stderr, "docs/surfaces.md lists %zu keywords, the table %zu\n", seen, n);
    assert_int_equal(seen, n);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_all_kinds),
        cmocka_unit_test(test_varady),
        cmocka_unit_test(test_newell_fallback),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_keywords),
        cmocka_unit_test(test_varady_extras),
        cmocka_unit_test(test_coons_derivatives_twists),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
