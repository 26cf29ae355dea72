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

/* Seed 002, solution 1: vertices on a circle, angles proportional to arc length; the
 * circle's circumference is the boundary's length, so domain units are about mm. */
static void place_arc(cs_varady_t *v, double total)
{
    double rho = total / (2 * PI), acc = 0;
    for (size_t i = 0; i < v->n; i++) {
        double beta = 2 * PI * acc / total;
        v->vert[i][0] = rho * cos(beta);
        v->vert[i][1] = rho * sin(beta);
        acc += v->len[i];
    }
}

/* Local frames of the domain sides (for the radial and central-line parametrisations). */
static void frames(cs_varady_t *v)
{
    size_t n = v->n;
    double cx = 0, cy = 0;
    for (size_t i = 0; i < n; i++) {
        cx += v->vert[i][0] / (double)n;
        cy += v->vert[i][1] / (double)n;
    }
    for (size_t i = 0; i < n; i++) {
        const double *a = v->vert[i], *b = v->vert[(i + 1) % n];
        const double *pp = v->vert[(i + n - 1) % n], *nn = v->vert[(i + 2) % n];
        double eu[2] = {b[0] - a[0], b[1] - a[1]}, l = sqrt(eu[0] * eu[0] + eu[1] * eu[1]);
        eu[0] /= l;
        eu[1] /= l;
        v->len_d[i] = l;
        double q1[2] = {pp[0] - a[0], pp[1] - a[1]}, q2[2] = {nn[0] - b[0], nn[1] - b[1]};
        double l1 = sqrt(q1[0] * q1[0] + q1[1] * q1[1]), l2 = sqrt(q2[0] * q2[0] + q2[1] * q2[1]);
        /* local (u, v) of a vector (x, y): u = x eu, v = x (-eu_y, eu_x) (inward: CCW) */
        v->w1[i][0] = (q1[0] * eu[0] + q1[1] * eu[1]) / l1;
        v->w1[i][1] = (-q1[0] * eu[1] + q1[1] * eu[0]) / l1;
        v->w2[i][0] = (q2[0] * eu[0] + q2[1] * eu[1]) / l2;
        v->w2[i][1] = (-q2[0] * eu[1] + q2[1] * eu[0]) / l2;
        /* Central line (seed 002, "Balayage de ligne centrale"): w12v = (w1v + w2v) / 2, then
         * r(1/2, dc) = c gives dc = 2 cv / (w1v + w2v) and w12u from cu. */
        double cu = (cx - a[0]) * eu[0] + (cy - a[1]) * eu[1];
        double cv = -(cx - a[0]) * eu[1] + (cy - a[1]) * eu[0];
        double dc = 2 * cv / (v->w1[i][1] + v->w2[i][1]);
        v->w12u[i] = (4 * (cu - 0.5 * l) / dc - v->w1[i][0] - v->w2[i][0]) / 2;
        /* Radial: the lines of sides i - 1 (through the origin along w1) and i + 1 (through
         * (l, 0) along w2) meet at a w1 = (l, 0) + b w2, unless parallel. */
        double det = -v->w1[i][0] * v->w2[i][1] + v->w1[i][1] * v->w2[i][0];
        if (fabs(det) < 1e-12) {
            v->rpar[i] = 1;
        } else {
            double ka = (-l * v->w2[i][1]) / det;
            v->rc[i][0] = ka * v->w1[i][0];
            v->rc[i][1] = ka * v->w1[i][1];
        }
    }
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
    v->domain = CS_VARADY_DOMAIN_ARC;
    place_arc(v, total);
    frames(v);
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

double cs_varady_corner_angle(const cs_varady_t *v, size_t i)
{
    double a[3], b[3];
    curve_d(&v->side[(i + v->n - 1) % v->n], 1, NULL, a);
    curve_d(&v->side[i], 0, NULL, b);
    double c = -(a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (norm3(a) * norm3(b));
    return acos(fmax(-1, fmin(1, c)));
}

/* Solution 2: R with sum 2 asin(L_i / 2R) = 2 pi (decreasing in R; asin x <= pi x / 2 bounds R
 * by sum L / 4), then the vertices at the accumulated central angles. */
static cs_err_t place_chords(cs_varady_t *v, double total, double out[][2])
{
    double lmax = 0;
    for (size_t i = 0; i < v->n; i++)
        lmax = fmax(lmax, v->len[i]);
    double lo = lmax / 2, hi = total / 4, f = 0;
    for (size_t i = 0; i < v->n; i++)
        f += 2 * asin(fmin(1, v->len[i] / (2 * lo)));
    if (!(hi >= lo) || f < 2 * PI)
        return CS_ERR_DEGENERATE; /* the centre would lie outside the polygon */
    for (int it = 0; it < 200 && hi - lo > 1e-14 * hi; it++) {
        double mid = (lo + hi) / 2;
        f = 0;
        for (size_t i = 0; i < v->n; i++)
            f += 2 * asin(v->len[i] / (2 * mid));
        *(f > 2 * PI ? &lo : &hi) = mid;
    }
    double r = (lo + hi) / 2, acc = 0;
    for (size_t i = 0; i < v->n; i++) {
        out[i][0] = r * cos(acc);
        out[i][1] = r * sin(acc);
        acc += 2 * asin(v->len[i] / (2 * r));
    }
    return CS_OK;
}

/* A polygon from its side lengths l and interior angles alpha (alpha[i] at vertex i, the start
 * of side i): p_0 = 0, side 0 along +x, turning left by pi - alpha at each vertex. Writes the
 * n + 1 points p_0 .. p_n (p_n = p_0 when it closes). */
static void turtle(size_t n, const double l[], const double alpha[], double p[][2])
{
    double th = 0;
    p[0][0] = p[0][1] = 0;
    for (size_t i = 0; i < n; i++) {
        if (i > 0)
            th += PI - alpha[i];
        p[i + 1][0] = p[i][0] + l[i] * cos(th);
        p[i + 1][1] = p[i][1] + l[i] * sin(th);
    }
}

/* Targets of solutions 3 and least squares: l_i = L_i, alpha_i = c_angle phi_i. */
static void targets(const cs_varady_t *v, double l[], double alpha[])
{
    double sum = 0;
    for (size_t i = 0; i < v->n; i++)
        sum += cs_varady_corner_angle(v, i);
    for (size_t i = 0; i < v->n; i++) {
        l[i] = v->len[i];
        alpha[i] = (double)(v->n - 2) * PI / sum * cs_varady_corner_angle(v, i);
    }
}

/* Solution 3: the targets' polygon, its gap e = p_0 - p_n spread as p_i += (i / n) e. */
static void place_angles(const cs_varady_t *v, double out[][2])
{
    double l[CS_VARADY_MAX_SIDES], alpha[CS_VARADY_MAX_SIDES], p[CS_VARADY_MAX_SIDES + 1][2];
    targets(v, l, alpha);
    turtle(v->n, l, alpha, p);
    double e[2] = {p[0][0] - p[v->n][0], p[0][1] - p[v->n][1]};
    for (size_t i = 0; i < v->n; i++) {
        out[i][0] = p[i][0] + (double)i / (double)v->n * e[0];
        out[i][1] = p[i][1] + (double)i / (double)v->n * e[1];
    }
}

static double det3(const double m[3][3])
{
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

/* a y = r for a 3 x 3 a, by Cramer's rule; false when singular. */
static bool solve3(const double a[3][3], const double r[3], double y[3])
{
    double det = det3(a);
    if (!(fabs(det) > 0))
        return false;
    for (int c = 0; c < 3; c++) {
        double m[3][3];
        memcpy(m, a, sizeof m);
        for (int k = 0; k < 3; k++)
            m[k][c] = r[k];
        y[c] = det3((const double(*)[3])m) / det;
    }
    return true;
}

/* Constraints of a closed polygon with sides x[0..n-1] and angles x[n..2n-1]: closure (x, y)
 * and sum alpha = (n - 2) pi. */
static void closing(size_t n, const double x[], double g[3])
{
    double p[CS_VARADY_MAX_SIDES + 1][2];
    turtle(n, x, x + n, p);
    g[0] = p[n][0];
    g[1] = p[n][1];
    g[2] = -(double)(n - 2) * PI;
    for (size_t i = 0; i < n; i++)
        g[2] += x[n + i];
}

/* Least squares: x = (l, alpha) nearest the targets x0 on {g = 0}, by Gauss-Newton steps
 * dx = (x0 - x) - J^T (J J^T)^-1 (g + J (x0 - x)) with J by central differences. */
static cs_err_t place_lsq(const cs_varady_t *v, double out[][2])
{
    size_t n = v->n, m = 2 * n;
    double x0[2 * CS_VARADY_MAX_SIDES], x[2 * CS_VARADY_MAX_SIDES];
    targets(v, x0, x0 + n);
    memcpy(x, x0, sizeof x);
    double g[3] = {1, 1, 1};
    for (int it = 0; it < 100 && fabs(g[0]) + fabs(g[1]) + fabs(g[2]) > 1e-12 * v->len[0]; it++) {
        double jac[3][2 * CS_VARADY_MAX_SIDES], r[3], a[3][3] = {{0}}, y[3];
        closing(n, x, g);
        for (size_t k = 0; k < m; k++) {
            double h = 1e-7 * (k < n ? x0[k] : 1), xp[2 * CS_VARADY_MAX_SIDES], gp[3], gm[3];
            memcpy(xp, x, sizeof xp);
            xp[k] = x[k] + h;
            closing(n, xp, gp);
            xp[k] = x[k] - h;
            closing(n, xp, gm);
            for (int c = 0; c < 3; c++)
                jac[c][k] = (gp[c] - gm[c]) / (2 * h);
        }
        for (int c = 0; c < 3; c++) {
            r[c] = g[c];
            for (size_t k = 0; k < m; k++)
                r[c] += jac[c][k] * (x0[k] - x[k]);
            for (int d = 0; d < 3; d++)
                for (size_t k = 0; k < m; k++)
                    a[c][d] += jac[c][k] * jac[d][k];
        }
        if (!solve3(a, r, y))
            return CS_ERR_DEGENERATE;
        for (size_t k = 0; k < m; k++)
            x[k] = x0[k] - (jac[0][k] * y[0] + jac[1][k] * y[1] + jac[2][k] * y[2]);
        closing(n, x, g);
    }
    if (fabs(g[0]) + fabs(g[1]) + fabs(g[2]) > 1e-9 * v->len[0])
        return CS_ERR_DEGENERATE;
    double p[CS_VARADY_MAX_SIDES + 1][2];
    turtle(n, x, x + n, p);
    for (size_t i = 0; i < n; i++) {
        if (!(x[n + i] > 0 && x[n + i] < PI) || !(x[i] > 0))
            return CS_ERR_DEGENERATE;
        out[i][0] = p[i][0];
        out[i][1] = p[i][1];
    }
    return CS_OK;
}

/* True when out[0..n-1] is a convex counter-clockwise polygon (every turn strictly left). */
static bool convex_ccw(size_t n, const double p[][2])
{
    for (size_t i = 0; i < n; i++) {
        const double *a = p[i], *b = p[(i + 1) % n], *c = p[(i + 2) % n];
        if ((b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]) <= 0)
            return false;
    }
    return true;
}

cs_err_t cs_varady_set_domain(cs_varady_t *v, cs_varady_domain_t domain)
{
    if (!v || v->n < 3)
        return CS_ERR_ARG;
    double total = 0, p[CS_VARADY_MAX_SIDES][2];
    for (size_t i = 0; i < v->n; i++)
        total += v->len[i];
    cs_err_t e = CS_OK;
    cs_varady_t w = *v;
    switch (domain) {
    case CS_VARADY_DOMAIN_ARC:
        place_arc(&w, total);
        memcpy(p, w.vert, sizeof p);
        break;
    case CS_VARADY_DOMAIN_CHORDS:
        e = place_chords(v, total, p);
        break;
    case CS_VARADY_DOMAIN_ANGLES:
        place_angles(v, p);
        break;
    case CS_VARADY_DOMAIN_LSQ:
        e = place_lsq(v, p);
        break;
    default:
        return CS_ERR_ARG;
    }
    if (e == CS_OK && !convex_ccw(v->n, p))
        e = CS_ERR_DEGENERATE;
    if (e != CS_OK)
        return e;
    memcpy(v->vert, p, sizeof p);
    v->domain = domain;
    frames(v);
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

cs_err_t cs_varady_set_scheme(cs_varady_t *v, cs_varady_blend_t blend, cs_varady_param_t param)
{
    if (!v || (blend != CS_VARADY_MU && blend != CS_VARADY_LAMBDA_KAPPA) ||
        (param != CS_VARADY_SIDE && param != CS_VARADY_RADIAL && param != CS_VARADY_CENTRE &&
         param != CS_VARADY_BIQUADRATIC))
        return CS_ERR_ARG;
    v->blend = blend;
    v->param = param;
    return CS_OK;
}

/* Central-line sweep for side i (seed 002): f(s) = (u0 - l s) (w1v (1 - s) + w2v s)
 * - v0 (w1u (1 - s)^2 + 2 w12u (1 - s) s + w2u s^2), zero where the seed's two expressions of d0
 * agree, i.e. where r(s, d0) = (u0, v0). */
static double centre_f(const cs_varady_t *v, size_t i, double u0, double v0, double s)
{
    const double *w1 = v->w1[i], *w2 = v->w2[i];
    double l = v->len_d[i], m = 1 - s;
    return (u0 - l * s) * (w1[1] * m + w2[1] * s) -
           v0 * (w1[0] * m * m + 2 * v->w12u[i] * m * s + w2[0] * s * s);
}

/* Its root in [0, 1] by bisection: inside the domain f(0) >= 0 (side i - 1's side) and
 * f(1) <= 0. Outside that wedge s is clamped to the end where |f| is smaller. */
static double centre_s(const cs_varady_t *v, size_t i, double u0, double v0)
{
    double f0 = centre_f(v, i, u0, v0, 0), f1 = centre_f(v, i, u0, v0, 1);
    if ((f0 > 0 && f1 > 0) || (f0 < 0 && f1 < 0))
        return fabs(f0) <= fabs(f1) ? 0 : 1;
    double lo = 0, hi = 1;
    for (int k = 0; k < 64; k++) {
        double m = 0.5 * (lo + hi);
        if (m <= lo || m >= hi)
            break;
        if ((centre_f(v, i, u0, v0, m) >= 0) == (f0 >= 0))
            lo = m;
        else
            hi = m;
    }
    return f0 == 0 ? 0 : f1 == 0 ? 1 : 0.5 * (lo + hi);
}

/* The centroid of the domain's vertices. */
static void centroid(const cs_varady_t *v, double ce[2])
{
    ce[0] = ce[1] = 0;
    for (size_t k = 0; k < v->n; k++)
        for (int x = 0; x < 2; x++)
            ce[x] += v->vert[k][x] / (double)v->n;
}

/* The biquadratic net of side i (cs_varady.h, CS_VARADY_BIQUADRATIC): C[a][b], a along s. */
static void biq_net(const cs_varady_t *v, size_t i, double c[3][3][2])
{
    size_t n = v->n;
    const double *pm = v->vert[(i + n - 1) % n], *p0 = v->vert[i], *p1 = v->vert[(i + 1) % n],
                 *p2 = v->vert[(i + 2) % n];
    double ce[2];
    centroid(v, ce);
    for (int x = 0; x < 2; x++) {
        c[0][0][x] = p0[x];
        c[1][0][x] = (p0[x] + p1[x]) / 2;
        c[2][0][x] = p1[x];
        c[0][2][x] = pm[x];
        c[1][2][x] = n == 3 ? pm[x] : ce[x]; /* a triangle: the row t = 2 is its apex */
        c[2][2][x] = p2[x];
        for (int a = 0; a < 3; a++)
            c[a][1][x] = (c[a][0][x] + c[a][2][x]) / 2;
    }
}

/* The map at (s, t) and its partial derivatives (Bernstein B2 and their derivatives). */
static void biq_map(const double c[3][3][2], double s, double t, double out[2], double ds[2],
                    double dt[2])
{
    double bs[3] = {(1 - s) * (1 - s), 2 * s * (1 - s), s * s};
    double bt[3] = {(1 - t) * (1 - t), 2 * t * (1 - t), t * t};
    double es[3] = {-2 * (1 - s), 2 - 4 * s, 2 * s}, et[3] = {-2 * (1 - t), 2 - 4 * t, 2 * t};
    for (int x = 0; x < 2; x++) {
        out[x] = ds[x] = dt[x] = 0;
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) {
                out[x] += bs[a] * bt[b] * c[a][b][x];
                ds[x] += es[a] * bt[b] * c[a][b][x];
                dt[x] += bs[a] * et[b] * c[a][b][x];
            }
    }
}

/* (s, t) with map(s, t) = (x, y) by Newton-Raphson from (s, t) (at most 50 steps, to 1e-13 of
 * the side's length); the last iterate when the Jacobian is singular. */
static void biq_invert(const cs_varady_t *v, size_t i, double x, double y, double *s, double *t)
{
    double c[3][3][2];
    biq_net(v, i, c);
    for (int it = 0; it < 50; it++) {
        double m[2], ds[2], dt[2];
        biq_map((const double(*)[3][2])c, *s, *t, m, ds, dt);
        double fx = m[0] - x, fy = m[1] - y, det = ds[0] * dt[1] - ds[1] * dt[0];
        if (fabs(fx) + fabs(fy) < 1e-13 * v->len_d[i] || !(fabs(det) > 0))
            break;
        *s -= (dt[1] * fx - dt[0] * fy) / det;
        *t -= (-ds[1] * fx + ds[0] * fy) / det;
    }
}

/* Distance from the vertices' centroid to side i's line (the biquadratic d scale). */
static double centre_height(const cs_varady_t *v, size_t i)
{
    double ce[2];
    centroid(v, ce);
    return side_dist(v, i, ce[0], ce[1]);
}

void cs_varady_params(const cs_varady_t *v, double x, double y, double s[], double d[])
{
    size_t n = v->n;
    double dist[CS_VARADY_MAX_SIDES];
    for (size_t i = 0; i < n; i++)
        dist[i] = side_dist(v, i, x, y);
    for (size_t i = 0; i < n; i++) {
        const double *a = v->vert[i], *b = v->vert[(i + 1) % n];
        double l = v->len_d[i], eu[2] = {(b[0] - a[0]) / l, (b[1] - a[1]) / l};
        double u0 = (x - a[0]) * eu[0] + (y - a[1]) * eu[1];
        double v0 = -(x - a[0]) * eu[1] + (y - a[1]) * eu[0];
        if (v->param == CS_VARADY_SIDE || v->param == CS_VARADY_BIQUADRATIC) {
            double dp = dist[(i + n - 1) % n], dn = dist[(i + 1) % n];
            s[i] = dp + dn != 0 ? dp / (dp + dn) : 0.5;
            d[i] = dist[i];
            if (v->param == CS_VARADY_BIQUADRATIC) {
                double h = centre_height(v, i), t = d[i] / h;
                biq_invert(v, i, x, y, &s[i], &t);
                d[i] = t * h;
            }
        } else if (v->param == CS_VARADY_RADIAL) {
            /* e: where the ray from the centre rc (or along w1) through (u0, v0) meets v = 0. */
            double eu0, len;
            if (v->rpar[i]) {
                const double *w = v->w1[i];
                eu0 = u0 - v0 * w[0] / w[1];
                len = fabs(v0 / w[1]);
            } else {
                const double *c = v->rc[i];
                double den = c[1] - v0;
                if (fabs(den) < 1e-12 * l) { /* at the centre itself: any ray (blend is 0) */
                    eu0 = 0.5 * l;
                } else {
                    double t = c[1] / den;
                    eu0 = c[0] + t * (u0 - c[0]);
                }
                len = sqrt((u0 - eu0) * (u0 - eu0) + v0 * v0);
            }
            s[i] = eu0 / l;
            d[i] = v0 < 0 ? -len : len;
        } else {
            double si = centre_s(v, i, u0, v0);
            double den = v->w1[i][1] * (1 - si) + v->w2[i][1] * si;
            s[i] = si;
            d[i] = v0 / den;
        }
    }
}

void cs_varady_blends(size_t n, const double d[], double lambda[], double kappa[], double mu[])
{
    /* The blends are ratios of products of equal degree: scale the distances to about 1 so
     * the products of up to 14 factors stay far from overflow and underflow. */
    double big = 0, q[CS_VARADY_MAX_SIDES];
    for (size_t i = 0; i < n; i++)
        big = fmax(big, fabs(d[i]));
    for (size_t i = 0; i < n; i++)
        q[i] = big > 0 ? (d[i] / big) * (d[i] / big) : 0;
    /* D_{i-1,i} = prod_{j != i-1, i} q_j and D_i = prod_{j != i} q_j. */
    double Dc[CS_VARADY_MAX_SIDES], Ds[CS_VARADY_MAX_SIDES], sc = 0, ss = 0;
    for (size_t i = 0; i < n; i++) {
        size_t im = (i + n - 1) % n;
        Dc[i] = 1;
        Ds[i] = 1;
        for (size_t j = 0; j < n; j++) {
            if (j != i)
                Ds[i] *= q[j];
            if (j != i && j != im)
                Dc[i] *= q[j];
        }
        sc += Dc[i];
        ss += Ds[i];
    }
    for (size_t i = 0; i < n; i++) {
        if (lambda)
            lambda[i] = sc > 0 ? (Dc[i] + Dc[(i + 1) % n]) / sc : 0;
        if (kappa)
            kappa[i] = sc > 0 ? Dc[i] / sc : 0;
        if (mu)
            mu[i] = ss > 0 ? Ds[i] / ss : 0;
    }
}

/* The corner nearest to (x, y): the surface's value where the blends are undefined. */
static void nearest_corner(const cs_varady_t *v, double x, double y, double out[3])
{
    size_t best = 0;
    double bd = HUGE_VAL;
    for (size_t i = 0; i < v->n; i++) {
        double dx = x - v->vert[i][0], dy = y - v->vert[i][1];
        if (dx * dx + dy * dy < bd) {
            bd = dx * dx + dy * dy;
            best = i;
        }
    }
    curve_d(&v->side[best], 0, out, NULL);
}

cs_err_t cs_varady_set_tangents(cs_varady_t *v, const cs_bezier_t *tan)
{
    if (!v)
        return CS_ERR_ARG;
    for (size_t i = 0; tan && i < v->n; i++) {
        if (tan[i].rational)
            return CS_ERR_UNSUPPORTED;
        if (tan[i].degree < 1 || tan[i].degree > 3)
            return CS_ERR_DEGREE;
    }
    v->user_tan = tan != NULL;
    for (size_t i = 0; tan && i < v->n; i++)
        v->tan[i] = tan[i];
    return CS_OK;
}

void cs_varady_set_twists(cs_varady_t *v, const double (*twist)[3])
{
    for (size_t i = 0; i < v->n; i++)
        for (int k = 0; k < 3; k++)
            v->twist[i][k] = twist ? twist[i][k] : 0;
}

/* Cross-boundary tangent T_i(s): the user's curve, or t0 -> t1 linearly. */
static void tangent(const cs_varady_t *v, size_t i, double s, double out[3])
{
    if (v->user_tan) {
        curve_d(&v->tan[i], s, out, NULL);
        return;
    }
    for (int k = 0; k < 3; k++)
        out[k] = (1 - s) * v->t0[i][k] + s * v->t1[i][k];
}

/* Ribbon R_i(s, d) = P_i(s) + d T_i(s). */
static void ribbon(const cs_varady_t *v, size_t i, double s, double d, double out[3])
{
    double p[3], t[3];
    curve_d(&v->side[i], s, p, NULL);
    tangent(v, i, s, t);
    for (int k = 0; k < 3; k++)
        out[k] = p[k] + d * t[k];
}

void cs_varady_eval(const cs_varady_t *v, double x, double y, double out[3])
{
    size_t n = v->n;
    double s[CS_VARADY_MAX_SIDES], d[CS_VARADY_MAX_SIDES];
    double lambda[CS_VARADY_MAX_SIDES], kappa[CS_VARADY_MAX_SIDES], mu[CS_VARADY_MAX_SIDES];
    cs_varady_params(v, x, y, s, d);
    out[0] = out[1] = out[2] = 0;
    if (v->blend == CS_VARADY_MU) {
        cs_varady_blends(n, d, NULL, NULL, mu);
        double sum = 0;
        for (size_t i = 0; i < n; i++)
            sum += mu[i];
        if (!(sum > 0.5)) { /* at a vertex (two distances zero): the corner itself */
            nearest_corner(v, x, y, out);
            return;
        }
        for (size_t i = 0; i < n; i++) {
            if (mu[i] == 0)
                continue;
            double r[3];
            ribbon(v, i, s[i], d[i], r);
            for (int k = 0; k < 3; k++)
                out[k] += mu[i] * r[k];
        }
        return;
    }
    cs_varady_blends(n, d, lambda, kappa, NULL);
    double sum = 0;
    for (size_t i = 0; i < n; i++)
        sum += kappa[i];
    if (!(sum > 0.5)) {
        nearest_corner(v, x, y, out);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        if (lambda[i] != 0) {
            double r[3];
            ribbon(v, i, s[i], d[i], r);
            for (int k = 0; k < 3; k++)
                out[k] += lambda[i] * r[k];
        }
        if (kappa[i] != 0) {
            /* Q_i = P_i(0) + d_{i-1} T_{i-1}(1) + d_i T_i(0) + d_{i-1} d_i W_i (W_i zero by
             * default, seed 000's choice). */
            size_t im = (i + n - 1) % n;
            double p[3], ta[3], tb[3];
            curve_d(&v->side[i], 0, p, NULL);
            tangent(v, im, 1, ta);
            tangent(v, i, 0, tb);
            for (int k = 0; k < 3; k++)
                out[k] -= kappa[i] *
                          (p[k] + d[im] * ta[k] + d[i] * tb[k] + d[im] * d[i] * v->twist[i][k]);
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

void cs_varady_quad_point(const cs_varady_t *v, size_t i, double a, double b, double out[2])
{
    size_t n = v->n;
    double c[2] = {0, 0};
    for (size_t k = 0; k < n; k++) {
        c[0] += v->vert[k][0] / (double)n;
        c[1] += v->vert[k][1] / (double)n;
    }
    const double *pp = v->vert[(i + n - 1) % n], *p = v->vert[i], *pn = v->vert[(i + 1) % n];
    double m0[2] = {0.5 * (pp[0] + p[0]), 0.5 * (pp[1] + p[1])};
    double m1[2] = {0.5 * (p[0] + pn[0]), 0.5 * (p[1] + pn[1])};
    /* X(0,0) = c, X(1,0) = m_{i-1}, X(1,1) = p_i, X(0,1) = m_i */
    for (int k = 0; k < 2; k++)
        out[k] =
            (1 - a) * (1 - b) * c[k] + a * (1 - b) * m0[k] + a * b * p[k] + (1 - a) * b * m1[k];
}

static void quad_eval(const cs_varady_t *v, size_t i, double a, double b, double out[3])
{
    double x[2];
    cs_varady_quad_point(v, i, a, b, x);
    cs_varady_eval(v, x[0], x[1], out);
}

/* Hermite data of quad i at (a, b): point, derivatives in a and b, twist (central differences;
 * the surface is extrapolated a little beyond the domain's sides). */
static void quad_hermite(const cs_varady_t *v, size_t i, double a, double b, double pt[3],
                         double da[3], double db[3], double dab[3])
{
    const double h = 1e-5, g = 1e-4;
    double p0[3], p1[3], q0[3], q1[3], r[4][3];
    quad_eval(v, i, a, b, pt);
    quad_eval(v, i, a - h, b, p0);
    quad_eval(v, i, a + h, b, p1);
    quad_eval(v, i, a, b - h, q0);
    quad_eval(v, i, a, b + h, q1);
    quad_eval(v, i, a + g, b + g, r[0]);
    quad_eval(v, i, a + g, b - g, r[1]);
    quad_eval(v, i, a - g, b + g, r[2]);
    quad_eval(v, i, a - g, b - g, r[3]);
    for (int k = 0; k < 3; k++) {
        da[k] = (p1[k] - p0[k]) / (2 * h);
        db[k] = (q1[k] - q0[k]) / (2 * h);
        dab[k] = (r[0][k] - r[1][k] - r[2][k] + r[3][k]) / (4 * g * g);
    }
}

/* Bicubic point in double from the control net (mm). */
static void patch_point(const cs_patch_t *p, double u, double w, double out[3])
{
    double bu[4], bw[4];
    for (int k = 0; k <= 3; k++) {
        static const double c[4] = {1, 3, 3, 1};
        bu[k] = c[k] * pow(u, k) * pow(1 - u, 3 - k);
        bw[k] = c[k] * pow(w, k) * pow(1 - w, 3 - k);
    }
    out[0] = out[1] = out[2] = 0;
    for (int i = 0; i <= 3; i++)
        for (int j = 0; j <= 3; j++) {
            out[0] += bu[i] * bw[j] * cs_conv_pos_to_mm(p->p[i][j].x);
            out[1] += bu[i] * bw[j] * cs_conv_pos_to_mm(p->p[i][j].y);
            out[2] += bu[i] * bw[j] * cs_conv_pos_to_mm(p->p[i][j].z);
        }
}

/* One cell of quad i: [a0, a0 + w] x [b0, b0 + w] as a Hermite bicubic, and its largest
 * distance to the surface at 9 x 9 samples. */
static cs_err_t fit_cell(const cs_varady_t *v, size_t i, double a0, double b0, double w,
                         cs_patch_t *out, double *err)
{
    cs_patch_hermite_t hm;
    for (int ca = 0; ca < 2; ca++)
        for (int cb = 0; cb < 2; cb++) {
            double pt[3], da[3], db[3], dab[3];
            quad_hermite(v, i, a0 + ca * w, b0 + cb * w, pt, da, db, dab);
            /* per unit of the cell's own parameters: x w, the twist x w^2 */
            cs_err_t e = cs_conv_mm_to_vec(pt[0], pt[1], pt[2], &hm.p[ca][cb]);
            if (e == CS_OK)
                e = cs_conv_mm_to_vec(da[0] * w, da[1] * w, da[2] * w, &hm.pu[ca][cb]);
            if (e == CS_OK)
                e = cs_conv_mm_to_vec(db[0] * w, db[1] * w, db[2] * w, &hm.pv[ca][cb]);
            if (e == CS_OK)
                e = cs_conv_mm_to_vec(dab[0] * w * w, dab[1] * w * w, dab[2] * w * w,
                                      &hm.puv[ca][cb]);
            if (e != CS_OK)
                return CS_ERR_RANGE;
        }
    cs_err_t e = cs_patch_from_hermite(out, &hm);
    if (e != CS_OK)
        return e;
    *err = 0;
    for (int sa = 0; sa <= 8; sa++)
        for (int sb = 0; sb <= 8; sb++) {
            double q[3], r[3];
            patch_point(out, sa / 8.0, sb / 8.0, q);
            quad_eval(v, i, a0 + w * sa / 8.0, b0 + w * sb / 8.0, r);
            double d[3] = {q[0] - r[0], q[1] - r[1], q[2] - r[2]};
            *err = fmax(*err, norm3(d));
        }
    return CS_OK;
}

cs_err_t cs_varady_patches(const cs_varady_t *v, double tol_mm, cs_patch_t *out,
                           cs_varady_cell_t *cells, size_t max, size_t *count, double *err_mm)
{
    if (!v || !out || !count || !(tol_mm > 0))
        return CS_ERR_ARG;
    /* Quadtree per quad, depth-first: a cell that misses tol is split in four. */
    struct {
        double a, b, w;
    } stack[4 * CS_VARADY_MAX_DEPTH + 4];
    size_t c = 0;
    double worst = 0;
    for (size_t i = 0; i < v->n; i++) {
        size_t sp = 0;
        stack[sp].a = 0;
        stack[sp].b = 0;
        stack[sp].w = 1;
        sp++;
        while (sp > 0) {
            sp--;
            double a = stack[sp].a, b = stack[sp].b, w = stack[sp].w, err;
            if (c == max)
                return CS_ERR_FULL;
            cs_err_t e = fit_cell(v, i, a, b, w, &out[c], &err);
            if (e != CS_OK)
                return e;
            if (err <= tol_mm) {
                worst = fmax(worst, err);
                if (cells)
                    cells[c] = (cs_varady_cell_t){i, a, b, w};
                c++;
                continue;
            }
            if (w <= 1.0 / (1 << CS_VARADY_MAX_DEPTH))
                return CS_ERR_TOLERANCE;
            double h = w / 2;
            for (int k = 3; k >= 0; k--) { /* pushed in reverse: popped row by row */
                stack[sp].a = a + h * (k % 2);
                stack[sp].b = b + h * (k / 2);
                stack[sp].w = h;
                sp++;
            }
        }
    }
    *count = c;
    if (err_mm)
        *err_mm = worst;
    return CS_OK;
}
