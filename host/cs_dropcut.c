/* cs_dropcut: the mesh, its bound, its grid and the drop-cutter query (see cs_dropcut.h). */
#include "cs_dropcut.h"

#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "cs_conv.h"
#include "cs_finish.h"
#include "cs_fixed.h"
#include "cs_varady.h"

#define DC_GRID_MAX  512  /* cells a patch in each direction, at most */
#define DC_ROOT_IT   100  /* steps of the search for f's peak along a bull-nose's edge, at most */
#define DC_MAX_CELLS 4000 /* grid cells in each direction, at most */
#define DC_CELL_TRIS 16   /* triangles' area a cell (teapot: 9 to 36 within 12 %, 4 far slower) */
#define DC_EPS_MIN   1e-6 /* mm: the least enlargement of the cutter (see cs_dropcut_drop) */

/* The pyramid over DC_MAX_CELLS a side halves down to one node. */
CS_STATIC_ASSERT(DC_MAX_CELLS <= (1 << (CS_DROPCUT_LEVELS - 1)), pyramid_levels_suffice);

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

/* A cell's entry: a triangle, its xy box and its highest z, in floats rounded outwards (a
 * looser box, a higher top: still bounds), so that a query scanning a cell reads one short array
 * and touches a triangle's own data only when its bound can beat the best contact. */
struct cs_dropcut_ent {
    float top, x0, y0, x1, y1;
    uint32_t tri;
};

static size_t cell_of(const cs_dropcut_mesh_t *ms, double v, int axis)
{
    double c = floor((v - ms->box[axis]) / ms->cell);
    size_t lim = axis == 0 ? ms->gx : ms->gy;
    if (c < 0)
        return 0;
    return c >= (double)lim ? lim - 1 : (size_t)c;
}

/* v rounded to a float towards -inf (down) or +inf (up). */
static float f_round(double v, bool up)
{
    float f = (float)v;
    if (up && (double)f < v)
        f = nextafterf(f, HUGE_VALF);
    if (!up && (double)f > v)
        f = nextafterf(f, -HUGE_VALF);
    return f;
}

static struct cs_dropcut_ent tri_ent(const cs_dropcut_tri_t *tr, size_t i)
{
    const double(*v)[3] = tr->v;
    struct cs_dropcut_ent e = {
        f_round(fmax(fmax(v[0][2], v[1][2]), v[2][2]), true),
        f_round(fmin(fmin(v[0][0], v[1][0]), v[2][0]), false),
        f_round(fmin(fmin(v[0][1], v[1][1]), v[2][1]), false),
        f_round(fmax(fmax(v[0][0], v[1][0]), v[2][0]), true),
        f_round(fmax(fmax(v[0][1], v[1][1]), v[2][1]), true),
        (uint32_t)i,
    };
    return e;
}

static int ent_desc(const void *a, const void *b)
{
    float x = ((const struct cs_dropcut_ent *)a)->top, y = ((const struct cs_dropcut_ent *)b)->top;
    return x < y ? 1 : x > y ? -1 : 0;
}

/* The unit normal of triangle tr (nz >= 0) and n . v0 into pl; all 0 when the triangle is
 * degenerate or vertical (no facet contact: its edges carry it). */
static void tri_plane(const cs_dropcut_tri_t *tr, double pl[4])
{
    const double *a = tr->v[0], *b = tr->v[1], *c = tr->v[2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    double len = norm3(n);
    pl[0] = pl[1] = pl[2] = pl[3] = 0;
    if (len == 0)
        return;
    if (n[2] < 0)
        for (int k = 0; k < 3; k++)
            n[k] = -n[k];
    for (int k = 0; k < 3; k++)
        n[k] /= len;
    if (n[2] < 1e-9)
        return;
    for (int k = 0; k < 3; k++)
        pl[k] = n[k];
    pl[3] = n[0] * a[0] + n[1] * a[1] + n[2] * a[2];
}

/* The pyramid's levels over the gx x gy cells, up to one node; its nodes in all. */
static size_t pyramid_size(cs_dropcut_mesh_t *ms)
{
    size_t n = 0, w = ms->gx, h = ms->gy;
    ms->lev = 0;
    for (;;) {
        ms->lgx[ms->lev] = w;
        ms->lgy[ms->lev] = h;
        ms->loff[ms->lev++] = n;
        n += w * h;
        if (w == 1 && h == 1)
            return n;
        w = (w + 1) / 2;
        h = (h + 1) / 2;
    }
}

/* Each node above the cells keeps the highest top of the (up to) 2 x 2 nodes below it. */
static void pyramid_fill(cs_dropcut_mesh_t *ms)
{
    for (size_t l = 1; l < ms->lev; l++) {
        const double *lo = ms->top + ms->loff[l - 1];
        double *up = ms->top + ms->loff[l];
        size_t w = ms->lgx[l - 1], h = ms->lgy[l - 1];
        for (size_t cy = 0; cy < ms->lgy[l]; cy++)
            for (size_t cx = 0; cx < ms->lgx[l]; cx++) {
                double m = -HUGE_VAL;
                for (size_t j = 2 * cy; j < 2 * cy + 2 && j < h; j++)
                    for (size_t i = 2 * cx; i < 2 * cx + 2 && i < w; i++)
                        m = fmax(m, lo[j * w + i]);
                up[cy * ms->lgx[l] + cx] = m;
            }
    }
}

/* Lists every triangle in each cell its box meets (pass 0 counts and keeps the cells' tops, pass
 * 1 fills), then sorts each cell's list highest first. */
static cs_err_t fill_cells(cs_dropcut_mesh_t *ms)
{
    size_t nc = ms->gx * ms->gy;
    for (size_t c = 0; c < nc; c++)
        ms->top[c] = -HUGE_VAL;
    for (int pass = 0; pass < 2; pass++) {
        for (size_t t = 0; t < ms->ntri; t++) {
            struct cs_dropcut_ent e = tri_ent(&ms->tri[t], t);
            for (size_t cy = cell_of(ms, e.y0, 1); cy <= cell_of(ms, e.y1, 1); cy++)
                for (size_t cx = cell_of(ms, e.x0, 0); cx <= cell_of(ms, e.x1, 0); cx++) {
                    size_t c = cy * ms->gx + cx;
                    if (pass == 0) {
                        ms->start[c + 1]++;
                        ms->top[c] = fmax(ms->top[c], e.top);
                    } else {
                        ms->ent[ms->start[c]++] = e;
                    }
                }
        }
        if (pass == 0) {
            for (size_t c = 0; c < nc; c++)
                ms->start[c + 1] += ms->start[c];
            ms->ent = malloc((ms->start[nc] + 1) * sizeof *ms->ent);
            if (!ms->ent)
                return CS_ERR_FULL;
        }
    }
    for (size_t c = nc; c > 0; c--) /* the second pass moved each start to its end */
        ms->start[c] = ms->start[c - 1];
    ms->start[0] = 0;
    for (size_t c = 0; c < nc; c++)
        qsort(ms->ent + ms->start[c], ms->start[c + 1] - ms->start[c], sizeof *ms->ent, ent_desc);
    return CS_OK;
}

cs_err_t cs_dropcut_index(cs_dropcut_mesh_t *ms, double rmax_mm)
{
    if (ms->ntri == 0)
        return CS_ERR_DEGENERATE;
    if ((uint64_t)ms->ntri > UINT32_MAX) /* a cell entry holds the number in 32 bits */
        return CS_ERR_FULL;
    double w = ms->box[3] - ms->box[0], h = ms->box[4] - ms->box[1];
    /* Cells of about DC_CELL_TRIS triangles' area (a query stops early in each: its list is
     * highest first), and no finer than a tool radius needs. */
    double cell = sqrt(fmax(w * h, 1e-12) / (double)ms->ntri * DC_CELL_TRIS);
    cell = fmax(cell, fmax(w, h) / DC_MAX_CELLS);
    cell = fmax(cell, fmin(rmax_mm, fmax(w, h)) / 16);
    ms->cell = fmax(cell, 1e-6);
    ms->gx = (size_t)(w / ms->cell) + 1;
    ms->gy = (size_t)(h / ms->cell) + 1;
    ms->start = calloc(ms->gx * ms->gy + 1, sizeof *ms->start);
    ms->stamp = calloc(ms->ntri, sizeof *ms->stamp);
    ms->top = malloc(pyramid_size(ms) * sizeof *ms->top);
    ms->pl = malloc(ms->ntri * sizeof *ms->pl);
    if (!ms->start || !ms->stamp || !ms->top || !ms->pl || fill_cells(ms) != CS_OK)
        return CS_ERR_FULL;
    for (size_t t = 0; t < ms->ntri; t++)
        tri_plane(&ms->tri[t], ms->pl[t]);
    pyramid_fill(ms);
    return CS_OK;
}

/* --- one triangle ------------------------------------------------------------------------- */

/* The profile at the horizontal distance sqrt(d2): a ball's with one square root. */
static double profile2(const cs_dropcut_tool_t *t, double d2)
{
    if (t->c_mm >= t->r_mm) {
        double q = t->c_mm * t->c_mm - d2;
        return t->c_mm - sqrt(q > 0 ? q : 0);
    }
    return cs_dropcut_profile(t, sqrt(d2));
}

/* Can a point at horizontal distance sqrt(d2) <= R and height at most top hold the cutter above
 * best, top - h > best? For a ball without a square root: h < top - best, i.e.
 * sqrt(R^2 - d2) > R - (top - best), always when the right side is negative. */
static bool can_beat(const cs_dropcut_tool_t *t, double top, double d2, double best)
{
    if (t->c_mm >= t->r_mm) {
        double m = t->c_mm - (top - best);
        return m < 0 || t->c_mm * t->c_mm - d2 > m * m;
    }
    return top - profile2(t, d2) > best;
}

/* f(p) = p.z - h(d) along the edge a -> b, for s in [s0, s1] where d <= R: concave in s. */
static double edge_f(const cs_dropcut_tool_t *t, const double a[3], const double b[3], double x,
                     double y, double s)
{
    double px = a[0] + s * (b[0] - a[0]) - x, py = a[1] + s * (b[1] - a[1]) - y;
    double d2 = px * px + py * py, r2 = t->r_mm * t->r_mm;
    if (d2 > r2)
        d2 = r2; /* only at the span's ends, by rounding */
    return a[2] + s * (b[2] - a[2]) - profile2(t, d2);
}

/* The edge's s range where the axis is within R (roots of a quadratic); false when empty. */
static bool edge_span(const cs_dropcut_tool_t *t, const double a[3], const double b[3], double x,
                      double y, double *s0, double *s1)
{
    /* d(s)^2 = |A + s B|^2 <= R^2. */
    double ax = a[0] - x, ay = a[1] - y, bx = b[0] - a[0], by = b[1] - a[1];
    double qa = bx * bx + by * by, qb = 2 * (ax * bx + ay * by);
    double qc = ax * ax + ay * ay - t->r_mm * t->r_mm;
    *s0 = 0;
    *s1 = 1;
    if (qa < 1e-24)
        return qc <= 0;
    double disc = qb * qb - 4 * qa * qc;
    if (disc < 0)
        return false;
    double r = sqrt(disc);
    *s0 = fmax(0, (-qb - r) / (2 * qa));
    *s1 = fmin(1, (-qb + r) / (2 * qa));
    return *s0 <= *s1;
}

/* Where a ball's f peaks along the edge's line: in the vertical plane of the line, at distance
 * dp from the axis, the ball's section is a circle of radius rho = sqrt(R^2 - dp^2) and
 * f(tau) = z(foot) + m tau - R + sqrt(rho^2 - tau^2) (tau along the line from the axis's foot,
 * m the line's slope), whose derivative vanishes at tau = m rho / sqrt(1 + m^2). A vertical edge
 * (no length in xy) peaks at its higher end. */
static double ball_peak(const cs_dropcut_tool_t *t, const double a[3], const double b[3], double x,
                        double y)
{
    double bx = b[0] - a[0], by = b[1] - a[1], l2 = bx * bx + by * by;
    if (l2 < 1e-24)
        return b[2] >= a[2] ? 1 : 0;
    double l = sqrt(l2), m = (b[2] - a[2]) / l;
    double foot = ((x - a[0]) * bx + (y - a[1]) * by) / l; /* mm along the line */
    double dp = ((x - a[0]) * by - (y - a[1]) * bx) / l;
    double rho2 = t->r_mm * t->r_mm - dp * dp;
    double rho = sqrt(rho2 > 0 ? rho2 : 0);
    return (foot + m * rho / sqrt(1 + m * m)) / l;
}

/* f'(s) along the edge: z's slope less h'(d) d'(s), h'(d) = e / sqrt(r^2 - e^2) with
 * e = d - (R - r) past the flat bottom (0 on it); +-HUGE_VAL where the corner turns vertical
 * (e = r). */
static double edge_df(const cs_dropcut_tool_t *t, const double a[3], const double b[3], double x,
                      double y, double s)
{
    double ux = b[0] - a[0], uy = b[1] - a[1];
    double px = a[0] + s * ux - x, py = a[1] + s * uy - y, d = sqrt(px * px + py * py);
    double e = d - (t->r_mm - t->c_mm);
    if (e <= 0)
        return b[2] - a[2];
    double q = t->c_mm * t->c_mm - e * e, dd = (px * ux + py * uy) / d;
    if (q <= 0)
        return dd > 0 ? -HUGE_VAL : dd < 0 ? HUGE_VAL : b[2] - a[2];
    return b[2] - a[2] - e / sqrt(q) * dd;
}

/* A bull-nose's maximum of f over [s0, s1]: f is concave, so f' falls; its root is bracketed
 * and found by regula falsi with the Illinois step (bisection where f' is infinite), to 1e-12
 * of the span; f at the bracket's ends, points of the edge, bounds the maximum from below. */
static double bull_peak(const cs_dropcut_tool_t *t, const double a[3], const double b[3], double x,
                        double y, double s0, double s1)
{
    double lo = s0, hi = s1, glo = edge_df(t, a, b, x, y, lo), ghi = edge_df(t, a, b, x, y, hi);
    if (glo <= 0 || ghi >= 0) /* the peak at an end: edge_drop has both */
        return -HUGE_VAL;
    int side = 0;
    for (int k = 0; k < DC_ROOT_IT && hi - lo > 1e-12 * (s1 - s0 + 1e-300); k++) {
        double m = isinf(glo) || isinf(ghi) ? (lo + hi) / 2 : (lo * ghi - hi * glo) / (ghi - glo);
        if (!(m > lo && m < hi))
            m = (lo + hi) / 2;
        double gm = edge_df(t, a, b, x, y, m);
        if (gm > 0) {
            lo = m;
            glo = gm;
            if (side == 1)
                ghi /= 2; /* Illinois: the end kept twice weighs half */
            side = 1;
        } else if (gm < 0) {
            hi = m;
            ghi = gm;
            if (side == -1)
                glo /= 2;
            side = -1;
        } else {
            lo = hi = m;
        }
    }
    return fmax(edge_f(t, a, b, x, y, lo), edge_f(t, a, b, x, y, hi));
}

/* f's maximum along the edge (concave in s): a ball's closed-form peak, or the end of the span
 * nearer to it (concavity); a flat end's higher end of the span (f is linear there); a
 * bull-nose's where f' changes sign (bull_peak). */
static double edge_drop(const cs_dropcut_tool_t *t, const double a[3], const double b[3],
                        double x, double y)
{
    double s0, s1;
    if (!edge_span(t, a, b, x, y, &s0, &s1))
        return -HUGE_VAL;
    if (t->c_mm >= t->r_mm) {
        double s = ball_peak(t, a, b, x, y);
        return edge_f(t, a, b, x, y, s < s0 ? s0 : s > s1 ? s1 : s);
    }
    double best = fmax(edge_f(t, a, b, x, y, s0), edge_f(t, a, b, x, y, s1));
    if (t->c_mm <= 0)
        return best;
    return fmax(best, bull_peak(t, a, b, x, y, s0, s1));
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

/* The facet contact: the cutter resting on the triangle's plane (unit normal n, nz > 0, and
 * n . v0 in pl). Its torus's tube circle meets the plane's rising direction g at
 * q = c + (R - r) g; the ball of radius r centred over q touches the plane at q - r (nx, ny), at
 * centre height (n.p0 + r - nx qx - ny qy) / nz. The cutter then lies on or above the whole
 * plane, so the tip height is also a bound on what any point of the triangle can hold it up to:
 * *in tells whether the contact lies inside the triangle (the bound is then the drop). */
static double facet_drop(const cs_dropcut_tool_t *t, const cs_dropcut_tri_t *tr, const double *pl,
                         double x, double y, bool *in)
{
    double a_r = t->r_mm - t->c_mm;
    double qx = x, qy = y;
    if (a_r > 0) {
        double nh = sqrt(pl[0] * pl[0] + pl[1] * pl[1]);
        if (nh > 0) {
            qx -= a_r * pl[0] / nh;
            qy -= a_r * pl[1] / nh;
        }
    }
    double cx = qx - t->c_mm * pl[0], cy = qy - t->c_mm * pl[1];
    *in = inside_xy(tr, cx, cy);
    double zc = (pl[3] + t->c_mm - pl[0] * qx - pl[1] * qy) / pl[2];
    return zc - t->c_mm;
}

/* --- queries ------------------------------------------------------------------------------- */

/* Squared lower bounds on the horizontal distance from the axis (x, y) to a box x0 y0 x1 y1 (a
 * node's, a triangle's) and to a segment: h is non-decreasing, so no point there holds the
 * cutter higher than the box's highest z minus h(that distance). */
static double box_dist2(double x0, double y0, double x1, double y1, double x, double y)
{
    double dx = x < x0 ? x0 - x : x > x1 ? x - x1 : 0;
    double dy = y < y0 ? y0 - y : y > y1 ? y - y1 : 0;
    return dx * dx + dy * dy;
}

static double seg_dist2(const double a[3], const double b[3], double x, double y)
{
    double bx = b[0] - a[0], by = b[1] - a[1], l2 = bx * bx + by * by;
    double s = l2 > 0 ? ((x - a[0]) * bx + (y - a[1]) * by) / l2 : 0;
    s = s < 0 ? 0 : s > 1 ? 1 : s;
    double ex = a[0] + s * bx - x, ey = a[1] + s * by - y;
    return ex * ex + ey * ey;
}

/* A node of the pyramid (level lev, column cx, row cy) and the most it can hold the cutter up
 * (its top - h(distance from the axis to its box)). */
struct cs_dropcut_cq {
    double bound;
    unsigned lev, cx, cy;
};

/* Pushes the node onto the query's max-heap of bounds when it can hold the cutter above best;
 * false out of memory. */
static bool heap_push(cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t, size_t *n, double x,
                      double y, double best, size_t lev, size_t cx, size_t cy)
{
    double top = ms->top[ms->loff[lev] + cy * ms->lgx[lev] + cx];
    if (top <= best)
        return true; /* empty (-HUGE_VAL) or too low to matter */
    double size = ms->cell * (double)((size_t)1 << lev);
    double x0 = ms->box[0] + (double)cx * size, y0 = ms->box[1] + (double)cy * size;
    double d2 = box_dist2(x0, y0, x0 + size, y0 + size, x, y);
    if (d2 > t->r_mm * t->r_mm || !can_beat(t, top, d2, best))
        return true;
    double bound = top - profile2(t, d2);
    if (*n == ms->cqcap) {
        size_t cap = ms->cqcap ? 2 * ms->cqcap : 256;
        struct cs_dropcut_cq *q = realloc(ms->cq, cap * sizeof *q);
        if (!q)
            return false;
        ms->cq = q;
        ms->cqcap = cap;
    }
    struct cs_dropcut_cq nd = {bound, (unsigned)lev, (unsigned)cx, (unsigned)cy};
    size_t i = (*n)++;
    while (i > 0 && ms->cq[(i - 1) / 2].bound < nd.bound) { /* sift up */
        ms->cq[i] = ms->cq[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    ms->cq[i] = nd;
    return true;
}

/* Removes the heap's highest node into *out. */
static void heap_pop(cs_dropcut_mesh_t *ms, size_t *n, struct cs_dropcut_cq *out)
{
    *out = ms->cq[0];
    struct cs_dropcut_cq last = ms->cq[--*n];
    size_t i = 0;
    for (;;) { /* sift down */
        size_t c = 2 * i + 1;
        if (c >= *n)
            break;
        if (c + 1 < *n && ms->cq[c + 1].bound > ms->cq[c].bound)
            c++;
        if (ms->cq[c].bound <= last.bound)
            break;
        ms->cq[i] = ms->cq[c];
        i = c;
    }
    if (*n > 0)
        ms->cq[i] = last;
}

/* One triangle's contribution: skipped when its box and top cannot beat best; else the facet
 * contact on its plane, which bounds the whole triangle (skipped when that cannot beat best)
 * and is its drop when the contact lies inside; else its edges, each while it can beat best. */
static double tri_drop(const cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                       const struct cs_dropcut_ent *en, double x, double y, double best)
{
    double d2 = box_dist2(en->x0, en->y0, en->x1, en->y1, x, y), r2 = t->r_mm * t->r_mm;
    if (d2 > r2 || !can_beat(t, en->top, d2, best))
        return best;
    const cs_dropcut_tri_t *tr = &ms->tri[en->tri];
    const double *pl = ms->pl[en->tri];
    if (pl[2] > 0) { /* not vertical */
        bool in;
        double zf = facet_drop(t, tr, pl, x, y, &in);
        if (zf <= best || in)
            return fmax(best, zf);
    }
    for (int e = 0; e < 3; e++) {
        const double *a = tr->v[e], *b = tr->v[(e + 1) % 3];
        double de2 = seg_dist2(a, b, x, y);
        if (de2 <= r2 && can_beat(t, fmax(a[2], b[2]), de2, best))
            best = fmax(best, edge_drop(t, a, b, x, y));
    }
    return best;
}

/* The triangles of cell c not visited yet by this query, highest first while they can beat
 * best. */
static double cell_drop(cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t, size_t c, double x,
                        double y, double best)
{
    for (size_t k = ms->start[c]; k < ms->start[c + 1] && ms->ent[k].top > best; k++) {
        uint32_t i = ms->ent[k].tri;
        if (ms->stamp[i] == ms->query)
            continue;
        ms->stamp[i] = ms->query;
        best = tri_drop(ms, t, &ms->ent[k], x, y, best);
    }
    return best;
}

double cs_dropcut_drop_exact(cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t, double x,
                             double y, bool *hit)
{
    double best = -HUGE_VAL, r = t->r_mm;
    if (ms->query >= UINT_MAX - 3) { /* the stamps would wrap: start them again */
        memset(ms->stamp, 0, ms->ntri * sizeof *ms->stamp);
        ms->query = 0;
    }
    ms->query++;
    *hit = false;
    if (x + r < ms->box[0] || x - r > ms->box[3] || y + r < ms->box[1] || y - r > ms->box[4])
        return best;
    /* Start at the lowest level whose nodes are at least the footprint's width (at most 2 x 2
     * of them cover it), then branch and bound: the node of highest bound is split into its
     * children, a cell's triangles are dropped on; once the highest bound is at or below the
     * best contact found, nothing left can raise it. */
    size_t lev = 0, n = 0;
    while (lev + 1 < ms->lev && ms->cell * (double)((size_t)1 << lev) < 2 * r)
        lev++;
    size_t span = (size_t)1 << lev;
    bool ok = true;
    for (size_t cy = cell_of(ms, y - r, 1) / span; ok && cy <= cell_of(ms, y + r, 1) / span; cy++)
        for (size_t cx = cell_of(ms, x - r, 0) / span; ok && cx <= cell_of(ms, x + r, 0) / span;
             cx++)
            ok = heap_push(ms, t, &n, x, y, best, lev, cx, cy);
    while (ok && n > 0 && ms->cq[0].bound > best) {
        struct cs_dropcut_cq nd;
        heap_pop(ms, &n, &nd);
        if (nd.lev == 0) {
            best = cell_drop(ms, t, nd.cy * ms->gx + nd.cx, x, y, best);
            continue;
        }
        size_t l = nd.lev - 1, y0 = 2 * (size_t)nd.cy, x0 = 2 * (size_t)nd.cx;
        for (size_t cy = y0; ok && cy < y0 + 2 && cy < ms->lgy[l]; cy++)
            for (size_t cx = x0; ok && cx < x0 + 2 && cx < ms->lgx[l]; cx++)
                ok = heap_push(ms, t, &n, x, y, best, l, cx, cy);
    }
    if (!ok) { /* out of memory: stand above the whole mesh */
        *hit = true;
        return ms->box[5];
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
        for (size_t k = ms->start[c]; k < ms->start[c + 1] && ms->ent[k].top > best; k++) {
            const struct cs_dropcut_ent *en = &ms->ent[k];
            const cs_dropcut_tri_t *tr = &ms->tri[en->tri];
            if (x < en->x0 || x > en->x1 || y < en->y0 || y > en->y1 || !inside_xy(tr, x, y))
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
    free(ms->ent);
    free(ms->stamp);
    free(ms->pl);
    free(ms->top);
    free(ms->cq);
    cs_dropcut_init(ms);
}
