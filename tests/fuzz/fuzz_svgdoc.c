/* libFuzzer target: arbitrary bytes as an SVG document (or bare path data) into the host
 * reader (host/cs_svgdoc.c with expat, cs_svgpath for path data and shapes), then the first
 * elements it produces through the core tracer. Asserts (abort = finding): no out-of-bounds
 * access or undefined behaviour (ASan, UBSan), no leak; only the documented status codes; a
 * diagnostic always names the file and has a line and a reason (column 0 only for whole-file
 * I/O errors, which cannot happen here); every element is a valid cs_bezier_t inside
 * +/-4096 mm and continuous with the previous element of its subpath; reading is
 * deterministic; tracing each element ends exactly on its last control point. Built and run by
 * scripts/fuzz.sh (host sources are compiled in below, as the script links only the core).
 * fuzz-libs: -lexpat -lm
 * With -DCS_FUZZ_SEED_MAIN it writes a seed corpus into argv[1]: the documents below plus every
 * file of ../shared/data/svg/<dir>/ and of tests/data/svg/use/ (matplotlib glyphs by <use>,
 * an Illustrator-style class sheet, Inkscape clones). */
#define _DEFAULT_SOURCE
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <string.h>

#define FUZZ_NAME "fuzz_svgdoc"
#include "fuzz_common.h"

#include "../../host/cs_conv.c"
#include "../../host/cs_css.c"
#include "../../host/cs_err_text.c"
#include "../../host/cs_hershey.c"
#include "../../host/cs_path.c"
#include "../../host/cs_readall.c"
#include "../../host/cs_svgdoc.c"
#include "../../host/cs_svgpath.c"
#include "fuzz_path.h"

/* Lines, quadratics and cubics are polynomial Béziers of degree kind + 1. */
static void check_kind(const cs_path_elem_t *e)
{
    const cs_bezier_t *c = &e->curve;
    FUZZ_CHECK(e->kind <= CS_PATH_CUBIC);
    FUZZ_CHECK(!c->rational && c->degree == e->kind + 1);
}

static void quiet(void *ctx, const cs_path_diag_t *w)
{
    (void)ctx;
    FUZZ_CHECK(w->loc.line >= 1 && w->reason[0] != '\0');
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    cs_svgdoc_opts_t o;
    cs_svgdoc_opts_init(&o);
    o.warn = quiet;
    cs_path_t p, q;
    cs_path_diag_t d, d2;
    cs_svgdoc_stats_t s;
    cs_path_init(&p);
    cs_path_init(&q);
    memset(&d, 0, sizeof d);
    memset(&d2, 0, sizeof d2);
    cs_err_t e = cs_svgdoc_read((const char *)data, size, "fuzz", &o, &p, &d, &s);
    FUZZ_CHECK(e == CS_OK || e == CS_ERR_PARSE || e == CS_ERR_RANGE || e == CS_ERR_DEGENERATE ||
               e == CS_ERR_WEIGHT || e == CS_ERR_ARG);
    fuzz_check_diag(e, &d, false);
    cs_err_t e2 = cs_svgdoc_read((const char *)data, size, "fuzz", &o, &q, &d2, NULL);
    fuzz_check_flat_reads(e, &d, &p, e2, &d2, &q, check_kind);
    cs_path_free(&p);
    cs_path_free(&q);
    return 0;
}

#ifdef CS_FUZZ_SEED_MAIN
static const char *const seeds[] = {
    "<svg xmlns='http://www.w3.org/2000/svg' xmlns:x='http://www.w3.org/1999/xlink'>"
    "<switch><foreignObject><p xmlns='http://www.w3.org/1999/xhtml'>a</p></foreignObject>"
    "<text x='1' y='9'>Box</text><line x1='0' y1='0' x2='1' y2='1' stroke='black'/></switch>"
    "<switch><g requiredFeatures='x'/><text>Text is not SVG</text></switch>"
    "<switch id='s'><line systemLanguage='fr' x2='5' stroke='black'/>"
    "<line systemLanguage='en-US' y2='5' stroke='black'/><rect requiredExtensions='e' width='1' "
    "height='1'/></switch><use x:href='#s' x='10'/>"
    "<flowRoot><flowRegion><rect width='20' height='10'/></flowRegion><flowPara>f</flowPara>"
    "</flowRoot></svg>",
    "<svg xmlns='http://www.w3.org/2000/svg' width='100mm' height='50mm' viewBox='0 0 200 100'>"
    "<rect x='10' y='10' width='50' height='30' rx='5' stroke='black' fill='none'/>"
    "<circle cx='100' cy='50' r='20'/><ellipse cx='150' cy='50' rx='30' ry='10'/>"
    "<line x1='0' y1='0' x2='200' y2='100' stroke='red'/>"
    "<polyline points='0,0 10,10 20,0' stroke='blue'/><polygon points='30 30 40 40 50 30'/>"
    "</svg>",
    "<svg width='4in' height='3in' viewBox='-10 -10 20 30' preserveAspectRatio='xMaxYMin slice'>"
    "<g transform='rotate(30) skewX(10)' style='stroke:#000;fill:none'>"
    "<path d='M0 0 C 1 2 3 4 5 6 A 3 4 10 1 0 -5 -5 z'/></g>"
    "<svg x='5' y='5' width='50%' height='10' viewBox='0 0 1 1' preserveAspectRatio='none'>"
    "<rect width='1' height='1' ry='0.5'/></svg></svg>",
    "<svg width='210mm' height='297mm'><g display='none'><rect width='5' height='5'/></g>"
    "<g style='display:none'><circle r='4'/></g><g visibility='hidden'><circle r='1' "
    "visibility='visible'/></g><rect width='10pt' height='2pc' x='1cm' y='3px'/></svg>",
    "<svg><defs><path d='M0 0L1 1'/></defs><text>hi</text><use href='#a'/>"
    "<rect width='-1' height='2'/></svg>",
    "<svg><polygon points='1 2 3'/></svg>",
    "<svg xmlns:xlink='http://www.w3.org/1999/xlink'><use xlink:href='#g' x='5' "
    "transform='rotate(9)'/><g id='g'><line x2='1' stroke='red'/><use href='#s' width='4' "
    "height='9'/></g><symbol id='s' viewBox='1 2 3 4' preserveAspectRatio='xMaxYMin slice'>"
    "<path d='M0 0L1 1' stroke='red'/><use href='#n'/></symbol><defs><svg id='n' "
    "viewBox='0 0 1 1'><circle r='1'/></svg></defs><use href='#u' id='u'/><use href='#g'/>"
    "<use href='x.svg#a'/><use href='#missing'/></svg>",
    "<svg><defs><g id='a'><use href='#b'/><use href='#b'/><use href='#b'/></g><g id='b'>"
    "<use href='#c'/><use href='#c'/></g><g id='c'><line x2='1' stroke='red'/></g></defs>"
    "<use href='#a'/></svg>",
    "<svg><style type='text/css'><![CDATA[@import url(a.css); @media print{g{x:y}}"
    ".st0{fill:none;stroke:#000;stroke-width:0.5} .st1,.st2{display:none} #i{stroke:none!"
    "important} g.k > line , svg g line{visibility:hidden} *{font-size:3px} line:hover{} "
    "li%ne{} a b c d e f g h i j k l m n o p q{}  /* c */ rect{stroke red]]></style>"
    "<g class='k'><line class='st0 st1' x2='3'/><line id='i' style='stroke:red !important'/>"
    "</g><rect class='st2' width='1' height='1'/><text class='st0'>x</text></svg>",
    "<svg viewBox='0 0 0 1'/>",
    "M 10 10 L 20 20",
};

static const char *const seed_dirs[] = {"../shared/data/svg/resvg_path_tests",
                                        "../shared/data/svg/w3c_svg11_paths", "tests/data/svg/use",
                                        NULL};

int main(int argc, char **argv)
{
    return fuzz_seed_main(argc, argv, seeds, sizeof seeds / sizeof seeds[0], seed_dirs);
}
#endif
