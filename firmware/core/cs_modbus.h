/* cs_modbus: the device's Modbus register map (docs/modbus.md) and a small Modbus RTU server for
 * microcontrollers, where libmodbus does not run. Owns the register addresses, the mailbox
 * layout of a SEGMENT or CURVE (one FC16 write, last register = sequence number), the sequence
 * rule that makes retries idempotent, the writer lease's registers (the decision and the clock
 * are the application's hook), the PDU handler (FC03, FC04, FC06, FC16, exception replies),
 * CRC-16/MODBUS, RTU framing and the Modbus TCP (MBAP) header checks. Transport-agnostic:
 * Modbus TCP servers call the PDU handler directly. All state lives in caller-owned structs;
 * nothing is ISR-safe except the CRC (feed bytes from a main loop; an ISR should only queue them).
 */
#ifndef CS_MODBUS_H
#define CS_MODBUS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_err.h"
#include "cs_fixed.h"
#include "cs_proto.h"

/* Version of the register map (input register VERSION). */
#define CS_MODBUS_MAP_VERSION 2 /* 2: the writer lease (LEASE, RELEASE, TOKEN, IR 24..25) */

/* Function codes served. */
#define CS_MODBUS_FC_READ_HOLDING 0x03
#define CS_MODBUS_FC_READ_INPUT   0x04
#define CS_MODBUS_FC_WRITE_SINGLE 0x06
#define CS_MODBUS_FC_WRITE_MULTI  0x10

/* Exception codes (Modbus Application Protocol V1.1b, section 7). */
/* 0x01: a function code not served; also a write refused by another client's writer lease ("the
 * server is in the wrong state to process a request of this type", spec 7; REFUSED says which) */
#define CS_MODBUS_EX_ILLEGAL_FUNCTION 0x01
#define CS_MODBUS_EX_ILLEGAL_ADDRESS  0x02 /* register range outside the map */
#define CS_MODBUS_EX_ILLEGAL_VALUE    0x03 /* bad count, bad command, refused mailbox contents */
#define CS_MODBUS_EX_DEVICE_FAILURE   0x04 /* the device cannot act on a valid request */
#define CS_MODBUS_EX_DEVICE_BUSY      0x06 /* motion queue full: retry later, nothing was taken */

/* Holding registers (FC03 read, FC06 / FC16 write). Protocol addresses (0-based). */
#define CS_MODBUS_HR_COMMAND 0x0000 /* write CS_MODBUS_CMD_*; reads the last command accepted */
#define CS_MODBUS_HR_LEASE   0x0001 /* write a token (!= 0): claim or renew the writer lease */
#define CS_MODBUS_HR_RELEASE 0x0002 /* write the holder's token: give the lease back */
#define CS_MODBUS_HR_TOKEN   0x00FF /* FC16 from here: the writer's token, then the mailbox */
#define CS_MODBUS_HR_MAILBOX 0x0100 /* CS_MODBUS_MAILBOX_REGS registers, FC16 from here only */
/* Mailbox: word 0 = message type (cs_proto_type_t), then the fields as 32-bit values in two
 * registers, high word first, then the sequence number in the last register written. */
#define CS_MODBUS_MAILBOX_SEGMENT_REGS (1 + 2 + 2 * CS_AXES + 1) /* 12 */
#define CS_MODBUS_MAILBOX_CURVE_REGS   (1 + 2 * 12 + 2 + 1)      /* 28 */
#define CS_MODBUS_MAILBOX_PEN_REGS     (1 + 1 + 1) /* 3: type, pulse width (us), sequence */
#define CS_MODBUS_MAILBOX_REGS         CS_MODBUS_MAILBOX_CURVE_REGS

/* Commands (holding register COMMAND). */
#define CS_MODBUS_CMD_HOLD   1 /* decelerate to a stop, keep the queue */
#define CS_MODBUS_CMD_RESUME 2 /* go on after HOLD */
#define CS_MODBUS_CMD_ABORT  3 /* stop now, flush the queue */
#define CS_MODBUS_CMD_RESET  4 /* flush the queue, clear ERROR and REFUSED, state idle */

/* Input registers (FC04). 32-bit values take two registers, high word first. */
enum {
    CS_MODBUS_IR_VERSION = 0,      /* CS_MODBUS_MAP_VERSION */
    CS_MODBUS_IR_CAPS = 1,         /* CS_PROTO_CAP_* bits */
    CS_MODBUS_IR_AXES = 2,         /* 1..4 */
    CS_MODBUS_IR_QUEUE_SIZE = 3,   /* motion-queue slots */
    CS_MODBUS_IR_TICK_HZ = 4,      /* 4..5: executor ticks per second */
    CS_MODBUS_IR_BOOT_ID = 6,      /* 6..7: random per boot (a change = the device restarted) */
    CS_MODBUS_IR_STATE = 8,        /* cs_proto_state_t */
    CS_MODBUS_IR_FREE = 9,         /* free motion-queue slots */
    CS_MODBUS_IR_LAST_EXEC = 10,   /* sequence of the last message executed */
    CS_MODBUS_IR_NEXT_SEQ = 11,    /* the sequence the mailbox takes next */
    CS_MODBUS_IR_ERROR = 12,       /* cs_err_t of the last execution error (0: none) */
    CS_MODBUS_IR_ERROR_SEQ = 13,   /* sequence of the message that error is about */
    CS_MODBUS_IR_REFUSED = 14,     /* cs_err_t of the last mailbox write refused (0: none) */
    CS_MODBUS_IR_REFUSED_SEQ = 15, /* the sequence that write carried */
    CS_MODBUS_IR_POS = 16,         /* 16..23: position of axes x, y, z, a in steps (int32) */
    CS_MODBUS_IR_LEASE = 24,       /* 0 the mailbox is free, 1 leased (the token is never shown) */
    CS_MODBUS_IR_LEASE_LEFT = 25,  /* ms until the lease expires unless renewed (0: free) */
    CS_MODBUS_IR_COUNT = 26
};

/* What the application reports on every FC04 read (identity and live status). */
typedef struct {
    uint16_t caps;
    uint8_t axes;
    uint16_t queue_size;
    uint32_t tick_hz;
    uint32_t boot_id;
    uint8_t state;          /* cs_proto_state_t */
    uint16_t free_slots;    /* free motion-queue slots */
    uint16_t last_exec;     /* sequence of the last message executed */
    uint16_t error;         /* cs_err_t of the last execution error, 0 none */
    uint16_t error_seq;     /* its message's sequence */
    int32_t pos[CS_AXES];   /* steps */
    uint8_t lease;          /* 1: the mailbox is leased */
    uint16_t lease_left_ms; /* until it expires unless renewed */
} cs_modbus_status_t;

/* What the lease hook is asked (docs/modbus.md, "The writer lease"). */
enum {
    CS_MODBUS_LEASE_CLAIM = 1,   /* token != 0 claims the free lease or renews its own */
    CS_MODBUS_LEASE_RELEASE = 2, /* token gives its lease back */
    CS_MODBUS_LEASE_WRITE = 3    /* a mailbox write carrying token (0: none) may be taken */
};

/* The application behind the map: every hook gets ctx. */
typedef struct {
    /* Queue a SEGMENT or CURVE (checked already) with its sequence: CS_OK, CS_ERR_FULL when no
     * slot is left (refused with exception DEVICE_BUSY), another code to refuse it. */
    cs_err_t (*submit)(void *ctx, const cs_proto_msg_t *m, uint16_t seq);
    /* Obey CS_MODBUS_CMD_* (already checked). */
    void (*command)(void *ctx, uint16_t cmd);
    /* Fill *st with the live status. */
    void (*status)(void *ctx, cs_modbus_status_t *st);
    /* Optional (NULL: no lease, LEASE and RELEASE are outside the map and every mailbox write
     * is considered). CS_MODBUS_LEASE_*: CS_OK (taken, renewed, released, or the write may go
     * on), CS_ERR_LEASED when another token holds an unexpired lease (exception 1, REFUSED =
     * CS_ERR_LEASED). */
    cs_err_t (*lease)(void *ctx, uint8_t op, uint16_t token);
    void *ctx;
} cs_modbus_app_t;

typedef struct {
    uint32_t requests;   /* PDUs handled */
    uint32_t exceptions; /* exception replies */
    uint32_t accepted;   /* mailbox writes queued */
    uint32_t repeats;    /* retries of the last accepted write, answered OK, not queued again */
    uint32_t refused;    /* mailbox writes refused (sequence, contents, queue full) */
} cs_modbus_stats_t;

/* The register map's state. */
typedef struct {
    cs_modbus_app_t app;
    uint16_t next_seq;                     /* sequence the mailbox takes next */
    uint16_t last[CS_MODBUS_MAILBOX_REGS]; /* the last accepted write, as written */
    uint8_t last_n;                        /* its register count, 0 before any */
    uint16_t last_cmd;                     /* last command accepted */
    uint16_t refused, refused_seq;         /* why the last mailbox write was refused */
    cs_modbus_stats_t stats;
} cs_modbus_map_t;

/* Sets up the map with the application's hooks (submit, command and status required; lease
 * optional) and the first sequence the mailbox takes (0 after a boot). CS_ERR_ARG for a missing
 * hook. */
cs_err_t cs_modbus_map_init(cs_modbus_map_t *mp, const cs_modbus_app_t *app, uint16_t first_seq);
/* Handles one request PDU (function code + data, req[0..n)) and writes the response PDU (the
 * normal answer or the two-byte exception) into rsp[0..cap), *rn = its length. CS_OK (a
 * response is always written), CS_ERR_ARG for NULL pointers or cap < CS_MODBUS_PDU_MAX. */
#define CS_MODBUS_PDU_MAX 253
cs_err_t cs_modbus_pdu(cs_modbus_map_t *mp, const uint8_t *req, size_t n, uint8_t *rsp, size_t cap,
                       size_t *rn);

/* Mailbox codec, shared by the host and the device. Encodes a SEGMENT, CURVE or PEN and its
 * sequence into regs[0..cap), *n = registers: CS_ERR_UNSUPPORTED for another type, CS_ERR_RANGE for
 * a field outside its cs_proto range, CS_ERR_FULL when cap is too small. Pure. */
cs_err_t cs_modbus_mailbox_encode(const cs_proto_msg_t *m, uint16_t seq, uint16_t *regs, size_t cap,
                                  size_t *n);
/* Decodes n registers written to the mailbox: CS_ERR_FRAME when n does not match the type in
 * word 0, CS_ERR_UNSUPPORTED for an unknown type, CS_ERR_RANGE for a field outside its range.
 * Pure. */
cs_err_t cs_modbus_mailbox_decode(const uint16_t *regs, size_t n, cs_proto_msg_t *m, uint16_t *seq);

/* CRC-16/MODBUS: reflected polynomial 0xA001 (0x8005), init 0xFFFF, no final xor; check value
 * CRC("123456789") = 0x4B37. Sent low byte first. Pure, ISR-safe, table-less. */
#define CS_MODBUS_CRC_INIT 0xFFFFu
uint16_t cs_modbus_crc(uint16_t crc, const uint8_t *data, size_t len);

/* --- Modbus TCP: the MBAP header (Modbus Messaging on TCP/IP Implementation Guide V1.0b, 3.1.3):
 * transaction id (2 bytes), protocol id (2, 0 = Modbus), length (2: the bytes that follow, unit
 * id + PDU), unit id (1), then the PDU. */
#define CS_MODBUS_MBAP_LEN 7
#define CS_MODBUS_TCP_MAX  (CS_MODBUS_MBAP_LEN + CS_MODBUS_PDU_MAX)

typedef struct {
    uint16_t tid;   /* transaction id, echoed in the answer */
    uint16_t proto; /* protocol id: 0 for Modbus */
    uint8_t unit;
    size_t pdu_len; /* bytes of PDU after the header */
} cs_modbus_mbap_t;

/* Looks at the first n bytes of a Modbus TCP stream. CS_ERR_EMPTY: the frame is not complete
 * yet; CS_OK: a whole frame of CS_MODBUS_MBAP_LEN + h->pdu_len bytes; CS_ERR_UNSUPPORTED: a whole
 * frame of that size whose protocol id is not 0 (not Modbus: drop it, unanswered);
 * CS_ERR_FRAME: a length field outside 2..254 (no PDU, or longer than any PDU: the stream
 * cannot be resynchronised, close the connection). Pure. */
cs_err_t cs_modbus_mbap_parse(const uint8_t *b, size_t n, cs_modbus_mbap_t *h);
/* Writes the answer frame: h's transaction id and unit, protocol 0, the length of pdu[0..n),
 * then the PDU, into out[0..cap): *len bytes. CS_ERR_FULL when it does not fit. Pure. */
cs_err_t cs_modbus_mbap_frame(const cs_modbus_mbap_t *h, const uint8_t *pdu, size_t n, uint8_t *out,
                              size_t cap, size_t *len);

/* --- RTU server ---------------------------------------------------------------------------- */

/* Largest RTU frame: address + PDU + CRC. */
#define CS_MODBUS_RTU_MAX (1 + CS_MODBUS_PDU_MAX + 2)

typedef struct {
    uint32_t frames;     /* frames addressed to this unit (or broadcast) and answered */
    uint32_t crc_errs;   /* frames dropped for a bad CRC */
    uint32_t other_unit; /* good frames for another unit: ignored, not answered */
    uint32_t broadcasts; /* broadcast writes (unit 0): executed, not answered */
    uint32_t overruns;   /* frames longer than CS_MODBUS_RTU_MAX: dropped */
} cs_modbus_rtu_stats_t;

typedef struct {
    cs_modbus_map_t *map;
    uint8_t unit;    /* 1..247 */
    uint32_t gap_us; /* silence that ends a frame (t3.5) in the caller's microseconds */
    uint8_t in[CS_MODBUS_RTU_MAX];
    size_t n;         /* bytes of the frame being received */
    bool overrun;     /* skip to the next silence */
    uint32_t last_us; /* time of the last byte */
    uint8_t out[CS_MODBUS_RTU_MAX];
    cs_modbus_rtu_stats_t stats;
} cs_modbus_rtu_t;

/* Sets up an RTU server for unit (1..247) on a line of baud bits/s: t3.5 = 3.5 characters of
 * 11 bits, fixed at 1750 us above 19200 baud (Modbus over serial line V1.02, 2.5.1.1).
 * CS_ERR_ARG for a bad unit, baud 0 or a NULL map. */
cs_err_t cs_modbus_rtu_init(cs_modbus_rtu_t *r, cs_modbus_map_t *map, uint8_t unit, uint32_t baud);
/* Feeds one received byte at now_us (microseconds, wrapping). A frame ends when its length is
 * complete for the request format of FC03/04/06/16 and its CRC checks, or (any other function)
 * at t3.5 of silence (cs_modbus_rtu_idle). CS_OK with *reply and *len set when a reply frame is to
 * be written now, CS_ERR_EMPTY otherwise. Not ISR-safe (runs the PDU handler). */
cs_err_t cs_modbus_rtu_feed(cs_modbus_rtu_t *r, uint8_t byte, uint32_t now_us,
                            const uint8_t **reply, size_t *len);
/* Called when no byte arrived: after t3.5 of silence, a pending frame of unknown length is
 * checked and handled (CS_OK with a reply, as cs_modbus_rtu_feed), or dropped. */
cs_err_t cs_modbus_rtu_idle(cs_modbus_rtu_t *r, uint32_t now_us, const uint8_t **reply,
                            size_t *len);
/* Builds an RTU frame (unit, PDU, CRC low byte first) into out[0..cap): *len bytes. For
 * replies the device makes itself (and the host's tests). CS_ERR_FULL when it does not fit. */
cs_err_t cs_modbus_rtu_frame(uint8_t unit, const uint8_t *pdu, size_t n, uint8_t *out, size_t cap,
                             size_t *len);

#endif
