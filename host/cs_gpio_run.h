/* cs_gpio_run: the step thread of the GPIO link. Owns a cs_stepper executor (fed and ticked by
 * this one thread, so the ring keeps one writer per index) and turns each call's output into
 * line changes through the cs_gpio_io seam at absolute deadlines on CLOCK_MONOTONIC (planned
 * time = start + ticks / tick_hz): DIR changes, then after the DIR set-up time the STEP lines
 * rise for the call's mask, stay up the pulse width, fall. It asks for SCHED_FIFO and locked
 * memory, holds on request (decelerates along the path, cs_hold, then stops at a segment end) and leaves
 * the lines safe (STEP inactive, ENABLE off). The main thread starts it, polls progress, asks
 * for a hold, joins. Host only. */
#ifndef CS_GPIO_RUN_H
#define CS_GPIO_RUN_H

#include <pthread.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_gpio_cfg.h"
#include "cs_gpio_in.h"
#include "cs_gpio_io.h"
#include "cs_machine.h"
#include "cs_segment.h"
#include "cs_stepper.h"

/* Lateness histogram of the STEP rising edges: bucket k counts edges late by [2^(k-1), 2^k) us
 * (bucket 0: under 1 us); the last bucket is open-ended. */
#define CS_GPIO_LATE_BUCKETS 24

typedef struct {
    const cs_machine_t *m;
    const cs_gpio_cfg_t *cfg; /* pulse, DIR set-up, enable delay, spin, rt_priority */
    cs_gpio_io_t *io;         /* opened; driven only by the step thread until joined */
    int step_line[CS_AXES];   /* io line index of each axis's STEP, -1 = none */
    int dir_line[CS_AXES];    /* io line index of each axis's DIR, -1 = none */
    int enable_line;          /* io line index of ENABLE, -1 = none */
    const cs_segment_t *segs; /* the job's segments (read by the thread while it runs) */
    size_t nsegs;
    size_t first;  /* segments 0..first-1 were executed already (--resume-from) */
    bool realtime; /* ask for SCHED_FIFO (cfg->rt_priority) and mlockall */
    /* inputs (NULL: none), read after every call that stepped and just before every STEP rise:
     * the e-stop active, an input of watch active, one of release inactive, or (hard_limits) a
     * limit switch becoming active stops the steps there (TRIPPED) */
    cs_gpio_in_t *in;
    uint16_t watch, release; /* CS_PROTO_IN_* bits an operation waits for (homing, probe) */
    bool hard_limits;
    int32_t start_pos[CS_AXES]; /* machine position at the start, steps (the recorder's model) */
} cs_gpio_run_opts_t;

typedef enum {
    CS_GPIO_RUN_DONE = 0,        /* every segment executed (also when a hold came too late) */
    CS_GPIO_RUN_HELD = 1,        /* hold: slowed down, stopped at a segment end */
    CS_GPIO_RUN_STOPPED = 2,     /* stop at once (mid-segment) */
    CS_GPIO_RUN_IO_ERROR = 3,    /* a set call failed (io_errno) */
    CS_GPIO_RUN_BAD_SEGMENT = 4, /* the executor refused a segment (bad_segment) */
    CS_GPIO_RUN_TRIPPED = 5,     /* an input stopped the steps at once (trip_code, trip_inputs) */
} cs_gpio_run_outcome_t;

typedef struct {
    cs_gpio_run_opts_t o;
    cs_stepper_t st;
    pthread_t th;
    bool started;
    /* shared: written by one side, read by the other with __atomic loads */
    size_t executed; /* job numbering: segments 1..executed are done (thread writes) */
    int finished;    /* thread writes 1 when the lines are safe and it is about to return */
    int hold;        /* main writes: 1 hold, 2 stop at once */
    int pause;       /* main writes: 1 hold and wait (the job kept), 0 resume */
    int paused;      /* thread writes: 1 while held at rest for a pause */
    /* what real-time features were granted (set by cs_gpio_run_start) */
    int sched_err; /* 0: SCHED_FIFO granted; else errno (-1: not asked) */
    int mlock_err; /* 0: memory locked; else errno (-1: not asked, -2: skipped under ASan) */
    /* results, read after cs_gpio_run_join */
    cs_gpio_run_outcome_t outcome;
    int io_errno;
    size_t bad_segment; /* BAD_SEGMENT: its job number (1-based) */
    int64_t t0_ns;      /* planned time of executor tick 0 (CLOCK_MONOTONIC) */
    int64_t t_end_ns;   /* when the lines were left safe */
    uint64_t ticks;     /* executor ticks run */
    uint64_t steps[CS_AXES];
    int32_t pos[CS_AXES]; /* executor position, steps (the steps on the lines) */
    uint8_t trip_code;    /* TRIPPED: 0 the watched input, else the cs_proto_alarm_t */
    uint16_t trip_inputs; /* TRIPPED: the input bits at the trip */
    uint16_t inputs;      /* the input bits last read */
    uint64_t rises;       /* STEP rising edges (calls with a step) */
    int64_t late_max_ns;  /* largest lateness of a STEP rise after its planned time */
    double late_sum_ns;
    uint64_t late_hist[CS_GPIO_LATE_BUCKETS];
} cs_gpio_run_t;

/* Starts the step thread on opts (copied). With opts->realtime: mlockall(MCL_CURRENT |
 * MCL_FUTURE) and a SCHED_FIFO thread; when refused, records the errno in sched_err /
 * mlock_err and runs anyway (the caller warns). Returns 0, or an errno when the thread cannot be
 * created or the executor refuses the machine. Not real-time; main thread only. */
int cs_gpio_run_start(cs_gpio_run_t *r, const cs_gpio_run_opts_t *opts);
/* Asks the thread to hold (level 1: decelerate along the job's own path to rest with the
 * core's ramp, cs_hold, every axis within its max_accel, then stop at a segment end) or to stop
 * at once (2). Any thread. */
void cs_gpio_run_hold(cs_gpio_run_t *r, int level);
/* Pauses (on: decelerate as for a hold, then wait at rest with ENABLE on and the job kept) or
 * resumes (off: back up to speed with the core's ramp, the job's time shifted by the pause).
 * A hold or stop requested while paused ends the run (HELD / STOPPED). Any thread. */
void cs_gpio_run_pause(cs_gpio_run_t *r, bool on);
/* True while the thread is at rest for a pause (the hold confirmed). Any thread. */
bool cs_gpio_run_paused(const cs_gpio_run_t *r);
/* Segments executed so far, job numbering (includes opts->first). Any thread. */
size_t cs_gpio_run_executed(const cs_gpio_run_t *r);
/* True once the thread has left the lines safe. Any thread. */
bool cs_gpio_run_finished(const cs_gpio_run_t *r);
/* Waits for the thread (and undoes mlockall). Main thread only. */
void cs_gpio_run_join(cs_gpio_run_t *r);
/* The lateness under which a fraction q (0..1) of the STEP rises fall, from the histogram: an
 * upper bound within a factor 2 (bucket edges), ns. */
int64_t cs_gpio_run_late_quantile(const cs_gpio_run_t *r, double q);
/* Set-call capacity a recorder needs for n segments: two per call with steps (bounded by the
 * sum of |steps| over axes), one per DIR change (at most one per segment), and a few more. */
size_t cs_gpio_run_record_capacity(const cs_segment_t *s, size_t n);

#endif
