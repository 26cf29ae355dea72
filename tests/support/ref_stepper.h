/* ref_stepper: a frozen copy of the step executor cs_stepper (firmware/core/cs_stepper.c/.h) as it
 * was before its 8-bit optimisation, prefix renamed; tests/unit/test_stepper_equiv.c runs it call
 * by call against cs_stepper to prove the optimised executor's output bit-identical. Tests only:
 * do not change its behaviour. Original header comment:
 *
 * cs_stepper: the step executor. Owns a single-producer/single-consumer ring of step segments
 * (the main loop pushes, the timer interrupt pops) and the per-tick DDA (Bresenham) that spreads
 * each segment's steps evenly over its ticks, oversampling slow segments AMASS-style so the
 * minor axes step on time. It touches no hardware: each call says which STEP lines to pulse,
 * the DIR levels and when to be called again; the port (firmware/ports/port.h) does the I/O. */
#ifndef REF_STEPPER_H
#define REF_STEPPER_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_err.h"
#include "cs_machine.h"
#include "cs_segment.h"

/* Segment ring: a power of two <= 128 (8-bit indices are read atomically on every target). */
#ifndef REF_STEPPER_RING
#define REF_STEPPER_RING 16
#endif
/* AMASS: a segment whose dominant axis makes n steps in T ticks is run as n * 2^k DDA calls,
 * k <= REF_STEPPER_AMASS_MAX, as long as each call still lasts >= REF_STEPPER_MIN_CALL_TICKS. */
#define REF_STEPPER_AMASS_MAX      3
#define REF_STEPPER_MIN_CALL_TICKS 4

/* What one call asks the port to do: pulse the STEP line of every axis in step_mask (bit i =
 * axis i) with the DIR lines as they are, then set the DIR lines to dir_mask (bit set = line
 * high; already corrected for invert_dir), then call again after next_ticks ticks (0 = idle:
 * stop the timer until the next push restarts it). */
typedef struct {
    uint8_t step_mask;
    uint8_t dir_mask;
    uint32_t next_ticks;
} ref_stepper_out_t;

typedef struct {
    cs_segment_t ring[REF_STEPPER_RING];
    volatile uint8_t head; /* written by the ISR only (consumer) */
    volatile uint8_t tail; /* written by the main loop only (producer) */
    /* ISR state */
    volatile bool running; /* a segment is being executed */
    uint8_t n_axes;
    uint8_t invert_mask;  /* axes whose DIR line is inverted */
    uint8_t dir_mask;     /* DIR levels for the current segment */
    uint8_t neg_mask;     /* axes moving negative in the current segment */
    uint32_t calls;       /* DDA calls in the current segment */
    uint32_t call_idx;    /* calls done */
    uint32_t period_base; /* ticks per call: base, +1 for rem of the calls (Bresenham) */
    uint32_t period_rem;
    uint32_t period_err;
    uint32_t mag[CS_AXES];         /* |steps| per axis (the DDA adds it every call) */
    uint32_t acc[CS_AXES];         /* DDA accumulators */
    volatile int32_t pos[CS_AXES]; /* position in steps */
    uint32_t steps_done;           /* step pulses issued since init (all axes) */
} ref_stepper_t;

/* Empty executor at position 0 for machine *m (axes, DIR inversion). Not ISR-safe. */
cs_err_t ref_stepper_init(ref_stepper_t *st, const cs_machine_t *m);
/* Queues a segment. CS_ERR_FULL when the ring is full, CS_ERR_ARG when the segment breaks its
 * invariant (ticks == 0 or > 2^24, |steps| > ticks). Main loop only; ISR-safe against
 * ref_stepper_tick (single producer, single consumer). */
cs_err_t ref_stepper_push(ref_stepper_t *st, const cs_segment_t *seg);
/* Free slots in the ring. ISR-safe. */
unsigned ref_stepper_free(const ref_stepper_t *st);
/* True when nothing is queued or executing. ISR-safe. */
bool ref_stepper_idle(const ref_stepper_t *st);
/* The timer call: ISR-safe, constant work per call (one DDA update per axis). */
void ref_stepper_tick(ref_stepper_t *st, ref_stepper_out_t *out);
/* Position in steps of axis (0 when out of range). Read it with the timer interrupt masked on
 * targets where a 32-bit read is not atomic. */
int32_t ref_stepper_position(const ref_stepper_t *st, unsigned axis);

#endif
