/* test_patch: cs_patch against a double-precision reference computed here: the tensor Bernstein
 * sum and its derivatives, the power form U^T A V and Mortenson's Hermite form U^T M^T B M V
 * (seed 004). Points and derivatives within 0.5 LSB (+ the documented guard error), normals
 * within 1e-4 rad (measured ~1e-9), conversions to 0.5 LSB, the 9-way split reproducing the
 * parent within 1 LSB, rasters equal to the exact iso-curves rounded once. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_patch.h"

#define Q30    1073741824.0
#define TEAPOT "tests/data/teapot/newell_teapot.txt"

static void report(const char *what, double worst, const char *unit)
{
    if (getenv("CS_TEST_VERBOSE"))
        printf("%s: worst %.3g %s\n", what, worst, unit);
}

static uint64_t rng = 0x9E3779B97F4A7C15u;
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
static cs_vec3_t rnd_vec(int32_t lim)
{
    return cs_fixed_vec(rnd(lim), rnd(lim), rnd(lim));
}
static cs_param_t rnd_param(void)
{
    return (cs_param_t)(xorshift() % ((uint64_t)CS_PARAM_ONE + 1));
}

/* --- double reference (coordinates in LSB) ------------------------------------------------ */

typedef struct {
    double x[3];
} dv3;

static double binom(int n, int k)
{
    if (k < 0 || k > n)
        return 0;
    double c = 1;
    for (int i = 1; i <= k; i++)
        c = c * (n - k + i) / i;
    return c;
}
/* Bernstein B_k^n(t) and its derivative. */
static double bern(int n, int k, double t)
{
    if (k < 0 || k > n)
        return 0;
    return binom(n, k) * pow(t, k) * pow(1 - t, n - k);
}
static double dbern(int n, int k, double t)
{
    return n * (bern(n - 1, k - 1, t) - bern(n - 1, k, t));
}
static double comp(const cs_vec3_t *p, int a)
{
    return a == 0 ? p->x : a == 1 ? p->y : p->z;
}
/* which: 0 P, 1 Pu, 2 Pv, 3 Puv. */
static dv3 ref_eval(const cs_patch_t *p, double u, double v, int which)
{
    dv3 r = {{0, 0, 0}};
    for (int i = 0; i <= p->deg_u; i++)
        for (int j = 0; j <= p->deg_v; j++) {
            double bu = (which & 1) ? dbern(p->deg_u, i, u) : bern(p->deg_u, i, u);
            double bv = (which & 2) ? dbern(p->deg_v, j, v) : bern(p->deg_v, j, v);
            for (int a = 0; a < 3; a++)
                r.x[a] += bu * bv * comp(&p->p[i][j], a);
        }
    return r;
}
static double maxdiff(dv3 r, const cs_vec3_t *p)
{
    double d = 0;
    for (int a = 0; a < 3; a++)
        d = fmax(d, fabs(r.x[a] - comp(p, a)));
    return d;
}
static dv3 dcross(dv3 a, dv3 b)
{
    dv3 c = {{a.x[1] * b.x[2] - a.x[2] * b.x[1], a.x[2] * b.x[0] - a.x[0] * b.x[2],
              a.x[0] * b.x[1] - a.x[1] * b.x[0]}};
    return c;
}
static double dlen(dv3 a)
{
    return sqrt(a.x[0] * a.x[0] + a.x[1] * a.x[1] + a.x[2] * a.x[2]);
}
/* Angle (rad) between a double direction and a Q30 unit vector. */
static double angle_to(dv3 ref, const cs_patch_unit_t *n)
{
    dv3 m = {{n->x / Q30, n->y / Q30, n->z / Q30}};
    double c = dlen(dcross(ref, m)), d = 0;
    for (int a = 0; a < 3; a++)
        d += ref.x[a] * m.x[a];
    return atan2(c, d);
}
/* Double reference normal (Pu x Pv) at (u, v). */
static dv3 ref_normal(const cs_patch_t *p, double u, double v)
{
    return dcross(ref_eval(p, u, v, 1), ref_eval(p, u, v, 2));
}

static void rnd_patch(cs_patch_t *p, unsigned du, unsigned dv, int32_t lim)
{
    cs_vec3_t pts[CS_PATCH_MAX_POINTS * CS_PATCH_MAX_POINTS];
    for (unsigned k = 0; k < (du + 1) * (dv + 1); k++)
        pts[k] = rnd_vec(lim);
    assert_int_equal(cs_patch_init(p, du, dv, pts), CS_OK);
}

/* --- Newell teapot ------------------------------------------------------------------------ */

static int teapot_load(cs_patch_t patches[32])
{
    FILE *f = fopen(TEAPOT, "r");
    if (!f)
        return 0;
    int np = 0, nv = 0, idx[32][16];
    if (fscanf(f, "%d", &np) != 1 || np != 32) {
        fclose(f);
        return 0;
    }
    for (int i = 0; i < np; i++)
        for (int k = 0; k < 16; k++)
            if (fscanf(f, " %d ,", &idx[i][k]) != 1) {
                fclose(f);
                return 0;
            }
    double vx[400][3];
    if (fscanf(f, "%d", &nv) != 1 || nv > 400) {
        fclose(f);
        return 0;
    }
    for (int i = 0; i < nv; i++)
        if (fscanf(f, " %lf , %lf , %lf", &vx[i][0], &vx[i][1], &vx[i][2]) != 3) {
            fclose(f);
            return 0;
        }
    fclose(f);
    for (int i = 0; i < np; i++) {
        cs_vec3_t pts[16];
        for (int k = 0; k < 16; k++) {
            const double *q = vx[idx[i][k] - 1];
            /* 10 mm per teapot unit: a 30 x 20 x 15 mm pot. */
            pts[k] =
                cs_fixed_vec((int32_t)lround(q[0] * 10 * 65536), (int32_t)lround(q[1] * 10 * 65536),
                             (int32_t)lround(q[2] * 10 * 65536));
        }
        if (cs_patch_init(&patches[i], 3, 3, pts) != CS_OK)
            return 0;
    }
    return np;
}

/* --- tests -------------------------------------------------------------------------------- */

static void test_eval_derivs(void **state)
{
    (void)state;
    /* Up to the cap, 7 x 7 (issue 19: patches were capped at 3 x 3). */
    static const unsigned degs[][2] = {{3, 3}, {1, 1}, {1, 3}, {2, 3}, {3, 2}, {2, 1},
                                       {4, 3}, {5, 2}, {7, 7}, {6, 1}, {7, 4}};
    double worst[4] = {0, 0, 0, 0};
    for (size_t d = 0; d < sizeof degs / sizeof degs[0]; d++) {
        for (int it = 0; it < 200; it++) {
            cs_patch_t p;
            /* Whole coordinate range for points; derivatives must still fit. */
            rnd_patch(&p, degs[d][0], degs[d][1], it % 2 ? CS_POS_LIMIT : 100 * CS_POS_ONE_MM);
            cs_param_t u = it % 7 == 0 ? 0 : rnd_param(),
                       v = it % 11 == 0 ? CS_PARAM_ONE : rnd_param();
            cs_patch_derivs_t r;
            cs_err_t e = cs_patch_derivs(&p, u, v, &r);
            if (e == CS_ERR_OVERFLOW) {
                /* Only legitimate when an exact derivative leaves int32. */
                double big = 0;
                for (int w = 1; w < 4; w++)
                    for (int a = 0; a < 3; a++)
                        big = fmax(big, fabs(ref_eval(&p, u / Q30, v / Q30, w).x[a]));
                assert_true(big > 2147483647.0 - 2);
                continue;
            }
            assert_int_equal(e, CS_OK);
            const cs_vec3_t *got[4] = {&r.p, &r.pu, &r.pv, &r.puv};
            for (int w = 0; w < 4; w++) {
                double dd = maxdiff(ref_eval(&p, u / Q30, v / Q30, w), got[w]);
                worst[w] = fmax(worst[w], dd);
                /* 0.5 LSB rounding + guard error (2^-20 LSB, header). */
                assert_true(dd <= 0.5 + 1e-6);
            }
            cs_vec3_t q;
            assert_int_equal(cs_patch_eval(&p, u, v, &q), CS_OK);
            assert_memory_equal(&q, &r.p, sizeof q);
        }
    }
    report("P", worst[0], "LSB");
    report("Pu", worst[1], "LSB");
    report("Pv", worst[2], "LSB");
    report("Puv", worst[3], "LSB");
}

static void test_args(void **state)
{
    (void)state;
    cs_vec3_t pts[CS_PATCH_MAX_POINTS * CS_PATCH_MAX_POINTS] = {{0, 0, 0}};
    cs_patch_t p;
    assert_int_equal(cs_patch_init(&p, 8, 3, pts), CS_ERR_DEGREE);
    assert_int_equal(cs_patch_init(&p, 3, 8, pts), CS_ERR_DEGREE);
    assert_int_equal(cs_patch_init(&p, 4, 3, pts), CS_OK);
    assert_int_equal(cs_patch_init(&p, 7, 7, pts), CS_OK);
    assert_int_equal(cs_patch_init(&p, 0, 3, pts), CS_ERR_DEGREE);
    pts[5].x = CS_POS_LIMIT + 1;
    assert_int_equal(cs_patch_init(&p, 3, 3, pts), CS_ERR_RANGE);
    pts[5].x = 0;
    assert_int_equal(cs_patch_init(&p, 3, 3, pts), CS_OK);
    cs_vec3_t q;
    assert_int_equal(cs_patch_eval(&p, -1, 0, &q), CS_ERR_ARG);
    assert_int_equal(cs_patch_eval(&p, 0, CS_PARAM_ONE + 1, &q), CS_ERR_ARG);
    cs_patch_t a, b;
    assert_int_equal(cs_patch_split_u(&p, 0, &a, &b), CS_ERR_ARG);
    assert_int_equal(cs_patch_split_v(&p, CS_PARAM_ONE, &a, &b), CS_ERR_ARG);
    cs_patch_raster_t r;
    assert_int_equal(cs_patch_raster_begin(&r, &p, CS_PATCH_ISO_U, CS_PATCH_RASTER_MAX_SHIFT + 1),
                     CS_ERR_ARG);
    /* A flat point patch has no normal anywhere. */
    cs_patch_unit_t n;
    assert_int_equal(cs_patch_normal(&p, CS_PARAM_ONE / 3, CS_PARAM_ONE / 5, &n),
                     CS_ERR_DEGENERATE);
    assert_int_equal(cs_patch_normal(&p, 0, 0, &n), CS_ERR_DEGENERATE);
    /* Derivatives wider than int32: the control net spans 8192 mm in one unit of u, so
     * Pu = 3 * 8192 mm = 2^30.6 LSB... still fits; twist 9 * 4 * 4096 mm does not. */
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            pts[i * 4 + j] = cs_fixed_vec((i + j) % 2 ? CS_POS_LIMIT : -CS_POS_LIMIT, 0, 0);
    assert_int_equal(cs_patch_init(&p, 3, 3, pts), CS_OK);
    cs_patch_derivs_t dv;
    assert_int_equal(cs_patch_derivs(&p, 0, 0, &dv), CS_ERR_OVERFLOW);
    assert_int_equal(cs_patch_eval(&p, 0, 0, &q), CS_OK);
}

static void test_normal_random(void **state)
{
    (void)state;
    double worst = 0;
    int checked = 0;
    for (int it = 0; it < 2000; it++) {
        cs_patch_t p;
        rnd_patch(&p, 1 + it % 3, 1 + (it / 3) % 3, 50 * CS_POS_ONE_MM);
        cs_param_t u = rnd_param(), v = rnd_param();
        dv3 ref = ref_normal(&p, u / Q30, v / Q30);
        dv3 pu = ref_eval(&p, u / Q30, v / Q30, 1), pv = ref_eval(&p, u / Q30, v / Q30, 2);
        double sine = dlen(ref) / (dlen(pu) * dlen(pv));
        cs_patch_unit_t n;
        cs_err_t e = cs_patch_normal(&p, u, v, &n);
        if (sine < 1e-5) {
            /* Near-parallel derivatives: either a normal or DEGENERATE is acceptable. */
            assert_true(e == CS_OK || e == CS_ERR_DEGENERATE);
            continue;
        }
        assert_int_equal(e, CS_OK);
        double ang = angle_to(ref, &n);
        worst = fmax(worst, ang);
        assert_true(ang <= 1e-4);
        /* Unit length to about 2^-28. */
        double l = sqrt((double)n.x * n.x + (double)n.y * n.y + (double)n.z * n.z) / Q30;
        assert_true(fabs(l - 1) < 1e-8);
        checked++;
    }
    assert_true(checked > 1900);
    report("normal (random)", worst, "rad");
}

/* The teapot's collapsed patches: at the pole the normal is the limit from inside. */
static void test_normal_teapot_poles(void **state)
{
    (void)state;
    cs_patch_t tp[32];
    assert_int_equal(teapot_load(tp), 32);
    double worst = 0;
    int poles = 0;
    for (int i = 0; i < 32; i++) {
        const cs_patch_t *p = &tp[i];
        bool collapsed_u0 = true;
        for (int j = 1; j < 4; j++)
            if (memcmp(&p->p[0][j], &p->p[0][0], sizeof(cs_vec3_t)) != 0)
                collapsed_u0 = false;
        for (int k = 0; k <= 8; k++) {
            double v = k / 8.0;
            cs_param_t vq = (cs_param_t)lround(v * Q30);
            for (int side = 0; side < 2; side++) {
                double u = side ? 1.0 : 0.0;
                cs_patch_unit_t n;
                cs_err_t e = cs_patch_normal(p, side ? CS_PARAM_ONE : 0, vq, &n);
                dv3 ref = ref_normal(p, u, v);
                if (dlen(ref) < 1e-3 || (!side && collapsed_u0)) {
                    /* Pole: the limit normal just inside the patch. */
                    ref = ref_normal(p, side ? 1 - 1e-7 : 1e-7, v);
                    if (!side && collapsed_u0)
                        poles++;
                }
                assert_int_equal(e, CS_OK);
                double ang = angle_to(ref, &n);
                worst = fmax(worst, ang);
                assert_true(ang <= 1e-4);
            }
        }
    }
    /* Lid top (4 patches) and bottom (4 patches) are collapsed at u = 0. */
    assert_int_equal(poles, 8 * 9);
    report("normal (teapot edges and poles)", worst, "rad");
}

static void test_split(void **state)
{
    (void)state;
    double worst = 0;
    for (int it = 0; it < 300; it++) {
        cs_patch_t p, lo, hi;
        rnd_patch(&p, 1 + it % 3, 1 + (it / 3) % 3, CS_POS_LIMIT);
        cs_param_t t = 1 + (cs_param_t)(xorshift() % (CS_PARAM_ONE - 1));
        bool in_u = it % 2 == 0;
        assert_int_equal(
            in_u ? cs_patch_split_u(&p, t, &lo, &hi) : cs_patch_split_v(&p, t, &lo, &hi), CS_OK);
        double tt = t / Q30;
        /* Shared boundary exactly. */
        for (int k = 0; k <= (in_u ? p.deg_v : p.deg_u); k++) {
            const cs_vec3_t *a = in_u ? &lo.p[p.deg_u][k] : &lo.p[k][p.deg_v];
            const cs_vec3_t *b = in_u ? &hi.p[0][k] : &hi.p[k][0];
            assert_memory_equal(a, b, sizeof *a);
        }
        for (int s = 0; s <= 4; s++)
            for (int r = 0; r <= 4; r++) {
                double a = s / 4.0, b = r / 4.0;
                dv3 ql = ref_eval(&lo, a, b, 0), qh = ref_eval(&hi, a, b, 0);
                dv3 pl = in_u ? ref_eval(&p, tt * a, b, 0) : ref_eval(&p, a, tt * b, 0);
                dv3 ph = in_u ? ref_eval(&p, tt + (1 - tt) * a, b, 0)
                              : ref_eval(&p, a, tt + (1 - tt) * b, 0);
                for (int x = 0; x < 3; x++) {
                    double d = fmax(fabs(ql.x[x] - pl.x[x]), fabs(qh.x[x] - ph.x[x]));
                    worst = fmax(worst, d);
                    /* Control points rounded once: the convex sum stays within 0.5 LSB. */
                    assert_true(d <= 0.5 + 1e-6);
                }
            }
    }
    report("split", worst, "LSB");
}

static void test_iso_and_raster(void **state)
{
    (void)state;
    double worst = 0;
    /* The largest shifts the bound m (shift + 1) + 29 <= 63 allows (cs_patch.h). */
    static const unsigned want[8] = {10, 10, 10, 10, 7, 5, 4, 3};
    for (unsigned m = 0; m <= 7; m++)
        assert_int_equal(cs_patch_raster_max_shift(m), want[m]);
    for (int it = 0; it < 120; it++) {
        cs_patch_t p;
        /* Cubics and below first, then degrees 4..7 (their raster stops at a smaller shift,
         * cs_patch_raster_max_shift: one more is refused). */
        unsigned du = it < 60 ? 1 + it % 3 : 1 + it % 7,
                 dv = it < 60 ? 1 + (it / 3) % 3 : 4 + it % 4;
        rnd_patch(&p, du, dv, CS_POS_LIMIT);
        for (int dir = 0; dir < 2; dir++) {
            unsigned m = dir == 0 ? p.deg_v : p.deg_u, top = cs_patch_raster_max_shift(m);
            unsigned shift = (unsigned)it % (top + 1);
            cs_patch_raster_t r;
            if (top < CS_PATCH_RASTER_MAX_SHIFT)
                assert_int_equal(cs_patch_raster_begin(&r, &p, (cs_patch_iso_t)dir, top + 1),
                                 CS_ERR_ARG);
            assert_int_equal(cs_patch_raster_begin(&r, &p, (cs_patch_iso_t)dir, shift), CS_OK);
            uint32_t n = 1u << shift, k = 0;
            cs_bezier_t c, iso;
            cs_param_t t;
            cs_err_t e;
            while ((e = cs_patch_raster_next(&r, &c, &t)) == CS_OK) {
                double tt = (double)k / n;
                assert_int_equal(t, (cs_param_t)(tt * Q30));
                assert_int_equal(c.degree, dir == 0 ? p.deg_u : p.deg_v);
                /* Control point i is column i's curve at tt, rounded once: compare the curve
                 * points (the convex sum keeps 0.5 LSB) with the patch. */
                for (int s = 0; s <= 8; s++) {
                    double a = s / 8.0;
                    dv3 ref = dir == 0 ? ref_eval(&p, a, tt, 0) : ref_eval(&p, tt, a, 0);
                    dv3 got = {{0, 0, 0}};
                    for (int i = 0; i <= c.degree; i++)
                        for (int x = 0; x < 3; x++)
                            got.x[x] += bern(c.degree, i, a) * comp(&c.p[i], x);
                    for (int x = 0; x < 3; x++) {
                        double d = fabs(got.x[x] - ref.x[x]);
                        worst = fmax(worst, d);
                        assert_true(d <= 0.5 + 1e-6);
                    }
                }
                /* Same curve as the direct evaluation (both round the exact value once;
                 * they may differ by 1 LSB only at an exact tie, which de Casteljau's guard
                 * error can break either way). */
                assert_int_equal(cs_patch_iso(&p, (cs_patch_iso_t)dir, t, &iso), CS_OK);
                for (int i = 0; i <= c.degree; i++)
                    for (int x = 0; x < 3; x++)
                        assert_true(fabs(comp(&c.p[i], x) - comp(&iso.p[i], x)) <= 1);
                if (k == 0 || k == n) {
                    /* The patch's own edges, exactly. */
                    for (int i = 0; i <= c.degree; i++) {
                        int j = k == 0 ? 0 : (dir == 0 ? p.deg_v : p.deg_u);
                        const cs_vec3_t *want = dir == 0 ? &p.p[i][j] : &p.p[j][i];
                        assert_memory_equal(&c.p[i], want, sizeof *want);
                    }
                }
                k++;
            }
            assert_int_equal(e, CS_END);
            assert_int_equal(k, n + 1);
        }
    }
    report("raster iso-curves", worst, "LSB");
}

/* Neighbouring teapot patches share edge curves: their rasters end on identical points. */
static void test_raster_no_cracks(void **state)
{
    (void)state;
    cs_patch_t tp[32];
    assert_int_equal(teapot_load(tp), 32);
    /* Patches 0 and 1 (rim): patch 1's edge v = 0 is patch 0's edge v = 1 (indices 4, 8, 12,
     * 16), so curves along v at the same u meet. */
    for (int i = 0; i < 4; i++)
        assert_memory_equal(&tp[0].p[i][3], &tp[1].p[i][0], sizeof(cs_vec3_t));
    cs_patch_raster_t ra, rb;
    assert_int_equal(cs_patch_raster_begin(&ra, &tp[0], CS_PATCH_ISO_V, 5), CS_OK);
    assert_int_equal(cs_patch_raster_begin(&rb, &tp[1], CS_PATCH_ISO_V, 5), CS_OK);
    cs_bezier_t ca, cb;
    int n = 0;
    while (cs_patch_raster_next(&ra, &ca, NULL) == CS_OK) {
        assert_int_equal(cs_patch_raster_next(&rb, &cb, NULL), CS_OK);
        assert_memory_equal(&ca.p[3], &cb.p[0], sizeof ca.p[3]);
        n++;
    }
    assert_int_equal(n, 33);
    /* The teapot body is smooth across that seam: G1 at least (Newell's data is C1 there). */
    cs_patch_t a, b;
    cs_patch_cont_t c;
    assert_int_equal(cs_patch_transpose(&tp[0], &a), CS_OK);
    assert_int_equal(cs_patch_transpose(&tp[1], &b), CS_OK);
    assert_int_equal(cs_patch_continuity(&a, &b, 3, (cs_param_t)(1e-4 * Q30), &c), CS_OK);
    assert_true(c >= CS_PATCH_CONT_G1);
    /* Transposing twice is the identity; evaluation swaps its arguments. */
    cs_patch_t back;
    assert_int_equal(cs_patch_transpose(&a, &back), CS_OK);
    assert_memory_equal(&back, &tp[0], sizeof back);
    cs_vec3_t p1, p2;
    assert_int_equal(cs_patch_eval(&tp[0], CS_PARAM_ONE / 3, CS_PARAM_ONE / 7, &p1), CS_OK);
    assert_int_equal(cs_patch_eval(&a, CS_PARAM_ONE / 7, CS_PARAM_ONE / 3, &p2), CS_OK);
    assert_true(abs(p1.x - p2.x) <= 1 && abs(p1.y - p2.y) <= 1 && abs(p1.z - p2.z) <= 1);
}

/* P = sum a_ij u^i v^j in double, LSB. */
static dv3 power_eval(const cs_vec3_t a[4][4], double u, double v)
{
    dv3 r = {{0, 0, 0}};
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            for (int x = 0; x < 3; x++)
                r.x[x] += pow(u, i) * pow(v, j) * comp(&a[i][j], x);
    return r;
}

static void test_from_power(void **state)
{
    (void)state;
    double worst = 0;
    for (int it = 0; it < 300; it++) {
        cs_vec3_t a[4][4];
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++)
                a[i][j] = rnd_vec(i + j == 0 ? CS_POS_LIMIT / 2 : CS_POS_LIMIT / 40);
        cs_patch_t p;
        assert_int_equal(cs_patch_from_power(&p, a), CS_OK);
        for (int s = 0; s <= 6; s++)
            for (int r = 0; r <= 6; r++) {
                dv3 pw = power_eval(a, s / 6.0, r / 6.0), bz = ref_eval(&p, s / 6.0, r / 6.0, 0);
                for (int x = 0; x < 3; x++) {
                    double e = fabs(pw.x[x] - bz.x[x]);
                    worst = fmax(worst, e);
                    assert_true(e <= 0.5 + 1e-6);
                }
            }
    }
    cs_vec3_t big[4][4] = {{{0, 0, 0}}};
    big[3][3] = cs_fixed_vec(INT32_MAX, 0, 0);
    cs_patch_t p;
    assert_int_equal(cs_patch_from_power(&p, big), CS_ERR_RANGE);
    report("power -> Bezier", worst, "LSB");
}

/* Mortenson's Hermite form P(u, v) = U^T M^T B M V (seed 004), written with the Hermite basis
 * functions h0 = 2t^3 - 3t^2 + 1, h1 = -2t^3 + 3t^2, h2 = t^3 - 2t^2 + t, h3 = t^3 - t^2. */
static void hbasis(double t, double h[4])
{
    h[0] = 2 * t * t * t - 3 * t * t + 1;
    h[1] = -2 * t * t * t + 3 * t * t;
    h[2] = t * t * t - 2 * t * t + t;
    h[3] = t * t * t - t * t;
}
/* Derivatives of the basis functions. */
static void dhbasis(double t, double h[4])
{
    h[0] = 6 * t * t - 6 * t;
    h[1] = -6 * t * t + 6 * t;
    h[2] = 3 * t * t - 4 * t + 1;
    h[3] = 3 * t * t - 2 * t;
}
/* which: 0 P, 1 Pu, 2 Pv, 3 Puv of the Hermite form. */
static dv3 hermite_eval_d(const cs_patch_hermite_t *h, double u, double v, int which)
{
    double hu[4], hv[4];
    if (which & 1)
        dhbasis(u, hu);
    else
        hbasis(u, hu);
    if (which & 2)
        dhbasis(v, hv);
    else
        hbasis(v, hv);
    const cs_vec3_t *b[4][4] = {
        {&h->p[0][0], &h->p[0][1], &h->pv[0][0], &h->pv[0][1]},
        {&h->p[1][0], &h->p[1][1], &h->pv[1][0], &h->pv[1][1]},
        {&h->pu[0][0], &h->pu[0][1], &h->puv[0][0], &h->puv[0][1]},
        {&h->pu[1][0], &h->pu[1][1], &h->puv[1][0], &h->puv[1][1]},
    };
    dv3 r = {{0, 0, 0}};
    for (int k = 0; k < 4; k++)
        for (int l = 0; l < 4; l++)
            for (int x = 0; x < 3; x++)
                r.x[x] += hu[k] * hv[l] * comp(b[k][l], x);
    return r;
}
static dv3 hermite_eval(const cs_patch_hermite_t *h, double u, double v)
{
    return hermite_eval_d(h, u, v, 0);
}
static void rnd_hermite(cs_patch_hermite_t *h, int32_t plim, int32_t tlim)
{
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++) {
            h->p[a][b] = rnd_vec(plim);
            h->pu[a][b] = rnd_vec(tlim);
            h->pv[a][b] = rnd_vec(tlim);
            h->puv[a][b] = rnd_vec(tlim);
        }
}

static void test_hermite(void **state)
{
    (void)state;
    double worst = 0;
    for (int it = 0; it < 300; it++) {
        cs_patch_hermite_t h;
        rnd_hermite(&h, CS_POS_LIMIT / 2, CS_POS_LIMIT / 4);
        cs_patch_t p;
        assert_int_equal(cs_patch_from_hermite(&p, &h), CS_OK);
        for (int s = 0; s <= 6; s++)
            for (int r = 0; r <= 6; r++) {
                dv3 hw = hermite_eval(&h, s / 6.0, r / 6.0), bz = ref_eval(&p, s / 6.0, r / 6.0, 0);
                for (int x = 0; x < 3; x++) {
                    double e = fabs(hw.x[x] - bz.x[x]);
                    worst = fmax(worst, e);
                    assert_true(e <= 0.5 + 1e-6);
                }
            }
        /* The other way is exact: Bézier -> Hermite -> Bézier gives the net back. */
        cs_patch_t q, q2;
        rnd_patch(&q, 3, 3, CS_POS_LIMIT / 40);
        cs_patch_hermite_t hq;
        assert_int_equal(cs_patch_to_hermite(&q, &hq), CS_OK);
        assert_int_equal(cs_patch_from_hermite(&q2, &hq), CS_OK);
        assert_memory_equal(q.p, q2.p, sizeof q.p);
        /* And the Hermite data are the derivatives at the corners. */
        for (int a = 0; a < 2; a++)
            for (int b = 0; b < 2; b++) {
                assert_true(maxdiff(ref_eval(&q, a, b, 1), &hq.pu[a][b]) == 0);
                assert_true(maxdiff(ref_eval(&q, a, b, 2), &hq.pv[a][b]) == 0);
                assert_true(maxdiff(ref_eval(&q, a, b, 3), &hq.puv[a][b]) < 1e-6);
            }
    }
    report("Hermite -> Bezier", worst, "LSB");
}

static void test_hermite_split9(void **state)
{
    (void)state;
    double worst_corner = 0, worst_surface = 0;
    for (int it = 0; it < 100; it++) {
        cs_patch_hermite_t h, out[3][3];
        rnd_hermite(&h, CS_POS_LIMIT / 2, CS_POS_LIMIT / 4);
        cs_param_t us[2], vs[2];
        do {
            us[0] = rnd_param();
            us[1] = rnd_param();
        } while (us[0] == 0 || us[0] >= us[1] || us[1] == CS_PARAM_ONE);
        if (it == 0) {
            us[0] = CS_PARAM_ONE / 3; /* the seed's picture: thirds */
            us[1] = 2 * (CS_PARAM_ONE / 3);
        }
        do {
            vs[0] = rnd_param();
            vs[1] = rnd_param();
        } while (vs[0] == 0 || vs[0] >= vs[1] || vs[1] == CS_PARAM_ONE);
        assert_int_equal(cs_patch_hermite_split9(&h, us, vs, out), CS_OK);
        double ub[4] = {0, us[0] / Q30, us[1] / Q30, 1}, vb[4] = {0, vs[0] / Q30, vs[1] / Q30, 1};
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) {
                double lu = ub[a + 1] - ub[a], lv = vb[b + 1] - vb[b];
                for (int ca = 0; ca < 2; ca++)
                    for (int cb = 0; cb < 2; cb++) {
                        double u = ub[a + ca], v = vb[b + cb];
                        dv3 p0 = hermite_eval_d(&h, u, v, 0), pu = hermite_eval_d(&h, u, v, 1);
                        dv3 pv = hermite_eval_d(&h, u, v, 2), puv = hermite_eval_d(&h, u, v, 3);
                        for (int x = 0; x < 3; x++) {
                            pu.x[x] *= lu;
                            pv.x[x] *= lv;
                            puv.x[x] *= lu * lv;
                        }
                        const cs_patch_hermite_t *q = &out[a][b];
                        double d =
                            fmax(fmax(maxdiff(p0, &q->p[ca][cb]), maxdiff(pu, &q->pu[ca][cb])),
                                 fmax(maxdiff(pv, &q->pv[ca][cb]), maxdiff(puv, &q->puv[ca][cb])));
                        worst_corner = fmax(worst_corner, d);
                        if (d > 0.5 + 1e-5)
                            printf("a%d b%d ca%d cb%d: %g %g %g %g\n", a, b, ca, cb,
                                   maxdiff(p0, &q->p[ca][cb]), maxdiff(pu, &q->pu[ca][cb]),
                                   maxdiff(pv, &q->pv[ca][cb]), maxdiff(puv, &q->puv[ca][cb]));
                        assert_true(d <= 0.5 + 1e-5); /* one rounding + guard error */
                    }
                /* The sub-patch reproduces the parent over its rectangle. */
                for (int s = 0; s <= 4; s++)
                    for (int r = 0; r <= 4; r++) {
                        double ss = s / 4.0, rr = r / 4.0;
                        dv3 sub = hermite_eval(&out[a][b], ss, rr);
                        dv3 par = hermite_eval(&h, ub[a] + lu * ss, vb[b] + lv * rr);
                        for (int x = 0; x < 3; x++) {
                            double d = fabs(sub.x[x] - par.x[x]);
                            worst_surface = fmax(worst_surface, d);
                            /* 0.5 LSB per datum times sum |h_k h_l| (<= 1.43 at most). */
                            assert_true(d <= 0.72);
                        }
                    }
            }
    }
    cs_patch_hermite_t h, out[3][3];
    rnd_hermite(&h, 10, 10);
    cs_param_t bad[2] = {CS_PARAM_ONE / 2, CS_PARAM_ONE / 4}, good[2] = {1, 2};
    assert_int_equal(cs_patch_hermite_split9(&h, bad, good, out), CS_ERR_ARG);
    h.puv[1][1].x = CS_POS_LIMIT + 1;
    assert_int_equal(cs_patch_hermite_split9(&h, good, good, out), CS_ERR_RANGE);
    report("9-way split corners", worst_corner, "LSB");
    report("9-way split surfaces", worst_surface, "LSB");
}

static void test_continuity(void **state)
{
    (void)state;
    for (int it = 0; it < 50; it++) {
        cs_patch_t p, lo, hi;
        rnd_patch(&p, 3, 3, 100 * CS_POS_ONE_MM);
        cs_patch_cont_t c;
        const cs_param_t sin_tol = (cs_param_t)(1e-4 * Q30);
        /* Halves at u = 1/2: same derivative scale both sides, C1 within rounding (each point
         * rounded by 0.5 LSB: a cross derivative 3 (p3 - p2) by up to 3 LSB), and C2 within
         * the second derivative's rounding, 6 (0.5 + 2 * 0.5 + 0.5) = 12 LSB. */
        assert_int_equal(cs_patch_split_u(&p, CS_PARAM_ONE / 2, &lo, &hi), CS_OK);
        assert_int_equal(cs_patch_continuity(&lo, &hi, 3, sin_tol, &c), CS_OK);
        assert_true(c == CS_PATCH_CONT_C1 || c == CS_PATCH_CONT_C2);
        assert_int_equal(cs_patch_continuity(&lo, &hi, 12, sin_tol, &c), CS_OK);
        assert_int_equal(c, CS_PATCH_CONT_C2);
        /* Move hi's third row: the first cross derivative (rows 0, 1) stays, the second
         * 6 (p0 - 2 p1 + p2) changes by 6 x 100 LSB: C1, not C2. */
        cs_patch_t third = hi;
        for (int j = 0; j < 4; j++)
            third.p[2][j].z += 100;
        assert_int_equal(cs_patch_continuity(&lo, &third, 12, sin_tol, &c), CS_OK);
        assert_int_equal(c, CS_PATCH_CONT_C1);
        /* At u = 1/4 the cross derivatives differ in length (1/4 vs 3/4 of Pu): G1 only. */
        assert_int_equal(cs_patch_split_u(&p, CS_PARAM_ONE / 4, &lo, &hi), CS_OK);
        assert_int_equal(cs_patch_continuity(&lo, &hi, 3, sin_tol, &c), CS_OK);
        assert_int_equal(c, CS_PATCH_CONT_G1);
        /* Bend hi's second row off the tangent plane: C0 only. */
        cs_patch_t bent = hi;
        bent.p[1][1].z += 20 * CS_POS_ONE_MM;
        bent.p[1][2].x -= 20 * CS_POS_ONE_MM;
        assert_int_equal(cs_patch_continuity(&lo, &bent, 3, sin_tol, &c), CS_OK);
        assert_int_equal(c, CS_PATCH_CONT_C0);
        /* Fold it back on itself (cross derivative reversed): coplanar but not G1. */
        cs_patch_t fold = hi;
        for (int j = 0; j < 4; j++) {
            for (int i = 1; i < 4; i++) {
                fold.p[i][j].x = 2 * hi.p[0][j].x - hi.p[i][j].x;
                fold.p[i][j].y = 2 * hi.p[0][j].y - hi.p[i][j].y;
                fold.p[i][j].z = 2 * hi.p[0][j].z - hi.p[i][j].z;
            }
        }
        assert_int_equal(cs_patch_continuity(&lo, &fold, 3, sin_tol, &c), CS_OK);
        assert_int_equal(c, CS_PATCH_CONT_C0);
        /* Move a shared edge point: no continuity. */
        cs_patch_t moved = hi;
        moved.p[0][2].y += 10;
        assert_int_equal(cs_patch_continuity(&lo, &moved, 3, sin_tol, &c), CS_OK);
        assert_int_equal(c, CS_PATCH_CONT_NONE);
    }
    cs_patch_t a, b;
    rnd_patch(&a, 3, 3, 1000);
    rnd_patch(&b, 3, 2, 1000);
    cs_patch_cont_t c;
    assert_int_equal(cs_patch_continuity(&a, &b, 0, 0, &c), CS_ERR_DEGREE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_eval_derivs),
        cmocka_unit_test(test_args),
        cmocka_unit_test(test_normal_random),
        cmocka_unit_test(test_normal_teapot_poles),
        cmocka_unit_test(test_split),
        cmocka_unit_test(test_iso_and_raster),
        cmocka_unit_test(test_raster_no_cracks),
        cmocka_unit_test(test_from_power),
        cmocka_unit_test(test_hermite),
        cmocka_unit_test(test_hermite_split9),
        cmocka_unit_test(test_continuity),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
