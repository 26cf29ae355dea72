/* cs_gcode: G-code text -> path elements (see cs_gcode.h; the words and the LinuxCNC semantics
 * chosen are listed in docs/inputs.md, section "G-code"). */
#include "cs_gcode.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_arc.h"
#include "cs_conv.h"
#include "cs_err_text.h"
#include "cs_gexpr.h"
#include "cs_gflow.h"
#include "cs_gnurbs.h"

#define MM_PER_INCH 25.4
/* pi, spelled out: M_PI is POSIX, not C99 (the fuzz build uses plain -std=c99). */
#define GC_PI 3.14159265358979323846
/* LinuxCNC's arc checks (src/emc/rs274ngc/interp_arc.cc and interp_internal.hh): an I/J/K arc
 * is refused when its end radius differs from its start radius by more than
 * CENTER_ARC_RADIUS_TOLERANCE (2 * 0.001 * sqrt 2 in, 2 * 0.01 * sqrt 2 mm: endpoints rounded
 * to 0.001 in or 0.01 mm pass) or by more than SPIRAL_RELATIVE_TOLERANCE (0.1 %); a radius below
 * RADIUS_TOLERANCE (0.00005 in, its mm equivalent) is zero; an R arc whose half chord exceeds
 * |R| by more than RADIUS_TOLERANCE cannot reach its end (up to that, a semicircle). */
#define SQRT2           1.41421356237309504880
#define ARC_TOL_MM      (2 * 0.01 * SQRT2)
#define ARC_TOL_INCH    (2 * 0.001 * SQRT2)
#define ARC_REL_TOL     0.001
#define ARC_TOL_HARD    100.0 /* beyond 100 x the absolute tolerance: refused whatever the radius */
#define RADIUS_TOL_INCH 0.00005
/* Grbl 1.1 (gcode.c, the I/J/K arc's final error checks): the end radius may differ from the
 * start radius by 0.005 mm; beyond that, an error if over 0.5 mm or over 0.1 % of the radius. */
#define GRBL_ARC_TOL_MM      0.005
#define GRBL_ARC_HARD_MM     0.5
/* Largest sweep of one arc piece: under 90 degrees, so cs_arc_gcode returns exactly one piece. */
#define ARC_PIECE_MAX (0.999 * GC_PI / 2.0)
/* Most pieces one G2/G3 may become (a helix of many turns at a fine tolerance). */
#define ARC_MAX_PIECES 100000u

/* Motion modes: the G number times ten. */
enum {
    MOT_DROPPED = -3, /* an unsupported motion mode dropped by --lenient (G81, G38.2...) */
    MOT_NONE = -1,
    MOT_G0 = 0,
    MOT_G1 = 10,
    MOT_G2 = 20,
    MOT_G3 = 30,
    MOT_G5 = 50,
    MOT_G51 = 51,
    MOT_G52 = 52,
    MOT_G62 = 62
};

typedef struct {
    bool has;
    double v;
    unsigned col;
} word_t;

typedef struct {
    const char *name;
    const cs_gcode_opts_t *o;
    cs_path_t *path;
    cs_path_diag_t *diag;
    cs_gcode_stats_t *stats;
    unsigned line;
    /* modal state */
    double pos[3]; /* machine position, mm */
    double off[3]; /* G92: program coordinate = machine - off */
    double unit;   /* mm per program unit */
    bool incr;     /* G91 */
    bool ijk_abs;  /* G90.1 */
    int plane;     /* 17, 18, 19 */
    int motion;    /* MOT_* */
    int dropped_code; /* --lenient: the unsupported motion code MOT_DROPPED stands for */
    double feed;   /* F in program units per minute; 0 = none given */
    bool g5_prev;  /* the last move was a G5: its P, Q continue */
    double g5_pq[2];
    bool last_rapid;
    bool ended; /* M2 / M30 */
    /* open NURBS block: G5.2 (until G5.3) or G6.2 (until a line without K) */
    cs_gnurbs_t nb;
    int nurbs;          /* 0 (none), MOT_G52 or MOT_G62 */
    bool g62_knots;     /* the G6.2 block has reached its knot-only lines */
    bool emit_failed;   /* a NURBS segment could not be added (diag set) */
    cs_path_loc_t nurbs_loc;
    double nurbs_feed;
    cs_gexpr_store_t st; /* parameters (LinuxCNC) */
} gc_t;

/* One line's words. */
typedef struct {
    word_t w[26]; /* by letter; G and M are kept apart */
    int g[8];
    unsigned gcol[8];
    unsigned ng;
    int m[8];
    unsigned mcol[8];
    unsigned nm;
    unsigned used; /* bit per letter consumed by the block */
} block_t;

static cs_path_loc_t loc_at(const gc_t *g, unsigned col)
{
    cs_path_loc_t l = {g->name, g->line, col};
    return l;
}

static void warn(gc_t *g, unsigned col, const char *fmt, ...)
{
    cs_path_diag_t w;
    w.code = CS_OK;
    w.loc = loc_at(g, col);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(w.reason, sizeof w.reason, fmt, ap);
    va_end(ap);
    if (g->stats)
        g->stats->warnings++;
    if (g->o->warn)
        g->o->warn(g->o->warn_ctx, &w);
    else
        fprintf(stderr, "%s:%u:%u: warning: %s\n", w.loc.file, w.loc.line, w.loc.col, w.reason);
}

/* An unsupported word: an error, or a warning (and CS_OK: the caller ignores it) when lenient. */
static cs_err_t unsupported(gc_t *g, unsigned col, const char *what)
{
    if (g->o->lenient) {
        warn(g, col, "%s is not supported: ignored (--lenient)", what);
        return CS_OK;
    }
    return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, loc_at(g, col),
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

#define BIT(c) (1u << ((c) - 'A'))

/* Column (1-based, in characters: UTF-8 continuation bytes do not count) of s[i] on a line that
 * starts at s[0]. */
static unsigned col_of(const char *s, size_t i)
{
    unsigned c = 1;
    for (size_t k = 0; k < i; k++)
        if (((unsigned char)s[k] & 0xC0) != 0x80)
            c++;
    return c;
}

/* ---- geometry helpers -------------------------------------------------------------------- */

static cs_err_t to_vec(gc_t *g, const double p[3], unsigned col, cs_vec3_t *out)
{
    if (cs_conv_mm_to_vec(p[0], p[1], p[2], out) != CS_OK)
        return cs_path_diag_set(g->diag, CS_ERR_RANGE, loc_at(g, col),
                                "point (%.4f, %.4f, %.4f) mm is outside +/-%d mm", p[0], p[1], p[2],
                                CS_POS_LIMIT_MM);
    return CS_OK;
}

static cs_pos_t *coord(cs_vec3_t *v, int axis)
{
    return axis == 0 ? &v->x : axis == 1 ? &v->y : &v->z;
}

static bool vec_eq(const cs_vec3_t *a, const cs_vec3_t *b)
{
    return a->x == b->x && a->y == b->y && a->z == b->z;
}

static cs_err_t add(gc_t *g, const cs_bezier_t *c, cs_path_kind_t kind, unsigned col, bool rapid)
{
    if (rapid != g->last_rapid) {
        cs_path_new_subpath(g->path);
        g->last_rapid = rapid;
    }
    if (g->o->max_elements > 0 && g->path->n >= g->o->max_elements)
        return cs_path_diag_set(g->diag, CS_ERR_FULL, loc_at(g, col),
                                "the job needs more than %zu path elements", g->o->max_elements);
    double feed = rapid ? 0.0 : g->feed * g->unit / 60.0;
    if (cs_path_add_move(g->path, c, kind, loc_at(g, col), feed, rapid) != CS_OK)
        return cs_path_diag_set(g->diag, CS_ERR_FULL, loc_at(g, col), "out of memory");
    return CS_OK;
}

static cs_err_t add_line(gc_t *g, const double a[3], const double b[3], unsigned col, bool rapid)
{
    cs_vec3_t p[2];
    cs_err_t e = to_vec(g, a, col, &p[0]);
    if (e == CS_OK)
        e = to_vec(g, b, col, &p[1]);
    if (e != CS_OK || vec_eq(&p[0], &p[1]))
        return e; /* a move that goes nowhere adds nothing */
    cs_bezier_t c;
    cs_bezier_init(&c, 1, p);
    return add(g, &c, CS_PATH_LINE, col, rapid);
}

/* Axis words -> target (machine mm). */
static void target_of(gc_t *g, block_t *b, double t[3])
{
    for (int a = 0; a < 3; a++) {
        const word_t *w = &b->w['X' - 'A' + a];
        if (!w->has) {
            t[a] = g->pos[a];
            continue;
        }
        b->used |= BIT('X' + a);
        t[a] = g->incr ? g->pos[a] + w->v * g->unit : w->v * g->unit + g->off[a];
    }
}

static bool any_axis(const block_t *b)
{
    return b->w['X' - 'A'].has || b->w['Y' - 'A'].has || b->w['Z' - 'A'].has;
}

/* Plane axes: first, second (counter-clockwise from first to second), normal. */
static void plane_axes(int plane, int ax[3])
{
    if (plane == 18) {
        ax[0] = 2, ax[1] = 0, ax[2] = 1;
    } else if (plane == 19) {
        ax[0] = 1, ax[1] = 2, ax[2] = 0;
    } else {
        ax[0] = 0, ax[1] = 1, ax[2] = 2;
    }
}

/* Largest distance between a helix piece of half-sweep a (<= pi/4) climbing dz and the rational
 * quadratic circle piece whose third coordinate has control values z0, (z0+z1)/2, z1: with
 * s = 2t - 1 the piece is at angle 2 atan(tan(a/2) s) from its middle while its third coordinate
 * is dz s (1 + tan^2(a/2)) / (2 (1 + tan^2(a/2) s^2)); the helix point at the same angle lies
 * dz |f_a(s)| away, and max |f_a| <= a^2/24 for a <= pi/4 (its series is a^2 (s - s^3)/12 + ...;
 * the maximum measured over s is 0.0321 a^2 at small a and 0.0342 a^2 at pi/4). Every point of
 * either curve has a point of the other at that distance, so this bounds the Hausdorff distance. */
static double helix_piece_err(double dz, double half_sweep)
{
    return fabs(dz) * half_sweep * half_sweep / 24.0;
}

/* Emits the arc (or helix) around centre c (machine mm; its normal coordinate is unused) from
 * g->pos to t, sweeping `sweep` radians (positive = counter-clockwise in the plane), radius
 * going linearly from r0 to r1 (equal unless the I/J/K end radius differs within tolerance). */
static cs_err_t emit_arc(gc_t *g, const double c[3], const double t[3], double sweep, double r0,
                         double r1, unsigned col)
{
    int ax[3];
    plane_axes(g->plane, ax);
    const double *s = g->pos;
    double th0 = atan2(s[ax[1]] - c[ax[1]], s[ax[0]] - c[ax[0]]);
    double dz = t[ax[2]] - s[ax[2]];
    double asw = fabs(sweep);
    unsigned n = (unsigned)ceil(asw / ARC_PIECE_MAX);
    if (n < 1)
        n = 1;
    /* A spiral (r0 != r1, within LinuxCNC's tolerance): each piece is a circular arc whose end
     * is snapped onto the spiral, so a piece may change the radius by at most half the helix
     * tolerance. */
    while (fabs(r1 - r0) / n > g->o->helix_tol_mm / 2 && n < ARC_MAX_PIECES)
        n = n * 2 > ARC_MAX_PIECES ? ARC_MAX_PIECES : n * 2;
    if (dz != 0.0) {
        if (g->stats)
            g->stats->helices++;
        while (helix_piece_err(dz / n, asw / n / 2.0) > g->o->helix_tol_mm) {
            if (n >= ARC_MAX_PIECES)
                return cs_path_diag_set(g->diag, CS_ERR_RANGE, loc_at(g, col),
                                        "helix needs more than %u pieces for a tolerance of "
                                        "%g mm",
                                        ARC_MAX_PIECES, g->o->helix_tol_mm);
            n = n * 2 > ARC_MAX_PIECES ? ARC_MAX_PIECES : n * 2;
        }
    }
    bool ccw = sweep > 0;
    cs_vec3_t cc, ps, pe;
    double cz[3] = {c[0], c[1], c[2]};
    cz[ax[2]] = s[ax[2]];
    cs_err_t e = to_vec(g, cz, col, &cc);
    if (e != CS_OK)
        return cs_path_diag_set(g->diag, CS_ERR_RANGE, loc_at(g, col),
                                "arc centre (%.4f, %.4f, %.4f) mm is outside +/-%d mm", c[0], c[1],
                                c[2], CS_POS_LIMIT_MM);
    if ((e = to_vec(g, s, col, &ps)) != CS_OK || (e = to_vec(g, t, col, &pe)) != CS_OK)
        return e;
    cs_vec3_t a = ps;
    for (unsigned k = 0; k < n; k++) {
        double f = (double)(k + 1) / n;
        cs_vec3_t b;
        if (k + 1 == n) {
            b = pe;
        } else {
            double th = th0 + sweep * f, r = r0 + (r1 - r0) * f, q[3];
            q[ax[0]] = c[ax[0]] + r * cos(th);
            q[ax[1]] = c[ax[1]] + r * sin(th);
            q[ax[2]] = s[ax[2]] + dz * f;
            if ((e = to_vec(g, q, col, &b)) != CS_OK)
                return e;
        }
        cs_pos_t an = *coord(&a, ax[2]), bn = *coord(&b, ax[2]);
        cs_vec3_t bflat = b, cflat = cc;
        *coord(&bflat, ax[2]) = an;
        *coord(&cflat, ax[2]) = an;
        /* In LSB: the piece's chord c and radius r. When c^2 <= 4 r the arc's sagitta
         * c^2 / (8 r) is at most half an LSB, so a line is as close to the circle as rounding
         * allows; and below that the two end directions may round to the same Q1.30 pair, which
         * cs_arc_gcode would read as a full turn. */
        double ch0 = (double)*coord(&bflat, ax[0]) - *coord(&a, ax[0]);
        double ch1 = (double)*coord(&bflat, ax[1]) - *coord(&a, ax[1]);
        double ra0 = (double)*coord(&a, ax[0]) - *coord(&cflat, ax[0]);
        double ra1 = (double)*coord(&a, ax[1]) - *coord(&cflat, ax[1]);
        if (ch0 * ch0 + ch1 * ch1 <= 4.0 * sqrt(ra0 * ra0 + ra1 * ra1) || vec_eq(&bflat, &cflat)) {
            if (!vec_eq(&a, &b)) {
                cs_vec3_t p[2] = {a, b};
                cs_bezier_t l;
                cs_bezier_init(&l, 1, p);
                if ((e = add(g, &l, CS_PATH_LINE, col, false)) != CS_OK)
                    return e;
            }
            a = b;
            continue;
        }
        cs_bezier_t out[CS_ARC_MAX_SEGMENTS];
        unsigned m = 0;
        e = cs_arc_gcode(&cflat, &a, &bflat, (cs_arc_plane_t)g->plane, ccw, out, &m);
        /* A piece is under 90 degrees in double; rounding its ends to the LSB turns it by at
         * most ~0.7 LSB / radius (0.5 degrees at the smallest radius accepted), so the builder
         * may halve it, never more: outside the line case above the turn keeps its direction
         * (reversing it would take a chord under 0.7 LSB). More pieces would mean a wrong turn. */
        if (e != CS_OK || m < 1 || m > 2)
            return cs_path_diag_set(g->diag, e == CS_OK ? CS_ERR_STATE : e, loc_at(g, col),
                                    "cannot build this arc: %s",
                                    e == CS_OK ? "piece split unexpectedly" : cs_err_text(e));
        for (unsigned j = 0; j < m; j++) {
            cs_bezier_t *pc = &out[j];
            /* The third axis: linear in angle (the builder's pieces are equal halves), control
             * values z0, (z0+z1)/2, z1 on each (helix_piece_err). */
            int64_t z0 = an + ((int64_t)bn - an) * j / m;
            int64_t z1 = an + ((int64_t)bn - an) * (j + 1) / m;
            *coord(&pc->p[0], ax[2]) = (cs_pos_t)z0;
            *coord(&pc->p[1], ax[2]) = (cs_pos_t)((z0 + z1) / 2);
            *coord(&pc->p[2], ax[2]) = (cs_pos_t)z1;
            /* Snap the outer ends onto the shared points (they differ by at most 2 LSB plus the
             * spiral's radius change over this piece): moving an end control point by d moves
             * the curve by at most d, and consecutive elements then meet exactly (the builder's
             * own pieces already share their ends). */
            if (j == 0)
                pc->p[0] = a;
            if (j + 1 == m)
                pc->p[2] = b;
            if ((e = add(g, pc, CS_PATH_ARC, col, false)) != CS_OK)
                return e;
        }
        a = b;
    }
    return CS_OK;
}

/* Both in mm, for the units in effect. */
static double arc_tol(const gc_t *g)
{
    return g->unit == 1.0 ? ARC_TOL_MM : ARC_TOL_INCH * MM_PER_INCH;
}

static double radius_tol(void)
{
    return RADIUS_TOL_INCH * MM_PER_INCH; /* LinuxCNC: the same length in either unit */
}

/* The end radius r1 of an I/J/K arc against its start radius r0 (mm). LinuxCNC (interp_arc.cc):
 * refused when the difference exceeds 100 times the absolute tolerance, or exceeds it while
 * also over 0.1 % of the radius (a spiral within those is cut as one). Grbl 1.1 (gcode.c):
 * refused over 0.005 mm when also over 0.5 mm or 0.1 % of the start radius. */
static cs_err_t arc_radius_check(gc_t *g, double r0, double r1, unsigned col)
{
    double ae = fabs(r0 - r1), rel = ae / fmax(r0, r1);
    bool grbl = g->o->dialect == CS_GCODE_GRBL;
    double tol = grbl ? GRBL_ARC_TOL_MM : arc_tol(g);
    double hard = grbl ? GRBL_ARC_HARD_MM : ARC_TOL_HARD * tol;
    if (grbl)
        rel = ae / r0;
    if (ae > hard || (ae > tol && rel > ARC_REL_TOL))
        return cs_path_diag_set(g->diag, CS_ERR_DEGENERATE, loc_at(g, col),
                                "radius to end of arc (%.4f mm) differs from radius to start "
                                "(%.4f mm) by %.4f mm (%.3f%%); %s accepts up to %.4f mm, or up "
                                "to %.4f mm within 0.1%%%s",
                                r1, r0, ae, 100 * rel, grbl ? "Grbl" : "LinuxCNC", tol, hard,
                                grbl ? " (Grbl: error:33)" : "");
    return CS_OK;
}

/* G2 / G3. */
static cs_err_t do_arc(gc_t *g, block_t *b, bool ccw, unsigned col)
{
    int ax[3];
    plane_axes(g->plane, ax);
    double t[3];
    target_of(g, b, t);
    if (g->stats)
        g->stats->arcs++;
    const char *names = g->plane == 17 ? "I/J" : g->plane == 18 ? "I/K" : "J/K";
    const word_t *r = &b->w['R' - 'A'];
    const word_t *ofs[3] = {&b->w['I' - 'A'], &b->w['J' - 'A'], &b->w['K' - 'A']};
    bool has_ijk = ofs[ax[0]]->has || ofs[ax[1]]->has;
    if (ofs[ax[2]]->has)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, ofs[ax[2]]->col),
                                "%c word in a G%d arc: the G%d plane uses %s", (char)('I' + ax[2]),
                                ccw ? 3 : 2, g->plane, names);
    if (r->has && has_ijk)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, r->col),
                                "R and %s in one arc: give the centre one way", names);
    if (!r->has && !has_ijk) {
        if (!g->o->lenient)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col),
                                    "G%d needs R (radius) or %s (centre)", ccw ? 3 : 2, names);
        /* Lenient: the arc's shape is unknown but its end is not. Skipping it would leave the
         * machine elsewhere than the program assumes, so every later R arc (whose centre
         * depends on its start) and every G91 move would be drawn wrong; a rapid would cross
         * the work at full speed. A straight feed move to the programmed end keeps the rest of
         * the file exact and only replaces this one arc by its chord. */
        warn(g, col,
             "G%d without R or %s: moved in a straight line (G1) to its end point instead "
             "(--lenient)",
             ccw ? 3 : 2, names);
        cs_err_t el = add_line(g, g->pos, t, col, false);
        if (el == CS_OK)
            memcpy(g->pos, t, sizeof g->pos);
        return el;
    }
    int turns = 1;
    const word_t *pw = &b->w['P' - 'A'];
    if (pw->has) {
        b->used |= BIT('P');
        if (pw->v < 1 || pw->v != floor(pw->v) || pw->v > 1000)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, pw->col),
                                    "P (turns) must be a whole number from 1 to 1000");
        turns = (int)pw->v;
    }
    double rtol = radius_tol();
    const double *s = g->pos;
    double s0 = s[ax[0]], s1 = s[ax[1]], e0 = t[ax[0]], e1 = t[ax[1]];
    double c[3] = {0, 0, 0};
    double r0, r1;
    if (r->has) {
        b->used |= BIT('R');
        double R = r->v * g->unit, aR = fabs(R);
        if (s0 == e0 && s1 == e1) {
            if (!g->o->lenient)
                return cs_path_diag_set(g->diag, CS_ERR_DEGENERATE, loc_at(g, r->col),
                                        "R-form arc ends where it starts: its centre is "
                                        "undefined (a full circle needs %s)",
                                        names);
            /* Lenient: no circle can be chosen (any centre at distance |R| fits), so nothing
             * is drawn in the plane; a move along the plane's normal is still made, straight
             * (the limit of a helix of no radius), so the position stays the programmed one. */
            warn(g, r->col,
                 "R-form arc ends where it starts (centre undefined): nothing drawn in the "
                 "plane (--lenient)");
            cs_err_t el = add_line(g, g->pos, t, col, false);
            if (el == CS_OK)
                memcpy(g->pos, t, sizeof g->pos);
            return el;
        }
        if (aR < rtol)
            return cs_path_diag_set(g->diag, CS_ERR_DEGENERATE, loc_at(g, r->col),
                                    "zero-radius arc (R %g)", r->v);
        double m0 = (s0 + e0) / 2, m1 = (s1 + e1) / 2;
        double half = hypot(e0 - m0, e1 - m1);
        if (half - aR > rtol)
            return cs_path_diag_set(g->diag, CS_ERR_DEGENERATE, loc_at(g, r->col),
                                    "radius %g is too small to reach the end point (half the "
                                    "chord is %.4f mm)",
                                    r->v, half);
        if (half > aR)
            half = aR;
        /* LinuxCNC arc_data_r: the centre is off the chord's midpoint, to the right of the
         * chord for G2 with R > 0 or G3 with R < 0 (the short arc), to the left otherwise. */
        double th = atan2(e1 - s1, e0 - s0) + ((!ccw) == (R > 0) ? -GC_PI / 2 : GC_PI / 2);
        double d = sqrt(aR * aR - half * half);
        c[ax[0]] = m0 + d * cos(th);
        c[ax[1]] = m1 + d * sin(th);
        /* The radii from the centre used (a chord a little over 2|R| gives the midpoint). */
        r0 = hypot(s0 - c[ax[0]], s1 - c[ax[1]]);
        r1 = hypot(e0 - c[ax[0]], e1 - c[ax[1]]);
    } else {
        for (int k = 0; k < 2; k++) {
            const word_t *w = ofs[ax[k]];
            double v = w->has ? w->v * g->unit : 0.0;
            if (w->has)
                b->used |= BIT('I' + ax[k]);
            c[ax[k]] = g->ijk_abs ? v + g->off[ax[k]] : s[ax[k]] + v;
        }
        r0 = hypot(s0 - c[ax[0]], s1 - c[ax[1]]);
        r1 = hypot(e0 - c[ax[0]], e1 - c[ax[1]]);
        if (r0 < rtol || r1 < rtol)
            return cs_path_diag_set(g->diag, CS_ERR_DEGENERATE, loc_at(g, col),
                                    "zero-radius arc (start or end on the centre)");
        cs_err_t ea = arc_radius_check(g, r0, r1, col);
        if (ea != CS_OK)
            return ea;
    }
    double a0 = atan2(s1 - c[ax[1]], s0 - c[ax[0]]);
    double a1 = atan2(e1 - c[ax[1]], e0 - c[ax[0]]);
    double sweep = ccw ? a1 - a0 : a0 - a1;
    while (sweep <= 0)
        sweep += 2 * GC_PI;
    while (sweep > 2 * GC_PI)
        sweep -= 2 * GC_PI;
    /* End on the start (to the LSB): a full circle (I/J/K form). */
    cs_pos_t q[4];
    if (cs_conv_mm_to_pos(s0, &q[0]) == CS_OK && cs_conv_mm_to_pos(s1, &q[1]) == CS_OK &&
        cs_conv_mm_to_pos(e0, &q[2]) == CS_OK && cs_conv_mm_to_pos(e1, &q[3]) == CS_OK &&
        q[0] == q[2] && q[1] == q[3])
        sweep = 2 * GC_PI;
    else if (sweep > 2 * GC_PI - 1e-12)
        sweep = 2 * GC_PI - 1e-12;
    sweep += 2 * GC_PI * (turns - 1);
    cs_err_t e = emit_arc(g, c, t, ccw ? sweep : -sweep, r0, r1, col);
    if (e == CS_OK)
        memcpy(g->pos, t, sizeof g->pos);
    return e;
}

/* G5 (cubic, continuation form when I and J are left out) and G5.1 (quadratic). */
static cs_err_t do_spline(gc_t *g, block_t *b, bool quad, unsigned col)
{
    const char *gname = quad ? "G5.1" : "G5";
    if (g->plane != 17)
        return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, loc_at(g, col),
                                "%s works in the G17 (XY) plane only", gname);
    if (b->w['Z' - 'A'].has)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, b->w['Z' - 'A'].col),
                                "%s moves in X and Y only (no Z word)", gname);
    const word_t *I = &b->w['I' - 'A'], *J = &b->w['J' - 'A'];
    const word_t *P = &b->w['P' - 'A'], *Q = &b->w['Q' - 'A'];
    double t[3];
    target_of(g, b, t);
    double ij[2];
    if (I->has || J->has) {
        if (!quad && I->has != J->has)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, (I->has ? I : J)->col),
                                    "G5 needs both I and J (or neither, to continue the "
                                    "previous G5)");
        ij[0] = I->has ? I->v * g->unit : 0.0;
        ij[1] = J->has ? J->v * g->unit : 0.0;
        b->used |= BIT('I') | BIT('J');
    } else if (!quad && g->g5_prev) {
        ij[0] = -g->g5_pq[0];
        ij[1] = -g->g5_pq[1];
    } else {
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col),
                                quad ? "G5.1 needs I and J (the control point offset)"
                                     : "G5 without I and J must follow another G5");
    }
    if (quad && ij[0] == 0.0 && ij[1] == 0.0)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col),
                                "G5.1 with I and J both zero");
    double pts[4][3];
    memcpy(pts[0], g->pos, sizeof pts[0]);
    pts[1][0] = g->pos[0] + ij[0];
    pts[1][1] = g->pos[1] + ij[1];
    pts[1][2] = g->pos[2];
    unsigned deg = quad ? 2 : 3;
    if (!quad) {
        if (!P->has || !Q->has)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col),
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
        cs_err_t e = to_vec(g, pts[i], col, &v[i]);
        if (e != CS_OK)
            return e;
    }
    cs_bezier_t c;
    cs_bezier_init(&c, deg, v);
    cs_err_t e = add(g, &c, quad ? CS_PATH_QUAD : CS_PATH_CUBIC, col, false);
    if (e == CS_OK)
        memcpy(g->pos, t, sizeof g->pos);
    return e;
}

/* ---- NURBS blocks: G5.2 ... G5.3 and G6.2 (cs_gnurbs) ------------------------------------ */

static cs_err_t nurbs_emit(void *ctx, const cs_bezier_t *seg)
{
    gc_t *g = ctx;
    cs_err_t e = add(g, seg, CS_PATH_OTHER, g->nurbs_loc.col, false);
    g->emit_failed = e != CS_OK;
    return e;
}

/* The open block becomes Bézier segments, at the feed of its first line. */
static cs_err_t nurbs_close(gc_t *g)
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
        return g->emit_failed ? e : cs_path_diag_set(g->diag, e, g->nurbs_loc, "%s block: %s",
                                                     gname, why);
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
    plane_axes(g->plane, ax);
    const word_t *A = &b->w['X' - 'A' + ax[0]], *B = &b->w['X' - 'A' + ax[1]];
    const word_t *N = &b->w['X' - 'A' + ax[2]];
    if (N->has)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, N->col),
                                "G5.2 control points in G%d are in %c and %c (no %c word)",
                                g->plane, 'X' + ax[0], 'X' + ax[1], 'X' + ax[2]);
    if (A->has != B->has)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, (A->has ? A : B)->col),
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
        return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, loc_at(g, col),
                                "G5.2 control points in G91 (incremental) mode are not "
                                "supported");
    g->nurbs = MOT_G52;
    g->nurbs_loc = loc_at(g, col);
    g->nurbs_feed = g->feed;
    cs_gnurbs_begin(&g->nb, 3);
    if (L->has) {
        b->used |= BIT('L');
        if (L->v != floor(L->v))
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, L->col),
                                    "L (order) must be a whole number");
        /* LinuxCNC takes L only when it is above 3 (the default order). */
        if (L->v > CS_GNURBS_MAX_ORDER)
            return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, loc_at(g, L->col),
                                    "NURBS order L%g: at most %d (cubic) is supported", L->v,
                                    CS_GNURBS_MAX_ORDER);
        if (L->v > 3)
            g->nb.order = (unsigned)L->v;
    }
    double w0 = (!has && P->has) ? P->v : 1.0;
    if (!(w0 > 0))
        return cs_path_diag_set(g->diag, CS_ERR_WEIGHT, loc_at(g, P->col),
                                "G5.2 weight P must be positive");
    return nurbs_push(g, g->pos, w0);
}

/* A G5.2 line (first = the line that carries G5.2) or a control point line inside the block. */
static cs_err_t do_nurbs_line(gc_t *g, block_t *b, bool first, unsigned col)
{
    const word_t *P = &b->w['P' - 'A'], *L = &b->w['L' - 'A'];
    bool has = false;
    cs_err_t e = nurbs_plane_words(g, b, &has);
    if (e != CS_OK)
        return e;
    if (first && (e = nurbs_open52(g, b, col, has)) != CS_OK)
        return e;
    if (L->has && !first)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, L->col),
                                "L (order) belongs on the G5.2 line");
    if (P->has)
        b->used |= BIT('P');
    if (!has)
        return CS_OK;
    if (!P->has || !(P->v > 0))
        return cs_path_diag_set(g->diag, CS_ERR_WEIGHT, loc_at(g, P->has ? P->col : col),
                                "each G5.2 control point needs a positive weight P");
    double t[3];
    target_of(g, b, t);
    return nurbs_push(g, t, P->v);
}

/* A G6.2 line (first) or a line of its block: "G6.2 P<order> K<knot> X.. Y.. Z.. R<weight>",
 * then "K.. X.. Y.. Z.. R.." per control point, then "K.." alone for the last order knots (the
 * block form of Fanuc's G06.2 that LinuxCNC's G6.2 follows). Axis words left out keep the
 * previous control point's value; R defaults to 1. */
static cs_err_t do_g62_line(gc_t *g, block_t *b, bool first, unsigned col)
{
    const word_t *P = &b->w['P' - 'A'], *K = &b->w['K' - 'A'], *R = &b->w['R' - 'A'];
    if (first) {
        if (!P->has || P->v != floor(P->v) || P->v < 2 || P->v > CS_GNURBS_MAX_ORDER)
            return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, loc_at(g, P->has ? P->col : col),
                                    "G6.2 needs P, the order: 2 to %d (cubic) are supported",
                                    CS_GNURBS_MAX_ORDER);
        if (g->incr)
            return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, loc_at(g, col),
                                    "G6.2 control points in G91 (incremental) mode are not "
                                    "supported");
        b->used |= BIT('P');
        g->nurbs = MOT_G62;
        g->g62_knots = false;
        g->nurbs_loc = loc_at(g, col);
        g->nurbs_feed = g->feed;
        cs_gnurbs_begin(&g->nb, (unsigned)P->v);
    }
    if (!K->has)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col),
                                "each line of a G6.2 block needs its knot K");
    b->used |= BIT('K') | BIT('R');
    if (cs_gnurbs_knot(&g->nb, K->v) != CS_OK)
        return cs_path_diag_set(g->diag, CS_ERR_FULL, loc_at(g, K->col), "too many G6.2 knots");
    if (!any_axis(b) && !R->has && !first) {
        g->g62_knots = true;
        return g->nb.nknots == g->nb.n + g->nb.order ? nurbs_close(g) : CS_OK;
    }
    if (g->g62_knots)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col),
                                "G6.2 control point after the knot-only lines that end the block");
    if (R->has && !(R->v > 0))
        return cs_path_diag_set(g->diag, CS_ERR_WEIGHT, loc_at(g, R->col),
                                "G6.2 weight R must be positive");
    double t[3];
    memcpy(t, g->nb.n ? g->nb.cps[g->nb.n - 1].p : g->pos, sizeof t);
    for (int a = 0; a < 3; a++) {
        const word_t *w = &b->w['X' - 'A' + a];
        if (w->has) {
            b->used |= BIT('X' + a);
            t[a] = w->v * g->unit + g->off[a];
        }
    }
    cs_vec3_t v0, v1;
    if (first && (to_vec(g, g->pos, col, &v0) != CS_OK || to_vec(g, t, col, &v1) != CS_OK ||
                  !vec_eq(&v0, &v1)))
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col),
                                "the first G6.2 control point must be where the tool is "
                                "(%.4f, %.4f, %.4f) mm", g->pos[0], g->pos[1], g->pos[2]);
    return nurbs_push(g, t, R->has ? R->v : 1.0);
}

/* ---- one block --------------------------------------------------------------------------- */

/* Letters this reader does not carry out (each once), then F and S. */
static cs_err_t run_letters(gc_t *g, block_t *b)
{
    static const char supported[] = "FGIJKLMNPQRSXYZ";
    for (int i = 0; i < 26; i++) {
        if (!b->w[i].has || strchr(supported, 'A' + i))
            continue;
        char what[48];
        snprintf(what, sizeof what, "the %c word", 'A' + i);
        cs_err_t e;
        if (i == 'T' - 'A' && g->o->dialect == CS_GCODE_GRBL) {
            /* Grbl 1.1 reads T and changes nothing (it has no tool changer). */
        } else if (i == 'T' - 'A' && g->o->lenient) {
            /* No tool changer: the tool in the machine stays, nothing moves. */
            warn(g, b->w[i].col, "T (tool select): ignored, there is no tool changer (--lenient)");
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
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, F->col),
                                    "F (feed) must be positive");
        g->feed = F->v;
    }
    if (b->w['S' - 'A'].has) {
        b->used |= BIT('S');
        if (b->w['S' - 'A'].v < 0)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, b->w['S' - 'A'].col),
                                    "S (spindle speed) must not be negative");
    }
    return CS_OK;
}

/* A G or M code's name ("G5.2", "M30"). */
static void code_name(char *out, size_t cap, char letter, int v)
{
    if (v % 10)
        snprintf(out, cap, "%c%d.%d", letter, v / 10, v % 10);
    else
        snprintf(out, cap, "%c%d", letter, v / 10);
}

/* M words: pen / spindle before the motion; *end for M2 / M30. */
static cs_err_t run_m(gc_t *g, block_t *b, bool *end)
{
    cs_err_t e;
    for (unsigned i = 0; i < b->nm; i++) {
        int m = b->m[i];
        if (m == 20 || m == 300) {
            *end = true;
        } else if (m == 30 || m == 40 || m == 50) {
            /* Pen down / spindle on, or pen up / spindle off: a new subpath either way, and
             * with opts->pen_z a rapid Z move to the pen height. */
            cs_path_new_subpath(g->path);
            if (g->o->pen_z) {
                double t[3] = {g->pos[0], g->pos[1],
                               m == 50 ? g->o->pen_up_z_mm : g->o->pen_down_z_mm};
                if ((e = add_line(g, g->pos, t, b->mcol[i], true)) != CS_OK)
                    return e;
                memcpy(g->pos, t, sizeof g->pos);
                cs_path_new_subpath(g->path);
            }
        } else if (m == 70 || m == 80 || m == 90) {
            /* Coolant mist / flood / off (LinuxCNC and Grbl): nothing to draw or move. */
        } else {
            char what[32];
            code_name(what, sizeof what, 'M', m);
            if ((e = unsupported(g, b->mcol[i], what)) != CS_OK)
                return e;
        }
    }
    return CS_OK;
}

/* What the G words of one line ask for. */
typedef struct {
    int motion; /* MOT_*, 53 (G5.3), or -2: no motion word on the line */
    unsigned mcol;
    bool g92, g64, drop;
    int drop_code;
    unsigned g92col, g64col, dropcol;
} gline_t;

/* G codes this reader carries out in LinuxCNC's dialect that Grbl 1.1 does not have. */
static bool grbl_lacks(int v)
{
    return v == 50 || v == 51 || v == 52 || v == 53 || v == 62 || v == 640 || v == 611 ||
           v == 901;
}

/* Codes that move (threading, probing, canned cycles...) or read the line's axis words for
 * another purpose (G4 dwell, G10, G28/G30 home, G52, G53, G92.2/3): when --lenient drops one, the
 * whole block goes with it; moving to its axis words as an ordinary move could plunge the tool. */
static bool moves_or_takes_axes(int v, bool *motion)
{
    *motion = v == 330 || v == 331 || (v >= 382 && v <= 385) || v == 730 || v == 740 ||
              v == 760 || (v >= 810 && v <= 890) || (v >= 50 && v <= 53) || v == 62;
    return *motion || v == 40 || v == 100 || v == 280 || v == 281 || v == 300 || v == 301 ||
           v == 520 || v == 530 || v == 922 || v == 923;
}

static cs_err_t set_motion(gc_t *g, gline_t *l, int v, unsigned c)
{
    if (l->motion != -2)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, c),
                                "two motion words on one line");
    l->motion = v;
    l->mcol = c;
    return CS_OK;
}

/* An unsupported G code: an error, or (lenient) dropped, with its block when it moves. */
static cs_err_t drop_g(gc_t *g, gline_t *l, int v, unsigned c)
{
    char what[48];
    code_name(what, sizeof what, 'G', v);
    if (g->o->dialect == CS_GCODE_GRBL && grbl_lacks(v))
        strcat(what, " (not in Grbl 1.1)");
    if (!g->o->lenient)
        return unsupported(g, c, what);
    bool motion;
    if (!moves_or_takes_axes(v, &motion)) {
        warn(g, c, "%s is not supported: ignored (--lenient)", what);
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
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, P->col),
                                "G64 P (path tolerance) must not be negative");
    double mm = P->v * g->unit;
    (void)col;
    if (mm > 0 && (g->path->blend_tol_mm == 0 || mm < g->path->blend_tol_mm))
        g->path->blend_tol_mm = mm;
    return CS_OK;
}

/* The modal G words of a line into the state, the motion word and the specials into *l. */
static cs_err_t run_g(gc_t *g, block_t *b, gline_t *l)
{
    cs_err_t e = CS_OK;
    for (unsigned i = 0; i < b->ng && e == CS_OK; i++) {
        int v = b->g[i];
        unsigned c = b->gcol[i];
        if (g->o->dialect == CS_GCODE_GRBL && grbl_lacks(v)) {
            e = drop_g(g, l, v, c);
            continue;
        }
        switch (v) {
        case 0: case 10: case 20: case 30: case 50: case 51: case 52: case 53: case 62:
            e = set_motion(g, l, v, c);
            break;
        case 800: e = set_motion(g, l, MOT_NONE, c); break;
        case 170: case 180: case 190: g->plane = v / 10; break;
        case 200: g->unit = MM_PER_INCH; break;
        case 210: g->unit = 1.0; break;
        case 900: g->incr = false; break;
        case 910: g->incr = true; break;
        case 901: g->ijk_abs = true; break;
        case 911: g->ijk_abs = false; break;
        case 920: l->g92 = true; l->g92col = c; break;
        case 921: memset(g->off, 0, sizeof g->off); break;
        case 640: l->g64 = true; l->g64col = c; break;
        case 610: /* exact path, */
        case 611: /* exact stop: curvestep never rounds a corner off, so the path is the same */
        case 940: /* feed in units per minute: the only feed mode */
        case 540: /* the first work coordinate system: the only one */
        case 400: /* cutter radius compensation off */
        case 490: /* tool length offset off */
            break;
        default:
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
    code_name(what, sizeof what, 'G', code);
    for (const char *q = "XYZIJKRPQL"; *q; q++) {
        word_t *w = &b->w[*q - 'A'];
        if (w->has && k < sizeof words - 24)
            k += (size_t)snprintf(words + k, sizeof words - k, " %c%g", *q, w->v);
        w->has = false;
    }
    if (modal)
        warn(g, col, "move in the unsupported motion mode %s skipped, with its words%s "
             "(--lenient)", what, words);
    else
        warn(g, col, "%s is not supported: its block skipped, with its words%s (--lenient)",
             what, k ? words : " (none)");
}

/* G92: the current position gets the coordinates of the axis words. */
static cs_err_t run_g92(gc_t *g, block_t *b, const gline_t *l)
{
    if (l->motion != -2)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, l->g92col),
                                "G92 and a motion word on one line");
    if (!any_axis(b)) {
        /* LinuxCNC refuses a bare G92; so do we unless lenient (RepRap's "G92 E0" is bare
         * once its E word was dropped as unsupported). */
        if (!g->o->lenient)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, l->g92col),
                                    "G92 needs axis words (the coordinates to give the "
                                    "current position)");
        warn(g, l->g92col, "G92 without X, Y or Z: ignored, offsets unchanged (--lenient)");
    }
    for (int a = 0; a < 3; a++) {
        const word_t *w = &b->w['X' - 'A' + a];
        if (w->has) {
            g->off[a] = g->pos[a] - w->v * g->unit;
            b->used |= BIT('X' + a);
        }
    }
    return CS_OK;
}

/* NURBS lines: G5.3, G5.2, G6.2 and the lines of an open block. *done when the line was one. */
static cs_err_t run_nurbs(gc_t *g, block_t *b, const gline_t *l, unsigned first_col, bool *done)
{
    cs_err_t e;
    *done = true;
    if (g->nurbs == MOT_G62 && !b->w['K' - 'A'].has && (e = nurbs_close(g)) != CS_OK)
        return e; /* a line without K ends a G6.2 block; the line then runs as usual */
    if (g->nurbs && l->motion != -2 && l->motion != MOT_G52 && l->motion != 53)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, l->mcol),
                                g->nurbs == MOT_G62
                                    ? "motion word inside a G6.2 block (it ends with its last "
                                      "K-only line)"
                                    : "motion word inside a G5.2 block (close it with G5.3 first)");
    if (l->motion == 53) {
        if (g->nurbs != MOT_G52)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, l->mcol),
                                    "G5.3 without an open G5.2 block");
        g->motion = MOT_NONE;
        g->g5_prev = false;
        return nurbs_close(g);
    }
    if (l->motion == MOT_G52 || l->motion == MOT_G62) {
        if (g->nurbs)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, l->mcol),
                                    "G%s inside an open NURBS block",
                                    l->motion == MOT_G52 ? "5.2" : "6.2");
        g->motion = l->motion;
        g->g5_prev = false;
        return l->motion == MOT_G52 ? do_nurbs_line(g, b, true, l->mcol)
                                    : do_g62_line(g, b, true, l->mcol);
    }
    if (g->nurbs)
        return g->nurbs == MOT_G52 ? do_nurbs_line(g, b, false, first_col)
                                   : do_g62_line(g, b, false, first_col);
    *done = false;
    return CS_OK;
}

/* The motion of a line (modal: the mode in effect when the line has none). */
static cs_err_t run_motion(gc_t *g, block_t *b, const gline_t *l, unsigned first_col)
{
    if (l->motion != -2)
        g->motion = l->motion;
    /* A move happens when the line has axis words or arc / spline words; a motion word alone
     * ("G2" on its own line) only sets the mode. */
    bool go = any_axis(b);
    for (const char *q = "IJKRPQ"; *q; q++)
        go = go || (b->w[*q - 'A'].has && !(b->used & BIT(*q))); /* G64's P and Q are its own */
    if (!go)
        return CS_OK;
    if (g->motion == MOT_NONE)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, first_col),
                                "axis words with no motion mode (G0, G1, G2...) in effect");
    if (g->motion == MOT_DROPPED) { /* only when lenient: the mode's moves are dropped too */
        drop_block(g, b, g->dropped_code, first_col, true);
        return CS_OK;
    }
    double t[3];
    cs_err_t e = CS_OK;
    switch (g->motion) {
    case MOT_G0:
    case MOT_G1:
        target_of(g, b, t);
        if ((e = add_line(g, g->pos, t, l->mcol, g->motion == MOT_G0)) == CS_OK)
            memcpy(g->pos, t, sizeof g->pos);
        g->g5_prev = false;
        break;
    case MOT_G2:
    case MOT_G3:
        e = do_arc(g, b, g->motion == MOT_G3, l->mcol);
        g->g5_prev = false;
        break;
    case MOT_G5:
    case MOT_G51:
        e = do_spline(g, b, g->motion == MOT_G51, l->mcol);
        g->g5_prev = g->motion == MOT_G5;
        break;
    default: /* G5.2 / G6.2 mode after its block: axis words alone start nothing */
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, first_col),
                                "axis words after a closed NURBS block: give G0, G1... first");
    }
    return e;
}

static cs_err_t run_block(gc_t *g, block_t *b, unsigned first_col)
{
    bool end = false, done;
    gline_t l = {-2, first_col, false, false, false, 0, 0, 0, 0};
    cs_err_t e = run_letters(g, b);
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
    if (!done && (e = l.g92 ? run_g92(g, b, &l) : run_motion(g, b, &l, first_col)) != CS_OK)
        return e;
    /* Words given but not used by anything on the line. */
    for (int i = 0; i < 26; i++) {
        if (!b->w[i].has || (b->used & (1u << i)))
            continue;
        if (!g->o->lenient)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, b->w[i].col),
                                    "%c word not used by anything on this line", 'A' + i);
        warn(g, b->w[i].col, "%c word not used by anything on this line: ignored (--lenient)",
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
        return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, loc_at(g, col_of(s, *i)),
                                "%s are LinuxCNC's: Grbl 1.1 has none (--dialect grbl)",
                                s[*i] == '#' ? "parameters (#)" : "expressions ([...])");
    cs_err_t e = grbl ? cs_gexpr_number(s, n, i, v, &f) : cs_gexpr_real(&g->st, s, n, i, v, &f);
    if (e == CS_OK)
        return CS_OK;
    if (f.at == start && strcmp(f.reason, "expected a number") == 0)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col),
                                "%c must be followed by a number", letter);
    return cs_path_diag_set(g->diag, e, loc_at(g, col_of(s, f.at)), "%s", f.reason);
}

/* "#... = value" at s[*i]: read now, set at the end of the line (cs_gexpr_commit). */
static cs_err_t read_assign(gc_t *g, const char *s, size_t n, size_t *i)
{
    cs_gexpr_fail_t f;
    if (g->o->dialect == CS_GCODE_GRBL)
        return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, loc_at(g, col_of(s, *i)),
                                "parameters (#) are LinuxCNC's: Grbl 1.1 has none "
                                "(--dialect grbl)");
    cs_err_t e = cs_gexpr_assign(&g->st, s, n, i, &f);
    if (e != CS_OK)
        return cs_path_diag_set(g->diag, e, loc_at(g, col_of(s, f.at)), "%s", f.reason);
    return CS_OK;
}

/* One line s[0..n) (without its end of line). */
static cs_err_t do_line(gc_t *g, const char *s, size_t n)
{
    /* Comments out, checksum found: pass 1. */
    size_t star = n, code_end = n, depth = 0;
    for (size_t i = 0; i < n; i++) {
        char c = s[i];
        if (c == '(') {
            size_t j = i + 1;
            while (j < n && s[j] != ')')
                j++;
            if (j == n)
                return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col_of(s, i)),
                                        "comment not closed on its line (missing ')')");
            i = j;
        } else if (c == ';') {
            code_end = i;
            break;
        } else if (c == '[') {
            depth++;
        } else if (c == ']') {
            depth -= depth > 0;
        } else if (c == '*' && star == n && depth == 0) {
            /* Inside [...] '*' multiplies (LinuxCNC); outside it starts a checksum. */
            star = i;
        } else if (c == '\0') {
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col_of(s, i)),
                                    "NUL byte in the input");
        }
    }
    if (star < n) {
        /* RepRap checksum: XOR of every byte before '*', written in decimal after it. */
        unsigned x = 0;
        for (size_t i = 0; i < star; i++)
            x ^= (unsigned char)s[i];
        size_t j = star + 1;
        unsigned v = 0, nd = 0;
        while (j < code_end && s[j] >= '0' && s[j] <= '9' && nd < 4)
            v = v * 10 + (unsigned)(s[j++] - '0'), nd++;
        size_t k = j;
        while (k < code_end && (s[k] == ' ' || s[k] == '\t'))
            k++;
        while (k < code_end && s[k] == '(') {
            while (k < code_end && s[k] != ')')
                k++;
            k++;
            while (k < code_end && (s[k] == ' ' || s[k] == '\t'))
                k++;
        }
        if (nd == 0 || nd > 3 || v > 255 || k < code_end)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col_of(s, star)),
                                    "'*' must end the line with a checksum from 0 to 255");
        if (v != x)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col_of(s, star)),
                                    "checksum *%u does not match the line (the XOR of the "
                                    "bytes before '*' is %u)",
                                    v, x);
        code_end = star;
    }
    /* Pass 2: words. */
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
    bool any = false;
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
        unsigned col = col_of(s, i);
        if (c == '#') {
            cs_err_t e = read_assign(g, s, code_end, &i);
            if (e != CS_OK)
                return e;
            continue;
        }
        if (c == '[')
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col),
                                    "an expression [...] must be the value of a word (X[...])");
        if (c == 'o' || c == 'O')
            return cs_path_diag_set(g->diag, g->o->dialect == CS_GCODE_GRBL ? CS_ERR_UNSUPPORTED
                                                                            : CS_ERR_PARSE,
                                    loc_at(g, col),
                                    g->o->dialect == CS_GCODE_GRBL
                                        ? "O-words are LinuxCNC's: Grbl 1.1 has none "
                                          "(--dialect grbl)"
                                        : "an O-word must begin its line (only a line number "
                                          "may come before it)");
        int li = letter_index(c);
        if (li < 0) {
            if ((unsigned char)c < 0x20 || (unsigned char)c >= 0x7F)
                return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col),
                                        "unexpected byte 0x%02X", (unsigned)(unsigned char)c);
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col),
                                    "unexpected character '%c' (expected a word: a letter and a "
                                    "number)",
                                    c);
        }
        i++;
        while (i < code_end && (s[i] == ' ' || s[i] == '\t'))
            i++;
        double v;
        cs_err_t ev = read_value(g, s, code_end, &i, (char)('A' + li), col, &v);
        if (ev != CS_OK)
            return ev;
        if (!any)
            first_col = col;
        any = true;
        char L = (char)('A' + li);
        if (L == 'G' || L == 'M') {
            double t = v * 10.0;
            if (v < 0 || v > 1000 || fabs(t - nearbyint(t)) > 1e-6)
                return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col),
                                        "%c%g is not a %c code", L, v, L);
            int code = (int)nearbyint(t);
            if (L == 'G') {
                if (b.ng == sizeof b.g / sizeof b.g[0])
                    return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col),
                                            "too many G words on one line");
                for (unsigned k = 0; k < b.ng; k++)
                    if (b.g[k] == code)
                        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col),
                                                "G%g given twice on one line", v);
                b.gcol[b.ng] = col;
                b.g[b.ng++] = code;
            } else {
                if (b.nm == sizeof b.m / sizeof b.m[0])
                    return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col),
                                            "too many M words on one line");
                b.mcol[b.nm] = col;
                b.m[b.nm++] = code;
            }
            continue;
        }
        if (b.w[li].has)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col),
                                    "%c given twice on one line", L);
        if (!isfinite(v) || fabs(v) > 1e9)
            return cs_path_diag_set(g->diag, CS_ERR_RANGE, loc_at(g, col), "%c value out of range",
                                    L);
        b.w[li].has = true;
        b.w[li].v = v;
        b.w[li].col = col;
    }
    if (!any)
        return CS_OK;
    return run_block(g, &b, first_col);
}

void cs_gcode_opts_init(cs_gcode_opts_t *o)
{
    memset(o, 0, sizeof *o);
    o->helix_tol_mm = CS_GCODE_HELIX_TOL_MM;
}

/* Runs the program line by line in the order its O-words decide (cs_gflow). */
static cs_err_t run_program(gc_t *g, cs_gflow_t *fl, const char *buf)
{
    cs_err_t e = CS_OK;
    size_t k = 0;
    while (k < fl->n && !g->ended && e == CS_OK) {
        size_t next = k + 1;
        g->line = (unsigned)(k + 1);
        if (g->stats)
            g->stats->lines++;
        if (fl->lines[k].kind != CS_GFLOW_NONE) {
            e = cs_gflow_exec(fl, g->name, buf, k, &g->st, &next, g->diag);
        } else if ((e = do_line(g, buf + fl->lines[k].start, fl->lines[k].len)) == CS_OK &&
                   cs_gexpr_commit(&g->st) != CS_OK) {
            e = cs_path_diag_set(g->diag, CS_ERR_FULL, loc_at(g, 1), "out of memory");
        }
        k = next;
    }
    if (e == CS_OK && g->nurbs == MOT_G62)
        e = nurbs_close(g); /* a G6.2 block at the end of the program */
    if (e == CS_OK && g->nurbs)
        e = cs_path_diag_set(g->diag, CS_ERR_PARSE, g->nurbs_loc,
                             "G5.2 block not closed by G5.3 before the end of the program");
    return e;
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
    memset(&g, 0, sizeof g);
    cs_path_loc_t l0 = {"<input>", 0, 0};
    g.name = cs_path_intern(path, name ? name : "<input>");
    if (!g.name)
        return cs_path_diag_set(diag, CS_ERR_FULL, l0, "out of memory");
    l0.file = g.name;
    if (!(o->helix_tol_mm > 0) || o->helix_tol_mm > CS_POS_LIMIT_MM)
        return cs_path_diag_set(diag, CS_ERR_TOLERANCE, l0, "helix tolerance %g mm not accepted",
                                o->helix_tol_mm);
    g.o = o;
    g.path = path;
    g.diag = diag;
    g.stats = stats;
    if (stats)
        memset(stats, 0, sizeof *stats);
    g.unit = o->start_inch ? MM_PER_INCH : 1.0;
    g.plane = 17;
    /* Grbl 1.1's defaults at power-up include G0 (its "$G" report: G0 G54 G17 G21 G90 G94). */
    g.motion = o->dialect == CS_GCODE_GRBL ? MOT_G0 : MOT_NONE;
    cs_path_new_subpath(path);
    if (cs_gexpr_init(&g.st) != CS_OK)
        return cs_path_diag_set(diag, CS_ERR_FULL, l0, "out of memory");
    cs_gflow_t fl;
    cs_err_t e = cs_gflow_init(&fl, g.name, buf, len, o->dialect != CS_GCODE_GRBL, o->max_loops,
                               diag);
    if (e == CS_OK)
        e = run_program(&g, &fl, buf);
    cs_gflow_free(&fl);
    cs_gexpr_free(&g.st);
    cs_gnurbs_free(&g.nb);
    return e;
}
