/* cs_gpio_io: libgpiod 1.6 backend (chip + one bulk output request) and the recorder. */
#include "cs_gpio_io.h"

#include <ctype.h>
#include <errno.h>
#include <gpiod.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

int64_t cs_gpio_io_now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

bool cs_gpio_io_wait_until(int64_t t, int64_t spin, int64_t slice, bool (*stop)(const void *ctx),
                           const void *ctx)
{
    for (;;) {
        int64_t now = cs_gpio_io_now_ns();
        if (now >= t)
            return true;
        if (t - now <= spin)
            break;
        int64_t wake = t - spin;
        if (wake - now > slice)
            wake = now + slice;
        struct timespec ts = {(time_t)(wake / 1000000000), (long)(wake % 1000000000)};
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL);
        if (stop && stop(ctx))
            return false;
    }
    while (cs_gpio_io_now_ns() < t) {
#if defined(__x86_64__) || defined(__i386__)
        __builtin_ia32_pause();
#endif
    }
    return true;
}

static void io_init(cs_gpio_io_t *io, cs_gpio_io_kind_t kind, const cs_gpio_lines_t *l)
{
    memset(io, 0, sizeof *io);
    io->kind = kind;
    io->lines = *l;
    io->levels = l->initial;
}

/* The chip by the kind of name given: path, number, "gpiochipN" name, else label. */
static struct gpiod_chip *open_any(const char *chip)
{
    if (chip[0] == '/')
        return gpiod_chip_open(chip);
    bool digits = chip[0] != '\0';
    for (const char *p = chip; *p; p++)
        if (!isdigit((unsigned char)*p))
            digits = false;
    if (digits)
        return gpiod_chip_open_by_number((unsigned)strtoul(chip, NULL, 10));
    if (strncmp(chip, "gpiochip", 8) == 0)
        return gpiod_chip_open_by_name(chip);
    return gpiod_chip_open_by_label(chip);
}

static void physical(const cs_gpio_io_t *io, uint32_t levels, int *vals)
{
    for (unsigned i = 0; i < io->lines.n; i++)
        vals[i] = (int)(((levels >> i) & 1u) ^ (io->lines.active_low[i] ? 1u : 0u));
}

int cs_gpio_io_open_chip(cs_gpio_io_t *io, const char *chip, const cs_gpio_lines_t *l, char *err,
                         size_t errlen)
{
    io_init(io, CS_GPIO_IO_CHIP, l);
    snprintf(io->chip_name, sizeof io->chip_name, "%s", chip);
    if (l->n > CS_GPIO_LINES_MAX) {
        snprintf(err, errlen, "GPIO chip %s: more than %d lines", chip, CS_GPIO_LINES_MAX);
        return -1;
    }
    errno = 0;
    struct gpiod_chip *c = open_any(chip);
    if (c == NULL) {
        int e = errno ? errno : ENOENT;
        const char *dev = strncmp(chip, "gpiochip", 8) == 0 ? chip : "gpiochipN";
        if (e == EACCES || e == EPERM)
            snprintf(err, errlen,
                     "cannot open GPIO chip %s: %s. Check the permissions of /dev/%s: your user "
                     "must be in its group (usually gpio: sudo usermod -aG gpio $USER, then log "
                     "in again) or a udev rule must grant it (README, GPIO)",
                     chip, strerror(e), dev);
        else
            snprintf(err, errlen,
                     "cannot open GPIO chip %s: %s. Check that /dev/%s exists (ls /dev/gpiochip*; "
                     "gpiodetect lists each chip with its label and line count) and that this "
                     "kernel has GPIO support; the chip name (gpiochipN, /dev/gpiochipN, N or the "
                     "chip's label); and the permissions: your user in the gpio group or a udev "
                     "rule (README, GPIO)",
                     chip, strerror(e), dev);
        return -1;
    }
    if (l->n == 0) { /* the chip is there; the caller has nothing to drive on it */
        snprintf(err, errlen, "GPIO chip %s (%s): no lines to drive", chip, gpiod_chip_label(c));
        gpiod_chip_close(c);
        return -2;
    }
    unsigned nl = gpiod_chip_num_lines(c);
    for (unsigned i = 0; i < l->n; i++)
        if (l->offset[i] >= nl) {
            snprintf(err, errlen,
                     "GPIO chip %s (%s) has %u lines (0..%u): %s = %u is beyond it; check the "
                     "[gpio] offsets against gpioinfo %s",
                     chip, gpiod_chip_label(c), nl, nl ? nl - 1 : 0, l->name[i], l->offset[i],
                     gpiod_chip_name(c));
            gpiod_chip_close(c);
            return -1;
        }
    struct gpiod_line_bulk *b = calloc(1, sizeof *b);
    if (b == NULL) {
        snprintf(err, errlen, "GPIO chip %s: out of memory", chip);
        gpiod_chip_close(c);
        return -1;
    }
    unsigned offs[CS_GPIO_LINES_MAX];
    for (unsigned i = 0; i < l->n; i++)
        offs[i] = l->offset[i];
    int vals[CS_GPIO_LINES_MAX];
    physical(io, l->initial, vals);
    if (gpiod_chip_get_lines(c, offs, l->n, b) != 0 ||
        gpiod_line_request_bulk_output(b, "curvestep", vals) != 0) {
        int e = errno;
        if (e == EBUSY)
            snprintf(err, errlen,
                     "GPIO chip %s: a line of the [gpio] section is in use by another consumer "
                     "(gpioinfo %s shows which and by whom): %s",
                     chip, gpiod_chip_name(c), strerror(e));
        else
            snprintf(err, errlen,
                     "GPIO chip %s: cannot request the %u [gpio] lines as outputs: %s; check "
                     "gpioinfo %s and the permissions of /dev/%s",
                     chip, l->n, strerror(e), gpiod_chip_name(c), gpiod_chip_name(c));
        free(b);
        gpiod_chip_close(c);
        return -1;
    }
    io->chip = c;
    io->bulk = b;
    return 0;
}

int cs_gpio_io_open_recorder(cs_gpio_io_t *io, const cs_gpio_lines_t *l, size_t capacity)
{
    io_init(io, CS_GPIO_IO_RECORDER, l);
    if (l->n == 0 || l->n > CS_GPIO_LINES_MAX)
        return -1;
    io->cap = capacity ? capacity : 1;
    io->rec = malloc(io->cap * sizeof *io->rec);
    if (io->rec == NULL)
        return -1;
    /* Touch every page now: the step thread must not take page faults on the record. */
    memset(io->rec, 0, io->cap * sizeof *io->rec);
    return 0;
}

int cs_gpio_io_set(cs_gpio_io_t *io, uint32_t mask, uint32_t levels, int64_t planned_ns,
                   int64_t *t_ns)
{
    uint32_t next = (io->levels & ~mask) | (levels & mask);
    uint32_t changed = next ^ io->levels;
    io->levels = next;
    if (io->kind == CS_GPIO_IO_CHIP) {
        if (changed == 0) {
            *t_ns = cs_gpio_io_now_ns();
            return 0;
        }
        int vals[CS_GPIO_LINES_MAX];
        physical(io, next, vals);
        int rc = gpiod_line_set_value_bulk(io->bulk, vals);
        *t_ns = cs_gpio_io_now_ns();
        return rc == 0 ? 0 : -1;
    }
    int64_t t = cs_gpio_io_now_ns();
    *t_ns = t;
    if (changed == 0)
        return 0;
    if (io->nrec >= io->cap) {
        io->dropped++;
        return 0;
    }
    cs_gpio_edge_t *e = &io->rec[io->nrec++];
    e->t_ns = t;
    e->planned_ns = planned_ns;
    e->mask = changed;
    e->levels = next & changed;
    return 0;
}

void cs_gpio_io_close(cs_gpio_io_t *io)
{
    if (io->kind == CS_GPIO_IO_CHIP) {
        if (io->bulk)
            gpiod_line_release_bulk(io->bulk);
        if (io->chip)
            gpiod_chip_close(io->chip);
        free(io->bulk);
        io->bulk = NULL;
        io->chip = NULL;
    }
}

void cs_gpio_io_free(cs_gpio_io_t *io)
{
    free(io->rec);
    io->rec = NULL;
    io->nrec = io->cap = 0;
}

int cs_gpio_io_write_record(const cs_gpio_io_t *io, FILE *f, int64_t t0_ns, const char *header)
{
    fprintf(f, "# curvestep gpio record%s%s\n", header ? " " : "", header ? header : "");
    fprintf(f, "t_ns,planned_ns,line,level\n");
    for (size_t k = 0; k < io->nrec; k++) {
        const cs_gpio_edge_t *e = &io->rec[k];
        for (unsigned i = 0; i < io->lines.n; i++)
            if (e->mask >> i & 1u)
                fprintf(f, "%lld,%lld,%s,%u\n", (long long)(e->t_ns - t0_ns),
                        (long long)(e->planned_ns - t0_ns), io->lines.name[i],
                        (unsigned)(e->levels >> i & 1u));
    }
    return fflush(f) == 0 && !ferror(f) ? 0 : -1;
}
