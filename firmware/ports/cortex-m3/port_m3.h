/* port_m3: what the Cortex-M3 port (TI Stellaris LM3S6965, qemu's lm3s6965evb board) offers
 * beyond port.h: the core clock and its cycle counter, the STEP/DIR lines as the pins saw them
 * (for the report a test compares with the simulator), sleeping until the next interrupt, and a
 * fault flag. Pin map: STEP x/y/z/a on PD0..PD3, DIR x/y/z/a on PD4..PD7 (high = positive),
 * driver ENABLE on PG0 (low = enabled), pen servo on PG1 (50 Hz, high = the pulse), UART0 on PA0 (RX) / PA1 (TX) at 115200 8N1. */
#ifndef PORT_M3_H
#define PORT_M3_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_exlog.h"
#include "port.h"

#define PORT_M3_SYSCLK_HZ 50000000u /* PLL: 200 MHz / 4 (8 MHz crystal on the EVB) */
#ifndef PORT_M3_TICK_HZ
#define PORT_M3_TICK_HZ 100000u /* port_tick_hz(): the executor's tick, 10 us */
#endif
#define PORT_M3_BAUD     115200u
#define PORT_M3_RX_RING  512u /* UART receive ring, bytes (power of two) */
#define PORT_M3_TX_RING  512u /* UART transmit ring, bytes (power of two) */
#define PORT_M3_PULSE_US 2u   /* STEP pulse width: machine.ini pulse_us */

/* Core clock cycles since port_init, modulo 2^32 (SysTick extended by its wrap interrupt).
 * ISR-safe. */
uint32_t port_m3_cycles(void);
/* Per axis: STEP pulses issued and the position they made with the DIR level at each pulse
 * (DIR high = +1). ISR-safe snapshot. */
void port_m3_pins(uint32_t pulses[4], int32_t pos[4]);
/* The STEP edges the step interrupt produced, logged on the executor's clock (cs_exlog: the
 * simulator logs the same through firmware/ports/posix). ISR-safe snapshot. */
void port_m3_edges(cs_exlog_edges_t *l);
/* Sleeps (WFI) until the next interrupt unless a received byte waits or transmit bytes are
 * queued. Main loop only. */
void port_m3_sleep(void);
/* Spins (no sleep) until the next interrupt has run, or a bounded while: the wait while motion
 * runs (see main_m3.c). Main loop only. */
void port_m3_spin(void);
/* Step interrupts that ran the executor (one per DDA call). */
uint32_t port_m3_step_irqs(void);
/* Bytes the UART received while its ring was full (lost). */
uint32_t port_m3_rx_overruns(void);
/* The pen servo's pulse train as the port measured it (SysTick cycles stamped in the edge
 * interrupts) and as its timers are programmed (registers read back): port_m3_servo.c. */
typedef struct {
    uint32_t periods;    /* rise-to-rise intervals measured */
    uint64_t span_cyc;   /* the periods summed, core cycles (mean = span / periods) */
    uint32_t min_cyc;    /* shortest period, core cycles (0 when none) */
    uint32_t max_cyc;    /* longest period, core cycles */
    uint32_t high_n;     /* pulses measured since the width last changed */
    uint32_t high_sum;   /* their widths summed, core cycles */
    uint32_t period_reg; /* Timer1A's period as programmed: TAILR + 1, cycles */
    uint32_t width_reg;  /* Timer2A's load (the last pulse's width) as programmed, cycles */
} port_m3_servo_t;
/* Snapshot of the servo measurements and registers. ISR-safe. */
void port_m3_servo(port_m3_servo_t *out);
/* Code passed to port_fault (CS_OK when none). */
cs_err_t port_m3_fault_code(void);
/* Machine control (port_m3_ctl.c). Pins: limit switches min x/y/z/a on PB0..PB3, max on
 * PB4..PB7, probe on PE0, e-stop on PE1: active high with the internal pull-downs (switches to
 * 3.3 V), or active low with the pull-ups when built with -DPORT_M3_INPUTS_ACTIVE_LOW=1; an
 * interrupt on both edges at the step timer's priority; spindle / laser PWM on PF0 (the PWM
 * module's generator 0, PORT_M3_SPINDLE_HZ), enable on PC4 (high = on), direction on PC5 (high =
 * counter-clockwise). Init: called by port_init. Stepped: the step interrupt calls it after
 * pulses (simulated switches). Sim switch: input bit `bit` (CS_PROTO_IN_*) reads active while
 * axis's STEP/DIR position is >= at (above) or <= at: qemu's board has no switch to press
 * (main_m3.c sets them from its command line). Spindle: the settings so far, the last duty and
 * mode. */
#ifndef PORT_M3_SPINDLE_HZ
#define PORT_M3_SPINDLE_HZ 5000u
#endif
void port_m3_ctl_init(void);
void port_m3_ctl_stepped(void);
void port_m3_sim_switch(uint16_t bit, uint8_t axis, int32_t at, bool above);
void port_m3_spindle(uint32_t *settings, uint16_t *duty, uint8_t *mode);
/* Called by port_fault after the machine is made safe (main_m3.c: report and exit under qemu). */
void port_m3_on_fault(cs_err_t code);

#endif
