/* cs_pen: pen lifts for the inputs that have no pen height of their own (SVG, HP-GL). A drawing
 * is a list of strokes (subpaths, and any break in continuity inside one); with a [pen] mode = z
 * machine every stroke is drawn at down_z, and between strokes the pen rises to up_z in place,
 * travels at up_z and comes down in place, the Z moves at [pen] z_feed (rapid when 0). G-code
 * lifts its own pen on M3/M4/M5 (cs_gcode, cs_input_opts_t.pen_z) and does not come here.
 * Owns nothing beyond the call. Host only. */
#ifndef CS_PEN_H
#define CS_PEN_H

#include <stdbool.h>

#include "cs_machine_ini.h"
#include "cs_path.h"

/* True when element k of p starts a new stroke: the first element, a new subpath, a start away
 * from the previous element's end (exactly, in LSB), or a rapid element (travel, never drawn). */
bool cs_pen_stroke_starts(const cs_path_t *p, size_t k);

/* Rewrites *path for pen mode z: every drawn element's z raised by down_z (SVG and HP-GL
 * drawings lie at z = 0), before each stroke a Z move from up_z to down_z at the stroke's start,
 * after it a Z move back to up_z at its end; rapid elements travel at up_z. The path's own
 * travel between strokes (cs_motion_plan_path's rapid to an element's start) then happens at
 * up_z. Does nothing for a pen mode other than z. CS_ERR_FULL when out of memory,
 * CS_ERR_RANGE (diag names the element) when a raised point leaves the coordinate range; on
 * error *path is unchanged. */
cs_err_t cs_pen_lift_z(cs_path_t *path, const cs_machine_pen_t *pen, cs_path_diag_t *diag);

/* Number of pen lifts (strokes) in path: what cs_pen_lift_z brackets with Z moves. */
size_t cs_pen_strokes(const cs_path_t *path);

#endif
