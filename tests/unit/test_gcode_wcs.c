/* test_gcode_wcs: work coordinates, probing and the line-at-a-time session of the G-code reader
 * (host/cs_gcode_wcs.c, host/cs_gcode_feed.c, host/cs_gcode_words.c). Expected machine positions
 * are worked out by hand from the LinuxCNC G-code reference ("Coordinate Systems": program
 * coordinate = machine - (coordinate system offset + G92 offset); "G10 L2": the origin of system
 * P set to the axis words; "G10 L20": set so the current position gets the axis words; "G92":
 * the current point gets the axis words; "G28": a rapid to the axis words, then those axes to
 * #5161..; "G53": machine coordinates for one line; "G38.2": #5061.. the contact in program
 * coordinates, #5070 1 on success). Tolerance: a point read from the file is rounded once to
 * Q15.16 (0.5 LSB). The session is checked against cs_gcode_read of the same whole program.
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

#define LSB    (1.0 / 65536.0)
#define PT_TOL (0.5 * LSB + 1e-9)

static cs_path_t P;
static cs_path_diag_t D;

static cs_err_t parse_o(const char *text, const cs_gcode_opts_t *o)
{
    cs_path_free(&P);
    cs_path_init(&P);
    memset(&D, 0, sizeof D);
    return cs_gcode_read("t.nc", text, strlen(text), o, &P, &D, NULL);
}

static cs_err_t parse(const char *text)
{
    return parse_o(text, NULL);
}

/* The end of element k is at x, y, z (mm). */
static void end_at(size_t k, double x, double y, double z)
{
    assert_true(k < P.n);
    double p[3];
    cs_path_eval_mm(&P.elems[k].curve, 1.0, p);
    assert_float_equal(p[0], x, PT_TOL);
    assert_float_equal(p[1], y, PT_TOL);
    assert_float_equal(p[2], z, PT_TOL);
}

static void last_at(double x, double y, double z)
{
    assert_true(P.n > 0);
    end_at(P.n - 1, x, y, z);
}

static void test_g10_l2_and_coordinate_systems(void **state)
{
    (void)state;
    /* G55 (system 2) at X10 Y20: X1 Y1 there is machine 11, 21; back in G54 X1 Y1 is 1, 1. */
    assert_int_equal(parse("G10 L2 P2 X10 Y20\nG55 G0 X1 Y1\nG54 X1 Y1\n"), CS_OK);
    assert_int_equal(P.n, 2);
    end_at(0, 11, 21, 0);
    end_at(1, 1, 1, 0);
    /* P0 is the system in use; G91 does not change what L2 sets; inches scale the offset. */
    assert_int_equal(parse("G56\nG91 G10 L2 P0 X3\nG90 G0 X1\nG20 G10 L2 P0 X1\nG0 X0\n"), CS_OK);
    end_at(0, 4, 0, 0);
    last_at(25.4, 0, 0);
    /* G59.3 is system 9; its X is #5381 (5221 + 20 * 8). */
    assert_int_equal(parse("G10 L2 P9 X-7\nG59.3 G0 X0\nG54 G0 X#5381\n"), CS_OK);
    end_at(0, -7, 0, 0);
    last_at(-7, 0, 0);
    /* The offsets are parameters: G56's X (#5261) set by G10 is read back. */
    assert_int_equal(parse("G10 L2 P3 X7.5\nG0 X#5261 Y#5220\n"), CS_OK);
    last_at(7.5, 1, 0);
}

static void test_g10_l20(void **state)
{
    (void)state;
    /* At machine 5, 5: G10 L20 P1 X0 Y0 makes it 0, 0 in G54, so X1 Y1 is machine 6, 6. */
    assert_int_equal(parse("G0 X5 Y5\nG10 L20 P1 X0 Y0\nG0 X1 Y1\n"), CS_OK);
    last_at(6, 6, 0);
    /* With a G92 offset of 2 in X in force, L20 leaves it out: program X2 is still machine 5. */
    assert_int_equal(parse("G0 X5\nG92 X3\nG10 L20 P1 X0\nG0 X2\nG92.1\nG0 X0\n"), CS_OK);
    end_at(1, 7, 0, 0); /* G10 L20: system 1 at 5 - 2 - 0 = 3; program 2 is 2 + 3 + 2 */
    last_at(3, 0, 0);
}

static void test_g92_family(void **state)
{
    (void)state;
    /* G92 X0 at machine 5: offset 5. G92.2: offsets off (X1 = machine 1), parameters kept;
     * G92.3: back on (X2 = 7); G92.1: off and zeroed (X3 = 3; G92.3 then restores zeros). */
    assert_int_equal(parse("G0 X5\nG92 X0\nG0 X1\nG92.2\nG0 X1\nG92.3\nG0 X2\nG92.1\nG0 X3\n"
                           "G92.3\nG0 X4\n"),
                     CS_OK);
    assert_int_equal(P.n, 6);
    end_at(1, 6, 0, 0);
    end_at(2, 1, 0, 0);
    end_at(3, 7, 0, 0);
    end_at(4, 3, 0, 0);
    end_at(5, 4, 0, 0);
    /* G92 on top of G55 (X10): at machine 12, G92 X0 makes the program X 0; #5211 is 2. */
    assert_int_equal(parse("G10 L2 P2 X10\nG55 G0 X2\nG92 X0\nG0 X1 Y#5211 Z#5210\n"), CS_OK);
    last_at(13, 2, 1);
    /* A bare G92 stays an error (LinuxCNC). */
    assert_int_equal(parse("G92\n"), CS_ERR_PARSE);
}

static void test_g28_g30_g53(void **state)
{
    (void)state;
    /* G28.1 stores 10, 10, 0; G28 X5 goes to X5 (Y where it is), then X to 10. */
    assert_int_equal(parse("G0 X10 Y10\nG28.1\nG0 X0 Y0\nG28 X5\nG28\n"), CS_OK);
    assert_int_equal(P.n, 5);
    end_at(2, 5, 0, 0);
    end_at(3, 10, 0, 0);
    last_at(10, 10, 0); /* bare G28: every axis home */
    /* G30 with its own home, through an offset: G30 Y1 in G54 X100 passes machine (100.., 1). */
    assert_int_equal(parse("G0 Z-3\nG30.1\nG10 L2 P1 X100\nG0 X0\nG30 Y1\n"), CS_OK);
    end_at(P.n - 2, 100, 1, -3);
    last_at(100, 0, -3);
    /* G53: one line in machine coordinates, the offset back on the next line. */
    assert_int_equal(parse("G10 L2 P1 X100\nG0 X1\nG53 G0 X1\nG1 X2 F60\n"), CS_OK);
    end_at(0, 101, 0, 0);
    end_at(1, 1, 0, 0);
    last_at(102, 0, 0);
    /* G53 needs G0 or G1. */
    assert_int_equal(parse("G53 X1\n"), CS_ERR_PARSE);
    assert_int_equal(parse("G1 X1 F60\nG53 G2 X2 R1\n"), CS_ERR_PARSE);
    /* Two words of one modal group, two non-modal codes: errors at the second word. */
    assert_int_equal(parse("G90 G91 X1\n"), CS_ERR_PARSE);
    assert_int_equal(D.loc.col, 5);
    assert_int_equal(parse("G28 G92 X1\n"), CS_ERR_PARSE);
    assert_int_equal(parse("G10 L1 P1 X1\n"), CS_ERR_UNSUPPORTED);
    assert_int_equal(parse("G10 L2 P10 X1\n"), CS_ERR_PARSE);
}

/* A probe that touches the plane z = PROBE_Z (machine). */
#define PROBE_Z (-3.0)
static int probe_calls;
static cs_err_t fake_probe(void *ctx, int code, const double from[3], const double to[3],
                           double feed, bool *contact, double hit[3])
{
    (void)ctx;
    (void)code;
    probe_calls++;
    assert_true(feed > 0);
    memcpy(hit, to, 3 * sizeof *hit);
    *contact = from[2] > PROBE_Z && to[2] <= PROBE_Z;
    if (*contact)
        hit[2] = PROBE_Z;
    return CS_OK;
}

static void test_probe(void **state)
{
    (void)state;
    cs_gcode_opts_t o;
    cs_gcode_opts_init(&o);
    o.probe = fake_probe;
    probe_calls = 0;
    /* G92 Z10 at machine 0: program = machine + 10. G38.2 Z-10 aims at machine -20 and stops at
     * -3: #5063 = -3 + 10 = 7, #5070 = 1; the next move starts at the contact. */
    assert_int_equal(parse_o("G92 Z10\nG38.2 Z-10 F100\nG1 X#5063 Y#5070\n", &o), CS_OK);
    assert_int_equal(probe_calls, 1);
    assert_int_equal(P.n, 1);
    double a[3];
    cs_path_eval_mm(&P.elems[0].curve, 0.0, a);
    assert_float_equal(a[2], PROBE_Z, PT_TOL);
    last_at(7, 1, PROBE_Z);
    /* No contact: G38.2 is an error, G38.3 is not (#5070 = 0, the machine at the target). */
    assert_int_equal(parse_o("G38.2 Z-1 F100\n", &o), CS_ERR_STATE);
    assert_int_equal(parse_o("G38.3 Z-1 F100\nG1 X#5070 Y1\n", &o), CS_OK);
    last_at(0, 1, -1);
    /* Without a feed: an error before any probing. */
    probe_calls = 0;
    assert_int_equal(parse_o("G38.2 Z-5\n", &o), CS_ERR_PARSE);
    assert_int_equal(probe_calls, 0);
    /* Without a probe (a file to plan): unsupported. */
    assert_int_equal(parse("G38.2 Z-5 F100\n"), CS_ERR_UNSUPPORTED);
}

/* Feeds text line by line into a session; the elements into P. */
static cs_err_t feed_all(cs_gcode_session_t *s, const char *text, unsigned *lines_out)
{
    cs_err_t e = CS_OK;
    unsigned no = 0;
    bool ended = false;
    for (const char *p = text; *p && e == CS_OK && !ended;) {
        size_t n = strcspn(p, "\n");
        e = cs_gcode_feed(s, p, n, ++no, &P, &D, &ended);
        p += n + (p[n] == '\n');
    }
    if (lines_out)
        *lines_out = no;
    return e;
}

static char *slurp(const char *name)
{
    FILE *f = fopen(name, "rb");
    assert_non_null(f);
    char *b = calloc(1, 1 << 16);
    assert_non_null(b);
    size_t n = fread(b, 1, (1 << 16) - 1, f);
    fclose(f);
    b[n] = '\0';
    return b;
}

/* The sub-and-loop sample fed a line at a time gives the very elements the whole read gives. */
static void test_session_matches_whole_read(void **state)
{
    (void)state;
    char *text = slurp("tests/data/gcode/linuxcnc-sub-loop.ngc");
    cs_path_t whole;
    cs_path_init(&whole);
    assert_int_equal(cs_gcode_read("w", text, strlen(text), NULL, &whole, &D, NULL), CS_OK);
    cs_path_free(&P);
    cs_path_init(&P);
    cs_gcode_session_t *s = cs_gcode_session_new("s", NULL);
    assert_non_null(s);
    assert_int_equal(feed_all(s, text, NULL), CS_OK);
    assert_int_equal(P.n, whole.n);
    assert_true(P.n >= 17);
    for (size_t k = 0; k < P.n; k++) {
        assert_int_equal(P.elems[k].curve.degree, whole.elems[k].curve.degree);
        assert_memory_equal(P.elems[k].curve.p, whole.elems[k].curve.p,
                            sizeof P.elems[k].curve.p[0] * (P.elems[k].curve.degree + 1u));
        assert_int_equal(P.elems[k].rapid, whole.elems[k].rapid);
        assert_int_equal(P.elems[k].loc.line, whole.elems[k].loc.line); /* client lines */
    }
    cs_gcode_session_free(s);
    cs_path_free(&whole);
    free(text);
}

static void test_session_state_carries(void **state)
{
    (void)state;
    cs_path_free(&P);
    cs_path_init(&P);
    cs_gcode_session_t *s = cs_gcode_session_new("s", NULL);
    assert_non_null(s);
    /* Parameters and offsets set on one line are there on the next. */
    assert_int_equal(feed_all(s, "#1=5\nG10 L2 P2 X100\nG55\nG0 X#1\n", NULL), CS_OK);
    last_at(105, 0, 0);
    cs_gcode_state_t st;
    cs_gcode_state(s, &st);
    assert_int_equal(st.wcs, 2);
    assert_float_equal(st.off[0], 100, 1e-12);
    assert_float_equal(cs_gcode_param(s, 5241), 100, 1e-12);
    /* A sub defined over three lines, called later: nothing runs until the call. */
    size_t n0 = P.n;
    assert_int_equal(feed_all(s, "o7 sub\nG0 Y[#1*2]\no7 endsub\n", NULL), CS_OK);
    assert_int_equal(P.n, n0);
    cs_gcode_state(s, &st);
    assert_false(st.holding);
    bool ended;
    assert_int_equal(cs_gcode_feed(s, "o7 call [4]", 11, 20, &P, &D, &ended), CS_OK);
    last_at(105, 8, 0);
    assert_int_equal(P.elems[P.n - 1].loc.line, 2); /* the sub's line, as the client sent it */
    /* An open block holds its lines; an error inside it is reported on the client's line. */
    assert_int_equal(cs_gcode_feed(s, "o8 if [1]", 9, 30, &P, &D, &ended), CS_OK);
    cs_gcode_state(s, &st);
    assert_true(st.holding);
    assert_int_equal(cs_gcode_feed(s, "G0 X[1/0]", 9, 31, &P, &D, &ended), CS_OK);
    assert_int_equal(cs_gcode_feed(s, "o8 endif", 8, 32, &P, &D, &ended), CS_ERR_RANGE);
    assert_int_equal(D.loc.line, 31);
    cs_gcode_state(s, &st);
    assert_false(st.holding);
    assert_float_equal(st.pos[1], 8, PT_TOL); /* the state is as before the block */
    /* Undo: the last line's modal change taken back. */
    assert_int_equal(cs_gcode_feed(s, "G91", 3, 40, &P, &D, &ended), CS_OK);
    cs_gcode_state(s, &st);
    assert_true(st.incr);
    assert_true(cs_gcode_undo(s));
    cs_gcode_state(s, &st);
    assert_false(st.incr);
    assert_false(cs_gcode_undo(s));
    /* M2: ended, back in G54 and the start modes; offsets and parameters kept. */
    assert_int_equal(cs_gcode_feed(s, "G20 G91 M2", 10, 50, &P, &D, &ended), CS_OK);
    assert_true(ended);
    cs_gcode_state(s, &st);
    assert_int_equal(st.wcs, 1);
    assert_false(st.incr);
    assert_false(st.inch);
    assert_float_equal(cs_gcode_param(s, 5241), 100, 1e-12);
    assert_float_equal(cs_gcode_param(s, 1), 5, 1e-12);
    cs_gcode_session_free(s);
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
        cmocka_unit_test(test_g10_l2_and_coordinate_systems),
        cmocka_unit_test(test_g10_l20),
        cmocka_unit_test(test_g92_family),
        cmocka_unit_test(test_g28_g30_g53),
        cmocka_unit_test(test_probe),
        cmocka_unit_test(test_session_matches_whole_read),
        cmocka_unit_test(test_session_state_carries),
    };
    return cmocka_run_group_tests(tests, NULL, teardown);
}
