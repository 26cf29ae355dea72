/* cs_modbus_stream: the host's Modbus link (docs/modbus.md). A libmodbus client (TCP or RTU)
 * that reads the device's status block, writes one SEGMENT or CURVE per FC16 mailbox write with
 * its sequence number, retries what timed out (the sequence makes a retry harmless: the device
 * answers OK and does not execute twice), goes back when the device refuses a gap, turns Modbus
 * exceptions into sentences, and streams a whole cs_stream job with the outcomes, counters and
 * progress display of the serial link (cs_stream). Host only. */
#ifndef CS_MODBUS_STREAM_H
#define CS_MODBUS_STREAM_H

#include <signal.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "cs_modbus.h"
#include "cs_stream.h"

/* Results of one request (after its retries). */
typedef enum {
    CS_MB_OK = 0,        /* answered normally */
    CS_MB_EXCEPTION = 1, /* answered with an exception (cs_mb_client_t.exception) */
    CS_MB_NO_ANSWER = 2, /* every try timed out or was garbled */
    CS_MB_IO = 3,        /* the connection or the line failed (errno in last_errno) */
} cs_mb_rc_t;

typedef struct {
    void *ctx; /* modbus_t */
    bool tcp;
    char where[160]; /* HOST:PORT or the device path, for messages */
    int unit;
    uint16_t token;      /* writer-lease token: mailbox writes carry it (0: none) */
    uint32_t timeout_ms; /* response timeout of one try */
    unsigned tries;      /* tries of one request before CS_MB_NO_ANSWER, >= 1 */
    int exception;       /* code of the last exception answer */
    int last_errno;      /* errno of the last failed try */
    /* counters */
    uint64_t requests;  /* tries sent */
    uint32_t timeouts;  /* tries that timed out */
    uint32_t garbled;   /* answers that did not fit the request (late, damaged): retried */
    uint32_t retries;   /* tries beyond the first of a request */
    uint64_t bytes_out; /* request frames sent (ADU bytes: MBAP + PDU, or unit + PDU + CRC) */
    uint64_t bytes_in;  /* answer frames received */
} cs_mb_client_t;

/* Opens a Modbus TCP client to "HOST:PORT" or an RTU client on the serial device dev at baud
 * with parity 'E' (8E1), 'O' (8O1) or 'N' (8N2: two stop bits without parity, Modbus over
 * serial line V1.02, 2.5.1), for unit. Timing: one try waits timeout_ms for the answer, tries
 * tries per request. Returns 0, or -1 with a sentence in why (-2: HOST:PORT is malformed or
 * parity is not one of N, E, O). */
int cs_mb_open_tcp(cs_mb_client_t *c, const char *hostport, int unit, uint32_t timeout_ms,
                   unsigned tries, char *why, size_t cap);
int cs_mb_open_rtu(cs_mb_client_t *c, const char *dev, uint32_t baud, char parity, int unit,
                   uint32_t timeout_ms, unsigned tries, char *why, size_t cap);
void cs_mb_close(cs_mb_client_t *c);
/* One try's answer timeout: 200 ms on TCP and on a pty (a loaded CI machine under ASan answers
 * well within it; the device answers within a few ms), plus on a real RTU line the time the
 * longest request and its answer take on the wire (11 bits a character). Six tries: a device
 * silent for about 1.2 s is declared gone. */
#define CS_MB_TIMEOUT_MS 200u
#define CS_MB_TRIES      6u
/* The client every command uses: TCP to tcp ("HOST:PORT") when it is not NULL, else RTU on the
 * device rtu at baud with parity (0: 'E') for unit, with the timing above; timeout_ms (0:
 * CS_MB_TIMEOUT_MS) is one try's wait before the line's own time (--modbus-timeout). As
 * cs_mb_open_*. */
int cs_mb_open_link(cs_mb_client_t *c, const char *tcp, const char *rtu, uint32_t baud, char parity,
                    int unit, uint32_t timeout_ms, char *why, size_t cap);

/* The device's input registers, decoded. */
typedef struct {
    uint16_t version, caps, axes, queue_size;
    uint32_t tick_hz, boot_id;
    uint16_t state, free_slots, last_exec, next_seq, error, error_seq, refused, refused_seq;
    int32_t pos[CS_AXES];
    uint16_t lease, lease_left_ms; /* 1: the mailbox is leased; ms until it expires */
} cs_mb_status_t;

cs_mb_rc_t cs_mb_read_status(cs_mb_client_t *c, cs_mb_status_t *st);
/* One mailbox write: FC16 of n registers at CS_MODBUS_HR_MAILBOX, or with c->token != 0 the
 * token and the n registers at CS_MODBUS_HR_TOKEN. */
cs_mb_rc_t cs_mb_write_mailbox(cs_mb_client_t *c, const uint16_t *regs, size_t n);
/* Claims or renews (claim) the writer lease with c->token, or gives it back (FC06 to LEASE or
 * RELEASE). CS_MB_EXCEPTION with exception 1: another client holds it. */
cs_mb_rc_t cs_mb_lease(cs_mb_client_t *c, bool claim);
/* How often the stream renews its lease when it has written nothing (the device keeps it
 * CS_FW_MODBUS_LEASE_MS, 5 s, after the last claim or write). */
#define CS_MB_LEASE_RENEW_MS 1000u
/* One command (FC06 to CS_MODBUS_HR_COMMAND). */
cs_mb_rc_t cs_mb_write_command(cs_mb_client_t *c, uint16_t cmd);
/* "illegal data value", ... for an exception code. */
const char *cs_mb_exception_text(int code);

typedef struct {
    cs_mb_client_t *c;
    uint8_t axes; /* the machine: the device must announce the same */
    uint32_t tick_hz;
    size_t resume_from;               /* messages 1..resume_from were executed already */
    volatile sig_atomic_t *interrupt; /* > 0: HOLD then ABORT; >= 2: at once */
    volatile sig_atomic_t *pause;     /* NULL: never; != 0: HOLD (queue kept), back to 0: RESUME */
    FILE *progress;                   /* NULL: none */
    bool progress_tty;
    uint32_t hello_ms;  /* the first status must come within this */
    uint32_t status_ms; /* poll the status at least this often while streaming (ms) */
    uint32_t idle_ms;   /* all delivered, device not running, not all executed: give up */
    uint32_t stall_ms;  /* no write taken, nothing executed, no axis moved this long (a pause
                         * excepted): give up */
} cs_mb_stream_opts_t;

/* Defaults: hello 2 s, status every 50 ms, idle 3 s, stall 30 s. */
void cs_mb_stream_opts_default(cs_mb_stream_opts_t *o, cs_mb_client_t *c, uint8_t axes,
                               uint32_t tick_hz);
/* Streams job messages resume_from+1..n; fills *r like cs_stream_run. It first claims the
 * writer lease with a fresh token (a lease another client holds is waited out once, for the
 * time the device says it has left, then CS_STREAM_DEVICE_ERROR with dev_error.code
 * CS_ERR_LEASED), renews it while it streams and gives it back at the end. Never waits without a
 * deadline: a device whose next sequence runs ahead of what this host wrote (another Modbus
 * client wrote to the mailbox) ends it at once as CS_STREAM_DEVICE_ERROR (dev_error.code
 * CS_ERR_SEQ); no progress for stall_ms ends it as CS_STREAM_CLOSED, with the reason in r->why
 * (r->hello from the status block: version = map version; r->link.retransmits = writes sent again
 * (timeouts, garbled answers, going back after a refused gap), r->link.timeouts = tries that timed
 * out, r->link.naks = mailbox writes the device refused and the host sent again (busy, gap)). CS_OK
 * when it ran to an outcome, CS_ERR_ARG for bad options. */
cs_err_t cs_mb_stream_run(const cs_stream_job_t *job, const cs_mb_stream_opts_t *o,
                          cs_stream_result_t *r);

#endif
