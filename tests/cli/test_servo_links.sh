#!/usr/bin/env bash
# A servo-pen plot over every link that carries pen events, to the simulated device with the
# plotter check: contrib/examples/plotter.svg on contrib/machines/servo-a4.ini, streamed
# (a) over Modbus TCP and (b) Modbus RTU in segments mode (PEN mailbox writes, docs/modbus.md),
# (c) over the serial link and (d) Modbus TCP in curves mode (the pen events between the curves,
# host/cs_stream_pen.c). Each time the device must set the pen as many times as `plan` writes
# "pen US" lines, lower it once a stroke (the plan's down_us lines), and pass the check (pen-down
# motion on the drawing, every stroke reached pen down). Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
need_bin "$CS" "$SIM"
MC=contrib/machines/servo-a4.ini
JOB=contrib/examples/plotter.svg
down=$(sed -n 's/^down_us *= *\([0-9]*\).*/\1/p' "$MC")
run "plan" 0 plan --machine "$MC" "$JOB" -o "$T/job.seg"
pens=$(grep -c '^pen ' "$T/job.seg")
lowers=$(grep -c "^pen $down\$" "$T/job.seg")
expect "plan: pen events ($pens, $lowers down)" [ "$pens" -gt 2 -a "$lowers" -gt 1 ]

# stop_dev PID: SIGTERM to the device running under `timeout` PID, to the device itself: through
# timeout (-k 5) it would be killed 5 s later, before an ASan build under load has written its
# report.
stop_dev() { kill $(pgrep -P "$1") 2>/dev/null || kill "$1" 2>/dev/null; }
# one NAME DEVICE-LINK HOST-LINK [stream options]: the device, the stream, the device's report
one() {
    local name=$1 dev=$2 host=$3
    shift 3
    timeout -k 5 300 "$SIM" $dev --instant --machine "$MC" --reference "$JOB" \
        --check >"$T/$name.sim" 2>"$T/$name.simerr" &
    local sp=$!
    pids+=($sp)
    wait_pty "$T/$name.sim" 60
    timeout -k 5 90 "$CS" stream $host "$PTY" --machine "$MC" "$@" "$JOB" >"$T/$name.out" 2>&1
    expect "$name: stream exit 0" [ $? -eq 0 ]
    stop_dev "$sp" # the host has exited: SIGTERM ends the device with its report
    wait_until 60 gone "$sp"
    wait "$sp"
    expect "$name: device exit 0" [ $? -eq 0 ]
    expect "$name: the device set the pen $pens times" \
        grep -q "^pen: the device set the servo pen $pens times" "$T/$name.sim"
    expect "$name: $lowers pen-downs, strokes reached" \
        grep -qE "^pen: $lowers pen-downs; drawn strokes reached pen down within .* ok\$" "$T/$name.sim"
    expect "$name: check ok" grep -q '^check: ok$' "$T/$name.sim"
}
one mbtcp "--modbus-tcp 127.0.0.1:0" --modbus-tcp
one mbrtu "--modbus-rtu pty" --modbus-rtu
one curves --pty --port --mode curves
one mbcurves "--modbus-tcp 127.0.0.1:0" --modbus-tcp --mode curves
finish
