/* cs_layout: the layout options' affine map and its exact application (see cs_layout.h). */
#include "cs_layout.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cs_conv.h"

void cs_layout_opts_init(cs_layout_opts_t *o)
{
    memset(o, 0, sizeof *o);
    o->scale = 1.0;
}

bool cs_layout_is_identity(const cs_layout_opts_t *o, const cs_path_t *p)
{
    return o->scale == 1.0 && !o->fit && o->page_w_mm == 0 && o->tx_mm == 0 && o->ty_mm == 0 &&
           o->rotate_deg == 0 && !o->flip_y && !p->page_y_down;
}

bool cs_layout_parse_page(const char *s, double *w_mm, double *h_mm)
{
    /* ISO 216 A sizes and ANSI letter (8.5 x 11 in), portrait */
    static const struct {
        const char *name;
        double w, h;
    } pages[] = {{"A3", 297, 420}, {"A4", 210, 297}, {"A5", 148, 210}, {"letter", 215.9, 279.4}};
    for (size_t i = 0; i < sizeof pages / sizeof pages[0]; i++)
        if (strcasecmp(s, pages[i].name) == 0) {
            *w_mm = pages[i].w;
            *h_mm = pages[i].h;
            return true;
        }
    char *end;
    double w = strtod(s, &end);
    if (end == s || (*end != 'x' && *end != 'X'))
        return false;
    const char *hs = end + 1;
    double h = strtod(hs, &end);
    if (end == hs || (*end != '\0' && strcmp(end, "mm") != 0))
        return false;
    if (!(w > 0 && w <= CS_POS_LIMIT_MM && h > 0 && h <= CS_POS_LIMIT_MM))
        return false;
    *w_mm = w;
    *h_mm = h;
    return true;
}

bool cs_layout_bbox(const cs_path_t *p, double min[2], double max[2])
{
    bool any = false;
    for (size_t i = 0; i < p->n; i++) {
        cs_vec3_t lo, hi;
        if (cs_bezier_bbox(&p->elems[i].curve, &lo, &hi) != CS_OK)
            continue; /* a curve the reader accepted always has a box */
        double l[2] = {cs_conv_pos_to_mm(lo.x), cs_conv_pos_to_mm(lo.y)};
        double h[2] = {cs_conv_pos_to_mm(hi.x), cs_conv_pos_to_mm(hi.y)};
        for (int a = 0; a < 2; a++) {
            min[a] = any && min[a] < l[a] ? min[a] : l[a];
            max[a] = any && max[a] > h[a] ? max[a] : h[a];
        }
        any = true;
    }
    return any;
}

/* Box of the image of the box min..max under the linear part of m plus translation. */
static void map_box(const cs_path_affine_t *m, const double min[2], const double max[2],
                    double omin[2], double omax[2])
{
    for (int k = 0; k < 4; k++) {
        double x, y;
        cs_path_affine_point(m, (k & 1) ? max[0] : min[0], (k & 2) ? max[1] : min[1], &x, &y);
        omin[0] = k && omin[0] < x ? omin[0] : x;
        omin[1] = k && omin[1] < y ? omin[1] : y;
        omax[0] = k && omax[0] > x ? omax[0] : x;
        omax[1] = k && omax[1] > y ? omax[1] : y;
    }
}

static cs_path_affine_t translate(double x, double y)
{
    cs_path_affine_t t = cs_path_affine_identity();
    t.e = x;
    t.f = y;
    return t;
}

/* Flip about the box's middle, then rotate keeping the box's lower-left corner. */
static cs_path_affine_t orient(const cs_layout_opts_t *o, const double min[2], const double max[2])
{
    cs_path_affine_t m = cs_path_affine_identity();
    if (o->flip_y) {
        m.d = -1.0; /* y' = (min + max) - y */
        m.f = min[1] + max[1];
    }
    /* rotation by q quarter turns counter-clockwise: exact cosines and sines */
    static const double cs[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
    int q = (o->rotate_deg / 90) & 3;
    cs_path_affine_t r = cs_path_affine_identity();
    r.a = cs[q][0];
    r.b = cs[q][1];
    r.c = -cs[q][1];
    r.d = cs[q][0];
    m = cs_path_affine_mul(r, m);
    double bmin[2], bmax[2];
    map_box(&m, min, max, bmin, bmax);
    return cs_path_affine_mul(translate(min[0] - bmin[0], min[1] - bmin[1]), m);
}

cs_err_t cs_layout_map(const cs_layout_opts_t *o, const double min[2], const double max[2],
                       const cs_layout_area_t *area, cs_path_affine_t *out)
{
    cs_path_affine_t m = orient(o, min, max);
    double bmin[2], bmax[2];
    map_box(&m, min, max, bmin, bmax);
    cs_path_affine_t s = cs_path_affine_identity();
    if (o->fit) {
        double aw = area->max[0] - area->min[0] - 2 * o->margin_mm;
        double ah = area->max[1] - area->min[1] - 2 * o->margin_mm;
        double bw = bmax[0] - bmin[0], bh = bmax[1] - bmin[1];
        if (!(aw > 0 && ah > 0) || !(bw > 0 || bh > 0))
            return CS_ERR_ARG;
        /* keep aspect: the larger factor that fits both sides (a line fits by its length) */
        double k = bw > 0 && bh > 0 ? fmin(aw / bw, ah / bh) : bw > 0 ? aw / bw : ah / bh;
        s.a = s.d = k;
        /* centre: the box's middle onto the area's middle */
        s.e = (area->min[0] + area->max[0]) / 2 - k * (bmin[0] + bmax[0]) / 2;
        s.f = (area->min[1] + area->max[1]) / 2 - k * (bmin[1] + bmax[1]) / 2;
    } else {
        s.a = s.d = o->scale;
    }
    m = cs_path_affine_mul(s, m);
    *out = cs_path_affine_mul(translate(o->tx_mm, o->ty_mm), m);
    return CS_OK;
}

cs_err_t cs_layout_transform(cs_path_t *p, const cs_path_affine_t *m, cs_path_diag_t *diag)
{
    for (size_t i = 0; i < p->n; i++) {
        cs_bezier_t *c = &p->elems[i].curve;
        for (unsigned k = 0; k <= c->degree && k < CS_BEZIER_MAX_POINTS; k++) {
            double x, y;
            cs_path_affine_point(m, cs_conv_pos_to_mm(c->p[k].x), cs_conv_pos_to_mm(c->p[k].y), &x,
                                 &y);
            if (cs_conv_mm_to_pos(x, &c->p[k].x) != CS_OK ||
                cs_conv_mm_to_pos(y, &c->p[k].y) != CS_OK)
                return cs_path_diag_set(diag, CS_ERR_RANGE, p->elems[i].loc,
                                        "after layout the point (%.3f, %.3f) mm is outside "
                                        "+/-%d mm",
                                        x, y, CS_POS_LIMIT_MM);
        }
    }
    return CS_OK;
}

cs_err_t cs_layout_apply(const cs_layout_opts_t *o, const cs_layout_area_t *area, cs_path_t *p,
                         cs_path_diag_t *diag)
{
    double min[2], max[2];
    if (cs_layout_is_identity(o, p) || !cs_layout_bbox(p, min, max))
        return CS_OK;
    cs_path_loc_t loc = p->elems[0].loc;
    if (p->page_y_down) {
        /* the SVG page turned y-up: y' = H - y (about the drawing's own box without a height) */
        cs_path_affine_t turn = cs_path_affine_identity();
        turn.d = -1.0;
        turn.f = p->page_h_mm > 0 ? p->page_h_mm : min[1] + max[1];
        cs_err_t e = cs_layout_transform(p, &turn, diag);
        if (e != CS_OK)
            return e;
        p->page_y_down = false;
        cs_layout_bbox(p, min, max);
    }
    cs_path_affine_t m;
    if (cs_layout_map(o, min, max, area, &m) != CS_OK)
        return cs_path_diag_set(diag, CS_ERR_ARG, loc,
                                "--fit: no room (the margin leaves no area, or the drawing has "
                                "no extent)");
    return cs_path_affine_is_identity(&m) ? CS_OK : cs_layout_transform(p, &m, diag);
}
