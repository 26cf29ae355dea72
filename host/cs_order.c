/* cs_order: line merging and travel sorting (see cs_order.h). */
#include "cs_order.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "cs_conv.h"

/* One element of the output, possibly drawn backwards. */
typedef struct {
    size_t elem;
    bool rev;
} ref_t;

/* A stroke or a chain of merged strokes: refs[off .. off + n). */
typedef struct {
    size_t off, n;
    bool closed; /* ends where it starts (exactly): may start at any element boundary */
} item_t;

/* --- a 2-d tree over points with deletion (implicit: the node of the range [lo, hi) is its
 * middle index; cnt[mid] counts the live points of the range) ----------------------------- */

typedef struct {
    double x, y;
    size_t id;
} kpt_t;

typedef struct {
    kpt_t *p;
    size_t *cnt, *where; /* where[id]: index of point id in p */
    bool *alive;
    size_t n;
} kdt_t;

static double coord(const kpt_t *k, unsigned dim)
{
    return dim ? k->y : k->x;
}

/* (coordinate, id) order: a total order, so the tree does not depend on the sort's details */
static bool kless(const kpt_t *a, const kpt_t *b, unsigned dim)
{
    double ca = coord(a, dim), cb = coord(b, dim);
    return ca < cb || (ca == cb && a->id < b->id);
}

static void kswap(kpt_t *a, kpt_t *b)
{
    kpt_t t = *a;
    *a = *b;
    *b = t;
}

/* Quickselect: p[k] is the element of rank k in [lo, hi), smaller ones before it. */
static void kselect(kpt_t *p, size_t lo, size_t hi, size_t k, unsigned dim)
{
    while (hi - lo > 1) {
        kswap(&p[lo + (hi - lo) / 2], &p[hi - 1]); /* pivot: the middle one, moved last */
        size_t s = lo;
        for (size_t i = lo; i + 1 < hi; i++)
            if (kless(&p[i], &p[hi - 1], dim))
                kswap(&p[i], &p[s++]);
        kswap(&p[s], &p[hi - 1]);
        if (s == k)
            return;
        if (k < s)
            hi = s;
        else
            lo = s + 1;
    }
}

static void kbuild(kdt_t *t, size_t lo, size_t hi, unsigned dim)
{
    if (lo >= hi)
        return;
    size_t mid = lo + (hi - lo) / 2;
    kselect(t->p, lo, hi, mid, dim);
    t->cnt[mid] = hi - lo;
    kbuild(t, lo, mid, dim ^ 1u);
    kbuild(t, mid + 1, hi, dim ^ 1u);
}

/* Takes ownership of p[0..n) (ids 0..n-1). False when out of memory (p freed). */
static bool kdt_init(kdt_t *t, kpt_t *p, size_t n)
{
    t->p = p;
    t->n = n;
    t->cnt = malloc((n + 1) * sizeof *t->cnt);
    t->where = malloc((n + 1) * sizeof *t->where);
    t->alive = malloc(n + 1);
    if (!t->cnt || !t->where || !t->alive) {
        free(t->cnt);
        free(t->where);
        free(t->alive);
        free(p);
        return false;
    }
    kbuild(t, 0, n, 0);
    for (size_t i = 0; i < n; i++) {
        t->where[p[i].id] = i;
        t->alive[i] = true;
    }
    return true;
}

static void kdt_free(kdt_t *t)
{
    free(t->p);
    free(t->cnt);
    free(t->where);
    free(t->alive);
}

static void kdt_delete(kdt_t *t, size_t id)
{
    size_t pos = t->where[id], lo = 0, hi = t->n;
    if (!t->alive[pos])
        return;
    t->alive[pos] = false;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        t->cnt[mid]--;
        if (pos == mid)
            break;
        if (pos < mid)
            hi = mid;
        else
            lo = mid + 1;
    }
}

typedef struct {
    double x, y, d2;
    size_t id;
    bool found;
} knn_t;

static void ksearch(const kdt_t *t, size_t lo, size_t hi, unsigned dim, knn_t *q)
{
    if (lo >= hi)
        return;
    size_t mid = lo + (hi - lo) / 2;
    if (t->cnt[mid] == 0)
        return;
    const kpt_t *k = &t->p[mid];
    if (t->alive[mid]) {
        double dx = k->x - q->x, dy = k->y - q->y, d2 = dx * dx + dy * dy;
        if (!q->found || d2 < q->d2 || (d2 == q->d2 && k->id < q->id)) {
            q->d2 = d2;
            q->id = k->id;
            q->found = true;
        }
    }
    double diff = (dim ? q->y : q->x) - coord(k, dim);
    bool left = diff < 0;
    ksearch(t, left ? lo : mid + 1, left ? mid : hi, dim ^ 1u, q);
    if (!q->found || diff * diff <= q->d2)
        ksearch(t, left ? mid + 1 : lo, left ? hi : mid, dim ^ 1u, q);
}

/* The live point nearest (x, y) (ties: the lowest id). False when none is left. */
static bool kdt_nearest(const kdt_t *t, double x, double y, size_t *id, double *d2)
{
    knn_t q = {x, y, 0, 0, false};
    ksearch(t, 0, t->n, 0, &q);
    *id = q.id;
    *d2 = q.d2;
    return q.found;
}

/* --- strokes and items ------------------------------------------------------------------ */

typedef struct {
    const cs_path_t *p;
    ref_t *refs;
    item_t *items;
    size_t nrefs, nitems;
} order_t;

static const cs_vec3_t *ref_start(const order_t *o, ref_t r)
{
    const cs_bezier_t *c = &o->p->elems[r.elem].curve;
    return r.rev ? &c->p[c->degree] : &c->p[0];
}

static const cs_vec3_t *ref_end(const order_t *o, ref_t r)
{
    const cs_bezier_t *c = &o->p->elems[r.elem].curve;
    return r.rev ? &c->p[0] : &c->p[c->degree];
}

static const cs_vec3_t *item_start(const order_t *o, const item_t *it)
{
    return ref_start(o, o->refs[it->off]);
}

static const cs_vec3_t *item_end(const order_t *o, const item_t *it)
{
    return ref_end(o, o->refs[it->off + it->n - 1]);
}

static bool same_point(const cs_vec3_t *a, const cs_vec3_t *b)
{
    return a->x == b->x && a->y == b->y && a->z == b->z;
}

static double dist_xy(const cs_vec3_t *a, const cs_vec3_t *b)
{
    double dx = cs_conv_pos_to_mm(a->x) - cs_conv_pos_to_mm(b->x);
    double dy = cs_conv_pos_to_mm(a->y) - cs_conv_pos_to_mm(b->y);
    return sqrt(dx * dx + dy * dy);
}

/* Element i starts a stroke: a new subpath, or not where the previous element ended. */
static bool starts_stroke(const cs_path_t *p, size_t i)
{
    if (i == 0 || p->elems[i].subpath != p->elems[i - 1].subpath)
        return true;
    const cs_bezier_t *a = &p->elems[i - 1].curve;
    return !same_point(&a->p[a->degree], &p->elems[i].curve.p[0]);
}

double cs_order_travel(const cs_path_t *p, size_t *lifts)
{
    cs_vec3_t cur = {0, 0, 0};
    double t = 0;
    size_t n = 0;
    for (size_t i = 0; i < p->n; i++) {
        const cs_bezier_t *c = &p->elems[i].curve;
        t += dist_xy(&cur, &c->p[0]);
        n += starts_stroke(p, i);
        cur = c->p[c->degree];
    }
    if (lifts)
        *lifts = n;
    return t;
}

/* Reverses refs[a .. b) in place; flip also turns each element round. */
static void reverse_refs(ref_t *r, size_t a, size_t b, bool flip)
{
    for (size_t i = a, j = b; i < j; i++, j--) {
        ref_t t = r[i];
        r[i] = r[j - 1];
        r[j - 1] = t;
    }
    if (flip)
        for (size_t i = a; i < b; i++)
            r[i].rev = !r[i].rev;
}

static void item_reverse(order_t *o, const item_t *it)
{
    reverse_refs(o->refs, it->off, it->off + it->n, true);
}

/* Rotates a closed item so that its k-th element comes first (three reversals). */
static void item_rotate(order_t *o, const item_t *it, size_t k)
{
    reverse_refs(o->refs, it->off, it->off + k, false);
    reverse_refs(o->refs, it->off + k, it->off + it->n, false);
    reverse_refs(o->refs, it->off, it->off + it->n, false);
}

/* --- merge ------------------------------------------------------------------------------ */

/* Strokes: sf[s] .. sf[s + 1] - 1 are the elements of stroke s (sf[ns] = p->n). */
static size_t *strokes(const cs_path_t *p, size_t *ns)
{
    size_t *sf = malloc((p->n + 1) * sizeof *sf);
    if (sf == NULL)
        return NULL;
    size_t k = 0;
    for (size_t i = 0; i < p->n; i++)
        if (starts_stroke(p, i))
            sf[k++] = i;
    sf[k] = p->n;
    *ns = k;
    return sf;
}

/* Appends stroke s, forwards or backwards, to o->refs. */
static void put_stroke(order_t *o, const size_t *sf, size_t s, bool rev)
{
    size_t len = sf[s + 1] - sf[s];
    for (size_t k = 0; k < len; k++)
        o->refs[o->nrefs++] = (ref_t){rev ? sf[s + 1] - 1 - k : sf[s] + k, rev};
}

/* Closes the item made of refs[off .. nrefs). */
static void end_item(order_t *o, size_t off)
{
    item_t *it = &o->items[o->nitems++];
    it->off = off;
    it->n = o->nrefs - off;
    it->closed = same_point(item_start(o, it), item_end(o, it));
}

/* End point of stroke id / 2 (id even: its start, odd: its end). */
static const cs_vec3_t *stroke_end(const cs_path_t *p, const size_t *sf, size_t id)
{
    const cs_bezier_t *c = &p->elems[id % 2 ? sf[id / 2 + 1] - 1 : sf[id / 2]].curve;
    return id % 2 ? &c->p[c->degree] : &c->p[0];
}

/* The live stroke end within tol of v (x, y and z), deleting both ends of its stroke. */
static bool take_near(kdt_t *t, const cs_path_t *p, const size_t *sf, const cs_vec3_t *v,
                      double tol, size_t *id)
{
    double d2;
    if (!kdt_nearest(t, cs_conv_pos_to_mm(v->x), cs_conv_pos_to_mm(v->y), id, &d2) ||
        d2 > tol * tol || fabs(cs_conv_pos_to_mm(stroke_end(p, sf, *id)->z - v->z)) > tol)
        return false;
    kdt_delete(t, *id & ~(size_t)1);
    kdt_delete(t, *id | 1);
    return true;
}

typedef struct {
    size_t s;
    bool rev;
} link_t;

/* Grows the chain of stroke s forwards (into fw) and backwards (into bw), then writes it. */
static void chain(order_t *o, kdt_t *t, const size_t *sf, size_t s, double tol, link_t *fw,
                  link_t *bw)
{
    const cs_path_t *p = o->p;
    kdt_delete(t, 2 * s);
    kdt_delete(t, 2 * s + 1);
    size_t nf = 0, nb = 0, id;
    fw[nf++] = (link_t){s, false};
    const cs_vec3_t *e = stroke_end(p, sf, 2 * s + 1);
    while (take_near(t, p, sf, e, tol, &id)) {
        bool at_start = id % 2 == 0; /* its start meets our end: forwards */
        fw[nf++] = (link_t){id / 2, !at_start};
        e = stroke_end(p, sf, at_start ? id + 1 : id - 1);
    }
    e = stroke_end(p, sf, 2 * s);
    while (take_near(t, p, sf, e, tol, &id)) {
        bool at_end = id % 2 == 1; /* its end meets our start: forwards, before us */
        bw[nb++] = (link_t){id / 2, !at_end};
        e = stroke_end(p, sf, at_end ? id - 1 : id + 1);
    }
    size_t off = o->nrefs;
    while (nb > 0) {
        nb--;
        put_stroke(o, sf, bw[nb].s, bw[nb].rev);
    }
    for (size_t k = 0; k < nf; k++)
        put_stroke(o, sf, fw[k].s, fw[k].rev);
    end_item(o, off);
}

static cs_err_t merge(order_t *o, const size_t *sf, size_t ns, double tol)
{
    kpt_t *pts = malloc((2 * ns + 1) * sizeof *pts);
    link_t *fw = malloc((ns + 1) * sizeof *fw), *bw = malloc((ns + 1) * sizeof *bw);
    kdt_t t;
    if (pts == NULL || fw == NULL || bw == NULL) {
        free(pts);
        free(fw);
        free(bw);
        return CS_ERR_FULL;
    }
    for (size_t id = 0; id < 2 * ns; id++) {
        const cs_vec3_t *v = stroke_end(o->p, sf, id);
        pts[id] = (kpt_t){cs_conv_pos_to_mm(v->x), cs_conv_pos_to_mm(v->y), id};
    }
    if (!kdt_init(&t, pts, 2 * ns)) {
        free(fw);
        free(bw);
        return CS_ERR_FULL;
    }
    for (size_t s = 0; s < ns; s++)
        if (t.alive[t.where[2 * s]])
            chain(o, &t, sf, s, tol, fw, bw);
    kdt_free(&t);
    free(fw);
    free(bw);
    return CS_OK;
}

/* --- sort ------------------------------------------------------------------------------- */

#define OPEN_REVERSED SIZE_MAX

/* Entry points of every item: each element boundary of a closed item (ek = the element to
 * start with), both ends of an open one (ek = 0 or OPEN_REVERSED). ioff[i]: item i's first. */
static kpt_t *entries(const order_t *o, size_t *ioff, size_t *eitem, size_t *ek, size_t *ne)
{
    size_t n = 0;
    for (size_t i = 0; i < o->nitems; i++)
        n += o->items[i].closed ? o->items[i].n : 2;
    kpt_t *pts = malloc((n + 1) * sizeof *pts);
    if (pts == NULL)
        return NULL;
    size_t e = 0;
    for (size_t i = 0; i < o->nitems; i++) {
        const item_t *it = &o->items[i];
        ioff[i] = e;
        size_t k_n = it->closed ? it->n : 2;
        for (size_t k = 0; k < k_n; k++, e++) {
            const cs_vec3_t *v = it->closed ? ref_start(o, o->refs[it->off + k])
                                 : k == 0   ? item_start(o, it)
                                            : item_end(o, it);
            pts[e] = (kpt_t){cs_conv_pos_to_mm(v->x), cs_conv_pos_to_mm(v->y), e};
            eitem[e] = i;
            ek[e] = it->closed || k == 0 ? k : OPEN_REVERSED;
        }
    }
    ioff[o->nitems] = e;
    *ne = n;
    return pts;
}

/* Nearest neighbour from the origin: order[0 .. nitems), each item turned to its best entry. */
static cs_err_t nn_sort(order_t *o, size_t *order)
{
    size_t m = o->nitems, ne = 0;
    size_t *ioff = malloc((m + 1) * sizeof *ioff);
    size_t *eitem = malloc((o->nrefs + 2 * m + 1) * sizeof *eitem);
    size_t *ek = malloc((o->nrefs + 2 * m + 1) * sizeof *ek);
    kpt_t *pts = ioff && eitem && ek ? entries(o, ioff, eitem, ek, &ne) : NULL;
    kdt_t t;
    if (pts == NULL || !kdt_init(&t, pts, ne)) {
        free(ioff);
        free(eitem);
        free(ek);
        return CS_ERR_FULL;
    }
    double x = 0, y = 0, d2;
    for (size_t step = 0; step < m; step++) {
        size_t id;
        kdt_nearest(&t, x, y, &id, &d2); /* one live entry per item left: always found */
        const item_t *it = &o->items[eitem[id]];
        for (size_t e = ioff[eitem[id]]; e < ioff[eitem[id] + 1]; e++)
            kdt_delete(&t, e);
        if (it->closed)
            item_rotate(o, it, ek[id]);
        else if (ek[id] == OPEN_REVERSED)
            item_reverse(o, it);
        order[step] = eitem[id];
        const cs_vec3_t *v = item_end(o, it);
        x = cs_conv_pos_to_mm(v->x);
        y = cs_conv_pos_to_mm(v->y);
    }
    kdt_free(&t);
    free(ioff);
    free(eitem);
    free(ek);
    return CS_OK;
}

/* Windowed 2-opt: reversing the run order[i .. j] (each item turned round) when that shortens
 * the two jumps around it. Bounded: CS_ORDER_PASSES passes of m x CS_ORDER_WINDOW trials. */
static void two_opt(order_t *o, size_t *order, size_t m)
{
    static const cs_vec3_t origin = {0, 0, 0};
    for (unsigned pass = 0; pass < CS_ORDER_PASSES; pass++) {
        bool improved = false;
        for (size_t i = 0; i < m; i++)
            for (size_t j = i; j < m && j < i + CS_ORDER_WINDOW; j++) {
                const cs_vec3_t *prev = i ? item_end(o, &o->items[order[i - 1]]) : &origin;
                const cs_vec3_t *a = item_start(o, &o->items[order[i]]);
                const cs_vec3_t *b = item_end(o, &o->items[order[j]]);
                const cs_vec3_t *next = j + 1 < m ? item_start(o, &o->items[order[j + 1]]) : NULL;
                double before = dist_xy(prev, a) + (next ? dist_xy(b, next) : 0);
                double after = dist_xy(prev, b) + (next ? dist_xy(a, next) : 0);
                if (!(after < before - 1e-9))
                    continue;
                for (size_t k = i; k <= j; k++)
                    item_reverse(o, &o->items[order[k]]);
                for (size_t u = i, v = j; u < v; u++, v--) {
                    size_t tmp = order[u];
                    order[u] = order[v];
                    order[v] = tmp;
                }
                improved = true;
            }
        if (!improved)
            break;
    }
}

/* --- output ----------------------------------------------------------------------------- */

/* The same curve traced from its other end: control points and weights in reverse order
 * (B_i(1 - t) = B_{n-i}(t), so the point set is exactly the same). */
static void reverse_curve(cs_bezier_t *c)
{
    for (unsigned i = 0, j = c->degree; i < j; i++, j--) {
        cs_vec3_t tp = c->p[i];
        c->p[i] = c->p[j];
        c->p[j] = tp;
        cs_weight_t tw = c->w[i];
        c->w[i] = c->w[j];
        c->w[j] = tw;
    }
}

/* Replaces p's elements by the items in order, subpath k = the k-th item; a gap inside an item
 * (merged ends within the tolerance, not equal) is drawn by a bridging line. */
static cs_err_t emit(const order_t *o, const size_t *order, cs_path_t *p, size_t *bridges)
{
    cs_path_elem_t *out = malloc((2 * o->nrefs + 1) * sizeof *out);
    if (out == NULL)
        return CS_ERR_FULL;
    size_t k = 0;
    for (size_t idx = 0; idx < o->nitems; idx++) {
        const item_t *it = &o->items[order[idx]];
        for (size_t r = 0; r < it->n; r++) {
            ref_t ref = o->refs[it->off + r];
            cs_path_elem_t el = p->elems[ref.elem];
            if (ref.rev)
                reverse_curve(&el.curve);
            el.subpath = (unsigned)idx;
            const cs_vec3_t *prev = r ? &out[k - 1].curve.p[out[k - 1].curve.degree] : NULL;
            if (prev != NULL && !same_point(prev, &el.curve.p[0])) {
                cs_path_elem_t br = el;
                cs_vec3_t pts[2] = {*prev, el.curve.p[0]};
                cs_bezier_init(&br.curve, 1, pts); /* both points already in range */
                br.kind = CS_PATH_LINE;
                out[k++] = br;
                (*bridges)++;
            }
            out[k++] = el;
        }
    }
    free(p->elems);
    p->elems = out;
    p->n = k;
    p->cap = 2 * o->nrefs + 1;
    p->nsubpaths = (unsigned)o->nitems;
    p->pending_subpath = true;
    return CS_OK;
}

/* Merge or not, sort or not, then emit. */
static cs_err_t run(order_t *ord, const cs_order_opts_t *o, const size_t *sf, size_t ns,
                    size_t *order, size_t *bridges)
{
    cs_err_t e = CS_OK;
    if (o->merge) {
        e = merge(ord, sf, ns, o->tol_mm);
    } else {
        for (size_t s = 0; s < ns; s++) {
            size_t off = ord->nrefs;
            put_stroke(ord, sf, s, false);
            end_item(ord, off);
        }
    }
    for (size_t i = 0; i < ord->nitems; i++)
        order[i] = i;
    if (e == CS_OK && o->sort && (e = nn_sort(ord, order)) == CS_OK)
        two_opt(ord, order, ord->nitems);
    return e == CS_OK ? emit(ord, order, (cs_path_t *)ord->p, bridges) : e;
}

cs_err_t cs_order_apply(cs_path_t *p, const cs_order_opts_t *o, cs_order_stats_t *st)
{
    memset(st, 0, sizeof *st);
    st->travel_before_mm = cs_order_travel(p, &st->lifts_before);
    st->travel_after_mm = st->travel_before_mm;
    st->lifts_after = st->lifts_before;
    for (size_t i = 0; i < p->n && !st->skipped; i++)
        st->skipped = p->elems[i].rapid;
    if (st->skipped || (!o->merge && !o->sort) || p->n == 0)
        return CS_OK;
    size_t ns = 0;
    size_t *sf = strokes(p, &ns);
    order_t ord = {p, malloc((p->n + 1) * sizeof(ref_t)), malloc((ns + 1) * sizeof(item_t)), 0, 0};
    size_t *order = malloc((ns + 1) * sizeof *order);
    cs_err_t e = sf && ord.refs && ord.items && order ? run(&ord, o, sf, ns, order, &st->bridges)
                                                      : CS_ERR_FULL;
    free(sf);
    free(ord.refs);
    free(ord.items);
    free(order);
    if (e == CS_OK)
        st->travel_after_mm = cs_order_travel(p, &st->lifts_after);
    return e;
}
