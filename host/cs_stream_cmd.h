/* cs_stream_cmd: what the `stream` command hands to each link. The command parses its options
 * and plans the job whole (cs_stream_cmd.c) before anything is sent; then one link runs it: the
 * serial protocol (cs_stream), Modbus RTU/TCP (cs_modbus_cmd.c) or GPIO pins (cs_gpio_cmd.c).
 * Every link prints the same summary lines and returns the same exit statuses. Host only. */
#ifndef CS_STREAM_CMD_H
#define CS_STREAM_CMD_H

#include <signal.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_machine.h"
#include "cs_machine_ini.h"
#include "cs_segment.h"
#include "cs_stream.h"

/* Exit statuses of `stream` beyond the shared ones (cs_cmd.h); every link uses them. */
enum {
    CS_EXIT_NO_DEVICE =
        4,              /* the port cannot be opened, no device answered, or it is incompatible */
    CS_EXIT_RESET = 5,  /* the device reset mid-job */
    CS_EXIT_CLOSED = 6, /* the link closed or the device stopped answering mid-job */
    CS_EXIT_DEV_ERROR = 7,  /* the device refused a message (ERROR) */
    CS_EXIT_INTERRUPTED = 8 /* Ctrl-C: held, then aborted */
};

/* The command line, parsed and checked. Exactly one of port, modbus_tcp, modbus_rtu, gpio_chip
 * is set. */
typedef struct {
    const char *job_file;
    const char *machine_file; /* NULL: the built-in machine */
    const char *port;         /* --port DEV: serial protocol */
    const char *modbus_tcp;   /* --modbus-tcp HOST:PORT */
    const char *modbus_rtu;   /* --modbus-rtu DEV */
    const char *gpio_chip;    /* --gpio CHIP */
    uint32_t baud;            /* --baud (serial and Modbus RTU), default 115200 */
    char parity;              /* --parity (Modbus RTU): 'E' (default, 8E1), 'O' (8O1), 'N' (8N2) */
    int unit;                 /* --unit ID (Modbus), default 1 */
    size_t resume_from;       /* --resume-from N: messages 1..N executed already */
    uint32_t line_rate;       /* --line-rate BPS (0: none) */
    bool curves;              /* --mode curves */
    bool quiet;               /* --quiet: no progress */
} cs_stream_args_t;

/* The planned job: the machine, the wire messages (segments or curves, per args.curves) and,
 * always, the step segments planned here (what the device must end up executing). */
typedef struct {
    cs_machine_t m;
    cs_machine_pen_t pen;
    cs_stream_job_t job;
    const cs_segment_t *segs; /* owned by the command; valid during the link call */
    size_t nsegs;
    uint64_t ticks; /* sum of the segments' durations (executor ticks) */
    const cs_motion_pen_t *pens; /* servo pen events of segs (GPIO: cs_gpio_pwm), npens of them */
    size_t npens;
} cs_stream_plan_t;

/* Links. Each runs the whole job (from args->resume_from + 1), shows progress on stderr unless
 * quiet, stops on *interrupted (> 0: hold then abort; >= 2: at once), prints the summary lines
 * "stream: LINK: outcome" / "stream: N of M ... executed ..." on stdout, and returns a
 * CS_EXIT_* status. */
int cs_stream_cmd_modbus(const cs_stream_args_t *a, const cs_stream_plan_t *p,
                         volatile sig_atomic_t *interrupted);
int cs_stream_cmd_gpio(const cs_stream_args_t *a, const cs_stream_plan_t *p,
                       volatile sig_atomic_t *interrupted);

#endif
