/* bench_link: the serial link end to end on this machine. The device is the simulator
 * (cs_sim_device, executing instantly) in a child process on the master end of a pty; the host
 * engine (cs_stream) streams on the slave end. Measured: step segments per second through the
 * pty with no throttle; bytes on the wire per drawing element in curves mode against the same
 * element as step segments; and with both ends paced at 115200 baud (--line-rate, 10 bits a
 * byte), for each W3C SVG drawing at 0.01 mm, the messages per second the line carries and so the
 * path speed it can feed in each mode, against the feed asked for.
 * Writes argv[1] (CSV) and prints a Markdown section on stdout. */
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bench_args.h"
#include "cs_conv.h"
#include "cs_machine_ini.h"
#include "cs_motion.h"
#include "cs_serial.h"
#include "cs_sim_device.h"
#include "cs_stream.h"
#include "cs_trace.h"

static cs_machine_t machine;

typedef struct {
    pid_t pid;
    int fd;
} dev_t_;

static int start_device(dev_t_ *d, uint32_t line_rate)
{
    int master, slave;
    if (cs_serial_openpty(&master, &slave, NULL, 0) != 0)
        return -1;
    fflush(NULL);
    pid_t pid = fork();
    if (pid < 0)
        return -1;
    if (pid == 0) {
        close(slave);
        alarm(600);
        cs_sim_device_cfg_t cfg;
        cs_sim_device_cfg_default(&cfg, &machine);
        cfg.speed = 0;
        cfg.idle_exit_s = 0.5;
        cfg.line_rate = line_rate;
        cs_sim_device_result_t res;
        cs_sim_device_serve(master, &cfg, NULL, &res);
        _exit(0);
    }
    close(master);
    d->pid = pid;
    d->fd = slave;
    return 0;
}

static void stop_device(dev_t_ *d)
{
    int st;
    kill(d->pid, SIGTERM);
    waitpid(d->pid, &st, 0);
    close(d->fd);
}

/* Streams job[0..n) (a prefix of the job) and returns the result. */
static int stream(const cs_stream_job_t *job, size_t n, uint32_t line_rate, cs_stream_result_t *r)
{
    dev_t_ d;
    if (start_device(&d, line_rate) != 0)
        return -1;
    cs_stream_job_t part = *job;
    part.n = n;
    cs_serial_t ser;
    cs_serial_attach(&ser, d.fd);
    cs_serial_set_line_rate(&ser, line_rate);
    cs_stream_opts_t o;
    cs_stream_opts_default(&o, &ser, machine.n_axes, machine.tick_hz);
    cs_stream_link_timing(&o.link, line_rate);
    cs_err_t e = cs_stream_run(&part, &o, r);
    stop_device(&d);
    return e == CS_OK && r->outcome == CS_STREAM_DONE ? 0 : -1;
}

static double path_length(const cs_path_t *p)
{
    double len = 0;
    for (size_t k = 0; k < p->n; k++) {
        double a[3], b[3];
        cs_path_eval_mm(&p->elems[k].curve, 0, a);
        for (int s = 1; s <= 256; s++) {
            cs_path_eval_mm(&p->elems[k].curve, s / 256.0, b);
            len += sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
                        (b[2] - a[2]) * (b[2] - a[2]));
            memcpy(a, b, sizeof a);
        }
    }
    return len;
}

int main(int argc, char **argv)
{
    static const char usage[] = "usage: bench_link OUT.csv\n"
        "Throughput of the serial link protocol against the simulator on a pseudo-terminal;\n"
        "a Markdown section on stdout, the figures in OUT.csv.\n";
    int usage_rc = bench_args_check(argc, argv, usage, 1);
    if (usage_rc >= 0)
        return usage_rc;
    if (argc < 2) {
        fprintf(stderr, "usage: bench_link OUT.csv\n");
        return 2;
    }
    FILE *csv = fopen(argv[1], "w");
    if (csv == NULL) {
        perror(argv[1]);
        return 1;
    }
    signal(SIGPIPE, SIG_IGN);
    cs_machine_ini_default(&machine);
    fprintf(csv, "what,file,mode,line_rate,messages,bytes,seconds,value\n");

    /* 1. raw throughput: random short segments, no throttle */
    const size_t n_raw = 50000;
    cs_segment_t *segs = calloc(n_raw, sizeof *segs);
    uint64_t x = 88172645463325252ull;
    for (size_t k = 0; k < n_raw; k++) {
        x ^= x << 13, x ^= x >> 7, x ^= x << 17;
        segs[k].ticks = 500;
        segs[k].steps[0] = (int32_t)(x % 200) - 100;
        segs[k].steps[1] = (int32_t)((x >> 16) % 200) - 100;
    }
    cs_stream_job_t job;
    cs_stream_job_init(&job, CS_STREAM_SEGMENTS);
    cs_stream_job_add_segments(&job, segs, n_raw);
    cs_stream_result_t r;
    printf("## Serial link (bench_link)\n\n");
    printf("The simulator is the device (`cs_sim_device`, executing instantly) in a child process "
           "on one end of a pseudo-terminal; `cs_stream` streams from the other end. Frames: a "
           "SEGMENT is %d bytes on the wire, a CURVE %d, an ACK %d.\n\n",
           (int)CS_FRAME_WIRE_LEN(CS_PROTO_LEN_SEGMENT), (int)CS_FRAME_WIRE_LEN(CS_PROTO_LEN_CURVE),
           (int)CS_FRAME_WIRE_LEN(CS_PROTO_LEN_ACK));
    if (stream(&job, n_raw, 0, &r) == 0) {
        double rate = (double)n_raw / r.stream_s;
        printf("- **Through the pty, no throttle:** %zu step segments in %.2f s = **%.0f "
               "segments/s** (%.1f MB/s of frames, %u retransmissions).\n",
               n_raw, r.stream_s, rate, (double)r.bytes_out / r.stream_s / 1e6,
               (unsigned)r.link.retransmits);
        fprintf(csv, "pty_no_throttle,random,segments,0,%zu,%llu,%.4f,%.1f\n", n_raw,
                (unsigned long long)r.bytes_out, r.stream_s, rate);
    } else {
        printf("- Through the pty, no throttle: FAILED (%s)\n", cs_stream_outcome_text(r.outcome));
    }
    cs_stream_job_free(&job);
    free(segs);

    /* 2 and 3: the drawings */
    static const char *files[] = {
        "tests/data/svg/w3c/paths-data-01-t.svg", "tests/data/svg/w3c/paths-data-02-t.svg",
        "tests/data/svg/w3c/paths-data-12-t.svg", "tests/data/svg/w3c/paths-data-14-t.svg"};
    const uint32_t baud = 115200;
    const size_t seg_prefix = 2500; /* segments streamed at 115200 to measure the rate */
    printf("\nDrawings planned at 0.01 mm with the built-in machine (feed %.0f mm/s, segments of "
           "%.0f ms). Bytes are what the host wrote, measured over the pty at memory speed. At "
           "%u baud both ends pace their writes as the line would (`--line-rate`); the rate is "
           "measured over the first %zu segments or all the curves. *Sustainable* is the path "
           "speed the line can feed: the job's average path speed times (messages/s the line "
           "carries) / (messages/s the job needs at its planned speed); above the feed asked for "
           "means the line keeps the planner fed (the device here computes instantly: on a real "
           "MCU, curves mode is also bounded by its tracing speed).\n\n",
           cs_machine_ini_to_double(machine.default_feed),
           machine.segment_ticks * 1e3 / machine.tick_hz, (unsigned)baud, seg_prefix);
    printf("| drawing | elements | path mm | job s | segments | bytes as segments | curves | "
           "bytes as curves | bytes per element (seg / curve) | segments/s at %u | curves/s at "
           "%u | sustainable mm/s (seg / curve) |\n",
           (unsigned)baud, (unsigned)baud);
    printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (size_t f = 0; f < sizeof files / sizeof files[0]; f++) {
        cs_path_t path;
        cs_path_init(&path);
        cs_path_diag_t diag;
        if (cs_motion_read_job(files[f], &path, &diag) != CS_OK)
            continue;
        cs_motion_t mo;
        cs_motion_init(&mo, &machine);
        if (cs_motion_plan_path(&mo, &path, machine.tolerance, CS_TRACE_SUBDIV, 0, &diag) !=
            CS_OK) {
            cs_motion_free(&mo);
            cs_path_free(&path);
            continue;
        }
        double job_s = (double)mo.ticks / machine.tick_hz, len = path_length(&path);
        cs_stream_job_t js, jc;
        cs_stream_job_init(&js, CS_STREAM_SEGMENTS);
        cs_stream_job_init(&jc, CS_STREAM_CURVES);
        cs_stream_job_add_segments(&js, mo.segs.v, mo.segs.n);
        cs_stream_job_add_path(&jc, &path, machine.default_feed, machine.tolerance, &diag);
        cs_stream_result_t rs, rc, ps, pc;
        int ok = stream(&js, js.n, 0, &rs) == 0 && stream(&jc, jc.n, 0, &rc) == 0;
        size_t np = js.n < seg_prefix ? js.n : seg_prefix;
        ok = ok && stream(&js, np, baud, &ps) == 0 && stream(&jc, jc.n, baud, &pc) == 0;
        const char *name = strrchr(files[f], '/') + 1;
        if (!ok) {
            printf("| %s | FAILED | | | | | | | | | | |\n", name);
        } else {
            double seg_rate = (double)np / ps.stream_s, cur_rate = (double)jc.n / pc.stream_s;
            double avg_v = len / job_s;
            double sus_s = avg_v * seg_rate / ((double)js.n / job_s);
            double sus_c = avg_v * cur_rate / ((double)jc.n / job_s);
            printf("| %s | %zu | %.0f | %.1f | %zu | %llu | %zu | %llu | %.0f / %.0f | %.0f | %.0f "
                   "| %.0f / %.0f |\n",
                   name, path.n, len, job_s, js.n, (unsigned long long)rs.bytes_out, jc.n,
                   (unsigned long long)rc.bytes_out, (double)rs.bytes_out / (double)path.n,
                   (double)rc.bytes_out / (double)path.n, seg_rate, cur_rate, sus_s, sus_c);
            fprintf(csv, "bytes,%s,segments,0,%zu,%llu,%.4f,%.1f\n", name, js.n,
                    (unsigned long long)rs.bytes_out, rs.stream_s,
                    (double)rs.bytes_out / (double)path.n);
            fprintf(csv, "bytes,%s,curves,0,%zu,%llu,%.4f,%.1f\n", name, jc.n,
                    (unsigned long long)rc.bytes_out, rc.stream_s,
                    (double)rc.bytes_out / (double)path.n);
            fprintf(csv, "sustain,%s,segments,%u,%zu,%llu,%.4f,%.1f\n", name, (unsigned)baud, np,
                    (unsigned long long)ps.bytes_out, ps.stream_s, sus_s);
            fprintf(csv, "sustain,%s,curves,%u,%zu,%llu,%.4f,%.1f\n", name, (unsigned)baud, jc.n,
                    (unsigned long long)pc.bytes_out, pc.stream_s, sus_c);
        }
        fflush(stdout);
        cs_stream_job_free(&js);
        cs_stream_job_free(&jc);
        cs_motion_free(&mo);
        cs_path_free(&path);
    }
    printf("\nFeed asked for: %.0f mm/s (drawing moves; travel moves are rapids). For comparison, "
           "Grbl on an ATmega328p sustains roughly 280-400 short moves a second before its "
           "planner starves; a 115200-baud line carries at most %.0f SEGMENT frames a second "
           "(one segment = %.0f ms of motion here).\n",
           cs_machine_ini_to_double(machine.default_feed),
           baud / 10.0 / CS_FRAME_WIRE_LEN(CS_PROTO_LEN_SEGMENT),
           machine.segment_ticks * 1e3 / machine.tick_hz);
    fclose(csv);
    return 0;
}
