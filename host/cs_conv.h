/* cs_conv: the one place where the host turns double-precision values into the core's
 * fixed-point formats (and back), and reads command-line numbers. Every conversion is range-checked: a value the format cannot
 * hold is refused with CS_ERR_RANGE, never clamped or wrapped. */
#ifndef CS_CONV_H
#define CS_CONV_H

#include <stdbool.h>

#include "cs_fixed.h"

/* mm -> cs_pos_t (Q15.16), rounded to the nearest LSB. CS_ERR_RANGE when mm is not finite or
 * |result| > CS_POS_LIMIT (4096 mm); *out is untouched then. */
cs_err_t cs_conv_mm_to_pos(double mm, cs_pos_t *out);
/* A command-line number: s read whole by strtod and finite (no trailing text); false else. */
bool cs_conv_number(const char *s, double *out);
/* cs_pos_t -> mm, exact (every Q15.16 value is a double). */
double cs_conv_pos_to_mm(cs_pos_t p);
/* (x, y, z) in mm -> cs_vec3_t, each coordinate as cs_conv_mm_to_pos. */
cs_err_t cs_conv_mm_to_vec(double x, double y, double z, cs_vec3_t *out);
/* Dimensionless value (a cosine, a curve parameter) -> Q1.30, rounded to nearest.
 * CS_ERR_RANGE when not finite or outside the int32 range of the format ([-2, 2)). */
cs_err_t cs_conv_to_param(double v, cs_param_t *out);
/* Q1.30 -> double, exact. */
double cs_conv_param_to_double(cs_param_t p);
/* Rational weight -> cs_weight_t; CS_ERR_WEIGHT unless CS_WEIGHT_MIN <= result <= CS_WEIGHT_ONE
 * (the caller normalises the largest weight to 1 first). */
cs_err_t cs_conv_to_weight(double w, cs_weight_t *out);
/* Tolerance in mm -> cs_pos_t: CS_ERR_TOLERANCE unless it is finite, > 0 and at least 1 LSB
 * after rounding, and at most CS_POS_LIMIT. */
cs_err_t cs_conv_tol_to_pos(double mm, cs_pos_t *out);

#endif
