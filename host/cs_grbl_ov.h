/* cs_grbl_ov: Grbl 1.1's feed, rapid and spindle overrides for the Grbl front end. Owns the
 * three percentages, what each real-time override byte does to them (grbl wiki, "Interface",
 * real-time commands 0x90..0x9D), and how they change the moves not yet planned. Host only. */
#ifndef CS_GRBL_OV_H
#define CS_GRBL_OV_H

#include <stdbool.h>

#include "cs_path.h"

#define CS_GRBL_OV_MIN 10  /* Grbl's MIN_FEED_RATE_OVERRIDE / MIN_SPINDLE_SPEED_OVERRIDE, % */
#define CS_GRBL_OV_MAX 200 /* Grbl's MAX_..._OVERRIDE, % */

typedef struct {
    int feed;    /* % of the programmed feed, 10..200 */
    int rapid;   /* % of the rapid rate: 100, 50 or 25 */
    int spindle; /* % of the programmed S, 10..200 */
} cs_grbl_ov_t;

/* All at 100 %. */
void cs_grbl_ov_init(cs_grbl_ov_t *ov);
/* Real-time byte b: true when it is one of the override bytes 0x90..0x9D (the percentages then
 * changed as Grbl changes them, clamped to 10..200). */
bool cs_grbl_ov_byte(cs_grbl_ov_t *ov, unsigned char b);
/* Elements n0.. of path at the overrides: a feed move's feed (its own, or default_mm_s when it
 * has none) times feed %; below 100 %, a rapid move becomes a feed move at rapid % of
 * rapid_mm_s (the slowest axis's max rate: the rapid rate on every axis). */
void cs_grbl_ov_apply(const cs_grbl_ov_t *ov, cs_path_t *path, size_t n0, double default_mm_s,
                      double rapid_mm_s);

#endif
