/* curvestep-sim: runs step segments through the firmware's executor on the POSIX port (simulated
 * time), then reports what the steps did: final position, per-axis peak velocity and
 * acceleration against the machine's limits, and (given the job) the largest distance between
 * the executed path and the exact geometry. Draws both as SVG/PNG and dumps a CSV trace. */
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cs_err_text.h"
#include "cs_jobplan.h"
#include "cs_machine_ini.h"
#include "cs_motion.h"
#include "cs_sim.h"
#include "cs_sim_check.h"
#include "cs_sim_device.h"
#include "cs_sim_draw.h"
#include "cs_sim_modbus.h"

enum { EXIT_OK = 0, EXIT_INPUT = 1, EXIT_USAGE = 2, EXIT_INTERNAL = 3, EXIT_CHECK = 4 };

static void usage(FILE *f)
{
    fputs(
        "usage: curvestep-sim --replay SEGMENTS [--machine FILE.ini] [--reference FILE]\n"
        "                     [--trace OUT.csv] [--svg OUT.svg] [--png OUT.png] [--check]\n"
        "                     [--window MS] [--font FILE.jhf] [--view top|front|side|iso]\n"
        "                     [input and layout options, for --reference]\n"
        "       curvestep-sim --pty | --port DEV ...  (the device on a serial line: --pty --help)\n"
        "       curvestep-sim --modbus-tcp ADDR:PORT | --modbus-rtu ...  (the device behind\n"
        "                     Modbus: --modbus-tcp --help)\n"
        "Executes the step segments written by `curvestep plan` (same --machine) with the\n"
        "firmware's executor in simulated time, records every STEP edge and reports:\n"
        "  - the final position of each axis, in steps and mm;\n"
        "  - each axis's peak velocity and acceleration against its limits, estimated from\n"
        "    the edges over windows of --window ms (default 50): velocity = steps over one\n"
        "    window, acceleration = change of that between windows; the estimator's own error\n"
        "    (2 steps/W, 4 steps/W^2) is allowed on top of the limit and printed;\n"
        "  - with --reference FILE (the job: SVG, G-code or HP-GL, read as `plan` reads it;\n"
        "    --font and the input and layout options as for plan; the machine's [pen] lifts "
        "included), the\n"
        "    largest distance from any position the steps visit to the exact geometry\n"
        "    (evaluated in double), against the tolerance plus one step, and whether the final\n"
        "    position is the job's end rounded to steps. With a [pen] (mode z: the pen is down\n"
        "    nearer down_z than up_z; mode servo: by the segments' \"pen US\" lines) only\n"
        "    pen-down x y motion is measured (in x y), and every drawn stroke must be reached\n"
        "    pen down: a pen-down travel or a stroke passed pen up fails, naming the segment.\n"
        "  --trace OUT.csv   every step edge: t_s,axis,dir,x_mm,y_mm,z_mm (a spindle / laser\n"
        "                    setting: t_s,s,duty,x_mm,y_mm,z_mm, duty in 1/1000)\n"
        "  --svg OUT.svg     drawing: exact geometry (black), executed path coloured by speed;\n"
        "                    with --reference, executed travel moves (the job's G0 moves and\n"
        "                    the jumps between its elements) thin dashed grey; with a [pen],\n"
        "                    pen-up motion dashed grey and each servo setting marked\n"
        "  --png OUT.png     the same drawing through cairo (1600 px wide)\n"
        "  --png-width PX    width of that picture, 100..8000 px (default 1600)\n"
        "  --view V          project the drawing: top (x y), front (x z), side (y z) or iso\n"
        "                    (orthographic from (1,-1,1)), y up, as `curvestep toolpath --view`;\n"
        "                    default: machine x y, y up, seen from above (SVG pages are\n"
        "                    turned y-up when read, so a drawing looks as in a browser)\n"
        "  --check           exit 4 when a limit, the deviation or the final position fails\n",
        f);
    cs_jobopts_help(f);
    fputs("Exit status: 0 ok, 1 bad input (file:line: reason), 2 bad command line,\n"
          "3 internal error, 4 a check failed (with --check).\n",
          f);
}

/* The job as `plan` reads and lays it out with the machine's [pen] (cs_jobplan_reference: pen
 * lifts included), as dense reference polylines; *end gets its last point. */
static cs_err_t read_reference(const char *file, const char *font, const cs_jobopts_t *in,
                               const char *machine_file, const cs_machine_t *m, cs_sim_ref_t *ref,
                               double end[3])
{
    cs_jobplan_t jp;
    cs_jobplan_init(&jp);
    jp.font_file = font;
    cs_err_t e = cs_jobplan_reference(&jp, file, in, machine_file, m);
    if (e == CS_OK)
        e = cs_sim_ref_from_path(ref, &jp.path, end);
    else
        cs_path_diag_print(stderr, &jp.diag);
    cs_jobplan_free(&jp);
    return e;
}

/* Prints the geometric check (cs_sim_check) and the final position; true when both pass. */

/* The replay's command line. */
typedef struct {
    const char *replay, *machine_file, *reference, *trace, *svg, *png, *font;
    bool check;
    cs_jobopts_t in; /* --reference is read, laid out, merged and sorted as plan does */
    double window_ms;
    long png_width;
    cs_sim_view_t view;
} replay_args_t;

/* The replay's options with a value check: 1 taken, 0 not one of them, -1 bad (said). */
static int replay_number_option(int argc, char **argv, int *i, replay_args_t *a)
{
    const char *o = argv[*i];
    if (*i + 1 >= argc)
        return 0;
    char *end;
    if (strcmp(o, "--window") == 0) {
        a->window_ms = strtod(argv[++*i], &end);
        if (*end != '\0' || !(a->window_ms > 0) || a->window_ms > 10000) {
            fprintf(stderr, "curvestep-sim: --window wants milliseconds in (0, 10000]\n");
            return -1;
        }
    } else if (strcmp(o, "--png-width") == 0) {
        a->png_width = strtol(argv[++*i], &end, 10);
        if (*end != '\0' || a->png_width < 100 || a->png_width > 8000) {
            fprintf(stderr, "curvestep-sim: --png-width wants pixels in 100..8000\n");
            return -1;
        }
    } else if (strcmp(o, "--view") == 0) {
        if (!cs_sim_view_parse(argv[++*i], &a->view)) {
            fprintf(stderr, "curvestep-sim: --view wants top, front, side or iso\n");
            return -1;
        }
    } else {
        return 0;
    }
    return 1;
}

/* The replay's file options: 1 taken, 0 not one of them. */
static int replay_file_option(int argc, char **argv, int *i, replay_args_t *a)
{
    static const char *const names[] = {"--replay", "--machine", "--reference", "--trace",
                                        "--svg",    "--png",     "--font"};
    const char **dst[] = {&a->replay, &a->machine_file, &a->reference, &a->trace,
                          &a->svg,    &a->png,          &a->font};
    if (*i + 1 >= argc)
        return 0;
    for (size_t k = 0; k < sizeof names / sizeof names[0]; k++)
        if (strcmp(argv[*i], names[k]) == 0) {
            *dst[k] = argv[++*i];
            return 1;
        }
    return 0;
}

/* Parses argv into *a: -1 to go on, else the exit status (--help, a usage error). */
static int replay_parse(int argc, char **argv, replay_args_t *a)
{
    memset(a, 0, sizeof *a);
    cs_jobopts_init(&a->in);
    a->window_ms = 50;
    a->png_width = 1600;
    cs_sim_view_default(&a->view);
    for (int i = 1; i < argc; i++) {
        const char *o = argv[i];
        int r = cs_jobopts_option("sim", argc, argv, &i, &a->in);
        if (r == 0)
            r = replay_file_option(argc, argv, &i, a);
        if (r == 0)
            r = replay_number_option(argc, argv, &i, a);
        if (r < 0)
            return EXIT_USAGE;
        if (r > 0)
            continue;
        if (strcmp(o, "--help") == 0 || strcmp(o, "-h") == 0) {
            usage(stdout);
            return EXIT_OK;
        } else if (strcmp(o, "--check") == 0) {
            a->check = true;
        } else {
            fprintf(stderr, "curvestep-sim: unknown or incomplete option %s\n", o);
            usage(stderr);
            return EXIT_USAGE;
        }
    }
    if (a->replay == NULL || cs_jobopts_check("sim", &a->in) != 0) {
        usage(stderr);
        return EXIT_USAGE;
    }
    return -1;
}

/* The segments file (- : standard input), read against machine m. EXIT_OK or EXIT_INPUT. */
static int replay_read(const char *replay, const cs_machine_t *m, cs_motion_segs_t *segs)
{
    char err[512];
    FILE *f = strcmp(replay, "-") == 0 ? stdin : fopen(replay, "r");
    if (f == NULL) {
        fprintf(stderr, "%s:0: cannot open the segments file\n", replay);
        return EXIT_INPUT;
    }
    int r = cs_motion_read(f, replay, m, segs, err, sizeof err);
    if (f != stdin)
        fclose(f);
    if (r != 0) {
        fprintf(stderr, "%s\n", err);
        return EXIT_INPUT;
    }
    return EXIT_OK;
}

/* "replay: ...", "final position: ..." and each axis's peaks against its limits; false when a
 * limit is exceeded. */
static bool replay_dynamics(const cs_machine_t *m, const cs_motion_segs_t *segs,
                            const cs_sim_exec_t *ex, double window_ms)
{
    bool ok = true;
    static const char names[] = "xyza";
    printf("replay: %zu segments, %zu steps, job time %.4f s\n", segs->n, ex->n,
           (double)ex->end_tick / m->tick_hz);
    printf("final position:");
    for (unsigned i = 0; i < m->n_axes; i++)
        printf(" %c=%lld steps (%.4f mm)", names[i], (long long)ex->pos[i],
               (double)ex->pos[i] * CS_MOTION_ONE / m->axis[i].steps_per_mm);
    printf("\n");
    cs_sim_dyn_t dyn;
    cs_sim_dynamics(m, ex, window_ms / 1000.0, &dyn);
    for (unsigned i = 0; i < m->n_axes; i++) {
        double rate = cs_machine_ini_to_double(m->axis[i].max_rate);
        double acc = cs_machine_ini_to_double(m->axis[i].max_accel);
        printf("axis %c: peak velocity %.3f mm/s at %.3f s (limit %.3f + %.3f) %s; "
               "peak acceleration %.1f mm/s^2 at %.3f s (limit %.1f + %.1f) %s\n",
               names[i], dyn.peak_rate[i], dyn.t_rate[i], rate, dyn.rate_allow[i],
               dyn.rate_ok[i] ? "ok" : "OVER", dyn.peak_accel[i], dyn.t_accel[i], acc,
               dyn.accel_allow[i], dyn.accel_ok[i] ? "ok" : "OVER");
        ok = ok && dyn.rate_ok[i] && dyn.accel_ok[i];
    }
    return ok;
}

/* The reference check, the trace and the pictures, then "check: ...". The exit status. */
static int replay_outputs(const replay_args_t *a, const cs_machine_t *m,
                          const cs_machine_pen_t *pen, const cs_motion_segs_t *segs,
                          const cs_sim_exec_t *ex, bool ok)
{
    cs_sim_ref_t ref;
    cs_sim_ref_init(&ref);
    int rc = EXIT_OK;
    if (a->reference) {
        double end[3];
        cs_err_t e = read_reference(a->reference, a->font, &a->in, a->machine_file, m, &ref, end);
        if (e != CS_OK)
            rc = EXIT_INPUT;
        else
            ok = cs_sim_check_print(m, segs, ex, &ref, pen, end) && ok;
    }
    const cs_sim_ref_t *r = a->reference ? &ref : NULL;
    if (rc == EXIT_OK && a->trace && cs_sim_write_trace(a->trace, m, ex) != 0) {
        perror(a->trace);
        rc = EXIT_INTERNAL;
    }
    cs_sim_draw_pen_t dp = {pen, segs}; /* pen-up travel and servo settings in the pictures */
    if (rc == EXIT_OK && a->svg && cs_sim_draw_svg_pen(a->svg, m, ex, r, &a->view, &dp) != 0) {
        perror(a->svg);
        rc = EXIT_INTERNAL;
    }
    if (rc == EXIT_OK && a->png &&
        cs_sim_draw_png_pen(a->png, m, ex, r, &a->view, (int)a->png_width, &dp) != 0)
        rc = EXIT_INTERNAL;
    if (rc == EXIT_OK && a->check) {
        printf("check: %s\n", ok ? "ok" : "FAILED");
        rc = ok ? EXIT_OK : EXIT_CHECK;
    }
    cs_sim_ref_free(&ref);
    return rc;
}

int main(int argc, char **argv)
{
    for (int i = 1; i < argc; i++) /* device mode: the simulator behind a serial line */
        if (strcmp(argv[i], "--pty") == 0 || strcmp(argv[i], "--port") == 0)
            return cs_sim_device_main(argc, argv);
    for (int i = 1; i < argc; i++) /* the device behind Modbus TCP or RTU (sim/cs_sim_modbus.h) */
        if (strcmp(argv[i], "--modbus-tcp") == 0 || strcmp(argv[i], "--modbus-rtu") == 0)
            return cs_sim_modbus_main(argc, argv);
    replay_args_t a;
    int rc = replay_parse(argc, argv, &a);
    if (rc >= 0)
        return rc;
    cs_machine_t m;
    cs_machine_pen_t pen;
    cs_machine_ini_pen_default(&pen);
    char err[512];
    if (cs_machine_ini_open("curvestep-sim", a.machine_file, &m, &pen, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return EXIT_INPUT;
    }
    cs_motion_segs_t segs = {0};
    rc = replay_read(a.replay, &m, &segs);
    cs_sim_exec_t ex;
    cs_err_t e = rc == EXIT_OK ? cs_sim_execute(&m, segs.v, segs.n, &ex) : CS_OK;
    if (rc == EXIT_OK && e != CS_OK) {
        fprintf(stderr, "curvestep-sim: execution failed: %s\n", cs_err_text(e));
        rc = EXIT_INTERNAL;
    } else if (rc == EXIT_OK) {
        bool ok = replay_dynamics(&m, &segs, &ex, a.window_ms);
        rc = replay_outputs(&a, &m, &pen, &segs, &ex, ok);
        cs_sim_exec_free(&ex);
    }
    cs_motion_segs_free(&segs);
    return rc;
}
