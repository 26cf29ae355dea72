/* cs_gcode: G-code text -> path elements (see cs_gcode.h; the words and the LinuxCNC semantics
 * chosen are listed in docs/inputs.md, section "G-code"). */
#include "cs_gcode_int.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_conv.h"
#include "cs_gflow.h"

cs_path_loc_t cs_gcode_loc(const gc_t *g, unsigned col)
{
    cs_path_loc_t l = {g->name, g->line, col};
    return l;
}

static void warn_text(gc_t *g, unsigned col, const char *msg)
{
    cs_path_diag_t w;
    cs_path_diag_set(&w, CS_OK, cs_gcode_loc(g, col), "%s", msg);
    if (g->stats)
        g->stats->warnings++;
    if (g->o->warn)
        g->o->warn(g->o->warn_ctx, &w);
    else
        cs_path_warn_print(stderr, &w);
}

/* A warning from fmt and ap; once: only the first time its text occurs in the program (the
 * others counted), marked so. */
static void warn_v(gc_t *g, unsigned col, bool once, const char *fmt, va_list ap)
{
    char msg[sizeof((cs_path_diag_t *)0)->reason];
    vsnprintf(msg, sizeof msg, fmt, ap);
    if (once) {
        /* FNV-1a of the text: the kind of warning, whatever its place. */
        uint32_t h = 2166136261u;
        for (const char *c = msg; *c; c++)
            h = (h ^ (unsigned char)*c) * 16777619u;
        for (unsigned i = 0; i < g->nwarned; i++)
            if (g->warned[i] == h) {
                if (g->stats)
                    g->stats->warnings++;
                return;
            }
        if (g->nwarned < GC_MAX_WARN_ONCE)
            g->warned[g->nwarned++] = h;
        size_t n = strlen(msg);
        snprintf(msg + n, sizeof msg - n, " (reported once)");
    }
    warn_text(g, col, msg);
}

void cs_gcode_warn(gc_t *g, unsigned col, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    warn_v(g, col, false, fmt, ap);
    va_end(ap);
}

void cs_gcode_warn_once(gc_t *g, unsigned col, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    warn_v(g, col, true, fmt, ap);
    va_end(ap);
}

/* An unsupported word: an error, or a warning (and CS_OK: the caller ignores it) when lenient. */
static cs_err_t unsupported(gc_t *g, unsigned col, const char *what)
{
    if (g->o->lenient) {
        cs_gcode_warn_once(g, col, "%s is not supported: ignored (--lenient)", what);
        return CS_OK;
    }
    return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, cs_gcode_loc(g, col),
                            "%s is not supported (--lenient makes this a warning)", what);
}

static int letter_index(char c)
{
    if (c >= 'a' && c <= 'z')
        return c - 'a';
    if (c >= 'A' && c <= 'Z')
        return c - 'A';
    return -1;
}

/* ---- geometry helpers -------------------------------------------------------------------- */

cs_err_t cs_gcode_to_vec(gc_t *g, const double p[3], unsigned col, cs_vec3_t *out)
{
    if (cs_conv_mm_to_vec(p[0], p[1], p[2], out) != CS_OK)
        return cs_path_diag_set(g->diag, CS_ERR_RANGE, cs_gcode_loc(g, col),
                                "point (%.4f, %.4f, %.4f) mm is outside +/-%d mm", p[0], p[1], p[2],
                                CS_POS_LIMIT_MM);
    return CS_OK;
}

cs_pos_t *cs_gcode_coord(cs_vec3_t *v, int axis)
{
    return axis == 0 ? &v->x : axis == 1 ? &v->y : &v->z;
}

bool cs_gcode_vec_eq(const cs_vec3_t *a, const cs_vec3_t *b)
{
    return a->x == b->x && a->y == b->y && a->z == b->z;
}

cs_err_t cs_gcode_add(gc_t *g, const cs_bezier_t *c, cs_path_kind_t kind, unsigned col, bool rapid)
{
    if (rapid != g->last_rapid) {
        cs_path_new_subpath(g->path);
        g->last_rapid = rapid;
    }
    if (g->o->max_elements > 0 && g->path->n >= g->o->max_elements)
        return cs_path_diag_set(g->diag, CS_ERR_FULL, cs_gcode_loc(g, col),
                                "the job needs more than %zu path elements", g->o->max_elements);
    double feed = rapid ? 0.0 : g->feed * g->unit / 60.0;
    if (cs_path_add_move(g->path, c, kind, cs_gcode_loc(g, col), feed, rapid) != CS_OK)
        return cs_path_diag_set(g->diag, CS_ERR_FULL, cs_gcode_loc(g, col), "out of memory");
    /* the spindle / laser with each move, so a plan carries its power (cs_motion power marks) */
    cs_path_elem_t *el = &g->path->elems[g->path->n - 1];
    el->spindle = (uint8_t)(g->spindle / 10);
    el->spindle_s = g->speed;
    return CS_OK;
}

cs_err_t cs_gcode_add_line(gc_t *g, const double a[3], const double b[3], unsigned col, bool rapid)
{
    cs_vec3_t p[2];
    cs_err_t e = cs_gcode_to_vec(g, a, col, &p[0]);
    if (e == CS_OK)
        e = cs_gcode_to_vec(g, b, col, &p[1]);
    if (e != CS_OK || cs_gcode_vec_eq(&p[0], &p[1]))
        return e; /* a move that goes nowhere adds nothing */
    cs_bezier_t c;
    cs_bezier_init(&c, 1, p);
    return cs_gcode_add(g, &c, CS_PATH_LINE, col, rapid);
}

/* Axis words -> target (machine mm). */
void cs_gcode_target(gc_t *g, block_t *b, double t[3])
{
    for (int a = 0; a < 3; a++) {
        const word_t *w = &b->w['X' - 'A' + a];
        if (!w->has) {
            t[a] = g->pos[a];
            continue;
        }
        b->used |= BIT('X' + a);
        /* G53: machine coordinates for this line (LinuxCNC "G53 Move in Machine Coordinates") */
        double off = b->machine ? 0.0 : cs_gcode_offset(g, a);
        t[a] = g->incr ? g->pos[a] + w->v * g->unit : w->v * g->unit + off;
    }
}

bool cs_gcode_any_axis(const block_t *b)
{
    return b->w['X' - 'A'].has || b->w['Y' - 'A'].has || b->w['Z' - 'A'].has;
}

/* Plane axes: first, second (counter-clockwise from first to second), normal. */
void cs_gcode_plane_axes(int plane, int ax[3])
{
    if (plane == 18) {
        ax[0] = 2, ax[1] = 0, ax[2] = 1;
    } else if (plane == 19) {
        ax[0] = 1, ax[1] = 2, ax[2] = 0;
    } else {
        ax[0] = 0, ax[1] = 1, ax[2] = 2;
    }
}

/* G5 (cubic, continuation form when I and J are left out) and G5.1 (quadratic). */
static cs_err_t do_spline(gc_t *g, block_t *b, bool quad, unsigned col)
{
    const char *gname = quad ? "G5.1" : "G5";
    if (g->plane != 17)
        return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, cs_gcode_loc(g, col),
                                "%s works in the G17 (XY) plane only", gname);
    if (b->w['Z' - 'A'].has)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, b->w['Z' - 'A'].col),
                                "%s moves in X and Y only (no Z word)", gname);
    const word_t *I = &b->w['I' - 'A'], *J = &b->w['J' - 'A'];
    const word_t *P = &b->w['P' - 'A'], *Q = &b->w['Q' - 'A'];
    double t[3];
    cs_gcode_target(g, b, t);
    double ij[2];
    if (I->has || J->has) {
        if (!quad && I->has != J->has)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, (I->has ? I : J)->col),
                                    "G5 needs both I and J (or neither, to continue the "
                                    "previous G5)");
        ij[0] = I->has ? I->v * g->unit : 0.0;
        ij[1] = J->has ? J->v * g->unit : 0.0;
        b->used |= BIT('I') | BIT('J');
    } else if (!quad && g->g5_prev) {
        ij[0] = -g->g5_pq[0];
        ij[1] = -g->g5_pq[1];
    } else {
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                quad ? "G5.1 needs I and J (the control point offset)"
                                     : "G5 without I and J must follow another G5");
    }
    if (quad && ij[0] == 0.0 && ij[1] == 0.0)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                "G5.1 with I and J both zero");
    double pts[4][3];
    memcpy(pts[0], g->pos, sizeof pts[0]);
    pts[1][0] = g->pos[0] + ij[0];
    pts[1][1] = g->pos[1] + ij[1];
    pts[1][2] = g->pos[2];
    unsigned deg = quad ? 2 : 3;
    if (!quad) {
        if (!P->has || !Q->has)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                    "G5 needs P and Q (the end control point offset)");
        b->used |= BIT('P') | BIT('Q');
        double pq[2] = {P->v * g->unit, Q->v * g->unit};
        pts[2][0] = t[0] + pq[0];
        pts[2][1] = t[1] + pq[1];
        pts[2][2] = g->pos[2];
        g->g5_pq[0] = pq[0];
        g->g5_pq[1] = pq[1];
    }
    memcpy(pts[deg], t, sizeof pts[deg]);
    cs_vec3_t v[4];
    for (unsigned i = 0; i <= deg; i++) {
        cs_err_t e = cs_gcode_to_vec(g, pts[i], col, &v[i]);
        if (e != CS_OK)
            return e;
    }
    cs_bezier_t c;
    cs_bezier_init(&c, deg, v);
    cs_err_t e = cs_gcode_add(g, &c, quad ? CS_PATH_QUAD : CS_PATH_CUBIC, col, false);
    if (e == CS_OK)
        memcpy(g->pos, t, sizeof g->pos);
    return e;
}

/* Letters this reader does not carry out (each once), then F and S. */
static cs_err_t run_letters(gc_t *g, block_t *b)
{
    static const char supported[] = "FGIJKLMNPQRSXYZ";
    for (int i = 0; i < 26; i++) {
        if (!b->w[i].has || strchr(supported, 'A' + i))
            continue;
        char what[96];
        snprintf(what, sizeof what, "the %c word%s", 'A' + i,
                 i == 'H' - 'A'   ? " (G43's tool length offset number: there is no tool table)"
                 : i == 'D' - 'A' ? " (G41/G42's cutter compensation number)"
                                  : "");
        cs_err_t e;
        if (i == 'T' - 'A' && g->o->dialect == CS_GCODE_GRBL) {
            /* Grbl 1.1 reads T and changes nothing (it has no tool changer). */
        } else if (i == 'T' - 'A' && g->o->lenient) {
            /* No tool changer: the tool in the machine stays, nothing moves. */
            cs_gcode_warn_once(g, b->w[i].col,
                               "T (tool select): ignored, there is no tool changer (--lenient)");
        } else if ((e = unsupported(g, b->w[i].col, what)) != CS_OK) {
            return e;
        }
        b->w[i].has = false;
    }
    b->used |= BIT('N');
    /* F (in program units per minute, read at each move in the units then active) and S. */
    const word_t *F = &b->w['F' - 'A'];
    if (F->has) {
        b->used |= BIT('F');
        if (!(F->v > 0))
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, F->col),
                                    "F (feed) must be positive");
        g->feed = F->v;
    }
    if (b->w['S' - 'A'].has) {
        b->used |= BIT('S');
        if (b->w['S' - 'A'].v < 0)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, b->w['S' - 'A'].col),
                                    "S (spindle speed) must not be negative");
        double was = g->speed;
        g->speed = b->w['S' - 'A'].v;
        if (g->o->spindle && g->spindle != GC_M5 && g->speed != was) {
            cs_err_t e = g->o->spindle(g->o->spindle_ctx, g->spindle, g->speed);
            if (e != CS_OK)
                return cs_path_diag_set(g->diag, e, cs_gcode_loc(g, b->w['S' - 'A'].col),
                                        "S: the spindle could not be set");
        }
    }
    return CS_OK;
}


/* The pen's Z move of M3/M4/M5 (opts->pen_z) to t: at opts->pen_z_feed_mm_s when it is given
 * (the [pen] z_feed, as cs_pen moves the pen for SVG and HP-GL), else rapid. The program's own F
 * is kept for the moves after it. */
static cs_err_t pen_z_move(gc_t *g, const double t[3], unsigned col)
{
    if (!(g->o->pen_z_feed_mm_s > 0))
        return cs_gcode_add_line(g, g->pos, t, col, true);
    double f = g->feed;
    g->feed = g->o->pen_z_feed_mm_s * 60.0 / g->unit; /* cs_gcode_add: feed * unit / 60 mm/s */
    cs_err_t e = cs_gcode_add_line(g, g->pos, t, col, false);
    g->feed = f;
    return e;
}

/* M words: pen / spindle before the motion; *end for M2 / M30. */
static cs_err_t run_m(gc_t *g, block_t *b, bool *end)
{
    cs_err_t e;
    for (unsigned i = 0; i < b->nm; i++) {
        int m = b->m[i];
        cs_gcode_group_t grp = cs_gcode_group_m(m);
        if (grp == GC_GROUP_M_STOP) {
            *end = true;
        } else if (grp == GC_GROUP_M_SPINDLE && g->nurbs) {
            /* The block's curve starts where it opened: a pen or spindle change (and its Z
             * move) cannot come between its control points. */
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, b->mcol[i]),
                                    "M%d inside a NURBS block: start or stop the spindle (pen) "
                                    "before the G5.2 or after its G5.3",
                                    m / 10);
        } else if (grp == GC_GROUP_M_SPINDLE) {
            g->spindle = m;
            if (g->o->spindle && (e = g->o->spindle(g->o->spindle_ctx, m, g->speed)) != CS_OK)
                return cs_path_diag_set(g->diag, e, cs_gcode_loc(g, b->mcol[i]),
                                        "M%d: the spindle could not be set", m / 10);
            /* Pen down / spindle on, or pen up / spindle off: a new subpath either way, and
             * with opts->pen_z a Z move to the pen height. */
            cs_path_new_subpath(g->path);
            if (g->o->pen_z) {
                double t[3] = {g->pos[0], g->pos[1],
                               m == GC_M5 ? g->o->pen_up_z_mm : g->o->pen_down_z_mm};
                if ((e = pen_z_move(g, t, b->mcol[i])) != CS_OK)
                    return e;
                memcpy(g->pos, t, sizeof g->pos);
                cs_path_new_subpath(g->path);
            }
        } else if (grp == GC_GROUP_M_COOLANT) {
            /* Coolant mist / flood / off (LinuxCNC and Grbl): nothing to draw or move. */
        } else {
            char what[32];
            cs_gcode_code_name(what, sizeof what, 'M', m);
            if ((e = unsupported(g, b->mcol[i], what)) != CS_OK)
                return e;
        }
    }
    return CS_OK;
}

/* What the G words of one line ask for. */
typedef struct {
    int motion; /* MOT_*, GC_G5_3, or MOT_LINE_NONE: no motion word on the line */
    unsigned mcol;
    bool g64, drop;
    int drop_code;
    int axes_code; /* G10, G28, G30, G92: a non-modal code that takes the axis words; -1: none */
    unsigned axes_col, g64col, dropcol;
} gline_t;

/* G codes this reader carries out in LinuxCNC's dialect that Grbl 1.1 does not have. */
static bool grbl_lacks(int v)
{
    return v == GC_G5 || v == GC_G5_1 || v == GC_G5_2 || v == GC_G5_3 || v == GC_G6_2 ||
           v == GC_G64 || v == GC_G61_1 || v == GC_G90_1 || v == GC_G59_1 || v == GC_G59_2 ||
           v == GC_G59_3 || v == GC_G92_2 || v == GC_G92_3 || v == GC_G73 || v == GC_G81 ||
           v == GC_G83 || v == GC_G98 || v == GC_G99;
}

/* Codes that move (threading, probing, canned cycles...) or read the line's axis words for
 * another purpose (G4 dwell, G10, G28/G30 home, G52, G53, G92.2/3): when --lenient drops one, the
 * whole block goes with it; moving to its axis words as an ordinary move could plunge the tool. */
static bool moves_or_takes_axes(int v, bool *motion)
{
    *motion = cs_gcode_group_g(v) == GC_GROUP_MOTION;
    return *motion || cs_gcode_group_g(v) == GC_GROUP_NONMODAL;
}

static cs_err_t set_motion(gc_t *g, gline_t *l, int v, unsigned c)
{
    if (l->motion != MOT_LINE_NONE)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, c),
                                "two motion words on one line");
    l->motion = v;
    l->mcol = c;
    return CS_OK;
}

/* An unsupported G code: an error, or (lenient) dropped, with its block when it moves. */
static cs_err_t drop_g(gc_t *g, gline_t *l, int v, unsigned c)
{
    char what[48];
    cs_gcode_code_name(what, sizeof what, 'G', v);
    if (g->o->dialect == CS_GCODE_GRBL && grbl_lacks(v))
        strcat(what, " (not in Grbl 1.1)");
    if (!g->o->lenient)
        return unsupported(g, c, what);
    bool motion;
    if (!moves_or_takes_axes(v, &motion)) {
        cs_gcode_warn_once(g, c, "%s is not supported: ignored (--lenient)", what);
        return CS_OK;
    }
    l->drop = true;
    l->drop_code = v;
    l->dropcol = c;
    return motion ? set_motion(g, l, MOT_DROPPED, c) : CS_OK;
}

/* G64 [P tolerance] [Q]: blending; P (program units) is the path tolerance the program asks for. */
static cs_err_t run_g64(gc_t *g, block_t *b, unsigned col)
{
    const word_t *P = &b->w['P' - 'A'], *Q = &b->w['Q' - 'A'];
    if (Q->has)
        b->used |= BIT('Q'); /* LinuxCNC's naive-CAM merge tolerance: every point is kept */
    if (!P->has)
        return CS_OK;
    b->used |= BIT('P');
    if (P->v < 0)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, P->col),
                                "G64 P (path tolerance) must not be negative");
    double mm = P->v * g->unit;
    (void)col;
    if (mm > 0 && (g->path->blend_tol_mm == 0 || mm < g->path->blend_tol_mm))
        g->path->blend_tol_mm = mm;
    return CS_OK;
}

/* Two G words of one modal group on a line (LinuxCNC G-code reference, "Modal Groups": "It is an
 * error to put a G-code from group 1 and a G-code from group 0 on the same line if both of them
 * use axis words" and two of one group are an error). Two motion words: set_motion says so. */
static cs_err_t check_groups(gc_t *g, const block_t *b)
{
    for (unsigned i = 0; i < b->ng; i++) {
        cs_gcode_group_t gi = cs_gcode_group_g(b->g[i]);
        for (unsigned j = 0; j < i && gi != GC_GROUP_NONE && gi != GC_GROUP_MOTION; j++) {
            if (cs_gcode_group_g(b->g[j]) != gi)
                continue;
            char a[16], c[16];
            cs_gcode_code_name(a, sizeof a, 'G', b->g[j]);
            cs_gcode_code_name(c, sizeof c, 'G', b->g[i]);
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, b->gcol[i]),
                                    "%s and %s on one line: two words of one modal group", a, c);
        }
    }
    return CS_OK;
}

/* Modes that set state and nothing else: plane, units, distance modes, path mode. */
static bool run_g_mode(gc_t *g, int v)
{
    switch (v) {
    case GC_G17:
        g->plane = 17;
        return true;
    case GC_G18:
        g->plane = 18;
        return true;
    case GC_G19:
        g->plane = 19;
        return true;
    case GC_G20:
        g->unit = MM_PER_INCH;
        return true;
    case GC_G21:
        g->unit = 1.0;
        return true;
    case GC_G90:
    case GC_G91:
        g->incr = v == GC_G91;
        return true;
    case GC_G90_1:
    case GC_G91_1:
        g->ijk_abs = v == GC_G90_1;
        return true;
    case GC_G61:   /* exact path, */
    case GC_G61_1: /* exact stop: curvestep never rounds a corner off, so the path is the same */
    case GC_G94:   /* feed in units per minute: the only feed mode */
    case GC_G40:   /* cutter radius compensation off */
    case GC_G49:   /* tool length offset off */
        return true;
    case GC_G98: /* canned cycles retract to the higher of R and the Z they start at */
    case GC_G99: /* ... to R */
        g->retract_r = v == GC_G99;
        return true;
    default:
        return false;
    }
}

/* The modal G words of a line into the state, the motion word and the specials into *l. */
static cs_err_t run_g(gc_t *g, block_t *b, gline_t *l)
{
    cs_err_t e = check_groups(g, b);
    for (unsigned i = 0; i < b->ng && e == CS_OK; i++) {
        int v = b->g[i];
        unsigned c = b->gcol[i];
        if ((g->o->dialect == CS_GCODE_GRBL && grbl_lacks(v)) ||
            (v >= GC_G38_2 && v <= GC_G38_5 && !g->o->probe)) {
            e = drop_g(g, l, v, c);
            continue;
        }
        if (run_g_mode(g, v))
            continue;
        if (v == GC_G4 && b->w['P' - 'A'].has && b->w['P' - 'A'].v == 0 && !cs_gcode_any_axis(b)) {
            /* "G4 P0": a dwell of no time, which laser and plotter posts and senders write to
             * wait for the moves before it; the plan runs every move in order: nothing to do.
             * A real dwell stays unsupported (the plan has no pauses). */
            b->used |= BIT('P');
            continue;
        }
        if (cs_gcode_coord_system(v) != 0 || v == GC_G28_1 || v == GC_G30_1 || v == GC_G92_1 ||
            v == GC_G92_2 || v == GC_G92_3) {
            cs_gcode_wcs_set(g, v);
        } else if (v == GC_G10 || v == GC_G28 || v == GC_G30 || v == GC_G92) {
            l->axes_code = v;
            l->axes_col = c;
        } else if (v == GC_G53) {
            b->machine = true;
        } else if (v == GC_G80) {
            e = set_motion(g, l, MOT_NONE, c);
        } else if (v == GC_G64) {
            l->g64 = true;
            l->g64col = c;
        } else if ((cs_gcode_group_g(v) == GC_GROUP_MOTION && v != GC_G33 && v != GC_G33_1 &&
                    v != GC_G73 && v != GC_G74 && v != GC_G76 && v < GC_G81) ||
                   v == GC_G73 || v == GC_G81 || v == GC_G83) {
            /* G0 .. G6.2, (with a probe) G38.2 .. G38.5, the cycles G73 G81 G83 */
            e = set_motion(g, l, v, c);
        } else {
            e = drop_g(g, l, v, c);
        }
    }
    return e;
}

/* Lenient: the dropped code's block is skipped whole; one warning names it and its words. */
static void drop_block(gc_t *g, block_t *b, int code, unsigned col, bool modal)
{
    char what[32], words[160] = "";
    size_t k = 0;
    cs_gcode_code_name(what, sizeof what, 'G', code);
    for (const char *q = "XYZIJKRPQL"; *q; q++) {
        word_t *w = &b->w[*q - 'A'];
        if (w->has && k < sizeof words - 24)
            k += (size_t)snprintf(words + k, sizeof words - k, " %c%g", *q, w->v);
        w->has = false;
    }
    b->polar[0].has = b->polar[1].has = false;
    if (modal)
        cs_gcode_warn(g, col,
                      "move in the unsupported motion mode %s skipped, with its words%s "
                      "(--lenient)",
                      what, words);
    else
        cs_gcode_warn(g, col,
                      "%s is not supported: its block skipped, with its words%s (--lenient)", what,
                      k ? words : " (none)");
}

cs_err_t cs_gcode_polar(gc_t *g, block_t *b, const double cur[2], double out[2])
{
    const word_t *d = &b->polar[0], *a = &b->polar[1];
    double r = hypot(cur[0], cur[1]), th = atan2(cur[1], cur[0]);
    b->polar_used = true;
    if (g->incr) {
        if (cur[0] == 0 && cur[1] == 0)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE,
                                    cs_gcode_loc(g, d->has ? d->col : a->col),
                                    "incremental polar coordinates at the origin: the angle is "
                                    "undefined (LinuxCNC refuses it too)");
        r += d->has ? d->v : 0;
        th += a->has ? a->v * GC_PI / 180 : 0;
    } else {
        r = d->has ? d->v : r;
        th = a->has ? a->v * GC_PI / 180 : th;
    }
    out[0] = r * cos(th);
    out[1] = r * sin(th);
    return CS_OK;
}

/* A straight move, arc or spline whose end is given by @ / ^: its X and Y words, as the
 * program would have written them (G91: increments). */
static cs_err_t polar_to_xy(gc_t *g, block_t *b)
{
    double cur[2], p[2];
    for (int a = 0; a < 2; a++)
        cur[a] = (g->pos[a] - cs_gcode_offset(g, a)) / g->unit;
    cs_err_t e = cs_gcode_polar(g, b, cur, p);
    for (int a = 0; a < 2 && e == CS_OK; a++) {
        word_t *w = &b->w['X' - 'A' + a];
        w->has = true;
        w->v = g->incr ? p[a] - cur[a] : p[a];
        w->col = b->polar[b->polar[0].has ? 0 : 1].col;
    }
    return e;
}

/* G10, G28, G30, G92: the line's axis words are theirs, so no motion word may share it. */
static cs_err_t run_axes_code(gc_t *g, block_t *b, const gline_t *l)
{
    if (l->motion != MOT_LINE_NONE) {
        char what[16];
        cs_gcode_code_name(what, sizeof what, 'G', l->axes_code);
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, l->axes_col),
                                "%s and a motion word on one line", what);
    }
    return cs_gcode_wcs_axes(g, b, l->axes_code, l->axes_col);
}

/* NURBS lines: G5.3, G5.2, G6.2 and the lines of an open block. *done when the line was one. */
static cs_err_t run_nurbs(gc_t *g, block_t *b, const gline_t *l, unsigned first_col, bool *done)
{
    *done = true;
    if (g->nurbs && l->motion != MOT_LINE_NONE && l->motion != MOT_G52 && l->motion != GC_G5_3)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, l->mcol),
                                g->nurbs == MOT_G62
                                    ? "motion word inside a G6.2 block (it ends with its last "
                                      "K-only line)"
                                    : "motion word inside a G5.2 block (close it with G5.3 first)");
    if (l->motion == GC_G5_3) {
        if (g->nurbs != MOT_G52)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, l->mcol),
                                    "G5.3 without an open G5.2 block");
        g->motion = MOT_NONE;
        g->g5_prev = false;
        return cs_gcode_nurbs_close(g);
    }
    if (l->motion == MOT_G52 || l->motion == MOT_G62) {
        if (g->nurbs)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, l->mcol),
                                    "G%s inside an open NURBS block",
                                    l->motion == MOT_G52 ? "5.2" : "6.2");
        g->motion = l->motion;
        g->g5_prev = false;
        return l->motion == MOT_G52 ? cs_gcode_nurbs_line(g, b, true, l->mcol)
                                    : cs_gcode_g62_line(g, b, true, l->mcol);
    }
    if (g->nurbs)
        return g->nurbs == MOT_G52 ? cs_gcode_nurbs_line(g, b, false, first_col)
                                   : cs_gcode_g62_line(g, b, false, first_col);
    *done = false;
    return CS_OK;
}

/* The motion of a line (modal: the mode in effect when the line has none). */
static cs_err_t run_motion(gc_t *g, block_t *b, const gline_t *l, unsigned first_col)
{
    int before = g->motion;
    if (l->motion != MOT_LINE_NONE)
        g->motion = l->motion;
    if (b->machine && g->motion != MOT_G0 && g->motion != MOT_G1)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, first_col),
                                "G53 needs G0 or G1 in effect (LinuxCNC: a move in machine "
                                "coordinates)");
    /* A move happens when the line has axis words or arc / spline words; a motion word alone
     * ("G2" on its own line) only sets the mode. */
    bool polar = b->polar[0].has || b->polar[1].has;
    bool go = cs_gcode_any_axis(b) || polar;
    for (const char *q = "IJKRPQ"; *q; q++)
        go = go || (b->w[*q - 'A'].has && !(b->used & BIT(*q))); /* G64's P and Q are its own */
    if (!go)
        return CS_OK;
    if (g->motion == MOT_NONE)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, first_col),
                                "axis words with no motion mode (G0, G1, G2...) in effect");
    if (g->motion == MOT_DROPPED) { /* only when lenient: the mode's moves are dropped too */
        drop_block(g, b, g->dropped_code, first_col, true);
        return CS_OK;
    }
    if (polar && (b->w['X' - 'A'].has || b->w['Y' - 'A'].has))
        return cs_path_diag_set(g->diag, CS_ERR_PARSE,
                                cs_gcode_loc(g, b->w[b->w['X' - 'A'].has ? 'X' - 'A' : 'Y' - 'A'].col),
                                "X or Y with polar coordinates (@ ^) on one line");
    double t[3];
    cs_err_t e = CS_OK;
    if (polar && g->motion != MOT_G73 && g->motion != MOT_G81 && g->motion != MOT_G83 &&
        (e = polar_to_xy(g, b)) != CS_OK)
        return e;
    switch (g->motion) {
    case MOT_G0:
    case MOT_G1:
        cs_gcode_target(g, b, t);
        if ((e = cs_gcode_add_line(g, g->pos, t, l->mcol, g->motion == MOT_G0)) == CS_OK)
            memcpy(g->pos, t, sizeof g->pos);
        g->g5_prev = false;
        break;
    case MOT_G2:
    case MOT_G3:
        e = cs_gcode_arc(g, b, g->motion == MOT_G3, l->mcol);
        g->g5_prev = false;
        break;
    case MOT_G5:
    case MOT_G51:
        e = do_spline(g, b, g->motion == MOT_G51, l->mcol);
        g->g5_prev = g->motion == MOT_G5;
        break;
    case GC_G38_2:
    case GC_G38_3:
    case GC_G38_4:
    case GC_G38_5:
        e = cs_gcode_probe(g, b, g->motion, l->mcol);
        g->g5_prev = false;
        break;
    case MOT_G73:
    case MOT_G81:
    case MOT_G83:
        e = cs_gcode_cycle(g, b, g->motion, before == g->motion, l->mcol);
        g->g5_prev = false;
        break;
    default: /* G5.2 / G6.2 mode after its block: axis words alone start nothing */
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, first_col),
                                "axis words after a closed NURBS block: give G0, G1... first");
    }
    return e;
}

static cs_err_t run_block(gc_t *g, block_t *b, unsigned first_col)
{
    bool end = false, done;
    gline_t l = {.motion = MOT_LINE_NONE, .mcol = first_col, .axes_code = -1};
    cs_err_t e = run_letters(g, b);
    /* A line without K ends a G6.2 block before anything on it runs. */
    if (e == CS_OK && g->nurbs == MOT_G62 && !b->w['K' - 'A'].has)
        e = cs_gcode_nurbs_close(g);
    if (e == CS_OK)
        e = run_m(g, b, &end);
    if (e == CS_OK)
        e = run_g(g, b, &l);
    if (e != CS_OK)
        return e;
    if (l.drop) {
        if (l.motion == MOT_DROPPED)
            g->dropped_code = l.drop_code;
        drop_block(g, b, l.drop_code, l.dropcol, false);
    }
    if (l.g64 && (e = run_g64(g, b, l.g64col)) != CS_OK)
        return e;
    if ((e = run_nurbs(g, b, &l, first_col, &done)) != CS_OK)
        return e;
    if (!done && (e = l.axes_code >= 0 ? run_axes_code(g, b, &l)
                                        : run_motion(g, b, &l, first_col)) != CS_OK)
        return e;
    /* Words given but not used by anything on the line. */
    for (int k = 0; k < 2; k++)
        if (b->polar[k].has && !b->polar_used)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, b->polar[k].col),
                                    "%c (polar coordinates) not used by anything on this line",
                                    k ? '^' : '@');
    for (int i = 0; i < 26; i++) {
        if (!b->w[i].has || (b->used & (1u << i)))
            continue;
        if (!g->o->lenient)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, b->w[i].col),
                                    "%c word not used by anything on this line", 'A' + i);
        cs_gcode_warn_once(g, b->w[i].col,
                           "%c word not used by anything on this line: ignored (--lenient)",
                           'A' + i);
    }
    if (end)
        g->ended = true;
    return CS_OK;
}

/* ---- lexing ------------------------------------------------------------------------------ */

/* The value of word `letter` (at column col) at s[*i]: a number, or in LinuxCNC's dialect any
 * real value (#parameter, [expression], function) read by cs_gexpr. */
static cs_err_t read_value(gc_t *g, const char *s, size_t n, size_t *i, char letter, unsigned col,
                           double *v)
{
    cs_gexpr_fail_t f;
    size_t start = *i;
    bool grbl = g->o->dialect == CS_GCODE_GRBL;
    if (grbl && *i < n && (s[*i] == '#' || s[*i] == '['))
        return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, cs_gcode_loc(g, cs_gflow_col(s, *i)),
                                "%s are LinuxCNC's: Grbl 1.1 has none (--dialect grbl)",
                                s[*i] == '#' ? "parameters (#)" : "expressions ([...])");
    cs_err_t e = grbl ? cs_gexpr_number(s, n, i, v, &f) : cs_gexpr_real(&g->st, s, n, i, v, &f);
    if (e == CS_OK)
        return CS_OK;
    if (f.at == start && strcmp(f.reason, "expected a number") == 0)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                "%c must be followed by a number", letter);
    return cs_path_diag_set(g->diag, e, cs_gcode_loc(g, cs_gflow_col(s, f.at)), "%s", f.reason);
}

/* "#... = value" at s[*i]: read now, set at the end of the line (cs_gexpr_commit). */
static cs_err_t read_assign(gc_t *g, const char *s, size_t n, size_t *i)
{
    cs_gexpr_fail_t f;
    if (g->o->dialect == CS_GCODE_GRBL)
        return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, cs_gcode_loc(g, cs_gflow_col(s, *i)),
                                "parameters (#) are LinuxCNC's: Grbl 1.1 has none "
                                "(--dialect grbl)");
    cs_err_t e = cs_gexpr_assign(&g->st, s, n, i, &f);
    if (e != CS_OK)
        return cs_path_diag_set(g->diag, e, cs_gcode_loc(g, cs_gflow_col(s, f.at)), "%s", f.reason);
    return CS_OK;
}

/* Pass 1 over line s[0..n): comments checked, a RepRap checksum checked; *code_end is where
 * the words end (';' or the checksum's '*'). */
static cs_err_t code_of_line(gc_t *g, const char *s, size_t n, size_t *code_end)
{
    size_t star = n, depth = 0;
    *code_end = n;
    for (size_t i = 0; i < n; i++) {
        char c = s[i];
        if (c == '(') {
            size_t j = i + 1;
            while (j < n && s[j] != ')')
                j++;
            if (j == n)
                return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, cs_gflow_col(s, i)),
                                        "comment not closed on its line (missing ')')");
            i = j;
        } else if (c == ';') {
            *code_end = i;
            break;
        } else if (c == '[') {
            depth++;
        } else if (c == ']') {
            depth -= depth > 0;
        } else if (c == '*' && star == n && depth == 0) {
            /* Inside [...] '*' multiplies (LinuxCNC); outside it starts a checksum. */
            star = i;
        } else if (c == '\0') {
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, cs_gflow_col(s, i)),
                                    "NUL byte in the input");
        }
    }
    if (star == n)
        return CS_OK;
    /* RepRap checksum: XOR of every byte before '*', written in decimal after it. */
    unsigned x = 0;
    for (size_t i = 0; i < star; i++)
        x ^= (unsigned char)s[i];
    size_t j = star + 1;
    unsigned v = 0, nd = 0;
    while (j < *code_end && s[j] >= '0' && s[j] <= '9' && nd < 4)
        v = v * 10 + (unsigned)(s[j++] - '0'), nd++;
    size_t k = j;
    while (k < *code_end && (s[k] == ' ' || s[k] == '\t'))
        k++;
    while (k < *code_end && s[k] == '(') {
        while (k < *code_end && s[k] != ')')
            k++;
        k++;
        while (k < *code_end && (s[k] == ' ' || s[k] == '\t'))
            k++;
    }
    if (nd == 0 || nd > 3 || v > 255 || k < *code_end)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, cs_gflow_col(s, star)),
                                "'*' must end the line with a checksum from 0 to 255");
    if (v != x)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, cs_gflow_col(s, star)),
                                "checksum *%u does not match the line (the XOR of the "
                                "bytes before '*' is %u)",
                                v, x);
    *code_end = star;
    return CS_OK;
}

/* Stores word L (letter index li) = v at col into the line's words. */
static cs_err_t keep_word(gc_t *g, block_t *b, int li, double v, unsigned col)
{
    char L = (char)('A' + li);
    if (L == 'G' || L == 'M') {
        double t = v * 10.0;
        if (v < 0 || v > 1000 || fabs(t - nearbyint(t)) > 1e-6)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                    "%c%g is not a %c code", L, v, L);
        int code = (int)nearbyint(t);
        int *codes = L == 'G' ? b->g : b->m;
        unsigned *cols = L == 'G' ? b->gcol : b->mcol, *nc = L == 'G' ? &b->ng : &b->nm;
        if (*nc == sizeof b->g / sizeof b->g[0])
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                    "too many %c words on one line", L);
        for (unsigned k = 0; k < *nc && L == 'G'; k++)
            if (codes[k] == code)
                return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                        "G%g given twice on one line", v);
        cols[*nc] = col;
        codes[(*nc)++] = code;
        return CS_OK;
    }
    if (b->w[li].has)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                "%c given twice on one line", L);
    if (!isfinite(v) || fabs(v) > 1e9)
        return cs_path_diag_set(g->diag, CS_ERR_RANGE, cs_gcode_loc(g, col),
                                "%c value out of range", L);
    b->w[li].has = true;
    b->w[li].v = v;
    b->w[li].col = col;
    return CS_OK;
}

/* What cannot start a word at s[i] (col): '[', an O-word not at the line's start, a byte. */
static cs_err_t not_a_word(gc_t *g, char c, unsigned col)
{
    bool grbl = g->o->dialect == CS_GCODE_GRBL;
    if (c == '[')
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                "an expression [...] must be the value of a word (X[...])");
    if (c == 'o' || c == 'O')
        return cs_path_diag_set(g->diag, grbl ? CS_ERR_UNSUPPORTED : CS_ERR_PARSE,
                                cs_gcode_loc(g, col),
                                grbl ? "O-words are LinuxCNC's: Grbl 1.1 has none "
                                       "(--dialect grbl)"
                                     : "an O-word must begin its line (only a line number may "
                                       "come before it)");
    if (c == '@' || c == '^') /* LinuxCNC's polar coordinates, read in its dialect only */
        return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, cs_gcode_loc(g, col),
                                "polar coordinates (@ distance, ^ angle) are LinuxCNC's: not in "
                                "Grbl 1.1 (--dialect grbl)");
    if ((unsigned char)c < 0x20 || (unsigned char)c >= 0x7F)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                "unexpected byte 0x%02X", (unsigned)(unsigned char)c);
    return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                            "unexpected character '%c' (expected a word: a letter and a number)",
                            c);
}

/* LinuxCNC's @ (distance) or ^ (angle) at s[*i] (column col): its value into b->polar. */
static cs_err_t read_polar(gc_t *g, block_t *b, const char *s, size_t n, size_t *i, unsigned col)
{
    char c = s[*i];
    word_t *w = &b->polar[c == '^'];
    (*i)++;
    while (*i < n && (s[*i] == ' ' || s[*i] == '\t'))
        (*i)++;
    double v;
    cs_err_t e = read_value(g, s, n, i, c, col, &v);
    if (e != CS_OK)
        return e;
    if (w->has)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                "%c given twice on one line", c);
    if (!isfinite(v) || fabs(v) > 1e9)
        return cs_path_diag_set(g->diag, CS_ERR_RANGE, cs_gcode_loc(g, col),
                                "%c value out of range", c);
    w->has = true;
    w->v = v;
    w->col = col;
    return CS_OK;
}

/* One line s[0..n) (without its end of line). */
static cs_err_t do_line(gc_t *g, const char *s, size_t n)
{
    size_t code_end;
    cs_err_t e = code_of_line(g, s, n, &code_end);
    if (e != CS_OK)
        return e;
    block_t b;
    memset(&b, 0, sizeof b);
    size_t i = 0;
    while (i < code_end && (s[i] == ' ' || s[i] == '\t'))
        i++;
    if (i < code_end && s[i] == '/')
        return CS_OK; /* block delete: the line is skipped (the switch is on) */
    if (i < code_end && s[i] == '%') {
        /* Program delimiter: nothing else may share its line. */
        size_t j = i + 1;
        while (j < code_end && (s[j] == ' ' || s[j] == '\t'))
            j++;
        if (j == code_end)
            return CS_OK;
    }
    unsigned first_col = 0;
    while (i < code_end) {
        char c = s[i];
        if (c == ' ' || c == '\t' || c == '\r') {
            i++;
            continue;
        }
        if (c == '(') {
            while (s[i] != ')')
                i++;
            i++;
            continue;
        }
        unsigned col = cs_gflow_col(s, i);
        if (c == '#') {
            if ((e = read_assign(g, s, code_end, &i)) != CS_OK)
                return e;
            continue;
        }
        if ((c == '@' || c == '^') && g->o->dialect != CS_GCODE_GRBL) {
            if ((e = read_polar(g, &b, s, code_end, &i, col)) != CS_OK)
                return e;
            if (first_col == 0)
                first_col = col;
            continue;
        }
        int li = letter_index(c);
        if (li < 0 || c == 'o' || c == 'O')
            return not_a_word(g, c, col);
        i++;
        while (i < code_end && (s[i] == ' ' || s[i] == '\t'))
            i++;
        double v;
        if ((e = read_value(g, s, code_end, &i, (char)('A' + li), col, &v)) != CS_OK ||
            (e = keep_word(g, &b, li, v, col)) != CS_OK)
            return e;
        if (first_col == 0)
            first_col = col;
    }
    return first_col == 0 ? CS_OK : run_block(g, &b, first_col);
}

void cs_gcode_opts_init(cs_gcode_opts_t *o)
{
    memset(o, 0, sizeof *o);
    o->helix_tol_mm = CS_GCODE_HELIX_TOL_MM;
}

cs_err_t cs_gcode_line(gc_t *g, const char *s, size_t n)
{
    cs_err_t e = do_line(g, s, n);
    if (e != CS_OK) {
        cs_gexpr_discard(&g->st);
        return e;
    }
    if (cs_gexpr_commit(&g->st) != CS_OK)
        return cs_path_diag_set(g->diag, CS_ERR_FULL, cs_gcode_loc(g, 1), "out of memory");
    return CS_OK;
}

cs_err_t cs_gcode_run_lines(gc_t *g, cs_gflow_t *fl, const char *buf)
{
    cs_err_t e = CS_OK;
    size_t k = 0;
    while (k < fl->n && !g->ended && e == CS_OK) {
        size_t next = k + 1;
        g->line = (unsigned)(k + 1);
        if (g->stats)
            g->stats->lines++;
        if (fl->lines[k].kind != CS_GFLOW_NONE)
            e = cs_gflow_exec(fl, g->name, buf, k, &g->st, &next, g->diag);
        else
            e = cs_gcode_line(g, buf + fl->lines[k].start, fl->lines[k].len);
        k = next;
    }
    return e;
}

/* Runs the program line by line in the order its O-words decide (cs_gflow). */
static cs_err_t run_program(gc_t *g, cs_gflow_t *fl, const char *buf)
{
    cs_err_t e = cs_gcode_run_lines(g, fl, buf);
    if (e == CS_OK && g->nurbs == MOT_G62)
        e = cs_gcode_nurbs_close(g); /* a G6.2 block at the end of the program */
    if (e == CS_OK && g->nurbs)
        e = cs_path_diag_set(g->diag, CS_ERR_PARSE, g->nurbs_loc,
                             "G5.2 block not closed by G5.3 before the end of the program");
    return e;
}

void cs_gcode_start_modes(gc_t *g)
{
    g->unit = g->o->start_inch ? MM_PER_INCH : 1.0;
    g->plane = 17;
    g->incr = false;
    g->ijk_abs = false;
    g->feed = 0;
    g->g5_prev = false;
    g->retract_r = false; /* G98 */
    g->spindle = GC_M5;
    /* Grbl 1.1's defaults at power-up include G0 (its "$G" report: G0 G54 G17 G21 G90 G94). */
    g->motion = g->o->dialect == CS_GCODE_GRBL ? MOT_G0 : MOT_NONE;
}

cs_err_t cs_gcode_begin(gc_t *g, const char *name, const cs_gcode_opts_t *o, cs_path_t *path,
                        cs_path_diag_t *diag)
{
    memset(g, 0, sizeof *g);
    cs_path_loc_t l0 = {"<input>", 0, 0};
    g->name = cs_path_intern(path, name ? name : "<input>");
    if (!g->name)
        return cs_path_diag_set(diag, CS_ERR_FULL, l0, "out of memory");
    l0.file = g->name;
    if (!(o->helix_tol_mm > 0) || o->helix_tol_mm > CS_POS_LIMIT_MM)
        return cs_path_diag_set(diag, CS_ERR_TOLERANCE, l0, "helix tolerance %g mm not accepted",
                                o->helix_tol_mm);
    g->o = o;
    g->path = path;
    g->diag = diag;
    cs_gcode_start_modes(g);
    if (o->pen_z) /* the pen starts up: moves before the first M3 are travel (cs_pen, z mode) */
        g->pos[2] = o->pen_up_z_mm;
    if (cs_gexpr_init(&g->st) != CS_OK)
        return cs_path_diag_set(diag, CS_ERR_FULL, l0, "out of memory");
    cs_gcode_wcs_init(g);
    return CS_OK;
}

cs_err_t cs_gcode_read(const char *name, const char *buf, size_t len, const cs_gcode_opts_t *o,
                       cs_path_t *path, cs_path_diag_t *diag, cs_gcode_stats_t *stats)
{
    cs_gcode_opts_t dflt;
    if (!o) {
        cs_gcode_opts_init(&dflt);
        o = &dflt;
    }
    gc_t g;
    cs_err_t e = cs_gcode_begin(&g, name, o, path, diag);
    if (e != CS_OK) {
        cs_gexpr_free(&g.st);
        return e;
    }
    g.stats = stats;
    if (stats)
        memset(stats, 0, sizeof *stats);
    cs_path_new_subpath(path);
    if (o->pen_z && o->pen_z_feed_mm_s > 0) {
        /* the pen starts up: with a z_feed the raise from the origin is a pen move too, at
         * that speed (else the planner's rapid to the path's start makes it) */
        double up[3] = {g.pos[0], g.pos[1], o->pen_up_z_mm};
        g.pos[2] = 0;
        if ((e = pen_z_move(&g, up, 0)) != CS_OK) {
            cs_gexpr_free(&g.st);
            return e;
        }
        g.pos[2] = o->pen_up_z_mm;
    }
    /* A UTF-8 byte order mark (Windows editors write one) is no G-code: skipped, so that line 1's
     * columns count from the first character shown. */
    if (len >= 3 && memcmp(buf, "\xef\xbb\xbf", 3) == 0) {
        buf += 3;
        len -= 3;
    }
    cs_gflow_t fl;
    e = cs_gflow_init(&fl, g.name, buf, len, o->dialect != CS_GCODE_GRBL, o->max_loops, diag);
    if (e == CS_OK)
        e = run_program(&g, &fl, buf);
    cs_gflow_free(&fl);
    cs_gexpr_free(&g.st);
    cs_gnurbs_free(&g.nb);
    return e;
}
