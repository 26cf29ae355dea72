/* cs_dsock: rules for the daemon's socket (see cs_dsock.h). */
#define _GNU_SOURCE /* struct ucred, SO_PEERCRED */
#include "cs_dsock.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

char *cs_dsock_default(char *buf, size_t cap)
{
    const char *rt = getenv("XDG_RUNTIME_DIR");
    if (rt != NULL && rt[0] == '/')
        snprintf(buf, cap, "%s/curvestep/curvestep.sock", rt);
    else
        snprintf(buf, cap, "/run/curvestep/curvestep.sock");
    return buf;
}

bool cs_dsock_uid_trusted(uid_t uid)
{
    return uid == geteuid() || uid == 0;
}

/* The directory part of path ("." for a bare name) into dir. */
static void dir_of(const char *path, char *dir, size_t cap)
{
    const char *slash = strrchr(path, '/');
    if (slash == NULL)
        snprintf(dir, cap, ".");
    else if (slash == path)
        snprintf(dir, cap, "/");
    else
        snprintf(dir, cap, "%.*s", (int)(slash - path), path);
}

bool cs_dsock_dir_ok(const char *path, char *err, size_t errcap)
{
    char dir[4096];
    dir_of(path, dir, sizeof dir);
    char dflt[4096];
    cs_dsock_default(dflt, sizeof dflt);
    if (strcmp(path, dflt) == 0 && mkdir(dir, 0700) != 0 && errno != EEXIST) {
        snprintf(err, errcap,
                 "%s: cannot create the socket's directory: %s (set XDG_RUNTIME_DIR "
                 "or give --socket in a directory of your own)",
                 dir, strerror(errno));
        return false;
    }
    struct stat st;
    if (lstat(dir, &st) != 0) {
        snprintf(err, errcap, "%s: %s", dir, strerror(errno));
        return false;
    }
    const char *why = S_ISLNK(st.st_mode)                       ? "is a symbolic link"
                      : !S_ISDIR(st.st_mode)                    ? "is not a directory"
                      : !cs_dsock_uid_trusted(st.st_uid)        ? "belongs to another user"
                      : (st.st_mode & (S_IWGRP | S_IWOTH)) != 0 ? "is writable by others"
                                                                : NULL;
    if (why != NULL) {
        snprintf(err, errcap,
                 "%s %s: refusing to put the daemon's socket there (another user "
                 "could take its place; docs/streaming.md)",
                 dir, why);
        return false;
    }
    return true;
}

bool cs_dsock_clear_stale(const char *path, char *err, size_t errcap)
{
    struct stat st;
    if (lstat(path, &st) != 0) {
        if (errno == ENOENT)
            return true;
        snprintf(err, errcap, "%s: %s", path, strerror(errno));
        return false;
    }
    if (!S_ISSOCK(st.st_mode) || st.st_uid != geteuid()) {
        snprintf(err, errcap, "%s exists and is not a socket of this user's: not removed", path);
        return false;
    }
    struct sockaddr_un a;
    memset(&a, 0, sizeof a);
    a.sun_family = AF_UNIX;
    snprintf(a.sun_path, sizeof a.sun_path, "%s", path);
    int probe = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (probe < 0) {
        snprintf(err, errcap, "socket: %s", strerror(errno));
        return false;
    }
    int rc = connect(probe, (struct sockaddr *)&a, sizeof a);
    int cerr = errno;
    close(probe);
    if (rc == 0) {
        snprintf(err, errcap, "%s: a daemon already answers there", path);
        return false;
    }
    if (cerr != ECONNREFUSED) {
        snprintf(err, errcap, "%s: %s: not removed", path, strerror(cerr));
        return false;
    }
    if (unlink(path) != 0) { /* a stale socket left by a daemon that died */
        snprintf(err, errcap, "%s: %s", path, strerror(errno));
        return false;
    }
    return true;
}

bool cs_dsock_peer_uid(int fd, uid_t *uid)
{
    struct ucred cr;
    socklen_t len = sizeof cr;
    if (getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &cr, &len) != 0 || len != sizeof cr)
        return false;
    *uid = cr.uid;
    return true;
}
