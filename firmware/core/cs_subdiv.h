/* cs_subdiv: flatness subdivision of a cs_bezier_t by de Casteljau (seed 003: "replace by the
 * chord P1P4 when d2 < eps and d3 < eps"), in homogeneous space so rational curves are handled.
 * Owns the homogeneous split, the proven flatness test and two tracers: dyadic subdivision with
 * an explicit fixed-depth stack, and "reach" (greedy-like farthest flat chord, no stack). */
#ifndef CS_SUBDIV_H
#define CS_SUBDIV_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_bezier.h"

/* Deepest split level (dyadic: stack entries; reach: halvings of the remaining curve before a
 * flat piece must be found). Each stack entry is one sizeof(cs_subdiv_hcurve_t) = 256 bytes:
 * build with -DCS_SUBDIV_MAX_DEPTH=4 on a 2 KB AVR. */
#ifndef CS_SUBDIV_MAX_DEPTH
#define CS_SUBDIV_MAX_DEPTH 24
#endif
/* Bisection steps refining the farthest flat parameter in reach mode (reach within 2^-10). */
#define CS_SUBDIV_REACH_STEPS 10
/* Rounding budget (LSB) charged against the tolerance: projecting control points to whole LSB
 * (<= sqrt(3)/2) plus the homogeneous splits' rounding (docs/fixed-point.md). */
#define CS_SUBDIV_SLACK_LSB 2
/* Accepted tolerance range, in cs_pos_t LSB. */
#define CS_SUBDIV_TOL_MIN (CS_SUBDIV_SLACK_LSB + 1)
#define CS_SUBDIV_TOL_MAX ((cs_pos_t)1 << 29)

/* A homogeneous control point: x, y, z = w * p in units of 2^-30 LSB (|.| <= 2^58), w in Q61.
 * A polynomial curve has w = 2^61 everywhere. */
typedef struct {
    int64_t x, y, z, w;
} cs_subdiv_hpt_t;

typedef struct {
    cs_subdiv_hpt_t p[CS_BEZIER_MAX_POINTS];
} cs_subdiv_hcurve_t;

/* The state both tracers share; alone, the reach tracer's whole state (312 bytes, no stack), so
 * cs_trace and firmware images that only reach never carry the dyadic stack. */
typedef struct {
    uint8_t degree;
    bool rational;
    bool reach; /* farthest-reach mode instead of dyadic subdivision */
    bool done;  /* the last vertex (P_n) was returned or an error happened */
    uint8_t sp; /* stack entries in use (dyadic) */
    uint8_t cur_depth;
    uint32_t thr;          /* largest accepted control-point distance to the chord, LSB */
    cs_param_t reach_prev; /* reach: the previous chord's share of the remaining curve */
    cs_vec3_t end;         /* P_n, returned exactly as the last vertex */
    cs_subdiv_hcurve_t cur;
} cs_subdiv_reach_t;

/* Either tracer: the shared state plus the dyadic tracer's explicit stack. */
typedef struct {
    cs_subdiv_reach_t b;
    cs_subdiv_hcurve_t stack[CS_SUBDIV_MAX_DEPTH];
    uint8_t depth[CS_SUBDIV_MAX_DEPTH];
} cs_subdiv_t;

/* Start tracing c (degree 1..7, polynomial or rational) with chord tolerance tol (LSB);
 * reach = true selects the farthest-reach tracer, false the dyadic one. CS_ERR_TOLERANCE,
 * CS_ERR_DEGREE, CS_ERR_RANGE, CS_ERR_WEIGHT for bad input. ISR-safe (no side effects). */
cs_err_t cs_subdiv_begin(cs_subdiv_t *s, const cs_bezier_t *c, cs_pos_t tol, bool reach);
/* Next vertex (see cs_trace_next): CS_OK, CS_END, or CS_ERR_DEPTH when a piece cannot be made
 * flat within CS_SUBDIV_MAX_DEPTH levels (nothing out of tolerance is ever returned). */
cs_err_t cs_subdiv_next(cs_subdiv_t *s, cs_vec3_t *pt);
/* The reach tracer alone, on its stack-free state: as cs_subdiv_begin(.., true) and
 * cs_subdiv_next. ISR-safe begin; next does bounded work (about 15 splits). */
cs_err_t cs_subdiv_reach_begin(cs_subdiv_reach_t *s, const cs_bezier_t *c, cs_pos_t tol);
cs_err_t cs_subdiv_reach_next(cs_subdiv_reach_t *s, cs_vec3_t *pt);

/* True when the chord P0-Pn of c is proven within tol (LSB) of the curve, with the same test
 * and rounding budget the tracers use (false for invalid input). */
bool cs_subdiv_is_flat(const cs_bezier_t *c, cs_pos_t tol);

/* True when the distance from p to the segment ab is <= thr, decided exactly (coordinates with
 * differences below 2^30, thr <= 2^30). Pure. */
bool cs_subdiv_dist_ok(const cs_vec3_t *p, const cs_vec3_t *a, const cs_vec3_t *b, uint32_t thr);
/* Homogeneous form of c (no checks: c must be valid). */
void cs_subdiv_to_homogeneous(const cs_bezier_t *c, cs_subdiv_hcurve_t *h);
/* Split h (degree n) at t in [0, CS_PARAM_ONE] into left [0, t] and right [t, 1] (either may
 * alias h; rounding <= 1/2 unit per de Casteljau level). */
void cs_subdiv_split(const cs_subdiv_hcurve_t *h, unsigned n, cs_param_t t,
                     cs_subdiv_hcurve_t *left, cs_subdiv_hcurve_t *right);
/* Real-space point of a homogeneous point, rounded to the nearest LSB. */
cs_err_t cs_subdiv_project(const cs_subdiv_hpt_t *h, bool rational, cs_vec3_t *out);

#endif
