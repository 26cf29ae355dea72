/* cs_linktime: line timing in integer ticks (see cs_linktime.h). */
#include "cs_linktime.h"

#include "cs_frame.h"

uint32_t cs_linktime_chars(uint32_t n, uint32_t bits_per_char, uint32_t bits_per_s,
                           uint32_t tick_hz)
{
    if (bits_per_s == 0)
        return 0;
    /* n * bits * tick_hz can reach 2^96: split the bits into whole seconds and a remainder,
     * ticks = whole * tick_hz + ceil(rem * tick_hz / bps), each product below 2^64 */
    uint64_t bits = (uint64_t)n * bits_per_char;
    uint64_t whole = bits / bits_per_s, rem = bits % bits_per_s;
    if (whole > UINT32_MAX)
        return UINT32_MAX;
    uint64_t t = whole * tick_hz + (rem * tick_hz + bits_per_s - 1u) / bits_per_s;
    return t > UINT32_MAX ? UINT32_MAX : (uint32_t)t;
}

/* ceil(ms * tick_hz / 1000): ms below 1000, so it fits 32 bits for any tick_hz */
static uint32_t ms_ticks(uint32_t ms, uint32_t tick_hz)
{
    return (uint32_t)(((uint64_t)ms * tick_hz + 999u) / 1000u);
}

/* rto_max and give_up from rto (the backoff rule of cs_link.h): CS_ERR_RANGE past 32 bits. */
static cs_err_t set_backoff(cs_link_cfg_t *c, uint64_t rto, uint32_t nak_holdoff,
                            uint32_t tick_hz)
{
    uint64_t cap = ((uint64_t)CS_LINKTIME_RTO_MAX_MS * tick_hz + 999u) / 1000u;
    uint64_t rto_max = rto > cap ? rto : cap;
    uint64_t give_up = (uint64_t)CS_LINKTIME_GIVE_UP_S * tick_hz;
    if (give_up < 2u * rto_max)
        give_up = 2u * rto_max;
    if (give_up > UINT32_MAX)
        return CS_ERR_RANGE;
    c->rto = (uint32_t)rto;
    c->rto_max = (uint32_t)rto_max;
    c->give_up = (uint32_t)give_up;
    c->nak_holdoff = nak_holdoff;
    return CS_OK;
}

cs_err_t cs_linktime_link(cs_link_cfg_t *c, uint32_t bits_per_s, uint32_t tick_hz)
{
    if (c == NULL || tick_hz < 1000u)
        return CS_ERR_ARG;
    if (bits_per_s == 0)
        return set_backoff(c, ms_ticks(CS_LINKTIME_MEM_RTO_MS, tick_hz), 0, tick_hz);
    uint32_t windows = cs_linktime_chars(3u * CS_LINK_WINDOW * CS_FRAME_WIRE_MAX,
                                         CS_LINKTIME_BITS_8N1, bits_per_s, tick_hz);
    uint64_t rto = (uint64_t)ms_ticks(CS_LINKTIME_RTT_MS, tick_hz) + windows;
    if (windows == UINT32_MAX || rto > UINT32_MAX)
        return CS_ERR_RANGE;
    return set_backoff(
        c, rto, cs_linktime_chars(2u * CS_FRAME_WIRE_MAX, CS_LINKTIME_BITS_8N1, bits_per_s, tick_hz),
        tick_hz);
}
