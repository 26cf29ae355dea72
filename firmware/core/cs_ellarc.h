/* cs_ellarc: the arc tracer for circles and ellipses (the conic pieces of cs_arc: SVG 'A', G2/G3).
 * A rational quadratic piece with weights (1, w, 1), cos 45deg <= w < 1, is the affine image of
 * the unit-circle arc from -alpha to +alpha (w = cos alpha): x(phi) = C + U cos phi + V sin phi.
 * Its chords are cut at equal angles delta = 2 alpha / n, n the least count whose chords all
 * stay within the tolerance (the closed-form deviation (1 - cos(delta/2)) |det[U V]| / |A t|,
 * worst over the piece), and the vertices come from the exact rotation recurrence
 * y_{k+1} = 2 cos(delta) y_k - y_{k-1} on y = x - C: two multiplies a coordinate per vertex, no
 * division, no trigonometry per vertex. Derivation and error bound in docs/fixed-point.md,
 * "Arc tracer". */
#ifndef CS_ELLARC_H
#define CS_ELLARC_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_bezier.h"

/* Fraction bits of the recurrence's state (units of 2^-28 LSB). */
#define CS_ELLARC_FRAC 28
/* Rounding budget charged against the tolerance (LSB): the vertex rounding (1/2) plus the
 * recurrence's accumulated error (< 2^-4 LSB, docs/fixed-point.md "Arc tracer"), rounded up to
 * 2 like cs_predict's, so that a tolerance given in mm and rounded to the LSB (0.001 mm = 66
 * LSB, 0.46 LSB more than asked) is still met in mm. */
#define CS_ELLARC_SLACK_LSB 2
/* Least tolerance (LSB) the arc tracer takes; below it cs_trace uses the conic predictor. */
#define CS_ELLARC_TOL_MIN (CS_ELLARC_SLACK_LSB + 2)
/* Most chords a piece may take (the error bound above); a piece needing more is refused. */
#define CS_ELLARC_MAX_CHORDS 4096u

/* Most sub-ranges of a piece (each with its own step: an ellipse's allowed step varies). */
#define CS_ELLARC_MAX_SUB 8

typedef struct {
    uint64_t delta; /* the step's angle, rad Q62 */
    uint64_t bound; /* entered when the angle left to Q2 is at most this (rad Q62) */
    uint64_t ratio; /* sin(delta) / sin(delta of the sub-range before), Q60 */
    uint32_t km;    /* K = 2 - 2 cos(delta) = km 2^-ks, km in [2^31, 2^32) */
    uint8_t ks;     /* 32..60 */
} cs_ellarc_sub_t;

typedef struct {
    int64_t x[2];  /* the last vertex, x and y, units 2^-CS_ELLARC_FRAC LSB */
    int64_t d[2];  /* the next step x_{k+1} - x_k */
    int64_t c[2];  /* the ellipse's centre C */
    uint64_t rem;  /* angle left from the last vertex to Q2, rad Q62 */
    cs_ellarc_sub_t sub[CS_ELLARC_MAX_SUB];
    uint8_t m;     /* sub-ranges in use */
    uint8_t cur;   /* the one the last vertex is in */
    bool done;
    cs_vec3_t end; /* Q2, returned exactly as the last vertex */
} cs_ellarc_t;

/* Start tracing the conic piece c with chord tolerance tol (LSB). CS_ERR_UNSUPPORTED when the arc
 * tracer does not take c (not a planar rational quadratic with w0 = w2 = 1 and
 * cos 45deg <= w1 < 1, straight, too flat or too large for its 64-bit state, more than
 * CS_ELLARC_MAX_CHORDS chords, or tol < CS_ELLARC_TOL_MIN): the caller then traces c otherwise.
 * Bounded work (a few 128-bit divisions and square roots); not meant for ISRs. */
cs_err_t cs_ellarc_begin(cs_ellarc_t *a, const cs_bezier_t *c, cs_pos_t tol);
/* Next vertex (see cs_trace_next): CS_OK with *pt, CS_END after Q2 (returned exactly).
 * Constant time (two 32x32 -> 64 multiplies a coordinate); ISR-safe. */
cs_err_t cs_ellarc_next(cs_ellarc_t *a, cs_vec3_t *pt);

#endif
