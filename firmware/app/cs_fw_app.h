/* cs_fw_app: the device's framed-serial front end, the same on every board and in the simulator
 * (sim/cs_sim_device.c runs it on firmware/ports/posix). Owns the device end of the link
 * (docs/protocol.md): HELLO at boot, the link's credits (the motion queue's free slots), messages
 * delivered to the motion side (cs_fw_motion: queue, curves, hold, abort, status), periodic
 * STATUS and ERROR reports. It touches hardware only through firmware/ports/port.h (UART bytes,
 * ticks, the step timer, interrupt masking) and is freestanding C99 like the core: no heap, no
 * float, no libc.
 *
 * Build-time sizes (-D on the compiler command line). RAM = sizeof(cs_fw_app_t), the one static
 * the application needs (arm-none-eabi-gcc / avr-gcc, measured with nm -S, docs/firmware.md):
 *   defaults (curves, queue 32, window 8)                           14880 B M3, 14609 B AVR
 *   -DCS_FW_CURVES=0                                                  2720 B M3,  2616 B AVR
 *   -DCS_FW_CURVES=0 -DCS_FW_QUEUE=8 -DCS_LINK_WINDOW=2
 *     -DCS_FRAME_PAYLOAD_MAX=27 -DCS_STEPPER_RING=8                    1196 B M3,  1142 B AVR
 *   (protocol 1; the AVR image now has -DCS_FRAME_PAYLOAD_MAX=40 for protocol 3's 3-axis STATUS and
 *   -DCS_FW_ERRQ=2 -DCS_FW_RX_CHUNK=16: 1198 B AVR)
 * The macros:
 *   CS_FW_QUEUE       motion-queue slots (HELLO queue_size = link credits; the most a run may
 *                     offer, cs_fw_app_cfg_t), 1..1024, default 32;
 *                     one slot is 56 B with curves, 24 B without.
 *   CS_FW_CURVES      1 (default): accept CURVE messages, traced and planned on board: adds
 *                     cs_trace_t (6464 B: the subdivision stack), cs_planner_t (4408 B with
 *                     CS_PLANNER_RING = 32) and cs_segment_gen_t (168 B); 0: SEGMENT only (HELLO
 *                     caps say so), no tracer or planner in RAM or flash.
 *   CS_FW_ERRQ        ERROR messages waiting for room in the link window, default 4 (4 B each).
 *   CS_FW_RX_CHUNK    UART bytes read per poll, on the stack, default 32.
 *   CS_FW_TRACE       tracer for CURVE messages (cs_trace_method_t), default CS_TRACE_DEFAULT.
 *   CS_FW_LINE_BPS    the line's bits/s, default 115200: the link's retransmission timeout and
 *                     NAK hold-off follow from it (cs_linktime_link, docs/protocol.md 3.6).
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
#include "cs_fw_motion.h"
#include "cs_link.h"
#include "cs_linktime.h"
#include "cs_machine.h"
#include "cs_proto.h"

#ifndef CS_FW_RX_CHUNK
#define CS_FW_RX_CHUNK 32
#endif
#ifndef CS_FW_LINE_BPS
#define CS_FW_LINE_BPS 115200u
#endif
#if CS_FW_CURVES
CS_STATIC_ASSERT(CS_FRAME_PAYLOAD_MAX >= CS_PROTO_LEN_CURVE, fw_payload_carries_curve);
#endif

/* The final report: what a test compares with the simulator. */
typedef struct {
    uint8_t n_axes;
    uint8_t state;        /* cs_proto_state_t */
    int32_t pos[CS_AXES]; /* executor position, steps */
    uint32_t steps;       /* step pulses the executor issued, all axes */
    cs_fw_stats_t stats;  /* counters above */
    cs_link_stats_t link; /* the link's counters (retransmissions, duplicates, ...) */
    cs_frame_stats_t rx;  /* frames decoded, CRC errors, malformed */
    cs_exlog_segs_t log;  /* the segments handed to the executor (cs_exlog) */
} cs_fw_report_t;

/* Run-time choices: a board takes cs_fw_app_cfg_default (its tick counter is the link's clock);
 * the simulator gives its wall clock in microseconds and the link timing of its line. */
typedef struct {
    cs_fw_motion_cfg_t motion;
    uint32_t (*clock)(void); /* the link's clock (port_ticks_now on a board) */
    uint32_t clock_hz;       /* its ticks per second */
    cs_link_cfg_t link;      /* rto, rto_max, give_up, nak_holdoff, keepalive: ticks */
    uint32_t status_ms;      /* STATUS period while running or held (idle: 250 ms) */
} cs_fw_app_cfg_t;

typedef struct {
    const cs_machine_t *m;
    cs_fw_app_cfg_t cfg;
    cs_link_t link;
    uint32_t boot, nonce;
    cs_fw_motion_t mo;
    uint8_t sent_state;
    bool status_due;
    uint32_t status_at;
    bool have_prev; /* a message was delivered since the link opened */
    uint16_t prev_seq;
    uint32_t out_of_order; /* deliveries whose sequence was not the previous + 1 (must be 0) */
    /* bytes the UART did not take yet (the link's pointer is only valid until its next poll) */
    uint8_t txp[CS_FRAME_WIRE_MAX];
    uint8_t txp_len, txp_off;
    uint32_t last_rx; /* link-clock time of the last byte received */
} cs_fw_app_t;

/* The default machine of the firmware images: 3 axes, 80 steps/mm, x/y 500 mm/s and 5000 mm/s^2,
 * z 50 mm/s and 500 mm/s^2, travel as the host's built-in plotter, tick_hz as given (the port's
 * port_tick_hz()), 5 ms segments, tolerance 0.01 mm, default feed 50 mm/s. The INI file of each
 * port (firmware/ports/<target>/machine.ini) says the same for the host. Not ISR-safe. */
void cs_fw_machine_default(cs_machine_t *m, uint32_t tick_hz);
/* A board's choices for machine *m: cs_fw_motion_cfg_default, port_ticks_now at port_tick_hz as
 * the link clock, the link timing of a CS_FW_LINE_BPS line (cs_linktime_link), STATUS every
 * 50 ms while moving. */
void cs_fw_app_cfg_default(cs_fw_app_cfg_t *c, const cs_machine_t *m);
/* Sets up the application for machine *m (kept; must outlive app) with boot id boot_id (random
 * per boot, != 0 preferred) and the defaults: executor, planner, link (CONNECTING), the step timer
 * attached. Call after port_init. CS_ERR_ARG when the machine is refused by the core. Not
 * ISR-safe. */
cs_err_t cs_fw_app_init(cs_fw_app_t *app, const cs_machine_t *m, uint32_t boot_id);
/* The same with explicit choices (*c is copied). */
cs_err_t cs_fw_app_init_cfg(cs_fw_app_t *app, const cs_machine_t *m, uint32_t boot_id,
                            const cs_fw_app_cfg_t *c);
/* A reset that keeps the machine where it is: a new boot id, the link back to CONNECTING, the
 * queue lost (cs_fw_motion_reboot). Main loop. */
void cs_fw_app_reboot(cs_fw_app_t *app, uint32_t boot_id);
/* One pass of the main loop: reads what the UART received, feeds the link, keeps the executor's
 * ring full (tracing curves as needed), sends HELLO/STATUS/ERROR and ACKs. Never blocks; bounded
 * work. Main loop only. */
void cs_fw_app_poll(cs_fw_app_t *app);
/* Sends a STATUS now if the link has room: true when it went out. Main loop only. */
bool cs_fw_app_send_status(cs_fw_app_t *app);
/* True when the last poll left nothing to do until an interrupt (a byte, a step, a timer): the
 * main loop may sleep (WFI) after it. Main loop only. */
bool cs_fw_app_can_sleep(const cs_fw_app_t *app);
/* True when everything received was executed and the executor is idle. Main loop only. */
bool cs_fw_app_idle(const cs_fw_app_t *app);
/* Link-clock time of the last byte received. */
uint32_t cs_fw_app_last_rx(const cs_fw_app_t *app);
/* Fills *r with the position, step count and counters. Main loop only (masks interrupts while it
 * reads the executor). */
void cs_fw_app_report(const cs_fw_app_t *app, cs_fw_report_t *r);

#endif
