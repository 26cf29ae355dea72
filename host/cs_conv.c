/* cs_conv: double <-> fixed-point conversions with range checks (see cs_conv.h). */
#include "cs_conv.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

cs_err_t cs_conv_mm_to_pos(double mm, cs_pos_t *out)
{
    if (!isfinite(mm))
        return CS_ERR_RANGE;
    /* Compare in LSB after rounding so that exactly +/-4096 mm is accepted and one LSB more is
     * not. Doubles hold every integer up to 2^53, so the comparison is exact. */
    double lsb = nearbyint(mm * (double)CS_POS_ONE_MM);
    if (fabs(lsb) > (double)CS_POS_LIMIT)
        return CS_ERR_RANGE;
    *out = (cs_pos_t)lsb;
    return CS_OK;
}

double cs_conv_pos_to_mm(cs_pos_t p)
{
    return (double)p / (double)CS_POS_ONE_MM;
}

cs_err_t cs_conv_mm_to_vec(double x, double y, double z, cs_vec3_t *out)
{
    cs_vec3_t v;
    cs_err_t e;
    if ((e = cs_conv_mm_to_pos(x, &v.x)) != CS_OK || (e = cs_conv_mm_to_pos(y, &v.y)) != CS_OK ||
        (e = cs_conv_mm_to_pos(z, &v.z)) != CS_OK)
        return e;
    *out = v;
    return CS_OK;
}

cs_err_t cs_conv_to_param(double v, cs_param_t *out)
{
    if (!isfinite(v))
        return CS_ERR_RANGE;
    double q = nearbyint(v * (double)CS_PARAM_ONE);
    if (q < (double)INT32_MIN || q > (double)INT32_MAX)
        return CS_ERR_RANGE;
    *out = (cs_param_t)q;
    return CS_OK;
}

double cs_conv_param_to_double(cs_param_t p)
{
    return (double)p / (double)CS_PARAM_ONE;
}

cs_err_t cs_conv_to_weight(double w, cs_weight_t *out)
{
    if (!isfinite(w))
        return CS_ERR_WEIGHT;
    double q = nearbyint(w * (double)CS_WEIGHT_ONE);
    if (q < (double)CS_WEIGHT_MIN || q > (double)CS_WEIGHT_ONE)
        return CS_ERR_WEIGHT;
    *out = (cs_weight_t)q;
    return CS_OK;
}

cs_err_t cs_conv_tol_to_pos(double mm, cs_pos_t *out)
{
    if (!isfinite(mm) || mm <= 0.0)
        return CS_ERR_TOLERANCE;
    double lsb = nearbyint(mm * (double)CS_POS_ONE_MM);
    if (lsb < 1.0 || lsb > (double)CS_POS_LIMIT)
        return CS_ERR_TOLERANCE;
    *out = (cs_pos_t)lsb;
    return CS_OK;
}

bool cs_conv_number(const char *s, double *out)
{
    char *end = NULL;
    double v = strtod(s, &end);
    if (!end || end == s || *end != '\0' || !isfinite(v))
        return false;
    *out = v;
    return true;
}
