/* cs_dclevel: the waterline's level step by slope, from the cutter's section (cs_dclevel.h). */
#include "cs_dclevel.h"

#include <math.h>

#define DCL_NU    48  /* surface points between the two contacts */
#define DCL_NT    96  /* steps along each normal, up to the cap */
#define DCL_ITER  14  /* bisections of the level step */
#define DCL_TERN  60  /* ternary steps for the contact */

/* Where the cutter with its axis at 0 touches the line z = m x (m >= 0): the u in [0, R]
 * maximising m u - h(u), concave (h convex); returns that maximum, the tip's height. */
static double contact(const cs_dropcut_tool_t *t, double m, double *u)
{
    double lo = 0, hi = t->r_mm;
    for (int k = 0; k < DCL_TERN; k++) {
        double a = lo + (hi - lo) / 3, b = hi - (hi - lo) / 3;
        if (m * a - cs_dropcut_profile(t, a) < m * b - cs_dropcut_profile(t, b))
            lo = a;
        else
            hi = b;
    }
    *u = (lo + hi) / 2;
    return m * *u - cs_dropcut_profile(t, *u);
}

/* Is (x, z) inside the cutter with its axis at ax and its tip at height tip? */
static bool inside(const cs_dropcut_tool_t *t, double ax, double tip, double x, double z)
{
    double d = fabs(x - ax);
    return d <= t->r_mm && z >= tip + cs_dropcut_profile(t, d);
}

double cs_dclevel_left(const cs_dropcut_tool_t *t, double theta, double dz, double cap)
{
    double m = tan(theta), dx = dz / m, u0;
    double tip = contact(t, m, &u0);
    double n[2] = {-sin(theta), cos(theta)}, worst = 0;
    for (int i = 0; i <= DCL_NU; i++) {
        double u = u0 + dx * i / DCL_NU, left = cap;
        for (int k = 0; k <= DCL_NT; k++) {
            double s = cap * k / DCL_NT, x = u + s * n[0], z = m * u + s * n[1];
            if (inside(t, 0, tip, x, z) || inside(t, dx, tip + m * dx, x, z)) {
                left = s;
                break;
            }
        }
        worst = fmax(worst, left);
    }
    return worst;
}

void cs_dclevel_table(cs_dclevel_t *tab, const cs_dropcut_tool_t *t, double h_mm, double dz_max)
{
    for (int a = 0; a < CS_DCLEVEL_NANG; a++) {
        /* 90 degrees: a vertical wall, taken at 89.5 (the section needs a finite slope) */
        double th = fmin(a * 2.0, 89.5) * M_PI / 180, lo = 0, hi = dz_max;
        if (a == 0) {
            tab->dz[a] = 0;
            continue;
        }
        if (cs_dclevel_left(t, th, dz_max, 2 * h_mm) <= h_mm) {
            tab->dz[a] = dz_max;
            continue;
        }
        for (int k = 0; k < DCL_ITER; k++) {
            double mid = (lo + hi) / 2;
            if (cs_dclevel_left(t, th, mid, 2 * h_mm) <= h_mm)
                lo = mid;
            else
                hi = mid;
        }
        tab->dz[a] = lo;
    }
    for (int a = CS_DCLEVEL_NANG - 1; a-- > 0;)
        tab->dz[a] = fmin(tab->dz[a], tab->dz[a + 1]);
}

double cs_dclevel_at(const cs_dclevel_t *tab, double slope)
{
    double deg = atan(slope) * 180 / M_PI;
    int a = (int)floor(deg / 2);
    return tab->dz[a < 0 ? 0 : a >= CS_DCLEVEL_NANG ? CS_DCLEVEL_NANG - 1 : a];
}
