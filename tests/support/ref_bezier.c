/* ref_bezier: double-precision reference (see ref_bezier.h). */
#include "ref_bezier.h"

#include <math.h>

void ref_bezier_from(const cs_bezier_t *c, ref_bezier_t *r)
{
    r->degree = c->degree;
    r->rational = c->rational;
    for (int i = 0; i <= c->degree; i++) {
        r->p[i][0] = c->p[i].x;
        r->p[i][1] = c->p[i].y;
        r->p[i][2] = c->p[i].z;
        r->w[i] = c->rational ? (double)c->w[i] / (double)CS_WEIGHT_ONE : 1.0;
    }
}

/* Homogeneous de Casteljau: h[0..2] = sum B_i w_i P_i, h[3] = sum B_i w_i. */
static void hom_eval(const ref_bezier_t *r, double t, double h[4])
{
    long double v[CS_BEZIER_MAX_POINTS][4];
    int n = r->degree;
    for (int i = 0; i <= n; i++) {
        for (int a = 0; a < 3; a++)
            v[i][a] = (long double)r->w[i] * r->p[i][a];
        v[i][3] = r->w[i];
    }
    for (int k = 1; k <= n; k++)
        for (int i = 0; i + k <= n; i++)
            for (int a = 0; a < 4; a++)
                v[i][a] = (1.0L - t) * v[i][a] + (long double)t * v[i + 1][a];
    for (int a = 0; a < 4; a++)
        h[a] = (double)v[0][a];
}

/* Homogeneous derivative: the hodograph of the homogeneous curve (degree n - 1). */
static void hom_deriv(const ref_bezier_t *r, double t, double d[4])
{
    int n = r->degree;
    if (n == 0) {
        d[0] = d[1] = d[2] = d[3] = 0;
        return;
    }
    long double v[CS_BEZIER_MAX_POINTS][4];
    for (int i = 0; i < n; i++) {
        for (int a = 0; a < 3; a++)
            v[i][a] = (long double)n * ((long double)r->w[i + 1] * r->p[i + 1][a] -
                                        (long double)r->w[i] * r->p[i][a]);
        v[i][3] = (long double)n * ((long double)r->w[i + 1] - r->w[i]);
    }
    for (int k = 1; k <= n - 1; k++)
        for (int i = 0; i + k <= n - 1; i++)
            for (int a = 0; a < 4; a++)
                v[i][a] = (1.0L - t) * v[i][a] + (long double)t * v[i + 1][a];
    for (int a = 0; a < 4; a++)
        d[a] = (double)v[0][a];
}

void ref_bezier_eval(const ref_bezier_t *r, double t, double out[3])
{
    double h[4];
    hom_eval(r, t, h);
    for (int a = 0; a < 3; a++)
        out[a] = h[a] / h[3];
}

void ref_bezier_deriv(const ref_bezier_t *r, double t, double out[3])
{
    double h[4], d[4];
    hom_eval(r, t, h);
    hom_deriv(r, t, d);
    /* (N/W)' = (N' W - N W') / W^2 */
    for (int a = 0; a < 3; a++)
        out[a] = (d[a] * h[3] - h[a] * d[3]) / (h[3] * h[3]);
}

void ref_bezier_deriv2(const ref_bezier_t *r, double t, double out[3])
{
    int n = r->degree;
    out[0] = out[1] = out[2] = 0;
    if (n < 2)
        return;
    long double v[CS_BEZIER_MAX_POINTS][3];
    for (int i = 0; i + 2 <= n; i++)
        for (int a = 0; a < 3; a++)
            v[i][a] =
                (long double)n * (n - 1) * (r->p[i + 2][a] - 2.0L * r->p[i + 1][a] + r->p[i][a]);
    for (int k = 1; k <= n - 2; k++)
        for (int i = 0; i + k <= n - 2; i++)
            for (int a = 0; a < 3; a++)
                v[i][a] = (1.0L - t) * v[i][a] + (long double)t * v[i + 1][a];
    for (int a = 0; a < 3; a++)
        out[a] = (double)v[0][a];
}

static double speed(const ref_bezier_t *r, double t)
{
    double d[3];
    ref_bezier_deriv(r, t, d);
    return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

static const double gl_x[7] = {0.0,
                               0.4058451513773971669066064,
                               -0.4058451513773971669066064,
                               0.7415311855993944398638648,
                               -0.7415311855993944398638648,
                               0.9491079123427585245261897,
                               -0.9491079123427585245261897};
static const double gl_w[7] = {0.4179591836734693877551020, 0.3818300505051189449503698,
                               0.3818300505051189449503698, 0.2797053914892766679014678,
                               0.2797053914892766679014678, 0.1294849661693832604404745,
                               0.1294849661693832604404745};

static double gl7(const ref_bezier_t *r, double a, double b)
{
    double m = 0.5 * (a + b), h = 0.5 * (b - a), s = 0;
    for (int i = 0; i < 7; i++)
        s += gl_w[i] * speed(r, m + h * gl_x[i]);
    return s * h;
}

static double adapt(const ref_bezier_t *r, double a, double b, double whole, double tol, int depth)
{
    double m = 0.5 * (a + b);
    double l = gl7(r, a, m), rr = gl7(r, m, b);
    if (depth > 40 || fabs(l + rr - whole) <= tol)
        return l + rr;
    return adapt(r, a, m, l, tol / 2, depth + 1) + adapt(r, m, b, rr, tol / 2, depth + 1);
}

double ref_bezier_length(const ref_bezier_t *r, double t0, double t1)
{
    /* Start from 64 pieces so no feature is missed, then refine each adaptively. */
    double total = 0;
    int k = 64;
    for (int i = 0; i < k; i++) {
        double a = t0 + (t1 - t0) * i / k, b = t0 + (t1 - t0) * (i + 1) / k;
        total += adapt(r, a, b, gl7(r, a, b), 1e-7, 0);
    }
    return total;
}

double ref_dist3(const double a[3], const double b[3])
{
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

void ref_rng_seed(ref_rng_t *g, uint64_t seed)
{
    g->s = seed ? seed : 0x9E3779B97F4A7C15ull;
}

uint64_t ref_rng_next(ref_rng_t *g)
{
    g->s ^= g->s >> 12;
    g->s ^= g->s << 25;
    g->s ^= g->s >> 27;
    return g->s * 0x2545F4914F6CDD1Dull;
}

int64_t ref_rng_range(ref_rng_t *g, int64_t lo, int64_t hi)
{
    uint64_t span = (uint64_t)(hi - lo) + 1;
    return lo + (int64_t)(ref_rng_next(g) % span);
}

double ref_rng_unit(ref_rng_t *g)
{
    return (double)(ref_rng_next(g) >> 11) / 9007199254740992.0;
}
