/* cs_dcpath: raster finishing passes over a drop-cutter mesh (issue 20). Owns the passes: each
 * a polyline of tool-tip points (mm) along a line of the raster, sampled adaptively so that the
 * chords stay within tol of the drop-cutter height along the line, and spaced so that the
 * scallop between neighbouring passes, measured across the surface, stays at most H. Host only,
 * double precision.
 *
 * Spacing: the nominal step-over is the flat-ground one (ball 2 sqrt(2RH - H^2); bull-nose
 * 2(R - r) + 2 sqrt(2rH - H^2); flat end mill 2R x 0.9), then every neighbouring pair is checked
 * at cross points (at least 7, no farther apart than the least gap) and every sample of the
 * finer pass: the cutters of the passes within R at the same along-pass position and, for the
 * two passes bounding the gap and the two bounding the axis of a cutter touching the surface
 * there, at every position along the pass within R of the point (the pass's chords: the
 * minimum of a convex function on each, by golden section), leave
 * E = min(z_j(t) + h(hypot(w_j - w, t - s))) above the mesh top S (on ground rising along the
 * passes the cutter at s stands R tan or R (1/cos - 1) above S, its neighbours along the pass
 * do not); the scallop is (E - S) cos(slope) for a ball
 * (its envelope is parallel to the surface), E - S for a flat or bull-nose end (a level bottom).
 * Where it exceeds H - eps - tol / 2 a pass is added in the gap holding the axis of a cutter
 * touching the surface there (r sin(slope) + R - r downhill of the point). A gap narrower than
 * twice the least width (a sixteenth of a ball's flat-ground step) is not split, so gaps end
 * between it and twice it; points whose gap cannot be split (rest material, walls) are
 * reported and flagged for the fill-in (cs_dcpath_fill), not chased. Every value is a cutter
 * of the path, so the estimate at a cross point is never below the envelope (the cross points
 * lie at most the least width apart, and between them it may miss a ball's cusp peak by up to
 * the cusp's slope times half that step, which is not allowed for: on a plane, passes 0.875 mm
 * apart, R 2, it reads 0.0428 mm where the cusp is 0.0484). Points within R of the rim of the
 * surface's projection and on walls (slope > 5) are left out, as in the check (cs_dropcheck.h). */
#ifndef CS_DCPATH_H
#define CS_DCPATH_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_dropcut.h"
#include "cs_surffile.h"

typedef struct {
    double angle_deg;  /* raster direction, degrees from +x (0: passes along x) */
    double scallop_mm; /* H > 0 */
    double step_mm;    /* > 0: fixed step-over (no scallop refinement); 0: from H */
    double tol_mm;     /* chord tolerance along a pass */
    double box[4];     /* x0 y0 x1 y1: the region the tool axis covers */
    double min_z;      /* the floor: the tip never goes lower */
    size_t max_passes; /* refinement stops here (a warning) */
    double max_slope;  /* > 0: the scallop refinement skips ground steeper than this (another
                        * strategy serves it, cs_dccombo.h); 0: only walls (slope > 5) */
} cs_dcpath_opts_t;

typedef struct {
    double (*pt)[3];   /* tip points, mm */
    size_t n, cap;
    size_t *start;     /* pass k is pt[start[k] .. start[k + 1]) */
    double *w;         /* pass k's cross offset, mm */
    size_t npass, pcap;
    double max_left;   /* largest estimated scallop left between passes, mm */
    double max_stuck;  /* largest left where no pass can be added (rest material, walls), mm */
    size_t refined;    /* passes added by the scallop check */
    bool capped;       /* max_passes was reached */
    size_t drops;      /* drop-cutter queries made */
    size_t links;      /* passes joined to the one before at cutting height (cs_dcpath_link) */
    double (*flag)[2]; /* xy (mm) of the points estimated over H where no pass can be added: */
    size_t nflag, flagcap; /* where the fill-in looks (cs_dropcut_cmd.c) */
} cs_dcpath_t;

void cs_dcpath_init(cs_dcpath_t *p);
/* Nominal step-over (mm) of tool t for scallop height h (flat ground). */
double cs_dcpath_step(const cs_dropcut_tool_t *t, double h);
/* Plans the raster of o over mesh ms for tool t into p, passes in cutting order (zig-zag).
 * CS_ERR_FULL out of memory, CS_ERR_RANGE for a region or step that makes no sense. */
cs_err_t cs_dcpath_raster(cs_dcpath_t *p, cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                          const cs_dcpath_opts_t *o);
/* Rest-material fill-in: the check's own measure of the passes (cs_dropcheck_gaps, z-map step
 * step_mm, the ideal cutter keeping the mesh bound eps) finds the nodes left more than H - eps
 * that a cutter from above could reach and the axis position from which the ideal cutter comes
 * nearest to each; one short pass there (the drop there and those tol / 2 before and after it
 * along x, each kept only where its chord passes the raster's test: no chord joins a low drop
 * to a high one across a jump). flagged: only the nodes within R / 4 of p's flagged points (the
 * raster); else every node (waterline, raster+waterline: they flag nothing). rounds (>= 1): the
 * measure again on the passes so far while the last round added some, at most that many in all.
 * *added counts the passes added. CS_ERR_FULL out of memory. */
cs_err_t cs_dcpath_fill(cs_dcpath_t *p, cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                        const cs_surffile_t *sf, const cs_dcpath_opts_t *o, double step_mm,
                        bool flagged, int rounds, size_t *added);
/* Joins each pass to the one before it where the straight move between the end of one and the
 * start of the next stays within tol_mm / 2 of the drop-cutter height of tool t or above it
 * (sampled every step_mm along the move; the passes' own chords are held to the same): one
 * polyline, no retract. The passes keep their order. */
void cs_dcpath_link(cs_dcpath_t *p, cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                    double step_mm, double tol_mm);
/* Appends one pass of n tip points (mm), cross offset or level w. CS_ERR_FULL out of memory. */
cs_err_t cs_dcpath_append(cs_dcpath_t *p, const double (*pts)[3], size_t n, double w);
void cs_dcpath_free(cs_dcpath_t *p);

#endif
