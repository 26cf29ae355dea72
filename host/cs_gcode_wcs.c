/* cs_gcode_wcs: work coordinates and probing for the G-code reader (see cs_gcode_int.h). The
 * offsets live in the numbered parameters, as LinuxCNC keeps them (G-code reference,
 * "Coordinate Systems" and "Numbered Parameters"): #5221.. for G54, 20 apart for G55 .. G59.3,
 * #5220 the system in use, #5211.. the G92 offsets with #5210 saying whether they apply,
 * #5161.. / #5181.. the G28 / G30 homes, #5061.. the last probe contact. A program that reads
 * or sets those parameters therefore sees and moves the same offsets. Stored in millimetres. */
#include "cs_gcode_int.h"

#include <math.h>
#include <string.h>

static double *param(gc_t *g, int index)
{
    return &g->st.num[index];
}

/* Index of axis 0 of coordinate system n (1 .. 9). */
static int wcs_base(int n)
{
    return GC_P_WCS1 + GC_P_WCS_STRIDE * (n - 1);
}

static int wcs_in_use(const gc_t *g)
{
    int n = (int)g->st.num[GC_P_WCS];
    return n >= 1 && n <= 9 ? n : 1;
}

static double g92_part(const gc_t *g, int a)
{
    return g->st.num[GC_P_G92_ON] != 0.0 ? g->st.num[GC_P_G92 + a] : 0.0;
}

double cs_gcode_offset(const gc_t *g, int a)
{
    return g->st.num[wcs_base(wcs_in_use(g)) + a] + g92_part(g, a);
}

void cs_gcode_wcs_init(gc_t *g)
{
    *param(g, GC_P_WCS) = 1;
}

void cs_gcode_wcs_set(gc_t *g, int code)
{
    int n = cs_gcode_coord_system(code);
    if (n != 0) {
        *param(g, GC_P_WCS) = n;
        return;
    }
    for (int a = 0; a < 3; a++) {
        if (code == GC_G28_1 || code == GC_G30_1) /* "G28.1: store the current position" */
            *param(g, (code == GC_G28_1 ? GC_P_G28 : GC_P_G30) + a) = g->pos[a];
        else if (code == GC_G92_1) /* reset the offsets and set the parameters to zero */
            *param(g, GC_P_G92 + a) = 0;
    }
    if (code == GC_G92_1 || code == GC_G92_2) /* G92.2: reset, parameters kept */
        *param(g, GC_P_G92_ON) = 0;
    else if (code == GC_G92_3) /* restore the offsets saved in #5211.. */
        *param(g, GC_P_G92_ON) = 1;
}

/* G92 X.. : the current position gets the coordinates of the axis words (LinuxCNC "G92"). */
static cs_err_t run_g92(gc_t *g, block_t *b, unsigned col)
{
    if (!cs_gcode_any_axis(b)) {
        /* LinuxCNC refuses a bare G92; so do we unless lenient (RepRap's "G92 E0" is bare
         * once its E word was dropped as unsupported). */
        if (!g->o->lenient)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                    "G92 needs axis words (the coordinates to give the "
                                    "current position)");
        cs_gcode_warn(g, col, "G92 without X, Y or Z: ignored, offsets unchanged (--lenient)");
        return CS_OK;
    }
    bool was_on = g->st.num[GC_P_G92_ON] != 0.0;
    int base = wcs_base(wcs_in_use(g));
    for (int a = 0; a < 3; a++) {
        const word_t *w = &b->w['X' - 'A' + a];
        if (w->has) {
            *param(g, GC_P_G92 + a) = g->pos[a] - g->st.num[base + a] - w->v * g->unit;
            b->used |= BIT('X' + a);
        } else if (!was_on) {
            *param(g, GC_P_G92 + a) = 0; /* offsets that did not apply stay without effect */
        }
    }
    *param(g, GC_P_G92_ON) = 1;
    return CS_OK;
}

/* G10 L2 Pn (offsets of system n set to the axis words) and G10 L20 Pn (set so that the current
 * position gets the axis words' coordinates in system n); P0 is the system in use (LinuxCNC
 * "G10 L2", "G10 L20"). G91 has no effect on either. */
static cs_err_t run_g10(gc_t *g, block_t *b, unsigned col)
{
    const word_t *L = &b->w['L' - 'A'], *P = &b->w['P' - 'A'], *R = &b->w['R' - 'A'];
    if (!L->has || (L->v != 2 && L->v != 20))
        return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, cs_gcode_loc(g, L->has ? L->col : col),
                                "G10 sets work offsets with L2 or L20 only (no tool table)");
    int pmax = g->o->dialect == CS_GCODE_GRBL ? 6 : 9;
    if (!P->has || P->v != floor(P->v) || P->v < 0 || P->v > pmax)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, P->has ? P->col : col),
                                "G10 L%g needs P0 (the system in use) .. P%d", L->v, pmax);
    if (R->has)
        return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, cs_gcode_loc(g, R->col),
                                "G10 R (a rotated coordinate system) is not supported");
    b->used |= BIT('L') | BIT('P');
    int n = P->v == 0 ? wcs_in_use(g) : (int)P->v, base = wcs_base(n);
    for (int a = 0; a < 3; a++) {
        const word_t *w = &b->w['X' - 'A' + a];
        if (!w->has)
            continue;
        b->used |= BIT('X' + a);
        double v = w->v * g->unit;
        *param(g, base + a) = L->v == 2 ? v : g->pos[a] - g92_part(g, a) - v;
    }
    return CS_OK;
}

/* G28 / G30: a rapid move to the axis words' point (if any), then the axes named (all without
 * axis words) to the home stored in #5161.. / #5181.. (LinuxCNC and Grbl "G28, G30"). */
static cs_err_t run_home(gc_t *g, block_t *b, int code, unsigned col)
{
    bool any = cs_gcode_any_axis(b);
    double mid[3], home[3];
    cs_gcode_target(g, b, mid);
    cs_err_t e = cs_gcode_add_line(g, g->pos, mid, col, true);
    if (e != CS_OK)
        return e;
    memcpy(g->pos, mid, sizeof g->pos);
    int p = code == GC_G28 ? GC_P_G28 : GC_P_G30;
    for (int a = 0; a < 3; a++)
        home[a] = !any || b->w['X' - 'A' + a].has ? g->st.num[p + a] : mid[a];
    if ((e = cs_gcode_add_line(g, mid, home, col, true)) == CS_OK)
        memcpy(g->pos, home, sizeof g->pos);
    return e;
}

cs_err_t cs_gcode_wcs_axes(gc_t *g, block_t *b, int code, unsigned col)
{
    if (code == GC_G92)
        return run_g92(g, b, col);
    if (code == GC_G10)
        return run_g10(g, b, col);
    return run_home(g, b, code, col);
}

cs_err_t cs_gcode_probe(gc_t *g, block_t *b, int code, unsigned col)
{
    char what[16];
    cs_gcode_code_name(what, sizeof what, 'G', code);
    if (!(g->feed > 0))
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                "%s needs a feed rate (F)", what);
    double t[3], hit[3];
    cs_gcode_target(g, b, t);
    if (t[0] == g->pos[0] && t[1] == g->pos[1] && t[2] == g->pos[2])
        return cs_path_diag_set(g->diag, CS_ERR_DEGENERATE, cs_gcode_loc(g, col),
                                "%s to where the machine already is", what);
    bool contact = false;
    memcpy(hit, t, sizeof hit);
    cs_err_t e = g->o->probe(g->o->probe_ctx, code, g->pos, t, g->feed * g->unit / 60.0,
                             &contact, hit);
    if (e != CS_OK)
        return cs_path_diag_set(g->diag, e, cs_gcode_loc(g, col), "%s: the probing move failed",
                                what);
    cs_path_new_subpath(g->path);
    memcpy(g->pos, hit, sizeof g->pos);
    /* LinuxCNC "G38.x": #5061.. the contact in the coordinate system in effect, #5070 1 on
     * success; G38.2 and G38.4 are errors without contact, G38.3 and G38.5 are not. */
    *param(g, GC_P_PROBE_OK) = contact;
    if (!contact && (code == GC_G38_2 || code == GC_G38_4))
        return cs_path_diag_set(g->diag, CS_ERR_STATE, cs_gcode_loc(g, col),
                                "%s: the probe %s before the end of the move", what,
                                code == GC_G38_2 ? "touched nothing" : "never lost contact");
    for (int a = 0; contact && a < 3; a++)
        *param(g, GC_P_PROBE + a) = (hit[a] - cs_gcode_offset(g, a)) / g->unit;
    return CS_OK;
}
