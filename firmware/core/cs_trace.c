/* cs_trace: one front for the tracers (see cs_trace.h). It checks the tolerance, picks the
 * engine (AFD does not difference rational curves, and FD hands back those that would need too
 * many steps for its 128-bit format: both then go to the homogeneous reach subdivision, see
 * docs/fixed-point.md; cs_predict takes planar polynomial curves up to degree 3, the reach tracer
 * the rest) and caps the vertex count so no caller can be made to loop forever. */
#include "cs_trace.h"

CS_STATIC_ASSERT(CS_TRACE_TOL_MIN >= CS_SUBDIV_TOL_MIN, trace_tol_min_covers_subdiv);
CS_STATIC_ASSERT(CS_TRACE_TOL_MAX <= CS_SUBDIV_TOL_MAX, trace_tol_max_within_subdiv);
CS_STATIC_ASSERT(CS_TRACE_TOL_MIN >= CS_PREDICT_TOL_MIN, trace_tol_min_covers_predict);
CS_STATIC_ASSERT(CS_TRACE_TOL_MAX <= CS_PREDICT_TOL_MAX, trace_tol_max_within_predict);
CS_STATIC_ASSERT(CS_TRACE_TOL_MIN > CS_FD3_SLACK_LSB, trace_tol_min_covers_fd3);

/* One begin per configured engine (CS_TRACE_METHODS); an engine left out answers
 * CS_ERR_UNSUPPORTED. Each sets tr->impl to what runs. */
static cs_err_t begin_reach(cs_trace_t *tr, const cs_bezier_t *c, cs_pos_t tol)
{
#if CS_TRACE_METHODS & CS_TRACE_WITH_SUBDIV
    tr->impl = CS_TRACE_IMPL_SUBDIV_REACH;
    return cs_subdiv_reach_begin(&tr->u.reach, c, tol);
#else
    (void)tr, (void)c, (void)tol;
    return CS_ERR_UNSUPPORTED;
#endif
}

static cs_err_t begin_predict(cs_trace_t *tr, const cs_bezier_t *c, cs_pos_t tol)
{
#if CS_TRACE_METHODS & CS_TRACE_WITH_PREDICT
    if (!c->rational) {
        /* cs_predict_begin makes cs_predict_accepts' checks itself: CS_ERR_UNSUPPORTED (tol is
         * within its range, the asserts above) exactly for a curve it does not take */
        tr->impl = CS_TRACE_IMPL_PREDICT;
        cs_err_t e = cs_predict_begin(&tr->u.pr, c, tol);
        if (e != CS_ERR_UNSUPPORTED)
            return e;
    } else if (cs_ellarc_begin(&tr->u.arc, c, tol) == CS_OK) {
        /* a circle or ellipse piece: equal-angle chords by the rotation recurrence (cs_ellarc);
         * the conic predictor takes the pieces it refuses (tol below its minimum, other
         * weights) */
        tr->impl = CS_TRACE_IMPL_ELLARC;
        return CS_OK;
    } else if (cs_predict_accepts(c)) {
        tr->impl = CS_TRACE_IMPL_PREDICT;
        return cs_predict_begin_conic(&tr->u.pr, c, tol);
    }
#endif
    return begin_reach(tr, c, tol);
}

static cs_err_t begin_fd(cs_trace_t *tr, const cs_bezier_t *c, cs_pos_t tol)
{
#if CS_TRACE_METHODS & CS_TRACE_WITH_FD
    cs_err_t e;
    if (cs_fd3_accepts(c) && (e = cs_fd3_begin(&tr->u.fd3, c, tol)) != CS_ERR_UNSUPPORTED) {
        tr->impl = CS_TRACE_IMPL_FD3; /* planar polynomial: the specialised loop */
        return e;
    }
    tr->impl = CS_TRACE_IMPL_FD;
    e = cs_fd_begin(&tr->u.fd, c, tol);
    /* a rational curve needing more than 2^(60/n) steps goes to the reach subdivision */
    return e == CS_ERR_UNSUPPORTED ? begin_reach(tr, c, tol) : e;
#else
    (void)tr, (void)c, (void)tol;
    return CS_ERR_UNSUPPORTED;
#endif
}

static cs_err_t begin_afd(cs_trace_t *tr, const cs_bezier_t *c, cs_pos_t tol)
{
#if CS_TRACE_METHODS & CS_TRACE_WITH_AFD
    if (!c->rational) {
        tr->impl = CS_TRACE_IMPL_AFD;
        return cs_afd_begin(&tr->u.afd, c, tol);
    }
    return begin_reach(tr, c, tol);
#else
    (void)tr, (void)c, (void)tol;
    return CS_ERR_UNSUPPORTED;
#endif
}

cs_err_t cs_trace_begin(cs_trace_t *tr, const cs_bezier_t *c, cs_pos_t tol,
                        cs_trace_method_t method)
{
    tr->done = true;
    tr->count = 0;
    tr->method = (uint8_t)method;
    if (method != CS_TRACE_FD && method != CS_TRACE_AFD && method != CS_TRACE_SUBDIV &&
        method != CS_TRACE_PREDICT)
        return CS_ERR_ARG;
    if (tol < CS_TRACE_TOL_MIN || tol > CS_TRACE_TOL_MAX)
        return CS_ERR_TOLERANCE;
    cs_err_t e = method == CS_TRACE_PREDICT  ? begin_predict(tr, c, tol)
                 : method == CS_TRACE_SUBDIV ? begin_reach(tr, c, tol)
                 : method == CS_TRACE_FD     ? begin_fd(tr, c, tol)
                                             : begin_afd(tr, c, tol);
    if (e == CS_OK)
        tr->done = false;
    return e;
}

/* The next vertex of every engine but the default one (cs_trace_next below). */
static cs_err_t next_other(cs_trace_t *tr, cs_vec3_t *pt)
{
    (void)pt; /* unused only when no engine is configured */
    switch (tr->impl) {
#if CS_TRACE_METHODS & CS_TRACE_WITH_FD
    case CS_TRACE_IMPL_FD:
        return cs_fd_next(&tr->u.fd, pt);
    case CS_TRACE_IMPL_FD3:
        return cs_fd3_next(&tr->u.fd3, pt);
#endif
#if CS_TRACE_METHODS & CS_TRACE_WITH_AFD
    case CS_TRACE_IMPL_AFD:
        return cs_afd_next(&tr->u.afd, pt);
#endif
#if CS_TRACE_METHODS & CS_TRACE_WITH_PREDICT
    case CS_TRACE_IMPL_ELLARC:
        return cs_ellarc_next(&tr->u.arc, pt);
#endif
#if CS_TRACE_METHODS & CS_TRACE_WITH_SUBDIV
    case CS_TRACE_IMPL_SUBDIV_REACH:
        return cs_subdiv_reach_next(&tr->u.reach, pt);
#endif
    default: /* no engine started (cannot happen after a successful begin) */
        return CS_ERR_ARG;
    }
}

cs_err_t cs_trace_next(cs_trace_t *tr, cs_vec3_t *pt)
{
    if (tr->done)
        return CS_END;
    if (tr->count >= CS_TRACE_MAX_VERTICES) {
        tr->done = true;
        return CS_ERR_DEPTH;
    }
#if CS_TRACE_METHODS & CS_TRACE_WITH_PREDICT
    /* the default tracer by a direct branch, not through the switch's jump table (an indirect
     * jump a vertex: 1.5 % of a curve at 0.1 mm on the host) */
    cs_err_t e =
        tr->impl == CS_TRACE_IMPL_PREDICT ? cs_predict_next(&tr->u.pr, pt) : next_other(tr, pt);
#else
    cs_err_t e = next_other(tr, pt);
#endif
    if (e == CS_OK)
        tr->count++;
    else
        tr->done = true;
    return e;
}
