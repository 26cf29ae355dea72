/* port_m3: port.h for the TI Stellaris LM3S6965 (qemu -M lm3s6965evb). Clocks: PLL to 50 MHz.
 * Time: SysTick runs at the core clock with a period of exactly 65536 ticks of 1 us, its wrap
 * interrupt counts the upper 16 bits, so port_ticks_now wraps at 2^32 like the executor expects.
 * The step timer: GPTM Timer0A in 32-bit one-shot mode, re-armed in its interrupt for an absolute
 * deadline (previous deadline + ticks, in core cycles) so call periods add up without drift
 * (interrupt latency is subtracted, not accumulated). UART0: interrupt-driven, receive and
 * transmit rings. See port_m3.h for the pin map. */
#include "port_m3.h"

#include <stddef.h>

#include "lm3s6965.h"

#define CYC_PER_TICK (PORT_M3_SYSCLK_HZ / PORT_M3_TICK_HZ)
/* SysTick wraps every 2^SYST_SHIFT ticks (the most that fits its 24 bits), so the tick counter
 * is (wraps << SYST_SHIFT) + elapsed ticks and wraps at 2^32 */
#define SYST_SHIFT  (CYC_PER_TICK <= 256u ? 16u : CYC_PER_TICK <= 512u ? 15u : 14u)
#define SYST_PERIOD (CYC_PER_TICK << SYST_SHIFT)
#define PULSE_CYC   (PORT_M3_PULSE_US * CYC_PER_TICK)
#define MIN_WAIT    20u /* cycles: a deadline already passed fires this soon */
#define RX_MASK     (PORT_M3_RX_RING - 1u)
#define TX_MASK     (PORT_M3_TX_RING - 1u)
#define STEP_PINS   0x0Fu /* PD0..PD3 */
#define DIR_PINS    0xF0u /* PD4..PD7 */
#define ENABLE_PIN  0x01u /* PG0, low = drivers enabled */

CS_STATIC_ASSERT(SYST_PERIOD <= 0x1000000u, systick_period_fits_24_bits);
CS_STATIC_ASSERT(PORT_M3_SYSCLK_HZ % PORT_M3_TICK_HZ == 0, tick_divides_the_clock);
CS_STATIC_ASSERT((PORT_M3_RX_RING & RX_MASK) == 0 && (PORT_M3_TX_RING & TX_MASK) == 0,
                 uart_rings_power_of_two);

static volatile uint32_t systick_wraps;
static cs_stepper_t *step_st;
static volatile bool timer_on; /* a chain of step interrupts is running */
static bool counting;          /* Timer0A enabled and counting down */
static uint32_t deadline;      /* core cycles of the step interrupt in flight */
static volatile uint32_t pulses[4];
static volatile int32_t pin_pos[4];
static uint8_t dir_lines; /* the DIR pins as last written (step interrupt only) */
static volatile cs_err_t fault_code;
static volatile uint32_t step_irqs; /* step interrupts that ran the executor */
static volatile uint32_t irq_count; /* interrupts taken: port_m3_spin waits for a change */
static cs_exlog_edges_t edge_log;   /* STEP edges on the executor's clock (cs_exlog) */

static volatile uint8_t rxb[PORT_M3_RX_RING];
static volatile uint16_t rx_head, rx_tail; /* head: written by the ISR, tail: by the main loop */
static volatile uint8_t txb[PORT_M3_TX_RING];
static volatile uint16_t tx_head, tx_tail; /* head: main loop, tail: ISR (or main, masked) */
static volatile uint32_t rx_overruns;

uint32_t port_irq_save(void)
{
    uint32_t primask;
    __asm volatile("mrs %0, primask\n\tcpsid i" : "=r"(primask)::"memory");
    return primask;
}

void port_irq_restore(uint32_t state)
{
    __asm volatile("msr primask, %0" ::"r"(state) : "memory");
}

/* Wraps and the SysTick value read together; a wrap whose interrupt is still pending (masked,
 * or lower priority than the caller) is counted and the value read again after it. */
static void systick_read(uint32_t *wraps, uint32_t *elapsed)
{
    uint32_t s = port_irq_save();
    uint32_t w = systick_wraps;
    uint32_t v = SYST_CVR;
    if (SCB_ICSR & SCB_ICSR_PENDSTSET) {
        w++;
        v = SYST_CVR;
    }
    port_irq_restore(s);
    *wraps = w;
    *elapsed = SYST_PERIOD - 1u - v;
}

uint32_t port_m3_cycles(void)
{
    uint32_t w, e;
    systick_read(&w, &e);
    return w * SYST_PERIOD + e; /* modulo 2^32 */
}

uint32_t port_ticks_now(void)
{
    uint32_t w, e;
    systick_read(&w, &e);
    return (w << SYST_SHIFT) + e / CYC_PER_TICK;
}

uint32_t port_tick_hz(void)
{
    return PORT_M3_TICK_HZ;
}

void SysTick_Handler(void);
void SysTick_Handler(void)
{
    irq_count++;
    systick_wraps++;
}

/* PLL from the 8 MHz crystal: 400 MHz VCO / 2 / SYSDIV 4 = 50 MHz (data sheet 6.3, "PLL
 * frequency configuration"): bypass, set the crystal, power the PLL, set the divider, wait for
 * lock (bounded), leave bypass. */
static void clock_init(void)
{
    uint32_t rcc = SYSCTL_RCC;
    rcc = (rcc | SYSCTL_RCC_BYPASS) & ~SYSCTL_RCC_USESYSDIV;
    SYSCTL_RCC = rcc;
    rcc = (rcc & ~(SYSCTL_RCC_XTAL_M | SYSCTL_RCC_OSCSRC_M | SYSCTL_RCC_PWRDN)) |
          SYSCTL_RCC_XTAL_8MHZ;
    SYSCTL_RCC = rcc;
    rcc = (rcc & ~SYSCTL_RCC_SYSDIV_M) | (3u << SYSCTL_RCC_SYSDIV_S) | SYSCTL_RCC_USESYSDIV;
    SYSCTL_RCC = rcc;
    for (uint32_t k = 0; k < 100000u && !(SYSCTL_RIS & SYSCTL_RIS_PLLLRIS); k++)
        ;
    SYSCTL_RCC = rcc & ~SYSCTL_RCC_BYPASS;
}

void port_init(void)
{
    clock_init();
    cs_exlog_edges_init(&edge_log);
    SYSCTL_RCGC1 |= SYSCTL_RCGC1_TIMER0 | SYSCTL_RCGC1_UART0;
    SYSCTL_RCGC2 |= SYSCTL_RCGC2_GPIOA | SYSCTL_RCGC2_GPIOD | SYSCTL_RCGC2_GPIOG;
    for (volatile uint32_t k = 0; k < 16u; k++) /* a few cycles before the clocks are up */
        ;
    /* STEP and DIR outputs, low; drivers enabled (PG0 low) */
    GPIO_DATA(GPIO_PORTD, 0xFFu) = 0;
    GPIO_DIR(GPIO_PORTD) |= STEP_PINS | DIR_PINS;
    GPIO_DEN(GPIO_PORTD) |= STEP_PINS | DIR_PINS;
    GPIO_DATA(GPIO_PORTG, ENABLE_PIN) = 0;
    GPIO_DIR(GPIO_PORTG) |= ENABLE_PIN;
    GPIO_DEN(GPIO_PORTG) |= ENABLE_PIN;
    /* free-running time: SysTick on the core clock, highest priority so wraps are counted */
    SYST_RVR = SYST_PERIOD - 1u;
    SYST_CVR = 0;
    SCB_SHPR3 = (SCB_SHPR3 & 0x00FFFFFFu); /* SysTick priority 0 */
    SYST_CSR = SYST_CSR_CLKSOURCE | SYST_CSR_TICKINT | SYST_CSR_ENABLE;
    /* step timer: 32-bit one-shot, interrupt on time-out, stopped */
    TIMER_CTL = 0;
    TIMER_CFG = 0;
    TIMER_TAMR = TIMER_TAMR_ONESHOT;
    TIMER_ICR = TIMER_INT_TATO;
    TIMER_IMR = TIMER_INT_TATO;
    /* UART0 on PA0/PA1: 115200 8N1, FIFOs, receive and receive-timeout interrupts */
    GPIO_AFSEL(GPIO_PORTA) |= 0x03u;
    GPIO_DEN(GPIO_PORTA) |= 0x03u;
    UART_CTL = 0;
    /* divisor = 50 MHz / (16 * 115200) = 27.127: IBRD 27, FBRD round(0.127 * 64) = 8 */
    UART_IBRD = PORT_M3_SYSCLK_HZ / (16u * PORT_M3_BAUD);
    UART_FBRD = ((PORT_M3_SYSCLK_HZ * 8u / PORT_M3_BAUD) + 1u) / 2u % 64u;
    UART_LCRH = UART_LCRH_WLEN8 | UART_LCRH_FEN;
    UART_IFLS = 0; /* interrupt at 1/8 full (receive) and 1/8 empty (transmit) */
    UART_ICR = 0x7FFu;
    UART_IM = UART_INT_RX | UART_INT_RT;
    UART_CTL = UART_CTL_UARTEN | UART_CTL_TXE | UART_CTL_RXE;
    NVIC_IPR(UART0_IRQ) = 0x40u;   /* the UART may interrupt the step interrupt: its FIFO */
    NVIC_IPR(TIMER0A_IRQ) = 0x80u; /* holds 16 bytes, the step interrupt runs for microseconds */
    NVIC_ISER(0) = (1u << UART0_IRQ) | (1u << TIMER0A_IRQ);
    port_m3_ctl_init(); /* switch, probe and e-stop pins, the spindle PWM (port_m3_ctl.c) */
    __asm volatile("cpsie i" ::: "memory");
}

/* --- step timer ------------------------------------------------------------------------------ */

void port_stepper_attach(cs_stepper_t *st)
{
    step_st = st;
}

void port_timer_arm(uint32_t ticks)
{
    uint32_t s = port_irq_save();
    uint32_t now = port_m3_cycles();
    if (!timer_on)
        deadline = now;                                   /* stopped: count from now */
    deadline += (ticks != 0 ? ticks : 1u) * CYC_PER_TICK; /* ticks <= 2^24: < 2^31 cycles */
    int32_t wait = (int32_t)(deadline - now);
    if (counting) /* re-armed while counting (not by the step interrupt): stop it first */
        TIMER_CTL = 0;
    TIMER_TAILR = wait < (int32_t)MIN_WAIT ? MIN_WAIT : (uint32_t)wait;
    TIMER_CTL = TIMER_CTL_TAEN;
    counting = true;
    timer_on = true;
    port_irq_restore(s);
}

void port_timer_stop(void)
{
    uint32_t s = port_irq_save();
    TIMER_CTL = 0;
    TIMER_ICR = TIMER_INT_TATO;
    counting = false;
    timer_on = false;
    port_irq_restore(s);
}

/* Busy-waits about n core cycles: 3 cycles a turn on a Cortex-M3 (subs + taken branch), no
 * register access (an emulator runs it at full speed; a SysTick-timed wait costs it a slow path
 * per read). */
static void delay_cycles(uint32_t n)
{
    uint32_t k = n / 3u + 1u;
    __asm volatile("1: subs %0, %0, #1\n\tbne 1b" : "+r"(k)::"cc");
}

void port_step_pulse(uint8_t mask)
{
    mask &= STEP_PINS;
    if (mask == 0)
        return;
    GPIO_DATA(GPIO_PORTD, STEP_PINS) = mask;
    for (unsigned i = 0; i < 4u; i++) {
        if (mask & (1u << i)) {
            pulses[i]++;
            pin_pos[i] += (dir_lines & (1u << i)) ? 1 : -1; /* DIR as the pins hold it */
        }
    }
    delay_cycles(PULSE_CYC); /* the pulse width, then low */
    GPIO_DATA(GPIO_PORTD, STEP_PINS) = 0;
}

void port_dir_set(uint8_t mask)
{
    mask &= 0x0Fu;
    if (mask == dir_lines)
        return;
    dir_lines = mask;
    GPIO_DATA(GPIO_PORTD, DIR_PINS) = (uint32_t)mask << 4;
}

/* The step interrupt: pulses, then DIR, then the next deadline (port_template.c). */
void Timer0A_Handler(void);
void Timer0A_Handler(void)
{
    TIMER_ICR = TIMER_INT_TATO;
    counting = false; /* one-shot: the hardware cleared TAEN at the time-out */
    irq_count++;
    if (!timer_on || step_st == NULL)
        return;
    step_irqs++;
    cs_stepper_out_t o;
    cs_stepper_tick(step_st, &o);
    cs_exlog_tick(&edge_log, &o);
    port_step_pulse(o.step_mask);
    port_dir_set(o.dir_mask);
    if (o.next_ticks != 0)
        port_timer_arm(o.next_ticks);
    else
        port_timer_stop();
    if (o.step_mask != 0)
        port_m3_ctl_stepped(); /* simulated switches move with the pins (port_m3_ctl.c) */
}

void port_m3_edges(cs_exlog_edges_t *l)
{
    uint32_t s = port_irq_save();
    *l = edge_log;
    port_irq_restore(s);
}

void port_m3_pins(uint32_t p[4], int32_t pos[4])
{
    uint32_t s = port_irq_save();
    for (unsigned i = 0; i < 4u; i++) {
        p[i] = pulses[i];
        pos[i] = pin_pos[i];
    }
    port_irq_restore(s);
}

/* --- UART ------------------------------------------------------------------------------------ */

/* Moves queued bytes into the transmit FIFO; the transmit interrupt stays on while bytes wait.
 * Interrupts masked (called from the UART interrupt or with them masked). */
static void tx_pump(void)
{
    while (tx_tail != tx_head && !(UART_FR & UART_FR_TXFF)) {
        UART_DR = txb[tx_tail & TX_MASK];
        tx_tail++;
    }
    if (tx_tail == tx_head)
        UART_IM &= ~UART_INT_TX;
    else
        UART_IM |= UART_INT_TX;
}

void UART0_Handler(void);
void UART0_Handler(void)
{
    UART_ICR = UART_MIS;
    irq_count++;
    while (!(UART_FR & UART_FR_RXFE)) {
        uint8_t b = (uint8_t)UART_DR;
        if ((uint16_t)(rx_head - rx_tail) < PORT_M3_RX_RING) {
            rxb[rx_head & RX_MASK] = b;
            rx_head++;
        } else {
            rx_overruns++;
        }
    }
    tx_pump();
}

size_t port_uart_read(uint8_t *buf, size_t max)
{
    size_t n = 0;
    uint16_t t = rx_tail;
    while (n < max && t != rx_head) {
        buf[n++] = rxb[t & RX_MASK];
        t++;
    }
    rx_tail = t;
    return n;
}

size_t port_uart_write(const uint8_t *buf, size_t len)
{
    size_t n = 0;
    uint16_t h = tx_head;
    while (n < len && (uint16_t)(h - tx_tail) < PORT_M3_TX_RING) {
        txb[h & TX_MASK] = buf[n++];
        h++;
    }
    tx_head = h;
    uint32_t s = port_irq_save();
    tx_pump();
    port_irq_restore(s);
    return n;
}

uint32_t port_m3_step_irqs(void)
{
    return step_irqs;
}

uint32_t port_m3_rx_overruns(void)
{
    return rx_overruns;
}

void port_m3_sleep(void)
{
    /* masked, so an interrupt between the check and WFI still wakes it (WFI wakes on a pending
     * interrupt even with PRIMASK set; it is taken after cpsie) */
    __asm volatile("cpsid i" ::: "memory");
    if (rx_head == rx_tail && tx_head == tx_tail) {
        __asm volatile("wfi" ::: "memory");
    }
    __asm volatile("cpsie i" ::: "memory");
}

void port_m3_spin(void)
{
    /* RAM only: an emulator runs this loop at full speed, where every register read (a SysTick
     * or UART access) costs it a slow path */
    uint32_t seen = irq_count;
    for (uint32_t k = 0; k < 100000u && irq_count == seen; k++)
        ;
}

/* --- faults ---------------------------------------------------------------------------------- */

void port_fault(cs_err_t code)
{
    port_timer_stop();
    GPIO_DATA(GPIO_PORTD, STEP_PINS) = 0;
    GPIO_DATA(GPIO_PORTG, ENABLE_PIN) = ENABLE_PIN; /* drivers off */
    fault_code = code;
    port_m3_on_fault(code);
}

cs_err_t port_m3_fault_code(void)
{
    return fault_code;
}
