/* cs_proto: the messages of the wire protocol and their byte layout (docs/protocol.md,
 * "Messages"): plain C structs <-> payload bytes, little-endian, every field range-checked both
 * ways. Owns the message type numbers, which types are sequenced (delivered reliably by cs_link)
 * and which take a slot of the device's motion queue (spend a flow-control credit). */
#ifndef CS_PROTO_H
#define CS_PROTO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_err.h"
#include "cs_fixed.h"
#include "cs_segment.h"

/* 2: STATUS carries the job's confirmed progress (flags, job id, done, received); QUERY and
 * SETPOS (issue 17: resume from what the device did). 3: STATUS carries the executor's tick of
 * its position sample (issue 21: the speed a host reports is the device's, not its own timing
 * of arrivals). A host takes a device of CS_PROTO_VERSION_MIN..CS_PROTO_VERSION: protocol 2's
 * STATUS is the same without the tick (CS_PROTO_LEN_STATUS2, flag CS_PROTO_STATUS_TICK clear). */
#define CS_PROTO_VERSION     3
#define CS_PROTO_VERSION_MIN 2
/* Axes a hello or a status may announce (x, y, z, a: cs_machine.h's CS_AXES). */
#define CS_PROTO_AXES_MAX 4

/* Message types (payload byte 0). 0x01..0x0F: link control, not sequenced (cs_link answers
 * them itself); 0x10..0x1F: device to host; 0x20..0x2F: host to device. */
typedef enum {
    CS_PROTO_ACK = 0x01,     /* next expected sequence + credits + boot id + ping echo */
    CS_PROTO_PING = 0x02,    /* asks the peer for an ACK echoing a nonce */
    CS_PROTO_HELLO = 0x10,   /* device identity and capacity, first message after boot */
    CS_PROTO_STATUS = 0x11,  /* state, queue fill, position in steps, last executed sequence */
    CS_PROTO_ERROR = 0x12,   /* a cs_err_t code about a message */
    CS_PROTO_EVENT = 0x13,   /* alarm, probe contact, axis homed, inputs changed (+ position) */
    CS_PROTO_SEGMENT = 0x20, /* step segment (cs_segment_t): ticks + signed steps per axis */
    CS_PROTO_CURVE = 0x21,   /* cubic Bezier, 4 control points + feed, traced on the device */
    CS_PROTO_HOLD = 0x22,    /* feed hold: decelerate and stop, keep the queue */
    CS_PROTO_RESUME = 0x23,  /* resume after hold */
    CS_PROTO_ABORT = 0x24,   /* stop now and flush the queue */
    CS_PROTO_PEN = 0x25,     /* servo pen pulse width, set between the queued neighbours */
    CS_PROTO_QUERY = 0x2C,   /* asks for a STATUS now (a host that reconnected) */
    CS_PROTO_SETPOS = 0x2D,  /* job id and numbering, and optionally the position in steps */
    CS_PROTO_HOME = 0x26,    /* home one axis on its switch (seek, back off, latch, pull off) */
    CS_PROTO_JOG = 0x27,     /* straight move planned on the device, cancellable */
    CS_PROTO_JOG_CANCEL = 0x28, /* decelerate a jog to rest and drop the queue */
    CS_PROTO_PROBE = 0x29,      /* straight move that stops when the probe input changes */
    CS_PROTO_SPINDLE = 0x2A,    /* spindle / laser output, in queue order */
    CS_PROTO_UNLOCK = 0x2B,     /* leave the alarm state */
    CS_PROTO_OVERRIDE = 0x2E,   /* feed / rapid / spindle overrides, acting on the running motion */
} cs_proto_type_t;

/* Payload sizes in bytes (n = number of axes a status carries, 1..CS_PROTO_AXES_MAX). */
#define CS_PROTO_LEN_ACK       14
#define CS_PROTO_LEN_PING      5
#define CS_PROTO_LEN_HELLO     15
#define CS_PROTO_LEN_STATUS(n)  (28 + 4 * (n)) /* with the tick (protocol 3) */
#define CS_PROTO_LEN_STATUS2(n) (24 + 4 * (n)) /* without it (protocol 2) */
#define CS_PROTO_LEN_ERROR     4
#define CS_PROTO_LEN_SEGMENT   (5 + 4 * CS_AXES)
#define CS_PROTO_LEN_CURVE     53
#define CS_PROTO_LEN_CONTROL   1 /* hold, resume, abort, query */
#define CS_PROTO_LEN_PEN       3
#define CS_PROTO_LEN_SETPOS    (10 + 4 * CS_AXES)
#define CS_PROTO_LEN_EVENT(n)  (6 + 4 * (n))
#define CS_PROTO_LEN_HOME      23
#define CS_PROTO_LEN_JOG       17
#define CS_PROTO_LEN_PROBE     18
#define CS_PROTO_LEN_SPINDLE   9
#define CS_PROTO_LEN_OVERRIDE  7
#define CS_PROTO_LEN_MAX       CS_PROTO_LEN_CURVE

/* ACK flags. */
#define CS_PROTO_ACK_NAK 0x01u /* the receiver saw a gap: resend from next_expected now */
/* HELLO capability bits. */
#define CS_PROTO_CAP_SEGMENTS 0x0001u
#define CS_PROTO_CAP_CURVES   0x0002u
#define CS_PROTO_CAP_CONTROL  0x0004u /* HOME, JOG, PROBE (planned on the device) */
#define CS_PROTO_CAP_SPINDLE  0x0008u /* SPINDLE */
#define CS_PROTO_CAP_ALL                                                                           \
    (CS_PROTO_CAP_SEGMENTS | CS_PROTO_CAP_CURVES | CS_PROTO_CAP_CONTROL | CS_PROTO_CAP_SPINDLE)

/* STATUS flags: what the device knows since its boot. */
#define CS_PROTO_STATUS_JOB 0x01u /* a SETPOS numbered the job: job_id, done, recv are valid */
#define CS_PROTO_STATUS_POS 0x02u /* a SETPOS stated the position: pos is the machine's */
#define CS_PROTO_STATUS_TICK 0x04u /* tick is on the wire (protocol 3; the length says so too) */
#define CS_PROTO_STATUS_ALL (CS_PROTO_STATUS_JOB | CS_PROTO_STATUS_POS | CS_PROTO_STATUS_TICK)
/* SETPOS flags. */
#define CS_PROTO_SETPOS_POS 0x01u /* set the position counters to pos[] (device idle only) */

/* Device states reported by STATUS. */
typedef enum {
    CS_PROTO_STATE_IDLE = 0,    /* queue empty, not moving */
    CS_PROTO_STATE_RUNNING = 1, /* executing the queue */
    CS_PROTO_STATE_HELD = 2,    /* stopped by HOLD, queue kept */
    CS_PROTO_STATE_ABORTED = 3, /* stopped by ABORT, queue flushed */
    CS_PROTO_STATE_FAULT = 4,   /* stopped on an error (see the ERROR messages) */
    CS_PROTO_STATE_ALARM = 5,   /* hard limit, e-stop, homing or probe failure: UNLOCK first */
    CS_PROTO_STATE_HOMING = 6,  /* a HOME is running */
    CS_PROTO_STATE_JOG = 7,     /* a JOG is running */
    CS_PROTO_STATE_COUNT_
} cs_proto_state_t;

typedef struct {
    uint8_t flags;          /* CS_PROTO_ACK_* */
    uint16_t next_expected; /* sequence the sender of the ack expects next */
    uint16_t credits;       /* queue slots free for messages with sequence >= next_expected */
    uint32_t boot_id;       /* boot id of the sender of the ack (a change = reset) */
    uint32_t echo;          /* nonce of the last PING received (0 before any) */
} cs_proto_ack_t;

typedef struct {
    uint32_t nonce;
} cs_proto_ping_t;

typedef struct {
    uint8_t version;     /* CS_PROTO_VERSION of the device, >= 1 */
    uint32_t boot_id;    /* random per boot; a new value means the device restarted */
    uint8_t axes;        /* 1..CS_PROTO_AXES_MAX */
    uint16_t queue_size; /* motion queue slots (credits when empty), >= 1 */
    uint32_t tick_hz;    /* executor ticks per second (segment durations are in ticks), >= 1 */
    uint16_t caps;       /* CS_PROTO_CAP_* bits; unknown bits are refused */
} cs_proto_hello_t;

typedef struct {
    uint8_t state;                  /* cs_proto_state_t */
    uint32_t boot_id;               /* as in HELLO */
    uint16_t queue_fill;            /* queue slots in use */
    uint16_t last_seq;              /* sequence of the last message executed */
    uint8_t axes;                   /* 1..CS_PROTO_AXES_MAX: entries of pos[] on the wire */
    int32_t pos[CS_PROTO_AXES_MAX]; /* position in steps per axis */
    uint8_t flags;                  /* CS_PROTO_STATUS_* */
    uint32_t job_id;                /* the job SETPOS named (0: none since boot) */
    uint32_t done; /* job number of the last queue item the executor finished (0: none) */
    uint32_t recv; /* job number of the last queue item received (done..recv: still to run) */
    /* with CS_PROTO_STATUS_TICK: the executor's clock (port_ticks_now, HELLO tick_hz a second,
     * wraps at 2^32: compare differences) when pos was sampled; else 0 and not on the wire */
    uint32_t tick;
} cs_proto_status_t;

/* SETPOS: from the next queue item on, items are numbered base+1, base+2, ... in job job_id;
 * with CS_PROTO_SETPOS_POS also the executor's position counters become pos[] (steps), which
 * the device accepts only when its queue is empty and its executor idle (else ERROR
 * CS_ERR_STATE). Takes no queue slot. */
typedef struct {
    uint8_t flags;         /* CS_PROTO_SETPOS_* */
    uint32_t job_id;       /* the host's name of the job (a hash of its messages) */
    uint32_t base;         /* job number of the last item executed before this session */
    int32_t pos[CS_AXES];  /* steps per axis (used with CS_PROTO_SETPOS_POS) */
} cs_proto_setpos_t;

typedef struct {
    uint8_t code; /* cs_err_t, CS_ERR_ARG..CS_ERR_COUNT_-1 (never CS_OK or CS_END) */
    uint16_t seq; /* sequence of the message the error is about */
} cs_proto_error_t;

/* Step segments travel as the executor's own cs_segment_t (cs_segment.h): ticks, then
 * steps[0..CS_AXES) (axes the machine lacks carry 0), with its invariant checked both ways:
 * 1 <= ticks <= CS_PROTO_SEGMENT_MAX_TICKS and |steps[i]| <= ticks. */
#define CS_PROTO_SEGMENT_MAX_TICKS ((uint32_t)1 << 24)

typedef struct {
    cs_vec3_t p[4]; /* control points, each coordinate inside CS_POS_LIMIT */
    int32_t feed;   /* mm/s, Q15.16 (cs_machine.h CS_MOTION_ONE = 1 mm/s), > 0 */
} cs_proto_curve_t;

/* PEN: the RC servo's pulse width once the executor has run every queued item before it and
 * before it starts the next one. The settle wait is not in the message: it is the zero-step
 * SEGMENT(s) the host's planner puts after it (cs_motion_pen), timed by the executor's clock. */
#define CS_PROTO_PEN_MIN_US 400  /* RC servo pulse range (host cs_machine_ini: up_us, down_us) */
#define CS_PROTO_PEN_MAX_US 2600

typedef struct {
    uint16_t pulse_us; /* CS_PROTO_PEN_MIN_US..CS_PROTO_PEN_MAX_US */
} cs_proto_pen_t;

/* Input bits (EVENT.inputs, port_inputs_read): set = active, whatever the wiring's polarity. */
#define CS_PROTO_IN_MIN(i)  ((uint16_t)(1u << (i)))        /* switch at axis i's minimum end */
#define CS_PROTO_IN_MAX(i)  ((uint16_t)(1u << (4u + (i)))) /* switch at axis i's maximum end */
#define CS_PROTO_IN_LIMITS  0x00FFu
#define CS_PROTO_IN_PROBE   0x0100u
#define CS_PROTO_IN_ESTOP   0x0200u
#define CS_PROTO_IN_ALL     0x03FFu

typedef enum {
    CS_PROTO_EVENT_ALARM = 1,  /* code: cs_proto_alarm_t; pos: where the machine stopped */
    CS_PROTO_EVENT_PROBE = 2,  /* code: 1 contact, 0 none; pos: the contact position */
    CS_PROTO_EVENT_HOMED = 3,  /* code: the axis; pos: the position set */
    CS_PROTO_EVENT_INPUTS = 4, /* code 0; the inputs changed while idle */
    CS_PROTO_EVENT_COUNT_
} cs_proto_event_kind_t;

/* Alarm codes, numbered as Grbl 1.1's ALARM:N where Grbl has one. */
typedef enum {
    CS_PROTO_ALARM_HARD_LIMIT = 1,
    CS_PROTO_ALARM_SOFT_LIMIT = 2,
    CS_PROTO_ALARM_ABORT_CYCLE = 3,
    CS_PROTO_ALARM_PROBE_INITIAL = 4,
    CS_PROTO_ALARM_PROBE_CONTACT = 5,
    CS_PROTO_ALARM_HOMING_RESET = 6,
    CS_PROTO_ALARM_HOMING_DOOR = 7,
    CS_PROTO_ALARM_HOMING_PULLOFF = 8,
    CS_PROTO_ALARM_HOMING_APPROACH = 9,
    CS_PROTO_ALARM_ESTOP = 10,
    CS_PROTO_ALARM_COUNT_
} cs_proto_alarm_t;

typedef struct {
    uint8_t kind;                   /* cs_proto_event_kind_t */
    uint8_t code;                   /* per kind (docs/protocol.md EVENT) */
    uint16_t inputs;                /* CS_PROTO_IN_* bits, within CS_PROTO_IN_ALL */
    uint8_t axes;                   /* 1..CS_PROTO_AXES_MAX */
    int32_t pos[CS_PROTO_AXES_MAX]; /* steps */
} cs_proto_event_t;

#define CS_PROTO_HOME_MAX 0x01u /* HOME flags: the switch is at the maximum end */
typedef struct {
    uint8_t axis;     /* 0..CS_PROTO_AXES_MAX-1 */
    uint8_t flags;    /* CS_PROTO_HOME_MAX */
    int32_t seek;     /* mm/s Q15.16, > 0 */
    int32_t latch;    /* mm/s Q15.16, > 0 */
    cs_pos_t pulloff; /* mm, 0..CS_POS_LIMIT */
    cs_pos_t search;  /* mm, 1 LSB..CS_POS_LIMIT: the longest seek */
    cs_pos_t home_pos; /* mm, |x| <= CS_POS_LIMIT: position set after the pull-off */
} cs_proto_home_t;

typedef struct {
    cs_vec3_t target; /* machine coordinates, mm, inside CS_POS_LIMIT */
    int32_t feed;     /* mm/s Q15.16, > 0 */
} cs_proto_jog_t;

#define CS_PROTO_PROBE_AWAY     0x01u /* stop when contact is lost (G38.4/.5) */
#define CS_PROTO_PROBE_NO_ERROR 0x02u /* no alarm without contact (G38.3/.5) */
typedef struct {
    cs_vec3_t target;
    int32_t feed;  /* mm/s Q15.16, > 0 */
    uint8_t flags; /* CS_PROTO_PROBE_* */
} cs_proto_probe_t;

typedef enum {
    CS_PROTO_SPINDLE_OFF = 0,
    CS_PROTO_SPINDLE_CW = 1,  /* M3 */
    CS_PROTO_SPINDLE_CCW = 2, /* M4 */
    CS_PROTO_SPINDLE_MODE_COUNT_
} cs_proto_spindle_mode_t;
#define CS_PROTO_SPINDLE_LASER 0x01u /* power scaled by speed, set per segment without a stop */
#define CS_PROTO_SPINDLE_FULL  1000u /* power: duty in 1/1000 */
typedef struct {
    uint8_t mode;   /* cs_proto_spindle_mode_t */
    uint8_t flags;  /* CS_PROTO_SPINDLE_LASER */
    uint16_t power; /* 0..CS_PROTO_SPINDLE_FULL */
    int32_t feed;   /* mm/s Q15.16, >= 0: laser mode's speed of full power (0: constant) */
} cs_proto_spindle_t;

/* OVERRIDE: scales in 1/1000 (CS_PROTO_OVERRIDE_ONE = as planned / as programmed), each
 * 1..CS_PROTO_OVERRIDE_MAX. feed: the speed of the motion the device holds, relative to its
 * planned speed (the host plans what it sends next at its own override: it sends the ratio);
 * rapid: carried for a device that marks rapid segments (this one does not: its step segments
 * carry no class, so every step takes `feed`); spindle: the spindle / laser power relative to
 * the programmed one (absolute). Takes no queue slot, acts at once; SETPOS puts feed and rapid
 * back to ONE, ABORT and a reboot every scale (docs/protocol.md, OVERRIDE). */
#define CS_PROTO_OVERRIDE_ONE 1000u
#define CS_PROTO_OVERRIDE_MAX 20000u
typedef struct {
    uint16_t feed;
    uint16_t rapid;
    uint16_t spindle;
} cs_proto_override_t;

typedef struct {
    uint8_t type; /* cs_proto_type_t */
    union {
        cs_proto_ack_t ack;
        cs_proto_ping_t ping;
        cs_proto_hello_t hello;
        cs_proto_status_t status;
        cs_proto_error_t error;
        cs_segment_t segment;
        cs_proto_curve_t curve;
        cs_proto_pen_t pen;
        cs_proto_setpos_t setpos;
        cs_proto_event_t event;
        cs_proto_home_t home;
        cs_proto_jog_t jog;
        cs_proto_probe_t probe;
        cs_proto_spindle_t spindle;
        cs_proto_override_t override;
    } u; /* none for HOLD, RESUME, ABORT, JOG_CANCEL, UNLOCK, QUERY */
} cs_proto_msg_t;

/* Encode *m into buf[0..cap), *len = bytes written. CS_ERR_UNSUPPORTED for an unknown type,
 * CS_ERR_RANGE for a field outside its range (as listed above), CS_ERR_FULL when cap is too
 * small, CS_ERR_ARG for a NULL pointer. ISR-safe (pure). */
cs_err_t cs_proto_encode(const cs_proto_msg_t *m, uint8_t *buf, size_t cap, size_t *len);
/* Decode payload buf[0..len) into *m. CS_ERR_FRAME when len is 0 or wrong for the type,
 * CS_ERR_UNSUPPORTED for an unknown type, CS_ERR_RANGE for a field outside its range (*m is then
 * unspecified), CS_ERR_ARG for a NULL pointer. Never reads outside buf[0..len). ISR-safe. */
cs_err_t cs_proto_decode(const uint8_t *buf, size_t len, cs_proto_msg_t *m);
/* True for the types cs_link delivers reliably (everything but ACK and PING). */
bool cs_proto_sequenced(uint8_t type);
/* True for the types that take a slot of the device's motion queue (SEGMENT, CURVE, PEN, HOME,
 * JOG, PROBE, SPINDLE): only these spend flow-control credits. */
bool cs_proto_uses_slot(uint8_t type);
/* True for the states in which the device is moving or about to (RUNNING, HOMING, JOG). */
bool cs_proto_state_busy(uint8_t state);
/* Boot id carried by a well-formed ACK, HELLO or STATUS payload (true), else false. */
bool cs_proto_peek_boot(const uint8_t *buf, size_t len, uint32_t *boot_id);

#endif
