/* cs_sphere: the exact sphere of seed 000 ("Surface sphérique"), kept in the seed's own
 * parametrisation S(u, w) = C + r (cos u cos w, cos u sin w, sin u), u in [-90, 90] degrees,
 * w in [0, 360]: its iso-curves are circles, so every parallel (u constant) and meridian
 * (w constant) is built exactly as rational quadratic arcs (cs_arc_build through
 * cs_curvefile_arc), on the sphere itself or on the concentric offset sphere a ball-end tool's
 * centre follows. Also the ball-end scallop between two passes in closed form. Host, double. */
#ifndef CS_SPHERE_H
#define CS_SPHERE_H

#include "cs_arc.h"
#include "cs_bezier.h"

typedef struct {
    double c[3]; /* centre, mm */
    double r;    /* radius, mm (> 0) */
} cs_sphere_t;

/* The parallel at latitude lat_deg (strictly between -90 and 90) of the sphere of radius
 * r + off (off: a tool's radius, or 0): a full counter-clockwise circle seen from +z, starting
 * at longitude 0, as *n (4) exact pieces. CS_ERR_RANGE when it leaves the coordinate range or
 * lat_deg is outside (-90, 90). */
cs_err_t cs_sphere_parallel(const cs_sphere_t *s, double off, double lat_deg,
                            cs_bezier_t out[CS_ARC_MAX_SEGMENTS], unsigned *n);
/* The meridian arc at longitude lon_deg from latitude lat0 to lat1 (degrees, each in
 * [-90, 90], lat0 != lat1) of the sphere of radius r + off, as *n exact pieces. */
cs_err_t cs_sphere_meridian(const cs_sphere_t *s, double off, double lon_deg, double lat0,
                            double lat1, cs_bezier_t out[CS_ARC_MAX_SEGMENTS], unsigned *n);
/* Scallop height (mm) left on the sphere of radius r by a ball of radius R whose centre runs on
 * the offset sphere r + R along two parallels dtheta radians apart, midway between them: going
 * out along the bisecting ray, material is left from the sphere (r) to where the ray first
 * enters a ball, rho = (r + R) cos(dtheta / 2) - sqrt(R^2 - (r + R)^2 sin^2(dtheta / 2)) (the
 * nearer root of |rho e - centre| = R), so h = rho - r. HUGE_VAL when the balls do not meet. */
double cs_sphere_scallop(double r, double ball, double dtheta);
/* The largest dtheta (radians, <= pi / 2) whose scallop is <= h (the scallop grows with
 * dtheta): by bisection to 1e-12. */
double cs_sphere_step(double r, double ball, double h);

#endif
