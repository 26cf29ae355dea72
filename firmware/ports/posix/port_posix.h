/* port_posix: the port in a POSIX process, for the simulator and the tests. Time is simulated
 * (no sleeping): port_posix_run jumps from one timer deadline to the next and calls the step
 * interrupt there, so a job runs as fast as the CPU allows and always the same way. Every STEP
 * pulse is recorded as an edge (time in ticks, axis, direction taken from the DIR lines). */
#ifndef PORT_POSIX_H
#define PORT_POSIX_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_exlog.h"
#include "port.h"

/* One recorded step: rising STEP edge at tick t on axis, dir = +1 or -1 (DIR line level after
 * the machine's inversion, i.e. the direction the motor turned). */
typedef struct {
    uint64_t t;
    uint8_t axis;
    int8_t dir;
} port_posix_edge_t;

/* One pen setting (port_pen_set): at tick t the servo's pulse became pulse_us. */
typedef struct {
    uint64_t t;
    uint16_t pulse_us;
} port_posix_pen_t;

/* One spindle / laser output setting (port_spindle_set): from tick t on, duty (1/1000), mode. */
typedef struct {
    uint64_t t;
    uint16_t duty;
    uint8_t mode;
} port_posix_spindle_t;

/* The simulated inputs: model(ctx, pos) gives the input bits for the positions pos[0..8) in
 * steps seen on the STEP/DIR lines (the physical machine); evaluated after every step interrupt
 * that stepped, and the attached edge hook (port_inputs_attach) is called there when the bits
 * change, as a real board's pin interrupt would. NULL: every input inactive. Kept across resets. */
void port_posix_inputs_model(uint16_t (*model)(void *ctx, const int64_t *pos), void *ctx);
/* Forces the bits in mask to the levels in value (an e-stop pressed by a test) and reports the
 * change to the hook at once; mask 0 releases them. */
void port_posix_inputs_force(uint16_t mask, uint16_t value);
/* The spindle settings since reset, in time order; *n gets their count. */
const port_posix_spindle_t *port_posix_spindles(size_t *n);
/* Forgets everything (time 0, timer stopped, no edges) and sets the tick rate and which axes have
 * an inverted DIR line (bit i = axis i). */
void port_posix_reset(uint32_t tick_hz, uint8_t invert_mask);
/* Simulated time, 64-bit ticks (port_ticks_now is its low 32 bits). */
uint64_t port_posix_now(void);
/* Runs the step timer until the attached stepper is idle (starting the timer if it is stopped
 * and work is queued) or until simulated time reaches `until` (UINT64_MAX: no limit; an `until`
 * in the past runs nothing and leaves the time as it is). Returns false when a fault was raised
 * or no stepper is attached. */
bool port_posix_run(uint64_t until);
/* Lets simulated time pass to `until` with the step timer stopped (a device at rest, e.g. held):
 * nothing happens when the timer is armed or work is queued, or when `until` is not ahead. */
void port_posix_idle_until(uint64_t until);
/* Runs exactly one step interrupt (starting the timer if work is queued): advances time to its
 * deadline. false when the stepper is idle with the timer stopped, or after a fault. */
bool port_posix_step(void);
/* The recorded edges, in time order; *n gets their count. */
const port_posix_edge_t *port_posix_edges(size_t *n);
/* The pen settings since reset, in time order (always recorded); *n gets their count. */
const port_posix_pen_t *port_posix_pens(size_t *n);
/* Turns edge recording on (the default) or off; false on out of memory while recording. */
void port_posix_record(bool on);
bool port_posix_record_ok(void);
/* Signed step count per axis seen on the STEP/DIR lines since reset. */
int64_t port_posix_position(unsigned axis);
/* Code passed to port_fault since reset (CS_OK when none). */
cs_err_t port_posix_fault(void);
/* The UART: file descriptors (non-blocking reads); -1 disables. */
void port_posix_uart(int fd_in, int fd_out);
/* The UART through functions instead (the simulator's line with its faults): port_uart_read and
 * port_uart_write call rd / wr with ctx; NULL rd and wr go back to the file descriptors. */
void port_posix_uart_hooks(size_t (*rd)(void *ctx, uint8_t *buf, size_t max),
                           size_t (*wr)(void *ctx, const uint8_t *buf, size_t len), void *ctx);
/* The STEP edges logged by the step interrupt on the executor's clock since reset (cs_exlog, as
 * the Cortex-M3 port logs them). */
cs_exlog_edges_t port_posix_edge_log(void);

#endif
