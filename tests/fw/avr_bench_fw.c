/* avr_bench_fw: the ATmega328p benchmark image (tests/fw/bench_avr.sh runs it in simavr through
 * tests/fw/avr_harness.c). No link: the main loop only keeps the executor's ring full, so the step
 * interrupt (the port's, the core's executor: exactly the production code) has the CPU to itself.
 * It runs phases of constant step rate, first on x alone, then on x, y and z together, each
 * phase N_STEPS steps per moving axis in 5 ms segments, phases 20 ms apart (the script splits the
 * STEP edges at those gaps and compares each phase's achieved rate with the requested one). */
#include <avr/interrupt.h>
#include <avr/sleep.h>

#include "cs_stepper.h"
#include "port_avr.h"

/* requested rates, steps per second per moving axis (a whole number of steps per segment) */
/* keep equal to RATES in tests/fw/bench_avr.sh */
static const uint16_t rates[] = {4000,  6000,  8000,  10000, 11000, 12000, 13000,
                                 14000, 15000, 16000, 18000, 20000, 24000, 31000};
#define N_RATES (sizeof rates / sizeof rates[0])
#define N_STEPS 2000u
#define SEG_MS  5u
#define GAP_MS  20u

static cs_stepper_t st;
static cs_machine_t m;

/* Queues one segment (spins while the ring is full) and starts the timer when it was idle. */
static void push(const cs_segment_t *s)
{
    for (;;) {
        uint32_t irq = port_irq_save();
        bool idle = cs_stepper_idle(&st);
        cs_err_t e = cs_stepper_push(&st, s);
        if (e == CS_OK && idle)
            port_timer_arm(1);
        port_irq_restore(irq);
        if (e == CS_OK)
            return;
    }
}

static void wait_idle_then(uint32_t ticks)
{
    while (!cs_stepper_idle(&st))
        ;
    uint32_t t0 = port_ticks_now();
    while (port_ticks_now() - t0 < ticks)
        ;
}

int main(void)
{
    m.n_axes = 3;
    (void)cs_stepper_init(&st, &m);
    port_init();
    port_stepper_attach(&st);
    uint32_t hz = port_tick_hz();
    uint32_t seg_ticks = hz * SEG_MS / 1000u;
    for (uint8_t axes = 1; axes <= 3; axes = (uint8_t)(axes + 2u)) {
        for (unsigned r = 0; r < N_RATES; r++) {
            uint32_t per_seg = (uint32_t)rates[r] * SEG_MS / 1000u;
            if (per_seg > seg_ticks)
                per_seg = seg_ticks;
            uint32_t done = 0;
            while (done < N_STEPS) {
                cs_segment_t s = {seg_ticks, {0, 0, 0, 0}};
                uint32_t n = N_STEPS - done < per_seg ? N_STEPS - done : per_seg;
                for (uint8_t i = 0; i < axes; i++)
                    s.steps[i] = (int32_t)n;
                if (n < per_seg) /* the last piece at the same rate */
                    s.ticks = seg_ticks * n / per_seg;
                push(&s);
                done += n;
            }
            wait_idle_then(hz * GAP_MS / 1000u);
        }
    }
    /* done: sleep with interrupts off, which ends the simulation */
    cli();
    SMCR = (uint8_t)(1u << SE);
    for (;;)
        sleep_cpu();
}
