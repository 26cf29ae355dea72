/* cs_gcode_int: what the parts of the G-code reader share (host/cs_gcode.c: lines, words, modal
 * state, straight moves, splines; host/cs_gcode_arc.c: G2/G3 arcs and helices;
 * host/cs_gcode_nurbs.c: the G5.2 and G6.2 blocks). Internal to them: the reader's state (gc_t),
 * one line's words (block_t), and the helpers that add path elements. Host only. */
#ifndef CS_GCODE_INT_H
#define CS_GCODE_INT_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_gcode.h"
#include "cs_gexpr.h"
#include "cs_gnurbs.h"

#define MM_PER_INCH 25.4
/* pi, spelled out: M_PI is POSIX, not C99 (the fuzz build uses plain -std=c99). */
#define GC_PI  3.14159265358979323846
#define BIT(c) (1u << ((c) - 'A'))

/* Motion modes: the G number times ten. */
enum {
    MOT_DROPPED = -3, /* an unsupported motion mode dropped by --lenient (G81, G38.2...) */
    MOT_NONE = -1,
    MOT_G0 = 0,
    MOT_G1 = 10,
    MOT_G2 = 20,
    MOT_G3 = 30,
    MOT_G5 = 50,
    MOT_G51 = 51,
    MOT_G52 = 52,
    MOT_G62 = 62
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
    double off[3];    /* G92: program coordinate = machine - off */
    double unit;      /* mm per program unit */
    bool incr;        /* G91 */
    bool ijk_abs;     /* G90.1 */
    int plane;        /* 17, 18, 19 */
    int motion;       /* MOT_* */
    int dropped_code; /* --lenient: the unsupported motion code MOT_DROPPED stands for */
    double feed;      /* F in program units per minute; 0 = none given */
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
} gc_t;

/* One line's words. */
typedef struct {
    word_t w[26]; /* by letter; G and M are kept apart */
    int g[8];
    unsigned gcol[8];
    unsigned ng;
    int m[8];
    unsigned mcol[8];
    unsigned nm;
    unsigned used; /* bit per letter consumed by the block */
} block_t;

/* Location col on the line being read. */
cs_path_loc_t cs_gcode_loc(const gc_t *g, unsigned col);
/* A warning at col (counted in stats; to opts->warn or stderr). */
void cs_gcode_warn(gc_t *g, unsigned col, const char *fmt, ...);
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
/* The plane's axes: first, second (counter-clockwise from first to second), normal. */
void cs_gcode_plane_axes(int plane, int ax[3]);

/* G2 (ccw false) / G3 from g->pos (cs_gcode_arc.c). */
cs_err_t cs_gcode_arc(gc_t *g, block_t *b, bool ccw, unsigned col);
/* The open NURBS block -> path elements; g->pos ends on its last point (cs_gcode_nurbs.c). */
cs_err_t cs_gcode_nurbs_close(gc_t *g);
/* A G5.2 line (first) or a control point line of its block. */
cs_err_t cs_gcode_nurbs_line(gc_t *g, block_t *b, bool first, unsigned col);
/* A G6.2 line (first) or a line of its block. */
cs_err_t cs_gcode_g62_line(gc_t *g, block_t *b, bool first, unsigned col);

#endif
