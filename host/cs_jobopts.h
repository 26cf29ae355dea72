/* cs_jobopts: the one set of input options of every command that reads a job (flatten, plan,
 * stream, submit and the daemon, curvestep-sim --reference): --lenient, --dialect, --units, the
 * layout (cs_layout) and --merge / --sort (cs_order). Owns the option table, which drives the
 * command line (--name [VALUE]), the daemon's SUBMIT words (name[=VALUE], docs/streaming.md) and
 * the help text alike, and the one preparation of a read job (layout, then merge and sort) all
 * those commands run before planning. Host only. */
#ifndef CS_JOBOPTS_H
#define CS_JOBOPTS_H

#include <stdbool.h>
#include <stdio.h>

#include "cs_input.h"
#include "cs_layout.h"
#include "cs_machine.h"
#include "cs_path.h"

/* Room for the options as SUBMIT words (fits a request line with a long path). */
#define CS_JOBOPTS_WORDS_MAX 512

typedef struct {
    bool lenient;            /* --lenient (G-code) */
    cs_dialect_t dialect;    /* --dialect */
    cs_units_t units;        /* --units */
    cs_layout_opts_t layout; /* --scale --fit --page --margin --translate --rotate --flip-y */
    int merge, sort; /* --merge / --no-merge ...: 1 on, 0 off, -1 the default (on for a plotter) */
    char words[CS_JOBOPTS_WORDS_MAX]; /* what was given, as SUBMIT words " name[=value]" */
} cs_jobopts_t;

/* Strict, linuxcnc, default units, no layout, merge and sort by default. */
void cs_jobopts_init(cs_jobopts_t *o);
/* argv[*i] is one of the shared options: stores it (and its value, moving *i onto it), returns 1;
 * any other word, or a valued option without its value: 0; a bad value: -1, after
 * "curvestep CMD: --NAME wants ..." on stderr (a usage error). */
int cs_jobopts_option(const char *cmd, int argc, char **argv, int *i, cs_jobopts_t *o);
/* A SUBMIT word "name" or "name=value" of the same table: stores it; false when it is none. */
bool cs_jobopts_word(const char *word, cs_jobopts_t *o);
/* Combinations: 0, or -1 after "curvestep CMD: reason" on stderr (--fit with --scale). */
int cs_jobopts_check(const char *cmd, const cs_jobopts_t *o);
/* The options' help lines (from the table), as every command's --help shows them. */
void cs_jobopts_help(FILE *f);
/* Copies the reader options (lenient, dialect, units) into *io. */
void cs_jobopts_input(const cs_jobopts_t *o, cs_input_opts_t *io);
/* Whether merge (or sort) runs: the option, else on for a plotter (a machine file whose [pen]
 * section has a mode other than none). */
bool cs_jobopts_merge(const cs_jobopts_t *o, bool plotter);
bool cs_jobopts_sort(const cs_jobopts_t *o, bool plotter);

/* Prepares a read job for planning: the layout (--fit into m's x y travel, or the page), then
 * merge / sort with merge distance tol_mm. When merge or sort ran, one line to report (NULL:
 * none): "CMD: N pen lifts -> M, pen-up travel A mm -> B mm (merge, sort)". CS_OK, or an error
 * with diag filled. */
cs_err_t cs_jobopts_prepare(const cs_jobopts_t *o, const char *cmd, const cs_machine_t *m,
                            bool plotter, double tol_mm, cs_path_t *p, cs_path_diag_t *diag,
                            FILE *report);

#endif
