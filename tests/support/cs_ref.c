/* cs_ref: double-precision reference for curve tracing (see cs_ref.h). Everything here is plain,
 * slow and obvious on purpose: it is what the fixed-point tracers are judged against. */
#include "cs_ref.h"

#include <math.h>
#include <stdlib.h>

#define REF_PIECE_SAMPLES 64   /* curve samples per piece for the curve -> chord maximum */
#define REF_CHORD_SAMPLES 16   /* chord points for the chord -> curve maximum */
#define REF_POLY_SAMPLES  32   /* piece polyline the chord points are measured against */
#define REF_GRID          8192 /* parameter grid used to place vertices on the curve */

static cs_ref_vec_t vsub(cs_ref_vec_t a, cs_ref_vec_t b)
{
    cs_ref_vec_t r = {a.x - b.x, a.y - b.y, a.z - b.z};
    return r;
}

static double vdot(cs_ref_vec_t a, cs_ref_vec_t b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

cs_ref_vec_t cs_ref_from_pos(const cs_vec3_t *p)
{
    cs_ref_vec_t r = {p->x * CS_REF_LSB_MM, p->y * CS_REF_LSB_MM, p->z * CS_REF_LSB_MM};
    return r;
}

cs_ref_vec_t cs_ref_eval(const cs_bezier_t *c, double t)
{
    double h[CS_BEZIER_MAX_POINTS][4];
    unsigned n = c->degree;
    for (unsigned i = 0; i <= n; i++) {
        double w = c->rational ? c->w[i] / (double)CS_WEIGHT_ONE : 1.0;
        cs_ref_vec_t p = cs_ref_from_pos(&c->p[i]);
        h[i][0] = w * p.x;
        h[i][1] = w * p.y;
        h[i][2] = w * p.z;
        h[i][3] = w;
    }
    for (unsigned r = 1; r <= n; r++)
        for (unsigned i = 0; i + r <= n; i++)
            for (unsigned k = 0; k < 4; k++)
                h[i][k] = (1.0 - t) * h[i][k] + t * h[i + 1][k];
    cs_ref_vec_t out = {h[0][0] / h[0][3], h[0][1] / h[0][3], h[0][2] / h[0][3]};
    return out;
}

double cs_ref_dist(cs_ref_vec_t a, cs_ref_vec_t b)
{
    cs_ref_vec_t d = vsub(a, b);
    return sqrt(vdot(d, d));
}

double cs_ref_dist_point_segment(cs_ref_vec_t p, cs_ref_vec_t a, cs_ref_vec_t b)
{
    cs_ref_vec_t d = vsub(b, a), v = vsub(p, a);
    double dd = vdot(d, d);
    if (dd == 0.0)
        return sqrt(vdot(v, v));
    double u = vdot(v, d) / dd;
    if (u <= 0.0)
        return sqrt(vdot(v, v));
    if (u >= 1.0)
        return cs_ref_dist(p, b);
    cs_ref_vec_t q = {a.x + u * d.x - p.x, a.y + u * d.y - p.y, a.z + u * d.z - p.z};
    return sqrt(vdot(q, q));
}

/* Golden-section search for the maximum (sign = 1) or minimum (sign = -1) of f on [lo, hi]. */
typedef double (*ref_fn)(const void *ctx, double t);

static double golden(ref_fn f, const void *ctx, double lo, double hi, double sign, double *arg)
{
    const double g = 0.6180339887498949;
    double a = lo, b = hi;
    double x1 = b - g * (b - a), x2 = a + g * (b - a);
    double f1 = sign * f(ctx, x1), f2 = sign * f(ctx, x2);
    for (int i = 0; i < 60; i++) {
        if (f1 > f2) {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = sign * f(ctx, x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = sign * f(ctx, x2);
        }
    }
    double best = f1 > f2 ? x1 : x2;
    double fb = sign * f(ctx, best);
    double fl = sign * f(ctx, lo), fh = sign * f(ctx, hi);
    if (fl > fb) {
        best = lo;
        fb = fl;
    }
    if (fh > fb) {
        best = hi;
        fb = fh;
    }
    if (arg)
        *arg = best;
    return sign * fb;
}

typedef struct {
    const cs_bezier_t *c;
    cs_ref_vec_t a, b, p;
} ref_ctx_t;

static double curve_to_chord(const void *ctx, double t)
{
    const ref_ctx_t *k = ctx;
    return cs_ref_dist_point_segment(cs_ref_eval(k->c, t), k->a, k->b);
}

static double curve_to_point(const void *ctx, double t)
{
    const ref_ctx_t *k = ctx;
    return cs_ref_dist(cs_ref_eval(k->c, t), k->p);
}

/* Curve piece -> chord maximum: sampled, then refined by golden section around the top sample. */
static double piece_to_chord(const cs_bezier_t *c, double t0, double t1, cs_ref_vec_t a,
                             cs_ref_vec_t b)
{
    ref_ctx_t k = {c, a, b, a};
    /* Curve -> chord: sample, then refine around the largest sample. */
    double best = 0.0;
    int kbest = 0;
    for (int i = 0; i <= REF_PIECE_SAMPLES; i++) {
        double t = t0 + (t1 - t0) * i / REF_PIECE_SAMPLES;
        double d = curve_to_chord(&k, t);
        if (d > best) {
            best = d;
            kbest = i;
        }
    }
    if (t1 > t0) {
        double lo = t0 + (t1 - t0) * (kbest > 0 ? kbest - 1 : 0) / REF_PIECE_SAMPLES;
        double hi = t0 + (t1 - t0) * (kbest < REF_PIECE_SAMPLES ? kbest + 1 : REF_PIECE_SAMPLES) /
                             REF_PIECE_SAMPLES;
        double r = golden(curve_to_chord, &k, lo, hi, 1.0, NULL);
        if (r > best)
            best = r;
    }
    return best;
}

double cs_ref_chord_piece_deviation(const cs_bezier_t *c, double t0, double t1, cs_ref_vec_t a,
                                    cs_ref_vec_t b)
{
    double best = piece_to_chord(c, t0, t1, a, b);
    /* Chord -> curve: each chord point to a fine polyline through the piece (the polyline is
     * within 1/32^2 of the piece's own sag, i.e. about tol/1000 for a chord near the tolerance). */
    static const int np = REF_POLY_SAMPLES;
    cs_ref_vec_t poly[REF_POLY_SAMPLES + 1];
    for (int i = 0; i <= np; i++)
        poly[i] = cs_ref_eval(c, t0 + (t1 - t0) * i / np);
    for (int m = 0; m <= REF_CHORD_SAMPLES; m++) {
        double u = (double)m / REF_CHORD_SAMPLES;
        cs_ref_vec_t q = {a.x + u * (b.x - a.x), a.y + u * (b.y - a.y), a.z + u * (b.z - a.z)};
        double dmin = HUGE_VAL;
        for (int i = 0; i < np && dmin > 0.0; i++) {
            double d = cs_ref_dist_point_segment(q, poly[i], poly[i + 1]);
            if (d < dmin)
                dmin = d;
        }
        if (dmin > best)
            best = dmin;
    }
    return best;
}

/* First parameter t >= from whose curve point is within thr of p; -1 if none. */
static double place_vertex(const cs_bezier_t *c, cs_ref_vec_t p, double from, double thr)
{
    ref_ctx_t k = {c, p, p, p};
    const double g = 1.0 / REF_GRID;
    double a = from;
    cs_ref_vec_t pa = cs_ref_eval(c, a);
    if (cs_ref_dist(pa, p) <= thr)
        return a;
    while (a < 1.0) {
        double b = a + g < 1.0 ? a + g : 1.0;
        cs_ref_vec_t pb = cs_ref_eval(c, b);
        /* The cell's curve is within about its chord of both ends (cells are tiny), so only a
         * cell whose start is close to p, relative to the cell length, can hold it. */
        double cell = cs_ref_dist(pa, pb);
        if (cs_ref_dist(pa, p) <= 3.0 * cell + thr || cs_ref_dist(pb, p) <= 3.0 * cell + thr) {
            double lo = a - g > from ? a - g : from;
            double hi = b + g < 1.0 ? b + g : 1.0;
            double t;
            double d = golden(curve_to_point, &k, lo, hi, -1.0, &t);
            if (d <= thr) {
                /* The first window may cut the valley of the nearest point: walk on while the
                 * distance keeps falling, then refine around the lowest grid point. */
                double tc = t, dc = d;
                for (;;) {
                    double tn = tc + g < 1.0 ? tc + g : 1.0;
                    double dn = cs_ref_dist(cs_ref_eval(c, tn), p);
                    if (tn <= tc || dn >= dc)
                        break;
                    tc = tn;
                    dc = dn;
                }
                double l2 = tc - g > from ? tc - g : from, h2 = tc + g < 1.0 ? tc + g : 1.0;
                d = golden(curve_to_point, &k, l2, h2, -1.0, &t);
                return d <= dc ? t : tc;
            }
        }
        a = b;
        pa = pb;
    }
    return -1.0;
}

/* Places every vertex; ts[i] is the parameter of v[i]. Returns false if one cannot be placed. */
static bool place_all(const cs_bezier_t *c, const cs_vec3_t *v, size_t n, double *ts)
{
    const double thr = 2.0 * CS_REF_LSB_MM;
    double from = 0.0;
    for (size_t i = 0; i < n; i++) {
        cs_ref_vec_t p = cs_ref_from_pos(&v[i]);
        double t;
        if (i + 1 == n) {
            t = 1.0;
            if (cs_ref_dist(cs_ref_eval(c, 1.0), p) > thr)
                return false;
        } else {
            t = place_vertex(c, p, from, thr);
            if (t < 0.0)
                return false;
        }
        ts[i] = t;
        from = t;
    }
    return true;
}

void cs_ref_measure(const cs_bezier_t *c, const cs_vec3_t *v, size_t n, double *max_dev,
                    double *max_vertex_err)
{
    double *ts = malloc((n ? n : 1) * sizeof *ts);
    if (!ts)
        abort();
    double worst = 0.0, verr = 0.0;
    if (n == 0 || !place_all(c, v, n, ts)) {
        worst = verr = HUGE_VAL;
    } else {
        cs_ref_vec_t a = cs_ref_from_pos(&c->p[0]);
        double t0 = 0.0;
        for (size_t i = 0; i < n; i++) {
            cs_ref_vec_t b = cs_ref_from_pos(&v[i]);
            double d = cs_ref_chord_piece_deviation(c, t0, ts[i], a, b);
            if (d > worst)
                worst = d;
            d = cs_ref_dist(cs_ref_eval(c, ts[i]), b);
            if (d > verr)
                verr = d;
            a = b;
            t0 = ts[i];
        }
    }
    free(ts);
    if (max_dev)
        *max_dev = worst;
    if (max_vertex_err)
        *max_vertex_err = verr;
}

double cs_ref_max_deviation(const cs_bezier_t *c, const cs_vec3_t *v, size_t n)
{
    double d;
    cs_ref_measure(c, v, n, &d, NULL);
    return d;
}

double cs_ref_max_vertex_error(const cs_bezier_t *c, const cs_vec3_t *v, size_t n)
{
    double e;
    cs_ref_measure(c, v, n, NULL, &e);
    return e;
}

/* For a chord whose end points are exact curve points the piece's projection onto the chord
 * line covers the chord, so chord -> curve <= curve -> chord: one way suffices here. */
static double chord_dev(const cs_bezier_t *c, double t0, double t1)
{
    return piece_to_chord(c, t0, t1, cs_ref_eval(c, t0), cs_ref_eval(c, t1));
}

size_t cs_ref_greedy_count(const cs_bezier_t *c, double tol)
{
    size_t count = 0;
    double t0 = 0.0;
    while (t0 < 1.0) {
        count++;
        if (chord_dev(c, t0, 1.0) <= tol)
            break;
        double lo = t0, hi = 1.0;
        for (int i = 0; i < 40; i++) {
            double mid = 0.5 * (lo + hi);
            if (chord_dev(c, t0, mid) <= tol)
                lo = mid;
            else
                hi = mid;
        }
        if (lo <= t0) /* cannot advance in double: give up counting (never for sane input) */
            return (size_t)-1;
        t0 = lo;
    }
    return count;
}

/* Largest distance (mm) of a vertex from a curve lying on the line y = P0.y (a collinear
 * fold): exact, the curve covers the x range between its extreme x on [0, 1] (sampled finely
 * enough for its own extremes, as cs_ref_eval is exact in double). cs_ref_measure places a
 * vertex on the first piece of curve within 2 LSB after the previous one, which on a curve
 * that retraces itself may be the outgoing branch for a vertex of the returning one. */
double cs_ref_fold_vertex_error(const cs_bezier_t *c, const cs_vec3_t *verts, size_t n)
{
    double lo = INFINITY, hi = -INFINITY;
    for (int k = 0; k <= 100000; k++) {
        double x = cs_ref_eval(c, k / 100000.0).x / CS_REF_LSB_MM;
        lo = fmin(lo, x);
        hi = fmax(hi, x);
    }
    double worst = 0;
    for (size_t i = 0; i < n; i++) {
        double x = verts[i].x, dy = fabs((double)verts[i].y - c->p[0].y);
        double dx = x < lo ? lo - x : x > hi ? x - hi : 0;
        worst = fmax(worst, hypot(dx, dy));
    }
    return worst * CS_REF_LSB_MM;
}

bool cs_ref_collinear_x(const cs_bezier_t *c)
{
    for (unsigned i = 1; i <= c->degree; i++)
        if (c->p[i].y != c->p[0].y)
            return false;
    return true;
}
