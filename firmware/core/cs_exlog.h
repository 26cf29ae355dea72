/* cs_exlog: the execution log a device keeps so that two devices can be proved to have run the
 * same job the same way: a running hash (FNV-1a 32, Fowler/Noll/Vo, public domain) and a count of
 * the step segments handed to the executor, and of the STEP edges it produced with their time on
 * the executor's clock. The executor's clock is the sum of the periods the executor asked for
 * (cs_stepper_out_t.next_ticks): it stands still while the executor is idle, so a device whose
 * ring ran dry for a while (a slow link) still logs the same edge times as one that never did,
 * and it equals the timer's ticks since the first segment when the ring never runs dry. Owns
 * nothing but the two small records below; no state of its own. */
#ifndef CS_EXLOG_H
#define CS_EXLOG_H

#include <stdint.h>

#include "cs_segment.h"
#include "cs_stepper.h"

/* FNV-1a 32 offset basis (the hash of nothing). */
#define CS_EXLOG_HASH0 2166136261u

/* Segments: count and hash of (ticks, steps[0..CS_AXES-1]) each as 4 bytes little-endian. */
typedef struct {
    uint32_t n;
    uint32_t hash;
} cs_exlog_segs_t;

/* STEP edges: count of pulses, hash of (clock as 4 bytes little-endian, step mask, DIR levels
 * during the pulse) for every executor call that pulsed, and the executor's clock, ticks. */
typedef struct {
    uint32_t n;
    uint32_t hash;
    uint32_t clock;
    uint8_t dir; /* DIR levels set by the previous call */
} cs_exlog_edges_t;

/* Empty logs. Not ISR-safe (call before the timer runs). */
void cs_exlog_segs_init(cs_exlog_segs_t *l);
void cs_exlog_edges_init(cs_exlog_edges_t *l);
/* Logs one segment handed to the executor. Main loop. */
void cs_exlog_segment(cs_exlog_segs_t *l, const cs_segment_t *s);
/* Logs one executor call's answer (right after cs_stepper_tick): its pulses, then advances the
 * clock by its period. ISR-safe (called from the step interrupt; a few dozen instructions). */
void cs_exlog_tick(cs_exlog_edges_t *l, const cs_stepper_out_t *o);

#endif
