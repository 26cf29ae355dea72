/* libFuzzer target: arbitrary bytes as an AutoCAD DXF file into the host reader (host/cs_dxf.c,
 * with cs_gnurbs, the core's cs_nurbs and cs_spline behind its SPLINEs), then the first elements
 * it produces through the core tracer. Asserts (abort = finding): no out-of-bounds access or
 * undefined behaviour (ASan, UBSan); only the documented status codes; a diagnostic always has a
 * position inside the file (line >= 1, column >= 1), the file's name and a reason; every element
 * is a valid cs_bezier_t (a line, an arc piece with weights in range, a spline segment of degree
 * 1..3) inside +/-4096 mm, z 0, continuous with the previous element of its subpath; reading is
 * deterministic; tracing each element ends exactly on its last control point. Text is laid
 * out in share/fonts/futural.jhf when it is found. Built and run by
 * scripts/fuzz.sh (host sources are compiled in below, as the script links only the core). With
 * -DCS_FUZZ_SEED_MAIN it writes a seed corpus into argv[1]: the entity forms below and the files
 * of tests/data/dxf. */
#define _DEFAULT_SOURCE
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <string.h>

#define FUZZ_NAME "fuzz_dxf"
#include "fuzz_common.h"

#include "../../host/cs_conv.c"
#include "../../host/cs_dxf.c"
#include "../../host/cs_err_text.c"
#include "../../host/cs_gnurbs.c"
#include "../../host/cs_hershey.c"
#include "../../host/cs_path.c"
#include "../../host/cs_readall.c"
#include "fuzz_path.h"

/* DXF makes lines, arc pieces, spline segments (B-spline, NURBS, natural) of degree 1..3. */
static void check_kind(const cs_path_elem_t *e)
{
    const cs_bezier_t *c = &e->curve;
    if (e->kind == CS_PATH_LINE)
        FUZZ_CHECK(!c->rational && c->degree == 1);
    else
        FUZZ_CHECK((e->kind == CS_PATH_BSPLINE || e->kind == CS_PATH_NURBS ||
                    e->kind == CS_PATH_NATURAL) &&
                   c->degree >= 1 && c->degree <= 3);
}

static void quiet(void *ctx, const cs_path_diag_t *w)
{
    (void)ctx;
    FUZZ_CHECK(w->loc.line >= 1 && w->loc.col >= 1 && w->reason[0] != '\0');
}

/* The shipped stroke font (run from the repository root, as scripts/fuzz.sh does), so that
 * TEXT, MTEXT and ATTRIB are laid out too; without it they are skipped. */
static const cs_hershey_font_t *fuzz_font(void)
{
    static cs_hershey_font_t f;
    static int state; /* 0 not tried, 1 loaded, -1 none */
    if (state == 0) {
        cs_path_diag_t d;
        state = cs_hershey_load("share/fonts/futural.jhf", &f, &d) == CS_OK ? 1 : -1;
    }
    return state == 1 ? &f : NULL;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    cs_dxf_opts_t o;
    cs_dxf_opts_init(&o);
    o.warn = quiet;
    o.font = fuzz_font();
    cs_path_t p, q;
    cs_path_diag_t d, d2;
    cs_path_init(&p);
    cs_path_init(&q);
    memset(&d, 0, sizeof d);
    memset(&d2, 0, sizeof d2);
    cs_err_t e = cs_dxf_read("fuzz", (const char *)data, size, &o, &p, &d);
    FUZZ_CHECK(e == CS_OK || e == CS_ERR_PARSE || e == CS_ERR_RANGE || e == CS_ERR_DEGENERATE ||
               e == CS_ERR_WEIGHT || e == CS_ERR_ARG || e == CS_ERR_KNOTS || e == CS_ERR_DEGREE ||
               e == CS_ERR_OVERFLOW);
    fuzz_check_diag(e, &d, true);
    cs_err_t e2 = cs_dxf_read("fuzz", (const char *)data, size, &o, &q, &d2);
    fuzz_check_flat_reads(e, &d, &p, e2, &d2, &q, check_kind);
    cs_path_free(&p);
    cs_path_free(&q);
    return 0;
}

#ifdef CS_FUZZ_SEED_MAIN
#define SEC(s) "0\nSECTION\n2\nENTITIES\n" s "0\nENDSEC\n0\nEOF\n"
static const char *const seeds[] = {
    SEC("0\nLINE\n10\n0\n20\n0\n11\n10\n21\n5\n0\nCIRCLE\n10\n3\n20\n4\n40\n2\n"),
    SEC("0\nARC\n10\n1\n20\n2\n40\n3\n50\n30\n51\n300\n210\n0\n220\n0\n230\n-1\n"),
    SEC("0\nELLIPSE\n10\n6\n20\n2\n11\n8\n21\n3\n40\n0.5\n41\n0.3\n42\n4.0\n"),
    SEC("0\nLWPOLYLINE\n90\n3\n70\n1\n10\n0\n20\n0\n42\n0.5\n10\n10\n20\n0\n42\n-"
        "1\n10\n9\n20\n9\n"),
    SEC("0\nPOLYLINE\n70\n1\n0\nVERTEX\n10\n0\n20\n0\n42\n1\n0\nVERTEX\n10\n4\n20\n0\n0\nSEQEND\n"),
    SEC("0\nSPLINE\n71\n3\n40\n0\n40\n1\n40\n2\n40\n3\n40\n4\n40\n5\n40\n6\n40\n7\n40\n8\n"
        "10\n0\n20\n0\n10\n1\n20\n2\n10\n3\n20\n0\n10\n4\n20\n2\n10\n5\n20\n0\n"),
    SEC("0\nSPLINE\n70\n4\n71\n2\n40\n0\n40\n0\n40\n0\n40\n1\n40\n1\n40\n1\n41\n1\n41\n3\n41\n1\n"
        "10\n0\n20\n0\n10\n1\n20\n2\n10\n3\n20\n0\n"),
    SEC("0\nSPLINE\n71\n3\n74\n3\n11\n0\n21\n0\n11\n1\n21\n2\n11\n3\n21\n0\n"),
    "0\nSECTION\n2\nHEADER\n9\n$INSUNITS\n70\n1\n0\nENDSEC\n0\nSECTION\n2\nTABLES\n0\nTABLE\n2\n"
    "LAYER\n0\nLAYER\n2\nOFF\n62\n-1\n70\n0\n0\nENDTAB\n0\nENDSEC\n0\nSECTION\n2\nBLOCKS\n0\n"
    "BLOCK\n2\nB\n10\n1\n20\n1\n0\nLINE\n11\n3\n0\nINSERT\n2\nC\n0\nENDBLK\n0\nBLOCK\n2\nC\n0\n"
    "CIRCLE\n40\n1\n0\nENDBLK\n0\nENDSEC\n" SEC("0\nINSERT\n2\nB\n10\n5\n20\n5\n41\n2\n50\n30\n70\n"
                                                "2\n71\n2\n44\n3\n45\n4\n0\nLINE\n8\nOFF\n11\n1\n"),
    SEC("0\nTEXT\n10\n0\n20\n0\n40\n3\n1\nAB%%d\n72\n1\n11\n5\n21\n0\n0\nMTEXT\n10\n0\n20\n9\n40\n"
        "2\n1\n{\\fA|b0;x}\\Py\n0\nHATCH\n0\nPOINT\n0\nDIMENSION\n2\n*D\n0\nLEADER\n10\n0\n20\n0\n"
        "10\n3\n20\n3\n"),
    "AutoCAD Binary DXF\r\n\x1a",
    "0\nSECTION\n2\nENTITIES\n0\nLINE\n10\nx\n",
};

static const char *const seed_dirs[] = {"tests/data/dxf", NULL};

int main(int argc, char **argv)
{
    return fuzz_seed_main(argc, argv, seeds, sizeof seeds / sizeof seeds[0], seed_dirs);
}
#endif
