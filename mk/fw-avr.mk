# ATmega328p firmware (16 MHz, an Arduino Uno with a Grbl-style shield): the core, the application
# (mk/fw-app.mk) and firmware/ports/avr linked with --gc-sections into
# build/fw/avr/curvestep.{elf,hex,bin}; flash and RAM printed (and checked against the chip's
# 32 KB / 2 KB with a stack reserve); scripts/fw-check.sh fails the build on soft-float or heap
# symbols. Also the simavr harness (tests/fw/avr_harness.c, a host program) and the benchmark
# image (tests/fw/avr_bench_fw.c), for tests/fw/test_fw_avr.sh and tests/fw/bench_avr.sh.
AVR_CC      := avr-gcc
AVR_OBJCOPY := avr-objcopy
AVR_SIZE    := avr-size
AVR_NM      := avr-nm
AVR_DIR     := $(BUILD)/fw/avr
AVR_PORT    := firmware/ports/avr
AVR_MCU     := -mmcu=atmega328p -DF_CPU=16000000UL
# The 2 KB build: segments only (the host plans; no tracer or planner on board) with machine
# control (CS_FW_CTL=1: limits, e-stop, probe, homing and jogs at constant speed, spindle PWM),
# a 7-slot motion queue, a 2-frame link window with 40-byte payloads (STATUS with 3 axes and its
# tick is the longest message the device sends or needs), a 4-segment executor ring (20 ms of 5 ms segments;
# 34 B a slot), an 8-entry sequence map (ring + 3), 2 waiting EVENTs; x/y at 100 mm/s (8000
# steps/s at 80 steps/mm), what the step interrupt sustains with room for the link
# (docs/firmware-avr.md); 2 waiting ERRORs (a 2-frame window) and 16-byte UART reads a pass (on
# the stack). Static RAM 1456 B + 496..511 B of stack measured in simavr (docs/firmware-avr.md,
# "The 2 KB build"). machine.ini in $(AVR_PORT) says the same for the host.
AVR_DEFS    := -DCS_FW_CURVES=0 -DCS_FW_CTL=1 -DCS_FW_QUEUE=7 -DCS_LINK_WINDOW=2 -DCS_FRAME_PAYLOAD_MAX=40 \
               -DCS_STEPPER_RING=4 -DCS_FW_XY_RATE=100 -DCS_FW_XY_ACCEL=2000 \
               -DCS_FW_ERRQ=2 -DCS_FW_RX_CHUNK=16 -DCS_FW_EVQ=2 -DCS_FW_SEQMAP=8
# -flto: the executor's call (cs_stepper_tick, in the core) is inlined into the step interrupt
# at link time, so the interrupt saves only the registers it uses and passes its answer in
# registers (about 40 cycles of the ~440 a call takes; docs/firmware-avr.md).
AVR_CFLAGS  := $(FW_CFLAGS) $(AVR_MCU) $(AVR_DEFS) -I$(AVR_PORT) -g -flto
AVR_LDFLAGS := $(AVR_MCU) -Os -flto -Wl,--gc-sections
# RAM the image may use statically: 2048 minus a stack reserve (the deepest call chain measured
# in simavr is printed by the harness as "stack:"; docs/firmware-avr.md).
AVR_RAM_MAX := 1536
AVR_PORT_SRC := $(AVR_PORT)/port_avr.c
AVR_SRC     := $(CORE_SRC) $(FW_APP_SRC) $(AVR_PORT_SRC) $(AVR_PORT)/main_avr.c
AVR_OBJ     := $(AVR_SRC:%.c=$(AVR_DIR)/obj/%.o)
AVR_BENCH_OBJ := $(AVR_DIR)/obj/tests/fw/avr_bench_fw.o $(AVR_PORT_SRC:%.c=$(AVR_DIR)/obj/%.o) \
                 $(AVR_DIR)/obj/firmware/core/cs_stepper.o
AVR_HDR     := $(wildcard firmware/core/*.h firmware/app/*.h firmware/ports/*.h $(AVR_PORT)/*.h)
AVR_CHECK   := $(wildcard scripts/fw-check.sh)

$(AVR_DIR)/obj/%.o: %.c $(AVR_HDR)
	@mkdir -p $(@D)
	$(AVR_CC) $(AVR_CFLAGS) -c $< -o $@

# Flash = .text + .data (the initial values live in flash); RAM = .data + .bss, the rest of the
# 2048 bytes is the stack's.
define AVR_LINK
	$(AVR_CC) $(AVR_LDFLAGS) $(1) -o $@
	$(if $(AVR_CHECK),@bash $(AVR_CHECK) $(AVR_NM) $@ || { rm -f $@; exit 1; })
	@$(AVR_SIZE) -A $@ | awk -v img=$@ -v max=$(AVR_RAM_MAX) \
	  '$$1==".text"{f+=$$2} $$1==".data"{f+=$$2; r+=$$2} $$1==".bss"||$$1==".noinit"{r+=$$2} \
	  END {printf "fw: %s: flash %d of 32768 bytes, RAM %d of 2048 bytes (.data+.bss+.noinit; %d left for the stack)\n", \
	  img, f, r, 2048 - r; if (f > 32768 || r > max) {print "fw: " img ": too big for the ATmega328p (RAM limit " max ")"; exit 1}}' \
	  || { rm -f $@; exit 1; }
endef

$(AVR_DIR)/curvestep.elf: $(AVR_OBJ) $(AVR_CHECK)
	$(call AVR_LINK,$(AVR_OBJ))

$(AVR_DIR)/bench.elf: $(AVR_BENCH_OBJ) $(AVR_CHECK)
	$(call AVR_LINK,$(AVR_BENCH_OBJ))

$(AVR_DIR)/%.hex: $(AVR_DIR)/%.elf
	$(AVR_OBJCOPY) -O ihex -R .eeprom $< $@

$(AVR_DIR)/%.bin: $(AVR_DIR)/%.elf
	$(AVR_OBJCOPY) -O binary -R .eeprom $< $@

# The harness: a host program against libsimavr (Debian libsimavr-dev, libelf-dev).
SIMAVR_CFLAGS := $(shell pkg-config --cflags simavr 2>/dev/null)
SIMAVR_LIBS   := $(shell pkg-config --libs simavr 2>/dev/null) -lelf -lutil
$(AVR_DIR)/avr_harness: tests/fw/avr_harness.c
	@mkdir -p $(@D)
	$(CC) -std=c99 -D_DEFAULT_SOURCE -D_POSIX_C_SOURCE=200809L $(WARN) -O2 -g $(SIMAVR_CFLAGS) \
	  $< -o $@ $(SIMAVR_LIBS)

FW_IMAGES += $(AVR_DIR)/curvestep.elf $(AVR_DIR)/curvestep.hex $(AVR_DIR)/curvestep.bin \
             $(AVR_DIR)/bench.elf $(AVR_DIR)/avr_harness
