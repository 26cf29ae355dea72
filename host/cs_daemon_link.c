/* cs_daemon_link: the daemon's links (see cs_daemon_link.h, docs/streaming.md "The daemon"). */
#include "cs_daemon_link.h"

#include <string.h>
#include <termios.h>

#include "cs_modbus_stream.h"

const char *cs_daemon_link_name(const cs_daemon_cfg_t *cfg)
{
    return cfg->modbus_tcp ? cfg->modbus_tcp : cfg->modbus_rtu ? cfg->modbus_rtu : cfg->port;
}

int cs_daemon_link_open(const cs_daemon_cfg_t *cfg, cs_serial_t *ser)
{
    ser->fd = -1;
    if (cfg->port == NULL)
        return 0;
    return cs_serial_open(ser, cfg->port, cfg->baud);
}

static cs_err_t run_modbus(const cs_daemon_cfg_t *cfg, const cs_machine_t *m,
                           const cs_stream_job_t *job, volatile sig_atomic_t *interrupt,
                           volatile sig_atomic_t *pause, FILE *progress, cs_stream_result_t *r)
{
    cs_mb_client_t c;
    char why[sizeof r->why];
    if (cs_mb_open_link(&c, cfg->modbus_tcp, cfg->modbus_rtu, cfg->baud, cfg->parity, cfg->unit,
                        why, sizeof why) != 0) {
        memset(r, 0, sizeof *r);
        r->outcome = CS_STREAM_NO_DEVICE;
        snprintf(r->why, sizeof r->why, "%s", why);
        return CS_OK;
    }
    cs_mb_stream_opts_t o;
    cs_mb_stream_opts_default(&o, &c, m->n_axes, m->tick_hz);
    o.interrupt = interrupt;
    o.pause = pause;
    o.progress = progress;
    o.progress_tty = false;
    cs_err_t e = cs_mb_stream_run(job, &o, r);
    cs_mb_close(&c);
    return e;
}

cs_err_t cs_daemon_link_run(const cs_daemon_cfg_t *cfg, cs_serial_t *ser, const cs_machine_t *m,
                            const cs_stream_job_t *job, volatile sig_atomic_t *interrupt,
                            volatile sig_atomic_t *pause, FILE *progress, cs_stream_result_t *r)
{
    if (cfg->port == NULL)
        return run_modbus(cfg, m, job, interrupt, pause, progress, r);
    tcflush(ser->fd, TCIFLUSH); /* what the device said between jobs */
    cs_stream_opts_t o;
    cs_stream_opts_default(&o, ser, m->n_axes, m->tick_hz);
    cs_stream_link_timing(&o.link, strncmp(cfg->port, "/dev/pts/", 9) == 0 ? 0 : cfg->baud);
    o.interrupt = interrupt;
    o.pause = pause;
    o.progress = progress;
    o.progress_tty = false;
    return cs_stream_run(job, &o, r);
}
