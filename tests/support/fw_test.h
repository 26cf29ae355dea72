/* fw_test: what the tests of the device application share: the firmware images' default machine
 * at 100 kHz on a freshly reset POSIX port with the motion side over it (tests/unit/test_fw_*.c),
 * and the execution log's fingerprint of the segments a test sent (test_stream, test_modbus,
 * bench_modbus). */
#ifndef FW_TEST_H
#define FW_TEST_H

#include <stdint.h>

#include "cs_exlog.h"
#include "cs_fw_motion.h"

/* The device's execution-log fingerprint of a segment sequence (cs_exlog, FNV-1a 32), chained
 * from h (start with FW_TEST_HASH0): what the simulator prints as "executed step segments'
 * hash", for tests that compare it with the segments they sent. */
#define FW_TEST_HASH0 ((uint64_t)CS_EXLOG_HASH0)
uint64_t fw_test_hash(uint64_t h, const cs_segment_t *s);
/* Fills *m (cs_fw_machine_default, 100 kHz), resets the POSIX port, initialises *mo with queue
 * slots (attached to the port). 0, or -1 when the motion refused the setting. */
int fw_test_motion(cs_machine_t *m, cs_fw_motion_t *mo, uint16_t queue);

#endif
