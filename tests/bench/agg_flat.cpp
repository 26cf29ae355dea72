// agg_flat: agg::curve4_div behind a C function (see agg_flat.h).
//
// Tolerance mapping (agg_curves.cpp, AGG 2.4): curve4_div::init sets
//   m_distance_tolerance_square = (0.5 / approximation_scale)^2
// and recursive_bezier stops splitting a piece when
//   (d2 + d3)^2 <= m_distance_tolerance_square * |P4 - P1|^2,
// d2, d3 being |P1P4 x P1P2| and |P1P4 x P1P3|: the SUM of the distances of the two inner
// control points from the chord's line is at most 0.5 / approximation_scale. Choosing
// approximation_scale = 0.5 / tol_mm makes that distance tolerance equal tol_mm. (The piece is
// then represented by the midpoint of its inner control points, a vertex off the curve; the
// angle tolerance and cusp limit stay at their default 0 = off.)
#include "agg_flat.h"

#include <agg_curves.h>

extern "C" size_t agg_flatten_cubic(const double p[8], double tol_mm, double *out_xy, size_t cap)
{
    agg::curve4_div c;
    c.approximation_scale(0.5 / tol_mm);
    c.angle_tolerance(0.0);
    c.cusp_limit(0.0);
    c.init(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]);
    size_t n = 0;
    double x, y;
    unsigned cmd;
    c.rewind(0);
    while (!agg::is_stop(cmd = c.vertex(&x, &y))) {
        if (n < cap) {
            out_xy[2 * n] = x;
            out_xy[2 * n + 1] = y;
        }
        n++;
    }
    return n;
}
