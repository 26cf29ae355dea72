/* Tests of cs_stepper on the POSIX port: the DDA makes exactly the steps of each segment, evenly
 * spread (each step within one call period after the ideal half-step crossing), the ring's full
 * and invalid cases, DIR inversion; and end to end (planner -> segments -> executor -> edges) on
 * random jobs and a flattened circle: final position exact, no axis over its rate or
 * acceleration, executed path within tolerance + one step of the exact geometry (double). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdlib.h>

#include "cs_machine_ini.h"
#include "cs_motion.h"
#include "cs_sim.h"
#include "cs_stepper.h"
#include "cs_trace.h"
#include "port_posix.h"
#include "ref_xorshift32.h"

#define Q16 65536.0

static cs_machine_t machine;

static int setup(void **state)
{
    (void)state;
    cs_machine_ini_default(&machine);
    return 0;
}

static ref_xorshift32_t rng;

static void test_ring_full_and_invalid(void **state)
{
    (void)state;
    cs_stepper_t st;
    assert_int_equal(cs_stepper_init(&st, &machine), CS_OK);
    cs_segment_t s = {100, {10, -5, 0, 0}};
    for (int i = 0; i < CS_STEPPER_RING; i++)
        assert_int_equal(cs_stepper_push(&st, &s), CS_OK);
    assert_int_equal(cs_stepper_free(&st), 0);
    assert_int_equal(cs_stepper_push(&st, &s), CS_ERR_FULL);
    cs_stepper_t st2;
    assert_int_equal(cs_stepper_init(&st2, &machine), CS_OK);
    cs_segment_t bad = {10, {11, 0, 0, 0}};
    assert_int_equal(cs_stepper_push(&st2, &bad), CS_ERR_ARG);
    cs_segment_t zero = {0, {0, 0, 0, 0}};
    assert_int_equal(cs_stepper_push(&st2, &zero), CS_ERR_ARG);
    cs_segment_t a_axis = {10, {0, 0, 0, 1}}; /* no a axis on a 3-axis machine */
    assert_int_equal(cs_stepper_push(&st2, &a_axis), CS_ERR_ARG);
    assert_true(cs_stepper_idle(&st2));
}

/* Runs segments on a fresh executor, returns the execution record. */
static void run(const cs_machine_t *m, const cs_segment_t *s, size_t n, cs_sim_exec_t *ex)
{
    assert_int_equal(cs_sim_execute(m, s, n, ex), CS_OK);
}

static void test_dda_exact_and_even(void **state)
{
    (void)state;
    rng.s = 777;
    enum { N = 300 };
    cs_segment_t segs[N];
    int64_t total[CS_AXES] = {0, 0, 0, 0};
    for (int k = 0; k < N; k++) {
        uint32_t ticks = 1 + ref_xorshift32_next(&rng) % 2000;
        segs[k].ticks = ticks;
        for (unsigned i = 0; i < CS_AXES; i++) {
            int32_t mag = i < 3 ? (int32_t)(ref_xorshift32_next(&rng) % (ticks + 1)) : 0;
            if (ref_xorshift32_next(&rng) % 4 == 0)
                mag = 0;
            segs[k].steps[i] = (ref_xorshift32_next(&rng) & 1) ? -mag : mag;
            total[i] += segs[k].steps[i];
        }
    }
    cs_sim_exec_t ex;
    run(&machine, segs, N, &ex);
    for (unsigned i = 0; i < 3; i++) {
        assert_int_equal(ex.pos[i], total[i]);
        assert_int_equal(ex.exec_pos[i], total[i]);
    }
    /* Per segment: edges inside [start, end] are exactly |steps| per axis, in its direction,
     * and the k-th one comes no earlier than the ideal crossing of k - 1/2 steps and at most one
     * DDA call period (ticks / C, C >= |steps|) after it. */
    uint64_t t0 = 1; /* the port wakes the timer one tick after the first push */
    size_t e = 0;
    for (int k = 0; k < N; k++) {
        uint64_t T = segs[k].ticks;
        int64_t cnt[CS_AXES] = {0, 0, 0, 0};
        uint32_t most = 0;
        for (unsigned i = 0; i < 3; i++)
            most = (uint32_t)fmax(most, abs(segs[k].steps[i]));
        double call = most ? (double)T / most : (double)T;
        while (e < ex.n && ex.edges[e].t <= t0 + T) {
            const port_posix_edge_t *ed = &ex.edges[e];
            unsigned i = ed->axis;
            int32_t n = segs[k].steps[i];
            assert_int_equal(ed->dir, n > 0 ? 1 : -1);
            cnt[i]++;
            double ideal = t0 + (cnt[i] - 0.5) * (double)T / abs(n);
            assert_true((double)ed->t >= ideal - 1e-9);
            assert_true((double)ed->t <= ideal + call + 1.0);
            e++;
        }
        for (unsigned i = 0; i < 3; i++)
            assert_int_equal(cnt[i], abs(segs[k].steps[i]));
        t0 += T;
    }
    assert_int_equal(e, ex.n);
    assert_int_equal(ex.end_tick, t0);
    cs_sim_exec_free(&ex);
}

static void test_amass_oversamples_slow_segments(void **state)
{
    (void)state;
    /* 3 steps of x and 2 of y in 2000 ticks: C = 3 * 8 calls, so y's steps land within
     * 2000 / 24 ticks of their ideal times instead of 2000 / 3. */
    cs_segment_t s = {2000, {3, 2, 0, 0}};
    cs_sim_exec_t ex;
    run(&machine, &s, 1, &ex);
    int cnt = 0;
    for (size_t e = 0; e < ex.n; e++) {
        if (ex.edges[e].axis != 1)
            continue;
        cnt++;
        double ideal = 1 + (cnt - 0.5) * 1000.0;
        assert_true(ex.edges[e].t >= ideal && ex.edges[e].t <= ideal + 2000.0 / 24 + 1);
    }
    assert_int_equal(cnt, 2);
    cs_sim_exec_free(&ex);
}

static void test_dir_inversion(void **state)
{
    (void)state;
    cs_machine_t m = machine;
    m.axis[0].invert_dir = true;
    cs_segment_t s[2] = {{100, {-7, 5, 0, 0}}, {100, {9, -3, 0, 0}}};
    cs_sim_exec_t ex;
    run(&m, s, 2, &ex);
    assert_int_equal(ex.pos[0], 2);
    assert_int_equal(ex.pos[1], 2);
    cs_sim_exec_free(&ex);
    /* What the executor drives on the DIR lines: x inverted. */
    cs_stepper_t st;
    cs_stepper_out_t o;
    assert_int_equal(cs_stepper_init(&st, &m), CS_OK);
    assert_int_equal(cs_stepper_push(&st, &s[0]), CS_OK);
    cs_stepper_tick(&st, &o);
    assert_int_equal(o.dir_mask & 3, 1 | 2); /* x negative but inverted: high; y positive: high */
}

/* End to end: plan, cut, execute, measure. */
typedef struct {
    double dev, tol_step;
    bool dyn_ok;
} e2e_t;

static void plan_exec_check(const cs_machine_t *m, cs_motion_t *mo, const cs_sim_ref_t *ref,
                            const double final_mm[3], e2e_t *r)
{
    assert_int_equal(cs_motion_finish(mo), CS_OK);
    cs_sim_exec_t ex;
    run(m, mo->segs.v, mo->segs.n, &ex);
    for (unsigned i = 0; i < 3; i++) {
        double spm = m->axis[i].steps_per_mm / Q16;
        double tgt = lround(final_mm[i] * Q16) / Q16;
        assert_int_equal(ex.pos[i], llround(tgt * spm));
    }
    cs_sim_dyn_t dyn;
    cs_sim_dynamics(m, &ex, 0.05, &dyn);
    r->dyn_ok = true;
    for (unsigned i = 0; i < m->n_axes; i++) {
        if (!dyn.rate_ok[i] || !dyn.accel_ok[i]) {
            print_message("axis %u: rate %.3f (t=%.3f) accel %.3f (t=%.3f)\n", i, dyn.peak_rate[i],
                          dyn.t_rate[i], dyn.peak_accel[i], dyn.t_accel[i]);
            r->dyn_ok = false;
        }
    }
    r->dev = ref ? cs_sim_deviation(m, &ex, ref, NULL) : 0;
    r->tol_step = m->tolerance / Q16 + cs_sim_step_mm(m);
    cs_sim_exec_free(&ex);
}

static void test_random_jobs_end_to_end(void **state)
{
    (void)state;
    rng.s = 4242;
    for (int job = 0; job < 6; job++) {
        cs_motion_t mo;
        assert_int_equal(cs_motion_init(&mo, &machine), CS_OK);
        cs_sim_ref_t ref;
        cs_sim_ref_init(&ref);
        double p[3] = {0, 0, 0};
        assert_int_equal(cs_sim_ref_move(&ref, p), CS_OK);
        for (int k = 0; k < 150; k++) {
            double len = ref_xorshift32_uniform(&rng, 0.05, 40),
                   ang = ref_xorshift32_uniform(&rng, -M_PI, M_PI);
            if (k % 5)
                ang = sin(0.1 * k) * 0.5; /* gentle turns */
            p[0] = fmin(fmax(p[0] + len * cos(ang), -990), 990);
            p[1] = fmin(fmax(p[1] + len * sin(ang), -990), 990);
            p[2] = fmin(fmax(p[2] + ref_xorshift32_uniform(&rng, -0.2, 0.2), -99), 99);
            assert_int_equal(
                cs_motion_line_mm(&mo, p[0], p[1], p[2], ref_xorshift32_uniform(&rng, 10, 300), 1),
                CS_OK);
            double q[3] = {lround(p[0] * Q16) / Q16, lround(p[1] * Q16) / Q16,
                           lround(p[2] * Q16) / Q16};
            assert_int_equal(cs_sim_ref_line(&ref, q), CS_OK);
        }
        e2e_t r;
        plan_exec_check(&machine, &mo, &ref, p, &r);
        assert_true(r.dyn_ok);
        /* Straight chords: per axis, every segment end is the chord's point rounded (within 1/2
         * step) and the DDA stays within 1/2 step of the line between two segment ends: at most
         * one step per axis from the chord. */
        print_message("job %d: deviation %.5f mm (one step %.5f)\n", job, r.dev,
                      cs_sim_step_mm(&machine));
        assert_true(r.dev <= cs_sim_step_mm(&machine));
        cs_sim_ref_free(&ref);
        cs_motion_free(&mo);
    }
}

static void test_flattened_circle_end_to_end(void **state)
{
    (void)state;
    /* A circle of radius 20 mm flattened in double within the tolerance, three turns at a feed
     * above what its curvature allows: within limits, within tol + 1 step of the exact circle. */
    cs_motion_t mo;
    assert_int_equal(cs_motion_init(&mo, &machine), CS_OK);
    double R = 20, tol = machine.tolerance / Q16;
    int n = (int)ceil(M_PI / acos(1 - tol / R));
    cs_sim_ref_t ref;
    cs_sim_ref_init(&ref);
    double p[3] = {0, 0, 0};
    assert_int_equal(cs_sim_ref_move(&ref, p), CS_OK);
    p[0] = R;
    assert_int_equal(cs_motion_line_mm(&mo, R, 0, 0, 0, 1), CS_OK);
    assert_int_equal(cs_sim_ref_line(&ref, p), CS_OK);
    /* The exact circle, sampled at 0.001 rad. */
    for (int k = 0; k <= 6283; k++) {
        double q[3] = {R * cos(k * 0.001), R * sin(k * 0.001), 0};
        assert_int_equal(cs_sim_ref_line(&ref, q), CS_OK);
    }
    for (int turn = 0; turn < 3; turn++)
        for (int k = 1; k <= n; k++) {
            double t = 2 * M_PI * k / n;
            p[0] = R * cos(t);
            p[1] = R * sin(t);
            assert_int_equal(cs_motion_line_mm(&mo, p[0], p[1], 0, 150, 2), CS_OK);
        }
    uint64_t blocks = mo.blocks;
    e2e_t r;
    plan_exec_check(&machine, &mo, &ref, p, &r);
    assert_true(r.dyn_ok);
    assert_true(r.dev <= r.tol_step);
    /* Curvature speed sqrt(0.51 a R) = 101 mm/s: three turns (377 mm) take 3.73 s, plus the
     * 20 mm rapid to the start and the ramps (0.3 s). (Grbl's junction deviation at 0.01 mm
     * would take these vertices at 142 mm/s: a centripetal 1000 mm/s^2, the whole budget.) */
    double t = (double)mo.ticks / machine.tick_hz;
    print_message("circle: %llu blocks, %.3f s, deviation %.4f mm\n", (unsigned long long)blocks, t,
                  r.dev);
    assert_true(t < 1.03 * (3 * 2 * M_PI * R / sqrt(0.51 * 1000 * R)) + 0.3);
    cs_sim_ref_free(&ref);
    cs_motion_free(&mo);
}

static void test_random_curves_end_to_end(void **state)
{
    (void)state;
    /* Random cubic Beziers (some chained smoothly, some with jumps between them = travel moves),
     * traced by cs_trace within the machine tolerance and planned by cs_motion_plan_path:
     * executed path within tolerance + one step of the exact curves (double), limits kept,
     * final position exact. */
    rng.s = 31337;
    for (int job = 0; job < 4; job++) {
        cs_path_t path;
        cs_path_init(&path);
        double x = ref_xorshift32_uniform(&rng, -200, 200),
               y = ref_xorshift32_uniform(&rng, -200, 200);
        for (int k = 0; k < 12; k++) {
            double pts[4][2];
            if (k % 4 == 0) {
                x = ref_xorshift32_uniform(&rng, -300, 300);
                y = ref_xorshift32_uniform(&rng, -300, 300);
            }
            pts[0][0] = x;
            pts[0][1] = y;
            for (int i = 1; i < 4; i++) {
                pts[i][0] =
                    fmin(fmax(pts[i - 1][0] + ref_xorshift32_uniform(&rng, -40, 40), -900), 900);
                pts[i][1] =
                    fmin(fmax(pts[i - 1][1] + ref_xorshift32_uniform(&rng, -40, 40), -900), 900);
            }
            cs_vec3_t cp[4];
            for (int i = 0; i < 4; i++)
                cp[i] = (cs_vec3_t){(cs_pos_t)lround(pts[i][0] * Q16),
                                    (cs_pos_t)lround(pts[i][1] * Q16), 0};
            cs_bezier_t c;
            assert_int_equal(cs_bezier_init(&c, 3, cp), CS_OK);
            cs_path_loc_t loc = {"random", (unsigned)k + 1, 1};
            assert_int_equal(cs_path_add(&path, &c, CS_PATH_CUBIC, loc), CS_OK);
            x = cp[3].x / Q16;
            y = cp[3].y / Q16;
        }
        cs_motion_t mo;
        assert_int_equal(cs_motion_init(&mo, &machine), CS_OK);
        cs_path_diag_t diag;
        cs_err_t e =
            cs_motion_plan_path(&mo, &path, machine.tolerance, CS_TRACE_SUBDIV,
                                cs_motion_speed(ref_xorshift32_uniform(&rng, 20, 200)), &diag);
        if (e != CS_OK)
            cs_path_diag_print(stderr, &diag);
        assert_int_equal(e, CS_OK);
        cs_sim_ref_t ref;
        cs_sim_ref_init(&ref);
        double end[3];
        assert_int_equal(cs_sim_ref_from_path(&ref, &path, end), CS_OK);
        e2e_t r;
        plan_exec_check(&machine, &mo, &ref, end, &r);
        print_message("curves %d: %zu blocks, deviation %.5f mm (bound %.5f)\n", job, mo.blocks,
                      r.dev, r.tol_step);
        assert_true(r.dyn_ok);
        assert_true(r.dev <= r.tol_step);
        cs_sim_ref_free(&ref);
        cs_motion_free(&mo);
        cs_path_free(&path);
    }
}

static void test_starved_streaming_keeps_limits(void **state)
{
    (void)state;
    /* Firmware-style streaming: a new move arrives only every few segments, so the queue runs
     * nearly empty and blocks start executing with one or two behind them (frozen entries,
     * junctions after the executing block). Limits kept, final position exact. */
    rng.s = 99;
    cs_planner_t pl;
    cs_segment_gen_t g;
    assert_int_equal(cs_planner_init(&pl, &machine), CS_OK);
    assert_int_equal(cs_segment_init(&g, &machine), CS_OK);
    size_t cap = 200000, n = 0;
    cs_segment_t *segs = malloc(cap * sizeof *segs);
    assert_non_null(segs);
    double x = 0, y = 0;
    for (int k = 0; k < 300; k++) {
        double len = ref_xorshift32_uniform(&rng, 0.2, 20),
               ang = k % 3 ? 0.3 * sin(0.4 * k) : ref_xorshift32_uniform(&rng, -M_PI, M_PI);
        x = fmin(fmax(x + len * cos(ang), -900), 900);
        y = fmin(fmax(y + len * sin(ang), -900), 900);
        cs_pos_t t[CS_AXES] = {(cs_pos_t)lround(x * Q16), (cs_pos_t)lround(y * Q16), 0, 0};
        while (cs_planner_full(&pl) && n < cap) {
            assert_int_equal(cs_segment_next(&g, &pl, &segs[n]), CS_OK);
            n++;
        }
        assert_int_equal(
            cs_planner_line(&pl, t, (int32_t)lround(ref_xorshift32_uniform(&rng, 20, 200) * Q16),
                            1),
            CS_OK);
        /* Cut until only one or two blocks remain queued (the executing one included), and
         * stop in the middle of a block half of the time. */
        unsigned keep = 1 + (unsigned)(ref_xorshift32_next(&rng) % 2);
        while (cs_planner_count(&pl) > keep && n < cap) {
            assert_int_equal(cs_segment_next(&g, &pl, &segs[n]), CS_OK);
            n++;
        }
        for (int c = (int)(ref_xorshift32_next(&rng) % 8); c > 0 && n < cap; c--) {
            cs_err_t e = cs_segment_next(&g, &pl, &segs[n]);
            if (e == CS_ERR_EMPTY)
                break;
            assert_int_equal(e, CS_OK);
            n++;
        }
    }
    while (n < cap && cs_segment_next(&g, &pl, &segs[n]) == CS_OK)
        n++;
    assert_true(n < cap);
    cs_sim_exec_t ex;
    run(&machine, segs, n, &ex);
    assert_int_equal(ex.pos[0], llround(lround(x * Q16) / Q16 * 80));
    assert_int_equal(ex.pos[1], llround(lround(y * Q16) / Q16 * 80));
    cs_sim_dyn_t dyn;
    cs_sim_dynamics(&machine, &ex, 0.05, &dyn);
    for (unsigned i = 0; i < 3; i++) {
        if (!dyn.rate_ok[i] || !dyn.accel_ok[i])
            print_message("axis %u: rate %.3f accel %.3f at %.3f s\n", i, dyn.peak_rate[i],
                          dyn.peak_accel[i], dyn.t_accel[i]);
        assert_true(dyn.rate_ok[i] && dyn.accel_ok[i]);
    }
    cs_sim_exec_free(&ex);
    free(segs);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_ring_full_and_invalid, setup),
        cmocka_unit_test_setup(test_dda_exact_and_even, setup),
        cmocka_unit_test_setup(test_amass_oversamples_slow_segments, setup),
        cmocka_unit_test_setup(test_dir_inversion, setup),
        cmocka_unit_test_setup(test_random_jobs_end_to_end, setup),
        cmocka_unit_test_setup(test_flattened_circle_end_to_end, setup),
        cmocka_unit_test_setup(test_random_curves_end_to_end, setup),
        cmocka_unit_test_setup(test_starved_streaming_keeps_limits, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
