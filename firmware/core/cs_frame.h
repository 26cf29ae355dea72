/* cs_frame: the framing layer of the wire protocol (docs/protocol.md, "Frames"). A frame is
 * LEN, SEQ (16-bit), PAYLOAD (LEN bytes), CRC-32 (cs_crc), COBS-encoded so that 0x00 never occurs
 * inside it, and delimited by 0x00 sync bytes. Owns the encoder (into a caller buffer) and the
 * incremental byte-at-a-time decoder that resynchronises on the next 0x00 after any garbage. */
#ifndef CS_FRAME_H
#define CS_FRAME_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_err.h"
#include "cs_fixed.h"

/* Largest payload (message) in bytes. The largest message (curve) needs 54; a build for a 2 KB
 * RAM part may lower it with -DCS_FRAME_PAYLOAD_MAX=... down to the messages it uses. */
#ifndef CS_FRAME_PAYLOAD_MAX
#define CS_FRAME_PAYLOAD_MAX 64
#endif
/* The sync byte: delimits frames; COBS guarantees it never occurs inside one. */
#define CS_FRAME_SYNC    0x00u
#define CS_FRAME_HEADER  3 /* LEN, SEQ low, SEQ high */
#define CS_FRAME_TRAILER 4 /* CRC-32, low byte first */
/* Decoded (inner) frame: header + payload + CRC. */
#define CS_FRAME_INNER_MAX (CS_FRAME_HEADER + CS_FRAME_PAYLOAD_MAX + CS_FRAME_TRAILER)
/* Bytes on the wire for the largest frame: leading sync, COBS (1 code byte per started 254-byte
 * block), trailing sync. */
#define CS_FRAME_WIRE_MAX (1 + CS_FRAME_INNER_MAX + CS_FRAME_INNER_MAX / 254 + 1 + 1)
/* Bytes on the wire for a frame carrying payload_len bytes. */
#define CS_FRAME_WIRE_LEN(payload_len)                                                             \
    (1 + (CS_FRAME_HEADER + (payload_len) + CS_FRAME_TRAILER) +                                    \
     (CS_FRAME_HEADER + (payload_len) + CS_FRAME_TRAILER) / 254 + 1 + 1)

/* A decoded frame. payload points into the decoder's buffer: valid until the next feed call. */
typedef struct {
    uint16_t seq;
    uint8_t len; /* 1..CS_FRAME_PAYLOAD_MAX */
    const uint8_t *payload;
} cs_frame_t;

/* Counters a link keeps for diagnostics (never wrap past UINT32_MAX: saturating). */
typedef struct {
    uint32_t frames;   /* good frames returned */
    uint32_t crc_errs; /* frames whose CRC failed */
    uint32_t bad;      /* malformed: truncated COBS block, wrong LEN, too short or too long */
} cs_frame_stats_t;

/* Caller-owned decoder state; no pointers, so it may be copied or zeroed. */
typedef struct {
    uint8_t buf[CS_FRAME_INNER_MAX];
    uint16_t len; /* decoded bytes in buf */
    uint32_t crc; /* CRC-32 register over buf[0..len) */
    uint8_t left; /* bytes still to come in the current COBS block (0: next is a code) */
    uint8_t code; /* code byte of the current COBS block */
    bool started; /* a non-sync byte has been seen since the last sync */
    bool overrun; /* too many bytes: the frame is discarded at the next sync */
    cs_frame_stats_t stats;
} cs_frame_dec_t;

CS_STATIC_ASSERT(CS_FRAME_PAYLOAD_MAX >= 16 && CS_FRAME_PAYLOAD_MAX <= 250, frame_payload_fits_len);
CS_STATIC_ASSERT(CS_FRAME_INNER_MAX <= 255, frame_inner_fits_u8);

/* Reset the decoder and zero its counters: it waits for the first byte of a frame (bytes before the
 * first sync are decoded too; a frame is accepted only if its CRC checks). Not ISR-safe against a
 * concurrent feed. */
void cs_frame_dec_init(cs_frame_dec_t *d);
/* Feed one received byte. ISR-safe: O(1), touches only *d. Returns
 *   CS_OK          a good frame ended with this byte: *out is set (payload valid until next feed);
 *   CS_ERR_EMPTY   byte consumed, no frame finished (also for empty frames between syncs);
 *   CS_ERR_CRC     a frame ended whose CRC failed (it is dropped; decoding goes on);
 *   CS_ERR_FRAME   a malformed frame ended (truncated COBS block, LEN disagreeing with the
 *                  frame size, shorter than header + 1 payload byte + CRC, or too long). */
cs_err_t cs_frame_dec_feed(cs_frame_dec_t *d, uint8_t byte, cs_frame_t *out);

/* Encode one frame into out[0..cap): sync, COBS(LEN SEQ PAYLOAD CRC), sync; *out_len = bytes
 * written (at most CS_FRAME_WIRE_LEN(len)). CS_ERR_ARG when len is 0 or above CS_FRAME_PAYLOAD_MAX
 * or a pointer is NULL; CS_ERR_FULL when cap < CS_FRAME_WIRE_LEN(len) (out untouched). ISR-safe. */
cs_err_t cs_frame_encode(uint16_t seq, const uint8_t *payload, size_t len, uint8_t *out, size_t cap,
                         size_t *out_len);

#endif
