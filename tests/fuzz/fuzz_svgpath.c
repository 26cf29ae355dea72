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
#include <string.h>

#define FUZZ_NAME "fuzz_svgpath"
#include "fuzz_common.h"

#include "../../host/cs_conv.c"
#include "../../host/cs_err_text.c"
#include "../../host/cs_path.c"
#include "../../host/cs_svgpath.c"
#include "fuzz_path.h"

/* Lines, quadratics and cubics are polynomial Béziers of degree kind + 1. */
static void check_kind(const cs_path_elem_t *e)
{
    const cs_bezier_t *c = &e->curve;
    FUZZ_CHECK(!c->rational && c->degree == e->kind + 1);
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
    fuzz_check_diag(e, &d, true);
    /* Deterministic: the same answer, the same elements. */
    cs_err_t e2 = cs_svgpath_parse((const char *)data, size, &o, &q, &d2);
    fuzz_check_flat_reads(e, &d, &p, e2, &d2, &q, check_kind);
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
    return fuzz_seed_main(argc, argv, seeds, sizeof seeds / sizeof seeds[0], NULL);
}
#endif
