/* test_finish: ball-end finishing passes (host/cs_finish) on test patches (flat, concave
 * cylinder, convex dome, saddle), checked against a double reference written here: every
 * vertex on the exact offset surface P + R N (2 LSB), every chord within tol of the exact
 * offset curve, the scallop measured densely between neighbouring passes below H, the flat
 * step-over close to w = 2 sqrt(2 R H - H^2), gouge warnings where the concave radius < R.
 * Triangular patches: the collapsed tensor form against the triangle's own barycentric formula
 * (0.5 LSB), and their finishing checked like the others against a triangle reference whose
 * normal comes from the barycentric partials Tu x Tv. */
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
    cs_finish_stats_t st = {0, 0, 0, 0, 0, HUGE_VAL, 0, 0, 0, 0, 0, 0};
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
    cs_finish_stats_t st = {0, 0, 0, 0, 0, HUGE_VAL, 0, 0, 0, 0, 0, 0};
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
    cs_finish_stats_t st2 = {0, 0, 0, 0, 0, HUGE_VAL, 0, 0, 0, 0, 0, 0};
    assert_int_equal(cs_finish_patch(&p, 3, 0.05, 655, collect, &k, &st2), CS_OK);
    assert_int_equal(st2.gouge_points, 0);
    assert_true(fabs(st2.min_radius - 37.5) < 1e-6);
    free(k.v);
    /* Bad arguments. */
    assert_int_equal(cs_finish_patch(&p, 3, 3, 655, collect, &k, &st2), CS_ERR_ARG);
    assert_int_equal(cs_finish_patch(&p, 3, 0.1, 1, collect, &k, &st2), CS_ERR_ARG);
}

/* --- triangular patches -------------------------------------------------------------------- */

static double fact(int k)
{
    return k <= 1 ? 1 : k * fact(k - 1);
}

/* T(u, v) of degree n (w = 1 - u - v), or with du / dv = 1 its partial derivative in u / v
 * (w depending on both): dT/du = n sum_{i+j+k=n-1} B_ijk (S_{i+1,j,k} - S_{i,j,k+1}). */
static void tri_ref(const cs_tripatch_t *t, double u, double v, int du, int dv, double o[3])
{
    int n = t->degree, m = n - (du || dv ? 1 : 0);
    double w = 1 - u - v;
    o[0] = o[1] = o[2] = 0;
    for (int i = 0; i <= m; i++)
        for (int j = 0; i + j <= m; j++) {
            int k = m - i - j;
            double b = fact(m) / (fact(i) * fact(j) * fact(k)) * pow(u, i) * pow(v, j) * pow(w, k);
            const cs_vec3_t *a, *c;
            if (du) {
                a = &t->p[cs_tripatch_index((unsigned)n, (unsigned)i + 1, (unsigned)j)];
                c = &t->p[cs_tripatch_index((unsigned)n, (unsigned)i, (unsigned)j)];
            } else if (dv) {
                a = &t->p[cs_tripatch_index((unsigned)n, (unsigned)i, (unsigned)j + 1)];
                c = &t->p[cs_tripatch_index((unsigned)n, (unsigned)i, (unsigned)j)];
            } else {
                a = &t->p[cs_tripatch_index((unsigned)n, (unsigned)i, (unsigned)j)];
                c = NULL;
            }
            double f = (du || dv) ? n : 1;
            o[0] += f * b * (a->x - (c ? c->x : 0)) * LSB;
            o[1] += f * b * (a->y - (c ? c->y : 0)) * LSB;
            o[2] += f * b * (a->z - (c ? c->z : 0)) * LSB;
        }
}

/* Reference tool centre over the triangle at (u, v): T + R (Tu x Tv) / |Tu x Tv|. */
static void tri_centre(const cs_tripatch_t *t, double r, double u, double v, double c[3])
{
    double pt[3], tu[3], tv[3], n[3];
    tri_ref(t, u, v, 0, 0, pt);
    tri_ref(t, u, v, 1, 0, tu);
    tri_ref(t, u, v, 0, 1, tv);
    n[0] = tu[1] * tv[2] - tu[2] * tv[1];
    n[1] = tu[2] * tv[0] - tu[0] * tv[2];
    n[2] = tu[0] * tv[1] - tu[1] * tv[0];
    double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int a = 0; a < 3; a++)
        c[a] = pt[a] + r * n[a] / l;
}

/* A curved triangle of degree n over the right triangle (0,0) (30,0) (0,30): z from a dome. */
static void make_tri(cs_tripatch_t *t, unsigned n)
{
    cs_vec3_t pts[CS_TRIPATCH_MAX_POINTS];
    for (unsigned i = 0; i <= n; i++)
        for (unsigned j = 0; i + j <= n; j++) {
            double x = 30.0 * i / n, y = 30.0 * j / n;
            double z = 4 - 0.01 * ((x - 10) * (x - 10) + (y - 10) * (y - 10)) + (i == 1 && j == 1);
            pts[cs_tripatch_index(n, i, j)] = cs_fixed_vec(
                (int32_t)lround(x * MM), (int32_t)lround(y * MM), (int32_t)lround(z * MM));
        }
    assert_int_equal(cs_tripatch_init(t, n, pts), CS_OK);
}

/* Tensor patch of any degree, own Bernstein evaluation. */
static void tensor_ref(const cs_patch_t *p, double a, double b, double o[3])
{
    o[0] = o[1] = o[2] = 0;
    for (int i = 0; i <= p->deg_u; i++)
        for (int j = 0; j <= p->deg_v; j++) {
            double w = fact(p->deg_u) / (fact(i) * fact(p->deg_u - i)) * pow(a, i) *
                       pow(1 - a, p->deg_u - i) * fact(p->deg_v) / (fact(j) * fact(p->deg_v - j)) *
                       pow(b, j) * pow(1 - b, p->deg_v - j);
            o[0] += w * p->p[i][j].x * LSB;
            o[1] += w * p->p[i][j].y * LSB;
            o[2] += w * p->p[i][j].z * LSB;
        }
}

static void test_tri_convert(void **state)
{
    (void)state;
    for (unsigned n = 1; n <= CS_TRIPATCH_MAX_DEGREE; n++) { /* every degree up to 7 */
        cs_tripatch_t t;
        make_tri(&t, n);
        cs_patch_t q;
        assert_int_equal(cs_finish_tri_patch(&t, &q), CS_OK);
        assert_int_equal(q.deg_u, n);
        assert_int_equal(q.deg_v, n);
        double worst = 0;
        for (int ia = 0; ia <= 32; ia++)
            for (int ib = 0; ib <= 32; ib++) {
                double a = ia / 32.0, b = ib / 32.0, x[3], y[3];
                tensor_ref(&q, a, b, x);
                tri_ref(&t, b, (1 - b) * (1 - a), 0, 0, y);
                for (int k = 0; k < 3; k++)
                    worst = fmax(worst, fabs(x[k] - y[k]));
            }
        char what[64];
        snprintf(what, sizeof what, "triangle degree %u as a collapsed %ux%u patch", n, n, n);
        report(what, worst / LSB, "LSB");
        assert_true(worst <= 0.5 * LSB + 1e-9);
        /* the edge b = 1 is the corner u = 1 */
        for (unsigned i = 0; i <= n; i++)
            assert_memory_equal(&q.p[i][n], &t.p[cs_tripatch_index(n, n, 0)], sizeof(cs_vec3_t));
    }
    cs_tripatch_t bad = {0};
    cs_patch_t q;
    assert_int_equal(cs_finish_tri_patch(&bad, &q), CS_ERR_DEGREE);
}

static void test_tri_finish(void **state)
{
    (void)state;
    const double r = 3, h = 0.05, tol_mm = 0.01;
    for (unsigned n = 2; n <= 3; n++) {
        cs_tripatch_t t;
        make_tri(&t, n);
        cs_patch_t q;
        assert_int_equal(cs_finish_tri_patch(&t, &q), CS_OK);
        coll_t k = {NULL, 0, 0};
        cs_finish_stats_t st = {0, 0, 0, 0, 0, HUGE_VAL, 0, 0, 0, 0, 0, 0};
        assert_int_equal(cs_finish_patch(&q, r, h, (cs_pos_t)lround(tol_mm * MM), collect, &k, &st),
                         CS_OK);
        double worst_v = 0, worst_chord = 0, worst_scallop = 0, prev_b = -1;
        for (size_t i = 0; i < k.n; i++) {
            /* the finishing's (a, b) is the triangle's (u, v) = (b, (1 - b)(1 - a)) */
            double a = k.v[i].u, b = k.v[i].v, c[3];
            if (b > 1 - 1e-9)
                continue; /* the apex: a limit normal */
            tri_centre(&t, r, b, (1 - b) * (1 - a), c);
            worst_v = fmax(
                worst_v, fmax(fabs(c[0] - k.v[i].c.x * LSB),
                              fmax(fabs(c[1] - k.v[i].c.y * LSB), fabs(c[2] - k.v[i].c.z * LSB))));
            if (i > 0 && k.v[i - 1].pass == k.v[i].pass) {
                double p0[3] = {k.v[i - 1].c.x * LSB, k.v[i - 1].c.y * LSB, k.v[i - 1].c.z * LSB};
                double p1[3] = {k.v[i].c.x * LSB, k.v[i].c.y * LSB, k.v[i].c.z * LSB};
                for (int s = 1; s < 32; s++) {
                    double aa = k.v[i - 1].u + (a - k.v[i - 1].u) * s / 32, qq[3];
                    tri_centre(&t, r, b, (1 - b) * (1 - aa), qq);
                    worst_chord = fmax(worst_chord, seg_dist(qq, p0, p1));
                }
            }
            if (b != prev_b && prev_b >= 0) {
                /* Left over between the passes at u = prev_b and u = b, along the normal, below
                 * the two balls at the same a (a subset of the swept balls: an upper bound). */
                for (int ia = 0; ia <= 64; ia++) {
                    double aa = ia / 64.0, c1[3], c2[3];
                    tri_centre(&t, r, prev_b, (1 - prev_b) * (1 - aa), c1);
                    tri_centre(&t, r, b, (1 - b) * (1 - aa), c2);
                    for (int is = 1; is < 32; is++) {
                        double uu = prev_b + (b - prev_b) * is / 32, vv = (1 - uu) * (1 - aa);
                        double sp[3], cc[3], nn[3], best = HUGE_VAL;
                        tri_ref(&t, uu, vv, 0, 0, sp);
                        tri_centre(&t, 1.0, uu, vv, cc);
                        for (int x = 0; x < 3; x++)
                            nn[x] = cc[x] - sp[x];
                        const double *cs[2] = {c1, c2};
                        for (int z = 0; z < 2; z++) {
                            double d[3] = {sp[0] - cs[z][0], sp[1] - cs[z][1], sp[2] - cs[z][2]};
                            double bb = d[0] * nn[0] + d[1] * nn[1] + d[2] * nn[2];
                            double cq = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - r * r;
                            double disc = bb * bb - cq;
                            if (cq <= 0)
                                best = 0;
                            else if (disc >= 0 && -bb - sqrt(disc) >= 0)
                                best = fmin(best, -bb - sqrt(disc));
                        }
                        worst_scallop = fmax(worst_scallop, best);
                    }
                }
            }
            prev_b = b;
        }
        assert_true(k.v[0].v == 0 && k.v[k.n - 1].v == 1);
        char what[96];
        snprintf(what, sizeof what, "triangle degree %u: %zu passes, vertex error", n, st.passes);
        report(what, worst_v / LSB, "LSB");
        snprintf(what, sizeof what, "triangle degree %u: chord deviation (tol %g)", n, tol_mm);
        report(what, worst_chord, "mm");
        snprintf(what, sizeof what, "triangle degree %u: scallop (H %g)", n, h);
        report(what, worst_scallop, "mm");
        assert_true(worst_v <= 2 * LSB);
        assert_true(worst_chord <= tol_mm);
        assert_true(worst_scallop < h);
        free(k.v);
    }
}

/* A crease across the passes: z = 0.5 (x - 15)^2, passes along u = x. Where the concave radius
 * is below R the offset curve C = P + R N runs backwards (C' . P' < 0): the planner counts those
 * chords and says where the first one starts; the reference computes C' . P' in double. */
static double crease_x(double x, double y)
{
    (void)y;
    return 0.5 * (x - 15) * (x - 15);
}

static void test_fold_detection(void **state)
{
    (void)state;
    cs_patch_t p;
    grid_patch(&p, crease_x, 30);
    coll_t k = {NULL, 0, 0};
    cs_finish_stats_t st = {0, 0, 0, 0, 0, HUGE_VAL, 0, 0, 0, 0, 0, 0};
    assert_int_equal(cs_finish_patch(&p, 5, 0.5, 655, collect, &k, &st), CS_OK);
    assert_true(st.folded > 0);
    /* The reference: C'(u) . P'(u) at v = fold_v, by central differences of ref_centre. */
    double lo = 2, hi = -1;
    for (int i = 1; i < 2000; i++) {
        double u = i / 2000.0, e = 1e-6, c0[3], c1[3], pu[3];
        ref_centre(&p, 5, u - e, st.fold_v, c0);
        ref_centre(&p, 5, u + e, st.fold_v, c1);
        ref_point(&p, u, st.fold_v, 1, 0, pu);
        double d = (c1[0] - c0[0]) * pu[0] + (c1[1] - c0[1]) * pu[1] + (c1[2] - c0[2]) * pu[2];
        if (d < 0) {
            lo = fmin(lo, u);
            hi = fmax(hi, u);
        }
    }
    report("crease, R 5: folded chords", (double)st.folded, "");
    report("crease, R 5: first fold at u", st.fold_u, "");
    report("crease, R 5: reference backwards interval from u", lo, "");
    report("crease, R 5: reference backwards interval to u", hi, "");
    /* the first backward chord starts at most one chord (<= 1/8) before the interval */
    assert_true(lo <= hi && st.fold_u >= lo - 0.125 && st.fold_u <= hi);
    /* The sections are planar (parabolas in x z), so each pass's loop closes and is cut at its
     * crossing: no tool centre is then closer than R - tol to the surface section of its pass
     * (1001 samples over u in [0.25, 0.75]), while the exact offset curve's loop comes far closer
     * (gouge). */
    report("crease, R 5: loops cut", (double)st.loops_cut, "");
    assert_true(st.loops_cut > 0);
    double closest = HUGE_VAL;
    for (size_t i = 0; i < k.n; i++) {
        if (k.v[i].u < 0.3 || k.v[i].u > 0.7)
            continue; /* away from the crease the path is the plain offset */
        double c[3] = {k.v[i].c.x * LSB, k.v[i].c.y * LSB, k.v[i].c.z * LSB};
        for (int j = 0; j <= 1000; j++) { /* u in [0.25, 0.75]: x within 7.5 mm of the crease */
            double q[3];
            ref_point(&p, 0.25 + 0.5 * j / 1000.0, k.v[i].v, 0, 0, q);
            closest =
                fmin(closest, sqrt((c[0] - q[0]) * (c[0] - q[0]) + (c[1] - q[1]) * (c[1] - q[1]) +
                                   (c[2] - q[2]) * (c[2] - q[2])));
        }
    }
    double untrimmed = HUGE_VAL; /* the exact offset curve of one pass, untrimmed */
    for (int i = 0; i <= 100; i++) {
        double e[3];
        ref_centre(&p, 5, 0.3 + 0.4 * i / 100.0, 0.5, e);
        for (int j = 0; j <= 1000; j++) {
            double q[3];
            ref_point(&p, 0.25 + 0.5 * j / 1000.0, 0.5, 0, 0, q);
            untrimmed =
                fmin(untrimmed, sqrt((e[0] - q[0]) * (e[0] - q[0]) + (e[1] - q[1]) * (e[1] - q[1]) +
                                     (e[2] - q[2]) * (e[2] - q[2])));
        }
    }
    report("crease, R 5: closest surface point to a trimmed-path centre", closest, "mm");
    report("crease, R 5: ... to the untrimmed exact offset curve", untrimmed, "mm");
    assert_true(closest >= 5 - 0.01);
    assert_true(untrimmed < 5 - 0.5);
    free(k.v);
    /* R = 1 below the smallest radius 1.5 mm (see test_gouge_warning): no fold. */
    k = (coll_t){NULL, 0, 0};
    cs_finish_stats_t st2 = {0, 0, 0, 0, 0, HUGE_VAL, 0, 0, 0, 0, 0, 0};
    assert_int_equal(cs_finish_patch(&p, 1, 0.1, 655, collect, &k, &st2), CS_OK);
    assert_int_equal(st2.folded, 0);
    free(k.v);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flat),          cmocka_unit_test(test_curved),
        cmocka_unit_test(test_gouge_warning), cmocka_unit_test(test_tri_convert),
        cmocka_unit_test(test_tri_finish),    cmocka_unit_test(test_fold_detection),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
