/* cs_curvefile: curvestep's native curves file, one curve per statement in any basis the core
 * converts to Bézier form (seed 003, "Conversion entre différentes représentations"), so every
 * basis reaches flatten, plan, stream, submit and the simulator (docs/inputs.md, "Curves file"):
 *
 *   curvestep-curves 1                 header (first token of the file)
 *   line P0 P1
 *   bezier N P0 .. PN                  degree N = 1..7 (cs_bezier_t)
 *   hermite N P1 T1 .. PN TN           N >= 2 points, each with its tangent (mm per unit t)
 *   bspline N P1 .. PN                 uniform cubic B-spline, N >= 4 (cs_basis)
 *   bspline N P1 .. PN knots K k1 .. k(N+K)        order K = 2..4, any knot vector (cs_nurbs)
 *   nurbs N P1 w1 .. PN wN knots K k1 .. k(N+K)    weights > 0 (cs_nurbs)
 *   catmull-rom N P1 .. PN             through P2 .. P(N-1), N >= 4 (cs_basis)
 *   beta B1 B2 N P1 .. PN              beta-spline, bias B1, tension B2, N >= 4 (cs_basis)
 *   natural N P1 .. PN [chord] [clamped T0 T1]
 *                                      cubic spline through the points, C2; ends natural (zero
 *                                      second derivative) or clamped to the tangents T0, T1;
 *                                      uniform or chord parameter
 *   arc C U V A0 A1                    C + U cos(a) + V sin(a), a from A0 to A1 degrees
 * P, T, C, U, V = three numbers in mm; '#' starts a comment; numbers are free-form across lines.
 * A statement whose start is not the previous end starts a new subpath (a pen lift). */
#ifndef CS_CURVEFILE_H
#define CS_CURVEFILE_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_arc.h"
#include "cs_path.h"

/* First token of every curves file. */
#define CS_CURVEFILE_MAGIC "curvestep-curves"
/* Most points one statement may have (bounds its buffers; the natural spline's own bound,
 * CS_SPLINE_MAX_POINTS, is lower). */
#define CS_CURVEFILE_MAX_POINTS 65536

/* The `arc` statement's curve: C + U cos(a) + V sin(a) (v[0..2] = C, U, V) for a from a0 to a1
 * degrees (counter-clockwise from U towards V when a1 > a0), 0 < |a1 - a0| <= 360, as the exact
 * rational quadratics of cs_arc_build (cos and sin in double, then Q1.30). CS_ERR_RANGE for a
 * sweep outside that range, plus cs_arc_build's errors. */
cs_err_t cs_curvefile_arc(const cs_vec3_t v[3], double a0_deg, double a1_deg,
                          cs_bezier_t out[CS_ARC_MAX_SEGMENTS], unsigned *n);
/* True when the first token of text[0..len) is CS_CURVEFILE_MAGIC. */
bool cs_curvefile_is(const char *text, size_t len);
/* Parses text[0..len) (name for diagnostics) and appends every curve's Bézier segments to
 * *path with the location of its keyword. CS_ERR_PARSE / CS_ERR_RANGE / a constructor's code
 * with *diag "file:line:col: reason"; CS_ERR_EMPTY for a file with no curve; CS_ERR_FULL when
 * out of memory. */
cs_err_t cs_curvefile_parse(const char *name, const char *text, size_t len, cs_path_t *path,
                            cs_path_diag_t *diag);

#endif
