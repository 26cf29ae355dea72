/* curvestep toolpath --cutter ...: drop-cutter finishing (issue 20). Parses the options, builds
 * the mesh (cs_dropcut), plans the raster (cs_dcpath), writes the tool points and G-code a Grbl
 * or LinuxCNC machine runs as written, and with --check measures gouge and scallop against the
 * exact surface (cs_dropcheck). The options are listed in `curvestep toolpath --help`. */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_cmd.h"
#include "cs_conv.h"
#include "cs_dccombo.h"
#include "cs_dcpath.h"
#include "cs_dcwater.h"
#include "cs_dropcheck.h"
#include "cs_dropcut.h"
#include "cs_path.h"
#include "cs_surffile.h"

#define DC_DEFAULT_TOL    0.01
#define DC_DEFAULT_FEED   1000.0 /* mm/min */
#define DC_DEFAULT_PLUNGE 300.0  /* mm/min */
#define DC_MAX_PASSES     20000

typedef struct {
    const char *file, *gcode, *name, *trace; /* trace: --check-trace, an executed path */
    double scale, tol, feed, plunge, safe_z, spindle, min_z, check_step;
    bool have_safe_z, have_min_z, have_stock, check, stats, centre, no_link, waterline, combo;
    cs_dropcut_tool_t tool;
    const char *tool_kind;
    cs_dcpath_opts_t po;
} dc_args_t;

static int bad(const char *opt, const char *val, const char *want)
{
    fprintf(stderr, "curvestep toolpath: %s '%s': expected %s\n", opt, val, want);
    return CS_EXIT_USAGE;
}

/* ball:R, flat:R or bull:R:r (radii in mm). */
static bool parse_cutter(const char *s, dc_args_t *a)
{
    char kind[8] = {0};
    double r = 0, c = 0;
    int used = 0;
    if (sscanf(s, "%7[a-z]:%lf%n", kind, &r, &used) != 2 || !(r > 0) || r > 100)
        return false;
    const char *rest = s + used;
    if (strcmp(kind, "ball") == 0 && *rest == '\0')
        c = r;
    else if (strcmp(kind, "flat") == 0 && *rest == '\0')
        c = 0;
    else if (strcmp(kind, "bull") != 0 || !cs_conv_number(rest + (*rest == ':'), &c) || *rest != ':' ||
             !(c > 0) || c >= r)
        return false;
    a->tool.r_mm = r;
    a->tool.c_mm = c;
    a->tool_kind = strcmp(kind, "ball") == 0 ? "ball" : strcmp(kind, "flat") == 0 ? "flat" : "bull-nose";
    return true;
}

/* X0,Y0,X1,Y1 */
static bool parse_box(const char *s, double b[4])
{
    char tail;
    return sscanf(s, "%lf,%lf,%lf,%lf%c", &b[0], &b[1], &b[2], &b[3], &tail) == 4 && b[2] > b[0] &&
           b[3] > b[1];
}

static int parse_value(int c, const char *v, dc_args_t *a)
{
    switch (c) {
    case 'p': a->file = v; return 0;
    case 'g': a->gcode = v; return 0;
    case 'c': return parse_cutter(v, a) ? 0 : bad("--cutter", v, "ball:R, flat:R or bull:R:r (mm, 0 < r < R <= 100)");
    case 'H': return cs_conv_number(v, &a->po.scallop_mm) && a->po.scallop_mm > 0 ? 0 : bad("--scallop", v, "a height in mm > 0");
    case 'w': return cs_conv_number(v, &a->po.step_mm) && a->po.step_mm > 0 ? 0 : bad("--stepover", v, "a distance in mm > 0");
    case 'a': return cs_conv_number(v, &a->po.angle_deg) ? 0 : bad("--angle", v, "degrees");
    case 't': return cs_conv_number(v, &a->tol) && a->tol >= 0.0001 && a->tol <= 10 ? 0 : bad("--tol", v, "a tolerance in mm, 0.0001 to 10");
    case 'S': return cs_conv_number(v, &a->scale) && a->scale > 0 ? 0 : bad("--scale", v, "a number > 0");
    case 'f': return cs_conv_number(v, &a->feed) && a->feed > 0 ? 0 : bad("--feed", v, "a feed in mm/min > 0");
    case 'P': return cs_conv_number(v, &a->plunge) && a->plunge > 0 ? 0 : bad("--plunge", v, "a feed in mm/min > 0");
    case 'z': a->have_safe_z = true; return cs_conv_number(v, &a->safe_z) ? 0 : bad("--safe-z", v, "a height in mm");
    case 'm': a->have_min_z = true; return cs_conv_number(v, &a->min_z) ? 0 : bad("--min-z", v, "a height in mm");
    case 's': return cs_conv_number(v, &a->spindle) && a->spindle >= 0 ? 0 : bad("--spindle", v, "a speed in rev/min >= 0");
    case 'k': a->have_stock = true; return parse_box(v, a->po.box) ? 0 : bad("--stock", v, "X0,Y0,X1,Y1 (mm, X0 < X1, Y0 < Y1)");
    case 'R': a->trace = v; return 0;
    case 'K': return cs_conv_number(v, &a->check_step) && a->check_step > 0 ? 0 : bad("--check-step", v, "a distance in mm > 0");
    case 'W':
        if (strcmp(v, "raster") && strcmp(v, "waterline") && strcmp(v, "raster+waterline"))
            return bad("--strategy", v, "raster, waterline or raster+waterline");
        a->waterline = strcmp(v, "waterline") == 0;
        a->combo = strcmp(v, "raster+waterline") == 0;
        return 0;
    case 'o':
        if (strcmp(v, "tip") && strcmp(v, "centre") && strcmp(v, "center"))
            return bad("--output", v, "tip or centre");
        a->centre = strcmp(v, "tip") != 0;
        return 0;
    default: return -1;
    }
}

static int parse_args(int argc, char **argv, dc_args_t *a)
{
    static const struct option longopts[] = {
        {"patches", required_argument, NULL, 'p'}, {"gcode", required_argument, NULL, 'g'},
        {"cutter", required_argument, NULL, 'c'},  {"scallop", required_argument, NULL, 'H'},
        {"stepover", required_argument, NULL, 'w'}, {"angle", required_argument, NULL, 'a'},
        {"tol", required_argument, NULL, 't'},     {"scale", required_argument, NULL, 'S'},
        {"feed", required_argument, NULL, 'f'},    {"plunge", required_argument, NULL, 'P'},
        {"safe-z", required_argument, NULL, 'z'},  {"min-z", required_argument, NULL, 'm'},
        {"spindle", required_argument, NULL, 's'}, {"stock", required_argument, NULL, 'k'},
        {"output", required_argument, NULL, 'o'},  {"check-step", required_argument, NULL, 'K'},
        {"check", no_argument, NULL, 'C'},         {"stats", no_argument, NULL, 'T'},
        {"no-link", no_argument, NULL, 'L'},       {"strategy", required_argument, NULL, 'W'},
        {"check-trace", required_argument, NULL, 'R'},
        {NULL, 0, NULL, 0},
    };
    int c;
    optind = 1;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":", longopts, NULL)) != -1) {
        if (c == 'C' || c == 'T' || c == 'L') {
            *(c == 'C' ? &a->check : c == 'T' ? &a->stats : &a->no_link) = true;
            continue;
        }
        if (c == ':' || c == '?') {
            fprintf(stderr, "curvestep toolpath: %s '%s' (with --cutter)\nTry 'curvestep toolpath --help'.\n",
                    c == ':' ? "option needs a value:" : "unknown option", argv[optind - 1]);
            return CS_EXIT_USAGE;
        }
        int r = parse_value(c, optarg, a);
        if (r != 0)
            return r;
    }
    if (optind != argc || !a->file) {
        fprintf(stderr, "curvestep toolpath: %s\nTry 'curvestep toolpath --help'.\n",
                optind != argc ? "unexpected argument (the file goes after --patches)" : "missing --patches FILE");
        return CS_EXIT_USAGE;
    }
    if (a->po.scallop_mm <= 0 && a->po.step_mm <= 0) {
        fprintf(stderr, "curvestep toolpath: --cutter needs --scallop H or --stepover MM\n");
        return CS_EXIT_USAGE;
    }
    if (a->po.scallop_mm <= 0)
        a->po.scallop_mm = HUGE_VAL;
    return CS_EXIT_OK;
}

/* --- output ------------------------------------------------------------------------------- */

/* The programmed point of a tip point: the tip, or the centre of the corner radius above it. */
static double out_z(const dc_args_t *a, double tip)
{
    return a->centre ? tip + a->tool.c_mm : tip;
}

static void write_points(const dc_args_t *a, const cs_dcpath_t *p)
{
    for (size_t k = 0; k < p->npass; k++) {
        for (size_t i = p->start[k]; i < p->start[k + 1]; i++)
            printf("%.6f %.6f %.6f\n", p->pt[i][0], p->pt[i][1], out_z(a, p->pt[i][2]));
        if (k + 1 < p->npass)
            printf("\n");
    }
}

/* G-code: metric, absolute, XY plane, feed per minute; the spindle on when asked; each pass:
 * rapid at the safe height over its start, plunge at the plunge feed, cut at the feed (F on
 * every feed move), retract. */
static bool write_gcode(const dc_args_t *a, const cs_dcpath_t *p, double safe)
{
    FILE *f = fopen(a->gcode, "w");
    if (!f)
        return false;
    bool plain = !strpbrk(a->name, "()");
    fprintf(f, "(curvestep toolpath: drop-cutter finishing of %s)\n", plain ? a->name : "the input");
    fprintf(f, "(%s cutter R %g mm, corner %g mm; programmed point: tool %s)\n", a->tool_kind,
            a->tool.r_mm, a->tool.c_mm, a->centre ? "corner centre" : "tip");
    fprintf(f, "G21 G90 G17 G94\nG0 Z%.4f\n", safe);
    if (a->spindle > 0)
        fprintf(f, "M3 S%.0f\n", a->spindle);
    for (size_t k = 0; k < p->npass; k++) {
        const double *s = p->pt[p->start[k]];
        fprintf(f, "G0 X%.4f Y%.4f\nG1 Z%.4f F%.0f\n", s[0], s[1], out_z(a, s[2]), a->plunge);
        for (size_t i = p->start[k] + 1; i < p->start[k + 1]; i++)
            fprintf(f, "G1 X%.4f Y%.4f Z%.4f F%.0f\n", p->pt[i][0], p->pt[i][1], out_z(a, p->pt[i][2]),
                    a->feed);
        fprintf(f, "G0 Z%.4f\n", safe);
    }
    if (a->spindle > 0)
        fprintf(f, "M5\n");
    fprintf(f, "M2\n");
    bool badw = ferror(f) != 0;
    return fclose(f) == 0 && !badw;
}

/* The check, the ideal cutter keeping the planner's stated margin (its mesh bound eps). */
static int report_check(const dc_args_t *a, const cs_surffile_t *sf, const cs_dcpath_t *p,
                        double margin)
{
    cs_dropcheck_t ck;
    double step = a->check_step > 0 ? a->check_step : 0.05;
    cs_err_t e = cs_dropcheck_run(sf, &a->tool, (const double(*)[3])p->pt, p->start, p->npass,
                                  a->po.box, step, a->po.scallop_mm, margin, &ck);
    if (e != CS_OK) {
        fprintf(stderr, "curvestep toolpath: check: out of memory\n");
        return CS_EXIT_INTERNAL;
    }
    fprintf(stderr,
            "toolpath: check (step %g mm, margin %g mm, %zu surface samples, %zu cutter positions, "
            "%zu nodes, %zu on walls left out): gouge %.6f mm, scallop %.6f mm at (%.3f, %.3f)\n",
            step, margin, ck.surf_samples, ck.path_samples, ck.nodes, ck.walls, ck.gouge_mm, ck.scallop_mm,
            ck.scallop_at[0], ck.scallop_at[1]);
    if (ck.rest_nodes > 0)
        fprintf(stderr,
                "toolpath: check: unreachable: %zu nodes (%.2f mm^2) where no cutter of this shape "
                "reaches from above, up to %.4f mm of rest material at (%.3f, %.3f)\n",
                ck.rest_nodes, (double)ck.rest_nodes * step * step, ck.rest_mm, ck.rest_at[0],
                ck.rest_at[1]);
    if (ck.corner_nodes > 0)
        fprintf(stderr,
                "toolpath: check: rest material <= H: %zu nodes (%.2f mm^2) in corners the "
                "cutter's shape keeps off, scallop measured from the best envelope it can leave "
                "there; up to %.4f mm left over the surface\n",
                ck.corner_nodes, (double)ck.corner_nodes * step * step, ck.corner_left_mm);
    bool gouged = ck.gouge_mm > a->tol, high = ck.scallop_mm > a->po.scallop_mm;
    if (gouged)
        fprintf(stderr,
                "toolpath: check FAILED: the cutter enters the surface by %.6f mm at (%.3f, %.3f, "
                "%.3f), tip at (%.4f, %.4f, %.4f), over the tolerance %g mm\n",
                ck.gouge_mm, ck.gouge_at[0], ck.gouge_at[1], ck.gouge_at[2], ck.gouge_tool[0],
                ck.gouge_tool[1], ck.gouge_tool[2], a->tol);
    if (high)
        fprintf(stderr, "toolpath: check FAILED: %.6f mm of material left at (%.3f, %.3f), over the scallop height %g mm\n",
                ck.scallop_mm, ck.scallop_at[0], ck.scallop_at[1], a->po.scallop_mm);
    return gouged || high ? CS_EXIT_INPUT : CS_EXIT_OK;
}

/* --- command ------------------------------------------------------------------------------ */

/* The mesh within tol / 4 of the surface (n-sided cells fitted within tol / 8 more); the region
 * and the floor from it unless given. */
static int build_mesh(dc_args_t *a, const cs_surffile_t *sf, cs_dropcut_mesh_t *ms)
{
    cs_err_t e = cs_dropcut_build(ms, sf, a->tol / 4, a->tol / 8, a->tool.r_mm);
    if (e != CS_OK) {
        fprintf(stderr, "%s: cannot mesh the surface: %s\n", a->name,
                e == CS_ERR_FULL ? "out of memory" : "no usable patch");
        return e == CS_ERR_FULL ? CS_EXIT_INTERNAL : CS_EXIT_INPUT;
    }
    /* By default the axis covers the surface's extent and a cutter radius beyond, so that the
     * cutter's side finishes the edges. */
    double r = a->tool.r_mm;
    if (!a->have_stock)
        memcpy(a->po.box, (double[4]){ms->box[0] - r, ms->box[1] - r, ms->box[3] + r, ms->box[4] + r},
               sizeof a->po.box);
    a->po.min_z = a->have_min_z ? a->min_z : ms->box[2];
    a->po.tol_mm = a->tol;
    a->po.max_passes = DC_MAX_PASSES;
    return CS_EXIT_OK;
}

/* The passes of the chosen strategy, then the fill-in (the raster's around its flagged points,
 * the others' over the whole region: they flag nothing), joined where the link is clear (unless
 * --no-link). */
static int plan(dc_args_t *a, const cs_surffile_t *sf, cs_dropcut_mesh_t *ms, cs_dcpath_t *p)
{
    cs_err_t e = a->waterline ? cs_dcwater_plan(p, ms, &a->tool, &a->po)
                 : a->combo   ? cs_dccombo_plan(p, ms, &a->tool, &a->po)
                              : cs_dcpath_raster(p, ms, &a->tool, &a->po);
    if (e != CS_OK) {
        fprintf(stderr, "curvestep toolpath: cannot plan the passes: %s\n",
                e == CS_ERR_FULL ? "out of memory" : "the region or step-over is empty");
        return e == CS_ERR_FULL ? CS_EXIT_INTERNAL : CS_EXIT_USAGE;
    }
    size_t filled = 0, nflag = p->nflag;
    double step = a->check_step > 0 ? a->check_step : 0.05;
    /* raster+waterline keeps its two rounds; the waterline's second round found nothing on the
     * teapot with any cutter (docs/surfaces.md) and costs a whole measure, so one */
    bool flagged = !a->combo && !a->waterline;
    int rounds = a->combo ? 2 : 1;
    if (cs_dcpath_fill(p, ms, &a->tool, sf, &a->po, step, flagged, rounds, &filled) != CS_OK) {
        fprintf(stderr, "curvestep toolpath: fill-in: out of memory\n");
        return CS_EXIT_INTERNAL;
    }
    size_t before = p->npass;
    if (!a->no_link)
        cs_dcpath_link(p, ms, &a->tool, a->tol, a->tol);
    if (p->capped)
        fprintf(stderr, "curvestep toolpath: warning: the scallop refinement stopped at %d passes; "
                        "estimated scallop %.4f mm (steep walls want a smaller step or another strategy)\n",
                DC_MAX_PASSES, p->max_left);
    if (a->stats)
        fprintf(stderr,
                "toolpath: %s cutter R %g mm corner %g mm, %s: mesh %zu triangles within %.6f mm, "
                "%zu passes (%zu added for the scallop, %zu short fill-in passes at %zu flagged points), %zu linked at cutting height (%zu "
                "retracts), %zu points, %zu drops, estimated scallop %.6f mm (nan: not estimated), "
                "%.6f mm where no pass can be added (rest material, walls)\n",
                a->tool_kind, a->tool.r_mm, a->tool.c_mm,
                a->waterline ? "waterline" : a->combo ? "raster+waterline" : "raster",
                ms->ntri, ms->eps, before, p->refined, filled, nflag, p->links, p->npass, p->n, p->drops,
                p->max_left, p->max_stuck);
    return CS_EXIT_OK;
}

static int plan_and_write(dc_args_t *a, const cs_surffile_t *sf)
{
    cs_dropcut_mesh_t ms;
    cs_dcpath_t p;
    cs_dcpath_init(&p);
    int status = build_mesh(a, sf, &ms);
    double safe = a->have_safe_z ? a->safe_z : ms.box[5] + a->tool.r_mm + 5;
    if (status == CS_EXIT_OK)
        status = plan(a, sf, &ms, &p);
    if (status == CS_EXIT_OK) {
        write_points(a, &p);
        if (a->gcode && !write_gcode(a, &p, safe)) {
            fprintf(stderr, "%s:0:0: cannot write the G-code\n", a->gcode);
            status = CS_EXIT_INTERNAL;
        }
    }
    if (status == CS_EXIT_OK && a->check)
        status = report_check(a, sf, &p, ms.eps);
    cs_dcpath_free(&p);
    cs_dropcut_free(&ms);
    return status;
}

/* The executed path of `curvestep-sim --trace` (t_s,axis,dir,x_mm,y_mm,z_mm, one line per
 * step edge; spindle lines "s" skipped) as one pass of tip points: the machine's position is the
 * programmed point (the tip, or the corner's centre with --output centre). */
static int load_trace(const dc_args_t *a, cs_dcpath_t *p)
{
    FILE *f = fopen(a->trace, "r");
    if (!f) {
        fprintf(stderr, "%s:0:0: cannot read: %s\n", a->trace, strerror(errno));
        return CS_EXIT_INPUT;
    }
    char line[256];
    double(*pt)[3] = NULL;
    size_t n = 0, cap = 0, ln = 0;
    int st = CS_EXIT_OK;
    while (st == CS_EXIT_OK && fgets(line, sizeof line, f)) {
        double t, x, y, z;
        char ax;
        int dir;
        if (++ln == 1 && strncmp(line, "t_s,", 4) == 0)
            continue;
        if (sscanf(line, "%lf,%c,%d,%lf,%lf,%lf", &t, &ax, &dir, &x, &y, &z) != 6) {
            fprintf(stderr, "%s:%zu:1: not a curvestep-sim --trace line\n", a->trace, ln);
            st = CS_EXIT_INPUT;
        } else if (ax != 's') {
            if (n == cap && !cs_path_grow((void **)&pt, &cap, n + 1, sizeof *pt))
                st = CS_EXIT_INTERNAL;
            else
                memcpy(pt[n++], (double[3]){x, y, a->centre ? z - a->tool.c_mm : z}, sizeof *pt);
        }
    }
    fclose(f);
    if (st == CS_EXIT_OK && n < 2) {
        fprintf(stderr, "%s:%zu:1: the trace holds no move\n", a->trace, ln);
        st = CS_EXIT_INPUT;
    }
    if (st == CS_EXIT_OK && cs_dcpath_append(p, (const double(*)[3])pt, n, 0) != CS_OK)
        st = CS_EXIT_INTERNAL;
    free(pt);
    return st;
}

/* --check-trace: the check of item 6 on the path a machine (the simulator) executed. */
static int check_trace(dc_args_t *a, const cs_surffile_t *sf)
{
    cs_dropcut_mesh_t ms;
    cs_dcpath_t p;
    cs_dcpath_init(&p);
    int status = build_mesh(a, sf, &ms);
    if (status == CS_EXIT_OK)
        status = load_trace(a, &p);
    if (status == CS_EXIT_OK) {
        fprintf(stderr, "toolpath: checking the executed path %s: %zu positions\n", a->trace, p.n);
        status = report_check(a, sf, &p, ms.eps);
    }
    cs_dcpath_free(&p);
    cs_dropcut_free(&ms);
    return status;
}

int cs_cmd_toolpath_drop(int argc, char **argv)
{
    dc_args_t a;
    memset(&a, 0, sizeof a);
    a.scale = 1;
    a.tol = DC_DEFAULT_TOL;
    a.feed = DC_DEFAULT_FEED;
    a.plunge = DC_DEFAULT_PLUNGE;
    int st = parse_args(argc, argv, &a);
    if (st != CS_EXIT_OK)
        return st;
    a.name = strcmp(a.file, "-") == 0 ? "<stdin>" : a.file;
    cs_surffile_t sf;
    st = cs_surffile_load("curvestep toolpath", a.file, a.scale, a.tol / 4, &sf);
    if (st != CS_EXIT_OK)
        return st;
    st = a.trace ? check_trace(&a, &sf) : plan_and_write(&a, &sf);
    if (fflush(stdout) != 0 && st == CS_EXIT_OK)
        st = CS_EXIT_INTERNAL;
    cs_surffile_free(&sf);
    return st;
}
