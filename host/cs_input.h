/* cs_input: the one input loader every command that takes FILE uses. Reads the whole file (or
 * standard input) first, picks the reader by extension or, for other names and stdin, by
 * content, and runs it: SVG documents and bare SVG path data (cs_svgdoc), G-code (cs_gcode),
 * HP-GL (cs_hpgl), DXF (cs_dxf), curves files (cs_curvefile). A job is parsed whole before anything is sent. */
#ifndef CS_INPUT_H
#define CS_INPUT_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_path.h"

typedef enum {
    CS_INPUT_AUTO = 0, /* by extension, then by content */
    CS_INPUT_SVG = 1,  /* SVG document or bare SVG path data */
    CS_INPUT_GCODE = 2,
    CS_INPUT_HPGL = 3,
    CS_INPUT_CURVES = 4, /* curvestep's curves file (cs_curvefile) */
    CS_INPUT_DXF = 5,    /* AutoCAD DXF, ASCII (cs_dxf) */
} cs_input_format_t;

/* G-code dialect (--dialect): whose modal defaults, words and error behaviour apply
 * (docs/inputs.md lists each difference). */
typedef enum {
    CS_DIALECT_LINUXCNC = 0, /* the default: LinuxCNC's G-code reference */
    CS_DIALECT_GRBL = 1,     /* Grbl 1.1 */
} cs_dialect_t;

/* Units a program starts in (--units) until it says G20 or G21. */
typedef enum {
    CS_UNITS_DEFAULT = 0, /* the dialect's own: millimetres */
    CS_UNITS_MM = 1,
    CS_UNITS_INCH = 2,
} cs_units_t;

/* Receives each warning of any reader (code CS_OK, loc and reason filled). */
typedef void (*cs_input_warn_fn)(void *ctx, const cs_path_diag_t *w);

typedef struct {
    cs_input_format_t format; /* CS_INPUT_AUTO unless the caller knows better */
    bool lenient;             /* G-code: unsupported words are warnings, not errors */
    double helix_tol_mm;      /* G-code helices (default CS_GCODE_HELIX_TOL_MM) */
    bool pen_z; /* G-code M3/M4/M5 also move Z (cs_gcode_opts_t); plan/stream: [pen] mode = z */
    double pen_down_z_mm, pen_up_z_mm;
    double pen_z_feed_mm_s; /* the pen's Z moves' speed ([pen] z_feed), mm/s; 0: rapid */
    cs_dialect_t dialect;  /* --dialect (G-code) */
    cs_units_t units;      /* --units (G-code: start units; DXF: overrides $INSUNITS) */
    const char *font_file; /* --font: stroke font for SVG <text> and HP-GL LB; NULL: default */
    size_t max_bytes;      /* input size limit in bytes; 0: the default (docs/inputs.md) */
    cs_input_format_t
        *detected;         /* non-NULL: receives the reader used (cs_pen: G-code lifts itself) */
    bool regular_only;     /* refuse FIFOs, devices, directories (the daemon; cs_readall) */
    cs_input_warn_fn warn; /* NULL: "file:line:col: warning: reason" on stderr */
    void *warn_ctx;
} cs_input_opts_t;

/* Auto format, strict, default helix tolerance, warnings to stderr. */
void cs_input_opts_init(cs_input_opts_t *o);

/* The reader for filename (may be NULL or "-") holding buf[0..len): by extension (.svg; .txt
 * and .d = bare path data -> SVG; .nc .gcode .ngc .g .tap .cnc -> G-code; .plt .hpgl .hgl .hpg
 * -> HP-GL; .dxf -> DXF; .curves -> curves file; any case), else by content (a first token
 * "curvestep-curves" is a curves file, "0" then "SECTION" DXF; the rest: docs/inputs.md). Never
 * CS_INPUT_AUTO. */
cs_input_format_t cs_input_detect(const char *filename, const char *buf, size_t len);

/* Short name of a format ("svg", "gcode", "hpgl", "curves", "dxf", "auto"). */
const char *cs_input_format_name(cs_input_format_t f);

/* Parses buf[0..len) named name (for diagnostics) as format f (CS_INPUT_AUTO: detected from
 * name and content) into *path. Errors as the reader's, with *diag "file:line:col: reason";
 * CS_ERR_EMPTY "no drawable geometry" when the input adds no element (empty, a BOM, comments);
 * CS_ERR_RANGE past CS_PATH_MAX_ELEMS elements. */
cs_err_t cs_input_parse(const char *name, const char *buf, size_t len, const cs_input_opts_t *o,
                        cs_path_t *path, cs_path_diag_t *diag);

/* Reads filename ("-" = standard input, named "<stdin>" in diagnostics) whole, then
 * cs_input_parse. CS_ERR_IO when it cannot be read; otherwise the reader's result. On error the
 * path may hold part of the input: the caller discards it and sends nothing. */
cs_err_t cs_input_load(const char *filename, const cs_input_opts_t *o, cs_path_t *path,
                       cs_path_diag_t *diag);

#endif
