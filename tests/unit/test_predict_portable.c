/* test_predict on the portable arithmetic: cs_predict.c built here with CS_PREDICT_PORTABLE 1
 * (the two 32x32 -> 64 products of mul_t, the bit-length logarithm and the test without the
 * guessed shift, what every firmware image runs, where a 64-bit host build takes its 128-bit
 * path), linked in place of the library's copy (every cs_predict symbol is defined here, so the
 * archive's member is never pulled), and checked by the same tests. */
#define CS_PREDICT_PORTABLE 1
#include "../../firmware/core/cs_predict.c"

#include "test_predict.c"
