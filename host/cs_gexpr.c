/* cs_gexpr: LinuxCNC parameters and expressions (see cs_gexpr.h). */
#include "cs_gexpr.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define GX_PI        3.14159265358979323846
#define GX_NUM_CHARS 64
#define GX_INT_TOL   0.0001 /* an index within this of a whole number is that number */
#define GX_WORD_MAX  8      /* longest operator or function name */

/* Binary operators; precedence from LinuxCNC's reference: "** / * / MOD / + - / EQ NE GT GE LT
 * LE / AND OR XOR", highest first, and "the operation on the left is performed first". */
typedef enum {
    GX_NONE,
    GX_POW,
    GX_MUL,
    GX_DIV,
    GX_MOD,
    GX_ADD,
    GX_SUB,
    GX_EQ,
    GX_NE,
    GX_GT,
    GX_GE,
    GX_LT,
    GX_LE,
    GX_AND,
    GX_OR,
    GX_XOR
} gx_op_t;

typedef struct {
    cs_gexpr_store_t *st;
    const char *s;
    size_t n;
    cs_gexpr_fail_t *f;
    unsigned nest;
} gx_t;

static cs_err_t gx_fail(cs_gexpr_fail_t *f, cs_err_t e, size_t at, const char *fmt, ...)
{
    f->at = at;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(f->reason, sizeof f->reason, fmt, ap);
    va_end(ap);
    return e;
}

static bool gx_digit(char c)
{
    return c >= '0' && c <= '9';
}

static bool gx_alpha(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
}

static void gx_blanks(const char *s, size_t n, size_t *i)
{
    while (*i < n && (s[*i] == ' ' || s[*i] == '\t'))
        (*i)++;
}

cs_err_t cs_gexpr_init(cs_gexpr_store_t *st)
{
    memset(st, 0, sizeof *st);
    st->num = calloc(CS_GEXPR_NUM_PARAMS, sizeof *st->num);
    return st->num ? CS_OK : CS_ERR_FULL;
}

cs_err_t cs_gexpr_copy(cs_gexpr_store_t *dst, const cs_gexpr_store_t *src)
{
    *dst = *src;
    dst->num = malloc(CS_GEXPR_NUM_PARAMS * sizeof *dst->num);
    dst->named = src->capnamed ? malloc(src->capnamed * sizeof *dst->named) : NULL;
    if (!dst->num || (src->capnamed && !dst->named)) {
        cs_gexpr_free(dst);
        return CS_ERR_FULL;
    }
    memcpy(dst->num, src->num, CS_GEXPR_NUM_PARAMS * sizeof *dst->num);
    if (src->nnamed)
        memcpy(dst->named, src->named, src->nnamed * sizeof *dst->named);
    return CS_OK;
}

void cs_gexpr_free(cs_gexpr_store_t *st)
{
    free(st->num);
    free(st->named);
    st->num = NULL;
    st->named = NULL;
    st->nnamed = st->capnamed = 0;
}

cs_err_t cs_gexpr_number(const char *s, size_t n, size_t *i, double *out, cs_gexpr_fail_t *f)
{
    char tmp[GX_NUM_CHARS];
    size_t k = 0, j = *i;
    bool digits = false;
    if (j < n && (s[j] == '+' || s[j] == '-'))
        tmp[k++] = s[j++];
    while (j < n && gx_digit(s[j]) && k < GX_NUM_CHARS - 2) {
        tmp[k++] = s[j++];
        digits = true;
    }
    if (j < n && s[j] == '.' && k < GX_NUM_CHARS - 2) {
        tmp[k++] = s[j++];
        while (j < n && gx_digit(s[j]) && k < GX_NUM_CHARS - 1) {
            tmp[k++] = s[j++];
            digits = true;
        }
    }
    if (!digits)
        return gx_fail(f, CS_ERR_PARSE, *i, "expected a number");
    if (j < n && gx_digit(s[j]))
        return gx_fail(f, CS_ERR_PARSE, *i, "number longer than %d characters", GX_NUM_CHARS - 2);
    /* "1e3", "2.5E-2": G-code has no exponent form; reading the E as a word would move
     * somewhere else than the writer meant. */
    if (j + 1 < n && (s[j] == 'e' || s[j] == 'E') &&
        (gx_digit(s[j + 1]) ||
         ((s[j + 1] == '-' || s[j + 1] == '+') && j + 2 < n && gx_digit(s[j + 2]))))
        return gx_fail(f, CS_ERR_PARSE, j,
                       "number in exponent form ('%.*s%c...'): G-code has no exponents "
                       "(LinuxCNC: a number is digits with at most one decimal point); write it "
                       "out in full",
                       (int)(j - *i), s + *i, s[j]);
    tmp[k] = '\0';
    *out = strtod(tmp, NULL);
    *i = j;
    return CS_OK;
}

/* Reads "<name>" at s[*i] == '<' into name (lower case, blanks removed, as LinuxCNC does). */
static cs_err_t gx_name(gx_t *x, size_t *i, char name[CS_GEXPR_NAME_MAX])
{
    size_t j = *i + 1, k = 0;
    while (j < x->n && x->s[j] != '>') {
        char c = x->s[j++];
        if (c == ' ' || c == '\t')
            continue;
        if (k + 1 >= CS_GEXPR_NAME_MAX)
            return gx_fail(x->f, CS_ERR_PARSE, *i, "parameter name longer than %d characters",
                           CS_GEXPR_NAME_MAX - 1);
        name[k++] = (c >= 'A' && c <= 'Z') ? (char)(c - 'A' + 'a') : c;
    }
    if (j >= x->n)
        return gx_fail(x->f, CS_ERR_PARSE, *i, "parameter name not closed by '>'");
    if (k == 0)
        return gx_fail(x->f, CS_ERR_PARSE, *i, "empty parameter name '#<>'");
    name[k] = '\0';
    *i = j + 1;
    return CS_OK;
}

static cs_gexpr_named_t *gx_find(const cs_gexpr_store_t *st, const char *name)
{
    unsigned level = name[0] == '_' ? 0 : st->level;
    for (size_t k = 0; k < st->nnamed; k++)
        if (st->named[k].level == level && strcmp(st->named[k].name, name) == 0)
            return &st->named[k];
    return NULL;
}

bool cs_gexpr_get_named(const cs_gexpr_store_t *st, const char *name, double *v)
{
    const cs_gexpr_named_t *p = gx_find(st, name);
    if (p)
        *v = p->v;
    return p != NULL;
}

cs_err_t cs_gexpr_set_named(cs_gexpr_store_t *st, const char *name, double v)
{
    cs_gexpr_named_t *p = gx_find(st, name);
    if (!p) {
        if (st->nnamed == st->capnamed) {
            size_t nc = st->capnamed ? 2 * st->capnamed : 16;
            cs_gexpr_named_t *q = realloc(st->named, nc * sizeof *q);
            if (!q)
                return CS_ERR_FULL;
            st->named = q;
            st->capnamed = nc;
        }
        p = &st->named[st->nnamed++];
        snprintf(p->name, sizeof p->name, "%s", name);
        p->level = name[0] == '_' ? 0 : st->level;
    }
    p->v = v;
    return CS_OK;
}

static cs_err_t gx_real(gx_t *x, size_t *i, double *out);

/* The index of "#index": a real value that is a whole number from 1 to 5399. */
static cs_err_t gx_index(gx_t *x, size_t *i, int *idx)
{
    size_t at = *i;
    double v;
    cs_err_t e = gx_real(x, i, &v);
    if (e != CS_OK)
        return e;
    double r = nearbyint(v);
    if (fabs(v - r) > GX_INT_TOL || r < 1 || r >= CS_GEXPR_NUM_PARAMS)
        return gx_fail(x->f, CS_ERR_PARSE, at,
                       "parameter number %g: LinuxCNC has numbered parameters #1 to #%d", v,
                       CS_GEXPR_NUM_PARAMS - 1);
    *idx = (int)r;
    return CS_OK;
}

/* "#..." at s[*i] == '#': its value. */
static cs_err_t gx_param(gx_t *x, size_t *i, double *out)
{
    size_t at = *i;
    (*i)++;
    gx_blanks(x->s, x->n, i);
    if (*i < x->n && x->s[*i] == '<') {
        char name[CS_GEXPR_NAME_MAX];
        cs_err_t e = gx_name(x, i, name);
        if (e != CS_OK)
            return e;
        if (!cs_gexpr_get_named(x->st, name, out))
            return gx_fail(x->f, CS_ERR_PARSE, at, "named parameter #<%s> is not defined", name);
        return CS_OK;
    }
    int idx;
    cs_err_t e = gx_index(x, i, &idx);
    if (e == CS_OK)
        *out = x->st->num[idx];
    return e;
}

/* Letters at s[*i] (at most GX_WORD_MAX), upper-cased, without moving *i. */
static size_t gx_word(const gx_t *x, size_t i, char w[GX_WORD_MAX + 1])
{
    size_t k = 0;
    while (i + k < x->n && gx_alpha(x->s[i + k]) && k < GX_WORD_MAX) {
        char c = x->s[i + k];
        w[k++] = (c >= 'a' && c <= 'z') ? (char)(c - 'a' + 'A') : c;
    }
    w[k] = '\0';
    return k;
}

static cs_err_t gx_bracket(gx_t *x, size_t *i, double *out);

/* EXISTS[#<name>] at s[*i] == '[': 1 if the named parameter is defined here. */
static cs_err_t gx_exists(gx_t *x, size_t *i, double *out)
{
    size_t j = *i + 1;
    gx_blanks(x->s, x->n, &j);
    char name[CS_GEXPR_NAME_MAX];
    double v;
    if (j + 1 >= x->n || x->s[j] != '#' || x->s[j + 1] != '<')
        return gx_fail(x->f, CS_ERR_PARSE, j, "EXISTS takes a named parameter: EXISTS[#<name>]");
    j++;
    cs_err_t e = gx_name(x, &j, name);
    if (e != CS_OK)
        return e;
    gx_blanks(x->s, x->n, &j);
    if (j >= x->n || x->s[j] != ']')
        return gx_fail(x->f, CS_ERR_PARSE, j, "expected ']' after EXISTS[#<%s>", name);
    *i = j + 1;
    *out = cs_gexpr_get_named(x->st, name, &v) ? 1.0 : 0.0;
    return CS_OK;
}

/* The functions, in the order of gx_func's names. */
enum { GXF_ABS, GXF_ACOS, GXF_ASIN, GXF_ATAN, GXF_COS, GXF_EXP, GXF_FIX, GXF_FUP, GXF_LN,
       GXF_ROUND, GXF_SIN, GXF_SQRT, GXF_TAN, GXF_EXISTS };

/* Function fn (named w, at column at) of a into *r; ATAN reads its "/[x]" at s[*i]. */
static cs_err_t gx_call_fn(gx_t *x, int fn, const char *w, size_t at, size_t *i, double a,
                           double *r)
{
    const double deg = GX_PI / 180.0; /* LinuxCNC: angles in degrees, in and out */
    cs_err_t e;
    switch (fn) {
    case GXF_ABS:
        *r = fabs(a);
        return CS_OK;
    case GXF_ACOS:
    case GXF_ASIN:
        if (a < -1.0 || a > 1.0)
            return gx_fail(x->f, CS_ERR_RANGE, at, "%s[%g]: the argument must be from -1 to 1", w,
                           a);
        *r = (fn == GXF_ACOS ? acos(a) : asin(a)) / deg;
        return CS_OK;
    case GXF_ATAN: { /* ATAN[y]/[x] */
        gx_blanks(x->s, x->n, i);
        if (*i >= x->n || x->s[*i] != '/')
            return gx_fail(x->f, CS_ERR_PARSE, *i, "ATAN takes two arguments: ATAN[y]/[x]");
        (*i)++;
        gx_blanks(x->s, x->n, i);
        double b;
        if (*i >= x->n || x->s[*i] != '[')
            return gx_fail(x->f, CS_ERR_PARSE, *i, "ATAN takes two arguments: ATAN[y]/[x]");
        if ((e = gx_bracket(x, i, &b)) != CS_OK)
            return e;
        *r = atan2(a, b) / deg;
        return CS_OK;
    }
    case GXF_COS:
        *r = cos(a * deg);
        return CS_OK;
    case GXF_EXP:
        *r = exp(a);
        return CS_OK;
    case GXF_FIX:
        *r = floor(a);
        return CS_OK;
    case GXF_FUP:
        *r = ceil(a);
        return CS_OK;
    case GXF_LN:
        if (!(a > 0))
            return gx_fail(x->f, CS_ERR_RANGE, at, "LN[%g]: the argument must be positive", a);
        *r = log(a);
        return CS_OK;
    case GXF_ROUND:
        *r = a < 0 ? -floor(-a + 0.5) : floor(a + 0.5); /* halves away from zero */
        return CS_OK;
    case GXF_SIN:
        *r = sin(a * deg);
        return CS_OK;
    case GXF_SQRT:
        if (a < 0)
            return gx_fail(x->f, CS_ERR_RANGE, at, "SQRT[%g]: the argument must not be negative",
                           a);
        *r = sqrt(a);
        return CS_OK;
    default:
        *r = tan(a * deg);
        return CS_OK;
    }
}

/* A unary function at s[*i] (letters). */
static cs_err_t gx_func(gx_t *x, size_t *i, double *out)
{
    static const char *const names[] = {"ABS", "ACOS", "ASIN",  "ATAN", "COS",  "EXP", "FIX",
                                        "FUP", "LN",   "ROUND", "SIN",  "SQRT", "TAN", "EXISTS"};
    char w[GX_WORD_MAX + 1];
    size_t at = *i, len = gx_word(x, *i, w);
    int fn = -1;
    for (int k = 0; k < (int)(sizeof names / sizeof names[0]); k++)
        if (strcmp(w, names[k]) == 0)
            fn = k;
    if (fn < 0)
        return gx_fail(x->f, CS_ERR_PARSE, at, "expected a number");
    *i += len;
    gx_blanks(x->s, x->n, i);
    if (*i >= x->n || x->s[*i] != '[')
        return gx_fail(x->f, CS_ERR_PARSE, *i, "%s must be followed by [argument]", w);
    if (fn == GXF_EXISTS)
        return gx_exists(x, i, out);
    double a, r = 0;
    cs_err_t e = gx_bracket(x, i, &a);
    if (e == CS_OK)
        e = gx_call_fn(x, fn, w, at, i, a, &r);
    if (e != CS_OK)
        return e;
    if (!isfinite(r))
        return gx_fail(x->f, CS_ERR_RANGE, at, "%s[%g] is not a finite number", w, a);
    *out = r;
    return CS_OK;
}

/* The operator at s[*i] (after blanks), without consuming it; *len its length. */
static gx_op_t gx_peek_op(const gx_t *x, size_t i, size_t *len)
{
    static const struct {
        const char *w;
        gx_op_t op;
    } words[] = {{"MOD", GX_MOD}, {"EQ", GX_EQ}, {"NE", GX_NE},   {"GT", GX_GT}, {"GE", GX_GE},
                 {"LT", GX_LT},   {"LE", GX_LE}, {"AND", GX_AND}, {"OR", GX_OR}, {"XOR", GX_XOR}};
    if (i >= x->n)
        return GX_NONE;
    char c = x->s[i];
    *len = 1;
    if (c == '*' && i + 1 < x->n && x->s[i + 1] == '*') {
        *len = 2;
        return GX_POW;
    }
    if (c == '*')
        return GX_MUL;
    if (c == '/')
        return GX_DIV;
    if (c == '+')
        return GX_ADD;
    if (c == '-')
        return GX_SUB;
    char w[GX_WORD_MAX + 1];
    size_t k = gx_word(x, i, w);
    for (size_t j = 0; j < sizeof words / sizeof words[0]; j++)
        if (strcmp(w, words[j].w) == 0) {
            *len = k;
            return words[j].op;
        }
    return GX_NONE;
}

static int gx_prec(gx_op_t op)
{
    switch (op) {
    case GX_POW:
        return 5;
    case GX_MUL:
    case GX_DIV:
    case GX_MOD:
        return 4;
    case GX_ADD:
    case GX_SUB:
        return 3;
    case GX_EQ:
    case GX_NE:
    case GX_GT:
    case GX_GE:
    case GX_LT:
    case GX_LE:
        return 2;
    case GX_AND:
    case GX_OR:
    case GX_XOR:
        return 1;
    default:
        return 0;
    }
}

static cs_err_t gx_apply(gx_t *x, gx_op_t op, size_t at, double a, double b, double *out)
{
    double r;
    switch (op) {
    case GX_POW:
        if (a < 0 && b != floor(b))
            return gx_fail(x->f, CS_ERR_RANGE, at,
                           "%g ** %g: a negative number to a fractional power", a, b);
        r = pow(a, b);
        break;
    case GX_MUL:
        r = a * b;
        break;
    case GX_DIV:
    case GX_MOD:
        if (b == 0.0)
            return gx_fail(x->f, CS_ERR_RANGE, at, "division by zero");
        /* MOD as LinuxCNC computes it: fmod, then made non-negative. */
        r = op == GX_DIV ? a / b : fmod(a, b);
        if (op == GX_MOD && r < 0)
            r += fabs(b);
        break;
    case GX_ADD:
        r = a + b;
        break;
    case GX_SUB:
        r = a - b;
        break;
    case GX_EQ:
        r = fabs(a - b) < CS_GEXPR_EQ_TOL;
        break;
    case GX_NE:
        r = !(fabs(a - b) < CS_GEXPR_EQ_TOL);
        break;
    case GX_GT:
        r = a > b;
        break;
    case GX_GE:
        r = a >= b;
        break;
    case GX_LT:
        r = a < b;
        break;
    case GX_LE:
        r = a <= b;
        break;
    case GX_AND:
        r = a != 0.0 && b != 0.0;
        break;
    case GX_OR:
        r = a != 0.0 || b != 0.0;
        break;
    default:
        r = (a != 0.0) != (b != 0.0);
        break;
    }
    if (!isfinite(r))
        return gx_fail(x->f, CS_ERR_RANGE, at, "the expression's value is not a finite number");
    *out = r;
    return CS_OK;
}

/* Precedence climbing over the operators of one bracket. */
static cs_err_t gx_binary(gx_t *x, size_t *i, int minprec, double *out)
{
    double a;
    cs_err_t e = gx_real(x, i, &a);
    while (e == CS_OK) {
        gx_blanks(x->s, x->n, i);
        size_t len = 0, at = *i;
        gx_op_t op = gx_peek_op(x, *i, &len);
        int p = gx_prec(op);
        if (op == GX_NONE || p < minprec)
            break;
        *i += len;
        double b;
        if ((e = gx_binary(x, i, p + 1, &b)) == CS_OK)
            e = gx_apply(x, op, at, a, b, &a);
    }
    if (e == CS_OK)
        *out = a;
    return e;
}

/* "[expression]" at s[*i] == '['. */
static cs_err_t gx_bracket(gx_t *x, size_t *i, double *out)
{
    size_t at = *i; /* the depth is counted by gx_real, which every operand goes through */
    (*i)++;
    cs_err_t e = gx_binary(x, i, 1, out);
    if (e == CS_OK) {
        gx_blanks(x->s, x->n, i);
        if (*i >= x->n || x->s[*i] != ']') {
            size_t len;
            e = gx_peek_op(x, *i, &len) == GX_NONE && *i < x->n
                    ? gx_fail(x->f, CS_ERR_PARSE, *i,
                              "unexpected '%c' in an expression (expected "
                              "an operator or ']')",
                              x->s[*i])
                    : gx_fail(x->f, CS_ERR_PARSE, at, "'[' not closed by ']' on its line");
        } else {
            (*i)++;
        }
    }
    return e;
}

static cs_err_t gx_real(gx_t *x, size_t *i, double *out)
{
    gx_blanks(x->s, x->n, i);
    if (*i >= x->n)
        return gx_fail(x->f, CS_ERR_PARSE, *i, "expected a number");
    char c = x->s[*i];
    if (++x->nest > CS_GEXPR_MAX_NEST)
        return gx_fail(x->f, CS_ERR_PARSE, *i, "expression nested more than %d deep",
                       CS_GEXPR_MAX_NEST);
    cs_err_t e;
    if (c == '[') {
        e = gx_bracket(x, i, out);
    } else if (c == '#') {
        e = gx_param(x, i, out);
    } else if (gx_alpha(c)) {
        e = gx_func(x, i, out);
    } else if ((c == '-' || c == '+') && *i + 1 < x->n && !gx_digit(x->s[*i + 1]) &&
               x->s[*i + 1] != '.') {
        /* A sign before a non-number real value ("-#1", "-[...]", "-SIN[...]"). */
        (*i)++;
        e = gx_real(x, i, out);
        if (e == CS_OK && c == '-')
            *out = -*out;
    } else {
        e = cs_gexpr_number(x->s, x->n, i, out, x->f);
    }
    x->nest--;
    return e;
}

cs_err_t cs_gexpr_real(cs_gexpr_store_t *st, const char *s, size_t n, size_t *i, double *out,
                       cs_gexpr_fail_t *f)
{
    gx_t x = {st, s, n, f, 0};
    return gx_real(&x, i, out);
}

cs_err_t cs_gexpr_assign(cs_gexpr_store_t *st, const char *s, size_t n, size_t *i,
                         cs_gexpr_fail_t *f)
{
    gx_t x = {st, s, n, f, 0};
    size_t at = *i;
    cs_gexpr_pending_t p;
    memset(&p, 0, sizeof p);
    (*i)++;
    gx_blanks(s, n, i);
    cs_err_t e = (*i < n && s[*i] == '<') ? gx_name(&x, i, p.name) : gx_index(&x, i, &p.index);
    if (e != CS_OK)
        return e;
    gx_blanks(s, n, i);
    if (*i >= n || s[*i] != '=')
        return gx_fail(f, CS_ERR_PARSE, at,
                       "a parameter outside a word must be set: '#... = value'");
    (*i)++;
    if ((e = gx_real(&x, i, &p.v)) != CS_OK)
        return e;
    if (st->npending >= CS_GEXPR_MAX_PENDING)
        return gx_fail(f, CS_ERR_FULL, at, "more than %d parameter settings on one line",
                       CS_GEXPR_MAX_PENDING);
    st->pending[st->npending++] = p;
    return CS_OK;
}

cs_err_t cs_gexpr_commit(cs_gexpr_store_t *st)
{
    cs_err_t e = CS_OK;
    for (size_t k = 0; k < st->npending && e == CS_OK; k++) {
        const cs_gexpr_pending_t *p = &st->pending[k];
        if (p->index > 0)
            st->num[p->index] = p->v;
        else
            e = cs_gexpr_set_named(st, p->name, p->v);
    }
    st->npending = 0;
    return e;
}

void cs_gexpr_discard(cs_gexpr_store_t *st)
{
    st->npending = 0;
}

cs_err_t cs_gexpr_call(cs_gexpr_store_t *st, const double *args, size_t nargs)
{
    if (st->level >= CS_GEXPR_MAX_CALLS || nargs > CS_GEXPR_LOCALS)
        return CS_ERR_FULL;
    memcpy(st->saved[st->level], &st->num[1], sizeof st->saved[0]);
    for (size_t k = 0; k < nargs; k++)
        st->num[1 + k] = args[k];
    st->level++;
    return CS_OK;
}

void cs_gexpr_return(cs_gexpr_store_t *st)
{
    if (st->level == 0)
        return;
    size_t w = 0;
    for (size_t k = 0; k < st->nnamed; k++)
        if (st->named[k].level != st->level)
            st->named[w++] = st->named[k];
    st->nnamed = w;
    st->level--;
    memcpy(&st->num[1], st->saved[st->level], sizeof st->saved[0]);
}
