/* cs_revolve: surfaces of revolution (seed 000, "Surface de révolution"): a planar profile
 * (radius, height) turned about an axis, built on the host in double and handed to the core as
 * bicubic-in-v cs_patch_t within a tolerance. Each patch is the exact tensor product of the
 * profile with a cubic Bézier approximation of a circular arc (tangent length 4/3 tan(phi/4)),
 * so the only geometric error is the arc's radial error times the radius; the sweep is cut into
 * enough arcs to keep it, plus the rounding of the control points, within the tolerance. */
#ifndef CS_REVOLVE_H
#define CS_REVOLVE_H

#include <stddef.h>

#include "cs_bezier.h"
#include "cs_patch.h"

/* Most arcs one surface is cut into (360 degrees in 1-degree arcs). */
#define CS_REVOLVE_MAX_ARCS 360

/* Largest radial deviation of the cubic arc approximation of a unit-circle arc of phi radians
 * from the circle (measured densely in double). */
double cs_revolve_arc_error(double phi);

/* Revolve profile (polynomial, degree 1..3; its x is the distance from the axis in mm, its y
 * the height along the axis, z ignored) about the axis through origin[] (mm) with direction
 * axis[] (any length > 0), from angle 0 (the direction ref[] projected off the axis; any
 * vector not parallel to the axis) counter-clockwise about axis[] by sweep_deg (0 < . <= 360).
 * Writes *n patches (deg_u = the profile's degree along the profile, deg_v = 3 around) to
 * out[0..max-1]; *dev_mm (may be NULL) gets the bound on the distance to the exact surface
 * (arc error x largest |radius| + 1 LSB of rounding). CS_ERR_TOLERANCE when tol_mm cannot be
 * met with CS_REVOLVE_MAX_ARCS arcs, CS_ERR_FULL when max is too small, CS_ERR_RANGE when a
 * control point leaves the coordinate range, CS_ERR_DEGENERATE for a zero axis or ref parallel
 * to it, CS_ERR_ARG for a bad sweep. */
cs_err_t cs_revolve(const cs_bezier_t *profile, const double origin[3], const double axis[3],
                    const double ref[3], double sweep_deg, double tol_mm, cs_patch_t *out,
                    size_t max, size_t *n, double *dev_mm);

#endif
