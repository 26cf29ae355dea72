/* cs_fd: uniform forward differencing of a polynomial cs_bezier_t (seed 003, "Forward
 * differences"): N = 2^K steps from Wang's bound, exact int64 recurrence (n*K guard bits), one
 * rounding per output point. Owns the step-count bound, the exact initial differences and the
 * dyadic pre-split used when K exceeds what int64 holds (shared with cs_afd). */
#ifndef CS_FD_H
#define CS_FD_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_bezier.h"

/* Bits available above a coordinate (|x| <= 2^28 LSB) in an int64 accumulator, keeping one bit
 * of headroom: 28 + g + n*K <= 61, so n*K <= CS_FD_GUARD_BITS - g (docs/fixed-point.md), where g
 * is the pieces' guard bits (0 when the curve is traced whole). */
#define CS_FD_GUARD_BITS 33
/* Most dyadic pre-split levels (2^20 pieces); beyond that the tolerance is refused. */
#define CS_FD_MAX_SPLIT 20
/* Fraction bits below the LSB carried by the control points of split pieces: each halving
 * rounds by <= 2^-9 LSB, so 20 levels stay under 0.04 LSB and every vertex within 1 LSB. */
#define CS_FD_PIECE_GUARD 8

/* A point with CS_FD_PIECE_GUARD (or 0) fraction bits below the LSB. */
typedef struct {
    int64_t x, y, z;
} cs_fd_pt_t;


/* Rational FD: homogeneous numerator w*P (Q30 x LSB, <= 2^58) and weight w (Q30) differenced
 * exactly with n*K guard bits in 128 bits: n*K <= CS_FD_RAT_GUARD_BITS. Build with
 * -DCS_FD_RATIONAL=0 to leave it out (about 18 KB of AVR flash, 512 bytes of state): rational
 * curves then get CS_ERR_UNSUPPORTED and cs_trace routes them to cs_subdiv. */
#define CS_FD_RAT_GUARD_BITS 60
#ifndef CS_FD_RATIONAL
#define CS_FD_RATIONAL 1
#endif

typedef struct {
    uint8_t degree;
    bool rational; /* homogeneous 128-bit differences in rd[] instead of d[] */
    uint8_t k;     /* this piece has 2^k steps */
    uint8_t split; /* the curve is cut into 2^split pieces */
    uint8_t guard; /* fraction bits of the pieces' control points (0 when split == 0) */
    bool done;
    uint32_t piece; /* index of the current piece */
    uint64_t step;  /* steps done in the current piece */
    cs_pos_t tol_eff;
    int64_t d[3][CS_BEZIER_MAX_POINTS]; /* [axis][order] x 2^(guard + n*k) */
#if CS_FD_RATIONAL
    cs_i128_t rd[4][CS_BEZIER_MAX_POINTS]; /* rational: [x, y, z, w][order] x 2^(n*k) */
#endif
    cs_bezier_t curve;
} cs_fd_t;

/* Largest K (2^K steps per piece) whose exact recurrence fits in `bits` (33 for FD, 30 for AFD)
 * for degree n and pieces with `guard` fraction bits: floor((bits - guard) / n), capped at 30. */
unsigned cs_fd_kmax(unsigned degree, unsigned bits, unsigned guard);
/* Smallest K with Wang's bound n(n-1)/8 * max|P_i - 2P_{i+1} + P_{i+2}| / 4^K <= tol (LSB), for
 * points with `guard` fraction bits. */
unsigned cs_fd_wang_k(const cs_fd_pt_t *p, unsigned degree, unsigned guard, cs_pos_t tol);
/* Control points of piece j of 2^s equal dyadic pieces of the polynomial c, with `guard`
 * fraction bits: s exact halvings, each rounded to the guard bits (<= 2^-(guard+1) LSB each). */
void cs_fd_piece(const cs_bezier_t *c, unsigned s, uint32_t j, unsigned guard, cs_fd_pt_t *out);
/* Choose the pre-split level s and effective tolerance for tracing c at tol with recurrences
 * of `bits` (see cs_fd_kmax), Wang's bound applied to tol_eff >> margin (margin 0 for FD, 1 for
 * AFD). CS_ERR_TOLERANCE when even CS_FD_MAX_SPLIT levels do not suffice. */
cs_err_t cs_fd_plan(const cs_bezier_t *c, cs_pos_t tol, unsigned bits, unsigned margin, unsigned *s,
                    cs_pos_t *tol_eff);
/* Exact forward differences of the degree-n polynomial with control points p at t = 0, step
 * 2^-k, scaled by 2^(n*k) on top of p's format: d[axis][0] = position, d[axis][j] = j-th
 * difference (orders above min(n, 2^k) are set to 0: the recurrence never needs them).
 * Requires guard + n*k <= 33. */
void cs_fd_init_diffs(const cs_fd_pt_t *p, unsigned degree, unsigned k,
                      int64_t d[3][CS_BEZIER_MAX_POINTS]);

/* Smallest K such that 2^K uniform chords of the rational curve c are within tol (LSB), from
 * the conservative bound h^2/8 max|R''| (docs/fixed-point.md); 255 when the bound saturates. */
#if CS_FD_RATIONAL
unsigned cs_fd_rational_k(const cs_bezier_t *c, cs_pos_t tol);
#endif

/* Start uniform FD of c at chord tolerance tol (LSB). Rational curves are differenced in
 * homogeneous space (128-bit, exact) and divided per vertex; CS_ERR_UNSUPPORTED when a rational
 * curve would need more than 2^(60/n) steps (cs_trace then routes it to cs_subdiv).
 * CS_ERR_DEGREE / CS_ERR_RANGE / CS_ERR_WEIGHT for bad input, CS_ERR_TOLERANCE when tol cannot
 * be met. Bounded work (<= 21 Wang bounds, one piece of
 * <= 20 halvings); not meant for ISRs. */
cs_err_t cs_fd_begin(cs_fd_t *f, const cs_bezier_t *c, cs_pos_t tol);
/* Next vertex: n additions per axis (3 for a cubic) and one rounding; CS_END when finished.
 * ISR-safe and constant time except at piece boundaries. */
cs_err_t cs_fd_next(cs_fd_t *f, cs_vec3_t *pt);

#endif
