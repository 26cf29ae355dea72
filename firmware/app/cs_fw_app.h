/* cs_fw_app: the device's application, the same on every board. Owns the device end of the link
 * (docs/protocol.md): HELLO at boot, the motion queue whose free slots are the link's credits,
 * SEGMENT messages fed to the step executor, CURVE messages traced and planned on board,
 * HOLD/RESUME/ABORT, periodic STATUS and ERROR reports. It touches hardware only through
 * firmware/ports/port.h (UART bytes, ticks, the step timer, interrupt masking) and is freestanding
 * C99 like the core: no heap, no float, no libc. It does on a microcontroller what
 * sim/cs_sim_device.c does in the simulator, minus fault injection and wall-clock pacing.
 *
 * Build-time sizes (-D on the compiler command line). RAM = sizeof(cs_fw_app_t), the one static
 * the application needs (arm-none-eabi-gcc / avr-gcc, measured with nm -S, docs/firmware.md):
 *   defaults (curves, queue 32, window 8)                           14736 B M3, 14488 B AVR
 *   -DCS_FW_CURVES=0                                                  2564 B M3,  2479 B AVR
 *   -DCS_FW_CURVES=0 -DCS_FW_QUEUE=8 -DCS_LINK_WINDOW=2
 *     -DCS_FRAME_PAYLOAD_MAX=27 -DCS_STEPPER_RING=8                    1036 B M3,  1005 B AVR
 * The macros:
 *   CS_FW_QUEUE       motion-queue slots (HELLO queue_size = link credits), 1..255, default 32;
 *                     one slot is 56 B with curves, 24 B without.
 *   CS_FW_CURVES      1 (default): accept CURVE messages, traced and planned on board: adds
 *                     cs_trace_t (6464 B: the subdivision stack), cs_planner_t (4408 B with
 *                     CS_PLANNER_RING = 32) and cs_segment_gen_t (168 B); 0: SEGMENT only (HELLO
 *                     caps say so), no tracer or planner in RAM or flash.
 *   CS_FW_ERRQ        ERROR messages waiting for room in the link window, default 4 (4 B each).
 *   CS_FW_RX_CHUNK    UART bytes read per poll, on the stack, default 32.
 *   CS_FW_TRACE       tracer for CURVE messages (cs_trace_method_t), default CS_TRACE_DEFAULT.
 *   CS_FW_RTO_MS      link retransmission timeout, ms, default 50 (>= a full window at the line
 *                     rate plus a round trip: docs/protocol.md 3.6); CS_FW_NAK_MS, default 2.
 *   CS_FW_XY_RATE, CS_FW_XY_ACCEL  x/y limits of cs_fw_machine_default (500 mm/s, 5000 mm/s^2).
 * The core's own sizes apply too: CS_LINK_WINDOW (default 8: cs_link_t 896 B on the M3, 863 B on
 * the AVR; 266 B on the AVR with CS_LINK_WINDOW=2 and CS_FRAME_PAYLOAD_MAX=27),
 * CS_FRAME_PAYLOAD_MAX (64; >= 53 to carry CURVE), CS_STEPPER_RING (16: cs_stepper_t 596 B on the
 * M3, 36 B a slot, plus a 4 B tag a slot here), CS_PLANNER_RING (32 blocks of 132 B, only with
 * CS_FW_CURVES).
 */
#ifndef CS_FW_APP_H
#define CS_FW_APP_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_err.h"
#include "cs_link.h"
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
#ifndef CS_FW_RX_CHUNK
#define CS_FW_RX_CHUNK 32
#endif
#ifndef CS_FW_RTO_MS
#define CS_FW_RTO_MS 50
#endif
#ifndef CS_FW_NAK_MS
#define CS_FW_NAK_MS 2
#endif

#if CS_FW_CURVES
#include "cs_planner.h"
#include "cs_trace.h"
#ifndef CS_FW_TRACE
#define CS_FW_TRACE CS_TRACE_DEFAULT
#endif
/* Items taken from the queue and not yet executed: the executor's ring, the planner's blocks
 * (one curve may be a single block), the curve being traced; a power of two above that. */
#define CS_FW_SEQMAP 64
CS_STATIC_ASSERT(CS_FW_SEQMAP >= CS_STEPPER_RING + CS_PLANNER_RING + 2, fw_seqmap_room);
#else
#define CS_FW_SEQMAP 32
CS_STATIC_ASSERT(CS_FW_SEQMAP >= CS_STEPPER_RING + 2, fw_seqmap_room);
#endif
CS_STATIC_ASSERT((CS_FW_SEQMAP & (CS_FW_SEQMAP - 1)) == 0, fw_seqmap_power_of_two);
CS_STATIC_ASSERT(CS_FW_QUEUE >= 1 && CS_FW_QUEUE <= 255, fw_queue_size);
CS_STATIC_ASSERT(CS_FW_ERRQ >= 1 && CS_FW_ERRQ <= 255, fw_errq_size);
#if CS_FW_CURVES
CS_STATIC_ASSERT(CS_FRAME_PAYLOAD_MAX >= CS_PROTO_LEN_CURVE, fw_payload_carries_curve);
#endif

/* One motion-queue slot: a SEGMENT or (with curves) a CURVE, and its link sequence. */
typedef struct {
    uint8_t type; /* CS_PROTO_SEGMENT or CS_PROTO_CURVE */
    uint16_t seq;
    union {
        cs_segment_t seg;
#if CS_FW_CURVES
        cs_proto_curve_t curve;
#endif
    } u;
} cs_fw_item_t;

/* Counters for the report (cs_fw_app_report) and the figures. */
typedef struct {
    uint32_t executed; /* queue items (SEGMENT, CURVE) fully executed since boot */
    uint32_t segments; /* step segments pushed to the executor */
    uint32_t curves;   /* CURVE messages traced */
    uint32_t holds, aborts;
    uint32_t errors;   /* ERROR messages queued (the first CS_FW_ERRQ waiting ones are sent) */
    uint32_t rx_bytes; /* UART bytes received */
} cs_fw_stats_t;

/* The final report: what a test compares with the simulator. */
typedef struct {
    uint8_t n_axes;
    uint8_t state;        /* cs_proto_state_t */
    int32_t pos[CS_AXES]; /* executor position, steps */
    uint32_t steps;       /* step pulses the executor issued, all axes */
    cs_fw_stats_t stats;  /* counters above */
    cs_link_stats_t link; /* the link's counters (retransmissions, duplicates, ...) */
    cs_frame_stats_t rx;  /* frames decoded, CRC errors, malformed */
} cs_fw_report_t;

typedef struct {
    const cs_machine_t *m;
    cs_link_t link;
    uint32_t boot, nonce;
    uint32_t hz; /* port_tick_hz() */
    /* motion queue: slots free = link credits */
    cs_fw_item_t q[CS_FW_QUEUE];
    uint8_t qhead, qcount;
    /* executor and which item each queued segment finishes */
    cs_stepper_t st;
    uint32_t tag[CS_STEPPER_RING]; /* item executed once segment k has run */
    uint8_t pushed, completed;     /* segments pushed / known complete, mod 256 */
    /* items: numbered from 1 in the order they leave the queue */
    uint32_t popped;    /* items taken from the queue */
    uint32_t exec_item; /* items executed (== stats.executed) */
    uint16_t item_seq[CS_FW_SEQMAP];
    uint16_t exec_seq; /* sequence of the last item executed */
#if CS_FW_CURVES
    cs_planner_t pl;
    cs_segment_gen_t gen;
    cs_trace_t tr;
    bool gen_busy, tracing, rapid_pending, pl_stale;
    cs_vec3_t rapid_to;
    int32_t tr_feed;
    uint32_t tr_item;
    int32_t steps_pos[CS_AXES]; /* position after everything pushed, steps */
#endif
    /* state */
    uint8_t state, sent_state;
    bool held, aborted, status_due;
    uint32_t status_at;
    cs_proto_error_t errs[CS_FW_ERRQ];
    uint8_t nerr;
    /* bytes the UART did not take yet (the link's pointer is only valid until its next poll) */
    uint8_t txp[CS_FRAME_WIRE_MAX];
    uint8_t txp_len, txp_off;
    uint32_t last_rx; /* tick of the last byte received */
    bool more;        /* the last poll stopped with work left (not waiting for anything) */
    cs_fw_stats_t stats;
} cs_fw_app_t;

/* The default machine of the firmware images: 3 axes, 80 steps/mm, x/y 500 mm/s and 5000 mm/s^2,
 * z 50 mm/s and 500 mm/s^2, travel as the host's built-in plotter, tick_hz as given (the port's
 * port_tick_hz()), 5 ms segments, tolerance 0.01 mm, default feed 50 mm/s. The INI file of each
 * port (firmware/ports/<target>/machine.ini) says the same for the host. Not ISR-safe. */
void cs_fw_machine_default(cs_machine_t *m, uint32_t tick_hz);
/* Sets up the application for machine *m (kept; must outlive app) with boot id boot_id (random
 * per boot, != 0 preferred): executor, planner, link (CONNECTING), the step timer attached.
 * Call after port_init. CS_ERR_ARG when the machine is refused by the core. Not ISR-safe. */
cs_err_t cs_fw_app_init(cs_fw_app_t *app, const cs_machine_t *m, uint32_t boot_id);
/* One pass of the main loop: reads what the UART received, feeds the link, keeps the executor's
 * ring full (tracing curves as needed), sends HELLO/STATUS/ERROR and ACKs. Never blocks; bounded
 * work. Main loop only. */
void cs_fw_app_poll(cs_fw_app_t *app);
/* True when the last poll left nothing to do until an interrupt (a byte, a step, a timer): the
 * main loop may sleep (WFI) after it. Main loop only. */
bool cs_fw_app_can_sleep(const cs_fw_app_t *app);
/* True when everything received was executed and the executor is idle. Main loop only. */
bool cs_fw_app_idle(const cs_fw_app_t *app);
/* Tick (port_ticks_now) of the last byte received. */
uint32_t cs_fw_app_last_rx(const cs_fw_app_t *app);
/* Fills *r with the position, step count and counters. Main loop only (masks interrupts while it
 * reads the executor). */
void cs_fw_app_report(const cs_fw_app_t *app, cs_fw_report_t *r);

#endif
