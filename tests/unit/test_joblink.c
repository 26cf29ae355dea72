/* Tests of cs_joblink, the links behind one interface: the link the options pick (exactly one;
 * none or two refused), the option parser `stream` and `serve` share (values checked, bad ones
 * refused), the line rate a serial device really moves (pty: memory speed), the step segments
 * and pen events of a job's messages (each PEN where it stood), and the one report: the exit
 * status of every outcome (README's table, written out here) and the summary lines, with the
 * link's own counters line in place of the byte counters and no resume hint after a stop
 * mid-message.
 * The links themselves run in tests/cli (test_stream, test_modbus, test_gpio, test_daemon*). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_cmd.h"
#include "cs_joblink.h"
#include "cs_stream_cmd.h"

static void test_select(void **state)
{
    (void)state;
    cs_joblink_t l;
    cs_joblink_cfg_t c;
    memset(&c, 0, sizeof c);
    assert_int_equal(cs_joblink_select(&l, &c), CS_EXIT_USAGE);
    assert_non_null(strstr(l.why, "is required"));
    c.port = "/dev/ttyUSB0";
    assert_int_equal(cs_joblink_select(&l, &c), CS_EXIT_OK);
    assert_ptr_equal(l.ops, &cs_joblink_serial_ops);
    assert_string_equal(l.name, "/dev/ttyUSB0");
    c.gpio = "gpiochip0";
    assert_int_equal(cs_joblink_select(&l, &c), CS_EXIT_USAGE);
    assert_non_null(strstr(l.why, "exclude each other"));
    c.port = NULL;
    assert_int_equal(cs_joblink_select(&l, &c), CS_EXIT_OK);
    assert_ptr_equal(l.ops, &cs_joblink_gpio_ops);
    assert_false(l.ops->curves);
    c.gpio = NULL;
    c.modbus_tcp = "127.0.0.1:1502";
    assert_int_equal(cs_joblink_select(&l, &c), CS_EXIT_OK);
    assert_ptr_equal(l.ops, &cs_joblink_modbus_ops);
    assert_string_equal(l.name, "127.0.0.1:1502");
    c.modbus_tcp = NULL;
    c.modbus_rtu = "/dev/ttyS1";
    assert_int_equal(cs_joblink_select(&l, &c), CS_EXIT_OK);
    assert_ptr_equal(l.ops, &cs_joblink_modbus_ops);
    /* what each link carries */
    assert_true(cs_joblink_serial_ops.keep_open); /* the port stays open between jobs */
    assert_false(cs_joblink_modbus_ops.keep_open || cs_joblink_gpio_ops.keep_open);
    /* every link carries servo pen events (PEN messages; GPIO: cs_gpio_pwm) */
    assert_true(cs_joblink_serial_ops.pens && cs_joblink_modbus_ops.pens &&
                cs_joblink_gpio_ops.pens);
}

/* Runs cs_joblink_option over words; returns its last result and the index reached. */
static int options(const char *const *words, int n, cs_joblink_cfg_t *c, int *last)
{
    char *argv[8];
    for (int k = 0; k < n; k++)
        argv[k] = (char *)words[k];
    int r = 0, i;
    for (i = 0; i < n; i++) {
        r = cs_joblink_option("test", n, argv, &i, c);
        if (r <= 0)
            break;
    }
    *last = i;
    return r;
}

static void test_options(void **state)
{
    (void)state;
    cs_joblink_cfg_t c;
    memset(&c, 0, sizeof c);
    int last;
    const char *good[] = {"--modbus-rtu", "/dev/ttyS1", "--baud", "19200",
                          "--parity",     "odd",        "--unit", "17"};
    assert_int_equal(options(good, 8, &c, &last), 1);
    assert_int_equal(last, 8);
    assert_string_equal(c.modbus_rtu, "/dev/ttyS1");
    assert_int_equal(c.baud, 19200);
    assert_int_equal(c.parity, 'O');
    assert_int_equal(c.unit, 17);
    const char *rate[] = {"--line-rate", "9600", "--gpio", "record:x.csv"};
    assert_int_equal(options(rate, 4, &c, &last), 1);
    assert_int_equal(c.line_rate, 9600);
    assert_string_equal(c.gpio, "record:x.csv");
    /* refused values: a baud termios does not know, unit 0 and 248, a parity, a rate < 10 */
    const char *bad[][2] = {{"--baud", "12345"},  {"--unit", "0"},      {"--unit", "248"},
                            {"--parity", "mark"}, {"--line-rate", "9"}, {"--baud", "-1"}};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++)
        assert_int_equal(options(bad[k], 2, &c, &last), -1);
    /* not a link option, or one without its value: 0, nothing taken */
    const char *other[] = {"--tol", "0.1"};
    assert_int_equal(options(other, 2, &c, &last), 0);
    assert_int_equal(last, 0);
    const char *lone[] = {"--port"};
    assert_int_equal(options(lone, 1, &c, &last), 0);
}

static void test_line_bps_and_counts(void **state)
{
    (void)state;
    assert_int_equal(cs_joblink_line_bps("/dev/pts/3", 115200, 0), 0);
    assert_int_equal(cs_joblink_line_bps("/dev/pts/3", 115200, 9600), 9600);
    assert_int_equal(cs_joblink_line_bps("/dev/ttyUSB0", 57600, 0), 57600);
    unsigned long long v;
    assert_int_equal(cs_joblink_parse_count("4000000", 4000000, &v), 0);
    assert_int_equal(v, 4000000);
    assert_int_equal(cs_joblink_parse_count("4000001", 4000000, &v), -1);
    assert_int_equal(cs_joblink_parse_count("", 10, &v), -1);
    assert_int_equal(cs_joblink_parse_count("-0", 10, &v), -1);
    assert_int_equal(cs_joblink_parse_count("7x", 10, &v), -1);
}

static void test_segments_of_a_job(void **state)
{
    (void)state;
    cs_stream_job_t job;
    cs_stream_job_init(&job, CS_STREAM_SEGMENTS);
    cs_segment_t s[3] = {{100, {5, -3, 0, 0}}, {200, {0, 7, 1, 0}}, {300, {-9, 0, 0, 2}}};
    cs_motion_segs_t ms;
    memset(&ms, 0, sizeof ms);
    ms.v = s;
    ms.n = 3;
    cs_motion_pen_t pens[2] = {{0, 1000}, {2, 2000}}; /* before segments 1 and 3 */
    ms.pens = pens;
    ms.npens = 2;
    assert_int_equal(cs_stream_job_add_motion(&job, &ms), CS_OK);
    assert_int_equal(job.n, 5);
    cs_segment_t *out;
    cs_motion_pen_t *pout;
    size_t n, np;
    assert_int_equal(cs_joblink_segments(&job, &out, &n, &pout, &np), CS_OK);
    assert_int_equal(n, 3);
    assert_int_equal(np, 2); /* where they were: before segments 0 and 2 */
    assert_int_equal(pout[0].seg, 0);
    assert_int_equal(pout[0].pulse_us, 1000);
    assert_int_equal(pout[1].seg, 2);
    assert_int_equal(pout[1].pulse_us, 2000);
    free(pout);
    for (size_t k = 0; k < 3; k++) {
        assert_int_equal(out[k].ticks, s[k].ticks);
        for (unsigned i = 0; i < CS_AXES; i++)
            assert_int_equal(out[k].steps[i], s[k].steps[i]);
    }
    free(out);
    cs_stream_job_free(&job);
}

/* The report of r over a serial link named "LINK" (counters: NULL or the test's own line) into
 * a string; returns the exit status. */
static bool custom_counters;
static void my_counters(cs_joblink_t *l, FILE *out, const cs_stream_result_t *r)
{
    (void)l;
    fprintf(out, "stream: my counters (%zu)\n", r->executed);
}

static int report(const cs_stream_result_t *r, size_t n, char *buf, size_t cap)
{
    cs_joblink_t l;
    cs_joblink_cfg_t c = {.port = "LINK"};
    assert_int_equal(cs_joblink_select(&l, &c), CS_EXIT_OK);
    cs_joblink_ops_t ops = *l.ops;
    ops.counters = custom_counters ? my_counters : NULL;
    l.ops = &ops;
    FILE *f = fmemopen(buf, cap, "w");
    assert_non_null(f);
    int rc = cs_joblink_report(&l, f, n, r);
    fclose(f);
    return rc;
}

static void test_report(void **state)
{
    (void)state;
    /* README "Exit status" of stream: 0 done, 4 no device / incompatible, 5 reset, 6 closed,
     * 7 device error, 8 interrupted */
    static const struct {
        cs_stream_outcome_t oc;
        int rc;
    } table[] = {{CS_STREAM_DONE, 0},       {CS_STREAM_NO_DEVICE, 4}, {CS_STREAM_INCOMPATIBLE, 4},
                 {CS_STREAM_RESET, 5},      {CS_STREAM_CLOSED, 6},    {CS_STREAM_DEVICE_ERROR, 7},
                 {CS_STREAM_INTERRUPTED, 8}};
    char buf[2048];
    custom_counters = false;
    for (size_t k = 0; k < sizeof table / sizeof table[0]; k++) {
        cs_stream_result_t r;
        memset(&r, 0, sizeof r);
        r.outcome = table[k].oc;
        r.executed = r.delivered = r.sent = 40;
        assert_int_equal(report(&r, 100, buf, sizeof buf), table[k].rc);
        assert_int_equal(strncmp(buf, "stream: LINK: ", 14), 0);
        assert_non_null(strstr(buf, "stream: 40 of 100 segments executed"));
        assert_non_null(strstr(buf, "bytes sent")); /* the serial and Modbus counters */
        bool hint = strstr(buf, "--resume-from 40") != NULL;
        assert_int_equal(hint, table[k].rc >= 5); /* a hint only when it ended mid-job */
    }
    /* the link's own sentence and counters; no hint after a stop mid-message */
    custom_counters = true;
    cs_stream_result_t r;
    memset(&r, 0, sizeof r);
    r.outcome = CS_STREAM_INTERRUPTED;
    r.executed = 12;
    r.what = "interrupted: stopped at once";
    r.mid_message = true;
    assert_int_equal(report(&r, 30, buf, sizeof buf), CS_EXIT_INTERRUPTED);
    assert_non_null(strstr(buf, "stream: LINK: interrupted: stopped at once\n"));
    assert_non_null(strstr(buf, "stream: my counters (12)\n"));
    assert_null(strstr(buf, "bytes sent"));
    assert_null(strstr(buf, "--resume-from"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_select),
        cmocka_unit_test(test_options),
        cmocka_unit_test(test_line_bps_and_counts),
        cmocka_unit_test(test_segments_of_a_job),
        cmocka_unit_test(test_report),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
