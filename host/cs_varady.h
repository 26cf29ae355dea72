/* cs_varady: transfinite n-sided patches after Várady, Rockwood and Salvi (seed 002), built on
 * the host in double precision; what reaches the fixed-point core is cubic Bézier curves (the
 * images of straight domain segments) fitted within a tolerance. Owns the domain polygon
 * (seed 002 "Solution 1": vertices on a circle at angles proportional to the boundary arc
 * lengths), the side-based parametrisation (d_i = distance to domain side i,
 * s_i = d_{i-1} / (d_{i-1} + d_{i+1})), linear ribbons R_i(s, d) = P_i(s) + d T_i(s) and the
 * seed's special side blends mu_i = D_i / sum D_j, D_i = prod_{j != i} d_j^2:
 * S = sum R_i(s_i, d_i) mu_i. (The lambda / kappa scheme with corner patches is not done.) */
#ifndef CS_VARADY_H
#define CS_VARADY_H

#include <stddef.h>

#include "cs_bezier.h"

#define CS_VARADY_MAX_SIDES 8

typedef struct {
    size_t n;
    cs_bezier_t side[CS_VARADY_MAX_SIDES]; /* P_i(s), s in [0, 1], P_i(1) = P_{i+1}(0) */
    double len[CS_VARADY_MAX_SIDES];       /* arc length of each side, mm */
    double vert[CS_VARADY_MAX_SIDES][2];   /* domain polygon, vertex i starts side i */
    double t0[CS_VARADY_MAX_SIDES][3];     /* cross-boundary tangent of side i at s = 0 */
    double t1[CS_VARADY_MAX_SIDES][3];     /* ... at s = 1 (unit vectors into the patch) */
} cs_varady_t;

/* n (3..CS_VARADY_MAX_SIDES) polynomial boundary curves of degree 1..3 forming a loop (the end
 * of side i is exactly the start of side i + 1, and of the last the start of the first):
 * CS_ERR_ARG / CS_ERR_DEGREE / CS_ERR_UNSUPPORTED (rational) / CS_ERR_DEGENERATE (loop not
 * closed, a zero-length side or zero tangent at a corner). Cross-boundary tangents: at each
 * corner the unit tangent of the neighbouring side leading away from it, blended linearly
 * along the side (1 mm per domain mm). */
cs_err_t cs_varady_init(cs_varady_t *v, const cs_bezier_t *sides, size_t n);
/* Surface point (mm) at domain point (x, y) inside the polygon (outside: extrapolated). On a
 * domain side it is that boundary curve; at a vertex, the corner. */
void cs_varady_eval(const cs_varady_t *v, double x, double y, double out[3]);
/* Domain polygon vertex i (i < n), in domain units. */
void cs_varady_vertex(const cs_varady_t *v, size_t i, double out[2]);
/* The image of the domain segment a -> b as cubic Béziers (Hermite pieces through the surface
 * with derivatives by central differences), each within tol_mm of the surface curve at 33
 * samples per piece, split in halves until they are (at most 64 pieces). Writes *count curves
 * to out[0..max-1]. CS_ERR_TOLERANCE when 64 pieces do not reach tol_mm, CS_ERR_FULL when max is
 * too small, CS_ERR_RANGE when a point leaves the coordinate range. */
cs_err_t cs_varady_curve(const cs_varady_t *v, const double a[2], const double b[2], double tol_mm,
                         cs_bezier_t *out, size_t max, size_t *count);

#endif
