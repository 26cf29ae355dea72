/* cs_grbl_link: the Grbl front end's device over the links other than the serial wire protocol
 * (cs_joblink: --modbus-tcp, --modbus-rtu, --gpio). cs_grbl_dev's worker hands it each queued
 * item; it runs a chunk of step segments through cs_joblink (opened for the item and closed
 * after it, as the daemon runs a job), plans a $J= jog here as a straight move (the JOG message
 * is the serial device's own), and carries out $H, G38.x and $X on GPIO with cs_gpio_ctl (the
 * device's rules on the host's step thread), reporting what the serial device would say in its
 * EVENTs (ALARM, PROBE, the inputs) through the caller's event function. What a link cannot do
 * is refused before it is queued (cs_grbl_link_can). Host only. */
#ifndef CS_GRBL_LINK_H
#define CS_GRBL_LINK_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_ctlcfg.h"
#include "cs_joblink.h"
#include "cs_machine.h"
#include "cs_proto.h"
#include "cs_stream.h"

typedef void (*cs_grbl_link_event_fn)(void *ctx, const cs_proto_event_t *ev);

typedef struct {
    cs_joblink_t l;
    const cs_machine_t *m;
    const cs_ctlcfg_t *ctl; /* [homing] */
    bool gpio;
    volatile sig_atomic_t *stop; /* > 0: a GPIO control command stops at once (cancel) */
    /* the running chunk on GPIO, for its position now (worker thread only) */
    bool running;
    size_t sum_k;                   /* segments summed into sum */
    int32_t sum[CS_PROTO_AXES_MAX]; /* steps: where the chunk started, plus those segments */
    uint32_t ticks; /* the step thread's clock: ticks of every segment it executed (wraps) */
} cs_grbl_link_t;

/* Picks the link of cfg for machine m with [homing] ctl (both outlive k) and reads where the
 * machine stands: *pos (steps; the device's registers on Modbus, the GPIO state file's
 * position when inputs are wired, else 0) and *alarm (the GPIO state's, else 0). stop: see
 * cs_grbl_link_t. CS_EXIT_OK, or an exit status with one sentence in why. */
int cs_grbl_link_start(cs_grbl_link_t *k, const cs_joblink_cfg_t *cfg, const cs_machine_t *m,
                       const cs_ctlcfg_t *ctl, volatile sig_atomic_t *stop,
                       int32_t pos[CS_PROTO_AXES_MAX], uint8_t *alarm, char *why, size_t cap);
/* True when the link carries a message of type t (CS_PROTO_HOME, _PROBE, _SPINDLE, _JOG...). */
bool cs_grbl_link_can(const cs_grbl_link_t *k, uint8_t t);
/* "Modbus", "GPIO" (messages). */
const char *cs_grbl_link_kind(const cs_grbl_link_t *k);
/* Runs one item (a chunk of SEGMENTs, a JOG, HOMEs, a PROBE, an UNLOCK) from the machine
 * position pos (steps), steered by c; fills *r (dev_pos: where the machine stands after it)
 * and says alarms, probe results and inputs through ev(ev_ctx, ...). Worker thread. CS_OK, or
 * an error of the run itself. */
cs_err_t cs_grbl_link_run(cs_grbl_link_t *k, const cs_stream_job_t *job,
                          const int32_t pos[CS_PROTO_AXES_MAX], const cs_joblink_ctl_t *c,
                          cs_stream_result_t *r, cs_grbl_link_event_fn ev, void *ev_ctx);
/* While a GPIO chunk runs: its position now into r->dev_pos (whole segments executed by the
 * step thread), the step thread's time of it into r->dev_tick (r->dev_timed: the segments'
 * ticks summed, so the speed is the executed one) and r->dev_state (HELD once a pause is at
 * rest). Nothing on Modbus: its run
 * fills r from the device's registers. Worker thread (from the run's progress output). */
void cs_grbl_link_where(cs_grbl_link_t *k, cs_stream_result_t *r);

#endif
