/* cs_sim_draw: SVG, PNG (cairo) and CSV views of a run. */
#include "cs_sim_draw.h"

#include <cairo.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct {
    double x, y, v; /* mm, and speed over the sample before it (mm/s) */
} sample_t;

/* The executed path sampled every dt ticks (about 20000 samples at most, >= 1 ms apart). */
static sample_t *exec_samples(const cs_machine_t *m, const cs_sim_exec_t *ex, size_t *n,
                              double *vmax)
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
    *vmax = 0;
    for (uint64_t t = 0; k < cap; t += dt) {
        while (e < ex->n && ex->edges[e].t <= t) {
            pos[ex->edges[e].axis] += ex->edges[e].dir;
            e++;
        }
        s[k].x = (double)pos[0] / spm[0];
        s[k].y = (double)pos[1] / spm[1];
        s[k].v = 0;
        if (k > 0) {
            double dx = s[k].x - s[k - 1].x, dy = s[k].y - s[k - 1].y;
            double z0 = 0; /* z speed ignored in the picture (pen up/down) */
            s[k].v = sqrt(dx * dx + dy * dy + z0) / ((double)dt / m->tick_hz);
            if (s[k].v > *vmax)
                *vmax = s[k].v;
        }
        k++;
        if (t > ex->end_tick)
            break;
    }
    *n = k;
    return s;
}

static void bounds(const sample_t *s, size_t n, const cs_sim_ref_t *ref, double lo[2], double hi[2])
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
        lo[0] = fmin(lo[0], ref->xyz[3 * k]);
        lo[1] = fmin(lo[1], ref->xyz[3 * k + 1]);
        hi[0] = fmax(hi[0], ref->xyz[3 * k]);
        hi[1] = fmax(hi[1], ref->xyz[3 * k + 1]);
    }
    if (!(lo[0] <= hi[0])) {
        lo[0] = lo[1] = 0;
        hi[0] = hi[1] = 1;
    }
    double pad = fmax(hi[0] - lo[0], hi[1] - lo[1]) * 0.03 + 1;
    lo[0] -= pad;
    lo[1] -= pad;
    hi[0] += pad;
    hi[1] += pad;
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

int cs_sim_draw_svg(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex,
                    const cs_sim_ref_t *ref)
{
    size_t n;
    double vmax, lo[2], hi[2];
    sample_t *s = exec_samples(m, ex, &n, &vmax);
    if (s == NULL)
        return -1;
    FILE *f = fopen(file, "w");
    if (f == NULL) {
        free(s);
        return -1;
    }
    bounds(s, n, ref, lo, hi);
    double w = hi[0] - lo[0], h = hi[1] - lo[1], lw = fmax(w, h) / 1500;
    fprintf(f,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.3fmm\" height=\"%.3fmm\" "
            "viewBox=\"%.4f %.4f %.4f %.4f\">\n"
            "<title>curvestep-sim: exact geometry (black) and executed path coloured by speed "
            "(blue slow .. red %.1f mm/s)</title>\n"
            "<rect x=\"%.4f\" y=\"%.4f\" width=\"%.4f\" height=\"%.4f\" fill=\"white\"/>\n",
            w, h, lo[0], lo[1], w, h, vmax, lo[0], lo[1], w, h);
    for (size_t k = 1; k < n; k++) {
        if (s[k].x == s[k - 1].x && s[k].y == s[k - 1].y)
            continue;
        double rgb[3];
        speed_rgb(vmax > 0 ? s[k].v / vmax : 0, rgb);
        fprintf(f,
                "<line x1=\"%.4f\" y1=\"%.4f\" x2=\"%.4f\" y2=\"%.4f\" stroke=\"#%02x%02x%02x\" "
                "stroke-width=\"%.4f\" stroke-linecap=\"round\"/>\n",
                s[k - 1].x, s[k - 1].y, s[k].x, s[k].y, (int)(rgb[0] * 255), (int)(rgb[1] * 255),
                (int)(rgb[2] * 255), 4 * lw);
    }
    for (size_t li = 0; ref && li < ref->nlines; li++) {
        size_t b = ref->starts[li], e = li + 1 < ref->nlines ? ref->starts[li + 1] : ref->n;
        fprintf(f, "<polyline fill=\"none\" stroke=\"black\" stroke-width=\"%.4f\" points=\"", lw);
        for (size_t k = b; k < e; k++)
            fprintf(f, "%.4f,%.4f ", ref->xyz[3 * k], ref->xyz[3 * k + 1]);
        fprintf(f, "\"/>\n");
    }
    fprintf(f, "</svg>\n");
    free(s);
    return fclose(f) == 0 ? 0 : -1;
}

int cs_sim_draw_png(const char *file, const cs_machine_t *m, const cs_sim_exec_t *ex,
                    const cs_sim_ref_t *ref, int width_px)
{
    size_t n;
    double vmax, lo[2], hi[2];
    sample_t *s = exec_samples(m, ex, &n, &vmax);
    if (s == NULL)
        return -1;
    bounds(s, n, ref, lo, hi);
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
    cairo_set_line_width(cr, 3.0 / scale);
    for (size_t k = 1; k < n; k++) {
        if (s[k].x == s[k - 1].x && s[k].y == s[k - 1].y)
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
    for (size_t li = 0; ref && li < ref->nlines; li++) {
        size_t b = ref->starts[li], e = li + 1 < ref->nlines ? ref->starts[li + 1] : ref->n;
        for (size_t k = b; k < e; k++) {
            if (k == b)
                cairo_move_to(cr, ref->xyz[3 * k], ref->xyz[3 * k + 1]);
            else
                cairo_line_to(cr, ref->xyz[3 * k], ref->xyz[3 * k + 1]);
        }
        cairo_stroke(cr);
    }
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
    for (size_t e = 0; e < ex->n; e++) {
        const port_posix_edge_t *d = &ex->edges[e];
        pos[d->axis] += d->dir;
        fprintf(f, "%.6f,%c,%d,%.5f,%.5f,%.5f\n", (double)d->t / m->tick_hz,
                names[d->axis < 4 ? d->axis : 0], d->dir, (double)pos[0] / spm[0],
                (double)pos[1] / spm[1], (double)pos[2] / spm[2]);
    }
    return fclose(f) == 0 ? 0 : -1;
}
