/* cs_fw_ctl: the device's machine control, the part of the motion side (cs_fw_motion) that
 * reacts to the machine's inputs: hard limits and e-stop (an alarm state left by UNLOCK), homing
 * on the limit switches, jogs with a decelerating cancel, probing, and the spindle / laser output
 * with laser power scaled by each segment's speed (docs/protocol.md, "Machine control";
 * docs/controller.md). Owns cs_fw_ctl_t (inside cs_fw_motion_t: the input interrupt's flags, the
 * operation in progress and its phase, the events to report, the spindle state). The input
 * interrupt (port_inputs_attach) and the executor's load hook (cs_stepper_on_load) run here; the
 * rest runs in the main loop from cs_fw_motion. Touches hardware only through port.h;
 * freestanding C99: no heap, no float, no libc. HOME, JOG and PROBE are planned with the device's
 * planner; a build without it (CS_FW_CURVES=0, the ATmega328p's) runs them as straight lines at
 * constant speed cut into step segments here (the line generator below: no acceleration ramp),
 * and HELLO caps CS_PROTO_CAP_CONTROL either way. */
#ifndef CS_FW_CTL_H
#define CS_FW_CTL_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_err.h"
#include "cs_machine.h"
#include "cs_proto.h"
#include "cs_segment.h"

#ifndef CS_FW_CURVES /* as cs_fw_motion.h: 1 = the on-board planner is there */
#define CS_FW_CURVES 1
#endif
/* 1 (default, the ATmega328p's too): machine control built in; 0: left out, HELLO then offers
 * no CONTROL or SPINDLE capability and the messages are refused with CS_ERR_UNSUPPORTED. */
#ifndef CS_FW_CTL
#define CS_FW_CTL 1
#endif
/* EVENT messages waiting for room in the link (an alarm, a probe contact and a homed axis fit). */
#ifndef CS_FW_EVQ
#define CS_FW_EVQ 4
#endif
CS_STATIC_ASSERT(CS_FW_EVQ >= 2 && CS_FW_EVQ <= 255, fw_evq_size);
/* The line generator's longest move, ticks (19 h at 31250 Hz; its counts stay below 2^31). */
#define CS_FW_CTL_LINE_TICKS_MAX 0x7FFFFFFFu

/* The operation the device runs itself (taken from the queue like a PEN). */
typedef enum {
    CS_FW_OP_NONE = 0,
    CS_FW_OP_HOME = 1,
    CS_FW_OP_PROBE = 2,
} cs_fw_op_t;

/* Why the input interrupt halted the executor. */
typedef enum {
    CS_FW_TRIP_NONE = 0,
    CS_FW_TRIP_WATCH = 1, /* the input an operation waits for (homing switch, probe contact) */
    CS_FW_TRIP_ALARM = 2, /* a hard limit or the e-stop: trip_code says which alarm */
} cs_fw_trip_t;

#if CS_FW_CTL
typedef struct {
    /* written by the input interrupt */
    volatile uint16_t inputs;      /* the last bits reported */
    volatile uint8_t trip;         /* cs_fw_trip_t: the executor was halted */
    volatile uint8_t trip_code;    /* cs_proto_alarm_t of an alarm trip */
    volatile uint16_t trip_inputs; /* the bits at the trip */
    volatile uint8_t trip_done;    /* segments finished at the trip (cs_fw_motion's count) */
    /* read by the input interrupt, written by the main loop with it masked */
    volatile uint16_t watch;   /* bits whose activation halts (homing switch, probe) */
    volatile uint16_t release; /* bits whose release halts (probe away, G38.4/.5) */
    volatile bool armed;       /* hard limits watched (off in alarm: a switch stays pressed) */
    /* the laser: read by the executor's load hook */
    volatile bool laser;  /* segments carry their power (aux = duty) */
    volatile uint8_t sp_mode; /* cs_proto_spindle_mode_t */
    volatile uint16_t duty_set; /* the last duty handed to port_spindle_set */
    uint16_t power;           /* programmed power, 1/1000 */
    int32_t sp_feed;          /* laser: full-power speed, mm/s Q16 (0: constant) */
    uint16_t sp_ov;           /* spindle override, 1/1000 of the programmed power */
    /* main loop */
    uint8_t alarm; /* 0, or the cs_proto_alarm_t the device is in */
    uint8_t op;    /* cs_fw_op_t */
    uint8_t phase; /* homing: seek, back off, latch, pull off */
    bool op_wait;  /* taken, waiting for the executor to stop before it starts */
    bool op_move;  /* a move of the operation is planned / executing */
    uint32_t op_item;
    uint16_t op_seq;
    union {
        cs_proto_home_t home;
        cs_proto_probe_t probe;
        cs_proto_spindle_t spindle;
    } u;
    bool sp_wait; /* a non-laser SPINDLE waits for the executor to stop */
    bool jogging; /* JOG items taken and not yet executed */
    uint32_t jog_last;
    bool cancel; /* JOG_CANCEL: holding, then flush */
    uint16_t homed; /* bit i: axis i homed since boot */
    uint16_t inputs_sent;
    cs_proto_event_t ev[CS_FW_EVQ];
    uint8_t nev;
    uint32_t alarms, probes, homings; /* counters */
#if CS_FW_CURVES
    cs_machine_t wide; /* the machine with the travel opened up: homing moves are not limited */
#else
    /* the line generator (no planner on board): a straight move at constant speed */
    int32_t ln_left[CS_AXES]; /* steps still to make per axis */
    uint32_t ln_ticks;        /* ticks still to run; 0: no line */
    uint32_t ln_item;         /* the item the line belongs to */
    bool ln_mark;             /* its last segment executes the item (a JOG; not HOME/PROBE) */
#endif
} cs_fw_ctl_t;
#else
typedef struct { /* what cs_fw_motion and cs_fw_app read: never set */
    uint8_t trip, nev;
    bool cancel;
} cs_fw_ctl_t;
#endif

struct cs_fw_motion_s;

/* Clears the control state, attaches the input interrupt and the executor's load hook, reads the
 * inputs (an e-stop pressed at boot is an alarm). Called by cs_fw_motion_init. Not ISR-safe. */
void cs_fw_ctl_init(struct cs_fw_motion_s *mo);
/* The input interrupt (the edge hook given to port_inputs_attach; ctx the cs_fw_motion_t):
 * reads port_inputs_read and, when the bits changed since the last call, halts the executor on
 * the e-stop, a limit switch becoming active while hard limits are armed, or the input an
 * operation watches. ISR (or interrupts masked). */
void cs_fw_ctl_inputs_isr(void *ctx);
/* Queues check: CS_ERR_STATE in alarm (a HOME unlocks first, unless the e-stop is pressed),
 * CS_ERR_UNSUPPORTED for HOME / JOG / PROBE without curves; CS_OK otherwise. Main loop. */
cs_err_t cs_fw_ctl_admit(struct cs_fw_motion_s *mo, uint8_t type);
/* A HOME, JOG, PROBE or SPINDLE item taken from the queue (item number n): starts it or sets it
 * waiting; true when the caller may go on taking items now. Main loop. */
bool cs_fw_ctl_take(struct cs_fw_motion_s *mo, const void *item, uint32_t n);
/* True while an operation or a waiting SPINDLE keeps the queue from being taken further. */
bool cs_fw_ctl_blocking(const struct cs_fw_motion_s *mo);
/* The trip handling, the operation's next phase, the jog cancel, INPUTS events: once a pass,
 * before the executor is fed. Main loop. */
void cs_fw_ctl_poll(struct cs_fw_motion_s *mo);
/* The aux word of segment s for the executor (laser: its duty), computed after a hold re-timed
 * it. Main loop. */
uint16_t cs_fw_ctl_aux(const struct cs_fw_motion_s *mo, const cs_segment_t *s);
/* True when the feed override applies to what the executor is fed now: not while homing,
 * probing or jogging (Grbl leaves those at their own speed). Main loop. */
bool cs_fw_ctl_overridable(const struct cs_fw_motion_s *mo);
/* OVERRIDE's spindle scale (1/1000 of the programmed power, the output at most full): a
 * running spindle is set again at once; the laser's power per segment takes it from the next
 * segment handed to the executor (the ring's CS_STEPPER_RING segments keep theirs). Main loop. */
void cs_fw_ctl_override(struct cs_fw_motion_s *mo, uint16_t spindle);
/* UNLOCK / JOG_CANCEL from the link. Main loop. */
cs_err_t cs_fw_ctl_unlock(struct cs_fw_motion_s *mo);
void cs_fw_ctl_jog_cancel(struct cs_fw_motion_s *mo);
/* ABORT reached the control side: a homing in progress ends in ALARM 6, the rest stops. */
void cs_fw_ctl_abort(struct cs_fw_motion_s *mo);
/* The state the control side imposes (ALARM, HOMING, JOG), or 0xFF for none. */
uint8_t cs_fw_ctl_state(const struct cs_fw_motion_s *mo);
/* The oldest event not yet sent: true and *e; drop it once sent. Main loop. */
bool cs_fw_ctl_peek_event(const struct cs_fw_motion_s *mo, cs_proto_event_t *e);
void cs_fw_ctl_drop_event(struct cs_fw_motion_s *mo);
/* Without the planner (CS_FW_CURVES=0): the line generator's next step segment (at most the
 * machine's segment_ticks long) with *done the item executed once it has run: true, or false
 * when no line is under way. Busy: a line has segments left. Stop: the line is dropped. Main
 * loop. (With the planner: false, false, nothing.) */
bool cs_fw_ctl_line_next(struct cs_fw_motion_s *mo, cs_segment_t *s, uint32_t *done);
bool cs_fw_ctl_line_busy(const struct cs_fw_motion_s *mo);
void cs_fw_ctl_line_stop(struct cs_fw_motion_s *mo);
/* Position in mm Q16 of a step count (rounded to nearest). */
cs_pos_t cs_fw_ctl_steps_to_pos(int32_t steps, int32_t spm);

#endif
