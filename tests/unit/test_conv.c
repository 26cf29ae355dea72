/* test_conv: host/cs_conv.c, the one place doubles become fixed point. Each conversion must
 * round to the nearest unit of its format (so within 0.5 unit of the exact value) and refuse
 * what the format or its accepted range cannot hold (never clamp, never wrap). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include <cmocka.h>

#include "cs_conv.h"

#define LSB (1.0 / 65536.0)

static uint64_t rng = 0x2545F4914F6CDD1Dull;

static uint64_t xorshift64(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

static double urand(double lo, double hi)
{
    return lo + (hi - lo) * (double)(xorshift64() >> 11) / 9007199254740992.0;
}

static void test_mm_to_pos(void **state)
{
    (void)state;
    cs_pos_t p = 0;
    assert_int_equal(cs_conv_mm_to_pos(1.0, &p), CS_OK);
    assert_int_equal(p, 65536);
    assert_int_equal(cs_conv_mm_to_pos(-2.5, &p), CS_OK);
    assert_int_equal(p, -163840);
    /* Random values over the whole range: within half an LSB, and back exactly. */
    for (int i = 0; i < 100000; i++) {
        double v = urand(-4096, 4096);
        assert_int_equal(cs_conv_mm_to_pos(v, &p), CS_OK);
        assert_true(fabs(cs_conv_pos_to_mm(p) - v) <= 0.5 * LSB);
        assert_true(cs_conv_pos_to_mm(p) == (double)p / 65536.0);
    }
    /* The limit itself and what rounds onto it are accepted; one LSB more is not. */
    assert_int_equal(cs_conv_mm_to_pos(4096.0, &p), CS_OK);
    assert_int_equal(p, CS_POS_LIMIT);
    assert_int_equal(cs_conv_mm_to_pos(-4096.0 - 0.4 * LSB, &p), CS_OK);
    assert_int_equal(p, -CS_POS_LIMIT);
    p = 77;
    assert_int_equal(cs_conv_mm_to_pos(4096.0 + LSB, &p), CS_ERR_RANGE);
    assert_int_equal(p, 77); /* untouched on error */
    assert_int_equal(cs_conv_mm_to_pos(-1e300, &p), CS_ERR_RANGE);
    assert_int_equal(cs_conv_mm_to_pos(NAN, &p), CS_ERR_RANGE);
    assert_int_equal(cs_conv_mm_to_pos(INFINITY, &p), CS_ERR_RANGE);
    assert_int_equal(p, 77);
    cs_vec3_t v = {1, 2, 3};
    assert_int_equal(cs_conv_mm_to_vec(1, 2, 5000, &v), CS_ERR_RANGE);
    assert_int_equal(v.x, 1); /* all or nothing */
    assert_int_equal(cs_conv_mm_to_vec(1, -2, 0.5, &v), CS_OK);
    assert_true(v.x == 65536 && v.y == -131072 && v.z == 32768);
}

static void test_param_weight_tol(void **state)
{
    (void)state;
    cs_param_t q = 0;
    assert_int_equal(cs_conv_to_param(1.0, &q), CS_OK);
    assert_int_equal(q, CS_PARAM_ONE);
    assert_int_equal(cs_conv_to_param(-2.0, &q), CS_OK);
    assert_int_equal(q, INT32_MIN);
    assert_int_equal(cs_conv_to_param(2.0, &q), CS_ERR_RANGE); /* 2^31 does not fit */
    assert_int_equal(cs_conv_to_param(NAN, &q), CS_ERR_RANGE);
    for (int i = 0; i < 10000; i++) {
        double v = urand(-1, 1);
        assert_int_equal(cs_conv_to_param(v, &q), CS_OK);
        assert_true(fabs(cs_conv_param_to_double(q) - v) <= 0.5 / (double)CS_PARAM_ONE);
    }
    cs_weight_t w = 0;
    assert_int_equal(cs_conv_to_weight(1.0, &w), CS_OK);
    assert_int_equal(w, CS_WEIGHT_ONE);
    assert_int_equal(cs_conv_to_weight(ldexp(1, -20), &w), CS_OK);
    assert_int_equal(w, CS_WEIGHT_MIN);
    assert_int_equal(cs_conv_to_weight(ldexp(1, -21), &w), CS_ERR_WEIGHT);
    assert_int_equal(cs_conv_to_weight(0.0, &w), CS_ERR_WEIGHT);
    assert_int_equal(cs_conv_to_weight(-0.5, &w), CS_ERR_WEIGHT);
    assert_int_equal(cs_conv_to_weight(1.0 + 1e-7, &w), CS_ERR_WEIGHT); /* 2^30 + 107 */
    cs_pos_t t = 0;
    assert_int_equal(cs_conv_tol_to_pos(0.01, &t), CS_OK);
    assert_int_equal(t, 655); /* 0.01 * 65536 = 655.36 */
    assert_int_equal(cs_conv_tol_to_pos(LSB, &t), CS_OK);
    assert_int_equal(t, 1);
    assert_int_equal(cs_conv_tol_to_pos(0.4 * LSB, &t), CS_ERR_TOLERANCE); /* rounds to 0 */
    assert_int_equal(cs_conv_tol_to_pos(0.0, &t), CS_ERR_TOLERANCE);
    assert_int_equal(cs_conv_tol_to_pos(-1.0, &t), CS_ERR_TOLERANCE);
    assert_int_equal(cs_conv_tol_to_pos(4097.0, &t), CS_ERR_TOLERANCE);
    assert_int_equal(cs_conv_tol_to_pos(NAN, &t), CS_ERR_TOLERANCE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mm_to_pos),
        cmocka_unit_test(test_param_weight_tol),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
