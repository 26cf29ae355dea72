#!/usr/bin/env bash
# Feed hold on the simulator's device (the firmware's application, firmware/app, on the POSIX
# port: the hold is the core's cs_hold). A straight 400 mm line at 200 mm/s (the built-in
# plotter: x/y max_accel 1000 mm/s^2) is submitted to `curvestep serve`, paused mid-cruise,
# left held, resumed, and run to the end; the device's STEP trace (--trace, simulated time) is
# read here with awk, independently of the code under test:
#   the stop: the longest pause between two x steps (> 0.5 s simulated) lies inside the job;
#   it decelerates to rest: x velocity in the last 10 ms before the stop <= 1/8 of the cruise
#     (without a ramp the axis would stop from full speed); it resumes from rest: the same in the
#     first 10 ms after;
#   within the axis limit: velocity over 50 ms windows (the device report's own window) through
#     the 0.5 s before the stop and after the restart changes by at most max_accel (+ 10 %: the
#     speed is constant inside a segment, so a start from rest is a jump to the first segment's
#     mean speed, cs_hold.h);
#   exact: the device's own check (--reference --check: final position = job end rounded to
#     steps, peak velocity and acceleration within the limits over the whole job);
#   every segment once: the device executed exactly the job's segments, and its execution log
#     (count and hash of the segments as planned) equals a run of the same job without a hold.
# Every process is bounded by `timeout`. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
. "$(dirname "${BASH_SOURCE[0]}")/lib/daemon.sh"
need_bin "$CS" "$SIM"

dmn_job 'G1 X400 F12000'
S=$T/sock/cs.sock
mkdir "$T/sock"
logline() { sed -n 's/^log: \([0-9]* segments hash [0-9]*\),.*/\1/p' "$1"; }

# stop_dev PID: SIGTERM to the device running under `timeout` PID, to the device itself: through
# timeout (-k 5) it would be killed 5 s later, before an ASan build under load has written its
# report.
stop_dev() { kill $(pgrep -P "$1") 2>/dev/null || kill "$1" 2>/dev/null; }
# 1. the reference: the same job without a hold (instant)
timeout -k 5 300 "$SIM" --pty --instant >"$T/ref.out" 2>"$T/ref.err" &
pids+=($!)
wait_pty "$T/ref.out" 60
timeout -k 5 60 "$CS" stream --port "$PTY" "$JOB" >"$T/ref.stream" 2>&1
stop_dev "${pids[-1]}" # the host has exited: SIGTERM ends the device with its report
wait_until 60 gone "${pids[-1]}"
expect "reference: $N segments logged" grep -q "^log: $N segments hash " "$T/ref.out"

# 2. the held run: half real time (the cruise takes ~4 s of wall time), traced
timeout -k 5 120 "$SIM" --pty --speed 0.5 --reference "$JOB" --check --trace "$T/trace.csv" \
    >"$T/sim.out" 2>"$T/sim.err" &
SIMPID=$!
pids+=($SIMPID)
wait_pty "$T/sim.out" 60
expect "sim printed a pty path" [ -c "$PTY" ]
dmn_start --port "$PTY"
C submit "$JOB" >"$T/s.out" 2>&1
expect "submit: exit 0" [ $? -eq 0 ]
# pause once a quarter of the job has run (mid-cruise: the ramp up is the first 5 %)
expect "job reached a quarter" wait_until 60 dmn_quarter
C pause >"$T/p.out"
expect "pause: device held" grep -q "^OK paused (device held)" "$T/p.out"
# held: the device confirmed it (status "(held)": it reported HELD)
expect "held: the device confirmed the hold" wait_until 60 dmn_still
# the stimulus, not a wait for an event: the machine stays held a while, so that the stop is
# the trace's longest gap (> 0.5 s simulated: 2.5 s of wall time at --speed 0.5 is 1.25 s
# simulated from the HOLD, the ramp down taking 0.25 s of it; a loaded machine only makes it
# longer)
sleep 2.5
C resume >"$T/r.out"
expect "resume: exit 0" [ $? -eq 0 ]
expect "job ended" wait_until 60 dmn_finished
C status >"$T/st.out" 2>&1
expect "job done, every segment executed" grep -q "^job 1 done: .*: $N/$N segments executed" "$T/st.out"
kill -TERM "$DPID"
wait "$DPID"
stop_dev "$SIMPID"
wait "$SIMPID"
expect "device: check ok (final position exact, limits kept)" grep -q '^check: ok$' "$T/sim.out"
expect "device: final position exact" grep -q '^final position vs job end .*: exact$' "$T/sim.out"
expect "device: $N executed, one hold" grep -q "^device: .* $N messages executed .* 1 holds, 0 aborts" "$T/sim.out"
expect "device: the same segments as without the hold, each once" \
    [ -n "$(logline "$T/sim.out")" ] && [ "$(logline "$T/sim.out")" = "$(logline "$T/ref.out")" ]

# 3. the trace: x steps' times and positions
awk -F, 'NR > 1 && $2 == "x" { print $1, $4 }' "$T/trace.csv" >"$T/x.txt"
read -r TA TB VPEAK VEND VSTART ACC_DN ACC_UP < <(awk '
    { t[NR] = $1; x[NR] = $2 }
    END {
        n = NR; g = 0
        for (i = 2; i <= n; i++) if (t[i] - t[i - 1] > g) { g = t[i] - t[i - 1]; a = i - 1 }
        ta = t[a]; tb = t[a + 1]
        # position at time s by the last step at or before s (binary search)
        # velocity over [s, s + w]: (x(s + w) - x(s)) / w
        vp = 0
        for (s = t[1]; s + 0.01 < t[n]; s += 0.01) { v = (px(s + 0.01) - px(s)) / 0.01; if (v < 0) v = -v; if (v > vp) vp = v }
        ve = (px(ta) - px(ta - 0.01)) / 0.01; if (ve < 0) ve = -ve
        vs = (px(tb + 0.01) - px(tb - 1e-9)) / 0.01; if (vs < 0) vs = -vs
        ad = 0
        for (s = ta - 0.5; s + 0.1 <= ta + 1e-9; s += 0.01) {
            d = ((px(s + 0.1) - px(s + 0.05)) - (px(s + 0.05) - px(s))) / 0.05 / 0.05
            if (d < 0) d = -d; if (d > ad) ad = d }
        au = 0
        for (s = tb - 0.05; s + 0.1 <= tb + 0.5; s += 0.01) {
            d = ((px(s + 0.1) - px(s + 0.05)) - (px(s + 0.05) - px(s))) / 0.05 / 0.05
            if (d < 0) d = -d; if (d > au) au = d }
        printf "%.6f %.6f %.3f %.3f %.3f %.1f %.1f\n", ta, tb, vp, ve, vs, ad, au
    }
    function px(s,   lo, hi, m) {
        if (s < t[1]) return 0
        lo = 1; hi = n
        while (lo < hi) { m = int((lo + hi + 1) / 2); if (t[m] <= s) lo = m; else hi = m - 1 }
        return x[lo]
    }' "$T/x.txt")
echo "note: stop at ${TA}s, restart at ${TB}s (simulated); cruise ${VPEAK} mm/s, ${VEND} mm/s in the last 10 ms, ${VSTART} mm/s in the first 10 ms after; |dv/dt| <= ${ACC_DN} mm/s^2 down, ${ACC_UP} up"
in_job() { awk -v a="$TA" -v b="$TB" 'BEGIN { exit !(b - a > 0.5 && a > 0.3) }'; }
expect "the stop is a pause inside the job" in_job
expect "cruise near 200 mm/s" awk -v v="$VPEAK" 'BEGIN { exit !(v > 190 && v < 205) }'
expect "decelerated to rest before the stop (<= cruise / 8)" awk -v v="$VEND" -v p="$VPEAK" 'BEGIN { exit !(v <= p / 8) }'
expect "restarted from rest (<= cruise / 8)" awk -v v="$VSTART" -v p="$VPEAK" 'BEGIN { exit !(v <= p / 8) }'
expect "ramp down within max_accel 1000 mm/s^2 (+10 %)" awk -v a="$ACC_DN" 'BEGIN { exit !(a <= 1100) }'
expect "ramp up within max_accel 1000 mm/s^2 (+10 %)" awk -v a="$ACC_UP" 'BEGIN { exit !(a <= 1100) }'
finish
