#!/usr/bin/env bash
# The Cortex-M3 image end to end: build/fw/cortex-m3/curvestep.elf runs in qemu-system-arm
# (-M lm3s6965evb, -icount for a fixed instruction rate), its UART0 on a pseudo-terminal, and
# `curvestep stream --port` sends a real job to it with the image's machine file. The image
# reports over semihosting (its position from the executor and from its STEP/DIR pins, the STEP
# pulses per axis, the steps in total) and ends qemu with SYS_EXIT_EXTENDED once the host has
# gone quiet. Checked against independent results:
#   segments mode: `curvestep plan` of the same job, replayed by `curvestep-sim --replay` (final
#     position, steps) and summed per axis here with awk (pulses per axis, messages);
#   curves mode (the device traces and plans): the simulator's device `curvestep-sim --pty` fed
#     the same stream (final position, steps in total);
#   one device application: the simulator's device runs the image's application (firmware/app)
#     on the POSIX port; fed the same segments it logs the same executed segments and the same
#     STEP edges, tick for tick on the executor's clock (cs_exlog: count and FNV-1a hash of each);
#   Ctrl-C: hold then abort reach the image, and it executed exactly what the host says;
#   feed hold (the core's cs_hold, run by the application): paused mid-job through
#     `curvestep serve`, held, resumed; the image executed every segment once (its log of the
#     segments as planned equals case 1's), counted one hold, and ended where the replay ends;
#   a machine file whose tick rate is not the image's is refused at the HELLO.
# Every process is bounded by `timeout` and killed on exit. Prints "cli: N passed, M failed".
set -u
B=${CS_BUILD:-build}
CS=$B/curvestep
SIM=$B/curvestep-sim
FW=${FW_M3_DIR:-${B%/asan}/fw/cortex-m3} # the images are built once, outside the variants
ELF=$FW/curvestep.elf
INI=firmware/ports/cortex-m3/machine.ini
JOB=tests/data/svg/resvg/M-L-Z-A.svg # lines, closepath and elliptical arcs, 132328 steps
FEED=400                             # mm/s: the job takes 4.4 s of machine time
# -icount shift=4: one instruction every 16 ns (62.5 MIPS, about the LM3S6965's 50 MHz core),
# whatever the host's speed; the image reports and exits 500 ms (its time) after the host left
QEMU=(qemu-system-arm -M lm3s6965evb -kernel "$ELF" -display none -monitor none -serial pty
    -icount shift=4
    -semihosting-config enable=on,target=native,arg=curvestep,arg=exit-idle=500)
# the shared harness: T, pids (killed on exit), ok / ko / expect (tests/cli/lib/common.sh)
. "$(dirname "${BASH_SOURCE[0]}")/../cli/lib/common.sh"
. "$(dirname "${BASH_SOURCE[0]}")/../cli/lib/daemon.sh"
# value NAME FILE SED-EXPR: the last match of a report line (for messages).
value() { sed -n "$2" "$1" | tail -n1; }

# start_fw NAME: qemu in the background (600 s at most: the hold case alone may wait 480 s on a loaded machine), PTY = the guest UART's pty.
start_fw() {
    local name=$1
    # qemu prints the pty on stdout, the semihosting console goes to stderr: one file
    timeout -k 5 600 "${QEMU[@]}" >"$T/$name.fw" 2>&1 &
    QPID=$!
    pids+=("$QPID")
    PTY=
    local end=$((SECONDS + 60))
    while [ $SECONDS -lt $end ]; do
        PTY=$(sed -n 's#^char device redirected to \(/dev/pts/[0-9]*\) .*#\1#p' "$T/$name.fw" 2>/dev/null)
        [ -n "$PTY" ] && break
        sleep 0.05
    done
}
# wait_fw: the exit status of the qemu started last. The image exits 500 ms (its time) after the
# host went quiet; one that has not within 60 s is killed (status 143: a failure, not a hang;
# generous: a loaded machine slows qemu down).
wait_fw() {
    local end=$((SECONDS + 60))
    while [ $SECONDS -lt $end ] && kill -0 "$QPID" 2>/dev/null; do sleep 0.05; done
    kill "$QPID" 2>/dev/null
    wait "$QPID"
    QRC=$?
}

if ! command -v qemu-system-arm >/dev/null; then
    echo "FAIL: qemu-system-arm missing (scripts/deps.sh installs it)"
    echo "cli: 0 passed, 1 failed"
    exit 1
fi
expect "image built" [ -f "$ELF" ]

# The curves-mode reference runs meanwhile: the simulator's device on its own pty, instant.
(
    timeout -k 5 240 "$SIM" --pty --instant --machine "$INI" >"$T/sim.out" 2>"$T/sim.err" &
    spid=$!
    spty=
    end=$((SECONDS + 60))
    while [ $SECONDS -lt $end ] && [ -z "$spty" ]; do spty=$(head -n1 "$T/sim.out" 2>/dev/null); sleep 0.05; done
    timeout -k 5 240 "$CS" stream --mode curves --machine "$INI" --feed $FEED --port "$spty" "$JOB" \
        >"$T/simcur.out" 2>&1
    kill "$spid" 2>/dev/null # SIGTERM: finishes what it holds, then reports
    wait "$spid"
) &
REFPID=$!
pids+=("$REFPID")
# The segments-mode twin: the simulator's device fed the plan the image gets in case 1.
(
    timeout -k 5 240 "$SIM" --pty --instant --machine "$INI" >"$T/simseg.out" 2>"$T/simseg.err" &
    spid=$!
    spty=
    end=$((SECONDS + 60))
    while [ $SECONDS -lt $end ] && [ -z "$spty" ]; do spty=$(head -n1 "$T/simseg.out" 2>/dev/null); sleep 0.05; done
    timeout -k 5 240 "$CS" stream --machine "$INI" --feed $FEED --port "$spty" "$JOB" >"$T/simseg.stream" 2>&1
    kill "$spid" 2>/dev/null
    wait "$spid"
) &
SEGPID=$!
pids+=("$SEGPID")

# 1. segments mode: the host plans, the image executes; everything equals the plan's replay.
"$CS" plan --machine "$INI" --feed $FEED "$JOB" -o "$T/job.seg" 2>/dev/null
"$SIM" --replay "$T/job.seg" --machine "$INI" >"$T/replay.out"
nseg=$(grep -vc '^#' "$T/job.seg")
read -r px py pz < <(awk '!/^#/ {x += $2 < 0 ? -$2 : $2; y += $3 < 0 ? -$3 : $3;
    z += $4 < 0 ? -$4 : $4} END {print x, y, z}' "$T/job.seg")
ref_pos=$(sed -n 's/^final position: x=\(-*[0-9]*\) steps .* y=\(-*[0-9]*\) steps .* z=\(-*[0-9]*\) steps .*/x=\1 y=\2 z=\3/p' "$T/replay.out")
ref_steps=$(sed -n 's/^replay: [0-9]* segments, \([0-9]*\) steps.*/\1/p' "$T/replay.out")
expect "reference: plan and replay ran" [ -n "$ref_pos" ] && [ -n "$ref_steps" ] && [ "$nseg" -gt 100 ]
start_fw seg
expect "qemu printed the UART's pty" wait_until 60 test -c "$PTY"
timeout -k 5 240 "$CS" stream --machine "$INI" --feed $FEED --line-rate 115200 --port "$PTY" "$JOB" \
    >"$T/seg.out" 2>"$T/seg.err"
rc=$?
wait_fw
expect "segments: stream exit 0" [ $rc -eq 0 ]
expect "segments: every segment executed" grep -q "^stream: $nseg of $nseg segments executed" "$T/seg.out"
expect "segments: image exit status 0 (semihosting)" [ $QRC -eq 0 ]
expect "segments: image executed every message" grep -q "^fw: executed $nseg messages, $nseg step segments, 0 curves, 0 errors" "$T/seg.fw"
expect "segments: executor position = replay" grep -q "^fw: position (executor): $ref_pos$" "$T/seg.fw"
expect "segments: STEP/DIR pins position = replay" grep -q "^fw: position (STEP/DIR pins): $ref_pos$" "$T/seg.fw"
expect "segments: STEP pulses per axis = the plan's" grep -q "^fw: step pulses: x=$px y=$py z=$pz$" "$T/seg.fw"
expect "segments: steps in total = replay" grep -q "^fw: steps total $ref_steps " "$T/seg.fw"
expect "segments: no UART byte lost" grep -q " 0 UART overruns$" "$T/seg.fw"
[ $fail -eq 0 ] || { echo "--- image report:"; tail -n 6 "$T/seg.fw"; tail -n 3 "$T/seg.out"; }
# 1b. the same application in the simulator: the same executed segments and step edges
wait "$SEGPID"
simlog=$(sed -n 's/^log: //p' "$T/simseg.out" | tail -n1)
fwlog=$(sed -n 's/^fw: log: //p' "$T/seg.fw" | tail -n1)
expect "one application: simulator logged $nseg segments" grep -q "^log: $nseg segments hash " "$T/simseg.out"
expect "one application: simulator = image, segments and step edges tick for tick" \
    [ -n "$simlog" ] && [ "$simlog" = "$fwlog" ]
echo "note: simulator log: ${simlog:-none}; image log: ${fwlog:-none}"

# 2. curves mode: the image traces and plans each cubic itself; the simulator's device, fed the
# same stream (run in the background during case 1), is the reference (same core, same machine).
wait "$REFPID"
sim_pos=$(sed -n 's/^final position: x=\(-*[0-9]*\) steps .* y=\(-*[0-9]*\) steps .* z=\(-*[0-9]*\) steps .*/x=\1 y=\2 z=\3/p' "$T/sim.out")
sim_steps=$(sed -n 's/^job time: .* simulated, \([0-9]*\) steps$/\1/p' "$T/sim.out")
ncur=$(sed -n 's/^device: .* \([0-9]*\) messages executed .*/\1/p' "$T/sim.out")
expect "curves reference: simulator ran" [ -n "$sim_pos" ] && [ -n "$sim_steps" ] && [ -n "$ncur" ]
start_fw cur
timeout -k 5 240 "$CS" stream --mode curves --machine "$INI" --feed $FEED --line-rate 115200 \
    --port "$PTY" "$JOB" >"$T/cur.out" 2>"$T/cur.err"
rc=$?
wait_fw
expect "curves: stream exit 0" [ $rc -eq 0 ]
expect "curves: image exit status 0" [ $QRC -eq 0 ]
expect "curves: image traced every curve" grep -q "^fw: executed $ncur messages, [0-9]* step segments, $ncur curves, 0 errors" "$T/cur.fw"
expect "curves: executor position = simulator" grep -q "^fw: position (executor): $sim_pos$" "$T/cur.fw"
expect "curves: STEP/DIR pins position = simulator" grep -q "^fw: position (STEP/DIR pins): $sim_pos$" "$T/cur.fw"
expect "curves: steps in total = simulator" grep -q "^fw: steps total $sim_steps " "$T/cur.fw"

# 3. Ctrl-C mid-job: HOLD then ABORT reach the image; the host's last executed is the image's.
start_fw int
timeout --foreground -k 5 300 "$CS" stream --machine "$INI" --feed $FEED --line-rate 115200 \
    --port "$PTY" "$JOB" >"$T/int.out" 2>"$T/int.err" &
spid=$!
pids+=("$spid")
# interrupt once the image has executed something (an event, not a guess of how long that takes
# on a loaded machine): the host's progress line names executed segments
wait_until 120 grep -q '^stream: [1-9][0-9]*/' "$T/int.err"
kill -INT "$spid"
wait "$spid"
rc=$?
wait_fw
k=$(value "$T/int.out" 's/.*last executed: \([0-9]*\)$/\1/p')
expect "ctrl-c: exit 8" [ $rc -eq 8 ]
expect "ctrl-c: image held and aborted" grep -q "^fw: executed [0-9]* messages, .* 1 holds, 1 aborts$" "$T/int.fw"
expect "ctrl-c: host and image agree on what ran" grep -q "^fw: executed ${k:-x} messages" "$T/int.fw"
expect "ctrl-c: stopped mid-job" [ "${k:-0}" -gt 0 ] && [ "${k:-0}" -lt "$nseg" ]

# 3b. feed hold and resume through the daemon: every segment once, the position exact.
S=$T/sock/cs.sock
N=$nseg
mkdir -p "$T/sock"
start_fw hold
dmn_start --port "$PTY" --machine "$INI" --line-rate 115200 # a UART, not a memory-speed pty
C submit --feed $FEED "$JOB" >"$T/hsub.out" 2>&1
expect "hold: submitted" grep -q "^OK job 1 queued: .*: $nseg segments$" "$T/hsub.out"
expect "hold: a quarter ran" wait_until 180 dmn_quarter
C pause >"$T/hp.out"
expect "hold: device held" grep -q "^OK paused (device held)" "$T/hp.out"
expect "hold: progress stands still" wait_until 60 dmn_still
C resume >/dev/null
expect "hold: job ended" wait_until 240 dmn_finished
C status >"$T/hst.out" 2>&1
expect "hold: every segment executed" grep -q "^job 1 done: .*: $nseg/$nseg segments executed" "$T/hst.out"
kill -TERM "$DPID"
wait "$DPID"
wait_fw
holdlog=$(sed -n 's/^fw: log: \([0-9]* segments hash [0-9]*\),.*/\1/p' "$T/hold.fw" | tail -n1)
expect "hold: image exit status 0" [ $QRC -eq 0 ]
expect "hold: one hold, no abort" grep -q "^fw: executed $nseg messages, $nseg step segments, .* 1 holds, 0 aborts$" "$T/hold.fw"
expect "hold: the same segments as without the hold, each once" \
    [ -n "$holdlog" ] && [ "$holdlog" = "$(echo "$fwlog" | sed 's/,.*//')" ]
# the ramps re-timed segments on the image: its executor's clock ran longer than case 1's
tick1=$(echo "$fwlog" | sed -n 's/.* at executor tick \([0-9]*\)$/\1/p')
tickh=$(sed -n 's/^fw: log: .* at executor tick \([0-9]*\)$/\1/p' "$T/hold.fw" | tail -n1)
expect "hold: the image ramped (executor clock ${tickh:-?} > ${tick1:-?} ticks)" \
    [ "${tickh:-0}" -gt "${tick1:-0}" ]
expect "hold: executor position = replay" grep -q "^fw: position (executor): $ref_pos$" "$T/hold.fw"
expect "hold: STEP/DIR pins position = replay" grep -q "^fw: position (STEP/DIR pins): $ref_pos$" "$T/hold.fw"

# 4. a machine file at another tick rate: the image's HELLO is refused (exit 4), nothing moves.
sed 's/^tick_hz = .*/tick_hz = 1000000/' "$INI" >"$T/fast.ini"
start_fw bad
timeout -k 5 120 "$CS" stream --machine "$T/fast.ini" --port "$PTY" "$JOB" >"$T/bad.out" 2>&1
rc=$?
kill "$QPID" 2>/dev/null
wait_fw
expect "hello: tick rate mismatch exit 4" [ $rc -eq 4 ]
expect "hello: reported" grep -q 'the device ticks at 100000 Hz' "$T/bad.out"

echo "cli: $pass passed, $fail failed"
[ $fail -eq 0 ]
