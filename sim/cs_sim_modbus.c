/* cs_sim_modbus: the simulated device behind Modbus (docs/modbus.md). The register map and its
 * sequence rule are the core's (firmware/core/cs_modbus); the motion side is the serial
 * device's (cs_sim_motion_*). Modbus TCP: the simulator's own server (cs_sim_mbtcp: several
 * clients, served in turn, MBAP checked) hands each request PDU to the core's handler. Modbus
 * RTU: the core's own RTU server, fed byte by byte from a pty or a tty. */
#include "cs_sim_modbus.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "cs_conv.h"
#include "cs_err_text.h"
#include "cs_jobplan.h"
#include "cs_fw_modbus.h"
#include "cs_machine_ini.h"
#include "cs_modbus.h"
#include "cs_motion.h"
#include "cs_serial.h"
#include "cs_sim_device.h"
#include "cs_sim_mbtcp.h"

#define DELAYED_MAX 8

typedef struct {
    double drop;      /* probability that an answer is not sent (the request was handled) */
    double delay;     /* probability that an answer is sent delay_ms late */
    double delay_ms;  /* default 300 */
    double busy;      /* probability that a mailbox write is refused with DEVICE_BUSY */
    uint64_t fail_at; /* the Nth mailbox write (counting every attempt) gets DEVICE_FAILURE */
    uint64_t seed;
} mb_faults_t;

typedef struct { /* an RTU answer held back by the delay fault (TCP: cs_sim_mbtcp's own) */
    double due;
    uint8_t rsp[CS_MODBUS_RTU_MAX];
    size_t rlen;
} delayed_t;

typedef struct {
    cs_sim_motion_t *mo;
    cs_fw_modbus_t fm; /* the device's Modbus front end (firmware/app) */
    const cs_machine_t *m;
    cs_modbus_map_t map;
    uint8_t unit;
    mb_faults_t f;
    uint64_t rng;
    uint64_t writes; /* mailbox writes seen by submit */
    /* counters for the report */
    uint64_t dropped, delayed, busy, failed, wrong_unit, requests;
    delayed_t dl[DELAYED_MAX];
    unsigned ndl;
    double last_rx_s;
    double idle_exit;         /* --idle-exit, 0: none */
    cs_sim_mbtcp_stats_t tcp; /* the TCP server's counters */
} mbdev_t;

static double rnd(mbdev_t *d)
{
    uint64_t x = d->rng;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    d->rng = x;
    return (double)(x >> 11) * (1.0 / 9007199254740992.0);
}

/* --- the register map's hooks: the firmware's Modbus front end, with faults in front ------- */

/* A mailbox write: the injected refusals first, then the device's own (cs_fw_modbus). */
static cs_err_t app_submit(void *ctx, const cs_proto_msg_t *m, uint16_t seq)
{
    mbdev_t *d = ctx;
    d->writes++;
    if (d->f.fail_at != 0 && d->writes == d->f.fail_at) {
        d->failed++;
        return CS_ERR_STATE; /* -> exception 04, SERVER DEVICE FAILURE */
    }
    if (d->f.busy > 0 && rnd(d) < d->f.busy) {
        d->busy++;
        return CS_ERR_FULL; /* -> exception 06, SERVER DEVICE BUSY */
    }
    return cs_fw_modbus_submit(&d->fm, m, seq);
}

/* The rest goes to the device's front end as it is (the map has one ctx for its hooks). */
static void app_command(void *ctx, uint16_t cmd)
{
    mbdev_t *d = ctx;
    cs_fw_modbus_command(&d->fm, cmd);
}

static void app_status(void *ctx, cs_modbus_status_t *st)
{
    mbdev_t *d = ctx;
    cs_fw_modbus_status(&d->fm, st);
}

static cs_err_t app_lease(void *ctx, uint8_t op, uint16_t token)
{
    mbdev_t *d = ctx;
    return cs_fw_modbus_lease(&d->fm, op, token);
}

/* Runs the motion paced to the wall clock, latches its errors (cs_fw_modbus) and sets the
 * lease's clock: a request sees the device as of now. */
static void step_motion(mbdev_t *d)
{
    double now = cs_serial_now_s();
    cs_sim_motion_advance(d->mo, now);
    cs_fw_modbus_collect(&d->fm);
    cs_fw_modbus_clock(&d->fm, (uint32_t)(uint64_t)(now * 1000.0));
}

/* True once the job ran and --idle-exit seconds passed since the last request. */
static bool idle_done(const mbdev_t *d)
{
    return d->idle_exit > 0 && cs_sim_motion_started(d->mo) && cs_sim_motion_done(d->mo) &&
           cs_serial_now_s() - d->last_rx_s > d->idle_exit;
}

/* What to do with an answer: 0 send now, 1 drop, 2 delay. */
static int answer_fate(mbdev_t *d)
{
    if (d->f.drop > 0 && rnd(d) < d->f.drop) {
        d->dropped++;
        return 1;
    }
    if (d->f.delay > 0 && d->ndl < DELAYED_MAX && rnd(d) < d->f.delay) {
        d->delayed++;
        return 2;
    }
    return 0;
}

static void sleep_us(long us)
{
    struct timespec ts = {us / 1000000L, (us % 1000000L) * 1000L};
    nanosleep(&ts, NULL);
}

/* --- Modbus TCP (cs_sim_mbtcp) -------------------------------------------------------------- */

/* One request from any client: another unit's is not answered (0 and 255, which some TCP
 * clients send, included); ours goes to the core's handler with the motion as of now, and the
 * answer faults decide when (or whether) it goes out. */
static double tcp_handle(void *ctx, uint8_t unit, const uint8_t *pdu, size_t n, uint8_t *rsp,
                         size_t *rn)
{
    mbdev_t *d = ctx;
    d->last_rx_s = cs_serial_now_s();
    d->requests++;
    if (unit != d->unit) {
        d->wrong_unit++;
        return -1;
    }
    step_motion(d);
    cs_modbus_pdu(&d->map, pdu, n, rsp, CS_MODBUS_PDU_MAX, rn);
    int fate = answer_fate(d);
    return fate == 0 ? 0.0 : fate == 1 ? -1.0 : d->f.delay_ms / 1000.0;
}

static bool tcp_tick(void *ctx)
{
    mbdev_t *d = ctx;
    step_motion(d);
    return idle_done(d);
}

static bool tcp_busy(void *ctx)
{
    mbdev_t *d = ctx;
    return cs_sim_motion_busy(d->mo) != 0;
}

static int serve_tcp(mbdev_t *d, const char *addr, volatile sig_atomic_t *stop)
{
    cs_sim_mbtcp_app_t app = {tcp_handle, tcp_tick, tcp_busy, d};
    return cs_sim_mbtcp_serve(addr, &app, stop, &d->tcp);
}

/* --- Modbus RTU (the core's server) ---------------------------------------------------------- */

static void rtu_write(cs_serial_t *ser, const uint8_t *b, size_t n)
{
    if (cs_serial_write(ser, b, n) != 0)
        ser->lost += n;
}

/* The character format of a real line: 8 data bits, parity 'E' / 'O' with one stop bit, or 'N'
 * with two (every character 11 bits, Modbus over serial line V1.02, 2.5.1). Parity errors are
 * checked (INPCK) and the byte dropped (IGNPAR): the frame then fails its length or CRC and is
 * not answered, as the spec wants for a character error. */
static int set_parity(int fd, char parity)
{
    struct termios t;
    if (tcgetattr(fd, &t) != 0)
        return -1;
    t.c_cflag &= ~(tcflag_t)(PARENB | PARODD | CSTOPB);
    t.c_iflag &= ~(tcflag_t)(INPCK | IGNPAR | PARMRK | ISTRIP);
    if (parity == 'N') {
        t.c_cflag |= CSTOPB;
    } else {
        t.c_cflag |= PARENB | (parity == 'O' ? PARODD : 0);
        t.c_iflag |= INPCK | IGNPAR;
    }
    return tcsetattr(fd, TCSANOW, &t);
}

/* Opens the line: a new pty (its path printed) or the serial device dev at baud and parity.
 * 0, or the exit status (1: the device, 3: the pty) with the reason on stderr. */
static int rtu_open(const char *dev, uint32_t baud, char parity, cs_serial_t *ser, int *keep)
{
    *keep = -1;
    if (strcmp(dev, "pty") == 0) {
        int fd;
        char name[256];
        if (cs_serial_openpty(&fd, keep, name, sizeof name) != 0) {
            perror("curvestep-sim: openpty");
            return 3;
        }
        printf("%s\n", name);
        fflush(stdout);
        cs_serial_attach(ser, fd);
        return 0;
    }
    if (cs_serial_open(ser, dev, baud) != 0) {
        fprintf(stderr, "curvestep-sim: %s: %s\n", dev, cs_serial_strerror(errno));
        return 1;
    }
    if (set_parity(ser->fd, parity) != 0) {
        fprintf(stderr, "curvestep-sim: %s: parity: %s\n", dev, strerror(errno));
        close(ser->fd);
        return 1;
    }
    return 0;
}

static int serve_rtu(mbdev_t *d, const char *dev, uint32_t baud, char parity,
                     volatile sig_atomic_t *stop, cs_modbus_rtu_stats_t *rs)
{
    int keep;
    cs_serial_t ser;
    int orc = rtu_open(dev, baud, parity, &ser, &keep);
    if (orc != 0)
        return orc;
    int fd = ser.fd;
    cs_serial_set_lossy(&ser, true);
    cs_modbus_rtu_t *r = calloc(1, sizeof *r);
    if (r == NULL || cs_modbus_rtu_init(r, &d->map, d->unit, baud) != CS_OK) {
        free(r);
        close(fd);
        if (keep >= 0)
            close(keep);
        return 3;
    }
    int rc = 0;
    uint8_t buf[512];
    while (!*stop) {
        double now = cs_serial_now_s();
        for (unsigned k = 0; k < d->ndl;) {
            if (d->dl[k].due <= now) {
                rtu_write(&ser, d->dl[k].rsp, d->dl[k].rlen);
                d->dl[k] = d->dl[--d->ndl];
            } else {
                k++;
            }
        }
        int busy = cs_sim_motion_busy(d->mo);
        ssize_t n = cs_serial_read(&ser, buf, sizeof buf, busy || d->ndl ? 1 : 2);
        if (n < 0) {
            if (errno == EIO || errno == EBADF) {
                rc = 3;
                break;
            }
            sleep_us(2000);
            n = 0;
        }
        uint32_t us = cs_serial_now_us();
        if (n > 0) {
            d->last_rx_s = cs_serial_now_s();
            step_motion(d); /* a status read sees the motion as of now */
        }
        for (ssize_t k = 0; k <= n; k++) {
            const uint8_t *reply = NULL;
            size_t len = 0;
            cs_err_t e;
            if (k < n) {
                e = cs_modbus_rtu_feed(r, buf[k], us, &reply, &len);
            } else {
                e = cs_modbus_rtu_idle(r, cs_serial_now_us(), &reply, &len);
            }
            if (e != CS_OK)
                continue;
            d->requests++;
            int fate = answer_fate(d);
            if (fate == 0) {
                rtu_write(&ser, reply, len);
            } else if (fate == 2) {
                delayed_t *q = &d->dl[d->ndl++];
                q->due = cs_serial_now_s() + d->f.delay_ms / 1000.0;
                memcpy(q->rsp, reply, len);
                q->rlen = len;
            }
        }
        step_motion(d);
        if (idle_done(d))
            break;
    }
    d->wrong_unit += r->stats.other_unit;
    *rs = r->stats;
    free(r);
    close(fd);
    if (keep >= 0)
        close(keep);
    return rc;
}

/* --- the command line ------------------------------------------------------------------------ */

static volatile sig_atomic_t g_stop;

static void on_signal(int sig)
{
    (void)sig;
    g_stop = 1;
}

static void usage(FILE *f)
{
    fputs("usage: curvestep-sim --modbus-tcp ADDR:PORT | --modbus-rtu pty|DEV [--baud N]\n"
          "                     [--parity none|even|odd] [--unit ID] [--machine FILE.ini]\n"
          "                     [--queue N] [--speed X | --instant] [--faults SPEC] [--tol MM]\n"
          "                     [--idle-exit S] [--reference JOB] [--check]\n"
          "                     [--svg OUT.svg] [--png OUT.png] [--trace OUT.csv]\n"
          "Runs the simulator as a Modbus device with the register map of docs/modbus.md:\n"
          "`curvestep stream --modbus-tcp ...` or `--modbus-rtu ...` streams to it.\n"
          "  --modbus-tcp A:P  serve Modbus TCP on IPv4 address A, port P, to up to 8 clients\n"
          "                    at once, in turn (docs/modbus.md); use\n"
          "                    127.0.0.1 (loopback) unless the device must be reachable from\n"
          "                    elsewhere. Port 0 picks a free port. The first line of standard\n"
          "                    output is the address and port bound, e.g. 127.0.0.1:40123\n"
          "  --modbus-rtu pty  serve Modbus RTU (the core's own RTU server) on a new\n"
          "                    pseudo-terminal; the first line of standard output is its path\n"
          "  --modbus-rtu DEV  serve Modbus RTU on the serial line DEV (raw, at --baud and\n"
          "                    --parity)\n"
          "  --baud N          RTU line speed (default 115200; sets the 3.5-character gap)\n"
          "  --parity P        RTU character format: even (default, 8E1), odd (8O1) or none\n"
          "                    (8N2), as `curvestep stream --parity`; a pty has no bits on a\n"
          "                    wire: there it is accepted and changes nothing\n"
          "  --unit ID         Modbus unit id, 1..247 (default 1); requests for another unit\n"
          "                    are not answered\n"
          "  --machine FILE    machine description (default: the built-in plotter)\n"
          "  --queue N         motion-queue slots, 1..256 (default 32)\n"
          "  --speed X         simulated seconds per wall second (default 1: real time)\n"
          "  --instant         execute everything as soon as it arrives\n"
          "  --faults SPEC     comma-separated: drop=P (an answer is not sent, after the request\n"
          "                    was handled), delay=P (an answer is sent late), delay-ms=MS (how\n"
          "                    late, default 300), busy=P (a mailbox write is refused with\n"
          "                    exception 6, SERVER DEVICE BUSY, and not taken), fail-at=N (the\n"
          "                    Nth mailbox write is refused with exception 4, SERVER DEVICE\n"
          "                    FAILURE), seed=N\n"
          "  --tol MM          chord tolerance for curves (default: the machine's)\n"
          "  --idle-exit S     stop S seconds after the last request, once something was\n"
          "                    executed and the queue is empty (default: run until a signal)\n"
          "  --reference JOB   the job: measure the deviation and the final position\n"
          "  --check           exit 4 when a check of the report fails\n"
          "  --svg/--png/--trace  drawings and the CSV of every step edge, as with --replay\n"
          "SIGINT or SIGTERM ends the service; the report goes to standard output.\n"
          "Exit status: 0 ok, 1 bad input, 2 bad command line, 3 internal or line error,\n"
          "4 a check failed (with --check).\n",
          f);
}

static int parse_faults(const char *spec, mb_faults_t *f)
{
    char buf[256];
    if (strlen(spec) >= sizeof buf)
        return -1;
    strcpy(buf, spec);
    for (char *tok = strtok(buf, ","); tok != NULL; tok = strtok(NULL, ",")) {
        char *eq = strchr(tok, '=');
        if (eq == NULL)
            return -1;
        *eq = '\0';
        char *end;
        double v = strtod(eq + 1, &end);
        if (*end != '\0' || eq[1] == '\0' || !(v >= 0))
            return -1;
        if (strcmp(tok, "drop") == 0 && v <= 1)
            f->drop = v;
        else if (strcmp(tok, "delay") == 0 && v <= 1)
            f->delay = v;
        else if (strcmp(tok, "delay-ms") == 0 && v >= 1 && v <= 60000)
            f->delay_ms = v;
        else if (strcmp(tok, "busy") == 0 && v <= 1)
            f->busy = v;
        else if (strcmp(tok, "fail-at") == 0 && v >= 1)
            f->fail_at = (uint64_t)v;
        else if (strcmp(tok, "seed") == 0)
            f->seed = (uint64_t)v;
        else
            return -1;
    }
    return 0;
}

enum { OK = 0, INPUT = 1, USAGE = 2, INTERNAL = 3 };

/* The command line, parsed. */
typedef struct {
    const char *tcp, *rtu;
    long unit;
    char parity;            /* 0: not given (even) */
    cs_sim_device_opts_t o; /* the options the serial device takes too */
    mb_faults_t f;
} mb_args_t;

/* Parses argv into *a: -1 to go on, else the exit status (--help: OK, a bad option: USAGE). */
static int parse_args(int argc, char **argv, mb_args_t *a)
{
    *a = (mb_args_t){.unit = 1, .f = {.delay_ms = 300}};
    cs_sim_device_opts_default(&a->o);
    for (int i = 1; i < argc; i++) /* `--modbus-tcp --help` too */
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            usage(stdout);
            return OK;
        }
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        bool has = i + 1 < argc;
        char *end = NULL;
        int took = cs_sim_device_opt(argc, argv, &i, &a->o);
        if (took < 0)
            return USAGE;
        if (took > 0)
            continue;
        if (strcmp(arg, "--modbus-tcp") == 0 && has) {
            a->tcp = argv[++i];
        } else if (strcmp(arg, "--modbus-rtu") == 0 && has) {
            a->rtu = argv[++i];
        } else if (strcmp(arg, "--parity") == 0 && has) {
            const char *v = argv[++i];
            a->parity = strcmp(v, "none") == 0   ? 'N'
                        : strcmp(v, "even") == 0 ? 'E'
                        : strcmp(v, "odd") == 0  ? 'O'
                                                 : 0;
            if (a->parity == 0) {
                fprintf(stderr, "curvestep-sim: --parity wants none, even or odd\n");
                return USAGE;
            }
        } else if (strcmp(arg, "--unit") == 0 && has) {
            a->unit = strtol(argv[++i], &end, 10);
            if (*end != '\0' || a->unit < 0) {
                fprintf(stderr, "curvestep-sim: %s wants a number\n", arg);
                return USAGE;
            }
        } else {
            fprintf(stderr, "curvestep-sim: unknown or incomplete option %s\n", arg);
            usage(stderr);
            return USAGE;
        }
    }
    return -1;
}

/* The combinations and ranges parse_args cannot see one option at a time: OK or USAGE. */
static int check_args(mb_args_t *a)
{
    const char *why = NULL;
    if ((a->tcp != NULL) == (a->rtu != NULL))
        why = "give exactly one of --modbus-tcp and --modbus-rtu";
    else if (a->parity != 0 && a->rtu == NULL)
        why = "--parity applies to --modbus-rtu only";
    else if (a->o.queue < 1 || a->o.queue > CS_SIM_DEVICE_QUEUE_MAX)
        why = "--queue wants 1..256";
    else if (a->unit < 1 || a->unit > 247)
        why = "--unit wants a Modbus unit id, 1..247";
    else if (!cs_serial_baud_ok((uint32_t)a->o.baud) || a->o.baud == 0)
        why = "--baud is not a termios rate";
    else if (a->o.faults != NULL && parse_faults(a->o.faults, &a->f) != 0)
        why = "--faults: bad list (see --modbus-tcp --help)";
    if (why != NULL) {
        fprintf(stderr, "curvestep-sim: %s\n", why);
        return USAGE;
    }
    return OK;
}

/* The machine (and its pen settings: with a servo pen the check follows them), the device's
 * configuration and the reference job: OK, INPUT or USAGE. */
static int prepare(const mb_args_t *a, cs_machine_t *m, cs_machine_pen_t *pen,
                   cs_sim_device_cfg_t *cfg, cs_sim_ref_t *ref, cs_sim_device_out_t *out)
{
    char err[512];
    cs_machine_ini_pen_default(pen);
    if (a->o.machine_file) {
        if (cs_machine_ini_load_pen(a->o.machine_file, m, pen, err, sizeof err) != 0) {
            fprintf(stderr, "%s\n", err);
            return INPUT;
        }
    } else {
        cs_machine_ini_default(m);
    }
    cs_sim_device_cfg_default(cfg, m);
    cfg->queue_size = (uint16_t)a->o.queue;
    cfg->speed = a->o.instant ? 0 : a->o.speed;
    cfg->keep_edges = true;
    if (a->o.tol_mm > 0 && cs_conv_tol_to_pos(a->o.tol_mm, &cfg->tol) != CS_OK) {
        fprintf(stderr, "curvestep-sim: --tol %g mm is outside the accepted range\n", a->o.tol_mm);
        return USAGE;
    }
    *out = a->o.out;
    out->ref = ref;
    if (pen->mode == CS_MACHINE_PEN_SERVO)
        out->pen = pen;
    if (out->reference) { /* a bad job is reported before anything is served */
        cs_jobplan_t jp;  /* read and laid out as plan / stream do (cs_jobopts) */
        cs_jobplan_init(&jp);
        cs_err_t e = cs_jobplan_reference(&jp, out->reference, &a->o.in, a->o.machine_file, m);
        if (e == CS_OK)
            e = cs_sim_ref_from_path(ref, &jp.path, out->end_mm);
        else
            cs_path_diag_print(stderr, &jp.diag);
        cs_jobplan_free(&jp);
        if (e != CS_OK)
            return INPUT;
    }
    return OK;
}

/* The device: the motion side and the firmware's Modbus front end behind the core's map, the
 * injected refusals in front (one ctx for the hooks). NULL (said on stderr) when it fails. */
static mbdev_t *open_device(const mb_args_t *a, const cs_machine_t *m,
                            const cs_sim_device_cfg_t *cfg, cs_sim_device_result_t *res,
                            double start)
{
    mbdev_t *d = calloc(1, sizeof *d);
    if (d == NULL)
        return NULL;
    d->m = m;
    d->unit = (uint8_t)a->unit;
    d->f = a->f;
    d->rng = a->f.seed ? a->f.seed : 0x9E3779B97F4A7C15ull;
    d->last_rx_s = start;
    d->idle_exit = a->o.idle_exit;
    cs_err_t e = cs_sim_motion_open(&d->mo, cfg, res);
    if (e == CS_OK) {
        cs_modbus_app_t app;
        cs_fw_modbus_init(&d->fm, cs_sim_motion_fw(d->mo),
                          (uint32_t)getpid() * 2654435761u ^ (uint32_t)(start * 1e6), &app);
        app = (cs_modbus_app_t){app_submit, app_command, app_status, app_lease, d};
        e = cs_modbus_map_init(&d->map, &app, 0);
    }
    if (e != CS_OK) {
        fprintf(stderr, "curvestep-sim: device failed: %s\n", cs_err_text(e));
        if (d->mo)
            cs_sim_motion_close(d->mo);
        free(d);
        return NULL;
    }
    return d;
}

/* The Modbus lines of the report (the rest is the serial device's). */
static void report_modbus(const mbdev_t *d, const cs_sim_device_result_t *res, bool tcp,
                          const cs_modbus_rtu_stats_t *rs)
{
    cs_modbus_stats_t ms = d->map.stats;
    printf("device: served %.2f s; %llu messages executed (%llu step segments, %llu curves); "
           "%u holds, %u aborts, error %u (%s)\n",
           res->wall_s, (unsigned long long)res->executed, (unsigned long long)res->segments,
           (unsigned long long)res->curves, (unsigned)res->holds, (unsigned)res->aborts,
           (unsigned)d->fm.error, d->fm.error ? cs_err_text((cs_err_t)d->fm.error) : "none");
    printf("modbus %s unit %u: %llu requests (%llu for other units, not answered); %u mailbox "
           "writes accepted, %u repeats answered without executing, %u refused; %u exceptions\n",
           tcp ? "tcp" : "rtu", (unsigned)d->unit, (unsigned long long)d->requests,
           (unsigned long long)d->wrong_unit, (unsigned)ms.accepted, (unsigned)ms.repeats,
           (unsigned)ms.refused, (unsigned)ms.exceptions);
    if (tcp)
        printf("tcp: %llu connections (at most %u at once, %llu closed to make room), %llu "
               "closed for a bad MBAP length, %llu frames with another protocol id dropped, "
               "%llu closed for not reading their answers\n",
               (unsigned long long)d->tcp.connections, d->tcp.most,
               (unsigned long long)d->tcp.evicted, (unsigned long long)d->tcp.bad_length,
               (unsigned long long)d->tcp.bad_proto, (unsigned long long)d->tcp.slow);
    else
        printf("rtu: %u frames answered, %u CRC errors, %u overruns\n", (unsigned)rs->frames,
               (unsigned)rs->crc_errs, (unsigned)rs->overruns);
    printf("faults: %llu answers dropped, %llu delayed, %llu busy refusals, %llu failures\n",
           (unsigned long long)d->dropped, (unsigned long long)d->delayed,
           (unsigned long long)d->busy, (unsigned long long)d->failed);
}

/* Serves until a signal (or --idle-exit), then reports: the exit status. */
static int serve(const mb_args_t *a, mbdev_t *d, cs_sim_device_result_t *res, double start,
                 cs_modbus_rtu_stats_t *rs)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);
    int rc = a->tcp ? serve_tcp(d, a->tcp, &g_stop)
                    : serve_rtu(d, a->rtu, (uint32_t)a->o.baud, a->parity != 0 ? a->parity : 'E',
                                &g_stop, rs);
    res->wall_s = cs_serial_now_s() - start;
    cs_err_t e = cs_sim_motion_close(d->mo);
    if (e != CS_OK && rc == OK) {
        fprintf(stderr, "curvestep-sim: device failed: %s\n", cs_err_text(e));
        rc = INTERNAL;
    }
    return rc;
}

int cs_sim_modbus_main(int argc, char **argv)
{
    mb_args_t a;
    int rc = parse_args(argc, argv, &a);
    if (rc >= 0)
        return rc;
    if (check_args(&a) != OK)
        return USAGE;
    cs_machine_t m;
    cs_machine_pen_t pen;
    cs_sim_device_cfg_t cfg;
    cs_sim_device_out_t out;
    cs_sim_ref_t ref;
    cs_sim_ref_init(&ref);
    rc = prepare(&a, &m, &pen, &cfg, &ref, &out);
    double start = cs_serial_now_s();
    cs_sim_device_result_t res;
    mbdev_t *d = rc == OK ? open_device(&a, &m, &cfg, &res, start) : NULL;
    if (d == NULL) {
        cs_sim_ref_free(&ref);
        return rc != OK ? rc : INTERNAL;
    }
    cs_modbus_rtu_stats_t rs = {0};
    rc = serve(&a, d, &res, start, &rs);
    if (rc != USAGE) {
        report_modbus(d, &res, a.tcp != NULL, &rs);
        rc = cs_sim_device_report(&m, &cfg, &res, &out, true, rc);
    }
    cs_sim_exec_free(&res.ex);
    cs_sim_ref_free(&ref);
    free(d);
    return rc;
}
