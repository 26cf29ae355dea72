/* cs_finish: 3-axis finishing of a bicubic patch with a ball-end tool (issue 5, tool paths).
 * Plans a zig-zag raster of passes along u (iso-curves at fixed v), the tool centre on the
 * offset surface C = P + R N (points and normals from the core, cs_patch_eval/_normal), passes
 * spaced so the measured scallop stays below H, each pass cut into chords within tol of the
 * exact offset curve. Planning (pass spacing, scallop, curvature) is done in double on the host.
 * Host only. */
#ifndef CS_FINISH_H
#define CS_FINISH_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_patch.h"
#include "cs_tripatch.h"

/* Called for every tool-centre vertex of a pass, in cutting order: pass index (0-based within
 * the patch), the parameters (u, v) the vertex sits at, the centre (fixed point) and whether it
 * starts a pass. Returns false to stop (out of memory...). */
typedef bool (*cs_finish_emit_fn)(void *ctx, size_t pass, double u, double v,
                                  const cs_vec3_t *centre, bool pass_start);

typedef struct {
    size_t passes;           /* passes cut */
    size_t vertices;         /* vertices emitted */
    size_t gouge_points;     /* samples whose concave curvature radius is below R */
    size_t undercut;         /* vertices whose normal points down (not reachable from above) */
    double max_scallop;      /* largest scallop measured between neighbouring passes, mm */
    double min_radius;       /* smallest concave curvature radius met, mm (HUGE_VAL if none) */
    double gouge_u, gouge_v; /* where the smallest radius was met */
    size_t folded;           /* chords of the offset path that run against the surface's own
                              * direction (a loop: the offset surface folds over itself where
                              * the concave radius along the pass is below R) */
    double fold_u, fold_v;   /* where the first such chord starts */
    size_t loops_cut;        /* loops cut out of passes at their self-crossing */
} cs_finish_stats_t;

/* Ball-end finishing of patch p: R = r_mm (> 0), scallop h_mm (0 < h < R), chord tolerance tol
 * (cs_pos_t LSB, >= CS_TRACE_TOL_MIN). Passes at v = 0, ..., 1; the step in v starts from the
 * flat-surface step-over w = 2 sqrt(2 R h - h^2) for h = 0.9 H divided by the largest |Pv|
 * along the pass, then shrinks (x 0.85) until cs_finish_scallop (17 x 8 samples) between the
 * two passes is below 0.9 H. Chords: each pass is bisected in u until the offset curve at the
 * quarter points of every piece is within tol / 2 of its chord (at least 8 pieces); the check
 * samples, the tests measure densely. Folds: a chord whose offset step C(u_k+1) - C(u_k) has a
 * negative dot product with the surface step P(u_k+1) - P(u_k) is counted in st->folded; where
 * the pass then crosses itself (two of its chords within tol, a backward chord between them)
 * the loop is cut out at the crossing, a vertex that is not on P + R N (st->loops_cut); loops
 * that do not close within a pass (folds across passes, non-planar sections) remain. St accumulates
 * (set min_radius to HUGE_VAL and the rest to 0 before the first patch); curvature is surveyed on a
 * 9 x 9 grid. CS_ERR_DEGENERATE when a normal is undefined (cs_patch_normal), CS_ERR_RANGE when an
 * offset point leaves the coordinate range, CS_ERR_FULL when emit returns false, CS_ERR_DEPTH when
 * a pass needs more than 2^20 chords. */
cs_err_t cs_finish_patch(const cs_patch_t *p, double r_mm, double h_mm, cs_pos_t tol,
                         cs_finish_emit_fn emit, void *ctx, cs_finish_stats_t *st);
/* Measured scallop (mm) left between the passes at v1 and v2 by a ball of radius r_mm: the
 * largest, over nu x ns surface points S = P(u, v1 + s (v2 - v1)), of the distance along the
 * normal from S to the first ball (centred at P + R N on either pass, at the same u) the normal
 * line meets; HUGE_VAL when some S is under neither ball. Double precision. */
double cs_finish_scallop(const cs_patch_t *p, double r_mm, double v1, double v2, int nu, int ns);
/* A triangular patch T (degree n = 1..3) as the tensor-product patch of degree n x n
 * Q(a, b) = T(u = b, v = (1 - b)(1 - a), w = (1 - b) a): each row b = const is the iso-line
 * u = b, run from the edge w = 0 to the edge v = 0, and the edge b = 1 collapses onto the corner
 * u = 1 (a pole, as at the teapot's lid: cs_patch_normal's limit normal applies). Substituting
 * gives Q(a, b) = sum_i B_i^n(b) sum_j B_j^m(1 - a) S_{i,j,m-j} with m = n - i, so row i is the
 * degree-m curve of the S_{i,j,k} elevated to degree n, reversed (exact rationals with
 * denominators C(n, l), each control point rounded once: within 0.5 LSB). Qa x Qb = (1 - b)
 * Tu x Tv (partials in u, v with w = 1 - u - v): the same surface, the same orientation, so
 * cs_finish_patch(Q) finishes T along its iso-lines u = const. CS_ERR_DEGREE for a bad degree. */
cs_err_t cs_finish_tri_patch(const cs_tripatch_t *t, cs_patch_t *out);
/* Double-precision point, derivatives and unit normal of p at (u, v), mm (either array may be
 * NULL): the reference the planner and the tests use. false when Pu x Pv vanishes. */
bool cs_finish_eval(const cs_patch_t *p, double u, double v, double pt[3], double n[3]);

#endif
