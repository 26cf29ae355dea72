/* cs_grbl_dev: the device side of the Grbl front end. A worker thread takes planned chunks (step
 * segments, cs_stream_job_t) and dwells from a short queue and runs each through cs_stream_run on
 * the serial link, one session per chunk (as the daemon runs one per job), or through
 * cs_grbl_link on Modbus or GPIO (cs_joblink); feed hold / resume and cancel reach the running
 * chunk through the pause and interrupt flags every link polls. It keeps what the device last
 * reported (position in steps, state; on GPIO the step thread's position) for the status
 * report. Host only. */
#ifndef CS_GRBL_DEV_H
#define CS_GRBL_DEV_H

#include <pthread.h>
#include <signal.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_feedrate.h"
#include "cs_grbl_link.h"
#include "cs_machine.h"
#include "cs_proto.h"
#include "cs_serial.h"
#include "cs_stream.h"

/* Items waiting behind the running one (the planner's look-ahead is within a chunk; this only
 * keeps the link busy while the next chunk is read). */
#define CS_GRBL_DEV_QUEUE 4

typedef struct {
    bool dwell;          /* a G4: wait dwell_s seconds; else run job */
    bool jog;            /* a $J= move (cancellable with 0x85) */
    double dwell_s;
    int ov_feed, ov_rapid; /* the feed / rapid override (%) the job was planned at (0: 100) */
    cs_stream_job_t job;   /* owned by the queue once pushed */
} cs_grbl_item_t;

/* What the status report needs, copied under the lock. */
typedef struct {
    bool busy;       /* an item is running */
    bool busy_jog;   /* ... and it is a jog */
    size_t queued;   /* items waiting */
    bool have_pos;   /* the device has reported a position */
    int32_t pos[CS_PROTO_AXES_MAX]; /* steps, from its last STATUS */
    uint8_t dev_state;              /* CS_PROTO_STATE_*, 0xFF: none yet */
    double speed_mm_min;            /* FS: the device's speed over a short window (cs_feedrate) */
    bool failed;                    /* a chunk ended other than done or cancelled */
    char why[200];                  /* ... why */
    unsigned cancelled;             /* runs ended by cancel (interrupt) so far */
    /* from the device's EVENTs (docs/protocol.md, EVENT) */
    bool have_inputs;
    uint16_t inputs;                      /* CS_PROTO_IN_* bits of the last EVENT */
    unsigned alarms;                      /* ALARM events so far */
    uint8_t alarm_code;                   /* the last one's (Grbl's ALARM:N numbering) */
    unsigned probes;                      /* PROBE events so far */
    bool probe_contact;                   /* the last one touched */
    int32_t probe_pos[CS_PROTO_AXES_MAX]; /* ... there (steps) */
} cs_grbl_dev_snap_t;

typedef struct {
    pthread_t th;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    cs_serial_t *ser;     /* the serial link, or NULL: */
    cs_grbl_link_t *link; /* Modbus or GPIO (&lk) */
    cs_grbl_link_t lk;
    volatile sig_atomic_t link_stop; /* cancel: a GPIO control command stops at once */
    uint8_t axes;
    uint32_t tick_hz;
    int32_t steps_per_mm[CS_PROTO_AXES_MAX]; /* Q15.16, for the speed */
    uint32_t bits_per_s;                     /* link timing (0: a pty) */
    cs_grbl_item_t q[CS_GRBL_DEV_QUEUE];
    size_t head, n;
    bool quit, started;
    bool req_cancel, req_hold; /* asked for (under mu): cancel the running item, feed hold */
    /* what cs_stream_run polls (worker thread only: copied from req_* under mu when a chunk
     * starts and at each progress call, ten times a second, so a hold or cancel takes effect
     * within ~0.1 s and no flag is shared without the lock) */
    volatile sig_atomic_t run_interrupt, run_pause;
    int req_ov[3];                /* feed, rapid, spindle override in force (%), under mu */
    int cur_ov[2];                /* the running job's planned feed, rapid (%; worker only) */
    cs_proto_override_t run_ov;   /* what cs_stream_run sends (worker thread only, as above) */
    cs_stream_result_t *cur;         /* the running chunk's result (worker thread only) */
    cs_feedrate_t fr;                /* timed positions, for FS (under mu) */
    cs_grbl_dev_snap_t s;
} cs_grbl_dev_t;

/* Starts the worker on the open port ser for machine m (axes, tick rate, steps/mm), link timing
 * for a line of bits_per_s (0: a pty). CS_ERR_STATE when the thread cannot start. */
cs_err_t cs_grbl_dev_start(cs_grbl_dev_t *d, cs_serial_t *ser, const cs_machine_t *m,
                           uint32_t bits_per_s);
/* Starts the worker on the Modbus or GPIO link of cfg (cs_grbl_link_start: where the machine
 * stands, an alarm its GPIO state keeps, counted as the device's) for machine m with [homing]
 * ctl; m, ctl and cfg's strings outlive d. CS_EXIT_OK, or an exit status with one sentence in why
 * (CS_EXIT_INTERNAL: the thread). */
int cs_grbl_dev_start_link(cs_grbl_dev_t *d, const cs_joblink_cfg_t *cfg, const cs_machine_t *m,
                           const cs_ctlcfg_t *ctl, char *why, size_t cap);
/* True when the device's link carries messages of type t (the serial link: all). */
bool cs_grbl_dev_can(const cs_grbl_dev_t *d, uint8_t t);
/* The link's name in messages: "serial", "Modbus", "GPIO". */
const char *cs_grbl_dev_kind(const cs_grbl_dev_t *d);
/* Queues it (taking its job); false when the queue is full (it is then not taken). */
bool cs_grbl_dev_push(cs_grbl_dev_t *d, cs_grbl_item_t *it);
/* True when the queue can take need more items. */
bool cs_grbl_dev_room(cs_grbl_dev_t *d, size_t need);
/* Drops every waiting item; when only_jogs, only if everything queued and running is a jog.
 * Cancels the running item (decelerating hold, then abort), waits until it has stopped and ends
 * the feed hold. False when only_jogs and something is not a jog (then nothing is done). */
bool cs_grbl_dev_cancel(cs_grbl_dev_t *d, bool only_jogs);
/* The overrides in force (Grbl's percentages): the running job gets them within ~0.1 s as an
 * OVERRIDE relative to what it was planned at (cs_grbl_item_t.ov_*), the spindle's absolute. */
void cs_grbl_dev_override(cs_grbl_dev_t *d, int feed, int rapid, int spindle);
/* Feed hold on (true) or off. */
void cs_grbl_dev_hold(cs_grbl_dev_t *d, bool on);
/* Clears the failure (Grbl's $X). */
void cs_grbl_dev_clear(cs_grbl_dev_t *d);
/* True when nothing is queued or running. */
bool cs_grbl_dev_idle(cs_grbl_dev_t *d);
/* Copies the state. */
void cs_grbl_dev_snap(cs_grbl_dev_t *d, cs_grbl_dev_snap_t *s);
/* Cancels everything, ends the worker and frees the queue. */
void cs_grbl_dev_stop(cs_grbl_dev_t *d);

#endif
