/* cs_gpio_cfg: [gpio] section -> cs_gpio_cfg_t, every value range-checked (docs/gpio.md). */
#include "cs_gpio_cfg.h"

#include <ctype.h>
#include <errno.h>
#include <ini.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static const char *const axis_names[CS_AXES] = {"x", "y", "z", "a"};

typedef struct {
    cs_gpio_cfg_t *c;
    const cs_machine_t *m;
    char reason[200];
} ctx_t;

void cs_gpio_cfg_default(cs_gpio_cfg_t *c, const cs_machine_t *m)
{
    memset(c, 0, sizeof *c);
    for (unsigned i = 0; i < CS_AXES; i++)
        c->step[i] = c->dir[i] = -1;
    c->enable = -1;
    c->pen = -1;
    for (unsigned i = 0; i < CS_AXES; i++)
        c->lim_min[i] = c->lim_max[i] = -1;
    c->probe = c->estop = -1;
    c->limit_active_low = c->probe_active_low = c->estop_active_low = true;
    c->step_active_low = false;
    c->enable_active_low = true;
    /* The executor's own pulse (what the simulator and a firmware port give): the longest of
     * the axes', pulse_ticks / tick_hz. */
    uint64_t ticks = 1;
    for (unsigned i = 0; i < m->n_axes && i < CS_AXES; i++)
        if (m->axis[i].pulse_ticks > ticks)
            ticks = m->axis[i].pulse_ticks;
    uint64_t hz = m->tick_hz ? m->tick_hz : 1;
    c->pulse_ns = (uint32_t)((ticks * 1000000000u + hz - 1) / hz);
    c->dir_setup_ns = 1000;
    c->enable_ns = 10000000;
    c->spin_ns = 100000;
    c->rt_priority = 50;
}

bool cs_gpio_cfg_has_inputs(const cs_gpio_cfg_t *c)
{
    bool any = c->probe >= 0 || c->estop >= 0;
    for (unsigned i = 0; i < CS_AXES; i++)
        any = any || c->lim_min[i] >= 0 || c->lim_max[i] >= 0;
    return any;
}

bool cs_gpio_cfg_wired(const cs_gpio_cfg_t *c, unsigned axis)
{
    return axis < CS_AXES && c->step[axis] >= 0 && c->dir[axis] >= 0;
}

void cs_gpio_cfg_chip_name(const char *user, char *out, size_t outlen)
{
    const char *s = user;
    if (strncmp(s, "/dev/", 5) == 0)
        s += 5;
    bool digits = *s != '\0';
    for (const char *p = s; *p; p++)
        if (!isdigit((unsigned char)*p))
            digits = false;
    if (digits)
        snprintf(out, outlen, "gpiochip%s", s);
    else if (strncmp(s, "gpiochip", 8) == 0)
        snprintf(out, outlen, "%s", s);
    else
        snprintf(out, outlen, "%s", user);
}

static int fail(ctx_t *x, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static int fail(ctx_t *x, const char *fmt, ...)
{
    if (x->reason[0] == '\0') { /* libinih reports the first bad line: keep its reason */
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(x->reason, sizeof x->reason, fmt, ap);
        va_end(ap);
    }
    return 0;
}

static bool parse_num(const char *v, double *out)
{
    char *end;
    errno = 0;
    double d = strtod(v, &end);
    while (*end == ' ' || *end == '\t')
        end++;
    if (end == v || *end != '\0' || errno != 0 || !isfinite(d))
        return false;
    *out = d;
    return true;
}

static int parse_bool(const char *v)
{
    if (strcasecmp(v, "true") == 0 || strcmp(v, "1") == 0 || strcasecmp(v, "yes") == 0)
        return 1;
    if (strcasecmp(v, "false") == 0 || strcmp(v, "0") == 0 || strcasecmp(v, "no") == 0)
        return 0;
    return -1;
}

/* The key naming line offset `off` other than `self`, or NULL (each line is used once, so the
 * order the keys are looked at in does not matter). */
static const char *offset_owner(const cs_gpio_cfg_t *c, int off, const int *self, char *buf,
                                size_t len)
{
    const struct {
        const int *v;
        const char *suffix;
    } per_axis[] = {{c->step, "step"}, {c->dir, "dir"}, {c->lim_min, "min"}, {c->lim_max, "max"}};
    for (unsigned k = 0; k < sizeof per_axis / sizeof per_axis[0]; k++)
        for (unsigned i = 0; i < CS_AXES; i++)
            if (&per_axis[k].v[i] != self && per_axis[k].v[i] == off) {
                snprintf(buf, len, "%s_%s", axis_names[i], per_axis[k].suffix);
                return buf;
            }
    const struct {
        const int *v;
        const char *name;
    } one[] = {{&c->enable, "enable"}, {&c->pen, "pen"}, {&c->probe, "probe"}, {&c->estop, "estop"}};
    for (unsigned k = 0; k < sizeof one / sizeof one[0]; k++)
        if (one[k].v != self && *one[k].v == off)
            return one[k].name;
    return NULL;
}

/* Microseconds (decimals allowed) in [lo, hi] -> ns. */
static bool us_to_ns(const char *v, double lo, double hi, uint32_t *ns)
{
    double d;
    if (!parse_num(v, &d) || d < lo || d > hi)
        return false;
    *ns = (uint32_t)llround(d * 1000.0);
    return true;
}

/* The line-offset field that key `name` sets, or NULL when it is not a line key. */
static int *offset_slot(cs_gpio_cfg_t *c, const char *name)
{
    int *slot = NULL;
    if (strcasecmp(name, "enable") == 0)
        slot = &c->enable;
    else if (strcasecmp(name, "pen") == 0)
        slot = &c->pen;
    else if (strcasecmp(name, "probe") == 0)
        slot = &c->probe;
    else if (strcasecmp(name, "estop") == 0)
        slot = &c->estop;
    for (unsigned i = 0; i < CS_AXES && slot == NULL; i++) {
        size_t n = strlen(axis_names[i]);
        if (strncasecmp(name, axis_names[i], n) == 0 && name[n] == '_') {
            if (strcasecmp(name + n + 1, "step") == 0)
                slot = &c->step[i];
            else if (strcasecmp(name + n + 1, "dir") == 0)
                slot = &c->dir[i];
            else if (strcasecmp(name + n + 1, "min") == 0)
                slot = &c->lim_min[i];
            else if (strcasecmp(name + n + 1, "max") == 0)
                slot = &c->lim_max[i];
        }
    }
    return slot;
}

static int handler(void *user, const char *section, const char *name, const char *value)
{
    ctx_t *x = user;
    cs_gpio_cfg_t *c = x->c;
    if (strcasecmp(section, "gpio") != 0)
        return 1; /* the machine's sections: cs_machine_ini's business */
    if (strcasecmp(name, "chip") == 0) {
        if (value[0] == '\0' || strlen(value) >= sizeof c->chip)
            return fail(x, "[gpio] chip: expected a chip name, path, number or label (< %zu chars)",
                        sizeof c->chip);
        cs_gpio_cfg_chip_name(value, c->chip, sizeof c->chip);
        return 1;
    }
    int *slot = offset_slot(c, name);
    if (slot) {
        double d;
        if (strcasecmp(value, "none") == 0) {
            *slot = -1;
            return 1;
        }
        if (!parse_num(value, &d) || d < 0 || d > CS_GPIO_OFFSET_MAX || d != floor(d))
            return fail(x, "[gpio] %s: expected a line offset 0..%d (or none)", name,
                        CS_GPIO_OFFSET_MAX);
        char buf[16];
        const char *other = offset_owner(c, (int)d, slot, buf, sizeof buf);
        if (other)
            return fail(x, "[gpio] %s: line %d is already %s", name, (int)d, other);
        *slot = (int)d;
        return 1;
    }
    bool *flag = strcasecmp(name, "step_active_low") == 0     ? &c->step_active_low
                 : strcasecmp(name, "enable_active_low") == 0 ? &c->enable_active_low
                 : strcasecmp(name, "limit_active_low") == 0  ? &c->limit_active_low
                 : strcasecmp(name, "probe_active_low") == 0  ? &c->probe_active_low
                 : strcasecmp(name, "estop_active_low") == 0  ? &c->estop_active_low
                                                              : NULL;
    if (flag) {
        int b = parse_bool(value);
        if (b < 0)
            return fail(x, "[gpio] %s: expected true or false", name);
        *flag = b == 1;
        return 1;
    }
    if (strcasecmp(name, "state") == 0) {
        if (value[0] == '\0' || strlen(value) >= sizeof c->state)
            return fail(x, "[gpio] state: expected a file path (< %zu chars)", sizeof c->state);
        snprintf(c->state, sizeof c->state, "%s", value);
        return 1;
    }
    if (strcasecmp(name, "pulse_us") == 0) {
        if (!us_to_ns(value, 0.001, 10000, &c->pulse_ns))
            return fail(x, "[gpio] %s: must be in [0.001, 10000] us", name);
    } else if (strcasecmp(name, "dir_setup_us") == 0) {
        if (!us_to_ns(value, 0, 10000, &c->dir_setup_ns))
            return fail(x, "[gpio] %s: must be in [0, 10000] us", name);
    } else if (strcasecmp(name, "spin_us") == 0) {
        if (!us_to_ns(value, 0, 10000, &c->spin_ns))
            return fail(x, "[gpio] %s: must be in [0, 10000] us", name);
    } else if (strcasecmp(name, "enable_ms") == 0) {
        double d;
        if (!parse_num(value, &d) || d < 0 || d > 4000)
            return fail(x, "[gpio] %s: must be in [0, 4000] ms", name);
        c->enable_ns = (uint32_t)llround(d * 1e6);
    } else if (strcasecmp(name, "rt_priority") == 0) {
        double d;
        if (!parse_num(value, &d) || d < 0 || d > 99 || d != floor(d))
            return fail(x, "[gpio] %s: must be an integer in 0..99 (0: no SCHED_FIFO)", name);
        c->rt_priority = (int)d;
    } else {
        return fail(x,
                    "[gpio] %s: unknown key (expected chip, x_step, x_dir, y_step, y_dir, z_step, "
                    "z_dir, a_step, a_dir, enable, pen, step_active_low, enable_active_low, pulse_us, "
                    "dir_setup_us, enable_ms, spin_us, rt_priority, x_min, x_max, y_min, y_max, "
                    "z_min, z_max, a_min, a_max, probe, estop, limit_active_low, "
                    "probe_active_low, estop_active_low or state)",
                    name);
    }
    return 1;
}

static int finish(ctx_t *x, int rc, const char *name, char *err, size_t errlen)
{
    const cs_gpio_cfg_t *c = x->c;
    const cs_machine_t *m = x->m;
    if (rc < 0) {
        snprintf(err, errlen, "%s:0: cannot read the machine file", name);
        return -1;
    }
    if (rc > 0) {
        snprintf(err, errlen, "%s:%d: %s", name, rc,
                 x->reason[0] ? x->reason : "syntax error (expected [section] or key = value)");
        return -1;
    }
    for (unsigned i = 0; i < CS_AXES; i++) {
        if ((c->step[i] >= 0) != (c->dir[i] >= 0)) {
            snprintf(err, errlen, "%s:0: [gpio] %s_step and %s_dir go together (one is missing)",
                     name, axis_names[i], axis_names[i]);
            return -1;
        }
        if ((c->lim_min[i] >= 0 || c->lim_max[i] >= 0) && i >= m->n_axes) {
            snprintf(err, errlen, "%s:0: [gpio] %s_%s: the machine has no %s axis", name,
                     axis_names[i], c->lim_min[i] >= 0 ? "min" : "max", axis_names[i]);
            return -1;
        }
        if (c->step[i] >= 0 && i >= m->n_axes) {
            snprintf(err, errlen, "%s:0: [gpio] %s_step: the machine has no %s axis", name,
                     axis_names[i], axis_names[i]);
            return -1;
        }
        if (c->step[i] < 0 || i >= m->n_axes)
            continue;
        /* The core's rule for the executor's pulse (cs_planner_init), in time: the pulse fits
         * half of the shortest step period, 1 / (max_rate * steps_per_mm). */
        double rate = (double)m->axis[i].max_rate / CS_MOTION_ONE *
                      ((double)m->axis[i].steps_per_mm / CS_MOTION_ONE);
        double half_ns = 0.5e9 / rate;
        if ((double)c->pulse_ns > half_ns) {
            snprintf(err, errlen,
                     "%s:0: [gpio] pulse_us = %.3f us does not fit half the shortest step period "
                     "of axis %s (%.3f us at max_rate)",
                     name, c->pulse_ns / 1000.0, axis_names[i], half_ns / 1000.0);
            return -1;
        }
    }
    return 0;
}

int cs_gpio_cfg_load(const char *path, const cs_machine_t *m, cs_gpio_cfg_t *c, char *err,
                     size_t errlen)
{
    ctx_t x;
    memset(&x, 0, sizeof x);
    x.c = c;
    x.m = m;
    cs_gpio_cfg_default(c, m);
    return finish(&x, ini_parse(path, handler, &x), path, err, errlen);
}

int cs_gpio_cfg_parse(const char *text, const char *name, const cs_machine_t *m, cs_gpio_cfg_t *c,
                      char *err, size_t errlen)
{
    ctx_t x;
    memset(&x, 0, sizeof x);
    x.c = c;
    x.m = m;
    cs_gpio_cfg_default(c, m);
    return finish(&x, ini_parse_string(text, handler, &x), name, err, errlen);
}
