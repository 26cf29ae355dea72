/* cs_gpio_in: the GPIO link's inputs (see cs_gpio_in.h; docs/gpio.md "Inputs"). */
#include "cs_gpio_in.h"

#include <errno.h>
#include <gpiod.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "cs_proto.h"

/* The levels of every line (logical: the request carries the polarity). */
static uint16_t read_levels(const cs_gpio_in_t *in)
{
    uint16_t b = 0;
    for (unsigned k = 0; k < in->n; k++)
        if (gpiod_line_get_value(in->line[k]) == 1)
            b = (uint16_t)(b | in->bit[k]);
    return b;
}

/* The edge thread: waits on the lines' event descriptors (poll, 20 ms slices to see quit),
 * reads each pending event, then publishes the levels read after it (an edge missed between
 * two reads still leaves the right level). */
static void *edge_thread(void *arg)
{
    cs_gpio_in_t *in = arg;
    struct pollfd pf[CS_GPIO_IN_MAX];
    for (unsigned k = 0; k < in->n; k++) {
        pf[k].fd = gpiod_line_event_get_fd(in->line[k]);
        pf[k].events = POLLIN | POLLPRI;
    }
    while (!__atomic_load_n(&in->quit, __ATOMIC_ACQUIRE)) {
        int r = poll(pf, in->n, 20);
        if (r <= 0)
            continue;
        for (unsigned k = 0; k < in->n; k++) {
            if (!(pf[k].revents & (POLLIN | POLLPRI)))
                continue;
            struct gpiod_line_event ev;
            if (gpiod_line_event_read(in->line[k], &ev) == 0)
                __atomic_add_fetch(&in->edges, 1, __ATOMIC_RELAXED);
        }
        __atomic_store_n(&in->bits, read_levels(in), __ATOMIC_RELEASE);
    }
    return NULL;
}

static void add_in(cs_gpio_in_t *in, int offset, uint16_t bit, bool active_low, unsigned *offs,
                   bool *low, const char **names, const char *name)
{
    if (offset < 0)
        return;
    offs[in->n] = (unsigned)offset;
    low[in->n] = active_low;
    names[in->n] = name;
    in->bit[in->n++] = bit;
}

/* The input lines of cfg, in bit order: x_min .. a_min, x_max .. a_max, probe, estop. */
static void list_lines(cs_gpio_in_t *in, const cs_gpio_cfg_t *cfg, unsigned *offs, bool *low,
                       const char **names)
{
    static const char *const mins[CS_AXES] = {"x_min", "y_min", "z_min", "a_min"};
    static const char *const maxs[CS_AXES] = {"x_max", "y_max", "z_max", "a_max"};
    for (unsigned i = 0; i < CS_AXES; i++)
        add_in(in, cfg->lim_min[i], CS_PROTO_IN_MIN(i), cfg->limit_active_low, offs, low, names,
               mins[i]);
    for (unsigned i = 0; i < CS_AXES; i++)
        add_in(in, cfg->lim_max[i], CS_PROTO_IN_MAX(i), cfg->limit_active_low, offs, low, names,
               maxs[i]);
    add_in(in, cfg->probe, CS_PROTO_IN_PROBE, cfg->probe_active_low, offs, low, names, "probe");
    add_in(in, cfg->estop, CS_PROTO_IN_ESTOP, cfg->estop_active_low, offs, low, names, "estop");
}

int cs_gpio_in_open_chip(cs_gpio_in_t *in, void *chip_handle, const char *chip,
                         const cs_gpio_cfg_t *cfg, char *err, size_t errlen)
{
    memset(in, 0, sizeof *in);
    unsigned offs[CS_GPIO_IN_MAX];
    bool low[CS_GPIO_IN_MAX];
    const char *names[CS_GPIO_IN_MAX];
    list_lines(in, cfg, offs, low, names);
    if (in->n == 0)
        return 0;
    struct gpiod_chip *c = chip_handle;
    in->chip = c;
    unsigned nl = gpiod_chip_num_lines(c);
    for (unsigned k = 0; k < in->n; k++) {
        struct gpiod_line *l = offs[k] < nl ? gpiod_chip_get_line(c, offs[k]) : NULL;
        int flags = low[k] ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
        if (l == NULL || gpiod_line_request_both_edges_events_flags(l, "curvestep", flags) != 0) {
            int e = errno;
            snprintf(err, errlen,
                     "GPIO chip %s: cannot request [gpio] %s = %u as an input with edge events: "
                     "%s (%u lines on the chip; gpioinfo %s shows who holds which)",
                     chip, names[k], offs[k], offs[k] >= nl ? "beyond the chip" : strerror(e), nl,
                     gpiod_chip_name(c));
            in->n = k;
            cs_gpio_in_close(in);
            return -1;
        }
        in->line[k] = l;
    }
    __atomic_store_n(&in->bits, read_levels(in), __ATOMIC_RELEASE);
    if (pthread_create(&in->th, NULL, edge_thread, in) != 0) {
        snprintf(err, errlen, "GPIO chip %s: cannot start the input thread", chip);
        cs_gpio_in_close(in);
        return -1;
    }
    in->th_started = true;
    return 0;
}

void cs_gpio_in_open_sim(cs_gpio_in_t *in, const cs_machine_t *m, const cs_ctlcfg_t *ctl,
                         const int64_t off[CS_AXES], const char *estop_file)
{
    memset(in, 0, sizeof *in);
    in->sim = true;
    in->m = m;
    in->ctl = ctl;
    for (unsigned i = 0; i < CS_AXES; i++)
        in->off[i] = off ? off[i] : 0;
    snprintf(in->estop_file, sizeof in->estop_file, "%s", estop_file ? estop_file : "");
    cs_gpio_in_poll(in);
}

bool cs_gpio_in_any(const cs_gpio_in_t *in)
{
    if (!in->sim)
        return in->n > 0;
    return in->estop_file[0] != '\0' || (in->ctl != NULL && cs_ctlcfg_has_inputs(in->ctl));
}

uint16_t cs_gpio_in_read(const cs_gpio_in_t *in, const int32_t pos[CS_AXES])
{
    uint16_t b = __atomic_load_n(&in->bits, __ATOMIC_ACQUIRE);
    if (!in->sim || in->ctl == NULL)
        return b;
    double mm[CS_AXES] = {0}; /* the physical position, as the simulator's model takes it */
    for (unsigned i = 0; i < in->m->n_axes && i < CS_AXES; i++)
        mm[i] = (double)(pos[i] + in->off[i]) * CS_MOTION_ONE /
                (double)in->m->axis[i].steps_per_mm;
    return (uint16_t)(b | cs_ctlcfg_inputs(in->ctl, mm));
}

void cs_gpio_in_poll(cs_gpio_in_t *in)
{
    if (!in->sim || in->estop_file[0] == '\0')
        return;
    uint16_t e = access(in->estop_file, F_OK) == 0 ? CS_PROTO_IN_ESTOP : 0;
    __atomic_store_n(&in->bits, e, __ATOMIC_RELEASE);
}

void cs_gpio_in_close(cs_gpio_in_t *in)
{
    if (in->th_started) {
        __atomic_store_n(&in->quit, 1, __ATOMIC_RELEASE);
        pthread_join(in->th, NULL);
        in->th_started = false;
    }
    for (unsigned k = 0; k < in->n; k++)
        if (in->line[k])
            gpiod_line_release(in->line[k]);
    in->n = 0;
    in->chip = NULL; /* the outputs' chip: closed with them (cs_gpio_io_close) */
}
