/* Equivalence of the optimised step executor with the executor it replaced: cs_stepper (the one
 * every target runs) against ref_stepper (tests/support: a frozen copy of cs_stepper as it was
 * before its 8-bit optimisation), driven with the same pushes and calls, compared call by call on
 * everything a port or the application can observe: each call's STEP mask, DIR levels and
 * next_ticks, every axis position, the step count, running/idle, the free slots and every push's
 * result. Scenarios (fixed seeds): random segments, 1-tick and 2-tick segments, 2^24-tick
 * segments (|steps| = ticks among them), 0-step segments, every AMASS level at its boundaries,
 * call counts around 2^15 and 2^16 (the 16-bit fast path's edges), 1 to 4 axes, inverted DIR,
 * invalid segments, a full ring and calls while idle.
 *
 * Each scenario's output sequence is also hashed (FNV-1a 64 over step mask, DIR mask and
 * next_ticks of every call, and every push result): `golden` holds the hashes and call counts
 * recorded from cs_stepper BEFORE the optimisation, so the old behaviour is pinned even if
 * ref_stepper were edited. CS_STEPPER_EQUIV_TRACE=FILE writes the whole trace (one line a call:
 * scenario, step mask, DIR mask, next_ticks) for a byte comparison between two builds. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <stdio.h>
#include <stdlib.h>

#include "cs_machine_ini.h"
#include "cs_stepper.h"
#include "ref_stepper.h"
#include "ref_xorshift32.h"

CS_STATIC_ASSERT(REF_STEPPER_RING == CS_STEPPER_RING, same_ring_size);

#define MAX_TICKS ((uint32_t)1 << 24)

typedef struct {
    cs_stepper_t cs;
    ref_stepper_t ref;
    uint64_t hash;
    uint64_t calls;
    FILE *trace;
    int scen;
} pair_t;

static FILE *trace_file;

static void hash_bytes(pair_t *p, const uint8_t *b, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        p->hash ^= b[i];
        p->hash *= 1099511628211ull; /* FNV-1a 64 prime */
    }
}

/* Everything observable besides a call's output. */
static void compare_state(const pair_t *p)
{
    for (unsigned i = 0; i <= CS_AXES; i++)
        assert_int_equal(cs_stepper_position(&p->cs, i), ref_stepper_position(&p->ref, i));
    assert_int_equal(p->cs.steps_done, p->ref.steps_done);
    assert_int_equal(p->cs.running, p->ref.running);
    assert_int_equal(p->cs.head, p->ref.head);
    assert_int_equal(p->cs.tail, p->ref.tail);
    assert_int_equal(cs_stepper_idle(&p->cs), ref_stepper_idle(&p->ref));
    assert_int_equal(cs_stepper_free(&p->cs), ref_stepper_free(&p->ref));
}

static void pair_init(pair_t *p, const cs_machine_t *m, int scen)
{
    assert_int_equal(cs_stepper_init(&p->cs, m), ref_stepper_init(&p->ref, m));
    assert_int_equal(cs_stepper_init(&p->cs, m), CS_OK);
    p->hash = 14695981039346656037ull; /* FNV-1a 64 offset basis */
    p->calls = 0;
    p->trace = trace_file;
    p->scen = scen;
    compare_state(p);
}

static cs_err_t pair_push(pair_t *p, const cs_segment_t *s)
{
    cs_err_t e = cs_stepper_push(&p->cs, s);
    assert_int_equal(e, ref_stepper_push(&p->ref, s));
    uint8_t b = (uint8_t)(0x80u | (uint8_t)e);
    hash_bytes(p, &b, 1);
    compare_state(p);
    return e;
}

/* One timer call on both; returns next_ticks. */
static uint32_t pair_tick(pair_t *p)
{
    cs_stepper_out_t a;
    ref_stepper_out_t r;
    cs_stepper_tick(&p->cs, &a);
    ref_stepper_tick(&p->ref, &r);
    if (a.step_mask != r.step_mask || a.dir_mask != r.dir_mask || a.next_ticks != r.next_ticks)
        fail_msg("scenario %d call %llu: new %02x %02x %lu, reference %02x %02x %lu", p->scen,
                 (unsigned long long)p->calls, a.step_mask, a.dir_mask, (unsigned long)a.next_ticks,
                 r.step_mask, r.dir_mask, (unsigned long)r.next_ticks);
    uint8_t b[6] = {a.step_mask,
                    a.dir_mask,
                    (uint8_t)a.next_ticks,
                    (uint8_t)(a.next_ticks >> 8),
                    (uint8_t)(a.next_ticks >> 16),
                    (uint8_t)(a.next_ticks >> 24)};
    hash_bytes(p, b, sizeof b);
    if (p->trace != NULL)
        fprintf(p->trace, "%d %02x %02x %lu\n", p->scen, a.step_mask, a.dir_mask,
                (unsigned long)a.next_ticks);
    p->calls++;
    compare_state(p);
    return a.next_ticks;
}

/* Feeds segs[0..n) through the pair the way a main loop and a timer would: the timer calls the
 * executor until it reports idle; between calls the producer pushes 0 to 3 segments (some into
 * a full ring, retried later); when idle, the timer may call 0 to 2 more times (a port armed by a
 * push calls once before anything is loaded) before the next push. Invalid segments are pushed
 * once and skipped (both must refuse them). */
static void feed(pair_t *p, const cs_segment_t *segs, size_t n, uint32_t seed)
{
    ref_xorshift32_t g = {seed};
    size_t next = 0;
    bool idle = true;
    while (next < n || !idle) {
        unsigned tries = ref_xorshift32_next(&g) % 4u;
        if (idle && next < n && tries == 0)
            tries = 1;
        for (unsigned k = 0; k < tries && next < n; k++) {
            cs_err_t e = pair_push(p, &segs[next]);
            if (e == CS_OK || e == CS_ERR_ARG)
                next++;
            else
                assert_int_equal(e, CS_ERR_FULL);
        }
        if (idle) {
            unsigned extra = ref_xorshift32_next(&g) % 3u;
            for (unsigned k = 0; k < extra; k++)
                (void)pair_tick(p);
        }
        idle = pair_tick(p) == 0;
    }
    /* drained: calls while idle change nothing */
    assert_int_equal(pair_tick(p), 0);
    assert_true(cs_stepper_idle(&p->cs));
}

static void machine_for(cs_machine_t *m, uint8_t n_axes, uint8_t invert)
{
    cs_machine_ini_default(m);
    m->n_axes = n_axes;
    for (unsigned i = 0; i < CS_AXES; i++)
        m->axis[i].invert_dir = (invert >> i) & 1u;
}

static int32_t signed_mag(ref_xorshift32_t *g, uint32_t mag)
{
    return (ref_xorshift32_next(g) & 1u) ? -(int32_t)mag : (int32_t)mag;
}

/* A random magnitude <= ticks: 0, ticks, or uniform, with a few small ones. */
static uint32_t random_mag(ref_xorshift32_t *g, uint32_t ticks)
{
    switch (ref_xorshift32_next(g) % 6u) {
    case 0:
        return 0;
    case 1:
        return ticks;
    case 2:
        return ref_xorshift32_next(g) % (ticks < 8u ? ticks + 1u : 8u);
    default:
        return ref_xorshift32_next(g) % (ticks + 1u);
    }
}

enum { MAX_SEGS = 4000 };
static cs_segment_t segs[MAX_SEGS];

/* The recorded hashes and call counts of cs_stepper before the optimisation (one per scenario,
 * in the order of the scenarios below). */
static const struct {
    uint64_t hash;
    uint64_t calls;
} golden[] = {
    {0xaff036c71d856a4aull, 868275u},  {0x3763cfc1c2ca5ee8ull, 1387401u},
    {0x8da478ce1ab8c621ull, 1602742u}, {0x0f68a12a5a2ce58full, 1834521u},
    {0xdd635ddcd9fd8100ull, 7281u},    {0x9a1cf87533c1d034ull, 318110u},
    {0xc43278a2fad86d8bull, 3514308u}, {0x2d202b18bf28f0e4ull, 17825859u},
    {0xfd9f593ee76a5b53ull, 9u},       {0x29f8c86e0e264488ull, 1257561u},
    {0x9c14979e1ce844a5ull, 20514u},
};
#define N_SCEN (sizeof golden / sizeof golden[0])

static uint64_t got_hash[N_SCEN], got_calls[N_SCEN];

static void finish(pair_t *p)
{
    got_hash[p->scen] = p->hash;
    got_calls[p->scen] = p->calls;
    printf("scenario %d: %llu calls, hash 0x%016llx\n", p->scen, (unsigned long long)p->calls,
           (unsigned long long)p->hash);
    assert_true(p->scen >= 0 && (size_t)p->scen < N_SCEN);
    assert_int_equal(p->calls, golden[p->scen].calls);
    assert_int_equal(p->hash, golden[p->scen].hash);
}

/* Scenarios 0-3: 1500 random segments of 1..3000 ticks on 1, 2, 3 and 4 axes, random DIR
 * inversion, some invalid segments among them. */
static void test_random_segments(void **state)
{
    (void)state;
    for (int sc = 0; sc < 4; sc++) {
        ref_xorshift32_t g = {(uint32_t)(1234567u + 99u * (uint32_t)sc)};
        uint8_t n_axes = (uint8_t)(sc + 1);
        cs_machine_t m;
        machine_for(&m, n_axes, (uint8_t)(ref_xorshift32_next(&g) & 0x0Fu));
        size_t n = 1500;
        for (size_t k = 0; k < n; k++) {
            uint32_t ticks = 1u + ref_xorshift32_next(&g) % 3000u;
            segs[k].ticks = ticks;
            for (unsigned i = 0; i < CS_AXES; i++)
                segs[k].steps[i] = i < n_axes ? signed_mag(&g, random_mag(&g, ticks)) : 0;
            switch (ref_xorshift32_next(&g) % 64u) { /* invalid now and then */
            case 0:
                segs[k].ticks = 0;
                break;
            case 1:
                segs[k].steps[0] = (int32_t)ticks + 1;
                break;
            case 2:
                segs[k].steps[CS_AXES - 1] = 1; /* an axis the machine may not have */
                break;
            case 3:
                segs[k].ticks = MAX_TICKS + 1u;
                break;
            default:
                break;
            }
        }
        pair_t p;
        pair_init(&p, &m, sc);
        feed(&p, segs, n, 42u + (uint32_t)sc);
        finish(&p);
    }
}

/* Scenario 4: 1-, 2- and 3-tick segments (0 or 1 step, either sign), 4 axes, x and z inverted. */
static void test_short_segments(void **state)
{
    (void)state;
    ref_xorshift32_t g = {2024u};
    cs_machine_t m;
    machine_for(&m, 4, 0x05u);
    size_t n = 4000;
    for (size_t k = 0; k < n; k++) {
        uint32_t ticks = 1u + ref_xorshift32_next(&g) % 3u;
        segs[k].ticks = ticks;
        for (unsigned i = 0; i < CS_AXES; i++)
            segs[k].steps[i] = signed_mag(&g, ref_xorshift32_next(&g) % (ticks + 1u));
    }
    pair_t p;
    pair_init(&p, &m, 4);
    feed(&p, segs, n, 7u);
    finish(&p);
}

/* Scenario 5: every AMASS level at its boundaries: for a dominant axis of n steps, ticks at
 * n * 8 * 2^k - 1, n * 8 * 2^k and + 1 (k = 0..3, where the oversampling doubles), and n, n + 1
 * (no oversampling), minor axes random; also 0-step segments of those lengths (one call). */
static void test_amass_boundaries(void **state)
{
    (void)state;
    ref_xorshift32_t g = {555u};
    cs_machine_t m;
    machine_for(&m, 4, 0x0Au);
    static const uint32_t most[] = {1, 2, 3, 5, 7, 100, 1000, 4095};
    size_t n = 0;
    for (size_t a = 0; a < sizeof most / sizeof most[0]; a++) {
        uint32_t t[14];
        size_t nt = 0;
        t[nt++] = most[a];
        t[nt++] = most[a] + 1u;
        for (unsigned k = 0; k < 4; k++)
            for (int d = -1; d <= 1; d++)
                t[nt++] = (uint32_t)((int64_t)most[a] * 8 * (1 << k) + d);
        for (size_t j = 0; j < nt; j++) {
            for (int zero = 0; zero < 2; zero++) {
                cs_segment_t *s = &segs[n++];
                s->ticks = t[j];
                unsigned dom = ref_xorshift32_next(&g) % CS_AXES;
                for (unsigned i = 0; i < CS_AXES; i++) {
                    uint32_t mg = i == dom ? most[a] : ref_xorshift32_next(&g) % (most[a] + 1u);
                    s->steps[i] = zero ? 0 : signed_mag(&g, mg);
                }
            }
        }
    }
    assert_true(n <= MAX_SEGS);
    pair_t p;
    pair_init(&p, &m, 5);
    feed(&p, segs, n, 8u);
    finish(&p);
}

/* Scenario 6: call counts around 2^15 and 2^16 (n * 2^k for the dominant n), where a 16-bit DDA
 * would overflow; dominant on each axis in turn, the others at 0, n - 1, n / 3 or random. */
static void test_sixteen_bit_edges(void **state)
{
    (void)state;
    ref_xorshift32_t g = {31337u};
    cs_machine_t m;
    machine_for(&m, 4, 0x03u);
    static const uint32_t most[] = {4095,  4096,  8191,  8192,  16383, 16384, 21845,
                                    32767, 32768, 32769, 65535, 65536, 65537};
    size_t n = 0;
    for (size_t a = 0; a < sizeof most / sizeof most[0]; a++) {
        /* every AMASS level that fits (calls = most * 2^k <= 2^18 keeps the test quick) */
        for (unsigned k = 0; k < 4 && (most[a] << k) <= (1u << 18); k++) {
            uint32_t ticks =
                k == 0 ? most[a] + ref_xorshift32_next(&g) % 16u
                       : most[a] * 8u * (1u << (k - 1)) + ref_xorshift32_next(&g) % (most[a] * 8u);
            cs_segment_t *s = &segs[n++];
            s->ticks = ticks;
            unsigned dom = (unsigned)(n % CS_AXES);
            for (unsigned i = 0; i < CS_AXES; i++) {
                uint32_t mg;
                switch ((i + n) % 4u) {
                case 0:
                    mg = 0;
                    break;
                case 1:
                    mg = most[a] - 1u;
                    break;
                case 2:
                    mg = most[a] / 3u;
                    break;
                default:
                    mg = ref_xorshift32_next(&g) % (most[a] + 1u);
                    break;
                }
                s->steps[i] = signed_mag(&g, i == dom ? most[a] : mg);
            }
        }
    }
    pair_t p;
    pair_init(&p, &m, 6);
    feed(&p, segs, n, 9u);
    finish(&p);
}

/* Scenario 7: 2^24-tick segments (the longest allowed): 0 steps (one call of 2^24 ticks),
 * 1 step, a few steps, and |steps| = ticks = 2^24 on x with the other axes near it (16.8 M
 * calls), 2^24 - 1 ticks. Scenario 8: the same lengths without steps, 3 axes, all inverted,
 * next to 1-tick segments. */
static void test_longest_segments(void **state)
{
    (void)state;
    cs_machine_t m;
    machine_for(&m, 4, 0x06u);
    cs_segment_t s[] = {
        {MAX_TICKS, {0, 0, 0, 0}},
        {MAX_TICKS, {1, 0, 0, -1}},
        {MAX_TICKS, {-3, 2, 7, 1}},
        {MAX_TICKS, {(int32_t)MAX_TICKS, -(int32_t)(MAX_TICKS - 1u), 12345, -8388608}},
        {MAX_TICKS - 1u, {5, 65535, 0, -1}},
        {MAX_TICKS, {-65537, 32768, 65535, 0}},
    };
    pair_t p;
    pair_init(&p, &m, 7);
    feed(&p, s, sizeof s / sizeof s[0], 10u);
    finish(&p);

    machine_for(&m, 3, 0x07u);
    cs_segment_t z[] = {
        {MAX_TICKS, {0, 0, 0, 0}}, {1, {1, -1, 0, 0}}, {MAX_TICKS, {0, 0, 0, 0}},
        {1, {0, 0, 0, 0}},         {2, {-2, 2, 1, 0}}, {MAX_TICKS - 1u, {0, 0, 0, 0}},
    };
    pair_init(&p, &m, 8);
    feed(&p, z, sizeof z / sizeof z[0], 11u);
    finish(&p);
}

/* Scenario 9: |steps| = ticks on every axis (a step every tick), lengths 1..5000, signs random;
 * scenario 10: bench-like constant-rate streams (156-tick segments, 1..156 steps on x, y, z). */
static void test_full_rate_and_streams(void **state)
{
    (void)state;
    ref_xorshift32_t g = {99u};
    cs_machine_t m;
    machine_for(&m, 4, 0x09u);
    size_t n = 500;
    for (size_t k = 0; k < n; k++) {
        uint32_t ticks = 1u + ref_xorshift32_next(&g) % 5000u;
        segs[k].ticks = ticks;
        for (unsigned i = 0; i < CS_AXES; i++)
            segs[k].steps[i] = signed_mag(&g, ticks);
    }
    pair_t p;
    pair_init(&p, &m, 9);
    feed(&p, segs, n, 12u);
    finish(&p);

    machine_for(&m, 3, 0x00u);
    n = 0;
    for (uint32_t rate = 1; rate <= 156u; rate += 5u)
        for (unsigned r = 0; r < 8; r++) {
            segs[n].ticks = 156;
            for (unsigned i = 0; i < CS_AXES; i++)
                segs[n].steps[i] = i < 3 ? (int32_t)(i == 0 ? rate : rate * i / 3u) : 0;
            n++;
        }
    pair_init(&p, &m, 10);
    feed(&p, segs, n, 13u);
    finish(&p);
}

static int teardown_all(void **state)
{
    (void)state;
    printf("golden (paste to record):\n");
    for (size_t i = 0; i < N_SCEN; i++)
        printf("    {0x%016llxull, %lluu},\n", (unsigned long long)got_hash[i],
               (unsigned long long)got_calls[i]);
    if (trace_file != NULL)
        fclose(trace_file);
    return 0;
}

static int setup_all(void **state)
{
    (void)state;
    const char *path = getenv("CS_STEPPER_EQUIV_TRACE");
    if (path != NULL && path[0] != '\0') {
        trace_file = fopen(path, "w");
        if (trace_file == NULL)
            return -1;
    }
    cs_machine_t bad;
    machine_for(&bad, 0, 0);
    cs_stepper_t a;
    ref_stepper_t r;
    if (cs_stepper_init(&a, &bad) != ref_stepper_init(&r, &bad))
        return -1;
    machine_for(&bad, CS_AXES + 1, 0);
    if (cs_stepper_init(&a, &bad) != ref_stepper_init(&r, &bad))
        return -1;
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random_segments),  cmocka_unit_test(test_short_segments),
        cmocka_unit_test(test_amass_boundaries), cmocka_unit_test(test_sixteen_bit_edges),
        cmocka_unit_test(test_longest_segments), cmocka_unit_test(test_full_rate_and_streams),
    };
    return cmocka_run_group_tests(tests, setup_all, teardown_all);
}
