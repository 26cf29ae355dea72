/* cs_lex: tokens of curvestep's text formats (see cs_lex.h). */
#include "cs_lex.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cs_conv.h"

void cs_lex_init(cs_lex_t *lx, const char *text, size_t len, const char *name, cs_path_diag_t *diag,
                 double scale)
{
    memset(lx, 0, sizeof *lx);
    lx->p = text;
    lx->end = text + len;
    lx->line = lx->col = 1;
    lx->name = name;
    lx->diag = diag;
    lx->scale = scale;
}

cs_path_loc_t cs_lex_here(const cs_lex_t *lx)
{
    cs_path_loc_t l = {lx->name, lx->tline, lx->tcol};
    return l;
}

bool cs_lex_next(cs_lex_t *lx)
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
    lx->tline = lx->line;
    lx->tcol = lx->col;
    if (lx->p >= lx->end) {
        lx->tok[0] = '\0';
        return false;
    }
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

bool cs_lex_peek_is(const cs_lex_t *lx, const char *word)
{
    cs_lex_t copy = *lx;
    return cs_lex_next(&copy) && strcmp(copy.tok, word) == 0;
}

cs_err_t cs_lex_number(cs_lex_t *lx, const char *what, double *out)
{
    if (!cs_lex_next(lx))
        return cs_path_diag_set(lx->diag, CS_ERR_PARSE, cs_lex_here(lx), "end of file: %s expected",
                                what);
    char *e = NULL;
    errno = 0;
    double v = strtod(lx->tok, &e);
    if (e == lx->tok || *e != '\0' || !isfinite(v))
        return cs_path_diag_set(lx->diag, CS_ERR_PARSE, cs_lex_here(lx), "'%s': %s expected",
                                lx->tok, what);
    *out = v;
    return CS_OK;
}

cs_err_t cs_lex_integer(cs_lex_t *lx, const char *what, int lo, int hi, int *out)
{
    double v;
    cs_err_t e = cs_lex_number(lx, what, &v);
    if (e != CS_OK)
        return e;
    if (v != floor(v) || v < lo || v > hi)
        return cs_path_diag_set(lx->diag, CS_ERR_RANGE, cs_lex_here(lx),
                                "%s must be an integer %d..%d", what, lo, hi);
    *out = (int)v;
    return CS_OK;
}

cs_err_t cs_lex_vec(cs_lex_t *lx, const char *what, cs_vec3_t *p, double d[3])
{
    double v[3];
    unsigned line = 0, col = 0;
    for (int k = 0; k < 3; k++) {
        cs_err_t e = cs_lex_number(lx, what, &v[k]);
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

cs_err_t cs_lex_choice(cs_lex_t *lx, const char *what, const char *const *words, int n, int *out)
{
    if (cs_lex_next(lx))
        for (int k = 0; k < n; k++)
            if (strcmp(lx->tok, words[k]) == 0) {
                *out = k;
                return CS_OK;
            }
    return cs_path_diag_set(lx->diag, CS_ERR_PARSE, cs_lex_here(lx), "'%s': %s expected", lx->tok,
                            what);
}
