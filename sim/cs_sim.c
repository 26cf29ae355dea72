/* cs_sim: execution on the POSIX port and measurements from the recorded edges. */
#include "cs_sim.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cs_stepper.h"

cs_err_t cs_sim_execute(const cs_machine_t *m, const cs_segment_t *s, size_t n, cs_sim_exec_t *ex)
{
    memset(ex, 0, sizeof *ex);
    static cs_stepper_t st; /* the port keeps a pointer to it while running */
    cs_err_t e = cs_stepper_init(&st, m);
    if (e != CS_OK)
        return e;
    uint8_t inv = 0;
    for (unsigned i = 0; i < m->n_axes; i++)
        if (m->axis[i].invert_dir)
            inv = (uint8_t)(inv | (1u << i));
    port_posix_reset(m->tick_hz, inv);
    port_stepper_attach(&st);
    for (size_t k = 0; k < n; k++) {
        while (cs_stepper_free(&st) == 0)
            if (!port_posix_step())
                return CS_ERR_STATE;
        e = cs_stepper_push(&st, &s[k]);
        if (e != CS_OK)
            return e;
    }
    if (!port_posix_run(UINT64_MAX))
        return CS_ERR_STATE;
    if (!port_posix_record_ok())
        return CS_ERR_FULL;
    size_t ne;
    const port_posix_edge_t *edges = port_posix_edges(&ne);
    if (ne > 0) {
        ex->edges = malloc(ne * sizeof *ex->edges);
        if (ex->edges == NULL)
            return CS_ERR_FULL;
        memcpy(ex->edges, edges, ne * sizeof *edges);
    }
    ex->n = ne;
    ex->end_tick = port_posix_now();
    for (unsigned i = 0; i < CS_AXES; i++) {
        ex->pos[i] = port_posix_position(i);
        ex->exec_pos[i] = cs_stepper_position(&st, i);
    }
    port_posix_reset(m->tick_hz, inv); /* frees the port's copy */
    port_stepper_attach(NULL);
    return CS_OK;
}

void cs_sim_exec_free(cs_sim_exec_t *ex)
{
    free(ex->edges);
    ex->edges = NULL;
    ex->n = 0;
}

void cs_sim_dynamics(const cs_machine_t *m, const cs_sim_exec_t *ex, double window_s,
                     cs_sim_dyn_t *out)
{
    memset(out, 0, sizeof *out);
    out->window_s = window_s;
    double hz = m->tick_hz;
    uint64_t w = (uint64_t)llround(window_s * hz);
    if (w < 1)
        w = 1;
    double W = (double)w / hz;
    /* Samples at k*w from 0 to past the end (the machine rests before 0 and after the end). */
    uint64_t nsamp = ex->end_tick / w + 3;
    for (unsigned i = 0; i < m->n_axes; i++) {
        double spm = (double)m->axis[i].steps_per_mm / CS_MOTION_ONE;
        int64_t p = 0, prev_p = 0;
        double prev_v = 0;
        size_t e = 0;
        for (uint64_t k = 0; k <= nsamp; k++) {
            uint64_t t = k * w;
            while (e < ex->n && ex->edges[e].t <= t) {
                if (ex->edges[e].axis == i)
                    p += ex->edges[e].dir;
                e++;
            }
            if (k > 0) {
                double v = (double)(p - prev_p) / spm / W;
                double a = (v - prev_v) / W;
                if (fabs(v) > out->peak_rate[i]) {
                    out->peak_rate[i] = fabs(v);
                    out->t_rate[i] = (double)t / hz;
                }
                if (fabs(a) > out->peak_accel[i]) {
                    out->peak_accel[i] = fabs(a);
                    out->t_accel[i] = (double)t / hz;
                }
                prev_v = v;
            }
            prev_p = p;
        }
        out->rate_allow[i] = 2.0 / spm / W;
        out->accel_allow[i] = 4.0 / spm / (W * W);
        double rate = (double)m->axis[i].max_rate / CS_MOTION_ONE;
        double acc = (double)m->axis[i].max_accel / CS_MOTION_ONE;
        out->rate_ok[i] = out->peak_rate[i] <= rate + out->rate_allow[i];
        out->accel_ok[i] = out->peak_accel[i] <= acc + out->accel_allow[i];
    }
}

void cs_sim_ref_init(cs_sim_ref_t *r)
{
    memset(r, 0, sizeof *r);
}

void cs_sim_ref_free(cs_sim_ref_t *r)
{
    free(r->xyz);
    free(r->travel);
    free(r->starts);
    cs_sim_ref_init(r);
}

static cs_err_t ref_point(cs_sim_ref_t *r, const double p[3], bool travel)
{
    if (r->n == r->cap) {
        size_t cap = r->cap ? r->cap * 2 : 1024;
        double *v = realloc(r->xyz, cap * 3 * sizeof *v);
        if (v == NULL)
            return CS_ERR_FULL;
        r->xyz = v;
        unsigned char *t = realloc(r->travel, cap);
        if (t == NULL)
            return CS_ERR_FULL;
        r->travel = t;
        r->cap = cap;
    }
    memcpy(&r->xyz[3 * r->n], p, 3 * sizeof *p);
    r->travel[r->n] = travel;
    r->n++;
    return CS_OK;
}

cs_err_t cs_sim_ref_move(cs_sim_ref_t *r, const double p[3])
{
    if (r->nlines == r->caplines) {
        size_t cap = r->caplines ? r->caplines * 2 : 64;
        size_t *v = realloc(r->starts, cap * sizeof *v);
        if (v == NULL)
            return CS_ERR_FULL;
        r->starts = v;
        r->caplines = cap;
    }
    r->starts[r->nlines++] = r->n;
    return ref_point(r, p, false);
}

cs_err_t cs_sim_ref_line(cs_sim_ref_t *r, const double p[3])
{
    if (r->nlines == 0)
        return cs_sim_ref_move(r, p);
    return ref_point(r, p, false);
}

cs_err_t cs_sim_ref_travel(cs_sim_ref_t *r, const double p[3])
{
    if (r->nlines == 0)
        return cs_sim_ref_move(r, p);
    return ref_point(r, p, true);
}

double cs_sim_step_mm(const cs_machine_t *m)
{
    double s = 0;
    for (unsigned i = 0; i < 3; i++) {
        double d = CS_MOTION_ONE / (double)m->axis[i].steps_per_mm;
        s += d * d;
    }
    return sqrt(s);
}

static double dist_point_seg(const double *p, const double *a, const double *b)
{
    double ab[3], ap[3], l2 = 0, t = 0;
    for (int i = 0; i < 3; i++) {
        ab[i] = b[i] - a[i];
        ap[i] = p[i] - a[i];
        l2 += ab[i] * ab[i];
        t += ab[i] * ap[i];
    }
    t = l2 > 0 ? t / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double d2 = 0;
    for (int i = 0; i < 3; i++) {
        double d = ap[i] - t * ab[i];
        d2 += d * d;
    }
    return sqrt(d2);
}

/* A uniform 2D grid (x, y) over the reference segments, each listed in every cell its box
 * touches; a query looks at its cell and the 8 around it, so it finds every segment within one
 * cell size, and falls back to all segments when none is that close. */
typedef struct {
    double x0, y0, cell;
    size_t nx, ny;
    size_t *head; /* per cell, start in idx */
    size_t *idx;  /* segment ids (index of its first point) */
} grid_t;

static bool seg_ok(const cs_sim_ref_t *r, size_t k, size_t *line_end)
{
    (void)r;
    return k + 1 < *line_end;
}

static void each_seg_end(const cs_sim_ref_t *r, size_t li, size_t *b, size_t *e)
{
    *b = r->starts[li];
    *e = li + 1 < r->nlines ? r->starts[li + 1] : r->n;
}

static int grid_build(grid_t *g, const cs_sim_ref_t *r, double cell)
{
    double lo[2] = {HUGE_VAL, HUGE_VAL}, hi[2] = {-HUGE_VAL, -HUGE_VAL};
    for (size_t k = 0; k < r->n; k++)
        for (int i = 0; i < 2; i++) {
            lo[i] = fmin(lo[i], r->xyz[3 * k + i]);
            hi[i] = fmax(hi[i], r->xyz[3 * k + i]);
        }
    g->cell = cell;
    g->x0 = lo[0];
    g->y0 = lo[1];
    g->nx = (size_t)((hi[0] - lo[0]) / cell) + 1;
    g->ny = (size_t)((hi[1] - lo[1]) / cell) + 1;
    while (g->nx * g->ny > 4000000) {
        g->cell *= 2;
        g->nx = (size_t)((hi[0] - lo[0]) / g->cell) + 1;
        g->ny = (size_t)((hi[1] - lo[1]) / g->cell) + 1;
    }
    size_t ncell = g->nx * g->ny;
    g->head = calloc(ncell + 1, sizeof *g->head);
    if (g->head == NULL)
        return -1;
    for (int pass = 0; pass < 2; pass++) {
        for (size_t li = 0; li < r->nlines; li++) {
            size_t b, e;
            each_seg_end(r, li, &b, &e);
            for (size_t k = b; seg_ok(r, k, &e); k++) {
                const double *p = &r->xyz[3 * k], *q = &r->xyz[3 * k + 3];
                size_t cx0 = (size_t)((fmin(p[0], q[0]) - g->x0) / g->cell);
                size_t cx1 = (size_t)((fmax(p[0], q[0]) - g->x0) / g->cell);
                size_t cy0 = (size_t)((fmin(p[1], q[1]) - g->y0) / g->cell);
                size_t cy1 = (size_t)((fmax(p[1], q[1]) - g->y0) / g->cell);
                for (size_t cy = cy0; cy <= cy1 && cy < g->ny; cy++)
                    for (size_t cx = cx0; cx <= cx1 && cx < g->nx; cx++) {
                        size_t c = cy * g->nx + cx;
                        if (pass == 0)
                            g->head[c + 1]++;
                        else
                            g->idx[g->head[c]++] = k;
                    }
            }
        }
        if (pass == 0) {
            for (size_t c = 0; c < ncell; c++)
                g->head[c + 1] += g->head[c];
            g->idx = malloc((g->head[ncell] + 1) * sizeof *g->idx);
            if (g->idx == NULL)
                return -1;
        } else {
            /* head[c] now points at the end of cell c: shift back to starts. */
            for (size_t c = ncell; c > 0; c--)
                g->head[c] = g->head[c - 1];
            g->head[0] = 0;
        }
    }
    return 0;
}

static double brute(const cs_sim_ref_t *r, const double *p)
{
    double best = HUGE_VAL;
    for (size_t li = 0; li < r->nlines; li++) {
        size_t b, e;
        each_seg_end(r, li, &b, &e);
        if (e - b == 1)
            best = fmin(best, dist_point_seg(p, &r->xyz[3 * b], &r->xyz[3 * b]));
        for (size_t k = b; k + 1 < e; k++)
            best = fmin(best, dist_point_seg(p, &r->xyz[3 * k], &r->xyz[3 * k + 3]));
    }
    return best;
}

static double grid_query(const grid_t *g, const cs_sim_ref_t *r, const double *p)
{
    double best = HUGE_VAL;
    long cx = (long)floor((p[0] - g->x0) / g->cell), cy = (long)floor((p[1] - g->y0) / g->cell);
    for (long y = cy - 1; y <= cy + 1; y++)
        for (long x = cx - 1; x <= cx + 1; x++) {
            if (x < 0 || y < 0 || x >= (long)g->nx || y >= (long)g->ny)
                continue;
            size_t c = (size_t)y * g->nx + (size_t)x;
            for (size_t j = g->head[c]; j < g->head[c + 1]; j++) {
                size_t k = g->idx[j];
                best = fmin(best, dist_point_seg(p, &r->xyz[3 * k], &r->xyz[3 * k + 3]));
            }
        }
    if (best > g->cell)
        best = brute(r, p); /* nothing within one cell: look everywhere */
    return best;
}

double cs_sim_deviation(const cs_machine_t *m, const cs_sim_exec_t *ex, const cs_sim_ref_t *r,
                        double where[3])
{
    if (r->n == 0)
        return HUGE_VAL;
    grid_t g = {0};
    bool use_grid = grid_build(&g, r, 1.0) == 0;
    double spm[CS_AXES];
    for (unsigned i = 0; i < CS_AXES; i++)
        spm[i] = i < m->n_axes ? (double)m->axis[i].steps_per_mm / CS_MOTION_ONE : 1.0;
    int64_t pos[CS_AXES] = {0, 0, 0, 0};
    double worst = -1;
    for (size_t e = 0; e <= ex->n; e++) {
        if (e > 0)
            pos[ex->edges[e - 1].axis] += ex->edges[e - 1].dir;
        /* Several axes stepping at the same tick move together: measure after the last. */
        if (e < ex->n && e > 0 && ex->edges[e].t == ex->edges[e - 1].t)
            continue;
        double p[3] = {(double)pos[0] / spm[0], (double)pos[1] / spm[1], (double)pos[2] / spm[2]};
        double d = use_grid ? grid_query(&g, r, p) : brute(r, p);
        if (d > worst) {
            worst = d;
            if (where)
                memcpy(where, p, sizeof p);
        }
    }
    free(g.head);
    free(g.idx);
    return worst;
}

cs_err_t cs_sim_ref_from_path(cs_sim_ref_t *r, const cs_path_t *path, double end[3])
{
    double cur[3] = {0, 0, 0};
    cs_err_t e = cs_sim_ref_move(r, cur);
    for (size_t k = 0; k < path->n && e == CS_OK; k++) {
        const cs_bezier_t *c = &path->elems[k].curve;
        double p0[3], poly = 0;
        cs_path_eval_mm(c, 0.0, p0);
        bool rapid = path->elems[k].rapid;
        if (p0[0] != cur[0] || p0[1] != cur[1] || p0[2] != cur[2])
            e = cs_sim_ref_travel(r, p0); /* travel */
        for (unsigned i = 0; i < c->degree; i++) {
            double dx = (c->p[i + 1].x - c->p[i].x) / 65536.0;
            double dy = (c->p[i + 1].y - c->p[i].y) / 65536.0;
            double dz = (c->p[i + 1].z - c->p[i].z) / 65536.0;
            poly += sqrt(dx * dx + dy * dy + dz * dz);
        }
        size_t n = c->degree == 1 ? 1 : (size_t)fmin(fmax(poly / 0.005, 64), 1e6);
        for (size_t j = 1; j <= n && e == CS_OK; j++) {
            double q[3];
            cs_path_eval_mm(c, (double)j / (double)n, q);
            e = rapid ? cs_sim_ref_travel(r, q) : cs_sim_ref_line(r, q);
            memcpy(cur, q, sizeof q);
        }
    }
    if (end)
        memcpy(end, cur, sizeof cur);
    return e;
}
