/* cs_gpio_link: the GPIO link's open state, shared by its job operations (cs_gpio_cmd.c:
 * `stream --gpio`, `serve --gpio`) and its machine-control commands (cs_gpio_ctl.c: `home`,
 * `probe`, `jog`, `unlock` with --gpio): the [gpio] section, the output lines (a chip or the
 * recorder), the inputs (cs_gpio_in) with the state kept between commands (cs_gpio_state), the
 * step thread's last run. Host only. */
#ifndef CS_GPIO_LINK_H
#define CS_GPIO_LINK_H

#include <signal.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_ctlcfg.h"
#include "cs_gpio_cfg.h"
#include "cs_gpio_in.h"
#include "cs_gpio_io.h"
#include "cs_gpio_pwm.h"
#include "cs_gpio_run.h"
#include "cs_gpio_state.h"
#include "cs_joblink.h"

typedef struct {
    const cs_machine_t *m;
    const char *record; /* record:FILE: the file; NULL: a chip */
    cs_gpio_cfg_t cfg;
    cs_gpio_lines_t lines;
    cs_gpio_run_opts_t ro;
    cs_gpio_io_t io;
    bool io_open;
    cs_segment_t *own;           /* segments taken from the job's messages (the daemon) */
    cs_motion_pen_t *own_pens;   /* and their pen events */
    const cs_motion_pen_t *pens; /* servo pen events ([pen] mode = servo): cs_gpio_pwm */
    size_t npens;
    cs_gpio_io_t pio; /* the pen's line, its own request */
    bool pio_open;
    cs_gpio_pwm_t pw;
    const cs_segment_t *segs;
    size_t nsegs, first;
    uint64_t ticks; /* the job's planned time from segment `first` on, executor ticks */
    cs_gpio_run_t run;
    double wall;
    /* inputs and the state between commands */
    cs_ctlcfg_t ctl;  /* [homing], and the recorder's simulated [limits] / [probe] */
    cs_gpio_in_t in;
    bool in_open;
    bool has_in;      /* an input can trip: the state file is kept */
    cs_gpio_state_t st;
    bool st_loaded;   /* read: written back at close */
    char state_path[400];
    int64_t t0_first; /* the first run's tick 0 (the record's time origin) */
} cs_gpio_link_t;

/* Opens the GPIO machine of l->cfg (--gpio CHIP or record:FILE, the machine file) for machine m
 * for a control command: the axes in mask `axes` (bit i: axis i) must be wired (the recorder
 * wires them all), the
 * inputs and the state are read; an alarm does not refuse (the command decides). record_cap:
 * set calls the recorder keeps for the whole command. CS_EXIT_OK, or a status with l->why. */
int cs_gpio_link_open_ctl(cs_joblink_t *l, const cs_machine_t *m, unsigned axes, size_t record_cap);
/* The open link (after cs_gpio_link_open_ctl). */
cs_gpio_link_t *cs_gpio_link_of(cs_joblink_t *l);
/* Runs segs on the step thread with the inputs watched (watch / release bits, hard limits),
 * Ctrl-C (*interrupt >= 1) stopping it at once; the state's position follows the steps made,
 * a hard-limit or e-stop trip enters the alarm. The run's result is in cs_gpio_link_of(l)->run.
 * 0, or an errno when the thread cannot start. */
int cs_gpio_link_move(cs_joblink_t *l, const cs_segment_t *segs, size_t n, uint16_t watch,
                      uint16_t release, bool hard_limits, volatile sig_atomic_t *interrupt);

#endif
