/* cs_grbl: the Grbl 1.1 front end (`curvestep grbl`). Serves one client at a time on a
 * pseudo-terminal or a TCP port with Grbl's text protocol (ok / error:N, the real-time bytes,
 * status reports, $ commands, $J= jogs), reads its G-code a line at a time (cs_grbl_gc), plans it
 * in chunks with the host planner and runs the chunks on a device over any link: the serial wire
 * protocol, Modbus TCP / RTU or GPIO (cs_grbl_dev). What is and is not supported:
 * docs/controller.md. Host only. */
#ifndef CS_GRBL_H
#define CS_GRBL_H

#include <stdbool.h>
#include <stdint.h>
#include <netinet/in.h>

#include "cs_joblink.h"
#include "cs_jobplan.h"

/* Grbl's serial receive buffer (RX_BUFFER_SIZE): what a character-counting sender fills. */
#define CS_GRBL_RX_SIZE 128
/* A chunk is planned and queued when it holds this many path elements... */
#define CS_GRBL_CHUNK_ELEMS 400
/* ... or when no line came for this long (the sender went idle). */
#define CS_GRBL_CHUNK_IDLE_MS 30

typedef struct {
    cs_joblink_cfg_t dev;  /* the device's link: --port DEV (--baud, --line-rate), --modbus-tcp,
                            * --modbus-rtu (--baud, --parity, --unit) or --gpio */
    cs_jobplan_opts_t job; /* --machine, --tol, --feed */
    const char *listen;    /* --listen [ADDR:]PORT; NULL: a pseudo-terminal */
    const char *link;      /* --link PATH: a symlink to the pty; NULL: none */
    const char *state;     /* --state FILE: work offsets kept across runs; NULL: none */
} cs_grbl_cfg_t;

/* --listen's value: [ADDR:]PORT, ADDR an IPv4 address (default 127.0.0.1), PORT 0..65535. False
 * when it is not one. */
bool cs_grbl_listen_parse(const char *spec, struct sockaddr_in *sa);
/* Runs until SIGINT or SIGTERM (the running chunk is then held and aborted). Prints the pty path
 * (or ADDR:PORT) on the first line of stdout. Returns CS_EXIT_OK, CS_EXIT_INPUT (machine file),
 * CS_EXIT_USAGE (bad --listen / --tol), CS_EXIT_INTERNAL (pty, socket, thread) or 4 (the port
 * cannot be opened). Not reentrant (installs signal handlers). */
int cs_grbl_serve(const cs_grbl_cfg_t *cfg);

#endif
