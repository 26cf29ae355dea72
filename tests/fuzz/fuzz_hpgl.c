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
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../../host/cs_conv.c"
#include "../../host/cs_err_text.c"
#include "../../host/cs_hpgl.c"
#include "../../host/cs_path.c"
#include "cs_trace.h"

#define FUZZ_CHECK(c)                                                                              \
    do {                                                                                           \
        if (!(c)) {                                                                                \
            fprintf(stderr, "fuzz_hpgl: check failed: %s (line %d)\n", #c, __LINE__);              \
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
        FUZZ_CHECK(e->kind == CS_PATH_LINE || e->kind == CS_PATH_CUBIC);
        FUZZ_CHECK(!c->rational && c->degree == (e->kind == CS_PATH_LINE ? 1 : 3));
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
    if (e != CS_OK) {
        FUZZ_CHECK(d.code == e && d.loc.line >= 1 && d.loc.col >= 1 && d.reason[0] != '\0');
        FUZZ_CHECK(strcmp(d.loc.file, "fuzz") == 0);
    }
    cs_err_t e2 = cs_hpgl_read("fuzz", (const char *)data, size, &o, &q, &d2);
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
};

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
    /* Real files (seeded from ../shared/data when it is there). */
    const char *dir = "../shared/data/hpgl";
    DIR *dp = opendir(dir);
    struct dirent *de;
    static char buf[1 << 20];
    while (dp && (de = readdir(dp)) != NULL) {
        if (de->d_name[0] == '.')
            continue;
        snprintf(name, sizeof name, "%s/%s", dir, de->d_name);
        FILE *f = fopen(name, "rb");
        if (!f)
            continue;
        size_t n = fread(buf, 1, sizeof buf, f);
        fclose(f);
        snprintf(name, sizeof name, "%s/data-%s", argv[1], de->d_name);
        FILE *g = fopen(name, "wb");
        if (!g)
            return 1;
        fwrite(buf, 1, n, g);
        fclose(g);
        LLVMFuzzerTestOneInput((const uint8_t *)buf, n);
    }
    if (dp)
        closedir(dp);
    return 0;
}
#endif
