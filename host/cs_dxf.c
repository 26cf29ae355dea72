/* cs_dxf: AutoCAD DXF -> cs_path_t (see cs_dxf.h).
 * The file is first cut into its groups (code, value, line, column), then read in two passes:
 * the first finds the units ($INSUNITS), the layers that are off or frozen and the blocks; the
 * second draws ENTITIES, entering blocks through INSERT. Geometry is computed in double in the
 * entity's own coordinates and mapped to machine mm by one affine map (block inserts, object
 * coordinate system, units); every point is converted once to cs_pos_t, so the end of one piece
 * and the start of the next are the same point. Group codes and entity fields follow Autodesk's
 * "DXF Reference" (AutoCAD 2012 edition, ENTITIES and TABLES sections). */
#include "cs_dxf.h"

#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cs_arc.h"
#include "cs_conv.h"
#include "cs_err_text.h"
#include "cs_gnurbs.h"
#include "cs_readall.h"
#include "cs_spline.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Arc ends are moved onto the exact neighbouring point (as cs_hpgl does); beyond this many LSB
 * the builder disagrees with the arc and it is refused rather than bent. */
#define DX_ARC_SNAP_MAX_LSB 8
/* An ELLIPSE whose parameters span 2 pi to within this many radians is closed (writers that
 * print 6.283185); the gap left otherwise would be 1e-6 of the radius. */
#define DX_FULL_TURN_EPS 1e-6
/* Longest value text read as a number. */
#define DX_NUM_CHARS 64
/* Kinds of skipped entity remembered for their one warning. */
#define DX_MAX_WARNED 64
/* Longest text of one TEXT/MTEXT drawn (longer is cut, warned). */
#define DX_TEXT_MAX 4096
/* Binary DXF starts with this sentinel (DXF Reference, "Binary DXF Files"). */
static const char DX_BINARY[] = "AutoCAD Binary DXF";

typedef struct {
    size_t off;    /* value's first non-blank byte */
    uint32_t len;  /* value's length, blanks trimmed */
    int32_t code;  /* group code */
    uint32_t line; /* value's line (1-based) */
    uint32_t col;  /* value's column */
} dx_grp_t;

typedef struct {
    size_t name; /* group index of the name */
    bool frozen, off, warned;
} dx_layer_t;

typedef struct {
    size_t name;       /* group index of the name (code 2 of BLOCK) */
    size_t first, end; /* its entities: groups [first, end) */
    double bx, by;     /* base point */
} dx_block_t;

typedef struct {
    const char *buf;
    size_t len;
    const char *file;
    const cs_dxf_opts_t *o;
    cs_path_t *path;
    cs_path_diag_t *diag;
    dx_grp_t *g;
    size_t ng, capg;
    dx_layer_t *lay;
    size_t nlay, caplay;
    dx_block_t *blk;
    size_t nblk, capblk;
    double unit_mm;
    size_t stack[CS_DXF_MAX_DEPTH]; /* blocks being inserted, outermost first */
    unsigned depth;
    unsigned long long visits;
    char warned[DX_MAX_WARNED][48];
    unsigned nwarned;
    cs_gnurbs_t nb; /* a SPLINE's control points and knots */
    size_t emit_at; /* the SPLINE whose segments spline_emit adds */
} dx_t;

/* One entity's groups [i, end) (group i is its "0 TYPE") and the map to machine mm. */
typedef struct {
    size_t i, end;
    cs_path_affine_t m;
} dx_ent_t;

/* --- diagnostics ----------------------------------------------------------------------- */

static cs_path_loc_t loc_of(const dx_t *d, size_t gi)
{
    cs_path_loc_t l = {d->file, 1, 1};
    if (gi < d->ng) {
        l.line = d->g[gi].line;
        l.col = d->g[gi].col;
    }
    return l;
}

/* A located error at group gi: "file:line:col: reason" (cs_path_diag_set formats it). */
#define DX_FAIL(d, gi, code, ...)                                                                  \
    cs_path_diag_set((d)->diag, (code), loc_of((d), (gi)), __VA_ARGS__)

/* Hands one warning to the caller's function, or prints it. */
static void emit_warning(const dx_t *d, const cs_path_diag_t *w)
{
    if (d->o->warn)
        d->o->warn(d->o->warn_ctx, w);
    else
        cs_path_warn_print(stderr, w);
}

/* A located warning at group gi. */
#define DX_WARN(d, gi, ...)                                                                        \
    do {                                                                                           \
        cs_path_diag_t w_;                                                                         \
        cs_path_diag_set(&w_, CS_OK, loc_of((d), (gi)), __VA_ARGS__);                              \
        emit_warning((d), &w_);                                                                    \
    } while (0)

/* One warning per key (an entity kind or a topic): true the first time. */
static bool first_time(dx_t *d, const char *key)
{
    for (unsigned i = 0; i < d->nwarned; i++)
        if (strcmp(d->warned[i], key) == 0)
            return false;
    if (d->nwarned < DX_MAX_WARNED)
        snprintf(d->warned[d->nwarned++], sizeof d->warned[0], "%s", key);
    return true;
}

/* --- groups ---------------------------------------------------------------------------- */

static const char *val(const dx_t *d, size_t gi)
{
    return d->buf + d->g[gi].off;
}

/* Value of group gi equals s (case-sensitive, as DXF keywords are upper case). */
static bool is(const dx_t *d, size_t gi, const char *s)
{
    size_t n = strlen(s);
    return gi < d->ng && d->g[gi].len == n && memcmp(val(d, gi), s, n) == 0;
}

static bool same_name(const dx_t *d, size_t a, size_t b)
{
    return d->g[a].len == d->g[b].len && strncasecmp(val(d, a), val(d, b), d->g[a].len) == 0;
}

/* The value as printable text for messages (cut at 40 characters). */
static const char *shown(const dx_t *d, size_t gi, char out[48])
{
    size_t n = d->g[gi].len < 40 ? d->g[gi].len : 40;
    memcpy(out, val(d, gi), n);
    out[n] = '\0';
    return out;
}

/* Next line of buf from *pos: [*s, *e) without its CR/LF; false at the end of the buffer. */
static bool next_line(const dx_t *d, size_t *pos, size_t *s, size_t *e)
{
    if (*pos >= d->len)
        return false;
    *s = *pos;
    const char *nl = memchr(d->buf + *pos, '\n', d->len - *pos);
    size_t end = nl ? (size_t)(nl - d->buf) : d->len;
    *pos = nl ? end + 1 : d->len;
    if (end > *s && d->buf[end - 1] == '\r')
        end--;
    *e = end;
    return true;
}

static bool blank(char c)
{
    return c == ' ' || c == '\t' || c == '\r';
}

/* Cuts the file into groups: a code line (an integer, blanks around it allowed) then a value
 * line (blanks trimmed). */
static cs_err_t lex(dx_t *d)
{
    size_t pos = cs_readall_bom(d->buf, d->len), s, e;
    uint32_t line = 0;
    while (next_line(d, &pos, &s, &e)) {
        line++;
        while (s < e && blank(d->buf[s]))
            s++;
        while (e > s && blank(d->buf[e - 1]))
            e--;
        if (s == e && pos >= d->len)
            break; /* a blank last line */
        char num[16];
        size_t n = e - s;
        char *end = NULL;
        long code = -1;
        if (n > 0 && n < sizeof num) {
            memcpy(num, d->buf + s, n);
            num[n] = '\0';
            code = strtol(num, &end, 10);
        }
        cs_path_loc_t l = {d->file, line, 1};
        if (n == 0 || n >= sizeof num || *end != '\0' || code < 0 || code > 1071)
            return cs_path_diag_set(d->diag, CS_ERR_PARSE, l,
                                    "group code expected (an integer 0..1071), found '%.*s'",
                                    (int)(n < 40 ? n : 40), d->buf + s);
        size_t vs, ve;
        if (!next_line(d, &pos, &vs, &ve))
            return cs_path_diag_set(d->diag, CS_ERR_PARSE, l,
                                    "group code %ld has no value line (the file is cut short)",
                                    code);
        line++;
        uint32_t col = 1;
        while (vs < ve && blank(d->buf[vs])) {
            vs++;
            col++;
        }
        while (ve > vs && blank(d->buf[ve - 1]))
            ve--;
        if (d->ng == d->capg && !cs_path_grow((void **)&d->g, &d->capg, d->ng + 1, sizeof *d->g))
            return cs_path_diag_set(d->diag, CS_ERR_FULL, l, "out of memory");
        if (ve - vs > UINT32_MAX)
            return cs_path_diag_set(d->diag, CS_ERR_RANGE, l, "value line too long");
        dx_grp_t *g = &d->g[d->ng++];
        g->off = vs;
        g->len = (uint32_t)(ve - vs);
        g->code = (int32_t)code;
        g->line = line;
        g->col = col;
        if (code == 0 && g->len == 3 && memcmp(d->buf + vs, "EOF", 3) == 0)
            break; /* anything after EOF is not the drawing's */
    }
    return CS_OK;
}

/* Group gi as a number (finite, the whole value). */
static cs_err_t num(dx_t *d, size_t gi, double *v)
{
    char tmp[DX_NUM_CHARS + 1], b[48];
    size_t n = d->g[gi].len;
    char *end = NULL;
    if (n == 0 || n > DX_NUM_CHARS)
        return DX_FAIL(d, gi, CS_ERR_PARSE, "group %d: a number expected, found '%s'",
                       d->g[gi].code, shown(d, gi, b));
    memcpy(tmp, val(d, gi), n);
    tmp[n] = '\0';
    double x = strtod(tmp, &end);
    if (*end != '\0' || !isfinite(x))
        return DX_FAIL(d, gi, CS_ERR_PARSE, "group %d: a number expected, found '%s'",
                       d->g[gi].code, shown(d, gi, b));
    *v = x;
    return CS_OK;
}

/* Group gi as an integer within [lo, hi]. */
static cs_err_t inum(dx_t *d, size_t gi, long lo, long hi, long *v)
{
    double x;
    cs_err_t e = num(d, gi, &x);
    if (e != CS_OK)
        return e;
    if (x != floor(x) || x < (double)lo || x > (double)hi)
        return DX_FAIL(d, gi, CS_ERR_RANGE, "group %d: an integer %ld..%ld expected, found %g",
                       d->g[gi].code, lo, hi, x);
    *v = (long)x;
    return CS_OK;
}

/* A flag or enumeration value read as a number, as an integer: out-of-range values (no
 * meaning in DXF) are clamped first, so the conversion is always defined. */
static long flag(double v)
{
    return v > 1e9 ? 1000000000L : v < -1e9 ? -1000000000L : (long)v;
}

/* Index of the next group of code 0 at or after i (d->ng when none). */
static size_t next0(const dx_t *d, size_t i)
{
    while (i < d->ng && d->g[i].code != 0)
        i++;
    return i;
}

/* --- first pass: header, layers, blocks -------------------------------------------------- */

/* $INSUNITS (DXF Reference, HEADER variables): millimetres per unit; 0 for unitless. */
static double insunits_mm(long u)
{
    static const double mm[] = {
        0,
        25.4,
        304.8,
        1609344.0,
        1,
        10,
        1000,
        1e6,
        25.4e-6,
        0.0254,
        914.4,
        1e-7,
        1e-6,
        1e-3,
        100,
        1e4,
        1e5,
        1e12,
        1.495978707e14,
        9.4607304725808e18,
        3.0856775814913673e19,
        1200000.0 / 3937.0,        /* 21 US survey foot: 1200/3937 m */
        100000.0 / 3937.0,         /* 22 US survey inch */
        3600000.0 / 3937.0,        /* 23 US survey yard */
        1200000.0 / 3937.0 * 5280, /* 24 US survey mile */
    };
    return u >= 0 && u < (long)(sizeof mm / sizeof mm[0]) ? mm[u] : 0;
}

static cs_err_t read_header(dx_t *d, size_t i, size_t end)
{
    for (; i < end; i++) {
        if (d->g[i].code != 9 || !is(d, i, "$INSUNITS") || i + 1 >= end)
            continue;
        long u;
        cs_err_t e = inum(d, i + 1, 0, 1000, &u);
        if (e != CS_OK)
            return e;
        double mm = insunits_mm(u);
        if (mm == 0 && u != 0)
            DX_WARN(d, i + 1, "$INSUNITS %ld is not a known unit: read as millimetres", u);
        if (d->unit_mm == 0)
            d->unit_mm = mm;
    }
    return CS_OK;
}

/* LAYER table entries: 2 name, 62 colour (negative: off), 70 flags (bit 1: frozen). */
static cs_err_t read_layer(dx_t *d, size_t i, size_t end)
{
    dx_layer_t L = {0, false, false, false};
    bool named = false;
    for (size_t k = i + 1; k < end; k++) {
        long v;
        cs_err_t e = CS_OK;
        if (d->g[k].code == 2) {
            L.name = k;
            named = true;
        } else if (d->g[k].code == 62 && (e = inum(d, k, -32768, 32767, &v)) == CS_OK) {
            L.off = v < 0;
        } else if (d->g[k].code == 70 && (e = inum(d, k, -2147483648L, 2147483647L, &v)) == CS_OK) {
            L.frozen = (v & 1) != 0;
        }
        if (e != CS_OK)
            return e;
    }
    if (!named || !(L.off || L.frozen))
        return CS_OK; /* only hidden layers are remembered */
    if (d->nlay == d->caplay &&
        !cs_path_grow((void **)&d->lay, &d->caplay, d->nlay + 1, sizeof *d->lay))
        return DX_FAIL(d, i, CS_ERR_FULL, "out of memory");
    d->lay[d->nlay++] = L;
    return CS_OK;
}

/* BLOCK i .. ENDBLK: its name (2), base point (10, 20) and entities. Returns the index after
 * ENDBLK in *next. */
static cs_err_t read_block(dx_t *d, size_t i, size_t sec_end, size_t *next)
{
    dx_block_t b = {0, 0, 0, 0, 0};
    bool named = false;
    size_t hdr_end = next0(d, i + 1);
    for (size_t k = i + 1; k < hdr_end; k++) {
        cs_err_t e = CS_OK;
        if (d->g[k].code == 2) {
            b.name = k;
            named = true;
        } else if (d->g[k].code == 10) {
            e = num(d, k, &b.bx);
        } else if (d->g[k].code == 20) {
            e = num(d, k, &b.by);
        }
        if (e != CS_OK)
            return e;
    }
    size_t k = hdr_end;
    while (k < sec_end && !is(d, k, "ENDBLK"))
        k = next0(d, k + 1);
    b.first = hdr_end;
    b.end = k;
    *next = k < sec_end ? next0(d, k + 1) : sec_end;
    if (!named)
        return DX_FAIL(d, i, CS_ERR_PARSE, "BLOCK without a name (group 2)");
    if (d->nblk == d->capblk &&
        !cs_path_grow((void **)&d->blk, &d->capblk, d->nblk + 1, sizeof *d->blk))
        return DX_FAIL(d, i, CS_ERR_FULL, "out of memory");
    d->blk[d->nblk++] = b;
    return CS_OK;
}

static cs_err_t read_tables(dx_t *d, size_t i, size_t end)
{
    for (i = next0(d, i); i < end; i = next0(d, i + 1)) {
        if (is(d, i, "LAYER")) {
            cs_err_t e = read_layer(d, i, next0(d, i + 1));
            if (e != CS_OK)
                return e;
        }
    }
    return CS_OK;
}

static cs_err_t read_blocks(dx_t *d, size_t i, size_t end)
{
    i = next0(d, i);
    while (i < end) {
        if (!is(d, i, "BLOCK")) {
            i = next0(d, i + 1);
            continue;
        }
        cs_err_t e = read_block(d, i, end, &i);
        if (e != CS_OK)
            return e;
    }
    return CS_OK;
}

/* Layer of entity [i, end) hidden (off or frozen)? Warns once per layer. */
static bool layer_hidden(dx_t *d, size_t i, size_t end)
{
    size_t k = i + 1;
    while (k < end && d->g[k].code != 8)
        k++;
    if (k == end)
        return false;
    for (size_t j = 0; j < d->nlay; j++) {
        dx_layer_t *L = &d->lay[j];
        if (!same_name(d, L->name, k))
            continue;
        if (!L->warned) {
            char b[48];
            L->warned = true;
            DX_WARN(d, k, "layer '%s' is %s: its entities are not drawn", shown(d, L->name, b),
                    L->frozen ? "frozen" : "off");
        }
        return true;
    }
    return false;
}

/* --- geometry ------------------------------------------------------------------------------ */

/* Entity-space point -> machine cs_vec3_t; CS_ERR_RANGE reported at group gi. */
static cs_err_t conv(dx_t *d, const cs_path_affine_t *m, double x, double y, size_t gi,
                     cs_vec3_t *out)
{
    double px, py;
    cs_path_affine_point(m, x, y, &px, &py);
    if (cs_conv_mm_to_vec(px, py, 0.0, out) != CS_OK)
        return DX_FAIL(d, gi, CS_ERR_RANGE,
                       "point (%.6g, %.6g) = (%.6g, %.6g) mm is outside the accepted range of "
                       "+/-%d mm",
                       x, y, px, py, CS_POS_LIMIT_MM);
    return CS_OK;
}

static cs_err_t add(dx_t *d, const cs_bezier_t *c, cs_path_kind_t kind, size_t gi)
{
    if (cs_path_add(d->path, c, kind, loc_of(d, gi)) != CS_OK)
        return DX_FAIL(d, gi, d->path->over_limit ? CS_ERR_RANGE : CS_ERR_FULL,
                       d->path->over_limit ? "too many curves" : "out of memory");
    return CS_OK;
}

/* The line a -> b (nothing when they are the same point). */
static cs_err_t line(dx_t *d, const cs_vec3_t *a, const cs_vec3_t *b, size_t gi)
{
    if (a->x == b->x && a->y == b->y)
        return CS_OK;
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = 1;
    c.p[0] = *a;
    c.p[1] = *b;
    c.w[0] = c.w[1] = CS_WEIGHT_ONE;
    return add(d, &c, CS_PATH_LINE, gi);
}

static int64_t lsb_dist(const cs_vec3_t *a, const cs_vec3_t *b)
{
    int64_t dx = (int64_t)a->x - b->x, dy = (int64_t)a->y - b->y;
    dx = dx < 0 ? -dx : dx;
    dy = dy < 0 ? -dy : dy;
    return dx > dy ? dx : dy;
}

/* The conic C + U cos t + V sin t (entity space, mapped by m) for t from t0 over sweep radians
 * (positive: from U towards V; |sweep| >= 2 pi: a full turn), as exact rational pieces. a and b
 * are its converted end points (the neighbours' points); the pieces are snapped onto them. */
typedef struct {
    double cx, cy, ux, uy, vx, vy, t0, sweep;
} dx_conic_t;

static cs_err_t conic(dx_t *d, const cs_path_affine_t *m, const dx_conic_t *k, const cs_vec3_t *a,
                      const cs_vec3_t *b, size_t gi)
{
    bool full = fabs(k->sweep) >= 2 * M_PI;
    double t1 = k->t0 + k->sweep;
    cs_vec3_t C, U, V;
    double mu[2], mv[2];
    cs_path_affine_vector(m, k->ux, k->uy, &mu[0], &mu[1]);
    cs_path_affine_vector(m, k->vx, k->vy, &mv[0], &mv[1]);
    cs_err_t e = conv(d, m, k->cx, k->cy, gi, &C);
    if (e != CS_OK)
        return e;
    if (cs_conv_mm_to_vec(mu[0], mu[1], 0, &U) != CS_OK ||
        cs_conv_mm_to_vec(mv[0], mv[1], 0, &V) != CS_OK)
        return DX_FAIL(d, gi, CS_ERR_RANGE, "arc radius too large for the +/-%d mm range",
                       CS_POS_LIMIT_MM);
    if ((U.x == 0 && U.y == 0) || (V.x == 0 && V.y == 0))
        return full ? CS_OK : line(d, a, b, gi); /* below one LSB: a point, or its chord */
    cs_param_t c0, s0, c1, s1;
    if (cs_conv_to_param(cos(k->t0), &c0) != CS_OK || cs_conv_to_param(sin(k->t0), &s0) != CS_OK ||
        cs_conv_to_param(cos(full ? k->t0 : t1), &c1) != CS_OK ||
        cs_conv_to_param(sin(full ? k->t0 : t1), &s1) != CS_OK)
        return DX_FAIL(d, gi, CS_ERR_RANGE, "arc angle not representable");
    /* Start and end directions equal to the Q1.30 step: a sweep that small is within an LSB of
     * its chord; one that close to a full turn is a full turn (the builder's reading). */
    if (!full && c0 == c1 && s0 == s1 && fabs(k->sweep) < M_PI)
        return line(d, a, b, gi);
    cs_bezier_t seg[CS_ARC_MAX_SEGMENTS];
    memset(seg, 0, sizeof seg);
    unsigned n = 0;
    e = cs_arc_build(&C, &U, &V, c0, s0, c1, s1, k->sweep > 0, seg, &n);
    if (e == CS_ERR_DEGENERATE)
        return line(d, a, b, gi); /* flattened to a segment (a projected circle seen edge-on) */
    if (e != CS_OK)
        return DX_FAIL(d, gi, e == CS_ERR_OVERFLOW ? CS_ERR_RANGE : e, "arc cannot be built: %s",
                       cs_err_text(e));
    if (n < 1 || n > CS_ARC_MAX_SEGMENTS || lsb_dist(&seg[0].p[0], a) > DX_ARC_SNAP_MAX_LSB ||
        lsb_dist(&seg[n - 1].p[2], b) > DX_ARC_SNAP_MAX_LSB)
        return DX_FAIL(d, gi, CS_ERR_ARG, "arc builder's end points are off the arc's ends");
    seg[0].p[0] = *a;
    seg[n - 1].p[2] = *b;
    for (unsigned i = 0; i < n; i++)
        if ((e = add(d, &seg[i], CS_PATH_ARC, gi)) != CS_OK)
            return e;
    return CS_OK;
}

/* conic() from its own end points. */
static cs_err_t conic_alone(dx_t *d, const cs_path_affine_t *m, const dx_conic_t *k, size_t gi)
{
    bool full = fabs(k->sweep) >= 2 * M_PI;
    double t1 = full ? k->t0 : k->t0 + k->sweep;
    cs_vec3_t a, b;
    cs_err_t e = conv(d, m, k->cx + k->ux * cos(k->t0) + k->vx * sin(k->t0),
                      k->cy + k->uy * cos(k->t0) + k->vy * sin(k->t0), gi, &a);
    if (e == CS_OK)
        e = conv(d, m, k->cx + k->ux * cos(t1) + k->vx * sin(t1),
                 k->cy + k->uy * cos(t1) + k->vy * sin(t1), gi, &b);
    if (e != CS_OK)
        return e;
    cs_path_new_subpath(d->path);
    return conic(d, m, k, &a, &b, gi);
}

/* The segment from p (vertex point a) to q (b) with bulge = tan(sweep / 4), sweep positive
 * counter-clockwise (DXF Reference, LWPOLYLINE group 42). Centre = chord midpoint + left normal
 * * (1 - bulge^2) / (4 bulge) (the normal as long as the chord). */
static cs_err_t bulge_seg(dx_t *d, const cs_path_affine_t *m, const double p[2], const double q[2],
                          double bulge, const cs_vec3_t *a, const cs_vec3_t *b, size_t gi)
{
    double dx = q[0] - p[0], dy = q[1] - p[1];
    if (bulge == 0 || (dx == 0 && dy == 0))
        return line(d, a, b, gi);
    double f = (1 - bulge * bulge) / (4 * bulge);
    dx_conic_t k;
    k.cx = (p[0] + q[0]) / 2 - dy * f;
    k.cy = (p[1] + q[1]) / 2 + dx * f;
    k.ux = p[0] - k.cx;
    k.uy = p[1] - k.cy;
    k.vx = -k.uy; /* U turned +90 degrees: the circle's parametrisation */
    k.vy = k.ux;
    k.t0 = 0;
    k.sweep = 4 * atan(bulge);
    return conic(d, m, &k, a, b, gi);
}

/* --- entity fields --------------------------------------------------------------------------- */

/* Up to DX_FIELDS single-valued groups of an entity, by code (the first occurrence). */
#define DX_FIELDS 16
typedef struct {
    int code[DX_FIELDS];
    double v[DX_FIELDS];
    size_t at[DX_FIELDS]; /* group index, or SIZE_MAX when absent */
    unsigned n;
} dx_fields_t;

/* Reads the numeric codes listed (default values def) from entity [i, end). */
static cs_err_t fields(dx_t *d, size_t i, size_t end, const int *codes, const double *def,
                       unsigned n, dx_fields_t *f)
{
    f->n = n;
    for (unsigned j = 0; j < n; j++) {
        f->code[j] = codes[j];
        f->v[j] = def[j];
        f->at[j] = SIZE_MAX;
    }
    for (size_t k = i + 1; k < end; k++)
        for (unsigned j = 0; j < n; j++)
            if (d->g[k].code == codes[j] && f->at[j] == SIZE_MAX) {
                cs_err_t e = num(d, k, &f->v[j]);
                if (e != CS_OK)
                    return e;
                f->at[j] = k;
            }
    return CS_OK;
}

/* The object coordinate system's map onto XY for extrusion (nx, ny, nz) with elevation z
 * (DXF Reference, "Arbitrary Axis Algorithm"): Ax = (Wy or Wz) x N, Ay = N x Ax, normalised; a
 * point (x, y, z) of the OCS is x Ax + y Ay + z N in the world, seen from above. false when N is
 * zero or the plane is seen edge-on. */
static bool ocs_map(double nx, double ny, double nz, double z, cs_path_affine_t *o)
{
    double l = sqrt(nx * nx + ny * ny + nz * nz);
    if (!(l > 0))
        return false;
    nx /= l;
    ny /= l;
    nz /= l;
    double ax[3];
    if (fabs(nx) < 1.0 / 64 && fabs(ny) < 1.0 / 64) { /* Wy x N */
        ax[0] = nz;
        ax[1] = 0;
        ax[2] = -nx;
    } else { /* Wz x N */
        ax[0] = -ny;
        ax[1] = nx;
        ax[2] = 0;
    }
    double la = sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]);
    ax[0] /= la;
    ax[1] /= la;
    ax[2] /= la;
    double ay[3] = {ny * ax[2] - nz * ax[1], nz * ax[0] - nx * ax[2], nx * ax[1] - ny * ax[0]};
    o->a = ax[0];
    o->b = ax[1];
    o->c = ay[0];
    o->d = ay[1];
    o->e = nx * z;
    o->f = ny * z;
    return fabs(o->a * o->d - o->b * o->c) > 1e-9;
}

/* The entity's map: its extrusion (210, 220, 230) and elevation z composed onto en->m. false
 * (after a warning) when the entity cannot be drawn from above. */
static cs_err_t entity_ocs(dx_t *d, const dx_ent_t *en, double z, cs_path_affine_t *m, bool *ok)
{
    static const int codes[] = {210, 220, 230};
    static const double def[] = {0, 0, 1};
    dx_fields_t f;
    cs_err_t e = fields(d, en->i, en->end, codes, def, 3, &f);
    if (e != CS_OK)
        return e;
    *ok = true;
    *m = en->m;
    if (f.v[0] == 0 && f.v[1] == 0 && f.v[2] == 1)
        return CS_OK;
    size_t at = f.at[0] != SIZE_MAX ? f.at[0] : f.at[2];
    cs_path_affine_t o;
    if (!ocs_map(f.v[0], f.v[1], f.v[2], z, &o)) {
        *ok = false;
        if (first_time(d, "ocs-edge"))
            DX_WARN(d, at,
                    "extrusion (%g, %g, %g): the entity's plane is seen edge-on from above "
                    "(or the normal is zero): not drawn",
                    f.v[0], f.v[1], f.v[2]);
        return CS_OK;
    }
    if (!(f.v[0] == 0 && f.v[1] == 0) && first_time(d, "ocs-tilted"))
        DX_WARN(d, at,
                "extrusion (%g, %g, %g): an entity in a tilted plane is drawn projected "
                "onto XY (as seen from above)",
                f.v[0], f.v[1], f.v[2]);
    *m = cs_path_affine_mul(en->m, o);
    return CS_OK;
}

/* --- entities ------------------------------------------------------------------------------ */

static cs_err_t ent_line(dx_t *d, const dx_ent_t *en)
{
    static const int codes[] = {10, 20, 11, 21};
    static const double def[] = {0, 0, 0, 0};
    dx_fields_t f;
    cs_vec3_t a, b;
    cs_err_t e = fields(d, en->i, en->end, codes, def, 4, &f);
    if (e == CS_OK)
        e = conv(d, &en->m, f.v[0], f.v[1], en->i, &a);
    if (e == CS_OK)
        e = conv(d, &en->m, f.v[2], f.v[3], en->i, &b);
    if (e != CS_OK)
        return e;
    cs_path_new_subpath(d->path);
    return line(d, &a, &b, en->i);
}

/* CIRCLE (10, 20, 30 centre, 40 radius) and ARC (plus 50, 51: start and end angles in degrees,
 * counter-clockwise in the OCS). */
static cs_err_t ent_arc(dx_t *d, const dx_ent_t *en, bool is_arc)
{
    static const int codes[] = {10, 20, 30, 40, 50, 51};
    static const double def[] = {0, 0, 0, 0, 0, 360};
    dx_fields_t f;
    cs_path_affine_t m;
    bool ok;
    cs_err_t e = fields(d, en->i, en->end, codes, def, 6, &f);
    if (e == CS_OK)
        e = entity_ocs(d, en, f.v[2], &m, &ok);
    if (e != CS_OK || !ok)
        return e;
    double r = f.v[3];
    if (r < 0)
        return DX_FAIL(d, f.at[3], CS_ERR_PARSE, "negative radius %g", r);
    if (r == 0)
        return CS_OK;
    dx_conic_t k = {f.v[0], f.v[1], r, 0, 0, r, 0, 2 * M_PI};
    if (is_arc) {
        double a0 = fmod(f.v[4], 360.0), sw = fmod(f.v[5] - f.v[4], 360.0);
        if (sw <= 0)
            sw += 360.0; /* end before start: through 0; equal: a full turn */
        k.t0 = a0 * (M_PI / 180.0);
        k.sweep = sw >= 360.0 ? 2 * M_PI : sw * (M_PI / 180.0);
    }
    return conic_alone(d, &m, &k, en->i);
}

/* ELLIPSE: 10/20/30 centre, 11/21/31 major axis end (from the centre), 40 ratio minor/major,
 * 41/42 start/end parameters (radians), 210.. normal: minor axis = ratio * (N x major), all in
 * world coordinates (no OCS). */
static cs_err_t ent_ellipse(dx_t *d, const dx_ent_t *en)
{
    static const int codes[] = {10, 20, 11, 21, 31, 40, 41, 42, 210, 220, 230};
    static const double def[] = {0, 0, 1, 0, 0, 1, 0, 2 * M_PI, 0, 0, 1};
    dx_fields_t f;
    cs_err_t e = fields(d, en->i, en->end, codes, def, 11, &f);
    if (e != CS_OK)
        return e;
    double ux = f.v[2], uy = f.v[3], uz = f.v[4], ratio = f.v[5];
    double nx = f.v[8], ny = f.v[9], nz = f.v[10], nl = sqrt(nx * nx + ny * ny + nz * nz);
    if (!(ratio > 0)) /* above 1 (some writers) the "minor" axis is the longer: still exact */
        return DX_FAIL(d, f.at[5] != SIZE_MAX ? f.at[5] : en->i, CS_ERR_PARSE,
                       "ellipse ratio %g is not positive", ratio);
    if (!(nl > 0))
        return DX_FAIL(d, f.at[8] != SIZE_MAX ? f.at[8] : en->i, CS_ERR_PARSE,
                       "ellipse normal is zero");
    nx /= nl;
    ny /= nl;
    nz /= nl;
    if ((nx != 0 || ny != 0) && first_time(d, "ocs-tilted"))
        DX_WARN(d, f.at[8],
                "extrusion (%g, %g, %g): an entity in a tilted plane is drawn projected "
                "onto XY (as seen from above)",
                nx, ny, nz);
    dx_conic_t k;
    k.cx = f.v[0];
    k.cy = f.v[1];
    k.ux = ux;
    k.uy = uy;
    k.vx = ratio * (ny * uz - nz * uy);
    k.vy = ratio * (nz * ux - nx * uz);
    double t0 = f.v[6], t1 = f.v[7];
    double sw = fmod(t1 - t0, 2 * M_PI);
    if (sw <= 0)
        sw += 2 * M_PI;
    if (fabs(fabs(t1 - t0) - 2 * M_PI) < DX_FULL_TURN_EPS || sw > 2 * M_PI - DX_FULL_TURN_EPS)
        sw = 2 * M_PI; /* 6.283185 written with 6 decimals is a full turn */
    k.t0 = t0;
    k.sweep = sw;
    return conic_alone(d, &en->m, &k, en->i);
}

/* A polyline's vertices: points (entity space), bulges, and the group of each. */
typedef struct {
    double (*p)[2];
    double *bulge;
    size_t *at;
    size_t n, cap;
} dx_verts_t;

static cs_err_t vpush(dx_t *d, dx_verts_t *v, size_t gi)
{
    if (v->n == v->cap) {
        size_t c1 = v->cap, c2 = v->cap, c3 = v->cap;
        if (!cs_path_grow((void **)&v->p, &c1, v->n + 1, sizeof *v->p) ||
            !cs_path_grow((void **)&v->bulge, &c2, v->n + 1, sizeof *v->bulge) ||
            !cs_path_grow((void **)&v->at, &c3, v->n + 1, sizeof *v->at))
            return DX_FAIL(d, gi, CS_ERR_FULL, "out of memory");
        v->cap = c1 < c2 ? (c1 < c3 ? c1 : c3) : (c2 < c3 ? c2 : c3);
    }
    v->p[v->n][0] = v->p[v->n][1] = 0;
    v->bulge[v->n] = 0;
    v->at[v->n++] = gi;
    return CS_OK;
}

static void vfree(dx_verts_t *v)
{
    free(v->p);
    free(v->bulge);
    free(v->at);
}

/* Draws the vertices in order (closed: back to the first), bulges as arcs. */
static cs_err_t draw_verts(dx_t *d, const cs_path_affine_t *m, const dx_verts_t *v, bool closed)
{
    if (v->n == 0)
        return CS_OK;
    cs_path_new_subpath(d->path);
    cs_vec3_t first, a, b;
    cs_err_t e = conv(d, m, v->p[0][0], v->p[0][1], v->at[0], &first);
    a = first;
    size_t nseg = closed ? v->n : v->n - 1;
    for (size_t i = 0; e == CS_OK && i < nseg; i++) {
        size_t j = (i + 1) % v->n;
        e = j == 0 ? (b = first, CS_OK) : conv(d, m, v->p[j][0], v->p[j][1], v->at[j], &b);
        if (e == CS_OK)
            e = bulge_seg(d, m, v->p[i], v->p[j], v->bulge[i], &a, &b, v->at[i]);
        a = b;
    }
    return e;
}

/* LWPOLYLINE: 70 flags (bit 1 closed), 38 elevation, then per vertex 10, 20 and an optional
 * 42 bulge (for the segment from it to the next). Widths (40, 41, 43) are ignored. */
static cs_err_t ent_lwpoly(dx_t *d, const dx_ent_t *en)
{
    dx_verts_t v = {0};
    double flags = 0, elev = 0;
    bool wide = false;
    cs_err_t e = CS_OK;
    for (size_t k = en->i + 1; e == CS_OK && k < en->end; k++) {
        int c = d->g[k].code;
        if (c == 10 && (e = vpush(d, &v, k)) == CS_OK)
            e = num(d, k, &v.p[v.n - 1][0]);
        else if (c == 20 && v.n > 0)
            e = num(d, k, &v.p[v.n - 1][1]);
        else if (c == 42 && v.n > 0)
            e = num(d, k, &v.bulge[v.n - 1]);
        else if (c == 70)
            e = num(d, k, &flags);
        else if (c == 38)
            e = num(d, k, &elev);
        else if (c == 40 || c == 41 || c == 43) {
            double w = 0;
            e = num(d, k, &w);
            wide = wide || w != 0;
        }
    }
    cs_path_affine_t m;
    bool ok = false;
    if (e == CS_OK)
        e = entity_ocs(d, en, elev, &m, &ok);
    if (e == CS_OK && wide && first_time(d, "width"))
        DX_WARN(d, en->i,
                "polyline widths are not drawn: a wide polyline is drawn as its centre line");
    if (e == CS_OK && ok)
        e = draw_verts(d, &m, &v, (flag(flags) & 1) != 0);
    vfree(&v);
    return e;
}

/* POLYLINE, its VERTEXes and SEQEND (the old form, R12): 70 flags: 1 closed, 8 a 3-D polyline
 * (world coordinates, drawn from above), 16 a polygon mesh and 64 a polyface mesh (not drawn);
 * vertices flagged 16 (a spline's frame) are not drawn, as AutoCAD shows only the fitted curve.
 * *next: the group after SEQEND. */
static cs_err_t ent_polyline(dx_t *d, const dx_ent_t *en, bool draw, size_t *next)
{
    static const int codes[] = {70, 30};
    static const double def[] = {0, 0};
    dx_fields_t f;
    cs_err_t e = fields(d, en->i, en->end, codes, def, 2, &f);
    if (e != CS_OK)
        return e;
    long flags = flag(f.v[0]);
    dx_verts_t v = {0};
    size_t k = en->end;
    static const int vcodes[] = {10, 20, 42, 70};
    static const double vdef[] = {0, 0, 0, 0};
    while (e == CS_OK && k < d->ng && is(d, k, "VERTEX")) {
        size_t ke = next0(d, k + 1);
        dx_fields_t vf;
        e = fields(d, k, ke, vcodes, vdef, 4, &vf);
        if (e == CS_OK && !(flag(vf.v[3]) & 16) && (e = vpush(d, &v, k)) == CS_OK) {
            v.p[v.n - 1][0] = vf.v[0];
            v.p[v.n - 1][1] = vf.v[1];
            v.bulge[v.n - 1] = vf.v[2];
        }
        k = ke;
    }
    *next = is(d, k, "SEQEND") ? next0(d, k + 1) : k;
    if (e == CS_OK && !draw) {
        /* hidden: its vertices are skipped */
    } else if (e == CS_OK && (flags & (16 | 64))) {
        if (first_time(d, "POLYLINE-mesh"))
            DX_WARN(d, en->i,
                    "POLYLINE: polygon and polyface meshes are not drawn (3-D surfaces): "
                    "geometry is missing");
    } else if (e == CS_OK) {
        cs_path_affine_t m = en->m;
        bool ok = true;
        if (!(flags & 8))
            e = entity_ocs(d, en, f.v[1], &m, &ok);
        if (e == CS_OK && ok)
            e = draw_verts(d, &m, &v, (flags & 1) != 0);
    }
    vfree(&v);
    return e;
}

/* --- splines ------------------------------------------------------------------------------ */

static cs_err_t spline_emit(void *ctx, const cs_bezier_t *seg)
{
    dx_t *d = ctx;
    cs_path_kind_t kind = seg->rational ? CS_PATH_NURBS : CS_PATH_BSPLINE;
    return cs_path_add(d->path, seg, kind, loc_of(d, d->emit_at)) == CS_OK ? CS_OK : CS_ERR_FULL;
}

/* Inserts knot u once into the homogeneous control points pw (x w, y w, w) and knots kn of
 * degree p (Boehm; Piegl & Tiller, "The NURBS Book", A5.1 with r = 1). n points, n + p + 1
 * knots; the arrays have room for one more of each. */
static void knot_insert(double (*pw)[3], size_t *n, double *kn, unsigned p, double u)
{
    size_t s = p;
    while (s + 1 < *n && kn[s + 1] <= u)
        s++;
    for (size_t i = *n; i > s; i--) /* points after the span move up by one */
        memcpy(pw[i], pw[i - 1], sizeof pw[0]);
    for (size_t i = s; i >= s - p + 1 && i >= 1; i--) {
        double den = kn[i + p] - kn[i], a = den > 0 ? (u - kn[i]) / den : 0;
        for (int c = 0; c < 3; c++)
            pw[i][c] = a * pw[i][c] + (1 - a) * pw[i - 1][c];
        if (i == s - p + 1)
            break;
    }
    memmove(&kn[s + 2], &kn[s + 1], (*n + p - s) * sizeof *kn);
    kn[s + 1] = u;
    (*n)++;
}

static size_t mult(const double *kn, size_t nk, double u)
{
    size_t m = 0;
    for (size_t i = 0; i < nk; i++)
        m += kn[i] == u;
    return m;
}

/* An unclamped (periodic) knot vector made clamped over the same domain [kn[p], kn[n]], by
 * inserting each end knot until it is p-fold and dropping what lies outside: the curve is
 * unchanged. pw and kn must have room for 2p more entries. */
static void clamp_spline(double (*pw)[3], size_t *n, double *kn, unsigned p)
{
    double u0 = kn[p], u1 = kn[*n];
    while (mult(kn, *n + p + 1, u0) < p)
        knot_insert(pw, n, kn, p, u0);
    while (mult(kn, *n + p + 1, u1) < p)
        knot_insert(pw, n, kn, p, u1);
    size_t j0 = 0; /* last index of u0, minus p: the curve starts on point j0 */
    for (size_t i = 0; i < *n + p + 1; i++)
        if (kn[i] == u0)
            j0 = i;
    j0 -= p;
    size_t j1 = 0; /* first index of u1, minus 1: the curve ends on point j1 */
    while (kn[j1] != u1)
        j1++;
    j1--;
    size_t cnt = j1 - j0 + 1;
    memmove(pw, pw + j0, cnt * sizeof pw[0]);
    memmove(kn + 1, kn + j0 + 1, (cnt + p - 1) * sizeof *kn);
    kn[0] = u0;
    kn[cnt + p] = u1;
    *n = cnt;
}

static bool clamped(const double *kn, size_t n, unsigned p)
{
    for (size_t i = 1; i <= p; i++)
        if (kn[i] != kn[0] || kn[n + p - i] != kn[n + p])
            return false;
    return true;
}

/* Fit points only (74, 11/21): the natural cubic spline through them, chord-length parameter
 * (cs_spline); more than CS_SPLINE_MAX_POINTS: lines through them (warned). */
static cs_err_t spline_fit(dx_t *d, const dx_ent_t *en, const dx_verts_t *fp)
{
    cs_vec3_t pts[CS_SPLINE_MAX_POINTS];
    size_t n = 0;
    cs_err_t e = CS_OK;
    if (fp->n > CS_SPLINE_MAX_POINTS) {
        if (first_time(d, "SPLINE-fitmax"))
            DX_WARN(d, en->i,
                    "SPLINE with %zu fit points and no control points: drawn as lines "
                    "through them (at most %d are interpolated)",
                    fp->n, CS_SPLINE_MAX_POINTS);
        return draw_verts(d, &en->m, fp, false);
    }
    for (size_t i = 0; i < fp->n && e == CS_OK; i++) {
        e = conv(d, &en->m, fp->p[i][0], fp->p[i][1], fp->at[i], &pts[n]);
        if (e == CS_OK && (n == 0 || pts[n].x != pts[n - 1].x || pts[n].y != pts[n - 1].y))
            n++;
    }
    if (e != CS_OK || n < 2)
        return e;
    cs_spline_t *s = malloc(sizeof *s);
    if (!s)
        return DX_FAIL(d, en->i, CS_ERR_FULL, "out of memory");
    cs_path_new_subpath(d->path);
    e = cs_spline_solve(s, pts, n, CS_SPLINE_CHORD);
    cs_bezier_t c;
    for (size_t i = 0; e == CS_OK && i < cs_spline_segments(s); i++)
        if ((e = cs_spline_segment(s, i, &c)) == CS_OK)
            e = add(d, &c, CS_PATH_NATURAL, en->i);
    free(s);
    if (e != CS_OK && d->diag->reason[0] == '\0')
        return DX_FAIL(d, en->i, e, "SPLINE through its fit points: %s", cs_err_text(e));
    return e;
}

/* A SPLINE's groups: control points cp (10/20), fit points fp (11/21), knots kv (40) and weights
 * wv (41, in the .bulge of their dx_verts_t), degree 71. */
typedef struct {
    dx_verts_t cp, fp, kv, wv;
    double deg;
    size_t at_deg;
} dx_spline_t;

static cs_err_t spline_read(dx_t *d, const dx_ent_t *en, dx_spline_t *sp)
{
    cs_err_t e = CS_OK;
    sp->deg = 3;
    sp->at_deg = en->i;
    for (size_t k = en->i + 1; e == CS_OK && k < en->end; k++) {
        int c = d->g[k].code;
        if (c == 10 && (e = vpush(d, &sp->cp, k)) == CS_OK)
            e = num(d, k, &sp->cp.p[sp->cp.n - 1][0]);
        else if (c == 20 && sp->cp.n > 0)
            e = num(d, k, &sp->cp.p[sp->cp.n - 1][1]);
        else if (c == 11 && (e = vpush(d, &sp->fp, k)) == CS_OK)
            e = num(d, k, &sp->fp.p[sp->fp.n - 1][0]);
        else if (c == 21 && sp->fp.n > 0)
            e = num(d, k, &sp->fp.p[sp->fp.n - 1][1]);
        else if (c == 40 && (e = vpush(d, &sp->kv, k)) == CS_OK)
            e = num(d, k, &sp->kv.bulge[sp->kv.n - 1]);
        else if (c == 41 && (e = vpush(d, &sp->wv, k)) == CS_OK)
            e = num(d, k, &sp->wv.bulge[sp->wv.n - 1]);
        else if (c == 71 && (e = num(d, k, &sp->deg)) == CS_OK)
            sp->at_deg = k;
    }
    return e;
}

/* The knots and weights of a spline of degree p: counts, order, no break inside the domain,
 * positive weights, a finite non-empty domain. */
static cs_err_t spline_check(dx_t *d, const dx_ent_t *en, const dx_spline_t *sp, unsigned p)
{
    size_t n = sp->cp.n;
    const double *K = sp->kv.bulge, *W = sp->wv.bulge;
    if (sp->kv.n != n + p + 1)
        return DX_FAIL(d, sp->kv.n ? sp->kv.at[0] : en->i, CS_ERR_PARSE,
                       "SPLINE: %zu control points of degree %u need %zu knots (group 40), not "
                       "%zu",
                       n, p, n + p + 1, sp->kv.n);
    if (sp->wv.n != 0 && sp->wv.n != n)
        return DX_FAIL(d, sp->wv.at[0], CS_ERR_PARSE,
                       "SPLINE: %zu weights (group 41) for %zu control points", sp->wv.n, n);
    for (size_t i = 1; i < sp->kv.n; i++)
        if (!(K[i] >= K[i - 1]))
            return DX_FAIL(d, sp->kv.at[i], CS_ERR_PARSE,
                           "SPLINE: knot %g is below the one before it", K[i]);
    for (size_t i = p + 1, m = 1; i < n; i++) { /* interior knots: at most p-fold */
        m = K[i] == K[i - 1] ? m + 1 : 1;
        if (m > p && K[i] > K[p] && K[i] < K[n])
            return DX_FAIL(d, sp->kv.at[i], CS_ERR_PARSE,
                           "SPLINE: knot %g repeated %zu times: the curve is discontinuous there",
                           K[i], m);
    }
    for (size_t i = 0; i < sp->wv.n; i++)
        if (!(W[i] > 0))
            return DX_FAIL(d, sp->wv.at[i], CS_ERR_WEIGHT, "SPLINE: weight %g is not positive",
                           W[i]);
    if (!(K[n] > K[p]) || !isfinite(K[sp->kv.n - 1] - K[0]))
        return DX_FAIL(d, sp->kv.at[0], CS_ERR_PARSE,
                       "SPLINE: the knots span nothing (or more than a double holds)");
    return CS_OK;
}

/* Machine-space homogeneous control points pw (x w, y w, w; weights scaled to at most 1, which
 * leaves the curve as it is and nothing can overflow), clamped, into d->nb. */
static cs_err_t spline_load(dx_t *d, const dx_ent_t *en, const dx_spline_t *sp, unsigned p,
                            double (*pw)[3], double *kn)
{
    size_t n = sp->cp.n;
    double wmax = 0;
    for (size_t i = 0; i < sp->wv.n; i++)
        wmax = fmax(wmax, sp->wv.bulge[i]);
    for (size_t i = 0; i < n; i++) {
        double w = sp->wv.n ? sp->wv.bulge[i] / wmax : 1.0, x, y;
        cs_vec3_t chk; /* a point out of range is reported at its own group */
        cs_err_t e = conv(d, &en->m, sp->cp.p[i][0], sp->cp.p[i][1], sp->cp.at[i], &chk);
        if (e != CS_OK)
            return e;
        cs_path_affine_point(&en->m, sp->cp.p[i][0], sp->cp.p[i][1], &x, &y);
        pw[i][0] = x * w;
        pw[i][1] = y * w;
        pw[i][2] = w;
    }
    memcpy(kn, sp->kv.bulge, sp->kv.n * sizeof *kn);
    if (!clamped(kn, n, p))
        clamp_spline(pw, &n, kn, p);
    cs_gnurbs_begin(&d->nb, p + 1);
    cs_err_t e = CS_OK;
    for (size_t i = 0; e == CS_OK && i < n + p + 1; i++)
        e = cs_gnurbs_knot(&d->nb, kn[i]);
    for (size_t i = 0; e == CS_OK && i < n; i++) {
        double q[3] = {pw[i][0] / pw[i][2], pw[i][1] / pw[i][2], 0};
        e = cs_gnurbs_push(&d->nb, q, pw[i][2]);
    }
    if (e != CS_OK)
        return DX_FAIL(d, en->i, e, "SPLINE: %s",
                       e == CS_ERR_FULL ? "too many control points or out of memory"
                                        : cs_err_text(e));
    return CS_OK;
}

/* The checked spline of degree p through cs_gnurbs (the G-code NURBS blocks' converter). */
static cs_err_t spline_draw(dx_t *d, const dx_ent_t *en, const dx_spline_t *sp, unsigned p)
{
    size_t n = sp->cp.n;
    double(*pw)[3] = malloc((n + 2 * p + 2) * sizeof *pw); /* room for 2p insertions */
    double *kn = malloc((n + 3 * p + 3) * sizeof *kn);
    cs_err_t e = pw && kn ? spline_load(d, en, sp, p, pw, kn)
                          : DX_FAIL(d, en->i, CS_ERR_FULL, "out of memory");
    free(pw);
    free(kn);
    if (e != CS_OK)
        return e;
    char why[160];
    cs_path_new_subpath(d->path);
    d->emit_at = en->i;
    e = cs_gnurbs_build(&d->nb, spline_emit, d, why, sizeof why);
    if (e != CS_OK)
        return DX_FAIL(d, en->i, e == CS_ERR_FULL && d->path->over_limit ? CS_ERR_RANGE : e,
                       "SPLINE: %s", why);
    return CS_OK;
}

/* SPLINE: 70 flags, 71 degree, 40 knots, 41 weights, 10/20/30 control points; 11/21 fit
 * points when there are no control points. Degrees 4..25 are skipped (warned). */
static cs_err_t ent_spline(dx_t *d, const dx_ent_t *en)
{
    dx_spline_t sp;
    memset(&sp, 0, sizeof sp);
    cs_err_t e = spline_read(d, en, &sp);
    double deg = sp.deg;
    bool whole = deg == floor(deg);
    if (e != CS_OK) {
        /* the error is set */
    } else if (sp.cp.n == 0) {
        e = spline_fit(d, en, &sp.fp);
    } else if (!whole || deg < 1 || deg > 25) {
        e = DX_FAIL(d, sp.at_deg, CS_ERR_PARSE, "SPLINE degree %g is not an integer 1..25", deg);
    } else if (deg > CS_NURBS_MAX_DEGREE) {
        if (first_time(d, "SPLINE-degree"))
            DX_WARN(d, sp.at_deg,
                    "SPLINE of degree %g not drawn (curvestep converts degrees 1 to 3): geometry "
                    "is missing",
                    deg);
    } else if ((e = spline_check(d, en, &sp, (unsigned)deg)) == CS_OK) {
        e = spline_draw(d, en, &sp, (unsigned)deg);
    }
    vfree(&sp.cp);
    vfree(&sp.fp);
    vfree(&sp.kv);
    vfree(&sp.wv);
    return e;
}

/* --- text ------------------------------------------------------------------------------- */

typedef struct {
    dx_t *d;
    cs_path_affine_t m; /* text space (baseline along +x, y up) -> machine mm */
    size_t gi;
    cs_vec3_t prev;
} dx_label_t;

static cs_err_t text_vertex(void *ctx, double x, double y, bool move)
{
    dx_label_t *l = ctx;
    cs_vec3_t q;
    cs_err_t e = conv(l->d, &l->m, x, y, l->gi, &q);
    if (e != CS_OK)
        return e;
    cs_vec3_t a = l->prev;
    l->prev = q;
    if (move) {
        cs_path_new_subpath(l->d->path);
        return CS_OK;
    }
    return line(l->d, &a, &q, l->gi);
}

/* s[0..n) starts with an AutoCAD Unicode escape \U+XXXX (4 hex digits): its code point. */
static bool unicode_escape(const char *s, size_t n, unsigned long *cp)
{
    if (n < 7 || s[1] != 'U' || s[2] != '+')
        return false;
    char hex[5];
    memcpy(hex, s + 3, 4);
    hex[4] = '\0';
    char *end;
    *cp = strtoul(hex, &end, 16);
    return end == hex + 4 && hex[0] != '-' && hex[0] != '+' && hex[0] != ' ';
}

/* The text with AutoCAD's control codes resolved: %%d -> 'o' (degree sign), %%p -> "+-", %%c ->
 * 'O' (diameter), %%% -> '%', %%u %%o %%k dropped; \U+XXXX: the character (ASCII), 'o', "+-",
 * 'O' for the degree, plus-minus and diameter signs, '?' for the rest; for MTEXT also its format
 * codes
 * (\P and \n: new line; \~: space; \S a^b; -> a/b; \\ \{ \}: the character; {, }, and
 * \X...; switches such as \fArial|b0; \H2.5x; \C1; dropped). Lines end with '\n'. */
static size_t text_plain(const char *s, size_t n, bool mtext, char *out, size_t cap)
{
    size_t o = 0;
    for (size_t i = 0; i < n && o + 3 < cap;) {
        char c = s[i];
        if (c == '%' && i + 2 < n && s[i + 1] == '%') {
            char k = (char)(s[i + 2] | 0x20);
            const char *r = k == 'd'          ? "o"
                            : k == 'p'        ? "+-"
                            : k == 'c'        ? "O"
                            : s[i + 2] == '%' ? "%"
                                              : "";
            while (*r)
                out[o++] = *r++;
            i += 3;
            continue;
        }
        unsigned long cp;
        if (c == '\\' && unicode_escape(s + i, n - i, &cp)) { /* \U+00B0 */
            const char *r = cp == 0xB0                   ? "o"
                            : cp == 0xB1                 ? "+-"
                            : cp == 0xD8 || cp == 0x2205 ? "O"
                            : cp < 0x7F && cp >= 0x20    ? NULL
                                                         : "?";
            if (r)
                while (*r)
                    out[o++] = *r++;
            else
                out[o++] = (char)cp;
            i += 7;
            continue;
        }
        if (mtext && (c == '{' || c == '}')) {
            i++;
            continue;
        }
        if (mtext && c == '\\' && i + 1 < n) {
            char k = s[i + 1];
            i += 2;
            if (k == 'P' || k == 'n' || k == 'N')
                out[o++] = '\n';
            else if (k == '~')
                out[o++] = ' ';
            else if (k == '\\' || k == '{' || k == '}')
                out[o++] = k;
            else if (k == 'S') {
                while (i < n && s[i] != ';') {
                    out[o++] = s[i] == '^' || s[i] == '#' ? '/' : s[i];
                    i++;
                    if (o + 3 >= cap)
                        break;
                }
                i++;
            } else if (k == 'L' || k == 'l' || k == 'O' || k == 'o' || k == 'K' || k == 'k') {
                /* underline, overline, strike: no argument */
            } else {
                while (i < n && s[i] != ';')
                    i++;
                i++;
            }
            continue;
        }
        out[o++] = c;
        i++;
    }
    out[o] = '\0';
    return o;
}

/* Draws the lines of text (separated by '\n') in the stroke font: cap height h, width factor wf,
 * line pitch (baseline to baseline) pitch; halign 0 left, 1 centre, 2 right of x = 0; the first
 * baseline at y = y0, each next one pitch lower; m maps that space to machine mm. */
static cs_err_t text_lines(dx_t *d, const cs_path_affine_t *m, const char *t, size_t n, double h,
                           double wf, double pitch, int halign, double y0, size_t gi)
{
    const cs_hershey_font_t *font = d->o->font;
    double sy = h / CS_HERSHEY_CAP, sx = sy * wf;
    dx_label_t l = {d, *m, gi, {0, 0, 0}};
    double y = y0;
    for (size_t i = 0; i <= n;) {
        size_t j = i;
        while (j < n && t[j] != '\n')
            j++;
        double w = cs_hershey_width(font, t + i, j - i) * sx;
        double x = halign == 1 ? -w / 2 : halign == 2 ? -w : 0;
        cs_err_t e = cs_hershey_layout(font, t + i, j - i, x, y, sx, -sy, text_vertex, &l);
        if (e != CS_OK)
            return d->diag->reason[0] ? e : DX_FAIL(d, gi, e, "text: %s", cs_err_text(e));
        y -= pitch;
        i = j + 1;
    }
    cs_path_new_subpath(d->path);
    return CS_OK;
}

/* The text value (1, after any 3 chunks for MTEXT) gathered into out. */
static size_t text_value(dx_t *d, const dx_ent_t *en, bool mtext, char *out, size_t cap)
{
    char raw[DX_TEXT_MAX + 1];
    size_t n = 0, last = SIZE_MAX;
    for (size_t k = en->i + 1; k < en->end; k++) {
        int c = d->g[k].code;
        if (c == 1)
            last = k;
        if ((mtext && c == 3) || c == 1) {
            size_t len = d->g[k].len;
            if (len > DX_TEXT_MAX - n)
                len = DX_TEXT_MAX - n;
            memcpy(raw + n, val(d, k), len);
            n += len;
        }
    }
    if (last == SIZE_MAX)
        return 0;
    return text_plain(raw, n, mtext, out, cap);
}

static bool text_skipped(dx_t *d, const dx_ent_t *en)
{
    if (d->o->font)
        return false;
    if (first_time(d, "TEXT-font"))
        DX_WARN(d, en->i, "text is not drawn (no stroke font: --font FILE.jhf)");
    return true;
}

/* The map of a text's own space: rotation rot (degrees) about its point (x, y), mirrored by
 * the generation flags (2: backwards, 4: upside down). */
static cs_path_affine_t text_map(const cs_path_affine_t *m, double x, double y, double rot,
                                 long gen)
{
    double r = rot * (M_PI / 180.0), c = cos(r), s = sin(r);
    double fx = (gen & 2) ? -1 : 1, fy = (gen & 4) ? -1 : 1;
    cs_path_affine_t t = {c * fx, s * fx, -s * fy, c * fy, x, y};
    return cs_path_affine_mul(*m, t);
}

/* TEXT and ATTRIB: 10/20 point, 40 height, 1 text, 50 rotation, 41 width factor, 71
 * generation flags, 72 horizontal (0 left, 1 centre, 2 right, 3 aligned, 4 middle, 5 fit) and
 * 73 vertical (0 baseline, 1 bottom, 2 middle, 3 top) justification about 11/21. ATTRIB with
 * flag 70 bit 1 is invisible. */
static cs_err_t ent_text(dx_t *d, const dx_ent_t *en, bool attrib)
{
    static const int codes[] = {10, 20, 11, 21, 40, 50, 41, 71, 72, 73, 70, 30};
    static const double def[] = {0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 0, 0};
    dx_fields_t f;
    cs_path_affine_t m;
    bool ok;
    cs_err_t e = fields(d, en->i, en->end, codes, def, 12, &f);
    if (e == CS_OK)
        e = entity_ocs(d, en, f.v[11], &m, &ok);
    if (e != CS_OK || !ok || (attrib && (flag(f.v[10]) & 1)) || text_skipped(d, en))
        return e;
    char t[DX_TEXT_MAX + 8];
    size_t n = text_value(d, en, false, t, sizeof t);
    double h = f.v[4], wf = f.v[6] > 0 ? f.v[6] : 1, rot = f.v[5];
    long hj = flag(f.v[8]), vj = attrib ? 0 : flag(f.v[9]);
    double x = f.v[0], y = f.v[1];
    if ((hj != 0 || vj != 0) && f.at[2] != SIZE_MAX) {
        if (hj == 3 || hj == 5) { /* between the two points: width (and for 3 height) fit */
            double dx = f.v[2] - f.v[0], dy = f.v[3] - f.v[1], len = hypot(dx, dy);
            double w = d->o->font ? cs_hershey_width(d->o->font, t, n) * h / CS_HERSHEY_CAP : 0;
            if (len > 0 && w > 0) {
                rot = atan2(dy, dx) * (180.0 / M_PI);
                if (hj == 3)
                    h *= len / (w * wf);
                else
                    wf = len / w;
            }
            hj = 0;
            vj = 0;
        } else {
            x = f.v[2];
            y = f.v[3];
        }
    }
    if (!(h > 0) || n == 0)
        return CS_OK;
    double y0 = vj == 1 ? h * 0.3 : vj == 2 ? -h / 2 : vj == 3 ? -h : 0; /* bottom: descenders */
    int ha = hj == 1 || hj == 4 ? 1 : hj == 2 ? 2 : 0;
    if (hj == 4)
        y0 = -h / 2;
    cs_path_affine_t tm = text_map(&m, x, y, rot, flag(f.v[7]));
    return text_lines(d, &tm, t, n, h, wf, 0, ha, y0, en->i);
}

/* MTEXT: 10/20 point, 40 height, 71 attachment (1..9: top/middle/bottom x left/centre/right),
 * 50 rotation or 11/21 x direction, 44 line spacing factor (pitch 5/3 of the height), 1 and 3
 * text. Lines break only at \P (no word wrap at the width 41). */
static cs_err_t ent_mtext(dx_t *d, const dx_ent_t *en)
{
    static const int codes[] = {10, 20, 11, 21, 40, 50, 71, 44, 30};
    static const double def[] = {0, 0, 1, 0, 1, 0, 1, 1, 0};
    dx_fields_t f;
    cs_path_affine_t m;
    bool ok;
    cs_err_t e = fields(d, en->i, en->end, codes, def, 9, &f);
    if (e == CS_OK)
        e = entity_ocs(d, en, f.v[8], &m, &ok);
    if (e != CS_OK || !ok || text_skipped(d, en))
        return e;
    char t[DX_TEXT_MAX + 8];
    size_t n = text_value(d, en, true, t, sizeof t);
    double h = f.v[4];
    if (!(h > 0) || n == 0)
        return CS_OK;
    double rot = f.at[2] != SIZE_MAX ? atan2(f.v[3], f.v[2]) * (180.0 / M_PI) : f.v[5];
    long att = flag(f.v[6]);
    if (att < 1 || att > 9)
        att = 1;
    size_t lines = 1;
    for (size_t i = 0; i < n; i++)
        lines += t[i] == '\n';
    double pitch = h * 5.0 / 3.0 * (f.v[7] > 0 ? f.v[7] : 1);
    double total = h + (double)(lines - 1) * pitch;
    int row = (int)((att - 1) / 3), ha = (int)((att - 1) % 3);
    double y0 = row == 0 ? -h : row == 1 ? total / 2 - h : total - h;
    cs_path_affine_t tm = text_map(&m, f.v[0], f.v[1], rot, 0);
    return text_lines(d, &tm, t, n, h, 1, pitch, ha, y0, en->i);
}

/* SOLID and TRACE (corners 10, 11, 12, 13 in the OCS, filled in the order 1 2 4 3: the DXF
 * Reference's "bow tie") and 3DFACE (corners in the world, edges 1 2 3 4, 70 bits 1/2/4/8 hide
 * edges 1..4): the outline, as fills are drawn for SVG. A missing fourth corner is the third. */
static cs_err_t ent_face(dx_t *d, const dx_ent_t *en, bool face3d)
{
    static const int codes[] = {10, 20, 11, 21, 12, 22, 13, 23, 70, 30};
    static const double def[] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    dx_fields_t f;
    cs_path_affine_t m = en->m;
    bool ok = true;
    cs_err_t e = fields(d, en->i, en->end, codes, def, 10, &f);
    if (e == CS_OK && !face3d)
        e = entity_ocs(d, en, f.v[9], &m, &ok);
    if (e != CS_OK || !ok)
        return e;
    if (f.at[6] == SIZE_MAX) { /* a triangle */
        f.v[6] = f.v[4];
        f.v[7] = f.v[5];
    }
    static const int order_solid[] = {0, 1, 3, 2}, order_face[] = {0, 1, 2, 3};
    const int *ord = face3d ? order_face : order_solid;
    long hide = face3d ? flag(f.v[8]) : 0;
    cs_vec3_t q[4];
    for (int k = 0; k < 4 && e == CS_OK; k++)
        e = conv(d, &m, f.v[2 * ord[k]], f.v[2 * ord[k] + 1], en->i, &q[k]);
    if (e == CS_OK && first_time(d, "fill-outline"))
        DX_WARN(d, en->i, "filled SOLID/TRACE/3DFACE: fills are not drawn, their outline is");
    cs_path_new_subpath(d->path);
    for (int k = 0; k < 4 && e == CS_OK; k++) {
        if (hide & (1L << k)) {
            cs_path_new_subpath(d->path);
            continue;
        }
        e = line(d, &q[k], &q[(k + 1) % 4], en->i);
    }
    return e;
}

/* LEADER: its vertices (10, 20) as lines; the arrowhead is not drawn. */
static cs_err_t ent_leader(dx_t *d, const dx_ent_t *en)
{
    dx_verts_t v = {0};
    cs_err_t e = CS_OK;
    for (size_t k = en->i + 1; e == CS_OK && k < en->end; k++) {
        if (d->g[k].code == 10 && (e = vpush(d, &v, k)) == CS_OK)
            e = num(d, k, &v.p[v.n - 1][0]);
        else if (d->g[k].code == 20 && v.n > 0)
            e = num(d, k, &v.p[v.n - 1][1]);
    }
    if (e == CS_OK && first_time(d, "LEADER"))
        DX_WARN(d, en->i, "LEADER: drawn as its line; the arrowhead is not drawn");
    if (e == CS_OK)
        e = draw_verts(d, &en->m, &v, false);
    vfree(&v);
    return e;
}

static cs_err_t too_many(dx_t *d, size_t gi)
{
    return DX_FAIL(d, gi, CS_ERR_RANGE,
                   "more than %llu entities and block copies drawn: the drawing is too large",
                   CS_DXF_MAX_VISITS);
}

/* --- blocks -------------------------------------------------------------------------------- */

static cs_err_t draw_range(dx_t *d, size_t i, size_t end, const cs_path_affine_t *m);

static int find_block(const dx_t *d, size_t name_gi)
{
    for (size_t b = 0; b < d->nblk; b++)
        if (same_name(d, d->blk[b].name, name_gi))
            return (int)b;
    return -1;
}

/* Draws block b at map m (the block's own coordinates, base point already subtracted). */
static cs_err_t draw_block(dx_t *d, int b, const cs_path_affine_t *m, size_t gi)
{
    char nm[48];
    for (unsigned k = 0; k < d->depth; k++)
        if (d->stack[k] == (size_t)b)
            return DX_FAIL(d, gi, CS_ERR_RANGE, "block '%s' inserts itself (recursion)",
                           shown(d, d->blk[b].name, nm));
    if (d->depth >= CS_DXF_MAX_DEPTH)
        return DX_FAIL(d, gi, CS_ERR_RANGE, "blocks nested deeper than %d", CS_DXF_MAX_DEPTH);
    d->stack[d->depth++] = (size_t)b;
    cs_err_t e = draw_range(d, d->blk[b].first, d->blk[b].end, m);
    d->depth--;
    return e;
}

/* INSERT: 2 block, 10/20/30 point, 41/42 scale, 50 rotation, 70/71 columns/rows, 44/45 their
 * spacing (in the rotated block frame), in the insert's OCS. Each copy is
 * OCS * T(point) * R(rotation) * T(col * dx, row * dy) * S(sx, sy) * T(-base). */
static cs_err_t ent_insert(dx_t *d, const dx_ent_t *en, bool dimension)
{
    static const int codes[] = {10, 20, 30, 41, 42, 50, 70, 71, 44, 45};
    static const double def[] = {0, 0, 0, 1, 1, 0, 1, 1, 0, 0};
    dx_fields_t f;
    size_t name = en->i + 1;
    while (name < en->end && d->g[name].code != 2)
        name++;
    cs_err_t e = fields(d, en->i, en->end, codes, def, 10, &f);
    if (e != CS_OK)
        return e;
    char nm[48];
    int b = name < en->end ? find_block(d, name) : -1;
    if (b < 0) {
        if (dimension) {
            if (first_time(d, "DIMENSION"))
                DX_WARN(d, en->i, "DIMENSION without its block: not drawn");
            return CS_OK;
        }
        return name < en->end
                   ? DX_FAIL(d, name, CS_ERR_PARSE, "INSERT of block '%s', which is not defined",
                             shown(d, name, nm))
                   : DX_FAIL(d, en->i, CS_ERR_PARSE, "INSERT without a block name (group 2)");
    }
    if (dimension) /* the dimension's picture, in world coordinates */
        return draw_block(d, b, &en->m, en->i);
    cs_path_affine_t m;
    bool ok;
    if ((e = entity_ocs(d, en, f.v[2], &m, &ok)) != CS_OK || !ok)
        return e;
    double cols = f.v[6] < 1 ? 1 : f.v[6], rows = f.v[7] < 1 ? 1 : f.v[7];
    if (cols > CS_DXF_MAX_ARRAY || rows > CS_DXF_MAX_ARRAY)
        return DX_FAIL(d, f.at[cols > CS_DXF_MAX_ARRAY ? 6 : 7], CS_ERR_RANGE,
                       "INSERT array larger than %d", CS_DXF_MAX_ARRAY);
    double r = f.v[5] * (M_PI / 180.0), c = cos(r), s = sin(r);
    const dx_block_t *bk = &d->blk[b];
    for (long row = 0; row < (long)rows; row++)
        for (long col = 0; col < (long)cols; col++) {
            double ox = (double)col * f.v[8], oy = (double)row * f.v[9];
            cs_path_affine_t t = {c * f.v[3], s * f.v[3], -s * f.v[4], c * f.v[4], 0, 0};
            t.e = f.v[0] + c * (ox - f.v[3] * bk->bx) - s * (oy - f.v[4] * bk->by);
            t.f = f.v[1] + s * (ox - f.v[3] * bk->bx) + c * (oy - f.v[4] * bk->by);
            cs_path_affine_t mm = cs_path_affine_mul(m, t);
            if (++d->visits > CS_DXF_MAX_VISITS)
                return too_many(d, en->i);
            if ((e = draw_block(d, b, &mm, en->i)) != CS_OK)
                return e;
        }
    return CS_OK;
}

/* --- dispatch ------------------------------------------------------------------------------ */

/* What skipping a kind costs the drawing, for its one warning. */
static const struct {
    const char *kind;
    const char *why;
} skipped[] = {
    {"POINT", "points are not drawn (a dot has no path)"},
    {"HATCH", "hatches and fills are not drawn: their boundaries and pattern lines are missing"},
    {"IMAGE", "raster images are not drawn"},
    {"WIPEOUT", "wipeouts are not applied: what they mask is drawn"},
    {"XLINE", "construction lines (infinite) are not drawn"},
    {"RAY", "rays (half-infinite lines) are not drawn"},
    {"MLINE", "multilines are not drawn: geometry is missing"},
    {"REGION", "regions (ACIS solids) are not drawn: geometry is missing"},
    {"3DSOLID", "3-D solids (ACIS) are not drawn: geometry is missing"},
    {"BODY", "ACIS bodies are not drawn: geometry is missing"},
    {"MESH", "meshes are not drawn: geometry is missing"},
    {"TOLERANCE", "geometric tolerance frames are not drawn: geometry is missing"},
    {"SHAPE", "shapes (SHX) are not drawn: geometry is missing"},
    {"HELIX", "helices are not drawn: geometry is missing"},
    {"ACAD_TABLE", "tables are not drawn: geometry is missing"},
    {"OLE2FRAME", "OLE objects are not drawn"},
};

static void skip_kind(dx_t *d, size_t i)
{
    char kind[48];
    shown(d, i, kind);
    if (!first_time(d, kind))
        return;
    const char *why = "not supported: not drawn (geometry may be missing)";
    for (size_t k = 0; k < sizeof skipped / sizeof skipped[0]; k++)
        if (strcmp(skipped[k].kind, kind) == 0)
            why = skipped[k].why;
    DX_WARN(d, i, "%s: %s", kind, why);
}

/* Skips the entity when it is invisible (60 = 1), in paper space (67 = 1) or on a hidden layer. */
static cs_err_t hidden(dx_t *d, const dx_ent_t *en, bool *h)
{
    static const int codes[] = {60, 67};
    static const double def[] = {0, 0};
    dx_fields_t f;
    cs_err_t e = fields(d, en->i, en->end, codes, def, 2, &f);
    *h = false;
    if (e != CS_OK)
        return e;
    if (f.v[1] == 1) {
        if (first_time(d, "paper"))
            DX_WARN(d, en->i, "paper-space entities are not drawn (model space only)");
        *h = true;
    } else {
        *h = f.v[0] == 1 || layer_hidden(d, en->i, en->end);
    }
    return CS_OK;
}

static cs_err_t entity(dx_t *d, dx_ent_t *en, size_t *next)
{
    bool h;
    cs_err_t e = hidden(d, en, &h);
    *next = en->end;
    if (e != CS_OK)
        return e;
    if (is(d, en->i, "POLYLINE")) {
        return ent_polyline(d, en, !h, next); /* consumes its vertices, even when hidden */
    }
    if (h)
        return CS_OK;
    if (++d->visits > CS_DXF_MAX_VISITS)
        return too_many(d, en->i);
    if (is(d, en->i, "LINE"))
        return ent_line(d, en);
    if (is(d, en->i, "CIRCLE") || is(d, en->i, "ARC"))
        return ent_arc(d, en, is(d, en->i, "ARC"));
    if (is(d, en->i, "ELLIPSE"))
        return ent_ellipse(d, en);
    if (is(d, en->i, "LWPOLYLINE"))
        return ent_lwpoly(d, en);
    if (is(d, en->i, "SPLINE"))
        return ent_spline(d, en);
    if (is(d, en->i, "TEXT") || is(d, en->i, "ATTRIB"))
        return ent_text(d, en, is(d, en->i, "ATTRIB"));
    if (is(d, en->i, "MTEXT"))
        return ent_mtext(d, en);
    if (is(d, en->i, "INSERT"))
        return ent_insert(d, en, false);
    if (is(d, en->i, "DIMENSION") || is(d, en->i, "ARC_DIMENSION") ||
        is(d, en->i, "LARGE_RADIAL_DIMENSION"))
        return ent_insert(d, en, true);
    if (is(d, en->i, "LEADER"))
        return ent_leader(d, en);
    if (is(d, en->i, "SOLID") || is(d, en->i, "TRACE") || is(d, en->i, "3DFACE"))
        return ent_face(d, en, is(d, en->i, "3DFACE"));
    if (is(d, en->i, "SEQEND") || is(d, en->i, "VIEWPORT") || is(d, en->i, "VERTEX") ||
        is(d, en->i, "ATTDEF"))
        return CS_OK; /* an INSERT's attributes end; paper-space viewports; stray vertices;
                       * attribute definitions (a block shows its INSERT's ATTRIB values) */
    skip_kind(d, en->i);
    return CS_OK;
}

/* Draws the entities of groups [i, end) with map m. */
static cs_err_t draw_range(dx_t *d, size_t i, size_t end, const cs_path_affine_t *m)
{
    i = next0(d, i);
    while (i < end) {
        dx_ent_t en = {i, next0(d, i + 1), *m};
        if (en.end > end)
            en.end = end;
        size_t next;
        cs_err_t e = entity(d, &en, &next);
        if (e != CS_OK)
            return e;
        i = next;
    }
    return CS_OK;
}

/* --- sections --------------------------------------------------------------------------------- */

/* Finds each section: 0 SECTION, 2 name, ..., 0 ENDSEC. fn gets [first group, end). */
typedef cs_err_t (*dx_section_fn)(dx_t *d, size_t i, size_t end);

static cs_err_t each_section(dx_t *d, const char *name, dx_section_fn fn)
{
    for (size_t i = 0; i < d->ng; i = next0(d, i + 1)) {
        if (d->g[i].code != 0 || !is(d, i, "SECTION"))
            continue;
        size_t end = next0(d, i + 1);
        while (end < d->ng && !is(d, end, "ENDSEC"))
            end = next0(d, end + 1);
        if (i + 1 < d->ng && d->g[i + 1].code == 2 && is(d, i + 1, name)) {
            cs_err_t e = fn(d, i + 2, end);
            if (e != CS_OK)
                return e;
        }
        i = end;
    }
    return CS_OK;
}

static cs_err_t read_entities(dx_t *d, size_t i, size_t end)
{
    cs_path_affine_t m = cs_path_affine_identity();
    m.a = m.d = d->unit_mm;
    d->depth = 0;
    return draw_range(d, i, end, &m);
}

void cs_dxf_opts_init(cs_dxf_opts_t *o)
{
    memset(o, 0, sizeof *o);
}

/* Line i of buf[0..len) from *pos, blanks trimmed: [*s, *e); false at the end. */
static bool sniff_line(const char *buf, size_t len, size_t *pos, size_t *s, size_t *e)
{
    if (*pos >= len)
        return false;
    size_t a = *pos, b = a;
    while (b < len && buf[b] != '\n')
        b++;
    *pos = b < len ? b + 1 : len;
    while (a < b && blank(buf[a]))
        a++;
    while (b > a && blank(buf[b - 1]))
        b--;
    *s = a;
    *e = b;
    return true;
}

bool cs_dxf_is(const char *buf, size_t len)
{
    size_t pos = cs_readall_bom(buf, len), s, e, vs, ve;
    if (len - pos >= sizeof DX_BINARY - 1 &&
        memcmp(buf + pos, DX_BINARY, sizeof DX_BINARY - 1) == 0)
        return true;
    /* group pairs: any 999 comments (LibreCAD starts with one), then 0 / SECTION */
    for (int k = 0; k < 8 && sniff_line(buf, len, &pos, &s, &e); k++) {
        if (!sniff_line(buf, len, &pos, &vs, &ve))
            return false;
        if (e - s == 3 && memcmp(buf + s, "999", 3) == 0)
            continue;
        return e - s == 1 && buf[s] == '0' && ve - vs == 7 && memcmp(buf + vs, "SECTION", 7) == 0;
    }
    return false;
}

/* Does the last 0/SECTION lack its 0/ENDSEC? */
static bool cut_short(const dx_t *d)
{
    for (size_t i = d->ng; i-- > 0;)
        if (d->g[i].code == 0 && (is(d, i, "ENDSEC") || is(d, i, "SECTION")))
            return is(d, i, "SECTION");
    return false;
}

static cs_err_t dxf_run(dx_t *d)
{
    size_t b = cs_readall_bom(d->buf, d->len);
    if (d->len - b >= sizeof DX_BINARY - 1 &&
        memcmp(d->buf + b, DX_BINARY, sizeof DX_BINARY - 1) == 0) {
        cs_path_loc_t l = {d->file, 1, 1};
        return cs_path_diag_set(d->diag, CS_ERR_PARSE, l,
                                "binary DXF is not read: save the drawing as ASCII DXF");
    }
    cs_err_t e = lex(d);
    /* A file cut short in transfer still parses up to its cut: draw it, but say so. The sign:
     * its last section never ends (a file that only lacks its closing 0/EOF is whole). */
    if (e == CS_OK && cut_short(d))
        DX_WARN(d, d->ng - 1, "the file ends inside a section (no 0/ENDSEC): it may be cut "
                              "short (drawn as far as it goes)");
    if (e == CS_OK)
        e = each_section(d, "HEADER", read_header);
    if (e == CS_OK && d->unit_mm == 0) {
        d->unit_mm = 1;
        cs_path_loc_t l = {d->file, 1, 1};
        cs_path_diag_t w;
        cs_path_diag_set(&w, CS_OK, l, "%s",
                         "the drawing has no units ($INSUNITS unitless or absent): one unit is "
                         "read as 1 mm (--units mm|inch says otherwise)");
        emit_warning(d, &w);
    }
    if (e == CS_OK)
        e = each_section(d, "TABLES", read_tables);
    if (e == CS_OK)
        e = each_section(d, "BLOCKS", read_blocks);
    if (e == CS_OK)
        e = each_section(d, "ENTITIES", read_entities);
    return e;
}

cs_err_t cs_dxf_read(const char *name, const char *buf, size_t len, const cs_dxf_opts_t *opts,
                     cs_path_t *path, cs_path_diag_t *diag)
{
    cs_dxf_opts_t defaults;
    if (!opts) {
        cs_dxf_opts_init(&defaults);
        opts = &defaults;
    }
    dx_t *d = calloc(1, sizeof *d);
    if (!d) {
        cs_path_loc_t l = {"-", 0, 0};
        return cs_path_diag_set(diag, CS_ERR_FULL, l, "out of memory");
    }
    d->buf = buf;
    d->len = len;
    d->o = opts;
    d->path = path;
    d->diag = diag;
    d->unit_mm = opts->unit_mm > 0 ? opts->unit_mm : 0;
    d->file = cs_path_intern(path, name ? name : "-");
    cs_err_t e;
    if (!d->file) {
        cs_path_loc_t l = {"-", 0, 0};
        e = cs_path_diag_set(diag, CS_ERR_FULL, l, "out of memory");
    } else {
        diag->reason[0] = '\0';
        e = dxf_run(d);
    }
    cs_gnurbs_free(&d->nb);
    free(d->g);
    free(d->lay);
    free(d->blk);
    free(d);
    return e;
}
