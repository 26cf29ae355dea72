/* cs_motion: the host's motion driver. Feeds moves to the core planner, keeps the look-ahead
 * ring full (segments are cut only when the ring is full or at the end of the job) and collects
 * the step segments in a growable array, with the job's totals. Shared by `curvestep plan`, the
 * simulator and the tests. */
#ifndef CS_MOTION_H
#define CS_MOTION_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <stdint.h>

#include "cs_machine_ini.h"
#include "cs_path.h"
#include "cs_planner.h"
#include "cs_segment.h"

/* A servo pen event: before segment `seg` runs, the pen servo's pulse becomes pulse_us (that
 * segment is the settle wait: no steps). In a segments file, a line "pen PULSE_US". */
typedef struct {
    size_t seg;
    uint16_t pulse_us;
} cs_motion_pen_t;

/* The spindle / laser from a segment on (G-code M3/M4/M5 and S, carried by the path's elements):
 * a change of power never stops the motion, it starts with the first segment of its move. */
typedef struct {
    size_t seg;       /* the first segment it applies to */
    uint8_t spindle;  /* 3, 4 or 5: M3, M4, M5 */
    bool rapid;       /* the moves are rapids (a laser is off in them) */
    double s;         /* S: spindle speed, laser power */
    double feed_mm_s; /* the moves' programmed feed (M4 laser: the speed of full power) */
} cs_motion_power_t;

typedef struct {
    cs_segment_t *v;
    size_t n, cap;
    cs_motion_pen_t *pens; /* in segment order ([pen] mode = servo; none otherwise) */
    size_t npens, cappens;
    cs_motion_power_t *powers; /* in segment order (G-code jobs; none otherwise) */
    size_t npowers, cappowers;
} cs_motion_segs_t;

/* Most step segments one plan holds by default: 2^23 (8.4 M, 168 MB of segments; hours of
 * motion on any machine). Beyond it planning stops with a located error (docs/inputs.md). */
#define CS_MOTION_MAX_SEGS ((size_t)1 << 23)

typedef struct {
    const cs_machine_t *m;
    const cs_machine_pen_t *pen; /* NULL or mode none / z: no pen events; servo: see plan_path */
    size_t max_segs; /* 0: CS_MOTION_MAX_SEGS (set after cs_motion_init) */
    bool over_limit; /* a segment was refused for max_segs */
    cs_planner_t pl;
    cs_segment_gen_t gen;
    cs_motion_segs_t segs;
    size_t blocks;        /* blocks queued */
    uint64_t ticks;       /* sum of the segments' durations */
    int64_t steps;        /* sum of |steps| over every axis */
    int64_t pos[CS_AXES]; /* sum of the segments' steps: the final position */
    /* power marks waiting for their block to be cut (seg holds the block's number) */
    cs_motion_power_t *pend;
    size_t npend, cappend, pend0;
    size_t blocks_cut; /* blocks cut into segments so far */
} cs_motion_t;

/* Planner and generator for machine *m (which must outlive mo), no segments yet. */
cs_err_t cs_motion_init(cs_motion_t *mo, const cs_machine_t *m);
/* Frees the segments. */
void cs_motion_free(cs_motion_t *mo);
/* Frees a segment list (and its pen events); empty afterwards. */
void cs_motion_segs_free(cs_motion_segs_t *s);
/* Appends a servo pen event: an exact stop (cs_motion_finish), then settle_ms of rest (one or
 * more segments without steps) that begins with the pulse pulse_us. CS_ERR_FULL on OOM. */
cs_err_t cs_motion_pen(cs_motion_t *mo, uint16_t pulse_us, double settle_ms);
/* True when a power mark turns a spindle or laser on (M3 or M4). */
bool cs_motion_spindle_used(const cs_motion_segs_t *s);
/* As cs_motion_write, with the "pen PULSE_US" line before each pen event's segment and, when
 * cs_motion_spindle_used, a comment line before the first segment of each power mark:
 * "# spindle M3|M4 S<S> F<mm/s>" (feed moves), "# spindle M3|M4 S<S> rapid", "# spindle M5". */
int cs_motion_write_segs(FILE *f, const cs_machine_t *m, const cs_motion_segs_t *s);
/* Queues a straight move to target (mm) at feed (mm/s Q15.16, <= 0 rapid); cuts segments first
 * when the ring is full. Planner errors pass through (CS_ERR_LIMIT: nothing was queued). */
cs_err_t cs_motion_line(cs_motion_t *mo, const cs_pos_t target[CS_AXES], int32_t feed,
                        uint32_t line);
/* Same in mm (double) for x, y, z (a unchanged); CS_ERR_RANGE when a value is not a cs_pos_t. */
cs_err_t cs_motion_line_mm(cs_motion_t *mo, double x, double y, double z, double feed_mm_s,
                           uint32_t line);
/* Marks *p (seg ignored) to take effect with the next move queued: it lands in segs.powers at
 * that move's first segment, with no stop. CS_ERR_FULL on OOM. */
cs_err_t cs_motion_power(cs_motion_t *mo, const cs_motion_power_t *p);
/* Cuts every queued block (the job ends with an exact stop). */
cs_err_t cs_motion_finish(cs_motion_t *mo);
/* Writes segments as text: a header line "# curvestep segments tick_hz=N axes=N" then one line
 * per segment, "ticks dx dy dz" (and " da" with 4 axes). Returns 0, -1 on a write error. */
int cs_motion_write(FILE *f, const cs_machine_t *m, const cs_segment_t *s, size_t n);
/* Reads that format (lines starting with '#' are comments; a header's tick_hz and axes must
 * match *m; "pen PULSE_US" lines become pen events). Appends to *out. Returns 0, or -1 with
 * "name:line: reason" in err. */
int cs_motion_read(FILE *f, const char *name, const cs_machine_t *m, cs_motion_segs_t *out,
                   char *err, size_t errlen);
/* Reads a job file into *path with the host's input loader (cs_input: SVG, G-code, HPGL, by
 * extension then content). CS_OK, or an error with *diag filled ("file:line:col: reason"). */
cs_err_t cs_motion_read_job(const char *file, cs_path_t *path, cs_path_diag_t *diag);
/* Same, lenient: unsupported G-code words are warnings, not errors (cs_input_opts_t.lenient). */
cs_err_t cs_motion_read_job_ex(const char *file, bool lenient, cs_path_t *path,
                               cs_path_diag_t *diag);
/* Plans a whole path: from the current position a rapid move to each element that does not start
 * where the previous one ended (with mo->pen in mode servo: the pen raised before it and lowered
 * after it, cs_pen_stroke_starts, and raised at the end), then the element's chords (cs_trace,
 * tolerance tol, method) at the element's own feed (G-code F), or rapid for a rapid element (G0),
 * or else at feed (mm/s Q15.16; <= 0: the machine's default feed); then cs_motion_finish. On error
 * *diag names the element's source location (CS_ERR_LIMIT: the move that leaves the travel;
 * CS_ERR_RANGE: the element whose chords would pass max_segs segments). */
cs_err_t cs_motion_plan_path(cs_motion_t *mo, const cs_path_t *path, cs_pos_t tol, int method,
                             int32_t feed, cs_path_diag_t *diag);
/* mm/s -> Q15.16 (<= 0 stays 0: rapid). */
int32_t cs_motion_speed(double mm_s);

#endif
