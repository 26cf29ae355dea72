/* Tests of cs_machine_ini: the built-in plotter, every key read and converted to the core's
 * formats (compared with the decimal value in double, within 1 LSB), the optional a axis, and
 * errors reported as file:line: reason (unknown key, bad value, unknown section, a rate the
 * executor cannot step, a missing file), and the host-only [pen] section (mode, heights, their
 * checks against the z travel). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_machine_ini.h"
#include "cs_planner.h"

#define Q16 65536.0

static void test_default_is_a_valid_80_steps_plotter(void **state)
{
    (void)state;
    cs_machine_t m;
    cs_machine_ini_default(&m);
    assert_int_equal(m.n_axes, 3);
    for (unsigned i = 0; i < 3; i++)
        assert_true(fabs(m.axis[i].steps_per_mm / Q16 - 80.0) <= 1 / Q16);
    cs_planner_t pl;
    assert_int_equal(cs_planner_init(&pl, &m), CS_OK);
    /* Parsing an empty file gives the default. */
    cs_machine_t e;
    char err[256];
    assert_int_equal(cs_machine_ini_parse("", "empty.ini", &e, err, sizeof err), 0);
    assert_memory_equal(&e, &m, sizeof m);
}

static const char *full = "; a small CNC\n"
                          "[machine]\n"
                          "tick_hz = 200000\n"
                          "segment_ms = 4\n"
                          "tolerance = 0.005\n"
                          "junction_deviation = 0.02\n"
                          "default_feed = 25.5\n"
                          "\n"
                          "[x]\n"
                          "steps_per_mm = 100.25\n"
                          "max_rate = 150\n"
                          "max_accel = 1500.5\n"
                          "travel_min = -10\n"
                          "travel_max = 300.125\n"
                          "invert_dir = true\n"
                          "pulse_us = 7\n"
                          "[z]\n"
                          "steps_per_mm = 400\n"
                          "max_rate = 10\n"
                          "max_accel = 200\n"
                          "[a]\n"
                          "steps_per_mm = 8.8888\n"
                          "max_rate = 360\n"
                          "max_accel = 3600\n"
                          "travel_min = -4000\n"
                          "travel_max = 4000\n";

static void close_to(int32_t q, double want)
{
    assert_true(fabs(q / Q16 - want) <= 1.0 / Q16);
}

static void test_every_key_read(void **state)
{
    (void)state;
    cs_machine_t m;
    char err[256];
    int rc = cs_machine_ini_parse(full, "cnc.ini", &m, err, sizeof err);
    if (rc != 0)
        print_message("%s\n", err);
    assert_int_equal(rc, 0);
    assert_int_equal(m.n_axes, 4);
    assert_int_equal(m.tick_hz, 200000);
    assert_int_equal(m.segment_ticks, 800);
    close_to(m.tolerance, 0.005);
    close_to(m.junction_deviation, 0.02);
    close_to(m.default_feed, 25.5);
    close_to(m.axis[0].steps_per_mm, 100.25);
    close_to(m.axis[0].max_rate, 150);
    close_to(m.axis[0].max_accel, 1500.5);
    close_to(m.axis[0].travel_min, -10);
    close_to(m.axis[0].travel_max, 300.125);
    assert_true(m.axis[0].invert_dir);
    assert_int_equal(m.axis[0].pulse_ticks, 2); /* 7 us at 200 kHz = 1.4 ticks, rounded up */
    close_to(m.axis[1].steps_per_mm, 80);       /* y untouched: default */
    assert_false(m.axis[1].invert_dir);
    close_to(m.axis[2].steps_per_mm, 400);
    close_to(m.axis[2].max_rate, 10);
    close_to(m.axis[3].steps_per_mm, 8.8888);
    close_to(m.axis[3].travel_min, -4000);
}

static void expect_error(const char *text, const char *want)
{
    cs_machine_t m;
    char err[256] = "";
    assert_int_equal(cs_machine_ini_parse(text, "bad.ini", &m, err, sizeof err), -1);
    if (strstr(err, want) == NULL)
        print_message("got '%s', want '%s'\n", err, want);
    assert_non_null(strstr(err, want));
}

static void test_errors_name_file_and_line(void **state)
{
    (void)state;
    expect_error("[machine]\ntick_hz = 100000\nspeed = 3\n",
                 "bad.ini:3: [machine] speed: unknown key");
    expect_error("[x]\n\nsteps_per_mm = eighty\n", "bad.ini:3: [x] steps_per_mm: not a number");
    expect_error("[x]\nmax_rate = -5\n", "bad.ini:2: [x] max_rate: must be in (0, 32768) mm/s");
    expect_error("[w]\nmax_rate = 5\n", "bad.ini:2: [w]: unknown section");
    expect_error("[machine]\nprofile = bumpy\n", "bad.ini:2: [machine] profile");
    expect_error("[x]\ninvert_dir = maybe\n", "bad.ini:2: [x] invert_dir");
    expect_error("[x]\nthis line has no equals sign\n", "bad.ini:2: syntax error");
    /* 1000 mm/s at 80 steps/mm is 80000 steps/s: more than 100 kHz / 2 allows. */
    expect_error("[x]\nmax_rate = 1000\n", "bad.ini:0: machine rejected");
    expect_error("[y]\ntravel_min = 10\ntravel_max = 5\n", "bad.ini:0: [y] travel_min is above");
    cs_machine_t m;
    char err[256];
    assert_int_equal(cs_machine_ini_load("/nonexistent/m.ini", &m, err, sizeof err), -1);
    assert_non_null(strstr(err, "/nonexistent/m.ini:0: cannot read"));
}

static void test_load_from_file(void **state)
{
    (void)state;
    char path[] = "/tmp/cs_test_machine_XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    FILE *f = fdopen(fd, "w");
    fputs(full, f);
    fclose(f);
    cs_machine_t m;
    char err[256];
    assert_int_equal(cs_machine_ini_load(path, &m, err, sizeof err), 0);
    close_to(m.axis[0].steps_per_mm, 100.25);
    remove(path);
}

/* [pen]: absent = mode none; mode = z with both heights read exactly (mm, as written); the plain
 * parser accepts the section too; every bad [pen] named with file and line. */
static void test_pen_section(void **state)
{
    (void)state;
    cs_machine_t m;
    cs_machine_pen_t pen;
    char err[256] = "";
    pen.mode = CS_MACHINE_PEN_Z;
    assert_int_equal(cs_machine_ini_parse_pen("", "p.ini", &m, &pen, err, sizeof err), 0);
    assert_int_equal(pen.mode, CS_MACHINE_PEN_NONE);
    const char *z = "[z]\ntravel_min = -20\ntravel_max = 30\n[pen]\nmode = Z\nup_z = 12.5\n"
                    "down_z = -3.25\n";
    assert_int_equal(cs_machine_ini_parse_pen(z, "p.ini", &m, &pen, err, sizeof err), 0);
    assert_int_equal(pen.mode, CS_MACHINE_PEN_Z);
    assert_true(fabs(pen.up_z_mm - 12.5) <= 1e-12);
    assert_true(fabs(pen.down_z_mm + 3.25) <= 1e-12);
    /* The other keys are unchanged by [pen]. */
    close_to(m.axis[2].travel_min, -20);
    assert_int_equal(cs_machine_ini_parse(z, "p.ini", &m, err, sizeof err), 0);
    assert_int_equal(
        cs_machine_ini_parse_pen("[pen]\nmode = none\n", "p.ini", &m, &pen, err, sizeof err), 0);
    assert_int_equal(pen.mode, CS_MACHINE_PEN_NONE);

    expect_error("[pen]\nmode = lift\n", "bad.ini:2: [pen] mode: expected none, z or servo");
    expect_error("[pen]\nmode = z\nheight = 3\n", "bad.ini:3: [pen] height: unknown key");
    expect_error("[pen]\nup_z = high\n", "bad.ini:2: [pen] up_z: must be a number");
    expect_error("[pen]\ndown_z = 5000\n", "bad.ini:2: [pen] down_z: must be a number in");
    expect_error("[pen]\nmode = z\nup_z = 5\n", "bad.ini:0: [pen] mode = z needs both");
    expect_error("[pen]\nmode = z\nup_z = 5\ndown_z = 5\n", "bad.ini:0: [pen] up_z and down_z");
    /* Default z travel is -100..100 mm. */
    expect_error("[pen]\nmode = z\nup_z = 101\ndown_z = 0\n",
                 "bad.ini:0: [pen] up_z = 101 mm is outside the z travel [-100, 100] mm");
    expect_error("[z]\ntravel_min = 0\n[pen]\nmode = z\nup_z = 5\ndown_z = -0.5\n",
                 "bad.ini:0: [pen] down_z = -0.5 mm is outside the z travel [0, 100] mm");
    /* Heights are only checked when used: mode none ignores them. */
    assert_int_equal(
        cs_machine_ini_parse_pen("[pen]\nup_z = 101\n", "p.ini", &m, &pen, err, sizeof err), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_default_is_a_valid_80_steps_plotter),
        cmocka_unit_test(test_every_key_read),
        cmocka_unit_test(test_errors_name_file_and_line),
        cmocka_unit_test(test_load_from_file),
        cmocka_unit_test(test_pen_section),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
