#!/usr/bin/env bash
# Kill-and-resume (issue 17, docs/streaming.md "Resume"): a job streams to `curvestep-sim --pty`
# and, at a random point, the device or the host is killed:
#   dev-TERM, dev-KILL  the device process gets SIGTERM / SIGKILL (the device resets: a new
#                       simulator is started, with the same executed log);
#   dev-close           the device closes the line (--faults close-after=K) and ends;
#   host-KILL, host-TERM the host dies, the device lives on (a line closed from the host's end).
# After a device death, plain `--resume` must be refused (exit 5, "position is unknown"), and
# `--resume-from N --position X,Y,Z` with N and X,Y,Z read off the device's executed log (what a
# user reads off the machine) finishes the job. After a host death, a new host's `--resume` asks
# the device and finishes the job. Every trial must end with the device's executed log (every
# finished segment, `JOB_NO TICKS X Y Z A`, appended across restarts) identical to the log of an
# uninterrupted run (count + sha256: every segment exactly once, in order) and the final
# position exactly the uninterrupted run's end (itself checked against the job's exact end by the
# simulator's --reference --check); after a device death the host's "confirmed" and "may have
# executed up to" numbers must bracket what the device's log says it executed.
# CS_RESUME_TRIALS (default 12) trials; CS_RESUME_SEED (default from the clock) seeds the kill
# points and kinds, printed first so a failure can be replayed. Every wait is on an event (a
# line count, a process gone) with a generous deadline. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
need_bin "$CS" "$SIM"

JOB=tests/data/svg/resvg/M-L-Z-A.svg
TRIALS=${CS_RESUME_TRIALS:-12}
SEED=${CS_RESUME_SEED:-$(( $(date +%s) % 100000 ))}
SPEED=${CS_RESUME_SPEED:-10}
echo "resume: seed $SEED, $TRIALS trials (replay: CS_RESUME_SEED=$SEED CS_RESUME_TRIALS=$TRIALS)"
RANDOM=$SEED
# the machine of both ends, stated here: 80 steps/mm on x, y and z, so a position read off the
# executed log in steps is X/80 mm exactly (1/80 = 0.0125)
printf '[x]\nsteps_per_mm = 80\n[y]\nsteps_per_mm = 80\n[z]\nsteps_per_mm = 80\n' >"$T/m.ini"
M=(--machine "$T/m.ini")

# start_sim NAME ARGS...: a device on a pty, in the background; PTY, SIMPID.
start_sim() {
    local name=$1; shift
    "$SIM" --pty --speed "$SPEED" "${M[@]}" "$@" >"$T/$name.sim" 2>"$T/$name.simerr" &
    SIMPID=$!
    pids+=("$SIMPID")
    wait_pty "$T/$name.sim" 60
}
# stop_sim: SIGTERM to the device started last, then wait (an event) until it wrote its report.
stop_sim() {
    kill -TERM "$SIMPID" 2>/dev/null
    wait_until 120 gone "$SIMPID"
    wait "$SIMPID" 2>/dev/null
}
lines() { [ -f "$1" ] && wc -l <"$1" || echo 0; }
atleast() { [ "$(lines "$1")" -ge "$2" ]; }
# final position the device printed, "x y z" in steps
final_pos() { sed -n 's/^final position: x=\(-*[0-9]*\) steps .* y=\(-*[0-9]*\) steps .* z=\(-*[0-9]*\) steps.*/\1 \2 \3/p' "$1"; }
# the sums of a log's steps columns, "x y z"
log_pos() { awk '{x += $3; y += $4; z += $5} END {printf "%d %d %d\n", x, y, z}' "$1"; }
# job numbers finished more than once
doubles() { awk '$1 > 0 {c[$1]++} END {n = 0; for (k in c) if (c[k] > 1) n++; print n}' "$1"; }

# 0. the uninterrupted run: the reference log and end (checked against the exact job end)
start_sim ref --exlog "$T/ref.log" --reference "$JOB" --check
timeout -k 5 300 "$CS" stream --quiet "${M[@]}" --port "$PTY" "$JOB" >"$T/ref.out" 2>"$T/ref.err"
rc=$?
stop_sim
expect "reference run: exit 0" [ $rc -eq 0 ]
expect "reference run: device check ok" grep -q '^check: ok$' "$T/ref.sim"
n=$(sed -n 's/.* -> \([0-9]*\) segments .*/\1/p' "$T/ref.err")
expect "reference run: one log line per segment ($n)" [ "$(lines "$T/ref.log")" = "$n" ]
expect "reference run: numbered 1..n in order" \
    awk -v n="$n" '$1 != NR {bad = 1} END {exit bad || NR != n}' "$T/ref.log"
REF_POS=$(final_pos "$T/ref.sim")
expect "reference run: log sums to the end" [ "$(log_pos "$T/ref.log")" = "$REF_POS" ]
REF_SHA=$(sha256sum <"$T/ref.log" | cut -d' ' -f1)

# the options' rules, before any device: refused as usage (exit 2)
run "usage: --resume with --resume-from" 2 stream --port /dev/null --resume --resume-from 5 "$JOB"
expect_err "usage: --resume takes no number" 'takes neither --resume-from nor --position'
run "usage: --position alone" 2 stream --port /dev/null --position 1,2,0 "$JOB"
expect_err "usage: --position needs --resume-from" 'needs --resume-from'
run "usage: --resume over Modbus" 2 stream --modbus-tcp 127.0.0.1:1 --resume "$JOB"
expect_err "usage: serial only" 'need --port'
run "usage: --position with a missing axis" 2 stream "${M[@]}" --port /dev/null --resume-from 100 --position 1,2 "$JOB"
# segments mode: the stated position must be where message 100 leaves the machine (the sum of
# the uninterrupted run's first 100 segments); one step off is refused naming it, the exact one
# passes the check (then no device answers on /dev/null: exit 4)
head -n 100 "$T/ref.log" >"$T/first100.log"
read -r px py pz <<<"$(log_pos "$T/first100.log")"
at100=$(awk -v x="$px" -v y="$py" -v z="$pz" 'BEGIN {printf "%.4f,%.4f,%.4f", x / 80, y / 80, z / 80}')
off100=$(awk -v x="$px" -v y="$py" -v z="$pz" 'BEGIN {printf "%.4f,%.4f,%.4f", (x + 1) / 80, y / 80, z / 80}')
run "--position one step off message 100's end" 2 stream "${M[@]}" --port /dev/null --resume-from 100 --position "$off100" "$JOB"
expect_err "names where message 100 left the machine" "message 100 left the machine at x = $(awk -v x="$px" 'BEGIN {printf "%.4f", x / 80}') mm \\($px steps\\)"
run "--position at message 100's end passes the check" 4 stream "${M[@]}" --port /dev/null --resume-from 100 --position "$at100" "$JOB"

kinds=(dev-TERM dev-KILL dev-close host-KILL host-TERM)
exact=0 doubled=0 t_start=$(date +%s)
for i in $(seq 1 "$TRIALS"); do
    kind=${kinds[$((RANDOM % ${#kinds[@]}))]}
    # a point between segment 50 and 90 % of the job (the job must not end before it)
    k=$((50 + (RANDOM * 32768 + RANDOM) % (n * 9 / 10 - 50)))
    log=$T/t$i.log
    ok_trial=1
    if [ "$kind" = dev-close ]; then
        start_sim "t$i.a" --exlog "$log" --faults "close-after=$k"
    else
        start_sim "t$i.a" --exlog "$log"
    fi
    # the host itself, not under timeout(1) (a signal must reach it, not a wrapper); it is
    # bounded by the waits below and killed on exit
    "$CS" stream --quiet "${M[@]}" --port "$PTY" "$JOB" >"$T/t$i.h1" 2>&1 &
    hpid=$!
    pids+=("$hpid")
    [ "$kind" = dev-close ] || wait_until 120 atleast "$log" "$k" || ok_trial=0
    # the victim must still be there: a host that ended by itself before the kill is a failure
    case $kind in
    dev-TERM) kill -TERM "$SIMPID" ;;
    dev-KILL) kill -KILL "$SIMPID" ;;
    host-KILL) kill -KILL "$hpid" 2>/dev/null ;;
    host-TERM) kill -TERM "$hpid" 2>/dev/null ;;
    esac || { ko "trial $i ($kind at $k): the victim had already ended"; sed 's/^/    /' "$T/t$i.h1" | head -8; ok_trial=0; }
    wait_until 120 gone "$hpid" || ok_trial=0
    wait "$hpid" 2>/dev/null; hrc=$?
    if [ "${kind%%-*}" = dev ]; then
        wait_until 120 gone "$SIMPID" || ok_trial=0
        wait "$SIMPID" 2>/dev/null
        [ $hrc -eq 6 ] || { ko "trial $i ($kind at $k): host exit $hrc, expected 6 (link lost)"; ok_trial=0; }
        grep -q 'confirmed by the device: segment no. [0-9]* finished' "$T/t$i.h1" ||
            { ko "trial $i ($kind at $k): no confirmed number"; ok_trial=0; }
        # what the user reads off the machine: the last finished segment and where it is
        N=$(lines "$log")
        # the host's two numbers bracket the truth: confirmed <= executed <= possibly executed
        K=$(sed -n 's/^stream: confirmed by the device: segment no. \([0-9]*\) finished.*/\1/p' "$T/t$i.h1")
        MX=$(sed -n 's/.* it may have executed up to no. \([0-9]*\) .*/\1/p' "$T/t$i.h1")
        MX=${MX:-$K}
        { [ -n "$K" ] && [ "$K" -le "$N" ] && [ "$N" -le "$MX" ]; } ||
            { ko "trial $i ($kind at $k): host said confirmed ${K:-?}, at most ${MX:-?}; the device executed $N"; ok_trial=0; }
        read -r px py pz <<<"$(log_pos "$log")"
        pos=$(awk -v x="$px" -v y="$py" -v z="$pz" 'BEGIN {printf "%.4f,%.4f,%.4f", x / 80, y / 80, z / 80}')
        start_sim "t$i.b" --exlog "$log"
        timeout -k 5 300 "$CS" stream --quiet "${M[@]}" --port "$PTY" --resume "$JOB" >"$T/t$i.h2" 2>&1
        rc=$?
        { [ $rc -eq 5 ] && grep -q 'position is unknown' "$T/t$i.h2"; } ||
            { ko "trial $i ($kind at $k): plain --resume after a device reset: exit $rc, not refused"; ok_trial=0; }
        timeout -k 5 300 "$CS" stream --quiet "${M[@]}" --port "$PTY" --resume-from "$N" \
            --position "$pos" "$JOB" >"$T/t$i.h3" 2>&1
        rc=$?
        [ $rc -eq 0 ] || { ko "trial $i ($kind at $k): --resume-from $N --position $pos: exit $rc"; ok_trial=0; }
        stop_sim
        last=$T/t$i.b.sim
    else
        timeout -k 5 300 "$CS" stream --quiet "${M[@]}" --port "$PTY" --resume "$JOB" >"$T/t$i.h2" 2>&1
        rc=$?
        { [ $rc -eq 0 ] && grep -q '^stream: resumed: ' "$T/t$i.h2"; } ||
            { ko "trial $i ($kind at $k): --resume on the living device: exit $rc"; ok_trial=0; }
        stop_sim
        last=$T/t$i.a.sim
    fi
    d=$(doubles "$log")
    doubled=$((doubled + d))
    got_sha=$(sha256sum <"$log" | cut -d' ' -f1)
    if [ "$got_sha" != "$REF_SHA" ] || [ "$(lines "$log")" != "$n" ]; then
        ko "trial $i ($kind at $k): executed log differs from the uninterrupted run ($(lines "$log") lines of $n, $d done twice)"
        ok_trial=0
    fi
    if [ "$(final_pos "$last")" != "$REF_POS" ]; then
        ko "trial $i ($kind at $k): final position $(final_pos "$last"), expected $REF_POS"
        ok_trial=0
    fi
    echo "resume: trial $i: $kind at segment $k: $([ $ok_trial = 1 ] && echo exact || echo FAILED)"
    if [ $ok_trial = 1 ]; then ok; exact=$((exact + 1)); fi
done
echo "resume: $TRIALS trials, $exact exact ends with every segment once, $doubled segments executed twice, $(( $(date +%s) - t_start )) s (seed $SEED)"
finish
