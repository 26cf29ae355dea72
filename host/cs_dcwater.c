/* cs_dcwater: waterline contours of the drop-cutter surface (cs_dcwater.h). Marching squares
 * on a grid of drop values (the classic 16 cases, the saddles decided by the drop at the cell's
 * centre), contour points by bisection along the grid edges, chained edge to edge. */
#include "cs_dcwater.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

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

/* One level: the edges' contour points, the cells' segments, the chains (open ones first). */
static cs_err_t level(wl_t *w, cs_dcpath_t *p)
{
    memset(w->deg, 0, w->ne);
    memset(w->seen, 0, w->ne);
    for (size_t e = 0; e < w->ne; e++) {
        size_t a[2], b[2];
        edge_nodes(w, e, a, b);
        if ((w->z[a[1] * w->nx + a[0]] > w->lev) != (w->z[b[1] * w->nx + b[0]] > w->lev))
            edge_point(w, e);
    }
    for (size_t j = 0; j + 1 < w->ny; j++)
        for (size_t i = 0; i + 1 < w->nx; i++)
            cell(w, i, j);
    cs_err_t e = CS_OK;
    for (unsigned want = 1; want <= 2 && e == CS_OK; want++)
        for (size_t s = 0; s < w->ne && e == CS_OK; s++)
            if (w->deg[s] == want && !w->seen[s])
                e = chain(w, p, s);
    return e;
}

/* The grid: spacing at most R / 4 (the raster's base sampling), its drops, the top. */
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
    w->z = malloc(w->nx * w->ny * sizeof *w->z);
    w->ep = malloc(w->ne * sizeof *w->ep);
    w->nb = malloc(w->ne * sizeof *w->nb);
    w->deg = malloc(w->ne);
    w->seen = malloc(w->ne);
    if (!w->z || !w->ep || !w->nb || !w->deg || !w->seen)
        return CS_ERR_FULL;
    *top = -HUGE_VAL;
    for (size_t j = 0; j < w->ny; j++)
        for (size_t i = 0; i < w->nx; i++) {
            double q[2];
            node_xy(w, i, j, q);
            w->z[j * w->nx + i] = drop(w, q[0], q[1]);
            *top = fmax(*top, w->z[j * w->nx + i]);
        }
    return CS_OK;
}

cs_err_t cs_dcwater_plan(cs_dcpath_t *p, cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                         const cs_dcpath_opts_t *o)
{
    wl_t w;
    memset(&w, 0, sizeof w);
    w.ms = ms, w.t = t, w.o = o;
    double top, dz = o->step_mm > 0 ? o->step_mm : cs_dcwater_zstep(t, o->scallop_mm);
    cs_err_t e = dz > 0 ? grid(&w, &top) : CS_ERR_RANGE;
    if (e == CS_OK && top > o->min_z) {
        /* Levels from just below the top down to the floor, evenly, no farther apart than dz. */
        size_t n = (size_t)ceil((top - o->min_z) / dz);
        for (size_t k = n; k-- > 0 && e == CS_OK;) {
            w.lev = o->min_z + (top - o->min_z) * (double)k / (double)n;
            e = level(&w, p);
        }
    }
    p->drops = w.drops;
    p->max_left = NAN;
    free(w.z), free(w.ep), free(w.nb), free(w.deg), free(w.seen), free(w.pt);
    return e;
}
