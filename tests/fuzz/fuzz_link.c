/* libFuzzer target: arbitrary bytes from the peer into a link endpoint that is open and has
 * messages in flight, with polls in between (the input also drives the clock and the free
 * slots). Asserts (abort = finding): no out-of-bounds access or UB, only documented answers,
 * deliveries strictly consecutive, the window and the credits never exceeded.
 * Built and run by scripts/fuzz.sh; -DCS_FUZZ_SEED_MAIN builds the seed writer instead. */
#include <stdint.h>
#include <string.h>

#define FUZZ_NAME "fuzz_link"
#include "fuzz_common.h"

#include "cs_link.h"

static const cs_link_cfg_t cfg = {.rto = 50, .nak_holdoff = 5, .keepalive = 200, .rto_max = 200, .give_up = 750};

static size_t frame(uint16_t seq, const cs_proto_msg_t *m, uint8_t *out)
{
    uint8_t p[CS_PROTO_LEN_MAX];
    size_t n = 0, wl = 0;
    FUZZ_CHECK(cs_proto_encode(m, p, sizeof p, &n) == CS_OK);
    FUZZ_CHECK(cs_frame_encode(seq, p, n, out, CS_FRAME_WIRE_MAX, &wl) == CS_OK);
    return wl;
}

/* An endpoint that pinged with nonce 7 and got the ACK (next_expected 100, 5 credits, boot 9). */
static void open_link(cs_link_t *l)
{
    FUZZ_CHECK(cs_link_init(l, &cfg, 0xB0, 7, 0xFFF0, 0) == CS_OK);
    const uint8_t *b;
    size_t n;
    FUZZ_CHECK(cs_link_poll(l, 0, 3, &b, &n) == CS_OK); /* the PING */
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_ACK;
    m.u.ack = (cs_proto_ack_t){0, 100, 5, 9, 7};
    uint8_t w[CS_FRAME_WIRE_MAX];
    size_t wl = frame(0, &m, w);
    cs_link_event_t ev;
    for (size_t i = 0; i < wl; i++)
        FUZZ_CHECK(cs_link_feed(l, w[i], 1, 3, &ev) == CS_OK);
    FUZZ_CHECK(cs_link_state(l) == CS_LINK_OPEN);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static cs_link_t l;
    open_link(&l);
    cs_proto_msg_t seg = {0};
    seg.type = CS_PROTO_SEGMENT;
    seg.u.segment = (cs_segment_t){10, {1, -2, 3, 0}};
    int queued = 0;
    while (cs_link_send_msg(&l, &seg, NULL) == CS_OK)
        queued++;
    FUZZ_CHECK(queued == 5); /* the credits, below the window */
    uint32_t now = 2;
    uint16_t free_slots = 3;
    uint16_t next_delivery = 0xFFF0;
    for (size_t i = 0; i < size; i++) {
        cs_link_event_t ev;
        cs_err_t e = cs_link_feed(&l, data[i], now, free_slots, &ev);
        FUZZ_CHECK(e == CS_OK || e == CS_ERR_CRC || e == CS_ERR_FRAME || e == CS_ERR_RANGE ||
                   e == CS_ERR_UNSUPPORTED || e == CS_ERR_SEQ || e == CS_ERR_FULL);
        if (ev.what & CS_LINK_EV_DELIVER) {
            FUZZ_CHECK(ev.seq == next_delivery);
            FUZZ_CHECK(ev.len >= 1 && ev.len <= CS_FRAME_PAYLOAD_MAX && ev.payload != NULL);
            next_delivery++;
            if (cs_proto_uses_slot(ev.payload[0])) {
                FUZZ_CHECK(free_slots > 0);
                free_slots--;
            }
        }
        FUZZ_CHECK(cs_link_unacked(&l) <= CS_LINK_WINDOW);
        FUZZ_CHECK(l.slots_out <= cs_link_unacked(&l));
        /* Every 16th byte: the clock moves by the byte's value, a slot frees, we poll. */
        if ((i & 15) == 15) {
            now += data[i];
            if (free_slots < 8)
                free_slots++;
            const uint8_t *b;
            size_t n;
            for (int k = 0; k < 2 * CS_LINK_WINDOW + 2; k++) {
                cs_err_t r = cs_link_poll(&l, now, free_slots, &b, &n);
                FUZZ_CHECK(r == CS_OK || r == CS_END || r == CS_ERR_TIMEOUT);
                if (r != CS_OK)
                    break;
                FUZZ_CHECK(n >= 1 && n <= CS_FRAME_WIRE_MAX);
            }
            if (cs_link_state(&l) == CS_LINK_OPEN && cs_link_can_send(&l, CS_PROTO_SEGMENT))
                FUZZ_CHECK(cs_link_send_msg(&l, &seg, NULL) == CS_OK);
        }
    }
    return 0;
}

#ifdef CS_FUZZ_SEED_MAIN
/* Seeds: the ACKs, a NAK, a PING, a status and a new-boot hello the endpoint may receive. */
int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s corpus-dir\n", argv[0]);
        return 2;
    }
    uint8_t buf[8 * CS_FRAME_WIRE_MAX];
    size_t n = 0;
    cs_proto_msg_t m = {0};
    m.type = CS_PROTO_ACK;
    m.u.ack = (cs_proto_ack_t){0, 102, 4, 9, 7};
    n += frame(0, &m, buf + n);
    m.u.ack = (cs_proto_ack_t){CS_PROTO_ACK_NAK, 102, 4, 9, 7};
    n += frame(0, &m, buf + n);
    memset(&m, 0, sizeof m);
    m.type = CS_PROTO_PING;
    m.u.ping.nonce = 55;
    n += frame(0, &m, buf + n);
    memset(&m, 0, sizeof m);
    m.type = CS_PROTO_STATUS;
    m.u.status.axes = 3;
    m.u.status.boot_id = 9;
    n += frame(0xFFF0, &m, buf + n);
    memset(&m, 0, sizeof m);
    m.type = CS_PROTO_HELLO;
    m.u.hello = (cs_proto_hello_t){1, 10, 3, 8, 1000, 1};
    n += frame(0xFFF1, &m, buf + n);
    fuzz_write_file(argv[1], "session", buf, n);
    return 0;
}
#endif
