/* test_layout: the layout options (host/cs_layout.c) against boxes and points worked out by hand:
 * pages, the tight bounding box, flip, rotation about the lower-left corner, scale, --fit into
 * an area with a margin (aspect kept, centred), translate, the SVG page turn, range errors, and
 * that an arc scaled stays exactly the scaled arc (the tolerance holds in output mm).
 * Points are compared to 1 LSB (each control point is rounded once after the map). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "cs_arc.h"
#include "cs_conv.h"
#include "cs_layout.h"
#include "cs_ref.h"

#define LSB (1.0 / 65536.0)

static void add_line(cs_path_t *p, double x0, double y0, double x1, double y1)
{
    cs_vec3_t v[2];
    assert_int_equal(cs_conv_mm_to_vec(x0, y0, 0, &v[0]), CS_OK);
    assert_int_equal(cs_conv_mm_to_vec(x1, y1, 0, &v[1]), CS_OK);
    cs_bezier_t c;
    assert_int_equal(cs_bezier_init(&c, 1, v), CS_OK);
    cs_path_loc_t loc = {"t", 1, 1};
    cs_path_new_subpath(p);
    assert_int_equal(cs_path_add(p, &c, CS_PATH_LINE, loc), CS_OK);
}

static void expect_pt(const cs_vec3_t *v, double x, double y)
{
    if (fabs(cs_conv_pos_to_mm(v->x) - x) > LSB || fabs(cs_conv_pos_to_mm(v->y) - y) > LSB)
        fail_msg("(%.7f, %.7f), expected (%.7f, %.7f)", cs_conv_pos_to_mm(v->x),
                 cs_conv_pos_to_mm(v->y), x, y);
}

static void expect_box(const cs_path_t *p, double x0, double y0, double x1, double y1)
{
    double lo[2], hi[2];
    assert_true(cs_layout_bbox(p, lo, hi));
    if (fabs(lo[0] - x0) > LSB || fabs(lo[1] - y0) > LSB || fabs(hi[0] - x1) > LSB ||
        fabs(hi[1] - y1) > LSB)
        fail_msg("box %.6f %.6f .. %.6f %.6f, expected %.6f %.6f .. %.6f %.6f", lo[0], lo[1], hi[0],
                 hi[1], x0, y0, x1, y1);
}

/* The box (10..30) x (5..15) drawn as its two diagonals' lower-left to upper-right and
 * lower-right to upper-left. */
static void rect_path(cs_path_t *p)
{
    cs_path_init(p);
    add_line(p, 10, 5, 30, 15);
    add_line(p, 30, 5, 10, 15);
}

static cs_layout_area_t no_area = {{0, 0}, {0, 0}};

static void test_pages(void **state)
{
    (void)state;
    double w, h;
    assert_true(cs_layout_parse_page("A4", &w, &h));
    assert_true(w == 210 && h == 297);
    assert_true(cs_layout_parse_page("a3", &w, &h));
    assert_true(w == 297 && h == 420);
    assert_true(cs_layout_parse_page("letter", &w, &h));
    assert_true(fabs(w - 215.9) < 1e-9 && fabs(h - 279.4) < 1e-9);
    assert_true(cs_layout_parse_page("297x210mm", &w, &h));
    assert_true(w == 297 && h == 210);
    assert_true(cs_layout_parse_page("100x50", &w, &h));
    assert_false(cs_layout_parse_page("A6", &w, &h));
    assert_false(cs_layout_parse_page("0x10", &w, &h));
    assert_false(cs_layout_parse_page("10x", &w, &h));
    assert_false(cs_layout_parse_page("10x10in", &w, &h));
}

static void test_bbox_tight(void **state)
{
    (void)state;
    /* cubic (0,0) (0,10) (10,10) (10,0): y(t) = 30 t (1 - t), at most 7.5 at t = 1/2 */
    cs_path_t p;
    cs_path_init(&p);
    cs_vec3_t v[4];
    double pts[4][2] = {{0, 0}, {0, 10}, {10, 10}, {10, 0}};
    for (int i = 0; i < 4; i++)
        assert_int_equal(cs_conv_mm_to_vec(pts[i][0], pts[i][1], 0, &v[i]), CS_OK);
    cs_bezier_t c;
    assert_int_equal(cs_bezier_init(&c, 3, v), CS_OK);
    cs_path_loc_t loc = {"t", 1, 1};
    assert_int_equal(cs_path_add(&p, &c, CS_PATH_CUBIC, loc), CS_OK);
    expect_box(&p, 0, 0, 10, 7.5);
    cs_path_free(&p);
}

static void test_orient_scale_translate(void **state)
{
    (void)state;
    cs_path_t p;
    cs_path_diag_t d;
    cs_layout_opts_t o;
    /* flip-y about the box's middle: y' = 20 - y */
    rect_path(&p);
    cs_layout_opts_init(&o);
    o.flip_y = true;
    assert_int_equal(cs_layout_apply(&o, &no_area, &p, &d), CS_OK);
    expect_pt(&p.elems[0].curve.p[0], 10, 15);
    expect_pt(&p.elems[0].curve.p[1], 30, 5);
    cs_path_free(&p);
    /* rotate 90 keeping the lower-left corner (10, 5): (x, y) -> (10 + 15 - y, 5 + x - 10) */
    rect_path(&p);
    cs_layout_opts_init(&o);
    o.rotate_deg = 90;
    assert_int_equal(cs_layout_apply(&o, &no_area, &p, &d), CS_OK);
    expect_pt(&p.elems[1].curve.p[0], 20, 25); /* (30, 5) */
    expect_pt(&p.elems[1].curve.p[1], 10, 5);  /* (10, 15) */
    expect_box(&p, 10, 5, 20, 25);
    cs_path_free(&p);
    /* rotate 180: (x, y) -> (40 - x, 20 - y) */
    rect_path(&p);
    o.rotate_deg = 180;
    assert_int_equal(cs_layout_apply(&o, &no_area, &p, &d), CS_OK);
    expect_pt(&p.elems[0].curve.p[0], 30, 15);
    cs_path_free(&p);
    /* scale 2 about the origin, then translate (1, -2) */
    rect_path(&p);
    cs_layout_opts_init(&o);
    o.scale = 2;
    o.tx_mm = 1;
    o.ty_mm = -2;
    assert_int_equal(cs_layout_apply(&o, &no_area, &p, &d), CS_OK);
    expect_box(&p, 21, 8, 61, 28);
    cs_path_free(&p);
    /* out of range after scaling: a located range error */
    rect_path(&p);
    o.scale = 1000;
    assert_int_equal(cs_layout_apply(&o, &no_area, &p, &d), CS_ERR_RANGE);
    assert_non_null(strstr(d.reason, "outside"));
    cs_path_free(&p);
}

static void test_fit(void **state)
{
    (void)state;
    cs_path_t p;
    cs_path_diag_t d;
    cs_layout_opts_t o;
    /* A drawing twice the bed: 0..400 x 0..200 into a 200 x 100 bed: factor 1/2, exactly the
     * bed. */
    cs_path_init(&p);
    add_line(&p, 0, 0, 400, 200);
    cs_layout_opts_init(&o);
    o.fit = true;
    cs_layout_area_t bed = {{0, 0}, {200, 100}};
    assert_int_equal(cs_layout_apply(&o, &bed, &p, &d), CS_OK);
    expect_box(&p, 0, 0, 200, 100);
    cs_path_free(&p);
    /* A margin of 10: 180 x 80 left, factor min(180/400, 80/200) = 0.4, 160 x 80, centred. */
    cs_path_init(&p);
    add_line(&p, 0, 0, 400, 200);
    o.margin_mm = 10;
    assert_int_equal(cs_layout_apply(&o, &bed, &p, &d), CS_OK);
    expect_box(&p, 20, 10, 180, 90);
    cs_path_free(&p);
    /* An A4 page 210 x 297 with 15 mm margin, box 50 x 25 at (100, 100): 180 / 50 = 3.6 wins,
     * 180 x 90 centred on (105, 148.5). */
    cs_path_init(&p);
    add_line(&p, 100, 100, 150, 125);
    cs_layout_area_t a4 = {{0, 0}, {210, 297}};
    o.margin_mm = 15;
    assert_int_equal(cs_layout_apply(&o, &a4, &p, &d), CS_OK);
    expect_box(&p, 15, 103.5, 195, 193.5);
    cs_path_free(&p);
    /* No room. */
    cs_path_init(&p);
    add_line(&p, 0, 0, 10, 10);
    o.margin_mm = 200;
    assert_int_equal(cs_layout_apply(&o, &a4, &p, &d), CS_ERR_ARG);
    cs_path_free(&p);
}

static void test_svg_page_turn(void **state)
{
    (void)state;
    /* An SVG page 100 mm high: y' = 100 - y, as a browser shows it seen from above. */
    cs_path_t p;
    cs_path_diag_t d;
    cs_layout_opts_t o;
    cs_layout_opts_init(&o);
    cs_path_init(&p);
    add_line(&p, 10, 20, 30, 25);
    p.page_y_down = true;
    p.page_h_mm = 100;
    assert_false(cs_layout_is_identity(&o, &p));
    assert_int_equal(cs_layout_apply(&o, &no_area, &p, &d), CS_OK);
    expect_pt(&p.elems[0].curve.p[0], 10, 80);
    expect_pt(&p.elems[0].curve.p[1], 30, 75);
    assert_false(p.page_y_down);
    cs_path_free(&p);
    /* No height given: about the drawing's own box (20..25): y' = 45 - y. */
    cs_path_init(&p);
    add_line(&p, 10, 20, 30, 25);
    p.page_y_down = true;
    assert_int_equal(cs_layout_apply(&o, &no_area, &p, &d), CS_OK);
    expect_pt(&p.elems[0].curve.p[0], 10, 25);
    cs_path_free(&p);
}

static void test_arc_scaled_exactly(void **state)
{
    (void)state;
    /* A quarter circle r = 10 about (5, 5), scaled by 3: every point of the result is on the
     * circle r = 30 about (15, 15) to within the arc's own error times 3 plus an LSB. */
    cs_vec3_t c, u, v;
    assert_int_equal(cs_conv_mm_to_vec(5, 5, 0, &c), CS_OK);
    assert_int_equal(cs_conv_mm_to_vec(10, 0, 0, &u), CS_OK);
    assert_int_equal(cs_conv_mm_to_vec(0, 10, 0, &v), CS_OK);
    cs_bezier_t seg[CS_ARC_MAX_SEGMENTS];
    unsigned n = 0;
    assert_int_equal(cs_arc_build(&c, &u, &v, CS_PARAM_ONE, 0, 0, CS_PARAM_ONE, true, seg, &n),
                     CS_OK);
    cs_path_t p;
    cs_path_init(&p);
    cs_path_loc_t loc = {"t", 1, 1};
    for (unsigned i = 0; i < n; i++)
        assert_int_equal(cs_path_add(&p, &seg[i], CS_PATH_ARC, loc), CS_OK);
    cs_layout_opts_t o;
    cs_layout_opts_init(&o);
    o.scale = 3;
    cs_path_diag_t d;
    assert_int_equal(cs_layout_apply(&o, &no_area, &p, &d), CS_OK);
    for (size_t i = 0; i < p.n; i++)
        for (int k = 0; k <= 64; k++) {
            cs_ref_vec_t q = cs_ref_eval(&p.elems[i].curve, k / 64.0);
            assert_true(fabs(hypot(q.x - 15, q.y - 15) - 30) <= 7 * LSB);
        }
    cs_path_free(&p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pages),
        cmocka_unit_test(test_bbox_tight),
        cmocka_unit_test(test_orient_scale_translate),
        cmocka_unit_test(test_fit),
        cmocka_unit_test(test_svg_page_turn),
        cmocka_unit_test(test_arc_scaled_exactly),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
