/* cs_fw_motion: the device's motion side, the same on every board and in the simulator. Owns the
 * motion queue (SEGMENT, CURVE and PEN messages with their link sequence; its free slots are a link's
 * credits), the on-board tracer and planner for CURVE messages, the step executor fed from them,
 * feed hold along the path (cs_hold) and abort, the device state, the sequence of the last
 * executed message, the errors to report and the execution log (cs_exlog). It knows no link:
 * the front ends (cs_fw_app: framed serial; the simulator's Modbus server) hand it messages and
 * read its status. Touches hardware only through firmware/ports/port.h (step timer, interrupt
 * masking); freestanding C99 like the core: no heap, no float, no libc. Build-time sizes: see
 * cs_fw_app.h (CS_FW_QUEUE, CS_FW_CURVES, CS_FW_ERRQ, CS_FW_TRACE). */
#ifndef CS_FW_MOTION_H
#define CS_FW_MOTION_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_err.h"
#include "cs_exlog.h"
#include "cs_hold.h"
#include "cs_machine.h"
#include "cs_proto.h"
#include "cs_segment.h"
#include "cs_stepper.h"

#ifndef CS_FW_QUEUE
#define CS_FW_QUEUE 32
#endif
#ifndef CS_FW_CURVES
#define CS_FW_CURVES 1
#endif
#ifndef CS_FW_ERRQ
#define CS_FW_ERRQ 4
#endif
/* 1 (the host build of the simulator): the executed-log hook and SETPOS's position delta. */
#ifndef CS_FW_SIM_HOOKS
#define CS_FW_SIM_HOOKS 0
#endif

#include "cs_fw_ctl.h"

/* 1: an override above 100 % acts on the segments already queued (the stretch tracking below
 * costs a segment of RAM); 0 (builds without the planner: the ATmega328p's): the device's
 * scale stays at or below 1, an override above 100 % acts from the next plan only. */
#ifndef CS_FW_OV_UP
#define CS_FW_OV_UP CS_FW_CURVES
#endif

#if CS_FW_CURVES
#include "cs_planner.h"
#include "cs_trace.h"
#ifndef CS_FW_TRACE
#define CS_FW_TRACE CS_TRACE_DEFAULT
#endif
/* Items taken from the queue and not yet executed: the executor's ring, the planner's blocks
 * (one curve may be a single block), the curve being traced, the segment held back by a hold;
 * a power of two above that. */
#define CS_FW_SEQMAP 64
CS_STATIC_ASSERT(CS_FW_SEQMAP >= CS_STEPPER_RING + CS_PLANNER_RING + 3, fw_seqmap_room);
#else
/* Overridable for the smallest builds (the AVR's 16: its ring of 8 + 3 fits). */
#ifndef CS_FW_SEQMAP
#define CS_FW_SEQMAP 32
#endif
CS_STATIC_ASSERT(CS_FW_SEQMAP >= CS_STEPPER_RING + 3, fw_seqmap_room);
#endif
CS_STATIC_ASSERT((CS_FW_SEQMAP & (CS_FW_SEQMAP - 1)) == 0, fw_seqmap_power_of_two);
/* Segment tags: a power of two above the segments in flight (the ring and the running one). */
#define CS_FW_TAGS (2 * CS_STEPPER_RING)
CS_STATIC_ASSERT(CS_FW_TAGS >= CS_STEPPER_RING + 1 && CS_FW_TAGS <= 256, fw_tags_room);
/* 8-bit tags name an item within 2^7 of the last executed: items in flight stay below
 * CS_FW_SEQMAP (the sequence map relies on it too). */
CS_STATIC_ASSERT(CS_FW_SEQMAP <= 128, fw_tags_8_bits);
CS_STATIC_ASSERT(CS_FW_QUEUE >= 1 && CS_FW_QUEUE <= 1024, fw_queue_size);
CS_STATIC_ASSERT(CS_FW_ERRQ >= 1 && CS_FW_ERRQ <= 255, fw_errq_size);

/* One motion-queue slot: a SEGMENT, a PEN, a SPINDLE or (with curves) a CURVE, HOME, JOG or
 * PROBE, and its link sequence. */
typedef struct {
    uint8_t type; /* CS_PROTO_SEGMENT, CS_PROTO_PEN, ... */
    uint16_t seq;
    union {
        cs_segment_t seg;
        uint16_t pen_us;
        cs_proto_spindle_t spindle;
#if CS_FW_CURVES
        cs_proto_curve_t curve;
#endif
#if CS_FW_CTL
        cs_proto_home_t home;
        cs_proto_jog_t jog;
        cs_proto_probe_t probe;
#endif
    } u;
} cs_fw_item_t;

/* Counters for the report (cs_fw_app_report) and the figures. */
typedef struct {
    uint32_t executed; /* queue items (SEGMENT, CURVE, PEN) fully executed since boot */
    uint32_t segments; /* step segments pushed to the executor */
    uint32_t curves;   /* CURVE messages traced */
    uint32_t pens;     /* PEN messages applied (port_pen_set calls) */
    uint16_t pen_us;   /* the last pulse width set, us (0: none since boot) */
    uint32_t holds, aborts;
    uint32_t errors;      /* errors raised (the first CS_FW_ERRQ waiting ones are reported) */
    uint32_t rx_bytes;    /* UART bytes received (the serial front end's) */
    uint32_t errors_sent; /* ERROR messages a front end took (cs_fw_motion_pop_error) */
} cs_fw_stats_t;

/* Run-time choices (a board takes cs_fw_motion_cfg_default). */
typedef struct {
    uint16_t queue_size; /* slots offered, 1..CS_FW_QUEUE */
    cs_pos_t tol;        /* chord tolerance for CURVE messages, > 0 */
    uint8_t method;      /* cs_trace_method_t for CURVE messages */
} cs_fw_motion_cfg_t;

typedef struct cs_fw_motion_s {
    const cs_machine_t *m;
    cs_fw_motion_cfg_t cfg;
    /* motion queue: slots free = link credits */
    cs_fw_item_t q[CS_FW_QUEUE];
    uint16_t qhead, qcount;
    /* executor and which item each queued segment finishes */
    cs_stepper_t st;
    /* item executed once segment k has run: one per segment in flight, which is the ring's
     * CS_STEPPER_RING plus the one running (a ring of only CS_STEPPER_RING tags had the newest
     * overwrite the running segment's, counting up to a ring of items executed early) */
    uint8_t tag[CS_FW_TAGS]; /* low 8 bits (items in flight: fewer than CS_FW_SEQMAP <= 128) */
    uint8_t pushed, completed;     /* segments pushed / known complete, mod 256 */
    cs_hold_t hold;
#if CS_FW_OV_UP
    /* the first segment of the stretch of constant speed the executor is in (override > 1) */
    cs_segment_t ov_anchor;
    bool ov_has_anchor;
#endif
    cs_segment_t pend; /* produced, held back by a hold at rest */
    uint32_t pend_done;
    bool has_pend;
    /* items: numbered from 1 in the order they leave the queue */
    uint32_t popped;    /* items taken from the queue */
    uint32_t take_max;  /* take no item past this number (0: no limit) */
    uint32_t exec_item; /* items executed */
    /* a PEN taken from the queue, applied once the executor stopped after what came before it */
    bool pen_wait;
    uint16_t pen_us;
    uint32_t pen_item;
    uint16_t item_seq[CS_FW_SEQMAP];
    uint16_t exec_seq;          /* sequence of the last item executed */
    /* the job's numbering (SETPOS): item i (counted like popped) is job number
     * job_base + i - job_item0; flags CS_PROTO_STATUS_*, forgotten at a reboot */
    uint32_t job_id, job_base, job_item0;
    uint8_t job_flags;
#if CS_FW_SIM_HOOKS
    /* for the simulator (host builds only): its executed log's hook (NULL: none), called for
     * every segment handed to the executor with the job number of the item it finishes; and
     * the position changes SETPOS made (the STEP lines did not move for them) */
    void (*pushed_hook)(void *ctx, const cs_segment_t *s, uint32_t job_no);
    void *hook_ctx;
    int32_t set_delta[CS_AXES];
#endif
    int32_t steps_pos[CS_AXES]; /* position after everything pushed, steps */
#if CS_FW_CURVES
    cs_planner_t pl;
    cs_segment_gen_t gen;
    cs_trace_t tr;
    bool gen_busy, tracing, rapid_pending, pl_stale;
    cs_vec3_t rapid_to;
    int32_t tr_feed;
    uint32_t tr_item;
#endif
    uint8_t state; /* cs_proto_state_t */
    bool aborted;
    bool news; /* state or hold changed since cs_fw_motion_news */
    bool more; /* the last poll stopped with work left */
    cs_proto_error_t errs[CS_FW_ERRQ];
    uint8_t nerr;
    cs_exlog_segs_t log; /* every segment handed to the executor */
    cs_fw_stats_t stats;
    cs_fw_ctl_t ctl; /* limits, alarm, homing, jog, probe, spindle (cs_fw_ctl) */
} cs_fw_motion_t;

/* Zeroes n bytes at p without memset (freestanding: no libc; the application's structs are
 * zeroed before they are set up). */
void cs_fw_motion_zero(void *p, size_t n);
/* Defaults: CS_FW_QUEUE slots, the machine's tolerance, CS_FW_TRACE (or subdivision). */
void cs_fw_motion_cfg_default(cs_fw_motion_cfg_t *c, const cs_machine_t *m);
/* Empty queue, executor at 0, attached to the port's step timer (port_stepper_attach); the last
 * executed sequence reads 0xFFFF. CS_ERR_ARG for a bad machine or cfg. Not ISR-safe. */
cs_err_t cs_fw_motion_init(cs_fw_motion_t *mo, const cs_machine_t *m, const cs_fw_motion_cfg_t *c);
/* Queues a SEGMENT, PEN, SPINDLE, CURVE, HOME, JOG or PROBE with its sequence (the last four
 * with curves only; HOME, PROBE and a non-laser SPINDLE start like a PEN, cs_fw_ctl; every one
 * refused with CS_ERR_STATE in alarm) (a PEN is applied with port_pen_set once the
 * executor has run everything queued before it and stopped, never while held, and nothing after
 * it starts before): CS_ERR_FULL when no slot is free,
 * CS_ERR_UNSUPPORTED for another type (or CURVE without curves). Main loop. */
cs_err_t cs_fw_motion_queue(cs_fw_motion_t *mo, const cs_proto_msg_t *msg, uint16_t seq);
/* HOLD (on: decelerate along the path to rest, cs_hold) or RESUME (off: from rest). */
void cs_fw_motion_hold(cs_fw_motion_t *mo, bool on);
/* OVERRIDE: the queued motion's speed ramps (cs_hold's slope) to feed / 1000 of its planned
 * speed, above 1 only inside stretches of constant speed and below each axis's max rate
 * (docs/controller.md, "Overrides"); the spindle to spindle / 1000 of its programmed power
 * (cs_fw_ctl). Fields as checked by cs_proto. Main loop. */
void cs_fw_motion_override(cs_fw_motion_t *mo, const cs_proto_override_t *ov);
/* ABORT: the queue and everything not yet in the executor's ring are dropped (the ring, at most
 * CS_STEPPER_RING segments, finishes), the hold is released. */
void cs_fw_motion_abort(cs_fw_motion_t *mo);
/* Keeps the executor's ring full (tracing curves as needed), notes what completed, updates the
 * state. Never blocks; bounded work. Main loop. */
void cs_fw_motion_poll(cs_fw_motion_t *mo);
/* A new boot of the link (a reset that keeps the machine where it is): the queue, the errors and
 * the sequences are forgotten; the executor, its position and what it holds are kept. */
void cs_fw_motion_reboot(cs_fw_motion_t *mo);
/* Before an ABORT message: the items taken from the queue but not handed to the executor get
 * their numbers back (they will not run; STATUS done/recv stay the truth). Main loop. */
void cs_fw_motion_give_back(cs_fw_motion_t *mo);
/* SETPOS: numbers the items received from now on base+1, ... in job job_id; with
 * CS_PROTO_SETPOS_POS sets the position counters to pos[] (steps), which needs the queue empty
 * and the executor idle: CS_ERR_STATE otherwise (nothing changed). Main loop. */
cs_err_t cs_fw_motion_setpos(cs_fw_motion_t *mo, const cs_proto_setpos_t *sp);
/* A message the host numbers as a job item but that takes no queue slot (UNLOCK) counts as
 * received and finished at once, so the job's numbering (done, recv) stays the host's; only
 * when the queue is empty and the executor idle. Main loop only, not ISR-safe. */
void cs_fw_motion_count_immediate(cs_fw_motion_t *mo);
/* Job number of item (counted from 1 since init like the queue's items): 0 without a job. */
uint32_t cs_fw_motion_job_no(const cs_fw_motion_t *mo, uint32_t item);
/* Takes no queue item numbered past n (items count from 1 since init; 0: no limit). */
void cs_fw_motion_take_limit(cs_fw_motion_t *mo, uint32_t n);
/* Free queue slots (the link's credits). */
uint16_t cs_fw_motion_free(const cs_fw_motion_t *mo);
/* Everything taken from the queue has been executed / that and the queue is empty too. */
bool cs_fw_motion_drained(const cs_fw_motion_t *mo);
bool cs_fw_motion_done(const cs_fw_motion_t *mo);
/* True (once) when the state changed or a hold/resume/abort came since the last call. */
bool cs_fw_motion_news(cs_fw_motion_t *mo);
/* State, queue fill, last executed sequence, axes, position and the job's progress (flags,
 * job id, last item finished, last item received; boot_id left as it is). Masks
 * the step interrupt while it reads the executor. Main loop. */
void cs_fw_motion_status(const cs_fw_motion_t *mo, cs_proto_status_t *st);
/* Executor position of axis, steps (interrupt masked while read). Main loop. */
int32_t cs_fw_motion_position(const cs_fw_motion_t *mo, unsigned axis);
/* Control side (cs_fw_ctl) helpers. Main loop. Drop: the queue and everything not yet in the
 * executor's ring are forgotten, the hold released (ABORT without the ABORTED state). Flush:
 * only what was taken from the queue and not yet pushed (planner, tracer, held-back segment,
 * waiting PEN), the planner restarted from steps_pos. Mark: item n (numbered from 1 as taken)
 * counts as executed. Still: nothing taken waits to run and the executor is idle. Executed: item n
 * has been executed. Current seq: the sequence of the item executing (the last executed when
 * none). Plan line: a straight move to target (mm) at feed for item n into the planner (an
 * error is reported about n). */
void cs_fw_motion_drop(cs_fw_motion_t *mo);
void cs_fw_motion_flush(cs_fw_motion_t *mo);
void cs_fw_motion_mark(cs_fw_motion_t *mo, uint32_t n);
bool cs_fw_motion_still(const cs_fw_motion_t *mo);
bool cs_fw_motion_executed(const cs_fw_motion_t *mo, uint32_t n);
uint16_t cs_fw_motion_current_seq(const cs_fw_motion_t *mo);
/* The executor was halted after `done` segments (mod 256, counted as cs_fw_motion pushes them):
 * those count as executed, the rest of the ring as gone; returns the sequence of the item whose
 * segment was cut (the current one when none was). */
uint16_t cs_fw_motion_halted(cs_fw_motion_t *mo, uint8_t done);
#if CS_FW_CURVES
void cs_fw_motion_plan_line(cs_fw_motion_t *mo, const cs_vec3_t *target, int32_t feed, uint32_t n);
#endif
/* Raises an error about the message with sequence seq (reported in an ERROR; the first
 * CS_FW_ERRQ waiting are kept, the rest only counted). */
void cs_fw_motion_error(cs_fw_motion_t *mo, cs_err_t code, uint16_t seq);
/* The oldest error not yet reported: true and *e (counted in stats.errors_sent), else false. */
bool cs_fw_motion_peek_error(const cs_fw_motion_t *mo, cs_proto_error_t *e);
void cs_fw_motion_drop_error(cs_fw_motion_t *mo);
bool cs_fw_motion_pop_error(cs_fw_motion_t *mo, cs_proto_error_t *e);

#endif
