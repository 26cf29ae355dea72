# Shared harness of the command-line tests tests/cli/test_*.sh (sourced, never run: it lives in
# lib/ because scripts/run-tests.sh runs every tests/cli/*.sh as a test). A script starts with
#     set -u
#     . "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
# and ends with `finish`. It gives:
#   B, CS, SIM    the build directory ($CS_BUILD, default build) and the two programs in it;
#   T             a fresh temp dir from mktemp, removed on exit;
#   pids          an array: every background process a script adds is killed on exit;
#   ok / ko MSG   count a passed / failed assertion (ko prints "FAIL: MSG");
#   expect NAME CMD...    one assertion: passes when CMD succeeds (check: the same);
#   run NAME RC ARGS...   runs "$CS" ARGS (stdout in $T/out, stderr in $T/err, status in $rc)
#                         and asserts its exit status is RC;
#   expect_out NAME TEXT  asserts $T/out is exactly TEXT (printf-interpreted);
#   expect_err NAME REGEX asserts $T/err matches REGEX (grep -E);
#   need_bin FILE...      ends the script as one failure when a program is not built;
#   wait_until SECS CMD...   polls CMD every 0.05 s until it succeeds or SECS seconds pass (a
#                         deadline in seconds, never a count of tries: a try that hangs in a
#                         `timeout 10` would multiply the wait); fails at the deadline;
#   gone PID              succeeds when process PID has ended;
#   wait_pty FILE SECS    sets PTY to the first line of FILE (where `curvestep-sim --pty` prints
#                         its terminal) once there is one (a /dev path: once it is a character
#                         device; TCP devices print their address there), or to
#                         "" after SECS seconds (a fresh pty's /dev/pts entry can be missing on
#                         and off for its first ~60 ms here: host/cs_serial.c open_tty);
#   (a script that failed leaves its temp files in $B/failed/<script>.<pid>/ for diagnosis)
#   finish                prints "cli: N passed, M failed" and returns non-zero on a failure
#                         (the last command of a script, so it is the script's exit status).

B=${CS_BUILD:-build}
CS=$B/curvestep
SIM=$B/curvestep-sim
T=$(mktemp -d)
pids=()
pass=0
fail=0

cs_cli_cleanup() {
    local p
    for p in ${pids[@]+"${pids[@]}"}; do kill "$p" 2>/dev/null; done
    wait 2>/dev/null
    # A failed script leaves its files (device reports, logs, plans) for diagnosis: a failure
    # seen only on a loaded machine cannot be rerun at will.
    if [ "$fail" -gt 0 ] && [ -d "$T" ]; then
        local keep
        keep="$B/failed/$(basename "$0" .sh).$$"
        mkdir -p "$keep" && cp -a "$T/." "$keep/" 2>/dev/null &&
            echo "note: $(basename "$0"): its files are kept in $keep"
    fi
    rm -rf "$T"
}
trap cs_cli_cleanup EXIT

ok() { pass=$((pass + 1)); }
ko() { fail=$((fail + 1)); echo "FAIL: $*"; }

expect() { # expect NAME CONDITION...
    local name=$1
    shift
    if "$@"; then ok; else ko "$name"; fi
}
check() { expect "$@"; } # the name test_toolpath.sh uses

run() {
    local name=$1 want=$2
    shift 2
    "$CS" "$@" >"$T/out" 2>"$T/err"
    rc=$?
    if [ "$rc" -ne "$want" ]; then
        ko "$name: exit $rc, expected $want"
        sed 's/^/    /' "$T/err" | head -5
        return 1
    fi
    ok
    return 0
}

expect_out() {
    printf "$2" >"$T/want"
    if cmp -s "$T/out" "$T/want"; then ok; else
        ko "$1: output differs"
        diff "$T/want" "$T/out" | head -10 | sed 's/^/    /'
    fi
}

expect_err() {
    if grep -qE "$2" "$T/err"; then ok; else
        ko "$1: stderr does not match /$2/"
        head -5 "$T/err" | sed 's/^/    /'
    fi
}

need_bin() {
    local f
    for f in "$@"; do
        if [ ! -x "$f" ]; then
            echo "no $f"
            echo "cli: 0 passed, 1 failed"
            exit 1
        fi
    done
}

wait_until() {
    local end=$((SECONDS + $1 + 1)) # SECONDS counts whole seconds: +1 waits at least $1
    shift
    while [ $SECONDS -lt $end ]; do
        "$@" && return 0
        sleep 0.05
    done
    return 1
}

gone() { ! kill -0 "$1" 2>/dev/null; }

cs_cli_pty_ready() {
    PTY=$(head -n1 "$1" 2>/dev/null)
    case $PTY in
    /dev/*) [ -c "$PTY" ] ;;
    *) [ -n "$PTY" ] ;; # a device's TCP address (curvestep-sim --modbus-tcp prints one)
    esac
}
wait_pty() {
    PTY=
    wait_until "$2" cs_cli_pty_ready "$1" || PTY=
}

finish() {
    echo "cli: $pass passed, $fail failed"
    [ "$fail" -eq 0 ]
}
