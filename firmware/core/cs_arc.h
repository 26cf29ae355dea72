/* cs_arc: circular and elliptical arcs as exact rational quadratic Bézier segments (conics).
 * An arc is the image of a unit-circle arc under X = C + U cos(phi) + V sin(phi), so circles in
 * any plane (G17/G18/G19), rotated ellipses (SVG 'A') and full turns share one construction,
 * done without trigonometry: sweeps are bisected on the unit circle (integer sqrt) until each
 * piece spans at most 90 degrees, and each piece is a rational quadratic with w1 = cos(half). */
#ifndef CS_ARC_H
#define CS_ARC_H

#include <stdbool.h>

#include "cs_bezier.h"

/* A full turn splits into 4 quarter pieces; no arc ever needs more. */
#define CS_ARC_MAX_SEGMENTS 4

/* Build the arc of the ellipse centred at *c with conjugate semi-axes *u, *v (mm, cs_pos_t),
 * from unit-circle direction (cos0, sin0) to (cos1, sin1) (each a Q1.30 pair of length ~1,
 * renormalised here), turning counter-clockwise (from U towards V) when ccw, clockwise otherwise.
 * Equal start and end directions mean a full turn. Writes *n (1..4) segments to out[], each a
 * rational quadratic (degree 2, rational = true); the first starts at C + U cos0 + V sin0 and
 * the last ends at C + U cos1 + V sin1 to within 1 LSB. CS_ERR_RANGE / CS_ERR_OVERFLOW when a
 * control point leaves the coordinate range; CS_ERR_DEGENERATE for zero-length directions. */
cs_err_t cs_arc_build(const cs_vec3_t *c, const cs_vec3_t *u, const cs_vec3_t *v, cs_param_t cos0,
                      cs_param_t sin0, cs_param_t cos1, cs_param_t sin1, bool ccw,
                      cs_bezier_t out[CS_ARC_MAX_SEGMENTS], unsigned *n);

#endif
