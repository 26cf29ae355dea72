#!/usr/bin/env bash
# `curvestep grbl` on the links other than the serial wire protocol (issue 21 item 4): a Grbl
# sender (tests/support/grbl_client.py) drives
#  - a Modbus TCP device (`curvestep-sim --modbus-tcp`): a real program (inches, modal arcs)
#    streamed by send-response with ? every 2 lines and a feed hold / resume mid-job, in real
#    time x40: the device's final position is the one `curvestep plan` + `curvestep-sim --replay`
#    give (an independent path), its check passes, it saw the hold; what Modbus cannot do ($H,
#    G38.2, M3) is error:5 / error:20 with a [MSG:] naming the link, M5 is ok;
#  - the GPIO link's recorder (`--gpio record:FILE`): a program whose end the test computes from
#    its G-code (mm x 80 steps/mm, rounded to a step), with ? and a hold / resume: the final
#    status and the GPIO state's position are exactly that; Ctrl-X stops a move short, at the
#    position its recorded STEP edges give; and with the simulated switches and
#    probe of tests/data/ctl-*.ini (by hand, as tests/cli/test_gpio_inputs.sh: home ends at
#    machine -99, 0, 0; the probe surface is machine z -4; the x max switch is machine x -45):
#    $H ok at -99 0 0, G38.2 touches at z -4, M3 is error:20, a move past the switch is ALARM:1
#    stopped at -45 with Pn:X, then G-code is locked (error:9) until $X; a 0x85 stops a jog
#    short of its end, and the GPIO state file keeps where it stopped; FS: on a straight cut
#    at F1200 is 1200 within 2 % on every report past the ramp; a new session (Modbus:
#    the device's registers; GPIO: the state file) starts where the machine stands.
# Every process is bounded by `timeout` and killed on exit. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
need_bin "$CS" "$SIM"

CLIENT=tests/support/grbl_client.py
PROG=tests/data/gcode/one-inch-circle.nc
client() { timeout -k 5 90 python3 "$CLIENT" "$@"; }
# start_grbl NAME ARGS...: the front end (GPTY: its pty once it prints one; "" when it ended
# first, GPID).
start_grbl() {
    local name=$1
    shift
    timeout -k 5 120 "$CS" grbl "$@" >"$T/$name.grbl" 2>"$T/$name.grblerr" &
    pids+=($!)
    GPID=$!
    wait_until 60 grbl_up "$T/$name.grbl"
    cs_cli_pty_ready "$T/$name.grbl" && GPTY=$PTY || GPTY=
    expect "$name: the front end serves a pty" [ -n "$GPTY" ]
}
grbl_up() { cs_cli_pty_ready "$1" || gone "$GPID"; }
stop_grbl() {
    kill "$GPID" 2>/dev/null
    wait "$GPID" 2>/dev/null
}
# The device under `timeout` gets SIGTERM itself (it finishes, then reports).
stop_dev() {
    kill $(pgrep -P "$1") 2>/dev/null || kill "$1" 2>/dev/null
    wait_until 60 gone "$1"
    wait "$1" 2>/dev/null
}

# --- Modbus TCP -------------------------------------------------------------------------------
"$CS" plan "$PROG" -o "$T/ref.seg" 2>/dev/null
REF_POS=$("$SIM" --replay "$T/ref.seg" 2>/dev/null | grep '^final position:')
expect "reference final position" [ -n "$REF_POS" ]

timeout -k 5 120 "$SIM" --modbus-tcp 127.0.0.1:0 --speed 40 --reference "$PROG" --check \
    >"$T/mb.sim" 2>"$T/mb.simerr" &
pids+=($!)
SIMPID=$!
wait_pty "$T/mb.sim" 60
start_grbl mb --modbus-tcp "$PTY"
client "$GPTY" stream "$PROG" --method simple --status-every 2 --hold-after 6 >"$T/mb.out"; rc=$?
stop_grbl
stop_dev "$SIMPID"
expect "modbus: client exit 0" [ $rc -eq 0 ]
expect "modbus: said which link" grep -q 'for the Modbus device on 127.0.0.1:' "$T/mb.grblerr"
expect "modbus: 11 ok, 0 errors" grep -q '^acks: 11 0$' "$T/mb.out"
expect "modbus: status while running" grep -qE '^running: <Run\|MPos:-?[0-9]+\.[0-9]{3},' "$T/mb.out"
expect "modbus: every status well formed" bash -c "! grep -q '^malformed' '$T/mb.out'"
expect "modbus: held (Hold:0)" grep -q '^held: <Hold:0|MPos:' "$T/mb.out"
h=$(sed -n 's/^held: <Hold:0|\(MPos:[^|]*\)|.*/\1/p' "$T/mb.out")
expect "modbus: held still 0.3 s later" grep -q "^still-held: <Hold:0|$h|" "$T/mb.out"
expect "modbus: held away from the end and the start" \
    bash -c "[ '$h' != 'MPos:0.000,0.000,6.350' ] && [ '$h' != 'MPos:0.000,0.000,0.000' ]"
expect "modbus: ends Idle at the program's end" grep -q '^final: <Idle|MPos:0.000,0.000,6.350|' "$T/mb.out"
expect "modbus: the device saw the hold" grep -qE ' [1-9][0-9]* holds' "$T/mb.sim"
expect "modbus: device check ok" grep -q '^check: ok$' "$T/mb.sim"
expect "modbus: final position exact, as plan + replay" grep -qxF "$REF_POS" "$T/mb.sim"
expect "modbus: the device's end is the program's, rounded to steps" grep -q 'rounded to steps: exact' "$T/mb.sim"

# what Modbus cannot do: refused with Grbl's error and the reason, never run; M5 is ok
printf '%s\n' '[homing]' 'order = x' 'x = min' 'x_pos = 0' '[probe]' 'z = -2' >"$T/mbctl.ini"
timeout -k 5 120 "$SIM" --modbus-tcp 127.0.0.1:0 --instant --machine "$T/mbctl.ini" \
    >"$T/mbc.sim" 2>"$T/mbc.simerr" &
pids+=($!)
SIMPID=$!
wait_pty "$T/mbc.sim" 60
ADDR=$PTY
start_grbl mbc --modbus-tcp "$ADDR" --machine "$T/mbctl.ini"
client "$GPTY" cmd '$H' 'G38.2 Z-5 F100' 'M3 S1000' 'M5' 'G0 X2' '@waitfor Idle' >"$T/mbc.out"; rc=$?
stop_grbl
start_grbl mbc2 --modbus-tcp "$ADDR" --machine "$T/mbctl.ini" # a new session: where is it?
client "$GPTY" cmd 'G91 G0 X1' '@waitfor Idle' >"$T/mbc2.out"
stop_grbl
stop_dev "$SIMPID"
expect "modbus ctl: client exit 0" [ $rc -eq 0 ]
expect "modbus ctl: \$H error:5, said why" \
    [ "$(grep -A1 -F '[MSG:line 1: $H (homing): the Modbus link cannot do it' "$T/mbc.out" | tail -1)" = error:5 ]
expect "modbus ctl: G38.2 error:20, said why" grep -qF '[MSG:line 2: G38.x (probing): the Modbus link cannot do it' "$T/mbc.out"
expect "modbus ctl: M3 error:20, said why" grep -qF '[MSG:line 3: M3 (spindle): the Modbus link cannot do it' "$T/mbc.out"
expect "modbus ctl: errors 5, 20, 20 in order, then ok for M5 and G0" \
    [ "$(grep -E '^(ok|error:[0-9]+)$' "$T/mbc.out" | tr '\n' ' ')" = 'error:5 error:20 error:20 ok ok ' ]
expect "modbus ctl: the log names the refusals" [ "$(grep -c 'refused: the Modbus link cannot do it' "$T/mbc.grblerr")" -eq 3 ]
expect "modbus ctl: G0 X2 ran after them" grep -q '^state: <Idle|MPos:2.000,0.000,0.000|' "$T/mbc.out"
expect "modbus: a new session starts where the registers say (2 mm), X1 more: 3" \
    grep -q '^state: <Idle|MPos:3.000,0.000,0.000|' "$T/mbc2.out"
expect "modbus ctl: the device moved x to 3 mm (240 steps)" grep -q '^final position: x=240 steps' "$T/mbc.sim"

# Modbus RTU (the simulator's RTU server on a pty): the same front end, a move and a jog.
timeout -k 5 120 "$SIM" --modbus-rtu pty --speed 1 >"$T/rtu.sim" 2>"$T/rtu.simerr" &
pids+=($!)
SIMPID=$!
wait_pty "$T/rtu.sim" 60
start_grbl rtu --modbus-rtu "$PTY"
client "$GPTY" cmd 'G21 G90 G0 X4 Y-2' '@waitfor Idle' '$J=G91 Y3 F600' '@waitfor Idle' >"$T/rtu.out"
client "$GPTY" reset 'G91 G1 X50 F600' >"$T/mbr.out" # Ctrl-X mid-move (5 s long)
stop_grbl
stop_dev "$SIMPID"
expect "modbus rtu: the move and the jog end at 4, 1" grep -q '^state: <Idle|MPos:4.000,1.000,0.000|' "$T/rtu.out"
xs=$(sed -n 's/^final position: x=\(-*[0-9]*\) steps.*/\1/p' "$T/rtu.sim")
xr=$(sed -n 's/^final: <Idle|MPos:\([0-9.-]*\),.*/\1/p' "$T/mbr.out")
expect "modbus reset: moving before Ctrl-X" grep -q '^moving: <Run|MPos:' "$T/mbr.out"
expect "modbus reset: the device stopped short of X54 ($xs steps)" [ "${xs:-0}" -gt 320 ] && [ "${xs:-0}" -lt 4320 ]
expect "modbus reset: Idle where the device stopped (x $xr)" \
    awk -v x="$xr" -v s="${xs:-0}" 'BEGIN { exit !(x != "" && sprintf("%.3f", s / 80) == x) }'
expect "modbus reset: the device held, then aborted" grep -qE ' 1 holds, 1 aborts' "$T/rtu.sim"
expect "modbus rtu: the device's y is the jog's end (80 steps)" grep -q '^final position: x=-*[0-9]* steps ([0-9.-]* mm) y=80 steps' "$T/rtu.sim"

# --- GPIO (the recorder) ----------------------------------------------------------------------
# a program ending at X12.33 Y7.88 (machine mm): 80 steps/mm, the end rounded to a step
printf '%s\n' 'G21 G90' 'G1 X20 Y10 F6000' 'G2 X30 Y20 I10 J0' 'G1 X0 Y30 F6000' \
    'G1 X12.33 Y7.88 F3000' >"$T/g.nc"
read -r wx wy < <(awk 'BEGIN { x = int(12.33 * 80 + 0.5); y = int(7.88 * 80 + 0.5); print x, y }')
want=$(awk -v x="$wx" -v y="$wy" 'BEGIN { printf "%.3f,%.3f,0.000", x / 80, y / 80 }')
start_grbl gp --gpio "record:$T/gp.csv"
client "$GPTY" stream "$T/g.nc" --method simple --status-every 1 --hold-after 3 >"$T/gp.out"; rc=$?
cp "$T/gp.csv.state" "$T/gp.state1"
client "$GPTY" reset 'G91 G1 X50 F600' >"$T/gpr.out" # Ctrl-X mid-move: 5 s long
stop_grbl
expect "gpio: client exit 0" [ $rc -eq 0 ]
expect "gpio: 5 ok, 0 errors" grep -q '^acks: 5 0$' "$T/gp.out"
expect "gpio: status while running" grep -qE '^running: <Run\|MPos:' "$T/gp.out"
expect "gpio: every status well formed" bash -c "! grep -q '^malformed' '$T/gp.out'"
expect "gpio: held (Hold:0)" grep -q '^held: <Hold:0|MPos:' "$T/gp.out"
h=$(sed -n 's/^held: <Hold:0|\(MPos:[^|]*\)|.*/\1/p' "$T/gp.out")
expect "gpio: held still 0.3 s later" grep -q "^still-held: <Hold:0|$h|" "$T/gp.out"
expect "gpio: held away from the start and the end ($h)" \
    bash -c "[ '$h' != 'MPos:$want' ] && [ '$h' != 'MPos:0.000,0.000,0.000' ] && [ -n '$h' ]"
expect "gpio: ends Idle exactly at the program's end ($want)" grep -q "^final: <Idle|MPos:$want|" "$T/gp.out"
expect "gpio: the state keeps that position ($wx $wy steps)" grep -q "^pos $wx $wy 0 " "$T/gp.state1"
# Ctrl-X: stopped short, where the record's edges of that chunk (the last) put the machine
read -r n s < <(awk -F, '$3 == "x_dir" { d = $4 ? 1 : -1 } $3 == "x_step" && $4 == 1 { n++; s += d }
    END { print n + 0, s + 0 }' "$T/gp.csv")
xr=$(sed -n 's/^final: <Idle|MPos:\([0-9.-]*\),.*/\1/p' "$T/gpr.out")
expect "gpio reset: moving before Ctrl-X" grep -q '^moving: <Run|MPos:' "$T/gpr.out"
expect "gpio reset: stopped short of X+50 ($n steps, all +x)" [ "$n" -gt 0 ] && [ "$n" -lt 4000 ] && [ "$n" = "$s" ]
expect "gpio reset: Idle where the record's steps put it (x $xr)" \
    awk -v x="$xr" -v s="$s" -v x0="$wx" 'BEGIN { exit !(x != "" && sprintf("%.3f", (x0 + s) / 80) == x) }'
expect "gpio reset: the state agrees" grep -q "^pos $((wx + s)) $wy 0 " "$T/gp.csv.state"

# FS: on GPIO the step thread's clock (the executed segments' ticks against their steps): a
# straight 40 mm cut at F1200 from a fresh state (X0), every report in Run past the ramp within
# 2 % of 1200 (the client computes where from $120; the byte, 0x90 feed 100 %, changes nothing)
printf '%s\n' 'G21 G90' 'G1 X40 F1200' >"$T/gf.nc"
start_grbl gf --gpio "record:$T/gf.csv"
client "$GPTY" override "$T/gf.nc" 90 30 1200 >"$T/gf.out"; rc=$?
stop_grbl
expect "gpio fs: client exit 0, ends at X40" \
    [ $rc -eq 0 -a -n "$(grep '^final: <Idle|MPos:40.000,0.000,0.000|' "$T/gf.out")" ]
expect "gpio fs: at least 5 reports past the ramp ($(grep '^steady:' "$T/gf.out"))" \
    grep -qE '^steady: ([5-9]|[1-9][0-9]+) ' "$T/gf.out"
expect "gpio fs: FS 1200 +- 2 % on every one ($(grep '^off:' "$T/gf.out"))" grep -qx 'off:' "$T/gf.out"

# machine control on GPIO: the switches and probe of the machine file (see the top)
M=$T/ctl.ini
cat tests/data/ctl-switches.ini >"$M" # ctl-homing.ini's cycle, faster (the same end positions)
printf '%s\n' '[homing]' 'order = zx' 'seek = 50' 'latch = 5' 'pulloff = 1' 'z = max' 'z_pos = 0' \
    'x = min' 'x_pos = -99' >>"$M"
start_grbl gc --gpio "record:$T/gc.csv" --machine "$M"
client "$GPTY" cmd '$H' '?' 'G38.2 Z-10 F600' 'M3 S100' 'G0 Z0' 'G1 X-40 F6000' '@waitfor Alarm' \
    'G0 X-60' '$X' 'G0 X-60' '@waitfor Idle' >"$T/gc.out"; rc=$?
client "$GPTY" jogcancel '$J=G91 X-30 F300' >"$T/gj.out"; rc2=$?
stop_grbl
start_grbl gc2 --gpio "record:$T/gc.csv" --machine "$M" # a new session: the state's position
client "$GPTY" cmd '?' >"$T/gc2.out"
stop_grbl
expect "gpio ctl: client exit 0" [ $rc -eq 0 ] && [ $rc2 -eq 0 ]
expect "gpio ctl: \$H ok, then at -99 0 0" grep -q '^<Idle|MPos:-99.000,0.000,0.000|' "$T/gc.out"
expect "gpio ctl: homed z then x (the log)" grep -q '^home: x homed; machine position -99.0000 ' "$T/gc.grblerr"
expect "gpio ctl: probe contact at z -4" grep -qx '\[PRB:-99.000,0.000,-4.000:1\]' "$T/gc.out"
expect "gpio ctl: M3 error:20, said why" grep -qF '[MSG:line 4: M3 (spindle): the GPIO link cannot do it' "$T/gc.out"
expect "gpio ctl: hard limit ALARM:1" grep -qx 'ALARM:1' "$T/gc.out"
expect "gpio ctl: stopped on the x max switch at -45, Pn:X" grep -q '^state: <Alarm|MPos:-45.000,0.000,0.000|FS:0,0|Pn:X' "$T/gc.out"
expect "gpio ctl: locked until \$X (error:9)" grep -qx 'error:9' "$T/gc.out"
expect "gpio ctl: \$X unlocks" grep -qx '\[MSG:Caution: Unlocked\]' "$T/gc.out"
expect "gpio ctl: then G-code runs: at -60" grep -q '^state: <Idle|MPos:-60.000,0.000,0.000|' "$T/gc.out"
x=$(sed -n 's/^final: <Idle|MPos:\([0-9.-]*\),.*/\1/p' "$T/gj.out")
expect "gpio jog: Jog state while moving" grep -q '^jogging: <Jog|MPos:' "$T/gj.out"
expect "gpio jog: 0x85 stopped it short of its end, -90 (x $x)" awk -v x="${x:-0}" 'BEGIN {exit !(x <= -60 && x > -90)}'
w=$(awk -v x="${x:-0}" 'BEGIN { printf "%d", x * 80 + (x < 0 ? -0.5 : 0.5) }')
expect "gpio jog: the state keeps where it stopped ($w steps)" grep -q "^pos $w 0 " "$T/gc.csv.state"
expect "gpio: a new session starts there" grep -q "^<Idle|MPos:$x,0.000,0.000|" "$T/gc2.out"

# usage: the link options are `curvestep stream`'s
run "no link: exit 2" 2 grbl
expect_err "no link: said" 'one of --port, --modbus-tcp, --modbus-rtu or --gpio is required'
run "two links: exit 2" 2 grbl --port /dev/null --gpio record:"$T/x.csv"
expect_err "two links: said" 'exclude each other'
run "bad unit: exit 2" 2 grbl --modbus-tcp 127.0.0.1:1 --unit 0
run "no Modbus device: exit 4" 4 grbl --modbus-tcp 127.0.0.1:1
run "no GPIO chip: exit 4" 4 grbl --gpio gpiochip9
expect_err "no GPIO chip: named" 'cannot open GPIO chip gpiochip9'
run "--line-rate off --port: exit 2" 2 grbl --gpio "record:$T/x.csv" --line-rate 100

finish
