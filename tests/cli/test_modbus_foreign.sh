#!/usr/bin/env bash
# The Modbus host never waits without a deadline (issue 17 item 2, host side): a second Modbus TCP
# client (libmodbus, tests/cli/lib/mb_foreign.c) writes one segment to the mailbox with the
# device's current sequence while `curvestep stream --modbus-tcp` streams a job to
# `curvestep-sim --modbus-tcp`. The host used to be refused forever (0 segments/s, never
# exiting); now it stops at once with exit 7 and says another client wrote to the mailbox.
# Every wait is an event with a generous deadline. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
LIB=$(dirname "${BASH_SOURCE[0]}")/lib
JOB=tests/data/gcode/one-inch-circle.nc # 78.7 s of motion: 16 s at --speed 5

if ! cc -O1 -o "$T/mb_foreign" "$LIB/mb_foreign.c" $(pkg-config --cflags --libs libmodbus); then
    ko "cannot build the libmodbus helper"
    finish
    exit
fi
timeout -k 5 240 "$SIM" --modbus-tcp 127.0.0.1:0 --speed 5 >"$T/sim.out" 2>"$T/sim.err" &
pids+=($!)
wait_until 30 [ -s "$T/sim.out" ]
ADDR=$(head -n1 "$T/sim.out")
expect "device listening" [ -n "$ADDR" ]
HOST=${ADDR%:*}
PORT=${ADDR##*:}

# the job streams; the host's exit status lands in $T/host.rc
(
    timeout -k 5 200 "$CS" stream --modbus-tcp "$ADDR" "$JOB" >"$T/host.out" 2>"$T/host.err"
    echo $? >"$T/host.rc"
) &
pids+=($!)
# the host's progress lines (one a second on a non-terminal): wait until it has executed some
wait_until 90 grep -qsE '^stream: [1-9][0-9]*/[0-9]+ segments executed' "$T/host.err"
expect "the job is running" grep -qE '^stream: [1-9][0-9]*/' "$T/host.err"
timeout -k 5 90 "$T/mb_foreign" "$HOST" "$PORT" write >"$T/foreign.out" 2>&1
expect "the foreign write was taken" grep -q "foreign segment written" "$T/foreign.out"
wait_until 120 [ -s "$T/host.rc" ]
rc=$(cat "$T/host.rc" 2>/dev/null)
expect "the host stopped by itself (exit ${rc:-none}, expected 7)" [ "${rc:-}" = 7 ]
expect "the host says another client wrote" grep -q "another Modbus client wrote to the mailbox" "$T/host.out"
finish
