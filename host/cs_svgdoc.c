/* cs_svgdoc: SVG documents through expat (see cs_svgdoc.h).
 * Expat hands over attribute values already decoded, without positions; to point an error at
 * the right character, the raw start tag is re-scanned from expat's byte index, the attribute's
 * value decoded here with a map from each decoded byte to its offset in the file. */
#include "cs_svgdoc.h"

#include <errno.h>
#include <expat.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_svgpath.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define SVG_NS "http://www.w3.org/2000/svg"
/* Element names come from expat as "namespace-URI<sep>local-name" (or just "local-name"). */
#define NS_SEP     '\x1f'
#define MAX_WARNED 32

/* --- file loading ------------------------------------------------------------------------ */

cs_err_t cs_svgdoc_load(const char *filename, char **buf, size_t *len, cs_path_diag_t *diag)
{
    bool is_stdin = strcmp(filename, "-") == 0;
    cs_path_loc_t loc = {is_stdin ? "<stdin>" : filename, 0, 0};
    FILE *f = is_stdin ? stdin : fopen(filename, "rb");
    if (!f)
        return cs_path_diag_set(diag, CS_ERR_IO, loc, "cannot open: %s", strerror(errno));
    size_t cap = 1 << 16, n = 0;
    char *b = malloc(cap);
    cs_err_t e = CS_OK;
    while (b) {
        if (n + 1 >= cap) {
            char *nb = cap < ((size_t)-1) / 2 ? realloc(b, cap * 2) : NULL;
            if (!nb) {
                free(b);
                b = NULL;
                break;
            }
            b = nb;
            cap *= 2;
        }
        size_t got = fread(b + n, 1, cap - 1 - n, f);
        n += got;
        if (got == 0) {
            if (ferror(f))
                e = cs_path_diag_set(diag, CS_ERR_IO, loc, "read error: %s", strerror(errno));
            break;
        }
    }
    if (!is_stdin)
        fclose(f);
    if (!b)
        return cs_path_diag_set(diag, CS_ERR_FULL, loc, "out of memory");
    if (e != CS_OK) {
        free(b);
        return e;
    }
    b[n] = '\0';
    *buf = b;
    *len = n;
    return CS_OK;
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
        size_t nl = i - ns;
        const char *name = s + ns;
        int kind;
        unsigned minargs, maxargs;
        if (nl == 6 && memcmp(name, "matrix", 6) == 0) {
            kind = 0;
            minargs = maxargs = 6;
        } else if (nl == 9 && memcmp(name, "translate", 9) == 0) {
            kind = 1;
            minargs = 1;
            maxargs = 2;
        } else if (nl == 5 && memcmp(name, "scale", 5) == 0) {
            kind = 2;
            minargs = 1;
            maxargs = 2;
        } else if (nl == 6 && memcmp(name, "rotate", 6) == 0) {
            kind = 3;
            minargs = 1;
            maxargs = 3;
        } else if (nl == 5 && memcmp(name, "skewX", 5) == 0) {
            kind = 4;
            minargs = maxargs = 1;
        } else if (nl == 5 && memcmp(name, "skewY", 5) == 0) {
            kind = 5;
            minargs = maxargs = 1;
        } else {
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
        unsigned n = 0;
        for (;;) {
            while (i < len && is_xml_space(s[i]))
                i++;
            if (i < len && s[i] == ')' && n > 0)
                break;
            if (n > 0 && i < len && s[i] == ',') {
                i++;
                while (i < len && is_xml_space(s[i]))
                    i++;
            }
            if (n >= maxargs) {
                *bad = i;
                *why = "too many arguments for this transform";
                return CS_ERR_PARSE;
            }
            size_t b = 0;
            size_t k = cs_svgpath_scan_number(s + i, len - i, &v[n], &b);
            if (k == 0) {
                *bad = i + b;
                *why = "expected a number in the transform";
                return CS_ERR_PARSE;
            }
            if (!isfinite(v[n])) {
                *bad = i;
                *why = "number too large";
                return CS_ERR_PARSE;
            }
            i += k;
            n++;
        }
        if (n < minargs || (kind == 3 && n == 2)) {
            *bad = i;
            *why = "too few arguments for this transform";
            return CS_ERR_PARSE;
        }
        i++; /* ')' */
        cs_path_affine_t t = cs_path_affine_identity();
        switch (kind) {
        case 0:
            t.a = v[0];
            t.b = v[1];
            t.c = v[2];
            t.d = v[3];
            t.e = v[4];
            t.f = v[5];
            break;
        case 1:
            t.e = v[0];
            t.f = n > 1 ? v[1] : 0.0;
            break;
        case 2:
            t.a = v[0];
            t.d = n > 1 ? v[1] : v[0];
            break;
        case 3: {
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
        case 4:
            t.c = tan(v[0] * (M_PI / 180.0));
            break;
        default:
            t.b = tan(v[0] * (M_PI / 180.0));
            break;
        }
        m = cs_path_affine_mul(m, t);
        need_sep = true;
    }
    *out = m;
    return CS_OK;
}

/* --- the document walk ------------------------------------------------------------------ */

typedef struct {
    cs_path_affine_t m; /* user space of this element -> mm */
    bool hidden;        /* inside <defs>, <symbol>, <clipPath>...: not drawn directly */
} frame_t;

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
    unsigned elements; /* start tags seen */
    cs_err_t err;
    const char *warned[MAX_WARNED];
    size_t nwarned;
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
        fprintf(stderr, "%s:%u:%u: warning: %s\n", w.loc.file, w.loc.line, w.loc.col, w.reason);
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

static cs_err_t on_path(doc_t *d, const char *local, const char **atts, size_t tag)
{
    frame_t *f = &d->stack[d->depth - 1];
    d->stats->paths++;
    if (f->hidden) {
        d->stats->ignored++;
        warn_once(d, "hidden-path", tag,
                  "ignoring <%s> inside <defs>/<symbol>/<clipPath>... (not drawn directly; <use> "
                  "is not supported yet)",
                  local);
        return CS_OK;
    }
    cs_err_t e = element_transform(d, atts, tag, &f->m);
    if (e != CS_OK)
        return e;
    const char *dv = att_get(atts, "d");
    if (!dv)
        return CS_OK; /* no 'd': nothing is rendered (SVG 1.1 §8.3.1) */
    attr_t a;
    if ((e = attr_load(d, dv, "d", tag, &a)) != CS_OK)
        return e;
    cs_svgpath_opts_t po;
    cs_svgpath_opts_init(&po, d->name);
    po.xform = cs_path_affine_mul(d->o->xform, f->m);
    po.locate = attr_locate;
    po.locate_ctx = &a;
    e = cs_svgpath_parse(a.text, a.n, &po, d->path, d->diag);
    attr_free(&a);
    return e;
}

static cs_err_t on_unsupported(doc_t *d, const char *local, const char **atts, size_t tag)
{
    (void)atts;
    if (d->stack[d->depth - 1].hidden)
        return CS_OK;
    d->stats->ignored++;
    static const char *const shapes[] = {"rect", "circle",   "ellipse",
                                         "line", "polyline", "polygon"};
    for (size_t i = 0; i < sizeof shapes / sizeof shapes[0]; i++)
        if (strcmp(local, shapes[i]) == 0) {
            warn_once(d, shapes[i], tag,
                      "ignoring <%s> elements: basic shapes are not supported yet (only <path>)",
                      local);
            return CS_OK;
        }
    static const char *const others[] = {"text", "use", "image"};
    for (size_t i = 0; i < sizeof others / sizeof others[0]; i++)
        if (strcmp(local, others[i]) == 0) {
            warn_once(d, others[i], tag, "ignoring <%s> elements: not drawn", local);
            return CS_OK;
        }
    return CS_OK;
}

/* What each SVG element does. Unlisted elements (title, desc, style, metadata...) are skipped
 * with their subtree drawn normally; shapes, units (width/height/viewBox on <svg>) and <use>
 * get their own handlers here when they are implemented. */
static const struct {
    const char *name;
    elem_fn fn;
} handlers[] = {
    {"svg", on_container},        {"g", on_container},         {"a", on_container},
    {"switch", on_container},     {"path", on_path},           {"defs", on_hidden},
    {"symbol", on_hidden},        {"clipPath", on_hidden},     {"mask", on_hidden},
    {"marker", on_hidden},        {"pattern", on_hidden},      {"rect", on_unsupported},
    {"circle", on_unsupported},   {"ellipse", on_unsupported}, {"line", on_unsupported},
    {"polyline", on_unsupported}, {"polygon", on_unsupported}, {"text", on_unsupported},
    {"use", on_unsupported},      {"image", on_unsupported},
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

static void XMLCALL on_start(void *ud, const XML_Char *el, const XML_Char **atts)
{
    doc_t *d = ud;
    if (d->err != CS_OK)
        return;
    if (d->depth == d->cap) {
        size_t ncap = d->cap ? d->cap * 2 : 16;
        frame_t *ns = realloc(d->stack, ncap * sizeof *ns);
        if (!ns) {
            d->err = cs_path_diag_set(d->diag, CS_ERR_FULL, loc_of(d, d->cur.off), "out of memory");
            XML_StopParser(d->xp, XML_FALSE);
            return;
        }
        d->stack = ns;
        d->cap = ncap;
    }
    /* A new frame inherits its parent's transform and visibility. */
    if (d->depth > 0)
        d->stack[d->depth] = d->stack[d->depth - 1];
    else {
        d->stack[0].m = cs_path_affine_identity();
        d->stack[0].hidden = false;
    }
    d->depth++;
    XML_Index bi = XML_GetCurrentByteIndex(d->xp);
    size_t tag = bi < 0 ? d->cur.off : (size_t)bi;
    cursor_advance(&d->cur, tag);
    d->tag = d->cur;
    const char *local = svg_local(el);
    if (d->elements++ == 0 && (!local || strcmp(local, "svg") != 0))
        warn_once(d, "root", tag, "the root element is not <svg>");
    if (!local)
        return;
    for (size_t i = 0; i < sizeof handlers / sizeof handlers[0]; i++)
        if (strcmp(local, handlers[i].name) == 0) {
            cs_err_t e = handlers[i].fn(d, local, atts, tag);
            if (e != CS_OK) {
                d->err = e;
                XML_StopParser(d->xp, XML_FALSE);
            }
            return;
        }
}

static void XMLCALL on_end(void *ud, const XML_Char *el)
{
    doc_t *d = ud;
    (void)el;
    if (d->depth > 0)
        d->depth--;
}

void cs_svgdoc_opts_init(cs_svgdoc_opts_t *o)
{
    memset(o, 0, sizeof *o);
    o->xform = cs_path_affine_identity();
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
    d.name = cs_path_intern(path, name ? name : "-");
    if (!d.name) {
        cs_path_loc_t l = {"-", 0, 0};
        return cs_path_diag_set(diag, CS_ERR_FULL, l, "out of memory");
    }
    if (len > INT_MAX) {
        cs_path_loc_t l = {d.name, 0, 0};
        return cs_path_diag_set(diag, CS_ERR_IO, l, "file too large for the XML parser");
    }
    d.xp = XML_ParserCreateNS(NULL, NS_SEP);
    if (!d.xp) {
        cs_path_loc_t l = {d.name, 0, 0};
        return cs_path_diag_set(diag, CS_ERR_FULL, l, "out of memory");
    }
    XML_SetUserData(d.xp, &d);
    XML_SetElementHandler(d.xp, on_start, on_end);
    enum XML_Status st = XML_Parse(d.xp, buf, (int)len, XML_TRUE);
    cs_err_t e = d.err;
    if (e == CS_OK && st != XML_STATUS_OK) {
        cs_path_loc_t l = {d.name, (unsigned)XML_GetCurrentLineNumber(d.xp),
                           (unsigned)XML_GetCurrentColumnNumber(d.xp) + 1};
        e = cs_path_diag_set(diag, CS_ERR_PARSE, l, "XML error: %s",
                             XML_ErrorString(XML_GetErrorCode(d.xp)));
    }
    XML_ParserFree(d.xp);
    free(d.stack);
    return e;
}

cs_err_t cs_svgdoc_read(const char *buf, size_t len, const char *name, const cs_svgdoc_opts_t *o,
                        cs_path_t *path, cs_path_diag_t *diag, cs_svgdoc_stats_t *stats)
{
    size_t i = 0;
    /* A UTF-8 byte order mark may precede either kind of input. */
    if (len >= 3 && (unsigned char)buf[0] == 0xEF && (unsigned char)buf[1] == 0xBB &&
        (unsigned char)buf[2] == 0xBF)
        i = 3;
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
    size_t bom = (len >= 3 && (unsigned char)buf[0] == 0xEF && (unsigned char)buf[1] == 0xBB &&
                  (unsigned char)buf[2] == 0xBF)
                     ? 3
                     : 0;
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
