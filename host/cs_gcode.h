/* cs_gcode: the G-code reader. Turns RS274/NGC text (LinuxCNC's semantics by default, Grbl 1.1's
 * with CS_GCODE_GRBL) into path elements with their feed and rapid flag: G0/G1 lines, G2/G3 arcs
 * and helices, G5 cubic and G5.1 quadratic splines, G5.2/G5.3 and G6.2 NURBS blocks. Owns the
 * modal state (plane, units, distance modes, G92 offsets, feed) and the checks that refuse bad
 * input "file:line:col"; parameters and expressions are cs_gexpr's, O-word control flow
 * cs_gflow's, NURBS blocks cs_gnurbs's. */
#ifndef CS_GCODE_H
#define CS_GCODE_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_path.h"

/* Receives each warning (code CS_OK, loc and reason filled). */
typedef void (*cs_gcode_warn_fn)(void *ctx, const cs_path_diag_t *w);

/* Carries out a probing move (G38.2 .. G38.5, code in tenths) from `from` toward `to` (machine
 * mm) at feed_mm_s: *contact says whether the probe touched (G38.4 / G38.5: lost contact), hit
 * where the machine stopped (mm). Anything but CS_OK ends the read with that error. */
typedef cs_err_t (*cs_gcode_probe_fn)(void *ctx, int code, const double from[3],
                                      const double to[3], double feed_mm_s, bool *contact,
                                      double hit[3]);

/* The spindle (or laser, or pen) changed: code GC_M3, GC_M4 or GC_M5 (tenths), s the S in force.
 * Called at M3/M4/M5 and at an S that changes the speed of a running spindle, before the line's
 * motion. Anything but CS_OK ends the read with that error. */
typedef cs_err_t (*cs_gcode_spindle_fn)(void *ctx, int code, double s);

/* Default largest distance (mm) between a helix (G2/G3 with a third-axis move) and the rational
 * quadratic pieces that carry it. */
#define CS_GCODE_HELIX_TOL_MM 0.001

/* Whose G-code (docs/inputs.md, "Dialects", lists each difference). */
typedef enum {
    CS_GCODE_LINUXCNC = 0, /* LinuxCNC's G-code reference (the default) */
    CS_GCODE_GRBL = 1,     /* Grbl 1.1: starts in G0; no parameters, expressions, O-words,
                            * splines or NURBS; Grbl's arc radius check */
} cs_gcode_dialect_t;

typedef struct {
    bool lenient;         /* unsupported words: a warning and the word is ignored (not an error);
                           * also (each warned) bare G92 = no-op, G2/G3 without R or I/J/K = a
                           * straight feed move to its end, R arc ending on its start = nothing
                           * drawn in the plane, T = ignored. Checksums stay errors. */
    double helix_tol_mm;  /* > 0: bound on the helix approximation (see docs/inputs.md) */
    size_t max_elements;  /* > 0: refuse (CS_ERR_FULL) a job that needs more path elements */
    bool pen_z;           /* M3/M4 (pen down) and M5 (pen up) also move Z: */
    double pen_down_z_mm; /* to this machine Z on M3/M4 */
    double pen_up_z_mm;   /* to this machine Z on M5, and where the program starts */
    double pen_z_feed_mm_s; /* at this speed, mm/s ([pen] z_feed); 0: rapid */
    cs_gcode_dialect_t dialect;
    bool start_inch;         /* the program starts in G20 (inches) instead of G21 (mm) */
    unsigned long max_loops; /* O-word loop passes allowed in one program; 0: the default
                              * CS_GFLOW_MAX_LOOPS (a runaway loop is a located error) */
    cs_gcode_warn_fn warn;   /* NULL: "file:line:col: warning: reason" on stderr */
    void *warn_ctx;
    cs_gcode_probe_fn probe; /* NULL: G38.2 .. G38.5 are unsupported (a file has no probe) */
    void *probe_ctx;
    cs_gcode_spindle_fn spindle; /* NULL: none (M3/M4/M5 only split subpaths) */
    void *spindle_ctx;
} cs_gcode_opts_t;

/* What a read found (for tests and --stats). */
typedef struct {
    unsigned lines;    /* lines run (up to M2/M30 or the end; a line in a loop counts each pass) */
    unsigned warnings; /* warnings issued (lenient mode) */
    unsigned arcs;     /* G2/G3 moves */
    unsigned helices;  /* of which with a third-axis move */
} cs_gcode_stats_t;

/* Strict LinuxCNC, millimetres, helix tolerance CS_GCODE_HELIX_TOL_MM, warnings to stderr. */
void cs_gcode_opts_init(cs_gcode_opts_t *o);

/* Parses G-code in buf[0..len) (need not be NUL-terminated) named name; appends its moves to
 * *path (each element's feed_mm_s from F, rapid for G0; pen/spindle on or off (M3/M4/M5) and
 * each change between rapid and feed moves start a new subpath). The machine starts at 0, 0, 0
 * in G17 G21 (G20 with start_inch) G90 G91.1 G94, with no motion mode (Grbl: G0). O-words run
 * as LinuxCNC runs them; G64 P (the program's path tolerance, mm) lowers path->blend_tol_mm.
 * The whole input is read before returning.
 * CS_ERR_PARSE (syntax, checksum, exponent form, inconsistent words, an undefined parameter, an
 * O-word that does not pair), CS_ERR_UNSUPPORTED (a word this reader or the dialect does not carry
 * out, unless lenient), CS_ERR_DEGENERATE / CS_ERR_RANGE (bad arcs, coordinates outside +/-4096
 * mm, a math error in an expression, calls nested past 10, a runaway loop), CS_ERR_WEIGHT /
 * CS_ERR_KNOTS (NURBS blocks), CS_ERR_FULL (out of memory), each with *diag. stats may be NULL. */
cs_err_t cs_gcode_read(const char *name, const char *buf, size_t len, const cs_gcode_opts_t *o,
                       cs_path_t *path, cs_path_diag_t *diag, cs_gcode_stats_t *stats);

/* ---- line at a time (a sender's stream: `curvestep grbl`) ---- */

/* A reader that keeps its state across lines: position, modal state, parameters (work offsets
 * among them), O-word subroutines defined so far, an open NURBS block. */
typedef struct cs_gcode_session cs_gcode_session_t;

/* What a sender may ask about (Grbl's $G, $#, status WCO). */
typedef struct {
    double pos[3];    /* machine position after the last line, mm */
    double off[3];    /* program coordinate = machine - off (coordinate system + G92), mm */
    int wcs;          /* coordinate system in use, 1 (G54) .. 9 (G59.3) */
    bool inch, incr, ijk_abs;
    int plane;        /* 17, 18, 19 */
    int motion;       /* G code of the motion mode in tenths (cs_gcode_words.h), -1: none */
    double feed;      /* F in program units per minute, 0: none given */
    int spindle;      /* M3, M4 or M5 in tenths (cs_gcode_words.h) */
    double speed;     /* S */
    bool holding;     /* lines are held: an O-word block or G5.2 block is open */
} cs_gcode_state_t;

/* A session named name (in locations) with options o (copied; NULL: defaults). NULL without
 * memory. The machine starts as cs_gcode_read starts it. */
cs_gcode_session_t *cs_gcode_session_new(const char *name, const cs_gcode_opts_t *o);
void cs_gcode_session_free(cs_gcode_session_t *s);
/* Reads one line (line[0..len), no end of line) numbered lineno (for locations) and appends its
 * moves to *out (loc file: the session's name). Lines of an O-word block (sub ... endsub, if,
 * while, do, repeat) are held and run when the block closes; a sub definition is kept for later
 * calls. *ended is set by M2 / M30 (the modal state is then back at the start, position, offsets
 * and parameters kept). Errors as cs_gcode_read; on an error the state is as before the line
 * and the held block (if any) is dropped. */
cs_err_t cs_gcode_feed(cs_gcode_session_t *s, const char *line, size_t len, unsigned lineno,
                       cs_path_t *out, cs_path_diag_t *diag, bool *ended);
/* Puts the state back to what it was before the last successful cs_gcode_feed (once). False
 * when there is nothing to undo. */
bool cs_gcode_undo(cs_gcode_session_t *s);
void cs_gcode_state(const cs_gcode_session_t *s, cs_gcode_state_t *st);
/* Numbered parameter #index (1..5399), 0 outside. */
double cs_gcode_param(const cs_gcode_session_t *s, int index);
/* The machine is at mm (after a cancelled move, a probe, homing). */
void cs_gcode_set_pos(cs_gcode_session_t *s, const double mm[3]);
/* Modal state back to the start; held lines dropped; with clear_g92 the G92 offsets too (a soft
 * reset). Position, coordinate systems and parameters are kept. */
void cs_gcode_reset(cs_gcode_session_t *s, bool clear_g92);

#endif
