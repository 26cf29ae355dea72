/* cs_sim: what the simulator measures. Runs step segments through the real executor
 * (cs_stepper) on the POSIX port in simulated time, keeps every STEP edge, and from the edges
 * alone reconstructs the executed path and measures it: final position, per-axis peak velocity
 * and acceleration (windowed estimator, docs/motion.md) and the largest distance to a reference
 * geometry given as polylines in double. Host only. */
#ifndef CS_SIM_H
#define CS_SIM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_machine.h"
#include "cs_path.h"
#include "cs_segment.h"
#include "port_posix.h"

/* A machine-control event of a simulated device run (cs_fw_ctl), where the machine was. */
typedef enum { CS_SIM_MARK_ALARM = 1, CS_SIM_MARK_PROBE = 2, CS_SIM_MARK_HOMED = 3 } cs_sim_mark_kind_t;
typedef struct {
    uint64_t t;    /* tick */
    uint8_t kind;  /* cs_sim_mark_kind_t */
    double p[3];   /* physical position, mm (the STEP/DIR lines) */
} cs_sim_mark_t;

typedef struct {
    port_posix_edge_t *edges; /* every step, time order (owned) */
    size_t n;
    cs_sim_mark_t *marks;         /* switch trips, probe contacts, axes homed (owned; may be 0) */
    size_t nmarks;
    port_posix_spindle_t *spins;  /* spindle / laser settings, time order (owned; may be 0) */
    size_t nspins;
    uint64_t end_tick;         /* when the executor went idle */
    int64_t pos[CS_AXES];      /* final position, steps (from the STEP/DIR lines) */
    int32_t exec_pos[CS_AXES]; /* the executor's own count */
} cs_sim_exec_t;

/* Executes n segments on a fresh executor (ring kept fed, no idle gaps) and records the edges.
 * CS_ERR_ARG for a segment that breaks the invariant, CS_ERR_FULL when out of memory. */
cs_err_t cs_sim_execute(const cs_machine_t *m, const cs_segment_t *s, size_t n, cs_sim_exec_t *ex);
void cs_sim_exec_free(cs_sim_exec_t *ex);

/* Windowed dynamics: each axis's step count is sampled every window W; v_k = (p_{k+1} - p_k)/W,
 * a_k = (v_{k+1} - v_k)/W, in mm/s and mm/s^2. Sampling a step train puts up to one step of
 * error on each sample, so the estimator's own error is at most 2 steps / W (velocity) and
 * 4 steps / W^2 (acceleration): the allowances the check adds to the limits. */
typedef struct {
    double window_s;
    double peak_rate[CS_AXES], peak_accel[CS_AXES];   /* measured, mm/s and mm/s^2 */
    double t_rate[CS_AXES], t_accel[CS_AXES];         /* when (s) */
    double rate_allow[CS_AXES], accel_allow[CS_AXES]; /* estimator error bound */
    bool rate_ok[CS_AXES], accel_ok[CS_AXES];
} cs_sim_dyn_t;

void cs_sim_dynamics(const cs_machine_t *m, const cs_sim_exec_t *ex, double window_s,
                     cs_sim_dyn_t *out);

/* Reference geometry: polylines in mm (3D), dense enough to stand for the exact curves. */
typedef struct {
    double *xyz;           /* 3 per point */
    unsigned char *travel; /* per point: 1 when the piece ending there is a travel (G0 or gap) */
    size_t n, cap;
    size_t *starts; /* first point of each polyline */
    size_t nlines, caplines;
} cs_sim_ref_t;

void cs_sim_ref_init(cs_sim_ref_t *r);
void cs_sim_ref_free(cs_sim_ref_t *r);
/* Starts a new polyline at p / appends p to the current one. CS_ERR_FULL on out of memory. */
cs_err_t cs_sim_ref_move(cs_sim_ref_t *r, const double p[3]);
cs_err_t cs_sim_ref_line(cs_sim_ref_t *r, const double p[3]);
/* Appends p as the end of a travel move (not drawn like a cut). CS_ERR_FULL on out of memory. */
cs_err_t cs_sim_ref_travel(cs_sim_ref_t *r, const double p[3]);

/* The job's exact geometry as dense polylines: from (0, 0, 0), a straight travel to every element
 * that does not start where the previous one ended (marked travel, as are rapid elements), then
 * each element sampled in double
 * (cs_path_eval_mm) every 0.005 mm of its control polygon (at least 64 pieces). *end gets the
 * last point (the job's final position). */
cs_err_t cs_sim_ref_from_path(cs_sim_ref_t *r, const cs_path_t *path, double end[3]);

/* Largest distance (mm) from any lattice point the executed path visits (the position after
 * every step edge, and the start) to the reference; *where gets that point (may be NULL). */
double cs_sim_deviation(const cs_machine_t *m, const cs_sim_exec_t *ex, const cs_sim_ref_t *r,
                        double where[3]);
/* One step, as a distance: sqrt(sum over axes of (1 / steps_per_mm)^2), mm (x, y, z). */
double cs_sim_step_mm(const cs_machine_t *m);

#endif
