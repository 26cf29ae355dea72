/* cs_coons: Coons patches from four boundary curves (seed 000, "Patches de Coons"), built exactly
 * as bicubic cs_patch_t when the boundaries (and cross-boundary derivative curves) are Bézier
 * curves of degree <= 3: bilinear S = S1 + S2 - S3 (linear blends) and bicubic (Hermite blends,
 * the seed's matrix H, twist vectors of S3 zero as the seed's default, or given). Also the swept
 * surfaces that are exact tensor products: ruled surfaces between two curves and extrusions. */
#ifndef CS_COONS_H
#define CS_COONS_H

#include "cs_bezier.h"
#include "cs_patch.h"

/* Boundary naming of seed 000: p1(u) = S(u, 0), p2(u) = S(u, 1), q1(v) = S(0, v),
 * q2(v) = S(1, v); corners A = p1(0) = q1(0), B = p1(1) = q2(0), C = p2(1) = q2(1),
 * D = p2(0) = q1(1) must agree exactly (CS_ERR_DEGENERATE otherwise). Curves: polynomial, degree
 * 1..3 (CS_ERR_UNSUPPORTED for rational, CS_ERR_DEGREE otherwise), control points inside
 * CS_POS_LIMIT. The result is bicubic; every control point is 1/9 of an exact integer
 * combination, rounded once (<= 0.5 LSB), and a cubic boundary is reproduced exactly.
 * CS_ERR_RANGE when a result point leaves CS_POS_LIMIT. Pure; not for ISRs. */
cs_err_t cs_coons_bilinear(const cs_bezier_t *p1, const cs_bezier_t *p2, const cs_bezier_t *q1,
                           const cs_bezier_t *q2, cs_patch_t *out);
/* Bicubic Coons: as above plus the cross-boundary derivative curves p1v(u) = dS/dv(u, 0),
 * p2v(u) = dS/dv(u, 1), q1u(v) = dS/du(0, v), q2u(v) = dS/du(1, v) (mm per unit parameter,
 * degree 1..3 with any int32 components). NULL picks the default compatible with the corners
 * and zero twists: the cubic (a, a, b, b) from the crossing curves' end tangents (p1v from
 * q1'(0) to q2'(0), p2v from q1'(1) to q2'(1), q1u from p1'(0) to p2'(0), q2u from p1'(1) to
 * p2'(1)). S3 is the Hermite bicubic of the corner points, the boundary curves' corner tangents
 * and zero twists (seed 000's usual choice). S interpolates the boundaries when each derivative
 * curve starts and ends on those corner tangents (always true of the defaults), and then its
 * cross-boundary derivatives too when the derivative curves have zero end slopes. */
cs_err_t cs_coons_bicubic(const cs_bezier_t *p1, const cs_bezier_t *p2, const cs_bezier_t *q1,
                          const cs_bezier_t *q2, const cs_bezier_t *p1v, const cs_bezier_t *p2v,
                          const cs_bezier_t *q1u, const cs_bezier_t *q2u, cs_patch_t *out);
/* Bicubic Coons with the twist vectors of S3 given (seed 000: A^uv_ab = d2S/dudv at corner
 * (u = a, v = b), twist[a][b], mm per unit u per unit v, any int32 components) instead of zero;
 * NULL twist is cs_coons_bicubic. A NULL derivative curve then defaults to the Hermite cubic
 * between the crossing curves' corner tangents whose end slopes are the twists (p1v: twist[0][0],
 * twist[1][0]; p2v: [0][1], [1][1]; q1u: [0][0], [0][1]; q2u: [1][0], [1][1]), so S interpolates
 * the boundaries and has those twists at the corners. Errors as cs_coons_bicubic. Pure. */
cs_err_t cs_coons_bicubic_twist(const cs_bezier_t *p1, const cs_bezier_t *p2, const cs_bezier_t *q1,
                                const cs_bezier_t *q2, const cs_bezier_t *p1v,
                                const cs_bezier_t *p2v, const cs_bezier_t *q1u,
                                const cs_bezier_t *q2u, const cs_vec3_t twist[2][2],
                                cs_patch_t *out);
/* Ruled surface S(u, v) = (1 - v) p(u) + v q(u) (seed 000, "Surface réglée"): a patch of degree
 * max(deg p, deg q) x 1; the lower-degree curve is elevated (exact to 0.5 LSB). Polynomial
 * curves of degree 1..3 only. Pure. */
cs_err_t cs_coons_ruled(const cs_bezier_t *p, const cs_bezier_t *q, cs_patch_t *out);
/* Extrusion (cylinder) S(u, v) = p(u) + v d: exact (d in mm); CS_ERR_RANGE when p + d leaves
 * CS_POS_LIMIT. Pure. */
cs_err_t cs_coons_extrude(const cs_bezier_t *p, const cs_vec3_t *d, cs_patch_t *out);

#endif
