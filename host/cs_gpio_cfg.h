/* cs_gpio_cfg: the [gpio] section of the machine file, for `curvestep stream --gpio`. Owns the
 * pin map (the chip, the line offset of each axis's STEP and DIR and of the shared ENABLE),
 * the lines' polarity and the step thread's timing (pulse width, DIR set-up, enable delay,
 * spin margin, SCHED_FIFO priority). Read with libinih in a pass of its own after
 * cs_machine_ini (which skips the section); keys and defaults: docs/gpio.md. Host only. */
#ifndef CS_GPIO_CFG_H
#define CS_GPIO_CFG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_machine.h"

/* Largest line offset accepted in the file (the chip's own count is checked when it opens). */
#define CS_GPIO_OFFSET_MAX 65535

typedef struct {
    char chip[64];          /* [gpio] chip: the chip the offsets belong to ("" = not given) */
    int step[CS_AXES];      /* STEP line offset of each axis, -1 = not wired */
    int dir[CS_AXES];       /* DIR line offset of each axis, -1 = not wired */
    int enable;             /* ENABLE line offset (shared by every driver), -1 = not wired */
    int pen;                /* the pen servo's line ([pen] mode = servo: cs_gpio_pwm), -1 = none */
    bool step_active_low;   /* STEP pulses low (default false: pulses high) */
    bool enable_active_low; /* ENABLE asserted low (default true: the /EN of most drivers) */
    uint32_t pulse_ns;      /* STEP pulse width, ns (default: the longest [axis] pulse) */
    uint32_t dir_setup_ns;  /* DIR stable this long before a STEP edge, ns (default 1000) */
    uint32_t enable_ns;     /* from ENABLE asserted to the first step, ns (default 10 ms) */
    uint32_t spin_ns;       /* sleep until this long before an edge, then spin (default 100 us) */
    int rt_priority;        /* SCHED_FIFO priority of the step thread, 1..99; 0 = do not ask */
    /* inputs (read with line events: cs_gpio_in), bits as CS_PROTO_IN_* */
    int lim_min[CS_AXES];   /* x_min ..: the switch at each axis's minimum end, -1 = none */
    int lim_max[CS_AXES];   /* x_max ..: at its maximum end */
    int probe;              /* the probe input, -1 = none */
    int estop;              /* the e-stop input, -1 = none */
    bool limit_active_low;  /* limit switches read active low (default true: to ground, pull-up) */
    bool probe_active_low;  /* the probe likewise (default true) */
    bool estop_active_low;  /* the e-stop likewise (default true) */
    char state[256];        /* state = PATH: alarm and position between commands ("" = default) */
} cs_gpio_cfg_t;

/* The defaults for machine *m: nothing wired, no chip, STEP active high, ENABLE active low,
 * pulse = the longest axis pulse of m (pulse_ticks / tick_hz), DIR set-up 1 us, enable delay
 * 10 ms, spin 100 us, priority 50. */
void cs_gpio_cfg_default(cs_gpio_cfg_t *c, const cs_machine_t *m);
/* Reads the [gpio] section of file `path` over the defaults (other sections are skipped: read
 * them with cs_machine_ini first and pass the machine as *m) and checks it: offsets distinct,
 * STEP and DIR given together, the pulse within half the shortest step period of every wired
 * axis. Returns 0, or -1 with "file:line: reason" in err (line 0 for whole-section checks). */
int cs_gpio_cfg_load(const char *path, const cs_machine_t *m, cs_gpio_cfg_t *c, char *err,
                     size_t errlen);
/* Same, from a string (`name` used in messages). */
int cs_gpio_cfg_parse(const char *text, const char *name, const cs_machine_t *m, cs_gpio_cfg_t *c,
                      char *err, size_t errlen);
/* True when any input line (limit switch, probe, e-stop) is wired. */
bool cs_gpio_cfg_has_inputs(const cs_gpio_cfg_t *c);
/* True when axis i has both its STEP and DIR lines. */
bool cs_gpio_cfg_wired(const cs_gpio_cfg_t *c, unsigned axis);
/* The chip name as libgpiod 1.6 spells it, from what a user may type: "gpiochip0",
 * "/dev/gpiochip0" and "0" all give "gpiochip0"; anything else (a label) is copied as is. */
void cs_gpio_cfg_chip_name(const char *user, char *out, size_t outlen);

#endif
