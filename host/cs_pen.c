/* cs_pen: pen lifts between the strokes of SVG and HP-GL drawings (see cs_pen.h). */
#include "cs_pen.h"

#include <string.h>

#include "cs_conv.h"

bool cs_pen_stroke_starts(const cs_path_t *p, size_t k)
{
    if (k == 0 || p->elems[k].rapid)
        return true;
    const cs_path_elem_t *a = &p->elems[k - 1], *b = &p->elems[k];
    const cs_vec3_t *end = &a->curve.p[a->curve.degree], *st = &b->curve.p[0];
    return a->rapid || a->subpath != b->subpath || end->x != st->x || end->y != st->y ||
           end->z != st->z;
}

size_t cs_pen_strokes(const cs_path_t *path)
{
    size_t n = 0;
    for (size_t k = 0; k < path->n; k++)
        if (!path->elems[k].rapid && cs_pen_stroke_starts(path, k))
            n++;
    return n;
}

/* The vertical pen move at (x, y) of p from z0 to z1 (mm), rapid or at feed mm/s. */
static cs_err_t add_z_move(cs_path_t *out, const cs_vec3_t *p, cs_pos_t z0, cs_pos_t z1,
                           double feed, cs_path_loc_t loc)
{
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = 1;
    c.p[0] = *p;
    c.p[0].z = z0;
    c.p[1] = *p;
    c.p[1].z = z1;
    return cs_path_add_move(out, &c, CS_PATH_LINE, loc, feed, !(feed > 0));
}

/* elem's curve with every z raised by dz (LSB); CS_ERR_RANGE when one leaves CS_POS_LIMIT. */
static cs_err_t raised(const cs_path_elem_t *el, cs_pos_t dz, cs_bezier_t *c)
{
    *c = el->curve;
    for (unsigned i = 0; i <= c->degree; i++) {
        int64_t z = (int64_t)c->p[i].z + dz;
        if (z > CS_POS_LIMIT || z < -CS_POS_LIMIT)
            return CS_ERR_RANGE;
        c->p[i].z = (cs_pos_t)z;
    }
    return CS_OK;
}

/* Appends element k of in to out with its pen moves (see cs_pen_lift_z); *down: pen state. */
static cs_err_t lift_one(const cs_path_t *in, size_t k, cs_path_t *out, const cs_pos_t z[2],
                         double feed, bool *down, cs_path_diag_t *diag)
{
    const cs_path_elem_t *el = &in->elems[k];
    if (cs_pen_stroke_starts(in, k)) {
        cs_err_t e = CS_OK;
        if (*down) { /* lift where the previous stroke ended */
            const cs_path_elem_t *pv = &out->elems[out->n - 1];
            e = add_z_move(out, &pv->curve.p[pv->curve.degree], z[1], z[0], feed, pv->loc);
        }
        *down = false;
        cs_path_new_subpath(out);
        if (e == CS_OK && !el->rapid) { /* and come down where this one starts */
            e = add_z_move(out, &el->curve.p[0], z[0], z[1], feed, el->loc);
            *down = true;
        }
        if (e != CS_OK)
            return e;
    }
    cs_bezier_t c;
    if (raised(el, el->rapid ? z[0] : z[1], &c) != CS_OK)
        return cs_path_diag_set(diag, CS_ERR_RANGE, el->loc,
                                "the pen height puts this element outside the coordinate range");
    return cs_path_add_move(out, &c, el->kind, el->loc, el->feed_mm_s, el->rapid);
}

cs_err_t cs_pen_lift_z(cs_path_t *path, const cs_machine_pen_t *pen, cs_path_diag_t *diag)
{
    if (pen == NULL || pen->mode != CS_MACHINE_PEN_Z || path->n == 0)
        return CS_OK;
    cs_pos_t z[2]; /* up, down */
    if (cs_conv_mm_to_pos(pen->up_z_mm, &z[0]) != CS_OK ||
        cs_conv_mm_to_pos(pen->down_z_mm, &z[1]) != CS_OK)
        return cs_path_diag_set(diag, CS_ERR_RANGE, path->elems[0].loc,
                                "[pen] heights outside the coordinate range");
    cs_path_t out;
    cs_path_init(&out);
    bool down = false;
    cs_err_t e = CS_OK;
    for (size_t k = 0; k < path->n && e == CS_OK; k++)
        e = lift_one(path, k, &out, z, pen->z_feed_mm_s, &down, diag);
    if (e == CS_OK && down) {
        const cs_path_elem_t *pv = &out.elems[out.n - 1];
        e = add_z_move(&out, &pv->curve.p[pv->curve.degree], z[1], z[0], pen->z_feed_mm_s, pv->loc);
    }
    if (e != CS_OK) {
        cs_path_free(&out);
        if (e == CS_ERR_FULL)
            cs_path_diag_set(diag, e, path->elems[0].loc, "out of memory");
        return e;
    }
    /* The elements' file names are interned in path: hand them over with it. */
    out.files = path->files;
    out.nfiles = path->nfiles;
    out.capfiles = path->capfiles;
    path->files = NULL;
    path->nfiles = path->capfiles = 0;
    cs_path_free(path);
    *path = out;
    return CS_OK;
}
