/* main_avr: the ATmega328p image's main: the port, the default machine at the port's tick rate
 * (firmware/ports/avr/machine.ini says the same for the host), the application, and its loop,
 * sleeping (idle mode: timers and the USART keep running) whenever a pass leaves nothing to do
 * until an interrupt. Every interrupt wakes the loop: a received byte, a step, and the Timer1
 * overflow every 32.8 ms that keeps the link's timers (50 ms and more) serviced. */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>

#include "cs_fw_app.h"
#include "port_avr.h"

static cs_machine_t machine;
static cs_fw_app_t app;
/* Power-up SRAM contents: noise on a real chip (zeros in simavr), mixed into the boot id. Read
 * from the first MAIN_AVR_NOISE_WORDS words of free RAM past the static data (__heap_start, the
 * avr-libc linker script's end of .noinit; no heap here), which the C start-up code never clears
 * and the stack, growing down from the top, has not reached yet: the 32 bytes of a .noinit array
 * without taking them from the static budget (docs/firmware-avr.md, "The 2 KB build"). A warm
 * reset keeps them (unless the stack went that deep since), and the value written back makes the
 * next boot id differ. */
#define MAIN_AVR_NOISE_WORDS 8u
extern uint8_t __heap_start;
int main(void)
{
    port_init();
    uint32_t boot = 2166136261u; /* FNV-1a over the noise */
    volatile uint32_t *noise = (volatile uint32_t *)(void *)&__heap_start;
    for (unsigned i = 0; i < MAIN_AVR_NOISE_WORDS; i++)
        boot = (boot ^ noise[i]) * 16777619u;
    boot ^= port_ticks_now();
    noise[0] = boot + 1u;
    cs_fw_machine_default(&machine, port_tick_hz());
    if (cs_fw_app_init(&app, &machine, boot) != CS_OK)
        port_fault(CS_ERR_ARG);
    for (;;) {
        cs_fw_app_poll(&app);
        /* sleep only when nothing is pending; interrupts masked from the check to the sleep
         * instruction (SEI's successor always runs first), so no wake-up is lost */
        cli();
        if (cs_fw_app_can_sleep(&app) && !port_avr_rx_pending()) {
            SMCR = (uint8_t)(1u << SE); /* idle mode (SM = 0), sleep enabled */
            sei();
            sleep_cpu();
            SMCR = 0;
        }
        sei();
    }
}
