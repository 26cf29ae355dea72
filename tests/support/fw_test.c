/* fw_test: see fw_test.h. */
#include "fw_test.h"

#include "cs_fw_app.h"
#include "port_posix.h"

int fw_test_motion(cs_machine_t *m, cs_fw_motion_t *mo, uint16_t queue)
{
    cs_fw_machine_default(m, 100000);
    port_posix_reset(m->tick_hz, 0);
    cs_fw_motion_cfg_t c;
    cs_fw_motion_cfg_default(&c, m);
    c.queue_size = queue;
    return cs_fw_motion_init(mo, m, &c) == CS_OK ? 0 : -1;
}

uint64_t fw_test_hash(uint64_t h, const cs_segment_t *s)
{
    cs_exlog_segs_t l = {0, (uint32_t)h};
    cs_exlog_segment(&l, s);
    return l.hash;
}
