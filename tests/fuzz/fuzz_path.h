/* Checks shared by the fuzz targets of the host path readers (G-code, HP-GL, SVG path data, SVG
 * documents): a diagnostic is complete, two reads of one input agree, every element is a valid
 * cs_bezier_t continuous with the one before it, and the core tracer ends each element exactly
 * on its last control point. Header only (see fuzz_common.h, included first, for why). */
#ifndef FUZZ_PATH_H
#define FUZZ_PATH_H

#include "cs_trace.h"

/* Elements traced per input, and vertices allowed per element (a 0.01 mm tolerance on a curve
 * inside the 8192 mm square needs far fewer). */
#define FUZZ_TRACE_ELEMS 8
#define FUZZ_TRACE_MAX   200000

/* Traces c at 0.01 mm: it must end (CS_END) within FUZZ_TRACE_MAX vertices, on c's last point. */
static inline void fuzz_trace(const cs_bezier_t *c)
{
    cs_trace_t tr;
    cs_pos_t tol = CS_POS_ONE_MM / 100;
    FUZZ_CHECK(cs_trace_begin(&tr, c, tol, CS_TRACE_SUBDIV) == CS_OK);
    cs_vec3_t pt, last = c->p[0];
    cs_err_t e;
    unsigned n = 0;
    while ((e = cs_trace_next(&tr, &pt)) == CS_OK) {
        last = pt;
        FUZZ_CHECK(++n <= FUZZ_TRACE_MAX);
    }
    FUZZ_CHECK(e == CS_END);
    const cs_vec3_t *end = &c->p[c->degree];
    FUZZ_CHECK(n == 0 || (last.x == end->x && last.y == end->y && last.z == end->z));
}

/* A refusal names the file "fuzz", carries its own code, a line (and a column when col) and a
 * reason. */
static inline void fuzz_check_diag(cs_err_t e, const cs_path_diag_t *d, bool col)
{
    if (e == CS_OK)
        return;
    FUZZ_CHECK(d->code == e && d->loc.line >= 1 && (!col || d->loc.col >= 1) &&
               d->reason[0] != '\0');
    FUZZ_CHECK(strcmp(d->loc.file, "fuzz") == 0);
}

/* Field by field (struct padding is not copied by assignment, so no memcmp). */
static inline bool fuzz_same_curve(const cs_bezier_t *a, const cs_bezier_t *b)
{
    if (a->degree != b->degree || a->rational != b->rational)
        return false;
    for (unsigned i = 0; i <= a->degree && i < CS_BEZIER_MAX_POINTS; i++)
        if (a->p[i].x != b->p[i].x || a->p[i].y != b->p[i].y || a->p[i].z != b->p[i].z ||
            (a->rational && a->w[i] != b->w[i]))
            return false;
    return true;
}

/* What a 2-D reader (HP-GL, SVG) makes of one input, read twice (p with e, d; q with e2, d2):
 * the same answer at the same place and the same elements (deterministic); every element has a
 * position, an arc piece is a rational quadratic with weights in range, every other kind passes
 * check_kind; every point is in range with z 0; an element starts where the previous one of its
 * subpath ended; subpath numbers never go down; the first FUZZ_TRACE_ELEMS trace cleanly. */
static inline void fuzz_check_flat_reads(cs_err_t e, const cs_path_diag_t *d, const cs_path_t *p,
                                         cs_err_t e2, const cs_path_diag_t *d2, const cs_path_t *q,
                                         void (*check_kind)(const cs_path_elem_t *))
{
    FUZZ_CHECK(e2 == e && q->n == p->n);
    if (e != CS_OK)
        FUZZ_CHECK(d2->loc.line == d->loc.line && d2->loc.col == d->loc.col);
    for (size_t i = 0; i < p->n; i++) {
        const cs_path_elem_t *el = &p->elems[i];
        const cs_bezier_t *c = &el->curve;
        FUZZ_CHECK(fuzz_same_curve(c, &q->elems[i].curve));
        FUZZ_CHECK(el->loc.line >= 1 && el->loc.col >= 1);
        if (el->kind == CS_PATH_ARC) {
            FUZZ_CHECK(c->degree == 2 && c->rational);
            for (unsigned k = 0; k <= 2; k++)
                FUZZ_CHECK(c->w[k] >= CS_WEIGHT_MIN && c->w[k] <= CS_WEIGHT_ONE);
        } else {
            check_kind(el);
        }
        for (unsigned k = 0; k <= c->degree; k++)
            FUZZ_CHECK(cs_fixed_vec_ok(&c->p[k]) && c->p[k].z == 0);
        if (i > 0 && el->subpath == p->elems[i - 1].subpath) {
            const cs_bezier_t *a = &p->elems[i - 1].curve;
            const cs_vec3_t *end = &a->p[a->degree], *start = &c->p[0];
            FUZZ_CHECK(end->x == start->x && end->y == start->y);
        }
        if (i > 0)
            FUZZ_CHECK(el->subpath >= p->elems[i - 1].subpath);
        if (i < FUZZ_TRACE_ELEMS)
            fuzz_trace(c);
    }
}

#endif /* FUZZ_PATH_H */
