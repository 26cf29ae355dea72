/* Tests of cs_gpio_cfg (the [gpio] section of the machine file): the defaults (pulse from the
 * machine's own), every key read and converted, errors as file:line: reason (unknown key, bad
 * offset, a line used twice, STEP without DIR, an axis the machine lacks, a pulse that does
 * not fit half the shortest step period), the chip names a user may type, and the machine
 * reader accepting the section while still refusing unknown ones. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cs_gpio_cfg.h"
#include "cs_machine_ini.h"

static void test_defaults(void **state)
{
    (void)state;
    cs_machine_t m;
    cs_machine_ini_default(&m);
    cs_gpio_cfg_t c;
    cs_gpio_cfg_default(&c, &m);
    for (unsigned i = 0; i < CS_AXES; i++) {
        assert_int_equal(c.step[i], -1);
        assert_int_equal(c.dir[i], -1);
        assert_false(cs_gpio_cfg_wired(&c, i));
    }
    assert_int_equal(c.enable, -1);
    assert_string_equal(c.chip, "");
    assert_false(c.step_active_low);
    assert_true(c.enable_active_low);
    /* the built-in machine's pulse: 2 us rounded up to one 100 kHz tick = 10 us */
    assert_int_equal(m.axis[0].pulse_ticks, 1);
    assert_int_equal(c.pulse_ns, 10000);
    assert_int_equal(c.dir_setup_ns, 1000);
    assert_int_equal(c.enable_ns, 10000000);
    assert_int_equal(c.spin_ns, 100000);
    assert_int_equal(c.rt_priority, 50);
    /* an empty file gives the defaults */
    cs_gpio_cfg_t e;
    char err[256];
    assert_int_equal(cs_gpio_cfg_parse("", "e.ini", &m, &e, err, sizeof err), 0);
    assert_memory_equal(&e, &c, sizeof c);
    /* 3 ticks of 30 kHz = 100 us, rounded up to the ns */
    m.tick_hz = 30000;
    m.axis[2].pulse_ticks = 3;
    cs_gpio_cfg_default(&c, &m);
    assert_int_equal(c.pulse_ns, 100000);
}

static const char *full = "[machine]\n"
                          "axes = 4\n"
                          "[gpio]\n"
                          "chip = /dev/gpiochip0\n"
                          "x_step = 17\n"
                          "X_DIR = 27\n"
                          "y_step = 22\n"
                          "y_dir = 23\n"
                          "z_step = 5\n"
                          "z_dir = 6\n"
                          "a_step = 12\n"
                          "a_dir = 13\n"
                          "enable = 4\n"
                          "step_active_low = yes\n"
                          "enable_active_low = false\n"
                          "pulse_us = 2.5\n"
                          "dir_setup_us = 0.65\n"
                          "enable_ms = 2\n"
                          "spin_us = 40\n"
                          "rt_priority = 80\n"
                          "[x]\n"
                          "steps_per_mm = 80\n";

static void test_every_key(void **state)
{
    (void)state;
    cs_machine_t m;
    char err[256];
    assert_int_equal(cs_machine_ini_parse(full, "full.ini", &m, err, sizeof err), 0);
    cs_gpio_cfg_t c;
    assert_int_equal(cs_gpio_cfg_parse(full, "full.ini", &m, &c, err, sizeof err), 0);
    assert_string_equal(c.chip, "gpiochip0");
    const int step[4] = {17, 22, 5, 12}, dir[4] = {27, 23, 6, 13};
    for (unsigned i = 0; i < 4; i++) {
        assert_int_equal(c.step[i], step[i]);
        assert_int_equal(c.dir[i], dir[i]);
        assert_true(cs_gpio_cfg_wired(&c, i));
    }
    assert_int_equal(c.enable, 4);
    assert_true(c.step_active_low);
    assert_false(c.enable_active_low);
    assert_int_equal(c.pulse_ns, 2500);
    assert_int_equal(c.dir_setup_ns, 650);
    assert_int_equal(c.enable_ns, 2000000);
    assert_int_equal(c.spin_ns, 40000);
    assert_int_equal(c.rt_priority, 80);
    /* from a file, too */
    char path[] = "/tmp/test_gpio_cfg_XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    assert_int_equal(write(fd, full, strlen(full)), (ssize_t)strlen(full));
    close(fd);
    cs_gpio_cfg_t f;
    assert_int_equal(cs_gpio_cfg_load(path, &m, &f, err, sizeof err), 0);
    unlink(path);
    assert_memory_equal(&f, &c, sizeof c);
    /* "none" unwires a line set earlier */
    assert_int_equal(
        cs_gpio_cfg_parse("[gpio]\nx_step = 1\nx_dir = 2\nx_step = none\nx_dir = none\n", "n.ini",
                          &m, &c, err, sizeof err),
        0);
    assert_false(cs_gpio_cfg_wired(&c, 0));
}

static void expect_error(const char *text, const char *want)
{
    cs_machine_t m;
    cs_machine_ini_default(&m);
    cs_gpio_cfg_t c;
    char err[512];
    assert_int_equal(cs_gpio_cfg_parse(text, "bad.ini", &m, &c, err, sizeof err), -1);
    if (strncmp(err, want, strlen(want)) != 0)
        fail_msg("got \"%s\", want \"%s...\"", err, want);
}

static void test_errors(void **state)
{
    (void)state;
    expect_error("[gpio]\nx_step = 1\nstep_pin = 3\n", "bad.ini:3: [gpio] step_pin: unknown key");
    expect_error("[gpio]\nx_step = -1\n", "bad.ini:2: [gpio] x_step: expected a line offset");
    expect_error("[gpio]\nx_step = 2.5\n", "bad.ini:2: [gpio] x_step: expected a line offset");
    expect_error("[gpio]\nx_step = 70000\n", "bad.ini:2: [gpio] x_step: expected a line offset");
    expect_error("[x]\n[gpio]\nx_step = 17\n\ny_dir = 17\n",
                 "bad.ini:5: [gpio] y_dir: line 17 is already x_step");
    expect_error("[gpio]\nenable = 4\nz_dir = 4\n",
                 "bad.ini:3: [gpio] z_dir: line 4 is already enable");
    expect_error("[gpio]\nstep_active_low = maybe\n",
                 "bad.ini:2: [gpio] step_active_low: expected true or false");
    expect_error("[gpio]\npulse_us = 0\n", "bad.ini:2: [gpio] pulse_us: must be in");
    expect_error("[gpio]\ndir_setup_us = -1\n", "bad.ini:2: [gpio] dir_setup_us: must be in");
    expect_error("[gpio]\nrt_priority = 100\n", "bad.ini:2: [gpio] rt_priority: must be");
    expect_error("[gpio]\nenable_ms = x\n", "bad.ini:2: [gpio] enable_ms: must be in");
    expect_error("[gpio]\nchip =\n", "bad.ini:2: [gpio] chip: expected a chip name");
    expect_error("[gpio]\nx_step = 1\n", "bad.ini:0: [gpio] x_step and x_dir go together");
    expect_error("[gpio]\na_step = 1\na_dir = 2\n",
                 "bad.ini:0: [gpio] a_step: the machine has no a axis");
    /* 200 mm/s * 80 steps/mm = 16000 steps/s: half a period is 31.25 us */
    expect_error("[gpio]\nx_step = 1\nx_dir = 2\npulse_us = 32\n",
                 "bad.ini:0: [gpio] pulse_us = 32.000 us does not fit half the shortest step "
                 "period of axis x (31.250 us at max_rate)");
    /* the same pulse on an axis that is not wired: nothing to check */
    cs_machine_t m;
    cs_machine_ini_default(&m);
    cs_gpio_cfg_t c;
    char err[256];
    assert_int_equal(
        cs_gpio_cfg_parse("[gpio]\npulse_us = 32\n", "ok.ini", &m, &c, err, sizeof err), 0);
    assert_int_equal(cs_gpio_cfg_load("/nonexistent/m.ini", &m, &c, err, sizeof err), -1);
    assert_string_equal(err, "/nonexistent/m.ini:0: cannot read the machine file");
}

/* The inputs: defaults (none wired, every polarity active low), each key, the state path. */
static void test_input_keys(void **state)
{
    (void)state;
    cs_machine_t m;
    cs_machine_ini_default(&m);
    cs_gpio_cfg_t c;
    char err[256];
    cs_gpio_cfg_default(&c, &m);
    assert_false(cs_gpio_cfg_has_inputs(&c));
    assert_true(c.limit_active_low && c.probe_active_low && c.estop_active_low);
    assert_string_equal(c.state, "");
    const char *t = "[gpio]\nx_min = 5\nx_max = 6\ny_min = 7\nz_max = 13\nprobe = 19\n"
                    "estop = 26\nlimit_active_low = no\nprobe_active_low = 0\n"
                    "estop_active_low = yes\nstate = /run/cs.state\n";
    assert_int_equal(cs_gpio_cfg_parse(t, "i.ini", &m, &c, err, sizeof err), 0);
    assert_true(cs_gpio_cfg_has_inputs(&c));
    assert_int_equal(c.lim_min[0], 5);
    assert_int_equal(c.lim_max[0], 6);
    assert_int_equal(c.lim_min[1], 7);
    assert_int_equal(c.lim_max[1], -1);
    assert_int_equal(c.lim_min[2], -1);
    assert_int_equal(c.lim_max[2], 13);
    assert_int_equal(c.probe, 19);
    assert_int_equal(c.estop, 26);
    assert_false(c.limit_active_low);
    assert_false(c.probe_active_low);
    assert_true(c.estop_active_low);
    assert_string_equal(c.state, "/run/cs.state");
    assert_int_equal(cs_gpio_cfg_parse("[gpio]\nprobe = 4\nz_min = 4\n", "d.ini", &m, &c, err,
                                       sizeof err),
                     -1);
    assert_string_equal(err, "d.ini:3: [gpio] z_min: line 4 is already probe");
    assert_int_equal(cs_gpio_cfg_parse("[gpio]\nestop = x\n", "e.ini", &m, &c, err, sizeof err),
                     -1);
    assert_string_equal(err, "e.ini:2: [gpio] estop: expected a line offset 0..65535 (or none)");
}

static void test_chip_names(void **state)
{
    (void)state;
    char out[64];
    const char *in[][2] = {{"gpiochip0", "gpiochip0"},
                           {"/dev/gpiochip4", "gpiochip4"},
                           {"4", "gpiochip4"},
                           {"pinctrl-bcm2711", "pinctrl-bcm2711"},
                           {"/dev/weird", "/dev/weird"}};
    for (unsigned k = 0; k < sizeof in / sizeof in[0]; k++) {
        cs_gpio_cfg_chip_name(in[k][0], out, sizeof out);
        assert_string_equal(out, in[k][1]);
    }
}

/* cs_machine_ini skips [gpio] (and its keys are not machine keys) but still refuses unknown
 * sections, naming gpio among the expected ones. */
static void test_machine_reader_accepts_the_section(void **state)
{
    (void)state;
    cs_machine_t m, d;
    char err[256];
    assert_int_equal(
        cs_machine_ini_parse("[gpio]\nx_step = 17\nbogus = 1\n", "g.ini", &m, err, sizeof err), 0);
    cs_machine_ini_default(&d);
    assert_memory_equal(&m, &d, sizeof m);
    assert_int_equal(cs_machine_ini_parse("[gpoi]\nx = 1\n", "g.ini", &m, err, sizeof err), -1);
    assert_non_null(strstr(err, "g.ini:2: [gpoi]: unknown section"));
    assert_non_null(strstr(err, "gpio"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_every_key),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_input_keys),
        cmocka_unit_test(test_chip_names),
        cmocka_unit_test(test_machine_reader_accepts_the_section),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
