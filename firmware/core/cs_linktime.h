/* cs_linktime: the timing of a byte line, computed once for every end of it (the host's serial
 * and Modbus RTU links, the device application, the simulator): how long characters take on the
 * wire, and the reliable link's retransmission timeout and NAK hold-off derived from it
 * (docs/protocol.md 3.6). Integer arithmetic in the caller's ticks, rounded up (a timeout is
 * never shorter than the wire time it covers). Owns no state; every function is ISR-safe. */
#ifndef CS_LINKTIME_H
#define CS_LINKTIME_H

#include <stdint.h>

#include "cs_err.h"
#include "cs_link.h"

/* Bits of one character: 8N1 (start, 8 data, stop) for the framed serial protocol; Modbus RTU
 * sends 11 (start, 8 data, parity or a second stop, stop: Modbus over serial line V1.02, 2.5.1). */
#define CS_LINKTIME_BITS_8N1 10u
#define CS_LINKTIME_BITS_RTU 11u
/* The reliable link's margin for a round trip's latencies (USB-serial, scheduling): 40 ms. */
#define CS_LINKTIME_RTT_MS 40u
/* At memory speed (a pty): the first timeout is 5 ms (a damaged ACK is repaired at once). */
#define CS_LINKTIME_MEM_RTO_MS 5u
/* The doubled timeout stops growing at 1 s (or at rto, on a line so slow that rto is longer):
 * a peer back from a stall is heard again within a second. */
#define CS_LINKTIME_RTO_MAX_MS 1000u
/* Silence before the link is closed, on every line: 30 s, generous against a loaded machine
 * (a host or simulator starved of the CPU for seconds) and still a bounded wait for a dead one;
 * at least two capped timeouts on a line so slow that rto_max exceeds 15 s. */
#define CS_LINKTIME_GIVE_UP_S 30u

/* Ticks of tick_hz that n characters of bits_per_char bits take on a line of bits_per_s:
 * ceil(n * bits_per_char * tick_hz / bits_per_s), UINT32_MAX when that does not fit 32 bits,
 * 0 when bits_per_s is 0 (memory speed). ISR-safe. */
uint32_t cs_linktime_chars(uint32_t n, uint32_t bits_per_char, uint32_t bits_per_s,
                           uint32_t tick_hz);

/* The reliable link's timing for a line of bits_per_s (8N1; 0: a pty at memory speed) in ticks
 * of tick_hz (>= 1000): rto = 40 ms + three windows of the largest frame
 * (3 * CS_LINK_WINDOW * CS_FRAME_WIRE_MAX characters), nak_holdoff = two largest frames; at
 * memory speed rto = 5 ms, nak_holdoff 0 (every NAK rewinds: a round trip is shorter than any
 * useful hold-off). Both: rto_max = max(rto, 1 s), give_up = max(30 s, 2 * rto_max). keepalive
 * is left as it is (each end's own choice). CS_ERR_ARG for a NULL c or tick_hz < 1000,
 * CS_ERR_RANGE when a time does not fit 32 bits (c untouched then). ISR-safe. */
cs_err_t cs_linktime_link(cs_link_cfg_t *c, uint32_t bits_per_s, uint32_t tick_hz);

#endif
