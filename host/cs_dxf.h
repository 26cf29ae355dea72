/* cs_dxf: reads AutoCAD DXF drawings (ASCII, any release R12..R2018) into a cs_path_t. Owns the
 * group-code lexer (code line / value line pairs, LF or CRLF), the HEADER's $INSUNITS, the LAYER
 * table (a layer that is off or frozen is not drawn), the BLOCKS section and its INSERTs (scale,
 * rotation, column/row arrays, nested to CS_DXF_MAX_DEPTH), the object coordinate systems
 * (extrusion 210/220/230: (0,0,-1) mirrors x; any other normal is projected onto XY), and the
 * geometry of LINE, ARC, CIRCLE, ELLIPSE (exact rational pieces, cs_arc_build), LWPOLYLINE and
 * POLYLINE (bulges as exact arcs), SPLINE (cs_gnurbs -> the core's cs_nurbs; fit points only:
 * cs_spline), TEXT/MTEXT/ATTRIB (Hershey stroke font), DIMENSION (its block), LEADER, and
 * SOLID/TRACE/3DFACE as outlines; the rest is skipped with one warning per kind saying what the
 * drawing loses. Everything is drawn as seen from above: z is dropped. Y points up, as in the
 * machine frame. See docs/inputs.md "## DXF". */
#ifndef CS_DXF_H
#define CS_DXF_H

#include <stddef.h>

#include "cs_hershey.h"
#include "cs_path.h"

/* Deepest nesting of INSERTs (a block inserting a block ...); deeper is CS_ERR_RANGE. */
#define CS_DXF_MAX_DEPTH 16
/* Most entities drawn from blocks in one file (arrays of arrays multiply): beyond it the file is
 * refused (CS_ERR_RANGE) rather than read for minutes. */
#define CS_DXF_MAX_VISITS 4000000ull
/* Largest INSERT array, columns x rows (AutoCAD's own limit is 32767 each). */
#define CS_DXF_MAX_ARRAY 32767

/* Receives each warning (code CS_OK, loc and reason filled). */
typedef void (*cs_dxf_warn_fn)(void *ctx, const cs_path_diag_t *w);

typedef struct {
    cs_dxf_warn_fn warn; /* NULL: "file:line:col: warning: reason" on stderr */
    void *warn_ctx;
    const cs_hershey_font_t *font; /* stroke font for TEXT/MTEXT/ATTRIB; NULL: skipped (warned) */
    double unit_mm; /* > 0: millimetres per drawing unit, overriding $INSUNITS (--units) */
} cs_dxf_opts_t;

/* Defaults: warnings to stderr, no font, units from the file. */
void cs_dxf_opts_init(cs_dxf_opts_t *o);

/* True when buf[0..len) starts like a DXF file: after any 999 comment pairs (LibreCAD writes
 * one), group code 0 then SECTION, blanks around each allowed; or the binary DXF sentinel. For
 * content detection of stdin and unknown names. */
bool cs_dxf_is(const char *buf, size_t len);

/* Parses the DXF text buf[0..len) (need not be NUL-terminated) named name and appends the drawn
 * geometry of model space (ENTITIES, and the blocks they insert) to *path, in mm; each entity
 * starts a new subpath. opts may be NULL. Returns CS_OK, or on the first error fills *diag
 * ("file:line:col: reason") and returns CS_ERR_PARSE (syntax: a group code that is no integer, a
 * value that is no number, binary DXF), CS_ERR_RANGE (a point outside +/-4096 mm, nesting
 * deeper than CS_DXF_MAX_DEPTH or recursive, too many entities), CS_ERR_FULL (out of memory),
 * or a curve builder's error; elements read before the error stay in *path (the caller discards
 * them). Reentrant; host only. */
cs_err_t cs_dxf_read(const char *name, const char *buf, size_t len, const cs_dxf_opts_t *opts,
                     cs_path_t *path, cs_path_diag_t *diag);

#endif
