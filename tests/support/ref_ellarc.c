/* ref_ellarc: see ref_ellarc.h. */
#include "ref_ellarc.h"

#include <math.h>

void ref_ellarc_point(const ref_ellarc_t *e, double phi, double p[2])
{
    for (int i = 0; i < 2; i++)
        p[i] = e->c[i] + e->u[i] * cos(phi) + e->v[i] * sin(phi);
}

/* Distance of p from the segment [a, b]. */
static double seg_dist(const double p[2], const double a[2], const double b[2])
{
    double dx = b[0] - a[0], dy = b[1] - a[1], l2 = dx * dx + dy * dy;
    double t = l2 > 0 ? ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy);
}

static double dist_at(const ref_ellarc_t *e, double phi, const double a[2], const double b[2])
{
    double p[2];
    ref_ellarc_point(e, phi, p);
    return seg_dist(p, a, b);
}

double ref_ellarc_chord_dev(const ref_ellarc_t *e, double f0, double f1)
{
    double a[2], b[2];
    ref_ellarc_point(e, f0, a);
    ref_ellarc_point(e, f1, b);
    const double g = 0.6180339887498949;
    double lo = f0, hi = f1, x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
    double d1 = dist_at(e, x1, a, b), d2 = dist_at(e, x2, a, b);
    for (int i = 0; i < 60; i++) {
        if (d1 > d2) {
            hi = x2, x2 = x1, d2 = d1, x1 = hi - g * (hi - lo);
            d1 = dist_at(e, x1, a, b);
        } else {
            lo = x1, x1 = x2, d1 = d2, x2 = lo + g * (hi - lo);
            d2 = dist_at(e, x2, a, b);
        }
    }
    return fmax(d1, d2);
}

size_t ref_ellarc_greedy(const ref_ellarc_t *e, double tol)
{
    size_t n = 0;
    for (double f = 0; f < e->sweep; n++) {
        double lo = f, hi = e->sweep;
        if (ref_ellarc_chord_dev(e, f, hi) > tol) {
            for (int i = 0; i < 50; i++) {
                double mid = 0.5 * (lo + hi);
                if (ref_ellarc_chord_dev(e, f, mid) <= tol)
                    lo = mid;
                else
                    hi = mid;
            }
            hi = lo;
        }
        f = hi;
    }
    return n;
}
