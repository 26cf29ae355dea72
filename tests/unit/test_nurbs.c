/* test_nurbs: Bézier extraction of B-splines and NURBS, checked two ways:
 *  - against published values of NURBS-Python (geomdl), copied below from
 *    /work/shared/data/reference_values/geomdl_bspline_nurbs_eval.json, whose source line is:
 *      orbingol/NURBS-Python (geomdl), tests/test_curve.py and tests/test_surface.py, commit
 *      8ae8b127eb0b130a25a6c81e98e90f319733bca0, MIT License
 *    ("expected" = as published, checked there with |err| < 0.001; "recomputed_float64" = an
 *    independent float64 Cox-de Boor evaluation of the same curves, stored in the same file);
 *  - against a double-precision Cox-de Boor evaluation (Piegl & Tiller A2.2/A4.1) written here,
 *    on random curves of degree 1..3 with repeated knots and random weights.
 * Segments are evaluated in double (tests/support/cs_ref) from their fixed-point data. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "cs_nurbs.h"
#include "cs_ref.h"

#define LSB    CS_REF_LSB_MM
#define MAXSEG 64

static cs_vec3_t vmm(double x, double y, double z)
{
    return cs_fixed_vec((cs_pos_t)lround(x * 65536.0), (cs_pos_t)lround(y * 65536.0),
                        (cs_pos_t)lround(z * 65536.0));
}

/* Curve point at knot value u (in the knots' own units), from the extracted segments. */
static cs_ref_vec_t seg_eval(const cs_nurbs_t *c, double u)
{
    cs_nurbs_iter_t it;
    cs_bezier_t b, last;
    cs_nurbs_knot_t u0, u1, l0 = 0, l1 = 1;
    int have = 0;
    cs_nurbs_iter_begin(c, &it);
    for (;;) {
        cs_err_t e = cs_nurbs_next(c, &it, &b, &u0, &u1);
        if (e == CS_END)
            break;
        assert_int_equal(e, CS_OK);
        if (u >= u0 && u < u1)
            return cs_ref_eval(&b, (u - u0) / ((double)u1 - u0));
        last = b;
        l0 = u0;
        l1 = u1;
        have = 1;
    }
    assert_true(have && u <= l1);
    return cs_ref_eval(&last, (u - l0) / ((double)l1 - l0));
}

/* Cox-de Boor in double: the reference. Knots and u in the same units. */
static cs_ref_vec_t cdb_eval(unsigned p, const cs_vec3_t *pts, const double *w, size_t count,
                             const double *kn, double u)
{
    size_t span = p;
    while (span + 1 < count && u >= kn[span + 1])
        span++;
    double N[4] = {1, 0, 0, 0}, left[4], right[4];
    for (unsigned jj = 1; jj <= p; jj++) {
        left[jj] = u - kn[span + 1 - jj];
        right[jj] = kn[span + jj] - u;
        double saved = 0;
        for (unsigned r = 0; r < jj; r++) {
            double tmp = N[r] / (right[r + 1] + left[jj - r]);
            N[r] = saved + right[r + 1] * tmp;
            saved = left[jj - r] * tmp;
        }
        N[jj] = saved;
    }
    cs_ref_vec_t num = {0, 0, 0};
    double den = 0;
    for (unsigned r = 0; r <= p; r++) {
        size_t i = span - p + r;
        double nw = N[r] * (w ? w[i] : 1.0);
        num.x += nw * pts[i].x * LSB;
        num.y += nw * pts[i].y * LSB;
        num.z += nw * pts[i].z * LSB;
        den += nw;
    }
    cs_ref_vec_t r = {num.x / den, num.y / den, num.z / den};
    return r;
}

static double dist(cs_ref_vec_t a, double x, double y)
{
    return fmax(fabs(a.x - x), fmax(fabs(a.y - y), fabs(a.z)));
}

/* geomdl test_bspline_curve2d_eval / test_nurbs_curve2d_eval data. */
static const double G_PTS[6][2] = {{5, 5}, {10, 10}, {20, 15}, {35, 15}, {45, 10}, {50, 5}};
static const double G_W[6] = {0.5, 1.0, 0.75, 1.0, 0.25, 1.0};
static const struct {
    double u, expected[2], recomputed[2];
} G_BSPLINE[] =
    {
        {0.0, {5.0, 5.0}, {5.0, 5.0}},
        {0.3, {18.617, 13.377}, {18.617580766, 13.37716003}},
        {0.5, {27.645, 14.691}, {27.645492307, 14.691702224}},
        {0.6, {32.143, 14.328}, {32.143206225, 14.32813561}},
        {1.0, {50.0, 5.0}, {50.0, 5.0}},
},
  G_NURBS[] =
      {
          {0.0, {5.0, 5.0}, {5.0, 5.0}},
          {0.2, {13.8181, 11.5103}, {13.818197582, 11.510396141}},
          {0.5, {28.1775, 14.7858}, {28.177525267, 14.785855215}},
          {0.95, {48.7837, 6.0022}, {48.783792218, 6.002231266}},
},
  G_UNNORM[] = {
      /* knots 0,0,0,0,1,2,3,3,3,3 */
      {0.0, {5.0, 5.0}, {5.0, 5.0}},          {1.0, {19.9998, 13.7499}, {20.0, 13.75}},
      {1.5, {27.5, 14.687}, {27.5, 14.6875}}, {2.0, {34.9997, 13.75}, {35.0, 13.75}},
      {3.0, {50.0, 5.0}, {50.0, 5.0}},
};
#define GEOMDL_TOL 0.001 /* the published check */

static void geomdl_points(cs_vec3_t pts[6])
{
    for (int i = 0; i < 6; i++)
        pts[i] = vmm(G_PTS[i][0], G_PTS[i][1], 0);
}

/* Knots 0.33 and 0.66 given exactly, on the scale 1 = 100 (only ratios matter). */
static void test_geomdl_bspline_exact_knots(void **state)
{
    (void)state;
    cs_vec3_t pts[6];
    geomdl_points(pts);
    const cs_nurbs_knot_t kn[10] = {0, 0, 0, 0, 33, 66, 100, 100, 100, 100};
    cs_nurbs_t c;
    assert_int_equal(cs_nurbs_init(&c, 3, pts, NULL, 6, kn, 10), CS_OK);
    assert_int_equal(cs_nurbs_segments(&c), 3);
    for (size_t i = 0; i < sizeof G_BSPLINE / sizeof G_BSPLINE[0]; i++) {
        cs_ref_vec_t p = seg_eval(&c, G_BSPLINE[i].u * 100);
        assert_true(dist(p, G_BSPLINE[i].expected[0], G_BSPLINE[i].expected[1]) <= GEOMDL_TOL);
        /* the float64 recomputation carries 9 decimals: 1 LSB + 1e-9 mm */
        assert_true(dist(p, G_BSPLINE[i].recomputed[0], G_BSPLINE[i].recomputed[1]) <= LSB + 1e-9);
    }
}

/* The same with the knots rounded to Q16.16 (0.33 -> 21627/65536): within the published
 * tolerance of the published values, and within 1 LSB of Cox-de Boor on the rounded knots. */
static void test_geomdl_bspline_q16_knots(void **state)
{
    (void)state;
    cs_vec3_t pts[6];
    geomdl_points(pts);
    const double kd[10] = {0, 0, 0, 0, 0.33, 0.66, 1, 1, 1, 1};
    cs_nurbs_knot_t kn[10];
    double kq[10];
    for (int i = 0; i < 10; i++) {
        kn[i] = (cs_nurbs_knot_t)lround(kd[i] * CS_NURBS_KNOT_ONE);
        kq[i] = (double)kn[i] / CS_NURBS_KNOT_ONE;
    }
    cs_nurbs_t c;
    assert_int_equal(cs_nurbs_init(&c, 3, pts, NULL, 6, kn, 10), CS_OK);
    for (size_t i = 0; i < sizeof G_BSPLINE / sizeof G_BSPLINE[0]; i++) {
        double u = G_BSPLINE[i].u;
        cs_ref_vec_t p = seg_eval(&c, u * CS_NURBS_KNOT_ONE);
        assert_true(dist(p, G_BSPLINE[i].expected[0], G_BSPLINE[i].expected[1]) <= GEOMDL_TOL);
        cs_ref_vec_t r = cdb_eval(3, pts, NULL, 6, kq, u);
        assert_true(dist(p, r.x, r.y) <= LSB);
    }
}

static void test_geomdl_nurbs(void **state)
{
    (void)state;
    cs_vec3_t pts[6];
    geomdl_points(pts);
    int32_t w[6];
    for (int i = 0; i < 6; i++)
        w[i] = (int32_t)lround(G_W[i] * CS_WEIGHT_ONE); /* exact in Q1.30 */
    const cs_nurbs_knot_t kn[10] = {0, 0, 0, 0, 33, 66, 100, 100, 100, 100};
    cs_nurbs_t c;
    assert_int_equal(cs_nurbs_init(&c, 3, pts, w, 6, kn, 10), CS_OK);
    double worst = 0;
    for (size_t i = 0; i < sizeof G_NURBS / sizeof G_NURBS[0]; i++) {
        cs_ref_vec_t p = seg_eval(&c, G_NURBS[i].u * 100);
        assert_true(dist(p, G_NURBS[i].expected[0], G_NURBS[i].expected[1]) <= GEOMDL_TOL);
        double d = dist(p, G_NURBS[i].recomputed[0], G_NURBS[i].recomputed[1]);
        worst = fmax(worst, d);
        assert_true(d <= LSB + 1e-9); /* in real space, after the division by the weight */
    }
    if (getenv("CS_TEST_VERBOSE"))
        printf("geomdl nurbs: worst %.3f LSB\n", worst / LSB);
    /* The segments really are rational, with the largest weight normalised to 1. */
    cs_bezier_t seg[3];
    size_t n = 0;
    assert_int_equal(cs_nurbs_to_bezier(&c, seg, 3, &n), CS_OK);
    assert_int_equal(n, 3);
    for (size_t s = 0; s < n; s++) {
        assert_true(seg[s].rational);
        cs_weight_t m = 0;
        for (int i = 0; i < 4; i++) {
            assert_true(seg[s].w[i] >= CS_WEIGHT_MIN && seg[s].w[i] <= CS_WEIGHT_ONE);
            if (seg[s].w[i] > m)
                m = seg[s].w[i];
        }
        assert_int_equal(m, CS_WEIGHT_ONE);
    }
}

static void test_geomdl_unnormalised_knots(void **state)
{
    (void)state;
    cs_vec3_t pts[6];
    geomdl_points(pts);
    const cs_nurbs_knot_t one = CS_NURBS_KNOT_ONE;
    const cs_nurbs_knot_t kn[10] = {0, 0, 0, 0, one, 2 * one, 3 * one, 3 * one, 3 * one, 3 * one};
    cs_nurbs_t c;
    assert_int_equal(cs_nurbs_init(&c, 3, pts, NULL, 6, kn, 10), CS_OK);
    for (size_t i = 0; i < sizeof G_UNNORM / sizeof G_UNNORM[0]; i++) {
        cs_ref_vec_t p = seg_eval(&c, G_UNNORM[i].u * one);
        assert_true(dist(p, G_UNNORM[i].expected[0], G_UNNORM[i].expected[1]) <= GEOMDL_TOL);
        assert_true(dist(p, G_UNNORM[i].recomputed[0], G_UNNORM[i].recomputed[1]) <= LSB + 1e-9);
    }
    /* Same knots on another scale: the very same segments. */
    const cs_nurbs_knot_t kn2[10] = {0, 0, 0, 0, 7, 14, 21, 21, 21, 21};
    cs_nurbs_t c2;
    assert_int_equal(cs_nurbs_init(&c2, 3, pts, NULL, 6, kn2, 10), CS_OK);
    cs_bezier_t a[3], b[3];
    size_t na, nb;
    assert_int_equal(cs_nurbs_to_bezier(&c, a, 3, &na), CS_OK);
    assert_int_equal(cs_nurbs_to_bezier(&c2, b, 3, &nb), CS_OK);
    assert_int_equal(na, 3);
    assert_int_equal(nb, 3);
    for (int s = 0; s < 3; s++)
        assert_memory_equal(a[s].p, b[s].p, 4 * sizeof(cs_vec3_t));
}

/* Classic 9-point NURBS circle (degree 2, weights 1, sqrt(2)/2): every point on the circle. */
static void test_nurbs_circle(void **state)
{
    (void)state;
    const double R = 123.456;
    const double xy[9][2] = {{1, 0},   {1, 1},  {0, 1},  {-1, 1}, {-1, 0},
                             {-1, -1}, {0, -1}, {1, -1}, {1, 0}};
    cs_vec3_t pts[9];
    int32_t w[9];
    for (int i = 0; i < 9; i++) {
        pts[i] = vmm(R * xy[i][0], R * xy[i][1], 10);
        w[i] = i % 2 ? (int32_t)lround(sqrt(0.5) * CS_WEIGHT_ONE) : CS_WEIGHT_ONE;
    }
    const cs_nurbs_knot_t kn[12] = {0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 4};
    cs_nurbs_t c;
    assert_int_equal(cs_nurbs_init(&c, 2, pts, w, 9, kn, 12), CS_OK);
    assert_int_equal(cs_nurbs_segments(&c), 4);
    double worst = 0;
    for (int k = 0; k <= 400; k++) {
        cs_ref_vec_t p = seg_eval(&c, 4.0 * k / 400);
        worst = fmax(worst, fabs(hypot(p.x, p.y) - R));
        assert_true(fabs(p.z - 10) <= 1e-12);
    }
    assert_true(worst <= LSB);
}

static uint64_t rng = 0xD1B54A32D192ED03u;
static uint64_t xorshift(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}
static double rnd(void)
{
    return (double)(xorshift() >> 11) / 9007199254740992.0;
}

/* Random curves of degree 1..3: clamped or not, interior knots repeated up to p times, random
 * weights over a 1:64 ratio; every segment against Cox-de Boor at 40 parameters per span. */
static void test_random_vs_cox_de_boor(void **state)
{
    (void)state;
    double worst_poly = 0, worst_rat = 0;
    for (int trial = 0; trial < 400; trial++) {
        unsigned p = 1 + (unsigned)(xorshift() % 3);
        size_t count = p + 1 + (size_t)(xorshift() % 9);
        size_t nk = count + p + 1;
        cs_vec3_t pts[16];
        int32_t w[16];
        cs_nurbs_knot_t kn[24];
        double kd[24], wd[16];
        int rational = trial % 2;
        int clamped = (trial / 2) % 2;
        for (size_t i = 0; i < count; i++) {
            pts[i] = vmm((rnd() - 0.5) * 4000, (rnd() - 0.5) * 4000, (rnd() - 0.5) * 400);
            w[i] = (int32_t)lround(exp2(-6 * rnd()) * CS_WEIGHT_ONE);
            wd[i] = w[i];
        }
        int32_t k = 0;
        for (size_t i = 0; i < nk; i++) {
            int repeat = (clamped && (i <= p || i >= count)) || (i > 0 && rnd() < 0.25);
            if (i > 0 && !repeat)
                k += 1 + (int32_t)(xorshift() % 200000);
            kn[i] = k;
        }
        /* Keep every multiplicity <= p + 1 (a random run may be longer): re-space it. */
        for (size_t i = p + 1; i < nk; i++)
            if (kn[i] == kn[i - p - 1])
                for (size_t m = i; m < nk; m++)
                    kn[m] += 1000;
        for (size_t i = 0; i < nk; i++)
            kd[i] = kn[i];
        cs_nurbs_t c;
        cs_err_t e = cs_nurbs_init(&c, p, pts, rational ? w : NULL, count, kn, nk);
        if (e == CS_ERR_KNOTS) /* empty domain: possible with long runs at the ends */
            continue;
        assert_int_equal(e, CS_OK);
        cs_nurbs_iter_t it;
        cs_nurbs_iter_begin(&c, &it);
        cs_bezier_t b;
        cs_nurbs_knot_t u0, u1;
        size_t nseg = 0;
        while ((e = cs_nurbs_next(&c, &it, &b, &u0, &u1)) == CS_OK) {
            nseg++;
            assert_int_equal(b.degree, p);
            for (int s = 0; s <= 40; s++) {
                double t = s / 40.0, u = u0 + t * ((double)u1 - u0);
                if (s == 40 && u1 < kn[count]) /* the span's end belongs to the next span */
                    continue;
                cs_ref_vec_t q = cs_ref_eval(&b, t);
                cs_ref_vec_t r = cdb_eval(p, pts, rational ? wd : NULL, count, kd, u);
                double d = fmax(fabs(q.x - r.x), fmax(fabs(q.y - r.y), fabs(q.z - r.z)));
                if (rational)
                    worst_rat = fmax(worst_rat, d);
                else
                    worst_poly = fmax(worst_poly, d);
            }
        }
        assert_int_equal(e, CS_END);
        assert_int_equal(nseg, cs_nurbs_segments(&c));
    }
    if (getenv("CS_TEST_VERBOSE"))
        printf("random: worst polynomial %.3f LSB, rational %.3f LSB\n", worst_poly / LSB,
               worst_rat / LSB);
    /* Control points carry <= 0.5 LSB, the curve is their convex combination. */
    assert_true(worst_poly <= 0.5 * LSB + 1e-9);
    assert_true(worst_rat <= 1.0 * LSB);
}

/* Clamped curves start and end on their end control points; segments join within 1 LSB. */
static void test_clamped_ends_and_joins(void **state)
{
    (void)state;
    cs_vec3_t pts[7];
    for (int i = 0; i < 7; i++)
        pts[i] = vmm((rnd() - 0.5) * 1000, (rnd() - 0.5) * 1000, 0);
    const cs_nurbs_knot_t kn[11] = {0, 0, 0, 0, 10, 25, 25, 40, 40, 40, 40};
    cs_nurbs_t c;
    assert_int_equal(cs_nurbs_init(&c, 3, pts, NULL, 7, kn, 11), CS_OK);
    cs_bezier_t seg[MAXSEG];
    size_t n = 0;
    assert_int_equal(cs_nurbs_to_bezier(&c, seg, MAXSEG, &n), CS_OK);
    assert_int_equal(n, 3);
    assert_memory_equal(&seg[0].p[0], &pts[0], sizeof(cs_vec3_t));
    assert_memory_equal(&seg[n - 1].p[3], &pts[6], sizeof(cs_vec3_t));
    for (size_t s = 1; s < n; s++) {
        assert_true(labs((long)seg[s].p[0].x - seg[s - 1].p[3].x) <= 1);
        assert_true(labs((long)seg[s].p[0].y - seg[s - 1].p[3].y) <= 1);
    }
    /* Too small an output array. */
    assert_int_equal(cs_nurbs_to_bezier(&c, seg, 2, &n), CS_ERR_FULL);
}

static void test_errors(void **state)
{
    (void)state;
    cs_vec3_t pts[5] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {4, 0, 0}};
    int32_t w[5] = {1, 1, 1, 1, 1};
    cs_nurbs_knot_t kn[9] = {0, 0, 0, 0, 5, 9, 9, 9, 9};
    cs_nurbs_t c;
    assert_int_equal(cs_nurbs_init(&c, 3, pts, w, 5, kn, 9), CS_OK);
    assert_int_equal(cs_nurbs_init(&c, 0, pts, w, 5, kn, 9), CS_ERR_DEGREE);
    assert_int_equal(cs_nurbs_init(&c, 4, pts, w, 5, kn, 10), CS_ERR_DEGREE);
    assert_int_equal(cs_nurbs_init(&c, 3, pts, w, 5, kn, 8), CS_ERR_KNOTS);
    assert_int_equal(cs_nurbs_init(&c, 3, pts, w, 3, kn, 7), CS_ERR_KNOTS); /* too few pts */
    assert_int_equal(cs_nurbs_init(NULL, 3, pts, w, 5, kn, 9), CS_ERR_ARG);
    assert_int_equal(cs_nurbs_init(&c, 3, pts, w, 5, NULL, 9), CS_ERR_ARG);
    kn[4] = -1; /* decreasing */
    assert_int_equal(cs_nurbs_init(&c, 3, pts, w, 5, kn, 9), CS_ERR_KNOTS);
    kn[4] = 0; /* multiplicity 5 > p + 1 */
    assert_int_equal(cs_nurbs_init(&c, 3, pts, w, 5, kn, 9), CS_ERR_KNOTS);
    cs_nurbs_knot_t flat[9] = {0, 3, 3, 3, 3, 3, 3, 3, 8}; /* empty domain, and run of 7 */
    assert_int_equal(cs_nurbs_init(&c, 3, pts, w, 5, flat, 9), CS_ERR_KNOTS);
    kn[4] = 5;
    w[2] = 0;
    assert_int_equal(cs_nurbs_init(&c, 3, pts, w, 5, kn, 9), CS_ERR_WEIGHT);
    w[2] = -3;
    assert_int_equal(cs_nurbs_init(&c, 3, pts, w, 5, kn, 9), CS_ERR_WEIGHT);
    w[2] = 1;
    pts[1].x = CS_POS_LIMIT + 1;
    assert_int_equal(cs_nurbs_init(&c, 3, pts, w, 5, kn, 9), CS_ERR_RANGE);
    pts[1].x = 1;
    /* A weight ratio of 2^26: the first segment's end weight normalises below CS_WEIGHT_MIN. */
    int32_t wx[5] = {1, 1 << 26, 1 << 26, 1 << 26, 1 << 26};
    assert_int_equal(cs_nurbs_init(&c, 3, pts, wx, 5, kn, 9), CS_OK);
    cs_nurbs_iter_t it;
    cs_bezier_t b;
    cs_nurbs_iter_begin(&c, &it);
    assert_int_equal(cs_nurbs_next(&c, &it, &b, NULL, NULL), CS_ERR_WEIGHT);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_geomdl_bspline_exact_knots),
        cmocka_unit_test(test_geomdl_bspline_q16_knots),
        cmocka_unit_test(test_geomdl_nurbs),
        cmocka_unit_test(test_geomdl_unnormalised_knots),
        cmocka_unit_test(test_nurbs_circle),
        cmocka_unit_test(test_random_vs_cox_de_boor),
        cmocka_unit_test(test_clamped_ends_and_joins),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
