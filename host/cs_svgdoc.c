/* cs_svgdoc: SVG documents through expat (see cs_svgdoc.h).
 * Two passes: expat reads the document into a tree of nodes (attributes copied, with the raw
 * offset and line/column of each start tag); then an id index and the style sheets are built and
 * the tree is walked depth first, a <use> walking the element it refers to as its child.
 * Expat hands over attribute values already decoded, without positions; to point an error at
 * the right character, the raw start tag is re-scanned from expat's byte index, the attribute's
 * value decoded here with a map from each decoded byte to its offset in the file. */
#include "cs_svgdoc.h"
#include "cs_readall.h"

#include <errno.h>
#include <expat.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_css.h"
#include "cs_svgpath.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define SVG_NS "http://www.w3.org/2000/svg"
/* Element names come from expat as "namespace-URI<sep>local-name" (or just "local-name"). */
#define NS_SEP     '\x1f'
#define MAX_WARNED 32
#define XLINK_HREF "http://www.w3.org/1999/xlink\x1fhref"
#define NONE       ((size_t)-1)

/* The properties the reader takes from style sheets, style="" and attributes (read_style). */
enum { P_DISPLAY, P_VISIBILITY, P_STROKE, P_FILL, P_FONT_SIZE, P_ANCHOR, NPROPS };
static const char *const style_props[NPROPS] = {"display", "visibility", "stroke",
                                                "fill",    "font-size",  "text-anchor"};

/* --- file loading ------------------------------------------------------------------------ */

cs_err_t cs_svgdoc_load(const char *filename, char **buf, size_t *len, cs_path_diag_t *diag)
{
    return cs_readall(filename, 0, false, buf, len, diag);
}

/* --- positions ------------------------------------------------------------------------------ */

/* Line/column of raw offsets in the document, counted forward from a cursor (tags arrive in
 * increasing order, so the whole document is scanned once). */
typedef struct {
    const char *buf;
    size_t len;
    size_t off;
    unsigned line, col;
} cursor_t;

static void cursor_reset(cursor_t *c)
{
    c->off = 0;
    c->line = 1;
    c->col = 1;
}

static void cursor_advance(cursor_t *c, size_t to)
{
    if (to > c->len)
        to = c->len;
    for (; c->off < to; c->off++) {
        unsigned char ch = (unsigned char)c->buf[c->off];
        if (ch == '\n') {
            c->line++;
            c->col = 1;
        } else if (ch != '\r' && (ch & 0xC0) != 0x80) {
            c->col++; /* columns count characters, not UTF-8 continuation bytes */
        }
    }
}

/* One attribute value: decoded text plus, for each decoded byte, its raw offset in the file. */
typedef struct {
    char *text;
    size_t *map; /* NULL: every offset maps to raw_start (fallback when decoding failed) */
    size_t n;
    size_t raw_start, raw_end;
    cursor_t base; /* position of raw_start */
    cursor_t cur;  /* moving cursor for locate() */
} attr_t;

static void attr_free(attr_t *a)
{
    free(a->text);
    free(a->map);
    memset(a, 0, sizeof *a);
}

static void attr_locate(void *ctx, size_t off, unsigned *line, unsigned *col)
{
    attr_t *a = ctx;
    size_t raw = a->map ? (off < a->n ? a->map[off] : a->raw_end) : a->raw_start;
    if (raw < a->cur.off)
        a->cur = a->base;
    cursor_advance(&a->cur, raw);
    *line = a->cur.line;
    *col = a->cur.col;
}

static bool is_xml_space(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

/* Finds attribute `name` in the raw start tag at buf[tag] ('<'); value span [*vs, *ve). */
static bool find_raw_attr(const char *buf, size_t len, size_t tag, const char *name, size_t *vs,
                          size_t *ve)
{
    size_t i = tag, nlen = strlen(name);
    if (i >= len || buf[i] != '<')
        return false;
    i++;
    while (i < len && !is_xml_space(buf[i]) && buf[i] != '>' && buf[i] != '/')
        i++;
    for (;;) {
        while (i < len && is_xml_space(buf[i]))
            i++;
        if (i >= len || buf[i] == '>' || buf[i] == '/')
            return false;
        size_t ns = i;
        while (i < len && !is_xml_space(buf[i]) && buf[i] != '=')
            i++;
        size_t ne = i;
        while (i < len && is_xml_space(buf[i]))
            i++;
        if (i >= len || buf[i] != '=')
            return false;
        i++;
        while (i < len && is_xml_space(buf[i]))
            i++;
        if (i >= len || (buf[i] != '"' && buf[i] != '\''))
            return false;
        char q = buf[i++];
        size_t s = i;
        while (i < len && buf[i] != q)
            i++;
        if (i >= len)
            return false;
        if (ne - ns == nlen && memcmp(buf + ns, name, nlen) == 0) {
            *vs = s;
            *ve = i;
            return true;
        }
        i++;
    }
}

/* Appends code point cp as UTF-8, each byte mapped to raw offset r. */
static void put_utf8(attr_t *a, unsigned long cp, size_t r)
{
    unsigned char b[4];
    size_t k;
    if (cp < 0x80) {
        b[0] = (unsigned char)cp;
        k = 1;
    } else if (cp < 0x800) {
        b[0] = (unsigned char)(0xC0 | (cp >> 6));
        b[1] = (unsigned char)(0x80 | (cp & 0x3F));
        k = 2;
    } else if (cp < 0x10000) {
        b[0] = (unsigned char)(0xE0 | (cp >> 12));
        b[1] = (unsigned char)(0x80 | ((cp >> 6) & 0x3F));
        b[2] = (unsigned char)(0x80 | (cp & 0x3F));
        k = 3;
    } else {
        b[0] = (unsigned char)(0xF0 | (cp >> 18));
        b[1] = (unsigned char)(0x80 | ((cp >> 12) & 0x3F));
        b[2] = (unsigned char)(0x80 | ((cp >> 6) & 0x3F));
        b[3] = (unsigned char)(0x80 | (cp & 0x3F));
        k = 4;
    }
    for (size_t j = 0; j < k; j++) {
        a->text[a->n] = (char)b[j];
        a->map[a->n++] = r;
    }
}

/* Decodes the raw value buf[vs..ve) (predefined entities and character references; white space
 * is left as is, the path grammar treats all of it alike). false on an entity it cannot
 * decode here (a DTD-defined one) or out of memory. */
static bool decode_raw(const char *buf, size_t vs, size_t ve, attr_t *a)
{
    size_t cap = ve - vs + 4;
    a->text = malloc(cap + 1);
    a->map = malloc((cap + 1) * sizeof *a->map);
    a->n = 0;
    if (!a->text || !a->map)
        return false;
    for (size_t i = vs; i < ve;) {
        if (buf[i] != '&') {
            a->text[a->n] = buf[i];
            a->map[a->n++] = i;
            i++;
            continue;
        }
        size_t semi = i + 1;
        while (semi < ve && buf[semi] != ';')
            semi++;
        if (semi >= ve)
            return false;
        const char *ent = buf + i + 1;
        size_t elen = semi - i - 1;
        unsigned long cp;
        if (elen == 2 && memcmp(ent, "lt", 2) == 0)
            cp = '<';
        else if (elen == 2 && memcmp(ent, "gt", 2) == 0)
            cp = '>';
        else if (elen == 3 && memcmp(ent, "amp", 3) == 0)
            cp = '&';
        else if (elen == 4 && memcmp(ent, "quot", 4) == 0)
            cp = '"';
        else if (elen == 4 && memcmp(ent, "apos", 4) == 0)
            cp = '\'';
        else if (elen >= 2 && ent[0] == '#') {
            char tmp[16];
            if (elen >= sizeof tmp)
                return false;
            memcpy(tmp, ent, elen);
            tmp[elen] = '\0';
            char *end = NULL;
            cp = (tmp[1] == 'x') ? strtoul(tmp + 2, &end, 16) : strtoul(tmp + 1, &end, 10);
            if (!end || *end != '\0' || cp > 0x10FFFF)
                return false;
        } else {
            return false;
        }
        if (a->n + 4 > cap)
            return false;
        put_utf8(a, cp, i);
        i = semi + 1;
    }
    a->text[a->n] = '\0';
    return true;
}

/* --- transforms (SVG 1.1 §7.6) ---------------------------------------------------------- */

static bool is_alpha(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
}

/* The transform functions of SVG 1.1 7.6 with their argument counts (rotate: 1 or 3). */
static const struct {
    const char *name;
    unsigned minargs, maxargs;
} xform_kinds[] = {
    {"matrix", 6, 6}, {"translate", 1, 2}, {"scale", 1, 2},
    {"rotate", 1, 3}, {"skewX", 1, 1},     {"skewY", 1, 1},
};
enum { XF_MATRIX, XF_TRANSLATE, XF_SCALE, XF_ROTATE, XF_SKEWX, XF_SKEWY, XF_KINDS };

/* The index of the transform name s[0..nl) in xform_kinds, or -1. */
static int xform_kind(const char *s, size_t nl)
{
    for (int k = 0; k < XF_KINDS; k++)
        if (strlen(xform_kinds[k].name) == nl && memcmp(s, xform_kinds[k].name, nl) == 0)
            return k;
    return -1;
}

/* The arguments of a transform from s[*i] (just after its '('), up to and past the ')': *n of
 * them into v. CS_OK, or CS_ERR_PARSE with *bad and *why. */
static cs_err_t xform_args(const char *s, size_t len, size_t *i, int kind, double v[6], unsigned *n,
                           size_t *bad, const char **why)
{
    *n = 0;
    for (;;) {
        while (*i < len && is_xml_space(s[*i]))
            (*i)++;
        if (*i < len && s[*i] == ')' && *n > 0)
            break;
        if (*n > 0 && *i < len && s[*i] == ',') {
            (*i)++;
            while (*i < len && is_xml_space(s[*i]))
                (*i)++;
        }
        if (*n >= xform_kinds[kind].maxargs) {
            *bad = *i;
            *why = "too many arguments for this transform";
            return CS_ERR_PARSE;
        }
        size_t b = 0;
        size_t k = cs_svgpath_scan_number(s + *i, len - *i, &v[*n], &b);
        if (k == 0) {
            *bad = *i + b;
            *why = "expected a number in the transform";
            return CS_ERR_PARSE;
        }
        if (!isfinite(v[*n])) {
            *bad = *i;
            *why = "number too large";
            return CS_ERR_PARSE;
        }
        *i += k;
        (*n)++;
    }
    if (*n < xform_kinds[kind].minargs || (kind == XF_ROTATE && *n == 2)) {
        *bad = *i;
        *why = "too few arguments for this transform";
        return CS_ERR_PARSE;
    }
    (*i)++; /* ')' */
    return CS_OK;
}

/* The matrix of one transform function (SVG 1.1 7.4, 7.6). */
static cs_path_affine_t xform_matrix(int kind, const double *v, unsigned n)
{
    cs_path_affine_t t = cs_path_affine_identity();
    switch (kind) {
    case XF_MATRIX:
        t.a = v[0];
        t.b = v[1];
        t.c = v[2];
        t.d = v[3];
        t.e = v[4];
        t.f = v[5];
        break;
    case XF_TRANSLATE:
        t.e = v[0];
        t.f = n > 1 ? v[1] : 0.0;
        break;
    case XF_SCALE:
        t.a = v[0];
        t.d = n > 1 ? v[1] : v[0];
        break;
    case XF_ROTATE: {
        double r = v[0] * (M_PI / 180.0);
        t.a = cos(r);
        t.b = sin(r);
        t.c = -sin(r);
        t.d = cos(r);
        if (n == 3) { /* rotate about (cx, cy): translate(c) rotate translate(-c) */
            t.e = v[1] - t.a * v[1] - t.c * v[2];
            t.f = v[2] - t.b * v[1] - t.d * v[2];
        }
        break;
    }
    case XF_SKEWX:
        t.c = tan(v[0] * (M_PI / 180.0));
        break;
    default:
        t.b = tan(v[0] * (M_PI / 180.0));
        break;
    }
    return t;
}

cs_err_t cs_svgdoc_parse_transform(const char *s, size_t len, cs_path_affine_t *out, size_t *bad,
                                   const char **why)
{
    cs_path_affine_t m = cs_path_affine_identity();
    size_t i = 0;
    bool need_sep = false;
    for (;;) {
        bool sep = false;
        while (i < len && (is_xml_space(s[i]) || s[i] == ',')) {
            i++;
            sep = true;
        }
        if (i >= len)
            break;
        if (need_sep && !sep && !is_alpha(s[i])) {
            *bad = i;
            *why = "expected a transform name";
            return CS_ERR_PARSE;
        }
        size_t ns = i;
        while (i < len && is_alpha(s[i]))
            i++;
        int kind = xform_kind(s + ns, i - ns);
        if (kind < 0) {
            *bad = ns;
            *why = "unknown transform (expected matrix, translate, scale, rotate, skewX or skewY)";
            return CS_ERR_PARSE;
        }
        while (i < len && is_xml_space(s[i]))
            i++;
        if (i >= len || s[i] != '(') {
            *bad = i;
            *why = "expected '(' after the transform name";
            return CS_ERR_PARSE;
        }
        i++;
        double v[6];
        unsigned n;
        cs_err_t e = xform_args(s, len, &i, kind, v, &n, bad, why);
        if (e != CS_OK)
            return e;
        m = cs_path_affine_mul(m, xform_matrix(kind, v, n));
        need_sep = true;
    }
    *out = m;
    return CS_OK;
}

/* --- the document walk ------------------------------------------------------------------ */

typedef struct {
    cs_path_affine_t m;  /* user space of this element -> mm */
    bool hidden;         /* inside <defs>, <symbol>, <clipPath>...: not drawn directly */
    bool none;           /* display="none" here or above: nothing below is drawn */
    bool invisible;      /* visibility hidden/collapse (inherited, a child may override) */
    bool stroke, fill;   /* stroke / fill paint other than none (inherited properties) */
    double vw, vh;       /* nearest viewport's size in user units (percentages); 0 = unknown */
    double font_size;    /* inherited font-size, user units (initial: medium = 16) */
    int anchor;          /* inherited text-anchor: 0 start, 1 middle, 2 end */
    size_t node;         /* the document node this frame walks */
    size_t inst;         /* <use>: the referenced element, walked as its only child; or NONE */
    bool instance;       /* this element is walked as the referenced element of a <use> */
    bool entered;        /* its children have been started */
    unsigned use_depth;  /* <use> elements above, through instances */
    bool has_uw, has_uh; /* a <use>'s width / height (for a <symbol> or <svg> it refers to) */
    double use_w, use_h;
} frame_t;

/* The document as read by the first pass: elements (and the character data of <text> and
 * <style>) with their attributes copied, linked as a tree, walked by the second pass. */
typedef struct {
    const char *local; /* SVG local name; NULL: foreign element, or character data */
    char **atts;       /* name/value pairs, NULL-terminated (one allocation with the strings) */
    const char *text;  /* character data (atts == NULL) */
    size_t tn;
    size_t tag;  /* raw offset of the start tag (of the data) */
    cursor_t at; /* its position */
    size_t parent, first, last, next;
} node_t;

typedef struct {
    const char *id;
    size_t node;
} idref_t;

typedef struct doc doc_t;
typedef cs_err_t (*elem_fn)(doc_t *d, const char *local, const char **atts, size_t tag);

struct doc {
    XML_Parser xp;
    const char *buf;
    size_t len;
    const char *name;
    const cs_svgdoc_opts_t *o;
    cs_path_t *path;
    cs_path_diag_t *diag;
    cs_svgdoc_stats_t *stats;
    cursor_t cur; /* moves forward through the document */
    cursor_t tag; /* position of the current start tag */
    frame_t *stack;
    size_t depth, cap;
    cs_err_t err;
    node_t *nodes;
    size_t nnodes, ncap;
    size_t open;       /* first pass: the element being read; NONE at the top */
    unsigned textlike; /* first pass: open <text> / <style> elements (their data is kept) */
    idref_t *ids;      /* elements with an id, sorted by id then document order */
    size_t nids;
    cs_css_elem_t *elems; /* each node as selectors see it */
    cs_css_sheet_t sheet; /* every <style> of the document, in document order */
    size_t inst_elems;    /* elements walked inside <use> instances */
    const char *warned[MAX_WARNED];
    size_t nwarned;
    /* the <text> being read: its current run's characters, pen position and frame */
    bool in_text;
    size_t text_depth, text_tag;
    cursor_t text_at; /* position of text_tag */
    double tx, ty;
    frame_t tframe;
    char *tbuf;
    size_t tn, tcap;
};

/* Cursor at raw offset raw: forward from the moving cursor, or (for an attribute written
 * before one already visited in the same tag) from the tag's start. */
static cursor_t cursor_at(doc_t *d, size_t raw)
{
    if (raw >= d->cur.off) {
        cursor_advance(&d->cur, raw);
        return d->cur;
    }
    cursor_t c = d->tag;
    if (raw < c.off)
        cursor_reset(&c);
    cursor_advance(&c, raw);
    return c;
}

static cs_path_loc_t loc_of(doc_t *d, size_t raw)
{
    cursor_t c = cursor_at(d, raw);
    cs_path_loc_t l = {d->name, c.line, c.col};
    return l;
}

/* One warning per `key` per document. */
static void warn_once(doc_t *d, const char *key, size_t raw, const char *fmt, ...)
{
    for (size_t i = 0; i < d->nwarned; i++)
        if (strcmp(d->warned[i], key) == 0)
            return;
    if (d->nwarned < MAX_WARNED)
        d->warned[d->nwarned++] = key;
    cs_path_diag_t w;
    char msg[200];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    cs_path_diag_set(&w, CS_OK, loc_of(d, raw), "%s", msg);
    d->stats->warnings++;
    if (d->o->warn)
        d->o->warn(d->o->warn_ctx, &w);
    else
        cs_path_warn_print(stderr, &w);
}

static const char *att_get(const char **atts, const char *name)
{
    for (size_t i = 0; atts[i]; i += 2)
        if (strcmp(atts[i], name) == 0)
            return atts[i + 1];
    return NULL;
}

/* The attribute's text with its position map (or a fallback that maps to the tag). */
static cs_err_t attr_load(doc_t *d, const char *value, const char *name, size_t tag, attr_t *a)
{
    memset(a, 0, sizeof *a);
    size_t vs, ve;
    bool raw = find_raw_attr(d->buf, d->len, tag, name, &vs, &ve);
    if (raw && decode_raw(d->buf, vs, ve, a)) {
        a->raw_start = vs;
        a->raw_end = ve;
    } else {
        attr_free(a);
        a->raw_start = a->raw_end = raw ? vs : tag;
        size_t n = strlen(value);
        a->text = malloc(n + 1);
        if (!a->text)
            return cs_path_diag_set(d->diag, CS_ERR_FULL, loc_of(d, tag), "out of memory");
        memcpy(a->text, value, n + 1);
        a->n = n;
    }
    a->base = cursor_at(d, a->raw_start);
    a->cur = a->base;
    return CS_OK;
}

/* The element's own transform attribute composed onto its parent's. */
static cs_err_t element_transform(doc_t *d, const char **atts, size_t tag, cs_path_affine_t *m)
{
    const char *tv = att_get(atts, "transform");
    if (!tv)
        return CS_OK;
    attr_t a;
    cs_err_t e = attr_load(d, tv, "transform", tag, &a);
    if (e != CS_OK)
        return e;
    cs_path_affine_t t;
    size_t bad = 0;
    const char *why = "";
    e = cs_svgdoc_parse_transform(a.text, a.n, &t, &bad, &why);
    if (e != CS_OK) {
        cs_path_loc_t l = {d->name, 0, 0};
        attr_locate(&a, bad, &l.line, &l.col);
        cs_path_diag_set(d->diag, e, l, "transform: %s", why);
    } else {
        *m = cs_path_affine_mul(*m, t);
    }
    attr_free(&a);
    return e;
}

/* --- lengths, viewports, style ------------------------------------------------------------- */

/* Millimetres per CSS pixel: SVG user units without a unit are px, at 96 per inch. */
#define MM_PER_PX (25.4 / 96.0)

/* Error at byte `off` of attribute `name`'s raw value in the current tag (or at the tag). */
static cs_err_t attr_fail(doc_t *d, size_t tag, const char *name, size_t off, cs_err_t code,
                          const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 6, 7)))
#endif
    ;

static cs_err_t attr_fail(doc_t *d, size_t tag, const char *name, size_t off, cs_err_t code,
                          const char *fmt, ...)
{
    size_t vs = tag, ve = tag;
    if (find_raw_attr(d->buf, d->len, tag, name, &vs, &ve))
        vs = vs + off <= ve ? vs + off : ve;
    char msg[200];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return cs_path_diag_set(d->diag, code, loc_of(d, vs), "%s: %s", name, msg);
}

typedef enum { LEN_X, LEN_Y, LEN_OTHER } len_axis_t;

/* A <length> attribute (number, optional unit px/mm/cm/in/pt/pc/%) in user units of frame f.
 * *present false (and *out = dflt) when the attribute is absent. Percentages refer to the
 * nearest viewport (SVG 1.1 §7.10); an unknown viewport size makes them an error. */
static cs_err_t get_length(doc_t *d, const frame_t *f, const char **atts, size_t tag,
                           const char *name, len_axis_t axis, double dflt, double *out,
                           bool *present)
{
    const char *v = att_get(atts, name);
    *out = dflt;
    if (present)
        *present = false;
    if (!v)
        return CS_OK;
    size_t n = strlen(v), i = 0;
    while (i < n && is_xml_space(v[i]))
        i++;
    double x = 0.0;
    size_t bad = 0, k = cs_svgpath_scan_number(v + i, n - i, &x, &bad);
    if (k == 0)
        return attr_fail(d, tag, name, i + bad, CS_ERR_PARSE, "expected a length");
    if (!isfinite(x))
        return attr_fail(d, tag, name, i, CS_ERR_RANGE, "number too large");
    size_t us = i + k;
    i = us;
    while (i < n && (is_alpha(v[i]) || v[i] == '%'))
        i++;
    size_t ul = i - us;
    const char *u = v + us;
    double s;
    if (ul == 0 || (ul == 2 && memcmp(u, "px", 2) == 0))
        s = 1.0;
    else if (ul == 2 && memcmp(u, "mm", 2) == 0)
        s = 1.0 / MM_PER_PX;
    else if (ul == 2 && memcmp(u, "cm", 2) == 0)
        s = 10.0 / MM_PER_PX;
    else if (ul == 2 && memcmp(u, "in", 2) == 0)
        s = 96.0;
    else if (ul == 2 && memcmp(u, "pt", 2) == 0)
        s = 96.0 / 72.0;
    else if (ul == 2 && memcmp(u, "pc", 2) == 0)
        s = 16.0;
    else if (ul == 1 && u[0] == '%') {
        double ref = axis == LEN_X   ? f->vw
                     : axis == LEN_Y ? f->vh
                                     : sqrt((f->vw * f->vw + f->vh * f->vh) / 2.0);
        if (!(f->vw > 0.0 && f->vh > 0.0))
            return attr_fail(d, tag, name, us, CS_ERR_PARSE,
                             "a percentage needs a viewport size (width/height or viewBox)");
        s = ref / 100.0;
    } else
        return attr_fail(d, tag, name, us, CS_ERR_PARSE,
                         "unsupported unit (expected px, mm, cm, in, pt, pc or %%)");
    while (i < n && is_xml_space(v[i]))
        i++;
    if (i < n)
        return attr_fail(d, tag, name, i, CS_ERR_PARSE, "unexpected text after the length");
    *out = x * s;
    if (!isfinite(*out))
        return attr_fail(d, tag, name, 0, CS_ERR_RANGE, "length too large");
    if (present)
        *present = true;
    return CS_OK;
}

/* The document size attribute width/height of the root <svg> in mm; *known false when absent
 * or a percentage (the size of a plotter's page is not known here). */
static cs_err_t get_doc_size(doc_t *d, const char **atts, size_t tag, const char *name, double *mm,
                             bool *known)
{
    frame_t f;
    memset(&f, 0, sizeof f);
    f.vw = f.vh = 100.0; /* a percentage reads as "unknown" below */
    *known = false;
    const char *v = att_get(atts, name);
    if (!v || strchr(v, '%'))
        return CS_OK;
    double px;
    bool present;
    cs_err_t e = get_length(d, &f, atts, tag, name, LEN_OTHER, 0.0, &px, &present);
    if (e != CS_OK)
        return e;
    if (px < 0.0)
        return attr_fail(d, tag, name, 0, CS_ERR_PARSE, "negative size");
    *mm = px * MM_PER_PX;
    *known = present;
    return CS_OK;
}

typedef struct {
    bool have;
    double x, y, w, h;
    int ax, ay; /* alignment: 0 min, 1 mid, 2 max; -1 = none (stretch) */
    bool slice;
} viewbox_t;

static cs_err_t get_viewbox(doc_t *d, const char **atts, size_t tag, viewbox_t *vb)
{
    memset(vb, 0, sizeof *vb);
    vb->ax = vb->ay = 1; /* default xMidYMid meet */
    const char *v = att_get(atts, "viewBox");
    if (!v)
        return CS_OK;
    size_t n = strlen(v), i = 0;
    double a[4];
    for (int k = 0; k < 4; k++) {
        while (i < n && (is_xml_space(v[i]) || (k > 0 && v[i] == ',')))
            i++;
        size_t bad = 0, m = cs_svgpath_scan_number(v + i, n - i, &a[k], &bad);
        if (m == 0)
            return attr_fail(d, tag, "viewBox", i + bad, CS_ERR_PARSE,
                             "expected four numbers: min-x min-y width height");
        if (!isfinite(a[k]))
            return attr_fail(d, tag, "viewBox", i, CS_ERR_RANGE, "number too large");
        i += m;
    }
    while (i < n && is_xml_space(v[i]))
        i++;
    if (i < n)
        return attr_fail(d, tag, "viewBox", i, CS_ERR_PARSE, "unexpected text after 4 numbers");
    if (!(a[2] > 0.0 && a[3] > 0.0))
        return attr_fail(d, tag, "viewBox", 0, CS_ERR_PARSE, "width and height must be positive");
    vb->have = true;
    vb->x = a[0];
    vb->y = a[1];
    vb->w = a[2];
    vb->h = a[3];
    const char *p = att_get(atts, "preserveAspectRatio");
    if (!p)
        return CS_OK;
    n = strlen(p);
    i = 0;
    while (i < n && is_xml_space(p[i]))
        i++;
    if (n - i >= 5 && memcmp(p + i, "defer", 5) == 0) {
        i += 5;
        while (i < n && is_xml_space(p[i]))
            i++;
    }
    static const char *const names[3] = {"Min", "Mid", "Max"};
    if (n - i >= 4 && memcmp(p + i, "none", 4) == 0) {
        vb->ax = vb->ay = -1;
        i += 4;
    } else {
        bool ok = false;
        if (n - i >= 8 && p[i] == 'x' && p[i + 4] == 'Y') {
            for (int x = 0; x < 3; x++)
                for (int y = 0; y < 3; y++)
                    if (memcmp(p + i + 1, names[x], 3) == 0 &&
                        memcmp(p + i + 5, names[y], 3) == 0) {
                        vb->ax = x;
                        vb->ay = y;
                        ok = true;
                    }
        }
        if (!ok)
            return attr_fail(d, tag, "preserveAspectRatio", i, CS_ERR_PARSE,
                             "expected none or x(Min|Mid|Max)Y(Min|Mid|Max)");
        i += 8;
    }
    while (i < n && is_xml_space(p[i]))
        i++;
    if (n - i >= 5 && memcmp(p + i, "slice", 5) == 0) {
        vb->slice = true;
        i += 5;
    } else if (n - i >= 4 && memcmp(p + i, "meet", 4) == 0) {
        i += 4;
    }
    while (i < n && is_xml_space(p[i]))
        i++;
    if (i < n)
        return attr_fail(d, tag, "preserveAspectRatio", i, CS_ERR_PARSE, "expected meet or slice");
    return CS_OK;
}

/* The viewBox -> viewport map (SVG 1.1 §7.8): viewport at (ex, ey), size ew x eh. */
static cs_path_affine_t viewbox_map(const viewbox_t *vb, double ex, double ey, double ew, double eh)
{
    cs_path_affine_t m = cs_path_affine_identity();
    double sx = ew / vb->w, sy = eh / vb->h;
    if (vb->ax >= 0) {
        double s = vb->slice ? (sx > sy ? sx : sy) : (sx < sy ? sx : sy);
        sx = sy = s;
    }
    double tx = ex - vb->x * sx, ty = ey - vb->y * sy;
    if (vb->ax > 0)
        tx += (ew - vb->w * sx) * (vb->ax == 1 ? 0.5 : 1.0);
    if (vb->ay > 0)
        ty += (eh - vb->h * sy) * (vb->ay == 1 ? 0.5 : 1.0);
    m.a = sx;
    m.d = sy;
    m.e = tx;
    m.f = ty;
    return m;
}

/* Value of property k for an element: CSS cascade order (CSS 2.1 §6.4, SVG 1.1 §6.4): style=""
 * over the style sheets' rules (`sheet`, by importance, specificity and order; !important in
 * a sheet over a plain style="") over the presentation attribute of the same name. Writes a
 * NUL-terminated, trimmed copy to out in lower case (CSS keywords are ASCII case-insensitive:
 * NONE is none); false when none is given. */
static bool get_prop(const char **atts, int k, const cs_css_value_t *sheet, char *out, size_t cap)
{
    cs_css_value_t v = cs_css_pick(cs_css_inline(att_get(atts, "style"), style_props[k]), sheet[k]);
    const char *found = v.text;
    size_t flen = v.len;
    if (!v.set) {
        found = att_get(atts, style_props[k]);
        if (!found)
            return false;
        flen = strlen(found);
        while (flen > 0 && is_xml_space(*found)) {
            found++;
            flen--;
        }
        while (flen > 0 && is_xml_space(found[flen - 1]))
            flen--;
    }
    if (flen >= cap)
        flen = cap - 1;
    for (size_t i = 0; i < flen; i++)
        out[i] = found[i] >= 'A' && found[i] <= 'Z' ? (char)(found[i] - 'A' + 'a') : found[i];
    out[flen] = '\0';
    return true;
}

/* display, visibility, stroke and fill of this element (inherited ones start from the parent's
 * values, already in *f); sheet: the style sheets' values for it (style_props order). */
static void read_style(const char **atts, const cs_css_value_t *sheet, frame_t *f)
{
    char v[64];
    if (get_prop(atts, P_DISPLAY, sheet, v, sizeof v) && strcmp(v, "none") == 0)
        f->none = true;
    if (get_prop(atts, P_VISIBILITY, sheet, v, sizeof v) && strcmp(v, "inherit") != 0)
        f->invisible = strcmp(v, "hidden") == 0 || strcmp(v, "collapse") == 0;
    if (get_prop(atts, P_STROKE, sheet, v, sizeof v) && strcmp(v, "inherit") != 0 && v[0] != '\0')
        f->stroke = strcmp(v, "none") != 0;
    if (get_prop(atts, P_FILL, sheet, v, sizeof v) && strcmp(v, "inherit") != 0 && v[0] != '\0')
        f->fill = strcmp(v, "none") != 0;
    char *end;
    /* font-size as a number of user units (px); other forms keep the inherited size */
    if (get_prop(atts, P_FONT_SIZE, sheet, v, sizeof v)) {
        double fs = strtod(v, &end);
        if (end != v && (*end == '\0' || strcmp(end, "px") == 0) && fs > 0)
            f->font_size = fs;
    }
    if (get_prop(atts, P_ANCHOR, sheet, v, sizeof v) && strcmp(v, "inherit") != 0)
        f->anchor = strcmp(v, "middle") == 0 ? 1 : strcmp(v, "end") == 0 ? 2 : 0;
}

/* --- elements ---------------------------------------------------------------------------- */

/* <svg>: the root maps its viewBox (or px user units) to the document size in mm; a nested one
 * establishes a new viewport at x, y of size width x height in its parent's user units. A
 * transform attribute (SVG 2) applies in the parent's space. No width/height on the root (or
 * percentages): one user unit is one millimetre, as for bare path data. Clipping to the
 * viewport is not done. */
static cs_err_t on_svg(doc_t *d, const char *local, const char **atts, size_t tag)
{
    (void)local;
    frame_t *f = &d->stack[d->depth - 1];
    const frame_t *parent = d->depth >= 2 ? &d->stack[d->depth - 2] : NULL;
    cs_err_t e = element_transform(d, atts, tag, &f->m);
    if (e != CS_OK)
        return e;
    viewbox_t vb;
    if ((e = get_viewbox(d, atts, tag, &vb)) != CS_OK)
        return e;
    if (!parent) {
        double w = 0.0, h = 0.0;
        bool hw, hh;
        if ((e = get_doc_size(d, atts, tag, "width", &w, &hw)) != CS_OK ||
            (e = get_doc_size(d, atts, tag, "height", &h, &hh)) != CS_OK)
            return e;
        if (vb.have && hw != hh) { /* one size given: the other from the viewBox's ratio */
            if (hw) {
                h = w * vb.h / vb.w;
                hh = true;
            } else {
                w = h * vb.w / vb.h;
                hw = true;
            }
        }
        /* the page is y-down, h mm high (0: unknown); cs_layout turns it y-up */
        d->path->page_y_down = true;
        d->path->page_h_mm = hh ? h : 0.0;
        if ((hw && w == 0.0) || (hh && h == 0.0)) {
            f->none = true; /* a zero-sized viewport disables rendering (SVG 1.1 §7.10) */
            return CS_OK;
        }
        if (hw && hh && vb.have) {
            f->m = cs_path_affine_mul(f->m, viewbox_map(&vb, 0.0, 0.0, w, h));
        } else if (hw || hh) {
            cs_path_affine_t s = cs_path_affine_identity();
            s.a = s.d = MM_PER_PX;
            f->m = cs_path_affine_mul(f->m, s);
        }
        if (vb.have) {
            f->vw = vb.w;
            f->vh = vb.h;
        } else {
            f->vw = hw ? w / MM_PER_PX : 0.0;
            f->vh = hh ? h / MM_PER_PX : 0.0;
        }
        return CS_OK;
    }
    double x, y, w, h;
    bool hw, hh;
    if ((e = get_length(d, f, atts, tag, "x", LEN_X, 0.0, &x, NULL)) != CS_OK ||
        (e = get_length(d, f, atts, tag, "y", LEN_Y, 0.0, &y, NULL)) != CS_OK ||
        (e = get_length(d, f, atts, tag, "width", LEN_X, f->vw, &w, &hw)) != CS_OK ||
        (e = get_length(d, f, atts, tag, "height", LEN_Y, f->vh, &h, &hh)) != CS_OK)
        return e;
    if (f->instance && f->has_uw) { /* a <use>'s width/height replace the <svg>'s (§5.6) */
        w = f->use_w;
        hw = true;
    }
    if (f->instance && f->has_uh) {
        h = f->use_h;
        hh = true;
    }
    if (w < 0.0 || h < 0.0)
        return attr_fail(d, tag, w < 0.0 ? "width" : "height", 0, CS_ERR_PARSE, "negative size");
    if ((hw && w == 0.0) || (hh && h == 0.0)) {
        f->none = true;
        return CS_OK;
    }
    cs_path_affine_t t = cs_path_affine_identity();
    t.e = x;
    t.f = y;
    if (vb.have && w > 0.0 && h > 0.0)
        t = viewbox_map(&vb, x, y, w, h);
    f->m = cs_path_affine_mul(f->m, t);
    f->vw = vb.have ? vb.w : w;
    f->vh = vb.have ? vb.h : h;
    return CS_OK;
}

static cs_err_t on_container(doc_t *d, const char *local, const char **atts, size_t tag)
{
    (void)local;
    return element_transform(d, atts, tag, &d->stack[d->depth - 1].m);
}

static cs_err_t on_hidden(doc_t *d, const char *local, const char **atts, size_t tag)
{
    (void)local;
    (void)atts;
    (void)tag;
    d->stack[d->depth - 1].hidden = true;
    return CS_OK;
}

/* <symbol>: never drawn where it stands; the instance of a <use> is a viewport (SVG 1.1 §5.5,
 * §5.6; SVG 2 §5.6) of the use's width x height (else the symbol's own, else 100%) at the use's
 * x, y (already in the transform), the symbol's viewBox mapped into it by its
 * preserveAspectRatio (default xMidYMid meet). A zero width or height draws nothing. */
static cs_err_t on_symbol(doc_t *d, const char *local, const char **atts, size_t tag)
{
    frame_t *f = &d->stack[d->depth - 1];
    if (!f->instance)
        return on_hidden(d, local, atts, tag);
    viewbox_t vb;
    double w, h;
    bool hw, hh;
    cs_err_t e;
    if ((e = get_viewbox(d, atts, tag, &vb)) != CS_OK ||
        (e = get_length(d, f, atts, tag, "width", LEN_X, f->vw, &w, &hw)) != CS_OK ||
        (e = get_length(d, f, atts, tag, "height", LEN_Y, f->vh, &h, &hh)) != CS_OK)
        return e;
    w = f->has_uw ? f->use_w : w;
    h = f->has_uh ? f->use_h : h;
    if ((f->has_uw || hw) && w <= 0.0) {
        f->none = true;
        return CS_OK;
    }
    if ((f->has_uh || hh) && h <= 0.0) {
        f->none = true;
        return CS_OK;
    }
    if (vb.have && w > 0.0 && h > 0.0) {
        f->m = cs_path_affine_mul(f->m, viewbox_map(&vb, 0.0, 0.0, w, h));
        f->vw = vb.w;
        f->vh = vb.h;
    }
    return CS_OK;
}

/* The element whose id is id (the first in document order), or NONE. */
static size_t find_id(const doc_t *d, const char *id)
{
    size_t lo = 0, hi = d->nids;
    while (lo < hi) { /* the first entry not below id */
        size_t mid = lo + (hi - lo) / 2;
        if (strcmp(d->ids[mid].id, id) < 0)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < d->nids && strcmp(d->ids[lo].id, id) == 0 ? d->ids[lo].node : NONE;
}

/* Why a <use> draws nothing, said (once per kind) at its tag; NULL: it is drawn. */
static const char *use_refusal(doc_t *d, const char *href, size_t *target, const char **key)
{
    *target = NONE;
    if (href[0] != '#') {
        *key = "use-external";
        return "ignoring <use> of another file (only '#id' in the same file is drawn)";
    }
    *target = find_id(d, href + 1);
    if (*target == NONE) {
        *key = "use-missing";
        return "<use>: no element has this id; nothing drawn (as in browsers)";
    }
    for (size_t k = 0; k < d->depth; k++)
        if (d->stack[k].node == *target) {
            *key = "use-cycle";
            return "<use> refers to itself or to an element containing it (a cycle): not drawn";
        }
    if (d->stack[d->depth - 1].use_depth >= CS_SVGDOC_MAX_USE_DEPTH) {
        *key = "use-depth";
        return "<use> nested deeper than CS_SVGDOC_MAX_USE_DEPTH: not drawn";
    }
    return NULL;
}

/* <use> (SVG 1.1 §5.6, SVG 2 §5.6): the element href (or xlink:href) names by '#id' is drawn as
 * the use's only child, inheriting the use's properties, in the use's user space followed by
 * translate(x, y). width/height pass to a <symbol> or <svg> it refers to. */
static cs_err_t on_use(doc_t *d, const char *local, const char **atts, size_t tag)
{
    (void)local;
    frame_t *f = &d->stack[d->depth - 1];
    if (f->hidden)
        return CS_OK; /* in <defs>: drawn only through the instance of what holds it */
    const char *href = att_get(atts, "href"); /* SVG 2: href over xlink:href */
    if (!href)
        href = att_get(atts, XLINK_HREF);
    f->none = true; /* its own children are never drawn (only what it refers to) */
    if (!href)
        return CS_OK; /* nothing referenced, nothing drawn */
    while (is_xml_space(*href))
        href++;
    const char *key = NULL;
    size_t target;
    const char *why = use_refusal(d, href, &target, &key);
    if (why) {
        d->stats->ignored++;
        warn_once(d, key, tag, "%s: '%.100s'", why, href);
        return CS_OK;
    }
    cs_err_t e = element_transform(d, atts, tag, &f->m);
    double x, y;
    if (e != CS_OK || (e = get_length(d, f, atts, tag, "x", LEN_X, 0.0, &x, NULL)) != CS_OK ||
        (e = get_length(d, f, atts, tag, "y", LEN_Y, 0.0, &y, NULL)) != CS_OK ||
        (e = get_length(d, f, atts, tag, "width", LEN_X, 0.0, &f->use_w, &f->has_uw)) != CS_OK ||
        (e = get_length(d, f, atts, tag, "height", LEN_Y, 0.0, &f->use_h, &f->has_uh)) != CS_OK)
        return e;
    if ((f->has_uw && f->use_w < 0.0) || (f->has_uh && f->use_h < 0.0))
        return attr_fail(d, tag, f->use_w < 0.0 ? "width" : "height", 0, CS_ERR_PARSE,
                         "negative size");
    cs_path_affine_t t = cs_path_affine_identity();
    t.e = x;
    t.f = y;
    f->m = cs_path_affine_mul(f->m, t);
    f->use_depth++;
    f->inst = target;
    f->none = false;
    d->stats->uses++;
    return CS_OK;
}

/* Whether a shape or path is drawn: not in <defs> and the like, visible, and with a stroke or a
 * fill (fills are drawn as their outline: a plotter has no area fill; said once). `open`
 * shapes (line) have no area, so only their stroke counts. */
static bool drawn(doc_t *d, bool open)
{
    frame_t *f = &d->stack[d->depth - 1];
    if (f->hidden) {
        d->stats->ignored++; /* drawn only through a <use>, if one refers to it */
        return false;
    }
    if (f->invisible || (!f->stroke && (open || !f->fill))) {
        d->stats->ignored++; /* visibility:hidden, or neither stroke nor fill: nothing shows */
        return false;
    }
    return true;
}

/* Said once, when a filled element is actually drawn. */
static void note_fill(doc_t *d, size_t tag)
{
    if (d->stack[d->depth - 1].fill)
        warn_once(d, "fill", tag,
                  "fills are not drawn: filled shapes are drawn as their outline (with or "
                  "without a stroke)");
}

/* A grammar error in path data as SVG 2 handles it (section 9.5.4, "Error handling in path
 * data": "render a path element up to (but not including) the path command containing the first
 * error"): a located warning, the valid prefix kept. Returns CS_OK after warning, or e. */
static cs_err_t path_error(cs_err_t e, const cs_path_diag_t *err, cs_svgdoc_warn_fn fn, void *ctx,
                           unsigned *warnings)
{
    if (e != CS_ERR_PARSE)
        return e; /* out of range, out of memory...: errors, as before */
    cs_path_diag_t w;
    cs_path_diag_set(&w, CS_OK, err->loc,
                     "%.150s: path drawn up to the command before it (SVG 2 "
                     "path data error handling)",
                     err->reason);
    if (warnings)
        (*warnings)++;
    if (fn)
        fn(ctx, &w);
    else
        cs_path_warn_print(stderr, &w);
    return CS_OK;
}

/* Parses path data text[0..n) in the current element's user space; positions come from
 * locate/ctx (into an attribute, or the element's tag for generated data). A grammar error keeps
 * the valid prefix with a warning (path_error); the other elements are drawn. */
static cs_err_t draw_data_in(doc_t *d, const cs_path_affine_t *m, const char *text, size_t n,
                             cs_svgpath_locate_fn locate, void *ctx)
{
    cs_svgpath_opts_t po;
    cs_svgpath_opts_init(&po, d->name);
    po.xform = cs_path_affine_mul(d->o->xform, *m);
    po.locate = locate;
    po.locate_ctx = ctx;
    cs_err_t e = cs_svgpath_parse(text, n, &po, d->path, d->diag);
    return path_error(e, d->diag, d->o->warn, d->o->warn_ctx, &d->stats->warnings);
}

static cs_err_t draw_data(doc_t *d, const char *text, size_t n, cs_svgpath_locate_fn locate,
                          void *ctx)
{
    return draw_data_in(d, &d->stack[d->depth - 1].m, text, n, locate, ctx);
}

static cs_err_t on_path(doc_t *d, const char *local, const char **atts, size_t tag)
{
    (void)local;
    frame_t *f = &d->stack[d->depth - 1];
    d->stats->paths++;
    if (!drawn(d, false))
        return CS_OK;
    cs_err_t e = element_transform(d, atts, tag, &f->m);
    if (e != CS_OK)
        return e;
    const char *dv = att_get(atts, "d");
    if (!dv)
        return CS_OK; /* no 'd': nothing is rendered (SVG 1.1 §8.3.1) */
    attr_t a;
    if ((e = attr_load(d, dv, "d", tag, &a)) != CS_OK)
        return e;
    note_fill(d, tag);
    e = draw_data(d, a.text, a.n, attr_locate, &a);
    attr_free(&a);
    return e;
}

/* Generated path data for a basic shape (SVG 1.1 §9: each shape is defined as an equivalent
 * path); numbers printed with 17 significant digits, so they read back as the same doubles. */
typedef struct {
    char *s;
    size_t n, cap;
    bool oom;
} gen_t;

static void gen_put(gen_t *g, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static void gen_put(gen_t *g, const char *fmt, ...)
{
    if (g->oom)
        return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int k = vsnprintf(g->s ? g->s + g->n : NULL, g->s ? g->cap - g->n : 0, fmt, ap);
        va_end(ap);
        if (k < 0) {
            g->oom = true;
            return;
        }
        if (g->s && g->n + (size_t)k < g->cap) {
            g->n += (size_t)k;
            return;
        }
        size_t ncap = (g->cap ? g->cap * 2 : 256) + (size_t)k;
        char *ns = realloc(g->s, ncap);
        if (!ns) {
            g->oom = true;
            return;
        }
        g->s = ns;
        g->cap = ncap;
    }
}

/* Draws generated data; errors point at the element's tag. */
static cs_err_t draw_gen(doc_t *d, const char *local, gen_t *g, size_t tag)
{
    if (g->oom) {
        free(g->s);
        return cs_path_diag_set(d->diag, CS_ERR_FULL, loc_of(d, tag), "out of memory");
    }
    if (strcmp(local, "line") != 0)
        note_fill(d, tag);
    attr_t a;
    memset(&a, 0, sizeof a);
    a.raw_start = a.raw_end = tag;
    a.base = cursor_at(d, tag);
    a.cur = a.base;
    cs_err_t e = draw_data(d, g->s, g->n, attr_locate, &a);
    free(g->s);
    return e;
}

/* Shape prologue: counts it, decides whether it is drawn, applies its transform. */
static cs_err_t shape_begin(doc_t *d, const char **atts, size_t tag, bool open, bool *draw)
{
    d->stats->shapes++;
    *draw = drawn(d, open);
    if (!*draw)
        return CS_OK;
    return element_transform(d, atts, tag, &d->stack[d->depth - 1].m);
}

/* A negative value is an error (SVG 1.1 §9.2-9.4). */
static cs_err_t non_negative(doc_t *d, size_t tag, const char *name, double v)
{
    if (v < 0.0)
        return attr_fail(d, tag, name, 0, CS_ERR_PARSE, "negative value");
    return CS_OK;
}

/* <rect> (SVG 1.1 §9.2): x, y, width, height, rounded corners rx/ry: one given stands for
 * both ("auto"), each clamped to half the width/height; zero width or height draws nothing. */
static cs_err_t on_rect(doc_t *d, const char *local, const char **atts, size_t tag)
{
    bool draw, hrx, hry;
    cs_err_t e = shape_begin(d, atts, tag, false, &draw);
    if (e != CS_OK || !draw)
        return e;
    frame_t *f = &d->stack[d->depth - 1];
    double x, y, w, h, rx, ry;
    if ((e = get_length(d, f, atts, tag, "x", LEN_X, 0.0, &x, NULL)) != CS_OK ||
        (e = get_length(d, f, atts, tag, "y", LEN_Y, 0.0, &y, NULL)) != CS_OK ||
        (e = get_length(d, f, atts, tag, "width", LEN_X, 0.0, &w, NULL)) != CS_OK ||
        (e = get_length(d, f, atts, tag, "height", LEN_Y, 0.0, &h, NULL)) != CS_OK ||
        (e = get_length(d, f, atts, tag, "rx", LEN_X, 0.0, &rx, &hrx)) != CS_OK ||
        (e = get_length(d, f, atts, tag, "ry", LEN_Y, 0.0, &ry, &hry)) != CS_OK ||
        (e = non_negative(d, tag, "width", w)) != CS_OK ||
        (e = non_negative(d, tag, "height", h)) != CS_OK ||
        (e = non_negative(d, tag, "rx", rx)) != CS_OK ||
        (e = non_negative(d, tag, "ry", ry)) != CS_OK)
        return e;
    if (w == 0.0 || h == 0.0)
        return CS_OK;
    if (hrx && !hry)
        ry = rx;
    else if (hry && !hrx)
        rx = ry;
    if (rx > w / 2.0)
        rx = w / 2.0;
    if (ry > h / 2.0)
        ry = h / 2.0;
    gen_t g = {NULL, 0, 0, false};
    double x1 = x + w, y1 = y + h;
    if (rx == 0.0 || ry == 0.0) {
        gen_put(&g, "M%.17g %.17gH%.17gV%.17gH%.17gZ", x, y, x1, y1, x);
    } else {
        /* The path of SVG 1.1 §9.2, straight sides left out where the corners meet. */
        double xa = x + rx, xb = x1 - rx, ya = y + ry, yb = y1 - ry;
        gen_put(&g, "M%.17g %.17g", xa, y);
        if (xb > xa)
            gen_put(&g, "H%.17g", xb);
        gen_put(&g, "A%.17g %.17g 0 0 1 %.17g %.17g", rx, ry, x1, ya);
        if (yb > ya)
            gen_put(&g, "V%.17g", yb);
        gen_put(&g, "A%.17g %.17g 0 0 1 %.17g %.17g", rx, ry, xb, y1);
        if (xb > xa)
            gen_put(&g, "H%.17g", xa);
        gen_put(&g, "A%.17g %.17g 0 0 1 %.17g %.17g", rx, ry, x, yb);
        if (yb > ya)
            gen_put(&g, "V%.17g", ya);
        gen_put(&g, "A%.17g %.17g 0 0 1 %.17g %.17gZ", rx, ry, xa, y);
    }
    return draw_gen(d, local, &g, tag);
}

/* <circle> and <ellipse> (SVG 1.1 §9.3-9.4): two half-turn arcs from (cx + rx, cy) in the
 * positive angle direction, through cs_svgpath's arcs (hence cs_arc_build). An ellipse with
 * one radius given uses it for both (SVG 2 "auto"); a zero radius draws nothing. */
static cs_err_t on_ellipse(doc_t *d, const char *local, const char **atts, size_t tag)
{
    bool draw, hrx = false, hry = false;
    cs_err_t e = shape_begin(d, atts, tag, false, &draw);
    if (e != CS_OK || !draw)
        return e;
    frame_t *f = &d->stack[d->depth - 1];
    double cx, cy, rx, ry;
    if ((e = get_length(d, f, atts, tag, "cx", LEN_X, 0.0, &cx, NULL)) != CS_OK ||
        (e = get_length(d, f, atts, tag, "cy", LEN_Y, 0.0, &cy, NULL)) != CS_OK)
        return e;
    if (strcmp(local, "circle") == 0) {
        if ((e = get_length(d, f, atts, tag, "r", LEN_OTHER, 0.0, &rx, NULL)) != CS_OK ||
            (e = non_negative(d, tag, "r", rx)) != CS_OK)
            return e;
        ry = rx;
    } else {
        if ((e = get_length(d, f, atts, tag, "rx", LEN_X, 0.0, &rx, &hrx)) != CS_OK ||
            (e = get_length(d, f, atts, tag, "ry", LEN_Y, 0.0, &ry, &hry)) != CS_OK ||
            (e = non_negative(d, tag, "rx", rx)) != CS_OK ||
            (e = non_negative(d, tag, "ry", ry)) != CS_OK)
            return e;
        if (hrx && !hry)
            ry = rx;
        else if (hry && !hrx)
            rx = ry;
    }
    if (rx == 0.0 || ry == 0.0)
        return CS_OK;
    gen_t g = {NULL, 0, 0, false};
    gen_put(&g, "M%.17g %.17gA%.17g %.17g 0 1 1 %.17g %.17gA%.17g %.17g 0 1 1 %.17g %.17gZ",
            cx + rx, cy, rx, ry, cx - rx, cy, rx, ry, cx + rx, cy);
    return draw_gen(d, local, &g, tag);
}

/* <line> (SVG 1.1 §9.5): drawn only when stroked (a line has no area to fill). */
static cs_err_t on_line(doc_t *d, const char *local, const char **atts, size_t tag)
{
    bool draw;
    cs_err_t e = shape_begin(d, atts, tag, true, &draw);
    if (e != CS_OK || !draw)
        return e;
    frame_t *f = &d->stack[d->depth - 1];
    double x1, y1, x2, y2;
    if ((e = get_length(d, f, atts, tag, "x1", LEN_X, 0.0, &x1, NULL)) != CS_OK ||
        (e = get_length(d, f, atts, tag, "y1", LEN_Y, 0.0, &y1, NULL)) != CS_OK ||
        (e = get_length(d, f, atts, tag, "x2", LEN_X, 0.0, &x2, NULL)) != CS_OK ||
        (e = get_length(d, f, atts, tag, "y2", LEN_Y, 0.0, &y2, NULL)) != CS_OK)
        return e;
    gen_t g = {NULL, 0, 0, false};
    gen_put(&g, "M%.17g %.17gL%.17g %.17g", x1, y1, x2, y2);
    return draw_gen(d, local, &g, tag);
}

/* Offsets of "M " + points map back into the points attribute. */
typedef struct {
    attr_t *a;
    size_t shift;
} shifted_t;

static void shifted_locate(void *ctx, size_t off, unsigned *line, unsigned *col)
{
    shifted_t *s = ctx;
    attr_locate(s->a, off >= s->shift ? off - s->shift : 0, line, col);
}

/* <polyline> and <polygon> (SVG 1.1 §9.6-9.7): the points list is path data "M x y x y ..."
 * (implicit linetos), closed for a polygon. An odd number of coordinates or a stray character
 * is an error at its place, drawn up to it (a warning); a single point draws nothing. */
static cs_err_t on_poly(doc_t *d, const char *local, const char **atts, size_t tag)
{
    bool draw;
    cs_err_t e = shape_begin(d, atts, tag, false, &draw);
    if (e != CS_OK || !draw)
        return e;
    const char *pv = att_get(atts, "points");
    if (!pv)
        return CS_OK;
    attr_t a;
    if ((e = attr_load(d, pv, "points", tag, &a)) != CS_OK)
        return e;
    note_fill(d, tag);
    /* Only numbers, commas and white space: path commands are not allowed in a points list.
     * Anything else is an error handled as in path data (SVG 2, 10.6: "the same user agent
     * behavior as occurs with an incorrectly specified path element"): drawn up to it. */
    for (size_t i = 0; i < a.n; i++) {
        char c = a.text[i];
        if (!(is_xml_space(c) || c == ',' || c == '+' || c == '-' || c == '.' || c == 'e' ||
              c == 'E' || (c >= '0' && c <= '9'))) {
            cs_path_loc_t l = {d->name, 0, 0};
            attr_locate(&a, i, &l.line, &l.col);
            e = cs_path_diag_set(d->diag, CS_ERR_PARSE, l,
                                 "points: expected numbers separated by commas or spaces");
            if ((e = path_error(e, d->diag, d->o->warn, d->o->warn_ctx, &d->stats->warnings)) !=
                CS_OK) {
                attr_free(&a);
                return e;
            }
            a.n = i;
            break;
        }
    }
    bool polygon = strcmp(local, "polygon") == 0;
    gen_t g = {NULL, 0, 0, false};
    gen_put(&g, "M %.*s%s", (int)(a.n > INT_MAX - 8 ? INT_MAX - 8 : a.n), a.text,
            polygon ? " Z" : "");
    if (g.oom) {
        attr_free(&a);
        return draw_gen(d, local, &g, tag);
    }
    shifted_t s = {&a, 2};
    e = draw_data(d, g.s, g.n, shifted_locate, &s);
    free(g.s);
    attr_free(&a);
    return e;
}

/* --- text (cs_hershey stroke font) ------------------------------------------------------ */

/* The first number of an x / y attribute (a list gives each character a position: only the
 * first is used), user units; false when absent. */
static bool first_number(const char **atts, const char *name, double *out)
{
    const char *v = att_get(atts, name);
    if (!v)
        return false;
    char *end;
    double x = strtod(v, &end);
    if (end == v)
        return false;
    *out = x;
    return true;
}

static cs_err_t gen_vertex(void *ctx, double x, double y, bool move)
{
    gen_put(ctx, "%s%.17g %.17g ", move ? "M" : "L", x, y);
    return CS_OK;
}

/* Draws the run read so far (white space collapsed, SVG 1.1 §10.15 xml:space default) at the pen
 * position in the run's frame, anchored, and moves the pen past it. */
static cs_err_t text_flush(doc_t *d)
{
    size_t n = 0;
    for (size_t i = 0; i < d->tn; i++) {
        char c = d->tbuf[i] == '\t' || d->tbuf[i] == '\n' || d->tbuf[i] == '\r' ? ' ' : d->tbuf[i];
        if (c == ' ' && (n == 0 || d->tbuf[n - 1] == ' '))
            continue;
        d->tbuf[n++] = c;
    }
    while (n > 0 && d->tbuf[n - 1] == ' ')
        n--;
    d->tn = 0;
    if (n == 0)
        return CS_OK;
    const frame_t *f = &d->tframe;
    double s = f->font_size / CS_HERSHEY_BODY; /* font units -> user units */
    double w = cs_hershey_width(d->o->font, d->tbuf, n) * s;
    double x0 = d->tx - (f->anchor == 1 ? w / 2 : f->anchor == 2 ? w : 0);
    gen_t g = {NULL, 0, 0, false};
    cs_hershey_layout(d->o->font, d->tbuf, n, x0, d->ty, s, s, gen_vertex, &g);
    d->tx = x0 + w;
    if (g.oom) {
        free(g.s);
        cs_path_loc_t l = {d->name, d->text_at.line, d->text_at.col};
        return cs_path_diag_set(d->diag, CS_ERR_FULL, l, "out of memory");
    }
    attr_t a; /* positions: the <text> tag */
    memset(&a, 0, sizeof a);
    a.raw_start = a.raw_end = d->text_tag;
    a.base = d->text_at;
    a.cur = a.base;
    cs_err_t e = g.n ? draw_data_in(d, &f->m, g.s, g.n, attr_locate, &a) : CS_OK;
    free(g.s);
    return e;
}

/* Character data inside <text>: added to the run being read. */
static cs_err_t text_append(doc_t *d, const char *s, size_t len)
{
    if (!d->in_text || len == 0)
        return CS_OK;
    if (d->tn + len > d->tcap) {
        size_t cap = (d->tcap ? d->tcap * 2 : 256) + len;
        char *nb = realloc(d->tbuf, cap);
        if (!nb) {
            cs_path_loc_t l = {d->name, d->text_at.line, d->text_at.col};
            return cs_path_diag_set(d->diag, CS_ERR_FULL, l, "out of memory");
        }
        d->tbuf = nb;
        d->tcap = cap;
    }
    memcpy(d->tbuf + d->tn, s, len);
    d->tn += len;
    return CS_OK;
}

static cs_err_t on_unsupported(doc_t *d, const char *local, const char **atts, size_t tag);

/* <text>: its characters (and those of its <tspan>s) in the stroke font, at x, y (font-size,
 * text-anchor, transform); without a font, ignored with a warning as before. */
static cs_err_t on_text(doc_t *d, const char *local, const char **atts, size_t tag)
{
    if (d->o->font == NULL)
        return on_unsupported(d, local, atts, tag);
    frame_t *f = &d->stack[d->depth - 1];
    if (!drawn(d, false))
        return CS_OK;
    cs_err_t e = element_transform(d, atts, tag, &f->m);
    if (e != CS_OK)
        return e;
    d->tx = d->ty = 0;
    first_number(atts, "x", &d->tx);
    first_number(atts, "y", &d->ty);
    d->in_text = true;
    d->text_depth = d->depth;
    d->text_tag = tag;
    d->text_at = d->tag;
    d->tframe = *f;
    d->tn = 0;
    return CS_OK;
}

/* <tspan> inside <text>: the run so far is drawn, then x / y (absolute) and its font apply. */
static cs_err_t on_tspan(doc_t *d, const char *local, const char **atts, size_t tag)
{
    (void)local;
    if (!d->in_text)
        return CS_OK;
    cs_err_t e = text_flush(d);
    frame_t *f = &d->stack[d->depth - 1];
    if (e == CS_OK)
        e = element_transform(d, atts, tag, &f->m);
    first_number(atts, "x", &d->tx);
    first_number(atts, "y", &d->ty);
    d->tframe = *f;
    return e;
}

/* The end of <text> or of one of its <tspan>s: draws the run; after a tspan, its parent's frame
 * applies again. */
static void text_end(doc_t *d)
{
    if (!d->in_text || d->err != CS_OK)
        return;
    cs_err_t e = text_flush(d);
    if (d->depth == d->text_depth)
        d->in_text = false;
    else if (d->depth >= 2)
        d->tframe = d->stack[d->depth - 2];
    if (e != CS_OK)
        d->err = e;
}

static cs_err_t on_unsupported(doc_t *d, const char *local, const char **atts, size_t tag)
{
    (void)atts;
    if (d->stack[d->depth - 1].hidden)
        return CS_OK;
    d->stats->ignored++;
    warn_once(d, strcmp(local, "text") == 0 ? "text" : "image", tag,
              "ignoring <%s> elements: not drawn", local);
    return CS_OK;
}

/* <flowRoot>: Inkscape 0.x's flowed text (an SVG 1.2 draft no browser draws). Its text is
 * not drawn, and neither is its <flowRegion> shape, which is the frame the text flows in, not
 * something Inkscape shows: drawing it would plot a box nobody sees on screen. */
static cs_err_t on_flowed(doc_t *d, const char *local, const char **atts, size_t tag)
{
    (void)local;
    (void)atts;
    frame_t *f = &d->stack[d->depth - 1];
    if (!f->hidden) {
        d->stats->ignored++;
        warn_once(d, "flowRoot", tag,
                  "ignoring <flowRoot> (Inkscape flowed text): neither its text nor its frame is "
                  "drawn; Inkscape's Text > Convert to Text makes it drawable");
    }
    f->hidden = true;
    return CS_OK;
}

/* What each SVG element does. Unlisted elements (title, desc, style, metadata...) are skipped
 * with their subtree drawn normally. */
static const struct {
    const char *name;
    elem_fn fn;
} handlers[] = {
    {"svg", on_svg},          {"g", on_container},       {"a", on_container},
    {"switch", on_container}, {"path", on_path},         {"defs", on_hidden},
    {"symbol", on_symbol},    {"clipPath", on_hidden},   {"mask", on_hidden},
    {"marker", on_hidden},    {"pattern", on_hidden},    {"rect", on_rect},
    {"circle", on_ellipse},   {"ellipse", on_ellipse},   {"line", on_line},
    {"polyline", on_poly},    {"polygon", on_poly},      {"text", on_text},
    {"use", on_use},          {"image", on_unsupported}, {"tspan", on_tspan},
    {"flowRoot", on_flowed},
};

/* The local name when el is in the SVG namespace (or in none), else NULL. */
static const char *svg_local(const char *el)
{
    const char *sep = strchr(el, NS_SEP);
    if (!sep)
        return el;
    size_t nl = (size_t)(sep - el);
    if (nl == strlen(SVG_NS) && memcmp(el, SVG_NS, nl) == 0)
        return sep + 1;
    return NULL;
}

/* --- first pass: the document tree ------------------------------------------------------- */

static bool pass1_fail(doc_t *d)
{
    if (d->err == CS_OK)
        d->err = cs_path_diag_set(d->diag, CS_ERR_FULL, loc_of(d, d->cur.off), "out of memory");
    XML_StopParser(d->xp, XML_FALSE);
    return false;
}

/* A new node under the open element at raw offset tag; its index in *idx. */
static bool node_add(doc_t *d, size_t tag, size_t *idx)
{
    void *nn = d->nodes;
    if (!cs_path_grow(&nn, &d->ncap, d->nnodes + 1, sizeof *d->nodes))
        return pass1_fail(d);
    d->nodes = nn;
    node_t *n = &d->nodes[d->nnodes];
    memset(n, 0, sizeof *n);
    n->tag = tag;
    cursor_advance(&d->cur, tag);
    n->at = d->cur;
    n->parent = d->open;
    n->first = n->last = n->next = NONE;
    if (d->open != NONE) {
        node_t *p = &d->nodes[d->open];
        if (p->last != NONE)
            d->nodes[p->last].next = d->nnodes;
        else
            p->first = d->nnodes;
        p->last = d->nnodes;
    }
    *idx = d->nnodes++;
    return true;
}

/* Copies expat's attribute list and the local name into one allocation. */
static char **atts_copy(const char *local, const XML_Char **atts)
{
    size_t n = 0, bytes = local ? strlen(local) + 1 : 0;
    for (; atts[n]; n++)
        bytes += strlen(atts[n]) + 1;
    char **v = malloc((n + 2) * sizeof *v + bytes);
    if (!v)
        return NULL;
    char *p = (char *)(v + n + 2);
    for (size_t i = 0; i < n; i++) {
        size_t k = strlen(atts[i]) + 1;
        v[i] = memcpy(p, atts[i], k);
        p += k;
    }
    v[n] = NULL;
    v[n + 1] = local ? memcpy(p, local, strlen(local) + 1) : NULL; /* the name, after the NULL */
    return v;
}

static bool is_textlike(const char *local)
{
    return local && (strcmp(local, "text") == 0 || strcmp(local, "style") == 0);
}

static void XMLCALL on_start(void *ud, const XML_Char *el, const XML_Char **atts)
{
    doc_t *d = ud;
    XML_Index bi = XML_GetCurrentByteIndex(d->xp);
    size_t idx;
    if (!node_add(d, bi < 0 ? d->cur.off : (size_t)bi, &idx))
        return;
    node_t *n = &d->nodes[idx];
    const char *local = svg_local(el);
    size_t na = 0;
    while (atts[na])
        na++;
    n->atts = atts_copy(local, atts);
    if (!n->atts) {
        pass1_fail(d);
        return;
    }
    n->local = n->atts[na + 1];
    d->open = idx;
    if (is_textlike(n->local))
        d->textlike++;
}

static void XMLCALL on_end(void *ud, const XML_Char *el)
{
    doc_t *d = ud;
    (void)el;
    if (d->open == NONE)
        return;
    if (is_textlike(d->nodes[d->open].local))
        d->textlike--;
    d->open = d->nodes[d->open].parent;
}

/* Character data inside <text> and <style> (the rest is white space between elements or
 * content of elements that are not drawn). */
static void XMLCALL on_chars(void *ud, const XML_Char *s, int len)
{
    doc_t *d = ud;
    if (d->textlike == 0 || len <= 0 || d->err != CS_OK)
        return;
    XML_Index bi = XML_GetCurrentByteIndex(d->xp);
    size_t idx;
    if (!node_add(d, bi < 0 ? d->cur.off : (size_t)bi, &idx))
        return;
    char *t = malloc((size_t)len);
    if (!t) {
        pass1_fail(d);
        return;
    }
    memcpy(t, s, (size_t)len);
    d->nodes[idx].text = t;
    d->nodes[idx].tn = (size_t)len;
}

static int id_cmp(const void *a, const void *b)
{
    const idref_t *x = a, *y = b;
    int c = strcmp(x->id, y->id);
    return c ? c : (x->node > y->node) - (x->node < y->node);
}

/* The id index and the elements as selectors see them. */
static cs_err_t index_nodes(doc_t *d)
{
    d->ids = malloc((d->nnodes ? d->nnodes : 1) * sizeof *d->ids);
    d->elems = malloc((d->nnodes ? d->nnodes : 1) * sizeof *d->elems);
    if (!d->ids || !d->elems) {
        cs_path_loc_t l = {d->name, 0, 0};
        return cs_path_diag_set(d->diag, CS_ERR_FULL, l, "out of memory");
    }
    for (size_t i = 0; i < d->nnodes; i++) {
        const node_t *n = &d->nodes[i];
        cs_css_elem_t *e = &d->elems[i];
        memset(e, 0, sizeof *e);
        e->parent = n->parent == NONE ? NULL : &d->elems[n->parent];
        if (!n->atts)
            continue;
        e->name = n->local;
        e->id = att_get((const char **)n->atts, "id");
        e->cls = att_get((const char **)n->atts, "class");
        if (e->id && n->local) {
            d->ids[d->nids].id = e->id;
            d->ids[d->nids++].node = i;
        }
    }
    qsort(d->ids, d->nids, sizeof *d->ids, id_cmp);
    return CS_OK;
}

/* --- style sheets ------------------------------------------------------------------------- */

/* Where a sheet's warnings point: its <style> element, whose character data pieces give the raw
 * offset of each byte of the sheet's text. */
typedef struct {
    doc_t *d;
    size_t node;
} sheet_ctx_t;

static void sheet_warn(void *ctx, size_t off, const char *kind, const char *msg)
{
    sheet_ctx_t *c = ctx;
    doc_t *d = c->d;
    size_t raw = d->nodes[c->node].tag;
    for (size_t k = d->nodes[c->node].first; k != NONE; k = d->nodes[k].next) {
        const node_t *t = &d->nodes[k];
        if (t->atts)
            continue;
        raw = t->tag + off;
        if (off < t->tn)
            break;
        off -= t->tn;
    }
    warn_once(d, kind, raw, "style sheet: %s", msg);
}

/* Every <style> (type text/css or none) into the sheet, in document order. */
static cs_err_t read_sheets(doc_t *d)
{
    for (size_t i = 0; i < d->nnodes; i++) {
        const node_t *n = &d->nodes[i];
        if (!n->local || strcmp(n->local, "style") != 0)
            continue;
        const char *type = att_get((const char **)n->atts, "type");
        if (type && type[0] && strcmp(type, "text/css") != 0) {
            warn_once(d, "style-type", n->tag, "ignoring a <style> of type '%.60s'", type);
            continue;
        }
        size_t len = 0, k;
        for (k = n->first; k != NONE; k = d->nodes[k].next)
            len += d->nodes[k].atts ? 0 : d->nodes[k].tn;
        char *text = malloc(len + 1), *p = text;
        if (!text)
            return cs_path_diag_set(d->diag, CS_ERR_FULL, loc_of(d, n->tag), "out of memory");
        for (k = n->first; k != NONE; k = d->nodes[k].next)
            if (!d->nodes[k].atts) {
                memcpy(p, d->nodes[k].text, d->nodes[k].tn);
                p += d->nodes[k].tn;
            }
        sheet_ctx_t c = {d, i};
        bool ok = cs_css_add(&d->sheet, text, len, sheet_warn, &c);
        free(text);
        if (!ok)
            return cs_path_diag_set(d->diag, CS_ERR_FULL, loc_of(d, n->tag), "out of memory");
    }
    return CS_OK;
}

/* --- second pass: the walk ------------------------------------------------------------------ */

/* Starts node idx (as the referenced element of a <use> when instance): a frame inheriting
 * its parent's, its style, its element's handler. */
static cs_err_t enter(doc_t *d, size_t idx, bool instance)
{
    void *ns = d->stack;
    if (!cs_path_grow(&ns, &d->cap, d->depth + 1, sizeof *d->stack))
        return cs_path_diag_set(d->diag, CS_ERR_FULL, loc_of(d, d->nodes[idx].tag),
                                "out of memory");
    d->stack = ns;
    frame_t *f = &d->stack[d->depth];
    if (d->depth > 0) { /* a new frame inherits transform, visibility, paint, viewport */
        *f = d->stack[d->depth - 1];
    } else {
        memset(f, 0, sizeof *f);
        f->m = cs_path_affine_identity();
        f->fill = true;    /* SVG initial values: fill black, stroke none */
        f->font_size = 16; /* font-size: medium (CSS: 16 px) */
    }
    bool in_use = d->depth > 0 && f->use_depth > 0; /* the parent is a <use> or inside one */
    d->depth++;
    f->node = idx;
    f->inst = NONE;
    f->instance = instance;
    f->entered = false;
    const node_t *n = &d->nodes[idx];
    if (!n->atts) {
        f->none = true; /* character data: no children */
        return text_append(d, n->text, n->tn);
    }
    if (in_use && ++d->inst_elems > CS_SVGDOC_MAX_USE_ELEMENTS) {
        cs_path_loc_t l = {d->name, n->at.line, n->at.col}; /* nested uses multiply */
        return cs_path_diag_set(d->diag, CS_ERR_RANGE, l,
                                "more than %u elements drawn through <use> "
                                "(CS_SVGDOC_MAX_USE_ELEMENTS)",
                                (unsigned)CS_SVGDOC_MAX_USE_ELEMENTS);
    }
    d->cur = n->at;
    d->tag = n->at;
    const char **atts = (const char **)n->atts;
    if (idx == 0 && (!n->local || strcmp(n->local, "svg") != 0))
        warn_once(d, "root", n->tag, "the root element is not <svg>");
    if (!n->local || f->none)
        return CS_OK; /* foreign elements, and everything under display="none" */
    cs_css_value_t sheet[NPROPS];
    if (d->sheet.nrules)
        cs_css_cascade(&d->sheet, &d->elems[idx], style_props, NPROPS, sheet);
    else
        memset(sheet, 0, sizeof sheet);
    read_style(atts, sheet, f);
    if (f->none) {
        d->stats->ignored++;
        return CS_OK;
    }
    for (size_t i = 0; i < sizeof handlers / sizeof handlers[0]; i++)
        if (strcmp(n->local, handlers[i].name) == 0)
            return handlers[i].fn(d, n->local, atts, n->tag);
    return CS_OK;
}

static void leave(doc_t *d)
{
    if (d->nodes[d->stack[d->depth - 1].node].atts)
        text_end(d); /* the end of an element (not of character data) */
    d->depth--;
}

static bool is_switch(const doc_t *d, size_t node)
{
    const char *l = d->nodes[node].local;
    return l && d->nodes[node].atts && strcmp(l, "switch") == 0;
}

/* systemLanguage="en-US, fr": true when a tag is English ("en" or "en-..."): the reader has
 * no user language, and English is the likeliest reader of a file that offers it. */
static bool language_ok(const char *v)
{
    while (*v) {
        while (*v == ' ' || *v == ',' || *v == '\t' || *v == '\n' || *v == '\r')
            v++;
        if ((v[0] == 'e' || v[0] == 'E') && (v[1] == 'n' || v[1] == 'N') &&
            (v[2] == '\0' || v[2] == '-' || v[2] == ',' || v[2] == ' '))
            return true;
        while (*v && *v != ',')
            v++;
    }
    return false;
}

/* <switch> (SVG 1.1 §5.8): only its first direct child whose conditions hold is drawn. Here
 * requiredFeatures holds (SVG 2 drops it), a non-empty requiredExtensions does not (the reader
 * has no extension), systemLanguage holds for English; and a <foreignObject> is passed over,
 * since it draws nothing here, so its SVG fallback is drawn (draw.io writes each label as an
 * HTML foreignObject with a <text> after it, and ends every file with a switch whose first
 * child is an empty <g>, so that "Text is not SVG - cannot display" shows only in viewers
 * without SVG 1.1: it is not drawn). NONE when no child qualifies. */
static size_t switch_pick(const doc_t *d, size_t sw)
{
    for (size_t k = d->nodes[sw].first; k != NONE; k = d->nodes[k].next) {
        const node_t *n = &d->nodes[k];
        if (!n->local || !n->atts || strcmp(n->local, "foreignObject") == 0)
            continue;
        const char **atts = (const char **)n->atts;
        const char *ext = att_get(atts, "requiredExtensions");
        const char *lang = att_get(atts, "systemLanguage");
        if (ext && strspn(ext, " \t\r\n") != strlen(ext))
            continue;
        if (lang && !language_ok(lang))
            continue;
        return k;
    }
    return NONE;
}

/* Depth first from the root: each element's children in order (a <use>: the element it refers
 * to; a <switch>: its one child switch_pick chooses), a <use>'s instance ending with it. */
static cs_err_t walk(doc_t *d)
{
    if (d->nnodes == 0)
        return CS_OK;
    cs_err_t e = enter(d, 0, false);
    while (e == CS_OK && d->err == CS_OK && d->depth > 0) {
        frame_t *f = &d->stack[d->depth - 1];
        if (!f->entered) {
            f->entered = true;
            size_t child = f->none              ? NONE
                           : f->inst != NONE      ? f->inst
                           : is_switch(d, f->node) ? switch_pick(d, f->node)
                                                   : d->nodes[f->node].first;
            if (child != NONE) {
                e = enter(d, child, child == f->inst);
                continue;
            }
        }
        size_t node = f->node;
        bool instance = f->instance;
        leave(d);
        if (d->depth > 0 && !instance && d->nodes[node].next != NONE &&
            !is_switch(d, d->stack[d->depth - 1].node))
            e = enter(d, d->nodes[node].next, false);
    }
    return e != CS_OK ? e : d->err;
}

void cs_svgdoc_opts_init(cs_svgdoc_opts_t *o)
{
    memset(o, 0, sizeof *o);
    o->xform = cs_path_affine_identity();
}

/* Pass 1: expat reads the whole document into d->nodes. */
static cs_err_t read_tree(doc_t *d)
{
    d->xp = XML_ParserCreateNS(NULL, NS_SEP);
    if (!d->xp) {
        cs_path_loc_t l = {d->name, 0, 0};
        return cs_path_diag_set(d->diag, CS_ERR_FULL, l, "out of memory");
    }
    XML_SetUserData(d->xp, d);
    XML_SetElementHandler(d->xp, on_start, on_end);
    XML_SetCharacterDataHandler(d->xp, on_chars);
    enum XML_Status st = XML_Parse(d->xp, d->buf, (int)d->len, XML_TRUE);
    cs_err_t e = d->err;
    if (e == CS_OK && st != XML_STATUS_OK) {
        cs_path_loc_t l = {d->name, (unsigned)XML_GetCurrentLineNumber(d->xp),
                           (unsigned)XML_GetCurrentColumnNumber(d->xp) + 1};
        e = cs_path_diag_set(d->diag, CS_ERR_PARSE, l, "XML error: %s",
                             XML_ErrorString(XML_GetErrorCode(d->xp)));
    }
    XML_ParserFree(d->xp);
    d->xp = NULL;
    return e;
}

static void doc_free(doc_t *d)
{
    for (size_t i = 0; i < d->nnodes; i++) {
        free(d->nodes[i].atts);
        free((char *)d->nodes[i].text);
    }
    free(d->nodes);
    free(d->ids);
    free(d->elems);
    cs_css_free(&d->sheet);
    free(d->stack);
    free(d->tbuf);
}

cs_err_t cs_svgdoc_parse(const char *buf, size_t len, const char *name, const cs_svgdoc_opts_t *o,
                         cs_path_t *path, cs_path_diag_t *diag, cs_svgdoc_stats_t *stats)
{
    cs_svgdoc_stats_t local_stats;
    cs_svgdoc_opts_t defaults;
    if (!o) {
        cs_svgdoc_opts_init(&defaults);
        o = &defaults;
    }
    doc_t d;
    memset(&d, 0, sizeof d);
    d.buf = buf;
    d.len = len;
    d.o = o;
    d.path = path;
    d.diag = diag;
    d.stats = stats ? stats : &local_stats;
    memset(d.stats, 0, sizeof *d.stats);
    d.cur.buf = buf;
    d.cur.len = len;
    cursor_reset(&d.cur);
    d.tag = d.cur;
    d.open = NONE;
    cs_css_init(&d.sheet);
    d.name = cs_path_intern(path, name ? name : "-");
    if (!d.name) {
        cs_path_loc_t l = {"-", 0, 0};
        return cs_path_diag_set(diag, CS_ERR_FULL, l, "out of memory");
    }
    if (len > INT_MAX) {
        cs_path_loc_t l = {d.name, 0, 0};
        return cs_path_diag_set(diag, CS_ERR_IO, l, "file too large for the XML parser");
    }
    cs_err_t e = read_tree(&d);
    if (e == CS_OK)
        e = index_nodes(&d);
    if (e == CS_OK)
        e = read_sheets(&d);
    if (e == CS_OK)
        e = walk(&d);
    doc_free(&d);
    return e;
}

cs_err_t cs_svgdoc_read(const char *buf, size_t len, const char *name, const cs_svgdoc_opts_t *o,
                        cs_path_t *path, cs_path_diag_t *diag, cs_svgdoc_stats_t *stats)
{
    /* A UTF-8 byte order mark may precede either kind of input. */
    size_t i = cs_readall_bom(buf, len);
    while (i < len && is_xml_space(buf[i]))
        i++;
    if (i < len && buf[i] == '<')
        return cs_svgdoc_parse(buf, len, name, o, path, diag, stats);
    if (stats)
        memset(stats, 0, sizeof *stats);
    cs_svgpath_opts_t po;
    cs_svgpath_opts_init(&po, name);
    if (o)
        po.xform = o->xform;
    /* Bare path data: lines and columns counted in the data itself (a BOM is no column). */
    /* Not a document: browsers never see it, so SVG's error handling does not apply; an error
     * anywhere in a job's one path stays an error (nothing is drawn or sent). */
    size_t bom = cs_readall_bom(buf, len);
    return cs_svgpath_parse(buf + bom, len - bom, &po, path, diag);
}

cs_err_t cs_svgdoc_read_file(const char *filename, const cs_svgdoc_opts_t *o, cs_path_t *path,
                             cs_path_diag_t *diag, cs_svgdoc_stats_t *stats)
{
    char *buf = NULL;
    size_t len = 0;
    cs_err_t e = cs_svgdoc_load(filename, &buf, &len, diag);
    if (e != CS_OK)
        return e;
    e = cs_svgdoc_read(buf, len, strcmp(filename, "-") == 0 ? "<stdin>" : filename, o, path, diag,
                       stats);
    free(buf);
    return e;
}
