/* cs_serial: the host's serial port. Opens a tty raw (termios, 8N1, no flow control) at a given
 * baud rate, flushes stale bytes on open (docs/protocol.md), reads with a timeout (poll), writes
 * everything, and can pace writes to a real line's rate (--line-rate) and inject faults (drop,
 * corrupt, duplicate) into what it writes, for tests. Also the pseudo-terminal pair helper
 * (openpty) the loopback tests and the simulator use. Host only (POSIX). */
#ifndef CS_SERIAL_H
#define CS_SERIAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>

/* Faults applied to every cs_serial_write call (one call = one frame from cs_link_poll):
 * probabilities in [0, 1], a fixed seed makes a run repeatable. */
typedef struct {
    double drop;    /* the whole write is lost */
    double corrupt; /* each byte is replaced by a different random byte */
    double dup;     /* the whole write is sent twice */
    uint64_t seed;  /* xorshift64 seed (0: a fixed default) */
} cs_serial_faults_t;

typedef struct {
    int fd;
    uint32_t line_rate;  /* bits per second to pace writes at (10 bits a byte); 0 = no pacing */
    double line_free_at; /* monotonic time (s) when the paced line is free again */
    bool faulty;         /* faults is in use */
    bool lossy;          /* a write that finds the driver full drops the rest (a device's UART
                          * with nobody listening) instead of waiting */
    cs_serial_faults_t faults;
    uint64_t rng;
    uint64_t bytes_out, bytes_in;            /* bytes written (after faults) and read */
    uint64_t dropped, corrupted, duplicated; /* faults injected */
    uint64_t lost;                           /* bytes dropped by a lossy write (driver full) */
} cs_serial_t;

/* Opens path (a tty or pty slave) read/write, non-blocking, raw 8N1 at baud (one of the termios
 * rates 1200..4000000; 0 = leave the speed alone), and discards stale input (tcflush). Returns 0,
 * or -1 with errno set (EINVAL for an unsupported baud, EBUSY when another program holds the
 * port: an exclusive flock is taken). A /dev/pts/ path that does not exist is retried for up
 * to 2 s (a fresh pty's entry can be missing for a moment). Not ISR-safe. */
int cs_serial_open(cs_serial_t *s, const char *path, uint32_t baud);
/* Why cs_serial_open failed, for people: strerror(e), except EBUSY (another program holds the
 * port). A static string. */
const char *cs_serial_strerror(int e);
/* Wraps an already open fd (a pty end from cs_serial_openpty): sets O_NONBLOCK, no termios. */
void cs_serial_attach(cs_serial_t *s, int fd);
/* Closes the port (fd = -1). */
void cs_serial_close(cs_serial_t *s);
/* Paces writes to line_rate bits/s (0 = off). */
void cs_serial_set_line_rate(cs_serial_t *s, uint32_t bits_per_s);
/* Lossy writes (see cs_serial_t.lossy): for a device that must never block on a dead line. */
void cs_serial_set_lossy(cs_serial_t *s, bool on);
/* Injects faults into every later write (NULL = none). */
void cs_serial_set_faults(cs_serial_t *s, const cs_serial_faults_t *f);
/* Reads up to cap bytes, waiting at most timeout_ms (0 = do not wait, -1 = forever) for the
 * first. Returns the count (0 on timeout), or -1 when the port is closed or failed (EIO: the
 * other end of a pty hung up; errno set). */
ssize_t cs_serial_read(cs_serial_t *s, uint8_t *buf, size_t cap, int timeout_ms);
/* Writes all len bytes (waiting for room; with a line rate, sleeping so that the line never
 * carries more than line_rate/10 bytes a second). Returns 0, or -1 on error (errno set). */
int cs_serial_write(cs_serial_t *s, const uint8_t *buf, size_t len);
/* Opens a pseudo-terminal pair, both ends raw (no echo, no line discipline), non-blocking;
 * *slave_name (may be NULL) gets the slave's path (caller's buffer of namecap bytes).
 * Returns 0 or -1 (errno). */
int cs_serial_openpty(int *master, int *slave, char *slave_name, size_t namecap);
/* Monotonic clock in seconds, in milliseconds and in microseconds (wrapping uint32: the link's
 * tick is the microsecond, fine enough for a NAK hold-off shorter than a pty's round trip). */
double cs_serial_now_s(void);
uint32_t cs_serial_now_ms(void);
uint32_t cs_serial_now_us(void);
/* Baud rate accepted by cs_serial_open (true when termios knows it). */
bool cs_serial_baud_ok(uint32_t baud);

#endif
