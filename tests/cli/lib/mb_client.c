/* Test helper (not a test; compiled by tests/cli/test_modbus_clients.sh): a second Modbus TCP
 * client that misbehaves beside a streaming host, on raw sockets (it must send frames no
 * library would). Register map and rules: docs/modbus.md. Every wait has a deadline.
 *   mb_client HOST PORT write          reads NEXT_SEQ and writes one zero-step SEGMENT (1000
 *                                      ticks) with it to the mailbox, without a token, until
 *                                      the device answers it (connecting again when it lost
 *                                      the connection); prints "written with sequence N" or
 *                                      "refused: exception E, REFUSED R, LEASE L" (the status
 *                                      read after it)
 *   mb_client HOST PORT poll STOPFILE  reads the status block flat out (connecting again when
 *                                      it lost the connection) until STOPFILE exists;
 *                                      prints "polling" after the first answer, then
 *                                      "polls: N answered, M bad, R reconnections"
 *   mb_client HOST PORT malformed      sends malformed frames; one line "ok WHAT" or
 *                                      "FAIL WHAT: why" per check
 *   mb_client HOST PORT status         prints "LEASE L LEFT MS NEXT_SEQ N"
 *   mb_client HOST PORT claim TOKEN    claims the lease with TOKEN once and exits (goes silent)
 *   mb_client HOST PORT hold TOKEN STOPFILE   claims it and renews it every 0.5 s until
 *                                      STOPFILE exists
 *   mb_client HOST PORT idle N STOPFILE       opens N connections and says nothing on them
 *                                      until STOPFILE exists
 * Exit status 0 when it could do what it was asked, 1 otherwise. */
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

static const char *g_host;
static int g_port;
static uint16_t g_tid = 1;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec / 1e9;
}

/* A connection to the device, or -1. */
static int try_connect(void)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in sa = {0};
    sa.sin_family = AF_INET;
    sa.sin_port = htons((uint16_t)g_port);
    inet_pton(AF_INET, g_host, &sa.sin_addr);
    int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    if (connect(fd, (struct sockaddr *)&sa, sizeof sa) != 0) {
        close(fd);
        return -1;
    }
    return fd;
}

static int connect_dev(void)
{
    int fd = try_connect();
    if (fd < 0) {
        perror("mb_client: connect");
        exit(1);
    }
    return fd;
}

/* After a failed request: a fresh connection (a client that lost its connection, to a server
 * that closed it or gave it to someone else, connects again, as a panel would). */
static int reconnect(int fd, unsigned long *count)
{
    close(fd);
    (*count)++;
    usleep(1000);
    return try_connect();
}

/* Reads exactly n bytes before the deadline: n, 0 when the server closed, -1 on timeout. */
static int read_all(int fd, uint8_t *b, size_t n, double secs)
{
    double end = now_s() + secs;
    size_t got = 0;
    while (got < n) {
        double left = end - now_s();
        if (left <= 0)
            return -1;
        struct pollfd pf = {fd, POLLIN, 0};
        if (poll(&pf, 1, (int)(left * 1000) + 1) <= 0)
            continue;
        ssize_t r = recv(fd, b + got, n - got, 0);
        if (r <= 0)
            return r == 0 || errno == ECONNRESET ? 0 : -1;
        got += (size_t)r;
    }
    return (int)n;
}

/* Sends an MBAP frame: transaction tid, protocol proto, length field len (normally 1 + n),
 * unit 1, then pdu[0..n). */
static void send_raw(int fd, uint16_t tid, uint16_t proto, uint16_t len, const uint8_t *pdu,
                     size_t n)
{
    uint8_t b[300] = {(uint8_t)(tid >> 8),
                      (uint8_t)tid,
                      (uint8_t)(proto >> 8),
                      (uint8_t)proto,
                      (uint8_t)(len >> 8),
                      (uint8_t)len,
                      1};
    memcpy(b + 7, pdu, n);
    if (send(fd, b, 7 + n, MSG_NOSIGNAL) != (ssize_t)(7 + n))
        perror("mb_client: send"); /* the answer that does not come says the rest */
}

/* Receives one answer: its PDU into pdu (*n bytes), its transaction id; 1 ok, 0 closed,
 * -1 no answer within secs. */
static int recv_answer(int fd, uint16_t *tid, uint8_t *pdu, size_t *n, double secs)
{
    uint8_t h[7];
    int r = read_all(fd, h, 7, secs);
    if (r <= 0)
        return r;
    size_t len = ((size_t)h[4] << 8) | h[5];
    if (len < 2 || len > 254)
        return -1;
    *tid = (uint16_t)((h[0] << 8) | h[1]);
    *n = len - 1;
    return read_all(fd, pdu, *n, secs) > 0 ? 1 : -1;
}

/* One request and its answer (PDU into rsp): its length, or -1. */
static int transact(int fd, const uint8_t *pdu, size_t n, uint8_t *rsp)
{
    uint16_t tid = g_tid++, got;
    size_t rn;
    send_raw(fd, tid, 0, (uint16_t)(1 + n), pdu, n);
    if (recv_answer(fd, &got, rsp, &rn, 10.0) != 1 || got != tid)
        return -1;
    return (int)rn;
}

/* FC04 of the first n status registers into ir: 0 ok. 24 are there in every map version (the
 * lease's two came with version 2), so the checks that do not need the lease read 24. */
static int read_status(int fd, uint16_t *ir, int n)
{
    uint8_t req[5] = {4, 0, 0, 0, (uint8_t)n}, rsp[260];
    if (transact(fd, req, 5, rsp) != 2 + 2 * n || rsp[0] != 4)
        return -1;
    for (int k = 0; k < n; k++)
        ir[k] = (uint16_t)((rsp[2 + 2 * k] << 8) | rsp[3 + 2 * k]);
    return 0;
}

static int write_one(int fd, uint16_t addr, uint16_t v)
{
    uint8_t req[5] = {6, (uint8_t)(addr >> 8), (uint8_t)addr, (uint8_t)(v >> 8), (uint8_t)v};
    uint8_t rsp[260];
    int n = transact(fd, req, 5, rsp);
    return n == 5 && rsp[0] == 6 ? 0 : n == 2 ? rsp[1] : -1;
}

/* One foreign SEGMENT with the device's NEXT_SEQ: 0 written, 1 refused (printed), -1 retry
 * (the host took that sequence first, or the connection failed). */
static int write_once(int fd)
{
    uint16_t ir[26];
    if (read_status(fd, ir, 24) != 0)
        return -1;
    uint16_t regs[12] = {0x20, 0, 1000, 0, 0, 0, 0, 0, 0, 0, 0, ir[11]};
    uint8_t req[6 + 24] = {16, 0x01, 0x00, 0, 12, 24}, rsp[260];
    for (int k = 0; k < 12; k++) {
        req[6 + 2 * k] = (uint8_t)(regs[k] >> 8);
        req[7 + 2 * k] = (uint8_t)regs[k];
    }
    int n = transact(fd, req, sizeof req, rsp);
    if (n == 5 && rsp[0] == 16) {
        printf("written with sequence %u\n", (unsigned)ir[11]);
        return 0;
    }
    if (n != 2 || rsp[1] == 3) /* no answer, or the sequence was taken meanwhile: again */
        return -1;
    if (read_status(fd, ir, 26) != 0)
        ir[14] = ir[24] = 0xFFFF;
    printf("refused: exception %u (function 0x%02x), REFUSED %u, LEASE %u\n", (unsigned)rsp[1],
           (unsigned)rsp[0], (unsigned)ir[14], (unsigned)ir[24]);
    return 1;
}

/* Tries until the device answers the write (taken or refused) or 60 s pass. */
static int do_write(int fd)
{
    unsigned long reconnects = 0;
    double end = now_s() + 60;
    while (now_s() < end) {
        int r = fd >= 0 ? write_once(fd) : -1;
        if (r >= 0)
            return 0;
        fd = reconnect(fd, &reconnects);
    }
    printf("no answer to the write in 60 s (%lu reconnections)\n", reconnects);
    return 1;
}

static int exists(const char *f)
{
    return access(f, F_OK) == 0;
}

static int do_poll(int fd, const char *stop)
{
    unsigned long ok = 0, bad = 0, reconnects = 0;
    double end = now_s() + 240;
    uint16_t ir[26];
    while (!exists(stop) && now_s() < end) {
        if (fd >= 0 && read_status(fd, ir, 24) == 0 && ir[0] >= 1) {
            ok++;
        } else {
            bad++;
            fd = reconnect(fd, &reconnects);
        }
        if (ok + bad == 1) {
            printf("polling\n"); /* the test waits for this before it opens more */
            fflush(stdout);
        }
    }
    printf("polls: %lu answered, %lu bad, %lu reconnections\n", ok, bad, reconnects);
    if (fd >= 0)
        close(fd);
    return bad == 0 && exists(stop) ? 0 : 1;
}

static int fails;

static void verdict(const char *what, int good, const char *why)
{
    if (good) {
        printf("ok %s\n", what);
    } else {
        printf("FAIL %s: %s\n", what, why);
        fails++;
    }
}

/* An unknown function code: the answer must be fc | 0x80, exception 1, same transaction. */
static void unknown_fc(int fd, uint8_t fc, const char *what)
{
    uint8_t pdu[4] = {fc, 0x0E, 0x01, 0x00}, rsp[260];
    uint16_t tid = g_tid++, got = 0;
    size_t n = 0;
    send_raw(fd, tid, 0, 5, pdu, 4);
    int r = recv_answer(fd, &got, rsp, &n, 10.0);
    char why[128];
    snprintf(why, sizeof why, "answer %d, tid %u/%u, %zu bytes, function 0x%02x, code %u", r,
             (unsigned)got, (unsigned)tid, n, n > 0 ? rsp[0] : 0, n > 1 ? rsp[1] : 0);
    verdict(what, r == 1 && got == tid && n == 2 && rsp[0] == (fc | 0x80) && rsp[1] == 1, why);
}

/* A status read that must be answered, on the same connection: the stream is still in step. */
static void still_in_step(int fd, const char *what)
{
    uint16_t ir[26];
    verdict(what, read_status(fd, ir, 24) == 0 && ir[0] >= 1,
            "no valid answer to the next request");
}

/* The server must close the connection (an MBAP length it cannot frame by). */
static void closed_on(uint16_t len, const char *what)
{
    int fd = connect_dev();
    uint8_t pdu[5] = {4, 0, 0, 0, 24}, b[300];
    send_raw(fd, g_tid++, 0, len, pdu, 5);
    int r = read_all(fd, b, sizeof b, 10.0); /* any answer is wrong; 0 = closed */
    char why[64];
    snprintf(why, sizeof why, "read returned %d, not the end of the connection", r);
    verdict(what, r == 0, why);
    close(fd);
}

/* Each check on a connection of its own, so that one failing does not hide the next. */
static int do_malformed(void)
{
    int fd = connect_dev();
    unknown_fc(fd, 0x41, "unknown function 0x41 -> 0xC1 exception 1");
    still_in_step(fd, "the request after function 0x41 is answered in step");
    close(fd);
    fd = connect_dev();
    unknown_fc(fd, 0x2B, "unserved function 0x2B -> 0xAB exception 1");
    still_in_step(fd, "the request after function 0x2B is answered in step");
    close(fd);
    fd = connect_dev();
    /* a read whose MBAP length says 4 bytes more than an FC04 request has: the whole frame is
     * the request (exception 3, bad length), and the next one starts after it */
    uint8_t pdu[9] = {4, 0, 0, 0, 24, 0x04, 0x00, 0x00, 0x01}, rsp[260];
    uint16_t tid = g_tid++, got = 0;
    size_t n = 0;
    send_raw(fd, tid, 0, 10, pdu, 9);
    int r = recv_answer(fd, &got, rsp, &n, 10.0);
    verdict("FC04 with 4 extra bytes in its length -> 0x84 exception 3",
            r == 1 && got == tid && n == 2 && rsp[0] == 0x84 && rsp[1] == 3, "other answer");
    still_in_step(fd, "the request after it is answered in step");
    close(fd);
    fd = connect_dev();
    /* protocol id 1: not Modbus, dropped; the next request (protocol 0) gets the first answer */
    uint16_t t1 = g_tid++, t2 = g_tid++;
    send_raw(fd, t1, 1, 6, pdu, 5);
    send_raw(fd, t2, 0, 6, pdu, 5);
    r = recv_answer(fd, &got, rsp, &n, 10.0);
    char why[96];
    snprintf(why, sizeof why, "first answer: %d, transaction %u (dropped one %u, next %u)", r,
             (unsigned)got, (unsigned)t1, (unsigned)t2);
    verdict("protocol id 1 dropped unanswered", r == 1 && got == t2, why);
    close(fd);
    closed_on(0, "MBAP length 0 closes the connection");
    closed_on(1, "MBAP length 1 (no function code) closes the connection");
    closed_on(300, "MBAP length 300 (longer than any PDU) closes the connection");
    return fails == 0 ? 0 : 1;
}

int main(int argc, char **argv)
{
    if (argc < 4)
        return 2;
    g_host = argv[1];
    g_port = atoi(argv[2]);
    const char *mode = argv[3];
    if (strcmp(mode, "malformed") == 0)
        return do_malformed();
    if (strcmp(mode, "idle") == 0 && argc == 6) {
        int n = atoi(argv[4]);
        for (int k = 0; k < n; k++)
            (void)connect_dev();
        double end = now_s() + 240;
        while (!exists(argv[5]) && now_s() < end)
            usleep(20000);
        return 0;
    }
    int fd = connect_dev();
    uint16_t ir[26];
    if (strcmp(mode, "write") == 0)
        return do_write(fd);
    if (strcmp(mode, "poll") == 0 && argc == 5)
        return do_poll(fd, argv[4]);
    if (strcmp(mode, "status") == 0 && read_status(fd, ir, 26) == 0) {
        printf("LEASE %u LEFT %u NEXT_SEQ %u\n", ir[24], ir[25], ir[11]);
        return 0;
    }
    if (strcmp(mode, "claim") == 0 && argc == 5)
        return write_one(fd, 0x0001, (uint16_t)atoi(argv[4])) == 0 ? 0 : 1;
    if (strcmp(mode, "hold") == 0 && argc == 6) {
        double end = now_s() + 240;
        while (!exists(argv[5]) && now_s() < end) {
            if (write_one(fd, 0x0001, (uint16_t)atoi(argv[4])) != 0)
                return 1;
            usleep(500000);
        }
        return 0;
    }
    return 2;
}
