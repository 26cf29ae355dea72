/* test_frame: the framing layer. Reference: a COBS encoder written here straight from Cheshire &
 * Baker's definition (code byte = distance to the next zero, 0xFF = 254 bytes with no zero) and
 * the CRC's bitwise definition; the frame layout LEN SEQ(lo,hi) PAYLOAD CRC(hi,lo) of
 * docs/protocol.md. Exact byte comparisons (framing has no tolerance). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "cs_frame.h"

static uint64_t rng_state = 0x243F6A8885A308D3ull;
static uint64_t rng(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return rng_state;
}

/* CRC-32 (IEEE 802.3) written from its definition, bit by bit with a branch. */
static uint32_t ref_crc(const uint8_t *p, size_t n)
{
    uint32_t crc = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; i++) {
        crc ^= p[i];
        for (int b = 0; b < 8; b++)
            crc = (crc & 1u) ? (crc >> 1) ^ 0xEDB88320u : crc >> 1;
    }
    return ~crc;
}

/* Inner frame with an arbitrary LEN byte (to build malformed but CRC-correct frames). */
static size_t ref_inner(uint8_t len_byte, uint16_t seq, const uint8_t *pl, size_t n, uint8_t *out)
{
    out[0] = len_byte;
    out[1] = (uint8_t)(seq & 0xFF);
    out[2] = (uint8_t)(seq >> 8);
    memcpy(out + 3, pl, n);
    uint32_t c = ref_crc(out, 3 + n);
    for (int k = 0; k < 4; k++)
        out[3 + n + (size_t)k] = (uint8_t)(c >> (8 * k));
    return 7 + n;
}

/* 00 COBS(in) 00, COBS per the paper: split at zeros, runs of 254 non-zero bytes get code 0xFF. */
static size_t ref_wire(const uint8_t *in, size_t n, uint8_t *out)
{
    size_t o = 0;
    out[o++] = 0;
    size_t i = 0;
    for (;;) {
        size_t run = 0;
        while (i + run < n && in[i + run] != 0 && run < 254)
            run++;
        out[o++] = (uint8_t)(run + 1);
        memcpy(out + o, in + i, run);
        o += run;
        i += run;
        if (run == 254) {
            if (i == n) {
                out[o++] = 1; /* an empty last block, as the encoder under test writes it */
                break;
            }
            continue;
        }
        if (i == n)
            break;
        i++; /* the zero this block stood for */
    }
    out[o++] = 0;
    return o;
}

typedef struct {
    int ok, crc, bad;
    cs_frame_t last;
    uint8_t last_payload[CS_FRAME_PAYLOAD_MAX];
} feed_result_t;

static void feed_all(cs_frame_dec_t *d, const uint8_t *p, size_t n, feed_result_t *r)
{
    for (size_t i = 0; i < n; i++) {
        cs_frame_t f;
        cs_err_t e = cs_frame_dec_feed(d, p[i], &f);
        if (e == CS_OK) {
            r->ok++;
            r->last = f;
            memcpy(r->last_payload, f.payload, f.len);
        } else if (e == CS_ERR_CRC) {
            r->crc++;
        } else if (e == CS_ERR_FRAME) {
            r->bad++;
        } else {
            assert_int_equal(e, CS_ERR_EMPTY);
        }
    }
}

static void random_payload(uint8_t *p, size_t n)
{
    int mode = (int)(rng() % 4); /* random, all zero, all 0xFF, sparse zeros */
    for (size_t i = 0; i < n; i++)
        p[i] = mode == 1 ? 0 : mode == 2 ? 0xFF : mode == 3 && rng() % 3 == 0 ? 0 : (uint8_t)rng();
}

static void test_encode_matches_reference_bytes(void **state)
{
    (void)state;
    uint8_t pl[CS_FRAME_PAYLOAD_MAX], inner[CS_FRAME_INNER_MAX], want[CS_FRAME_WIRE_MAX + 8];
    uint8_t got[CS_FRAME_WIRE_MAX];
    for (int t = 0; t < 5000; t++) {
        size_t n = 1 + (size_t)(rng() % CS_FRAME_PAYLOAD_MAX);
        uint16_t seq = (uint16_t)(t < 4 ? (t == 0   ? 0
                                           : t == 1 ? 0x0100
                                           : t == 2 ? 0xFF00
                                                    : 0xFFFF)
                                        : rng());
        random_payload(pl, n);
        size_t wn = ref_wire(inner, ref_inner((uint8_t)n, seq, pl, n, inner), want);
        size_t gn = 0;
        assert_int_equal(cs_frame_encode(seq, pl, n, got, sizeof got, &gn), CS_OK);
        assert_int_equal(gn, wn);
        assert_memory_equal(got, want, wn);
        assert_true(gn <= (size_t)CS_FRAME_WIRE_LEN(n));
        /* The sync byte occurs only at both ends. */
        for (size_t i = 1; i + 1 < gn; i++)
            assert_int_not_equal(got[i], CS_FRAME_SYNC);
    }
}

static void test_round_trip_every_length(void **state)
{
    (void)state;
    uint8_t pl[CS_FRAME_PAYLOAD_MAX], wire[CS_FRAME_WIRE_MAX];
    cs_frame_dec_t d;
    cs_frame_dec_init(&d);
    for (size_t n = 1; n <= CS_FRAME_PAYLOAD_MAX; n++) {
        for (int t = 0; t < 50; t++) {
            uint16_t seq = (uint16_t)rng();
            random_payload(pl, n);
            size_t wl = 0;
            assert_int_equal(cs_frame_encode(seq, pl, n, wire, sizeof wire, &wl), CS_OK);
            feed_result_t r = {0};
            feed_all(&d, wire, wl, &r);
            assert_int_equal(r.ok, 1);
            assert_int_equal(r.crc + r.bad, 0);
            assert_int_equal(r.last.seq, seq);
            assert_int_equal(r.last.len, n);
            assert_memory_equal(r.last_payload, pl, n);
        }
    }
    assert_int_equal(d.stats.frames, CS_FRAME_PAYLOAD_MAX * 50);
}

static void test_encode_refuses_bad_arguments(void **state)
{
    (void)state;
    uint8_t pl[CS_FRAME_PAYLOAD_MAX + 1] = {1}, wire[CS_FRAME_WIRE_MAX + 8];
    size_t wl = 0;
    assert_int_equal(cs_frame_encode(1, pl, 0, wire, sizeof wire, &wl), CS_ERR_ARG);
    assert_int_equal(cs_frame_encode(1, pl, CS_FRAME_PAYLOAD_MAX + 1, wire, sizeof wire, &wl),
                     CS_ERR_ARG);
    assert_int_equal(cs_frame_encode(1, NULL, 1, wire, sizeof wire, &wl), CS_ERR_ARG);
    assert_int_equal(cs_frame_encode(1, pl, 1, NULL, sizeof wire, &wl), CS_ERR_ARG);
    memset(wire, 0xAA, sizeof wire);
    assert_int_equal(cs_frame_encode(1, pl, 10, wire, (size_t)CS_FRAME_WIRE_LEN(10) - 1, &wl),
                     CS_ERR_FULL);
    assert_int_equal(wire[0], 0xAA); /* untouched */
    assert_int_equal(cs_frame_encode(1, pl, 10, wire, (size_t)CS_FRAME_WIRE_LEN(10), &wl), CS_OK);
}

/* Garbage of any kind before a frame costs nothing: the frame's leading sync resynchronises. */
static void test_resync_after_garbage(void **state)
{
    (void)state;
    uint8_t pl[20], wire[CS_FRAME_WIRE_MAX], junk[600];
    cs_frame_dec_t d;
    cs_frame_dec_init(&d);
    for (int t = 0; t < 2000; t++) {
        size_t jn = (size_t)(rng() % sizeof junk);
        for (size_t i = 0; i < jn; i++)
            junk[i] = (uint8_t)rng();
        random_payload(pl, sizeof pl);
        uint16_t seq = (uint16_t)rng();
        size_t wl = 0;
        assert_int_equal(cs_frame_encode(seq, pl, sizeof pl, wire, sizeof wire, &wl), CS_OK);
        feed_result_t r = {0};
        feed_all(&d, junk, jn, &r);
        int before = r.ok;
        feed_all(&d, wire, wl, &r);
        /* The junk's own tail ends at the frame's leading sync and could, by a 2^-16 chance,
         * pass as a frame: what matters is that ours arrives intact, last. */
        assert_true(r.ok - before >= 1);
        assert_int_equal(r.last.seq, seq);
        assert_memory_equal(r.last_payload, pl, sizeof pl);
    }
}

/* One corrupted byte (any position, any value) loses exactly that frame, never its neighbours,
 * and the damaged frame is answered with CS_ERR_CRC or CS_ERR_FRAME (or split in two, each
 * answered). */
static void test_one_corrupt_byte_loses_one_frame(void **state)
{
    (void)state;
    enum { N = 3 };
    uint8_t pl[N][24], stream[N * CS_FRAME_WIRE_MAX];
    for (int t = 0; t < 3000; t++) {
        size_t sn = 0, start[N], end[N];
        for (int k = 0; k < N; k++) {
            random_payload(pl[k], sizeof pl[k]);
            size_t wl = 0;
            start[k] = sn;
            assert_int_equal(cs_frame_encode((uint16_t)k, pl[k], sizeof pl[k], stream + sn,
                                             CS_FRAME_WIRE_MAX, &wl),
                             CS_OK);
            sn += wl;
            end[k] = sn;
        }
        /* Corrupt a byte strictly inside frame 1 (its syncs are shared with neighbours' ends). */
        size_t pos = start[1] + 1 + (size_t)(rng() % (end[1] - start[1] - 2));
        uint8_t flip = (uint8_t)(1 + rng() % 255);
        stream[pos] ^= flip;
        cs_frame_dec_t d;
        cs_frame_dec_init(&d);
        int got[N] = {0};
        int errors = 0;
        for (size_t i = 0; i < sn; i++) {
            cs_frame_t f;
            cs_err_t e = cs_frame_dec_feed(&d, stream[i], &f);
            if (e == CS_OK) {
                assert_true(f.seq < N);
                assert_memory_equal(f.payload, pl[f.seq], sizeof pl[0]);
                got[f.seq]++;
            } else if (e != CS_ERR_EMPTY) {
                assert_true(e == CS_ERR_CRC || e == CS_ERR_FRAME);
                errors++;
            }
        }
        assert_int_equal(got[0], 1);
        assert_int_equal(got[2], 1);
        assert_int_equal(got[1], 0);
        assert_true(errors >= 1);
    }
}

static void test_truncated_frame_then_good_frame(void **state)
{
    (void)state;
    uint8_t pl[24], wire[CS_FRAME_WIRE_MAX], good[CS_FRAME_WIRE_MAX];
    random_payload(pl, sizeof pl);
    pl[5] = 0; /* a few zeros so COBS has several blocks */
    pl[20] = 0;
    size_t wl = 0, gl = 0;
    assert_int_equal(cs_frame_encode(7, pl, sizeof pl, wire, sizeof wire, &wl), CS_OK);
    assert_int_equal(cs_frame_encode(8, pl, sizeof pl, good, sizeof good, &gl), CS_OK);
    for (size_t cut = 2; cut + 1 < wl; cut++) {
        cs_frame_dec_t d;
        cs_frame_dec_init(&d);
        feed_result_t r = {0};
        feed_all(&d, wire, cut, &r); /* frame 7 cut short; frame 8's leading sync ends it */
        feed_all(&d, good, gl, &r);
        assert_int_equal(r.ok, 1);
        assert_int_equal(r.last.seq, 8);
        assert_int_equal(r.crc + r.bad, 1);
    }
}

static void test_malformed_frames_get_error_codes(void **state)
{
    (void)state;
    uint8_t pl[CS_FRAME_PAYLOAD_MAX + 10], inner[CS_FRAME_PAYLOAD_MAX + 16], wire[400];
    memset(pl, 0x11, sizeof pl);
    cs_frame_dec_t d;
    cs_frame_dec_init(&d);
    feed_result_t r = {0};
    /* LEN disagrees with the frame's size but the CRC is right: CS_ERR_FRAME, not accepted. */
    size_t n = ref_inner(9, 1, pl, 10, inner);
    feed_all(&d, wire, ref_wire(inner, n, wire), &r);
    assert_int_equal(r.bad, 1);
    /* Empty payload (LEN 0, header + CRC only). */
    n = ref_inner(0, 1, pl, 0, inner);
    feed_all(&d, wire, ref_wire(inner, n, wire), &r);
    assert_int_equal(r.bad, 2);
    /* Payload one byte longer than CS_FRAME_PAYLOAD_MAX: overrun, dropped. */
    n = ref_inner((uint8_t)(CS_FRAME_PAYLOAD_MAX + 1), 1, pl, CS_FRAME_PAYLOAD_MAX + 1, inner);
    feed_all(&d, wire, ref_wire(inner, n, wire), &r);
    assert_int_equal(r.bad, 3);
    /* 300 non-zero bytes: far too long. */
    memset(wire, 0x5A, 300);
    wire[300] = 0;
    feed_all(&d, wire, 301, &r);
    assert_int_equal(r.bad, 4);
    /* Short garbage between syncs. */
    const uint8_t shortf[] = {0, 3, 1, 1, 0, 0x01, 0, 0x02, 0x55, 0};
    feed_all(&d, shortf, sizeof shortf, &r);
    assert_int_equal(r.ok, 0);
    assert_int_equal(r.bad, 7);
    /* Right size, wrong CRC. */
    n = ref_inner(10, 1, pl, 10, inner);
    inner[n - 1] ^= 0x40;
    feed_all(&d, wire, ref_wire(inner, n, wire), &r);
    assert_int_equal(r.crc, 1);
    /* Runs of syncs are empty frames: no error, no frame. */
    memset(wire, 0, 50);
    feed_all(&d, wire, 50, &r);
    assert_int_equal(r.ok + r.crc, 1);
    assert_int_equal(r.bad, 7);
    assert_int_equal(d.stats.bad, 7);
    assert_int_equal(d.stats.crc_errs, 1);
    assert_int_equal(d.stats.frames, 0);
    /* And after all that, a good frame still decodes. */
    size_t wl = 0;
    assert_int_equal(cs_frame_encode(0xBEEF, pl, 12, wire, sizeof wire, &wl), CS_OK);
    feed_all(&d, wire, wl, &r);
    assert_int_equal(r.ok, 1);
    assert_int_equal(r.last.seq, 0xBEEF);
}

/* The decoder needs no leading sync for the very first frame after init (a frame's own leading
 * sync is only there to flush line noise). */
static void test_first_frame_without_leading_sync(void **state)
{
    (void)state;
    uint8_t pl[5] = {1, 2, 0, 4, 5}, wire[CS_FRAME_WIRE_MAX];
    size_t wl = 0;
    assert_int_equal(cs_frame_encode(3, pl, sizeof pl, wire, sizeof wire, &wl), CS_OK);
    cs_frame_dec_t d;
    cs_frame_dec_init(&d);
    feed_result_t r = {0};
    feed_all(&d, wire + 1, wl - 1, &r);
    assert_int_equal(r.ok, 1);
    assert_memory_equal(r.last_payload, pl, sizeof pl);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_encode_matches_reference_bytes),
        cmocka_unit_test(test_round_trip_every_length),
        cmocka_unit_test(test_encode_refuses_bad_arguments),
        cmocka_unit_test(test_resync_after_garbage),
        cmocka_unit_test(test_one_corrupt_byte_loses_one_frame),
        cmocka_unit_test(test_truncated_frame_then_good_frame),
        cmocka_unit_test(test_malformed_frames_get_error_codes),
        cmocka_unit_test(test_first_frame_without_leading_sync),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
