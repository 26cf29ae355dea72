# The portable firmware application (firmware/app): every firmware target links FW_APP_SRC with
# the core and its port. FW_APP_MAIN is a plain main for ports that need nothing else (a port may
# have its own). FW_APP_INC: include paths for app, core and the port seam.
FW_APP_SRC  := firmware/app/cs_fw_app.c firmware/app/cs_fw_motion.c firmware/app/cs_fw_modbus.c \
               firmware/app/cs_fw_ctl.c
FW_APP_MAIN := firmware/app/main.c
FW_APP_INC  := -Ifirmware/app -Ifirmware/core -Ifirmware/ports
# Flags every firmware object is compiled with (the core's rules): the target adds -mcpu/-mmcu.
FW_CFLAGS   := -std=c99 -ffreestanding -Wall -Wextra -Werror -Wconversion -Os \
               -ffunction-sections -fdata-sections $(FW_APP_INC)
