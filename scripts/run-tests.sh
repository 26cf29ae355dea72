#!/usr/bin/env bash
# Run every test binary given, then tests/cli/*.sh (command-line tests, which use $CS_BUILD), and
# print one closing line "<variant>: N passed, N failed" summed from cmocka's own counts.
set -u
variant=$1; shift
pass=0; fail=0; failed_bins=()
for bin in "$@"; do
    out=$("$bin" 2>&1); rc=$?
    p=$(printf '%s\n' "$out" | sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' | tail -n1)
    f=$(printf '%s\n' "$out" | sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' | tail -n1)
    p=${p:-0}; f=${f:-0}
    if [ $rc -ne 0 ] && [ "$f" = 0 ]; then f=1; fi   # crashed or sanitizer abort: count it
    pass=$((pass + p)); fail=$((fail + f))
    if [ $rc -ne 0 ]; then failed_bins+=("$bin"); printf '%s\n' "$out" | tail -n 40; fi
    printf '  %-40s %3d passed, %d failed\n' "$(basename "$bin")" "$p" "$f"
done
for t in tests/cli/*.sh; do
    [ -f "$t" ] || continue
    out=$(CS_BUILD=${CS_BUILD:-build} bash "$t" 2>&1); rc=$?
    p=$(printf '%s\n' "$out" | sed -n 's/^cli: \([0-9]*\) passed, \([0-9]*\) failed$/\1/p' | tail -n1)
    f=$(printf '%s\n' "$out" | sed -n 's/^cli: \([0-9]*\) passed, \([0-9]*\) failed$/\2/p' | tail -n1)
    p=${p:-0}; f=${f:-0}
    if [ $rc -ne 0 ] && [ "$f" = 0 ]; then f=1; fi
    pass=$((pass + p)); fail=$((fail + f))
    if [ $rc -ne 0 ]; then failed_bins+=("$t"); printf '%s\n' "$out" | tail -n 40; fi
    printf '  %-40s %3d passed, %d failed\n' "$(basename "$t")" "$p" "$f"
done
echo "$variant: $pass passed, $fail failed"
[ "$fail" -eq 0 ] && [ ${#failed_bins[@]} -eq 0 ]
