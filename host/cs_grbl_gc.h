/* cs_grbl_gc: G-code one line at a time for the Grbl front end (`curvestep grbl`). cs_gcode reads
 * a whole program; this module keeps the modal state a sender builds up line by line (position,
 * G92 offsets, units, distance modes, plane, motion mode, feed) and feeds each line to cs_gcode
 * behind a short preamble that recreates that state, keeping only the line's own elements. Lines
 * of a G5.2 ... G5.3 NURBS block are held and read together at the G5.3. Host only. */
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
    double pos[3];   /* machine position after the last line, mm */
    double off[3];   /* G92 offsets: program coordinate = machine - off, mm */
    bool inch;       /* G20 */
    bool incr;       /* G91 */
    bool ijk_abs;    /* G90.1 */
    int plane;       /* 17, 18, 19 */
    int motion;      /* G word x10 of the motion mode (0, 10, 20, 30, 50, 51), -1: none */
    double feed;     /* F in program units per minute, 0: none given */
    char *block;     /* lines of an open G5.2 block, '\n'-separated (NULL: none open) */
    size_t block_len, block_lines;
} cs_grbl_gc_t;

/* Program start: position 0, no offsets, G21 G90 G91.1 G17, no motion mode, no feed. */
void cs_grbl_gc_init(cs_grbl_gc_t *g);
/* Frees the held block. */
void cs_grbl_gc_free(cs_grbl_gc_t *g);
/* Modal state back to the start (units, distance modes, plane, motion, feed; an open block
 * dropped); position and offsets are kept (what M2/M30 do, and what a soft reset does before
 * it clears the offsets itself). */
void cs_grbl_gc_reset_modal(cs_grbl_gc_t *g);
/* Reads one line (no newline; client line number lineno for messages). The line's path
 * elements are appended to *out (loc "grbl" line lineno); *end is set by M2/M30. On an error
 * *diag says why (cs_gcode's codes and reasons) and the state is unchanged, but for an open
 * G5.2 block: refused with its G5.3 line, it is dropped. */
cs_err_t cs_grbl_gc_line(cs_grbl_gc_t *g, const char *line, unsigned lineno, cs_path_t *out,
                         cs_path_diag_t *diag, bool *end);
/* Program coordinate of axis a (0..2) in the current units: (pos - off) / unit. */
double cs_grbl_gc_work(const cs_grbl_gc_t *g, int a);

#endif
