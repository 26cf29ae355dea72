/* cs_svgpath: the SVG path data grammar (SVG 1.1 §8.3 and implementation notes F.6): turns a
 * 'd' attribute into cs_path_t elements. M L H V C S Q T A Z, absolute and relative, implicit
 * repeated commands, every legal number form, S/T reflection; arcs are converted from endpoint
 * to centre form in double (F.6.5, radii scaled up per F.6.6) then built by cs_arc_build.
 * Errors point at the offending character as file:line:col. */
#ifndef CS_SVGPATH_H
#define CS_SVGPATH_H

#include <stddef.h>

#include "cs_path.h"

/* Maps a byte offset inside the path data to a 1-based line and column of the source file
 * (the SVG document reader supplies one that points into the attribute in the file). */
typedef void (*cs_svgpath_locate_fn)(void *ctx, size_t offset, unsigned *line, unsigned *col);

typedef struct {
    const char *file;            /* name used in diagnostics and element locations */
    cs_path_affine_t xform;      /* user units -> mm, applied in double before conversion */
    cs_svgpath_locate_fn locate; /* NULL: lines and columns counted inside the data itself */
    void *locate_ctx;
} cs_svgpath_opts_t;

/* Defaults: the given file name, identity transform, positions counted within the data. */
void cs_svgpath_opts_init(cs_svgpath_opts_t *o, const char *file);

/* Parses len bytes of path data d (need not be NUL-terminated) and appends its elements to
 * *path; every moveto starts a new subpath. Returns CS_OK, or on the first error fills *diag and
 * returns: CS_ERR_PARSE (grammar), CS_ERR_RANGE (a point outside +/-4096 mm after the transform,
 * or a number too large for a double), CS_ERR_FULL (out of memory), or cs_arc_build's error.
 * Elements parsed before an error stay in *path. Empty data (or only white space) is valid and
 * adds nothing. Reentrant: no state outside its arguments. */
cs_err_t cs_svgpath_parse(const char *d, size_t len, const cs_svgpath_opts_t *o, cs_path_t *path,
                          cs_path_diag_t *diag);

/* Scans one SVG number (sign? (digits ('.' digits?)? | '.' digits) ([eE] sign? digits)?) at
 * s[0..len) and returns how many bytes it spans, with its value in *out (which may be +/-inf
 * for absurdly large numbers: check isfinite). Returns 0 when s does not start with a valid
 * number; *bad (may be NULL) then gets the offset of the offending character. */
size_t cs_svgpath_scan_number(const char *s, size_t len, double *out, size_t *bad);

#endif
