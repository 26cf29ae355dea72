/* test_order: line merging and travel sorting (host/cs_order.c). Travel figures are worked out by
 * hand for small drawings; on random drawings the drawn geometry is proved unchanged by a check
 * written here, independent of the merge code: every element's control polygon, direction
 * normalised (the lexicographically smaller end first), as an unordered multiset, before and
 * after, must be equal, apart from bridging lines no longer than the tolerance. Also: travel
 * never grows, every element is continuous within a subpath, and the result is the same on
 * every run (determinism). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cs_conv.h"
#include "cs_order.h"
#include "ref_xorshift32.h"

static void add_curve(cs_path_t *p, unsigned deg, const double (*pt)[2], bool new_sub)
{
    cs_vec3_t v[4];
    for (unsigned i = 0; i <= deg; i++)
        assert_int_equal(cs_conv_mm_to_vec(pt[i][0], pt[i][1], 0, &v[i]), CS_OK);
    cs_bezier_t c;
    assert_int_equal(cs_bezier_init(&c, deg, v), CS_OK);
    cs_path_loc_t loc = {"t", 1, 1};
    if (new_sub)
        cs_path_new_subpath(p);
    assert_int_equal(cs_path_add(p, &c, deg == 1 ? CS_PATH_LINE : CS_PATH_CUBIC, loc), CS_OK);
}

static void add_line(cs_path_t *p, double x0, double y0, double x1, double y1, bool new_sub)
{
    const double pt[2][2] = {{x0, y0}, {x1, y1}};
    add_curve(p, 1, pt, new_sub);
}

static cs_order_opts_t opts(bool merge, bool sort)
{
    cs_order_opts_t o = {merge, sort, 0.01};
    return o;
}

static void expect_start(const cs_path_t *p, size_t i, double x, double y)
{
    const cs_vec3_t *v = &p->elems[i].curve.p[0];
    assert_true(fabs(cs_conv_pos_to_mm(v->x) - x) < 1e-4 &&
                fabs(cs_conv_pos_to_mm(v->y) - y) < 1e-4);
}

static void test_travel_count(void **state)
{
    (void)state;
    /* origin -> (100,0): 100; (100,10) -> (0,0): sqrt(100^2 + 10^2); (0,10) -> (50,10): 50 */
    cs_path_t p;
    cs_path_init(&p);
    add_line(&p, 100, 0, 100, 10, true);
    add_line(&p, 0, 0, 0, 10, true);
    add_line(&p, 50, 10, 50, 0, true);
    size_t lifts;
    double t = cs_order_travel(&p, &lifts);
    assert_true(fabs(t - (150 + sqrt(10100.0))) < 1e-9);
    assert_int_equal(lifts, 3);
    /* sorted: (0,0) first (0 travel), up to (0,10), over to (50,10) (50), down, over to
     * (100,0) (50): 100 in all, the least possible */
    cs_order_opts_t o = opts(false, true);
    cs_order_stats_t st;
    assert_int_equal(cs_order_apply(&p, &o, &st), CS_OK);
    assert_true(fabs(st.travel_before_mm - t) < 1e-9);
    assert_true(fabs(st.travel_after_mm - 100) < 1e-9);
    assert_int_equal(st.lifts_after, 3);
    expect_start(&p, 0, 0, 0);
    expect_start(&p, 1, 50, 10);
    expect_start(&p, 2, 100, 0);
    cs_path_free(&p);
}

static void test_merge(void **state)
{
    (void)state;
    cs_path_t p;
    cs_order_stats_t st;
    cs_order_opts_t o = opts(true, false);
    /* (0,0)-(10,0) and (20,0)-(10,0): one stroke, the second reversed exactly */
    cs_path_init(&p);
    add_line(&p, 0, 0, 10, 0, true);
    add_line(&p, 20, 0, 10, 0, true);
    assert_int_equal(cs_order_apply(&p, &o, &st), CS_OK);
    assert_int_equal(st.lifts_before, 2);
    assert_int_equal(st.lifts_after, 1);
    assert_int_equal(p.n, 2);
    expect_start(&p, 1, 10, 0);
    assert_int_equal(p.elems[0].subpath, p.elems[1].subpath);
    cs_path_free(&p);
    /* a gap of 0.005 mm (< tol 0.01): joined by a bridging line */
    cs_path_init(&p);
    add_line(&p, 0, 0, 10, 0, true);
    add_line(&p, 10.005, 0, 20, 0, true);
    assert_int_equal(cs_order_apply(&p, &o, &st), CS_OK);
    assert_int_equal(st.lifts_after, 1);
    assert_int_equal(st.bridges, 1);
    assert_int_equal(p.n, 3);
    cs_path_free(&p);
    /* a gap of 0.02 mm: kept apart */
    cs_path_init(&p);
    add_line(&p, 0, 0, 10, 0, true);
    add_line(&p, 10.02, 0, 20, 0, true);
    assert_int_equal(cs_order_apply(&p, &o, &st), CS_OK);
    assert_int_equal(st.lifts_after, 2);
    cs_path_free(&p);
    /* travel moves of its own (G0): left alone */
    cs_path_init(&p);
    add_line(&p, 0, 0, 10, 0, true);
    p.elems[0].rapid = true;
    assert_int_equal(cs_order_apply(&p, &o, &st), CS_OK);
    assert_true(st.skipped);
    cs_path_free(&p);
}

static void test_closed_rotated(void **state)
{
    (void)state;
    /* the square (5,5)..(15,15) drawn from (15,15): sorting starts it at (5,5), the corner
     * nearest the origin: travel sqrt(50) instead of sqrt(450) */
    cs_path_t p;
    cs_path_init(&p);
    add_line(&p, 15, 15, 5, 15, true);
    add_line(&p, 5, 15, 5, 5, false);
    add_line(&p, 5, 5, 15, 5, false);
    add_line(&p, 15, 5, 15, 15, false);
    cs_order_opts_t o = opts(false, true);
    cs_order_stats_t st;
    assert_int_equal(cs_order_apply(&p, &o, &st), CS_OK);
    assert_true(fabs(st.travel_before_mm - sqrt(450.0)) < 1e-9);
    assert_true(fabs(st.travel_after_mm - sqrt(50.0)) < 1e-9);
    expect_start(&p, 0, 5, 5);
    assert_int_equal(st.lifts_after, 1);
    cs_path_free(&p);
}

/* --- random drawings: geometry unchanged, travel reduced, deterministic -------------------- */

static ref_xorshift32_t rng; /* the tests' one generator (tests/support) */

static double urand(double lo, double hi)
{
    return ref_xorshift32_uniform(&rng, lo, hi);
}

/* Random polylines and cubics; some strokes share end points (chains to merge). */
static void random_path(cs_path_t *p, size_t n)
{
    cs_path_init(p);
    rng.s = 0x2545F491u;
    double lx = 0, ly = 0;
    for (size_t i = 0; i < n; i++) {
        bool chain = i > 0 && urand(0, 1) < 0.3; /* start where the last stroke ended */
        double x = chain ? lx : urand(0, 300), y = chain ? ly : urand(0, 200);
        unsigned k = 1 + (unsigned)urand(0, 3);
        for (unsigned j = 0; j < k; j++) {
            double nx = x + urand(-5, 5), ny = y + urand(-5, 5);
            if (urand(0, 1) < 0.5) {
                add_line(p, x, y, nx, ny, j == 0);
            } else {
                const double pt[4][2] = {{x, y}, {x + 1, y + 2}, {nx - 2, ny + 1}, {nx, ny}};
                add_curve(p, 3, pt, j == 0);
            }
            x = nx;
            y = ny;
        }
        lx = x;
        ly = y;
    }
}

/* An element's control polygon, the smaller end first: the key of the geometry multiset. */
typedef struct {
    int32_t v[8][2];
    unsigned deg;
} geomkey_t;

static geomkey_t key_of(const cs_bezier_t *c)
{
    geomkey_t k;
    memset(&k, 0, sizeof k);
    k.deg = c->degree;
    const cs_vec3_t *a = &c->p[0], *b = &c->p[c->degree];
    bool rev = a->x > b->x || (a->x == b->x && a->y > b->y);
    for (unsigned i = 0; i <= c->degree; i++) {
        const cs_vec3_t *q = &c->p[rev ? c->degree - i : i];
        k.v[i][0] = q->x;
        k.v[i][1] = q->y;
    }
    return k;
}

static int key_cmp(const void *x, const void *y)
{
    return memcmp(x, y, sizeof(geomkey_t));
}

/* Keys of p's elements, sorted; bridging lines (<= tol) left out and counted. */
static geomkey_t *keys(const cs_path_t *p, size_t *n, double tol, size_t *bridges)
{
    geomkey_t *k = calloc(p->n + 1, sizeof *k);
    assert_non_null(k);
    *n = 0;
    *bridges = 0;
    for (size_t i = 0; i < p->n; i++) {
        const cs_bezier_t *c = &p->elems[i].curve;
        double len = hypot(cs_conv_pos_to_mm(c->p[1].x - c->p[0].x),
                           cs_conv_pos_to_mm(c->p[1].y - c->p[0].y));
        bool cont = i > 0 && p->elems[i].subpath == p->elems[i - 1].subpath;
        if (c->degree == 1 && len <= tol && cont && i + 1 < p->n &&
            p->elems[i + 1].subpath == p->elems[i].subpath) {
            (*bridges)++;
            continue;
        }
        k[(*n)++] = key_of(c);
    }
    qsort(k, *n, sizeof *k, key_cmp);
    return k;
}

static void check_random(bool merge, bool sort)
{
    cs_path_t a, b;
    random_path(&a, 3000);
    random_path(&b, 3000);
    cs_order_opts_t o = opts(merge, sort);
    cs_order_stats_t st, st2;
    size_t na, nb, ba, bb;
    geomkey_t *ka = keys(&a, &na, -1, &ba);
    assert_int_equal(cs_order_apply(&b, &o, &st), CS_OK);
    geomkey_t *kb = keys(&b, &nb, o.tol_mm, &bb);
    assert_int_equal(na, nb);
    assert_int_equal(bb, st.bridges);
    assert_int_equal(memcmp(ka, kb, na * sizeof *ka), 0);
    /* within a subpath every element starts where the last ended */
    for (size_t i = 1; i < b.n; i++)
        if (b.elems[i].subpath == b.elems[i - 1].subpath) {
            const cs_bezier_t *p = &b.elems[i - 1].curve, *c = &b.elems[i].curve;
            assert_true(p->p[p->degree].x == c->p[0].x && p->p[p->degree].y == c->p[0].y);
        }
    if (sort)
        assert_true(st.travel_after_mm < 0.5 * st.travel_before_mm);
    if (merge)
        assert_true(st.lifts_after < st.lifts_before);
    /* the same again: the same elements in the same order */
    cs_path_t c;
    random_path(&c, 3000);
    assert_int_equal(cs_order_apply(&c, &o, &st2), CS_OK);
    assert_int_equal(c.n, b.n);
    for (size_t i = 0; i < b.n; i++) {
        const cs_bezier_t *x = &b.elems[i].curve, *y = &c.elems[i].curve;
        assert_int_equal(x->degree, y->degree);
        assert_int_equal(b.elems[i].subpath, c.elems[i].subpath);
        for (unsigned k = 0; k <= x->degree; k++)
            assert_true(x->p[k].x == y->p[k].x && x->p[k].y == y->p[k].y);
    }
    free(ka);
    free(kb);
    cs_path_free(&a);
    cs_path_free(&b);
    cs_path_free(&c);
}

static void test_random_sort(void **state)
{
    (void)state;
    check_random(false, true);
}

static void test_random_merge(void **state)
{
    (void)state;
    check_random(true, false);
}

static void test_random_both(void **state)
{
    (void)state;
    check_random(true, true);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_travel_count),   cmocka_unit_test(test_merge),
        cmocka_unit_test(test_closed_rotated), cmocka_unit_test(test_random_sort),
        cmocka_unit_test(test_random_merge),   cmocka_unit_test(test_random_both),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
