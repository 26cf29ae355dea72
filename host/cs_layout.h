/* cs_layout: where a drawing goes on the machine, applied to the path before planning (the
 * options --scale, --fit, --page, --margin, --translate, --rotate, --flip-y of every command that
 * reads a job; docs/plotting.md, "Layout"). Owns the layout options, the one affine map they make
 * and its exact application to every control point of a path (lines, Béziers, rational arcs:
 * an affine map of a Bézier is the Bézier of the mapped control points with the same weights),
 * so the chord tolerance still holds in output millimetres. Host only. */
#ifndef CS_LAYOUT_H
#define CS_LAYOUT_H

#include <stdbool.h>

#include "cs_path.h"

/* Largest --scale factor and smallest (a typo guard; coordinates stay within +/-4096 mm). */
#define CS_LAYOUT_SCALE_MAX 10000.0
#define CS_LAYOUT_SCALE_MIN 1e-4

typedef struct {
    double scale;     /* --scale F (> 0); 1 = as drawn */
    bool fit;         /* --fit: bounding box to the area (machine travel or page) */
    double page_w_mm; /* --page: area 0..W x 0..H mm (0: the machine's travel) */
    double page_h_mm;
    double margin_mm;    /* --margin: kept free on every side of the area when fitting */
    double tx_mm, ty_mm; /* --translate X,Y, applied last */
    int rotate_deg;      /* --rotate: 0, 90, 180 or 270, counter-clockwise */
    bool flip_y;         /* --flip-y: mirror top to bottom (after the SVG page turn) */
} cs_layout_opts_t;

/* The area --fit fills, in machine mm (the travel of x and y, or the page at the origin). */
typedef struct {
    double min[2], max[2];
} cs_layout_area_t;

/* Scale 1, nothing else. */
void cs_layout_opts_init(cs_layout_opts_t *o);
/* True when o changes nothing (and the path has no y-down page to turn). */
bool cs_layout_is_identity(const cs_layout_opts_t *o, const cs_path_t *p);
/* Parses a page: A3, A4, A5, letter (any case; portrait) or WxH with an optional "mm"
 * ("297x210mm"). False for anything else or a side outside (0, 4096] mm. */
bool cs_layout_parse_page(const char *s, double *w_mm, double *h_mm);

/* Drawn extent of p in x and y, mm: the union of cs_bezier_bbox of every element (tight at the
 * extrema of lines, quadratics and cubics; rational arcs by their control hull). False when p
 * has no element. */
bool cs_layout_bbox(const cs_path_t *p, double min[2], double max[2]);

/* The map o makes for a drawing whose box is min..max (after the SVG page turn), into area:
 * flip-y about the box's middle, rotate about the box keeping its lower-left corner, then scale
 * about the origin (or, with fit, scale and centre the box in area less the margin, keeping
 * aspect), then translate. CS_ERR_ARG when fit has no room (margin too large, empty box). */
cs_err_t cs_layout_map(const cs_layout_opts_t *o, const double min[2], const double max[2],
                       const cs_layout_area_t *area, cs_path_affine_t *out);

/* Applies m to every control point of every element (x, y; z kept), rounding each once to the
 * LSB. CS_ERR_RANGE (diag located at the element) when a point leaves +/-4096 mm. */
cs_err_t cs_layout_transform(cs_path_t *p, const cs_path_affine_t *m, cs_path_diag_t *diag);

/* The whole layout of p: the SVG page turn (an SVG document's y-down page turned to the
 * machine's y-up frame, y' = page height - y, so it looks as a browser shows it), then
 * cs_layout_map / cs_layout_transform. CS_OK, or an error with diag filled. */
cs_err_t cs_layout_apply(const cs_layout_opts_t *o, const cs_layout_area_t *area, cs_path_t *p,
                         cs_path_diag_t *diag);

#endif
