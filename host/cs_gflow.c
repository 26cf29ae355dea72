/* cs_gflow: O-word control flow (see cs_gflow.h). */
#include "cs_gflow.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    size_t line; /* where the construct opened */
    size_t last; /* if: its latest branch line */
} gf_open_t;

static const char *const gf_words[] = {
    [CS_GFLOW_SUB] = "sub",
    [CS_GFLOW_ENDSUB] = "endsub",
    [CS_GFLOW_CALL] = "call",
    [CS_GFLOW_RETURN] = "return",
    [CS_GFLOW_IF] = "if",
    [CS_GFLOW_ELSEIF] = "elseif",
    [CS_GFLOW_ELSE] = "else",
    [CS_GFLOW_ENDIF] = "endif",
    [CS_GFLOW_WHILE] = "while",
    [CS_GFLOW_ENDWHILE] = "endwhile",
    [CS_GFLOW_DO] = "do",
    [CS_GFLOW_REPEAT] = "repeat",
    [CS_GFLOW_ENDREPEAT] = "endrepeat",
    [CS_GFLOW_BREAK] = "break",
    [CS_GFLOW_CONTINUE] = "continue",
};

unsigned cs_gflow_col(const char *s, size_t i)
{
    unsigned c = 1;
    for (size_t k = 0; k < i; k++)
        if (((unsigned char)s[k] & 0xC0) != 0x80)
            c++;
    return c;
}

/* "o<label> <keyword><tail>" at line k + 1, column col. */
static cs_err_t gf_err(cs_path_diag_t *d, cs_err_t e, const char *name, size_t k, unsigned col,
                       const cs_gflow_line_t *l, const char *tail)
{
    cs_path_loc_t loc = {name, (unsigned)(k + 1), col};
    return cs_path_diag_set(d, e, loc, "o%s %s%s", l->label,
                            l->kind == CS_GFLOW_DOWHILE ? "while" : gf_words[l->kind], tail);
}

static void gf_blanks(const char *s, size_t n, size_t *i)
{
    while (*i < n && (s[*i] == ' ' || s[*i] == '\t' || s[*i] == '('))
        if (s[(*i)++] == '(')
            while (*i < n && s[(*i)++] != ')')
                ;
}

/* Reads line l's O-word (if it has one) into l. */
static cs_err_t gf_parse(cs_gflow_line_t *l, const char *s, const char *name, size_t k,
                         cs_path_diag_t *d)
{
    size_t n = l->len, i = 0;
    gf_blanks(s, n, &i);
    if (i < n && (s[i] == 'n' || s[i] == 'N')) {
        i++;
        while (i < n && s[i] >= '0' && s[i] <= '9')
            i++;
        gf_blanks(s, n, &i);
    }
    if (i >= n || (s[i] != 'o' && s[i] != 'O'))
        return CS_OK;
    l->ocol = cs_gflow_col(s, i);
    cs_path_loc_t loc = {name, (unsigned)(k + 1), l->ocol};
    size_t j = ++i, w = 0;
    while (j < n && (s[j] == ' ' || s[j] == '\t'))
        j++;
    if (j < n && s[j] == '<') {
        l->label[w++] = '<';
        for (j++; j < n && s[j] != '>'; j++)
            if (s[j] != ' ' && s[j] != '\t' && w + 2 < CS_GFLOW_LABEL_MAX)
                l->label[w++] = (char)((s[j] >= 'A' && s[j] <= 'Z') ? s[j] - 'A' + 'a' : s[j]);
        if (j >= n)
            return cs_path_diag_set(d, CS_ERR_PARSE, loc, "O-word name not closed by '>'");
        l->label[w++] = '>';
        j++;
    } else if (j < n && s[j] >= '0' && s[j] <= '9') {
        while (j < n && s[j] == '0' && j + 1 < n && s[j + 1] >= '0' && s[j + 1] <= '9')
            j++; /* o0100 is o100 */
        while (j < n && s[j] >= '0' && s[j] <= '9' && w + 1 < CS_GFLOW_LABEL_MAX)
            l->label[w++] = s[j++];
    } else if (j < n && s[j] == '[') {
        l->label[w++] = '['; /* o[expression] call: the label is computed when called */
        size_t depth = 0;
        for (; j < n; j++) {
            depth += s[j] == '[';
            depth -= s[j] == ']';
            if (depth == 0)
                break;
        }
        if (j >= n)
            return cs_path_diag_set(d, CS_ERR_PARSE, loc, "'[' not closed by ']' on its line");
        j++;
    } else {
        return cs_path_diag_set(d, CS_ERR_PARSE, loc,
                                "O must be followed by a number or <name> (an O-word label)");
    }
    l->label[w] = '\0';
    gf_blanks(s, n, &j);
    char kw[12];
    size_t m = 0, at = j;
    while (j < n && ((s[j] >= 'a' && s[j] <= 'z') || (s[j] >= 'A' && s[j] <= 'Z')) &&
           m + 1 < sizeof kw)
        kw[m++] = (char)(s[j++] | 0x20);
    kw[m] = '\0';
    for (int q = CS_GFLOW_SUB; q <= CS_GFLOW_CONTINUE; q++)
        if (gf_words[q] && strcmp(kw, gf_words[q]) == 0)
            l->kind = (cs_gflow_kind_t)q;
    loc.col = m == 0 ? l->ocol : cs_gflow_col(s, at);
    if (l->kind == CS_GFLOW_NONE && m == 0)
        return cs_path_diag_set(d, CS_ERR_PARSE, loc,
                                "o%s without a keyword: a program number (\"O1001 (NAME)\", as "
                                "Fanuc-style posts begin) is no LinuxCNC O-word; delete the line",
                                l->label);
    if (l->kind == CS_GFLOW_NONE)
        return cs_path_diag_set(d, CS_ERR_PARSE, loc,
                                "o%s: expected sub, endsub, call, return, if, elseif, else, "
                                "endif, while, endwhile, do, repeat, endrepeat, break or continue",
                                l->label);
    if (l->label[0] == '[' && l->kind != CS_GFLOW_CALL)
        return cs_path_diag_set(d, CS_ERR_PARSE, loc, "a computed O label o[...] only calls");
    l->args = j;
    return CS_OK;
}

cs_err_t cs_gflow_line_parse(const char *s, size_t n, cs_gflow_line_t *l)
{
    cs_path_diag_t d;
    memset(l, 0, sizeof *l);
    l->len = n;
    return gf_parse(l, s, "", 0, &d);
}

/* The innermost open construct with line's label, of one of kinds, not past a sub. */
static gf_open_t *gf_find(cs_gflow_t *f, gf_open_t *st, size_t nst, const char *label,
                          const cs_gflow_kind_t *kinds, size_t nk)
{
    for (size_t q = nst; q-- > 0;) {
        const cs_gflow_line_t *o = &f->lines[st[q].line];
        for (size_t z = 0; z < nk; z++)
            if (o->kind == kinds[z] && (label == NULL || strcmp(o->label, label) == 0))
                return &st[q];
        if (o->kind == CS_GFLOW_SUB)
            return NULL;
    }
    return NULL;
}

/* Pairs line k with the construct it closes or continues. */
static cs_err_t gf_pair(cs_gflow_t *f, gf_open_t *st, size_t *nst, size_t k, const char *name,
                        cs_path_diag_t *d)
{
    cs_gflow_line_t *l = &f->lines[k];
    const cs_gflow_line_t *top = *nst ? &f->lines[st[*nst - 1].line] : NULL;
    bool same = top && strcmp(top->label, l->label) == 0;
    static const cs_gflow_kind_t loops[] = {CS_GFLOW_WHILE, CS_GFLOW_DO, CS_GFLOW_REPEAT};
    static const cs_gflow_kind_t subs[] = {CS_GFLOW_SUB};
    cs_gflow_kind_t opener = l->kind == CS_GFLOW_ENDSUB      ? CS_GFLOW_SUB
                             : l->kind == CS_GFLOW_ENDWHILE  ? CS_GFLOW_WHILE
                             : l->kind == CS_GFLOW_ENDREPEAT ? CS_GFLOW_REPEAT
                                                             : CS_GFLOW_IF;
    if (l->kind == CS_GFLOW_WHILE && same && top->kind == CS_GFLOW_DO) {
        /* LinuxCNC: a while whose label is an open do ends that do loop. */
        l->kind = CS_GFLOW_DOWHILE;
        l->next = st[*nst - 1].line;
        f->lines[l->next].next = k;
        (*nst)--;
        return CS_OK;
    }
    switch (l->kind) {
    case CS_GFLOW_WHILE:
    case CS_GFLOW_SUB:
    case CS_GFLOW_IF:
    case CS_GFLOW_DO:
    case CS_GFLOW_REPEAT:
        if (l->kind == CS_GFLOW_SUB)
            for (size_t q = 0; q < k; q++)
                if (f->lines[q].kind == CS_GFLOW_SUB && strcmp(f->lines[q].label, l->label) == 0)
                    return gf_err(d, CS_ERR_PARSE, name, k, l->ocol, l,
                                  ": a subroutine of that name is already defined");
        if (*nst >= CS_GFLOW_MAX_OPEN)
            return gf_err(d, CS_ERR_FULL, name, k, l->ocol, l, ": nested too deep");
        st[*nst].line = st[*nst].last = k;
        (*nst)++;
        return CS_OK;
    case CS_GFLOW_ELSEIF:
    case CS_GFLOW_ELSE:
        if (!same || top->kind != CS_GFLOW_IF || f->lines[st[*nst - 1].last].kind == CS_GFLOW_ELSE)
            return gf_err(d, CS_ERR_PARSE, name, k, l->ocol, l, " without a matching if");
        f->lines[st[*nst - 1].last].next = k;
        st[*nst - 1].last = k;
        return CS_OK;
    case CS_GFLOW_ENDSUB:
    case CS_GFLOW_ENDWHILE:
    case CS_GFLOW_ENDREPEAT:
    case CS_GFLOW_ENDIF:
        if (!same || top->kind != opener)
            return gf_err(d, CS_ERR_PARSE, name, k, l->ocol, l,
                          opener == CS_GFLOW_IF    ? " without a matching if"
                          : opener == CS_GFLOW_SUB ? " without a matching sub"
                                                   : " without the loop it ends");
        if (opener == CS_GFLOW_IF) {
            f->lines[st[*nst - 1].last].next = k;
            for (size_t b = st[*nst - 1].line; b != k; b = f->lines[b].next)
                f->lines[b].end = k;
        } else {
            f->lines[st[*nst - 1].line].next = k;
        }
        l->next = st[*nst - 1].line;
        (*nst)--;
        return CS_OK;
    case CS_GFLOW_BREAK:
    case CS_GFLOW_CONTINUE:
    case CS_GFLOW_RETURN: {
        bool ret = l->kind == CS_GFLOW_RETURN;
        gf_open_t *o =
            ret ? gf_find(f, st, *nst, NULL, subs, 1) : gf_find(f, st, *nst, l->label, loops, 3);
        if (!o)
            return gf_err(d, CS_ERR_PARSE, name, k, l->ocol, l,
                          ret ? " outside a subroutine" : " outside a loop of that label");
        l->next = o->line;
        return CS_OK;
    }
    default:
        return CS_OK;
    }
}

/* The sub table, and each call with a written label linked to its sub (once, not per call). */
static cs_err_t gf_link_calls(cs_gflow_t *f, const char *name, cs_path_diag_t *diag)
{
    for (size_t k = 0; k < f->n; k++)
        f->nsubs += f->lines[k].kind == CS_GFLOW_SUB;
    f->subs = malloc((f->nsubs ? f->nsubs : 1) * sizeof *f->subs);
    if (!f->subs) {
        cs_path_loc_t l0 = {name, 0, 0};
        return cs_path_diag_set(diag, CS_ERR_FULL, l0, "out of memory");
    }
    size_t m = 0;
    for (size_t k = 0; k < f->n; k++)
        if (f->lines[k].kind == CS_GFLOW_SUB)
            f->subs[m++] = k;
    for (size_t k = 0; k < f->n; k++)
        if (f->lines[k].kind == CS_GFLOW_CALL && f->lines[k].label[0] != '[')
            f->lines[k].next = cs_gflow_find_sub(f, f->lines[k].label);
    return CS_OK;
}

size_t cs_gflow_find_sub(const cs_gflow_t *f, const char *label)
{
    for (size_t q = 0; q < f->nsubs; q++)
        if (strcmp(f->lines[f->subs[q]].label, label) == 0)
            return f->subs[q];
    return f->n;
}

cs_err_t cs_gflow_init(cs_gflow_t *f, const char *name, const char *buf, size_t len, bool o_words,
                       unsigned long max_iterations, cs_path_diag_t *diag)
{
    memset(f, 0, sizeof *f);
    f->max_iterations = max_iterations ? max_iterations : CS_GFLOW_MAX_LOOPS;
    size_t cap = 0;
    cs_path_loc_t l0 = {name, 0, 0};
    for (size_t i = 0; i < len;) {
        size_t j = i;
        while (j < len && buf[j] != '\n' && buf[j] != '\r')
            j++;
        if (f->n == cap) {
            cap = cap ? 2 * cap : 256;
            cs_gflow_line_t *p = realloc(f->lines, cap * sizeof *p);
            if (!p)
                return cs_path_diag_set(diag, CS_ERR_FULL, l0, "out of memory");
            f->lines = p;
        }
        cs_gflow_line_t *l = &f->lines[f->n++];
        memset(l, 0, sizeof *l);
        l->start = i;
        l->len = j - i;
        if (j < len && buf[j] == '\r' && j + 1 < len && buf[j + 1] == '\n')
            j++;
        i = j + 1;
    }
    if (!o_words)
        return CS_OK;
    gf_open_t *st = malloc(CS_GFLOW_MAX_OPEN * sizeof *st);
    if (!st)
        return cs_path_diag_set(diag, CS_ERR_FULL, l0, "out of memory");
    size_t nst = 0;
    cs_err_t e = CS_OK;
    for (size_t k = 0; k < f->n && e == CS_OK; k++) {
        e = gf_parse(&f->lines[k], buf + f->lines[k].start, name, k, diag);
        if (e == CS_OK && f->lines[k].kind != CS_GFLOW_NONE)
            e = gf_pair(f, st, &nst, k, name, diag);
    }
    if (e == CS_OK)
        e = gf_link_calls(f, name, diag);
    if (e == CS_OK && nst > 0) {
        const cs_gflow_line_t *o = &f->lines[st[nst - 1].line];
        e = gf_err(diag, CS_ERR_PARSE, name, st[nst - 1].line, o->ocol, o,
                   " is not closed before the end of the program");
    }
    free(st);
    return e;
}

void cs_gflow_free(cs_gflow_t *f)
{
    free(f->subs);
    f->subs = NULL;
    f->nsubs = 0;
    free(f->lines);
    f->lines = NULL;
    f->n = 0;
}

/* ---- running ------------------------------------------------------------------------------ */

typedef struct {
    cs_gflow_t *f;
    const char *name;
    const char *buf;
    const char *s; /* the line */
    size_t n, k;
    cs_gexpr_store_t *st;
    cs_path_diag_t *diag;
} gf_run_t;

static cs_err_t gf_expr_err(gf_run_t *r, cs_err_t e, const cs_gexpr_fail_t *fl)
{
    cs_path_loc_t loc = {r->name, (unsigned)(r->k + 1), cs_gflow_col(r->s, fl->at)};
    return cs_path_diag_set(r->diag, e, loc, "%s", fl->reason);
}

/* Up to max values after the keyword (*got of them); required: at least one. Then only
 * comments may follow. */
static cs_err_t gf_args(gf_run_t *r, size_t i, double *v, size_t max, size_t *got, bool required)
{
    cs_gexpr_fail_t fl;
    size_t m = 0;
    for (;;) {
        gf_blanks(r->s, r->n, &i);
        if (i >= r->n || r->s[i] == ';')
            break;
        if (m == max) {
            fl.at = i;
            snprintf(fl.reason, sizeof fl.reason, "o%s %s: unexpected '%c' (at most %zu value%s)",
                     r->f->lines[r->k].label, gf_words[r->f->lines[r->k].kind], r->s[i], max,
                     max == 1 ? "" : "s");
            return gf_expr_err(r, CS_ERR_PARSE, &fl);
        }
        cs_err_t e = cs_gexpr_real(r->st, r->s, r->n, &i, &v[m], &fl);
        if (e != CS_OK)
            return gf_expr_err(r, e, &fl);
        m++;
    }
    if (required && m == 0) {
        const cs_gflow_line_t *l = &r->f->lines[r->k];
        return gf_err(r->diag, CS_ERR_PARSE, r->name, r->k, l->ocol, l,
                      " needs a condition or count: [expression]");
    }
    *got = m;
    return CS_OK;
}

/* A backward jump: one more loop pass, within the bound. */
static cs_err_t gf_iterate(gf_run_t *r)
{
    const cs_gflow_line_t *l = &r->f->lines[r->k];
    if (++r->f->iterations > r->f->max_iterations) {
        char tail[96];
        snprintf(tail, sizeof tail, ": more than %lu loop passes in the program (a runaway loop?)",
                 r->f->max_iterations);
        return gf_err(r->diag, CS_ERR_RANGE, r->name, r->k, l->ocol, l, tail);
    }
    return CS_OK;
}

/* o... call [args]: to the sub's first line, with its own #1..#30. */
static cs_err_t gf_call(gf_run_t *r, size_t *next)
{
    cs_gflow_t *f = r->f;
    const cs_gflow_line_t *l = &f->lines[r->k];
    char label[CS_GFLOW_LABEL_MAX];
    size_t i = l->args;
    snprintf(label, sizeof label, "%s", l->label);
    if (label[0] == '[') { /* o[expression] call */
        double v;
        cs_gexpr_fail_t fl;
        size_t j = 0;
        while (r->s[j] != '[')
            j++;
        cs_err_t e = cs_gexpr_real(r->st, r->s, r->n, &j, &v, &fl);
        if (e != CS_OK)
            return gf_expr_err(r, e, &fl);
        snprintf(label, sizeof label, "%.0f", nearbyint(v));
    }
    double args[CS_GEXPR_LOCALS];
    size_t nargs;
    cs_err_t e = gf_args(r, i, args, CS_GEXPR_LOCALS, &nargs, false);
    if (e != CS_OK)
        return e;
    size_t sub = l->label[0] == '[' ? cs_gflow_find_sub(f, label) : l->next;
    cs_path_loc_t loc = {r->name, (unsigned)(r->k + 1), l->ocol};
    if (sub == f->n)
        return cs_path_diag_set(r->diag, CS_ERR_PARSE, loc,
                                "o%s call: no subroutine o%s in this file (subroutine files are "
                                "not read)",
                                label, label);
    /* LinuxCNC: "If the subroutine is defined in the same file as the main program that calls
     * the subroutine, it must be defined before the call statement." */
    if (!f->lines[sub].defined)
        return cs_path_diag_set(r->diag, CS_ERR_PARSE, loc,
                                "o%s call: the subroutine is defined after the call (line %zu); "
                                "LinuxCNC needs it defined first",
                                label, sub + 1);
    if (f->ncalls >= CS_GEXPR_MAX_CALLS || cs_gexpr_call(r->st, args, nargs) != CS_OK)
        return cs_path_diag_set(r->diag, CS_ERR_RANGE, loc,
                                "o%s call: subroutines nested more than %d deep", label,
                                CS_GEXPR_MAX_CALLS);
    f->calls[f->ncalls].ret = r->k + 1;
    f->calls[f->ncalls].loops = f->nreps;
    f->ncalls++;
    *next = sub + 1;
    return CS_OK;
}

/* endsub / return [value]: back to the caller. */
static cs_err_t gf_return(gf_run_t *r, size_t *next)
{
    cs_gflow_t *f = r->f;
    const cs_gflow_line_t *l = &f->lines[r->k];
    double v;
    size_t got;
    cs_err_t e = gf_args(r, l->args, &v, 1, &got, false);
    if (e != CS_OK)
        return e;
    if (f->ncalls == 0)
        return gf_err(r->diag, CS_ERR_PARSE, r->name, r->k, l->ocol, l, " reached outside a call");
    f->ncalls--;
    f->nreps = f->calls[f->ncalls].loops;
    cs_gexpr_return(r->st);
    /* LinuxCNC leaves a returned value in #<_value> (and #<_value_returned> = 1). */
    if ((e = cs_gexpr_set_named(r->st, "_value", got ? v : 0.0)) == CS_OK)
        e = cs_gexpr_set_named(r->st, "_value_returned", got ? 1.0 : 0.0);
    if (e != CS_OK)
        return gf_err(r->diag, e, r->name, r->k, l->ocol, l, ": out of memory");
    *next = f->calls[f->ncalls].ret;
    return CS_OK;
}

/* if [c] and its chain: the first branch whose condition holds, else the else, else past. */
static cs_err_t gf_if(gf_run_t *r, size_t *next)
{
    cs_gflow_t *f = r->f;
    size_t b = r->k;
    while (f->lines[b].kind == CS_GFLOW_IF || f->lines[b].kind == CS_GFLOW_ELSEIF) {
        r->k = b; /* each condition is read, and located, on its own line */
        r->s = r->buf + f->lines[b].start;
        r->n = f->lines[b].len;
        double c;
        size_t got;
        cs_err_t e = gf_args(r, f->lines[b].args, &c, 1, &got, true);
        if (e != CS_OK)
            return e;
        if (c != 0.0) {
            *next = b + 1;
            return CS_OK;
        }
        b = f->lines[b].next;
    }
    *next = b + 1; /* the else's body, or past the endif */
    return CS_OK;
}

/* The loop keywords. */
static cs_err_t gf_loop(gf_run_t *r, size_t *next)
{
    cs_gflow_t *f = r->f;
    const cs_gflow_line_t *l = &f->lines[r->k];
    double c = 0;
    size_t got;
    cs_err_t e = CS_OK;
    switch (l->kind) {
    case CS_GFLOW_WHILE:
        if ((e = gf_args(r, l->args, &c, 1, &got, true)) == CS_OK)
            *next = c != 0.0 ? r->k + 1 : l->next + 1;
        return e;
    case CS_GFLOW_ENDWHILE:
        *next = l->next;
        return gf_iterate(r);
    case CS_GFLOW_DO:
        *next = r->k + 1;
        return CS_OK;
    case CS_GFLOW_DOWHILE:
        if ((e = gf_args(r, l->args, &c, 1, &got, true)) != CS_OK)
            return e;
        *next = c != 0.0 ? l->next + 1 : r->k + 1;
        return c != 0.0 ? gf_iterate(r) : CS_OK;
    case CS_GFLOW_REPEAT:
        if ((e = gf_args(r, l->args, &c, 1, &got, true)) != CS_OK)
            return e;
        c = nearbyint(c);
        if (c < 1) {
            *next = l->next + 1;
            return CS_OK;
        }
        if (f->nreps >= CS_GFLOW_MAX_OPEN)
            return gf_err(r->diag, CS_ERR_RANGE, r->name, r->k, l->ocol, l,
                          ": repeats nested too deep");
        f->reps[f->nreps].line = r->k;
        f->reps[f->nreps++].remaining = c;
        *next = r->k + 1;
        return CS_OK;
    case CS_GFLOW_ENDREPEAT: {
        cs_gflow_rep_t *p = f->nreps ? &f->reps[f->nreps - 1] : NULL;
        if (!p || p->line != l->next)
            return gf_err(r->diag, CS_ERR_STATE, r->name, r->k, l->ocol, l,
                          " reached without its repeat");
        if (--p->remaining >= 1) {
            *next = l->next + 1;
            return gf_iterate(r);
        }
        f->nreps--;
        *next = r->k + 1;
        return CS_OK;
    }
    default: { /* break / continue: l->next is the loop's first line */
        const cs_gflow_line_t *o = &f->lines[l->next];
        bool cont = l->kind == CS_GFLOW_CONTINUE;
        /* Leaving the inner repeats (and, on break, the loop's own count). */
        while (f->nreps && f->reps[f->nreps - 1].line < o->next &&
               (f->reps[f->nreps - 1].line > l->next ||
                (!cont && f->reps[f->nreps - 1].line == l->next)))
            f->nreps--;
        if (cont) {
            *next = o->kind == CS_GFLOW_WHILE ? l->next : o->next;
            return o->kind == CS_GFLOW_WHILE ? gf_iterate(r) : CS_OK;
        }
        *next = o->next + 1;
        return CS_OK;
    }
    }
}

cs_err_t cs_gflow_exec(cs_gflow_t *f, const char *name, const char *buf, size_t k,
                       cs_gexpr_store_t *st, size_t *next, cs_path_diag_t *diag)
{
    cs_gflow_line_t *l = &f->lines[k];
    gf_run_t r = {f, name, buf, buf + l->start, l->len, k, st, diag};
    switch (l->kind) {
    case CS_GFLOW_SUB: /* a definition met in the flow: remembered, its body skipped */
        l->defined = true;
        *next = l->next + 1;
        return CS_OK;
    case CS_GFLOW_CALL:
        return gf_call(&r, next);
    case CS_GFLOW_ENDSUB:
    case CS_GFLOW_RETURN:
        return gf_return(&r, next);
    case CS_GFLOW_IF:
        return gf_if(&r, next);
    case CS_GFLOW_ELSEIF:
    case CS_GFLOW_ELSE: /* the end of a branch that ran */
        *next = l->end + 1;
        return CS_OK;
    case CS_GFLOW_ENDIF:
        *next = k + 1;
        return CS_OK;
    default:
        return gf_loop(&r, next);
    }
}
