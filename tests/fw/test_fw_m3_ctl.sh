#!/usr/bin/env bash
# Machine control on the Cortex-M3 image under qemu (as tests/fw/test_fw_m3.sh runs it). qemu's
# board has no switch to press, so the image's command line places simulated ones
# (main_m3.c, port_m3_sim_switch) in STEP/DIR pin steps, 80 steps/mm: x min at -400 (-5 mm),
# x max at 4000 (50 mm), z max at 160 (2 mm), the probe surface at z -240 (-3 mm). Expected
# values by hand, as in tests/cli/test_control.sh:
#  - `curvestep home` (order zx, pull-off 1 mm): the pins end at x -400 + 80 = -320 and
#    z 160 - 80 = 80 steps; the device reads x -99 mm, z 0 (x_pos, z_pos): device = pins - (95
#    mm, 0, 1 mm) from then on;
#  - `curvestep probe` down to z = -10: contact at pin z -240, device z -4 mm;
#  - a jog into the x max switch: ALARM:1 with the x max bit (0x010), stopped at pin x 4000
#    (device -45 mm); `unlock`; a jog back to -60 mm (pins 2800);
#  - `curvestep spindle --ccw 250`, then `curvestep grbl` on the same port: M4 S250 and the
#    spindle override +10 % (0x9A, the OVERRIDE message) during a 5 mm move (pins x 3200):
#    the port's PWM last set to duty 275/1000, mode 2 (the alarm and `unlock` set it off).
# Every process is bounded by `timeout`. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/m3.sh" x_min=-400 x_max=4000 z_max=160 probe_z=-240
MC=$T/m3.ini
cat firmware/ports/cortex-m3/machine.ini tests/data/ctl-homing.ini >"$MC"
near() { awk -v a="$1" -v b="$2" -v t="$3" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d <= t) }'; }

timeout -k 5 400 "${QEMU[@]}" >"$T/fw.out" 2>&1 &
QPID=$!
pids+=("$QPID")
wait_until 60 grep -q '^char device redirected to /dev/pts/' "$T/fw.out"
FPTY=$(sed -n 's#^char device redirected to \(/dev/pts/[0-9]*\) .*#\1#p' "$T/fw.out")
expect "qemu: pty" [ -n "$FPTY" ]
ctl() { c=$1; shift; timeout -k 5 180 "$CS" "$c" --port "$FPTY" --machine "$MC" "$@"; }

ctl home >"$T/home.out" 2>&1; rc=$?
expect "home: exit 0 (got $rc)" [ $rc -eq 0 ]
expect "home: final position" grep -q '^home: machine position -99.0000 0.0000 0.0000 mm$' \
    "$T/home.out"
ctl probe --feed 2 -- -99 0 -10 >"$T/probe.out" 2>&1; rc=$?
expect "probe: exit 0 (got $rc)" [ $rc -eq 0 ]
pz=$(grep '^probe: contact at' "$T/probe.out" | awk '{ print $6 }')
expect "probe: contact at z = -4 mm within a step (got $pz)" near "${pz:-x}" -4 0.0125
ctl jog --feed 50 -- -40 0 -1 >"$T/hl.out" 2>&1; rc=$?
expect "hard limit: exit 7 (got $rc)" [ $rc -eq 7 ]
expect "hard limit: ALARM:1 with the x max switch" grep -q '^jog: ALARM:1 (hard limit.*inputs 0x010' \
    "$T/hl.out"
hx=$(grep '^jog: ALARM:1' "$T/hl.out" | awk '{ print $13 }')
expect "hard limit: stopped at x = -45 mm (got $hx)" near "${hx:-x}" -45 0.0001
ctl unlock >"$T/u.out" 2>&1; rc=$?
expect "unlock: exit 0 (got $rc)" [ $rc -eq 0 ]
ctl jog --feed 50 -- -60 0 -1 >"$T/back.out" 2>&1; rc=$?
expect "jog back: exit 0 (got $rc)" [ $rc -eq 0 ]
ctl spindle --ccw 250 >"$T/sp.out" 2>&1; rc=$?
expect "spindle M4 S250: exit 0 (got $rc)" [ $rc -eq 0 ]
# the OVERRIDE message on the image: `curvestep grbl` on the same port, M4 S250 and a 5 mm move
# at 100 mm/min (3 s), Grbl's spindle +10 % (0x9A) during it: the image sets 250 x 1.1 = 275
timeout -k 5 120 "$CS" grbl --port "$FPTY" --machine "$MC" >"$T/g.grbl" 2>"$T/g.err" &
GP=$!
pids+=("$GP")
wait_pty "$T/g.grbl" 60
gc() { timeout -k 5 90 python3 tests/support/grbl_client.py "$PTY" "$@"; }
printf '%s\n' 'M4 S250' 'G91 G1 X5 F100' >"$T/g.nc"
gc override "$T/g.nc" 9a -59 100 >"$T/g1.out" 2>&1 # the byte once x >= -59 mm (the move: -60 to -55)
kill -TERM "$GP" 2>/dev/null
wait "$GP" 2>/dev/null
expect "grbl: Ov:100,100,110 after 0x9A" grep -q '^ov: 100,100,110$' "$T/g1.out"
expect "grbl: idle 5 mm further" grep -q '^final: <Idle|MPos:-55.000,0.000,-1.000|' "$T/g1.out"
kill -TERM "$QPID" 2>/dev/null
wait_until 60 gone "$QPID"
expect "image: control line" grep -q '^fw: control: 2 axes homed, [1-9] alarms (now 0), 1 probe cycles' \
    "$T/fw.out"
expect "image: spindle last set to duty 275/1000 (S250 +10 %), counter-clockwise" \
    grep -qE '; spindle: [0-9]+ settings, last duty 275 mode 2$' "$T/fw.out"
expect "image: STEP/DIR pins at (3200, 0, 0) (the jog back, then 5 mm x 80)" \
    grep -q '^fw: position (STEP/DIR pins): x=3200 y=0 z=0$' "$T/fw.out"
finish
