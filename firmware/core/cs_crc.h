/* cs_crc: the frame check of the wire protocol, CRC-32 (IEEE 802.3: reflected poly 0xEDB88320,
 * init and final xor 0xFFFFFFFF; check value CRC("123456789") = 0xCBF43926), and CRC-16/CCITT-FALSE
 * (poly 0x1021, init 0xFFFF; check 0x29B1) for short local checks. Table-less byte updates
 * (no 512-byte table in an AVR's RAM), constant time per byte, so it can run inside a UART ISR.
 * Parameters and the residue property used by cs_frame are in docs/protocol.md. */
#ifndef CS_CRC_H
#define CS_CRC_H

#include <stddef.h>
#include <stdint.h>

/* Initial register value of CRC-16/CCITT-FALSE. */
#define CS_CRC16_INIT 0xFFFFu
/* Appending a message's CRC to it (high byte first) makes the CRC of the whole equal to this
 * residue: the decoder checks frames without knowing where the CRC starts. */
#define CS_CRC16_RESIDUE 0x0000u

/* Register after one more byte. Pure, ISR-safe, a dozen shifts and xors. */
uint16_t cs_crc16_byte(uint16_t crc, uint8_t byte);
/* Register after len more bytes of data (data may be NULL when len is 0). ISR-safe, O(len).
 * Start with CS_CRC16_INIT; the final register is the CRC (no final xor). */
uint16_t cs_crc16_update(uint16_t crc, const uint8_t *data, size_t len);

/* CRC-32: initial register; the CRC of a message is register ^ 0xFFFFFFFF. */
#define CS_CRC32_INIT 0xFFFFFFFFu
/* Appending a message's CRC-32 to it (low byte first) leaves this in the register: the decoder
 * checks frames without knowing where the CRC starts (the standard CRC-32 residue). */
#define CS_CRC32_RESIDUE 0xDEBB20E3u

/* CRC-32 register after one more byte. Pure, ISR-safe, 8 shift-and-xor steps. */
uint32_t cs_crc32_byte(uint32_t reg, uint8_t byte);
/* CRC-32 register after len more bytes (data may be NULL when len is 0). ISR-safe, O(len). */
uint32_t cs_crc32_update(uint32_t reg, const uint8_t *data, size_t len);

#endif
