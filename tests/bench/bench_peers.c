/* bench_peers: curvestep beside cairo and AGG in one run (issue 10). One corpus of planar cubics
 * (200 random cubics from a fixed xorshift seed plus the hard cubic cases of test_trace; every
 * cubic and quadratic of the SVG files in ../shared/data/svg, user unit = 1 mm; the Utah
 * teapot's iso-curves, 9 per family per patch, projected on z = 0, 10 mm per file unit) is
 * flattened by every curvestep method, by cairo (cairo_copy_path_flat after
 * cairo_set_tolerance) and by AGG (agg::curve4_div, tests/bench/agg_flat.cpp), at 0.1, 0.01 and
 * 0.001 mm. One judge (judge() below, double precision, the same code for every engine) measures
 * the largest distance between each polyline and the exact curve both ways. Throughput is the
 * median of 5 runs. Usage: bench_peers [out.csv]; Markdown on stdout, progress on stderr. */
#include <cairo.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_args.h"
#include "agg_flat.h"
#include "bench_curves.h"
#include "cs_arc.h"
#include "cs_patchfile.h"
#include "cs_ref.h"
#include "cs_svgdoc.h"
#include "cs_trace.h"
#include "ref_ellarc.h"

#define MAX_VERTS (1u << 21)
#define N_TOLS    3
#define N_ENG     7
#define N_CS      5 /* engines 0..4 are curvestep's */
#define ENG_PRED  4 /* the default tracer (CS_TRACE_DEFAULT) */
#define ENG_CAIRO 5
#define ENG_AGG   6
#define N_RUNS    5
/* cairo keeps paths in 24.8 fixed point device units: 1/256 mm with an identity matrix, coarser
 * than the 0.001 mm tolerance. Coordinates are therefore handed to cairo multiplied by
 * CAIRO_SCALE (still an identity matrix; tolerance multiplied alike) and divided back: its
 * grid becomes 2^-18 mm, 1/4 of curvestep's LSB. */
#define CAIRO_SCALE 1024.0

typedef struct {
    double x, y;
} pt2_t;

static const double tols_mm[N_TOLS] = {0.1, 0.01, 0.001};
static const char *eng_name[N_ENG] = {"curvestep FD (uniform, Wang)",
                                      "curvestep AFD",
                                      "curvestep subdiv dyadic",
                                      "curvestep subdiv reach (CS_TRACE_SUBDIV)",
                                      "curvestep predict (CS_TRACE_PREDICT, default)",
                                      "cairo copy_path_flat",
                                      "AGG curve4_div"};
static const cs_trace_method_t eng_method[N_CS] = {CS_TRACE_FD, CS_TRACE_AFD, CS_TRACE_SUBDIV,
                                                   CS_TRACE_SUBDIV, CS_TRACE_PREDICT};
static cs_vec3_t verts[MAX_VERTS];
static bench_rng_t rng = {BENCH_RNG_SEED};
static pt2_t poly[MAX_VERTS + 1];
static cairo_t *cr;
/* On curvestep's polylines: largest (judge - cs_ref_max_deviation) / tol, and largest
 * cs_ref_max_deviation / tol (the per-chord measure, stricter than Hausdorff). */
static double judge_gap, ref_worst;

static cs_pos_t mm(double v)
{
    return (cs_pos_t)lround(v * 65536);
}

static cs_bezier_t cubic(const double (*p)[2])
{
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = 3;
    for (unsigned i = 0; i <= 3; i++) {
        c.p[i] = cs_fixed_vec(mm(p[i][0]), mm(p[i][1]), 0);
        c.w[i] = CS_WEIGHT_ONE;
    }
    return c;
}

/* The planar cubic peers can take: z dropped; a polynomial quadratic elevated to degree 3 (its
 * inner points rounded to the LSB: every engine then gets that same cubic). False otherwise. */
static bool planar_cubic(const cs_bezier_t *in, cs_bezier_t *out)
{
    if (in->rational || (in->degree != 2 && in->degree != 3))
        return false;
    double p[4][2];
    for (unsigned i = 0; i <= 3; i++) {
        unsigned k = in->degree == 3 ? i : 0;
        cs_ref_vec_t a = cs_ref_from_pos(&in->p[k]);
        p[i][0] = a.x;
        p[i][1] = a.y;
    }
    if (in->degree == 2) {
        cs_ref_vec_t q0 = cs_ref_from_pos(&in->p[0]), q1 = cs_ref_from_pos(&in->p[1]),
                     q2 = cs_ref_from_pos(&in->p[2]);
        p[1][0] = q0.x + 2.0 / 3.0 * (q1.x - q0.x);
        p[1][1] = q0.y + 2.0 / 3.0 * (q1.y - q0.y);
        p[2][0] = q2.x + 2.0 / 3.0 * (q1.x - q2.x);
        p[2][1] = q2.y + 2.0 / 3.0 * (q1.y - q2.y);
        p[3][0] = q2.x;
        p[3][1] = q2.y;
    }
    *out = cubic((const double(*)[2])p);
    return true;
}

static void random_and_hard(bench_set_t *s)
{
    for (int k = 0; k < 200; k++) {
        double p[4][2];
        for (int i = 0; i < 4; i++)
            for (int a = 0; a < 2; a++)
                p[i][a] = (bench_rng_unit(&rng) * 2 - 1) * 100.0;
        cs_bezier_t c = cubic((const double(*)[2])p);
        bench_set_add(s, &c);
    }
    static const double hard[][4][2] = {
        {{0, 0}, {0, 0}, {50, 20}, {50, 20}},                   /* coincident */
        {{0, 0}, {100, 100}, {0, 100}, {100, 0}},               /* cusp */
        {{0, 0}, {150, 100}, {-50, 100}, {100, 0}},             /* loop */
        {{0, 0}, {33, 50}, {66, -50}, {100, 0}},                /* inflection */
        {{0, 0}, {100, 0}, {20, 0}, {60, 0}},                   /* collinear fold */
        {{-1000, -500}, {-300, 900}, {400, -900}, {1000, 500}}, /* 2 m */
    };
    for (size_t i = 0; i < sizeof hard / sizeof hard[0]; i++) {
        cs_bezier_t c = cubic(hard[i]);
        bench_set_add(s, &c);
    }
}

static void teapot_set(bench_set_t *s)
{
    cs_patchfile_t pf;
    cs_path_diag_t d;
    if (cs_patchfile_read("tests/data/teapot/newell_teapot.txt", &pf, &d) != CS_OK) {
        cs_path_diag_print(stderr, &d);
        cs_patchfile_free(&pf);
        return;
    }
    for (size_t i = 0; i < pf.npatches; i++) {
        cs_patch_t p;
        if (cs_patchfile_patch(&pf, i, 10.0, &p, &d) != CS_OK)
            continue;
        for (int dir = 0; dir < 2; dir++)
            for (int k = 0; k <= 8; k++) {
                cs_bezier_t c, c2;
                if (cs_patch_iso(&p, (cs_patch_iso_t)dir, (cs_param_t)(CS_PARAM_ONE / 8 * k), &c) ==
                        CS_OK &&
                    planar_cubic(&c, &c2))
                    bench_set_add(s, &c2);
            }
    }
    cs_patchfile_free(&pf);
}

static void ctrl(const cs_bezier_t *c, double p[8])
{
    for (int i = 0; i < 4; i++) {
        cs_ref_vec_t a = cs_ref_from_pos(&c->p[i]);
        p[2 * i] = a.x;
        p[2 * i + 1] = a.y;
    }
}

/* Flattens c with engine e; when out is set, writes the polyline (P0 first) to poly[]. Returns
 * the chord count, or SIZE_MAX on error. */
static size_t flatten(const cs_bezier_t *c, double tol, int e, bool out)
{
    size_t n = 0;
    if (e < N_CS) {
        static cs_trace_t tr;
        static cs_subdiv_t sd;
        cs_pos_t t = mm(tol);
        cs_err_t r = CS_OK;
        if (e == 2) {
            if (cs_subdiv_begin(&sd, c, t, false) != CS_OK)
                return SIZE_MAX;
            while (n < MAX_VERTS && (r = cs_subdiv_next(&sd, &verts[n])) == CS_OK)
                n++;
        } else {
            if (cs_trace_begin(&tr, c, t, eng_method[e]) != CS_OK)
                return SIZE_MAX;
            while (n < MAX_VERTS && (r = cs_trace_next(&tr, &verts[n])) == CS_OK)
                n++;
        }
        if (r != CS_END)
            return SIZE_MAX;
        if (out) {
            cs_ref_vec_t a = cs_ref_from_pos(&c->p[0]);
            poly[0] = (pt2_t){a.x, a.y};
            for (size_t i = 0; i < n; i++) {
                a = cs_ref_from_pos(&verts[i]);
                poly[i + 1] = (pt2_t){a.x, a.y};
            }
        }
        return n;
    }
    double p[8];
    ctrl(c, p);
    if (e == ENG_AGG) {
        size_t nv = agg_flatten_cubic(p, tol, &poly[0].x, MAX_VERTS + 1);
        return nv >= 1 && nv <= MAX_VERTS + 1 ? nv - 1 : SIZE_MAX;
    }
    const double k = CAIRO_SCALE;
    cairo_new_path(cr);
    cairo_set_tolerance(cr, tol * k);
    cairo_move_to(cr, p[0] * k, p[1] * k);
    cairo_curve_to(cr, p[2] * k, p[3] * k, p[4] * k, p[5] * k, p[6] * k, p[7] * k);
    cairo_path_t *path = cairo_copy_path_flat(cr);
    if (path->status != CAIRO_STATUS_SUCCESS) {
        cairo_path_destroy(path);
        return SIZE_MAX;
    }
    size_t np = 0;
    for (int i = 0; i < path->num_data; i += path->data[i].header.length) {
        cairo_path_data_t *dt = &path->data[i];
        if (dt->header.type == CAIRO_PATH_LINE_TO)
            n++;
        if (out && np <= MAX_VERTS &&
            (dt->header.type == CAIRO_PATH_LINE_TO || dt->header.type == CAIRO_PATH_MOVE_TO))
            poly[np++] = (pt2_t){dt[1].point.x / k, dt[1].point.y / k};
    }
    cairo_path_destroy(path);
    return n;
}

/* --- the judge: one double-precision measure for every engine ------------------------------ */
static double seg_dist(pt2_t q, pt2_t a, pt2_t b)
{
    double dx = b.x - a.x, dy = b.y - a.y, l2 = dx * dx + dy * dy, t = 0;
    if (l2 > 0) {
        t = ((q.x - a.x) * dx + (q.y - a.y) * dy) / l2;
        t = t < 0 ? 0 : t > 1 ? 1 : t;
    }
    return hypot(q.x - (a.x + t * dx), q.y - (a.y + t * dy));
}

/* Distance from q to the polyline P[0..np-1]: first among segments near *hint (walking on
 * while the nearest is at the window's edge: the polylines follow the curve in order); when that
 * is above both floor and the running maximum, by a scan of every segment, so the largest
 * value reported is exact. */
static double near_poly(pt2_t q, const pt2_t *P, size_t np, size_t *hint, double floor)
{
    const size_t W = 8;
    if (np < 2)
        return hypot(q.x - P[0].x, q.y - P[0].y);
    size_t ns = np - 1, h = *hint < ns ? *hint : ns - 1;
    size_t lo = h > W ? h - W : 0, hi = h + W + 1 < ns ? h + W + 1 : ns, bi = h;
    double best = INFINITY;
    for (size_t i = lo; i < hi; i++) {
        double d = seg_dist(q, P[i], P[i + 1]);
        if (d < best)
            best = d, bi = i;
    }
    while (bi + 1 == hi && hi < ns) {
        size_t e = hi + W < ns ? hi + W : ns;
        for (size_t i = hi; i < e; i++) {
            double d = seg_dist(q, P[i], P[i + 1]);
            if (d < best)
                best = d, bi = i;
        }
        hi = e;
    }
    while (bi == lo && lo > 0) {
        size_t s = lo > W ? lo - W : 0;
        for (size_t i = s; i < lo; i++) {
            double d = seg_dist(q, P[i], P[i + 1]);
            if (d < best)
                best = d, bi = i;
        }
        lo = s;
    }
    if (best > floor)
        for (size_t i = 0; i < ns; i++) {
            double d = seg_dist(q, P[i], P[i + 1]);
            if (d < best)
                best = d, bi = i;
        }
    *hint = bi;
    return best;
}

static pt2_t *dense;
static size_t dense_cap;

/* Hausdorff distance (mm) between the polyline P[0..np-1] and the planar cubic c: every point
 * of a dense sampling of the curve to the polyline, and 9 points per chord (its ends included)
 * to the dense sampling's polyline. The sampling has at least 32 points per chord and is fine
 * enough that its own sag (|C''| dt^2 / 8, |C''| <= 6 max|P_i - 2P_i+1 + P_i+2|) is at most
 * tol / 500, the judge's resolution. */
static double judge(const cs_bezier_t *c, const pt2_t *P, size_t np, double tol)
{
    double p[8], d2 = 0;
    ctrl(c, p);
    for (int i = 0; i < 2; i++)
        d2 = fmax(d2, hypot(p[2 * i] - 2 * p[2 * i + 2] + p[2 * i + 4],
                            p[2 * i + 1] - 2 * p[2 * i + 3] + p[2 * i + 5]));
    double mf = ceil(sqrt(6 * d2 / (8 * tol / 500)));
    size_t m = mf > 4e6 ? 4000000 : (size_t)mf;
    if (m < 32 * np)
        m = 32 * np;
    if (m < 64)
        m = 64;
    if (m + 1 > dense_cap) {
        dense_cap = m + 1;
        dense = realloc(dense, dense_cap * sizeof *dense);
        if (!dense)
            abort();
    }
    for (size_t j = 0; j <= m; j++) {
        cs_ref_vec_t a = cs_ref_eval(c, (double)j / (double)m);
        dense[j] = (pt2_t){a.x, a.y};
    }
    double worst = 0;
    size_t h = 0;
    for (size_t j = 0; j <= m; j++)
        worst = fmax(worst, near_poly(dense[j], P, np, &h, worst));
    h = 0;
    for (size_t i = 0; i + 1 < np || i == 0; i++) {
        for (int k = 0; k <= 8; k++) {
            pt2_t q = P[i];
            if (i + 1 < np)
                q = (pt2_t){P[i].x + (P[i + 1].x - P[i].x) * k / 8.0,
                            P[i].y + (P[i + 1].y - P[i].y) * k / 8.0};
            worst = fmax(worst, near_poly(q, dense, m + 1, &h, worst));
        }
        if (np < 2)
            break;
    }
    return worst;
}

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Curves per second for the whole set (median of N_RUNS runs, each repeating the set for at
 * least 30 ms); *pps gets the points (chords) per second of the same runs. */
static double speed(const bench_set_t *s, double tol, int e, double *pps)
{
    double cps[N_RUNS], ps[N_RUNS];
    for (int r = 0; r < N_RUNS; r++) {
        size_t curves = 0, pts = 0;
        double t0 = bench_now(), t1;
        do {
            for (size_t k = 0; k < s->n; k++) {
                size_t n = flatten(&s->c[k], tol, e, false);
                pts += n == SIZE_MAX ? 0 : n;
            }
            curves += s->n;
            t1 = bench_now();
        } while (t1 - t0 < 0.03);
        cps[r] = (double)curves / (t1 - t0);
        ps[r] = (double)pts / (t1 - t0);
    }
    qsort(cps, N_RUNS, sizeof cps[0], cmp_d);
    qsort(ps, N_RUNS, sizeof ps[0], cmp_d);
    *pps = ps[N_RUNS / 2];
    return cps[N_RUNS / 2];
}

/* The physical floor of forward differencing on this machine: a cubic stepped by 3 int64
 * additions per coordinate per point (x, y, z) and each point stored, nothing else. Points/s. */
static double fd_floor_pps(void)
{
    static cs_vec3_t buf[4096];
    double best[N_RUNS];
    for (int r = 0; r < N_RUNS; r++) {
        int64_t d[3][4] = {{1 << 20, 3, 5, 7}, {2 << 20, -3, 11, 13}, {3 << 20, 1, -2, 3}};
        size_t n = 0;
        double t0 = bench_now(), t1;
        do {
            for (size_t i = 0; i < 4096; i++) {
                for (int a = 0; a < 3; a++) {
                    d[a][0] += d[a][1];
                    d[a][1] += d[a][2];
                    d[a][2] += d[a][3];
                }
                buf[i] = cs_fixed_vec((cs_pos_t)(d[0][0] >> 20), (cs_pos_t)(d[1][0] >> 20),
                                      (cs_pos_t)(d[2][0] >> 20));
            }
            n += 4096;
            t1 = bench_now();
        } while (t1 - t0 < 0.05);
        __asm__ __volatile__("" : : "r"(buf) : "memory");
        best[r] = (double)n / (t1 - t0);
    }
    qsort(best, N_RUNS, sizeof best[0], cmp_d);
    return best[N_RUNS / 2];
}

typedef struct {
    size_t chords;
    double worst, cps, pps;
    double worst_curve; /* largest chords / greedy of one curve with greedy >= GREEDY_MIN */
    int errors;
} result_t;

/* Per-curve ratios are judged on curves of at least this many greedy chords (below it one
 * chord more is already a ratio of 1.1 or more). */
#define GREEDY_MIN 20
static size_t *greedy_of; /* greedy chord count of each curve of the set being run */

/* --- arcs: circular and elliptical arcs, greedy over the whole arc ------------------------- */
#define N_ARCS_R  6
#define N_ARCS_Q  2
#define N_ARCS_SW 5
#define N_ARCS    (N_ARCS_R * N_ARCS_Q * N_ARCS_SW)
typedef struct {
    double r, q, sweep; /* radius (mm), minor/major axis ratio, sweep (rad) */
    cs_bezier_t seg[CS_ARC_MAX_SEGMENTS];
    unsigned n;
} arc_t;
static arc_t arcs[N_ARCS];

/* The corpus: radii 0.5 .. 1000 mm, circles and 1:2 ellipses, sweeps 30 .. 360 degrees, each
 * built by cs_arc_build (centre at the origin, axes x and y) as the parsers build SVG 'A' and
 * G2/G3. */
static void arcs_set(void)
{
    static const double rs[N_ARCS_R] = {0.5, 2, 10, 50, 200, 1000}, qs[N_ARCS_Q] = {1, 0.5};
    static const double sws[N_ARCS_SW] = {30, 90, 180, 300, 360};
    size_t k = 0;
    for (int i = 0; i < N_ARCS_R; i++)
        for (int j = 0; j < N_ARCS_Q; j++)
            for (int w = 0; w < N_ARCS_SW; w++, k++) {
                arc_t *a = &arcs[k];
                a->r = rs[i];
                a->q = qs[j];
                a->sweep = sws[w] * M_PI / 180;
                cs_vec3_t C = {0, 0, 0}, U = {mm(a->r), 0, 0}, V = {0, mm(a->r * a->q), 0};
                cs_param_t c1 = (cs_param_t)lround(cos(a->sweep) * CS_PARAM_ONE);
                cs_param_t s1 = (cs_param_t)lround(sin(a->sweep) * CS_PARAM_ONE);
                if (sws[w] == 360) {
                    c1 = CS_PARAM_ONE;
                    s1 = 0;
                }
                if (cs_arc_build(&C, &U, &V, CS_PARAM_ONE, 0, c1, s1, true, a->seg, &a->n) != CS_OK)
                    abort();
            }
}

/* Greedy chord count over the whole arc (ref_ellarc: no vertex forced at the pieces' joins). */
static size_t arc_greedy(const arc_t *a, double tol)
{
    ref_ellarc_t e = {{0, 0}, {a->r, 0}, {0, a->r * a->q}, a->sweep};
    return ref_ellarc_greedy(&e, tol);
}

/* Chords of one arc by engine e (curvestep: every piece traced, the joins are vertices; cairo:
 * cairo_arc on the scaled ellipse); *dev = worst cs_ref_max_deviation of curvestep's pieces. */
static size_t arc_flatten(const arc_t *a, double tol, int e, double *dev)
{
    size_t total = 0;
    if (e == ENG_CAIRO) {
        const double k = CAIRO_SCALE;
        cairo_new_path(cr);
        cairo_set_tolerance(cr, tol * k);
        cairo_save(cr);
        cairo_scale(cr, k, k * a->q);
        cairo_arc(cr, 0, 0, a->r, 0, a->sweep);
        cairo_restore(cr);
        cairo_path_t *path = cairo_copy_path_flat(cr);
        for (int i = 0; i < path->num_data; i += path->data[i].header.length)
            if (path->data[i].header.type == CAIRO_PATH_LINE_TO)
                total++;
        cairo_path_destroy(path);
        return total;
    }
    for (unsigned k = 0; k < a->n; k++) {
        static cs_trace_t tr;
        size_t n = 0;
        if (cs_trace_begin(&tr, &a->seg[k], mm(tol), eng_method[e]) != CS_OK)
            return SIZE_MAX;
        cs_err_t r;
        while (n < MAX_VERTS && (r = cs_trace_next(&tr, &verts[n])) == CS_OK)
            n++;
        if (r != CS_END)
            return SIZE_MAX;
        if (dev)
            *dev = fmax(*dev, cs_ref_max_deviation(&a->seg[k], verts, n));
        total += n;
    }
    return total;
}

/* The default tracer's worst figures on the arcs (for the issue 18 goals table). */
static double arcs_worst_greedy, arcs_worst_dev, arcs_worst_cps = INFINITY,
                                                 arcs_worst_pps = INFINITY;

static void arcs_report(FILE *csv);

/* One speed row of the goal table: the worst ratio to cairo's over the sets, and at each
 * tolerance, with the arcs', against goal; the verdict names the tolerances (or the arcs) that
 * miss. */
static void goal_speed_row(const char *what, const double worst_t[N_TOLS], double arcs, double goal)
{
    double worst = arcs;
    char per[96] = "", miss[64] = "";
    if (arcs < goal)
        snprintf(miss, sizeof miss, "arcs");
    for (int ti = 0; ti < N_TOLS; ti++) {
        size_t n = strlen(per), m = strlen(miss);
        snprintf(per + n, sizeof per - n, "%s%.2fx", ti ? " / " : "", worst_t[ti]);
        if (worst_t[ti] < goal)
            snprintf(miss + m, sizeof miss - m, "%s%g", m ? ", " : "", tols_mm[ti]);
        worst = fmin(worst, worst_t[ti]);
    }
    printf("| %s | %.2fx (at %g / %g / %g mm: %s; arcs %.2fx) | %s%s%s |\n", what, worst,
           tols_mm[0], tols_mm[1], tols_mm[2], per, arcs, worst >= goal ? "met" : "MISSED",
           miss[0] ? " at " : "", miss[0] ? miss : "");
}

/* The goals of issue 18 for the default tracer (ENG_PRED), worst over the sets and tolerances
 * above and the arcs. */
static void goals18(result_t res[3][N_TOLS][N_ENG], size_t greedy[3][N_TOLS],
                    const bench_set_t *sets)
{
    double dev = arcs_worst_dev, gr = 0;
    double cps_t[N_TOLS], pps_t[N_TOLS]; /* the worst set at each tolerance */
    for (int ti = 0; ti < N_TOLS; ti++)
        cps_t[ti] = pps_t[ti] = INFINITY;
    int errors = 0;
    for (int si = 0; si < 3; si++)
        for (int ti = 0; ti < N_TOLS; ti++) {
            if (sets[si].n == 0)
                continue;
            result_t *r = &res[si][ti][ENG_PRED], *c = &res[si][ti][ENG_CAIRO];
            errors += r->errors;
            dev = fmax(dev, r->worst / tols_mm[ti]);
            gr = fmax(gr, (double)r->chords / (double)greedy[si][ti]);
            cps_t[ti] = fmin(cps_t[ti], r->cps / c->cps);
            pps_t[ti] = fmin(pps_t[ti], r->pps / c->pps);
        }
    printf("### Goals (issue 18) for the default tracer, %s\n\n", eng_name[ENG_PRED]);
    printf("Worst case over the three sets and three tolerances above, and the arcs.\n\n");
    printf("| goal | measured | verdict |\n|---|---|---|\n");
    printf("| max dev / tol <= 1, no error | %.4f, %d errors | %s |\n", dev, errors,
           dev <= 1 && errors == 0 ? "met" : "MISSED");
    printf("| chords <= 1.05x greedy (per set of curves) | %.3f | %s |\n", gr,
           gr <= 1.05 ? "met" : "MISSED");
    printf("| chords <= 1.10x whole-element greedy, arcs | %.3f | %s |\n", arcs_worst_greedy,
           arcs_worst_greedy <= 1.10 ? "met" : "MISSED");
    goal_speed_row("curves/s >= 2x cairo's", cps_t, arcs_worst_cps, 2);
    goal_speed_row("points/s >= cairo's", pps_t, arcs_worst_pps, 1);
    printf("\n");
    printf("What limits the speed (docs/fixed-point.md, \"Predicted-step tracer\", Cost, \"Host "
           "path of 64-bit speed builds\" and \"Per-curve work of speed builds\"): wall clock on "
           "this shared machine moves between runs, cairo's too (compare within one table; "
           "`bench_peers --speed` times only the default tracer and cairo on the three sets and "
           "the arcs, in a fresh process, for a quick A/B). The tracer is bound by the latency of "
           "one chain of dependent operations a flatness test (sub-curve products, cross "
           "products, majorant, logarithm, next step). On 2026-12-03 two passes, each keeping "
           "the host's vertices bit for bit the portable code's (the firmware's), took the random "
           "set from 1511 / 3325 / 9302 ns a curve to 821-858 / 1912-1994 / 5503-5648 at 0.1 / "
           "0.01 / 0.001 mm and the teapot's from 217 / 409 / 977 to 156-160 / 337-346 / "
           "889-893 (focused harness, several runs): the test's "
           "threshold below 2^14 units, so that it sets the normalising shift on nearly every "
           "test (the host guesses it: 0.5 wrong guesses a chord at 0.1 mm -> 0), the acceptance "
           "at 1.35 (1.62 -> 1.45 tests a chord at 0.1 mm, +1 %% chords), the set-up of a curve "
           "50 -> about 20 ns, one-chord curves without their test. What is left at 0.1 mm, "
           "where the ratio to cairo is closest to 2: `--speed` measures 1.90-1.97x on the "
           "random set and 1.94-1.97x on the teapot, whole runs of this table on "
           "2026-12-03 1.89x to 2.06x (cairo's own curves/s moved by 7 %% between them). A "
           "curve is 20.6 chords and 1.45 tests a chord there (26 %% of the first tests fail, "
           "20 %% pass with more room than accepted: the ideal step changes more between "
           "neighbouring chords than the acceptance window; a host-only "
           "predictor that halved the retries gained 5 %% and would make the host trace other "
           "chords than the firmware). On the teapot a third of the curves are one chord and 78 "
           "are folds (radial edges out and back along a line) whose first chord takes 3.8 tests: "
           "a first step just past the turning point (-5.6 %% on the set, host-only prototype) "
           "needs a square root and a division, beyond the M0+ curve core's 18 bytes of room. "
           "Arcs go through the arc tracer (cs_ellarc: a rotation recurrence, no division a "
           "vertex).\n\n");
}

/* Arcs per second and points per second of engine e over the arcs at tol, N_RUNS runs each
 * repeating the arcs for at least 30 ms, sorted (the median at N_RUNS / 2). */
static void arcs_speed(double tol, int e, double aps[N_RUNS], double pps[N_RUNS])
{
    for (int r = 0; r < N_RUNS; r++) {
        size_t na = 0, np = 0;
        double t0 = bench_now(), t1;
        do {
            for (int k = 0; k < N_ARCS; k++)
                np += arc_flatten(&arcs[k], tol, e, NULL);
            na += N_ARCS;
            t1 = bench_now();
        } while (t1 - t0 < 0.03);
        aps[r] = (double)na / (t1 - t0);
        pps[r] = (double)np / (t1 - t0);
    }
    qsort(aps, N_RUNS, sizeof aps[0], cmp_d);
    qsort(pps, N_RUNS, sizeof pps[0], cmp_d);
}

static void arcs_report(FILE *csv)
{
    static const int engs[] = {ENG_CAIRO, 3, ENG_PRED}; /* cairo first: the others' reference */
    arcs_set();
    printf("### Arcs: circles and ellipses traced as drawn elements (%d arcs)\n\n", N_ARCS);
    printf("Radii 0.5, 2, 10, 50, 200, 1000 mm; circles and 1:2 ellipses; sweeps 30, 90, 180, "
           "300, 360 degrees; each built by `cs_arc_build` as the parsers build SVG `A` and "
           "G2/G3 (pieces of at most 90 degrees, rational quadratics; a join between pieces is "
           "a vertex). Greedy = over the **whole arc** (bisection on the angle, chord deviation by "
           "golden-section search, double). Max dev / tol: `cs_ref_max_deviation` per piece "
           "(curvestep only). cairo: `cairo_arc` on the scaled ellipse (not judged). "
           "Throughput: median of %d runs.\n\n",
           N_RUNS);
    printf("| engine | tol (mm) | chords/arc | greedy/arc (whole arc) | vs greedy | vs cairo | "
           "max dev / tol | arcs/s | points/s |\n|---|---|---|---|---|---|---|---|---|\n");
    for (int ti = 0; ti < N_TOLS; ti++) {
        double tol = tols_mm[ti], cairo_aps = 0, cairo_pps = 0;
        size_t greedy = 0, cairo_n = 0;
        for (int k = 0; k < N_ARCS; k++) {
            greedy += arc_greedy(&arcs[k], tol);
            cairo_n += arc_flatten(&arcs[k], tol, ENG_CAIRO, NULL);
        }
        for (size_t ei = 0; ei < sizeof engs / sizeof engs[0]; ei++) {
            int e = engs[ei];
            size_t chords = 0;
            double dev = 0, aps[N_RUNS], pps[N_RUNS];
            for (int k = 0; k < N_ARCS; k++)
                chords += arc_flatten(&arcs[k], tol, e, e == ENG_CAIRO ? NULL : &dev);
            arcs_speed(tol, e, aps, pps);
            if (e == ENG_CAIRO) {
                cairo_aps = aps[N_RUNS / 2];
                cairo_pps = pps[N_RUNS / 2];
            } else if (e == ENG_PRED) {
                arcs_worst_greedy = fmax(arcs_worst_greedy, (double)chords / (double)greedy);
                arcs_worst_dev = fmax(arcs_worst_dev, dev / tol);
                arcs_worst_cps = fmin(arcs_worst_cps, aps[N_RUNS / 2] / cairo_aps);
                arcs_worst_pps = fmin(arcs_worst_pps, pps[N_RUNS / 2] / cairo_pps);
            }
            char devs[32] = "-";
            if (e != ENG_CAIRO)
                snprintf(devs, sizeof devs, "%.4f", dev / tol);
            printf("| %s | %g | %.1f | %.1f | %.3f | %.3f | %s | %.3g | %.3g |\n", eng_name[e], tol,
                   (double)chords / N_ARCS, (double)greedy / N_ARCS,
                   (double)chords / (double)greedy, (double)chords / (double)cairo_n, devs,
                   aps[N_RUNS / 2], pps[N_RUNS / 2]);
            if (csv)
                fprintf(csv, "arcs,%s,%g,%d,%zu,%.6g,%.4g,%.4g,0\n", eng_name[e], tol, N_ARCS,
                        chords, dev, aps[N_RUNS / 2], pps[N_RUNS / 2]);
        }
    }
    printf("\n");
}

/* --profile: each of the default tracer and cairo flattens the three sets at the three
 * tolerances once, then the arcs; one function per engine and corpus, so that a profiler's
 * inclusive cost of it is that engine's work (valgrind --tool=callgrind, callgrind_annotate
 * --inclusive=yes: profile_curves_pred against profile_curves_cairo). Prints the curve and
 * chord counts. */
static size_t profile_curves(const bench_set_t *sets, int e, size_t *curves)
{
    size_t chords = 0;
    for (int si = 0; si < 3; si++)
        for (int ti = 0; ti < N_TOLS; ti++)
            for (size_t k = 0; k < sets[si].n; k++) {
                chords += flatten(&sets[si].c[k], tols_mm[ti], e, false);
                ++*curves;
            }
    return chords;
}

static size_t profile_arcs(int e, size_t *curves)
{
    size_t chords = 0;
    for (int ti = 0; ti < N_TOLS; ti++)
        for (size_t k = 0; k < N_ARCS; k++) {
            chords += arc_flatten(&arcs[k], tols_mm[ti], e, NULL);
            ++*curves;
        }
    return chords;
}

__attribute__((noinline)) static size_t profile_curves_pred(const bench_set_t *s, size_t *n)
{
    return profile_curves(s, ENG_PRED, n);
}

__attribute__((noinline)) static size_t profile_curves_cairo(const bench_set_t *s, size_t *n)
{
    return profile_curves(s, ENG_CAIRO, n);
}

__attribute__((noinline)) static size_t profile_arcs_pred(size_t *n)
{
    return profile_arcs(ENG_PRED, n);
}

__attribute__((noinline)) static size_t profile_arcs_cairo(size_t *n)
{
    return profile_arcs(ENG_CAIRO, n);
}

/* --speed: the default tracer against cairo only, wall clock (median of N_RUNS), on the three
 * sets (random, SVG, teapot) and the arcs at the three tolerances: a quick A/B of the tracer's
 * host speed (the full run takes minutes, most of it in the judge). */
static int speed_only(const bench_set_t *sets)
{
    printf("set tol(mm) pred-curves/s cairo-curves/s ratio pred-pts/s cairo-pts/s ratio\n");
    enum { N_SETS = 3 };
    static const char *set_name[N_SETS] = {"random", "svg", "teapot"};
    for (int si = 0; si < N_SETS; si++)
        for (int ti = 0; ti < N_TOLS; ti++) {
            double pp, cp, pc = speed(&sets[si], tols_mm[ti], ENG_PRED, &pp);
            double cc = speed(&sets[si], tols_mm[ti], ENG_CAIRO, &cp);
            printf("%s %g %.3g %.3g %.2f %.3g %.3g %.2f\n", set_name[si], tols_mm[ti], pc, cc,
                   pc / cc, pp, cp, pp / cp);
        }
    for (int ti = 0; ti < N_TOLS; ti++) {
        double pa[N_RUNS], pp[N_RUNS], ca[N_RUNS], cp[N_RUNS];
        arcs_speed(tols_mm[ti], ENG_PRED, pa, pp);
        arcs_speed(tols_mm[ti], ENG_CAIRO, ca, cp);
        int m = N_RUNS / 2;
        printf("arcs %g %.3g %.3g %.2f %.3g %.3g %.2f\n", tols_mm[ti], pa[m], ca[m], pa[m] / ca[m],
               pp[m], cp[m], pp[m] / cp[m]);
    }
    return 0;
}

static int profile(const bench_set_t *sets)
{
    size_t n[4] = {0, 0, 0, 0};
    size_t c[4] = {profile_curves_pred(sets, &n[0]), profile_curves_cairo(sets, &n[1]),
                   profile_arcs_pred(&n[2]), profile_arcs_cairo(&n[3])};
    static const char *what[4] = {"curves, predict", "curves, cairo", "arcs, predict",
                                  "arcs, cairo"};
    for (int i = 0; i < 4; i++)
        printf("%s: %zu elements, %zu chords\n", what[i], n[i], c[i]);
    return 0;
}

int main(int argc, char **argv)
{
    static const char usage[] =
        "usage: bench_peers [OUT.csv | --profile | --speed]\n"
        "curvestep's tracers beside cairo and AGG on one corpus of cubics; a Markdown\n"
        "section on stdout, the figures in OUT.csv. --profile: only the default tracer and\n"
        "cairo, once over the corpus and the arcs (for callgrind, see profile_curves).\n"
        "--speed: only the default tracer's and cairo's wall-clock speed on the three sets\n"
        "and the arcs (a quick A/B; no judge, no file).\n";
    bool prof = argc == 2 && strcmp(argv[1], "--profile") == 0;
    bool spd = argc == 2 && strcmp(argv[1], "--speed") == 0;
    int usage_rc = prof || spd ? -1 : bench_args_check(argc, argv, usage, 1);
    if (usage_rc >= 0)
        return usage_rc;
    FILE *csv = argc > 1 && !prof && !spd ? fopen(argv[1], "w") : NULL;
    cairo_surface_t *surf = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, 1, 1);
    cr = cairo_create(surf);
    bench_set_t sets[3] = {{"random cubics + hard cases", NULL, 0, 0},
                           {"SVG files (cubics, quadratics elevated)", NULL, 0, 0},
                           {"teapot iso-curves (projected on z = 0)", NULL, 0, 0}};
    random_and_hard(&sets[0]);
    size_t skipped = bench_svg_curves(&sets[1], NULL, 0, planar_cubic);
    teapot_set(&sets[2]);
    if (prof || spd) {
        arcs_set();
        return prof ? profile(sets) : speed_only(sets);
    }
    static result_t res[3][N_TOLS][N_ENG];
    static size_t greedy[3][N_TOLS];
    if (csv)
        fprintf(csv, "set,engine,tol_mm,curves,chords,max_dev_mm,curves_per_s,points_per_s,"
                     "errors\n");
    printf("## Peers: curvestep beside cairo and AGG\n\n");
    printf("bench_peers: one corpus of planar cubics flattened by every curvestep method, by cairo "
           "%s (`cairo_copy_path_flat` after `cairo_set_tolerance`) and by AGG "
           "(`agg::curve4_div`, Debian libagg-dev), at the same tolerances.\n\n",
           cairo_version_string());
    printf("- Tolerances made comparable: cairo subdivides (de Casteljau) until both inner "
           "control points are within `tolerance` device units of the chord, so the curve is "
           "within it too; it is called with an identity matrix on coordinates multiplied by "
           "%g (cairo stores paths in 24.8 fixed point; this makes its grid 2^-18 mm) and "
           "tolerance tol x %g. AGG stops when the sum of the inner control points' distances to "
           "the chord is <= 0.5 / approximation_scale, so approximation_scale = 0.5 / tol "
           "(angle tolerance and cusp limit off); it emits the midpoint of the inner control "
           "points, a vertex off the curve. curvestep gets tol rounded to its LSB (2^-16 mm).\n",
           CAIRO_SCALE, CAIRO_SCALE);
    printf("- Judge: one double-precision Hausdorff measure for every engine (bench_peers.c "
           "`judge`): dense samples of the exact curve (`cs_ref_eval`, >= 32 per chord, sag <= "
           "tol/500) to the polyline, and 9 points per chord to the curve.\n");
    printf("- Throughput: curves/s and points (chords)/s, median of %d runs, one core; cairo's "
           "figure includes building its path (`cairo_new_path`, `move_to`, `curve_to`) and "
           "freeing the copy, AGG's its `init`, curvestep's `cs_trace_begin`.\n",
           N_RUNS);
    printf("- Corpus: %zu random cubics (xorshift, fixed seed, 200 mm box) + hard cases "
           "(coincident, cusp, loop, inflection, collinear fold, 2 m); %zu SVG curves (%zu "
           "rational or higher-degree elements left out: the peers take cubics only); %zu "
           "teapot iso-curves (tests/data/teapot, 10 mm per unit, t = k/8 both families).\n\n",
           (size_t)200, sets[1].n, skipped, sets[2].n);
    for (int si = 0; si < 3; si++) {
        bench_set_t *s = &sets[si];
        if (s->n == 0)
            continue;
        printf("### %s (%zu curves)\n\n", s->name, s->n);
        printf("| engine | tol (mm) | chords/curve | vs cairo | vs AGG | vs greedy (worst curve) "
               "| max dev / tol | curves/s | points/s | errors |\n"
               "|---|---|---|---|---|---|---|---|---|---|\n");
        greedy_of = realloc(greedy_of, s->n * sizeof *greedy_of);
        if (!greedy_of)
            abort();
        for (int ti = 0; ti < N_TOLS; ti++) {
            double tol = tols_mm[ti];
            greedy[si][ti] = 0;
            for (size_t k = 0; k < s->n; k++) {
                greedy_of[k] = cs_ref_greedy_count(&s->c[k], tol);
                greedy[si][ti] += greedy_of[k];
            }
            for (int e = 0; e < N_ENG; e++) {
                result_t *r = &res[si][ti][e];
                memset(r, 0, sizeof *r);
                for (size_t k = 0; k < s->n; k++) {
                    size_t n = flatten(&s->c[k], tol, e, true);
                    if (n == SIZE_MAX) {
                        r->errors++;
                        continue;
                    }
                    r->chords += n;
                    if (greedy_of[k] >= GREEDY_MIN)
                        r->worst_curve = fmax(r->worst_curve, (double)n / (double)greedy_of[k]);
                    double dev = judge(&s->c[k], poly, n + 1, tol);
                    r->worst = fmax(r->worst, dev);
                    /* Cross-check of the judge against the project's reference on the
                     * on-curve polylines (curvestep's vertices are on the LSB grid). */
                    if (e < N_CS) {
                        double rd = cs_ref_max_deviation(&s->c[k], verts, n);
                        judge_gap = fmax(judge_gap, (dev - rd) / tol);
                        ref_worst = fmax(ref_worst, rd / tol);
                    }
                }
                r->cps = speed(s, tol, e, &r->pps);
                fprintf(stderr, "bench_peers: %s tol %g %s: %zu chords\n", s->name, tol,
                        eng_name[e], r->chords);
            }
            for (int e = 0; e < N_ENG; e++) {
                result_t *r = &res[si][ti][e];
                printf("| %s | %g | %.1f | %.3f | %.3f | %.3f (%.3f) | %.4f | %.3g | %.3g | %d |\n",
                       eng_name[e], tol, (double)r->chords / (double)s->n,
                       (double)r->chords / (double)res[si][ti][ENG_CAIRO].chords,
                       (double)r->chords / (double)res[si][ti][ENG_AGG].chords,
                       (double)r->chords / (double)greedy[si][ti], r->worst_curve, r->worst / tol,
                       r->cps, r->pps, r->errors);
                if (csv)
                    fprintf(csv, "%s,%s,%g,%zu,%zu,%.6g,%.4g,%.4g,%d\n", s->name, eng_name[e], tol,
                            s->n, r->chords, r->worst, r->cps, r->pps, r->errors);
            }
        }
        printf("\n");
    }
    printf("### Goals (issue 10), judged on the tables above\n\n");
    printf("Worst case over the three sets and three tolerances, per curvestep method.\n\n");
    printf("| curvestep method | max dev / tol (goal <= 1) | chords / cairo's (goal <= 0.8) | "
           "chords / AGG's (goal <= 1) | speed / cairo's, curves/s (goal >= 2) |\n"
           "|---|---|---|---|---|\n");
    double sp_worst[N_CS];
    for (int e = 0; e < N_CS; e++) {
        double dev = 0, vc = 0, va = 0, sp = INFINITY;
        int errors = 0;
        for (int si = 0; si < 3; si++)
            for (int ti = 0; ti < N_TOLS; ti++) {
                if (sets[si].n == 0)
                    continue;
                result_t *r = &res[si][ti][e];
                errors += r->errors;
                dev = fmax(dev, r->worst / tols_mm[ti]);
                vc = fmax(vc, (double)r->chords / (double)res[si][ti][ENG_CAIRO].chords);
                va = fmax(va, (double)r->chords / (double)res[si][ti][ENG_AGG].chords);
                sp = fmin(sp, r->cps / res[si][ti][ENG_CAIRO].cps);
            }
        sp_worst[e] = sp;
        printf("| %s | %.4f %s%s | %.3f %s | %.3f %s | %.2f %s |\n", eng_name[e], dev,
               dev <= 1.0 && errors == 0 ? "met" : "MISSED", errors ? " (errors)" : "", vc,
               vc <= 0.8 ? "met" : "MISSED", va, va <= 1.0 ? "met" : "MISSED", sp,
               sp >= 2.0 ? "met" : "MISSED");
    }
    double peer_dev[2] = {0, 0};
    for (int si = 0; si < 3; si++)
        for (int ti = 0; ti < N_TOLS; ti++)
            for (int p = 0; p < 2; p++)
                peer_dev[p] = fmax(peer_dev[p], res[si][ti][ENG_CAIRO + p].worst / tols_mm[ti]);
    printf("\nFor comparison, the peers' own worst max dev / tol: cairo %.4f, AGG %.4f.\n\n",
           peer_dev[0], peer_dev[1]);
    /* Why goals are missed: per-vertex costs and chord ratios on the random set at 0.01 mm. */
    result_t *fd = &res[0][1][0], *reach = &res[0][1][3], *ca = &res[0][1][ENG_CAIRO];
    printf("Notes on the goals (figures from the random set at 0.01 mm):\n\n");
    printf("- Speed: uniform FD steps at %.3g points/s (%.1fx cairo's %.3g points/s) but emits "
           "%.2fx cairo's chords, because its one step size comes from Wang's bound for the "
           "most curved spot of the curve; so per curve it is %.2fx cairo here and %.2fx at "
           "worst (goals table). The method "
           "that meets the chord goal, subdiv reach, spends %.2f us per vertex (it finds the "
           "farthest flat chord by bisection, %d steps per vertex, each a homogeneous de "
           "Casteljau split in 2^-30 LSB units and a flatness test) against cairo's %.3f us per "
           "point: %.2fx cairo per curve. "
           "No single method is both 0.8x cairo's chords and 2x its speed yet.\n",
           fd->pps, fd->pps / ca->pps, ca->pps, (double)fd->chords / (double)ca->chords,
           fd->cps / ca->cps, sp_worst[0], 1e6 / reach->pps, CS_SUBDIV_REACH_STEPS, 1e6 / ca->pps,
           reach->cps / ca->cps);
    printf("- AGG: curve4_div's criterion bounds the inner control points' distance to the "
           "chord, but it then emits the midpoint of the inner control points in place of the "
           "piece's end point, so a narrow piece (a U turn, a collapsed teapot edge) is cut "
           "short: its worst deviation above is %.1fx the tolerance asked. Its chord counts are "
           "therefore not for the same accuracy; curvestep's are compared with them anyway.\n",
           peer_dev[1]);
    printf("- The judge is a Hausdorff distance; the project's reference `cs_ref_max_deviation` "
           "measures each chord against its own piece of curve, which is stricter where a "
           "polyline folds back on itself (the collinear fold). On every curvestep polyline of "
           "the corpus the judge was never more than %.2g tol above it, and by that stricter "
           "measure curvestep's worst is %.4f tol.\n",
           judge_gap, ref_worst);
    printf("- cairo keeps within its tolerance (its test bounds the control points, a "
           "conservative bound on the curve, which is why it stays near 0.75 of tol and emits "
           "more chords than needed).\n\n");

    arcs_report(csv);
    goals18(res, greedy, sets);

    /* FD rate against the floor: random cubics at 0.001 mm, uniform FD only. */
    bench_set_t rnd = sets[0];
    rnd.n = 200;
    double fd_pps;
    speed(&rnd, 0.001, 0, &fd_pps);
    double floor_pps = fd_floor_pps();
    printf("### Forward differences against the floor\n\n");
    printf("curvestep FD (`cs_trace_next`, CS_TRACE_FD) on the 200 random cubics at 0.001 mm: "
           "%.3g points/s. Floor on this machine (a bare loop of 3 int64 additions per "
           "coordinate per point, x y z, each point stored): %.3g points/s. FD runs at %.2f of "
           "the floor (%.2f ns per point against %.2f ns).\n\n",
           fd_pps, floor_pps, fd_pps / floor_pps, 1e9 / fd_pps, 1e9 / floor_pps);
    if (csv) {
        fprintf(csv, "fd_floor,CS_TRACE_FD,0.001,200,,,,%.4g,\n", fd_pps);
        fprintf(csv, "fd_floor,floor (3 adds/coord/point),,,,,,%.4g,\n", floor_pps);
        fclose(csv);
    }
    cairo_destroy(cr);
    cairo_surface_destroy(surf);
    free(dense);
    for (int si = 0; si < 3; si++)
        free(sets[si].c);
    return 0;
}
