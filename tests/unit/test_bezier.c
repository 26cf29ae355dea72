/* Unit tests for cs_bezier: every fixed-point result is compared with a double (long double)
 * reference computed from the same fixed-point control points (tests/support/ref_bezier). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "cs_bezier.h"
#include "ref_bezier.h"

#define LIM CS_POS_LIMIT
/* Exact-polynomial bound of cs_bezier_eval, LSB (header: 0.5 + 2^-25; 1e-6 covers the double
 * reference's own rounding). */
#define EVAL_TOL (0.5 + 1e-6)

static void rand_curve(ref_rng_t *g, cs_bezier_t *c, unsigned deg, int32_t span, bool rational)
{
    cs_vec3_t p[CS_BEZIER_MAX_POINTS];
    cs_weight_t w[CS_BEZIER_MAX_POINTS];
    for (unsigned i = 0; i <= deg; i++) {
        p[i].x = (int32_t)ref_rng_range(g, -span, span);
        p[i].y = (int32_t)ref_rng_range(g, -span, span);
        p[i].z = (int32_t)ref_rng_range(g, -span, span);
        /* log-uniform weights over the whole accepted range 2^-20..1 */
        double lw = -20.0 * ref_rng_unit(g);
        w[i] = (cs_weight_t)ldexp(1.0, 30 + (int)floor(lw));
        w[i] = (cs_weight_t)ref_rng_range(g, w[i],
                                          w[i] * 2 > CS_WEIGHT_ONE ? CS_WEIGHT_ONE : w[i] * 2);
    }
    if (rational)
        assert_int_equal(cs_bezier_init_rational(c, deg, p, w), CS_OK);
    else
        assert_int_equal(cs_bezier_init(c, deg, p), CS_OK);
}

static void check_close(const cs_vec3_t *got, const double ref[3], double tol)
{
    double g[3] = {got->x, got->y, got->z};
    for (int a = 0; a < 3; a++) {
        if (fabs(g[a] - ref[a]) > tol)
            fail_msg("axis %d: got %.0f, reference %.9f, error %.9f LSB > %.9f", a, g[a], ref[a],
                     g[a] - ref[a], tol);
    }
}

static void test_init_validation(void **state)
{
    (void)state;
    cs_bezier_t c;
    cs_vec3_t p[8] = {{0, 0, 0}, {LIM, -LIM, LIM}, {1, 2, 3}, {4, 5, 6},
                      {0, 0, 0}, {0, 0, 0},        {0, 0, 0}, {0, 0, 0}};
    cs_weight_t w[8] = {CS_WEIGHT_ONE, CS_WEIGHT_MIN, CS_WEIGHT_ONE, CS_WEIGHT_ONE,
                        CS_WEIGHT_ONE, CS_WEIGHT_ONE, CS_WEIGHT_ONE, CS_WEIGHT_ONE};
    assert_int_equal(cs_bezier_init(&c, 0, p), CS_ERR_DEGREE);
    assert_int_equal(cs_bezier_init(&c, 8, p), CS_ERR_DEGREE);
    assert_int_equal(cs_bezier_init(&c, 3, p), CS_OK);
    assert_int_equal(c.degree, 3);
    assert_false(c.rational);
    p[2].y = LIM + 1;
    assert_int_equal(cs_bezier_init(&c, 3, p), CS_ERR_RANGE);
    p[2].y = -LIM - 1;
    assert_int_equal(cs_bezier_init(&c, 3, p), CS_ERR_RANGE);
    assert_int_equal(cs_bezier_init(&c, 1, p), CS_OK); /* bad point 2 unused by a line */
    p[2].y = 2;
    assert_int_equal(cs_bezier_init_rational(&c, 3, p, w), CS_OK);
    assert_true(c.rational);
    w[3] = CS_WEIGHT_MIN - 1;
    assert_int_equal(cs_bezier_init_rational(&c, 3, p, w), CS_ERR_WEIGHT);
    w[3] = 0;
    assert_int_equal(cs_bezier_init_rational(&c, 3, p, w), CS_ERR_WEIGHT);
    w[3] = -CS_WEIGHT_ONE;
    assert_int_equal(cs_bezier_init_rational(&c, 3, p, w), CS_ERR_WEIGHT);
    w[3] = CS_WEIGHT_ONE + 1;
    assert_int_equal(cs_bezier_init_rational(&c, 3, p, w), CS_ERR_WEIGHT);
}

static void test_eval_polynomial_random(void **state)
{
    (void)state;
    ref_rng_t g;
    ref_rng_seed(&g, 0x1234);
    double worst = 0;
    for (unsigned deg = 1; deg <= 7; deg++) {
        for (int k = 0; k < 200; k++) {
            cs_bezier_t c;
            ref_bezier_t r;
            rand_curve(&g, &c, deg, k % 2 ? LIM : 10 * CS_POS_ONE_MM, false);
            ref_bezier_from(&c, &r);
            for (int j = 0; j < 20; j++) {
                cs_param_t t = j == 0   ? 0
                               : j == 1 ? CS_PARAM_ONE
                                        : (cs_param_t)ref_rng_range(&g, 0, CS_PARAM_ONE);
                cs_vec3_t got;
                double ref[3];
                assert_int_equal(cs_bezier_eval(&c, t, &got), CS_OK);
                ref_bezier_eval(&r, ldexp((double)t, -30), ref);
                check_close(&got, ref, EVAL_TOL);
                for (int a = 0; a < 3; a++) {
                    double e = fabs((a == 0 ? got.x : a == 1 ? got.y : got.z) - ref[a]);
                    worst = e > worst ? e : worst;
                }
            }
        }
    }
    print_message("eval polynomial: worst |error| %.9f LSB (bound 0.5 + 2^-25)\n", worst);
    /* end points are exact */
    cs_bezier_t c;
    cs_vec3_t p[2] = {{-LIM, 5, LIM}, {LIM, -7, -LIM}}, q;
    assert_int_equal(cs_bezier_init(&c, 1, p), CS_OK);
    assert_int_equal(cs_bezier_eval(&c, 0, &q), CS_OK);
    assert_memory_equal(&q, &p[0], sizeof q);
    assert_int_equal(cs_bezier_eval(&c, CS_PARAM_ONE, &q), CS_OK);
    assert_memory_equal(&q, &p[1], sizeof q);
    assert_int_equal(cs_bezier_eval(&c, -1, &q), CS_ERR_ARG);
    assert_int_equal(cs_bezier_eval(&c, CS_PARAM_ONE + 1, &q), CS_ERR_ARG);
}

static void test_eval_rational_random(void **state)
{
    (void)state;
    ref_rng_t g;
    ref_rng_seed(&g, 0x777);
    double worst = 0;
    for (unsigned deg = 1; deg <= 7; deg++) {
        for (int k = 0; k < 200; k++) {
            cs_bezier_t c;
            ref_bezier_t r;
            rand_curve(&g, &c, deg, LIM, true);
            ref_bezier_from(&c, &r);
            for (int j = 0; j < 20; j++) {
                cs_param_t t = (cs_param_t)ref_rng_range(&g, 0, CS_PARAM_ONE);
                cs_vec3_t got;
                double ref[3];
                assert_int_equal(cs_bezier_eval(&c, t, &got), CS_OK);
                ref_bezier_eval(&r, ldexp((double)t, -30), ref);
                check_close(&got, ref, 0.5 + ldexp(1, -8) + 1e-6);
                for (int a = 0; a < 3; a++) {
                    double e = fabs((a == 0 ? got.x : a == 1 ? got.y : got.z) - ref[a]);
                    worst = e > worst ? e : worst;
                }
            }
        }
    }
    print_message("eval rational: worst |error| %.9f LSB (bound 0.5 + 2^-8)\n", worst);
}

/* A circle quarter as a rational quadratic (w = 1, sqrt(2)/2, 1): every point at radius R. */
static void test_eval_rational_circle(void **state)
{
    (void)state;
    const int32_t R = 100 * CS_POS_ONE_MM;
    cs_vec3_t p[3] = {{R, 0, 0}, {R, R, 0}, {0, R, 0}};
    cs_weight_t w[3] = {CS_WEIGHT_ONE, (cs_weight_t)lround(ldexp(sqrt(0.5), 30)), CS_WEIGHT_ONE};
    cs_bezier_t c;
    assert_int_equal(cs_bezier_init_rational(&c, 2, p, w), CS_OK);
    for (int j = 0; j <= 64; j++) {
        cs_vec3_t q;
        assert_int_equal(cs_bezier_eval(&c, (cs_param_t)(((int64_t)CS_PARAM_ONE * j) / 64), &q),
                         CS_OK);
        double rad = hypot(q.x, q.y);
        /* w1 rounded to Q30 moves the curve by < R * 2^-30; point rounding by < 0.71 LSB */
        assert_true(fabs(rad - R) < 1.0);
    }
}

static void ref_split(const ref_bezier_t *r, double t, ref_bezier_t *L, ref_bezier_t *Rr)
{
    long double v[8][4];
    int n = r->degree;
    for (int i = 0; i <= n; i++) {
        for (int a = 0; a < 3; a++)
            v[i][a] = (long double)r->w[i] * r->p[i][a];
        v[i][3] = r->w[i];
    }
    *L = *r;
    *Rr = *r;
    for (int a = 0; a < 4; a++) {
        if (a < 3) {
            L->p[0][a] = r->p[0][a];
            Rr->p[n][a] = r->p[n][a];
        }
    }
    L->w[0] = r->w[0];
    Rr->w[n] = r->w[n];
    for (int k = 1; k <= n; k++) {
        for (int i = 0; i + k <= n; i++)
            for (int a = 0; a < 4; a++)
                v[i][a] = (1.0L - t) * v[i][a] + (long double)t * v[i + 1][a];
        L->w[k] = (double)v[0][3];
        Rr->w[n - k] = (double)v[n - k][3];
        for (int a = 0; a < 3; a++) {
            L->p[k][a] = (double)(v[0][a] / v[0][3]);
            Rr->p[n - k][a] = (double)(v[n - k][a] / v[n - k][3]);
        }
    }
}

static void test_split_polynomial(void **state)
{
    (void)state;
    ref_rng_t g;
    ref_rng_seed(&g, 42);
    double worst_cp = 0, worst_curve = 0;
    for (unsigned deg = 1; deg <= 7; deg++) {
        for (int k = 0; k < 150; k++) {
            cs_bezier_t c, l, rr;
            ref_bezier_t r, rl, rrr, el, er;
            rand_curve(&g, &c, deg, LIM, false);
            ref_bezier_from(&c, &r);
            cs_param_t t = (cs_param_t)ref_rng_range(&g, 1, CS_PARAM_ONE - 1);
            double td = ldexp((double)t, -30);
            assert_int_equal(cs_bezier_split(&c, t, &l, &rr), CS_OK);
            assert_int_equal(l.degree, deg);
            ref_bezier_from(&l, &rl);
            ref_bezier_from(&rr, &rrr);
            /* every new control point: the exact one rounded once */
            ref_split(&r, td, &el, &er);
            for (unsigned i = 0; i <= deg; i++)
                for (int a = 0; a < 3; a++) {
                    double e1 = fabs(rl.p[i][a] - el.p[i][a]);
                    double e2 = fabs(rrr.p[i][a] - er.p[i][a]);
                    worst_cp = fmax(worst_cp, fmax(e1, e2));
                    assert_true(e1 <= EVAL_TOL && e2 <= EVAL_TOL);
                }
            /* halves at s equal the parent at t s and t + (1 - t) s */
            for (int j = 0; j <= 8; j++) {
                double s = j / 8.0, a1[3], b1[3], a2[3], b2[3];
                ref_bezier_eval(&rl, s, a1);
                ref_bezier_eval(&r, td * s, b1);
                ref_bezier_eval(&rrr, s, a2);
                ref_bezier_eval(&r, td + (1 - td) * s, b2);
                for (int a = 0; a < 3; a++) {
                    worst_curve = fmax(worst_curve, fabs(a1[a] - b1[a]));
                    worst_curve = fmax(worst_curve, fabs(a2[a] - b2[a]));
                    assert_true(fabs(a1[a] - b1[a]) <= EVAL_TOL);
                    assert_true(fabs(a2[a] - b2[a]) <= EVAL_TOL);
                }
                /* and through the fixed-point evaluator: 2 roundings */
                cs_vec3_t q;
                assert_int_equal(cs_bezier_eval(&l, (cs_param_t)lround(ldexp(s, 30)), &q), CS_OK);
                check_close(&q, b1, 2 * EVAL_TOL);
            }
            /* end points shared exactly */
            assert_memory_equal(&l.p[deg], &rr.p[0], sizeof(cs_vec3_t));
            assert_memory_equal(&l.p[0], &c.p[0], sizeof(cs_vec3_t));
            assert_memory_equal(&rr.p[deg], &c.p[deg], sizeof(cs_vec3_t));
        }
    }
    print_message("split: worst control point %.9f LSB, worst curve %.9f LSB (bound 0.5)\n",
                  worst_cp, worst_curve);
    cs_bezier_t c, l;
    rand_curve(&g, &c, 3, LIM, false);
    assert_int_equal(cs_bezier_split(&c, 0, &l, NULL), CS_ERR_ARG);
    assert_int_equal(cs_bezier_split(&c, CS_PARAM_ONE, &l, NULL), CS_ERR_ARG);
    /* in place: left written over the parent */
    cs_bezier_t ref = c;
    assert_int_equal(cs_bezier_split(&c, CS_PARAM_ONE / 2, &c, NULL), CS_OK);
    cs_vec3_t q0, q1;
    assert_int_equal(cs_bezier_eval(&ref, CS_PARAM_ONE / 4, &q0), CS_OK);
    assert_int_equal(cs_bezier_eval(&c, CS_PARAM_ONE / 2, &q1), CS_OK);
    assert_true(labs((long)q0.x - q1.x) <= 1 && labs((long)q0.y - q1.y) <= 1);
}

/* Field by field (struct padding is not part of the value). */
static bool same_curve(const cs_bezier_t *a, const cs_bezier_t *b)
{
    if (a->degree != b->degree || a->rational != b->rational)
        return false;
    for (unsigned i = 0; i <= a->degree; i++)
        if (a->p[i].x != b->p[i].x || a->p[i].y != b->p[i].y || a->p[i].z != b->p[i].z ||
            a->w[i] != b->w[i])
            return false;
    return true;
}

/* Bound on the curve change caused by rounding weights to Q30 (see cs_bezier.h). */
static double weight_bound(const cs_bezier_t *c)
{
    double wmin = 1, lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300}, d2 = 0;
    for (int i = 0; i <= c->degree; i++) {
        wmin = fmin(wmin, (double)c->w[i] / CS_WEIGHT_ONE);
        double p[3] = {c->p[i].x, c->p[i].y, c->p[i].z};
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], p[a]);
            hi[a] = fmax(hi[a], p[a]);
        }
    }
    for (int a = 0; a < 3; a++)
        d2 += (hi[a] - lo[a]) * (hi[a] - lo[a]);
    return ldexp(1, -31) / wmin * sqrt(d2);
}

static void test_split_rational(void **state)
{
    (void)state;
    ref_rng_t g;
    ref_rng_seed(&g, 4242);
    double worst = 0;
    for (unsigned deg = 1; deg <= 7; deg++) {
        for (int k = 0; k < 150; k++) {
            cs_bezier_t c, l, rr;
            ref_bezier_t r, rl, rrr;
            rand_curve(&g, &c, deg, LIM, true);
            ref_bezier_from(&c, &r);
            cs_param_t t = (cs_param_t)ref_rng_range(&g, 1, CS_PARAM_ONE - 1);
            double td = ldexp((double)t, -30);
            assert_int_equal(cs_bezier_split(&c, t, &l, &rr), CS_OK);
            assert_true(l.rational && rr.rational);
            cs_weight_t ml = 0, mr = 0;
            for (unsigned i = 0; i <= deg; i++) {
                assert_true(l.w[i] >= CS_WEIGHT_MIN && l.w[i] <= CS_WEIGHT_ONE);
                assert_true(rr.w[i] >= CS_WEIGHT_MIN && rr.w[i] <= CS_WEIGHT_ONE);
                ml = l.w[i] > ml ? l.w[i] : ml;
                mr = rr.w[i] > mr ? rr.w[i] : mr;
            }
            assert_int_equal(ml, CS_WEIGHT_ONE); /* normalised */
            /* in place (right written over the parent, then left over a copy): identical */
            cs_bezier_t c2 = c, c3 = c;
            assert_int_equal(cs_bezier_split(&c2, t, NULL, &c2), CS_OK);
            assert_true(same_curve(&c2, &rr));
            assert_int_equal(cs_bezier_split(&c3, t, &c3, NULL), CS_OK);
            assert_true(same_curve(&c3, &l));
            assert_int_equal(mr, CS_WEIGHT_ONE);
            ref_bezier_from(&l, &rl);
            ref_bezier_from(&rr, &rrr);
            double tl = 0.5 + ldexp(1, -8) + weight_bound(&l) + 1e-6;
            double tr = 0.5 + ldexp(1, -8) + weight_bound(&rr) + 1e-6;
            for (int j = 0; j <= 8; j++) {
                double s = j / 8.0, a1[3], b1[3], a2[3], b2[3];
                ref_bezier_eval(&rl, s, a1);
                ref_bezier_eval(&r, td * s, b1);
                ref_bezier_eval(&rrr, s, a2);
                ref_bezier_eval(&r, td + (1 - td) * s, b2);
                for (int a = 0; a < 3; a++) {
                    worst = fmax(worst, fmax(fabs(a1[a] - b1[a]) / tl, fabs(a2[a] - b2[a]) / tr));
                    if (fabs(a1[a] - b1[a]) > tl || fabs(a2[a] - b2[a]) > tr)
                        fail_msg("deg %u s %g: left err %g (tol %g), right err %g (tol %g)", deg, s,
                                 a1[a] - b1[a], tl, a2[a] - b2[a], tr);
                }
            }
        }
    }
    print_message("rational split: worst error / stated bound = %.3f\n", worst);
}

static void test_elevate(void **state)
{
    (void)state;
    ref_rng_t g;
    ref_rng_seed(&g, 99);
    for (int rat = 0; rat <= 1; rat++) {
        for (unsigned deg = 1; deg <= 6; deg++) {
            for (int k = 0; k < 100; k++) {
                cs_bezier_t c, e;
                ref_bezier_t r, re;
                rand_curve(&g, &c, deg, LIM, rat != 0);
                assert_int_equal(cs_bezier_elevate(&c, &e), CS_OK);
                assert_int_equal(e.degree, deg + 1);
                ref_bezier_from(&c, &r);
                ref_bezier_from(&e, &re);
                double tol = 0.5 + 1e-6 + (rat ? weight_bound(&e) : 0);
                for (int j = 0; j <= 16; j++) {
                    double a1[3], b1[3];
                    ref_bezier_eval(&r, j / 16.0, a1);
                    ref_bezier_eval(&re, j / 16.0, b1);
                    for (int a = 0; a < 3; a++)
                        if (fabs(a1[a] - b1[a]) > tol)
                            fail_msg("rat %d deg %u: error %g > %g", rat, deg, a1[a] - b1[a], tol);
                }
                assert_memory_equal(&e.p[0], &c.p[0], sizeof(cs_vec3_t));
                assert_memory_equal(&e.p[deg + 1], &c.p[deg], sizeof(cs_vec3_t));
            }
        }
    }
    cs_bezier_t c, e;
    rand_curve(&g, &c, 7, LIM, false);
    assert_int_equal(cs_bezier_elevate(&c, &e), CS_ERR_DEGREE);
}

static void test_hodograph(void **state)
{
    (void)state;
    ref_rng_t g;
    ref_rng_seed(&g, 5);
    for (unsigned deg = 1; deg <= 7; deg++) {
        for (int k = 0; k < 50; k++) {
            cs_bezier_t c, h;
            ref_bezier_t r, rh;
            rand_curve(&g, &c, deg, LIM / 8, false);
            assert_int_equal(cs_bezier_hodograph(&c, &h), CS_OK);
            assert_int_equal(h.degree, deg - 1);
            ref_bezier_from(&c, &r);
            ref_bezier_from(&h, &rh);
            for (int j = 0; j <= 10; j++) {
                double d[3], v[3];
                ref_bezier_deriv(&r, j / 10.0, d);
                ref_bezier_eval(&rh, j / 10.0, v);
                for (int a = 0; a < 3; a++)
                    assert_true(fabs(d[a] - v[a]) <= 1e-6 * (1 + fabs(d[a])));
                /* the fixed-point evaluator works on the (out of CS_POS_LIMIT) hodograph */
                cs_vec3_t q;
                assert_int_equal(cs_bezier_eval(&h, (cs_param_t)(CS_PARAM_ONE / 10 * j), &q),
                                 CS_OK);
                ref_bezier_eval(&rh, ldexp((double)(CS_PARAM_ONE / 10 * j), -30), v);
                check_close(&q, v, EVAL_TOL);
            }
        }
    }
    /* 7 * 8192 mm does not fit Q15.16 */
    cs_vec3_t p[8];
    for (int i = 0; i < 8; i++)
        p[i] = cs_fixed_vec(i % 2 ? LIM : -LIM, 0, 0);
    cs_bezier_t c, h;
    assert_int_equal(cs_bezier_init(&c, 7, p), CS_OK);
    assert_int_equal(cs_bezier_hodograph(&c, &h), CS_ERR_OVERFLOW);
    /* 1 * 8192 mm does fit (a line's hodograph: degree 0) */
    assert_int_equal(cs_bezier_init(&c, 1, p), CS_OK);
    assert_int_equal(cs_bezier_hodograph(&c, &h), CS_OK);
    assert_int_equal(h.degree, 0);
    assert_int_equal(h.p[0].x, 2 * LIM);
    cs_weight_t w[8] = {CS_WEIGHT_ONE, CS_WEIGHT_ONE};
    assert_int_equal(cs_bezier_init_rational(&c, 1, p, w), CS_OK);
    assert_int_equal(cs_bezier_hodograph(&c, &h), CS_ERR_UNSUPPORTED);
}

/* exact extent of one axis of a polynomial degree <= 3 in double (roots of B') */
static void ref_extent(const ref_bezier_t *r, int a, double *mn, double *mx)
{
    int n = r->degree;
    double ts[4] = {0, 1, -1, -1};
    if (n == 2) {
        double d0 = r->p[1][a] - r->p[0][a], d1 = r->p[2][a] - r->p[1][a];
        if (d0 != d1)
            ts[2] = d0 / (d0 - d1);
    } else if (n == 3) {
        long double A = r->p[1][a] - r->p[0][a], B = r->p[2][a] - r->p[1][a],
                    C = r->p[3][a] - r->p[2][a];
        long double qa = A - 2 * B + C, qb = 2 * (B - A), qc = A;
        if (fabsl(qa) < 1e-30L) {
            if (qb != 0)
                ts[2] = (double)(-qc / qb);
        } else {
            long double disc = qb * qb - 4 * qa * qc;
            if (disc >= 0) {
                long double s = sqrtl(disc);
                ts[2] = (double)((-qb + s) / (2 * qa));
                ts[3] = (double)((-qb - s) / (2 * qa));
            }
        }
    }
    *mn = 1e300;
    *mx = -1e300;
    for (int i = 0; i < 4; i++) {
        if (ts[i] < 0 || ts[i] > 1)
            continue;
        double v[3];
        ref_bezier_eval(r, ts[i], v);
        *mn = fmin(*mn, v[a]);
        *mx = fmax(*mx, v[a]);
    }
}

static void test_bbox(void **state)
{
    (void)state;
    ref_rng_t g;
    ref_rng_seed(&g, 77);
    double worst_loose = 0;
    for (int rat = 0; rat <= 1; rat++) {
        for (unsigned deg = 1; deg <= 7; deg++) {
            for (int k = 0; k < 200; k++) {
                cs_bezier_t c;
                ref_bezier_t r;
                rand_curve(&g, &c, deg, k % 3 ? LIM : 300, rat != 0);
                ref_bezier_from(&c, &r);
                cs_vec3_t lo, hi;
                assert_int_equal(cs_bezier_bbox(&c, &lo, &hi), CS_OK);
                double l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
                for (int j = 0; j <= 1000; j++) {
                    double v[3];
                    ref_bezier_eval(&r, j / 1000.0, v);
                    for (int a = 0; a < 3; a++)
                        if (!(v[a] >= l[a] - 1e-6 && v[a] <= h[a] + 1e-6))
                            fail_msg("rat %d deg %u axis %d t %g: %.6f outside [%.0f, %.0f]", rat,
                                     deg, a, j / 1000.0, v[a], l[a], h[a]);
                }
                for (int a = 0; a < 3; a++) {
                    if (!rat && deg <= 3) {
                        double mn, mx;
                        ref_extent(&r, a, &mn, &mx);
                        /* contains the exact extremes, < 1 + 2^-20 LSB loose (header) */
                        if (!(l[a] <= mn + 1e-9 && h[a] >= mx - 1e-9 && mn - l[a] <= 1.0 + 1e-6 &&
                              h[a] - mx <= 1.0 + 1e-6))
                            fail_msg("deg %u axis %d: box [%.3f, %.3f] exact [%.6f, %.6f]", deg, a,
                                     l[a], h[a], mn, mx);
                        worst_loose = fmax(worst_loose, fmax(mn - l[a], h[a] - mx));
                    } else {
                        /* hull box */
                        double mn = 1e300, mx = -1e300;
                        for (unsigned i = 0; i <= deg; i++) {
                            mn = fmin(mn, r.p[i][a]);
                            mx = fmax(mx, r.p[i][a]);
                        }
                        assert_true(l[a] == mn && h[a] == mx);
                    }
                }
            }
        }
    }
    print_message("bbox degree <= 3: loosest side %.7f LSB (bound 1 + 2^-20)\n", worst_loose);
    /* a symmetric arch: x extent [0, 100 mm], y max = 3/4 * 100 mm exactly */
    cs_vec3_t p[4] = {{0, 0, 0},
                      {0, 100 * CS_POS_ONE_MM, 0},
                      {100 * CS_POS_ONE_MM, 100 * CS_POS_ONE_MM, 0},
                      {100 * CS_POS_ONE_MM, 0, 0}};
    cs_bezier_t c;
    cs_vec3_t lo, hi;
    assert_int_equal(cs_bezier_init(&c, 3, p), CS_OK);
    assert_int_equal(cs_bezier_bbox(&c, &lo, &hi), CS_OK);
    assert_int_equal(lo.y, 0);
    assert_true(hi.y >= 75 * CS_POS_ONE_MM && hi.y <= 75 * CS_POS_ONE_MM + 1);
    assert_int_equal(lo.x, 0);
    assert_int_equal(hi.x, 100 * CS_POS_ONE_MM);
}

static void test_piece(void **state)
{
    (void)state;
    ref_rng_t g;
    ref_rng_seed(&g, 31337);
    for (unsigned deg = 1; deg <= 7; deg++) {
        for (int k = 0; k < 100; k++) {
            cs_bezier_t c;
            ref_bezier_t r, rp;
            rand_curve(&g, &c, deg, LIM, false);
            ref_bezier_from(&c, &r);
            cs_param_t t0 = (cs_param_t)ref_rng_range(&g, 0, CS_PARAM_ONE);
            cs_param_t t1 = (cs_param_t)ref_rng_range(&g, 0, CS_PARAM_ONE);
            cs_vec3w_t pts[CS_BEZIER_MAX_POINTS];
            assert_int_equal(cs_bezier_piece(&c, t0, t1, 8, pts), CS_OK);
            rp = r;
            for (unsigned i = 0; i <= deg; i++) {
                rp.p[i][0] = ldexp((double)pts[i].x, -8);
                rp.p[i][1] = ldexp((double)pts[i].y, -8);
                rp.p[i][2] = ldexp((double)pts[i].z, -8);
            }
            /* the piece's end points are the evaluator's points (shared exactly by neighbours) */
            cs_vec3_t e0;
            assert_int_equal(cs_bezier_eval(&c, t0, &e0), CS_OK);
            cs_vec3w_t p0[CS_BEZIER_MAX_POINTS];
            assert_int_equal(cs_bezier_piece(&c, t0, t1, 0, p0), CS_OK);
            assert_true(p0[0].x == e0.x && p0[0].y == e0.y && p0[0].z == e0.z);
            double d0 = ldexp((double)t0, -30), d1 = ldexp((double)t1, -30);
            for (int j = 0; j <= 8; j++) {
                double a1[3], b1[3];
                ref_bezier_eval(&rp, j / 8.0, a1);
                ref_bezier_eval(&r, d0 + (d1 - d0) * j / 8.0, b1);
                for (int a = 0; a < 3; a++)
                    assert_true(fabs(a1[a] - b1[a]) <= ldexp(1, -9) + 1e-6);
            }
        }
    }
}

static void test_blossom_args(void **state)
{
    (void)state;
    ref_rng_t g;
    ref_rng_seed(&g, 8);
    cs_bezier_t c;
    rand_curve(&g, &c, 3, CS_POS_LIMIT, true);
    cs_param_t ts[3] = {0, CS_PARAM_ONE / 3, CS_PARAM_ONE};
    cs_vec3w_t out;
    assert_int_equal(cs_bezier_blossom(&c, ts, CS_BEZIER_MAX_FRAC + 1, &out), CS_ERR_ARG);
    ts[1] = -1;
    assert_int_equal(cs_bezier_blossom(&c, ts, 0, &out), CS_ERR_ARG);
    ts[1] = CS_PARAM_ONE + 1;
    assert_int_equal(cs_bezier_blossom(&c, ts, 0, &out), CS_ERR_ARG);
    /* a blossom is symmetric and affine in each argument: b(0, x, 1) against the reference
     * (b(u, v, w) of a rational curve = homogeneous blossom, divided) */
    ts[1] = CS_PARAM_ONE / 3;
    assert_int_equal(cs_bezier_blossom(&c, ts, CS_BEZIER_MAX_FRAC, &out), CS_OK);
    ref_bezier_t r;
    ref_bezier_from(&c, &r);
    long double h[4][4], x = ldexp((double)ts[1], -30);
    for (int i = 0; i < 4; i++) {
        for (int a = 0; a < 3; a++)
            h[i][a] = (long double)r.w[i] * r.p[i][a];
        h[i][3] = r.w[i];
    }
    long double tt[3] = {0.0L, x, 1.0L};
    for (int k = 1; k <= 3; k++)
        for (int i = 0; i + k <= 3; i++)
            for (int a = 0; a < 4; a++)
                h[i][a] = (1 - tt[k - 1]) * h[i][a] + tt[k - 1] * h[i + 1][a];
    double want[3] = {(double)(h[0][0] / h[0][3]), (double)(h[0][1] / h[0][3]),
                      (double)(h[0][2] / h[0][3])};
    double got[3] = {ldexp((double)out.x, -CS_BEZIER_MAX_FRAC),
                     ldexp((double)out.y, -CS_BEZIER_MAX_FRAC),
                     ldexp((double)out.z, -CS_BEZIER_MAX_FRAC)};
    double wmin = 1;
    for (int i = 0; i < 4; i++)
        wmin = fmin(wmin, r.w[i]);
    for (int a = 0; a < 3; a++)
        assert_true(fabs(got[a] - want[a]) <=
                    ldexp(1, -CS_BEZIER_MAX_FRAC - 1) + ldexp(7, -31) / wmin + 1e-6);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_init_validation),
        cmocka_unit_test(test_eval_polynomial_random),
        cmocka_unit_test(test_eval_rational_random),
        cmocka_unit_test(test_eval_rational_circle),
        cmocka_unit_test(test_split_polynomial),
        cmocka_unit_test(test_split_rational),
        cmocka_unit_test(test_elevate),
        cmocka_unit_test(test_hodograph),
        cmocka_unit_test(test_bbox),
        cmocka_unit_test(test_piece),
        cmocka_unit_test(test_blossom_args),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
