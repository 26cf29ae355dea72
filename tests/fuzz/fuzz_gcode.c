/* libFuzzer target: arbitrary bytes as G-code into the host reader (host/cs_gcode.c), strict and
 * lenient (one input in four in Grbl's dialect), with LinuxCNC's parameters, expressions and
 * O-word control flow (loops bounded by FUZZ_MAX_LOOPS), then the first elements it produces
 * through the core tracer. Asserts (abort =
 * finding): no out-of-bounds access or undefined behaviour (ASan, UBSan); only the documented
 * status codes; a diagnostic always has a line >= 1, a column >= 1 and a reason; every element
 * is a valid cs_bezier_t (degree 1..3; rational only for arc pieces and NURBS segments, weights
 * in range) inside +/-4096 mm; each element starts exactly where the previous one ended (G-code
 * moves are continuous); a lenient read never fails where a strict one succeeds and then yields
 * the same elements; parsing is deterministic; tracing ends on the last control point.
 * Built and run by scripts/fuzz.sh (host sources are compiled in below, as the script links
 * only the core). Seeds: tests/fuzz/corpus_gcode/ (copies of shared/data/gcode) and, with
 * -DCS_FUZZ_SEED_MAIN, the list below written into argv[1]. */
#include <stdint.h>
#include <string.h>

#define FUZZ_NAME "fuzz_gcode"
#include "fuzz_common.h"

#include "../../host/cs_conv.c"
#include "../../host/cs_err_text.c"
#include "../../host/cs_gcode.c"
#include "../../host/cs_gcode_arc.c"
#include "../../host/cs_gcode_cycle.c"
#include "../../host/cs_gcode_nurbs.c"
#include "../../host/cs_gcode_wcs.c"
#include "../../host/cs_gcode_words.c"
#include "../../host/cs_gexpr.c"
#include "../../host/cs_gflow.c"
#include "../../host/cs_gnurbs.c"
#include "../../host/cs_path.c"
#include "fuzz_path.h"

/* Elements allowed per job (keeps a many-turn helix per line from exhausting memory; the reader
 * refuses more with CS_ERR_FULL). */
#define FUZZ_MAX_ELEMS 100000
/* O-word loop passes allowed per input (a runaway loop ends quickly, as a located error). */
#define FUZZ_MAX_LOOPS 20000

static void quiet(void *ctx, const cs_path_diag_t *w)
{
    (void)ctx;
    FUZZ_CHECK(w->loc.line >= 1 && w->loc.col >= 1 && w->reason[0] != '\0');
}

static void check_curve(const cs_path_elem_t *e)
{
    const cs_bezier_t *c = &e->curve;
    FUZZ_CHECK(e->loc.line >= 1 && e->loc.col >= 1);
    FUZZ_CHECK(c->degree >= 1 && c->degree <= 3);
    if (c->rational) {
        FUZZ_CHECK(e->kind == CS_PATH_ARC || e->kind == CS_PATH_OTHER);
        for (unsigned i = 0; i <= c->degree; i++)
            FUZZ_CHECK(c->w[i] >= CS_WEIGHT_MIN && c->w[i] <= CS_WEIGHT_ONE);
    }
    if (e->kind == CS_PATH_ARC)
        FUZZ_CHECK(c->degree == 2 && c->rational);
    for (unsigned i = 0; i <= c->degree; i++)
        FUZZ_CHECK(cs_fixed_vec_ok(&c->p[i]));
    FUZZ_CHECK(e->feed_mm_s >= 0 && (!e->rapid || e->feed_mm_s == 0));
}

/* FNV-1a over the fields that matter (struct padding is not hashed). */
static uint64_t hash_path(const cs_path_t *p)
{
    uint64_t h = 1469598103934665603ull;
#define MIX(v)                                                                                     \
    do {                                                                                           \
        h ^= (uint64_t)(v);                                                                        \
        h *= 1099511628211ull;                                                                     \
    } while (0)
    MIX(p->n);
    for (size_t i = 0; i < p->n; i++) {
        const cs_bezier_t *c = &p->elems[i].curve;
        MIX(c->degree);
        MIX(c->rational);
        for (unsigned k = 0; k <= c->degree && k < CS_BEZIER_MAX_POINTS; k++) {
            MIX((uint32_t)c->p[k].x);
            MIX((uint32_t)c->p[k].y);
            MIX((uint32_t)c->p[k].z);
            MIX(c->rational ? (uint32_t)c->w[k] : 0u);
        }
        MIX(p->elems[i].subpath);
        MIX(p->elems[i].rapid);
        MIX(p->elems[i].loc.line);
        MIX(p->elems[i].loc.col);
    }
#undef MIX
    return h;
}

static cs_err_t run(const uint8_t *data, size_t size, bool lenient, cs_path_diag_t *d,
                    uint64_t *hash, size_t *n)
{
    cs_gcode_opts_t o;
    cs_gcode_opts_init(&o);
    o.lenient = lenient;
    o.max_elements = FUZZ_MAX_ELEMS;
    o.max_loops = FUZZ_MAX_LOOPS;
    o.dialect = size % 4 == 1 ? CS_GCODE_GRBL : CS_GCODE_LINUXCNC;
    o.start_inch = size % 7 == 3;
    /* One input in three also moves Z on M3/M4/M5 (the pen heights of a plotter). */
    o.pen_z = size % 3 == 0;
    o.pen_down_z_mm = -1.0;
    o.pen_up_z_mm = 2.0;
    o.warn = quiet;
    cs_path_t p;
    cs_path_init(&p);
    memset(d, 0, sizeof *d);
    cs_err_t e = cs_gcode_read("fuzz", (const char *)data, size, &o, &p, d, NULL);
    FUZZ_CHECK(e == CS_OK || e == CS_ERR_PARSE || e == CS_ERR_UNSUPPORTED || e == CS_ERR_RANGE ||
               e == CS_ERR_DEGENERATE || e == CS_ERR_WEIGHT || e == CS_ERR_KNOTS ||
               e == CS_ERR_OVERFLOW || e == CS_ERR_FULL);
    fuzz_check_diag(e, d, true);
    for (size_t i = 0; i < p.n; i++) {
        check_curve(&p.elems[i]);
        if (i > 0) {
            const cs_bezier_t *a = &p.elems[i - 1].curve;
            const cs_vec3_t *end = &a->p[a->degree], *start = &p.elems[i].curve.p[0];
            FUZZ_CHECK(end->x == start->x && end->y == start->y && end->z == start->z);
            FUZZ_CHECK(p.elems[i].subpath >= p.elems[i - 1].subpath);
        }
        if (i < FUZZ_TRACE_ELEMS && !lenient)
            fuzz_trace(&p.elems[i].curve);
    }
    *hash = hash_path(&p);
    *n = p.n;
    cs_path_free(&p);
    return e;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    cs_path_diag_t d, d2, dl;
    uint64_t h, h2, hl;
    size_t n, n2, nl;
    cs_err_t e = run(data, size, false, &d, &h, &n);
    /* Deterministic: the same answer, the same elements. */
    cs_err_t e2 = run(data, size, false, &d2, &h2, &n2);
    FUZZ_CHECK(e2 == e && h2 == h && n2 == n);
    if (e != CS_OK)
        FUZZ_CHECK(d2.loc.line == d.loc.line && d2.loc.col == d.loc.col);
    /* Lenient only turns refusals into warnings: a strict success reads the same. */
    cs_err_t el = run(data, size, true, &dl, &hl, &nl);
    if (e == CS_OK)
        FUZZ_CHECK(el == CS_OK && hl == h && nl == n);
    return 0;
}

#ifdef CS_FUZZ_SEED_MAIN
/* Seeds: every word this reader carries out, modes, and a few errors of each kind. */
static const char *const seeds[] = {
    "G21 G90 G17\nG0 X1 Y2 Z3\nG1 X10 Y0 F600\nG2 X0 Y10 I-10 J0\nG3 X10 Y0 R10\nM2\n",
    "G20 G91 G1 X1 Y1 F60\nX1\nG90 G18 G2 X0 Z1 I-1 K0\nG19 G3 Y1 Z0 J0 K-1\n",
    "G1 X10 Y0 F60\nG3 X10 Y0 Z5 I-10 J0 P3\nG2 X0 Y10 R-10\n",
    "G1 X0 Y0 F60\nG5 I0 J3 P0 Q-3 X1 Y1\nG5 P0 Q-3 X2 Y2\nG0 X-2 Y4\nG5.1 X2 I2 J-8\n",
    "G0 X0 Y0\nF10\nG5.2 X0 Y1 P1 L3\nX2 Y2 P1\nX2 Y0 P1\nX0 Y0 P2\nG5.3\n",
    "G5.2 X2 Y5 P0.5 L4\nX6 Y6 P3\nX9 Y2 P1.5\nX12 Y4 P1\nG5.3\n",
    "%\nN10 G92 X10 Y10 (set)\nN20 G1 X11 Y12 F100 ; go\n/G1 X100\nG92.1\nM3 S100\nM5\n%\n",
    "N1 G1 X1 F60*29\nN2 G1 X2*30\n",
    "G90.1 G1 X12 Y2 F60\nG3 X2 Y12 I2 J2\nG91.1 G2 X12 Y2 I-10 J0\n",
    "G1 X1 F60\nG2 X2 Y0 R0\n",
    "G4 P1\nT1 M6\nG1 X#1\n",
    "G1 X5000\n",
    "G1 X10 F1\nG2 X0 Y11 I-10\n",
    "G1 (unclosed\n",
    "#3=15\n#3=6 G1 x#3 F60\n#<_a>=[2**3 MOD 5]\nG1 Y[#<_a>*SIN[30]+ATAN[1]/[1]-FIX[-2.5]]\n",
    "#1=[1 EQ 1 AND 2 GT 1 OR 0 XOR 1]\nG1 X[ROUND[2.5]+FUP[0.1]+ABS[-1]+SQRT[4]+EXP[0]+LN[1]] "
    "F9\n",
    "o<sq> sub\nG1 X#1 Y0\nG1 X#1 Y#1\no<sq> endsub\nF60\no<sq> call [10]\no<sq> call [5]\n",
    "F60\n#1=1\no1 while [#1 LT 4]\nG1 X#1\n#1=[#1+1]\no1 endwhile\no2 repeat [2]\nG91 X1\n"
    "o2 endrepeat\nG90\n#2=0\no3 do\n#2=[#2+1]\no4 if [#2 EQ 2]\no3 continue\no4 elseif [#2 GT "
    "3]\no3 break\no4 else\nG1 Y#2\no4 endif\no3 while [#2 LT 9]\n",
    "o2 sub\no3 if [#1 GT 0]\nG91 G1 X1 F60\no2 call [#1-1]\no3 endif\no2 return [#1*2]\n"
    "o2 endsub\no2 call [4]\nG90 G1 Y#<_value>\n",
    "o1 while [1]\nG91 G1 X0.001 F1\no1 endwhile\n",
    "G18 G0 Z0 X0\nF10\nG5.2 Z0 X1 P1 L3\nZ2 X2 P1\nZ2 X0 P1\nZ0 X0 P2\nG5.3\nG19 G5.2 Y1 Z1 P1\n"
    "Y2 Z0 P1\nG5.3\n",
    "F60\nG6.2 P4 K0 X0 Y0\nK0 X1 Y4 R2\nK0 X5 Y5\nK0 X8 Y1 R0.5\nK1 X9 Y3\nK3\nK3\nK3\nK3\n"
    "G1 X1\n",
    "G64 P0.01 Q0.005\nG61\nG1 X1e3 F60\n",
    "G90 G94\nG17\nG21\nX10 Y5\nG1 Z-1 F300\nG2 X20 Y5 I5 J0\nM8\nM9\nM30\n",
    "G0 X100\nG3 X0 Y100.09 I-100 F100\nG0 X4000 Y0\nG3 X0 Y4002.9 I-4000\n",
    "G81 X1 Y1 Z-1 R1 F100\nX2 Y2\nG80\nG38.2 Z-5\n",
    "G0 Z5\nG99 G83 X1 Y2 Z-3 R1 Q1.5 F100\nX3\nG98 G73 Y4 Z-2 R1 Q0.7\nG91 G81 X1 R-1 Z-1 L3\n",
    "G20 G0 X1.5 Y0 Z0\nG91 G81 R.1 Z-.5 ^60 L6 F10\nG90 G1 @.5 ^90\nG91 ^90\n@.1\n"
    "G3 @1 ^45 R2\n",
    "\xef\xbb\xbfG17 G2 X1 Y1 I1 J0 K0 F60\n",
};

int main(int argc, char **argv)
{
    return fuzz_seed_main(argc, argv, seeds, sizeof seeds / sizeof seeds[0], NULL);
}
#endif
