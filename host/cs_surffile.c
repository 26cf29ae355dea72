/* cs_surffile: Newell or native surface files -> core patches (see cs_surffile.h). */
#include "cs_surffile.h"
#include "cs_readall.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_coons.h"
#include "cs_conv.h"
#include "cs_err_text.h"
#include "cs_gcoons.h"
#include "cs_lex.h"
#include "cs_patchfile.h"
#include "cs_revolve.h"

#define NATIVE_MAGIC "curvestep-surfaces"

static cs_err_t curve(cs_lex_t *lx, cs_bezier_t *c)
{
    int n;
    cs_err_t e = cs_lex_integer(lx, "curve degree", 1, 3, &n);
    if (e != CS_OK)
        return e;
    cs_vec3_t pts[4];
    for (int i = 0; i <= n; i++) {
        e = cs_lex_vec(lx, "curve point", &pts[i], NULL);
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

/* coons-bicubic C C C C [derivatives C C C C] [twists V V V V] (after the keyword): boundaries
 * p1 p2 q1 q2, cross-boundary derivative curves p1v p2v q1u q2u, twists at the corners (u, v) =
 * (0,0) (1,0) (0,1) (1,1) (seed 000; cs_coons_bicubic_twist). */
static cs_err_t coons_bicubic(cs_lex_t *lx, cs_patch_t *p)
{
    cs_bezier_t c[8];
    const cs_bezier_t *der[4] = {NULL, NULL, NULL, NULL};
    cs_vec3_t tw[2][2];
    bool twists = false;
    cs_err_t e = CS_OK;
    for (int k = 0; e == CS_OK && k < 4; k++)
        e = curve(lx, &c[k]);
    if (e == CS_OK && cs_lex_peek_is(lx, "derivatives")) {
        cs_lex_next(lx);
        for (int k = 0; e == CS_OK && k < 4; k++) {
            e = curve(lx, &c[4 + k]); /* mm per unit parameter, within the point range */
            der[k] = &c[4 + k];
        }
    }
    if (e == CS_OK && cs_lex_peek_is(lx, "twists")) {
        cs_lex_next(lx);
        twists = true;
        for (int k = 0; e == CS_OK && k < 4; k++)
            e = cs_lex_vec(lx, "twist vector", &tw[k % 2][k / 2], NULL);
    }
    if (e != CS_OK)
        return e;
    return cs_coons_bicubic_twist(&c[0], &c[1], &c[2], &c[3], der[0], der[1], der[2], der[3],
                                  twists ? (const cs_vec3_t(*)[2])tw : NULL, p);
}

/* A blend of coons-blend: linear | hermite | bernstein b0 b1 b2 b3 (cs_gcoons). */
static cs_err_t blend(cs_lex_t *lx, cs_gcoons_blend_t *f)
{
    static const char *const kinds[] = {"linear", "hermite", "bernstein"};
    int k = 0;
    cs_err_t e = cs_lex_choice(lx, "blend linear, hermite or bernstein", kinds, 3, &k);
    if (e != CS_OK)
        return e;
    if (k < 2) {
        *f = k == 0 ? cs_gcoons_linear() : cs_gcoons_hermite();
        return CS_OK;
    }
    for (int i = 0; e == CS_OK && i < 4; i++)
        e = cs_lex_number(lx, "Bernstein coefficient of the blend", &f->b[i]);
    if (e == CS_OK && (f->b[0] != 1 || f->b[3] != 0))
        e = cs_path_diag_set(lx->diag, CS_ERR_RANGE, cs_lex_here(lx),
                             "a blend starts at 1 and ends at 0 (b0 = 1, b3 = 0; seed 002)");
    return e;
}

/* varady-scheme's words after the keyword: B P [domain D] (cs_varady). */
static cs_err_t varady_scheme(cs_lex_t *lx, cs_varady_blend_t *blend, cs_varady_param_t *param,
                              cs_varady_domain_t *domain)
{
    static const char *const blends[] = {"mu", "lambda-kappa"};
    static const char *const params[] = {"side", "radial", "centre", "biquadratic"};
    static const char *const doms[] = {"arc", "chords", "angles", "least-squares"};
    int got = 0;
    cs_err_t e = cs_lex_choice(lx, "blend mu or lambda-kappa", blends, 2, &got);
    *blend = (cs_varady_blend_t)got;
    if (e == CS_OK)
        e = cs_lex_choice(lx, "parametrisation side, radial, centre or biquadratic", params, 4,
                          &got);
    *param = (cs_varady_param_t)got;
    if (e == CS_OK && cs_lex_peek_is(lx, "domain")) {
        cs_lex_next(lx);
        e = cs_lex_choice(lx, "domain arc, chords, angles or least-squares", doms, 4, &got);
        *domain = (cs_varady_domain_t)got;
    }
    return e;
}

/* The optional "tangents C x n" and "twists V x n" of a varady statement, taken as written
 * (mm per domain unit, not scaled: the domain scales with the boundary). */
static cs_err_t varady_extras(cs_lex_t *lx, cs_varady_t *v)
{
    double scale = lx->scale;
    cs_err_t e = CS_OK;
    lx->scale = 1;
    if (cs_lex_peek_is(lx, "tangents")) {
        cs_bezier_t tan[CS_VARADY_MAX_SIDES];
        cs_lex_next(lx);
        for (size_t k = 0; e == CS_OK && k < v->n; k++)
            e = curve(lx, &tan[k]);
        if (e == CS_OK)
            e = cs_varady_set_tangents(v, tan);
    }
    if (e == CS_OK && cs_lex_peek_is(lx, "twists")) {
        double tw[CS_VARADY_MAX_SIDES][3];
        cs_lex_next(lx);
        for (size_t k = 0; e == CS_OK && k < v->n; k++)
            e = cs_lex_vec(lx, "twist", NULL, tw[k]);
        if (e == CS_OK)
            cs_varady_set_twists(v, (const double(*)[3])tw);
    }
    lx->scale = scale;
    return e;
}

/* varady N C x N [tangents ..] [twists ..], or varady-scheme B P [domain D] N C x N [..]. */
static cs_err_t varady(cs_lex_t *lx, bool scheme, unsigned line, cs_surffile_t *sf)
{
    int n;
    cs_bezier_t c[CS_VARADY_MAX_SIDES];
    cs_varady_blend_t blend = CS_VARADY_MU;
    cs_varady_param_t param = CS_VARADY_SIDE;
    cs_varady_domain_t domain = CS_VARADY_DOMAIN_ARC;
    cs_err_t e = scheme ? varady_scheme(lx, &blend, &param, &domain) : CS_OK;
    if (e == CS_OK)
        e = cs_lex_integer(lx, "number of sides", 3, CS_VARADY_MAX_SIDES, &n);
    for (int k = 0; e == CS_OK && k < n; k++)
        e = curve(lx, &c[k]);
    cs_surf_item_t *it = e == CS_OK ? calloc(1, sizeof *it) : NULL;
    if (e == CS_OK && !it)
        return CS_ERR_FULL;
    if (e == CS_OK && (e = cs_varady_init(&it->nside, c, (size_t)n)) == CS_OK &&
        (e = cs_varady_set_scheme(&it->nside, blend, param)) == CS_OK &&
        (e = cs_varady_set_domain(&it->nside, domain)) == CS_OK &&
        (e = varady_extras(lx, &it->nside)) == CS_OK) {
        it->varady = true;
        it->line = line;
        e = push(sf, it);
    }
    free(it);
    return e;
}

/* sphere C R (after the keyword): the exact sphere (cs_sphere), inside the coordinate range. */
static cs_err_t sphere(cs_lex_t *lx, unsigned line, cs_surffile_t *sf)
{
    cs_surf_item_t it;
    memset(&it, 0, sizeof it);
    cs_err_t e = cs_lex_vec(lx, "centre", NULL, it.sph.c);
    if (e == CS_OK)
        e = cs_lex_number(lx, "radius", &it.sph.r);
    if (e != CS_OK)
        return e;
    it.sph.r *= lx->scale;
    cs_vec3_t lo, hi;
    if (!(it.sph.r > 0) ||
        cs_conv_mm_to_vec(it.sph.c[0] - it.sph.r, it.sph.c[1] - it.sph.r, it.sph.c[2] - it.sph.r,
                          &lo) != CS_OK ||
        cs_conv_mm_to_vec(it.sph.c[0] + it.sph.r, it.sph.c[1] + it.sph.r, it.sph.c[2] + it.sph.r,
                          &hi) != CS_OK)
        return cs_path_diag_set(lx->diag, CS_ERR_RANGE, cs_lex_here(lx),
                                "radius %g mm: must be > 0 and keep the sphere inside +/-%d mm",
                                it.sph.r, CS_POS_LIMIT_MM);
    it.sphere = true;
    it.line = line;
    return push(sf, &it);
}

static const char *const keywords[] = {
    "bezier",        "tri",         "hermite", "power",         "coons-bilinear",
    "coons-bicubic", "coons-blend", "varady",  "varady-scheme", "ruled",
    "extrude",       "revolve",     "sphere",
};

const char *cs_surffile_keyword(size_t i)
{
    return i < sizeof keywords / sizeof keywords[0] ? keywords[i] : NULL;
}

void cs_surffile_keyword_list(char *buf, size_t cap)
{
    size_t n = 0;
    buf[0] = '\0';
    for (size_t i = 0; cs_surffile_keyword(i) && n + 1 < cap; i++) {
        int w = snprintf(buf + n, cap - n, "%s%s", i ? ", " : "", cs_surffile_keyword(i));
        n = w < 0 ? cap : n + (size_t)w;
    }
}

/* bezier DU DV then (DU + 1)(DV + 1) control points. */
static cs_err_t bezier_stmt(cs_lex_t *lx, cs_patch_t *p)
{
    int du, dv;
    cs_vec3_t pts[CS_PATCH_MAX_POINTS * CS_PATCH_MAX_POINTS];
    cs_err_t e = cs_lex_integer(lx, "degree in u", 1, CS_PATCH_MAX_DEGREE, &du);
    if (e == CS_OK)
        e = cs_lex_integer(lx, "degree in v", 1, CS_PATCH_MAX_DEGREE, &dv);
    for (int k = 0; e == CS_OK && k < (du + 1) * (dv + 1); k++)
        e = cs_lex_vec(lx, "control point", &pts[k], NULL);
    return e == CS_OK ? cs_patch_init(p, (unsigned)du, (unsigned)dv, pts) : e;
}

/* tri N then (N + 1)(N + 2) / 2 control points: pushed as a triangular item. */
static cs_err_t tri_stmt(cs_lex_t *lx, int line, cs_surffile_t *sf, bool *pushed)
{
    int n;
    cs_vec3_t pts[CS_TRIPATCH_MAX_POINTS];
    cs_err_t e = cs_lex_integer(lx, "degree", 1, CS_TRIPATCH_MAX_DEGREE, &n);
    for (int k = 0; e == CS_OK && k < (n + 1) * (n + 2) / 2; k++)
        e = cs_lex_vec(lx, "control point", &pts[k], NULL);
    cs_surf_item_t it;
    memset(&it, 0, sizeof it);
    if (e == CS_OK && (e = cs_tripatch_init(&it.trip, (unsigned)n, pts)) == CS_OK) {
        it.tri = true;
        it.line = line;
        *pushed = true;
        return push(sf, &it);
    }
    return e;
}

/* hermite (16 vectors: P, Pu, Pv, Puv at the four corners) or power (16 coefficients). */
static cs_err_t hermite_power_stmt(cs_lex_t *lx, bool herm, cs_patch_t *p)
{
    cs_vec3_t v[16];
    cs_err_t e = CS_OK;
    for (int k = 0; e == CS_OK && k < 16; k++)
        e = cs_lex_vec(lx, herm ? "Hermite vector" : "coefficient", &v[k], NULL);
    if (e != CS_OK)
        return e;
    if (herm) {
        cs_patch_hermite_t h;
        for (int k = 0; k < 4; k++) {
            int a = k % 2, b = k / 2;
            h.p[a][b] = v[k];
            h.pu[a][b] = v[4 + k];
            h.pv[a][b] = v[8 + k];
            h.puv[a][b] = v[12 + k];
        }
        return cs_patch_from_hermite(p, &h);
    }
    cs_vec3_t a[4][4];
    for (int k = 0; k < 16; k++)
        a[k / 4][k % 4] = v[k];
    return cs_patch_from_power(p, a);
}

/* The patches built from boundary curves: coons-bilinear, coons-blend, ruled, extrude. */
static cs_err_t curves_stmt(cs_lex_t *lx, const char *kw, cs_patch_t *p)
{
    cs_bezier_t c[4];
    cs_err_t e = CS_OK;
    if (strcmp(kw, "coons-blend") == 0) {
        cs_gcoons_blend_t f, g;
        e = blend(lx, &f);
        if (e == CS_OK)
            e = blend(lx, &g);
        for (int k = 0; e == CS_OK && k < 4; k++)
            e = curve(lx, &c[k]);
        return e == CS_OK ? cs_gcoons_build(&c[0], &c[1], &c[2], &c[3], &f, &g, p) : e;
    }
    if (strcmp(kw, "extrude") == 0) {
        cs_vec3_t d;
        e = curve(lx, &c[0]);
        if (e == CS_OK)
            e = cs_lex_vec(lx, "direction", &d, NULL);
        return e == CS_OK ? cs_coons_extrude(&c[0], &d, p) : e;
    }
    bool ruled = strcmp(kw, "ruled") == 0;
    for (int k = 0; e == CS_OK && k < (ruled ? 2 : 4); k++)
        e = curve(lx, &c[k]);
    if (e != CS_OK)
        return e;
    return ruled ? cs_coons_ruled(&c[0], &c[1], p) : cs_coons_bilinear(&c[0], &c[1], &c[2], &c[3], p);
}

/* revolve ORIGIN AXIS REF SWEEP CURVE: the arcs' patches pushed. */
static cs_err_t revolve_stmt(cs_lex_t *lx, int line, double rev_tol, cs_surffile_t *sf,
                             bool *pushed)
{
    double o[3], ax[3], rf[3], sweep;
    cs_bezier_t c;
    cs_err_t e = cs_lex_vec(lx, "axis origin", NULL, o);
    if (e == CS_OK)
        e = cs_lex_vec(lx, "axis direction", NULL, ax);
    if (e == CS_OK)
        e = cs_lex_vec(lx, "reference direction", NULL, rf);
    if (e == CS_OK)
        e = cs_lex_number(lx, "sweep in degrees", &sweep);
    if (e == CS_OK)
        e = curve(lx, &c);
    if (e != CS_OK)
        return e;
    cs_patch_t out[CS_REVOLVE_MAX_ARCS];
    size_t n = 0;
    e = cs_revolve(&c, o, ax, rf, sweep, rev_tol, out, CS_REVOLVE_MAX_ARCS, &n, NULL);
    for (size_t k = 0; e == CS_OK && k < n; k++)
        e = push_quad(sf, &out[k], line);
    *pushed = e == CS_OK || e == CS_ERR_FULL;
    return e;
}

/* One statement after its keyword (in lx->tok). Items that push themselves set pushed: their
 * code is returned as is; the others' patch is pushed here, and a constructor's failure gets
 * its located diagnostic. */
static cs_err_t statement(cs_lex_t *lx, cs_surffile_t *sf, double rev_tol)
{
    char kw[64];
    snprintf(kw, sizeof kw, "%s", lx->tok);
    cs_path_loc_t at = cs_lex_here(lx);
    cs_err_t e;
    cs_patch_t p;
    bool pushed = false;
    if (strcmp(kw, "bezier") == 0)
        e = bezier_stmt(lx, &p);
    else if (strcmp(kw, "tri") == 0)
        e = tri_stmt(lx, at.line, sf, &pushed);
    else if (strcmp(kw, "hermite") == 0 || strcmp(kw, "power") == 0)
        e = hermite_power_stmt(lx, kw[0] == 'h', &p);
    else if (strcmp(kw, "coons-bicubic") == 0)
        e = coons_bicubic(lx, &p);
    else if (strcmp(kw, "coons-bilinear") == 0 || strcmp(kw, "coons-blend") == 0 ||
             strcmp(kw, "ruled") == 0 || strcmp(kw, "extrude") == 0)
        e = curves_stmt(lx, kw, &p);
    else if (strcmp(kw, "sphere") == 0)
        return sphere(lx, at.line, sf);
    else if (strcmp(kw, "revolve") == 0)
        e = revolve_stmt(lx, at.line, rev_tol, sf, &pushed);
    else if (strcmp(kw, "varady") == 0 || strcmp(kw, "varady-scheme") == 0) {
        e = varady(lx, strcmp(kw, "varady-scheme") == 0, at.line, sf);
        pushed = e == CS_OK || e == CS_ERR_FULL;
    } else {
        char list[256];
        cs_surffile_keyword_list(list, sizeof list);
        return cs_path_diag_set(lx->diag, CS_ERR_PARSE, at, "unknown surface '%s' (%s)", kw, list);
    }
    if (pushed)
        return e;
    if (e == CS_OK)
        return push_quad(sf, &p, at.line);
    if (lx->diag->code != e)
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
    cs_lex_t lx;
    cs_lex_init(&lx, text, len, "", NULL, 1);
    return cs_lex_next(&lx) && strcmp(lx.tok, NATIVE_MAGIC) == 0;
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
    cs_lex_t lx;
    cs_lex_init(&lx, text, len, sf->file, diag, scale);
    cs_lex_next(&lx); /* the magic */
    int version;
    cs_err_t e = cs_lex_integer(&lx, "format version", 1, 1, &version);
    while (e == CS_OK && cs_lex_next(&lx))
        e = statement(&lx, sf, rev_tol_mm);
    if (e == CS_OK && sf->n == 0)
        e = cs_path_diag_set(diag, CS_ERR_EMPTY, cs_lex_here(&lx), "no surfaces in the file");
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

int cs_surffile_load(const char *who, const char *filename, double scale, double rev_tol_mm,
                     cs_surffile_t *sf)
{
    cs_path_diag_t diag;
    cs_err_t e = cs_surffile_read(filename, scale, rev_tol_mm, sf, &diag);
    if (e == CS_OK)
        return 0;
    if (e == CS_ERR_FULL)
        fprintf(stderr, "%s: out of memory\n", who);
    else
        cs_path_diag_print(stderr, &diag);
    cs_surffile_free(sf);
    return e == CS_ERR_FULL ? 3 : 1;
}
