/* cs_dropcheck: an independent check of a 3-axis finishing path against the exact surface
 * (issue 20, `toolpath --check`). Shares nothing with the planner (cs_dropcut, cs_dcpath) but
 * the patch evaluator and the cutter's profile: the surface is sampled on a dense (u, v) grid of
 * every patch, in double; the path's chords are sampled at spacing <= step.
 *  - gouge: the deepest a surface sample lies inside the cutter's solid at a path sample,
 *    measured vertically (tip + h(d) - z < 0);
 *  - scallop: on a z-map of the region (spacing step, the dense triangles rasterised into it),
 *    the material's thickness over each node's surface point s along the surface normal there:
 *    how far the ray from s goes before it meets a cutter (sphere tracing against the exact
 *    solids), capped at twice H. On a plane with passes w apart this is the textbook cusp
 *    R - sqrt(R^2 - (w/2)^2) (tests/cli/test_dropcut_shapes.sh);
 *  - rest material: where more than H is left, how near any cutter from above can come to s:
 *    the ideal cutter, dropped onto the surface samples at z-map nodes within R + cap, no
 *    farther apart than 0.05 mm (the grayscale closing of the surface by the cutter), keeping
 *    the planner's stated margin m: dropped as K + B(m) (R + m, r + m) and raised by m, as the
 *    planner's gouge-free drop is defined (cs_dropcut.h), so "gouge-free within m". Where even that stays more than H away
 *    (slots narrower than the cutter, the foot of a wall, the gap between the teapot's lid and
 *    its rim) the node is unreachable, counted apart (nodes, area, depth). At such a node, and
 *    wherever the ideal cutter stays more than H / 4 off s (nearer, a lattice position may
 *    merely miss a touching cutter), the path is also measured from the point q of
 *    the ideal envelope nearest to s (along the envelope's normal there, away from s): the
 *    scallop is the smaller of the two thicknesses, i.e. the path comes within the scallop of the
 *    surface or of the best envelope any cutter of this shape can leave; the rest material
 *    under that envelope is reported apart (unreachable nodes; where the rest is <= H, corner
 *    nodes and the most material left over them).
 * Both are estimates from samples: a finer step only finds more. The scallop is measured where
 * the cutter lies over the surface all round (nodes farther than R from the rim of the
 * surface's projection): nearer the rim the floor (--min-z) or the rim itself holds the cutter
 * up, and beyond it is no material of the part; and not on walls (a neighbour's top more than
 * 5 steps away, slope > 5 as the planner's bound, or a sample of the node's cell that far above
 * the top: a thin lip seen through), counted apart. Host only. */
#ifndef CS_DROPCHECK_H
#define CS_DROPCHECK_H

#include <stddef.h>

#include "cs_dropcut.h"
#include "cs_surffile.h"

typedef struct {
    double gouge_mm;      /* deepest penetration found (0 when none) */
    double gouge_at[3];   /* where (the surface sample) */
    double gouge_tool[3]; /* the cutter's tip there */
    double scallop_mm;    /* largest material height left over a node with surface below */
    double scallop_at[2]; /* where */
    size_t surf_samples, path_samples, nodes;
    size_t walls; /* nodes left out of the scallop: a wall passes through them */
    size_t rest_nodes; /* nodes where even the ideal cutter leaves more than H: unreachable */
    double rest_mm;    /* the deepest such rest material, mm */
    double rest_at[2]; /* where */
    size_t corner_nodes;   /* reachable nodes (rest <= H) met from the ideal envelope above them */
    double corner_left_mm; /* the most material left over such a node, rest <= H, mm */
} cs_dropcheck_t;

/* Where cs_dropcheck_gaps measures: the z-map nodes within rad_mm of one of the n points. */
typedef struct {
    const double (*pts)[2]; /* xy, mm */
    size_t n;
    double rad_mm;
} cs_dropcheck_win_t;

/* Checks the passes (tip points pts[start[k] .. start[k + 1]), k < npass, mm) of tool t over sf
 * within the region box (x0 y0 x1 y1) at sampling step step_mm; nodes left more than h_mm get
 * the ideal envelope (rest material) of the cutter that keeps margin_mm off the surface (the
 * planner's stated margin). CS_ERR_FULL out of memory. */
cs_err_t cs_dropcheck_run(const cs_surffile_t *sf, const cs_dropcut_tool_t *t,
                          const double (*pts)[3], const size_t *start, size_t npass,
                          const double box[4], double step_mm, double h_mm, double margin_mm,
                          cs_dropcheck_t *out);

/* The gaps, no gouge test: *at (malloc'd, *nat points, the caller frees) gets the axis positions
 * (x, y, mm; the z-map nodes where the ideal cutter stands) from which a cutter dropped onto the
 * surface comes nearest to each node left more than h_mm beyond the best any cutter could do,
 * where one more cutter position closes the gap (the planner's fill-in, cs_dropcut_cmd.c);
 * only the nodes of window w are measured (NULL: all). CS_ERR_FULL out of memory. */
cs_err_t cs_dropcheck_gaps(const cs_surffile_t *sf, const cs_dropcut_tool_t *t,
                           const double (*pts)[3], const size_t *start, size_t npass,
                           const double box[4], double step_mm, double h_mm, double margin_mm,
                           const cs_dropcheck_win_t *w, cs_dropcheck_t *out, double (**at)[2],
                           size_t *nat);

#endif
