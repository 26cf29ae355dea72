# Shared set-up of the Cortex-M3 image tests (sourced, never run: run-tests.sh runs only
# tests/fw/*.sh). Usage, after `set -u`:
#     . "$(dirname "${BASH_SOURCE[0]}")/lib/m3.sh" [IMAGE-ARG...]
# Sets B, FW, ELF and QEMU: qemu-system-arm on the LM3S6965 board with -icount shift=4 (one
# instruction every 16 ns, about the part's 50 MHz, whatever the host's speed), the UART on a
# pty, and the image's semihosting arguments `curvestep IMAGE-ARG...` (exit-idle=MS, simulated
# switches ...: firmware/ports/cortex-m3/main_m3.c). Sources the CLI harness
# (tests/cli/lib/common.sh), ends the script as one failure when qemu is missing, and counts
# one check that the image is built.
B=${CS_BUILD:-build}
FW=${FW_M3_DIR:-${B%/asan}/fw/cortex-m3} # the images are built once, outside the variants
ELF=$FW/curvestep.elf
cs_m3_args=curvestep
for cs_m3_a in "$@"; do cs_m3_args+=",arg=$cs_m3_a"; done
QEMU=(qemu-system-arm -M lm3s6965evb -kernel "$ELF" -display none -monitor none -serial pty
    -icount shift=4 -semihosting-config "enable=on,target=native,arg=$cs_m3_args")
. "$(dirname "${BASH_SOURCE[0]}")/../../cli/lib/common.sh"

if ! command -v qemu-system-arm >/dev/null; then
    echo "FAIL: qemu-system-arm missing (scripts/deps.sh installs it)"
    echo "cli: 0 passed, 1 failed"
    exit 1
fi
expect "image built" [ -f "$ELF" ]
