/* The Modbus link of `curvestep stream` (--modbus-tcp HOST:PORT, --modbus-rtu DEV): opens the
 * libmodbus client, streams the planned job with cs_mb_stream_run and prints the summary lines
 * and exit status every link prints (cs_stream_report). See docs/modbus.md. */
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "cs_cmd.h"
#include "cs_err_text.h"
#include "cs_modbus_stream.h"
#include "cs_stream_cmd.h"
#include "cs_stream_report.h"

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
    return cs_stream_report(stdout, where, &p->job, &r, o.resume_from, a->curves);
}
