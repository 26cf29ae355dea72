/* curvestep serve | submit | status | pause | resume | cancel: the streaming daemon (cs_daemon)
 * and the commands that talk to it over its UNIX socket (docs/streaming.md, "The daemon"). */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_cmd.h"
#include "cs_daemon.h"
#include "cs_jobopts.h"
#include "cs_readall.h"
#include "cs_serial.h"

/* Exit status of the clients beyond the shared ones: no daemon answers on the socket. */
enum { EXIT_NO_DAEMON = 4 };

static void serve_usage(FILE *f)
{
    char sock[256];
    fprintf(f,
            "usage: curvestep serve --port DEV | --modbus-tcp HOST:PORT | --modbus-rtu DEV\n"
            "                       [--baud N] [--parity none|even|odd] [--unit ID]\n"
            "                       [--machine FILE.ini] [--socket PATH] [--max-input-mb N]\n"
            "Streams the jobs submitted to it over one link, one at a time, in the order they\n"
            "came (as `curvestep stream` does: read once and planned whole at submit time, then\n"
            "streamed with the protocol of docs/protocol.md, or over Modbus as in\n"
            "docs/modbus.md). Clients talk to it on the UNIX socket PATH, created with mode 0600\n"
            "(owner only): curvestep submit, status, pause, resume, cancel. One line per event\n"
            "on standard error.\n"
            "SIGTERM or SIGINT stops it: the running job is held, then aborted.\n"
            "  --port DEV      serial device, kept open (one link is required)\n"
            "  --modbus-tcp HOST:PORT  a Modbus TCP device (connected for each job)\n"
            "  --modbus-rtu DEV        a Modbus RTU device on serial line DEV (opened each job)\n"
            "  --baud N        line speed of --port and --modbus-rtu (default 115200)\n"
            "  --parity P      Modbus RTU: even (default, 8E1), odd (8O1), none (8N2)\n"
            "  --unit ID       Modbus unit id, 1..247 (default 1)\n"
            "  --machine FILE  machine description (default: the built-in plotter)\n"
            "  --max-input-mb N  refuse a submitted job file larger than N MiB (default 64)\n"
            "  --socket PATH   the socket (default %s); its directory must belong to\n"
            "                  this user or root and be writable by nobody else (never /tmp);\n"
            "                  only a stale socket of this user's is ever removed there\n"
            "Only this user's (and root's) clients are answered (docs/streaming.md).\n"
            "Exit status: 0 stopped by a signal; 1 bad machine file; 2 bad command line;\n"
            "3 the socket cannot be created (unsafe directory, something else at PATH) or a\n"
            "daemon already answers on it; 4 the port cannot be opened.\n",
            cs_daemon_default_socket(sock, sizeof sock));
}

static int parse_baud(const char *s, uint32_t *out)
{
    char *end;
    errno = 0;
    unsigned long v = strtoul(s, &end, 10);
    if (*s == '\0' || *s == '-' || *end != '\0' || errno != 0 || v > 4000000 ||
        !cs_serial_baud_ok((uint32_t)v))
        return -1;
    *out = (uint32_t)v;
    return 0;
}

int cs_cmd_serve(int argc, char **argv)
{
    char sock[256];
    cs_daemon_cfg_t cfg = {.baud = 115200, .unit = 1, .log = stderr};
    cfg.socket_path = cs_daemon_default_socket(sock, sizeof sock);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        bool has = i + 1 < argc;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            serve_usage(stdout);
            return CS_EXIT_OK;
        } else if (strcmp(a, "--port") == 0 && has) {
            cfg.port = argv[++i];
        } else if (strcmp(a, "--modbus-tcp") == 0 && has) {
            cfg.modbus_tcp = argv[++i];
        } else if (strcmp(a, "--modbus-rtu") == 0 && has) {
            cfg.modbus_rtu = argv[++i];
        } else if (strcmp(a, "--parity") == 0 && has) {
            const char *v = argv[++i];
            cfg.parity = strcmp(v, "none") == 0   ? 'N'
                         : strcmp(v, "even") == 0 ? 'E'
                         : strcmp(v, "odd") == 0  ? 'O'
                                                  : 0;
            if (cfg.parity == 0) {
                fprintf(stderr, "curvestep serve: --parity wants none, even or odd\n");
                return CS_EXIT_USAGE;
            }
        } else if (strcmp(a, "--unit") == 0 && has) {
            char *end;
            long v = strtol(argv[++i], &end, 10);
            if (*end != '\0' || v < 1 || v > 247) {
                fprintf(stderr, "curvestep serve: --unit wants a Modbus unit id, 1..247\n");
                return CS_EXIT_USAGE;
            }
            cfg.unit = (int)v;
        } else if (strcmp(a, "--socket") == 0 && has) {
            cfg.socket_path = argv[++i];
        } else if (strcmp(a, "--machine") == 0 && has) {
            cfg.machine_file = argv[++i];
        } else if (strcmp(a, "--max-input-mb") == 0 && has) {
            if (!cs_readall_parse_mb(argv[++i], &cfg.max_input_bytes)) {
                fprintf(stderr,
                        "curvestep serve: --max-input-mb wants a whole number of MiB, "
                        "1 to %u\n",
                        CS_READALL_MAX_MB);
                return CS_EXIT_USAGE;
            }
        } else if (strcmp(a, "--baud") == 0 && has) {
            if (parse_baud(argv[++i], &cfg.baud) != 0) {
                fprintf(stderr, "curvestep serve: --baud wants a termios rate (e.g. 115200)\n");
                return CS_EXIT_USAGE;
            }
        } else {
            fprintf(stderr, "curvestep serve: unknown or incomplete option %s\n", a);
            serve_usage(stderr);
            return CS_EXIT_USAGE;
        }
    }
    if ((cfg.port != NULL) + (cfg.modbus_tcp != NULL) + (cfg.modbus_rtu != NULL) != 1) {
        fprintf(stderr, "curvestep serve: give one link: --port DEV, --modbus-tcp HOST:PORT or "
                        "--modbus-rtu DEV\n");
        serve_usage(stderr);
        return CS_EXIT_USAGE;
    }
    return cs_daemon_serve(&cfg);
}

/* The client commands: name, one-line synopsis, description. */
static void client_usage(FILE *f, const char *name)
{
    char sock[256];
    cs_daemon_default_socket(sock, sizeof sock);
    if (strcmp(name, "submit") == 0)
        fprintf(f, "usage: curvestep submit [--socket PATH] [--mode segments|curves] [--tol MM]\n"
                   "                        [--feed MM/S] [--font FILE.jhf] [input and layout\n"
                   "                        options] FILE\n"
                   "Queues the job FILE (SVG, G-code or HPGL) on the daemon (`curvestep serve`).\n"
                   "The daemon reads and plans it whole now: a bad file is refused at once with\n"
                   "file:line:col: reason. Prints the job's number. Options as for `stream`;\n"
                   "--font FILE.jhf: the stroke font for SVG <text> and HP-GL LB (read by the\n"
                   "daemon at submit; a file that is not a font is refused, file:line:col).\n");
    else if (strcmp(name, "status") == 0)
        fprintf(f, "usage: curvestep status [--socket PATH]\n"
                   "Prints the daemon's device and whether its queue is paused, then one line per\n"
                   "job: number, state (queued, running, done, failed, cancelled), file, messages\n"
                   "executed of the job's total (updated once a second), and how it ended.\n");
    else if (strcmp(name, "pause") == 0)
        fprintf(f, "usage: curvestep pause [--socket PATH]\n"
                   "Holds the running job (the device decelerates and stops, keeping its queue)\n"
                   "and starts no other job until `curvestep resume`.\n");
    else if (strcmp(name, "resume") == 0)
        fprintf(f, "usage: curvestep resume [--socket PATH]\n"
                   "Resumes the held job and the queue.\n");
    else
        fprintf(f, "usage: curvestep cancel [--socket PATH] [JOB]\n"
                   "Cancels job number JOB (default: the running one): a queued job is dropped;\n"
                   "the running one is held, then aborted (the device flushes its queue) and the\n"
                   "next job starts.\n");
    if (strcmp(name, "submit") == 0)
        cs_jobopts_help(f); /* sent along; the daemon's machine decides --fit and the defaults */
    fprintf(f,
            "  --socket PATH   the daemon's socket (default %s)\n"
            "Exit status: 0 the daemon said OK; 1 it refused the request (the reason is\n"
            "printed; for a bad job file: file:line:col: reason); 2 bad command line; 4 no\n"
            "daemon answers on the socket, or the process there is not this user's or root's.\n",
            sock);
}

static int client(int argc, char **argv, const char *verb)
{
    const char *name = argv[0];
    char sock[256];
    const char *socket_path = cs_daemon_default_socket(sock, sizeof sock);
    const char *file = NULL, *mode = NULL, *tol = NULL, *feed = NULL, *job = NULL, *font = NULL;
    bool submit = strcmp(name, "submit") == 0, cancel = strcmp(name, "cancel") == 0;
    cs_jobopts_t in; /* sent as SUBMIT words; the daemon reads and lays out the job */
    cs_jobopts_init(&in);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        bool has = i + 1 < argc;
        int r = submit ? cs_jobopts_option(name, argc, argv, &i, &in) : 0;
        if (r < 0)
            return CS_EXIT_USAGE;
        if (r > 0)
            continue;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            client_usage(stdout, name);
            return CS_EXIT_OK;
        } else if (strcmp(a, "--socket") == 0 && has) {
            socket_path = argv[++i];
        } else if (submit && strcmp(a, "--mode") == 0 && has) {
            mode = argv[++i];
            if (strcmp(mode, "segments") != 0 && strcmp(mode, "curves") != 0) {
                fprintf(stderr, "curvestep submit: --mode wants segments or curves\n");
                return CS_EXIT_USAGE;
            }
        } else if (submit && strcmp(a, "--tol") == 0 && has) {
            tol = argv[++i];
            char *end;
            if (!(strtod(tol, &end) > 0) || *end != '\0' || strchr(tol, ' ')) {
                fprintf(stderr, "curvestep submit: --tol wants a positive number of mm\n");
                return CS_EXIT_USAGE;
            }
        } else if (submit && strcmp(a, "--feed") == 0 && has) {
            feed = argv[++i];
            char *end;
            double v = strtod(feed, &end);
            if (!(v > 0) || v >= 32768 || *end != '\0') {
                fprintf(stderr, "curvestep submit: --feed wants a speed in (0, 32768) mm/s\n");
                return CS_EXIT_USAGE;
            }
        } else if (submit && strcmp(a, "--font") == 0 && has) {
            font = argv[++i];
        } else if (a[0] == '-' && a[1] != '\0') {
            fprintf(stderr, "curvestep %s: unknown or incomplete option %s\n", name, a);
            client_usage(stderr, name);
            return CS_EXIT_USAGE;
        } else if (submit && file == NULL) {
            file = a;
        } else if (cancel && job == NULL) {
            char *end;
            unsigned long v = strtoul(a, &end, 10);
            if (*a == '\0' || *a == '-' || *end != '\0' || v == 0 || v > UINT_MAX) {
                fprintf(stderr, "curvestep cancel: JOB is a job number (see `status`)\n");
                return CS_EXIT_USAGE;
            }
            job = a;
        } else {
            fprintf(stderr, "curvestep %s: unexpected argument %s\n", name, a);
            client_usage(stderr, name);
            return CS_EXIT_USAGE;
        }
    }
    char req[CS_DAEMON_LINE_MAX];
    if (submit) {
        if (file == NULL) {
            fprintf(stderr, "curvestep submit: no job file\n");
            client_usage(stderr, name);
            return CS_EXIT_USAGE;
        }
        char abs[PATH_MAX];
        if (realpath(file, abs) == NULL) {
            fprintf(stderr, "%s:0:0: cannot open the job file (%s)\n", file, strerror(errno));
            return CS_EXIT_INPUT;
        }
        if (cs_jobopts_check(name, &in) != 0)
            return CS_EXIT_USAGE;
        /* the font goes by its absolute path, one word: the daemon reads it at submit */
        char fabs[PATH_MAX] = "";
        if (font != NULL && realpath(font, fabs) == NULL) {
            fprintf(stderr, "%s:0:0: cannot open the font (%s)\n", font, strerror(errno));
            return CS_EXIT_INPUT;
        }
        if (strpbrk(fabs, " \t\n") != NULL) {
            fprintf(stderr, "%s:0:0: a font path with blanks cannot be sent to the daemon\n", font);
            return CS_EXIT_INPUT;
        }
        int k = snprintf(req, sizeof req, "SUBMIT%s%s%s%s%s%s%s%s%s %s", mode ? " mode=" : "",
                         mode ? mode : "", tol ? " tol=" : "", tol ? tol : "", feed ? " feed=" : "",
                         feed ? feed : "", font ? " font=" : "", fabs, in.words, abs);
        if (k < 0 || (size_t)k >= sizeof req || strchr(abs, '\n')) {
            fprintf(stderr, "%s:0:0: path too long or not on one line\n", file);
            return CS_EXIT_INPUT;
        }
    } else {
        snprintf(req, sizeof req, "%s%s%s", verb, job ? " " : "", job ? job : "");
    }
    char err[512];
    char *reply = NULL;
    size_t rlen = 0;
    FILE *out = open_memstream(&reply, &rlen);
    if (out == NULL) {
        fprintf(stderr, "curvestep %s: out of memory\n", name);
        return CS_EXIT_INTERNAL;
    }
    int rc = cs_daemon_request(socket_path, req, out, err, sizeof err);
    fclose(out);
    /* OK replies on standard output; a refusal on standard error, without the "ERR " */
    if (rc == 0)
        fputs(reply, stdout);
    else if (rc > 0)
        fputs(strncmp(reply, "ERR ", 4) == 0 ? reply + 4 : reply, stderr);
    free(reply);
    fflush(stdout);
    if (rc < 0) {
        fprintf(stderr, "curvestep %s: %s\n", name, err);
        return EXIT_NO_DAEMON;
    }
    return rc == 0 ? CS_EXIT_OK : CS_EXIT_INPUT;
}

int cs_cmd_submit(int argc, char **argv)
{
    return client(argc, argv, "SUBMIT");
}
int cs_cmd_status(int argc, char **argv)
{
    return client(argc, argv, "STATUS");
}
int cs_cmd_pause(int argc, char **argv)
{
    return client(argc, argv, "PAUSE");
}
int cs_cmd_resume(int argc, char **argv)
{
    return client(argc, argv, "RESUME");
}
int cs_cmd_cancel(int argc, char **argv)
{
    return client(argc, argv, "CANCEL");
}
