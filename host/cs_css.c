/* cs_css: style sheets and the cascade for the SVG reader (see cs_css.h).
 * Grammar after CSS Syntax 3 (tokenisation simplified: strings, comments, blocks) and
 * Selectors 3 (type, universal, id, class, descendant and child combinators). */
#include "cs_css.h"
#include "cs_path.h"

#include <stdlib.h>
#include <string.h>

/* Classes in one compound selector honoured (more: the selector is skipped). */
#define MAX_CLASSES 8
/* Steps of the backtracking descendant match per rule and element: a bound on hostile input
 * (a a a a ... against a deep tree), far above what real selectors need. */
#define MATCH_BUDGET 4096u

typedef struct {
    const char *p;
    size_t n;
} span_t;

typedef struct {
    span_t name; /* n == 0: any element */
    span_t id;   /* n == 0: no id required */
    span_t cls[MAX_CLASSES];
    unsigned ncls;
    char comb; /* how the compound on its left relates: ' ' ancestor, '>' parent */
} compound_t;

struct cs_css_rule {
    compound_t c[CS_CSS_MAX_COMPOUNDS]; /* left to right; the last matches the element */
    unsigned n;
    unsigned long long rank; /* specificity << 32 | order */
    size_t dfirst, dn;       /* its block's declarations: s->decls[dfirst..dfirst + dn) */
};

void cs_css_init(cs_css_sheet_t *s)
{
    memset(s, 0, sizeof *s);
}

void cs_css_free(cs_css_sheet_t *s)
{
    for (size_t i = 0; i < s->ntexts; i++)
        free(s->texts[i]);
    free(s->texts);
    free(s->rules);
    free(s->decls);
    cs_css_init(s);
}

/* --- scanning ------------------------------------------------------------------------------- */

static bool is_ws(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f';
}

static bool is_ident(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-' || (unsigned char)c >= 0x80;
}

/* Past a comment at s[i] ("/ *...* /"; unterminated: to the end); i when none. */
static size_t past_comment(const char *s, size_t len, size_t i)
{
    if (i + 1 >= len || s[i] != '/' || s[i + 1] != '*')
        return i;
    for (i += 2; i + 1 < len; i++)
        if (s[i] == '*' && s[i + 1] == '/')
            return i + 2;
    return len;
}

/* Past white space, comments and (at the top level) the HTML comment tokens <!-- and -->. */
static size_t skip_blank(const char *s, size_t len, size_t i, bool cdo)
{
    for (;;) {
        size_t j = past_comment(s, len, i);
        if (j != i) {
            i = j;
        } else if (i < len && is_ws(s[i])) {
            i++;
        } else if (cdo && len - i >= 4 && memcmp(s + i, "<!--", 4) == 0) {
            i += 4;
        } else if (cdo && len - i >= 3 && memcmp(s + i, "-->", 3) == 0) {
            i += 3;
        } else {
            return i;
        }
    }
}

/* Scans from s[i] to the first of the characters in `stop` found outside strings, comments and
 * (), [] or {} nesting; len when none. */
static size_t scan_to(const char *s, size_t len, size_t i, const char *stop)
{
    unsigned depth = 0;
    while (i < len) {
        char c = s[i];
        size_t j = past_comment(s, len, i);
        if (j != i) {
            i = j;
            continue;
        }
        if (depth == 0 && strchr(stop, c))
            return i;
        if (c == '"' || c == '\'') {
            for (i++; i < len && s[i] != c; i++)
                if (s[i] == '\\')
                    i++;
        } else if (c == '(' || c == '[' || c == '{') {
            depth++;
        } else if ((c == ')' || c == ']' || c == '}') && depth > 0) {
            depth--;
        } else if (c == '\\') {
            i++;
        }
        i++;
    }
    return len;
}

static span_t trim(const char *p, size_t n)
{
    while (n > 0 && is_ws(*p)) {
        p++;
        n--;
    }
    while (n > 0 && is_ws(p[n - 1]))
        n--;
    span_t r = {p, n};
    return r;
}

static bool ieq(const char *a, const char *b, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        char x = a[i], y = b[i];
        if (x >= 'A' && x <= 'Z')
            x = (char)(x - 'A' + 'a');
        if (y >= 'A' && y <= 'Z')
            y = (char)(y - 'A' + 'a');
        if (x != y)
            return false;
    }
    return true;
}

/* --- declarations --------------------------------------------------------------------------- */

struct cs_css_decl {
    span_t name, value;
    bool important;
    bool bad;   /* no colon, or no property name */
    size_t off; /* offset of the declaration in the scanned text */
};
typedef struct cs_css_decl decl_t;

/* The next declaration of s[*i..len); false at the end. */
static bool next_decl(const char *s, size_t len, size_t *i, decl_t *d)
{
    size_t j = *i;
    for (;;) {
        j = skip_blank(s, len, j, false);
        if (j < len && s[j] == ';')
            j++;
        else
            break;
    }
    if (j >= len)
        return false;
    memset(d, 0, sizeof *d);
    d->off = j;
    size_t end = scan_to(s, len, j, ";");
    size_t colon = scan_to(s, end, j, ":");
    *i = end < len ? end + 1 : len;
    d->name = trim(s + j, colon - j);
    if (colon >= end || d->name.n == 0) {
        d->bad = true;
        return true;
    }
    for (size_t k = 0; k < d->name.n; k++)
        if (!is_ident(d->name.p[k]))
            d->bad = true;
    span_t v = trim(s + colon + 1, end - colon - 1);
    size_t bang = scan_to(v.p, v.n, 0, "!");
    if (bang < v.n) {
        span_t imp = trim(v.p + bang + 1, v.n - bang - 1);
        if (imp.n == 9 && ieq(imp.p, "important", 9))
            d->important = true;
        else
            d->bad = true;
        v = trim(v.p, bang);
    }
    d->value = v;
    return true;
}

static bool better(const cs_css_value_t *a, const cs_css_value_t *b)
{
    if (!b->set)
        return true;
    if (a->important != b->important)
        return a->important;
    return a->rank >= b->rank;
}

/* Offers declaration d to out if it declares one of props (rank: its rule's). */
static void offer(const decl_t *d, unsigned long long rank, const char *const *props, size_t np,
                  cs_css_value_t *out)
{
    for (size_t k = 0; k < np; k++) {
        if (strlen(props[k]) != d->name.n || !ieq(props[k], d->name.p, d->name.n))
            continue;
        cs_css_value_t c = {d->value.p, d->value.n, d->important, true, rank};
        if (better(&c, &out[k]))
            out[k] = c;
    }
}

cs_css_value_t cs_css_inline(const char *decls, const char *prop)
{
    cs_css_value_t v;
    memset(&v, 0, sizeof v);
    size_t i = 0, n = decls ? strlen(decls) : 0;
    decl_t d;
    while (n && next_decl(decls, n, &i, &d))
        if (!d.bad)
            offer(&d, 0, &prop, 1, &v);
    return v;
}

cs_css_value_t cs_css_pick(cs_css_value_t inline_, cs_css_value_t sheet)
{
    if (inline_.set && (inline_.important || !sheet.important))
        return inline_;
    return sheet.set ? sheet : inline_;
}

/* --- selectors ------------------------------------------------------------------------------ */

enum { SEL_OK, SEL_UNSUPPORTED, SEL_INVALID };

static size_t ident_end(const char *s, size_t len, size_t i)
{
    while (i < len && is_ident(s[i]))
        i++;
    return i;
}

/* One compound selector from s[*i]: type or '*', then #id / .class. *i: past it, or at the
 * offending character. */
static int parse_compound(const char *s, size_t len, size_t *i, compound_t *c, unsigned *spec)
{
    size_t j = *i, start = j;
    if (j < len && s[j] == '*') {
        j++;
    } else if (j < len && is_ident(s[j]) && !(s[j] >= '0' && s[j] <= '9')) {
        size_t e = ident_end(s, len, j);
        c->name.p = s + j;
        c->name.n = e - j;
        j = e;
        *spec += 1;
    }
    while (j < len) {
        char k = s[j];
        *i = j;
        if (k == ':' || k == '[' || k == '\\' || k == '|')
            return SEL_UNSUPPORTED;
        if (k != '#' && k != '.')
            break;
        size_t e = ident_end(s, len, j + 1);
        if (e == j + 1)
            return SEL_INVALID;
        span_t name = {s + j + 1, e - j - 1};
        if (k == '#') {
            if (c->id.n && (c->id.n != name.n || memcmp(c->id.p, name.p, name.n) != 0))
                return SEL_UNSUPPORTED; /* two ids: matches nothing */
            c->id = name;
            *spec += 1u << 20;
        } else {
            if (c->ncls == MAX_CLASSES)
                return SEL_UNSUPPORTED;
            c->cls[c->ncls++] = name;
            *spec += 1u << 10;
        }
        j = e;
    }
    if (j == start)
        return SEL_INVALID;
    *i = j;
    return SEL_OK;
}

/* One selector s[0..len) (no commas) into r; specificity after CSS 2.1 §6.4.3 (ids, classes,
 * types; each count below 1024). */
static int parse_selector(const char *s, size_t len, cs_css_rule_t *r, unsigned *spec, size_t *bad)
{
    size_t i = skip_blank(s, len, 0, false);
    char comb = 0;
    r->n = 0;
    *spec = 0;
    for (;;) {
        *bad = i;
        if (r->n == CS_CSS_MAX_COMPOUNDS)
            return SEL_UNSUPPORTED;
        compound_t *c = &r->c[r->n];
        memset(c, 0, sizeof *c);
        c->comb = comb;
        int k = parse_compound(s, len, &i, c, spec);
        *bad = i;
        if (k != SEL_OK)
            return k;
        r->n++;
        size_t j = skip_blank(s, len, i, false);
        bool ws = j > i;
        i = j;
        *bad = i;
        if (i >= len)
            return r->n ? SEL_OK : SEL_INVALID;
        if (s[i] == '>') {
            comb = '>';
            i = skip_blank(s, len, i + 1, false);
        } else if (s[i] == '+' || s[i] == '~') {
            return SEL_UNSUPPORTED;
        } else if (ws) {
            comb = ' ';
        } else {
            return SEL_INVALID;
        }
    }
}

static bool add_rule(cs_css_sheet_t *s, const cs_css_rule_t *r)
{
    void *b = s->rules;
    if (!cs_path_grow(&b, &s->cap, s->nrules + 1, sizeof *s->rules))
        return false;
    s->rules = b;
    s->rules[s->nrules++] = *r;
    return true;
}

/* Every selector of a rule's prelude s[ps..pe) with its block: a group holding an invalid
 * selector is dropped whole (CSS); an unsupported one alone. */
static bool add_group(cs_css_sheet_t *s, const char *t, size_t ps, size_t pe, size_t dfirst,
                      cs_css_warn_fn warn, void *ctx)
{
    cs_css_rule_t *tmp = malloc(sizeof *tmp); /* ~3 KB: off the stack */
    if (!tmp)
        return false;
    /* first pass: validity; second: add */
    for (int pass = 0; pass < 2; pass++) {
        for (size_t a = ps; a < pe;) {
            size_t b = scan_to(t, pe, a, ",");
            unsigned spec = 0;
            size_t bad = 0;
            int k = parse_selector(t + a, b - a, &tmp[0], &spec, &bad);
            if (pass == 0 && k == SEL_INVALID) {
                if (warn)
                    warn(ctx, a + bad, "css-selector", "invalid selector: the rule is skipped");
                free(tmp);
                return true;
            }
            if (pass == 1 && k == SEL_UNSUPPORTED && warn)
                warn(ctx, a + bad, "css-unsupported",
                     "unsupported selector (pseudo-class, attribute, sibling or namespace "
                     "selector): it matches nothing here");
            if (pass == 1 && k == SEL_OK) {
                tmp[0].dfirst = dfirst;
                tmp[0].dn = s->ndecls - dfirst;
                tmp[0].rank = (unsigned long long)spec << 32 | (unsigned long long)s->nrules;
                if (!add_rule(s, &tmp[0])) {
                    free(tmp);
                    return false;
                }
            }
            a = b + 1;
        }
    }
    free(tmp);
    return true;
}

/* The declarations of a block into s->decls (parsed once for every element they are offered
 * to); a warning for each malformed one. */
static bool read_decls(cs_css_sheet_t *s, span_t b, const char *t, cs_css_warn_fn warn, void *ctx)
{
    size_t i = 0;
    decl_t d;
    while (next_decl(b.p, b.n, &i, &d)) {
        if (d.bad) {
            if (warn)
                warn(ctx, (size_t)(b.p - t) + d.off, "css-decl",
                     "malformed declaration (expected property: value): skipped");
            continue;
        }
        void *nd = s->decls;
        if (!cs_path_grow(&nd, &s->dcap, s->ndecls + 1, sizeof *s->decls))
            return false;
        s->decls = nd;
        s->decls[s->ndecls++] = d;
    }
    return true;
}

bool cs_css_add(cs_css_sheet_t *s, const char *text, size_t len, cs_css_warn_fn warn, void *ctx)
{
    char **nt = realloc(s->texts, (s->ntexts + 1) * sizeof *nt);
    if (!nt)
        return false;
    s->texts = nt;
    char *t = malloc(len + 1);
    if (!t)
        return false;
    memcpy(t, text, len);
    t[len] = '\0';
    s->texts[s->ntexts++] = t;
    size_t i = 0;
    for (;;) {
        i = skip_blank(t, len, i, true);
        if (i >= len)
            return true;
        if (t[i] == '@') { /* an at-rule: up to its ';' or past its {} block */
            if (warn)
                warn(ctx, i, "css-at", "ignoring at-rules (@media, @import, @font-face...)");
            i = scan_to(t, len, i, ";{");
            if (i < len && t[i] == '{')
                i = scan_to(t, len, i + 1, "}");
            i = i < len ? i + 1 : len;
            continue;
        }
        size_t ps = i, pe = scan_to(t, len, i, "{");
        if (pe >= len) {
            if (warn)
                warn(ctx, ps, "css-syntax", "a selector without a { declaration block }");
            return true;
        }
        size_t be = scan_to(t, len, pe + 1, "}"); /* the end of the sheet closes it (CSS) */
        span_t b = {t + pe + 1, be - pe - 1};
        size_t dfirst = s->ndecls;
        if (!read_decls(s, b, t, warn, ctx) || !add_group(s, t, ps, pe, dfirst, warn, ctx))
            return false;
        i = be < len ? be + 1 : len;
    }
}

/* --- matching ------------------------------------------------------------------------------- */

static bool span_is(span_t a, const char *z)
{
    return z && strlen(z) == a.n && memcmp(z, a.p, a.n) == 0;
}

/* Whether the white-space separated list `list` holds the word w. */
static bool has_word(const char *list, span_t w)
{
    if (!list)
        return false;
    for (const char *p = list; *p;) {
        while (*p && is_ws(*p))
            p++;
        const char *q = p;
        while (*q && !is_ws(*q))
            q++;
        if ((size_t)(q - p) == w.n && memcmp(p, w.p, w.n) == 0)
            return true;
        p = q;
    }
    return false;
}

static bool compound_match(const compound_t *c, const cs_css_elem_t *e)
{
    if (c->name.n && !span_is(c->name, e->name))
        return false;
    if (c->id.n && !span_is(c->id, e->id))
        return false;
    for (unsigned k = 0; k < c->ncls; k++)
        if (!has_word(e->cls, c->cls[k]))
            return false;
    return true;
}

/* Compounds 0..k of r against e and its ancestors, right to left, backtracking over the
 * ancestors a descendant combinator allows (within *budget steps). */
static bool match_from(const cs_css_rule_t *r, unsigned k, const cs_css_elem_t *e, unsigned *budget)
{
    if (*budget == 0)
        return false;
    (*budget)--;
    if (!compound_match(&r->c[k], e))
        return false;
    if (k == 0)
        return true;
    if (r->c[k].comb == '>')
        return e->parent && match_from(r, k - 1, e->parent, budget);
    for (const cs_css_elem_t *a = e->parent; a; a = a->parent)
        if (match_from(r, k - 1, a, budget))
            return true;
    return false;
}

void cs_css_cascade(const cs_css_sheet_t *s, const cs_css_elem_t *e, const char *const *props,
                    size_t n, cs_css_value_t *out)
{
    memset(out, 0, n * sizeof *out);
    for (size_t i = 0; i < s->nrules; i++) {
        const cs_css_rule_t *r = &s->rules[i];
        unsigned budget = MATCH_BUDGET;
        if (r->n && match_from(r, r->n - 1, e, &budget))
            for (size_t k = 0; k < r->dn; k++)
                offer(&s->decls[r->dfirst + k], r->rank, props, n, out);
    }
}
