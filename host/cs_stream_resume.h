/* cs_stream_resume: the command-line side of resuming a job (docs/streaming.md, "Resume"): the
 * position a user states (--position X,Y,Z in mm) in the device's steps, and where a
 * segments-mode job leaves the machine after its first n messages, so that a stated position
 * that is not where message n left the machine is refused before anything moves. Host only. */
#ifndef CS_STREAM_RESUME_H
#define CS_STREAM_RESUME_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "cs_err.h"
#include "cs_machine.h"
#include "cs_stream.h"

/* "X,Y,Z" (or "X,Y" on a 2-axis machine; missing axes are 0) in mm -> steps per axis, rounded
 * to the nearest step as the planner rounds (cs_planner pos_to_steps). CS_ERR_PARSE for text
 * that is not n_axes comma-separated numbers, CS_ERR_RANGE outside the fixed-point range. */
cs_err_t cs_stream_resume_position(const char *text, const cs_machine_t *m,
                                   int32_t steps[CS_AXES]);
/* Steps per axis the job's SEGMENT messages 1..n add up to: where a segments-mode job started
 * at the origin leaves the machine after message n. */
void cs_stream_resume_steps_after(const cs_stream_job_t *job, size_t n, int64_t steps[CS_AXES]);
/* After a run that did not finish on a device that numbered the job (r->numbered): the last
 * message the device confirmed finished (K), the last one it may have executed (M: sent, so
 * perhaps received and run), where message K leaves the machine (mm) and the commands that
 * resume: --resume when the device did not reset, --resume-from N --position X,Y,Z when it
 * did (N between K and M: what the machine shows). Nothing for other runs. */
void cs_stream_resume_hint(FILE *out, const cs_stream_job_t *job, const cs_stream_result_t *r,
                           const cs_machine_t *m, const char *file);

#endif
