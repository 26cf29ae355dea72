/* cs_horner: power basis and Horner evaluation (see cs_horner.h). */
#include "cs_horner.h"

CS_STATIC_ASSERT(CS_BEZIER_MAX_DEGREE <= CS_FIXED_BINOM_MAX, binomials_up_to_the_degree);
CS_STATIC_ASSERT(40 + CS_HORNER_GUARD + 3 <= 62, horner_sums_below_2_62);

cs_err_t cs_horner_init(cs_horner_t *h, const cs_bezier_t *c)
{
    if (!h || !c)
        return CS_ERR_ARG;
    if (c->rational)
        return CS_ERR_UNSUPPORTED;
    if (c->degree < 1 || c->degree > CS_BEZIER_MAX_DEGREE)
        return CS_ERR_DEGREE;
    unsigned n = c->degree;
    h->degree = c->degree;
    for (unsigned k = 0; k <= n; k++)
        for (unsigned a = 0; a < 3; a++) {
            /* a_k = C(n, k) * k-th forward difference of the control points (exact) */
            int64_t s = 0;
            for (unsigned i = 0; i <= k; i++) {
                int64_t term = (int64_t)cs_fixed_binom(k, i) * (int64_t)cs_fixed_vec_get(&c->p[i], a);
                s += ((k - i) % 2u) ? -term : term;
            }
            h->a[k][a] = (int64_t)cs_fixed_binom(n, k) * s * ((int64_t)1 << CS_HORNER_GUARD);
        }
    return CS_OK;
}

cs_err_t cs_horner_eval(const cs_horner_t *h, cs_param_t t, cs_vec3_t *out)
{
    if (!h || !out || t < 0 || t > CS_PARAM_ONE || h->degree < 1 ||
        h->degree > CS_BEZIER_MAX_DEGREE)
        return CS_ERR_ARG;
    int32_t r[3];
    for (unsigned a = 0; a < 3; a++) {
        int64_t s = h->a[h->degree][a];
        for (unsigned k = h->degree; k-- > 0;)
            s = h->a[k][a] + cs_fixed_mul64_q30(s, t);
        if (cs_fixed_narrow(cs_fixed_round_shift64(s, CS_HORNER_GUARD), &r[a]) != CS_OK)
            return CS_ERR_OVERFLOW;
    }
    out->x = r[0];
    out->y = r[1];
    out->z = r[2];
    return CS_OK;
}
