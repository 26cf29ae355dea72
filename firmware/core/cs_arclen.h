/* cs_arclen: arc length of a Bézier segment and the feed parametrisation the planner needs
 * ("where is the point at distance s along this curve"). Owns the adaptive length computation
 * (dyadic subdivision, no recursion, no stack of curves) and the s -> t table. */
#ifndef CS_ARCLEN_H
#define CS_ARCLEN_H

#include "cs_bezier.h"

/* Deepest dyadic subdivision of a length interval (pieces 2^-24 of it) before CS_ERR_DEPTH;
 * cusps need it: there polygon - chord shrinks only like the width squared. */
#define CS_ARCLEN_MAX_DEPTH 24
/* Extra fraction bits of the internal lengths (2^-24 LSB). */
#define CS_ARCLEN_FRAC 24
/* Intervals of the feed table: entries at t = k / CS_ARCLEN_TABLE_N, k = 0..N. */
#define CS_ARCLEN_TABLE_N 32
/* Each table interval is measured in at least 2^3 pieces, whose partial lengths bound the
 * interpolation error (about 1/8 of the interval's length at worst). */
#define CS_ARCLEN_TABLE_MIN_DEPTH 3

/* Length of c (polynomial or rational), within tol of the exact length of the curve defined by
 * its fixed-point control points. Each dyadic piece [t0, t1] is bracketed by its chord and its
 * control-polygon length (the length lies between them: de Casteljau subdivision only cuts
 * corners); a piece is accepted when polygon - chord plus its rounding allowance fits its share
 * of tol (half in proportion to its polygon length, half to its width in t), and contributes
 * (2 chord + (n-1) polygon) / (n+1) (Gravesen). tol in LSB, >= 1 (else CS_ERR_TOLERANCE).
 * CS_ERR_DEPTH when a piece of width 2^-CS_ARCLEN_MAX_DEPTH still misses its share (tolerance
 * too tight for this curve), CS_ERR_OVERFLOW when the length exceeds the cs_pos_t format.
 * Cost: per piece (n+1) blossoms; not for an ISR. */
cs_err_t cs_arclen_length(const cs_bezier_t *c, cs_pos_t tol, cs_pos_t *len);

/* Feed table: s[k] = arc length from t = 0 to t = k / N (monotone, s[0] = 0, s[N] = length).
 * err bounds, for any s in [0, length], |arclen(0, cs_arclen_lookup(s)) - s| in LSB: the
 * tolerance of the lengths plus the largest per-interval error of interpolating t linearly in
 * s. That error is bounded two ways, the smaller kept: from the partial lengths of the
 * interval's >= 2^CS_ARCLEN_TABLE_MIN_DEPTH pieces (s is monotone, so inside a piece it cannot
 * stray further than the piece's ends allow), and for a polynomial segment by (vmax - vmin) / 4,
 * vmax and vmin bounds on the speed from the piece's hodograph control points. Both include
 * the rounding of t. Size: 35 x 4 bytes. */
typedef struct {
    cs_pos_t s[CS_ARCLEN_TABLE_N + 1];
    cs_pos_t length;
    cs_pos_t err;
} cs_arclen_table_t;

/* Build the table of c with the lengths to within tol (LSB, >= 1) in total. Errors as
 * cs_arclen_length (the table is then unspecified). Not for an ISR (a full length
 * computation). */
cs_err_t cs_arclen_table_build(cs_arclen_table_t *tab, const cs_bezier_t *c, cs_pos_t tol);
/* Parameter t (Q1.30) at arc length s (LSB) from the start, by linear interpolation in the
 * interval that holds s (binary search, no division but one 64-bit one): within tab->err of
 * the exact position along the curve. CS_ERR_RANGE for s outside [0, tab->length]. ISR-safe. */
cs_err_t cs_arclen_lookup(const cs_arclen_table_t *tab, cs_pos_t s, cs_param_t *t);

#endif
