/* cs_fw_modbus: the device's Modbus front end (docs/modbus.md), the same on a board and in the
 * simulator. Owns the application side of the core's register map (cs_modbus: its
 * cs_modbus_app_t hooks) over the motion side (cs_fw_motion): a mailbox write queues its SEGMENT
 * or CURVE, the command register holds, resumes, aborts or resets, the input registers show the
 * identity and live status. An execution error stops the job: the first one is latched (state
 * FAULT, its code and sequence in the status) and the motion aborted, until a RESET command.
 * It also owns the writer lease (docs/modbus.md, "The writer lease"): one token at a time may
 * write the mailbox; the lease ends CS_FW_MODBUS_LEASE_MS after its holder's last claim or
 * write, on the clock the caller gives (cs_fw_modbus_clock).
 * The transport (the core's RTU server on a UART, or libmodbus TCP in the simulator) feeds the
 * map; this module never touches it. Freestanding C99: no heap, no float, no libc. */
#ifndef CS_FW_MODBUS_H
#define CS_FW_MODBUS_H

#include <stdint.h>

#include "cs_err.h"
#include "cs_fw_motion.h"
#include "cs_modbus.h"

/* How long a lease lasts after its holder's last claim or mailbox write (the host renews every
 * second while it streams, so five renewals may be lost before it ends). */
#define CS_FW_MODBUS_LEASE_MS 5000u

typedef struct {
    cs_fw_motion_t *mo;
    uint32_t boot;
    uint16_t error, error_seq; /* the latched execution error (0: none) */
    uint16_t lease_token;      /* holder of the writer lease (0: none) */
    uint32_t lease_until_ms;   /* when it ends unless renewed (now_ms's clock) */
    uint32_t now_ms;           /* the caller's millisecond clock (wraps) */
} cs_fw_modbus_t;

/* Sets up the front end over mo (kept) with boot id boot_id, and fills *app with its hooks (ctx
 * = fm) for cs_modbus_map_init. Not ISR-safe. */
void cs_fw_modbus_init(cs_fw_modbus_t *fm, cs_fw_motion_t *mo, uint32_t boot_id,
                       cs_modbus_app_t *app);
/* The map's hooks (ctx: the cs_fw_modbus_t). submit: CS_OK, CS_ERR_FULL when no slot is free,
 * CS_ERR_UNSUPPORTED for a type the build does not take. Main loop. */
cs_err_t cs_fw_modbus_submit(void *ctx, const cs_proto_msg_t *m, uint16_t seq);
void cs_fw_modbus_command(void *ctx, uint16_t cmd);
void cs_fw_modbus_status(void *ctx, cs_modbus_status_t *st);
/* The lease hook (cs_modbus_app_t.lease): CS_OK or CS_ERR_LEASED (another token holds an
 * unexpired lease). Main loop. */
cs_err_t cs_fw_modbus_lease(void *ctx, uint8_t op, uint16_t token);
/* Sets the clock the lease runs on: milliseconds, wrapping; call before handling requests. */
void cs_fw_modbus_clock(cs_fw_modbus_t *fm, uint32_t now_ms);
/* Runs the motion (cs_fw_motion_poll) and latches its errors. Main loop, once a pass. */
void cs_fw_modbus_poll(cs_fw_modbus_t *fm);
/* Latches the motion's waiting errors without running it (a caller that paces the motion
 * itself, as the simulator does). Main loop. */
void cs_fw_modbus_collect(cs_fw_modbus_t *fm);

#endif
