/* cs_gcode_int: what the parts of the G-code reader share (host/cs_gcode.c: lines, words, modal
 * state, straight moves, splines; host/cs_gcode_arc.c: G2/G3 arcs and helices;
 * host/cs_gcode_nurbs.c: the G5.2 and G6.2 blocks). Internal to them: the reader's state (gc_t),
 * one line's words (block_t), and the helpers that add path elements. Host only. */
#ifndef CS_GCODE_INT_H
#define CS_GCODE_INT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_gcode.h"
#include "cs_gexpr.h"
#include "cs_gflow.h"
#include "cs_gcode_words.h"
#include "cs_gnurbs.h"

#define MM_PER_INCH 25.4
/* pi, spelled out: M_PI is POSIX, not C99 (the fuzz build uses plain -std=c99). */
#define GC_PI  3.14159265358979323846
#define BIT(c) (1u << ((c) - 'A'))
/* Kinds of once-only warning remembered per program (beyond: each is printed every time). */
#define GC_MAX_WARN_ONCE 64

/* Motion modes: the motion group's G code (cs_gcode_words.h), or one of these. */
enum {
    MOT_LINE_NONE = -2, /* gline_t: no motion word on the line */
    MOT_DROPPED = -3,   /* an unsupported motion mode dropped by --lenient (G81, G38.2...) */
    MOT_NONE = -1,
    MOT_G0 = GC_G0,
    MOT_G1 = GC_G1,
    MOT_G2 = GC_G2,
    MOT_G3 = GC_G3,
    MOT_G5 = GC_G5,
    MOT_G51 = GC_G5_1,
    MOT_G52 = GC_G5_2,
    MOT_G62 = GC_G6_2,
    MOT_G73 = GC_G73, /* canned cycles (cs_gcode_cycle.c) */
    MOT_G81 = GC_G81,
    MOT_G83 = GC_G83
};

/* Numbered parameters the reader keeps (LinuxCNC G-code reference, "Numbered Parameters"); the
 * offsets are stored in millimetres, the machine's unit. */
enum {
    GC_P_PROBE = 5061,    /* #5061..#5063: the last probe's contact (program coordinates) */
    GC_P_PROBE_OK = 5070, /* 1: the last probe made contact */
    GC_P_G28 = 5161,      /* #5161..#5163: G28 home (machine coordinates) */
    GC_P_G30 = 5181,      /* #5181..#5183: G30 home */
    GC_P_G92_ON = 5210,   /* 1: the G92 offsets apply */
    GC_P_G92 = 5211,      /* #5211..#5213: the G92 offsets */
    GC_P_WCS = 5220,      /* the coordinate system in use, 1 (G54) .. 9 (G59.3) */
    GC_P_WCS1 = 5221,     /* #5221..#5223: G54's offsets; system n at GC_P_WCS1 + 20 (n - 1) */
    GC_P_WCS_STRIDE = 20
};

typedef struct {
    bool has;
    double v;
    unsigned col;
} word_t;

typedef struct {
    const char *name;
    const cs_gcode_opts_t *o;
    cs_path_t *path;
    cs_path_diag_t *diag;
    cs_gcode_stats_t *stats;
    unsigned line;
    /* modal state */
    double pos[3];    /* machine position, mm */
    double unit;      /* mm per program unit */
    bool incr;        /* G91 */
    bool ijk_abs;     /* G90.1 */
    int plane;        /* 17, 18, 19 */
    int motion;       /* MOT_* */
    int dropped_code; /* --lenient: the unsupported motion code MOT_DROPPED stands for */
    double feed;      /* F in program units per minute; 0 = none given */
    int spindle;      /* GC_M3, GC_M4 or GC_M5 (the spindle / laser / pen state) */
    double speed;     /* S (spindle speed, laser power), 0 until given */
    bool g5_prev;     /* the last move was a G5: its P, Q continue */
    double g5_pq[2];
    bool last_rapid;
    bool ended; /* M2 / M30 */
    /* open NURBS block: G5.2 (until G5.3) or G6.2 (until a line without K) */
    cs_gnurbs_t nb;
    int nurbs;        /* 0 (none), MOT_G52 or MOT_G62 */
    bool g62_knots;   /* the G6.2 block has reached its knot-only lines */
    bool emit_failed; /* a NURBS segment could not be added (diag set) */
    cs_path_loc_t nurbs_loc;
    double nurbs_feed;
    cs_gexpr_store_t st; /* parameters (LinuxCNC) */
    /* canned cycles (cs_gcode_cycle.c) */
    bool retract_r;   /* G99: retract to R; G98 (the start): to the higher of R and the old Z */
    bool cyc_set;     /* a cycle has run: its R, Z (and Q) numbers below may be left out */
    double cyc_r;     /* the last cycle's R, Z and Q numbers as written (program units) */
    double cyc_z;
    double cyc_q;
    /* Warnings given once per program (cs_gcode_warn_once): hashes of their texts. */
    uint32_t warned[GC_MAX_WARN_ONCE];
    unsigned nwarned;
} gc_t;

/* One line's words. */
typedef struct {
    bool machine; /* G53 on the line: its axis words are machine coordinates */
    word_t w[26]; /* by letter; G and M are kept apart */
    int g[8];
    unsigned gcol[8];
    unsigned ng;
    int m[8];
    unsigned mcol[8];
    unsigned nm;
    unsigned used; /* bit per letter consumed by the block */
    word_t polar[2];  /* LinuxCNC's polar coordinates: @ (distance), ^ (angle, degrees) */
    bool polar_used;
} block_t;

/* Location col on the line being read. */
cs_path_loc_t cs_gcode_loc(const gc_t *g, unsigned col);
/* A warning at col (counted in stats; to opts->warn or stderr). */
void cs_gcode_warn(gc_t *g, unsigned col, const char *fmt, ...);
/* The same for a warning about something that changes no geometry (a word ignored): given the
 * first time its text occurs in the program, with "(reported once)"; later ones are counted in
 * stats only, so a CAM file with a T word per tool change does not repeat it per line. */
void cs_gcode_warn_once(gc_t *g, unsigned col, const char *fmt, ...);
/* Machine mm -> Q15.16; CS_ERR_RANGE with diag outside +/-4096 mm. */
cs_err_t cs_gcode_to_vec(gc_t *g, const double p[3], unsigned col, cs_vec3_t *out);
/* Coordinate axis (0 x, 1 y, 2 z) of v. */
cs_pos_t *cs_gcode_coord(cs_vec3_t *v, int axis);
bool cs_gcode_vec_eq(const cs_vec3_t *a, const cs_vec3_t *b);
/* Appends curve c (a feed move at the current F unless rapid); a change between rapid and feed
 * starts a subpath. CS_ERR_FULL with diag past max_elements or without memory. */
cs_err_t cs_gcode_add(gc_t *g, const cs_bezier_t *c, cs_path_kind_t kind, unsigned col, bool rapid);
/* A straight move a -> b (mm); nothing when both round to one point. */
cs_err_t cs_gcode_add_line(gc_t *g, const double a[3], const double b[3], unsigned col, bool rapid);
/* The line's X Y Z (absolute or G91, units, G92 offsets) -> target t in machine mm. */
void cs_gcode_target(gc_t *g, block_t *b, double t[3]);
bool cs_gcode_any_axis(const block_t *b);
/* Program coordinate = machine - offset: axis a's offset (coordinate system + G92), mm. */
double cs_gcode_offset(const gc_t *g, int a);
/* G10, G28, G30, G92 (the non-modal codes that take the line's axis words, cs_gcode_wcs.c). */
cs_err_t cs_gcode_wcs_axes(gc_t *g, block_t *b, int code, unsigned col);
/* G28.1, G30.1, G92.1, G92.2, G92.3 and G54..G59.3 (no axis words). */
void cs_gcode_wcs_set(gc_t *g, int code);
/* Parameters at program start: G54 in use, no offsets. */
void cs_gcode_wcs_init(gc_t *g);
/* G38.2 .. G38.5 to the line's target, through opts->probe (cs_gcode_wcs.c). */
cs_err_t cs_gcode_probe(gc_t *g, block_t *b, int code, unsigned col);
/* The plane's axes: first, second (counter-clockwise from first to second), normal. */
void cs_gcode_plane_axes(int plane, int ax[3]);

/* The point the line's @ / ^ give from the program point cur (program units): G90 about the
 * origin, the missing one kept from cur; G91 added to cur's distance and angle (LinuxCNC
 * "Polar Coordinates"). CS_ERR_PARSE with diag for G91 at the origin. */
cs_err_t cs_gcode_polar(gc_t *g, block_t *b, const double cur[2], double out[2]);
/* G2 (ccw false) / G3 from g->pos (cs_gcode_arc.c). */
cs_err_t cs_gcode_arc(gc_t *g, block_t *b, bool ccw, unsigned col);
/* Canned cycle code (MOT_G73, MOT_G81 or MOT_G83) from g->pos (cs_gcode_cycle.c); same: the
 * same cycle was in effect before the line (its R, Z and Q stick). */
cs_err_t cs_gcode_cycle(gc_t *g, block_t *b, int code, bool same, unsigned col);
/* The open NURBS block -> path elements; g->pos ends on its last point (cs_gcode_nurbs.c). */
cs_err_t cs_gcode_nurbs_close(gc_t *g);
/* A G5.2 line (first) or a control point line of its block. */
cs_err_t cs_gcode_nurbs_line(gc_t *g, block_t *b, bool first, unsigned col);
/* A G6.2 line (first) or a line of its block. */
cs_err_t cs_gcode_g62_line(gc_t *g, block_t *b, bool first, unsigned col);

/* ---- the reader's steps, shared with the line-at-a-time session (cs_gcode_feed.c) ---- */

/* *g at program start for a read named name with options o into path (diag for errors).
 * CS_ERR_FULL, CS_ERR_TOLERANCE with diag. The caller frees g->st and g->nb. */
cs_err_t cs_gcode_begin(gc_t *g, const char *name, const cs_gcode_opts_t *o, cs_path_t *path,
                        cs_path_diag_t *diag);
/* Units, plane, distance modes, motion mode and feed as at program start. */
void cs_gcode_start_modes(gc_t *g);
/* One ordinary (not O-word) line s[0..n): its words run, its parameter settings committed. */
cs_err_t cs_gcode_line(gc_t *g, const char *s, size_t n);
/* Runs fl's lines of buf from the first in the order the O-words decide, up to M2 / M30. */
cs_err_t cs_gcode_run_lines(gc_t *g, cs_gflow_t *fl, const char *buf);

#endif
