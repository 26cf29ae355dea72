/* cs_stepper: the step executor. Owns a single-producer/single-consumer ring of step segments
 * (the main loop pushes, the timer interrupt pops) and the per-tick DDA (Bresenham) that spreads
 * each segment's steps evenly over its ticks, oversampling slow segments AMASS-style so the
 * minor axes step on time. It touches no hardware: each call says which STEP lines to pulse,
 * the DIR levels and when to be called again; the port (firmware/ports/port.h) does the I/O. */
#ifndef CS_STEPPER_H
#define CS_STEPPER_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_err.h"
#include "cs_machine.h"
#include "cs_segment.h"

/* Segment ring: a power of two <= 128 (8-bit indices are read atomically on every target). */
#ifndef CS_STEPPER_RING
#define CS_STEPPER_RING 16
#endif
/* AMASS: a segment whose dominant axis makes n steps in T ticks is run as n * 2^k DDA calls,
 * k <= CS_STEPPER_AMASS_MAX, as long as each call still lasts >= CS_STEPPER_MIN_CALL_TICKS. */
#define CS_STEPPER_AMASS_MAX      3
#define CS_STEPPER_MIN_CALL_TICKS 4

/* What one call asks the port to do: pulse the STEP line of every axis in step_mask (bit i =
 * axis i) with the DIR lines as they are, then set the DIR lines to dir_mask (bit set = line
 * high; already corrected for invert_dir), then call again after next_ticks ticks (0 = idle:
 * stop the timer until a push restarts it). */
typedef struct {
    uint8_t step_mask;
    uint8_t dir_mask;
    uint32_t next_ticks;
} cs_stepper_out_t;

/* A queued segment, prepared by cs_stepper_push (the main loop) so that loading it in the timer
 * interrupt is a copy: no division there. Calls C, base and rem as in cs_stepper.c. */
typedef struct {
    uint32_t calls; /* DDA calls C = n * 2^k */
    uint32_t base;  /* ticks per call: base, +1 for rem of the C calls */
    uint32_t rem;
    union {
        uint32_t w[CS_AXES]; /* |steps| per axis, wide segments */
        uint16_t n[CS_AXES]; /* |steps| per axis, narrow segments (C <= CS_STEPPER_NARROW_CALLS) */
    } mag;
    uint8_t neg;  /* axes moving negative */
    uint8_t dir;  /* DIR levels (invert_dir applied) */
    uint8_t move; /* axes with steps (bit i = axis i) */
    uint8_t wide; /* needs the 32-bit DDA */
    uint16_t aux; /* the producer's word for this segment, handed to the load hook */
} cs_stepper_seg_t;

/* Called from the step interrupt when a segment is loaded (its aux word) and when the ring has
 * run dry (aux 0): how the application makes an output follow the segments (laser power). */
typedef void (*cs_stepper_load_fn)(void *ctx, uint16_t aux);

/* A segment runs on the 16-bit DDA when C <= this and its base period < 0xFFFF: then every
 * accumulator, count and period of the segment fits 16 bits (8-bit targets do half the work). */
#define CS_STEPPER_NARROW_CALLS 0x7FFFu

typedef struct {
    /* ISR state. The common path (a narrow segment) reads only the fields up to n_e/n_mag, 55
     * bytes: on the AVR all within ldd's 63-byte displacement of one pointer. */
    volatile bool running; /* a segment is being executed */
    uint8_t wide;          /* the current segment runs on the 32-bit DDA */
    uint8_t move;          /* its axes with steps (bit i = axis i): the DDA visits only these */
    uint8_t neg_mask;      /* axes moving negative in the current segment */
    uint8_t dir_mask;      /* DIR levels for the current segment */
    volatile uint8_t head; /* written by the ISR only (consumer) */
    volatile uint8_t tail; /* written by the main loop only (producer) */
    uint8_t n_axes;
    uint8_t invert_mask; /* axes whose DIR line is inverted */
    /* The current segment's DDA, narrow (16 bits) or wide (32 bits, the w_ fields): left =
     * calls still to do; the period is base, + 1 when err + rem reaches C (Bresenham); per axis
     * e = accumulator - C, in [-C, 0): the axis steps when e + |steps| >= 0 (cs_stepper.c). */
    uint16_t n_left, n_calls, n_base, n_rem, n_err;
    uint32_t steps_done;           /* step pulses issued since init (all axes) */
    volatile int32_t pos[CS_AXES]; /* position in steps */
    int16_t n_e[CS_AXES];
    uint16_t n_mag[CS_AXES];
    uint32_t w_left, w_calls, w_base, w_rem, w_err;
    int32_t w_e[CS_AXES];
    uint32_t w_mag[CS_AXES];
    cs_stepper_seg_t ring[CS_STEPPER_RING];
    cs_stepper_load_fn on_load; /* NULL: none */
    void *load_ctx;
} cs_stepper_t;

/* Empty executor at position 0 for machine *m (axes, DIR inversion). Not ISR-safe. */
cs_err_t cs_stepper_init(cs_stepper_t *st, const cs_machine_t *m);
/* Queues a segment, with its DDA constants computed (one division: a few shift-subtract steps
 * when the period is under 256 ticks), so the interrupt's load is a copy. CS_ERR_FULL when the
 * ring is full, CS_ERR_ARG when the segment breaks its invariant (ticks == 0 or > 2^24,
 * |steps| > ticks). Main loop only; ISR-safe against cs_stepper_tick (single producer, single
 * consumer). */
cs_err_t cs_stepper_push(cs_stepper_t *st, const cs_segment_t *seg);
/* The same with the aux word the load hook gets when the segment starts. */
cs_err_t cs_stepper_push_aux(cs_stepper_t *st, const cs_segment_t *seg, uint16_t aux);
/* Sets the load hook (NULL: none). Not ISR-safe: call with the step interrupt masked. */
void cs_stepper_on_load(cs_stepper_t *st, cs_stepper_load_fn fn, void *ctx);
/* Stops at once: the running segment ends where it is and the ring is emptied (a hard limit, a
 * probe contact); the position stays exact (every step issued was counted). Call from the step
 * interrupt, from an interrupt that cannot preempt it or with it masked; the producer must push
 * nothing more until it has seen the halt (it pushes with the interrupt masked). The port's
 * timer is the caller's business (port_timer_stop). */
void cs_stepper_halt(cs_stepper_t *st);
/* Sets axis's position to steps (homing). Only while idle; not ISR-safe. CS_ERR_STATE when not
 * idle, CS_ERR_ARG for an axis out of range. */
cs_err_t cs_stepper_set_position(cs_stepper_t *st, unsigned axis, int32_t steps);
/* Free slots in the ring. ISR-safe. */
unsigned cs_stepper_free(const cs_stepper_t *st);
/* True when nothing is queued or executing. ISR-safe. */
bool cs_stepper_idle(const cs_stepper_t *st);
/* The timer call: ISR-safe. Work per call: one DDA update per moving axis, on 16 bits (on 32 for
 * a segment of more than CS_STEPPER_NARROW_CALLS calls or a period of 65535 ticks or more); a
 * call that ends a segment also loads the next (a copy). */
void cs_stepper_tick(cs_stepper_t *st, cs_stepper_out_t *out);
/* Position in steps of axis (0 when out of range). Read it with the timer interrupt masked on
 * targets where a 32-bit read is not atomic. */
int32_t cs_stepper_position(const cs_stepper_t *st, unsigned axis);

#endif
