/* cs_gflow: LinuxCNC O-word control flow for the G-code reader (cs_gcode). Owns the program's
 * line table, the O-word lines found in it and how they pair up (sub/endsub, if/elseif/else/
 * endif, while/endwhile, do/while, repeat/endrepeat, break/continue to their loop, return to its
 * sub), the call stack, repeat counters and the runaway-loop bound. It decides which line runs
 * next; cs_gcode runs every other line. Semantics from LinuxCNC's G-code reference, "O Codes"
 * (cited in tests/unit/test_gcode.c). Host only. */
#ifndef CS_GFLOW_H
#define CS_GFLOW_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_gexpr.h"
#include "cs_path.h"

#define CS_GFLOW_LABEL_MAX 64      /* longest O label ("100", "<name>" lower case) kept */
#define CS_GFLOW_MAX_OPEN  256     /* constructs open at once while pairing */
#define CS_GFLOW_MAX_LOOPS 1000000 /* default bound on loop iterations in one program */

typedef enum {
    CS_GFLOW_NONE = 0, /* not an O-word line */
    CS_GFLOW_SUB,
    CS_GFLOW_ENDSUB,
    CS_GFLOW_CALL,
    CS_GFLOW_RETURN,
    CS_GFLOW_IF,
    CS_GFLOW_ELSEIF,
    CS_GFLOW_ELSE,
    CS_GFLOW_ENDIF,
    CS_GFLOW_WHILE,
    CS_GFLOW_ENDWHILE,
    CS_GFLOW_DO,
    CS_GFLOW_DOWHILE, /* the "while" that ends a do loop */
    CS_GFLOW_REPEAT,
    CS_GFLOW_ENDREPEAT,
    CS_GFLOW_BREAK,
    CS_GFLOW_CONTINUE,
} cs_gflow_kind_t;

typedef struct {
    size_t start, len;    /* the line's bytes in the buffer (no end of line) */
    cs_gflow_kind_t kind; /* CS_GFLOW_NONE for ordinary lines */
    char label[CS_GFLOW_LABEL_MAX];
    size_t args;   /* offset in the line just past the keyword */
    unsigned ocol; /* column of the 'o' */
    size_t next;   /* if/elseif/else: the next branch line; loops: their other end;
                    * break/continue/return: the loop or sub start */
    size_t end;    /* if branches: the endif line */
    bool defined;  /* sub: execution has passed its definition */
} cs_gflow_line_t;

typedef struct {
    size_t ret;   /* line to go on with after the call */
    size_t loops; /* repeat frames open when called */
} cs_gflow_call_t;

typedef struct {
    size_t line;      /* the repeat line */
    double remaining; /* passes left */
} cs_gflow_rep_t;

typedef struct {
    cs_gflow_line_t *lines;
    size_t n;
    size_t *subs; /* the sub lines, in file order (a call looks its sub up here) */
    size_t nsubs;
    cs_gflow_call_t calls[CS_GEXPR_MAX_CALLS];
    unsigned ncalls;
    cs_gflow_rep_t reps[CS_GFLOW_MAX_OPEN];
    size_t nreps;
    unsigned long iterations, max_iterations;
} cs_gflow_t;

/* Splits buf[0..len) into lines (LF, CR or CR LF) and pairs the O-words of a LinuxCNC program
 * (o_words false: Grbl, none are looked for). max_iterations: loop passes allowed in all (0:
 * CS_GFLOW_MAX_LOOPS). CS_ERR_PARSE with *diag "name:line:col: reason" for an O-word that does
 * not pair (an endif with no if, a sub not closed...), CS_ERR_FULL without memory. */
cs_err_t cs_gflow_init(cs_gflow_t *f, const char *name, const char *buf, size_t len, bool o_words,
                       unsigned long max_iterations, cs_path_diag_t *diag);
void cs_gflow_free(cs_gflow_t *f);

/* Reads the O-word of line s[0..n) into *l (kind CS_GFLOW_NONE when the line has none): what a
 * line-at-a-time reader needs to know whether a block opens or closes. CS_ERR_PARSE when it is
 * malformed (cs_gflow_init then says where and why). */
cs_err_t cs_gflow_line_parse(const char *s, size_t n, cs_gflow_line_t *l);

/* The line of sub o<label> ("100", "<name>"), or f->n when the file has none. */
size_t cs_gflow_find_sub(const cs_gflow_t *f, const char *label);

/* Column (1-based, in characters: UTF-8 continuation bytes do not count) of s[i] on a line that
 * starts at s[0]; the column every G-code diagnostic gives. */
unsigned cs_gflow_col(const char *s, size_t i);

/* Runs O-word line k (f->lines[k].kind != NONE) of buf, evaluating its arguments with st, and
 * sets *next to the line to run next. Errors (CS_ERR_PARSE, CS_ERR_RANGE, CS_ERR_FULL) with
 * *diag: a call to a sub not defined before it, too deep a call, a runaway loop... */
cs_err_t cs_gflow_exec(cs_gflow_t *f, const char *name, const char *buf, size_t k,
                       cs_gexpr_store_t *st, size_t *next, cs_path_diag_t *diag);

#endif
