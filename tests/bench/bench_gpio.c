/* bench_gpio: the GPIO link's step thread (cs_gpio_run) on this machine, through the recorder
 * backend of the pin seam (every edge stamped on CLOCK_MONOTONIC with its planned time):
 *   1. edge timing on a drawing job (the built-in plotter, a spiral of 0.01 mm chords at
 *      100 mm/s, 3 s): lateness of every STEP rise after its planned time (median, p99,
 *      p99.9, max), pulse width and DIR set-up as measured;
 *   2. sustained step rate: one axis at constant rates from 10 k to 2 M steps/s (10 MHz
 *      executor ticks, 0.3 s each); the thread keeps up at a rate when its edges do not fall
 *      behind (median lateness under half a step period and the last 1 % of rises less than
 *      100 us late); the achieved rate says how many rises per second it managed.
 * Writes argv[1] (CSV) and prints a Markdown section. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_args.h"
#include "cs_gpio_cfg.h"
#include "cs_gpio_io.h"
#include "cs_gpio_run.h"
#include "cs_machine_ini.h"
#include "cs_motion.h"

typedef struct {
    size_t rises;
    double med_us, p99_us, p999_us, max_us, tail_us; /* lateness of the STEP rises */
    double pulse_min_us, pulse_med_us, pulse_max_us, setup_min_us;
    double achieved; /* rises per second, first to last */
    int sched_err, mlock_err;
} stats_t;

static int cmp_i64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return x < y ? -1 : x > y;
}

/* Runs segs on the step thread through a recorder with every axis of m wired, and measures. */
static void run(const cs_machine_t *m, const cs_gpio_cfg_t *cfg, const cs_segment_t *segs, size_t n,
                stats_t *s)
{
    memset(s, 0, sizeof *s);
    cs_gpio_lines_t l;
    memset(&l, 0, sizeof l);
    cs_gpio_run_opts_t o;
    memset(&o, 0, sizeof o);
    for (unsigned i = 0; i < CS_AXES; i++) {
        o.step_line[i] = o.dir_line[i] = -1;
        if (i < m->n_axes) {
            o.step_line[i] = (int)l.n;
            snprintf(l.name[l.n++], sizeof l.name[0], "s%u", i);
            o.dir_line[i] = (int)l.n;
            snprintf(l.name[l.n++], sizeof l.name[0], "d%u", i);
        }
    }
    o.enable_line = (int)l.n;
    snprintf(l.name[l.n++], sizeof l.name[0], "enable");
    cs_gpio_io_t io;
    if (cs_gpio_io_open_recorder(&io, &l, cs_gpio_run_record_capacity(segs, n)) != 0) {
        fprintf(stderr, "bench_gpio: out of memory\n");
        exit(1);
    }
    o.m = m;
    o.cfg = cfg;
    o.io = &io;
    o.segs = segs;
    o.nsegs = n;
    o.realtime = true;
    cs_gpio_run_t r;
    if (cs_gpio_run_start(&r, &o) != 0) {
        fprintf(stderr, "bench_gpio: cannot start the step thread\n");
        exit(1);
    }
    while (!cs_gpio_run_finished(&r)) {
        struct timespec ts = {0, 10000000};
        nanosleep(&ts, NULL);
    }
    cs_gpio_run_join(&r);
    cs_gpio_io_close(&io);
    s->sched_err = r.sched_err;
    s->mlock_err = r.mlock_err;
    uint32_t step_mask = 0, dir_mask = 0;
    for (unsigned i = 0; i < m->n_axes; i++) {
        step_mask |= 1u << o.step_line[i];
        dir_mask |= 1u << o.dir_line[i];
    }
    int64_t *late = malloc((io.nrec + 1) * sizeof *late);
    int64_t *pulse = malloc((io.nrec + 1) * sizeof *pulse);
    size_t nl = 0, np = 0;
    int64_t t_rise = 0, t_dir = INT64_MIN / 2, setup_min = INT64_MAX, first = 0, last = 0;
    for (size_t k = 0; k < io.nrec; k++) {
        const cs_gpio_edge_t *e = &io.rec[k];
        if (e->mask & dir_mask)
            t_dir = e->t_ns;
        if (!(e->mask & step_mask))
            continue;
        if (e->levels & step_mask) {
            late[nl++] = e->t_ns - e->planned_ns;
            if (e->t_ns - t_dir < setup_min)
                setup_min = e->t_ns - t_dir;
            t_rise = e->t_ns;
            if (nl == 1)
                first = e->t_ns;
            last = e->t_ns;
        } else {
            pulse[np++] = e->t_ns - t_rise;
        }
    }
    s->rises = nl;
    if (nl > 1)
        s->achieved = (double)(nl - 1) / ((double)(last - first) * 1e-9);
    if (nl > 0) {
        /* the tail: median lateness of the last 1 % of rises (grows when the thread lags) */
        size_t tail = nl / 100 ? nl / 100 : 1;
        qsort(late + nl - tail, tail, sizeof *late, cmp_i64);
        s->tail_us = late[nl - tail + tail / 2] / 1e3;
        qsort(late, nl, sizeof *late, cmp_i64);
        s->med_us = late[nl / 2] / 1e3;
        s->p99_us = late[(size_t)(nl * 0.99)] / 1e3;
        s->p999_us = late[(size_t)(nl * 0.999)] / 1e3;
        s->max_us = late[nl - 1] / 1e3;
        s->setup_min_us = setup_min / 1e3;
    }
    if (np > 0) {
        qsort(pulse, np, sizeof *pulse, cmp_i64);
        s->pulse_min_us = pulse[0] / 1e3;
        s->pulse_med_us = pulse[np / 2] / 1e3;
        s->pulse_max_us = pulse[np - 1] / 1e3;
    }
    free(late);
    free(pulse);
    cs_gpio_io_free(&io);
}

/* The drawing job: an Archimedean spiral of chords (0.01 mm sagitta) from r = 5 mm, 3 s. */
static void spiral_job(const cs_machine_t *m, cs_motion_t *mo)
{
    cs_motion_init(mo, m);
    double a = 0;
    for (int k = 0; k < 100000 && mo->ticks < 3u * m->tick_hz; k++) {
        double r = 5 + a * 0.5;
        double chord = sqrt(8 * r * 0.01);
        a += chord / r;
        if (cs_motion_line_mm(mo, (5 + a * 0.5) * cos(a), (5 + a * 0.5) * sin(a), 0, 100,
                              (uint32_t)k) != CS_OK)
            break;
    }
    cs_motion_finish(mo);
}

static const char *granted(int err)
{
    return err == 0 ? "granted" : err == -2 ? "skipped (ASan)" : "refused";
}

int main(int argc, char **argv)
{
    static const char usage[] = "usage: bench_gpio [OUT.csv]\n"
        "Timing of the GPIO step thread on a recorded job; a Markdown section on stdout,\n"
        "the figures in OUT.csv.\n";
    int usage_rc = bench_args_check(argc, argv, usage, 1);
    if (usage_rc >= 0)
        return usage_rc;
    FILE *csv = argc > 1 ? fopen(argv[1], "w") : NULL;
    /* 1. drawing job */
    cs_machine_t m;
    cs_machine_ini_default(&m);
    cs_gpio_cfg_t cfg;
    cs_gpio_cfg_default(&cfg, &m);
    cfg.pulse_ns = 2000; /* [gpio] pulse_us = 2 */
    cs_motion_t mo;
    spiral_job(&m, &mo);
    stats_t job;
    fprintf(stderr, "bench_gpio: drawing job, %zu segments, %.1f s\n", mo.segs.n,
            (double)mo.ticks / m.tick_hz);
    run(&m, &cfg, mo.segs.v, mo.segs.n, &job);
    double job_s = (double)mo.ticks / m.tick_hz;
    size_t job_segs = mo.segs.n;
    cs_motion_free(&mo);

    /* 2. sustained rate, one axis, constant rate per run */
    static const double rates[] = {10e3, 20e3, 50e3, 100e3, 200e3, 500e3, 1e6, 1.5e6, 2e6};
    enum { NR = sizeof rates / sizeof rates[0] };
    stats_t rs[NR];
    cs_machine_t hm;
    cs_machine_ini_default(&hm);
    hm.tick_hz = 10000000;
    cs_gpio_cfg_t hc;
    cs_gpio_cfg_default(&hc, &hm);
    hc.pulse_ns = 200;
    hc.dir_setup_ns = 0;
    double best = 0;
    for (int k = 0; k < NR; k++) {
        enum { SEG_TICKS = 50000, NSEG = 60 }; /* 5 ms segments, 0.3 s */
        static cs_segment_t segs[NSEG];
        uint32_t steps = (uint32_t)llround(rates[k] * SEG_TICKS / hm.tick_hz);
        for (int j = 0; j < NSEG; j++) {
            memset(&segs[j], 0, sizeof segs[j]);
            segs[j].ticks = SEG_TICKS;
            segs[j].steps[0] = (int32_t)steps;
        }
        fprintf(stderr, "bench_gpio: %.0f steps/s\n", rates[k]);
        run(&hm, &hc, segs, NSEG, &rs[k]);
        double half_period_us = 0.5e6 / rates[k];
        bool kept = rs[k].med_us < half_period_us && rs[k].tail_us < 100;
        if (kept && rates[k] > best)
            best = rates[k];
    }

    printf("## GPIO step thread (bench_gpio)\n\n");
    printf("The step thread of `curvestep stream --gpio` (host/cs_gpio_run.c) driving the "
           "recorder backend\nof the pin seam: every edge is stamped on CLOCK_MONOTONIC right "
           "after it is set, with the\ntime it was planned for. A real chip adds one ioctl "
           "(GPIOHANDLE_SET_LINE_VALUES) to every\nset call, not measured here: this machine has "
           "no GPIO chip. SCHED_FIFO %s,\nmlockall %s; spin margin %.0f us. Lateness = stamp "
           "minus planned time (never negative:\nthe thread never sets a line early).\n\n",
           granted(job.sched_err), granted(job.mlock_err), cfg.spin_ns / 1e3);
    printf("### Edge timing on a drawing job\n\n");
    printf("Built-in plotter (80 steps/mm, 100 kHz executor ticks), a spiral of 0.01 mm chords "
           "at\n100 mm/s: %zu segments, %.1f s, %zu STEP rises (x and y), pulse_us = 2, "
           "dir_setup_us = 1.\n\n",
           job_segs, job_s, job.rises);
    printf("| STEP rise lateness | median | p99 | p99.9 | max |\n|---|---:|---:|---:|---:|\n");
    printf("| us | %.2f | %.1f | %.1f | %.1f |\n\n", job.med_us, job.p99_us, job.p999_us,
           job.max_us);
    printf("| measured | min | median | max |\n|---|---:|---:|---:|\n");
    printf("| STEP pulse width, us (configured 2) | %.2f | %.2f | %.1f |\n", job.pulse_min_us,
           job.pulse_med_us, job.pulse_max_us);
    printf("| DIR set-up before a STEP rise, us (configured 1) | %.2f | | |\n\n", job.setup_min_us);
    printf("### Sustained step rate\n\n");
    printf("One axis at a constant rate, 10 MHz executor ticks, 5 ms segments for 0.3 s, pulse "
           "0.2 us,\nno DIR change. Kept up = median lateness under half a step period and the "
           "last 1 %% of\nrises less than 100 us late (a thread that cannot keep up falls "
           "further behind with\nevery step).\n\n");
    printf("| steps/s | rises | achieved rises/s | median late, us | p99, us | max, us | last 1 "
           "%%, us | kept up |\n|---:|---:|---:|---:|---:|---:|---:|---|\n");
    if (csv)
        fprintf(csv,
                "test,rate,rises,achieved,median_us,p99_us,p999_us,max_us,tail_us,"
                "pulse_min_us,pulse_med_us,setup_min_us\n"
                "drawing,,%zu,%.0f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f\n",
                job.rises, job.achieved, job.med_us, job.p99_us, job.p999_us, job.max_us,
                job.tail_us, job.pulse_min_us, job.pulse_med_us, job.setup_min_us);
    for (int k = 0; k < NR; k++) {
        double half_period_us = 0.5e6 / rates[k];
        bool kept = rs[k].med_us < half_period_us && rs[k].tail_us < 100;
        printf("| %.0f | %zu | %.0f | %.2f | %.1f | %.1f | %.1f | %s |\n", rates[k], rs[k].rises,
               rs[k].achieved, rs[k].med_us, rs[k].p99_us, rs[k].max_us, rs[k].tail_us,
               kept ? "yes" : "**no**");
        if (csv)
            fprintf(csv, "constant,%.0f,%zu,%.0f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,\n", rates[k],
                    rs[k].rises, rs[k].achieved, rs[k].med_us, rs[k].p99_us, rs[k].p999_us,
                    rs[k].max_us, rs[k].tail_us, rs[k].pulse_min_us, rs[k].pulse_med_us);
    }
    printf("\nSustained step rate of the thread on this machine: **%.0f steps/s** (the highest "
           "rate above\nthat kept up).\n",
           best);
    if (csv)
        fclose(csv);
    return 0;
}
