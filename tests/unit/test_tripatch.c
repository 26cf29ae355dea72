/* test_tripatch: triangular Bézier patches against seed 000's formula evaluated in double here,
 * p(u, v) = sum n! / (i! j! k!) u^i v^j w^k S_ijk: points within 0.5 LSB (+ 2^-25), domain lines
 * (edges, iso-lines) within 0.5 LSB at every sample, edges exactly the boundary points, and
 * the degree-1 patch is the plane through its corners. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "cs_ref.h"
#include "cs_tripatch.h"

#define Q30 1073741824.0

static uint64_t rng = 0x243F6A8885A308D3u;
static uint64_t xorshift(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}
static int32_t rnd(int32_t lim)
{
    return (int32_t)((int64_t)(xorshift() % (2 * (uint64_t)lim + 1)) - lim);
}
static void report(const char *what, double lsb)
{
    if (getenv("CS_TEST_VERBOSE"))
        printf("%s: worst %.4f LSB\n", what, lsb);
}

static double fact(int n)
{
    return n <= 1 ? 1 : n * fact(n - 1);
}
/* Seed 000's sum, LSB units; S_ijk looked up by (i, j) in the documented order. */
static void ref_eval(const cs_tripatch_t *t, double u, double v, double out[3])
{
    int n = t->degree;
    double w = 1 - u - v;
    out[0] = out[1] = out[2] = 0;
    for (int i = 0; i <= n; i++)
        for (int j = 0; i + j <= n; j++) {
            int k = n - i - j;
            double b = fact(n) / (fact(i) * fact(j) * fact(k)) * pow(u, i) * pow(v, j) * pow(w, k);
            /* Row-by-row order: rows of constant i, j ascending. */
            int idx = 0;
            for (int r = 0; r < i; r++)
                idx += n - r + 1;
            idx += j;
            out[0] += b * t->p[idx].x;
            out[1] += b * t->p[idx].y;
            out[2] += b * t->p[idx].z;
        }
}
static double diff(const double r[3], const cs_vec3_t *p)
{
    return fmax(fabs(r[0] - p->x), fmax(fabs(r[1] - p->y), fabs(r[2] - p->z)));
}
static cs_param_t rnd_unit(void)
{
    return (cs_param_t)(xorshift() % ((uint64_t)CS_PARAM_ONE + 1));
}

static void rnd_patch(cs_tripatch_t *t, unsigned n)
{
    cs_vec3_t pts[CS_TRIPATCH_MAX_POINTS];
    for (unsigned k = 0; k < (n + 1) * (n + 2) / 2; k++)
        pts[k] = cs_fixed_vec(rnd(CS_POS_LIMIT), rnd(CS_POS_LIMIT), rnd(CS_POS_LIMIT));
    assert_int_equal(cs_tripatch_init(t, n, pts), CS_OK);
}

static void test_index(void **state)
{
    (void)state;
    /* Cubic: rows i = 0 (4 points), 1 (3), 2 (2), 3 (1). */
    assert_int_equal(cs_tripatch_index(3, 0, 0), 0);
    assert_int_equal(cs_tripatch_index(3, 0, 3), 3);
    assert_int_equal(cs_tripatch_index(3, 1, 0), 4);
    assert_int_equal(cs_tripatch_index(3, 2, 1), 8);
    assert_int_equal(cs_tripatch_index(3, 3, 0), 9);
    assert_int_equal(cs_tripatch_index(2, 2, 0), 5);
}

static void test_eval(void **state)
{
    (void)state;
    double worst = 0;
    for (int it = 0; it < 3000; it++) {
        cs_tripatch_t t;
        rnd_patch(&t, 1 + it % 7); /* every degree up to the cap, 7 */
        cs_param_t u = rnd_unit(), v = rnd_unit();
        if ((int64_t)u + v > CS_PARAM_ONE) {
            u = CS_PARAM_ONE - u;
            v = CS_PARAM_ONE - v;
        }
        if (it % 10 == 0)
            v = CS_PARAM_ONE - u; /* on the edge w = 0 */
        cs_vec3_t p;
        assert_int_equal(cs_tripatch_eval(&t, u, v, &p), CS_OK);
        double r[3];
        ref_eval(&t, u / Q30, v / Q30, r);
        double d = diff(r, &p);
        worst = fmax(worst, d);
        assert_true(d <= 0.5 + 1e-6);
    }
    report("triangular eval", worst);
    /* Corners are the corner control points exactly. */
    cs_tripatch_t t;
    rnd_patch(&t, 3);
    cs_vec3_t p;
    assert_int_equal(cs_tripatch_eval(&t, CS_PARAM_ONE, 0, &p), CS_OK);
    assert_memory_equal(&p, &t.p[cs_tripatch_index(3, 3, 0)], sizeof p);
    assert_int_equal(cs_tripatch_eval(&t, 0, 0, &p), CS_OK);
    assert_memory_equal(&p, &t.p[cs_tripatch_index(3, 0, 0)], sizeof p);
    assert_int_equal(cs_tripatch_eval(&t, CS_PARAM_ONE / 2 + 1, CS_PARAM_ONE / 2, &p), CS_ERR_ARG);
    assert_int_equal(cs_tripatch_eval(&t, -1, 0, &p), CS_ERR_ARG);
    cs_vec3_t pts[CS_TRIPATCH_MAX_POINTS] = {{0, 0, 0}};
    assert_int_equal(cs_tripatch_init(&t, 8, pts), CS_ERR_DEGREE);
    assert_int_equal(cs_tripatch_init(&t, 7, pts), CS_OK);
    pts[9].z = CS_POS_LIMIT + 1;
    assert_int_equal(cs_tripatch_init(&t, 3, pts), CS_ERR_RANGE);
}

static void test_lines(void **state)
{
    (void)state;
    double worst = 0;
    for (int it = 0; it < 500; it++) {
        cs_tripatch_t t;
        unsigned n = 1 + (unsigned)(it % 7);
        rnd_patch(&t, n);
        /* Iso-line u = u0 from (u0, 0) to (u0, 1 - u0), and a random chord of the domain. */
        cs_param_t u0 = rnd_unit();
        cs_param_t a[2] = {u0, 0}, b[2] = {u0, CS_PARAM_ONE - u0};
        if (it % 2) {
            a[0] = rnd_unit() / 2;
            a[1] = rnd_unit() / 2;
            b[0] = rnd_unit() / 2;
            b[1] = rnd_unit() / 2;
        }
        cs_bezier_t c;
        assert_int_equal(cs_tripatch_line(&t, a[0], a[1], b[0], b[1], &c), CS_OK);
        assert_int_equal(c.degree, n);
        for (int s = 0; s <= 16; s++) {
            double ss = s / 16.0, r[3];
            ref_eval(&t, (1 - ss) * a[0] / Q30 + ss * b[0] / Q30,
                     (1 - ss) * a[1] / Q30 + ss * b[1] / Q30, r);
            cs_ref_vec_t q = cs_ref_eval(&c, ss);
            double d = fmax(fabs(r[0] - q.x * 65536),
                            fmax(fabs(r[1] - q.y * 65536), fabs(r[2] - q.z * 65536)));
            worst = fmax(worst, d);
            /* Each control point rounded once; the Bernstein sum keeps 0.5 LSB. */
            assert_true(d <= 0.5 + 1e-6);
        }
        /* The edge w = 0 from (1, 0) to (0, 1): control points S_(n-m) m 0 exactly. */
        assert_int_equal(cs_tripatch_line(&t, CS_PARAM_ONE, 0, 0, CS_PARAM_ONE, &c), CS_OK);
        for (unsigned m = 0; m <= n; m++)
            assert_memory_equal(&c.p[m], &t.p[cs_tripatch_index(n, n - m, m)], sizeof(cs_vec3_t));
    }
    report("triangular lines", worst);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_index),
        cmocka_unit_test(test_eval),
        cmocka_unit_test(test_lines),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
