/* bench_merge: line merging and travel sorting (cs_order) of 100,000 random subpaths, the
 * everyday plotter job of issue 16 (goal: merge + sort in under 2 s on this machine). The
 * drawing: short polylines (1 to 3 lines, up to 5 mm each) scattered over a 1000 x 700 mm sheet,
 * a third of them starting where the previous one ended (chains the merge joins), from a fixed
 * seed. Timed on CLOCK_PROCESS_CPUTIME_ID (CPU time: the machine is shared, wall time
 * measures the neighbours), best of 3 runs (each on a fresh copy). Writes argv[1] (CSV)
 * and prints a Markdown section. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_args.h"
#include "cs_conv.h"
#include "cs_order.h"
#include "ref_xorshift32.h"

#define SUBPATHS 100000
#define RUNS     3
#define GOAL_S   2.0

static ref_xorshift32_t rng; /* the tests' one generator (tests/support) */

static double urand(double lo, double hi)
{
    return ref_xorshift32_uniform(&rng, lo, hi);
}

static int add_line(cs_path_t *p, double x0, double y0, double x1, double y1, int new_sub)
{
    cs_vec3_t v[2];
    cs_bezier_t c;
    cs_path_loc_t loc = {"bench", 1, 1};
    if (cs_conv_mm_to_vec(x0, y0, 0, &v[0]) != CS_OK ||
        cs_conv_mm_to_vec(x1, y1, 0, &v[1]) != CS_OK || cs_bezier_init(&c, 1, v) != CS_OK)
        return -1;
    if (new_sub)
        cs_path_new_subpath(p);
    return cs_path_add(p, &c, CS_PATH_LINE, loc) == CS_OK ? 0 : -1;
}

static void drawing(cs_path_t *p)
{
    cs_path_init(p);
    rng.s = 0x9E3779B9u;
    double lx = 0, ly = 0;
    for (size_t i = 0; i < SUBPATHS; i++) {
        int chain = i > 0 && urand(0, 1) < 1.0 / 3.0;
        double x = chain ? lx : urand(0, 1000), y = chain ? ly : urand(0, 700);
        unsigned k = 1 + (unsigned)urand(0, 3);
        for (unsigned j = 0; j < k; j++) {
            double nx = x + urand(-5, 5), ny = y + urand(-5, 5);
            if (add_line(p, x, y, nx, ny, j == 0) != 0) {
                fprintf(stderr, "bench_merge: cannot build the drawing\n");
                exit(1);
            }
            x = nx;
            y = ny;
        }
        lx = x;
        ly = y;
    }
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* Best time of RUNS runs of o on fresh copies; the stats of the last. */
static double timed(const cs_order_opts_t *o, cs_order_stats_t *st, size_t *elems)
{
    double best = 1e9;
    for (int r = 0; r < RUNS; r++) {
        cs_path_t p;
        drawing(&p);
        *elems = p.n;
        double t0 = now_s();
        if (cs_order_apply(&p, o, st) != CS_OK) {
            fprintf(stderr, "bench_merge: out of memory\n");
            exit(1);
        }
        double t = now_s() - t0;
        best = t < best ? t : best;
        cs_path_free(&p);
    }
    return best;
}

int main(int argc, char **argv)
{
    static const char usage[] = "usage: bench_merge [OUT.csv]\n"
        "Merge and sort (cs_order) of 100,000 random subpaths: time, pen lifts and pen-up\n"
        "travel before and after; a Markdown section on stdout, the figures in OUT.csv.\n";
    int usage_rc = bench_args_check(argc, argv, usage, 1);
    if (usage_rc >= 0)
        return usage_rc;
    static const struct {
        const char *what;
        int merge, sort;
    } cases[] = {{"merge", 1, 0}, {"sort", 0, 1}, {"**merge + sort**", 1, 1}};
    FILE *csv = argc > 1 ? fopen(argv[1], "w") : NULL;
    if (csv)
        fprintf(csv, "case,subpaths,elements,seconds,lifts_before,lifts_after,travel_before_mm,"
                     "travel_after_mm\n");
    printf("## Merge and sort (cs_order)\n\n");
    printf("tests/bench/bench_merge.c: %d random subpaths (1 to 3 lines of up to 5 mm, a third\n"
           "chained end to start) on a 1000 x 700 mm sheet; `--merge` / `--sort` as the commands\n"
           "run them (tolerance 0.01 mm); CPU time of the process, best of %d runs.\n\n",
           SUBPATHS, RUNS);
    printf("| case | time s | pen lifts before | after | pen-up travel before mm | after mm |\n");
    printf("|---|---:|---:|---:|---:|---:|\n");
    double both = 0;
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        cs_order_opts_t o = {cases[k].merge != 0, cases[k].sort != 0, 0.01};
        cs_order_stats_t st;
        size_t elems = 0;
        double t = timed(&o, &st, &elems);
        both = t;
        printf("| %s | %.3f | %zu | %zu | %.0f | %.0f |\n", cases[k].what, t, st.lifts_before,
               st.lifts_after, st.travel_before_mm, st.travel_after_mm);
        if (csv)
            fprintf(csv, "%s,%d,%zu,%.6f,%zu,%zu,%.3f,%.3f\n", cases[k].what, SUBPATHS, elems, t,
                    st.lifts_before, st.lifts_after, st.travel_before_mm, st.travel_after_mm);
    }
    printf("\nGoal: merge + sort of 100,000 subpaths under %.0f s: **%.3f s, %s**.\n", GOAL_S, both,
           both < GOAL_S ? "met" : "NOT met");
    if (csv)
        fclose(csv);
    return 0;
}
