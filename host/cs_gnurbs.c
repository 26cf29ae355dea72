/* cs_gnurbs: G-code NURBS blocks -> Bézier segments (see cs_gnurbs.h). */
#include "cs_gnurbs.h"

#include <math.h>
#include <stdbool.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_conv.h"
#include "cs_err_text.h"

/* Largest knot span after rescaling, in Q15.16 units (leaves headroom below INT32_MAX). */
#define GN_KNOT_RANGE 16384.0

static cs_err_t gn_why(cs_err_t e, char *why, size_t len, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, len, fmt, ap);
    va_end(ap);
    return e;
}

/* Doubles the array *p of *cap elements of size sz (16 at first); false without memory. */
static bool gn_grow(void **p, size_t *cap, size_t sz)
{
    size_t nc = *cap ? 2 * *cap : 16;
    void *q = realloc(*p, nc * sz);
    if (!q)
        return false;
    *p = q;
    *cap = nc;
    return true;
}

void cs_gnurbs_begin(cs_gnurbs_t *nb, unsigned order)
{
    nb->n = 0;
    nb->nknots = 0;
    nb->order = order;
}

cs_err_t cs_gnurbs_push(cs_gnurbs_t *nb, const double p[3], double w)
{
    if (nb->n >= CS_GNURBS_MAX_POINTS)
        return CS_ERR_FULL;
    if (nb->n == nb->cap && !gn_grow((void **)&nb->cps, &nb->cap, sizeof *nb->cps))
        return CS_ERR_FULL;
    memcpy(nb->cps[nb->n].p, p, sizeof nb->cps[0].p);
    nb->cps[nb->n++].w = w;
    return CS_OK;
}

cs_err_t cs_gnurbs_knot(cs_gnurbs_t *nb, double k)
{
    if (nb->nknots >= CS_GNURBS_MAX_POINTS + CS_GNURBS_MAX_ORDER)
        return CS_ERR_FULL;
    if (nb->nknots == nb->capknots &&
        !gn_grow((void **)&nb->knots, &nb->capknots, sizeof *nb->knots))
        return CS_ERR_FULL;
    nb->knots[nb->nknots++] = k;
    return CS_OK;
}

/* The knots in Q15.16: LinuxCNC's G5.2 vector, or the given ones rescaled so that their span
 * is GN_KNOT_RANGE (a NURBS curve does not change when its knots are scaled and shifted). */
static cs_err_t gn_knots(const cs_gnurbs_t *nb, cs_nurbs_knot_t *kn, char *why, size_t len)
{
    size_t cnt = nb->n, k = nb->order, n = cnt - 1;
    if (nb->nknots == 0) {
        for (size_t i = 0; i <= n + k; i++) {
            size_t v = i < k ? 0 : i <= n ? i - k + 1 : n - k + 2;
            kn[i] = (cs_nurbs_knot_t)v * CS_NURBS_KNOT_ONE;
        }
        return CS_OK;
    }
    if (nb->nknots != cnt + k)
        return gn_why(CS_ERR_PARSE, why, len,
                      "%zu control points of order %zu need %zu knots (K words), not %zu", cnt, k,
                      cnt + k, nb->nknots);
    const double *K = nb->knots;
    double span = K[cnt + k - 1] - K[0];
    for (size_t i = 1; i < cnt + k; i++)
        if (K[i] < K[i - 1])
            return gn_why(CS_ERR_PARSE, why, len, "knot %zu (K%g) is below the one before it",
                          i + 1, K[i]);
    if (!(span > 0))
        return gn_why(CS_ERR_PARSE, why, len, "the knots span nothing");
    for (size_t i = 1; i < k; i++)
        if (K[i] != K[0] || K[cnt + k - 1 - i] != K[cnt + k - 1])
            return gn_why(CS_ERR_PARSE, why, len,
                          "the first and the last %zu knots must be equal (a clamped curve, "
                          "starting where the tool is)",
                          k);
    for (size_t i = 0; i < cnt + k; i++) {
        kn[i] =
            (cs_nurbs_knot_t)nearbyint((K[i] - K[0]) / span * GN_KNOT_RANGE * CS_NURBS_KNOT_ONE);
        if (i > 0 && K[i] > K[i - 1] && kn[i] == kn[i - 1])
            return gn_why(CS_ERR_RANGE, why, len, "knots %g and %g are too close together",
                          K[i - 1], K[i]);
    }
    return CS_OK;
}

static cs_err_t gn_convert(const cs_gnurbs_t *nb, cs_vec3_t *pts, int32_t *w, cs_nurbs_knot_t *kn,
                           cs_gnurbs_emit_fn emit, void *ctx, char *why, size_t len)
{
    size_t cnt = nb->n;
    double wmax = 0;
    for (size_t i = 0; i < cnt; i++)
        wmax = fmax(wmax, nb->cps[i].w);
    for (size_t i = 0; i < cnt; i++) {
        const double *p = nb->cps[i].p;
        if (cs_conv_mm_to_vec(p[0], p[1], p[2], &pts[i]) != CS_OK)
            return gn_why(CS_ERR_RANGE, why, len,
                          "control point (%.4f, %.4f, %.4f) mm is outside "
                          "+/-%d mm",
                          p[0], p[1], p[2], CS_POS_LIMIT_MM);
        double wq = nearbyint(nb->cps[i].w / wmax * (double)CS_PARAM_ONE);
        if (!(wq >= 1))
            return gn_why(CS_ERR_WEIGHT, why, len,
                          "weight %g is too small next to the largest "
                          "weight %g",
                          nb->cps[i].w, wmax);
        w[i] = (int32_t)wq;
    }
    cs_err_t e = gn_knots(nb, kn, why, len);
    if (e != CS_OK)
        return e;
    cs_nurbs_t nc;
    if ((e = cs_nurbs_init(&nc, nb->order - 1, pts, w, cnt, kn, cnt + nb->order)) != CS_OK)
        return gn_why(e, why, len, "bad NURBS block: %s", cs_err_text(e));
    cs_nurbs_iter_t it;
    cs_nurbs_iter_begin(&nc, &it);
    cs_bezier_t seg;
    cs_vec3_t prev = pts[0];
    size_t nseg = cs_nurbs_segments(&nc), iseg = 0;
    while ((e = cs_nurbs_next(&nc, &it, &seg, NULL, NULL)) == CS_OK) {
        /* Consecutive segments share their end point to within 1 LSB: snap them together (and
         * the block's ends onto its first and last control points, where a clamped curve ends). */
        seg.p[0] = prev;
        if (++iseg == nseg)
            seg.p[seg.degree] = pts[cnt - 1];
        prev = seg.p[seg.degree];
        cs_err_t ea = emit(ctx, &seg);
        if (ea != CS_OK)
            return gn_why(ea, why, len, "%s", cs_err_text(ea));
    }
    if (e != CS_END)
        return gn_why(e, why, len, "cannot convert this NURBS block: %s", cs_err_text(e));
    return CS_OK;
}

cs_err_t cs_gnurbs_build(const cs_gnurbs_t *nb, cs_gnurbs_emit_fn emit, void *ctx, char *why,
                         size_t whylen)
{
    size_t cnt = nb->n;
    if (cnt < nb->order)
        return gn_why(CS_ERR_PARSE, why, whylen,
                      "a block of order %u needs at least %u control points (has %zu)", nb->order,
                      nb->order, cnt);
    cs_vec3_t *pts = malloc(cnt * sizeof *pts);
    int32_t *w = malloc(cnt * sizeof *w);
    cs_nurbs_knot_t *kn = malloc((cnt + nb->order) * sizeof *kn);
    cs_err_t e = (pts && w && kn) ? gn_convert(nb, pts, w, kn, emit, ctx, why, whylen)
                                  : gn_why(CS_ERR_FULL, why, whylen, "out of memory");
    free(pts);
    free(w);
    free(kn);
    return e;
}

cs_err_t cs_gnurbs_copy(cs_gnurbs_t *dst, const cs_gnurbs_t *src)
{
    *dst = *src;
    dst->cps = src->n ? malloc(src->n * sizeof *dst->cps) : NULL;
    dst->knots = src->nknots ? malloc(src->nknots * sizeof *dst->knots) : NULL;
    dst->cap = src->n;
    dst->capknots = src->nknots;
    if ((src->n && !dst->cps) || (src->nknots && !dst->knots)) {
        cs_gnurbs_free(dst);
        return CS_ERR_FULL;
    }
    if (src->n)
        memcpy(dst->cps, src->cps, src->n * sizeof *dst->cps);
    if (src->nknots)
        memcpy(dst->knots, src->knots, src->nknots * sizeof *dst->knots);
    return CS_OK;
}

void cs_gnurbs_free(cs_gnurbs_t *nb)
{
    free(nb->cps);
    free(nb->knots);
    memset(nb, 0, sizeof *nb);
}
