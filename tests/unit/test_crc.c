/* test_crc: CRC-16/CCITT-FALSE against the published check values of the CRC catalogue
 * (Greg Cook's "Catalogue of parametrised CRC algorithms": CCITT-FALSE 0x29B1, XMODEM 0x31C3,
 * SPI-FUJITSU/AUG-CCITT 0xE5CC, GENIBUS 0xD64E for "123456789") and against a bitwise
 * (one polynomial division step per bit) reference written here, for every register and byte. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "cs_crc.h"

static const uint8_t check_msg[] = "123456789";

/* MSB-first division by x^16 + x^12 + x^5 + 1, one bit at a time: the CRC's definition. */
static uint16_t ref_byte(uint16_t crc, uint8_t b)
{
    crc ^= (uint16_t)(b << 8);
    for (int i = 0; i < 8; i++)
        crc = (crc & 0x8000u) ? (uint16_t)((crc << 1) ^ 0x1021u) : (uint16_t)(crc << 1);
    return crc;
}

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static uint64_t rng(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return rng_state;
}

static void test_published_check_values(void **state)
{
    (void)state;
    assert_int_equal(cs_crc16_update(CS_CRC16_INIT, check_msg, 9), 0x29B1); /* CCITT-FALSE */
    assert_int_equal(cs_crc16_update(0x0000, check_msg, 9), 0x31C3);        /* XMODEM */
    assert_int_equal(cs_crc16_update(0x1D0F, check_msg, 9), 0xE5CC);        /* AUG-CCITT */
    assert_int_equal(cs_crc16_update(CS_CRC16_INIT, check_msg, 9) ^ 0xFFFF, 0xD64E); /* GENIBUS */
}

/* CRC-32 (IEEE 802.3), the frame check: the published check value, and the residue that the frame
 * decoder relies on (message followed by its CRC, low byte first) for every length up to 80. */
static void test_crc32_check_value_and_residue(void **state)
{
    (void)state;
    assert_int_equal(cs_crc32_update(CS_CRC32_INIT, check_msg, 9) ^ 0xFFFFFFFFu, 0xCBF43926u);
    uint8_t msg[84];
    for (size_t n = 0; n <= 80; n++) {
        for (size_t i = 0; i < n; i++)
            msg[i] = (uint8_t)(i * 37u + n);
        uint32_t c = cs_crc32_update(CS_CRC32_INIT, msg, n) ^ 0xFFFFFFFFu;
        for (int k = 0; k < 4; k++)
            msg[n + (size_t)k] = (uint8_t)(c >> (8 * k));
        assert_int_equal(cs_crc32_update(CS_CRC32_INIT, msg, n + 4), CS_CRC32_RESIDUE);
    }
}

static void test_empty_input_keeps_register(void **state)
{
    (void)state;
    assert_int_equal(cs_crc16_update(CS_CRC16_INIT, NULL, 0), CS_CRC16_INIT);
    assert_int_equal(cs_crc16_update(0x1234, check_msg, 0), 0x1234);
}

static void test_byte_update_matches_bitwise_definition(void **state)
{
    (void)state;
    unsigned mismatches = 0;
    for (uint32_t crc = 0; crc <= 0xFFFF; crc++)
        for (uint32_t b = 0; b <= 0xFF; b++)
            if (cs_crc16_byte((uint16_t)crc, (uint8_t)b) != ref_byte((uint16_t)crc, (uint8_t)b))
                mismatches++;
    assert_int_equal(mismatches, 0);
}

static void test_appended_crc_leaves_zero_residue(void **state)
{
    (void)state;
    uint8_t msg[80];
    for (int trial = 0; trial < 1000; trial++) {
        size_t n = 1 + (size_t)(rng() % 70);
        for (size_t i = 0; i < n; i++)
            msg[i] = (uint8_t)rng();
        uint16_t c = cs_crc16_update(CS_CRC16_INIT, msg, n);
        msg[n] = (uint8_t)(c >> 8);
        msg[n + 1] = (uint8_t)c;
        assert_int_equal(cs_crc16_update(CS_CRC16_INIT, msg, n + 2), CS_CRC16_RESIDUE);
    }
}

/* A CRC-16 with this polynomial detects every 1- and 2-bit error in frames far longer than ours
 * (x^16+x^12+x^5+1 has period 32767): check every single and double flip of a 64-byte frame. */
static void test_detects_all_one_and_two_bit_errors(void **state)
{
    (void)state;
    uint8_t msg[64];
    for (size_t i = 0; i < sizeof msg; i++)
        msg[i] = (uint8_t)rng();
    const uint16_t good = cs_crc16_update(CS_CRC16_INIT, msg, sizeof msg);
    unsigned undetected = 0;
    const unsigned bits = sizeof msg * 8;
    for (unsigned a = 0; a < bits; a++) {
        msg[a / 8] ^= (uint8_t)(1u << (a % 8));
        if (cs_crc16_update(CS_CRC16_INIT, msg, sizeof msg) == good)
            undetected++;
        for (unsigned b = a + 1; b < bits; b++) {
            msg[b / 8] ^= (uint8_t)(1u << (b % 8));
            if (cs_crc16_update(CS_CRC16_INIT, msg, sizeof msg) == good)
                undetected++;
            msg[b / 8] ^= (uint8_t)(1u << (b % 8));
        }
        msg[a / 8] ^= (uint8_t)(1u << (a % 8));
    }
    assert_int_equal(undetected, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_published_check_values),
        cmocka_unit_test(test_crc32_check_value_and_residue),
        cmocka_unit_test(test_empty_input_keeps_register),
        cmocka_unit_test(test_byte_update_matches_bitwise_definition),
        cmocka_unit_test(test_appended_crc_leaves_zero_residue),
        cmocka_unit_test(test_detects_all_one_and_two_bit_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
