/* cs_readall: the one bounded whole-file reader every input reader uses (SVG, G-code, HP-GL,
 * patch and surface files). Reads a named file or standard input ("-") into one NUL-terminated
 * buffer and refuses, with a message naming the file, anything past a byte limit, so a hostile
 * input (a 10 GB file, /dev/zero, an endless pipe) costs at most the limit in memory. Optionally
 * refuses anything but a regular file without blocking on it (the daemon: a FIFO would freeze it).
 * Host only. */
#ifndef CS_READALL_H
#define CS_READALL_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_path.h"

/* The default input size limit: 64 MiB, far above any real job (the largest file in
 * ../shared/data is under 2 MB) and small enough to read whole into memory. docs/inputs.md. */
#define CS_READALL_DEFAULT_MAX ((size_t)64 << 20)
/* The largest limit --max-input-mb accepts (MiB): 4 GiB. */
#define CS_READALL_MAX_MB 4096u

/* Reads filename ("-": standard input, named "<stdin>" in messages) whole into *buf (malloc'd,
 * NUL-terminated, *len bytes without the NUL). max_bytes: the limit (0: CS_READALL_DEFAULT_MAX);
 * more is CS_ERR_RANGE "file:0:0: larger than the input limit of N MiB (--max-input-mb)" after
 * reading at most max_bytes + 1 bytes. regular_only: a name that is not a regular file (FIFO,
 * device, directory, socket) is CS_ERR_IO without opening it for a blocking read. CS_ERR_IO when
 * it cannot be opened or read; CS_ERR_FULL out of memory; diag's file is filename itself (the
 * caller keeps it alive while it uses diag). */
cs_err_t cs_readall(const char *filename, size_t max_bytes, bool regular_only, char **buf,
                    size_t *len, cs_path_diag_t *diag);

/* cs_readall with the default limit, for a reader whose result owns the file's name: on failure
 * *name_out = a malloc'd copy of the name shown ("<stdin>" for "-"; NULL out of memory), which
 * diag then points at, so the message outlives filename. */
cs_err_t cs_readall_keep_name(const char *filename, char **buf, size_t *len, char **name_out,
                              cs_path_diag_t *diag);

/* Bytes of the UTF-8 byte order mark at buf[0..len): 3 or 0. */
size_t cs_readall_bom(const char *buf, size_t len);
/* True when buf[0..len) holds nothing but a byte order mark and white space. */
bool cs_readall_blank(const char *buf, size_t len);

/* Parses the value of --max-input-mb (a whole number of MiB, 1..CS_READALL_MAX_MB) into *bytes.
 * False when it is not one. */
bool cs_readall_parse_mb(const char *s, size_t *bytes);

#endif
