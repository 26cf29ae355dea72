/* curve_cases: the planar test corpus the tracer tests share (test_predict, test_fd3): a
 * xorshift64 stream of doubles, planar Béziers from millimetre control points, random curves in
 * a box, and the hard cases (cusp, loop, collinear folds, coincident and near-equal end points,
 * 2 m curves, worst-case coordinates, a 1 um curve, a line, a quadratic U turn). */
#ifndef CURVE_CASES_H
#define CURVE_CASES_H

#include <stddef.h>
#include <stdint.h>

#include "cs_bezier.h"

/* Next double in [0, 1) of the xorshift64 stream *state (nonzero seed). */
double curve_cases_unit(uint64_t *state);
/* Polynomial Bézier of the given degree from control points in mm (rounded to the LSB), every
 * point at height z mm. */
cs_bezier_t curve_cases_planar(unsigned degree, const double (*p)[2], double z);
/* Random curve of the given degree, control points uniform in [-box, box] mm, z in
 * [-10, 10] mm, drawn from *state. */
cs_bezier_t curve_cases_random(uint64_t *state, unsigned degree, double box);

typedef struct {
    const char *name;
    unsigned degree;
    double p[4][2]; /* mm */
} curve_case_t;

extern const curve_case_t curve_cases_hard[];
extern const size_t curve_cases_hard_n;

#endif
