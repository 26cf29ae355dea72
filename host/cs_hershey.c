/* cs_hershey: .jhf reader and text layout (see cs_hershey.h). */
#include "cs_hershey.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef struct {
    const char *name, *buf;
    size_t len, pos;
    unsigned line, col;
    cs_path_diag_t *diag;
} rd_t;

/* The next character of the record, skipping line ends (records wrap); -1 at the end. */
static int next_char(rd_t *r, bool wrap)
{
    while (r->pos < r->len && wrap && (r->buf[r->pos] == '\n' || r->buf[r->pos] == '\r')) {
        if (r->buf[r->pos] == '\n') {
            r->line++;
            r->col = 0;
        }
        r->pos++;
    }
    if (r->pos >= r->len || r->buf[r->pos] == '\n' || r->buf[r->pos] == '\r')
        return -1;
    r->col++;
    return (unsigned char)r->buf[r->pos++];
}

static cs_err_t bad(rd_t *r, const char *why)
{
    cs_path_loc_t loc = {r->name, r->line, r->col ? r->col : 1};
    return cs_path_diag_set(r->diag, CS_ERR_PARSE, loc, "not a Hershey font (.jhf): %s", why);
}

/* A right-aligned number in a fixed field of w columns. */
static bool field(rd_t *r, int w, long *out)
{
    long v = 0;
    bool digits = false;
    for (int i = 0; i < w; i++) {
        int c = next_char(r, false);
        if (c >= '0' && c <= '9') {
            v = v * 10 + (c - '0');
            digits = true;
        } else if (!(c == ' ' && !digits)) {
            return false;
        }
    }
    *out = v;
    return digits;
}

static cs_err_t add_vertex(cs_hershey_font_t *f, size_t *cap, int x, int y, bool move)
{
    void *b = f->v;
    if (!cs_path_grow(&b, cap, f->nv + 1, sizeof *f->v))
        return CS_ERR_FULL;
    f->v = b;
    f->v[f->nv].x = (signed char)x;
    f->v[f->nv].y = (signed char)y;
    f->v[f->nv++].move = move;
    return CS_OK;
}

/* One record: number, count, count pairs (the first the bearings). */
static cs_err_t record(rd_t *r, cs_hershey_font_t *f, size_t *cap)
{
    long num, count;
    if (!field(r, 5, &num))
        return bad(r, "columns 1-5 must hold the glyph number");
    if (!field(r, 3, &count) || count < 1)
        return bad(r, "columns 6-8 must hold the number of coordinate pairs (at least 1)");
    if (f->nglyphs == CS_HERSHEY_MAX_GLYPHS)
        return bad(r, "more than 96 glyphs (ASCII 32..127)");
    cs_hershey_glyph_t *g = &f->glyph[f->nglyphs];
    g->first = f->nv;
    bool move = true;
    for (long k = 0; k < count; k++) {
        int a = next_char(r, true), b = next_char(r, true);
        if (a < 0 || b < 0)
            return bad(r, "the record ends before its coordinate pairs do");
        if (a < ' ' || a > '~' || b < ' ' || b > '~')
            return bad(r, "a coordinate is not a printable character");
        if (k == 0) {
            g->left = a - 'R';
            g->right = b - 'R';
        } else if (a == ' ' && b == 'R') {
            move = true;
        } else {
            if (add_vertex(f, cap, a - 'R', b - 'R', move) != CS_OK)
                return CS_ERR_FULL;
            move = false;
        }
    }
    if (g->right < g->left)
        return bad(r, "the right bearing is left of the left one");
    while (r->pos < r->len && r->buf[r->pos] == ' ') /* trailing blanks of the record's line */
        next_char(r, false);
    g->n = f->nv - g->first;
    f->nglyphs++;
    return CS_OK;
}

cs_err_t cs_hershey_parse(const char *name, const char *buf, size_t len, cs_hershey_font_t *f,
                          cs_path_diag_t *diag)
{
    memset(f, 0, sizeof *f);
    rd_t r = {name, buf, len, 0, 1, 0, diag};
    size_t cap = 0;
    while (r.pos < len) {
        if (buf[r.pos] == '\n' || buf[r.pos] == '\r') { /* line ends between records */
            r.line += buf[r.pos] == '\n';
            r.col = 0;
            r.pos++;
            continue;
        }
        cs_err_t e = record(&r, f, &cap);
        if (e != CS_OK) {
            cs_hershey_free(f);
            return e == CS_ERR_FULL ? cs_path_diag_set(diag, e, (cs_path_loc_t){name, r.line, 1},
                                                       "out of memory")
                                    : e;
        }
    }
    if (f->nglyphs == 0) {
        cs_path_loc_t loc = {name, 1, 1};
        return cs_path_diag_set(diag, CS_ERR_PARSE, loc, "not a Hershey font (.jhf): no glyph");
    }
    return CS_OK;
}

cs_err_t cs_hershey_load(const char *file, cs_hershey_font_t *f, cs_path_diag_t *diag)
{
    memset(f, 0, sizeof *f);
    cs_path_loc_t loc = {file, 0, 0};
    FILE *fp = fopen(file, "rb");
    if (fp == NULL)
        return cs_path_diag_set(diag, CS_ERR_IO, loc, "cannot open the font: %s", strerror(errno));
    char *buf = NULL;
    size_t len = 0, cap = 0;
    cs_err_t e = CS_OK;
    for (;;) {
        if (len == cap) {
            /* 1 MB: ten times the largest Hershey font; more is not a font */
            char *nb = cap < (1u << 20) ? realloc(buf, cap ? 2 * cap : 8192) : NULL;
            if (nb == NULL) {
                e = cs_path_diag_set(diag, CS_ERR_PARSE, loc, "not a Hershey font: too large");
                break;
            }
            buf = nb;
            cap = cap ? 2 * cap : 8192;
        }
        size_t got = fread(buf + len, 1, cap - len, fp);
        len += got;
        if (got == 0)
            break;
    }
    if (e == CS_OK && ferror(fp))
        e = cs_path_diag_set(diag, CS_ERR_IO, loc, "read error");
    fclose(fp);
    if (e == CS_OK)
        e = cs_hershey_parse(file, buf, len, f, diag);
    free(buf);
    return e;
}

void cs_hershey_free(cs_hershey_font_t *f)
{
    free(f->v);
    memset(f, 0, sizeof *f);
}

bool cs_hershey_default_path(char *out, size_t outlen)
{
    char exe[4096];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n <= 0)
        return false;
    exe[n] = '\0';
    char *slash = strrchr(exe, '/');
    if (slash == NULL)
        return false;
    *slash = '\0'; /* the program's folder */
    /* build/curvestep (the repository's share/), build/asan/curvestep (a build variant's),
     * PREFIX/bin/curvestep (installed). */
    static const char *const rel[] = {"../share/fonts/futural.jhf", "../../share/fonts/futural.jhf",
                                      "../share/curvestep/fonts/futural.jhf"};
    for (size_t i = 0; i < sizeof rel / sizeof rel[0]; i++) {
        int k = snprintf(out, outlen, "%s/%s", exe, rel[i]);
        if (k > 0 && (size_t)k < outlen && access(out, R_OK) == 0)
            return true;
    }
    return false;
}

/* The glyph of character c: '?' (or the space) for one the font lacks. */
static const cs_hershey_glyph_t *glyph_of(const cs_hershey_font_t *f, unsigned char c)
{
    size_t i = c >= 32 ? (size_t)(c - 32) : f->nglyphs;
    if (i >= f->nglyphs)
        i = (size_t)('?' - 32) < f->nglyphs ? (size_t)('?' - 32) : 0;
    return &f->glyph[i];
}

double cs_hershey_width(const cs_hershey_font_t *f, const char *s, size_t n)
{
    double w = 0;
    for (size_t i = 0; i < n; i++) {
        const cs_hershey_glyph_t *g = glyph_of(f, (unsigned char)s[i]);
        w += g->right - g->left;
    }
    return w;
}

cs_err_t cs_hershey_layout(const cs_hershey_font_t *f, const char *s, size_t n, double x, double y,
                           double sx, double sy, cs_hershey_emit_fn emit, void *ctx)
{
    double adv = 0;
    for (size_t i = 0; i < n; i++) {
        const cs_hershey_glyph_t *g = glyph_of(f, (unsigned char)s[i]);
        for (size_t k = 0; k < g->n; k++) {
            const cs_hershey_vertex_t *v = &f->v[g->first + k];
            cs_err_t e = emit(ctx, x + sx * (adv + v->x - g->left),
                              y + sy * (v->y - CS_HERSHEY_BASELINE), v->move);
            if (e != CS_OK)
                return e;
        }
        adv += g->right - g->left;
    }
    return CS_OK;
}
