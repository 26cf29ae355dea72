/* cs_svgout: the picture of a flattening (see cs_svgout.h). Sizes of strokes, dots and text are
 * fractions of the drawing's extent, so a 2 mm glyph and a 400 mm sheet both read well. */
#include "cs_svgout.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include "cs_conv.h"

/* Samples per element for curves SVG cannot write exactly (rational, degree > 3). */
#define SVGOUT_DENSE 64
/* Nominal picture size in pixels along the drawing's larger side. */
#define SVGOUT_PX 900.0

#define COLOR_CURVE "#3a7bd5"
#define COLOR_CHORD "#d62728"

void cs_svgout_opts_init(cs_svgout_opts_t *o)
{
    memset(o, 0, sizeof *o);
    o->max_dev_mm = -1.0;
}

static void grow_box(double box[4], bool *any, double x, double y)
{
    if (!*any) {
        box[0] = box[2] = x;
        box[1] = box[3] = y;
        *any = true;
        return;
    }
    box[0] = fmin(box[0], x);
    box[1] = fmin(box[1], y);
    box[2] = fmax(box[2], x);
    box[3] = fmax(box[3], y);
}

static void put_text(FILE *f, const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '&':
            fputs("&amp;", f);
            break;
        case '<':
            fputs("&lt;", f);
            break;
        case '>':
            fputs("&gt;", f);
            break;
        case '"':
            fputs("&quot;", f);
            break;
        default:
            fputc(*s, f);
        }
    }
}

static double pmm(cs_pos_t v)
{
    return cs_conv_pos_to_mm(v);
}

/* Largest 1, 2 or 5 times a power of ten not above limit. */
static double nice_length(double limit)
{
    double p = pow(10.0, floor(log10(limit)));
    if (5.0 * p <= limit)
        return 5.0 * p;
    if (2.0 * p <= limit)
        return 2.0 * p;
    return p;
}

static void curve_data(FILE *f, const cs_path_t *c)
{
    bool have_end = false;
    cs_vec3_t end = {0, 0, 0};
    unsigned sub = 0;
    for (size_t i = 0; i < c->n; i++) {
        const cs_path_elem_t *e = &c->elems[i];
        const cs_bezier_t *b = &e->curve;
        if (!have_end || e->subpath != sub || b->p[0].x != end.x || b->p[0].y != end.y)
            fprintf(f, "M%.6f %.6f", pmm(b->p[0].x), pmm(b->p[0].y));
        if (!b->rational && b->degree >= 1 && b->degree <= 3) {
            fputs(b->degree == 1 ? "L" : b->degree == 2 ? "Q" : "C", f);
            for (unsigned k = 1; k <= b->degree; k++)
                fprintf(f, "%s%.6f %.6f", k > 1 ? " " : "", pmm(b->p[k].x), pmm(b->p[k].y));
        } else {
            fputs("L", f);
            for (int k = 1; k <= SVGOUT_DENSE; k++) {
                double q[3];
                cs_path_eval_mm(b, (double)k / SVGOUT_DENSE, q);
                /* The last sample is P_n itself, written exactly. */
                if (k == SVGOUT_DENSE) {
                    q[0] = pmm(b->p[b->degree].x);
                    q[1] = pmm(b->p[b->degree].y);
                }
                fprintf(f, "%s%.6f %.6f", k > 1 ? " " : "", q[0], q[1]);
            }
        }
        end = b->p[b->degree];
        sub = e->subpath;
        have_end = true;
        fputc(i + 1 < c->n ? '\n' : '"', f);
    }
}

/* Extent of what is drawn: the curves themselves (sampled, tighter than the control polygon)
 * and every chord vertex. false when there is nothing (box: 0..10 mm then). */
static bool extent(const cs_path_t *curves, const cs_path_poly_t *chords, double box[4])
{
    bool any = false;
    box[0] = box[1] = box[2] = box[3] = 0;
    for (size_t i = 0; curves && i < curves->n; i++) {
        for (int k = 0; k <= 32; k++) {
            double q[3];
            cs_path_eval_mm(&curves->elems[i].curve, k / 32.0, q);
            grow_box(box, &any, q[0], q[1]);
        }
    }
    for (size_t i = 0; chords && i < chords->n; i++)
        grow_box(box, &any, chords->pts[i].x, chords->pts[i].y);
    if (!any) {
        box[0] = box[1] = 0.0;
        box[2] = box[3] = 10.0;
    }
    return any;
}

/* The exact curves (wide, pale) and the chords with their vertices; u: one pixel in mm. */
static void draw_body(FILE *f, const cs_path_t *curves, const cs_path_poly_t *chords, double u)
{
    size_t nv = chords ? chords->n : 0;
    if (curves && curves->n > 0) {
        fprintf(f,
                "<path id=\"curves\" fill=\"none\" stroke=\"" COLOR_CURVE
                "\" stroke-width=\"%.6g\" "
                "stroke-opacity=\"0.5\" stroke-linecap=\"round\" stroke-linejoin=\"round\" d=\"",
                6.0 * u);
        curve_data(f, curves);
        fprintf(f, "/>\n");
    }
    if (nv == 0)
        return;
    fprintf(f,
            "<g id=\"chords\" fill=\"none\" stroke=\"" COLOR_CHORD "\" stroke-width=\"%.6g\" "
            "stroke-linejoin=\"round\">\n",
            1.0 * u);
    for (size_t l = 0; l < chords->nlines; l++) {
        size_t s = chords->starts[l], n = cs_path_poly_len(chords, l);
        fprintf(f, "<polyline points=\"");
        for (size_t k = 0; k < n; k++)
            fprintf(f, "%s%.6f,%.6f", k ? " " : "", chords->pts[s + k].x, chords->pts[s + k].y);
        fprintf(f, "\"/>\n");
    }
    fprintf(f, "</g>\n<g id=\"vertices\" fill=\"" COLOR_CHORD "\">\n");
    double r = (nv > 20000 ? 1.0 : 1.6) * u;
    for (size_t k = 0; k < nv; k++)
        fprintf(f, "<circle cx=\"%.6f\" cy=\"%.6f\" r=\"%.6g\"/>\n", chords->pts[k].x,
                chords->pts[k].y, r);
    fprintf(f, "</g>\n");
}

/* The legend's settings line: tolerance, method, measured deviation. */
static void legend_settings(FILE *f, const cs_svgout_opts_t *o, double lx, double ly)
{
    fprintf(f, "<text x=\"%.6f\" y=\"%.6f\">", lx, ly);
    const char *sep = "";
    if (o->tol_mm > 0.0) {
        fprintf(f, "tolerance %.6g mm", o->tol_mm);
        sep = ", ";
    }
    if (o->method) {
        fprintf(f, "%smethod ", sep);
        put_text(f, o->method);
        sep = ", ";
    }
    if (o->max_dev_mm >= 0.0)
        fprintf(f, "%smax deviation %.5g mm (measured)", sep, o->max_dev_mm);
    fprintf(f, "</text>\n");
}

/* Legend under the drawing from (lx, ly): title, the two samples with their counts, the
 * settings, a scale bar (a round length about a quarter of span, with end ticks). */
static void draw_legend(FILE *f, const cs_svgout_opts_t *o, const cs_path_t *curves,
                        const cs_path_poly_t *chords, double lx, double ly, double line,
                        double span, double u)
{
    size_t nelem = curves ? curves->n : 0, nv = chords ? chords->n : 0;
    fprintf(f, "<g id=\"legend\" font-family=\"sans-serif\" font-size=\"%.6g\" fill=\"#222\">\n",
            13.0 * u);
    if (o->title) {
        fprintf(f, "<text x=\"%.6f\" y=\"%.6f\" font-weight=\"bold\">", lx, ly);
        put_text(f, o->title);
        fprintf(f, "</text>\n");
        ly += line;
    }
    fprintf(f,
            "<line x1=\"%.6f\" y1=\"%.6f\" x2=\"%.6f\" y2=\"%.6f\" stroke=\"" COLOR_CURVE
            "\" stroke-opacity=\"0.5\" stroke-width=\"%.6g\"/>\n",
            lx, ly - 4.0 * u, lx + 24.0 * u, ly - 4.0 * u, 6.0 * u);
    fprintf(f, "<text x=\"%.6f\" y=\"%.6f\">exact curves: %zu element%s</text>\n", lx + 32.0 * u,
            ly, nelem, nelem == 1 ? "" : "s");
    ly += line;
    fprintf(
        f,
        "<line x1=\"%.6f\" y1=\"%.6f\" x2=\"%.6f\" y2=\"%.6f\" stroke=\"" COLOR_CHORD
        "\" stroke-width=\"%.6g\"/><circle cx=\"%.6f\" cy=\"%.6f\" r=\"%.6g\" fill=\"" COLOR_CHORD
        "\"/>\n",
        lx, ly - 4.0 * u, lx + 24.0 * u, ly - 4.0 * u, 1.0 * u, lx + 12.0 * u, ly - 4.0 * u,
        1.6 * u);
    size_t nchords = chords && chords->n >= chords->nlines ? chords->n - chords->nlines : 0;
    fprintf(f, "<text x=\"%.6f\" y=\"%.6f\">chords: %zu (%zu vertices, %zu polyline%s)</text>\n",
            lx + 32.0 * u, ly, nchords, nv, chords ? chords->nlines : 0,
            chords && chords->nlines == 1 ? "" : "s");
    ly += line;
    legend_settings(f, o, lx, ly);
    ly += line;
    double bar = nice_length(span / 4.0);
    double by = ly + 10.0 * u, tick = 5.0 * u;
    fprintf(f,
            "<path d=\"M%.6f %.6f v%.6g h%.6g v%.6g\" fill=\"none\" stroke=\"#222\" "
            "stroke-width=\"%.6g\"/>\n",
            lx, by - tick, tick, bar, -tick, 1.5 * u);
    fprintf(f, "<text x=\"%.6f\" y=\"%.6f\">%g mm</text>\n", lx + bar + 8.0 * u, by, bar);
    fprintf(f, "</g>\n");
}

cs_err_t cs_svgout_fprint(FILE *f, const cs_path_t *curves, const cs_path_poly_t *chords,
                          const cs_svgout_opts_t *o)
{
    cs_svgout_opts_t defaults;
    if (!o) {
        cs_svgout_opts_init(&defaults);
        o = &defaults;
    }
    double box[4];
    bool empty = !extent(curves, chords, box);
    double w = box[2] - box[0], h = box[3] - box[1];
    double span = fmax(fmax(w, h), 1e-3);
    double u = span / SVGOUT_PX; /* one nominal pixel, in mm */
    double margin = 24.0 * u, line = 17.0 * u;
    int nlines = 3 + (o->title ? 1 : 0);
    double legend = nlines * line + 40.0 * u;
    double vx = box[0] - margin, vy = box[1] - margin;
    double vw = fmax(w + 2.0 * margin, 520.0 * u), vh = h + 2.0 * margin + legend;

    fprintf(f, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    fprintf(f,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"%.0f\" "
            "height=\"%.0f\" viewBox=\"%.6f %.6f %.6f %.6f\">\n",
            vw / u, vh / u, vx, vy, vw, vh);
    fprintf(f, "<title>curvestep flatten");
    if (o->title) {
        fputs(": ", f);
        put_text(f, o->title);
    }
    fprintf(f, "</title>\n");
    fprintf(f, "<rect x=\"%.6f\" y=\"%.6f\" width=\"%.6f\" height=\"%.6f\" fill=\"white\"/>\n", vx,
            vy, vw, vh);
    /* The machine's frame is y-up (SVG pages are turned when read, docs/inputs.md "Axes"), and
     * an SVG picture is y-down: the drawing is mirrored about its box's middle, so it looks as
     * on the bed seen from above (and an SVG input as in a browser); the legend is not. */
    fprintf(f, "<g id=\"drawing\" transform=\"matrix(1 0 0 -1 0 %.6f)\">\n", box[1] + box[3]);
    draw_body(f, curves, chords, u);
    fprintf(f, "</g>\n");
    draw_legend(f, o, curves, chords, box[0], box[3] + margin + line, line, span, u);
    fprintf(f, "</svg>\n");
    if (ferror(f))
        return CS_ERR_IO;
    return empty ? CS_ERR_EMPTY : CS_OK;
}

cs_err_t cs_svgout_write(const char *filename, const cs_path_t *curves,
                         const cs_path_poly_t *chords, const cs_svgout_opts_t *o,
                         cs_path_diag_t *diag)
{
    cs_path_loc_t loc = {filename, 0, 0};
    FILE *f = fopen(filename, "w");
    if (!f)
        return cs_path_diag_set(diag, CS_ERR_IO, loc, "cannot write: %s", strerror(errno));
    cs_err_t e = cs_svgout_fprint(f, curves, chords, o);
    if (fclose(f) != 0 && e == CS_OK)
        e = CS_ERR_IO;
    if (e == CS_ERR_IO)
        return cs_path_diag_set(diag, CS_ERR_IO, loc, "write error: %s", strerror(errno));
    return e;
}
