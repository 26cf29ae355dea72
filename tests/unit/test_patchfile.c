/* test_patchfile: the Newell patch reader on the Utah teapot (tests/data/teapot, counts and
 * values checked against the file read here independently with sscanf) and on broken inputs,
 * each refused with the right code at the right line and column. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_patchfile.h"

#define TEAPOT "tests/data/teapot/newell_teapot.txt"

static void test_teapot(void **state)
{
    (void)state;
    cs_patchfile_t pf;
    cs_path_diag_t d;
    assert_int_equal(cs_patchfile_read(TEAPOT, &pf, &d), CS_OK);
    assert_int_equal(pf.npatches, 32);
    assert_int_equal(pf.nverts, 306);
    /* Independent read: every line of the file, patch lines 2..33, vertices 35..340. */
    FILE *f = fopen(TEAPOT, "r");
    assert_non_null(f);
    char line[256];
    unsigned ln = 0;
    while (fgets(line, sizeof line, f)) {
        ln++;
        if (ln >= 2 && ln <= 33) {
            int k[16];
            assert_int_equal(sscanf(line, "%d,%d,%d,%d,%d,%d,%d,%d,%d,%d,%d,%d,%d,%d,%d,%d", &k[0],
                                    &k[1], &k[2], &k[3], &k[4], &k[5], &k[6], &k[7], &k[8], &k[9],
                                    &k[10], &k[11], &k[12], &k[13], &k[14], &k[15]),
                             16);
            for (int j = 0; j < 16; j++)
                assert_int_equal(pf.idx[ln - 2][j], (size_t)(k[j] - 1));
            assert_int_equal(pf.line[ln - 2], ln);
        } else if (ln >= 35) {
            double x, y, z;
            assert_int_equal(sscanf(line, "%lf,%lf,%lf", &x, &y, &z), 3);
            assert_true(pf.vert[ln - 35][0] == x && pf.vert[ln - 35][1] == y &&
                        pf.vert[ln - 35][2] == z);
            assert_int_equal(pf.vert_line[ln - 35], ln);
        }
    }
    fclose(f);
    assert_int_equal(ln, 340);
    /* Patch conversion: 10 mm per unit, each coordinate within 0.5 LSB. */
    for (size_t i = 0; i < pf.npatches; i++) {
        cs_patch_t p;
        assert_int_equal(cs_patchfile_patch(&pf, i, 10.0, &p, &d), CS_OK);
        assert_int_equal(p.deg_u, 3);
        for (int k = 0; k < 16; k++) {
            const double *q = pf.vert[pf.idx[i][k]];
            const cs_vec3_t *c = &p.p[k / 4][k % 4];
            assert_true(fabs(c->x / 65536.0 - 10 * q[0]) <= 0.5 / 65536 + 1e-12);
            assert_true(fabs(c->y / 65536.0 - 10 * q[1]) <= 0.5 / 65536 + 1e-12);
            assert_true(fabs(c->z / 65536.0 - 10 * q[2]) <= 0.5 / 65536 + 1e-12);
        }
    }
    /* 3.4 units * 2000 mm leaves the 4096 mm range: refused at the vertex's line. */
    cs_patch_t p;
    assert_int_equal(cs_patchfile_patch(&pf, 0, 2000.0, &p, &d), CS_ERR_RANGE);
    assert_int_equal(d.loc.line >= 35, 1);
    assert_string_equal(d.loc.file, TEAPOT);
    cs_patchfile_free(&pf);
    cs_patchfile_free(&pf); /* twice is fine */
}

/* One small valid file: 1 patch on vertices 1..16 of a 4 x 4 grid. */
static char *grid_file(const char *patch_line, const char *count, int nverts, const char *extra)
{
    static char buf[4096];
    int n = snprintf(buf, sizeof buf, "1\n%s\n%s\n", patch_line, count);
    for (int i = 0; i < nverts; i++)
        n += snprintf(buf + n, sizeof buf - (size_t)n, "%d, %d ,0.5\n", i % 4, i / 4);
    snprintf(buf + n, sizeof buf - (size_t)n, "%s", extra);
    return buf;
}

static const char *IDX16 = "1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16";

static void expect(const char *text, cs_err_t code, unsigned line, unsigned col, const char *words)
{
    cs_patchfile_t pf;
    cs_path_diag_t d;
    cs_err_t e = cs_patchfile_parse(text, strlen(text), "t.txt", &pf, &d);
    if (e != code || d.loc.line != line || d.loc.col != col || !strstr(d.reason, words))
        fprintf(stderr, "got %d %s:%u:%u: %s\n", e, d.loc.file, d.loc.line, d.loc.col, d.reason);
    assert_int_equal(e, code);
    assert_string_equal(d.loc.file, "t.txt");
    assert_int_equal(d.loc.line, line);
    assert_int_equal(d.loc.col, col);
    assert_non_null(strstr(d.reason, words));
    cs_patchfile_free(&pf);
}

static void test_small_and_errors(void **state)
{
    (void)state;
    cs_patchfile_t pf;
    cs_path_diag_t d;
    const char *ok = grid_file(IDX16, "16", 16, "\n\n");
    assert_int_equal(cs_patchfile_parse(ok, strlen(ok), "t.txt", &pf, &d), CS_OK);
    assert_int_equal(pf.npatches, 1);
    assert_int_equal(pf.nverts, 16);
    cs_patch_t p;
    assert_int_equal(cs_patchfile_patch(&pf, 0, 1.0, &p, &d), CS_OK);
    assert_int_equal(p.p[2][1].x, 1 * 65536);
    assert_int_equal(p.p[2][1].y, 2 * 65536);
    assert_int_equal(p.p[2][1].z, 32768);
    assert_int_equal(cs_patchfile_patch(&pf, 1, 1.0, &p, &d), CS_ERR_ARG);
    cs_patchfile_free(&pf);
    /* Blanks as separators, blank lines skipped, CRLF accepted. */
    const char *spaced = "\n1\r\n1 2 3 4 1 2 3 4 1 2 3 4 1 2 3 4\r\n\n4\n0 0 0\n1,0,0\n"
                         "0,1,0\n1 , 1 , 1\n";
    assert_int_equal(cs_patchfile_parse(spaced, strlen(spaced), "s", &pf, &d), CS_OK);
    assert_int_equal(pf.idx[0][15], 3);
    assert_true(pf.vert[3][0] == 1 && pf.vert[3][2] == 1);
    cs_patchfile_free(&pf);

    /* empty, BOM-only, blank: "no drawable geometry" (issue 15 item 9), never a parse error */
    expect("", CS_ERR_EMPTY, 1, 1, "no drawable geometry");
    expect("\xEF\xBB\xBF", CS_ERR_EMPTY, 1, 1, "no drawable geometry");
    expect(" \n\r\n\t", CS_ERR_EMPTY, 1, 1, "no drawable geometry");
    expect("\xEF\xBB\xBFx\n", CS_ERR_PARSE, 1, 1, "not a finite number"); /* BOM skipped */
    expect("x\n", CS_ERR_PARSE, 1, 1, "not a finite number");
    expect("1.5\n", CS_ERR_PARSE, 1, 1, "patch count");
    expect("0\n", CS_ERR_RANGE, 1, 1, "outside");
    expect("2 3\n", CS_ERR_PARSE, 1, 1, "one integer");
    expect(grid_file("1,2,3,4,5,6,7,8,9,10,11,12,13,14,15", "16", 16, ""), CS_ERR_PARSE, 2, 36,
           "found 15");
    expect(grid_file("1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17", "17", 17, ""), CS_ERR_PARSE, 2,
           42, "more than 16");
    expect(grid_file("1,2,3,4,5,6,7,8,9,10,11,12,13,14,,16", "16", 16, ""), CS_ERR_PARSE, 2, 34,
           "empty field");
    expect(grid_file("1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,", "16", 16, ""), CS_ERR_PARSE, 2, 40,
           "after the last ','");
    expect(grid_file("0,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16", "16", 16, ""), CS_ERR_RANGE, 2, 1,
           "one-based");
    expect(grid_file("1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,2.5", "16", 16, ""), CS_ERR_PARSE, 2, 37,
           "integer");
    /* An index too large for any vertex table (found by fuzz_patchfile: it overflowed size_t). */
    expect(grid_file("1,2,3,4,5,6,7,8,888888888888888888888888888888888889,10,11,12,13,14,15,16",
                     "16", 16, ""),
           CS_ERR_RANGE, 2, 17, "one-based");
    /* Index 17 of 16 vertices: at the index itself. */
    expect(grid_file("1,2,3,4,5,6,7,8,9,10,11,12,13,17,15,16", "16", 16, ""), CS_ERR_RANGE, 2, 31,
           "17 outside 1..16");
    expect(grid_file(IDX16, "16", 15, ""), CS_ERR_PARSE, 19, 1, "15 of 16 vertices");
    expect(grid_file(IDX16, "16", 16, "1,2,3\n"), CS_ERR_PARSE, 20, 1, "after the last");
    expect("1\n1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1\n1\n1,2\n", CS_ERR_PARSE, 4, 4, "found 2");
    expect("1\n1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1\n1\n1,2,nan\n", CS_ERR_PARSE, 4, 5,
           "not a finite number");
    expect("1\n1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1\n1\n1,2,1e999\n", CS_ERR_RANGE, 4, 5,
           "not a finite number");
    expect("1\n1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1\n", CS_ERR_PARSE, 3, 1, "vertex count");
    /* Missing file. */
    assert_int_equal(cs_patchfile_read("tests/data/teapot/no_such_file", &pf, &d), CS_ERR_IO);
    assert_string_equal(d.loc.file, "tests/data/teapot/no_such_file");
    cs_patchfile_free(&pf);
}

/* Writing then reading gives the patches back (6 decimals of a 2^-16 mm grid: 0.5 LSB). */
static void test_write_roundtrip(void **state)
{
    (void)state;
    cs_patchfile_t pf;
    cs_path_diag_t d;
    assert_int_equal(cs_patchfile_read(TEAPOT, &pf, &d), CS_OK);
    cs_patch_t p[32];
    for (size_t i = 0; i < 32; i++)
        assert_int_equal(cs_patchfile_patch(&pf, i, 10.0, &p[i], &d), CS_OK);
    cs_patchfile_free(&pf);
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    assert_non_null(f);
    assert_int_equal(cs_patchfile_write(f, p, 32), CS_OK);
    fclose(f);
    assert_int_equal(cs_patchfile_parse(buf, len, "mem", &pf, &d), CS_OK);
    assert_int_equal(pf.npatches, 32);
    assert_int_equal(pf.nverts, 512);
    for (size_t i = 0; i < 32; i++) {
        cs_patch_t q;
        assert_int_equal(cs_patchfile_patch(&pf, i, 1.0, &q, &d), CS_OK);
        assert_memory_equal(&q, &p[i], sizeof q);
    }
    cs_patchfile_free(&pf);
    free(buf);
    p[3].deg_v = 2;
    f = open_memstream(&buf, &len);
    assert_int_equal(cs_patchfile_write(f, p, 32), CS_ERR_DEGREE);
    fclose(f);
    free(buf);
}

/* The .bpt format (issue 15 item 8): the teapot written as .bpt (tests/data/teapot/teapot.bpt,
 * the same numbers as Newell's file, converted by a script) gives bit for bit the patches of
 * Newell's file; patches of other degrees; errors name the format tried and what it expects. */
static void test_bpt(void **state)
{
    (void)state;
    cs_patchfile_t nw, bp;
    cs_path_diag_t d;
    assert_int_equal(cs_patchfile_read(TEAPOT, &nw, &d), CS_OK);
    assert_int_equal(cs_patchfile_read("tests/data/teapot/teapot.bpt", &bp, &d), CS_OK);
    assert_false(nw.bpt);
    assert_true(bp.bpt);
    assert_int_equal(bp.npatches, 32);
    for (size_t i = 0; i < 32; i++) {
        cs_patch_t a, b;
        assert_int_equal(cs_patchfile_patch(&nw, i, 10.0, &a, &d), CS_OK);
        assert_int_equal(cs_patchfile_patch(&bp, i, 10.0, &b, &d), CS_OK);
        assert_memory_equal(&a, &b, sizeof a);
        assert_int_equal(bp.line[i], 2 + 17 * i);
    }
    cs_patchfile_free(&nw);
    cs_patchfile_free(&bp);
    /* A 1 x 2 patch: point k = i (degv + 1) + j, i along u. */
    const char *small = "1\n1 2\n0 0 0\n0 1 0\n0 2 1\n1 0 0\n1 1 0\n1 2 1.5\n";
    assert_int_equal(cs_patchfile_parse(small, strlen(small), "s.bpt", &bp, &d), CS_OK);
    cs_patch_t p;
    assert_int_equal(cs_patchfile_patch(&bp, 0, 2.0, &p, &d), CS_OK);
    assert_int_equal(p.deg_u, 1);
    assert_int_equal(p.deg_v, 2);
    assert_int_equal(p.p[1][2].x, 2 * 65536);
    assert_int_equal(p.p[1][2].y, 4 * 65536);
    assert_int_equal(p.p[1][2].z, 3 * 65536);
    assert_int_equal(p.p[0][1].y, 2 * 65536);
    cs_patchfile_free(&bp);
    expect("1\n3 8\n", CS_ERR_DEGREE, 2, 3, "degree 8 outside 1..7 (.bpt format)");
    expect("1\n1 2 3\n", CS_ERR_PARSE, 2, 6, "16 vertex indices (Newell's format; a .bpt file");
    expect("2\n1 1\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n1 1 1\n", CS_ERR_PARSE, 7, 6,
           "expected 'degu degv' (.bpt format), found 3");
    expect("1\n1 1\n0 0 0\n1 0 0\n0 1 0\n", CS_ERR_PARSE, 6, 1, "end of file after 3 of 4");
    expect("1\n1 1\n0 0 0\n1 0 0\n0 1 0\n1 1\n", CS_ERR_PARSE, 6, 4, "expected x,y,z");
    expect("1\n1 1\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n9\n", CS_ERR_PARSE, 7, 1, "after the last patch");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_teapot),
        cmocka_unit_test(test_small_and_errors),
        cmocka_unit_test(test_write_roundtrip),
        cmocka_unit_test(test_bpt),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
