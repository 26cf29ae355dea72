/* cs_trace: turns one cs_bezier_t into chords within a tolerance, by one of three methods:
 * uniform forward differences (cs_fd), adaptive forward differences (cs_afd) or flatness
 * subdivision by de Casteljau (cs_subdiv). A pull iterator: the caller owns the state and
 * asks for one vertex at a time, so firmware can interpolate on board with bounded memory. */
#ifndef CS_TRACE_H
#define CS_TRACE_H

#include "cs_afd.h"
#include "cs_bezier.h"
#include "cs_ellarc.h"
#include "cs_fd.h"
#include "cs_fd3.h"
#include "cs_predict.h"
#include "cs_subdiv.h"

typedef enum {
    CS_TRACE_FD = 0,      /* uniform forward differences, step count from Wang's bound */
    CS_TRACE_AFD = 1,     /* adaptive forward differences (step doubling/halving) */
    CS_TRACE_SUBDIV = 2,  /* flatness subdivision: farthest flat chord by de Casteljau splits */
    CS_TRACE_PREDICT = 3, /* predicted step, verified by one direct sub-curve test (cs_predict);
                           * circle and ellipse pieces by the rotation recurrence (cs_ellarc) */
} cs_trace_method_t;

/* The method every caller uses unless told otherwise (flatten, plan, stream, the daemon, the
 * firmware's curves mode): near-greedy chord counts at a few tests per chord (docs/benchmarks.md).
 */
#define CS_TRACE_DEFAULT CS_TRACE_PREDICT

/* The state struct (cs_trace_t) is defined below by the tracing modules; its size is fixed at
 * compile time. Every vertex it yields lies on the curve to within 1 LSB, and every chord between
 * consecutive vertices (starting from P0) lies within tol of the exact curve. */
/* --- API every caller uses (host flatten, planner feed, firmware curves mode) --- */
/* Accepted chord tolerance, cs_pos_t LSB: 4 LSB (61 nm) to 4096 mm. The rounding budget of each
 * method is charged against it (docs/fixed-point.md). */
#define CS_TRACE_TOL_MIN 4
#define CS_TRACE_TOL_MAX CS_POS_LIMIT
/* Hard cap on vertices per curve: a tracer that would exceed it reports CS_ERR_DEPTH instead of
 * running on (none does for valid input: FD <= 2^(20+30), subdivision <= 2^depth). */
#define CS_TRACE_MAX_VERTICES ((uint32_t)1 << 26)

/* Which engine a cs_trace_t runs: rational curves asked for AFD, or for FD when they would need
 * more than 2^(60/n) uniform steps, are traced by the homogeneous reach subdivision (see
 * docs/fixed-point.md; until issue 18 the dyadic one, whose 6 KB stack cs_trace_t no longer
 * carries); CS_TRACE_SUBDIV runs the reach tracer, and so does CS_TRACE_PREDICT for
 * the curves cs_predict does not take (rational, degree > 3, not in a plane z = const). */
typedef enum {
    CS_TRACE_IMPL_FD = 0,
    CS_TRACE_IMPL_AFD = 1,
    CS_TRACE_IMPL_SUBDIV_DYADIC = 2, /* not run by cs_trace any more (cs_subdiv_t directly) */
    CS_TRACE_IMPL_SUBDIV_REACH = 3,
    CS_TRACE_IMPL_PREDICT = 4,
    CS_TRACE_IMPL_FD3 = 5, /* CS_TRACE_FD on a planar polynomial curve of degree <= 3 (cs_fd3) */
    CS_TRACE_IMPL_ELLARC = 6, /* CS_TRACE_PREDICT on a circle or ellipse piece (cs_ellarc) */
} cs_trace_impl_t;

/* Which tracers an image carries (compile-time, e.g. -DCS_TRACE_METHODS=CS_TRACE_WITH_PREDICT):
 * cs_trace_t holds the state of those only, and cs_trace_begin answers CS_ERR_UNSUPPORTED for
 * the others (and for curves whose fallback, the reach subdivision, is left out). Default: all.
 * Sizes on a 64-bit host: FD 872 bytes (its rational part; 216 for the planar path alone), AFD
 * 352, reach subdivision 288, predicted step 176. */
#define CS_TRACE_WITH_FD      1u /* cs_fd and cs_fd3 */
#define CS_TRACE_WITH_AFD     2u
#define CS_TRACE_WITH_SUBDIV  4u /* the reach subdivision: also the others' fallback */
#define CS_TRACE_WITH_PREDICT 8u
#ifndef CS_TRACE_METHODS
#define CS_TRACE_METHODS 15u
#endif

/* The tracing state: caller-owned, fixed size (the configured engine states; no dyadic stack). */
typedef struct {
    uint8_t method; /* cs_trace_method_t asked for */
    uint8_t impl;   /* cs_trace_impl_t running */
    bool done;
    uint32_t count; /* vertices returned so far */
    union {
#if CS_TRACE_METHODS & CS_TRACE_WITH_FD
        cs_fd_t fd;
        cs_fd3_t fd3;
#endif
#if CS_TRACE_METHODS & CS_TRACE_WITH_AFD
        cs_afd_t afd;
#endif
#if CS_TRACE_METHODS & CS_TRACE_WITH_SUBDIV
        cs_subdiv_reach_t reach;
#endif
#if CS_TRACE_METHODS & CS_TRACE_WITH_PREDICT
        cs_predict_t pr;
        cs_ellarc_t arc;
#endif
        uint8_t none; /* keeps the union valid when nothing is configured */
    } u;
} cs_trace_t;

/* Start tracing c with chord tolerance tol (cs_pos_t, > 0). CS_ERR_TOLERANCE when tol is
 * outside the accepted range; CS_ERR_ARG for an unknown method; CS_ERR_DEGREE, CS_ERR_RANGE,
 * CS_ERR_WEIGHT for a curve cs_bezier_init* would refuse. Bounded work; not meant for ISRs. */
cs_err_t cs_trace_begin(cs_trace_t *tr, const cs_bezier_t *c, cs_pos_t tol,
                        cs_trace_method_t method);
/* Next vertex after the previous one (the first call returns the first vertex after P0; the
 * last vertex is exactly P_n). CS_OK with *pt set, CS_END when the curve is finished, or an
 * error (overflow, depth) after which the iterator is finished. */
/* ISR-safe for CS_TRACE_FD (constant time per vertex inside a piece); the other methods do a
 * bounded amount of work per vertex. */
cs_err_t cs_trace_next(cs_trace_t *tr, cs_vec3_t *pt);

#endif
