/* bench_motion: throughput of the motion core on the host -- planner blocks per second (queue,
 * junction, reverse/forward passes with the ring full), step segments per second (cutting the
 * planned blocks) and executor DDA calls per second -- for the trapezoid and S-curve profiles,
 * on a job of short chords (a spiral flattened at 0.01 mm) and long random lines.
 * Writes argv[1] (CSV) and prints a Markdown section. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "bench_args.h"
#include "cs_machine_ini.h"
#include "cs_planner.h"
#include "cs_segment.h"
#include "cs_stepper.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

typedef struct {
    const char *job, *profile;
    size_t blocks, segments;
    double plan_s, seg_s;
    double calls, exec_s;
} result_t;

/* Targets of the job (mm): spiral chords or random lines. */
static size_t make_job(int kind, double (*p)[2], size_t cap)
{
    size_t n = 0;
    if (kind == 0) {
        double a = 0;
        while (n < cap) {
            double r = 5 + a * 0.5;
            double chord = sqrt(8 * r * 0.01);
            p[n][0] = r * cos(a);
            p[n][1] = r * sin(a);
            n++;
            a += chord / r;
        }
    } else {
        uint32_t s = 2463534242u;
        for (; n < cap; n++) {
            s ^= s << 13, s ^= s >> 17, s ^= s << 5;
            p[n][0] = (s % 160000) / 100.0 - 800;
            s ^= s << 13, s ^= s >> 17, s ^= s << 5;
            p[n][1] = (s % 160000) / 100.0 - 800;
        }
    }
    return n;
}

static void run(const cs_machine_t *m, double (*p)[2], size_t n, result_t *r)
{
    static cs_planner_t pl;
    static cs_segment_gen_t g;
    static cs_stepper_t st;
    int32_t feed = 150 * 65536;
    /* 1. Planner alone: queue every block, retire the oldest when the ring is full. */
    cs_planner_init(&pl, m);
    double t0 = now();
    for (size_t k = 0; k < n; k++) {
        if (cs_planner_full(&pl)) {
            cs_planner_begin_head(&pl);
            cs_planner_end_head(&pl);
        }
        cs_pos_t t[CS_AXES] = {(cs_pos_t)lround(p[k][0] * 65536), (cs_pos_t)lround(p[k][1] * 65536),
                               0, 0};
        cs_planner_line(&pl, t, feed, 1);
    }
    r->plan_s = now() - t0;
    r->blocks = n;
    /* 2. Planner and segments; segments timed apart from the planner. */
    cs_planner_init(&pl, m);
    cs_segment_init(&g, m);
    cs_stepper_init(&st, m);
    cs_segment_t s;
    size_t segs = 0;
    double seg_time = 0, exec_time = 0, calls = 0;
    for (size_t k = 0; k <= n; k++) {
        while (cs_planner_full(&pl) || (k == n && cs_planner_count(&pl) > 0)) {
            double a = now();
            do {
                cs_segment_next(&g, &pl, &s);
                segs++;
                /* 3. Executor: run every DDA call of the segment. */
                double b = now();
                seg_time += b - a;
                cs_stepper_push(&st, &s);
                cs_stepper_out_t o;
                do {
                    cs_stepper_tick(&st, &o);
                    calls++;
                } while (o.next_ticks != 0 && !(st.head == st.tail && !st.running));
                a = now();
                exec_time += a - b;
            } while (!cs_segment_block_end(&g));
        }
        if (k < n) {
            cs_pos_t t[CS_AXES] = {(cs_pos_t)lround(p[k][0] * 65536),
                                   (cs_pos_t)lround(p[k][1] * 65536), 0, 0};
            cs_planner_line(&pl, t, feed, 1);
        }
    }
    r->segments = segs;
    r->seg_s = seg_time;
    r->calls = calls;
    r->exec_s = exec_time;
}

int main(int argc, char **argv)
{
    static const char usage[] = "usage: bench_motion [OUT.csv]\n"
        "Planner and step-segment throughput and job times, trapezoid and S-curve; a\n"
        "Markdown section on stdout, the figures in OUT.csv.\n";
    int usage_rc = bench_args_check(argc, argv, usage, 1);
    if (usage_rc >= 0)
        return usage_rc;
    enum { N = 50000 };
    static double p[N][2];
    result_t res[4];
    int k = 0;
    for (int job = 0; job < 2; job++) {
        size_t n = make_job(job, p, job == 0 ? N : N / 10);
        for (int prof = 0; prof < 2; prof++, k++) {
            cs_machine_t m;
            cs_machine_ini_default(&m);
            m.profile = prof ? CS_PROFILE_SCURVE : CS_PROFILE_TRAPEZOID;
            res[k].job = job == 0 ? "spiral, 0.01 mm chords" : "random long lines";
            res[k].profile = prof ? "S-curve" : "trapezoid";
            run(&m, p, n, &res[k]);
        }
    }
    FILE *f = argc > 1 ? fopen(argv[1], "w") : NULL;
    if (f)
        fprintf(f, "job,profile,blocks,blocks_per_s,segments,segments_per_s,dda_calls_per_s\n");
    printf("## Motion: planner, step segments, executor (bench_motion)\n\n");
    printf(
        "Default plotter machine (80 steps/mm, 1000 mm/s^2, 100 kHz ticks, 5 ms segments), feed\n"
        "150 mm/s, look-ahead ring of %d blocks kept full. Planner = queue one block and replan\n"
        "the ring; segments = cut the planned blocks into segments; executor = every DDA call\n"
        "(cs_stepper_tick) of those segments.\n\n",
        CS_PLANNER_RING);
    printf("| job | profile | blocks | planner blocks/s | segments | segments/s | DDA calls/s |\n");
    printf("|---|---|---:|---:|---:|---:|---:|\n");
    for (int i = 0; i < k; i++) {
        printf("| %s | %s | %zu | %.0f | %zu | %.0f | %.0f |\n", res[i].job, res[i].profile,
               res[i].blocks, res[i].blocks / res[i].plan_s, res[i].segments,
               res[i].segments / res[i].seg_s, res[i].calls / res[i].exec_s);
        if (f)
            fprintf(f, "\"%s\",%s,%zu,%.0f,%zu,%.0f,%.0f\n", res[i].job, res[i].profile,
                    res[i].blocks, res[i].blocks / res[i].plan_s, res[i].segments,
                    res[i].segments / res[i].seg_s, res[i].calls / res[i].exec_s);
    }
    if (f)
        fclose(f);
    return 0;
}
