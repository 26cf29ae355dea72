/* cs_grbl_gc: G-code one line at a time for the Grbl front end (see cs_grbl_gc.h): a cs_gcode
 * session named "grbl", and its state copied out after each call. */
#include "cs_grbl_gc.h"

#include <string.h>

#define MM_PER_INCH 25.4

/* The copy the reports read. */
static void mirror(cs_grbl_gc_t *g)
{
    if (g->s == NULL)
        return;
    cs_gcode_state_t st;
    cs_gcode_state(g->s, &st);
    memcpy(g->pos, st.pos, sizeof g->pos);
    memcpy(g->off, st.off, sizeof g->off);
    g->wcs = st.wcs;
    g->inch = st.inch;
    g->incr = st.incr;
    g->ijk_abs = st.ijk_abs;
    g->plane = st.plane;
    g->motion = st.motion;
    g->feed = st.feed;
}

cs_err_t cs_grbl_gc_init(cs_grbl_gc_t *g, const cs_gcode_opts_t *o)
{
    memset(g, 0, sizeof *g);
    g->s = cs_gcode_session_new("grbl", o);
    mirror(g);
    return g->s ? CS_OK : CS_ERR_FULL;
}

void cs_grbl_gc_free(cs_grbl_gc_t *g)
{
    cs_gcode_session_free(g->s);
    g->s = NULL;
}

void cs_grbl_gc_reset_modal(cs_grbl_gc_t *g, bool clear_g92)
{
    if (g->s)
        cs_gcode_reset(g->s, clear_g92);
    mirror(g);
}

cs_err_t cs_grbl_gc_line(cs_grbl_gc_t *g, const char *line, unsigned lineno, cs_path_t *out,
                         cs_path_diag_t *diag, bool *end)
{
    *end = false;
    if (g->s == NULL) {
        cs_path_loc_t loc = {"grbl", lineno, 1};
        return cs_path_diag_set(diag, CS_ERR_FULL, loc, "out of memory");
    }
    cs_err_t e = cs_gcode_feed(g->s, line, strlen(line), lineno, out, diag, end);
    mirror(g);
    return e;
}

bool cs_grbl_gc_undo(cs_grbl_gc_t *g)
{
    bool ok = g->s && cs_gcode_undo(g->s);
    mirror(g);
    return ok;
}

void cs_grbl_gc_set_pos(cs_grbl_gc_t *g, const double mm[3])
{
    if (g->s)
        cs_gcode_set_pos(g->s, mm);
    mirror(g);
}

double cs_grbl_gc_work(const cs_grbl_gc_t *g, int a)
{
    return (g->pos[a] - g->off[a]) / (g->inch ? MM_PER_INCH : 1.0);
}

double cs_grbl_gc_param(const cs_grbl_gc_t *g, int index)
{
    return g->s ? cs_gcode_param(g->s, index) : 0.0;
}
