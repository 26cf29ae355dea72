/* ref_bezier: double-precision reference for Bézier tests (cs_bezier, cs_join, cs_arclen).
 * Coordinates are kept in LSB units (1 LSB = 2^-16 mm) so test tolerances read in LSB. */
#ifndef REF_BEZIER_H
#define REF_BEZIER_H

#include <stdint.h>

#include "cs_bezier.h"

typedef struct {
    int degree;
    int rational;
    double p[CS_BEZIER_MAX_POINTS][3]; /* LSB */
    double w[CS_BEZIER_MAX_POINTS];    /* real weights (1.0 for polynomial) */
} ref_bezier_t;

/* Exact copy of a fixed-point segment (every int32 and Q30 weight is exact in double). */
void ref_bezier_from(const cs_bezier_t *c, ref_bezier_t *r);
/* Point at t (de Casteljau in homogeneous doubles), LSB. */
void ref_bezier_eval(const ref_bezier_t *r, double t, double out[3]);
/* First derivative dB/dt at t, LSB per unit t (rational: quotient rule). */
void ref_bezier_deriv(const ref_bezier_t *r, double t, double out[3]);
/* Second derivative d2B/dt2 at t (polynomial only), LSB per unit t^2. */
void ref_bezier_deriv2(const ref_bezier_t *r, double t, double out[3]);
/* Arc length between t0 and t1, LSB: adaptive Gauss-Legendre (7 points) on |B'|, relative
 * tolerance ~1e-12, so it is a reference far finer than any fixed-point tolerance. */
double ref_bezier_length(const ref_bezier_t *r, double t0, double t1);
/* Euclidean distance of two 3-vectors. */
double ref_dist3(const double a[3], const double b[3]);

/* xorshift64* PRNG for seeded random tests. */
typedef struct {
    uint64_t s;
} ref_rng_t;
void ref_rng_seed(ref_rng_t *g, uint64_t seed);
uint64_t ref_rng_next(ref_rng_t *g);
/* Uniform integer in [lo, hi]. */
int64_t ref_rng_range(ref_rng_t *g, int64_t lo, int64_t hi);
/* Uniform double in [0, 1). */
double ref_rng_unit(ref_rng_t *g);

#endif
