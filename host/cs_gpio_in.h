/* cs_gpio_in: the inputs of the GPIO link: limit / home switches per axis end, the probe and the
 * e-stop, as CS_PROTO_IN_* bits (the device's, docs/protocol.md "Machine control"). Two sources
 * behind one read: a GPIO chip's lines requested for both-edge events through libgpiod 1.6 (a
 * thread of its own waits on the lines' event descriptors and publishes the levels after every
 * edge), or, with the recorder (`--gpio record:FILE`), the simulator's switch model of the
 * machine file ([limits], [probe]: cs_ctlcfg_inputs, the one the posix port's simulator uses)
 * evaluated at the position the step thread has put on the lines, and an e-stop pressed while a
 * file exists. Host only; the core never sees a line. */
#ifndef CS_GPIO_IN_H
#define CS_GPIO_IN_H

#include <pthread.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_ctlcfg.h"
#include "cs_gpio_cfg.h"
#include "cs_machine.h"

/* Input lines one chip request holds: a switch at each end of 4 axes, the probe, the e-stop. */
#define CS_GPIO_IN_MAX (2 * CS_AXES + 2)

typedef struct {
    bool sim; /* the recorder's model; else a chip */
    /* recorder */
    const cs_machine_t *m;
    const cs_ctlcfg_t *ctl;    /* [limits], [probe] (may have none) */
    int64_t off[CS_AXES];      /* physical position = machine position + off, steps */
    char estop_file[300];      /* the simulated e-stop is pressed while this file exists */
    /* chip */
    void *chip;                     /* struct gpiod_chip * (the outputs' request owns it) */
    void *line[CS_GPIO_IN_MAX];     /* struct gpiod_line * */
    uint16_t bit[CS_GPIO_IN_MAX];   /* CS_PROTO_IN_* of each line */
    unsigned n;
    pthread_t th;
    bool th_started;
    int quit;     /* main writes 1: the thread ends */
    uint64_t edges; /* edges read (the thread writes) */
    /* shared: the chip's levels, or the recorder's e-stop (__atomic) */
    uint16_t bits;
} cs_gpio_in_t;

/* Requests the [gpio] input lines of cfg on the chip the outputs opened (chip_handle: the struct
 * gpiod_chip * of cs_gpio_io_t.chip; `chip`: its name for messages) for both-edge events (each line with
 * its polarity; consumer "curvestep"), reads their levels and starts the thread that follows
 * their edges. 0 (also when cfg wires no input: in->n == 0), or -1 with one sentence in err.
 * Not real-time. */
int cs_gpio_in_open_chip(cs_gpio_in_t *in, void *chip_handle, const char *chip,
                         const cs_gpio_cfg_t *cfg, char *err, size_t errlen);
/* The recorder's inputs: ctl's switches and probe surface for machine m, physical position =
 * machine position + off (steps); the e-stop pressed while estop_file exists. */
void cs_gpio_in_open_sim(cs_gpio_in_t *in, const cs_machine_t *m, const cs_ctlcfg_t *ctl,
                         const int64_t off[CS_AXES], const char *estop_file);
/* True when the inputs can ever be active (a line wired, a simulated switch, probe or e-stop). */
bool cs_gpio_in_any(const cs_gpio_in_t *in);
/* The input bits now; pos: the machine position in steps the lines stand at (the recorder's
 * model needs it). Real-time safe: atomic loads (chip) or arithmetic (recorder). Any thread. */
uint16_t cs_gpio_in_read(const cs_gpio_in_t *in, const int32_t pos[CS_AXES]);
/* The recorder: looks at the e-stop file (main thread, between steps of the job). */
void cs_gpio_in_poll(cs_gpio_in_t *in);
/* Stops the thread and releases the lines (before cs_gpio_io_close closes the chip). */
void cs_gpio_in_close(cs_gpio_in_t *in);

#endif
