/* cs_sim: execution on the POSIX port and measurements from the recorded edges. */
#include "cs_sim.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cs_sim_check.h"
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
    free(ex->marks);
    ex->marks = NULL;
    ex->nmarks = 0;
    free(ex->spins);
    ex->spins = NULL;
    ex->nspins = 0;
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

double cs_sim_deviation(const cs_machine_t *m, const cs_sim_exec_t *ex, const cs_sim_ref_t *r,
                        double where[3])
{
    if (r->n == 0)
        return HUGE_VAL;
    cs_sim_check_t c; /* the 3D check through the grid (cs_sim_check), segments unnamed */
    if (cs_sim_check(m, NULL, ex, r, NULL, &c) != CS_OK)
        return HUGE_VAL;
    if (where)
        memcpy(where, c.dev_at, sizeof c.dev_at);
    return c.dev;
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
