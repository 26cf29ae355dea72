/* cs_sim_device: the simulator as the device on the far end of a serial line (a pty or a tty).
 * The device is the firmware's own application (firmware/app: cs_fw_app over cs_fw_motion) on the
 * POSIX port (firmware/ports/posix), unchanged; this module adds what a simulator is for: the
 * simulated time paced against the wall clock (see docs/streaming.md, "The device's pacing"),
 * faults injected on the line and scheduled resets/hangs/closes, every STEP edge recorded for the
 * check report, the command line. Host only (POSIX); one device per process (the POSIX port is
 * process-wide). */
#ifndef CS_SIM_DEVICE_H
#define CS_SIM_DEVICE_H

#include <signal.h>
#include <stdbool.h>
#include <stdint.h>

#include "cs_jobopts.h"
#include "cs_exlog.h"
#include "cs_fw_motion.h"
#include "cs_link.h"
#include "cs_machine.h"
#include "cs_ctlcfg.h"
#include "cs_machine_ini.h"
#include "cs_motion.h"
#include "cs_serial.h"
#include "cs_sim.h"

/* Largest motion queue (slot-using messages waiting for the executor): the application's
 * compile-time queue (the host build sets CS_FW_QUEUE=256). */
#define CS_SIM_DEVICE_QUEUE_MAX CS_FW_QUEUE

typedef struct {
    const cs_machine_t *m;
    uint16_t queue_size; /* motion-queue slots announced in HELLO, 1..CS_SIM_DEVICE_QUEUE_MAX */
    double speed;        /* simulated seconds per wall second (1 = real time); 0 = instant:
                          * everything queued is executed at once, the queue never fills */
    uint32_t line_rate;  /* pace the device's writes to this many bits/s (0 = memory speed) */
    cs_serial_faults_t faults; /* injected into what the device writes; all zero = none */
    double corrupt_in;         /* probability that a byte the device reads is changed */
    uint64_t reset_after; /* after executing this many messages, reboot (new boot id, queue lost,
                           * position kept as a machine that homes would): 0 = never */
    uint64_t hang_after;  /* after this many, stop reading and writing (a dead cable): 0 = never */
    uint64_t close_after; /* after this many, close the line and return: 0 = never */
    uint32_t boot_id;     /* first boot id (0 = from the clock and pid) */
    cs_pos_t tol;         /* chord tolerance for CURVE messages (0 = the machine's) */
    int method;           /* cs_trace_method_t for CURVE messages */
    uint32_t status_ms;   /* STATUS period while running or held (0 = 50 ms) */
    double idle_exit_s;   /* return after this long idle with nothing received, once something
                           * was executed (0 = never) */
    bool keep_edges;      /* copy the recorded STEP edges into the result (for checks) */
    const char *exlog;    /* append every finished segment to this file (cs_sim_exlog); NULL:
                           * none */
    const cs_ctlcfg_t *ctl; /* [limits] and [probe]: the simulated switches and probe surface
                             * (physical machine coordinates, 0 at start); NULL: none */
} cs_sim_device_cfg_t;

typedef struct {
    uint64_t executed;       /* slot-using messages executed (SEGMENT and CURVE) */
    uint64_t segments;       /* step segments run by the executor */
    uint64_t seg_hash;       /* FNV-1a 32 over every segment handed to the executor (cs_exlog) */
    uint64_t curves;         /* CURVE messages executed */
    uint64_t out_of_order;   /* deliveries whose sequence was not the previous + 1 (must be 0) */
    uint32_t resets;         /* simulated reboots */
    uint32_t boot_id;        /* boot id at the end */
    uint32_t holds, aborts;  /* HOLD and ABORT messages obeyed */
    uint32_t errors_sent;    /* ERROR messages sent (bad CURVE, refused SEGMENT) */
    uint32_t exec_gaps;      /* times the executor ran dry and was fed again later */
    double gap_wall_s;       /* wall time spent dry between two such feeds */
    cs_link_stats_t link;    /* the device's link counters (duplicates, out of order, ...) */
    cs_frame_stats_t frames; /* frames decoded, CRC errors, malformed */
    uint64_t bytes_in, bytes_out;
    uint64_t ticks;             /* simulated time at the end (executor ticks) */
    double wall_s;              /* wall time served */
    int64_t pos[CS_AXES];       /* final position from the STEP/DIR lines, steps */
    cs_sim_exec_t ex;           /* with keep_edges: every STEP edge (free with cs_sim_exec_free) */
    cs_exlog_segs_t log_segs;   /* the execution log, as a board keeps it (cs_exlog) */
    cs_exlog_edges_t log_edges; /* the STEP edges on the executor's clock (cs_exlog) */
    size_t pens;                /* PEN messages the device set (port_pen_set) */
    /* with keep_edges and pens: the run cut at each pen setting into pseudo-segments (segment
     * k+1 starts at the tick of pen setting k), the settings as their pen events: what
     * cs_sim_check reads from a segments file's "pen US" lines (free: cs_motion_segs_free) */
    cs_motion_segs_t pen_segs;
    /* machine control (cs_fw_ctl): axes homed, alarms (the last one's code), probe cycles,
     * spindle / laser output settings recorded (port_spindle_set) and the largest duty */
    uint32_t homings, alarms, probes;
    uint8_t last_alarm;
    size_t spindles;
    uint16_t max_duty;
} cs_sim_device_result_t;

/* Defaults: queue 32, real time, no faults, subdivision at the machine's tolerance. */
void cs_sim_device_cfg_default(cs_sim_device_cfg_t *cfg, const cs_machine_t *m);
/* Serves the device on fd (a pty master or an open tty, made non-blocking) until *stop becomes
 * non-zero (may be NULL), the line fails, a close_after fault fires or idle_exit_s elapses.
 * Fills *res (always). CS_OK, CS_ERR_IO when the line failed, CS_ERR_ARG for a bad cfg,
 * CS_ERR_FULL when out of memory. Not reentrant (uses the process-wide POSIX port). */
cs_err_t cs_sim_device_serve(int fd, const cs_sim_device_cfg_t *cfg, volatile sig_atomic_t *stop,
                             cs_sim_device_result_t *res);

/* The device's motion side, shared by the serial device above and the Modbus device
 * (cs_sim_modbus): the motion queue, the planner and tracer for CURVE, the executor on the POSIX
 * port paced against the wall clock (cfg->speed), HOLD / RESUME / ABORT, the sequence of the
 * last executed message. Uses cfg's m, queue_size, speed, tol, method and keep_edges; one at a
 * time per process (the POSIX port is process-wide). */
typedef struct cs_sim_motion cs_sim_motion_t;
/* Starts one (the last executed sequence reads 0xFFFF until something runs); *res is zeroed and
 * filled as it runs. CS_ERR_ARG for a bad cfg, CS_ERR_FULL out of memory. */
cs_err_t cs_sim_motion_open(cs_sim_motion_t **d, const cs_sim_device_cfg_t *cfg,
                            cs_sim_device_result_t *res);
/* The firmware's motion side it runs (for a front end of the firmware's own, cs_fw_modbus). */
cs_fw_motion_t *cs_sim_motion_fw(cs_sim_motion_t *d);
/* Queues a SEGMENT or CURVE with its sequence: CS_ERR_FULL when no slot is free,
 * CS_ERR_UNSUPPORTED for another type. */
cs_err_t cs_sim_motion_queue(cs_sim_motion_t *d, const cs_proto_msg_t *m, uint16_t seq);
/* HOLD (on) or RESUME (off); ABORT (the queue is flushed, the executor's ring finishes). */
void cs_sim_motion_hold(cs_sim_motion_t *d, bool on);
void cs_sim_motion_abort(cs_sim_motion_t *d);
/* Runs the executor up to the wall time wall_s (cs_serial_now_s), feeding it from the queue. */
void cs_sim_motion_advance(cs_sim_motion_t *d, double wall_s);
uint16_t cs_sim_motion_free_slots(const cs_sim_motion_t *d);
/* State, queue fill, last executed sequence and position (boot_id is not the motion's). */
void cs_sim_motion_status(const cs_sim_motion_t *d, cs_proto_status_t *st);
/* The oldest error the motion raised (a CURVE it cannot trace, ...): true and *e, else false. */
bool cs_sim_motion_pop_error(cs_sim_motion_t *d, cs_proto_error_t *e);
/* Queue empty and everything executed / something was executed / work to do and not held. */
bool cs_sim_motion_done(const cs_sim_motion_t *d);
bool cs_sim_motion_started(const cs_sim_motion_t *d);
bool cs_sim_motion_busy(const cs_sim_motion_t *d);
/* Finishes what the executor holds, fills res (ticks, pos, edges with keep_edges) and frees d.
 * CS_ERR_FULL when the edges could not be kept. */
cs_err_t cs_sim_motion_close(cs_sim_motion_t *d);

/* The end-of-service report's common part (executor gaps, job time, final position, order,
 * per-axis peaks, deviation from the reference, pictures, the check line), shared by the
 * serial and the Modbus devices. ok: the link-specific checks passed. Returns rc, or 3 when a
 * file could not be written, 4 when --check failed. */
typedef struct {
    const char *reference, *trace, *svg, *png; /* NULL: none */
    bool check;
    const cs_sim_ref_t *ref; /* loaded from reference (cs_sim_ref_from_path) */
    double end_mm[3];        /* the job's end */
    const cs_machine_pen_t *pen; /* mode servo: the check is cs_sim_check's pen check on
                                  * res->pen_segs; NULL or another mode: the 3D deviation */
} cs_sim_device_out_t;
int cs_sim_device_report(const cs_machine_t *m, const cs_sim_device_cfg_t *cfg,
                         const cs_sim_device_result_t *res, const cs_sim_device_out_t *o, bool ok,
                         int rc);

/* The options every device front end takes (the serial device here, the Modbus device in
 * cs_sim_modbus.c): machine, checks and pictures, faults, pacing, queue, baud. */
typedef struct {
    const char *machine_file, *faults; /* NULL: the built-in machine, no faults */
    cs_sim_device_out_t out;           /* --reference --svg --png --trace --check */
    bool instant;                      /* --instant */
    double speed, idle_exit, tol_mm;   /* --speed (default 1), --idle-exit s, --tol mm (0: none) */
    long queue, baud;                  /* --queue (default 32), --baud (default 115200) */
    cs_jobopts_t in; /* the shared input and layout options, for --reference (cs_jobopts) */
} cs_sim_device_opts_t;
void cs_sim_device_opts_default(cs_sim_device_opts_t *o);
/* Takes argv[*i] (and its value, advancing *i) when it is one of those options: 1 taken, 0 not
 * one of them, -1 a bad value (the sentence printed on stderr). */
int cs_sim_device_opt(int argc, char **argv, int *i, cs_sim_device_opts_t *o);

/* The e-stop of the simulated machine: pressed (true) or released, reported to the device at
 * its next pass (curvestep-sim: SIGUSR1 presses, SIGUSR2 releases). ISR-safe (a flag). */
void cs_sim_device_estop(bool pressed);

/* The `curvestep-sim --pty | --port DEV ...` command line (sim/main.c hands these over). */
int cs_sim_device_main(int argc, char **argv);

#endif
