/* cs_sim_exlog: the simulated device's executed log on disk, for the kill-and-resume test
 * (tests/cli/test_resume.sh, docs/streaming.md "Resume"). One line per step segment the
 * executor FINISHED, `JOB_NO TICKS X Y Z A` (the job number of the queue item the segment
 * belongs to, 0 without a SETPOS since boot), appended with one write(2) a pass to a file opened
 * O_APPEND: a device killed with SIGKILL leaves every finished segment in it, and successive
 * devices (restarts) append to the same file. Owns the file and a small FIFO of the segments
 * handed to the executor and not yet finished. Host only (POSIX). */
#ifndef CS_SIM_EXLOG_H
#define CS_SIM_EXLOG_H

#include <stdint.h>

#include "cs_err.h"
#include "cs_fw_motion.h"
#include "cs_segment.h"

/* Segments handed to the executor and not finished: the ring, the one running, and a margin. */
#define CS_SIM_EXLOG_FIFO 256
CS_STATIC_ASSERT(CS_SIM_EXLOG_FIFO > CS_STEPPER_RING + 1, sim_exlog_fifo_room);

typedef struct {
    int fd;
    uint8_t done; /* segments written, mod 256 (cs_fw_motion_t.completed counts the same) */
    uint32_t head, count;
    struct {
        uint32_t job_no;
        cs_segment_t seg;
    } q[CS_SIM_EXLOG_FIFO];
} cs_sim_exlog_t;

/* Opens path for appending (created 0644) and hooks *mo's pushed segments. CS_ERR_IO when it
 * cannot be opened (errno says why). */
cs_err_t cs_sim_exlog_open(cs_sim_exlog_t *x, const char *path, cs_fw_motion_t *mo);
/* Writes the lines of the segments *mo has finished since the last call (after a poll).
 * CS_ERR_IO on a write error. */
cs_err_t cs_sim_exlog_flush(cs_sim_exlog_t *x, const cs_fw_motion_t *mo);
/* Unhooks and closes. */
void cs_sim_exlog_close(cs_sim_exlog_t *x, cs_fw_motion_t *mo);

#endif
