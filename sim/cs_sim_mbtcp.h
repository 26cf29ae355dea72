/* cs_sim_mbtcp: the simulator's Modbus TCP server (docs/modbus.md, "Several clients"). Owns the
 * listening socket, up to CS_SIM_MBTCP_CONNS connections at once, the MBAP framing (the core's
 * cs_modbus_mbap_parse: protocol id and length checked) and fair service: each round answers at
 * most one request per connection, in turn, so a client polling flat out gets no more than the
 * streaming host. A new connection beyond the limit closes one that never sent a request (the
 * oldest), else the one silent the longest; a connection whose length field is impossible, or
 * that does not read its answers, is closed; a frame whose protocol id is not 0 is dropped
 * unanswered. What a request means is the caller's
 * (cs_sim_mbtcp_app_t.handle). Host-side POSIX code (sockets, poll), single-threaded. */
#ifndef CS_SIM_MBTCP_H
#define CS_SIM_MBTCP_H

#include <signal.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Connections served at once (the streaming host, a panel, a logger, a few spares). */
#define CS_SIM_MBTCP_CONNS 8
/* Answers held back by the delay fault at once. */
#define CS_SIM_MBTCP_DELAYED 8

typedef struct {
    /* One request PDU (pdu[0..n)) for unit: writes the answer PDU into rsp (room for
     * CS_MODBUS_PDU_MAX bytes), *rn its length; returns when to send it, in seconds from now:
     * 0 at once, > 0 later (delay fault), < 0 never (another unit's request, a lost answer). */
    double (*handle)(void *ctx, uint8_t unit, const uint8_t *pdu, size_t n, uint8_t *rsp,
                     size_t *rn);
    /* Runs after every round (the motion); true ends the service. */
    bool (*tick)(void *ctx);
    /* True while the motion runs: the server then waits at most 1 ms for requests, else 5. */
    bool (*busy)(void *ctx);
    void *ctx;
} cs_sim_mbtcp_app_t;

typedef struct {
    uint64_t connections; /* accepted */
    uint64_t evicted;     /* closed to make room for a new one (see cs_sim_mbtcp_serve) */
    uint64_t bad_length;  /* closed: an MBAP length outside 2..254 */
    uint64_t bad_proto;   /* frames dropped: protocol id not 0 */
    uint64_t slow;        /* closed: did not read its answers (send buffer full) */
    unsigned most;        /* most connections open at once */
} cs_sim_mbtcp_stats_t;

/* Serves Modbus TCP on addr ("IPv4:PORT", port 0: any free port; the first line of standard
 * output is the address and port bound) until *stop or app->tick says so. Returns 0, 2 for a
 * malformed addr (message on stderr), 3 when it cannot listen. */
int cs_sim_mbtcp_serve(const char *addr, const cs_sim_mbtcp_app_t *app, volatile sig_atomic_t *stop,
                       cs_sim_mbtcp_stats_t *st);

#endif
