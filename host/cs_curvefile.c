/* cs_curvefile: the curves file -> cs_path_t through the core's bases (see cs_curvefile.h). */
#include "cs_curvefile.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_arc.h"
#include "cs_basis.h"
#include "cs_conv.h"
#include "cs_err_text.h"
#include "cs_lex.h"
#include "cs_nurbs.h"
#include "cs_spline.h"

/* Knots are mapped onto [0, 2^30] in cs_nurbs_knot_t (only ratios of knot differences matter,
 * cs_nurbs.h): relative rounding 2^-31 of the knot range. */
#define KNOT_SPAN ((double)(1L << 30))

typedef struct {
    cs_lex_t lx;
    cs_path_t *path;
    cs_path_loc_t at; /* the statement's keyword */
    cs_path_kind_t kind;
    bool have_end; /* end is the previous statement's last point */
    cs_vec3_t end;
} cf_t;

static bool same_point(const cs_vec3_t *a, const cs_vec3_t *b)
{
    return a->x == b->x && a->y == b->y && a->z == b->z;
}

/* Appends one segment; a statement that does not start where the last one ended lifts the pen. */
static cs_err_t emit(cf_t *c, const cs_bezier_t *b, bool first)
{
    if (first && c->have_end && !same_point(&c->end, &b->p[0]))
        cs_path_new_subpath(c->path);
    cs_err_t e = cs_path_add(c->path, b, c->kind, c->at);
    c->end = b->p[b->degree];
    c->have_end = true;
    return e;
}

/* The number of points of a statement, at least min. */
static cs_err_t count(cf_t *c, int min, int *n)
{
    return cs_lex_integer(&c->lx, "number of points", min, CS_CURVEFILE_MAX_POINTS, n);
}

/* n points (and, when tan is not NULL, a tangent after each; when w is not NULL, a weight > 0
 * after each) into caller arrays of n. */
static cs_err_t points(cf_t *c, int n, cs_vec3_t *pts, cs_vec3_t *tan, double *w)
{
    for (int i = 0; i < n; i++) {
        cs_err_t e = cs_lex_vec(&c->lx, "point", &pts[i], NULL);
        if (e == CS_OK && tan)
            e = cs_lex_vec(&c->lx, "tangent", &tan[i], NULL);
        if (e == CS_OK && w) {
            e = cs_lex_number(&c->lx, "weight", &w[i]);
            if (e == CS_OK && !(w[i] > 0))
                return cs_path_diag_set(c->lx.diag, CS_ERR_WEIGHT, cs_lex_here(&c->lx),
                                        "weight %g must be > 0", w[i]);
        }
        if (e != CS_OK)
            return e;
    }
    return CS_OK;
}

static cs_err_t st_line(cf_t *c)
{
    cs_vec3_t p[2];
    cs_bezier_t b;
    cs_err_t e = points(c, 2, p, NULL, NULL);
    if (e == CS_OK && (e = cs_bezier_init(&b, 1, p)) == CS_OK)
        e = emit(c, &b, true);
    return e;
}

static cs_err_t st_bezier(cf_t *c)
{
    int n;
    cs_vec3_t p[CS_BEZIER_MAX_POINTS];
    cs_bezier_t b;
    cs_err_t e = cs_lex_integer(&c->lx, "degree", 1, CS_BEZIER_MAX_DEGREE, &n);
    if (e == CS_OK)
        e = points(c, n + 1, p, NULL, NULL);
    if (e == CS_OK && (e = cs_bezier_init(&b, (unsigned)n, p)) == CS_OK)
        e = emit(c, &b, true);
    return e;
}

/* Every segment of a cs_basis sequence. */
static cs_err_t emit_seq(cf_t *c, const cs_basis_seq_t *s)
{
    cs_err_t e = CS_OK;
    for (size_t i = 0; e == CS_OK && i < cs_basis_seq_segments(s); i++) {
        cs_bezier_t b;
        if ((e = cs_basis_seq_segment(s, i, &b)) == CS_OK)
            e = emit(c, &b, i == 0);
    }
    return e;
}

/* hermite, catmull-rom, uniform bspline and beta: N points (with tangents for Hermite). */
static cs_err_t basis_stmt(cf_t *c, cs_basis_kind_t kind, double beta1, double beta2)
{
    int n;
    cs_err_t e = count(c, kind == CS_BASIS_HERMITE ? 2 : 4, &n);
    if (e != CS_OK)
        return e;
    cs_vec3_t *p = malloc(2 * (size_t)n * sizeof *p);
    if (!p)
        return CS_ERR_FULL;
    cs_basis_seq_t s;
    e = points(c, n, p, kind == CS_BASIS_HERMITE ? p + n : NULL, NULL);
    if (e == CS_OK && kind == CS_BASIS_BETA) {
        cs_basis_beta_t b1 = (cs_basis_beta_t)lround(beta1 * CS_BASIS_BETA_ONE);
        cs_basis_beta_t b2 = (cs_basis_beta_t)lround(beta2 * CS_BASIS_BETA_ONE);
        e = cs_basis_seq_init_beta(&s, p, (size_t)n, b1, b2);
    } else if (e == CS_OK) {
        e = cs_basis_seq_init(&s, kind, p, kind == CS_BASIS_HERMITE ? p + n : NULL, (size_t)n);
    }
    if (e == CS_OK)
        e = emit_seq(c, &s);
    free(p);
    return e;
}

static cs_err_t st_hermite(cf_t *c)
{
    return basis_stmt(c, CS_BASIS_HERMITE, 0, 0);
}

static cs_err_t st_catmull_rom(cf_t *c)
{
    return basis_stmt(c, CS_BASIS_CATMULL_ROM, 0, 0);
}

static cs_err_t st_beta(cf_t *c)
{
    double b1, b2;
    cs_err_t e = cs_lex_number(&c->lx, "bias beta1", &b1);
    if (e == CS_OK && !(b1 > 0 && b1 <= (double)(CS_BASIS_BETA1_MAX / CS_BASIS_BETA_ONE)))
        e = cs_path_diag_set(c->lx.diag, CS_ERR_RANGE, cs_lex_here(&c->lx),
                             "bias beta1 %g must be in (0, %d]", b1,
                             (int)(CS_BASIS_BETA1_MAX / CS_BASIS_BETA_ONE));
    if (e == CS_OK)
        e = cs_lex_number(&c->lx, "tension beta2", &b2);
    if (e == CS_OK && !(b2 >= 0 && b2 <= (double)(CS_BASIS_BETA2_MAX / CS_BASIS_BETA_ONE)))
        e = cs_path_diag_set(c->lx.diag, CS_ERR_RANGE, cs_lex_here(&c->lx),
                             "tension beta2 %g must be in [0, %d]", b2,
                             (int)(CS_BASIS_BETA2_MAX / CS_BASIS_BETA_ONE));
    return e == CS_OK ? basis_stmt(c, CS_BASIS_BETA, b1, b2) : e;
}

/* "knots K k1 .. k(n+K)" after n control points (w: weights, NULL for a B-spline). */
static cs_err_t knots_and_emit(cf_t *c, const cs_vec3_t *p, const double *w, int n)
{
    int order;
    if (!cs_lex_next(&c->lx) || strcmp(c->lx.tok, "knots") != 0)
        return cs_path_diag_set(c->lx.diag, CS_ERR_PARSE, cs_lex_here(&c->lx),
                                "'%s': 'knots' expected", c->lx.tok);
    cs_err_t e = cs_lex_integer(&c->lx, "order", 2, CS_NURBS_MAX_DEGREE + 1, &order);
    if (e != CS_OK)
        return e;
    size_t nk = (size_t)n + (size_t)order;
    double *k = malloc(nk * sizeof *k);
    cs_nurbs_knot_t *kq = malloc(nk * sizeof *kq);
    int32_t *wq = w ? malloc((size_t)n * sizeof *wq) : NULL;
    if (!k || !kq || (w && !wq))
        e = CS_ERR_FULL;
    for (size_t i = 0; e == CS_OK && i < nk; i++) {
        e = cs_lex_number(&c->lx, "knot", &k[i]);
        if (e == CS_OK && i > 0 && k[i] < k[i - 1])
            e = cs_path_diag_set(c->lx.diag, CS_ERR_KNOTS, cs_lex_here(&c->lx),
                                 "knot %g is below the one before it (%g)", k[i], k[i - 1]);
    }
    if (e == CS_OK && !(k[nk - 1] > k[0]))
        e = cs_path_diag_set(c->lx.diag, CS_ERR_KNOTS, cs_lex_here(&c->lx),
                             "the knot vector is constant");
    for (size_t i = 0; e == CS_OK && i < nk; i++)
        kq[i] = (cs_nurbs_knot_t)llround((k[i] - k[0]) / (k[nk - 1] - k[0]) * KNOT_SPAN);
    double wmax = 0;
    for (int i = 0; w && i < n; i++)
        wmax = fmax(wmax, w[i]);
    for (int i = 0; e == CS_OK && w && i < n; i++)
        e = cs_conv_to_weight(w[i] / wmax, &wq[i]);
    cs_nurbs_t nu;
    if (e == CS_OK)
        e = cs_nurbs_init(&nu, (unsigned)order - 1, p, wq, (size_t)n, kq, nk);
    if (e == CS_OK) {
        cs_nurbs_iter_t it;
        cs_bezier_t b;
        cs_nurbs_iter_begin(&nu, &it);
        for (bool first = true; (e = cs_nurbs_next(&nu, &it, &b, NULL, NULL)) == CS_OK;
             first = false)
            if ((e = emit(c, &b, first)) != CS_OK)
                break;
        if (e == CS_END)
            e = CS_OK;
    }
    free(k);
    free(kq);
    free(wq);
    return e;
}

/* bspline N P.. [knots K k..] and nurbs N (P w).. knots K k.. */
static cs_err_t spline_stmt(cf_t *c, bool rational)
{
    int n;
    cs_err_t e = count(c, 2, &n);
    if (e != CS_OK)
        return e;
    cs_vec3_t *p = malloc((size_t)n * sizeof *p);
    double *w = rational ? malloc((size_t)n * sizeof *w) : NULL;
    if (!p || (rational && !w))
        e = CS_ERR_FULL;
    if (e == CS_OK)
        e = points(c, n, p, NULL, w);
    if (e == CS_OK && (rational || cs_lex_peek_is(&c->lx, "knots"))) {
        e = knots_and_emit(c, p, w, n);
    } else if (e == CS_OK) {
        cs_basis_seq_t s;
        if ((e = cs_basis_seq_init(&s, CS_BASIS_BSPLINE, p, NULL, (size_t)n)) == CS_OK)
            e = emit_seq(c, &s);
    }
    free(p);
    free(w);
    return e;
}

static cs_err_t st_bspline(cf_t *c)
{
    return spline_stmt(c, false);
}

static cs_err_t st_nurbs(cf_t *c)
{
    return spline_stmt(c, true);
}

/* The clamped cubic spline through p[0..n-1] with end tangents t0, t1 (mm per unit of the
 * parameter: 1 per segment, or the chord length with chord), in double: C2 at every inner point,
 * h_i D_(i-1) + 2 (h_(i-1) + h_i) D_i + h_(i-1) D_(i+1) = 3 (h_i (P_i - P_(i-1)) / h_(i-1) +
 * h_(i-1) (P_(i+1) - P_i) / h_i), D_0 = t0, D_(n-1) = t1 (Thomas algorithm), then each segment
 * the Bézier (P_i, P_i + h_i D_i / 3, P_(i+1) - h_i D_(i+1) / 3, P_(i+1)). */
static cs_err_t clamped(cf_t *c, const cs_vec3_t *p, int n, bool chord, const double t0[3],
                        const double t1[3])
{
    double h[CS_SPLINE_MAX_POINTS], d[CS_SPLINE_MAX_POINTS][3], q[CS_SPLINE_MAX_POINTS][3];
    double diag[CS_SPLINE_MAX_POINTS], up[CS_SPLINE_MAX_POINTS];
    for (int i = 0; i < n; i++) {
        q[i][0] = cs_conv_pos_to_mm(p[i].x);
        q[i][1] = cs_conv_pos_to_mm(p[i].y);
        q[i][2] = cs_conv_pos_to_mm(p[i].z);
    }
    for (int i = 0; i + 1 < n; i++) {
        h[i] = chord ? sqrt(pow(q[i + 1][0] - q[i][0], 2) + pow(q[i + 1][1] - q[i][1], 2) +
                            pow(q[i + 1][2] - q[i][2], 2))
                     : 1;
        if (!(h[i] > 0))
            return CS_ERR_DEGENERATE;
    }
    diag[0] = 1, up[0] = 0;
    for (int k = 0; k < 3; k++)
        d[0][k] = t0[k], d[n - 1][k] = t1[k];
    for (int i = 1; i + 1 < n; i++) { /* forward elimination of row i against row i - 1 */
        double lo = h[i], di = 2 * (h[i - 1] + h[i]), m = lo / diag[i - 1];
        diag[i] = di - m * up[i - 1];
        up[i] = h[i - 1];
        for (int k = 0; k < 3; k++)
            d[i][k] = 3 * (h[i] * (q[i][k] - q[i - 1][k]) / h[i - 1] +
                           h[i - 1] * (q[i + 1][k] - q[i][k]) / h[i]) -
                      m * d[i - 1][k];
    }
    for (int i = n - 2; i >= 1; i--) /* back substitution; D_(n-1) is given */
        for (int k = 0; k < 3; k++)
            d[i][k] = (d[i][k] - up[i] * d[i + 1][k]) / diag[i];
    cs_err_t e = CS_OK;
    for (int i = 0; e == CS_OK && i + 1 < n; i++) {
        cs_vec3_t b[4] = {p[i], {0, 0, 0}, {0, 0, 0}, p[i + 1]};
        if (cs_conv_mm_to_vec(q[i][0] + h[i] * d[i][0] / 3, q[i][1] + h[i] * d[i][1] / 3,
                              q[i][2] + h[i] * d[i][2] / 3, &b[1]) != CS_OK ||
            cs_conv_mm_to_vec(q[i + 1][0] - h[i] * d[i + 1][0] / 3,
                              q[i + 1][1] - h[i] * d[i + 1][1] / 3,
                              q[i + 1][2] - h[i] * d[i + 1][2] / 3, &b[2]) != CS_OK)
            return CS_ERR_RANGE;
        cs_bezier_t seg;
        if ((e = cs_bezier_init(&seg, 3, b)) == CS_OK)
            e = emit(c, &seg, i == 0);
    }
    return e;
}

/* natural N P.. [chord] [clamped T0 T1]: cs_spline's natural ends, or clamped end tangents. */
static cs_err_t st_natural(cf_t *c)
{
    int n;
    cs_err_t e = count(c, 2, &n);
    if (e != CS_OK)
        return e;
    if (n > CS_SPLINE_MAX_POINTS)
        return cs_path_diag_set(c->lx.diag, CS_ERR_FULL, cs_lex_here(&c->lx),
                                "a natural spline has at most %d points", CS_SPLINE_MAX_POINTS);
    cs_vec3_t p[CS_SPLINE_MAX_POINTS];
    e = points(c, n, p, NULL, NULL);
    bool chord = e == CS_OK && cs_lex_peek_is(&c->lx, "chord");
    if (chord)
        cs_lex_next(&c->lx);
    if (e == CS_OK && cs_lex_peek_is(&c->lx, "clamped")) {
        double t[2][3];
        cs_lex_next(&c->lx);
        for (int k = 0; e == CS_OK && k < 2; k++)
            e = cs_lex_vec(&c->lx, k ? "end tangent" : "start tangent", NULL, t[k]);
        return e == CS_OK ? clamped(c, p, n, chord, t[0], t[1]) : e;
    }
    cs_spline_t *s = e == CS_OK ? malloc(sizeof *s) : NULL;
    if (e == CS_OK && !s)
        return CS_ERR_FULL;
    if (e == CS_OK)
        e = cs_spline_solve(s, p, (size_t)n, chord ? CS_SPLINE_CHORD : CS_SPLINE_UNIFORM);
    for (size_t i = 0; e == CS_OK && i < cs_spline_segments(s); i++) {
        cs_bezier_t b;
        if ((e = cs_spline_segment(s, i, &b)) == CS_OK)
            e = emit(c, &b, i == 0);
    }
    free(s);
    return e;
}

cs_err_t cs_curvefile_arc(const cs_vec3_t v[3], double a0_deg, double a1_deg,
                          cs_bezier_t out[CS_ARC_MAX_SEGMENTS], unsigned *n)
{
    double sweep = fabs(a1_deg - a0_deg);
    if (!(sweep > 0 && sweep <= 360))
        return CS_ERR_RANGE;
    cs_param_t cs[4];
    for (int i = 0; i < 2; i++) {
        double r = (i ? a1_deg : a0_deg) * M_PI / 180;
        if (cs_conv_to_param(cos(r), &cs[2 * i]) != CS_OK ||
            cs_conv_to_param(sin(r), &cs[2 * i + 1]) != CS_OK)
            return CS_ERR_RANGE;
    }
    return cs_arc_build(&v[0], &v[1], &v[2], cs[0], cs[1], cs[2], cs[3], a1_deg > a0_deg, out, n);
}

/* arc C U V A0 A1: the ellipse arc C + U cos(a) + V sin(a) for a from A0 to A1 degrees. */
static cs_err_t st_arc(cf_t *c)
{
    cs_vec3_t v[3];
    double a[2];
    cs_err_t e = CS_OK;
    static const char *const what[3] = {"centre", "first semi-axis", "second semi-axis"};
    for (int i = 0; e == CS_OK && i < 3; i++)
        e = cs_lex_vec(&c->lx, what[i], &v[i], NULL);
    for (int i = 0; e == CS_OK && i < 2; i++)
        e = cs_lex_number(&c->lx, i ? "end angle (degrees)" : "start angle (degrees)", &a[i]);
    if (e != CS_OK)
        return e;
    double sweep = fabs(a[1] - a[0]);
    if (!(sweep > 0 && sweep <= 360))
        return cs_path_diag_set(c->lx.diag, CS_ERR_RANGE, cs_lex_here(&c->lx),
                                "the sweep %g degrees must be in (0, 360]", a[1] - a[0]);
    cs_bezier_t seg[CS_ARC_MAX_SEGMENTS];
    unsigned n = 0;
    e = cs_curvefile_arc(v, a[0], a[1], seg, &n);
    for (unsigned i = 0; e == CS_OK && i < n; i++)
        e = emit(c, &seg[i], i == 0);
    return e;
}

static const struct {
    const char *name;
    cs_path_kind_t kind;
    cs_err_t (*fn)(cf_t *c);
} statements[] = {
    {"line", CS_PATH_LINE, st_line},
    {"bezier", CS_PATH_BEZIER, st_bezier},
    {"hermite", CS_PATH_HERMITE, st_hermite},
    {"bspline", CS_PATH_BSPLINE, st_bspline},
    {"nurbs", CS_PATH_NURBS, st_nurbs},
    {"catmull-rom", CS_PATH_CATMULL_ROM, st_catmull_rom},
    {"beta", CS_PATH_BETA, st_beta},
    {"natural", CS_PATH_NATURAL, st_natural},
    {"arc", CS_PATH_ARC, st_arc},
};
#define NSTATEMENTS (sizeof statements / sizeof statements[0])

static cs_err_t statement(cf_t *c)
{
    c->at = cs_lex_here(&c->lx);
    size_t k = 0;
    while (k < NSTATEMENTS && strcmp(statements[k].name, c->lx.tok) != 0)
        k++;
    if (k == NSTATEMENTS) {
        char list[256] = "";
        for (size_t i = 0; i < NSTATEMENTS; i++)
            snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", i ? ", " : "",
                     statements[i].name);
        return cs_path_diag_set(c->lx.diag, CS_ERR_PARSE, c->at, "unknown curve '%s' (%s)",
                                c->lx.tok, list);
    }
    c->kind = statements[k].kind;
    cs_err_t e = statements[k].fn(c);
    if (e != CS_OK && c->lx.diag->code != e)
        return cs_path_diag_set(c->lx.diag, e, c->at, "%s: %s", statements[k].name, cs_err_text(e));
    return e;
}

bool cs_curvefile_is(const char *text, size_t len)
{
    cs_lex_t lx;
    cs_lex_init(&lx, text, len, "", NULL, 1);
    return cs_lex_next(&lx) && strcmp(lx.tok, CS_CURVEFILE_MAGIC) == 0;
}

cs_err_t cs_curvefile_parse(const char *name, const char *text, size_t len, cs_path_t *path,
                            cs_path_diag_t *diag)
{
    cf_t c;
    memset(&c, 0, sizeof c);
    diag->code = CS_OK;
    const char *file = cs_path_intern(path, name ? name : "-");
    if (!file)
        return CS_ERR_FULL;
    cs_lex_init(&c.lx, text, len, file, diag, 1);
    c.path = path;
    if (!cs_lex_next(&c.lx) || strcmp(c.lx.tok, CS_CURVEFILE_MAGIC) != 0)
        return cs_path_diag_set(diag, CS_ERR_PARSE, cs_lex_here(&c.lx),
                                "'%s': the header '%s 1' expected", c.lx.tok, CS_CURVEFILE_MAGIC);
    int version;
    cs_err_t e = cs_lex_integer(&c.lx, "format version", 1, 1, &version);
    size_t before = path->n;
    while (e == CS_OK && cs_lex_next(&c.lx))
        e = statement(&c);
    if (e == CS_OK && path->n == before)
        e = cs_path_diag_set(diag, CS_ERR_EMPTY, cs_lex_here(&c.lx), "no curves in the file");
    return e;
}
