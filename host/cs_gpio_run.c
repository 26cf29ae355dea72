/* cs_gpio_run: the step thread. One thread owns the executor (pushes and ticks), so the
 * cs_stepper ring keeps its one-writer-per-index rule without any cross-thread ordering. Each
 * executor call is computed ahead of its deadline, then the thread waits (clock_nanosleep to
 * spin_ns before the deadline, then spins on clock_gettime: wake-up latency on a loaded
 * machine is tens of microseconds) and drives the lines (docs/gpio.md "The step thread"). */
#include "cs_gpio_run.h"

#include "cs_hold.h"
#include "cs_proto.h"

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

/* True when the run is asked to stop at once (a cancel): ends a wait early. */
static bool stop_now(const void *ctx)
{
    const cs_gpio_run_t *r = ctx;
    /* the e-stop ends a long wait too (a dwell, a slow axis): seen within one sleep slice */
    const cs_gpio_in_t *in = r->o.in;
    if (in != NULL && (__atomic_load_n(&in->bits, __ATOMIC_ACQUIRE) & CS_PROTO_IN_ESTOP))
        return true;
    return load_hold(r) >= 2;
}

/* Waits until CLOCK_MONOTONIC reaches t. false when asked to stop at once meanwhile. */
static bool wait_until(const cs_gpio_run_t *r, int64_t t, int64_t spin)
{
    return cs_gpio_io_wait_until(t, spin, SLEEP_SLICE_NS, stop_now, r);
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

/* The step thread's working state (one per run, on its stack). */
typedef struct {
    cs_gpio_run_t *r;
    const cs_gpio_run_opts_t *o;
    cs_gpio_io_t *io;
    cs_stepper_t *st;
    uint32_t hz;
    int64_t spin, pulse, setup;     /* cfg, ns */
    uint32_t all_step, all_dir, en; /* line masks */
    cs_hold_t hold;                 /* the core's ramp (cs_hold) */
    int64_t t_dir;                  /* last DIR change on the lines */
    bool ok;                        /* every set call succeeded */
    size_t next, pushed;            /* job index of the next segment; segments pushed */
    cs_stepper_out_t out;           /* the executor's last call */
    cs_gpio_run_outcome_t oc;       /* DONE while running */
    uint32_t dir;                   /* DIR levels on the lines */
    uint64_t vt;                    /* executor ticks so far */
    int64_t planned;                /* planned time of the current call */
    int64_t shift;                  /* ns added to the plan by pauses */
    bool unsent;                    /* stopped with a call's steps computed, not on lines */
    int32_t unsent_pos[CS_AXES];    /* the executor's position without them */
    uint16_t in_prev;               /* the input bits last read */
} stepper_run_t;

/* The inputs with the lines at executor position pos: true (and the outcome TRIPPED) when the
 * e-stop is active, an input the operation watches changed as it waits for, or a limit switch
 * became active with hard limits on -- the device's rule (cs_fw_ctl_inputs_isr), in the same
 * order. */
static bool inputs_trip(stepper_run_t *s, const int32_t pos[CS_AXES])
{
    const cs_gpio_run_opts_t *o = s->o;
    if (o->in == NULL)
        return false;
    int32_t p[CS_AXES];
    for (unsigned i = 0; i < CS_AXES; i++)
        p[i] = o->start_pos[i] + pos[i];
    uint16_t b = cs_gpio_in_read(o->in, p);
    uint16_t on = (uint16_t)(b & ~s->in_prev), off = (uint16_t)(s->in_prev & ~b);
    s->in_prev = b;
    s->r->inputs = b;
    int code = -1;
    if (b & CS_PROTO_IN_ESTOP)
        code = CS_PROTO_ALARM_ESTOP;
    else if ((b & o->watch) || (off & o->release))
        code = 0;
    else if (o->hard_limits && (on & CS_PROTO_IN_LIMITS))
        code = CS_PROTO_ALARM_HARD_LIMIT;
    if (code < 0)
        return false;
    s->r->trip_code = (uint8_t)code;
    s->r->trip_inputs = b;
    s->oc = CS_GPIO_RUN_TRIPPED;
    return true;
}

static void exec_pos(const stepper_run_t *s, int32_t pos[CS_AXES])
{
    for (unsigned i = 0; i < CS_AXES; i++)
        pos[i] = cs_stepper_position(s->st, i);
}

/* Pushes segment s->next (after the hold's admission) into the executor. false when the
 * executor refused it (BAD_SEGMENT) or the hold keeps it back. */
static bool feed_next(stepper_run_t *s, bool admit)
{
    cs_segment_t sg = s->o->segs[s->next];
    if (admit && !cs_hold_admit(&s->hold, &sg))
        return false;
    if (cs_stepper_push(s->st, &sg) != CS_OK) {
        s->oc = CS_GPIO_RUN_BAD_SEGMENT; /* the executor refused it: stop here */
        s->r->bad_segment = s->next + 1;
        return false;
    }
    s->next++;
    s->pushed++;
    return true;
}

/* ENABLE on, the first segment loaded (the kick: no step), tick 0 planned, first DIR levels. */
static void step_begin(stepper_run_t *s)
{
    cs_gpio_run_t *r = s->r;
    const cs_gpio_run_opts_t *o = s->o;
    const cs_gpio_cfg_t *cfg = o->cfg;
    int64_t t;
    s->st = &r->st;
    s->io = o->io;
    s->hz = o->m->tick_hz;
    s->spin = cfg->spin_ns;
    s->pulse = cfg->pulse_ns;
    s->setup = cfg->dir_setup_ns;
    s->all_step = step_lines(o, 0xff);
    s->all_dir = dir_lines(o, 0xff);
    s->en = o->enable_line >= 0 ? 1u << o->enable_line : 0;
    /* The hold: the core's ramp (cs_hold), the one every device runs: segments re-timed along
     * the job's own path down to rest, then feeding stops at a segment end. */
    (void)cs_hold_init(&s->hold, o->m); /* the executor accepted the machine: so does the ramp */
    s->t_dir = INT64_MIN / 2;
    s->ok = true;
    if (s->en)
        s->ok = cs_gpio_io_set(s->io, s->en, s->en, cs_gpio_io_now_ns(), &t) == 0;
    s->next = o->first;
    s->oc = CS_GPIO_RUN_DONE;
    if (o->in != NULL) { /* the levels at the start: a switch already pressed is no new edge */
        int32_t p[CS_AXES];
        for (unsigned i = 0; i < CS_AXES; i++)
            p[i] = o->start_pos[i];
        s->in_prev = cs_gpio_in_read(o->in, p) & (uint16_t)~CS_PROTO_IN_ESTOP;
    }
    if (s->ok && s->next < o->nsegs)
        (void)feed_next(s, false);
    cs_stepper_tick(s->st, &s->out);
    int64_t start = cs_gpio_io_now_ns();
    r->t0_ns = start + (cfg->enable_ns > START_LEAD_NS && s->en ? cfg->enable_ns : START_LEAD_NS);
    s->dir = s->io->levels & s->all_dir;
    uint32_t want = dir_lines(o, s->out.dir_mask);
    if (s->ok && want != s->dir) {
        s->ok = cs_gpio_io_set(s->io, s->all_dir, want, start, &s->t_dir) == 0;
        s->dir = want;
    }
    s->planned = r->t0_ns;
}

/* The STEP pulse of the call just computed (before[]: the position without its steps): rise at
 * the planned time (not before the DIR set-up), fall a pulse width later. false to stop. */
static bool emit_steps(stepper_run_t *s, const int32_t before[CS_AXES])
{
    cs_gpio_run_t *r = s->r;
    uint32_t lines = step_lines(s->o, s->out.step_mask);
    int64_t at = s->planned > s->t_dir + s->setup ? s->planned : s->t_dir + s->setup;
    bool waited = wait_until(r, at, s->spin);
    /* the inputs read after the wait (an edge while waiting, or the e-stop that ended it) */
    bool tripped = inputs_trip(s, before);
    if (!waited || tripped) { /* stopped or tripped: this call's steps are not made */
        if (!tripped)
            s->oc = CS_GPIO_RUN_STOPPED;
        s->unsent = true;
        for (unsigned i = 0; i < CS_AXES; i++)
            s->unsent_pos[i] = before[i];
        return false;
    }
    int64_t t_rise, t_fall;
    if (cs_gpio_io_set(s->io, lines, lines, s->planned, &t_rise) != 0) {
        s->ok = false;
        return false;
    }
    note_late(r, t_rise - s->planned);
    for (unsigned i = 0; i < CS_AXES; i++)
        if (s->out.step_mask >> i & 1u)
            r->steps[i]++;
    wait_until(r, t_rise + s->pulse, s->spin);
    if (cs_gpio_io_set(s->io, lines, 0, s->planned + s->pulse, &t_fall) != 0) {
        s->ok = false;
        return false;
    }
    return true;
}

/* The DIR levels of the call just computed, after its STEP pulse. false to stop. */
static bool emit_dir(stepper_run_t *s)
{
    uint32_t want = dir_lines(s->o, s->out.dir_mask);
    if (want == s->dir)
        return true;
    if (!s->out.step_mask && !wait_until(s->r, s->planned, s->spin)) {
        int32_t pos[CS_AXES];
        exec_pos(s, pos);
        if (!inputs_trip(s, pos))
            s->oc = CS_GPIO_RUN_STOPPED;
        return false;
    }
    int64_t at = s->out.step_mask ? s->planned + s->pulse : s->planned;
    if (cs_gpio_io_set(s->io, s->all_dir, want, at, &s->t_dir) != 0) {
        s->ok = false;
        return false;
    }
    s->dir = want;
    return true;
}

/* Held at rest for a pause: waits (in sleep slices) for the resume, then loads the next segment
 * with the ramp back up (cs_hold) and shifts the plan to start again START_LEAD_NS from now.
 * false when the run ends instead (a hold or stop while paused, or nothing left to run). */
static bool pause_wait(stepper_run_t *s)
{
    cs_gpio_run_t *r = s->r;
    if (s->next >= s->o->nsegs) { /* the hold came too late to stop anything */
        s->oc = CS_GPIO_RUN_DONE;
        return false;
    }
    __atomic_store_n(&r->paused, 1, __ATOMIC_RELEASE);
    while (__atomic_load_n(&r->pause, __ATOMIC_ACQUIRE) && load_hold(r) == 0) {
        struct timespec ts = {0, SLEEP_SLICE_NS};
        nanosleep(&ts, NULL);
    }
    __atomic_store_n(&r->paused, 0, __ATOMIC_RELEASE);
    int h = load_hold(r);
    if (h != 0) {
        s->oc = h >= 2 ? CS_GPIO_RUN_STOPPED : CS_GPIO_RUN_HELD;
        return false;
    }
    cs_hold_set(&s->hold, false);
    if (!feed_next(s, true))
        return false;
    cs_stepper_tick(s->st, &s->out); /* the kick: loads the segment, no step */
    int64_t now = cs_gpio_io_now_ns();
    s->shift = now + START_LEAD_NS - (r->t0_ns + ticks_to_ns(s->vt, s->hz));
    uint32_t want = dir_lines(s->o, s->out.dir_mask);
    if (want != s->dir) {
        s->ok = cs_gpio_io_set(s->io, s->all_dir, want, now, &s->t_dir) == 0;
        s->dir = want;
    }
    return s->ok && s->out.next_ticks != 0;
}

/* The hold, pause and stop requests: false when the run ends here. */
static bool step_requests(stepper_run_t *s)
{
    cs_gpio_run_t *r = s->r;
    int32_t pos[CS_AXES];
    exec_pos(s, pos);
    if (inputs_trip(s, pos)) /* after the last call's steps: stop before the next */
        return false;
    int h = load_hold(r);
    bool p = __atomic_load_n(&r->pause, __ATOMIC_ACQUIRE) != 0;
    if (s->out.next_ticks == 0) { /* the executor ran dry: the end, or a hold at rest */
        if (s->hold.hold && p && h == 0)
            return pause_wait(s);
        s->oc = s->hold.hold ? CS_GPIO_RUN_HELD : CS_GPIO_RUN_DONE;
        return false;
    }
    if (h >= 2) {
        s->oc = CS_GPIO_RUN_STOPPED;
        return false;
    }
    if ((h == 1 || p) && !s->hold.hold)
        cs_hold_set(&s->hold, true);
    else if (h == 0 && !p && s->hold.hold)
        cs_hold_set(&s->hold, false); /* resumed before coming to rest: back up to speed */
    return true;
}

/* One executor call: hold request, refill, tick, lines, progress. false when the run ends. */
static bool step_call(stepper_run_t *s)
{
    cs_gpio_run_t *r = s->r;
    const cs_gpio_run_opts_t *o = s->o;
    if (!step_requests(s))
        return false;
    s->vt += s->out.next_ticks;
    s->planned = r->t0_ns + s->shift + ticks_to_ns(s->vt, s->hz);
    /* one segment queued behind the running one is enough (this thread refills before every
     * call); once the hold has come to rest, nothing more is fed */
    if (s->next < o->nsegs && cs_stepper_free(s->st) == CS_STEPPER_RING) {
        (void)feed_next(s, true);
        if (s->oc != CS_GPIO_RUN_DONE)
            return false;
    }
    int32_t before[CS_AXES]; /* the executor's position without this call's steps */
    for (unsigned i = 0; i < CS_AXES; i++)
        before[i] = cs_stepper_position(s->st, i);
    cs_stepper_tick(s->st, &s->out);
    if (s->out.step_mask && !emit_steps(s, before))
        return false;
    if (!emit_dir(s))
        return false;
    /* segments popped by the executor; all but the running one are done */
    size_t popped = s->pushed - (CS_STEPPER_RING - cs_stepper_free(s->st));
    size_t done = popped - (s->out.next_ticks != 0 && popped > 0 ? 1u : 0u);
    __atomic_store_n(&r->executed, o->first + done, __ATOMIC_RELEASE);
    return true;
}

/* Leaves the lines safe (every STEP inactive, ENABLE off, DIR as it is) and the results. */
static void step_end(stepper_run_t *s)
{
    cs_gpio_run_t *r = s->r;
    const cs_gpio_run_opts_t *o = s->o;
    if (!s->ok) {
        s->oc = CS_GPIO_RUN_IO_ERROR;
        r->io_errno = errno;
    }
    cs_gpio_io_set(s->io, s->all_step | s->en, 0, cs_gpio_io_now_ns(), &r->t_end_ns);
    r->ticks = s->vt;
    for (unsigned i = 0; i < CS_AXES; i++)
        r->pos[i] = s->unsent ? s->unsent_pos[i] : cs_stepper_position(s->st, i);
    if (s->oc == CS_GPIO_RUN_DONE || s->oc == CS_GPIO_RUN_HELD) {
        size_t popped = s->pushed - (CS_STEPPER_RING - cs_stepper_free(s->st));
        __atomic_store_n(&r->executed, o->first + popped, __ATOMIC_RELEASE);
        if (o->first + popped >= o->nsegs) /* a hold that came too late to stop anything */
            s->oc = CS_GPIO_RUN_DONE;
    }
    r->outcome = s->oc;
    __atomic_store_n(&r->finished, 1, __ATOMIC_RELEASE);
}

static void *thread_main(void *arg)
{
    stepper_run_t s;
    memset(&s, 0, sizeof s);
    s.r = arg;
    s.o = &s.r->o;
    prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL); /* ns-precise sleeps without SCHED_FIFO */
    step_begin(&s);
    while (s.ok && s.oc == CS_GPIO_RUN_DONE && step_call(&s))
        ;
    step_end(&s);
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

void cs_gpio_run_pause(cs_gpio_run_t *r, bool on)
{
    __atomic_store_n(&r->pause, on ? 1 : 0, __ATOMIC_RELEASE);
}

bool cs_gpio_run_paused(const cs_gpio_run_t *r)
{
    return __atomic_load_n(&r->paused, __ATOMIC_ACQUIRE) != 0;
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
