/* cs_stream_cmd: the exit statuses of `stream` that every link shares. The command parses its
 * options and plans the job whole (cs_stream_cmd.c) before anything is sent; then one link runs
 * it through cs_joblink: the serial protocol (cs_stream), Modbus RTU/TCP (cs_modbus_cmd.c) or
 * GPIO pins (cs_gpio_cmd.c). Every link prints the same summary lines and returns the same exit
 * statuses (cs_joblink_report). Host only. */
#ifndef CS_STREAM_CMD_H
#define CS_STREAM_CMD_H

#include <signal.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cs_machine.h"
#include "cs_machine_ini.h"
#include "cs_segment.h"
#include "cs_stream.h"

/* Exit statuses of `stream` beyond the shared ones (cs_cmd.h); every link uses them. */
enum {
    CS_EXIT_NO_DEVICE =
        4,              /* the port cannot be opened, no device answered, or it is incompatible */
    CS_EXIT_RESET = 5,  /* the device reset mid-job */
    CS_EXIT_CLOSED = 6, /* the link closed or the device stopped answering mid-job */
    CS_EXIT_DEV_ERROR = 7,  /* the device refused a message (ERROR) */
    CS_EXIT_INTERRUPTED = 8 /* Ctrl-C: held, then aborted */
};

#endif
