/* ref_stepper: the frozen pre-optimisation cs_stepper (see ref_stepper.h). DDA over the segments of
 * a SPSC ring. For a segment of T ticks whose dominant axis makes n steps, C = n * 2^k calls share
 * the T ticks (call lengths by Bresenham, so they sum to T exactly); each call adds |steps_i| to
 * axis i's accumulator and steps when it reaches C, so every axis makes exactly |steps_i| steps in
 * the segment, evenly spread (Grbl's Bresenham with AMASS oversampling 2^k at low rates). */
#include "ref_stepper.h"

#include <stddef.h>

CS_STATIC_ASSERT((REF_STEPPER_RING & (REF_STEPPER_RING - 1)) == 0, ref_stepper_ring_power_of_two);
CS_STATIC_ASSERT(REF_STEPPER_RING >= 2 && REF_STEPPER_RING <= 128, ref_stepper_ring_size);
CS_STATIC_ASSERT(CS_AXES <= 8, ref_axes_fit_a_mask);

#define SEG_MAX_TICKS ((uint32_t)1 << 24)
#define RING_MASK     ((uint8_t)(REF_STEPPER_RING - 1))

cs_err_t ref_stepper_init(ref_stepper_t *st, const cs_machine_t *m)
{
    if (st == NULL || m == NULL || m->n_axes < 1 || m->n_axes > CS_AXES)
        return CS_ERR_ARG;
    st->head = 0;
    st->tail = 0;
    st->running = false;
    st->n_axes = m->n_axes;
    st->invert_mask = 0;
    for (unsigned i = 0; i < m->n_axes; i++)
        if (m->axis[i].invert_dir)
            st->invert_mask = (uint8_t)(st->invert_mask | (1u << i));
    st->dir_mask = st->invert_mask; /* positive motion selected at rest */
    st->neg_mask = 0;
    st->calls = 0;
    st->call_idx = 0;
    st->steps_done = 0;
    for (unsigned i = 0; i < CS_AXES; i++) {
        st->pos[i] = 0;
        st->mag[i] = 0;
        st->acc[i] = 0;
    }
    return CS_OK;
}

unsigned ref_stepper_free(const ref_stepper_t *st)
{
    uint8_t used = (uint8_t)(st->tail - st->head);
    return (unsigned)REF_STEPPER_RING - used;
}

bool ref_stepper_idle(const ref_stepper_t *st)
{
    return !st->running && st->head == st->tail;
}

cs_err_t ref_stepper_push(ref_stepper_t *st, const cs_segment_t *seg)
{
    if (seg->ticks == 0 || seg->ticks > SEG_MAX_TICKS)
        return CS_ERR_ARG;
    for (unsigned i = 0; i < CS_AXES; i++) {
        int64_t s = seg->steps[i];
        if ((s < 0 ? -s : s) > (int64_t)seg->ticks || (i >= st->n_axes && s != 0))
            return CS_ERR_ARG;
    }
    if (ref_stepper_free(st) == 0)
        return CS_ERR_FULL;
    uint8_t t = st->tail;
    st->ring[t & RING_MASK] = *seg;
    /* The slot is written before the index that publishes it (both volatile accesses are
     * ordered; one core, so no hardware barrier is needed). */
    st->tail = (uint8_t)(t + 1u);
    return CS_OK;
}

int32_t ref_stepper_position(const ref_stepper_t *st, unsigned axis)
{
    return axis < CS_AXES ? st->pos[axis] : 0;
}

/* Ticks until the next call: C calls over T ticks, base or base + 1 (Bresenham). */
static uint32_t next_period(ref_stepper_t *st)
{
    uint32_t p = st->period_base;
    st->period_err += st->period_rem;
    if (st->period_err >= st->calls) {
        st->period_err -= st->calls;
        p++;
    }
    return p;
}

static void load_segment(ref_stepper_t *st, const cs_segment_t *seg)
{
    uint32_t most = 0;
    uint8_t neg = 0;
    for (unsigned i = 0; i < CS_AXES; i++) {
        int32_t s = seg->steps[i];
        uint32_t mag = s < 0 ? (uint32_t)0 - (uint32_t)s : (uint32_t)s;
        if (s < 0)
            neg = (uint8_t)(neg | (1u << i));
        st->mag[i] = mag;
        if (mag > most)
            most = mag;
    }
    uint32_t calls = most;
    if (calls == 0) {
        calls = 1;
    } else {
        /* The DDA steps axis i when its accumulator, fed |steps_i| per call, reaches C: C may
         * grow by 2^k with the rates unchanged, so the oversampling costs nothing else. */
        for (unsigned k = 0; k < REF_STEPPER_AMASS_MAX; k++) {
            if ((uint64_t)calls * 2u * REF_STEPPER_MIN_CALL_TICKS > seg->ticks)
                break;
            calls *= 2u;
        }
    }
    st->calls = calls;
    st->call_idx = 0;
    st->period_base = seg->ticks / calls;
    st->period_rem = seg->ticks % calls;
    /* Starting the error at C - 1 makes call j end at ceil(j T / C): never before the ideal. */
    st->period_err = calls - 1u;
    /* Accumulators start at C/2: step k comes at the first call past (k - 1/2) C / n, i.e. the
     * step lands where the ideal position crosses a half step (rounded position). */
    for (unsigned i = 0; i < CS_AXES; i++)
        st->acc[i] = calls / 2u;
    st->neg_mask = neg;
    st->dir_mask = (uint8_t)(((uint8_t)~neg) ^ st->invert_mask);
    st->running = true;
}

void ref_stepper_tick(ref_stepper_t *st, ref_stepper_out_t *out)
{
    uint8_t mask = 0;
    if (st->running) {
        for (unsigned i = 0; i < CS_AXES; i++) {
            st->acc[i] += st->mag[i];
            if (st->acc[i] >= st->calls) {
                st->acc[i] -= st->calls;
                mask = (uint8_t)(mask | (1u << i));
                st->pos[i] += (st->neg_mask & (1u << i)) ? -1 : 1;
                st->steps_done++;
            }
        }
        if (++st->call_idx >= st->calls)
            st->running = false;
    }
    out->step_mask = mask;
    if (!st->running) {
        uint8_t h = st->head;
        if (h == st->tail) {
            out->dir_mask = st->dir_mask;
            out->next_ticks = 0;
            return;
        }
        load_segment(st, &st->ring[h & RING_MASK]);
        st->head = (uint8_t)(h + 1u);
    }
    out->dir_mask = (uint8_t)(st->dir_mask & ((1u << CS_AXES) - 1u));
    out->next_ticks = next_period(st);
}
