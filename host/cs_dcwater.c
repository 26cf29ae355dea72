/* cs_dcwater: waterline contours of the drop-cutter surface (cs_dcwater.h). Marching squares
 * on a grid of drop values (the classic 16 cases, the saddles decided by the drop at the cell's
 * centre), contour points by bisection along the grid edges, chained edge to edge; added levels
 * on shallow ground (the cells of a node mask only), flat areas by a clipped raster. */
#include "cs_dcwater.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "cs_dclevel.h"

#define WL_LEVEL_DEPTH 4     /* halvings of a level step on shallow ground: down to 1/16 */
#define WL_KINK        0.15  /* a concave corner: second difference over distance, at least */
#define WL_CORNER_DIV  4     /* the corner rasters' step-over: the flat-ground one over this */
#define WL_MAX_DEPTH 12      /* chord refinements of one contour segment */
#define WL_MAX_NODES 4000000 /* grid nodes, at most */
#define WL_NONE      SIZE_MAX

typedef struct {
    cs_dropcut_mesh_t *ms;
    const cs_dropcut_tool_t *t;
    const cs_dcpath_opts_t *o;
    double gx, gy, lev;
    size_t nx, ny, nh, ne; /* nodes across, down; horizontal edges; all edges */
    double *z;             /* drop at each node */
    unsigned char *surf;   /* per node: the cutter rests on the surface, not on the floor */
    double *allow;         /* per node: the level step its slope allows (cs_dclevel) */
    double *allow3;        /* per node: the least of allow over it and its 8 neighbours */
    unsigned char *mask;   /* NULL: every node; else the nodes a clipped level uses */
    unsigned char *band;   /* scratch: the nodes of a band that want an added level */
    double dz_fin;         /* the least level step; ground wanting less is a flat area */
    double (*ep)[2];       /* per edge: its contour point at this level */
    size_t (*nb)[2];       /* per edge: the edges joined to it by a cell's segment */
    unsigned char *deg, *seen;
    double (*pt)[3]; /* the contour being built */
    size_t n, cap;
    size_t drops;
} wl_t;

double cs_dcwater_zstep(const cs_dropcut_tool_t *t, double h)
{
    double r = t->c_mm;
    if (r <= 0)
        return h;
    double hh = fmin(h, r);
    return 2 * sqrt(2 * r * hh - hh * hh);
}

static double drop(wl_t *w, double x, double y)
{
    bool hit;
    double z = cs_dropcut_drop(w->ms, w->t, x, y, &hit);
    w->drops++;
    return hit ? fmax(z, w->o->min_z) : w->o->min_z;
}

/* Bisects between in (z_d > lev) and out (z_d <= lev) down to tol / 2; out ends outside. */
static void bisect(wl_t *w, double in[2], double out[2])
{
    while (hypot(out[0] - in[0], out[1] - in[1]) > w->o->tol_mm / 2) {
        double m[2] = {(in[0] + out[0]) / 2, (in[1] + out[1]) / 2};
        double *side = drop(w, m[0], m[1]) > w->lev ? in : out;
        side[0] = m[0];
        side[1] = m[1];
    }
}

static void node_xy(const wl_t *w, size_t i, size_t j, double p[2])
{
    p[0] = w->o->box[0] + (double)i * w->gx;
    p[1] = w->o->box[1] + (double)j * w->gy;
}

/* Edge e's two nodes (horizontal edges first, then vertical). */
static void edge_nodes(const wl_t *w, size_t e, size_t a[2], size_t b[2])
{
    if (e < w->nh) {
        a[0] = e % (w->nx - 1), a[1] = e / (w->nx - 1), b[0] = a[0] + 1, b[1] = a[1];
    } else {
        a[0] = (e - w->nh) % w->nx, a[1] = (e - w->nh) / w->nx, b[0] = a[0], b[1] = a[1] + 1;
    }
}

/* The contour point on edge e (whose ends lie on either side of the level). */
static void edge_point(wl_t *w, size_t e)
{
    size_t a[2], b[2];
    edge_nodes(w, e, a, b);
    double pa[2], pb[2];
    node_xy(w, a[0], a[1], pa);
    node_xy(w, b[0], b[1], pb);
    bool ina = w->z[a[1] * w->nx + a[0]] > w->lev;
    bisect(w, ina ? pa : pb, ina ? pb : pa);
    memcpy(w->ep[e], ina ? pb : pa, sizeof w->ep[e]);
}

static void join(wl_t *w, size_t e, size_t f)
{
    w->nb[e][w->deg[e]++] = f;
    w->nb[f][w->deg[f]++] = e;
}

/* Cell (i, j)'s segments: corner k (0 (i,j), 1 (i+1,j), 2 (i+1,j+1), 3 (i,j+1)) lies between
 * edges k - 1 and k (0 bottom, 1 right, 2 top, 3 left); every corner on the other side of the
 * level from the rest (or, in a saddle, from the cell's centre) is cut off by a segment. */
static void cell(wl_t *w, size_t i, size_t j)
{
    size_t nx = w->nx;
    bool in[4] = {w->z[j * nx + i] > w->lev, w->z[j * nx + i + 1] > w->lev,
                  w->z[(j + 1) * nx + i + 1] > w->lev, w->z[(j + 1) * nx + i] > w->lev};
    int nin = in[0] + in[1] + in[2] + in[3];
    if (nin == 0 || nin == 4)
        return;
    size_t e[4] = {j * (nx - 1) + i, w->nh + j * nx + i + 1, (j + 1) * (nx - 1) + i,
                   w->nh + j * nx + i};
    bool centre = nin == 3;
    if (nin == 2 && in[0] == in[2]) { /* a saddle */
        double c[2];
        node_xy(w, i, j, c);
        centre = drop(w, c[0] + w->gx / 2, c[1] + w->gy / 2) > w->lev;
    } else if (nin == 2) { /* two neighbouring corners each side: one segment across */
        if (in[0] == in[1])
            join(w, e[3], e[1]);
        else
            join(w, e[0], e[2]);
        return;
    }
    for (int k = 0; k < 4; k++)
        if (in[k] != centre)
            join(w, e[(k + 3) % 4], e[k]);
}

static bool push(wl_t *w, const double p[2])
{
    if (w->n == w->cap) {
        size_t cap = w->cap ? 2 * w->cap : 256;
        double(*np)[3] = realloc(w->pt, cap * sizeof *np);
        if (!np)
            return false;
        w->pt = np;
        w->cap = cap;
    }
    w->pt[w->n][0] = p[0];
    w->pt[w->n][1] = p[1];
    w->pt[w->n++][2] = w->lev;
    return true;
}

/* A point with z_d <= lev near m, across the chord a -> b: m itself, or found stepping out
 * along the chord's normal (both ways, up to a grid cell) and bisected back to tol / 2. */
static bool outside_near(wl_t *w, const double a[2], const double b[2], double m[2])
{
    if (drop(w, m[0], m[1]) <= w->lev)
        return true;
    double len = hypot(b[0] - a[0], b[1] - a[1]);
    double n[2] = {-(b[1] - a[1]) / len, (b[0] - a[0]) / len};
    for (double d = w->o->tol_mm / 2; d <= 2 * fmax(w->gx, w->gy); d *= 2)
        for (int s = -1; s <= 1; s += 2) {
            double q[2] = {m[0] + s * d * n[0], m[1] + s * d * n[1]};
            if (drop(w, q[0], q[1]) <= w->lev) {
                double in[2] = {m[0], m[1]};
                bisect(w, in, q);
                memcpy(m, q, sizeof q);
                return true;
            }
        }
    return false;
}

/* Pushes the points strictly between a and b (then b) that keep the chords' drops within
 * tol / 2 of the level: the middle and quarters of each chord are dropped. */
static bool refine(wl_t *w, const double a[2], const double b[2], int depth)
{
    double worst = -HUGE_VAL;
    for (int k = 1; k <= 3; k++)
        worst = fmax(worst, drop(w, a[0] + (b[0] - a[0]) * k / 4, a[1] + (b[1] - a[1]) * k / 4));
    double m[2] = {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2};
    if (worst - w->lev > w->o->tol_mm / 2 && depth < WL_MAX_DEPTH &&
        hypot(b[0] - a[0], b[1] - a[1]) > w->o->tol_mm / 2 && outside_near(w, a, b, m))
        return refine(w, a, m, depth + 1) && refine(w, m, b, depth + 1);
    return push(w, b);
}

/* Walks the chain from edge s (an end, or any edge of a loop) into one pass. */
static cs_err_t chain(wl_t *w, cs_dcpath_t *p, size_t s)
{
    w->n = 0;
    size_t prev = WL_NONE, cur = s;
    if (!push(w, w->ep[s]))
        return CS_ERR_FULL;
    w->seen[s] = 1;
    for (;;) {
        size_t next = WL_NONE;
        for (unsigned k = 0; k < w->deg[cur]; k++)
            if (w->nb[cur][k] != prev && (!w->seen[w->nb[cur][k]] || (w->nb[cur][k] == s && w->n > 2)))
                next = w->nb[cur][k];
        if (next == WL_NONE)
            break;
        if (!refine(w, w->ep[cur], w->ep[next], 0))
            return CS_ERR_FULL;
        if (next == s)
            break;
        w->seen[next] = 1;
        prev = cur;
        cur = next;
    }
    return w->n > 1 ? cs_dcpath_append(p, (const double(*)[3])w->pt, w->n, w->lev) : CS_OK;
}

static bool on(const wl_t *w, size_t i, size_t j)
{
    return !w->mask || w->mask[j * w->nx + i];
}

/* One level: the edges' contour points, the cells' segments, the chains (open ones first). With
 * a mask only the edges and cells whose nodes all lie in it: the chains end at its border. */
static cs_err_t level(wl_t *w, cs_dcpath_t *p)
{
    memset(w->deg, 0, w->ne);
    memset(w->seen, 0, w->ne);
    for (size_t e = 0; e < w->ne; e++) {
        size_t a[2], b[2];
        edge_nodes(w, e, a, b);
        if ((w->z[a[1] * w->nx + a[0]] > w->lev) != (w->z[b[1] * w->nx + b[0]] > w->lev) &&
            on(w, a[0], a[1]) && on(w, b[0], b[1]))
            edge_point(w, e);
    }
    for (size_t j = 0; j + 1 < w->ny; j++)
        for (size_t i = 0; i + 1 < w->nx; i++)
            if (on(w, i, j) && on(w, i + 1, j) && on(w, i, j + 1) && on(w, i + 1, j + 1))
                cell(w, i, j);
    cs_err_t e = CS_OK;
    for (unsigned want = 1; want <= 2 && e == CS_OK; want++)
        for (size_t s = 0; s < w->ne && e == CS_OK; s++)
            if (w->deg[s] == want && !w->seen[s])
                e = chain(w, p, s);
    return e;
}

/* The grid: spacing at most R / 4 (the raster's base sampling), its drops, the top; which
 * nodes rest on the surface (a hit at or above the floor). */
static cs_err_t grid(wl_t *w, double *top)
{
    const double *b = w->o->box;
    double g = fmax(w->t->r_mm / 4, w->o->tol_mm);
    w->nx = (size_t)ceil((b[2] - b[0]) / g) + 1;
    w->ny = (size_t)ceil((b[3] - b[1]) / g) + 1;
    if (w->nx < 2 || w->ny < 2 || w->nx * w->ny > WL_MAX_NODES)
        return CS_ERR_RANGE;
    w->gx = (b[2] - b[0]) / (double)(w->nx - 1);
    w->gy = (b[3] - b[1]) / (double)(w->ny - 1);
    w->nh = (w->nx - 1) * w->ny;
    w->ne = w->nh + w->nx * (w->ny - 1);
    size_t nn = w->nx * w->ny;
    w->z = malloc(nn * sizeof *w->z);
    w->allow = malloc(nn * sizeof *w->allow);
    w->allow3 = malloc(nn * sizeof *w->allow3);
    w->surf = malloc(nn);
    w->band = malloc(nn);
    w->ep = malloc(w->ne * sizeof *w->ep);
    w->nb = malloc(w->ne * sizeof *w->nb);
    w->deg = malloc(w->ne);
    w->seen = malloc(w->ne);
    if (!w->z || !w->allow || !w->allow3 || !w->surf || !w->band || !w->ep || !w->nb || !w->deg || !w->seen)
        return CS_ERR_FULL;
    *top = -HUGE_VAL;
    for (size_t j = 0; j < w->ny; j++)
        for (size_t i = 0; i < w->nx; i++) {
            double q[2];
            bool hit;
            node_xy(w, i, j, q);
            double z = cs_dropcut_drop(w->ms, w->t, q[0], q[1], &hit);
            w->drops++;
            w->surf[j * w->nx + i] = hit && z >= w->o->min_z;
            w->z[j * w->nx + i] = hit ? fmax(z, w->o->min_z) : w->o->min_z;
            *top = fmax(*top, w->z[j * w->nx + i]);
        }
    return CS_OK;
}

/* Is node (i, j) a concave corner of the drop surface: along x, y or a diagonal, is the second
 * difference z(a) + z(b) - 2 z(n) over its two neighbours more than WL_KINK times their
 * distance? A valley's floor (the cutter on two flanks at once: the lid-rim slot) or the foot
 * of a wall (the cutter against a knob); a bowl's gentle bend is not. Levels cannot serve it:
 * the grid does not see a floor narrower than its cells, and the lowest level above a foot may
 * stand a level step above the best cutter there. */
static bool corner(const wl_t *w, size_t i, size_t j)
{
    static const int d[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};
    size_t nx = w->nx;
    double zc = w->z[j * nx + i];
    if (i == 0 || j == 0 || i + 1 == nx || j + 1 == w->ny)
        return false;
    for (int k = 0; k < 4; k++) {
        size_t a = (size_t)((long)j + d[k][1]) * nx + i + (size_t)d[k][0];
        size_t b = (size_t)((long)j - d[k][1]) * nx + i - (size_t)d[k][0];
        double len = hypot(d[k][0] * w->gx, d[k][1] * w->gy);
        if (w->z[a] + w->z[b] - 2 * zc > WL_KINK * len)
            return true;
    }
    return false;
}

/* Each node's allowed level step: its slope by central differences (one-sided at the border);
 * a concave corner is marked (surf 2) for the corner passes. */
static void slopes(wl_t *w, const cs_dclevel_t *tab)
{
    size_t nx = w->nx, ny = w->ny;
    for (size_t j = 0; j < ny; j++)
        for (size_t i = 0; i < nx; i++) {
            size_t i0 = i ? i - 1 : i, i1 = i + 1 < nx ? i + 1 : i;
            size_t j0 = j ? j - 1 : j, j1 = j + 1 < ny ? j + 1 : j;
            double sx = (w->z[j * nx + i1] - w->z[j * nx + i0]) / ((double)(i1 - i0) * w->gx);
            double sy = (w->z[j1 * nx + i] - w->z[j0 * nx + i]) / ((double)(j1 - j0) * w->gy);
            w->allow[j * nx + i] = cs_dclevel_at(tab, hypot(sx, sy));
            if (w->surf[j * nx + i] && corner(w, i, j))
                w->surf[j * nx + i] = 2;
        }
    /* A contour runs between nodes and the slope bends between them (a rim's curl): a band asks
     * for the least step any node next to its own allows. */
    for (size_t j = 0; j < ny; j++)
        for (size_t i = 0; i < nx; i++) {
            double m = HUGE_VAL;
            for (size_t b = j ? j - 1 : j; b <= j + 1 && b < ny; b++)
                for (size_t a = i ? i - 1 : i; a <= i + 1 && a < nx; a++)
                    m = fmin(m, w->allow[b * nx + a]);
            w->allow3[j * nx + i] = m;
        }
}

void cs_dcwater_dilate(const unsigned char *src, unsigned char *dst, size_t nx, size_t ny,
                       double gx, double gy, double rho)
{
    long ri = (long)ceil(rho / gx), rj = (long)ceil(rho / gy);
    memset(dst, 0, nx * ny);
    for (long j = 0; j < (long)ny; j++)
        for (long i = 0; i < (long)nx; i++) {
            if (!src[j * (long)nx + i])
                continue;
            for (long dj = -rj; dj <= rj; dj++)
                for (long di = -ri; di <= ri; di++) {
                    long a = i + di, c = j + dj;
                    double dx = (double)di * gx, dy = (double)dj * gy;
                    if (a >= 0 && c >= 0 && a < (long)nx && c < (long)ny &&
                        dx * dx + dy * dy <= rho * rho)
                        dst[c * (long)nx + a] = 1;
                }
        }
}

static bool kept(const cs_dcwater_mask_t *m, const double *q)
{
    double fi = floor((q[0] - m->x0) / m->gx + 0.5), fj = floor((q[1] - m->y0) / m->gy + 0.5);
    size_t i = fi < 0 ? 0 : fi >= (double)m->nx ? m->nx - 1 : (size_t)fi;
    size_t j = fj < 0 ? 0 : fj >= (double)m->ny ? m->ny - 1 : (size_t)fj;
    return m->on[j * m->nx + i] != 0;
}

cs_err_t cs_dcwater_clip(cs_dcpath_t *out, const cs_dcpath_t *in, const cs_dcwater_mask_t *m)
{
    for (size_t k = 0; k < in->npass; k++) {
        size_t i = in->start[k], end = in->start[k + 1];
        while (i < end) {
            while (i < end && !kept(m, in->pt[i]))
                i++;
            size_t s = i;
            while (i < end && kept(m, in->pt[i]))
                i++;
            if (i - s >= 2 &&
                cs_dcpath_append(out, (const double(*)[3])in->pt + s, i - s, in->w[k]) != CS_OK)
                return CS_ERR_FULL;
        }
    }
    return CS_OK;
}

/* Does a surface node with its drop in [lo, hi] want a level step below dz (and not below the
 * least step: flat ground)? Marks them in w->band; returns whether any. */
static bool wanting(wl_t *w, double hi, double lo, double dz)
{
    bool any = false;
    for (size_t k = 0; k < w->nx * w->ny; k++) {
        w->band[k] = w->surf[k] && w->z[k] >= lo && w->z[k] <= hi && w->allow3[k] < dz &&
                     w->allow3[k] >= w->dz_fin;
        any |= w->band[k];
    }
    return any;
}

/* Added levels between hi and lo (dz apart): where a node of the band wants less, the level
 * halfway, clipped to those nodes and two cells round them, then each half the same way, down
 * to the least step. Top down. */
static cs_err_t added(wl_t *w, cs_dcpath_t *p, unsigned char *mask, double hi, double lo,
                      double dz)
{
    if (dz / 2 < w->dz_fin * (1 - 1e-9) || !wanting(w, hi, lo, dz))
        return CS_OK;
    double mid = (hi + lo) / 2;
    cs_err_t e = added(w, p, mask, hi, mid, dz / 2);
    if (e != CS_OK)
        return e;
    wanting(w, hi, lo, dz);
    cs_dcwater_dilate(w->band, mask, w->nx, w->ny, w->gx, w->gy, 2.01 * fmax(w->gx, w->gy));
    size_t n0 = p->npass;
    w->mask = mask;
    w->lev = mid;
    e = level(w, p);
    w->mask = NULL;
    p->refined += p->npass - n0;
    return e == CS_OK ? added(w, p, mask, mid, lo, dz / 2) : e;
}

/* The boxes (x0 y0 x1 y1, mm) of the 4-connected groups of flat nodes (w->band), each grown by
 * rho and cut to the stock box, merged while two overlap. *nb boxes; false out of memory. */
static bool flat_boxes(wl_t *w, double rho, double (**bx)[4], size_t *nb)
{
    size_t nx = w->nx, nn = nx * w->ny, cap = 0;
    size_t *q = malloc(nn * sizeof *q);
    unsigned char *vis = calloc(nn, 1);
    bool ok = q && vis;
    *bx = NULL, *nb = 0;
    for (size_t s = 0; s < nn && ok; s++) {
        if (!w->band[s] || vis[s])
            continue;
        size_t n = 0, i0 = s % nx, i1 = i0, j0 = s / nx, j1 = j0;
        q[n++] = s, vis[s] = 1;
        for (size_t h = 0; h < n; h++) { /* breadth first */
            size_t k = q[h], i = k % nx, j = k / nx;
            i0 = i < i0 ? i : i0, i1 = i > i1 ? i : i1, j0 = j < j0 ? j : j0, j1 = j > j1 ? j : j1;
            size_t nbr[4] = {i ? k - 1 : k, i + 1 < nx ? k + 1 : k, j ? k - nx : k,
                             j + 1 < w->ny ? k + nx : k};
            for (int d = 0; d < 4; d++)
                if (w->band[nbr[d]] && !vis[nbr[d]])
                    q[n++] = nbr[d], vis[nbr[d]] = 1;
        }
        if (*nb == cap) {
            cap = cap ? 2 * cap : 16;
            double(*nbx)[4] = realloc(*bx, cap * sizeof *nbx);
            if (!(ok = nbx != NULL))
                break;
            *bx = nbx;
        }
        const double *b = w->o->box;
        double *o = (*bx)[(*nb)++];
        o[0] = fmax(b[0], b[0] + (double)i0 * w->gx - rho);
        o[1] = fmax(b[1], b[1] + (double)j0 * w->gy - rho);
        o[2] = fmin(b[2], b[0] + (double)i1 * w->gx + rho);
        o[3] = fmin(b[3], b[1] + (double)j1 * w->gy + rho);
    }
    for (size_t a = 0; a < *nb && ok; a++) /* merge overlapping boxes into the first */
        for (size_t c = a + 1; c < *nb; c++) {
            double *u = (*bx)[a], *v = (*bx)[c];
            if (u[0] > v[2] || v[0] > u[2] || u[1] > v[3] || v[1] > u[3])
                continue;
            u[0] = fmin(u[0], v[0]), u[1] = fmin(u[1], v[1]);
            u[2] = fmax(u[2], v[2]), u[3] = fmax(u[3], v[3]);
            memcpy(v, (*bx)[--*nb], sizeof(double[4]));
            c = a; /* the grown box may meet one passed over */
        }
    free(q), free(vis);
    return ok;
}

/* Clipped rasters over the groups of nodes in w->band (flat areas, corners): each group's box,
 * grown by rho = R + 2 cells (a cutter touching a point stands within R of it), gets a raster
 * at step-over `step` along each of the nang directions from o's angle, 90 degrees apart (no
 * refinement), clipped to the nodes within rho of a marked node. The same drop: gouge-free like
 * the contours. */
static cs_err_t rasters(wl_t *w, cs_dcpath_t *p, unsigned char *mask, double step, int nang)
{
    double rho = w->t->r_mm + 2 * fmax(w->gx, w->gy), (*bx)[4];
    size_t nb;
    if (!flat_boxes(w, rho, &bx, &nb))
        return CS_ERR_FULL;
    cs_dcwater_dilate(w->band, mask, w->nx, w->ny, w->gx, w->gy, rho);
    cs_dcwater_mask_t m = {w->o->box[0], w->o->box[1], w->gx, w->gy, w->nx, w->ny, mask};
    cs_err_t e = CS_OK;
    for (size_t k = 0; k < nb * (size_t)nang && e == CS_OK; k++) {
        cs_dcpath_opts_t ro = *w->o;
        memcpy(ro.box, bx[k / (size_t)nang], sizeof ro.box);
        ro.step_mm = step;
        ro.angle_deg += 90.0 * (double)(k % (size_t)nang);
        cs_dcpath_t r;
        cs_dcpath_init(&r);
        size_t n0 = p->npass;
        e = cs_dcpath_raster(&r, w->ms, w->t, &ro);
        if (e == CS_OK)
            e = cs_dcwater_clip(p, &r, &m);
        w->drops += r.drops;
        p->refined += p->npass - n0;
        cs_dcpath_free(&r);
    }
    free(bx);
    return e;
}

/* Flat areas: surface nodes whose slope allows less than the least level step (a plateau, a
 * flat bottom, a crest), a raster at the flat-ground step-over for h (cs_dcpath_step: the ground
 * is level within the least level step over a step-over). Corners (concave kinks of the drop
 * surface: a valley's floor, a wall's foot), a raster each way at that step over sqrt 2: the
 * passes cross a corner of any direction at most the flat-ground step apart along it, each
 * crossing with the cutter at the corner itself (the raster's points follow the drop to tol). */
static cs_err_t flats(wl_t *w, cs_dcpath_t *p, unsigned char *mask, double h)
{
    for (size_t k = 0; k < w->nx * w->ny; k++)
        w->band[k] = w->surf[k] == 1 && w->allow[k] < w->dz_fin;
    cs_err_t e = rasters(w, p, mask, cs_dcpath_step(w->t, h), 1);
    for (size_t k = 0; k < w->nx * w->ny; k++)
        w->band[k] = w->surf[k] == 2;
    /* a corner's foot is met by the corner arc (the ball r, or the flat end's rim of radius R):
     * passes at most half its cusp step apart, and a quarter of the flat-ground step-over */
    double r = w->t->c_mm > 0 ? w->t->c_mm : w->t->r_mm, hr = fmin(h, r);
    double step = fmin(cs_dcpath_step(w->t, h) / WL_CORNER_DIV, sqrt(2 * r * hr - hr * hr));
    return e == CS_OK ? rasters(w, p, mask, step, 2) : e;
}

/* The levels: evenly from just below the top to the floor, no farther apart than dz; with
 * `full`, the added levels above each and the flat areas after them. */
static cs_err_t levels(wl_t *w, cs_dcpath_t *p, double top, double dz, double h, bool full)
{
    size_t n = (size_t)ceil((top - w->o->min_z) / dz), nn = w->nx * w->ny;
    unsigned char *mask = full ? malloc(nn) : NULL;
    if (full && !mask)
        return CS_ERR_FULL;
    cs_err_t e = CS_OK;
    double band = (top - w->o->min_z) / (double)n;
    for (size_t k = n; k-- > 0 && e == CS_OK;) {
        double lev = w->o->min_z + (top - w->o->min_z) * (double)k / (double)n;
        if (full)
            e = added(w, p, mask, lev + band, lev, band);
        w->lev = lev;
        if (e == CS_OK)
            e = level(w, p);
    }
    if (full && e == CS_OK)
        e = flats(w, p, mask, h);
    free(mask);
    return e;
}

static cs_err_t plan(cs_dcpath_t *p, cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                     const cs_dcpath_opts_t *o, bool full)
{
    wl_t w;
    memset(&w, 0, sizeof w);
    w.ms = ms, w.t = t, w.o = o;
    /* H less the mesh bound and half the chord tolerance (both may add to what is left) */
    double h = fmax(o->scallop_mm - ms->eps - o->tol_mm / 2, o->scallop_mm / 4);
    double top, dz = o->step_mm > 0 ? o->step_mm : cs_dcwater_zstep(t, full ? h : o->scallop_mm);
    /* A flat end's terrace leaves dz cos(theta) along the normal: 2h serves walls from 60
     * degrees, the added levels the rest (its wall step h is the step on level terraces). */
    if (full && o->step_mm <= 0 && t->c_mm <= 0)
        dz = 2 * h;
    cs_err_t e = dz > 0 ? grid(&w, &top) : CS_ERR_RANGE;
    if (e == CS_OK && full) {
        cs_dclevel_t tab;
        cs_dclevel_table(&tab, t, h, dz);
        w.dz_fin = dz / (1 << WL_LEVEL_DEPTH);
        slopes(&w, &tab);
    }
    p->refined = 0;
    if (e == CS_OK && top > o->min_z)
        e = levels(&w, p, top, dz, h, full);
    p->drops = w.drops;
    p->max_left = NAN;
    free(w.z), free(w.ep), free(w.nb), free(w.deg), free(w.seen), free(w.pt);
    free(w.allow), free(w.allow3), free(w.surf), free(w.band);
    return e;
}

cs_err_t cs_dcwater_plan(cs_dcpath_t *p, cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                         const cs_dcpath_opts_t *o)
{
    return plan(p, ms, t, o, true);
}

cs_err_t cs_dcwater_contours(cs_dcpath_t *p, cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                             const cs_dcpath_opts_t *o)
{
    return plan(p, ms, t, o, false);
}
