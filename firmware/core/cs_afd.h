/* cs_afd: adaptive forward differencing of a polynomial cs_bezier_t (Lien, Shantz & Pratt 1987;
 * integer form after Chang, Shantz & Rocchetti 1989): the step is halved or doubled in the
 * forward-difference basis so each chord stays within tol and is no shorter than it needs to be.
 * Owns the exact halving/doubling transforms and the per-step flatness bound. */
#ifndef CS_AFD_H
#define CS_AFD_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_bezier.h"

/* Guard bits: differences are kept x 2^(g + n*Lmax) with g + n*Lmax <= 30 (g: the pieces'
 * CS_FD_PIECE_GUARD bits when the curve is split), so values stay below 2^(28+30) with 2^4 of
 * headroom for differences whose window runs past t = 1 (larger ones are refused, not wrapped). */
#define CS_AFD_GUARD_BITS 30

typedef struct {
    uint8_t degree;
    uint8_t level; /* current step is 2^-level of the piece */
    uint8_t lmin; /* coarsest level (0: a whole piece; doublings that would overflow are refused) */
    uint8_t lmax; /* finest level: guard + n * lmax <= CS_AFD_GUARD_BITS */
    uint8_t split; /* the curve is cut into 2^split pieces (as cs_fd) */
    uint8_t guard; /* fraction bits of the pieces' control points (0 when split == 0) */
    bool done;
    uint32_t piece;
    uint32_t t; /* position in the piece, in units of 2^-lmax */
    cs_pos_t tol_eff;
    int64_t d[3][CS_BEZIER_MAX_POINTS]; /* [axis][order] x 2^(guard + n*lmax) */
    cs_bezier_t curve;
} cs_afd_t;

/* Start AFD of the polynomial c at chord tolerance tol (LSB). CS_ERR_UNSUPPORTED for rational
 * curves (cs_trace routes those to cs_subdiv), CS_ERR_DEGREE / CS_ERR_RANGE / CS_ERR_TOLERANCE
 * for bad input. Not for ISRs. */
cs_err_t cs_afd_begin(cs_afd_t *a, const cs_bezier_t *c, cs_pos_t tol);
/* Next vertex; CS_END when finished; CS_ERR_DEPTH if a step finer than 2^-lmax would be needed,
 * CS_ERR_OVERFLOW if a difference would leave its format (reported, never wrapped). */
cs_err_t cs_afd_next(cs_afd_t *a, cs_vec3_t *pt);

#endif
