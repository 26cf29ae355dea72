/* cs_path: the host-side path model every command shares. A path is a growable list of
 * elements, each one cs_bezier_t (lines are degree 1, SVG/G-code arcs the rational quadratics of
 * cs_arc_build, quadratic and cubic Béziers) with its source location and subpath index.
 * Also owns what goes with it on the host: affine transforms (applied in double before
 * conversion), diagnostics "file:line:col: reason", double evaluation, and chord polylines. */
#ifndef CS_PATH_H
#define CS_PATH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "cs_bezier.h"

/* What an element was written as in its source (the curve itself is always a cs_bezier_t). */
typedef enum {
    CS_PATH_LINE = 0,  /* degree 1 */
    CS_PATH_QUAD = 1,  /* quadratic Bézier (SVG Q/T) */
    CS_PATH_CUBIC = 2, /* cubic Bézier (SVG C/S) */
    CS_PATH_ARC = 3,   /* one piece (<= 90 degrees) of a circular/elliptical arc, rational */
    CS_PATH_OTHER = 4, /* any other curve converted to Bézier form */
    /* The curves file's bases (cs_curvefile), each converted to Bézier segments: */
    CS_PATH_BEZIER = 5,      /* a Bézier of any degree 1..7 */
    CS_PATH_HERMITE = 6,     /* cubic Hermite (points and tangents) */
    CS_PATH_BSPLINE = 7,     /* uniform cubic or non-uniform B-spline */
    CS_PATH_NURBS = 8,       /* rational B-spline */
    CS_PATH_CATMULL_ROM = 9, /* Catmull-Rom spline */
    CS_PATH_BETA = 10,       /* Barsky beta-spline */
    CS_PATH_NATURAL = 11,    /* natural cubic spline */
} cs_path_kind_t;

/* The kind's name as the curves file spells it ("line", "quad", "cubic", "arc", "other",
 * "bezier", "hermite", ...); "?" for a value outside the enum. */
const char *cs_path_kind_name(cs_path_kind_t k);

/* A place in an input file: 1-based line and column (columns count characters, a tab is 1).
 * file points to a name owned by the cs_path_t (or a static string); never NULL. */
typedef struct {
    const char *file;
    unsigned line, col;
} cs_path_loc_t;

typedef struct {
    cs_bezier_t curve;
    cs_path_kind_t kind;
    cs_path_loc_t loc; /* the command (or argument) the element comes from */
    unsigned subpath;  /* 0-based, counts only subpaths that hold at least one element */
    double feed_mm_s;  /* feed for this move in mm/s; 0 = the machine's default (cs_path_add) */
    bool rapid;        /* a travel move (G-code G0): at the machine's rapid rate, not drawn */
    uint8_t spindle;   /* G-code: the spindle / laser in force, 3, 4 or 5 (M3, M4, M5); 0: the
                        * input says nothing about it (SVG, HP-GL, curves) */
    double spindle_s;  /* ... and its S (G-code: spindle speed, laser power) */
} cs_path_elem_t;

/* Most elements a path holds by default: 2^20 (1 M curves, about 190 MB), far above
 * any real job; beyond it cs_path_add is refused (docs/inputs.md, "Limits"). */
#define CS_PATH_MAX_ELEMS ((size_t)1 << 20)

typedef struct {
    cs_path_elem_t *elems;
    size_t n, cap;
    size_t max_elems;       /* 0: CS_PATH_MAX_ELEMS */
    bool over_limit;        /* an element was refused for the limit ... */
    cs_path_loc_t over_loc; /* ... this one */
    char **files; /* interned file names, freed with the path */
    size_t nfiles, capfiles;
    unsigned nsubpaths;
    bool pending_subpath; /* the next element added starts a new subpath */
    double blend_tol_mm;  /* the job's own path tolerance (G-code G64 P, the smallest given), mm;
                           * 0: none. Planning keeps chords within the smaller of it and its own */
    /* An SVG document's page (set by cs_svgdoc): its y axis points down the page, which is
     * page_h_mm high (0: no height given). cs_layout turns it to the machine's y-up frame. */
    bool page_y_down;
    double page_h_mm;
} cs_path_t;

/* Grows the array *buf of elements of sz bytes (capacity *cap, doubled from 16) to hold at
 * least need; false when out of memory (*buf unchanged). The host's one growable-array step. */
bool cs_path_grow(void **buf, size_t *cap, size_t need, size_t sz);
/* Empty path. */
void cs_path_init(cs_path_t *p);
/* Frees every element and interned name; the path is empty (and reusable) afterwards. */
void cs_path_free(cs_path_t *p);
/* Stable copy of name owned by p (the same pointer for the same name), NULL when out of memory. */
const char *cs_path_intern(cs_path_t *p, const char *name);
/* Marks that the next element added starts a new subpath (a pen lift before it). */
void cs_path_new_subpath(cs_path_t *p);
/* Appends curve as a new element of the current subpath. CS_ERR_FULL when out of memory. */
cs_err_t cs_path_add(cs_path_t *p, const cs_bezier_t *curve, cs_path_kind_t kind,
                     cs_path_loc_t loc);
/* cs_path_add with motion attributes: feed in mm/s (0 = machine default), rapid for G0 travel.
 * cs_path_add is this with feed 0 and rapid false. CS_ERR_FULL when out of memory. */
cs_err_t cs_path_add_move(cs_path_t *p, const cs_bezier_t *curve, cs_path_kind_t kind,
                          cs_path_loc_t loc, double feed_mm_s, bool rapid);

/* Copies src into dst (cap bytes, NUL-terminated) with every control character (below 0x20,
 * and 0x7f) written as \xHH: text from input files is safe to print. */
void cs_path_escape(char *dst, size_t cap, const char *src);

/* Affine map of the plane in SVG matrix order: x' = a x + c y + e, y' = b x + d y + f. */
typedef struct {
    double a, b, c, d, e, f;
} cs_path_affine_t;

/* The identity map. */
cs_path_affine_t cs_path_affine_identity(void);
/* m * n: the map that applies n first, then m (SVG nesting order: parent * child). */
cs_path_affine_t cs_path_affine_mul(cs_path_affine_t m, cs_path_affine_t n);
/* Image of the point (x, y). */
void cs_path_affine_point(const cs_path_affine_t *m, double x, double y, double *ox, double *oy);
/* Image of the vector (x, y) (linear part only, no translation). */
void cs_path_affine_vector(const cs_path_affine_t *m, double x, double y, double *ox, double *oy);
/* True when m is exactly the identity. */
bool cs_path_affine_is_identity(const cs_path_affine_t *m);

/* A diagnostic for bad input: code plus "file:line:col: reason". */
typedef struct {
    cs_err_t code;
    cs_path_loc_t loc;
    char reason[256];
} cs_path_diag_t;

/* Fills *d (printf-style reason; control characters in the result are escaped as \xHH, so text
 * quoted from a hostile file cannot drive the terminal). Returns code, so callers can
 * `return cs_path_diag_set(...)`. */
cs_err_t cs_path_diag_set(cs_path_diag_t *d, cs_err_t code, cs_path_loc_t loc, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
/* Prints "file:line:col: reason\n" to f (control characters in the file name escaped). */
void cs_path_diag_print(FILE *f, const cs_path_diag_t *d);
/* Prints "file:line:col: warning: reason\n" to f, escaped as cs_path_diag_print. */
void cs_path_warn_print(FILE *f, const cs_path_diag_t *w);
/* When p refused an element for its limit (CS_PATH_MAX_ELEMS): fills *d with a located
 * CS_ERR_RANGE "more than N curves: the job is too large" and returns true. */
bool cs_path_over_limit(const cs_path_t *p, cs_path_diag_t *d);

/* Point of curve c at t in [0, 1], in mm, evaluated in double by de Casteljau (rational curves
 * in homogeneous coordinates): the exact curve the fixed-point control points describe. */
void cs_path_eval_mm(const cs_bezier_t *c, double t, double out[3]);
/* Largest distance (mm) from the exact curve c to the polyline v[0..n-1] that traces it
 * (v[0] = P0, v[n-1] = P_n, vertices on the curve in order), measured in double: each inner
 * vertex is placed at the first parameter after its predecessor where the curve comes within
 * 2 LSB of it (dense grid, then golden-section refinement), then each chord is measured against
 * its piece of curve (grid maximum, refined). Returns HUGE_VAL when a vertex is not on the curve
 * (no such parameter). Host only: slow and plain, for --stats and checks. */
double cs_path_deviation_mm(const cs_bezier_t *c, const cs_vec3_t *v, size_t n);
/* Box of every element's control points (which contains the curves), in mm. false when empty. */
bool cs_path_bbox_mm(const cs_path_t *p, double min[3], double max[3]);

/* A set of polylines in mm (the chords a tracer emitted), for pictures and checks. */
typedef struct {
    double x, y;
} cs_path_pt_t;

typedef struct {
    cs_path_pt_t *pts;
    size_t n, cap;
    size_t *starts; /* index in pts of each polyline's first vertex */
    size_t nlines, caplines;
} cs_path_poly_t;

/* Empty set. */
void cs_path_poly_init(cs_path_poly_t *s);
/* Frees it; empty and reusable afterwards. */
void cs_path_poly_free(cs_path_poly_t *s);
/* Starts a new polyline whose first vertex is (x, y). CS_ERR_FULL when out of memory. */
cs_err_t cs_path_poly_move(cs_path_poly_t *s, double x, double y);
/* Appends (x, y) to the current polyline (starts one if there is none). CS_ERR_FULL on OOM. */
cs_err_t cs_path_poly_line(cs_path_poly_t *s, double x, double y);
/* Number of vertices of polyline i. */
size_t cs_path_poly_len(const cs_path_poly_t *s, size_t i);

#endif
