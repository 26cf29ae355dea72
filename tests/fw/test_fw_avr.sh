#!/usr/bin/env bash
# The ATmega328p image end to end: the firmware (build/fw/avr/curvestep.elf) runs in simavr under
# tests/fw/avr_harness.c, which joins its USART to a pseudo-terminal and watches its STEP/DIR
# pins cycle by cycle; `curvestep stream` sends a real job to it with the image's machine file.
# The step counts per axis must equal the plan's (`curvestep plan`, summed independently here),
# the final position the simulator's (`curvestep-sim --replay` of the same plan), every STEP
# pulse must last the configured pulse_us and every DIR change come at least the configured
# set-up before the next STEP of its axis. Ctrl-C mid-job holds and aborts the image cleanly;
# curves mode is refused (the 2 KB image takes segments only). Then the harness itself: a pulse
# shorter than asked is reported as a violation, a silent image ends at the wall timeout. Every
# process is bounded by `timeout`. Prints "cli: N passed, M failed".
set -u
B=${CS_BUILD:-build}
CS=$B/curvestep
SIM=$B/curvestep-sim
FW=${FW_AVR_DIR:-${B%/asan}/fw/avr} # the images are built once, outside the variants
H=$FW/avr_harness
ELF=$FW/curvestep.elf
INI=firmware/ports/avr/machine.ini
JOB=tests/fw/avr_job.nc
# what the port guarantees (firmware/ports/avr/port_avr.h) and the drivers need: the pulse is
# the machine file's pulse_us; DIR set-up 1 us covers common drivers (A4988 0.2 us, DRV8825
# 0.65 us)
PULSE_US=$(sed -n 's/^pulse_us *= *\([0-9.]*\).*/\1/p' "$INI" | sort -n | tail -n1)
SETUP_US=1
# the shared harness: T, pids (killed on exit), ok / ko / expect (tests/cli/lib/common.sh)
. "$(dirname "${BASH_SOURCE[0]}")/../cli/lib/common.sh"
field() { # field FILE KEY AXIS: the number after "AXIS=" on the line starting with "KEY:"
    sed -n "s/^$2:.* $3=\\(-\\?[0-9]*\\).*/\\1/p" "$1" | head -n1
}

for f in "$H" "$ELF" "$CS" "$SIM"; do
    if [ ! -x "$f" ] && [ ! -f "$f" ]; then
        ko "missing $f (make firmware)"
        echo "cli: $pass passed, $fail failed"
        exit 1
    fi
done

# 1. the reference: the plan's per-axis step totals, and the simulator's final position
timeout -k 5 30 "$CS" plan --machine "$INI" "$JOB" -o "$T/job.seg" 2>"$T/plan.err"
expect "plan: segments written" grep -q '^# curvestep segments tick_hz=31250 axes=3' "$T/job.seg"
read -r PX PY PZ < <(awk '!/^#/ { for (i = 2; i <= 4; i++) t[i] += ($i < 0 ? -$i : $i) }
                         END { print t[2] + 0, t[3] + 0, t[4] + 0 }' "$T/job.seg")
timeout -k 5 30 "$SIM" --replay "$T/job.seg" --machine "$INI" >"$T/replay.out" 2>&1
SX=$(sed -n 's/^final position: x=\(-\?[0-9]*\) steps.*/\1/p' "$T/replay.out")
SY=$(sed -n 's/^final position: .* y=\(-\?[0-9]*\) steps.*/\1/p' "$T/replay.out")
SZ=$(sed -n 's/^final position: .* z=\(-\?[0-9]*\) steps.*/\1/p' "$T/replay.out")
expect "replay: final position read" [ -n "$SX" -a -n "$SY" -a -n "$SZ" ]
expect "plan: every axis moves" [ "$PX" -gt 0 -a "$PY" -gt 0 -a "$PZ" -gt 0 ]

# 2. the image on a pty, the job streamed to it
# (the harness never runs ahead of the wall clock and falls behind it on a loaded machine: 6.3
# of 16 MHz at load 16, the 3.9 s job in 9.8 s; its wall limit and the host's are hang guards)
timeout -k 5 310 "$H" --pty --idle-exit 0.5 --timeout 300 --min-pulse-us "$PULSE_US" \
    --min-dir-setup-us "$SETUP_US" "$ELF" >"$T/h.out" 2>"$T/h.err" &
HPID=$!
pids+=("$HPID")
wait_pty "$T/h.out" 60
expect "harness printed a pty path" wait_until 60 test -c "$PTY"
# --line-rate: the pty moves bytes at memory speed, the AVR's USART at 115200 baud; time the
# link (and pace the writes) for the real line
timeout -k 5 300 "$CS" stream --line-rate 115200 --port "$PTY" --machine "$INI" "$JOB" \
    >"$T/s.out" 2>"$T/s.err"
rc=$?
expect "stream: exit 0" [ $rc -eq 0 ]
expect "stream: job executed" grep -q "^stream: $PTY: job executed$" "$T/s.out"
wait_until 60 gone "$HPID" # its idle exit: 0.5 s of its time, slower than ours under load
kill "$HPID" 2>/dev/null
wait "$HPID"
hrc=$?
expect "harness: exit 0" [ $hrc -eq 0 ]
expect "harness: stopped when idle" grep -q 'stopped: idle$' "$T/h.out"
expect "harness: result ok" grep -q '^result: ok$' "$T/h.out"
expect "steps x = plan" [ "$(field "$T/h.out" steps x)" = "$PX" ]
expect "steps y = plan" [ "$(field "$T/h.out" steps y)" = "$PY" ]
expect "steps z = plan" [ "$(field "$T/h.out" steps z)" = "$PZ" ]
expect "position x = simulator" [ "$(field "$T/h.out" position x)" = "$SX" ]
expect "position y = simulator" [ "$(field "$T/h.out" position y)" = "$SY" ]
expect "position z = simulator" [ "$(field "$T/h.out" position z)" = "$SZ" ]
# the widths, checked here again from the cycle counts (16 cycles a microsecond)
pc=$(sed -n 's/^pulse: min \([0-9]*\) cycles.*/\1/p' "$T/h.out")
lc=$(sed -n 's/^step-low: min \([0-9]*\) cycles.*/\1/p' "$T/h.out")
sc=$(sed -n 's/^dir-setup: min \([0-9]*\) cycles.*/\1/p' "$T/h.out")
expect "pulse width >= pulse_us" awk -v c="${pc:-0}" -v us="$PULSE_US" 'BEGIN { exit !(c >= us * 16) }'
expect "STEP low between pulses >= pulse_us" awk -v c="${lc:-0}" -v us="$PULSE_US" 'BEGIN { exit !(c >= us * 16) }'
expect "DIR set-up >= $SETUP_US us" awk -v c="${sc:-0}" -v us="$SETUP_US" 'BEGIN { exit !(c >= us * 16) }'
expect "DIR never changes during a pulse" grep -q '^dir-in-pulse: 0 ' "$T/h.out"
expect "no byte lost on the way out" grep -q ', 0 dropped$' "$T/h.out"
expect "step interrupt timed" grep -qE '^isr: vector 11 .*: [1-9][0-9]* calls' "$T/h.out"
# the stack never reached the static data: lowest SP above _end (the end of .data/.bss/.noinit)
heap=$(avr-nm "$ELF" 2>/dev/null | awk '$3 == "_end" { print $1 }')
sp=$(sed -n 's/^stack: lowest SP 0x\([0-9a-f]*\).*/\1/p' "$T/h.out")
above=0
[ -n "$heap" ] && [ -n "$sp" ] && [ $((16#$sp)) -gt $((16#$heap & 0xffff)) ] && above=1
expect "stack stays above the static RAM" [ $above -eq 1 ]

# 3. Ctrl-C mid-job: the host holds, then aborts (HOLD and ABORT on the 2 KB build); the image
#    stops stepping cleanly (no pulse or DIR violation while it stops) before the job's end
timeout -k 5 310 "$H" --pty --idle-exit 0.5 --timeout 300 --min-pulse-us "$PULSE_US" \
    --min-dir-setup-us "$SETUP_US" "$ELF" >"$T/i.out" 2>"$T/i.err" &
HPID=$!
pids+=("$HPID")
wait_pty "$T/i.out" 60
# (--foreground: timeout would otherwise pass the signal on twice, and a second Ctrl-C means
# "leave at once")
timeout --foreground -k 5 300 "$CS" stream --line-rate 115200 --port "$PTY" --machine "$INI" "$JOB" \
    >"$T/is.out" 2>"$T/is.err" &
spid=$!
pids+=("$spid")
# until the job is under way (the first progress line with work done)
wait_until 120 grep -qsE '^stream: [1-9][0-9]*/[0-9]+ segments executed' "$T/is.err"
kill -INT "$spid"
wait "$spid"
rc=$?
wait_until 60 gone "$HPID" # its idle exit: 0.5 s of its time, slower than ours under load
kill "$HPID" 2>/dev/null
wait "$HPID"
hrc=$?
expect "ctrl-c: exit 8" [ $rc -eq 8 ]
expect "ctrl-c: held, then aborted" grep -q 'interrupted: held, then aborted' "$T/is.out"
expect "ctrl-c: harness ok" [ $hrc -eq 0 ]
ix=$(field "$T/i.out" steps x)
expect "ctrl-c: the job stopped early" [ -n "$ix" -a "${ix:-0}" -lt "$PX" ]

# 4. the 2 KB image takes segments only: its HELLO says so and the host refuses curves (exit 4)
timeout -k 5 130 "$H" --pty --idle-exit 0.5 --timeout 120 "$ELF" >"$T/c.out" 2>/dev/null &
HPID=$!
pids+=("$HPID")
wait_pty "$T/c.out" 60
timeout -k 5 120 "$CS" stream --mode curves --quiet --line-rate 115200 --port "$PTY" --machine "$INI" \
    "$JOB" >"$T/cs.out" 2>&1
rc=$?
kill "$HPID" 2>/dev/null
wait "$HPID" 2>/dev/null
expect "curves: refused, exit 4" [ $rc -eq 4 ]
expect "curves: the device cannot take them" grep -q 'the device cannot take curves' "$T/cs.out"

# 5. the harness can fail: a pulse requirement above what the port gives is a violation (exit 1)
timeout -k 5 120 "$H" --fast --cycles 4e6 --min-pulse-us 1000 "$FW/bench.elf" >"$T/v.out" 2>/dev/null
rc=$?
expect "violation: exit 1" [ $rc -eq 1 ]
expect "violation: reported" grep -q '^pulse: .*: VIOLATION$' "$T/v.out"
# ... and a silent image (no host, nothing to do) ends at the wall timeout: exit 4
timeout -k 5 120 "$H" --timeout 1 "$ELF" >"$T/w.out" 2>/dev/null
rc=$?
expect "wall timeout: exit 4" [ $rc -eq 4 ]
expect "wall timeout: reported" grep -q 'stopped: wall timeout$' "$T/w.out"
"$H" --help >"$T/help.out"
expect "help: exit codes" grep -q '4 wall timeout' "$T/help.out"

if [ $fail -ne 0 ]; then
    echo "--- harness:"; cat "$T/h.out"; echo "--- stream:"; tail -n 5 "$T/s.out" "$T/s.err"
fi
echo "cli: $pass passed, $fail failed"
[ $fail -eq 0 ]
