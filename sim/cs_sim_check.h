/* cs_sim_check: the simulator's geometric check of a run against its job, through the spatial
 * index (cs_sim_grid) so that a 200,000-segment job takes seconds. Without a pen (a CAM job) every
 * position the steps visit is measured in 3D against the whole reference, travel included. With
 * a pen ([pen] mode = z: the pen is down when z is nearer down_z than up_z; mode = servo: by the
 * segments' pen events) only the drawing is
 * measured, in x y: each pen-down position reached by an x y move must lie on a drawn piece of the
 * reference (else a pen-down travel), and each point of a drawn piece must be reached pen down
 * (else a stroke drawn pen up); a failure names the segment (its 1-based number in the segments
 * file). Owns nothing beyond the call. Host only. */
#ifndef CS_SIM_CHECK_H
#define CS_SIM_CHECK_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_machine_ini.h"
#include "cs_motion.h"
#include "cs_sim.h"

typedef struct {
    double dev;       /* largest distance of a measured position to the (drawn) reference */
    double dev_at[3]; /* where (mm) */
    size_t dev_seg;   /* in which segment (1-based; 0: the start) */
    bool pen;         /* a plotter check (the two below are filled) */
    double undrawn;   /* largest distance of a drawn reference point to any pen-down position */
    double undrawn_at[3];
    size_t undrawn_seg; /* the segment that passes nearest to it (1-based) */
    size_t pen_downs;   /* pen lowerings seen in the run */
} cs_sim_check_t;

/* Measures run ex of the segments segs on m against ref with pen (NULL or mode none: the 3D
 * check; mode servo: the pen is down after a pen event of pulse down_us, up before the first
 * event and after one of up_us). CS_ERR_FULL when out of memory. */
cs_err_t cs_sim_check(const cs_machine_t *m, const cs_motion_segs_t *segs, const cs_sim_exec_t *ex,
                      const cs_sim_ref_t *ref, const cs_machine_pen_t *pen, cs_sim_check_t *out);
/* Runs cs_sim_check and prints its lines (deviation, pen-downs and strokes reached with a pen,
 * the final position ex->pos against the job's end `end` mm rounded to steps): true when all
 * hold. false (and a message on stderr) when out of memory. */
bool cs_sim_check_print(const cs_machine_t *m, const cs_motion_segs_t *segs,
                        const cs_sim_exec_t *ex, const cs_sim_ref_t *ref,
                        const cs_machine_pen_t *pen, const double end[3]);

#endif
