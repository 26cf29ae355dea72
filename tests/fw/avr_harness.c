/* avr_harness: runs a curvestep ATmega328p image in simavr (libsimavr) and checks what its pins
 * do. USART0 is joined to a pseudo-terminal (the slave's path is the first line of standard
 * output, as `curvestep-sim --pty` prints it, so `curvestep stream --port PTY` talks to the
 * firmware); the STEP/DIR lines of Grbl's Uno pin map (port_avr.h: STEP x/y/z = PD2..PD4, DIR =
 * PD5..PD7) are watched through simavr's pin IRQs, stamped with the exact CPU cycle; the step
 * interrupt (Timer1 compare A) is timed from its vector fetch to its RETI through simavr's
 * per-vector "running" IRQ. At the end (idle after activity, a cycle budget, a wall timeout, or
 * SIGTERM/SIGINT) it prints the step counts and final position per axis, the shortest STEP pulse
 * and the shortest DIR set-up before a STEP, and the interrupt's cycle counts; it exits non-zero
 * on a violation. Usage: avr_harness --help. */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <signal.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <avr_extint.h>
#include <avr_ioport.h>
#include <avr_uart.h>
#include <sim_avr.h>
#include <sim_elf.h>
#include <sim_interrupts.h>
#include <sim_irq.h>

/* Exit codes */
enum { EX_OK = 0, EX_VIOLATION = 1, EX_USAGE = 2, EX_EMU = 3, EX_TIMEOUT = 4 };

#define AXES         3
#define STEP_BIT0    2 /* PD2 */
#define DIR_BIT0     5 /* PD5 */
#define VEC_T1_COMPA 11
#define HIST_MAX     8192 /* interrupt lengths histogrammed exactly below this many cycles */
#define VEC_T1_COMPB 12   /* Timer1 compare B: the pen servo's edges (port_avr.c) */
#define SERVO_WRAP_CYC 524288u /* one Timer1 wrap: 65536 counts of 8 cycles */
#define TCCR1A_ADDR  0x80 /* data-space address of TCCR1A (ATmega328P register summary) */
#define SERVO_WIDTHS 256 /* distinct successive servo pulse widths kept for the report */
#define SLICE        1024 /* cycles run between two services of the pty and the clocks */
/* Machine-control pins (port_avr.h): inputs active low (pulled up), a switch per axis on PB1
 * (D9) / PC1 (A1) / PB4 (D12), the probe on PC5, the e-stop on PC0; the spindle's Timer2 PWM on
 * OC2A, enable PC3, direction PC4. Data-space addresses from the ATmega328P register summary. */
#define SW_MAX       8
#define PROBE_BIT    5 /* PC5 */
#define ESTOP_BIT    0 /* PC0 */
#define SP_EN_BIT    3 /* PC3 */
#define SP_DIR_BIT   4 /* PC4 */
#define PORTC_ADDR   0x28
#define TCCR2A_ADDR  0xB0
#define TCCR2B_ADDR  0xB1
#define OCR2A_ADDR   0xB3
#define PWM_SETS     64 /* distinct successive spindle settings kept for the report */
static const uint8_t limit_bit[AXES] = {1, 1, 4}; /* PB1 (D9), PC1 (A1), PB4 (D12) */
static const char limit_port[AXES] = {'B', 'C', 'B'};

typedef struct {
    uint64_t steps;   /* rising STEP edges */
    int64_t pos;      /* signed by the DIR line (and the invert mask) */
    bool step_high;   /* STEP line level */
    bool dir_high;    /* DIR line level */
    uint64_t rise_at; /* cycle of the last STEP rise */
    uint64_t dir_at;  /* cycle of the last DIR change (0: never changed) */
    bool dir_changed; /* DIR has changed at least once */
    uint64_t fall_at; /* cycle of the last STEP fall (0: none yet) */
    uint64_t min_pulse, min_low, min_setup, min_hold;
    uint64_t first_rise, last_rise;
    uint64_t dir_in_pulse; /* DIR changes while STEP was high */
} axis_t;

typedef struct {
    uint8_t tccr2a, tccr2b, ocr2a, portc;
} pwm_set_t;

static struct {
    avr_t *avr;
    axis_t ax[AXES];
    uint8_t invert;
    /* interrupt timing */
    uint64_t isr_enter;
    bool isr_in;
    uint64_t isr_n, isr_sum, isr_min, isr_max, isr_over;
    uint32_t *hist;
    /* uart */
    int master, slave;
    avr_irq_t *uart_in;
    avr_uart_t *uart;
    uint8_t inbuf[4096];
    size_t in_len, in_pos;
    uint8_t outbuf[65536];
    size_t out_len;
    uint64_t bytes_in, bytes_out, bytes_dropped;
    /* activity */
    bool active;
    uint64_t last_activity; /* cycle */
    uint64_t min_sp;
    /* the servo pin (OC1B = PB2): rises, the period between them, the distinct widths in turn */
    bool servo_high;
    uint64_t servo_rise, servo_periods, servo_pmin, servo_pmax;
    uint64_t servo_dropped; /* compare matches simavr did not deliver (whole wraps late) */
    uint64_t servo_w[SERVO_WIDTHS];
    size_t servo_nw;
    /* simulated switches: pressed while the axis's pin position is at or beyond `at` */
    struct {
        char port;   /* 'B' or 'C' */
        uint8_t bit; /* pin */
        int axis;
        bool above; /* pressed while pos >= at (else pos <= at) */
        int64_t at;
        bool pressed;
        uint64_t presses;
        int64_t press_pos[AXES]; /* every axis's pin position at the last press */
    } sw[SW_MAX];
    int nsw;
    uint8_t ext[2]; /* the levels driven on ports B and C (bit set = high = released) */
    double estop_at; /* --estop-at: simulated second the e-stop is pressed (< 0: never) */
    bool estop_done;
    /* the spindle's settings as the registers show them, sampled every slice */
    pwm_set_t pwm[PWM_SETS];
    int npwm;
    FILE *csv;
    FILE *isr_csv;  /* --isr-csv: every step interrupt, "entry-cycle,cycles" */
    uint64_t *prof; /* --profile: cycles spent at each flash word inside the step interrupt */
} g;

static volatile sig_atomic_t g_stop;

static void on_signal(int sig)
{
    (void)sig;
    g_stop = 1;
}

static double wall_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* --- pins ---------------------------------------------------------------------------------- */

/* Drives input pin (port, bit) to level, as simavr's default for an input too (so a write of
 * PORT, which simavr turns into the pull-up level, keeps a pressed switch pressed). */
static void drive(char port, uint8_t bit, bool high)
{
    uint8_t *e = &g.ext[port == 'B' ? 0 : 1];
    *e = (uint8_t)(high ? *e | (1u << bit) : *e & ~(1u << bit));
    avr_ioport_external_t x = {.name = (unsigned long)port, .mask = 0xFFu, .value = *e};
    avr_ioctl(g.avr, AVR_IOCTL_IOPORT_SET_EXTERNAL(port), &x);
    avr_raise_irq(avr_io_getirq(g.avr, AVR_IOCTL_IOPORT_GETIRQ(port), bit), high ? 1 : 0);
}

/* The switches against the pin positions: a pin goes low (active) while any switch on it is
 * pressed. Called at start and after every STEP rise. */
static void switches_update(void)
{
    for (int k = 0; k < g.nsw; k++) {
        int64_t p = g.ax[g.sw[k].axis].pos;
        bool on = g.sw[k].above ? p >= g.sw[k].at : p <= g.sw[k].at;
        if (on && !g.sw[k].pressed) {
            g.sw[k].presses++;
            for (int i = 0; i < AXES; i++)
                g.sw[k].press_pos[i] = g.ax[i].pos;
        }
        g.sw[k].pressed = on;
    }
    for (int k = 0; k < g.nsw; k++) {
        bool low = false;
        for (int j = 0; j < g.nsw; j++)
            if (g.sw[j].port == g.sw[k].port && g.sw[j].bit == g.sw[k].bit && g.sw[j].pressed)
                low = true;
        uint8_t e = g.ext[g.sw[k].port == 'B' ? 0 : 1];
        if (((e >> g.sw[k].bit) & 1u) != (low ? 0u : 1u))
            drive(g.sw[k].port, g.sw[k].bit, !low);
    }
}

/* The spindle's registers now, kept when they differ from the last kept. */
static void pwm_sample(void)
{
    const uint8_t *d = g.avr->data;
    uint8_t a = d[TCCR2A_ADDR], b = d[TCCR2B_ADDR], o = d[OCR2A_ADDR];
    uint8_t c = (uint8_t)(d[PORTC_ADDR] & ((1u << SP_EN_BIT) | (1u << SP_DIR_BIT)));
    if (g.npwm > 0) {
        const pwm_set_t *l = &g.pwm[g.npwm - 1];
        if (l->tccr2a == a && l->tccr2b == b && l->ocr2a == o && l->portc == c)
            return;
    } else if (a == 0 && b == 0 && c == 0) {
        return; /* off since reset: nothing to say */
    }
    if (g.npwm < PWM_SETS) {
        g.pwm[g.npwm].tccr2a = a;
        g.pwm[g.npwm].tccr2b = b;
        g.pwm[g.npwm].ocr2a = o;
        g.pwm[g.npwm].portc = c;
        g.npwm++;
    }
}

static void on_step(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    axis_t *a = &g.ax[(intptr_t)param];
    uint64_t now = g.avr->cycle;
    bool high = value != 0;
    if (high == a->step_high)
        return;
    a->step_high = high;
    if (high) {
        a->rise_at = now;
        if (a->fall_at != 0 && now - a->fall_at < a->min_low)
            a->min_low = now - a->fall_at;
        a->steps++;
        bool positive = a->dir_high != (((g.invert >> (intptr_t)param) & 1u) != 0);
        a->pos += positive ? 1 : -1;
        if (g.nsw > 0)
            switches_update();
        if (a->first_rise == 0)
            a->first_rise = now;
        a->last_rise = now;
        if (a->dir_changed) {
            uint64_t setup = now - a->dir_at;
            if (setup < a->min_setup)
                a->min_setup = setup;
        }
        if (g.csv)
            fprintf(g.csv, "%llu,%d,%d\n", (unsigned long long)now, (int)(intptr_t)param,
                    positive ? 1 : -1);
        g.active = true;
        g.last_activity = now;
    } else {
        uint64_t w = now - a->rise_at;
        if (w < a->min_pulse)
            a->min_pulse = w;
        a->fall_at = now;
    }
}

static void on_dir(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    axis_t *a = &g.ax[(intptr_t)param];
    bool high = value != 0;
    if (high == a->dir_high)
        return;
    uint64_t now = g.avr->cycle;
    a->dir_high = high;
    a->dir_at = now;
    a->dir_changed = true;
    if (a->step_high)
        a->dir_in_pulse++;
    if (a->steps > 0) {
        uint64_t hold = now - a->rise_at;
        if (hold < a->min_hold)
            a->min_hold = hold;
    }
}

/* The servo output OC1B (PB2), as the data sheet defines it (ATmega328P 16.7.1, normal mode):
 * at each Timer1 compare-B match the pin goes to the level its COM1B1:0 bits in TCCR1A say
 * (3: set, 2: clear). The match is seen here as the compare-B interrupt becoming pending, at its
 * exact cycle, and the bits are read from the chip's registers at that cycle. (simavr 1.6 also
 * drives the pin, but models normal mode like PWM mode, forcing the opposite level at every
 * overflow and on every OCR1A write, which the real chip does not: the pin itself is not read.)
 * Each rise closes a period (rise to rise); each fall closes a pulse, whose width is kept when it
 * differs from the one before. Not activity: the train runs while idle.
 * simavr 1.6 now and then drops a compare match (its normal-mode compare timers are cancelled and
 * re-armed on every OCR1x write, and the step interrupt writes OCR1A all the time): the edge
 * then comes a whole Timer1 wrap (65536 counts) late. Such an interval is counted as a drop and
 * measured less the wraps, so the period and width figures stay those the firmware programmed;
 * any other error still shows. */
static void on_servo(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    if (value == 0)
        return;
    uint8_t com = (uint8_t)((g.avr->data[TCCR1A_ADDR] >> 4) & 3u);
    if (com < 2)
        return;
    bool high = com == 3;
    if (high == g.servo_high)
        return;
    g.servo_high = high;
    uint64_t now = g.avr->cycle;
    if (high) {
        if (g.servo_rise != 0) {
            uint64_t p = now - g.servo_rise;
            while (p > SERVO_WRAP_CYC + SERVO_WRAP_CYC / 2u) { /* a match simavr did not deliver */
                p -= SERVO_WRAP_CYC;
                g.servo_dropped++;
            }
            g.servo_pmin = p < g.servo_pmin ? p : g.servo_pmin;
            g.servo_pmax = p > g.servo_pmax ? p : g.servo_pmax;
            g.servo_periods++;
        }
        g.servo_rise = now;
    } else if (g.servo_rise != 0) {
        /* in Timer1 counts (8 cycles): simavr stamps events at instruction boundaries, a few
         * cycles after the match; the pin itself switches on the count */
        uint64_t w = now - g.servo_rise;
        while (w > SERVO_WRAP_CYC / 2u) { /* as above: no servo pulse is 32 ms long */
            w -= SERVO_WRAP_CYC;
            g.servo_dropped++;
        }
        w = (w + 4u) / 8u;
        if ((g.servo_nw == 0 || g.servo_w[g.servo_nw - 1] != w) && g.servo_nw < SERVO_WIDTHS)
            g.servo_w[g.servo_nw++] = w;
    }
}

/* --- the step interrupt ---------------------------------------------------------------------- */

static void on_isr(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    uint64_t now = g.avr->cycle;
    if (value) {
        g.isr_enter = now;
        g.isr_in = true;
        return;
    }
    if (!g.isr_in)
        return;
    g.isr_in = false;
    uint64_t d = now - g.isr_enter;
    g.isr_n++;
    g.isr_sum += d;
    if (d < g.isr_min)
        g.isr_min = d;
    if (d > g.isr_max)
        g.isr_max = d;
    if (g.isr_csv)
        fprintf(g.isr_csv, "%llu,%llu\n", (unsigned long long)g.isr_enter, (unsigned long long)d);
    if (d < HIST_MAX)
        g.hist[d]++;
    else
        g.isr_over++;
}

static uint64_t isr_percentile(double p)
{
    uint64_t want = (uint64_t)(p * (double)(g.isr_n - 1)), seen = 0;
    for (uint64_t c = 0; c < HIST_MAX; c++) {
        seen += g.hist[c];
        if (seen > want)
            return c;
    }
    return g.isr_max;
}

/* --- uart ---------------------------------------------------------------------------------- */

static void on_uart_out(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    g.bytes_out++;
    if (g.out_len < sizeof g.outbuf)
        g.outbuf[g.out_len++] = (uint8_t)value;
    else
        g.bytes_dropped++;
}

/* The simulated USART0 (found by walking simavr's IO modules: its RX FIFO is needed to feed
 * bytes no faster than the line takes them). */
static avr_uart_t *find_uart(avr_t *avr)
{
    for (avr_io_t *io = avr->io_port; io; io = io->next)
        if (io->kind && strcmp(io->kind, "uart") == 0 && ((avr_uart_t *)io)->name == '0')
            return (avr_uart_t *)io;
    return NULL;
}

/* Bytes waiting in simavr's USART input FIFO (its accessors are only declared in the header). */
static unsigned fifo_fill(const uart_fifo_t *f)
{
    return (unsigned)((f->write + uart_fifo_fifo_size) - f->read) & (uart_fifo_fifo_size - 1u);
}

/* Moves bytes between the pty and the USART. The USART's input FIFO is kept at most a few
 * bytes deep; simavr hands them to the firmware one per byte time of the configured baud. */
static void service_uart(void)
{
    if (g.master < 0)
        return;
    if (g.in_pos == g.in_len) {
        g.in_pos = g.in_len = 0;
        ssize_t r = read(g.master, g.inbuf, sizeof g.inbuf);
        if (r > 0)
            g.in_len = (size_t)r;
    }
    while (g.in_pos < g.in_len && fifo_fill(&g.uart->input) < 4) {
        avr_raise_irq(g.uart_in, g.inbuf[g.in_pos++]);
        g.bytes_in++;
        g.active = true;
        g.last_activity = g.avr->cycle;
    }
    if (g.out_len > 0) {
        ssize_t w = write(g.master, g.outbuf, g.out_len);
        if (w > 0) {
            memmove(g.outbuf, g.outbuf + w, g.out_len - (size_t)w);
            g.out_len -= (size_t)w;
        } else if (w < 0 && errno != EAGAIN && errno != EINTR) {
            g.bytes_dropped += g.out_len; /* nobody on the line: a real UART loses them too */
            g.out_len = 0;
        }
    }
}

/* simavr's default sleep callback sleeps on the wall clock to keep pace; the main loop below
 * paces (or not, --fast) itself, and must keep serving the pty while the chip sleeps. */
static void no_sleep(avr_t *avr, avr_cycle_count_t how_long)
{
    (void)avr;
    (void)how_long;
}

/* --- main ---------------------------------------------------------------------------------- */

/* A number in [lo, hi] (a bad one ends the program: usage error). */
static double number(const char *v, double lo, double hi)
{
    char *end;
    double d = strtod(v, &end);
    if (end == v || *end != '\0' || !(d >= lo && d <= hi)) {
        fprintf(stderr, "avr_harness: '%s': expected a number in [%g, %g]\n", v, lo, hi);
        exit(EX_USAGE);
    }
    return d;
}

/* "--switch-min x=STEPS" and the like: a switch on (port, bit) pressed while axis's position is
 * at or beyond STEPS. */
static void add_switch(const char *v, char port, int bit, bool above, int fixed_axis)
{
    int axis = fixed_axis;
    if (axis < 0) {
        if (v[0] < 'x' || v[0] > 'z' || v[1] != '=') {
            fprintf(stderr, "avr_harness: '%s': expected AXIS=STEPS, AXIS x, y or z\n", v);
            exit(EX_USAGE);
        }
        axis = v[0] - 'x';
        v += 2;
        bit = limit_bit[axis];
        port = limit_port[axis];
    }
    if (g.nsw >= SW_MAX) {
        fprintf(stderr, "avr_harness: at most %d switches\n", SW_MAX);
        exit(EX_USAGE);
    }
    g.sw[g.nsw].port = port;
    g.sw[g.nsw].bit = (uint8_t)bit;
    g.sw[g.nsw].axis = axis;
    g.sw[g.nsw].above = above;
    g.sw[g.nsw].at = (int64_t)number(v, -1e12, 1e12);
    g.nsw++;
}

static void usage(FILE *f)
{
    fprintf(
        f,
        "usage: avr_harness [--pty] [--cycles N] [--timeout SEC] [--idle-exit SEC] [--fast]\n"
        "                   [--batch] [--min-pulse-us US] [--min-dir-setup-us US] [--invert MASK]\n"
        "                   [--steps-csv FILE] [--isr-csv FILE] [--profile FILE]\n"
        "                   [--switch-min AXIS=STEPS] [--switch-max AXIS=STEPS]\n"
        "                   [--probe-z STEPS] [--estop-at SEC] FIRMWARE.elf\n"
        "Runs FIRMWARE.elf on a simulated ATmega328p at 16 MHz (simavr) and watches its\n"
        "STEP (PD2..PD4) and DIR (PD5..PD7) pins and its step interrupt (Timer1 COMPA).\n"
        "  --pty               USART0 on a new pseudo-terminal; its path is the first line\n"
        "                      of standard output (for curvestep stream --port)\n"
        "  --cycles N          cycle budget: stop after N cycles (default 16e6 x 120)\n"
        "  --timeout SEC       wall-clock limit (default 50): reaching it is exit 4\n"
        "  --idle-exit SEC     after activity (a step or a byte from the host), stop when\n"
        "                      neither happens for SEC simulated seconds (default 1; 0: never)\n"
        "  --fast              run as fast as the host can (default: never ahead of the\n"
        "                      wall clock, as the real chip; the host's timeouts assume it)\n"
        "  --batch             let simavr run instructions in batches (faster; timing stays\n"
        "                      cycle-exact, but the lowest SP is only sampled at batch ends\n"
        "                      and --profile is refused)\n"
        "  --min-pulse-us US   a STEP pulse, or a STEP low time between two pulses,\n"
        "                      shorter than US is a violation (default 0)\n"
        "  --min-dir-setup-us US  a STEP rise less than US after its DIR changed is a\n"
        "                      violation (default 0); so is DIR changing while STEP is high\n"
        "  --invert MASK       axes whose DIR line is inverted (bit i = axis i), for signs\n"
        "  --steps-csv FILE    every STEP rise: cycle,axis,dir\n"
        "  --isr-csv FILE      every step interrupt: entry-cycle,cycles (vector to RETI)\n"
        "  --profile FILE      cycles spent at each instruction inside the step interrupt:\n"
        "                      lines 'byte-address cycles' (avr-addr2line, nm to read)\n"
        "  --switch-min AXIS=STEPS, --switch-max AXIS=STEPS  the limit switch of AXIS (x\n"
        "                      PB1/D9, y PC1/A1, z PB4/D12; one pin an axis, as Grbl's)\n"
        "                      is pressed (pin low) while the axis's STEP/DIR position is\n"
        "                      <= (min) or >= (max) STEPS; evaluated at every STEP rise\n"
        "  --probe-z STEPS     the probe (PC5/A5) touches while z <= STEPS\n"
        "  --estop-at SEC      the e-stop (PC0/A0) is pressed at that simulated second\n"
        "                      (reported at once: 'estop: pressed at SEC s')\n"
        "Prints (after the pty line): the run, the UART traffic, per-axis steps and final\n"
        "position, the shortest pulse and low time, DIR set-up and hold, the step\n"
        "interrupt's cycles, the lowest stack pointer, each switch's presses with the\n"
        "positions at the last one, and the spindle's settings in turn (Timer2's\n"
        "registers and the enable / direction pins, sampled every 64 us).\n"
        "Exit status: 0 ok, 1 a pulse or DIR violation, 2 usage, 3 emulator error (ELF,\n"
        "crash), 4 wall timeout.\n");
}

int main(int argc, char **argv)
{
    const char *elf = NULL, *csv = NULL, *prof = NULL, *isr_csv = NULL;
    bool pty = false, fast = false, batch = false;
    uint64_t budget = 16000000ull * 120;
    double timeout = 50, idle_exit = 1, min_pulse_us = 0, min_setup_us = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        bool more = i + 1 < argc;
        if (strcmp(a, "--help") == 0) {
            usage(stdout);
            return EX_OK;
        } else if (strcmp(a, "--pty") == 0) {
            pty = true;
        } else if (strcmp(a, "--fast") == 0) {
            fast = true;
        } else if (strcmp(a, "--batch") == 0) {
            batch = true;
        } else if (strcmp(a, "--cycles") == 0 && more) {
            budget = (uint64_t)number(argv[++i], 1, 1e15);
        } else if (strcmp(a, "--timeout") == 0 && more) {
            timeout = number(argv[++i], 0.001, 1e6);
        } else if (strcmp(a, "--idle-exit") == 0 && more) {
            idle_exit = number(argv[++i], 0, 1e6);
        } else if (strcmp(a, "--min-pulse-us") == 0 && more) {
            min_pulse_us = number(argv[++i], 0, 1e6);
        } else if (strcmp(a, "--min-dir-setup-us") == 0 && more) {
            min_setup_us = number(argv[++i], 0, 1e6);
        } else if (strcmp(a, "--invert") == 0 && more) {
            g.invert = (uint8_t)number(argv[++i], 0, 7);
        } else if (strcmp(a, "--steps-csv") == 0 && more) {
            csv = argv[++i];
        } else if (strcmp(a, "--isr-csv") == 0 && more) {
            isr_csv = argv[++i];
        } else if (strcmp(a, "--profile") == 0 && more) {
            prof = argv[++i];
        } else if (strcmp(a, "--switch-min") == 0 && more) {
            add_switch(argv[++i], 'B', 0, false, -1);
        } else if (strcmp(a, "--switch-max") == 0 && more) {
            add_switch(argv[++i], 'B', 0, true, -1);
        } else if (strcmp(a, "--probe-z") == 0 && more) {
            add_switch(argv[++i], 'C', PROBE_BIT, false, 2);
        } else if (strcmp(a, "--estop-at") == 0 && more) {
            g.estop_at = number(argv[++i], 1e-6, 1e6);
        } else if (a[0] == '-' || elf != NULL) {
            fprintf(stderr, "avr_harness: bad argument '%s'\n", a);
            usage(stderr);
            return EX_USAGE;
        } else {
            elf = a;
        }
    }
    if (batch && prof != NULL) {
        fprintf(stderr,
                "avr_harness: --profile needs one instruction at a time: not with --batch\n");
        return EX_USAGE;
    }
    if (elf == NULL) {
        usage(stderr);
        return EX_USAGE;
    }
    /* Our report goes to the real standard output; simavr prints its own chatter with printf,
     * which goes to standard error from here on, so the pty path stays the first line. */
    int out_fd = dup(STDOUT_FILENO);
    FILE *out = out_fd >= 0 ? fdopen(out_fd, "w") : NULL;
    if (out == NULL || dup2(STDERR_FILENO, STDOUT_FILENO) < 0) {
        perror("avr_harness: stdout");
        return EX_EMU;
    }
    g.master = g.slave = -1;
    if (g.estop_at == 0)
        g.estop_at = -1; /* (0 is refused above: a pressed e-stop at boot is not modelled) */
    g.isr_min = UINT64_MAX;
    g.min_sp = UINT64_MAX;
    g.hist = calloc(HIST_MAX, sizeof *g.hist);
    for (int i = 0; i < AXES; i++)
        g.ax[i].min_pulse = g.ax[i].min_low = g.ax[i].min_setup = g.ax[i].min_hold = UINT64_MAX;
    if (prof != NULL && (g.prof = calloc(0x4000, sizeof *g.prof)) == NULL)
        return EX_EMU;
    if (isr_csv != NULL && (g.isr_csv = fopen(isr_csv, "w")) == NULL) {
        perror(isr_csv);
        return EX_USAGE;
    }
    if (csv != NULL && (g.csv = fopen(csv, "w")) == NULL) {
        perror(csv);
        return EX_USAGE;
    }

    elf_firmware_t fw;
    memset(&fw, 0, sizeof fw);
    if (elf_read_firmware(elf, &fw) != 0) {
        fprintf(stderr, "avr_harness: %s: cannot read the ELF\n", elf);
        return EX_EMU;
    }
    avr_t *avr = avr_make_mcu_by_name("atmega328p");
    if (avr == NULL || g.hist == NULL) {
        fprintf(stderr, "avr_harness: no atmega328p in this simavr\n");
        return EX_EMU;
    }
    g.avr = avr;
    avr_init(avr);
    avr->log = LOG_ERROR;
    avr->sleep = no_sleep;
    /* --batch: simavr runs instructions in batches up to the next timer event or interrupt
     * (timing stays exact) instead of one per call; only the per-instruction watches (lowest
     * SP, --profile) then see the batch ends */
    if (batch)
        avr->run_cycle_limit = SLICE;
    /* INT0/INT1 (PD2/PD3, our STEP x/y outputs) are unused; simavr's "strict" level trigger
     * polls them with a cycle timer every cycle, which makes every cycle a timer event: a
     * sleeping chip then takes as long to simulate as a running one (10x slower overall) */
    avr_extint_set_strict_lvl_trig(avr, 0, 0);
    avr_extint_set_strict_lvl_trig(avr, 1, 0);
    fw.frequency = 16000000; /* the image carries no .mmcu section: the clock is set here */
    avr_load_firmware(avr, &fw);
    avr->frequency = 16000000;

    for (intptr_t i = 0; i < AXES; i++) {
        avr_irq_register_notify(
            avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('D'), (int)(STEP_BIT0 + i)), on_step,
            (void *)i);
        avr_irq_register_notify(
            avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('D'), (int)(DIR_BIT0 + i)), on_dir,
            (void *)i);
    }
    /* every machine-control input released (high: the pull-ups), then the switches' state */
    g.ext[0] = 0xFF;
    g.ext[1] = 0xFF;
    for (int b = 0; b < AXES; b++)
        drive('B', limit_bit[b], true);
    drive('C', PROBE_BIT, true);
    drive('C', ESTOP_BIT, true);
    switches_update();
    avr_irq_t *vecb = avr_get_interrupt_irq(avr, VEC_T1_COMPB);
    if (vecb == NULL) {
        fprintf(stderr, "avr_harness: no vector %d\n", VEC_T1_COMPB);
        return EX_EMU;
    }
    avr_irq_register_notify(vecb + AVR_INT_IRQ_PENDING, on_servo, NULL);
    g.servo_pmin = UINT64_MAX;
    avr_irq_t *vec = avr_get_interrupt_irq(avr, VEC_T1_COMPA);
    if (vec == NULL) {
        fprintf(stderr, "avr_harness: no vector %d\n", VEC_T1_COMPA);
        return EX_EMU;
    }
    avr_irq_register_notify(vec + AVR_INT_IRQ_RUNNING, on_isr, NULL);

    uint32_t flags = 0; /* no console echo, no usleep when the firmware polls the status */
    avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
    g.uart = find_uart(avr);
    g.uart_in = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT),
                            on_uart_out, NULL);
    if (g.uart == NULL || g.uart_in == NULL) {
        fprintf(stderr, "avr_harness: USART0 not found\n");
        return EX_EMU;
    }
    if (pty) {
        char name[256];
        struct termios t;
        if (openpty(&g.master, &g.slave, name, NULL, NULL) != 0) {
            perror("avr_harness: openpty");
            return EX_EMU;
        }
        /* raw, and keep our slave open: no hang-up between hosts; a host flushes what piled
         * up meanwhile */
        if (tcgetattr(g.slave, &t) == 0) {
            cfmakeraw(&t);
            tcsetattr(g.slave, TCSANOW, &t);
        }
        fcntl(g.master, F_SETFL, fcntl(g.master, F_GETFL) | O_NONBLOCK);
        fprintf(out, "%s\n", name);
        fflush(out);
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);

    const char *why = "cycle budget";
    int rc = EX_OK;
    double t0 = wall_now();
    uint64_t idle_cycles = (uint64_t)(idle_exit * 16e6);
    int state = cpu_Running;
    for (;;) {
        /* a slice of SLICE cycles between two services of the pty and the clocks: 64 us of
         * the chip's time, under a byte time at 115200 baud */
        uint64_t until = avr->cycle + SLICE;
        while (avr->cycle < until) {
            uint32_t pc = avr->pc;
            uint64_t c0 = avr->cycle;
            bool in = g.isr_in;
            state = avr_run(avr);
            if (g.prof != NULL && in && pc < 0x8000)
                g.prof[pc >> 1] += avr->cycle - c0;
            uint16_t sp = (uint16_t)(avr->data[0x5D] | (avr->data[0x5E] << 8));
            if (sp < g.min_sp && sp >= 0x100)
                g.min_sp = sp;
            if (state == cpu_Done || state == cpu_Crashed)
                break;
        }
        if (state == cpu_Done || state == cpu_Crashed) {
            why = state == cpu_Done ? "the firmware stopped" : "the firmware crashed";
            rc = state == cpu_Crashed ? EX_EMU : rc;
            break;
        }
        service_uart();
        pwm_sample();
        if (g.estop_at >= 0 && !g.estop_done && (double)avr->cycle / 16e6 >= g.estop_at) {
            drive('C', ESTOP_BIT, false);
            g.estop_done = true;
            fprintf(out, "estop: pressed at %.3f s\n", g.estop_at); /* now: tests wait on it */
            fflush(out);
        }
        if (g_stop) {
            why = "signal";
            break;
        }
        if (avr->cycle >= budget)
            break;
        if (g.active && idle_cycles > 0 && avr->cycle - g.last_activity > idle_cycles) {
            why = "idle";
            break;
        }
        double wall = wall_now() - t0;
        if (wall > timeout) {
            why = "wall timeout";
            rc = EX_TIMEOUT;
            break;
        }
        /* pacing: a real chip never runs ahead of the clock on the wall */
        double ahead = (double)avr->cycle / 16e6 - wall;
        if (!fast && ahead > 0.002) {
            struct pollfd p = {g.master, POLLIN, 0};
            int ms = (int)(ahead * 1000);
            if (g.master >= 0 && g.in_pos == g.in_len)
                poll(&p, 1, ms);
            else
                usleep((useconds_t)ms * 1000u);
        }
    }
    service_uart();
    double wall = wall_now() - t0;
    double sim_s = (double)avr->cycle / 16e6;
    static const char names[] = "xyz";

    fprintf(out,
            "avr: %llu cycles (%.4f s at 16 MHz) in %.2f s wall (%.1f MHz equivalent); "
            "stopped: %s\n",
            (unsigned long long)avr->cycle, sim_s, wall,
            wall > 0 ? (double)avr->cycle / wall / 1e6 : 0.0, why);
    fprintf(out, "uart: %llu bytes in, %llu bytes out, %llu dropped\n",
            (unsigned long long)g.bytes_in, (unsigned long long)g.bytes_out,
            (unsigned long long)g.bytes_dropped);
    fprintf(out, "steps:");
    for (int i = 0; i < AXES; i++)
        fprintf(out, " %c=%llu", names[i], (unsigned long long)g.ax[i].steps);
    fprintf(out, "\nposition:");
    for (int i = 0; i < AXES; i++)
        fprintf(out, " %c=%lld", names[i], (long long)g.ax[i].pos);
    fprintf(out, "\n");

    uint64_t mp = UINT64_MAX, ml = UINT64_MAX, ms = UINT64_MAX, mh = UINT64_MAX, in_pulse = 0;
    for (int i = 0; i < AXES; i++) {
        mp = g.ax[i].min_pulse < mp ? g.ax[i].min_pulse : mp;
        ml = g.ax[i].min_low < ml ? g.ax[i].min_low : ml;
        ms = g.ax[i].min_setup < ms ? g.ax[i].min_setup : ms;
        mh = g.ax[i].min_hold < mh ? g.ax[i].min_hold : mh;
        in_pulse += g.ax[i].dir_in_pulse;
    }
    bool bad_high = mp != UINT64_MAX && (double)mp < min_pulse_us * 16.0;
    bool bad_low = ml != UINT64_MAX && (double)ml < min_pulse_us * 16.0;
    bool bad_setup = ms != UINT64_MAX && (double)ms < min_setup_us * 16.0;
    if (mp != UINT64_MAX)
        fprintf(out, "pulse: min %llu cycles (%.3f us), required %.3f us: %s\n",
                (unsigned long long)mp, (double)mp / 16.0, min_pulse_us,
                bad_high ? "VIOLATION" : "ok");
    else
        fprintf(out, "pulse: none\n");
    if (ml != UINT64_MAX)
        fprintf(out,
                "step-low: min %llu cycles (%.3f us) between two pulses of an axis, "
                "required %.3f us: %s\n",
                (unsigned long long)ml, (double)ml / 16.0, min_pulse_us,
                bad_low ? "VIOLATION" : "ok");
    if (ms != UINT64_MAX)
        fprintf(out, "dir-setup: min %llu cycles (%.3f us), required %.3f us: %s\n",
                (unsigned long long)ms, (double)ms / 16.0, min_setup_us,
                bad_setup ? "VIOLATION" : "ok");
    else
        fprintf(out, "dir-setup: no DIR change before a step\n");
    if (mh != UINT64_MAX)
        fprintf(out, "dir-hold: min %llu cycles (%.3f us) from a STEP rise to a DIR change\n",
                (unsigned long long)mh, (double)mh / 16.0);
    fprintf(out, "dir-in-pulse: %llu DIR changes while STEP was high: %s\n",
            (unsigned long long)in_pulse, in_pulse ? "VIOLATION" : "ok");
    if (g.isr_n > 0)
        fprintf(out,
                "isr: vector %d (TIMER1_COMPA): %llu calls; cycles from vector to reti: min "
                "%llu, median %llu, p99 %llu, max %llu, mean %.1f\n",
                VEC_T1_COMPA, (unsigned long long)g.isr_n, (unsigned long long)g.isr_min,
                (unsigned long long)isr_percentile(0.5), (unsigned long long)isr_percentile(0.99),
                (unsigned long long)g.isr_max, (double)g.isr_sum / (double)g.isr_n);
    else
        fprintf(out, "isr: vector %d (TIMER1_COMPA): no calls\n", VEC_T1_COMPA);
    if (g.servo_periods > 0) {
        fprintf(out, "servo: OC1B %llu periods, rise to rise min %llu max %llu cycles (%.3f..%.3f "
                     "us), %llu dropped matches, widths (us):",
                (unsigned long long)g.servo_periods, (unsigned long long)g.servo_pmin,
                (unsigned long long)g.servo_pmax, (double)g.servo_pmin / 16.0,
                (double)g.servo_pmax / 16.0, (unsigned long long)g.servo_dropped);
        for (size_t k = 0; k < g.servo_nw; k++)
            fprintf(out, " %.1f", (double)g.servo_w[k] / 2.0);
        fprintf(out, "\n");
    } else {
        fprintf(out, "servo: OC1B no period\n");
    }
    for (int k = 0; k < g.nsw; k++) {
        fprintf(out, "switch: P%c%d %s %c %s %lld: %llu presses", g.sw[k].port, g.sw[k].bit,
                g.sw[k].port == 'C' && g.sw[k].bit == PROBE_BIT ? "probe" : "limit",
                names[g.sw[k].axis], g.sw[k].above ? ">=" : "<=", (long long)g.sw[k].at,
                (unsigned long long)g.sw[k].presses);
        if (g.sw[k].presses > 0) {
            fprintf(out, ", last at");
            for (int i = 0; i < AXES; i++)
                fprintf(out, " %c=%lld", names[i], (long long)g.sw[k].press_pos[i]);
        }
        fprintf(out, "\n");
    }
    if (g.estop_at >= 0 && !g.estop_done)
        fprintf(out, "estop: not reached (%.3f s)\n", g.estop_at);
    for (int k = 0; k < g.npwm; k++) {
        const pwm_set_t *w = &g.pwm[k];
        /* on: OC2A connected non-inverting (COM2A = 2) in fast PWM (WGM 3), clocked */
        bool on = (w->tccr2a & 0xC3u) == 0x83u && (w->tccr2b & 0x0Fu) != 0;
        fprintf(out, "pwm: %d: TCCR2A=0x%02x TCCR2B=0x%02x OCR2A=%u enable=%d dir=%d", k,
                w->tccr2a, w->tccr2b, w->ocr2a, (w->portc >> SP_EN_BIT) & 1,
                (w->portc >> SP_DIR_BIT) & 1);
        if (on)
            fprintf(out, " duty %u/256\n", w->ocr2a + 1u);
        else
            fprintf(out, " off\n");
    }
    if (g.min_sp != UINT64_MAX)
        fprintf(out, "stack: lowest SP 0x%04llx (%llu bytes below the top of RAM 0x08ff)%s\n",
                (unsigned long long)g.min_sp, (unsigned long long)(0x8ffu - g.min_sp),
                batch ? ", sampled (--batch)" : "");
    for (int i = 0; i < AXES; i++)
        if (g.ax[i].steps > 1)
            fprintf(out, "rate: %c %.1f steps/s from its first to its last step\n", names[i],
                    (double)(g.ax[i].steps - 1) * 16e6 /
                        (double)(g.ax[i].last_rise - g.ax[i].first_rise));
    if (rc == EX_OK && (bad_high || bad_low || bad_setup || in_pulse))
        rc = EX_VIOLATION;
    fprintf(out, "result: %s\n",
            rc == EX_OK          ? "ok"
            : rc == EX_VIOLATION ? "VIOLATION"
            : rc == EX_TIMEOUT   ? "TIMEOUT"
                                 : "EMULATOR ERROR");
    fflush(out);
    if (g.csv)
        fclose(g.csv);
    if (g.isr_csv)
        fclose(g.isr_csv);
    if (g.prof != NULL) {
        FILE *f = fopen(prof, "w");
        for (unsigned w = 0; f != NULL && w < 0x4000; w++)
            if (g.prof[w])
                fprintf(f, "0x%04x %llu\n", w * 2, (unsigned long long)g.prof[w]);
        if (f)
            fclose(f);
        free(g.prof);
    }
    if (g.master >= 0)
        close(g.master);
    if (g.slave >= 0)
        close(g.slave);
    avr_terminate(avr);
    /* what elf_read_firmware allocated is the caller's (avr_load_firmware copied the code) */
    free(fw.flash);
    free(fw.eeprom);
    free(fw.fuse);
    free(fw.lockbits);
    for (uint32_t i = 0; fw.symbol != NULL && i < fw.symbolcount; i++)
        free(fw.symbol[i]);
    free(fw.symbol);
    free(g.hist);
    return rc;
}
