/* cs_svgout: writes an SVG picture of a flattening for people to look at: the exact curves (as
 * SVG path data from the Béziers; rational and high-degree ones as dense polylines) in one
 * colour, the emitted chords and their vertices (dots) in another, a legend and a scale bar,
 * with the viewBox fitted to the drawing (1 user unit = 1 mm), y up as the machine's frame. */
#ifndef CS_SVGOUT_H
#define CS_SVGOUT_H

#include <stdio.h>

#include "cs_path.h"

typedef struct {
    const char *title;  /* first legend line (e.g. the input's name); NULL: none */
    const char *method; /* tracing method named in the legend; NULL: not shown */
    double tol_mm;      /* tolerance shown in the legend when > 0 */
    double max_dev_mm;  /* measured deviation shown in the legend when >= 0 */
} cs_svgout_opts_t;

/* Title NULL, method NULL, tol 0, deviation -1 (nothing optional shown). */
void cs_svgout_opts_init(cs_svgout_opts_t *o);
/* Writes the picture of curves (may be empty) and chords (may be NULL or empty) to f.
 * CS_ERR_IO when writing fails; CS_ERR_EMPTY when there is nothing at all to draw (a picture
 * with a legend only is still written). */
cs_err_t cs_svgout_fprint(FILE *f, const cs_path_t *curves, const cs_path_poly_t *chords,
                          const cs_svgout_opts_t *o);
/* Same, to a new file at filename; CS_ERR_IO with *diag ("file:0:0: reason") on failure. */
cs_err_t cs_svgout_write(const char *filename, const cs_path_t *curves,
                         const cs_path_poly_t *chords, const cs_svgout_opts_t *o,
                         cs_path_diag_t *diag);

#endif
