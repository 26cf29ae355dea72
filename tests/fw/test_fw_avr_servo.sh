#!/usr/bin/env bash
# The ATmega328p image drives the pen servo (firmware/ports/avr/port_avr.c: Timer1 compare B on
# OC1B = PB2). A small servo-pen drawing (three strokes) is planned and streamed to the image in
# simavr (tests/fw/avr_harness.c), which watches PB2 cycle by cycle: every rise-to-rise period
# must be 20 ms (320000 cycles at 16 MHz, exact: the hardware switches the pin), and the pulse
# widths, in the order the pin made them, must be the plan's "pen US" lines with repeats merged.
# The steps per axis must still be the plan's. The pin is read as the data sheet defines it from
# the compare-B matches and the COM1B bits (avr_harness.c, on_servo: simavr's own OC1B model is
# wrong in normal mode). Prints "cli: N passed, M failed".
set -u
B=${CS_BUILD:-build}
CS=$B/curvestep
FW=${FW_AVR_DIR:-${B%/asan}/fw/avr}
H=$FW/avr_harness
ELF=$FW/curvestep.elf
. "$(dirname "${BASH_SOURCE[0]}")/../cli/lib/common.sh"

for f in "$H" "$ELF" "$CS"; do
    if [ ! -f "$f" ]; then
        ko "missing $f (make firmware)"
        echo "cli: $pass passed, $fail failed"
        exit 1
    fi
done
# the image's machine with a servo pen (widths chosen apart from servo-a4.ini's, settle 60 ms:
# three periods at each setting at least)
{ cat firmware/ports/avr/machine.ini
  printf '\n[pen]\nmode = servo\nup_us = 2000\ndown_us = 1100\nsettle_ms = 60\n'; } >"$T/m.ini"
cat >"$T/job.svg" <<'SVG'
<svg xmlns="http://www.w3.org/2000/svg" width="30mm" height="20mm" viewBox="0 0 30 20">
  <path d="M 2 2 L 8 2 L 8 6" fill="none" stroke="black"/>
  <path d="M 20 10 L 25 12" fill="none" stroke="black"/>
  <circle cx="10" cy="14" r="3" fill="none" stroke="black"/>
</svg>
SVG
timeout -k 5 30 "$CS" plan --machine "$T/m.ini" --no-sort --no-merge "$T/job.svg" -o "$T/job.seg" 2>"$T/plan.err"
expect "plan: written" [ -s "$T/job.seg" ]
want=$(awk '/^pen / { if ($2 != last) printf " %d.0", $2; last = $2 }' "$T/job.seg")
npen=$(grep -c '^pen ' "$T/job.seg")
expect "plan: pen events ($npen)" [ "$npen" -ge 6 ]
read -r PX PY < <(awk '!/^#/ && !/^pen/ { for (i = 2; i <= 3; i++) t[i] += ($i < 0 ? -$i : $i) }
                       END { print t[2] + 0, t[3] + 0 }' "$T/job.seg")

timeout -k 5 310 "$H" --pty --idle-exit 0.5 --timeout 300 "$ELF" >"$T/h.out" 2>"$T/h.err" &
HPID=$!
pids+=("$HPID")
wait_pty "$T/h.out" 60
expect "harness printed a pty path" wait_until 60 test -c "$PTY"
timeout -k 5 300 "$CS" stream --line-rate 115200 --port "$PTY" --machine "$T/m.ini" --no-sort \
    --no-merge "$T/job.svg" >"$T/s.out" 2>"$T/s.err"
expect "stream: exit 0" [ $? -eq 0 ]
wait_until 60 gone "$HPID"
wait "$HPID"
expect "harness: exit 0" [ $? -eq 0 ]
line=$(grep '^servo: ' "$T/h.out")
echo "  $line"
# the job runs about 2.6 s: 130 periods; simavr's dropped matches (avr_harness.c, on_servo) are
# measured less the wrap, and must stay rare
np=$(sed -n 's/^servo: OC1B \([0-9]*\) periods.*/\1/p' "$T/h.out")
nd=$(sed -n 's/.* \([0-9]*\) dropped matches.*/\1/p' "$T/h.out")
expect "servo: 100+ periods ($np), under 1 in 10 dropped by simavr ($nd)" \
    [ "${np:-0}" -ge 100 -a "${nd:-999}" -le $((${np:-0} / 10)) ]
# 20 ms = 320000 cycles; the harness sees the match at the next instruction boundary: within one
# Timer1 count (8 cycles)
pmin=$(sed -n 's/.*rise to rise min \([0-9]*\) max.*/\1/p' "$T/h.out")
pmax=$(sed -n 's/.*rise to rise min [0-9]* max \([0-9]*\) cycles.*/\1/p' "$T/h.out")
expect "servo: every period 20 ms ($pmin..$pmax cycles)" \
    [ "${pmin:-0}" -ge 319992 -a "${pmax:-0}" -le 320008 ]
expect "servo: widths in turn =$want" [ "${line#*widths (us):}" = "$want" ]
expect "steps x = plan" grep -qE "^steps: x=$PX y=$PY " "$T/h.out"
finish
