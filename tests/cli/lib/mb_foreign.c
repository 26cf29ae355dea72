/* Test helper (not a test; compiled by tests/cli/test_modbus_foreign.sh): a second Modbus TCP
 * client, built on libmodbus, that misbehaves beside a streaming host.
 *   mb_foreign HOST PORT write   writes one zero-step segment (1000 ticks) to the mailbox with
 *                                the device's current next sequence, retrying (the host may take
 *                                that sequence first) until the device accepts one; exit 0 then.
The simulator serves one connection at a time (a new one replaces the old): connecting takes
 * the device from the host for a moment, which reconnects (docs/modbus.md).
 * Register map: docs/modbus.md (input registers 10 LAST_EXEC, 11 NEXT_SEQ; mailbox at 0x0100:
 * type 0x20, ticks high/low, 4 x steps high/low, sequence). Every loop has a deadline (60 s). */
#include <errno.h>
#include <modbus/modbus.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

int main(int argc, char **argv)
{
    if (argc < 4)
        return 2;
    modbus_t *mb = modbus_new_tcp(argv[1], atoi(argv[2]));
    if (mb == NULL || modbus_set_slave(mb, 1) != 0 || modbus_connect(mb) != 0) {
        fprintf(stderr, "mb_foreign: connect: %s\n", modbus_strerror(errno));
        return 3;
    }
    time_t end = time(NULL) + 60;
    int rc = 1;
    while (time(NULL) < end && rc != 0) {
        uint16_t ir[12];
        if (modbus_read_input_registers(mb, 0, 12, ir) != 12) {
            modbus_close(mb); /* the host took the connection back: take it again */
            usleep(1000);
            if (modbus_connect(mb) != 0)
                usleep(10000);
            continue;
        }
        uint16_t regs[12] = {0x20, 0, 1000, 0, 0, 0, 0, 0, 0, 0, 0, ir[11]};
        if (modbus_write_registers(mb, 0x0100, 12, regs) == 12) {
            printf("foreign segment written with sequence %u\n", (unsigned)ir[11]);
            rc = 0;
        }
    }
    modbus_close(mb);
    modbus_free(mb);
    return rc;
}
