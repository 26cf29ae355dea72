/* cs_jobplan: the planning that every job command shares (`curvestep plan`, `curvestep stream`,
 * the daemon's SUBMIT): the options --machine/--tol/--feed, the machine (and its [pen]) from a
 * machine file, the job read whole by cs_input, planned whole into step segments by cs_motion,
 * and the exit status an error maps to. Owns the job's path and segments. Host only. */
#ifndef CS_JOBPLAN_H
#define CS_JOBPLAN_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_jobopts.h"
#include "cs_machine_ini.h"
#include "cs_motion.h"
#include "cs_path.h"

/* The options the job commands share. */
typedef struct {
    const char *machine_file; /* --machine FILE.ini; NULL: the built-in machine */
    double tol_mm;            /* --tol MM; 0: the machine's tolerance */
    double feed_mm_s;         /* --feed MM/S; 0: the machine's default_feed */
    const char *font_file;    /* --font FILE.jhf: stroke font for text; NULL: the default */
    cs_jobopts_t in;          /* the shared input and layout options (cs_jobopts) */
    size_t max_input_bytes;   /* --max-input-mb N; 0: CS_READALL_DEFAULT_MAX (64 MiB) */
    size_t max_segs;          /* --max-segments N; 0: CS_MOTION_MAX_SEGS */
} cs_jobplan_opts_t;

/* One job: read, then planned. */
typedef struct {
    cs_path_t path;      /* the job's elements (cs_jobplan_read) */
    cs_motion_t mo;      /* its step segments and totals (cs_jobplan_plan, when have_mo) */
    cs_path_diag_t diag; /* after an error: "file:line:col: reason" (cs_path_diag_print) */
    bool have_mo;        /* mo was initialised (and must be freed) */
    bool read_ok;        /* the file was read: a later error is the planner's */
    cs_machine_pen_t pen;  /* the [pen] the job was read with (cs_jobplan_read) */
    bool pen_raise;        /* cs_pen lifted the job: the plan starts by raising the pen in place */
    bool gcode;            /* the job was G-code (its own M3/M5 lift the pen) */
    const char *font_file; /* stroke font for text (set before cs_jobplan_read); NULL: default */
    size_t max_bytes;    /* input size limit (cs_readall; 0: its default) */
    size_t max_segs;     /* segment limit (cs_motion_t.max_segs; 0: its default) */
    bool regular_only;   /* refuse FIFOs, devices, directories (the daemon) */
} cs_jobplan_t;

/* No machine file, no --tol, no --feed, cs_jobopts_init. */
void cs_jobplan_opts_init(cs_jobplan_opts_t *o);
/* argv[*i] is --machine FILE, --tol MM, --feed MM/S, --font FILE, --max-input-mb N or
 * --max-segments N with its value, or one of the shared input options (cs_jobopts_option): stores
 * it, moves *i onto the value and returns 1; any other word: 0; a bad value: -1, after "curvestep
 * CMD: --tol wants ..." on stderr (a usage error). */
int cs_jobplan_option(const char *cmd, int argc, char **argv, int *i, cs_jobplan_opts_t *o);
/* Chord tolerance: tol_mm (> 0) converted, else the machine's. False when tol_mm is outside
 * what cs_conv accepts. */
bool cs_jobplan_tol(const cs_machine_t *m, double tol_mm, cs_pos_t *tol);
/* The machine of o->machine_file with its [pen] (cs_machine_ini_load_pen), or the built-in one
 * with no pen, and the chord tolerance (cs_jobplan_tol). Returns CS_EXIT_OK; CS_EXIT_INPUT after
 * "file:line: reason" on stderr; CS_EXIT_USAGE after "curvestep CMD: --tol ..." (or a bad
 * combination of the shared options, cs_jobopts_check) on stderr. */
int cs_jobplan_machine(const char *cmd, const cs_jobplan_opts_t *o, cs_machine_t *m,
                       cs_machine_pen_t *pen, cs_pos_t *tol);

/* Empty job: no path, no segments, diag cleared, default limits. */
void cs_jobplan_init(cs_jobplan_t *jp);
/* The limits of o (--max-input-mb, --max-segments) for the next read and plan of jp. */
void cs_jobplan_limits(cs_jobplan_t *jp, const cs_jobplan_opts_t *o);
/* Reads file (cs_input_load: SVG, G-code, HP-GL) into jp->path. pen (NULL: none) with mode = z
 * turns G-code M3/M4 and M5 into rapid Z moves to its down_z / up_z, and lifts the pen between
 * the strokes of SVG and HP-GL drawings (cs_pen_lift_z); lenient: unsupported G-code words are
 * warnings. CS_OK, or an error with jp->diag filled. */
cs_err_t cs_jobplan_read(cs_jobplan_t *jp, const char *file, const cs_machine_pen_t *pen,
                         bool lenient);
/* cs_jobplan_read with the shared input options in (lenient, dialect, units), without the pen
 * lifts between SVG and HP-GL strokes: cs_jobplan_prepare adds them after layout and order. */
cs_err_t cs_jobplan_read_opts(cs_jobplan_t *jp, const char *file, const cs_machine_pen_t *pen,
                              const cs_jobopts_t *in);
/* After a read: the layout, merge and sort of in (cs_jobopts_prepare) on machine m, then the
 * pen lifts of a [pen] mode = z drawing (cs_pen_lift_z); merge
 * distance tol, plotter defaults when pen has a mode; the merge/sort line to report (NULL:
 * none), prefixed cmd. CS_OK, or an error with jp->diag filled (an input error). */
cs_err_t cs_jobplan_prepare(cs_jobplan_t *jp, const char *cmd, const cs_jobopts_t *in,
                            const cs_machine_t *m, const cs_machine_pen_t *pen, cs_pos_t tol,
                            FILE *report);
/* The job as plan reads and lays it out, for a check against it (curvestep-sim --reference):
 * the machine file's [pen] (NULL file: none), cs_jobplan_read_opts, then cs_jobplan_prepare
 * with m's tolerance and no report. CS_OK, or an error with jp->diag filled. */
cs_err_t cs_jobplan_reference(cs_jobplan_t *jp, const char *file, const cs_jobopts_t *in,
                              const char *machine_file, const cs_machine_t *m);
/* Plans jp->path whole on machine m (which must outlive jp; file names it in messages) from
 * start (after raising the pen there to up_z when jp->pen_raise) (cs_pos_t per axis, CS_AXES of
 * them; NULL: the origin), chords within tol by tracer method (CS_TRACE_*), at feed (mm/s Q15.16
 * from cs_motion_speed; 0: the machine's default) where the job gives none. CS_OK with jp->mo's
 * segments, or an error with jp->diag filled (CS_ERR_LIMIT: the move that leaves the travel, or a
 * start outside it). */
cs_err_t cs_jobplan_plan(cs_jobplan_t *jp, const char *file, const cs_machine_t *m,
                         const cs_pos_t *start, cs_pos_t tol, int method, int32_t feed);
/* The planned job can go down a device link: CS_OK, or CS_ERR_UNSUPPORTED with jp->diag
 * "file: ..." when it holds servo pen events and the link does not carry them (pens false).
 * Every link carries them now: the serial and Modbus links as PEN messages (docs/protocol.md),
 * in segments mode in their place among the segments, in curves mode between the curves
 * (cs_stream_pen); the GPIO link by software PWM (cs_gpio_pwm). curves no longer refuses. */
cs_err_t cs_jobplan_linkable(cs_jobplan_t *jp, const char *file, bool pens, bool curves);
/* The exit status for error e of cs_jobplan_read / _plan: a file that cannot be read as a job
 * (anything but running out of memory, CS_ERR_FULL) and a job the machine cannot do (outside the
 * travel, a number out of range, a tolerance it cannot meet, a curve too deep for the tracer)
 * are CS_EXIT_INPUT; the rest
 * CS_EXIT_INTERNAL. */
int cs_jobplan_exit(const cs_jobplan_t *jp, cs_err_t e);
/* Frees the path and the segments (jp may be freed twice). */
void cs_jobplan_free(cs_jobplan_t *jp);

#endif
