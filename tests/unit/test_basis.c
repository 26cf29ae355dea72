/* test_basis: every basis conversion against the seed's own matrices (seed 003), evaluated in
 * double in the power basis Q(t) = T . M . G, versus the fixed-point Bézier evaluated in double
 * (tests/support/cs_ref). Conversions with an exact integer matrix must agree to 0.5 LSB (one
 * rounding), the beta-spline to 1 LSB (weights rounded to 2^-31). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "cs_basis.h"
#include "cs_ref.h"

#define LSB CS_REF_LSB_MM
#define EPS 1e-9 /* double rounding slack, mm */

/* CS_TEST_VERBOSE=1 prints the measured worst errors. */
static void report(const char *what, double worst_mm)
{
    if (getenv("CS_TEST_VERBOSE"))
        printf("%s: worst %.3f LSB\n", what, worst_mm / LSB);
}

static uint64_t rng = 0x2545F4914F6CDD1Du;
static uint64_t xorshift(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}
/* Uniform integer in [-lim, lim]. */
static int32_t rnd_pos(int32_t lim)
{
    return (int32_t)((int64_t)(xorshift() % (2 * (uint64_t)lim + 1)) - lim);
}
static cs_vec3_t rnd_vec(int32_t lim)
{
    return cs_fixed_vec(rnd_pos(lim), rnd_pos(lim), rnd_pos(lim));
}

/* Q(t) = [t^3 t^2 t 1] . (m / div) . G, coordinates in mm. */
static cs_ref_vec_t power_eval(const double m[4][4], double div, const cs_vec3_t g[4], double t)
{
    double tt[4] = {t * t * t, t * t, t, 1};
    cs_ref_vec_t r = {0, 0, 0};
    for (int i = 0; i < 4; i++) {
        for (int j = 0; j < 4; j++) {
            double k = tt[i] * m[i][j] / div;
            r.x += k * g[j].x * LSB;
            r.y += k * g[j].y * LSB;
            r.z += k * g[j].z * LSB;
        }
    }
    return r;
}

/* Largest per-coordinate difference (mm) between the Bézier and the power form over 21 t. */
static double max_diff(const cs_bezier_t *b, const double m[4][4], double div, const cs_vec3_t g[4])
{
    double worst = 0;
    for (int k = 0; k <= 20; k++) {
        double t = k / 20.0;
        cs_ref_vec_t p = cs_ref_eval(b, t), q = power_eval(m, div, g, t);
        double d = fmax(fabs(p.x - q.x), fmax(fabs(p.y - q.y), fabs(p.z - q.z)));
        worst = fmax(worst, d);
    }
    return worst;
}

/* Seed 003 matrices. */
static const double M_H[4][4] = {{2, -2, 1, 1}, {-3, 3, -2, -1}, {0, 0, 1, 0}, {1, 0, 0, 0}};
static const double M_BS[4][4] = {{-1, 3, -3, 1}, {3, -6, 3, 0}, {-3, 0, 3, 0}, {1, 4, 1, 0}};
static const double M_CR[4][4] = {{-1, 3, -3, 1}, {2, -5, 4, -1}, {-1, 0, 1, 0}, {0, 2, 0, 0}};

static void test_hermite_exact(void **state)
{
    (void)state;
    double worst = 0;
    for (int i = 0; i < 2000; i++) {
        cs_vec3_t g[4] = {rnd_vec(CS_POS_LIMIT / 2), rnd_vec(CS_POS_LIMIT / 2),
                          rnd_vec(CS_POS_LIMIT / 2), rnd_vec(CS_POS_LIMIT / 2)};
        cs_bezier_t b;
        assert_int_equal(cs_basis_hermite(&g[0], &g[1], &g[2], &g[3], &b), CS_OK);
        assert_int_equal(b.degree, 3);
        assert_false(b.rational);
        worst = fmax(worst, max_diff(&b, M_H, 1, g));
        /* Endpoints are interpolated exactly. */
        assert_memory_equal(&b.p[0], &g[0], sizeof(cs_vec3_t));
        assert_memory_equal(&b.p[3], &g[1], sizeof(cs_vec3_t));
    }
    report("hermite", worst);
    assert_true(worst <= 0.5 * LSB + EPS);
}

static void test_hermite_tangent_range(void **state)
{
    (void)state;
    /* A tangent past the coordinate range is fine while P1 + R1/3 stays inside... */
    cs_vec3_t p1 = cs_fixed_vec(0, 0, 0), p4 = cs_fixed_vec(CS_POS_ONE_MM, 0, 0);
    cs_vec3_t r = cs_fixed_vec(3 * (CS_POS_LIMIT - CS_POS_ONE_MM), 0, 0), z = {0, 0, 0};
    cs_bezier_t b;
    assert_int_equal(cs_basis_hermite(&p1, &p4, &r, &z, &b), CS_OK);
    assert_int_equal(b.p[1].x, CS_POS_LIMIT - CS_POS_ONE_MM);
    /* ...and refused when it leaves it. */
    r.x = 3 * CS_POS_LIMIT + 6;
    assert_int_equal(cs_basis_hermite(&p1, &p4, &r, &z, &b), CS_ERR_RANGE);
    cs_vec3_t far = cs_fixed_vec(0, CS_POS_LIMIT + 1, 0);
    assert_int_equal(cs_basis_hermite(&far, &p4, &z, &z, &b), CS_ERR_RANGE);
    assert_int_equal(cs_basis_hermite(NULL, &p4, &z, &z, &b), CS_ERR_ARG);
}

static void test_bspline_exact(void **state)
{
    (void)state;
    double worst = 0;
    for (int i = 0; i < 2000; i++) {
        cs_vec3_t g[4] = {rnd_vec(CS_POS_LIMIT), rnd_vec(CS_POS_LIMIT), rnd_vec(CS_POS_LIMIT),
                          rnd_vec(CS_POS_LIMIT)};
        cs_bezier_t b;
        assert_int_equal(cs_basis_bspline(g, &b), CS_OK);
        worst = fmax(worst, max_diff(&b, M_BS, 6, g));
    }
    report("bspline", worst);
    assert_true(worst <= 0.5 * LSB + EPS);
}

static void test_catmull_rom_exact(void **state)
{
    (void)state;
    double worst = 0;
    for (int i = 0; i < 2000; i++) {
        cs_vec3_t g[4] = {rnd_vec(CS_POS_LIMIT / 2), rnd_vec(CS_POS_LIMIT / 2),
                          rnd_vec(CS_POS_LIMIT / 2), rnd_vec(CS_POS_LIMIT / 2)};
        cs_bezier_t b;
        assert_int_equal(cs_basis_catmull_rom(g, &b), CS_OK);
        worst = fmax(worst, max_diff(&b, M_CR, 2, g));
        /* Interpolates G1 and G2. */
        assert_memory_equal(&b.p[0], &g[1], sizeof(cs_vec3_t));
        assert_memory_equal(&b.p[3], &g[2], sizeof(cs_vec3_t));
    }
    report("catmull-rom", worst);
    assert_true(worst <= 0.5 * LSB + EPS);
    /* Full-range points can push the inner Bézier points outside the range. */
    cs_vec3_t g[4] = {cs_fixed_vec(-CS_POS_LIMIT, 0, 0), cs_fixed_vec(CS_POS_LIMIT, 0, 0),
                      cs_fixed_vec(CS_POS_LIMIT, 0, 0), cs_fixed_vec(0, 0, 0)};
    cs_bezier_t b;
    assert_int_equal(cs_basis_catmull_rom(g, &b), CS_ERR_RANGE);
}

/* Barsky's beta-spline matrix in double (Foley-van Dam eq. 11.47), written from the formula
 * independently of the code's Bézier form. */
static void beta_matrix(double b1, double b2, double m[4][4], double *div)
{
    double d = 2 * b1 * b1 * b1 + 4 * b1 * b1 + 4 * b1 + b2 + 2;
    double r[4][4] = {
        {-2 * b1 * b1 * b1, 2 * (b2 + b1 * b1 * b1 + b1 * b1 + b1), -2 * (b2 + b1 * b1 + b1 + 1),
         2},
        {6 * b1 * b1 * b1, -3 * (b2 + 2 * b1 * b1 * b1 + 2 * b1 * b1), 3 * (b2 + 2 * b1 * b1), 0},
        {-6 * b1 * b1 * b1, 6 * (b1 * b1 * b1 - b1), 6 * b1, 0},
        {2 * b1 * b1 * b1, b2 + 4 * (b1 * b1 + b1), 2, 0},
    };
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            m[i][j] = r[i][j];
    *div = d;
}

static void test_beta_against_matrix(void **state)
{
    (void)state;
    const double params[][2] = {{1, 0},    {0.5, 0},   {2, 0},     {1, 5},          {3.25, 12.5},
                                {0.01, 0}, {16, 1024}, {0.1, 100}, {1.0 / 65536, 0}};
    double worst = 0;
    for (size_t p = 0; p < sizeof params / sizeof params[0]; p++) {
        cs_basis_beta_t b1 = (cs_basis_beta_t)lround(params[p][0] * CS_BASIS_BETA_ONE);
        cs_basis_beta_t b2 = (cs_basis_beta_t)lround(params[p][1] * CS_BASIS_BETA_ONE);
        cs_basis_beta_mat_t mat;
        assert_int_equal(cs_basis_beta_init(&mat, b1, b2), CS_OK);
        double m[4][4], div;
        beta_matrix((double)b1 / CS_BASIS_BETA_ONE, (double)b2 / CS_BASIS_BETA_ONE, m, &div);
        for (int i = 0; i < 500; i++) {
            cs_vec3_t g[4] = {rnd_vec(CS_POS_LIMIT), rnd_vec(CS_POS_LIMIT), rnd_vec(CS_POS_LIMIT),
                              rnd_vec(CS_POS_LIMIT)};
            cs_bezier_t b;
            assert_int_equal(cs_basis_beta(&mat, g, &b), CS_OK);
            worst = fmax(worst, max_diff(&b, m, div, g));
        }
    }
    report("beta", worst);
    assert_true(worst <= 1.0 * LSB + EPS);
}

static void test_beta_reproduces_bspline(void **state)
{
    (void)state;
    cs_basis_beta_mat_t mat;
    assert_int_equal(cs_basis_beta_init(&mat, CS_BASIS_BETA_ONE, 0), CS_OK);
    for (int i = 0; i < 2000; i++) {
        cs_vec3_t g[4] = {rnd_vec(CS_POS_LIMIT), rnd_vec(CS_POS_LIMIT), rnd_vec(CS_POS_LIMIT),
                          rnd_vec(CS_POS_LIMIT)};
        cs_bezier_t a, b;
        assert_int_equal(cs_basis_beta(&mat, g, &a), CS_OK);
        assert_int_equal(cs_basis_bspline(g, &b), CS_OK);
        for (int k = 0; k < 4; k++) {
            assert_true(labs((long)a.p[k].x - b.p[k].x) <= 1);
            assert_true(labs((long)a.p[k].y - b.p[k].y) <= 1);
            assert_true(labs((long)a.p[k].z - b.p[k].z) <= 1);
        }
    }
}

/* Derivatives of a cubic Bézier at its ends (mm per unit t, mm per unit t^2). */
static cs_ref_vec_t d1(const cs_bezier_t *b, int end)
{
    const cs_vec3_t *p = b->p;
    int i = end ? 2 : 0;
    cs_ref_vec_t r = {3 * (p[i + 1].x - p[i].x) * LSB, 3 * (p[i + 1].y - p[i].y) * LSB,
                      3 * (p[i + 1].z - p[i].z) * LSB};
    return r;
}
static cs_ref_vec_t d2(const cs_bezier_t *b, int end)
{
    const cs_vec3_t *p = b->p;
    int i = end ? 1 : 0;
    cs_ref_vec_t r = {6 * (p[i + 2].x - 2.0 * p[i + 1].x + p[i].x) * LSB,
                      6 * (p[i + 2].y - 2.0 * p[i + 1].y + p[i].y) * LSB,
                      6 * (p[i + 2].z - 2.0 * p[i + 1].z + p[i].z) * LSB};
    return r;
}
static double vmax(cs_ref_vec_t a)
{
    return fmax(fabs(a.x), fmax(fabs(a.y), fabs(a.z)));
}

/* Beta-spline joins are G2: Q_i'(0) = b1 Q_{i-1}'(1) and Q_i''(0) = b1^2 Q_{i-1}''(1) + b2
 * Q_{i-1}'(1) (Barsky's beta-constraints). Each control point carries <= 1 LSB, so a first
 * derivative carries <= 6 LSB and a second <= 24 LSB. */
static void test_beta_sequence_g2(void **state)
{
    (void)state;
    cs_vec3_t pts[12];
    for (int i = 0; i < 12; i++)
        pts[i] = rnd_vec(200 * CS_POS_ONE_MM);
    const double params[][2] = {{1, 0}, {1.5, 0}, {0.75, 8}, {2.5, 3}};
    for (size_t p = 0; p < sizeof params / sizeof params[0]; p++) {
        double b1 = params[p][0], b2 = params[p][1];
        cs_basis_seq_t s;
        assert_int_equal(cs_basis_seq_init_beta(&s, pts, 12,
                                                (cs_basis_beta_t)lround(b1 * CS_BASIS_BETA_ONE),
                                                (cs_basis_beta_t)lround(b2 * CS_BASIS_BETA_ONE)),
                         CS_OK);
        assert_int_equal(cs_basis_seq_segments(&s), 9);
        cs_bezier_t prev, cur;
        assert_int_equal(cs_basis_seq_segment(&s, 0, &prev), CS_OK);
        for (size_t i = 1; i < 9; i++) {
            assert_int_equal(cs_basis_seq_segment(&s, i, &cur), CS_OK);
            assert_memory_equal(&prev.p[3], &cur.p[0], sizeof(cs_vec3_t)); /* C0 exactly */
            cs_ref_vec_t a1 = d1(&prev, 1), a2 = d2(&prev, 1), c1 = d1(&cur, 0), c2 = d2(&cur, 0);
            cs_ref_vec_t e1 = {c1.x - b1 * a1.x, c1.y - b1 * a1.y, c1.z - b1 * a1.z};
            cs_ref_vec_t e2 = {c2.x - b1 * b1 * a2.x - b2 * a1.x, c2.y - b1 * b1 * a2.y - b2 * a1.y,
                               c2.z - b1 * b1 * a2.z - b2 * a1.z};
            assert_true(vmax(e1) <= (6 + 6 * b1) * LSB);
            assert_true(vmax(e2) <= (24 + 24 * b1 * b1 + 6 * b2) * LSB);
            prev = cur;
        }
        assert_int_equal(cs_basis_seq_segment(&s, 9, &cur), CS_END);
    }
}

/* Uniform B-spline sequence: m+1 points -> m-2 segments, C2 at the joins (to the LSB bound). */
static void test_bspline_sequence_c2(void **state)
{
    (void)state;
    cs_vec3_t pts[10];
    for (int i = 0; i < 10; i++)
        pts[i] = rnd_vec(1000 * CS_POS_ONE_MM);
    cs_basis_seq_t s;
    assert_int_equal(cs_basis_seq_init(&s, CS_BASIS_BSPLINE, pts, NULL, 10), CS_OK);
    assert_int_equal(cs_basis_seq_segments(&s), 7);
    cs_bezier_t prev, cur;
    assert_int_equal(cs_basis_seq_segment(&s, 0, &prev), CS_OK);
    for (size_t i = 1; i < 7; i++) {
        assert_int_equal(cs_basis_seq_segment(&s, i, &cur), CS_OK);
        assert_memory_equal(&prev.p[3], &cur.p[0], sizeof(cs_vec3_t));
        cs_ref_vec_t a1 = d1(&prev, 1), c1 = d1(&cur, 0), a2 = d2(&prev, 1), c2 = d2(&cur, 0);
        cs_ref_vec_t e1 = {c1.x - a1.x, c1.y - a1.y, c1.z - a1.z};
        cs_ref_vec_t e2 = {c2.x - a2.x, c2.y - a2.y, c2.z - a2.z};
        /* 0.5 LSB per control point: 3 LSB per first derivative, 12 per second. */
        assert_true(vmax(e1) <= 6 * LSB);
        assert_true(vmax(e2) <= 24 * LSB);
        prev = cur;
    }
}

/* Catmull-Rom sequence: interpolates P1..P(m-1); tangent at P_i is (P_{i+1} - P_{i-1}) / 2. */
static void test_catmull_rom_sequence(void **state)
{
    (void)state;
    cs_vec3_t pts[8];
    for (int i = 0; i < 8; i++)
        pts[i] = rnd_vec(1000 * CS_POS_ONE_MM);
    cs_basis_seq_t s;
    assert_int_equal(cs_basis_seq_init(&s, CS_BASIS_CATMULL_ROM, pts, NULL, 8), CS_OK);
    assert_int_equal(cs_basis_seq_segments(&s), 5);
    for (size_t i = 0; i < 5; i++) {
        cs_bezier_t b;
        assert_int_equal(cs_basis_seq_segment(&s, i, &b), CS_OK);
        assert_memory_equal(&b.p[0], &pts[i + 1], sizeof(cs_vec3_t));
        assert_memory_equal(&b.p[3], &pts[i + 2], sizeof(cs_vec3_t));
        cs_ref_vec_t t0 = d1(&b, 0);
        cs_ref_vec_t want = {(pts[i + 2].x - pts[i].x) * LSB / 2,
                             (pts[i + 2].y - pts[i].y) * LSB / 2,
                             (pts[i + 2].z - pts[i].z) * LSB / 2};
        cs_ref_vec_t e = {t0.x - want.x, t0.y - want.y, t0.z - want.z};
        assert_true(vmax(e) <= 1.5 * LSB + EPS); /* 3 x 0.5 LSB */
    }
}

static void test_hermite_sequence(void **state)
{
    (void)state;
    cs_vec3_t pts[5], tan[5];
    for (int i = 0; i < 5; i++) {
        pts[i] = rnd_vec(1000 * CS_POS_ONE_MM);
        tan[i] = rnd_vec(300 * CS_POS_ONE_MM);
    }
    cs_basis_seq_t s;
    assert_int_equal(cs_basis_seq_init(&s, CS_BASIS_HERMITE, pts, tan, 5), CS_OK);
    assert_int_equal(cs_basis_seq_segments(&s), 4);
    for (size_t i = 0; i < 4; i++) {
        cs_bezier_t b;
        assert_int_equal(cs_basis_seq_segment(&s, i, &b), CS_OK);
        cs_vec3_t g[4] = {pts[i], pts[i + 1], tan[i], tan[i + 1]};
        assert_true(max_diff(&b, M_H, 1, g) <= 0.5 * LSB + EPS);
    }
    cs_bezier_t b;
    assert_int_equal(cs_basis_seq_segment(&s, 4, &b), CS_END);
}

/* LinuxCNC's G5 documentation (quoted in /work/shared/data/SOURCES.md): `G5 I0 J3 P0 Q-3 X1 Y1`
 * from (0, 0) passes through (0.5, 0.5) at t = 0.5, and the following `G5 P0 Q-3 X2 Y2` (I, J =
 * the negated previous P, Q) through (1.5, 1.5). G5's offsets are Bézier handles, so the Hermite
 * tangents are R1 = 3 (I, J) and R4 = -3 (P, Q) = (0, 9) at every point. */
static void test_hermite_linuxcnc_g5(void **state)
{
    (void)state;
    const cs_pos_t mm = CS_POS_ONE_MM;
    cs_vec3_t pts[3] = {{0, 0, 0}, {mm, mm, 0}, {2 * mm, 2 * mm, 0}};
    cs_vec3_t tan[3] = {{0, 9 * mm, 0}, {0, 9 * mm, 0}, {0, 9 * mm, 0}};
    cs_basis_seq_t s;
    assert_int_equal(cs_basis_seq_init(&s, CS_BASIS_HERMITE, pts, tan, 3), CS_OK);
    const double want[2] = {0.5, 1.5};
    for (size_t i = 0; i < 2; i++) {
        cs_bezier_t b;
        assert_int_equal(cs_basis_seq_segment(&s, i, &b), CS_OK);
        cs_ref_vec_t q = cs_ref_eval(&b, 0.5);
        assert_true(fabs(q.x - want[i]) <= 0.5 * LSB && fabs(q.y - want[i]) <= 0.5 * LSB);
        /* and the G5 handles themselves: P1 = start + (I, J), P2 = end + (P, Q) */
        assert_int_equal(b.p[1].y, pts[i].y + 3 * mm);
        assert_int_equal(b.p[2].y, pts[i + 1].y - 3 * mm);
    }
}

static void test_seq_errors(void **state)
{
    (void)state;
    cs_vec3_t pts[4] = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {3, 3, 3}};
    cs_basis_seq_t s;
    assert_int_equal(cs_basis_seq_init(&s, CS_BASIS_BSPLINE, pts, NULL, 3), CS_ERR_DEGENERATE);
    assert_int_equal(cs_basis_seq_init(&s, CS_BASIS_HERMITE, pts, NULL, 4), CS_ERR_ARG);
    assert_int_equal(cs_basis_seq_init(&s, CS_BASIS_HERMITE, pts, pts, 1), CS_ERR_DEGENERATE);
    assert_int_equal(cs_basis_seq_init(&s, CS_BASIS_BETA, pts, NULL, 4), CS_ERR_ARG);
    assert_int_equal(cs_basis_seq_init(&s, CS_BASIS_CATMULL_ROM, NULL, NULL, 4), CS_ERR_ARG);
    pts[2].y = CS_POS_LIMIT + 1;
    assert_int_equal(cs_basis_seq_init(&s, CS_BASIS_BSPLINE, pts, NULL, 4), CS_ERR_RANGE);
    pts[2].y = 2;
    cs_basis_beta_mat_t m;
    assert_int_equal(cs_basis_beta_init(&m, 0, 0), CS_ERR_RANGE);
    assert_int_equal(cs_basis_beta_init(&m, -1, 0), CS_ERR_RANGE);
    assert_int_equal(cs_basis_beta_init(&m, CS_BASIS_BETA1_MAX + 1, 0), CS_ERR_RANGE);
    assert_int_equal(cs_basis_beta_init(&m, CS_BASIS_BETA_ONE, -1), CS_ERR_RANGE);
    assert_int_equal(cs_basis_beta_init(&m, CS_BASIS_BETA_ONE, CS_BASIS_BETA2_MAX + 1),
                     CS_ERR_RANGE);
    assert_int_equal(cs_basis_seq_init_beta(&s, pts, 4, 0, 0), CS_ERR_RANGE);
    assert_int_equal(cs_basis_seq_init_beta(&s, pts, 4, CS_BASIS_BETA1_MAX, CS_BASIS_BETA2_MAX),
                     CS_OK);
    assert_int_equal(cs_basis_seq_segments(&s), 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hermite_exact),        cmocka_unit_test(test_hermite_tangent_range),
        cmocka_unit_test(test_bspline_exact),        cmocka_unit_test(test_catmull_rom_exact),
        cmocka_unit_test(test_beta_against_matrix),  cmocka_unit_test(test_beta_reproduces_bspline),
        cmocka_unit_test(test_beta_sequence_g2),     cmocka_unit_test(test_bspline_sequence_c2),
        cmocka_unit_test(test_catmull_rom_sequence), cmocka_unit_test(test_hermite_sequence),
        cmocka_unit_test(test_hermite_linuxcnc_g5),  cmocka_unit_test(test_seq_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
