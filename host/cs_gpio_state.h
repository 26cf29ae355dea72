/* cs_gpio_state: what a GPIO machine keeps between commands, where a device keeps it in RAM:
 * the alarm (a hard limit, the e-stop, a failed homing or probe: motion refused until `curvestep
 * unlock` or `curvestep home`), the machine position in steps (set by homing, moved by every
 * job), the axes homed, and for the recorder the simulated machine's offset (physical = machine
 * + off, steps: where the simulated switches are). A small text file (docs/gpio.md "Inputs"),
 * `[gpio] state = PATH`, by default $XDG_RUNTIME_DIR/curvestep-gpio-CHIP.state (else
 * $HOME/.curvestep-gpio-CHIP.state) on a chip and FILE.state beside a record:FILE. Host only. */
#ifndef CS_GPIO_STATE_H
#define CS_GPIO_STATE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_machine.h"

typedef struct {
    uint8_t alarm;        /* 0, or the cs_proto_alarm_t the machine is in */
    uint16_t inputs;      /* the input bits when it was saved */
    int32_t pos[CS_AXES]; /* machine position, steps */
    int64_t off[CS_AXES]; /* the recorder's physical position minus the machine's, steps */
    uint16_t homed;       /* bit i: axis i homed */
} cs_gpio_state_t;

/* The state file's path: cfg_state when given, else beside the record (record:FILE ->
 * FILE.state), else $XDG_RUNTIME_DIR/curvestep-gpio-CHIP.state, else
 * $HOME/.curvestep-gpio-CHIP.state (never /tmp). 0, or -1 when none applies. */
int cs_gpio_state_path(const char *cfg_state, const char *record, const char *chip, char *out,
                       size_t outlen);
/* Reads the state (a missing file: everything 0, no alarm). 0, or -1 with "PATH: reason". */
int cs_gpio_state_load(const char *path, cs_gpio_state_t *s, char *err, size_t errlen);
/* Writes it (to PATH.tmp, not through a symbolic link, then renamed). 0, or -1 with errno set. */
int cs_gpio_state_save(const char *path, const cs_gpio_state_t *s);

#endif
