/* cs_dcpath: raster passes, adaptive along each pass, refined across by scallop (cs_dcpath.h). */
#include "cs_dcpath.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cs_dropcheck.h"

#define DC_MAX_DEPTH   24 /* bisections of one along-pass interval */
#define DC_SCAN_FRACS  7  /* cross fractions 1/8 .. 7/8 of a gap, at least */
#define DC_SCAN_MAX    64 /* cross points in one gap, at most */
#define DC_PASS_MAXPTS (1u << 22)
#define DC_WALL_D      0.05 /* mm: the step of the slope test (slope_cos) */
#define DC_WALL_SLOPE  5    /* steeper (79 deg): a wall, left to the check's report */
#define DC_ALONG_ITER  12   /* golden-section steps on one chord: 0.618^12 = 3e-3 of it */

/* One pass being built: points along s, in increasing s. */
typedef struct {
    double *s, *z;
    size_t n, cap;
} dc_line_t;

typedef struct {
    cs_dropcut_mesh_t *ms;
    const cs_dropcut_tool_t *t;
    const cs_dcpath_opts_t *o;
    double d[2], e[2]; /* along and across unit vectors */
    size_t drops;
} dc_ctx_t;

void cs_dcpath_init(cs_dcpath_t *p)
{
    memset(p, 0, sizeof *p);
}

double cs_dcpath_step(const cs_dropcut_tool_t *t, double h)
{
    double a = t->r_mm - t->c_mm, r = t->c_mm;
    if (r <= 0)
        return 2 * t->r_mm * 0.9;
    double hh = fmin(h, r);
    return 2 * a + 2 * sqrt(2 * r * hh - hh * hh);
}

static double tip_at(dc_ctx_t *c, double s, double w)
{
    bool hit;
    double x = s * c->d[0] + w * c->e[0], y = s * c->d[1] + w * c->e[1];
    double z = cs_dropcut_drop(c->ms, c->t, x, y, &hit);
    c->drops++;
    return hit ? fmax(z, c->o->min_z) : c->o->min_z;
}

static bool line_push(dc_line_t *l, double s, double z)
{
    if (l->n == l->cap) {
        size_t cap = l->cap ? 2 * l->cap : 256;
        if (cap > DC_PASS_MAXPTS)
            return false;
        double *ns = realloc(l->s, cap * sizeof *ns);
        if (!ns)
            return false;
        l->s = ns;
        double *nz = realloc(l->z, cap * sizeof *nz);
        if (!nz)
            return false;
        l->z = nz;
        l->cap = cap;
    }
    l->s[l->n] = s;
    l->z[l->n++] = z;
    return true;
}

/* Adds the points strictly inside (sa, sb) that keep every chord within tol of the drop height:
 * the midpoint and both quarter points are compared with the chord. */
static bool refine(dc_ctx_t *c, dc_line_t *l, double w, double sa, double za, double sb,
                   double zb, int depth)
{
    double sm = (sa + sb) / 2, zm = tip_at(c, sm, w);
    /* Half the tolerance at the sampled points leaves room for what lies between them. */
    double tol = c->o->tol_mm / 2;
    bool split = fabs(zm - (za + zb) / 2) > tol;
    if (!split) { /* the quarters too: near a kink (the floor, an edge) the midpoint hides it */
        double q1 = tip_at(c, (sa + sm) / 2, w), q3 = tip_at(c, (sm + sb) / 2, w);
        split = fabs(q1 - (3 * za + zb) / 4) > tol || fabs(q3 - (za + 3 * zb) / 4) > tol;
    }
    if (split && (depth >= DC_MAX_DEPTH || sb - sa < c->o->tol_mm)) {
        /* A step too short to resolve: the drop height jumps (the cutter reaching the edge of
         * the surface, a wall). Cross it at the higher height, rising before the move and
         * descending after it, never along a slope that would cut into the step. */
        return line_push(l, za >= zb ? sb : sa, fmax(za, zb));
    }
    if (!split)
        return true;
    return refine(c, l, w, sa, za, sm, zm, depth + 1) && line_push(l, sm, zm) &&
           refine(c, l, w, sm, zm, sb, zb, depth + 1);
}

/* The s range of the line at cross offset w inside the region box; false when it misses it. */
static bool clip(const dc_ctx_t *c, double w, double *s0, double *s1)
{
    const double *b = c->o->box;
    double lo = -HUGE_VAL, hi = HUGE_VAL;
    for (int k = 0; k < 2; k++) {
        double p = w * c->e[k], dk = c->d[k];
        if (fabs(dk) < 1e-12) {
            if (p < b[k] - 1e-9 || p > b[k + 2] + 1e-9)
                return false;
            continue;
        }
        double ta = (b[k] - p) / dk, tb = (b[k + 2] - p) / dk;
        lo = fmax(lo, fmin(ta, tb));
        hi = fmin(hi, fmax(ta, tb));
    }
    *s0 = lo;
    *s1 = hi;
    return hi >= lo;
}

static bool build_line(dc_ctx_t *c, dc_line_t *l, double w)
{
    l->n = 0;
    double s0, s1;
    if (!clip(c, w, &s0, &s1))
        return true;
    /* Base samples no farther apart than a quarter of the tool radius. */
    double base = fmax(c->t->r_mm / 4, c->o->tol_mm);
    size_t n = (size_t)ceil((s1 - s0) / base);
    n = n ? n : 1;
    double sp = s0, zp = tip_at(c, s0, w);
    if (!line_push(l, sp, zp))
        return false;
    for (size_t k = 1; k <= n; k++) {
        double s = s0 + (s1 - s0) * (double)k / (double)n, z = tip_at(c, s, w);
        if (!refine(c, l, w, sp, zp, s, z, 0) || !line_push(l, s, z))
            return false;
        sp = s;
        zp = z;
    }
    return true;
}

/* z of a pass at s, linear between its points (the pass's own ends beyond). */
static double line_z(const dc_line_t *l, double s)
{
    if (s <= l->s[0])
        return l->z[0];
    if (s >= l->s[l->n - 1])
        return l->z[l->n - 1];
    size_t lo = 0, hi = l->n - 1;
    while (hi - lo > 1) {
        size_t m = (lo + hi) / 2;
        if (l->s[m] <= s)
            lo = m;
        else
            hi = m;
    }
    if (l->s[hi] <= l->s[lo]) /* a vertical step: the higher side */
        return fmax(l->z[lo], l->z[hi]);
    double f = (s - l->s[lo]) / (l->s[hi] - l->s[lo]);
    return l->z[lo] + f * (l->z[hi] - l->z[lo]);
}

/* Is the point within R of the rim of the surface's projection (seen at four points R away)? */
static bool near_rim(dc_ctx_t *c, double x, double y)
{
    double r = c->t->r_mm, z;
    return !cs_dropcut_top(c->ms, x + r, y, &z) || !cs_dropcut_top(c->ms, x - r, y, &z) ||
           !cs_dropcut_top(c->ms, x, y + r, &z) || !cs_dropcut_top(c->ms, x, y - r, &z);
}

/* The cosine of the surface's slope at (x, y) (central differences of the mesh top over
 * DC_WALL_D), or 0 on a wall: the top rising or falling more than DC_WALL_SLOPE d over d in one of
 * four directions. The height left, measured vertically, times it is the scallop across the
 * surface (for a plane exactly: the vertical through a point meets the envelope 1 / cos above
 * it); the check (cs_dropcheck.h) measures the distance to the cutters, never more. */
static double slope_cos(dc_ctx_t *c, double x, double y, double top, double g[2])
{
    static const double dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
    double z[4];
    for (int i = 0; i < 4; i++) {
        if (!cs_dropcut_top(c->ms, x + DC_WALL_D * dx[i], y + DC_WALL_D * dy[i], &z[i]))
            z[i] = top;
        if (fabs(z[i] - top) > DC_WALL_SLOPE * DC_WALL_D)
            return 0;
    }
    double gx = (z[0] - z[1]) / (2 * DC_WALL_D), gy = (z[2] - z[3]) / (2 * DC_WALL_D);
    double ms = c->o->max_slope;
    if (ms > 0 && gx * gx + gy * gy > ms * ms)
        return 0; /* steep ground another strategy serves */
    g[0] = gx;
    g[1] = gy;
    return 1 / sqrt(1 + gx * gx + gy * gy);
}

/* The cross offset of the axis of a cutter touching the surface at cross offset wp where its
 * slope is g (the contact normal n = (-g, 1) / |(-g, 1)|): the axis stands at q + r n_xy +
 * (R - r) n_xy / |n_xy| (the corner centre along the normal, the axis R - r beyond it). */
static double contact_axis(const dc_ctx_t *c, double wp, const double g[2])
{
    double gl = sqrt(g[0] * g[0] + g[1] * g[1]);
    if (gl < 1e-12)
        return wp;
    double ge = (g[0] * c->e[0] + g[1] * c->e[1]) / gl; /* uphill, across the passes */
    double off = c->t->c_mm * gl / sqrt(1 + gl * gl) + (c->t->r_mm - c->t->c_mm);
    return wp - off * ge;
}

/* The gap (lines g, g + 1) holding cross offset w, or SIZE_MAX (ws ascending: bisection). */
static size_t gap_of(const double *ws, size_t n, double w)
{
    if (n < 2 || !(ws[0] <= w && w < ws[n - 1]))
        return (size_t)-1;
    size_t lo = 0, hi = n - 1; /* ws[lo] <= w < ws[hi] */
    while (hi - lo > 1) {
        size_t m = (lo + hi) / 2;
        if (ws[m] <= w)
            lo = m;
        else
            hi = m;
    }
    return lo;
}

/* Is line j one of the two bounding gap i or gap ca (SIZE_MAX: none)? The search
 * along the passes takes those: the lines nearest the point and those nearest the axis of a
 * cutter touching the surface there. The others count at the same position only: a subset of
 * the path's cutters, so the estimate stays an upper bound. */
static bool near_line(size_t j, size_t i, size_t ca)
{
    return (j >= i && j <= i + 1) || (ca != (size_t)-1 && j >= ca && j <= ca + 1);
}

/* The first index of l whose s is at least s (l->n when none). */
static size_t line_lower(const dc_line_t *l, double s)
{
    size_t lo = 0, hi = l->n;
    while (lo < hi) {
        size_t m = (lo + hi) / 2;
        if (l->s[m] < s)
            lo = m + 1;
        else
            hi = m;
    }
    return lo;
}

/* The tip height of the chord from (sa, za) to (sb, zb) at t (a vertical step: its lower end,
 * where the pass also stands). */
static double chord_z(double sa, double za, double sb, double zb, double t)
{
    return sb > sa ? za + (t - sa) / (sb - sa) * (zb - za) : fmin(za, zb);
}

/* z(t) + h(hypot(dw, t - s)): the cutter of that chord at t over the point (s, dw). */
static double chord_env(const dc_ctx_t *c, double sa, double za, double sb, double zb, double t,
                        double s, double dw)
{
    return chord_z(sa, za, sb, zb, t) +
           cs_dropcut_profile(c->t, fmin(c->t->r_mm, hypot(dw, t - s)));
}

/* The least of best and the height a cutter of line l leaves over the point at along-pass s,
 * cross distance dw (<= R) from the line: the minimum over the line's positions t within R of
 * the point of z(t) + h(hypot(dw, t - s)). Along a chord z is linear and h(hypot) convex
 * (h convex non-decreasing, hypot convex), so the sum is convex: a golden-section search
 * (DC_ALONG_ITER steps) finds its minimum; a chord whose lower bound (its lower end plus h at its
 * nearest distance) cannot beat best is skipped, and the search stops once best <= stop (the
 * caller needs no less). Every value taken is the cutter at a position of the pass, so the
 * result is never below the envelope the pass leaves there: the estimate stays conservative. */
static double line_env(const dc_ctx_t *c, const dc_line_t *l, double s, double dw, double best,
                       double stop)
{
    double r = c->t->r_mm, a = sqrt(fmax(0, r * r - dw * dw)), s0 = s - a, s1 = s + a;
    size_t k = line_lower(l, s0);
    for (k = k > 0 ? k - 1 : 0; k + 1 < l->n && l->s[k] <= s1 && best > stop; k++) {
        double sa = l->s[k], sb = l->s[k + 1], za = l->z[k], zb = l->z[k + 1];
        double lo = fmax(sa, s0), hi = fmin(sb, s1);
        if (hi < lo)
            continue;
        double zl = chord_z(sa, za, sb, zb, lo), zh = chord_z(sa, za, sb, zb, hi);
        double near = s < lo ? lo - s : s > hi ? s - hi : 0;
        if (fmin(zl, zh) + cs_dropcut_profile(c->t, fmin(r, hypot(dw, near))) >= best)
            continue;
        double x = lo, y = hi; /* golden section on [x, y] */
        for (int it = 0; it < DC_ALONG_ITER; it++) {
            double m1 = y - (y - x) * 0.6180339887498949, m2 = x + (y - x) * 0.6180339887498949;
            if (chord_env(c, sa, za, sb, zb, m1, s, dw) <= chord_env(c, sa, za, sb, zb, m2, s, dw))
                y = m2;
            else
                x = m1;
        }
        best = fmin(best, chord_env(c, sa, za, sb, zb, (x + y) / 2, s, dw));
        best = fmin(best, fmin(chord_env(c, sa, za, sb, zb, lo, s, dw),
                               chord_env(c, sa, za, sb, zb, hi, s, dw)));
    }
    return best;
}

/* Appends (x, y) to p's flagged points. */
static bool flag_push(cs_dcpath_t *p, double x, double y)
{
    if (p->nflag == p->flagcap) {
        size_t cap = p->flagcap ? 2 * p->flagcap : 256;
        double(*f)[2] = realloc(p->flag, cap * sizeof *f);
        if (!f)
            return false;
        p->flag = f;
        p->flagcap = cap;
    }
    p->flag[p->nflag][0] = x;
    p->flag[p->nflag++][1] = y;
    return true;
}

/* Largest material height left between lines[i] and lines[i + 1], estimated as in the header
 * with the cutters of every line within R of the point, at every position along it within R
 * (line_env); *cusp gets the gap to refine for the worst point: the gap holding the axis of a
 * cutter that touches the surface there (on a slope not gap i: each cutter touches the surface
 * uphill of its axis), else the gap next to the lowest cutter, towards the second lowest. A point
 * whose estimate at the same along-pass position (an upper bound) is no more than the worst so
 * far cannot change the result and is not searched along the passes. */
static double left_between(dc_ctx_t *c, const dc_line_t *lines, const double *w, size_t n,
                           size_t i, double min_gap, size_t *cusp, double *stuck, cs_dcpath_t *fl,
                           double need)
{
    const dc_line_t *a = &lines[i], *b = &lines[i + 1];
    const dc_line_t *fine = a->n >= b->n ? a : b;
    double worst = 0, r = c->t->r_mm;
    *cusp = i;
    if (a->n == 0 || b->n == 0)
        return 0;
    size_t lo = i, hi = i + 1;
    while (lo > 0 && w[i] - w[lo - 1] <= r)
        lo--;
    while (hi + 1 < n && w[hi + 1] - w[i + 1] <= r)
        hi++;
    /* Across the gap at least every min_gap (a flat end's step changes abruptly where a
     * neighbour's rim passes), at least DC_SCAN_FRACS points, at most DC_SCAN_MAX. */
    int nf = (int)fmin(DC_SCAN_MAX, fmax(DC_SCAN_FRACS, ceil((w[i + 1] - w[i]) / min_gap)));
    for (size_t k = 0; k < fine->n; k++) {
        double s = fine->s[k];
        for (int f = 1; f <= nf; f++) {
            double wp = w[i] + (w[i + 1] - w[i]) * f / (nf + 1.0);
            double x = s * c->d[0] + wp * c->e[0], y = s * c->d[1] + wp * c->e[1], top, cs;
            double g[2];
            if (!cs_dropcut_top(c->ms, x, y, &top) || near_rim(c, x, y) ||
                (cs = slope_cos(c, x, y, top, g)) == 0)
                continue; /* the scallop is promised where the cutter lies over the surface */
            /* A ball's envelope runs parallel to the surface: across it the height left is the
             * vertical one times cos. A flat or bull-nose end's bottom is level, not parallel:
             * the vertical height bounds the distance to it (the check's measure). */
            double fac = c->t->c_mm >= c->t->r_mm ? cs : 1, base = fmax(top, c->o->min_z);
            double env = HUGE_VAL, env2 = HUGE_VAL, stop = base + worst / fac;
            size_t j1 = i, j2 = i + 1;
            for (size_t j = lo; j <= hi; j++) {
                double d = fabs(w[j] - wp);
                if (d > r || lines[j].n == 0)
                    continue;
                double e = line_z(&lines[j], s) + cs_dropcut_profile(c->t, d);
                if (e < env) {
                    env2 = env, j2 = j1;
                    env = e, j1 = j;
                } else if (e < env2) {
                    env2 = e, j2 = j;
                }
            }
            if (env == HUGE_VAL || env <= stop)
                continue;
            size_t ca = gap_of(w, n, contact_axis(c, wp, g));
            for (size_t j = lo; j <= hi && env > stop; j++) {
                double d = fabs(w[j] - wp);
                if (d > r || lines[j].n == 0 || !near_line(j, i, ca))
                    continue;
                double e = line_env(c, &lines[j], s, d, env, stop);
                if (e < env && j != j1)
                    env2 = env, j2 = j1, j1 = j;
                env = e;
            }
            double left = (env - base) * fac;
            if (left > worst) {
                size_t ga = ca != (size_t)-1 ? ca : j2 > j1 ? j1 : (j1 > 0 ? j1 - 1 : 0);
                if (ga + 1 >= n || w[ga + 1] - w[ga] < 2 * min_gap) {
                    /* no pass can be added there: rest material (a slot narrower than the
                     * cutter, a corner) or a wall; reported, not chased */
                    *stuck = fmax(*stuck, left);
                    if (left > need && !flag_push(fl, x, y))
                        return -1;
                    continue;
                }
                worst = left;
                *cusp = ga;
            }
        }
    }
    return worst;
}

/* Room for one more pass of n points. */
static cs_err_t reserve(cs_dcpath_t *p, size_t n)
{
    if (p->npass + 1 >= p->pcap) {
        size_t cap = p->pcap ? 2 * p->pcap : 64;
        size_t *ns = realloc(p->start, (cap + 1) * sizeof *ns);
        if (!ns)
            return CS_ERR_FULL;
        p->start = ns;
        double *nw = realloc(p->w, cap * sizeof *nw);
        if (!nw)
            return CS_ERR_FULL;
        p->w = nw;
        p->pcap = cap;
    }
    if (p->n + n > p->cap) {
        size_t cap = p->cap ? p->cap : 1024;
        while (cap < p->n + n)
            cap *= 2;
        double(*np)[3] = realloc(p->pt, cap * sizeof *np);
        if (!np)
            return CS_ERR_FULL;
        p->pt = np;
        p->cap = cap;
    }
    if (p->npass == 0)
        p->start[0] = 0;
    return CS_OK;
}

cs_err_t cs_dcpath_append(cs_dcpath_t *p, const double (*pts)[3], size_t n, double w)
{
    if (reserve(p, n) != CS_OK)
        return CS_ERR_FULL;
    memcpy(p->pt[p->n], pts, n * sizeof *pts);
    p->n += n;
    p->w[p->npass++] = w;
    p->start[p->npass] = p->n;
    return CS_OK;
}

static cs_err_t add_pass(cs_dcpath_t *p, const dc_ctx_t *c, const dc_line_t *l, double w)
{
    if (reserve(p, l->n) != CS_OK)
        return CS_ERR_FULL;
    bool rev = p->npass % 2 == 1; /* zig-zag */
    for (size_t k = 0; k < l->n; k++) {
        size_t i = rev ? l->n - 1 - k : k;
        double *q = p->pt[p->n++];
        q[0] = l->s[i] * c->d[0] + w * c->e[0];
        q[1] = l->s[i] * c->d[1] + w * c->e[1];
        q[2] = l->z[i];
    }
    p->w[p->npass++] = w;
    p->start[p->npass] = p->n;
    return CS_OK;
}

/* The lines of the raster, in cross order, while it is refined. */
typedef struct {
    dc_line_t *l;
    double *w;
    size_t n, cap;
} dc_set_t;

static cs_err_t set_insert(dc_set_t *set, size_t at, dc_line_t *l, double w)
{
    if (set->n == set->cap) {
        size_t cap = set->cap ? 2 * set->cap : 64;
        dc_line_t *nl = realloc(set->l, cap * sizeof *nl);
        if (!nl)
            return CS_ERR_FULL;
        set->l = nl;
        double *nw = realloc(set->w, cap * sizeof *nw);
        if (!nw)
            return CS_ERR_FULL;
        set->w = nw;
        set->cap = cap;
    }
    memmove(&set->l[at + 1], &set->l[at], (set->n - at) * sizeof *set->l);
    memmove(&set->w[at + 1], &set->w[at], (set->n - at) * sizeof *set->w);
    set->l[at] = *l;
    set->w[at] = w;
    set->n++;
    return CS_OK;
}

/* Halves the gap whose cutters leave more than H - eps between them (found from every gap in
 * turn), until none does or the gap is narrower than 2 min_gap, so that both halves stay at
 * least min_gap wide: the least gap lies between min_gap and 2 min_gap (steep walls, concave
 * corners narrower than the cutter: reported by max_stuck). */
static cs_err_t refine_gaps(cs_dcpath_t *p, dc_ctx_t *c, dc_set_t *set, double min_gap)
{
    /* The mesh stands up to eps off the surface and a pass's chords up to tol / 2 off the drop
     * height (refine): both may add to what the cutters leave. */
    double need = c->o->scallop_mm - c->ms->eps - c->o->tol_mm / 2;
    cs_err_t e = CS_OK;
    for (size_t i = 0; i + 1 < set->n && e == CS_OK;) {
        size_t g, mark = p->nflag;
        double stuck = 0;
        double left = left_between(c, set->l, set->w, set->n, i, min_gap, &g, &stuck, p, need);
        if (left < 0)
            return CS_ERR_FULL;
        if (left > need && set->n < c->o->max_passes)
            p->nflag = mark; /* the gap changes: its points are flagged when it is final */
        if (left <= need || set->n >= c->o->max_passes) {
            p->capped |= left > need && set->n >= c->o->max_passes;
            p->max_left = fmax(p->max_left, left);
            p->max_stuck = fmax(p->max_stuck, stuck);
            i++;
            continue;
        }
        dc_line_t m = {0};
        double wm = (set->w[g] + set->w[g + 1]) / 2;
        e = build_line(c, &m, wm) ? CS_OK : CS_ERR_FULL;
        if (e == CS_OK)
            e = set_insert(set, g + 1, &m, wm);
        p->refined++;
        if (g < i)
            i = g; /* the new line changes the estimates from gap g on */
    }
    return e;
}

cs_err_t cs_dcpath_raster(cs_dcpath_t *p, cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                          const cs_dcpath_opts_t *o)
{
    double a = o->angle_deg * M_PI / 180;
    dc_ctx_t c = {ms, t, o, {cos(a), sin(a)}, {-sin(a), cos(a)}, 0};
    double step = o->step_mm > 0 ? o->step_mm : cs_dcpath_step(t, o->scallop_mm);
    if (!(step > 0) || !(o->tol_mm > 0) || o->box[2] < o->box[0] || o->box[3] < o->box[1])
        return CS_ERR_RANGE;
    /* The cross extent of the region: its corners projected on e. */
    double w0 = HUGE_VAL, w1 = -HUGE_VAL;
    for (int k = 0; k < 4; k++) {
        double x = o->box[(k & 1) ? 2 : 0], y = o->box[(k & 2) ? 3 : 1];
        w0 = fmin(w0, x * c.e[0] + y * c.e[1]);
        w1 = fmax(w1, x * c.e[0] + y * c.e[1]);
    }
    size_t n = (size_t)ceil((w1 - w0) / step);
    n = n ? n : 1;
    dc_set_t set = {0};
    cs_err_t e = CS_OK;
    for (size_t k = 0; k <= n && e == CS_OK; k++) {
        dc_line_t l = {0};
        double w = w0 + (w1 - w0) * (double)k / (double)n;
        e = build_line(&c, &l, w) ? CS_OK : CS_ERR_FULL;
        if (e == CS_OK)
            e = set_insert(&set, set.n, &l, w);
    }
    /* Every cutter's gaps are refined: a flat or bull-nose end leaves a step on a slope about
     * the slope times the gap, which the refinement brings under H like a ball's cusp. The
     * least gap: a sixteenth of a ball's flat-ground step of the same radius. */
    if (e == CS_OK && o->step_mm <= 0)
        e = refine_gaps(p, &c, &set, 2 * sqrt(2 * t->r_mm * o->scallop_mm) / 16);
    else if (e == CS_OK)
        p->max_left = NAN;
    for (size_t k = 0; k < set.n; k++) {
        if (e == CS_OK && set.l[k].n > 0)
            e = add_pass(p, &c, &set.l[k], set.w[k]);
        free(set.l[k].s);
        free(set.l[k].z);
    }
    free(set.l);
    free(set.w);
    p->drops = c.drops;
    return e;
}

/* Is the chord from a to b (tip points, mm) within tol / 2 of the drop height of t, as refine
 * holds the raster's chords: at its midpoint and both quarter points? */
static bool chord_clear(cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                        const cs_dcpath_opts_t *o, const double a[3], const double b[3],
                        size_t *drops)
{
    for (int k = 1; k <= 3; k++) {
        double f = k / 4.0, z = a[2] + f * (b[2] - a[2]);
        bool hit;
        double d = cs_dropcut_drop(ms, t, a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), &hit);
        (*drops)++;
        if (fabs((hit ? fmax(d, o->min_z) : o->min_z) - z) > o->tol_mm / 2)
            return false;
    }
    return true;
}

/* One short pass at each of the n axis positions at (xy, mm): the drop there, and the drops
 * tol / 2 before and after it along x where the chord to them passes refine's test (near a jump
 * of the drop height, a low and a high drop joined by a chord would cut into the step: that
 * side is left out, down to the one point, a plunge). */
static cs_err_t fill_at(cs_dcpath_t *p, cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                        const cs_dcpath_opts_t *o, const double (*at)[2], size_t n)
{
    cs_err_t e = CS_OK;
    for (size_t i = 0; i < n && e == CS_OK; i++) {
        double q[3][3];
        for (int j = 0; j < 3; j++) {
            bool hit;
            q[j][0] = at[i][0] + (j - 1) * o->tol_mm / 2;
            q[j][1] = at[i][1];
            double z = cs_dropcut_drop(ms, t, q[j][0], q[j][1], &hit);
            q[j][2] = hit ? fmax(z, o->min_z) : o->min_z;
            p->drops++;
        }
        bool lo = chord_clear(ms, t, o, q[0], q[1], &p->drops);
        bool hi = chord_clear(ms, t, o, q[1], q[2], &p->drops);
        if (!lo)
            memcpy(q[0], q[1], sizeof q[0]), memcpy(q[1], q[2], sizeof q[1]);
        e = cs_dcpath_append(p, (const double(*)[3])q, 1 + (size_t)lo + (size_t)hi, at[i][1]);
    }
    return e;
}

cs_err_t cs_dcpath_fill(cs_dcpath_t *p, cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                        const cs_surffile_t *sf, const cs_dcpath_opts_t *o, double step_mm,
                        bool flagged, int rounds, size_t *added)
{
    cs_dropcheck_win_t win = {(const double(*)[2])p->flag, p->nflag, t->r_mm / 4};
    if (flagged && p->nflag == 0)
        return CS_OK;
    for (int round = 0; round < rounds; round++) {
        cs_dropcheck_t ck;
        double(*at)[2];
        size_t nat;
        cs_err_t e = cs_dropcheck_gaps(sf, t, (const double(*)[3])p->pt, p->start, p->npass, o->box,
                                       step_mm, o->scallop_mm - ms->eps, ms->eps,
                                       flagged ? &win : NULL, &ck, &at, &nat);
        if (e == CS_OK)
            e = fill_at(p, ms, t, o, (const double(*)[2])at, nat);
        free(at);
        *added += nat;
        if (e != CS_OK)
            return e;
        if (nat == 0)
            break;
    }
    return CS_OK;
}

/* Does the straight move a -> b keep the cutter no lower than the drop height less slack? */
static bool link_clear(cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t, const double a[3],
                       const double b[3], double step, double slack)
{
    double len = hypot(b[0] - a[0], b[1] - a[1]);
    size_t n = (size_t)ceil(len / step) + 1;
    for (size_t k = 0; k <= n; k++) {
        double f = (double)k / (double)n, z = a[2] + f * (b[2] - a[2]);
        bool hit;
        double d = cs_dropcut_drop(ms, t, a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), &hit);
        if (hit && d - slack > z)
            return false;
    }
    return true;
}

void cs_dcpath_link(cs_dcpath_t *p, cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                    double step_mm, double tol_mm)
{
    size_t out = 0; /* passes kept: pass k joins pass out - 1 or starts anew */
    for (size_t k = 0; k < p->npass; k++) {
        size_t s0 = p->start[k], s1 = p->start[k + 1];
        bool join = out > 0 && s1 > s0 &&
                    link_clear(ms, t, p->pt[s0 - 1], p->pt[s0], step_mm, tol_mm / 2);
        if (join) {
            p->links++;
        } else {
            p->start[out++] = s0;
        }
    }
    p->start[out] = p->n;
    p->npass = out;
}

void cs_dcpath_free(cs_dcpath_t *p)
{
    free(p->flag);
    free(p->pt);
    free(p->start);
    free(p->w);
    cs_dcpath_init(p);
}
