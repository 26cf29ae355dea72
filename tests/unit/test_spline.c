/* test_spline: the fixed-point natural cubic spline against a double-precision solve of the
 * textbook second-derivative formulation (unknowns M_i = S''(u_i), M_0 = M_n = 0; Numerical
 * Recipes "spline", the code cited by seed 003), which shares nothing with the code's tangent
 * formulation. All lengths here are in LSB (1/65536 mm). Bounds checked:
 *   - interpolation: every segment starts and ends exactly on its points;
 *   - inner Bézier points within 1 LSB of the exact spline's (0.5 LSB rounding + solve error);
 *   - the curve within 1 LSB of the exact spline at 21 parameters per segment;
 *   - C1 and C2 at the joins and zero curvature at the ends, within what 1 LSB of control
 *     point error allows (derivatives formed from the fixed-point control points). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "cs_ref.h"
#include "cs_spline.h"

#define N_MAX CS_SPLINE_MAX_POINTS

static uint64_t rng = 0x853C49E6748FEA9Bu;
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

static double coord(const cs_vec3_t *p, int a)
{
    return a == 0 ? p->x : a == 1 ? p->y : p->z;
}

typedef struct {
    double h[N_MAX];     /* parameter steps (LSB in chord mode, 1 in uniform) */
    double M[N_MAX][3];  /* second derivatives at the points */
    double b1[N_MAX][3]; /* exact Bézier inner points of each segment */
    double b2[N_MAX][3];
} ref_t;

/* Natural spline, second-derivative form, tridiagonal solve in double. */
static void ref_solve(const cs_vec3_t *p, size_t count, cs_spline_param_t param, ref_t *r)
{
    size_t n = count - 1;
    for (size_t i = 0; i < n; i++) {
        double dx = coord(&p[i + 1], 0) - coord(&p[i], 0),
               dy = coord(&p[i + 1], 1) - coord(&p[i], 1),
               dz = coord(&p[i + 1], 2) - coord(&p[i], 2);
        r->h[i] = param == CS_SPLINE_UNIFORM ? 1.0 : sqrt(dx * dx + dy * dy + dz * dz);
    }
    for (int a = 0; a < 3; a++) {
        double cp[N_MAX], dp[N_MAX];
        r->M[0][a] = r->M[n][a] = 0;
        /* rows 1..n-1: h_{i-1} M_{i-1} + 2(h_{i-1}+h_i) M_i + h_i M_{i+1} = 6(s_i - s_{i-1}) */
        for (size_t i = 1; i < n; i++) {
            double lo = r->h[i - 1], di = 2 * (r->h[i - 1] + r->h[i]), up = r->h[i];
            double rhs = 6 * ((coord(&p[i + 1], a) - coord(&p[i], a)) / r->h[i] -
                              (coord(&p[i], a) - coord(&p[i - 1], a)) / r->h[i - 1]);
            if (i > 1) {
                di -= lo * cp[i - 1];
                rhs -= lo * dp[i - 1];
            }
            cp[i] = up / di;
            dp[i] = rhs / di;
        }
        for (size_t i = n - 1; i >= 1; i--)
            r->M[i][a] = dp[i] - (i + 1 < n ? cp[i] * r->M[i + 1][a] : 0);
        for (size_t i = 0; i < n; i++) {
            double h = r->h[i], pi = coord(&p[i], a), pj = coord(&p[i + 1], a);
            double d0 = (pj - pi) / h - h * (2 * r->M[i][a] + r->M[i + 1][a]) / 6;
            double d1 = (pj - pi) / h + h * (r->M[i][a] + 2 * r->M[i + 1][a]) / 6;
            r->b1[i][a] = pi + h * d0 / 3;
            r->b2[i][a] = pj - h * d1 / 3;
        }
    }
}

/* S on segment i at t in [0, 1], in LSB. */
static double ref_eval(const cs_vec3_t *p, const ref_t *r, size_t i, int a, double t)
{
    double s = 1 - t, h = r->h[i];
    return s * coord(&p[i], a) + t * coord(&p[i + 1], a) +
           h * h / 6 * ((s * s * s - s) * r->M[i][a] + (t * t * t - t) * r->M[i + 1][a]);
}

static double worst_ctrl, worst_curve;

static void check_spline(const cs_vec3_t *p, size_t count, cs_spline_param_t param)
{
    static cs_spline_t s; /* ~2.3 KB: kept off the test stack on purpose, as firmware would */
    static ref_t r;
    assert_int_equal(cs_spline_solve(&s, p, count, param), CS_OK);
    assert_int_equal(cs_spline_segments(&s), count - 1);
    ref_solve(p, count, param, &r);
    cs_bezier_t seg[N_MAX];
    size_t n = 0;
    assert_int_equal(cs_spline_to_bezier(&s, seg, N_MAX, &n), CS_OK);
    assert_int_equal(n, count - 1);
    const double eps = 1.0; /* LSB: the stated bound on inner control points */
    for (size_t i = 0; i < n; i++) {
        const cs_bezier_t *b = &seg[i];
        assert_int_equal(b->degree, 3);
        assert_false(b->rational);
        assert_memory_equal(&b->p[0], &p[i], sizeof(cs_vec3_t));
        assert_memory_equal(&b->p[3], &p[i + 1], sizeof(cs_vec3_t));
        for (int a = 0; a < 3; a++) {
            double e1 = fabs(coord(&b->p[1], a) - r.b1[i][a]);
            double e2 = fabs(coord(&b->p[2], a) - r.b2[i][a]);
            worst_ctrl = fmax(worst_ctrl, fmax(e1, e2));
            assert_true(e1 <= eps && e2 <= eps);
        }
        for (int k = 0; k <= 20; k++) {
            double t = k / 20.0;
            cs_ref_vec_t q = cs_ref_eval(b, t);
            double qa[3] = {q.x / CS_REF_LSB_MM, q.y / CS_REF_LSB_MM, q.z / CS_REF_LSB_MM};
            for (int a = 0; a < 3; a++) {
                double d = fabs(qa[a] - ref_eval(p, &r, i, a, t));
                worst_curve = fmax(worst_curve, d);
                assert_true(d <= eps + 1e-6);
            }
        }
    }
    /* Derivatives with respect to the spline parameter u, from the fixed-point points. */
    for (int a = 0; a < 3; a++) {
        double h0 = r.h[0], hn = r.h[n - 1];
        const cs_vec3_t *f = seg[0].p, *l = seg[n - 1].p;
        double c0 = 6 * (coord(&f[0], a) - 2 * coord(&f[1], a) + coord(&f[2], a)) / (h0 * h0);
        double cn = 6 * (coord(&l[1], a) - 2 * coord(&l[2], a) + coord(&l[3], a)) / (hn * hn);
        /* natural ends: S'' = 0 up to 18 eps / h^2 (6 (2 eps + eps) / h^2) */
        assert_true(fabs(c0) <= 18 * eps / (h0 * h0) + 1e-9);
        assert_true(fabs(cn) <= 18 * eps / (hn * hn) + 1e-9);
        for (size_t i = 1; i < n; i++) {
            const cs_vec3_t *L = seg[i - 1].p, *R = seg[i].p;
            double hl = r.h[i - 1], hr = r.h[i];
            double d1l = 3 * (coord(&L[3], a) - coord(&L[2], a)) / hl;
            double d1r = 3 * (coord(&R[1], a) - coord(&R[0], a)) / hr;
            assert_true(fabs(d1l - d1r) <= 3 * eps * (1 / hl + 1 / hr) + 1e-9);
            double d2l = 6 * (coord(&L[1], a) - 2 * coord(&L[2], a) + coord(&L[3], a)) / (hl * hl);
            double d2r = 6 * (coord(&R[0], a) - 2 * coord(&R[1], a) + coord(&R[2], a)) / (hr * hr);
            assert_true(fabs(d2l - d2r) <= 18 * eps * (1 / (hl * hl) + 1 / (hr * hr)) + 1e-9);
        }
    }
}

static cs_vec3_t rnd_pt(double range_mm)
{
    return cs_fixed_vec((cs_pos_t)lround((rnd() - 0.5) * range_mm * 65536),
                        (cs_pos_t)lround((rnd() - 0.5) * range_mm * 65536),
                        (cs_pos_t)lround((rnd() - 0.5) * range_mm * 65536));
}

static void test_uniform_random(void **state)
{
    (void)state;
    cs_vec3_t p[N_MAX];
    worst_ctrl = worst_curve = 0;
    for (int trial = 0; trial < 300; trial++) {
        size_t count = 2 + (size_t)(xorshift() % (N_MAX - 1));
        for (size_t i = 0; i < count; i++)
            p[i] = rnd_pt(trial % 3 == 0 ? 2000 : 200);
        check_spline(p, count, CS_SPLINE_UNIFORM);
    }
    if (getenv("CS_TEST_VERBOSE"))
        printf("uniform: worst control point %.3f LSB, curve %.3f LSB\n", worst_ctrl, worst_curve);
}

static void test_chord_random(void **state)
{
    (void)state;
    cs_vec3_t p[N_MAX];
    worst_ctrl = worst_curve = 0;
    for (int trial = 0; trial < 300; trial++) {
        size_t count = 2 + (size_t)(xorshift() % (N_MAX - 1));
        /* a random walk with steps from 10 um to 500 mm: chord ratios up to 5e4 */
        p[0] = rnd_pt(1000);
        for (size_t i = 1; i < count; i++) {
            double step = 0.01 * pow(5e4, rnd());
            cs_vec3_t d = rnd_pt(step);
            p[i] = cs_fixed_vec(p[i - 1].x + d.x, p[i - 1].y + d.y, p[i - 1].z + d.z);
            if (p[i].x == p[i - 1].x && p[i].y == p[i - 1].y && p[i].z == p[i - 1].z)
                p[i].x += 100;
        }
        check_spline(p, count, CS_SPLINE_CHORD);
    }
    if (getenv("CS_TEST_VERBOSE"))
        printf("chord: worst control point %.3f LSB, curve %.3f LSB\n", worst_ctrl, worst_curve);
}

/* Points on a straight line, evenly spaced: the natural spline is the line itself, traversed
 * uniformly, so the Bézier inner points sit at exact thirds. */
static void test_line_is_reproduced(void **state)
{
    (void)state;
    cs_vec3_t p[10];
    for (int i = 0; i < 10; i++)
        p[i] = cs_fixed_vec(3 * 65536 * i, -6 * 65536 * i, 300 * i);
    cs_spline_t s;
    for (int mode = 0; mode < 2; mode++) {
        assert_int_equal(cs_spline_solve(&s, p, 10, mode ? CS_SPLINE_CHORD : CS_SPLINE_UNIFORM),
                         CS_OK);
        for (size_t i = 0; i < 9; i++) {
            cs_bezier_t b;
            assert_int_equal(cs_spline_segment(&s, i, &b), CS_OK);
            assert_true(labs((long)b.p[1].x - (p[i].x + 65536)) <= 1);
            assert_true(labs((long)b.p[1].y - (p[i].y - 2 * 65536)) <= 1);
            assert_true(labs((long)b.p[2].z - (p[i].z + 200)) <= 1);
        }
    }
    /* Two points: one segment, the straight line. */
    assert_int_equal(cs_spline_solve(&s, p, 2, CS_SPLINE_UNIFORM), CS_OK);
    cs_bezier_t b;
    assert_int_equal(cs_spline_segment(&s, 0, &b), CS_OK);
    assert_int_equal(b.p[1].x, 65536);
    assert_int_equal(b.p[2].x, 2 * 65536);
    assert_int_equal(cs_spline_segment(&s, 1, &b), CS_END);
}

static void test_full_size_and_errors(void **state)
{
    (void)state;
    static cs_vec3_t p[N_MAX + 1];
    for (size_t i = 0; i <= N_MAX; i++)
        p[i] = rnd_pt(100);
    static cs_spline_t s;
    check_spline(p, N_MAX, CS_SPLINE_UNIFORM);
    check_spline(p, N_MAX, CS_SPLINE_CHORD);
    assert_int_equal(cs_spline_solve(&s, p, N_MAX + 1, CS_SPLINE_UNIFORM), CS_ERR_FULL);
    assert_int_equal(cs_spline_segments(&s), 0);
    assert_int_equal(cs_spline_solve(&s, p, 1, CS_SPLINE_UNIFORM), CS_ERR_DEGENERATE);
    assert_int_equal(cs_spline_solve(&s, NULL, 5, CS_SPLINE_UNIFORM), CS_ERR_ARG);
    assert_int_equal(cs_spline_solve(&s, p, 5, (cs_spline_param_t)7), CS_ERR_ARG);
    cs_vec3_t q[4] = {{0, 0, 0}, {5, 5, 5}, {5, 5, 5}, {9, 0, 0}};
    assert_int_equal(cs_spline_solve(&s, q, 4, CS_SPLINE_CHORD), CS_ERR_DEGENERATE);
    assert_int_equal(cs_spline_solve(&s, q, 4, CS_SPLINE_UNIFORM), CS_OK); /* allowed there */
    q[3].y = CS_POS_LIMIT + 1;
    assert_int_equal(cs_spline_solve(&s, q, 4, CS_SPLINE_UNIFORM), CS_ERR_RANGE);
    /* Overshoot past the range: a zig-zag at the edge pushes inner points outside. */
    cs_vec3_t z[4] = {
        {CS_POS_LIMIT, 0, 0}, {-CS_POS_LIMIT, 0, 0}, {CS_POS_LIMIT, 0, 0}, {-CS_POS_LIMIT, 0, 0}};
    assert_int_equal(cs_spline_solve(&s, z, 4, CS_SPLINE_UNIFORM), CS_OK);
    /* Tangents (uniform): m0 = -10L/3, m1 = 2L/3, so segment 0 ends with B2 = -L - 2L/9 (out)
     * while segment 1 (-L + 2L/9, L - 2L/9) stays inside. */
    cs_bezier_t b;
    assert_int_equal(cs_spline_segment(&s, 0, &b), CS_ERR_RANGE);
    assert_int_equal(cs_spline_segment(&s, 1, &b), CS_OK);
    assert_true(labs((long)b.p[1].x - (-CS_POS_LIMIT + 2L * CS_POS_LIMIT / 9)) <= 1);
    cs_bezier_t out[2];
    size_t n;
    assert_int_equal(cs_spline_to_bezier(&s, out, 2, &n), CS_ERR_FULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_uniform_random),
        cmocka_unit_test(test_chord_random),
        cmocka_unit_test(test_line_is_reproduced),
        cmocka_unit_test(test_full_size_and_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
