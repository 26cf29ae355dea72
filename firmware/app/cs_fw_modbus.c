/* cs_fw_modbus: the Modbus register map's application hooks over cs_fw_motion. See
 * cs_fw_modbus.h and docs/modbus.md. */
#include "cs_fw_modbus.h"

#include <stdbool.h>
#include <stddef.h>

void cs_fw_modbus_init(cs_fw_modbus_t *fm, cs_fw_motion_t *mo, uint32_t boot_id,
                       cs_modbus_app_t *app)
{
    /* no error latched, no lease, the clock at 0 until the caller sets it */
    *fm = (cs_fw_modbus_t){.mo = mo, .boot = boot_id != 0 ? boot_id : 1u};
    app->submit = cs_fw_modbus_submit;
    app->command = cs_fw_modbus_command;
    app->status = cs_fw_modbus_status;
    app->lease = cs_fw_modbus_lease;
    app->ctx = fm;
}

void cs_fw_modbus_clock(cs_fw_modbus_t *fm, uint32_t now_ms)
{
    fm->now_ms = now_ms;
}

/* ms left of the lease, 0 when there is none or it expired (wrap-safe: the difference of two
 * wrapping counters, read as signed). */
static uint32_t lease_left(const cs_fw_modbus_t *fm)
{
    uint32_t d = fm->lease_until_ms - fm->now_ms;
    return fm->lease_token != 0 && d - 1u < CS_FW_MODBUS_LEASE_MS ? d : 0u;
}

cs_err_t cs_fw_modbus_lease(void *ctx, uint8_t op, uint16_t token)
{
    cs_fw_modbus_t *fm = ctx;
    if (lease_left(fm) == 0)
        fm->lease_token = 0; /* expired: its holder went silent */
    bool mine = fm->lease_token == token;
    if (fm->lease_token != 0 && !mine)
        return CS_ERR_LEASED;
    if (op == CS_MODBUS_LEASE_RELEASE) {
        fm->lease_token = 0;
        return CS_OK;
    }
    if (op == CS_MODBUS_LEASE_CLAIM || (op == CS_MODBUS_LEASE_WRITE && fm->lease_token != 0)) {
        fm->lease_token = token; /* taken, or renewed by its holder's claim or write */
        fm->lease_until_ms = fm->now_ms + CS_FW_MODBUS_LEASE_MS;
    }
    return CS_OK; /* a write with no lease held: as before leases existed */
}

cs_err_t cs_fw_modbus_submit(void *ctx, const cs_proto_msg_t *m, uint16_t seq)
{
    cs_fw_modbus_t *fm = ctx;
    return cs_fw_motion_queue(fm->mo, m, seq);
}

void cs_fw_modbus_command(void *ctx, uint16_t cmd)
{
    cs_fw_modbus_t *fm = ctx;
    switch (cmd) {
    case CS_MODBUS_CMD_HOLD:
    case CS_MODBUS_CMD_RESUME:
        cs_fw_motion_hold(fm->mo, cmd == CS_MODBUS_CMD_HOLD);
        break;
    case CS_MODBUS_CMD_ABORT:
        cs_fw_motion_abort(fm->mo);
        break;
    case CS_MODBUS_CMD_RESET:
        cs_fw_motion_abort(fm->mo);
        fm->error = 0;
        fm->error_seq = 0;
        break;
    default: /* the map checked the command already */
        break;
    }
}

void cs_fw_modbus_status(void *ctx, cs_modbus_status_t *st)
{
    cs_fw_modbus_t *fm = ctx;
    const cs_fw_motion_t *mo = fm->mo;
    cs_proto_status_t ps;
    cs_fw_motion_status(mo, &ps);
    st->caps = CS_FW_CURVES ? CS_PROTO_CAP_ALL : CS_PROTO_CAP_SEGMENTS;
    st->axes = mo->m->n_axes;
    st->queue_size = mo->cfg.queue_size;
    st->tick_hz = mo->m->tick_hz;
    st->boot_id = fm->boot;
    /* an execution error stops the job: FAULT until the host resets */
    st->state =
        (uint8_t)(fm->error != 0 && ps.state != CS_PROTO_STATE_RUNNING ? CS_PROTO_STATE_FAULT
                                                                       : ps.state);
    st->free_slots = cs_fw_motion_free(mo);
    st->last_exec = ps.last_seq;
    st->error = fm->error;
    st->error_seq = fm->error_seq;
    for (unsigned i = 0; i < CS_AXES; i++)
        st->pos[i] = i < CS_PROTO_AXES_MAX ? ps.pos[i] : 0;
    uint32_t left = lease_left(fm);
    st->lease = left != 0;
    st->lease_left_ms = (uint16_t)left;
}

void cs_fw_modbus_collect(cs_fw_modbus_t *fm)
{
    cs_proto_error_t e;
    while (cs_fw_motion_pop_error(fm->mo, &e)) {
        if (fm->error == 0) { /* the first one stays until RESET */
            fm->error = e.code;
            fm->error_seq = e.seq;
            cs_fw_motion_abort(fm->mo);
        }
    }
}

void cs_fw_modbus_poll(cs_fw_modbus_t *fm)
{
    cs_fw_motion_poll(fm->mo);
    cs_fw_modbus_collect(fm);
}
