/* cs_lex: the whitespace-separated token reader of curvestep's own text formats (the surfaces
 * file, the curves file): tokens separated by blanks and newlines, '#' to the end of the line a
 * comment, each token with its 1-based line and column. Owns the located number, integer and
 * point readers those formats share, with "file:line:col: reason" diagnostics. */
#ifndef CS_LEX_H
#define CS_LEX_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_path.h"

/* Longest token kept (longer ones are cut, and then never a valid number or keyword). */
#define CS_LEX_TOK_MAX 64

typedef struct {
    const char *p, *end;
    unsigned line, col;
    const char *name;     /* file name for diagnostics */
    cs_path_diag_t *diag; /* where errors go (may be NULL only for cs_lex_next) */
    double scale;         /* cs_lex_vec multiplies coordinates by it (mm per file unit) */
    char tok[CS_LEX_TOK_MAX];
    unsigned tline, tcol; /* where tok starts (or the end of the text) */
} cs_lex_t;

/* Reader over text[0..len) named name, diagnostics into *diag, coordinates times scale. */
void cs_lex_init(cs_lex_t *lx, const char *text, size_t len, const char *name, cs_path_diag_t *diag,
                 double scale);
/* Next token into lx->tok; false at the end of the text (tline/tcol then point there). */
bool cs_lex_next(cs_lex_t *lx);
/* Location of the token just read. */
cs_path_loc_t cs_lex_here(const cs_lex_t *lx);
/* True when the next token is word (nothing consumed either way). */
bool cs_lex_peek_is(const cs_lex_t *lx, const char *word);
/* Next token as a finite number; CS_ERR_PARSE "'tok': WHAT expected" (or end of file). */
cs_err_t cs_lex_number(cs_lex_t *lx, const char *what, double *out);
/* Next token as an integer in lo..hi; CS_ERR_RANGE with the range otherwise. */
cs_err_t cs_lex_integer(cs_lex_t *lx, const char *what, int lo, int hi, int *out);
/* Three numbers times scale: the raw scaled values into d[] (may be NULL) and, when p is not
 * NULL, the point in fixed point (CS_ERR_RANGE, located at its first number, outside
 * +/-CS_POS_LIMIT_MM). */
cs_err_t cs_lex_vec(cs_lex_t *lx, const char *what, cs_vec3_t *p, double d[3]);
/* Next token as one of words[0..n) into *out; CS_ERR_PARSE "'tok': WHAT expected". */
cs_err_t cs_lex_choice(cs_lex_t *lx, const char *what, const char *const *words, int n, int *out);

#endif
