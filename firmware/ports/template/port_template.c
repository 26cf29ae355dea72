/* port_template: the skeleton of a new port. Copy this folder to firmware/ports/<target>/ and
 * fill each function as its comment says; everything here compiles as is (freestanding C99; `make
 * firmware` compiles it for the Cortex-M3 so it stays buildable) and does nothing, so a port can be
 * brought up one function at a time. The step interrupt at the bottom is the one piece of glue
 * every port needs: it is written once, here, and a port only renames it to its timer's vector.
 *
 * What sits on top: the application (firmware/app/cs_fw_app.h) is the whole device (link, queue,
 * executor feeding, curves); a port adds a main that calls port_init, fills the machine
 * (cs_fw_machine_default(&m, port_tick_hz())), cs_fw_app_init and then cs_fw_app_poll in a loop
 * (firmware/app/main.c does exactly that; firmware/ports/cortex-m3/main_m3.c also sleeps and
 * reports). The host's machine file must say the same (firmware/ports/<target>/machine.ini).
 *
 * Bring-up order that works: (1) port_init + port_ticks_now (blink a pin every 2^k ticks);
 * (2) the UART rings (echo bytes); (3) port_irq_save/restore; (4) the step timer and its interrupt
 * with port_step_pulse/port_dir_set (a scope, or an emulator's pin trace); (5) the application:
 * `curvestep stream --port` a job and compare the final position with `curvestep-sim --replay`
 * (tests/fw/test_fw_m3.sh does this under qemu). A build rule in mk/fw-<target>.mk links the core,
 * $(FW_APP_SRC) and the port with --gc-sections and runs scripts/fw-check.sh on the image. */
#include "port.h"

static cs_stepper_t *step_st;

void port_init(void)
{
    /* Clocks; a free-running counter at port_tick_hz() (e.g. a 32-bit timer, or a 16-bit one
     * extended in its overflow interrupt); the one-shot step timer, stopped; STEP and DIR pins
     * as outputs, low; the UART with receive and transmit buffers. */
}

uint32_t port_ticks_now(void)
{
    /* Return the free-running counter. Must be callable from interrupts, and wrap at 2^32
     * exactly (the link and the main loop compare ticks with port_ticks_before): a 16-bit
     * timer is extended by counting its overflows in software, reading both consistently. */
    return 0;
}

uint32_t port_tick_hz(void)
{
    /* The counter's and step timer's rate: the machine file's tick_hz must equal it. */
    return 100000u;
}

void port_stepper_attach(cs_stepper_t *st)
{
    step_st = st;
}

void port_timer_arm(uint32_t ticks)
{
    /* Program the step timer to interrupt once, `ticks` ticks after the previous deadline (or
     * after now when the timer was stopped), so periods add up without drift. A timer with
     * fewer bits splits long periods and calls the step interrupt on the last part only. */
    (void)ticks;
}

void port_pen_set(uint16_t pulse_us)
{
    /* The pen servo: a 50 Hz pulse train (20 ms period) whose high time becomes pulse_us,
     * e.g. a PWM timer channel with a 1 us count and compare = pulse_us; the new width takes
     * effect at the next period. Without a servo output, keep the value (a debugger reads it). */
    (void)pulse_us;
}

uint16_t port_inputs_read(void)
{
    /* Read the switch, probe and e-stop pins, invert the active-low ones and pack them as
     * CS_PROTO_IN_* bits (min switch of axis i = bit i, max = bit 4 + i, probe 8, e-stop 9). */
    return 0;
}

void port_inputs_attach(void (*fn)(void *ctx), void *ctx)
{
    /* Keep fn and ctx (interrupts masked); enable a pin-change / edge interrupt on every input
     * pin at the step timer's priority (so fn never preempts the step interrupt). Its handler
     * clears the flag and calls fn(ctx), nothing more: the application reads port_inputs_read
     * and keeps what changed, and reads the pins once at start (a switch already pressed). */
    (void)fn;
    (void)ctx;
}

void port_spindle_set(uint16_t duty, uint8_t mode)
{
    /* A hardware PWM timer's compare = duty x period / 1000; enable pin = mode != 0; direction
     * pin = mode == 2. Must be safe to call from the step interrupt (laser power per segment). */
    (void)duty;
    (void)mode;
}

void port_timer_stop(void)
{
    /* Disable the step timer interrupt. */
}

uint32_t port_irq_save(void)
{
    /* Read the interrupt-enable state, disable interrupts, return the old state
     * (Cortex-M: PRIMASK then cpsid i; AVR: SREG then cli). */
    return 0;
}

void port_irq_restore(uint32_t state)
{
    /* Put back the state port_irq_save returned. */
    (void)state;
}

void port_step_pulse(uint8_t mask)
{
    /* Raise STEP of every axis in mask, hold it for that axis's pulse_ticks (busy-wait when
     * short, or a second compare channel), lower it. DIR must not change meanwhile. */
    (void)mask;
}

void port_dir_set(uint8_t mask)
{
    /* Drive DIR of axis i high when bit i is set. The executor changes it at least one DDA call
     * before the next step, which must cover the driver's DIR setup time. */
    (void)mask;
}

size_t port_uart_read(uint8_t *buf, size_t max)
{
    /* Copy up to max received bytes from the receive ring (filled by the UART's receive
     * interrupt: the application reads in its main loop, which may be busy tracing a curve for
     * longer than the UART's FIFO lasts); never block. */
    (void)buf;
    (void)max;
    return 0;
}

size_t port_uart_write(const uint8_t *buf, size_t len)
{
    /* Queue up to len bytes for transmission; return how many fit; never block (the
     * application keeps what did not fit and offers it again). A transmit ring of a few hundred
     * bytes, emptied by the UART's transmit interrupt, lets a whole frame go at once. */
    (void)buf;
    (void)len;
    return 0;
}

void port_fault(cs_err_t code)
{
    /* Stop the step timer, drop every STEP line, report code (LED, UART) and stay safe until
     * reset. Never returns to motion by itself. */
    (void)code;
    port_timer_stop();
}

/* The step interrupt: rename to the timer's vector. Pulses, then DIR, then the next deadline. */
void port_template_step_isr(void);
void port_template_step_isr(void)
{
    cs_stepper_out_t o;
    if (step_st == NULL)
        return;
    cs_stepper_tick(step_st, &o);
    port_step_pulse(o.step_mask);
    port_dir_set(o.dir_mask);
    if (o.next_ticks != 0)
        port_timer_arm(o.next_ticks);
    else
        port_timer_stop();
}
