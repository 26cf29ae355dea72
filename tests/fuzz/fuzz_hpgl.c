/* libFuzzer target: arbitrary bytes as an HP-GL / HP-GL/2 file into the host reader
 * (host/cs_hpgl.c), then the first elements it produces through the core tracer. Asserts (abort
 * = finding): no out-of-bounds access or undefined behaviour (ASan, UBSan); only the documented
 * status codes; a diagnostic always has a position inside the file (line >= 1, column >= 1), the
 * file's name and a reason; every element is a valid cs_bezier_t (a line, a cubic or a rational
 * quadratic arc piece with weights in range) inside +/-4096 mm and continuous with the previous
 * element of its subpath; reading is deterministic; tracing each element ends exactly on its
 * last control point. Built and run by scripts/fuzz.sh (host sources are compiled in below, as
 * the script links only the core). With -DCS_FUZZ_SEED_MAIN it writes a seed corpus into
 * argv[1]: the instruction forms below plus every file of ../shared/data/hpgl. */
#define _DEFAULT_SOURCE
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <string.h>

#define FUZZ_NAME "fuzz_hpgl"
#include "fuzz_common.h"

#include "../../host/cs_conv.c"
#include "../../host/cs_err_text.c"
#include "../../host/cs_hershey.c"
#include "../../host/cs_hpgl.c"
#include "../../host/cs_path.c"
#include "../../host/cs_readall.c"
#include "fuzz_path.h"

/* HP-GL makes lines (PD/PR/PA), cubics (BZ/BR) and arc pieces (CI/AA/AR), nothing else. */
static void check_kind(const cs_path_elem_t *e)
{
    const cs_bezier_t *c = &e->curve;
    FUZZ_CHECK(e->kind == CS_PATH_LINE || e->kind == CS_PATH_CUBIC);
    FUZZ_CHECK(!c->rational && c->degree == (e->kind == CS_PATH_LINE ? 1 : 3));
}

static void quiet(void *ctx, const cs_path_diag_t *w)
{
    (void)ctx;
    FUZZ_CHECK(w->loc.line >= 1 && w->loc.col >= 1 && w->reason[0] != '\0');
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    cs_hpgl_opts_t o;
    cs_hpgl_opts_init(&o);
    o.warn = quiet;
    cs_path_t p, q;
    cs_path_diag_t d, d2;
    cs_path_init(&p);
    cs_path_init(&q);
    memset(&d, 0, sizeof d);
    memset(&d2, 0, sizeof d2);
    cs_err_t e = cs_hpgl_read("fuzz", (const char *)data, size, &o, &p, &d);
    FUZZ_CHECK(e == CS_OK || e == CS_ERR_PARSE || e == CS_ERR_RANGE || e == CS_ERR_DEGENERATE ||
               e == CS_ERR_WEIGHT || e == CS_ERR_ARG);
    fuzz_check_diag(e, &d, true);
    cs_err_t e2 = cs_hpgl_read("fuzz", (const char *)data, size, &o, &q, &d2);
    fuzz_check_flat_reads(e, &d, &p, e2, &d2, &q, check_kind);
    cs_path_free(&p);
    cs_path_free(&q);
    return 0;
}

#ifdef CS_FUZZ_SEED_MAIN
static const char *const seeds[] = {
    "IN;SP1;PU0,0;PD400,0,400,400;PU;PA800,800;PD;PR100,0,0,100,-100,0;PA;PU0,0;SP0;",
    "IN;PU1000,1000;CI200;CI-100,5;PD;AA1000,1000,90;AR-100,0,-270,10;PU;",
    "IN;PA0,0;PD;BZ100,0,200,100,300,300,400,400,500,400,600,300;BR10,0,20,10,30,30;PU;",
    "in;pu 10 20 pd 30 40 -50 60;sp2 pa 1.5,2.5;pd 3.25,-4.75;",
    "IN;PE<=5?_:A7>2?_?_;",
    "IN;DT*;LBhello*PD100,100;SM*;PA1,1;SM;CO\"comment\";LT2;IW0,0,10,10;RO90;SC0,1,0,1;",
    "\x1b.(\x1b.I81;;17:\x1b%-1BIN;PD10,10;\x1b"
    "E",
    "IN;PD200000,0;",
    "IN;PD10;",
    "IN;AA0,0;",
    "IN;PD10,10@;",
    "IN;BZ1,2,3,4,5;",
    /* scaling, rotation, plot size, window; PE ended by the next instruction (AutoCAD) */
    "IN;IP1000,1000,5000,3000;SC0,100,0,50;PU0,0;PD100,50;SC0,100,0,100,1,0,100;CI10;",
    "IN;PS8000,6000;IR10,20,60,70;SC0,2,0,3,2;RO90;PU1,1;PD5,5;RO180;AR1,1,90;RO270;IP;SC;",
    "IN;IW1000,1000,2000,2000;PU0,1500;PD3000,1500;CI700;BZ1,2,3000,4,5,6;IW;DF;PD0,0;",
    "IN;SP1;PE7<=__?x__?x@x_PU0,0;PE<=\xbf\xbf_\xcb\xbfSP2;PD0,0;",
};

/* Real files too (seeded from ../shared/data when it is there). */
static const char *const seed_dirs[] = {"../shared/data/hpgl", NULL};

int main(int argc, char **argv)
{
    return fuzz_seed_main(argc, argv, seeds, sizeof seeds / sizeof seeds[0], seed_dirs);
}
#endif
