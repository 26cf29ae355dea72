/* agg_flat: a C wrapper around AGG's agg::curve4_div (Debian libagg-dev) so the C benchmark
 * bench_peers can flatten a cubic with it. Owns the mapping from a distance tolerance in mm to
 * AGG's approximation_scale. Host/bench only (C++ inside, double precision). */
#ifndef AGG_FLAT_H
#define AGG_FLAT_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Flattens the planar cubic p = {x0, y0, x1, y1, x2, y2, x3, y3} (mm) with curve4_div at
 * distance tolerance tol_mm (> 0); writes the vertices, the start point first, as x, y pairs
 * to out_xy (room for cap vertices) and returns how many it produced (may exceed cap: then
 * only the first cap were written). Not thread-safe-relevant: no shared state. */
size_t agg_flatten_cubic(const double p[8], double tol_mm, double *out_xy, size_t cap);

#ifdef __cplusplus
}
#endif

#endif
