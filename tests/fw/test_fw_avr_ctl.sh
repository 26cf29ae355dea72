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
#  5. the e-stop (A0) pressed by the harness: an alarm that `curvestep unlock` cannot clear;
#  6. a jog cancel (Ctrl-C: JOG_CANCEL, 0x85) mid-jog at JV mm/s: exit 8, stopped short of the
#     target, the host's position the pins', and the harness's step times show the feed-hold
#     ramp: the speed (over one 5 ms segment's steps) falls, and from where it drops below 90 %
#     to rest the axis runs 0.81 x v T / 2 (a linear ramp from v to 0 over T, T = 5/4 x the
#     slowest max_rate / max_accel of machine.ini: cs_hold.h), less half the speed window;
#  7. the pin map: the pen servo (OC1B, D10) runs while the y switch (A1) trips a job (ALARM,
#     the switch pressed at its position), and a second function on a pin is a build error
#     (port_avr.c's static assert, tried on a copy with the y switch moved onto the e-stop).
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
expect "harness: pty" wait_until 60 test -c "$PTY"

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

# 6. a jog cancelled mid-move: JV mm/s towards x 100 mm, Ctrl-C once the harness has written its
# first block of step times (4 KB: a few hundred steps, so the jog is at speed)
JV=20 JT=100
start_harness "$T/jc.out" --steps-csv "$T/jc.csv"
timeout -k 5 100 "$CS" jog --port "$PTY" --machine "$MC" --feed $JV -- $JT 0 0 >"$T/jc.jog" \
    2>"$T/jc.err" &
JPID=$!
expect "jog cancel: the jog is moving" wait_until 60 test -s "$T/jc.csv"
kill -INT "$(pgrep -P "$JPID" -x curvestep)" # one Ctrl-C: JOG_CANCEL, then wait for rest
wait "$JPID"
rc=$?
stop_harness
expect "jog cancel: exit 8 (got $rc)" [ $rc -eq 8 ]
expect "jog cancel: harness ok (pulses, DIR setup)" grep -q '^result: ok$' "$T/jc.out"
jx=$(sed -n 's/^jog: machine position \([-0-9.]*\) .*/\1/p' "$T/jc.jog")
cx=$(sed -n 's/^position: x=\(-\?[0-9]*\) .*/\1/p' "$T/jc.out")
expect "jog cancel: stopped short of x $JT mm (x ${jx:-?} mm)" \
    awk -v x="${jx:-x}" -v t=$JT 'BEGIN { exit !(x > 1 && x < t) }'
expect "jog cancel: the host's position is the pins' (${jx:-?} mm, ${cx:-?} steps)" \
    near "${jx:-x}" "$(mm "${cx:-0}")" 0.00001
# T from machine.ini (max over the axes of max_rate / max_accel, x 5/4), and the ramp in steps
RT=$(awk -F' *= *' '/^\[/ { ax = $0 } /^max_rate/ { r[ax] = $2 } /^max_accel/ { a[ax] = $2 }
    END { for (k in r) if (r[k] / a[k] > t) t = r[k] / a[k]; print t * 5 / 4 }' "$MC")
W=$(awk -v v=$JV -v k=$SPM 'BEGIN { print v * k * 0.005 }') # steps of one 5 ms segment
want=$(awk -v v=$JV -v k=$SPM -v t="$RT" -v w="$W" 'BEGIN { print 0.81 * v * k * t / 2 - w / 2 }')
# The speed at cruise over 4 segments (4 W steps): a step's ISR may start up to about 700
# cycles late (the harness's TIMER1 vector-to-reti max, when a UART interrupt is in the way;
# 10,000 cycles a step at 1600 steps/s), which over one 8-step window alone reads up to 1.8 %
# fast, over 32 steps under 0.5 % (a loaded run read 1616.6 over 8 steps, 1603.4 over 32).
read -r vmax run vend < <(awk -F, -v w="$W" -v v=$JV -v k=$SPM '
    $2 == 0 { t[++n] = $1 }
    END { for (i = 4 * w + 1; i <= n; i++) { s = 4 * w * 16e6 / (t[i] - t[i - 4 * w])
              if (s > m) m = s }
          for (i = w + 1; i <= n; i++) { s = w * 16e6 / (t[i] - t[i - w])
              if (!c && i > 3 * w && s < 0.9 * v * k) c = i }
          print m, (c ? n - c : -1), w * 16e6 / (t[n] - t[n - w]) }' "$T/jc.csv")
expect "jog cancel: at $JV mm/s before the cancel (${vmax:-?} steps/s, want $((JV * SPM)) within 1 %)" \
    near "${vmax:-0}" $((JV * SPM)) $((JV * SPM / 100))
expect "jog cancel: decelerated to under half speed at the last step (${vend:-?} steps/s)" \
    awk -v s="${vend:-1e9}" -v f=$((JV * SPM)) 'BEGIN { exit !(s < f / 2) }'
expect "jog cancel: ${run:-?} steps from 90 % of the speed to rest, want $want within 2 segments (T $RT s)" \
    near "${run:--99}" "$want" $((2 * W))

# 7. the pen servo on D10 and the y switch on A1 together: a servo-pen drawing whose pen-up
# travel runs y to 35 mm (the SVG's y is flipped) trips the y switch at 30 mm
YS=$((30 * SPM))
{ cat "$MC"; printf '\n[pen]\nmode = servo\nup_us = 2000\ndown_us = 1100\nsettle_ms = 60\n'; } \
    >"$T/pen.ini"
cat >"$T/y.svg" <<'SVG'
<svg xmlns="http://www.w3.org/2000/svg" width="20mm" height="40mm" viewBox="0 0 20 40">
  <path d="M 5 5 L 5 35" fill="none" stroke="black"/>
</svg>
SVG
start_harness "$T/y.out" --switch-max y=$YS
timeout -k 5 60 "$CS" stream --line-rate 115200 --port "$PTY" --machine "$T/pen.ini" --no-sort \
    "$T/y.svg" >"$T/y.stream" 2>&1
rc=$?
ctl unlock >"$T/yu.out" 2>&1
read -r _ uy _ < <(sed -n 's/^unlock: machine position \(.*\) mm$/\1/p' "$T/yu.out")
stop_harness
expect "pins: the y switch trips the servo job (exit 7, got $rc)" [ $rc -eq 7 ]
expect "pins: harness ok" grep -q '^result: ok$' "$T/y.out"
expect "pins: y switch A1 (PC1) pressed once at y $YS" \
    grep -q "^switch: PC1 limit y >= $YS: 1 presses, last at x=[0-9]* y=$YS z=0$" "$T/y.out"
expect "pins: stopped on the y switch, $(mm $YS) mm within a step (got ${uy:-?})" \
    near "${uy:-x}" "$(mm $YS)" "$(mm 1)"
np=$(sed -n 's/^servo: OC1B \([0-9]*\) periods.*/\1/p' "$T/y.out")
expect "pins: the servo's pulse train ran on OC1B meanwhile (${np:-0} periods, 3 at least)" \
    [ "${np:-0}" -ge 3 ]
if command -v avr-gcc >/dev/null; then
    P=firmware/ports/avr/port_avr.c
    AVRC=(avr-gcc -std=c99 -mmcu=atmega328p -DF_CPU=16000000UL -Ifirmware/app -Ifirmware/core
        -Ifirmware/ports -Ifirmware/ports/avr -fsyntax-only)
    sed 's/^#define LIM_Y_PIN .*/#define LIM_Y_PIN ((uint8_t)(1u << PC0))/' "$P" >"$T/clash.c"
    expect "pins: the port's map compiles" "${AVRC[@]}" "$P"
    expect "pins: y switch on the e-stop's pin is refused (static assert)" \
        eval '! "${AVRC[@]}" "$T/clash.c" 2>"$T/clash.err" && grep -q avr_pins_one_function_each "$T/clash.err"'
else
    ko "pins: avr-gcc missing (make firmware)"
fi
finish
