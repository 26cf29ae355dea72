/* cs_dclevel: the level step a waterline may take on ground of a given slope (issue 20,
 * `toolpath --strategy waterline`). Two contours dz apart on a plane of slope angle theta lie
 * dx = dz / tan(theta) apart in xy; the material left between the two cutters standing on them is
 * measured in the vertical section across the contours, as the check measures it: along the
 * plane's normal from each surface point between the two contacts to the first cutter it meets.
 * The closed forms this reproduces (tested in tests/unit/test_dclevel.c):
 *  - ball R: the cutters' contacts lie s = dz / sin(theta) apart along the plane, the cusp is
 *    R - sqrt(R^2 - (s / 2)^2), so dz <= sin(theta) 2 sqrt(2RH - H^2) (xy gap <= cos(theta)
 *    times the flat-ground step-over);
 *  - flat end R: terraces dz high, their corner dz cos(theta) from the plane, covered while the
 *    xy gap is at most the cutter's diameter: dz <= min(H / cos(theta), 2R tan(theta));
 *  - bull-nose (R, r): the ball r's cusp on steep ground (contacts on the corner arc), the flat
 *    end's terrace of the flat part R - r on shallow ground; the section is computed, not a
 *    formula (the cusp between the corner arc of one cutter and the bottom of the next).
 * On level ground (theta -> 0) every form goes to 0: that ground is cut by flat-area passes
 * (cs_dcwater.h). Host only, double precision. */
#ifndef CS_DCLEVEL_H
#define CS_DCLEVEL_H

#include "cs_dropcut.h"

#define CS_DCLEVEL_NANG 46 /* slope angles 0, 2, ..., 90 degrees */

typedef struct {
    double dz[CS_DCLEVEL_NANG]; /* the level step allowed at each angle, mm, non-decreasing */
} cs_dclevel_t;

/* The material (mm, along the normal, at most cap) two cutters t whose contours lie dz apart in
 * z on a plane at theta radians (0 < theta < pi / 2) leave between their contacts. */
double cs_dclevel_left(const cs_dropcut_tool_t *t, double theta, double dz, double cap);
/* Fills tab for tool t: at each angle the largest level step <= dz_max leaving at most h_mm
 * (bisected to dz_max / 2^14), then made non-decreasing in the angle (the least from above). */
void cs_dclevel_table(cs_dclevel_t *tab, const cs_dropcut_tool_t *t, double h_mm, double dz_max);
/* The level step allowed on ground rising `slope` (mm / mm, >= 0): the table's entry at the
 * angle rounded down, so never more than the angle allows. */
double cs_dclevel_at(const cs_dclevel_t *tab, double slope);

#endif
