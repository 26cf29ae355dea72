/* cs_gpio_io: the pin seam of the GPIO link. Owns a set of output lines (STEP, DIR, ENABLE, up
 * to CS_GPIO_LINES_MAX) behind three calls -- open, set, close -- with two backends: libgpiod
 * 1.6 (one bulk request on a chip, one ioctl per set) and a recorder that keeps every edge with
 * its time on CLOCK_MONOTONIC and the time it was planned for (tests, benchmarks, and users
 * without hardware). Levels are logical (1 = asserted); active-low lines are inverted here, on
 * the way to the chip. Host only. */
#ifndef CS_GPIO_IO_H
#define CS_GPIO_IO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#define CS_GPIO_LINES_MAX 16

/* The lines to drive, by index 0..n-1 (masks below: bit i = line i). */
typedef struct {
    unsigned n;
    unsigned offset[CS_GPIO_LINES_MAX]; /* line offsets on the chip (ignored by the recorder) */
    bool active_low[CS_GPIO_LINES_MAX]; /* physical level = !logical */
    char name[CS_GPIO_LINES_MAX][12];   /* "x_step", "enable" ... (messages, records) */
    uint32_t initial;                   /* logical levels driven when the lines are requested */
} cs_gpio_lines_t;

/* One set call as the recorder keeps it: the lines it changed and their new logical levels. */
typedef struct {
    int64_t t_ns;       /* CLOCK_MONOTONIC after the lines were set */
    int64_t planned_ns; /* the time the caller planned it for (CLOCK_MONOTONIC) */
    uint32_t mask;      /* lines whose level changed */
    uint32_t levels;    /* their new logical levels */
} cs_gpio_edge_t;

typedef enum { CS_GPIO_IO_CHIP = 0, CS_GPIO_IO_RECORDER = 1 } cs_gpio_io_kind_t;

typedef struct {
    cs_gpio_io_kind_t kind;
    cs_gpio_lines_t lines;
    uint32_t levels; /* logical levels now */
    /* libgpiod */
    void *chip; /* struct gpiod_chip * */
    void *bulk; /* struct gpiod_line_bulk * (heap: 520 bytes) */
    char chip_name[64];
    /* recorder */
    cs_gpio_edge_t *rec;
    size_t nrec, cap;
    size_t dropped; /* set calls that found the record full */
} cs_gpio_io_t;

/* Opens chip `chip` with libgpiod (a name "gpiochipN", a path "/dev/gpiochipN", a number "N"
 * or the chip's label) and requests lines l as outputs at their initial levels, consumer
 * "curvestep". Returns 0, or -1 with one sentence in err that names the chip, says what failed
 * and what to check (permissions, /dev/gpiochipN, labels, an offset beyond the chip, a line
 * taken by another consumer). With l->n == 0 only checks that the chip opens: returns -2 when
 * it does. Not real-time: call before the step thread starts. */
int cs_gpio_io_open_chip(cs_gpio_io_t *io, const char *chip, const cs_gpio_lines_t *l, char *err,
                         size_t errlen);
/* A recorder for lines l with room for `capacity` set calls (allocated here, before the step
 * thread starts). Returns 0, or -1 when out of memory. */
int cs_gpio_io_open_recorder(cs_gpio_io_t *io, const cs_gpio_lines_t *l, size_t capacity);
/* Sets the lines in mask to the logical levels in `levels` (other lines keep theirs), then
 * returns (in *t_ns) CLOCK_MONOTONIC read after the lines changed. planned_ns is what the caller
 * planned (the recorder keeps it). Real-time safe: no allocation, one ioctl (chip) or one store
 * (recorder). Returns 0, or -1 when the chip refused (errno set). */
int cs_gpio_io_set(cs_gpio_io_t *io, uint32_t mask, uint32_t levels, int64_t planned_ns,
                   int64_t *t_ns);
/* Releases the lines and the chip (they keep the levels last set: set them safe first). The
 * recorder's record stays readable until cs_gpio_io_free. */
void cs_gpio_io_close(cs_gpio_io_t *io);
/* Frees the record (after cs_gpio_io_close). */
void cs_gpio_io_free(cs_gpio_io_t *io);
/* Writes the record as CSV, one row per line change: "t_ns,planned_ns,line,level" with times
 * relative to t0_ns, after a "# curvestep gpio record" header line carrying `header` (may be
 * NULL). Returns 0, or -1 on a write error. */
int cs_gpio_io_write_record(const cs_gpio_io_t *io, FILE *f, int64_t t0_ns, const char *header);
/* CLOCK_MONOTONIC in ns. */
int64_t cs_gpio_io_now_ns(void);
/* Waits until CLOCK_MONOTONIC reaches t ns: sleeps (clock_nanosleep, slices of at most slice ns)
 * until spin ns before t, then spins. Returns false as soon as stop(ctx) is true (asked after
 * each slice; stop may be NULL), true at t. Not for a signal handler. */
bool cs_gpio_io_wait_until(int64_t t, int64_t spin, int64_t slice, bool (*stop)(const void *ctx),
                           const void *ctx);

#endif
