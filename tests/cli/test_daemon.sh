#!/usr/bin/env bash
# Command-line tests of the daemon: `curvestep serve` on `curvestep-sim --pty` (5x real time),
# with its socket in a mktemp dir (mode 0600 checked); two jobs submitted and a third one
# cancelled while queued; status shows the queue and the running job's progress; pause holds the
# device (progress stops, the device counts a HOLD) and resume finishes; both jobs run to the end,
# the device's final position is the second job's end; a bad file is refused at submit with
# file:line:col; clients name the socket when no daemon runs. Every process is bounded by
# `timeout` and killed on exit. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"

JOB1=tests/data/svg/resvg/M-L-Z-A.svg     # 25.9 s of motion
JOB2=tests/data/gcode/one-inch-circle.nc   # 78.7 s of motion; ends at X0 Y0 Z0.25 in (G20 G90)
JOB3=tests/data/svg/w3c/paths-data-12-t.svg
# job 1's size as `curvestep plan` counts it (the daemon plans the same way)
N1=$("$CS" plan -o /dev/null "$JOB1" 2>&1 | sed -n 's/.* blocks, \([0-9]*\) segments,.*/\1/p')
S=$T/sock/curvestep.sock
mkdir "$T/sock"
C() { timeout -k 5 120 "$CS" "$@" --socket "$S"; }

# 0. no daemon yet: the clients say so, naming the socket.
C status >/dev/null 2>"$T/nod.err"; rc=$?
expect "no daemon: exit 4" [ $rc -eq 4 ]
expect "no daemon: socket named" grep -q "no daemon answers on $S" "$T/nod.err"

# 1. the device (5 simulated seconds per second: job 1 takes ~5.2 s, long enough that the pause
# below lands inside it even under ASan on a loaded machine; the two jobs ~21 s) and the daemon.
timeout -k 5 90 "$SIM" --pty --speed 5 >"$T/sim.out" 2>"$T/sim.err" &
SIMPID=$!
pids+=($SIMPID)
wait_pty "$T/sim.out" 60
expect "sim printed a pty path" [ -c "$PTY" ]
timeout -k 5 90 "$CS" serve --port "$PTY" --socket "$S" 2>"$T/serve.err" &
DPID=$!
pids+=($DPID)
wait_until 60 [ -S "$S" ]
expect "socket created" [ -S "$S" ]
expect "socket mode 0600" [ "$(stat -c %a "$S")" = 600 ]

# 2. a bad file is refused at submit, with file:line:col; nothing queued.
printf 'M 0 0 L 10 10 Q\n' >"$T/bad.svg"
C submit "$T/bad.svg" >"$T/bad.out" 2>"$T/bad.err"; rc=$?
expect "bad job: exit 1" [ $rc -eq 1 ]
expect "bad job: file:line:col" grep -qE "^$T/bad.svg:[0-9]+:[0-9]+: " "$T/bad.err"
# The shared input options travel as SUBMIT words: --lenient reaches the daemon's G-code reader
# (the unsupported probe move G38.2 becomes a warning) and --fit --margin its layout (no room:
# refused).
printf 'G21\nG1 X1 Y1 F600\nG38.2 Z-1 F100\nG1 X2\n' >"$T/lenient.nc"
C submit "$T/lenient.nc" >"$T/len.out" 2>&1; rc=$?
expect "strict: G38.2 refused" grep -q 'G38.2 is not supported' "$T/len.out"
C submit --lenient --fit --margin 1500 "$T/lenient.nc" >"$T/len.out" 2>&1; rc=$?
expect "--lenient --fit --margin reach the daemon: exit 1, layout refused" [ $rc -eq 1 ]
expect "--lenient --fit --margin reach the daemon: the layout's reason" grep -q 'fit: no room' "$T/len.out"

# 3. two jobs and a third; status shows the queue.
C submit "$JOB1" >"$T/s1.out" 2>&1; r1=$?
C submit "$JOB2" >"$T/s2.out" 2>&1; r2=$?
C submit --mode segments "$JOB3" >"$T/s3.out" 2>&1; r3=$?
expect "submit: exit 0 three times" [ $r1 -eq 0 -a $r2 -eq 0 -a $r3 -eq 0 ]
expect "submit: plan counted job 1" [ -n "$N1" ]
expect "submit: job 1 numbered, size" grep -q "^OK job 1 queued: .*M-L-Z-A.svg: $N1 segments$" "$T/s1.out"
expect "submit: job 2 numbered" grep -q "^OK job 2 queued: .*one-inch-circle.nc: [0-9]* segments$" "$T/s2.out"
C status >"$T/st1.out"; rc=$?
expect "status: exit 0" [ $rc -eq 0 ]
expect "status: device named" grep -q "^OK device $PTY, queue running$" "$T/st1.out"
expect "status: job 1 running" grep -qE "^job 1 running: .*: [0-9]+/$N1 segments executed" "$T/st1.out"
expect "status: job 2 queued" grep -qE "^job 2 queued: .*: 0/[0-9]+ segments executed" "$T/st1.out"
expect "status: job 3 queued" grep -q "^job 3 queued: " "$T/st1.out"

# 4. cancel the queued job 3.
C cancel 3 >"$T/c3.out" 2>&1; rc=$?
expect "cancel queued: exit 0" [ $rc -eq 0 ]
expect "cancel queued: said" grep -q "^OK job 3 cancelled" "$T/c3.out"
C cancel 3 >/dev/null 2>"$T/c3b.err"; rc=$?
expect "cancel again: refused" [ $rc -eq 1 ]
expect "cancel again: why" grep -q "job 3 is cancelled" "$T/c3b.err"

# 5. pause while job 1 runs: progress stops (held), then resume. Job 1 is running and has
# executed some segments (an event, waited for with a generous deadline) when the pause lands.
job1_moving() { C status 2>/dev/null | grep -qE "^job 1 running: .*: [1-9][0-9]*/"; }
wait_until 60 job1_moving
C pause >"$T/p.out"; rc=$?
expect "pause: exit 0" [ $rc -eq 0 ]
expect "pause: device held" grep -q "^OK paused (device held)" "$T/p.out"
# the event: the device confirmed the hold (it reported HELD), status says "(held)"
job1_held() { C status 2>/dev/null >"$T/st2.out" && grep -qE "^job 1 running: .* \(held\)$" "$T/st2.out"; }
expect "paused: the device confirmed the hold" wait_until 60 job1_held
C status >"$T/st3.out"
expect "paused: status says so" grep -q "queue paused" "$T/st2.out"
a=$(sed -n "s/^job 1 running: .*: \([0-9]*\)\/$N1 segments executed (held)$/\1/p" "$T/st2.out")
b=$(sed -n "s/^job 1 running: .*: \([0-9]*\)\/$N1 segments executed (held)$/\1/p" "$T/st3.out")
expect "paused: progress shown" [ -n "$a" ] && [ "${a:-0}" -gt 0 ] && [ "${a:-0}" -lt "$N1" ]
expect "paused: no progress while held" [ -n "$a" ] && [ "$a" = "$b" ]
C resume >"$T/r.out"; rc=$?
expect "resume: exit 0" [ $rc -eq 0 ]

# 6. both jobs finish.
done2=
end=$((SECONDS + 70)) # a deadline, not a count: a daemon that stops answering costs 10 s a call
while [ $SECONDS -lt $end ]; do
    C status >"$T/st4.out" 2>/dev/null || [ $? -ne 124 ] || break
    grep -qE "^job 2 (done|failed|cancelled)" "$T/st4.out" && { done2=1; break; }
    sleep 0.1
done
expect "job 2 ended in time" [ -n "$done2" ]
expect "job 1 done, all executed" grep -q "^job 1 done: .*: $N1/$N1 segments executed (job executed)$" "$T/st4.out"
N2=$(sed -n 's/^job 2 done: .*: \([0-9]*\)\/\1 segments executed (job executed)$/\1/p' "$T/st4.out")
expect "job 2 done, all executed" [ -n "$N2" ]
expect "job 3 stays cancelled" grep -q "^job 3 cancelled: " "$T/st4.out"

# 7. the daemon stops on SIGTERM and removes its socket; the device reports.
kill -TERM "$DPID"
wait "$DPID"; rc=$?
expect "serve: exit 0 on SIGTERM" [ $rc -eq 0 ]
expect "serve: socket removed" [ ! -e "$S" ]
expect "serve: log lines" grep -q "^serve: job 2 done: ${N2:-x}/${N2:-x} executed" "$T/serve.err"
kill -TERM "$SIMPID"
wait "$SIMPID" 2>/dev/null
expect "device: both jobs executed, one hold" \
    grep -q "^device: .* $((N1 + ${N2:-0})) messages executed .* 0 resets, 1 holds, 0 aborts" "$T/sim.out"
# job 2 ends at X0 Y0 Z0.25 in = 6.35 mm, though it started where job 1 ended (the daemon
# plans step segments from the device's position)
expect "device: final position is job 2's end" \
    grep -qE '^final position: x=-?0 steps \(-?0\.0000 mm\) y=-?0 steps \(-?0\.0000 mm\) z=[0-9]+ steps \(6\.3500 mm\)$' "$T/sim.out"

# 8. usage.
"$CS" serve --help >"$T/help.out"; rc=$?
expect "serve --help: exit 0" [ $rc -eq 0 ]
expect "serve --help: 0600" grep -q "0600" "$T/help.out"
"$CS" serve >/dev/null 2>&1; rc=$?
expect "serve without --port: exit 2" [ $rc -eq 2 ]
"$CS" submit --socket "$S" >/dev/null 2>&1; rc=$?
expect "submit without a file: exit 2" [ $rc -eq 2 ]
"$CS" cancel --socket "$S" x >/dev/null 2>&1; rc=$?
expect "cancel x: exit 2" [ $rc -eq 2 ]

finish
