/* curve_core_m0: the smallest program that uses the curve core, to measure what the core costs in
 * flash on a Cortex-M0+ once linked with --gc-sections (scripts/bench.sh, "The curve core").
 * CURVE_CORE_FD: a cubic Bezier traced by uniform forward differences (cs_bezier_init,
 * cs_fd_begin, cs_fd_next), the equivalent of Marlin's G5; CURVE_CORE_TRACE: any Bezier by any of
 * the tracers (cs_trace); CURVE_CORE_PREDICT: a planar cubic by the default tracer alone
 * (cs_predict_begin, cs_predict_next); CURVE_CORE_FD3: a planar polynomial cubic by the specialised
 * FD path (cs_fd3_begin, cs_fd3_fill). Not run: the volatile sink keeps every call. */
#include <stddef.h>
#include <stdint.h>

#if defined(CURVE_CORE_TRACE)
#include "cs_trace.h"
#elif defined(CURVE_CORE_PREDICT)
#include "cs_predict.h"
#elif defined(CURVE_CORE_FD3)
#include "cs_fd3.h"
#else
#include "cs_fd.h"
#endif

volatile int32_t sink;
volatile cs_pos_t in[12];
volatile int method;

void *memcpy(void *restrict d, const void *restrict s, size_t n);
void *memset(void *d, int c, size_t n);
void *memmove(void *d, const void *s, size_t n);
void *memcpy(void *restrict d, const void *restrict s, size_t n)
{
    uint8_t *dp = d;
    const uint8_t *sp = s;
    while (n--)
        *dp++ = *sp++;
    return d;
}
void *memmove(void *d, const void *s, size_t n)
{
    uint8_t *dp = d;
    const uint8_t *sp = s;
    if (dp < sp) {
        while (n--)
            *dp++ = *sp++;
    } else {
        while (n--)
            dp[n] = sp[n];
    }
    return d;
}
void *memset(void *d, int c, size_t n)
{
    uint8_t *dp = d;
    while (n--)
        *dp++ = (uint8_t)c;
    return d;
}

int main(void);
int main(void)
{
    cs_vec3_t p[4];
    for (unsigned i = 0; i < 4; i++) {
        p[i].x = in[3 * i];
        p[i].y = in[3 * i + 1];
        p[i].z = in[3 * i + 2];
    }
    cs_bezier_t c;
    if (cs_bezier_init(&c, 3, p) != CS_OK)
        return 1;
    cs_vec3_t v;
#if defined(CURVE_CORE_TRACE)
    static cs_trace_t tr;
    if (cs_trace_begin(&tr, &c, 655, (cs_trace_method_t)method) != CS_OK)
        return 1;
    while (cs_trace_next(&tr, &v) == CS_OK)
        sink = v.x + v.y + v.z;
#elif defined(CURVE_CORE_PREDICT)
    static cs_predict_t pr;
    if (cs_predict_begin(&pr, &c, 655) != CS_OK)
        return 1;
    while (cs_predict_next(&pr, &v) == CS_OK)
        sink = v.x + v.y + v.z;
#elif defined(CURVE_CORE_FD3)
    static cs_fd3_t f3;
    static cs_vec3_t blk[16];
    size_t got;
    if (cs_fd3_begin(&f3, &c, 655) != CS_OK)
        return 1;
    while ((got = cs_fd3_fill(&f3, blk, 16)) != 0) {
        v = blk[got - 1];
        sink = v.x + v.y + v.z;
    }
#else
    static cs_fd_t f;
    if (cs_fd_begin(&f, &c, 655) != CS_OK)
        return 1;
    while (cs_fd_next(&f, &v) == CS_OK)
        sink = v.x + v.y + v.z;
#endif
    return 0;
}
