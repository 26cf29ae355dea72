/* test_fixed on the portable arithmetic: cs_fixed.c built here with CS_FIXED_WIDE 0 (the 64-bit
 * schoolbook product and the bit-by-bit 128/64 divisions every MCU runs, where a 64-bit host
 * build takes its 128-bit type), linked in place of the library's copy (every cs_fixed symbol is
 * defined here, so the archive's member is never pulled), and checked by the same tests. */
#define CS_FIXED_WIDE 0
#include "../../firmware/core/cs_fixed.c"

#include "test_fixed.c"
