#!/usr/bin/env bash
# Command-line tests of `curvestep stream` against `curvestep-sim --pty`: a real SVG job streamed
# in segments mode and in curves mode with the simulator's check passing (deviation, exact final
# position); a device reset mid-job reported with the last executed segment and finished with
# --resume-from; a closed line reported; usage errors. Every process is bounded by `timeout` and
# killed on exit. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"

JOB=tests/data/svg/w3c/paths-data-12-t.svg
ARCS=tests/data/svg/resvg/M-L-Z-A.svg

# stop_dev PID: SIGTERM to the device running under `timeout` PID, to the device itself: through
# timeout (-k 5) it would be killed 5 s later, before an ASan build under load has written its
# report.
stop_dev() { kill $(pgrep -P "$1") 2>/dev/null || kill "$1" 2>/dev/null; }
# start_sim NAME ARGS...: starts the device on a pty in the background (bounded by timeout;
# --instant unless ARGS start with --speed; no idle timer: wait_sim ends it, so a host starved
# of the CPU between two runs or mid-job never finds the device gone),
# sets PTY to its path (empty when it did not start).
start_sim() {
    local name=$1; shift
    local pace=--instant
    [ "${1:-}" = --speed ] && pace=
    timeout -k 5 300 "$SIM" --pty $pace "$@" >"$T/$name.sim" 2>"$T/$name.simerr" &
    pids+=($!)
    SIMPID=$!
    wait_pty "$T/$name.sim" 60
}
# wait_sim: once the host has exited, ends the device started last (SIGTERM: it finishes what
# its executor holds, then reports) and waits for it (at most 60 s: an event, generous under load).
wait_sim() {
    stop_dev "$SIMPID"
    wait_until 60 gone "$SIMPID"
    kill -KILL "$SIMPID" 2>/dev/null
    wait "$SIMPID" 2>/dev/null
}

# 1. segments mode: the whole job executed, the device's check passes.
start_sim seg --reference "$JOB" --check --svg "$T/seg.svg"
expect "sim printed a pty path" [ -c "$PTY" ]
timeout -k 5 60 "$CS" stream --port "$PTY" "$JOB" >"$T/seg.out" 2>"$T/seg.err"; rc=$?
wait_sim
expect "segments: exit 0" [ $rc -eq 0 ]
n=$(sed -n 's/.* -> \([0-9]*\) segments .*/\1/p' "$T/seg.err")
expect "segments: job size on stderr" [ -n "$n" ]
expect "segments: job executed" grep -q "^stream: $PTY: job executed$" "$T/seg.out"
expect "segments: every segment executed" grep -q "^stream: $n of $n segments executed, $n delivered" "$T/seg.out"
expect "segments: plain progress lines" grep -q '^stream: [0-9]*/[0-9]* segments executed' "$T/seg.err"
expect "segments: device executed them all" grep -q "^device: .* $n messages executed ($n step segments" "$T/seg.sim"
expect "segments: device check ok" grep -q '^check: ok$' "$T/seg.sim"
expect "segments: final position exact" grep -q 'rounded to steps: exact' "$T/seg.sim"
expect "segments: deviation reported" grep -qE '^max deviation: [0-9.]+ mm .* ok$' "$T/seg.sim"
expect "segments: picture drawn" grep -q '<polyline' "$T/seg.svg"

# 1b. one sender at a time: while another program holds the port's lock (an exclusive flock, as
# pyserial's exclusive mode; taken here by python, not by the code under test) a sender is
# refused at once, exit 4, naming why, and the device receives nothing.
start_sim busy
python3 -c 'import fcntl, os, sys, time
fd = os.open(sys.argv[1], os.O_RDWR | os.O_NOCTTY)
fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
open(sys.argv[2], "w").write("held\n")
time.sleep(120)' "$PTY" "$T/held" &
holder=$!
pids+=("$holder")
wait_until 60 test -s "$T/held"
run "port locked by another program: exit 4" 4 stream --port "$PTY" "$JOB" &&
    expect_err "port locked: says why" "$PTY: in use by another program"
kill "$holder" 2>/dev/null
wait_sim
expect "port locked: the device received nothing" grep -q ' 0 messages executed' "$T/busy.sim"

# 2. curves mode, with arcs approximated by cubics: same checks on the device.
start_sim cur --reference "$ARCS" --check
timeout -k 5 60 "$CS" stream --mode curves --port "$PTY" "$ARCS" >"$T/cur.out" 2>"$T/cur.err"; rc=$?
wait_sim
expect "curves: exit 0" [ $rc -eq 0 ]
expect "curves: job executed" grep -q "job executed" "$T/cur.out"
expect "curves: arcs approximated (said so)" grep -q 'approximated by cubics' "$T/cur.err"
expect "curves: device traced curves" grep -qE '^device: .*, [1-9][0-9]* curves\)' "$T/cur.sim"
expect "curves: device check ok" grep -q '^check: ok$' "$T/cur.sim"
expect "curves: final position exact" grep -q 'rounded to steps: exact' "$T/cur.sim"

# 2b. on a terminal (script(1) gives it one): a progress bar with percent, ETA, rate, retx.
if command -v script >/dev/null 2>&1; then
    start_sim tty
    timeout -k 5 60 script -qec "'$CS' stream --port '$PTY' '$ARCS'" /dev/null >"$T/tty.out" 2>&1
    rc=$?
    wait_sim
    expect "tty: exit 0" [ $rc -eq 0 ]
    expect "tty: progress bar" grep -qE '\[#+\] 100\.0% [0-9]+/[0-9]+ segments  ETA 0:00  [0-9]+ segments/s  retx [0-9]+' "$T/tty.out"
fi

# 3. a device reset after 500 segments: exit 5, last executed 500; --resume-from 500 alone is
# refused (the position is unknown), with --position (where segment 500 left it) it finishes.
start_sim rst --reference "$JOB" --check --faults reset-after=500
timeout -k 5 60 "$CS" stream --port "$PTY" "$JOB" >"$T/rst.out" 2>"$T/rst.err"; rc=$?
expect "reset: exit 5" [ $rc -eq 5 ]
expect "reset: reported" grep -q 'device reset mid-job (boot id' "$T/rst.out"
expect "reset: last executed 500" grep -q 'last executed: 500$' "$T/rst.out"
expect "reset: confirmed 500" grep -q 'confirmed by the device: segment no. 500 finished' "$T/rst.out"
expect "reset: says how to resume" grep -q -- '--resume-from N --position X,Y,Z' "$T/rst.out"
expect "reset: no plain --resume after a reset" bash -c "! grep -q -- '--resume $JOB' '$T/rst.out'"
# the machine stands where segment 500 left it (the simulator keeps it): state it
at=$(sed -n 's/^stream: segment no. 500 leaves the machine at \([-0-9.,]*\) mm$/\1/p' "$T/rst.out")
expect "reset: position after 500 named" [ -n "$at" ]
timeout -k 5 60 "$CS" stream --resume-from 500 --port "$PTY" "$JOB" >"$T/rst1.out" 2>"$T/rst1.err"; rc=$?
expect "reset: --resume-from without --position refused (exit 5)" [ $rc -eq 5 ]
expect "reset: refusal says what to do" grep -q 'position is unknown. Home it' "$T/rst1.out"
timeout -k 5 60 "$CS" stream --resume-from 500 --position "$at" --port "$PTY" "$JOB" >"$T/rst2.out" 2>"$T/rst2.err"; rc=$?
wait_sim
expect "resume: exit 0" [ $rc -eq 0 ]
expect "resume: job executed" grep -q "job executed" "$T/rst2.out"
expect "resume: device saw one reset" grep -q ' 1 resets' "$T/rst.sim"
expect "resume: device check ok" grep -q '^check: ok$' "$T/rst.sim"
expect "resume: final position exact" grep -q 'rounded to steps: exact' "$T/rst.sim"

# 4. the device closes the line after 300 segments: exit 6, last executed 300.
start_sim cls --faults close-after=300
timeout -k 5 60 "$CS" stream --port "$PTY" "$JOB" >"$T/cls.out" 2>"$T/cls.err"; rc=$?
wait_sim
expect "closed: exit 6" [ $rc -eq 6 ]
expect "closed: reported" grep -q 'link closed' "$T/cls.out"
expect "closed: last executed 300" grep -q 'last executed: 300$' "$T/cls.out"

# 5. Ctrl-C (SIGINT) while the device runs in real time: hold, abort, exit 8.
start_sim int --speed 1 --reference "$JOB"
# (--foreground: timeout would otherwise pass the signal on twice, to the command and to its
# process group, and a second Ctrl-C means "leave at once")
timeout --foreground -k 5 60 "$CS" stream --port "$PTY" "$JOB" >"$T/int.out" 2>"$T/int.err" &
spid=$!
pids+=("$spid")
# an event, not a wall-clock guess: the job is streaming once a progress line counts executed
wait_until 60 grep -qE '^stream: [1-9][0-9]*/' "$T/int.err"
kill -INT "$spid"
wait "$spid"; rc=$?
wait_sim
expect "ctrl-c: exit 8" [ $rc -eq 8 ]
expect "ctrl-c: reported" grep -q 'interrupted: held, then aborted' "$T/int.out"
expect "ctrl-c: device held and aborted" grep -q ' 1 holds, 1 aborts' "$T/int.sim"
k=$(sed -n 's/.*last executed: \([0-9]*\)$/\1/p' "$T/int.out")
expect "ctrl-c: host and device agree on what ran" grep -q "^device: .* $k messages executed" "$T/int.sim"

# 6. a device whose travel is smaller than the host's machine refuses a curve: exit 7, ABORT.
printf '[x]\ntravel_min = 0\ntravel_max = 100\n' >"$T/small.ini"
start_sim err --machine "$T/small.ini"
timeout -k 5 60 "$CS" stream --mode curves --port "$PTY" "$JOB" >"$T/err.out" 2>"$T/err.err"; rc=$?
wait_sim
expect "device error: exit 7" [ $rc -eq 7 ]
expect "device error: reported" grep -qE "device reported an error \(move outside the machine's travel limits, about curve no. [0-9]+\)" "$T/err.out"
expect "device error: aborted" grep -q ' 1 aborts' "$T/err.sim"

# 7. usage and a port that is not there.
"$CS" stream --help >"$T/help.out"; rc=$?
expect "help: exit 0" [ $rc -eq 0 ]
expect "help: exit codes" grep -q '5 the device reset mid-job' "$T/help.out"
"$CS" stream "$JOB" >/dev/null 2>&1; rc=$?
expect "no --port: exit 2" [ $rc -eq 2 ]
timeout -k 5 120 "$CS" stream --port "$T/nope" "$JOB" >/dev/null 2>"$T/nope.err"; rc=$?
expect "missing port: exit 4" [ $rc -eq 4 ]
expect "missing port: named" grep -q "$T/nope" "$T/nope.err"
printf 'M 0 0 L 10 10 Q\n' >"$T/bad.svg"
timeout -k 5 120 "$CS" stream --port /dev/null "$T/bad.svg" >/dev/null 2>"$T/bad.err"; rc=$?
expect "bad job: exit 1, nothing opened" [ $rc -eq 1 ]
expect "bad job: file:line:col" grep -qE "^$T/bad.svg:[0-9]+:[0-9]+: " "$T/bad.err"

finish
