/* port_posix: simulated time for the executor; records every STEP edge with its direction. */
#include "port_posix.h"

#include <stdlib.h>
#include <unistd.h>

struct posix_state {
    uint64_t now;
    uint32_t hz;
    bool armed;
    uint64_t deadline;
    uint8_t dir_lines;
    uint8_t invert;
    cs_stepper_t *st;
    port_posix_edge_t *edges;
    size_t n, cap;
    port_posix_pen_t *pens;
    size_t npens, cappens;
    bool record, record_ok;
    int64_t pos[8];
    cs_err_t fault;
    uint32_t irq_depth;
    int fd_in, fd_out;
    size_t (*rd)(void *, uint8_t *, size_t);
    size_t (*wr)(void *, const uint8_t *, size_t);
    void *io_ctx;
    cs_exlog_edges_t elog;
    port_posix_spindle_t *spins;
    size_t nspins, capspins;
    uint16_t inputs, force_mask, force_val;
    void (*in_fn)(void *);
    void *in_ctx;
    uint16_t (*model)(void *, const int64_t *);
    void *model_ctx;
};
static struct posix_state g = {.hz = 100000,
                               .record = true,
                               .record_ok = true,
                               .fd_in = -1,
                               .fd_out = -1,
                               .elog = {0, CS_EXLOG_HASH0, 0, 0}};

void port_posix_reset(uint32_t tick_hz, uint8_t invert_mask)
{
    free(g.edges);
    free(g.pens);
    free(g.spins);
    cs_stepper_t *st = g.st;
    void (*in_fn)(void *) = g.in_fn;
    void *in_ctx = g.in_ctx;
    uint16_t (*model)(void *, const int64_t *) = g.model;
    void *model_ctx = g.model_ctx;
    int in = g.fd_in, out = g.fd_out;
    size_t (*rd)(void *, uint8_t *, size_t) = g.rd;
    size_t (*wr)(void *, const uint8_t *, size_t) = g.wr;
    void *ctx = g.io_ctx;
    g = (struct posix_state){0};
    g.in_fn = in_fn;
    g.in_ctx = in_ctx;
    g.model = model;
    g.model_ctx = model_ctx;
    g.rd = rd;
    g.wr = wr;
    g.io_ctx = ctx;
    cs_exlog_edges_init(&g.elog);
    g.hz = tick_hz;
    g.invert = invert_mask;
    g.dir_lines = invert_mask; /* positive direction at rest */
    g.record = true;
    g.record_ok = true;
    g.st = st;
    g.fd_in = in;
    g.fd_out = out;
    g.fault = CS_OK;
}

void port_init(void)
{
    port_posix_reset(g.hz, g.invert);
}

uint32_t port_ticks_now(void)
{
    return (uint32_t)g.now;
}

uint64_t port_posix_now(void)
{
    return g.now;
}

uint32_t port_tick_hz(void)
{
    return g.hz;
}

void port_stepper_attach(cs_stepper_t *st)
{
    g.st = st;
}

void port_timer_arm(uint32_t ticks)
{
    g.armed = true;
    g.deadline = g.now + (ticks ? ticks : 1u);
}

void port_timer_stop(void)
{
    g.armed = false;
}

uint32_t port_irq_save(void)
{
    return g.irq_depth++;
}

void port_irq_restore(uint32_t state)
{
    g.irq_depth = state;
}

/* Room for one more of n records of sz bytes at *buf (doubling, from first); false when out of
 * memory (*buf unchanged). */
static bool grow(void **buf, size_t *cap, size_t n, size_t sz, size_t first)
{
    if (n < *cap)
        return true;
    size_t c = *cap ? *cap * 2 : first;
    void *p = realloc(*buf, c * sz);
    if (p == NULL)
        return false;
    *buf = p;
    *cap = c;
    return true;
}

void port_step_pulse(uint8_t mask)
{
    for (unsigned i = 0; i < 8; i++) {
        if (!(mask & (1u << i)))
            continue;
        bool high = (g.dir_lines >> i) & 1u;
        bool inv = (g.invert >> i) & 1u;
        int8_t dir = (high != inv) ? 1 : -1;
        g.pos[i] += dir;
        if (!g.record)
            continue;
        void *b = g.edges;
        bool ok = grow(&b, &g.cap, g.n, sizeof *g.edges, 4096);
        g.edges = b;
        if (!ok) {
            g.record_ok = false;
            continue;
        }
        g.edges[g.n++] = (port_posix_edge_t){g.now, (uint8_t)i, dir};
    }
}

void port_pen_set(uint16_t pulse_us)
{
    void *b = g.pens;
    bool ok = grow(&b, &g.cappens, g.npens, sizeof *g.pens, 64);
    g.pens = b;
    if (!ok) {
        g.record_ok = false;
        return;
    }
    g.pens[g.npens++] = (port_posix_pen_t){g.now, pulse_us};
}

void port_spindle_set(uint16_t duty, uint8_t mode)
{
    void *b = g.spins;
    bool ok = grow(&b, &g.capspins, g.nspins, sizeof *g.spins, 256);
    g.spins = b;
    if (!ok) {
        g.record_ok = false;
        return;
    }
    g.spins[g.nspins++] = (port_posix_spindle_t){g.now, duty, mode};
}

const port_posix_spindle_t *port_posix_spindles(size_t *n)
{
    *n = g.nspins;
    return g.spins;
}

/* The pins: the bits from the model and the forced ones; a pin that changed fires the edge hook
 * (a board's pin-change interrupt fires on a change only). */
static void inputs_update(void)
{
    uint16_t b = g.model != NULL ? g.model(g.model_ctx, g.pos) : 0;
    b = (uint16_t)((b & (uint16_t)~g.force_mask) | (g.force_val & g.force_mask));
    if (b == g.inputs)
        return;
    g.inputs = b;
    if (g.in_fn != NULL)
        g.in_fn(g.in_ctx);
}

uint16_t port_inputs_read(void)
{
    return g.inputs;
}

void port_inputs_attach(void (*fn)(void *ctx), void *ctx)
{
    g.in_fn = fn;
    g.in_ctx = ctx;
    inputs_update();
}

void port_posix_inputs_model(uint16_t (*model)(void *ctx, const int64_t *pos), void *ctx)
{
    g.model = model;
    g.model_ctx = ctx;
    inputs_update();
}

void port_posix_inputs_force(uint16_t mask, uint16_t value)
{
    g.force_mask = mask;
    g.force_val = value;
    inputs_update();
}

const port_posix_pen_t *port_posix_pens(size_t *n)
{
    *n = g.npens;
    return g.pens;
}

void port_dir_set(uint8_t mask)
{
    g.dir_lines = mask;
}

size_t port_uart_read(uint8_t *buf, size_t max)
{
    if (g.rd != NULL)
        return g.rd(g.io_ctx, buf, max);
    if (g.fd_in < 0)
        return 0;
    ssize_t r = read(g.fd_in, buf, max);
    return r > 0 ? (size_t)r : 0;
}

size_t port_uart_write(const uint8_t *buf, size_t len)
{
    if (g.wr != NULL)
        return g.wr(g.io_ctx, buf, len);
    if (g.fd_out < 0)
        return 0;
    ssize_t r = write(g.fd_out, buf, len);
    return r > 0 ? (size_t)r : 0;
}

void port_fault(cs_err_t code)
{
    g.armed = false;
    g.fault = code;
}

/* The step interrupt, as a real port's timer ISR would be written. */
static void step_isr(void)
{
    cs_stepper_out_t o;
    cs_stepper_tick(g.st, &o);
    cs_exlog_tick(&g.elog, &o);
    port_step_pulse(o.step_mask);
    port_dir_set(o.dir_mask);
    if (o.next_ticks != 0)
        port_timer_arm(o.next_ticks);
    else
        port_timer_stop();
    /* the switches move with the machine: sampled after each step (the hook may halt) */
    if (o.step_mask != 0)
        inputs_update();
}

bool port_posix_run(uint64_t until)
{
    if (g.st == NULL)
        return false;
    for (;;) {
        if (g.fault != CS_OK)
            return false;
        if (!g.armed) {
            if (cs_stepper_idle(g.st))
                return true;
            port_timer_arm(1); /* wake up: work was queued while stopped */
        }
        if (g.deadline > until) {
            if (until > g.now)
                g.now = until; /* time never runs backwards */
            return true;
        }
        g.now = g.deadline;
        g.armed = false;
        step_isr();
    }
}

void port_posix_idle_until(uint64_t until)
{
    if (!g.armed && (g.st == NULL || cs_stepper_idle(g.st)) && until > g.now)
        g.now = until;
}

bool port_posix_step(void)
{
    if (g.st == NULL || g.fault != CS_OK)
        return false;
    if (!g.armed) {
        if (cs_stepper_idle(g.st))
            return false;
        port_timer_arm(1);
    }
    g.now = g.deadline;
    g.armed = false;
    step_isr();
    return true;
}

const port_posix_edge_t *port_posix_edges(size_t *n)
{
    *n = g.n;
    return g.edges;
}

void port_posix_record(bool on)
{
    g.record = on;
}

bool port_posix_record_ok(void)
{
    return g.record_ok;
}

int64_t port_posix_position(unsigned axis)
{
    return axis < 8 ? g.pos[axis] : 0;
}

cs_err_t port_posix_fault(void)
{
    return g.fault;
}

void port_posix_uart(int fd_in, int fd_out)
{
    g.fd_in = fd_in;
    g.fd_out = fd_out;
}

void port_posix_uart_hooks(size_t (*rd)(void *ctx, uint8_t *buf, size_t max),
                           size_t (*wr)(void *ctx, const uint8_t *buf, size_t len), void *ctx)
{
    g.rd = rd;
    g.wr = wr;
    g.io_ctx = ctx;
}

cs_exlog_edges_t port_posix_edge_log(void)
{
    return g.elog;
}
