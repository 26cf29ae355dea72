#!/usr/bin/env bash
# Run every test binary given, then tests/cli/test_*.sh (command-line tests, which use $CS_BUILD; or
# $CLI_DIR/test_*.sh), and
# print one closing line "<variant>: N passed, N failed" summed from cmocka's own counts.
set -u
. "$(dirname "$0")/args.sh"
cs_args "usage: scripts/run-tests.sh VARIANT [TEST-BINARY...]\nRuns each binary, then tests/cli/test_*.sh (or CLI_DIR/test_*.sh) with\nCS_BUILD; prints \"VARIANT: N passed, M failed\"." -1 "$@"
variant=$1; shift
# A hung test must fail with its name, never hang the run (CI gives the whole `make test` 90
# minutes): each binary gets UNIT_TIMEOUT seconds, each CLI script CLI_TIMEOUT (ASan runs ~4x
# slower than plain; the slowest binary, test_stream, takes ~65 s under ASan here).
UNIT_TIMEOUT=${UNIT_TIMEOUT:-300}
CLI_TIMEOUT=${CLI_TIMEOUT:-600}
pass=0; fail=0; failed_bins=()
for bin in "$@"; do
    t0=$SECONDS
    out=$(timeout -k 10 "$UNIT_TIMEOUT" "$bin" 2>&1 </dev/null); rc=$?
    if [ $rc -eq 124 ] || [ $rc -eq 137 ]; then out="$out
TIMEOUT: $bin did not finish in $UNIT_TIMEOUT s"; fi
    p=$(printf '%s\n' "$out" | sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' | tail -n1)
    f=$(printf '%s\n' "$out" | sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' | tail -n1)
    p=${p:-0}; f=${f:-0}
    if [ $rc -ne 0 ] && [ "$f" = 0 ]; then f=1; fi   # crashed or sanitizer abort: count it
    pass=$((pass + p)); fail=$((fail + f))
    if [ $rc -ne 0 ]; then failed_bins+=("$bin"); printf '%s\n' "$out" | tail -n 40; fi
    printf '  %-40s %3d passed, %d failed  (%d s)\n' "$(basename "$bin")" "$p" "$f" $((SECONDS - t0))
done
# CLI scripts signal their background devices and daemons by design (SIGTERM, SIGINT, then the
# timeouts' own). Under ASan, LeakSanitizer's stop-the-world pass at exit can deadlock when a
# second signal lands during it (seen once: an ASan simulator spinning for 9 minutes at exit), so
# leak checking is off for the programs the CLI scripts start; it stays on in the unit tests,
# which run the same modules in-process. Address and UB checking stay on everywhere.
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
cap=$(mktemp)
trap 'rm -f "$cap"' EXIT
for t in "${CLI_DIR:-tests/cli}"/test_*.sh; do
    [ -f "$t" ] || continue
    t0=$SECONDS
    # stdout goes through a file, not a pipe: a background process a script leaves behind
    # cannot hold the capture open.
    CS_BUILD=${CS_BUILD:-build} timeout -k 10 "$CLI_TIMEOUT" bash "$t" >"$cap" 2>&1 </dev/null; rc=$?
    out=$(cat "$cap")
    if [ $rc -eq 124 ] || [ $rc -eq 137 ]; then out="$out
TIMEOUT: $t did not finish in $CLI_TIMEOUT s"; fi
    p=$(printf '%s\n' "$out" | sed -n 's/^cli: \([0-9]*\) passed, \([0-9]*\) failed$/\1/p' | tail -n1)
    f=$(printf '%s\n' "$out" | sed -n 's/^cli: \([0-9]*\) passed, \([0-9]*\) failed$/\2/p' | tail -n1)
    p=${p:-0}; f=${f:-0}
    if [ $rc -ne 0 ] && [ "$f" = 0 ]; then f=1; fi
    pass=$((pass + p)); fail=$((fail + f))
    if [ $rc -ne 0 ]; then failed_bins+=("$t"); printf '%s\n' "$out" | tail -n 40; fi
    printf '  %-40s %3d passed, %d failed  (%d s)\n' "$(basename "$t")" "$p" "$f" $((SECONDS - t0))
done
echo "$variant: $pass passed, $fail failed"
[ "$fail" -eq 0 ] && [ ${#failed_bins[@]} -eq 0 ]
