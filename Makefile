# curvestep build. Every module is picked up by wildcard: add a .c file in the right folder and
# it is built; add tests/unit/test_<module>.c and it becomes a test binary.
#   make            core library, host program, simulator, freestanding + cross checks of the core
#   make host       host program and simulator, built and tested with the host's packages only
#   make test       every unit test, once plain and once under ASan+UBSan
#   make demo       the main job (see README.md)
#   make bench      benchmarks -> docs/benchmarks.md and build/bench/*.csv
#   make firmware   cross-compiled core for each target, sizes printed
#   make install    PREFIX (/usr/local) and DESTDIR; make uninstall removes the same files
#   make deb        the Debian package, build/curvestep_*.deb (docs/install.md)
#   make format     clang-format -i on every source
#   make clean
.DEFAULT_GOAL := all
SHELL := /bin/bash

# --- stage 1: install what the goals need, then build them in a fresh parse -----------------
# This file reads pkg-config when make parses it (PKG_CFLAGS here, SIMAVR_CFLAGS in mk/fw-avr.mk,
# AGG_CFLAGS below), so on a fresh machine the packages must be there before that parse, not
# merely before the first recipe. Stage 1 maps the goals to scripts/deps.sh groups, runs it, then
# runs make again with CS_DEPS_DONE=1: the rest of this file (stage 2), parsed with the packages
# installed. tests/cli/test_firstrun.sh fails if a goal reads pkg-config before deps has run.
BUILD ?= build
ifndef CS_DEPS_DONE
CS_GOALS := $(or $(MAKECMDGOALS),$(.DEFAULT_GOAL))
cs_group = $(strip \
  $(if $(filter clean format uninstall,$(1)),,\
  $(if $(filter deb deb-check,$(1)),host deb,\
  $(if $(filter fuzz,$(1)),host fuzz,\
  $(if $(filter bench test,$(1)),host firmware bench,\
  $(if $(filter all deps demo firmware cross fw-test $(BUILD)/fw/% $(BUILD)/cross/% build/fw/%,$(1)),\
    host firmware,host))))))
CS_GROUPS := $(sort $(foreach g,$(CS_GOALS),$(call cs_group,$(g))))
.PHONY: $(CS_GOALS) cs-stage1
$(CS_GOALS): cs-stage1 ; @:
cs-stage1:
	$(if $(CS_GROUPS),@sh scripts/deps.sh $(CS_GROUPS))
	@$(MAKE) --no-print-directory CS_DEPS_DONE=1 CS_DEPS_GROUPS='$(CS_GROUPS)' $(MAKECMDGOALS)
else
# --- stage 2: the build ---------------------------------------------------------------------
BUILD    ?= build
VARIANT  ?= plain
CC       ?= cc
ifeq ($(VARIANT),asan)
OUT      := $(BUILD)/asan
SANFLAGS := -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
OPT      := -O1 -g
else
OUT      := $(BUILD)
SANFLAGS :=
OPT      := -O2 -g
endif

CORE_SRC  := $(sort $(wildcard firmware/core/*.c))
HOST_SRC  := $(sort $(filter-out host/main.c,$(wildcard host/*.c)))
SIM_SRC   := $(sort $(filter-out sim/main.c,$(wildcard sim/*.c)))
SUP_SRC   := $(sort $(wildcard tests/support/*.c))
UNIT_SRC  := $(sort $(wildcard tests/unit/test_*.c))
BENCH_SRC := $(sort $(wildcard tests/bench/bench_*.c))
PORT_POSIX_SRC := $(sort $(wildcard firmware/ports/posix/*.c))
# The device application (firmware/app) without its bare-metal main: linked into the host
# library so that the simulator and the unit tests run the firmware's own code on the POSIX port.
FW_HOST_SRC := $(sort $(filter-out firmware/app/main.c,$(wildcard firmware/app/*.c)))

PKGS      := cairo expat libmodbus libgpiod
PKG_CFLAGS := $(shell pkg-config --cflags $(PKGS) 2>/dev/null)
PKG_LIBS   := $(shell pkg-config --libs $(PKGS) 2>/dev/null) -linih -lpthread -lm

# Layers the compiler enforces (docs/architecture.md): each layer sees only the include paths
# of the layers below it, so a header from above is "No such file" at compile time, and the
# host program links without the simulator's library, so a call from above is an undefined
# symbol. tests/cli/test_layers.sh proves both.
CORE_INC  := -Ifirmware/core
APP_INC   := $(CORE_INC) -Ifirmware/ports -Ifirmware/app
PORT_INC  := $(APP_INC) -Ifirmware/ports/posix
HOST_INC  := $(CORE_INC) -Ihost
SIM_INC   := $(PORT_INC) -Ihost -Isim
# tests, benchmarks and fuzz targets may look at every layer
INCLUDES  := $(SIM_INC) -Itests/support
# The host's build of the application offers the simulator's largest queue (--queue 1..256).
FW_HOST_DEFS := -DCS_FW_QUEUE=256 -DCS_FW_SIM_HOOKS=1
WARN      := -Wall -Wextra -Werror
CORE_BASE   := -std=c99 $(WARN) -Wconversion $(OPT) $(SANFLAGS)
CORE_CFLAGS := $(CORE_BASE) $(CORE_INC)
APP_CFLAGS  := $(CORE_BASE) $(APP_INC) $(FW_HOST_DEFS)
POSIX_BASE  := -std=c99 -D_DEFAULT_SOURCE -D_POSIX_C_SOURCE=200809L $(WARN) $(OPT) $(SANFLAGS) \
               $(FW_HOST_DEFS) $(PKG_CFLAGS)
HOST_ONLY_CFLAGS := $(POSIX_BASE) $(HOST_INC)
SIM_CFLAGS  := $(POSIX_BASE) $(SIM_INC)
HOST_CFLAGS := $(POSIX_BASE) $(INCLUDES)
LDFLAGS_ALL := $(SANFLAGS)

CORE_OBJ := $(CORE_SRC:%.c=$(OUT)/obj/%.o)
HOST_OBJ := $(HOST_SRC:%.c=$(OUT)/obj/%.o)
SIM_OBJ  := $(SIM_SRC:%.c=$(OUT)/obj/%.o)
SUP_OBJ  := $(SUP_SRC:%.c=$(OUT)/obj/%.o)
PORT_POSIX_OBJ := $(PORT_POSIX_SRC:%.c=$(OUT)/obj/%.o)
FW_HOST_OBJ := $(FW_HOST_SRC:%.c=$(OUT)/obj/%.o)
UNIT_BIN := $(UNIT_SRC:tests/unit/%.c=$(OUT)/tests/%)
BENCH_BIN := $(BENCH_SRC:tests/bench/%.c=$(BUILD)/bench/%)

CORE_LIB := $(OUT)/libcscore.a
HOST_LIB := $(OUT)/libcshost.a
# the simulator: its own code, the device application and the POSIX port it runs on
SIM_LIB  := $(OUT)/libcssim.a
TEST_LIBS := $(SIM_LIB) $(HOST_LIB) $(CORE_LIB)

.SECONDARY:

.PHONY: fw-test all deps host test test-plain test-asan unit-run demo bench firmware core-check cross clean format fuzz

all: deps $(OUT)/curvestep $(if $(wildcard sim/main.c),$(OUT)/curvestep-sim) core-check cross \
     firmware

# Stage 1 has installed the packages; `make CS_DEPS_DONE=1 deps` runs deps.sh here, after the
# parse (how the Makefile worked before stage 1; tests/cli/test_firstrun.sh shows it failing).
deps:
	@sh scripts/deps.sh $(if $(CS_DEPS_GROUPS),$(CS_DEPS_GROUPS),host firmware)

# --- objects --------------------------------------------------------------------------------
$(OUT)/obj/firmware/core/%.o: firmware/core/%.c $(wildcard firmware/core/*.h)
	@mkdir -p $(@D)
	$(CC) $(CORE_CFLAGS) -c $< -o $@

# the application under the core's rules (-Wconversion), with the host's sizes
$(OUT)/obj/firmware/app/%.o: firmware/app/%.c $(wildcard firmware/core/*.h firmware/app/*.h firmware/ports/*.h)
	@mkdir -p $(@D)
	$(CC) $(APP_CFLAGS) -c $< -o $@

$(OUT)/obj/host/%.o: host/%.c $(wildcard firmware/core/*.h host/*.h)
	@mkdir -p $(@D)
	$(CC) $(HOST_ONLY_CFLAGS) -c $< -o $@

$(OUT)/obj/sim/%.o: sim/%.c $(wildcard firmware/core/*.h firmware/app/*.h firmware/ports/*.h firmware/ports/posix/*.h host/*.h sim/*.h)
	@mkdir -p $(@D)
	$(CC) $(SIM_CFLAGS) -c $< -o $@

$(OUT)/obj/firmware/ports/posix/%.o: firmware/ports/posix/%.c $(wildcard firmware/core/*.h firmware/app/*.h firmware/ports/*.h firmware/ports/posix/*.h)
	@mkdir -p $(@D)
	$(CC) $(POSIX_BASE) $(PORT_INC) -c $< -o $@

$(OUT)/obj/%.o: %.c $(wildcard firmware/core/*.h firmware/app/*.h host/*.h sim/*.h tests/support/*.h firmware/ports/*.h firmware/ports/posix/*.h)
	@mkdir -p $(@D)
	$(CC) $(HOST_CFLAGS) -c $< -o $@

$(CORE_LIB): $(CORE_OBJ)
	@mkdir -p $(@D)
	rm -f $@ && ar rcs $@ $^

$(HOST_LIB): $(HOST_OBJ)
	@mkdir -p $(@D)
	rm -f $@ && ar rcs $@ $^ $(if $^,,/dev/null)

$(SIM_LIB): $(SIM_OBJ) $(PORT_POSIX_OBJ) $(FW_HOST_OBJ)
	@mkdir -p $(@D)
	rm -f $@ && ar rcs $@ $^ $(if $^,,/dev/null)

$(OUT)/curvestep: $(OUT)/obj/host/main.o $(HOST_LIB) $(CORE_LIB)
	$(CC) $(LDFLAGS_ALL) $^ -o $@ $(PKG_LIBS)

$(OUT)/curvestep-sim: $(OUT)/obj/sim/main.o $(TEST_LIBS)
	$(CC) $(LDFLAGS_ALL) $^ -o $@ $(PKG_LIBS)

$(OUT)/tests/%: $(OUT)/obj/tests/unit/%.o $(SUP_OBJ) $(TEST_LIBS)
	@mkdir -p $(@D)
	$(CC) $(LDFLAGS_ALL) $< $(SUP_OBJ) $(TEST_LIBS) -o $@ -lcmocka $(PKG_LIBS)

# `make -s CS_DEPS_DONE=1 print-VAR`: the value of a variable (tests/cli/test_layers.sh reads
# the layers' flags this way instead of copying them).
print-%:
	@echo '$($*)'

# --- tests ----------------------------------------------------------------------------------
# Each variant builds everything (host program and simulator too: tests may run them) and runs
# every unit test binary; scripts/run-tests.sh prints the cmocka totals as "N passed, N failed".
# The builds run CS_JOBS compilers at once and the tests CS_TEST_JOBS at once (both default to
# the number of cores; scripts/run-tests.sh).
CS_JOBS ?= $(shell nproc 2>/dev/null || echo 2)
test: deps
	$(MAKE) --no-print-directory -j$(CS_JOBS) VARIANT=plain test-variant
	$(MAKE) --no-print-directory -j$(CS_JOBS) VARIANT=asan test-variant
	@$(MAKE) --no-print-directory -j$(CS_JOBS) core-check cross
	$(MAKE) --no-print-directory -j$(CS_JOBS) fw-test

# Host only: the host program and simulator, built and tested (unit and CLI tests, plain), and
# the freestanding check of the core, with no cross toolchain, emulator or clang.
host: core-check
	$(MAKE) --no-print-directory VARIANT=plain test-variant

test-variant: $(OUT)/curvestep $(if $(wildcard sim/main.c),$(OUT)/curvestep-sim) $(UNIT_BIN)
	@CS_BUILD=$(OUT) bash scripts/run-tests.sh $(VARIANT) $(UNIT_BIN)

# --- the core's rules, checked by the build ------------------------------------------------
FREESTANDING := -std=c99 -ffreestanding -nostdlib -mgeneral-regs-only $(WARN) -Wconversion -Ifirmware/core
core-check:
	@mkdir -p $(BUILD)/freestanding
	@for f in $(CORE_SRC); do \
	  gcc $(FREESTANDING) -O2 -c $$f -o $(BUILD)/freestanding/$$(basename $$f .c).o || exit 1; done
	@und=$$(comm -23 <(nm -u $(BUILD)/freestanding/*.o | awk 'NF==2 {print $$2}' | sort -u) \
	  <(nm --defined-only $(BUILD)/freestanding/*.o | awk 'NF==3 {print $$3}' | sort -u) \
	  | grep -vE '^(memcpy|memset|memmove)$$' | tr '\n' ' '); \
	if [ -n "$$und" ]; then echo "core-check: firmware/core calls outside itself: $$und"; exit 1; fi; \
	echo "core-check: firmware/core builds freestanding (-mgeneral-regs-only), no outside symbols"
	@if grep -rnE '\b(malloc|calloc|realloc|free)\s*\(' firmware/core; then echo "core-check: heap use in core"; exit 1; fi

# Cross-compile the core for each firmware target and print its code size (text+data, bytes).
CROSS_TARGETS := cortex-m0plus cortex-m3 avr
cross:
	@bash scripts/cross-size.sh $(BUILD)/cross $(CORE_SRC)

# --- firmware images -------------------------------------------------------------------------
# Each target's rules live in mk/fw-<target>.mk (one file a target). Each appends its images
# (ELF, HEX, BIN) to FW_IMAGES; its emulator tests are tests/fw/*.sh, run by `make fw-test`
# (part of `make test`) with the plain host build, printing "cli: N passed, M failed".
# mk/install.mk (not a target): make install, uninstall, deb, deb-check (docs/install.md).
FW_IMAGES :=
-include $(sort $(wildcard mk/*.mk))

firmware: cross $(FW_IMAGES)

fw-test: firmware $(BUILD)/curvestep $(BUILD)/curvestep-sim
	@CLI_DIR=tests/fw CS_BUILD=$(BUILD) bash scripts/run-tests.sh firmware

# --- demo, bench ----------------------------------------------------------------------------
demo: deps all
	@bash scripts/demo.sh

$(BUILD)/bench/%: tests/bench/%.c $(SUP_OBJ) $(TEST_LIBS)
	@mkdir -p $(@D)
	$(CC) $(HOST_CFLAGS) $< $(SUP_OBJ) $(TEST_LIBS) -o $@ $(PKG_LIBS)

# bench_peers also links AGG (C++ headers + static lib, pkg-config libagg) via agg_flat.cpp.
AGG_CFLAGS := $(shell pkg-config --cflags libagg 2>/dev/null)
AGG_LIBS   := $(shell pkg-config --libs libagg 2>/dev/null)
CXX        ?= g++
$(BUILD)/bench/agg_flat.o: tests/bench/agg_flat.cpp tests/bench/agg_flat.h
	@mkdir -p $(@D)
	$(CXX) -O2 -Wall -Wextra $(AGG_CFLAGS) -Itests/bench -c $< -o $@

$(BUILD)/bench/bench_peers: tests/bench/bench_peers.c tests/bench/agg_flat.h \
		$(BUILD)/bench/agg_flat.o $(SUP_OBJ) $(TEST_LIBS)
	@mkdir -p $(@D)
	$(CC) $(HOST_CFLAGS) -Itests/bench -c $< -o $@.o
	$(CXX) $@.o $(BUILD)/bench/agg_flat.o $(SUP_OBJ) $(TEST_LIBS) -o $@ \
		$(PKG_LIBS) $(AGG_LIBS)

bench: deps all $(BENCH_BIN)
	@bash scripts/bench.sh $(BENCH_BIN)

# --- fuzzing: every tests/fuzz/fuzz_*.c under libFuzzer+ASan+UBSan, FUZZ_SECONDS (60) each --
FUZZ_SECONDS ?= 60
fuzz: deps
	@BUILD=$(BUILD) FUZZ_SECONDS=$(FUZZ_SECONDS) bash scripts/fuzz.sh

format:
	clang-format -i $$(find firmware host sim tests -name '*.[ch]')

clean:
	rm -rf $(BUILD)

endif # stage 2
