/* cs_tripatch: triangular Bézier patches of degree 1..7 (seed 000, "Carreaux triangulaires de
 * Bézier"): p(u, v) = sum over i + j + k = n of n! / (i! j! k!) u^i v^j w^k S_ijk with
 * barycentric (u, v, w), w = 1 - u - v. Owns evaluation by barycentric de Casteljau and the
 * image of a straight domain segment (edges and iso-lines) as a cs_bezier_t, by blossoming. */
#ifndef CS_TRIPATCH_H
#define CS_TRIPATCH_H

#include <stdint.h>

#include "cs_bezier.h"
#include "cs_err.h"
#include "cs_fixed.h"

#define CS_TRIPATCH_MAX_DEGREE CS_BEZIER_MAX_DEGREE /* its lines are cs_bezier_t of degree n */
#define CS_TRIPATCH_MAX_POINTS ((CS_TRIPATCH_MAX_DEGREE + 1) * (CS_TRIPATCH_MAX_DEGREE + 2) / 2)

/* Control point S_ijk (k = n - i - j) is p[cs_tripatch_index(n, i, j)]: rows of constant i,
 * i = 0..n, each holding j = 0..n - i. Points inside CS_POS_LIMIT. */
typedef struct {
    uint8_t degree;
    cs_vec3_t p[CS_TRIPATCH_MAX_POINTS];
} cs_tripatch_t;

/* Index of S_ijk in p[] for degree n (i + j <= n; no check). Pure. */
unsigned cs_tripatch_index(unsigned n, unsigned i, unsigned j);
/* Patch of degree 1..3 (CS_ERR_DEGREE) from (n + 1)(n + 2) / 2 points in the order above
 * (CS_ERR_RANGE for a point outside CS_POS_LIMIT). */
cs_err_t cs_tripatch_init(cs_tripatch_t *t, unsigned degree, const cs_vec3_t *pts);
/* p(u, v) with w = 1 - u - v, u, v >= 0, u + v <= 1 (Q1.30; CS_ERR_ARG otherwise), by
 * barycentric de Casteljau on values with 28 guard bits: within 0.5 + 2^-25 LSB of the exact
 * value. Pure, ISR-safe. */
cs_err_t cs_tripatch_eval(const cs_tripatch_t *t, cs_param_t u, cs_param_t v, cs_vec3_t *out);
/* The curve s -> p((1 - s) a + s b) for domain points a = (ua, va), b = (ub, vb) (each inside
 * the triangle, CS_ERR_ARG otherwise), as a degree-n Bézier: control point m is the blossom
 * b(a^(n-m), b^m), rounded once (<= 0.5 + 2^-25 LSB). Edges come out exactly as the boundary
 * control points; a = (u0, 0), b = (u0, 1 - u0) is the iso-line u = u0. Pure. */
cs_err_t cs_tripatch_line(const cs_tripatch_t *t, cs_param_t ua, cs_param_t va, cs_param_t ub,
                          cs_param_t vb, cs_bezier_t *out);

#endif
