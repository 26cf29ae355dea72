/* cs_surffile: Newell or native surface files -> core patches (see cs_surffile.h). */
#include "cs_surffile.h"
#include "cs_readall.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_coons.h"
#include "cs_conv.h"
#include "cs_err_text.h"
#include "cs_patchfile.h"
#include "cs_revolve.h"

#define NATIVE_MAGIC "curvestep-surfaces"

typedef struct {
    const char *p, *end;
    unsigned line, col;
    const char *name;
    cs_path_diag_t *diag;
    double scale;
    /* the token just read */
    char tok[64];
    unsigned tline, tcol;
} lex_t;

static cs_path_loc_t here(const lex_t *lx)
{
    cs_path_loc_t l = {lx->name, lx->tline, lx->tcol};
    return l;
}

/* Next token into lx->tok; false at end of text. */
static bool next_tok(lex_t *lx)
{
    for (;;) {
        while (lx->p < lx->end && isspace((unsigned char)*lx->p)) {
            if (*lx->p == '\n') {
                lx->line++;
                lx->col = 1;
            } else {
                lx->col++;
            }
            lx->p++;
        }
        if (lx->p < lx->end && *lx->p == '#') {
            while (lx->p < lx->end && *lx->p != '\n')
                lx->p++;
            continue;
        }
        break;
    }
    if (lx->p >= lx->end) {
        lx->tline = lx->line;
        lx->tcol = lx->col;
        return false;
    }
    lx->tline = lx->line;
    lx->tcol = lx->col;
    size_t k = 0;
    while (lx->p < lx->end && !isspace((unsigned char)*lx->p) && *lx->p != '#') {
        if (k < sizeof lx->tok - 1)
            lx->tok[k++] = *lx->p;
        lx->p++;
        lx->col++;
    }
    lx->tok[k] = '\0';
    return true;
}

static cs_err_t number(lex_t *lx, const char *what, double *out)
{
    if (!next_tok(lx))
        return cs_path_diag_set(lx->diag, CS_ERR_PARSE, here(lx), "end of file: %s expected", what);
    char *e = NULL;
    errno = 0;
    double v = strtod(lx->tok, &e);
    if (e == lx->tok || *e != '\0' || !isfinite(v))
        return cs_path_diag_set(lx->diag, CS_ERR_PARSE, here(lx), "'%s': %s expected", lx->tok,
                                what);
    *out = v;
    return CS_OK;
}

static cs_err_t integer(lex_t *lx, const char *what, int lo, int hi, int *out)
{
    double v;
    cs_err_t e = number(lx, what, &v);
    if (e != CS_OK)
        return e;
    if (v != floor(v) || v < lo || v > hi)
        return cs_path_diag_set(lx->diag, CS_ERR_RANGE, here(lx), "%s must be an integer %d..%d",
                                what, lo, hi);
    *out = (int)v;
    return CS_OK;
}

/* Three numbers; a point (scaled, range-checked) into *p, the raw scaled values into d[]. */
static cs_err_t vec(lex_t *lx, const char *what, cs_vec3_t *p, double d[3])
{
    double v[3];
    unsigned line = 0, col = 0;
    for (int k = 0; k < 3; k++) {
        cs_err_t e = number(lx, what, &v[k]);
        if (e != CS_OK)
            return e;
        if (k == 0) {
            line = lx->tline;
            col = lx->tcol;
        }
        v[k] *= lx->scale;
    }
    if (d)
        for (int k = 0; k < 3; k++)
            d[k] = v[k];
    if (p && cs_conv_mm_to_vec(v[0], v[1], v[2], p) != CS_OK) {
        cs_path_loc_t l = {lx->name, line, col};
        return cs_path_diag_set(lx->diag, CS_ERR_RANGE, l, "%s (%g, %g, %g) mm is outside +/-%d mm",
                                what, v[0], v[1], v[2], CS_POS_LIMIT_MM);
    }
    return CS_OK;
}

static cs_err_t curve(lex_t *lx, cs_bezier_t *c)
{
    int n;
    cs_err_t e = integer(lx, "curve degree", 1, 3, &n);
    if (e != CS_OK)
        return e;
    cs_vec3_t pts[4];
    for (int i = 0; i <= n; i++) {
        e = vec(lx, "curve point", &pts[i], NULL);
        if (e != CS_OK)
            return e;
    }
    return cs_bezier_init(c, (unsigned)n, pts);
}

static cs_err_t push(cs_surffile_t *sf, const cs_surf_item_t *it)
{
    if (sf->n == sf->cap) {
        size_t nc = sf->cap ? 2 * sf->cap : 16;
        cs_surf_item_t *ni = realloc(sf->items, nc * sizeof *ni);
        if (!ni)
            return CS_ERR_FULL;
        sf->items = ni;
        sf->cap = nc;
    }
    sf->items[sf->n++] = *it;
    return CS_OK;
}

static cs_err_t push_quad(cs_surffile_t *sf, const cs_patch_t *p, unsigned line)
{
    cs_surf_item_t it;
    memset(&it, 0, sizeof it);
    it.quad = *p;
    it.line = line;
    return push(sf, &it);
}

/* One statement after its keyword (in lx->tok). */
static cs_err_t statement(lex_t *lx, cs_surffile_t *sf, double rev_tol)
{
    char kw[64];
    snprintf(kw, sizeof kw, "%s", lx->tok);
    cs_path_loc_t at = here(lx);
    cs_err_t e = CS_OK;
    cs_patch_t p;
    if (strcmp(kw, "bezier") == 0) {
        int du, dv;
        cs_vec3_t pts[16];
        e = integer(lx, "degree in u", 1, 3, &du);
        if (e == CS_OK)
            e = integer(lx, "degree in v", 1, 3, &dv);
        for (int k = 0; e == CS_OK && k < (du + 1) * (dv + 1); k++)
            e = vec(lx, "control point", &pts[k], NULL);
        if (e == CS_OK && (e = cs_patch_init(&p, (unsigned)du, (unsigned)dv, pts)) == CS_OK)
            return push_quad(sf, &p, at.line);
    } else if (strcmp(kw, "tri") == 0) {
        int n;
        cs_vec3_t pts[CS_TRIPATCH_MAX_POINTS];
        e = integer(lx, "degree", 1, 3, &n);
        for (int k = 0; e == CS_OK && k < (n + 1) * (n + 2) / 2; k++)
            e = vec(lx, "control point", &pts[k], NULL);
        cs_surf_item_t it;
        memset(&it, 0, sizeof it);
        if (e == CS_OK && (e = cs_tripatch_init(&it.trip, (unsigned)n, pts)) == CS_OK) {
            it.tri = true;
            it.line = at.line;
            return push(sf, &it);
        }
    } else if (strcmp(kw, "hermite") == 0 || strcmp(kw, "power") == 0) {
        bool herm = kw[0] == 'h';
        cs_vec3_t v[16];
        for (int k = 0; e == CS_OK && k < 16; k++)
            e = vec(lx, herm ? "Hermite vector" : "coefficient", &v[k], NULL);
        if (e == CS_OK) {
            if (herm) {
                cs_patch_hermite_t h;
                for (int k = 0; k < 4; k++) {
                    int a = k % 2, b = k / 2;
                    h.p[a][b] = v[k];
                    h.pu[a][b] = v[4 + k];
                    h.pv[a][b] = v[8 + k];
                    h.puv[a][b] = v[12 + k];
                }
                e = cs_patch_from_hermite(&p, &h);
            } else {
                cs_vec3_t a[4][4];
                for (int k = 0; k < 16; k++)
                    a[k / 4][k % 4] = v[k];
                e = cs_patch_from_power(&p, a);
            }
            if (e == CS_OK)
                return push_quad(sf, &p, at.line);
        }
    } else if (strcmp(kw, "coons-bilinear") == 0 || strcmp(kw, "coons-bicubic") == 0) {
        cs_bezier_t c[4];
        for (int k = 0; e == CS_OK && k < 4; k++)
            e = curve(lx, &c[k]);
        if (e == CS_OK) {
            e = strcmp(kw, "coons-bilinear") == 0
                    ? cs_coons_bilinear(&c[0], &c[1], &c[2], &c[3], &p)
                    : cs_coons_bicubic(&c[0], &c[1], &c[2], &c[3], NULL, NULL, NULL, NULL, &p);
            if (e == CS_OK)
                return push_quad(sf, &p, at.line);
        }
    } else if (strcmp(kw, "ruled") == 0) {
        cs_bezier_t c[2];
        for (int k = 0; e == CS_OK && k < 2; k++)
            e = curve(lx, &c[k]);
        if (e == CS_OK && (e = cs_coons_ruled(&c[0], &c[1], &p)) == CS_OK)
            return push_quad(sf, &p, at.line);
    } else if (strcmp(kw, "extrude") == 0) {
        cs_bezier_t c;
        cs_vec3_t d;
        e = curve(lx, &c);
        if (e == CS_OK)
            e = vec(lx, "direction", &d, NULL);
        if (e == CS_OK && (e = cs_coons_extrude(&c, &d, &p)) == CS_OK)
            return push_quad(sf, &p, at.line);
    } else if (strcmp(kw, "revolve") == 0) {
        double o[3], ax[3], rf[3], sweep;
        cs_bezier_t c;
        e = vec(lx, "axis origin", NULL, o);
        if (e == CS_OK)
            e = vec(lx, "axis direction", NULL, ax);
        if (e == CS_OK)
            e = vec(lx, "reference direction", NULL, rf);
        if (e == CS_OK)
            e = number(lx, "sweep in degrees", &sweep);
        if (e == CS_OK)
            e = curve(lx, &c);
        if (e == CS_OK) {
            cs_patch_t out[CS_REVOLVE_MAX_ARCS];
            size_t n = 0;
            e = cs_revolve(&c, o, ax, rf, sweep, rev_tol, out, CS_REVOLVE_MAX_ARCS, &n, NULL);
            for (size_t k = 0; e == CS_OK && k < n; k++)
                e = push_quad(sf, &out[k], at.line);
            if (e == CS_OK || e == CS_ERR_FULL)
                return e;
        }
    } else if (strcmp(kw, "varady") == 0 || strcmp(kw, "varady-scheme") == 0) {
        int n;
        cs_bezier_t c[CS_VARADY_MAX_SIDES];
        cs_varady_blend_t blend = CS_VARADY_MU;
        cs_varady_param_t param = CS_VARADY_SIDE;
        if (strcmp(kw, "varady-scheme") == 0) {
            /* varady-scheme BLEND PARAM N C x N */
            static const char *const blends[] = {"mu", "lambda-kappa"};
            static const char *const params[] = {"side", "radial", "centre"};
            int got = -1;
            if (next_tok(lx))
                for (int k = 0; k < 2; k++)
                    if (strcmp(lx->tok, blends[k]) == 0)
                        got = k;
            if (got < 0)
                return cs_path_diag_set(lx->diag, CS_ERR_PARSE, here(lx),
                                        "'%s': blend mu or lambda-kappa expected", lx->tok);
            blend = (cs_varady_blend_t)got;
            got = -1;
            if (next_tok(lx))
                for (int k = 0; k < 3; k++)
                    if (strcmp(lx->tok, params[k]) == 0)
                        got = k;
            if (got < 0)
                return cs_path_diag_set(lx->diag, CS_ERR_PARSE, here(lx),
                                        "'%s': parametrisation side, radial or centre expected",
                                        lx->tok);
            param = (cs_varady_param_t)got;
        }
        e = integer(lx, "number of sides", 3, CS_VARADY_MAX_SIDES, &n);
        for (int k = 0; e == CS_OK && k < n; k++)
            e = curve(lx, &c[k]);
        cs_surf_item_t *it = e == CS_OK ? calloc(1, sizeof *it) : NULL;
        if (e == CS_OK && !it)
            return CS_ERR_FULL;
        if (e == CS_OK && (e = cs_varady_init(&it->nside, c, (size_t)n)) == CS_OK &&
            (e = cs_varady_set_scheme(&it->nside, blend, param)) == CS_OK) {
            it->varady = true;
            it->line = at.line;
            e = push(sf, it);
            free(it);
            return e;
        }
        free(it);
    } else {
        return cs_path_diag_set(lx->diag, CS_ERR_PARSE, at,
                                "unknown surface '%s' (bezier, tri, hermite, power, "
                                "coons-bilinear, coons-bicubic, ruled, extrude, revolve, "
                                "varady, varady-scheme)",
                                kw);
    }
    if (e != CS_OK && lx->diag->code != e)
        return cs_path_diag_set(lx->diag, e, at, "%s: %s", kw, cs_err_text(e));
    return e;
}

void cs_surffile_free(cs_surffile_t *sf)
{
    free(sf->file);
    free(sf->items);
    memset(sf, 0, sizeof *sf);
}

static bool is_native(const char *text, size_t len)
{
    lex_t lx = {text, text + len, 1, 1, "", NULL, 1, "", 0, 0};
    return next_tok(&lx) && strcmp(lx.tok, NATIVE_MAGIC) == 0;
}

cs_err_t cs_surffile_parse(const char *text, size_t len, const char *name, double scale,
                           double rev_tol_mm, cs_surffile_t *sf, cs_path_diag_t *diag)
{
    memset(sf, 0, sizeof *sf);
    sf->file = strdup(name ? name : "-");
    if (!sf->file)
        return CS_ERR_FULL;
    diag->code = CS_OK;
    if (!is_native(text, len)) {
        cs_patchfile_t pf;
        cs_err_t e = cs_patchfile_parse(text, len, sf->file, &pf, diag);
        for (size_t i = 0; e == CS_OK && i < pf.npatches; i++) {
            cs_patch_t p;
            e = cs_patchfile_patch(&pf, i, scale, &p, diag);
            if (e == CS_OK)
                e = push_quad(sf, &p, pf.line[i]);
        }
        diag->loc.file = sf->file; /* pf's copy of the name goes away */
        cs_patchfile_free(&pf);
        return e;
    }
    sf->native = true;
    lex_t lx = {text, text + len, 1, 1, sf->file, diag, scale, "", 0, 0};
    next_tok(&lx); /* the magic */
    int version;
    cs_err_t e = integer(&lx, "format version", 1, 1, &version);
    while (e == CS_OK && next_tok(&lx))
        e = statement(&lx, sf, rev_tol_mm);
    if (e == CS_OK && sf->n == 0)
        e = cs_path_diag_set(diag, CS_ERR_EMPTY, here(&lx), "no surfaces in the file");
    return e;
}

cs_err_t cs_surffile_read(const char *filename, double scale, double rev_tol_mm, cs_surffile_t *sf,
                          cs_path_diag_t *diag)
{
    memset(sf, 0, sizeof *sf);
    bool use_stdin = strcmp(filename, "-") == 0;
    const char *name = use_stdin ? "<stdin>" : filename;
    char *buf = NULL;
    size_t n = 0;
    cs_err_t re = cs_readall_keep_name(filename, &buf, &n, &sf->file, diag);
    if (re != CS_OK)
        return re;
    cs_err_t e = cs_surffile_parse(buf ? buf : "", n, name, scale, rev_tol_mm, sf, diag);
    free(buf);
    return e;
}
