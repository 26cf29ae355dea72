/* cs_gpio_ctl: the machine-control commands over the GPIO link (`curvestep home|probe|jog|unlock
 * --gpio CHIP`): the device's rules (cs_fw_ctl: homing's seek, back-off, latch and pull-off,
 * G38.2-G38.5 probing, the alarm and its unlock) carried out by the host on the step thread with
 * the link's inputs watched (cs_gpio_link), the alarm and the position kept in the GPIO state
 * file between commands. Output lines and exit codes as over the serial link (cs_ctl_cmd.c).
 * Host only. */
#ifndef CS_GPIO_CTL_H
#define CS_GPIO_CTL_H

#include <signal.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "cs_ctlcfg.h"
#include "cs_machine.h"

/* The machine after a command, for a caller that keeps its own picture (`curvestep grbl`). */
typedef struct {
    bool have_state;      /* the link keeps a state (inputs wired): pos, alarm, inputs valid */
    int32_t pos[CS_AXES]; /* machine position, steps */
    uint8_t alarm;        /* 0, or the cs_proto_alarm_t the machine is in */
    uint16_t inputs;      /* the input bits last read */
    bool contact;         /* probe: the probe input stopped the move */
} cs_gpio_ctl_result_t;

typedef struct {
    const char *who;          /* "home", "probe", "jog", "unlock" */
    const char *chip;         /* --gpio CHIP or record:FILE */
    const char *machine_file; /* NULL: the built-in machine */
    const cs_machine_t *m;
    const cs_ctlcfg_t *ctl; /* [homing] (order: the axes to home) */
    double feed;            /* probe, jog: mm/s */
    double xyz[3];          /* probe, jog: the target, machine mm */
    bool away, no_error;    /* probe: G38.4/.5, G38.3/.5 */
    /* a caller that runs the command inside its own program (`curvestep grbl`; all NULL for
     * the commands of their own): the lines said on out (NULL: stdout), the command stopped at
     * once when *stop > 0 (NULL: Ctrl-C, a SIGINT handler installed for the command), the
     * machine after it in *res */
    FILE *out;
    volatile sig_atomic_t *stop;
    cs_gpio_ctl_result_t *res;
} cs_gpio_ctl_args_t;

/* Each runs the command and returns its exit status (0 done, 1 bad machine file, 2 usage, 3
 * internal, 4 chip, 7 an alarm or a refusal, 8 Ctrl-C). Installs a SIGINT handler for its
 * duration when a->stop is NULL (then main thread only). */
int cs_gpio_ctl_home(const cs_gpio_ctl_args_t *a);
int cs_gpio_ctl_probe(const cs_gpio_ctl_args_t *a);
int cs_gpio_ctl_jog(const cs_gpio_ctl_args_t *a);
int cs_gpio_ctl_unlock(const cs_gpio_ctl_args_t *a);

#endif
