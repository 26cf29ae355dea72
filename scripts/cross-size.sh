#!/usr/bin/env bash
# Cross-compile the freestanding core for each firmware target and print its size.
# Usage: cross-size.sh OUTDIR core-sources...   (fails if a compiler is missing or a file fails)
set -eu
. "$(dirname "$0")/args.sh"
cs_args "usage: scripts/cross-size.sh OUTDIR CORE-SOURCE...   (make cross)\nCompiles the core for each firmware target and prints its code size." -1 "$@"
out=$1; shift
common="-std=c99 -ffreestanding -Wall -Wextra -Werror -Wconversion -Os -ffunction-sections -fdata-sections -Ifirmware/core"
declare -A cc=( [cortex-m0plus]=arm-none-eabi-gcc [cortex-m3]=arm-none-eabi-gcc [avr]=avr-gcc )
declare -A fl=( [cortex-m0plus]="-mcpu=cortex-m0plus -mthumb" [cortex-m3]="-mcpu=cortex-m3 -mthumb" [avr]="-mmcu=atmega328p" )
declare -A sz=( [cortex-m0plus]=arm-none-eabi-size [cortex-m3]=arm-none-eabi-size [avr]=avr-size )
printf 'cross: core code size (text+data bytes, -Os, every module)\n'
for t in cortex-m0plus cortex-m3 avr; do
    mkdir -p "$out/$t"
    if ! command -v "${cc[$t]}" >/dev/null; then echo "cross: ${cc[$t]} missing (run scripts/deps.sh)"; exit 1; fi
    for f in "$@"; do
        "${cc[$t]}" $common ${fl[$t]} -c "$f" -o "$out/$t/$(basename "$f" .c).o"
    done
    total=$("${sz[$t]}" -t "$out/$t"/*.o | tail -n1 | awk '{print $1 + $2}')
    printf '  %-14s %7d bytes\n' "$t" "$total"
    "${sz[$t]}" "$out/$t"/*.o | awk 'NR>1 {printf "    %-24s %6d\n", $6, $1+$2}' | sed "s#$out/$t/##" > "$out/$t/sizes.txt"
done
