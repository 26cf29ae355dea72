/* cs_dropcheck: gouge and scallop of a finishing path, measured against dense samples of the
 * exact surface (cs_dropcheck.h). */
#include "cs_dropcheck.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cs_finish.h"
#include "cs_varady.h"

#define CK_MAX_K 1200 /* samples a patch in each direction, at most */
#define CK_IDEAL_STEP 0.05 /* mm: the lattice of the ideal cutter's positions (ideal_dist) */
#define CK_WALL       5   /* a wall: the surface rises more than 5 map steps within one (79 deg) */
#define CK_TRACE      64  /* sphere-tracing steps along a ray (path_thick) */
#define CK_HIT        1e-7 /* mm: a ray this near a cutter has reached it */
/* The ideal cutter stands on a lattice of axis positions, so where a real cutter touches the
 * surface the nearest lattice cutter may stay a little off it (on a 65 deg flank with a 2 mm
 * ball and 0.05 mm nodes, up to about 0.002 mm): nearer than this fraction of H it counts as
 * touching, and the path is measured from the surface itself (the stricter measure). */
#define CK_TOUCH      0.25

typedef struct {
    /* surface samples bucketed by xy cell */
    double (*s)[3];
    size_t ns, scap;
    double cell;
    double org[2];
    size_t gx, gy;
    size_t *start, *idx;
    /* the z-map over the region */
    double box[4], step;
    size_t mx, my;
    double *top;
    double dcap;  /* mm: distances beyond this are not measured */
    /* the path's cutter positions (tips, every chord sampled at <= step) bucketed by xy cell,
     * each cell with its lowest tip: a cell whose cutters cannot come nearer is skipped */
    double (*p)[3];
    size_t np, pcap;
    size_t pgx, pgy, *pstart, *pidx;
    double *pzlo;
    double *peak; /* highest sample whose nearest node this is: a wall shows above top */
    double *cmax; /* per sample cell: its highest sample z (prunes the gouge test) */
    double *dropm; /* per node: the ideal drop height there, NAN until needed (rest_at) */
    unsigned char *gap; /* per node, or NULL: 1 where a cutter would close a gap (cs_dropcheck_gaps) */
    unsigned char *win; /* per node, or NULL: 1 where the scallop is measured (cs_dropcheck_gaps) */
    cs_dropcut_tool_t big; /* the cutter enlarged by the margin (R + m, r + m): the ideal drop */
    double margin;         /* mm: the planner's stated margin m (cs_dropcheck.h) */
    long stride;  /* nodes between the ideal cutter's positions (rest_at) */
} ck_t;

/* Appends point p to the growing array *a (*n points of room *cap). */
static cs_err_t push3(double (**a)[3], size_t *n, size_t *cap, const double p[3])
{
    if (*n == *cap) {
        size_t c = *cap ? 2 * *cap : 65536;
        double(*m)[3] = realloc(*a, c * sizeof *m);
        if (!m)
            return CS_ERR_FULL;
        *a = m;
        *cap = c;
    }
    memcpy((*a)[(*n)++], p, 3 * sizeof *p);
    return CS_OK;
}

/* Node index of a map coordinate, or SIZE_MAX outside. */
static size_t node(const ck_t *k, long ix, long iy)
{
    if (ix < 0 || iy < 0 || (size_t)ix >= k->mx || (size_t)iy >= k->my)
        return (size_t)-1;
    return (size_t)iy * k->mx + (size_t)ix;
}

/* Rasterises triangle a b c into the top map (max of its interpolated z at covered nodes). */
static void raster_tri(ck_t *k, const double *a, const double *b, const double *c)
{
    double x0 = fmin(fmin(a[0], b[0]), c[0]), x1 = fmax(fmax(a[0], b[0]), c[0]);
    double y0 = fmin(fmin(a[1], b[1]), c[1]), y1 = fmax(fmax(a[1], b[1]), c[1]);
    double det = (b[1] - c[1]) * (a[0] - c[0]) + (c[0] - b[0]) * (a[1] - c[1]);
    if (fabs(det) < 1e-18)
        return;
    for (long iy = (long)ceil((y0 - k->box[1]) / k->step); iy <= (long)floor((y1 - k->box[1]) / k->step); iy++)
        for (long ix = (long)ceil((x0 - k->box[0]) / k->step); ix <= (long)floor((x1 - k->box[0]) / k->step); ix++) {
            size_t n = node(k, ix, iy);
            if (n == (size_t)-1)
                continue;
            double x = k->box[0] + (double)ix * k->step, y = k->box[1] + (double)iy * k->step;
            double l1 = ((b[1] - c[1]) * (x - c[0]) + (c[0] - b[0]) * (y - c[1])) / det;
            double l2 = ((c[1] - a[1]) * (x - c[0]) + (a[0] - c[0]) * (y - c[1])) / det;
            double l3 = 1 - l1 - l2;
            if (l1 < -1e-12 || l2 < -1e-12 || l3 < -1e-12)
                continue;
            k->top[n] = fmax(k->top[n], l1 * a[2] + l2 * b[2] + l3 * c[2]);
        }
}

/* The sample's z into the peak map at its nearest node. */
static void splat(ck_t *k, const double *p)
{
    size_t n = node(k, lround((p[0] - k->box[0]) / k->step), lround((p[1] - k->box[1]) / k->step));
    if (n != (size_t)-1)
        k->peak[n] = fmax(k->peak[n], p[2]);
}

typedef void (*ck_eval_fn)(const void *ctx, double u, double v, double p[3]);

static void eval_patch(const void *ctx, double u, double v, double p[3])
{
    cs_finish_eval(ctx, u, v, p, NULL);
}

/* The sphere in the seed's parametrisation (cs_sphere.h), u and v in [0, 1]. */
static void eval_sphere(const void *ctx, double u, double v, double p[3])
{
    const cs_sphere_t *s = ctx;
    double lat = -M_PI / 2 + M_PI * u, lon = 2 * M_PI * v;
    p[0] = s->c[0] + s->r * cos(lat) * cos(lon);
    p[1] = s->c[1] + s->r * cos(lat) * sin(lon);
    p[2] = s->c[2] + s->r * sin(lat);
}

/* Samples one surface on a (nu + 1) x (nv + 1) grid: points for the gouge test, triangles into
 * the top map. */
static cs_err_t sample_grid(ck_t *k, ck_eval_fn ev, const void *ctx, int nu, int nv)
{
    double *row = malloc(2 * (size_t)(nv + 1) * 3 * sizeof *row);
    if (!row)
        return CS_ERR_FULL;
    cs_err_t e = CS_OK;
    for (int i = 0; i <= nu && e == CS_OK; i++) {
        double *cur = row + (size_t)(i & 1) * (size_t)(nv + 1) * 3;
        double *prev = row + (size_t)((i + 1) & 1) * (size_t)(nv + 1) * 3;
        for (int j = 0; j <= nv && e == CS_OK; j++) {
            ev(ctx, (double)i / nu, (double)j / nv, &cur[j * 3]);
            e = push3(&k->s, &k->ns, &k->scap, &cur[j * 3]);
            splat(k, &cur[j * 3]);
        }
        for (int j = 0; i > 0 && j < nv; j++) {
            raster_tri(k, &prev[j * 3], &cur[j * 3], &cur[(j + 1) * 3]);
            raster_tri(k, &prev[j * 3], &cur[(j + 1) * 3], &prev[(j + 1) * 3]);
        }
    }
    free(row);
    return e;
}

/* A patch: as many samples each way as its control box's diagonal has steps. */
static cs_err_t sample_patch(ck_t *k, const cs_patch_t *q)
{
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double p[3];
            cs_finish_eval(q, i / 3.0, j / 3.0, p, NULL);
            for (int c = 0; c < 3; c++) {
                lo[c] = fmin(lo[c], p[c]);
                hi[c] = fmax(hi[c], p[c]);
            }
        }
    double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                       (hi[2] - lo[2]) * (hi[2] - lo[2]));
    int kk = (int)fmin(CK_MAX_K, fmax(8, ceil(diag / k->step)));
    return sample_grid(k, eval_patch, q, kk, kk);
}

/* A sphere: a meridian's half circle and the equator at spacing <= step. */
static cs_err_t sample_sphere(ck_t *k, const cs_sphere_t *s)
{
    int nu = (int)fmin(CK_MAX_K, fmax(8, ceil(M_PI * s->r / k->step)));
    return sample_grid(k, eval_sphere, s, nu, 2 * nu);
}

static cs_err_t sample_all(ck_t *k, const cs_surffile_t *sf)
{
    cs_patch_t *cells = malloc(CS_VARADY_MAX_PATCHES * sizeof *cells);
    if (!cells)
        return CS_ERR_FULL;
    cs_err_t e = CS_OK;
    for (size_t i = 0; i < sf->n && e == CS_OK; i++) {
        const cs_surf_item_t *it = &sf->items[i];
        size_t nc = 1;
        double fit;
        if (it->sphere) {
            e = sample_sphere(k, &it->sph);
            continue;
        }
        if (it->tri)
            e = cs_finish_tri_patch(&it->trip, &cells[0]);
        else if (it->varady)
            e = cs_varady_patches(&it->nside, k->step / 4, cells, NULL, CS_VARADY_MAX_PATCHES, &nc,
                                  &fit);
        else
            cells[0] = it->quad;
        for (size_t c = 0; c < nc && e == CS_OK; c++)
            e = sample_patch(k, &cells[c]);
    }
    free(cells);
    return e;
}

/* Puts the n points *pts in the order of their cells (cell[i] of nc, start[c + 1] holding each
 * cell's count on entry): start becomes each cell's first index, idx the identity, and a cell's
 * points lie contiguous in memory (the queries read them cell by cell). */
static cs_err_t cell_order(double (**pts)[3], size_t n, size_t *cap, const size_t *cell,
                           size_t *start, size_t *idx, size_t nc)
{
    for (size_t c = 0; c < nc; c++)
        start[c + 1] += start[c];
    for (size_t i = 0; i < n; i++)
        idx[start[cell[i]]++] = i;
    for (size_t c = nc; c > 0; c--)
        start[c] = start[c - 1];
    start[0] = 0;
    double(*sorted)[3] = malloc((n + 1) * sizeof *sorted);
    if (!sorted)
        return CS_ERR_FULL;
    for (size_t m = 0; m < n; m++) {
        memcpy(sorted[m], (*pts)[idx[m]], sizeof *sorted);
        idx[m] = m;
    }
    free(*pts);
    *pts = sorted;
    *cap = n + 1;
    return CS_OK;
}

/* Buckets the samples by xy cells of size cell. */
static cs_err_t bucket(ck_t *k, double cell)
{
    double lo[2] = {HUGE_VAL, HUGE_VAL}, hi[2] = {-HUGE_VAL, -HUGE_VAL};
    for (size_t i = 0; i < k->ns; i++)
        for (int c = 0; c < 2; c++) {
            lo[c] = fmin(lo[c], k->s[i][c]);
            hi[c] = fmax(hi[c], k->s[i][c]);
        }
    k->cell = cell;
    k->org[0] = lo[0];
    k->org[1] = lo[1];
    k->gx = (size_t)((hi[0] - lo[0]) / cell) + 1;
    k->gy = (size_t)((hi[1] - lo[1]) / cell) + 1;
    size_t nc = k->gx * k->gy;
    k->start = calloc(nc + 1, sizeof *k->start);
    k->idx = malloc((k->ns + 1) * sizeof *k->idx);
    k->cmax = malloc(nc * sizeof *k->cmax);
    size_t *at = malloc((k->ns + 1) * sizeof *at);
    if (!k->start || !k->idx || !k->cmax || !at) {
        free(at);
        return CS_ERR_FULL;
    }
    for (size_t c = 0; c < nc; c++)
        k->cmax[c] = -HUGE_VAL;
    for (size_t i = 0; i < k->ns; i++) {
        size_t cx = (size_t)((k->s[i][0] - lo[0]) / cell), cy = (size_t)((k->s[i][1] - lo[1]) / cell);
        at[i] = cy * k->gx + cx;
        k->start[at[i] + 1]++;
        k->cmax[at[i]] = fmax(k->cmax[at[i]], k->s[i][2]);
    }
    cs_err_t e = cell_order(&k->s, k->ns, &k->scap, at, k->start, k->idx, nc);
    free(at);
    return e;
}

/* Horizontal distance from (x, y) to the box of sample cell (cx, cy): no sample in it is nearer. */
static double cell_dist(const ck_t *k, long cx, long cy, double x, double y)
{
    double x0 = k->org[0] + (double)cx * k->cell, y0 = k->org[1] + (double)cy * k->cell;
    double dx = x < x0 ? x0 - x : x > x0 + k->cell ? x - x0 - k->cell : 0;
    double dy = y < y0 ? y0 - y : y > y0 + k->cell ? y - y0 - k->cell : 0;
    return sqrt(dx * dx + dy * dy);
}

/* A lower bound on the profile h(d) of tool t from d^2, without the profile's square roots: on the
 * corner arc (e = d - (R - r) > 0) h = r - sqrt(r^2 - e^2) = e^2 / (r + sqrt(r^2 - e^2)) >=
 * e^2 / (2 r); 0 on the flat bottom. A sample that stands no higher above the tip than this
 * cannot be deeper inside the cutter than the deepest found (nor raise a drop). */
static double profile_lb(const cs_dropcut_tool_t *t, double d2)
{
    double a = t->r_mm - t->c_mm;
    if (t->c_mm <= 0)
        return 0;
    if (a <= 0)
        return d2 / (2 * t->c_mm);
    double e = sqrt(d2) - a;
    return e > 0 ? e * e / (2 * t->c_mm) : 0;
}

/* One cutter position's deepest penetration: the samples within R, cell by cell; a cell whose
 * highest sample stands no more above the cutter's lowest point over it than the deepest found
 * so far cannot hold a deeper one (h is non-decreasing in d). */
static void visit_gouge(ck_t *k, const cs_dropcut_tool_t *t, const double p[3], cs_dropcheck_t *o)
{
    double r = t->r_mm;
    long cx0 = (long)floor((p[0] - r - k->org[0]) / k->cell), cx1 = (long)floor((p[0] + r - k->org[0]) / k->cell);
    long cy0 = (long)floor((p[1] - r - k->org[1]) / k->cell), cy1 = (long)floor((p[1] + r - k->org[1]) / k->cell);
    for (long cy = cy0 < 0 ? 0 : cy0; cy <= cy1 && cy < (long)k->gy; cy++)
        for (long cx = cx0 < 0 ? 0 : cx0; cx <= cx1 && cx < (long)k->gx; cx++) {
            size_t c = (size_t)cy * k->gx + (size_t)cx;
            double cd = cell_dist(k, cx, cy, p[0], p[1]);
            if (cd > r || k->cmax[c] - (p[2] + cs_dropcut_profile(t, cd)) <= o->gouge_mm)
                continue;
            for (size_t m = k->start[c]; m < k->start[c + 1]; m++) {
                const double *s = k->s[k->idx[m]];
                double dx = s[0] - p[0], dy = s[1] - p[1], d2 = dx * dx + dy * dy;
                if (d2 > r * r || s[2] - p[2] - profile_lb(t, d2) <= o->gouge_mm)
                    continue;
                double pen = s[2] - (p[2] + cs_dropcut_profile(t, sqrt(d2)));
                if (pen > o->gouge_mm) {
                    o->gouge_mm = pen;
                    memcpy(o->gouge_at, s, sizeof o->gouge_at);
                    memcpy(o->gouge_tool, p, sizeof o->gouge_tool);
                }
            }
        }
}

/* Distance (mm) from point s to the solid of tool t with its tip at p: the disk of radius
 * R - r at the corner centres' height swept by the ball of radius r, the shank (radius R) above;
 * 0 inside. The solid is convex: below the corner centres the nearest point lies on the swept
 * ball, above them on the shank's side. */
static double tool_dist(const cs_dropcut_tool_t *t, const double p[3], double sx, double sy,
                        double sz)
{
    double dx = sx - p[0], dy = sy - p[1], rho = sqrt(dx * dx + dy * dy);
    double dz = sz - (p[2] + t->c_mm);
    if (dz >= 0)
        return rho > t->r_mm ? rho - t->r_mm : 0;
    double e = rho - (t->r_mm - t->c_mm);
    e = e > 0 ? e : 0;
    double d = sqrt(e * e + dz * dz) - t->c_mm;
    return d > 0 ? d : 0;
}

/* Every chord sampled at spacing <= step: the gouge at each sample (unless !gouge: the fill-in
 * wants the gaps only), the samples kept. */
static cs_err_t walk(ck_t *k, const cs_dropcut_tool_t *t, const double (*pts)[3],
                     const size_t *start, size_t npass, bool gouge, cs_dropcheck_t *o)
{
    cs_err_t e = CS_OK;
    for (size_t pass = 0; pass < npass; pass++)
        for (size_t i = start[pass]; i < start[pass + 1] && e == CS_OK; i++) {
            const double *a = pts[i], *b = i + 1 < start[pass + 1] ? pts[i + 1] : pts[i];
            double len = sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
                              (b[2] - a[2]) * (b[2] - a[2]));
            size_t n = (size_t)ceil(len / k->step);
            /* the chord's last sample is the next chord's first */
            size_t last = n == 0 || i + 2 > start[pass + 1] ? n : n - 1;
            for (size_t j = 0; j <= last && e == CS_OK; j++) {
                double f = n ? (double)j / (double)n : 0, p[3];
                for (int c = 0; c < 3; c++)
                    p[c] = a[c] + f * (b[c] - a[c]);
                if (gouge)
                    visit_gouge(k, t, p, o);
                e = push3(&k->p, &k->np, &k->pcap, p);
                o->path_samples++;
            }
        }
    return e;
}

/* Buckets the path's cutter positions over the sample cells' grid (same origin and size). */
static cs_err_t bucket_tips(ck_t *k)
{
    k->pgx = k->gx, k->pgy = k->gy;
    size_t nc = k->pgx * k->pgy;
    k->pstart = calloc(nc + 1, sizeof *k->pstart);
    k->pidx = malloc((k->np + 1) * sizeof *k->pidx);
    k->pzlo = malloc(nc * sizeof *k->pzlo);
    if (!k->pstart || !k->pidx || !k->pzlo)
        return CS_ERR_FULL;
    size_t *cell = malloc((k->np + 1) * sizeof *cell);
    if (!cell)
        return CS_ERR_FULL;
    for (size_t c = 0; c < nc; c++)
        k->pzlo[c] = HUGE_VAL;
    for (size_t i = 0; i < k->np; i++) {
        double fx = floor((k->p[i][0] - k->org[0]) / k->cell), fy = floor((k->p[i][1] - k->org[1]) / k->cell);
        size_t cx = fx < 0 ? 0 : fx >= (double)k->pgx ? k->pgx - 1 : (size_t)fx;
        size_t cy = fy < 0 ? 0 : fy >= (double)k->pgy ? k->pgy - 1 : (size_t)fy;
        cell[i] = cy * k->pgx + cx;
        k->pstart[cell[i] + 1]++;
        k->pzlo[cell[i]] = fmin(k->pzlo[cell[i]], k->p[i][2]);
    }
    cs_err_t e = cell_order(&k->p, k->np, &k->pcap, cell, k->pstart, k->pidx, nc);
    free(cell);
    return e;
}

/* How far along the ray o + u d (u a unit vector) the path's cutters begin: the material's
 * thickness there, capped at dcap. For one cutter the distance f(d) = tool_dist(o + u d) is
 * convex and 1-Lipschitz, so d += f(d) from d = f(0) never passes the first hit and reaches
 * it (sphere tracing); a cutter no nearer than the best hit is skipped. A ray that has not
 * reached a cutter within CK_TRACE steps (grazing it) counts as missing it: the thickness is
 * then overstated, never understated. A cell's cutters all lie in the half-cylinders of radius
 * R - r over its box from its lowest corner centres up, so none comes nearer than the distance
 * to that set less r (tool_dist's form): such a cell is skipped. Cells at the grid's edge hold
 * the tips beyond it too (clamped): never skipped by their box. */
static double path_thick(const ck_t *k, const cs_dropcut_tool_t *t, const double o[3],
                         const double u[3])
{
    double best = k->dcap, r = t->r_mm + best, a = t->r_mm - t->c_mm;
    long cx0 = (long)floor((o[0] - r - k->org[0]) / k->cell), cx1 = (long)floor((o[0] + r - k->org[0]) / k->cell);
    long cy0 = (long)floor((o[1] - r - k->org[1]) / k->cell), cy1 = (long)floor((o[1] + r - k->org[1]) / k->cell);
    long mx = (long)k->pgx - 1, my = (long)k->pgy - 1;
    cx0 = cx0 < 0 ? 0 : cx0, cy0 = cy0 < 0 ? 0 : cy0, cx1 = cx1 > mx ? mx : cx1, cy1 = cy1 > my ? my : cy1;
    for (long cy = cy0; cy <= cy1; cy++)
        for (long cx = cx0; cx <= cx1; cx++) {
            size_t c = (size_t)cy * k->pgx + (size_t)cx;
            if (k->pstart[c] == k->pstart[c + 1])
                continue;
            bool edge = cx == 0 || cy == 0 || cx == mx || cy == my;
            double e = edge ? 0 : fmax(0, cell_dist(k, cx, cy, o[0], o[1]) - a);
            double dz = fmax(0, k->pzlo[c] + t->c_mm - o[2]);
            if (sqrt(e * e + dz * dz) - t->c_mm >= best)
                continue;
            for (size_t m = k->pstart[c]; m < k->pstart[c + 1]; m++) {
                const double *p = k->p[k->pidx[m]];
                double d = tool_dist(t, p, o[0], o[1], o[2]), f = d;
                for (int i = 0; i < CK_TRACE && f > CK_HIT && d < best; i++) {
                    f = tool_dist(t, p, o[0] + u[0] * d, o[1] + u[1] * d, o[2] + u[2] * d);
                    d += f;
                }
                if (f <= CK_HIT && d < best)
                    best = d;
            }
        }
    return best;
}

/* The unit normal (upwards) of the rasterised top at node (ix, iy): central differences where
 * both neighbours have surface, one-sided where one has. */
static void top_normal(const ck_t *k, long ix, long iy, double u[3])
{
    double z0 = k->top[node(k, ix, iy)], g[2];
    for (int c = 0; c < 2; c++) {
        size_t np = node(k, ix + (c == 0), iy + (c == 1)), nm = node(k, ix - (c == 0), iy - (c == 1));
        bool hp = np != (size_t)-1 && k->top[np] > -HUGE_VAL, hm = nm != (size_t)-1 && k->top[nm] > -HUGE_VAL;
        g[c] = hp && hm ? (k->top[np] - k->top[nm]) / (2 * k->step)
               : hp     ? (k->top[np] - z0) / k->step
               : hm     ? (z0 - k->top[nm]) / k->step
                        : 0;
    }
    double l = sqrt(1 + g[0] * g[0] + g[1] * g[1]);
    u[0] = -g[0] / l, u[1] = -g[1] / l, u[2] = 1 / l;
}

/* Marks in far[] the nodes at least r_nodes (chessboard distance) from every node with no
 * surface above it: the interior where a cutter of radius r lies over the surface all round.
 * Two-pass distance transform (Rosenfeld and Pfaltz), capped at r_nodes + 1. */
static bool interior(const ck_t *k, long r_nodes, unsigned char *far)
{
    size_t nn = k->mx * k->my;
    long *d = malloc(nn * sizeof *d);
    if (!d)
        return false;
    long cap = r_nodes + 1;
    for (size_t n = 0; n < nn; n++)
        d[n] = k->top[n] == -HUGE_VAL ? 0 : cap;
    for (int pass = 0; pass < 2; pass++)
        for (size_t i = 0; i < nn; i++) {
            size_t n = pass == 0 ? i : nn - 1 - i;
            long ix = (long)(n % k->mx), iy = (long)(n / k->mx), s = pass == 0 ? -1 : 1;
            long nb[4][2] = {{ix + s, iy}, {ix - 1, iy + s}, {ix, iy + s}, {ix + 1, iy + s}};
            for (int j = 0; j < 4; j++) {
                size_t m = node(k, nb[j][0], nb[j][1]);
                long dm = m == (size_t)-1 ? 0 : d[m]; /* beyond the map: no surface known */
                if (dm + 1 < d[n])
                    d[n] = dm + 1;
            }
        }
    for (size_t n = 0; n < nn; n++)
        far[n] = d[n] > r_nodes;
    free(d);
    return true;
}

/* The drop at (x, y) over one sample cell, given the best so far: skipped when even its highest
 * sample at the cell's nearest point cannot beat it. */
static double drop_cell(const ck_t *k, const cs_dropcut_tool_t *t, long gx, long gy, double x,
                        double y, double best)
{
    if (gx < 0 || gy < 0 || gx >= (long)k->gx || gy >= (long)k->gy)
        return best;
    size_t g = (size_t)gy * k->gx + (size_t)gx;
    double r = t->r_mm, cd = cell_dist(k, gx, gy, x, y);
    if (cd > r || k->cmax[g] - cs_dropcut_profile(t, cd) <= best)
        return best;
    for (size_t m = k->start[g]; m < k->start[g + 1]; m++) {
        const double *s = k->s[k->idx[m]];
        double dx = s[0] - x, dy = s[1] - y, d2 = dx * dx + dy * dy;
        if (d2 > r * r || s[2] - profile_lb(t, d2) <= best)
            continue;
        best = fmax(best, s[2] - cs_dropcut_profile(t, sqrt(d2)));
    }
    return best;
}

/* The ideal drop at node c: the highest tip of a cutter whose axis stands at c that no surface
 * sample enters with the margin m kept, i.e. the cutter K + B(m) (R + m, r + m) dropped, max over
 * samples q within R + m of q.z - h'(|q - c|), raised by m (the dense samples of the exact
 * surface, as the gouge test). The cells in rings from the axis out: the highest contacts come
 * first, so that most cells farther out are pruned by their bound. Memoised. */
static double ideal_drop(ck_t *k, long cx, long cy)
{
    const cs_dropcut_tool_t *t = &k->big;
    size_t c = node(k, cx, cy);
    if (!isnan(k->dropm[c]))
        return k->dropm[c];
    double best = -HUGE_VAL;
    double x = k->box[0] + (double)cx * k->step, y = k->box[1] + (double)cy * k->step;
    long gx = (long)floor((x - k->org[0]) / k->cell), gy = (long)floor((y - k->org[1]) / k->cell);
    long rings = (long)ceil(t->r_mm / k->cell) + 1;
    for (long ring = 0; ring <= rings; ring++)
        for (long i = -ring; i <= ring; i++) {
            best = drop_cell(k, t, gx + i, gy - ring, x, y, best);
            if (ring > 0)
                best = drop_cell(k, t, gx + i, gy + ring, x, y, best);
            if (i > -ring && i < ring) {
                best = drop_cell(k, t, gx - ring, gy + i, x, y, best);
                best = drop_cell(k, t, gx + ring, gy + i, x, y, best);
            }
        }
    return k->dropm[c] = best + k->margin; /* K + B(m) resting there: K's tip m higher */
}

/* How near any cutter position from above comes to the surface point s over node (ix, iy): min
 * over axis positions c (every node within R + dcap) of the distance to the cutter dropped at
 * c; *arg gets that c, pc its tip. More than H: rest material, no 3-axis cutter of this shape
 * reaches it. */
static double ideal_dist(ck_t *k, const cs_dropcut_tool_t *t, long ix, long iy, size_t *arg,
                         double pc[3])
{
    *arg = (size_t)-1;
    double r = t->r_mm + k->dcap, best = HUGE_VAL;
    long rn = (long)ceil(r / k->step / (double)k->stride) * k->stride;
    long bx = ix / k->stride * k->stride, by = iy / k->stride * k->stride;
    double sx = k->box[0] + (double)ix * k->step, sy = k->box[1] + (double)iy * k->step;
    double sz = k->top[node(k, ix, iy)];
    for (long cy = by - rn; cy <= by + rn && best > 0; cy += k->stride)
        for (long cx = bx - rn; cx <= bx + rn && best > 0; cx += k->stride) {
            double dx = (double)(cx - ix) * k->step, dy = (double)(cy - iy) * k->step;
            double d2 = dx * dx + dy * dy, near = t->r_mm + best; /* squares: no root */
            if (d2 > r * r || d2 >= near * near || node(k, cx, cy) == (size_t)-1)
                continue; /* (no cutter whose axis stands d away comes nearer than d - R) */
            double z = ideal_drop(k, cx, cy);
            double q[3] = {k->box[0] + (double)cx * k->step, k->box[1] + (double)cy * k->step, z};
            double dd = z > -HUGE_VAL ? tool_dist(t, q, sx, sy, sz) : HUGE_VAL;
            if (dd < best) {
                best = dd;
                *arg = node(k, cx, cy);
                memcpy(pc, q, sizeof q);
            }
        }
    return best;
}

/* The point q of the solid of tool t (tip at p) nearest to s: the nearest point m of the
 * half-cylinder of radius R - r from the corner centres up (tool_dist), then r towards s. */
static void tool_nearest(const cs_dropcut_tool_t *t, const double p[3], const double s[3],
                         double q[3])
{
    double dx = s[0] - p[0], dy = s[1] - p[1], rho = sqrt(dx * dx + dy * dy), a = t->r_mm - t->c_mm;
    double f = rho > a ? a / rho : 1;
    double m[3] = {p[0] + f * dx, p[1] + f * dy, fmax(s[2], p[2] + t->c_mm)};
    double v[3] = {s[0] - m[0], s[1] - m[1], s[2] - m[2]};
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    double g = l > t->c_mm ? t->c_mm / l : 1; /* inside: s itself */
    for (int c = 0; c < 3; c++)
        q[c] = m[c] + g * v[c];
}

/* Is there a wall at node n: the rasterised top of a neighbour more than CK_WALL steps above or
 * below (slope > CK_WALL, the planner's own bound, cs_dcpath.h), or a sample of the node's cell
 * that far above the top (a thin lip seen through)? The raster does not promise its scallop
 * there; such nodes are counted apart. */
static bool wall_at(const ck_t *k, size_t n)
{
    long ix = (long)(n % k->mx), iy = (long)(n / k->mx);
    static const int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
    double lim = CK_WALL * k->step;
    if (k->peak[n] > k->top[n] + lim)
        return true;
    for (int i = 0; i < 4; i++) {
        size_t m = node(k, ix + dx[i], iy + dy[i]);
        if (m != (size_t)-1 && k->top[m] > -HUGE_VAL && fabs(k->top[m] - k->top[n]) > lim)
            return true;
    }
    return false;
}

/* The scallop and rest material over every node with the cutter over the surface all round
 * (cs_dropcheck.h): the path's distance to the surface point s, or where that exceeds H, to the
 * point q of the ideal envelope nearest to s, whichever is less. */
static void measure(ck_t *k, const cs_dropcut_tool_t *t, const unsigned char *far, double h_mm,
                    cs_dropcheck_t *out)
{
    for (size_t n = 0; n < k->mx * k->my; n++) {
        if (k->top[n] == -HUGE_VAL || !far[n] || (k->win && !k->win[n]))
            continue;
        if (wall_at(k, n)) {
            out->walls++;
            continue;
        }
        out->nodes++;
        long ix = (long)(n % k->mx), iy = (long)(n / k->mx);
        double s[3] = {k->box[0] + (double)ix * k->step, k->box[1] + (double)iy * k->step, k->top[n]};
        double un[3];
        top_normal(k, ix, iy, un);
        double left = path_thick(k, t, s, un); /* the material over s along the normal */
        size_t arg = (size_t)-1;
        if (left > h_mm) { /* is it within reach at all? */
            double pc[3] = {0, 0, 0}, q[3];
            double ideal = ideal_dist(k, t, ix, iy, &arg, pc);
            if (ideal > h_mm) {
                out->rest_nodes++;
                if (ideal > out->rest_mm) {
                    out->rest_mm = ideal;
                    memcpy(out->rest_at, s, sizeof out->rest_at);
                }
            }
            if (arg != (size_t)-1 && ideal > CK_TOUCH * h_mm) {
                tool_nearest(t, pc, s, q);
                /* from q on, away from the surface: the ideal envelope's normal there */
                double v[3] = {q[0] - s[0], q[1] - s[1], q[2] - s[2]};
                double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
                for (int c = 0; c < 3; c++)
                    v[c] = l > 0 ? v[c] / l : un[c];
                double beyond = path_thick(k, t, q, v);
                if (beyond < left && ideal <= h_mm) { /* rest under the envelope, <= H */
                    out->corner_nodes++;
                    out->corner_left_mm = fmax(out->corner_left_mm, left);
                }
                left = fmin(left, beyond);
            }
        }
        if (left > h_mm && arg != (size_t)-1 && k->gap)
            k->gap[arg] = 1; /* the position from which the ideal cutter comes nearest */
        if (left > out->scallop_mm) {
            out->scallop_mm = left;
            memcpy(out->scallop_at, s, sizeof out->scallop_at);
        }
    }
}

/* The maps over the region: top and peak empty, the envelope infinitely high. */
static cs_err_t maps(ck_t *k, const double box[4], double step_mm)
{
    memcpy(k->box, box, sizeof k->box);
    k->step = step_mm;
    k->stride = lround(fmax(1, CK_IDEAL_STEP / step_mm));
    k->mx = (size_t)floor((box[2] - box[0]) / step_mm) + 1;
    k->my = (size_t)floor((box[3] - box[1]) / step_mm) + 1;
    size_t nn = k->mx * k->my;
    k->top = malloc(nn * sizeof *k->top);
    k->peak = malloc(nn * sizeof *k->peak);
    k->dropm = malloc(nn * sizeof *k->dropm);
    if (!k->top || !k->peak || !k->dropm)
        return CS_ERR_FULL;
    for (size_t n = 0; n < nn; n++) {
        k->top[n] = k->peak[n] = -HUGE_VAL;
        k->dropm[n] = NAN;
    }
    return CS_OK;
}

/* The gap positions marked in k->gap, as xy points into *at (malloc'd). */
static cs_err_t collect(const ck_t *k, double (**at)[2], size_t *nat)
{
    size_t nn = k->mx * k->my, m = 0;
    for (size_t n = 0; n < nn; n++)
        m += k->gap[n];
    *at = malloc((m ? m : 1) * sizeof **at);
    if (!*at)
        return CS_ERR_FULL;
    *nat = 0;
    for (size_t n = 0; n < nn; n++)
        if (k->gap[n]) {
            (*at)[*nat][0] = k->box[0] + (double)(n % k->mx) * k->step;
            (*at)[(*nat)++][1] = k->box[1] + (double)(n / k->mx) * k->step;
        }
    return CS_OK;
}

/* The window of the measure: the nodes within rad of one of the n points (xy, mm): each point's
 * nearest node, then those dilated by a disk of rad. */
static cs_err_t window(ck_t *k, const double (*near)[2], size_t n, double rad)
{
    size_t nn = k->mx * k->my;
    unsigned char *c = calloc(nn, 1);
    if (!c || !(k->win = calloc(nn, 1))) {
        free(c);
        return CS_ERR_FULL;
    }
    for (size_t i = 0; i < n; i++) {
        size_t m = node(k, lround((near[i][0] - k->box[0]) / k->step), lround((near[i][1] - k->box[1]) / k->step));
        if (m != (size_t)-1)
            c[m] = 1;
    }
    long rn = (long)ceil(rad / k->step);
    for (size_t m = 0; m < nn; m++) {
        long ix = (long)(m % k->mx), iy = (long)(m / k->mx);
        for (long jy = -rn; c[m] && jy <= rn; jy++)
            for (long jx = -rn; jx <= rn; jx++) {
                size_t q = node(k, ix + jx, iy + jy);
                if (q != (size_t)-1 && jx * jx + jy * jy <= rn * rn)
                    k->win[q] = 1;
            }
    }
    free(c);
    return CS_OK;
}

static cs_err_t check(const cs_surffile_t *sf, const cs_dropcut_tool_t *t,
                      const double (*pts)[3], const size_t *start, size_t npass,
                      const double box[4], double step_mm, double h_mm, double margin_mm,
                      const cs_dropcheck_win_t *w, cs_dropcheck_t *out, double (**at)[2],
                      size_t *nat)
{
    memset(out, 0, sizeof *out);
    ck_t k;
    memset(&k, 0, sizeof k);
    k.margin = margin_mm;
    k.big.r_mm = t->r_mm + margin_mm;
    k.big.c_mm = t->c_mm + margin_mm;
    unsigned char *far = NULL;
    /* Twice the promise (a failure still shows its size), within half the cutter. */
    k.dcap = fmin(fmax(2 * h_mm, 0.1), t->r_mm / 2);
    cs_err_t e = maps(&k, box, step_mm);
    if (e == CS_OK)
        e = sample_all(&k, sf);
    if (e == CS_OK)
        e = bucket(&k, fmax(t->r_mm / 8, 2 * step_mm));
    if (e == CS_OK) {
        e = walk(&k, t, pts, start, npass, at == NULL, out);
        out->surf_samples = k.ns;
    }
    if (e == CS_OK)
        e = bucket_tips(&k);
    if (e == CS_OK) {
        far = malloc(k.mx * k.my);
        if (!far || !interior(&k, (long)ceil(t->r_mm / step_mm), far))
            e = CS_ERR_FULL;
    }
    if (e == CS_OK && at && !(k.gap = calloc(k.mx * k.my, 1)))
        e = CS_ERR_FULL;
    if (e == CS_OK && w)
        e = window(&k, w->pts, w->n, w->rad_mm);
    if (e == CS_OK)
        measure(&k, t, far, h_mm, out);
    if (e == CS_OK && at)
        e = collect(&k, at, nat);
    free(k.gap);
    free(k.win);
    free(far);
    free(k.s);
    free(k.start);
    free(k.idx);
    free(k.cmax);
    free(k.top);
    free(k.p);
    free(k.pstart);
    free(k.pidx);
    free(k.pzlo);
    free(k.peak);
    free(k.dropm);
    return e;
}

cs_err_t cs_dropcheck_run(const cs_surffile_t *sf, const cs_dropcut_tool_t *t,
                          const double (*pts)[3], const size_t *start, size_t npass,
                          const double box[4], double step_mm, double h_mm, double margin_mm,
                          cs_dropcheck_t *out)
{
    return check(sf, t, pts, start, npass, box, step_mm, h_mm, margin_mm, NULL, out, NULL, NULL);
}

cs_err_t cs_dropcheck_gaps(const cs_surffile_t *sf, const cs_dropcut_tool_t *t,
                           const double (*pts)[3], const size_t *start, size_t npass,
                           const double box[4], double step_mm, double h_mm, double margin_mm,
                           const cs_dropcheck_win_t *w, cs_dropcheck_t *out, double (**at)[2],
                           size_t *nat)
{
    *at = NULL;
    *nat = 0;
    return check(sf, t, pts, start, npass, box, step_mm, h_mm, margin_mm, w, out, at, nat);
}
