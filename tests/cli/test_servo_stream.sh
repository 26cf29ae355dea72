#!/usr/bin/env bash
# Command-line test of a servo-pen plot streamed over the serial link: contrib/examples/plotter.svg
# on contrib/machines/servo-a4.ini, `curvestep stream --port` to `curvestep-sim --pty`. The pen
# events travel as PEN messages (docs/protocol.md); the device sets the pen as many times as
# `plan` writes "pen US" lines, the simulator's pen check (by the device's pen settings) passes
# with as many pen-downs as the plan lowers the pen, and the device executed exactly the plan's
# segments (count against the plan). The same job through the daemon (`serve --port`, `submit`)
# gives the device the same pen settings and passes the same check. Every process is bounded by
# `timeout`. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"

MC=contrib/machines/servo-a4.ini
JOB=contrib/examples/plotter.svg

run "plan" 0 plan --machine "$MC" "$JOB" -o "$T/job.seg"
pens=$(grep -c '^pen ' "$T/job.seg")
downs=$(grep '^down_us' "$MC" | sed 's/[^0-9]*\([0-9]*\).*/\1/')
lowers=$(grep -c "^pen $downs\$" "$T/job.seg")
nseg=$(grep -vc -e '^#' -e '^pen ' "$T/job.seg")
expect "plan has pen events ($pens, $lowers lowerings to $downs us)" [ "$pens" -gt 0 -a "$lowers" -gt 0 ]

# stop_dev PID: SIGTERM to the device running under `timeout` PID, to the device itself: through
# timeout (-k 5) it would be killed 5 s later, before an ASan build under load has written its
# report.
stop_dev() { kill $(pgrep -P "$1") 2>/dev/null || kill "$1" 2>/dev/null; }
timeout -k 5 300 "$SIM" --pty --instant --machine "$MC" --reference "$JOB" \
    --check >"$T/dev.sim" 2>"$T/dev.simerr" &
pids+=($!)
SIMPID=$!
wait_pty "$T/dev.sim" 60
expect "sim printed a pty path" [ -c "$PTY" ]
timeout -k 5 120 "$CS" stream --machine "$MC" --port "$PTY" "$JOB" >"$T/st.out" 2>"$T/st.err"
rc=$?
stop_dev "$SIMPID" # the host has exited: SIGTERM ends the device with its report
wait_until 60 gone "$SIMPID"
wait "$SIMPID"; simrc=$?
expect "stream: exit 0" [ $rc -eq 0 ]
expect "stream: job executed" grep -q ": job executed$" "$T/st.out"
expect "device: exit 0 (got $simrc)" [ $simrc -eq 0 ]
expect "device: check passes" grep -q '^check: ok$' "$T/dev.sim"
expect "device: set the pen $pens times" grep -q "^pen: the device set the servo pen $pens times" "$T/dev.sim"
expect "device: $lowers pen-downs, strokes reached" \
    grep -qE "^pen: $lowers pen-downs; drawn strokes reached pen down within [0-9.]+ mm, .* ok\$" "$T/dev.sim"
expect "device: pen-down deviation ok" grep -qE '^deviation of pen-down motion \(x y\): .* ok$' "$T/dev.sim"
expect "device: $nseg segments executed, as planned" \
    grep -qE "^log: $nseg segments hash [0-9]+," "$T/dev.sim"
expect "device: $((nseg + pens)) messages executed" \
    grep -q "^device: served .*; $((nseg + pens)) messages executed ($nseg step segments" "$T/dev.sim"

# The daemon: serve on a fresh simulated device, submit, wait for the job's end, stop both (the
# simulator reports on SIGTERM).
timeout -k 5 120 "$SIM" --pty --instant --machine "$MC" --reference "$JOB" --check \
    >"$T/dd.sim" 2>"$T/dd.simerr" &
pids+=($!)
SIMPID=$!
wait_pty "$T/dd.sim" 60
S=$T/sock
timeout -k 5 120 "$CS" serve --port "$PTY" --machine "$MC" --socket "$S" 2>"$T/serve.err" &
DPID=$!
pids+=($DPID)
wait_until 60 [ -S "$S" ]
timeout -k 5 60 "$CS" submit --socket "$S" "$JOB" >"$T/sub.out" 2>&1
expect "daemon: submitted" [ $? -eq 0 ]
job_done() { timeout -k 5 10 "$CS" status --socket "$S" 2>/dev/null | grep -q '^job 1 done: '; }
wait_until 90 job_done
expect "daemon: job 1 done" job_done
kill "$DPID"
wait_until 60 gone "$DPID"
stop_dev "$SIMPID"
wait_until 60 gone "$SIMPID"
wait "$SIMPID"; simrc=$?
expect "daemon device: exit 0 (got $simrc)" [ $simrc -eq 0 ]
expect "daemon device: check passes" grep -q '^check: ok$' "$T/dd.sim"
expect "daemon device: set the pen $pens times" \
    grep -q "^pen: the device set the servo pen $pens times" "$T/dd.sim"
expect "daemon device: $lowers pen-downs" grep -q "^pen: $lowers pen-downs; .* ok\$" "$T/dd.sim"
finish
