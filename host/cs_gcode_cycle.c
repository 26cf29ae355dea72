/* cs_gcode_cycle: the G81 drilling cycle of the G-code reader (see cs_gcode_int.h), after
 * LinuxCNC's G-code reference ("Canned Cycles": common words, "Preliminary and In-Between
 * Motion", "G81 Drilling Cycle", "G98 G99 Canned Cycle Return Level") and its interpreter
 * (interp_cycles.cc convert_cycle_xy / convert_cycle_g81). The XY plane (G17) only. Host only. */
#include "cs_gcode_int.h"

#include <math.h>
#include <string.h>

/* L: the number of repeats, a whole number 1.. (LinuxCNC: "L-" repeats; 1 without it). */
#define CYC_MAX_REPEATS 10000

/* A straight move from g->pos to (x, y, z) machine mm, rapid or at F; g->pos follows. */
static cs_err_t move_to(gc_t *g, double x, double y, double z, unsigned col, bool rapid)
{
    double t[3] = {x, y, z};
    cs_err_t e = cs_gcode_add_line(g, g->pos, t, col, rapid);
    if (e == CS_OK)
        memcpy(g->pos, t, sizeof g->pos);
    return e;
}

/* The R and Z numbers (program units) of the line, or the last cycle's when it left them out
 * and the same cycle was in effect ("the Z number is sticky"); else an error at col. */
static cs_err_t sticky(gc_t *g, block_t *b, bool same, char letter, double *v, unsigned col)
{
    const word_t *w = &b->w[letter - 'A'];
    if (w->has) {
        b->used |= BIT(letter);
        *v = w->v;
        return CS_OK;
    }
    if (same && g->cyc_set) {
        *v = letter == 'R' ? g->cyc_r : g->cyc_z;
        return CS_OK;
    }
    return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                            "G81 needs %c (%s) on its first line", letter,
                            letter == 'R' ? "the retract plane" : "the bottom of the hole");
}

/* In program coordinates (machine - offset), with c the offsets: in G90 X Y R Z are positions;
 * in G91 X Y are increments of the current point at each repeat, R an increment of the Z the
 * cycle starts at, Z an increment of R ([NCMS, page 98], as LinuxCNC). Each repeat: rapid to
 * X Y at the current height, rapid down to R, feed to Z, rapid out to the clearance height: R
 * under G99, the higher of R and the starting Z under G98. Before the first, a tool below R
 * rises to R. */
cs_err_t cs_gcode_cycle(gc_t *g, block_t *b, bool same, unsigned col)
{
    if (g->plane != 17)
        return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, cs_gcode_loc(g, col),
                                "G81 is read in the G17 (XY) plane only");
    double rn = 0, zn = 0;
    cs_err_t e = sticky(g, b, same, 'R', &rn, col);
    if (e == CS_OK)
        e = sticky(g, b, same, 'Z', &zn, col);
    if (e != CS_OK)
        return e;
    int reps = 1;
    const word_t *L = &b->w['L' - 'A'];
    if (L->has) {
        b->used |= BIT('L');
        if (L->v < 1 || L->v > CYC_MAX_REPEATS || L->v != floor(L->v))
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, L->col),
                                    "L (repeats) must be a whole number from 1 to %d",
                                    CYC_MAX_REPEATS);
        reps = (int)L->v;
    }
    double c[3] = {cs_gcode_offset(g, 0), cs_gcode_offset(g, 1), cs_gcode_offset(g, 2)};
    const word_t *X = &b->w['X' - 'A'], *Y = &b->w['Y' - 'A'];
    b->used |= BIT('X') | BIT('Y');
    double z0 = g->pos[2] - c[2]; /* program Z before the cycle */
    double r = g->incr ? z0 + rn * g->unit : rn * g->unit;
    double bottom = g->incr ? r + zn * g->unit : zn * g->unit;
    if (r < bottom)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                "G81: R (%g) is below Z (%g): the retract plane must be above "
                                "the bottom of the hole",
                                r / g->unit, bottom / g->unit);
    g->cyc_r = rn;
    g->cyc_z = zn;
    g->cyc_set = true;
    if (z0 < r && (e = move_to(g, g->pos[0], g->pos[1], r + c[2], col, true)) != CS_OK)
        return e;
    double clear = g->retract_r ? r : fmax(z0, r);
    for (int k = 0; k < reps && e == CS_OK; k++) {
        double x = g->pos[0], y = g->pos[1];
        if (X->has)
            x = g->incr ? x + X->v * g->unit : X->v * g->unit + c[0];
        if (Y->has)
            y = g->incr ? y + Y->v * g->unit : Y->v * g->unit + c[1];
        e = move_to(g, x, y, g->pos[2], col, true);
        if (e == CS_OK)
            e = move_to(g, x, y, r + c[2], col, true);
        if (e == CS_OK)
            e = move_to(g, x, y, bottom + c[2], col, false);
        if (e == CS_OK)
            e = move_to(g, x, y, clear + c[2], col, true);
    }
    return e;
}
