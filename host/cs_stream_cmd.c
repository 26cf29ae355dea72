/* curvestep stream: parses its options, plans a job whole (nothing is sent before the whole job
 * planned without an error), then runs it over the link the options pick (cs_joblink: serial,
 * Modbus TCP/RTU or GPIO), showing progress, and reports how it ended (docs/streaming.md). */
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
#include "cs_joblink.h"
#include "cs_serial.h"
#include "cs_stream.h"
#include "cs_stream_cmd.h"
#include "cs_stream_pen.h"
#include "cs_stream_resume.h"
#include "cs_trace.h"

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
          "Plans the job FILE (SVG, G-code, HPGL or DXF) for the machine, whole, before sending\n"
          "anything, then streams it to the device on the serial port DEV (a tty, or the pty\n"
          "path printed by `curvestep-sim --pty`) with the protocol of docs/protocol.md:\n"
          "raw 8N1 at the given speed, stale input flushed, a handshake (the device's HELLO\n"
          "must match the machine: axes, tick rate, capabilities), then every message,\n"
          "keeping the device's queue full without ever overflowing it, resending what the\n"
          "line lost or damaged.\n"
          "  --port DEV         serial device\n"
          "  --font FILE.jhf    Hershey stroke font for SVG <text>, HP-GL LB and DXF TEXT\n"
          "  --modbus-tcp H:P   Modbus TCP device at host H, port P (docs/modbus.md)\n"
          "  --modbus-rtu DEV   Modbus RTU device on serial line DEV (docs/modbus.md)\n"
          "  --unit ID          Modbus unit id, 1..247 (default 1)\n"
          "  --parity P         Modbus RTU character format: even (default: 8E1, the Modbus\n"
          "                     serial-line default), odd (8O1) or none (8N2: no parity, two\n"
          "                     stop bits, as the spec asks). Must match the device's setting\n"
          "  --modbus-timeout MS  Modbus: one try's wait for its answer (default 200 ms, plus\n"
          "                     the line time at --baud on RTU); 6 tries, then exit 6\n"
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

/* The command line. */
typedef struct {
    const char *job_file;
    cs_jobplan_opts_t jo;
    cs_joblink_cfg_t link;
    size_t resume_from;   /* --resume-from N */
    bool resume_ask;      /* --resume */
    const char *position; /* --position X,Y,Z (mm) */
    int32_t pos[CS_AXES]; /* --position in steps */
    bool curves, quiet;
} stream_args_t;

/* The command's own options: 1 taken, 0 not one of them, -1 a bad value (said). */
static int stream_option(int argc, char **argv, int *i, stream_args_t *a)
{
    const char *o = argv[*i];
    bool has = *i + 1 < argc;
    unsigned long long n;
    if (strcmp(o, "--resume-from") == 0 && has) {
        if (cs_joblink_parse_count(argv[++*i], (unsigned long long)SIZE_MAX / 2, &n) != 0) {
            fprintf(stderr, "curvestep stream: --resume-from wants a message number\n");
            return -1;
        }
        a->resume_from = (size_t)n;
    } else if (strcmp(o, "--resume") == 0) {
        a->resume_ask = true;
    } else if (strcmp(o, "--position") == 0 && has) {
        a->position = argv[++*i];
    } else if (strcmp(o, "--mode") == 0 && has) {
        const char *m = argv[++*i];
        if (strcmp(m, "segments") != 0 && strcmp(m, "curves") != 0) {
            fprintf(stderr, "curvestep stream: --mode wants segments or curves\n");
            return -1;
        }
        a->curves = strcmp(m, "curves") == 0;
    } else if (strcmp(o, "--quiet") == 0) {
        a->quiet = true;
    } else {
        return 0;
    }
    return 1;
}

/* Parses argv into *a: -1 to go on, else the exit status (--help, a usage error). */
static int parse_args(int argc, char **argv, stream_args_t *a)
{
    memset(a, 0, sizeof *a);
    cs_jobplan_opts_init(&a->jo);
    a->link.baud = 115200;
    a->link.unit = 1;
    for (int i = 1; i < argc; i++) {
        const char *o = argv[i];
        int r = cs_jobplan_option("stream", argc, argv, &i, &a->jo);
        if (r == 0)
            r = cs_joblink_option("stream", argc, argv, &i, &a->link);
        if (r == 0)
            r = stream_option(argc, argv, &i, a);
        if (r < 0)
            return CS_EXIT_USAGE;
        if (r > 0)
            continue;
        if (strcmp(o, "--help") == 0 || strcmp(o, "-h") == 0) {
            usage(stdout);
            return CS_EXIT_OK;
        } else if (o[0] == '-' && o[1] != '\0') {
            fprintf(stderr, "curvestep stream: unknown or incomplete option %s\n", o);
            usage(stderr);
            return CS_EXIT_USAGE;
        } else if (a->job_file != NULL) {
            fprintf(stderr, "curvestep stream: one job file only\n");
            return CS_EXIT_USAGE;
        }
        a->job_file = o;
    }
    return -1;
}

/* --resume, --resume-from and --position together: true (said on stderr) when they clash. */
static bool resume_opts_bad(bool serial, bool ask, bool from, bool pos)
{
    const char *why = (ask || pos) && !serial
                          ? "--resume and --position need --port (the serial protocol; "
                            "docs/streaming.md, Resume)"
                      : ask && (from || pos) ? "--resume asks the device where to go on: it takes "
                                               "neither --resume-from nor --position"
                      : pos && !from         ? "--position needs --resume-from N"
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

/* The link the options pick, checked against the other options. */
static int pick_link(stream_args_t *a, cs_joblink_t *l)
{
    int rc = cs_joblink_select(l, &a->link);
    if (rc != CS_EXIT_OK || a->job_file == NULL) {
        fprintf(stderr, "curvestep stream: %s\n", rc != CS_EXIT_OK ? l->why : "no job file");
        usage(stderr);
        return CS_EXIT_USAGE;
    }
    if (resume_opts_bad(l->ops == &cs_joblink_serial_ops, a->resume_ask, a->resume_from != 0,
                        a->position != NULL))
        return CS_EXIT_USAGE;
    if (a->link.parity != 0 && a->link.modbus_rtu == NULL) {
        fprintf(stderr, "curvestep stream: --parity applies to --modbus-rtu only\n");
        return CS_EXIT_USAGE;
    }
    if (a->link.mb_timeout_ms != 0 && a->link.modbus_rtu == NULL && a->link.modbus_tcp == NULL) {
        fprintf(stderr, "curvestep stream: --modbus-timeout applies to a Modbus link only\n");
        return CS_EXIT_USAGE;
    }
    if (a->curves && !l->ops->curves) {
        fprintf(stderr,
                "curvestep stream: --%s runs the step segments planned here: --mode "
                "curves does not apply\n",
                a->link.gpio ? "gpio" : "link");
        return CS_EXIT_USAGE;
    }
    if (a->link.parity == 0)
        a->link.parity = 'E';
    l->cfg.parity = a->link.parity;
    return CS_EXIT_OK;
}

/* Reads and plans the job whole (the plan also checks the travel limits in curves mode, where
 * the device plans again itself) into jp and its wire messages into job. */
static int plan(const stream_args_t *a, const cs_joblink_t *l, const cs_machine_t *m,
                const cs_machine_pen_t *pen, cs_pos_t tol, cs_jobplan_t *jp, cs_stream_job_t *job)
{
    cs_jobplan_init(jp);
    cs_jobplan_limits(jp, &a->jo);
    jp->font_file = a->jo.font_file;
    cs_stream_job_init(job, a->curves ? CS_STREAM_CURVES : CS_STREAM_SEGMENTS);
    cs_err_t e = cs_jobplan_read_opts(jp, a->job_file, pen, &a->jo.in);
    if (e == CS_OK)
        e = cs_jobplan_prepare(jp, "stream", &a->jo.in, m, pen, tol, stderr);
    int32_t feed_q = cs_motion_speed(a->jo.feed_mm_s);
    if (e == CS_OK)
        e = cs_jobplan_plan(jp, a->job_file, m, NULL, tol, CS_TRACE_DEFAULT, feed_q);
    if (e == CS_OK)
        e = cs_jobplan_linkable(jp, a->job_file, l->ops->pens, a->curves);
    if (e == CS_OK)
        e = a->curves
                ? cs_stream_job_add_path_pen(job, &jp->path, feed_q > 0 ? feed_q : m->default_feed,
                                             tol, &jp->pen, m->tick_hz, &(cs_vec3_t){0, 0, 0},
                                             &jp->diag)
                : cs_stream_job_add_motion(job, &jp->mo.segs);
    if (e != CS_OK) {
        cs_path_diag_print(stderr, &jp->diag);
        return cs_jobplan_exit(jp, e);
    }
    const char *what = a->curves ? "curves" : "segments";
    fprintf(stderr,
            "stream: %s: %zu elements -> %zu %s (%zu segments planned here, job time %.3f s)%s\n",
            a->job_file, jp->path.n, job->n, what, jp->mo.segs.n, (double)jp->mo.ticks / m->tick_hz,
            a->curves && job->approximated
                ? " ; arcs and other rational curves approximated by cubics within tol/4"
                : "");
    if (a->resume_from > job->n) {
        fprintf(stderr, "curvestep stream: --resume-from %zu: the job has %zu %s\n", a->resume_from,
                job->n, what);
        return CS_EXIT_USAGE;
    }
    cs_path_free(&jp->path);
    return CS_EXIT_OK;
}

/* What a serial run says beyond the one report: where --resume started, and after a lost link
 * the device's confirmed and possibly executed numbers and how to resume. */
static void resume_lines(const stream_args_t *a, const cs_joblink_job_t *j,
                         const cs_stream_result_t *r)
{
    if (a->resume_ask && r->numbered)
        fprintf(stdout,
                "stream: resumed: the device had received %s 1..%zu of this job and finished "
                "%zu of them; sent from %zu on\n",
                a->curves ? "curves" : "segments", r->resume_from, r->resume_done,
                r->resume_from + 1);
    cs_stream_resume_hint(stdout, j->job, r, j->m, a->job_file);
}

/* Opens the link, runs the job with Ctrl-C as a hold, reports, closes. */
static int run_link(const stream_args_t *a, cs_joblink_t *l, const cs_joblink_job_t *j, size_t n)
{
    struct sigaction sig;
    memset(&sig, 0, sizeof sig);
    sig.sa_handler = on_sigint;
    sigaction(SIGINT, &sig, NULL);
    signal(SIGPIPE, SIG_IGN);
    int rc = cs_joblink_open(l, j);
    if (rc != CS_EXIT_OK) {
        if (rc == CS_EXIT_INPUT) /* "file:line: reason" as it is */
            fprintf(stderr, "%s\n", l->why);
        else
            fprintf(stderr, "curvestep stream: %s\n", l->why);
        signal(SIGINT, SIG_DFL);
        return cs_joblink_close(l, rc);
    }
    cs_joblink_ctl_t c = {&interrupted, NULL, a->quiet ? NULL : stderr, isatty(STDERR_FILENO) != 0};
    cs_stream_result_t r;
    cs_err_t e = cs_joblink_run(l, j, &c, &r);
    signal(SIGINT, SIG_DFL);
    if (e != CS_OK) {
        fprintf(stderr, "curvestep stream: %s\n", cs_err_text(e));
        return cs_joblink_close(l, CS_EXIT_INTERNAL);
    }
    rc = cs_joblink_report(l, stdout, n, &r);
    resume_lines(a, j, &r);
    fflush(stdout);
    return cs_joblink_close(l, rc);
}

int cs_cmd_stream(int argc, char **argv)
{
    stream_args_t a;
    int rc = parse_args(argc, argv, &a);
    if (rc >= 0)
        return rc;
    cs_joblink_t l;
    rc = pick_link(&a, &l);
    if (rc != CS_EXIT_OK)
        return rc;
    cs_machine_t m;
    cs_machine_pen_t pen;
    cs_pos_t tol;
    char found[4096]; /* the default machine file, named for the GPIO link too */
    if (a.jo.machine_file == NULL && cs_machine_ini_find(found, sizeof found))
        a.jo.machine_file = found;
    l.cfg.machine_file = a.jo.machine_file;
    rc = cs_jobplan_machine("stream", &a.jo, &m, &pen, &tol);
    if (rc != CS_EXIT_OK)
        return rc;
    cs_jobplan_t jp;
    cs_stream_job_t job;
    rc = plan(&a, &l, &m, &pen, tol, &jp, &job);
    if (rc == CS_EXIT_OK) {
        /* GPIO runs the segments planned here (numbered as segments), the others the messages */
        bool segs = l.ops == &cs_joblink_gpio_ops;
        cs_joblink_job_t j = {.m = &m,
                              .job = &job,
                              .segs = jp.mo.segs.v,
                              .nsegs = jp.mo.segs.n,
                              .pens = jp.mo.segs.pens,
                              .npens = jp.mo.segs.npens,
                              .resume_from = a.resume_from,
                              .resume_ask = a.resume_ask,
                              .stated_pos = a.position != NULL ? a.pos : NULL};
        if (a.position != NULL && check_position(a.position, &m, &job, a.resume_from, a.pos) != 0)
            rc = CS_EXIT_USAGE;
        else
            rc = run_link(&a, &l, &j, segs ? jp.mo.segs.n : job.n);
    }
    cs_stream_job_free(&job);
    cs_jobplan_free(&jp);
    return rc;
}
