/* cs_hpgl: HP-GL / HP-GL/2 -> cs_path_t (see cs_hpgl.h).
 * Positions are kept in double plotter units (absolute); every point is converted once to
 * cs_pos_t, so the end of one element and the start of the next are the same cs_pos_t.
 * Instruction semantics follow the HP-GL/2 reference (HP 5959-9733): a mnemonic is two letters,
 * its parameters numbers separated by commas or blanks, ended by ';' or by the next mnemonic. */
#include "cs_hpgl.h"

#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_arc.h"
#include "cs_conv.h"
#include "cs_err_text.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* HP-GL/2 parameters are at most 2^30 in magnitude (integers -2^30..2^30-1). */
#define HP_NUM_MAX 1073741824.0
/* Longest number text accepted (digits, sign, point). */
#define HP_NUM_CHARS 40
/* The default label terminator: ETX. */
#define HP_ETX 3
/* Arc end points are moved onto the exact neighbouring point (as cs_svgpath does); beyond this
 * many LSB the builder disagrees with the arc and it is refused rather than bent. */
#define HP_ARC_SNAP_MAX_LSB 8

typedef struct {
    const char *buf;
    size_t len, pos;
    const char *file;
    const cs_hpgl_opts_t *o;
    cs_path_t *path;
    cs_path_diag_t *diag;
    size_t loc_off; /* line/column cache: offsets mostly increase */
    unsigned loc_line, loc_col;
    double x, y;   /* current position, plotter units, absolute */
    cs_vec3_t cur; /* the same, converted */
    bool relative, pen_down;
    double si_w, si_h; /* SI character width and height, cm (HP default 0.19 x 0.27) */
    long pen;             /* selected pen; 0 = none (nothing is drawn) */
    char label_term;      /* LB/BL/WD text terminator (DT) */
    cs_path_affine_t map; /* user units -> physical plotter units (RO, IP/IR, SC), y up */
    double frame[2];      /* picture frame (PS), plotter units: x, y before rotation */
    double p1[2], p2[2];  /* scaling points, in rotated plotter units */
    int ro;               /* RO: 0, 90, 180 or 270 */
    bool sc_on;           /* SC in effect */
    double sc[7];         /* SC xmin,xmax|xfactor,ymin,ymax|yfactor,type,left,bottom */
    bool win_on;          /* IW window in effect */
    double win[4];        /* IW window, physical plotter units: x0, y0, x1, y1 */
    bool warned[26 * 26];
    bool warned_esc, warned_nopen, warned_big_sweep;
} hp_t;

static cs_path_loc_t loc_at(hp_t *h, size_t off)
{
    cs_path_loc_t l = {h->file, 1, 1};
    if (off > h->len)
        off = h->len;
    if (off < h->loc_off) {
        h->loc_off = 0;
        h->loc_line = 1;
        h->loc_col = 1;
    }
    for (size_t i = h->loc_off; i < off; i++) {
        unsigned char ch = (unsigned char)h->buf[i];
        if (ch == '\n') {
            h->loc_line++;
            h->loc_col = 1;
        } else if (ch != '\r' && (ch & 0xC0) != 0x80) {
            h->loc_col++; /* one column per character, not per UTF-8 byte */
        }
    }
    h->loc_off = off;
    l.line = h->loc_line;
    l.col = h->loc_col;
    return l;
}

static cs_err_t fail(hp_t *h, size_t off, cs_err_t code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static cs_err_t fail(hp_t *h, size_t off, cs_err_t code, const char *fmt, ...)
{
    char msg[200];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return cs_path_diag_set(h->diag, code, loc_at(h, off), "%s", msg);
}

static void warn(hp_t *h, size_t off, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static void warn(hp_t *h, size_t off, const char *fmt, ...)
{
    cs_path_diag_t w;
    char msg[220];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    cs_path_diag_set(&w, CS_OK, loc_at(h, off), "%s", msg);
    if (h->o->warn)
        h->o->warn(h->o->warn_ctx, &w);
    else
        cs_path_warn_print(stderr, &w);
}

/* What sits at offset off, for messages. */
static const char *what_at(const hp_t *h, size_t off, char buf[24])
{
    if (off >= h->len)
        return "end of file";
    unsigned char ch = (unsigned char)h->buf[off];
    if (ch > 0x20 && ch < 0x7f)
        snprintf(buf, 24, "'%c'", ch);
    else
        snprintf(buf, 24, "byte 0x%02X", (unsigned)ch);
    return buf;
}

static bool is_letter(char c)
{
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z');
}

static bool is_digit(char c)
{
    return c >= '0' && c <= '9';
}

static char upper(char c)
{
    return (c >= 'a' && c <= 'z') ? (char)(c - 'a' + 'A') : c;
}

/* Blanks and control characters (other than ESC) separate everything and mean nothing. */
static bool is_blank(char c)
{
    unsigned char u = (unsigned char)c;
    return u == ' ' || (u < 0x20 && u != 0x1B);
}

/* --- parameters ------------------------------------------------------------------------ */

/* Skips blanks and commas before a parameter. */
static void skip_sep(hp_t *h)
{
    while (h->pos < h->len && (is_blank(h->buf[h->pos]) || h->buf[h->pos] == ','))
        h->pos++;
}

/* Next numeric parameter of instruction mn: 1 with *v and *off set, 0 when the parameters end
 * (';', a letter, ESC, end of file; the terminator is left in place), or -1 with *e set. */
static int next_num(hp_t *h, const char *mn, double *v, size_t *off, cs_err_t *e)
{
    skip_sep(h);
    if (h->pos >= h->len)
        return 0;
    char c = h->buf[h->pos];
    if (c == ';' || is_letter(c) || c == 0x1B)
        return 0;
    size_t s = h->pos, i = s;
    if (i < h->len && (h->buf[i] == '+' || h->buf[i] == '-'))
        i++;
    size_t digits = 0;
    while (i < h->len && is_digit(h->buf[i])) {
        i++;
        digits++;
    }
    if (i < h->len && h->buf[i] == '.') {
        i++;
        while (i < h->len && is_digit(h->buf[i])) {
            i++;
            digits++;
        }
    }
    if (digits == 0) {
        char b[24];
        *e = fail(h, digits == 0 && i > s ? i : s, CS_ERR_PARSE,
                  "%s: expected a number, ';' or the next instruction, found %s", mn,
                  what_at(h, i > s ? i : s, b));
        return -1;
    }
    /* "1e15": an exponent is no HP-GL number, and "e1" is no instruction (two letters): say
     * so at the number rather than "expected a two-letter instruction" at the digit after. */
    if (i + 1 < h->len && (h->buf[i] == 'e' || h->buf[i] == 'E') &&
        (is_digit(h->buf[i + 1]) ||
         ((h->buf[i + 1] == '+' || h->buf[i + 1] == '-') && i + 2 < h->len &&
          is_digit(h->buf[i + 2])))) {
        *e = fail(h, s, CS_ERR_PARSE, "%s: number in exponent form: HP-GL numbers have no exponent",
                  mn);
        return -1;
    }
    if (i - s > HP_NUM_CHARS) {
        *e = fail(h, s, CS_ERR_RANGE, "%s: number too long (%zu characters)", mn, i - s);
        return -1;
    }
    char tmp[HP_NUM_CHARS + 1];
    memcpy(tmp, h->buf + s, i - s);
    tmp[i - s] = '\0';
    double d = strtod(tmp, NULL);
    if (!(fabs(d) <= HP_NUM_MAX)) {
        *e = fail(h, s, CS_ERR_RANGE, "%s: number %s is outside the HP-GL/2 range of +/-2^30", mn,
                  tmp);
        return -1;
    }
    *v = d;
    *off = s;
    h->pos = i;
    return 1;
}

/* End of an instruction's parameters: blanks, then an optional ';'. Anything other than ';',
 * a letter, ESC or the end of file is an error. */
static cs_err_t end_instr(hp_t *h, const char *mn)
{
    skip_sep(h);
    if (h->pos >= h->len)
        return CS_OK;
    char c = h->buf[h->pos];
    if (c == ';') {
        h->pos++;
        return CS_OK;
    }
    if (is_letter(c) || c == 0x1B)
        return CS_OK;
    char b[24];
    return fail(h, h->pos, CS_ERR_PARSE, "%s: unexpected %s in the parameters", mn,
                what_at(h, h->pos, b));
}

/* Skips an unsupported instruction's numeric parameters. */
static cs_err_t skip_params(hp_t *h, const char *mn)
{
    double v;
    size_t off;
    cs_err_t e = CS_OK;
    int r;
    while ((r = next_num(h, mn, &v, &off, &e)) == 1)
        ;
    return r < 0 ? e : end_instr(h, mn);
}

/* --- geometry ------------------------------------------------------------------------------ */

/* Plotter units -> cs_vec3_t in mm; CS_ERR_RANGE reported at off. */
static cs_err_t convert(hp_t *h, double x, double y, size_t off, cs_vec3_t *out)
{
    double px, py;
    cs_path_affine_point(&h->map, x, y, &px, &py);
    double mx = px / CS_HPGL_PLU_PER_MM, my = py / CS_HPGL_PLU_PER_MM;
    if (cs_conv_mm_to_vec(mx, my, 0.0, out) != CS_OK)
        return fail(h, off, CS_ERR_RANGE,
                    "point (%.6g, %.6g) plotter units = (%.6g, %.6g) mm is outside the accepted "
                    "range of +/-%d mm",
                    x, y, mx, my, CS_POS_LIMIT_MM);
    return CS_OK;
}

static bool drawing(hp_t *h, size_t off)
{
    if (h->pen != 0)
        return true;
    if (!h->warned_nopen) {
        h->warned_nopen = true;
        warn(h, off, "drawing with no pen selected (SP0): not drawn");
    }
    return false;
}

/* --- IW: the clipping window ------------------------------------------------------------- */

static bool in_window(const hp_t *h, const double p[3])
{
    /* half an LSB of slack: a point on the edge, rounded, is inside */
    double eps = 0.5 / CS_POS_ONE_MM;
    double x = p[0] * CS_HPGL_PLU_PER_MM, y = p[1] * CS_HPGL_PLU_PER_MM;
    return x >= h->win[0] - eps && x <= h->win[2] + eps && y >= h->win[1] - eps &&
           y <= h->win[3] + eps;
}

static bool in_window_at(const hp_t *h, const cs_bezier_t *c, double t)
{
    double p[3];
    cs_path_eval_mm(c, t, p);
    return in_window(h, p);
}

/* Appends c's piece over [t0, t1] (cs_bezier_split, each new point rounded once). */
static cs_err_t add_piece(hp_t *h, const cs_bezier_t *c, double t0, double t1, cs_path_kind_t kind,
                          size_t off)
{
    cs_bezier_t a = *c, b;
    cs_param_t q;
    if (t0 > 0 && cs_conv_to_param(t0, &q) == CS_OK && q > 0 && q < CS_PARAM_ONE &&
        cs_bezier_split(c, q, NULL, &a) != CS_OK)
        return fail(h, off, CS_ERR_RANGE, "IW: cannot clip this curve");
    double u = t0 > 0 ? (t1 - t0) / (1 - t0) : t1;
    if (u < 1 && cs_conv_to_param(u, &q) == CS_OK && q > 0 && q < CS_PARAM_ONE) {
        if (cs_bezier_split(&a, q, &b, NULL) != CS_OK)
            return fail(h, off, CS_ERR_RANGE, "IW: cannot clip this curve");
        a = b;
    }
    if (cs_path_add(h->path, &a, kind, loc_at(h, off)) != CS_OK)
        return fail(h, off, CS_ERR_FULL, "out of memory");
    return CS_OK;
}

/* The curve clipped to the window: the parameter runs inside it, found on a grid of
 * HP_CLIP_GRID and refined by bisection on the exact curve, each appended as its own piece;
 * anything cut away lifts the pen (a new subpath). */
#define HP_CLIP_GRID 64
static cs_err_t add_curve(hp_t *h, const cs_bezier_t *c, cs_path_kind_t kind, size_t off)
{
    if (!h->win_on) {
        if (cs_path_add(h->path, c, kind, loc_at(h, off)) != CS_OK)
            return fail(h, off, CS_ERR_FULL, "out of memory");
        return CS_OK;
    }
    bool in = in_window_at(h, c, 0.0);
    double start = 0.0; /* where the current inside run began */
    for (int k = 1; k <= HP_CLIP_GRID; k++) {
        double lo = (double)(k - 1) / HP_CLIP_GRID, hi = (double)k / HP_CLIP_GRID;
        bool now = in_window_at(h, c, hi);
        if (now != in) {
            for (int it = 0; it < 50; it++) { /* the crossing, bracketed: lo as before */
                double mid = (lo + hi) / 2;
                *(in_window_at(h, c, mid) == in ? &lo : &hi) = mid;
            }
            if (in) { /* leaving: the run ends at lo, the last point inside */
                cs_err_t e = add_piece(h, c, start, lo, kind, off);
                if (e != CS_OK)
                    return e;
            } else { /* entering at hi: a new stroke, the pen was lifted outside */
                cs_path_new_subpath(h->path);
                start = hi;
            }
            in = now;
        }
    }
    if (in)
        return add_piece(h, c, start, 1.0, kind, off);
    cs_path_new_subpath(h->path); /* the pen ends outside: whatever is drawn next starts anew */
    return CS_OK;
}

static cs_err_t emit(hp_t *h, cs_path_kind_t kind, unsigned degree, const cs_vec3_t *pts,
                     size_t off)
{
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = (uint8_t)degree;
    for (unsigned i = 0; i <= degree; i++) {
        c.p[i] = pts[i];
        c.w[i] = CS_WEIGHT_ONE;
    }
    return add_curve(h, &c, kind, off);
}

/* Moves the pen to (x, y) plotter units (absolute), drawing a line when the pen is down. A
 * pen-down move to the current point draws nothing (a dot has no path). */
static cs_err_t move_to(hp_t *h, double x, double y, size_t off)
{
    cs_vec3_t q[2];
    cs_err_t e = convert(h, x, y, off, &q[1]);
    if (e != CS_OK)
        return e;
    q[0] = h->cur;
    if (h->pen_down && drawing(h, off)) {
        if (q[0].x != q[1].x || q[0].y != q[1].y) {
            if ((e = emit(h, CS_PATH_LINE, 1, q, off)) != CS_OK)
                return e;
        }
    } else {
        cs_path_new_subpath(h->path);
    }
    h->x = x;
    h->y = y;
    h->cur = q[1];
    return CS_OK;
}

static int64_t lsb_dist(const cs_vec3_t *a, const cs_vec3_t *b)
{
    int64_t dx = (int64_t)a->x - b->x, dy = (int64_t)a->y - b->y;
    dx = dx < 0 ? -dx : dx;
    dy = dy < 0 ? -dy : dy;
    return dx > dy ? dx : dy;
}

/* The arc about centre (cx, cy) plotter units from the current point over sweep degrees
 * (positive = counter-clockwise; |sweep| >= 360 is one full turn). When draw is false the pen
 * only moves to the end. The current point becomes the arc's end. */
static cs_err_t arc(hp_t *h, double cx, double cy, double sweep, bool draw, size_t off)
{
    double ux = h->x - cx, uy = h->y - cy;
    bool full = fabs(sweep) >= 360.0;
    if (fabs(sweep) > 360.0 && !h->warned_big_sweep) {
        h->warned_big_sweep = true;
        warn(h, off, "arc sweep beyond 360 degrees: drawn as one full turn");
    }
    double r = sweep * (M_PI / 180.0);
    double cs = full ? 1.0 : cos(r), sn = full ? 0.0 : sin(r);
    /* End: C + U cos + V sin with V = U turned +90 degrees. */
    double ex = cx + ux * cs - uy * sn, ey = cy + uy * cs + ux * sn;
    cs_vec3_t endf;
    cs_err_t e = convert(h, ex, ey, off, &endf);
    if (e != CS_OK)
        return e;
    cs_vec3_t C, U, V;
    if ((e = convert(h, cx, cy, off, &C)) != CS_OK)
        return e;
    bool degenerate = (ux == 0.0 && uy == 0.0) || sweep == 0.0;
    if (!draw || !drawing(h, off))
        cs_path_new_subpath(h->path);
    if (!draw || degenerate || h->pen == 0) {
        /* Pen up, no pen, or an arc that is a point (radius 0, sweep 0): the pen just goes
         * to the end. */
        h->x = ex;
        h->y = ey;
        h->cur = endf;
        return CS_OK;
    }
    /* U and V through the linear part of the map: the image of the circle is the ellipse with
     * those conjugate semi-axes, exactly (an affine map of a rational Bézier is the Bézier of
     * the mapped points, same weights) */
    double mu[2], mv[2];
    cs_path_affine_vector(&h->map, ux, uy, &mu[0], &mu[1]);
    cs_path_affine_vector(&h->map, -uy, ux, &mv[0], &mv[1]);
    if (cs_conv_mm_to_vec(mu[0] / CS_HPGL_PLU_PER_MM, mu[1] / CS_HPGL_PLU_PER_MM, 0.0, &U) !=
            CS_OK ||
        cs_conv_mm_to_vec(mv[0] / CS_HPGL_PLU_PER_MM, mv[1] / CS_HPGL_PLU_PER_MM, 0.0, &V) != CS_OK)
        return fail(h, off, CS_ERR_RANGE, "arc radius too large for the +/-%d mm range",
                    CS_POS_LIMIT_MM);
    cs_param_t c1, s1;
    if (cs_conv_to_param(cs, &c1) != CS_OK || cs_conv_to_param(sn, &s1) != CS_OK)
        return fail(h, off, CS_ERR_RANGE, "arc direction not representable");
    if (!full && c1 == CS_PARAM_ONE && s1 == 0) {
        /* A sweep too small to turn the direction by one Q1.30 step would read as a full
         * turn; at any radius in range it is within an LSB of its chord. */
        bool pd = h->pen_down;
        h->pen_down = true;
        e = move_to(h, ex, ey, off);
        h->pen_down = pd;
        return e;
    }
    cs_bezier_t seg[CS_ARC_MAX_SEGMENTS];
    memset(seg, 0, sizeof seg);
    unsigned n = 0;
    e = cs_arc_build(&C, &U, &V, CS_PARAM_ONE, 0, c1, s1, sweep > 0.0, seg, &n);
    if (e != CS_OK)
        return fail(h, off, e == CS_ERR_OVERFLOW ? CS_ERR_RANGE : e, "arc cannot be built: %s",
                    cs_err_text(e));
    if (n < 1 || n > CS_ARC_MAX_SEGMENTS)
        return fail(h, off, CS_ERR_ARG, "arc builder returned %u pieces", n);
    if (lsb_dist(&seg[0].p[0], &h->cur) > HP_ARC_SNAP_MAX_LSB ||
        lsb_dist(&seg[n - 1].p[2], &endf) > HP_ARC_SNAP_MAX_LSB)
        return fail(h, off, CS_ERR_ARG, "arc builder's end points are off the arc's ends");
    seg[0].p[0] = h->cur; /* continuous to the LSB with the neighbours */
    seg[n - 1].p[2] = endf;
    for (unsigned i = 0; i < n; i++)
        if ((e = add_curve(h, &seg[i], CS_PATH_ARC, off)) != CS_OK)
            return e;
    h->x = ex;
    h->y = ey;
    h->cur = endf;
    return CS_OK;
}

/* --- instructions -------------------------------------------------------------------------- */

/* PU, PD, PA, PR: optional coordinate pairs, each interpreted in the current PA/PR mode. */
static cs_err_t pen_moves(hp_t *h, const char *mn)
{
    for (;;) {
        double a, b;
        size_t oa, ob;
        cs_err_t e = CS_OK;
        int r = next_num(h, mn, &a, &oa, &e);
        if (r < 0)
            return e;
        if (r == 0)
            break;
        r = next_num(h, mn, &b, &ob, &e);
        if (r < 0)
            return e;
        if (r == 0)
            return fail(h, oa, CS_ERR_PARSE, "%s: x without y (coordinates come in pairs)", mn);
        double x = h->relative ? h->x + a : a, y = h->relative ? h->y + b : b;
        if ((e = move_to(h, x, y, oa)) != CS_OK)
            return e;
    }
    return end_instr(h, mn);
}

/* Reads exactly the parameters an instruction needs (min..max); extras are an error. */
static cs_err_t get_params(hp_t *h, const char *mn, size_t mn_off, double *v, size_t *voff,
                           unsigned min, unsigned max, unsigned *n, const char *usage)
{
    *n = 0;
    for (;;) {
        double x;
        size_t off;
        cs_err_t e = CS_OK;
        int r = next_num(h, mn, &x, &off, &e);
        if (r < 0)
            return e;
        if (r == 0)
            break;
        if (*n >= max)
            return fail(h, off, CS_ERR_PARSE, "%s: too many parameters (%s)", mn, usage);
        v[*n] = x;
        voff[*n] = off;
        (*n)++;
    }
    if (*n < min)
        return fail(h, mn_off, CS_ERR_PARSE, "%s: too few parameters (%s)", mn, usage);
    return end_instr(h, mn);
}

/* --- scaling: SC, IP, IR, RO, PS (HP-GL/2 reference, "The Configuration and Status Group") -- */

/* The picture frame's size in the rotated coordinate system (RO 90 / 270 swap its sides). */
static void frame_rotated(const hp_t *h, double *w, double *fh)
{
    bool swap = h->ro == 90 || h->ro == 270;
    *w = swap ? h->frame[1] : h->frame[0];
    *fh = swap ? h->frame[0] : h->frame[1];
}

/* Default P1, P2: the lower-left and upper-right corners of the (rotated) frame. */
static void default_p1p2(hp_t *h)
{
    h->p1[0] = h->p1[1] = 0.0;
    frame_rotated(h, &h->p2[0], &h->p2[1]);
}

/* User units -> rotated plotter units by SC: type 0 P1..P2 anisotropic, type 1 isotropic
 * (the smaller factor, the extra space split left/bottom %), type 2 point factor. */
static cs_path_affine_t scale_map(const hp_t *h)
{
    cs_path_affine_t m = cs_path_affine_identity();
    if (!h->sc_on)
        return m;
    const double *v = h->sc;
    int type = (int)v[4];
    double sx, sy, ox = 0, oy = 0;
    if (type == 2) {
        sx = v[1];
        sy = v[3];
        m.a = sx;
        m.d = sy;
        m.e = h->p1[0] - v[0] * sx;
        m.f = h->p1[1] - v[2] * sy;
        return m;
    }
    sx = (h->p2[0] - h->p1[0]) / (v[1] - v[0]);
    sy = (h->p2[1] - h->p1[1]) / (v[3] - v[2]);
    if (type == 1) {
        double k = fmin(fabs(sx), fabs(sy));
        sx = copysign(k, sx);
        sy = copysign(k, sy);
        ox = ((h->p2[0] - h->p1[0]) - (v[1] - v[0]) * sx) * v[5] / 100.0;
        oy = ((h->p2[1] - h->p1[1]) - (v[3] - v[2]) * sy) * v[6] / 100.0;
    }
    m.a = sx;
    m.d = sy;
    m.e = h->p1[0] + ox - v[0] * sx;
    m.f = h->p1[1] + oy - v[2] * sy;
    return m;
}

/* Rotated plotter units -> physical (the unrotated frame, origin lower left): RO turns the
 * coordinate system counter-clockwise and shifts it so the frame stays in its first quadrant. */
static cs_path_affine_t rotate_map(const hp_t *h)
{
    cs_path_affine_t m = cs_path_affine_identity();
    double w = h->frame[0], fh = h->frame[1];
    if (h->ro == 90) { /* X = W - y, Y = x */
        m.a = 0, m.b = 1, m.c = -1, m.d = 0, m.e = w;
    } else if (h->ro == 180) { /* X = W - x, Y = H - y */
        m.a = -1, m.d = -1, m.e = w, m.f = fh;
    } else if (h->ro == 270) { /* X = y, Y = H - x */
        m.a = 0, m.b = -1, m.c = 1, m.d = 0, m.f = fh;
    }
    return m;
}

/* Rebuilds the map after a change of SC, P1/P2, RO or the frame. The pen does not move on the
 * paper: its user coordinates are recomputed through the new map's inverse. */
static void update_map(hp_t *h)
{
    double px, py;
    cs_path_affine_point(&h->map, h->x, h->y, &px, &py);
    h->map = cs_path_affine_mul(rotate_map(h), scale_map(h));
    const cs_path_affine_t *m = &h->map;
    double det = m->a * m->d - m->b * m->c;
    if (det != 0.0) {
        double dx = px - m->e, dy = py - m->f;
        h->x = (m->d * dx - m->c * dy) / det;
        h->y = (m->a * dy - m->b * dx) / det;
    }
}

/* IN (and the start): frame kept, no rotation, default P1/P2, no scaling, no window. */
static void reset_scaling(hp_t *h)
{
    h->ro = 0;
    h->sc_on = false;
    h->win_on = false;
    default_p1p2(h);
    update_map(h);
}

/* SC [xmin,xmax,ymin,ymax[,type[,left,bottom]]] */
static cs_err_t instr_sc(hp_t *h, const char *mn, size_t off)
{
    double v[7] = {0, 0, 0, 0, 0, 50, 50};
    size_t vo[7];
    unsigned n;
    const char *use = "SC xmin,xmax,ymin,ymax[,type[,left,bottom]]";
    cs_err_t e = get_params(h, mn, off, v, vo, 0, 7, &n, use);
    if (e != CS_OK)
        return e;
    if (n != 0 && n != 4 && n != 5 && n != 7)
        return fail(h, off, CS_ERR_PARSE, "SC: %u parameters (%s)", n, use);
    int type = (int)v[4];
    if (n >= 5 && (v[4] != type || type < 0 || type > 2))
        return fail(h, vo[4], CS_ERR_PARSE, "SC: type must be 0, 1 or 2");
    if (n && (type == 2 ? (v[1] == 0 || v[3] == 0) : (v[0] == v[1] || v[2] == v[3])))
        return fail(h, vo[0], CS_ERR_PARSE, "SC: %s",
                    type == 2 ? "a scale factor of 0" : "xmin = xmax or ymin = ymax");
    if (n == 7 && (v[5] < 0 || v[5] > 100 || v[6] < 0 || v[6] > 100))
        return fail(h, vo[5], CS_ERR_PARSE, "SC: left and bottom are percentages, 0..100");
    h->sc_on = n != 0;
    memcpy(h->sc, v, sizeof v);
    update_map(h);
    return CS_OK;
}

/* IP [p1x,p1y[,p2x,p2y]] (plotter units) and IR (percentages of the frame): P2 keeps its
 * offset from P1 when only P1 is given. */
static cs_err_t instr_ip(hp_t *h, const char *mn, size_t off, bool rel)
{
    double v[4];
    size_t vo[4];
    unsigned n;
    cs_err_t e = get_params(h, mn, off, v, vo, 0, 4, &n,
                            rel ? "IR p1x,p1y[,p2x,p2y] in %" : "IP p1x,p1y[,p2x,p2y]");
    if (e != CS_OK)
        return e;
    if (n == 1 || n == 3)
        return fail(h, off, CS_ERR_PARSE, "%s: coordinates come in pairs", mn);
    double w, fh;
    frame_rotated(h, &w, &fh);
    for (unsigned i = 0; rel && i < n; i++)
        v[i] = v[i] / 100.0 * (i % 2 ? fh : w);
    if (n == 0) {
        default_p1p2(h);
    } else {
        double d[2] = {h->p2[0] - h->p1[0], h->p2[1] - h->p1[1]};
        h->p1[0] = v[0];
        h->p1[1] = v[1];
        h->p2[0] = n == 4 ? v[2] : v[0] + d[0];
        h->p2[1] = n == 4 ? v[3] : v[1] + d[1];
    }
    update_map(h);
    return CS_OK;
}

/* RO [0|90|180|270]: P1 and P2 keep their coordinate values (they turn with the system). */
static cs_err_t instr_ro(hp_t *h, const char *mn, size_t off)
{
    double v[1] = {0};
    size_t vo[1];
    unsigned n;
    cs_err_t e = get_params(h, mn, off, v, vo, 0, 1, &n, "RO [0|90|180|270]");
    if (e != CS_OK)
        return e;
    if (v[0] != 0 && v[0] != 90 && v[0] != 180 && v[0] != 270)
        return fail(h, vo[0], CS_ERR_PARSE, "RO: the angle must be 0, 90, 180 or 270");
    h->ro = (int)v[0];
    update_map(h);
    return CS_OK;
}

/* PS [length[,width]]: the frame's size (plotter units); P1/P2 go to its corners. */
static cs_err_t instr_ps(hp_t *h, const char *mn, size_t off)
{
    double v[2];
    size_t vo[2];
    unsigned n;
    cs_err_t e = get_params(h, mn, off, v, vo, 0, 2, &n, "PS [length[,width]]");
    if (e != CS_OK)
        return e;
    if ((n >= 1 && !(v[0] > 0)) || (n == 2 && !(v[1] > 0)))
        return fail(h, vo[0], CS_ERR_PARSE, "PS: sizes must be positive plotter units");
    h->frame[0] = n >= 1 ? v[0] : CS_HPGL_FRAME_W;
    h->frame[1] = n == 2 ? v[1] : n == 1 ? h->frame[1] : CS_HPGL_FRAME_H;
    default_p1p2(h);
    update_map(h);
    return CS_OK;
}

/* IW [x0,y0,x1,y1] (current units): the window, kept on the paper (physical units). */
static cs_err_t instr_iw(hp_t *h, const char *mn, size_t off)
{
    double v[4];
    size_t vo[4];
    unsigned n;
    cs_err_t e = get_params(h, mn, off, v, vo, 0, 4, &n, "IW x0,y0,x1,y1");
    if (e != CS_OK)
        return e;
    if (n != 0 && n != 4)
        return fail(h, off, CS_ERR_PARSE, "IW: four numbers or none");
    h->win_on = n == 4;
    if (n == 4) {
        double ax, ay, bx, by;
        cs_path_affine_point(&h->map, v[0], v[1], &ax, &ay);
        cs_path_affine_point(&h->map, v[2], v[3], &bx, &by);
        h->win[0] = fmin(ax, bx);
        h->win[1] = fmin(ay, by);
        h->win[2] = fmax(ax, bx);
        h->win[3] = fmax(ay, by);
    }
    return CS_OK;
}

static void select_pen(hp_t *h, double v)
{
    h->pen = v < 1.0 ? 0 : (long)v;
    cs_path_new_subpath(h->path);
}

/* CI radius[,chord]: a full circle about the current point, drawn whatever the pen state
 * (the plotter lowers the pen for it), starting at angle 0 (180 for a negative radius) and
 * counter-clockwise; the pen then returns to the centre in its former state. The chord angle
 * is ignored: the circle is exact. */
static cs_err_t circle(hp_t *h, size_t mn_off)
{
    double v[2];
    size_t vo[2];
    unsigned n;
    cs_err_t e = get_params(h, "CI", mn_off, v, vo, 1, 2, &n, "CI radius[,chord angle]");
    if (e != CS_OK)
        return e;
    double cx = h->x, cy = h->y;
    cs_vec3_t centre = h->cur;
    if (v[0] == 0.0 || !drawing(h, mn_off))
        return CS_OK;
    cs_vec3_t start;
    if ((e = convert(h, cx + v[0], cy, vo[0], &start)) != CS_OK)
        return e;
    cs_path_new_subpath(h->path);
    h->x = cx + v[0];
    h->cur = start;
    bool pd = h->pen_down;
    e = arc(h, cx, cy, 360.0, true, vo[0]);
    h->pen_down = pd;
    cs_path_new_subpath(h->path);
    h->x = cx;
    h->y = cy;
    h->cur = centre;
    return e;
}

/* AA x,y,sweep[,chord] (centre absolute) and AR dx,dy,sweep[,chord] (centre relative to the
 * current point): the arc from the current point, + = counter-clockwise, drawn when the pen is
 * down; the pen ends on the arc's end. */
static cs_err_t arc_instr(hp_t *h, const char *mn, size_t mn_off, bool rel)
{
    double v[4];
    size_t vo[4];
    unsigned n;
    cs_err_t e =
        get_params(h, mn, mn_off, v, vo, 3, 4, &n,
                   rel ? "AR dx,dy,sweep angle[,chord angle]" : "AA x,y,sweep angle[,chord angle]");
    if (e != CS_OK)
        return e;
    double cx = rel ? h->x + v[0] : v[0], cy = rel ? h->y + v[1] : v[1];
    return arc(h, cx, cy, v[2], h->pen_down, vo[0]);
}

/* BZ (absolute) and BR (relative: every point of a curve relative to that curve's start):
 * cubic Béziers from the current point, control points in groups of three x,y pairs. */
static cs_err_t bezier(hp_t *h, const char *mn, bool rel)
{
    for (;;) {
        double v[6];
        size_t vo[6];
        unsigned k = 0;
        cs_err_t e = CS_OK;
        for (; k < 6; k++) {
            int r = next_num(h, mn, &v[k], &vo[k], &e);
            if (r < 0)
                return e;
            if (r == 0)
                break;
        }
        if (k == 0)
            break;
        if (k < 6)
            return fail(h, vo[0], CS_ERR_PARSE,
                        "%s: incomplete curve (%u of 6 numbers: control points come in groups of "
                        "three x,y pairs)",
                        mn, k);
        cs_vec3_t q[4];
        q[0] = h->cur;
        double px[3], py[3];
        for (unsigned i = 0; i < 3; i++) {
            px[i] = rel ? h->x + v[2 * i] : v[2 * i];
            py[i] = rel ? h->y + v[2 * i + 1] : v[2 * i + 1];
            if ((e = convert(h, px[i], py[i], vo[2 * i], &q[i + 1])) != CS_OK)
                return e;
        }
        if (h->pen_down && drawing(h, vo[0])) {
            if ((e = emit(h, CS_PATH_CUBIC, 3, q, vo[0])) != CS_OK)
                return e;
        } else {
            cs_path_new_subpath(h->path);
        }
        h->x = px[2];
        h->y = py[2];
        h->cur = q[3];
    }
    return end_instr(h, mn);
}

/* One PE value (HP-GL/2 polyline encoding): base-64 digits, least significant first, 63..126
 * continuing and 191..254 ending (base 32 in 7-bit mode: 63..94 and 95..126); other bytes are
 * ignored. The lowest bit of the result is the sign. 1 with *v set, 0 at ';'/end, -1 error. */
static int pe_value(hp_t *h, bool seven, int64_t *v, cs_err_t *e)
{
    uint64_t acc = 0;
    unsigned shift = 0, bits = seven ? 5u : 6u;
    size_t start = h->pos;
    while (h->pos < h->len) {
        unsigned char c = (unsigned char)h->buf[h->pos];
        if (c == ';')
            break;
        h->pos++;
        unsigned d;
        bool last;
        if (seven && c >= 63 && c <= 126) {
            last = c >= 95;
            d = last ? c - 95u : c - 63u;
        } else if (!seven && c >= 63 && c <= 126) {
            last = false;
            d = c - 63u;
        } else if (!seven && c >= 191 && c <= 254) {
            last = true;
            d = c - 191u;
        } else {
            continue;
        }
        if (shift > 36) {
            *e = fail(h, start, CS_ERR_RANGE, "PE: encoded number too long");
            return -1;
        }
        acc |= (uint64_t)d << shift;
        shift += bits;
        if (last) {
            int64_t m = (int64_t)(acc >> 1);
            *v = (acc & 1u) ? -m : m;
            return 1;
        }
    }
    if (shift > 0) {
        *e = fail(h, start, CS_ERR_PARSE, "PE: encoded number not terminated");
        return -1;
    }
    return 0;
}

/* Where a flag or a coordinate pair may start: the next instruction begins here. HP's reference
 * asks for ';' after PE, but AutoCAD's HP-GL/2 output ends it with the next mnemonic: two
 * letters followed by a byte no encoded value can hold next (a digit, ',', ';', a flag, a
 * blank, the end) -- the two letters then cannot be a value's digits, which need a terminating
 * digit (191..254, 95..126 in 7-bit mode) after their continuation digits. */
static bool pe_ends(const hp_t *h)
{
    size_t i = h->pos;
    if (i + 1 >= h->len || !is_letter(h->buf[i]) || !is_letter(h->buf[i + 1]))
        return false;
    if (i + 2 >= h->len)
        return true;
    unsigned char c = (unsigned char)h->buf[i + 2];
    return !((c >= 63 && c <= 126) || (c >= 191 && c <= 254));
}

/* PE: flags ':' pen, '<' next move pen up, '>' fractional bits, '=' next point absolute, '7'
 * 7-bit mode; coordinates are relative pen-down moves unless flagged. The pen state after PE is
 * that of its last move. */
static cs_err_t polyline_encoded(hp_t *h, size_t mn_off)
{
    bool seven = false, next_up = false, next_abs = false;
    int64_t frac = 0;
    cs_err_t e = CS_OK;
    for (;;) {
        while (h->pos < h->len && h->buf[h->pos] != ';' && !pe_ends(h)) {
            unsigned char c = (unsigned char)h->buf[h->pos];
            if ((c >= 63 && c <= 126) || (c >= 191 && c <= 254))
                break;
            h->pos++;
            size_t foff = h->pos - 1;
            int64_t v;
            int r;
            switch (c) {
            case ':':
                if ((r = pe_value(h, seven, &v, &e)) < 0)
                    return e;
                if (r == 0)
                    return fail(h, foff, CS_ERR_PARSE, "PE: pen flag ':' without a pen number");
                select_pen(h, (double)v);
                break;
            case '<':
                next_up = true;
                break;
            case '>':
                if ((r = pe_value(h, seven, &v, &e)) < 0)
                    return e;
                if (r == 0 || v < -26 || v > 26)
                    return fail(h, foff, CS_ERR_PARSE,
                                "PE: fractional-bits flag '>' needs a value in -26..26");
                frac = v;
                break;
            case '=':
                next_abs = true;
                break;
            case '7':
                seven = true;
                break;
            default:
                break; /* other bytes are ignored */
            }
        }
        if (h->pos >= h->len || h->buf[h->pos] == ';' || pe_ends(h))
            break;
        int64_t a, b;
        size_t off = h->pos;
        int r = pe_value(h, seven, &a, &e);
        if (r < 0)
            return e;
        if (r == 0)
            break;
        if ((r = pe_value(h, seven, &b, &e)) < 0)
            return e;
        if (r == 0)
            return fail(h, off, CS_ERR_PARSE, "PE: x without y (coordinates come in pairs)");
        double s = ldexp(1.0, (int)-frac), x = (double)a * s, y = (double)b * s;
        if (!next_abs) {
            x += h->x;
            y += h->y;
        }
        if (!(fabs(x) <= HP_NUM_MAX && fabs(y) <= HP_NUM_MAX))
            return fail(h, off, CS_ERR_RANGE, "PE: point outside the HP-GL/2 range");
        h->pen_down = !next_up;
        if ((e = move_to(h, x, y, off)) != CS_OK)
            return e;
        next_up = next_abs = false;
    }
    (void)mn_off;
    if (h->pos < h->len && h->buf[h->pos] == ';')
        h->pos++; /* ';' (or the next instruction, left in place) */
    return CS_OK;
}

/* Text up to the label terminator (LB, BL, WD): skipped, the terminator consumed. */
static void skip_label(hp_t *h)
{
    while (h->pos < h->len && h->buf[h->pos] != h->label_term)
        h->pos++;
    if (h->pos < h->len)
        h->pos++;
}

static void warn_mnemonic(hp_t *h, const char *mn, size_t off, const char *why);

/* Where a label's strokes go: plotter units -> path lines. */
typedef struct {
    hp_t *h;
    size_t off;
    cs_vec3_t prev;
    bool draw; /* a pen is selected (SP0: the label only moves the current point) */
} label_t;

static cs_err_t label_vertex(void *ctx, double x, double y, bool move)
{
    label_t *l = ctx;
    cs_vec3_t q[2];
    cs_err_t e = convert(l->h, x, y, l->off, &q[1]);
    if (e != CS_OK)
        return e;
    q[0] = l->prev;
    l->prev = q[1];
    if (!l->draw)
        return CS_OK;
    if (move) {
        cs_path_new_subpath(l->h->path);
        return CS_OK;
    }
    return emit(l->h, CS_PATH_LINE, 1, q, l->off);
}

/* LB text<terminator>: the label in the stroke font from the current point, the pen lowered for
 * its strokes whatever its state (as a plotter does); cap height = SI height (default 0.27 cm,
 * width 0.19 cm: the HP 7475A's defaults, HP 7475A Interfacing and Programming Manual, SI);
 * CR returns to the label's start, LF moves down two cap heights. The current point ends after
 * the last character (also with no pen selected, when nothing is drawn). Without a font the label is skipped with a warning. */
static cs_err_t label(hp_t *h, const char *mn, size_t off)
{
    size_t b = h->pos;
    skip_label(h);
    size_t e_ = h->pos > b && h->buf[h->pos - 1] == h->label_term ? h->pos - 1 : h->pos;
    if (h->o->font == NULL) {
        warn_mnemonic(h, mn, off, "labels are not drawn (no stroke font: --font FILE.jhf)");
        return CS_OK;
    }
    double hh = (h->si_h > 0 ? h->si_h : 0.27) * 10.0 * CS_HPGL_PLU_PER_MM;
    double ww = (h->si_w > 0 ? h->si_w : 0.19) * 10.0 * CS_HPGL_PLU_PER_MM;
    double sy = hh / CS_HERSHEY_CAP, sx = sy * (ww / hh) / (0.19 / 0.27);
    label_t l = {h, off, h->cur, drawing(h, off)};
    double x0 = h->x, x = h->x, y = h->y;
    for (size_t i = b; i < e_;) {
        size_t j = i;
        while (j < e_ && h->buf[j] != '\r' && h->buf[j] != '\n')
            j++;
        cs_err_t e =
            cs_hershey_layout(h->o->font, h->buf + i, j - i, x, y, sx, -sy, label_vertex, &l);
        if (e != CS_OK)
            return e;
        x += cs_hershey_width(h->o->font, h->buf + i, j - i) * sx;
        if (j < e_ && h->buf[j] == '\r')
            x = x0;
        else if (j < e_)
            y -= 2.0 * hh;
        i = j < e_ ? j + 1 : j;
    }
    cs_path_new_subpath(h->path);
    cs_vec3_t end;
    cs_err_t e = convert(h, x, y, off, &end);
    if (e == CS_OK) {
        h->x = x;
        h->y = y;
        h->cur = end;
    }
    return e;
}

/* What skipping an instruction costs the drawing, for its one warning. */
static const struct {
    const char *mn;
    const char *why;
} skipped[] = {
    {"EA", "rectangle outline not drawn: geometry is missing"},
    {"ER", "rectangle outline not drawn: geometry is missing"},
    {"EW", "wedge outline not drawn: geometry is missing"},
    {"RA", "filled rectangle not drawn (fills are not supported): geometry is missing"},
    {"RR", "filled rectangle not drawn (fills are not supported): geometry is missing"},
    {"WG", "filled wedge not drawn (fills are not supported): geometry is missing"},
    {"EP", "polygon edge instruction ignored: moves made in polygon mode are drawn as they come"},
    {"FP", "polygon fill ignored: moves made in polygon mode are drawn as outlines"},
    {"PM", "polygon mode ignored: pen-down moves inside it are drawn as ordinary lines (a "
           "polygon later filled or edged shows as its outline; one never used would not have "
           "been drawn by a plotter)"},
    {"LT", "line types ignored: dashed lines are drawn solid"},
    {"DF", "defaults: scaling (SC) and the window (IW) reset; text, fill and line type "
           "settings are not used here"},
    {"FT", "fill type ignored (fills are not drawn)"},
    {"PT", "pen thickness ignored"},
    {"PW", "pen width ignored"},
    {"VS", "velocity ignored (the planner sets speeds)"},
    {"SL", "text setting ignored (text is not drawn)"},
    {"SR", "relative character size ignored: labels use SI (absolute) sizes"},
    {"DI", "label direction ignored: labels are drawn horizontally"},
    {"DR", "label direction ignored: labels are drawn horizontally"},
    {"CS", "text setting ignored (text is not drawn)"},
    {"CA", "text setting ignored (text is not drawn)"},
    {"SA", "text setting ignored (text is not drawn)"},
    {"SS", "text setting ignored (text is not drawn)"},
    {"CP", "character plot ignored (text is not drawn): the pen does not move"},
};

static void warn_mnemonic(hp_t *h, const char *mn, size_t off, const char *why)
{
    size_t k = (size_t)(mn[0] - 'A') * 26 + (size_t)(mn[1] - 'A');
    if (h->warned[k])
        return;
    h->warned[k] = true;
    if (!why) {
        why = "not supported, skipped";
        for (size_t i = 0; i < sizeof skipped / sizeof skipped[0]; i++)
            if (strcmp(skipped[i].mn, mn) == 0)
                why = skipped[i].why;
    }
    warn(h, off, "%s: %s", mn, why);
}

/* ESC sequences (RS-232 device control "ESC . x ... :", PCL "ESC % n A|B", "ESC E"): skipped. */
static cs_err_t escape(hp_t *h)
{
    size_t off = h->pos++;
    if (!h->warned_esc) {
        h->warned_esc = true;
        warn(h, off, "device-control escape sequences skipped");
    }
    if (h->pos >= h->len)
        return CS_OK;
    char c = h->buf[h->pos++];
    if (c == 'E')
        return CS_OK;
    if (c == '%') {
        if (h->pos < h->len && (h->buf[h->pos] == '-' || h->buf[h->pos] == '+'))
            h->pos++;
        while (h->pos < h->len && is_digit(h->buf[h->pos]))
            h->pos++;
        if (h->pos < h->len && is_letter(h->buf[h->pos])) {
            h->pos++;
            return CS_OK;
        }
        return fail(h, off, CS_ERR_PARSE, "malformed escape sequence ESC %%");
    }
    if (c == '.') {
        if (h->pos >= h->len)
            return fail(h, off, CS_ERR_PARSE, "malformed escape sequence ESC .");
        char k = h->buf[h->pos++];
        if (k == '(' || k == ')' || k == 'Y' || k == 'Z' || k == 'K' || k == 'J' || k == 'R')
            return CS_OK;
        /* The others (ESC.@ .B .H .I .M .N .T and the queries) end with ':' when they have
         * parameters; those without end right after their letter. */
        size_t i = h->pos;
        while (i < h->len && (is_digit(h->buf[i]) || h->buf[i] == ';' || h->buf[i] == ' '))
            i++;
        if (i < h->len && h->buf[i] == ':')
            h->pos = i + 1;
        return CS_OK;
    }
    char b[24];
    return fail(h, off, CS_ERR_PARSE, "unknown escape sequence (ESC followed by %s)",
                what_at(h, h->pos - 1, b));
}

/* IN[n]: initialise: absolute, pen up, at the origin; default label terminator. */
static cs_err_t instr_in(hp_t *h, const char *mn, size_t off)
{
    double v[2];
    size_t vo[2];
    unsigned n;
    cs_err_t e = get_params(h, mn, off, v, vo, 0, 1, &n, "IN[n]");
    if (e != CS_OK)
        return e;
    h->relative = false;
    h->pen_down = false;
    h->label_term = HP_ETX;
    reset_scaling(h);
    return move_to(h, 0.0, 0.0, off);
}

/* SP[pen]: select a pen (SP0, SP: put it away). */
static cs_err_t instr_sp(hp_t *h, const char *mn, size_t off)
{
    double v[2];
    size_t vo[2];
    unsigned n;
    cs_err_t e = get_params(h, mn, off, v, vo, 0, 1, &n, "SP[pen]");
    if (e == CS_OK)
        select_pen(h, n ? v[0] : 0.0);
    return e;
}

/* SI w,h: character size in cm; SI; the default. */
static cs_err_t instr_si(hp_t *h, const char *mn, size_t off)
{
    double v[2];
    size_t vo[2];
    unsigned n;
    cs_err_t e = get_params(h, mn, off, v, vo, 0, 2, &n, "SI[width,height]");
    if (e != CS_OK)
        return e;
    if (n == 1)
        return fail(h, off, CS_ERR_PARSE, "SI: width and height, or none");
    h->si_w = n == 2 ? v[0] : 0;
    h->si_h = n == 2 ? v[1] : 0;
    return CS_OK;
}

/* DF: scaling off and the window gone, as IN does; P1, P2 and RO stay (HP-GL/2 reference, DF's
 * default-values table). */
static cs_err_t instr_df(hp_t *h, const char *mn, size_t off)
{
    warn_mnemonic(h, mn, off, NULL);
    h->sc_on = false;
    h->win_on = false;
    update_map(h);
    return skip_params(h, mn);
}

/* DT t[,mode]: the label terminator is the next character ("DT;" = ETX again). */
static cs_err_t instr_dt(hp_t *h, const char *mn)
{
    if (h->pos < h->len && h->buf[h->pos] != ';')
        h->label_term = h->buf[h->pos++];
    else
        h->label_term = HP_ETX;
    return skip_params(h, mn);
}

/* SM c: symbol mode with the next character as the symbol; "SM;" ends it. */
static cs_err_t instr_sm(hp_t *h, const char *mn, size_t off)
{
    warn_mnemonic(h, mn, off, "symbol mode ignored: no symbol is drawn at the points");
    if (h->pos < h->len && h->buf[h->pos] != ';' && !is_blank(h->buf[h->pos]))
        h->pos++;
    return end_instr(h, mn);
}

/* HP-GL/2 comment: CO "text". */
static cs_err_t instr_co(hp_t *h, const char *mn)
{
    skip_sep(h);
    if (h->pos < h->len && h->buf[h->pos] == '"') {
        size_t q = h->pos++;
        while (h->pos < h->len && h->buf[h->pos] != '"')
            h->pos++;
        if (h->pos >= h->len)
            return fail(h, q, CS_ERR_PARSE, "CO: comment string not closed");
        h->pos++;
    }
    return end_instr(h, mn);
}

static cs_err_t instruction(hp_t *h, const char *mn, size_t off)
{
    switch ((mn[0] << 8) | mn[1]) {
    case ('I' << 8) | 'N':
        return instr_in(h, mn, off);
    case ('P' << 8) | 'U':
        h->pen_down = false;
        cs_path_new_subpath(h->path);
        return pen_moves(h, mn);
    case ('P' << 8) | 'D':
        h->pen_down = true;
        return pen_moves(h, mn);
    case ('P' << 8) | 'A':
        h->relative = false;
        return pen_moves(h, mn);
    case ('P' << 8) | 'R':
        h->relative = true;
        return pen_moves(h, mn);
    case ('S' << 8) | 'P':
        return instr_sp(h, mn, off);
    case ('C' << 8) | 'I':
        return circle(h, off);
    case ('A' << 8) | 'A':
        return arc_instr(h, mn, off, false);
    case ('A' << 8) | 'R':
        return arc_instr(h, mn, off, true);
    case ('B' << 8) | 'Z':
        return bezier(h, mn, false);
    case ('B' << 8) | 'R':
        return bezier(h, mn, true);
    case ('P' << 8) | 'E':
        return polyline_encoded(h, off);
    case ('S' << 8) | 'C':
        return instr_sc(h, mn, off);
    case ('I' << 8) | 'P':
        return instr_ip(h, mn, off, false);
    case ('I' << 8) | 'R':
        return instr_ip(h, mn, off, true);
    case ('R' << 8) | 'O':
        return instr_ro(h, mn, off);
    case ('P' << 8) | 'S':
        return instr_ps(h, mn, off);
    case ('I' << 8) | 'W':
        return instr_iw(h, mn, off);
    case ('L' << 8) | 'B':
        return label(h, mn, off);
    case ('S' << 8) | 'I':
        return instr_si(h, mn, off);
    case ('B' << 8) | 'L':
    case ('W' << 8) | 'D':
        warn_mnemonic(h, mn, off, "text instruction skipped (text is not drawn)");
        skip_label(h);
        return CS_OK;
    case ('D' << 8) | 'F':
        return instr_df(h, mn, off);
    case ('D' << 8) | 'T':
        return instr_dt(h, mn);
    case ('S' << 8) | 'M':
        return instr_sm(h, mn, off);
    case ('C' << 8) | 'O':
        return instr_co(h, mn);
    default:
        warn_mnemonic(h, mn, off, NULL);
        return skip_params(h, mn);
    }
}

void cs_hpgl_opts_init(cs_hpgl_opts_t *o)
{
    memset(o, 0, sizeof *o);
}

cs_err_t cs_hpgl_read(const char *name, const char *buf, size_t len, const cs_hpgl_opts_t *opts,
                      cs_path_t *path, cs_path_diag_t *diag)
{
    cs_hpgl_opts_t defaults;
    if (!opts) {
        cs_hpgl_opts_init(&defaults);
        opts = &defaults;
    }
    hp_t *h = calloc(1, sizeof *h);
    if (!h) {
        cs_path_loc_t l = {"-", 0, 0};
        return cs_path_diag_set(diag, CS_ERR_FULL, l, "out of memory");
    }
    h->buf = buf;
    h->len = len;
    h->o = opts;
    h->path = path;
    h->diag = diag;
    h->loc_line = h->loc_col = 1;
    h->pen = 1; /* files that never say SP still draw */
    h->label_term = HP_ETX;
    h->map = cs_path_affine_identity();
    h->frame[0] = CS_HPGL_FRAME_W;
    h->frame[1] = CS_HPGL_FRAME_H;
    reset_scaling(h);
    h->file = cs_path_intern(path, name ? name : "-");
    cs_err_t e = CS_OK;
    if (!h->file) {
        cs_path_loc_t l = {"-", 0, 0};
        e = cs_path_diag_set(diag, CS_ERR_FULL, l, "out of memory");
    }
    cs_path_new_subpath(path);
    /* The plotter starts at the origin, pen up, absolute. */
    if (e == CS_OK)
        e = convert(h, 0.0, 0.0, 0, &h->cur);
    while (e == CS_OK && h->pos < len) {
        char c = buf[h->pos];
        if (is_blank(c) || c == ';') {
            h->pos++;
            continue;
        }
        if (c == 0x1B) {
            e = escape(h);
            continue;
        }
        size_t off = h->pos;
        if (!is_letter(c) || off + 1 >= len || !is_letter(buf[off + 1])) {
            char b[24];
            size_t at = is_letter(c) ? off + 1 : off;
            e = fail(h, at, CS_ERR_PARSE, "expected a two-letter instruction, found %s",
                     what_at(h, at, b));
            break;
        }
        char mn[3] = {upper(c), upper(buf[off + 1]), '\0'};
        h->pos += 2;
        e = instruction(h, mn, off);
    }
    free(h);
    return e;
}
