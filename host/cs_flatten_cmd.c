/* curvestep flatten: reads any input cs_input_load takes (SVG, G-code, HP-GL), traces every
 * element with the core's pull iterator (cs_trace_begin / cs_trace_next) and prints the
 * polyline, one vertex "x y" (mm, 6 decimals) per line, a blank line between subpaths.
 * Optional summary (--stats) and picture (--svg). */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_cmd.h"
#include "cs_conv.h"
#include "cs_err_text.h"
#include "cs_input.h"
#include "cs_jobopts.h"
#include "cs_machine_ini.h"
#include "cs_lensub.h"
#include "cs_motion.h"
#include "cs_readall.h"
#include "cs_path.h"
#include "cs_svgdoc.h"
#include "cs_svgout.h"
#include "cs_trace.h"

#define FLATTEN_DEFAULT_TOL_MM 0.01

static const struct {
    const char *name;
    cs_trace_method_t method;
} methods[] = {
    {"fd", CS_TRACE_FD},
    {"afd", CS_TRACE_AFD},
    {"subdiv", CS_TRACE_SUBDIV},
    {"predict", CS_TRACE_PREDICT},
    {"length", CS_TRACE_SUBDIV}, /* not a cs_trace method: cs_lensub (FLATTEN_METHOD_LENGTH) */
};

/* Seed 003's length-based subdivision: chords at most --seg-len long (cs_lensub). */
#define FLATTEN_METHOD_LENGTH      4
#define FLATTEN_DEFAULT_SEG_LEN_MM 1.0

/* The default: CS_TRACE_DEFAULT (the predicted-step tracer: near-greedy chords, proven within
 * the tolerance, several times faster than subdiv; docs/benchmarks.md). */
#define FLATTEN_DEFAULT_METHOD 3

static void flatten_usage(FILE *f)
{
    fprintf(f,
            "Usage: curvestep flatten [--tol MM] [--method fd|afd|subdiv|predict] [--stats]\n"
            "                         [--svg OUT.svg] [--font FILE.jhf] [input and layout options] FILE\n"
            "       curvestep flatten --method length [--seg-len MM] [--eval decasteljau|horner]\n"
            "                         [--stats] [--svg OUT.svg] [input and layout options] FILE\n"
            "\n"
            "Flattens the curves of FILE into chords that stay within a tolerance of the exact\n"
            "curves, and prints the polyline: one vertex \"x y\" per line in millimetres (6\n"
            "decimals), a blank line between subpaths.\n"
            "\n"
            "FILE is G-code (.nc .gcode .ngc .g .tap .cnc: G0 G1 G2 G3 G5 G5.1 G5.2 G6.2,\n"
            "LinuxCNC parameters, expressions and O-words; see docs/inputs.md), HP-GL\n"
            "(.plt .hpgl .hgl .hpg), AutoCAD DXF (.dxf, ASCII: lines, arcs, ellipses, polylines\n"
            "with bulges, splines, text, blocks; $INSUNITS gives the unit, docs/inputs.md),\n"
            "a curves file (.curves, or first word \"curvestep-curves\":\n"
            "every basis, docs/inputs.md), or, for .svg .txt .d and by default,\n"
            "an SVG document (<path>, <rect>, <circle>, <ellipse>, <line>, <polyline>,\n"
            "<polygon>, with every transform; width/height/viewBox map it to millimetres;\n"
            "fills are drawn as outlines; <text> is drawn in a stroke font; <use> is not drawn:\n"
            "a warning on stderr names it) or a file holding bare SVG path data (M L H V C S Q T A "
            "Z, absolute\n"
            "and relative); other names and '-' (standard input) are recognised by their\n"
            "content. SVG without width/height and bare path data: 1 user unit = 1 mm. An SVG\n"
            "document's page is turned y-up (y' = page height - y: the drawing as a browser\n"
            "shows it); G-code, HP-GL, DXF and bare path data keep their axes. Coordinates must\n"
            "stay within +/-%d mm.\n"
            "\n"
            "Options:\n"
            "  --tol MM        chord tolerance in mm (default %g; from %.7f to %d)\n"
            "  --method M      fd (uniform forward differences), afd (adaptive forward\n"
            "                  differences), subdiv (flatness subdivision) or predict\n"
            "                  (predicted step verified by one flatness test; the default),\n"
            "                  or length, seed 003's length-based subdivision: chords at most\n"
            "                  --seg-len long, with no promise on the deviation (--tol is not\n"
            "                  used; --stats measures the deviation)\n"
            "  --seg-len MM    longest chord of --method length (default %g)\n"
            "  --eval E        how --method length evaluates points: decasteljau (the default)\n"
            "                  or horner (power basis, Horner's rule; rational curves keep de\n"
            "                  Casteljau)\n"
            "  --stats         print a summary on stderr: elements, chords, and the largest\n"
            "                  deviation of a chord from its exact curve, measured in double on\n"
            "                  the host\n"
            "  --svg OUT.svg   also write a picture: exact curves, chords and their vertices\n"
            "  --font FILE.jhf Hershey stroke font for SVG <text>, HP-GL LB and DXF TEXT (default:\n"
            "                  share/fonts/futural.jhf; a file that is not a font is an error)\n"
            "  --max-input-mb N  refuse a FILE larger than N MiB (default 64; docs/inputs.md)\n"
            "  -h, --help      show this help\n",
            CS_POS_LIMIT_MM, FLATTEN_DEFAULT_TOL_MM, (double)CS_TRACE_TOL_MIN / CS_POS_ONE_MM,
            CS_POS_LIMIT_MM, FLATTEN_DEFAULT_SEG_LEN_MM);
    cs_jobopts_help(f);
    fprintf(f,
            "--fit uses the built-in machine's travel (or --page); merge and sort are off\n"
            "unless asked for. The chords printed are those of the laid-out drawing.\n"
            "\n"
            "Exit status: 0 success; 1 bad input (\"file:line:col: reason\" on stderr, including\n"
            "coordinates outside the range); 2 usage error; 3 internal error (arithmetic overflow\n"
            "or depth limit while tracing, out of memory, write error).\n");
}

/* Exit status for a code met while reading input. */
static int input_status(cs_err_t e)
{
    return (e == CS_ERR_FULL || e == CS_ERR_OVERFLOW) ? CS_EXIT_INTERNAL : CS_EXIT_INPUT;
}

typedef struct {
    cs_vec3_t *v;
    size_t n, cap;
} vbuf_t;

static bool vbuf_push(vbuf_t *b, cs_vec3_t p)
{
    if (b->n == b->cap) {
        size_t ncap = b->cap ? 2 * b->cap : 256;
        cs_vec3_t *nv = realloc(b->v, ncap * sizeof *nv);
        if (!nv)
            return false;
        b->v = nv;
        b->cap = ncap;
    }
    b->v[b->n++] = p;
    return true;
}

/* Takes the shared input options (cs_jobopts) out of argv (getopt sees the rest): 0, or the
 * exit status of a bad value or combination. */
static int take_jobopts(int *argc, char **argv, cs_jobopts_t *in)
{
    int k = 1;
    for (int i = 1; i < *argc; i++) {
        int r = cs_jobopts_option("flatten", *argc, argv, &i, in);
        if (r < 0)
            return CS_EXIT_USAGE;
        if (r > 0)
            continue;
        bool valued = strcmp(argv[i], "--tol") == 0 || strcmp(argv[i], "--method") == 0 ||
                      strcmp(argv[i], "--svg") == 0;
        argv[k++] = argv[i];
        if (valued && i + 1 < *argc)
            argv[k++] = argv[++i];
    }
    *argc = k;
    return cs_jobopts_check("flatten", in) != 0 ? CS_EXIT_USAGE : 0;
}

/* The command line, parsed. */
typedef struct {
    double tol_mm;
    size_t method;
    bool stats;
    const char *svg_out;
    const char *font;
    cs_jobopts_t in;
    double seg_len_mm;
    bool horner, eval_given;
    size_t max_bytes;
    const char *file;
} flatten_opts_t;

/* One option (getopt's code c, its value optarg): 0 to go on, or the exit status (--help: 0
 * after the usage, as -1 would be ambiguous it returns CS_EXIT_OK). */
static int parse_opt(int c, char **argv, flatten_opts_t *o)
{
    char *end = NULL;
    cs_pos_t t = 0;
    switch (c) {
    case 't':
        o->tol_mm = strtod(optarg, &end);
        /* The tracers accept CS_TRACE_TOL_MIN LSB and up (their rounding budget is charged
         * against the tolerance); the host refuses more than the coordinate range. */
        if (!end || end == optarg || *end != '\0' || cs_conv_tol_to_pos(o->tol_mm, &t) != CS_OK ||
            t < CS_TRACE_TOL_MIN || t > CS_TRACE_TOL_MAX) {
            fprintf(stderr,
                    "curvestep flatten: --tol '%s': expected a tolerance in mm, from %.7f "
                    "(%d LSB) to %d\n",
                    optarg, (double)CS_TRACE_TOL_MIN / CS_POS_ONE_MM, CS_TRACE_TOL_MIN,
                    CS_POS_LIMIT_MM);
            return CS_EXIT_USAGE;
        }
        return -1;
    case 'm': {
        size_t k = 0;
        while (k < sizeof methods / sizeof methods[0] && strcmp(methods[k].name, optarg) != 0)
            k++;
        if (k == sizeof methods / sizeof methods[0]) {
            fprintf(stderr,
                    "curvestep flatten: --method '%s': expected fd, afd, subdiv, predict or length\n",
                    optarg);
            return CS_EXIT_USAGE;
        }
        o->method = k;
        return -1;
    }
    case 's':
        o->stats = true;
        return -1;
    case 'o':
        o->svg_out = optarg;
        return -1;
    case 'f':
        o->font = optarg;
        return -1;
    case 'L':
        o->seg_len_mm = strtod(optarg, &end);
        if (!end || end == optarg || *end != '\0' || cs_conv_tol_to_pos(o->seg_len_mm, &t) != CS_OK) {
            fprintf(stderr,
                    "curvestep flatten: --seg-len '%s': expected a length in mm, "
                    "from 1 LSB (0.0000153) to 4096\n",
                    optarg);
            return CS_EXIT_USAGE;
        }
        return -1;
    case 'E':
        o->eval_given = true;
        o->horner = strcmp(optarg, "horner") == 0;
        if (!o->horner && strcmp(optarg, "decasteljau") != 0) {
            fprintf(stderr, "curvestep flatten: --eval '%s': expected decasteljau or horner\n",
                    optarg);
            return CS_EXIT_USAGE;
        }
        return -1;
    case 'M':
        if (!cs_readall_parse_mb(optarg, &o->max_bytes)) {
            fprintf(stderr,
                    "curvestep flatten: --max-input-mb '%s': expected a whole number of MiB, "
                    "1 to %u\n",
                    optarg, CS_READALL_MAX_MB);
            return CS_EXIT_USAGE;
        }
        return -1;
    case 'h':
        flatten_usage(stdout);
        return CS_EXIT_OK;
    case ':':
        fprintf(stderr, "curvestep flatten: option '%s' needs a value\n", argv[optind - 1]);
        fprintf(stderr, "Try 'curvestep flatten --help'.\n");
        return CS_EXIT_USAGE;
    default:
        fprintf(stderr, "curvestep flatten: unknown option '%s'\n", argv[optind - 1]);
        fprintf(stderr, "Try 'curvestep flatten --help'.\n");
        return CS_EXIT_USAGE;
    }
}

/* Parses argv into *o: -1 to run, or the exit status (usage errors, --help). */
static int parse_args(int argc, char **argv, flatten_opts_t *o)
{
    static const struct option longopts[] = {
        {"tol", required_argument, NULL, 't'},
        {"method", required_argument, NULL, 'm'},
        {"stats", no_argument, NULL, 's'},
        {"svg", required_argument, NULL, 'o'},
        {"help", no_argument, NULL, 'h'},
        {"font", required_argument, NULL, 'f'},
        {"seg-len", required_argument, NULL, 'L'},
        {"eval", required_argument, NULL, 'E'},
        {"max-input-mb", required_argument, NULL, 'M'},
        {NULL, 0, NULL, 0},
    };
    memset(o, 0, sizeof *o);
    o->tol_mm = FLATTEN_DEFAULT_TOL_MM;
    o->method = FLATTEN_DEFAULT_METHOD;
    o->seg_len_mm = FLATTEN_DEFAULT_SEG_LEN_MM;
    cs_jobopts_init(&o->in);
    int r = take_jobopts(&argc, argv, &o->in);
    if (r != 0)
        return r;
    int c;
    optind = 1;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":h", longopts, NULL)) != -1)
        if ((r = parse_opt(c, argv, o)) >= 0)
            return r;
    if (optind != argc - 1) {
        fprintf(stderr, "curvestep flatten: %s\n",
                optind >= argc ? "missing FILE" : "expected exactly one FILE");
        fprintf(stderr, "Try 'curvestep flatten --help'.\n");
        return CS_EXIT_USAGE;
    }
    if (o->eval_given && o->method != FLATTEN_METHOD_LENGTH) {
        fprintf(stderr, "curvestep flatten: --eval applies to --method length (the other "
                        "tracers step their own differences)\n");
        return CS_EXIT_USAGE;
    }
    o->file = argv[optind];
    return -1;
}

/* What a run made: the polyline, the chords counted, the worst deviation (--stats). */
typedef struct {
    cs_path_poly_t poly;
    vbuf_t vb;
    size_t nchords;
    double maxdev;
    size_t maxdev_elem;
} flatten_run_t;

/* Starts element el's polyline where it starts (a new subpath, or a jump). 0 or an exit status. */
static int start_elem(const cs_path_t *path, size_t i, flatten_run_t *fr)
{
    const cs_bezier_t *cv = &path->elems[i].curve;
    bool new_sub = i == 0 || path->elems[i].subpath != path->elems[i - 1].subpath;
    const cs_vec3_t *prev_end =
        i > 0 ? &path->elems[i - 1].curve.p[path->elems[i - 1].curve.degree] : NULL;
    if (new_sub || prev_end->x != cv->p[0].x || prev_end->y != cv->p[0].y) {
        if (i > 0 && new_sub)
            putchar('\n');
        double x = cs_conv_pos_to_mm(cv->p[0].x), y = cs_conv_pos_to_mm(cv->p[0].y);
        printf("%.6f %.6f\n", x, y);
        if ((new_sub ? cs_path_poly_move(&fr->poly, x, y) : cs_path_poly_line(&fr->poly, x, y)) !=
            CS_OK) {
            fprintf(stderr, "curvestep flatten: out of memory\n");
            return CS_EXIT_INTERNAL;
        }
    }
    fr->vb.n = 0;
    if (!vbuf_push(&fr->vb, cv->p[0])) {
        fprintf(stderr, "curvestep flatten: out of memory\n");
        return CS_EXIT_INTERNAL;
    }
    return CS_EXIT_OK;
}

/* Traces element i of path, printing its chords. An exit status (CS_EXIT_OK). */
static int trace_elem(const flatten_opts_t *o, const cs_path_t *path, size_t i, cs_pos_t tol,
                      cs_pos_t seg_len, flatten_run_t *fr, cs_path_diag_t *diag)
{
    const cs_path_elem_t *el = &path->elems[i];
    const cs_bezier_t *cv = &el->curve;
    int status = start_elem(path, i, fr);
    if (status != CS_EXIT_OK)
        return status;
    cs_trace_t tr;
    cs_lensub_t ls;
    bool by_length = o->method == FLATTEN_METHOD_LENGTH;
    cs_err_t e = by_length ? cs_lensub_begin(&ls, cv, seg_len, o->horner && !cv->rational)
                           : cs_trace_begin(&tr, cv, tol, methods[o->method].method);
    if (e == CS_ERR_TOLERANCE) {
        fprintf(stderr, "curvestep flatten: --tol %g: %s (method %s)\n", o->tol_mm,
                cs_err_text(e), methods[o->method].name);
        return CS_EXIT_USAGE;
    }
    cs_vec3_t pt;
    while (e == CS_OK &&
           (e = by_length ? cs_lensub_next(&ls, &pt) : cs_trace_next(&tr, &pt)) == CS_OK) {
        if (++fr->nchords > CS_MOTION_MAX_SEGS) { /* bounded memory: the plan's own limit */
            e = CS_ERR_RANGE;
            break;
        }
        printf("%.6f %.6f\n", cs_conv_pos_to_mm(pt.x), cs_conv_pos_to_mm(pt.y));
        if (cs_path_poly_line(&fr->poly, cs_conv_pos_to_mm(pt.x), cs_conv_pos_to_mm(pt.y)) !=
                CS_OK ||
            !vbuf_push(&fr->vb, pt)) {
            e = CS_ERR_FULL;
            break;
        }
    }
    if (e == CS_ERR_RANGE) {
        cs_path_diag_set(diag, e, el->loc,
                         "more than %zu chords: too large to flatten (docs/inputs.md, Limits)",
                         CS_MOTION_MAX_SEGS);
        cs_path_diag_print(stderr, diag);
        return CS_EXIT_INPUT;
    }
    if (e != CS_END) {
        cs_path_diag_set(diag, e, el->loc, "cannot trace this curve: %s", cs_err_text(e));
        cs_path_diag_print(stderr, diag);
        return CS_EXIT_INTERNAL;
    }
    if (o->stats) {
        double d = cs_path_deviation_mm(cv, fr->vb.v, fr->vb.n);
        if (d > fr->maxdev || i == 0) {
            fr->maxdev = d;
            fr->maxdev_elem = i;
        }
    }
    return CS_EXIT_OK;
}

/* --stats: the counts and the worst deviation on stderr. An exit status. */
static int report_stats(const flatten_opts_t *o, const char *shown, const cs_path_t *path,
                        const flatten_run_t *fr)
{
    fprintf(stderr, "flatten: %s: %zu elements in %u subpaths, %zu chords (%zu vertices)\n", shown,
            path->n, path->nsubpaths, fr->nchords, fr->poly.n);
    if (o->method == FLATTEN_METHOD_LENGTH)
        fprintf(stderr, "flatten: method length (%s), chords at most %.6g mm\n",
                o->horner ? "horner" : "decasteljau", o->seg_len_mm);
    else
        fprintf(stderr, "flatten: method %s, tolerance %.6g mm\n", methods[o->method].name,
                o->tol_mm);
    if (path->n == 0) {
        fprintf(stderr, "flatten: max deviation 0.000000 mm (nothing to trace)\n");
        return CS_EXIT_OK;
    }
    const cs_path_loc_t *l = &path->elems[fr->maxdev_elem].loc;
    if (isinf(fr->maxdev)) {
        fprintf(stderr, "%s:%u:%u: internal error: the tracer returned a vertex off this curve\n",
                l->file, l->line, l->col);
        return CS_EXIT_INTERNAL;
    }
    fprintf(stderr,
            "flatten: max deviation %.6f mm (measured in double on the host against "
            "the exact curves; element at %s:%u:%u)\n",
            fr->maxdev, l->file, l->line, l->col);
    return CS_EXIT_OK;
}

/* Reads and lays out the job. CS_EXIT_OK, or the exit status after the located error. */
static int load(const flatten_opts_t *o, cs_path_t *path, cs_path_diag_t *diag)
{
    cs_input_opts_t iopts;
    cs_input_opts_init(&iopts);
    cs_jobopts_input(&o->in, &iopts);
    iopts.font_file = o->font;
    iopts.max_bytes = o->max_bytes;
    cs_err_t e = cs_input_load(o->file, &iopts, path, diag);
    cs_machine_t m;
    cs_machine_ini_default(&m); /* --fit: the built-in machine's travel */
    if (e == CS_OK)
        e = cs_jobopts_prepare(&o->in, "flatten", &m, false, o->tol_mm, path, diag, stderr);
    if (e == CS_OK)
        return CS_EXIT_OK;
    cs_path_diag_print(stderr, diag);
    return input_status(e);
}

int cs_cmd_flatten(int argc, char **argv)
{
    flatten_opts_t o;
    int status = parse_args(argc, argv, &o);
    if (status >= 0)
        return status;
    const char *shown = strcmp(o.file, "-") == 0 ? "<stdin>" : o.file;
    cs_pos_t seg_len, tol;
    cs_conv_tol_to_pos(o.seg_len_mm, &seg_len); /* validated above */
    cs_conv_tol_to_pos(o.tol_mm, &tol);         /* validated above */
    cs_path_t path;
    cs_path_init(&path);
    cs_path_diag_t diag;
    if ((status = load(&o, &path, &diag)) != CS_EXIT_OK) {
        cs_path_free(&path);
        return status;
    }
    flatten_run_t fr;
    memset(&fr, 0, sizeof fr);
    cs_path_poly_init(&fr.poly);
    for (size_t i = 0; i < path.n && status == CS_EXIT_OK; i++)
        status = trace_elem(&o, &path, i, tol, seg_len, &fr, &diag);
    if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "curvestep flatten: error writing the output\n");
        if (status == CS_EXIT_OK)
            status = CS_EXIT_INTERNAL;
    }
    if (o.stats && status == CS_EXIT_OK)
        status = report_stats(&o, shown, &path, &fr);
    if (o.svg_out && status == CS_EXIT_OK) {
        cs_svgout_opts_t so;
        cs_svgout_opts_init(&so);
        so.title = shown;
        so.method = methods[o.method].name;
        so.tol_mm = o.tol_mm;
        so.max_dev_mm = o.stats && !isinf(fr.maxdev) ? fr.maxdev : -1.0;
        if (cs_svgout_write(o.svg_out, &path, &fr.poly, &so, &diag) == CS_ERR_IO) {
            cs_path_diag_print(stderr, &diag);
            status = CS_EXIT_INTERNAL;
        }
    }
    free(fr.vb.v);
    cs_path_poly_free(&fr.poly);
    cs_path_free(&path);
    return status;
}
