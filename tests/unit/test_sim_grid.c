/* test_sim_grid: the simulator's spatial index (sim/cs_sim_grid.c) against a brute-force scan
 * computed here: for random segments in 2D and 3D (short chords, long travels, points) and random
 * query points near and far, the nearest distance equals the scan's minimum (1e-12 mm: the same
 * point-segment formula); with a threshold, the answer is some segment within the threshold
 * when the scan has one, else the exact nearest. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include <cmocka.h>

#include "cs_sim_grid.h"

enum { NSEG = 3000, NQ = 1000 };

static uint32_t rng = 2463534242u;
static double urand(void) /* xorshift32 in [0, 1) */
{
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return (double)rng / 4294967296.0;
}

static double pts[2 * NSEG * 3];
static size_t seg[2 * NSEG];

/* Segments: mostly 0.5 mm chords in a 100 mm square (z in 0..3 layers), some 80 mm travels,
 * some points. */
static void make_segments(void)
{
    for (size_t k = 0; k < NSEG; k++) {
        double *a = &pts[6 * k], *b = a + 3;
        for (int i = 0; i < 3; i++)
            a[i] = i < 2 ? 100 * urand() : floor(4 * urand());
        double len = k % 50 == 0 ? 80 : k % 37 == 0 ? 0 : 0.5, ang = 6.283185307 * urand();
        b[0] = a[0] + len * cos(ang);
        b[1] = a[1] + len * sin(ang);
        b[2] = a[2];
        seg[2 * k] = 2 * k;
        seg[2 * k + 1] = 2 * k + 1;
    }
}

static double brute(const double *p, unsigned dims)
{
    double best = HUGE_VAL;
    for (size_t k = 0; k < NSEG; k++)
        best = fmin(best, cs_sim_grid_dist(p, &pts[6 * k], &pts[6 * k + 3], dims));
    return best;
}

static void check_dims(unsigned dims)
{
    cs_sim_grid_t g;
    assert_int_equal(cs_sim_grid_build(&g, pts, seg, NSEG, dims, 0.05), CS_OK);
    for (size_t q = 0; q < NQ; q++) {
        /* near the drawing, and (one in ten) far outside it */
        double far = q % 10 == 0 ? 400 : 0, p[3];
        for (int i = 0; i < 3; i++)
            p[i] = (i < 2 ? -far + (100 + 2 * far) * urand() : 4 * urand());
        size_t which;
        double want = brute(p, dims), got = cs_sim_grid_nearest(&g, p, -1, &which);
        assert_true(fabs(got - want) <= 1e-12);
        assert_true(fabs(cs_sim_grid_dist(p, &pts[6 * which], &pts[6 * which + 3], dims) - got) <=
                    1e-12);
        /* threshold: anything within 0.3 mm will do; else the exact answer */
        double t = cs_sim_grid_nearest(&g, p, 0.3, &which);
        if (want <= 0.3)
            assert_true(t <= 0.3 && t >= want - 1e-12);
        else
            assert_true(fabs(t - want) <= 1e-12);
    }
    cs_sim_grid_free(&g);
}

static void test_nearest_2d(void **state)
{
    (void)state;
    make_segments();
    check_dims(2);
}

static void test_nearest_3d(void **state)
{
    (void)state;
    make_segments();
    check_dims(3);
}

static void test_empty_is_refused(void **state)
{
    (void)state;
    cs_sim_grid_t g;
    assert_int_equal(cs_sim_grid_build(&g, pts, seg, 0, 2, 0.05), CS_ERR_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_nearest_2d),
        cmocka_unit_test(test_nearest_3d),
        cmocka_unit_test(test_empty_is_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
