/* The Modbus link of `curvestep stream` (--modbus-tcp HOST:PORT, --modbus-rtu DEV): opens the
 * libmodbus client, streams the planned job with cs_mb_stream_run and prints the summary lines
 * and exit status of the serial link (cs_stream_cmd.c). See docs/modbus.md. */
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "cs_cmd.h"
#include "cs_err_text.h"
#include "cs_modbus_stream.h"
#include "cs_stream_cmd.h"

/* One try's answer timeout: 200 ms on TCP and on a pty (a loaded CI machine under ASan answers
 * well within it; the device answers within a few ms), plus on a real RTU line the time the
 * longest request and its answer take on the wire (11 bits a character). Six tries: a device
 * silent for about 1.2 s is declared gone. */
#define MB_TIMEOUT_MS 200u
#define MB_TRIES      6u

int cs_stream_cmd_modbus(const cs_stream_args_t *a, const cs_stream_plan_t *p,
                         volatile sig_atomic_t *interrupted)
{
    if (a->line_rate != 0) {
        fprintf(stderr, "curvestep stream: --line-rate applies to --port only\n");
        return CS_EXIT_USAGE;
    }
    cs_mb_client_t c;
    char why[256];
    int orc;
    const char *where = a->modbus_tcp ? a->modbus_tcp : a->modbus_rtu;
    if (a->modbus_tcp) {
        orc = cs_mb_open_tcp(&c, a->modbus_tcp, a->unit, MB_TIMEOUT_MS, MB_TRIES, why, sizeof why);
    } else {
        uint32_t timeout = MB_TIMEOUT_MS;
        if (strncmp(a->modbus_rtu, "/dev/pts/", 9) != 0 && a->baud > 0) {
            /* request of CS_MODBUS_MAILBOX_REGS registers + its answer, 11 bits a byte */
            uint32_t bytes = 9u + 2u * CS_MODBUS_MAILBOX_REGS + 8u;
            timeout += (uint32_t)((uint64_t)bytes * 11u * 1000u / a->baud) + 1u;
        }
        orc = cs_mb_open_rtu(&c, a->modbus_rtu, a->baud, a->parity != 0 ? a->parity : 'E', a->unit,
                             timeout, MB_TRIES, why, sizeof why);
    }
    if (orc != 0) {
        fprintf(stderr, "curvestep stream: %s\n", why);
        return orc == -2 ? CS_EXIT_USAGE : CS_EXIT_NO_DEVICE;
    }
    cs_mb_stream_opts_t o;
    cs_mb_stream_opts_default(&o, &c, p->m.n_axes, p->m.tick_hz);
    o.resume_from = a->resume_from;
    o.interrupt = interrupted;
    o.progress = a->quiet ? NULL : stderr;
    o.progress_tty = isatty(STDERR_FILENO) != 0;
    cs_stream_result_t r;
    cs_err_t e = cs_mb_stream_run(&p->job, &o, &r);
    cs_mb_close(&c);
    if (e != CS_OK) {
        fprintf(stderr, "curvestep stream: %s\n", cs_err_text(e));
        return CS_EXIT_INTERNAL;
    }
    int rc = CS_EXIT_OK;
    switch (r.outcome) {
    case CS_STREAM_DONE:
        rc = CS_EXIT_OK;
        break;
    case CS_STREAM_NO_DEVICE:
    case CS_STREAM_INCOMPATIBLE:
        rc = CS_EXIT_NO_DEVICE;
        break;
    case CS_STREAM_RESET:
        rc = CS_EXIT_RESET;
        break;
    case CS_STREAM_CLOSED:
        rc = CS_EXIT_CLOSED;
        break;
    case CS_STREAM_DEVICE_ERROR:
        rc = CS_EXIT_DEV_ERROR;
        break;
    case CS_STREAM_INTERRUPTED:
        rc = CS_EXIT_INTERRUPTED;
        break;
    }
    /* the serial link's summary lines, word for word (cs_stream_cmd.c) */
    const char *what = a->curves ? "curves" : "segments";
    const cs_stream_job_t *job = &p->job;
    printf("stream: %s: %s", where, cs_stream_outcome_text(r.outcome));
    if (r.why[0] && r.outcome != CS_STREAM_DEVICE_ERROR)
        printf(" (%s)", r.why);
    if (r.outcome == CS_STREAM_RESET)
        printf(" (boot id %08x -> %08x; %u messages were in flight)", (unsigned)r.old_boot,
               (unsigned)r.new_boot, (unsigned)r.unacked);
    if (r.outcome == CS_STREAM_DEVICE_ERROR) {
        if (r.why[0])
            printf(" (%s: %s, about %s no. %zu)", r.why, cs_err_text((cs_err_t)r.dev_error.code),
                   a->curves ? "curve" : "segment", r.dev_error_msg);
        else
            printf(" (%s, about %s no. %zu)", cs_err_text((cs_err_t)r.dev_error.code),
                   a->curves ? "curve" : "segment", r.dev_error_msg);
    }
    printf("\n");
    printf("stream: %zu of %zu %s executed, %zu delivered, %zu sent; last executed: %zu\n",
           r.executed, job->n, what, r.delivered, r.sent, r.executed);
    printf("stream: %llu bytes sent, %llu received in %.2f s; %u retransmissions (%u timeouts, "
           "%u NAKs); %.0f %s/s\n",
           (unsigned long long)r.bytes_out, (unsigned long long)r.bytes_in, r.wall_s,
           (unsigned)r.link.retransmits, (unsigned)r.link.timeouts, (unsigned)r.link.naks,
           r.stream_s > 0 ? (double)(r.executed - o.resume_from) / r.stream_s : 0.0, what);
    if (rc != CS_EXIT_OK && r.executed < job->n && r.outcome != CS_STREAM_NO_DEVICE &&
        r.outcome != CS_STREAM_INCOMPATIBLE)
        printf("stream: to continue once the machine is where %s no. %zu left it: "
               "curvestep stream --resume-from %zu ...\n",
               a->curves ? "curve" : "segment", r.executed, r.executed);
    fflush(stdout);
    return rc;
}
