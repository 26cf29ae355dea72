/* cs_fd3: uniform forward differences specialised for a planar polynomial curve of degree 1..3
 * (lines, quadratics, cubics at one z: what SVG and G5 give), the hot loop of CS_TRACE_FD for
 * them. The curve is cut into 2^s equal pieces (s <= CS_FD3_MAX_SPLIT, chosen to minimise the
 * chords) and each piece gets its own step count N, the exact Wang bound for that piece (any
 * integer, not a power of two). Each point costs 3 additions per coordinate (x, y) with a fixed
 * 32-bit fraction: no degree loop, no z, no variable shift. Owns the piece plan and the
 * differences; error bound in docs/fixed-point.md, "Planar cubic FD". Rational curves, degree
 * > 3 and 3D curves keep the general cs_fd. */
#ifndef CS_FD3_H
#define CS_FD3_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_bezier.h"

/* Most steps a piece planned: the rounding of the initial differences grows as C(N, 3), so
 * N <= 1025 (one more for the pieces' rounding) keeps every vertex within 0.021 LSB of the
 * exact recurrence (docs/fixed-point.md). */
#define CS_FD3_MAX_STEPS 1024u
/* Most split levels (2^6 pieces); a curve that would need more is left to cs_fd. */
#define CS_FD3_MAX_SPLIT 6u
/* Split levels always compared (1, 2, 4, 8 pieces); more only when a piece needs them. */
#define CS_FD3_TRY_SPLIT 3u
/* Fraction bits of the recurrence below the LSB: a vertex is the high word, no shift. */
#define CS_FD3_FRAC 32
/* Rounding budget charged against the tolerance, LSB: vertices rounded to the LSB (<= 0.5 +
 * 0.021 per axis, 0.74 in the plane) plus the pieces' control points (<= 6 * 2^-9 LSB). */
#define CS_FD3_SLACK_LSB 1

/* State: the differences (64 bytes), the piece plan and the curve (for the next piece). */
typedef struct {
    /* Modulo 2^64 (unsigned: wrap-around is defined): the recurrence is linear, so positions
     * come out exact even where a difference of a short piece, extrapolated past its end by
     * the last steps, leaves int64. Units 2^-32 LSB. */
    uint64_t x, y;          /* position + 2^31 + 2^62 (rounding and sign bias) */
    uint64_t dx1, dx2, dx3; /* forward differences of x */
    uint64_t dy1, dy2, dy3;
    uint32_t left;        /* steps left in this piece */
    uint32_t piece;       /* index of this piece */
    uint8_t split;        /* 2^split pieces */
    bool done;
    cs_pos_t tol_eff;     /* tol - CS_FD3_SLACK_LSB */
    cs_pos_t z;
    cs_bezier_t curve;    /* to start the next piece */
} cs_fd3_t;

/* True when cs_fd3 takes c: polynomial, degree 1..3, every control point at the same z. */
bool cs_fd3_accepts(const cs_bezier_t *c);
/* Start tracing c at tolerance tol (LSB, >= CS_FD3_SLACK_LSB + 1). CS_ERR_UNSUPPORTED when
 * !cs_fd3_accepts(c) or a piece would need more than CS_FD3_MAX_STEPS at CS_FD3_MAX_SPLIT
 * (cs_trace then runs cs_fd), CS_ERR_TOLERANCE for tol out of range, CS_ERR_RANGE for a point
 * outside CS_POS_LIMIT. Bounded work (at most 2^(CS_FD3_TRY_SPLIT+1) + 2^CS_FD3_MAX_SPLIT piece
 * plans); not for ISRs. */
cs_err_t cs_fd3_begin(cs_fd3_t *f, const cs_bezier_t *c, cs_pos_t tol);
/* Next vertex: CS_OK with *pt (the last one is P_n exactly), CS_END after it. Constant time
 * inside a piece (3 additions per axis); ISR-safe. */
cs_err_t cs_fd3_next(cs_fd3_t *f, cs_vec3_t *pt);
/* The next vertices, up to max, into out[]: the same vertices as cs_fd3_next, with the
 * recurrence kept in registers (the firmware's block loop: fewest instructions a point).
 * Returns how many were written, 0 once the curve is finished. ISR-safe. */
size_t cs_fd3_fill(cs_fd3_t *f, cs_vec3_t *out, size_t max);

#endif
