/* cs_dropcut: the mesh, its bound, its grid and the drop-cutter query (see cs_dropcut.h). */
#include "cs_dropcut.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cs_conv.h"
#include "cs_finish.h"
#include "cs_varady.h"

#define DC_GRID_MAX  512  /* cells a patch in each direction, at most */
#define DC_GOLDEN_IT 40   /* golden-section steps: the bracket shrinks by 0.618^40 ~ 4e-9 */
#define DC_MAX_CELLS 4000 /* grid cells in each direction, at most */
#define DC_EPS_MIN   1e-6 /* mm: the least enlargement of the cutter (see cs_dropcut_drop) */

double cs_dropcut_profile(const cs_dropcut_tool_t *t, double d)
{
    double a = t->r_mm - t->c_mm; /* radius of the flat bottom */
    if (d <= a)
        return 0;
    double e = d - a;
    double q = t->c_mm * t->c_mm - e * e;
    return t->c_mm - sqrt(q > 0 ? q : 0);
}

static double norm3(const double v[3])
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

double cs_dropcut_grid_eps(const double *p, int m, int n, int nu, int nv)
{
    /* P(i, j) at p[(i * (n + 1) + j) * 3]. */
#define PT(i, j, k) p[((i) * (n + 1) + (j)) * 3 + (k)]
    double duu = 0, dvv = 0, duv = 0;
    for (int i = 0; i <= m; i++)
        for (int j = 0; j <= n; j++) {
            double v[3];
            for (int k = 0; i + 2 <= m && k < 3; k++)
                v[k] = PT(i + 2, j, k) - 2 * PT(i + 1, j, k) + PT(i, j, k);
            if (i + 2 <= m)
                duu = fmax(duu, norm3(v));
            for (int k = 0; j + 2 <= n && k < 3; k++)
                v[k] = PT(i, j + 2, k) - 2 * PT(i, j + 1, k) + PT(i, j, k);
            if (j + 2 <= n)
                dvv = fmax(dvv, norm3(v));
            for (int k = 0; i + 1 <= m && j + 1 <= n && k < 3; k++)
                v[k] = PT(i + 1, j + 1, k) - PT(i + 1, j, k) - PT(i, j + 1, k) + PT(i, j, k);
            if (i + 1 <= m && j + 1 <= n)
                duv = fmax(duv, norm3(v));
        }
#undef PT
    double muu = m * (m - 1) * duu, mvv = n * (n - 1) * dvv, muv = m * n * duv;
    return ((muu + muv) / ((double)nu * nu) + (mvv + muv) / ((double)nv * nv)) / 8;
}

void cs_dropcut_init(cs_dropcut_mesh_t *ms)
{
    memset(ms, 0, sizeof *ms);
    for (int k = 0; k < 3; k++) {
        ms->box[k] = HUGE_VAL;
        ms->box[k + 3] = -HUGE_VAL;
    }
}

cs_err_t cs_dropcut_add(cs_dropcut_mesh_t *ms, const double a[3], const double b[3],
                        const double c[3])
{
    if (ms->ntri == ms->cap) {
        size_t cap = ms->cap ? 2 * ms->cap : 1024;
        cs_dropcut_tri_t *t = realloc(ms->tri, cap * sizeof *t);
        if (!t)
            return CS_ERR_FULL;
        ms->tri = t;
        ms->cap = cap;
    }
    cs_dropcut_tri_t *t = &ms->tri[ms->ntri++];
    const double *v[3] = {a, b, c};
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) {
            t->v[i][k] = v[i][k];
            ms->box[k] = fmin(ms->box[k], v[i][k]);
            ms->box[k + 3] = fmax(ms->box[k + 3], v[i][k]);
        }
    return CS_OK;
}

/* The grid size of patch q for a bound eps (each direction's term gets half of it). */
static void grid_for(const double *p, int m, int n, double eps, int *nu, int *nv)
{
    double base = cs_dropcut_grid_eps(p, m, n, 1, 1) * 8; /* (Muu + Muv) + (Mvv + Muv) */
    double tu = cs_dropcut_grid_eps(p, m, n, 1, 1 << 30) * 8, tv = base - tu;
    *nu = (int)fmin(DC_GRID_MAX, fmax(2, ceil(sqrt(tu / (4 * eps)))));
    *nv = (int)fmin(DC_GRID_MAX, fmax(2, ceil(sqrt(tv / (4 * eps)))));
}

/* Triangulates one tensor patch; *eps_out gets its bound. */
static cs_err_t mesh_patch(cs_dropcut_mesh_t *ms, const cs_patch_t *q, double eps, double *eps_out)
{
    int m = q->deg_u, n = q->deg_v;
    double cp[CS_PATCH_MAX_POINTS * CS_PATCH_MAX_POINTS * 3];
    for (int i = 0; i <= m; i++)
        for (int j = 0; j <= n; j++) {
            double *d = &cp[(i * (n + 1) + j) * 3];
            d[0] = cs_conv_pos_to_mm(q->p[i][j].x);
            d[1] = cs_conv_pos_to_mm(q->p[i][j].y);
            d[2] = cs_conv_pos_to_mm(q->p[i][j].z);
        }
    int nu, nv;
    grid_for(cp, m, n, eps, &nu, &nv);
    *eps_out = cs_dropcut_grid_eps(cp, m, n, nu, nv);
    double *row = malloc(2 * (size_t)(nv + 1) * 3 * sizeof *row);
    if (!row)
        return CS_ERR_FULL;
    cs_err_t e = CS_OK;
    for (int i = 0; i <= nu && e == CS_OK; i++) {
        double *cur = row + (size_t)(i & 1) * (size_t)(nv + 1) * 3;
        double *prev = row + (size_t)((i + 1) & 1) * (size_t)(nv + 1) * 3;
        for (int j = 0; j <= nv; j++)
            cs_finish_eval(q, (double)i / nu, (double)j / nv, &cur[j * 3], NULL);
        for (int j = 0; i > 0 && j < nv && e == CS_OK; j++) {
            e = cs_dropcut_add(ms, &prev[j * 3], &cur[j * 3], &cur[(j + 1) * 3]);
            if (e == CS_OK)
                e = cs_dropcut_add(ms, &prev[j * 3], &cur[(j + 1) * 3], &prev[(j + 1) * 3]);
        }
    }
    free(row);
    return e;
}

/* Circumradius of triangle a b c (half the longest edge when degenerate), mm. */
static double circumradius(const double a[3], const double b[3], const double c[3])
{
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; k++) {
        u[k] = b[k] - a[k];
        v[k] = c[k] - a[k];
        w[k] = c[k] - b[k];
    }
    double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    double lu = norm3(u), lv = norm3(v), lw = norm3(w), a2 = norm3(n); /* a2: twice the area */
    if (a2 < 1e-15 * fmax(lu * lv, 1e-300))
        return fmax(fmax(lu, lv), lw) / 2;
    return lu * lv * lw / (2 * a2);
}

/* A sphere (centre c, radius r) on a latitude-longitude grid fine enough for eps: every point of
 * the sphere projects radially into the triangle whose cap holds it, at most the cap's height
 * r - sqrt(r^2 - rho^2) away (rho the triangle's circumradius); *eps_out gets the largest. The
 * angular step 2 sqrt(eps / r) makes a cell's half-diagonal about sqrt(2 eps r). */
static cs_err_t mesh_sphere(cs_dropcut_mesh_t *ms, const cs_sphere_t *sp, double eps,
                            double *eps_out)
{
    double r = sp->r, step = 2 * sqrt(eps / r);
    int nlat = (int)fmin(DC_GRID_MAX, fmax(4, ceil(M_PI / step)));
    int nlon = 2 * nlat;
    double prev[2 * DC_GRID_MAX + 1][3], cur[2 * DC_GRID_MAX + 1][3];
    cs_err_t e = CS_OK;
    *eps_out = 0;
    for (int i = 0; i <= nlat && e == CS_OK; i++) {
        double u = -M_PI / 2 + M_PI * i / nlat;
        for (int j = 0; j <= nlon; j++) {
            double w = 2 * M_PI * j / nlon;
            cur[j][0] = sp->c[0] + r * cos(u) * cos(w);
            cur[j][1] = sp->c[1] + r * cos(u) * sin(w);
            cur[j][2] = sp->c[2] + r * sin(u);
        }
        for (int j = 0; i > 0 && j < nlon && e == CS_OK; j++) {
            const double *t[2][3] = {{prev[j], cur[j], cur[j + 1]}, {prev[j], cur[j + 1], prev[j + 1]}};
            for (int k = 0; k < 2 && e == CS_OK; k++) {
                double rho = fmin(circumradius(t[k][0], t[k][1], t[k][2]), r);
                *eps_out = fmax(*eps_out, r - sqrt(r * r - rho * rho));
                e = cs_dropcut_add(ms, t[k][0], t[k][1], t[k][2]);
            }
        }
        memcpy(prev, cur, sizeof prev);
    }
    return e;
}

/* The tensor patches of one item: itself, its collapsed tensor form, or fitted cells. */
static cs_err_t mesh_item(cs_dropcut_mesh_t *ms, const cs_surf_item_t *it, double eps,
                          double fit_mm, cs_patch_t *cells)
{
    double pe = 0;
    if (it->sphere) {
        cs_err_t e = mesh_sphere(ms, &it->sph, eps, &pe);
        ms->eps = fmax(ms->eps, pe);
        return e;
    }
    if (it->tri) {
        cs_patch_t tq;
        cs_err_t e = cs_finish_tri_patch(&it->trip, &tq);
        if (e == CS_OK)
            e = mesh_patch(ms, &tq, eps, &pe);
        ms->eps = fmax(ms->eps, pe);
        return e;
    }
    if (!it->varady) {
        cs_err_t e = mesh_patch(ms, &it->quad, eps, &pe);
        ms->eps = fmax(ms->eps, pe);
        return e;
    }
    size_t ncell = 0;
    double fit = 0;
    cs_err_t e = cs_varady_patches(&it->nside, fit_mm, cells, NULL, CS_VARADY_MAX_PATCHES, &ncell,
                                   &fit);
    for (size_t c = 0; e == CS_OK && c < ncell; c++) {
        e = mesh_patch(ms, &cells[c], eps, &pe);
        ms->eps = fmax(ms->eps, pe + fit);
    }
    return e;
}

cs_err_t cs_dropcut_build(cs_dropcut_mesh_t *ms, const cs_surffile_t *sf, double eps_mm,
                          double fit_mm, double rmax_mm)
{
    cs_dropcut_init(ms);
    if (sf->n == 0)
        return CS_ERR_DEGENERATE;
    cs_patch_t *cells = malloc(CS_VARADY_MAX_PATCHES * sizeof *cells);
    if (!cells)
        return CS_ERR_FULL;
    cs_err_t e = CS_OK;
    for (size_t i = 0; i < sf->n && e == CS_OK; i++)
        e = mesh_item(ms, &sf->items[i], eps_mm, fit_mm, cells);
    free(cells);
    if (e == CS_OK)
        e = cs_dropcut_index(ms, rmax_mm);
    return e;
}

/* --- the grid ------------------------------------------------------------------------------ */

static size_t cell_of(const cs_dropcut_mesh_t *ms, double v, int axis)
{
    double c = floor((v - ms->box[axis]) / ms->cell);
    size_t lim = axis == 0 ? ms->gx : ms->gy;
    if (c < 0)
        return 0;
    return c >= (double)lim ? lim - 1 : (size_t)c;
}

/* The xy box and top of every triangle, and the grid's cell tops (for the query's bounds). */
static cs_err_t index_boxes(cs_dropcut_mesh_t *ms)
{
    ms->bb = malloc(ms->ntri * sizeof *ms->bb);
    if (!ms->bb)
        return CS_ERR_FULL;
    for (size_t t = 0; t < ms->ntri; t++) {
        const cs_dropcut_tri_t *tr = &ms->tri[t];
        double *b = ms->bb[t];
        b[0] = fmin(fmin(tr->v[0][0], tr->v[1][0]), tr->v[2][0]);
        b[1] = fmin(fmin(tr->v[0][1], tr->v[1][1]), tr->v[2][1]);
        b[2] = fmax(fmax(tr->v[0][0], tr->v[1][0]), tr->v[2][0]);
        b[3] = fmax(fmax(tr->v[0][1], tr->v[1][1]), tr->v[2][1]);
        b[4] = fmax(fmax(tr->v[0][2], tr->v[1][2]), tr->v[2][2]);
    }
    return CS_OK;
}

cs_err_t cs_dropcut_index(cs_dropcut_mesh_t *ms, double rmax_mm)
{
    if (ms->ntri == 0)
        return CS_ERR_DEGENERATE;
    double w = ms->box[3] - ms->box[0], h = ms->box[4] - ms->box[1];
    /* About as many cells as triangles, and no finer than a tool radius needs. */
    double cell = sqrt(fmax(w * h, 1e-12) / (double)ms->ntri) * 2;
    cell = fmax(cell, fmax(w, h) / DC_MAX_CELLS);
    cell = fmax(cell, fmin(rmax_mm, fmax(w, h)) / 16);
    ms->cell = fmax(cell, 1e-6);
    ms->gx = (size_t)(w / ms->cell) + 1;
    ms->gy = (size_t)(h / ms->cell) + 1;
    size_t nc = ms->gx * ms->gy;
    ms->start = calloc(nc + 1, sizeof *ms->start);
    ms->stamp = calloc(ms->ntri, sizeof *ms->stamp);
    ms->ctop = malloc(nc * sizeof *ms->ctop);
    if (!ms->start || !ms->stamp || !ms->ctop || index_boxes(ms) != CS_OK)
        return CS_ERR_FULL;
    for (size_t c = 0; c < nc; c++)
        ms->ctop[c] = -HUGE_VAL;
    for (int pass = 0; pass < 2; pass++) {
        for (size_t t = 0; t < ms->ntri; t++) {
            const double *b = ms->bb[t];
            for (size_t cy = cell_of(ms, b[1], 1); cy <= cell_of(ms, b[3], 1); cy++)
                for (size_t cx = cell_of(ms, b[0], 0); cx <= cell_of(ms, b[2], 0); cx++) {
                    size_t c = cy * ms->gx + cx;
                    if (pass == 0) {
                        ms->start[c + 1]++;
                        ms->ctop[c] = fmax(ms->ctop[c], b[4]);
                    } else {
                        ms->idx[ms->start[c]++] = t;
                    }
                }
        }
        if (pass == 0) {
            for (size_t c = 0; c < nc; c++)
                ms->start[c + 1] += ms->start[c];
            ms->idx = malloc((ms->start[nc] + 1) * sizeof *ms->idx);
            if (!ms->idx)
                return CS_ERR_FULL;
        }
    }
    for (size_t c = nc; c > 0; c--) /* the second pass moved each start to its end */
        ms->start[c] = ms->start[c - 1];
    ms->start[0] = 0;
    return CS_OK;
}

/* --- one triangle ------------------------------------------------------------------------- */

/* f(p) = p.z - h(d) along the edge a -> b, for t in [t0, t1] where d <= R: concave, so a
 * golden-section search finds its maximum. */
static double edge_f(const cs_dropcut_tool_t *t, const double a[3], const double b[3], double x,
                     double y, double s)
{
    double px = a[0] + s * (b[0] - a[0]) - x, py = a[1] + s * (b[1] - a[1]) - y;
    double d = sqrt(px * px + py * py);
    if (d > t->r_mm)
        d = t->r_mm; /* only at the bracket's ends, by rounding */
    return a[2] + s * (b[2] - a[2]) - cs_dropcut_profile(t, d);
}

static double edge_drop(const cs_dropcut_tool_t *t, const double a[3], const double b[3],
                        double x, double y)
{
    /* d(s)^2 = |A + s B|^2 <= R^2: s in [s0, s1] (roots of a quadratic). */
    double ax = a[0] - x, ay = a[1] - y, bx = b[0] - a[0], by = b[1] - a[1];
    double qa = bx * bx + by * by, qb = 2 * (ax * bx + ay * by);
    double qc = ax * ax + ay * ay - t->r_mm * t->r_mm;
    double s0 = 0, s1 = 1;
    if (qa < 1e-24) {
        if (qc > 0)
            return -HUGE_VAL;
    } else {
        double disc = qb * qb - 4 * qa * qc;
        if (disc < 0)
            return -HUGE_VAL;
        double r = sqrt(disc);
        s0 = fmax(0, (-qb - r) / (2 * qa));
        s1 = fmin(1, (-qb + r) / (2 * qa));
        if (s0 > s1)
            return -HUGE_VAL;
    }
    const double g = 0.61803398874989484820;
    double lo = s0, hi = s1;
    double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo);
    double f1 = edge_f(t, a, b, x, y, m1), f2 = edge_f(t, a, b, x, y, m2);
    for (int k = 0; k < DC_GOLDEN_IT; k++) {
        if (f1 < f2) {
            lo = m1;
            m1 = m2;
            f1 = f2;
            m2 = lo + g * (hi - lo);
            f2 = edge_f(t, a, b, x, y, m2);
        } else {
            hi = m2;
            m2 = m1;
            f2 = f1;
            m1 = hi - g * (hi - lo);
            f1 = edge_f(t, a, b, x, y, m1);
        }
    }
    double best = fmax(f1, f2);
    best = fmax(best, edge_f(t, a, b, x, y, s0));
    return fmax(best, edge_f(t, a, b, x, y, s1));
}

/* Is (px, py) inside the triangle's xy projection (boundary included)? */
static bool inside_xy(const cs_dropcut_tri_t *tr, double px, double py)
{
    double s[3];
    for (int i = 0; i < 3; i++) {
        const double *a = tr->v[i], *b = tr->v[(i + 1) % 3];
        s[i] = (b[0] - a[0]) * (py - a[1]) - (b[1] - a[1]) * (px - a[0]);
    }
    return (s[0] >= 0 && s[1] >= 0 && s[2] >= 0) || (s[0] <= 0 && s[1] <= 0 && s[2] <= 0);
}

/* The facet contact: the cutter resting on the triangle's plane. Its torus's tube circle meets
 * the plane's rising direction g at q = c + (R - r) g; the ball of radius r centred over q
 * touches the plane at q - r (nx, ny), at centre height (n.p0 + r - nx qx - ny qy) / nz. */
static double facet_drop(const cs_dropcut_tool_t *t, const cs_dropcut_tri_t *tr, double x,
                         double y)
{
    const double *a = tr->v[0], *b = tr->v[1], *c = tr->v[2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    double len = norm3(n);
    if (len == 0)
        return -HUGE_VAL;
    if (n[2] < 0)
        for (int k = 0; k < 3; k++)
            n[k] = -n[k];
    for (int k = 0; k < 3; k++)
        n[k] /= len;
    if (n[2] < 1e-9) /* vertical: its edges carry the contact */
        return -HUGE_VAL;
    double nh = sqrt(n[0] * n[0] + n[1] * n[1]), a_r = t->r_mm - t->c_mm;
    double qx = x, qy = y;
    if (nh > 0) {
        qx -= a_r * n[0] / nh;
        qy -= a_r * n[1] / nh;
    }
    double cx = qx - t->c_mm * n[0], cy = qy - t->c_mm * n[1];
    if (!inside_xy(tr, cx, cy))
        return -HUGE_VAL;
    double d0 = n[0] * a[0] + n[1] * a[1] + n[2] * a[2];
    double zc = (d0 + t->c_mm - n[0] * qx - n[1] * qy) / n[2];
    return zc - t->c_mm;
}

/* --- queries ------------------------------------------------------------------------------- */

/* Lower bounds on the horizontal distance from the axis (x, y) to a box x0 y0 x1 y1 (a
 * triangle's, a cell's) and to a segment: h is non-decreasing, so no point there holds the
 * cutter higher than the box's highest z minus h(that distance). */
static double box_dist(const double *b, double x, double y)
{
    double dx = x < b[0] ? b[0] - x : x > b[2] ? x - b[2] : 0;
    double dy = y < b[1] ? b[1] - y : y > b[3] ? y - b[3] : 0;
    return sqrt(dx * dx + dy * dy);
}

static double seg_dist(const double a[3], const double b[3], double x, double y)
{
    double bx = b[0] - a[0], by = b[1] - a[1], l2 = bx * bx + by * by;
    double s = l2 > 0 ? ((x - a[0]) * bx + (y - a[1]) * by) / l2 : 0;
    s = s < 0 ? 0 : s > 1 ? 1 : s;
    double ex = a[0] + s * bx - x, ey = a[1] + s * by - y;
    return sqrt(ex * ex + ey * ey);
}

/* A cell of the footprint and the most it can hold the cutter up (its top - h(distance)). */
struct cs_dropcut_cq {
    double bound;
    size_t cell;
};

static int cq_desc(const void *a, const void *b)
{
    double x = ((const struct cs_dropcut_cq *)a)->bound, y = ((const struct cs_dropcut_cq *)b)->bound;
    return x < y ? 1 : x > y ? -1 : 0;
}

/* The footprint's cells that can hold the cutter up at all, highest bound first; false out of
 * memory. */
static bool footprint(cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t, double x, double y,
                      size_t *n)
{
    double r = t->r_mm;
    size_t cx0 = cell_of(ms, x - r, 0), cx1 = cell_of(ms, x + r, 0);
    size_t cy0 = cell_of(ms, y - r, 1), cy1 = cell_of(ms, y + r, 1);
    size_t need = (cx1 - cx0 + 1) * (cy1 - cy0 + 1);
    if (need > ms->cqcap) {
        struct cs_dropcut_cq *q = realloc(ms->cq, need * sizeof *q);
        if (!q)
            return false;
        ms->cq = q;
        ms->cqcap = need;
    }
    *n = 0;
    for (size_t cy = cy0; cy <= cy1; cy++)
        for (size_t cx = cx0; cx <= cx1; cx++) {
            size_t c = cy * ms->gx + cx;
            if (ms->start[c] == ms->start[c + 1])
                continue;
            double b[4] = {ms->box[0] + (double)cx * ms->cell, ms->box[1] + (double)cy * ms->cell};
            b[2] = b[0] + ms->cell;
            b[3] = b[1] + ms->cell;
            double d = box_dist(b, x, y);
            if (d > r)
                continue;
            ms->cq[*n].bound = ms->ctop[c] - cs_dropcut_profile(t, d);
            ms->cq[(*n)++].cell = c;
        }
    qsort(ms->cq, *n, sizeof *ms->cq, cq_desc);
    return true;
}

/* One triangle's contribution (facet, then its edges while they can still beat best). */
static double tri_drop(const cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t, size_t i,
                       double x, double y, double best)
{
    const cs_dropcut_tri_t *tr = &ms->tri[i];
    double d = box_dist(ms->bb[i], x, y);
    if (d > t->r_mm || ms->bb[i][4] - cs_dropcut_profile(t, d) <= best)
        return best;
    best = fmax(best, facet_drop(t, tr, x, y));
    if (ms->bb[i][4] - cs_dropcut_profile(t, d) <= best)
        return best;
    for (int e = 0; e < 3; e++) {
        const double *a = tr->v[e], *b = tr->v[(e + 1) % 3];
        double de = seg_dist(a, b, x, y);
        if (de <= t->r_mm && fmax(a[2], b[2]) - cs_dropcut_profile(t, de) > best)
            best = fmax(best, edge_drop(t, a, b, x, y));
    }
    return best;
}

double cs_dropcut_drop_exact(cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t, double x,
                             double y, bool *hit)
{
    double best = -HUGE_VAL;
    if (ms->query >= UINT_MAX - 3) { /* the stamps would wrap: start them again */
        memset(ms->stamp, 0, ms->ntri * sizeof *ms->stamp);
        ms->query = 0;
    }
    ms->query++;
    double r = t->r_mm;
    size_t n = 0;
    *hit = false;
    if (x + r < ms->box[0] || x - r > ms->box[3] || y + r < ms->box[1] || y - r > ms->box[4])
        return best;
    if (!footprint(ms, t, x, y, &n)) { /* out of memory: stand above the whole mesh */
        *hit = true;
        return ms->box[5];
    }
    /* Cells in decreasing bound: once a cell's bound is at or below the best contact found, no
     * later cell can raise it (a branch-and-bound over the grid). */
    for (size_t q = 0; q < n && ms->cq[q].bound > best; q++) {
        size_t c = ms->cq[q].cell;
        for (size_t k = ms->start[c]; k < ms->start[c + 1]; k++) {
            size_t i = ms->idx[k];
            if (ms->stamp[i] == ms->query)
                continue;
            ms->stamp[i] = ms->query;
            best = tri_drop(ms, t, i, x, y, best);
        }
    }
    *hit = best > -HUGE_VAL;
    return best;
}

double cs_dropcut_drop(cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t, double x, double y,
                       bool *hit)
{
    /* At least DC_EPS_MIN: a cutter whose rim only grazes an edge (d = R to the last bit) is
     * still held up by it, whatever the rounding of the clip. */
    double eps = fmax(ms->eps, DC_EPS_MIN);
    cs_dropcut_tool_t big = {t->r_mm + eps, t->c_mm + eps};
    double z = cs_dropcut_drop_exact(ms, &big, x, y, hit);
    return *hit ? z + eps : z;
}

bool cs_dropcut_top(cs_dropcut_mesh_t *ms, double x, double y, double *z)
{
    double best = -HUGE_VAL;
    if (x >= ms->box[0] && x <= ms->box[3] && y >= ms->box[1] && y <= ms->box[4]) {
        size_t c = cell_of(ms, y, 1) * ms->gx + cell_of(ms, x, 0);
        for (size_t k = ms->start[c]; k < ms->start[c + 1]; k++) {
            const cs_dropcut_tri_t *tr = &ms->tri[ms->idx[k]];
            if (!inside_xy(tr, x, y))
                continue;
            const double *a = tr->v[0], *b = tr->v[1], *cc = tr->v[2];
            /* Barycentric z of (x, y). */
            double det = (b[1] - cc[1]) * (a[0] - cc[0]) + (cc[0] - b[0]) * (a[1] - cc[1]);
            if (fabs(det) < 1e-18) {
                best = fmax(best, fmax(fmax(a[2], b[2]), cc[2]));
                continue;
            }
            double l1 = ((b[1] - cc[1]) * (x - cc[0]) + (cc[0] - b[0]) * (y - cc[1])) / det;
            double l2 = ((cc[1] - a[1]) * (x - cc[0]) + (a[0] - cc[0]) * (y - cc[1])) / det;
            best = fmax(best, l1 * a[2] + l2 * b[2] + (1 - l1 - l2) * cc[2]);
        }
    }
    *z = best;
    return best > -HUGE_VAL;
}

void cs_dropcut_free(cs_dropcut_mesh_t *ms)
{
    free(ms->tri);
    free(ms->start);
    free(ms->idx);
    free(ms->stamp);
    free(ms->bb);
    free(ms->ctop);
    free(ms->cq);
    cs_dropcut_init(ms);
}
