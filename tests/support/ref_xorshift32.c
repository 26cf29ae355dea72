/* ref_xorshift32: see ref_xorshift32.h. */
#include "ref_xorshift32.h"

uint32_t ref_xorshift32_next(ref_xorshift32_t *g)
{
    g->s ^= g->s << 13;
    g->s ^= g->s >> 17;
    g->s ^= g->s << 5;
    return g->s;
}

double ref_xorshift32_uniform(ref_xorshift32_t *g, double lo, double hi)
{
    return lo + (hi - lo) * (ref_xorshift32_next(g) / 4294967296.0);
}
