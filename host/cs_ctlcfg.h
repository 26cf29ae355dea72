/* cs_ctlcfg: the machine file's control sections (docs/controller.md, man curvestep-machine(5)):
 * [homing] (the order the axes home in, seek and latch speeds, pull-off, search distance, which
 * end each switch is at and the position set there), [limits] (where the simulator's limit
 * switches are, in the machine's coordinates at boot), [probe] (the simulator's probe surface)
 * and [spindle] (laser mode, the S of full power). Read in a second pass over the file, as
 * [gpio] is (cs_machine_ini skips these sections). Also builds the HOME messages of a homing
 * cycle and gives the simulator's switch and probe states for a position. Host only. */
#ifndef CS_CTLCFG_H
#define CS_CTLCFG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_machine.h"
#include "cs_proto.h"

typedef struct {
    /* [homing] */
    unsigned n_order;          /* axes in order[] (0: homing not configured) */
    uint8_t order[CS_AXES];    /* order = zxy: axis indices */
    double seek, latch;        /* mm/s: seek = 20, latch = 2 */
    double pulloff;            /* mm: pulloff = 1 */
    double search;             /* mm: 0 = 1.5 x the axis's travel length */
    bool at_max[CS_AXES];      /* x = min | max: the end the switch is at (min) */
    bool has_pos[CS_AXES];     /* x_pos = mm given (else the travel's end at the switch) */
    double pos[CS_AXES];
    /* [limits]: switch trip points, mm (the simulator's; x_min = ... / x_max = ...) */
    bool has_min[CS_AXES], has_max[CS_AXES];
    double min_mm[CS_AXES], max_mm[CS_AXES];
    /* [probe]: z = mm: the probe touches at or below it (the simulator's) */
    bool has_probe;
    double probe_z;
    /* [spindle] */
    bool laser;   /* laser = true: power scaled by speed, off in rapids (Grbl $32) */
    double s_max; /* s_max = 1000: the S of full power (Grbl $30) */
} cs_ctlcfg_t;

/* Nothing configured: no homing, no switches, no probe; seek 20, latch 2, pull-off 1, s_max
 * 1000, laser off. */
void cs_ctlcfg_default(cs_ctlcfg_t *c);
/* True for the sections this module reads (homing, limits, probe, spindle). */
bool cs_ctlcfg_section(const char *section);
/* Reads those sections of file path (NULL: the defaults) for machine *m (the axes it has) over
 * the defaults. 0, or -1 with "file:line: reason" in err. */
int cs_ctlcfg_load(const char *path, const cs_machine_t *m, cs_ctlcfg_t *c, char *err,
                   size_t errlen);
/* The same from a string (name for messages). */
int cs_ctlcfg_parse(const char *text, const char *name, const cs_machine_t *m, cs_ctlcfg_t *c,
                    char *err, size_t errlen);
/* The HOME message of the k-th axis of the order (k < n_order): CS_ERR_RANGE when a value does
 * not fit the message (docs/protocol.md HOME). */
cs_err_t cs_ctlcfg_home_msg(const cs_ctlcfg_t *c, const cs_machine_t *m, unsigned k,
                            cs_proto_msg_t *out);
/* The simulator's input bits (CS_PROTO_IN_*) at position mm[0..CS_AXES): a min switch is active
 * at or below its trip point, a max switch at or above, the probe at or below the surface. */
uint16_t cs_ctlcfg_inputs(const cs_ctlcfg_t *c, const double mm[CS_AXES]);
/* What ALARM:code means (Grbl's alarm codes, curvestep's 10 = e-stop; docs/controller.md). */
const char *cs_ctlcfg_alarm_text(uint8_t code);
/* True when [limits] or [probe] give the simulator anything to trip on. */
bool cs_ctlcfg_has_inputs(const cs_ctlcfg_t *c);

#endif
