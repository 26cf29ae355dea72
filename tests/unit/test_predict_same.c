/* test_predict_same: the host's cs_predict (the library's: speed build, 64-bit paths, shift
 * guess, closed-form begin, one-chord curves without their test) traces the same vertices as the
 * code every firmware image runs. That code is cs_predict.c built here with CS_PREDICT_SPEED 0
 * (what -Os selects) and CS_PREDICT_PORTABLE 1 (no 128-bit arithmetic), its four public functions
 * renamed fw_*, beside the library's. Curves: random polynomial curves of degree 1 to 3 from
 * 1 um to 4 m across, curves on one line (folds, P0 = P2, P2 = P3), single points, P0 = P1
 * starts, coordinates at the limit, and conic arcs; tolerances from the smallest accepted to
 * 64 mm. Every begin code, vertex and end code must agree. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "cs_predict.h" /* the library's prototypes, before the renames below */

#define CS_PREDICT_SPEED       0
#define CS_PREDICT_PORTABLE    1
#define cs_predict_accepts     fw_predict_accepts
#define cs_predict_begin       fw_predict_begin
#define cs_predict_begin_conic fw_predict_begin_conic
#define cs_predict_next        fw_predict_next
#include "../../firmware/core/cs_predict.c"
#undef cs_predict_accepts
#undef cs_predict_begin
#undef cs_predict_begin_conic
#undef cs_predict_next

#define MAX_VERTS 200000
#define N_CURVES  20000

static uint64_t rng = 0x9E3779B97F4A7C15ull;

static uint64_t next_u64(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

/* Uniform integer in [-r, r] (r < 2^31). */
static cs_pos_t coord(int64_t r)
{
    return (cs_pos_t)((int64_t)(next_u64() % (uint64_t)(2 * r + 1)) - r);
}

/* A curve of kind k (0..6) within a box of half-size r LSB around a random centre. */
static cs_bezier_t make_curve(unsigned k, int64_t r)
{
    cs_bezier_t c;
    memset(&c, 0, sizeof c);
    c.degree = k == 6 ? 2 : (unsigned)(1 + next_u64() % 3);
    int64_t room = CS_POS_LIMIT - r;
    cs_pos_t cx = coord(room), cy = coord(room);
    for (unsigned i = 0; i <= c.degree; i++) {
        c.p[i] = cs_fixed_vec(cx + coord(r), cy + coord(r), 0);
        c.w[i] = CS_WEIGHT_ONE;
    }
    unsigned n = c.degree;
    if (k == 1 || k == 2) { /* exactly on one line through P0: P_i = P0 + s_i d, s_i in -4..4 */
        cs_pos_t dx = coord(r / 8), dy = coord(r / 8), x0 = c.p[0].x, y0 = c.p[0].y;
        for (unsigned i = 1; i <= n; i++) {
            cs_pos_t s = (cs_pos_t)(next_u64() % 9) - 4;
            c.p[i] = cs_fixed_vec(x0 + dx * s, y0 + dy * s, 0);
        }
        if (k == 2 && n == 3)
            c.p[next_u64() % 2 ? 2 : 3] = c.p[next_u64() % 2 ? 0 : 2]; /* P0 = P2 or P2 = P3 */
    } else if (k == 3) {                                               /* a single point */
        for (unsigned i = 1; i <= n; i++)
            c.p[i] = c.p[0];
    } else if (k == 4) { /* P0 = P1: B'(0) = 0 */
        c.p[1] = c.p[0];
    } else if (k == 5) { /* the corners of the coordinate range */
        for (unsigned i = 0; i <= n; i++)
            c.p[i] = cs_fixed_vec(next_u64() % 2 ? CS_POS_LIMIT : -CS_POS_LIMIT,
                                  next_u64() % 2 ? CS_POS_LIMIT : -CS_POS_LIMIT, 0);
    } else if (k == 6) { /* a conic arc: w0 = w2 = 1, w1 in [1/16, 1] (cs_predict's range) */
        c.rational = true;
        c.w[1] =
            (cs_weight_t)(CS_WEIGHT_ONE / 16 +
                          (cs_weight_t)(next_u64() % (CS_WEIGHT_ONE - CS_WEIGHT_ONE / 16 + 1)));
    }
    return c;
}

typedef cs_err_t (*begin_fn)(cs_predict_t *, const cs_bezier_t *, cs_pos_t);
typedef cs_err_t (*next_fn)(cs_predict_t *, cs_vec3_t *);

/* Traces c into v; returns the begin code or the last next's, *n vertices. */
static cs_err_t trace(begin_fn begin, next_fn next, const cs_bezier_t *c, cs_pos_t tol,
                      cs_vec3_t *v, size_t *n)
{
    static cs_predict_t p;
    *n = 0;
    cs_err_t e = begin(&p, c, tol);
    if (e != CS_OK)
        return e;
    while (*n < MAX_VERTS && (e = next(&p, &v[*n])) == CS_OK)
        (*n)++;
    return e;
}

static void test_same_vertices(void **state)
{
    (void)state;
    static cs_vec3_t va[MAX_VERTS], vb[MAX_VERTS];
    size_t checked = 0, vertices = 0;
    for (unsigned i = 0; i < N_CURVES; i++) {
        unsigned k = i % 7;
        int64_t r = k == 5 ? CS_POS_LIMIT : (int64_t)1024 << (next_u64() % 18); /* 16 um .. 4 m */
        if (r > CS_POS_LIMIT / 2 && k != 5)
            r = CS_POS_LIMIT / 2;
        cs_bezier_t c = make_curve(k, r);
        /* tolerance 2^-4 .. 2^-20 of the box (most curves many chords), log-uniform, at
         * least the smallest accepted: 4 LSB .. 64 mm */
        int64_t t = r >> (4 + next_u64() % 17);
        t += (int64_t)(next_u64() % (uint64_t)(t + 1));
        cs_pos_t tol = t < CS_PREDICT_TOL_MIN ? CS_PREDICT_TOL_MIN : (cs_pos_t)t;
        bool conic = c.rational;
        size_t na, nb;
        cs_err_t ea = trace(conic ? cs_predict_begin_conic : cs_predict_begin, cs_predict_next, &c,
                            tol, va, &na);
        cs_err_t eb = trace(conic ? fw_predict_begin_conic : fw_predict_begin, fw_predict_next, &c,
                            tol, vb, &nb);
        if (ea != eb || na != nb || memcmp(va, vb, na * sizeof va[0]) != 0) {
            print_error("curve %u (kind %u, degree %u, tol %ld LSB): host %d, %zu vertices; "
                        "firmware code %d, %zu vertices\n",
                        i, k, c.degree, (long)tol, (int)ea, na, (int)eb, nb);
            fail();
        }
        checked++;
        vertices += na;
    }
    print_message("%zu curves, %zu vertices, the same from both builds\n", checked, vertices);
    assert_true(vertices > N_CURVES); /* the corpus traced something */
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_same_vertices)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
