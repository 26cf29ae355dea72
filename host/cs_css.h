/* cs_css: the part of CSS an SVG reader needs to decide what a plotter draws: style sheets
 * (<style> contents) of rules with selectors by element name, '*', '#id', '.class' (several per
 * element), compounds of those (rect.a.b#c), comma groups, descendant (' ') and child ('>')
 * combinators; declarations with !important; the cascade of CSS 2.1 §6.4 (importance, then
 * specificity, then order; the caller puts style="" above the sheet and presentation attributes
 * below it). Comments, CDO/CDC are skipped; at-rules (@media, @import, @font-face...) and
 * selectors using pseudo-classes, attribute selectors or sibling combinators are skipped with a
 * warning; a malformed rule is skipped with a warning at its offset and the rest read. Host
 * only (malloc). See docs/inputs.md "SVG". */
#ifndef CS_CSS_H
#define CS_CSS_H

#include <stdbool.h>
#include <stddef.h>

/* Longest selector (compounds joined by combinators) honoured; longer ones are skipped. */
#define CS_CSS_MAX_COMPOUNDS 16

/* An element as selectors see it: local name, id and class attributes (NULL: none), parent
 * (NULL at the root). */
typedef struct cs_css_elem {
    const char *name;
    const char *id;
    const char *cls;
    const struct cs_css_elem *parent;
} cs_css_elem_t;

/* One declared value: text[0..len) trimmed, without "!important". */
typedef struct {
    const char *text;
    size_t len;
    bool important;
    bool set;                /* false: not declared */
    unsigned long long rank; /* sheets: specificity, then order (larger wins, same importance) */
} cs_css_value_t;

/* Receives a warning at byte `off` of the sheet text given to cs_css_add (kind: a static key
 * naming the kind of problem, for "once per kind" reporting; msg: static text). */
typedef void (*cs_css_warn_fn)(void *ctx, size_t off, const char *kind, const char *msg);

typedef struct cs_css_rule cs_css_rule_t;
typedef struct cs_css_decl cs_css_decl_t;

typedef struct {
    char **texts; /* owned copies of the sheets (values point into them) */
    size_t ntexts;
    cs_css_rule_t *rules;
    size_t nrules, cap;
    cs_css_decl_t *decls; /* every rule's declarations, parsed */
    size_t ndecls, dcap;
    bool out_of_memory;
} cs_css_sheet_t;

/* An empty sheet. */
void cs_css_init(cs_css_sheet_t *s);

/* Releases everything cs_css_add allocated. */
void cs_css_free(cs_css_sheet_t *s);

/* Reads the style sheet text[0..len) after the rules already held (later sheets come later in
 * the cascade order). Problems are warnings through warn (may be NULL). false when out of
 * memory (the rules read so far stay). */
bool cs_css_add(cs_css_sheet_t *s, const char *text, size_t len, cs_css_warn_fn warn, void *ctx);

/* The cascaded sheet values of props[0..n) for element e: out[i] is the winning declaration of
 * props[i] among the matching rules (out[i].set false when none declares it). */
void cs_css_cascade(const cs_css_sheet_t *s, const cs_css_elem_t *e, const char *const *props,
                    size_t n, cs_css_value_t *out);

/* The value of property prop in a declaration list (a style="" attribute's text, NUL
 * terminated): the last declaration of it, an !important one over any normal one. */
cs_css_value_t cs_css_inline(const char *decls, const char *prop);

/* The winner of two declarations of one property: CSS cascade order, inline over sheet.
 * `inline_` is a style="" value, `sheet` a cs_css_cascade value. */
cs_css_value_t cs_css_pick(cs_css_value_t inline_, cs_css_value_t sheet);

#endif
