/* cs_motion: planner + segment generator on the host, segments kept in memory. */
#include "cs_motion.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cs_conv.h"
#include "cs_err_text.h"
#include "cs_input.h"
#include "cs_pen.h"
#include "cs_trace.h"

cs_err_t cs_motion_init(cs_motion_t *mo, const cs_machine_t *m)
{
    memset(mo, 0, sizeof *mo);
    mo->m = m;
    cs_err_t e = cs_planner_init(&mo->pl, m);
    if (e == CS_OK)
        e = cs_segment_init(&mo->gen, m);
    return e;
}

void cs_motion_segs_free(cs_motion_segs_t *s)
{
    free(s->v);
    free(s->pens);
    free(s->powers);
    memset(s, 0, sizeof *s);
}

void cs_motion_free(cs_motion_t *mo)
{
    cs_motion_segs_free(&mo->segs);
    free(mo->pend);
    mo->pend = NULL;
    mo->npend = mo->cappend = mo->pend0 = 0;
}

cs_err_t cs_motion_power(cs_motion_t *mo, const cs_motion_power_t *p)
{
    void *b = mo->pend;
    if (!cs_path_grow(&b, &mo->cappend, mo->npend + 1, sizeof *mo->pend))
        return CS_ERR_FULL;
    mo->pend = b;
    mo->pend[mo->npend] = *p;
    mo->pend[mo->npend++].seg = mo->blocks; /* the number of the next block queued */
    return CS_OK;
}

/* The marks whose block is the next one cut (or every one, all) go to segs.powers, at the next
 * segment. */
static cs_err_t land_powers(cs_motion_t *mo, bool all)
{
    cs_motion_segs_t *v = &mo->segs;
    for (; mo->pend0 < mo->npend && (all || mo->pend[mo->pend0].seg <= mo->blocks_cut);
         mo->pend0++) {
        void *b = v->powers;
        if (!cs_path_grow(&b, &v->cappowers, v->npowers + 1, sizeof *v->powers))
            return CS_ERR_FULL;
        v->powers = b;
        v->powers[v->npowers] = mo->pend[mo->pend0];
        v->powers[v->npowers++].seg = v->n;
    }
    return CS_OK;
}

/* Records a pen event before segment seg. */
static cs_err_t add_pen(cs_motion_segs_t *v, size_t seg, uint16_t pulse_us)
{
    void *b = v->pens;
    if (!cs_path_grow(&b, &v->cappens, v->npens + 1, sizeof *v->pens))
        return CS_ERR_FULL;
    v->pens = b;
    v->pens[v->npens].seg = seg;
    v->pens[v->npens++].pulse_us = pulse_us;
    return CS_OK;
}

static cs_err_t push(cs_motion_t *mo, const cs_segment_t *s)
{
    cs_motion_segs_t *v = &mo->segs;
    if (v->n >= (mo->max_segs ? mo->max_segs : CS_MOTION_MAX_SEGS)) {
        mo->over_limit = true;
        return CS_ERR_FULL;
    }
    if (v->n == v->cap) {
        size_t cap = v->cap ? v->cap * 2 : 1024;
        cs_segment_t *p = realloc(v->v, cap * sizeof *p);
        if (p == NULL)
            return CS_ERR_FULL;
        v->v = p;
        v->cap = cap;
    }
    v->v[v->n++] = *s;
    mo->ticks += s->ticks;
    for (unsigned i = 0; i < CS_AXES; i++) {
        mo->pos[i] += s->steps[i];
        mo->steps += s->steps[i] < 0 ? -(int64_t)s->steps[i] : s->steps[i];
    }
    return CS_OK;
}

/* Cuts segments until the oldest block is finished (one slot freed). */
static cs_err_t cut_one_block(cs_motion_t *mo)
{
    cs_segment_t s;
    cs_err_t le = land_powers(mo, false);
    if (le != CS_OK)
        return le;
    mo->blocks_cut++;
    do {
        cs_err_t e = cs_segment_next(&mo->gen, &mo->pl, &s);
        if (e != CS_OK)
            return e;
        e = push(mo, &s);
        if (e != CS_OK)
            return e;
    } while (!cs_segment_block_end(&mo->gen));
    return CS_OK;
}

cs_err_t cs_motion_line(cs_motion_t *mo, const cs_pos_t target[CS_AXES], int32_t feed,
                        uint32_t line)
{
    if (cs_planner_full(&mo->pl)) {
        cs_err_t e = cut_one_block(mo);
        if (e != CS_OK)
            return e;
    }
    unsigned before = cs_planner_count(&mo->pl);
    cs_err_t e = cs_planner_line(&mo->pl, target, feed, line);
    if (e == CS_OK && cs_planner_count(&mo->pl) > before)
        mo->blocks++;
    return e;
}

cs_err_t cs_motion_pen(cs_motion_t *mo, uint16_t pulse_us, double settle_ms)
{
    cs_err_t e = cs_motion_finish(mo);
    if (e == CS_OK)
        e = add_pen(&mo->segs, mo->segs.n, pulse_us);
    /* the wait, in segments of at most 2^24 ticks (cs_segment_t's limit), at least one tick */
    double left = fmax(1.0, ceil(settle_ms * mo->m->tick_hz / 1000.0));
    while (e == CS_OK && left > 0) {
        cs_segment_t s = {(uint32_t)fmin(left, (double)(1u << 24)), {0, 0, 0, 0}};
        left -= s.ticks;
        e = push(mo, &s);
    }
    return e;
}

int32_t cs_motion_speed(double mm_s)
{
    if (!(mm_s > 0))
        return 0;
    double q = mm_s * CS_MOTION_ONE;
    return q >= 2147483647.0 ? INT32_MAX : (int32_t)llround(q) < 1 ? 1 : (int32_t)llround(q);
}

cs_err_t cs_motion_line_mm(cs_motion_t *mo, double x, double y, double z, double feed_mm_s,
                           uint32_t line)
{
    cs_vec3_t p;
    cs_err_t e = cs_conv_mm_to_vec(x, y, z, &p);
    if (e != CS_OK)
        return e;
    cs_pos_t t[CS_AXES] = {p.x, p.y, p.z, mo->pl.pos[CS_AXIS_A]};
    return cs_motion_line(mo, t, cs_motion_speed(feed_mm_s), line);
}

cs_err_t cs_motion_finish(cs_motion_t *mo)
{
    while (cs_planner_count(&mo->pl) > 0) {
        cs_err_t e = cut_one_block(mo);
        if (e != CS_OK)
            return e;
    }
    return land_powers(mo, true); /* marks after the last move: at the end */
}

static void write_seg(FILE *f, const cs_machine_t *m, const cs_segment_t *s)
{
    fprintf(f, "%u %d %d %d", (unsigned)s->ticks, (int)s->steps[0], (int)s->steps[1],
            (int)s->steps[2]);
    if (m->n_axes > 3)
        fprintf(f, " %d", (int)s->steps[3]);
    fputc('\n', f);
}

int cs_motion_write(FILE *f, const cs_machine_t *m, const cs_segment_t *s, size_t n)
{
    fprintf(f, "# curvestep segments tick_hz=%u axes=%u\n", (unsigned)m->tick_hz,
            (unsigned)m->n_axes);
    for (size_t k = 0; k < n; k++)
        write_seg(f, m, &s[k]);
    return ferror(f) ? -1 : 0;
}

bool cs_motion_spindle_used(const cs_motion_segs_t *s)
{
    for (size_t q = 0; q < s->npowers; q++)
        if (s->powers[q].spindle == 3 || s->powers[q].spindle == 4)
            return true;
    return false;
}

/* The power marks before segment k (all: every one left) as comment lines. */
static void write_powers(FILE *f, const cs_motion_segs_t *s, size_t *q, size_t k, bool all)
{
    for (; *q < s->npowers && (all || s->powers[*q].seg == k); (*q)++) {
        const cs_motion_power_t *p = &s->powers[*q];
        if (p->spindle == 5)
            fprintf(f, "# spindle M5\n");
        else if (p->rapid)
            fprintf(f, "# spindle M%u S%g rapid\n", (unsigned)p->spindle, p->s);
        else
            fprintf(f, "# spindle M%u S%g F%.3f\n", (unsigned)p->spindle, p->s, p->feed_mm_s);
    }
}

int cs_motion_write_segs(FILE *f, const cs_machine_t *m, const cs_motion_segs_t *s)
{
    cs_motion_write(f, m, s->v, 0); /* the header */
    size_t p = 0, q = s->npowers;
    if (cs_motion_spindle_used(s))
        q = 0; /* a job that never turns a spindle on says nothing about it */
    for (size_t k = 0; k < s->n; k++) {
        for (; p < s->npens && s->pens[p].seg == k; p++)
            fprintf(f, "pen %u\n", (unsigned)s->pens[p].pulse_us);
        write_powers(f, s, &q, k, false);
        write_seg(f, m, &s->v[k]);
    }
    for (; p < s->npens; p++)
        fprintf(f, "pen %u\n", (unsigned)s->pens[p].pulse_us);
    write_powers(f, s, &q, s->n, true);
    return ferror(f) ? -1 : 0;
}

static int grow(cs_motion_segs_t *v)
{
    if (v->n < v->cap)
        return 0;
    size_t cap = v->cap ? v->cap * 2 : 1024;
    cs_segment_t *p = realloc(v->v, cap * sizeof *p);
    if (p == NULL)
        return -1;
    v->v = p;
    v->cap = cap;
    return 0;
}

int cs_motion_read(FILE *f, const char *name, const cs_machine_t *m, cs_motion_segs_t *out,
                   char *err, size_t errlen)
{
    char buf[512];
    unsigned lineno = 0;
    while (fgets(buf, sizeof buf, f)) {
        lineno++;
        char *p = buf;
        while (*p == ' ' || *p == '\t')
            p++;
        if (*p == '\n' || *p == '\0' || *p == '\r')
            continue;
        if (*p == '#') {
            unsigned hz, axes;
            if (sscanf(p, "# curvestep segments tick_hz=%u axes=%u", &hz, &axes) == 2) {
                if (hz != m->tick_hz || axes != m->n_axes) {
                    snprintf(err, errlen,
                             "%s:%u: segments made for tick_hz=%u axes=%u, machine has "
                             "tick_hz=%u axes=%u (use the same --machine as plan)",
                             name, lineno, hz, axes, (unsigned)m->tick_hz, (unsigned)m->n_axes);
                    return -1;
                }
            }
            continue;
        }
        unsigned us;
        char tail;
        if (strncmp(p, "pen", 3) == 0) { /* a servo pen event before the next segment */
            if (sscanf(p, "pen %u %c", &us, &tail) != 1 || us < CS_MACHINE_SERVO_MIN_US ||
                us > CS_MACHINE_SERVO_MAX_US) {
                snprintf(err, errlen, "%s:%u: expected \"pen PULSE_US\" with 400..2600 us", name,
                         lineno);
                return -1;
            }
            if (add_pen(out, out->n, (uint16_t)us) != CS_OK) {
                snprintf(err, errlen, "%s:%u: out of memory", name, lineno);
                return -1;
            }
            continue;
        }
        long long v[1 + CS_AXES] = {0, 0, 0, 0, 0};
        int used = 0, k = 0;
        while (k < 1 + CS_AXES && sscanf(p, "%lld%n", &v[k], &used) == 1) {
            p += used;
            k++;
        }
        while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n')
            p++;
        if (k != 1 + m->n_axes || *p != '\0') {
            snprintf(err, errlen, "%s:%u: expected %u integers: ticks and the steps of each axis",
                     name, lineno, 1u + m->n_axes);
            return -1;
        }
        cs_segment_t s = {0, {0, 0, 0, 0}};
        if (v[0] < 1 || v[0] > (1LL << 24)) {
            snprintf(err, errlen, "%s:%u: ticks must be in 1..16777216", name, lineno);
            return -1;
        }
        s.ticks = (uint32_t)v[0];
        for (unsigned i = 0; i < m->n_axes; i++) {
            if (v[1 + i] > v[0] || v[1 + i] < -v[0]) {
                snprintf(err, errlen, "%s:%u: more steps than ticks on axis %u", name, lineno, i);
                return -1;
            }
            s.steps[i] = (int32_t)v[1 + i];
        }
        if (grow(out) != 0) {
            snprintf(err, errlen, "%s:%u: out of memory", name, lineno);
            return -1;
        }
        out->v[out->n++] = s;
    }
    if (ferror(f)) {
        snprintf(err, errlen, "%s:%u: read error", name, lineno);
        return -1;
    }
    return 0;
}

cs_err_t cs_motion_read_job(const char *file, cs_path_t *path, cs_path_diag_t *diag)
{
    return cs_motion_read_job_ex(file, false, path, diag);
}

cs_err_t cs_motion_read_job_ex(const char *file, bool lenient, cs_path_t *path,
                               cs_path_diag_t *diag)
{
    cs_input_opts_t o;
    cs_input_opts_init(&o);
    o.lenient = lenient;
    return cs_input_load(file, &o, path, diag);
}

static const char *axis_letter(unsigned i)
{
    static const char *const n[CS_AXES] = {"x", "y", "z", "a"};
    return i < CS_AXES ? n[i] : "?";
}

static cs_err_t too_many(const cs_motion_t *mo, cs_path_loc_t loc, cs_path_diag_t *diag)
{
    return cs_path_diag_set(diag, CS_ERR_RANGE, loc,
                            "the job needs more than %zu step segments: too large to plan "
                            "(--max-segments; docs/inputs.md, Limits)",
                            mo->max_segs ? mo->max_segs : CS_MOTION_MAX_SEGS);
}

static cs_err_t move_to(cs_motion_t *mo, const cs_vec3_t *p, int32_t feed, cs_path_loc_t loc,
                        cs_path_diag_t *diag)
{
    cs_pos_t t[CS_AXES] = {p->x, p->y, p->z, mo->pl.pos[CS_AXIS_A]};
    cs_err_t e = cs_motion_line(mo, t, feed, loc.line);
    if (e == CS_ERR_LIMIT) {
        for (unsigned i = 0; i < mo->m->n_axes; i++) {
            const cs_axis_cfg_t *a = &mo->m->axis[i];
            if (t[i] < a->travel_min || t[i] > a->travel_max)
                return cs_path_diag_set(diag, e, loc,
                                        "move to %s = %.4f mm leaves the travel %.4f .. %.4f mm "
                                        "(soft limit; nothing was sent)",
                                        axis_letter(i), cs_conv_pos_to_mm(t[i]),
                                        cs_conv_pos_to_mm(a->travel_min),
                                        cs_conv_pos_to_mm(a->travel_max));
        }
    }
    if (e != CS_OK && mo->over_limit)
        return too_many(mo, loc, diag);
    if (e != CS_OK)
        return cs_path_diag_set(diag, e, loc, "planning failed: %s", cs_err_text(e));
    return CS_OK;
}

/* [pen] mode = servo: raise the pen before a stroke starts (or a rapid), lower it before a
 * drawn element while it is up; the first raise happens before the first travel. */
static cs_err_t servo_before(cs_motion_t *mo, const cs_path_t *path, size_t k, bool *down,
                             cs_path_diag_t *diag)
{
    const cs_path_elem_t *el = &path->elems[k];
    const cs_machine_pen_t *pen = mo->pen;
    if (pen == NULL || pen->mode != CS_MACHINE_PEN_SERVO)
        return CS_OK;
    cs_err_t e = CS_OK;
    if ((k == 0 || *down) && cs_pen_stroke_starts(path, k)) {
        e = cs_motion_pen(mo, (uint16_t)pen->up_us, pen->settle_ms);
        *down = false;
    }
    if (e == CS_OK && !*down && !el->rapid) {
        /* the travel to the element's start, then the pen comes down there */
        e = move_to(mo, &el->curve.p[0], 0, el->loc, diag);
        if (e != CS_OK)
            return e;
        e = cs_motion_pen(mo, (uint16_t)pen->down_us, pen->settle_ms);
        *down = e == CS_OK;
    }
    return e != CS_OK ? cs_path_diag_set(diag, e, el->loc, "pen event: %s", cs_err_text(e)) : e;
}

/* A power mark before element el's moves (travel: before the rapid travel to its start) when
 * the input gave a spindle state and it differs from *last. */
static cs_err_t mark_power(cs_motion_t *mo, const cs_path_elem_t *el, bool travel,
                           int32_t el_feed, cs_motion_power_t *last, cs_path_diag_t *diag)
{
    if (el->spindle == 0)
        return CS_OK;
    cs_motion_power_t p = {0, el->spindle, travel || el->rapid, el->spindle_s,
                           travel || el->rapid ? 0.0 : (double)el_feed / CS_MOTION_ONE};
    if (p.spindle == last->spindle && p.rapid == last->rapid && p.s == last->s &&
        p.feed_mm_s == last->feed_mm_s)
        return CS_OK;
    *last = p;
    if (cs_motion_power(mo, &p) != CS_OK)
        return cs_path_diag_set(diag, CS_ERR_FULL, el->loc, "out of memory");
    return CS_OK;
}

cs_err_t cs_motion_plan_path(cs_motion_t *mo, const cs_path_t *path, cs_pos_t tol, int method,
                             int32_t feed, cs_path_diag_t *diag)
{
    if (feed <= 0)
        feed = mo->m->default_feed;
    cs_vec3_t cur = {mo->pl.pos[0], mo->pl.pos[1], mo->pl.pos[2]};
    bool down = false;
    cs_motion_power_t last = {0};
    for (size_t k = 0; k < path->n; k++) {
        const cs_path_elem_t *el = &path->elems[k];
        const cs_bezier_t *c = &el->curve;
        cs_err_t pe = servo_before(mo, path, k, &down, diag);
        if (pe != CS_OK)
            return pe;
        /* The job's own feed (G-code F) wins; rapid moves (G0) run at the axes' max rates. */
        int32_t el_feed = el->rapid ? 0 : el->feed_mm_s > 0 ? cs_motion_speed(el->feed_mm_s) : feed;
        bool travel = c->p[0].x != cur.x || c->p[0].y != cur.y || c->p[0].z != cur.z;
        cs_err_t me = mark_power(mo, el, travel, el_feed, &last, diag);
        if (me != CS_OK)
            return me;
        if (travel) {
            cs_err_t e = move_to(mo, &c->p[0], 0, el->loc, diag); /* rapid travel */
            if (e != CS_OK)
                return e;
        }
        me = mark_power(mo, el, false, el_feed, &last, diag);
        if (me != CS_OK)
            return me;
        cs_trace_t tr;
        cs_err_t e = cs_trace_begin(&tr, c, tol, (cs_trace_method_t)method);
        if (e != CS_OK)
            return cs_path_diag_set(diag, e, el->loc, "cannot trace: %s", cs_err_text(e));
        cs_vec3_t pt;
        while ((e = cs_trace_next(&tr, &pt)) == CS_OK) {
            e = move_to(mo, &pt, el_feed, el->loc, diag);
            if (e != CS_OK)
                return e;
        }
        if (e != CS_END)
            return cs_path_diag_set(diag, e, el->loc, "tracing failed: %s", cs_err_text(e));
        cur = c->p[c->degree];
    }
    cs_err_t e = down ? cs_motion_pen(mo, (uint16_t)mo->pen->up_us, mo->pen->settle_ms) : CS_OK;
    if (e == CS_OK)
        e = cs_motion_finish(mo);
    if (e != CS_OK && mo->over_limit && path->n > 0)
        return too_many(mo, path->elems[path->n - 1].loc, diag);
    if (e != CS_OK) {
        cs_path_loc_t loc = {path->n ? path->elems[path->n - 1].loc.file : "job", 0, 0};
        return cs_path_diag_set(diag, e, loc, "cutting segments failed: %s", cs_err_text(e));
    }
    return CS_OK;
}
