/* cs_path: growable element list, interned file names, affine maps, diagnostics, double
 * evaluation and chord polylines (see cs_path.h). */
#include "cs_path.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "cs_conv.h"

void cs_path_init(cs_path_t *p)
{
    memset(p, 0, sizeof *p);
    p->pending_subpath = true;
}

void cs_path_free(cs_path_t *p)
{
    for (size_t i = 0; i < p->nfiles; i++)
        free(p->files[i]);
    free(p->files);
    free(p->elems);
    cs_path_init(p);
}

bool cs_path_grow(void **buf, size_t *cap, size_t need, size_t sz)
{
    if (need <= *cap)
        return true;
    size_t ncap = *cap ? *cap : 16;
    while (ncap < need) {
        if (ncap > ((size_t)-1) / 2 / sz)
            return false;
        ncap *= 2;
    }
    void *nb = realloc(*buf, ncap * sz);
    if (!nb)
        return false;
    *buf = nb;
    *cap = ncap;
    return true;
}

const char *cs_path_intern(cs_path_t *p, const char *name)
{
    for (size_t i = 0; i < p->nfiles; i++)
        if (strcmp(p->files[i], name) == 0)
            return p->files[i];
    void *buf = p->files;
    if (!cs_path_grow(&buf, &p->capfiles, p->nfiles + 1, sizeof *p->files))
        return NULL;
    p->files = buf;
    size_t len = strlen(name) + 1;
    char *copy = malloc(len);
    if (!copy)
        return NULL;
    memcpy(copy, name, len);
    p->files[p->nfiles++] = copy;
    return copy;
}

void cs_path_new_subpath(cs_path_t *p)
{
    p->pending_subpath = true;
}

cs_err_t cs_path_add(cs_path_t *p, const cs_bezier_t *curve, cs_path_kind_t kind, cs_path_loc_t loc)
{
    return cs_path_add_move(p, curve, kind, loc, 0.0, false);
}

cs_err_t cs_path_add_move(cs_path_t *p, const cs_bezier_t *curve, cs_path_kind_t kind,
                          cs_path_loc_t loc, double feed_mm_s, bool rapid)
{
    if (p->n >= (p->max_elems ? p->max_elems : CS_PATH_MAX_ELEMS)) {
        p->over_limit = true;
        p->over_loc = loc;
        return CS_ERR_FULL;
    }
    void *buf = p->elems;
    if (!cs_path_grow(&buf, &p->cap, p->n + 1, sizeof *p->elems))
        return CS_ERR_FULL;
    p->elems = buf;
    if (p->pending_subpath || p->nsubpaths == 0) {
        p->nsubpaths++;
        p->pending_subpath = false;
    }
    cs_path_elem_t *e = &p->elems[p->n++];
    e->curve = *curve;
    e->kind = kind;
    e->loc = loc;
    e->subpath = p->nsubpaths - 1;
    e->feed_mm_s = feed_mm_s;
    e->rapid = rapid;
    e->spindle = 0;
    e->spindle_s = 0;
    return CS_OK;
}

cs_path_affine_t cs_path_affine_identity(void)
{
    cs_path_affine_t m = {1.0, 0.0, 0.0, 1.0, 0.0, 0.0};
    return m;
}

cs_path_affine_t cs_path_affine_mul(cs_path_affine_t m, cs_path_affine_t n)
{
    /* [a c e; b d f; 0 0 1] matrices, product m * n. */
    cs_path_affine_t r;
    r.a = m.a * n.a + m.c * n.b;
    r.b = m.b * n.a + m.d * n.b;
    r.c = m.a * n.c + m.c * n.d;
    r.d = m.b * n.c + m.d * n.d;
    r.e = m.a * n.e + m.c * n.f + m.e;
    r.f = m.b * n.e + m.d * n.f + m.f;
    return r;
}

void cs_path_affine_point(const cs_path_affine_t *m, double x, double y, double *ox, double *oy)
{
    double nx = m->a * x + m->c * y + m->e;
    double ny = m->b * x + m->d * y + m->f;
    *ox = nx;
    *oy = ny;
}

void cs_path_affine_vector(const cs_path_affine_t *m, double x, double y, double *ox, double *oy)
{
    double nx = m->a * x + m->c * y;
    double ny = m->b * x + m->d * y;
    *ox = nx;
    *oy = ny;
}

bool cs_path_affine_is_identity(const cs_path_affine_t *m)
{
    return m->a == 1.0 && m->b == 0.0 && m->c == 0.0 && m->d == 1.0 && m->e == 0.0 && m->f == 0.0;
}

cs_err_t cs_path_diag_set(cs_path_diag_t *d, cs_err_t code, cs_path_loc_t loc, const char *fmt, ...)
{
    va_list ap;
    d->code = code;
    d->loc = loc;
    if (!d->loc.file)
        d->loc.file = "-";
    char raw[sizeof d->reason];
    va_start(ap, fmt);
    vsnprintf(raw, sizeof raw, fmt, ap);
    va_end(ap);
    cs_path_escape(d->reason, sizeof d->reason, raw);
    return code;
}

void cs_path_escape(char *dst, size_t cap, const char *src)
{
    static const char hex[] = "0123456789abcdef";
    size_t o = 0;
    for (; *src != '\0' && o + 1 < cap; src++) {
        unsigned char c = (unsigned char)*src;
        if (c >= 0x20 && c != 0x7f) {
            dst[o++] = (char)c;
            continue;
        }
        if (o + 5 > cap)
            break; /* no room for the whole escape: cut before it */
        dst[o++] = '\\';
        dst[o++] = 'x';
        dst[o++] = hex[c >> 4];
        dst[o++] = hex[c & 15];
    }
    if (cap > 0)
        dst[o < cap ? o : cap - 1] = '\0';
}

bool cs_path_over_limit(const cs_path_t *p, cs_path_diag_t *d)
{
    if (!p->over_limit)
        return false;
    cs_path_diag_set(d, CS_ERR_RANGE, p->over_loc,
                     "more than %zu curves: the job is too large (docs/inputs.md, Limits)",
                     p->max_elems ? p->max_elems : CS_PATH_MAX_ELEMS);
    return true;
}

/* The one place a located message is written: every part escaped (cs_path_escape). */
static void diag_write(FILE *f, const cs_path_diag_t *d, const char *kind)
{
    char file[1024], reason[sizeof d->reason];
    cs_path_escape(file, sizeof file, d->loc.file ? d->loc.file : "-");
    cs_path_escape(reason, sizeof reason, d->reason); /* a reason set without cs_path_diag_set */
    fprintf(f, "%s:%u:%u: %s%s\n", file, d->loc.line, d->loc.col, kind, reason);
}

void cs_path_diag_print(FILE *f, const cs_path_diag_t *d)
{
    diag_write(f, d, "");
}

void cs_path_warn_print(FILE *f, const cs_path_diag_t *w)
{
    diag_write(f, w, "warning: ");
}

void cs_path_eval_mm(const cs_bezier_t *c, double t, double out[3])
{
    /* de Casteljau on (w x, w y, w z, w) (seed 003: B(t) as repeated linear interpolation);
     * for a polynomial curve every w is 1 and the last division is exact. */
    double q[CS_BEZIER_MAX_POINTS][4];
    unsigned n = c->degree;
    if (n > CS_BEZIER_MAX_DEGREE)
        n = CS_BEZIER_MAX_DEGREE;
    for (unsigned i = 0; i <= n; i++) {
        double w = c->rational ? (double)c->w[i] / (double)CS_WEIGHT_ONE : 1.0;
        q[i][0] = w * cs_conv_pos_to_mm(c->p[i].x);
        q[i][1] = w * cs_conv_pos_to_mm(c->p[i].y);
        q[i][2] = w * cs_conv_pos_to_mm(c->p[i].z);
        q[i][3] = w;
    }
    for (unsigned r = 1; r <= n; r++)
        for (unsigned i = 0; i + r <= n; i++)
            for (unsigned k = 0; k < 4; k++)
                q[i][k] = (1.0 - t) * q[i][k] + t * q[i + 1][k];
    for (unsigned k = 0; k < 3; k++)
        out[k] = q[0][k] / q[0][3];
}

bool cs_path_bbox_mm(const cs_path_t *p, double min[3], double max[3])
{
    if (p->n == 0)
        return false;
    for (size_t i = 0; i < p->n; i++) {
        const cs_bezier_t *c = &p->elems[i].curve;
        for (unsigned k = 0; k <= c->degree && k < CS_BEZIER_MAX_POINTS; k++) {
            double v[3] = {cs_conv_pos_to_mm(c->p[k].x), cs_conv_pos_to_mm(c->p[k].y),
                           cs_conv_pos_to_mm(c->p[k].z)};
            for (int a = 0; a < 3; a++) {
                if ((i == 0 && k == 0) || v[a] < min[a])
                    min[a] = v[a];
                if ((i == 0 && k == 0) || v[a] > max[a])
                    max[a] = v[a];
            }
        }
    }
    return true;
}

void cs_path_poly_init(cs_path_poly_t *s)
{
    memset(s, 0, sizeof *s);
}

void cs_path_poly_free(cs_path_poly_t *s)
{
    free(s->pts);
    free(s->starts);
    cs_path_poly_init(s);
}

cs_err_t cs_path_poly_move(cs_path_poly_t *s, double x, double y)
{
    void *b = s->starts;
    if (!cs_path_grow(&b, &s->caplines, s->nlines + 1, sizeof *s->starts))
        return CS_ERR_FULL;
    s->starts = b;
    b = s->pts;
    if (!cs_path_grow(&b, &s->cap, s->n + 1, sizeof *s->pts))
        return CS_ERR_FULL;
    s->pts = b;
    s->starts[s->nlines++] = s->n;
    s->pts[s->n].x = x;
    s->pts[s->n].y = y;
    s->n++;
    return CS_OK;
}

cs_err_t cs_path_poly_line(cs_path_poly_t *s, double x, double y)
{
    if (s->nlines == 0)
        return cs_path_poly_move(s, x, y);
    void *b = s->pts;
    if (!cs_path_grow(&b, &s->cap, s->n + 1, sizeof *s->pts))
        return CS_ERR_FULL;
    s->pts = b;
    s->pts[s->n].x = x;
    s->pts[s->n].y = y;
    s->n++;
    return CS_OK;
}

size_t cs_path_poly_len(const cs_path_poly_t *s, size_t i)
{
    if (i >= s->nlines)
        return 0;
    size_t end = i + 1 < s->nlines ? s->starts[i + 1] : s->n;
    return end - s->starts[i];
}

/* --- measured deviation (host, double) ------------------------------------------------- */

typedef struct {
    double x, y, z;
} dvec_t;

static dvec_t eval_d(const cs_bezier_t *c, double t)
{
    double q[3];
    cs_path_eval_mm(c, t, q);
    dvec_t r = {q[0], q[1], q[2]};
    return r;
}

static double dist_d(dvec_t a, dvec_t b)
{
    double dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
    return sqrt(dx * dx + dy * dy + dz * dz);
}

static double dist_seg_d(dvec_t p, dvec_t a, dvec_t b)
{
    double vx = b.x - a.x, vy = b.y - a.y, vz = b.z - a.z;
    double wx = p.x - a.x, wy = p.y - a.y, wz = p.z - a.z;
    double l2 = vx * vx + vy * vy + vz * vz;
    double u = l2 > 0.0 ? (wx * vx + wy * vy + wz * vz) / l2 : 0.0;
    u = u < 0.0 ? 0.0 : u > 1.0 ? 1.0 : u;
    dvec_t q = {a.x + u * vx, a.y + u * vy, a.z + u * vz};
    return dist_d(p, q);
}

static dvec_t vec_d(const cs_vec3_t *p)
{
    dvec_t r = {cs_conv_pos_to_mm(p->x), cs_conv_pos_to_mm(p->y), cs_conv_pos_to_mm(p->z)};
    return r;
}

/* f(t) = sign * distance from the curve at t to the point (seg_b NULL) or segment. */
typedef struct {
    const cs_bezier_t *c;
    dvec_t a, b;
    bool segment;
    double sign;
} gold_ctx_t;

static double gold_f(const gold_ctx_t *g, double t)
{
    dvec_t p = eval_d(g->c, t);
    return g->sign * (g->segment ? dist_seg_d(p, g->a, g->b) : dist_d(p, g->a));
}

/* Golden-section search for the maximum of gold_f on [lo, hi]; returns the maximum, *arg its t. */
static double golden_max(const gold_ctx_t *g, double lo, double hi, double *arg)
{
    const double r = 0.6180339887498949;
    double a = lo, b = hi;
    double x1 = b - r * (b - a), x2 = a + r * (b - a);
    double f1 = gold_f(g, x1), f2 = gold_f(g, x2);
    for (int i = 0; i < 60 && b - a > 1e-15; i++) {
        if (f1 < f2) {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + r * (b - a);
            f2 = gold_f(g, x2);
        } else {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - r * (b - a);
            f1 = gold_f(g, x1);
        }
    }
    double best = f1 > f2 ? f1 : f2, bt = f1 > f2 ? x1 : x2;
    double fl = gold_f(g, lo), fh = gold_f(g, hi);
    if (fl > best) {
        best = fl;
        bt = lo;
    }
    if (fh > best) {
        best = fh;
        bt = hi;
    }
    if (arg)
        *arg = bt;
    return best;
}

double cs_path_deviation_mm(const cs_bezier_t *c, const cs_vec3_t *v, size_t n)
{
    if (n < 2)
        return 0.0;
    const double lsb = 1.0 / (double)CS_POS_ONE_MM;
    size_t m = 64 * n < 2048 ? 2048 : 64 * n; /* grid intervals */
    dvec_t *s = malloc((m + 1) * sizeof *s);
    double *tv = malloc(n * sizeof *tv);
    if (!s || !tv) {
        free(s);
        free(tv);
        return HUGE_VAL;
    }
    for (size_t j = 0; j <= m; j++)
        s[j] = eval_d(c, (double)j / (double)m);
    tv[0] = 0.0;
    tv[n - 1] = 1.0;
    size_t jprev = 0;
    double worst = 0.0;
    for (size_t k = 1; k + 1 < n; k++) {
        dvec_t p = vec_d(&v[k]);
        /* First grid point after the previous vertex that is within reach of p: the grid step
         * there (the curve between two samples is about that long) plus the 2 LSB allowed. */
        size_t j = jprev;
        bool found = false;
        for (; j <= m; j++) {
            double step = dist_d(s[j], s[j < m ? j + 1 : j]);
            double back = j > 0 ? dist_d(s[j], s[j - 1]) : 0.0;
            double reach = 1.5 * (step > back ? step : back) + 2.0 * lsb;
            if (dist_d(s[j], p) <= reach) {
                found = true;
                break;
            }
        }
        if (!found) {
            worst = HUGE_VAL;
            break;
        }
        double lo = (double)(j > jprev + 1 ? j - 1 : jprev) / (double)m;
        double hi = (double)(j + 3 < m ? j + 3 : m) / (double)m;
        if (lo < tv[k - 1])
            lo = tv[k - 1];
        gold_ctx_t g = {c, p, p, false, -1.0};
        double t;
        double d = -golden_max(&g, lo, hi, &t);
        if (d > 2.0 * lsb) {
            worst = HUGE_VAL;
            break;
        }
        tv[k] = t;
        jprev = (size_t)floor(t * (double)m);
    }
    for (size_t k = 0; k + 1 < n && worst != HUGE_VAL; k++) {
        dvec_t a = vec_d(&v[k]), b = vec_d(&v[k + 1]);
        gold_ctx_t g = {c, a, b, true, 1.0};
        double t0 = tv[k], t1 = tv[k + 1];
        /* Grid maximum inside [t0, t1], then refined around it. */
        size_t j0 = (size_t)ceil(t0 * (double)m), j1 = (size_t)floor(t1 * (double)m);
        double best = gold_f(&g, t0), bt = t0;
        for (size_t j = j0; j <= j1 && j <= m; j++) {
            double d = dist_seg_d(s[j], a, b);
            if (d > best) {
                best = d;
                bt = (double)j / (double)m;
            }
        }
        double lo = bt - 1.0 / (double)m, hi = bt + 1.0 / (double)m;
        lo = lo < t0 ? t0 : lo;
        hi = hi > t1 ? t1 : hi;
        double r = golden_max(&g, lo, hi, NULL);
        if (r > best)
            best = r;
        if (best > worst)
            worst = best;
    }
    free(s);
    free(tv);
    return worst;
}

const char *cs_path_kind_name(cs_path_kind_t k)
{
    static const char *const names[] = {"line",  "quad",        "cubic",   "arc",
                                        "other", "bezier",      "hermite", "bspline",
                                        "nurbs", "catmull-rom", "beta",    "natural"};
    return (unsigned)k < sizeof names / sizeof names[0] ? names[k] : "?";
}
