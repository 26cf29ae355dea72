#!/usr/bin/env bash
# The GPIO link's inputs (issue 21 item 1; docs/gpio.md "Inputs"): homing, a hard limit tripped
# mid-job, the e-stop, the alarm and its unlock, probing, all over `--gpio record:FILE`, whose
# simulated switches and probe surface come from the machine file written here (the simulator's
# [limits] / [probe] model, physical mm, 0 where the state file starts): x min switch at -5 mm,
# x max at 50 mm, z max at 2 mm, probe surface at z = -3 mm; 80 steps/mm (the built-in axes).
# Expected values by hand from those numbers (the same as tests/cli/test_control.sh's over the
# serial link to the simulator):
#  - home (order zx, pull-off 1 mm): z ends 1 mm below its switch (physical 1 mm), x 1 mm above
#    its switch (physical -4 mm); positions set to z_pos 0, x_pos -99. Machine = physical - (95,
#    0, 1) mm from then on.
#  - a job moving x +60 mm from there crosses the x max switch at physical 50 mm: (50 - -4) x 80
#    = 4320 steps. The record holds exactly 4320 x rises, all in +x, no rise of any line after the
#    4320th, and the run reports ALARM:1 with the x max bit (0x010) stopped at machine -45 mm
#    (exit 7). The next job and jog are refused (exit 7) until unlock.
#  - the e-stop (record FILE.estop present): a job refused at its first step (no STEP edge,
#    ALARM:10); pressed mid-job: stopped, the position reported equals the record's own step sum,
#    short of the job's; unlock refused while pressed, accepted once released.
#  - probe down to z = -10: contact where physical z reaches -3 mm: machine z = -4 mm, the record
#    holding exactly (1 - -3) x 80 = 320 z rises downwards; G38.3 above the surface: no contact,
#    exit 0; G38.2 there: ALARM:5, exit 7.
#  - [gpio] input keys read and checked (a line used twice, a switch of an axis the machine lacks);
#    a missing chip (exit 4), --port with --gpio (exit 2), a homing switch not there (exit 1).
# Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
need_bin "$CS"

M=$T/m.ini
cat tests/data/ctl-switches.ini tests/data/ctl-homing.ini >"$M"
cat >>"$M" <<EOF
[gpio]
x_step = 17
x_dir = 27
x_min = 5
x_max = 6
z_max = 13
probe = 19
estop = 26
limit_active_low = true
probe_active_low = false
state = $T/machine.state
EOF

# rises AXIS FILE: "N S": the record's STEP rises of AXIS and their signed sum (DIR level 1 = +)
rises() {
    awk -F, -v ax="$1" '$3 == ax "_dir" { d = $4 ? 1 : -1 }
        $3 == ax "_step" && $4 == 1 { n++; s += d } END { print n + 0, s + 0 }' "$2"
}
# after_nth AXIS N FILE: STEP rises of any line after the N-th rise of AXIS
after_nth() {
    awk -F, -v ax="$1" -v n="$2" '$3 ~ /_step$/ && $4 == 1 { if (k >= n) late++; if ($3 == ax "_step") k++ }
        END { print late + 0 }' "$3"
}
g() { c=$1; r=$2; shift 2; timeout -k 5 120 "$CS" "$c" --gpio "record:$T/$r.csv" --machine "$M" "$@"; }

# 1. homing
g home home >"$T/home.out" 2>"$T/home.err"; rc=$?
expect "home: exit 0 (got $rc)" [ $rc -eq 0 ]
expect "home: z first" grep -q '^home: z homed; machine position .* 0.0000 mm$' "$T/home.out"
expect "home: then x at x_pos" grep -q '^home: x homed; machine position -99.0000 ' "$T/home.out"
expect "home: final position" grep -q '^home: machine position -99.0000 0.0000 0.0000 mm$' \
    "$T/home.out"
expect "home: the state kept in [gpio] state" grep -q '^pos -7920 0 0 0$' "$T/machine.state"
# seek, back-off, latch, pull-off per axis: x ends 1 mm (80 steps) above its switch at -5 mm
# after starting at 0: net -(5 - 1) x 80 = -320 steps; z net +(2 - 1) x 80 = +80
read -r _ xs < <(rises x "$T/home.csv")
read -r _ zs < <(rises z "$T/home.csv")
expect "home: x net steps -320 in the record (got $xs)" [ "$xs" -eq -320 ]
expect "home: z net steps 80 in the record (got $zs)" [ "$zs" -eq 80 ]

# 2. a hard limit mid-job
printf 'G21 G90\nG1 X60 F1200\n' >"$T/x60.gcode"
g stream trip "$T/x60.gcode" >"$T/trip.out" 2>"$T/trip.err"; rc=$?
expect "trip: exit 7 (got $rc)" [ $rc -eq 7 ]
expect "trip: ALARM:1 naming x max, stopped at -45" grep -q \
    'ALARM:1 (hard limit: a limit switch tripped), inputs 0x010, stopped at -45.0000 0.0000 0.0000 mm' \
    "$T/trip.out"
read -r n s < <(rises x "$T/trip.csv")
expect "trip: 4320 x rises (got $n)" [ "$n" -eq 4320 ]
expect "trip: all in +x (sum $s)" [ "$s" -eq 4320 ]
late=$(after_nth x 4320 "$T/trip.csv")
expect "trip: no step after the trip (got $late)" [ "$late" -eq 0 ]
expect "trip: STEP and ENABLE left low" [ "$(awk -F, '$3 == "enable" { v = $4 } END { print v }' \
    "$T/trip.csv")" = 0 ]
g stream trip2 "$T/x60.gcode" >"$T/t2.out" 2>"$T/t2.err"; rc=$?
expect "in alarm: the next job refused, exit 7 (got $rc)" [ $rc -eq 7 ]
expect "in alarm: says how to clear it" grep -q 'the machine is in alarm (ALARM:1.*curvestep unlock --gpio' \
    "$T/t2.err"
expect "in alarm: no edge made" [ ! -e "$T/trip2.csv" ]
g jog jog0 --feed 10 -- -60 0 0 >"$T/j0.out" 2>&1; rc=$?
expect "in alarm: a jog refused, exit 7 (got $rc)" [ $rc -eq 7 ]
g unlock u1 >"$T/u1.out" 2>&1; rc=$?
expect "unlock: exit 0 with the switch still pressed (got $rc)" [ $rc -eq 0 ]
g jog jog1 --feed 40 -- -60 0 0 >"$T/j1.out" 2>&1; rc=$?
expect "after unlock: a jog back runs (got $rc)" [ $rc -eq 0 ]
expect "after unlock: at -60" grep -q '^jog: machine position -60.0000 0.0000 0.0000 mm$' "$T/j1.out"

# 3. the e-stop: pressed before a job (no step), then mid-job (a job along y: no switch there)
printf 'G21 G90\nG1 Y50 F120\n' >"$T/y50.gcode"
touch "$T/es0.csv.estop"
g stream es0 "$T/y50.gcode" >"$T/es0.out" 2>"$T/es0.err"; rc=$?
expect "e-stop pressed: exit 7 (got $rc)" [ $rc -eq 7 ]
expect "e-stop pressed: ALARM:10" grep -q 'ALARM:10 (e-stop pressed), inputs 0x200' "$T/es0.out"
read -r n _ < <(rises y "$T/es0.csv")
expect "e-stop pressed: no step made (got $n)" [ "$n" -eq 0 ]
g unlock es0 >"$T/u2.out" 2>&1; rc=$?
expect "unlock refused while the e-stop is pressed (got $rc)" [ $rc -eq 7 ]
rm -f "$T/es0.csv.estop"
g unlock es0 >"$T/u3.out" 2>&1; rc=$?
expect "unlock after the release (got $rc)" [ $rc -eq 0 ]
g stream es1 "$T/y50.gcode" >"$T/es1.out" 2>"$T/es1.err" &
SPID=$!
pids+=($SPID)
wait_until 60 grep -q 'segments executed' "$T/es1.err"
expect "mid-job: progress seen" grep -q 'segments executed' "$T/es1.err"
touch "$T/es1.csv.estop"
wait_until 60 gone $SPID
wait $SPID; rc=$?
expect "mid-job e-stop: exit 7 (got $rc)" [ $rc -eq 7 ]
read -r n s < <(rises y "$T/es1.csv")
want=$(awk -v s="$s" 'BEGIN { printf "%.4f", s / 80 }')
expect "mid-job e-stop: stopped short of the job's 4000 y steps (got $n)" [ "$n" -gt 0 ] && [ "$n" -lt 4000 ]
expect "mid-job e-stop: reports the record's position (y $want)" grep -q \
    "ALARM:10 (e-stop pressed), inputs 0x200, stopped at -60.0000 $want 0.0000 mm" "$T/es1.out"
rm -f "$T/es1.csv.estop"
g unlock u4 >/dev/null 2>&1

# 4. probing
g probe p1 --feed 2 -- -60 0 -10 >"$T/p1.out" 2>&1; rc=$?
expect "probe: exit 0 (got $rc)" [ $rc -eq 0 ]
expect "probe: contact at z = -4" grep -q '^probe: contact at -60.0000 .* -4.0000 mm$' "$T/p1.out"
read -r n s < <(rises z "$T/p1.csv")
expect "probe: 320 z steps down in the record (got $n, $s)" [ "$n" -eq 320 ] && [ "$s" -eq -320 ]
g jog j2 --feed 10 -- -60 0 -1 >/dev/null 2>&1
g probe p3 --feed 5 --no-error -- -60 0 -2 >"$T/p3.out" 2>&1; rc=$?
expect "G38.3 without contact: exit 0 (got $rc)" [ $rc -eq 0 ]
expect "G38.3: says no contact" grep -q '^probe: no contact; ended at -60.0000 .* -2.0000 mm$' "$T/p3.out"
g probe p2 --feed 5 -- -60 0 -1.5 >"$T/p2.out" 2>&1; rc=$?
expect "G38.2 without contact: exit 7 (got $rc)" [ $rc -eq 7 ]
expect "G38.2: ALARM:5" grep -q '^probe: ALARM:5 ' "$T/p2.out"

# 5. the [gpio] input keys checked
bad() { # bad NAME KEYS REGEX
    printf '[gpio]\nx_step = 17\nx_dir = 27\n%b' "$2" >"$T/bad.ini"
    "$CS" stream --gpio record:"$T/bad.csv" --machine "$T/bad.ini" "$T/x60.gcode" >/dev/null \
        2>"$T/bad.err"
    local r=$?
    expect "$1: exit 1 (got $r)" [ $r -eq 1 ]
    expect "$1: the reason" grep -qE "$3" "$T/bad.err"
}
bad "a switch on a STEP line" 'x_min = 17\n' 'bad.ini:4: \[gpio\] x_min: line 17 is already x_step'
bad "the probe on the e-stop's line" 'estop = 3\nprobe = 3\n' 'bad.ini:5: \[gpio\] probe: line 3 is already estop'
bad "a switch of no axis" 'a_max = 4\n' 'bad.ini:0: \[gpio\] a_max: the machine has no a axis'
bad "a bad polarity" 'limit_active_low = maybe\n' 'bad.ini:4: \[gpio\] limit_active_low: expected true or false'

# 6. the command line and the machine file: a chip that is not there (exit 4, named), --port and
# --gpio together (exit 2), a [homing] switch the recorder has no [limits] for (exit 1)
run "home on a missing chip" 4 home --gpio gpiochip9 --machine "$M"
expect_err "home on a missing chip: named" 'cannot open GPIO chip gpiochip9'
run "--port and --gpio" 2 unlock --port /dev/null --gpio record:"$T/u.csv"
expect_err "--port and --gpio: said" 'exclude each other'
grep -v '^x_min = -5$' "$M" >"$T/nox.ini"
run "home without the x min switch" 1 home --gpio record:"$T/nx.csv" --machine "$T/nox.ini"
expect_err "home without the x min switch: said" 'wires no x_min'

finish
