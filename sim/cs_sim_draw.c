/* cs_sim_draw: SVG, PNG (cairo) and CSV views of a run. */
#include "cs_sim_draw.h"

#include <cairo.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define S2 0.70710678118654752440
#define S6 0.40824829046386301637
/* The projections of `curvestep toolpath --view` (host/cs_toolpath_cmd.c), same matrices:
 * orthographic, orthonormal rows, picture y up. */
static const cs_sim_view_t views[] = {
    {"top", {{1, 0, 0, 0}, {0, 1, 0, 0}}, false},
    {"front", {{1, 0, 0, 0}, {0, 0, 1, 0}}, false},
    {"side", {{0, 1, 0, 0}, {0, 0, 1, 0}}, false},
    /* seen from (1, -1, 1): right (1, 1, 0)/sqrt 2, up (-1, 1, 2)/sqrt 6 */
    {"iso", {{S2, S2, 0, 0}, {-S6, S6, 2 * S6, 0}}, false},
};

void cs_sim_view_default(cs_sim_view_t *v)
{
    *v = views[0];
    v->name = "xy";
    v->y_down = false; /* the machine seen from above: jobs are y-up (SVG pages turned, cs_layout) */
}

bool cs_sim_view_parse(const char *s, cs_sim_view_t *v)
{
    for (size_t k = 0; k < sizeof views / sizeof views[0]; k++)
        if (strcmp(s, views[k].name) == 0) {
            *v = views[k];
            return true;
        }
    return false;
}

void cs_sim_view_project(const cs_sim_view_t *v, const double p[3], double out[2])
{
    for (int r = 0; r < 2; r++)
        out[r] = v->m[r][0] * p[0] + v->m[r][1] * p[1] + v->m[r][2] * p[2] + v->m[r][3];
    if (!v->y_down)
        out[1] = -out[1]; /* picture coordinates have y down */
}

typedef struct {
    double x, y, v; /* picture coordinates (mm), and speed over the sample before it (mm/s) */
    double p[3];    /* machine position, mm */
    bool travel;    /* the reference piece it lies on is a travel (or the run's pen is up) */
    uint64_t t;     /* its tick */
    int mark;       /* a servo setting at this sample: 1 pen down, -1 pen up, 0 none */
} sample_t;

/* The executed path sampled every dt ticks (about 20000 samples at most, >= 1 ms apart). */
static sample_t *exec_samples(const cs_machine_t *m, const cs_sim_exec_t *ex,
                              const cs_sim_view_t *view, size_t *n)
{
    uint64_t dt = m->tick_hz / 1000;
    if (ex->end_tick / 20000 > dt)
        dt = ex->end_tick / 20000;
    if (dt == 0)
        dt = 1;
    size_t cap = (size_t)(ex->end_tick / dt) + 3;
    sample_t *s = malloc(cap * sizeof *s);
    if (s == NULL)
        return NULL;
    double spm[3];
    for (unsigned i = 0; i < 3; i++)
        spm[i] = (double)m->axis[i].steps_per_mm / CS_MOTION_ONE;
    int64_t pos[CS_AXES] = {0, 0, 0, 0};
    size_t e = 0, k = 0;
    for (uint64_t t = 0; k < cap; t += dt) {
        while (e < ex->n && ex->edges[e].t <= t) {
            pos[ex->edges[e].axis] += ex->edges[e].dir;
            e++;
        }
        for (int i = 0; i < 3; i++)
            s[k].p[i] = (double)pos[i] / spm[i];
        double q[2];
        cs_sim_view_project(view, s[k].p, q);
        s[k].x = q[0];
        s[k].y = q[1];
        s[k].v = 0;
        s[k].travel = false;
        s[k].t = t;
        s[k].mark = 0;
        if (k > 0) {
            double d2 = 0;
            /* The legacy xy picture ignores z in the speed (pen up/down); a view uses 3D speed. */
            for (int i = 0; i < (view->y_down ? 2 : 3); i++)
                d2 += (s[k].p[i] - s[k - 1].p[i]) * (s[k].p[i] - s[k - 1].p[i]);
            s[k].v = sqrt(d2) / ((double)dt / m->tick_hz);
        }
        k++;
        if (t > ex->end_tick)
            break;
    }
    *n = k;
    return s;
}

static double seg_dist(const double *p, const double *a, const double *b)
{
    double ab[3], ap[3], l2 = 0, t = 0, d2 = 0;
    for (int i = 0; i < 3; i++) {
        ab[i] = b[i] - a[i];
        ap[i] = p[i] - a[i];
        l2 += ab[i] * ab[i];
        t += ab[i] * ap[i];
    }
    t = l2 > 0 ? fmin(fmax(t / l2, 0), 1) : 0;
    for (int i = 0; i < 3; i++) {
        double d = ap[i] - t * ab[i];
        d2 += d * d;
    }
    return sqrt(d2);
}

/* Piece j of the reference runs from point j - 1 to point j; false for a polyline's first point
 * (no piece ends there). */
static bool is_piece(const cs_sim_ref_t *r, size_t j, size_t *line)
{
    while (*line + 1 < r->nlines && r->starts[*line + 1] <= j)
        (*line)++;
    return j > 0 && r->starts[*line] != j;
}

/* Marks the samples that lie on travel pieces of the reference. The executor runs the job in
 * order, so a cursor moves forward along the reference: each sample takes the nearest piece
 * within a window ahead of the cursor (the rest of the cursor's piece and then an arc length of
 * 2 x the larger of the sample's move and its distance from the cursor's piece, + 1 mm; a piece
 * that points against the sample's motion counts 0.1 mm farther; ties go to the earliest
 * piece); when nothing in the window is within 0.2 mm (the executed path stays within
 * tolerance + one step of the reference) the rest of the reference is searched (at most 200
 * times per picture). Returns whether any sample is travel. */
static bool classify(sample_t *s, size_t n, const cs_sim_ref_t *r)
{
    if (r == NULL || r->travel == NULL || r->n < 2)
        return false;
    bool any = false;
    size_t cur = 1, line = 0;
    int searches = 0;
    for (size_t k = 0; k < n; k++) {
        double move = 0;
        if (k > 0)
            for (int i = 0; i < 3; i++)
                move += (s[k].p[i] - s[k - 1].p[i]) * (s[k].p[i] - s[k - 1].p[i]);
        double dcur = seg_dist(s[k].p, &r->xyz[3 * (cur - 1)], &r->xyz[3 * cur]);
        const double *ca = &r->xyz[3 * (cur - 1)], *cb = &r->xyz[3 * cur];
        /* The window is the rest of the cursor's piece (counted whole) and reach beyond it. */
        double reach = 2 * fmax(sqrt(move), dcur) + 1, best = HUGE_VAL;
        double walked =
            -sqrt((cb[0] - ca[0]) * (cb[0] - ca[0]) + (cb[1] - ca[1]) * (cb[1] - ca[1]) +
                  (cb[2] - ca[2]) * (cb[2] - ca[2]));
        size_t best_j = cur, l = line, best_l = line;
        /* The search of the whole rest costs the reference's size: at most 200 of them (a
         * reference that does not match the run, or a machine tolerance above 0.2 mm). */
        for (int pass = 0; pass < 2 && best > 0.2 && (pass == 0 || searches++ < 200); pass++) {
            for (size_t j = cur; j < r->n && (pass == 1 || walked <= reach); j++) {
                if (!is_piece(r, j, &l))
                    continue;
                const double *a = &r->xyz[3 * (j - 1)], *b = &r->xyz[3 * j];
                double d = seg_dist(s[k].p, a, b);
                /* A piece run backwards scores worse: the retract of one patch and the plunge
                 * of the next can be the same line, told apart by the direction of motion. */
                double dot = 0;
                for (int i = 0; k > 0 && i < 3; i++)
                    dot += (s[k].p[i] - s[k - 1].p[i]) * (b[i] - a[i]);
                if (dot < 0)
                    d += 0.1;
                if (d < best) {
                    best = d;
                    best_j = j;
                    best_l = l;
                }
                walked += sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
                               (b[2] - a[2]) * (b[2] - a[2]));
            }
            l = line;
        }
        cur = best_j;
        line = best_l;
        s[k].travel = r->travel[cur] != 0;
        any = any || s[k].travel;
    }
    return any;
}

static double top_speed(const sample_t *s, size_t n)
{
    double vmax = 0;
    for (size_t k = 1; k < n; k++)
        if (!s[k].travel && s[k].v > vmax)
            vmax = s[k].v;
    return vmax;
}

/* The servo pen's state over the samples (cs_sim_draw_pen_t): segment i starts at the sum of the
 * ticks before it (the run has no idle gaps, cs_sim_execute); an event applies before its
 * segment. Marks the sample at or after each event. */
static void pen_servo(sample_t *s, size_t n, const cs_machine_pen_t *pen,
                      const cs_motion_segs_t *segs)
{
    size_t i = 0, ev = 0;
    uint64_t start = 0;
    bool down = false;
    for (size_t k = 0; k < n; k++) {
        while (i < segs->n && start + segs->v[i].ticks <= s[k].t)
            start += segs->v[i++].ticks;
        for (; ev < segs->npens && segs->pens[ev].seg <= i; ev++) {
            down = segs->pens[ev].pulse_us == pen->down_us;
            s[k].mark = down ? 1 : -1;
        }
        s[k].travel = !down;
    }
}

/* Classifies the samples by the run's own pen (pp NULL or mode none: unchanged, returns
 * travel_known). Returns whether any sample is pen-up. */
static bool pen_classify(sample_t *s, size_t n, const cs_sim_draw_pen_t *pp, bool travel_known)
{
    if (pp == NULL || pp->pen == NULL || pp->pen->mode == CS_MACHINE_PEN_NONE)
        return travel_known;
    const cs_machine_pen_t *pen = pp->pen;
    if (pen->mode == CS_MACHINE_PEN_SERVO && pp->segs != NULL)
        pen_servo(s, n, pen, pp->segs);
    else /* z: as the check (cs_sim_check.c, pen_is_down) */
        for (size_t k = 0; k < n; k++)
            s[k].travel = !(fabs(s[k].p[2] - pen->down_z_mm) < fabs(s[k].p[2] - pen->up_z_mm));
    bool any = false;
    for (size_t k = 0; k < n && !any; k++)
        any = s[k].travel;
    return any;
}

/* The end (exclusive) of the travel run that starts at sample k, and whether it moves in the
 * picture (a pen-up stretch without motion, as the raise at the job's end, draws nothing). */
static size_t travel_run(const sample_t *s, size_t n, size_t k, bool *moves)
{
    *moves = false;
    size_t j = k;
    for (; j < n && s[j].travel; j++)
        *moves = *moves || s[j].x != s[k - 1].x || s[j].y != s[k - 1].y;
    return j;
}

/* The page outline: the machine's x y travel as drawn in the picture, for the default and top
 * views, when it is a real bed (both spans under 2 m: not the built-in machine's 2 m box). */
static bool bed_box(const cs_machine_t *m, const cs_sim_view_t *view, double lo[2], double hi[2])
{
    double x0 = (double)m->axis[0].travel_min / CS_POS_ONE_MM;
    double x1 = (double)m->axis[0].travel_max / CS_POS_ONE_MM;
    double y0 = (double)m->axis[1].travel_min / CS_POS_ONE_MM;
    double y1 = (double)m->axis[1].travel_max / CS_POS_ONE_MM;
    if (view->m[0][2] != 0 || view->m[1][2] != 0 || view->m[0][1] != 0 || x1 - x0 >= 2000 ||
        y1 - y0 >= 2000)
        return false; /* a view with z in it, or no bed to speak of */
    double a[2], b[2], p[3] = {x0, y0, 0}, q[3] = {x1, y1, 0};
    cs_sim_view_project(view, p, a);
    cs_sim_view_project(view, q, b);
    lo[0] = fmin(a[0], b[0]);
    lo[1] = fmin(a[1], b[1]);
    hi[0] = fmax(a[0], b[0]);
    hi[1] = fmax(a[1], b[1]);
    return true;
}

static void speed_rgb(double f, double rgb[3]);

/* The legend band under the drawing: its top y and text size (picture mm). */
typedef struct {
    double x0, y, u, w;
} legend_t;

static void bounds(const cs_machine_t *m, const sample_t *s, size_t n, const cs_sim_ref_t *ref,
                   const cs_sim_view_t *view, double lo[2], double hi[2], legend_t *lg)
{
    lo[0] = lo[1] = HUGE_VAL;
    hi[0] = hi[1] = -HUGE_VAL;
    for (size_t k = 0; k < n; k++) {
        lo[0] = fmin(lo[0], s[k].x);
        lo[1] = fmin(lo[1], s[k].y);
        hi[0] = fmax(hi[0], s[k].x);
        hi[1] = fmax(hi[1], s[k].y);
    }
    for (size_t k = 0; ref && k < ref->n; k++) {
        double q[2];
        cs_sim_view_project(view, &ref->xyz[3 * k], q);
        lo[0] = fmin(lo[0], q[0]);
        lo[1] = fmin(lo[1], q[1]);
        hi[0] = fmax(hi[0], q[0]);
        hi[1] = fmax(hi[1], q[1]);
    }
    if (!(lo[0] <= hi[0])) {
        lo[0] = lo[1] = 0;
        hi[0] = hi[1] = 1;
    }
    double blo[2], bhi[2];
    if (bed_box(m, view, blo, bhi))
        for (int i = 0; i < 2; i++) {
            lo[i] = fmin(lo[i], blo[i]);
            hi[i] = fmax(hi[i], bhi[i]);
        }
    double pad = fmax(hi[0] - lo[0], hi[1] - lo[1]) * 0.03 + 1;
    lo[0] -= pad;
    lo[1] -= pad;
    hi[0] += pad;
    hi[1] += pad;
    /* the legend: a band 6 % of the width tall under everything, text a third of it */
    lg->x0 = lo[0] + pad;
    lg->w = hi[0] - lo[0] - 2 * pad;
    lg->u = (hi[0] - lo[0]) * 0.06 / 3;
    lg->y = hi[1];
    hi[1] += 3 * lg->u;
}

/* x positions of the legend's three items: speed bar, travel, exact geometry. */
static double legend_x(const legend_t *lg, int item)
{
    return lg->x0 + lg->w * (item == 0 ? 0.0 : item == 1 ? 0.4 : 0.7);
}

static void svg_legend(FILE *f, const legend_t *lg, double vmax, double lw, bool travel,
                       const cs_machine_t *m, const cs_sim_view_t *view)
{
    double y = lg->y + 1.5 * lg->u, bar = lg->w * 0.3, x = legend_x(lg, 0);
    fprintf(f, "<g class=\"legend\" font-family=\"sans-serif\" font-size=\"%.4f\">\n", lg->u);
    for (int k = 0; k < 20; k++) {
        double rgb[3];
        speed_rgb((k + 0.5) / 20, rgb);
        fprintf(f,
                "<rect x=\"%.4f\" y=\"%.4f\" width=\"%.4f\" height=\"%.4f\" "
                "fill=\"#%02x%02x%02x\"/>\n",
                x + bar * k / 20, y - lg->u * 0.4, bar / 20 + lw, lg->u * 0.8, (int)(rgb[0] * 255),
                (int)(rgb[1] * 255), (int)(rgb[2] * 255));
    }
    fprintf(f, "<text x=\"%.4f\" y=\"%.4f\">speed 0 .. %.1f mm/s (drawing)</text>\n", x,
            y + 1.3 * lg->u, vmax);
    x = legend_x(lg, 1);
    if (travel)
        fprintf(f,
                "<line x1=\"%.4f\" y1=\"%.4f\" x2=\"%.4f\" y2=\"%.4f\" stroke=\"#999999\" "
                "stroke-width=\"%.4f\" stroke-dasharray=\"%.4f %.4f\"/>\n"
                "<text x=\"%.4f\" y=\"%.4f\">pen-up travel</text>\n",
                x, y, x + 3 * lg->u, y, lw, 6 * lw, 4 * lw, x + 3.5 * lg->u, y + 0.35 * lg->u);
    double bx = x; /* the bed's note goes under the travel sample */
    x = legend_x(lg, 2);
    fprintf(f,
            "<line x1=\"%.4f\" y1=\"%.4f\" x2=\"%.4f\" y2=\"%.4f\" stroke=\"black\" "
            "stroke-width=\"%.4f\"/>\n<text x=\"%.4f\" y=\"%.4f\">exact geometry</text>\n",
            x, y, x + 3 * lg->u, y, lw, x + 3.5 * lg->u, y + 0.35 * lg->u);
    double blo[2], bhi[2];
    if (bed_box(m, view, blo, bhi))
        fprintf(f,
                "<text x=\"%.4f\" y=\"%.4f\">grey box: the machine's x y travel; "
                "x right, y %s</text>\n",
                bx, y + 1.3 * lg->u, view->y_down ? "down" : "up");
    fprintf(f, "</g>\n");
}

/* Speed fraction f in [0, 1] -> blue (slow) .. green .. red (fast). */
static void speed_rgb(double f, double rgb[3])
{
    f = f < 0 ? 0 : f > 1 ? 1 : f;
    double h = (1 - f) * 240.0 / 60.0; /* hue in sextants: 4 = blue, 0 = red */
    double x = 1 - fabs(fmod(h, 2) - 1);
    double r = 0, g = 0, b = 0;
    if (h < 1)
        r = 1, g = x;
    else if (h < 2)
        r = x, g = 1;
    else if (h < 3)
        g = 1, b = x;
    else
        g = x, b = 1;
    rgb[0] = r * 0.9;
    rgb[1] = g * 0.8;
    rgb[2] = b * 0.9;
}

/* The reference's cut pieces as runs of consecutive points (travel pieces are left out: the
 * executed travel is drawn instead). Calls fn(ctx, first, count) per run of >= 2 points. */
static void ref_runs(const cs_sim_ref_t *ref,
                     void (*fn)(void *, const cs_sim_ref_t *, size_t, size_t,
                                const cs_sim_view_t *),
                     void *ctx, const cs_sim_view_t *view)
{
    for (size_t li = 0; ref && li < ref->nlines; li++) {
        size_t b = ref->starts[li], e = li + 1 < ref->nlines ? ref->starts[li + 1] : ref->n;
        size_t run = b;
        for (size_t k = b + 1; k <= e; k++) {
            bool cut_piece = k < e && !(ref->travel && ref->travel[k]);
            if (cut_piece)
                continue;
            if (k - run >= 2)
                fn(ctx, ref, run, k - run, view);
            run = k;
        }
        if (e - b == 1)
            fn(ctx, ref, b, 1, view);
    }
}

static void svg_ref_run(void *ctx, const cs_sim_ref_t *ref, size_t b, size_t n,
                        const cs_sim_view_t *view)
{
    FILE *f = ctx;
    fprintf(f, "<polyline points=\"");
    for (size_t k = b; k < b + n; k++) {
        double q[2];
        cs_sim_view_project(view, &ref->xyz[3 * k], q);
        fprintf(f, "%.4f,%.4f ", q[0], q[1]);
    }
    fprintf(f, "\"/>\n");
}

/* --- machine control: spindle / laser power along the path, switch trips, probe contacts -- */

/* The spindle duty (1/1000) in force at tick t, 0 before the first setting. */
static unsigned duty_at(const cs_sim_exec_t *ex, uint64_t t, size_t *cur)
{
    while (*cur < ex->nspins && ex->spins[*cur].t <= t)
        (*cur)++;
    if (*cur == 0)
        return 0;
    const port_posix_spindle_t *sp = &ex->spins[*cur - 1];
    return sp->mode != 0 ? sp->duty : 0;
}

/* Mark colours: alarm (switch trip, e-stop) red, probe contact green, axis homed blue. */
static void mark_rgb(uint8_t kind, double rgb[3])
{
    rgb[0] = kind == CS_SIM_MARK_ALARM ? 0.85 : 0.1;
    rgb[1] = kind == CS_SIM_MARK_PROBE ? 0.65 : 0.1;
    rgb[2] = kind == CS_SIM_MARK_HOMED ? 0.85 : 0.1;
}

/* Under the path: where the output is on, a translucent orange band as wide as the duty (up to
 * 12 line widths at full power); over it: a ring at each mark. */
static void svg_control(FILE *f, const cs_sim_exec_t *ex, const sample_t *s, size_t n,
                        const cs_sim_view_t *view, double lw)
{
    size_t cur = 0;
    for (size_t k = 1; k < n && ex->nspins > 0; k++) {
        unsigned d = duty_at(ex, s[k].t, &cur);
        if (d == 0)
            continue;
        fprintf(f,
                "<line class=\"power\" x1=\"%.4f\" y1=\"%.4f\" x2=\"%.4f\" y2=\"%.4f\" "
                "stroke=\"#ff8c00\" stroke-opacity=\"0.45\" stroke-width=\"%.4f\"/>\n",
                s[k - 1].x, s[k - 1].y, s[k].x, s[k].y, 12 * lw * d / 1000.0);
    }
    for (size_t i = 0; i < ex->nmarks; i++) {
        double q[2], rgb[3];
        cs_sim_view_project(view, ex->marks[i].p, q);
        mark_rgb(ex->marks[i].kind, rgb);
        fprintf(f,
                "<circle class=\"mark\" cx=\"%.4f\" cy=\"%.4f\" r=\"%.4f\" fill=\"none\" "
                "stroke=\"#%02x%02x%02x\" stroke-width=\"%.4f\"/>\n",
                q[0], q[1], 8 * lw, (int)(rgb[0] * 255), (int)(rgb[1] * 255), (int)(rgb[2] * 255),
                2 * lw);
    }
}

static void png_control(cairo_t *cr, const cs_sim_exec_t *ex, const sample_t *s, size_t n,
                        const cs_sim_view_t *view, double scale)
{
    size_t cur = 0;
    for (size_t k = 1; k < n && ex->nspins > 0; k++) {
        unsigned d = duty_at(ex, s[k].t, &cur);
        if (d == 0)
            continue;
        cairo_set_source_rgba(cr, 1.0, 0.55, 0.0, 0.45);
        cairo_set_line_width(cr, 12.0 * d / 1000.0 / scale);
        cairo_move_to(cr, s[k - 1].x, s[k - 1].y);
        cairo_line_to(cr, s[k].x, s[k].y);
        cairo_stroke(cr);
    }
    cairo_set_line_width(cr, 2.0 / scale);
    for (size_t i = 0; i < ex->nmarks; i++) {
        double q[2], rgb[3];
        cs_sim_view_project(view, ex->marks[i].p, q);
        mark_rgb(ex->marks[i].kind, rgb);
        cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
        cairo_new_sub_path(cr);
        cairo_arc(cr, q[0], q[1], 8.0 / scale, 0, 2 * M_PI);
        cairo_stroke(cr);
    }
}

/* The servo settings as circles (cs_sim_draw_pen_t), radius r. */
static void svg_marks(FILE *f, const sample_t *s, size_t n, double r, double lw)
{
    fprintf(f, "<g class=\"pen-marks\">\n");
    for (size_t k = 0; k < n; k++)
        if (s[k].mark > 0)
            fprintf(f, "<circle class=\"pen-down\" cx=\"%.4f\" cy=\"%.4f\" r=\"%.4f\" "
                       "fill=\"#1a9641\"/>\n", s[k].x, s[k].y, r);
        else if (s[k].mark < 0)
            fprintf(f, "<circle class=\"pen-up\" cx=\"%.4f\" cy=\"%.4f\" r=\"%.4f\" "
                       "fill=\"none\" stroke=\"#d7191c\" stroke-width=\"%.4f\"/>\n",
                    s[k].x, s[k].y, r, lw);
    fprintf(f, "</g>\n");
}

/* Travel first (underneath): runs of travel samples that move, as dashed grey polylines. */
static void svg_travel(FILE *f, const sample_t *s, size_t n, double lw)
{
    for (size_t k = 1; k < n;) {
        if (!s[k].travel) {
            k++;
            continue;
        }
        bool moves;
        size_t end = travel_run(s, n, k, &moves);
        if (moves) {
            fprintf(f,
                    "<polyline class=\"travel\" fill=\"none\" stroke=\"#999999\" "
                    "stroke-width=\"%.4f\" stroke-dasharray=\"%.4f %.4f\" points=\"%.4f,%.4f",
                    lw, 6 * lw, 4 * lw, s[k - 1].x, s[k - 1].y);
            for (; k < end; k++)
                fprintf(f, " %.4f,%.4f", s[k].x, s[k].y);
            fprintf(f, "\"/>\n");
        }
        k = end;
    }
}

int cs_sim_draw_svg_view(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex,
                         const cs_sim_ref_t *ref, const cs_sim_view_t *view)
{
    return cs_sim_draw_svg_pen(file, m, ex, ref, view, NULL);
}

int cs_sim_draw_svg_pen(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex,
                        const cs_sim_ref_t *ref, const cs_sim_view_t *view,
                        const cs_sim_draw_pen_t *pen)
{
    size_t n;
    double lo[2], hi[2];
    sample_t *s = exec_samples(m, ex, view, &n);
    if (s == NULL)
        return -1;
    bool travel = pen_classify(s, n, pen, classify(s, n, ref));
    double vmax = top_speed(s, n);
    FILE *f = fopen(file, "w");
    if (f == NULL) {
        free(s);
        return -1;
    }
    legend_t lg;
    bounds(m, s, n, ref, view, lo, hi, &lg);
    double w = hi[0] - lo[0], h = hi[1] - lo[1], lw = fmax(w, h) / 1500;
    fprintf(f,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.3fmm\" height=\"%.3fmm\" "
            "viewBox=\"%.4f %.4f %.4f %.4f\">\n"
            "<title>curvestep-sim, view %s: exact geometry (black), executed path coloured by "
            "speed (blue slow .. red %.1f mm/s)%s</title>\n"
            "<rect x=\"%.4f\" y=\"%.4f\" width=\"%.4f\" height=\"%.4f\" fill=\"white\"/>\n",
            w, h, lo[0], lo[1], w, h, view->name, vmax, travel ? ", travel moves dashed grey" : "",
            lo[0], lo[1], w, h);
    double blo[2], bhi[2];
    if (bed_box(m, view, blo, bhi))
        fprintf(f,
                "<rect class=\"bed\" x=\"%.4f\" y=\"%.4f\" width=\"%.4f\" height=\"%.4f\" "
                "fill=\"none\" stroke=\"#bbbbbb\" stroke-width=\"%.4f\"/>\n",
                blo[0], blo[1], bhi[0] - blo[0], bhi[1] - blo[1], 2 * lw);
    svg_legend(f, &lg, vmax, 2 * lw, travel, m, view);
    svg_travel(f, s, n, lw);
    for (size_t k = 1; k < n; k++) {
        if (s[k].travel || (s[k].x == s[k - 1].x && s[k].y == s[k - 1].y))
            continue;
        double rgb[3];
        speed_rgb(vmax > 0 ? s[k].v / vmax : 0, rgb);
        fprintf(f,
                "<line x1=\"%.4f\" y1=\"%.4f\" x2=\"%.4f\" y2=\"%.4f\" stroke=\"#%02x%02x%02x\" "
                "stroke-width=\"%.4f\" stroke-linecap=\"round\"/>\n",
                s[k - 1].x, s[k - 1].y, s[k].x, s[k].y, (int)(rgb[0] * 255), (int)(rgb[1] * 255),
                (int)(rgb[2] * 255), 4 * lw);
    }
    if (ref) {
        fprintf(f, "<g class=\"reference\" fill=\"none\" stroke=\"black\" stroke-width=\"%.4f\">\n",
                lw);
        ref_runs(ref, svg_ref_run, f, view);
        fprintf(f, "</g>\n");
    }
    svg_marks(f, s, n, 5 * lw, lw);
    svg_control(f, ex, s, n, view, lw);
    fprintf(f, "</svg>\n");
    free(s);
    return fclose(f) == 0 ? 0 : -1;
}

static void png_ref_run(void *ctx, const cs_sim_ref_t *ref, size_t b, size_t n,
                        const cs_sim_view_t *view)
{
    cairo_t *cr = ctx;
    for (size_t k = b; k < b + n; k++) {
        double q[2];
        cs_sim_view_project(view, &ref->xyz[3 * k], q);
        if (k == b)
            cairo_move_to(cr, q[0], q[1]);
        else
            cairo_line_to(cr, q[0], q[1]);
    }
    cairo_stroke(cr);
}

/* The PNG's page outline and legend (as svg_legend). */
static void png_bed_legend(cairo_t *cr, const legend_t *lg, double vmax, double scale, bool travel,
                           const cs_machine_t *m, const cs_sim_view_t *view)
{
    double blo[2], bhi[2], y = lg->y + 1.5 * lg->u, bar = lg->w * 0.3, x = legend_x(lg, 0);
    char t[96];
    cairo_set_line_width(cr, 2.0 / scale);
    cairo_set_source_rgb(cr, 0.73, 0.73, 0.73);
    bool bed = bed_box(m, view, blo, bhi);
    if (bed) {
        cairo_rectangle(cr, blo[0], blo[1], bhi[0] - blo[0], bhi[1] - blo[1]);
        cairo_stroke(cr);
    }
    for (int k = 0; k < 20; k++) {
        double rgb[3];
        speed_rgb((k + 0.5) / 20, rgb);
        cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
        cairo_rectangle(cr, x + bar * k / 20, y - lg->u * 0.4, bar / 20 + 1 / scale, lg->u * 0.8);
        cairo_fill(cr);
    }
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, lg->u);
    cairo_set_source_rgb(cr, 0, 0, 0);
    snprintf(t, sizeof t, "speed 0 .. %.1f mm/s (drawing)", vmax);
    cairo_move_to(cr, x, y + 1.3 * lg->u);
    cairo_show_text(cr, t);
    for (int item = travel ? 1 : 2; item <= 2; item++) {
        x = legend_x(lg, item);
        double dash[2] = {6.0 / scale, 4.0 / scale};
        cairo_set_dash(cr, dash, item == 1 ? 2 : 0, 0);
        cairo_set_source_rgb(cr, item == 1 ? 0.6 : 0, item == 1 ? 0.6 : 0, item == 1 ? 0.6 : 0);
        cairo_move_to(cr, x, y);
        cairo_line_to(cr, x + 3 * lg->u, y);
        cairo_stroke(cr);
        cairo_set_dash(cr, NULL, 0, 0);
        cairo_set_source_rgb(cr, 0, 0, 0);
        cairo_move_to(cr, x + 3.5 * lg->u, y + 0.35 * lg->u);
        cairo_show_text(cr, item == 1 ? "pen-up travel" : "exact geometry");
    }
    if (bed) {
        snprintf(t, sizeof t, "grey box: the machine's x y travel; x right, y %s",
                 view->y_down ? "down" : "up");
        cairo_move_to(cr, legend_x(lg, 1), y + 1.3 * lg->u);
        cairo_show_text(cr, t);
    }
}

/* The servo settings as circles, as svg_marks. */
static void png_marks(cairo_t *cr, const sample_t *s, size_t n, double r, double lw)
{
    cairo_set_line_width(cr, lw);
    for (size_t k = 0; k < n; k++) {
        if (s[k].mark == 0)
            continue;
        cairo_new_sub_path(cr);
        cairo_arc(cr, s[k].x, s[k].y, r, 0, 2 * M_PI);
        if (s[k].mark > 0) {
            cairo_set_source_rgb(cr, 0.10, 0.59, 0.25);
            cairo_fill(cr);
        } else {
            cairo_set_source_rgb(cr, 0.84, 0.10, 0.11);
            cairo_stroke(cr);
        }
    }
}

int cs_sim_draw_png_view(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex,
                         const cs_sim_ref_t *ref, const cs_sim_view_t *view, int width_px)
{
    return cs_sim_draw_png_pen(file, m, ex, ref, view, width_px, NULL);
}

int cs_sim_draw_png_pen(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex,
                        const cs_sim_ref_t *ref, const cs_sim_view_t *view, int width_px,
                        const cs_sim_draw_pen_t *pen)
{
    size_t n;
    double lo[2], hi[2];
    sample_t *s = exec_samples(m, ex, view, &n);
    if (s == NULL)
        return -1;
    bool travel = pen_classify(s, n, pen, classify(s, n, ref));
    double vmax = top_speed(s, n);
    legend_t lg;
    bounds(m, s, n, ref, view, lo, hi, &lg);
    double w = hi[0] - lo[0], h = hi[1] - lo[1];
    double scale = width_px / w;
    int height_px = (int)ceil(h * scale);
    if (height_px < 1)
        height_px = 1;
    if (height_px > 8192)
        height_px = 8192;
    cairo_surface_t *sf = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width_px, height_px);
    cairo_t *cr = cairo_create(sf);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    cairo_scale(cr, scale, scale);
    cairo_translate(cr, -lo[0], -lo[1]);
    cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
    png_bed_legend(cr, &lg, vmax, scale, travel, m, view);
    /* Travel: thin dashed grey, underneath. */
    double dash[2] = {6.0 / scale, 4.0 / scale};
    cairo_set_dash(cr, dash, 2, 0);
    cairo_set_line_width(cr, 1.0 / scale);
    cairo_set_source_rgb(cr, 0.6, 0.6, 0.6);
    for (size_t k = 1; k < n;) {
        if (!s[k].travel) {
            k++;
            continue;
        }
        bool moves;
        size_t end = travel_run(s, n, k, &moves);
        cairo_move_to(cr, s[k - 1].x, s[k - 1].y);
        for (; k < end; k++)
            cairo_line_to(cr, s[k].x, s[k].y);
        if (moves)
            cairo_stroke(cr);
        else
            cairo_new_path(cr);
    }
    cairo_set_dash(cr, NULL, 0, 0);
    cairo_set_line_width(cr, (view->y_down ? 3.0 : 2.0) / scale);
    for (size_t k = 1; k < n; k++) {
        if (s[k].travel || (s[k].x == s[k - 1].x && s[k].y == s[k - 1].y))
            continue;
        double rgb[3];
        speed_rgb(vmax > 0 ? s[k].v / vmax : 0, rgb);
        cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
        cairo_move_to(cr, s[k - 1].x, s[k - 1].y);
        cairo_line_to(cr, s[k].x, s[k].y);
        cairo_stroke(cr);
    }
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 0.8 / scale);
    ref_runs(ref, png_ref_run, cr, view);
    png_marks(cr, s, n, 5.0 / scale, 1.5 / scale);
    png_control(cr, ex, s, n, view, scale);
    cairo_destroy(cr);
    cairo_status_t st = cairo_surface_write_to_png(sf, file);
    cairo_surface_destroy(sf);
    free(s);
    if (st != CAIRO_STATUS_SUCCESS) {
        fprintf(stderr, "%s: %s\n", file, cairo_status_to_string(st));
        return -1;
    }
    return 0;
}

int cs_sim_draw_svg(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex,
                    const cs_sim_ref_t *ref)
{
    cs_sim_view_t v;
    cs_sim_view_default(&v);
    return cs_sim_draw_svg_view(file, m, ex, ref, &v);
}

int cs_sim_draw_png(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex,
                    const cs_sim_ref_t *ref, int width_px)
{
    cs_sim_view_t v;
    cs_sim_view_default(&v);
    return cs_sim_draw_png_view(file, m, ex, ref, &v, width_px);
}

int cs_sim_write_trace(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex)
{
    FILE *f = fopen(file, "w");
    if (f == NULL)
        return -1;
    double spm[3];
    for (unsigned i = 0; i < 3; i++)
        spm[i] = (double)m->axis[i].steps_per_mm / CS_MOTION_ONE;
    static const char names[] = "xyza";
    int64_t pos[CS_AXES] = {0, 0, 0, 0};
    fprintf(f, "t_s,axis,dir,x_mm,y_mm,z_mm\n");
    size_t sp = 0;
    for (size_t e = 0; e <= ex->n; e++) {
        /* the spindle / laser settings in time order among the edges: axis "s", the duty
         * (1/1000, 0 when off) in the dir column, the position where it was set */
        for (; sp < ex->nspins && (e == ex->n || ex->spins[sp].t <= ex->edges[e].t); sp++)
            fprintf(f, "%.6f,s,%u,%.5f,%.5f,%.5f\n", (double)ex->spins[sp].t / m->tick_hz,
                    ex->spins[sp].mode != 0 ? (unsigned)ex->spins[sp].duty : 0u,
                    (double)pos[0] / spm[0], (double)pos[1] / spm[1], (double)pos[2] / spm[2]);
        if (e == ex->n)
            break;
        const port_posix_edge_t *d = &ex->edges[e];
        pos[d->axis] += d->dir;
        fprintf(f, "%.6f,%c,%d,%.5f,%.5f,%.5f\n", (double)d->t / m->tick_hz,
                names[d->axis < 4 ? d->axis : 0], d->dir, (double)pos[0] / spm[0],
                (double)pos[1] / spm[1], (double)pos[2] / spm[2]);
    }
    return fclose(f) == 0 ? 0 : -1;
}
