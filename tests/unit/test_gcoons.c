/* test_gcoons: the generalised Coons patch (host/cs_gcoons) against seed 002's formula
 * transcribed here in double, S = [f1 f2][S(0,v) S(1,v)]^T + [S(u,0) S(u,1)][g1 g2]^T
 * - [f1 f2][corners][g1 g2]^T, with the boundary curves evaluated at their own degree and the
 * blends as functions (the Hermite blend as 1 - 3t^2 + 2t^3, random cubic blends by their
 * Bernstein sums); linear blends against the core's bilinear Coons; the boundaries are
 * interpolated; bad blends and corners are refused. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "cs_coons.h"
#include "cs_gcoons.h"
#include "cs_ref.h"
#include "ref_xorshift32.h"

#define LSB CS_REF_LSB_MM

static ref_xorshift32_t rng = {0x9E3779B9u};

static cs_vec3_t rnd_vec(double lim_mm)
{
    return cs_fixed_vec((int32_t)lround(ref_xorshift32_uniform(&rng, -lim_mm, lim_mm) / LSB),
                        (int32_t)lround(ref_xorshift32_uniform(&rng, -lim_mm, lim_mm) / LSB),
                        (int32_t)lround(ref_xorshift32_uniform(&rng, -lim_mm, lim_mm) / LSB));
}

static cs_bezier_t curve(unsigned n, cs_vec3_t a, cs_vec3_t b)
{
    cs_vec3_t pts[4] = {a, rnd_vec(200), rnd_vec(200), b};
    pts[n] = b;
    cs_bezier_t c;
    assert_int_equal(cs_bezier_init(&c, n, pts), CS_OK);
    return c;
}

/* f(t) of a blend: the Hermite one in closed form, others by their Bernstein sum. */
static double blend_at(const cs_gcoons_blend_t *f, bool hermite, double t)
{
    if (hermite)
        return 1 - 3 * t * t + 2 * t * t * t;
    double s = 1 - t;
    return f->b[0] * s * s * s + 3 * f->b[1] * t * s * s + 3 * f->b[2] * t * t * s +
           f->b[3] * t * t * t;
}

/* Patch point in double (tensor Bernstein, bicubic), mm. */
static cs_ref_vec_t patch_at(const cs_patch_t *p, double u, double v)
{
    static const double bin[4] = {1, 3, 3, 1};
    cs_ref_vec_t r = {0, 0, 0};
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double b =
                bin[i] * pow(u, i) * pow(1 - u, 3 - i) * bin[j] * pow(v, j) * pow(1 - v, 3 - j);
            cs_ref_vec_t q = cs_ref_from_pos(&p->p[i][j]);
            r.x += b * q.x;
            r.y += b * q.y;
            r.z += b * q.z;
        }
    return r;
}

static void test_against_seed(void **state)
{
    (void)state;
    double worst = 0;
    for (int it = 0; it < 200; it++) {
        cs_vec3_t A = rnd_vec(300), B = rnd_vec(300), C = rnd_vec(300), D = rnd_vec(300);
        cs_bezier_t p1 = curve(1 + it % 3, A, B), p2 = curve(1 + (it / 3) % 3, D, C);
        cs_bezier_t q1 = curve(1 + (it / 9) % 3, A, D), q2 = curve(3, B, C);
        bool fh = it % 2 == 0, gh = it % 4 < 2;
        cs_gcoons_blend_t f = cs_gcoons_hermite(), g = cs_gcoons_hermite();
        if (!fh) {
            f.b[1] = ref_xorshift32_uniform(&rng, -1, 2);
            f.b[2] = ref_xorshift32_uniform(&rng, -1, 2);
        }
        if (!gh) {
            g.b[1] = ref_xorshift32_uniform(&rng, -1, 2);
            g.b[2] = ref_xorshift32_uniform(&rng, -1, 2);
        }
        cs_patch_t p;
        assert_int_equal(cs_gcoons_build(&p1, &p2, &q1, &q2, &f, &g, &p), CS_OK);
        cs_ref_vec_t a = cs_ref_from_pos(&A), b = cs_ref_from_pos(&B), c = cs_ref_from_pos(&C),
                     d = cs_ref_from_pos(&D);
        for (int s = 0; s <= 8; s++)
            for (int r = 0; r <= 8; r++) {
                double u = s / 8.0, v = r / 8.0;
                double f1 = blend_at(&f, fh, u), f2 = 1 - f1, g1 = blend_at(&g, gh, v), g2 = 1 - g1;
                cs_ref_vec_t Q1 = cs_ref_eval(&q1, v), Q2 = cs_ref_eval(&q2, v);
                cs_ref_vec_t P1 = cs_ref_eval(&p1, u), P2 = cs_ref_eval(&p2, u);
                /* corners: S(0,0) = A, S(0,1) = D, S(1,0) = B, S(1,1) = C */
                cs_ref_vec_t want = {
                    f1 * Q1.x + f2 * Q2.x + P1.x * g1 + P2.x * g2 -
                        (f1 * g1 * a.x + f1 * g2 * d.x + f2 * g1 * b.x + f2 * g2 * c.x),
                    f1 * Q1.y + f2 * Q2.y + P1.y * g1 + P2.y * g2 -
                        (f1 * g1 * a.y + f1 * g2 * d.y + f2 * g1 * b.y + f2 * g2 * c.y),
                    f1 * Q1.z + f2 * Q2.z + P1.z * g1 + P2.z * g2 -
                        (f1 * g1 * a.z + f1 * g2 * d.z + f2 * g1 * b.z + f2 * g2 * c.z)};
                double e = cs_ref_dist(want, patch_at(&p, u, v));
                worst = fmax(worst, e);
                /* each control point rounded once: <= 0.5 LSB per coordinate */
                assert_true(e <= 0.5 * sqrt(3) * LSB + 1e-9);
            }
    }
    if (getenv("CS_TEST_VERBOSE"))
        printf("generalised Coons vs seed 002: worst %.3f LSB\n", worst / LSB);
}

/* Linear blends are the bilinear Coons patch (core, exact integers over 9). */
static void test_linear_is_bilinear(void **state)
{
    (void)state;
    for (int it = 0; it < 50; it++) {
        cs_vec3_t A = rnd_vec(300), B = rnd_vec(300), C = rnd_vec(300), D = rnd_vec(300);
        cs_bezier_t p1 = curve(3, A, B), p2 = curve(2, D, C), q1 = curve(1, A, D),
                    q2 = curve(3, B, C);
        cs_gcoons_blend_t lin = cs_gcoons_linear();
        cs_patch_t g, c;
        assert_int_equal(cs_gcoons_build(&p1, &p2, &q1, &q2, &lin, &lin, &g), CS_OK);
        assert_int_equal(cs_coons_bilinear(&p1, &p2, &q1, &q2, &c), CS_OK);
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++) {
                /* both round the same exact value once (ties may break apart by 1 LSB) */
                assert_true(abs(g.p[i][j].x - c.p[i][j].x) <= 1);
                assert_true(abs(g.p[i][j].y - c.p[i][j].y) <= 1);
                assert_true(abs(g.p[i][j].z - c.p[i][j].z) <= 1);
            }
    }
}

static void test_refused(void **state)
{
    (void)state;
    cs_vec3_t A = rnd_vec(100), B = rnd_vec(100), C = rnd_vec(100), D = rnd_vec(100);
    cs_bezier_t p1 = curve(1, A, B), p2 = curve(1, D, C), q1 = curve(1, A, D), q2 = curve(1, B, C);
    cs_gcoons_blend_t h = cs_gcoons_hermite(), bad = {{0.9, 1, 0, 0}};
    cs_patch_t p;
    assert_int_equal(cs_gcoons_build(&p1, &p2, &q1, &q2, &bad, &h, &p), CS_ERR_ARG);
    bad.b[0] = 1;
    bad.b[3] = 0.1;
    assert_int_equal(cs_gcoons_build(&p1, &p2, &q1, &q2, &h, &bad, &p), CS_ERR_ARG);
    q2.p[0].x++;
    assert_int_equal(cs_gcoons_build(&p1, &p2, &q1, &q2, &h, &h, &p), CS_ERR_DEGENERATE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_against_seed),
        cmocka_unit_test(test_linear_is_bilinear),
        cmocka_unit_test(test_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
