/* bench_modbus: step segments per second over each link on this machine: the serial protocol
 * through a pty (cs_stream against cs_sim_device), Modbus TCP on loopback (cs_mb_stream_run with
 * libmodbus's client against the simulator's own server, cs_sim_mbtcp) and Modbus RTU through a pty
 * (libmodbus's RTU client against the core's RTU server in the simulator). The devices execute
 * instantly, so the figure is what the link carries. Each link streams the same random job; the
 * device's count and hash of the executed segments are checked against the job. Also the bytes
 * each link puts on the wire per segment, and the rate a real 115200-baud RTU line allows.
 * Writes argv[1] (CSV) and prints a Markdown section on stdout. */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bench_args.h"
#include "cs_machine_ini.h"
#include "fw_test.h"
#include "cs_modbus.h"
#include "cs_modbus_stream.h"
#include "cs_serial.h"
#include "cs_sim_device.h"
#include "cs_sim_modbus.h"
#include "cs_stream.h"

static cs_machine_t machine;

/* The Modbus device: `curvestep-sim --modbus-tcp 127.0.0.1:0 | --modbus-rtu pty --instant` in a
 * child process; its first stdout line (the address) is read from a pipe, its report is
 * discarded except the executed count and hash, returned through *out when it ends. */
typedef struct {
    pid_t pid;
    FILE *out;
    char addr[256];
} mbdev_t_;

static int start_modbus(mbdev_t_ *d, bool tcp)
{
    int p[2];
    if (pipe(p) != 0)
        return -1;
    fflush(NULL);
    pid_t pid = fork();
    if (pid < 0)
        return -1;
    if (pid == 0) {
        close(p[0]);
        dup2(p[1], STDOUT_FILENO);
        close(p[1]);
        alarm(600);
        char *argv[] = {"curvestep-sim", tcp ? "--modbus-tcp" : "--modbus-rtu",
                        tcp ? "127.0.0.1:0" : "pty", "--instant", NULL};
        _exit(cs_sim_modbus_main(4, argv));
    }
    close(p[1]);
    d->pid = pid;
    d->out = fdopen(p[0], "r");
    if (d->out == NULL || fgets(d->addr, sizeof d->addr, d->out) == NULL)
        return -1;
    d->addr[strcspn(d->addr, "\n")] = '\0';
    return 0;
}

/* Stops the device and reads the executed count and hash from its report. */
static void stop_modbus(mbdev_t_ *d, unsigned long long *executed, unsigned long long *hash)
{
    kill(d->pid, SIGTERM);
    char line[512];
    *executed = 0, *hash = 0;
    while (fgets(line, sizeof line, d->out) != NULL) {
        sscanf(line, "device: served %*f s; %llu messages executed", executed);
        sscanf(line, "executed step segments' hash (FNV-1a 32, in order): %llx", hash);
    }
    fclose(d->out);
    int st;
    waitpid(d->pid, &st, 0);
}

typedef struct {
    const char *name;
    double seconds, rate, bytes_per_seg;
    unsigned retx;
    bool ok;
} row_t;

static row_t run_serial(const cs_stream_job_t *job, uint64_t want)
{
    row_t row = {"serial protocol, pty", 0, 0, 0, 0, false};
    int master, slave, p[2];
    if (cs_serial_openpty(&master, &slave, NULL, 0) != 0 || pipe(p) != 0)
        return row;
    fflush(NULL);
    pid_t pid = fork();
    if (pid == 0) {
        close(slave);
        close(p[0]);
        alarm(600);
        cs_sim_device_cfg_t cfg;
        cs_sim_device_cfg_default(&cfg, &machine);
        cfg.speed = 0;
        cfg.idle_exit_s = 0.5;
        cs_sim_device_result_t res;
        cs_sim_device_serve(master, &cfg, NULL, &res);
        unsigned long long v[2] = {res.executed, res.seg_hash};
        _exit(write(p[1], v, sizeof v) == sizeof v ? 0 : 1);
    }
    close(master);
    close(p[1]);
    cs_serial_t ser;
    cs_serial_attach(&ser, slave);
    cs_stream_opts_t o;
    cs_stream_opts_default(&o, &ser, machine.n_axes, machine.tick_hz);
    cs_stream_result_t r;
    cs_err_t e = cs_stream_run(job, &o, &r);
    unsigned long long v[2] = {0, 0};
    if (read(p[0], v, sizeof v) != sizeof v)
        v[0] = 0;
    int st;
    waitpid(pid, &st, 0);
    close(slave);
    close(p[0]);
    row.ok = e == CS_OK && r.outcome == CS_STREAM_DONE && v[0] == job->n && v[1] == want;
    row.seconds = r.stream_s;
    row.rate = (double)job->n / r.stream_s;
    row.bytes_per_seg = (double)(r.bytes_out + r.bytes_in) / (double)job->n;
    row.retx = r.link.retransmits;
    return row;
}

static row_t run_modbus(const cs_stream_job_t *job, uint64_t want, bool tcp)
{
    row_t row = {tcp ? "Modbus TCP, loopback" : "Modbus RTU, pty", 0, 0, 0, 0, false};
    mbdev_t_ d;
    if (start_modbus(&d, tcp) != 0)
        return row;
    cs_mb_client_t c;
    char why[256];
    int orc = tcp ? cs_mb_open_tcp(&c, d.addr, 1, 200, 6, why, sizeof why)
                  : cs_mb_open_rtu(&c, d.addr, 115200, 'E', 1, 200, 6, why, sizeof why);
    cs_stream_result_t r;
    memset(&r, 0, sizeof r);
    cs_err_t e = CS_ERR_IO;
    if (orc == 0) {
        cs_mb_stream_opts_t o;
        cs_mb_stream_opts_default(&o, &c, machine.n_axes, machine.tick_hz);
        e = cs_mb_stream_run(job, &o, &r);
        cs_mb_close(&c);
    } else {
        fprintf(stderr, "bench_modbus: %s\n", why);
    }
    unsigned long long executed, hash;
    stop_modbus(&d, &executed, &hash);
    row.ok = e == CS_OK && r.outcome == CS_STREAM_DONE && executed == job->n && hash == want;
    row.seconds = r.stream_s;
    row.rate = r.stream_s > 0 ? (double)job->n / r.stream_s : 0;
    row.bytes_per_seg = (double)(r.bytes_out + r.bytes_in) / (double)job->n;
    row.retx = r.link.retransmits;
    return row;
}

int main(int argc, char **argv)
{
    static const char usage[] = "usage: bench_modbus OUT.csv\n"
        "Throughput of streaming over Modbus TCP and RTU to the simulator; a Markdown\n"
        "section on stdout, the figures in OUT.csv.\n";
    int usage_rc = bench_args_check(argc, argv, usage, 1);
    if (usage_rc >= 0)
        return usage_rc;
    if (argc < 2) {
        fprintf(stderr, "usage: bench_modbus OUT.csv\n");
        return 2;
    }
    FILE *csv = fopen(argv[1], "w");
    if (csv == NULL) {
        perror(argv[1]);
        return 1;
    }
    signal(SIGPIPE, SIG_IGN);
    cs_machine_ini_default(&machine);
    fprintf(csv, "link,segments,seconds,segments_per_s,bytes_per_segment,retransmissions,ok\n");
    const size_t n = 20000;
    cs_stream_job_t job;
    cs_stream_job_init(&job, CS_STREAM_SEGMENTS);
    uint64_t x = 88172645463325252ull, want = FW_TEST_HASH0;
    for (size_t k = 0; k < n; k++) {
        x ^= x << 13, x ^= x >> 7, x ^= x << 17;
        cs_segment_t s = {.ticks = 500};
        s.steps[0] = (int32_t)(x % 200) - 100;
        s.steps[1] = (int32_t)((x >> 16) % 200) - 100;
        cs_stream_job_add_segments(&job, &s, 1);
        want = fw_test_hash(want, &s);
    }
    row_t rows[3];
    fprintf(stderr, "bench_modbus: serial\n");
    rows[0] = run_serial(&job, want);
    fprintf(stderr, "bench_modbus: modbus tcp\n");
    rows[1] = run_modbus(&job, want, true);
    fprintf(stderr, "bench_modbus: modbus rtu\n");
    rows[2] = run_modbus(&job, want, false);

    /* a real RTU line: an FC16 request of R registers is 9 + 2 R bytes (unit, function,
     * address, quantity, byte count, data, CRC), R = the token + a SEGMENT's 12; its answer 8
     * bytes; one status read (8 bytes, answer 5 + 2 x 26) per queue's worth of writes; at 11
     * bits a character, plus the 3.5-character gap after each frame (1750 us above 19200) */
    const double baud = 115200, qsize = 32;
    const double seg_req = 9.0 + 2.0 * (1 + CS_MODBUS_MAILBOX_SEGMENT_REGS);
    const double cur_req = 9.0 + 2.0 * (1 + CS_MODBUS_MAILBOX_CURVE_REGS);
    const double st_bytes = 8.0 + 5.0 + 2.0 * CS_MODBUS_IR_COUNT;
    double wr = (seg_req + 8.0) * 11.0 / baud + 2 * 1750e-6;
    double st = st_bytes * 11.0 / baud + 2 * 1750e-6;
    double line_rate = 1.0 / (wr + st / qsize);

    printf("## Links: serial, Modbus TCP, Modbus RTU (bench_modbus)\n\n");
    printf("The same job, %zu random step segments (5 ms each, up to 100 steps per axis), streamed "
           "by the host engine of each link to the simulator executing instantly in a child "
           "process, so the figure is what the link carries. Serial: `cs_stream` over a pty, "
           "window of 8 frames. Modbus: `cs_mb_stream_run`, libmodbus 3.1.6 client, one FC16 "
           "mailbox write (the lease's token and 12 registers) per segment, waiting for its "
           "answer, plus one FC04 status read (26 registers) whenever the %d queue slots it "
           "knows of are used; TCP through the simulator's own server (`cs_sim_mbtcp`) on "
           "127.0.0.1, RTU through the core's RTU "
           "server on a pty (no baud-rate pacing). Every run is checked: the device executed "
           "exactly the job (count and FNV-1a hash of the executed segments).\n\n",
           n, (int)qsize);
    printf("| link | seconds | segments/s | bytes per segment (both ways) | retransmissions | "
           "executed = job |\n");
    printf("|---|---:|---:|---:|---:|---|\n");
    for (int k = 0; k < 3; k++) {
        printf("| %s | %.2f | **%.0f** | %.1f | %u | %s |\n", rows[k].name, rows[k].seconds,
               rows[k].rate, rows[k].bytes_per_seg, rows[k].retx, rows[k].ok ? "yes" : "NO");
        fprintf(csv, "%s,%zu,%.4f,%.1f,%.2f,%u,%d\n", rows[k].name, n, rows[k].seconds,
                rows[k].rate, rows[k].bytes_per_seg, rows[k].retx, rows[k].ok);
    }
    /* a CURVE: the token and 28 registers, same answer */
    double wr_c = (cur_req + 8.0) * 11.0 / baud + 2 * 1750e-6;
    double curve_rate = 1.0 / (wr_c + st / qsize);
    printf("\nModbus waits for each answer before the next write (one request in flight, as "
           "the protocol has it), so its rate is one round trip per segment; the serial link "
           "keeps 8 frames in flight. On a real 115200-baud RTU line the wire itself allows "
           "about **%.0f segments/s** (computed: %.0f bytes for a write and its answer at 11 "
           "bits a character, the 3.5-character gap of 1.75 ms after each frame, a status read "
           "every %d writes), i.e. %.2f s of motion per second with 5 ms segments: below the "
           "%.0f segments/s the built-in machine's segments need, so the executor would run dry. "
           "Over a real RTU line stream curves (`--mode curves`: one %d-register write a cubic, "
           "about **%.0f curves/s** on the same line, each curve many segments of motion) or "
           "plan longer segments.\n",
           line_rate, seg_req + 8.0, (int)qsize, line_rate * 0.005,
           (double)machine.tick_hz / machine.segment_ticks, CS_MODBUS_MAILBOX_CURVE_REGS,
           curve_rate);
    fprintf(csv, "Modbus RTU 115200 baud (computed),0,0,%.1f,%.1f,0,1\n", line_rate,
            seg_req + 8.0 + st_bytes / qsize);
    fprintf(csv, "Modbus RTU 115200 baud curves (computed),0,0,%.1f,%.1f,0,1\n", curve_rate,
            cur_req + 8.0 + st_bytes / qsize);
    fclose(csv);
    cs_stream_job_free(&job);
    return 0;
}
