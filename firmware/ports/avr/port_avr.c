/* port_avr: ATmega328p at 16 MHz. See port_avr.h for the clocks, pins and sizes.
 *
 * The step interrupt (Timer1 compare A) is pipelined as Grbl's is: each interrupt first emits
 * the STEP pulse the previous executor call asked for (raise, hold PORT_AVR_PULSE_US on Timer1,
 * drop), writes that call's DIR levels, and only then runs the executor for the next call. So
 * the rising edge comes a constant 54 cycles after the vector is taken whatever the executor
 * costs (a call that loads a segment takes ~1.7 times an ordinary one), the pulse is
 * the configured width and not the executor's duration, and DIR changes a whole DDA period
 * before the first step that needs it. Every step is emitted one DDA period after the executor
 * computed it; counts, order and directions are unchanged.
 *
 * Cost (docs/firmware-avr.md, "Figures"): ~390 cycles a call with one axis moving, ~490 with
 * three. The executor is inlined here at link time (-flto, mk/fw-avr.mk); its answer lives in a
 * static (no stack frame); a period of up to FAST_TICKS is converted to counts and armed inline,
 * the rare late deadline handled out of line; long-period chunking is a one-byte flag. */
#include "port_avr.h"

#include <avr/interrupt.h>
#include <avr/io.h>

#include "cs_proto.h"

CS_STATIC_ASSERT((PORT_AVR_RX_RING & (PORT_AVR_RX_RING - 1)) == 0 && PORT_AVR_RX_RING <= 256,
                 avr_rx_ring_pow2);
CS_STATIC_ASSERT((PORT_AVR_TX_RING & (PORT_AVR_TX_RING - 1)) == 0 && PORT_AVR_TX_RING <= 256,
                 avr_tx_ring_pow2);
CS_STATIC_ASSERT(PORT_AVR_TICK_SHIFT <= 8, avr_tick_shift);
CS_STATIC_ASSERT(PORT_AVR_PULSE_COUNTS >= 1 && PORT_AVR_PULSE_COUNTS < 1000, avr_pulse);

#define STEP_LINES ((uint8_t)(0x07u << PORT_AVR_STEP_BIT0))
#define DIR_LINES  ((uint8_t)(0x07u << PORT_AVR_DIR_BIT0))
#define EN_LINE    ((uint8_t)(1u << PB0))
#define LED_LINE   ((uint8_t)(1u << PB5)) /* the Uno's LED: lit by port_fault */

/* A period longer than CHUNK_LIMIT counts is waited in CHUNK pieces (no executor call in
 * between); both stay below 2^15 so "deadline passed" is a signed 16-bit difference. */
#define CHUNK       0x4000u
#define CHUNK_LIMIT 0x7000u
/* Re-arm distance when a deadline was already past: more counts (8 cycles each) than the few
 * cycles between reading TCNT1 and writing OCR1A. */
#define LATE_MARGIN 3u
/* Lag (counts) beyond which a late timeline restarts from now: 4 ms, far inside the 16-bit
 * half-range the lag is measured in (one interrupt adds at most a few hundred counts). */
#define LAG_MAX 0x2000u

/* Periods up to FAST_TICKS ticks (never chunked: FAST_TICKS << TICK_SHIFT <= CHUNK_LIMIT, and
 * < 256 so the conversion to counts is a byte move and a short shift) take the interrupt's
 * short path. */
#define FAST_TICKS                                                                                 \
    ((CHUNK_LIMIT >> PORT_AVR_TICK_SHIFT) < 255u ? (CHUNK_LIMIT >> PORT_AVR_TICK_SHIFT) : 255u)

#define UBRR_VALUE ((uint16_t)((F_CPU + 4u * PORT_AVR_BAUD) / (8u * PORT_AVR_BAUD) - 1u))

static cs_stepper_t *step_st;
static volatile uint8_t armed;   /* the compare interrupt is enabled */
static uint16_t deadline;        /* OCR1A of the next interrupt (ideal, drift-free) */
static uint32_t remain;          /* counts still to wait after the current chunk */
static uint8_t waiting;          /* remain != 0: the step interrupt's first test, one byte */
static cs_stepper_out_t isr_out; /* the executor's answer (static: no stack frame in the ISR) */
static uint16_t last_ticks;      /* the last period armed, for the final step's flush */
static uint8_t pend_step;        /* PORTD STEP bits of the last executor call */
static uint8_t pend_dir;         /* PORTD DIR bits of the last executor call */
static volatile uint32_t ovf;    /* Timer1 overflows: the counter's high bits */
static port_avr_stats_t stats;   /* written and read with interrupts masked */
static volatile uint8_t rx_buf[PORT_AVR_RX_RING];
static volatile uint8_t rx_head, rx_tail; /* head: RX ISR only; tail: main loop only */
static volatile uint8_t tx_buf[PORT_AVR_TX_RING];
static volatile uint8_t tx_head, tx_tail; /* head: main loop only; tail: UDRE ISR only */

static inline void end_pulse(uint16_t t0);

/* Axis mask (bit i = axis i) -> PORTD bits at bit0. */
static inline uint8_t lines(uint8_t mask, uint8_t bit0)
{
    return (uint8_t)((uint8_t)(mask & 0x07u) << bit0);
}

static void ctl_pins_init(void);

void port_init(void)
{
    uint8_t s = SREG;
    cli();
    /* pins: STEP and DIR outputs, low; enable low (drivers on); the LED off */
    PORTD = (uint8_t)(PORTD & (uint8_t) ~(STEP_LINES | DIR_LINES));
    DDRD = (uint8_t)(DDRD | STEP_LINES | DIR_LINES);
    PORTB = (uint8_t)(PORTB & (uint8_t) ~(EN_LINE | LED_LINE));
    DDRB = (uint8_t)(DDRB | EN_LINE | LED_LINE);
    ctl_pins_init();
    /* Timer1: normal mode (free-running 0..0xFFFF), clock / 8, overflow interrupt on; the
     * compare A interrupt stays off until port_timer_arm */
    TCCR1A = 0;
    TCCR1B = (uint8_t)(1u << CS11);
    TIMSK1 = (uint8_t)(1u << TOIE1);
    TIFR1 = (uint8_t)((1u << OCF1A) | (1u << TOV1));
    armed = 0;
    remain = 0;
    waiting = 0;
    pend_step = 0;
    pend_dir = 0;
    last_ticks = 1;
    /* USART0: 8N1, double speed, RX interrupt; the UDRE interrupt runs while TX has bytes */
    UBRR0 = UBRR_VALUE;
    UCSR0A = (uint8_t)(1u << U2X0);
    UCSR0C = (uint8_t)((1u << UCSZ01) | (1u << UCSZ00));
    UCSR0B = (uint8_t)((1u << RXEN0) | (1u << TXEN0) | (1u << RXCIE0));
    rx_head = rx_tail = 0;
    tx_head = tx_tail = 0;
    SREG = s;
    sei();
}

uint32_t port_ticks_now(void)
{
    uint8_t s = SREG;
    cli();
    uint16_t t = TCNT1;
    uint32_t o = ovf;
    /* an overflow not yet serviced (we are in an ISR or just masked): count it */
    if ((TIFR1 & (1u << TOV1)) && t < 0x8000u)
        o++;
    SREG = s;
    return (o << (16 - PORT_AVR_TICK_SHIFT)) + (uint32_t)(t >> PORT_AVR_TICK_SHIFT);
}

uint32_t port_tick_hz(void)
{
    return PORT_AVR_TICK_HZ;
}

void port_stepper_attach(cs_stepper_t *st)
{
    step_st = st;
}

/* Writes OCR1A = deadline. When that moment is already past (the interrupt overran its
 * period), fires as soon as possible instead: while the lag is under LAG_MAX counts the ideal
 * deadline is kept, so the following periods catch up; beyond it the timeline restarts from now
 * (an executor asked for more than it can do runs slower, never wrapping a 16-bit compare).
 * Interrupts masked. */
static __attribute__((noinline)) void set_compare_late(void);
static void set_compare(void)
{
    OCR1A = deadline;
    if ((uint16_t)(TCNT1 - deadline) < 0x8000u)
        set_compare_late();
}

/* set_compare's rare case: the deadline already passed (or is now). */
static __attribute__((noinline)) void set_compare_late(void)
{
    uint16_t lag = (uint16_t)(TCNT1 - deadline);
    if (lag < 0x8000u) {
        TIFR1 = (uint8_t)(1u << OCF1A); /* a match at the old value must not fire twice */
        uint16_t soon = (uint16_t)(TCNT1 + LATE_MARGIN);
        OCR1A = soon;
        if (lag > LAG_MAX)
            deadline = soon;
        stats.late++;
    }
}

/* Next interrupt `ticks` after the current deadline. Interrupts masked. */
static void schedule(uint32_t ticks)
{
    uint32_t counts = ticks << PORT_AVR_TICK_SHIFT;
    if (counts > CHUNK_LIMIT) {
        remain = counts - CHUNK;
        waiting = 1;
        counts = CHUNK;
    }
    deadline = (uint16_t)(deadline + (uint16_t)counts);
    set_compare();
}

static void stop_timer(void)
{
    TIMSK1 = (uint8_t)(TIMSK1 & (uint8_t) ~(1u << OCIE1A));
    armed = 0;
    remain = 0;
    waiting = 0;
}

void port_timer_arm(uint32_t ticks)
{
    uint8_t s = SREG;
    cli();
    /* Already running: the pending interrupt calls the executor, which picks up whatever was
     * queued; re-arming would move a deadline the DDA counts on. After a fault: never. */
    if (!armed && stats.fault == 0) {
        if (ticks == 0)
            ticks = 1;
        remain = 0;
        waiting = 0;
        pend_step = 0;
        deadline = (uint16_t)(TCNT1 + LATE_MARGIN);
        schedule(ticks);
        TIFR1 = (uint8_t)(1u << OCF1A);
        TIMSK1 = (uint8_t)(TIMSK1 | (1u << OCIE1A));
        armed = 1;
    }
    SREG = s;
}

void port_timer_stop(void)
{
    uint8_t s = SREG;
    cli();
    stop_timer();
    /* the step the executor computed last and counted, still pending in the pipeline (see the
     * top of this file): emitted now, so the pins end where the executor's count does (a hard
     * limit or a probe contact halts it from an input interrupt) */
    uint8_t b = pend_step;
    pend_step = 0;
    if (b != 0) {
        PORTD = (uint8_t)(PORTD | b);
        end_pulse(TCNT1);
    }
    SREG = s;
}

uint32_t port_irq_save(void)
{
    uint8_t s = SREG;
    cli();
    return s;
}

void port_irq_restore(uint32_t state)
{
    SREG = (uint8_t)state;
}

/* Drops the STEP lines raised just before TCNT1 read t0, once the pulse width has passed: t0 may
 * have been read on the last cycle of its count, so the width is guaranteed by waiting for
 * PULSE_COUNTS + 1 count changes (at least PULSE_COUNTS * 8 + 1 cycles). */
static inline void end_pulse(uint16_t t0)
{
    while ((uint16_t)(TCNT1 - t0) <= PORT_AVR_PULSE_COUNTS)
        ;
    PORTD = (uint8_t)(PORTD & (uint8_t)~STEP_LINES);
}

void port_step_pulse(uint8_t mask)
{
    uint8_t s = SREG;
    cli();
    uint8_t b = lines(mask, PORT_AVR_STEP_BIT0);
    if (b != 0) {
        PORTD = (uint8_t)(PORTD | b);
        end_pulse(TCNT1);
    }
    SREG = s;
}

/* The pen servo: a 50 Hz RC-servo pulse train on OC1B (PB2, the Uno's D10), made by Timer1's
 * compare unit B while Timer1 keeps counting freely for the step timer (fast PWM with an ICR1
 * top would take Timer1 from the steps). The pin is switched by the hardware at the compare
 * match ("set / clear OC1B on compare match", ATmega328P data sheet 16.7.1, COM1B1:0 in normal
 * mode), so its edges are exact to the count (0.5 us); the compare B interrupt only programs the
 * next edge, at any time before it (at least PORT_PEN_MIN_US later): a step interrupt running
 * meanwhile delays nothing. Period SERVO_PERIOD counts = 20 ms; a new width takes effect at the
 * next rising edge. */
#define SERVO_PERIOD ((uint16_t)(F_CPU / 8u / 50u)) /* counts of 0.5 us in 20 ms: 40000 */
#define SERVO_PIN    ((uint8_t)(1u << PB2))
#define COM1B_SET    ((uint8_t)((1u << COM1B1) | (1u << COM1B0)))
#define COM1B_CLEAR  ((uint8_t)(1u << COM1B1))
CS_STATIC_ASSERT(F_CPU / 8u / 50u < 65536u && F_CPU / 8u / 1000000u * 2600u < F_CPU / 8u / 50u,
                 avr_servo_period_fits);
static volatile uint16_t servo_counts; /* the width in counts, 0: no pulse train yet */
static uint16_t servo_cur;             /* the width of the pulse under way (fixed at its rise) */
static uint8_t servo_high;             /* the last edge programmed was the rise */

void port_pen_set(uint16_t pulse_us)
{
    uint16_t c = (uint16_t)(pulse_us * (uint16_t)(F_CPU / 8000000u));
    uint8_t s = SREG;
    cli();
    if (servo_counts == 0 && c != 0) { /* first setting: start the train, rising soon */
        PORTB = (uint8_t)(PORTB & (uint8_t)~SERVO_PIN);
        DDRB = (uint8_t)(DDRB | SERVO_PIN);
        OCR1B = (uint16_t)(TCNT1 + 64u);
        TCCR1A = (uint8_t)((TCCR1A & (uint8_t)~COM1B_SET) | COM1B_SET);
        servo_high = 0;
        TIFR1 = (uint8_t)(1u << OCF1B);
        TIMSK1 = (uint8_t)(TIMSK1 | (1u << OCIE1B));
    }
    servo_counts = c;
    SREG = s;
}

/* Compare B matched: the pin has just risen or fallen; program the other edge. */
ISR(TIMER1_COMPB_vect)
{
    if (!servo_high) { /* it rose at OCR1B: fall after the width */
        servo_cur = servo_counts;
        OCR1B = (uint16_t)(OCR1B + servo_cur);
        TCCR1A = (uint8_t)((TCCR1A & (uint8_t)~COM1B_SET) | COM1B_CLEAR);
        servo_high = 1;
    } else { /* it fell: rise one period after the last rise */
        OCR1B = (uint16_t)(OCR1B + (uint16_t)(SERVO_PERIOD - servo_cur));
        TCCR1A = (uint8_t)(TCCR1A | COM1B_SET);
        servo_high = 0;
    }
}

/* The machine's inputs (port_avr.h's pin table): one switch per axis, x on PB1 (D9) and z on
 * PB4 (D12) as Grbl 1.1's, y on PC1 (A1: Grbl's D10 is the pen servo's OC1B here), read as both
 * that axis's min and max bits (Grbl wires one pin per axis, for either end: homing seeks the end
 * the HOME names, a hard limit trips on either), the probe on PC5 (A5), the e-stop on PC0 (A0).
 * Pin-change interrupts PCINT0 (port B) and PCINT1 (port C) call the edge hook; an AVR interrupt
 * never preempts another (the I bit is clear inside one), so the hook cannot preempt the step
 * interrupt, as port.h asks. */
#define LIM_X_PIN  ((uint8_t)(1u << PB1)) /* D9 */
#define LIM_Y_PIN  ((uint8_t)(1u << PC1)) /* A1 */
#define LIM_Z_PIN  ((uint8_t)(1u << PB4)) /* D12 */
#define LIM_B_PINS ((uint8_t)(LIM_X_PIN | LIM_Z_PIN))
#define PROBE_PIN  ((uint8_t)(1u << PC5)) /* A5 */
#define ESTOP_PIN  ((uint8_t)(1u << PC0)) /* A0 */
#define CTL_C_PINS ((uint8_t)(LIM_Y_PIN | PROBE_PIN | ESTOP_PIN))
#define SP_EN_PIN  ((uint8_t)(1u << PC3)) /* A3: spindle enable, high = on */
#define SP_DIR_PIN ((uint8_t)(1u << PC4)) /* A4: spindle direction, high = counter-clockwise */
#define SP_PWM_PIN ((uint8_t)(1u << PB3)) /* D11: OC2A */
#define UART_PINS  ((uint8_t)((1u << PD0) | (1u << PD1)))
/* No two functions on one pin: per port, the functions' masks summed equal them or-ed (a + b =
 * (a | b) + (a & b), so the sum exceeds the or as soon as two masks share a bit), and every pin
 * exists (port B and C: bits 0..5 on the Uno; PB6/PB7 carry the crystal, PC6 is RESET). */
#define PINS_B_SUM (EN_LINE + LIM_X_PIN + SERVO_PIN + SP_PWM_PIN + LIM_Z_PIN + LED_LINE)
#define PINS_B_OR  (EN_LINE | LIM_X_PIN | SERVO_PIN | SP_PWM_PIN | LIM_Z_PIN | LED_LINE)
#define PINS_C_SUM (ESTOP_PIN + LIM_Y_PIN + SP_EN_PIN + SP_DIR_PIN + PROBE_PIN)
#define PINS_C_OR  (ESTOP_PIN | LIM_Y_PIN | SP_EN_PIN | SP_DIR_PIN | PROBE_PIN)
#define PINS_D_SUM (UART_PINS + STEP_LINES + DIR_LINES)
#define PINS_D_OR  (UART_PINS | STEP_LINES | DIR_LINES)
CS_STATIC_ASSERT(PINS_B_SUM == PINS_B_OR && PINS_C_SUM == PINS_C_OR && PINS_D_SUM == PINS_D_OR &&
                     (PINS_B_OR & 0xC0u) == 0 && (PINS_C_OR & 0xC0u) == 0,
                 avr_pins_one_function_each);
#if PORT_AVR_INPUTS_ACTIVE_LOW
#define ACTIVE(v) ((uint8_t) ~(v))
#else
#define ACTIVE(v) ((uint8_t)(v))
#endif

uint16_t port_inputs_read(void)
{
    uint8_t b = (uint8_t)(ACTIVE(PINB) & LIM_B_PINS);
    uint8_t c = (uint8_t)(ACTIVE(PINC) & CTL_C_PINS);
    uint16_t in = 0;
    if (b & LIM_X_PIN)
        in |= (uint16_t)(CS_PROTO_IN_MIN(0) | CS_PROTO_IN_MAX(0));
    if (c & LIM_Y_PIN)
        in |= (uint16_t)(CS_PROTO_IN_MIN(1) | CS_PROTO_IN_MAX(1));
    if (b & LIM_Z_PIN)
        in |= (uint16_t)(CS_PROTO_IN_MIN(2) | CS_PROTO_IN_MAX(2));
    if (c & PROBE_PIN)
        in |= CS_PROTO_IN_PROBE;
    if (c & ESTOP_PIN)
        in |= CS_PROTO_IN_ESTOP;
    return in;
}

/* The edge hook (port.h): every pin change of a switch, the probe or the e-stop calls it; the
 * application reads the pins and keeps what changed. */
static void (*in_fn)(void *ctx);
static void *in_ctx;

void port_inputs_attach(void (*fn)(void *ctx), void *ctx)
{
    uint8_t s = SREG;
    cli();
    in_fn = fn;
    in_ctx = ctx;
    SREG = s;
}

static void inputs_edge(void)
{
    if (in_fn != NULL)
        in_fn(in_ctx);
}

ISR(PCINT0_vect)
{
    inputs_edge();
}

ISR(PCINT1_vect)
{
    inputs_edge();
}

/* The spindle / laser output, Grbl's: Timer2 fast PWM (WGM 3, TOP 0xFF) at F_CPU / 8 / 256 =
 * 7.8 kHz on OC2A (D11), non-inverting: the pin is high for OCR2A + 1 of every 256 counts
 * (ATmega328P data sheet 18.7.3), so n/256 with n = round(duty x 256 / 1000); n = 0 (or mode
 * off) disconnects OC2A and holds the pin low (OCR2A = 0 would still pulse 1/256). Timer2 runs
 * only while the output is on. Enable on A3, direction on A4. */
#define SP_TCCR2A_ON ((uint8_t)((1u << COM2A1) | (1u << WGM21) | (1u << WGM20)))
#define SP_TCCR2B_ON ((uint8_t)(1u << CS21))
#define SP_STEPS     256u /* Timer2's counts a period */
#define SP_DUTY_FULL 1000u

void port_spindle_set(uint16_t duty, uint8_t mode)
{
    uint16_t d = duty > SP_DUTY_FULL ? (uint16_t)SP_DUTY_FULL : duty;
    uint16_t n = (uint16_t)(((uint32_t)d * SP_STEPS + SP_DUTY_FULL / 2u) / SP_DUTY_FULL);
    uint8_t s = SREG;
    cli();
    if (mode == CS_PROTO_SPINDLE_OFF || n == 0) {
        TCCR2A = 0;
        TCCR2B = 0;
        PORTB = (uint8_t)(PORTB & (uint8_t)~SP_PWM_PIN);
    } else {
        OCR2A = (uint8_t)(n - 1u);
        TCCR2A = SP_TCCR2A_ON;
        TCCR2B = SP_TCCR2B_ON;
    }
    uint8_t c = (uint8_t)(PORTC & (uint8_t) ~(SP_EN_PIN | SP_DIR_PIN));
    if (mode != CS_PROTO_SPINDLE_OFF)
        c = (uint8_t)(c | SP_EN_PIN);
    if (mode == CS_PROTO_SPINDLE_CCW)
        c = (uint8_t)(c | SP_DIR_PIN);
    PORTC = c;
    SREG = s;
}

/* Inputs with the pull-ups on (PORT_AVR_INPUTS_ACTIVE_LOW: switches to ground, Grbl's wiring)
 * or off (external pull-downs), their pin-change interrupts on; the spindle's pins and the
 * servo's (no pulse until the first PEN) outputs, low. Interrupts masked. */
static void ctl_pins_init(void)
{
    DDRB = (uint8_t)((DDRB & (uint8_t)~LIM_B_PINS) | SP_PWM_PIN | SERVO_PIN);
    DDRC = (uint8_t)((DDRC & (uint8_t)~CTL_C_PINS) | SP_EN_PIN | SP_DIR_PIN);
    PORTB = (uint8_t)(PORTB & (uint8_t) ~(SP_PWM_PIN | SERVO_PIN));
    PORTC = (uint8_t)(PORTC & (uint8_t) ~(SP_EN_PIN | SP_DIR_PIN));
#if PORT_AVR_INPUTS_ACTIVE_LOW
    PORTB = (uint8_t)(PORTB | LIM_B_PINS);
    PORTC = (uint8_t)(PORTC | CTL_C_PINS);
#endif
    PCMSK0 = LIM_B_PINS;
    PCMSK1 = CTL_C_PINS;
    PCIFR = (uint8_t)((1u << PCIF0) | (1u << PCIF1));
    PCICR = (uint8_t)((1u << PCIE0) | (1u << PCIE1));
}

void port_dir_set(uint8_t mask)
{
    uint8_t s = SREG;
    cli();
    PORTD = (uint8_t)((PORTD & (uint8_t)~DIR_LINES) | lines(mask, PORT_AVR_DIR_BIT0));
    SREG = s;
}

size_t port_uart_read(uint8_t *buf, size_t max)
{
    size_t n = 0;
    uint8_t t = rx_tail;
    while (n < max && t != rx_head) {
        buf[n++] = rx_buf[t];
        t = (uint8_t)((t + 1u) & (PORT_AVR_RX_RING - 1u));
    }
    rx_tail = t;
    return n;
}

size_t port_uart_write(const uint8_t *buf, size_t len)
{
    size_t n = 0;
    uint8_t h = tx_head;
    while (n < len) {
        uint8_t next = (uint8_t)((h + 1u) & (PORT_AVR_TX_RING - 1u));
        if (next == tx_tail)
            break;
        tx_buf[h] = buf[n++];
        h = next;
    }
    tx_head = h;
    if (n != 0)
        /* not atomic (UCSR0B is out of sbi's reach) but safe: the UDRE interrupt only clears
         * the bit when the ring is empty, and it just was not */
        UCSR0B = (uint8_t)(UCSR0B | (1u << UDRIE0));
    return n;
}

void port_fault(cs_err_t code)
{
    uint8_t s = SREG;
    cli();
    stop_timer();
    PORTD = (uint8_t)(PORTD & (uint8_t)~STEP_LINES);
    PORTB = (uint8_t)(PORTB | EN_LINE | LED_LINE); /* drivers off, LED on */
    stats.fault = (uint8_t)(code == CS_OK ? CS_ERR_STATE : code);
    SREG = s;
}

void port_avr_stats(port_avr_stats_t *out)
{
    uint8_t s = SREG;
    cli();
    *out = stats;
    SREG = s;
}

bool port_avr_rx_pending(void)
{
    return rx_head != rx_tail;
}

/* --- interrupts ---------------------------------------------------------------------------- */

ISR(TIMER1_OVF_vect)
{
    ovf = ovf + 1u;
}

ISR(TIMER1_COMPA_vect)
{
    if (waiting) { /* a long period: one more piece to wait */
        uint16_t c = remain > CHUNK_LIMIT ? (uint16_t)CHUNK : (uint16_t)remain;
        remain -= c;
        waiting = remain != 0;
        deadline = (uint16_t)(deadline + c);
        set_compare();
        return;
    }
    /* 1. the previous executor call's steps, for the pulse width, with the DIR lines as the
     *    call before it left them; then the DIR levels the previous call asks for, which the
     *    steps computed now need (they go out at the next interrupt, a whole period later) */
    uint8_t b = pend_step;
    if (b != 0) {
        PORTD = (uint8_t)(PORTD | b);
        end_pulse(TCNT1);
    }
    PORTD = (uint8_t)((PORTD & (uint8_t)~DIR_LINES) | pend_dir);
    /* 2. the executor's next call */
    cs_stepper_t *st = step_st;
    if (st == NULL) {
        stop_timer();
        return;
    }
    cs_stepper_tick(st, &isr_out);
    uint8_t step = lines(isr_out.step_mask, PORT_AVR_STEP_BIT0);
    pend_step = step;
    pend_dir = lines(isr_out.dir_mask, PORT_AVR_DIR_BIT0);
    uint32_t t = isr_out.next_ticks;
    if (t - 1u < FAST_TICKS) {
        /* the common case, a short period: counts = t << TICK_SHIFT on one byte, the next
         * deadline, and the late test of set_compare inline */
        last_ticks = (uint8_t)t;
        uint16_t d = (uint16_t)(deadline + (uint16_t)((uint16_t)((uint16_t)(uint8_t)t << 8) >>
                                                      (8 - PORT_AVR_TICK_SHIFT)));
        deadline = d;
        OCR1A = d;
        if ((uint16_t)(TCNT1 - d) < 0x8000u)
            set_compare_late();
    } else if (t != 0) {
        last_ticks = t > 0xFFFFu ? (uint16_t)0xFFFFu : (uint16_t)t;
        schedule(t);
    } else if (step != 0) {
        /* the executor went idle after a call that steps: emit that step one period later,
         * like every other (pipelined) step */
        schedule(last_ticks);
    } else {
        stop_timer();
    }
}

ISR(USART_RX_vect)
{
    uint8_t st = UCSR0A;
    uint8_t c = UDR0;
    if (st & ((1u << FE0) | (1u << DOR0)))
        stats.rx_error++;
    uint8_t h = rx_head;
    uint8_t next = (uint8_t)((h + 1u) & (PORT_AVR_RX_RING - 1u));
    if (next == rx_tail) {
        stats.rx_lost++;
        return;
    }
    rx_buf[h] = c;
    rx_head = next;
}

ISR(USART_UDRE_vect)
{
    uint8_t t = tx_tail;
    if (t == tx_head) {
        UCSR0B = (uint8_t)(UCSR0B & (uint8_t) ~(1u << UDRIE0));
        return;
    }
    UDR0 = tx_buf[t];
    tx_tail = (uint8_t)((t + 1u) & (PORT_AVR_TX_RING - 1u));
}
