/* fw_test: the setting the firmware application's unit tests (tests/unit/test_fw_*.c) share: the
 * firmware images' default machine at 100 kHz on a freshly reset POSIX port, and the motion side
 * over it with a given queue size. */
#ifndef FW_TEST_H
#define FW_TEST_H

#include <stdint.h>

#include "cs_fw_motion.h"

/* Fills *m (cs_fw_machine_default, 100 kHz), resets the POSIX port, initialises *mo with queue
 * slots (attached to the port). 0, or -1 when the motion refused the setting. */
int fw_test_motion(cs_machine_t *m, cs_fw_motion_t *mo, uint16_t queue);

#endif
