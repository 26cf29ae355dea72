/* test_finish: ball-end finishing passes (host/cs_finish) on test patches (flat, concave
 * cylinder, convex dome, saddle), checked against a double reference written here: every
 * vertex on the exact offset surface P + R N (2 LSB), every chord within tol of the exact
 * offset curve, the scallop measured densely between neighbouring passes below H, the flat
 * step-over close to w = 2 sqrt(2 R H - H^2), gouge warnings where the concave radius < R. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_finish.h"
#include "cs_trace.h"

#define MM  65536.0
#define LSB (1.0 / MM)

static void report(const char *what, double v, const char *unit)
{
    if (getenv("CS_TEST_VERBOSE"))
        printf("%s: %.6g %s\n", what, v, unit);
}

/* --- double reference of a bicubic (own code, not cs_finish's) ---------------------------- */

static double b3(int k, double t)
{
    static const double c[4] = {1, 3, 3, 1};
    return c[k] * pow(t, k) * pow(1 - t, 3 - k);
}
static double db3(int k, double t)
{
    /* d/dt of C(3,k) t^k (1-t)^(3-k) */
    static const double c[4] = {1, 3, 3, 1};
    double a = k > 0 ? k * pow(t, k - 1) * pow(1 - t, 3 - k) : 0;
    double b = k < 3 ? (3 - k) * pow(t, k) * pow(1 - t, 2 - k) : 0;
    return c[k] * (a - b);
}
static void ref_point(const cs_patch_t *p, double u, double v, int du, int dv, double o[3])
{
    o[0] = o[1] = o[2] = 0;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double w = (du ? db3(i, u) : b3(i, u)) * (dv ? db3(j, v) : b3(j, v));
            o[0] += w * p->p[i][j].x * LSB;
            o[1] += w * p->p[i][j].y * LSB;
            o[2] += w * p->p[i][j].z * LSB;
        }
}
static void ref_centre(const cs_patch_t *p, double r, double u, double v, double c[3])
{
    double pt[3], pu[3], pv[3], n[3];
    ref_point(p, u, v, 0, 0, pt);
    ref_point(p, u, v, 1, 0, pu);
    ref_point(p, u, v, 0, 1, pv);
    n[0] = pu[1] * pv[2] - pu[2] * pv[1];
    n[1] = pu[2] * pv[0] - pu[0] * pv[2];
    n[2] = pu[0] * pv[1] - pu[1] * pv[0];
    double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int a = 0; a < 3; a++)
        c[a] = pt[a] + r * n[a] / l;
}
static double seg_dist(const double q[3], const double a[3], const double b[3])
{
    double ab[3], aq[3], l2 = 0, t = 0;
    for (int k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k];
        aq[k] = q[k] - a[k];
        l2 += ab[k] * ab[k];
        t += aq[k] * ab[k];
    }
    t = l2 > 0 ? fmin(1, fmax(0, t / l2)) : 0;
    double d = 0;
    for (int k = 0; k < 3; k++)
        d += (aq[k] - t * ab[k]) * (aq[k] - t * ab[k]);
    return sqrt(d);
}
/* Material left over surface point S(u, v) below balls centred at c1, c2 (radius r), along
 * the normal; HUGE_VAL if neither ball is met. */
static double left_over(const cs_patch_t *p, double r, double u, double v, const double c1[3],
                        const double c2[3])
{
    double s[3], n[3], cc[3];
    ref_point(p, u, v, 0, 0, s);
    ref_centre(p, 1.0, u, v, cc); /* unit normal = cc - s */
    for (int a = 0; a < 3; a++)
        n[a] = cc[a] - s[a];
    double best = HUGE_VAL;
    const double *cs[2] = {c1, c2};
    for (int k = 0; k < 2; k++) {
        double d[3] = {s[0] - cs[k][0], s[1] - cs[k][1], s[2] - cs[k][2]};
        double b = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
        double c = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - r * r;
        if (c <= 0)
            return 0;
        double disc = b * b - c;
        if (disc >= 0 && -b - sqrt(disc) >= 0)
            best = fmin(best, -b - sqrt(disc));
    }
    return best;
}

/* --- collecting the passes ----------------------------------------------------------------- */

typedef struct {
    double u, v;
    cs_vec3_t c;
    size_t pass;
} vtx_t;

typedef struct {
    vtx_t *v;
    size_t n, cap;
} coll_t;

static bool collect(void *ctx, size_t pass, double u, double v, const cs_vec3_t *c, bool start)
{
    (void)start;
    coll_t *k = ctx;
    if (k->n == k->cap) {
        k->cap = k->cap ? 2 * k->cap : 1024;
        k->v = realloc(k->v, k->cap * sizeof *k->v);
        if (!k->v)
            return false;
    }
    k->v[k->n++] = (vtx_t){u, v, *c, pass};
    return true;
}

static void grid_patch(cs_patch_t *p, double (*f)(double x, double y), double size)
{
    /* z = f(x, y) sampled as a bicubic: control points on the grid, heights interpolated by
     * the Bézier form only approximately; the tests compare with the patch itself. */
    cs_vec3_t pts[16];
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double x = size * i / 3, y = size * j / 3;
            pts[4 * i + j] = cs_fixed_vec((int32_t)lround(x * MM), (int32_t)lround(y * MM),
                                          (int32_t)lround(f(x, y) * MM));
        }
    assert_int_equal(cs_patch_init(p, 3, 3, pts), CS_OK);
}

static double flat(double x, double y)
{
    (void)x;
    (void)y;
    return 5;
}
/* Concave trough along x (radius ~ 30 mm) */
static double trough(double x, double y)
{
    (void)x;
    return 0.02 * (y - 15) * (y - 15);
}
static double dome(double x, double y)
{
    return -0.015 * ((x - 15) * (x - 15) + (y - 15) * (y - 15));
}
static double saddle(double x, double y)
{
    return 0.01 * ((x - 15) * (x - 15) - (y - 15) * (y - 15));
}
/* A sharp concave crease (radius ~ 1 mm or less) for the gouge warning. */
static double crease(double x, double y)
{
    (void)x;
    return 0.5 * (y - 15) * (y - 15);
}

/* Runs the planner and checks everything the header promises. */
static void check_surface(double (*f)(double, double), const char *name, double r, double h,
                          double tol_mm, size_t *passes_out)
{
    cs_patch_t p;
    grid_patch(&p, f, 30);
    coll_t k = {NULL, 0, 0};
    cs_finish_stats_t st = {0, 0, 0, 0, 0, HUGE_VAL, 0, 0};
    cs_pos_t tol = (cs_pos_t)lround(tol_mm * MM);
    assert_int_equal(cs_finish_patch(&p, r, h, tol, collect, &k, &st), CS_OK);
    assert_true(st.passes >= 2);
    assert_int_equal(k.n, st.vertices);
    double worst_v = 0, worst_chord = 0, worst_scallop = 0;
    size_t first = 0;
    double prev_v = -1;
    for (size_t i = 0; i < k.n; i++) {
        double c[3];
        ref_centre(&p, r, k.v[i].u, k.v[i].v, c);
        double d = fmax(fabs(c[0] - k.v[i].c.x * LSB),
                        fmax(fabs(c[1] - k.v[i].c.y * LSB), fabs(c[2] - k.v[i].c.z * LSB)));
        worst_v = fmax(worst_v, d);
        assert_true(d <= 2 * LSB);
        if (i > 0 && k.v[i].pass == k.v[i - 1].pass) {
            /* The chord against the exact offset curve between its end parameters. */
            double a[3] = {k.v[i - 1].c.x * LSB, k.v[i - 1].c.y * LSB, k.v[i - 1].c.z * LSB};
            double b[3] = {k.v[i].c.x * LSB, k.v[i].c.y * LSB, k.v[i].c.z * LSB};
            for (int s = 1; s < 32; s++) {
                double u = k.v[i - 1].u + (k.v[i].u - k.v[i - 1].u) * s / 32;
                double q[3];
                ref_centre(&p, r, u, k.v[i].v, q);
                worst_chord = fmax(worst_chord, seg_dist(q, a, b));
            }
        }
        if (k.v[i].v != prev_v) {
            /* A new pass: the scallop between it and the previous one, densely. */
            if (prev_v >= 0) {
                double v1 = prev_v, v2 = k.v[i].v;
                for (int iu = 0; iu <= 64; iu++) {
                    double u = iu / 64.0, c1[3], c2[3];
                    ref_centre(&p, r, u, v1, c1);
                    ref_centre(&p, r, u, v2, c2);
                    for (int is = 1; is < 32; is++)
                        worst_scallop = fmax(worst_scallop,
                                             left_over(&p, r, u, v1 + (v2 - v1) * is / 32, c1, c2));
                }
            }
            prev_v = k.v[i].v;
            first = i;
        }
    }
    (void)first;
    assert_true(k.v[0].v == 0 && k.v[k.n - 1].v == 1); /* the raster covers the whole patch */
    char what[96];
    snprintf(what, sizeof what, "%s: %zu passes, vertex error", name, st.passes);
    report(what, worst_v / LSB, "LSB");
    snprintf(what, sizeof what, "%s: chord deviation (tol %g)", name, tol_mm);
    report(what, worst_chord, "mm");
    snprintf(what, sizeof what, "%s: scallop (H %g)", name, h);
    report(what, worst_scallop, "mm");
    assert_true(worst_chord <= tol_mm);
    assert_true(worst_scallop < h);
    if (passes_out)
        *passes_out = st.passes;
    free(k.v);
}

static void test_flat(void **state)
{
    (void)state;
    size_t passes = 0;
    check_surface(flat, "flat", 3, 0.05, 0.01, &passes);
    /* 30 mm wide: the flat step-over w = 2 sqrt(2 R H - H^2) = 1.0939 mm needs >= 28 strips;
     * the planner aims at 0.9 H (w = 1.0378 mm, 29 strips) and may shrink a step once by 0.85
     * on a plane (sampling), no more. */
    double w = 2 * sqrt(2 * 3 * 0.05 - 0.05 * 0.05), ht = 0.9 * 0.05;
    double w9 = 2 * sqrt(2 * 3 * ht - ht * ht);
    assert_true(passes >= (size_t)ceil(30 / w) + 1);
    assert_true(passes <= (size_t)ceil(30 / (0.85 * w9)) + 1);
}

static void test_curved(void **state)
{
    (void)state;
    check_surface(trough, "concave trough", 3, 0.05, 0.01, NULL);
    check_surface(dome, "convex dome", 3, 0.05, 0.01, NULL);
    check_surface(saddle, "saddle", 2, 0.02, 0.005, NULL);
}

static void test_gouge_warning(void **state)
{
    (void)state;
    cs_patch_t p;
    grid_patch(&p, crease, 30);
    coll_t k = {NULL, 0, 0};
    cs_finish_stats_t st = {0, 0, 0, 0, 0, HUGE_VAL, 0, 0};
    assert_int_equal(cs_finish_patch(&p, 5, 0.05, 655, collect, &k, &st), CS_OK);
    /* The Bézier through the crease's grid has z = 112.5, 12.5, 12.5, 112.5 along v, so at
     * v = 1/2: z_vv = 6 (1/2 (12.5 - 25 + 112.5) + 1/2 (112.5 - 25 + 12.5)) = 600 mm, y_v = 30 mm,
     * slope 0: curvature 600 / 900 per mm, radius 1.5 mm < R = 5 mm (flat along x). */
    assert_true(st.gouge_points > 0);
    assert_true(fabs(st.min_radius - 1.5) < 1e-6);
    assert_true(st.gouge_v == 0.5);
    free(k.v);
    /* The trough (smallest radius 900 / 24 = 37.5 mm, same computation) with a 3 mm ball: no
     * warning. */
    grid_patch(&p, trough, 30);
    k.n = 0;
    k.v = NULL;
    k.cap = 0;
    cs_finish_stats_t st2 = {0, 0, 0, 0, 0, HUGE_VAL, 0, 0};
    assert_int_equal(cs_finish_patch(&p, 3, 0.05, 655, collect, &k, &st2), CS_OK);
    assert_int_equal(st2.gouge_points, 0);
    assert_true(fabs(st2.min_radius - 37.5) < 1e-6);
    free(k.v);
    /* Bad arguments. */
    assert_int_equal(cs_finish_patch(&p, 3, 3, 655, collect, &k, &st2), CS_ERR_ARG);
    assert_int_equal(cs_finish_patch(&p, 3, 0.1, 1, collect, &k, &st2), CS_ERR_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flat),
        cmocka_unit_test(test_curved),
        cmocka_unit_test(test_gouge_warning),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
