/* cs_gpio_pwm: software PWM for the GPIO link's pen servo (see cs_gpio_pwm.h). */
#include "cs_gpio_pwm.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

/* Sleeps in slices so a stop request is seen within this long. */
#define SLEEP_SLICE_NS 5000000

/* Waits until CLOCK_MONOTONIC reaches t: clock_nanosleep to spin before it, then spins. */
static void wait_until(int64_t t, int64_t spin)
{
    for (;;) {
        int64_t now = cs_gpio_io_now_ns();
        if (t - now <= spin)
            break;
        int64_t wake = t - spin;
        if (wake - now > SLEEP_SLICE_NS)
            wake = now + SLEEP_SLICE_NS;
        struct timespec ts = {(time_t)(wake / 1000000000), (long)(wake % 1000000000)};
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL);
    }
    while (cs_gpio_io_now_ns() < t) {
#if defined(__x86_64__) || defined(__i386__)
        __builtin_ia32_pause();
#endif
    }
}

/* The width in force once `executed` segments are done: the last event before segment index
 * `executed` (0-based: the one running), 0 before the first event (no pulse). */
static uint16_t width_now(const cs_gpio_pwm_t *p, size_t executed, size_t *ev, uint16_t w)
{
    for (; *ev < p->npens && p->pens[*ev].seg <= executed; (*ev)++)
        w = p->pens[*ev].pulse_us;
    return w;
}

/* One edge at planned time t: sets the line, keeps the lateness. false when the set failed. */
static bool edge(cs_gpio_pwm_t *p, int64_t t, uint32_t level)
{
    int64_t got;
    wait_until(t, p->spin_ns);
    if (cs_gpio_io_set(p->io, 1u, level, t, &got) != 0) {
        p->io_errno = errno != 0 ? errno : EIO;
        return false;
    }
    if (got - t > p->late_max_ns)
        p->late_max_ns = got - t;
    return true;
}

static void *thread_main(void *arg)
{
    cs_gpio_pwm_t *p = arg;
    size_t ev = 0;
    uint16_t w = 0;
    unsigned since = 0;                        /* pulses made at width w */
    int64_t t = cs_gpio_io_now_ns() + 1000000; /* the first period starts 1 ms from now */
    for (;;) {
        uint16_t nw = width_now(p, cs_gpio_run_executed(p->run), &ev, w);
        if (nw != w) {
            w = nw;
            since = 0;
        }
        /* asked to end (the job is over: its progress is final): once the last width in force
         * has gone out CS_GPIO_PWM_TAIL times, so the servo gets there however late this
         * thread ran */
        if (__atomic_load_n(&p->stop, __ATOMIC_ACQUIRE) && (w == 0 || since >= CS_GPIO_PWM_TAIL))
            break;
        if (w != 0) {
            if (!edge(p, t, 1u) || !edge(p, t + (int64_t)w * 1000, 0u))
                break;
            p->periods++;
            since++;
        }
        t += CS_GPIO_PWM_PERIOD_NS;
        wait_until(t - CS_GPIO_PWM_PERIOD_NS / 2, 0); /* half a period before the next rise */
    }
    int64_t got;
    cs_gpio_io_set(p->io, 1u, 0u, cs_gpio_io_now_ns(), &got); /* left low */
    return NULL;
}

int cs_gpio_pwm_start(cs_gpio_pwm_t *p, cs_gpio_io_t *io, const cs_gpio_run_t *run,
                      const cs_motion_pen_t *pens, size_t npens, int64_t spin_ns)
{
    *p = (cs_gpio_pwm_t){.io = io, .run = run, .pens = pens, .npens = npens, .spin_ns = spin_ns};
    int rc = pthread_create(&p->th, NULL, thread_main, p);
    p->started = rc == 0;
    return rc;
}

void cs_gpio_pwm_stop(cs_gpio_pwm_t *p)
{
    if (!p->started || p->joined)
        return;
    __atomic_store_n(&p->stop, 1, __ATOMIC_RELEASE);
    pthread_join(p->th, NULL);
    p->joined = true;
}

bool cs_gpio_pwm_report(FILE *f, const cs_gpio_pwm_t *p)
{
    bool ok = p->started && p->io_errno == 0;
    fprintf(f, "stream: pen servo: %llu pulses at 50 Hz (software PWM), edges late by max %.1f us",
            (unsigned long long)p->periods, (double)p->late_max_ns / 1000.0);
    if (!ok)
        fprintf(f, "; FAILED: %s", p->io_errno ? strerror(p->io_errno) : "no thread");
    fputc('\n', f);
    return ok;
}

int cs_gpio_pwm_open(cs_gpio_io_t *io, const char *chip, bool record, int offset,
                     double seconds, char *err, size_t errlen)
{
    cs_gpio_lines_t l = {0};
    l.n = 1;
    l.offset[0] = offset >= 0 ? (unsigned)offset : 0;
    snprintf(l.name[0], sizeof l.name[0], "pen");
    if (!record)
        return cs_gpio_io_open_chip(io, chip, &l, err, errlen) == 0 ? 0 : -1;
    /* two set calls a period, a margin for the start and the end */
    double periods = (seconds > 0 ? seconds : 0) * (1e9 / CS_GPIO_PWM_PERIOD_NS) + 100;
    if (cs_gpio_io_open_recorder(io, &l, (size_t)(2 * periods)) == 0)
        return 0;
    snprintf(err, errlen, "--gpio record: out of memory for the pen's record");
    return -1;
}
