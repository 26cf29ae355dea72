/* ref_ellarc: the double-precision reference for arcs of circles and ellipses, x(phi) = C +
 * U cos phi + V sin phi for phi in [0, sweep]: a chord's largest distance from the arc and the
 * greedy chord count over the WHOLE arc (no vertex forced where cs_arc joins its pieces), the
 * yardstick of issue 18's "chords <= 1.10x the whole-element greedy". One copy for test_ellarc
 * and bench_peers. Tests and benchmarks only. */
#ifndef REF_ELLARC_H
#define REF_ELLARC_H

#include <stddef.h>

typedef struct {
    double c[2], u[2], v[2], sweep; /* mm; sweep in rad */
} ref_ellarc_t;

/* The point at angle phi (mm). */
void ref_ellarc_point(const ref_ellarc_t *e, double phi, double p[2]);
/* Largest distance (mm) of the arc [f0, f1] from its chord segment: the arc is convex, so the
 * distance is unimodal in phi; golden-section search, 60 steps. */
double ref_ellarc_chord_dev(const ref_ellarc_t *e, double f0, double f1);
/* Chords of the greedy over the whole arc at tol (mm): from each vertex the largest phi whose
 * chord stays within tol, by bisection on phi (50 steps). */
size_t ref_ellarc_greedy(const ref_ellarc_t *e, double tol);

#endif
