/* cs_sim_check: run vs job, 3D or pen-aware, through the grid (see cs_sim_check.h). */
#include "cs_sim_check.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_sim_grid.h"

/* Walks the run position by position (after the last edge of each tick, and the start). */
typedef struct {
    const cs_sim_exec_t *ex;
    double spm[3];
    uint64_t *t0; /* start tick of each segment, n + 1 of them */
    size_t nseg, e, k;
    int64_t pos[CS_AXES];
} walk_t;

static cs_err_t walk_init(walk_t *w, const cs_machine_t *m, const cs_segment_t *s, size_t n,
                          const cs_sim_exec_t *ex)
{
    memset(w, 0, sizeof *w);
    w->ex = ex;
    w->nseg = n;
    for (unsigned i = 0; i < 3; i++)
        w->spm[i] = (double)m->axis[i].steps_per_mm / CS_MOTION_ONE;
    w->t0 = malloc((n + 1) * sizeof *w->t0);
    if (w->t0 == NULL)
        return CS_ERR_FULL;
    w->t0[0] = 0;
    for (size_t k = 0; k < n; k++)
        w->t0[k + 1] = w->t0[k] + s[k].ticks;
    return CS_OK;
}

/* Next position into p (mm) and its segment (1-based, 0 for the start); false after the last. */
static bool walk_next(walk_t *w, double p[3], size_t *seg)
{
    const cs_sim_exec_t *ex = w->ex;
    if (w->e > ex->n)
        return false;
    uint64_t t = 0;
    if (w->e > 0) { /* several axes stepping at one tick move together: take them all */
        t = ex->edges[w->e - 1].t;
        w->pos[ex->edges[w->e - 1].axis] += ex->edges[w->e - 1].dir;
        while (w->e < ex->n && ex->edges[w->e].t == t) {
            w->pos[ex->edges[w->e].axis] += ex->edges[w->e].dir;
            w->e++;
        }
        while (w->k < w->nseg && w->t0[w->k] < t)
            w->k++;
    }
    w->e++;
    for (unsigned i = 0; i < 3; i++)
        p[i] = (double)w->pos[i] / w->spm[i];
    *seg = w->k;
    return true;
}

/* Pen down at height z: mode z, nearer down_z than up_z; mode servo, always (the events say). */
static bool pen_is_down(const cs_machine_pen_t *pen, double z)
{
    return pen->mode != CS_MACHINE_PEN_Z || fabs(z - pen->down_z_mm) < fabs(z - pen->up_z_mm);
}

/* Pen down at a position of segment seg (1-based) of the run: by height (mode z), or by the last
 * servo event before that segment (events[*cur..] not yet passed). */
static bool run_pen_down(const cs_machine_pen_t *pen, const cs_motion_segs_t *segs, size_t *cur,
                         bool *servo_down, size_t seg, double z)
{
    if (pen->mode == CS_MACHINE_PEN_Z)
        return pen_is_down(pen, z);
    for (; segs != NULL && *cur < segs->npens && segs->pens[*cur].seg < seg; (*cur)++)
        *servo_down = segs->pens[*cur].pulse_us == pen->down_us;
    return *servo_down;
}

/* Reference pieces to measure against: all (pen NULL) or the drawn ones (pen-down, not travel). */

static size_t *ref_pieces(const cs_sim_ref_t *r, const cs_machine_pen_t *pen, size_t *count)
{
    size_t *v = malloc((2 * r->n + 2) * sizeof *v), n = 0;
    if (v == NULL)
        return NULL;
    for (size_t li = 0; li < r->nlines; li++) {
        size_t b = r->starts[li], e = li + 1 < r->nlines ? r->starts[li + 1] : r->n;
        if (e - b == 1 && pen == NULL) { /* a lone point */
            v[2 * n] = v[2 * n + 1] = b;
            n++;
        }
        for (size_t k = b; k + 1 < e; k++) {
            if (pen != NULL && (r->travel[k + 1] || !pen_is_down(pen, r->xyz[3 * k + 2]) ||
                                !pen_is_down(pen, r->xyz[3 * k + 5])))
                continue;
            v[2 * n] = k;
            v[2 * n + 1] = k + 1;
            n++;
        }
    }
    *count = n;
    return v;
}

/* Growable list of points (3 doubles each). */
typedef struct {
    double *v;
    size_t n, cap;
} pts_t;

static cs_err_t pts_add(pts_t *a, const double p[3])
{
    void *b = a->v;
    if (!cs_path_grow(&b, &a->cap, a->n + 1, 3 * sizeof *a->v))
        return CS_ERR_FULL;
    a->v = b;
    memcpy(&a->v[3 * a->n++], p, 3 * sizeof *p);
    return CS_OK;
}

/* Pass 1: each measured position against the reference grid g; pen-down positions into *down. */
static cs_err_t measure_run(walk_t *w, cs_sim_grid_t *g, const cs_machine_pen_t *pen,
                            const cs_motion_segs_t *segs, pts_t *down, cs_sim_check_t *out)
{
    double p[3], prev[3] = {NAN, NAN, NAN};
    size_t seg, cur = 0;
    bool was_down = false, first = true, servo_down = false;
    out->dev = -1;
    while (walk_next(w, p, &seg)) {
        bool measure = true;
        if (pen != NULL) { /* drawing: an x y move pen down (the start is no move) */
            bool d = run_pen_down(pen, segs, &cur, &servo_down, seg, p[2]);
            out->pen_downs += d && !was_down && !first;
            measure = d && !first && (p[0] != prev[0] || p[1] != prev[1]);
            first = false;
            was_down = d;
            memcpy(prev, p, sizeof p);
            if (d && pts_add(down, p) != CS_OK)
                return CS_ERR_FULL;
        }
        if (!measure)
            continue;
        double d = g->nseg ? cs_sim_grid_nearest(g, p, out->dev, NULL) : HUGE_VAL;
        if (d > out->dev) {
            out->dev = d;
            memcpy(out->dev_at, p, sizeof p);
            out->dev_seg = seg;
        }
    }
    if (out->dev < 0)
        out->dev = 0; /* nothing drawn, nothing measured */
    return CS_OK;
}

/* Pass 2 (pen): points along the drawn reference pieces, spacing mm apart (so a stretch drawn
 * pen up longer than about spacing + 2 * the bound is seen), against the pen-down positions. */
static cs_err_t measure_drawn(const cs_sim_ref_t *r, const size_t *pc, size_t npc, pts_t *down,
                              double spacing, cs_sim_check_t *out)
{
    out->undrawn = 0;
    if (npc == 0)
        return CS_OK;
    if (down->n == 0) {
        out->undrawn = HUGE_VAL;
        memcpy(out->undrawn_at, &r->xyz[3 * pc[0]], sizeof out->undrawn_at);
        return CS_OK;
    }
    size_t *idx = malloc(2 * down->n * sizeof *idx);
    if (idx == NULL)
        return CS_ERR_FULL;
    for (size_t k = 0; k < down->n; k++)
        idx[2 * k] = idx[2 * k + 1] = k;
    cs_sim_grid_t g;
    cs_err_t e = cs_sim_grid_build(&g, down->v, idx, down->n, 2, 0.05);
    free(idx);
    if (e != CS_OK)
        return e;
    for (size_t j = 0; j < npc; j++) { /* along each drawn piece, every `spacing` mm */
        const double *a = &r->xyz[3 * pc[2 * j]], *b = &r->xyz[3 * pc[2 * j + 1]];
        double len = hypot(b[0] - a[0], b[1] - a[1]);
        size_t steps = (size_t)ceil(len / spacing);
        for (size_t i = 0; i <= steps; i++) {
            double t = steps ? (double)i / (double)steps : 0, q[3];
            for (int c = 0; c < 3; c++)
                q[c] = a[c] + t * (b[c] - a[c]);
            double d = cs_sim_grid_nearest(&g, q, out->undrawn, NULL);
            if (d > out->undrawn) {
                out->undrawn = d;
                memcpy(out->undrawn_at, q, sizeof out->undrawn_at);
            }
        }
    }
    cs_sim_grid_free(&g);
    return CS_OK;
}

/* The segment whose positions pass nearest (x y) to at. */
static size_t nearest_seg(walk_t *w, const double at[3])
{
    double p[3], best = HUGE_VAL;
    size_t seg, which = 0;
    w->e = w->k = 0;
    memset(w->pos, 0, sizeof w->pos);
    while (walk_next(w, p, &seg)) {
        double d = hypot(p[0] - at[0], p[1] - at[1]);
        if (d < best) {
            best = d;
            which = seg;
        }
    }
    return which;
}

cs_err_t cs_sim_check(const cs_machine_t *m, const cs_motion_segs_t *segs, const cs_sim_exec_t *ex,
                      const cs_sim_ref_t *ref, const cs_machine_pen_t *pen, cs_sim_check_t *out)
{
    memset(out, 0, sizeof *out);
    if (pen != NULL && pen->mode == CS_MACHINE_PEN_NONE)
        pen = NULL;
    out->pen = pen != NULL;
    /* tolerance + one step: the check's own bound (curvestep-sim) */
    double spacing = (double)m->tolerance / CS_POS_ONE_MM + cs_sim_step_mm(m);
    walk_t w;
    size_t npc = 0;
    size_t *pc = ref_pieces(ref, pen, &npc);
    cs_err_t e =
        pc == NULL ? CS_ERR_FULL : walk_init(&w, m, segs ? segs->v : NULL, segs ? segs->n : 0, ex);
    if (e != CS_OK) {
        free(pc);
        return e;
    }
    cs_sim_grid_t g;
    memset(&g, 0, sizeof g);
    /* cells no finer than 0.05 mm: a tolerance-scale search radius covers a few cells */
    if (npc > 0)
        e = cs_sim_grid_build(&g, ref->xyz, pc, npc, pen ? 2 : 3, 0.05);
    pts_t down = {NULL, 0, 0};
    if (e == CS_OK)
        e = measure_run(&w, &g, pen, segs, &down, out);
    cs_sim_grid_free(&g);
    if (e == CS_OK && pen != NULL)
        e = measure_drawn(ref, pc, npc, &down, spacing, out);
    if (e == CS_OK && pen != NULL && out->undrawn > 0)
        out->undrawn_seg = nearest_seg(&w, out->undrawn_at);
    free(down.v);
    free(pc);
    free(w.t0);
    return e;
}

bool cs_sim_check_print(const cs_machine_t *m, const cs_motion_segs_t *segs,
                         const cs_sim_exec_t *ex, const cs_sim_ref_t *ref,
                         const cs_machine_pen_t *pen, const double end[3])
{
    cs_sim_check_t c;
    if (cs_sim_check(m, segs, ex, ref, pen, &c) != CS_OK) {
        fprintf(stderr, "curvestep-sim: out of memory in the check\n");
        return false;
    }
    double bound = cs_machine_ini_to_double(m->tolerance) + cs_sim_step_mm(m);
    bool dev_ok = c.dev <= bound, drawn_ok = !c.pen || c.undrawn <= bound;
    printf("deviation%s: %.5f mm at (%.4f, %.4f, %.4f), segment %zu (tolerance + one step = "
           "%.5f mm) %s\n",
           c.pen ? " of pen-down motion (x y)" : "", c.dev, c.dev_at[0], c.dev_at[1], c.dev_at[2],
           c.dev_seg, bound,
           dev_ok  ? "ok"
           : c.pen ? "OVER: a pen-down travel"
                   : "OVER");
    if (c.pen)
        printf("pen: %zu pen-downs; drawn strokes reached pen down within %.5f mm, worst at "
               "(%.4f, %.4f) %s\n",
               c.pen_downs, c.undrawn, c.undrawn_at[0], c.undrawn_at[1],
               drawn_ok ? "ok" : "NOT DRAWN");
    if (!drawn_ok)
        printf("pen: segment %zu moves pen up over a stroke the job draws\n", c.undrawn_seg);
    bool end_ok = true;
    for (unsigned i = 0; i < 3; i++) {
        double spm = (double)m->axis[i].steps_per_mm / CS_MOTION_ONE;
        long long want = llround((double)llround(end[i] * 65536.0) / 65536.0 * spm);
        if (want != ex->pos[i])
            end_ok = false;
    }
    printf("final position vs job end (%.4f, %.4f, %.4f) rounded to steps: %s\n", end[0], end[1],
           end[2], end_ok ? "exact" : "DIFFERENT");
    return dev_ok && drawn_ok && end_ok;
}
