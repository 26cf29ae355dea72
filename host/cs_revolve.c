/* cs_revolve: see cs_revolve.h. Double precision on the host; the core sees Bézier patches. */
#include "cs_revolve.h"

#include <math.h>

#include "cs_conv.h"

#define PI 3.14159265358979323846

double cs_revolve_arc_error(double phi)
{
    double k = 4.0 / 3.0 * tan(phi / 4);
    double c[4][2] = {
        {1, 0}, {1, k}, {cos(phi) + k * sin(phi), sin(phi) - k * cos(phi)}, {cos(phi), sin(phi)}};
    double worst = 0;
    for (int s = 0; s <= 512; s++) {
        double t = s / 512.0, m = 1 - t;
        double b[4] = {m * m * m, 3 * t * m * m, 3 * t * t * m, t * t * t};
        double x = 0, y = 0;
        for (int j = 0; j < 4; j++) {
            x += b[j] * c[j][0];
            y += b[j] * c[j][1];
        }
        worst = fmax(worst, fabs(sqrt(x * x + y * y) - 1));
    }
    return worst;
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

cs_err_t cs_revolve(const cs_bezier_t *profile, const double origin[3], const double axis[3],
                    const double ref[3], double sweep_deg, double tol_mm, cs_patch_t *out,
                    size_t max, size_t *n, double *dev_mm)
{
    if (!profile || !origin || !axis || !ref || !out || !n)
        return CS_ERR_ARG;
    if (profile->rational)
        return CS_ERR_UNSUPPORTED;
    if (profile->degree < 1 || profile->degree > 3)
        return CS_ERR_DEGREE;
    if (!(sweep_deg > 0 && sweep_deg <= 360) || !(tol_mm > 0))
        return CS_ERR_ARG;
    /* Orthonormal frame: a along the axis, e1 towards ref, e2 = a x e1. */
    double la = sqrt(dot3(axis, axis));
    if (!(la > 0))
        return CS_ERR_DEGENERATE;
    double a[3] = {axis[0] / la, axis[1] / la, axis[2] / la};
    double d = dot3(ref, a);
    double e1[3] = {ref[0] - d * a[0], ref[1] - d * a[1], ref[2] - d * a[2]};
    double l1 = sqrt(dot3(e1, e1));
    if (!(l1 > 1e-12 * sqrt(dot3(ref, ref))) || l1 == 0)
        return CS_ERR_DEGENERATE;
    for (int k = 0; k < 3; k++)
        e1[k] /= l1;
    double e2[3] = {a[1] * e1[2] - a[2] * e1[1], a[2] * e1[0] - a[0] * e1[2],
                    a[0] * e1[1] - a[1] * e1[0]};
    double rmax = 0;
    for (unsigned i = 0; i <= profile->degree; i++)
        rmax = fmax(rmax, fabs(cs_conv_pos_to_mm(profile->p[i].x)));
    /* Rounding: control points to 0.5 LSB each (the surface stays within 0.5 LSB), plus 0.5
     * LSB of margin for the profile's own rounding-free use. */
    double budget = tol_mm - 1.0 / CS_POS_ONE_MM;
    if (!(budget > 0))
        return CS_ERR_TOLERANCE;
    double sweep = sweep_deg * PI / 180;
    size_t arcs = (size_t)ceil(sweep_deg / 90.0);
    while (arcs <= CS_REVOLVE_MAX_ARCS &&
           rmax * cs_revolve_arc_error(sweep / (double)arcs) > budget)
        arcs++;
    if (arcs > CS_REVOLVE_MAX_ARCS)
        return CS_ERR_TOLERANCE;
    if (arcs > max)
        return CS_ERR_FULL;
    double phi = sweep / (double)arcs, k = 4.0 / 3.0 * tan(phi / 4);
    for (size_t s = 0; s < arcs; s++) {
        double t0 = phi * (double)s, t1 = s + 1 == arcs ? sweep : phi * (double)(s + 1);
        /* Unit-circle cubic from angle t0 to t1 in the (e1, e2) plane. */
        double c[4][2] = {{cos(t0), sin(t0)},
                          {cos(t0) - k * sin(t0), sin(t0) + k * cos(t0)},
                          {cos(t1) + k * sin(t1), sin(t1) - k * cos(t1)},
                          {cos(t1), sin(t1)}};
        cs_patch_t pt = {0};
        pt.deg_u = profile->degree;
        pt.deg_v = 3;
        for (unsigned i = 0; i <= profile->degree; i++) {
            double r = cs_conv_pos_to_mm(profile->p[i].x), h = cs_conv_pos_to_mm(profile->p[i].y);
            for (int j = 0; j < 4; j++) {
                double q[3];
                for (int x = 0; x < 3; x++)
                    q[x] = origin[x] + h * a[x] + r * (c[j][0] * e1[x] + c[j][1] * e2[x]);
                if (cs_conv_mm_to_vec(q[0], q[1], q[2], &pt.p[i][j]) != CS_OK)
                    return CS_ERR_RANGE;
            }
        }
        out[s] = pt;
    }
    *n = arcs;
    if (dev_mm)
        *dev_mm = rmax * cs_revolve_arc_error(phi) + 1.0 / CS_POS_ONE_MM;
    return CS_OK;
}
