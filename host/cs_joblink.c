/* cs_joblink: the choice of a link, the calls through its operations, the one report, and the
 * serial link's operations (see cs_joblink.h; docs/architecture.md "Links"). */
#include "cs_joblink.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>

#include "cs_cmd.h"
#include "cs_stream_cmd.h"
#include "cs_stream_report.h"

int cs_joblink_select(cs_joblink_t *l, const cs_joblink_cfg_t *cfg)
{
    memset(l, 0, sizeof *l);
    l->cfg = *cfg;
    int links = (cfg->port != NULL) + (cfg->modbus_tcp != NULL) + (cfg->modbus_rtu != NULL) +
                (cfg->gpio != NULL);
    if (links != 1) {
        snprintf(l->why, sizeof l->why, "%s",
                 links == 0 ? "one of --port, --modbus-tcp, --modbus-rtu or --gpio is required"
                            : "--port, --modbus-tcp, --modbus-rtu and --gpio exclude each other");
        return CS_EXIT_USAGE;
    }
    l->ops = cfg->port   ? &cs_joblink_serial_ops
             : cfg->gpio ? &cs_joblink_gpio_ops
                         : &cs_joblink_modbus_ops;
    l->name = cfg->port         ? cfg->port
              : cfg->gpio       ? cfg->gpio
              : cfg->modbus_tcp ? cfg->modbus_tcp
                                : cfg->modbus_rtu;
    return CS_EXIT_OK;
}

int cs_joblink_parse_count(const char *s, unsigned long long max, unsigned long long *out)
{
    char *end;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (*s == '\0' || *s == '-' || *end != '\0' || errno != 0 || v > max)
        return -1;
    *out = v;
    return 0;
}

int cs_joblink_option(const char *cmd, int argc, char **argv, int *i, cs_joblink_cfg_t *l)
{
    const char *a = argv[*i];
    if (*i + 1 >= argc)
        return 0;
    const char *v = argv[*i + 1];
    unsigned long long n;
    if (strcmp(a, "--port") == 0) {
        l->port = v;
    } else if (strcmp(a, "--modbus-tcp") == 0) {
        l->modbus_tcp = v;
    } else if (strcmp(a, "--modbus-rtu") == 0) {
        l->modbus_rtu = v;
    } else if (strcmp(a, "--gpio") == 0) {
        l->gpio = v;
    } else if (strcmp(a, "--unit") == 0) {
        if (cs_joblink_parse_count(v, 247, &n) != 0 || n < 1) {
            fprintf(stderr, "curvestep %s: --unit wants a Modbus unit id, 1..247\n", cmd);
            return -1;
        }
        l->unit = (int)n;
    } else if (strcmp(a, "--baud") == 0) {
        if (cs_joblink_parse_count(v, 4000000, &n) != 0 || !cs_serial_baud_ok((uint32_t)n)) {
            fprintf(stderr, "curvestep %s: --baud wants a termios rate (e.g. 115200)\n", cmd);
            return -1;
        }
        l->baud = (uint32_t)n;
    } else if (strcmp(a, "--parity") == 0) {
        l->parity = strcmp(v, "none") == 0   ? 'N'
                    : strcmp(v, "even") == 0 ? 'E'
                    : strcmp(v, "odd") == 0  ? 'O'
                                             : 0;
        if (l->parity == 0) {
            fprintf(stderr, "curvestep %s: --parity wants none, even or odd\n", cmd);
            return -1;
        }
    } else if (strcmp(a, "--modbus-timeout") == 0) {
        if (cs_joblink_parse_count(v, 60000, &n) != 0 || n < 10) {
            fprintf(stderr, "curvestep %s: --modbus-timeout wants milliseconds, 10..60000\n", cmd);
            return -1;
        }
        l->mb_timeout_ms = (uint32_t)n;
    } else if (strcmp(a, "--line-rate") == 0) {
        if (cs_joblink_parse_count(v, 100000000, &n) != 0 || n < 10) {
            fprintf(stderr, "curvestep %s: --line-rate wants bits/s (>= 10)\n", cmd);
            return -1;
        }
        l->line_rate = (uint32_t)n;
    } else {
        return 0;
    }
    (*i)++;
    return 1;
}

int cs_joblink_open(cs_joblink_t *l, const cs_joblink_job_t *j)
{
    l->why[0] = '\0';
    if (j != NULL) {
        l->resume_from = j->resume_from;
        l->curves = j->job != NULL && j->job->mode == CS_STREAM_CURVES;
    }
    return l->ops->open(l, j);
}

cs_err_t cs_joblink_run(cs_joblink_t *l, const cs_joblink_job_t *j, const cs_joblink_ctl_t *c,
                        cs_stream_result_t *r)
{
    l->resume_from = j->resume_from;
    l->curves = j->job != NULL && j->job->mode == CS_STREAM_CURVES;
    return l->ops->run(l, j, c, r);
}

int cs_joblink_close(cs_joblink_t *l, int rc)
{
    return l->ops->close(l, rc);
}

static void report_counters(void *ctx, FILE *out, const cs_stream_result_t *r)
{
    cs_joblink_t *l = ctx;
    l->ops->counters(l, out, r);
}

int cs_joblink_report(cs_joblink_t *l, FILE *out, size_t n, const cs_stream_result_t *r)
{
    return cs_stream_report(out, l->name, n, r, l->resume_from, l->curves,
                            l->ops->counters != NULL ? report_counters : NULL, l);
}

uint32_t cs_joblink_line_bps(const char *dev, uint32_t baud, uint32_t line_rate)
{
    if (line_rate != 0)
        return line_rate;
    return strncmp(dev, "/dev/pts/", 9) == 0 ? 0 : baud;
}

cs_err_t cs_joblink_segments(const cs_stream_job_t *job, cs_segment_t **segs, size_t *n,
                             cs_motion_pen_t **pens, size_t *npens)
{
    size_t k = 0, p = 0, cap = job->n ? job->n : 1;
    cs_segment_t *v = malloc(cap * sizeof *v);
    cs_motion_pen_t *pv = malloc(cap * sizeof *pv);
    if (v == NULL || pv == NULL) {
        free(v);
        free(pv);
        return CS_ERR_FULL;
    }
    for (size_t i = 0; i < job->n; i++)
        if (job->v[i].type == CS_PROTO_SEGMENT)
            v[k++] = job->v[i].u.segment;
        else if (job->v[i].type == CS_PROTO_PEN)
            pv[p++] = (cs_motion_pen_t){k, job->v[i].u.pen.pulse_us};
    *segs = v;
    *n = k;
    *pens = pv;
    *npens = p;
    return CS_OK;
}

/* --- the serial link: cs_stream over a cs_serial port ------------------------------------- */

static int serial_open(cs_joblink_t *l, const cs_joblink_job_t *j)
{
    (void)j;
    if (l->ser_open)
        return CS_EXIT_OK;
    if (cs_serial_open(&l->ser, l->cfg.port, l->cfg.baud) != 0) {
        snprintf(l->why, sizeof l->why, "%s: %s", l->cfg.port, cs_serial_strerror(errno));
        return CS_EXIT_NO_DEVICE;
    }
    cs_serial_set_line_rate(&l->ser, l->cfg.line_rate);
    l->ser_open = true;
    return CS_EXIT_OK;
}

static cs_err_t serial_run(cs_joblink_t *l, const cs_joblink_job_t *j, const cs_joblink_ctl_t *c,
                           cs_stream_result_t *r)
{
    tcflush(l->ser.fd, TCIFLUSH); /* what the device said before this job (between jobs) */
    cs_stream_opts_t o;
    cs_stream_opts_default(&o, &l->ser, j->m->n_axes, j->m->tick_hz);
    /* the link's timing for the rate the line really moves, in cs_serial_now_us microseconds */
    cs_stream_link_timing(&o.link, cs_joblink_line_bps(l->cfg.port, l->cfg.baud, l->cfg.line_rate));
    o.resume_from = j->resume_from;
    o.resume_ask = j->resume_ask;
    o.set_pos = j->stated_pos != NULL;
    for (unsigned i = 0; o.set_pos && i < CS_PROTO_AXES_MAX; i++)
        o.pos[i] = j->stated_pos[i];
    o.interrupt = c->interrupt;
    o.pause = c->pause;
    o.progress = c->progress;
    o.progress_tty = c->progress_tty;
    cs_err_t e = cs_stream_run(j->job, &o, r);
    l->resume_from = r->resume_from; /* --resume: where the device's word put the start */
    return e;
}

static int serial_close(cs_joblink_t *l, int rc)
{
    if (l->ser_open)
        cs_serial_close(&l->ser);
    l->ser_open = false;
    return rc;
}

const cs_joblink_ops_t cs_joblink_serial_ops = {
    .kind = "serial",
    .keep_open = true,
    .curves = true,
    .pens = true,
    .open = serial_open,
    .run = serial_run,
    .counters = NULL,
    .close = serial_close,
};
