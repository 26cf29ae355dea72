/* The GPIO link's operations (cs_joblink.h: --gpio CHIP): the job's step segments run here, on
 * the step thread (cs_gpio_run) driving a GPIO chip's lines through libgpiod, or a recorder
 * (`--gpio record:FILE`) that writes every edge with its time. The calling thread shows
 * progress and passes on the hold, pause and stop requests; the summary is every link's
 * (cs_joblink_report) with this link's counters (steps, lateness of the STEP edges). Used by
 * `curvestep stream --gpio` and `curvestep serve --gpio` (docs/gpio.md). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cs_cmd.h"
#include "cs_gpio_link.h"
#include "cs_proto.h"
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
static void progress(progress_t *pg, const cs_segment_t *segs, size_t nsegs, uint64_t ticks,
                     uint32_t tick_hz, const cs_gpio_run_t *r, bool final)
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
    while (pg->eta_k < ex && pg->eta_k < nsegs)
        pg->eta_done += segs[pg->eta_k++].ticks;
    double eta = (double)(ticks - pg->eta_done) / tick_hz;
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

static void add_line(cs_gpio_lines_t *l, unsigned offset, bool active_low, const char *name)
{
    unsigned i = l->n++;
    l->offset[i] = offset;
    l->active_low[i] = active_low;
    snprintf(l->name[i], sizeof l->name[i], "%s", name);
}

/* Said once per process: the daemon and `curvestep grbl` start the step thread for every job
 * or chunk, and what the system grants does not change between them. */
static void warn_rt(const cs_gpio_run_t *r, const cs_gpio_cfg_t *cfg)
{
    static bool warned;
    if (warned)
        return;
    warned = true;
    if (r->sched_err > 0)
        fprintf(stderr,
                "curvestep: warning: SCHED_FIFO priority %d not granted (%s): the step "
                "thread runs at normal priority and its edges may be late under load; grant it "
                "with CAP_SYS_NICE (sudo setcap cap_sys_nice+ep build/curvestep) or an rtprio "
                "limit (/etc/security/limits.d: @gpio - rtprio %d), README \"GPIO\"\n",
                cfg->rt_priority, strerror(r->sched_err), cfg->rt_priority);
    if (r->mlock_err > 0)
        fprintf(stderr,
                "curvestep: warning: memory not locked (mlockall: %s): a page fault can "
                "delay an edge; grant it with CAP_IPC_LOCK or a memlock limit "
                "(/etc/security/limits.d: @gpio - memlock unlimited), README \"GPIO\"\n",
                strerror(r->mlock_err));
    if (r->mlock_err == -2)
        fprintf(stderr, "curvestep: note: memory not locked (AddressSanitizer build)\n");
}

typedef cs_gpio_link_t gpio_link_t;

/* Steps the job makes on each axis (from segment `first` on). */
static void job_steps(const gpio_link_t *g, uint64_t *steps)
{
    for (unsigned i = 0; i < CS_AXES; i++)
        steps[i] = 0;
    for (size_t k = g->first; k < g->nsegs; k++)
        for (unsigned i = 0; i < CS_AXES; i++)
            steps[i] += (uint64_t)(g->segs[k].steps[i] < 0 ? -(int64_t)g->segs[k].steps[i]
                                                           : g->segs[k].steps[i]);
}

/* The lines: STEP and DIR of every wired axis, ENABLE. The recorder stands for a board wired in
 * full: an axis or ENABLE the file leaves unwired gets a line of its own there. Returns the
 * first axis the job moves that has no lines (-1: none); *any: an axis is wired. */
static int wire_lines(gpio_link_t *g, const uint64_t *steps, bool *any)
{
    cs_gpio_lines_t *l = &g->lines;
    cs_gpio_run_opts_t *ro = &g->ro;
    int unwired = -1;
    *any = false;
    for (unsigned i = 0; i < CS_AXES; i++) {
        ro->step_line[i] = ro->dir_line[i] = -1;
        if (i >= g->m->n_axes)
            continue;
        bool wired = cs_gpio_cfg_wired(&g->cfg, i);
        if (!wired && !g->record) {
            if (steps[i] > 0 && unwired < 0)
                unwired = (int)i;
            continue;
        }
        char name[12];
        ro->step_line[i] = (int)l->n;
        snprintf(name, sizeof name, "%s_step", axis_names[i]);
        add_line(l, wired ? (unsigned)g->cfg.step[i] : 0, g->cfg.step_active_low, name);
        ro->dir_line[i] = (int)l->n;
        snprintf(name, sizeof name, "%s_dir", axis_names[i]);
        add_line(l, wired ? (unsigned)g->cfg.dir[i] : 0, false, name);
        *any = *any || wired;
    }
    ro->enable_line = -1;
    if (g->cfg.enable >= 0 || g->record) {
        ro->enable_line = (int)l->n;
        add_line(l, g->cfg.enable >= 0 ? (unsigned)g->cfg.enable : 0, g->cfg.enable_active_low,
                 "enable");
    }
    return unwired;
}

/* The chip (a missing chip is exit 4 whatever the wiring), then the wiring's own errors. */
static int open_chip(cs_joblink_t *l, gpio_link_t *g, const uint64_t *steps, int unwired, bool any)
{
    const char *chip_arg = l->cfg.gpio;
    int orc = cs_gpio_io_open_chip(&g->io, chip_arg, &g->lines, l->why, sizeof l->why);
    if (orc == -1)
        return CS_EXIT_NO_DEVICE;
    if (orc == 0 && (unwired >= 0 || !any))
        cs_gpio_io_close(&g->io);
    if (!any) {
        snprintf(l->why, sizeof l->why,
                 "--gpio %s: %s wires no axis: give a machine file with a [gpio] section "
                 "(x_step, x_dir, ...; docs/gpio.md, contrib/gpio-rpi.ini)",
                 chip_arg, l->cfg.machine_file ? l->cfg.machine_file : "the built-in machine");
        return CS_EXIT_USAGE;
    }
    if (unwired >= 0) {
        snprintf(l->why, sizeof l->why,
                 "%s:0: [gpio] wires no %s_step / %s_dir, but the job moves %s (%llu steps)",
                 l->cfg.machine_file, axis_names[unwired], axis_names[unwired], axis_names[unwired],
                 (unsigned long long)steps[unwired]);
        return CS_EXIT_INPUT;
    }
    g->io_open = true;
    return CS_EXIT_OK;
}

/* The [gpio] section and the checks of the option against it. */
static int gpio_config(cs_joblink_t *l, gpio_link_t *g, const cs_joblink_job_t *j)
{
    const char *chip_arg = l->cfg.gpio;
    g->record = strncmp(chip_arg, "record:", 7) == 0 ? chip_arg + 7 : NULL;
    if (g->record && g->record[0] == '\0') {
        snprintf(l->why, sizeof l->why, "--gpio record:FILE needs a file name");
        return CS_EXIT_USAGE;
    }
    if (j != NULL && j->job != NULL && j->job->mode == CS_STREAM_CURVES) {
        snprintf(l->why, sizeof l->why,
                 "--gpio runs the step segments planned here: "
                 "--mode curves does not apply");
        return CS_EXIT_USAGE;
    }
    if (l->cfg.machine_file) {
        if (cs_gpio_cfg_load(l->cfg.machine_file, g->m, &g->cfg, l->why, sizeof l->why) != 0)
            return CS_EXIT_INPUT;
    } else {
        cs_gpio_cfg_default(&g->cfg, g->m);
    }
    char chip[64];
    cs_gpio_cfg_chip_name(chip_arg, chip, sizeof chip);
    if (!g->record && g->cfg.chip[0] && strcmp(g->cfg.chip, chip) != 0) {
        snprintf(l->why, sizeof l->why,
                 "--gpio %s, but %s says [gpio] chip = %s: its line offsets are for that chip "
                 "(give --gpio %s, or change the file)",
                 chip_arg, l->cfg.machine_file, g->cfg.chip, g->cfg.chip);
        return CS_EXIT_USAGE;
    }
    return CS_EXIT_OK;
}

/* The job's segments: the plan's, or the SEGMENT messages of the job. */
static int gpio_segments(cs_joblink_t *l, gpio_link_t *g, const cs_joblink_job_t *j)
{
    g->segs = j->segs;
    g->nsegs = j->nsegs;
    if (g->segs == NULL) {
        if (cs_joblink_segments(j->job, &g->own, &g->nsegs, &g->own_pens, &g->npens) != CS_OK) {
            snprintf(l->why, sizeof l->why, "out of memory");
            return CS_EXIT_INTERNAL;
        }
        g->segs = g->own;
        g->pens = g->own_pens;
    } else {
        g->pens = j->pens;
        g->npens = j->npens;
    }
    g->first = j->resume_from < g->nsegs ? j->resume_from : g->nsegs;
    g->ticks = 0;
    for (size_t k = 0; k < g->nsegs; k++)
        g->ticks += g->segs[k].ticks;
    return CS_EXIT_OK;
}

/* "stream: LINK: 7 lines (x_step 17, ...); STEP pulse 4.000 us, DIR set-up 20.000 us" */
static void say_lines(const cs_joblink_t *l, const gpio_link_t *g)
{
    const cs_gpio_lines_t *ln = &g->lines;
    fprintf(stderr, "stream: %s: %u lines (", l->name, ln->n);
    for (unsigned i = 0; i < ln->n; i++)
        if (g->record)
            fprintf(stderr, "%s%s", i ? ", " : "", ln->name[i]);
        else
            fprintf(stderr, "%s%s %u%s", i ? ", " : "", ln->name[i], ln->offset[i],
                    ln->active_low[i] ? " active-low" : "");
    fprintf(stderr, "); STEP pulse %.3f us, DIR set-up %.3f us\n", g->cfg.pulse_ns / 1000.0,
            g->cfg.dir_setup_ns / 1000.0);
}

/* A new link state for machine m, or NULL with the reason in l->why. */
static gpio_link_t *gpio_new(cs_joblink_t *l, const cs_machine_t *m)
{
    gpio_link_t *g = calloc(1, sizeof *g);
    if (g == NULL)
        snprintf(l->why, sizeof l->why, "out of memory");
    else
        g->m = m;
    return g;
}

/* The [gpio] section against the option and machine m, before any job (the daemon's start). */
static int gpio_check(cs_joblink_t *l, const cs_machine_t *m)
{
    gpio_link_t *g = gpio_new(l, m);
    int rc = g != NULL ? gpio_config(l, g, NULL) : CS_EXIT_INTERNAL;
    free(g);
    return rc;
}

/* The pen servo's line for a job with pen events: [gpio] pen on the chip, or a recorder with
 * room for the job (no pen line wired: exit 1; the chip refused it: 4). */
static int open_pen(cs_joblink_t *l, gpio_link_t *g)
{
    if (g->cfg.pen < 0 && !g->record) {
        snprintf(l->why, sizeof l->why,
                 "%s:0: [pen] mode = servo, but [gpio] wires no pen line (pen = OFFSET, "
                 "docs/gpio.md)",
                 l->cfg.machine_file ? l->cfg.machine_file : "the built-in machine");
        return CS_EXIT_INPUT;
    }
    if (cs_gpio_pwm_open(&g->pio, l->cfg.gpio, g->record != NULL, g->cfg.pen,
                         (double)g->ticks / g->m->tick_hz + 2.0, l->why, sizeof l->why) != 0)
        return g->record ? CS_EXIT_INTERNAL : CS_EXIT_NO_DEVICE;
    g->pio_open = true;
    return CS_EXIT_OK;
}

/* The inputs (a chip's lines, or the recorder's simulated switches, probe and e-stop file) and
 * the state kept between commands; an alarm refuses a job unless `ctl` (the control commands
 * decide themselves). */
static int open_inputs(cs_joblink_t *l, gpio_link_t *g, bool ctl)
{
    cs_ctlcfg_default(&g->ctl);
    if (l->cfg.machine_file &&
        cs_ctlcfg_load(l->cfg.machine_file, g->m, &g->ctl, l->why, sizeof l->why) != 0)
        return CS_EXIT_INPUT;
    if (g->record) {
        char estop[400];
        snprintf(estop, sizeof estop, "%s.estop", g->record);
        cs_gpio_in_open_sim(&g->in, g->m, &g->ctl, NULL, estop);
    } else if (cs_gpio_in_open_chip(&g->in, g->io.chip, l->cfg.gpio, &g->cfg, l->why,
                                    sizeof l->why) != 0) {
        return CS_EXIT_NO_DEVICE;
    }
    g->in_open = true;
    g->has_in = cs_gpio_in_any(&g->in);
    if (!g->has_in)
        return CS_EXIT_OK; /* nothing can trip: no state to keep */
    if (cs_gpio_state_path(g->cfg.state, g->record, l->cfg.gpio, g->state_path,
                           sizeof g->state_path) != 0) {
        snprintf(l->why, sizeof l->why,
                 "%s:0: [gpio] state: no XDG_RUNTIME_DIR or HOME for the GPIO state file: give "
                 "state = PATH (docs/gpio.md, \"Inputs\")",
                 l->cfg.machine_file ? l->cfg.machine_file : "the built-in machine");
        return CS_EXIT_INPUT;
    }
    if (cs_gpio_state_load(g->state_path, &g->st, l->why, sizeof l->why) != 0)
        return CS_EXIT_INPUT;
    g->st_loaded = true;
    for (unsigned i = 0; i < CS_AXES; i++)
        g->in.off[i] = g->st.off[i];
    if (g->st.alarm && !ctl) {
        snprintf(l->why, sizeof l->why,
                 "the machine is in alarm (ALARM:%u, %s; %s): motion is refused until `curvestep "
                 "unlock --gpio %s` (or `curvestep home --gpio %s`) clears it",
                 (unsigned)g->st.alarm, cs_ctlcfg_alarm_text(g->st.alarm), g->state_path,
                 l->cfg.gpio, l->cfg.gpio);
        return CS_EXIT_DEV_ERROR;
    }
    return CS_EXIT_OK;
}

/* The output lines for a job moving steps[] (a chip, or a recorder with room for cap set calls),
 * then the inputs. */
static int open_lines(cs_joblink_t *l, gpio_link_t *g, const uint64_t *steps, size_t cap, bool ctl)
{
    bool any;
    int rc = CS_EXIT_OK;
    int unwired = wire_lines(g, steps, &any);
    if (!g->record) {
        rc = open_chip(l, g, steps, unwired, any);
    } else if (cs_gpio_io_open_recorder(&g->io, &g->lines, cap) != 0) {
        snprintf(l->why, sizeof l->why, "--gpio record: out of memory");
        rc = CS_EXIT_INTERNAL;
    } else {
        g->io_open = true;
    }
    if (rc == CS_EXIT_OK)
        rc = open_inputs(l, g, ctl);
    return rc;
}

static int gpio_open(cs_joblink_t *l, const cs_joblink_job_t *j)
{
    gpio_link_t *g = gpio_new(l, j->m);
    if (g == NULL)
        return CS_EXIT_INTERNAL;
    l->gpio = g;
    int rc = gpio_config(l, g, j);
    if (rc == CS_EXIT_OK)
        rc = gpio_segments(l, g, j);
    if (rc != CS_EXIT_OK)
        return rc;
    uint64_t steps[CS_AXES];
    job_steps(g, steps);
    rc = open_lines(l, g, steps,
                    cs_gpio_run_record_capacity(g->segs + g->first, g->nsegs - g->first), false);
    if (rc == CS_EXIT_OK && g->npens > 0) /* the pen servo: its own line and thread */
        rc = open_pen(l, g);
    if (rc == CS_EXIT_OK)
        say_lines(l, g);
    return rc;
}

int cs_gpio_link_open_ctl(cs_joblink_t *l, const cs_machine_t *m, unsigned axes, size_t record_cap)
{
    gpio_link_t *g = gpio_new(l, m);
    if (g == NULL)
        return CS_EXIT_INTERNAL;
    l->gpio = g;
    int rc = gpio_config(l, g, NULL);
    if (rc != CS_EXIT_OK)
        return rc;
    uint64_t steps[CS_AXES];
    for (unsigned i = 0; i < CS_AXES; i++)
        steps[i] = i < m->n_axes && (axes >> i & 1u) ? 1 : 0; /* the axes the command moves */
    return open_lines(l, g, steps, record_cap, true);
}

cs_gpio_link_t *cs_gpio_link_of(cs_joblink_t *l)
{
    return l->gpio;
}

/* The calling thread while the step thread runs: the interrupt (1: hold then end, 2: stop at
 * once) and pause requests passed on, progress shown, the confirmed pause said once. */
static void gpio_watch(gpio_link_t *g, const cs_joblink_ctl_t *c, progress_t *pg)
{
    cs_gpio_run_t *r = &g->run;
    int held = 0;
    bool paused = false, told = false;
    while (!cs_gpio_run_finished(r)) {
        int want = c->interrupt == NULL ? 0 : *c->interrupt >= 2 ? 2 : *c->interrupt >= 1 ? 1 : 0;
        if (want > held) {
            cs_gpio_run_hold(r, want);
            held = want;
            if (want == 1 && c->progress)
                fprintf(c->progress, "\nstream: Ctrl-C: holding (slowing down, then stopping at "
                                     "the end of a segment); Ctrl-C again stops at once\n");
        }
        bool p = c->pause != NULL && *c->pause != 0;
        if (p != paused) {
            cs_gpio_run_pause(r, p);
            paused = p;
            told = false;
        }
        if (paused && !told && cs_gpio_run_paused(r)) {
            cs_stream_progress_held(c->progress, cs_gpio_run_executed(r), g->nsegs, "segments");
            told = true;
        }
        if (g->in_open)
            cs_gpio_in_poll(&g->in); /* the recorder's e-stop file */
        progress(pg, g->segs, g->nsegs, g->ticks, g->m->tick_hz, r, false);
        struct timespec ts = {0, 20000000};
        nanosleep(&ts, NULL);
    }
}

/* "ALARM:1 (hard limit: ...), inputs 0x010, stopped at X Y Z mm" */
static void alarm_line(const gpio_link_t *g, char *out, size_t len)
{
    const cs_gpio_run_t *r = &g->run;
    int n = snprintf(out, len, "ALARM:%u (%s), inputs 0x%03x, stopped at", (unsigned)r->trip_code,
                     cs_ctlcfg_alarm_text(r->trip_code), (unsigned)r->trip_inputs);
    for (unsigned i = 0; i < g->m->n_axes && n > 0 && (size_t)n < len; i++)
        n += snprintf(out + n, len - (size_t)n, " %.4f",
                      g->st.pos[i] * (double)CS_MOTION_ONE / g->m->axis[i].steps_per_mm);
    if (n > 0 && (size_t)n < len)
        snprintf(out + n, len - (size_t)n, " mm");
}

/* The step thread's outcome as every link's result. */
static void gpio_result(const gpio_link_t *g, const cs_joblink_job_t *j, cs_stream_result_t *r)
{
    const cs_gpio_run_t *run = &g->run;
    memset(r, 0, sizeof *r);
    r->executed = r->delivered = r->sent = cs_gpio_run_executed(run);
    r->wall_s = r->stream_s = g->wall;
    r->dev_state = CS_PROTO_STATE_IDLE; /* the lines are safe: the position below is known */
    for (unsigned i = 0; i < CS_AXES && i < CS_PROTO_AXES_MAX; i++)
        r->dev_pos[i] = (j->start_pos ? j->start_pos[i] : 0) + run->pos[i];
    switch (run->outcome) {
    case CS_GPIO_RUN_DONE:
        r->outcome = CS_STREAM_DONE;
        if (g->npens > 0 && !(g->pw.started && g->pw.io_errno == 0)) {
            r->outcome = CS_STREAM_CLOSED; /* the servo may not have followed: say so */
            r->what = "job executed, but the pen servo's pulse train failed";
        }
        break;
    case CS_GPIO_RUN_HELD:
        r->outcome = CS_STREAM_INTERRUPTED;
        r->what = "interrupted: held, then stopped at the end of a segment (STEP low, ENABLE off)";
        break;
    case CS_GPIO_RUN_STOPPED:
        r->outcome = CS_STREAM_INTERRUPTED;
        r->what = "interrupted: stopped at once, mid-segment (STEP low, ENABLE off)";
        r->mid_message = true;
        break;
    case CS_GPIO_RUN_TRIPPED: /* as the device: an ERROR about the segment cut, exit 7 */
        r->outcome = CS_STREAM_DEVICE_ERROR;
        r->what = "the machine raised an alarm";
        r->dev_error.code =
            (uint8_t)(run->trip_code == CS_PROTO_ALARM_ESTOP ? CS_ERR_STATE : CS_ERR_LIMIT);
        r->dev_error_msg = r->executed + 1;
        r->mid_message = true;
        alarm_line(g, r->why, sizeof r->why);
        break;
    case CS_GPIO_RUN_BAD_SEGMENT:
        r->outcome = CS_STREAM_DEVICE_ERROR;
        r->what = "the executor refused a segment";
        r->dev_error.code = (uint8_t)CS_ERR_RANGE;
        r->dev_error_msg = run->bad_segment;
        snprintf(r->why, sizeof r->why, "ticks 0 or over 2^24, or more steps than ticks");
        break;
    case CS_GPIO_RUN_IO_ERROR:
        r->outcome = CS_STREAM_CLOSED;
        r->what = "setting the lines failed";
        snprintf(r->why, sizeof r->why, "%s", strerror(run->io_errno));
        break;
    }
}

/* The step thread's inputs: the link's, with the bits an operation waits for. */
static void inputs_opts(gpio_link_t *g, uint16_t watch, uint16_t release, bool hard_limits)
{
    cs_gpio_run_opts_t *ro = &g->ro;
    ro->in = g->has_in ? &g->in : NULL;
    ro->watch = watch;
    ro->release = release;
    ro->hard_limits = hard_limits;
    for (unsigned i = 0; i < CS_AXES; i++)
        ro->start_pos[i] = g->st.pos[i];
}

/* After a run: the machine position follows the steps on the lines; a trip other than the
 * operation's own input is the alarm (kept in the state file until unlock or homing). */
static void after_run(gpio_link_t *g)
{
    const cs_gpio_run_t *r = &g->run;
    if (g->t0_first == 0)
        g->t0_first = r->t0_ns;
    for (unsigned i = 0; i < CS_AXES; i++)
        g->st.pos[i] += r->pos[i];
    g->st.inputs = r->inputs;
    if (r->outcome == CS_GPIO_RUN_TRIPPED && r->trip_code != 0)
        g->st.alarm = r->trip_code;
}

static cs_err_t gpio_run(cs_joblink_t *l, const cs_joblink_job_t *j, const cs_joblink_ctl_t *c,
                         cs_stream_result_t *r)
{
    gpio_link_t *g = l->gpio;
    cs_gpio_run_opts_t *ro = &g->ro;
    ro->m = g->m;
    ro->cfg = &g->cfg;
    ro->io = &g->io;
    ro->segs = g->segs;
    ro->nsegs = g->nsegs;
    ro->first = g->first;
    ro->realtime = true;
    inputs_opts(g, 0, 0, true);
    int rc = cs_gpio_run_start(&g->run, ro);
    if (rc != 0) {
        fprintf(stderr, "curvestep: cannot start the step thread: %s\n", strerror(rc));
        cs_gpio_io_set(&g->io, (1u << g->lines.n) - 1u, 0, 0, &(int64_t){0});
        memset(r, 0, sizeof *r);
        return CS_ERR_IO;
    }
    warn_rt(&g->run, &g->cfg);
    if (g->npens > 0 &&
        (rc = cs_gpio_pwm_start(&g->pw, &g->pio, &g->run, g->pens, g->npens, g->cfg.spin_ns)) != 0)
        fprintf(stderr, "curvestep: cannot start the pen's thread: %s\n", strerror(rc));
    progress_t pg;
    memset(&pg, 0, sizeof pg);
    pg.f = c->progress;
    pg.tty = c->progress_tty;
    pg.n = g->nsegs;
    double t_start = now_s();
    pg.t0 = t_start;
    pg.first = g->first;
    gpio_watch(g, c, &pg);
    cs_gpio_run_join(&g->run);
    after_run(g);
    if (g->npens > 0)
        cs_gpio_pwm_stop(&g->pw); /* the last width out a few times, the line low */
    progress(&pg, g->segs, g->nsegs, g->ticks, g->m->tick_hz, &g->run, true);
    g->wall = now_s() - t_start;
    gpio_result(g, j, r);
    return CS_OK;
}

int cs_gpio_link_move(cs_joblink_t *l, const cs_segment_t *segs, size_t n, uint16_t watch,
                      uint16_t release, bool hard_limits, volatile sig_atomic_t *interrupt)
{
    gpio_link_t *g = l->gpio;
    cs_gpio_run_opts_t *ro = &g->ro;
    ro->m = g->m;
    ro->cfg = &g->cfg;
    ro->io = &g->io;
    ro->segs = g->segs = segs;
    ro->nsegs = g->nsegs = n;
    ro->first = g->first = 0;
    ro->realtime = true;
    inputs_opts(g, watch, release, hard_limits);
    int rc = cs_gpio_run_start(&g->run, ro);
    if (rc != 0)
        return rc;
    warn_rt(&g->run, &g->cfg);
    while (!cs_gpio_run_finished(&g->run)) {
        if (interrupt != NULL && *interrupt > 0)
            cs_gpio_run_hold(&g->run, 2);
        cs_gpio_in_poll(&g->in);
        struct timespec ts = {0, 5000000};
        nanosleep(&ts, NULL);
    }
    cs_gpio_run_join(&g->run);
    after_run(g);
    return 0;
}

/* "stream: S steps (x .., y ..) in T s (job time ..); STEP edges late by: ..." and, after a stop
 * at once, the note that the machine is past the last executed segment. */
static void gpio_counters(cs_joblink_t *l, FILE *out, const cs_stream_result_t *res)
{
    const gpio_link_t *g = l->gpio;
    const cs_gpio_run_t *r = &g->run;
    fprintf(out, "stream: %llu steps (",
            (unsigned long long)(r->steps[0] + r->steps[1] + r->steps[2] + r->steps[3]));
    for (unsigned i = 0; i < g->m->n_axes; i++)
        fprintf(out, "%s%s %llu", i ? ", " : "", axis_names[i], (unsigned long long)r->steps[i]);
    fprintf(out,
            ") in %.2f s (job time %.3f s); STEP edges late by: median <= %.0f us, 99 %% <= "
            "%.0f us, max %.1f us\n",
            g->wall, (double)r->ticks / g->m->tick_hz,
            (double)cs_gpio_run_late_quantile(r, 0.5) / 1000.0,
            (double)cs_gpio_run_late_quantile(r, 0.99) / 1000.0, (double)r->late_max_ns / 1000.0);
    if (g->npens > 0)
        (void)cs_gpio_pwm_report(out, &g->pw); /* a failure is the outcome already */
    if (res->mid_message)
        fprintf(out,
                "stream: (stopped mid-segment: the machine is past segment no. %zu, re-home it "
                "before resuming)\n",
                res->executed);
}

/* Writes the recorder's edges to its file: CS_EXIT_OK, or CS_EXIT_INTERNAL (said on stderr). */
static int write_record(const gpio_link_t *g)
{
    FILE *f = fopen(g->record, "w");
    char hdr[200];
    snprintf(hdr, sizeof hdr, "tick_hz=%u pulse_ns=%u dir_setup_ns=%u t0=tick0",
             (unsigned)g->m->tick_hz, (unsigned)g->cfg.pulse_ns, (unsigned)g->cfg.dir_setup_ns);
    int wr = f ? cs_gpio_io_write_record(&g->io, f, g->t0_first, hdr) : -1;
    if (wr == 0 && g->pio_open) /* the pen's line after the others, its own header line */
        wr = cs_gpio_io_write_record(&g->pio, f, g->t0_first, "pen servo: software PWM, 50 Hz");
    if (f && fclose(f) != 0)
        wr = -1;
    if (wr != 0) {
        fprintf(stderr, "curvestep: %s: %s\n", g->record, strerror(errno));
        return CS_EXIT_INTERNAL;
    }
    if (g->io.dropped) {
        fprintf(stderr, "curvestep: %s: %zu set calls did not fit the record\n", g->record,
                g->io.dropped);
        return CS_EXIT_INTERNAL;
    }
    return CS_EXIT_OK;
}

static int gpio_close(cs_joblink_t *l, int rc)
{
    gpio_link_t *g = l->gpio;
    if (g == NULL)
        return rc;
    if (g->pio_open)
        cs_gpio_io_close(&g->pio);
    if (g->in_open)
        cs_gpio_in_close(&g->in); /* before the outputs: they own the chip */
    if (g->st_loaded && cs_gpio_state_save(g->state_path, &g->st) != 0) {
        fprintf(stderr, "curvestep: cannot write the GPIO state %s: %s\n", g->state_path,
                strerror(errno));
        if (rc == CS_EXIT_OK)
            rc = CS_EXIT_INTERNAL;
    }
    if (g->io_open) {
        cs_gpio_io_close(&g->io);
        if (g->record && g->t0_first != 0) {
            int wrc = write_record(g);
            if (rc == CS_EXIT_OK)
                rc = wrc;
        }
    }
    cs_gpio_io_free(&g->io);
    cs_gpio_io_free(&g->pio);
    free(g->own);
    free(g->own_pens);
    free(g);
    l->gpio = NULL;
    return rc;
}

const cs_joblink_ops_t cs_joblink_gpio_ops = {
    .kind = "GPIO",
    .keep_open = false,
    .curves = false,
    .pens = true,
    .check = gpio_check,
    .open = gpio_open,
    .run = gpio_run,
    .counters = gpio_counters,
    .close = gpio_close,
};
