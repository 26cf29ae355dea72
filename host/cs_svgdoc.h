/* cs_svgdoc: reads an SVG document with expat into a cs_path_t: <path> data (through
 * cs_svgpath) and the basic shapes (rect with rounded corners, circle, ellipse, line, polyline,
 * polygon) as their SVG 1.1 equivalent paths, with every transform composed down the tree, the
 * root's width/height/viewBox/preserveAspectRatio (and nested <svg> viewports) mapped to mm,
 * <use> of any element, <g>, <symbol> or <svg> by '#id' (forward references too: the document
 * is read whole into a tree first, then walked), and the display/visibility/stroke/fill
 * properties (attributes, <style> sheets through cs_css, style="") deciding what is drawn:
 * fills are drawn as outlines. Errors point at the character inside the attribute in the file.
 * Also reads bare path data (a file holding only a 'd' value). See docs/inputs.md. */
#ifndef CS_SVGDOC_H
#define CS_SVGDOC_H

#include <stddef.h>

#include "cs_hershey.h"
#include "cs_path.h"

/* <use> inside the instances of <use> deeper than this: a warning, not drawn. */
#define CS_SVGDOC_MAX_USE_DEPTH 32
/* Elements drawn through <use> in one document, at most (nested uses multiply: a few bytes of
 * SVG could ask for billions): past it, CS_ERR_RANGE. */
#define CS_SVGDOC_MAX_USE_ELEMENTS 1000000u

/* Receives each warning (code CS_OK, loc and reason filled). */
typedef void (*cs_svgdoc_warn_fn)(void *ctx, const cs_path_diag_t *w);

typedef struct {
    cs_path_affine_t xform; /* applied after the document's own transforms (user units -> mm) */
    const cs_hershey_font_t *font; /* stroke font for <text> (cs_hershey); NULL: text ignored */
    cs_svgdoc_warn_fn warn;        /* NULL: "file:line:col: warning: reason" on stderr */
    void *warn_ctx;
} cs_svgdoc_opts_t;

/* What a read found (for --stats and tests). */
typedef struct {
    unsigned paths;    /* <path> elements read (with or without a 'd' attribute) */
    unsigned shapes;   /* basic shapes read: rect, circle, ellipse, line, polyline, polygon */
    unsigned ignored;  /* elements not drawn: text without a font, image, display="none", no
                          stroke and no fill, visibility hidden, paths and shapes inside <defs>
                          and the like (where they stand), <use> refused (missing, cycle...) */
    unsigned uses;     /* <use> instances drawn */
    unsigned warnings; /* warnings issued (each kind once per document) */
} cs_svgdoc_stats_t;

/* Identity transform, warnings to stderr. */
void cs_svgdoc_opts_init(cs_svgdoc_opts_t *o);

/* Reads the whole of filename ("-" = standard input) into a NUL-terminated heap buffer (*buf,
 * free() it; *len excludes the NUL): cs_readall with the default size limit. CS_ERR_IO (or
 * CS_ERR_RANGE past the limit) with *diag ("file:0:0: reason") on failure. */
cs_err_t cs_svgdoc_load(const char *filename, char **buf, size_t *len, cs_path_diag_t *diag);

/* Parses an SVG document held in buf[0..len) named name; appends every drawn path's and shape's
 * elements to *path (every moveto and every shape starts a subpath). CS_ERR_PARSE for XML
 * errors, path-data errors and bad attribute values (lengths, viewBox, preserveAspectRatio,
 * points, transform, negative sizes), CS_ERR_RANGE for points outside +/-4096 mm, CS_ERR_FULL
 * when out of memory (all with *diag). stats may be NULL. */
cs_err_t cs_svgdoc_parse(const char *buf, size_t len, const char *name, const cs_svgdoc_opts_t *o,
                         cs_path_t *path, cs_path_diag_t *diag, cs_svgdoc_stats_t *stats);

/* Either kind of input: an SVG document when the first non-blank character is '<' (path data
 * never starts with one), else bare path data with o->xform applied. Same results as above. */
cs_err_t cs_svgdoc_read(const char *buf, size_t len, const char *name, const cs_svgdoc_opts_t *o,
                        cs_path_t *path, cs_path_diag_t *diag, cs_svgdoc_stats_t *stats);

/* cs_svgdoc_load then cs_svgdoc_read; the name in diagnostics is filename ("<stdin>" for "-"). */
cs_err_t cs_svgdoc_read_file(const char *filename, const cs_svgdoc_opts_t *o, cs_path_t *path,
                             cs_path_diag_t *diag, cs_svgdoc_stats_t *stats);

/* Parses an SVG transform list (SVG 1.1 §7.6: matrix, translate, scale, rotate, skewX, skewY)
 * in s[0..len) into *out (identity for an empty list). CS_ERR_PARSE with *bad = offset of the
 * offending character and *why (static text) set; *out untouched then. */
cs_err_t cs_svgdoc_parse_transform(const char *s, size_t len, cs_path_affine_t *out, size_t *bad,
                                   const char **why);

#endif
