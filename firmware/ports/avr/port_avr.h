/* port_avr: the ATmega328p port (16 MHz, an Arduino Uno with a Grbl-style CNC shield). Owns
 * USART0 (interrupt-driven, RX and TX rings), Timer1 (free-running tick counter and one-shot
 * step deadlines on compare A) and the STEP/DIR/enable pins of Grbl 1.1's Uno pin map. Every
 * size and rate is a compile-time macro below; docs/firmware-avr.md gives the numbers.
 *
 * Time: Timer1 counts F_CPU / 8 = 2 MHz ("counts"); the executor's tick is 2^PORT_AVR_TICK_SHIFT
 * counts, so port_tick_hz() = 2 MHz >> PORT_AVR_TICK_SHIFT (31.25 kHz, a 32 us tick, by
 * default) and ticks <-> counts are shifts, never a division. The machine file's tick_hz must
 * equal it (firmware/ports/avr/machine.ini). */
#ifndef PORT_AVR_H
#define PORT_AVR_H

#include <stdbool.h>
#include <stdint.h>

#include "port.h"

#ifndef F_CPU
#define F_CPU 16000000UL
#endif
/* Timer1 prescaler 8: 2 MHz counts, 0.5 us resolution, 32.8 ms per 16-bit wrap. */
#define PORT_AVR_COUNT_HZ (F_CPU / 8u)
/* One executor tick = 2^PORT_AVR_TICK_SHIFT counts. 6: 31.25 kHz (32 us). The executor's AMASS runs
 * the step interrupt at up to tick_hz / 4 on slow moves (cs_stepper.h: calls >= 4 ticks), so the
 * tick rate bounds the interrupt load: 7.8 kHz at most from AMASS at 31.25 kHz. */
#ifndef PORT_AVR_TICK_SHIFT
#define PORT_AVR_TICK_SHIFT 6
#endif
#define PORT_AVR_TICK_HZ ((uint32_t)(PORT_AVR_COUNT_HZ >> PORT_AVR_TICK_SHIFT))
/* STEP pulse width, microseconds (the machine file's pulse_us must say the same). */
#ifndef PORT_AVR_PULSE_US
#define PORT_AVR_PULSE_US 2
#endif
#define PORT_AVR_PULSE_COUNTS ((uint16_t)(PORT_AVR_PULSE_US * (PORT_AVR_COUNT_HZ / 1000000u)))
/* Line speed; U2X is used (115200: UBRR 16, 117647 baud, +2.1 %, as on every Arduino). */
#ifndef PORT_AVR_BAUD
#define PORT_AVR_BAUD 115200UL
#endif
/* UART rings, bytes (powers of two <= 256). RX: 64 bytes = 5.5 ms of line at 115200, two
 * segment frames; TX: the longest frame the device sends (STATUS, 33 bytes) plus an ACK. */
#ifndef PORT_AVR_RX_RING
#define PORT_AVR_RX_RING 64
#endif
#ifndef PORT_AVR_TX_RING
#define PORT_AVR_TX_RING 64
#endif

/* Pins (Grbl 1.1, Uno): STEP x/y/z = PD2/PD3/PD4, DIR x/y/z = PD5/PD6/PD7, stepper enable = PB0
 * (active low, as on the CNC shield: low = drivers on). Three axes; an a axis has no pin.
 * Machine control: limit / home switches x/y/z = PB1 (D9) / PC1 (A1) / PB4 (D12), probe PC5
 * (A5), e-stop PC0 (A0: Grbl's reset pin), spindle PWM PB3 (D11, OC2A on Timer2), spindle enable
 * PC3 (A3), direction PC4 (A4), the pen servo OC1B = PB2 (D10, Timer1 compare B: the one
 * hardware-timed output left, so Grbl's y switch pin moved to A1). Timers: Timer1 the tick
 * counter, the step deadline (compare A) and the servo (compare B); Timer2 the spindle; Timer0
 * unused. port_avr.c static-asserts that no two functions share a pin. */
#define PORT_AVR_AXES      3
#define PORT_AVR_STEP_BIT0 2
#define PORT_AVR_DIR_BIT0  5

/* 1 (Grbl's wiring): switches, probe and e-stop pull their pin to ground, the internal pull-ups
 * hold it high otherwise, so low = active; 0: active high (external pull-downs). */
#ifndef PORT_AVR_INPUTS_ACTIVE_LOW
#define PORT_AVR_INPUTS_ACTIVE_LOW 1
#endif

/* Diagnostics, for tests and benchmarks (read with interrupts masked or when idle). */
typedef struct {
    uint16_t late;     /* step deadlines already past when armed (interrupt overran) */
    uint16_t rx_lost;  /* bytes dropped: RX ring full */
    uint16_t rx_error; /* bytes with a framing or overrun error */
    uint8_t fault;     /* cs_err_t given to port_fault, 0 when none */
} port_avr_stats_t;

/* Copy of the counters. Not ISR-safe (masks interrupts briefly). */
void port_avr_stats(port_avr_stats_t *out);
/* True when received bytes wait in the RX ring (for the main loop's sleep decision, checked with
 * interrupts masked so a byte cannot slip in between the check and the sleep). ISR-safe. */
bool port_avr_rx_pending(void);

#endif
