/* cs_sim_draw: pictures of a simulated run. The exact geometry (reference) in thin black and the
 * executed path (reconstructed from the step edges, sampled every few ms) coloured by speed,
 * blue = slow to red = the run's top cutting speed; travel moves (the reference's G0 moves and
 * the gaps between its elements) thin dashed grey; projected through a view (the machine's x y
 * by default, or top/front/side/iso); as SVG written directly or PNG through cairo. */
#ifndef CS_SIM_DRAW_H
#define CS_SIM_DRAW_H

#include <stdbool.h>

#include "cs_machine_ini.h"
#include "cs_motion.h"
#include "cs_sim.h"

/* A projection to the picture: picture x, y = rows of m applied to (x y z 1), mm. */
typedef struct {
    const char *name;
    double m[2][4];
    bool y_down; /* machine y drawn downwards (no view does now: SVG pages are turned y-up) */
} cs_sim_view_t;

/* The default: machine x, y, y up, seen from above (name "xy"). */
void cs_sim_view_default(cs_sim_view_t *v);
/* top (x y), front (x z), side (y z), iso (orthographic from (1, -1, 1)), y up; the same as
 * `curvestep toolpath --view`. false for anything else. */
bool cs_sim_view_parse(const char *s, cs_sim_view_t *v);
/* Machine point p (mm) -> picture coordinates (mm, y down as in SVG and cairo). */
void cs_sim_view_project(const cs_sim_view_t *v, const double p[3], double out[2]);

/* With a view. A reference with travel marks lets every executed sample be classified (travel
 * or cut, by the nearest reference piece ahead of a cursor that follows the job in order). */
int cs_sim_draw_svg_view(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex,
                         const cs_sim_ref_t *ref, const cs_sim_view_t *view);
int cs_sim_draw_png_view(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex,
                         const cs_sim_ref_t *ref, const cs_sim_view_t *view, int width_px);

/* The run's own pen, for the pictures: with a pen (mode z: down while z is nearer down_z than
 * up_z; mode servo: by the segments' pen events, up before the first) every pen-up sample is
 * drawn as travel (dashed grey, SVG class "travel", one polyline per pen-up stretch that moves
 * in x y) and every pen-down one as drawing, whatever the reference says; each servo setting is
 * marked where the run stood (SVG circles of class "pen-down", filled green, and "pen-up", open
 * red). pen NULL or mode none: as the _view functions. */
typedef struct {
    const cs_machine_pen_t *pen;  /* the machine's [pen] */
    const cs_motion_segs_t *segs; /* the segments run: their ticks and pen events */
} cs_sim_draw_pen_t;
int cs_sim_draw_svg_pen(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex,
                        const cs_sim_ref_t *ref, const cs_sim_view_t *view,
                        const cs_sim_draw_pen_t *pen);
int cs_sim_draw_png_pen(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex,
                        const cs_sim_ref_t *ref, const cs_sim_view_t *view, int width_px,
                        const cs_sim_draw_pen_t *pen);

/* The default view. ref may be NULL. Return 0, or -1 (I/O or cairo error; errno / message on
 * stderr). */
int cs_sim_draw_svg(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex,
                    const cs_sim_ref_t *ref);
/* width_px: picture width (height follows the drawing's aspect ratio). */
int cs_sim_draw_png(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex,
                    const cs_sim_ref_t *ref, int width_px);
/* Writes every step edge as CSV: t_s,axis,dir,x_mm,y_mm,z_mm (position after the step), and each
 * spindle / laser setting among them as t_s,s,duty,x_mm,y_mm,z_mm (duty 1/1000, 0 when off). */
int cs_sim_write_trace(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex);

#endif
