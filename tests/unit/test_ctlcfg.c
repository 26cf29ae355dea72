/* cs_ctlcfg: the machine file's [homing], [limits], [probe], [spindle]: values read, defaults,
 * located errors (file:line), the HOME messages of a cycle (values by hand in Q15.16) and the
 * simulator's input bits at positions on each side of the trip points; the machine reader
 * accepts the sections. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "cs_ctlcfg.h"
#include "cs_machine_ini.h"

static const char *const text = "[machine]\n"
                                "tick_hz = 100000\n"
                                "[homing]\n"
                                "order = zx\n"
                                "seek = 25\n"
                                "latch = 0.5\n"
                                "pulloff = 2\n"
                                "z = max\n"
                                "x_pos = -3.25\n"
                                "[limits]\n"
                                "x_min = -5\n"
                                "z_max = 2.5\n"
                                "[probe]\n"
                                "z = -3\n"
                                "[spindle]\n"
                                "laser = true\n"
                                "s_max = 255\n";

static void test_read_and_messages(void **state)
{
    (void)state;
    cs_machine_t m;
    char err[256] = "";
    assert_int_equal(cs_machine_ini_parse(text, "m.ini", &m, err, sizeof err), 0);
    cs_ctlcfg_t c;
    assert_int_equal(cs_ctlcfg_parse(text, "m.ini", &m, &c, err, sizeof err), 0);
    assert_int_equal(c.n_order, 2);
    assert_int_equal(c.order[0], 2);
    assert_int_equal(c.order[1], 0);
    assert_true(c.at_max[2] && !c.at_max[0]);
    assert_true(c.laser);
    assert_true(c.s_max == 255);
    /* z: seek 25 mm/s = 0x190000, latch 0.5 = 0x8000, pull-off 2 = 0x20000, search 1.5 x the
     * built-in z travel of 200 mm = 300 mm, position: z's travel_max 100 mm (switch at max) */
    cs_proto_msg_t h;
    assert_int_equal(cs_ctlcfg_home_msg(&c, &m, 0, &h), CS_OK);
    assert_int_equal(h.type, CS_PROTO_HOME);
    assert_int_equal(h.u.home.axis, 2);
    assert_int_equal(h.u.home.flags, CS_PROTO_HOME_MAX);
    assert_int_equal(h.u.home.seek, 25 << 16);
    assert_int_equal(h.u.home.latch, 1 << 15);
    assert_int_equal(h.u.home.pulloff, 2 << 16);
    assert_int_equal(h.u.home.search, 300 << 16);
    assert_int_equal(h.u.home.home_pos, 100 << 16);
    /* x: at min, x_pos -3.25 mm = -(3 x 65536 + 16384) */
    assert_int_equal(cs_ctlcfg_home_msg(&c, &m, 1, &h), CS_OK);
    assert_int_equal(h.u.home.axis, 0);
    assert_int_equal(h.u.home.flags, 0);
    assert_int_equal(h.u.home.home_pos, -(3 * 65536 + 16384));
    assert_int_equal(cs_ctlcfg_home_msg(&c, &m, 2, &h), CS_ERR_ARG);
    /* inputs on each side of the trip points */
    double at[CS_AXES] = {-4.99, 0, 2.49, 0};
    assert_int_equal(cs_ctlcfg_inputs(&c, at), 0);
    double on[CS_AXES] = {-5, 0, 2.5, 0};
    assert_int_equal(cs_ctlcfg_inputs(&c, on), CS_PROTO_IN_MIN(0) | CS_PROTO_IN_MAX(2));
    double probe[CS_AXES] = {0, 0, -3, 0};
    assert_int_equal(cs_ctlcfg_inputs(&c, probe), CS_PROTO_IN_PROBE);
    assert_true(cs_ctlcfg_has_inputs(&c));
}

static void test_defaults_and_errors(void **state)
{
    (void)state;
    cs_machine_t m;
    cs_machine_ini_default(&m);
    cs_ctlcfg_t c;
    char err[256];
    assert_int_equal(cs_ctlcfg_load(NULL, &m, &c, err, sizeof err), 0);
    assert_int_equal(c.n_order, 0);
    assert_true(c.seek == 20 && c.latch == 2 && c.pulloff == 1 && c.s_max == 1000 && !c.laser);
    assert_false(cs_ctlcfg_has_inputs(&c));
    static const struct {
        const char *text, *want;
    } bad[] = {
        {"[homing]\norder = xq\n", "b.ini:2: [homing] order: expected axis letters"},
        {"[homing]\norder = xx\n", "b.ini:2: [homing] order: an axis is named twice"},
        {"[homing]\n\nseek = 0\n", "b.ini:3: [homing] seek: must be in (0, 4096] mm/s"},
        {"[homing]\nx = middle\n", "b.ini:2: [homing] x: expected min or max"},
        {"[homing]\nspeed = 3\n", "b.ini:2: [homing] speed: unknown key"},
        {"[limits]\nx_min = 5000\n", "b.ini:2: [limits] x_min: must be a position"},
        {"[limits]\nw_min = 1\n", "b.ini:2: [limits] w_min: unknown key"},
        {"[probe]\nz = deep\n", "b.ini:2: [probe] z: must be a position"},
        {"[spindle]\nlaser = maybe\n", "b.ini:2: [spindle] laser: expected true or false"},
        {"[spindle]\ns_max = 0\n", "b.ini:2: [spindle] s_max: must be in (0, 1000000]"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        err[0] = '\0';
        assert_int_equal(cs_ctlcfg_parse(bad[i].text, "b.ini", &m, &c, err, sizeof err), -1);
        if (strncmp(err, bad[i].want, strlen(bad[i].want)) != 0)
            fail_msg("got '%s', want '%s...'", err, bad[i].want);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_read_and_messages),
        cmocka_unit_test(test_defaults_and_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
