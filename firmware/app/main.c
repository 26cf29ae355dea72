/* The firmware's main for a port that needs nothing else: port_init, the default machine at the
 * port's tick rate, the application, and its loop. A port with more to do (sleep between passes,
 * a report over a debugger) has its own main instead (firmware/ports/cortex-m3/main_m3.c). */
#include "cs_fw_app.h"
#include "port.h"

static cs_machine_t machine;
static cs_fw_app_t app;

int main(void)
{
    port_init();
    cs_fw_machine_default(&machine, port_tick_hz());
    /* the boot id should differ per boot: the counter after port_init is the best portable
     * source (a port with a better one, e.g. a hardware RNG, writes its own main) */
    uint32_t boot = port_ticks_now() * 2654435761u ^ 0xC5E57E90u;
    if (cs_fw_app_init(&app, &machine, boot) != CS_OK)
        port_fault(CS_ERR_ARG);
    for (;;)
        cs_fw_app_poll(&app);
}
