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
 * file of ../shared/data/svg/<dir>/. */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../../host/cs_conv.c"
#include "../../host/cs_err_text.c"
#include "../../host/cs_path.c"
#include "../../host/cs_svgdoc.c"
#include "../../host/cs_svgpath.c"
#include "cs_trace.h"

#define FUZZ_CHECK(c)                                                                              \
    do {                                                                                           \
        if (!(c)) {                                                                                \
            fprintf(stderr, "fuzz_svgdoc: check failed: %s (line %d)\n", #c, __LINE__);            \
            abort();                                                                               \
        }                                                                                          \
    } while (0)

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
        FUZZ_CHECK(e->kind <= CS_PATH_CUBIC);
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
    if (e != CS_OK) {
        FUZZ_CHECK(d.code == e && d.loc.line >= 1 && d.reason[0] != '\0');
        FUZZ_CHECK(strcmp(d.loc.file, "fuzz") == 0);
    }
    cs_err_t e2 = cs_svgdoc_read((const char *)data, size, "fuzz", &o, &q, &d2, NULL);
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
static const char *const seeds[] = {
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
    "<svg viewBox='0 0 0 1'/>",
    "M 10 10 L 20 20",
};

static void seed_dir(const char *dir, const char *out, int *k)
{
    DIR *dp = opendir(dir);
    if (!dp)
        return;
    struct dirent *de;
    static char buf[1 << 20];
    char name[4096];
    while ((de = readdir(dp)) != NULL) {
        if (de->d_name[0] == '.')
            continue;
        snprintf(name, sizeof name, "%s/%s", dir, de->d_name);
        FILE *f = fopen(name, "rb");
        if (!f)
            continue;
        size_t n = fread(buf, 1, sizeof buf, f);
        fclose(f);
        snprintf(name, sizeof name, "%s/data-%03d", out, (*k)++);
        FILE *g = fopen(name, "wb");
        if (!g)
            continue;
        fwrite(buf, 1, n, g);
        fclose(g);
        LLVMFuzzerTestOneInput((const uint8_t *)buf, n);
    }
    closedir(dp);
}

int main(int argc, char **argv)
{
    if (argc < 2)
        return 2;
    char name[4096];
    for (size_t i = 0; i < sizeof seeds / sizeof seeds[0]; i++) {
        snprintf(name, sizeof name, "%s/seed-%02zu", argv[1], i);
        FILE *f = fopen(name, "wb");
        if (!f)
            return 1;
        fwrite(seeds[i], 1, strlen(seeds[i]), f);
        fclose(f);
        LLVMFuzzerTestOneInput((const uint8_t *)seeds[i], strlen(seeds[i]));
    }
    int k = 0;
    seed_dir("../shared/data/svg/resvg_path_tests", argv[1], &k);
    seed_dir("../shared/data/svg/w3c_svg11_paths", argv[1], &k);
    return 0;
}
#endif
