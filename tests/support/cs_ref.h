/* cs_ref: the one double-precision reference of the project, used by every test and benchmark
 * that checks a traced curve. Evaluates a cs_bezier_t (polynomial or rational) in double, measures
 * how far a polyline strays from the exact curve (both ways, per chord), and counts the chords of
 * a greedy reference flattening. Host/tests only (uses double and libm). */
#ifndef CS_REF_H
#define CS_REF_H

#include <stddef.h>

#include "cs_bezier.h"

typedef struct {
    double x, y, z;
} cs_ref_vec_t;

/* One LSB of cs_pos_t in millimetres (2^-16 mm). */
#define CS_REF_LSB_MM (1.0 / 65536.0)

/* A cs_pos_t point in millimetres. */
cs_ref_vec_t cs_ref_from_pos(const cs_vec3_t *p);
/* Curve point at t in [0, 1], in mm (rational curves by homogeneous de Casteljau). */
cs_ref_vec_t cs_ref_eval(const cs_bezier_t *c, double t);
/* Euclidean distance |a - b| (mm). */
double cs_ref_dist(cs_ref_vec_t a, cs_ref_vec_t b);
/* Distance from p to the segment [a, b] (to a when a == b), mm. */
double cs_ref_dist_point_segment(cs_ref_vec_t p, cs_ref_vec_t a, cs_ref_vec_t b);
/* Largest distance (mm) between the chord a-b and the curve piece t in [t0, t1], both ways: every
 * piece point to the chord (dense sampling plus golden-section refinement of the maximum) and
 * every chord point to the piece (to a 32-point polyline through the piece, within about
 * 1/1000 of the piece's sag of the curve). */
double cs_ref_chord_piece_deviation(const cs_bezier_t *c, double t0, double t1, cs_ref_vec_t a,
                                    cs_ref_vec_t b);
/* Largest deviation (mm) between the polyline P0, v[0] .. v[n-1] and the curve: each vertex is
 * placed on the curve (first parameter after the previous vertex within 2 LSB of it; the last
 * vertex at t = 1), then each chord is measured against its piece with
 * cs_ref_chord_piece_deviation. Returns HUGE_VAL when a vertex is not on the curve (more than
 * 2 LSB away from every point after the previous vertex). */
double cs_ref_max_deviation(const cs_bezier_t *c, const cs_vec3_t *v, size_t n);
/* Largest distance (mm) from a vertex to the curve point at the parameter cs_ref_max_deviation
 * assigns it (HUGE_VAL if a vertex cannot be placed). */
double cs_ref_max_vertex_error(const cs_bezier_t *c, const cs_vec3_t *v, size_t n);
/* Both measures above with one placement of the vertices (either output may be NULL). */
void cs_ref_measure(const cs_bezier_t *c, const cs_vec3_t *v, size_t n, double *max_dev,
                    double *max_vertex_err);
/* Greedy reference chord count for tolerance tol (mm): from each vertex, the longest chord (largest
 * t found by bisection on t, 40 steps) whose deviation stays within tol, in double. */
size_t cs_ref_greedy_count(const cs_bezier_t *c, double tol);
/* True when every control point of c lies on the line y = P0.y (a collinear fold). */
bool cs_ref_collinear_x(const cs_bezier_t *c);
/* Largest distance (mm) of v[0..n-1] from such a curve, exact: the curve covers the x range
 * between its extremes, so it is the distance to that segment (cs_ref_measure's placement may
 * put a vertex of the returning branch on the outgoing one). */
double cs_ref_fold_vertex_error(const cs_bezier_t *c, const cs_vec3_t *verts, size_t n);

#endif
