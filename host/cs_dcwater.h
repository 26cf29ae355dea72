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
 * its corner: dz = 2 sqrt(2rH - H^2); a flat end's terraces are at most dz high: dz = H
 * (cs_dcwater_plan starts a flat end at 2H: a terrace leaves dz cos(theta) along the normal,
 * and the added levels serve slopes under 60 degrees). H is taken less the mesh bound and half
 * the chord tolerance (both may add to what is left).
 *
 * Shallow ground (cs_dcwater_plan; Mastercam's "add cuts in shallow areas"): on ground of
 * slope theta the levels lie dz / tan(theta) apart in xy, and the step they may take there is
 * cs_dclevel's (ball dz <= sin(theta) 2 sqrt(2RH - H^2); flat end dz <= min(H / cos(theta),
 * 2R tan(theta)); bull-nose from its section). Each grid node gets that step from its slope
 * (central differences of the drops). Between two levels, where a node with its drop between
 * them wants less than their spacing, the level halfway is added, its contour clipped to those
 * nodes and two cells round them (marching squares on those cells only), and each half is
 * treated the same way, down to 1/16 of the level step. Flat areas (Mastercam's "flat
 * areas"): nodes whose slope allows less than that least step (a plateau, the cup's bottom, a
 * crest) are cut by a raster at the flat-ground step-over (cs_dcpath_step, the same drop),
 * one over each group's box grown by R + 2 cells, clipped to the nodes within that distance of
 * a flat node. Concave corners of the drop surface (a valley's floor, a wall's foot: a
 * second difference over a node steeper than WL_KINK), which levels on the grid cannot hug,
 * get a raster each way at a quarter of that step-over (at most sqrt(2rH - H^2)), clipped
 * the same way. Nodes where the cutter rests on the floor, not the surface, want nothing.
 * The command then adds the fill-in over the whole region (cs_dcpath_fill, one round).
 * Host only, double precision. */
#ifndef CS_DCWATER_H
#define CS_DCWATER_H

#include "cs_dcpath.h"
#include "cs_dropcut.h"

/* The level spacing (mm) of tool t for scallop height h on a vertical wall (see above). */
double cs_dcwater_zstep(const cs_dropcut_tool_t *t, double h);
/* A node mask over a grid (x0 + i gx, y0 + j gy), on[j nx + i] != 0 where kept. */
typedef struct {
    double x0, y0, gx, gy;
    size_t nx, ny;
    const unsigned char *on;
} cs_dcwater_mask_t;

/* Plans the waterline over mesh ms for tool t into p (levels from the top down, each contour
 * one pass, its level in p->w; the added levels above each level; the flat areas' raster passes
 * last; p->refined counts the added and flat passes), within o's box, above o->min_z, level step
 * from o->scallop_mm (or o->step_mm when given). CS_ERR_FULL out of memory, CS_ERR_RANGE for an
 * empty region. */
cs_err_t cs_dcwater_plan(cs_dcpath_t *p, cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                         const cs_dcpath_opts_t *o);
/* The even levels' contours only (no added levels, no flat areas: raster+waterline's steep
 * part, cs_dccombo.h), level step from o->step_mm or else the wall step for H. Errors as above. */
cs_err_t cs_dcwater_contours(cs_dcpath_t *p, cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                             const cs_dcpath_opts_t *o);
/* Appends to out the runs (two points or more) of in's passes whose points' nearest node is on
 * in m. CS_ERR_FULL out of memory. */
cs_err_t cs_dcwater_clip(cs_dcpath_t *out, const cs_dcpath_t *in, const cs_dcwater_mask_t *m);
/* dst (nx * ny) = the nodes within rho (mm) of a node set in src, grid spacing gx, gy. */
void cs_dcwater_dilate(const unsigned char *src, unsigned char *dst, size_t nx, size_t ny,
                       double gx, double gy, double rho);

#endif
