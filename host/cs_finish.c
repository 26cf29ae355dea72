/* cs_finish: ball-end finishing passes over a bicubic patch (see cs_finish.h).
 *
 * Scallop geometry. A ball of radius R touching the surface at P has its centre at C = P + R N.
 * Between two passes the material left over a surface point S is the distance along N(S) to
 * the first ball the normal line enters; the scallop is its largest value over the strip. On a
 * flat surface with passes w apart this is R - sqrt(R^2 - w^2 / 4), so w = 2 sqrt(2 R H - H^2)
 * gives H; concave surfaces leave more, convex less, hence the measured check. */
#include "cs_finish.h"

#include <math.h>
#include <stdlib.h>

#include "cs_conv.h"
#include "cs_trace.h"

#define Q30          1073741824.0
#define PASS_MAX_LOG 20   /* at most 2^20 chords per pass */
#define NU_CHECK     17   /* u samples of the scallop check while planning */
#define NS_CHECK     8    /* samples across the strip */
#define TARGET       0.9  /* planned scallop, fraction of H */
#define SHRINK       0.85 /* step reduction while the measured scallop is too high */

/* C(n, k) for n <= CS_PATCH_MAX_DEGREE (exact in int64). */
static int64_t binomial(unsigned n, unsigned k)
{
    int64_t c = 1;
    for (unsigned i = 1; i <= k; i++)
        c = c * (int64_t)(n - k + i) / (int64_t)i;
    return c;
}

static double bern(int n, int k, double t)
{
    if (k < 0 || k > n)
        return 0;
    return (double)binomial((unsigned)n, (unsigned)k) * pow(t, k) * pow(1 - t, n - k);
}

/* d-th derivative of B_k^n at t (d = 0..2). */
static double dbern(int n, int k, double t, int d)
{
    if (d == 0)
        return bern(n, k, t);
    if (n == 0)
        return 0;
    return n * (dbern(n - 1, k - 1, t, d - 1) - dbern(n - 1, k, t, d - 1));
}

/* Derivative d^(du+dv) P / du^du dv^dv at (u, v), mm. */
static void deriv(const cs_patch_t *p, double u, double v, int du, int dv, double out[3])
{
    out[0] = out[1] = out[2] = 0;
    for (int i = 0; i <= p->deg_u; i++)
        for (int j = 0; j <= p->deg_v; j++) {
            double b = dbern(p->deg_u, i, u, du) * dbern(p->deg_v, j, v, dv);
            out[0] += b * cs_conv_pos_to_mm(p->p[i][j].x);
            out[1] += b * cs_conv_pos_to_mm(p->p[i][j].y);
            out[2] += b * cs_conv_pos_to_mm(p->p[i][j].z);
        }
}

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void crossd(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

bool cs_finish_eval(const cs_patch_t *p, double u, double v, double pt[3], double n[3])
{
    if (pt)
        deriv(p, u, v, 0, 0, pt);
    if (!n)
        return true;
    double pu[3], pv[3];
    deriv(p, u, v, 1, 0, pu);
    deriv(p, u, v, 0, 1, pv);
    crossd(pu, pv, n);
    double l = sqrt(dot(n, n)), scale = sqrt(dot(pu, pu) * dot(pv, pv));
    if (!(l > 1e-12 * scale) || l == 0) {
        /* On a collapsed edge: the limit from inside, as cs_patch_normal (seed 004 leaves the
         * normal undefined there). */
        double e = 1e-7, uu = u < 0.5 ? u + e : u - e, vv = v < 0.5 ? v + e : v - e;
        bool on_u = u == 0 || u == 1, on_v = v == 0 || v == 1;
        deriv(p, on_u ? uu : u, on_v ? vv : v, 1, 0, pu);
        deriv(p, on_u ? uu : u, on_v ? vv : v, 0, 1, pv);
        crossd(pu, pv, n);
        l = sqrt(dot(n, n));
        if (!(l > 0))
            return false;
    }
    n[0] /= l;
    n[1] /= l;
    n[2] /= l;
    return true;
}

/* Largest principal curvature towards the normal (1/mm; > 0 where the surface is concave
 * seen from the tool side), from the fundamental forms. */
static double concave_curvature(const cs_patch_t *p, double u, double v)
{
    double pu[3], pv[3], puu[3], puv[3], pvv[3], n[3];
    deriv(p, u, v, 1, 0, pu);
    deriv(p, u, v, 0, 1, pv);
    deriv(p, u, v, 2, 0, puu);
    deriv(p, u, v, 1, 1, puv);
    deriv(p, u, v, 0, 2, pvv);
    if (!cs_finish_eval(p, u, v, NULL, n))
        return 0;
    double E = dot(pu, pu), F = dot(pu, pv), G = dot(pv, pv);
    double L = dot(puu, n), M = dot(puv, n), N = dot(pvv, n), det = E * G - F * F;
    if (!(det > 0))
        return 0;
    double H = (E * N - 2 * F * M + G * L) / (2 * det), K = (L * N - M * M) / det;
    double disc = H * H - K;
    return H + sqrt(disc > 0 ? disc : 0);
}

/* Distance along the unit n from s to where the line enters the ball (c, r); HUGE_VAL when it
 * never does ahead of s; 0 when s is inside. */
static double entry(const double s[3], const double n[3], const double c[3], double r)
{
    double d[3] = {s[0] - c[0], s[1] - c[1], s[2] - c[2]};
    double b = dot(d, n), cc = dot(d, d) - r * r;
    if (cc <= 0)
        return 0;
    double disc = b * b - cc;
    if (disc < 0)
        return HUGE_VAL;
    double t = -b - sqrt(disc);
    return t >= 0 ? t : HUGE_VAL;
}

double cs_finish_scallop(const cs_patch_t *p, double r_mm, double v1, double v2, int nu, int ns)
{
    double worst = 0;
    for (int i = 0; i < nu; i++) {
        double u = nu > 1 ? (double)i / (nu - 1) : 0.5;
        double p1[3], n1[3], p2[3], n2[3], c1[3], c2[3];
        if (!cs_finish_eval(p, u, v1, p1, n1) || !cs_finish_eval(p, u, v2, p2, n2))
            return HUGE_VAL;
        for (int a = 0; a < 3; a++) {
            c1[a] = p1[a] + r_mm * n1[a];
            c2[a] = p2[a] + r_mm * n2[a];
        }
        for (int k = 1; k < ns; k++) {
            double s[3], n[3];
            if (!cs_finish_eval(p, u, v1 + (v2 - v1) * k / ns, s, n))
                return HUGE_VAL;
            double h = fmin(entry(s, n, c1, r_mm), entry(s, n, c2, r_mm));
            if (h > worst)
                worst = h;
        }
    }
    return worst;
}

cs_err_t cs_finish_tri_patch(const cs_tripatch_t *t, cs_patch_t *out)
{
    if (!t || !out || t->degree < 1 || t->degree > CS_TRIPATCH_MAX_DEGREE)
        return CS_ERR_DEGREE;
    unsigned n = t->degree;
    cs_vec3_t pts[CS_PATCH_MAX_POINTS * CS_PATCH_MAX_POINTS];
    for (unsigned i = 0; i <= n; i++) {
        unsigned m = n - i;
        for (unsigned l = 0; l <= n; l++) {
            /* degree elevation m -> n of b_j = S_{i,j,m-j}: c_l = sum_j C(m,j) C(n-m,l-j) b_j
             * / C(n,l), at t = 1 - a, so it lands at a-index n - l */
            int64_t acc[3] = {0, 0, 0};
            for (unsigned j = 0; j <= m; j++) {
                if (l < j || l - j > n - m)
                    continue;
                int64_t w = binomial(m, j) * binomial(n - m, l - j);
                const cs_vec3_t *b = &t->p[cs_tripatch_index(n, i, j)];
                acc[0] += w * b->x;
                acc[1] += w * b->y;
                acc[2] += w * b->z;
            }
            int64_t den = binomial(n, l), r[3];
            for (int k = 0; k < 3; k++) /* round half away from zero */
                r[k] = acc[k] >= 0 ? (2 * acc[k] + den) / (2 * den)
                                   : -((-2 * acc[k] + den) / (2 * den));
            pts[(n - l) * (n + 1) + i] =
                cs_fixed_vec((cs_pos_t)r[0], (cs_pos_t)r[1], (cs_pos_t)r[2]);
        }
    }
    return cs_patch_init(out, n, n, pts);
}

/* Tool centre at (u, v) in fixed point: P + R N from the core, R N rounded once. */
static cs_err_t centre_at(const cs_patch_t *p, cs_param_t u, cs_param_t v, int64_t r_lsb,
                          cs_vec3_t *c)
{
    cs_vec3_t pt;
    cs_patch_unit_t n;
    cs_err_t e = cs_patch_eval(p, u, v, &pt);
    if (e == CS_OK)
        e = cs_patch_normal(p, u, v, &n);
    if (e != CS_OK)
        return e;
    int64_t x = pt.x + cs_fixed_round_shift64(r_lsb * n.x, 30);
    int64_t y = pt.y + cs_fixed_round_shift64(r_lsb * n.y, 30);
    int64_t z = pt.z + cs_fixed_round_shift64(r_lsb * n.z, 30);
    if (!cs_fixed_pos_ok(x) || !cs_fixed_pos_ok(y) || !cs_fixed_pos_ok(z))
        return CS_ERR_RANGE;
    *c = cs_fixed_vec((cs_pos_t)x, (cs_pos_t)y, (cs_pos_t)z);
    return CS_OK;
}

/* Distance (LSB) from q to the segment [a, b]. */
static double seg_dist(const cs_vec3_t *q, const cs_vec3_t *a, const cs_vec3_t *b)
{
    double ab[3] = {(double)b->x - a->x, (double)b->y - a->y, (double)b->z - a->z};
    double aq[3] = {(double)q->x - a->x, (double)q->y - a->y, (double)q->z - a->z};
    double l2 = dot(ab, ab), t = l2 > 0 ? dot(aq, ab) / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double d[3] = {aq[0] - t * ab[0], aq[1] - t * ab[1], aq[2] - t * ab[2]};
    return sqrt(dot(d, d));
}

typedef struct {
    cs_param_t u;
    cs_vec3_t c;
    bool back; /* the chord ending here runs backwards against the surface (a fold) */
} pass_pt_t;

/* One pass at v: the u values where the chords of the offset curve stay within tol / 2 of it
 * at the quarter points (at least 8 chords), collected in order into *pts. */
static cs_err_t pass_points(const cs_patch_t *p, cs_param_t v, int64_t r_lsb, cs_pos_t tol,
                            pass_pt_t **pts, size_t *n, size_t *cap)
{
    struct {
        cs_param_t a, b;
        cs_vec3_t ca, cb;
        unsigned depth;
    } stack[PASS_MAX_LOG + 2];
    size_t sp = 0;
    *n = 0;
    cs_vec3_t c0, c1;
    cs_err_t e = centre_at(p, 0, v, r_lsb, &c0);
    if (e == CS_OK)
        e = centre_at(p, CS_PARAM_ONE, v, r_lsb, &c1);
    if (e != CS_OK)
        return e;
    if (*cap == 0) {
        *pts = malloc(64 * sizeof **pts);
        if (!*pts)
            return CS_ERR_FULL;
        *cap = 64;
    }
    (*pts)[(*n)++] = (pass_pt_t){0, c0, false};
    stack[sp].a = 0;
    stack[sp].b = CS_PARAM_ONE;
    stack[sp].ca = c0;
    stack[sp].cb = c1;
    stack[sp].depth = 0;
    sp++;
    while (sp > 0) {
        sp--;
        cs_param_t a = stack[sp].a, b = stack[sp].b;
        cs_vec3_t ca = stack[sp].ca, cb = stack[sp].cb;
        unsigned depth = stack[sp].depth;
        cs_param_t m = a + (b - a) / 2;
        cs_vec3_t cm, cq1, cq3;
        e = centre_at(p, m, v, r_lsb, &cm);
        if (e == CS_OK)
            e = centre_at(p, a + (m - a) / 2, v, r_lsb, &cq1);
        if (e == CS_OK)
            e = centre_at(p, m + (b - m) / 2, v, r_lsb, &cq3);
        if (e != CS_OK)
            return e;
        double worst =
            fmax(seg_dist(&cm, &ca, &cb), fmax(seg_dist(&cq1, &ca, &cb), seg_dist(&cq3, &ca, &cb)));
        if (depth >= 3 && worst <= 0.5 * tol) {
            if (*n == *cap) {
                pass_pt_t *np = realloc(*pts, 2 * *cap * sizeof *np);
                if (!np)
                    return CS_ERR_FULL;
                *pts = np;
                *cap *= 2;
            }
            (*pts)[(*n)++] = (pass_pt_t){b, cb, false};
            continue;
        }
        if (depth >= PASS_MAX_LOG || b - a < 4)
            return CS_ERR_DEPTH;
        /* Right half below the left one: the left is popped (emitted) first. */
        stack[sp].a = m;
        stack[sp].b = b;
        stack[sp].ca = cm;
        stack[sp].cb = cb;
        stack[sp].depth = depth + 1;
        sp++;
        stack[sp].a = a;
        stack[sp].b = m;
        stack[sp].ca = ca;
        stack[sp].cb = cm;
        stack[sp].depth = depth + 1;
        sp++;
    }
    return CS_OK;
}

/* Closest points of the segments a0-a1 and b0-b1 (mm): parameters *s, *t in [0, 1] and the
 * distance (Ericson, "Real-Time Collision Detection", 5.1.9). */
static double seg_seg(const double a0[3], const double a1[3], const double b0[3],
                      const double b1[3], double *s, double *t)
{
    double d1[3], d2[3], r[3];
    for (int k = 0; k < 3; k++) {
        d1[k] = a1[k] - a0[k];
        d2[k] = b1[k] - b0[k];
        r[k] = a0[k] - b0[k];
    }
    double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r), ss = 0, tt = 0;
    if (a <= 1e-30 && e <= 1e-30) {
        ss = tt = 0;
    } else if (a <= 1e-30) {
        tt = fmin(fmax(f / e, 0), 1);
    } else {
        double c = dot(d1, r);
        if (e <= 1e-30) {
            ss = fmin(fmax(-c / a, 0), 1);
        } else {
            double b = dot(d1, d2), den = a * e - b * b;
            ss = den > 0 ? fmin(fmax((b * f - c * e) / den, 0), 1) : 0;
            tt = (b * ss + f) / e;
            if (tt < 0) {
                tt = 0;
                ss = fmin(fmax(-c / a, 0), 1);
            } else if (tt > 1) {
                tt = 1;
                ss = fmin(fmax((b - c) / a, 0), 1);
            }
        }
    }
    double q[3];
    for (int k = 0; k < 3; k++)
        q[k] = a0[k] + ss * d1[k] - (b0[k] + tt * d2[k]);
    *s = ss;
    *t = tt;
    return sqrt(dot(q, q));
}

static void pt_mm(const pass_pt_t *q, double out[3])
{
    out[0] = cs_conv_pos_to_mm(q->c.x);
    out[1] = cs_conv_pos_to_mm(q->c.y);
    out[2] = cs_conv_pos_to_mm(q->c.z);
}

/* Cuts the loops of one pass: where chord i (pts[i] -> pts[i+1]) and a later chord j come
 * within tol_mm of each other and a backward chord lies between them, the vertices i + 1 .. j
 * are replaced by one vertex at the crossing (the midpoint of the closest points), as a 2D
 * offset curve's swallowtail is trimmed at its self-intersection. Returns the loops cut. */
static size_t trim_loops(pass_pt_t *pts, size_t *n, double tol_mm)
{
    size_t cut = 0;
    for (size_t i = 0; i + 3 < *n; i++) {
        bool back = false; /* a backward chord among i + 2 .. j */
        double a0[3], a1[3];
        pt_mm(&pts[i], a0);
        pt_mm(&pts[i + 1], a1);
        for (size_t j = i + 2; j + 1 < *n; j++) {
            back = back || pts[j].back;
            if (!back)
                continue;
            double b0[3], b1[3], s, t;
            pt_mm(&pts[j], b0);
            pt_mm(&pts[j + 1], b1);
            if (seg_seg(a0, a1, b0, b1, &s, &t) > tol_mm)
                continue;
            double x[3];
            for (int k = 0; k < 3; k++)
                x[k] = 0.5 * (a0[k] + s * (a1[k] - a0[k]) + b0[k] + t * (b1[k] - b0[k]));
            pass_pt_t m = pts[i + 1];
            if (cs_conv_mm_to_vec(x[0], x[1], x[2], &m.c) != CS_OK)
                continue;
            m.u = pts[i].u + (cs_param_t)llround(s * (pts[i + 1].u - pts[i].u));
            m.back = false;
            /* keep i, the crossing, then j + 1 .. */
            pts[i + 1] = m;
            size_t tail = *n - (j + 1);
            for (size_t k = 0; k < tail; k++)
                pts[i + 2 + k] = pts[j + 1 + k];
            pts[i + 2].back = false;
            *n = i + 2 + tail;
            cut++;
            break;
        }
    }
    return cut;
}

cs_err_t cs_finish_patch(const cs_patch_t *p, double r_mm, double h_mm, cs_pos_t tol,
                         cs_finish_emit_fn emit, void *ctx, cs_finish_stats_t *st)
{
    if (!(r_mm > 0) || !(h_mm > 0) || h_mm >= r_mm || tol < CS_TRACE_TOL_MIN || !emit || !st)
        return CS_ERR_ARG;
    int64_t r_lsb = (int64_t)llround(r_mm * CS_POS_ONE_MM);
    /* The flat-surface step-over for the target TARGET * H (the margin covers the sampled
     * scallop check). */
    double ht = TARGET * h_mm, w = 2 * sqrt(2 * r_mm * ht - ht * ht);
    /* Curvature survey (gouge warnings): a 9 x 9 grid. */
    for (int i = 0; i <= 8; i++)
        for (int j = 0; j <= 8; j++) {
            double k = concave_curvature(p, i / 8.0, j / 8.0);
            if (k > 0 && 1 / k < st->min_radius) {
                st->min_radius = 1 / k;
                st->gouge_u = i / 8.0;
                st->gouge_v = j / 8.0;
            }
            if (k > 0 && 1 / k < r_mm)
                st->gouge_points++;
        }
    pass_pt_t *pts = NULL;
    size_t n = 0, cap = 0;
    cs_err_t e = CS_OK;
    double v = 0;
    size_t pass = 0;
    for (;;) {
        cs_param_t vq = (cs_param_t)llround(v * Q30);
        e = pass_points(p, vq, r_lsb, tol, &pts, &n, &cap);
        if (e != CS_OK)
            break;
        /* Folds: the offset path running backwards against the surface along the pass. */
        double prev_p[3] = {0, 0, 0};
        for (size_t k = 0; k < n; k++) {
            double sp[3];
            cs_finish_eval(p, pts[k].u / Q30, vq / Q30, sp, NULL);
            if (k > 0) {
                double dc[3] = {cs_conv_pos_to_mm(pts[k].c.x - pts[k - 1].c.x),
                                cs_conv_pos_to_mm(pts[k].c.y - pts[k - 1].c.y),
                                cs_conv_pos_to_mm(pts[k].c.z - pts[k - 1].c.z)};
                double ds[3] = {sp[0] - prev_p[0], sp[1] - prev_p[1], sp[2] - prev_p[2]};
                pts[k].back = dot(dc, ds) < 0;
                if (pts[k].back) {
                    if (st->folded == 0) {
                        st->fold_u = pts[k - 1].u / Q30;
                        st->fold_v = vq / Q30;
                    }
                    st->folded++;
                }
            }
            prev_p[0] = sp[0];
            prev_p[1] = sp[1];
            prev_p[2] = sp[2];
        }
        st->loops_cut += trim_loops(pts, &n, cs_conv_pos_to_mm(tol));
        for (size_t k = 0; k < n; k++) {
            const pass_pt_t *q = &pts[pass % 2 ? n - 1 - k : k];
            double nn[3];
            if (cs_finish_eval(p, q->u / Q30, vq / Q30, NULL, nn) && nn[2] < 0)
                st->undercut++;
            if (!emit(ctx, pass, q->u / Q30, vq / Q30, &q->c, k == 0)) {
                e = CS_ERR_FULL;
                break;
            }
            st->vertices++;
        }
        if (e != CS_OK)
            break;
        st->passes++;
        pass++;
        if (vq == CS_PARAM_ONE)
            break;
        /* Next pass: the flat step-over over the largest |Pv| along this pass, shrunk until
         * the measured scallop is below TARGET * H. */
        double v0 = vq / Q30, maxpv = 0;
        for (int i = 0; i < NU_CHECK; i++) {
            double pv[3];
            deriv(p, (double)i / (NU_CHECK - 1), v0, 0, 1, pv);
            maxpv = fmax(maxpv, sqrt(dot(pv, pv)));
        }
        double dv = maxpv > 0 ? w / maxpv : 1 - v0;
        if (dv > 1 - v0)
            dv = 1 - v0;
        while (dv > 1e-6 &&
               cs_finish_scallop(p, r_mm, v0, v0 + dv, NU_CHECK, NS_CHECK) > ht * (1 + 1e-9))
            dv *= SHRINK;
        if (dv <= 1e-6) {
            e = CS_ERR_DEPTH;
            break;
        }
        v = v0 + dv;
        if (v > 1 - 1e-9)
            v = 1;
        double s = cs_finish_scallop(p, r_mm, v0, v, NU_CHECK, NS_CHECK);
        if (s > st->max_scallop)
            st->max_scallop = s;
    }
    free(pts);
    return e;
}
