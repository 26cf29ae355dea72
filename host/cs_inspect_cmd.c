/* curvestep inspect: what a file holds, element by element, before anything is cut. For a job
 * (curves file, SVG, G-code, HP-GL: cs_input) each element's kind, degree, arc length
 * (cs_arclen) and box (cs_bezier_bbox), and at each join inside a subpath its continuity class
 * (cs_join_classify, from the end control points: seed 003, "Continuité") with the measured
 * mismatch in double; for a surfaces file (native, Newell, .bpt: cs_surffile) each patch's kind,
 * degrees and box, and along each shared edge of two tensor patches its continuity
 * (cs_patch_continuity, plus C2 measured here). A summary line; --json for scripts. */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_arclen.h"
#include "cs_cmd.h"
#include "cs_conv.h"
#include "cs_err_text.h"
#include "cs_input.h"
#include "cs_join.h"
#include "cs_lex.h"
#include "cs_surffile.h"
#include "cs_svgdoc.h"

#define INSPECT_DEFAULT_TOL_MM 0.001
#define INSPECT_DEFAULT_REL    0.001
/* Arc lengths to within this many LSB (cs_arclen_length's tol). */
#define INSPECT_LENGTH_TOL_LSB 4

typedef struct {
    bool json;
    double tol_mm, rel;
} inspect_opts_t;

static void inspect_usage(FILE *f)
{
    fprintf(f,
            "Usage: curvestep inspect [--json] [--tol MM] [--rel R] [--patches] FILE\n"
            "\n"
            "Describes what FILE holds without cutting it. Any job curvestep reads (curves\n"
            "file, SVG, G-code, HP-GL; see 'curvestep flatten --help'): one line per element\n"
            "with its kind, degree, arc length (mm) and bounding box (mm; tight for degree <= 3,\n"
            "the control points' box otherwise), then one line per join of two elements inside\n"
            "a subpath with its continuity class (C2, G2, C1, G1, C0, or 'gap') and the measured\n"
            "mismatch: gap (mm), angle between the tangents (degrees), |difference| of the\n"
            "first and second derivatives (mm per unit t, per unit t^2) and of the curvature\n"
            "vectors (1/mm). A surfaces file (first token 'curvestep-surfaces', or any file\n"
            "with --patches: Newell's format or .bpt) gives one line per patch and, for each\n"
            "edge two tensor patches share, its continuity (C0, G1, C1, C2: cs_patch_continuity\n"
            "within --tol). A summary line\n"
            "ends the report.\n"
            "\n"
            "Options:\n"
            "  --json        one JSON object on stdout instead of the text report\n"
            "  --tol MM      position tolerance of the classes (default %g mm): points closer\n"
            "                than MM are equal, derivatives within MM (absolute) too\n"
            "  --rel R       relative tolerance of derivatives and curvatures, and the sine of\n"
            "                the largest angle G1 accepts (default %g)\n"
            "  --patches     read FILE as a surfaces file (Newell's format or .bpt)\n"
            "  -h, --help    show this help\n"
            "\n"
            "Exit status: 0 success; 1 bad input (\"file:line:col: reason\" on stderr); 2 usage\n"
            "error; 3 internal error (out of memory, I/O).\n",
            INSPECT_DEFAULT_TOL_MM, INSPECT_DEFAULT_REL);
}

/* A JSON string (RFC 8259, section 7). */
static void json_str(const char *s)
{
    putchar('"');
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            printf("\\%c", c);
        else if (c < 0x20)
            printf("\\u%04x", c);
        else
            putchar(c);
    }
    putchar('"');
}

/* A measurement, or null (JSON) / "-" (text) when it could not be made. */
static void num(bool json, double v)
{
    if (!isfinite(v))
        fputs(json ? "null" : "-", stdout);
    else
        printf("%.6g", v);
}

/* ---------------------------------------------------------------- joins of curve elements */

typedef struct {
    double gap, angle, d1, d2, dk; /* mm, degrees, mm/t, mm/t^2, 1/mm; NaN when not defined */
    unsigned flags;
} join_t;

static void pt_mm(const cs_vec3_t *p, double o[3])
{
    o[0] = cs_conv_pos_to_mm(p->x);
    o[1] = cs_conv_pos_to_mm(p->y);
    o[2] = cs_conv_pos_to_mm(p->z);
}

/* First and second derivatives of c at its end (end = true, t = 1) or start, in mm per unit t
 * (cs_join.h: B'(1) = n w_{n-1}/w_n (P_n - P_{n-1}), B''(1) = n (n-1) (P_n - 2 P_{n-1} +
 * P_{n-2}) for polynomial segments; rational: the second derivative is not measured, NaN). */
static void end_derivs(const cs_bezier_t *c, bool end, double d1[3], double d2[3])
{
    unsigned n = c->degree;
    int a = end ? (int)n : 0, s = end ? -1 : 1;
    double p0[3], p1[3], p2[3];
    pt_mm(&c->p[a], p0);
    pt_mm(&c->p[a + s], p1);
    pt_mm(&c->p[n >= 2 ? a + 2 * s : a + s], p2);
    double wr = c->rational ? (double)c->w[a + s] / c->w[a] : 1;
    for (int k = 0; k < 3; k++) {
        d1[k] = end ? n * wr * (p0[k] - p1[k]) : n * wr * (p1[k] - p0[k]);
        d2[k] = c->rational ? NAN : n >= 2 ? n * (n - 1.0) * (p0[k] - 2 * p1[k] + p2[k]) : 0;
    }
}

static double norm3(const double v[3])
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/* Curvature vector (d2 - (d2.T) T) / |d1|^2, T = d1 / |d1| (NaN when d1 = 0). */
static void curvature(const double d1[3], const double d2[3], double k[3])
{
    double l = norm3(d1), dot = 0;
    for (int i = 0; i < 3; i++)
        dot += d2[i] * d1[i] / (l * l);
    for (int i = 0; i < 3; i++)
        k[i] = (d2[i] - dot * d1[i]) / (l * l);
}

static cs_err_t measure_join(const cs_bezier_t *a, const cs_bezier_t *b, const cs_join_tol_t *tol,
                             join_t *j)
{
    double pa[3], pb[3], a1[3], a2[3], b1[3], b2[3], ka[3], kb[3], dd[3];
    pt_mm(&a->p[a->degree], pa);
    pt_mm(&b->p[0], pb);
    end_derivs(a, true, a1, a2);
    end_derivs(b, false, b1, b2);
    curvature(a1, a2, ka);
    curvature(b1, b2, kb);
    double dot = 0;
    for (int k = 0; k < 3; k++) {
        dot += a1[k] * b1[k];
        dd[k] = pa[k] - pb[k];
    }
    j->gap = norm3(dd);
    j->angle = acos(fmax(-1, fmin(1, dot / (norm3(a1) * norm3(b1))))) * 180 / M_PI;
    for (int k = 0; k < 3; k++)
        dd[k] = a1[k] - b1[k];
    j->d1 = norm3(dd);
    for (int k = 0; k < 3; k++)
        dd[k] = a2[k] - b2[k];
    j->d2 = norm3(dd);
    for (int k = 0; k < 3; k++)
        dd[k] = ka[k] - kb[k];
    j->dk = norm3(dd);
    return cs_join_classify(a, b, tol, &j->flags);
}

/* The strongest class of a join in the order C0 < G1 < C1 < G2 < C2 (issue 19). */
static const char *join_class(unsigned f)
{
    if (f & CS_JOIN_C2)
        return "C2";
    if (f & CS_JOIN_G2)
        return "G2";
    if (f & CS_JOIN_C1)
        return "C1";
    if (f & CS_JOIN_G1)
        return "G1";
    return (f & CS_JOIN_C0) ? "C0" : "gap";
}

#define NCLASSES 6
static int class_index(unsigned f)
{
    static const char *const names[NCLASSES] = {"C2", "G2", "C1", "G1", "C0", "gap"};
    for (int i = 0; i < NCLASSES; i++)
        if (strcmp(names[i], join_class(f)) == 0)
            return i;
    return NCLASSES - 1;
}

static void print_elem(const inspect_opts_t *o, size_t i, const cs_path_elem_t *el)
{
    const cs_bezier_t *c = &el->curve;
    cs_pos_t len = 0;
    double lmm =
        cs_arclen_length(c, INSPECT_LENGTH_TOL_LSB, &len) == CS_OK ? cs_conv_pos_to_mm(len) : NAN;
    cs_vec3_t lo, hi;
    double b[6] = {NAN, NAN, NAN, NAN, NAN, NAN};
    if (cs_bezier_bbox(c, &lo, &hi) == CS_OK) {
        pt_mm(&lo, b);
        pt_mm(&hi, b + 3);
    }
    if (o->json) {
        printf("%s\n    {\"index\": %zu, \"kind\": \"%s\", \"degree\": %u, \"rational\": %s, "
               "\"subpath\": %u, \"line\": %u, \"col\": %u, \"length_mm\": ",
               i ? "," : "", i + 1, cs_path_kind_name(el->kind), c->degree,
               c->rational ? "true" : "false", el->subpath, el->loc.line, el->loc.col);
        num(true, lmm);
        printf(", \"bbox_mm\": [");
        for (int k = 0; k < 6; k++) {
            printf(k ? ", " : "");
            num(true, b[k]);
        }
        printf("]}");
        return;
    }
    printf("element %zu %s:%u:%u: %s degree %u%s, length ", i + 1, el->loc.file, el->loc.line,
           el->loc.col, cs_path_kind_name(el->kind), c->degree, c->rational ? " rational" : "");
    num(false, lmm);
    printf(" mm, box (%.4f %.4f %.4f)-(%.4f %.4f %.4f)\n", b[0], b[1], b[2], b[3], b[4], b[5]);
}

static void print_join(const inspect_opts_t *o, size_t i, const join_t *j, bool first)
{
    double v[5] = {j->gap, j->angle, j->d1, j->d2, j->dk};
    static const char *const keys[5] = {"gap_mm", "angle_deg", "d1_mm", "d2_mm", "dk_per_mm"};
    if (o->json) {
        printf("%s\n    {\"after\": %zu, \"class\": \"%s\", \"flags\": [", first ? "" : ",", i + 1,
               join_class(j->flags));
        static const char *const fl[5] = {"C0", "G1", "C1", "G2", "C2"};
        for (int k = 0, n = 0; k < 5; k++)
            if (j->flags & (1u << k))
                printf("%s\"%s\"", n++ ? ", " : "", fl[k]);
        printf("]");
        for (int k = 0; k < 5; k++) {
            printf(", \"%s\": ", keys[k]);
            num(true, v[k]);
        }
        printf("}");
        return;
    }
    printf("join %zu-%zu: %s (gap ", i + 1, i + 2, join_class(j->flags));
    for (int k = 0; k < 5; k++) {
        num(false, v[k]);
        printf("%s", k == 0   ? " mm, angle "
                     : k == 1 ? " deg, |d1| "
                     : k == 2 ? ", |d2| "
                     : k == 3 ? ", |dk| "
                              : " 1/mm)\n");
    }
}

static int inspect_path(const inspect_opts_t *o, const char *name, cs_input_format_t f,
                        const cs_path_t *p)
{
    cs_join_tol_t tol;
    if (cs_conv_mm_to_pos(o->tol_mm, &tol.pos) != CS_OK ||
        cs_conv_to_param(o->rel, &tol.rel) != CS_OK)
        return CS_EXIT_USAGE; /* checked by the option parser */
    tol.sin_angle = tol.rel;
    if (o->json) {
        printf("{\"file\": ");
        json_str(name);
        printf(", \"format\": \"%s\", \"elements\": [", cs_input_format_name(f));
    }
    double total = 0;
    for (size_t i = 0; i < p->n; i++) {
        print_elem(o, i, &p->elems[i]);
        cs_pos_t len;
        if (cs_arclen_length(&p->elems[i].curve, INSPECT_LENGTH_TOL_LSB, &len) == CS_OK)
            total += cs_conv_pos_to_mm(len);
    }
    if (o->json)
        printf("\n  ],\n  \"joins\": [");
    size_t count[NCLASSES] = {0}, nj = 0;
    for (size_t i = 0; i + 1 < p->n; i++) {
        if (p->elems[i].subpath != p->elems[i + 1].subpath)
            continue;
        join_t j;
        cs_err_t e = measure_join(&p->elems[i].curve, &p->elems[i + 1].curve, &tol, &j);
        if (e != CS_OK)
            j.flags = 0; /* a curvature out of range: report the measured mismatch only */
        print_join(o, i, &j, nj == 0);
        count[class_index(j.flags)]++;
        nj++;
    }
    static const char *const names[NCLASSES] = {"C2", "G2", "C1", "G1", "C0", "gap"};
    if (o->json) {
        printf("\n  ],\n  \"summary\": {\"elements\": %zu, \"subpaths\": %u, \"length_mm\": %.6g, "
               "\"joins\": %zu",
               p->n, p->nsubpaths, total, nj);
        for (int k = 0; k < NCLASSES; k++)
            printf(", \"%s\": %zu", names[k], count[k]);
        printf("}}\n");
        return CS_EXIT_OK;
    }
    printf("inspect: %s (%s): %zu elements in %u subpaths, length %.6g mm; %zu joins:", name,
           cs_input_format_name(f), p->n, p->nsubpaths, total, nj);
    for (int k = 0; k < NCLASSES; k++)
        printf(" %zu %s%s", count[k], names[k], k + 1 < NCLASSES ? "," : "\n");
    return CS_EXIT_OK;
}

/* ---------------------------------------------------------------- surfaces */

/* Patch edges, named by the parameter held fixed. */
enum { EDGE_U0, EDGE_U1, EDGE_V0, EDGE_V1 };
static const char *const edge_names[4] = {"u=0", "u=1", "v=0", "v=1"};

static void flip_u(cs_patch_t *p)
{
    for (int i = 0; i < (p->deg_u + 1) / 2; i++)
        for (int j = 0; j <= p->deg_v; j++) {
            cs_vec3_t t = p->p[i][j];
            p->p[i][j] = p->p[p->deg_u - i][j];
            p->p[p->deg_u - i][j] = t;
        }
}

static void flip_v(cs_patch_t *p)
{
    cs_patch_t t;
    cs_patch_transpose(p, &t);
    flip_u(&t);
    cs_patch_transpose(&t, p);
}

/* p turned so that its edge e is u = 1 (at_end) or u = 0 (else), v along the edge. */
static void orient(cs_patch_t *p, int e, bool at_end)
{
    if (e == EDGE_V0 || e == EDGE_V1)
        cs_patch_transpose(p, p);
    bool is_end = e == EDGE_U1 || e == EDGE_V1;
    if (is_end != at_end)
        flip_u(p);
}

/* True when a's edge u = 1 is a single point (a collapsed edge, as at the teapot's lid: every
 * patch meeting there would "share" it). */
static bool edge_is_point(const cs_patch_t *a)
{
    for (int j = 1; j <= a->deg_v; j++)
        if (memcmp(&a->p[a->deg_u][j], &a->p[a->deg_u][0], sizeof a->p[0][0]) != 0)
            return false;
    return true;
}

/* The continuity of the first shared edge of patches a and b (either orientation), or false. */
static bool shared_edge(const cs_patch_t *a, const cs_patch_t *b, const inspect_opts_t *o, int *ea,
                        int *eb, const char **cls)
{
    cs_pos_t tol;
    cs_param_t sin_tol;
    cs_conv_mm_to_pos(o->tol_mm, &tol);
    cs_conv_to_param(o->rel, &sin_tol);
    for (*ea = 0; *ea < 4; (*ea)++)
        for (*eb = 0; *eb < 4; (*eb)++)
            for (int rev = 0; rev < 2; rev++) {
                cs_patch_t pa = *a, pb = *b;
                orient(&pa, *ea, true);
                orient(&pb, *eb, false);
                if (rev)
                    flip_v(&pb);
                cs_patch_cont_t c;
                if (pa.deg_v != pb.deg_v || edge_is_point(&pa) ||
                    cs_patch_continuity(&pa, &pb, tol, sin_tol, &c) != CS_OK ||
                    c == CS_PATCH_CONT_NONE)
                    continue;
                static const char *const names[5] = {"none", "C0", "G1", "C1", "C2"};
                *cls = names[c];
                return true;
            }
    return false;
}

/* Box of a surface item's control points (which contains the surface: convex hull); a
 * sphere's own box. */
static void item_box(const cs_surf_item_t *it, double b[6])
{
    for (int k = 0; k < 3; k++) {
        b[k] = INFINITY;
        b[k + 3] = -INFINITY;
    }
    const cs_vec3_t *pts[CS_VARADY_MAX_SIDES * CS_BEZIER_MAX_POINTS];
    size_t n = 0;
    if (it->sphere) {
        for (int k = 0; k < 3; k++) {
            b[k] = it->sph.c[k] - it->sph.r;
            b[k + 3] = it->sph.c[k] + it->sph.r;
        }
        return;
    }
    if (it->tri) {
        for (unsigned i = 0; i < (it->trip.degree + 1u) * (it->trip.degree + 2u) / 2; i++)
            pts[n++] = &it->trip.p[i];
    } else if (it->varady) {
        for (size_t s = 0; s < it->nside.n; s++)
            for (unsigned i = 0; i <= it->nside.side[s].degree; i++)
                pts[n++] = &it->nside.side[s].p[i];
    } else {
        for (int i = 0; i <= it->quad.deg_u; i++)
            for (int j = 0; j <= it->quad.deg_v; j++)
                pts[n++] = &it->quad.p[i][j];
    }
    for (size_t i = 0; i < n; i++) {
        double q[3];
        pt_mm(pts[i], q);
        for (int k = 0; k < 3; k++) {
            b[k] = fmin(b[k], q[k]);
            b[k + 3] = fmax(b[k + 3], q[k]);
        }
    }
}

static void print_item(const inspect_opts_t *o, const cs_surffile_t *sf, size_t i)
{
    const cs_surf_item_t *it = &sf->items[i];
    char kind[48];
    if (it->sphere)
        snprintf(kind, sizeof kind, "sphere radius %g", it->sph.r);
    else if (it->tri)
        snprintf(kind, sizeof kind, "triangle degree %u", it->trip.degree);
    else if (it->varady)
        snprintf(kind, sizeof kind, "%zu-sided", it->nside.n);
    else
        snprintf(kind, sizeof kind, "tensor degree %u x %u", it->quad.deg_u, it->quad.deg_v);
    double b[6];
    item_box(it, b);
    if (o->json) {
        printf("%s\n    {\"index\": %zu, \"kind\": \"%s\", \"line\": %u, \"bbox_mm\": [",
               i ? "," : "", i + 1, kind, it->line);
        for (int k = 0; k < 6; k++) {
            printf(k ? ", " : "");
            num(true, b[k]);
        }
        printf("]}");
        return;
    }
    printf("patch %zu %s:%u: %s, box (%.4f %.4f %.4f)-(%.4f %.4f %.4f)\n", i + 1, sf->file,
           it->line, kind, b[0], b[1], b[2], b[3], b[4], b[5]);
}

#define NPCLASSES 4
static int inspect_surfaces(const inspect_opts_t *o, const cs_surffile_t *sf)
{
    static const char *const names[NPCLASSES] = {"C2", "C1", "G1", "C0"};
    size_t count[NPCLASSES] = {0}, ne = 0;
    if (o->json) {
        printf("{\"file\": ");
        json_str(sf->file);
        printf(", \"format\": \"%s\", \"patches\": [", sf->native ? "surfaces" : "patches");
    }
    for (size_t i = 0; i < sf->n; i++)
        print_item(o, sf, i);
    if (o->json)
        printf("\n  ],\n  \"edges\": [");
    for (size_t i = 0; i < sf->n; i++)
        for (size_t j = i + 1; j < sf->n; j++) {
            const cs_surf_item_t *a = &sf->items[i], *b = &sf->items[j];
            int ea, eb;
            const char *cls;
            if (a->tri || a->varady || a->sphere || b->tri || b->varady || b->sphere ||
                !shared_edge(&a->quad, &b->quad, o, &ea, &eb, &cls))
                continue;
            for (int k = 0; k < NPCLASSES; k++)
                count[k] += strcmp(cls, names[k]) == 0;
            if (o->json)
                printf("%s\n    {\"patches\": [%zu, %zu], \"edges\": [\"%s\", \"%s\"], "
                       "\"class\": \"%s\"}",
                       ne ? "," : "", i + 1, j + 1, edge_names[ea], edge_names[eb], cls);
            else
                printf("edge patch %zu (%s) - patch %zu (%s): %s\n", i + 1, edge_names[ea], j + 1,
                       edge_names[eb], cls);
            ne++;
        }
    if (o->json) {
        printf("\n  ],\n  \"summary\": {\"patches\": %zu, \"edges\": %zu", sf->n, ne);
        for (int k = 0; k < NPCLASSES; k++)
            printf(", \"%s\": %zu", names[k], count[k]);
        printf("}}\n");
        return CS_EXIT_OK;
    }
    printf("inspect: %s (%s): %zu patches, %zu shared edges:", sf->file,
           sf->native ? "surfaces" : "patches", sf->n, ne);
    for (int k = 0; k < NPCLASSES; k++)
        printf(" %zu %s%s", count[k], names[k], k + 1 < NPCLASSES ? "," : "\n");
    return CS_EXIT_OK;
}

/* ---------------------------------------------------------------- the command */

static bool is_surfaces(const char *file, const char *buf, size_t len)
{
    const char *dot = strrchr(file, '.');
    if (dot && strcmp(dot, ".bpt") == 0)
        return true;
    cs_lex_t lx;
    cs_lex_init(&lx, buf, len, "", NULL, 1);
    return cs_lex_next(&lx) && strcmp(lx.tok, "curvestep-surfaces") == 0;
}

static int input_status(cs_err_t e)
{
    return (e == CS_ERR_FULL || e == CS_ERR_OVERFLOW) ? CS_EXIT_INTERNAL : CS_EXIT_INPUT;
}

static int inspect_file(const inspect_opts_t *o, const char *file, bool patches)
{
    char *buf = NULL;
    size_t len = 0;
    cs_path_diag_t diag;
    cs_err_t e = cs_svgdoc_load(file, &buf, &len, &diag);
    if (e != CS_OK) {
        cs_path_diag_print(stderr, &diag);
        return input_status(e);
    }
    const char *name = strcmp(file, "-") == 0 ? "<stdin>" : file;
    int status;
    if (patches || is_surfaces(file, buf, len)) {
        cs_surffile_t sf;
        e = cs_surffile_parse(buf, len, name, 1.0, o->tol_mm, &sf, &diag);
        status = e == CS_OK ? inspect_surfaces(o, &sf) : input_status(e);
        if (e != CS_OK)
            cs_path_diag_print(stderr, &diag);
        cs_surffile_free(&sf);
    } else {
        cs_path_t path;
        cs_path_init(&path);
        cs_input_format_t f = cs_input_detect(strcmp(file, "-") ? file : NULL, buf, len);
        cs_input_opts_t io;
        cs_input_opts_init(&io);
        io.format = f;
        e = cs_input_parse(name, buf, len, &io, &path, &diag);
        status = e == CS_OK ? inspect_path(o, name, f, &path) : input_status(e);
        if (e != CS_OK)
            cs_path_diag_print(stderr, &diag);
        cs_path_free(&path);
    }
    free(buf);
    return status;
}

static bool positive(const char *s, double lo, double hi, double *out)
{
    char *end = NULL;
    double v = strtod(s, &end);
    if (end == s || *end != '\0' || !(v >= lo && v <= hi))
        return false;
    *out = v;
    return true;
}

int cs_cmd_inspect(int argc, char **argv)
{
    static const struct option longopts[] = {
        {"json", no_argument, NULL, 'j'},      {"tol", required_argument, NULL, 't'},
        {"rel", required_argument, NULL, 'r'}, {"patches", no_argument, NULL, 'p'},
        {"help", no_argument, NULL, 'h'},      {NULL, 0, NULL, 0},
    };
    inspect_opts_t o = {false, INSPECT_DEFAULT_TOL_MM, INSPECT_DEFAULT_REL};
    bool patches = false;
    int c;
    optind = 1;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":h", longopts, NULL)) != -1) {
        const char *bad = NULL;
        if (c == 'j')
            o.json = true;
        else if (c == 'p')
            patches = true;
        else if (c == 't' && !positive(optarg, 1.0 / CS_POS_ONE_MM, CS_POS_LIMIT_MM, &o.tol_mm))
            bad = "--tol: expected a tolerance in mm, from 0.0000153 to 4096";
        else if (c == 'r' && !positive(optarg, 0, 1, &o.rel))
            bad = "--rel: expected a number from 0 to 1";
        else if (c == 'h') {
            inspect_usage(stdout);
            return CS_EXIT_OK;
        } else if (c == ':' || c == '?')
            bad = c == ':' ? "option needs a value" : "unknown option";
        if (bad) {
            fprintf(stderr, "curvestep inspect: %s ('%s')\nTry 'curvestep inspect --help'.\n", bad,
                    argv[optind - 1]);
            return CS_EXIT_USAGE;
        }
    }
    if (optind != argc - 1) {
        fprintf(stderr, "curvestep inspect: %s\nTry 'curvestep inspect --help'.\n",
                optind >= argc ? "missing FILE" : "expected exactly one FILE");
        return CS_EXIT_USAGE;
    }
    return inspect_file(&o, argv[optind], patches);
}
