/* bench_flatten: chords per curve, accuracy and speed of every tracing method against the greedy
 * reference (cs_ref_greedy_count: from each vertex the longest chord within tol, in double).
 * Curve sets: 200 random cubics (xorshift, fixed seed, 100 mm box), the hard cases of
 * test_trace, and every curved element of the SVG files in ../shared/data/svg (user unit =
 * 1 mm). Tolerances 0.1, 0.01, 0.001 mm. Usage: bench_flatten [out.csv] [svg files...] (no
 * files: every .svg one folder below ../shared/data/svg, else tests/data/svg); prints a Markdown
 * section on stdout, progress on stderr. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_args.h"
#include "bench_curves.h"
#include "cs_ref.h"
#include "cs_svgdoc.h"
#include "cs_trace.h"

#define MAX_VERTS 400000
#define N_TOLS    3
#define N_METH    5

static const double tols_mm[N_TOLS] = {0.1, 0.01, 0.001};
static const char *meth_name[N_METH] = {"FD (uniform, Wang)", "AFD", "subdiv dyadic",
                                        "subdiv reach (CS_TRACE_SUBDIV)",
                                        "predict (CS_TRACE_PREDICT, default)"};
static cs_vec3_t verts[MAX_VERTS];
static bench_rng_t rng = {BENCH_RNG_SEED};

static cs_bezier_t mk(unsigned n, const double (*p)[3], const double *w)
{
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = (uint8_t)n;
    c.rational = w != NULL;
    for (unsigned i = 0; i <= n; i++) {
        c.p[i] = cs_fixed_vec((cs_pos_t)lround(p[i][0] * 65536), (cs_pos_t)lround(p[i][1] * 65536),
                              (cs_pos_t)lround(p[i][2] * 65536));
        c.w[i] = w ? (cs_weight_t)lround(w[i] * CS_WEIGHT_ONE) : CS_WEIGHT_ONE;
    }
    return c;
}

static void hard_cases(bench_set_t *s)
{
    static const double cases[][4][3] = {
        {{0, 0, 0}, {0, 0, 0}, {50, 20, 0}, {50, 20, 0}},                      /* coincident */
        {{0, 0, 0}, {100, 100, 0}, {0, 100, 0}, {100, 0, 0}},                  /* cusp */
        {{0, 0, 0}, {150, 100, 0}, {-50, 100, 0}, {100, 0, 0}},                /* loop */
        {{0, 0, 0}, {33, 50, 0}, {66, -50, 0}, {100, 0, 0}},                   /* inflection */
        {{0, 0, 0}, {100, 0, 0}, {20, 0, 0}, {60, 0, 0}},                      /* collinear fold */
        {{-1000, -500, 0}, {-300, 900, 50}, {400, -900, -50}, {1000, 500, 0}}, /* 2 m */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        cs_bezier_t c = mk(3, cases[i], NULL);
        bench_set_add(s, &c);
    }
    const double q[3][3] = {{50, 0, 0}, {50, 50, 0}, {0, 50, 0}};
    const double wq[3] = {1.0, 0.70710678118654752, 1.0};
    cs_bezier_t c = mk(2, q, wq);
    bench_set_add(s, &c);
    const double d7[8][3] = {{0, 0, 0},    {10, 80, 0},   {25, -60, 10}, {40, 90, 0},
                             {55, -70, 0}, {70, 60, -10}, {85, -30, 0},  {100, 0, 0}};
    c = mk(7, d7, NULL);
    bench_set_add(s, &c);
}

/* Traces c with method m; returns the vertex count, or 0 on error. */
static size_t run(const cs_bezier_t *c, cs_pos_t tol, int m)
{
    static cs_trace_t tr;
    static cs_subdiv_t sd;
    size_t n = 0;
    cs_err_t e;
    if (m == 2) {
        if (cs_subdiv_begin(&sd, c, tol, false) != CS_OK)
            return 0;
        while (n < MAX_VERTS && (e = cs_subdiv_next(&sd, &verts[n])) == CS_OK)
            n++;
    } else {
        cs_trace_method_t tm = m == 0   ? CS_TRACE_FD
                               : m == 1 ? CS_TRACE_AFD
                               : m == 3 ? CS_TRACE_SUBDIV
                                        : CS_TRACE_PREDICT;
        if (cs_trace_begin(&tr, c, tol, tm) != CS_OK)
            return 0;
        while (n < MAX_VERTS && (e = cs_trace_next(&tr, &verts[n])) == CS_OK)
            n++;
    }
    return e == CS_END ? n : 0;
}

int main(int argc, char **argv)
{
    static const char usage[] = "usage: bench_flatten [OUT.csv] [FILE.svg...]\n"
        "Chords per curve, accuracy and speed of every tracing method against the greedy\n"
        "double-precision reference; a Markdown section on stdout, the figures in OUT.csv.\n"
        "No SVG named: the corpus under ../shared/data/svg (else tests/data/svg).\n";
    int usage_rc = bench_args_check(argc, argv, usage, -1);
    if (usage_rc >= 0)
        return usage_rc;
    FILE *csv = argc > 1 ? fopen(argv[1], "w") : NULL;
    bench_set_t sets[3] = {
        {"random cubics", NULL, 0, 0}, {"hard cases", NULL, 0, 0}, {"SVG files", NULL, 0, 0}};
    for (int k = 0; k < 200; k++) {
        double p[4][3];
        for (int i = 0; i < 4; i++)
            for (int a = 0; a < 3; a++)
                p[i][a] = a == 2 ? 0.0 : (bench_rng_unit(&rng) * 2 - 1) * 100.0;
        cs_bezier_t c = mk(3, p, NULL);
        bench_set_add(&sets[0], &c);
    }
    hard_cases(&sets[1]);
    /* Run from the repository root (make bench): no files named, the SVG corpus. */
    bench_svg_curves(&sets[2], argv + 2, argc > 2 ? (size_t)(argc - 2) : 0, NULL);
    if (csv)
        fprintf(csv, "set,method,tol_mm,curves,chords,greedy_chords,ratio,max_dev_mm,"
                     "points_per_s,errors\n");
    printf("## Flattening: chords, accuracy and speed per method\n\n");
    printf("bench_flatten: chords per curve for each method against the greedy reference (from "
           "each vertex the longest chord within tol, double precision, bisection on t); max "
           "deviation measured both ways by cs_ref_max_deviation; speed = vertices per second of "
           "tracing alone (one core).\n\n");
    double worst_dev_ratio = 0, worst_best_ratio = 0;
    for (int si = 0; si < 3; si++) {
        bench_set_t *s = &sets[si];
        if (s->n == 0)
            continue;
        printf("### %s (%zu curves)\n\n", s->name, s->n);
        printf("| method | tol (mm) | chords/curve | greedy/curve | ratio | max dev / tol | "
               "vertices/s | errors |\n|---|---|---|---|---|---|---|---|\n");
        for (int ti = 0; ti < N_TOLS; ti++) {
            cs_pos_t tol = (cs_pos_t)lround(tols_mm[ti] * 65536);
            size_t greedy = 0;
            for (size_t k = 0; k < s->n; k++)
                greedy += cs_ref_greedy_count(&s->c[k], tols_mm[ti]);
            fprintf(stderr, "bench_flatten: %s tol %g: greedy %zu\n", s->name, tols_mm[ti], greedy);
            for (int m = 0; m < N_METH; m++) {
                size_t chords = 0;
                int errors = 0;
                double worst = 0;
                for (size_t k = 0; k < s->n; k++) {
                    size_t n = run(&s->c[k], tol, m);
                    if (n == 0) {
                        errors++;
                        continue;
                    }
                    chords += n;
                    double d = cs_ref_max_deviation(&s->c[k], verts, n);
                    if (d > worst)
                        worst = d;
                }
                /* Speed: repeat the whole set until 0.2 s have passed. */
                size_t done = 0;
                double t0 = bench_now(), t1;
                do {
                    for (size_t k = 0; k < s->n; k++)
                        done += run(&s->c[k], tol, m);
                    t1 = bench_now();
                } while (t1 - t0 < 0.2);
                double pps = done / (t1 - t0);
                double ratio = (double)chords / (double)greedy;
                double dev_ratio = errors ? INFINITY : worst / tols_mm[ti];
                if (dev_ratio > worst_dev_ratio)
                    worst_dev_ratio = dev_ratio;
                if (m == N_METH - 1 && ratio > worst_best_ratio)
                    worst_best_ratio = ratio;
                printf("| %s | %g | %.1f | %.1f | %.3f | %.4f | %.3g | %d |\n", meth_name[m],
                       tols_mm[ti], (double)chords / s->n, (double)greedy / s->n, ratio,
                       worst / tols_mm[ti], pps, errors);
                if (csv)
                    fprintf(csv, "%s,%s,%g,%zu,%zu,%zu,%.4f,%.6g,%.4g,%d\n", s->name, meth_name[m],
                            tols_mm[ti], s->n, chords, greedy, ratio, worst, pps, errors);
            }
        }
        printf("\n");
    }
    printf("Goals (issue 2), judged on the figures above:\n\n");
    printf("- every chord of every method within the tolerance (max dev / tol <= 1): %s (worst "
           "%.4f)\n",
           worst_dev_ratio <= 1.0 ? "met" : "MISSED", worst_dev_ratio);
    printf("- best method (%s) at most 1.15x the greedy chord count: %s (worst ratio %.3f)\n\n",
           meth_name[N_METH - 1], worst_best_ratio <= 1.15 ? "met" : "MISSED", worst_best_ratio);
    if (csv)
        fclose(csv);
    for (int si = 0; si < 3; si++)
        free(sets[si].c);
    return 0;
}
