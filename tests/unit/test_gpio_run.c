/* Tests of the GPIO link's step thread (cs_gpio_run) through the recorder backend of the pin
 * seam (cs_gpio_io): jobs planned with cs_motion run on the real thread in real time, and the
 * recorded edges are checked against the simulator (sim/cs_sim.h, the same segments on the
 * same cs_stepper in simulated time): signed steps per axis, and the planned time of every
 * STEP rise equal to the simulator's tick for that step; every STEP pulse at least the
 * configured width; DIR stable at least the set-up time before every STEP rise; edges in order
 * and never before their planned time; ENABLE on before the first step and off at the end.
 * Hold (slow down, stop at a segment end), stop at once and resume. The edge timing error is
 * printed, not asserted (timing goals: tests/bench/bench_gpio.c). Also the recorder itself, the
 * message for a missing chip, and the inputs (the recorder's simulated switches, probe and e-stop
 * stopping the thread on the very step that trips them). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cs_ctlcfg.h"
#include "cs_gpio_cfg.h"
#include "cs_gpio_in.h"
#include "cs_gpio_io.h"
#include "cs_gpio_run.h"
#include "cs_machine_ini.h"
#include "cs_motion.h"
#include "cs_proto.h"
#include "cs_sim.h"

/* A job of straight moves (mm, 4 axes) planned whole: the segments `curvestep plan` would give. */
static void plan(const cs_machine_t *m, const double (*pts)[4], size_t n, double feed,
                 cs_motion_t *mo)
{
    assert_int_equal(cs_motion_init(mo, m), CS_OK);
    for (size_t k = 0; k < n; k++) {
        cs_pos_t t[CS_AXES];
        for (unsigned i = 0; i < CS_AXES; i++)
            t[i] = (cs_pos_t)(pts[k][i] * CS_POS_ONE_MM);
        assert_int_equal(cs_motion_line(mo, t, cs_motion_speed(feed), (uint32_t)k + 1), CS_OK);
    }
    assert_int_equal(cs_motion_finish(mo), CS_OK);
}

/* Every axis of the machine wired (the recorder ignores offsets), plus ENABLE. */
static void lines_for(const cs_machine_t *m, const cs_gpio_cfg_t *cfg, cs_gpio_lines_t *l,
                      cs_gpio_run_opts_t *o)
{
    static const char *const names[CS_AXES] = {"x", "y", "z", "a"};
    memset(l, 0, sizeof *l);
    memset(o, 0, sizeof *o);
    for (unsigned i = 0; i < CS_AXES; i++) {
        o->step_line[i] = o->dir_line[i] = -1;
        if (i >= m->n_axes)
            continue;
        o->step_line[i] = (int)l->n;
        snprintf(l->name[l->n], sizeof l->name[0], "%s_step", names[i]);
        l->active_low[l->n++] = cfg->step_active_low;
        o->dir_line[i] = (int)l->n;
        snprintf(l->name[l->n++], sizeof l->name[0], "%s_dir", names[i]);
    }
    o->enable_line = (int)l->n;
    l->active_low[l->n] = cfg->enable_active_low;
    snprintf(l->name[l->n++], sizeof l->name[0], "enable");
}

static int cmp_i64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return x < y ? -1 : x > y;
}

static int64_t ticks_ns(uint64_t t, uint32_t hz)
{
    return (int64_t)((t / hz) * 1000000000u + (t % hz) * 1000000000u / hz);
}

/* What the record says, checked edge by edge against the configuration and, when sim != NULL,
 * against the simulator's steps (sim_upto: rises compared with the simulator until that planned
 * time, relative to t0; INT64_MAX for all). */
typedef struct {
    int64_t pos[CS_AXES];
    uint64_t rises[CS_AXES];
    size_t n_rises; /* set calls with a STEP rise */
    int64_t min_pulse, min_setup;
    int64_t *late; /* lateness of each STEP rise set call, ns */
    int64_t last_planned_gap[CS_AXES], last_sim_gap[CS_AXES]; /* last two rises of the axis */
} decoded_t;

static void decode(const cs_gpio_io_t *io, const cs_gpio_run_t *r, const cs_machine_t *m,
                   const cs_gpio_cfg_t *cfg, const cs_sim_exec_t *sim, int64_t sim_upto,
                   decoded_t *d)
{
    const cs_gpio_run_opts_t *o = &r->o;
    memset(d, 0, sizeof *d);
    d->min_pulse = d->min_setup = INT64_MAX;
    d->late = calloc(io->nrec + 1, sizeof *d->late);
    assert_non_null(d->late);
    assert_int_equal(io->dropped, 0);
    uint32_t lv = io->lines.initial;
    int64_t t_prev = INT64_MIN, t_dir = INT64_MIN / 2, t_rise[CS_AXES] = {0};
    int64_t planned_rise[CS_AXES] = {0};
    size_t sim_k[CS_AXES] = {0};
    uint64_t sim_prev[CS_AXES] = {0};
    uint32_t en = 1u << o->enable_line;
    bool enabled_seen = false;
    for (size_t k = 0; k < io->nrec; k++) {
        const cs_gpio_edge_t *e = &io->rec[k];
        assert_true(e->t_ns >= t_prev);        /* in order */
        assert_true(e->t_ns >= e->planned_ns); /* never early */
        t_prev = e->t_ns;
        uint32_t now = (lv & ~e->mask) | (e->levels & e->mask);
        if (e->mask & en && now & en)
            enabled_seen = true;
        bool rise_call = false;
        for (unsigned i = 0; i < m->n_axes; i++) {
            uint32_t sb = 1u << o->step_line[i], db = 1u << o->dir_line[i];
            if (e->mask & db)
                t_dir = e->t_ns;
            if (!(e->mask & sb))
                continue;
            if (now & sb) { /* STEP rise: one step in the direction DIR shows */
                assert_true(enabled_seen);
                rise_call = true;
                int64_t setup = e->t_ns - t_dir;
                if (setup < d->min_setup)
                    d->min_setup = setup;
                bool high = (lv & db) != 0;
                bool positive = high != m->axis[i].invert_dir;
                d->pos[i] += positive ? 1 : -1;
                d->rises[i]++;
                t_rise[i] = e->t_ns;
                if (sim) {
                    /* the simulator's next step of axis i */
                    while (sim_k[i] < sim->n && sim->edges[sim_k[i]].axis != i)
                        sim_k[i]++;
                    assert_true(sim_k[i] < sim->n);
                    const port_posix_edge_t *se = &sim->edges[sim_k[i]++];
                    assert_int_equal(se->dir, positive ? 1 : -1);
                    int64_t want = ticks_ns(se->t - 1, m->tick_hz); /* the sim kicks at tick 1 */
                    if (e->planned_ns - r->t0_ns <= sim_upto)
                        assert_int_equal(e->planned_ns - r->t0_ns, want);
                    if (d->rises[i] > 1) {
                        d->last_planned_gap[i] = e->planned_ns - planned_rise[i];
                        d->last_sim_gap[i] =
                            ticks_ns(se->t, m->tick_hz) - ticks_ns(sim_prev[i], m->tick_hz);
                    }
                    sim_prev[i] = se->t;
                }
                planned_rise[i] = e->planned_ns;
            } else { /* STEP fall */
                int64_t w = e->t_ns - t_rise[i];
                if (w < d->min_pulse)
                    d->min_pulse = w;
            }
        }
        /* DIR never changes while a STEP line is up */
        for (unsigned i = 0; i < m->n_axes; i++)
            if (e->mask & (1u << o->dir_line[i]))
                for (unsigned j = 0; j < m->n_axes; j++)
                    assert_false(lv & (1u << o->step_line[j]) && now & (1u << o->step_line[j]));
        if (rise_call)
            d->late[d->n_rises++] = e->t_ns - e->planned_ns;
        lv = now;
    }
    /* the lines left safe: every STEP low, ENABLE off */
    for (unsigned i = 0; i < m->n_axes; i++)
        assert_int_equal(io->levels & (1u << o->step_line[i]), 0);
    assert_int_equal(io->levels & en, 0);
    (void)cfg;
}

static void report_timing(const char *what, decoded_t *d)
{
    if (d->n_rises == 0)
        return;
    qsort(d->late, d->n_rises, sizeof *d->late, cmp_i64);
    print_message("  %s: %zu STEP rises late by median %.1f us, p99 %.1f us, max %.1f us; "
                  "pulse >= %.2f us, DIR set-up >= %.2f us\n",
                  what, d->n_rises, d->late[d->n_rises / 2] / 1e3,
                  d->late[d->n_rises * 99 / 100] / 1e3, d->late[d->n_rises - 1] / 1e3,
                  d->min_pulse / 1e3, d->min_setup / 1e3);
}

/* Runs segs[first..n) on the step thread through a recorder; waits (bounded) for the end, or
 * asks for a hold of `hold_level` after hold_after_ms. */
/* The inputs run_job hands the thread (test_inputs_trip sets them; none otherwise). */
static cs_gpio_run_opts_t g_in_opts;

static void run_job(const cs_machine_t *m, const cs_gpio_cfg_t *cfg, const cs_segment_t *segs,
                    size_t n, size_t first, bool realtime, int hold_level, int hold_after_ms,
                    cs_gpio_io_t *io, cs_gpio_run_t *r)
{
    cs_gpio_lines_t l;
    cs_gpio_run_opts_t o;
    lines_for(m, cfg, &l, &o);
    assert_int_equal(cs_gpio_io_open_recorder(io, &l, cs_gpio_run_record_capacity(segs, n)), 0);
    o.m = m;
    o.cfg = cfg;
    o.io = io;
    o.segs = segs;
    o.nsegs = n;
    o.first = first;
    o.realtime = realtime;
    o.in = g_in_opts.in;
    o.watch = g_in_opts.watch;
    o.release = g_in_opts.release;
    o.hard_limits = g_in_opts.hard_limits;
    memcpy(o.start_pos, g_in_opts.start_pos, sizeof o.start_pos);
    assert_int_equal(cs_gpio_run_start(r, &o), 0);
    int64_t t_start = cs_gpio_io_now_ns();
    bool held = false;
    /* bounded: the longest job here lasts 3 s */
    while (!cs_gpio_run_finished(r) && cs_gpio_io_now_ns() - t_start < 30000000000LL) {
        if (hold_level && !held && cs_gpio_io_now_ns() - t_start >= hold_after_ms * 1000000LL) {
            cs_gpio_run_hold(r, hold_level);
            held = true;
        }
        struct timespec ts = {0, 5000000};
        nanosleep(&ts, NULL);
    }
    assert_true(cs_gpio_run_finished(r));
    cs_gpio_run_join(r);
    cs_gpio_io_close(io);
}

static void expect_like_sim(const cs_machine_t *m, const cs_gpio_cfg_t *cfg, const double (*pts)[4],
                            size_t npts, double feed, const char *what)
{
    cs_motion_t mo;
    plan(m, pts, npts, feed, &mo);
    cs_sim_exec_t sim;
    assert_int_equal(cs_sim_execute(m, mo.segs.v, mo.segs.n, &sim), CS_OK);
    cs_gpio_io_t io;
    cs_gpio_run_t r;
    run_job(m, cfg, mo.segs.v, mo.segs.n, 0, true, 0, 0, &io, &r);
    assert_int_equal(r.outcome, CS_GPIO_RUN_DONE);
    assert_int_equal(cs_gpio_run_executed(&r), mo.segs.n);
    decoded_t d;
    decode(&io, &r, m, cfg, &sim, INT64_MAX, &d);
    uint64_t total = 0;
    for (unsigned i = 0; i < m->n_axes; i++) {
        assert_int_equal(d.pos[i], sim.pos[i]); /* signed steps, from the lines */
        assert_int_equal(d.pos[i], mo.pos[i]);  /* = the plan's own total */
        assert_int_equal(r.pos[i], mo.pos[i]);
        assert_int_equal(d.rises[i], r.steps[i]);
        total += d.rises[i];
    }
    assert_int_equal(total, sim.n); /* and not one step more */
    assert_true(total > 0);
    assert_true(d.min_pulse >= (int64_t)cfg->pulse_ns);
    assert_true(d.min_setup >= (int64_t)cfg->dir_setup_ns);
    assert_int_equal(r.ticks, sim.end_tick - 1);
    print_message("  %s: %llu steps, sched_err %d, mlock_err %d\n", what, (unsigned long long)total,
                  r.sched_err, r.mlock_err);
    report_timing(what, &d);
    free(d.late);
    cs_gpio_io_free(&io);
    cs_sim_exec_free(&sim);
    cs_motion_free(&mo);
}

/* A 3-axis job with reversals on every axis, the built-in plotter (100 kHz ticks), about 0.6 s. */
static void test_thread_matches_simulator(void **state)
{
    (void)state;
    cs_machine_t m;
    cs_machine_ini_default(&m);
    cs_gpio_cfg_t cfg;
    cs_gpio_cfg_default(&cfg, &m);
    static const double pts[][4] = {
        {10, 5, 0, 0}, {2, 8, 1, 0}, {-3, -2, -1, 0}, {4, -6, 0.5, 0}, {0, 0, 0, 0}};
    expect_like_sim(&m, &cfg, pts, sizeof pts / sizeof pts[0], 120, "3 axes");
}

/* 4 axes, DIR inverted on y and a, STEP active low, a longer DIR set-up than the shortest
 * step period leaves after a reversal, a 3 us pulse, 50 kHz ticks. */
static void test_thread_4_axes_inverted_long_setup(void **state)
{
    (void)state;
    cs_machine_t m;
    char err[256];
    assert_int_equal(cs_machine_ini_parse("[machine]\ntick_hz = 50000\n[y]\ninvert_dir = true\n"
                                          "[a]\ninvert_dir = true\nsteps_per_mm = 40\n",
                                          "m.ini", &m, err, sizeof err),
                     0);
    cs_gpio_cfg_t cfg;
    assert_int_equal(cs_gpio_cfg_parse("[gpio]\nstep_active_low = true\npulse_us = 3\n"
                                       "dir_setup_us = 150\n",
                                       "m.ini", &m, &cfg, err, sizeof err),
                     0);
    static const double pts[][4] = {{6, -4, 0, 3}, {-2, 3, 0.5, -5}, {0, 0, 0, 0}};
    expect_like_sim(&m, &cfg, pts, sizeof pts / sizeof pts[0], 100, "4 axes");
}

/* Sum of the segments' steps over [a, b). */
static void seg_sum(const cs_segment_t *s, size_t a, size_t b, int64_t *pos)
{
    for (unsigned i = 0; i < CS_AXES; i++)
        pos[i] = 0;
    for (size_t k = a; k < b; k++)
        for (unsigned i = 0; i < CS_AXES; i++)
            pos[i] += s[k].steps[i];
}

/* Hold mid-job: the thread decelerates along the path (the core's cs_hold), stops at a segment
 * end, leaves the lines safe; the position is exactly the executed segments' sum. */
static void test_hold_stops_at_a_segment_end(void **state)
{
    (void)state;
    cs_machine_t m;
    cs_machine_ini_default(&m);
    cs_gpio_cfg_t cfg;
    cs_gpio_cfg_default(&cfg, &m);
    static const double pts[][4] = {{150, 100, 0, 0}}; /* 180 mm at 100 mm/s: ~2 s */
    cs_motion_t mo;
    plan(&m, pts, 1, 100, &mo);
    cs_sim_exec_t sim;
    assert_int_equal(cs_sim_execute(&m, mo.segs.v, mo.segs.n, &sim), CS_OK);
    cs_gpio_io_t io;
    cs_gpio_run_t r;
    run_job(&m, &cfg, mo.segs.v, mo.segs.n, 0, false, 1, 400, &io, &r);
    assert_int_equal(r.outcome, CS_GPIO_RUN_HELD);
    size_t k = cs_gpio_run_executed(&r);
    assert_true(k > 0 && k < mo.segs.n);
    decoded_t d;
    /* planned times match the simulator's until the hold, asked for at 400 ms (compared up to
     * 100 ms: the thread may see the request late, and then stretches from its last planned
     * time) */
    decode(&io, &r, &m, &cfg, &sim, 100000000, &d);
    int64_t want[CS_AXES];
    seg_sum(mo.segs.v, 0, k, want);
    for (unsigned i = 0; i < m.n_axes; i++) {
        assert_int_equal(d.pos[i], want[i]);
        assert_int_equal(r.pos[i], want[i]);
    }
    /* the hold ramps the speed down to rest (cs_hold.h): the last segment runs at most at the
     * mean of a linear ramp from rest through one segment of job time tau, sqrt(2 tau / T) / 2
     * of the job's speed, T = 5/4 of the longest max_rate / max_accel (0.25 s here): the last
     * planned interval between two x steps is at least 1 / that times the simulator's at full
     * speed (0.8: the DDA's spacing inside a segment and the integer ns) */
    double T = 0;
    for (unsigned i = 0; i < m.n_axes; i++) {
        double ti = 1.25 * m.axis[i].max_rate / (double)m.axis[i].max_accel;
        T = ti > T ? ti : T;
    }
    double tau = (double)m.segment_ticks / m.tick_hz;
    double last_scale = sqrt(2 * tau / T) / 2;
    assert_true(d.last_sim_gap[0] > 0);
    assert_true((double)d.last_planned_gap[0] >= 0.8 * (double)d.last_sim_gap[0] / last_scale);
    print_message("  hold: stopped after segment %zu of %zu; last x step interval %.1f us "
                  "planned vs %.1f us at full speed\n",
                  k, mo.segs.n, d.last_planned_gap[0] / 1e3, d.last_sim_gap[0] / 1e3);
    free(d.late);
    cs_gpio_io_free(&io);
    cs_sim_exec_free(&sim);
    cs_motion_free(&mo);
}

/* Stop at once (a second Ctrl-C): mid-segment, every step the executor made is on the lines,
 * the lines left safe. */
static void test_stop_at_once(void **state)
{
    (void)state;
    cs_machine_t m;
    cs_machine_ini_default(&m);
    cs_gpio_cfg_t cfg;
    cs_gpio_cfg_default(&cfg, &m);
    static const double pts[][4] = {{150, 100, 0, 0}};
    cs_motion_t mo;
    plan(&m, pts, 1, 100, &mo);
    cs_gpio_io_t io;
    cs_gpio_run_t r;
    run_job(&m, &cfg, mo.segs.v, mo.segs.n, 0, false, 2, 300, &io, &r);
    assert_int_equal(r.outcome, CS_GPIO_RUN_STOPPED);
    assert_true(cs_gpio_run_executed(&r) < mo.segs.n);
    decoded_t d;
    decode(&io, &r, &m, &cfg, NULL, 0, &d);
    for (unsigned i = 0; i < m.n_axes; i++)
        assert_int_equal(d.pos[i], r.pos[i]);
    assert_true(d.pos[0] > 0);
    free(d.late);
    cs_gpio_io_free(&io);
    cs_motion_free(&mo);
}

/* Resume from segment k: exactly the steps of segments k+1..n. */
static void test_resume(void **state)
{
    (void)state;
    cs_machine_t m;
    cs_machine_ini_default(&m);
    cs_gpio_cfg_t cfg;
    cs_gpio_cfg_default(&cfg, &m);
    static const double pts[][4] = {{10, 5, 0, 0}, {0, 9, 0, 0}, {0, 0, 0, 0}};
    cs_motion_t mo;
    plan(&m, pts, 3, 150, &mo);
    size_t first = mo.segs.n / 2;
    cs_gpio_io_t io;
    cs_gpio_run_t r;
    run_job(&m, &cfg, mo.segs.v, mo.segs.n, first, false, 0, 0, &io, &r);
    assert_int_equal(r.outcome, CS_GPIO_RUN_DONE);
    assert_int_equal(cs_gpio_run_executed(&r), mo.segs.n);
    decoded_t d;
    decode(&io, &r, &m, &cfg, NULL, 0, &d);
    int64_t want[CS_AXES];
    seg_sum(mo.segs.v, first, mo.segs.n, want);
    for (unsigned i = 0; i < m.n_axes; i++)
        assert_int_equal(d.pos[i], want[i]);
    free(d.late);
    cs_gpio_io_free(&io);
    cs_motion_free(&mo);
}

/* Waits (bounded, 30 s) until cond(r) holds; false at the deadline. */
static bool wait_for(cs_gpio_run_t *r, bool (*cond)(const cs_gpio_run_t *))
{
    int64_t t_start = cs_gpio_io_now_ns();
    while (!cond(r) && cs_gpio_io_now_ns() - t_start < 30000000000LL) {
        struct timespec ts = {0, 5000000};
        nanosleep(&ts, NULL);
    }
    return cond(r);
}

static bool moved(const cs_gpio_run_t *r)
{
    return cs_gpio_run_executed(r) > 0 || cs_gpio_run_finished(r);
}

/* Pause (the daemon's): the thread decelerates with the core's ramp, waits at rest with the job
 * kept, and on resume ramps back up and runs the rest: every step of the plan on the lines, in
 * order, never early, pulses and DIR set-up kept across the pause. */
static void test_pause_and_resume(void **state)
{
    (void)state;
    cs_machine_t m;
    cs_machine_ini_default(&m);
    cs_gpio_cfg_t cfg;
    cs_gpio_cfg_default(&cfg, &m);
    static const double pts[][4] = {{60, 40, 0, 0}, {20, 60, 0, 0}}; /* ~1.5 s at 80 mm/s */
    cs_motion_t mo;
    plan(&m, pts, 2, 80, &mo);
    cs_gpio_lines_t l;
    cs_gpio_run_opts_t o;
    lines_for(&m, &cfg, &l, &o);
    cs_gpio_io_t io;
    assert_int_equal(
        cs_gpio_io_open_recorder(&io, &l, cs_gpio_run_record_capacity(mo.segs.v, mo.segs.n)), 0);
    o.m = &m;
    o.cfg = &cfg;
    o.io = &io;
    o.segs = mo.segs.v;
    o.nsegs = mo.segs.n;
    o.first = 0;
    o.realtime = false;
    cs_gpio_run_t r;
    assert_int_equal(cs_gpio_run_start(&r, &o), 0);
    assert_true(wait_for(&r, moved)); /* the event: a segment executed */
    cs_gpio_run_pause(&r, true);
    assert_true(wait_for(&r, cs_gpio_run_paused)); /* at rest, the hold confirmed */
    size_t k = cs_gpio_run_executed(&r);
    assert_false(cs_gpio_run_finished(&r));
    assert_true(k > 0 && k < mo.segs.n);
    int64_t at_rest[CS_AXES];
    seg_sum(mo.segs.v, 0, k, at_rest); /* at rest at a segment end */
    for (unsigned i = 0; i < m.n_axes; i++)
        assert_int_equal(cs_stepper_position(&r.st, i), at_rest[i]);
    cs_gpio_run_pause(&r, false);
    assert_true(wait_for(&r, cs_gpio_run_finished));
    cs_gpio_run_join(&r);
    cs_gpio_io_close(&io);
    assert_int_equal(r.outcome, CS_GPIO_RUN_DONE);
    assert_int_equal(cs_gpio_run_executed(&r), mo.segs.n);
    decoded_t d;
    decode(&io, &r, &m, &cfg, NULL, 0, &d);
    for (unsigned i = 0; i < m.n_axes; i++) {
        assert_int_equal(d.pos[i], mo.pos[i]); /* every step of the plan, none twice */
        assert_int_equal(r.pos[i], mo.pos[i]);
    }
    assert_true(d.min_pulse >= (int64_t)cfg.pulse_ns);
    assert_true(d.min_setup >= (int64_t)cfg.dir_setup_ns);
    print_message("  pause: at rest after segment %zu of %zu, then resumed to the end\n", k,
                  mo.segs.n);
    free(d.late);
    cs_gpio_io_free(&io);
    cs_motion_free(&mo);
}

/* A segment the executor refuses (more steps than ticks) stops the run there, named, with
 * every step before it on the lines and the lines safe. */
static void test_bad_segment(void **state)
{
    (void)state;
    cs_machine_t m;
    cs_machine_ini_default(&m);
    cs_gpio_cfg_t cfg;
    cs_gpio_cfg_default(&cfg, &m);
    cs_segment_t segs[6];
    memset(segs, 0, sizeof segs);
    for (unsigned k = 0; k < 6; k++) {
        segs[k].ticks = 500;
        segs[k].steps[0] = 20;
        segs[k].steps[1] = -7;
    }
    segs[3].steps[1] = 501; /* |steps| > ticks */
    cs_gpio_io_t io;
    cs_gpio_run_t r;
    run_job(&m, &cfg, segs, 6, 0, false, 0, 0, &io, &r);
    assert_int_equal(r.outcome, CS_GPIO_RUN_BAD_SEGMENT);
    assert_int_equal(r.bad_segment, 4);
    assert_true(cs_gpio_run_executed(&r) <= 3);
    decoded_t d;
    decode(&io, &r, &m, &cfg, NULL, 0, &d);
    assert_int_equal(d.pos[0], r.pos[0]);
    assert_int_equal(d.pos[1], r.pos[1]);
    assert_true(d.pos[0] >= 40 && d.pos[0] <= 60); /* segments 1, 2 and part of 3 */
    free(d.late);
    cs_gpio_io_free(&io);
}

/* The recorder keeps changes only, with their planned time, and writes one CSV row per line
 * change. */
static void test_recorder(void **state)
{
    (void)state;
    cs_gpio_lines_t l;
    memset(&l, 0, sizeof l);
    l.n = 3;
    strcpy(l.name[0], "x_step");
    strcpy(l.name[1], "x_dir");
    strcpy(l.name[2], "enable");
    l.initial = 0x2; /* x_dir high */
    cs_gpio_io_t io;
    assert_int_equal(cs_gpio_io_open_recorder(&io, &l, 3), 0);
    int64_t t0 = cs_gpio_io_now_ns(), t1, t2, t3, t4;
    assert_int_equal(cs_gpio_io_set(&io, 0x4, 0x4, t0, &t1), 0);     /* enable on */
    assert_int_equal(cs_gpio_io_set(&io, 0x2, 0x2, t0, &t2), 0);     /* x_dir already high */
    assert_int_equal(cs_gpio_io_set(&io, 0x3, 0x1, t0 + 5, &t3), 0); /* step up, dir down */
    assert_int_equal(cs_gpio_io_set(&io, 0x1, 0x0, t0 + 9, &t4), 0); /* step down */
    assert_true(t1 >= t0 && t2 >= t1 && t3 >= t2 && t4 >= t3);
    assert_int_equal(io.nrec, 3); /* the no-change call left nothing */
    assert_int_equal(io.dropped, 0);
    int64_t t5;
    assert_int_equal(cs_gpio_io_set(&io, 0x4, 0x0, t0 + 20, &t5), 0); /* enable off: no room */
    assert_int_equal(io.nrec, 3);
    assert_int_equal(io.dropped, 1);
    assert_int_equal(io.rec[0].mask, 0x4);
    assert_int_equal(io.rec[1].mask, 0x3);
    assert_int_equal(io.rec[1].levels, 0x1);
    assert_int_equal(io.rec[1].planned_ns, t0 + 5);
    assert_int_equal(io.levels, 0x0); /* the shadow follows even when the record is full */
    char buf[512];
    FILE *f = fmemopen(buf, sizeof buf, "w");
    assert_non_null(f);
    assert_int_equal(cs_gpio_io_write_record(&io, f, t0, "k=v"), 0);
    fclose(f);
    char want[256];
    snprintf(want, sizeof want,
             "# curvestep gpio record k=v\nt_ns,planned_ns,line,level\n%lld,0,enable,1\n"
             "%lld,5,x_step,1\n%lld,5,x_dir,0\n%lld,9,x_step,0\n",
             (long long)(t1 - t0), (long long)(t3 - t0), (long long)(t3 - t0),
             (long long)(t4 - t0));
    assert_string_equal(buf, want);
    cs_gpio_io_close(&io);
    cs_gpio_io_free(&io);
}

/* A chip that is not there: -1 and a message that names it and says what to check. */
static void test_missing_chip(void **state)
{
    (void)state;
    cs_gpio_lines_t l;
    memset(&l, 0, sizeof l);
    l.n = 1;
    strcpy(l.name[0], "x_step");
    cs_gpio_io_t io;
    char err[640];
    const char *names[] = {"gpiochip987", "/dev/gpiochip987", "987", "no-such-label"};
    for (unsigned k = 0; k < 4; k++) {
        assert_int_equal(cs_gpio_io_open_chip(&io, names[k], &l, err, sizeof err), -1);
        assert_non_null(strstr(err, names[k]));
        assert_non_null(strstr(err, "/dev/gpiochip"));
        assert_non_null(strstr(err, "label"));
        assert_non_null(strstr(err, "gpio group"));
    }
    assert_non_null(strstr(err, "cannot open GPIO chip no-such-label"));
}

/* The histogram quantiles: upper bounds within a factor of 2, never above the max. */
/* One run with the recorder's simulated inputs: the outcome, the trip, the steps on the lines. */
static void run_inputs(const cs_machine_t *m, const cs_ctlcfg_t *ctl, const char *estop,
                       const double (*pts)[4], size_t npts, int32_t start_x, uint16_t watch,
                       cs_gpio_run_t *r, cs_gpio_io_t *io)
{
    cs_gpio_cfg_t cfg;
    cs_gpio_cfg_default(&cfg, m);
    cs_motion_t mo;
    plan(m, pts, npts, 80, &mo);
    static cs_gpio_in_t in;
    cs_gpio_in_open_sim(&in, m, ctl, NULL, estop);
    memset(&g_in_opts, 0, sizeof g_in_opts);
    g_in_opts.in = &in;
    g_in_opts.watch = watch;
    g_in_opts.hard_limits = true;
    g_in_opts.start_pos[0] = start_x;
    run_job(m, &cfg, mo.segs.v, mo.segs.n, 0, false, 0, 0, io, r);
    memset(&g_in_opts, 0, sizeof g_in_opts);
    cs_motion_free(&mo);
}

/* x rises in the record (every one counted, so a step after the trip would show). */
static uint64_t x_rises(const cs_gpio_io_t *io)
{
    uint64_t n = 0;
    for (size_t k = 0; k < io->nrec; k++)
        if ((io->rec[k].mask & 1u) && (io->rec[k].levels & 1u)) /* line 0: x_step */
            n++;
    return n;
}

/* Inputs on the step thread: a max switch at 12.5 mm (80 steps/mm: active from step 1000 on)
 * stops a 30 mm move on exactly its 1000th step with ALARM:1 and the x max bit; started 900
 * steps along, on the 100th; the probe surface at z = -2 mm (the watched input) stops a move
 * down on step 160 with no alarm code; an e-stop pressed before the start: no step at all. */
static void test_inputs_trip(void **state)
{
    (void)state;
    cs_machine_t m;
    cs_machine_ini_default(&m);
    cs_ctlcfg_t ctl;
    cs_ctlcfg_default(&ctl);
    ctl.has_max[0] = true;
    ctl.max_mm[0] = 12.5;
    ctl.has_probe = true;
    ctl.probe_z = -2;
    static const double x30[][4] = {{30, 0, 0, 0}};
    static const double zdown[][4] = {{0, 0, -5, 0}};
    cs_gpio_run_t r;
    cs_gpio_io_t io;
    run_inputs(&m, &ctl, NULL, x30, 1, 0, 0, &r, &io);
    assert_int_equal(r.outcome, CS_GPIO_RUN_TRIPPED);
    assert_int_equal(r.trip_code, CS_PROTO_ALARM_HARD_LIMIT);
    assert_int_equal(r.trip_inputs, CS_PROTO_IN_MAX(0));
    assert_int_equal(r.pos[0], 1000);
    assert_int_equal(x_rises(&io), 1000);
    cs_gpio_io_free(&io);
    run_inputs(&m, &ctl, NULL, x30, 1, 900, 0, &r, &io);
    assert_int_equal(r.outcome, CS_GPIO_RUN_TRIPPED);
    assert_int_equal(r.pos[0], 100);
    assert_int_equal(x_rises(&io), 100);
    cs_gpio_io_free(&io);
    run_inputs(&m, &ctl, NULL, zdown, 1, 0, CS_PROTO_IN_PROBE, &r, &io);
    assert_int_equal(r.outcome, CS_GPIO_RUN_TRIPPED);
    assert_int_equal(r.trip_code, 0);
    assert_int_equal(r.pos[2], -160);
    cs_gpio_io_free(&io);
    char estop[] = "/tmp/cs_test_gpio_estopXXXXXX";
    int fd = mkstemp(estop);
    assert_true(fd >= 0);
    run_inputs(&m, &ctl, estop, x30, 1, 0, 0, &r, &io);
    assert_int_equal(r.outcome, CS_GPIO_RUN_TRIPPED);
    assert_int_equal(r.trip_code, CS_PROTO_ALARM_ESTOP);
    assert_int_equal(r.pos[0], 0);
    assert_int_equal(x_rises(&io), 0);
    cs_gpio_io_free(&io);
    unlink(estop);
}

static void test_late_quantile(void **state)
{
    (void)state;
    cs_gpio_run_t r;
    memset(&r, 0, sizeof r);
    r.late_hist[0] = 90; /* < 1 us */
    r.late_hist[3] = 9;  /* [4, 8) us */
    r.late_hist[7] = 1;  /* [64, 128) us */
    r.rises = 100;
    r.late_max_ns = 100000;
    assert_int_equal(cs_gpio_run_late_quantile(&r, 0.5), 1000);
    assert_int_equal(cs_gpio_run_late_quantile(&r, 0.99), 8000);
    assert_int_equal(cs_gpio_run_late_quantile(&r, 1.0), 100000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_recorder),
        cmocka_unit_test(test_missing_chip),
        cmocka_unit_test(test_late_quantile),
        cmocka_unit_test(test_inputs_trip),
        cmocka_unit_test(test_thread_matches_simulator),
        cmocka_unit_test(test_thread_4_axes_inverted_long_setup),
        cmocka_unit_test(test_hold_stops_at_a_segment_end),
        cmocka_unit_test(test_stop_at_once),
        cmocka_unit_test(test_resume),
        cmocka_unit_test(test_pause_and_resume),
        cmocka_unit_test(test_bad_segment),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
