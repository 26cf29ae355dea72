/* test_coons: Coons, ruled and extruded patches against seed 000's formulas evaluated in double
 * here: bilinear S1 + S2 - S3 with linear blends, bicubic with the seed's Hermite matrix H
 * (whose monomial vector is (1, u, u^2, u^3): (A1, A2, A1u, A2u) H gives 1 - 3u^2 + 2u^3 ...),
 * ruled (1 - v) P(u) + v Q(u), extrusion P(u) + v d. Conversions within 0.5 LSB (one rounding
 * of 9 x an exact integer net; ruled with an elevated curve 1 LSB), cubic boundaries exact. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "cs_coons.h"
#include "cs_patchfile.h"
#include "cs_ref.h"

#define LSB CS_REF_LSB_MM

static void report(const char *what, double worst_mm)
{
    if (getenv("CS_TEST_VERBOSE"))
        printf("%s: worst %.3f LSB\n", what, worst_mm / LSB);
}

static uint64_t rng = 0xD1B54A32D192ED03u;
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

/* A polynomial curve of degree n from a to b with random inner points. */
static cs_bezier_t curve(unsigned n, cs_vec3_t a, cs_vec3_t b, int32_t lim)
{
    cs_vec3_t pts[4];
    pts[0] = a;
    for (unsigned i = 1; i < n; i++)
        pts[i] = rnd_vec(lim);
    pts[n] = b;
    cs_bezier_t c;
    assert_int_equal(cs_bezier_init(&c, n, pts), CS_OK);
    return c;
}

/* Derivative of a curve at t, mm (own formula: n sum B_i^{n-1} (P_{i+1} - P_i)). */
static cs_ref_vec_t deriv(const cs_bezier_t *c, double t)
{
    int n = c->degree;
    cs_ref_vec_t r = {0, 0, 0};
    for (int i = 0; i < n; i++) {
        double b = 1;
        for (int k = 0; k < i; k++)
            b *= t;
        for (int k = i; k < n - 1; k++)
            b *= 1 - t;
        double binom = n - 1 == 2 ? (i == 1 ? 2 : 1) : 1;
        b *= binom * n;
        r.x += b * (c->p[i + 1].x - c->p[i].x) * LSB;
        r.y += b * (c->p[i + 1].y - c->p[i].y) * LSB;
        r.z += b * (c->p[i + 1].z - c->p[i].z) * LSB;
    }
    return r;
}

/* Patch point in double (tensor Bernstein), mm. */
static cs_ref_vec_t patch_eval(const cs_patch_t *p, double u, double v)
{
    static const double bin[4][4] = {{1, 0, 0, 0}, {1, 1, 0, 0}, {1, 2, 1, 0}, {1, 3, 3, 1}};
    cs_ref_vec_t r = {0, 0, 0};
    for (int i = 0; i <= p->deg_u; i++)
        for (int j = 0; j <= p->deg_v; j++) {
            double b = bin[p->deg_u][i] * pow(u, i) * pow(1 - u, p->deg_u - i) * bin[p->deg_v][j] *
                       pow(v, j) * pow(1 - v, p->deg_v - j);
            r.x += b * p->p[i][j].x * LSB;
            r.y += b * p->p[i][j].y * LSB;
            r.z += b * p->p[i][j].z * LSB;
        }
    return r;
}

static double maxc(cs_ref_vec_t a, cs_ref_vec_t b)
{
    return fmax(fabs(a.x - b.x), fmax(fabs(a.y - b.y), fabs(a.z - b.z)));
}

static cs_ref_vec_t lin(double a, cs_ref_vec_t p, double b, cs_ref_vec_t q)
{
    cs_ref_vec_t r = {a * p.x + b * q.x, a * p.y + b * q.y, a * p.z + b * q.z};
    return r;
}

/* Seed 000's H, rows applied to (1, t, t^2, t^3). */
static void hblend(double t, double h[4])
{
    static const double H[4][4] = {{1, 0, -3, 2}, {0, 0, 3, -2}, {0, 1, -2, 1}, {0, 0, -1, 1}};
    double m[4] = {1, t, t * t, t * t * t};
    for (int k = 0; k < 4; k++)
        h[k] = H[k][0] * m[0] + H[k][1] * m[1] + H[k][2] * m[2] + H[k][3] * m[3];
}

/* Seed 000: S = S1 + S2 - S3, S1 = (P1, P2, P1v, P2v) H(v), S2 = (Q1, Q2, Q1u, Q2u) H(u),
 * S3 = H(u)^T A H(v), with hu, hv the Hermite blends and c1, c2 the curves at u, v. */
static cs_ref_vec_t seed_coons(const double hu[4], const double hv[4], const cs_ref_vec_t c1[4],
                               const cs_ref_vec_t c2[4], const cs_ref_vec_t A[4][4])
{
    cs_ref_vec_t want = {0, 0, 0};
    for (int k = 0; k < 4; k++) {
        want = lin(1, want, hv[k], c1[k]);
        want = lin(1, want, hu[k], c2[k]);
        for (int l = 0; l < 4; l++)
            want = lin(1, want, -hu[k] * hv[l], A[k][l]);
    }
    return want;
}

typedef struct {
    cs_bezier_t p1, p2, q1, q2;
} boundary_t;

static boundary_t rnd_boundary(int32_t lim)
{
    cs_vec3_t A = rnd_vec(lim), B = rnd_vec(lim), C = rnd_vec(lim), D = rnd_vec(lim);
    boundary_t b;
    b.p1 = curve(1 + (unsigned)(xorshift() % 3), A, B, lim);
    b.p2 = curve(1 + (unsigned)(xorshift() % 3), D, C, lim);
    b.q1 = curve(1 + (unsigned)(xorshift() % 3), A, D, lim);
    b.q2 = curve(1 + (unsigned)(xorshift() % 3), B, C, lim);
    return b;
}

/* Seed 000's bicubic Coons point at (u, v) from the boundaries, the derivative curves dp (when
 * with) or their defaults, and S3's matrix A (twists in its lower right block): the default
 * derivative curves are the Hermite cubics between the crossing curves' corner tangents with the
 * twists as end slopes (zero twists: Bézier (a, a, b, b)). */
static cs_ref_vec_t coons_ref(const boundary_t *b, const cs_bezier_t *const dp[4], bool with,
                              const cs_ref_vec_t A[4][4], double u, double v)
{
    double hu[4], hv[4];
    hblend(u, hu);
    hblend(v, hv);
    cs_ref_vec_t d0 =
        lin(1, lin(hu[0], A[0][2], hu[1], A[1][2]), 1, lin(hu[2], A[2][2], hu[3], A[3][2]));
    cs_ref_vec_t d1 =
        lin(1, lin(hu[0], A[0][3], hu[1], A[1][3]), 1, lin(hu[2], A[2][3], hu[3], A[3][3]));
    cs_ref_vec_t d2 =
        lin(1, lin(hv[0], A[2][0], hv[1], A[2][1]), 1, lin(hv[2], A[2][2], hv[3], A[2][3]));
    cs_ref_vec_t d3 =
        lin(1, lin(hv[0], A[3][0], hv[1], A[3][1]), 1, lin(hv[2], A[3][2], hv[3], A[3][3]));
    cs_ref_vec_t c1[4] = {cs_ref_eval(&b->p1, u), cs_ref_eval(&b->p2, u),
                          with ? cs_ref_eval(dp[0], u) : d0, with ? cs_ref_eval(dp[1], u) : d1};
    cs_ref_vec_t c2[4] = {cs_ref_eval(&b->q1, v), cs_ref_eval(&b->q2, v),
                          with ? cs_ref_eval(dp[2], v) : d2, with ? cs_ref_eval(dp[3], v) : d3};
    return seed_coons(hu, hv, c1, c2, A);
}

static void test_bilinear(void **state)
{
    (void)state;
    double worst = 0;
    for (int it = 0; it < 300; it++) {
        boundary_t b = rnd_boundary(CS_POS_LIMIT / 2);
        cs_patch_t p;
        assert_int_equal(cs_coons_bilinear(&b.p1, &b.p2, &b.q1, &b.q2, &p), CS_OK);
        cs_ref_vec_t A = cs_ref_from_pos(&b.p1.p[0]), B = cs_ref_from_pos(&b.q2.p[0]);
        cs_ref_vec_t C = cs_ref_from_pos(&b.p2.p[b.p2.degree]), D = cs_ref_from_pos(&b.p2.p[0]);
        for (int s = 0; s <= 8; s++)
            for (int r = 0; r <= 8; r++) {
                double u = s / 8.0, v = r / 8.0;
                cs_ref_vec_t s1 = lin(1 - v, cs_ref_eval(&b.p1, u), v, cs_ref_eval(&b.p2, u));
                cs_ref_vec_t s2 = lin(1 - u, cs_ref_eval(&b.q1, v), u, cs_ref_eval(&b.q2, v));
                cs_ref_vec_t s3 = lin(1, lin((1 - u) * (1 - v), A, u * (1 - v), B), 1,
                                      lin(v * (1 - u), D, u * v, C));
                cs_ref_vec_t want = {s1.x + s2.x - s3.x, s1.y + s2.y - s3.y, s1.z + s2.z - s3.z};
                double d = maxc(want, patch_eval(&p, u, v));
                worst = fmax(worst, d);
                assert_true(d <= 0.5 * LSB + 1e-9);
            }
        /* Cubic boundaries come back exactly. */
        if (b.p1.degree == 3)
            for (int i = 0; i < 4; i++)
                assert_memory_equal(&p.p[i][0], &b.p1.p[i], sizeof(cs_vec3_t));
        if (b.q2.degree == 3)
            for (int j = 0; j < 4; j++)
                assert_memory_equal(&p.p[3][j], &b.q2.p[j], sizeof(cs_vec3_t));
    }
    report("bilinear Coons", worst);
    /* Corners that do not meet. */
    boundary_t b = rnd_boundary(1000);
    b.q2.p[0].x++;
    cs_patch_t p;
    assert_int_equal(cs_coons_bilinear(&b.p1, &b.p2, &b.q1, &b.q2, &p), CS_ERR_DEGENERATE);
}

static void test_bicubic(void **state)
{
    (void)state;
    double worst = 0;
    for (int it = 0; it < 300; it++) {
        boundary_t b = rnd_boundary(CS_POS_LIMIT / 4);
        cs_bezier_t dv[4];
        const cs_bezier_t *dp[4] = {NULL, NULL, NULL, NULL};
        bool with = it % 2 == 1;
        for (int k = 0; k < 4 && with; k++) {
            dv[k] = curve(1 + (unsigned)(xorshift() % 3), rnd_vec(CS_POS_LIMIT / 8),
                          rnd_vec(CS_POS_LIMIT / 8), CS_POS_LIMIT / 8);
            dp[k] = &dv[k];
        }
        cs_patch_t p;
        assert_int_equal(
            cs_coons_bicubic(&b.p1, &b.p2, &b.q1, &b.q2, dp[0], dp[1], dp[2], dp[3], &p), CS_OK);
        /* S3's matrix from the curves (seed 000), zero twists. */
        cs_ref_vec_t A[4][4] = {
            {cs_ref_eval(&b.p1, 0), cs_ref_eval(&b.p2, 0), deriv(&b.q1, 0), deriv(&b.q1, 1)},
            {cs_ref_eval(&b.p1, 1), cs_ref_eval(&b.p2, 1), deriv(&b.q2, 0), deriv(&b.q2, 1)},
            {deriv(&b.p1, 0), deriv(&b.p2, 0), {0, 0, 0}, {0, 0, 0}},
            {deriv(&b.p1, 1), deriv(&b.p2, 1), {0, 0, 0}, {0, 0, 0}},
        };
        for (int s = 0; s <= 8; s++)
            for (int r = 0; r <= 8; r++) {
                double u = s / 8.0, v = r / 8.0;
                cs_ref_vec_t want = coons_ref(&b, dp, with, (const cs_ref_vec_t(*)[4])A, u, v);
                double d = maxc(want, patch_eval(&p, u, v));
                worst = fmax(worst, d);
                assert_true(d <= 0.5 * LSB + 1e-9);
            }
        /* With the compatible defaults the boundaries come back exactly. */
        if (!with && b.p2.degree == 3)
            for (int i = 0; i < 4; i++)
                assert_memory_equal(&p.p[i][3], &b.p2.p[i], sizeof(cs_vec3_t));
        if (!with && b.q1.degree == 3)
            for (int j = 0; j < 4; j++)
                assert_memory_equal(&p.p[0][j], &b.q1.p[j], sizeof(cs_vec3_t));
    }
    report("bicubic Coons", worst);
    boundary_t b = rnd_boundary(1000);
    b.p1.rational = true;
    cs_patch_t p;
    assert_int_equal(cs_coons_bicubic(&b.p1, &b.p2, &b.q1, &b.q2, NULL, NULL, NULL, NULL, &p),
                     CS_ERR_UNSUPPORTED);
}

/* Bicubic Coons with the twists given (cs_coons_bicubic_twist) against seed 000's formula
 * transcribed here: S = S1 + S2 - S3, S3 = H(u)^T A H(v) with the twists in A's lower right
 * block; default derivative curves are then the Hermite cubics between the crossing curves'
 * corner tangents with the twists as end slopes. With the defaults, the patch's corner twists
 * (9 (p11 - p10 - p01 + p00) at (0, 0), ...) are the given ones. */
static void test_bicubic_twist(void **state)
{
    (void)state;
    double worst = 0, worst_tw = 0;
    for (int it = 0; it < 300; it++) {
        boundary_t b = rnd_boundary(CS_POS_LIMIT / 4);
        cs_vec3_t tw[2][2];
        cs_ref_vec_t T[2][2];
        for (int i = 0; i < 2; i++)
            for (int j = 0; j < 2; j++) {
                tw[i][j] = rnd_vec(CS_POS_LIMIT / 8);
                T[i][j] = cs_ref_from_pos(&tw[i][j]);
            }
        cs_bezier_t dv[4];
        const cs_bezier_t *dp[4] = {NULL, NULL, NULL, NULL};
        bool with = it % 3 == 1;
        for (int k = 0; k < 4 && with; k++) {
            dv[k] = curve(1 + (unsigned)(xorshift() % 3), rnd_vec(CS_POS_LIMIT / 8),
                          rnd_vec(CS_POS_LIMIT / 8), CS_POS_LIMIT / 8);
            dp[k] = &dv[k];
        }
        cs_patch_t p;
        assert_int_equal(cs_coons_bicubic_twist(&b.p1, &b.p2, &b.q1, &b.q2, dp[0], dp[1], dp[2],
                                                dp[3], (const cs_vec3_t(*)[2])tw, &p),
                         CS_OK);
        cs_ref_vec_t A[4][4] = {
            {cs_ref_eval(&b.p1, 0), cs_ref_eval(&b.p2, 0), deriv(&b.q1, 0), deriv(&b.q1, 1)},
            {cs_ref_eval(&b.p1, 1), cs_ref_eval(&b.p2, 1), deriv(&b.q2, 0), deriv(&b.q2, 1)},
            {deriv(&b.p1, 0), deriv(&b.p2, 0), T[0][0], T[0][1]},
            {deriv(&b.p1, 1), deriv(&b.p2, 1), T[1][0], T[1][1]},
        };
        for (int s = 0; s <= 8; s++)
            for (int r = 0; r <= 8; r++) {
                double u = s / 8.0, v = r / 8.0;
                cs_ref_vec_t want = coons_ref(&b, dp, with, (const cs_ref_vec_t(*)[4])A, u, v);
                double d = maxc(want, patch_eval(&p, u, v));
                worst = fmax(worst, d);
                assert_true(d <= 0.5 * LSB + 1e-9);
            }
        for (int i = 0; i < 2 && !with; i++)
            for (int j = 0; j < 2; j++) {
                /* d2S/dudv at corner (i, j) of a bicubic net: 9 times the corner cell's
                 * second difference, signed by the direction of each step. */
                int a0 = 3 * i, a1 = i ? 2 : 1, b0 = 3 * j, b1 = j ? 2 : 1;
                double sg = (i ? -1 : 1) * (j ? -1 : 1);
                cs_ref_vec_t q00 = cs_ref_from_pos(&p.p[a0][b0]),
                             q10 = cs_ref_from_pos(&p.p[a1][b0]);
                cs_ref_vec_t q01 = cs_ref_from_pos(&p.p[a0][b1]),
                             q11 = cs_ref_from_pos(&p.p[a1][b1]);
                cs_ref_vec_t got = {9 * sg * (q11.x - q10.x - q01.x + q00.x),
                                    9 * sg * (q11.y - q10.y - q01.y + q00.y),
                                    9 * sg * (q11.z - q10.z - q01.z + q00.z)};
                double d = maxc(got, T[i][j]);
                worst_tw = fmax(worst_tw, d);
                assert_true(d <= 18 * LSB + 1e-9); /* four points rounded by 0.5 LSB, times 9 */
            }
    }
    report("bicubic Coons with twists", worst);
    report("bicubic Coons: corner twists", worst_tw);
}

static void test_ruled_extrude(void **state)
{
    (void)state;
    double worst = 0;
    for (int it = 0; it < 300; it++) {
        cs_bezier_t a = curve(1 + (unsigned)(xorshift() % 3), rnd_vec(CS_POS_LIMIT / 2),
                              rnd_vec(CS_POS_LIMIT / 2), CS_POS_LIMIT / 2);
        cs_bezier_t b = curve(1 + (unsigned)(xorshift() % 3), rnd_vec(CS_POS_LIMIT / 2),
                              rnd_vec(CS_POS_LIMIT / 2), CS_POS_LIMIT / 2);
        cs_patch_t p;
        assert_int_equal(cs_coons_ruled(&a, &b, &p), CS_OK);
        assert_int_equal(p.deg_v, 1);
        for (int s = 0; s <= 8; s++)
            for (int r = 0; r <= 4; r++) {
                double u = s / 8.0, v = r / 4.0;
                cs_ref_vec_t want = lin(1 - v, cs_ref_eval(&a, u), v, cs_ref_eval(&b, u));
                double d = maxc(want, patch_eval(&p, u, v));
                worst = fmax(worst, d);
                /* Exact, except the elevated curve's points (0.5 LSB each, convex sum). */
                assert_true(d <= (a.degree == b.degree ? 1e-9 : 0.5 * LSB + 1e-9));
            }
        cs_vec3_t dir = rnd_vec(CS_POS_LIMIT / 2);
        assert_int_equal(cs_coons_extrude(&a, &dir, &p), CS_OK);
        for (int s = 0; s <= 8; s++) {
            double u = s / 8.0;
            cs_ref_vec_t c = cs_ref_eval(&a, u), dd = cs_ref_from_pos(&dir);
            assert_true(maxc(c, patch_eval(&p, u, 0)) < 1e-9);
            assert_true(maxc(lin(1, c, 1, dd), patch_eval(&p, u, 1)) < 1e-9);
            assert_true(maxc(lin(1, c, 0.5, dd), patch_eval(&p, u, 0.5)) < 1e-9);
        }
    }
    report("ruled", worst);
    cs_bezier_t a = curve(3, rnd_vec(10), cs_fixed_vec(CS_POS_LIMIT, 0, 0), 10);
    cs_vec3_t dir = cs_fixed_vec(1, 0, 0);
    cs_patch_t p;
    assert_int_equal(cs_coons_extrude(&a, &dir, &p), CS_ERR_RANGE);
}

/* CS_SURF_PICTURES=DIR: also write the example surfaces of docs/surfaces.md as Newell files
 * (drawn with `curvestep toolpath --svg`). Not a check. */
static cs_vec3_t mm(double x, double y, double z)
{
    return cs_fixed_vec((int32_t)lround(x * 65536), (int32_t)lround(y * 65536),
                        (int32_t)lround(z * 65536));
}
static cs_bezier_t bz(unsigned n, const cs_vec3_t *p)
{
    cs_bezier_t c;
    if (cs_bezier_init(&c, n, p) != CS_OK)
        abort();
    return c;
}
/* deg_v 1 -> 3 for the Newell writer (rounded to 0.5 LSB: pictures only). */
static void to_bicubic(cs_patch_t *p)
{
    cs_patch_t r = *p;
    r.deg_v = 3;
    for (int i = 0; i <= p->deg_u; i++) {
        cs_vec3_t a = p->p[i][0], b = p->p[i][1];
        r.p[i][0] = a;
        r.p[i][1] = cs_fixed_vec((2 * a.x + b.x) / 3, (2 * a.y + b.y) / 3, (2 * a.z + b.z) / 3);
        r.p[i][2] = cs_fixed_vec((a.x + 2 * b.x) / 3, (a.y + 2 * b.y) / 3, (a.z + 2 * b.z) / 3);
        r.p[i][3] = b;
    }
    *p = r;
}
static void save(const char *dir, const char *name, const cs_patch_t *p, size_t n)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s.txt", dir, name);
    FILE *f = fopen(path, "w");
    if (!f || cs_patchfile_write(f, p, n) != CS_OK)
        abort();
    fclose(f);
}
static void write_pictures(const char *dir)
{
    cs_vec3_t a[4] = {mm(0, 0, 0), mm(10, 0, 12), mm(20, 0, -6), mm(30, 0, 0)};
    cs_vec3_t b[3] = {mm(0, 30, 5), mm(15, 30, 20), mm(30, 30, 5)};
    cs_vec3_t c[2] = {mm(0, 0, 0), mm(0, 30, 5)};
    cs_vec3_t d[4] = {mm(30, 0, 0), mm(30, 10, -10), mm(30, 20, 15), mm(30, 30, 5)};
    cs_bezier_t p1 = bz(3, a), p2 = bz(2, b), q1 = bz(1, c), q2 = bz(3, d);
    cs_patch_t p;
    if (cs_coons_bilinear(&p1, &p2, &q1, &q2, &p) != CS_OK)
        abort();
    save(dir, "coons_bilinear", &p, 1);
    if (cs_coons_bicubic(&p1, &p2, &q1, &q2, NULL, NULL, NULL, NULL, &p) != CS_OK)
        abort();
    save(dir, "coons_bicubic", &p, 1);
    if (cs_coons_ruled(&p1, &q2, &p) != CS_OK)
        abort();
    to_bicubic(&p);
    save(dir, "ruled", &p, 1);
    cs_vec3_t s[4] = {mm(0, 0, 0), mm(20, 0, 0), mm(0, 20, 0), mm(20, 20, 0)};
    cs_bezier_t sc = bz(3, s);
    cs_vec3_t dir3 = mm(0, 5, 15);
    if (cs_coons_extrude(&sc, &dir3, &p) != CS_OK)
        abort();
    to_bicubic(&p);
    save(dir, "extrusion", &p, 1);
}

int main(void)
{
    if (getenv("CS_SURF_PICTURES"))
        write_pictures(getenv("CS_SURF_PICTURES"));
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bilinear),
        cmocka_unit_test(test_bicubic),
        cmocka_unit_test(test_bicubic_twist),
        cmocka_unit_test(test_ruled_extrude),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
