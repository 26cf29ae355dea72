/* test_horner: cs_horner (power basis, Horner's rule) and cs_lensub (seed 003's length-based
 * subdivision). Horner points against the Bernstein sum in long double, every degree 1..7 over
 * the whole coordinate range: within 0.5 + n 2^-17 LSB. Length-based subdivision against the
 * seed's recursive formulation written here (subdivide [t0, t1] while |Q(t1) - Q(t0)| > L, same
 * evaluator): the same points in the same order; every chord at most L; the exact end point;
 * Horner and de Casteljau evaluations give chords within a few of each other. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "cs_horner.h"
#include "cs_lensub.h"
#include "ref_xorshift32.h"

static ref_xorshift32_t rng = {0x2545F491u};

static cs_bezier_t rnd_curve(unsigned n, int32_t lim)
{
    cs_vec3_t p[CS_BEZIER_MAX_POINTS];
    for (unsigned i = 0; i <= n; i++)
        p[i] = cs_fixed_vec((int32_t)ref_xorshift32_uniform(&rng, -lim, lim),
                            (int32_t)ref_xorshift32_uniform(&rng, -lim, lim),
                            (int32_t)ref_xorshift32_uniform(&rng, -lim, lim));
    cs_bezier_t c;
    assert_int_equal(cs_bezier_init(&c, n, p), CS_OK);
    return c;
}

static long double bern_ref(const cs_bezier_t *c, long double t, int axis)
{
    long double s = 0, b = 1;
    unsigned n = c->degree;
    for (unsigned i = 0; i <= n; i++) {
        long double v = axis == 0 ? c->p[i].x : axis == 1 ? c->p[i].y : c->p[i].z;
        s += b * powl(t, (long double)i) * powl(1 - t, (long double)(n - i)) * v;
        b = b * (n - i) / (i + 1);
    }
    return s;
}

static void test_horner_eval(void **state)
{
    (void)state;
    double worst = 0;
    for (int it = 0; it < 3000; it++) {
        unsigned n = 1 + (unsigned)it % 7;
        cs_bezier_t c = rnd_curve(n, CS_POS_LIMIT);
        cs_horner_t h;
        assert_int_equal(cs_horner_init(&h, &c), CS_OK);
        cs_param_t t = it % 13 == 0   ? 0
                       : it % 17 == 0 ? CS_PARAM_ONE
                                      : (cs_param_t)(ref_xorshift32_next(&rng) >> 2);
        cs_vec3_t p;
        assert_int_equal(cs_horner_eval(&h, t, &p), CS_OK);
        long double tt = (long double)t / CS_PARAM_ONE;
        double d = (double)fmaxl(
            fabsl(bern_ref(&c, tt, 0) - p.x),
            fmaxl(fabsl(bern_ref(&c, tt, 1) - p.y), fabsl(bern_ref(&c, tt, 2) - p.z)));
        worst = fmax(worst, d);
        assert_true(d <= 0.5 + n * ldexp(1, -17) + 1e-9);
    }
    if (getenv("CS_TEST_VERBOSE"))
        printf("Horner vs Bernstein (long double): worst %.6f LSB\n", worst);
    cs_bezier_t c = rnd_curve(3, 1000);
    cs_horner_t h;
    c.rational = true;
    assert_int_equal(cs_horner_init(&h, &c), CS_ERR_UNSUPPORTED);
    c.rational = false;
    assert_int_equal(cs_horner_init(&h, &c), CS_OK);
    cs_vec3_t p;
    assert_int_equal(cs_horner_eval(&h, CS_PARAM_ONE + 1, &p), CS_ERR_ARG);
}

/* The seed's recursion, points from the same evaluator (units of 2^-24 of the parameter). */
static const cs_bezier_t *rc;
static uint64_t rmax2;
static cs_vec3_t rpts[1 << 16];
static size_t rn;
static void at(uint32_t t, cs_vec3_t *p)
{
    if (t == 1u << CS_LENSUB_MAX_DEPTH) {
        *p = rc->p[rc->degree];
        return;
    }
    assert_int_equal(cs_bezier_eval(rc, (cs_param_t)((int64_t)t << 6), p), CS_OK);
}
static void recurse(uint32_t t0, uint32_t t1, const cs_vec3_t *p0)
{
    cs_vec3_t p1;
    at(t1, &p1);
    int64_t dx = (int64_t)p1.x - p0->x, dy = (int64_t)p1.y - p0->y, dz = (int64_t)p1.z - p0->z;
    if ((uint64_t)(dx * dx + dy * dy + dz * dz) > rmax2 && t1 - t0 > 1) {
        uint32_t m = (t0 + t1) / 2;
        cs_vec3_t pm;
        recurse(t0, m, p0);
        at(m, &pm);
        recurse(m, t1, &pm);
        return;
    }
    rpts[rn++] = p1;
}

static void test_lensub(void **state)
{
    (void)state;
    for (int it = 0; it < 200; it++) {
        unsigned n = 1 + (unsigned)it % 7;
        cs_bezier_t c = rnd_curve(n, 200 * CS_POS_ONE_MM);
        cs_pos_t len = (cs_pos_t)(5 + it % 40) * CS_POS_ONE_MM;
        rc = &c;
        rmax2 = (uint64_t)len * (uint64_t)len;
        rn = 0;
        recurse(0, 1u << CS_LENSUB_MAX_DEPTH, &c.p[0]);
        for (int horner = 0; horner < 2; horner++) {
            cs_lensub_t s;
            assert_int_equal(cs_lensub_begin(&s, &c, len, horner), CS_OK);
            cs_vec3_t p, prev = c.p[0];
            size_t k = 0;
            cs_err_t e;
            while ((e = cs_lensub_next(&s, &p)) == CS_OK) {
                if (!horner) {
                    assert_true(k < rn);
                    assert_memory_equal(&p, &rpts[k], sizeof p);
                }
                double dl =
                    sqrt(pow(p.x - prev.x, 2) + pow(p.y - prev.y, 2) + pow(p.z - prev.z, 2));
                assert_true(dl <= len);
                prev = p;
                k++;
            }
            assert_int_equal(e, CS_END);
            assert_memory_equal(&prev, &c.p[n], sizeof prev);
            if (!horner)
                assert_int_equal(k, rn);
            else /* the evaluators differ by < 1 LSB: a few borderline chords may split apart */
                assert_true(k + 4 >= rn && k <= rn + 4);
        }
    }
    cs_lensub_t s;
    cs_bezier_t c = rnd_curve(3, 1000);
    assert_int_equal(cs_lensub_begin(&s, &c, 0, false), CS_ERR_TOLERANCE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_horner_eval),
        cmocka_unit_test(test_lensub),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
