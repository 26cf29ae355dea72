/* cs_hershey: Hershey stroke fonts (.jhf, James Hurt's format) for drawing text with a pen: the
 * reader (with located errors for a file that is not a font) and the layout of a string into
 * strokes. Format (one glyph per record, records may wrap at 72 columns): columns 1-5 the glyph
 * number, 6-8 the number of coordinate pairs, then the pairs as two characters each, value =
 * character - 'R'; the first pair is the left and right bearing, " R" lifts the pen; y points
 * down. The glyphs are ASCII 32 .. 32 + n - 1 in file order. Owns the font's vertices. Host only.
 */
#ifndef CS_HERSHEY_H
#define CS_HERSHEY_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_path.h"

/* Glyphs read: ASCII 32..127 at most (a longer file is refused). */
#define CS_HERSHEY_MAX_GLYPHS 96
/* The font's nominal body height in font units (y -16 .. 16): font-size maps onto it. */
#define CS_HERSHEY_BODY 32.0
/* Baseline of the Roman simplex font in font units (y down: capitals span -12 .. 9). */
#define CS_HERSHEY_BASELINE 9.0
/* Cap height of the Roman simplex font, font units (HP-GL SI height maps onto it). */
#define CS_HERSHEY_CAP 21.0

typedef struct {
    signed char x, y; /* font units, y down */
    bool move;        /* the pen lifts before this vertex (starts a stroke) */
} cs_hershey_vertex_t;

typedef struct {
    int left, right; /* bearings: the glyph spans left .. right (advance = right - left) */
    size_t first, n; /* its vertices in the font's array */
} cs_hershey_glyph_t;

typedef struct {
    cs_hershey_glyph_t glyph[CS_HERSHEY_MAX_GLYPHS];
    size_t nglyphs;
    cs_hershey_vertex_t *v;
    size_t nv;
} cs_hershey_font_t;

/* Reads buf[0..len) named name. CS_OK, or CS_ERR_PARSE with *diag "name:line:col: reason" (a
 * record that is not "number, count, pairs": a file that is not a Hershey font), CS_ERR_FULL. */
cs_err_t cs_hershey_parse(const char *name, const char *buf, size_t len, cs_hershey_font_t *f,
                          cs_path_diag_t *diag);
/* Reads file (CS_ERR_IO when it cannot be read), then cs_hershey_parse. */
cs_err_t cs_hershey_load(const char *file, cs_hershey_font_t *f, cs_path_diag_t *diag);
void cs_hershey_free(cs_hershey_font_t *f);
/* The shipped default font: share/fonts/futural.jhf one or two folders above the program's (a
 * build tree: build/curvestep or build/asan/curvestep -> share/fonts) or
 * share/curvestep/fonts/futural.jhf (an install: bin -> share), written to out. false when none
 * exists. */
bool cs_hershey_default_path(char *out, size_t outlen);

/* Receives each vertex of laid-out text: (x, y) in the caller's space, move = pen lifts first. */
typedef cs_err_t (*cs_hershey_emit_fn)(void *ctx, double x, double y, bool move);
/* Width of s[0..n) in font units (sum of advances; characters outside the font count as '?'
 * when the font has it, else as a space). */
double cs_hershey_width(const cs_hershey_font_t *f, const char *s, size_t n);
/* Lays out s[0..n) from pen position (x, y) on the baseline: font point (gx, gy) of a glyph at
 * advance a becomes (x + sx * (a + gx - left), y + sy * (gy - CS_HERSHEY_BASELINE)) (sy < 0 for
 * a y-up space). Stops at the first error of emit. */
cs_err_t cs_hershey_layout(const cs_hershey_font_t *f, const char *s, size_t n, double x, double y,
                           double sx, double sy, cs_hershey_emit_fn emit, void *ctx);

#endif
