/* cs_serial: termios serial port, pty pairs, write pacing and fault injection. */
#include "cs_serial.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <string.h>
#include <sys/file.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

static const struct {
    uint32_t baud;
    speed_t code;
} bauds[] = {
    {1200, B1200},       {2400, B2400},       {4800, B4800},       {9600, B9600},
    {19200, B19200},     {38400, B38400},     {57600, B57600},     {115200, B115200},
    {230400, B230400},   {460800, B460800},   {500000, B500000},   {576000, B576000},
    {921600, B921600},   {1000000, B1000000}, {1500000, B1500000}, {2000000, B2000000},
    {3000000, B3000000}, {4000000, B4000000},
};

static bool baud_code(uint32_t baud, speed_t *code)
{
    for (size_t i = 0; i < sizeof bauds / sizeof bauds[0]; i++)
        if (bauds[i].baud == baud) {
            *code = bauds[i].code;
            return true;
        }
    return false;
}

bool cs_serial_baud_ok(uint32_t baud)
{
    speed_t c;
    return baud_code(baud, &c);
}

double cs_serial_now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

uint32_t cs_serial_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint32_t)((uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u);
}

uint32_t cs_serial_now_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint32_t)((uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u);
}

static void init_struct(cs_serial_t *s, int fd)
{
    memset(s, 0, sizeof *s);
    s->fd = fd;
}

static int set_nonblock(int fd)
{
    int fl = fcntl(fd, F_GETFL);
    if (fl < 0)
        return -1;
    return fcntl(fd, F_SETFL, fl | O_NONBLOCK);
}

static int make_raw(int fd, uint32_t baud)
{
    struct termios t;
    if (tcgetattr(fd, &t) != 0)
        return -1;
    cfmakeraw(&t);
    t.c_cflag |= CLOCAL | CREAD;
    t.c_cflag &= ~(tcflag_t)(CSTOPB | PARENB | CRTSCTS);
    t.c_iflag &= ~(tcflag_t)(IXON | IXOFF | IXANY);
    t.c_cc[VMIN] = 1; /* with O_NONBLOCK: EAGAIN when empty, so 0 means end of file */
    t.c_cc[VTIME] = 0;
    if (baud != 0) {
        speed_t code;
        if (!baud_code(baud, &code)) {
            errno = EINVAL;
            return -1;
        }
        cfsetispeed(&t, code);
        cfsetospeed(&t, code);
    }
    return tcsetattr(fd, TCSANOW, &t);
}

/* A pseudo-terminal's /dev/pts entry can be missing for a moment right after its creation:
 * on this project's Linux 6.18 machine, with the pty index just freed by the previous device,
 * stat and open of the path the creator printed fail with ENOENT on and off for up to 57 ms
 * (3 of 300 creations; `curvestep stream` to a fresh `curvestep-sim --pty` failed to open it 2
 * times in 300). A path under /dev/pts/ is therefore retried on ENOENT until this deadline
 * (35 times the longest gap seen; kept short: a path whose device has gone for good can be
 * given to the next pty created, and a sender still waiting would open that one). */
#define CS_SERIAL_PTS_WAIT_S 2.0

static int open_tty(const char *path)
{
    const int flags = O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC;
    int fd = open(path, flags);
    if (fd >= 0 || errno != ENOENT || strncmp(path, "/dev/pts/", 9) != 0)
        return fd;
    double end = cs_serial_now_s() + CS_SERIAL_PTS_WAIT_S;
    while (fd < 0 && errno == ENOENT && cs_serial_now_s() < end) {
        struct timespec ts = {0, 5000000L}; /* 5 ms: the entry comes back within a few */
        nanosleep(&ts, NULL);
        fd = open(path, flags);
    }
    return fd;
}

int cs_serial_open(cs_serial_t *s, const char *path, uint32_t baud)
{
    init_struct(s, -1);
    if (baud != 0 && !cs_serial_baud_ok(baud)) {
        errno = EINVAL;
        return -1;
    }
    int fd = open_tty(path);
    if (fd < 0)
        return -1;
    if (!isatty(fd)) {
        close(fd);
        errno = ENOTTY;
        return -1;
    }
    /* One program on a port at a time: two senders' frames interleaved on one line would each
     * be taken for the other's retransmissions (seen once on a loaded test machine: a sender
     * that waited for a vanished pty's path opened the next device given that number). The
     * lock is advisory, as pyserial's exclusive mode: every curvestep program takes it. */
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
        int e = errno == EWOULDBLOCK ? EBUSY : errno;
        close(fd);
        errno = e;
        return -1;
    }
    if (make_raw(fd, baud) != 0) {
        int e = errno;
        close(fd);
        errno = e;
        return -1;
    }
    /* Bytes a previous session left in the driver are stale: the protocol resynchronises on
     * them anyway, but they cost a CRC error and a NAK each (docs/protocol.md). */
    tcflush(fd, TCIOFLUSH);
    s->fd = fd;
    return 0;
}

const char *cs_serial_strerror(int e)
{
    if (e == EBUSY)
        return "in use by another program (it holds the port's lock): one sender at a time";
    return strerror(e);
}

void cs_serial_attach(cs_serial_t *s, int fd)
{
    init_struct(s, fd);
    set_nonblock(fd);
}

void cs_serial_close(cs_serial_t *s)
{
    if (s->fd >= 0)
        close(s->fd);
    s->fd = -1;
}

void cs_serial_set_line_rate(cs_serial_t *s, uint32_t bits_per_s)
{
    s->line_rate = bits_per_s;
    s->line_free_at = 0;
}

void cs_serial_set_lossy(cs_serial_t *s, bool on)
{
    s->lossy = on;
}

void cs_serial_set_faults(cs_serial_t *s, const cs_serial_faults_t *f)
{
    s->faulty = f != NULL && (f->drop > 0 || f->corrupt > 0 || f->dup > 0);
    if (f != NULL)
        s->faults = *f;
    s->rng = (f != NULL && f->seed != 0) ? f->seed : 0x9E3779B97F4A7C15ull;
}

/* xorshift64 (Marsaglia 2003), uniform in [0, 1). */
static double rnd(cs_serial_t *s)
{
    uint64_t x = s->rng;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    s->rng = x;
    return (double)(x >> 11) * (1.0 / 9007199254740992.0);
}

ssize_t cs_serial_read(cs_serial_t *s, uint8_t *buf, size_t cap, int timeout_ms)
{
    if (s->fd < 0) {
        errno = EBADF;
        return -1;
    }
    for (;;) {
        ssize_t r = read(s->fd, buf, cap);
        if (r > 0) {
            s->bytes_in += (uint64_t)r;
            return r;
        }
        if (r == 0) { /* end of file: a tty whose other end is gone */
            errno = EIO;
            return -1;
        }
        if (errno == EINTR)
            continue;
        if (errno != EAGAIN && errno != EWOULDBLOCK)
            return -1;
        if (timeout_ms == 0)
            return 0;
        struct pollfd p = {.fd = s->fd, .events = POLLIN};
        int n = poll(&p, 1, timeout_ms);
        if (n < 0) {
            if (errno == EINTR)
                return 0; /* let the caller look at its signal flags */
            return -1;
        }
        if (n == 0)
            return 0;
        if ((p.revents & (POLLIN | POLLHUP | POLLERR)) == 0)
            return 0;
        timeout_ms = 0; /* readable (or hung up: read says which) */
    }
}

static int write_raw(cs_serial_t *s, const uint8_t *buf, size_t len)
{
    size_t done = 0;
    while (done < len) {
        ssize_t w = write(s->fd, buf + done, len - done);
        if (w > 0) {
            done += (size_t)w;
            continue;
        }
        if (w < 0 && errno == EINTR)
            continue;
        if (w < 0 && (errno == EAGAIN || errno == EWOULDBLOCK) && s->lossy) {
            s->lost += len - done;
            return 0;
        }
        if (w < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
            struct pollfd p = {.fd = s->fd, .events = POLLOUT};
            int n = poll(&p, 1, 1000);
            if (n < 0 && errno != EINTR)
                return -1;
            if (n > 0 && (p.revents & (POLLERR | POLLHUP | POLLNVAL)) && !(p.revents & POLLOUT)) {
                errno = EIO;
                return -1;
            }
            continue;
        }
        if (w == 0)
            errno = EIO;
        return -1;
    }
    s->bytes_out += len;
    return 0;
}

static void pace(cs_serial_t *s, size_t len)
{
    if (s->line_rate == 0)
        return;
    double now = cs_serial_now_s();
    if (s->line_free_at < now)
        s->line_free_at = now;
    /* A byte is 10 bits on the line (start, 8 data, stop). The caller may write once the line
     * has finished the previous bytes; it then stays busy for len bytes. */
    double wait = s->line_free_at - now;
    if (wait > 0) {
        struct timespec ts = {(time_t)wait, (long)((wait - (double)(time_t)wait) * 1e9)};
        while (nanosleep(&ts, &ts) != 0 && errno == EINTR) {
        }
    }
    s->line_free_at += (double)len * 10.0 / (double)s->line_rate;
}

int cs_serial_write(cs_serial_t *s, const uint8_t *buf, size_t len)
{
    if (s->fd < 0) {
        errno = EBADF;
        return -1;
    }
    if (len == 0)
        return 0;
    if (!s->faulty) {
        pace(s, len);
        return write_raw(s, buf, len);
    }
    if (rnd(s) < s->faults.drop) {
        s->dropped++;
        pace(s, len); /* the bytes were "sent" and lost on the line */
        return 0;
    }
    uint8_t tmp[512];
    size_t off = 0;
    while (off < len) {
        size_t n = len - off < sizeof tmp ? len - off : sizeof tmp;
        memcpy(tmp, buf + off, n);
        for (size_t i = 0; i < n; i++)
            if (s->faults.corrupt > 0 && rnd(s) < s->faults.corrupt) {
                uint8_t x = (uint8_t)(1u + (uint8_t)(rnd(s) * 255.0)); /* 1..255: never same */
                tmp[i] ^= x;
                s->corrupted++;
            }
        pace(s, n);
        if (write_raw(s, tmp, n) != 0)
            return -1;
        off += n;
    }
    if (s->faults.dup > 0 && rnd(s) < s->faults.dup) {
        s->duplicated++;
        pace(s, len);
        return write_raw(s, buf, len);
    }
    return 0;
}

int cs_serial_openpty(int *master, int *slave, char *slave_name, size_t namecap)
{
    int m, sl;
    char name[256];
    if (openpty(&m, &sl, name, NULL, NULL) != 0)
        return -1;
    if (make_raw(sl, 0) != 0 || set_nonblock(m) != 0 || set_nonblock(sl) != 0) {
        int e = errno;
        close(m);
        close(sl);
        errno = e;
        return -1;
    }
    fcntl(m, F_SETFD, FD_CLOEXEC);
    fcntl(sl, F_SETFD, FD_CLOEXEC);
    if (slave_name != NULL && namecap > 0) {
        strncpy(slave_name, name, namecap - 1);
        slave_name[namecap - 1] = '\0';
    }
    *master = m;
    *slave = sl;
    return 0;
}
