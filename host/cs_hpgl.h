/* cs_hpgl: reads HP-GL and HP-GL/2 plotter files into a cs_path_t. Owns the instruction
 * lexer (two-letter mnemonics, ';' or the next mnemonic as terminator, commas/blanks between
 * parameters), the plotter state (pen up/down, absolute/relative, pen number, label terminator,
 * scaling SC IP IR, rotation RO, plot size PS, clipping window IW) and the geometry of IN PU PD
 * PA PR SP CI AA AR BZ BR PE, mapped exactly (affine map of the control points) from user units
 * to the paper; everything else is skipped with one warning per mnemonic. Plotter units are 0.025 mm (40 per mm); Y points up, as on the plotter
 * and in the machine frame, so no axis is flipped. See docs/inputs.md "## HPGL". */
#ifndef CS_HPGL_H
#define CS_HPGL_H

#include <stddef.h>

#include "cs_hershey.h"
#include "cs_path.h"

/* Plotter units per millimetre (1 plu = 0.025 mm). */
#define CS_HPGL_PLU_PER_MM 40.0
/* The picture frame until PS says otherwise: ISO A4 landscape, 297 x 210 mm in plotter units.
 * P1/P2 default to its corners; RO turns about it; IR is relative to it. */
#define CS_HPGL_FRAME_W 11880.0
#define CS_HPGL_FRAME_H 8400.0

/* Receives each warning (code CS_OK, loc and reason filled). */
typedef void (*cs_hpgl_warn_fn)(void *ctx, const cs_path_diag_t *w);

typedef struct {
    cs_hpgl_warn_fn warn; /* NULL: "file:line:col: warning: reason" on stderr */
    const cs_hershey_font_t *font; /* stroke font for LB labels (cs_hershey); NULL: skipped */
    void *warn_ctx;
} cs_hpgl_opts_t;

/* Defaults: warnings to stderr. */
void cs_hpgl_opts_init(cs_hpgl_opts_t *o);

/* Parses the HP-GL text buf[0..len) (need not be NUL-terminated) named name and appends its
 * drawn geometry to *path: pen-down moves as lines, CI/AA/AR as exact arcs (cs_arc_build),
 * BZ/BR as cubics; each pen lift or pen change starts a new subpath. opts may be NULL.
 * Returns CS_OK, or on the first error fills *diag ("file:line:col: reason") and returns
 * CS_ERR_PARSE (syntax), CS_ERR_RANGE (a point outside +/-4096 mm), CS_ERR_FULL (out of memory)
 * or an arc builder error; elements read before the error stay in *path (the caller discards
 * them: nothing is sent on error). Reentrant; host only. */
cs_err_t cs_hpgl_read(const char *name, const char *buf, size_t len, const cs_hpgl_opts_t *opts,
                      cs_path_t *path, cs_path_diag_t *diag);

#endif
