/* libFuzzer target: arbitrary bytes as SVG path data into the host parser (host/cs_svgpath.c),
 * then the first elements it produces through the core tracer. Asserts (abort = finding): no
 * out-of-bounds access or undefined behaviour (ASan, UBSan); only the documented status codes;
 * a diagnostic always has a position inside the data (line >= 1, column >= 1) and a reason;
 * every element is a valid cs_bezier_t (degree 1..3 polynomial, or a rational quadratic arc
 * piece with weights in range), inside +/-4096 mm, continuous with the previous element of its
 * subpath; parsing is deterministic; tracing each element ends exactly on its last control
 * point. Built and run by scripts/fuzz.sh (host sources are compiled in below, as the script
 * links only the core). With -DCS_FUZZ_SEED_MAIN it writes a seed corpus into argv[1]. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../../host/cs_conv.c"
#include "../../host/cs_err_text.c"
#include "../../host/cs_path.c"
#include "../../host/cs_svgpath.c"
#include "cs_trace.h"

#define FUZZ_CHECK(c)                                                                              \
    do {                                                                                           \
        if (!(c)) {                                                                                \
            fprintf(stderr, "fuzz_svgpath: check failed: %s (line %d)\n", #c, __LINE__);           \
            abort();                                                                               \
        }                                                                                          \
    } while (0)

/* Elements traced per input, and vertices allowed per element (a 0.01 mm tolerance on a curve
 * inside the 8192 mm square needs far fewer). */
#define FUZZ_TRACE_ELEMS 8
#define FUZZ_TRACE_MAX   200000

static void check_curve(const cs_path_elem_t *e)
{
    const cs_bezier_t *c = &e->curve;
    FUZZ_CHECK(e->loc.line >= 1 && e->loc.col >= 1);
    if (e->kind == CS_PATH_ARC) {
        FUZZ_CHECK(c->degree == 2 && c->rational);
        for (unsigned i = 0; i <= 2; i++)
            FUZZ_CHECK(c->w[i] >= CS_WEIGHT_MIN && c->w[i] <= CS_WEIGHT_ONE);
    } else {
        FUZZ_CHECK(!c->rational && c->degree == e->kind + 1);
    }
    for (unsigned i = 0; i <= c->degree; i++)
        FUZZ_CHECK(cs_fixed_vec_ok(&c->p[i]) && c->p[i].z == 0);
}

static void trace(const cs_bezier_t *c)
{
    cs_trace_t tr;
    cs_pos_t tol = CS_POS_ONE_MM / 100;
    FUZZ_CHECK(cs_trace_begin(&tr, c, tol, CS_TRACE_SUBDIV) == CS_OK);
    cs_vec3_t pt, last = c->p[0];
    cs_err_t e;
    unsigned n = 0;
    while ((e = cs_trace_next(&tr, &pt)) == CS_OK) {
        last = pt;
        FUZZ_CHECK(++n <= FUZZ_TRACE_MAX);
    }
    FUZZ_CHECK(e == CS_END);
    const cs_vec3_t *end = &c->p[c->degree];
    FUZZ_CHECK(n == 0 || (last.x == end->x && last.y == end->y && last.z == end->z));
}

/* Field by field (struct padding is not copied by assignment, so no memcmp). */
static bool same_curve(const cs_bezier_t *a, const cs_bezier_t *b)
{
    if (a->degree != b->degree || a->rational != b->rational)
        return false;
    for (unsigned i = 0; i <= a->degree && i < CS_BEZIER_MAX_POINTS; i++)
        if (a->p[i].x != b->p[i].x || a->p[i].y != b->p[i].y || a->p[i].z != b->p[i].z ||
            (a->rational && a->w[i] != b->w[i]))
            return false;
    return true;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    cs_svgpath_opts_t o;
    cs_svgpath_opts_init(&o, "fuzz");
    cs_path_t p, q;
    cs_path_diag_t d, d2;
    cs_path_init(&p);
    cs_path_init(&q);
    memset(&d, 0, sizeof d);
    memset(&d2, 0, sizeof d2);
    cs_err_t e = cs_svgpath_parse((const char *)data, size, &o, &p, &d);
    FUZZ_CHECK(e == CS_OK || e == CS_ERR_PARSE || e == CS_ERR_RANGE || e == CS_ERR_DEGENERATE ||
               e == CS_ERR_WEIGHT || e == CS_ERR_ARG);
    if (e != CS_OK) {
        FUZZ_CHECK(d.code == e && d.loc.line >= 1 && d.loc.col >= 1 && d.reason[0] != '\0');
        FUZZ_CHECK(strcmp(d.loc.file, "fuzz") == 0);
    }
    /* Deterministic: the same answer, the same elements. */
    cs_err_t e2 = cs_svgpath_parse((const char *)data, size, &o, &q, &d2);
    FUZZ_CHECK(e2 == e && q.n == p.n);
    if (e != CS_OK)
        FUZZ_CHECK(d2.loc.line == d.loc.line && d2.loc.col == d.loc.col);
    for (size_t i = 0; i < p.n; i++) {
        FUZZ_CHECK(same_curve(&p.elems[i].curve, &q.elems[i].curve));
        check_curve(&p.elems[i]);
        if (i > 0 && p.elems[i].subpath == p.elems[i - 1].subpath) {
            const cs_bezier_t *a = &p.elems[i - 1].curve;
            const cs_vec3_t *end = &a->p[a->degree], *start = &p.elems[i].curve.p[0];
            FUZZ_CHECK(end->x == start->x && end->y == start->y);
        }
        if (i > 0)
            FUZZ_CHECK(p.elems[i].subpath >= p.elems[i - 1].subpath);
        if (i < FUZZ_TRACE_ELEMS)
            trace(&p.elems[i].curve);
    }
    cs_path_free(&p);
    cs_path_free(&q);
    return 0;
}

#ifdef CS_FUZZ_SEED_MAIN
/* Seeds: every command form, numbers in every legal form, and a few errors. */
static const char *const seeds[] = {
    "M10 20 L30 40 l5 -5 H 50 h 5 V 10 v 5 Z",
    "m 30 40 110 120 -20 -130 z m 5 5 1 1",
    "M 30 40 C 16 137 171 45 100 90 S 171 45 180 155 s 10 10 20 0",
    "M 30 40 Q 171 45 100 90 T 160 180 t 10 10 q 1 2 3 4",
    "M 30 40 A 40 30 20 1 1 150 100 a1 1 0 00 1 1 A 0 5 0 0 1 9 9",
    "M1e1-2e-1L.5.5l+1.5E+1-.25 L1. 2.,3e0,4E-0",
    "M 4090 0 A 100 100 0 0 0 4090 150",
    "M 0 0 A 5000 100 0 0 1 100 10",
    "M 10 10 L 20 x",
    "A 5 5 0 0 1 50 50",
    "M 5000 0",
};

int main(int argc, char **argv)
{
    if (argc < 2)
        return 2;
    for (size_t i = 0; i < sizeof seeds / sizeof seeds[0]; i++) {
        char name[4096];
        snprintf(name, sizeof name, "%s/seed-%02zu", argv[1], i);
        FILE *f = fopen(name, "wb");
        if (!f)
            return 1;
        fwrite(seeds[i], 1, strlen(seeds[i]), f);
        fclose(f);
        LLVMFuzzerTestOneInput((const uint8_t *)seeds[i], strlen(seeds[i]));
    }
    return 0;
}
#endif
