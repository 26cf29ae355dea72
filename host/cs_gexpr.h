/* cs_gexpr: LinuxCNC G-code parameters and expressions for the G-code reader (cs_gcode). Owns the
 * parameter store: numbered parameters #1..#5399 (#1..#30 local to a subroutine call), named
 * local #<name> and global #<_name> parameters, the assignments of the current line (which take
 * effect at its end), and the call frames that save #1..#30. Evaluates real values: numbers,
 * #parameters, [expressions] with LinuxCNC's operators and precedence, and the unary functions.
 * Semantics from LinuxCNC's G-code reference ("Overview": parameters, expressions, binary
 * operators, functions); the exact sentences are cited in tests/unit/test_gexpr.c. Host only. */
#ifndef CS_GEXPR_H
#define CS_GEXPR_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_err.h"

#define CS_GEXPR_NUM_PARAMS  5400   /* numbered parameters #1..#5399 (index 0 unused) */
#define CS_GEXPR_LOCALS      30     /* #1..#30: a call's arguments, restored on return */
#define CS_GEXPR_NAME_MAX    64     /* longest parameter name kept, with its NUL */
#define CS_GEXPR_MAX_PENDING 64     /* parameter settings on one line */
#define CS_GEXPR_MAX_CALLS   10     /* LinuxCNC: "The maximum subroutine nesting level is 10" */
#define CS_GEXPR_MAX_NEST    32     /* brackets and functions nested in one real value */
#define CS_GEXPR_EQ_TOL      0.0001 /* EQ and NE compare to this (LinuxCNC's TOLERANCE_EQUAL) */

/* Where and why a read failed: byte index into the line, and a reason. */
typedef struct {
    size_t at;
    char reason[160];
} cs_gexpr_fail_t;

typedef struct {
    char name[CS_GEXPR_NAME_MAX]; /* lower case, blanks removed; "_..." is global */
    double v;
    unsigned level; /* call level it belongs to (globals: 0) */
} cs_gexpr_named_t;

typedef struct {
    int index; /* numbered parameter, or 0 for a named one */
    char name[CS_GEXPR_NAME_MAX];
    double v;
} cs_gexpr_pending_t;

typedef struct {
    double *num; /* CS_GEXPR_NUM_PARAMS values, all 0 at start */
    cs_gexpr_named_t *named;
    size_t nnamed, capnamed;
    cs_gexpr_pending_t pending[CS_GEXPR_MAX_PENDING];
    size_t npending;
    double saved[CS_GEXPR_MAX_CALLS][CS_GEXPR_LOCALS]; /* #1..#30 of each caller */
    unsigned level;                                    /* 0: the main program */
} cs_gexpr_store_t;

/* Empty store (every numbered parameter 0, no named ones). CS_ERR_FULL without memory. */
cs_err_t cs_gexpr_init(cs_gexpr_store_t *st);
void cs_gexpr_free(cs_gexpr_store_t *st);
/* *dst becomes an independent copy of *src (a session's undo). CS_ERR_FULL without memory (dst
 * is then empty). */
cs_err_t cs_gexpr_copy(cs_gexpr_store_t *dst, const cs_gexpr_store_t *src);

/* An explicit number at s[*i] (line s[0..n)): [+-] digits [. digits], no blanks inside. A number
 * followed by e/E and a digit is refused (LinuxCNC has no exponent form). On success *i moves
 * past it. CS_ERR_PARSE with *f otherwise (f->at = *i when no number starts there). */
cs_err_t cs_gexpr_number(const char *s, size_t n, size_t *i, double *out, cs_gexpr_fail_t *f);

/* A real value at s[*i]: a number, #parameter, [expression], unary function or a sign before
 * one of those. Blanks are skipped between items. CS_ERR_PARSE (syntax, an undefined named
 * parameter, an index outside 1..5399) or CS_ERR_RANGE (division by zero, a function outside
 * its domain, a result that is not finite) with *f. */
cs_err_t cs_gexpr_real(cs_gexpr_store_t *st, const char *s, size_t n, size_t *i, double *out,
                       cs_gexpr_fail_t *f);

/* A parameter setting at s[*i] == '#': "#index = value" or "#<name> = value"; the value is read
 * now (with the line's old values) and stored by cs_gexpr_commit. Errors as cs_gexpr_real. */
cs_err_t cs_gexpr_assign(cs_gexpr_store_t *st, const char *s, size_t n, size_t *i,
                         cs_gexpr_fail_t *f);
/* Stores the line's pending settings in the order written (the last of one parameter wins);
 * CS_ERR_FULL when a new named parameter finds no memory. */
cs_err_t cs_gexpr_commit(cs_gexpr_store_t *st);
/* Drops the line's pending settings (a line that failed). */
void cs_gexpr_discard(cs_gexpr_store_t *st);

/* Sets named parameter name (lower case, "_..." global) now. CS_ERR_FULL without memory. */
cs_err_t cs_gexpr_set_named(cs_gexpr_store_t *st, const char *name, double v);
/* The value of a named parameter visible here; false if it is not defined. */
bool cs_gexpr_get_named(const cs_gexpr_store_t *st, const char *name, double *v);

/* A subroutine call: saves #1..#30, sets #1..#nargs to args (the rest keep their values, as
 * LinuxCNC specifies) and enters a new level. CS_ERR_FULL past CS_GEXPR_MAX_CALLS levels. */
cs_err_t cs_gexpr_call(cs_gexpr_store_t *st, const double *args, size_t nargs);
/* The matching return: restores #1..#30 and forgets the level's local named parameters. */
void cs_gexpr_return(cs_gexpr_store_t *st);

#endif
