/* cs_patchfile: Newell's indexed patch format (see cs_patchfile.h), parsed line by line. */
#include "cs_patchfile.h"
#include "cs_readall.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_conv.h"

/* Most patches / vertices accepted (guards the allocation a hostile count would ask for). */
#define PATCHFILE_MAX_COUNT 1000000

typedef struct {
    const char *name;
    const char *s, *end; /* whole text */
    const char *line;    /* start of the current line */
    unsigned lineno;
    cs_path_diag_t *diag;
} lexer_t;

#define MAX_FIELDS 17 /* one more than any line needs, to report "too many" */
CS_STATIC_ASSERT(CS_PATCHFILE_MAX_POINTS >= 16, newell_patch_fits);

typedef struct {
    size_t n;
    double v[MAX_FIELDS];
    unsigned col[MAX_FIELDS];
    bool integer[MAX_FIELDS];
    unsigned lineno, endcol;
} fields_t;

static cs_path_loc_t loc(const lexer_t *lx, unsigned line, unsigned col)
{
    cs_path_loc_t l = {lx->name, line, col};
    return l;
}

/* Next non-blank line split into numbers; false at end of text. CS_ERR_PARSE in *e for a
 * malformed field. */
static bool next_line(lexer_t *lx, fields_t *f, cs_err_t *e)
{
    *e = CS_OK;
    while (lx->s < lx->end) {
        const char *b = lx->s, *nl = memchr(b, '\n', (size_t)(lx->end - b));
        const char *le = nl ? nl : lx->end;
        lx->s = nl ? nl + 1 : lx->end;
        lx->lineno++;
        f->n = 0;
        f->lineno = lx->lineno;
        const char *p = b;
        bool want_value = false; /* after a comma */
        while (p < le) {
            while (p < le && (*p == ' ' || *p == '\t' || *p == '\r'))
                p++;
            if (p >= le)
                break;
            unsigned col = (unsigned)(p - b) + 1;
            if (*p == ',') {
                if (f->n == 0 || want_value) {
                    *e = cs_path_diag_set(lx->diag, CS_ERR_PARSE, loc(lx, lx->lineno, col),
                                          "empty field before ','");
                    return true;
                }
                want_value = true;
                p++;
                continue;
            }
            char buf[64];
            size_t k = 0;
            while (p + k < le && k < sizeof buf - 1 && !isspace((unsigned char)p[k]) && p[k] != ',')
                buf[k] = p[k], k++;
            buf[k] = '\0';
            if (p + k < le && !isspace((unsigned char)p[k]) && p[k] != ',') {
                *e = cs_path_diag_set(lx->diag, CS_ERR_PARSE, loc(lx, lx->lineno, col),
                                      "number longer than %zu characters", sizeof buf - 1);
                return true;
            }
            char *ep = NULL;
            errno = 0;
            double v = strtod(buf, &ep);
            if (ep == buf || *ep != '\0' || !isfinite(v) || (errno == ERANGE && fabs(v) > 1.0)) {
                bool overflow = ep != buf && *ep == '\0' && errno == ERANGE; /* not underflow */
                *e = cs_path_diag_set(lx->diag, overflow ? CS_ERR_RANGE : CS_ERR_PARSE,
                                      loc(lx, lx->lineno, col), "'%s' is not a finite number", buf);
                return true;
            }
            if (f->n == MAX_FIELDS) {
                f->n++; /* the caller reports "too many" */
                f->endcol = col;
                return true;
            }
            f->v[f->n] = v;
            f->col[f->n] = col;
            f->integer[f->n] = strspn(buf, "+-0123456789") == k;
            f->n++;
            want_value = false;
            p += k;
        }
        if (want_value) {
            *e = cs_path_diag_set(lx->diag, CS_ERR_PARSE,
                                  loc(lx, lx->lineno, (unsigned)(le - b) + 1),
                                  "a number was expected after the last ','");
            return true;
        }
        f->endcol = (unsigned)(le - b) + 1;
        if (f->n > 0)
            return true;
    }
    return false;
}

/* A count line: exactly one integer 1..PATCHFILE_MAX_COUNT. */
static cs_err_t read_count(lexer_t *lx, const char *what, size_t *out)
{
    fields_t f;
    cs_err_t e;
    if (!next_line(lx, &f, &e))
        return cs_path_diag_set(lx->diag, CS_ERR_PARSE, loc(lx, lx->lineno + 1, 1),
                                "end of file: the %s count was expected", what);
    if (e != CS_OK)
        return e;
    if (f.n != 1 || !f.integer[0])
        return cs_path_diag_set(lx->diag, CS_ERR_PARSE, loc(lx, f.lineno, f.col[0]),
                                "expected the %s count (one integer) on this line", what);
    if (f.v[0] < 1 || f.v[0] > PATCHFILE_MAX_COUNT)
        return cs_path_diag_set(lx->diag, CS_ERR_RANGE, loc(lx, f.lineno, f.col[0]),
                                "%s count %.0f outside 1..%d", what, f.v[0], PATCHFILE_MAX_COUNT);
    *out = (size_t)f.v[0];
    return CS_OK;
}

void cs_patchfile_free(cs_patchfile_t *pf)
{
    free(pf->file);
    free(pf->idx);
    free(pf->deg);
    free(pf->line);
    free(pf->vert);
    free(pf->vert_line);
    memset(pf, 0, sizeof *pf);
}

/* Room for n patches' indices, degrees and lines. */
static cs_err_t alloc_patches(cs_patchfile_t *pf, size_t n)
{
    pf->npatches = n;
    pf->idx = calloc(n, sizeof *pf->idx);
    pf->deg = calloc(n, sizeof *pf->deg);
    pf->line = calloc(n, sizeof *pf->line);
    return pf->idx && pf->deg && pf->line ? CS_OK : CS_ERR_FULL;
}

/* Room for n vertices. */
static cs_err_t alloc_verts(cs_patchfile_t *pf, size_t n)
{
    pf->nverts = n;
    pf->vert = calloc(n, sizeof *pf->vert);
    pf->vert_line = calloc(n, sizeof *pf->vert_line);
    return pf->vert && pf->vert_line ? CS_OK : CS_ERR_FULL;
}

/* One "x y z" line into vertex v. */
static cs_err_t read_vertex(lexer_t *lx, cs_patchfile_t *pf, size_t v, const char *what, size_t of)
{
    fields_t f;
    cs_err_t e;
    if (!next_line(lx, &f, &e))
        return cs_path_diag_set(lx->diag, CS_ERR_PARSE, loc(lx, lx->lineno + 1, 1),
                                "end of file after %zu of %zu %s", v, of, what);
    if (e != CS_OK)
        return e;
    if (f.n != 3)
        return cs_path_diag_set(lx->diag, CS_ERR_PARSE, loc(lx, f.lineno, f.endcol),
                                "vertex %zu: expected x,y,z (3 numbers), found %s%zu", v + 1,
                                f.n > MAX_FIELDS ? "more than " : "",
                                f.n > MAX_FIELDS ? (size_t)MAX_FIELDS : f.n);
    for (unsigned a = 0; a < 3; a++)
        pf->vert[v][a] = f.v[a];
    pf->vert_line[v] = f.lineno;
    return CS_OK;
}

/* .bpt: per patch "degu degv" then its points, each stored as a vertex of its own. */
static cs_err_t parse_bpt(lexer_t *lx, cs_patchfile_t *pf)
{
    size_t np = pf->npatches, nv = 0;
    if (alloc_verts(pf, np * CS_PATCHFILE_MAX_POINTS) != CS_OK)
        return CS_ERR_FULL;
    for (size_t i = 0; i < np; i++) {
        fields_t f;
        cs_err_t e;
        if (!next_line(lx, &f, &e))
            return cs_path_diag_set(lx->diag, CS_ERR_PARSE, loc(lx, lx->lineno + 1, 1),
                                    "end of file after %zu of %zu patches", i, np);
        if (e != CS_OK)
            return e;
        for (unsigned k = 0; k < 2 && f.n == 2; k++)
            if (!f.integer[k] || f.v[k] < 1 || f.v[k] > CS_PATCH_MAX_DEGREE)
                return cs_path_diag_set(lx->diag, CS_ERR_DEGREE, loc(lx, f.lineno, f.col[k]),
                                        "patch %zu: degree %g outside 1..%d (.bpt format)", i + 1,
                                        f.v[k], CS_PATCH_MAX_DEGREE);
        if (f.n != 2)
            return cs_path_diag_set(lx->diag, CS_ERR_PARSE, loc(lx, f.lineno, f.endcol),
                                    "patch %zu: expected 'degu degv' (.bpt format), found %zu "
                                    "numbers",
                                    i + 1, f.n);
        pf->deg[i][0] = (uint8_t)f.v[0];
        pf->deg[i][1] = (uint8_t)f.v[1];
        pf->line[i] = f.lineno;
        size_t npts = (size_t)(pf->deg[i][0] + 1) * (size_t)(pf->deg[i][1] + 1);
        for (size_t k = 0; k < npts; k++, nv++) {
            pf->idx[i][k] = nv;
            if ((e = read_vertex(lx, pf, nv, "control points", nv + npts - k)) != CS_OK)
                return e;
        }
    }
    pf->nverts = nv;
    return CS_OK;
}

/* Newell's format after the patch count: index lines, vertex count, vertices. */
static cs_err_t parse_newell(lexer_t *lx, cs_patchfile_t *pf)
{
    cs_path_diag_t *diag = lx->diag;
    cs_err_t e = CS_OK;
    unsigned(*icol)[16] = calloc(pf->npatches, sizeof *icol);
    if (!icol)
        return CS_ERR_FULL;
    for (size_t i = 0; i < pf->npatches; i++) {
        fields_t f;
        if (!next_line(lx, &f, &e)) {
            e = cs_path_diag_set(diag, CS_ERR_PARSE, loc(lx, lx->lineno + 1, 1),
                                 "end of file after %zu of %zu patches", i, pf->npatches);
            break;
        }
        if (e != CS_OK)
            break;
        if (f.n != 16) {
            e = cs_path_diag_set(diag, CS_ERR_PARSE, loc(lx, f.lineno, f.endcol),
                                 "patch %zu: expected 16 vertex indices (Newell's format%s), "
                                 "found %s%zu",
                                 i + 1, i == 0 ? "; a .bpt file has 'degu degv' here" : "",
                                 f.n > 16 ? "more than " : "", f.n > 16 ? (size_t)16 : f.n);
            break;
        }
        pf->line[i] = f.lineno;
        pf->deg[i][0] = pf->deg[i][1] = 3;
        for (unsigned k = 0; k < 16; k++) {
            /* Beyond the vertex count limit it cannot name a vertex (and would not fit a
             * size_t: the fuzzer's 8.9e53). */
            if (!f.integer[k] || f.v[k] < 1 || f.v[k] > PATCHFILE_MAX_COUNT) {
                e = cs_path_diag_set(diag, f.integer[k] ? CS_ERR_RANGE : CS_ERR_PARSE,
                                     loc(lx, f.lineno, f.col[k]),
                                     "vertex index must be an integer from 1 to %d (indices "
                                     "are one-based)",
                                     PATCHFILE_MAX_COUNT);
                break;
            }
            pf->idx[i][k] = (size_t)f.v[k] - 1;
            icol[i][k] = f.col[k];
        }
        if (e != CS_OK)
            break;
    }
    size_t nverts = 0;
    if (e == CS_OK)
        e = read_count(lx, "vertex", &nverts);
    /* Every index must name a vertex (checked now that the count is known). */
    for (size_t i = 0; i < pf->npatches && e == CS_OK; i++)
        for (unsigned k = 0; k < 16 && e == CS_OK; k++)
            if (pf->idx[i][k] >= nverts)
                e = cs_path_diag_set(diag, CS_ERR_RANGE, loc(lx, pf->line[i], icol[i][k]),
                                     "vertex index %zu outside 1..%zu", pf->idx[i][k] + 1, nverts);
    free(icol);
    if (e == CS_OK)
        e = alloc_verts(pf, nverts);
    for (size_t i = 0; e == CS_OK && i < nverts; i++)
        e = read_vertex(lx, pf, i, "vertices", nverts);
    return e;
}

/* Which format: the line after the patch count holds 2 degrees (.bpt) or, in Newell's format,
 * 16 indices (parse_newell refuses any other count, naming both formats). */
static cs_err_t which_format(const lexer_t *lx, bool *bpt)
{
    lexer_t peek = *lx;
    fields_t f;
    cs_err_t e;
    if (!next_line(&peek, &f, &e))
        return cs_path_diag_set(lx->diag, CS_ERR_PARSE, loc(lx, lx->lineno + 1, 1),
                                "end of file: the first patch was expected");
    if (e != CS_OK)
        return e;
    *bpt = f.n == 2;
    return CS_OK;
}

cs_err_t cs_patchfile_parse(const char *text, size_t len, const char *name, cs_patchfile_t *pf,
                            cs_path_diag_t *diag)
{
    memset(pf, 0, sizeof *pf);
    pf->file = strdup(name ? name : "-");
    if (!pf->file)
        return CS_ERR_FULL;
    if (cs_readall_blank(text, len)) {
        cs_path_loc_t l = {pf->file, 1, 1};
        return cs_path_diag_set(diag, CS_ERR_EMPTY, l,
                                "no drawable geometry (the patch file is empty)");
    }
    size_t bom = cs_readall_bom(text, len); /* as the other readers: a leading BOM is skipped */
    lexer_t lx = {pf->file, text + bom, text + len, text + bom, 0, diag};
    size_t np = 0;
    cs_err_t e = read_count(&lx, "patch", &np);
    if (e == CS_OK)
        e = which_format(&lx, &pf->bpt);
    if (e == CS_OK)
        e = alloc_patches(pf, np);
    if (e == CS_OK)
        e = pf->bpt ? parse_bpt(&lx, pf) : parse_newell(&lx, pf);
    fields_t f;
    if (e == CS_OK && next_line(&lx, &f, &e) && e == CS_OK)
        e = cs_path_diag_set(diag, CS_ERR_PARSE, loc(&lx, f.lineno, f.col[0]),
                             "unexpected data after the last %s", pf->bpt ? "patch" : "vertex");
    if (e == CS_OK)
        return CS_OK;
    /* Keep only the name, which the diagnostic points to (freed by cs_patchfile_free). */
    char *file = pf->file;
    pf->file = NULL;
    cs_patchfile_free(pf);
    pf->file = file;
    return e;
}

cs_err_t cs_patchfile_read(const char *filename, cs_patchfile_t *pf, cs_path_diag_t *diag)
{
    memset(pf, 0, sizeof *pf);
    bool use_stdin = strcmp(filename, "-") == 0;
    const char *name = use_stdin ? "<stdin>" : filename;
    char *buf = NULL;
    size_t n = 0;
    cs_err_t re = cs_readall_keep_name(filename, &buf, &n, &pf->file, diag);
    if (re != CS_OK)
        return re;
    cs_err_t e = cs_patchfile_parse(buf, n, name, pf, diag);
    free(buf);
    return e;
}

cs_err_t cs_patchfile_patch(const cs_patchfile_t *pf, size_t i, double scale, cs_patch_t *out,
                            cs_path_diag_t *diag)
{
    if (i >= pf->npatches || !isfinite(scale))
        return CS_ERR_ARG;
    cs_vec3_t pts[CS_PATCHFILE_MAX_POINTS];
    unsigned du = pf->deg[i][0], dv = pf->deg[i][1];
    for (unsigned k = 0; k < (du + 1) * (dv + 1); k++) {
        size_t v = pf->idx[i][k];
        const double *q = pf->vert[v];
        if (cs_conv_mm_to_vec(q[0] * scale, q[1] * scale, q[2] * scale, &pts[k]) != CS_OK) {
            cs_path_loc_t l = {pf->file, pf->vert_line[v], 1};
            return cs_path_diag_set(diag, CS_ERR_RANGE, l,
                                    "vertex %zu (patch %zu) times scale %g is outside +/-%d mm",
                                    v + 1, i + 1, scale, CS_POS_LIMIT_MM);
        }
    }
    return cs_patch_init(out, du, dv, pts);
}

cs_err_t cs_patchfile_write(FILE *f, const cs_patch_t *patches, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (patches[i].deg_u != 3 || patches[i].deg_v != 3)
            return CS_ERR_DEGREE;
    fprintf(f, "%zu\n", n);
    for (size_t i = 0; i < n; i++)
        for (unsigned k = 0; k < 16; k++)
            fprintf(f, "%zu%c", 16 * i + k + 1, k == 15 ? '\n' : ',');
    fprintf(f, "%zu\n", 16 * n);
    for (size_t i = 0; i < n; i++)
        for (unsigned k = 0; k < 16; k++) {
            const cs_vec3_t *p = &patches[i].p[k / 4][k % 4];
            fprintf(f, "%.6f,%.6f,%.6f\n", cs_conv_pos_to_mm(p->x), cs_conv_pos_to_mm(p->y),
                    cs_conv_pos_to_mm(p->z));
        }
    return ferror(f) ? CS_ERR_IO : CS_OK;
}
