/* cs_dccombo: raster + waterline finishing over a drop-cutter mesh (issue 20, `toolpath
 * --strategy raster+waterline`). The raster serves shallow ground, the waterline steep ground,
 * each clipped to its region with an overlap, so that the scallop is at most H on both.
 *
 * Regions: a grid over the stock box at spacing g = max(R / 4, tol); a node is steep where the
 * mesh top rises faster than DCC_STEEP (45 deg) over 0.05 mm in x or y, or differs from a
 * neighbouring node's by more than DCC_STEEP g (a wall between nodes; where there is no surface
 * the floor counts). The waterline keeps its points whose nearest node lies within R + 2 g of a
 * steep node, the raster those within R + 2 g of a shallow node: a cutter touching the surface at
 * a point stands within R of it, so each region's points are served by its own strategy.
 *
 * Scallops: the raster's gap refinement skips points steeper than DCC_STEEP (cs_dcpath_opts_t
 * max_slope). On a plane of slope theta, waterline levels dz apart leave contacts dz / sin theta
 * apart along the surface, so the level step is the wall step (cs_dcwater_zstep) times
 * sin(atan(DCC_STEEP)), from H less the mesh bound and half the chord tolerance (the raster's own
 * margin). Host only, double precision. */
#ifndef CS_DCCOMBO_H
#define CS_DCCOMBO_H

#include "cs_dcpath.h"
#include "cs_dropcut.h"

#define DCC_STEEP 1.0 /* slope above which the waterline serves (45 deg) */

/* Plans raster then waterline over mesh ms for tool t into p (raster passes first, in their
 * zig-zag order, then the contours from the top down), each clipped to its region.
 * CS_ERR_FULL out of memory, CS_ERR_RANGE for an empty region. */
cs_err_t cs_dccombo_plan(cs_dcpath_t *p, cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                         const cs_dcpath_opts_t *o);

#endif
