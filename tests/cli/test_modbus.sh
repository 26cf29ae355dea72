#!/usr/bin/env bash
# Command-line tests of the Modbus link: `curvestep stream --modbus-tcp / --modbus-rtu` against
# `curvestep-sim --modbus-tcp 127.0.0.1:0` (libmodbus server) and `--modbus-rtu pty` (the core's
# RTU server), as a user runs them. The same job streamed over serial, Modbus TCP and Modbus RTU
# gives the same step trace (every STEP edge, its axis, direction and position) and the same
# executed segments; curves mode passes the device's check; with answers lost, answers late
# (past the host's timeout), busy refusals and a device failure, every segment is executed exactly
# once (executed count, hash of the executed segments and step trace equal the fault-free run's);
# a wrong unit id is reported as such; Ctrl-C holds then aborts; usage errors. Every process is
# bounded by `timeout` and killed on exit. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"

need_bin "$CS" "$SIM"
JOB=tests/data/svg/resvg/M-L-Z-A.svg
# a small job (271 segments): the fault runs wait out one 200 ms timeout per lost answer
SMALL=$T/small.nc
printf 'G21 G90\nG1 X10 Y0 F3000\nG2 X10 Y10 I0 J5\nG1 X0 Y10\nG3 X0 Y0 I0 J-5\n' >"$SMALL"

# stop_dev PID: SIGTERM to the device running under `timeout` PID, to the device itself: through
# timeout (-k 5) it would be killed 5 s later, before an ASan build under load has written its
# report.
stop_dev() { kill $(pgrep -P "$1") 2>/dev/null || kill "$1" 2>/dev/null; }
# start_dev NAME ser|tcp|rtu ARGS...: the device in the background (--instant unless ARGS start
# with --speed; it runs until wait_dev ends it: no idle timer, which a host starved of the CPU
# on a loaded machine would outlast mid-job), ADDR = the pty path or HOST:PORT it printed first
# ("" when it did not start).
declare -A devpid
start_dev() {
    local name=$1 mode=$2
    shift 2
    local pace=--instant
    [ "${1:-}" = --speed ] && pace=
    case $mode in
    ser) set -- --pty "$@" ;;
    tcp) set -- --modbus-tcp 127.0.0.1:0 "$@" ;;
    rtu) set -- --modbus-rtu pty "$@" ;;
    esac
    timeout -k 5 300 "$SIM" "$@" $pace >"$T/$name.sim" 2>"$T/$name.simerr" &
    pids+=($!)
    devpid[$name]=$!
    wait_pty "$T/$name.sim" 60
    ADDR=$PTY
}
# wait_dev NAME: once its host has exited, ends device NAME (SIGTERM: it finishes what its
# executor holds, then reports) and waits for it (at most 60 s: an event, generous under load).
wait_dev() {
    local p=${devpid[$1]}
    stop_dev "$p"
    wait_until 60 gone "$p"
    kill "$p" 2>/dev/null
    wait "$p" 2>/dev/null
}
# stream_to NAME ser|tcp|rtu ARGS...: streams to device NAME's address; stdout/stderr in
# $T/NAME.out/.err, rc.
stream_to() {
    local name=$1 mode=$2
    shift 2
    local link=--port
    [ "$mode" = tcp ] && link=--modbus-tcp
    [ "$mode" = rtu ] && link=--modbus-rtu
    timeout -k 5 60 "$CS" stream "$link" "$(head -n1 "$T/$name.sim")" "$@" >"$T/$name.out" 2>"$T/$name.err"
    rc=$?
}
# launch NAME ser|tcp|rtu "SIM ARGS" HOST ARGS...: a device (with --trace $T/NAME.csv) and a host
# streaming to it, in the background; landed waits for every host, then ends every device and
# waits for its report, the host's exit status then in $T/NAME.rc.
launched=()
hostpids=()
launch() {
    local name=$1 mode=$2 simargs=$3
    shift 3
    start_dev "$name" $mode $simargs --trace "$T/$name.csv"
    (stream_to "$name" $mode "$@"; echo $rc >"$T/$name.rc") &
    hostpids+=($!)
    pids+=($!)
    launched+=("$name")
}
landed() {
    local name
    wait "${hostpids[@]}"
    for name in "${launched[@]}"; do wait_dev "$name"; done
    launched=()
    hostpids=()
}
rc_of() { cat "$T/$1.rc" 2>/dev/null; }
hash_of() { sed -n "s/^executed step segments' hash (FNV-1a 32, in order): //p" "$T/$1.sim"; }
executed_of() { sed -n 's/^device: served [0-9.]* s; \([0-9]*\) messages executed.*/\1/p' "$T/$1.sim"; }
# the step trace without its time column (see docs/modbus.md: the time of an edge moves by one
# executor tick each time the executor runs dry and restarts, which depends on the link's pace)
steps_of() { cut -d, -f2- "$T/$1.csv"; }

# 1. the same job over serial, Modbus TCP and Modbus RTU (at once): identical steps; the device
# on the serial link checks the trace against the drawing.
launch same_ser ser "--reference $JOB --check" "$JOB"
launch same_tcp tcp "" "$JOB"
launch same_rtu rtu "" "$JOB"
landed
n=$(sed -n 's/.* -> \([0-9]*\) segments .*/\1/p' "$T/same_ser.err")
for mode in ser tcp rtu; do
    ADDR=$(head -n1 "$T/same_$mode.sim")
    expect "$mode: device started" [ -n "$ADDR" ]
    expect "$mode: exit 0" [ "$(rc_of "same_$mode")" = 0 ]
    expect "$mode: job executed" grep -q "^stream: $ADDR: job executed$" "$T/same_$mode.out"
    expect "$mode: all $n executed" grep -q "^stream: $n of $n segments executed, $n delivered" "$T/same_$mode.out"
    expect "$mode: device executed $n" [ "$(executed_of "same_$mode")" = "$n" ]
done
expect "ser: device check ok" grep -q '^check: ok$' "$T/same_ser.sim"
expect "tcp: bound to loopback" grep -qE '^127\.0\.0\.1:[0-9]+$' "$T/same_tcp.sim"
expect "job has segments" [ "${n:-0}" -gt 1000 ]
expect "traces are not empty" [ "$(steps_of same_ser | wc -l)" -gt 10000 ]
expect "serial = TCP: same step trace" cmp -s <(steps_of same_ser) <(steps_of same_tcp)
expect "serial = RTU: same step trace" cmp -s <(steps_of same_ser) <(steps_of same_rtu)
expect "serial = TCP = RTU: same executed segments" [ "$(hash_of same_ser)" = "$(hash_of same_tcp)" -a "$(hash_of same_ser)" = "$(hash_of same_rtu)" -a -n "$(hash_of same_ser)" ]
expect "progress lines" grep -q '^stream: [0-9]*/[0-9]* segments executed' "$T/same_tcp.err"

# 1b. in (half) real time, where every link keeps the device's queue ahead of the motion (it
# never runs dry), the whole trace is identical, the time of every edge included.
# A host stalled for a few hundred ms by a loaded machine (CI under ASan) lets a device run dry,
# which moves later edges by a tick: then the run is made again, slower (at 0.2 and then 0.1 of
# real time the queue covers 2.5x and 5x longer stalls; measured: with two busy loops beside an
# ASan run, the RTU device at 0.5 ran dry 10 times in 2 of 4 runs), and judged on the last.
# The Modbus hosts wait up to 1 s for an answer (--modbus-timeout): on a loaded machine an
# answer 200 ms late is taken, not retried (a retry costs the timeout and a round trip more).
for speed in 0.5 0.2 0.1; do
    launch rt_ser ser "--speed $speed" "$SMALL"
    for mode in tcp rtu; do launch "rt_$mode" $mode "--speed $speed" --modbus-timeout 1000 "$SMALL"; done
    landed
    dry=0
    for mode in ser tcp rtu; do
        grep -q '^executor ran dry 0 times' "$T/rt_$mode.sim" || dry=1
    done
    [ $dry -eq 0 ] && break
    [ $speed != 0.1 ] && echo "note: a device ran dry in the real-time run at $speed (machine loaded?): slower"
done
for mode in ser tcp rtu; do
    expect "real time $mode: exit 0" [ "$(rc_of "rt_$mode")" = 0 ]
done
# Whether a host keeps a device fed is a matter of pace, which a loaded machine decides (the
# loaded CI still saw the RTU device run dry at 0.1): a run where one ran dry at every speed is
# judged without the time column, and says so; a quiet machine judges the times too.
if [ $dry -eq 0 ]; then
    expect "real time: serial = TCP, times included" cmp -s "$T/rt_ser.csv" "$T/rt_tcp.csv"
    expect "real time: serial = RTU, times included" cmp -s "$T/rt_ser.csv" "$T/rt_rtu.csv"
else
    echo "note: a device ran dry at every speed (machine loaded): the real-time traces are compared without their times"
    expect "real time: serial = TCP (steps)" cmp -s <(steps_of rt_ser) <(steps_of rt_tcp)
    expect "real time: serial = RTU (steps)" cmp -s <(steps_of rt_ser) <(steps_of rt_rtu)
fi
expect "real time: trace not empty" [ "$(wc -l <"$T/rt_ser.csv")" -gt 1000 ]

# 2. curves mode over TCP and RTU: the device traces the cubics, its check passes.
for mode in tcp rtu; do launch "cur_$mode" $mode "--reference $JOB --check" --mode curves "$JOB"; done
landed
for mode in tcp rtu; do
    expect "curves $mode: exit 0" [ "$(rc_of "cur_$mode")" = 0 ]
    expect "curves $mode: job executed" grep -q "job executed" "$T/cur_$mode.out"
    expect "curves $mode: device traced curves" grep -qE '^device: .*, [1-9][0-9]* curves\)' "$T/cur_$mode.sim"
    expect "curves $mode: device check ok" grep -q '^check: ok$' "$T/cur_$mode.sim"
done

# 3. faults on the small job: every segment executed exactly once, whatever was lost.
start_dev base tcp --trace "$T/base.csv"
stream_to base tcp "$SMALL"
wait_dev base
ns=$(sed -n 's/.* -> \([0-9]*\) segments .*/\1/p' "$T/base.err")
expect "base: exit 0" [ $rc -eq 0 ]
expect "base: $ns executed" [ -n "$ns" -a "$(executed_of base)" = "$ns" ]
# once_as_base NAME: the device executed the base job's segments, each once, in order
once_as_base() {
    expect "$1: executed $ns" [ "$(executed_of "$1")" = "$ns" ]
    expect "$1: same segments as without faults" [ "$(hash_of "$1")" = "$(hash_of base)" ]
    expect "$1: same step trace as without faults" cmp -s <(steps_of "$1") <(steps_of base)
}
# answers lost after the device acted: the host's retries are answered, not executed again;
# answers sent late, 1 s, past the host's --modbus-timeout 600: the host retries, then meets the
# late answer; (the tries of every run are widened from the default 200 ms so that six runs at
# once under ASan on a loaded machine still answer in time)
# exception 6 (server device busy): nothing taken, the host writes it again
# (all six at once, and a seventh, fault-free, over RTU in 8N2: both sides --parity none, where
# the default is 8E1; a pty takes either)
for mode in tcp rtu; do
    launch "drop_$mode" $mode "--faults drop=0.02,seed=3" --modbus-timeout 1000 "$SMALL"
    launch "late_$mode" $mode "--faults delay=0.02,delay-ms=1000,seed=7" --modbus-timeout 600 "$SMALL"
    launch "busy_$mode" $mode "--faults busy=0.2,seed=5" --modbus-timeout 1000 "$SMALL"
done
launch par_rtu rtu "--parity none" --parity none "$SMALL"
landed
expect "parity none: exit 0" [ "$(rc_of par_rtu)" = 0 ]
once_as_base par_rtu
for mode in tcp rtu; do
    expect "drop $mode: exit 0" [ "$(rc_of "drop_$mode")" = 0 ]
    expect "drop $mode: answers were dropped" grep -qE '^faults: [1-9][0-9]* answers dropped' "$T/drop_$mode.sim"
    expect "drop $mode: host timed out and retried" grep -qE '[1-9][0-9]* retransmissions \([1-9][0-9]* timeouts' "$T/drop_$mode.out"
    expect "drop $mode: repeats answered without executing" grep -qE ' [1-9][0-9]* repeats answered without executing' "$T/drop_$mode.sim"
    once_as_base "drop_$mode"
    expect "late $mode: exit 0" [ "$(rc_of "late_$mode")" = 0 ]
    expect "late $mode: answers were late" grep -qE ' [1-9][0-9]* delayed' "$T/late_$mode.sim"
    once_as_base "late_$mode"
    expect "busy $mode: exit 0" [ "$(rc_of "busy_$mode")" = 0 ]
    expect "busy $mode: refusals counted" grep -qE ' [1-9][0-9]* NAKs\)' "$T/busy_$mode.out"
    once_as_base "busy_$mode"
done

# 4. exception 4 (server device failure) on the 100th write: exit 7, a clear sentence, the last
# executed segment; --resume-from finishes, each segment once.
# (the device stays up between the two hosts; SIGTERM ends it, with its report)
start_dev fail tcp --faults fail-at=100 --trace "$T/fail.csv"
stream_to fail tcp "$SMALL"
expect "failure: exit 7" [ $rc -eq 7 ]
expect "failure: says which exception" grep -q 'Modbus exception 4 (server device failure)' "$T/fail.out"
expect "failure: about segment 100" grep -q 'about segment no. 100)' "$T/fail.out"
expect "failure: last executed 99" grep -q 'last executed: 99$' "$T/fail.out"
expect "failure: says how to resume" grep -q -- '--resume-from 99 ' "$T/fail.out"
stream_to fail tcp --resume-from 99 "$SMALL"
wait_dev fail
expect "resume: exit 0" [ $rc -eq 0 ]
expect "resume: job executed" grep -q "job executed" "$T/fail.out"
once_as_base fail

# 5. a wrong unit id: the device does not answer, the host says to check --unit (exit 4).
#    (and over TCP once more with --modbus-timeout 1000: each try waits 1 s, so at most one try
#    a second, where the default makes five)
for mode in tcp rtu; do launch "unit_$mode" $mode "" --unit 7 "$SMALL"; done
launch unit_slow tcp "" --unit 7 --modbus-timeout 1000 "$SMALL"
landed
tries_per_s=$(sed -n 's/.*no answer from unit 7: \([0-9]*\) tries in \([0-9.]*\) s.*/\1 \2/p' "$T/unit_slow.out")
expect "unit --modbus-timeout 1000: exit 4" [ "$(rc_of unit_slow)" = 4 ]
expect "unit --modbus-timeout 1000: tries 1 s apart ($tries_per_s)" \
    awk -v v="$tries_per_s" 'BEGIN { split(v, a, " "); exit !(a[1] > 0 && a[1] <= a[2] + 1) }'
for mode in tcp rtu; do
    expect "unit $mode: exit 4" [ "$(rc_of "unit_$mode")" = 4 ]
    expect "unit $mode: says so" grep -qE 'no device answered \(no answer from unit 7: [0-9]+ tries in [0-9.]+ s; is --unit right' "$T/unit_$mode.out"
    expect "unit $mode: device ignored them" grep -qE '\([1-9][0-9]* for other units, not answered\); 0 mailbox writes accepted' "$T/unit_$mode.sim"
done

# 6. Ctrl-C over RTU in (a quarter of) real time: HOLD, then ABORT; host and device agree on
# the last executed.
start_dev int rtu --speed 0.25
# (--foreground: timeout would otherwise pass the signal on twice, to the command and to its
# process group, and a second Ctrl-C means "leave at once")
timeout --foreground -k 5 60 "$CS" stream --modbus-rtu "$ADDR" "$SMALL" >"$T/int.out" 2>"$T/int.err" &
hp=$!
pids+=($hp)
wait_until 60 grep -q '^stream: [1-9][0-9]*/' "$T/int.err"
sleep 0.2
kill -INT $hp
wait $hp
rc=$?
wait_dev int
expect "ctrl-c: exit 8" [ $rc -eq 8 ]
expect "ctrl-c: held, then aborted" grep -q 'interrupted: held, then aborted' "$T/int.out"
expect "ctrl-c: device held and aborted" grep -qE '^device: .* 1 holds, 1 aborts' "$T/int.sim"
hx=$(sed -n 's/.*last executed: \([0-9]*\)$/\1/p' "$T/int.out")
expect "ctrl-c: host's last executed = device's count" [ -n "$hx" -a "$hx" = "$(executed_of int)" ]
expect "ctrl-c: stopped mid-job" [ "${hx:-0}" -gt 0 -a "${hx:-0}" -lt "$ns" ]

# 7. usage and connection errors.
run "malformed HOST:PORT" 2 stream --modbus-tcp nowhere "$SMALL"
expect_err "says what it wants" 'HOST:PORT'
run "nobody listening" 4 stream --modbus-tcp 127.0.0.1:1 "$SMALL"
expect_err "says it cannot connect" 'cannot connect'
run "no such serial device" 4 stream --modbus-rtu "$T/no-such-tty" "$SMALL"
run "--line-rate is for --port" 2 stream --modbus-tcp 127.0.0.1:1 --line-rate 9600 "$SMALL"
run "bad --parity" 2 stream --modbus-rtu "$T/no-such-tty" --parity mark "$SMALL"
expect_err "says what --parity wants" 'parity wants none, even or odd'
run "--parity is for --modbus-rtu" 2 stream --modbus-tcp 127.0.0.1:1 --parity even "$SMALL"
expect_err "says where --parity applies" 'parity applies to --modbus-rtu only'
run "bad --modbus-timeout" 2 stream --modbus-tcp 127.0.0.1:1 --modbus-timeout 5 "$SMALL"
expect_err "says what --modbus-timeout wants" 'modbus-timeout wants milliseconds, 10..60000'
run "--modbus-timeout is for Modbus" 2 stream --port "$T/no-such-tty" --modbus-timeout 500 "$SMALL"
expect_err "says where --modbus-timeout applies" 'modbus-timeout applies to a Modbus link only'
run "serve: --modbus-timeout is for Modbus" 2 serve --port "$T/no-such-tty" --modbus-timeout 500
expect_err "serve says where --modbus-timeout applies" 'modbus-timeout applies to a Modbus link only'
"$SIM" --modbus-rtu pty --parity space >"$T/out" 2>"$T/err"
expect "sim: bad --parity (exit 2)" [ $? -eq 2 ]
"$SIM" --modbus-tcp 127.0.0.1:0 --parity odd >"$T/out" 2>"$T/err"
expect "sim: --parity is for --modbus-rtu (exit 2)" [ $? -eq 2 ]
"$SIM" --modbus-tcp 127.0.0.1:0 --modbus-rtu pty >"$T/out" 2>"$T/err"
expect "sim: one link only (exit 2)" [ $? -eq 2 ]
"$SIM" --modbus-tcp 127.0.0.1:0 --faults drop=2 >"$T/out" 2>"$T/err"
expect "sim: bad fault list (exit 2)" [ $? -eq 2 ]
"$SIM" --modbus-tcp localhost:0 >"$T/out" 2>"$T/err"
expect "sim: wants an IPv4 address (exit 2)" [ $? -eq 2 ]
"$SIM" --modbus-tcp --help >"$T/out" 2>"$T/err"
expect "sim: --help" grep -q 'curvestep-sim --modbus-tcp ADDR:PORT' "$T/out"

finish
