/* cs_sim_draw: pictures of a simulated run. The exact geometry (reference) in thin black and the
 * executed path (reconstructed from the step edges, sampled every few ms) coloured by speed,
 * blue = slow to red = the run's top speed; as SVG written directly or PNG through cairo. */
#ifndef CS_SIM_DRAW_H
#define CS_SIM_DRAW_H

#include "cs_sim.h"

/* ref may be NULL. Return 0, or -1 (I/O or cairo error; errno / message on stderr). */
int cs_sim_draw_svg(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex,
                    const cs_sim_ref_t *ref);
/* width_px: picture width (height follows the drawing's aspect ratio). */
int cs_sim_draw_png(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex,
                    const cs_sim_ref_t *ref, int width_px);
/* Writes every step edge as CSV: t_s,axis,dir,x_mm,y_mm,z_mm (position after the step). */
int cs_sim_write_trace(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex);

#endif
