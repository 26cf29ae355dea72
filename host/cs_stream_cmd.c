/* curvestep stream: plans a job whole (nothing is sent before the whole job planned without an
 * error), then streams it to a device over a serial port with cs_stream, showing progress, and
 * reports how it ended (docs/streaming.md). */
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cs_cmd.h"
#include "cs_conv.h"
#include "cs_err_text.h"
#include "cs_input.h"
#include "cs_machine_ini.h"
#include "cs_motion.h"
#include "cs_serial.h"
#include "cs_stream.h"
#include "cs_trace.h"

/* Exit statuses of `stream` beyond the shared ones (cs_cmd.h). */
enum {
    EXIT_NO_DEVICE = 4,  /* the port cannot be opened, no device answered, or it is incompatible */
    EXIT_RESET = 5,      /* the device reset mid-job */
    EXIT_CLOSED = 6,     /* the link closed or the device stopped answering mid-job */
    EXIT_DEV_ERROR = 7,  /* the device refused a message (ERROR) */
    EXIT_INTERRUPTED = 8 /* Ctrl-C: held, then aborted */
};

static volatile sig_atomic_t interrupted;

static void on_sigint(int sig)
{
    (void)sig;
    if (interrupted < 2)
        interrupted++;
}

static void usage(FILE *f)
{
    fputs("usage: curvestep stream --port DEV [--baud N] [--machine FILE.ini]\n"
          "                        [--mode segments|curves] [--tol MM] [--feed MM/S]\n"
          "                        [--resume-from N] [--line-rate BPS] [--quiet] FILE\n"
          "Plans the job FILE (SVG, G-code or HPGL) for the machine, whole, before sending\n"
          "anything, then streams it to the device on the serial port DEV (a tty, or the pty\n"
          "path printed by `curvestep-sim --pty`) with the protocol of docs/protocol.md:\n"
          "raw 8N1 at the given speed, stale input flushed, a handshake (the device's HELLO\n"
          "must match the machine: axes, tick rate, capabilities), then every message,\n"
          "keeping the device's queue full without ever overflowing it, resending what the\n"
          "line lost or damaged.\n"
          "  --port DEV         serial device (required)\n"
          "  --baud N           line speed (default 115200)\n"
          "  --machine FILE     machine description (default: the built-in plotter); with\n"
          "                     [pen] mode = z, G-code M3/M4 (pen down) and M5 (pen up) move\n"
          "                     Z, rapid, to its down_z / up_z\n"
          "  --mode segments    send step segments planned here (default)\n"
          "  --mode curves      send cubic Beziers; the device traces and plans them itself.\n"
          "                     Lines and quadratics are sent as exact cubics; arcs and other\n"
          "                     rational curves as cubic pieces within tol/4 of the exact curve\n"
          "  --tol MM           chord tolerance (default: the machine's)\n"
          "  --feed MM/S        drawing feed (default: the machine's default_feed)\n"
          "  --resume-from N    messages 1..N were executed already: send from N+1 on (the\n"
          "                     number printed after a reset or a lost link). The machine must\n"
          "                     be where message N left it\n"
          "  --line-rate BPS    pace writes as a real line of BPS bits/s would (10 bits a byte),\n"
          "                     for measurements on a pseudo-terminal\n"
          "  --quiet            no progress\n"
          "Progress goes to standard error: a bar (percent, ETA, messages per second,\n"
          "retransmissions) on a terminal, else one line a second. Ctrl-C holds the motion,\n"
          "then aborts it (the device's queue is flushed); a second Ctrl-C leaves at once.\n"
          "The summary line names the last executed message, to use with --resume-from.\n"
          "Exit status: 0 the whole job was executed; 1 bad input (file:line:col: reason);\n"
          "2 bad command line; 3 internal error; 4 the port cannot be opened, no device\n"
          "answered or it does not match the machine; 5 the device reset mid-job; 6 the link\n"
          "closed or the device stopped answering; 7 the device refused a message; 8\n"
          "interrupted (Ctrl-C).\n",
          f);
}

static int parse_count(const char *s, unsigned long long max, unsigned long long *out)
{
    char *end;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (*s == '\0' || *s == '-' || *end != '\0' || errno != 0 || v > max)
        return -1;
    *out = v;
    return 0;
}

int cs_cmd_stream(int argc, char **argv)
{
    const char *port = NULL, *machine_file = NULL, *job_file = NULL;
    unsigned long long baud = 115200, resume = 0, line_rate = 0;
    double tol_mm = 0, feed = 0;
    bool curves = false, quiet = false;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        bool has = i + 1 < argc;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            return CS_EXIT_OK;
        } else if (strcmp(a, "--port") == 0 && has) {
            port = argv[++i];
        } else if (strcmp(a, "--machine") == 0 && has) {
            machine_file = argv[++i];
        } else if (strcmp(a, "--baud") == 0 && has) {
            if (parse_count(argv[++i], 4000000, &baud) != 0 || !cs_serial_baud_ok((uint32_t)baud)) {
                fprintf(stderr, "curvestep stream: --baud wants a termios rate (e.g. 115200)\n");
                return CS_EXIT_USAGE;
            }
        } else if (strcmp(a, "--resume-from") == 0 && has) {
            if (parse_count(argv[++i], (unsigned long long)SIZE_MAX / 2, &resume) != 0) {
                fprintf(stderr, "curvestep stream: --resume-from wants a message number\n");
                return CS_EXIT_USAGE;
            }
        } else if (strcmp(a, "--line-rate") == 0 && has) {
            if (parse_count(argv[++i], 100000000, &line_rate) != 0 || line_rate < 10) {
                fprintf(stderr, "curvestep stream: --line-rate wants bits/s (>= 10)\n");
                return CS_EXIT_USAGE;
            }
        } else if (strcmp(a, "--mode") == 0 && has) {
            const char *m = argv[++i];
            if (strcmp(m, "segments") == 0)
                curves = false;
            else if (strcmp(m, "curves") == 0)
                curves = true;
            else {
                fprintf(stderr, "curvestep stream: --mode wants segments or curves\n");
                return CS_EXIT_USAGE;
            }
        } else if (strcmp(a, "--tol") == 0 && has) {
            char *end;
            tol_mm = strtod(argv[++i], &end);
            if (*end != '\0' || !(tol_mm > 0)) {
                fprintf(stderr, "curvestep stream: --tol wants a positive number of mm\n");
                return CS_EXIT_USAGE;
            }
        } else if (strcmp(a, "--feed") == 0 && has) {
            char *end;
            feed = strtod(argv[++i], &end);
            if (*end != '\0' || !(feed > 0) || feed >= 32768) {
                fprintf(stderr, "curvestep stream: --feed wants a speed in (0, 32768) mm/s\n");
                return CS_EXIT_USAGE;
            }
        } else if (strcmp(a, "--quiet") == 0) {
            quiet = true;
        } else if (a[0] == '-' && a[1] != '\0') {
            fprintf(stderr, "curvestep stream: unknown or incomplete option %s\n", a);
            usage(stderr);
            return CS_EXIT_USAGE;
        } else if (job_file == NULL) {
            job_file = a;
        } else {
            fprintf(stderr, "curvestep stream: one job file only\n");
            return CS_EXIT_USAGE;
        }
    }
    if (job_file == NULL || port == NULL) {
        fprintf(stderr, "curvestep stream: %s\n", port ? "no job file" : "--port DEV is required");
        usage(stderr);
        return CS_EXIT_USAGE;
    }
    cs_machine_t m;
    cs_machine_pen_t pen;
    cs_machine_ini_pen_default(&pen);
    char err[512];
    if (machine_file) {
        if (cs_machine_ini_load_pen(machine_file, &m, &pen, err, sizeof err) != 0) {
            fprintf(stderr, "%s\n", err);
            return CS_EXIT_INPUT;
        }
    } else {
        cs_machine_ini_default(&m);
    }
    cs_pos_t tol = m.tolerance;
    if (tol_mm > 0 && cs_conv_tol_to_pos(tol_mm, &tol) != CS_OK) {
        fprintf(stderr, "curvestep stream: --tol %g mm is outside the accepted range\n", tol_mm);
        return CS_EXIT_USAGE;
    }
    /* 1. the whole job, planned before anything is sent (the plan also checks the travel
     * limits in curves mode, where the device plans again itself) */
    cs_path_t path;
    cs_path_init(&path);
    cs_path_diag_t diag;
    /* [pen] mode = z: G-code M3/M4 (pen down) and M5 (pen up) become rapid Z moves. */
    cs_input_opts_t iopts;
    cs_input_opts_init(&iopts);
    iopts.pen_z = pen.mode == CS_MACHINE_PEN_Z;
    iopts.pen_up_z_mm = pen.up_z_mm;
    iopts.pen_down_z_mm = pen.down_z_mm;
    cs_err_t e = cs_input_load(job_file, &iopts, &path, &diag);
    if (e != CS_OK) {
        cs_path_diag_print(stderr, &diag);
        cs_path_free(&path);
        return e == CS_ERR_FULL ? CS_EXIT_INTERNAL : CS_EXIT_INPUT;
    }
    cs_motion_t mo;
    e = cs_motion_init(&mo, &m);
    int32_t feed_q = cs_motion_speed(feed);
    if (e == CS_OK)
        e = cs_motion_plan_path(&mo, &path, tol, CS_TRACE_SUBDIV, feed_q, &diag);
    else
        snprintf(diag.reason, sizeof diag.reason, "machine rejected"), diag.loc.file = job_file;
    cs_stream_job_t job;
    cs_stream_job_init(&job, curves ? CS_STREAM_CURVES : CS_STREAM_SEGMENTS);
    if (e == CS_OK)
        e = curves ? cs_stream_job_add_path(&job, &path, feed_q > 0 ? feed_q : m.default_feed, tol,
                                            &diag)
                   : cs_stream_job_add_segments(&job, mo.segs.v, mo.segs.n);
    if (e != CS_OK) {
        cs_path_diag_print(stderr, &diag);
        cs_stream_job_free(&job);
        cs_motion_free(&mo);
        cs_path_free(&path);
        return (e == CS_ERR_LIMIT || e == CS_ERR_RANGE || e == CS_ERR_TOLERANCE ||
                e == CS_ERR_DEPTH)
                   ? CS_EXIT_INPUT
                   : CS_EXIT_INTERNAL;
    }
    const char *what = curves ? "curves" : "segments";
    fprintf(stderr,
            "stream: %s: %zu elements -> %zu %s (%zu segments planned here, job time %.3f s)%s\n",
            job_file, path.n, job.n, what, mo.segs.n, (double)mo.ticks / m.tick_hz,
            curves && job.approximated
                ? " ; arcs and other rational curves approximated by cubics within tol/4"
                : "");
    if (resume > job.n) {
        fprintf(stderr, "curvestep stream: --resume-from %llu: the job has %zu %s\n", resume, job.n,
                what);
        cs_stream_job_free(&job);
        cs_motion_free(&mo);
        cs_path_free(&path);
        return CS_EXIT_USAGE;
    }
    cs_motion_free(&mo);
    cs_path_free(&path);
    /* 2. the port */
    cs_serial_t ser;
    if (cs_serial_open(&ser, port, (uint32_t)baud) != 0) {
        fprintf(stderr, "curvestep stream: %s: %s\n", port, strerror(errno));
        cs_stream_job_free(&job);
        return EXIT_NO_DEVICE;
    }
    cs_serial_set_line_rate(&ser, (uint32_t)line_rate);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_sigint;
    sigaction(SIGINT, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);
    cs_stream_opts_t o;
    cs_stream_opts_default(&o, &ser, m.n_axes, m.tick_hz);
    /* a pty moves bytes at memory speed whatever its baud: time the link for the real rate */
    cs_stream_link_timing(&o.link, line_rate                            ? (uint32_t)line_rate
                                   : strncmp(port, "/dev/pts/", 9) == 0 ? 0
                                                                        : (uint32_t)baud);
    o.resume_from = (size_t)resume;
    o.interrupt = &interrupted;
    o.progress = quiet ? NULL : stderr;
    o.progress_tty = isatty(STDERR_FILENO) != 0;
    cs_stream_result_t r;
    e = cs_stream_run(&job, &o, &r);
    cs_serial_close(&ser);
    signal(SIGINT, SIG_DFL);
    if (e != CS_OK) {
        fprintf(stderr, "curvestep stream: %s\n", cs_err_text(e));
        cs_stream_job_free(&job);
        return CS_EXIT_INTERNAL;
    }
    int rc = CS_EXIT_OK;
    switch (r.outcome) {
    case CS_STREAM_DONE:
        rc = CS_EXIT_OK;
        break;
    case CS_STREAM_NO_DEVICE:
    case CS_STREAM_INCOMPATIBLE:
        rc = EXIT_NO_DEVICE;
        break;
    case CS_STREAM_RESET:
        rc = EXIT_RESET;
        break;
    case CS_STREAM_CLOSED:
        rc = EXIT_CLOSED;
        break;
    case CS_STREAM_DEVICE_ERROR:
        rc = EXIT_DEV_ERROR;
        break;
    case CS_STREAM_INTERRUPTED:
        rc = EXIT_INTERRUPTED;
        break;
    }
    printf("stream: %s: %s", port, cs_stream_outcome_text(r.outcome));
    if (r.why[0])
        printf(" (%s)", r.why);
    if (r.outcome == CS_STREAM_RESET)
        printf(" (boot id %08x -> %08x; %u messages were in flight)", (unsigned)r.old_boot,
               (unsigned)r.new_boot, (unsigned)r.unacked);
    if (r.outcome == CS_STREAM_DEVICE_ERROR)
        printf(" (%s, about %s no. %zu)", cs_err_text((cs_err_t)r.dev_error.code),
               curves ? "curve" : "segment", r.dev_error_msg);
    printf("\n");
    printf("stream: %zu of %zu %s executed, %zu delivered, %zu sent; last executed: %zu\n",
           r.executed, job.n, what, r.delivered, r.sent, r.executed);
    printf("stream: %llu bytes sent, %llu received in %.2f s; %u retransmissions (%u timeouts, "
           "%u NAKs); %.0f %s/s\n",
           (unsigned long long)r.bytes_out, (unsigned long long)r.bytes_in, r.wall_s,
           (unsigned)r.link.retransmits, (unsigned)r.link.timeouts, (unsigned)r.link.naks,
           r.stream_s > 0 ? (double)(r.executed - o.resume_from) / r.stream_s : 0.0, what);
    if (rc != CS_EXIT_OK && r.executed < job.n && r.outcome != CS_STREAM_NO_DEVICE &&
        r.outcome != CS_STREAM_INCOMPATIBLE)
        printf("stream: to continue once the machine is where %s no. %zu left it: "
               "curvestep stream --resume-from %zu ...\n",
               curves ? "curve" : "segment", r.executed, r.executed);
    fflush(stdout);
    cs_stream_job_free(&job);
    return rc;
}
