/* cs_stream_pen: a servo-pen job streamed as curves (`stream --mode curves`, `submit --mode
 * curves`). The device plans the strokes itself from CURVE messages, so the pen events cannot
 * come from the host's plan as in segments mode (cs_motion): they are put between the curves
 * here, by the same rule (cs_motion.c, servo_before): before a stroke starts the pen is raised
 * (PEN up_us, then a SEGMENT of settle_ms ticks without steps: the settle wait), the pen travels
 * to the stroke's start in an explicit straight rapid CURVE, comes down (PEN down_us, the settle
 * wait) and draws; the job ends with the pen raised. The device runs every curve before a PEN to
 * a stop and sets the pen once the executor has stopped (firmware/app/cs_fw_motion.c), so the
 * pen changes exactly between travel and strokes. Owns nothing beyond the call. Host only. */
#ifndef CS_STREAM_PEN_H
#define CS_STREAM_PEN_H

#include "cs_machine_ini.h"
#include "cs_stream.h"

/* As cs_stream_job_add_path, with pen's events when pen is mode servo (otherwise exactly
 * cs_stream_job_add_path). start: where the device stands when the job begins (mm Q16, the
 * first travel starts there); tick_hz: the device's executor rate (the settle waits' ticks).
 * Errors as cs_stream_job_add_path; CS_ERR_RANGE (diag names the element) for a settle wait
 * longer than the segments it is cut into can carry. */
cs_err_t cs_stream_job_add_path_pen(cs_stream_job_t *j, const cs_path_t *path, int32_t feed,
                                    cs_pos_t tol, const cs_machine_pen_t *pen, uint32_t tick_hz,
                                    const cs_vec3_t *start, cs_path_diag_t *diag);

#endif
