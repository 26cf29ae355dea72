/* cs_sim_modbus: the simulated device behind Modbus (docs/modbus.md). The register map and its
 * sequence rule are the core's (firmware/core/cs_modbus); the motion side is the serial
 * device's (cs_sim_motion_*). Modbus TCP: libmodbus listens, accepts and receives; each request
 * PDU goes to the core's handler, and libmodbus sends the answer it decided. Modbus RTU: the
 * core's own RTU server, fed byte by byte from a pty or a tty. */
#include "cs_sim_modbus.h"

#include <arpa/inet.h>
#include <errno.h>
#include <modbus/modbus.h>
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

#define DELAYED_MAX 8

typedef struct {
    double drop;      /* probability that an answer is not sent (the request was handled) */
    double delay;     /* probability that an answer is sent delay_ms late */
    double delay_ms;  /* default 300 */
    double busy;      /* probability that a mailbox write is refused with DEVICE_BUSY */
    uint64_t fail_at; /* the Nth mailbox write (counting every attempt) gets DEVICE_FAILURE */
    uint64_t seed;
} mb_faults_t;

typedef struct {
    double due;
    int fd; /* TCP client socket the answer belongs to (-1: RTU) */
    uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
    int qlen;
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

/* Runs the motion paced to the wall clock and latches its errors (cs_fw_modbus). */
static void step_motion(mbdev_t *d)
{
    cs_sim_motion_advance(d->mo, cs_serial_now_s());
    cs_fw_modbus_collect(&d->fm);
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

/* --- Modbus TCP (libmodbus) ----------------------------------------------------------------- */

/* Sends the answer the core decided, through libmodbus: an exception as such, a normal answer
 * by modbus_reply from a mapping that holds the values the core put in it. */
static void tcp_send(modbus_t *ctx, modbus_mapping_t *map, int fd, const uint8_t *query, int qlen,
                     const uint8_t *rsp, size_t rlen)
{
    modbus_set_socket(ctx, fd);
    int hl = modbus_get_header_length(ctx);
    if (rsp[0] & 0x80u) {
        modbus_reply_exception(ctx, query, rsp[1]);
        return;
    }
    uint8_t fc = rsp[0];
    if (fc == CS_MODBUS_FC_READ_HOLDING || fc == CS_MODBUS_FC_READ_INPUT) {
        unsigned addr = ((unsigned)query[hl + 1] << 8) | query[hl + 2];
        uint16_t *tab =
            fc == CS_MODBUS_FC_READ_INPUT ? map->tab_input_registers : map->tab_registers;
        for (size_t k = 0; 2 + 2 * k + 1 < rlen; k++)
            tab[addr + k] = (uint16_t)((rsp[2 + 2 * k] << 8) | rsp[3 + 2 * k]);
    }
    modbus_reply(ctx, query, qlen, map);
}

static int parse_hostport(const char *s, char *host, size_t cap, int *port)
{
    const char *colon = strrchr(s, ':');
    if (colon == NULL || (size_t)(colon - s) >= cap || colon == s)
        return -1;
    memcpy(host, s, (size_t)(colon - s));
    host[colon - s] = '\0';
    char *end;
    long p = strtol(colon + 1, &end, 10);
    if (*end != '\0' || p < 0 || p > 65535 || colon[1] == '\0')
        return -1;
    struct in_addr a;
    if (inet_pton(AF_INET, host, &a) != 1)
        return -1;
    *port = (int)p;
    return 0;
}

static int serve_tcp(mbdev_t *d, const char *addr, double idle_exit, volatile sig_atomic_t *stop)
{
    char host[64];
    int port;
    if (parse_hostport(addr, host, sizeof host, &port) != 0) {
        fprintf(stderr, "curvestep-sim: --modbus-tcp wants ADDR:PORT with an IPv4 address, "
                        "e.g. 127.0.0.1:1502 (port 0: any free port)\n");
        return 2;
    }
    modbus_t *ctx = modbus_new_tcp(host, port);
    if (ctx == NULL) {
        fprintf(stderr, "curvestep-sim: modbus_new_tcp: %s\n", modbus_strerror(errno));
        return 3;
    }
    int ls = modbus_tcp_listen(ctx, 4);
    if (ls < 0) {
        fprintf(stderr, "curvestep-sim: cannot listen on %s: %s\n", addr, modbus_strerror(errno));
        modbus_free(ctx);
        return 3;
    }
    struct sockaddr_in sa;
    socklen_t sl = sizeof sa;
    if (getsockname(ls, (struct sockaddr *)&sa, &sl) != 0) {
        perror("curvestep-sim: getsockname");
        close(ls);
        modbus_free(ctx);
        return 3;
    }
    printf("%s:%u\n", host, (unsigned)ntohs(sa.sin_port));
    fflush(stdout);
    modbus_mapping_t *map = modbus_mapping_new_start_address(
        0, 0, 0, 0, 0, CS_MODBUS_HR_MAILBOX + CS_MODBUS_MAILBOX_REGS, 0, CS_MODBUS_IR_COUNT);
    if (map == NULL) {
        close(ls);
        modbus_free(ctx);
        return 3;
    }
    /* a request's bytes arrive together on loopback; a peer that stalls mid-request is cut */
    modbus_set_byte_timeout(ctx, 0, 500000);
    int client = -1;
    uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
    while (!*stop) {
        double now = cs_serial_now_s();
        /* answers held back by the delay fault */
        for (unsigned k = 0; k < d->ndl;) {
            if (d->dl[k].due <= now) {
                if (d->dl[k].fd == client && client >= 0)
                    tcp_send(ctx, map, client, d->dl[k].query, d->dl[k].qlen, d->dl[k].rsp,
                             d->dl[k].rlen);
                d->dl[k] = d->dl[--d->ndl];
            } else {
                k++;
            }
        }
        struct pollfd pf[2] = {{ls, POLLIN, 0}, {client, POLLIN, 0}};
        int busy = cs_sim_motion_busy(d->mo);
        int pr = poll(pf, client >= 0 ? 2 : 1, busy || d->ndl ? 1 : 5);
        if (pr < 0 && errno != EINTR)
            break;
        if (pr > 0 && (pf[0].revents & POLLIN)) {
            int s = ls;
            int c = modbus_tcp_accept(ctx, &s); /* sets ctx's socket to the new client */
            if (c >= 0) {
                if (client >= 0) /* one host at a time: a new connection replaces the old */
                    close(client);
                client = c;
                /* answers go out at once: with Nagle's algorithm an answer written while the
                 * previous one waits for the host's delayed ACK is held up to 40 ms */
                int one = 1;
                setsockopt(c, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
            }
        }
        if (client >= 0 && pr > 0 && (pf[1].revents & (POLLIN | POLLHUP | POLLERR))) {
            modbus_set_socket(ctx, client);
            int rc = modbus_receive(ctx, query);
            if (rc < 0) { /* the host closed the connection (or sent garbage): drop it */
                close(client);
                client = -1;
            } else if (rc > 0) {
                d->last_rx_s = cs_serial_now_s();
                int hl = modbus_get_header_length(ctx);
                uint8_t unit = query[hl - 1];
                d->requests++;
                if (unit != d->unit) {
                    d->wrong_unit++; /* another unit's request: not ours to answer */
                } else {
                    uint8_t rsp[CS_MODBUS_PDU_MAX];
                    size_t rn;
                    step_motion(d); /* the status read sees the motion as of now */
                    cs_modbus_pdu(&d->map, query + hl, (size_t)(rc - hl), rsp, sizeof rsp, &rn);
                    int fate = answer_fate(d);
                    if (fate == 0) {
                        tcp_send(ctx, map, client, query, rc, rsp, rn);
                    } else if (fate == 2) {
                        delayed_t *q = &d->dl[d->ndl++];
                        q->due = cs_serial_now_s() + d->f.delay_ms / 1000.0;
                        q->fd = client;
                        memcpy(q->query, query, (size_t)rc);
                        q->qlen = rc;
                        memcpy(q->rsp, rsp, rn);
                        q->rlen = rn;
                    }
                }
            }
        }
        step_motion(d);
        if (idle_exit > 0 && cs_sim_motion_started(d->mo) && cs_sim_motion_done(d->mo) &&
            cs_serial_now_s() - d->last_rx_s > idle_exit)
            break;
    }
    if (client >= 0)
        close(client);
    close(ls);
    modbus_mapping_free(map);
    modbus_free(ctx);
    return 0;
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

static int serve_rtu(mbdev_t *d, const char *dev, uint32_t baud, char parity, double idle_exit,
                     volatile sig_atomic_t *stop, cs_modbus_rtu_stats_t *rs)
{
    int fd = -1, keep = -1;
    cs_serial_t ser;
    if (strcmp(dev, "pty") == 0) {
        char name[256];
        if (cs_serial_openpty(&fd, &keep, name, sizeof name) != 0) {
            perror("curvestep-sim: openpty");
            return 3;
        }
        printf("%s\n", name);
        fflush(stdout);
        cs_serial_attach(&ser, fd);
    } else {
        if (cs_serial_open(&ser, dev, baud) != 0) {
            fprintf(stderr, "curvestep-sim: %s: %s\n", dev, strerror(errno));
            return 1;
        }
        fd = ser.fd;
        if (set_parity(fd, parity) != 0) {
            fprintf(stderr, "curvestep-sim: %s: parity: %s\n", dev, strerror(errno));
            close(fd);
            return 1;
        }
    }
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
                q->fd = -1;
                memcpy(q->rsp, reply, len);
                q->rlen = len;
            }
        }
        step_motion(d);
        if (idle_exit > 0 && cs_sim_motion_started(d->mo) && cs_sim_motion_done(d->mo) &&
            cs_serial_now_s() - d->last_rx_s > idle_exit)
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
          "  --modbus-tcp A:P  serve Modbus TCP (libmodbus) on IPv4 address A, port P; use\n"
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

int cs_sim_modbus_main(int argc, char **argv)
{
    enum { OK = 0, INPUT = 1, USAGE = 2, INTERNAL = 3 };
    const char *tcp = NULL, *rtu = NULL;
    long unit = 1;
    char parity = 0;        /* 0: not given (even) */
    cs_sim_device_opts_t o; /* the options the serial device takes too */
    cs_sim_device_opts_default(&o);
    for (int i = 1; i < argc; i++) /* `--modbus-tcp --help` too */
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            usage(stdout);
            return OK;
        }
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        bool has = i + 1 < argc;
        char *end = NULL;
        int took = cs_sim_device_opt(argc, argv, &i, &o);
        if (took < 0)
            return USAGE;
        if (took > 0)
            continue;
        if (strcmp(a, "--modbus-tcp") == 0 && has) {
            tcp = argv[++i];
        } else if (strcmp(a, "--modbus-rtu") == 0 && has) {
            rtu = argv[++i];
        } else if (strcmp(a, "--parity") == 0 && has) {
            const char *v = argv[++i];
            parity = strcmp(v, "none") == 0   ? 'N'
                     : strcmp(v, "even") == 0 ? 'E'
                     : strcmp(v, "odd") == 0  ? 'O'
                                              : 0;
            if (parity == 0) {
                fprintf(stderr, "curvestep-sim: --parity wants none, even or odd\n");
                return USAGE;
            }
        } else if (strcmp(a, "--unit") == 0 && has) {
            unit = strtol(argv[++i], &end, 10);
            if (*end != '\0' || unit < 0) {
                fprintf(stderr, "curvestep-sim: %s wants a number\n", a);
                return USAGE;
            }
        } else {
            fprintf(stderr, "curvestep-sim: unknown or incomplete option %s\n", a);
            usage(stderr);
            return USAGE;
        }
    }
    const char *machine_file = o.machine_file, *faults = o.faults;
    cs_sim_device_out_t out = o.out;
    bool instant = o.instant;
    double speed = o.speed, idle_exit = o.idle_exit, tol_mm = o.tol_mm;
    long queue = o.queue, baud = o.baud;
    if ((tcp != NULL) == (rtu != NULL)) {
        fprintf(stderr, "curvestep-sim: give exactly one of --modbus-tcp and --modbus-rtu\n");
        return USAGE;
    }
    if (parity != 0 && rtu == NULL) {
        fprintf(stderr, "curvestep-sim: --parity applies to --modbus-rtu only\n");
        return USAGE;
    }
    if (queue < 1 || queue > CS_SIM_DEVICE_QUEUE_MAX) {
        fprintf(stderr, "curvestep-sim: --queue wants 1..%d\n", CS_SIM_DEVICE_QUEUE_MAX);
        return USAGE;
    }
    if (unit < 1 || unit > 247) {
        fprintf(stderr, "curvestep-sim: --unit wants a Modbus unit id, 1..247\n");
        return USAGE;
    }
    if (!cs_serial_baud_ok((uint32_t)baud) || baud == 0) {
        fprintf(stderr, "curvestep-sim: --baud %ld is not a termios rate\n", baud);
        return USAGE;
    }
    mb_faults_t f = {.delay_ms = 300};
    if (faults != NULL && parse_faults(faults, &f) != 0) {
        fprintf(stderr, "curvestep-sim: --faults: bad list '%s' (see --modbus-tcp --help)\n",
                faults);
        return USAGE;
    }
    cs_machine_t m;
    cs_machine_pen_t pen; /* mode servo: the check follows the device's pen settings */
    cs_machine_ini_pen_default(&pen);
    char err[512];
    if (machine_file) {
        if (cs_machine_ini_load_pen(machine_file, &m, &pen, err, sizeof err) != 0) {
            fprintf(stderr, "%s\n", err);
            return INPUT;
        }
    } else {
        cs_machine_ini_default(&m);
    }
    cs_sim_device_cfg_t cfg;
    cs_sim_device_cfg_default(&cfg, &m);
    cfg.queue_size = (uint16_t)queue;
    cfg.speed = instant ? 0 : speed;
    cfg.keep_edges = true;
    if (tol_mm > 0 && cs_conv_tol_to_pos(tol_mm, &cfg.tol) != CS_OK) {
        fprintf(stderr, "curvestep-sim: --tol %g mm is outside the accepted range\n", tol_mm);
        return USAGE;
    }
    cs_sim_ref_t ref;
    cs_sim_ref_init(&ref);
    out.ref = &ref;
    if (pen.mode == CS_MACHINE_PEN_SERVO)
        out.pen = &pen;
    if (out.reference) { /* a bad job is reported before anything is served */
        cs_jobplan_t jp; /* read and laid out as plan / stream do (cs_jobopts) */
        cs_jobplan_init(&jp);
        cs_err_t e = cs_jobplan_reference(&jp, out.reference, &o.in, machine_file, &m);
        if (e == CS_OK)
            e = cs_sim_ref_from_path(&ref, &jp.path, out.end_mm);
        else
            cs_path_diag_print(stderr, &jp.diag);
        cs_jobplan_free(&jp);
        if (e != CS_OK) {
            cs_sim_ref_free(&ref);
            return INPUT;
        }
    }
    mbdev_t *d = calloc(1, sizeof *d);
    if (d == NULL) {
        cs_sim_ref_free(&ref);
        return INTERNAL;
    }
    d->m = &m;
    d->unit = (uint8_t)unit;
    d->f = f;
    d->rng = f.seed ? f.seed : 0x9E3779B97F4A7C15ull;
    double start = cs_serial_now_s();
    d->last_rx_s = start;
    cs_sim_device_result_t res;
    cs_err_t e = cs_sim_motion_open(&d->mo, &cfg, &res);
    if (e == CS_OK) {
        cs_modbus_app_t app;
        cs_fw_modbus_init(&d->fm, cs_sim_motion_fw(d->mo),
                          (uint32_t)getpid() * 2654435761u ^ (uint32_t)(start * 1e6), &app);
        /* the injected refusals in front of the device's; one ctx for the three hooks */
        app = (cs_modbus_app_t){app_submit, app_command, app_status, d};
        e = cs_modbus_map_init(&d->map, &app, 0);
    }
    if (e != CS_OK) {
        fprintf(stderr, "curvestep-sim: device failed: %s\n", cs_err_text(e));
        if (d->mo)
            cs_sim_motion_close(d->mo);
        free(d);
        cs_sim_ref_free(&ref);
        return INTERNAL;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);
    cs_modbus_rtu_stats_t rs = {0};
    int rc = tcp ? serve_tcp(d, tcp, idle_exit, &g_stop)
                 : serve_rtu(d, rtu, (uint32_t)baud, parity != 0 ? parity : 'E', idle_exit, &g_stop,
                             &rs);
    res.wall_s = cs_serial_now_s() - start;
    cs_modbus_stats_t ms = d->map.stats;
    e = cs_sim_motion_close(d->mo);
    if (e != CS_OK && rc == OK) {
        fprintf(stderr, "curvestep-sim: device failed: %s\n", cs_err_text(e));
        rc = INTERNAL;
    }
    if (rc == USAGE) {
        cs_sim_exec_free(&res.ex);
        cs_sim_ref_free(&ref);
        free(d);
        return rc;
    }
    printf("device: served %.2f s; %llu messages executed (%llu step segments, %llu curves); "
           "%u holds, %u aborts, error %u (%s)\n",
           res.wall_s, (unsigned long long)res.executed, (unsigned long long)res.segments,
           (unsigned long long)res.curves, (unsigned)res.holds, (unsigned)res.aborts,
           (unsigned)d->fm.error, d->fm.error ? cs_err_text((cs_err_t)d->fm.error) : "none");
    printf("modbus %s unit %u: %llu requests (%llu for other units, not answered); %u mailbox "
           "writes accepted, %u repeats answered without executing, %u refused; %u exceptions\n",
           tcp ? "tcp" : "rtu", (unsigned)d->unit, (unsigned long long)d->requests,
           (unsigned long long)d->wrong_unit, (unsigned)ms.accepted, (unsigned)ms.repeats,
           (unsigned)ms.refused, (unsigned)ms.exceptions);
    if (rtu)
        printf("rtu: %u frames answered, %u CRC errors, %u overruns\n", (unsigned)rs.frames,
               (unsigned)rs.crc_errs, (unsigned)rs.overruns);
    printf("faults: %llu answers dropped, %llu delayed, %llu busy refusals, %llu failures\n",
           (unsigned long long)d->dropped, (unsigned long long)d->delayed,
           (unsigned long long)d->busy, (unsigned long long)d->failed);
    rc = cs_sim_device_report(&m, &cfg, &res, &out, true, rc);
    cs_sim_exec_free(&res.ex);
    cs_sim_ref_free(&ref);
    free(d);
    return rc;
}
