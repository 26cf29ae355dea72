/* The GPIO link of `curvestep stream` (cs_stream_cmd.h): the job's step segments run here, on
 * the step thread (cs_gpio_run) driving a GPIO chip's lines through libgpiod, or a recorder
 * (`--gpio record:FILE`) that writes every edge with its time. The main thread shows progress,
 * turns Ctrl-C into a hold (a second one: stop at once), and prints the summary every link
 * prints (docs/gpio.md). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cs_cmd.h"
#include "cs_gpio_cfg.h"
#include "cs_gpio_io.h"
#include "cs_gpio_pwm.h"
#include "cs_gpio_run.h"
#include "cs_stream_cmd.h"
#include "cs_stream_report.h"

static const char *const axis_names[CS_AXES] = {"x", "y", "z", "a"};

typedef struct {
    FILE *f;
    bool tty;
    size_t n;    /* segments in the job */
    double last; /* last progress line (s) */
    double rate_t, rate_ex, rate;
    double t0;         /* start (s) */
    size_t first;      /* segments executed before the start (--resume-from) */
    size_t eta_k;      /* segments 0..eta_k-1 summed in eta_done */
    uint64_t eta_done; /* ticks */
} progress_t;

static double now_s(void)
{
    return (double)cs_gpio_io_now_ns() * 1e-9;
}

/* The progress display of cs_stream (docs/streaming.md "Progress"): a bar ten times a second
 * on a terminal, else one line a second. The ETA is exact here: the planned time left. */
static void progress(progress_t *pg, const cs_stream_plan_t *p, const cs_gpio_run_t *r, bool final)
{
    if (pg->f == NULL)
        return;
    double now = now_s();
    if (!final && now - pg->last < (pg->tty ? 0.1 : 1.0))
        return;
    pg->last = now;
    size_t ex = cs_gpio_run_executed(r);
    if (now - pg->rate_t >= 0.5) {
        if (pg->rate_t > 0)
            pg->rate = ((double)ex - pg->rate_ex) / (now - pg->rate_t);
        pg->rate_t = now;
        pg->rate_ex = (double)ex;
    }
    if (final && now > pg->t0) /* the summary: the average over the whole run */
        pg->rate = (double)(ex - pg->first) / (now - pg->t0);
    while (pg->eta_k < ex && pg->eta_k < p->nsegs)
        pg->eta_done += p->segs[pg->eta_k++].ticks;
    double eta = (double)(p->ticks - pg->eta_done) / p->m.tick_hz;
    double pct = pg->n ? 100.0 * (double)ex / (double)pg->n : 100.0;
    double late_us = (double)__atomic_load_n(&r->late_max_ns, __ATOMIC_RELAXED) / 1000.0;
    if (pg->tty) {
        char bar[31];
        int fill = (int)(pct * 30 / 100);
        for (int i = 0; i < 30; i++)
            bar[i] = i < fill ? '#' : '-';
        bar[30] = '\0';
        fprintf(pg->f,
                "\r[%s] %5.1f%% %zu/%zu segments  ETA %d:%02d  %.0f segments/s  late <= %.0f us ",
                bar, pct, ex, pg->n, (int)eta / 60, (int)eta % 60, pg->rate, late_us);
        if (final)
            fputc('\n', pg->f);
    } else {
        fprintf(pg->f,
                "stream: %zu/%zu segments executed (%.1f %%), %.0f/s, ETA %.0f s, STEP edges "
                "late by up to %.0f us\n",
                ex, pg->n, pct, pg->rate, eta, late_us);
    }
    fflush(pg->f);
}

/* Steps the job makes on each axis (from segment `first` on). */
static void job_steps(const cs_stream_plan_t *p, size_t first, uint64_t *steps)
{
    for (unsigned i = 0; i < CS_AXES; i++)
        steps[i] = 0;
    for (size_t k = first; k < p->nsegs; k++)
        for (unsigned i = 0; i < CS_AXES; i++)
            steps[i] += (uint64_t)(p->segs[k].steps[i] < 0 ? -(int64_t)p->segs[k].steps[i]
                                                           : p->segs[k].steps[i]);
}

static void add_line(cs_gpio_lines_t *l, unsigned offset, bool active_low, const char *name)
{
    unsigned i = l->n++;
    l->offset[i] = offset;
    l->active_low[i] = active_low;
    snprintf(l->name[i], sizeof l->name[i], "%s", name);
}

static void warn_rt(const cs_gpio_run_t *r, const cs_gpio_cfg_t *cfg)
{
    if (r->sched_err > 0)
        fprintf(stderr,
                "curvestep stream: warning: SCHED_FIFO priority %d not granted (%s): the step "
                "thread runs at normal priority and its edges may be late under load; grant it "
                "with CAP_SYS_NICE (sudo setcap cap_sys_nice+ep build/curvestep) or an rtprio "
                "limit (/etc/security/limits.d: @gpio - rtprio %d), README \"GPIO\"\n",
                cfg->rt_priority, strerror(r->sched_err), cfg->rt_priority);
    if (r->mlock_err > 0)
        fprintf(stderr,
                "curvestep stream: warning: memory not locked (mlockall: %s): a page fault can "
                "delay an edge; grant it with CAP_IPC_LOCK or a memlock limit "
                "(/etc/security/limits.d: @gpio - memlock unlimited), README \"GPIO\"\n",
                strerror(r->mlock_err));
    if (r->mlock_err == -2)
        fprintf(stderr, "curvestep stream: note: memory not locked (AddressSanitizer build)\n");
}

/* Opens the pen servo's line for a job with pen events: [gpio] pen on the chip, or a recorder
 * with room for the job. CS_EXIT_OK, or the exit status after the reason on stderr (no pen line
 * wired: 1; the chip refused it: 4). */
static int open_pen(cs_gpio_io_t *pio, const cs_stream_args_t *a, const cs_stream_plan_t *p,
                    const cs_gpio_cfg_t *cfg, const char *chip, bool record, const cs_machine_t *m)
{
    char err[512];
    if (cfg->pen < 0 && !record) {
        fprintf(stderr,
                "%s:0: [pen] mode = servo, but [gpio] wires no pen line (pen = OFFSET, "
                "docs/gpio.md)\n",
                a->machine_file ? a->machine_file : "the built-in machine");
        return CS_EXIT_INPUT;
    }
    if (cs_gpio_pwm_open(pio, chip, record, cfg->pen, (double)p->ticks / m->tick_hz + 2.0, err,
                         sizeof err) == 0)
        return CS_EXIT_OK;
    fprintf(stderr, "curvestep stream: %s\n", err);
    return record ? CS_EXIT_INTERNAL : CS_EXIT_NO_DEVICE;
}

int cs_stream_cmd_gpio(const cs_stream_args_t *a, const cs_stream_plan_t *p,
                       volatile sig_atomic_t *interrupted)
{
    const char *chip_arg = a->gpio_chip;
    const char *record = strncmp(chip_arg, "record:", 7) == 0 ? chip_arg + 7 : NULL;
    if (record && record[0] == '\0') {
        fprintf(stderr, "curvestep stream: --gpio record:FILE needs a file name\n");
        return CS_EXIT_USAGE;
    }
    if (a->curves) {
        fprintf(stderr, "curvestep stream: --gpio runs the step segments planned here: "
                        "--mode curves does not apply\n");
        return CS_EXIT_USAGE;
    }
    const cs_machine_t *m = &p->m;
    cs_gpio_cfg_t cfg;
    char err[640];
    if (a->machine_file) {
        if (cs_gpio_cfg_load(a->machine_file, m, &cfg, err, sizeof err) != 0) {
            fprintf(stderr, "%s\n", err);
            return CS_EXIT_INPUT;
        }
    } else {
        cs_gpio_cfg_default(&cfg, m);
    }
    char chip[64];
    cs_gpio_cfg_chip_name(chip_arg, chip, sizeof chip);
    if (!record && cfg.chip[0] && strcmp(cfg.chip, chip) != 0) {
        fprintf(stderr,
                "curvestep stream: --gpio %s, but %s says [gpio] chip = %s: its line offsets "
                "are for that chip (give --gpio %s, or change the file)\n",
                chip_arg, a->machine_file, cfg.chip, cfg.chip);
        return CS_EXIT_USAGE;
    }
    /* The lines: STEP and DIR of every wired axis, ENABLE. The recorder stands for a board
     * wired in full: an axis or ENABLE the file leaves unwired gets a line of its own there. */
    uint64_t steps[CS_AXES];
    job_steps(p, a->resume_from, steps);
    cs_gpio_lines_t l;
    memset(&l, 0, sizeof l);
    cs_gpio_run_opts_t ro;
    memset(&ro, 0, sizeof ro);
    bool any = false;
    int unwired = -1; /* an axis the job moves that has no lines */
    for (unsigned i = 0; i < CS_AXES; i++) {
        ro.step_line[i] = ro.dir_line[i] = -1;
        if (i >= m->n_axes)
            continue;
        bool wired = cs_gpio_cfg_wired(&cfg, i);
        if (!wired && !record) {
            if (steps[i] > 0 && unwired < 0)
                unwired = (int)i;
            continue;
        }
        char name[12];
        ro.step_line[i] = (int)l.n;
        snprintf(name, sizeof name, "%s_step", axis_names[i]);
        add_line(&l, wired ? (unsigned)cfg.step[i] : 0, cfg.step_active_low, name);
        ro.dir_line[i] = (int)l.n;
        snprintf(name, sizeof name, "%s_dir", axis_names[i]);
        add_line(&l, wired ? (unsigned)cfg.dir[i] : 0, false, name);
        any = any || wired;
    }
    ro.enable_line = -1;
    if (cfg.enable >= 0 || record) {
        ro.enable_line = (int)l.n;
        add_line(&l, cfg.enable >= 0 ? (unsigned)cfg.enable : 0, cfg.enable_active_low, "enable");
    }
    cs_gpio_io_t io;
    if (!record) { /* the chip first: a missing chip is exit 4 whatever the wiring */
        int orc = cs_gpio_io_open_chip(&io, chip_arg, &l, err, sizeof err);
        if (orc == -1) {
            fprintf(stderr, "curvestep stream: %s\n", err);
            return CS_EXIT_NO_DEVICE;
        }
        if (orc == 0 && (unwired >= 0 || !any))
            cs_gpio_io_close(&io);
        if (!any) {
            fprintf(stderr,
                    "curvestep stream: --gpio %s: %s wires no axis: give a machine file with a "
                    "[gpio] section (x_step, x_dir, ...; docs/gpio.md, contrib/gpio-rpi.ini)\n",
                    chip_arg, a->machine_file ? a->machine_file : "the built-in machine");
            return CS_EXIT_USAGE;
        }
        if (unwired >= 0) {
            fprintf(stderr,
                    "%s:0: [gpio] wires no %s_step / %s_dir, but the job moves %s (%llu steps)\n",
                    a->machine_file, axis_names[unwired], axis_names[unwired], axis_names[unwired],
                    (unsigned long long)steps[unwired]);
            return CS_EXIT_INPUT;
        }
    } else {
        if (cs_gpio_io_open_recorder(&io, &l,
                                     cs_gpio_run_record_capacity(p->segs + a->resume_from,
                                                                 p->nsegs - a->resume_from)) != 0) {
            fprintf(stderr, "curvestep stream: --gpio record: out of memory\n");
            cs_gpio_io_free(&io);
            return CS_EXIT_INTERNAL;
        }
    }
    /* the pen servo ([pen] mode = servo): its own line and thread (cs_gpio_pwm) */
    cs_gpio_io_t pio = {0};
    bool pen = p->npens > 0;
    int prc = pen ? open_pen(&pio, a, p, &cfg, chip_arg, record != NULL, m) : CS_EXIT_OK;
    if (prc != CS_EXIT_OK) {
        cs_gpio_io_close(&io);
        cs_gpio_io_free(&io);
        return prc;
    }
    const char *link = chip_arg; /* "stream: LINK: outcome" */
    fprintf(stderr, "stream: %s: %u lines (", link, l.n);
    for (unsigned i = 0; i < l.n; i++)
        if (record)
            fprintf(stderr, "%s%s", i ? ", " : "", l.name[i]);
        else
            fprintf(stderr, "%s%s %u%s", i ? ", " : "", l.name[i], l.offset[i],
                    l.active_low[i] ? " active-low" : "");
    fprintf(stderr, "); STEP pulse %.3f us, DIR set-up %.3f us\n", cfg.pulse_ns / 1000.0,
            cfg.dir_setup_ns / 1000.0);

    ro.m = m;
    ro.cfg = &cfg;
    ro.io = &io;
    ro.segs = p->segs;
    ro.nsegs = p->nsegs;
    ro.first = a->resume_from;
    ro.realtime = true;
    cs_gpio_run_t r;
    int rc = cs_gpio_run_start(&r, &ro);
    if (rc != 0) {
        fprintf(stderr, "curvestep stream: cannot start the step thread: %s\n", strerror(rc));
        cs_gpio_io_set(&io, (1u << l.n) - 1u, 0, 0, &(int64_t){0});
        cs_gpio_io_close(&io);
        cs_gpio_io_free(&io);
        cs_gpio_io_close(&pio);
        cs_gpio_io_free(&pio);
        return CS_EXIT_INTERNAL;
    }
    warn_rt(&r, &cfg);
    cs_gpio_pwm_t pw = {0};
    if (pen && (rc = cs_gpio_pwm_start(&pw, &pio, &r, p->pens, p->npens, cfg.spin_ns)) != 0)
        fprintf(stderr, "curvestep stream: cannot start the pen's thread: %s\n", strerror(rc));
    progress_t pg;
    memset(&pg, 0, sizeof pg);
    pg.f = a->quiet ? NULL : stderr;
    pg.tty = isatty(STDERR_FILENO) != 0;
    pg.n = p->nsegs;
    double t_start = now_s();
    pg.t0 = t_start;
    pg.first = a->resume_from;
    int held = 0;
    while (!cs_gpio_run_finished(&r)) {
        int want = *interrupted >= 2 ? 2 : *interrupted >= 1 ? 1 : 0;
        if (want > held) {
            cs_gpio_run_hold(&r, want);
            held = want;
            if (want == 1)
                fprintf(stderr, "\nstream: Ctrl-C: holding (slowing down, then stopping at the "
                                "end of a segment); Ctrl-C again stops at once\n");
        }
        progress(&pg, p, &r, false);
        struct timespec ts = {0, 20000000};
        nanosleep(&ts, NULL);
    }
    cs_gpio_run_join(&r);
    cs_gpio_pwm_stop(&pw);
    if (pen)
        cs_gpio_io_close(&pio);
    progress(&pg, p, &r, true);
    double wall = now_s() - t_start;
    cs_gpio_io_close(&io);

    int exit_rc = CS_EXIT_OK;
    const char *what = "job executed";
    char why[200] = "";
    switch (r.outcome) {
    case CS_GPIO_RUN_DONE:
        break;
    case CS_GPIO_RUN_HELD:
        exit_rc = CS_EXIT_INTERRUPTED;
        what = "interrupted: held, then stopped at the end of a segment (STEP low, ENABLE off)";
        break;
    case CS_GPIO_RUN_STOPPED:
        exit_rc = CS_EXIT_INTERRUPTED;
        what = "interrupted: stopped at once, mid-segment (STEP low, ENABLE off)";
        break;
    case CS_GPIO_RUN_BAD_SEGMENT:
        exit_rc = CS_EXIT_INTERNAL;
        what = "the executor refused a segment";
        snprintf(why, sizeof why, " (no. %zu: ticks 0 or over 2^24, or more steps than ticks)",
                 r.bad_segment);
        break;
    case CS_GPIO_RUN_IO_ERROR:
        exit_rc = CS_EXIT_CLOSED;
        what = "setting the lines failed";
        snprintf(why, sizeof why, " (%s)", strerror(r.io_errno));
        break;
    }
    size_t ex = cs_gpio_run_executed(&r);
    printf("stream: %s: %s%s\n", link, what, why);
    cs_stream_report_counts(stdout, ex, p->nsegs, ex, ex, "segments");
    printf("stream: %llu steps (",
           (unsigned long long)(r.steps[0] + r.steps[1] + r.steps[2] + r.steps[3]));
    for (unsigned i = 0; i < m->n_axes; i++)
        printf("%s%s %llu", i ? ", " : "", axis_names[i], (unsigned long long)r.steps[i]);
    printf(") in %.2f s (job time %.3f s); STEP edges late by: median <= %.0f us, 99 %% <= %.0f "
           "us, max %.1f us\n",
           wall, (double)r.ticks / m->tick_hz, (double)cs_gpio_run_late_quantile(&r, 0.5) / 1000.0,
           (double)cs_gpio_run_late_quantile(&r, 0.99) / 1000.0, (double)r.late_max_ns / 1000.0);
    if (pen && !cs_gpio_pwm_report(stdout, &pw) && exit_rc == CS_EXIT_OK)
        exit_rc = CS_EXIT_CLOSED;
    if (exit_rc != CS_EXIT_OK && ex < p->nsegs && r.outcome != CS_GPIO_RUN_STOPPED)
        cs_stream_report_resume(stdout, "segment", ex);
    if (r.outcome == CS_GPIO_RUN_STOPPED)
        printf("stream: (stopped mid-segment: the machine is past segment no. %zu, re-home it "
               "before resuming)\n",
               ex);
    fflush(stdout);
    if (record) {
        FILE *f = fopen(record, "w");
        char hdr[200];
        snprintf(hdr, sizeof hdr, "tick_hz=%u pulse_ns=%u dir_setup_ns=%u t0=tick0",
                 (unsigned)m->tick_hz, (unsigned)cfg.pulse_ns, (unsigned)cfg.dir_setup_ns);
        int wr = f ? cs_gpio_io_write_record(&io, f, r.t0_ns, hdr) : -1;
        if (wr == 0 && pen) /* the pen's line after the others, its own header line */
            wr = cs_gpio_io_write_record(&pio, f, r.t0_ns, "pen servo: software PWM, 50 Hz");
        if (f && fclose(f) != 0)
            wr = -1;
        if (wr != 0) {
            fprintf(stderr, "curvestep stream: %s: %s\n", record, strerror(errno));
            if (exit_rc == CS_EXIT_OK)
                exit_rc = CS_EXIT_INTERNAL;
        } else if (io.dropped) {
            fprintf(stderr, "curvestep stream: %s: %zu set calls did not fit the record\n", record,
                    io.dropped);
            if (exit_rc == CS_EXIT_OK)
                exit_rc = CS_EXIT_INTERNAL;
        }
    }
    cs_gpio_io_free(&io);
    cs_gpio_io_free(&pio);
    return exit_rc;
}
