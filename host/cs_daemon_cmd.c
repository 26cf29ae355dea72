/* curvestep serve | submit | status | pause | resume | cancel: the streaming daemon (cs_daemon)
 * and the commands that talk to it over its UNIX socket (docs/streaming.md, "The daemon"). */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_cmd.h"
#include "cs_daemon.h"
#include "cs_joblink.h"
#include "cs_jobopts.h"
#include "cs_readall.h"

/* Exit status of the clients beyond the shared ones: no daemon answers on the socket. */
enum { EXIT_NO_DAEMON = 4 };

static void serve_usage(FILE *f)
{
    char sock[256];
    fprintf(f,
            "usage: curvestep serve --port DEV | --modbus-tcp HOST:PORT | --modbus-rtu DEV\n"
            "                       | --gpio CHIP\n"
            "                       [--baud N] [--line-rate BPS] [--parity none|even|odd] [--unit ID]\n"
            "                       [--modbus-timeout MS] [--machine FILE.ini] [--socket PATH]\n"
            "                       [--max-input-mb N]\n"
            "Streams the jobs submitted to it over one link, one at a time, in the order they\n"
            "came (as `curvestep stream` does: read once and planned whole at submit time, then\n"
            "streamed with the protocol of docs/protocol.md, over Modbus as in docs/modbus.md,\n"
            "or run here on GPIO lines as in docs/gpio.md). Clients talk to it on the UNIX\n"
            "socket PATH, created with mode 0600 (owner only): curvestep submit, status, pause,\n"
            "resume, cancel. One line per event on standard error.\n"
            "SIGTERM or SIGINT stops it: the running job is held, then aborted.\n"
            "  --port DEV      serial device, kept open (one link is required)\n"
            "  --modbus-tcp HOST:PORT  a Modbus TCP device (connected for each job)\n"
            "  --modbus-rtu DEV        a Modbus RTU device on serial line DEV (opened each job)\n"
            "  --gpio CHIP     the step/dir lines of GPIO chip CHIP, wired as the machine\n"
            "                  file's [gpio] section says (requested for each job);\n"
            "                  --gpio record:FILE runs on no hardware and writes each job's\n"
            "                  edges to FILE (docs/gpio.md)\n"
            "  --baud N        line speed of --port and --modbus-rtu (default 115200)\n"
            "  --line-rate BPS --port: time the link for a line of BPS bits/s and pace writes\n"
            "                  to it (for a pty that stands for a real UART, e.g. qemu's; a\n"
            "                  pty is otherwise timed at memory speed)\n"
            "  --parity P      Modbus RTU: even (default, 8E1), odd (8O1), none (8N2)\n"
            "  --unit ID       Modbus unit id, 1..247 (default 1)\n"
            "  --modbus-timeout MS  Modbus: one try's wait for its answer (default 200)\n"
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

/* serve's own options (the link's are cs_joblink_option's): 1 taken, 0 not one, -1 bad. */
static int serve_option(int argc, char **argv, int *i, cs_daemon_cfg_t *cfg)
{
    const char *a = argv[*i];
    if (*i + 1 >= argc)
        return 0;
    if (strcmp(a, "--socket") == 0) {
        cfg->socket_path = argv[++*i];
    } else if (strcmp(a, "--machine") == 0) {
        cfg->machine_file = argv[++*i];
    } else if (strcmp(a, "--max-input-mb") == 0) {
        if (!cs_readall_parse_mb(argv[++*i], &cfg->max_input_bytes)) {
            fprintf(stderr,
                    "curvestep serve: --max-input-mb wants a whole number of MiB, 1 to %u\n",
                    CS_READALL_MAX_MB);
            return -1;
        }
    } else {
        return 0;
    }
    return 1;
}

int cs_cmd_serve(int argc, char **argv)
{
    char sock[256];
    cs_daemon_cfg_t cfg = {.link = {.baud = 115200, .unit = 1}, .log = stderr};
    cfg.socket_path = cs_daemon_default_socket(sock, sizeof sock);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            serve_usage(stdout);
            return CS_EXIT_OK;
        }
        int r = cs_joblink_option("serve", argc, argv, &i, &cfg.link);
        if (r == 0)
            r = serve_option(argc, argv, &i, &cfg);
        if (r < 0)
            return CS_EXIT_USAGE;
        if (r == 0) {
            fprintf(stderr, "curvestep serve: unknown or incomplete option %s\n", a);
            serve_usage(stderr);
            return CS_EXIT_USAGE;
        }
    }
    cs_joblink_t probe;
    if (cs_joblink_select(&probe, &cfg.link) != CS_EXIT_OK) {
        fprintf(stderr, "curvestep serve: give one link: --port DEV, --modbus-tcp HOST:PORT, "
                        "--modbus-rtu DEV or --gpio CHIP\n");
        serve_usage(stderr);
        return CS_EXIT_USAGE;
    }
    if (cfg.link.line_rate != 0 && cfg.link.port == NULL) {
        fprintf(stderr, "curvestep serve: --line-rate applies to --port only\n");
        return CS_EXIT_USAGE;
    }
    if (cfg.link.parity != 0 && cfg.link.modbus_rtu == NULL) {
        fprintf(stderr, "curvestep serve: --parity applies to --modbus-rtu only\n");
        return CS_EXIT_USAGE;
    }
    if (cfg.link.mb_timeout_ms != 0 && cfg.link.modbus_rtu == NULL &&
        cfg.link.modbus_tcp == NULL) {
        fprintf(stderr, "curvestep serve: --modbus-timeout applies to a Modbus link only\n");
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
                   "Queues the job FILE (SVG, G-code, HPGL or DXF) on the daemon (`curvestep serve`).\n"
                   "The daemon reads and plans it whole now: a bad file is refused at once with\n"
                   "file:line:col: reason. Prints the job's number. Options as for `stream`;\n"
                   "--font FILE.jhf: the stroke font for SVG <text>, HP-GL LB, DXF TEXT (read by the\n"
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

/* A client's command line. */
typedef struct {
    const char *name; /* submit, status, ... */
    const char *socket_path;
    const char *file, *mode, *tol, *feed, *job, *font;
    bool submit, cancel;
    cs_jobopts_t in; /* sent as SUBMIT words; the daemon reads and lays out the job */
} client_args_t;

/* submit's --mode / --tol / --feed / --font: 1 taken, 0 not one, -1 a bad value (said). */
static int submit_option(int argc, char **argv, int *i, client_args_t *c)
{
    const char *a = argv[*i];
    if (!c->submit || *i + 1 >= argc)
        return 0;
    const char *v = argv[*i + 1];
    char *end;
    if (strcmp(a, "--mode") == 0) {
        if (strcmp(v, "segments") != 0 && strcmp(v, "curves") != 0) {
            fprintf(stderr, "curvestep submit: --mode wants segments or curves\n");
            return -1;
        }
        c->mode = v;
    } else if (strcmp(a, "--tol") == 0) {
        if (!(strtod(v, &end) > 0) || *end != '\0' || strchr(v, ' ')) {
            fprintf(stderr, "curvestep submit: --tol wants a positive number of mm\n");
            return -1;
        }
        c->tol = v;
    } else if (strcmp(a, "--feed") == 0) {
        double f = strtod(v, &end);
        if (!(f > 0) || f >= 32768 || *end != '\0') {
            fprintf(stderr, "curvestep submit: --feed wants a speed in (0, 32768) mm/s\n");
            return -1;
        }
        c->feed = v;
    } else if (strcmp(a, "--font") == 0) {
        c->font = v;
    } else {
        return 0;
    }
    (*i)++;
    return 1;
}

/* A word that is not an option: submit's FILE or cancel's JOB. CS_EXIT_OK, or a usage error. */
static int client_word(client_args_t *c, const char *a)
{
    if (c->submit && c->file == NULL) {
        c->file = a;
    } else if (c->cancel && c->job == NULL) {
        char *end;
        unsigned long v = strtoul(a, &end, 10);
        if (*a == '\0' || *a == '-' || *end != '\0' || v == 0 || v > UINT_MAX) {
            fprintf(stderr, "curvestep cancel: JOB is a job number (see `status`)\n");
            return CS_EXIT_USAGE;
        }
        c->job = a;
    } else {
        fprintf(stderr, "curvestep %s: unexpected argument %s\n", c->name, a);
        client_usage(stderr, c->name);
        return CS_EXIT_USAGE;
    }
    return CS_EXIT_OK;
}

/* Parses a client's argv: -1 to go on, else the exit status (--help, a usage error). */
static int client_parse(int argc, char **argv, client_args_t *c, char *sock, size_t cap)
{
    memset(c, 0, sizeof *c);
    c->name = argv[0];
    c->socket_path = cs_daemon_default_socket(sock, cap);
    c->submit = strcmp(c->name, "submit") == 0;
    c->cancel = strcmp(c->name, "cancel") == 0;
    cs_jobopts_init(&c->in);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int r = c->submit ? cs_jobopts_option(c->name, argc, argv, &i, &c->in) : 0;
        if (r == 0)
            r = submit_option(argc, argv, &i, c);
        if (r < 0)
            return CS_EXIT_USAGE;
        if (r > 0)
            continue;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            client_usage(stdout, c->name);
            return CS_EXIT_OK;
        } else if (strcmp(a, "--socket") == 0 && i + 1 < argc) {
            c->socket_path = argv[++i];
        } else if (a[0] == '-' && a[1] != '\0') {
            fprintf(stderr, "curvestep %s: unknown or incomplete option %s\n", c->name, a);
            client_usage(stderr, c->name);
            return CS_EXIT_USAGE;
        } else if ((r = client_word(c, a)) != CS_EXIT_OK) {
            return r;
        }
    }
    return -1;
}

/* The request line: "SUBMIT [words] /ABS/PATH", or the verb [JOB]. CS_EXIT_OK, or an error. */
static int client_request(const client_args_t *c, const char *verb, char *req, size_t cap)
{
    if (!c->submit) {
        snprintf(req, cap, "%s%s%s", verb, c->job ? " " : "", c->job ? c->job : "");
        return CS_EXIT_OK;
    }
    if (c->file == NULL) {
        fprintf(stderr, "curvestep submit: no job file\n");
        client_usage(stderr, c->name);
        return CS_EXIT_USAGE;
    }
    char abs[PATH_MAX];
    if (realpath(c->file, abs) == NULL) {
        fprintf(stderr, "%s:0:0: cannot open the job file (%s)\n", c->file, strerror(errno));
        return CS_EXIT_INPUT;
    }
    if (cs_jobopts_check(c->name, &c->in) != 0)
        return CS_EXIT_USAGE;
    /* the font goes by its absolute path, one word: the daemon reads it at submit */
    char fabs[PATH_MAX] = "";
    if (c->font != NULL && realpath(c->font, fabs) == NULL) {
        fprintf(stderr, "%s:0:0: cannot open the font (%s)\n", c->font, strerror(errno));
        return CS_EXIT_INPUT;
    }
    if (strpbrk(fabs, " \t\n") != NULL) {
        fprintf(stderr, "%s:0:0: a font path with blanks cannot be sent to the daemon\n", c->font);
        return CS_EXIT_INPUT;
    }
    int k = snprintf(req, cap, "SUBMIT%s%s%s%s%s%s%s%s%s %s", c->mode ? " mode=" : "",
                     c->mode ? c->mode : "", c->tol ? " tol=" : "", c->tol ? c->tol : "",
                     c->feed ? " feed=" : "", c->feed ? c->feed : "", c->font ? " font=" : "", fabs,
                     c->in.words, abs);
    if (k < 0 || (size_t)k >= cap || strchr(abs, '\n')) {
        fprintf(stderr, "%s:0:0: path too long or not on one line\n", c->file);
        return CS_EXIT_INPUT;
    }
    return CS_EXIT_OK;
}

/* Sends req and prints the reply: OK on standard output, a refusal on standard error (without
 * the "ERR "). The exit status. */
static int client_send(const char *name, const char *socket_path, const char *req)
{
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

static int client(int argc, char **argv, const char *verb)
{
    char sock[256];
    client_args_t c;
    int rc = client_parse(argc, argv, &c, sock, sizeof sock);
    if (rc >= 0)
        return rc;
    char req[CS_DAEMON_LINE_MAX];
    rc = client_request(&c, verb, req, sizeof req);
    if (rc != CS_EXIT_OK)
        return rc;
    return client_send(c.name, c.socket_path, req);
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
