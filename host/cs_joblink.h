/* cs_joblink: the host's links behind one interface. A job planned whole on the host runs over
 * one link, picked by option: the framed serial protocol (--port: cs_stream), Modbus TCP or RTU
 * (--modbus-tcp, --modbus-rtu: cs_modbus_stream) or the GPIO step thread here (--gpio:
 * cs_gpio_run). Each link implements the same calls (cs_joblink_ops_t): open, run the job with
 * progress, report its own counters, close (and an optional check of its configuration before
 * any job); `curvestep stream` and the daemon (`serve`) call only these. Owns: the link's open
 * state (port, Modbus client, GPIO lines), the choice of the link from the options (one parser
 * for both commands), the one report of an outcome (cs_joblink_report: exit status and summary
 * lines, cs_stream_report), and the rate a serial line really moves (its timing: cs_linktime).
 *
 * Hold, resume and cancel are not calls but the two flags of cs_joblink_ctl_t, polled by run:
 * they are set from signal handlers (Ctrl-C; the daemon's SIGUSR1/SIGUSR2/SIGTERM to the job's
 * process), where only a sig_atomic_t store is safe. Host only. */
#ifndef CS_JOBLINK_H
#define CS_JOBLINK_H

#include <signal.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "cs_machine.h"
#include "cs_modbus_stream.h"
#include "cs_motion.h"
#include "cs_segment.h"
#include "cs_serial.h"
#include "cs_stream.h"

/* The link as the options name it: exactly one of port, modbus_tcp, modbus_rtu, gpio. */
typedef struct {
    const char *port;         /* --port DEV: the framed serial protocol */
    const char *modbus_tcp;   /* --modbus-tcp HOST:PORT */
    const char *modbus_rtu;   /* --modbus-rtu DEV */
    const char *gpio;         /* --gpio CHIP, or record:FILE */
    uint32_t baud;            /* serial and Modbus RTU line speed (termios rate) */
    char parity;              /* Modbus RTU: 'E', 'O' or 'N' (0: 'E') */
    int unit;                 /* Modbus unit id */
    uint32_t mb_timeout_ms;   /* Modbus: one try's wait for its answer, ms (0: CS_MB_TIMEOUT_MS) */
    uint32_t line_rate;       /* serial: pace writes to this many bits/s (0: none) */
    const char *machine_file; /* GPIO: its [gpio] section (NULL: the built-in machine) */
} cs_joblink_cfg_t;

/* The job, planned whole, in the forms the links take. */
typedef struct {
    const cs_machine_t *m;
    const cs_stream_job_t *job; /* wire messages (serial, Modbus) */
    const cs_segment_t *segs;   /* the step segments (GPIO; NULL: taken from job's SEGMENTs) */
    size_t nsegs;
    const cs_motion_pen_t *pens; /* their servo pen events (GPIO: cs_gpio_pwm; with segs) */
    size_t npens;
    size_t resume_from;       /* in the link's numbering: messages (GPIO: segments) done */
    const int32_t *start_pos; /* steps where the machine stands (GPIO reports its end
                               * position from it); NULL: the origin */
    /* serial: --resume (ask the device where the job stands; resume_from is then ignored) and
     * --position (steps the user stated, sent before any motion: SETPOS), docs/streaming.md
     * "Resume"; false / NULL elsewhere */
    bool resume_ask;
    const int32_t *stated_pos;
} cs_joblink_job_t;

/* How the caller steers a run (all polled by run; any may be NULL / false). */
typedef struct {
    volatile sig_atomic_t *interrupt; /* > 0: hold, then end the job (cancel); >= 2: at once */
    volatile sig_atomic_t *pause;     /* != 0: hold, the job kept; back to 0: resume */
    FILE *progress;                   /* progress lines (docs/streaming.md "Progress") */
    bool progress_tty;                /* a redrawn bar instead of lines */
} cs_joblink_ctl_t;

typedef struct cs_joblink cs_joblink_t;

typedef struct {
    const char *kind; /* "serial", "Modbus", "GPIO" (messages) */
    bool keep_open;   /* the daemon opens it once and keeps it (serial); else once per job */
    bool curves;      /* carries CURVE messages (--mode curves) */
    bool pens;        /* carries servo pen events (PEN messages) */
    /* Checks the link's configuration for machine m before any job (NULL: nothing to check):
     * the daemon refuses to start on a bad one. CS_EXIT_OK, or an exit status with l->why. */
    int (*check)(cs_joblink_t *l, const cs_machine_t *m);
    /* Opens the link for job j (j may be NULL for a keep_open link). CS_EXIT_OK, or an exit
     * status (CS_EXIT_NO_DEVICE, _USAGE, _INPUT, _INTERNAL) with one sentence in l->why. */
    int (*open)(cs_joblink_t *l, const cs_joblink_job_t *j);
    /* Runs j (from j->resume_from + 1) to an outcome; always fills *r (r->executed in the
     * link's numbering). CS_OK, or an error of the run itself (CS_ERR_ARG, CS_ERR_IO). */
    cs_err_t (*run)(cs_joblink_t *l, const cs_joblink_job_t *j, const cs_joblink_ctl_t *c,
                    cs_stream_result_t *r);
    /* The link's own counters line(s) of the summary (NULL: bytes and retransmissions). */
    void (*counters)(cs_joblink_t *l, FILE *out, const cs_stream_result_t *r);
    /* Releases the link; rc is the run's exit status, returned or made worse (GPIO: the record
     * file could not be written). */
    int (*close)(cs_joblink_t *l, int rc);
} cs_joblink_ops_t;

struct cs_joblink {
    const cs_joblink_ops_t *ops;
    cs_joblink_cfg_t cfg;
    const char *name; /* "stream: NAME: outcome": the port, HOST:PORT, the chip */
    char why[640];    /* open's reason when it fails */
    size_t resume_from;
    bool curves;
    cs_serial_t ser; /* serial */
    bool ser_open;
    cs_mb_client_t mb; /* Modbus */
    bool mb_open;
    void *gpio; /* the GPIO link's state (cs_gpio_cmd.c) */
};

/* The links' operations (cs_joblink.c: serial; cs_modbus_cmd.c; cs_gpio_cmd.c). */
extern const cs_joblink_ops_t cs_joblink_serial_ops;
extern const cs_joblink_ops_t cs_joblink_modbus_ops;
extern const cs_joblink_ops_t cs_joblink_gpio_ops;

/* Picks the link cfg names (copied; its strings must outlive l): CS_EXIT_OK, or CS_EXIT_USAGE
 * with the reason in l->why when none or more than one is named. */
int cs_joblink_select(cs_joblink_t *l, const cs_joblink_cfg_t *cfg);
/* argv[*i] is one of the link options (--port, --modbus-tcp, --modbus-rtu, --gpio, --unit,
 * --baud, --parity, --modbus-timeout, --line-rate) with its value: stores it in *l, moves *i onto
 * the value and returns 1; any other word: 0; a bad value: -1 after "curvestep CMD: --baud wants
 * ..." on stderr (a usage error). */
int cs_joblink_option(const char *cmd, int argc, char **argv, int *i, cs_joblink_cfg_t *l);
/* s is a whole decimal number 0..max and nothing else: 0 with *out set, else -1. */
int cs_joblink_parse_count(const char *s, unsigned long long max, unsigned long long *out);
/* The link's calls (see cs_joblink_ops_t). Call close after every open, even a failed one (it
 * frees what open allocated); the daemon keeps a keep_open link open across jobs. */
int cs_joblink_open(cs_joblink_t *l, const cs_joblink_job_t *j);
cs_err_t cs_joblink_run(cs_joblink_t *l, const cs_joblink_job_t *j, const cs_joblink_ctl_t *c,
                        cs_stream_result_t *r);
int cs_joblink_close(cs_joblink_t *l, int rc);
/* The one report of a run: the summary lines of r on out (cs_stream_report, with the link's
 * counters) and the exit status of its outcome. n: messages in the job (GPIO: segments). */
int cs_joblink_report(cs_joblink_t *l, FILE *out, size_t n, const cs_stream_result_t *r);
/* Bits/s a serial device really moves (timing of the link, cs_linktime): line_rate when set,
 * 0 (memory speed) for a pseudo-terminal (/dev/pts/N: bytes move at memory speed whatever its
 * baud), else baud. */
uint32_t cs_joblink_line_bps(const char *dev, uint32_t baud, uint32_t line_rate);
/* The step segments of a segments-mode job (its SEGMENT messages, in order) and its servo pen
 * events (a PEN message before segment k: {k, pulse_us}, as cs_stream_job_add_motion laid them
 * out): new arrays in *segs and *pens (free both), their lengths in *n and *npens. CS_ERR_FULL
 * out of memory. */
cs_err_t cs_joblink_segments(const cs_stream_job_t *job, cs_segment_t **segs, size_t *n,
                             cs_motion_pen_t **pens, size_t *npens);

#endif
