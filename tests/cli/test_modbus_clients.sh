#!/usr/bin/env bash
# Modbus among other clients (issue 17 item 2, docs/modbus.md "Several clients"). Three times
# `curvestep stream --modbus-tcp` streams a job to `curvestep-sim --modbus-tcp` while a second
# client (tests/cli/lib/mb_client.c, raw sockets) (a) writes the mailbox with the device's
# current sequence, (b) polls the status flat out beside nine idle connections, (c) sends
# malformed frames: each time the job
# completes exactly (the host's count, the device's count, its check of the drawing and the
# final position), the foreign write gets exception 1 with REFUSED = 23 (leased), unknown
# function codes get fc | 0x80 with exception 1, a bad protocol id is dropped, an impossible
# MBAP length closes that connection. Then the lease itself: a holder that went silent is waited
# out; a holder that keeps renewing stops the host (exit 7) instead of leaving it waiting.
# Every wait is an event with a generous deadline. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
LIB=$(dirname "${BASH_SOURCE[0]}")/lib
JOB=tests/data/gcode/one-inch-circle.nc # ~15,800 segments, 78.7 s of motion: 8 s at --speed 10
# N: the job's segment count as `curvestep plan` says it (the tracer decides it; it was written
# here as a number until the arc tracer changed it)
need_bin "$CS" "$SIM"
N=$("$CS" plan "$JOB" -o "$T/job.seg" 2>&1 | sed -n 's/^plan: .* blocks, \([0-9]*\) segments,.*/\1/p')
expect "the job plans into segments ($N)" [ "${N:-0}" -gt 1000 ]

if ! cc -std=c99 -D_DEFAULT_SOURCE -O1 -o "$T/mbc" "$LIB/mb_client.c"; then
    ko "cannot build the test client"
    finish
    exit
fi

# start_sim NAME ARGS...: a device in the background; sets ADDR, HOST, PORT, SIMPID
start_sim() {
    local name=$1
    shift
    timeout -k 5 300 "$SIM" --modbus-tcp 127.0.0.1:0 --reference "$JOB" --check "$@" \
        >"$T/$name.out" 2>"$T/$name.err" &
    SIMPID=$!
    pids+=($SIMPID)
    wait_until 60 [ -s "$T/$name.out" ]
    ADDR=$(head -n1 "$T/$name.out")
    HOST=${ADDR%:*}
    PORT=${ADDR##*:}
}

# stop_sim NAME: SIGTERM to the device itself (through its timeout wrapper, -k 5, it would be
# killed 5 s later, before an ASan build under load has checked the job), then its report is
# complete
stop_sim() {
    kill -TERM $(pgrep -P "$SIMPID") 2>/dev/null || kill -TERM "$SIMPID" 2>/dev/null
    wait_until 60 gone "$SIMPID"
    wait "$SIMPID" 2>/dev/null
    SIMRC=$?
}

# stream NAME: the host in the background, its exit status in $T/NAME.rc
stream() {
    (
        timeout -k 5 240 "$CS" stream --modbus-tcp "$ADDR" "$JOB" >"$T/$1.out" 2>"$T/$1.err"
        echo $? >"$T/$1.rc"
    ) &
    pids+=($!)
}

# --- 1. a job streams while another client writes, polls flat out or misbehaves --------------
# the job completes exactly: the host's count, the device's count, its check, the final position
job_exact() {
    local name=$1 rc
    wait_until 200 [ -s "$T/$name-host.rc" ]
    rc=$(cat "$T/$name-host.rc" 2>/dev/null)
    expect "$name: the host finished the job (exit ${rc:-none}, expected 0)" [ "${rc:-}" = 0 ]
    [ "${rc:-}" = 0 ] || sed 's/^/    /' "$T/$name-host.out" | head -3
    expect "$name: the host executed every segment" \
        grep -q "^stream: $N of $N segments executed" "$T/$name-host.out"
    "$T/mbc" "$HOST" "$PORT" status >"$T/$name-status.out" 2>&1
    expect "$name: the host gave the lease back at the end" grep -q "^LEASE 0 " "$T/$name-status.out"
    stop_sim
    expect "$name: device check passed (exit $SIMRC)" [ "$SIMRC" = 0 ]
    expect "$name: device executed the job's segments, exactly" \
        grep -q "; $N messages executed ($N step segments" "$T/dev-$name.out"
    expect "$name: device: final position exact" \
        grep -q "^final position vs job end .*: exact" "$T/dev-$name.out"
}

# with_company NAME: a device, a host streaming to it, until the job runs
with_company() {
    start_sim "dev-$1" --speed 10
    expect "$1: device listening" [ -n "$ADDR" ]
    stream "$1-host"
    wait_until 90 grep -qsE '^stream: [1-9][0-9]*/[0-9]+ segments executed' "$T/$1-host.err"
    expect "$1: the job is running" grep -qE '^stream: [1-9][0-9]*/' "$T/$1-host.err"
}

# a) a foreign write to the mailbox with the device's current sequence
with_company write
timeout -k 5 60 "$T/mbc" "$HOST" "$PORT" write >"$T/foreign.out" 2>&1
expect "write: refused with exception 1, REFUSED 23 (leased), LEASE 1 ($(cat "$T/foreign.out"))" \
    grep -qx "refused: exception 1 (function 0x90), REFUSED 23, LEASE 1" "$T/foreign.out"
job_exact write

# b) a client reading the status flat out, and nine that connect and say nothing
with_company poll
rm -f "$T/stop"
"$T/mbc" "$HOST" "$PORT" poll "$T/stop" >"$T/poll.out" 2>&1 &
pids+=($!)
# the poller has spoken before the idle ones come: a connection that never said anything is
# the one a full server closes first, and the poller must not be taken for one
wait_until 60 grep -qs '^polling' "$T/poll.out"
"$T/mbc" "$HOST" "$PORT" idle 9 "$T/stop" >"$T/idle.out" 2>&1 &
pids+=($!)
wait_until 200 [ -s "$T/poll-host.rc" ]
touch "$T/stop"
wait_until 60 grep -qs '^polls: ' "$T/poll.out"
polls=$(sed -n 's/^polls: \([0-9]*\) answered, 0 bad, 0 reconnections$/\1/p' "$T/poll.out")
expect "poll: the flat-out poller was served too, never refused or cut ($(cat "$T/poll.out" | tail -n1))" \
    [ "${polls:-0}" -ge 100 ]
job_exact poll
expect "poll: the silent connections were closed to make room, not the host's" \
    grep -qE "^tcp: .* [1-9][0-9]* closed to make room" "$T/dev-poll.out"

# c) malformed frames: unknown function codes, a wrong length, a bad protocol id, impossible
# lengths
with_company malformed
timeout -k 5 120 "$T/mbc" "$HOST" "$PORT" malformed >"$T/malformed.out" 2>&1
expect "malformed: every check passed" [ "$(grep -c '^ok ' "$T/malformed.out")" = 10 ]
grep '^FAIL' "$T/malformed.out" | sed 's/^/    /'
job_exact malformed
expect "malformed: a bad MBAP length closed 3 connections, a bad protocol id dropped 1 frame" \
    grep -qE "^tcp: .* 3 closed for a bad MBAP length, 1 frames with another protocol id" \
    "$T/dev-malformed.out"

# --- 2. the lease: a silent holder is waited out, a live one stops the host -----------------
start_sim dev2 --instant
"$T/mbc" "$HOST" "$PORT" claim 4242 >"$T/claim.out" 2>&1
expect "a client claimed the lease and went silent" [ $? = 0 ]
"$T/mbc" "$HOST" "$PORT" status >"$T/status2.out" 2>&1
expect "the device shows it leased" grep -q "^LEASE 1 " "$T/status2.out"
stream host2
wait_until 120 [ -s "$T/host2.rc" ]
rc=$(cat "$T/host2.rc" 2>/dev/null)
expect "the host waited out the silent holder's lease and finished (exit ${rc:-none})" [ "${rc:-}" = 0 ]
expect "... every segment" grep -q "^stream: $N of $N segments executed" "$T/host2.out"
rm -f "$T/stop"
"$T/mbc" "$HOST" "$PORT" hold 4343 "$T/stop" >"$T/hold.out" 2>&1 &
pids+=($!)
wait_until 60 sh -c "'$T/mbc' '$HOST' '$PORT' status | grep -q '^LEASE 1 '"
stream host3
wait_until 120 [ -s "$T/host3.rc" ]
touch "$T/stop"
rc=$(cat "$T/host3.rc" 2>/dev/null)
expect "a host facing a live lease stops by itself (exit ${rc:-none}, expected 7)" [ "${rc:-}" = 7 ]
expect "... and says another client holds the lease" \
    grep -q "another Modbus client holds the writer lease" "$T/host3.out"
expect "... having sent nothing" grep -q "^stream: 0 of $N segments executed, 0 delivered, 0 sent" "$T/host3.out"
stop_sim
expect "device 2: one job executed exactly, check ok" grep -qx "check: ok" "$T/dev2.out"
expect "device 2: $N messages, not one more" grep -q "; $N messages executed" "$T/dev2.out"
finish
