/* cs_grbl_gc: G-code one line at a time for the Grbl front end (`curvestep grbl`): a cs_gcode
 * session (cs_gcode_feed: parameters, work offsets, O-word subroutines and blocks, NURBS blocks
 * carried across the lines a sender sends) and a copy of its state after each line for the
 * status report, $G and $#. Host only. */
#ifndef CS_GRBL_GC_H
#define CS_GRBL_GC_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_gcode.h"
#include "cs_path.h"

/* Longest line a client may send (Grbl's LINE_BUFFER_SIZE is 80; we are more generous). */
#define CS_GRBL_GC_LINE_MAX 256
/* Most lines held in one open G5.2 block. */
#define CS_GRBL_GC_BLOCK_MAX 256

typedef struct {
    cs_gcode_session_t *s; /* the reader (NULL: out of memory at init) */
    /* the session's state after the last call (cs_gcode_state), for the reports */
    double pos[3];   /* machine position, mm */
    double off[3];   /* program coordinate = machine - off (coordinate system + G92), mm */
    int wcs;         /* 1 (G54) .. 9 (G59.3) */
    bool inch;       /* G20 */
    bool incr;       /* G91 */
    bool ijk_abs;    /* G90.1 */
    int plane;       /* 17, 18, 19 */
    int motion;      /* G code of the motion mode in tenths (cs_gcode_words.h), -1: none */
    double feed;     /* F in program units per minute, 0: none given */
    int spindle;     /* M3, M4, M5 in tenths */
    double speed;    /* S */
} cs_grbl_gc_t;

/* Program start: position 0, no offsets, G54 G21 G90 G91.1 G17, no motion mode, no feed.
 * CS_ERR_FULL without memory. o: the reader's options (NULL: LinuxCNC's dialect). */
cs_err_t cs_grbl_gc_init(cs_grbl_gc_t *g, const cs_gcode_opts_t *o);
void cs_grbl_gc_free(cs_grbl_gc_t *g);
/* Modal state back to the start, open blocks dropped; position, offsets and parameters kept
 * (what M2/M30 do). With clear_g92, the G92 offsets go too (Grbl's soft reset). */
void cs_grbl_gc_reset_modal(cs_grbl_gc_t *g, bool clear_g92);
/* Reads one line (no newline; client line number lineno for messages). The line's path
 * elements are appended to *out (loc "grbl" line lineno); *end is set by M2/M30. On an error
 * *diag says why (cs_gcode's codes and reasons) and the state is unchanged (an open O-word
 * block is dropped). */
cs_err_t cs_grbl_gc_line(cs_grbl_gc_t *g, const char *line, unsigned lineno, cs_path_t *out,
                         cs_path_diag_t *diag, bool *end);
/* Takes the last line back (its state; the caller drops its elements). False: nothing to undo. */
bool cs_grbl_gc_undo(cs_grbl_gc_t *g);
/* The machine is at mm (a cancelled move, a probe, homing). */
void cs_grbl_gc_set_pos(cs_grbl_gc_t *g, const double mm[3]);
/* Program coordinate of axis a (0..2) in the current units: (pos - off) / unit. */
double cs_grbl_gc_work(const cs_grbl_gc_t *g, int a);
/* Numbered parameter #index of the reader (the offsets for $#: G54 at #5221...). */
double cs_grbl_gc_param(const cs_grbl_gc_t *g, int index);

/* --state FILE: the coordinate systems G54 .. G59.3 and the G28 / G30 homes written as G-code
 * (G10 L2 lines and parameter settings, millimetres) that cs_grbl_gc_load reads back; Grbl keeps
 * the same in its EEPROM. CS_ERR_IO when the file cannot be written. */
cs_err_t cs_grbl_gc_save(const cs_grbl_gc_t *g, const char *path);
/* Reads a --state FILE through the reader (a missing file is no error: nothing stored yet).
 * CS_ERR_IO (unreadable) or the reader's error, with *diag (file:line:col). */
cs_err_t cs_grbl_gc_load(cs_grbl_gc_t *g, const char *path, cs_path_diag_t *diag);

#endif
