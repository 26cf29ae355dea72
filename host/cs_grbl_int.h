/* cs_grbl_int: what the parts of the Grbl front end share (host/cs_grbl.c: the protocol, lines,
 * status and $ commands; host/cs_grbl_ctl.c: homing, unlock, probing, spindle and laser through
 * the device's machine-control messages). Internal to them: the session (grbl_t) and the steps
 * both call. Host only. */
#ifndef CS_GRBL_INT_H
#define CS_GRBL_INT_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_ctlcfg.h"
#include "cs_grbl.h"
#include "cs_grbl_dev.h"
#include "cs_grbl_gc.h"
#include "cs_grbl_ov.h"
#include "cs_motion.h"
#include "cs_serial.h"
#include "cs_stream.h"

/* Grbl 1.1 error codes we answer (grbl wiki, "Interface", error codes). */
enum {
    ERR_LETTER = 1,       /* expected command letter */
    ERR_NUMBER = 2,       /* bad number format */
    ERR_DOLLAR = 3,       /* '$' statement not recognized or supported */
    ERR_HOMING = 5,       /* homing not enabled */
    ERR_NOT_IDLE = 8,     /* '$' command only when idle */
    ERR_LOCKED = 9,       /* G-code locked out during alarm */
    ERR_OVERFLOW = 11,    /* line overflow */
    ERR_JOG_TRAVEL = 15,  /* jog target exceeds machine travel */
    ERR_JOG = 16,         /* invalid jog command */
    ERR_UNSUPPORTED = 20, /* unsupported or invalid g-code command */
    ERR_MODAL = 21,       /* modal group violation */
    ERR_NO_FEED = 22,     /* undefined feed rate */
    ERR_NO_AXIS = 26,     /* no axis words */
    ERR_NO_COMMAND = 31,  /* axis words with no command that uses them */
    ERR_TARGET = 33,      /* invalid target */
    ERR_UNUSED = 36,      /* unused value words */
};

typedef struct {
    const cs_grbl_cfg_t *cfg;
    cs_machine_t m;
    cs_pos_t tol;
    int32_t feed; /* --feed (Q15.16 mm/s), 0: the machine's */
    cs_serial_t ser;
    cs_grbl_dev_t dev;
    cs_grbl_gc_t gc;
    cs_path_t pending;           /* read, not yet planned */
    cs_pos_t plan_pos[CS_AXES];  /* where the last planned chunk ends */
    bool last_push_jog;          /* the last item queued was a jog */
    int fd;                      /* the client (-1: none) */
    char rx[CS_GRBL_RX_SIZE];    /* Grbl's receive buffer */
    size_t rxn;
    bool rx_overflow;            /* a line longer than the buffer: dropped up to its newline */
    bool after_cr;               /* the last line ended with '\r' */
    unsigned lineno;             /* lines received since the start */
    double t_last_line;
    bool held, check_mode, alarm; /* alarm: a soft limit, cleared by $X */
    int report_mask;              /* $10 */
    unsigned reports;
    double wco_sent[3];
    unsigned cancelled_seen; /* device runs ended by cancel that were synced */
    cs_grbl_ov_t ov;         /* feed, rapid, spindle overrides */
    bool ov_changed;         /* ... not yet in a status report */
    double prb[3];           /* the last probe's contact, machine mm ($# PRB) */
    bool prb_ok;             /* ... and whether it touched */
    cs_ctlcfg_t ctl;         /* the machine file's [homing], [spindle] */
    bool homing;             /* a $H is running (status Home) */
    unsigned alarms_seen;    /* device ALARM events reported to the client */
    int sp_code;             /* the spindle the device was last told: GC_M3, GC_M4, GC_M5 */
    double sp_s;             /* ... and its S */
    bool in_reader;          /* a line is being read (a probe may be waiting on the device) */
    bool reset_pending;      /* Ctrl-X came meanwhile: the reset follows the line */
    bool probe_failed;       /* the line's G38.2/.4 ended in ALARM:5: its answer is ok */
} grbl_t;

/* Writes a line + "\r\n" to the client; a client that does not read loses it (never blocks). */
void cs_grbl_say(grbl_t *g, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Device steps of axis a -> mm. */
double cs_grbl_steps_mm(const grbl_t *g, int a, int32_t steps);
/* The reader and the next chunk start where the device last reported it is. */
void cs_grbl_sync(grbl_t *g);
/* Plans path (emptied) into a chunk and queues it, waiting for room; false when the planner
 * refused it (an alarm was raised). */
bool cs_grbl_queue_path(grbl_t *g, cs_path_t *path);
/* Queues a job of the n messages m (waiting for room) and, with wait, waits until the device
 * has run everything queued (client bytes keep being taken meanwhile: ? is answered). False when
 * the device failed (an alarm, an error) or the job could not be built. */
bool cs_grbl_run_msgs(grbl_t *g, const cs_proto_msg_t *m, size_t n, bool wait);

/* cs_grbl_ctl.c */
/* $H: every axis of [homing] order homed on the device; ok, or ALARM:N and error:9. */
void cs_grbl_home(grbl_t *g);
/* $X: the alarm cleared here and on the device (UNLOCK). */
void cs_grbl_unlock(grbl_t *g);
/* The reader's G38.x (cs_gcode_probe_fn; ctx is the grbl_t). */
cs_err_t cs_grbl_probe(void *ctx, int code, const double from[3], const double to[3],
                       double feed_mm_s, bool *contact, double hit[3]);
/* The reader's M3/M4/M5 and S (cs_gcode_spindle_fn; ctx is the grbl_t). */
cs_err_t cs_grbl_spindle(void *ctx, int code, double s);
/* Queues the pending moves as one chunk (laser mode: cs_grbl_laser_job). */
void cs_grbl_flush(grbl_t *g);
/* Laser mode ([spindle] laser = true): the plan's segments into job with a live SPINDLE before
 * the first segment of each power mark (off in rapids, S with the spindle override, M4's full
 * power at the moves' F), so power changes never stop the motion. CS_ERR_FULL / _RANGE as
 * cs_stream_job_add_segments. */
cs_err_t cs_grbl_laser_job(const grbl_t *g, const cs_motion_segs_t *sg, cs_stream_job_t *job);
/* "|Pn:XYZP" from the device's last inputs ("" when none is active). */
void cs_grbl_pins(const grbl_t *g, const cs_grbl_dev_snap_t *s, char *out, size_t cap);
/* The device raised an alarm since the last call: ALARM:N said, everything dropped. */
void cs_grbl_watch_alarm(grbl_t *g);

#endif
