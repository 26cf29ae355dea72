/* curvestep stream: plans a job whole (nothing is sent before the whole job planned without an
 * error), then streams it to a device over a serial port with cs_stream (or hands it to the
 * Modbus or GPIO link, cs_stream_cmd.h), showing progress, and reports how it ended
 * (docs/streaming.md). */
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cs_cmd.h"
#include "cs_conv.h"
#include "cs_err_text.h"
#include "cs_jobplan.h"
#include "cs_serial.h"
#include "cs_stream.h"
#include "cs_stream_cmd.h"
#include "cs_stream_report.h"
#include "cs_stream_resume.h"
#include "cs_trace.h"

#define EXIT_NO_DEVICE CS_EXIT_NO_DEVICE

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
          "                        [--resume | --resume-from N [--position X,Y,Z]]\n"
          "                        [--line-rate BPS] [--font FILE.jhf]\n"
          "                        [--quiet] [input and layout options] FILE\n"
          "       curvestep stream --modbus-tcp HOST:PORT [--unit ID] [options] FILE\n"
          "       curvestep stream --modbus-rtu DEV [--baud N] [--parity P] [--unit ID]\n"
          "                        [options] FILE\n"
          "       curvestep stream --gpio CHIP [--machine FILE.ini] [options] FILE\n"
          "Plans the job FILE (SVG, G-code or HPGL) for the machine, whole, before sending\n"
          "anything, then streams it to the device on the serial port DEV (a tty, or the pty\n"
          "path printed by `curvestep-sim --pty`) with the protocol of docs/protocol.md:\n"
          "raw 8N1 at the given speed, stale input flushed, a handshake (the device's HELLO\n"
          "must match the machine: axes, tick rate, capabilities), then every message,\n"
          "keeping the device's queue full without ever overflowing it, resending what the\n"
          "line lost or damaged.\n"
          "  --port DEV         serial device\n"
          "  --font FILE.jhf    Hershey stroke font for SVG <text> and HP-GL LB\n"
          "  --modbus-tcp H:P   Modbus TCP device at host H, port P (docs/modbus.md)\n"
          "  --modbus-rtu DEV   Modbus RTU device on serial line DEV (docs/modbus.md)\n"
          "  --unit ID          Modbus unit id, 1..247 (default 1)\n"
          "  --parity P         Modbus RTU character format: even (default: 8E1, the Modbus\n"
          "                     serial-line default), odd (8O1) or none (8N2: no parity, two\n"
          "                     stop bits, as the spec asks). Must match the device's setting\n"
          "  --gpio CHIP        run the job here, on the step/dir lines of GPIO chip CHIP\n"
          "                     (the machine file's [gpio] section; README, GPIO).\n"
          "                     --gpio record:FILE runs it on no hardware and writes every\n"
          "                     edge with its time to FILE (CSV; docs/gpio.md)\n"
          "                     One of --port, --modbus-tcp, --modbus-rtu, --gpio is required\n"
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
          "  --max-input-mb N   refuse a job file larger than N MiB (default 64)\n"
          "  --max-segments N   refuse a job of more than N step segments (default 8388608)\n"
          "  --resume           (--port) the link was lost but the device did not reset: ask\n"
          "                     it where this job stands and go on after the last message it\n"
          "                     received (refused, saying what to do, if it reset)\n"
          "  --resume-from N    messages 1..N were executed already: send from N+1 on. With\n"
          "                     --port, a device that did not reset must agree (else use\n"
          "                     --resume); one that reset needs --position\n"
          "  --position X,Y,Z   (--port, with --resume-from) where the machine is, mm: sent to\n"
          "                     the device (SETPOS) before any motion. In segments mode it must\n"
          "                     be where message N left the machine\n"
          "  --line-rate BPS    pace writes as a real line of BPS bits/s would (10 bits a byte),\n"
          "                     for measurements on a pseudo-terminal\n"
          "  --quiet            no progress\n"
          "Progress goes to standard error: a bar (percent, ETA, messages per second,\n"
          "retransmissions) on a terminal, else one line a second. Ctrl-C holds the motion,\n"
          "then aborts it (the device's queue is flushed); a second Ctrl-C leaves at once.\n"
          "When the link dies the summary names the last message the device confirmed and the\n"
          "last one it may have executed, and how to resume (docs/streaming.md, Resume).\n",
          f);
    cs_jobopts_help(f);
    fputs("Exit status: 0 the whole job was executed; 1 bad input (file:line:col: reason);\n"
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

/* --resume, --resume-from and --position together: true (said on stderr) when they clash. */
static bool resume_opts_bad(bool serial, bool ask, bool from, bool pos)
{
    const char *why = (ask || pos) && !serial
                          ? "--resume and --position need --port (the serial protocol; "
                            "docs/streaming.md, Resume)"
                      : ask && (from || pos) ? "--resume asks the device where to go on: it takes "
                                               "neither --resume-from nor --position"
                      : pos && !from ? "--position needs --resume-from N"
                                     : NULL;
    if (why != NULL)
        fprintf(stderr, "curvestep stream: %s\n", why);
    return why != NULL;
}

/* --position X,Y,Z in steps; in segments mode it must be where message n left the machine
 * (the segments are relative moves: from anywhere else the rest of the job would be offset). */
static int check_position(const char *text, const cs_machine_t *m, const cs_stream_job_t *job,
                          size_t n, int32_t steps[CS_AXES])
{
    cs_err_t e = cs_stream_resume_position(text, m, steps);
    if (e != CS_OK) {
        fprintf(stderr, "curvestep stream: --position %s: %s\n", text,
                e == CS_ERR_RANGE ? "outside the coordinate range"
                                  : "wants one number of mm per axis, comma-separated");
        return -1;
    }
    if (job->mode != CS_STREAM_SEGMENTS)
        return 0; /* curves: the device travels to the next curve's start itself */
    int64_t want[CS_AXES];
    cs_stream_resume_steps_after(job, n, want);
    for (unsigned i = 0; i < m->n_axes; i++)
        if (want[i] != steps[i]) {
            static const char names[] = "xyza";
            fprintf(stderr,
                    "curvestep stream: --position %s: message %zu left the machine at %c = %.4f mm "
                    "(%lld steps), not %.4f mm: move it there first (the segments are relative "
                    "moves), or give the right N\n",
                    text, n, names[i], (double)want[i] * CS_MOTION_ONE / m->axis[i].steps_per_mm,
                    (long long)want[i], (double)steps[i] * CS_MOTION_ONE / m->axis[i].steps_per_mm);
            return -1;
        }
    return 0;
}

int cs_cmd_stream(int argc, char **argv)
{
    const char *port = NULL, *job_file = NULL;
    const char *mb_tcp = NULL, *mb_rtu = NULL, *gpio = NULL, *position = NULL;
    bool resume_ask = false;
    unsigned long long baud = 115200, resume = 0, line_rate = 0, unit = 1;
    cs_jobplan_opts_t jo;
    cs_jobplan_opts_init(&jo);
    bool curves = false, quiet = false;
    char parity = 0; /* --parity: 0 = not given (even) */
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        bool has = i + 1 < argc;
        int r = cs_jobplan_option("stream", argc, argv, &i, &jo);
        if (r < 0)
            return CS_EXIT_USAGE;
        if (r > 0)
            continue;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            return CS_EXIT_OK;
        } else if (strcmp(a, "--port") == 0 && has) {
            port = argv[++i];
        } else if (strcmp(a, "--modbus-tcp") == 0 && has) {
            mb_tcp = argv[++i];
        } else if (strcmp(a, "--modbus-rtu") == 0 && has) {
            mb_rtu = argv[++i];
        } else if (strcmp(a, "--gpio") == 0 && has) {
            gpio = argv[++i];
        } else if (strcmp(a, "--unit") == 0 && has) {
            if (parse_count(argv[++i], 247, &unit) != 0 || unit < 1) {
                fprintf(stderr, "curvestep stream: --unit wants a Modbus unit id, 1..247\n");
                return CS_EXIT_USAGE;
            }
        } else if (strcmp(a, "--baud") == 0 && has) {
            if (parse_count(argv[++i], 4000000, &baud) != 0 || !cs_serial_baud_ok((uint32_t)baud)) {
                fprintf(stderr, "curvestep stream: --baud wants a termios rate (e.g. 115200)\n");
                return CS_EXIT_USAGE;
            }
        } else if (strcmp(a, "--parity") == 0 && has) {
            const char *v = argv[++i];
            parity = strcmp(v, "none") == 0   ? 'N'
                     : strcmp(v, "even") == 0 ? 'E'
                     : strcmp(v, "odd") == 0  ? 'O'
                                              : 0;
            if (parity == 0) {
                fprintf(stderr, "curvestep stream: --parity wants none, even or odd\n");
                return CS_EXIT_USAGE;
            }
        } else if (strcmp(a, "--resume-from") == 0 && has) {
            if (parse_count(argv[++i], (unsigned long long)SIZE_MAX / 2, &resume) != 0) {
                fprintf(stderr, "curvestep stream: --resume-from wants a message number\n");
                return CS_EXIT_USAGE;
            }
        } else if (strcmp(a, "--resume") == 0) {
            resume_ask = true;
        } else if (strcmp(a, "--position") == 0 && has) {
            position = argv[++i];
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
    int links = (port != NULL) + (mb_tcp != NULL) + (mb_rtu != NULL) + (gpio != NULL);
    if (job_file == NULL || links != 1) {
        fprintf(stderr, "curvestep stream: %s\n",
                links == 0  ? "one of --port, --modbus-tcp, --modbus-rtu or --gpio is required"
                : links > 1 ? "--port, --modbus-tcp, --modbus-rtu and --gpio exclude each other"
                            : "no job file");
        usage(stderr);
        return CS_EXIT_USAGE;
    }
    if (resume_opts_bad(port != NULL, resume_ask, resume != 0, position != NULL))
        return CS_EXIT_USAGE;
    if (parity != 0 && mb_rtu == NULL) {
        fprintf(stderr, "curvestep stream: --parity applies to --modbus-rtu only\n");
        return CS_EXIT_USAGE;
    }
    cs_machine_t m;
    cs_machine_pen_t pen;
    cs_pos_t tol;
    char found[4096]; /* the default machine file, named for the Modbus and GPIO links too */
    if (jo.machine_file == NULL && cs_machine_ini_find(found, sizeof found))
        jo.machine_file = found;
    int mrc = cs_jobplan_machine("stream", &jo, &m, &pen, &tol);
    if (mrc != CS_EXIT_OK)
        return mrc;
    /* 1. the whole job, planned before anything is sent (the plan also checks the travel
     * limits in curves mode, where the device plans again itself) */
    cs_jobplan_t jp;
    cs_jobplan_init(&jp);
    cs_jobplan_limits(&jp, &jo);
    jp.font_file = jo.font_file;
    cs_err_t e = cs_jobplan_read_opts(&jp, job_file, &pen, &jo.in);
    if (e == CS_OK)
        e = cs_jobplan_prepare(&jp, "stream", &jo.in, &m, &pen, tol, stderr);
    if (e != CS_OK) {
        cs_path_diag_print(stderr, &jp.diag);
        int rc = cs_jobplan_exit(&jp, e);
        cs_jobplan_free(&jp);
        return rc;
    }
    int32_t feed_q = cs_motion_speed(jo.feed_mm_s);
    e = cs_jobplan_plan(&jp, job_file, &m, NULL, tol, CS_TRACE_DEFAULT, feed_q);
    if (e == CS_OK)
        e = cs_jobplan_linkable(&jp, job_file, port != NULL, curves);
    cs_stream_job_t job;
    cs_stream_job_init(&job, curves ? CS_STREAM_CURVES : CS_STREAM_SEGMENTS);
    if (e == CS_OK)
        e = curves ? cs_stream_job_add_path(&job, &jp.path, feed_q > 0 ? feed_q : m.default_feed,
                                            tol, &jp.diag)
                   : cs_stream_job_add_motion(&job, &jp.mo.segs);
    if (e != CS_OK) {
        cs_path_diag_print(stderr, &jp.diag);
        int rc = cs_jobplan_exit(&jp, e);
        cs_stream_job_free(&job);
        cs_jobplan_free(&jp);
        return rc;
    }
    const char *what = curves ? "curves" : "segments";
    fprintf(stderr,
            "stream: %s: %zu elements -> %zu %s (%zu segments planned here, job time %.3f s)%s\n",
            job_file, jp.path.n, job.n, what, jp.mo.segs.n, (double)jp.mo.ticks / m.tick_hz,
            curves && job.approximated
                ? " ; arcs and other rational curves approximated by cubics within tol/4"
                : "");
    if (resume > job.n) {
        fprintf(stderr, "curvestep stream: --resume-from %llu: the job has %zu %s\n", resume, job.n,
                what);
        cs_stream_job_free(&job);
        cs_jobplan_free(&jp);
        return CS_EXIT_USAGE;
    }
    int32_t pos_steps[CS_AXES] = {0};
    if (position != NULL && check_position(position, &m, &job, (size_t)resume, pos_steps) != 0) {
        cs_stream_job_free(&job);
        cs_jobplan_free(&jp);
        return CS_EXIT_USAGE;
    }
    cs_path_free(&jp.path);
    if (port == NULL) { /* 2'. another link: Modbus or GPIO */
        cs_stream_args_t sa;
        memset(&sa, 0, sizeof sa);
        sa.job_file = job_file;
        sa.machine_file = jo.machine_file;
        sa.modbus_tcp = mb_tcp;
        sa.modbus_rtu = mb_rtu;
        sa.gpio_chip = gpio;
        sa.baud = (uint32_t)baud;
        sa.parity = parity != 0 ? parity : 'E';
        sa.unit = (int)unit;
        sa.resume_from = (size_t)resume;
        sa.line_rate = (uint32_t)line_rate;
        sa.curves = curves;
        sa.quiet = quiet;
        cs_stream_plan_t pl;
        pl.m = m;
        pl.pen = pen;
        pl.job = job;
        pl.segs = jp.mo.segs.v;
        pl.nsegs = jp.mo.segs.n;
        pl.ticks = jp.mo.ticks;
        struct sigaction sig;
        memset(&sig, 0, sizeof sig);
        sig.sa_handler = on_sigint;
        sigaction(SIGINT, &sig, NULL);
        signal(SIGPIPE, SIG_IGN);
        int lrc = gpio ? cs_stream_cmd_gpio(&sa, &pl, &interrupted)
                       : cs_stream_cmd_modbus(&sa, &pl, &interrupted);
        signal(SIGINT, SIG_DFL);
        fflush(stdout);
        cs_stream_job_free(&job);
        cs_jobplan_free(&jp);
        return lrc;
    }
    cs_jobplan_free(&jp);
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
    o.resume_ask = resume_ask;
    o.set_pos = position != NULL;
    memcpy(o.pos, pos_steps, sizeof pos_steps);
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
    if (resume_ask && r.numbered) /* where the device's word put the start */
        fprintf(stdout,
                "stream: resumed: the device had received %s 1..%zu of this job and finished "
                "%zu of them; sent from %zu on\n",
                what, r.resume_from, r.resume_done, r.resume_from + 1);
    int rc = cs_stream_report(stdout, port, &job, &r, r.resume_from, curves);
    cs_stream_resume_hint(stdout, &job, &r, &m, job_file);
    cs_stream_job_free(&job);
    return rc;
}
