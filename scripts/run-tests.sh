#!/usr/bin/env bash
# Run every test binary given and tests/cli/test_*.sh (command-line tests, which use $CS_BUILD; or
# $CLI_DIR/test_*.sh), CS_TEST_JOBS at a time (default: the number of cores), and print one
# closing line "<variant>: N passed, N failed" summed from the tests' own counts (cmocka's
# "[  PASSED  ] N" lines, the scripts' "cli: N passed, M failed" lines).
set -u
. "$(dirname "$0")/args.sh"
cs_args "usage: scripts/run-tests.sh VARIANT [TEST-BINARY...]\nRuns each binary and tests/cli/test_*.sh (or CLI_DIR/test_*.sh) with CS_BUILD,\nCS_TEST_JOBS at a time (default: nproc); prints \"VARIANT: N passed, M failed\"." -1 "$@"
variant=$1; shift
# A hung test must fail with its name, never hang the run (CI gives the whole `make test` 90
# minutes): each binary gets UNIT_TIMEOUT seconds, each CLI script CLI_TIMEOUT (ASan runs ~4x
# slower than plain; under a two-core busy load with two tests at a time the slowest script
# takes a few minutes).
UNIT_TIMEOUT=${UNIT_TIMEOUT:-300}
CLI_TIMEOUT=${CLI_TIMEOUT:-900}
JOBS=${CS_TEST_JOBS:-$(nproc 2>/dev/null || echo 2)}
case "$JOBS" in '' | *[!0-9]* | 0) echo "run-tests.sh: CS_TEST_JOBS must be a positive number" >&2; exit 2 ;; esac

# The tests are independent (each script works in its own mktemp directory, takes ephemeral
# ports and its own pseudo-terminals; build/failed/<script>.<pid> is per process), so they run
# side by side. The slow ones start first, so that the runners end together (the list is by
# their time on this machine, longest first: a script or a unit binary by its name); then the
# other scripts; the unit binaries, mostly short, fill in at the end.
slow_first="test_dropcut_shapes test_dropcut test_predict test_resume test_modbus_clients test_plan"
slow_first+=" test_safety_inputs test_help test_grbl test_modbus test_stream test_daemon test_fw_m3_page"
all=("${CLI_DIR:-tests/cli}"/test_*.sh "$@")
items=()
for s in $slow_first; do
    for t in "${all[@]}"; do
        case "$t" in *.sh) k=cli ;; *) k=unit ;; esac
        [ "$(basename "$t" .sh)" = "$s" ] && items+=("$k:$t")
    done
done
for t in "${all[@]}"; do
    case " $slow_first " in *" $(basename "$t" .sh) "*) continue ;; esac
    case "$t" in *.sh) [ -f "$t" ] && items+=("cli:$t") ;; *) items+=("unit:$t") ;; esac
done

dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT

# start_item I: runs item I in the background, its output in $dir/I.out, its exit status in
# $dir/I.rc. stdout goes to a file, not a pipe: a background process a script leaves behind
# cannot hold the capture open.
start_item() {
    local i=$1 kind=${items[$1]%%:*} what=${items[$1]#*:}
    if [ "$kind" = unit ]; then
        ( timeout -k 10 "$UNIT_TIMEOUT" "$what" >"$dir/$i.out" 2>&1 </dev/null; echo $? >"$dir/$i.rc" ) &
    else
        # CLI scripts signal their background devices and daemons by design (SIGTERM, SIGINT,
        # then the timeouts' own). Under ASan, LeakSanitizer's stop-the-world pass at exit can
        # deadlock when a second signal lands during it (seen once: an ASan simulator spinning
        # for 9 minutes at exit), so leak checking is off for the programs the CLI scripts
        # start; it stays on in the unit tests, which run the same modules in-process. Address
        # and UB checking stay on everywhere.
        ( ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" CS_BUILD=${CS_BUILD:-build} \
            timeout -k 10 "$CLI_TIMEOUT" bash "$what" >"$dir/$i.out" 2>&1 </dev/null
          echo $? >"$dir/$i.rc" ) &
    fi
    pid_item[$!]=$i
    t_start[$i]=$SECONDS
}

pass=0; fail=0; failed=()
# finish_item I: adds item I's counts and prints its line (and its last 40 lines if it failed).
finish_item() {
    local i=$1 kind=${items[$1]%%:*} what=${items[$1]#*:} out rc p f limit
    out=$(cat "$dir/$i.out"); rc=$(cat "$dir/$i.rc" 2>/dev/null || echo 1)
    if [ "$kind" = unit ]; then
        limit=$UNIT_TIMEOUT
        p=$(printf '%s\n' "$out" | sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' | tail -n1)
        f=$(printf '%s\n' "$out" | sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' | tail -n1)
    else
        limit=$CLI_TIMEOUT
        p=$(printf '%s\n' "$out" | sed -n 's/^cli: \([0-9]*\) passed, \([0-9]*\) failed$/\1/p' | tail -n1)
        f=$(printf '%s\n' "$out" | sed -n 's/^cli: \([0-9]*\) passed, \([0-9]*\) failed$/\2/p' | tail -n1)
    fi
    if [ "$rc" -eq 124 ] || [ "$rc" -eq 137 ]; then out="$out
TIMEOUT: $what did not finish in $limit s"; fi
    p=${p:-0}; f=${f:-0}
    if [ "$rc" -ne 0 ] && [ "$f" = 0 ]; then f=1; fi   # crashed or sanitizer abort: count it
    pass=$((pass + p)); fail=$((fail + f))
    if [ "$rc" -ne 0 ]; then failed+=("$what"); printf '%s\n' "$out" | tail -n 40; fi
    printf '  %-40s %3d passed, %d failed  (%d s)\n' "$(basename "$what")" "$p" "$f" \
        $((SECONDS - t_start[$i]))
}

declare -A pid_item=()
declare -a t_start=()
next=0 running=0
while [ $next -lt ${#items[@]} ] || [ $running -gt 0 ]; do
    while [ $running -lt "$JOBS" ] && [ $next -lt ${#items[@]} ]; do
        start_item $next; next=$((next + 1)); running=$((running + 1))
    done
    done_pid=
    wait -n -p done_pid
    [ -n "$done_pid" ] || continue
    finish_item "${pid_item[$done_pid]}"
    unset "pid_item[$done_pid]"
    running=$((running - 1))
done
[ ${#failed[@]} -eq 0 ] || printf 'failed: %s\n' "${failed[*]}"
echo "$variant: $pass passed, $fail failed"
[ "$fail" -eq 0 ] && [ ${#failed[@]} -eq 0 ]
