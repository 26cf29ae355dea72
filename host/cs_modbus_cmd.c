/* The Modbus link's operations (cs_joblink.h: --modbus-tcp HOST:PORT, --modbus-rtu DEV): opens
 * the libmodbus client, streams the planned job with cs_mb_stream_run, closes. Its summary lines
 * and exit status are every link's (cs_joblink_report). See docs/modbus.md. */
#include <stdio.h>
#include <string.h>

#include "cs_cmd.h"
#include "cs_joblink.h"
#include "cs_modbus_stream.h"
#include "cs_stream_cmd.h"

static int modbus_open(cs_joblink_t *l, const cs_joblink_job_t *j)
{
    (void)j;
    if (l->cfg.line_rate != 0) {
        snprintf(l->why, sizeof l->why, "--line-rate applies to --port only");
        return CS_EXIT_USAGE;
    }
    int orc =
        cs_mb_open_link(&l->mb, l->cfg.modbus_tcp, l->cfg.modbus_rtu, l->cfg.baud, l->cfg.parity,
                        l->cfg.unit, l->cfg.mb_timeout_ms, l->why, sizeof l->why);
    if (orc != 0)
        return orc == -2 ? CS_EXIT_USAGE : CS_EXIT_NO_DEVICE;
    l->mb_open = true;
    return CS_EXIT_OK;
}

static cs_err_t modbus_run(cs_joblink_t *l, const cs_joblink_job_t *j, const cs_joblink_ctl_t *c,
                           cs_stream_result_t *r)
{
    cs_mb_stream_opts_t o;
    cs_mb_stream_opts_default(&o, &l->mb, j->m->n_axes, j->m->tick_hz);
    o.resume_from = j->resume_from;
    o.interrupt = c->interrupt;
    o.pause = c->pause;
    o.progress = c->progress;
    o.progress_tty = c->progress_tty;
    return cs_mb_stream_run(j->job, &o, r);
}

static int modbus_close(cs_joblink_t *l, int rc)
{
    if (l->mb_open)
        cs_mb_close(&l->mb);
    l->mb_open = false;
    return rc;
}

const cs_joblink_ops_t cs_joblink_modbus_ops = {
    .kind = "Modbus",
    .keep_open = false,
    .curves = true,
    .pens = true,
    .open = modbus_open,
    .run = modbus_run,
    .counters = NULL,
    .close = modbus_close,
};
