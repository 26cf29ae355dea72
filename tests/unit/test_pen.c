/* test_pen: pen lifts (host/cs_pen.c for [pen] mode z, cs_motion's servo events) and the [pen]
 * keys. A two-stroke drawing (a line and a cubic in subpath 0, a line in subpath 1) is lifted:
 * the expected element list is written out by hand (plunge, strokes at down_z, lift, plunge,
 * stroke, lift; Z moves rapid or at z_feed); planned on a servo machine it gets five pen events
 * (up, down, up, down, up), each on a rest segment of settle_ms with no steps, and no segment
 * between an up event and the next down event moves unless it is travel to the next stroke's
 * start (checked by summing the steps). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "cs_conv.h"
#include "cs_motion.h"
#include "cs_pen.h"

static cs_path_t P;

static void add(double x0, double y0, double x1, double y1, int degree)
{
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = (uint8_t)degree;
    for (int i = 0; i <= degree; i++) {
        double t = (double)i / degree; /* control points on the chord: a straight curve */
        cs_conv_mm_to_vec(x0 + t * (x1 - x0), y0 + t * (y1 - y0), 0, &c.p[i]);
        c.w[i] = CS_WEIGHT_ONE;
    }
    cs_path_loc_t loc = {"t.svg", 1, 1};
    assert_int_equal(cs_path_add(&P, &c, degree == 1 ? CS_PATH_LINE : CS_PATH_CUBIC, loc), CS_OK);
}

static void drawing(void)
{
    cs_path_free(&P);
    cs_path_init(&P);
    add(10, 10, 20, 10, 1);
    add(20, 10, 20, 30, 3);
    cs_path_new_subpath(&P);
    add(40, 40, 50, 40, 1);
}

/* Element k: start (x, y, z0), end (., ., z1) in mm, rapid flag and feed. */
static void expect_el(size_t k, double x, double y, double z0, double z1, bool rapid, double feed)
{
    const cs_path_elem_t *e = &P.elems[k];
    const cs_bezier_t *c = &e->curve;
    assert_true(fabs(c->p[0].x / 65536.0 - x) < 1e-4 && fabs(c->p[0].y / 65536.0 - y) < 1e-4);
    assert_true(fabs(c->p[0].z / 65536.0 - z0) < 1e-4);
    assert_true(fabs(c->p[c->degree].z / 65536.0 - z1) < 1e-4);
    assert_int_equal(e->rapid, rapid);
    assert_true(e->feed_mm_s == feed);
}

static void test_lift_z(void **state)
{
    (void)state;
    drawing();
    assert_int_equal(cs_pen_strokes(&P), 2);
    cs_machine_pen_t pen;
    cs_machine_ini_pen_default(&pen);
    pen.mode = CS_MACHINE_PEN_Z;
    pen.up_z_mm = 5;
    pen.down_z_mm = 1;
    cs_path_diag_t d;
    assert_int_equal(cs_pen_lift_z(&P, &pen, &d), CS_OK);
    assert_int_equal(P.n, 7);
    expect_el(0, 10, 10, 5, 1, true, 0); /* plunge at the first stroke's start */
    expect_el(1, 10, 10, 1, 1, false, 0);
    expect_el(2, 20, 10, 1, 1, false, 0); /* the cubic, all its points at down_z */
    for (int i = 0; i <= 3; i++)
        assert_true(fabs(P.elems[2].curve.p[i].z / 65536.0 - 1) < 1e-4);
    expect_el(3, 20, 30, 1, 5, true, 0); /* lift at its end */
    expect_el(4, 40, 40, 5, 1, true, 0);
    expect_el(5, 40, 40, 1, 1, false, 0);
    expect_el(6, 50, 40, 1, 5, true, 0);
    assert_string_equal(P.elems[6].loc.file, "t.svg"); /* names survive the rebuild */
    /* z_feed: the Z moves at that speed, not rapid */
    drawing();
    pen.z_feed_mm_s = 12;
    assert_int_equal(cs_pen_lift_z(&P, &pen, &d), CS_OK);
    expect_el(0, 10, 10, 5, 1, false, 12);
    /* a height that pushes the drawing out of the coordinate range */
    drawing();
    pen.down_z_mm = 4095.99;
    pen.up_z_mm = 4096;
    P.elems[0].curve.p[0].z = P.elems[0].curve.p[1].z = 100 * 65536;
    assert_int_equal(cs_pen_lift_z(&P, &pen, &d), CS_ERR_RANGE);
    assert_int_equal(P.n, 3); /* unchanged on error */
}

static void test_servo_events(void **state)
{
    (void)state;
    drawing();
    cs_machine_t m;
    cs_machine_pen_t pen;
    char err[256];
    assert_int_equal(cs_machine_ini_parse_pen("[pen]\nmode = servo\nup_us = 1900\ndown_us = 1200\n"
                                              "settle_ms = 20\n",
                                              "m.ini", &m, &pen, err, sizeof err),
                     0);
    cs_motion_t mo;
    assert_int_equal(cs_motion_init(&mo, &m), CS_OK);
    mo.pen = &pen;
    cs_path_diag_t d;
    assert_int_equal(cs_motion_plan_path(&mo, &P, m.tolerance, 0, 0, &d), CS_OK);
    static const uint16_t want[5] = {1900, 1200, 1900, 1200, 1900};
    assert_int_equal(mo.segs.npens, 5);
    for (size_t k = 0; k < 5; k++) {
        assert_int_equal(mo.segs.pens[k].pulse_us, want[k]);
        const cs_segment_t *s = &mo.segs.v[mo.segs.pens[k].seg];
        assert_int_equal(s->ticks, 2000); /* 20 ms at 100 kHz */
        assert_true(s->steps[0] == 0 && s->steps[1] == 0 && s->steps[2] == 0);
    }
    /* steps between events: travel to (10, 10), the first stroke's 10 + 20 mm, travel to (40,
     * 40), the second stroke; x, y in steps at 80 steps/mm */
    static const int64_t dx[4] = {800, 800, 1600, 800}, dy[4] = {800, 1600, 800, 0};
    for (size_t k = 0; k + 1 < 5; k++) {
        int64_t sx = 0, sy = 0;
        for (size_t j = mo.segs.pens[k].seg; j < mo.segs.pens[k + 1].seg; j++) {
            sx += mo.segs.v[j].steps[0];
            sy += mo.segs.v[j].steps[1];
        }
        assert_int_equal(sx, dx[k]);
        assert_int_equal(sy, dy[k]);
    }
    cs_motion_free(&mo);
}

static void expect_ini_error(const char *text, const char *msg)
{
    cs_machine_t m;
    cs_machine_pen_t pen;
    char err[256];
    assert_int_equal(cs_machine_ini_parse_pen(text, "bad.ini", &m, &pen, err, sizeof err), -1);
    if (strstr(err, msg) == NULL)
        print_error("got '%s', expected '%s'\n", err, msg);
    assert_non_null(strstr(err, msg));
}

static void test_pen_keys(void **state)
{
    (void)state;
    expect_ini_error("[pen]\nmode = servo\nup_us = 1900\n", "bad.ini:0: [pen] mode = servo needs");
    expect_ini_error("[pen]\nmode = servo\nup_us = 1500\ndown_us = 1500\n",
                     "needs up_us and down_us, different");
    expect_ini_error("[pen]\nup_us = 3000\n", "bad.ini:2: [pen] up_us: must be a whole number");
    expect_ini_error("[pen]\ndown_us = 1500.5\n", "bad.ini:2: [pen] down_us: must be a whole");
    expect_ini_error("[pen]\nsettle_ms = -1\n", "bad.ini:2: [pen] settle_ms: must be a time");
    expect_ini_error("[pen]\nz_feed = 40000\n", "bad.ini:2: [pen] z_feed: must be a speed");
    expect_ini_error("[pen]\nlift = 1\n", "bad.ini:2: [pen] lift: unknown key");
    cs_machine_t m;
    cs_machine_pen_t pen;
    char err[256];
    assert_int_equal(cs_machine_ini_parse_pen("[pen]\nmode = servo\nup_us = 2000\ndown_us = 1000\n",
                                              "ok.ini", &m, &pen, err, sizeof err),
                     0);
    assert_int_equal(pen.mode, CS_MACHINE_PEN_SERVO);
    assert_true(pen.settle_ms == 150); /* the default */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lift_z),
        cmocka_unit_test(test_servo_events),
        cmocka_unit_test(test_pen_keys),
    };
    int r = cmocka_run_group_tests(tests, NULL, NULL);
    cs_path_free(&P);
    return r;
}
