/* cs_sim_mbtcp: the simulator's Modbus TCP server. See cs_sim_mbtcp.h and docs/modbus.md. The
 * framing is "Modbus Messaging on TCP/IP Implementation Guide V1.0b", 3.1.3 (MBAP header): the
 * length field, not the function code, says where a request ends, so a request of unknown or
 * wrong shape is read whole and answered (the core answers fc | 0x80 with its exception), and
 * the next one starts where it should. */
#include "cs_sim_mbtcp.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "cs_modbus.h"
#include "cs_serial.h"

typedef struct {
    int fd;        /* -1: free slot */
    uint32_t gen;  /* which connection this slot holds (a delayed answer names it) */
    double last_s; /* last request (or the connection), for eviction */
    bool spoke;    /* has sent a request: closed after every one that has not */
    size_t n;      /* bytes buffered */
    uint8_t in[2 * CS_MODBUS_TCP_MAX];
} conn_t;

typedef struct {
    double due;
    unsigned slot;
    uint32_t gen;
    size_t len;
    uint8_t adu[CS_MODBUS_TCP_MAX];
} delayed_t;

typedef struct {
    const cs_sim_mbtcp_app_t *app;
    cs_sim_mbtcp_stats_t *st;
    int ls;
    uint32_t gen;
    unsigned rr; /* where the next round starts */
    conn_t c[CS_SIM_MBTCP_CONNS];
    delayed_t dl[CS_SIM_MBTCP_DELAYED];
    unsigned ndl;
} server_t;

static int parse_hostport(const char *s, struct sockaddr_in *sa, char *host, size_t cap)
{
    const char *colon = strrchr(s, ':');
    if (colon == NULL || (size_t)(colon - s) >= cap || colon == s || colon[1] == '\0')
        return -1;
    memcpy(host, s, (size_t)(colon - s));
    host[colon - s] = '\0';
    char *end;
    long p = strtol(colon + 1, &end, 10);
    if (*end != '\0' || p < 0 || p > 65535)
        return -1;
    memset(sa, 0, sizeof *sa);
    sa->sin_family = AF_INET;
    sa->sin_port = htons((uint16_t)p);
    return inet_pton(AF_INET, host, &sa->sin_addr) == 1 ? 0 : -1;
}

/* Binds and listens; prints "HOST:PORT" bound. -1 with a message when it cannot. */
static int listen_on(const char *addr, char *host, size_t cap)
{
    struct sockaddr_in sa;
    if (parse_hostport(addr, &sa, host, cap) != 0)
        return -2;
    int ls = socket(AF_INET, SOCK_STREAM, 0);
    int one = 1;
    if (ls < 0 || setsockopt(ls, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0 ||
        bind(ls, (struct sockaddr *)&sa, sizeof sa) != 0 || listen(ls, 8) != 0) {
        fprintf(stderr, "curvestep-sim: cannot listen on %s: %s\n", addr, strerror(errno));
        if (ls >= 0)
            close(ls);
        return -1;
    }
    socklen_t sl = sizeof sa;
    if (getsockname(ls, (struct sockaddr *)&sa, &sl) != 0) {
        perror("curvestep-sim: getsockname");
        close(ls);
        return -1;
    }
    printf("%s:%u\n", host, (unsigned)ntohs(sa.sin_port));
    fflush(stdout);
    return ls;
}

static void drop_conn(server_t *s, unsigned k)
{
    if (s->c[k].fd >= 0)
        close(s->c[k].fd);
    s->c[k].fd = -1;
    s->c[k].n = 0;
}

/* The slot a new connection takes when all are open: a connection that never sent a request,
 * the oldest first, else the one silent the longest. A silent client never locks the streaming
 * host out, and a client that speaks is not closed for a moment's delay (a loaded machine)
 * while one that never spoke is open. */
static bool evict_before(const conn_t *a, const conn_t *b)
{
    return a->spoke != b->spoke ? !a->spoke : a->last_s < b->last_s;
}

/* A new connection: a free slot, or the one evict_before picks. */
static void accept_one(server_t *s)
{
    int fd = accept(s->ls, NULL, NULL);
    if (fd < 0)
        return;
    if (fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK) != 0 ||
        fcntl(fd, F_SETFD, FD_CLOEXEC) != 0) {
        close(fd);
        return;
    }
    unsigned slot = CS_SIM_MBTCP_CONNS, open = 0;
    for (unsigned k = 0; k < CS_SIM_MBTCP_CONNS; k++)
        open += s->c[k].fd >= 0;
    for (unsigned k = 0; k < CS_SIM_MBTCP_CONNS; k++) {
        if (s->c[k].fd < 0) {
            slot = k;
            break;
        }
        if (slot == CS_SIM_MBTCP_CONNS || evict_before(&s->c[k], &s->c[slot]))
            slot = k;
    }
    if (open == CS_SIM_MBTCP_CONNS) {
        drop_conn(s, slot);
        s->st->evicted++;
        open--;
    }
    /* answers go out at once: with Nagle's algorithm an answer written while the previous one
     * waits for the client's delayed ACK is held up to 40 ms */
    int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    conn_t *c = &s->c[slot];
    c->fd = fd;
    c->gen = ++s->gen;
    c->n = 0;
    c->spoke = false;
    c->last_s = cs_serial_now_s();
    s->st->connections++;
    if (open + 1 > s->st->most)
        s->st->most = open + 1;
}

/* Sends an answer whole, or closes a client that does not read its answers. */
static void send_adu(server_t *s, unsigned k, const uint8_t *adu, size_t len)
{
    ssize_t w = send(s->c[k].fd, adu, len, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (w == (ssize_t)len)
        return;
    if (w < 0 && errno != EAGAIN && errno != EWOULDBLOCK) {
        drop_conn(s, k); /* the client went away */
        return;
    }
    s->st->slow++;
    drop_conn(s, k);
}

/* Serves the first whole request buffered on connection k, if there is one. */
static void serve_one(server_t *s, unsigned k)
{
    conn_t *c = &s->c[k];
    cs_modbus_mbap_t h;
    cs_err_t e = cs_modbus_mbap_parse(c->in, c->n, &h);
    if (e == CS_ERR_EMPTY)
        return;
    if (e == CS_ERR_FRAME) { /* where would the next request start? nowhere we can know */
        s->st->bad_length++;
        drop_conn(s, k);
        return;
    }
    size_t whole = CS_MODBUS_MBAP_LEN + h.pdu_len;
    uint8_t rsp[CS_MODBUS_PDU_MAX], adu[CS_MODBUS_TCP_MAX];
    size_t rn = 0, len = 0;
    double delay = -1;
    c->last_s = cs_serial_now_s();
    c->spoke = true;
    if (e == CS_ERR_UNSUPPORTED)
        s->st->bad_proto++; /* not Modbus: dropped unanswered */
    else
        delay =
            s->app->handle(s->app->ctx, h.unit, c->in + CS_MODBUS_MBAP_LEN, h.pdu_len, rsp, &rn);
    memmove(c->in, c->in + whole, c->n - whole);
    c->n -= whole;
    if (delay < 0 || cs_modbus_mbap_frame(&h, rsp, rn, adu, sizeof adu, &len) != CS_OK)
        return;
    if (delay == 0 || s->ndl == CS_SIM_MBTCP_DELAYED) { /* no room to hold it: now */
        send_adu(s, k, adu, len);
    } else {
        delayed_t *q = &s->dl[s->ndl++];
        q->due = cs_serial_now_s() + delay;
        q->slot = k;
        q->gen = c->gen;
        q->len = len;
        memcpy(q->adu, adu, len);
    }
}

/* Answers held back by the delay fault, to connections still open. */
static void send_delayed(server_t *s)
{
    double now = cs_serial_now_s();
    for (unsigned k = 0; k < s->ndl;) {
        delayed_t *q = &s->dl[k];
        if (q->due > now) {
            k++;
            continue;
        }
        if (s->c[q->slot].fd >= 0 && s->c[q->slot].gen == q->gen)
            send_adu(s, q->slot, q->adu, q->len);
        *q = s->dl[--s->ndl];
    }
}

/* Reads what connection k has sent (never blocks); closes it at its end. */
static void read_conn(server_t *s, unsigned k)
{
    conn_t *c = &s->c[k];
    ssize_t r = recv(c->fd, c->in + c->n, sizeof c->in - c->n, MSG_DONTWAIT);
    if (r > 0)
        c->n += (size_t)r;
    else if (r == 0 || (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR))
        drop_conn(s, k);
}

/* Waits for requests (not at all when one is buffered), takes a new connection, reads. */
static void wait_round(server_t *s)
{
    struct pollfd pf[1 + CS_SIM_MBTCP_CONNS];
    bool pending = false;
    pf[0] = (struct pollfd){s->ls, POLLIN, 0};
    for (unsigned k = 0; k < CS_SIM_MBTCP_CONNS; k++) {
        conn_t *c = &s->c[k];
        cs_modbus_mbap_t h;
        bool whole = c->fd >= 0 && cs_modbus_mbap_parse(c->in, c->n, &h) != CS_ERR_EMPTY;
        pending = pending || whole;
        /* a client with a whole request waiting is not read further: TCP pushes back on a
         * client that sends faster than it is served */
        pf[1 + k] = (struct pollfd){whole || c->fd < 0 ? -1 : c->fd, POLLIN, 0};
    }
    int wait_ms = pending ? 0 : s->ndl > 0 || s->app->busy(s->app->ctx) ? 1 : 5;
    if (poll(pf, 1 + CS_SIM_MBTCP_CONNS, wait_ms) <= 0)
        return;
    for (unsigned k = 0; k < CS_SIM_MBTCP_CONNS; k++)
        if (pf[1 + k].fd >= 0 && (pf[1 + k].revents & (POLLIN | POLLHUP | POLLERR)))
            read_conn(s, k);
    if (pf[0].revents & POLLIN)
        accept_one(s);
}

int cs_sim_mbtcp_serve(const char *addr, const cs_sim_mbtcp_app_t *app, volatile sig_atomic_t *stop,
                       cs_sim_mbtcp_stats_t *st)
{
    char host[64];
    int ls = listen_on(addr, host, sizeof host);
    if (ls == -2) {
        fprintf(stderr, "curvestep-sim: --modbus-tcp wants ADDR:PORT with an IPv4 address, "
                        "e.g. 127.0.0.1:1502 (port 0: any free port)\n");
        return 2;
    }
    if (ls < 0)
        return 3;
    server_t *s = calloc(1, sizeof *s);
    if (s == NULL) {
        close(ls);
        return 3;
    }
    *st = (cs_sim_mbtcp_stats_t){0};
    s->app = app;
    s->st = st;
    s->ls = ls;
    for (unsigned k = 0; k < CS_SIM_MBTCP_CONNS; k++)
        s->c[k].fd = -1;
    while (!*stop) {
        send_delayed(s);
        wait_round(s);
        /* one request per connection per round, starting with a different one each round */
        for (unsigned i = 0; i < CS_SIM_MBTCP_CONNS; i++) {
            unsigned k = (s->rr + i) % CS_SIM_MBTCP_CONNS;
            if (s->c[k].fd >= 0)
                serve_one(s, k);
        }
        s->rr = (s->rr + 1) % CS_SIM_MBTCP_CONNS;
        if (app->tick(app->ctx))
            break;
    }
    for (unsigned k = 0; k < CS_SIM_MBTCP_CONNS; k++)
        drop_conn(s, k);
    close(ls);
    free(s);
    return 0;
}
