/* cs_dsock: the daemon's UNIX socket, safe by default (docs/streaming.md, "Who may talk to the
 * daemon"). Owns the rules: where the default socket lives ($XDG_RUNTIME_DIR/curvestep/ or
 * /run/curvestep/, a directory created 0700), which directories a socket may be created in (owned
 * by the daemon's user or root, writable by nobody else: never /tmp), what may be removed before
 * binding (only a stale socket of the daemon's own user: nothing answers on it), and the peer
 * check both sides make (SO_PEERCRED: the same user, or root). Host only (Linux). */
#ifndef CS_DSOCK_H
#define CS_DSOCK_H

#include <stdbool.h>
#include <stddef.h>
#include <sys/types.h>

/* The default socket: $XDG_RUNTIME_DIR/curvestep/curvestep.sock when XDG_RUNTIME_DIR is an
 * absolute path, else /run/curvestep/curvestep.sock, into buf (cap bytes). Returns buf. */
char *cs_dsock_default(char *buf, size_t cap);

/* Makes sure the directory of path is fit to hold the daemon's socket: when it is the default
 * one (dir named "curvestep" under the runtime directory) and missing, creates it 0700; then
 * refuses (false, a sentence in err) a directory that is a symlink, is not owned by the
 * effective user or root, or is writable by group or others. */
bool cs_dsock_dir_ok(const char *path, char *err, size_t errcap);

/* Before bind: true when nothing is at path, or a stale socket owned by the effective user is
 * (nothing accepts on it; then removed). False, a sentence in err, for anything else: a
 * daemon answering, a socket of another user, a regular file, a directory... (never removed). */
bool cs_dsock_clear_stale(const char *path, char *err, size_t errcap);

/* The uid of the process at the other end of the connected UNIX socket fd (SO_PEERCRED).
 * False when the kernel cannot tell. */
bool cs_dsock_peer_uid(int fd, uid_t *uid);

/* True when a peer with this uid may talk to us: the same effective user, or root. */
bool cs_dsock_uid_trusted(uid_t uid);

#endif
