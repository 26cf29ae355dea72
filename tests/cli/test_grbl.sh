#!/usr/bin/env bash
# Command-line tests of `curvestep grbl`, the Grbl 1.1 front end, with tests/support/
# grbl_client.py as the sender (Grbl's two documented streaming methods) and `curvestep-sim
# --pty` as the device: a real G-code program (inches, modal arcs) streamed by character
# counting and by send-response ends at the exact position `curvestep plan` + `curvestep-sim
# --replay` give; ? during the job is well formed; ! then ~ holds and resumes with the final
# position still exact; $$ $# $G $I answer in Grbl's format, an unknown $ gives error:3; a bad
# line gives error:N and the stream goes on; a jog is cancelled by 0x85; TCP with --listen;
# usage. Every process is bounded by `timeout` and killed on exit. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"

CLIENT=tests/support/grbl_client.py
PROG=tests/data/gcode/one-inch-circle.nc

# start_sim NAME ARGS...: the device on a pty (PTY, SIMPID); --instant unless ARGS start with --speed.
# Every scenario ends it with stop_all; --idle-exit is only a backstop (a short one ended the
# device mid-job when the sender paused over 3 s between lines on a loaded machine under ASan).
start_sim() {
    local name=$1; shift
    local pace=--instant
    [ "${1:-}" = --speed ] && pace=
    timeout -k 5 120 "$SIM" --pty $pace --idle-exit 60 "$@" >"$T/$name.sim" 2>"$T/$name.simerr" &
    pids+=($!)
    SIMPID=$!
    wait_pty "$T/$name.sim" 60
}
# start_grbl NAME ARGS...: the front end on the device's pty (GPTY: its own pty, GPID).
start_grbl() {
    local name=$1; shift
    timeout -k 5 120 "$CS" grbl --port "$PTY" "$@" >"$T/$name.grbl" 2>"$T/$name.grblerr" &
    pids+=($!)
    GPID=$!
    wait_pty "$T/$name.grbl" 60
    GPTY=$PTY
}
# stop_all: ends the front end, then the device, and waits for its report (SIGTERM: it finishes
# what its executor holds, then reports; every client below waits for Idle first, and a device
# that executed nothing never reaches its idle exit).
stop_all() {
    kill "$GPID" 2>/dev/null
    wait "$GPID" 2>/dev/null
    kill "$SIMPID" 2>/dev/null
    wait "$SIMPID" 2>/dev/null
}
client() { timeout -k 5 90 python3 "$CLIENT" "$@"; }

# The reference: the same program planned whole and replayed (an independent path to the device).
"$CS" plan "$PROG" -o "$T/ref.seg" 2>/dev/null
"$SIM" --replay "$T/ref.seg" >"$T/ref.out" 2>&1
REF_POS=$(grep '^final position:' "$T/ref.out")
expect "reference final position" [ -n "$REF_POS" ]

# 1. character counting: every line ok, the device's final position exact.
start_sim cc --reference "$PROG" --check
start_grbl cc
expect "cc: pty path printed" wait_until 60 test -c "$GPTY"
client "$GPTY" stream "$PROG" --method counting >"$T/cc.out"; rc=$?
stop_all
expect "cc: client exit 0" [ $rc -eq 0 ]
expect "cc: welcome line" grep -qF "welcome: Grbl 1.1h ['\$' for help]" "$T/cc.out"
expect "cc: 11 ok, 0 errors" grep -q '^acks: 11 0$' "$T/cc.out"
expect "cc: ends Idle at the program's end (0, 0, 0.25 in)" grep -q '^final: <Idle|MPos:0.000,0.000,6.350|' "$T/cc.out"
expect "cc: device check ok" grep -q '^check: ok$' "$T/cc.sim"
expect "cc: final position exact" grep -q 'rounded to steps: exact' "$T/cc.sim"
expect "cc: same final position as plan + replay" grep -qxF "$REF_POS" "$T/cc.sim"

# 1b. a long program (2500 short moves: several chunks, the queue fills and ok waits for room),
#     by character counting: every line ok, the same final position as plan + replay.
awk 'BEGIN {print "G21 G90 F3000"; for (i = 1; i <= 2500; i++)
    printf "G1 X%.3f Y%.3f\n", (i % 50) * 2 + 0.5 * sin(i), int(i / 50) * 1.5 + (i % 7) * 0.1
    print "G0 X1 Y1"}' >"$T/long.nc"
"$CS" plan "$T/long.nc" -o "$T/long.seg" 2>/dev/null
LONG_POS=$("$SIM" --replay "$T/long.seg" 2>/dev/null | grep '^final position:')
start_sim long
start_grbl long
client "$GPTY" stream "$T/long.nc" --method counting --status-every 100 >"$T/long.out"; rc=$?
stop_all
expect "long: client exit 0" [ $rc -eq 0 ]
expect "long: 2502 ok, 0 errors" grep -q '^acks: 2502 0$' "$T/long.out"
expect "long: ends Idle at (1, 1)" grep -q '^final: <Idle|MPos:1.000,1.000,0.000|' "$T/long.out"
expect "long: same final position as plan + replay" grep -qxF "$LONG_POS" "$T/long.sim"

# 1c. work offsets (G10 L20, G10 L2, G54/G55, G92, G92.1) and an O-word sub defined and called
#     over several lines, by character counting: the final position is the hand-computed machine
#     17, 18 (G54 zero at 10, 10 plus X7 Y8), the same as plan + replay; then $# shows the offsets
#     kept (G92 cleared by the client's soft reset) and $G a coordinate system and spindle.
WCS=tests/data/gcode/grbl-wcs-sub.ngc
"$CS" plan "$WCS" -o "$T/wcs.seg" 2>/dev/null
WCS_POS=$("$SIM" --replay "$T/wcs.seg" 2>/dev/null | grep '^final position:')
expect "wcs: plan + replay at machine 17, 18" grep -q 'x=1360 steps (17.0000 mm) y=1440 steps (18.0000 mm)' <<<"$WCS_POS"
start_sim wcs
start_grbl wcs
client "$GPTY" stream "$WCS" --method counting >"$T/wcs.out"; rc=$?
client "$GPTY" cmd '$#' 'G55 G20 M3 S1000' '$G' >"$T/wcs2.out"
stop_all
expect "wcs: client exit 0" [ $rc -eq 0 ]
expect "wcs: 20 ok, 0 errors" grep -q '^acks: 20 0$' "$T/wcs.out"
expect "wcs: ends Idle at machine 17, 18" grep -q '^final: <Idle|MPos:17.000,18.000,0.000|' "$T/wcs.out"
expect "wcs: same final position as plan + replay" grep -qxF "$WCS_POS" "$T/wcs.sim"
expect "wcs: \$# G54 from G10 L20" grep -qx '\[G54:10.000,10.000,0.000\]' "$T/wcs2.out"
expect "wcs: \$# G55 from G10 L2" grep -qx '\[G55:40.000,5.000,0.000\]' "$T/wcs2.out"
expect "wcs: \$# G92 cleared" grep -qx '\[G92:0.000,0.000,0.000\]' "$T/wcs2.out"
expect "wcs: \$G" grep -qx '\[GC:G80 G55 G17 G20 G90 G94 M3 M9 T0 F0 S1000\]' "$T/wcs2.out"

# 2. send-response, ? every 2 lines, and a hold (!) mid-job then resume (~), in real time x20.
start_sim sr --speed 20 --reference "$PROG" --check
start_grbl sr
client "$GPTY" stream "$PROG" --method simple --status-every 2 --hold-after 6 >"$T/sr.out"; rc=$?
stop_all
expect "sr: client exit 0" [ $rc -eq 0 ]
expect "sr: 11 ok, 0 errors" grep -q '^acks: 11 0$' "$T/sr.out"
expect "sr: status while running" grep -qE '^running: <Run\|MPos:-?[0-9]+\.[0-9]{3},-?[0-9]+\.[0-9]{3},-?[0-9]+\.[0-9]{3}\|FS:[0-9]+,0' "$T/sr.out"
expect "sr: every status well formed" bash -c "! grep -q '^malformed' '$T/sr.out'"
expect "sr: held (Hold:0)" grep -q '^held: <Hold:0|MPos:' "$T/sr.out"
h=$(sed -n 's/^held: <Hold:0|\(MPos:[^|]*\)|.*/\1/p' "$T/sr.out")
expect "sr: held still 0.3 s later" grep -q "^still-held: <Hold:0|$h|" "$T/sr.out"
expect "sr: held away from the end" bash -c "[ '$h' != 'MPos:0.000,0.000,6.350' ]"
expect "sr: ends Idle at the program's end" grep -q '^final: <Idle|MPos:0.000,0.000,6.350|' "$T/sr.out"
expect "sr: device saw the hold" grep -qE ' [1-9][0-9]* holds' "$T/sr.sim"
expect "sr: device check ok" grep -q '^check: ok$' "$T/sr.sim"
expect "sr: final position exact after hold/resume" grep -qxF "$REF_POS" "$T/sr.sim"

# 3. $ commands in Grbl's format; unknown $ -> error:3; machine settings read-only; $10 sets Bf.
start_sim dol
start_grbl dol
client "$GPTY" cmd '$$' '$#' '$G' '$I' '$Q' '$100=5' '$10=3' '$' >"$T/dol.out"; rc=$?
client "$GPTY" cmd '$H' >"$T/dolh.out"
client "$GPTY" cmd 'G0 X3000' '$J=X5' '$J=X5 S3 F100' '$J=G91 X-3000 F100' >"$T/dolerr.out"
client "$GPTY" raw 3f >"$T/dolq.out"
client "$GPTY" raw 91 9a 9d 84 3f >"$T/dolov.out"
stop_all
expect "\$: client exit 0" [ $rc -eq 0 ]
expect "\$\$: steps/mm of the machine" grep -qx '\$100=80.000' "$T/dol.out"
expect "\$\$: max rate mm/min" grep -qx '\$110=12000.000' "$T/dol.out"
expect "\$\$: accel mm/s2" grep -qx '\$122=500.000' "$T/dol.out"
n_bad=$(awk 'NR == 1 {next} /^ok$/ {exit} !/^\$[0-9]+=-?[0-9.]+$/ {n++} END {print n+0}' "$T/dol.out")
expect "\$\$: every line \$N=value" [ "$n_bad" -eq 0 ]
expect "\$#: G54 and G92 lines" grep -qx '\[G92:0.000,0.000,0.000\]' "$T/dol.out"
expect "\$#: PRB line" grep -qx '\[PRB:0.000,0.000,0.000:0\]' "$T/dol.out"
expect "\$G: modal state" grep -qx '\[GC:G80 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0\]' "$T/dol.out"
expect "\$I: version" grep -qE '^\[VER:1\.1h\.[0-9]+:curvestep [0-9.]+\]$' "$T/dol.out"
expect "\$I: options" grep -qE '^\[OPT:[A-Z]*,[0-9]+,128\]$' "$T/dol.out"
expect "\$Q: error:3" [ "$(grep -A2 '^\[OPT:' "$T/dol.out" | tail -1)" = error:3 ]
expect "\$100=5: read-only, said why" grep -q '^\[MSG:\$100 is read-only here: the machine file' "$T/dol.out"
expect "\$: help" grep -q '^\[HLP:' "$T/dol.out"
expect "\$H: error:5 (no homing)" grep -qx 'error:5' "$T/dolh.out"
expect "errors: beyond the travel error:33, said why" grep -q '^\[MSG:line [0-9]*: the move leaves the machine.s travel\]$' "$T/dolerr.out"
expect "errors: in order 33, 22 (jog without F), 16 (bad jog word), 15 (jog beyond travel)" \
    [ "$(grep '^error:' "$T/dolerr.out" | tr '\n' ' ')" = "error:33 error:22 error:16 error:15 " ]
expect "override bytes: nothing but the status back" [ "$(grep -c . "$T/dolov.out")" -eq 2 ]
expect "override bytes: feed +10 %, spindle +10 -1 % in Ov (0x91 0x9A 0x9D)" grep -qE '^<Idle\|.*\|Ov:110,100,109>$' "$T/dolov.out"
expect "\$10=3: Bf in the status" grep -qE '^<Idle\|MPos:0\.000,0\.000,0\.000\|Bf:[0-9]+,128\|FS:0,0' "$T/dolq.out"

# 4. a bad line mid-program: error:N for it alone, the rest runs (final position exact against
#    the program without it).
sed '6a G1 X0.1 Q' "$PROG" >"$T/bad.nc"
start_sim bad --reference "$PROG" --check
start_grbl bad
client "$GPTY" stream "$T/bad.nc" --method counting >"$T/bad.out"; rc=$?
stop_all
expect "bad: client exit 0" [ $rc -eq 0 ]
expect "bad: error:2 for line 7 only" grep -qx 'error: line 7: error:2' "$T/bad.out"
expect "bad: 11 ok, 1 error" grep -q '^acks: 11 1$' "$T/bad.out"
expect "bad: device check ok" grep -q '^check: ok$' "$T/bad.sim"
expect "bad: final position exact" grep -qxF "$REF_POS" "$T/bad.sim"

# 5. a jog (10 s long in real time; the device's JOG) cancelled with 0x85 (the device's
#    JOG_CANCEL, decelerating within the machine's acceleration): stops short of its end; then
#    the program's G-code goes on from where the jog stopped.
start_sim jog --speed 1
start_grbl jog
client "$GPTY" jogcancel '$J=G91 X100 F600' >"$T/jog.out"; rc=$?
client "$GPTY" cmd 'G90 G0 X0 Y0' >"$T/jog2.out"
client "$GPTY" idle >"$T/jog3.out"
stop_all
expect "jog: client exit 0" [ $rc -eq 0 ]
expect "jog: accepted" grep -qx 'reply: ok' "$T/jog.out"
expect "jog: Jog state while moving" grep -q '^jogging: <Jog|MPos:' "$T/jog.out"
x=$(sed -n 's/^final: <Idle|MPos:\([0-9.-]*\),.*/\1/p' "$T/jog.out")
expect "jog: cancelled between 0 and 100 mm" awk -v x="${x:-0}" 'BEGIN {exit !(x > 0 && x < 100)}'
expect "jog: the device's JOG_CANCEL stopped it (counted as its one hold), no ABORT" grep -q ' 1 holds, 0 aborts' "$T/jog.sim"
expect "jog: the cancel decelerated (x within its acceleration)" grep -qE '^axis x: .*peak acceleration [0-9.]+ mm/s\^2 \(limit [0-9.]+ \+ [0-9.]+\) ok$' "$T/jog.sim"
expect "jog: G-code after the cancel ok" grep -qx ok "$T/jog2.out"
expect "jog: then Idle at the origin" grep -q '^final: <Idle|MPos:0.000,0.000,0.000|' "$T/jog3.out"
expect "jog: device back at the origin" grep -q '^final position: x=0 steps (0.0000 mm) y=0 steps' "$T/jog.sim"

# 6. TCP on loopback (port 0: any free one), a symlinked pty.
start_sim tcp
timeout -k 5 60 "$CS" grbl --port "$PTY" --listen 0 >"$T/tcp.grbl" 2>"$T/tcp.grblerr" &
pids+=($!)
GPID=$!
wait_pty "$T/tcp.grbl" 60
expect "tcp: 127.0.0.1:PORT printed" grep -qE '^127\.0\.0\.1:[0-9]+$' "$T/tcp.grbl"
client "$PTY" cmd '$I' >"$T/tcp.out"
expect "tcp: \$I answered" grep -qE '^\[VER:1\.1h' "$T/tcp.out"
stop_all
start_sim lnk
start_grbl lnk --link "$T/ttyCURVESTEP"
expect "link: symlink to the pty" [ "$(readlink "$T/ttyCURVESTEP")" = "$GPTY" ]
client "$T/ttyCURVESTEP" cmd '$G' >"$T/lnk.out"
expect "link: answers" grep -q '^\[GC:' "$T/lnk.out"
stop_all
expect "link: removed on exit" [ ! -e "$T/ttyCURVESTEP" ]

# 6b. --state FILE: G10 offsets and a G28.1 home written on exit, read back by the next run.
start_sim st1
start_grbl st1 --state "$T/state.ngc"
client "$GPTY" cmd 'G10 L2 P3 X1.5 Y-2' 'G0 X4 Y5' 'G28.1' >"$T/st1.out"
stop_all
expect "state: written on exit" grep -qx 'G10 L2 P3 X1.5 Y-2 Z0' "$T/state.ngc"
start_sim st2
start_grbl st2 --state "$T/state.ngc"
client "$GPTY" cmd '$#' >"$T/st2.out"
stop_all
expect "state: G56 read back" grep -qx '\[G56:1.500,-2.000,0.000\]' "$T/st2.out"
expect "state: G28 home read back" grep -qx '\[G28:4.000,5.000,0.000\]' "$T/st2.out"
printf 'G10 L2 P1 X1\nG10 L7 P1 X1\n' >"$T/badstate.ngc"
run "state: a bad state file is exit 1" 1 grbl --port /dev/null --state "$T/badstate.ngc"
expect "state: located error" grep -q "badstate.ngc:2:5: G10 sets work offsets with L2 or L20 only" "$T/err"

# 8. machine control on the device (the simulator's switches and probe from the machine file):
#    by hand, with the switches at x -5, y -5 (min) and z 3 (max), pull-off 1 and every axis
#    set to 0 where it ends, the machine's 0 is the simulator's (-4, -4, 2); its probe surface at
#    z -2.5 is machine z -4.5. $H homes (ok, at 0 0 0); G38.2 from 10 10 0 touches at
#    [PRB:10.000,10.000,-4.500:1]; a G38.2 that touches nothing is ALARM:5 (then its PRB and ok,
#    as Grbl's), G-code is then
#    locked (error:9) until $X; a G0 X-20 trips the x switch at machine -1 (ALARM:1, Pn:X);
#    $H clears that alarm and homes again.
printf '%s\n' '[homing]' 'order = zxy' 'x = min' 'y = min' 'z = max' 'x_pos = 0' 'y_pos = 0' \
    'z_pos = 0' 'pulloff = 1' '[limits]' 'x_min = -5' 'y_min = -5' 'z_max = 3' '[probe]' \
    'z = -2.5' >"$T/ctl.ini"
start_sim ctl --speed 20 --machine "$T/ctl.ini"
start_grbl ctl --machine "$T/ctl.ini"
client "$GPTY" cmd '$H' '?' 'G0 X10 Y10' 'G38.2 Z-20 F100' '$#' 'G0 Z0' 'G38.2 Z-1 F100' '?' \
    'G0 X1' '$X' 'G0 X-20' '@waitfor Alarm' '$H' '?' >"$T/ctl.out"; rc=$?
stop_all
expect "ctl: client exit 0" [ $rc -eq 0 ]
expect "ctl: \$H ok, then at 0 0 0" grep -q '^<Idle|MPos:0.000,0.000,0.000|' "$T/ctl.out"
expect "ctl: probe contact" grep -qx '\[PRB:10.000,10.000,-4.500:1\]' "$T/ctl.out"
expect "ctl: \$# PRB" [ "$(grep -c '^\[PRB:10.000,10.000,-4.500:1\]$' "$T/ctl.out")" -eq 2 ]
expect "ctl: probe without contact: PRB :0" grep -qx '\[PRB:10.000,10.000,-1.000:0\]' "$T/ctl.out"
expect "ctl: ALARM:5" grep -qx 'ALARM:5' "$T/ctl.out"
# Grbl 1.1 (gnea/grbl motion_control.c mc_probe_cycle, gcode.c): a probe without contact raises
# ALARM:5 from the realtime check, then reports [PRB:..:0], then the line returns STATUS_OK: ok
expect "ctl: failed probe answers ALARM:5, [PRB:..:0], ok (as Grbl), no error" \
    [ "$(grep -A2 -x 'ALARM:5' "$T/ctl.out" | tr '\n' ' ')" = 'ALARM:5 [PRB:10.000,10.000,-1.000:0] ok ' ]
expect "ctl: Alarm state where it stopped" grep -q '^<Alarm|MPos:10.000,10.000,-1.000|' "$T/ctl.out"
expect "ctl: locked until \$X (error:9)" grep -qx 'error:9' "$T/ctl.out"
expect "ctl: \$X unlocks" grep -qx '\[MSG:Caution: Unlocked\]' "$T/ctl.out"
expect "ctl: hard limit ALARM:1" grep -qx 'ALARM:1' "$T/ctl.out"
expect "ctl: stopped on the x switch (machine -1), Pn:X" grep -q '^state: <Alarm|MPos:-1.000,10.000,-1.000|FS:0,0|Pn:X' "$T/ctl.out"
expect "ctl: \$H again: ok at 0 0 0" [ "$(grep -c '^<Idle|MPos:0.000,0.000,0.000|' "$T/ctl.out")" -eq 2 ]
expect "ctl: the device homed 6 axes, 2 alarms, 2 probes" grep -q '^control: 6 axes homed, 2 alarms (last ALARM:1), 2 probe cycles' "$T/ctl.sim"

# 9. a laser job (Grbl's laser mode: [spindle] laser = true): M4 S600 with rapids between the
#    cuts; the device's largest duty is 600/1000 (full power at the programmed speed) and the
#    final position is the one plan + replay gives.
printf '%s\n' '[spindle]' 'laser = true' 's_max = 1000' >"$T/laser.ini"
printf '%s\n' 'G21 G90' 'M4 S600' 'G0 X5' 'G1 X25 F600' 'G0 X30 Y5' 'G1 Y25 F300' 'M5' \
    'G0 X0 Y1' >"$T/laser.nc"
"$CS" plan --machine "$T/laser.ini" "$T/laser.nc" -o "$T/laser.seg" 2>/dev/null
LASER_POS=$("$SIM" --replay "$T/laser.seg" --machine "$T/laser.ini" 2>/dev/null | grep '^final position:')
start_sim laser --machine "$T/laser.ini"
start_grbl laser --machine "$T/laser.ini"
client "$GPTY" stream "$T/laser.nc" --method counting >"$T/laser.out"; rc=$?
stop_all
expect "laser: client exit 0" [ $rc -eq 0 ]
expect "laser: 8 ok" grep -q '^acks: 8 0$' "$T/laser.out"
expect "laser: largest duty 600/1000" grep -q 'largest duty 600/1000' "$T/laser.sim"
expect "laser: final position as plan + replay" grep -qxF "$LASER_POS" "$T/laser.sim"

# 10. laser mode runs through power changes (Grbl's $32=1): M4 with S changing mid-straight (at
#     X10, collinear) and at a corner (20,0), then a rapid home. The sim's trace gives every laser
#     setting with the position and time it was set (each is the start of a segment), so from
#     one setting to the next the executed speed is v = |P1 - P0| / (t1 - t0). Checked from it:
#     - at X10 the speed on both sides is the feed (20 mm/s, >= 95 %): no stop (a stop at
#       200 mm/s^2 would leave the 5 ms segment there at <= 0.5 mm/s);
#     - at the corner both sides move >= 1 mm/s (a stop: <= 0.5 mm/s, a t_seg / 2);
#     - M4: every setting during the cuts is S / s_max x min(1, v / F) x 1000, S the power of the
#       move it starts (x < 10: 1000, then 500 up to x = 20, then 1000 along y), within 1 % of
#       S plus 1 (the device truncates to 1/1000);
#     - the rapid back to 0,0 runs with the laser off (duty 0 from the corner's end on).
printf '%s\n' '[x]' 'steps_per_mm = 400' 'max_rate = 100' 'max_accel = 200' '[y]' \
    'steps_per_mm = 400' 'max_rate = 100' 'max_accel = 200' '[spindle]' 'laser = true' \
    's_max = 1000' >"$T/blend.ini"
printf '%s\n' 'G21 G90' 'M4 S1000' 'G1 X10 F1200' 'G1 X20 S500' 'G1 X20 Y10 S1000' 'G0 X0 Y0' \
    'M5' >"$T/blend.nc"
start_sim blend --machine "$T/blend.ini" --trace "$T/blend.csv" --svg "$T/blend.svg"
start_grbl blend --machine "$T/blend.ini"
client "$GPTY" stream "$T/blend.nc" --method burst >"$T/blend.out"; rc=$?
stop_all
expect "blend: client exit 0, 7 ok" grep -q '^acks: 7 0$' "$T/blend.out"
python3 - "$T/blend.csv" >"$T/blend.chk" <<'PY'
import math, sys
rows = [l.split(",") for l in open(sys.argv[1]).read().split("\n")[1:] if ",s," in l]
st = [(float(r[0]), int(r[2]), float(r[3]), float(r[4])) for r in rows]
F = 20.0
def s_of(x, y):  # the programmed power of the move a segment starting at (x, y) belongs to
    return 1000 if y > 1e-9 or x >= 20 - 1e-9 else 500 if x >= 10 - 1e-9 else 1000
segs = []  # (x0, y0, x1, y1, v, duty)
for a, b in zip(st, st[1:]):
    dt = b[0] - a[0]
    d = math.hypot(b[2] - a[2], b[3] - a[3])
    segs.append((a[2], a[3], b[2], b[3], d / dt if dt > 0 else 0.0, a[1]))
def speed_around(x, y):  # mean speeds of the moving segments ending and starting at (x, y)
    end = [g[4] for g in segs if abs(g[2] - x) < 1e-9 and abs(g[3] - y) < 1e-9 and g[4] > 0]
    beg = [g[4] for g in segs if abs(g[0] - x) < 1e-9 and abs(g[1] - y) < 1e-9 and g[4] > 0]
    return min(end[-1:] + beg[:1]) if end and beg else 0.0
print("x10 %.3f" % speed_around(10, 0))
print("corner %.3f" % speed_around(20, 0))
bad = n = 0
worst = 0.0
cut_end = max(i for i, g in enumerate(segs) if g[3] <= 10 + 1e-9 and g[2] >= 20 - 1e-9 and g[4] > 0 and g[1] < 10 - 1e-9)
for g in segs[:cut_end + 1]:
    S = s_of(g[0], g[1])
    want = S * min(1.0, g[4] / F)
    err = abs(g[5] - want)
    n += 1
    worst = max(worst, err)
    if err > 0.01 * S + 1:
        bad += 1
        print("bad: at %.4f,%.4f v %.3f duty %d want %.1f" % (g[0], g[1], g[4], g[5], want))
print("power %d segments, %d off, worst %.2f" % (n, bad, worst))
rapid_on = [g for g in segs[cut_end + 1:] if g[5] != 0]
print("rapid lit %d" % len(rapid_on))
PY
expect "blend: the speed at the S change on X10 is the feed (>= 19 mm/s)" \
    awk '$1 == "x10" && $2 >= 19 { ok = 1 } END { exit !ok }' "$T/blend.chk"
expect "blend: the corner's S change keeps moving (>= 1 mm/s)" \
    awk '$1 == "corner" && $2 >= 1 { ok = 1 } END { exit !ok }' "$T/blend.chk"
expect "blend: M4 power / S = v / F within 1 % on every segment of the cuts" \
    grep -Eq '^power [1-9][0-9]+ segments, 0 off' "$T/blend.chk"
expect "blend: the rapid runs with the laser off" grep -qx 'rapid lit 0' "$T/blend.chk"
# the drawing shows the power along the path: a band per lit stretch, as wide as the duty, so
# the M4 ramps at the start and at the corner give many widths
expect "blend: the picture draws the laser power, its width following the duty" \
    [ "$(grep -o 'class="power"[^>]*stroke-width="[0-9.]*"' "$T/blend.svg" | sed 's/.*stroke-width=//' | sort -u | wc -l)" -ge 10 ]

# 11. feed override on the running chunk: a 4 s straight cut at 1200 mm/min (real time), 0x91
#     (+10 %) once it is half done; the device's reported feed (FS:, the device's speed over its
#     own clock: STATUS positions and ticks, cs_feedrate) rises by 10 % (within 4 %) while the
#     same chunk still runs (reports in Run from 0.6 s after the byte), Ov shows 110, and the
#     final position is exact (the check also bounds the acceleration). Before the byte, every
#     report in Run past the ramp shows 1200 within 2 % (the client computes where the ramp and
#     the FS window end from $120: grbl_client.py override).
printf '%s\n' 'G21 G90' 'G1 X80 F1200' >"$T/ov.nc"
start_sim ov --speed 1 --reference "$T/ov.nc" --check
start_grbl ov
client "$GPTY" override "$T/ov.nc" 91 40 1200 >"$T/ov.out"; rc=$?
stop_all
ov_before=$(sed -n 's/^before: //p' "$T/ov.out")
ov_after=$(sed -n 's/^after: //p' "$T/ov.out")
expect "ov: client exit 0" [ $rc -eq 0 ]
expect "ov: feed before near 1200 mm/min ($ov_before)" awk -v b="$ov_before" 'BEGIN {exit !(b > 1100 && b < 1300)}'
expect "ov: at least 5 reports past the ramp ($(grep '^steady:' "$T/ov.out"))" \
    grep -qE '^steady: ([5-9]|[1-9][0-9]+) ' "$T/ov.out"
expect "ov: FS 1200 +- 2 % on every one ($(grep '^off:' "$T/ov.out"))" grep -qx 'off:' "$T/ov.out"
expect "ov: reports in Run after the byte" grep -qE '^after-reports: [1-9]' "$T/ov.out"
expect "ov: feed x 1.10 +- 0.04 mid-chunk ($ov_before -> $ov_after)" \
    awk -v b="$ov_before" -v a="$ov_after" 'BEGIN {exit !(b > 0 && a / b > 1.06 && a / b < 1.14)}'
expect "ov: Ov:110,100,100" grep -q '^ov: 110,100,100$' "$T/ov.out"
expect "ov: ends Idle at X80" grep -q '^final: <Idle|MPos:80.000,0.000,0.000|' "$T/ov.out"
expect "ov: device check ok" grep -q '^check: ok$' "$T/ov.sim"
expect "ov: final position exact" grep -q 'rounded to steps: exact' "$T/ov.sim"

# 7. usage.
run "help: exit 0" 0 grbl --help
expect "help: names --listen and the pty" grep -q -- '--listen \[ADDR:\]PORT' "$T/out"
run "no --port: exit 2" 2 grbl
run "bad --listen: exit 2" 2 grbl --port /dev/null --listen nowhere:x
run "missing port: exit 4" 4 grbl --port "$T/none"

finish
