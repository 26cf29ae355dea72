/* cs_patch: tensor-product Bézier patches of degree up to 7 x 7 (bicubic above all), the one
 * surface representation of the core (seed 003 "Surfaces bicubiques", seed 004 Hermite).
 * Owns evaluation with Pu, Pv, Puv and the unit normal (limit normal on collapsed edges), de
 * Casteljau splits, iso-curves as cs_bezier_t (stepped by exact forward differences for a
 * raster), exact conversion from algebraic and Hermite form, the 9-way Hermite split and the
 * continuity test along a shared edge. */
#ifndef CS_PATCH_H
#define CS_PATCH_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_bezier.h"
#include "cs_err.h"
#include "cs_fixed.h"

/* Any degree the curves have (seed 000's patches are not limited to bicubics); the Hermite and
 * algebraic forms and the 9-way split stay bicubic (seed 004). */
#define CS_PATCH_MAX_DEGREE CS_BEZIER_MAX_DEGREE
#define CS_PATCH_MAX_POINTS (CS_PATCH_MAX_DEGREE + 1)

/* P(u, v) = sum_i sum_j B_i^du(u) B_j^dv(v) p[i][j], u, v in [0, 1]: i runs along u, j along v
 * (Newell's 16 indices k = 4 i + j). Every control point inside CS_POS_LIMIT. */
typedef struct {
    uint8_t deg_u, deg_v; /* 1..CS_PATCH_MAX_DEGREE each */
    cs_vec3_t p[CS_PATCH_MAX_POINTS][CS_PATCH_MAX_POINTS];
} cs_patch_t;

/* Point and first derivatives, cs_pos_t units: pu = dP/du and pv = dP/dv in mm per unit
 * parameter, puv = d2P/dudv (the twist) in mm per unit u per unit v. */
typedef struct {
    cs_vec3_t p, pu, pv, puv;
} cs_patch_derivs_t;

/* A unit vector, each component signed Q1.30 (CS_PARAM_ONE = 1.0). */
typedef struct {
    int32_t x, y, z;
} cs_patch_unit_t;

/* Hermite bicubic in the geometric form of seed 004 (Mortenson's B matrix): index [a][b] is the
 * corner u = a, v = b (a, b in {0, 1}); p the corner points, pu / pv the tangents (mm per unit
 * u / v), puv the twist vectors (mm per unit u per unit v). */
typedef struct {
    cs_vec3_t p[2][2], pu[2][2], pv[2][2], puv[2][2];
} cs_patch_hermite_t;

/* Which family of iso-parametric curves: ISO_U curves run along u at a fixed v (their degree is
 * deg_u), ISO_V curves run along v at a fixed u. */
typedef enum {
    CS_PATCH_ISO_U = 0,
    CS_PATCH_ISO_V = 1,
} cs_patch_iso_t;

/* Raster of N + 1 iso-curves at the parameters k / N, N = 2^shift: each control point of the
 * iso-curve is a polynomial of degree m <= 7 (the patch's degree in the fixed parameter) in it,
 * stepped by exact integer forward differences (values scaled by N^m), so each step is m int64
 * additions per coordinate per control point and every curve is the exact iso-curve rounded
 * once (<= 0.5 LSB). Exactness needs |N^m c| 2^m < 2^63 with |c| < 2^28 LSB: m (shift + 1) + 29
 * <= 63, so shift <= cs_patch_raster_max_shift(m) (10 up to cubics, 7, 5, 4, 3 for m = 4..7). */
#define CS_PATCH_RASTER_MAX_SHIFT 10
typedef struct {
    uint8_t degree; /* of each iso-curve */
    uint8_t order;  /* m: degree of the control points in the fixed parameter */
    uint8_t shift;
    uint16_t k;                                             /* next curve, 0..N; N + 1: done */
    int64_t f[CS_PATCH_MAX_POINTS][3][CS_PATCH_MAX_POINTS]; /* N^m * value, then differences */
} cs_patch_raster_t;

/* Continuity along the shared edge a(1, v) = b(0, v), the highest that holds. */
typedef enum {
    CS_PATCH_CONT_NONE = 0, /* the edges differ */
    CS_PATCH_CONT_C0 = 1,   /* same edge curve */
    CS_PATCH_CONT_G1 = 2,   /* same tangent plane all along the edge */
    CS_PATCH_CONT_C1 = 3,   /* same cross-boundary derivative dP/du all along the edge */
    CS_PATCH_CONT_C2 = 4,   /* C1 and the same second cross-boundary derivative d2P/du2 */
} cs_patch_cont_t;

/* Patch from (deg_u + 1) * (deg_v + 1) points, pts[i * (deg_v + 1) + j] = p[i][j].
 * CS_ERR_DEGREE for a degree outside 1..3, CS_ERR_RANGE for a point outside CS_POS_LIMIT. */
cs_err_t cs_patch_init(cs_patch_t *p, unsigned deg_u, unsigned deg_v, const cs_vec3_t *pts);
/* P(u, v), u, v in [0, CS_PARAM_ONE] (else CS_ERR_ARG); within 0.5 + 2^-24 LSB of the exact
 * value for the fixed-point control points. Pure, ISR-safe (about 30 64-bit multiplies). */
cs_err_t cs_patch_eval(const cs_patch_t *p, cs_param_t u, cs_param_t v, cs_vec3_t *out);
/* P, Pu, Pv, Puv at (u, v), each within 0.5 + 2^-20 LSB of the exact value; CS_ERR_OVERFLOW
 * when a derivative does not fit cs_pos_t (possible only for control nets wider than 2^15 mm
 * per unit parameter). Pure, ISR-safe. */
cs_err_t cs_patch_derivs(const cs_patch_t *p, cs_param_t u, cs_param_t v, cs_patch_derivs_t *out);
/* Unit normal (Pu x Pv) / |Pu x Pv| at (u, v), components Q1.30. Pu and Pv (2^-28 LSB guard
 * error) are scaled to 30 bits before the cross product, so the direction error is about
 * 2^-29 / sin(Pu, Pv) plus 2^-20 LSB / min(|Pu|, |Pv|) (measured <= 4e-8 rad on random patches
 * with sine >= 1e-5). Where Pu x Pv vanishes (sine below ~2^-23) on an edge, the limit normal
 * from the inside: a collapsed edge v = 0 (Pu = 0 there) uses Pu ~ v Puv, so Puv x Pv (v = 1:
 * -Puv x Pv); a collapsed edge u = 0 uses Pu x Puv (u = 1: -Pu x Puv).
 * CS_ERR_DEGENERATE when that limit vanishes too, or Pu x Pv vanishes inside the patch or
 * between two non-zero derivatives. Pure; not for ISRs (a 128-bit division per component). */
cs_err_t cs_patch_normal(const cs_patch_t *p, cs_param_t u, cs_param_t v, cs_patch_unit_t *n);
/* De Casteljau split at u in (0, 1) into lo = [0, u] x [0, 1] and hi = [u, 1] x [0, 1] (either
 * may be NULL or p itself, not both the same struct); each point rounded once
 * (<= 0.5 + 2^-25 LSB), so lo(s, v) = p(u s, v) within that. CS_ERR_ARG for u outside (0, 1). */
cs_err_t cs_patch_split_u(const cs_patch_t *p, cs_param_t u, cs_patch_t *lo, cs_patch_t *hi);
/* Same in v: lo = [0, 1] x [0, v], hi = [0, 1] x [v, 1]. */
cs_err_t cs_patch_split_v(const cs_patch_t *p, cs_param_t v, cs_patch_t *lo, cs_patch_t *hi);
/* The iso-curve at a fixed parameter t in [0, 1] (CS_ERR_ARG outside): ISO_U gives u -> P(u, t)
 * (degree deg_u), ISO_V gives v -> P(t, v); control points rounded once (<= 0.5 + 2^-25 LSB). */
cs_err_t cs_patch_iso(const cs_patch_t *p, cs_patch_iso_t dir, cs_param_t t, cs_bezier_t *out);

/* Largest raster shift for iso-curves whose control points have degree m in the fixed
 * parameter (see cs_patch_raster_t): min(CS_PATCH_RASTER_MAX_SHIFT, (34 - m) / m). Pure. */
unsigned cs_patch_raster_max_shift(unsigned m);
/* Start a raster of 2^shift + 1 iso-curves of family dir at t = k / 2^shift, k = 0..2^shift
 * (shift 0..cs_patch_raster_max_shift(the other degree), else CS_ERR_ARG). Bounded work,
 * ISR-safe. */
cs_err_t cs_patch_raster_begin(cs_patch_raster_t *r, const cs_patch_t *p, cs_patch_iso_t dir,
                               unsigned shift);
/* Next iso-curve (*t its fixed parameter, may be NULL); CS_END after the last (k = 2^shift, the
 * patch's far edge, exactly its control points). Additions only; ISR-safe. */
cs_err_t cs_patch_raster_next(cs_patch_raster_t *r, cs_bezier_t *out, cs_param_t *t);

/* Bicubic from the algebraic form P(u, v) = sum a[i][j] u^i v^j (seed 004's A matrix; a[i][j]
 * in mm per unit u^i v^j, any int32): Bézier points 1/9 * (integer combination), each rounded
 * once (<= 0.5 LSB). CS_ERR_RANGE when a Bézier point leaves CS_POS_LIMIT. Not for ISRs. */
cs_err_t cs_patch_from_power(cs_patch_t *p, const cs_vec3_t a[4][4]);
/* Bicubic from the Hermite form (seed 004: P = U^T M^T B M V), exact to 0.5 LSB: b = P + Pu/3
 * + Pv/3 + Puv/9 at the corners (one rounding). CS_ERR_RANGE as above. Not for ISRs. */
cs_err_t cs_patch_from_hermite(cs_patch_t *p, const cs_patch_hermite_t *h);
/* Hermite form of a bicubic (deg 3 x 3, else CS_ERR_DEGREE), exact: Pu = 3 (b10 - b00),
 * Puv = 9 (b11 - b10 - b01 + b00) ... CS_ERR_OVERFLOW when a twist does not fit int32. */
cs_err_t cs_patch_to_hermite(const cs_patch_t *p, cs_patch_hermite_t *h);
/* Exact subdivision of a Hermite bicubic into 9 (seed 004): cuts at us[0] < us[1] and
 * vs[0] < vs[1], all in (0, 1) (else CS_ERR_ARG); out[a][b] covers [u_a, u_a+1] x [v_b, v_b+1]
 * (u_0 = 0, u_3 = 1) reparametrised to [0, 1]^2: corner values of the parent, tangents scaled
 * by the interval length (uj - ui) Pu, twists by (uj - ui)(vl - vk) Puv, each within
 * 0.5 + 2^-20 LSB of the exact value. Every input vector must be inside CS_POS_LIMIT
 * (CS_ERR_RANGE), so must every output point (CS_ERR_RANGE); an output tangent or twist must
 * fit int32 (CS_ERR_OVERFLOW; inside the patch a tangent can exceed the corners' by up to ~5x).
 * Not for ISRs (144 bit-serial divisions). */
cs_err_t cs_patch_hermite_split9(const cs_patch_hermite_t *h, const cs_param_t us[2],
                                 const cs_param_t vs[2], cs_patch_hermite_t out[3][3]);
/* The same surface with u and v exchanged (out may be p): orients a patch so that a shared edge
 * becomes the u-edge cs_patch_continuity compares. */
cs_err_t cs_patch_transpose(const cs_patch_t *p, cs_patch_t *out);
/* Continuity along a's edge u = 1 against b's edge u = 0 (same deg_v, else CS_ERR_DEGREE):
 * C0 when the edge control points agree within tol LSB (each coordinate); C1 when also the
 * cross-boundary derivative control vectors deg_u (p[n][j] - p[n-1][j]) agree within tol; C2
 * when, beyond C1, the second ones deg_u (deg_u - 1) (p[n][j] - 2 p[n-1][j] + p[n-2][j]) (zero
 * for deg_u = 1) agree within tol too (exact integers); G1
 * when instead det(Pu_a, Pu_b, Pv) / (|Pu_a| |Pu_b| |Pv|) <= sin_tol (Q30) with Pu_a . Pu_b > 0
 * relative to the edge (same side) at 3 deg_v + 1 points along the edge: the determinant is a
 * polynomial of degree <= 3 deg_v - 1 in v, so that many zeros mean it vanishes everywhere.
 * Pure; not for ISRs. */
cs_err_t cs_patch_continuity(const cs_patch_t *a, const cs_patch_t *b, cs_pos_t tol,
                             cs_param_t sin_tol, cs_patch_cont_t *out);

#endif
