#!/usr/bin/env bash
# Machine control on the ATmega328p image (build/fw/avr/curvestep.elf) in simavr. The harness
# (tests/fw/avr_harness.c) presses the Uno's switch pins (active low: Grbl's wiring) at STEP/DIR
# pin positions it counts itself, and reads the spindle's Timer2 registers. 80 steps/mm
# (firmware/ports/avr/machine.ini); the switches, in pin steps: x's (D9) pressed at x <= -400
# (-5 mm) and at x >= 4000 (50 mm), z's (D12) at z >= 160 (2 mm), the probe (A5) at z <= -240
# (-3 mm). Expected values from those numbers and the job, never from the image's output:
#  1. a job streamed from the origin that runs x to 60 mm at y = 5 mm crosses the x switch at
#     pin x 4000: the steps stop there (the pins end at 4000, or one step on: the step already
#     computed when the pin changed), the host reports ALARM:1 with the x bits (0x011: one pin
#     for both ends) at the pins' position, and exits 7; the same job again is refused (exit 7),
#     until `curvestep unlock`;
#  2. `curvestep home` (order zx, pull-off 1 mm, tests/data/ctl-homing.ini): the pins end at
#     x -400 + 80 = -320 and z 160 - 80 = 80, the device reads x_pos -99 mm and z_pos 0;
#  3. `curvestep probe` down to z -10 mm: contact on the pin step z -240, so the device's z is
#     (-240 - 80) / 80 = -4 mm within one step;
#  4. `curvestep spindle S` / `--ccw S` / `--off`: Timer2 in fast PWM on OC2A (TCCR2A 0x83, clock
#     / 8: 7.8 kHz) with (OCR2A + 1) / 256 within 1/512 of S / s_max, enable (A3) on, direction
#     (A4) low for M3 and high for M4; all off after --off; laser mode at power 800, full at 20
#     mm/s, during a 10 mm/s jog: 800 x 10 / 20 = 400 of s_max, dark when the jog ends;
#  5. the e-stop (A0) pressed by the harness: an alarm that `curvestep unlock` cannot clear.
# Every process is bounded by `timeout`. Prints "cli: N passed, M failed".
set -u
B=${CS_BUILD:-build}
CS=$B/curvestep
FW=${FW_AVR_DIR:-${B%/asan}/fw/avr} # the images are built once, outside the variants
H=$FW/avr_harness
ELF=$FW/curvestep.elf
. "$(dirname "${BASH_SOURCE[0]}")/../cli/lib/common.sh"
SPM=80
XMIN=-400 XMAX=4000 ZMAX=160 PZ=-240 PULL=80 # pin steps; PULL: the 1 mm pull-off
S_MAX=1000
MC=$T/m.ini
{
    cat firmware/ports/avr/machine.ini tests/data/ctl-homing.ini
    printf '[spindle]\ns_max = %s\n' "$S_MAX"
} >"$MC"
near() { awk -v a="$1" -v b="$2" -v t="$3" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d <= t + 1e-9) }'; }
mm() { awk -v s="$1" -v o="${2:-0}" -v k="$SPM" 'BEGIN { printf "%.4f", (s - o) / k }'; }

for f in "$H" "$ELF" "$CS"; do
    if [ ! -x "$f" ] && [ ! -f "$f" ]; then
        ko "missing $f (make firmware)"
        echo "cli: $pass passed, $fail failed"
        exit 1
    fi
done

start_harness() { # start_harness OUT ARGS...: the image on a pty; sets HPID and PTY
    local out=$1
    shift
    timeout -k 5 120 "$H" --pty --idle-exit 0 --timeout 110 "$@" "$ELF" >"$out" 2>"$out.err" &
    HPID=$!
    pids+=("$HPID")
    wait_until 60 grep -q '^/dev/pts/' "$out"
    PTY=$(head -n1 "$out")
}
stop_harness() {
    kill -TERM "$HPID" 2>/dev/null
    wait_until 60 gone "$HPID"
}
ctl() { c=$1; shift; timeout -k 5 120 "$CS" "$c" --port "$PTY" --machine "$MC" "$@"; }

start_harness "$T/h.out" --switch-min x=$XMIN --switch-max x=$XMAX --switch-max z=$ZMAX \
    --probe-z $PZ
expect "harness: pty" [ -c "$PTY" ]

# 1. a hard limit mid-job
printf 'G21 G90\nG1 X10 F3000\nG1 Y5\nG1 X60\nG1 X0\n' >"$T/trip.nc"
YT=$((5 * SPM))
timeout -k 5 60 "$CS" stream --line-rate 115200 --port "$PTY" --machine "$MC" "$T/trip.nc" \
    >"$T/trip.out" 2>"$T/trip.err"
rc=$?
expect "trip: stream exit 7 (got $rc)" [ $rc -eq 7 ]
expect "trip: the device stopped the job" grep -q 'device reported an error' "$T/trip.out"
ctl jog --feed 20 -- 0 0 0 >"$T/refused.out" 2>&1
rc=$?
expect "alarm: a jog is refused (exit 7, got $rc)" [ $rc -eq 7 ]
expect "alarm: refused for the state" grep -q 'refused message 1: operation not allowed' \
    "$T/refused.out"
timeout -k 5 60 "$CS" stream --line-rate 115200 --port "$PTY" --machine "$MC" "$T/trip.nc" \
    >"$T/again.out" 2>"$T/again.err"
rc=$?
expect "alarm: the job again is refused (exit 7, got $rc)" [ $rc -eq 7 ]
ctl unlock >"$T/unlock.out" 2>&1
rc=$?
expect "unlock: exit 0 (got $rc)" [ $rc -eq 0 ]
read -r ux uy uz < <(sed -n 's/^unlock: machine position \(.*\) mm$/\1/p' "$T/unlock.out")
expect "alarm: stopped on the switch, x $(mm $XMAX) mm within a step (got ${ux:-?})" \
    near "${ux:-x}" "$(mm $XMAX)" "$(mm 1)"
expect "alarm: y $(mm $YT) mm (got ${uy:-?})" near "${uy:-x}" "$(mm $YT)" 0.00001
# off the switch (its pin serves both ends: homing x would find it pressed)
ctl jog --feed 50 -- 40 5 0 >"$T/off.out" 2>&1
rc=$?
expect "after unlock: a jog runs (exit 0, got $rc)" [ $rc -eq 0 ]

# 2. homing
ctl home >"$T/home.out" 2>&1
rc=$?
expect "home: exit 0 (got $rc)" [ $rc -eq 0 ]
expect "home: position -99, $(mm $YT), 0 mm (y not homed)" \
    grep -q "^home: machine position -99.0000 $(mm $YT) 0.0000 mm$" "$T/home.out"
OX=$((XMIN + PULL + 99 * SPM)) OZ=$((ZMAX - PULL)) # pins = device + offset, steps (x_pos -99)

# 3. probing
ctl probe --feed 5 -- -99 $(mm $YT) -10 >"$T/probe.out" 2>&1
rc=$?
expect "probe: exit 0 (got $rc)" [ $rc -eq 0 ]
pz=$(grep '^probe: contact at' "$T/probe.out" | awk '{ print $6 }')
expect "probe: contact at z $(mm $PZ $OZ) mm within a step (got ${pz:-?})" \
    near "${pz:-x}" "$(mm $PZ $OZ)" "$(mm 1)"

# a jog into the x switch: ALARM:1 with the switch's bits, stopped on it; unlock
JX=-40
ctl jog --feed 50 -- $JX $(mm $YT) $(mm $PZ $OZ) >"$T/hl.out" 2>&1
rc=$?
expect "jog trip: exit 7 (got $rc)" [ $rc -eq 7 ]
# the x switch (0x011: its pin for both ends) and the probe, still touching (0x100)
expect "jog trip: ALARM:1 with the x switch and the probe (0x111)" \
    grep -q '^jog: ALARM:1 (hard limit.*inputs 0x111' "$T/hl.out"
hx=$(grep '^jog: ALARM:1' "$T/hl.out" | awk '{ print $13 }')
expect "jog trip: stopped at x $(mm $XMAX $OX) mm within a step (got ${hx:-?})" \
    near "${hx:-x}" "$(mm $XMAX $OX)" "$(mm 1)"
ctl unlock >"$T/unlock2.out" 2>&1
rc=$?
expect "unlock again: exit 0 (got $rc)" [ $rc -eq 0 ]

# 4. spindle: M3 S600, M4 S250, M5
ctl spindle 600 >"$T/sp1.out" 2>&1
rc1=$?
ctl spindle --ccw 250 >"$T/sp2.out" 2>&1
rc2=$?
ctl spindle --off >"$T/sp3.out" 2>&1
rc3=$?
expect "spindle: three settings, exit 0 ($rc1 $rc2 $rc3)" [ $rc1 -eq 0 -a $rc2 -eq 0 -a $rc3 -eq 0 ]
# laser mode: power LP, full at LF mm/s; a jog at LV mm/s (x off the switch, LD mm) runs at
# LP x LV / LF of s_max (the device's jog is at constant speed); then dark, then M5
LP=800 LF=20 LV=10 LD=10
ctl spindle --laser --feed $LF $LP >"$T/sp4.out" 2>&1
rc4=$?
ctl jog --feed $LV -- "$(awk -v h="$hx" -v d=$LD 'BEGIN { printf "%.4f", h - d }')" \
    "$(mm $YT)" "$(mm $PZ $OZ)" >"$T/lj.out" 2>&1
rc5=$?
ctl spindle --off >"$T/sp5.out" 2>&1
rc6=$?
expect "laser: set, jog, off: exit 0 ($rc4 $rc5 $rc6)" [ $rc4 -eq 0 -a $rc5 -eq 0 -a $rc6 -eq 0 ]
stop_harness
expect "harness: result ok" grep -q '^result: ok$' "$T/h.out"
expect "trips: x pressed at x $XMAX twice, the last at y $YT z $PZ" \
    grep -q "^switch: PB1 limit x >= $XMAX: 2 presses, last at x=$XMAX y=$YT z=$PZ$" "$T/h.out"
expect "home: x switch pressed twice (seek, latch)" \
    grep -q "^switch: PB1 limit x <= $XMIN: 2 presses" "$T/h.out"
expect "home: z switch pressed twice (seek, latch)" \
    grep -q "^switch: PB4 limit z >= $ZMAX: 2 presses" "$T/h.out"
expect "probe: one contact at z $PZ" grep -q "^switch: PC5 probe z <= $PZ: 1 presses, last at .* z=$PZ$" \
    "$T/h.out"
# the pins at the end: LD mm back from the x switch (where it stopped: one step at most beyond),
# at the probe's contact
px=$(sed -n 's/^position: x=\(-\?[0-9]*\) .*/\1/p' "$T/h.out")
expect "pins: x $XMAX - $LD mm within a step (got ${px:-?})" near "${px:-x}" $((XMAX - LD * SPM)) 1
expect "pins: y $YT, z $PZ" grep -q "^position: x=.* y=$YT z=$PZ$" "$T/h.out"
pwm_ok() { # pwm_ok N S EN DIR [REL]: setting N is fast PWM at S / s_max (within 1/512, and REL
    # of it), enable EN, direction DIR
    local l
    l=$(grep "^pwm: $1: " "$T/h.out")
    [ -n "$l" ] || return 1
    local a b o en dir
    a=$(sed -n 's/.*TCCR2A=0x\([0-9a-f]*\).*/\1/p' <<<"$l")
    b=$(sed -n 's/.*TCCR2B=0x\([0-9a-f]*\).*/\1/p' <<<"$l")
    o=$(sed -n 's/.*OCR2A=\([0-9]*\).*/\1/p' <<<"$l")
    en=$(sed -n 's/.* enable=\([01]\).*/\1/p' <<<"$l")
    dir=$(sed -n 's/.* dir=\([01]\).*/\1/p' <<<"$l")
    [ "$a" = 83 ] && [ $((16#$b & 7)) -eq 2 ] && [ "$en" = "$3" ] && [ "$dir" = "$4" ] &&
        awk -v o="$o" -v s="$2" -v m="$S_MAX" -v r="${5:-0}" \
            'BEGIN { d = (o + 1) / 256 - s / m; if (d < 0) d = -d; exit !(d <= 1 / 512 + r * s / m) }'
}
expect "pwm: M3 S600 = fast PWM on OC2A, duty 600/$S_MAX, enable, cw" pwm_ok 0 600 1 0
expect "pwm: M4 S250 = duty 250/$S_MAX, enable, ccw" pwm_ok 1 250 1 1
expect "pwm: M5 = OC2A off, enable and direction low" \
    grep -qE '^pwm: 2: TCCR2A=0x00 TCCR2B=0x00 OCR2A=[0-9]+ enable=0 dir=0 off$' "$T/h.out"
# the laser's jog: fast PWM at LP x LV / LF (within 1/512, and 1 % for the speed of 5 ms
# segments of whole steps and ticks), enable on, clockwise, first; then other segments' speeds:
# LV x SPM x 5 ms = 4 steps a segment, and a segment one step short (the rounding that keeps the
# line's total exact) runs at 3/4 of it, so every setting while it runs lies between LP x (3/4)
# LV / LF and LP x LV / LF; then, the ring run dry, dark but enabled; M5: all off, the last
expect "pwm: laser at $LP x $LV / $LF of $S_MAX as the jog starts" \
    pwm_ok 3 "$(awk -v p=$LP -v v=$LV -v f=$LF 'BEGIN { print p * v / f }')" 1 0 0.01
awk -v p=$LP -v v=$LV -v f=$LF -v m=$S_MAX '
    /^pwm: / { n = $2 + 0 }
    /^pwm: / && n >= 3 && / duty / && !dark {
        split($NF, q, "/"); d = q[1] / 256; hi = p * v / f / m; lo = hi * 3 / 4
        if (d < lo - 1 / 512 - hi / 100 || d > hi + 1 / 512 + hi / 100) bad++
        if (/enable=1 dir=0/) on++; else bad++
    }
    /^pwm: / && n >= 3 && / off$/ && !dark { dark = n; if ($0 !~ /enable=1 dir=0/) bad++ }
    /^pwm: / { last = $0 }
    END { exit !(on >= 1 && !bad && dark > 3 && last ~ /enable=0 dir=0 off$/ &&
                 last ~ ("^pwm: " dark + 1 ":")) }' "$T/h.out"
expect "pwm: laser power follows the segments' speed, then dark, then M5 (all off)" [ $? -eq 0 ]

# 5. the e-stop, pressed 0.3 s after boot: an alarm unlock cannot clear
start_harness "$T/e.out" --estop-at 0.3
wait_until 60 grep -q '^estop: pressed at 0.300 s$' "$T/e.out" # printed as it happens
ctl unlock >"$T/eu.out" 2>&1
rc=$?
expect "e-stop: unlock refused (exit 7, got $rc)" [ $rc -eq 7 ]
stop_harness
expect "e-stop: pressed" grep -q '^estop: pressed at 0.300 s$' "$T/e.out"
expect "e-stop: harness ok" grep -q '^result: ok$' "$T/e.out"
finish
