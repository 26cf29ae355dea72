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
#include "cs_nurbs.h"

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
#define RADIUS_TOL_INCH 0.00005
/* Largest sweep of one arc piece: under 90 degrees, so cs_arc_gcode returns exactly one piece. */
#define ARC_PIECE_MAX (0.999 * GC_PI / 2.0)
/* Most pieces one G2/G3 may become (a helix of many turns at a fine tolerance). */
#define ARC_MAX_PIECES 100000u
/* Most control points in one G5.2 block (the knots 0..n-k+2 must fit cs_nurbs_knot_t). */
#define NURBS_MAX_POINTS 10000u
#define NURBS_MAX_ORDER  (CS_NURBS_MAX_DEGREE + 1)
#define NUM_MAX_CHARS    64

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
    MOT_G52 = 52
};

typedef struct {
    bool has;
    double v;
    unsigned col;
} word_t;

typedef struct {
    double x, y, w;
} nurbs_cp_t;

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
    double feed;   /* F in program units per minute; 0 = none given */
    bool g5_prev;  /* the last move was a G5: its P, Q continue */
    double g5_pq[2];
    bool last_rapid;
    bool ended; /* M2 / M30 */
    /* open G5.2 block */
    nurbs_cp_t *cps;
    size_t ncps, capcps;
    unsigned nurbs_order;
    cs_path_loc_t nurbs_loc;
    double nurbs_feed;
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
    char msg[sizeof w.reason];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    cs_path_diag_set(&w, CS_OK, loc_at(g, col), "%s", msg);
    if (g->stats)
        g->stats->warnings++;
    if (g->o->warn)
        g->o->warn(g->o->warn_ctx, &w);
    else
        cs_path_warn_print(stderr, &w);
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
    double tol = arc_tol(g), rtol = radius_tol();
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
        double ae = fabs(r0 - r1), rel = ae / fmax(r0, r1);
        if (ae > tol || rel > ARC_REL_TOL)
            return cs_path_diag_set(g->diag, CS_ERR_DEGENERATE, loc_at(g, col),
                                    "radius to end of arc (%.4f mm) differs from radius to "
                                    "start (%.4f mm) by %.4f mm (%.3f%%); at most %.4f mm and "
                                    "0.1%% are accepted",
                                    r1, r0, ae, 100 * rel, tol);
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

/* G5.3: the open G5.2 block becomes Bézier segments (cs_nurbs), LinuxCNC's uniform clamped knot
 * vector of order k over n+1 points: k zeros, 1 .. n-k+1, k times n-k+2. */
static cs_err_t nurbs_close(gc_t *g)
{
    unsigned k = g->nurbs_order;
    size_t cnt = g->ncps;
    cs_path_loc_t loc = g->nurbs_loc;
    if (cnt < k)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc,
                                "G5.2 block of order %u needs at least %u control points "
                                "(has %zu)",
                                k, k, cnt);
    size_t n = cnt - 1;
    cs_vec3_t *pts = malloc(cnt * sizeof *pts);
    int32_t *w = malloc(cnt * sizeof *w);
    cs_nurbs_knot_t *kn = malloc((cnt + k) * sizeof *kn);
    cs_err_t e = CS_OK;
    if (!pts || !w || !kn) {
        e = cs_path_diag_set(g->diag, CS_ERR_FULL, loc, "out of memory");
        goto out;
    }
    double wmax = 0;
    for (size_t i = 0; i < cnt; i++)
        wmax = fmax(wmax, g->cps[i].w);
    for (size_t i = 0; i < cnt; i++) {
        double p[3] = {g->cps[i].x, g->cps[i].y, g->pos[2]};
        if ((e = to_vec(g, p, loc.col, &pts[i])) != CS_OK)
            goto out;
        double wq = nearbyint(g->cps[i].w / wmax * (double)CS_PARAM_ONE);
        if (!(wq >= 1)) {
            e = cs_path_diag_set(g->diag, CS_ERR_WEIGHT, loc,
                                 "weight P%g is too small next to the largest weight P%g",
                                 g->cps[i].w, wmax);
            goto out;
        }
        w[i] = (int32_t)wq;
    }
    for (size_t i = 0; i <= n + k; i++) {
        size_t v = i < k ? 0 : i <= n ? i - k + 1 : n - k + 2;
        kn[i] = (cs_nurbs_knot_t)v * CS_NURBS_KNOT_ONE;
    }
    cs_nurbs_t nc;
    e = cs_nurbs_init(&nc, k - 1, pts, w, cnt, kn, cnt + k);
    if (e != CS_OK) {
        e = cs_path_diag_set(g->diag, e, loc, "bad G5.2 block: %s", cs_err_text(e));
        goto out;
    }
    cs_nurbs_iter_t it;
    cs_nurbs_iter_begin(&nc, &it);
    cs_bezier_t seg;
    cs_vec3_t prev = pts[0];
    double save_feed = g->feed;
    g->feed = g->nurbs_feed;
    size_t nseg = cs_nurbs_segments(&nc), iseg = 0;
    while ((e = cs_nurbs_next(&nc, &it, &seg, NULL, NULL)) == CS_OK) {
        /* Consecutive segments share their end point to within 1 LSB: snap them together (and
         * the block's ends onto its first and last control points, where a clamped curve ends). */
        seg.p[0] = prev;
        if (++iseg == nseg)
            seg.p[seg.degree] = pts[cnt - 1];
        prev = seg.p[seg.degree];
        cs_err_t ea = add(g, &seg, CS_PATH_OTHER, loc.col, false);
        if (ea != CS_OK) {
            g->feed = save_feed;
            e = ea;
            goto out;
        }
    }
    g->feed = save_feed;
    if (e != CS_END) {
        e = cs_path_diag_set(g->diag, e, loc, "cannot convert this G5.2 block: %s", cs_err_text(e));
        goto out;
    }
    e = CS_OK;
    g->pos[0] = g->cps[cnt - 1].x;
    g->pos[1] = g->cps[cnt - 1].y;
out:
    free(pts);
    free(w);
    free(kn);
    g->ncps = 0;
    return e;
}

static cs_err_t nurbs_push(gc_t *g, double x, double y, double w)
{
    if (g->ncps >= NURBS_MAX_POINTS)
        return cs_path_diag_set(g->diag, CS_ERR_FULL, g->nurbs_loc,
                                "G5.2 block with more than %u control points", NURBS_MAX_POINTS);
    if (g->ncps == g->capcps) {
        size_t nc = g->capcps ? 2 * g->capcps : 16;
        nurbs_cp_t *p = realloc(g->cps, nc * sizeof *p);
        if (!p)
            return cs_path_diag_set(g->diag, CS_ERR_FULL, g->nurbs_loc, "out of memory");
        g->cps = p;
        g->capcps = nc;
    }
    g->cps[g->ncps].x = x;
    g->cps[g->ncps].y = y;
    g->cps[g->ncps].w = w;
    g->ncps++;
    return CS_OK;
}

/* A G5.2 line (first = the line that carries G5.2) or a control point line inside the block. */
static cs_err_t do_nurbs_line(gc_t *g, block_t *b, bool first, unsigned col)
{
    const word_t *X = &b->w['X' - 'A'], *Y = &b->w['Y' - 'A'], *P = &b->w['P' - 'A'];
    const word_t *L = &b->w['L' - 'A'];
    if (first) {
        if (g->plane != 17)
            return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, loc_at(g, col),
                                    "G5.2 works in the G17 (XY) plane only");
        if (g->incr)
            return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, loc_at(g, col),
                                    "G5.2 control points in G91 (incremental) mode are not "
                                    "supported");
        g->nurbs_loc = loc_at(g, col);
        g->nurbs_order = 3;
        g->nurbs_feed = g->feed;
        g->ncps = 0;
        double w0 = (!X->has && !Y->has && P->has) ? P->v : 1.0;
        if (!(w0 > 0))
            return cs_path_diag_set(g->diag, CS_ERR_WEIGHT, loc_at(g, P->col),
                                    "G5.2 weight P must be positive");
        cs_err_t e = nurbs_push(g, g->pos[0], g->pos[1], w0);
        if (e != CS_OK)
            return e;
    }
    if (L->has) {
        b->used |= BIT('L');
        if (!first)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, L->col),
                                    "L (order) belongs on the G5.2 line");
        if (L->v != floor(L->v))
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, L->col),
                                    "L (order) must be a whole number");
        /* LinuxCNC takes L only when it is above 3 (the default order). */
        if (L->v > NURBS_MAX_ORDER)
            return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, loc_at(g, L->col),
                                    "NURBS order L%g: at most %d (cubic) is supported", L->v,
                                    NURBS_MAX_ORDER);
        if (L->v > 3)
            g->nurbs_order = (unsigned)L->v;
    }
    if (b->w['Z' - 'A'].has)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, b->w['Z' - 'A'].col),
                                "G5.2 control points are in X and Y only (no Z word)");
    if (X->has != Y->has)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, (X->has ? X : Y)->col),
                                "a G5.2 control point needs both X and Y");
    if (P->has)
        b->used |= BIT('P');
    if (!X->has)
        return CS_OK;
    if (!P->has || !(P->v > 0))
        return cs_path_diag_set(g->diag, CS_ERR_WEIGHT, loc_at(g, P->has ? P->col : X->col),
                                "each G5.2 control point needs a positive weight P");
    double t[3];
    target_of(g, b, t);
    return nurbs_push(g, t[0], t[1], P->v);
}

/* ---- one block --------------------------------------------------------------------------- */

static cs_err_t run_block(gc_t *g, block_t *b, unsigned first_col)
{
    cs_err_t e;
    /* Unsupported letters first (each once). */
    static const char supported[] = "FGIJKLMNPQRSXYZ";
    for (int i = 0; i < 26; i++) {
        if (!b->w[i].has || strchr(supported, 'A' + i))
            continue;
        char what[48];
        snprintf(what, sizeof what, "the %c word", 'A' + i);
        if (i == 'T' - 'A' && g->o->lenient) {
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
    /* M words (pen / spindle before the motion, program end after it). */
    bool end = false;
    for (unsigned i = 0; i < b->nm; i++) {
        int m = b->m[i];
        if (m == 20 || m == 300) {
            end = true;
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
        } else {
            char what[32];
            if (m % 10)
                snprintf(what, sizeof what, "M%d.%d", m / 10, m % 10);
            else
                snprintf(what, sizeof what, "M%d", m / 10);
            if ((e = unsupported(g, b->mcol[i], what)) != CS_OK)
                return e;
        }
    }
    /* Modal G words, then the motion. */
    int motion = -2; /* none on this line */
    unsigned mcol = first_col;
    bool g92 = false, drop_words = false;
    unsigned g92col = 0;
    for (unsigned i = 0; i < b->ng; i++) {
        int v = b->g[i];
        unsigned c = b->gcol[i];
        switch (v) {
        case 0:
        case 10:
        case 20:
        case 30:
        case 50:
        case 51:
        case 52:
        case 53:
        case 800:
            if (motion != -2)
                return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, c),
                                        "two motion words on one line");
            motion = v == 800 ? MOT_NONE : v;
            mcol = c;
            break;
        case 170:
        case 180:
        case 190:
            g->plane = v / 10;
            break;
        case 200:
            g->unit = MM_PER_INCH;
            break;
        case 210:
            g->unit = 1.0;
            break;
        case 900:
            g->incr = false;
            break;
        case 910:
            g->incr = true;
            break;
        case 901:
            g->ijk_abs = true;
            break;
        case 911:
            g->ijk_abs = false;
            break;
        case 920:
            g92 = true;
            g92col = c;
            break;
        case 921:
            memset(g->off, 0, sizeof g->off);
            break;
        case 940: /* feed in units per minute: the only feed mode */
        case 540: /* the first work coordinate system: the only one */
        case 400: /* cutter radius compensation off */
        case 490: /* tool length offset off */
            break;
        default: {
            char what[32];
            if (v % 10)
                snprintf(what, sizeof what, "G%d.%d", v / 10, v % 10);
            else
                snprintf(what, sizeof what, "G%d", v / 10);
            if ((e = unsupported(g, c, what)) != CS_OK)
                return e;
            /* Lenient: a dropped code that moves (threading, probing, canned cycles) takes its
             * motion mode with it, and one that reads the line's axis words for another purpose
             * (G4 dwell, G10, G28/G30 home, G52, G53 machine coordinates, G92.2/3) takes the
             * words: moving to them as if they were an ordinary move could plunge the tool. */
            if (v == 330 || v == 331 || (v >= 382 && v <= 385) || v == 730 || v == 740 ||
                v == 760 || (v >= 810 && v <= 890)) {
                if (motion != -2)
                    return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, c),
                                            "two motion words on one line");
                motion = MOT_DROPPED;
                mcol = c;
                drop_words = true;
            } else if (v == 40 || v == 100 || v == 280 || v == 281 || v == 300 || v == 301 ||
                       v == 520 || v == 530 || v == 922 || v == 923) {
                drop_words = true;
            }
        }
        }
    }
    if (drop_words) {
        bool any = false;
        for (const char *q = "XYZIJKRPQL"; *q; q++) {
            any = any || b->w[*q - 'A'].has;
            b->w[*q - 'A'].has = false;
        }
        if (any)
            warn(g, first_col,
                 "the line's axis and arc words go with the unsupported code: "
                 "ignored (--lenient)");
    }
    if (g->ncps > 0 && motion != -2 && motion != MOT_G52 && motion != 53)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, mcol),
                                "motion word inside a G5.2 block (close it with G5.3 first)");
    if (g92) {
        if (motion != -2)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, g92col),
                                    "G92 and a motion word on one line");
        if (!any_axis(b)) {
            /* LinuxCNC refuses a bare G92; so do we unless lenient (RepRap's "G92 E0" is bare
             * once its E word was dropped as unsupported). */
            if (!g->o->lenient)
                return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, g92col),
                                        "G92 needs axis words (the coordinates to give the "
                                        "current position)");
            warn(g, g92col, "G92 without X, Y or Z: ignored, offsets unchanged (--lenient)");
        }
        for (int a = 0; a < 3; a++) {
            const word_t *w = &b->w['X' - 'A' + a];
            if (w->has) {
                g->off[a] = g->pos[a] - w->v * g->unit;
                b->used |= BIT('X' + a);
            }
        }
    } else if (motion == 53) {
        /* G5.3 ends the open G5.2 block. */
        if (g->ncps == 0)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, mcol),
                                    "G5.3 without an open G5.2 block");
        g->motion = MOT_NONE;
        if ((e = nurbs_close(g)) != CS_OK)
            return e;
        g->g5_prev = false;
    } else if (motion == MOT_G52) {
        if (g->ncps > 0)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, mcol),
                                    "G5.2 inside an open G5.2 block");
        g->motion = MOT_G52;
        if ((e = do_nurbs_line(g, b, true, mcol)) != CS_OK)
            return e;
    } else if (g->ncps > 0) {
        if ((e = do_nurbs_line(g, b, false, first_col)) != CS_OK)
            return e;
    } else {
        if (motion != -2)
            g->motion = motion;
        /* A move happens when the line has axis words or arc / spline words; a motion word
         * alone ("G2" on its own line) only sets the mode. */
        bool go = any_axis(b);
        for (const char *q = "IJKRPQ"; *q; q++)
            go = go || b->w[*q - 'A'].has;
        if (go && g->motion == MOT_NONE)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, first_col),
                                    "axis words with no motion mode (G0, G1, G2...) in effect");
        if (go && g->motion == MOT_DROPPED) {
            /* Only reached when lenient: the mode was dropped, so are its moves. */
            warn(g, first_col,
                 "move in an unsupported motion mode (a canned cycle...): ignored (--lenient)");
            for (const char *q = "XYZIJKRPQL"; *q; q++)
                b->w[*q - 'A'].has = false;
            go = false;
        }
        if (go && g->motion != MOT_NONE) {
            double t[3];
            switch (g->motion) {
            case MOT_G0:
            case MOT_G1:
                target_of(g, b, t);
                e = add_line(g, g->pos, t, mcol, g->motion == MOT_G0);
                if (e != CS_OK)
                    return e;
                memcpy(g->pos, t, sizeof g->pos);
                g->g5_prev = false;
                break;
            case MOT_G2:
            case MOT_G3:
                if ((e = do_arc(g, b, g->motion == MOT_G3, mcol)) != CS_OK)
                    return e;
                g->g5_prev = false;
                break;
            case MOT_G5:
            case MOT_G51:
                if ((e = do_spline(g, b, g->motion == MOT_G51, mcol)) != CS_OK)
                    return e;
                g->g5_prev = g->motion == MOT_G5;
                break;
            default:
                break;
            }
        }
    }
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

/* Number at s[*i] (line s[0..n)): [+-] digits [. digits]; spaces are not allowed inside. */
static bool read_number(const char *s, size_t n, size_t *i, double *out)
{
    char tmp[NUM_MAX_CHARS];
    size_t k = 0, j = *i;
    bool digits = false;
    if (j < n && (s[j] == '+' || s[j] == '-'))
        tmp[k++] = s[j++];
    while (j < n && s[j] >= '0' && s[j] <= '9' && k < NUM_MAX_CHARS - 2) {
        tmp[k++] = s[j++];
        digits = true;
    }
    if (j < n && s[j] == '.' && k < NUM_MAX_CHARS - 2) {
        tmp[k++] = s[j++];
        while (j < n && s[j] >= '0' && s[j] <= '9' && k < NUM_MAX_CHARS - 1) {
            tmp[k++] = s[j++];
            digits = true;
        }
    }
    if (!digits || (j < n && s[j] >= '0' && s[j] <= '9'))
        return false;
    tmp[k] = '\0';
    *out = strtod(tmp, NULL);
    *i = j;
    return true;
}

/* One line s[0..n) (without its end of line). */
static cs_err_t do_line(gc_t *g, const char *s, size_t n)
{
    /* Comments out, checksum found: pass 1. */
    size_t star = n, code_end = n;
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
        } else if (c == '*' && star == n) {
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
        if (c == '#' || c == '[' || c == 'o' || c == 'O')
            return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, loc_at(g, col),
                                    "%s are not supported",
                                    c == '#'   ? "parameters (#)"
                                    : c == '[' ? "expressions ([...])"
                                               : "O-word subroutines and control flow");
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
        if (i < code_end && (s[i] == '#' || s[i] == '['))
            return cs_path_diag_set(g->diag, CS_ERR_UNSUPPORTED, loc_at(g, col_of(s, i)),
                                    "%s are not supported",
                                    s[i] == '#' ? "parameters (#)" : "expressions ([...])");
        if (!read_number(s, code_end, &i, &v))
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, loc_at(g, col),
                                    "%c must be followed by a number", 'A' + li);
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
    g.unit = 1.0;
    g.plane = 17;
    g.motion = MOT_NONE;
    cs_path_new_subpath(path);
    cs_err_t e = CS_OK;
    size_t i = 0;
    while (i < len && !g.ended) {
        size_t j = i;
        while (j < len && buf[j] != '\n' && buf[j] != '\r')
            j++;
        g.line++;
        if (stats)
            stats->lines++;
        if ((e = do_line(&g, buf + i, j - i)) != CS_OK)
            break;
        if (j < len && buf[j] == '\r' && j + 1 < len && buf[j + 1] == '\n')
            j++;
        i = j + 1;
    }
    if (e == CS_OK && g.ncps > 0)
        e = cs_path_diag_set(diag, CS_ERR_PARSE, g.nurbs_loc,
                             "G5.2 block not closed by G5.3 before the end of the program");
    free(g.cps);
    return e;
}
