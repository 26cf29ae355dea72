/* cs_gpio_run: the step thread. One thread owns the executor (pushes and ticks), so the
 * cs_stepper ring keeps its one-writer-per-index rule without any cross-thread ordering. Each
 * executor call is computed ahead of its deadline, then the thread waits (clock_nanosleep to
 * spin_ns before the deadline, then spins on clock_gettime: wake-up latency on a loaded
 * machine is tens of microseconds) and drives the lines (docs/gpio.md "The step thread"). */
#include "cs_gpio_run.h"

#include "cs_hold.h"

#include <errno.h>
#include <sched.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <time.h>

#if defined(__SANITIZE_ADDRESS__)
#define GPIO_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define GPIO_ASAN 1
#endif
#endif

/* At least this long between starting the thread and tick 0 (the first DIR levels settle). */
#define START_LEAD_NS 1000000
/* Sleeps are cut into pieces of at most this, to see a stop-at-once request. */
#define SLEEP_SLICE_NS 20000000
#define THREAD_STACK   (256 * 1024)

static int64_t ticks_to_ns(uint64_t ticks, uint32_t hz)
{
    /* exact floor(ticks * 1e9 / hz) without overflowing 64 bits for any job length */
    return (int64_t)((ticks / hz) * 1000000000u + (ticks % hz) * 1000000000u / hz);
}

static int load_hold(const cs_gpio_run_t *r)
{
    return __atomic_load_n(&r->hold, __ATOMIC_ACQUIRE);
}

/* Waits until CLOCK_MONOTONIC reaches t. false when asked to stop at once meanwhile. */
static bool wait_until(const cs_gpio_run_t *r, int64_t t, int64_t spin)
{
    for (;;) {
        int64_t now = cs_gpio_io_now_ns();
        if (now >= t)
            return true;
        if (t - now <= spin)
            break;
        int64_t wake = t - spin;
        if (wake - now > SLEEP_SLICE_NS)
            wake = now + SLEEP_SLICE_NS;
        struct timespec ts = {(time_t)(wake / 1000000000), (long)(wake % 1000000000)};
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL);
        if (load_hold(r) >= 2)
            return false;
    }
    while (cs_gpio_io_now_ns() < t) {
#if defined(__x86_64__) || defined(__i386__)
        __builtin_ia32_pause();
#endif
    }
    return true;
}

static void note_late(cs_gpio_run_t *r, int64_t late)
{
    if (late < 0)
        late = 0;
    if (late > r->late_max_ns) /* the main thread reads it for its progress line */
        __atomic_store_n(&r->late_max_ns, late, __ATOMIC_RELAXED);
    r->late_sum_ns += (double)late;
    int64_t us = late / 1000;
    unsigned k = 0;
    while (us > 0 && k + 1 < CS_GPIO_LATE_BUCKETS) {
        us >>= 1;
        k++;
    }
    r->late_hist[k]++;
    r->rises++;
}

/* Line levels for an executor output: STEP lines of the axes in step_mask, DIR lines from
 * dir_mask (bit set = line high, already corrected for invert_dir by the executor). */
static uint32_t step_lines(const cs_gpio_run_opts_t *o, uint8_t step_mask)
{
    uint32_t v = 0;
    for (unsigned i = 0; i < CS_AXES; i++)
        if ((step_mask >> i & 1u) && o->step_line[i] >= 0)
            v |= 1u << o->step_line[i];
    return v;
}

static uint32_t dir_lines(const cs_gpio_run_opts_t *o, uint8_t dir_mask)
{
    uint32_t v = 0;
    for (unsigned i = 0; i < CS_AXES; i++)
        if ((dir_mask >> i & 1u) && o->dir_line[i] >= 0)
            v |= 1u << o->dir_line[i];
    return v;
}

static void *thread_main(void *arg)
{
    cs_gpio_run_t *r = arg;
    const cs_gpio_run_opts_t *o = &r->o;
    const cs_gpio_cfg_t *cfg = o->cfg;
    cs_gpio_io_t *io = o->io;
    cs_stepper_t *st = &r->st;
    const uint32_t hz = o->m->tick_hz;
    const int64_t spin = cfg->spin_ns, pulse = cfg->pulse_ns, setup = cfg->dir_setup_ns;
    prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL); /* ns-precise sleeps without SCHED_FIFO */

    uint32_t all_step = step_lines(o, 0xff), all_dir = dir_lines(o, 0xff);
    uint32_t en = o->enable_line >= 0 ? 1u << o->enable_line : 0;
    /* The hold: the core's ramp (cs_hold), the one every device runs: segments re-timed along
     * the job's own path down to rest, then feeding stops at a segment end. */
    cs_hold_t hold;
    (void)cs_hold_init(&hold, o->m); /* the executor accepted the machine: so does the ramp */
    int64_t t, t_dir = INT64_MIN / 2;
    bool ok = true;
    if (en)
        ok = cs_gpio_io_set(io, en, en, cs_gpio_io_now_ns(), &t) == 0;
    size_t next = o->first, pushed = 0;
    cs_stepper_out_t out = {0, 0, 0};
    cs_gpio_run_outcome_t oc = CS_GPIO_RUN_DONE;
    if (ok && next < o->nsegs) {
        if (cs_stepper_push(st, &o->segs[next]) == CS_OK) {
            next++;
            pushed++;
        } else {
            oc = CS_GPIO_RUN_BAD_SEGMENT;
            r->bad_segment = next + 1;
        }
    }
    cs_stepper_tick(st, &out); /* the kick: loads the first segment, no step */
    int64_t start = cs_gpio_io_now_ns();
    r->t0_ns = start + (cfg->enable_ns > START_LEAD_NS && en ? cfg->enable_ns : START_LEAD_NS);
    uint32_t dir = io->levels & all_dir;
    uint32_t want = dir_lines(o, out.dir_mask);
    if (ok && want != dir) {
        ok = cs_gpio_io_set(io, all_dir, want, start, &t_dir) == 0;
        dir = want;
    }
    uint64_t vt = 0;
    int64_t planned = r->t0_ns;
    bool unsent = false; /* stopped with a call's steps computed but not on the lines */
    int32_t unsent_pos[CS_AXES];
    while (ok && oc == CS_GPIO_RUN_DONE) {
        if (out.next_ticks == 0) {
            oc = hold.hold ? CS_GPIO_RUN_HELD : CS_GPIO_RUN_DONE;
            break;
        }
        int h = load_hold(r);
        if (h >= 2) {
            oc = CS_GPIO_RUN_STOPPED;
            break;
        }
        if (h == 1 && !hold.hold)
            cs_hold_set(&hold, true);
        vt += out.next_ticks;
        planned = r->t0_ns + ticks_to_ns(vt, hz);
        /* one segment queued behind the running one is enough (this thread refills before
         * every call); once the hold has come to rest, nothing more is fed */
        if (next < o->nsegs && cs_stepper_free(st) == CS_STEPPER_RING) {
            cs_segment_t sg = o->segs[next];
            if (cs_hold_admit(&hold, &sg)) {
                if (cs_stepper_push(st, &sg) != CS_OK) {
                    oc = CS_GPIO_RUN_BAD_SEGMENT; /* the executor refused it: stop here */
                    r->bad_segment = next + 1;
                    break;
                }
                next++;
                pushed++;
            }
        }
        int32_t before[CS_AXES]; /* the executor's position without this call's steps */
        for (unsigned i = 0; i < CS_AXES; i++)
            before[i] = cs_stepper_position(st, i);
        cs_stepper_tick(st, &out);
        if (out.step_mask) {
            uint32_t s = step_lines(o, out.step_mask);
            int64_t at = planned > t_dir + setup ? planned : t_dir + setup;
            if (!wait_until(r, at, spin)) {
                oc = CS_GPIO_RUN_STOPPED;
                unsent = true;
                for (unsigned i = 0; i < CS_AXES; i++)
                    unsent_pos[i] = before[i];
                break;
            }
            int64_t t_rise, t_fall;
            if (cs_gpio_io_set(io, s, s, planned, &t_rise) != 0) {
                ok = false;
                break;
            }
            note_late(r, t_rise - planned);
            for (unsigned i = 0; i < CS_AXES; i++)
                if (out.step_mask >> i & 1u)
                    r->steps[i]++;
            wait_until(r, t_rise + pulse, spin);
            if (cs_gpio_io_set(io, s, 0, planned + pulse, &t_fall) != 0) {
                ok = false;
                break;
            }
        }
        want = dir_lines(o, out.dir_mask);
        if (want != dir) {
            if (!out.step_mask && !wait_until(r, planned, spin)) {
                oc = CS_GPIO_RUN_STOPPED;
                break;
            }
            if (cs_gpio_io_set(io, all_dir, want, out.step_mask ? planned + pulse : planned,
                               &t_dir) != 0) {
                ok = false;
                break;
            }
            dir = want;
        }
        /* segments popped by the executor; all but the running one are done */
        size_t popped = pushed - (CS_STEPPER_RING - cs_stepper_free(st));
        size_t done = popped - (out.next_ticks != 0 && popped > 0 ? 1u : 0u);
        __atomic_store_n(&r->executed, o->first + done, __ATOMIC_RELEASE);
    }
    if (!ok) {
        oc = CS_GPIO_RUN_IO_ERROR;
        r->io_errno = errno;
    }
    /* safe: every STEP inactive, ENABLE off (DIR as it is) */
    cs_gpio_io_set(io, all_step | en, 0, cs_gpio_io_now_ns(), &r->t_end_ns);
    r->ticks = vt;
    for (unsigned i = 0; i < CS_AXES; i++)
        r->pos[i] = unsent ? unsent_pos[i] : cs_stepper_position(st, i);
    if (oc == CS_GPIO_RUN_DONE || oc == CS_GPIO_RUN_HELD) {
        size_t popped = pushed - (CS_STEPPER_RING - cs_stepper_free(st));
        __atomic_store_n(&r->executed, o->first + popped, __ATOMIC_RELEASE);
        if (o->first + popped >= o->nsegs) /* a hold that came too late to stop anything */
            oc = CS_GPIO_RUN_DONE;
    }
    r->outcome = oc;
    __atomic_store_n(&r->finished, 1, __ATOMIC_RELEASE);
    return NULL;
}

int cs_gpio_run_start(cs_gpio_run_t *r, const cs_gpio_run_opts_t *opts)
{
    memset(r, 0, sizeof *r);
    r->o = *opts;
    r->sched_err = -1;
    r->mlock_err = -1;
    r->executed = opts->first;
    if (cs_stepper_init(&r->st, opts->m) != CS_OK)
        return EINVAL;
    if (opts->realtime) {
#ifdef GPIO_ASAN
        r->mlock_err = -2; /* ASan's shadow memory is terabytes of reserved address space */
#else
        r->mlock_err = mlockall(MCL_CURRENT | MCL_FUTURE) == 0 ? 0 : errno;
#endif
    }
    pthread_attr_t at;
    pthread_attr_init(&at);
    pthread_attr_setstacksize(&at, THREAD_STACK);
    int rc = EPERM;
    if (opts->realtime && opts->cfg->rt_priority > 0) {
        struct sched_param sp;
        memset(&sp, 0, sizeof sp);
        sp.sched_priority = opts->cfg->rt_priority;
        pthread_attr_t rt;
        pthread_attr_init(&rt);
        pthread_attr_setstacksize(&rt, THREAD_STACK);
        pthread_attr_setinheritsched(&rt, PTHREAD_EXPLICIT_SCHED);
        pthread_attr_setschedpolicy(&rt, SCHED_FIFO);
        pthread_attr_setschedparam(&rt, &sp);
        rc = pthread_create(&r->th, &rt, thread_main, r);
        pthread_attr_destroy(&rt);
        r->sched_err = rc;
    }
    if (rc != 0)
        rc = pthread_create(&r->th, &at, thread_main, r);
    pthread_attr_destroy(&at);
    if (rc != 0) {
        if (r->mlock_err == 0)
            munlockall();
        return rc;
    }
    r->started = true;
    return 0;
}

void cs_gpio_run_hold(cs_gpio_run_t *r, int level)
{
    int cur = __atomic_load_n(&r->hold, __ATOMIC_ACQUIRE);
    if (level > cur)
        __atomic_store_n(&r->hold, level, __ATOMIC_RELEASE);
}

size_t cs_gpio_run_executed(const cs_gpio_run_t *r)
{
    return __atomic_load_n(&r->executed, __ATOMIC_ACQUIRE);
}

bool cs_gpio_run_finished(const cs_gpio_run_t *r)
{
    return __atomic_load_n(&r->finished, __ATOMIC_ACQUIRE) != 0;
}

void cs_gpio_run_join(cs_gpio_run_t *r)
{
    if (!r->started)
        return;
    pthread_join(r->th, NULL);
    r->started = false;
    if (r->mlock_err == 0)
        munlockall();
}

int64_t cs_gpio_run_late_quantile(const cs_gpio_run_t *r, double q)
{
    if (r->rises == 0)
        return 0;
    double want = q * (double)r->rises;
    uint64_t acc = 0;
    for (unsigned k = 0; k < CS_GPIO_LATE_BUCKETS; k++) {
        acc += r->late_hist[k];
        if ((double)acc >= want) {
            if (k + 1 == CS_GPIO_LATE_BUCKETS)
                return r->late_max_ns;
            int64_t ub = ((int64_t)1 << k) * 1000; /* bucket k: below 2^k us */
            return ub < r->late_max_ns ? ub : r->late_max_ns;
        }
    }
    return r->late_max_ns;
}

size_t cs_gpio_run_record_capacity(const cs_segment_t *s, size_t n)
{
    size_t steps = 0;
    for (size_t k = 0; k < n; k++)
        for (unsigned i = 0; i < CS_AXES; i++)
            steps += (size_t)(s[k].steps[i] < 0 ? -(int64_t)s[k].steps[i] : s[k].steps[i]);
    return 2 * steps + n + 16;
}
