/* cs_crc: CRC-16/CCITT-FALSE, one byte at a time without a table.
 * Byte-wise form of the bitwise MSB-first division by x^16 + x^12 + x^5 + 1: with
 * x = (crc >> 8) ^ byte folded once (x ^= x >> 4), the eight bit steps collapse to
 * crc' = (crc << 8) ^ (x << 12) ^ (x << 5) ^ x (the classic table-less CCITT update; the
 * test checks it against the bitwise definition on every byte value and register). */
#include "cs_crc.h"

uint16_t cs_crc16_byte(uint16_t crc, uint8_t byte)
{
    uint16_t x = (uint16_t)(((unsigned)crc >> 8) ^ byte);
    x = (uint16_t)(x ^ (x >> 4));
    return (uint16_t)(((unsigned)crc << 8) ^ ((unsigned)x << 12) ^ ((unsigned)x << 5) ^ x);
}

uint16_t cs_crc16_update(uint16_t crc, const uint8_t *data, size_t len)
{
    for (size_t i = 0; i < len; i++)
        crc = cs_crc16_byte(crc, data[i]);
    return crc;
}

uint32_t cs_crc32_byte(uint32_t reg, uint8_t byte)
{
    /* Reflected (LSB-first) shift register: one conditional xor of the polynomial per bit,
     * written without a branch so every byte costs the same. */
    reg ^= byte;
    for (unsigned i = 0; i < 8; i++)
        reg = (reg >> 1) ^ (0xEDB88320u & (0u - (reg & 1u)));
    return reg;
}

uint32_t cs_crc32_update(uint32_t reg, const uint8_t *data, size_t len)
{
    for (size_t i = 0; i < len; i++)
        reg = cs_crc32_byte(reg, data[i]);
    return reg;
}
