/* cs_gcode_cycle: the canned drilling cycles of the G-code reader (see cs_gcode_int.h): G81
 * drilling, G83 peck drilling, G73 chip-break drilling, after LinuxCNC's G-code reference
 * ("Canned Cycles": common words, "Preliminary and In-Between Motion", "G73", "G81", "G83",
 * "G98 G99 Canned Cycle Return Level") and its interpreter (LinuxCNC 2.9 interp_cycles.cc:
 * convert_cycle_xy, convert_cycle_g81 / g83 / g73). The XY plane (G17) only. Host only. */
#include "cs_gcode_int.h"

#include <math.h>
#include <string.h>

/* L: the number of repeats, a whole number 1.. (LinuxCNC: "L-" repeats; 1 without it). */
#define CYC_MAX_REPEATS 10000
/* Pecks per hole: beyond, Q is refused as too small for the depth (a Q so small that d - Q
 * rounds back to d would otherwise never reach the bottom). */
#define CYC_MAX_PECKS 100000

/* How far above the last peck's bottom G83 comes back down at rapid, and G73 backs off:
 * LinuxCNC 2.9's G83_RAPID_DELTA, 0.010 in (0.254 mm in either unit). */
#define CYC_PECK_DELTA_MM (0.010 * MM_PER_INCH)

/* A straight move from g->pos to (x, y, z) machine mm, rapid or at F; g->pos follows. */
static cs_err_t move_to(gc_t *g, double x, double y, double z, unsigned col, bool rapid)
{
    double t[3] = {x, y, z};
    cs_err_t e = cs_gcode_add_line(g, g->pos, t, col, rapid);
    if (e == CS_OK)
        memcpy(g->pos, t, sizeof g->pos);
    return e;
}

/* The R, Z or Q number (program units) of the line, or the last cycle's when it left it out
 * and the same cycle was in effect ("the Z number is sticky"); else an error at col. */
static cs_err_t sticky(gc_t *g, block_t *b, int code, bool same, char letter, double *v,
                       unsigned col)
{
    const word_t *w = &b->w[letter - 'A'];
    if (w->has) {
        b->used |= BIT(letter);
        *v = w->v;
        return CS_OK;
    }
    if (same && g->cyc_set) {
        *v = letter == 'R' ? g->cyc_r : letter == 'Z' ? g->cyc_z : g->cyc_q;
        return CS_OK;
    }
    return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                            "G%d needs %c (%s) on its first line", code / 10, letter,
                            letter == 'R'   ? "the retract plane"
                            : letter == 'Z' ? "the bottom of the hole"
                                            : "the peck depth");
}

/* One hole at (x, y) from R: G81 feeds to the bottom; G83 and G73 in pecks of q, G83 rapid
 * out to R after each and back down to CYC_PECK_DELTA_MM above the last peck's bottom, G73
 * backing off CYC_PECK_DELTA_MM (convert_cycle_g83 / g73). Then rapid out to clear. */
static cs_err_t one_hole(gc_t *g, int code, double x, double y, double r, double bottom,
                         double clear, double q, unsigned col)
{
    cs_err_t e = CS_OK;
    if (code != MOT_G81)
        for (double d = r - q; d > bottom && e == CS_OK; d -= q) {
            e = move_to(g, x, y, d, col, false);
            if (e == CS_OK && code == MOT_G83)
                e = move_to(g, x, y, r, col, true);
            if (e == CS_OK)
                e = move_to(g, x, y, d + CYC_PECK_DELTA_MM, col, true);
        }
    if (e == CS_OK)
        e = move_to(g, x, y, bottom, col, false);
    if (e == CS_OK)
        e = move_to(g, x, y, clear, col, true);
    return e;
}

/* In program coordinates (machine - offset), with c the offsets: in G90 X Y R Z are positions;
 * in G91 X Y are increments of the current point at each repeat, R an increment of the Z the
 * cycle starts at, Z an increment of R ([NCMS, page 98], as LinuxCNC). Each repeat: rapid to
 * X Y at the current height, rapid down to R, feed to Z, rapid out to the clearance height: R
 * under G99, the higher of R and the starting Z under G98. Before the first, a tool below R
 * rises to R. */
cs_err_t cs_gcode_cycle(gc_t *g, block_t *b, int code, bool same, unsigned col)
{
    if (g->plane != 17)
        return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, cs_gcode_loc(g, col),
                                "G%d is read in the G17 (XY) plane only", code / 10);
    double rn = 0, zn = 0, qn = 0;
    cs_err_t e = sticky(g, b, code, same, 'R', &rn, col);
    if (e == CS_OK)
        e = sticky(g, b, code, same, 'Z', &zn, col);
    if (e == CS_OK && code != MOT_G81)
        e = sticky(g, b, code, same, 'Q', &qn, col);
    if (e != CS_OK)
        return e;
    /* A peck of q > 0 (LinuxCNC: NCE_NEGATIVE_OR_ZERO_Q_VALUE_USED). */
    if (code != MOT_G81 && !(qn > 0))
        return cs_path_diag_set(g->diag, CS_ERR_PARSE,
                                cs_gcode_loc(g, b->w['Q' - 'A'].has ? b->w['Q' - 'A'].col : col),
                                "G%d: Q (the peck depth) must be positive", code / 10);
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
                                "G%d: R (%g) is below Z (%g): the retract plane must be above "
                                "the bottom of the hole",
                                code / 10, r / g->unit, bottom / g->unit);
    if (code != MOT_G81 && (r - bottom) / (qn * g->unit) > CYC_MAX_PECKS)
        return cs_path_diag_set(g->diag, CS_ERR_RANGE,
                                cs_gcode_loc(g, b->w['Q' - 'A'].has ? b->w['Q' - 'A'].col : col),
                                "G%d: Q %g is too small for a hole %g deep (more than %d pecks)",
                                code / 10, qn, (r - bottom) / g->unit, CYC_MAX_PECKS);
    g->cyc_r = rn;
    g->cyc_z = zn;
    g->cyc_q = qn;
    g->cyc_set = true;
    if (z0 < r && (e = move_to(g, g->pos[0], g->pos[1], r + c[2], col, true)) != CS_OK)
        return e;
    double clear = g->retract_r ? r : fmax(z0, r);
    for (int k = 0; k < reps && e == CS_OK; k++) {
        double x = g->pos[0], y = g->pos[1];
        if (b->polar[0].has || b->polar[1].has) {
            /* each repeat turns / moves on from the last hole (G91; hole-circle.ngc) */
            double cur[2] = {(x - c[0]) / g->unit, (y - c[1]) / g->unit}, p[2];
            if ((e = cs_gcode_polar(g, b, cur, p)) != CS_OK)
                return e;
            x = p[0] * g->unit + c[0];
            y = p[1] * g->unit + c[1];
        }
        if (X->has)
            x = g->incr ? x + X->v * g->unit : X->v * g->unit + c[0];
        if (Y->has)
            y = g->incr ? y + Y->v * g->unit : Y->v * g->unit + c[1];
        e = move_to(g, x, y, g->pos[2], col, true);
        if (e == CS_OK)
            e = move_to(g, x, y, r + c[2], col, true);
        if (e == CS_OK)
            e = one_hole(g, code, x, y, r + c[2], bottom + c[2], clear + c[2], qn * g->unit,
                         col);
    }
    return e;
}
