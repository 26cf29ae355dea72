#!/usr/bin/env bash
# The daemon on the Modbus links: `curvestep serve --modbus-tcp HOST:PORT` and
# `serve --modbus-rtu DEV`, each in front of the simulator's Modbus device (the firmware's
# application: cs_fw_modbus over cs_fw_motion). On each: a job submitted, paused mid-job (the
# device is held: progress stands still, the device counts one HOLD and decelerates, cs_hold),
# resumed, run to the end with every segment executed; the device's own check passes (final
# position = the job's end rounded to steps, velocity and acceleration within the limits); the
# status names the link. The serial link is tests/cli/test_daemon.sh. Every process is bounded by
# `timeout` and killed on exit. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
. "$(dirname "${BASH_SOURCE[0]}")/lib/daemon.sh"
need_bin "$CS" "$SIM"

dmn_job 'G1 X300 Y100 F9000'

for mode in tcp rtu; do
    S=$T/$mode.sock
    if [ $mode = tcp ]; then dev=(--modbus-tcp 127.0.0.1:0); else dev=(--modbus-rtu pty); fi
    timeout -k 5 120 "$SIM" "${dev[@]}" --speed 1 --reference "$JOB" --check >"$T/$mode.sim" \
        2>"$T/$mode.simerr" &
    SIMPID=$!
    pids+=($SIMPID)
    wait_pty "$T/$mode.sim" 60
    ADDR=$PTY
    expect "$mode: device started" [ -n "$ADDR" ]
    dmn_start "--modbus-$mode" "$ADDR"
    C status >"$T/$mode.st0" 2>&1
    expect "$mode: status names the link" grep -q "^OK device $ADDR, queue running$" "$T/$mode.st0"
    C submit "$JOB" >"$T/$mode.sub" 2>&1
    expect "$mode: submitted" grep -q "^OK job 1 queued: .*: $N segments$" "$T/$mode.sub"
    expect "$mode: a quarter ran" wait_until 60 dmn_quarter
    C pause >"$T/$mode.p"
    expect "$mode: paused, device held" grep -q "^OK paused (device held)" "$T/$mode.p"
    expect "$mode: held: progress stands still" wait_until 60 dmn_still
    C resume >/dev/null
    expect "$mode: job ended" wait_until 60 dmn_finished
    C status >"$T/$mode.st" 2>&1
    expect "$mode: every segment executed" \
        grep -q "^job 1 done: .*: $N/$N segments executed (job executed)$" "$T/$mode.st"
    kill -TERM "$DPID"
    wait "$DPID"
    expect "$mode: serve exit 0" [ $? -eq 0 ]
    kill -TERM "$SIMPID"
    wait "$SIMPID"
    expect "$mode: device executed $N, one hold" \
        grep -qE "^device: .* $N messages executed .* 1 holds" "$T/$mode.sim"
    expect "$mode: device check ok (position exact, limits kept)" grep -q '^check: ok$' "$T/$mode.sim"
done

# usage: one link exactly
"$CS" serve --port /dev/null --modbus-tcp 127.0.0.1:1 >/dev/null 2>"$T/two.err"
expect "two links: exit 2" [ $? -eq 2 ]
expect "two links: said" grep -q "give one link" "$T/two.err"
"$CS" serve --modbus-rtu /dev/null --parity mark >/dev/null 2>&1
expect "bad parity: exit 2" [ $? -eq 2 ]
finish
