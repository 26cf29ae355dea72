/* port_template: the skeleton of a new port. Copy this folder to firmware/ports/<target>/ and
 * fill each function as its comment says; everything here compiles as is (freestanding C99)
 * and does nothing, so a port can be brought up one function at a time. The step interrupt at
 * the bottom is the one piece of glue every port needs: it is written once, here, and a port
 * only renames it to its timer's vector. */
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
    /* Return the free-running counter. Must be callable from interrupts. */
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
    /* Copy up to max received bytes from the receive buffer; never block. */
    (void)buf;
    (void)max;
    return 0;
}

size_t port_uart_write(const uint8_t *buf, size_t len)
{
    /* Queue up to len bytes for transmission; return how many fit; never block. */
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
