/* port_m3_servo: port_pen_set for the LM3S6965: a 50 Hz RC-servo pulse train on PG1.
 *
 * Why two timers and not a PWM output: the LM3S6965's GPTM PWM mode is a 16-bit down-counter
 * with no prescaler (data sheet 9.3.2.5), at most 1.31 ms at 50 MHz, short of a servo's 20 ms
 * period; its PWM module (data sheet ch. 16) would do, but qemu's lm3s6965evb does not model it
 * (an unimplemented region: nothing could be checked). So Timer1A, in 32-bit periodic mode,
 * times the period exactly (the hardware reloads: no drift), and its interrupt raises PG1 and
 * starts Timer2A one-shot for the width; Timer2A's interrupt drops PG1. Both interrupts run at
 * a priority above the step and UART interrupts (below SysTick), a few instructions each: the
 * width is the programmed one plus the difference of the two entry latencies (the same code
 * path: well under 1 us, a servo's dead band is 2-5 us). Each edge is stamped with
 * port_m3_cycles (SysTick, a clock apart from the GPTMs) for port_m3_servo, which also reads
 * the two timers' load registers back: the report, and the test under qemu, compare both with
 * what was asked. (qemu delivers timer interrupts late by a varying amount while the image
 * sleeps: single intervals there scatter by ~10 % and widths read long; the mean period holds.
 * A chip's latency is the 12-cycle exception entry plus any masked section.) */
#include "port_m3.h"

#include "lm3s6965.h"

#define SERVO_PERIOD_CYC (PORT_M3_SYSCLK_HZ / 50u)      /* 20 ms */
#define CYC_PER_US       (PORT_M3_SYSCLK_HZ / 1000000u) /* 50 */
#define SERVO_PIN        0x02u                          /* PG1 */
#define SERVO_PRIORITY   0x20u /* above UART0 (0x40) and the step timer (0x80) */

CS_STATIC_ASSERT(PORT_M3_SYSCLK_HZ % 1000000u == 0, servo_whole_cycles_per_us);

static volatile uint32_t width_cyc; /* the pulse width, cycles; 0 until the first setting */
static volatile uint32_t rise_at;   /* port_m3_cycles at the last rise */
static volatile bool risen;         /* a rise has been stamped */
static uint32_t pulse_cyc;          /* the width of the pulse under way */
static port_m3_servo_t meas;        /* written by the two interrupts only */

/* Clocks both timers, PG1 low as an output, Timer1A periodic at 20 ms (running), Timer2A
 * one-shot (stopped), both interrupts on. Interrupts masked by the caller. */
static void servo_start(void)
{
    SYSCTL_RCGC1 |= SYSCTL_RCGC1_TIMER1 | SYSCTL_RCGC1_TIMER2;
    for (volatile uint32_t k = 0; k < 16u; k++) /* a few cycles before the clocks are up */
        ;
    GPIO_DATA(GPIO_PORTG, SERVO_PIN) = 0;
    GPIO_DIR(GPIO_PORTG) |= SERVO_PIN;
    GPIO_DEN(GPIO_PORTG) |= SERVO_PIN;
    GPTM_CTL(TIMER2) = 0;
    GPTM_CFG(TIMER2) = 0;
    GPTM_TAMR(TIMER2) = TIMER_TAMR_ONESHOT;
    GPTM_ICR(TIMER2) = TIMER_INT_TATO;
    GPTM_IMR(TIMER2) = TIMER_INT_TATO;
    GPTM_CTL(TIMER1) = 0;
    GPTM_CFG(TIMER1) = 0;
    GPTM_TAMR(TIMER1) = TIMER_TAMR_PERIODIC;
    GPTM_TAILR(TIMER1) = SERVO_PERIOD_CYC - 1u; /* counts TAILR..0: TAILR + 1 cycles */
    GPTM_ICR(TIMER1) = TIMER_INT_TATO;
    GPTM_IMR(TIMER1) = TIMER_INT_TATO;
    NVIC_IPR(TIMER1A_IRQ) = SERVO_PRIORITY;
    NVIC_IPR(TIMER2A_IRQ) = SERVO_PRIORITY;
    NVIC_ISER(0) = (1u << TIMER1A_IRQ) | (1u << TIMER2A_IRQ);
    GPTM_CTL(TIMER1) = TIMER_CTL_TAEN;
}

void port_pen_set(uint16_t pulse_us)
{
    uint32_t s = port_irq_save();
    bool first = width_cyc == 0;
    width_cyc = (uint32_t)pulse_us * CYC_PER_US; /* taken at the next rise */
    if (first && pulse_us != 0)
        servo_start();
    port_irq_restore(s);
}

/* The period: raise PG1, time the width. */
void Timer1A_Handler(void);
void Timer1A_Handler(void)
{
    GPTM_ICR(TIMER1) = TIMER_INT_TATO;
    GPIO_DATA(GPIO_PORTG, SERVO_PIN) = SERVO_PIN;
    GPTM_TAILR(TIMER2) = width_cyc;
    GPTM_CTL(TIMER2) = TIMER_CTL_TAEN;
    uint32_t now = port_m3_cycles();
    if (pulse_cyc != width_cyc) { /* a new width: its pulses are averaged afresh */
        pulse_cyc = width_cyc;
        meas.high_n = 0;
        meas.high_sum = 0;
    }
    if (risen) {
        uint32_t p = now - rise_at;
        if (meas.periods == 0 || p < meas.min_cyc)
            meas.min_cyc = p;
        if (p > meas.max_cyc)
            meas.max_cyc = p;
        meas.periods++;
        meas.span_cyc += p; /* each difference < 2^32 cycles; their sum past the counter's wrap */
    }
    rise_at = now;
    risen = true;
}

/* The width has passed: drop PG1. */
void Timer2A_Handler(void);
void Timer2A_Handler(void)
{
    GPTM_ICR(TIMER2) = TIMER_INT_TATO;
    GPIO_DATA(GPIO_PORTG, SERVO_PIN) = 0;
    meas.high_sum += port_m3_cycles() - rise_at;
    meas.high_n++;
}

void port_m3_servo(port_m3_servo_t *out)
{
    uint32_t s = port_irq_save();
    *out = meas;
    out->period_reg = risen ? GPTM_TAILR(TIMER1) + 1u : 0;
    out->width_reg = risen ? GPTM_TAILR(TIMER2) : 0;
    port_irq_restore(s);
}
