/* cs_svgpath: SVG 1.1 path data (§8.3.9 grammar, F.6 arcs) -> cs_path_t elements.
 * Geometry is computed in double in user units (absolute), then mapped by the caller's affine
 * transform and converted once per point by cs_conv, so a point shared by two elements (the end
 * of one, the start of the next) is the same cs_pos_t in both. */
#include "cs_svgpath.h"

#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_arc.h"
#include "cs_conv.h"
#include "cs_err_text.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* An arc whose sagitta (largest distance from its chord) is below half an LSB is the chord. */
#define ARC_FLAT_MM (0.5 / (double)CS_POS_ONE_MM)
/* Samples used to measure that sagitta (ample for a sweep of at most 360 degrees). */
#define ARC_FLAT_SAMPLES 64
/* The arc pieces' end points are moved onto the exact neighbouring points; cs_arc_build promises
 * 1 LSB from the quantised centre and axes, whose own rounding adds a few more. Beyond this the
 * builder disagrees with F.6 and the arc is refused rather than silently bent. */
#define ARC_SNAP_MAX_LSB 8

typedef struct {
    const char *d;
    size_t len, pos;
    const cs_svgpath_opts_t *o;
    const char *file;
    cs_path_t *path;
    cs_path_diag_t *diag;
    /* Line/column cache for the built-in locator (offsets mostly increase). */
    size_t loc_off;
    unsigned loc_line, loc_col;
    bool have_cur;        /* a moveto has been seen */
    double cx, cy;        /* current point, user units */
    double sx, sy;        /* start of the current subpath */
    cs_vec3_t cur, start; /* the same two points, transformed and converted */
    bool have_k, have_q;  /* the previous command was C/S (have_k) or Q/T (have_q) */
    double kx, ky;        /* its second cubic control point (reflected by S) */
    double qx, qy;        /* its quadratic control point (reflected by T) */
} parser_t;

static cs_path_loc_t loc_at(parser_t *p, size_t off)
{
    cs_path_loc_t l = {p->file, 1, 1};
    if (off > p->len)
        off = p->len;
    if (p->o->locate) {
        p->o->locate(p->o->locate_ctx, off, &l.line, &l.col);
        return l;
    }
    if (off < p->loc_off) {
        p->loc_off = 0;
        p->loc_line = 1;
        p->loc_col = 1;
    }
    for (size_t i = p->loc_off; i < off; i++) {
        unsigned char ch = (unsigned char)p->d[i];
        if (ch == '\n') {
            p->loc_line++;
            p->loc_col = 1;
        } else if (ch != '\r' && (ch & 0xC0) != 0x80) {
            p->loc_col++; /* one column per character: UTF-8 continuation bytes do not count */
        }
    }
    p->loc_off = off;
    l.line = p->loc_line;
    l.col = p->loc_col;
    return l;
}

/* Fills the diagnostic for offset off and returns code. */
static cs_err_t fail(parser_t *p, size_t off, cs_err_t code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static cs_err_t fail(parser_t *p, size_t off, cs_err_t code, const char *fmt, ...)
{
    char msg[200];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return cs_path_diag_set(p->diag, code, loc_at(p, off), "%s", msg);
}

/* What sits at offset off, for messages: "'x'", "end of data", "byte 0xNN". */
static const char *what_at(const parser_t *p, size_t off, char buf[24])
{
    if (off >= p->len)
        return "end of data";
    unsigned char ch = (unsigned char)p->d[off];
    if (ch > 0x20 && ch < 0x7f)
        snprintf(buf, 24, "'%c'", ch);
    else if (ch == ' ')
        snprintf(buf, 24, "a space");
    else if (ch == '\n' || ch == '\r')
        snprintf(buf, 24, "end of line");
    else
        snprintf(buf, 24, "byte 0x%02X", (unsigned)ch);
    return buf;
}

static bool is_wsp(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

static bool is_digit(char c)
{
    return c >= '0' && c <= '9';
}

static bool is_num_start(char c)
{
    return is_digit(c) || c == '+' || c == '-' || c == '.';
}

static bool at(const parser_t *p, size_t off)
{
    return off < p->len;
}

static void skip_wsp(parser_t *p)
{
    while (at(p, p->pos) && is_wsp(p->d[p->pos]))
        p->pos++;
}

/* comma-wsp between two arguments of one set: wsp* ','? wsp*. */
static void skip_comma_wsp(parser_t *p)
{
    skip_wsp(p);
    if (at(p, p->pos) && p->d[p->pos] == ',') {
        p->pos++;
        skip_wsp(p);
    }
}

size_t cs_svgpath_scan_number(const char *s, size_t len, double *out, size_t *bad)
{
    size_t i = 0, badpos = 0;
    bool digits = false;
    if (i < len && (s[i] == '+' || s[i] == '-'))
        i++;
    while (i < len && is_digit(s[i])) {
        i++;
        digits = true;
    }
    if (i < len && s[i] == '.') {
        i++;
        while (i < len && is_digit(s[i])) {
            i++;
            digits = true;
        }
    }
    if (!digits) {
        badpos = i;
        goto bad;
    }
    if (i < len && (s[i] == 'e' || s[i] == 'E')) {
        size_t j = i + 1;
        if (j < len && (s[j] == '+' || s[j] == '-'))
            j++;
        if (j >= len || !is_digit(s[j])) {
            badpos = j;
            goto bad;
        }
        while (j < len && is_digit(s[j]))
            j++;
        i = j;
    }
    /* The span is validated above, so strtod (C locale) reads exactly it. */
    char small[64];
    char *tmp = small;
    if (i >= sizeof small) {
        tmp = malloc(i + 1);
        if (!tmp) {
            badpos = 0;
            goto bad;
        }
    }
    memcpy(tmp, s, i);
    tmp[i] = '\0';
    *out = strtod(tmp, NULL);
    if (tmp != small)
        free(tmp);
    return i;
bad:
    if (bad)
        *bad = badpos;
    return 0;
}

/* A number argument of command cmd at the current position. */
static cs_err_t parse_number(parser_t *p, double *out, char cmd, const char *what)
{
    char buf[24];
    size_t s = p->pos, bad = 0;
    if (!at(p, s) || !is_num_start(p->d[s]))
        return fail(p, s, CS_ERR_PARSE, "'%c' expects a number (%s), found %s", cmd, what,
                    what_at(p, s, buf));
    double v = 0.0;
    size_t n = cs_svgpath_scan_number(p->d + s, p->len - s, &v, &bad);
    if (n == 0)
        return fail(p, s + bad, CS_ERR_PARSE, "invalid number: expected a digit, found %s",
                    what_at(p, s + bad, buf));
    if (!isfinite(v))
        return fail(p, s, CS_ERR_RANGE, "number too large for a double");
    *out = v;
    p->pos = s + n;
    return CS_OK;
}

/* flag: '0' | '1' (one character, so "00" is two flags: F.6 note on "a1 1 0 00 1 1"). */
static cs_err_t parse_flag(parser_t *p, double *out, char cmd, const char *what)
{
    char buf[24];
    if (!at(p, p->pos) || (p->d[p->pos] != '0' && p->d[p->pos] != '1'))
        return fail(p, p->pos, CS_ERR_PARSE, "'%c' expects a flag 0 or 1 (%s), found %s", cmd, what,
                    what_at(p, p->pos, buf));
    *out = p->d[p->pos] == '1' ? 1.0 : 0.0;
    p->pos++;
    return CS_OK;
}

/* Maps user point (x, y) to mm and converts it; CS_ERR_RANGE reported at off. */
static cs_err_t point(parser_t *p, double x, double y, size_t off, cs_vec3_t *out)
{
    double tx, ty;
    cs_path_affine_point(&p->o->xform, x, y, &tx, &ty);
    if (cs_conv_mm_to_vec(tx, ty, 0.0, out) != CS_OK)
        return fail(p, off, CS_ERR_RANGE,
                    "point (%.6g, %.6g) mm is outside the accepted range of +/-%d mm", tx, ty,
                    CS_POS_LIMIT_MM);
    return CS_OK;
}

static cs_err_t emit(parser_t *p, cs_path_kind_t kind, unsigned degree, const cs_vec3_t *pts,
                     size_t off)
{
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = (uint8_t)degree;
    c.rational = false;
    for (unsigned i = 0; i <= degree; i++) {
        c.p[i] = pts[i];
        c.w[i] = CS_WEIGHT_ONE;
    }
    if (cs_path_add(p->path, &c, kind, loc_at(p, off)) != CS_OK)
        return fail(p, off, CS_ERR_FULL, "out of memory");
    return CS_OK;
}

static cs_err_t line_to(parser_t *p, double x, double y, size_t pt_off, size_t elem_off)
{
    cs_vec3_t q[2];
    cs_err_t e = point(p, x, y, pt_off, &q[1]);
    if (e != CS_OK)
        return e;
    q[0] = p->cur;
    if ((e = emit(p, CS_PATH_LINE, 1, q, elem_off)) != CS_OK)
        return e;
    p->cx = x;
    p->cy = y;
    p->cur = q[1];
    return CS_OK;
}

static bool vec_eq(const cs_vec3_t *a, const cs_vec3_t *b)
{
    return a->x == b->x && a->y == b->y && a->z == b->z;
}

static int64_t lsb_dist(const cs_vec3_t *a, const cs_vec3_t *b)
{
    int64_t dx = (int64_t)a->x - b->x, dy = (int64_t)a->y - b->y, dz = (int64_t)a->z - b->z;
    dx = dx < 0 ? -dx : dx;
    dy = dy < 0 ? -dy : dy;
    dz = dz < 0 ? -dz : dz;
    return dx > dy ? (dx > dz ? dx : dz) : (dy > dz ? dy : dz);
}

/* Distance from (px, py) to the segment (ax, ay)-(bx, by). */
static double seg_dist(double px, double py, double ax, double ay, double bx, double by)
{
    double vx = bx - ax, vy = by - ay, wx = px - ax, wy = py - ay;
    double l2 = vx * vx + vy * vy;
    double t = l2 > 0.0 ? (wx * vx + wy * vy) / l2 : 0.0;
    t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
    return hypot(wx - t * vx, wy - t * vy);
}

/* The arc X = C + U cos(theta) + V sin(theta), theta from th0 over dth, as rational quadratic
 * pieces of at most 90 degrees built in double (for ellipses whose centre or semi-axes
 * cs_arc_build cannot take): on the unit circle a piece from a to b has its middle control
 * point at the tangents' intersection (cos m, sin m) / cos h and weight cos h (m = (a + b) / 2,
 * h = (b - a) / 2), mapped by the affine map X, under which rational Béziers are invariant. */
static cs_err_t arc_pieces_double(parser_t *p, double Cx, double Cy, double Ux, double Uy,
                                  double Vx, double Vy, double th0, double dth,
                                  const cs_vec3_t *endf, size_t elem_off)
{
    int n = (int)ceil(fabs(dth) / (M_PI / 2.0) - 1e-9);
    if (n < 1)
        n = 1;
    double h = dth / (2.0 * n);
    cs_weight_t w1;
    if (cs_conv_to_weight(cos(h), &w1) != CS_OK)
        return fail(p, elem_off, CS_ERR_WEIGHT, "arc piece weight out of range");
    cs_bezier_t seg;
    memset(&seg, 0, sizeof seg);
    seg.degree = 2;
    seg.rational = true;
    seg.w[0] = seg.w[2] = CS_WEIGHT_ONE;
    seg.w[1] = w1;
    cs_vec3_t start = p->cur;
    for (int i = 0; i < n; i++) {
        double a = th0 + 2.0 * h * i, m = a + h, b = a + 2.0 * h;
        double ux = cos(m) / cos(h), uy = sin(m) / cos(h);
        double mx = Cx + Ux * ux + Vx * uy, my = Cy + Uy * ux + Vy * uy;
        double bx = Cx + Ux * cos(b) + Vx * sin(b), by = Cy + Uy * cos(b) + Vy * sin(b);
        seg.p[0] = start;
        if (cs_conv_mm_to_vec(mx, my, 0.0, &seg.p[1]) != CS_OK)
            return fail(p, elem_off, CS_ERR_RANGE,
                        "arc leaves the accepted range of +/-%d mm (control point (%.6g, %.6g))",
                        CS_POS_LIMIT_MM, mx, my);
        if (i == n - 1)
            seg.p[2] = *endf; /* the exact end point, so the path stays continuous */
        else if (cs_conv_mm_to_vec(bx, by, 0.0, &seg.p[2]) != CS_OK)
            return fail(p, elem_off, CS_ERR_RANGE,
                        "arc leaves the accepted range of +/-%d mm (point (%.6g, %.6g))",
                        CS_POS_LIMIT_MM, bx, by);
        if (cs_path_add(p->path, &seg, CS_PATH_ARC, loc_at(p, elem_off)) != CS_OK)
            return fail(p, elem_off, CS_ERR_FULL, "out of memory");
        start = seg.p[2];
    }
    return CS_OK;
}

/* Elliptical arc from the current point (SVG 1.1 F.6.5 endpoint -> centre conversion, F.6.6
 * out-of-range radii), then cs_arc_build on the transformed centre and conjugate semi-axes: an
 * affine image of X = C + U cos(theta) + V sin(theta) is C' + U' cos(theta) + V' sin(theta), so
 * the unit-circle directions carry over unchanged. */
/* An arc's centre parameterisation (SVG 1.1 F.6.5): centre (ccx, ccy) and radii (rx, ry,
 * scaled up when too small, F.6.6.2) in user units, the x axis' direction (cp, sp), the unit
 * start and end directions (u0, u1), the start angle th0 and the signed sweep dth. */
typedef struct {
    double ccx, ccy, rx, ry, cp, sp;
    double u0x, u0y, u1x, u1y;
    double th0, dth;
} arc_geo_t;

/* From (x1, y1) to (x2, y2) with radii rx, ry > 0, rotation phi_deg, the flags fa, fs. false
 * when the directions degenerate (the caller draws a line). */
static bool arc_centre(double x1, double y1, double x2, double y2, double rx, double ry,
                       double phi_deg, bool fa, bool fs, arc_geo_t *g)
{
    double phi = fmod(phi_deg, 360.0) * (M_PI / 180.0);
    double cp = cos(phi), sp = sin(phi);
    double dx2 = (x1 - x2) / 2.0, dy2 = (y1 - y2) / 2.0;
    double x1p = cp * dx2 + sp * dy2; /* F.6.5.1 */
    double y1p = -sp * dx2 + cp * dy2;
    double lam = (x1p / rx) * (x1p / rx) + (y1p / ry) * (y1p / ry); /* F.6.6.2 */
    if (lam > 1.0) {
        double s = sqrt(lam);
        rx *= s;
        ry *= s;
        lam = (x1p / rx) * (x1p / rx) + (y1p / ry) * (y1p / ry);
    }
    /* F.6.5.2, with numerator and denominator divided by rx^2 ry^2: (1 - lam) / lam. */
    double coef = lam > 0.0 && lam < 1.0 ? sqrt((1.0 - lam) / lam) : 0.0;
    if (fa == fs)
        coef = -coef;
    double cxp = coef * rx * y1p / ry, cyp = -coef * ry * x1p / rx;
    g->ccx = cp * cxp - sp * cyp + (x1 + x2) / 2.0; /* F.6.5.3 */
    g->ccy = sp * cxp + cp * cyp + (y1 + y2) / 2.0;
    g->rx = rx;
    g->ry = ry;
    g->cp = cp;
    g->sp = sp;
    /* Start and end directions on the unit circle (the vectors of F.6.5.5 and F.6.5.6). */
    double u0x = (x1p - cxp) / rx, u0y = (y1p - cyp) / ry;
    double u1x = (-x1p - cxp) / rx, u1y = (-y1p - cyp) / ry;
    double n0 = hypot(u0x, u0y), n1 = hypot(u1x, u1y);
    if (!(n0 > 0.0) || !(n1 > 0.0))
        return false;
    g->u0x = u0x / n0;
    g->u0y = u0y / n0;
    g->u1x = u1x / n1;
    g->u1y = u1y / n1;
    g->th0 = atan2(g->u0y, g->u0x);
    g->dth = atan2(g->u0x * g->u1y - g->u0y * g->u1x, g->u0x * g->u1x + g->u0y * g->u1y);
    if (fs && g->dth < 0.0) /* F.6.5.6 */
        g->dth += 2.0 * M_PI;
    else if (!fs && g->dth > 0.0)
        g->dth -= 2.0 * M_PI;
    return true;
}

/* Largest distance (mm) of the arc with centre C and conjugate semi-axes U, V (mm) from the chord
 * a-b, sampled: a nearly flat arc is drawn as its chord. */
static double arc_sag(const arc_geo_t *g, const double C[2], const double U[2], const double V[2],
                      double ax, double ay, double bx, double by)
{
    double sag = 0.0;
    for (int k = 1; k < ARC_FLAT_SAMPLES; k++) {
        double th = g->th0 + g->dth * k / ARC_FLAT_SAMPLES;
        double px = C[0] + U[0] * cos(th) + V[0] * sin(th);
        double py = C[1] + U[1] * cos(th) + V[1] * sin(th);
        double dd = seg_dist(px, py, ax, ay, bx, by);
        if (dd > sag)
            sag = dd;
    }
    return sag;
}

/* The arc's rational pieces from the core's builder (cs_arc_build), snapped to the path's end
 * points, added to the path; the parser's position moves to (x2, y2) / endf. */
static cs_err_t arc_emit(parser_t *p, const arc_geo_t *g, const cs_vec3_t *C, const cs_vec3_t *U,
                         const cs_vec3_t *V, bool fs, const cs_vec3_t *endf, double x2, double y2,
                         size_t end_off, size_t elem_off)
{
    cs_param_t c0, s0, c1, s1;
    if (cs_conv_to_param(g->u0x, &c0) != CS_OK || cs_conv_to_param(g->u0y, &s0) != CS_OK ||
        cs_conv_to_param(g->u1x, &c1) != CS_OK || cs_conv_to_param(g->u1y, &s1) != CS_OK)
        return fail(p, elem_off, CS_ERR_RANGE, "arc direction not representable");
    if (c0 == c1 && s0 == s1 && fabs(g->dth) < M_PI) {
        /* Distinct small-sweep directions that round together would read as a full turn. */
        return line_to(p, x2, y2, end_off, elem_off);
    }
    cs_bezier_t seg[CS_ARC_MAX_SEGMENTS];
    memset(seg, 0, sizeof seg); /* unused points of each piece stay defined (zero) */
    unsigned n = 0;
    cs_err_t e = cs_arc_build(C, U, V, c0, s0, c1, s1, fs, seg, &n);
    if (e != CS_OK)
        return fail(p, elem_off, e == CS_ERR_OVERFLOW ? CS_ERR_RANGE : e, "arc cannot be built: %s",
                    cs_err_text(e));
    if (n < 1 || n > CS_ARC_MAX_SEGMENTS)
        return fail(p, elem_off, CS_ERR_ARG, "arc builder returned %u pieces", n);
    unsigned last = seg[n - 1].degree;
    if (lsb_dist(&seg[0].p[0], &p->cur) > ARC_SNAP_MAX_LSB ||
        lsb_dist(&seg[n - 1].p[last], endf) > ARC_SNAP_MAX_LSB)
        return fail(p, elem_off, CS_ERR_ARG,
                    "arc builder's end points are %lld and %lld LSB away from the arc's ends",
                    (long long)lsb_dist(&seg[0].p[0], &p->cur),
                    (long long)lsb_dist(&seg[n - 1].p[last], endf));
    /* Make the path continuous to the LSB: the neighbours' end points are the exact ones. */
    seg[0].p[0] = p->cur;
    seg[n - 1].p[last] = *endf;
    for (unsigned i = 0; i < n; i++)
        if (cs_path_add(p->path, &seg[i], CS_PATH_ARC, loc_at(p, elem_off)) != CS_OK)
            return fail(p, elem_off, CS_ERR_FULL, "out of memory");
    p->cx = x2;
    p->cy = y2;
    p->cur = *endf;
    return CS_OK;
}

static cs_err_t arc_to(parser_t *p, double rx, double ry, double phi_deg, bool fa, bool fs,
                       double x2, double y2, size_t end_off, size_t elem_off)
{
    double x1 = p->cx, y1 = p->cy;
    cs_vec3_t endf;
    cs_err_t e = point(p, x2, y2, end_off, &endf);
    if (e != CS_OK)
        return e;
    if (x1 == x2 && y1 == y2)
        return CS_OK; /* F.6.2: identical end points, the arc is omitted */
    rx = fabs(rx);
    ry = fabs(ry);
    arc_geo_t g;
    if (rx == 0.0 || ry == 0.0 || /* F.6.2: zero radius = straight line */
        !arc_centre(x1, y1, x2, y2, rx, ry, phi_deg, fa, fs, &g))
        return line_to(p, x2, y2, end_off, elem_off);

    /* Centre and conjugate semi-axes in mm. */
    double Cm[2], Um[2], Vm[2];
    cs_path_affine_point(&p->o->xform, g.ccx, g.ccy, &Cm[0], &Cm[1]);
    cs_path_affine_vector(&p->o->xform, g.rx * g.cp, g.rx * g.sp, &Um[0], &Um[1]);
    cs_path_affine_vector(&p->o->xform, -g.ry * g.sp, g.ry * g.cp, &Vm[0], &Vm[1]);

    /* A nearly flat arc (tiny sweep of a huge ellipse) is its chord to within half an LSB;
     * drawing it as a line also spares a centre far outside the coordinate range. */
    double sag = arc_sag(&g, Cm, Um, Vm, cs_conv_pos_to_mm(p->cur.x), cs_conv_pos_to_mm(p->cur.y),
                         cs_conv_pos_to_mm(endf.x), cs_conv_pos_to_mm(endf.y));
    if (!isfinite(sag))
        return fail(p, elem_off, CS_ERR_RANGE, "arc is too large for the coordinate range");
    if (sag < ARC_FLAT_MM)
        return line_to(p, x2, y2, end_off, elem_off);

    cs_vec3_t C, U, V;
    bool centre_ok = cs_conv_mm_to_vec(Cm[0], Cm[1], 0.0, &C) == CS_OK;
    bool axes_ok = cs_conv_mm_to_vec(Um[0], Um[1], 0.0, &U) == CS_OK &&
                   cs_conv_mm_to_vec(Vm[0], Vm[1], 0.0, &V) == CS_OK;
    if (centre_ok && axes_ok)
        return arc_emit(p, &g, &C, &U, &V, fs, &endf, x2, y2, end_off, elem_off);
    /* cs_arc_build needs the centre and semi-axes inside the coordinate range; a flat arc of a
     * large ellipse lies in range while they do not. Build the same pieces here. */
    e = arc_pieces_double(p, Cm[0], Cm[1], Um[0], Um[1], Vm[0], Vm[1], g.th0, g.dth, &endf,
                          elem_off);
    if (e == CS_OK) {
        p->cx = x2;
        p->cy = y2;
        p->cur = endf;
    } else if (e == CS_ERR_RANGE && !centre_ok) {
        fail(p, elem_off, CS_ERR_RANGE,
             "arc leaves the accepted range of +/-%d mm (its centre is at (%.6g, %.6g) mm)",
             CS_POS_LIMIT_MM, Cm[0], Cm[1]);
    }
    return e;
}

static unsigned nargs_of(char up)
{
    switch (up) {
    case 'M':
    case 'L':
    case 'T':
        return 2;
    case 'H':
    case 'V':
        return 1;
    case 'C':
        return 6;
    case 'S':
    case 'Q':
        return 4;
    case 'A':
        return 7;
    default:
        return 0;
    }
}

static const char *arg_name(char up, unsigned i)
{
    static const char *const arc_names[7] = {
        "rx", "ry", "x-axis-rotation", "large-arc-flag", "sweep-flag", "x", "y"};
    if (up == 'A')
        return arc_names[i];
    if (up == 'H')
        return "x";
    if (up == 'V')
        return "y";
    return (i % 2) ? "y" : "x";
}

/* Executes one argument set of command cmd (upper case up); a[] are the arguments, aoff[] their
 * offsets; elem_off is where the element is said to come from. */
/* M: a new subpath at (ox + a0, oy + a1). */
static cs_err_t move_set(parser_t *p, double ox, double oy, const double *a, const size_t *aoff)
{
    double x = ox + a[0], y = oy + a[1];
    cs_vec3_t q;
    cs_err_t e = point(p, x, y, aoff[0], &q);
    if (e != CS_OK)
        return e;
    p->cx = p->sx = x;
    p->cy = p->sy = y;
    p->cur = p->start = q;
    p->have_cur = true;
    cs_path_new_subpath(p->path);
    return CS_OK;
}

/* C or S (up): one cubic from the current point. */
static cs_err_t cubic_set(parser_t *p, char up, double ox, double oy, const double *a,
                          const size_t *aoff, size_t elem_off)
{
    double c1x, c1y, c2x, c2y, x, y;
    size_t o2;
    if (up == 'C') {
        c1x = ox + a[0];
        c1y = oy + a[1];
        c2x = ox + a[2];
        c2y = oy + a[3];
        x = ox + a[4];
        y = oy + a[5];
        o2 = 2;
    } else {
        /* S: the first control point is the reflection of the previous C/S's second control
         * point about the current point, or the current point itself (§8.3.6). */
        c1x = p->have_k ? 2.0 * p->cx - p->kx : p->cx;
        c1y = p->have_k ? 2.0 * p->cy - p->ky : p->cy;
        c2x = ox + a[0];
        c2y = oy + a[1];
        x = ox + a[2];
        y = oy + a[3];
        o2 = 0;
    }
    cs_vec3_t q[4];
    q[0] = p->cur;
    cs_err_t e;
    if ((e = point(p, c1x, c1y, up == 'C' ? aoff[0] : elem_off, &q[1])) != CS_OK ||
        (e = point(p, c2x, c2y, aoff[o2], &q[2])) != CS_OK ||
        (e = point(p, x, y, aoff[o2 + 2], &q[3])) != CS_OK ||
        (e = emit(p, CS_PATH_CUBIC, 3, q, elem_off)) != CS_OK)
        return e;
    p->kx = c2x;
    p->ky = c2y;
    p->cx = x;
    p->cy = y;
    p->cur = q[3];
    return CS_OK;
}

/* Q or T (up): one quadratic from the current point. */
static cs_err_t quad_set(parser_t *p, char up, double ox, double oy, const double *a,
                         const size_t *aoff, size_t elem_off)
{
    double c1x, c1y, x, y;
    size_t o1;
    if (up == 'Q') {
        c1x = ox + a[0];
        c1y = oy + a[1];
        x = ox + a[2];
        y = oy + a[3];
        o1 = 2;
    } else {
        /* T: reflection of the previous Q/T's control point, else the current point. */
        c1x = p->have_q ? 2.0 * p->cx - p->qx : p->cx;
        c1y = p->have_q ? 2.0 * p->cy - p->qy : p->cy;
        x = ox + a[0];
        y = oy + a[1];
        o1 = 0;
    }
    cs_vec3_t q[3];
    q[0] = p->cur;
    cs_err_t e;
    if ((e = point(p, c1x, c1y, up == 'Q' ? aoff[0] : elem_off, &q[1])) != CS_OK ||
        (e = point(p, x, y, aoff[o1], &q[2])) != CS_OK ||
        (e = emit(p, CS_PATH_QUAD, 2, q, elem_off)) != CS_OK)
        return e;
    p->qx = c1x;
    p->qy = c1y;
    p->cx = x;
    p->cy = y;
    p->cur = q[2];
    return CS_OK;
}

static cs_err_t exec_set(parser_t *p, char cmd, char up, const double *a, const size_t *aoff,
                         size_t elem_off)
{
    bool rel = cmd != up;
    double ox = rel ? p->cx : 0.0, oy = rel ? p->cy : 0.0;
    cs_err_t e = CS_OK;
    switch (up) {
    case 'M':
        e = move_set(p, ox, oy, a, aoff);
        break;
    case 'L':
        e = line_to(p, ox + a[0], oy + a[1], aoff[0], elem_off);
        break;
    case 'H':
        e = line_to(p, ox + a[0], p->cy, aoff[0], elem_off);
        break;
    case 'V':
        e = line_to(p, p->cx, oy + a[0], aoff[0], elem_off);
        break;
    case 'C':
    case 'S':
        e = cubic_set(p, up, ox, oy, a, aoff, elem_off);
        break;
    case 'Q':
    case 'T':
        e = quad_set(p, up, ox, oy, a, aoff, elem_off);
        break;
    case 'A':
        e = arc_to(p, a[0], a[1], a[2], a[3] != 0.0, a[4] != 0.0, ox + a[5], oy + a[6], aoff[5],
                   elem_off);
        break;
    default:
        break;
    }
    if (e != CS_OK && (up == 'M' || up == 'C' || up == 'S' || up == 'Q' || up == 'T'))
        return e; /* as before: the reflection state is left as it was on these errors */
    p->have_k = e == CS_OK && (up == 'C' || up == 'S');
    p->have_q = e == CS_OK && (up == 'Q' || up == 'T');
    return e;
}

static cs_err_t close_path(parser_t *p, size_t off)
{
    cs_err_t e = CS_OK;
    /* Z draws the straight line back to the subpath's start (§8.3.3); when the pen is already
     * there (to the LSB) there is nothing to draw. */
    if (!vec_eq(&p->cur, &p->start)) {
        cs_vec3_t q[2] = {p->cur, p->start};
        e = emit(p, CS_PATH_LINE, 1, q, off);
    }
    p->cx = p->sx;
    p->cy = p->sy;
    p->cur = p->start;
    p->have_k = p->have_q = false;
    /* A command after Z starts a new subpath at the same initial point. */
    cs_path_new_subpath(p->path);
    return e;
}

void cs_svgpath_opts_init(cs_svgpath_opts_t *o, const char *file)
{
    memset(o, 0, sizeof *o);
    o->file = file ? file : "-";
    o->xform = cs_path_affine_identity();
}

cs_err_t cs_svgpath_parse(const char *d, size_t len, const cs_svgpath_opts_t *o, cs_path_t *path,
                          cs_path_diag_t *diag)
{
    parser_t p;
    memset(&p, 0, sizeof p);
    p.d = d;
    p.len = len;
    p.o = o;
    p.path = path;
    p.diag = diag;
    p.loc_line = 1;
    p.loc_col = 1;
    p.file = cs_path_intern(path, o->file ? o->file : "-");
    if (!p.file) {
        p.file = "-";
        return fail(&p, 0, CS_ERR_FULL, "out of memory");
    }
    char buf[24];
    cs_err_t e;
    for (;;) {
        skip_wsp(&p);
        if (!at(&p, p.pos))
            return CS_OK;
        size_t cmd_off = p.pos;
        char cmd = d[p.pos];
        char up = (cmd >= 'a' && cmd <= 'z') ? (char)(cmd - 'a' + 'A') : cmd;
        bool known = strchr("MLHVCSQTAZ", up) != NULL && up != '\0';
        if (!p.have_cur && up != 'M')
            return fail(&p, cmd_off, CS_ERR_PARSE,
                        "path data must begin with a moveto ('M' or 'm'), found %s",
                        what_at(&p, cmd_off, buf));
        if (!known)
            return fail(&p, cmd_off, CS_ERR_PARSE, "expected a path command letter, found %s",
                        what_at(&p, cmd_off, buf));
        p.pos++;
        if (up == 'Z') {
            if ((e = close_path(&p, cmd_off)) != CS_OK)
                return e;
            skip_wsp(&p);
            if (at(&p, p.pos) && (is_num_start(d[p.pos]) || d[p.pos] == ','))
                return fail(&p, p.pos, CS_ERR_PARSE,
                            "'%c' (closepath) takes no arguments, found %s", cmd,
                            what_at(&p, p.pos, buf));
            continue;
        }
        unsigned nargs = nargs_of(up);
        bool first = true;
        for (;;) {
            double a[7];
            size_t aoff[7];
            skip_wsp(&p);
            for (unsigned i = 0; i < nargs; i++) {
                if (i > 0)
                    skip_comma_wsp(&p);
                aoff[i] = p.pos;
                e = (up == 'A' && (i == 3 || i == 4))
                        ? parse_flag(&p, &a[i], cmd, arg_name(up, i))
                        : parse_number(&p, &a[i], cmd, arg_name(up, i));
                if (e != CS_OK)
                    return e;
            }
            if ((e = exec_set(&p, cmd, up, a, aoff, first ? cmd_off : aoff[0])) != CS_OK)
                return e;
            /* Extra coordinate pairs after a moveto are implicit linetos (§8.3.2). */
            if (up == 'M') {
                up = 'L';
                cmd = cmd == 'm' ? 'l' : 'L';
            }
            first = false;
            skip_wsp(&p);
            bool comma = false;
            if (at(&p, p.pos) && d[p.pos] == ',') {
                comma = true;
                p.pos++;
                skip_wsp(&p);
            }
            if (at(&p, p.pos) && is_num_start(d[p.pos]))
                continue; /* implicit repetition of the same command */
            if (comma)
                return fail(&p, p.pos, CS_ERR_PARSE, "expected a number after ',', found %s",
                            what_at(&p, p.pos, buf));
            break;
        }
    }
}
