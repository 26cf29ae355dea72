#!/usr/bin/env bash
# Command-line test of the device's machine control (issue 21; docs/controller.md) against
# `curvestep-sim --pty`, whose switches and probe surface come from the machine file written
# here: x min switch at -5 mm, x max at 50 mm, z max at 2 mm, probe surface at z = -3 mm, all in
# the simulator's physical coordinates (0 at start). Expected values by hand from those:
#  - `curvestep home` (order zx, pull-off 1 mm): z ends 1 mm below its switch (physical 1 mm),
#    x 1 mm above its switch (physical -4 mm); the device reads z 0 and x -99 (x_pos, z_pos).
#    Device = physical - (95, 0, 1) mm from then on.
#  - `curvestep probe` down to z = -10: contact where the physical z reaches -3 mm, i.e. device
#    z = -4 mm, within one step (1/80 mm); G38.3 (--no-error) above the surface: no contact,
#    exit 0; G38.2 there: ALARM:5, exit 7.
#  - a jog into the x max switch (device -45 mm): ALARM:1 naming the switch (inputs 0x010),
#    stopped exactly there; the next jog refused (exit 7); `unlock` (exit 0); a jog back runs;
#    `curvestep stream` into the same switch: exit 7 and a located ALARM line.
#  - the e-stop (SIGUSR1 to the simulator): unlock refused while pressed, accepted after
#    SIGUSR2.
#  - laser mode (S 800, full power from 20 mm/s) during a 40 mm/s jog: the largest duty the
#    device set is 800/1000, the ramps set lower ones, the picture draws the power.
#  - a jog interrupted with Ctrl-C (a real-time simulator): JOG_CANCEL, the device decelerates
#    (a hold) and drops the jog without an abort; exit 8, the position it prints is the
#    simulator's final position, between start and target;
#  - the simulator's picture rings each event: 2 axes homed (x at physical -4 mm), 3 probe
#    cycles, the alarms.
# Every process is bounded by `timeout`. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"

MC=$T/m.ini
cat tests/data/ctl-switches.ini tests/data/ctl-homing.ini >"$MC"

# near A B TOL: |A - B| <= TOL
near() { awk -v a="$1" -v b="$2" -v t="$3" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d <= t) }'; }
# field N of the last line of FILE matching RE
last_field() { grep -E "$2" "$1" | tail -1 | awk -v n="$3" '{ print $n }'; }

timeout -k 5 300 "$SIM" --pty --instant --machine "$MC" --svg "$T/ctl.svg" >"$T/dev.sim" \
    2>"$T/dev.simerr" &
pids+=($!)
SIMPID=$!
wait_pty "$T/dev.sim" 60
expect "sim printed a pty path" wait_until 60 test -c "$PTY"
ctl() { c=$1; shift; timeout -k 5 120 "$CS" "$c" --port "$PTY" --machine "$MC" "$@"; }

# 1. homing
ctl home >"$T/home.out" 2>"$T/home.err"; rc=$?
expect "home: exit 0 (got $rc)" [ $rc -eq 0 ]
expect "home: z first" grep -q '^home: z homed; machine position .* 0.0000 mm$' "$T/home.out"
expect "home: then x at x_pos" grep -q '^home: x homed; machine position -99.0000 ' "$T/home.out"
expect "home: final position" grep -q '^home: machine position -99.0000 0.0000 0.0000 mm$' \
    "$T/home.out"

# 2. probing
ctl probe --feed 2 -- -99 0 -10 >"$T/probe.out" 2>&1; rc=$?
expect "probe: exit 0 (got $rc)" [ $rc -eq 0 ]
pz=$(last_field "$T/probe.out" '^probe: contact at' 6)
expect "probe: contact at z = -4 mm within a step (got $pz)" near "$pz" -4 0.0125
ctl jog --feed 10 -- -99 0 -1 >/dev/null 2>&1
ctl probe --feed 5 --no-error -- -99 0 -2 >"$T/p3.out" 2>&1; rc=$?
expect "G38.3 without contact: exit 0 (got $rc)" [ $rc -eq 0 ]
expect "G38.3: says no contact" grep -q '^probe: no contact; ended at -99.0000 0.0000 -2.0000 mm$' \
    "$T/p3.out"
ctl probe --feed 5 -- -99 0 -1.5 >"$T/p2.out" 2>&1; rc=$?
expect "G38.2 without contact: exit 7 (got $rc)" [ $rc -eq 7 ]
expect "G38.2: ALARM:5" grep -q '^probe: ALARM:5 ' "$T/p2.out"
ctl unlock >"$T/u0.out" 2>&1; rc=$?
expect "unlock after the probe alarm: exit 0 (got $rc)" [ $rc -eq 0 ]

# 3. hard limit
ctl jog --feed 50 -- -40 0 -1 >"$T/hl.out" 2>&1; rc=$?
expect "jog into the switch: exit 7 (got $rc)" [ $rc -eq 7 ]
expect "hard limit: ALARM:1 with the x max switch" grep -q '^jog: ALARM:1 (hard limit.*inputs 0x010' \
    "$T/hl.out"
hx=$(last_field "$T/hl.out" '^jog: ALARM:1' 13)
expect "hard limit: stopped at x = -45 mm (got $hx)" near "$hx" -45 0.0001
ctl jog --feed 50 -- -60 0 -1 >"$T/hl2.out" 2>&1; rc=$?
expect "motion refused in alarm: exit 7 (got $rc)" [ $rc -eq 7 ]
expect "refused: operation not allowed" grep -q 'refused message 1: ' "$T/hl2.out"
ctl unlock >"$T/u1.out" 2>&1; rc=$?
expect "unlock: exit 0 (got $rc)" [ $rc -eq 0 ]
ctl jog --feed 50 -- -60 0 -1 >"$T/back.out" 2>&1; rc=$?
expect "jog back after unlock: exit 0 (got $rc)" [ $rc -eq 0 ]
expect "jog back: at -60" grep -q '^jog: machine position -60.0000 0.0000 -1.0000 mm$' "$T/back.out"

# 3b. `curvestep stream` into the same switch (it plans from 0: +20 mm from device -60 crosses
# the switch at device -45): exit 7 and a line naming the alarm, the switch, the segment and
# where the device stopped (-45 x 80 = -3600 steps, z -1 mm = -80); unlock.
printf '%s\n' 'G21 G90' 'G1 X20 F1200' >"$T/x20.nc"
timeout -k 5 120 "$CS" stream --port "$PTY" --machine "$MC" "$T/x20.nc" >"$T/st.out" 2>&1; rc=$?
expect "stream into the switch: exit 7 (got $rc)" [ $rc -eq 7 ]
expect "stream: ALARM:1 located (switch, segment, position)" grep -qE \
    '^stream: ALARM:1 \(hard limit: a limit switch tripped\): x max switch, during segment no\. [1-9][0-9]*; stopped at x -3600 y 0 z -80 steps$' \
    "$T/st.out"
ctl unlock >/dev/null 2>&1; rc=$?
expect "unlock after the stream's alarm: exit 0 (got $rc)" [ $rc -eq 0 ]

# 4. e-stop (to the simulator itself: `timeout` would die of SIGUSR1)
DEVPID=$(pgrep -P "$SIMPID" -x curvestep-sim)
kill -USR1 "$DEVPID"
ctl jog --feed 50 -- -70 0 -1 >"$T/es.out" 2>&1; rc=$?
expect "jog with the e-stop pressed: exit 7 (got $rc)" [ $rc -eq 7 ]
ctl unlock >"$T/u2.out" 2>&1; rc=$?
expect "unlock refused while pressed: exit 7 (got $rc)" [ $rc -eq 7 ]
kill -USR2 "$DEVPID"
ctl unlock >"$T/u3.out" 2>&1; rc=$?
expect "unlock after release: exit 0 (got $rc)" [ $rc -eq 0 ]

# 5. laser: S 800 of 1000, full power from 20 mm/s; a jog at 40 mm/s cruises at full power and
# ramps below it; off after
ctl spindle --laser --feed 20 800 >"$T/sp.out" 2>&1; rc=$?
expect "laser on: exit 0 (got $rc)" [ $rc -eq 0 ]
ctl jog --feed 40 -- -80 0 -1 >/dev/null 2>&1; rc=$?
expect "laser jog: exit 0 (got $rc)" [ $rc -eq 0 ]
ctl spindle --off >/dev/null 2>&1; rc=$?
expect "laser off: exit 0 (got $rc)" [ $rc -eq 0 ]
ctl spindle 1001 >/dev/null 2>&1; rc=$?
expect "S above s_max: usage (got $rc)" [ $rc -eq 2 ]

kill -TERM "$SIMPID"
wait_until 60 gone "$SIMPID"
wait "$SIMPID"
expect "sim: laser at most 800/1000, ramped" \
    grep -qE '^control: .* spindle: ([4-9]|[1-9][0-9]+) settings, largest duty 800/1000$' "$T/dev.sim"
expect "picture: the power drawn along the jog" grep -q 'class="power"' "$T/ctl.svg"
expect "sim: 2 axes homed, alarms counted" grep -qE '^control: 2 axes homed, [3-9] alarms' "$T/dev.sim"
# the picture: a ring per event, blue where an axis was homed (x at physical -4 mm), green at
# each of the 3 probe cycles' ends, red at each alarm
expect "picture: 2 homed rings" [ "$(grep -c 'class="mark".*stroke="#1919d8"' "$T/ctl.svg")" -eq 2 ]
expect "picture: x homed at physical -4 mm" grep -q 'class="mark" cx="-4.0000" .*#1919d8' "$T/ctl.svg"
expect "picture: 3 probe rings" [ "$(grep -c 'class="mark".*stroke="#19a519"' "$T/ctl.svg")" -eq 3 ]
expect "picture: alarm rings" [ "$(grep -c 'class="mark".*stroke="#d81919"' "$T/ctl.svg")" -ge 3 ]
# physical final position: device (-80, 0, -1) + (95, 0, 1)
expect "sim: final position physical (15, 0, 0) mm" \
    grep -q '^final position: x=1200 steps (15.0000 mm) y=0 steps (0.0000 mm) z=0 steps' "$T/dev.sim"

# 6. a jog cancelled by Ctrl-C on a real-time device (no switches: the built-in machine)
# (the target 300 mm away at 5 mm/s: a minute of jog, so the Ctrl-C lands mid-jog however slow
# the machine; it comes once the device's executed log shows the jog moving)
timeout -k 5 120 "$SIM" --pty --exlog "$T/rt.exlog" >"$T/rt.sim" 2>"$T/rt.simerr" &
pids+=($!)
RTPID=$!
wait_pty "$T/rt.sim" 60
timeout -k 5 100 "$CS" jog --port "$PTY" --feed 5 -- 300 0 0 >"$T/jc.out" 2>"$T/jc.err" &
JPID=$!
expect "jog cancel: the jog is moving" wait_until 60 test -s "$T/rt.exlog"
# one Ctrl-C to curvestep itself: `timeout` would pass it on to its whole process group too, and
# a second Ctrl-C means "give up at once" (no wait for the device to come to rest)
kill -INT "$(pgrep -P "$JPID" -x curvestep)"
wait "$JPID"; rc=$?
expect "jog cancel: exit 8 (got $rc)" [ $rc -eq 8 ]
jx=$(last_field "$T/jc.out" '^jog: machine position' 4)
kill -TERM "$RTPID"
wait_until 60 gone "$RTPID"
wait "$RTPID"
sx=$(grep '^final position:' "$T/rt.sim" | sed 's/.*x=-\{0,1\}[0-9]* steps (\([-0-9.]*\) mm).*/\1/')
expect "jog cancel: stopped between start and target (x $jx)" \
    awk -v x="$jx" 'BEGIN { exit !(x > 0 && x < 300) }'
expect "jog cancel: the position reported is the device's final one ($jx = $sx)" near "$jx" "$sx" 0
expect "jog cancel: decelerated (a hold), not aborted" \
    grep -qE '^device: .* [1-9][0-9]* holds, 0 aborts' "$T/rt.sim"

finish
