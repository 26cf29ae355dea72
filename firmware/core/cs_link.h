/* cs_link: the reliable link of the wire protocol (docs/protocol.md, "Reliable delivery"), one
 * endpoint = a sender (window of unacknowledged frames, go-back-N retransmission on timeout or
 * NAK, flow-control credits never exceeded, reset and dead-peer detection) and a receiver
 * (in-order exactly-once delivery, duplicates dropped, ACK = next expected + credits). Transport-
 * agnostic and clock-agnostic: the caller feeds received bytes, polls bytes to write, and passes
 * the time in its own ticks. All state lives in the caller's cs_link_t; nothing is ISR-safe
 * (feed bytes from a main loop; an ISR should only queue them). */
#ifndef CS_LINK_H
#define CS_LINK_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_err.h"
#include "cs_fixed.h"
#include "cs_frame.h"
#include "cs_proto.h"

/* Unacknowledged frames the sender keeps for retransmission: a power of two, 1..128 (a 2 KB AVR
 * build may use -DCS_LINK_WINDOW=2 -DCS_FRAME_PAYLOAD_MAX=40: STATUS with 3 axes and its tick). */
#ifndef CS_LINK_WINDOW
#define CS_LINK_WINDOW 8
#endif
#define CS_LINK_WINDOW_MASK (CS_LINK_WINDOW - 1)
CS_STATIC_ASSERT(CS_LINK_WINDOW >= 1 && CS_LINK_WINDOW <= 128 &&
                     (CS_LINK_WINDOW & (CS_LINK_WINDOW - 1)) == 0,
                 link_window_power_of_two);
/* Bytes of the largest link-control frame (ACK). */
#define CS_LINK_CTL_WIRE CS_FRAME_WIRE_LEN(CS_PROTO_LEN_ACK)

/* Timing, in the caller's ticks (any unit, uint32, wrapping is fine). Backoff (docs/protocol.md
 * 3.3): the k-th timeout in a row without progress (k = 0, 1, ...) waits min(rto * 2^k, rto_max)
 * after the frame or PING it covers was (re)sent; the first progress (an ACK that moves the
 * window, or the echo of our PING) starts again at rto. The link is closed by the first timeout
 * that finds the peer silent (no valid ACK from it since the link was opened or started) for
 * give_up ticks, so a dead peer is declared so between give_up and give_up + rto_max after its
 * last ACK. */
typedef struct {
    uint32_t rto;         /* first retransmission timeout: > round trip + one window, >= 1 */
    uint32_t rto_max;     /* cap of the doubled timeout, >= rto */
    uint32_t give_up;     /* silence before the link is closed, >= 1 */
    uint32_t nak_holdoff; /* a NAK resends only if the frame it names went out this long ago:
                           * about one round trip (frame + ACK), so repeats are ignored */
    uint32_t keepalive;   /* silence from the peer before a PING probes it; 0 = no probing */
} cs_link_cfg_t;

/* Sender states. */
typedef enum {
    CS_LINK_CONNECTING = 0, /* pinging the peer to learn its next expected sequence and boot id */
    CS_LINK_OPEN = 1,       /* sending */
    CS_LINK_RESET = 2,      /* the peer restarted (new boot id): stopped until cs_link_restart */
    CS_LINK_CLOSED = 3,     /* the peer stopped answering: stopped until cs_link_restart */
} cs_link_state_t;

/* What a received frame did (bits of cs_link_event_t.what). */
#define CS_LINK_EV_DELIVER 0x01u /* seq/payload/len: the next message, in order, exactly once */
#define CS_LINK_EV_OPEN    0x02u /* the sender connected (peer_boot, last_acked = base - 1) */
#define CS_LINK_EV_RESET   0x04u /* the peer restarted: old/new boot ids, last_acked, unacked */

typedef struct {
    uint8_t what;           /* CS_LINK_EV_* bits, 0 when the frame only fed the link */
    uint16_t seq;           /* DELIVER: sequence of the message */
    uint8_t len;            /* DELIVER: payload bytes */
    const uint8_t *payload; /* DELIVER: valid until the next cs_link_feed */
    uint32_t old_boot;      /* RESET: boot id the sender was talking to */
    uint32_t new_boot;      /* RESET: the peer's new boot id; OPEN: the peer's boot id */
    uint16_t last_acked;    /* RESET/OPEN: last sequence the peer acknowledged */
    uint16_t unacked;       /* RESET: messages sent after last_acked whose fate is unknown */
} cs_link_event_t;

typedef struct {
    uint32_t delivered;    /* messages delivered in order */
    uint32_t duplicates;   /* sequenced frames already delivered, dropped */
    uint32_t out_of_order; /* sequenced frames beyond the next expected, dropped */
    uint32_t refused;      /* slot-using frames refused: no room (the peer broke the credits) */
    uint32_t retransmits;  /* frames sent again */
    uint32_t timeouts;     /* retransmission timeouts */
    uint32_t naks;         /* NAKs received that triggered a resend */
    uint32_t stale_acks;   /* ACKs older than the window, ignored */
    uint32_t bad;          /* frames that decoded but made no sense (bad ACK/PING, seq) */
} cs_link_stats_t;

typedef struct {
    uint8_t wire[CS_FRAME_WIRE_MAX];
    uint8_t wire_len;
    bool uses_slot;
    bool sent;
    uint32_t sent_at; /* last (re)transmission, for the NAK hold-off */
} cs_link_slot_t;

typedef struct {
    cs_link_cfg_t cfg;
    cs_frame_dec_t dec;
    uint8_t ctl[CS_LINK_CTL_WIRE]; /* last ACK or PING handed out by cs_link_poll */
    /* sender */
    cs_link_slot_t ring[CS_LINK_WINDOW]; /* frame seq lives in ring[seq & CS_LINK_WINDOW_MASK] */
    uint8_t state;                       /* cs_link_state_t */
    uint16_t base;                       /* oldest unacknowledged sequence */
    uint16_t next;                       /* sequence of the next message queued */
    uint16_t send_pos;                   /* next sequence to put on the wire (go-back-N) */
    uint16_t credits;                    /* peer's free slots for sequences >= base */
    uint16_t slots_out;                  /* slot-using messages in [base, next) */
    uint32_t peer_boot;
    uint32_t nonce;    /* of the outstanding or last PING; never 0 */
    bool ping_out;     /* a PING waits for its echo */
    bool blocked;      /* a send was refused for want of credits */
    uint8_t retries;   /* timeouts in a row without progress (saturating): the backoff's k */
    uint32_t timer_at; /* oldest frame last sent, or last progress */
    uint32_t ping_at;  /* PING last sent */
    uint32_t heard_at; /* last valid ACK from the peer (or the start): silence for give_up */
    /* receiver */
    uint32_t boot_id;       /* our own boot id, in every ACK */
    uint16_t next_expected; /* next sequence to deliver */
    uint16_t adv_credits;   /* credits the peer believes it has (last ACK minus deliveries) */
    uint32_t echo;          /* nonce of the last PING received, 0 before any */
    bool ack_due, nak_due, heard;
    cs_link_stats_t stats;
} cs_link_t;

/* Set up an endpoint: receiver expecting rx_first_seq, sender CONNECTING (its first poll sends a
 * PING with nonce). boot_id: our own random boot id; nonce: != 0, should differ per start.
 * CS_ERR_ARG for a NULL pointer, cfg->rto or cfg->give_up of 0, cfg->rto_max < cfg->rto, or
 * nonce 0. */
cs_err_t cs_link_init(cs_link_t *l, const cs_link_cfg_t *cfg, uint32_t boot_id, uint32_t nonce,
                      uint16_t rx_first_seq, uint32_t now);
/* Restart the sender only (after RESET or CLOSED, or to start a new job): drops every queued
 * frame, back to CONNECTING with a new nonce (!= 0, CS_ERR_ARG). The receiver is kept. */
cs_err_t cs_link_restart(cs_link_t *l, uint32_t nonce, uint32_t now);

/* Feed one received byte. free_slots: motion-queue slots free now. CS_OK with ev->what telling
 * what happened (0 when nothing for the caller); a delivered slot-using message must be queued
 * before the next call. Errors (the byte is still consumed, the link goes on): CS_ERR_CRC /
 * CS_ERR_FRAME (a damaged frame was dropped), CS_ERR_FULL (the next message uses a slot and
 * free_slots is 0: dropped, it will be resent), CS_ERR_FRAME / CS_ERR_RANGE / CS_ERR_UNSUPPORTED
 * (an ACK or PING with a bad payload), CS_ERR_SEQ (an ACK for a sequence never sent). */
cs_err_t cs_link_feed(cs_link_t *l, uint8_t byte, uint32_t now, uint16_t free_slots,
                      cs_link_event_t *ev);
/* The same for an already decoded frame (from cs_frame_dec_feed). */
cs_err_t cs_link_on_frame(cs_link_t *l, const cs_frame_t *f, uint32_t now, uint16_t free_slots,
                          cs_link_event_t *ev);

/* True when cs_link_send would accept a message of this type now (OPEN, window not full and, for
 * a slot-using type, a credit left). */
bool cs_link_can_send(const cs_link_t *l, uint8_t type);
/* Queue one sequenced message (payload = an encoded cs_proto message, 1..CS_FRAME_PAYLOAD_MAX
 * bytes); *seq (may be NULL) = its sequence. CS_ERR_STATE unless OPEN, CS_ERR_FULL when the
 * window is full or no credit is left (retry after the next ACK), CS_ERR_ARG for a bad length or
 * an unsequenced type (ACK, PING). The bytes go out through cs_link_poll. */
cs_err_t cs_link_send(cs_link_t *l, const uint8_t *payload, size_t len, uint16_t *seq);
/* cs_proto_encode then cs_link_send. */
cs_err_t cs_link_send_msg(cs_link_t *l, const cs_proto_msg_t *m, uint16_t *seq);

/* Next bytes to write to the transport: an ACK when one is due, else a PING when connecting or
 * probing, else the next new or retransmitted frame. CS_OK with *bytes and *len set (valid until
 * the next call), CS_END when nothing is to be written now, CS_ERR_TIMEOUT once when the peer has
 * stopped answering for cfg.give_up (state becomes CLOSED). Call it after feeding bytes and every few ticks.
 * free_slots: as for cs_link_feed (sent as the credits of the ACK). */
cs_err_t cs_link_poll(cs_link_t *l, uint32_t now, uint16_t free_slots, const uint8_t **bytes,
                      size_t *len);

/* Sender state (cs_link_state_t). */
cs_link_state_t cs_link_state(const cs_link_t *l);
/* Last sequence the peer acknowledged (base - 1). */
uint16_t cs_link_last_acked(const cs_link_t *l);
/* Messages queued and not yet acknowledged. */
uint16_t cs_link_unacked(const cs_link_t *l);
/* Wrap-safe sequence order: true when a comes before b (a - b in 0x8000..0xFFFF mod 2^16). */
bool cs_link_seq_before(uint16_t a, uint16_t b);

#endif
