/* libFuzzer target: arbitrary bytes into the frame decoder, every frame it accepts into the
 * message decoder, and every message decoded back through the encoders. Asserts (abort = finding):
 * the decoder never reads or writes out of bounds (ASan), no undefined behaviour (UBSan), every
 * byte gets one of the documented answers, an accepted frame re-encodes to a frame that decodes
 * to the same seq and payload, and a decoded message re-encodes to exactly the same bytes.
 * Built and run by scripts/fuzz.sh. Compiled with -DCS_FUZZ_SEED_MAIN it is instead a small
 * program writing the seed corpus (one valid frame of every message type) into argv[1]. */
#include <stdint.h>
#include <string.h>

#define FUZZ_NAME "fuzz_frame"
#include "fuzz_common.h"

#include "cs_frame.h"
#include "cs_proto.h"

static void check_message(const uint8_t *p, size_t n)
{
    cs_proto_msg_t m;
    cs_err_t e = cs_proto_decode(p, n, &m);
    FUZZ_CHECK(e == CS_OK || e == CS_ERR_FRAME || e == CS_ERR_RANGE || e == CS_ERR_UNSUPPORTED);
    if (e != CS_OK)
        return;
    uint8_t again[CS_PROTO_LEN_MAX];
    size_t len = 0;
    FUZZ_CHECK(cs_proto_encode(&m, again, sizeof again, &len) == CS_OK);
    FUZZ_CHECK(len == n && memcmp(again, p, n) == 0);
}

static void check_frame(const cs_frame_t *f)
{
    FUZZ_CHECK(f->len >= 1 && f->len <= CS_FRAME_PAYLOAD_MAX);
    uint8_t wire[CS_FRAME_WIRE_MAX];
    size_t wl = 0;
    FUZZ_CHECK(cs_frame_encode(f->seq, f->payload, f->len, wire, sizeof wire, &wl) == CS_OK);
    cs_frame_dec_t d;
    memset(&d, 0, sizeof d);
    cs_frame_dec_init(&d);
    cs_frame_t g;
    int got = 0;
    for (size_t i = 0; i < wl; i++) {
        cs_err_t e = cs_frame_dec_feed(&d, wire[i], &g);
        FUZZ_CHECK(e == CS_OK || e == CS_ERR_EMPTY);
        if (e == CS_OK) {
            got++;
            FUZZ_CHECK(g.seq == f->seq && g.len == f->len &&
                       memcmp(g.payload, f->payload, f->len) == 0);
        }
    }
    FUZZ_CHECK(got == 1);
    check_message(f->payload, f->len);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* The raw input as a message payload too (the link decodes what the frame layer hands it). */
    check_message(data, size);

    cs_frame_dec_t d;
    memset(&d, 0, sizeof d);
    cs_frame_dec_init(&d);
    for (size_t i = 0; i < size; i++) {
        cs_frame_t f;
        cs_err_t e = cs_frame_dec_feed(&d, data[i], &f);
        FUZZ_CHECK(e == CS_OK || e == CS_ERR_EMPTY || e == CS_ERR_CRC || e == CS_ERR_FRAME);
        if (e == CS_OK) {
            uint8_t copy[CS_FRAME_PAYLOAD_MAX];
            cs_frame_t c = f;
            memcpy(copy, f.payload, f.len); /* the view dies at the next feed */
            c.payload = copy;
            check_frame(&c);
        }
    }
    return 0;
}

#ifdef CS_FUZZ_SEED_MAIN
static void write_seed(const char *dir, const char *name, const cs_proto_msg_t *m, uint16_t seq)
{
    uint8_t p[CS_PROTO_LEN_MAX], wire[CS_FRAME_WIRE_MAX];
    size_t n = 0, wl = 0;
    if (cs_proto_encode(m, p, sizeof p, &n) != CS_OK ||
        cs_frame_encode(seq, p, n, wire, sizeof wire, &wl) != CS_OK) {
        fprintf(stderr, "fuzz_frame seed: cannot encode %s\n", name);
        exit(1);
    }
    fuzz_write_file(dir, name, wire, wl);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s corpus-dir\n", argv[0]);
        return 2;
    }
    cs_proto_msg_t m;
    memset(&m, 0, sizeof m);
    m.type = CS_PROTO_ACK;
    m.u.ack = (cs_proto_ack_t){CS_PROTO_ACK_NAK, 300, 12, 0xDEADBEEFu, 7};
    write_seed(argv[1], "ack", &m, 0);
    m.type = CS_PROTO_PING;
    m.u.ping.nonce = 0x01020304u;
    write_seed(argv[1], "ping", &m, 0);
    m.type = CS_PROTO_HELLO;
    m.u.hello = (cs_proto_hello_t){1, 0xCAFEF00Du, 4, 32, 1000000u, CS_PROTO_CAP_ALL};
    write_seed(argv[1], "hello", &m, 1);
    m.type = CS_PROTO_STATUS;
    m.u.status = (cs_proto_status_t){CS_PROTO_STATE_RUNNING,
                                     0xCAFEF00Du,
                                     5,
                                     99,
                                     4,
                                     {-1, 2, -300000, 40000},
                                     CS_PROTO_STATUS_JOB | CS_PROTO_STATUS_TICK,
                                     0x12345678u,
                                     1000u,
                                     1005u,
                                     0xFFFFFF00u};
    write_seed(argv[1], "status", &m, 2);
    m.u.status.flags = CS_PROTO_STATUS_JOB; /* protocol 2's, without the tick */
    m.u.status.tick = 0;
    write_seed(argv[1], "status2", &m, 2);
    m.type = CS_PROTO_ERROR;
    m.u.error = (cs_proto_error_t){CS_ERR_LIMIT, 77};
    write_seed(argv[1], "error", &m, 3);
    m.type = CS_PROTO_SEGMENT;
    m.u.segment = (cs_segment_t){2000, {120, -45, 0, 0}};
    write_seed(argv[1], "segment", &m, 0xFFFF);
    memset(&m, 0, sizeof m);
    m.type = CS_PROTO_CURVE;
    for (int i = 0; i < 4; i++)
        m.u.curve.p[i] = (cs_vec3_t){i * 65536, -i * 1000, 0};
    m.u.curve.feed = 50 * 65536;
    write_seed(argv[1], "curve", &m, 0x1234);
    memset(&m, 0, sizeof m);
    m.type = CS_PROTO_HOLD;
    write_seed(argv[1], "hold", &m, 5);
    m.type = CS_PROTO_RESUME;
    write_seed(argv[1], "resume", &m, 6);
    m.type = CS_PROTO_ABORT;
    write_seed(argv[1], "abort", &m, 7);
    m.type = CS_PROTO_QUERY;
    write_seed(argv[1], "query", &m, 8);
    m.type = CS_PROTO_SETPOS;
    m.u.setpos = (cs_proto_setpos_t){CS_PROTO_SETPOS_POS, 0x12345678u, 1000u, {800, -80, 0, 0}};
    write_seed(argv[1], "setpos", &m, 9);
    return 0;
}
#endif
