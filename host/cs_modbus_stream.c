/* cs_modbus_stream: libmodbus client and the Modbus streaming loop. See cs_modbus_stream.h and
 * docs/modbus.md. */
#include "cs_modbus_stream.h"

#include <errno.h>
#include <modbus/modbus.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cs_linktime.h"
#include "cs_serial.h"

/* --- client --------------------------------------------------------------------------------- */

static void set_timing(cs_mb_client_t *c, uint32_t timeout_ms, unsigned tries)
{
    c->timeout_ms = timeout_ms ? timeout_ms : 200;
    c->tries = tries ? tries : 1;
    modbus_t *ctx = c->ctx;
    modbus_set_response_timeout(ctx, c->timeout_ms / 1000u, (c->timeout_ms % 1000u) * 1000u);
    /* the bytes of one answer follow each other: a gap of 50 ms inside one means it is cut */
    modbus_set_byte_timeout(ctx, 0, 50000);
    modbus_set_slave(ctx, c->unit);
}

int cs_mb_open_tcp(cs_mb_client_t *c, const char *hostport, int unit, uint32_t timeout_ms,
                   unsigned tries, char *why, size_t cap)
{
    memset(c, 0, sizeof *c);
    c->tcp = true;
    c->unit = unit;
    snprintf(c->where, sizeof c->where, "%s", hostport);
    char host[128];
    const char *colon = strrchr(hostport, ':');
    char *end = NULL;
    long port = colon ? strtol(colon + 1, &end, 10) : -1;
    if (colon == NULL || colon == hostport || (size_t)(colon - hostport) >= sizeof host ||
        colon[1] == '\0' || *end != '\0' || port < 1 || port > 65535) {
        snprintf(why, cap, "--modbus-tcp wants HOST:PORT (an IPv4 address and a port), not '%s'",
                 hostport);
        return -2;
    }
    memcpy(host, hostport, (size_t)(colon - hostport));
    host[colon - hostport] = '\0';
    /* a name or an address (IPv6 in brackets: [::1]:1502), resolved by libmodbus */
    size_t hl = strlen(host);
    if (hl >= 2 && host[0] == '[' && host[hl - 1] == ']') {
        memmove(host, host + 1, hl - 2);
        host[hl - 2] = '\0';
    }
    modbus_t *ctx = modbus_new_tcp_pi(host, colon + 1);
    if (ctx == NULL) {
        snprintf(why, cap, "%s: %s", hostport, modbus_strerror(errno));
        return -1;
    }
    c->ctx = ctx;
    set_timing(c, timeout_ms, tries);
    if (modbus_connect(ctx) != 0) {
        snprintf(why, cap, "%s: cannot connect: %s", hostport, modbus_strerror(errno));
        modbus_free(ctx);
        c->ctx = NULL;
        return -1;
    }
    return 0;
}

int cs_mb_open_rtu(cs_mb_client_t *c, const char *dev, uint32_t baud, char parity, int unit,
                   uint32_t timeout_ms, unsigned tries, char *why, size_t cap)
{
    memset(c, 0, sizeof *c);
    c->tcp = false;
    c->unit = unit;
    snprintf(c->where, sizeof c->where, "%s", dev);
    if (parity != 'N' && parity != 'E' && parity != 'O') {
        snprintf(why, cap, "%s: parity must be N, E or O", dev);
        return -2;
    }
    /* every character is 11 bits: start, 8 data, parity, stop; without parity a second stop
     * bit takes the parity bit's place (Modbus over serial line V1.02, 2.5.1) */
    modbus_t *ctx = modbus_new_rtu(dev, (int)baud, parity, 8, parity == 'N' ? 2 : 1);
    if (ctx == NULL) {
        snprintf(why, cap, "%s: %s", dev, modbus_strerror(errno));
        return -1;
    }
    c->ctx = ctx;
    set_timing(c, timeout_ms, tries);
    if (modbus_connect(ctx) != 0) {
        snprintf(why, cap, "%s: cannot open: %s", dev, modbus_strerror(errno));
        modbus_free(ctx);
        c->ctx = NULL;
        return -1;
    }
    modbus_flush(ctx); /* stale bytes from an earlier session */
    return 0;
}

void cs_mb_close(cs_mb_client_t *c)
{
    if (c->ctx) {
        modbus_close(c->ctx);
        modbus_free(c->ctx);
        c->ctx = NULL;
    }
}

const char *cs_mb_exception_text(int code)
{
    switch (code) {
    case 1:
        return "illegal function";
    case 2:
        return "illegal data address";
    case 3:
        return "illegal data value";
    case 4:
        return "server device failure";
    case 5:
        return "acknowledge";
    case 6:
        return "server device busy";
    case 8:
        return "memory parity error";
    case 10:
        return "gateway path unavailable";
    case 11:
        return "gateway target device failed to respond";
    default:
        return "unknown exception";
    }
}

static size_t adu(const cs_mb_client_t *c, size_t pdu)
{
    return pdu + (c->tcp ? 7u : 3u);
}

/* One request with its retries. op: 0 read input, 1 write registers, 2 write register. */
static cs_mb_rc_t request(cs_mb_client_t *c, int op, int addr, int nb, const uint16_t *src,
                          uint16_t *dst)
{
    modbus_t *ctx = c->ctx;
    size_t req_pdu = op == 0 ? 5 : op == 1 ? 6 + 2 * (size_t)nb : 5;
    size_t rsp_pdu = op == 0 ? 2 + 2 * (size_t)nb : 5;
    for (unsigned t = 0; t < c->tries; t++) {
        if (t > 0)
            c->retries++;
        c->requests++;
        c->bytes_out += adu(c, req_pdu);
        int rc = op == 0   ? modbus_read_input_registers(ctx, addr, nb, dst)
                 : op == 1 ? modbus_write_registers(ctx, addr, nb, src)
                           : modbus_write_register(ctx, addr, src[0]);
        if (rc >= 0) {
            c->bytes_in += adu(c, rsp_pdu);
            return CS_MB_OK;
        }
        int err = errno;
        c->last_errno = err;
        if (err > MODBUS_ENOBASE && err <= EMBXGTAR) {
            c->exception = err - MODBUS_ENOBASE;
            c->bytes_in += adu(c, 2);
            return CS_MB_EXCEPTION;
        }
        if (err == ETIMEDOUT) {
            c->timeouts++;
        } else if (err == EMBBADDATA || err == EMBBADCRC || err == EMBBADSLAVE || err == EMBMDATA ||
                   err == EMBBADEXC || err == EMBUNKEXC) {
            /* an answer that is not this request's (a late one, a damaged one) */
            c->garbled++;
        } else if (c->tcp && (err == ECONNRESET || err == EPIPE || err == ENOTCONN ||
                              err == EBADF || err == ECONNREFUSED)) {
            /* the connection broke: connect again once; the sequence makes the retry safe */
            modbus_close(ctx);
            if (modbus_connect(ctx) != 0)
                return CS_MB_IO;
            continue;
        } else if (err == EIO || err == EBADF || err == ENXIO) {
            return CS_MB_IO;
        } else {
            c->garbled++;
        }
        /* whatever is left of a late or damaged answer must not be read as the next one: let
         * the answer still on its way (this try's, after a late one of an earlier try) arrive,
         * then drop it all and ask again */
        if (err != ETIMEDOUT) {
            struct timespec ts = {0, 20L * 1000000L};
            nanosleep(&ts, NULL);
        }
        modbus_flush(ctx);
    }
    return CS_MB_NO_ANSWER;
}

static int32_t s32(const uint16_t *r)
{
    uint32_t u = ((uint32_t)r[0] << 16) | r[1];
    return u <= 0x7FFFFFFFu ? (int32_t)u : -(int32_t)(0xFFFFFFFFu - u) - 1;
}

cs_mb_rc_t cs_mb_read_status(cs_mb_client_t *c, cs_mb_status_t *st)
{
    uint16_t ir[CS_MODBUS_IR_COUNT];
    cs_mb_rc_t rc = request(c, 0, 0, CS_MODBUS_IR_COUNT, NULL, ir);
    if (rc != CS_MB_OK)
        return rc;
    st->version = ir[CS_MODBUS_IR_VERSION];
    st->caps = ir[CS_MODBUS_IR_CAPS];
    st->axes = ir[CS_MODBUS_IR_AXES];
    st->queue_size = ir[CS_MODBUS_IR_QUEUE_SIZE];
    st->tick_hz = (uint32_t)s32(ir + CS_MODBUS_IR_TICK_HZ);
    st->boot_id = (uint32_t)s32(ir + CS_MODBUS_IR_BOOT_ID);
    st->state = ir[CS_MODBUS_IR_STATE];
    st->free_slots = ir[CS_MODBUS_IR_FREE];
    st->last_exec = ir[CS_MODBUS_IR_LAST_EXEC];
    st->next_seq = ir[CS_MODBUS_IR_NEXT_SEQ];
    st->error = ir[CS_MODBUS_IR_ERROR];
    st->error_seq = ir[CS_MODBUS_IR_ERROR_SEQ];
    st->refused = ir[CS_MODBUS_IR_REFUSED];
    st->refused_seq = ir[CS_MODBUS_IR_REFUSED_SEQ];
    for (unsigned i = 0; i < CS_AXES; i++)
        st->pos[i] = s32(ir + CS_MODBUS_IR_POS + 2 * i);
    st->lease = ir[CS_MODBUS_IR_LEASE];
    st->lease_left_ms = ir[CS_MODBUS_IR_LEASE_LEFT];
    return CS_MB_OK;
}

cs_mb_rc_t cs_mb_write_mailbox(cs_mb_client_t *c, const uint16_t *regs, size_t n)
{
    if (c->token == 0 || n > CS_MODBUS_MAILBOX_REGS)
        return request(c, 1, CS_MODBUS_HR_MAILBOX, (int)n, regs, NULL);
    uint16_t with[1 + CS_MODBUS_MAILBOX_REGS]; /* the token just before the mailbox */
    with[0] = c->token;
    memcpy(with + 1, regs, n * sizeof *regs);
    return request(c, 1, CS_MODBUS_HR_TOKEN, (int)n + 1, with, NULL);
}

cs_mb_rc_t cs_mb_lease(cs_mb_client_t *c, bool claim)
{
    return request(c, 2, claim ? CS_MODBUS_HR_LEASE : CS_MODBUS_HR_RELEASE, 1, &c->token, NULL);
}

cs_mb_rc_t cs_mb_write_command(cs_mb_client_t *c, uint16_t cmd)
{
    return request(c, 2, CS_MODBUS_HR_COMMAND, 1, &cmd, NULL);
}

int cs_mb_open_link(cs_mb_client_t *c, const char *tcp, const char *rtu, uint32_t baud, char parity,
                    int unit, uint32_t timeout_ms, char *why, size_t cap)
{
    uint32_t timeout = timeout_ms != 0 ? timeout_ms : CS_MB_TIMEOUT_MS;
    if (tcp != NULL)
        return cs_mb_open_tcp(c, tcp, unit, timeout, CS_MB_TRIES, why, cap);
    if (strncmp(rtu, "/dev/pts/", 9) != 0 && baud > 0) {
        /* request of CS_MODBUS_MAILBOX_REGS registers + its answer, 11 bits a byte */
        uint32_t bytes = 9u + 2u * CS_MODBUS_MAILBOX_REGS + 8u;
        timeout += cs_linktime_chars(bytes, CS_LINKTIME_BITS_RTU, baud, 1000u);
    }
    return cs_mb_open_rtu(c, rtu, baud, parity != 0 ? parity : 'E', unit, timeout, CS_MB_TRIES, why,
                          cap);
}

/* --- streaming ------------------------------------------------------------------------------ */

void cs_mb_stream_opts_default(cs_mb_stream_opts_t *o, cs_mb_client_t *c, uint8_t axes,
                               uint32_t tick_hz)
{
    memset(o, 0, sizeof *o);
    o->c = c;
    o->axes = axes;
    o->tick_hz = tick_hz;
    o->hello_ms = 2000;
    o->status_ms = 50;
    o->idle_ms = 3000;
    /* far above one segment (a few ms) or one curve's wait for the queue, far below "forever" */
    o->stall_ms = 30000;
}

typedef struct {
    const cs_stream_job_t *job;
    const cs_mb_stream_opts_t *o;
    cs_stream_result_t *r;
    cs_mb_client_t *c;
    uint16_t base;      /* sequence of job message resume_from + 1 */
    uint16_t exec_seq;  /* last executed sequence seen */
    size_t next;        /* job index of the next message to write */
    uint16_t credits;   /* free slots as far as the host knows */
    double last_status; /* when the status was read last */
    cs_mb_status_t st;
    bool stop;
    cs_stream_progress_t prog;
    double t_first;
    uint32_t resent, refused;
    bool held;         /* HOLD sent for o->pause, RESUME not yet */
    double t_progress; /* last write taken, message executed or axis moved (stall_ms) */
    double t_lease;    /* last claim or mailbox write that renewed the lease (0: none held) */
} mrun_t;

static void finish(mrun_t *s, cs_stream_outcome_t oc)
{
    if (!s->stop) {
        s->r->outcome = oc;
        s->stop = true;
    }
}

static void sleep_ms(double ms)
{
    struct timespec ts = {(time_t)(ms / 1000), (long)((ms - 1000.0 * (time_t)(ms / 1000)) * 1e6)};
    nanosleep(&ts, NULL);
}

static const char *what(const mrun_t *s)
{
    return s->job->mode == CS_STREAM_CURVES ? "curves" : "segments";
}

static void lost(mrun_t *s, cs_mb_rc_t rc, const char *doing)
{
    cs_mb_client_t *c = s->c;
    if (rc == CS_MB_IO)
        snprintf(s->r->why, sizeof s->r->why, "%s: %s", doing,
                 c->tcp ? "the connection broke" : "the line failed");
    else
        snprintf(s->r->why, sizeof s->r->why,
                 "unit %d stopped answering (%s: %u tries of %u ms without a valid answer)",
                 c->unit, doing, c->tries, (unsigned)c->timeout_ms);
    finish(s, CS_STREAM_CLOSED);
}

/* True (and the outcome set) when nothing moved for o->stall_ms: no write taken, no message
 * executed, no axis moved (a foreign HOLD, a device that refuses everything): never wait on. */
static bool stalled(mrun_t *s, double now)
{
    if (s->held) /* our own pause (a feed hold): at rest for as long as the operator wants */
        s->t_progress = now;
    if (s->o->stall_ms == 0 || now - s->t_progress <= s->o->stall_ms / 1000.0)
        return false;
    snprintf(s->r->why, sizeof s->r->why,
             "no progress for %.0f s: the device took no message, executed none and moved no "
             "axis (state %u; another client may hold it)",
             now - s->t_progress, (unsigned)s->st.state);
    finish(s, CS_STREAM_CLOSED);
    return true;
}

/* A token for this job's lease: the clock's nanoseconds and the process id, folded to 16 bits,
 * never 0 (0 means "no token"). Two hosts picking the same one: 1 in 65535. */
static uint16_t new_token(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    uint32_t h =
        (uint32_t)ts.tv_nsec * 2654435761u ^ (uint32_t)getpid() * 40503u ^ (uint32_t)ts.tv_sec;
    uint16_t t = (uint16_t)(h ^ (h >> 16));
    return t != 0 ? t : 1u;
}

static void lease_refused(mrun_t *s, const char *doing)
{
    s->r->dev_error.code = CS_ERR_LEASED;
    s->r->dev_error_msg = s->next + 1;
    snprintf(s->r->why, sizeof s->r->why,
             "%s: another Modbus client holds the writer lease (it ends %u ms after that "
             "client's last write unless renewed)",
             doing, (unsigned)s->st.lease_left_ms);
    finish(s, CS_STREAM_DEVICE_ERROR);
}

/* Claims the writer lease before the first write. A lease another client holds (a host that
 * just died, a panel) is waited out once, for the time the device says is left plus a second;
 * then the stream stops (exit 7) rather than wait on. A map without a lease (exception 2 to
 * LEASE) is written without a token. */
static void claim_lease(mrun_t *s)
{
    s->c->token = new_token();
    double deadline = 0;
    for (;;) {
        cs_mb_rc_t rc = cs_mb_lease(s->c, true);
        if (rc == CS_MB_OK) {
            s->t_lease = cs_serial_now_s();
            return;
        }
        if (rc != CS_MB_EXCEPTION) {
            lost(s, rc, "claiming the writer lease");
            return;
        }
        if (s->c->exception == CS_MODBUS_EX_ILLEGAL_ADDRESS) {
            s->c->token = 0; /* a map without a lease (its application has none): write as is */
            return;
        }
        rc = cs_mb_read_status(s->c, &s->st);
        if (rc != CS_MB_OK) {
            lost(s, rc, "reading the status");
            return;
        }
        double now = cs_serial_now_s();
        if (deadline == 0)
            deadline = now + s->st.lease_left_ms / 1000.0 + 1.0;
        if (s->o->interrupt != NULL && *s->o->interrupt) {
            finish(s, CS_STREAM_INTERRUPTED); /* nothing was sent: nothing to stop */
            return;
        }
        if (now >= deadline) {
            lease_refused(s, "claiming the writer lease");
            return;
        }
        sleep_ms(100);
    }
}

/* Renews the lease when nothing renewed it for CS_MB_LEASE_RENEW_MS (the queue draining, a
 * pause): false (and the outcome set) when it was lost or the device stopped answering. */
static bool renew_lease(mrun_t *s, double now)
{
    if (s->t_lease == 0 || now - s->t_lease < CS_MB_LEASE_RENEW_MS / 1000.0)
        return true;
    cs_mb_rc_t rc = cs_mb_lease(s->c, true);
    if (rc == CS_MB_OK) {
        s->t_lease = now;
        return true;
    }
    if (rc == CS_MB_EXCEPTION) {
        (void)cs_mb_read_status(s->c, &s->st);
        lease_refused(s, "renewing the writer lease");
    } else {
        lost(s, rc, "renewing the writer lease");
    }
    return false;
}

/* Reads the status and follows it: executed count, credits, the device's next sequence (going
 * back when a write the host believed taken never arrived), a reset, an execution error.
 * Returns false when the stream must stop. */
static bool poll_status(mrun_t *s)
{
    cs_mb_status_t st;
    cs_mb_rc_t rc = cs_mb_read_status(s->c, &st);
    s->last_status = cs_serial_now_s();
    if (rc == CS_MB_EXCEPTION) {
        snprintf(s->r->why, sizeof s->r->why, "the status read got Modbus exception %d (%s)",
                 s->c->exception, cs_mb_exception_text(s->c->exception));
        s->r->dev_error.code = CS_ERR_UNSUPPORTED;
        finish(s, CS_STREAM_DEVICE_ERROR);
        return false;
    }
    if (rc != CS_MB_OK) {
        lost(s, rc, "reading the status");
        return false;
    }
    cs_stream_result_t *r = s->r;
    if (st.boot_id != s->st.boot_id) {
        r->old_boot = s->st.boot_id;
        r->new_boot = st.boot_id;
        r->unacked = (uint16_t)(r->sent - r->executed);
        s->st = st;
        finish(s, CS_STREAM_RESET);
        return false;
    }
    if (memcmp(st.pos, s->st.pos, sizeof st.pos) != 0)
        s->t_progress = cs_serial_now_s(); /* an axis moved */
    s->st = st;
    r->dev_state = (uint8_t)st.state;
    for (unsigned i = 0; i < CS_PROTO_AXES_MAX; i++)
        r->dev_pos[i] = i < st.axes && i < CS_AXES ? st.pos[i] : 0;
    uint16_t d = (uint16_t)(st.last_exec - s->exec_seq);
    if (d != 0 && d <= r->sent - r->executed) {
        s->t_progress = cs_serial_now_s();
        r->executed += d;
        s->exec_seq = st.last_exec;
    }
    /* the device's next sequence behind ours: writes believed taken never arrived (a stale
     * answer was taken for theirs): send them again from there */
    uint16_t ours = (uint16_t)(s->base + (s->next - s->o->resume_from));
    uint16_t behind = (uint16_t)(ours - st.next_seq);
    uint16_t ahead = (uint16_t)(st.next_seq - ours);
    if (behind != 0 && behind <= s->next - r->executed) {
        s->next -= behind;
        s->resent += behind;
        r->delivered = s->next;
    } else if (ahead != 0 && ahead <= r->sent - s->next) {
        /* after going back on a stale status: the device had them all */
        s->next += ahead;
        r->delivered = s->next;
    } else if (ahead != 0 && ahead < 0x8000u) {
        /* ahead of anything this host wrote: another client wrote to the mailbox, and the
         * device queued (and may have run) a message that is not the job's. Retrying would be
         * refused forever (the sequence is taken) and the machine is no longer where the job
         * thinks: stop, and say why. */
        r->dev_error.code = CS_ERR_SEQ;
        r->dev_error.seq = st.next_seq;
        r->dev_error_msg = s->next + 1;
        snprintf(r->why, sizeof r->why,
                 "the device's next sequence is %u ahead of this host's: another Modbus client "
                 "wrote to the mailbox (the machine may have moved)",
                 (unsigned)ahead);
        finish(s, CS_STREAM_DEVICE_ERROR);
        return false;
    }
    s->credits = st.free_slots;
    if (st.error != 0) {
        r->dev_error.code = (uint8_t)st.error;
        r->dev_error.seq = st.error_seq;
        uint16_t k = (uint16_t)(st.error_seq - s->base);
        r->dev_error_msg = k < r->sent - s->o->resume_from ? s->o->resume_from + k + 1 : 0;
        finish(s, CS_STREAM_DEVICE_ERROR);
        return false;
    }
    return true;
}

/* Writes a command and polls until the state is want_a or want_b or wait_ms passed. */
static void control(mrun_t *s, uint16_t cmd, uint16_t want_a, uint16_t want_b, uint32_t wait_ms)
{
    double t_end = cs_serial_now_s() + wait_ms / 1000.0;
    if (cs_mb_write_command(s->c, cmd) != CS_MB_OK)
        return;
    while (cs_serial_now_s() < t_end) {
        cs_mb_status_t st;
        if (cs_mb_read_status(s->c, &st) != CS_MB_OK)
            return;
        s->r->dev_state = (uint8_t)st.state;
        for (unsigned i = 0; i < CS_PROTO_AXES_MAX; i++)
            s->r->dev_pos[i] = i < st.axes && i < CS_AXES ? st.pos[i] : 0;
        uint16_t d = (uint16_t)(st.last_exec - s->exec_seq);
        if (d != 0 && d <= s->r->sent - s->r->executed) {
            s->r->executed += d;
            s->exec_seq = st.last_exec;
        }
        if (st.state == want_a || st.state == want_b)
            return;
        if (s->o->interrupt != NULL && *s->o->interrupt >= 2)
            return;
        sleep_ms(5);
    }
}

/* Writes job message s->next. Returns false when the stream must stop. */
static bool write_next(mrun_t *s)
{
    cs_stream_result_t *r = s->r;
    uint16_t regs[CS_MODBUS_MAILBOX_REGS];
    size_t n;
    uint16_t seq = (uint16_t)(s->base + (s->next - s->o->resume_from));
    cs_err_t e =
        cs_modbus_mailbox_encode(&s->job->v[s->next], seq, regs, CS_MODBUS_MAILBOX_REGS, &n);
    if (e != CS_OK) { /* the planner made it: cannot happen; say so rather than skip it */
        r->dev_error.code = (uint8_t)e;
        r->dev_error_msg = s->next + 1;
        snprintf(r->why, sizeof r->why, "cannot encode it for the mailbox");
        finish(s, CS_STREAM_DEVICE_ERROR);
        return false;
    }
    cs_mb_rc_t rc = cs_mb_write_mailbox(s->c, regs, n);
    if (rc == CS_MB_OK) {
        s->t_progress = cs_serial_now_s();
        s->t_lease = s->t_progress; /* a write carrying the token renews the lease */
        s->next++;
        if (s->next > r->sent)
            r->sent = s->next;
        r->delivered = s->next;
        if (s->credits > 0)
            s->credits--;
        return true;
    }
    if (rc != CS_MB_EXCEPTION) {
        char doing[64];
        snprintf(doing, sizeof doing, "writing %s no. %zu", s->job->mode ? "curve" : "segment",
                 s->next + 1);
        lost(s, rc, doing);
        return false;
    }
    int ex = s->c->exception;
    if (ex == CS_MODBUS_EX_DEVICE_BUSY) { /* queue full: nothing taken, ask again later */
        s->refused++;
        s->credits = 0;
        return true;
    }
    /* why: the device's REFUSED register */
    if (!poll_status(s))
        return false;
    if (ex == CS_MODBUS_EX_ILLEGAL_VALUE && s->st.refused == CS_ERR_SEQ &&
        s->st.refused_seq == seq) {
        /* a gap or a stale sequence: poll_status went to the device's next sequence */
        s->refused++;
        return true;
    }
    r->dev_error.code =
        (uint8_t)(s->st.refused_seq == seq && s->st.refused != 0 ? s->st.refused
                                                                 : CS_ERR_UNSUPPORTED);
    r->dev_error.seq = seq;
    r->dev_error_msg = s->next + 1;
    snprintf(r->why, sizeof r->why, "Modbus exception %d (%s)", ex, cs_mb_exception_text(ex));
    finish(s, CS_STREAM_DEVICE_ERROR);
    return false;
}

/* Phase 1: the status block, the device's identity (the serial link's HELLO), read until it
 * answers or o->hello_ms pass; NO_DEVICE or INCOMPATIBLE with the reason in r->why. */
static void mb_connect(mrun_t *s, double t0)
{
    const cs_mb_stream_opts_t *o = s->o;
    cs_stream_result_t *r = s->r;
    const cs_mb_status_t *st = &s->st;
    cs_mb_rc_t rc;
    do {
        rc = cs_mb_read_status(s->c, &s->st);
    } while (rc == CS_MB_NO_ANSWER && cs_serial_now_s() - t0 < o->hello_ms / 1000.0 &&
             !(o->interrupt && *o->interrupt));
    if (rc == CS_MB_IO) {
        snprintf(r->why, sizeof r->why, "the %s failed", s->c->tcp ? "connection" : "line");
        finish(s, CS_STREAM_NO_DEVICE);
    } else if (rc == CS_MB_NO_ANSWER) {
        snprintf(r->why, sizeof r->why,
                 "no answer from unit %d: %u tries in %.1f s; is --unit right, and is a "
                 "curvestep device there?",
                 s->c->unit, (unsigned)s->c->requests, cs_serial_now_s() - t0);
        finish(s, CS_STREAM_NO_DEVICE);
    } else if (rc == CS_MB_EXCEPTION) {
        snprintf(r->why, sizeof r->why,
                 "unit %d answered the status read with Modbus exception %d (%s): not a "
                 "curvestep register map",
                 s->c->unit, s->c->exception, cs_mb_exception_text(s->c->exception));
        finish(s, CS_STREAM_INCOMPATIBLE);
    } else {
        r->hello.version = (uint8_t)st->version;
        r->hello.boot_id = st->boot_id;
        r->hello.axes = (uint8_t)st->axes;
        r->hello.queue_size = st->queue_size;
        r->hello.tick_hz = st->tick_hz;
        r->hello.caps = st->caps;
        if (st->version != CS_MODBUS_MAP_VERSION)
            snprintf(r->why, sizeof r->why, "register map version %u, this host reads %u",
                     (unsigned)st->version, (unsigned)CS_MODBUS_MAP_VERSION);
        else
            (void)cs_stream_hello_mismatch(&r->hello, o->axes, o->tick_hz, s->job->mode, r->why,
                                           sizeof r->why);
        if (r->why[0] != '\0')
            finish(s, CS_STREAM_INCOMPATIBLE);
    }
}

/* Clears an error an earlier job left, and starts the sequence at the device's next one. */
static void mb_prepare(mrun_t *s)
{
    const cs_mb_status_t *st = &s->st;
    if (!s->stop && (st->error != 0 || st->state == CS_PROTO_STATE_FAULT)) {
        /* an error left by an earlier job: clear it, or it would stop this one at once */
        if (cs_mb_write_command(s->c, CS_MODBUS_CMD_RESET) != CS_MB_OK ||
            cs_mb_read_status(s->c, &s->st) != CS_MB_OK) {
            lost(s, CS_MB_NO_ANSWER, "resetting an earlier error");
        }
    }
    if (!s->stop)
        claim_lease(s);
    s->base = st->next_seq;
    s->exec_seq = (uint16_t)(st->next_seq - 1u);
    s->credits = st->free_slots;
    s->last_status = cs_serial_now_s();
    s->t_progress = s->last_status;
}

/* The user's interrupt (HOLD then ABORT; at once on a second one) and the daemon's pause (HOLD
 * / RESUME, the queue kept). Returns true when the run must stop. */
static bool mb_controls(mrun_t *s, double *t_all_sent)
{
    const cs_mb_stream_opts_t *o = s->o;
    if (o->interrupt != NULL && *o->interrupt) {
        if (*o->interrupt < 2) {
            control(s, CS_MODBUS_CMD_HOLD, CS_PROTO_STATE_HELD, CS_PROTO_STATE_IDLE, 2000);
            control(s, CS_MODBUS_CMD_ABORT, CS_PROTO_STATE_ABORTED, CS_PROTO_STATE_IDLE, 2000);
        }
        finish(s, CS_STREAM_INTERRUPTED);
        return true;
    }
    if (o->pause != NULL && (*o->pause != 0) != s->held) {
        s->held = !s->held;
        control(s, s->held ? CS_MODBUS_CMD_HOLD : CS_MODBUS_CMD_RESUME,
                s->held ? CS_PROTO_STATE_HELD : CS_PROTO_STATE_RUNNING, CS_PROTO_STATE_IDLE, 2000);
        if (s->held &&
            (s->r->dev_state == CS_PROTO_STATE_HELD || s->r->dev_state == CS_PROTO_STATE_IDLE))
            cs_stream_progress_held(o->progress, s->r->executed, s->job->n, what(s));
        *t_all_sent = 0;
    }
    return false;
}

/* Once everything is written: DONE when the device reports the last message executed and is
 * no longer running, CLOSED when it stays idle without that for o->idle_ms. */
static void mb_check_end(mrun_t *s, double *t_all_sent)
{
    cs_stream_result_t *r = s->r;
    if (s->next < s->job->n) {
        *t_all_sent = 0;
        return;
    }
    if (*t_all_sent == 0)
        *t_all_sent = cs_serial_now_s();
    if (r->executed == s->job->n && s->st.state != CS_PROTO_STATE_RUNNING) {
        finish(s, CS_STREAM_DONE);
        return;
    }
    if (s->st.state == CS_PROTO_STATE_RUNNING || s->st.state == CS_PROTO_STATE_HELD)
        *t_all_sent = cs_serial_now_s();
    else if (cs_serial_now_s() - *t_all_sent > s->o->idle_ms / 1000.0) {
        snprintf(r->why, sizeof r->why,
                 "everything was delivered but the device reports %zu executed", r->executed);
        finish(s, CS_STREAM_CLOSED);
    }
}

/* Phase 2: writes while there are credits, polls the status, until an outcome. */
static void mb_stream(mrun_t *s)
{
    const cs_mb_stream_opts_t *o = s->o;
    const cs_stream_job_t *job = s->job;
    s->t_first = cs_serial_now_s();
    s->prog.t_first = s->t_first;
    double t_all_sent = 0;
    while (!s->stop) {
        if (mb_controls(s, &t_all_sent))
            break;
        double now = cs_serial_now_s();
        if (stalled(s, now) || !renew_lease(s, now))
            break;
        bool wrote = false;
        if (s->next < job->n && s->credits > 0) {
            if (!write_next(s))
                break;
            wrote = true;
        }
        if (s->credits == 0 || s->next >= job->n || now - s->last_status >= o->status_ms / 1000.0) {
            if (!wrote && (s->credits == 0 || s->next >= job->n))
                sleep_ms(1); /* waiting for the queue to drain: do not spin on the link */
            if (!poll_status(s))
                break;
        }
        cs_stream_progress(&s->prog, o->progress, o->progress_tty, false, job->n, s->r->executed,
                           s->r->sent, o->resume_from, s->c->retries + s->resent, what(s));
        mb_check_end(s, &t_all_sent);
    }
}

/* Phase 3: aborts after a device error, the last progress line, the counters. */
static void mb_finish(mrun_t *s, double t0)
{
    const cs_mb_stream_opts_t *o = s->o;
    cs_stream_result_t *r = s->r;
    if (r->outcome == CS_STREAM_DEVICE_ERROR)
        control(s, CS_MODBUS_CMD_ABORT, CS_PROTO_STATE_ABORTED, CS_PROTO_STATE_IDLE, 2000);
    if (s->t_lease != 0 && r->outcome != CS_STREAM_CLOSED && r->outcome != CS_STREAM_RESET)
        (void)cs_mb_lease(s->c, false); /* the next job, or another client, may write now */
    double t_end = cs_serial_now_s();
    cs_stream_progress(&s->prog, o->progress, o->progress_tty, true, s->job->n, r->executed,
                       r->sent, o->resume_from, s->c->retries + s->resent, what(s));
    r->link.retransmits = s->c->retries + s->resent;
    r->link.timeouts = s->c->timeouts;
    r->link.naks = s->refused;
    r->link.delivered = (uint32_t)(r->delivered - o->resume_from);
    r->bytes_out = s->c->bytes_out;
    r->bytes_in = s->c->bytes_in;
    r->wall_s = t_end - t0;
    r->stream_s = t_end - s->t_first;
}

cs_err_t cs_mb_stream_run(const cs_stream_job_t *job, const cs_mb_stream_opts_t *o,
                          cs_stream_result_t *r)
{
    memset(r, 0, sizeof *r);
    r->dev_state = 0xFF;
    if (job == NULL || o == NULL || o->c == NULL || o->c->ctx == NULL || o->resume_from > job->n)
        return CS_ERR_ARG;
    mrun_t s0 = {0}, *s = &s0;
    s->job = job;
    s->o = o;
    s->r = r;
    s->c = o->c;
    r->sent = r->delivered = r->executed = o->resume_from;
    s->next = o->resume_from;
    double t0 = cs_serial_now_s();
    mb_connect(s, t0);
    mb_prepare(s);
    mb_stream(s);
    mb_finish(s, t0);
    return CS_OK;
}
