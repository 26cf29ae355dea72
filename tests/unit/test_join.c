/* Unit tests for cs_join: joins built in double with a known continuity (Hermite-style k = 1
 * and k = 2, kinks, cusps with zero tangents, B-spline C2 joins, G2 with a speed change), the
 * construction checked against the double reference derivatives, then classified. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "cs_join.h"
#include "ref_bezier.h"

#define MM     CS_POS_ONE_MM
#define Q30(x) ((cs_param_t)lround(ldexp((x), 30)))

static const cs_join_tol_t TOL = {2, Q30(1e-4), Q30(1e-4)};

static cs_bezier_t mk(unsigned deg, const int32_t (*pts)[3])
{
    cs_vec3_t p[CS_BEZIER_MAX_POINTS];
    for (unsigned i = 0; i <= deg; i++)
        p[i] = cs_fixed_vec(pts[i][0], pts[i][1], pts[i][2]);
    cs_bezier_t c;
    assert_int_equal(cs_bezier_init(&c, deg, p), CS_OK);
    return c;
}

static unsigned classify(const cs_bezier_t *a, const cs_bezier_t *b, const cs_join_tol_t *t)
{
    unsigned f = 0xFFu;
    assert_int_equal(cs_join_classify(a, b, t, &f), CS_OK);
    return f;
}

/* double reference: B'_b(0) = k B'_a(1) (returns k, and the residual of the best fit) */
static double ref_ratio(const cs_bezier_t *a, const cs_bezier_t *b, double *resid)
{
    ref_bezier_t ra, rb;
    double da[3], db[3];
    ref_bezier_from(a, &ra);
    ref_bezier_from(b, &rb);
    ref_bezier_deriv(&ra, 1.0, da);
    ref_bezier_deriv(&rb, 0.0, db);
    double dd = da[0] * da[0] + da[1] * da[1] + da[2] * da[2];
    double k = (db[0] * da[0] + db[1] * da[1] + db[2] * da[2]) / dd;
    double r = 0;
    for (int i = 0; i < 3; i++)
        r += (db[i] - k * da[i]) * (db[i] - k * da[i]);
    *resid = sqrt(r);
    return k;
}

/* Reference curvature vector (1/LSB) of a polynomial segment at t: (B' x B'') x B' / |B'|^4 */
static void ref_kappa(const cs_bezier_t *c, double t, double k[3])
{
    ref_bezier_t r;
    double d1[3], d2[3];
    ref_bezier_from(c, &r);
    ref_bezier_deriv(&r, t, d1);
    ref_bezier_deriv2(&r, t, d2);
    double s2 = d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2];
    double dot = d1[0] * d2[0] + d1[1] * d2[1] + d1[2] * d2[2];
    for (int i = 0; i < 3; i++)
        k[i] = (d2[i] - dot / s2 * d1[i]) / s2;
}

static void test_hermite_k1_k2(void **state)
{
    (void)state;
    /* a ends at (40, 10) with leg (10, 5) mm; b continues with k * leg */
    const int32_t pa[4][3] = {
        {0, 0, 0}, {10 * MM, 20 * MM, 0}, {30 * MM, 5 * MM, MM}, {40 * MM, 10 * MM, MM}};
    cs_bezier_t a = mk(3, pa);
    for (int k = 1; k <= 2; k++) {
        const int32_t pb[4][3] = {{40 * MM, 10 * MM, MM},
                                  {40 * MM + k * 10 * MM, 10 * MM + k * 5 * MM, MM},
                                  {70 * MM, 60 * MM, 0},
                                  {90 * MM, 0, 0}};
        cs_bezier_t b = mk(3, pb);
        double resid, kk = ref_ratio(&a, &b, &resid);
        assert_true(fabs(kk - k) < 1e-12 && resid < 1e-6);
        unsigned f = classify(&a, &b, &TOL);
        if (k == 1)
            assert_int_equal(f, CS_JOIN_C0 | CS_JOIN_G1 | CS_JOIN_C1);
        else
            assert_int_equal(f, CS_JOIN_C0 | CS_JOIN_G1);
    }
}

static void test_kink_and_reversal(void **state)
{
    (void)state;
    const int32_t pa[3][3] = {{0, 0, 0}, {10 * MM, 0, 0}, {20 * MM, 0, 0}};
    cs_bezier_t a = mk(2, pa);
    /* 30 degree kink, then an exact reversal (k = -1), then an angle of ~1e-5 rad */
    double ang[3] = {M_PI / 6, M_PI, 1e-5};
    unsigned want[3] = {CS_JOIN_C0, CS_JOIN_C0, CS_JOIN_C0 | CS_JOIN_G1};
    for (int i = 0; i < 3; i++) {
        const int32_t pb[3][3] = {{20 * MM, 0, 0},
                                  {20 * MM + (int32_t)lround(10 * MM * cos(ang[i])),
                                   (int32_t)lround(10 * MM * sin(ang[i])), 0},
                                  {50 * MM, 40 * MM, 0}};
        cs_bezier_t b = mk(2, pb);
        unsigned f = classify(&a, &b, &TOL);
        /* the third: sine 1e-5 < 1e-4 -> G1; the speeds equal within 1e-5 too -> C1 */
        if (i == 2)
            want[i] |= CS_JOIN_C1;
        assert_int_equal(f, want[i]);
    }
    /* the same 1e-5 angle with sin_angle = 1e-6 and rel = 1e-6: neither G1 nor C1 */
    cs_join_tol_t tight = {2, Q30(1e-6), Q30(1e-6)};
    const int32_t pb[3][3] = {
        {20 * MM, 0, 0},
        {20 * MM + (int32_t)lround(10 * MM * cos(1e-5)), (int32_t)lround(10 * MM * sin(1e-5)), 0},
        {50 * MM, 40 * MM, 0}};
    cs_bezier_t b = mk(2, pb);
    assert_int_equal(classify(&a, &b, &tight), CS_JOIN_C0);
}

static void test_gap(void **state)
{
    (void)state;
    const int32_t pa[2][3] = {{0, 0, 0}, {10 * MM, 0, 0}};
    const int32_t pb[2][3] = {{10 * MM + 3, 0, 0}, {20 * MM + 3, 0, 0}};
    cs_bezier_t a = mk(1, pa), b = mk(1, pb);
    cs_join_tol_t t = TOL;
    t.pos = 2;
    assert_int_equal(classify(&a, &b, &t), 0u);
    t.pos = 3;
    /* two collinear lines with equal speed: everything holds (zero curvature both sides) */
    assert_int_equal(classify(&a, &b, &t),
                     CS_JOIN_C0 | CS_JOIN_G1 | CS_JOIN_C1 | CS_JOIN_G2 | CS_JOIN_C2);
}

/* Uniform cubic B-spline -> Bézier (seed 003 basis change), control points multiples of 6 so
 * every Bézier point is an exact integer. */
static cs_bezier_t bspline_seg(const double (*d)[3], int i)
{
    int32_t p[4][3];
    for (int a = 0; a < 3; a++) {
        double d0 = d[i][a], d1 = d[i + 1][a], d2 = d[i + 2][a], d3 = d[i + 3][a];
        p[0][a] = (int32_t)((d0 + 4 * d1 + d2) / 6);
        p[1][a] = (int32_t)((2 * d1 + d2) / 3);
        p[2][a] = (int32_t)((d1 + 2 * d2) / 3);
        p[3][a] = (int32_t)((d1 + 4 * d2 + d3) / 6);
    }
    return mk(3, (const int32_t(*)[3])p);
}

static void test_bspline_c2(void **state)
{
    (void)state;
    ref_rng_t g;
    ref_rng_seed(&g, 2024);
    for (int k = 0; k < 200; k++) {
        double d[5][3];
        for (int i = 0; i < 5; i++)
            for (int a = 0; a < 3; a++)
                d[i][a] = 6.0 * (double)ref_rng_range(&g, -600 * MM / 6, 600 * MM / 6);
        cs_bezier_t a = bspline_seg((const double(*)[3])d, 0);
        cs_bezier_t b = bspline_seg((const double(*)[3])d, 1);
        double ka[3], kb[3], resid;
        ref_kappa(&a, 1.0, ka);
        ref_kappa(&b, 0.0, kb);
        assert_true(fabs(ref_ratio(&a, &b, &resid) - 1) < 1e-12);
        for (int i = 0; i < 3; i++)
            assert_true(fabs(ka[i] - kb[i]) <= 1e-9 * (fabs(ka[i]) + 1e-12));
        assert_int_equal(classify(&a, &b, &TOL),
                         CS_JOIN_C0 | CS_JOIN_G1 | CS_JOIN_C1 | CS_JOIN_G2 | CS_JOIN_C2);
        /* moving b's third point along the tangent (by the first leg exactly) keeps the
         * curvature vector (G2) but changes B''(0) (not C2) */
        cs_bezier_t b2 = b;
        b2.p[2].x += b.p[1].x - b.p[0].x;
        b2.p[2].y += b.p[1].y - b.p[0].y;
        b2.p[2].z += b.p[1].z - b.p[0].z;
        ref_kappa(&b2, 0.0, kb);
        for (int i = 0; i < 3; i++)
            assert_true(fabs(ka[i] - kb[i]) <= 1e-9 * (fabs(ka[i]) + 1e-12));
        unsigned f = classify(&a, &b2, &TOL);
        assert_int_equal(f, CS_JOIN_C0 | CS_JOIN_G1 | CS_JOIN_C1 | CS_JOIN_G2);
    }
}

/* G2 without C1: b = a's parametric continuation sped up by k: B_b' = k B_a', B_b'' = k^2 B_a'' */
static void test_g2_speed_change(void **state)
{
    (void)state;
    const int32_t pa[4][3] = {
        {0, 0, 0}, {20 * MM, 30 * MM, 0}, {50 * MM, 40 * MM, 0}, {60 * MM, 40 * MM, 10 * MM}};
    cs_bezier_t a = mk(3, pa);
    int32_t d1[3], d2[3];
    for (int i = 0; i < 3; i++) {
        int32_t *P3 = (int32_t *)pa[3], *P2 = (int32_t *)pa[2], *P1 = (int32_t *)pa[1];
        d1[i] = P3[i] - P2[i];
        d2[i] = P3[i] - 2 * P2[i] + P1[i];
    }
    int32_t pb[4][3];
    for (int i = 0; i < 3; i++) {
        pb[0][i] = pa[3][i];
        pb[1][i] = pb[0][i] + 2 * d1[i];
        pb[2][i] = 2 * pb[1][i] - pb[0][i] + 4 * d2[i];
        pb[3][i] = pb[2][i] + 5 * MM;
    }
    cs_bezier_t b = mk(3, (const int32_t(*)[3])pb);
    double ka[3], kb[3], resid;
    assert_true(fabs(ref_ratio(&a, &b, &resid) - 2) < 1e-12);
    ref_kappa(&a, 1.0, ka);
    ref_kappa(&b, 0.0, kb);
    for (int i = 0; i < 3; i++)
        assert_true(fabs(ka[i] - kb[i]) <= 1e-12 + 1e-9 * fabs(ka[i]));
    assert_int_equal(classify(&a, &b, &TOL), CS_JOIN_C0 | CS_JOIN_G1 | CS_JOIN_G2);
    /* curvature off by 10 %: G1 only */
    for (int i = 0; i < 3; i++)
        pb[2][i] = 2 * pb[1][i] - pb[0][i] + 4 * d2[i] + (4 * d2[i]) / 10;
    b = mk(3, (const int32_t(*)[3])pb);
    assert_int_equal(classify(&a, &b, &TOL), CS_JOIN_C0 | CS_JOIN_G1);
}

/* Different degrees: a quadratic (B'(1) = 2 leg) into a cubic (B'(0) = 3 leg), and a line
 * into a quintic. */
static void test_mixed_degrees(void **state)
{
    (void)state;
    const int32_t pa[3][3] = {{0, 0, 0}, {30 * MM, 30 * MM, 0}, {60 * MM, 45 * MM, 0}};
    cs_bezier_t a = mk(2, pa);
    /* C1: 3 (Q1 - Q0) = 2 (P2 - P1) = (60, 30) mm  ->  Q1 - Q0 = (20, 10) mm */
    const int32_t pb[4][3] = {{60 * MM, 45 * MM, 0},
                              {80 * MM, 55 * MM, 0},
                              {90 * MM, 90 * MM, 0},
                              {120 * MM, 90 * MM, 0}};
    cs_bezier_t b = mk(3, pb);
    double resid;
    assert_true(fabs(ref_ratio(&a, &b, &resid) - 1) < 1e-12);
    assert_int_equal(classify(&a, &b, &TOL), CS_JOIN_C0 | CS_JOIN_G1 | CS_JOIN_C1);
    /* line (B' = (60,0) mm) into a quintic with 5 (Q1-Q0) = (60,0), Q2 on the line: C2
     * (B'' = 20 (Q2 - 2Q1 + Q0) = 0 and the line's B'' = 0) */
    const int32_t pl[2][3] = {{0, 0, 0}, {60 * MM, 0, 0}};
    const int32_t pq[6][3] = {{60 * MM, 0, 0},      {72 * MM, 0, 0},       {84 * MM, 0, 0},
                              {90 * MM, 9 * MM, 0}, {99 * MM, 30 * MM, 0}, {99 * MM, 60 * MM, 0}};
    cs_bezier_t l = mk(1, pl), q = mk(5, pq);
    assert_int_equal(classify(&l, &q, &TOL),
                     CS_JOIN_C0 | CS_JOIN_G1 | CS_JOIN_C1 | CS_JOIN_G2 | CS_JOIN_C2);
    /* degree 7 into degree 1, kink */
    const int32_t p7[8][3] = {{0, 0, 0},      {MM, 0, 0},     {2 * MM, MM, 0}, {3 * MM, 0, 0},
                              {4 * MM, 0, 0}, {5 * MM, 0, 0}, {6 * MM, 0, 0},  {7 * MM, 0, 0}};
    const int32_t pk[2][3] = {{7 * MM, 0, 0}, {7 * MM, 7 * MM, 0}};
    cs_bezier_t s7 = mk(7, p7), k1 = mk(1, pk);
    assert_int_equal(classify(&s7, &k1, &TOL), CS_JOIN_C0);
}

/* Zero tangents (seed 003: C1 implies G1 except when the tangent is (0,0,0)). */
static void test_zero_tangent(void **state)
{
    (void)state;
    /* a: P3 = P2, arriving along +x; b: Q1 = Q0, leaving along +y: B' = 0 on both sides */
    const int32_t pa[4][3] = {{0, 0, 0}, {10 * MM, 0, 0}, {20 * MM, 0, 0}, {20 * MM, 0, 0}};
    const int32_t pb[4][3] = {
        {20 * MM, 0, 0}, {20 * MM, 0, 0}, {20 * MM, 10 * MM, 0}, {20 * MM, 20 * MM, 0}};
    cs_bezier_t a = mk(3, pa), b = mk(3, pb);
    ref_bezier_t ra;
    double d[3];
    ref_bezier_from(&a, &ra);
    ref_bezier_deriv(&ra, 1.0, d);
    assert_true(d[0] == 0 && d[1] == 0 && d[2] == 0);
    /* C1 (both derivatives zero) but a right-angle corner: not G1 */
    assert_int_equal(classify(&a, &b, &TOL), CS_JOIN_C0 | CS_JOIN_C1);
    /* same with b leaving along +x: the geometric tangents agree -> G1 too (no G2: the
     * curvature is undefined where B' = 0) */
    const int32_t pc[4][3] = {
        {20 * MM, 0, 0}, {20 * MM, 0, 0}, {30 * MM, 0, 0}, {40 * MM, 5 * MM, 0}};
    cs_bezier_t c = mk(3, pc);
    unsigned f = classify(&a, &c, &TOL);
    assert_true((f & (CS_JOIN_C0 | CS_JOIN_G1 | CS_JOIN_C1)) ==
                (CS_JOIN_C0 | CS_JOIN_G1 | CS_JOIN_C1));
    assert_true((f & CS_JOIN_G2) == 0);
    /* a fully degenerate segment (one point): C0 only, nothing about tangents */
    const int32_t pz[2][3] = {{20 * MM, 0, 0}, {20 * MM, 0, 0}};
    cs_bezier_t z = mk(1, pz);
    assert_int_equal(classify(&z, &c, &TOL) & CS_JOIN_G1, 0u);
}

/* Rational: two quarter circles (w = 1, sqrt(2)/2, 1) making a half circle: C0, G1 and, with
 * the symmetric weights, C1 (B' = 2 w1/w2 (P2 - P1) on both sides); never G2/C2. */
static void test_rational(void **state)
{
    (void)state;
    const int32_t R = 50 * MM;
    cs_vec3_t pa[3] = {{R, 0, 0}, {R, R, 0}, {0, R, 0}};
    cs_vec3_t pb[3] = {{0, R, 0}, {-R, R, 0}, {-R, 0, 0}};
    cs_weight_t w[3] = {CS_WEIGHT_ONE, Q30(sqrt(0.5)), CS_WEIGHT_ONE};
    cs_bezier_t a, b;
    assert_int_equal(cs_bezier_init_rational(&a, 2, pa, w), CS_OK);
    assert_int_equal(cs_bezier_init_rational(&b, 2, pb, w), CS_OK);
    double resid;
    assert_true(fabs(ref_ratio(&a, &b, &resid) - 1) < 1e-9);
    assert_int_equal(classify(&a, &b, &TOL), CS_JOIN_C0 | CS_JOIN_G1 | CS_JOIN_C1);
    /* b with its weights halved at the start: same circle direction, speed ratio differs */
    cs_weight_t w2[3] = {CS_WEIGHT_ONE / 2, Q30(sqrt(0.5)), CS_WEIGHT_ONE};
    assert_int_equal(cs_bezier_init_rational(&b, 2, pb, w2), CS_OK);
    double k = ref_ratio(&a, &b, &resid);
    assert_true(fabs(k - 2) < 1e-6);
    assert_int_equal(classify(&a, &b, &TOL), CS_JOIN_C0 | CS_JOIN_G1);
}

static void test_bad_args(void **state)
{
    (void)state;
    const int32_t pa[2][3] = {{0, 0, 0}, {10 * MM, 0, 0}};
    cs_bezier_t a = mk(1, pa), bad = a;
    unsigned f;
    cs_join_tol_t t = TOL;
    t.sin_angle = CS_PARAM_ONE + 1;
    assert_int_equal(cs_join_classify(&a, &a, &t, &f), CS_ERR_TOLERANCE);
    t = TOL;
    t.pos = -1;
    assert_int_equal(cs_join_classify(&a, &a, &t, &f), CS_ERR_TOLERANCE);
    t = TOL;
    t.rel = -1;
    assert_int_equal(cs_join_classify(&a, &a, &t, &f), CS_ERR_TOLERANCE);
    bad.degree = 0;
    assert_int_equal(cs_join_classify(&a, &bad, &TOL, &f), CS_ERR_DEGREE);
    bad.degree = 8;
    assert_int_equal(cs_join_classify(&bad, &a, &TOL, &f), CS_ERR_DEGREE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hermite_k1_k2),
        cmocka_unit_test(test_kink_and_reversal),
        cmocka_unit_test(test_gap),
        cmocka_unit_test(test_bspline_c2),
        cmocka_unit_test(test_g2_speed_change),
        cmocka_unit_test(test_mixed_degrees),
        cmocka_unit_test(test_zero_tangent),
        cmocka_unit_test(test_rational),
        cmocka_unit_test(test_bad_args),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
