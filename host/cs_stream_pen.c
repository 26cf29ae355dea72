/* cs_stream_pen: pen events between the curves of a servo-pen job (see cs_stream_pen.h). */
#include "cs_stream_pen.h"

#include <math.h>

#include "cs_err_text.h"
#include "cs_pen.h"

/* Settle waits cut into at most this many zero-step segments of 2^24 ticks (cs_segment_t's
 * limit): 16 x 2^24 ticks is 2.7 minutes at 100 kHz, far above any servo's settle time. */
#define SETTLE_SEGS_MAX 16

/* PEN us, then the settle wait: settle_ms of ticks (at least one) in zero-step SEGMENTs, as
 * cs_motion_pen plans it for segments mode. */
static cs_err_t pen_event(cs_stream_job_t *j, uint16_t us, double settle_ms, uint32_t tick_hz)
{
    cs_segment_t seg[SETTLE_SEGS_MAX] = {{0, {0, 0, 0, 0}}};
    double left = fmax(1.0, ceil(settle_ms * tick_hz / 1000.0));
    size_t n = 0;
    for (; left > 0 && n < SETTLE_SEGS_MAX; n++) {
        seg[n].ticks = (uint32_t)fmin(left, (double)(1u << 24));
        left -= seg[n].ticks;
    }
    if (left > 0)
        return CS_ERR_RANGE;
    cs_motion_pen_t ev = {0, us};
    cs_motion_segs_t s = {.v = seg, .n = n, .pens = &ev, .npens = 1};
    return cs_stream_job_add_motion(j, &s);
}

/* One element of path as cs_stream_job_add_path sends it. */
static cs_err_t add_elem(cs_stream_job_t *j, const cs_path_elem_t *el, int32_t feed, cs_pos_t tol,
                         cs_path_diag_t *diag)
{
    cs_path_t one = {0};
    one.elems = (cs_path_elem_t *)el; /* read only */
    one.n = 1;
    return cs_stream_job_add_path(j, &one, feed, tol, diag);
}

/* The straight rapid travel from *from to *to (nothing when they are the same point). */
static cs_err_t travel(cs_stream_job_t *j, const cs_vec3_t *from, const cs_vec3_t *to,
                       cs_path_loc_t loc, cs_pos_t tol, cs_path_diag_t *diag)
{
    if (from->x == to->x && from->y == to->y && from->z == to->z)
        return CS_OK;
    cs_path_elem_t el = {0};
    cs_vec3_t p[2] = {*from, *to};
    cs_err_t e = cs_bezier_init(&el.curve, 1, p);
    el.kind = CS_PATH_LINE;
    el.loc = loc;
    el.rapid = true;
    return e != CS_OK ? e : add_elem(j, &el, 0, tol, diag);
}

cs_err_t cs_stream_job_add_path_pen(cs_stream_job_t *j, const cs_path_t *path, int32_t feed,
                                    cs_pos_t tol, const cs_machine_pen_t *pen, uint32_t tick_hz,
                                    const cs_vec3_t *start, cs_path_diag_t *diag)
{
    if (pen == NULL || pen->mode != CS_MACHINE_PEN_SERVO)
        return cs_stream_job_add_path(j, path, feed, tol, diag);
    cs_vec3_t cur = *start;
    bool down = false;
    for (size_t k = 0; k < path->n; k++) {
        const cs_path_elem_t *el = &path->elems[k];
        cs_err_t e = CS_OK;
        if ((k == 0 || down) && cs_pen_stroke_starts(path, k)) {
            e = pen_event(j, (uint16_t)pen->up_us, pen->settle_ms, tick_hz);
            down = false;
        }
        if (e == CS_OK && !down && !el->rapid) {
            e = travel(j, &cur, &el->curve.p[0], el->loc, tol, diag);
            if (e == CS_OK)
                e = pen_event(j, (uint16_t)pen->down_us, pen->settle_ms, tick_hz);
            down = e == CS_OK;
        }
        if (e != CS_OK)
            return cs_path_diag_set(diag, e, el->loc, "pen event: %s", cs_err_text(e));
        if ((e = add_elem(j, el, feed, tol, diag)) != CS_OK)
            return e; /* diag set */
        cur = el->curve.p[el->curve.degree];
    }
    cs_err_t e = down ? pen_event(j, (uint16_t)pen->up_us, pen->settle_ms, tick_hz) : CS_OK;
    if (e != CS_OK)
        return cs_path_diag_set(diag, e, path->elems[path->n - 1].loc, "pen event: %s",
                                cs_err_text(e));
    return CS_OK;
}
