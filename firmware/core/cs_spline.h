/* cs_spline: the natural cubic spline through up to CS_SPLINE_MAX_POINTS points (seed 003,
 * "Spline cubique naturelle": C2, interpolates every point, second derivative zero at both ends),
 * solved in fixed point by a tridiagonal (Thomas) solve in a caller-owned struct, no heap, and
 * emitted as cubic Bézier segments. Owns the solve and the parametrisation (uniform or chord). */
#ifndef CS_SPLINE_H
#define CS_SPLINE_H

#include <stddef.h>
#include <stdint.h>

#include "cs_bezier.h"
#include "cs_err.h"
#include "cs_fixed.h"

/* Largest number of points of one spline; sets the size of cs_spline_t (40 bytes per point,
 * 2.6 KB at 64). A firmware build may define it smaller (e.g. -DCS_SPLINE_MAX_POINTS=16 on AVR),
 * for the whole build at once: every translation unit must see the same struct. */
#ifndef CS_SPLINE_MAX_POINTS
#define CS_SPLINE_MAX_POINTS 64
#endif

typedef enum {
    CS_SPLINE_UNIFORM = 0, /* parameter step 1 per segment */
    CS_SPLINE_CHORD = 1,   /* parameter step = chord length |P(i+1) - P(i)| */
} cs_spline_param_t;

/* The solved spline and its workspace (caller-owned; borrows the points, which must outlive it).
 * m[i] is the tangent at point i: uniform, in LSB per unit parameter scaled by 2^20; chord, in
 * mm per mm scaled by 2^40. */
typedef struct {
    const cs_vec3_t *pts;
    size_t count;
    cs_spline_param_t param;
    uint64_t h[CS_SPLINE_MAX_POINTS];   /* chord lengths, LSB * 2^16 (chord mode) */
    int64_t piv[CS_SPLINE_MAX_POINTS];  /* Thomas pivots, 2^40 = 1 */
    int64_t m[CS_SPLINE_MAX_POINTS][3]; /* right-hand sides, then the tangents */
} cs_spline_t;

/* Solve the spline through pts[0..count-1]. CS_ERR_ARG (NULL, unknown param), CS_ERR_DEGENERATE
 * (count < 2, or two consecutive equal points in chord mode), CS_ERR_FULL (count >
 * CS_SPLINE_MAX_POINTS), CS_ERR_RANGE (a point outside CS_POS_LIMIT). O(count), not ISR-safe. */
cs_err_t cs_spline_solve(cs_spline_t *s, const cs_vec3_t *pts, size_t count,
                         cs_spline_param_t param);
/* Number of segments, count - 1 (0 before a successful solve). ISR-safe. */
size_t cs_spline_segments(const cs_spline_t *s);
/* Segment index (0-based) as a cubic Bézier from P(i) to P(i+1), exact end points, inner points
 * within 1 LSB of the exact spline's. CS_END past the last; CS_ERR_RANGE if an inner point
 * leaves CS_POS_LIMIT (overshoot near the edge of the range). */
cs_err_t cs_spline_segment(const cs_spline_t *s, size_t index, cs_bezier_t *out);
/* All segments into out[0..cap-1] (*n of them); CS_ERR_FULL when cap < count - 1. Not
 * ISR-safe (count segments' worth of 128-bit mul-divs). */
cs_err_t cs_spline_to_bezier(const cs_spline_t *s, cs_bezier_t *out, size_t cap, size_t *n);

#endif
