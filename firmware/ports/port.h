/* port: the seam between the core and one target. The core never touches a register: the
 * executor (cs_stepper) says what to do, a port does it. Every target implements these plain
 * functions (firmware/ports/<target>/); firmware/ports/template/port_template.c says what each
 * one must do. Ticks are the executor's time base (cs_machine_t.tick_hz). */
#ifndef PORT_H
#define PORT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_err.h"
#include "cs_stepper.h"

/* Brings up clocks, the step timer (stopped), STEP/DIR pins (low) and the UART. */
void port_init(void);
/* Free-running tick counter (wraps at 2^32; compare with port_ticks_before). ISR-safe. */
uint32_t port_ticks_now(void);
/* Ticks per second of port_ticks_now and of the step timer. ISR-safe. */
uint32_t port_tick_hz(void);
/* The step interrupt calls cs_stepper_tick on st; attach before arming the timer. */
void port_stepper_attach(cs_stepper_t *st);
/* Arms the step timer to fire once, `ticks` (>= 1) ticks from now. ISR-safe. */
void port_timer_arm(uint32_t ticks);
/* Stops the step timer (no further step interrupt until armed again). ISR-safe. */
void port_timer_stop(void);
/* Masks interrupts and returns the previous state, for port_irq_restore. */
uint32_t port_irq_save(void);
/* Restores the interrupt state returned by port_irq_save. */
void port_irq_restore(uint32_t state);
/* Raises the STEP line of every axis in mask (bit i = axis i) for the axis's pulse width, with
 * the DIR lines as they are. ISR-safe. */
void port_step_pulse(uint8_t mask);
/* Sets the DIR lines (bit set = high). ISR-safe. */
void port_dir_set(uint8_t mask);
/* Reads up to max bytes received on the UART without blocking; returns the count. */
size_t port_uart_read(uint8_t *buf, size_t max);
/* Queues len bytes for the UART; returns how many were accepted (non-blocking). */
size_t port_uart_write(const uint8_t *buf, size_t len);
/* Sets the pen servo's pulse width, us (400..2600: a PEN message, docs/protocol.md); the port
 * keeps it (a 50 Hz RC-servo pulse train, or a recorded value: docs/firmware.md says which
 * port does what). Called from the main loop with the executor stopped; not ISR-safe. */
void port_pen_set(uint16_t pulse_us);
/* The machine's inputs now: CS_PROTO_IN_* bits (cs_proto.h: min / max limit switch per axis,
 * probe, e-stop), set = active whatever the wiring's polarity (the port inverts). ISR-safe. */
uint16_t port_inputs_read(void);
/* The edge hook: the port calls fn(ctx) from its pin-change / edge interrupt on the input pins
 * (or where it samples them, e.g. after a step), an interrupt that cannot preempt the step
 * interrupt (same priority, or the step interrupt itself); fn reads port_inputs_read and keeps
 * what changed (firmware/app/cs_fw_ctl.c: the one change detector), so a call with nothing
 * changed is harmless. fn may halt the executor. NULL fn: none. Not ISR-safe. */
void port_inputs_attach(void (*fn)(void *ctx), void *ctx);
/* The spindle / laser output: PWM duty in 1/1000 of the period (0..1000), mode 0 off (enable
 * low, duty 0), 1 clockwise, 2 counter-clockwise (direction line high). ISR-safe. */
void port_spindle_set(uint16_t duty, uint8_t mode);
/* Unrecoverable error: stop the timer, drop STEP lines, report code, stay safe. */
void port_fault(cs_err_t code);

/* True when tick a is before tick b, across the 2^32 wrap (valid for distances < 2^31). */
static inline bool port_ticks_before(uint32_t a, uint32_t b)
{
    return (int32_t)(a - b) < 0;
}

#endif
