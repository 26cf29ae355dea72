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
} cs_finish_stats_t;

/* Ball-end finishing of patch p: R = r_mm (> 0), scallop h_mm (0 < h < R), chord tolerance tol
 * (cs_pos_t LSB, >= CS_TRACE_TOL_MIN). Passes at v = 0, ..., 1; the step in v starts from the
 * flat-surface step-over w = 2 sqrt(2 R h - h^2) for h = 0.9 H divided by the largest |Pv|
 * along the pass, then shrinks (x 0.85) until cs_finish_scallop (17 x 8 samples) between the
 * two passes is below 0.9 H. Chords: each pass is bisected in u until the offset curve at the
 * quarter points of every piece is within tol / 2 of its chord (at least 8 pieces); the check
 * samples, the tests measure densely. St accumulates (set min_radius to HUGE_VAL and the rest
 * to 0 before the first patch); curvature is surveyed on a 9 x 9 grid. CS_ERR_DEGENERATE when a
 * normal is undefined (cs_patch_normal), CS_ERR_RANGE when an offset point leaves the
 * coordinate range, CS_ERR_FULL when emit returns false, CS_ERR_DEPTH when a pass needs more
 * than 2^20 chords. */
cs_err_t cs_finish_patch(const cs_patch_t *p, double r_mm, double h_mm, cs_pos_t tol,
                         cs_finish_emit_fn emit, void *ctx, cs_finish_stats_t *st);
/* Measured scallop (mm) left between the passes at v1 and v2 by a ball of radius r_mm: the
 * largest, over nu x ns surface points S = P(u, v1 + s (v2 - v1)), of the distance along the
 * normal from S to the first ball (centred at P + R N on either pass, at the same u) the normal
 * line meets; HUGE_VAL when some S is under neither ball. Double precision. */
double cs_finish_scallop(const cs_patch_t *p, double r_mm, double v1, double v2, int nu, int ns);
/* Double-precision point, derivatives and unit normal of p at (u, v), mm (either array may be
 * NULL): the reference the planner and the tests use. false when Pu x Pv vanishes. */
bool cs_finish_eval(const cs_patch_t *p, double u, double v, double pt[3], double n[3]);

#endif
