/* cs_lensub: length-based subdivision (see cs_lensub.h). */
#include "cs_lensub.h"

#define ONE ((uint32_t)1 << CS_LENSUB_MAX_DEPTH)

CS_STATIC_ASSERT(CS_LENSUB_MAX_DEPTH <= CS_PARAM_FRAC_BITS, steps_are_params);

static cs_err_t point(const cs_lensub_t *s, uint32_t t, cs_vec3_t *out)
{
    cs_param_t tp = (cs_param_t)((int64_t)t << (CS_PARAM_FRAC_BITS - CS_LENSUB_MAX_DEPTH));
    if (t == ONE) {
        *out = s->c.p[s->c.degree]; /* the exact end */
        return CS_OK;
    }
    return s->horner ? cs_horner_eval(&s->h, tp, out) : cs_bezier_eval(&s->c, tp, out);
}

static uint64_t dist2(const cs_vec3_t *a, const cs_vec3_t *b)
{
    int64_t dx = (int64_t)a->x - b->x, dy = (int64_t)a->y - b->y, dz = (int64_t)a->z - b->z;
    /* each |d| < 2^29: the sum of squares < 3 * 2^58 */
    return (uint64_t)(dx * dx) + (uint64_t)(dy * dy) + (uint64_t)(dz * dz);
}

cs_err_t cs_lensub_begin(cs_lensub_t *s, const cs_bezier_t *c, cs_pos_t max_len, bool horner)
{
    if (!s || !c)
        return CS_ERR_ARG;
    if (max_len < 1)
        return CS_ERR_TOLERANCE;
    cs_err_t e = c->rational ? cs_bezier_init_rational(&s->c, c->degree, c->p, c->w)
                             : cs_bezier_init(&s->c, c->degree, c->p);
    if (e == CS_OK && horner)
        e = cs_horner_init(&s->h, c);
    if (e != CS_OK)
        return e;
    s->horner = horner;
    s->max2 = (uint64_t)max_len * (uint64_t)max_len;
    s->t = 0;
    s->step = ONE;
    s->cur = c->p[0];
    return CS_OK;
}

cs_err_t cs_lensub_next(cs_lensub_t *s, cs_vec3_t *out)
{
    if (!s || !out)
        return CS_ERR_ARG;
    if (s->t >= ONE)
        return CS_END;
    for (;;) {
        cs_vec3_t p;
        cs_err_t e = point(s, s->t + s->step, &p);
        if (e != CS_OK)
            return e;
        if (dist2(&p, &s->cur) > s->max2) {
            if (s->step == 1)
                return CS_ERR_DEPTH;
            s->step >>= 1; /* subdivide dt */
            continue;
        }
        s->t += s->step;
        s->cur = p;
        *out = p;
        /* The recursion's next interval: the largest dyadic one starting at t (its parent
         * holds the points already emitted, so it was split). t + step <= ONE stays true: ONE
         * and t are multiples of the step. */
        while (s->t < ONE && s->step < ONE && (s->t & (2 * s->step - 1)) == 0)
            s->step <<= 1;
        return CS_OK;
    }
}
