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
 * control point leaves the coordinate range; CS_ERR_DEGENERATE for zero-length directions.
 * Sweeps <= 90 degrees give 1 piece, <= 180 give 2, more give 4 (equal halves/quarters); pieces
 * share their end points exactly and every point of them is within 2 LSB of the exact ellipse.
 * C, U, V must be inside CS_POS_LIMIT and no direction component INT32_MIN (CS_ERR_RANGE).
 * Reentrant, bounded time (a few dozen bit-serial 128-bit divisions): not meant for ISRs. */
cs_err_t cs_arc_build(const cs_vec3_t *c, const cs_vec3_t *u, const cs_vec3_t *v, cs_param_t cos0,
                      cs_param_t sin0, cs_param_t cos1, cs_param_t sin1, bool ccw,
                      cs_bezier_t out[CS_ARC_MAX_SEGMENTS], unsigned *n);

/* G-code working planes (G17, G18, G19) and the axes (first, second) an arc turns between. */
typedef enum {
    CS_ARC_PLANE_XY = 17, /* G17: X then Y, normal +Z */
    CS_ARC_PLANE_ZX = 18, /* G18: Z then X, normal +Y */
    CS_ARC_PLANE_YZ = 19, /* G19: Y then Z, normal +X */
} cs_arc_plane_t;

/* G2/G3 circle arc in a principal plane, built on cs_arc_build: from *start around *centre
 * (only its two in-plane coordinates are used; the arc lies at start's third coordinate),
 * counter-clockwise (G3: first axis towards second, right-handed about the normal) when ccw,
 * clockwise (G2) otherwise. Radius = in-plane |start - centre|; *end gives the end direction only
 * (the last piece ends at centre + radius * unit(end - centre), which the caller compares with
 * *end against its radius tolerance). End direction = start direction: a full circle.
 * CS_ERR_ARG for an unknown plane or start and end at different heights (a helix is not a
 * conic; the caller moves the third axis itself), CS_ERR_DEGENERATE when start or end is on the
 * centre, plus cs_arc_build's errors. */
cs_err_t cs_arc_gcode(const cs_vec3_t *centre, const cs_vec3_t *start, const cs_vec3_t *end,
                      cs_arc_plane_t plane, bool ccw, cs_bezier_t out[CS_ARC_MAX_SEGMENTS],
                      unsigned *n);

#endif
