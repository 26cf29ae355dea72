/* test_fd: uniform forward differences. The recurrence is exact (n*K guard bits), so every
 * vertex is the exact curve point at t = i / 2^K rounded once: checked against the double
 * reference at the worst-case coordinates (|coordinate| = 4096 mm) over the longest run int64
 * holds, for every degree (error <= 1/2 LSB per axis, so <= 1 LSB). Also: the initial
 * differences equal the exact ones, the dyadic pieces used beyond the longest run are within
 * their rounding budget, Wang's step count keeps chords within tol (and is tight for a
 * parabola), rational curves are differenced exactly in 128 bits, and bad input is refused. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_fd.h"
#include "cs_ref.h"

#define LSB       CS_REF_LSB_MM
#define MAX_VERTS (1 << 20)

static cs_vec3_t verts[MAX_VERTS];
static double vert_t[MAX_VERTS];

static uint64_t rng = 0xD1B54A32D192ED03ull;
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

/* Control points at the corners of the accepted cube, alternating to maximise the differences. */
static cs_bezier_t worst_curve(unsigned n)
{
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = (uint8_t)n;
    for (unsigned i = 0; i <= n; i++) {
        /* A few odd LSB inside the corners, so the exact points are not round numbers. */
        cs_pos_t in = (cs_pos_t)(1 + (i * 7919u) % 997u);
        c.p[i].x = (i % 2) ? CS_POS_LIMIT - in : -CS_POS_LIMIT + in;
        c.p[i].y = (i % 2) ? -CS_POS_LIMIT + 2 * in : CS_POS_LIMIT - 3 * in;
        c.p[i].z = (i % 3 == 0) ? CS_POS_LIMIT - 5 * in : -CS_POS_LIMIT + in;
    }
    return c;
}

/* Traces with f, records each vertex's parameter from the state (piece, step, k). */
static size_t trace(cs_fd_t *f, const cs_bezier_t *c, cs_pos_t tol)
{
    assert_int_equal(cs_fd_begin(f, c, tol), CS_OK);
    size_t n = 0;
    cs_err_t e;
    while (n < MAX_VERTS && (e = cs_fd_next(f, &verts[n])) == CS_OK) {
        vert_t[n] = ((double)f->piece + (double)f->step / (double)((uint64_t)1 << f->k)) /
                    (double)((uint64_t)1 << f->split);
        n++;
    }
    assert_int_equal(cs_fd_next(f, &verts[0 < n ? n - 1 : 0]), CS_END);
    return n;
}

/* Largest per-axis error (LSB) of the vertices against the double curve at their parameters. */
static double max_axis_error(const cs_bezier_t *c, size_t n)
{
    double worst = 0;
    for (size_t i = 0; i < n; i++) {
        cs_ref_vec_t e = cs_ref_eval(c, vert_t[i]);
        double dx = fabs(verts[i].x - e.x / LSB), dy = fabs(verts[i].y - e.y / LSB),
               dz = fabs(verts[i].z - e.z / LSB);
        worst = fmax(worst, fmax(dx, fmax(dy, dz)));
    }
    return worst;
}

static void test_longest_run_worst_case(void **state)
{
    (void)state;
    static cs_fd_t f;
    for (unsigned n = 2; n <= CS_BEZIER_MAX_DEGREE; n++) {
        cs_bezier_t c = worst_curve(n);
        unsigned kmax = cs_fd_kmax(n, CS_FD_GUARD_BITS, 0);
        /* Halve the tolerance until the plan asks for the longest unsplit run (for degree 2
         * even the smallest tolerance needs fewer than 2^16 steps: the longest it can ask). */
        cs_pos_t tol = CS_POS_LIMIT, best = tol;
        unsigned kbest = 0;
        while (tol > 2) {
            assert_int_equal(cs_fd_begin(&f, &c, tol), CS_OK);
            if (f.split != 0)
                break;
            if (f.k >= kbest) {
                kbest = f.k;
                best = tol;
            }
            tol /= 2;
        }
        assert_true(kbest == kmax || (n == 2 && kbest >= 13));
        assert_true(kbest <= kmax);
        size_t nv = trace(&f, &c, best);
        assert_int_equal(f.split, 0);
        assert_int_equal(nv, (size_t)1 << kbest);
        kmax = kbest;
        double err = max_axis_error(&c, nv);
        print_message("  degree %u: K = %u (%zu steps), worst-case coordinates, max error %.4f "
                      "LSB per axis\n",
                      n, kmax, nv, err);
        assert_true(err <= 0.5 + 1e-6); /* exact recurrence, one rounding */
        assert_int_equal(verts[nv - 1].x, c.p[n].x);
        assert_int_equal(verts[nv - 1].y, c.p[n].y);
        assert_int_equal(verts[nv - 1].z, c.p[n].z);
    }
}

/* Beyond the longest run: the curve is cut into 2^s pieces; vertices stay within 1 LSB and the
 * chords within tol. */
static void test_beyond_split(void **state)
{
    (void)state;
    static cs_fd_t f;
    const unsigned degrees[] = {3, 5, 7};
    for (unsigned d = 0; d < 3; d++) {
        cs_bezier_t c = worst_curve(degrees[d]);
        for (unsigned i = 0; i <= c.degree; i++) { /* 1 m box: the trace stays short */
            c.p[i].x /= 4;
            c.p[i].y /= 4;
            c.p[i].z /= 4;
        }
        cs_pos_t tol = 40; /* 0.6 um: more steps than one int64 run holds */
        size_t nv = trace(&f, &c, tol);
        assert_true(f.split > 0);
        double err = max_axis_error(&c, nv);
        double dev = cs_ref_max_deviation(&c, verts, nv);
        print_message("  degree %u split into 2^%u pieces: %zu vertices, max error %.3f LSB "
                      "per axis, deviation %.4f tol\n",
                      c.degree, f.split, nv, err, dev / (tol * LSB));
        assert_true(err * sqrt(3.0) <= 1.0);
        assert_true(dev <= tol * LSB);
        assert_int_equal(verts[nv - 1].x, c.p[c.degree].x);
        assert_int_equal(verts[nv - 1].y, c.p[c.degree].y);
        assert_int_equal(verts[nv - 1].z, c.p[c.degree].z);
    }
}

static void test_init_diffs_exact(void **state)
{
    (void)state;
    rng = 99;
    for (int rep = 0; rep < 50; rep++) {
        unsigned n = 1 + (unsigned)(xorshift() % 7);
        unsigned k = (unsigned)(xorshift() % 5) + 1;
        cs_fd_pt_t p[CS_BEZIER_MAX_POINTS];
        for (unsigned i = 0; i <= n; i++) { /* small coordinates: every value exact in double */
            p[i].x = (int64_t)(xorshift() % 2001) - 1000;
            p[i].y = (int64_t)(xorshift() % 2001) - 1000;
            p[i].z = 0;
        }
        int64_t d[3][CS_BEZIER_MAX_POINTS];
        cs_fd_init_diffs(p, n, k, d);
        /* Reference: x(i / 2^k) * 2^(n k) by Bernstein sums in double (exact: < 2^53). */
        unsigned m = (1u << k) < n ? (1u << k) : n;
        double x[CS_BEZIER_MAX_POINTS];
        for (unsigned i = 0; i <= m; i++) {
            double t = i / (double)(1u << k), s = 0;
            for (unsigned j = 0; j <= n; j++) {
                double b = 1;
                for (unsigned q = 0; q < j; q++)
                    b = b * (n - q) / (q + 1);
                s += b * pow(t, j) * pow(1 - t, n - j) * (double)p[j].x;
            }
            x[i] = s * pow(2.0, (double)(n * k));
        }
        for (unsigned r = 1; r <= m; r++)
            for (unsigned i = m; i >= r; i--)
                x[i] -= x[i - 1];
        for (unsigned j = 0; j <= m; j++)
            assert_true(fabs((double)d[0][j] - x[j]) <= 1e-6 * fmax(1.0, fabs(x[j])) &&
                        fabs((double)d[0][j] - round(x[j])) < 0.5);
    }
}

static void test_piece_rounding(void **state)
{
    (void)state;
    rng = 7;
    for (int rep = 0; rep < 40; rep++) {
        cs_bezier_t c;
        memset(&c, 0, sizeof c);
        c.degree = (uint8_t)(2 + xorshift() % 6);
        for (unsigned i = 0; i <= c.degree; i++) {
            c.p[i].x = (cs_pos_t)((unit() * 2 - 1) * CS_POS_LIMIT);
            c.p[i].y = (cs_pos_t)((unit() * 2 - 1) * CS_POS_LIMIT);
            c.p[i].z = (cs_pos_t)((unit() * 2 - 1) * CS_POS_LIMIT);
        }
        unsigned s = 1 + (unsigned)(xorshift() % CS_FD_MAX_SPLIT);
        uint32_t j = (uint32_t)(xorshift() % ((uint64_t)1 << s));
        cs_fd_pt_t q[CS_BEZIER_MAX_POINTS];
        cs_fd_piece(&c, s, j, CS_FD_PIECE_GUARD, q);
        /* Exact piece by blossoming in double would lose bits at 2^28; compare the piece's end
         * points (its curve at u = 0 and 1) with the exact curve instead. */
        double a = j / pow(2.0, s), b = (j + 1) / pow(2.0, s);
        cs_ref_vec_t ea = cs_ref_eval(&c, a), eb = cs_ref_eval(&c, b);
        double g = pow(2.0, CS_FD_PIECE_GUARD);
        double err = fmax(fabs(q[0].x / g - ea.x / LSB), fabs(q[c.degree].y / g - eb.y / LSB));
        assert_true(err <= s * 0.5 / g + 1e-3);
    }
}

static double uniform_dev(const cs_bezier_t *c, unsigned k)
{
    size_t n = (size_t)1 << k;
    double worst = 0;
    for (size_t i = 0; i < n; i++) {
        double t0 = (double)i / n, t1 = (double)(i + 1) / n;
        double d = cs_ref_chord_piece_deviation(c, t0, t1, cs_ref_eval(c, t0), cs_ref_eval(c, t1));
        worst = fmax(worst, d);
    }
    return worst;
}

static void test_wang_bound(void **state)
{
    (void)state;
    rng = 2024;
    for (int rep = 0; rep < 60; rep++) {
        cs_bezier_t c;
        memset(&c, 0, sizeof c);
        c.degree = (uint8_t)(2 + rep % 6);
        cs_fd_pt_t p[CS_BEZIER_MAX_POINTS];
        for (unsigned i = 0; i <= c.degree; i++) {
            c.p[i].x = (cs_pos_t)((unit() * 2 - 1) * 100 * 65536);
            c.p[i].y = (cs_pos_t)((unit() * 2 - 1) * 100 * 65536);
            c.p[i].z = (cs_pos_t)((unit() * 2 - 1) * 10 * 65536);
            p[i].x = c.p[i].x;
            p[i].y = c.p[i].y;
            p[i].z = c.p[i].z;
        }
        cs_pos_t tol = (cs_pos_t)(65536 * (rep % 3 == 0 ? 0.1 : rep % 3 == 1 ? 0.01 : 0.001));
        unsigned k = cs_fd_wang_k(p, c.degree, 0, tol);
        if (k > 12)
            continue;
        assert_true(uniform_dev(&c, k) <= tol * LSB);
    }
    /* A parabola meets Wang's bound with equality: 2^K chords fit, 2^(K-1) do not. */
    cs_bezier_t q;
    memset(&q, 0, sizeof q);
    q.degree = 2;
    q.p[1].x = 50 * 65536;
    q.p[1].y = 100 * 65536;
    q.p[2].x = 100 * 65536;
    cs_fd_pt_t qp[3] = {{0, 0, 0}, {q.p[1].x, q.p[1].y, 0}, {q.p[2].x, 0, 0}};
    for (cs_pos_t tol = 6; tol < 65536; tol = tol * 3 + 1) {
        unsigned k = cs_fd_wang_k(qp, 2, 0, tol);
        assert_true(uniform_dev(&q, k) <= tol * LSB);
        if (k > 0)
            assert_true(uniform_dev(&q, k - 1) > tol * LSB);
    }
}

/* Rational curves: homogeneous differences are exact in 128 bits, so each vertex is the exact
 * rational point at t = i / 2^K rounded once; the step count comes from the conservative bound
 * h^2/8 max|R''|, so every chord is within tol. */
static void test_rational(void **state)
{
    (void)state;
    static cs_fd_t f;
    const double tols[3] = {0.1, 0.01, 0.001};
    rng = 31;
    int handed_back = 0, traced = 0;
    for (int k = 0; k < 40; k++) {
        cs_bezier_t c;
        memset(&c, 0, sizeof c);
        c.rational = true;
        if (k == 0) { /* quarter circle, r = 50 mm */
            c.degree = 2;
            c.p[0] = cs_fixed_vec(50 * 65536, 0, 0);
            c.p[1] = cs_fixed_vec(50 * 65536, 50 * 65536, 0);
            c.p[2] = cs_fixed_vec(0, 50 * 65536, 0);
            c.w[0] = c.w[2] = CS_WEIGHT_ONE;
            c.w[1] = (cs_weight_t)lround(0.70710678118654752 * CS_WEIGHT_ONE);
        } else {
            c.degree = (uint8_t)(2 + k % 6);
            for (unsigned i = 0; i <= c.degree; i++) {
                c.p[i].x = (cs_pos_t)((unit() * 2 - 1) * 100 * 65536);
                c.p[i].y = (cs_pos_t)((unit() * 2 - 1) * 100 * 65536);
                c.p[i].z = (cs_pos_t)((unit() * 2 - 1) * 10 * 65536);
                c.w[i] = (cs_weight_t)((0.05 + 0.95 * unit()) * CS_WEIGHT_ONE);
            }
        }
        for (int ti = 0; ti < 3; ti++) {
            cs_pos_t tol = (cs_pos_t)lround(tols[ti] * 65536);
            cs_err_t e = cs_fd_begin(&f, &c, tol);
            if (e == CS_ERR_UNSUPPORTED) {
                handed_back++;
                continue;
            }
            assert_int_equal(e, CS_OK);
            traced++;
            size_t nv = trace(&f, &c, tol);
            assert_int_equal(nv, (size_t)1 << f.k);
            double err = max_axis_error(&c, nv);
            if (!(err <= 0.5 + 1e-6))
                fail_msg("rational degree %u: vertex %.6f LSB off its exact point", c.degree, err);
            double dev = cs_ref_max_deviation(&c, verts, nv);
            if (!(dev <= tols[ti]))
                fail_msg("rational degree %u tol %g: deviation %.9g", c.degree, tols[ti], dev);
            assert_true(verts[nv - 1].x == c.p[c.degree].x && verts[nv - 1].y == c.p[c.degree].y &&
                        verts[nv - 1].z == c.p[c.degree].z);
            if (k == 0)
                print_message("  quarter circle r = 50 mm, tol %g: 2^%u chords (greedy %zu)\n",
                              tols[ti], f.k, cs_ref_greedy_count(&c, tols[ti]));
        }
    }
    print_message("  rational: %d traced by FD, %d handed back (more than 2^(60/n) steps)\n",
                  traced, handed_back);
    assert_true(traced > 60);
}

static void test_errors(void **state)
{
    (void)state;
    static cs_fd_t f;
    cs_bezier_t c = worst_curve(3);
    cs_vec3_t v;
    c.rational = true;
    for (int i = 0; i < 4; i++)
        c.w[i] = CS_WEIGHT_MIN;
    c.w[1] = CS_WEIGHT_ONE; /* 2^20 weight ratio at 4 km: more than 2^20 steps, handed back */
    assert_int_equal(cs_fd_begin(&f, &c, 2), CS_ERR_UNSUPPORTED);
    assert_int_equal(cs_fd_next(&f, &v), CS_END);
    c.w[2] = 0;
    assert_int_equal(cs_fd_begin(&f, &c, 100), CS_ERR_WEIGHT);
    c.rational = false;
    assert_int_equal(cs_fd_begin(&f, &c, 0), CS_ERR_TOLERANCE);
    assert_int_equal(cs_fd_begin(&f, &c, 1), CS_ERR_TOLERANCE); /* no room for the rounding */
    c.degree = 0;
    assert_int_equal(cs_fd_begin(&f, &c, 100), CS_ERR_DEGREE);
    c.degree = 3;
    c.p[1].y = CS_POS_LIMIT + 1;
    assert_int_equal(cs_fd_begin(&f, &c, 100), CS_ERR_RANGE);
    /* Degree 1: one step, the end point exactly. */
    cs_bezier_t l;
    memset(&l, 0, sizeof l);
    l.degree = 1;
    l.p[1] = cs_fixed_vec(CS_POS_LIMIT, -CS_POS_LIMIT, 12345);
    assert_int_equal(cs_fd_begin(&f, &l, 10), CS_OK);
    assert_int_equal(cs_fd_next(&f, &v), CS_OK);
    assert_int_equal(v.x, l.p[1].x);
    assert_int_equal(v.y, l.p[1].y);
    assert_int_equal(v.z, l.p[1].z);
    assert_int_equal(cs_fd_next(&f, &v), CS_END);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_longest_run_worst_case),
        cmocka_unit_test(test_beyond_split),
        cmocka_unit_test(test_init_diffs_exact),
        cmocka_unit_test(test_piece_rounding),
        cmocka_unit_test(test_wang_bound),
        cmocka_unit_test(test_rational),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
