/* curvestep plan: job file -> step segments. Reads the job (cs_input_load: SVG, G-code,
 * HP-GL), traces every element into chords within the machine's tolerance, plans them
 * (cs_planner, look-ahead ring kept full), cuts step segments (cs_segment) and writes them one
 * per line, "ticks dx dy dz". */
#include <stdio.h>
#include <stdlib.h>
#include <errno.h>
#include <string.h>

#include "cs_cmd.h"
#include "cs_jobplan.h"
#include "cs_trace.h"

static void usage(FILE *f)
{
    fputs("usage: curvestep plan [--machine FILE.ini] [--tol MM] [--method fd|afd|subdiv|predict]\n"
          "                      [--feed MM/S] [input and layout options] [-o OUT] FILE\n"
          "Plans the job FILE (G-code .nc .gcode .ngc .g .tap .cnc, HP-GL .plt .hpgl .hgl .hpg,\n"
          "DXF .dxf, SVG document or bare SVG path data; other names and '-' by content) on\n"
          "the machine\n"
          "and writes its step segments to OUT (default: standard output): a header line\n"
          "  # curvestep segments tick_hz=N axes=N\n"
          "then one line per segment, \"ticks dx dy dz\" (\" da\" too on a 4-axis machine): the\n"
          "segment lasts ticks executor ticks and moves each axis by that many steps.\n"
          "The machine starts at 0 and moves in straight rapid travel to each subpath start;\n"
          "G-code G0 moves are rapid too (each axis at its max_rate), G1/G2/G3 use their F.\n"
          "A summary goes to standard error: blocks, segments, steps, job time.\n"
          "A G-code job that turns a spindle or laser on (M3/M4) gets a comment line\n"
          "\"# spindle M4 S500 F10.000\" (F: the moves' feed, mm/s; \"rapid\" for G0 moves,\n"
          "\"M5\" when off) before the first segment of each change of M, S or feed.\n"
          "  --machine FILE.ini  machine description (default: the first machine.ini found in\n"
          "                      $XDG_CONFIG_HOME/curvestep, ~/.config/curvestep,\n"
          "                      /etc/curvestep, else a built-in 3-axis plotter, 80 steps/mm;\n"
          "                      keys in docs/motion.md); its [pen] lifts the pen between\n"
          "                      strokes: [pen] mode = z moves Z to up_z / down_z (G-code\n"
          "                      M5 / M3); [pen] mode = servo writes \"pen US\" lines, each\n"
          "                      followed by the settle wait (docs/plotting.md)\n"
          "  --tol MM            chord tolerance (default: the machine's tolerance)\n"
          "  --method M          tracer: fd, afd, subdiv or predict (default predict)\n"
          "  --feed MM/S         feed for moves the job gives none (SVG, HP-GL, G-code before\n"
          "                      any F; default: the machine's default_feed)\n"
          "  --font FILE.jhf     Hershey stroke font for SVG <text>, HP-GL LB, DXF TEXT (default:\n"
          "                      share/fonts/futural.jhf, docs/plotting.md)\n"
          "  --max-input-mb N    refuse a job file larger than N MiB (default 64)\n"
          "  --max-segments N    refuse a job of more than N step segments (default 8388608)\n"
          "  -o OUT              write segments to OUT\n",
          f);
    cs_jobopts_help(f);
    fputs("Exit status: 0 ok, 1 bad input (file:line:col: reason; a move outside the travel\n"
          "is refused before any segment is written), 2 bad command line, 3 internal error.\n",
          f);
}


/* The spindle / laser line of the summary: how many power changes, the largest S. */
static void spindle_summary(const cs_motion_segs_t *s)
{
    double smax = 0;
    for (size_t q = 0; q < s->npowers; q++)
        if (s->powers[q].spindle != 5 && s->powers[q].s > smax)
            smax = s->powers[q].s;
    fprintf(stderr, "plan: spindle: %zu changes (\"# spindle\" lines), largest S %g\n",
            s->npowers, smax);
}

int cs_cmd_plan(int argc, char **argv)
{
    const char *out_file = NULL, *job = NULL;
    cs_jobplan_opts_t jo;
    cs_jobplan_opts_init(&jo);
    int method = CS_TRACE_DEFAULT;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int r = cs_jobplan_option("plan", argc, argv, &i, &jo);
        if (r < 0)
            return CS_EXIT_USAGE;
        if (r > 0)
            continue;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            return CS_EXIT_OK;
        } else if (strcmp(a, "-o") == 0 && i + 1 < argc) {
            out_file = argv[++i];
        } else if (strcmp(a, "--method") == 0 && i + 1 < argc) {
            const char *m = argv[++i];
            if (strcmp(m, "fd") == 0)
                method = CS_TRACE_FD;
            else if (strcmp(m, "afd") == 0)
                method = CS_TRACE_AFD;
            else if (strcmp(m, "subdiv") == 0)
                method = CS_TRACE_SUBDIV;
            else if (strcmp(m, "predict") == 0)
                method = CS_TRACE_PREDICT;
            else {
                fprintf(stderr, "curvestep plan: --method wants fd, afd, subdiv or predict\n");
                return CS_EXIT_USAGE;
            }
        } else if (a[0] == '-' && a[1] != '\0') {
            fprintf(stderr, "curvestep plan: unknown or incomplete option %s\n", a);
            usage(stderr);
            return CS_EXIT_USAGE;
        } else if (job == NULL) {
            job = a;
        } else {
            fprintf(stderr, "curvestep plan: one job file only\n");
            return CS_EXIT_USAGE;
        }
    }
    if (job == NULL) {
        usage(stderr);
        return CS_EXIT_USAGE;
    }
    cs_machine_t m;
    cs_machine_pen_t pen;
    cs_pos_t tol;
    int rc = cs_jobplan_machine("plan", &jo, &m, &pen, &tol);
    if (rc != CS_EXIT_OK)
        return rc;
    cs_jobplan_t jp;
    cs_jobplan_init(&jp);
    cs_jobplan_limits(&jp, &jo);
    jp.font_file = jo.font_file;
    cs_err_t e = cs_jobplan_read_opts(&jp, job, &pen, &jo.in);
    if (e == CS_OK)
        e = cs_jobplan_prepare(&jp, "plan", &jo.in, &m, &pen, tol, stderr);
    if (e == CS_OK)
        e = cs_jobplan_plan(&jp, job, &m, NULL, tol, method, cs_motion_speed(jo.feed_mm_s));
    if (e != CS_OK) {
        cs_path_diag_print(stderr, &jp.diag);
        rc = cs_jobplan_exit(&jp, e);
    } else {
        FILE *f = out_file ? fopen(out_file, "w") : stdout;
        const char *name = out_file ? out_file : "<stdout>";
        if (f == NULL) {
            fprintf(stderr, "curvestep plan: %s: cannot open: %s\n", name, strerror(errno));
            rc = CS_EXIT_INTERNAL;
        } else {
            int w = cs_motion_write_segs(f, &m, &jp.mo.segs);
            int err = errno;
            if (out_file ? fclose(f) != 0 : fflush(f) != 0)
                w = -1, err = errno;
            if (w != 0) {
                fprintf(stderr, "curvestep plan: %s: write error: %s\n", name, strerror(err));
                rc = CS_EXIT_INTERNAL;
            }
        }
        if (rc == CS_EXIT_OK)
            fprintf(stderr,
                    "plan: %zu elements, %zu blocks, %zu segments, %lld steps, job time %.4f s "
                    "(%llu ticks at %u Hz)\n",
                    jp.path.n, jp.mo.blocks, jp.mo.segs.n, (long long)jp.mo.steps,
                    (double)jp.mo.ticks / m.tick_hz, (unsigned long long)jp.mo.ticks,
                    (unsigned)m.tick_hz);
        if (rc == CS_EXIT_OK && cs_motion_spindle_used(&jp.mo.segs))
            spindle_summary(&jp.mo.segs);
    }
    cs_jobplan_free(&jp);
    return rc;
}
