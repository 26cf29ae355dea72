/* The machine-control commands over the serial link (docs/controller.md, docs/protocol.md
 * "Machine control"): `curvestep home` (a HOME per axis of the machine file's [homing] order),
 * `curvestep jog` (a JOG to a machine position; Ctrl-C holds the jog to rest and drops it),
 * `curvestep probe` (a PROBE, G38.2..G38.5, printing the contact position) and `curvestep
 * unlock` (UNLOCK, leaving an alarm). Each runs a short job through cs_stream_run and reports
 * the device's EVENTs (axis homed, probe contact, alarm). */
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cs_cmd.h"
#include "cs_conv.h"
#include "cs_ctlcfg.h"
#include "cs_err_text.h"
#include "cs_gpio_ctl.h"
#include "cs_machine_ini.h"
#include "cs_path.h"
#include "cs_serial.h"
#include "cs_stream.h"
#include "cs_stream_cmd.h"
#include "cs_stream_report.h"

static volatile sig_atomic_t interrupted;

static void on_sigint(int sig)
{
    (void)sig;
    if (interrupted < 2)
        interrupted++;
}

/* What the command line gave. */
typedef struct {
    const char *who; /* "home", "jog", ... */
    const char *port, *machine_file;
    const char *gpio; /* --gpio CHIP: the GPIO link instead (cs_gpio_ctl) */
    long baud;
    double feed; /* jog, probe: mm/s */
    double xyz[3];
    int nxyz;
    bool away, no_error; /* probe */
    int mode;            /* spindle: cs_proto_spindle_mode_t */
    bool laser;          /* spindle: --laser */
    cs_machine_t m;
} ctl_args_t;

/* What the device reported (cs_stream_opts_t.on_event). */
typedef struct {
    const ctl_args_t *a;
    bool alarm, probed, contact;
    uint8_t alarm_code;
    int32_t probe_pos[CS_PROTO_AXES_MAX];
    unsigned homed;
} ctl_seen_t;

static void print_pos(const cs_machine_t *m, const int32_t *steps)
{
    for (unsigned i = 0; i < m->n_axes; i++)
        printf("%s%.4f", i ? " " : "", steps[i] * (double)CS_MOTION_ONE / m->axis[i].steps_per_mm);
}

static void on_event(void *ctx, const cs_proto_event_t *ev)
{
    ctl_seen_t *s = ctx;
    const cs_machine_t *m = &s->a->m;
    static const char names[] = "xyza";
    if (ev->kind == CS_PROTO_EVENT_ALARM) {
        s->alarm = true;
        s->alarm_code = ev->code;
        printf("%s: ALARM:%u (%s), inputs 0x%03x, stopped at ", s->a->who, (unsigned)ev->code,
               cs_ctlcfg_alarm_text(ev->code), (unsigned)ev->inputs);
    } else if (ev->kind == CS_PROTO_EVENT_PROBE) {
        s->probed = true;
        s->contact = ev->code != 0;
        memcpy(s->probe_pos, ev->pos, sizeof s->probe_pos);
        printf("%s: %s at ", s->a->who, ev->code ? "contact" : "no contact; ended");
    } else if (ev->kind == CS_PROTO_EVENT_HOMED && ev->code < 4) {
        s->homed++;
        printf("%s: %c homed; machine position ", s->a->who, names[ev->code]);
    } else {
        return; /* INPUTS */
    }
    print_pos(m, ev->pos);
    printf(" mm\n");
    fflush(stdout);
}

/* Runs job on the device at a->port; prints the outcome; returns the exit status. */
static int run_job(const ctl_args_t *a, cs_stream_job_t *job, ctl_seen_t *seen)
{
    cs_serial_t ser;
    if (cs_serial_open(&ser, a->port, (uint32_t)a->baud) != 0) {
        fprintf(stderr, "curvestep %s: %s: %s\n", a->who, a->port, cs_serial_strerror(errno));
        return CS_EXIT_NO_DEVICE;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_sigint;
    sigaction(SIGINT, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);
    cs_stream_opts_t o;
    cs_stream_opts_default(&o, &ser, a->m.n_axes, a->m.tick_hz);
    cs_stream_link_timing(&o.link, strncmp(a->port, "/dev/pts/", 9) == 0 ? 0 : (uint32_t)a->baud);
    o.interrupt = &interrupted;
    o.on_event = on_event;
    o.event_ctx = seen;
    o.status_ms = 120000; /* a homing cycle reports nothing executed for a while */
    o.jog_cancel = job->n > 0 && job->v[0].type == CS_PROTO_JOG; /* Ctrl-C: Grbl's 0x85 */
    job->mode = CS_STREAM_CURVES; /* planned on the device: the tick rate need not match */
    cs_stream_result_t r;
    cs_err_t e = cs_stream_run(job, &o, &r);
    cs_serial_close(&ser);
    signal(SIGINT, SIG_DFL);
    if (e != CS_OK) {
        fprintf(stderr, "curvestep %s: %s\n", a->who, cs_err_text(e));
        return CS_EXIT_INTERNAL;
    }
    int rc = cs_stream_exit_code(r.outcome);
    if (r.outcome == CS_STREAM_DEVICE_ERROR && !seen->alarm)
        printf("%s: the device refused message %zu: %s\n", a->who, r.dev_error_msg,
               cs_err_text((cs_err_t)r.dev_error.code));
    else if (r.outcome != CS_STREAM_DONE && r.outcome != CS_STREAM_DEVICE_ERROR)
        printf("%s: %s%s%s\n", a->who, cs_stream_outcome_text(r.outcome), r.why[0] ? ": " : "",
               r.why);
    if (seen->alarm)
        printf("%s: the device is in alarm: `curvestep unlock` (or `curvestep home`) clears it\n",
               a->who);
    if (r.outcome == CS_STREAM_DONE || r.outcome == CS_STREAM_INTERRUPTED) {
        printf("%s: machine position ", a->who);
        print_pos(&a->m, r.dev_pos);
        printf(" mm\n");
    }
    return seen->alarm && rc == CS_EXIT_OK ? CS_EXIT_DEV_ERROR : rc;
}

static void usage(FILE *f, const char *who)
{
    static const struct {
        const char *who, *synopsis, *what;
    } u[] = {
        {"home", "home (--port DEV [--baud N] | --gpio CHIP) [--machine FILE.ini] [--axes ORDER]",
         "Homes the axes in the order of the machine file's [homing] (or --axes ORDER, e.g.\n"
         "zxy): the device seeks each switch, backs off, latches slowly and pulls off, then\n"
         "sets the axis's position to [homing] x_pos (default: the travel's end at the\n"
         "switch). Homing also clears an alarm.\n"},
        {"jog", "jog (--port DEV [--baud N] | --gpio CHIP) [--machine FILE.ini] --feed MM/S X Y Z",
         "Moves straight to the machine position X Y Z (mm) at --feed, planned and\n"
         "accelerated on the device; Ctrl-C decelerates it to rest and drops the rest.\n"},
        {"probe",
         "probe (--port DEV [--baud N] | --gpio CHIP) [--machine FILE.ini] --feed MM/S [--away]\n"
         "                       [--no-error] X Y Z",
         "Moves towards X Y Z at --feed until the probe touches (G38.2) and prints the\n"
         "contact position; --away: until it lets go (G38.4); --no-error: no alarm when the\n"
         "move ends without contact (G38.3, G38.5).\n"},
        {"unlock", "unlock (--port DEV [--baud N] | --gpio CHIP) [--machine FILE.ini]",
         "Leaves the device's alarm state (Grbl's $X); refused while the e-stop is pressed.\n"},
        {"spindle",
         "spindle --port DEV [--baud N] [--machine FILE.ini] [--ccw | --off]\n"
         "                       [--laser [--feed MM/S]] [S]",
         "Sets the spindle or laser output in queue order (M3 S, M4 with --ccw, M5 with --off):\n"
         "power S of the machine file's [spindle] s_max (default 1000). --laser: the power of\n"
         "the moves that follow scales with their speed, full at --feed (Grbl's $32).\n"},
    };
    size_t k = 0;
    while (k + 1 < sizeof u / sizeof u[0] && strcmp(u[k].who, who) != 0)
        k++;
    fprintf(f,
            "usage: curvestep %s\n%s"
            "Over the serial link to a device (a board or the simulator; docs/controller.md)%s.\n"
            "Options:\n"
            "  --port DEV         the device's serial line\n"
            "  --baud N           its rate (default 115200)\n"
            "%s"
            "  --machine FILE     the machine file (default: as `curvestep plan`)\n"
            "Exit status: 0 done, 1 bad input (machine file), 2 usage, 3 internal error, 4 no\n"
            "device, 5 device reset, 6 link closed, 7 the device refused a message or raised an\n"
            "alarm (ALARM:N printed), 8 interrupted (Ctrl-C).\n",
            u[k].synopsis, u[k].what, strcmp(who, "spindle") == 0 ? "" : ",\nor over GPIO lines",
            strcmp(who, "spindle") == 0
                ? ""
                : "  --gpio CHIP        drive the machine's [gpio] lines directly (or record:FILE:\n"
                  "                     no hardware, simulated switches; docs/gpio.md \"Inputs\")\n");
}

/* Parses the shared options and the command's own; returns -1 to go on, else an exit status. */
static int parse(int argc, char **argv, ctl_args_t *a, const char **axes)
{
    bool opts = true;
    for (int i = 1; i < argc; i++) {
        const char *s = argv[i];
        bool has = i + 1 < argc;
        if (opts && strcmp(s, "--") == 0) {
            opts = false;
        } else if (!opts || s[0] != '-' || (s[1] >= '0' && s[1] <= '9') || s[1] == '.') {
            if (axes != NULL || a->nxyz >= 3 || !cs_conv_number(s, &a->xyz[a->nxyz])) {
                fprintf(stderr, "curvestep %s: unexpected argument %s\n", a->who, s);
                return CS_EXIT_USAGE;
            }
            a->nxyz++;
        } else if (strcmp(s, "--help") == 0 || strcmp(s, "-h") == 0) {
            usage(stdout, a->who);
            return CS_EXIT_OK;
        } else if (strcmp(s, "--port") == 0 && has) {
            a->port = argv[++i];
        } else if (strcmp(s, "--gpio") == 0 && has && strcmp(a->who, "spindle") != 0) {
            a->gpio = argv[++i];
        } else if (strcmp(s, "--machine") == 0 && has) {
            a->machine_file = argv[++i];
        } else if (strcmp(s, "--baud") == 0 && has) {
            char *end;
            a->baud = strtol(argv[++i], &end, 10);
            if (*end != '\0' || !cs_serial_baud_ok((uint32_t)a->baud)) {
                fprintf(stderr, "curvestep %s: --baud %s is not a termios rate\n", a->who, argv[i]);
                return CS_EXIT_USAGE;
            }
        } else if (strcmp(s, "--axes") == 0 && has && axes != NULL) {
            *axes = argv[++i];
        } else if (strcmp(s, "--feed") == 0 && has && axes == NULL &&
                   strcmp(a->who, "unlock") != 0) {
            if (!cs_conv_number(argv[++i], &a->feed) || !(a->feed > 0 && a->feed <= 4096)) {
                fprintf(stderr, "curvestep %s: --feed wants mm/s in (0, 4096]\n", a->who);
                return CS_EXIT_USAGE;
            }
        } else if (strcmp(s, "--ccw") == 0 && strcmp(a->who, "spindle") == 0) {
            a->mode = CS_PROTO_SPINDLE_CCW;
        } else if (strcmp(s, "--off") == 0 && strcmp(a->who, "spindle") == 0) {
            a->mode = CS_PROTO_SPINDLE_OFF;
        } else if (strcmp(s, "--laser") == 0 && strcmp(a->who, "spindle") == 0) {
            a->laser = true;
        } else if (strcmp(s, "--away") == 0 && strcmp(a->who, "probe") == 0) {
            a->away = true;
        } else if (strcmp(s, "--no-error") == 0 && strcmp(a->who, "probe") == 0) {
            a->no_error = true;
        } else {
            fprintf(stderr, "curvestep %s: unknown or incomplete option %s\n", a->who, s);
            usage(stderr, a->who);
            return CS_EXIT_USAGE;
        }
    }
    if ((a->port == NULL) == (a->gpio == NULL)) {
        fprintf(stderr, "curvestep %s: %s\n", a->who,
                a->port ? "--port and --gpio exclude each other"
                : strcmp(a->who, "spindle") == 0 ? "--port DEV is required"
                                                 : "--port DEV or --gpio CHIP is required");
        return CS_EXIT_USAGE;
    }
    return -1;
}

/* The common start: arguments, then the machine file (and its control sections into *ctl when
 * not NULL). */
static int start(int argc, char **argv, ctl_args_t *a, const char *who, const char **axes,
                 cs_ctlcfg_t *ctl)
{
    memset(a, 0, sizeof *a);
    a->who = who;
    a->baud = 115200;
    a->mode = CS_PROTO_SPINDLE_CW;
    int rc = parse(argc, argv, a, axes);
    if (rc >= 0)
        return rc;
    char err[512];
    char name[32];
    snprintf(name, sizeof name, "curvestep %s", who);
    if (cs_machine_ini_open(name, a->machine_file, &a->m, NULL, err, sizeof err) != 0 ||
        (ctl != NULL && cs_ctlcfg_load(a->machine_file, &a->m, ctl, err, sizeof err) != 0)) {
        fprintf(stderr, "%s\n", err);
        return CS_EXIT_INPUT;
    }
    return -1;
}

/* The command over the GPIO link (cs_gpio_ctl). */
static int via_gpio(const ctl_args_t *a, const cs_ctlcfg_t *c,
                    int (*fn)(const cs_gpio_ctl_args_t *g))
{
    cs_gpio_ctl_args_t g = {.who = a->who,
                            .chip = a->gpio,
                            .machine_file = a->machine_file,
                            .m = &a->m,
                            .ctl = c,
                            .feed = a->feed,
                            .xyz = {a->xyz[0], a->xyz[1], a->xyz[2]},
                            .away = a->away,
                            .no_error = a->no_error};
    return fn(&g);
}

static int add_msg(cs_stream_job_t *j, const cs_proto_msg_t *m)
{
    void *b = j->v;
    if (!cs_path_grow(&b, &j->cap, j->n + 1, sizeof *j->v))
        return -1;
    j->v = b;
    j->v[j->n++] = *m;
    return 0;
}

int cs_cmd_home(int argc, char **argv)
{
    ctl_args_t a;
    const char *axes = NULL;
    cs_ctlcfg_t c;
    char err[512];
    int rc = start(argc, argv, &a, "home", &axes, &c);
    if (rc >= 0)
        return rc;
    if (axes != NULL) { /* --axes: the order, read by the machine file's own rule */
        char text[64];
        snprintf(text, sizeof text, "[homing]\norder = %s\n", axes);
        cs_ctlcfg_t o;
        if (cs_ctlcfg_parse(text, "--axes", &a.m, &o, err, sizeof err) != 0) {
            fprintf(stderr, "curvestep home: --axes %s: expected axis letters (e.g. zxy)\n", axes);
            return CS_EXIT_USAGE;
        }
        c.n_order = o.n_order;
        memcpy(c.order, o.order, sizeof c.order);
    }
    if (c.n_order == 0) {
        fprintf(stderr, "%s:0: [homing] order: not given (the axes to home, e.g. order = zxy)\n",
                a.machine_file ? a.machine_file : "the built-in machine");
        return CS_EXIT_INPUT;
    }
    if (a.gpio != NULL)
        return via_gpio(&a, &c, cs_gpio_ctl_home);
    cs_stream_job_t job;
    cs_stream_job_init(&job, CS_STREAM_CURVES);
    for (unsigned k = 0; k < c.n_order; k++) {
        cs_proto_msg_t m;
        if (cs_ctlcfg_home_msg(&c, &a.m, k, &m) != CS_OK || add_msg(&job, &m) != 0) {
            fprintf(stderr, "%s:0: [homing]: a value does not fit the HOME message\n",
                    a.machine_file ? a.machine_file : "the built-in machine");
            cs_stream_job_free(&job);
            return CS_EXIT_INPUT;
        }
    }
    ctl_seen_t seen = {&a, false, false, false, 0, {0}, 0};
    rc = run_job(&a, &job, &seen);
    cs_stream_job_free(&job);
    return rc;
}

/* jog and probe: the target, the feed. */
static int target_msg(const ctl_args_t *a, cs_proto_msg_t *m)
{
    if (a->nxyz != 3 || a->feed <= 0) {
        fprintf(stderr, "curvestep %s: wants --feed MM/S and the target X Y Z (mm)\n", a->who);
        return CS_EXIT_USAGE;
    }
    cs_vec3_t t;
    int32_t feed;
    if (cs_conv_mm_to_vec(a->xyz[0], a->xyz[1], a->xyz[2], &t) != CS_OK ||
        cs_conv_mm_to_pos(a->feed, &feed) != CS_OK) {
        fprintf(stderr, "curvestep %s: the target is outside +-4096 mm\n", a->who);
        return CS_EXIT_USAGE;
    }
    if (m->type == CS_PROTO_JOG) {
        m->u.jog.target = t;
        m->u.jog.feed = feed;
    } else {
        m->u.probe.target = t;
        m->u.probe.feed = feed;
        m->u.probe.flags = (uint8_t)((a->away ? CS_PROTO_PROBE_AWAY : 0) |
                                     (a->no_error ? CS_PROTO_PROBE_NO_ERROR : 0));
    }
    return -1;
}

static int one_msg(int argc, char **argv, const char *who, uint8_t type)
{
    ctl_args_t a;
    int rc = start(argc, argv, &a, who, NULL, NULL);
    if (rc >= 0)
        return rc;
    cs_stream_job_t job;
    cs_stream_job_init(&job, CS_STREAM_CURVES);
    cs_proto_msg_t m = {.type = type};
    if (type == CS_PROTO_JOG || type == CS_PROTO_PROBE) {
        rc = target_msg(&a, &m);
        if (rc >= 0)
            return rc;
    }
    if (a.gpio != NULL) {
        cs_stream_job_free(&job);
        return via_gpio(&a, NULL, type == CS_PROTO_JOG     ? cs_gpio_ctl_jog
                                  : type == CS_PROTO_PROBE ? cs_gpio_ctl_probe
                                                           : cs_gpio_ctl_unlock);
    }
    /* UNLOCK takes no slot, so nothing would report it executed: a SPINDLE off (what the
     * alarm left anyway) behind it does */
    cs_proto_msg_t off = {.type = CS_PROTO_SPINDLE};
    if (add_msg(&job, &m) != 0 || (type == CS_PROTO_UNLOCK && add_msg(&job, &off) != 0)) {
        cs_stream_job_free(&job);
        return CS_EXIT_INTERNAL;
    }
    ctl_seen_t seen = {&a, false, false, false, 0, {0}, 0};
    rc = run_job(&a, &job, &seen);
    cs_stream_job_free(&job);
    if (type == CS_PROTO_PROBE && rc == CS_EXIT_OK && !seen.probed)
        printf("probe: the device reported no probe cycle\n");
    return rc;
}

int cs_cmd_jog(int argc, char **argv)
{
    return one_msg(argc, argv, "jog", CS_PROTO_JOG);
}

int cs_cmd_probe(int argc, char **argv)
{
    return one_msg(argc, argv, "probe", CS_PROTO_PROBE);
}

int cs_cmd_unlock(int argc, char **argv)
{
    return one_msg(argc, argv, "unlock", CS_PROTO_UNLOCK);
}

/* S of [spindle] s_max -> duty in 1/1000, rounded; false outside 0..s_max. */
static bool spindle_duty(const ctl_args_t *a, double s_max, uint16_t *duty)
{
    double s = a->nxyz == 1 ? a->xyz[0] : 0;
    if (a->nxyz > 1 || !(s >= 0 && s <= s_max))
        return false;
    *duty = (uint16_t)(s / s_max * CS_PROTO_SPINDLE_FULL + 0.5);
    return true;
}

int cs_cmd_spindle(int argc, char **argv)
{
    ctl_args_t a;
    cs_ctlcfg_t c;
    int rc = start(argc, argv, &a, "spindle", NULL, &c);
    if (rc >= 0)
        return rc;
    cs_proto_msg_t m = {.type = CS_PROTO_SPINDLE};
    if (!spindle_duty(&a, c.s_max, &m.u.spindle.power)) {
        fprintf(stderr, "curvestep spindle: S wants one number in [0, %g] ([spindle] s_max)\n",
                c.s_max);
        return CS_EXIT_USAGE;
    }
    m.u.spindle.mode = (uint8_t)a.mode;
    m.u.spindle.flags = a.laser ? CS_PROTO_SPINDLE_LASER : 0;
    if (a.laser && a.feed > 0 && cs_conv_mm_to_pos(a.feed, &m.u.spindle.feed) != CS_OK)
        return CS_EXIT_USAGE;
    cs_stream_job_t job;
    cs_stream_job_init(&job, CS_STREAM_CURVES);
    if (add_msg(&job, &m) != 0)
        return CS_EXIT_INTERNAL;
    ctl_seen_t seen = {&a, false, false, false, 0, {0}, 0};
    rc = run_job(&a, &job, &seen);
    cs_stream_job_free(&job);
    return rc;
}
