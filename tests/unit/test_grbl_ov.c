/* test_grbl_ov: Grbl 1.1's override bytes (host/cs_grbl_ov.c) against the grbl wiki's table
 * ("Interface", real-time commands): 0x90 feed 100 %, 0x91/0x92 +/-10, 0x93/0x94 +/-1, clamped to
 * 10..200; 0x95/0x96/0x97 rapid 100/50/25; 0x99..0x9D the spindle like the feed. Feeds of the
 * moves not yet planned, worked out by hand. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "cs_grbl_ov.h"

static void send(cs_grbl_ov_t *ov, const unsigned char *b, size_t n)
{
    for (size_t k = 0; k < n; k++)
        assert_true(cs_grbl_ov_byte(ov, b[k]));
}

static void test_bytes(void **state)
{
    (void)state;
    cs_grbl_ov_t ov;
    cs_grbl_ov_init(&ov);
    send(&ov, (const unsigned char[]){0x91, 0x91, 0x93}, 3); /* 100 + 10 + 10 + 1 */
    assert_int_equal(ov.feed, 121);
    send(&ov, (const unsigned char[]){0x92, 0x94, 0x94}, 3); /* 121 - 10 - 1 - 1 */
    assert_int_equal(ov.feed, 109);
    for (int k = 0; k < 20; k++)
        send(&ov, (const unsigned char[]){0x91}, 1);
    assert_int_equal(ov.feed, 200);
    for (int k = 0; k < 30; k++)
        send(&ov, (const unsigned char[]){0x92}, 1);
    assert_int_equal(ov.feed, 10);
    send(&ov, (const unsigned char[]){0x90, 0x97}, 2);
    assert_int_equal(ov.feed, 100);
    assert_int_equal(ov.rapid, 25);
    send(&ov, (const unsigned char[]){0x96, 0x9B, 0x9D}, 3); /* spindle 100 - 10 - 1 */
    assert_int_equal(ov.rapid, 50);
    assert_int_equal(ov.spindle, 89);
    send(&ov, (const unsigned char[]){0x95, 0x99}, 2);
    assert_int_equal(ov.rapid, 100);
    assert_int_equal(ov.spindle, 100);
    assert_false(cs_grbl_ov_byte(&ov, 0x85)); /* jog cancel is not an override */
    assert_false(cs_grbl_ov_byte(&ov, 0x9E));
    assert_false(cs_grbl_ov_byte(&ov, '?'));
}

static void test_apply(void **state)
{
    (void)state;
    cs_path_t p;
    cs_path_init(&p);
    cs_bezier_t c = {.degree = 1};
    cs_path_loc_t loc = {"t", 1, 1};
    assert_int_equal(cs_path_add_move(&p, &c, CS_PATH_LINE, loc, 10.0, false), CS_OK);
    assert_int_equal(cs_path_add_move(&p, &c, CS_PATH_LINE, loc, 0.0, false), CS_OK);
    assert_int_equal(cs_path_add_move(&p, &c, CS_PATH_LINE, loc, 0.0, true), CS_OK);
    cs_grbl_ov_t ov;
    cs_grbl_ov_init(&ov);
    cs_grbl_ov_apply(&ov, &p, 0, 5.0, 200.0); /* 100 %: nothing changes */
    assert_true(p.elems[0].feed_mm_s == 10.0 && p.elems[1].feed_mm_s == 0.0 && p.elems[2].rapid);
    ov.feed = 150;
    ov.rapid = 25;
    cs_grbl_ov_apply(&ov, &p, 1, 5.0, 200.0); /* element 0 already planned: left alone */
    assert_true(p.elems[0].feed_mm_s == 10.0);
    assert_true(p.elems[1].feed_mm_s == 7.5);  /* the default 5 mm/s x 1.5 */
    assert_false(p.elems[2].rapid);            /* 25 % of 200 mm/s */
    assert_true(p.elems[2].feed_mm_s == 50.0);
    cs_path_free(&p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bytes),
        cmocka_unit_test(test_apply),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
