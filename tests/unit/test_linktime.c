/* Tests of cs_linktime, the line timing every end of a link uses, against a double-precision
 * reference of the formulas of docs/protocol.md 3.6 (a character of 10 bits on 8N1, 11 on Modbus
 * RTU; rto = 40 ms + three windows of the largest frame, NAK hold-off = two largest frames):
 * the integer result must be the reference rounded up, i.e. within [ref, ref + 1) ticks, over
 * the termios rates from 50 to 4,000,000 bits/s and tick rates from 1 kHz to 1 GHz. Plus the
 * memory-speed case, saturation, and refused arguments. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

#include "cs_frame.h"
#include "cs_linktime.h"

static const uint32_t rates[] = {50,     300,    1200,   9600,   19200,   38400,   57600,
                                 115200, 230400, 460800, 921600, 1000000, 3000000, 4000000};
static const uint32_t ticks[] = {1000, 32768, 100000, 1000000, 16000000, 72000000, 1000000000};

/* the reference: n characters of bits on a line of bps, in ticks of hz (double) */
static double ref_chars(double n, double bits, double bps, double hz)
{
    return n * bits * hz / bps;
}

static void within_one(double ref, uint32_t got)
{
    /* rounded up: never below the exact value, less than one tick above it (1e-9 relative for
     * the double's own rounding) */
    assert_true((double)got >= ref * (1 - 1e-12) - 1e-9);
    assert_true((double)got < ref + 1.0 + 1e-9 * ref);
}

static void test_chars(void **state)
{
    (void)state;
    for (size_t r = 0; r < sizeof rates / sizeof rates[0]; r++)
        for (size_t t = 0; t < sizeof ticks / sizeof ticks[0]; t++) {
            uint32_t n = 256; /* a Modbus RTU ADU, 11 bits a character */
            double ref = ref_chars(n, 11, rates[r], ticks[t]);
            uint32_t got = cs_linktime_chars(n, CS_LINKTIME_BITS_RTU, rates[r], ticks[t]);
            if (ref >= 4294967295.0)
                assert_int_equal(got, UINT32_MAX);
            else
                within_one(ref, got);
        }
    /* hand computed: 7 characters of 11 bits at 9600 baud = 77 / 9600 s = 8020.8 us -> 8021 */
    assert_int_equal(cs_linktime_chars(7, 11, 9600, 1000000), 8021);
    /* exact divisions are not rounded up: 115200 bits at 115200 bits/s = 1 s */
    assert_int_equal(cs_linktime_chars(11520, 10, 115200, 1000000), 1000000);
    assert_int_equal(cs_linktime_chars(0, 10, 115200, 1000000), 0);
    assert_int_equal(cs_linktime_chars(10, 10, 0, 1000000), 0); /* memory speed */
    /* saturates: 4e9 characters at 50 bits/s in ns */
    assert_int_equal(cs_linktime_chars(4000000000u, 11, 50, 1000000000u), UINT32_MAX);
}

static void test_link(void **state)
{
    (void)state;
    for (size_t r = 0; r < sizeof rates / sizeof rates[0]; r++)
        for (size_t t = 0; t < sizeof ticks / sizeof ticks[0]; t++) {
            cs_link_cfg_t c = {.keepalive = 1234};
            double hz = ticks[t], frame = ref_chars(CS_FRAME_WIRE_MAX, 10, rates[r], hz);
            double rto = ceil(0.040 * hz) + 3.0 * CS_LINK_WINDOW * frame;
            cs_err_t e = cs_linktime_link(&c, rates[r], ticks[t]);
            /* backoff: doubled up to max(rto, 1 s); closed after max(30 s, 2 rto_max) */
            double rto_max = fmax(rto, hz), give_up = fmax(30.0 * hz, 2.0 * rto_max);
            if (rto >= 4294967295.0 || give_up >= 4294967295.5) {
                assert_int_equal(e, CS_ERR_RANGE);
                continue;
            }
            assert_int_equal(e, CS_OK);
            within_one(rto, c.rto);
            within_one(2.0 * frame, c.nak_holdoff);
            within_one(rto_max, c.rto_max);
            within_one(give_up, c.give_up);
            assert_int_equal(c.keepalive, 1234); /* left as it was */
        }
    /* hand computed, the host's microseconds at 115200 baud with the default sizes: a frame of
     * CS_FRAME_WIRE_MAX characters takes CS_FRAME_WIRE_MAX * 10 / 0.1152 us */
    cs_link_cfg_t c;
    assert_int_equal(cs_linktime_link(&c, 115200, 1000000), CS_OK);
    double f_us = CS_FRAME_WIRE_MAX * 10 / 0.1152;
    assert_int_equal(c.rto, (uint32_t)ceil(40000 + 3 * CS_LINK_WINDOW * f_us));
    assert_int_equal(c.nak_holdoff, (uint32_t)ceil(2 * f_us));
}

static void test_memory_speed_and_args(void **state)
{
    (void)state;
    cs_link_cfg_t c;
    assert_int_equal(cs_linktime_link(&c, 0, 1000000), CS_OK);
    assert_int_equal(c.rto, 5000);
    assert_int_equal(c.nak_holdoff, 0);
    assert_int_equal(c.rto_max, 1000000); /* 1 s */
    assert_int_equal(c.give_up, 30000000); /* 30 s */
    assert_int_equal(cs_linktime_link(&c, 0, 32768), CS_OK);
    assert_int_equal(c.rto, 164); /* ceil(5 ms * 32768 Hz) = ceil(163.84) */
    assert_int_equal(cs_linktime_link(NULL, 115200, 1000000), CS_ERR_ARG);
    assert_int_equal(cs_linktime_link(&c, 115200, 999), CS_ERR_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_chars),
        cmocka_unit_test(test_link),
        cmocka_unit_test(test_memory_speed_and_args),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
