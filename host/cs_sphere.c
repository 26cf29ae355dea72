/* cs_sphere: exact sphere iso-curves and the ball-end scallop (see cs_sphere.h). */
#include "cs_sphere.h"

#include <math.h>

#include "cs_conv.h"
#include "cs_curvefile.h"

/* Fixed-point centre and semi-axes of an arc; CS_ERR_RANGE outside the range. */
static cs_err_t axes(const double c[3], const double u[3], const double v[3], cs_vec3_t out[3])
{
    if (cs_conv_mm_to_vec(c[0], c[1], c[2], &out[0]) != CS_OK ||
        cs_conv_mm_to_vec(u[0], u[1], u[2], &out[1]) != CS_OK ||
        cs_conv_mm_to_vec(v[0], v[1], v[2], &out[2]) != CS_OK)
        return CS_ERR_RANGE;
    return CS_OK;
}

cs_err_t cs_sphere_parallel(const cs_sphere_t *s, double off, double lat_deg,
                            cs_bezier_t out[CS_ARC_MAX_SEGMENTS], unsigned *n)
{
    if (!(lat_deg > -90 && lat_deg < 90))
        return CS_ERR_RANGE;
    double rho = s->r + off, la = lat_deg * M_PI / 180, rc = rho * cos(la);
    double c[3] = {s->c[0], s->c[1], s->c[2] + rho * sin(la)};
    double u[3] = {rc, 0, 0}, v[3] = {0, rc, 0};
    cs_vec3_t f[3];
    cs_err_t e = axes(c, u, v, f);
    return e == CS_OK ? cs_curvefile_arc(f, 0, 360, out, n) : e;
}

cs_err_t cs_sphere_meridian(const cs_sphere_t *s, double off, double lon_deg, double lat0,
                            double lat1, cs_bezier_t out[CS_ARC_MAX_SEGMENTS], unsigned *n)
{
    if (!(fabs(lat0) <= 90 && fabs(lat1) <= 90) || lat0 == lat1)
        return CS_ERR_RANGE;
    double rho = s->r + off, lo = lon_deg * M_PI / 180;
    double u[3] = {rho * cos(lo), rho * sin(lo), 0}, v[3] = {0, 0, rho};
    cs_vec3_t f[3];
    cs_err_t e = axes(s->c, u, v, f);
    return e == CS_OK ? cs_curvefile_arc(f, lat0, lat1, out, n) : e;
}

double cs_sphere_scallop(double r, double ball, double dtheta)
{
    double big = r + ball, s = big * sin(dtheta / 2);
    if (s >= ball)
        return HUGE_VAL; /* the balls do not overlap: the passes leave a full ridge */
    return big * cos(dtheta / 2) - sqrt(ball * ball - s * s) - r;
}

double cs_sphere_step(double r, double ball, double h)
{
    double lo = 0, hi = M_PI / 2;
    if (cs_sphere_scallop(r, ball, hi) <= h)
        return hi;
    while (hi - lo > 1e-12) {
        double mid = (lo + hi) / 2;
        if (cs_sphere_scallop(r, ball, mid) <= h)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}
