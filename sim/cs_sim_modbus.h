/* cs_sim_modbus: the simulator as a Modbus device (docs/modbus.md): Modbus TCP served with
 * libmodbus, Modbus RTU over a pseudo-terminal served by the core's own RTU server. Host only. */
#ifndef CS_SIM_MODBUS_H
#define CS_SIM_MODBUS_H

/* The `curvestep-sim --modbus-tcp ADDR:PORT | --modbus-rtu ...` command line. */
int cs_sim_modbus_main(int argc, char **argv);

#endif
