/* test_afd: adaptive forward differences. Chords within tol (0.1, 0.01, 0.001 mm; measured both
 * ways by cs_ref_max_deviation) on random cubics and random curves of degree 2..7; every vertex
 * is the exact curve point at its dyadic parameter rounded once (halving and doubling are exact
 * changes of basis, so no error accumulates: <= 1/2 LSB per axis); adaptivity pays (fewer
 * chords than uniform FD on a curve with one sharp bend, one chord for a straight cubic). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_afd.h"
#include "cs_fd.h"
#include "cs_ref.h"

#define LSB       CS_REF_LSB_MM
#define MAX_VERTS 200000

static cs_vec3_t verts[MAX_VERTS];
static double vert_t[MAX_VERTS];
static const double tols_mm[3] = {0.1, 0.01, 0.001};

static uint64_t rng = 0xA0761D6478BD642Full;
static uint64_t xorshift(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}
static double unit(void)
{
    return (double)(xorshift() >> 11) * (1.0 / 9007199254740992.0);
}

static cs_bezier_t random_curve(unsigned n, double scale)
{
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = (uint8_t)n;
    for (unsigned i = 0; i <= n; i++) {
        c.p[i].x = (cs_pos_t)lround((unit() * 2 - 1) * scale * 65536);
        c.p[i].y = (cs_pos_t)lround((unit() * 2 - 1) * scale * 65536);
        c.p[i].z = (cs_pos_t)lround((unit() * 2 - 1) * scale * 6553.6);
    }
    return c;
}

static size_t trace(const cs_bezier_t *c, cs_pos_t tol, cs_afd_t *a)
{
    cs_err_t e = cs_afd_begin(a, c, tol);
    if (e != CS_OK)
        fail_msg("begin: code %d", (int)e);
    size_t n = 0;
    while (n < MAX_VERTS && (e = cs_afd_next(a, &verts[n])) == CS_OK) {
        vert_t[n] = ((double)a->piece + (double)a->t / (double)((uint32_t)1 << a->lmax)) /
                    (double)((uint32_t)1 << a->split);
        n++;
    }
    if (e != CS_END)
        fail_msg("next: code %d after %zu vertices", (int)e, n);
    return n;
}

static void check(const cs_bezier_t *c, double tol_mm)
{
    static cs_afd_t a;
    cs_pos_t tol = (cs_pos_t)lround(tol_mm * 65536);
    size_t n = trace(c, tol, &a);
    const cs_vec3_t *pn = &c->p[c->degree];
    assert_true(verts[n - 1].x == pn->x && verts[n - 1].y == pn->y && verts[n - 1].z == pn->z);
    double dev = cs_ref_max_deviation(c, verts, n);
    if (!(dev <= tol_mm))
        fail_msg("degree %u tol %g: deviation %.9g", c->degree, tol_mm, dev);
    /* Exact basis changes: each vertex is the exact point at its parameter, rounded once (plus
     * the pieces' rounding, < 0.04 LSB, when the curve had to be split). */
    double worst = 0;
    for (size_t i = 0; i < n; i++) {
        cs_ref_vec_t e = cs_ref_eval(c, vert_t[i]);
        worst = fmax(worst, fabs(verts[i].x - e.x / LSB));
        worst = fmax(worst, fabs(verts[i].y - e.y / LSB));
        worst = fmax(worst, fabs(verts[i].z - e.z / LSB));
    }
    double lim = a.split ? 0.5 + CS_FD_MAX_SPLIT * 0.5 / (1 << CS_FD_PIECE_GUARD) : 0.5 + 1e-6;
    if (!(worst <= lim))
        fail_msg("degree %u tol %g: vertex %.4f LSB off its exact point", c->degree, tol_mm, worst);
}

static void test_random_cubics(void **state)
{
    (void)state;
    rng = 0xA0761D6478BD642Full;
    for (int k = 0; k < 100; k++) {
        cs_bezier_t c = random_curve(3, k % 3 ? 100.0 : 10.0);
        for (int ti = 0; ti < 3; ti++)
            check(&c, tols_mm[ti]);
    }
}

static void test_degrees(void **state)
{
    (void)state;
    rng = 4242;
    for (unsigned n = 1; n <= CS_BEZIER_MAX_DEGREE; n++)
        for (int k = 0; k < 6; k++) {
            cs_bezier_t c = random_curve(n, 50.0);
            for (int ti = 0; ti < 3; ti++)
                check(&c, tols_mm[ti]);
        }
}

static size_t count_fd(const cs_bezier_t *c, cs_pos_t tol)
{
    static cs_fd_t f;
    cs_vec3_t v;
    size_t n = 0;
    assert_int_equal(cs_fd_begin(&f, c, tol), CS_OK);
    while (cs_fd_next(&f, &v) == CS_OK)
        n++;
    return n;
}

static void test_adaptivity(void **state)
{
    (void)state;
    static cs_afd_t a;
    /* One sharp bend near the start, long straight run after it. */
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = 3;
    c.p[1] = cs_fixed_vec(20 * 65536, 40 * 65536, 0);
    c.p[2] = cs_fixed_vec(0, 0, 0);
    c.p[3] = cs_fixed_vec(200 * 65536, 0, 0);
    for (int ti = 0; ti < 3; ti++) {
        cs_pos_t tol = (cs_pos_t)lround(tols_mm[ti] * 65536);
        size_t nafd = trace(&c, tol, &a), nfd = count_fd(&c, tol);
        print_message("  sharp bend, tol %g: AFD %zu chords, uniform FD %zu\n", tols_mm[ti], nafd,
                      nfd);
        assert_true(nafd < nfd);
    }
    /* Collinear control points at uniform speed: a straight line, one chord. */
    memset(&c, 0, sizeof c);
    c.degree = 3;
    for (int i = 0; i <= 3; i++)
        c.p[i] = cs_fixed_vec(i * 30 * 65536, i * 10 * 65536, -i * 65536);
    assert_int_equal(trace(&c, 66, &a), 1);
}

static void test_errors(void **state)
{
    (void)state;
    static cs_afd_t a;
    cs_vec3_t v;
    cs_bezier_t c = random_curve(3, 10);
    c.rational = true;
    for (int i = 0; i < 4; i++)
        c.w[i] = CS_WEIGHT_ONE;
    assert_int_equal(cs_afd_begin(&a, &c, 100), CS_ERR_UNSUPPORTED);
    assert_int_equal(cs_afd_next(&a, &v), CS_END);
    c.rational = false;
    assert_int_equal(cs_afd_begin(&a, &c, 0), CS_ERR_TOLERANCE);
    c.degree = 8;
    assert_int_equal(cs_afd_begin(&a, &c, 100), CS_ERR_DEGREE);
    c.degree = 3;
    c.p[0].z = -CS_POS_LIMIT - 1;
    assert_int_equal(cs_afd_begin(&a, &c, 100), CS_ERR_RANGE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random_cubics),
        cmocka_unit_test(test_degrees),
        cmocka_unit_test(test_adaptivity),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
