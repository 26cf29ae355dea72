/* ref_xorshift32: the 32-bit xorshift generator (shifts 13, 17, 5; Marsaglia, "Xorshift RNGs",
 * 2003) the motion tests (test_segment, test_stepper) draw their random jobs from: one generator,
 * so a seed names the same job in every test. Caller-owned state; tests only. */
#ifndef REF_XORSHIFT32_H
#define REF_XORSHIFT32_H

#include <stdint.h>

typedef struct {
    uint32_t s; /* the state: set it to the seed (never 0) */
} ref_xorshift32_t;

/* Next 32-bit value (advances g). */
uint32_t ref_xorshift32_next(ref_xorshift32_t *g);
/* Uniform double in [lo, hi) from the next value (advances g). */
double ref_xorshift32_uniform(ref_xorshift32_t *g, double lo, double hi);

#endif
