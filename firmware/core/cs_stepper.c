/* cs_stepper: DDA over the segments of a SPSC ring. For a segment of T ticks whose dominant axis
 * makes n steps, C = n * 2^k calls share the T ticks (call lengths by Bresenham, so they sum to T
 * exactly); each call adds |steps_i| to axis i's accumulator and steps when it reaches C, so
 * every axis makes exactly |steps_i| steps in the segment, evenly spread (Grbl's Bresenham with
 * AMASS oversampling 2^k at low rates).
 *
 * Cost, for 8-bit targets (docs/firmware-avr.md): everything per segment (C, the period's base
 * and remainder by one division, DIR levels, the axes that move) is computed in
 * cs_stepper_push, in the main loop; the interrupt's load is a copy. The accumulator is kept as
 * e = acc - C (step when e + |steps_i| >= 0: a sign test, no compare with C), only the axes
 * that move are visited (the others have |steps_i| = 0 and never step), and a segment with
 * C <= CS_STEPPER_NARROW_CALLS and a base period below 0xFFFF runs on 16-bit arithmetic: with
 * |steps_i| <= C every value of its DDA then lies in [-C, C). The outputs are
 * those of the plain 32-bit formulation, call for call (tests/unit/test_stepper_equiv.c checks
 * it against a copy of that formulation, tests/support/ref_stepper.c). */
#include "cs_stepper.h"

#include <stddef.h>

CS_STATIC_ASSERT((CS_STEPPER_RING & (CS_STEPPER_RING - 1)) == 0, stepper_ring_power_of_two);
CS_STATIC_ASSERT(CS_STEPPER_RING >= 2 && CS_STEPPER_RING <= 128, stepper_ring_size);
CS_STATIC_ASSERT(CS_AXES <= 8, axes_fit_a_mask);
CS_STATIC_ASSERT(CS_AXES <= 4, narrow_dda_unrolled_for_4_axes);
/* the common path's fields within 64 bytes of the struct (AVR: ldd's displacement reach) */
CS_STATIC_ASSERT(offsetof(cs_stepper_t, n_mag) + sizeof(uint16_t) * CS_AXES <= 64,
                 stepper_hot_fields_first);
/* narrow: e + |steps| in [-C, C) and err + rem < 2 C must fit int16 / uint16 */
CS_STATIC_ASSERT(CS_STEPPER_NARROW_CALLS <= 0x7FFFu, narrow_fits_int16);

#define SEG_MAX_TICKS ((uint32_t)1 << 24)
#define RING_MASK     ((uint8_t)(CS_STEPPER_RING - 1))
#define AXES_MASK     ((uint8_t)((1u << CS_AXES) - 1u))

/* Keeps a function out of line (GCC and Clang; elsewhere a hint the compiler may ignore). */
#if defined(__GNUC__)
#define CS_STEPPER_NOINLINE __attribute__((noinline))
#else
#define CS_STEPPER_NOINLINE
#endif

cs_err_t cs_stepper_init(cs_stepper_t *st, const cs_machine_t *m)
{
    if (st == NULL || m == NULL || m->n_axes < 1 || m->n_axes > CS_AXES)
        return CS_ERR_ARG;
    st->head = 0;
    st->tail = 0;
    st->running = false;
    st->wide = 0;
    st->move = 0;
    st->n_axes = m->n_axes;
    st->invert_mask = 0;
    for (unsigned i = 0; i < m->n_axes; i++)
        if (m->axis[i].invert_dir)
            st->invert_mask = (uint8_t)(st->invert_mask | (1u << i));
    st->dir_mask = st->invert_mask; /* positive motion selected at rest */
    st->neg_mask = 0;
    st->steps_done = 0;
    for (unsigned i = 0; i < CS_AXES; i++)
        st->pos[i] = 0;
    st->on_load = NULL;
    st->load_ctx = NULL;
    return CS_OK;
}

unsigned cs_stepper_free(const cs_stepper_t *st)
{
    uint8_t used = (uint8_t)(st->tail - st->head);
    return (unsigned)CS_STEPPER_RING - used;
}

bool cs_stepper_idle(const cs_stepper_t *st)
{
    return !st->running && st->head == st->tail;
}

/* *q = t / c, returns t % c (1 <= c <= t <= 2^24). Callers push segments with interrupts
 * masked, so this runs in the step interrupt's way: when the quotient (a call's period in
 * ticks) is below 256, as at any speed that matters, a shift-and-subtract over its few bits
 * (<= 8 steps) instead of a general 32-bit division (32 steps in libgcc on 8-bit targets). */
static uint32_t div_period(uint32_t t, uint32_t c, uint32_t *q)
{
    if (c <= (t >> 8)) {
        *q = t / c;
        return t % c;
    }
    uint32_t d = c;
    uint8_t s = 0;
    while (d <= (t >> 1)) { /* align: d <= t < 2 d, the quotient's top bit is bit s */
        d <<= 1;
        s++;
    }
    uint8_t quot = 0;
    for (;;) {
        quot = (uint8_t)(quot << 1);
        if (t >= d) {
            t -= d;
            quot |= 1u;
        }
        if (s == 0)
            break;
        s--;
        d >>= 1;
    }
    *q = quot;
    return t;
}

cs_err_t cs_stepper_push(cs_stepper_t *st, const cs_segment_t *seg)
{
    return cs_stepper_push_aux(st, seg, 0);
}

void cs_stepper_on_load(cs_stepper_t *st, cs_stepper_load_fn fn, void *ctx)
{
    st->on_load = fn;
    st->load_ctx = ctx;
}

void cs_stepper_halt(cs_stepper_t *st)
{
    st->running = false;
    st->head = st->tail;
}

cs_err_t cs_stepper_set_position(cs_stepper_t *st, unsigned axis, int32_t steps)
{
    if (axis >= CS_AXES)
        return CS_ERR_ARG;
    if (!cs_stepper_idle(st))
        return CS_ERR_STATE;
    st->pos[axis] = steps;
    return CS_OK;
}

cs_err_t cs_stepper_push_aux(cs_stepper_t *st, const cs_segment_t *seg, uint16_t aux)
{
    uint32_t ticks = seg->ticks;
    if (ticks == 0 || ticks > SEG_MAX_TICKS)
        return CS_ERR_ARG;
    uint32_t mag[CS_AXES];
    uint32_t most = 0;
    uint8_t neg = 0;
    uint8_t move = 0;
    for (unsigned i = 0; i < CS_AXES; i++) {
        int32_t s = seg->steps[i];
        uint32_t m = s < 0 ? (uint32_t)0 - (uint32_t)s : (uint32_t)s; /* INT32_MIN: 2^31 */
        if (m > ticks || (i >= st->n_axes && m != 0))
            return CS_ERR_ARG;
        if (s < 0)
            neg = (uint8_t)(neg | (1u << i));
        if (m != 0)
            move = (uint8_t)(move | (1u << i));
        if (m > most)
            most = m;
        mag[i] = m;
    }
    if (cs_stepper_free(st) == 0)
        return CS_ERR_FULL;
    /* Everything the interrupt needs, so that loading the segment there is a copy. */
    uint32_t calls = most;
    if (calls == 0) {
        calls = 1;
    } else {
        /* The DDA steps axis i when its accumulator, fed |steps_i| per call, reaches C: C may
         * grow by 2^k with the rates unchanged, so the oversampling costs nothing else. Doubling
         * keeps every call >= MIN_CALL_TICKS long: 2 C * MIN <= T, i.e. C <= floor(T / 2 MIN)
         * (C <= T <= 2^24, so nothing overflows; the divisor is a power of two, a shift). */
        for (unsigned k = 0; k < CS_STEPPER_AMASS_MAX; k++) {
            if (calls > ticks / (2u * CS_STEPPER_MIN_CALL_TICKS))
                break;
            calls *= 2u;
        }
    }
    uint8_t t = st->tail;
    cs_stepper_seg_t *p = &st->ring[t & RING_MASK];
    uint32_t base;
    p->rem = div_period(ticks, calls, &base);
    p->base = base;
    p->calls = calls;
    uint8_t wide = (uint8_t)(calls > CS_STEPPER_NARROW_CALLS || base >= 0xFFFFu);
    p->wide = wide;
    for (unsigned i = 0; i < CS_AXES; i++) {
        if (wide)
            p->mag.w[i] = mag[i];
        else
            p->mag.n[i] = (uint16_t)mag[i]; /* <= C <= 0x7FFF */
    }
    p->neg = neg;
    p->dir = (uint8_t)(((uint8_t)~neg) ^ st->invert_mask);
    p->move = move;
    p->aux = aux;
    /* The slot is written before the index that publishes it (both volatile accesses are
     * ordered; one core, so no hardware barrier is needed). */
    st->tail = (uint8_t)(t + 1u);
    return CS_OK;
}

int32_t cs_stepper_position(const cs_stepper_t *st, unsigned axis)
{
    return axis < CS_AXES ? st->pos[axis] : 0;
}

/* Makes *p the current segment. Starting the period error at C - 1 makes call j end at
 * ceil(j T / C): never before the ideal. Accumulators start at C/2 (e = C/2 - C): step k comes
 * at the first call past (k - 1/2) C / n, i.e. where the ideal position crosses a half step. */
static void load_segment(cs_stepper_t *st, const cs_stepper_seg_t *p)
{
    st->move = p->move;
    st->neg_mask = p->neg;
    st->dir_mask = p->dir;
    st->wide = p->wide;
    if (!p->wide) {
        uint16_t c = (uint16_t)p->calls;
        st->n_calls = c;
        st->n_left = c;
        st->n_base = (uint16_t)p->base;
        st->n_rem = (uint16_t)p->rem;
        st->n_err = (uint16_t)(c - 1u);
        int16_t e0 = (int16_t)((int16_t)(c / 2u) - (int16_t)c);
        for (unsigned i = 0; i < CS_AXES; i++) {
            st->n_e[i] = e0;
            st->n_mag[i] = p->mag.n[i];
        }
    } else {
        uint32_t c = p->calls;
        st->w_calls = c;
        st->w_left = c;
        st->w_base = p->base;
        st->w_rem = p->rem;
        st->w_err = c - 1u;
        int32_t e0 = (int32_t)(c / 2u) - (int32_t)c;
        for (unsigned i = 0; i < CS_AXES; i++) {
            st->w_e[i] = e0;
            st->w_mag[i] = p->mag.w[i];
        }
    }
    st->running = true;
}

/* This call's period, narrow segment: base, or base + 1 when the Bresenham error wraps
 * (err + rem < 2 C <= 0xFFFE: no overflow). */
static inline uint16_t period_narrow(cs_stepper_t *st)
{
    uint16_t p = st->n_base;
    uint16_t calls = st->n_calls;
    uint16_t err = (uint16_t)(st->n_err + st->n_rem);
    if (err >= calls) {
        err = (uint16_t)(err - calls);
        p++;
    }
    st->n_err = err;
    return p;
}

static uint32_t period_wide(cs_stepper_t *st)
{
    uint32_t p = st->w_base;
    uint32_t err = st->w_err + st->w_rem;
    if (err >= st->w_calls) {
        err -= st->w_calls;
        p++;
    }
    st->w_err = err;
    return p;
}

/* The current segment is done (or none runs): load the next one or report idle. Off the
 * common path, so kept out of line: its registers are not saved on every call. */
static CS_STEPPER_NOINLINE void next_segment(cs_stepper_t *st, cs_stepper_out_t *out)
{
    uint8_t h = st->head;
    if (h == st->tail) {
        out->dir_mask = st->dir_mask;
        out->next_ticks = 0;
        if (st->on_load != NULL)
            st->on_load(st->load_ctx, 0);
        return;
    }
    load_segment(st, &st->ring[h & RING_MASK]);
    if (st->on_load != NULL)
        st->on_load(st->load_ctx, st->ring[h & RING_MASK].aux);
    st->head = (uint8_t)(h + 1u);
    out->dir_mask = (uint8_t)(st->dir_mask & AXES_MASK);
    out->next_ticks = st->wide ? period_wide(st) : period_narrow(st);
}

/* A call of a wide segment, or while idle (out of line, as next_segment). */
static CS_STEPPER_NOINLINE void tick_slow(cs_stepper_t *st, cs_stepper_out_t *out)
{
    uint8_t mask = 0;
    if (st->running) {
        uint8_t neg = st->neg_mask;
        uint8_t move = st->move;
        int32_t calls = (int32_t)st->w_calls;
        for (unsigned i = 0; i < CS_AXES; i++) {
            uint8_t bit = (uint8_t)(1u << i);
            if (!(move & bit))
                continue;
            int32_t v = st->w_e[i] + (int32_t)st->w_mag[i];
            if (v >= 0) {
                v -= calls;
                mask = (uint8_t)(mask | bit);
                st->steps_done++;
                st->pos[i] += (neg & bit) ? -1 : 1;
            }
            st->w_e[i] = v;
        }
        out->step_mask = mask;
        if (--st->w_left != 0) {
            out->dir_mask = (uint8_t)(st->dir_mask & AXES_MASK);
            out->next_ticks = period_wide(st);
            return;
        }
        st->running = false;
    }
    out->step_mask = mask;
    next_segment(st, out);
}

/* One axis of the narrow DDA (i a constant: every field at a fixed offset from st, which 8-bit
 * targets reach with one displacement load each). Axes that do not move are skipped: their
 * |steps| is 0, they would never step. */
#define NARROW_AXIS(i)                                                                             \
    if (move & (1u << (i))) {                                                                      \
        int16_t v = (int16_t)(st->n_e[i] + (int16_t)st->n_mag[i]);                                 \
        if (v >= 0) {                                                                              \
            v = (int16_t)(v - calls);                                                              \
            mask = (uint8_t)(mask | (1u << (i)));                                                  \
            n++;                                                                                   \
            if (neg & (1u << (i)))                                                                 \
                st->pos[i] = st->pos[i] - 1;                                                       \
            else                                                                                   \
                st->pos[i] = st->pos[i] + 1;                                                       \
        }                                                                                          \
        st->n_e[i] = v;                                                                            \
    }

void cs_stepper_tick(cs_stepper_t *st, cs_stepper_out_t *out)
{
    if (!st->running || st->wide) {
        tick_slow(st, out);
        return;
    }
    /* the common path: a narrow segment's DDA call, on 16 bits */
    uint8_t mask = 0;
    uint8_t n = 0;
    uint8_t move = st->move;
    uint8_t neg = st->neg_mask;
    int16_t calls = (int16_t)st->n_calls;
    NARROW_AXIS(0)
#if CS_AXES > 1
    NARROW_AXIS(1)
#endif
#if CS_AXES > 2
    NARROW_AXIS(2)
#endif
#if CS_AXES > 3
    NARROW_AXIS(3)
#endif
    if (n != 0)
        st->steps_done += n;
    out->step_mask = mask;
    uint16_t left = (uint16_t)(st->n_left - 1u);
    st->n_left = left;
    if (left != 0) {
        out->dir_mask = (uint8_t)(st->dir_mask & AXES_MASK);
        out->next_ticks = period_narrow(st);
        return;
    }
    st->running = false;
    next_segment(st, out);
}
