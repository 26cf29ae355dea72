/* curve_cases: the planar test corpus (see curve_cases.h). */
#include "curve_cases.h"

#include <math.h>
#include <string.h>

double curve_cases_unit(uint64_t *state)
{
    uint64_t r = *state;
    r ^= r << 13;
    r ^= r >> 7;
    r ^= r << 17;
    *state = r;
    return (double)(r >> 11) * (1.0 / 9007199254740992.0);
}

static cs_pos_t mm(double v)
{
    return (cs_pos_t)lround(v * 65536.0);
}

cs_bezier_t curve_cases_planar(unsigned degree, const double (*p)[2], double z)
{
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = (uint8_t)degree;
    for (unsigned i = 0; i <= degree; i++) {
        c.p[i] = cs_fixed_vec(mm(p[i][0]), mm(p[i][1]), mm(z));
        c.w[i] = CS_WEIGHT_ONE;
    }
    return c;
}

cs_bezier_t curve_cases_random(uint64_t *state, unsigned degree, double box)
{
    double p[4][2];
    for (unsigned i = 0; i <= degree; i++)
        for (unsigned a = 0; a < 2; a++)
            p[i][a] = (curve_cases_unit(state) * 2 - 1) * box;
    return curve_cases_planar(degree, (const double(*)[2])p, (curve_cases_unit(state) * 2 - 1) * 10);
}

const curve_case_t curve_cases_hard[] = {
    {"coincident", 3, {{0, 0}, {0, 0}, {50, 20}, {50, 20}}},
    {"all points equal", 3, {{7, 7}, {7, 7}, {7, 7}, {7, 7}}},
    {"cusp", 3, {{0, 0}, {100, 100}, {0, 100}, {100, 0}}},
    {"loop", 3, {{0, 0}, {150, 100}, {-50, 100}, {100, 0}}},
    {"inflection", 3, {{0, 0}, {33, 50}, {66, -50}, {100, 0}}},
    {"collinear fold", 3, {{0, 0}, {100, 0}, {20, 0}, {60, 0}}},
    {"collinear fold back", 3, {{0, 0}, {100, 0}, {-50, 0}, {0, 0}}},
    {"closed loop (equal ends)", 3, {{0, 0}, {80, 60}, {-80, 60}, {0, 0}}},
    {"near-equal ends", 3, {{0, 0}, {80, 60}, {-80, 60}, {0.00002, 0}}},
    {"2 m S", 3, {{-1000, -500}, {-300, 900}, {400, -900}, {1000, 500}}},
    {"2 m loop", 3, {{-1000, 0}, {1500, 1500}, {-1500, 1500}, {1000, 0}}},
    {"worst-case coordinates", 3, {{-4096, -4096}, {4096, 4096}, {-4096, 4096}, {4096, -4096}}},
    {"1 um", 3, {{0, 0}, {0.001, 0.001}, {0.002, -0.001}, {0.003, 0}}},
    {"straight 8 m", 3, {{-4000, -4000}, {-1000, -1000}, {1000, 1000}, {4000, 4000}}},
    {"line", 1, {{-30, 5}, {70, -12}}},
    {"quadratic U turn", 2, {{0, 0}, {100, 1000}, {0.5, 0}}},
};
const size_t curve_cases_hard_n = sizeof curve_cases_hard / sizeof curve_cases_hard[0];
