/* cs_gpio_pwm: the pen servo of the GPIO link ([pen] mode = servo, [gpio] pen = OFFSET). Owns a
 * thread of its own that makes the 50 Hz RC-servo pulse train on one line by software PWM: at
 * each 20 ms period boundary (absolute deadlines on CLOCK_MONOTONIC, sleep then spin as the step
 * thread does) the line rises, and falls after the pulse width in force. The width follows the
 * job: the pen event before segment k (cs_motion_pen_t) is in force from the period that starts
 * once the step thread (cs_gpio_run) has executed the segments before k -- at most one period
 * (20 ms) after the settle wait of that event began, which settle_ms must cover. The line is
 * its own request (its own cs_gpio_io_t), so the two threads never share a line handle.
 * Jitter: the wake-up latency of the host beyond the spin margin (docs/gpio.md). Host only. */
#ifndef CS_GPIO_PWM_H
#define CS_GPIO_PWM_H

#include <pthread.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "cs_gpio_io.h"
#include "cs_gpio_run.h"
#include "cs_motion.h"

#define CS_GPIO_PWM_PERIOD_NS 20000000 /* 50 Hz, the RC-servo frame */
#define CS_GPIO_PWM_TAIL      5        /* pulses of the last width at least, before the end */

typedef struct {
    cs_gpio_io_t *io;              /* opened with the pen line as line 0 */
    const cs_gpio_run_t *run;      /* the step thread whose progress picks the width */
    const cs_motion_pen_t *pens;   /* the job's pen events, in segment order */
    size_t npens;
    int64_t spin_ns;               /* sleep until this long before an edge, then spin */
    pthread_t th;
    bool started;                  /* the thread was created */
    bool joined;                   /* ... and has ended */
    int stop;                      /* main writes 1: end (see cs_gpio_pwm_stop) */
    /* results, read after cs_gpio_pwm_stop */
    uint64_t periods;              /* pulses made */
    int64_t late_max_ns;           /* largest lateness of an edge after its planned time */
    int io_errno;                  /* a set call failed (0: none) */
} cs_gpio_pwm_t;

/* Starts the pulse thread (not real-time scheduled: see docs/gpio.md) on io for the events
 * pens[0..npens) of the job run by run; the first period starts now. Returns 0 or an errno.
 * Main thread only. */
int cs_gpio_pwm_start(cs_gpio_pwm_t *p, cs_gpio_io_t *io, const cs_gpio_run_t *run,
                      const cs_motion_pen_t *pens, size_t npens, int64_t spin_ns);
/* Ends the train once the last width in force (the job's progress is final: call it after
 * cs_gpio_run_join) has gone out CS_GPIO_PWM_TAIL times (100 ms), the line left low, and joins.
 * Main thread only. */
void cs_gpio_pwm_stop(cs_gpio_pwm_t *p);
/* Prints "stream: pen servo: N pulses at 50 Hz (software PWM), edges late by max X us" (and
 * "; FAILED: why") on f, after cs_gpio_pwm_stop. false when the train failed (no thread, or a
 * set call refused). */
bool cs_gpio_pwm_report(FILE *f, const cs_gpio_pwm_t *p);
/* Opens the pen line as io's line 0: [gpio] pen of cfg on chip `chip` (record false), or a
 * recorder (record true) with room for a train of `seconds`. Returns 0, -1 with one sentence in
 * err (the chip refused the line: cs_gpio_io_open_chip's reasons; out of memory). Not
 * real-time: before the threads start. */
int cs_gpio_pwm_open(cs_gpio_io_t *io, const char *chip, bool record, int offset,
                     double seconds, char *err, size_t errlen);

#endif
