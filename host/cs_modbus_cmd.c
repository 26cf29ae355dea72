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
    orc = cs_mb_open_link(&c, a->modbus_tcp, a->modbus_rtu, a->baud, a->parity, a->unit, why,
                          sizeof why);
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
