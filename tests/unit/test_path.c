/* test_path: the host path model (host/cs_path.c): elements and subpath numbering, interned
 * names, affine maps, diagnostics, the double evaluator (against tests/support/cs_ref) and the
 * measured chord deviation used by `flatten --stats`, checked against a brute-force maximum
 * computed here from known vertex parameters.
 * Tolerances: the evaluator is the same de Casteljau in double as cs_ref: 1e-12 mm. The
 * deviation: vertices are rounded to the LSB, so the parameter placed for each may move the
 * measured maximum by about one LSB: agreement within 2 LSB (3.1e-5 mm). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_conv.h"
#include "cs_path.h"
#include "cs_ref.h"

#define LSB (1.0 / 65536.0)

static uint64_t rng = 0x9E3779B97F4A7C15ull;

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

static cs_bezier_t line(double x0, double y0, double x1, double y1)
{
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = 1;
    assert_int_equal(cs_conv_mm_to_vec(x0, y0, 0, &c.p[0]), CS_OK);
    assert_int_equal(cs_conv_mm_to_vec(x1, y1, 0, &c.p[1]), CS_OK);
    c.w[0] = c.w[1] = CS_WEIGHT_ONE;
    return c;
}

static cs_bezier_t random_curve(bool rational)
{
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = rational ? 2 : (uint8_t)(1 + xorshift64() % 7);
    c.rational = rational;
    for (unsigned i = 0; i <= c.degree; i++) {
        assert_int_equal(
            cs_conv_mm_to_vec(urand(-100, 100), urand(-100, 100), urand(-5, 5), &c.p[i]), CS_OK);
        c.w[i] = CS_WEIGHT_ONE;
    }
    if (rational)
        assert_int_equal(cs_conv_to_weight(urand(0.2, 1.0), &c.w[1]), CS_OK);
    return c;
}

static void test_elements_and_subpaths(void **state)
{
    (void)state;
    cs_path_t p;
    cs_path_init(&p);
    const char *f = cs_path_intern(&p, "a.svg");
    assert_non_null(f);
    assert_ptr_equal(cs_path_intern(&p, "a.svg"), f);
    assert_ptr_not_equal(cs_path_intern(&p, "b.svg"), f);
    cs_path_loc_t loc = {f, 3, 7};
    cs_bezier_t c = line(0, 0, 1, 1);
    /* The first element opens subpath 0; new_subpath only counts once elements follow. */
    assert_int_equal(cs_path_add(&p, &c, CS_PATH_LINE, loc), CS_OK);
    assert_int_equal(cs_path_add(&p, &c, CS_PATH_LINE, loc), CS_OK);
    cs_path_new_subpath(&p);
    assert_int_equal(cs_path_add(&p, &c, CS_PATH_LINE, loc), CS_OK);
    cs_path_new_subpath(&p);
    cs_path_new_subpath(&p);
    for (int i = 0; i < 1000; i++)
        assert_int_equal(cs_path_add(&p, &c, CS_PATH_CUBIC, loc), CS_OK);
    assert_int_equal(p.n, 1003);
    assert_int_equal(p.nsubpaths, 3);
    assert_int_equal(p.elems[1].subpath, 0);
    assert_int_equal(p.elems[2].subpath, 1);
    assert_int_equal(p.elems[1002].subpath, 2);
    assert_int_equal(p.elems[1002].kind, CS_PATH_CUBIC);
    assert_string_equal(p.elems[1002].loc.file, "a.svg");
    assert_int_equal(p.elems[1002].loc.col, 7);
    double mn[3], mx[3];
    assert_true(cs_path_bbox_mm(&p, mn, mx));
    assert_true(mn[0] == 0 && mn[1] == 0 && mx[0] == 1 && mx[1] == 1);
    cs_path_free(&p);
    assert_int_equal(p.n, 0);
    assert_false(cs_path_bbox_mm(&p, mn, mx));
}

static void test_affine_and_diag(void **state)
{
    (void)state;
    cs_path_affine_t t = {1, 0, 0, 1, 10, 20}, s = {2, 0, 0, 3, 0, 0};
    cs_path_affine_t ts = cs_path_affine_mul(t, s); /* scale first, then translate */
    double x, y;
    cs_path_affine_point(&ts, 1, 1, &x, &y);
    assert_true(x == 12 && y == 23);
    cs_path_affine_t st = cs_path_affine_mul(s, t);
    cs_path_affine_point(&st, 1, 1, &x, &y);
    assert_true(x == 22 && y == 63);
    cs_path_affine_vector(&ts, 1, 1, &x, &y); /* no translation for vectors */
    assert_true(x == 2 && y == 3);
    cs_path_affine_t id = cs_path_affine_identity();
    assert_true(cs_path_affine_is_identity(&id));
    assert_false(cs_path_affine_is_identity(&t));
    cs_path_diag_t d;
    cs_path_loc_t loc = {"f.svg", 12, 34};
    assert_int_equal(cs_path_diag_set(&d, CS_ERR_PARSE, loc, "bad %s %d", "thing", 5),
                     CS_ERR_PARSE);
    char buf[128];
    FILE *m = fmemopen(buf, sizeof buf, "w");
    assert_non_null(m);
    cs_path_diag_print(m, &d);
    fclose(m);
    assert_string_equal(buf, "f.svg:12:34: bad thing 5\n");
}

static void test_eval_matches_reference(void **state)
{
    (void)state;
    for (int i = 0; i < 2000; i++) {
        cs_bezier_t c = random_curve(i % 3 == 0);
        double t = urand(0, 1), q[3];
        cs_path_eval_mm(&c, t, q);
        cs_ref_vec_t r = cs_ref_eval(&c, t);
        assert_true(fabs(q[0] - r.x) < 1e-12 && fabs(q[1] - r.y) < 1e-12 &&
                    fabs(q[2] - r.z) < 1e-12);
    }
    /* Ends are the end control points. */
    cs_bezier_t c = random_curve(true);
    double q[3];
    cs_path_eval_mm(&c, 1.0, q);
    assert_true(q[0] == c.p[2].x * LSB && q[1] == c.p[2].y * LSB);
}

/* Brute force: the largest distance from the curve to the chord of each piece, the pieces
 * between the known parameters ts[] (20000 samples per piece). */
static double brute_deviation(const cs_bezier_t *c, const double *ts, const cs_vec3_t *v, size_t n)
{
    double worst = 0;
    for (size_t k = 0; k + 1 < n; k++) {
        cs_ref_vec_t a = cs_ref_from_pos(&v[k]), b = cs_ref_from_pos(&v[k + 1]);
        for (int j = 0; j <= 20000; j++) {
            double t = ts[k] + (ts[k + 1] - ts[k]) * j / 20000.0;
            double d = cs_ref_dist_point_segment(cs_ref_eval(c, t), a, b);
            if (d > worst)
                worst = d;
        }
    }
    return worst;
}

static void test_deviation(void **state)
{
    (void)state;
    enum { NV = 12 };
    for (int i = 0; i < 60; i++) {
        cs_bezier_t c = random_curve(i % 2 == 0);
        if (c.degree == 1)
            continue; /* a line's chords have no deviation to speak of */
        /* Vertices on the curve at increasing (non-uniform) parameters, rounded to the LSB. */
        double ts[NV];
        cs_vec3_t v[NV];
        ts[0] = 0;
        for (int k = 1; k < NV; k++)
            ts[k] = ts[k - 1] + urand(0.2, 1.0);
        for (int k = 0; k < NV; k++) {
            ts[k] /= ts[NV - 1];
            cs_ref_vec_t q = cs_ref_eval(&c, ts[k]);
            assert_int_equal(cs_conv_mm_to_vec(q.x, q.y, q.z, &v[k]), CS_OK);
        }
        v[0] = c.p[0];
        v[NV - 1] = c.p[c.degree];
        double got = cs_path_deviation_mm(&c, v, NV);
        double want = brute_deviation(&c, ts, v, NV);
        if (fabs(got - want) > 2 * LSB)
            fail_msg("curve %d (degree %u%s): measured %.9f, brute force %.9f", i, c.degree,
                     c.rational ? ", rational" : "", got, want);
    }
    /* A vertex that is not on the curve is reported as HUGE_VAL. */
    cs_bezier_t c = random_curve(false);
    cs_vec3_t v[3] = {c.p[0], {0, 0, 0}, c.p[c.degree]};
    cs_ref_vec_t mid = cs_ref_eval(&c, 0.5);
    assert_int_equal(cs_conv_mm_to_vec(mid.x + 1.0, mid.y + 1.0, mid.z + 1.0, &v[1]), CS_OK);
    assert_true(isinf(cs_path_deviation_mm(&c, v, 3)));
    /* The chord P0-Pn of a straight line: zero. */
    cs_bezier_t l = line(0, 0, 10, 5);
    assert_true(cs_path_deviation_mm(&l, l.p, 2) < 1e-12);
}

static void test_poly(void **state)
{
    (void)state;
    cs_path_poly_t s;
    cs_path_poly_init(&s);
    assert_int_equal(cs_path_poly_line(&s, 1, 2), CS_OK); /* starts a polyline by itself */
    assert_int_equal(cs_path_poly_line(&s, 3, 4), CS_OK);
    assert_int_equal(cs_path_poly_move(&s, 5, 6), CS_OK);
    for (int i = 0; i < 5000; i++)
        assert_int_equal(cs_path_poly_line(&s, i, -i), CS_OK);
    assert_int_equal(s.nlines, 2);
    assert_int_equal(cs_path_poly_len(&s, 0), 2);
    assert_int_equal(cs_path_poly_len(&s, 1), 5001);
    assert_int_equal(cs_path_poly_len(&s, 2), 0);
    assert_true(s.pts[s.starts[1]].x == 5 && s.pts[s.n - 1].y == -4999);
    cs_path_poly_free(&s);
    assert_int_equal(s.n, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_elements_and_subpaths),
        cmocka_unit_test(test_affine_and_diag),
        cmocka_unit_test(test_eval_matches_reference),
        cmocka_unit_test(test_deviation),
        cmocka_unit_test(test_poly),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
