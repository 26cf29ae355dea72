/* cs_basis: cubic curves given in another basis (Hermite, uniform B-spline, Catmull-Rom,
 * Barsky beta-spline) converted to cubic Bézier segments by G_B = M_B^-1 . M . G (seed 003,
 * "Conversion entre différentes représentations"). Owns the exact conversion matrices and a
 * sequence type that yields the segments of a whole curve one at a time (no storage). */
#ifndef CS_BASIS_H
#define CS_BASIS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_bezier.h"
#include "cs_err.h"
#include "cs_fixed.h"

/* Beta-spline shape parameters: unsigned Q16.16 in int32 (1.0 = CS_BASIS_BETA_ONE).
 * Accepted: 0 < beta1 <= CS_BASIS_BETA1_MAX (bias), 0 <= beta2 <= CS_BASIS_BETA2_MAX (tension);
 * the bounds keep delta * 2^48 = 2 b1^3 + 4 b1^2 2^16 + (4 b1 + b2) 2^32 + 2^49 below 2^63. */
typedef int32_t cs_basis_beta_t;
#define CS_BASIS_BETA_FRAC_BITS 16
#define CS_BASIS_BETA_ONE       ((cs_basis_beta_t)1 << CS_BASIS_BETA_FRAC_BITS)
#define CS_BASIS_BETA1_MAX      ((cs_basis_beta_t)16 << CS_BASIS_BETA_FRAC_BITS)
#define CS_BASIS_BETA2_MAX      ((cs_basis_beta_t)1024 << CS_BASIS_BETA_FRAC_BITS)

/* The beta-spline Bézier conversion matrix for one (beta1, beta2): each Bézier point is a convex
 * combination of two or three of the four control points; w[i][j] is the weight (Q1.30) of
 * G_j in Bézier point i, each rounded from the exact rational c_ij / delta. */
typedef struct {
    int32_t w[4][4];
} cs_basis_beta_mat_t;

/* The kinds of sequence cs_basis_seq_t can carry. */
typedef enum {
    CS_BASIS_HERMITE = 0,     /* n points + n tangents -> n-1 segments, C1 */
    CS_BASIS_BSPLINE = 1,     /* uniform cubic B-spline: m+1 points -> m-2 segments, C2 */
    CS_BASIS_CATMULL_ROM = 2, /* m+1 points -> m-2 segments through P1..P(m-1), C1 */
    CS_BASIS_BETA = 3,        /* beta-spline: m+1 points -> m-2 segments, G2 */
} cs_basis_kind_t;

/* A whole curve in one basis: borrows the caller's arrays (they must outlive the sequence). */
typedef struct {
    cs_basis_kind_t kind;
    const cs_vec3_t *pts;
    const cs_vec3_t *tangents; /* Hermite only: one tangent per point, mm per unit t */
    size_t count;              /* number of points */
    cs_basis_beta_mat_t beta;  /* beta-spline only */
} cs_basis_seq_t;

/* Hermite segment (P1, P4, R1, R4), tangents in mm per unit t (cs_pos_t units), to the cubic
 * Bézier (P1, P1 + R1/3, P4 - R4/3, P4); exact to 0.5 LSB. CS_ERR_RANGE for a point outside
 * CS_POS_LIMIT or a result outside it. ISR-safe (no state). */
cs_err_t cs_basis_hermite(const cs_vec3_t *p1, const cs_vec3_t *p4, const cs_vec3_t *r1,
                          const cs_vec3_t *r4, cs_bezier_t *out);
/* Uniform cubic B-spline segment from its 4 control points g[0..3]; exact to 0.5 LSB.
 * CS_ERR_RANGE for a point outside CS_POS_LIMIT. ISR-safe. */
cs_err_t cs_basis_bspline(const cs_vec3_t g[4], cs_bezier_t *out);
/* Catmull-Rom segment between g[1] and g[2] (g[0], g[3] set the tangents (g[2]-g[0])/2 and
 * (g[3]-g[1])/2); exact to 0.5 LSB. CS_ERR_RANGE for a point or result outside the range. */
cs_err_t cs_basis_catmull_rom(const cs_vec3_t g[4], cs_bezier_t *out);
/* Precompute the beta-spline conversion for bias beta1 and tension beta2 (Barsky,
 * delta = 2 b1^3 + 4 b1^2 + 4 b1 + b2 + 2). CS_ERR_RANGE outside the accepted ranges.
 * Not for ISRs (16 bit-serial 128-bit divisions). */
cs_err_t cs_basis_beta_init(cs_basis_beta_mat_t *m, cs_basis_beta_t beta1, cs_basis_beta_t beta2);
/* Beta-spline segment from its 4 control points; error <= 1 LSB (weights rounded to 2^-31).
 * CS_ERR_RANGE for a point outside CS_POS_LIMIT. ISR-safe. */
cs_err_t cs_basis_beta(const cs_basis_beta_mat_t *m, const cs_vec3_t g[4], cs_bezier_t *out);

/* Sequence of `count` points (and, for Hermite, `count` tangents; NULL otherwise). CS_ERR_ARG for
 * NULL arrays or an unknown kind, CS_ERR_DEGENERATE when there are too few points for one
 * segment (Hermite 2, others 4), CS_ERR_RANGE for a point outside CS_POS_LIMIT. Beta-splines
 * use cs_basis_seq_init_beta instead. */
cs_err_t cs_basis_seq_init(cs_basis_seq_t *s, cs_basis_kind_t kind, const cs_vec3_t *pts,
                           const cs_vec3_t *tangents, size_t count);
/* Beta-spline sequence: as cs_basis_seq_init plus the shape parameters (see cs_basis_beta_init). */
cs_err_t cs_basis_seq_init_beta(cs_basis_seq_t *s, const cs_vec3_t *pts, size_t count,
                                cs_basis_beta_t beta1, cs_basis_beta_t beta2);
/* Number of Bézier segments the sequence yields. ISR-safe. */
size_t cs_basis_seq_segments(const cs_basis_seq_t *s);
/* Segment `index` (0-based) as a cubic Bézier; CS_END when index >= the segment count.
 * ISR-safe (reads the sequence only; bounded time). */
cs_err_t cs_basis_seq_segment(const cs_basis_seq_t *s, size_t index, cs_bezier_t *out);

#endif
