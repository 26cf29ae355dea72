/* cs_gcode_arc: G2/G3 arcs and helices of the G-code reader (see cs_gcode_int.h; the checks
 * and pieces are described in docs/inputs.md, "Arcs"). */
#include <math.h>
#include <string.h>

#include "cs_arc.h"
#include "cs_conv.h"
#include "cs_err_text.h"
#include "cs_gcode_int.h"

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
#define GRBL_ARC_TOL_MM  0.005
#define GRBL_ARC_HARD_MM 0.5
/* Largest sweep of one arc piece: under 90 degrees, so cs_arc_gcode returns exactly one piece. */
#define ARC_PIECE_MAX (0.999 * GC_PI / 2.0)
/* Most pieces one G2/G3 may become (a helix of many turns at a fine tolerance). */
#define ARC_MAX_PIECES 100000u

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
/* How many pieces an arc of |sweep| asw climbing dz with radius r0 -> r1 becomes. */
static cs_err_t arc_pieces(gc_t *g, double asw, double dz, double r0, double r1, unsigned col,
                           unsigned *pn)
{
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
                return cs_path_diag_set(g->diag, CS_ERR_RANGE, cs_gcode_loc(g, col),
                                        "helix needs more than %u pieces for a tolerance of "
                                        "%g mm",
                                        ARC_MAX_PIECES, g->o->helix_tol_mm);
            n = n * 2 > ARC_MAX_PIECES ? ARC_MAX_PIECES : n * 2;
        }
    }
    *pn = n;
    return CS_OK;
}

static cs_err_t emit_arc(gc_t *g, const double c[3], const double t[3], double sweep, double r0,
                         double r1, unsigned col)
{
    int ax[3];
    cs_gcode_plane_axes(g->plane, ax);
    const double *s = g->pos;
    double th0 = atan2(s[ax[1]] - c[ax[1]], s[ax[0]] - c[ax[0]]);
    double dz = t[ax[2]] - s[ax[2]];
    unsigned n = 1;
    cs_err_t e0 = arc_pieces(g, fabs(sweep), dz, r0, r1, col, &n);
    if (e0 != CS_OK)
        return e0;
    bool ccw = sweep > 0;
    cs_vec3_t cc, ps, pe;
    double cz[3] = {c[0], c[1], c[2]};
    cz[ax[2]] = s[ax[2]];
    cs_err_t e = cs_gcode_to_vec(g, cz, col, &cc);
    if (e != CS_OK)
        return cs_path_diag_set(g->diag, CS_ERR_RANGE, cs_gcode_loc(g, col),
                                "arc centre (%.4f, %.4f, %.4f) mm is outside +/-%d mm", c[0], c[1],
                                c[2], CS_POS_LIMIT_MM);
    if ((e = cs_gcode_to_vec(g, s, col, &ps)) != CS_OK ||
        (e = cs_gcode_to_vec(g, t, col, &pe)) != CS_OK)
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
            if ((e = cs_gcode_to_vec(g, q, col, &b)) != CS_OK)
                return e;
        }
        cs_pos_t an = *cs_gcode_coord(&a, ax[2]), bn = *cs_gcode_coord(&b, ax[2]);
        cs_vec3_t bflat = b, cflat = cc;
        *cs_gcode_coord(&bflat, ax[2]) = an;
        *cs_gcode_coord(&cflat, ax[2]) = an;
        /* In LSB: the piece's chord c and radius r. When c^2 <= 4 r the arc's sagitta
         * c^2 / (8 r) is at most half an LSB, so a line is as close to the circle as rounding
         * allows; and below that the two end directions may round to the same Q1.30 pair, which
         * cs_arc_gcode would read as a full turn. */
        double ch0 = (double)*cs_gcode_coord(&bflat, ax[0]) - *cs_gcode_coord(&a, ax[0]);
        double ch1 = (double)*cs_gcode_coord(&bflat, ax[1]) - *cs_gcode_coord(&a, ax[1]);
        double ra0 = (double)*cs_gcode_coord(&a, ax[0]) - *cs_gcode_coord(&cflat, ax[0]);
        double ra1 = (double)*cs_gcode_coord(&a, ax[1]) - *cs_gcode_coord(&cflat, ax[1]);
        if (ch0 * ch0 + ch1 * ch1 <= 4.0 * sqrt(ra0 * ra0 + ra1 * ra1) ||
            cs_gcode_vec_eq(&bflat, &cflat)) {
            if (!cs_gcode_vec_eq(&a, &b)) {
                cs_vec3_t p[2] = {a, b};
                cs_bezier_t l;
                cs_bezier_init(&l, 1, p);
                if ((e = cs_gcode_add(g, &l, CS_PATH_LINE, col, false)) != CS_OK)
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
            return cs_path_diag_set(g->diag, e == CS_OK ? CS_ERR_STATE : e, cs_gcode_loc(g, col),
                                    "cannot build this arc: %s",
                                    e == CS_OK ? "piece split unexpectedly" : cs_err_text(e));
        for (unsigned j = 0; j < m; j++) {
            cs_bezier_t *pc = &out[j];
            /* The third axis: linear in angle (the builder's pieces are equal halves), control
             * values z0, (z0+z1)/2, z1 on each (helix_piece_err). */
            int64_t z0 = an + ((int64_t)bn - an) * j / m;
            int64_t z1 = an + ((int64_t)bn - an) * (j + 1) / m;
            *cs_gcode_coord(&pc->p[0], ax[2]) = (cs_pos_t)z0;
            *cs_gcode_coord(&pc->p[1], ax[2]) = (cs_pos_t)((z0 + z1) / 2);
            *cs_gcode_coord(&pc->p[2], ax[2]) = (cs_pos_t)z1;
            /* Snap the outer ends onto the shared points (they differ by at most 2 LSB plus the
             * spiral's radius change over this piece): moving an end control point by d moves
             * the curve by at most d, and consecutive elements then meet exactly (the builder's
             * own pieces already share their ends). */
            if (j == 0)
                pc->p[0] = a;
            if (j + 1 == m)
                pc->p[2] = b;
            if ((e = cs_gcode_add(g, pc, CS_PATH_ARC, col, false)) != CS_OK)
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
        return cs_path_diag_set(g->diag, CS_ERR_DEGENERATE, cs_gcode_loc(g, col),
                                "radius to end of arc (%.4f mm) differs from radius to start "
                                "(%.4f mm) by %.4f mm (%.3f%%); %s accepts up to %.4f mm, or up "
                                "to %.4f mm within 0.1%%%s",
                                r1, r0, ae, 100 * rel, grbl ? "Grbl" : "LinuxCNC", tol, hard,
                                grbl ? " (Grbl: error:33)" : "");
    return CS_OK;
}
/* The R form's centre c (and the radii r0, r1 it gives) from g->pos to t. *done when --lenient
 * settled the arc another way (an R arc ending on its start). */
static cs_err_t arc_centre_r(gc_t *g, block_t *b, bool ccw, const double t[3], unsigned col,
                             double c[3], double *r0, double *r1, bool *done)
{
    int ax[3];
    cs_gcode_plane_axes(g->plane, ax);
    const char *names = g->plane == 17 ? "I/J" : g->plane == 18 ? "I/K" : "J/K";
    const word_t *r = &b->w['R' - 'A'];
    double rtol = radius_tol();
    const double *s = g->pos;
    double s0 = s[ax[0]], s1 = s[ax[1]], e0 = t[ax[0]], e1 = t[ax[1]];
    b->used |= BIT('R');
    double R = r->v * g->unit, aR = fabs(R);
    if (s0 == e0 && s1 == e1) {
        if (!g->o->lenient)
            return cs_path_diag_set(g->diag, CS_ERR_DEGENERATE, cs_gcode_loc(g, r->col),
                                    "R-form arc ends where it starts: its centre is "
                                    "undefined (a full circle needs %s)",
                                    names);
        /* Lenient: no circle can be chosen (any centre at distance |R| fits), so nothing
         * is drawn in the plane; a move along the plane's normal is still made, straight
         * (the limit of a helix of no radius), so the position stays the programmed one. */
        cs_gcode_warn(g, r->col,
                      "R-form arc ends where it starts (centre undefined): nothing drawn in the "
                      "plane (--lenient)");
        cs_err_t el = cs_gcode_add_line(g, g->pos, t, col, false);
        if (el == CS_OK)
            memcpy(g->pos, t, sizeof g->pos);
        *done = true;
        return el;
    }
    if (aR < rtol)
        return cs_path_diag_set(g->diag, CS_ERR_DEGENERATE, cs_gcode_loc(g, r->col),
                                "zero-radius arc (R %g)", r->v);
    double m0 = (s0 + e0) / 2, m1 = (s1 + e1) / 2;
    double half = hypot(e0 - m0, e1 - m1);
    if (half - aR > rtol)
        return cs_path_diag_set(g->diag, CS_ERR_DEGENERATE, cs_gcode_loc(g, r->col),
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
    *r0 = hypot(s0 - c[ax[0]], s1 - c[ax[1]]);
    *r1 = hypot(e0 - c[ax[0]], e1 - c[ax[1]]);
    return CS_OK;
}

/* The offset along the plane's normal (K in G17, J in G18, I in G19), which FreeCAD's posts
 * and others write as K0 on every arc. LinuxCNC refuses it (interp_arc.cc convert_arc:
 * NCE_K_WORD_GIVEN_FOR_ARC_IN_XY_PLANE and the like); Grbl 1.1 reads and ignores it (gcode.c
 * clears I, J and K for every arc): the centre lies in the plane whatever it says. So: ignored
 * in Grbl's dialect (warned once when it is not 0), a warning with --lenient, else an error that
 * says both. */
static cs_err_t off_plane_offset(gc_t *g, block_t *b, const word_t *w, char letter, bool ccw,
                                 const char *names)
{
    bool grbl = g->o->dialect == CS_GCODE_GRBL;
    if (!grbl && !g->o->lenient)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, w->col),
                                "%c word in a G%d arc: the G%d plane uses %s (LinuxCNC refuses "
                                "it; Grbl ignores it: --dialect grbl or --lenient)",
                                letter, ccw ? 3 : 2, g->plane, names);
    if (!grbl || w->v != 0)
        cs_gcode_warn_once(g, w->col,
                           "%c word in a G%d-plane arc: ignored, the centre is in the plane (%s)%s",
                           letter, g->plane, names, grbl ? "" : " (--lenient)");
    b->used |= BIT(letter);
    return CS_OK;
}

/* G2 / G3. */
cs_err_t cs_gcode_arc(gc_t *g, block_t *b, bool ccw, unsigned col)
{
    int ax[3];
    cs_gcode_plane_axes(g->plane, ax);
    double t[3];
    cs_gcode_target(g, b, t);
    if (g->stats)
        g->stats->arcs++;
    const char *names = g->plane == 17 ? "I/J" : g->plane == 18 ? "I/K" : "J/K";
    const word_t *r = &b->w['R' - 'A'];
    const word_t *ofs[3] = {&b->w['I' - 'A'], &b->w['J' - 'A'], &b->w['K' - 'A']};
    bool has_ijk = ofs[ax[0]]->has || ofs[ax[1]]->has;
    if (ofs[ax[2]]->has) {
        cs_err_t eo = off_plane_offset(g, b, ofs[ax[2]], (char)('I' + ax[2]), ccw, names);
        if (eo != CS_OK)
            return eo;
    }
    if (r->has && has_ijk)
        return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, r->col),
                                "R and %s in one arc: give the centre one way", names);
    if (!r->has && !has_ijk) {
        if (!g->o->lenient)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, col),
                                    "G%d needs R (radius) or %s (centre)", ccw ? 3 : 2, names);
        /* Lenient: the arc's shape is unknown but its end is not. Skipping it would leave the
         * machine elsewhere than the program assumes, so every later R arc (whose centre
         * depends on its start) and every G91 move would be drawn wrong; a rapid would cross
         * the work at full speed. A straight feed move to the programmed end keeps the rest of
         * the file exact and only replaces this one arc by its chord. */
        cs_gcode_warn(g, col,
                      "G%d without R or %s: moved in a straight line (G1) to its end point instead "
                      "(--lenient)",
                      ccw ? 3 : 2, names);
        cs_err_t el = cs_gcode_add_line(g, g->pos, t, col, false);
        if (el == CS_OK)
            memcpy(g->pos, t, sizeof g->pos);
        return el;
    }
    int turns = 1;
    const word_t *pw = &b->w['P' - 'A'];
    if (pw->has) {
        b->used |= BIT('P');
        if (pw->v < 1 || pw->v != floor(pw->v) || pw->v > 1000)
            return cs_path_diag_set(g->diag, CS_ERR_PARSE, cs_gcode_loc(g, pw->col),
                                    "P (turns) must be a whole number from 1 to 1000");
        turns = (int)pw->v;
    }
    double rtol = radius_tol();
    const double *s = g->pos;
    double s0 = s[ax[0]], s1 = s[ax[1]], e0 = t[ax[0]], e1 = t[ax[1]];
    double c[3] = {0, 0, 0};
    double r0 = 0, r1 = 0;
    if (r->has) {
        bool done = false;
        cs_err_t er = arc_centre_r(g, b, ccw, t, col, c, &r0, &r1, &done);
        if (er != CS_OK || done)
            return er;
    } else {
        for (int k = 0; k < 2; k++) {
            const word_t *w = ofs[ax[k]];
            double v = w->has ? w->v * g->unit : 0.0;
            if (w->has)
                b->used |= BIT('I' + ax[k]);
            c[ax[k]] = g->ijk_abs ? v + cs_gcode_offset(g, ax[k]) : s[ax[k]] + v;
        }
        r0 = hypot(s0 - c[ax[0]], s1 - c[ax[1]]);
        r1 = hypot(e0 - c[ax[0]], e1 - c[ax[1]]);
        if (r0 < rtol || r1 < rtol)
            return cs_path_diag_set(g->diag, CS_ERR_DEGENERATE, cs_gcode_loc(g, col),
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
