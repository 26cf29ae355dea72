/* bench_curves: what the flattening benchmarks (bench_flatten, bench_peers) share: a growable
 * set of curves, the fixed-seed xorshift64 generator (shifts 13, 7, 17; Marsaglia 2003) they
 * draw random cubics from, a monotonic clock, and the curved elements of the SVG corpus.
 * Caller-owned state; benchmarks and tests only. */
#ifndef BENCH_CURVES_H
#define BENCH_CURVES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_bezier.h"

/* A named, growable set of curves. */
typedef struct {
    const char *name;
    cs_bezier_t *c;
    size_t n, cap;
} bench_set_t;

/* The generator; start it at BENCH_RNG_SEED so every run draws the same curves. */
typedef struct {
    uint64_t s;
} bench_rng_t;
#define BENCH_RNG_SEED 0x9E3779B97F4A7C15ull

/* Appends a copy of *c to s (aborts when out of memory). */
void bench_set_add(bench_set_t *s, const cs_bezier_t *c);
/* Uniform double in [0, 1) (53 bits of the next value; advances g). */
double bench_rng_unit(bench_rng_t *g);
/* Seconds of CLOCK_MONOTONIC. */
double bench_now(void);
/* Adds to s the curved elements (degree > 1) of the SVG files files[0..nfiles) (user unit =
 * 1 mm) or, when nfiles is 0, of every ../shared/data/svg/<dir>/<file>.svg (run from the
 * repository root) or, when there is none, of tests/data/svg/<dir>/<file>.svg. keep (NULL:
 * every curve as it is) converts a curve into *out and returns true, or returns false to leave
 * it out. A file that does not read is reported on stderr. Returns how many curves keep left
 * out. */
size_t bench_svg_curves(bench_set_t *s, char *const *files, size_t nfiles,
                        bool (*keep)(const cs_bezier_t *in, cs_bezier_t *out));

#endif
