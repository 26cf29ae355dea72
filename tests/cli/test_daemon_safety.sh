#!/usr/bin/env bash
# The daemon, safe by default (issue 17 item 3; docs/streaming.md, "Who may talk to the daemon"):
# the default socket lives in $XDG_RUNTIME_DIR/curvestep/ (created 0700); a socket directory that
# is writable by others or owned by another user is refused; --socket never removes anything but
# a stale socket of ours; sixteen silent clients never lock out status; an idle client is closed;
# a FIFO, a device or a directory submitted is refused at once (the daemon keeps answering); a job
# is read once, at submit (rewriting the file afterwards changes nothing); as root, a client of
# another user is refused by the daemon and a socket served by another user is refused by the
# client. Every wait is an event with a generous deadline. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
LIB=$(dirname "${BASH_SOURCE[0]}")/lib

timeout -k 5 120 "$SIM" --pty --speed 50 >"$T/sim.out" 2>"$T/sim.err" &
pids+=($!)
wait_pty "$T/sim.out" 60
expect "sim printed a pty path" [ -c "$PTY" ]

# 1. a socket directory writable by others (/tmp's kind) is refused: exit 3, nothing created.
mkdir -m 777 "$T/ww"
timeout -k 5 30 "$CS" serve --port "$PTY" --socket "$T/ww/d.sock" 2>"$T/ww.err"; rc=$?
expect "world-writable dir: exit 3" [ $rc -eq 3 ]
expect "world-writable dir: says why" grep -q "is writable by others" "$T/ww.err"
expect "world-writable dir: no socket" [ ! -e "$T/ww/d.sock" ]

# 2. --socket naming a regular file: refused, and the file is left alone.
mkdir "$T/own"
echo precious >"$T/own/file"
timeout -k 5 30 "$CS" serve --port "$PTY" --socket "$T/own/file" 2>"$T/reg.err"; rc=$?
expect "regular file: exit 3" [ $rc -eq 3 ]
expect "regular file: not removed" grep -q precious "$T/own/file"
expect "regular file: says so" grep -q "not a socket of this user's: not removed" "$T/reg.err"

# 3. the default socket: $XDG_RUNTIME_DIR/curvestep/curvestep.sock in a directory made 0700.
mkdir -m 700 "$T/rt"
XDG_RUNTIME_DIR=$T/rt timeout -k 5 120 "$CS" serve --port "$PTY" 2>"$T/serve.err" &
DPID=$!
pids+=($DPID)
S=$T/rt/curvestep/curvestep.sock
wait_until 60 [ -S "$S" ]
expect "default socket in \$XDG_RUNTIME_DIR/curvestep/" [ -S "$S" ]
expect "its directory is 0700" [ "$(stat -c %a "$T/rt/curvestep")" = 700 ]
C() { timeout -k 5 30 "$CS" "$@" --socket "$S"; }
XDG_RUNTIME_DIR=$T/rt timeout -k 5 30 "$CS" status >"$T/st0.out" 2>&1; rc=$?
expect "clients find the default socket" [ $rc -eq 0 ]
kill -TERM $DPID
wait_until 60 gone $DPID
expect "default socket removed on stop" [ ! -e "$S" ]

# The rest with --socket in a private directory (as the old daemon could be run).
mkdir "$T/priv"
S=$T/priv/d.sock
timeout -k 5 120 "$CS" serve --port "$PTY" --socket "$S" --max-input-mb 1 2>"$T/serve2.err" &
DPID=$!
pids+=($DPID)
wait_until 60 [ -S "$S" ]
expect "second daemon up" [ -S "$S" ]

# 4. sixteen silent clients (the old limit) and more: status still answers.
python3 "$LIB/holdconn.py" "$S" 20 40 >"$T/hold.out" 2>&1 &
HPID=$!
pids+=($HPID)
wait_until 60 grep -qs holding "$T/hold.out"
C status >"$T/st1.out" 2>&1; rc=$?
expect "20 silent clients: status exit 0" [ $rc -eq 0 ]
expect "20 silent clients: status answered" grep -q "^OK device" "$T/st1.out"
C pause >"$T/p1.out" 2>&1; rc=$?
expect "20 silent clients: pause answered" [ $rc -eq 0 ]
kill $HPID 2>/dev/null

# 5. an idle client is closed by the daemon (after 5 s; the deadline here is 60 s).
python3 "$LIB/holdconn.py" "$S" 1 60 --wait-eof >"$T/idle.out" 2>&1; rc=$?
expect "idle client closed by the daemon" [ $rc -eq 0 ]
expect "idle client told why" grep -q "idle" "$T/idle.out"

# 7. a job is read once, at submit. The queue is paused (step 4): job A ends away from the origin,
# so the daemon plans job B again from there when it starts; B's file is rewritten after submit
# with a much longer job, which must not be what runs.
printf 'M 0 0 L 10 10\n' >"$T/a.txt"
printf 'M 10 10 L 15 10\n' >"$T/b.txt"
C submit "$T/a.txt" >"$T/sa.out" 2>&1
C submit "$T/b.txt" >"$T/sb.out" 2>&1
NB=$(sed -n 's/^OK job [0-9]* queued: .*: \([0-9]*\) segments$/\1/p' "$T/sb.out")
expect "job B queued with a count" [ -n "$NB" ]
python3 -c "print('M 0 0 ' + ' '.join('L %d %d' % (i % 50, (i * 7) % 50) for i in range(2000)))" \
    >"$T/b.txt"
C resume >/dev/null 2>&1
wait_until 120 sh -c "timeout 30 \"$CS\" status --socket \"$S\" | grep -q '^job 2 done'"
C status >"$T/st3.out" 2>&1
expect "job B done" grep -q "^job 2 done" "$T/st3.out"
NR=$(sed -n 's|^job 2 done: .*: \([0-9]*\)/\([0-9]*\) segments executed.*|\2|p' "$T/st3.out")
expect "job B ran as read at submit ($NB segments, not the rewritten file)" \
    [ -n "$NR" ] && [ "${NR:-0}" -le $((NB + 2)) ]

# 6. a FIFO, a character device and a directory are refused at submit; the daemon answers on.
mkfifo "$T/job.fifo"
C submit "$T/job.fifo" >"$T/fifo.out" 2>&1; rc=$?
expect "FIFO: refused (exit 1)" [ $rc -eq 1 ]
expect "FIFO: says so" grep -q "a FIFO, not a regular file" "$T/fifo.out"
C submit /dev/zero >"$T/zero.out" 2>&1; rc=$?
expect "/dev/zero: refused" [ $rc -eq 1 ]
expect "/dev/zero: says so" grep -q "a character device, not a regular file" "$T/zero.out"
C submit "$T/own" >"$T/dir.out" 2>&1; rc=$?
expect "directory: refused" [ $rc -eq 1 ]
expect "directory: says so" grep -q "a directory, not a regular file" "$T/dir.out"
C status >"$T/st2.out" 2>&1; rc=$?
expect "after the FIFO: status answers" [ $rc -eq 0 ]
# serve --max-input-mb 1: a 2 MB job file is refused at submit.
head -c 2000000 /dev/zero | tr '\0' ' ' >"$T/big.txt"
printf 'M 0 0 L 1 1\n' >>"$T/big.txt"
C submit "$T/big.txt" >"$T/big.out" 2>&1; rc=$?
expect "2 MB job over --max-input-mb 1: refused" [ $rc -eq 1 ]
expect "2 MB job: says so" grep -q "larger than the input limit of 1 MiB" "$T/big.out"

# 8. as root: a client of another user is refused by the daemon, and a socket served by another
# user is refused by the client (nothing sent: the /tmp squatting attack).
if [ "$(id -u)" = 0 ] && command -v setpriv >/dev/null; then
    NOB="setpriv --reuid=65534 --regid=65534 --clear-groups"
    chmod 711 "$T" "$T/priv"
    chmod 666 "$S"
    $NOB timeout -k 5 30 "$CS" status --socket "$S" >"$T/nob.out" 2>&1; rc=$?
    expect "another user's client: refused" [ $rc -ne 0 ]
    expect "another user's client: permission denied" grep -q "permission denied\|not run by this user" "$T/nob.out"
    chmod 700 "$T/priv"
    mkdir -m 777 "$T/squat"
    $NOB timeout -k 5 60 python3 "$LIB/fakeserver.py" "$T/squat/s.sock" "$T/squat/log" \
        >"$T/fake.out" 2>&1 &
    pids+=($!)
    wait_until 60 grep -qs ready "$T/fake.out"
    C0() { timeout -k 5 30 "$CS" "$@" --socket "$T/squat/s.sock"; }
    C0 submit "$T/a.txt" >"$T/sq.out" 2>&1; rc=$?
    expect "squatted socket: client refuses (exit 4)" [ $rc -eq 4 ]
    expect "squatted socket: says why" grep -q "not run by this user or root" "$T/sq.out"
    expect "squatted socket: nothing sent" [ ! -s "$T/squat/log" ]
    chmod 700 "$T"
fi

# 9. the daemon stops on SIGTERM and removes its socket.
kill -TERM $DPID
wait_until 60 gone $DPID
expect "serve stopped" gone $DPID
expect "socket removed" [ ! -e "$S" ]
finish
