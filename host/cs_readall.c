/* cs_readall: bounded whole-file reading (see cs_readall.h). */
#include "cs_readall.h"

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *kind_of(mode_t m)
{
    return S_ISDIR(m)    ? "a directory"
           : S_ISFIFO(m) ? "a FIFO"
           : S_ISCHR(m)  ? "a character device"
           : S_ISBLK(m)  ? "a block device"
           : S_ISSOCK(m) ? "a socket"
                         : "not a regular file";
}

/* Opens filename for reading; for regular_only, without blocking (O_NONBLOCK: opening a FIFO
 * with no writer would wait forever) and refusing what fstat says is not a regular file. */
static int open_input(const char *filename, bool regular_only, cs_path_loc_t loc,
                      cs_path_diag_t *diag)
{
    int fd = open(filename, O_RDONLY | O_NOCTTY | O_CLOEXEC | (regular_only ? O_NONBLOCK : 0));
    if (fd < 0) {
        cs_path_diag_set(diag, CS_ERR_IO, loc, "cannot open: %s", strerror(errno));
        return -1;
    }
    struct stat st;
    if (fstat(fd, &st) != 0) {
        cs_path_diag_set(diag, CS_ERR_IO, loc, "cannot stat: %s", strerror(errno));
        close(fd);
        return -1;
    }
    if (regular_only && !S_ISREG(st.st_mode)) {
        cs_path_diag_set(diag, CS_ERR_IO, loc, "%s, not a regular file: refused",
                         kind_of(st.st_mode));
        close(fd);
        return -1;
    }
    if (regular_only) /* a regular file never blocks: back to plain reads */
        (void)fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) & ~O_NONBLOCK);
    return fd;
}

/* Reads fd to its end or to max + 1 bytes into a growing buffer. */
static cs_err_t read_fd(int fd, size_t max, cs_path_loc_t loc, char **out, size_t *len,
                        cs_path_diag_t *diag)
{
    size_t cap = 1 << 16, n = 0;
    char *b = malloc(cap);
    for (;;) {
        if (b == NULL)
            return cs_path_diag_set(diag, CS_ERR_FULL, loc, "out of memory");
        if (n + 1 >= cap) {
            char *nb = cap < ((size_t)-1) / 2 ? realloc(b, cap * 2) : NULL;
            if (nb == NULL) {
                free(b);
                b = NULL;
                continue;
            }
            b = nb;
            cap *= 2;
        }
        size_t want = cap - 1 - n;
        if (want > max + 1 - n)
            want = max + 1 - n; /* never read (or hold) more than the limit and one byte */
        ssize_t got = read(fd, b + n, want);
        if (got < 0 && errno == EINTR)
            continue;
        if (got < 0) {
            free(b);
            return cs_path_diag_set(diag, CS_ERR_IO, loc, "read error: %s", strerror(errno));
        }
        if (got == 0)
            break;
        n += (size_t)got;
        if (n > max) {
            free(b);
            return cs_path_diag_set(diag, CS_ERR_RANGE, loc,
                                    "larger than the input limit of %zu MiB (--max-input-mb)",
                                    max >> 20 ? max >> 20 : 1);
        }
    }
    b[n] = '\0';
    *out = b;
    *len = n;
    return CS_OK;
}

cs_err_t cs_readall(const char *filename, size_t max_bytes, bool regular_only, char **buf,
                    size_t *len, cs_path_diag_t *diag)
{
    bool is_stdin = strcmp(filename, "-") == 0;
    cs_path_loc_t loc = {is_stdin ? "<stdin>" : filename, 0, 0};
    if (max_bytes == 0)
        max_bytes = CS_READALL_DEFAULT_MAX;
    int fd = is_stdin ? STDIN_FILENO : open_input(filename, regular_only, loc, diag);
    if (fd < 0)
        return diag->code;
    cs_err_t e = read_fd(fd, max_bytes, loc, buf, len, diag);
    if (!is_stdin)
        close(fd);
    return e;
}

cs_err_t cs_readall_keep_name(const char *filename, char **buf, size_t *len, char **name_out,
                              cs_path_diag_t *diag)
{
    cs_err_t e = cs_readall(filename, 0, false, buf, len, diag);
    if (e != CS_OK) {
        *name_out = strdup(strcmp(filename, "-") == 0 ? "<stdin>" : filename);
        diag->loc.file = *name_out ? *name_out : "-";
    }
    return e;
}

bool cs_readall_parse_mb(const char *s, size_t *bytes)
{
    char *end = NULL;
    errno = 0;
    unsigned long v = strtoul(s, &end, 10);
    if (s[0] < '0' || s[0] > '9' || *end != '\0' || errno != 0 || v < 1 || v > CS_READALL_MAX_MB)
        return false;
    *bytes = (size_t)v << 20;
    return true;
}

size_t cs_readall_bom(const char *buf, size_t len)
{
    return len >= 3 && (unsigned char)buf[0] == 0xEF && (unsigned char)buf[1] == 0xBB &&
                   (unsigned char)buf[2] == 0xBF
               ? 3
               : 0;
}

bool cs_readall_blank(const char *buf, size_t len)
{
    for (size_t i = cs_readall_bom(buf, len); i < len; i++)
        if (buf[i] != ' ' && buf[i] != '\t' && buf[i] != '\r' && buf[i] != '\n')
            return false;
    return true;
}
