/* cs_varady: see cs_varady.h (seed 002). Double precision, host only. */
#include "cs_varady.h"

#include <math.h>
#include <string.h>

#include "cs_conv.h"

#define PI         3.14159265358979323846
#define MAX_PIECES 64

static void curve_d(const cs_bezier_t *c, double t, double out[3], double der[3])
{
    /* de Casteljau in double (mm), derivative from the last level. */
    double p[4][3];
    unsigned n = c->degree;
    for (unsigned i = 0; i <= n; i++) {
        p[i][0] = cs_conv_pos_to_mm(c->p[i].x);
        p[i][1] = cs_conv_pos_to_mm(c->p[i].y);
        p[i][2] = cs_conv_pos_to_mm(c->p[i].z);
    }
    for (unsigned m = n; m > 1; m--)
        for (unsigned i = 0; i < m; i++)
            for (int a = 0; a < 3; a++)
                p[i][a] = (1 - t) * p[i][a] + t * p[i + 1][a];
    for (int a = 0; a < 3; a++) {
        if (der)
            der[a] = n * (p[1][a] - p[0][a]);
        if (out)
            out[a] = (1 - t) * p[0][a] + t * p[1][a];
    }
}

static double norm3(const double a[3])
{
    return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}

cs_err_t cs_varady_init(cs_varady_t *v, const cs_bezier_t *sides, size_t n)
{
    if (!v || !sides || n < 3 || n > CS_VARADY_MAX_SIDES)
        return CS_ERR_ARG;
    memset(v, 0, sizeof *v);
    v->n = n;
    double total = 0;
    for (size_t i = 0; i < n; i++) {
        const cs_bezier_t *c = &sides[i], *nx = &sides[(i + 1) % n];
        if (c->rational)
            return CS_ERR_UNSUPPORTED;
        if (c->degree < 1 || c->degree > 3)
            return CS_ERR_DEGREE;
        const cs_vec3_t *e = &c->p[c->degree];
        if (e->x != nx->p[0].x || e->y != nx->p[0].y || e->z != nx->p[0].z)
            return CS_ERR_DEGENERATE;
        v->side[i] = *c;
        /* Arc length by 64-chord polyline (enough for the domain's proportions). */
        double prev[3], q[3];
        curve_d(c, 0, prev, NULL);
        for (int k = 1; k <= 64; k++) {
            curve_d(c, k / 64.0, q, NULL);
            double d[3] = {q[0] - prev[0], q[1] - prev[1], q[2] - prev[2]};
            v->len[i] += norm3(d);
            memcpy(prev, q, sizeof q);
        }
        if (!(v->len[i] > 0))
            return CS_ERR_DEGENERATE;
        total += v->len[i];
    }
    /* Seed 002, solution 1: vertices on a circle, angles proportional to arc length; the
     * circle's circumference is the boundary's length, so domain units are about mm. */
    double rho = total / (2 * PI), acc = 0;
    for (size_t i = 0; i < n; i++) {
        double beta = 2 * PI * acc / total;
        v->vert[i][0] = rho * cos(beta);
        v->vert[i][1] = rho * sin(beta);
        acc += v->len[i];
    }
    /* Cross-boundary tangents: away from each corner along the neighbouring side. */
    for (size_t i = 0; i < n; i++) {
        double a[3], b[3];
        curve_d(&v->side[(i + n - 1) % n], 1, NULL, a);
        curve_d(&v->side[(i + 1) % n], 0, NULL, b);
        double la = norm3(a), lb = norm3(b);
        if (!(la > 0) || !(lb > 0))
            return CS_ERR_DEGENERATE;
        for (int k = 0; k < 3; k++) {
            v->t0[i][k] = -a[k] / la;
            v->t1[i][k] = b[k] / lb;
        }
    }
    return CS_OK;
}

void cs_varady_vertex(const cs_varady_t *v, size_t i, double out[2])
{
    out[0] = v->vert[i][0];
    out[1] = v->vert[i][1];
}

/* Signed distance from (x, y) to the line of domain side i (positive inside: the polygon is
 * counter-clockwise). */
static double side_dist(const cs_varady_t *v, size_t i, double x, double y)
{
    const double *a = v->vert[i], *b = v->vert[(i + 1) % v->n];
    double ex = b[0] - a[0], ey = b[1] - a[1], l = sqrt(ex * ex + ey * ey);
    return (ex * (y - a[1]) - ey * (x - a[0])) / l;
}

void cs_varady_eval(const cs_varady_t *v, double x, double y, double out[3])
{
    size_t n = v->n;
    double d[CS_VARADY_MAX_SIDES];
    for (size_t i = 0; i < n; i++)
        d[i] = side_dist(v, i, x, y);
    /* mu_i = D_i / sum D_j with D_i = prod_{j != i} d_j^2. */
    double D[CS_VARADY_MAX_SIDES], sum = 0;
    for (size_t i = 0; i < n; i++) {
        D[i] = 1;
        for (size_t j = 0; j < n; j++)
            if (j != i)
                D[i] *= d[j] * d[j];
        sum += D[i];
    }
    out[0] = out[1] = out[2] = 0;
    if (!(sum > 1e-300)) {
        /* At a vertex (two distances zero): the corner itself. */
        size_t best = 0;
        double bd = HUGE_VAL;
        for (size_t i = 0; i < n; i++) {
            double dx = x - v->vert[i][0], dy = y - v->vert[i][1];
            if (dx * dx + dy * dy < bd) {
                bd = dx * dx + dy * dy;
                best = i;
            }
        }
        curve_d(&v->side[best], 0, out, NULL);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        double mu = D[i] / sum;
        if (mu == 0)
            continue;
        double dp = d[(i + n - 1) % n], dn = d[(i + 1) % n];
        double s = dp + dn != 0 ? dp / (dp + dn) : 0.5;
        double p[3];
        curve_d(&v->side[i], s, p, NULL);
        for (int k = 0; k < 3; k++) {
            double t = (1 - s) * v->t0[i][k] + s * v->t1[i][k];
            out[k] += mu * (p[k] + d[i] * t);
        }
    }
}

/* Point and derivative (by central differences of step h, clamped to the segment) of the
 * surface curve c(t) = S(a + t (b - a)). */
static void seg_eval(const cs_varady_t *v, const double a[2], const double b[2], double t,
                     double p[3], double dp[3])
{
    double x = a[0] + t * (b[0] - a[0]), y = a[1] + t * (b[1] - a[1]);
    cs_varady_eval(v, x, y, p);
    if (!dp)
        return;
    double h = 1e-5, t0 = t - h < 0 ? 0 : t - h, t1 = t + h > 1 ? 1 : t + h, p0[3], p1[3];
    cs_varady_eval(v, a[0] + t0 * (b[0] - a[0]), a[1] + t0 * (b[1] - a[1]), p0);
    cs_varady_eval(v, a[0] + t1 * (b[0] - a[0]), a[1] + t1 * (b[1] - a[1]), p1);
    for (int k = 0; k < 3; k++)
        dp[k] = (p1[k] - p0[k]) / (t1 - t0);
}

/* Hermite cubic on [t0, t1] as a Bézier in double, and its largest distance from the surface
 * curve at 33 samples. */
static double fit(const cs_varady_t *v, const double a[2], const double b[2], double t0, double t1,
                  double bz[4][3])
{
    double p0[3], d0[3], p1[3], d1[3], w = t1 - t0;
    seg_eval(v, a, b, t0, p0, d0);
    seg_eval(v, a, b, t1, p1, d1);
    for (int k = 0; k < 3; k++) {
        bz[0][k] = p0[k];
        bz[1][k] = p0[k] + d0[k] * w / 3;
        bz[2][k] = p1[k] - d1[k] * w / 3;
        bz[3][k] = p1[k];
    }
    double worst = 0;
    for (int s = 1; s < 32; s++) {
        double u = s / 32.0, m = 1 - u, q[3], c[3];
        seg_eval(v, a, b, t0 + u * w, q, NULL);
        for (int k = 0; k < 3; k++)
            c[k] = m * m * m * bz[0][k] + 3 * u * m * m * bz[1][k] + 3 * u * u * m * bz[2][k] +
                   u * u * u * bz[3][k];
        double d[3] = {c[0] - q[0], c[1] - q[1], c[2] - q[2]};
        worst = fmax(worst, norm3(d));
    }
    return worst;
}

cs_err_t cs_varady_curve(const cs_varady_t *v, const double a[2], const double b[2], double tol_mm,
                         cs_bezier_t *out, size_t max, size_t *count)
{
    if (!v || !a || !b || !out || !count || !(tol_mm > 0))
        return CS_ERR_ARG;
    /* Uniform pieces, doubling until every piece fits (sampled) within tol. */
    double budget = tol_mm - 1.0 / CS_POS_ONE_MM; /* rounding of the control points */
    if (!(budget > 0))
        return CS_ERR_TOLERANCE;
    for (size_t pieces = 1; pieces <= MAX_PIECES; pieces *= 2) {
        double worst = 0, bz[4][3];
        for (size_t k = 0; k < pieces && worst <= budget; k++)
            worst = fmax(worst, fit(v, a, b, (double)k / pieces, (double)(k + 1) / pieces, bz));
        if (worst > budget)
            continue;
        if (pieces > max)
            return CS_ERR_FULL;
        for (size_t k = 0; k < pieces; k++) {
            fit(v, a, b, (double)k / pieces, (double)(k + 1) / pieces, bz);
            cs_vec3_t pts[4];
            for (int j = 0; j < 4; j++)
                if (cs_conv_mm_to_vec(bz[j][0], bz[j][1], bz[j][2], &pts[j]) != CS_OK)
                    return CS_ERR_RANGE;
            if (k > 0)
                pts[0] = out[k - 1].p[3]; /* pieces share their end points exactly */
            cs_err_t e = cs_bezier_init(&out[k], 3, pts);
            if (e != CS_OK)
                return e;
        }
        *count = pieces;
        return CS_OK;
    }
    return CS_ERR_TOLERANCE;
}
