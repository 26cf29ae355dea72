/* cs_sim_grid: uniform grid over segments, ring search (see cs_sim_grid.h). */
#include "cs_sim_grid.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

double cs_sim_grid_dist(const double *p, const double *a, const double *b, unsigned dims)
{
    double ab[3] = {0, 0, 0}, ap[3] = {0, 0, 0}, l2 = 0, t = 0;
    for (unsigned i = 0; i < dims; i++) {
        ab[i] = b[i] - a[i];
        ap[i] = p[i] - a[i];
        l2 += ab[i] * ab[i];
        t += ab[i] * ap[i];
    }
    t = l2 > 0 ? t / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double d2 = 0;
    for (unsigned i = 0; i < dims; i++) {
        double d = ap[i] - t * ab[i];
        d2 += d * d;
    }
    return sqrt(d2);
}

/* Cell index of coordinate v on axis i, clamped to the grid. */
static size_t cell_of(const cs_sim_grid_t *g, unsigned i, double v)
{
    double c = floor((v - g->lo[i]) / g->cell);
    return c < 0 ? 0 : c >= (double)g->n[i] ? g->n[i] - 1 : (size_t)c;
}

/* Box and cell size: about two segments per cell, at least min_cell, at most MAX_CELLS. */
static void size_grid(cs_sim_grid_t *g, double min_cell)
{
    double hi[3] = {-HUGE_VAL, -HUGE_VAL, 0};
    g->lo[0] = g->lo[1] = HUGE_VAL;
    g->lo[2] = 0;
    for (size_t k = 0; k < 2 * g->nseg; k++)
        for (unsigned i = 0; i < g->dims; i++) {
            double v = g->pts[3 * g->seg[k] + i];
            g->lo[i] = fmin(g->lo[i], v);
            hi[i] = fmax(hi[i], v);
        }
    double vol = 1;
    unsigned used = 0;
    for (unsigned i = 0; i < g->dims; i++)
        if (hi[i] - g->lo[i] > 0) {
            vol *= hi[i] - g->lo[i];
            used++;
        }
    double c = used ? pow(vol / (double)g->nseg * 2.0, 1.0 / used) : 1.0;
    g->cell = fmax(c, min_cell > 0 ? min_cell : 1e-3);
    for (;;) {
        double total = 1;
        for (unsigned i = 0; i < 3; i++) {
            g->n[i] = i < g->dims ? (size_t)((hi[i] - g->lo[i]) / g->cell) + 1 : 1;
            total *= (double)g->n[i];
        }
        if (total <= CS_SIM_GRID_MAX_CELLS)
            break;
        g->cell *= 1.5;
    }
}

/* Calls add(cell) for the cells that pieces (no longer than half a cell) of segment s touch. */
static void each_cell(cs_sim_grid_t *g, size_t s, size_t *count, size_t *fill)
{
    const double *a = &g->pts[3 * g->seg[2 * s]], *b = &g->pts[3 * g->seg[2 * s + 1]];
    double len = cs_sim_grid_dist(a, b, b, g->dims); /* |a - b| */
    size_t pieces = (size_t)ceil(len / (0.5 * g->cell));
    pieces = pieces < 1 ? 1 : pieces;
    size_t prev = (size_t)-1;
    for (size_t j = 0; j <= pieces; j++) {
        double t = (double)j / (double)pieces, c[3];
        size_t ci[3] = {0, 0, 0};
        for (unsigned i = 0; i < g->dims; i++) {
            c[i] = a[i] + t * (b[i] - a[i]);
            ci[i] = cell_of(g, i, c[i]);
        }
        size_t cell = (ci[2] * g->n[1] + ci[1]) * g->n[0] + ci[0];
        if (cell == prev) /* consecutive samples in one cell: list it once */
            continue;
        prev = cell;
        if (count)
            count[cell + 1]++;
        else
            g->idx[fill[cell]++] = s;
    }
}

cs_err_t cs_sim_grid_build(cs_sim_grid_t *g, const double *pts, const size_t *seg, size_t nseg,
                           unsigned dims, double min_cell)
{
    memset(g, 0, sizeof *g);
    if (nseg == 0)
        return CS_ERR_ARG;
    g->pts = pts;
    g->nseg = nseg;
    g->dims = dims == 2 ? 2 : 3;
    size_t *copy = malloc(2 * nseg * sizeof *copy);
    if (copy == NULL)
        return CS_ERR_FULL;
    memcpy(copy, seg, 2 * nseg * sizeof *copy);
    g->seg = copy;
    size_grid(g, min_cell);
    size_t ncell = g->n[0] * g->n[1] * g->n[2];
    g->head = calloc(ncell + 1, sizeof *g->head);
    size_t *fill = malloc(ncell * sizeof *fill);
    if (g->head == NULL || fill == NULL) {
        free(fill);
        cs_sim_grid_free(g);
        return CS_ERR_FULL;
    }
    for (size_t s = 0; s < nseg; s++)
        each_cell(g, s, g->head, NULL);
    for (size_t c = 0; c < ncell; c++)
        g->head[c + 1] += g->head[c];
    g->idx = malloc((g->head[ncell] + 1) * sizeof *g->idx);
    if (g->idx == NULL) {
        free(fill);
        cs_sim_grid_free(g);
        return CS_ERR_FULL;
    }
    memcpy(fill, g->head, ncell * sizeof *fill);
    for (size_t s = 0; s < nseg; s++)
        each_cell(g, s, NULL, fill);
    free(fill);
    return CS_OK;
}

void cs_sim_grid_free(cs_sim_grid_t *g)
{
    free((void *)g->seg);
    free(g->head);
    free(g->idx);
    memset(g, 0, sizeof *g);
}

static double seg_dist(const cs_sim_grid_t *g, const double *p, size_t s)
{
    return cs_sim_grid_dist(p, &g->pts[3 * g->seg[2 * s]], &g->pts[3 * g->seg[2 * s + 1]], g->dims);
}

/* Visits the cells of ring r (Chebyshev distance r in cells) around cell c; keeps the best. */
static void ring(const cs_sim_grid_t *g, const double *p, const size_t c[3], long r, double *best,
                 size_t *which)
{
    long rz = g->dims == 3 ? r : 0;
    for (long dz = -rz; dz <= rz; dz++)
        for (long dy = -r; dy <= r; dy++)
            for (long dx = -r; dx <= r; dx++) {
                if (labs(dx) != r && labs(dy) != r && labs(dz) != r)
                    continue; /* inside: an earlier ring */
                long x = (long)c[0] + dx, y = (long)c[1] + dy, z = (long)c[2] + dz;
                if (x < 0 || y < 0 || z < 0 || x >= (long)g->n[0] || y >= (long)g->n[1] ||
                    z >= (long)g->n[2])
                    continue;
                size_t cell = ((size_t)z * g->n[1] + (size_t)y) * g->n[0] + (size_t)x;
                for (size_t j = g->head[cell]; j < g->head[cell + 1]; j++) {
                    double d = seg_dist(g, p, g->idx[j]);
                    if (d < *best) {
                        *best = d;
                        *which = g->idx[j];
                    }
                }
            }
}

double cs_sim_grid_nearest(cs_sim_grid_t *g, const double p[3], double enough, size_t *which)
{
    size_t w = g->last;
    double best = seg_dist(g, p, w);
    size_t c[3] = {0, 0, 0};
    for (unsigned i = 0; i < g->dims; i++)
        c[i] = cell_of(g, i, p[i]);
    long rmax = (long)(g->n[0] > g->n[1] ? g->n[0] : g->n[1]);
    rmax = (long)g->n[2] > rmax ? (long)g->n[2] : rmax;
    /* Before ring r, every unvisited cell is at least r - 1 cells away from p's cell. */
    for (long r = 0; r <= rmax && best > enough && best > (double)(r - 1) * g->cell; r++) {
        if (r > 32 && (double)r * (double)r > (double)g->nseg) { /* far from all: scan */
            for (size_t s = 0; s < g->nseg; s++) {
                double d = seg_dist(g, p, s);
                if (d < best) {
                    best = d;
                    w = s;
                }
            }
            break;
        }
        ring(g, p, c, r, &best, &w);
    }
    g->last = w;
    if (which)
        *which = w;
    return best;
}
