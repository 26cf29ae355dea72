/* cs_daemon: the streaming daemon (`curvestep serve`) and its client side. The daemon keeps one
 * link (cs_joblink: a serial port kept open, a Modbus TCP/RTU device or GPIO lines), reads every
 * submitted job once (regular files only) and plans it whole at submit time, and streams the jobs
 * one at a time (each in a child process running the link's stream); clients talk to it over a
 * UNIX socket (mode 0600, in a directory of its own: cs_dsock) with the one-line text protocol of
 * docs/streaming.md. Host only.
 */
#ifndef CS_DAEMON_H
#define CS_DAEMON_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "cs_joblink.h"

/* How long a client waits for the daemon's reply, in seconds. */
#define CS_DAEMON_REPLY_S 600

/* Maximum length of a request line (the path included). */
#define CS_DAEMON_LINE_MAX 4400

typedef struct {
    /* the link, exactly one (a serial port is opened once and kept open; a Modbus connection
     * and the GPIO lines are opened for each job); link.machine_file is set from machine_file */
    cs_joblink_cfg_t link;
    const char *socket_path;  /* UNIX socket to create (0600); removed on exit */
    const char *machine_file; /* NULL: the built-in machine */
    FILE *log;                /* one line per event (job queued, started, ended); NULL: none */
    size_t max_input_bytes;   /* job file size limit (--max-input-mb); 0: cs_readall's default */
} cs_daemon_cfg_t;

/* Runs the daemon until SIGTERM or SIGINT (the running job is then held and aborted). Returns an
 * exit status: 0 after a clean stop, 1 bad machine file, 2 no link or two, 3 socket error (or a
 * daemon already answers on the socket), 4 the port cannot be opened. Not reentrant (installs signal handlers). */
int cs_daemon_serve(const cs_daemon_cfg_t *cfg);

/* The default socket path (cs_dsock_default): $XDG_RUNTIME_DIR/curvestep/curvestep.sock, else
 * /run/curvestep/curvestep.sock, into buf (cap bytes). Returns buf. */
char *cs_daemon_default_socket(char *buf, size_t cap);

/* Client: sends one request line (no newline) to the daemon at socket_path and copies its reply
 * to out. Returns 0 when the reply starts with "OK", 1 with "ERR", -1 when no daemon answers on
 * socket_path, or the process answering is not this user's or root's (SO_PEERCRED: nothing is
 * sent), or no reply comes within CS_DAEMON_REPLY_S (a sentence naming the path in err). */
int cs_daemon_request(const char *socket_path, const char *request, FILE *out, char *err,
                      size_t errcap);

#endif
