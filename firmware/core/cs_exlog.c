/* cs_exlog: FNV-1a 32 over segments and step edges (see cs_exlog.h). The constants are FNV's
 * 32-bit offset basis and prime (Fowler, Noll, Vo: "FNV hash", IETF draft-eastlake-fnv). */
#include "cs_exlog.h"

#define FNV_PRIME 16777619u

static uint32_t mix8(uint32_t h, uint8_t b)
{
    return (h ^ b) * FNV_PRIME;
}

static uint32_t mix32(uint32_t h, uint32_t v)
{
    for (unsigned k = 0; k < 4u; k++)
        h = mix8(h, (uint8_t)(v >> (8u * k)));
    return h;
}

void cs_exlog_segs_init(cs_exlog_segs_t *l)
{
    l->n = 0;
    l->hash = CS_EXLOG_HASH0;
}

void cs_exlog_edges_init(cs_exlog_edges_t *l)
{
    l->n = 0;
    l->hash = CS_EXLOG_HASH0;
    l->clock = 0;
    l->dir = 0;
}

void cs_exlog_segment(cs_exlog_segs_t *l, const cs_segment_t *s)
{
    uint32_t h = mix32(l->hash, s->ticks);
    for (unsigned i = 0; i < CS_AXES; i++)
        h = mix32(h, (uint32_t)s->steps[i]);
    l->hash = h;
    l->n++;
}

void cs_exlog_tick(cs_exlog_edges_t *l, const cs_stepper_out_t *o)
{
    uint8_t m = o->step_mask;
    if (m != 0) {
        l->hash = mix8(mix8(mix32(l->hash, l->clock), m), l->dir);
        for (; m != 0; m = (uint8_t)(m & (m - 1u)))
            l->n++;
    }
    l->dir = o->dir_mask;
    l->clock += o->next_ticks;
}
