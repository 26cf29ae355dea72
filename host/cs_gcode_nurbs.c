/* cs_gcode_nurbs: the NURBS blocks of the G-code reader, G5.2 ... G5.3 in any plane and G6.2
 * (see cs_gcode_int.h; cs_gnurbs converts them). */
#include <math.h>
#include <string.h>

#include "cs_gcode_int.h"

static cs_err_t nurbs_emit(void *ctx, const cs_bezier_t *seg)
{
    gc_t *g = ctx;
    cs_err_t e = cs_gcode_add(g, seg, CS_PATH_OTHER, g->nurbs_loc.col, false);
    g->emit_failed = e != CS_OK;
    return e;
}

/* The open block becomes Bézier segments, at the feed of its first line. */
cs_err_t cs_gcode_nurbs_close(gc_t *g)
{
    const char *gname = g->nurbs == MOT_G62 ? "G6.2" : "G5.2";
    char why[160];
    double save_feed = g->feed;
    g->feed = g->nurbs_feed;
    g->emit_failed = false;
    cs_err_t e = cs_gnurbs_build(&g->nb, nurbs_emit, g, why, sizeof why);
    g->feed = save_feed;
    g->nurbs = 0;
    if (e != CS_OK)
        return g->emit_failed
                   ? e
                   : cs_path_diag_set(g->diag, e, g->nurbs_loc, "%s block: %s", gname, why);
    memcpy(g->pos, g->nb.cps[g->nb.n - 1].p, sizeof g->pos);
    return CS_OK;
}

static cs_err_t nurbs_push(gc_t *g, const double p[3], double w)
{
    if (cs_gnurbs_push(&g->nb, p, w) != CS_OK)
        return cs_path_diag_set(g->diag, CS_ERR_FULL, g->nurbs_loc,
                                "NURBS block with more than %u control points (or out of memory)",
                                CS_GNURBS_MAX_POINTS);
    return CS_OK;
}

/* A control point's axis words: the two of the plane (G5.2 works in G17, G18 and G19 as
 * LinuxCNC runs it), none of its normal. */
static cs_err_t nurbs_plane_words(gc_t *g, block_t *b, bool *has)
{
    int ax[3];
    cs_gcode_plane_axes(g->plane, ax);
    const word_t *A = &b->w['X' - 'A' + ax[0]], *B = &b->w['X' - 'A' + ax[1]];
    const word_t *N = &b->w['X' - 'A' + ax[2]];
    if (N->has)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, N->col),
                                "G5.2 control points in G%d are in %c and %c (no %c word)",
                                g->plane, 'X' + ax[0], 'X' + ax[1], 'X' + ax[2]);
    if (A->has != B->has)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, (A->has ? A : B)->col),
                                "a G5.2 control point in G%d needs both %c and %c", g->plane,
                                'X' + ax[0], 'X' + ax[1]);
    *has = A->has;
    return CS_OK;
}

/* The G5.2 line: opens the block with the tool's position as its first control point. */
static cs_err_t nurbs_open52(gc_t *g, block_t *b, unsigned col, bool has)
{
    const word_t *P = &b->w['P' - 'A'], *L = &b->w['L' - 'A'];
    if (g->incr)
        return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, cs_gcode_loc(g, col),
                                "G5.2 control points in G91 (incremental) mode are not "
                                "supported");
    g->nurbs = MOT_G52;
    g->nurbs_loc = cs_gcode_loc(g, col);
    g->nurbs_feed = g->feed;
    cs_gnurbs_begin(&g->nb, 3);
    if (L->has) {
        b->used |= BIT('L');
        if (L->v != floor(L->v))
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, L->col),
                                    "L (order) must be a whole number");
        /* LinuxCNC takes L only when it is above 3 (the default order). */
        if (L->v > CS_GNURBS_MAX_ORDER)
            return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, cs_gcode_loc(g, L->col),
                                    "NURBS order L%g: at most %d (cubic) is supported", L->v,
                                    CS_GNURBS_MAX_ORDER);
        if (L->v > 3)
            g->nb.order = (unsigned)L->v;
    }
    double w0 = (!has && P->has) ? P->v : 1.0;
    if (!(w0 > 0))
        return cs_path_diag_set(g->diag, CS_ERR_WEIGHT, cs_gcode_loc(g, P->col),
                                "G5.2 weight P must be positive");
    return nurbs_push(g, g->pos, w0);
}

/* A G5.2 line (first = the line that carries G5.2) or a control point line inside the block. */
cs_err_t cs_gcode_nurbs_line(gc_t *g, block_t *b, bool first, unsigned col)
{
    const word_t *P = &b->w['P' - 'A'], *L = &b->w['L' - 'A'];
    bool has = false;
    cs_err_t e = nurbs_plane_words(g, b, &has);
    if (e != CS_OK)
        return e;
    if (first && (e = nurbs_open52(g, b, col, has)) != CS_OK)
        return e;
    if (L->has && !first)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, L->col),
                                "L (order) belongs on the G5.2 line");
    if (P->has)
        b->used |= BIT('P');
    if (!has)
        return CS_OK;
    if (!P->has || !(P->v > 0))
        return cs_path_diag_set(g->diag, CS_ERR_WEIGHT, cs_gcode_loc(g, P->has ? P->col : col),
                                "each G5.2 control point needs a positive weight P");
    double t[3];
    cs_gcode_target(g, b, t);
    return nurbs_push(g, t, P->v);
}

/* A G6.2 line (first) or a line of its block: "G6.2 P<order> K<knot> X.. Y.. Z.. R<weight>",
 * then "K.. X.. Y.. Z.. R.." per control point, then "K.." alone for the last order knots (the
 * block form of Fanuc's G06.2 that LinuxCNC's G6.2 follows). Axis words left out keep the
 * previous control point's value; R defaults to 1. */
cs_err_t cs_gcode_g62_line(gc_t *g, block_t *b, bool first, unsigned col)
{
    const word_t *P = &b->w['P' - 'A'], *K = &b->w['K' - 'A'], *R = &b->w['R' - 'A'];
    if (first) {
        if (!P->has || P->v != floor(P->v) || P->v < 2 || P->v > CS_GNURBS_MAX_ORDER)
            return cs_path_diag_set(
                g->diag, CS_ERR_UNSUPPORTED, cs_gcode_loc(g, P->has ? P->col : col),
                "G6.2 needs P, the order: 2 to %d (cubic) are supported", CS_GNURBS_MAX_ORDER);
        if (g->incr)
            return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, cs_gcode_loc(g, col),
                                    "G6.2 control points in G91 (incremental) mode are not "
                                    "supported");
        b->used |= BIT('P');
        g->nurbs = MOT_G62;
        g->g62_knots = false;
        g->nurbs_loc = cs_gcode_loc(g, col);
        g->nurbs_feed = g->feed;
        cs_gnurbs_begin(&g->nb, (unsigned)P->v);
    }
    if (!K->has)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                "each line of a G6.2 block needs its knot K");
    b->used |= BIT('K') | BIT('R');
    if (cs_gnurbs_knot(&g->nb, K->v) != CS_OK)
        return cs_path_diag_set(g->diag, CS_ERR_FULL, cs_gcode_loc(g, K->col),
                                "too many G6.2 knots");
    if (!cs_gcode_any_axis(b) && !R->has && !first) {
        g->g62_knots = true;
        return g->nb.nknots == g->nb.n + g->nb.order ? cs_gcode_nurbs_close(g) : CS_OK;
    }
    if (g->g62_knots)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                "G6.2 control point after the knot-only lines that end the block");
    if (R->has && !(R->v > 0))
        return cs_path_diag_set(g->diag, CS_ERR_WEIGHT, cs_gcode_loc(g, R->col),
                                "G6.2 weight R must be positive");
    double t[3];
    memcpy(t, g->nb.n ? g->nb.cps[g->nb.n - 1].p : g->pos, sizeof t);
    for (int a = 0; a < 3; a++) {
        const word_t *w = &b->w['X' - 'A' + a];
        if (w->has) {
            b->used |= BIT('X' + a);
            t[a] = w->v * g->unit + cs_gcode_offset(g, a);
        }
    }
    cs_vec3_t v0, v1;
    if (first && (cs_gcode_to_vec(g, g->pos, col, &v0) != CS_OK ||
                  cs_gcode_to_vec(g, t, col, &v1) != CS_OK || !cs_gcode_vec_eq(&v0, &v1)))
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                "the first G6.2 control point must be where the tool is "
                                "(%.4f, %.4f, %.4f) mm",
                                g->pos[0], g->pos[1], g->pos[2]);
    return nurbs_push(g, t, R->has ? R->v : 1.0);
}

/* ---- one block --------------------------------------------------------------------------- */
