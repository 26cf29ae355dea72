/* cs_dcwater: waterline finishing passes over a drop-cutter mesh (issue 20, `toolpath
 * --strategy waterline`). Owns the constant-z contours of the drop-cutter surface z_d(x, y) (the
 * tip height of the cutter dropped at (x, y), cs_dropcut_drop, never below the floor min_z): for
 * each level z_k the closed or open polylines where z_d = z_k, with the tip at z_k.
 *
 * Gouge-free by construction: the cutter with its tip at (x, y, z) with z >= z_d(x, y) does not
 * enter the surface (z_d is the lowest such z, and raising the cutter only moves it away from a
 * surface seen from above). The contour points are found by bisection along the edges of a grid
 * of drop values between a node with z_d > z_k (the material side) and one with z_d <= z_k, down
 * to tol / 2 in xy, and the point kept is always the end with z_d <= z_k: the outside of the
 * material region at that level. Between two contour points the chord is checked at its middle
 * and quarters; where z_d there exceeds z_k + tol / 2 a point found the same way (bisection
 * across the chord towards z_d <= z_k) is inserted.
 *
 * Level spacing: the scallop a ball of radius R leaves on a vertical wall between two levels dz
 * apart is the flat-ground one turned on its side, so dz = 2 sqrt(2RH - H^2) (the raster's
 * step-over formula, cs_dcpath_step, applied vertically); a bull-nose meets a vertical wall with
 * its corner: dz = 2 sqrt(2rH - H^2); a flat end's terraces are at most dz high: dz = H. On
 * shallow ground the levels lie far apart in xy and leave more than H: waterline is for the
 * steep parts, the raster for the rest. Host only, double precision. */
#ifndef CS_DCWATER_H
#define CS_DCWATER_H

#include "cs_dcpath.h"
#include "cs_dropcut.h"

/* The level spacing (mm) of tool t for scallop height h on a vertical wall (see above). */
double cs_dcwater_zstep(const cs_dropcut_tool_t *t, double h);
/* Plans the waterline contours over mesh ms for tool t into p (levels from the top down, each
 * contour one pass, its level in p->w), within o's box, above o->min_z, level step from
 * o->scallop_mm (or o->step_mm when given). CS_ERR_FULL out of memory, CS_ERR_RANGE for an
 * empty region. */
cs_err_t cs_dcwater_plan(cs_dcpath_t *p, cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                         const cs_dcpath_opts_t *o);

#endif
