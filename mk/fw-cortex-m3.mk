# Cortex-M3 firmware: TI Stellaris LM3S6965 (qemu -M lm3s6965evb). The core, the application
# (mk/fw-app.mk) and firmware/ports/cortex-m3 linked with --gc-sections and no C library into
# build/fw/cortex-m3/curvestep.{elf,hex,bin}; sizes printed; scripts/fw-check.sh fails the build
# on soft-float or heap symbols. The template port is compiled (not linked) for the same CPU.
M3_CC      := arm-none-eabi-gcc
M3_OBJCOPY := arm-none-eabi-objcopy
M3_SIZE    := arm-none-eabi-size
M3_NM      := arm-none-eabi-nm
M3_DIR     := $(BUILD)/fw/cortex-m3
M3_CPU     := -mcpu=cortex-m3 -mthumb
M3_PORT    := firmware/ports/cortex-m3
M3_CFLAGS  := $(FW_CFLAGS) $(M3_CPU) -I$(M3_PORT) -g
M3_LDFLAGS := $(M3_CPU) -nostdlib -nostartfiles -Wl,--gc-sections -T $(M3_PORT)/lm3s6965.ld \
              -Wl,-Map=$(M3_DIR)/curvestep.map
M3_SRC     := $(CORE_SRC) $(FW_APP_SRC) $(filter-out $(M3_PORT)/fdbench.c,$(wildcard $(M3_PORT)/*.c))
M3_OBJ     := $(M3_SRC:%.c=$(M3_DIR)/obj/%.o)
M3_HDR     := $(wildcard firmware/core/*.h firmware/app/*.h firmware/ports/*.h $(M3_PORT)/*.h)

$(M3_DIR)/obj/%.o: %.c $(M3_HDR)
	@mkdir -p $(@D)
	$(M3_CC) $(M3_CFLAGS) -c $< -o $@

$(M3_DIR)/curvestep.elf: $(M3_OBJ) $(M3_PORT)/lm3s6965.ld scripts/fw-check.sh
	$(M3_CC) $(M3_LDFLAGS) $(M3_OBJ) -lgcc -o $@
	@bash scripts/fw-check.sh $(M3_NM) $@ || { rm -f $@; exit 1; }
	@$(M3_SIZE) -A $@ | awk -v img=$@ '$$1==".isr_vector"||$$1==".text"||$$1==".ARM.exidx"{f+=$$2} \
	  $$1==".data"{f+=$$2; r+=$$2} $$1==".bss"||$$1==".noinit"{r+=$$2} \
	  END {printf "fw: %s: flash %d of 262144 bytes, RAM %d of 65536 bytes (.data+.bss+.noinit; the stack above)\n", img, f, r}'

$(M3_DIR)/%.hex: $(M3_DIR)/%.elf
	$(M3_OBJCOPY) -O ihex $< $@

$(M3_DIR)/%.bin: $(M3_DIR)/%.elf
	$(M3_OBJCOPY) -O binary $< $@

# The template port, compile-only: it must stay buildable as the starting point of a new port.
$(BUILD)/fw/template/port_template.o: firmware/ports/template/port_template.c $(M3_HDR)
	@mkdir -p $(@D)
	$(M3_CC) $(FW_CFLAGS) $(M3_CPU) -c $< -o $@

FW_IMAGES += $(M3_DIR)/curvestep.elf $(M3_DIR)/curvestep.hex $(M3_DIR)/curvestep.bin \
             $(BUILD)/fw/template/port_template.o

# The benchmark image (not firmware): curve code timed under qemu -icount (scripts/bench.sh).
M3_BENCH_SRC := $(CORE_SRC) $(M3_PORT)/fdbench.c $(M3_PORT)/startup_m3.c $(M3_PORT)/semihost.c
M3_BENCH_OBJ := $(M3_BENCH_SRC:%.c=$(M3_DIR)/obj/%.o)
$(M3_DIR)/fdbench.elf: $(M3_BENCH_OBJ) $(M3_PORT)/lm3s6965.ld scripts/fw-check.sh
	$(M3_CC) $(M3_CPU) -nostdlib -nostartfiles -Wl,--gc-sections -T $(M3_PORT)/lm3s6965.ld \
	  $(M3_BENCH_OBJ) -lgcc -o $@
	@bash scripts/fw-check.sh $(M3_NM) $@ || { rm -f $@; exit 1; }

FW_IMAGES += $(M3_DIR)/fdbench.elf

# The plain main of firmware/app (for ports that need nothing else), compile-only like the template.
$(BUILD)/fw/template/main.o: $(FW_APP_MAIN) $(M3_HDR)
	@mkdir -p $(@D)
	$(M3_CC) $(FW_CFLAGS) $(M3_CPU) -c $< -o $@

FW_IMAGES += $(BUILD)/fw/template/main.o
