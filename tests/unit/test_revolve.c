/* test_revolve: surfaces of revolution (host/cs_revolve) against the exact surface in double:
 * every sampled point's distance from the axis equals the profile's radius at that u within the
 * tolerance, its height along the axis equals the profile's height (1 LSB), the sweep is
 * covered (ends at the requested angles, a full turn closes on itself), the quarter-arc error is
 * the published 2.7253e-4 of the 4/3 tan(phi/4) cubic. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "cs_ref.h"
#include "cs_patchfile.h"
#include "cs_revolve.h"

#define LSB CS_REF_LSB_MM
#define PI  3.14159265358979323846

static void report(const char *what, double v)
{
    if (getenv("CS_TEST_VERBOSE"))
        printf("%s: %.3g mm\n", what, v);
}

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

/* Radius, height and angle of q about the axis (o, a unit), angle from e1. */
static void cyl(cs_ref_vec_t q, const double o[3], const double a[3], const double e1[3], double *r,
                double *h, double *ang)
{
    double d[3] = {q.x - o[0], q.y - o[1], q.z - o[2]};
    *h = d[0] * a[0] + d[1] * a[1] + d[2] * a[2];
    double p[3] = {d[0] - *h * a[0], d[1] - *h * a[1], d[2] - *h * a[2]};
    *r = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    double e2[3] = {a[1] * e1[2] - a[2] * e1[1], a[2] * e1[0] - a[0] * e1[2],
                    a[0] * e1[1] - a[1] * e1[0]};
    *ang = atan2(p[0] * e2[0] + p[1] * e2[1] + p[2] * e2[2],
                 p[0] * e1[0] + p[1] * e1[1] + p[2] * e1[2]);
}

static void check(const cs_bezier_t *prof, const double o[3], const double axis[3],
                  const double ref[3], double sweep, double tol, const char *name)
{
    cs_patch_t out[CS_REVOLVE_MAX_ARCS];
    size_t n = 0;
    double dev = 0;
    assert_int_equal(cs_revolve(prof, o, axis, ref, sweep, tol, out, CS_REVOLVE_MAX_ARCS, &n, &dev),
                     CS_OK);
    assert_true(dev <= tol);
    double la = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    double a[3] = {axis[0] / la, axis[1] / la, axis[2] / la};
    double dd = ref[0] * a[0] + ref[1] * a[1] + ref[2] * a[2];
    double e1[3] = {ref[0] - dd * a[0], ref[1] - dd * a[1], ref[2] - dd * a[2]};
    double l1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    for (int k = 0; k < 3; k++)
        e1[k] /= l1;
    double worst_r = 0, worst_h = 0;
    for (size_t s = 0; s < n; s++) {
        for (int iu = 0; iu <= 16; iu++)
            for (int iv = 0; iv <= 32; iv++) {
                double u = iu / 16.0, v = iv / 32.0, r, h, ang;
                cs_ref_vec_t q = patch_eval(&out[s], u, v);
                cyl(q, o, a, e1, &r, &h, &ang);
                cs_ref_vec_t pr = cs_ref_eval(prof, u);
                worst_r = fmax(worst_r, fabs(r - fabs(pr.x)));
                worst_h = fmax(worst_h, fabs(h - pr.y));
            }
    }
    /* Start and end of the sweep. */
    double r, h, ang;
    cyl(patch_eval(&out[0], 0.5, 0), o, a, e1, &r, &h, &ang);
    assert_true(fabs(ang) < 1e-5);
    cyl(patch_eval(&out[n - 1], 0.5, 1), o, a, e1, &r, &h, &ang);
    double want = sweep >= 360 ? 0 : (sweep > 180 ? sweep - 360 : sweep) * PI / 180;
    assert_true(fabs(ang - want) < 1e-5);
    if (sweep == 360)
        for (int i = 0; i <= out[0].deg_u; i++) {
            assert_true(abs(out[n - 1].p[i][3].x - out[0].p[i][0].x) <= 1);
            assert_true(abs(out[n - 1].p[i][3].y - out[0].p[i][0].y) <= 1);
            assert_true(abs(out[n - 1].p[i][3].z - out[0].p[i][0].z) <= 1);
        }
    char what[80];
    snprintf(what, sizeof what, "%s: %zu arcs, radius error (bound %.3g)", name, n, dev);
    report(what, worst_r);
    assert_true(worst_r <= dev + 1e-9);
    assert_true(worst_h <= 2 * LSB);
}

static void test_arc_error(void **state)
{
    (void)state;
    /* The classic quarter-circle cubic (k = 0.5523) strays 2.7253e-4 of the radius. */
    assert_true(fabs(cs_revolve_arc_error(PI / 2) - 2.7253e-4) < 2e-8);
    /* Sixth-order: halving the angle divides the error by ~64. */
    double r = cs_revolve_arc_error(PI / 4) / cs_revolve_arc_error(PI / 8);
    assert_true(r > 60 && r < 68);
}

static void test_surfaces(void **state)
{
    (void)state;
    cs_vec3_t line[2] = {cs_fixed_vec(20 << 16, 0, 0), cs_fixed_vec(20 << 16, 30 << 16, 0)};
    cs_bezier_t prof;
    assert_int_equal(cs_bezier_init(&prof, 1, line), CS_OK);
    double o[3] = {5, -3, 2}, z[3] = {0, 0, 1}, x[3] = {1, 0, 0};
    check(&prof, o, z, x, 360, 0.001, "cylinder");
    check(&prof, o, z, x, 90, 0.01, "quarter cylinder");
    /* A bowl-like cubic profile about an oblique axis, 250 degrees. */
    cs_vec3_t cub[4] = {cs_fixed_vec(0, 0, 0), cs_fixed_vec(15 << 16, 0, 0),
                        cs_fixed_vec(25 << 16, 10 << 16, 0), cs_fixed_vec(25 << 16, 25 << 16, 0)};
    assert_int_equal(cs_bezier_init(&prof, 3, cub), CS_OK);
    double ax[3] = {1, 1, 1}, rf[3] = {0, 0, 1};
    check(&prof, o, ax, rf, 250, 0.0005, "bowl about (1,1,1)");
    /* Errors. */
    cs_patch_t out[4];
    size_t n;
    assert_int_equal(cs_revolve(&prof, o, ax, rf, 360, 0.0001, out, 4, &n, NULL), CS_ERR_FULL);
    assert_int_equal(cs_revolve(&prof, o, ax, ax, 90, 0.01, out, 4, &n, NULL), CS_ERR_DEGENERATE);
    assert_int_equal(cs_revolve(&prof, o, ax, rf, 0, 0.01, out, 4, &n, NULL), CS_ERR_ARG);
    assert_int_equal(cs_revolve(&prof, o, ax, rf, 90, 1e-6, out, 4, &n, NULL), CS_ERR_TOLERANCE);
}

/* CS_SURF_PICTURES=DIR: also write a vase (cubic profile turned 360 degrees) as a Newell
 * file for docs/surfaces.md. Not a check. */
static void write_picture(const char *dir)
{
    cs_vec3_t v[4] = {cs_fixed_vec(8 << 16, 0, 0), cs_fixed_vec(30 << 16, 10 << 16, 0),
                      cs_fixed_vec(0, 30 << 16, 0), cs_fixed_vec(10 << 16, 40 << 16, 0)};
    cs_bezier_t prof;
    cs_patch_t out[16];
    size_t n = 0;
    double o[3] = {0, 0, 0}, z[3] = {0, 0, 1}, x[3] = {1, 0, 0};
    char path[512];
    snprintf(path, sizeof path, "%s/revolution.txt", dir);
    FILE *f = fopen(path, "w");
    if (!f || cs_bezier_init(&prof, 3, v) != CS_OK ||
        cs_revolve(&prof, o, z, x, 360, 0.01, out, 16, &n, NULL) != CS_OK ||
        cs_patchfile_write(f, out, n) != CS_OK)
        abort();
    fclose(f);
}

int main(void)
{
    if (getenv("CS_SURF_PICTURES"))
        write_picture(getenv("CS_SURF_PICTURES"));
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_arc_error),
        cmocka_unit_test(test_surfaces),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
