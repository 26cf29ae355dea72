/* curvestep toolpath: surface patches (Newell's format or the native one, cs_surffile) turned
 * into paths.
 *  - wireframe (default): the iso-parametric lines of every patch, N + 1 in each direction
 *    (edges included), made by the core (cs_patch_raster_* forward differences when N is a power
 *    of two, cs_patch_iso otherwise), traced in 3D by cs_trace within --tol, and projected
 *    through a view to 2D: "x y" per line, a blank line between polylines, like flatten.
 *  - finishing (--ball R): see the comment above finish_patch.
 * Neighbouring patches that share an edge's control points get identical iso-curve end points
 * (the same integer computation), so the wireframe has no cracks. */
#include <getopt.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_cmd.h"
#include "cs_conv.h"
#include "cs_finish.h"
#include "cs_err_text.h"
#include "cs_patch.h"
#include "cs_surffile.h"
#include "cs_path.h"
#include "cs_trace.h"

#define TP_DEFAULT_TOL_MM 0.01
#define TP_DEFAULT_LINES  8
#define TP_MAX_LINES      4096

/* A view: rows 0 and 1 give the printed x and y, row 2 the depth (unused): v = M (x y z 1). */
typedef struct {
    const char *name;
    double m[3][4];
} tp_view_t;

#define S2 0.70710678118654752440
#define S6 0.40824829046386301637
#define S3 0.57735026918962576451
static const tp_view_t views[] = {
    {"top", {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}},
    {"front", {{1, 0, 0, 0}, {0, 0, 1, 0}, {0, -1, 0, 0}}},
    {"side", {{0, 1, 0, 0}, {0, 0, 1, 0}, {1, 0, 0, 0}}},
    /* Orthographic, seen from (1, -1, 1): right (1, 1, 0)/sqrt 2, up (-1, 1, 2)/sqrt 6. */
    {"iso", {{S2, S2, 0, 0}, {-S6, S6, 2 * S6, 0}, {S3, -S3, S3, 0}}},
};

/* The drop-cutter part of the help (--cutter and the options only it takes). */
static void tp_usage_dropcut(FILE *f)
{
    fputs(
        "Drop-cutter finishing (--cutter): gouge-free from above for ball, flat and\n"
        "bull-nose cutters. The surface is meshed within tol / 4 (a proven bound), the cutter\n"
        "enlarged by that bound is dropped onto the mesh along a zig-zag raster (OpenCAMLib's\n"
        "drop-cutter: facet, edge and vertex contacts), points along each pass added until\n"
        "every chord is within tol of the drop height, and passes added between two\n"
        "neighbours until the scallop between them (measured across the surface) is at most H\n"
        "for every cutter; passes joined at cutting height where the straight link stays above\n"
        "the drop surface. Sphere items are meshed too. Prints the programmed point \"x y z\"\n"
        "(mm) per line, a blank line between polylines.\n"
        "  --cutter K      ball:R, flat:R or bull:R:r (radius R, corner radius r, mm)\n"
        "  --scallop H     largest material height left between passes, mm\n"
        "  --stepover MM   a fixed step-over instead (no scallop refinement)\n"
        "  --angle DEG     raster direction from +x (default 0: passes along x)\n"
        "  --strategy S    raster (default: zig-zag passes) or waterline (constant-z contours\n"
        "                  of the drop surface, levels 2 sqrt(2rH - H^2) apart, r the corner\n"
        "                  radius, 2H for a flat end, levels added where the slope wants\n"
        "                  them, flat areas and concave corners by a clipped raster), or\n"
        "                  raster+waterline (the raster on ground up to 45 deg, the waterline\n"
        "                  above, each clipped to its region with R of overlap, then short\n"
        "                  passes where the check's measure finds a reachable gap over H)\n"
        "  --output P      tip (default) or centre (of the corner radius: the ball's centre)\n"
        "  --feed F        cutting feed in mm/min on every G1 (default 1000)\n"
        "  --plunge F      plunge feed in mm/min (default 300)\n"
        "  --spindle S     M3 S<S> before cutting, M5 after (default: no spindle words)\n"
        "  --min-z Z       the lowest the tip goes (default: the surface's lowest point)\n"
        "  --stock BOX     X0,Y0,X1,Y1: the region the cutter's axis covers (default: the\n"
        "                  surface's extent and R beyond)\n"
        "  --check         measure, against dense samples of the exact surface, the deepest\n"
        "                  penetration of the cutter along the path and the scallop (distance\n"
        "                  from the surface to the nearest cutter; what no cutter from above\n"
        "                  reaches is reported apart as unreachable); exit 1 when over --tol\n"
        "                  or H (--check-step MM: the sampling step, default 0.05 mm)\n"
        "  --check-trace F.csv  check a path a machine executed instead of planning one: the\n"
        "                  step trace of `curvestep-sim --trace F.csv` (the programmed point\n"
        "                  as --output says), measured as --check measures (exit 1 over tol/H)\n"
        "  --no-link       retract after every pass (default: link at cutting height where\n"
        "                  the straight move stays above the drop surface)\n"
        "\n"
        , f);
}

static void tp_usage(FILE *f)
{
    char kw[256];
    cs_surffile_keyword_list(kw, sizeof kw);
    fprintf(
        f,
        "Usage: curvestep toolpath --patches FILE [--view V] [--lines N] [--tol MM]\n"
        "                          [--scale S] [--stats] [--svg OUT.svg]\n"
        "       curvestep toolpath --patches FILE --ball R --scallop H [--tol MM]\n"
        "                          [--safe-z Z] [--scale S] [--view V] [--svg OUT.svg]\n"
        "       curvestep toolpath --patches FILE --cutter ball:R|flat:R|bull:R:r\n"
        "                          (--scallop H | --stepover MM) [--angle DEG] [--tol MM]\n"
        "                          [--strategy raster|waterline|raster+waterline]\n"
        "                          [--output tip|centre] [--feed F] [--plunge F] [--spindle S]\n"
        "                          [--safe-z Z] [--min-z Z] [--stock X0,Y0,X1,Y1] [--scale S]\n"
        "                          [--check [--check-step MM]] [--check-trace F.csv] [--no-link] [--stats]\n"
        "                          [--gcode OUT.nc]\n"
        "       (the first two forms also take --gcode OUT.nc)\n"
        "\n"
        "Reads surface patches and prints a path over them. FILE is in Newell's format (a\n"
        "patch count; one line of 16 one-based vertex indices per patch; a vertex count; one\n"
        "\"x,y,z\" line per vertex: the Utah teapot's format), in the .bpt format (a patch\n"
        "count; per patch a line \"degu degv\" and its (degu+1)(degv+1) points \"x y z\"), or\n"
        "in curvestep's native surface format (first word \"curvestep-surfaces 1\", then\n"
        "items, each starting with one of the keywords\n"
        "  %s;\n"
        "see docs/surfaces.md). Surfaces of revolution are approximated within --tol / 4.\n"
        "\n"
        "Wireframe (without --ball): the iso-parametric lines of each patch, N + 1 in each\n"
        "parameter direction (edges included), traced into chords within the tolerance of the\n"
        "exact lines in 3D, then projected through the view; one vertex \"x y\" (mm, 6 decimals)\n"
        "per line, a blank line between polylines.\n"
        "\n"
        "Finishing (--ball R): a zig-zag raster along each patch's u lines (a triangle's\n"
        "iso-lines u = const) for a ball-end tool of radius R, its centre on the offset\n"
        "surface P + R N (N = Pu x Pv as the file orients the patch), passes spaced so the\n"
        "measured scallop stays below H; prints the tool centre \"x y z\" (mm) per line (the\n"
        "tool tip is R below it). Each patch is one block: approach at the safe height, the\n"
        "passes, retract to the safe height; a blank line between patches. Warnings on stderr\n"
        "where the surface is concave with a curvature radius below R (gouge), where the path\n"
        "folds back on itself there (loops that close within a pass are cut at the crossing)\n"
        "or faces down (undercut). n-sided patches are finished as bicubic cells fitted within\n"
        "tol / 2, one block per cell. See docs/surfaces.md.\n"
        "\n"
        , kw);
    tp_usage_dropcut(f);
    fprintf(f,
        "Options:\n"
        "  --patches FILE  the surface file ('-' reads standard input)\n"
        "  --view V        top (x y), front (x z), side (y z), iso (orthographic, seen from\n"
        "                  (1,-1,1)) or 12 comma-separated numbers: a 3x4 matrix, row-major,\n"
        "                  whose first two rows give the printed x and y (default iso)\n"
        "  --lines N       iso-parametric intervals per patch and direction, 1..%d\n"
        "                  (default %d; powers of two use exact forward differences;\n"
        "                  triangular patches get N + 1 lines in each of 3 directions)\n"
        "  --tol MM        chord tolerance in mm, in 3D model space (default %g)\n"
        "  --scale S       millimetres per file unit (default 1)\n"
        "  --ball R        ball-end tool radius in mm: finishing path instead of wireframe\n"
        "  --scallop H     largest scallop height in mm (with --ball; 0 < H < R)\n"
        "  --safe-z Z      retract height in mm (default: 5 mm above the highest control point\n"
        "                  plus R)\n"
        "  --stats         summary on stderr: patches, curves, chords, largest deviation of a\n"
        "                  chord from its exact curve (measured in double)\n"
        "  --svg OUT.svg   also draw the projected path (y up)\n"
        "  --gcode OUT.nc  also write the path as G-code for `curvestep plan`: G21 G90, a G0\n"
        "                  travel to the start of each polyline and G1 moves along it, no F\n"
        "                  (plan's --feed or the machine's default feed applies); the\n"
        "                  wireframe as projected X Y with the pen lifted (M5) for every\n"
        "                  travel and lowered (M3) to draw, the finishing path as the tool\n"
        "                  centre X Y Z (G0 up to the safe height first, G0 approach over each\n"
        "                  patch, G1 plunge and passes, G0 retract)\n"
        "  -h, --help      show this help\n"
        "\n"
        "Exit status: 0 success; 1 bad input (\"file:line:col: reason\" on stderr, including\n"
        "coordinates outside +/-%d mm after scaling); 2 usage error; 3 internal error.\n",
        TP_MAX_LINES, TP_DEFAULT_LINES, TP_DEFAULT_TOL_MM, CS_POS_LIMIT_MM);
}

static bool parse_view(const char *s, tp_view_t *v)
{
    for (size_t k = 0; k < sizeof views / sizeof views[0]; k++)
        if (strcmp(s, views[k].name) == 0) {
            *v = views[k];
            return true;
        }
    double m[12];
    const char *p = s;
    for (int k = 0; k < 12; k++) {
        char *end = NULL;
        m[k] = strtod(p, &end);
        if (end == p || !isfinite(m[k]))
            return false;
        p = end;
        if (k < 11) {
            if (*p != ',')
                return false;
            p++;
        }
    }
    if (*p != '\0')
        return false;
    v->name = "matrix";
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++)
            v->m[r][c] = m[4 * r + c];
    return true;
}

static void project(const tp_view_t *v, const double q[3], double *x, double *y)
{
    *x = v->m[0][0] * q[0] + v->m[0][1] * q[1] + v->m[0][2] * q[2] + v->m[0][3];
    *y = v->m[1][0] * q[0] + v->m[1][1] * q[1] + v->m[1][2] * q[2] + v->m[1][3];
}

static void to_mm(const cs_vec3_t *p, double q[3])
{
    q[0] = cs_conv_pos_to_mm(p->x);
    q[1] = cs_conv_pos_to_mm(p->y);
    q[2] = cs_conv_pos_to_mm(p->z);
}

/* Output: stdout text plus the projected polylines for the picture, and optionally the same
 * path as G-code (--gcode): G0 for a polyline's first vertex (travel), G1 for the others. */
typedef struct {
    const tp_view_t *view;
    bool three_d; /* print x y z instead of the projection */
    bool first;   /* nothing printed yet */
    FILE *gcode;  /* NULL: no G-code */
    bool pen;     /* wireframe G-code: the pen is down (M3; M5 lifts it for every G0) */
    cs_path_poly_t poly;
    cs_vec3_t *v; /* vertices of the current curve (for --stats) */
    size_t nv, capv;
    size_t curves, chords;
    double maxdev;
    bool stats;
} tp_out_t;

/* One vertex: printed, kept for the picture, and written as G-code, a G0 (travel) when rapid.
 * start begins a new polyline of the text output. */
static bool out_vertex_g(tp_out_t *o, const cs_vec3_t *p, bool start, bool rapid)
{
    double q[3], x, y;
    to_mm(p, q);
    project(o->view, q, &x, &y);
    if (start && !o->first)
        putchar('\n');
    o->first = false;
    if (o->three_d)
        printf("%.6f %.6f %.6f\n", q[0], q[1], q[2]);
    else
        printf("%.6f %.6f\n", x, y);
    if (o->gcode && o->three_d)
        fprintf(o->gcode, "G%d X%.6f Y%.6f Z%.6f\n", rapid ? 0 : 1, q[0], q[1], q[2]);
    else if (o->gcode) {
        if (rapid == o->pen) /* pen up before a travel, down before the first drawn move */
            fprintf(o->gcode, "%s\n", rapid ? "M5" : "M3");
        o->pen = !rapid;
        fprintf(o->gcode, "G%d X%.6f Y%.6f\n", rapid ? 0 : 1, x, y);
    }
    return (start ? cs_path_poly_move(&o->poly, x, y) : cs_path_poly_line(&o->poly, x, y)) == CS_OK;
}

/* Wireframe vertices: a polyline starts with a travel. */
static bool out_vertex(tp_out_t *o, const cs_vec3_t *p, bool start)
{
    return out_vertex_g(o, p, start, start);
}

static bool keep_vertex(tp_out_t *o, const cs_vec3_t *p)
{
    if (o->nv == o->capv) {
        size_t nc = o->capv ? 2 * o->capv : 256;
        cs_vec3_t *nv = realloc(o->v, nc * sizeof *nv);
        if (!nv)
            return false;
        o->v = nv;
        o->capv = nc;
    }
    o->v[o->nv++] = *p;
    return true;
}

static bool degenerate_curve(const cs_bezier_t *c)
{
    for (unsigned k = 1; k <= c->degree; k++)
        if (c->p[k].x != c->p[0].x || c->p[k].y != c->p[0].y || c->p[k].z != c->p[0].z)
            return false;
    return true;
}

/* Trace one curve and print it as one polyline (or continue the current one when !start). */
static cs_err_t emit_curve(tp_out_t *o, const cs_bezier_t *c, cs_pos_t tol, bool start)
{
    o->nv = 0;
    if (!keep_vertex(o, &c->p[0]) || !out_vertex(o, &c->p[0], start))
        return CS_ERR_FULL;
    if (degenerate_curve(c))
        return CS_OK; /* a collapsed edge: a single point */
    cs_trace_t tr;
    cs_err_t e = cs_trace_begin(&tr, c, tol, CS_TRACE_SUBDIV);
    cs_vec3_t pt;
    while (e == CS_OK && (e = cs_trace_next(&tr, &pt)) == CS_OK) {
        o->chords++;
        if (!out_vertex(o, &pt, false) || !keep_vertex(o, &pt))
            return CS_ERR_FULL;
    }
    if (e != CS_END)
        return e;
    o->curves++;
    if (o->stats) {
        double d = cs_path_deviation_mm(c, o->v, o->nv);
        if (d > o->maxdev)
            o->maxdev = d;
    }
    return CS_OK;
}

static bool is_pow2(unsigned n)
{
    return n && (n & (n - 1)) == 0;
}

static cs_err_t wire_patch(tp_out_t *o, const cs_patch_t *p, unsigned lines, cs_pos_t tol)
{
    for (int dir = 0; dir < 2; dir++) {
        cs_bezier_t c;
        cs_err_t e;
        /* Exact forward differences while N^m fits (cs_patch_raster_t), de Casteljau per
         * line beyond (higher degrees, more lines). */
        unsigned m = dir == CS_PATCH_ISO_U ? p->deg_v : p->deg_u;
        if (is_pow2(lines) && lines <= (1u << cs_patch_raster_max_shift(m))) {
            unsigned shift = 0;
            while ((1u << shift) < lines)
                shift++;
            cs_patch_raster_t r;
            e = cs_patch_raster_begin(&r, p, (cs_patch_iso_t)dir, shift);
            while (e == CS_OK && (e = cs_patch_raster_next(&r, &c, NULL)) == CS_OK)
                e = emit_curve(o, &c, tol, true);
            if (e != CS_END)
                return e;
        } else {
            for (unsigned k = 0; k <= lines; k++) {
                cs_param_t t = (cs_param_t)(((int64_t)k * CS_PARAM_ONE + lines / 2) / lines);
                e = cs_patch_iso(p, (cs_patch_iso_t)dir, t, &c);
                if (e == CS_OK)
                    e = emit_curve(o, &c, tol, true);
                if (e != CS_OK)
                    return e;
            }
        }
    }
    return CS_OK;
}

/* Triangular patch: the lines u = k/N, v = k/N and w = k/N (k = 0..N), each the image of a
 * straight domain segment (cs_tripatch_line). */
static cs_err_t wire_tri(tp_out_t *o, const cs_tripatch_t *t, unsigned lines, cs_pos_t tol)
{
    for (unsigned k = 0; k <= lines; k++) {
        cs_param_t c = (cs_param_t)(((int64_t)k * CS_PARAM_ONE + lines / 2) / lines);
        cs_param_t r = CS_PARAM_ONE - c;
        /* (u, v) end points of the three families; w = 1 - u - v. */
        const cs_param_t seg[3][4] = {{c, 0, c, r}, {0, c, r, c}, {r, 0, 0, r}};
        for (int f = 0; f < 3; f++) {
            cs_bezier_t b;
            cs_err_t e = cs_tripatch_line(t, seg[f][0], seg[f][1], seg[f][2], seg[f][3], &b);
            if (e == CS_OK)
                e = emit_curve(o, &b, tol, true);
            if (e != CS_OK)
                return e;
        }
    }
    return CS_OK;
}

/* One domain segment of an n-sided patch: fitted cubics (within tol / 4 of the surface), each
 * traced, printed as one polyline. */
static cs_err_t varady_segment(tp_out_t *o, const cs_varady_t *v, const double a[2],
                               const double b[2], cs_pos_t tol)
{
    cs_bezier_t pieces[64];
    size_t n = 0;
    cs_err_t e = cs_varady_curve(v, a, b, cs_conv_pos_to_mm(tol) / 4, pieces, 64, &n);
    for (size_t k = 0; e == CS_OK && k < n; k++)
        e = emit_curve(o, &pieces[k], tol, k == 0);
    return e;
}

/* n-sided patch: the boundary curves themselves, rays from the domain centre to every vertex
 * and N - 1 concentric copies of the domain polygon (scaled by k / N about the centre). */
static cs_err_t wire_varady(tp_out_t *o, const cs_varady_t *v, unsigned lines, cs_pos_t tol)
{
    cs_err_t e = CS_OK;
    for (size_t i = 0; e == CS_OK && i < v->n; i++)
        e = emit_curve(o, &v->side[i], tol, true);
    double c[2] = {0, 0};
    for (size_t i = 0; e == CS_OK && i < v->n; i++) {
        double p[2];
        cs_varady_vertex(v, i, p);
        e = varady_segment(o, v, c, p, tol);
    }
    for (unsigned k = 1; e == CS_OK && k < lines; k++) {
        double f = (double)k / lines;
        for (size_t i = 0; e == CS_OK && i < v->n; i++) {
            double p[2], q[2];
            cs_varady_vertex(v, i, p);
            cs_varady_vertex(v, (i + 1) % v->n, q);
            double a[2] = {f * p[0], f * p[1]}, b[2] = {f * q[0], f * q[1]};
            e = varady_segment(o, v, a, b, tol);
        }
    }
    return e;
}

/* The exact sphere (cs_sphere): N meridians (longitudes 360 k / N, each a half circle from
 * pole to pole) and the N - 1 parallels at latitudes -90 + 180 k / N, every piece an exact
 * rational arc, traced within tol. */
static cs_err_t wire_sphere(tp_out_t *o, const cs_sphere_t *s, unsigned lines, cs_pos_t tol)
{
    cs_bezier_t arc[CS_ARC_MAX_SEGMENTS];
    unsigned n = 0;
    cs_err_t e = CS_OK;
    for (unsigned k = 0; e == CS_OK && k < 2 * lines; k++) {
        bool meridian = k < lines;
        e = meridian     ? cs_sphere_meridian(s, 0, 360.0 * k / lines, -90, 90, arc, &n)
            : k == lines ? CS_END
                         : cs_sphere_parallel(s, 0, -90 + 180.0 * (k - lines) / lines, arc, &n);
        for (unsigned i = 0; e == CS_OK && i < n; i++)
            e = emit_curve(o, &arc[i], tol, i == 0);
        if (e == CS_END)
            e = CS_OK;
    }
    return e;
}

/* --- finishing with a ball-end tool -------------------------------------------------------- */

typedef struct {
    double r_mm, h_mm, safe_z_mm;
    bool have_safe_z;
} tp_ball_t;

typedef struct {
    tp_out_t *o;
    bool patch_start;
    cs_vec3_t last;
    double safe_z;
} tp_ball_ctx_t;

static bool ball_emit(void *ctx, size_t pass, double u, double v, const cs_vec3_t *c,
                      bool pass_start)
{
    (void)pass;
    (void)u;
    (void)v;
    (void)pass_start;
    tp_ball_ctx_t *b = ctx;
    cs_vec3_t above = *c;
    if (b->patch_start) {
        /* Rapid approach: over the first point at the safe height, then down. */
        cs_conv_mm_to_pos(b->safe_z, &above.z);
        if (!out_vertex_g(b->o, &above, true, true))
            return false;
        b->patch_start = false;
    }
    b->last = *c;
    b->o->chords++;
    return out_vertex_g(b->o, c, false, false); /* the plunge too is a feed move */
}

/* Traces c within tol and hands every vertex after the first to ball_emit (a feed move). */
static cs_err_t ball_trace(tp_ball_ctx_t *ctx, const cs_bezier_t *c, cs_pos_t tol)
{
    cs_trace_t tr;
    cs_vec3_t pt;
    cs_err_t e = cs_trace_begin(&tr, c, tol, CS_TRACE_SUBDIV);
    while (e == CS_OK && (e = cs_trace_next(&tr, &pt)) == CS_OK)
        if (!ball_emit(ctx, 0, 0, 0, &pt, false))
            return CS_ERR_FULL;
    return e == CS_END ? CS_OK : e;
}

/* The upper hemisphere of an exact sphere (below the equator a 3-axis tool cannot reach): the
 * tool centre runs on the offset sphere r + R, from the pole down a meridian (longitude 0) to
 * each parallel in turn and once around it, the parallels spaced equally in latitude by at most
 * cs_sphere_step(r, R, H), so the scallop (closed form, cs_sphere_scallop) stays below H. */
static cs_err_t finish_sphere(tp_ball_ctx_t *ctx, const cs_sphere_t *s, const tp_ball_t *bp,
                              cs_pos_t tol, cs_finish_stats_t *st)
{
    double step = cs_sphere_step(s->r, bp->r_mm, bp->h_mm);
    unsigned n = (unsigned)ceil((M_PI / 2) / step - 1e-9);
    double dlat = 90.0 / n, rho = s->r + bp->r_mm;
    cs_vec3_t pole;
    if (n == 0 || n > 100000 || cs_conv_mm_to_vec(s->c[0], s->c[1], s->c[2] + rho, &pole) != CS_OK)
        return CS_ERR_RANGE;
    if (!ball_emit(ctx, 0, 0, 0, &pole, true))
        return CS_ERR_FULL;
    cs_bezier_t arc[CS_ARC_MAX_SEGMENTS];
    unsigned na = 0;
    cs_err_t e = CS_OK;
    for (unsigned k = 1; e == CS_OK && k <= n; k++) {
        e = cs_sphere_meridian(s, bp->r_mm, 0, 90 - dlat * (k - 1), 90 - dlat * k, arc, &na);
        for (unsigned i = 0; e == CS_OK && i < na; i++)
            e = ball_trace(ctx, &arc[i], tol);
        if (e == CS_OK)
            e = cs_sphere_parallel(s, bp->r_mm, 90 - dlat * k, arc, &na);
        for (unsigned i = 0; e == CS_OK && i < na; i++)
            e = ball_trace(ctx, &arc[i], tol);
    }
    st->passes += n;
    st->max_scallop = fmax(st->max_scallop, cs_sphere_scallop(s->r, bp->r_mm, dlat * M_PI / 180));
    return e;
}

/* Every patch in turn: approach from the safe height, the zig-zag passes, retract. */
static int finish_all(tp_out_t *o, const cs_surffile_t *sf, cs_pos_t tol, const tp_ball_t *bp,
                      cs_finish_stats_t *st, double *fit_out)
{
    double top = -HUGE_VAL;
    for (size_t i = 0; i < sf->n; i++) {
        const cs_surf_item_t *it = &sf->items[i];
        for (size_t k = 0; it->varady && k < it->nside.n; k++)
            for (unsigned j = 0; j <= it->nside.side[k].degree; j++)
                top = fmax(top, cs_conv_pos_to_mm(it->nside.side[k].p[j].z));
        if (it->tri)
            for (unsigned k = 0; k < (it->trip.degree + 1u) * (it->trip.degree + 2u) / 2; k++)
                top = fmax(top, cs_conv_pos_to_mm(it->trip.p[k].z));
        if (it->sphere)
            top = fmax(top, it->sph.c[2] + it->sph.r);
        for (int a = 0; !it->tri && !it->varady && !it->sphere && a <= it->quad.deg_u; a++)
            for (int b = 0; b <= it->quad.deg_v; b++)
                top = fmax(top, cs_conv_pos_to_mm(it->quad.p[a][b].z));
    }
    tp_ball_ctx_t ctx = {o, true, {0, 0, 0}, bp->have_safe_z ? bp->safe_z_mm : top + bp->r_mm + 5};
    cs_pos_t zq;
    if (cs_conv_mm_to_pos(ctx.safe_z, &zq) != CS_OK) {
        fprintf(stderr, "curvestep toolpath: safe height %g mm outside +/-%d mm\n", ctx.safe_z,
                CS_POS_LIMIT_MM);
        return CS_EXIT_USAGE;
    }
    if (o->gcode) /* up first, so the first travel does not cross the part */
        fprintf(o->gcode, "G0 Z%.6f\n", cs_conv_pos_to_mm(zq));
    cs_patch_t *cells = NULL;
    for (size_t i = 0; i < sf->n; i++) {
        /* A triangle is finished as its exact collapsed tensor form, along its iso-lines u; an
         * n-sided patch as bicubic cells fitted within tol / 2 (cs_varady_patches), each cell
         * its own block. */
        const cs_surf_item_t *it = &sf->items[i];
        cs_patch_t tq;
        size_t ncell = 1;
        const cs_patch_t *list = &it->quad;
        cs_err_t e = CS_OK;
        if (it->sphere) {
            ncell = 0;
            ctx.patch_start = true;
            e = finish_sphere(&ctx, &it->sph, bp, tol, st);
        } else if (it->tri) {
            e = cs_finish_tri_patch(&it->trip, &tq);
            list = &tq;
        } else if (it->varady) {
            if (!cells && !(cells = malloc(CS_VARADY_MAX_PATCHES * sizeof *cells)))
                e = CS_ERR_FULL;
            double fit = 0;
            if (e == CS_OK)
                e = cs_varady_patches(&it->nside, cs_conv_pos_to_mm(tol) / 2, cells, NULL,
                                      CS_VARADY_MAX_PATCHES, &ncell, &fit);
            if (e == CS_OK && *fit_out < fit)
                *fit_out = fit;
            list = cells;
        }
        for (size_t c = 0; e == CS_OK && c < ncell; c++) {
            ctx.patch_start = true;
            e = cs_finish_patch(&list[c], bp->r_mm, bp->h_mm, tol, ball_emit, &ctx, st);
            if (e == CS_OK && c + 1 < ncell) {
                cs_vec3_t up = ctx.last;
                up.z = zq;
                if (!out_vertex_g(o, &up, false, true))
                    e = CS_ERR_FULL;
            }
        }
        if (e != CS_OK) {
            free(cells);
            cs_path_diag_t d;
            cs_path_loc_t l = {sf->file, sf->items[i].line, 1};
            cs_path_diag_set(&d, e, l, "patch %zu: cannot plan the finishing passes: %s", i + 1,
                             cs_err_text(e));
            cs_path_diag_print(stderr, &d);
            return e == CS_ERR_FULL ? CS_EXIT_INTERNAL : CS_EXIT_INPUT;
        }
        cs_vec3_t up = ctx.last;
        up.z = zq;
        if (!out_vertex_g(o, &up, false, true)) { /* retract: a travel */
            free(cells);
            return CS_EXIT_INTERNAL;
        }
        o->curves++;
    }
    free(cells);
    if (st->gouge_points > 0)
        fprintf(stderr,
                "curvestep toolpath: warning: %zu surface samples are concave with a curvature "
                "radius below R = %g mm (smallest %.4g mm): the ball gouges there\n",
                st->gouge_points, bp->r_mm, st->min_radius);
    if (st->folded > 0)
        fprintf(stderr,
                "curvestep toolpath: warning: %zu chords of the tool path run backwards (first "
                "at u %.3f, v %.3f of a patch): the offset surface folds over itself where the "
                "surface is concave with a radius below R; %zu loops were cut out of their "
                "passes at the self-crossing, the other folds remain\n",
                st->folded, st->fold_u, st->fold_v, st->loops_cut);
    if (st->undercut > 0)
        fprintf(stderr,
                "curvestep toolpath: warning: %zu vertices have a downward normal (undercut): "
                "not reachable by a 3-axis tool from above\n",
                st->undercut);
    return CS_EXIT_OK;
}

/* --- picture ------------------------------------------------------------------------------ */

static cs_err_t write_svg(const char *file, const cs_path_poly_t *poly, const char *title)
{
    FILE *f = fopen(file, "w");
    if (!f)
        return CS_ERR_IO;
    double box[4] = {0, 0, 0, 0};
    for (size_t i = 0; i < poly->n; i++) {
        double x = poly->pts[i].x, y = poly->pts[i].y;
        if (i == 0 || x < box[0])
            box[0] = x;
        if (i == 0 || y < box[1])
            box[1] = y;
        if (i == 0 || x > box[2])
            box[2] = x;
        if (i == 0 || y > box[3])
            box[3] = y;
    }
    double w = box[2] - box[0], h = box[3] - box[1], ext = fmax(fmax(w, h), 1e-3);
    double m = 0.05 * ext, sw = ext / 800;
    double px =
        800.0 / (w + 2 * m) < 800.0 / (h + 2 * m) ? 800.0 / (w + 2 * m) : 800.0 / (h + 2 * m);
    fprintf(f,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" "
            "viewBox=\"%.6f %.6f %.6f %.6f\">\n",
            (w + 2 * m) * px, (h + 2 * m) * px, box[0] - m, -box[3] - m, w + 2 * m, h + 2 * m);
    fprintf(f, "<title>"); /* XML-escaped: "<stdin>" or a file name with & or < */
    for (const char *c = title; *c; c++)
        fputs(*c == '<' ? "&lt;" : *c == '>' ? "&gt;" : *c == '&' ? "&amp;" : (char[2]){*c, 0}, f);
    fprintf(f, "</title>\n");
    fprintf(f, "<rect x=\"%.6f\" y=\"%.6f\" width=\"%.6f\" height=\"%.6f\" fill=\"white\"/>\n",
            box[0] - m, -box[3] - m, w + 2 * m, h + 2 * m);
    /* y up: every y is negated (SVG's y points down). */
    fprintf(f,
            "<g fill=\"none\" stroke=\"#1f4e9a\" stroke-width=\"%.6f\" "
            "stroke-linejoin=\"round\" stroke-linecap=\"round\">\n",
            sw);
    for (size_t l = 0; l < poly->nlines; l++) {
        size_t s = poly->starts[l], n = cs_path_poly_len(poly, l);
        fprintf(f, "<polyline points=\"");
        for (size_t k = 0; k < n; k++)
            fprintf(f, "%s%.5f,%.5f", k ? " " : "", poly->pts[s + k].x, -poly->pts[s + k].y);
        fprintf(f, "\"/>\n");
    }
    fprintf(f, "</g>\n</svg>\n");
    bool bad = ferror(f) != 0;
    if (fclose(f) != 0 || bad)
        return CS_ERR_IO;
    return CS_OK;
}

/* --- command ------------------------------------------------------------------------------ */

/* The command line of the wireframe and normal-offset modes. */
typedef struct {
    const char *file, *svg_out, *gcode_out;
    tp_view_t view;
    double tol_mm, scale;
    unsigned lines;
    bool stats, ball, have_h;
    tp_ball_t bp;
} tp_args_t;

/* One option's value into *a: CS_EXIT_OK, CS_EXIT_USAGE (message printed), or -1 for --help. */
static int tp_option(int c, const char *v, char **argv, tp_args_t *a)
{
    double d = 0;
    cs_pos_t t = 0;
    switch (c) {
    case 'p': a->file = v; return CS_EXIT_OK;
    case 'o': a->svg_out = v; return CS_EXIT_OK;
    case 'g': a->gcode_out = v; return CS_EXIT_OK;
    case 's': a->stats = true; return CS_EXIT_OK;
    case 'h': return -1;
    case 'v':
        if (parse_view(v, &a->view))
            return CS_EXIT_OK;
        fprintf(stderr, "curvestep toolpath: --view '%s': expected top, front, side, iso or 12 "
                        "comma-separated numbers\n", v);
        return CS_EXIT_USAGE;
    case 'n':
        if (!cs_conv_number(v, &d) || d != floor(d) || d < 1 || d > TP_MAX_LINES) {
            fprintf(stderr, "curvestep toolpath: --lines '%s': expected an integer 1..%d\n", v,
                    TP_MAX_LINES);
            return CS_EXIT_USAGE;
        }
        a->lines = (unsigned)d;
        return CS_EXIT_OK;
    case 't':
        if (cs_conv_number(v, &a->tol_mm) && cs_conv_tol_to_pos(a->tol_mm, &t) == CS_OK &&
            t >= CS_TRACE_TOL_MIN && t <= CS_TRACE_TOL_MAX)
            return CS_EXIT_OK;
        fprintf(stderr, "curvestep toolpath: --tol '%s': expected a tolerance in mm, from %.7f to %d\n",
                v, (double)CS_TRACE_TOL_MIN / CS_POS_ONE_MM, CS_POS_LIMIT_MM);
        return CS_EXIT_USAGE;
    case 'S':
        if (cs_conv_number(v, &a->scale) && a->scale > 0)
            return CS_EXIT_OK;
        fprintf(stderr, "curvestep toolpath: --scale '%s': expected a number > 0\n", v);
        return CS_EXIT_USAGE;
    case 'b':
        a->ball = true;
        if (cs_conv_number(v, &a->bp.r_mm) && a->bp.r_mm > 0 && a->bp.r_mm <= 100)
            return CS_EXIT_OK;
        fprintf(stderr, "curvestep toolpath: --ball '%s': expected a radius in mm, 0 < R <= 100\n", v);
        return CS_EXIT_USAGE;
    case 'H':
        a->have_h = true;
        if (cs_conv_number(v, &a->bp.h_mm) && a->bp.h_mm > 0)
            return CS_EXIT_OK;
        fprintf(stderr, "curvestep toolpath: --scallop '%s': expected a height in mm > 0\n", v);
        return CS_EXIT_USAGE;
    case 'z':
        a->bp.have_safe_z = true;
        if (cs_conv_number(v, &a->bp.safe_z_mm) && fabs(a->bp.safe_z_mm) <= CS_POS_LIMIT_MM)
            return CS_EXIT_OK;
        fprintf(stderr, "curvestep toolpath: --safe-z '%s': expected a height in mm\n", v);
        return CS_EXIT_USAGE;
    default:
        fprintf(stderr, "curvestep toolpath: %s '%s'\nTry 'curvestep toolpath --help'.\n",
                c == ':' ? "option needs a value:" : "unknown option", argv[optind - 1]);
        return CS_EXIT_USAGE;
    }
}

/* Parses the command line into *a: CS_EXIT_OK, CS_EXIT_USAGE, or -1 after --help (printed). */
static int tp_parse(int argc, char **argv, tp_args_t *a)
{
    static const struct option longopts[] = {
        {"patches", required_argument, NULL, 'p'}, {"view", required_argument, NULL, 'v'},
        {"lines", required_argument, NULL, 'n'},   {"tol", required_argument, NULL, 't'},
        {"scale", required_argument, NULL, 'S'},   {"ball", required_argument, NULL, 'b'},
        {"scallop", required_argument, NULL, 'H'}, {"safe-z", required_argument, NULL, 'z'},
        {"stats", no_argument, NULL, 's'},         {"svg", required_argument, NULL, 'o'},
        {"gcode", required_argument, NULL, 'g'},   {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0},
    };
    int c;
    optind = 1;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":h", longopts, NULL)) != -1) {
        int r = tp_option(c, optarg, argv, a);
        if (r == -1)
            tp_usage(stdout);
        if (r != CS_EXIT_OK)
            return r;
    }
    if (optind != argc || !a->file) {
        fprintf(stderr, "curvestep toolpath: %s\nTry 'curvestep toolpath --help'.\n",
                optind != argc ? "unexpected argument (the file goes after --patches)"
                               : "missing --patches FILE");
        return CS_EXIT_USAGE;
    }
    if (a->ball != a->have_h || (a->ball && a->bp.h_mm >= a->bp.r_mm)) {
        fprintf(stderr, "curvestep toolpath: --ball R and --scallop H go together, 0 < H < R\n");
        return CS_EXIT_USAGE;
    }
    if (!a->ball && a->bp.have_safe_z) {
        fprintf(stderr, "curvestep toolpath: --safe-z needs --ball\n");
        return CS_EXIT_USAGE;
    }
    return CS_EXIT_OK;
}

/* The G-code file's header; false when it cannot be opened (reported). */
static bool tp_gcode_open(const tp_args_t *a, tp_out_t *o, const char *shown)
{
    o->gcode = fopen(a->gcode_out, "w");
    if (!o->gcode) {
        fprintf(stderr, "%s:0:0: cannot write the G-code\n", a->gcode_out);
        return false;
    }
    /* Parentheses would end the comment early: the file name is only cited when it has none. */
    bool plain = strchr(shown, '(') == NULL && strchr(shown, ')') == NULL;
    if (a->ball)
        fprintf(o->gcode, "(curvestep toolpath: finishing of %s, ball R %g mm, tool centre)\n",
                plain ? shown : "the input", a->bp.r_mm);
    else
        fprintf(o->gcode, "(curvestep toolpath: wireframe of %s, view %s)\n",
                plain ? shown : "the input", a->view.name);
    fprintf(o->gcode, "G21 G90\n");
    return true;
}

/* Traces every item (wireframe) or finishes them (--ball); closes the G-code. */
static int tp_run(tp_args_t *a, const cs_surffile_t *sf, tp_out_t *o, cs_finish_stats_t *fst,
                  double *varady_fit)
{
    cs_pos_t tol;
    cs_conv_tol_to_pos(a->tol_mm, &tol); /* validated by tp_option */
    int status = CS_EXIT_OK;
    if (a->ball)
        status = finish_all(o, sf, tol, &a->bp, fst, varady_fit);
    for (size_t i = 0; i < sf->n && status == CS_EXIT_OK && !a->ball; i++) {
        const cs_surf_item_t *it = &sf->items[i];
        cs_err_t e = it->tri      ? wire_tri(o, &it->trip, a->lines, tol)
                     : it->varady ? wire_varady(o, &it->nside, a->lines, tol)
                     : it->sphere ? wire_sphere(o, &it->sph, a->lines, tol)
                                  : wire_patch(o, &it->quad, a->lines, tol);
        if (e != CS_OK) {
            cs_path_diag_t diag;
            cs_path_loc_t l = {sf->file, it->line, 1};
            cs_path_diag_set(&diag, e, l, "patch %zu: %s", i + 1, cs_err_text(e));
            cs_path_diag_print(stderr, &diag);
            status = CS_EXIT_INTERNAL;
        }
    }
    if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "curvestep toolpath: error writing the output\n");
        if (status == CS_EXIT_OK)
            status = CS_EXIT_INTERNAL;
    }
    if (o->gcode) {
        fprintf(o->gcode, "%sM2\n", o->pen ? "M5\n" : "");
        bool bad = ferror(o->gcode) != 0;
        if ((fclose(o->gcode) != 0 || bad) && status == CS_EXIT_OK) {
            fprintf(stderr, "%s:0:0: cannot write the G-code\n", a->gcode_out);
            status = CS_EXIT_INTERNAL;
        }
    }
    return status;
}

/* --stats on stderr and the --svg picture. */
static int tp_report(const tp_args_t *a, const cs_surffile_t *sf, const tp_out_t *o,
                     const cs_finish_stats_t *fst, double varady_fit, const char *shown)
{
    if (a->stats) {
        fprintf(stderr, "toolpath: %s: %zu patches, %zu curves, %zu chords, view %s\n", shown,
                sf->n, o->curves, o->chords, a->view.name);
        if (a->ball)
            fprintf(stderr,
                    "toolpath: ball R %.6g mm, scallop %.6g mm: %zu passes, measured scallop "
                    "%.6f mm (between pass centres, double)\n",
                    a->bp.r_mm, a->bp.h_mm, fst->passes, fst->max_scallop);
        if (a->ball && varady_fit > 0)
            fprintf(stderr,
                    "toolpath: n-sided patches finished as fitted bicubic cells within %.6f mm "
                    "(sampled, 9 x 9 per cell)\n",
                    varady_fit);
        if (!a->ball)
            fprintf(stderr,
                    "toolpath: tolerance %.6g mm, max deviation %.6f mm (chords against their "
                    "exact curves, 3D, measured in double)\n",
                    a->tol_mm, o->maxdev);
    }
    if (a->svg_out && write_svg(a->svg_out, &o->poly, shown) != CS_OK) {
        fprintf(stderr, "%s:0:0: cannot write the picture\n", a->svg_out);
        return CS_EXIT_INTERNAL;
    }
    return CS_EXIT_OK;
}

int cs_cmd_toolpath(int argc, char **argv)
{
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0)
            break;
        if (strncmp(argv[i], "--cutter", 8) == 0 && (argv[i][8] == '\0' || argv[i][8] == '='))
            return cs_cmd_toolpath_drop(argc, argv);
    }
    tp_args_t a = {NULL, NULL, NULL, views[3], TP_DEFAULT_TOL_MM, 1.0, TP_DEFAULT_LINES,
                   false, false, false, {0, 0, 0, false}};
    int status = tp_parse(argc, argv, &a);
    if (status != CS_EXIT_OK)
        return status == -1 ? CS_EXIT_OK : status;
    cs_surffile_t sf;
    /* Surfaces of revolution are approximated within tol / 4 before tracing. */
    status = cs_surffile_load("curvestep toolpath", a.file, a.scale, a.tol_mm / 4, &sf);
    if (status != CS_EXIT_OK)
        return status;
    const char *shown = strcmp(a.file, "-") == 0 ? "<stdin>" : a.file;
    cs_finish_stats_t fst = {0, 0, 0, 0, 0.0, HUGE_VAL, 0, 0, 0, 0, 0, 0};
    double varady_fit = 0; /* n-sided patches: largest sampled distance of the fitted cells */
    tp_out_t o = {&a.view, a.ball, true, NULL, false, {0}, NULL, 0, 0, 0, 0, 0.0, a.stats};
    cs_path_poly_init(&o.poly);
    if (a.gcode_out && !tp_gcode_open(&a, &o, shown))
        status = CS_EXIT_INTERNAL;
    if (status == CS_EXIT_OK)
        status = tp_run(&a, &sf, &o, &fst, &varady_fit);
    if (status == CS_EXIT_OK)
        status = tp_report(&a, &sf, &o, &fst, varady_fit, shown);
    free(o.v);
    cs_path_poly_free(&o.poly);
    cs_surffile_free(&sf);
    return status;
}
