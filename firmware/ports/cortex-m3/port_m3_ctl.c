/* port_m3_ctl: port.h's machine-control half on the LM3S6965 (pin map in port_m3.h): the limit
 * switches, probe and e-stop as CS_PROTO_IN_* bits with a both-edge GPIO interrupt at the step
 * timer's priority (so the application's hook, which may halt the executor, never preempts the
 * step interrupt), simulated switches for qemu, and the spindle / laser output on the PWM
 * module's generator 0 in count-down mode (output high from the load to compare A: the high time
 * is LOAD - CMPA, data sheet 20.3.3), with enable and direction pins. */
#include <stddef.h>

#include "cs_proto.h"
#include "lm3s6965.h"
#include "port_m3.h"

#define LIMIT_PINS 0xFFu /* PB0..PB7: min x y z a, max x y z a */
#define PROBE_PIN  0x01u /* PE0 */
#define ESTOP_PIN  0x02u /* PE1 */
#define SP_EN_PIN  0x10u /* PC4 */
#define SP_DIR_PIN 0x20u /* PC5 */
#define SP_PWM_PIN 0x01u /* PF0: PWM0 */
#define PWM_LOAD   (PORT_M3_SYSCLK_HZ / PORT_M3_SPINDLE_HZ - 1u)
#define SIM_MAX    10u /* one simulated input per bit: 8 switches, the probe, the e-stop */
/* Wiring: 0 (default) switches to 3.3 V with the internal pull-downs, a pin reads high when
 * active (an unconnected pin, and every pin of qemu's board, reads inactive); 1: switches to
 * ground with the internal pull-ups (Grbl's usual wiring), low when active. */
#ifndef PORT_M3_INPUTS_ACTIVE_LOW
#define PORT_M3_INPUTS_ACTIVE_LOW 0
#endif
#if PORT_M3_INPUTS_ACTIVE_LOW
#define GPIO_PULL GPIO_PUR
#define ACTIVE(v) (~(v))
#else
#define GPIO_PULL GPIO_PDR
#define ACTIVE(v) (v)
#endif

CS_STATIC_ASSERT(PWM_LOAD <= 0xFFFFu && PWM_LOAD >= 1000u, spindle_pwm_load_fits_16_bits);

static void (*in_fn)(void *);
static void *in_ctx;
static struct {
    uint16_t bit;
    uint8_t axis;
    bool above;
    int32_t at;
} sim[SIM_MAX];
static uint8_t nsim;
static volatile uint32_t sp_settings;
static volatile uint16_t sp_duty;
static volatile uint8_t sp_mode;

void port_m3_ctl_init(void)
{
    SYSCTL_RCGC0 |= SYSCTL_RCGC0_PWM;
    SYSCTL_RCGC2 |= SYSCTL_RCGC2_GPIOB | SYSCTL_RCGC2_GPIOC | SYSCTL_RCGC2_GPIOE |
                    SYSCTL_RCGC2_GPIOF;
    for (volatile uint32_t k = 0; k < 16u; k++) /* a few cycles before the clocks are up */
        ;
    /* inputs: pulled to their inactive level; interrupts on both edges, cleared, unmasked */
    GPIO_DIR(GPIO_PORTB) &= ~LIMIT_PINS;
    GPIO_PULL(GPIO_PORTB) |= LIMIT_PINS;
    GPIO_DEN(GPIO_PORTB) |= LIMIT_PINS;
    GPIO_DIR(GPIO_PORTE) &= ~(PROBE_PIN | ESTOP_PIN);
    GPIO_PULL(GPIO_PORTE) |= PROBE_PIN | ESTOP_PIN;
    GPIO_DEN(GPIO_PORTE) |= PROBE_PIN | ESTOP_PIN;
    GPIO_IS(GPIO_PORTB) &= ~LIMIT_PINS;
    GPIO_IBE(GPIO_PORTB) |= LIMIT_PINS;
    GPIO_ICR(GPIO_PORTB) = LIMIT_PINS;
    GPIO_IM(GPIO_PORTB) |= LIMIT_PINS;
    GPIO_IS(GPIO_PORTE) &= ~(PROBE_PIN | ESTOP_PIN);
    GPIO_IBE(GPIO_PORTE) |= PROBE_PIN | ESTOP_PIN;
    GPIO_ICR(GPIO_PORTE) = PROBE_PIN | ESTOP_PIN;
    GPIO_IM(GPIO_PORTE) |= PROBE_PIN | ESTOP_PIN;
    NVIC_IPR(GPIOB_IRQ) = 0x80u; /* the step timer's priority: neither preempts the other */
    NVIC_IPR(GPIOE_IRQ) = 0x80u;
    NVIC_ISER(0) = (1u << GPIOB_IRQ) | (1u << GPIOE_IRQ);
    /* spindle: enable and direction low, PWM0 on PF0 off */
    GPIO_DATA(GPIO_PORTC, SP_EN_PIN | SP_DIR_PIN) = 0;
    GPIO_DIR(GPIO_PORTC) |= SP_EN_PIN | SP_DIR_PIN;
    GPIO_DEN(GPIO_PORTC) |= SP_EN_PIN | SP_DIR_PIN;
    GPIO_AFSEL(GPIO_PORTF) |= SP_PWM_PIN;
    GPIO_DEN(GPIO_PORTF) |= SP_PWM_PIN;
    PWM0_CTL = 0;
    PWM0_LOAD = PWM_LOAD;
    PWM0_CMPA = PWM_LOAD;
    PWM0_GENA = PWM_GENA_LOAD_HIGH | PWM_GENA_CMPAD_LOW;
    PWM0_CTL = PWM_GEN_ENABLE;
    PWM_ENABLE = 0;
}

static uint16_t sim_read(void)
{
    if (nsim == 0)
        return 0;
    uint32_t pulses[4];
    int32_t pos[4];
    port_m3_pins(pulses, pos);
    uint16_t b = 0;
    for (unsigned i = 0; i < nsim; i++) {
        int32_t p = pos[sim[i].axis];
        if (sim[i].above ? p >= sim[i].at : p <= sim[i].at)
            b = (uint16_t)(b | sim[i].bit);
    }
    return b;
}

uint16_t port_inputs_read(void)
{
    uint32_t lim = ACTIVE(GPIO_DATA(GPIO_PORTB, LIMIT_PINS));
    uint32_t pe = ACTIVE(GPIO_DATA(GPIO_PORTE, PROBE_PIN | ESTOP_PIN));
    uint16_t b = (uint16_t)(lim & LIMIT_PINS);
    if (pe & PROBE_PIN)
        b |= CS_PROTO_IN_PROBE;
    if (pe & ESTOP_PIN)
        b |= CS_PROTO_IN_ESTOP;
    return (uint16_t)(b | sim_read());
}

/* The edge hook (port.h): the application reads the pins and keeps what changed (ISR context). */
static void edge(void)
{
    if (in_fn != NULL)
        in_fn(in_ctx);
}

void GPIOB_Handler(void);
void GPIOB_Handler(void)
{
    GPIO_ICR(GPIO_PORTB) = LIMIT_PINS;
    edge();
}

void GPIOE_Handler(void);
void GPIOE_Handler(void)
{
    GPIO_ICR(GPIO_PORTE) = PROBE_PIN | ESTOP_PIN;
    edge();
}

void port_m3_ctl_stepped(void)
{
    if (nsim != 0)
        edge(); /* the simulated switches move with the machine: sampled after each step */
}

void port_inputs_attach(void (*fn)(void *ctx), void *ctx)
{
    uint32_t s = port_irq_save();
    in_fn = fn;
    in_ctx = ctx;
    port_irq_restore(s);
}

void port_m3_sim_switch(uint16_t bit, uint8_t axis, int32_t at, bool above)
{
    if (nsim >= SIM_MAX || axis >= 4u)
        return;
    uint32_t s = port_irq_save();
    sim[nsim].bit = bit;
    sim[nsim].axis = axis;
    sim[nsim].at = at;
    sim[nsim].above = above;
    nsim++;
    port_irq_restore(s);
}

void port_spindle_set(uint16_t duty, uint8_t mode)
{
    uint32_t d = duty > 1000u ? 1000u : duty;
    bool on = mode != CS_PROTO_SPINDLE_OFF && d != 0;
    if (on)
        PWM0_CMPA = PWM_LOAD - (PWM_LOAD * d) / 1000u; /* high time LOAD - CMPA */
    PWM_ENABLE = on ? 1u : 0u;
    GPIO_DATA(GPIO_PORTC, SP_EN_PIN | SP_DIR_PIN) =
        (mode != CS_PROTO_SPINDLE_OFF ? SP_EN_PIN : 0u) |
        (mode == CS_PROTO_SPINDLE_CCW ? SP_DIR_PIN : 0u);
    sp_duty = (uint16_t)d;
    sp_mode = mode;
    sp_settings++;
}

void port_m3_spindle(uint32_t *settings, uint16_t *duty, uint8_t *mode)
{
    uint32_t s = port_irq_save();
    *settings = sp_settings;
    *duty = sp_duty;
    *mode = sp_mode;
    port_irq_restore(s);
}
