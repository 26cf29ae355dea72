/* cs_stream: the host's streaming engine. Holds a whole planned job as wire messages (SEGMENT
 * step segments, or CURVE cubic Béziers the device interpolates), connects to the device through
 * cs_link over a cs_serial port, checks its HELLO, keeps the window and the credits full, follows
 * the device's STATUS to know the last executed message, and stops at once on a device reset
 * (new boot id), a closed link, a device ERROR or Ctrl-C (HOLD, then ABORT). Host only. */
#ifndef CS_STREAM_H
#define CS_STREAM_H

#include <signal.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "cs_link.h"
#include "cs_motion.h"
#include "cs_path.h"
#include "cs_proto.h"
#include "cs_serial.h"

typedef enum {
    CS_STREAM_SEGMENTS = 0, /* the host plans; the device executes step segments */
    CS_STREAM_CURVES = 1,   /* the device traces cubic Béziers with the core and plans them */
} cs_stream_mode_t;

/* The job: every message, in order (numbered 1..n in reports and --resume-from). */
typedef struct {
    cs_proto_msg_t *v;
    size_t n, cap;
    cs_stream_mode_t mode;
    size_t exact; /* curves mode: elements sent exactly (lines, quadratics elevated, cubics) */
    size_t approximated; /* curves mode: elements (arcs, other rationals, degree > 3) sent as
                          * cubic Hermite pieces within tol/4 */
} cs_stream_job_t;

void cs_stream_job_init(cs_stream_job_t *j, cs_stream_mode_t mode);
void cs_stream_job_free(cs_stream_job_t *j);
/* Appends step segments as SEGMENT messages. CS_ERR_FULL out of memory, CS_ERR_RANGE for a
 * segment the protocol cannot carry. */
cs_err_t cs_stream_job_add_segments(cs_stream_job_t *j, const cs_segment_t *s, size_t n);
/* Appends one message as it is (HOME, JOG, PROBE, SPINDLE, UNLOCK: docs/protocol.md).
 * CS_ERR_RANGE (or the encoder's error) for a message the protocol cannot carry, CS_ERR_FULL out
 * of memory. */
cs_err_t cs_stream_job_add_msg(cs_stream_job_t *j, const cs_proto_msg_t *m);
/* Appends a plan's segments with its servo pen events as PEN messages in their place (a pen
 * event before segment k goes right before that segment's SEGMENT; docs/protocol.md, PEN).
 * Errors as cs_stream_job_add_segments (CS_ERR_RANGE: a pulse width outside 400..2600 us). */
cs_err_t cs_stream_job_add_motion(cs_stream_job_t *j, const cs_motion_segs_t *s);
/* Appends every element of path as CURVE messages at the element's own feed (G-code F), else
 * at feed (mm/s Q15.16, > 0); a rapid element (G0) gets INT32_MAX, which the device's planner
 * limits to each axis's max rate (its rapid, as `curvestep plan` does). Lines and
 * quadratics degree-elevated to cubics (exact up to 1 LSB of rounding), cubics as they are;
 * rational elements (arcs) and degrees above 3 are approximated, in double, by cubic Hermite
 * pieces that match the exact curve's end points and end tangents, halved until every piece is
 * within max(tol/4, 2 LSB) of the exact curve (parametric distance, 64 samples). On error
 * *diag names the element. The device travels in a straight rapid move to a curve's P0 when it
 * is not already there (the rule `curvestep plan` follows). */
cs_err_t cs_stream_job_add_path(cs_stream_job_t *j, const cs_path_t *path, int32_t feed,
                                cs_pos_t tol, cs_path_diag_t *diag);

typedef enum {
    CS_STREAM_DONE = 0,         /* every message executed (device idle, last one reported) */
    CS_STREAM_NO_DEVICE = 1,    /* no answer to the connection or no HELLO in time */
    CS_STREAM_INCOMPATIBLE = 2, /* HELLO: other protocol version, axes, tick rate or caps */
    CS_STREAM_RESET = 3,        /* the device restarted mid-job (new boot id) */
    CS_STREAM_CLOSED = 4,       /* the line closed or the device stopped answering */
    CS_STREAM_DEVICE_ERROR = 5, /* the device sent ERROR about a message (then ABORT was sent) */
    CS_STREAM_INTERRUPTED = 6,  /* the user asked to stop: HOLD, then ABORT */
} cs_stream_outcome_t;

typedef struct {
    cs_serial_t *ser;
    uint8_t axes; /* the machine: HELLO must announce the same */
    uint32_t tick_hz;
    size_t resume_from; /* messages 1..resume_from were executed already: start after them */
    bool resume_ask;    /* --resume: ask the device (QUERY) where this job stands, go on from
                         * the last message it received; refused when it does not know the job */
    bool set_pos;       /* --position: with resume_from, SETPOS the device's position first */
    int32_t pos[CS_PROTO_AXES_MAX]; /* set_pos: the machine's position, steps */
    volatile sig_atomic_t *interrupt; /* > 0: stop (HOLD, ABORT); >= 2: give up at once */
    volatile sig_atomic_t *pause;     /* NULL: never; != 0: HOLD (queue kept), back to 0: RESUME */
    FILE *progress;                   /* NULL: none; else progress bar (tty) or lines */
    bool progress_tty;
    cs_link_cfg_t link; /* in microseconds (cs_serial_now_us) */
    uint32_t hello_ms;  /* wait this long for the connection and HELLO */
    uint32_t status_ms; /* after the last ACK, wait this long for the final STATUS */
    bool quiet_hello;
    /* NULL: none; else called with every EVENT the device sends (alarm, probe contact, axis
     * homed, inputs: docs/protocol.md), before the ERROR an alarm is followed by */
    void (*on_event)(void *ctx, const cs_proto_event_t *ev);
    void *event_ctx;
    /* interrupt < 2: send JOG_CANCEL (decelerate to rest, drop the rest, back to IDLE) instead
     * of HOLD then ABORT (a job of jogs) */
    bool jog_cancel;
    /* NULL: none; else the overrides the running job should have (docs/protocol.md, OVERRIDE):
     * read every pass, sent (OVERRIDE, acknowledged, answered by a STATUS) after the SETPOS and
     * again whenever it changes. Change it only on the thread that runs cs_stream_run (from the
     * progress stream's write, as cs_grbl_dev does), like the pause flag it is polled as. */
    const cs_proto_override_t *override;
} cs_stream_opts_t;

typedef struct {
    cs_stream_outcome_t outcome;
    size_t sent;      /* messages handed to the link (job numbering: last one's number) */
    size_t delivered; /* acknowledged by the device */
    size_t executed;  /* last message the device reported executed (job numbering) */
    cs_proto_hello_t hello;
    uint32_t old_boot, new_boot; /* RESET */
    uint16_t unacked;            /* RESET: messages sent whose fate is unknown */
    cs_proto_error_t dev_error;  /* DEVICE_ERROR */
    size_t dev_error_msg;        /* DEVICE_ERROR: job number of the message it is about (0: ?) */
    uint8_t dev_state;           /* last STATUS */
    int32_t dev_pos[CS_PROTO_AXES_MAX];
    bool dev_timed;   /* dev_tick is the device's clock when dev_pos was sampled (protocol 3's
                       * STATUS; the GPIO link's step thread); false: only the host's timing */
    uint32_t dev_tick; /* ... executor ticks (hello.tick_hz a second), wraps at 2^32 */
    size_t resume_from;   /* the run started after this message (o->resume_from, or the
                           * device's answer to --resume) */
    size_t resume_done;   /* --resume: the last message the device had finished then */
    bool refused;         /* a resume refused at the start (why says what to do), nothing sent */
    bool numbered;        /* the device numbers this job's messages: executed is its word */
    size_t dev_recv;      /* last STATUS: the last message of the job the device received */
    uint32_t job_id;      /* cs_stream_job_id of the job */
    cs_link_stats_t link;
    uint64_t bytes_out, bytes_in;
    double wall_s;   /* from the connection to the end */
    double stream_s; /* from the first message sent to the last one executed */
    char why[320];   /* one sentence for NO_DEVICE / INCOMPATIBLE / CLOSED / RESET */
    const char *what; /* the link's own sentence for the outcome (a static string; NULL:
                       * cs_stream_outcome_text): the GPIO link's "held, then stopped ..." */
    bool mid_message; /* stopped inside message `executed` + 1: the machine is past the last
                       * executed one, so no --resume-from hint (GPIO: stop at once) */
    bool alarm;               /* the device reported an ALARM EVENT (hard limit, e-stop, ...) */
    cs_proto_event_t alarm_ev; /* ... the last one: code, inputs, where it stopped */
    size_t alarm_msg;          /* ... during job message no. (executed + 1 then) */
} cs_stream_result_t;

/* Defaults: link timing for a pty at memory speed (cs_linktime_link(.., 0, 1000000)), keepalive
 * 500 ms, HELLO and the final STATUS each within 30 s (the link's give-up time). */
void cs_stream_opts_default(cs_stream_opts_t *o, cs_serial_t *ser, uint8_t axes, uint32_t tick_hz);
/* The device's identity (HELLO, or the Modbus status block) against the machine and the job:
 * true with a sentence in why when the axes, the tick rate (segments only) or the capabilities
 * do not match; the version is each link's own check. */
bool cs_stream_hello_mismatch(const cs_proto_hello_t *h, uint8_t axes, uint32_t tick_hz,
                              cs_stream_mode_t mode, char *why, size_t cap);
/* The job's name on the device (SETPOS, STATUS): FNV-1a 32 over every message as encoded, never
 * 0. A different file, mode or plan gives another id, so --resume refuses it. */
uint32_t cs_stream_job_id(const cs_stream_job_t *job);
/* Link timing for a line of bits_per_s (0: a pty at memory speed) in cs_serial_now_us
 * microseconds: the core's cs_linktime_link (docs/protocol.md 3.6), the one every end computes
 * (below 5 bits/s the timeout does not fit 32 bits: c is left as it was). */
void cs_stream_link_timing(cs_link_cfg_t *c, uint32_t bits_per_s);
/* Streams job messages resume_from+1..n (the port is switched to lossy writes: a peer that
 * stops reading never blocks the host). Always fills *r; returns CS_OK when it ran to an
 * outcome (see r->outcome), CS_ERR_ARG for bad options, CS_ERR_IO for a write error. */
cs_err_t cs_stream_run(const cs_stream_job_t *job, const cs_stream_opts_t *o,
                       cs_stream_result_t *r);
/* The progress display every link shares: on a terminal (tty) a bar redrawn at most ten times
 * a second, else one plain line a second; final: the last one, with the average rate since
 * p->t_first (set it when the first message goes out). n messages in the job, ex executed,
 * sent handed to the link, resume_from skipped, retx retransmissions, what "segments" or
 * "curves". Start with p zeroed; f NULL prints nothing. */
typedef struct {
    double t_first;         /* cs_serial_now_s() when streaming started */
    double last;            /* last display */
    double rate_t, rate_ex; /* for the speed estimate */
    double rate;            /* messages per second */
} cs_stream_progress_t;
void cs_stream_progress(cs_stream_progress_t *p, FILE *f, bool tty, bool final, size_t n, size_t ex,
                        size_t sent, size_t resume_from, unsigned retx, const char *what);
/* "stream: device held at E of N WHAT": the line every link prints on the progress stream
 * once the device confirmed a pause's hold (the daemon's `status` shows "(held)" from then).
 * f NULL prints nothing. */
void cs_stream_progress_held(FILE *f, size_t ex, size_t n, const char *what);
/* One line for an outcome ("device reset", ...). */
const char *cs_stream_outcome_text(cs_stream_outcome_t oc);
/* r->what, else cs_stream_outcome_text(r->outcome). */
const char *cs_stream_result_text(const cs_stream_result_t *r);

#endif
