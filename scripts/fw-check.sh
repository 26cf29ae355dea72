#!/usr/bin/env bash
# Checks a firmware image for what it must never link: software floating point (the core is
# integer-only; a float that slipped in drags in libgcc's __aeabi_f*/__aeabi_d* on ARM or
# __addsf3-style routines on AVR) and the heap (malloc, free, ...). Prints the offending symbols
# and exits 1. Usage: fw-check.sh NM IMAGE.elf   (NM: arm-none-eabi-nm, avr-nm, ...)
set -eu
. "$(dirname "$0")/args.sh"
cs_args "usage: scripts/fw-check.sh NM IMAGE.elf   (NM: arm-none-eabi-nm, avr-nm, ...)\nFails when the image links software floating point or the heap." 2 "$@"
nm=$1
img=$2
syms=$("$nm" "$img" | awk 'NF >= 2 {print $NF}' | sort -u)
float_re='^(__aeabi_[fd][a-z0-9]*|__aeabi_[iul]*[2][fd]|__aeabi_[fd]2[a-z0-9]*|__(add|sub|mul|div|neg|cmp|eq|ne|lt|le|gt|ge|unord)[sdtx]f[23]|__(fix|fixuns|float|floatun|extend|trunc)[a-z]*[sdtx]f[a-z0-9]*|__(pack|unpack)_[fd]|__fp_[a-z0-9_]*|__gesf2|__ltsf2|__(sqrt|sin|cos|pow|exp|log)[f]?)$'
heap_re='^(malloc|free|calloc|realloc|_malloc_r|_free_r|_calloc_r|_realloc_r|__malloc_[a-z_]*|_sbrk|sbrk)$'
bad_float=$(grep -E "$float_re" <<<"$syms" | tr '\n' ' ' || true)
bad_heap=$(grep -E "$heap_re" <<<"$syms" | tr '\n' ' ' || true)
rc=0
if [ -n "$bad_float" ]; then
    echo "fw-check: $img links software floating point: $bad_float" >&2
    rc=1
fi
if [ -n "$bad_heap" ]; then
    echo "fw-check: $img links the heap: $bad_heap" >&2
    rc=1
fi
exit $rc
