/* cs_daemon_link: the links the daemon (`curvestep serve`) streams its jobs over, behind two
 * calls: open what stays open between jobs (the serial port), and run one job in the job's child
 * process over the configured link, the serial protocol (cs_stream) or Modbus TCP/RTU
 * (cs_modbus_stream), with the same interrupt, pause and progress contract and the same result.
 * Host only. */
#ifndef CS_DAEMON_LINK_H
#define CS_DAEMON_LINK_H

#include <signal.h>
#include <stdio.h>

#include "cs_daemon.h"
#include "cs_machine.h"
#include "cs_serial.h"
#include "cs_stream.h"

/* The link's name for messages: the port, HOST:PORT or the RTU device. */
const char *cs_daemon_link_name(const cs_daemon_cfg_t *cfg);
/* Opens what the daemon keeps open (the serial port of --port; nothing for Modbus, whose client
 * is opened by each job). 0, or -1 with errno. */
int cs_daemon_link_open(const cs_daemon_cfg_t *cfg, cs_serial_t *ser);
/* Runs job over the link (ser: the port opened above, serial only), for machine m; interrupt,
 * pause and progress as cs_stream_opts_t's. Fills *r (a Modbus client that cannot be opened:
 * outcome NO_DEVICE, the reason in r->why). CS_OK, or an error from the run itself. */
cs_err_t cs_daemon_link_run(const cs_daemon_cfg_t *cfg, cs_serial_t *ser, const cs_machine_t *m,
                            const cs_stream_job_t *job, volatile sig_atomic_t *interrupt,
                            volatile sig_atomic_t *pause, FILE *progress, cs_stream_result_t *r);

#endif
