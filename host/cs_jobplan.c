/* cs_jobplan: read a job, plan it whole, map its errors (see cs_jobplan.h). */
#include "cs_jobplan.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_cmd.h"
#include "cs_conv.h"
#include "cs_input.h"
#include "cs_pen.h"
#include "cs_readall.h"

void cs_jobplan_opts_init(cs_jobplan_opts_t *o)
{
    memset(o, 0, sizeof *o);
    cs_jobopts_init(&o->in);
}

int cs_jobplan_option(const char *cmd, int argc, char **argv, int *i, cs_jobplan_opts_t *o)
{
    const char *a = argv[*i];
    int r = cs_jobopts_option(cmd, argc, argv, i, &o->in);
    if (r != 0)
        return r;
    if (*i + 1 >= argc)
        return 0; /* no value: the caller's "unknown or incomplete option" */
    char *end;
    if (strcmp(a, "--machine") == 0) {
        o->machine_file = argv[++*i];
    } else if (strcmp(a, "--font") == 0) {
        o->font_file = argv[++*i];
    } else if (strcmp(a, "--tol") == 0) {
        o->tol_mm = strtod(argv[++*i], &end);
        if (*end != '\0' || !(o->tol_mm > 0)) {
            fprintf(stderr, "curvestep %s: --tol wants a positive number of mm\n", cmd);
            return -1;
        }
    } else if (strcmp(a, "--feed") == 0) {
        /* 32768 mm/s: the Q15.16 speed's range (cs_motion_speed) */
        o->feed_mm_s = strtod(argv[++*i], &end);
        if (*end != '\0' || !(o->feed_mm_s > 0) || o->feed_mm_s >= 32768) {
            fprintf(stderr, "curvestep %s: --feed wants a speed in (0, 32768) mm/s\n", cmd);
            return -1;
        }
    } else if (strcmp(a, "--max-input-mb") == 0) {
        if (!cs_readall_parse_mb(argv[++*i], &o->max_input_bytes)) {
            fprintf(stderr, "curvestep %s: --max-input-mb wants a whole number of MiB, 1 to %u\n",
                    cmd, CS_READALL_MAX_MB);
            return -1;
        }
    } else if (strcmp(a, "--max-segments") == 0) {
        unsigned long long v = strtoull(argv[++*i], &end, 10);
        if (argv[*i][0] < '0' || argv[*i][0] > '9' || *end != '\0' || v < 1 || v > SIZE_MAX / 64) {
            fprintf(stderr, "curvestep %s: --max-segments wants a positive whole number\n", cmd);
            return -1;
        }
        o->max_segs = (size_t)v;
    } else {
        return 0;
    }
    return 1;
}

void cs_jobplan_limits(cs_jobplan_t *jp, const cs_jobplan_opts_t *o)
{
    jp->max_bytes = o->max_input_bytes;
    jp->max_segs = o->max_segs;
}

bool cs_jobplan_tol(const cs_machine_t *m, double tol_mm, cs_pos_t *tol)
{
    *tol = m->tolerance;
    return !(tol_mm > 0) || cs_conv_tol_to_pos(tol_mm, tol) == CS_OK;
}

int cs_jobplan_machine(const char *cmd, const cs_jobplan_opts_t *o, cs_machine_t *m,
                       cs_machine_pen_t *pen, cs_pos_t *tol)
{
    cs_machine_ini_pen_default(pen);
    if (cs_jobopts_check(cmd, &o->in) != 0)
        return CS_EXIT_USAGE;
    char err[512], who[64];
    snprintf(who, sizeof who, "curvestep %s", cmd);
    if (cs_machine_ini_open(who, o->machine_file, m, pen, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return CS_EXIT_INPUT;
    }
    if (!cs_jobplan_tol(m, o->tol_mm, tol)) {
        fprintf(stderr, "curvestep %s: --tol %g mm is outside the accepted range\n", cmd,
                o->tol_mm);
        return CS_EXIT_USAGE;
    }
    return CS_EXIT_OK;
}

void cs_jobplan_init(cs_jobplan_t *jp)
{
    memset(jp, 0, sizeof *jp);
    cs_path_init(&jp->path);
}

static cs_err_t pen_lift(cs_jobplan_t *jp);

cs_err_t cs_jobplan_read(cs_jobplan_t *jp, const char *file, const cs_machine_pen_t *pen,
                         bool lenient)
{
    cs_jobopts_t in;
    cs_jobopts_init(&in);
    in.lenient = lenient;
    cs_err_t e = cs_jobplan_read_opts(jp, file, pen, &in);
    return e == CS_OK ? pen_lift(jp) : e;
}

cs_err_t cs_jobplan_read_opts(cs_jobplan_t *jp, const char *file, const cs_machine_pen_t *pen,
                              const cs_jobopts_t *in)
{
    cs_input_opts_t iopts;
    cs_input_opts_init(&iopts);
    cs_jobopts_input(in, &iopts);
    iopts.font_file = jp->font_file;
    cs_input_format_t fmt = CS_INPUT_AUTO;
    iopts.detected = &fmt;
    cs_machine_ini_pen_default(&jp->pen);
    iopts.max_bytes = jp->max_bytes;
    iopts.regular_only = jp->regular_only;
    if (pen != NULL) {
        jp->pen = *pen;
        /* [pen] mode = z: G-code M3/M4 (pen down) and M5 (pen up) become Z moves at z_feed. */
        iopts.pen_z = pen->mode == CS_MACHINE_PEN_Z;
        iopts.pen_up_z_mm = pen->up_z_mm;
        iopts.pen_down_z_mm = pen->down_z_mm;
        iopts.pen_z_feed_mm_s = pen->z_feed_mm_s;
    }
    cs_err_t e = cs_input_load(file, &iopts, &jp->path, &jp->diag);
    jp->gcode = fmt == CS_INPUT_GCODE;
    jp->read_ok = e == CS_OK;
    return e;
}

/* SVG and HP-GL have no pen height of their own: with [pen] mode = z the pen is lifted between
 * their strokes (G-code's M3/M5 did it while reading). After layout, merge and sort, which
 * work on the drawn strokes alone. */
static cs_err_t pen_lift(cs_jobplan_t *jp)
{
    jp->pen_raise = !jp->gcode && jp->pen.mode == CS_MACHINE_PEN_Z;
    cs_err_t e = jp->pen_raise ? cs_pen_lift_z(&jp->path, &jp->pen, &jp->diag) : CS_OK;
    jp->read_ok = e == CS_OK;
    return e;
}

cs_err_t cs_jobplan_prepare(cs_jobplan_t *jp, const char *cmd, const cs_jobopts_t *in,
                            const cs_machine_t *m, const cs_machine_pen_t *pen, cs_pos_t tol,
                            FILE *report)
{
    bool plotter = pen != NULL && pen->mode != CS_MACHINE_PEN_NONE;
    cs_err_t e = cs_jobopts_prepare(in, cmd, m, plotter, cs_conv_pos_to_mm(tol), &jp->path,
                                    &jp->diag, report);
    jp->read_ok = e == CS_OK;
    return e == CS_OK ? pen_lift(jp) : e;
}

cs_err_t cs_jobplan_reference(cs_jobplan_t *jp, const char *file, const cs_jobopts_t *in,
                              const char *machine_file, const cs_machine_t *m)
{
    cs_machine_pen_t pen;
    cs_machine_t scratch;
    char err[512];
    char found[4096];
    cs_machine_ini_pen_default(&pen);
    /* The same file the caller's cs_machine_ini_open used: given, or the default one found. */
    if (machine_file == NULL && cs_machine_ini_find(found, sizeof found))
        machine_file = found;
    if (machine_file != NULL &&
        cs_machine_ini_load_pen(machine_file, &scratch, &pen, err, sizeof err) != 0)
        cs_machine_ini_pen_default(&pen); /* the caller loaded (and checked) it already */
    cs_err_t e = cs_jobplan_read_opts(jp, file, &pen, in);
    return e == CS_OK ? cs_jobplan_prepare(jp, "sim", in, m, &pen, m->tolerance, NULL) : e;
}

/* diag "file: reason" for an error that has no place in the file. */
static cs_err_t fail_whole(cs_jobplan_t *jp, const char *file, cs_err_t e, const char *reason)
{
    snprintf(jp->diag.reason, sizeof jp->diag.reason, "%s", reason);
    jp->diag.loc.file = file;
    return e;
}

cs_err_t cs_jobplan_plan(cs_jobplan_t *jp, const char *file, const cs_machine_t *m,
                         const cs_pos_t *start, cs_pos_t tol, int method, int32_t feed)
{
    cs_err_t e = cs_motion_init(&jp->mo, m);
    if (e != CS_OK)
        return fail_whole(jp, file, e, "machine rejected");
    jp->have_mo = true;
    jp->mo.pen = &jp->pen; /* mode servo: pen events between the strokes */
    jp->mo.max_segs = jp->max_segs;
    if (start != NULL && (e = cs_planner_set_position(&jp->mo.pl, start)) != CS_OK)
        return fail_whole(jp, file, e, "the device's position is outside the machine's travel");
    if (jp->pen_raise) { /* the pen up where the machine stands, before the first travel */
        const cs_pos_t *p = jp->mo.pl.pos;
        double up = jp->pen.up_z_mm;
        e = cs_motion_line_mm(&jp->mo, cs_conv_pos_to_mm(p[0]), cs_conv_pos_to_mm(p[1]), up,
                              jp->pen.z_feed_mm_s, 0);
        if (e != CS_OK)
            return fail_whole(jp, file, e, "raising the pen failed");
    }
    /* G64 P: the program asks for its path to be kept within P; curvestep never blends
     * corners away, so that bounds the chords when it is tighter than the tolerance in use. */
    cs_pos_t ptol;
    if (jp->path.blend_tol_mm > 0 && cs_conv_tol_to_pos(jp->path.blend_tol_mm, &ptol) == CS_OK &&
        ptol < tol)
        tol = ptol;
    return cs_motion_plan_path(&jp->mo, &jp->path, tol, method, feed, &jp->diag);
}

cs_err_t cs_jobplan_linkable(cs_jobplan_t *jp, const char *file, bool pens, bool curves)
{
    (void)curves; /* curves mode carries them too (cs_stream_pen) */
    if (jp->mo.segs.npens == 0 || pens)
        return CS_OK;
    return fail_whole(jp, file, CS_ERR_UNSUPPORTED,
                      "[pen] mode = servo: this link does not carry pen events (the serial, Modbus "
                      "and GPIO links do); use mode = z or a G-code M3/M5 spindle pen");
}

int cs_jobplan_exit(const cs_jobplan_t *jp, cs_err_t e)
{
    if (!jp->read_ok)
        return e == CS_ERR_FULL ? CS_EXIT_INTERNAL : CS_EXIT_INPUT;
    /* CS_ERR_DEPTH: a curve the tracer cannot bring within the tolerance in its bounded depth
     * is the job's (or the tolerance's) doing, as is a tolerance it cannot meet */
    return (e == CS_ERR_LIMIT || e == CS_ERR_RANGE || e == CS_ERR_TOLERANCE || e == CS_ERR_DEPTH ||
            e == CS_ERR_UNSUPPORTED)
               ? CS_EXIT_INPUT
               : CS_EXIT_INTERNAL;
}

void cs_jobplan_free(cs_jobplan_t *jp)
{
    if (jp->have_mo)
        cs_motion_free(&jp->mo);
    jp->have_mo = false;
    cs_path_free(&jp->path);
}
