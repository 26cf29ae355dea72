#!/usr/bin/env bash
# Command-line tests of pen lifts ([pen] mode = z) for every input kind and of the simulator's
# pen-aware check: each job planned on a z-pen machine, the segments read back independently (an
# awk replay of the step counts) to count the pen lowerings against the strokes the input
# draws, to show that the pen moves only vertically and that x y never moves between the heights;
# the simulator's --check passes on those plans and fails, naming the segment, on a plan that
# travels pen down and on one that moves pen up over a stroke. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
need_bin "$CS" "$SIM"

cat >"$T/zpen.ini" <<'INI'
[pen]
mode = z
up_z = 5
down_z = 1
z_feed = 20
INI
# Three strokes (two paths, one circle); four with the second subpath of the first path.
cat >"$T/job.svg" <<'SVG'
<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" viewBox="0 0 100 100">
<path fill="none" stroke="black" d="M10 10 L50 10 L50 50 M55 55 L58 58"/>
<path fill="none" stroke="black" d="M60 60 C70 80 80 40 90 60"/>
<circle fill="none" stroke="black" cx="30" cy="70" r="10"/>
</svg>
SVG
# Two strokes: a square's three sides (one PD with three points) and one line; PU in between.
printf 'IN;SP1;PU400,400;PD2000,400,2000,2000,400,2000;PU3000,400;PD3000,2000;PU0,0;SP0;\n' \
    >"$T/job.plt"
# G-code: M3 lowers, M5 raises: two strokes.
printf 'G21 G90\nG0 X10 Y10\nM3\nG1 X40 Y10 F1000\nG1 X40 Y40\nM5\nG0 X60 Y10\nM3\nG1 X80 Y30\nM5\nG0 X0 Y0\n' \
    >"$T/job.nc"

# replay SEGMENTS: one line per segment "sx sy sz" (position in steps after it) and its deltas.
# Checks: z moves never move x y; x y moves only at the down height (80 steps/mm * 1 mm = 80)
# or at the up height (400); prints the number of pen lowerings (z arriving at 80 from above).
replay() {
    awk -v down=80 -v up=400 '
        /^#/ {next}
        { dx = $2; dy = $3; dz = $4; x += dx; y += dy; z += dz
          if (dz != 0 && (dx != 0 || dy != 0)) bad = bad " diagonal@" NR
          if ((dx != 0 || dy != 0) && z != down && z != up && z != 0) bad = bad " between@" NR
          if (dz < 0 && z == down) lowers++ }
        END { if (bad != "") print "BAD" bad; else print lowers + 0 }' "$1"
}

for kind in svg plt nc; do
    want=$([ $kind = svg ] && echo 4 || echo 2)
    run "$kind plan" 0 plan --machine "$T/zpen.ini" "$T/job.$kind" -o "$T/$kind.seg"
    got=$(replay "$T/$kind.seg")
    expect "$kind: $want pen lowerings, z moves vertical, x y only at a pen height (got $got)" \
        [ "$got" = "$want" ]
    "$SIM" --replay "$T/$kind.seg" --machine "$T/zpen.ini" --reference "$T/job.$kind" --check \
        >"$T/$kind.sim" 2>/dev/null
    expect "$kind: simulator check passes" grep -q '^check: ok$' "$T/$kind.sim"
    expect "$kind: check reports pen-down motion" grep -q '^deviation of pen-down motion' "$T/$kind.sim"
done
# The pen moves at [pen] z_feed (20 mm/s) for every input, G-code's M3/M5 included: the fastest
# z-only segment, |dz| steps / 80 steps/mm over its ticks / tick_hz, is at most z_feed plus one
# step's worth of that segment (rounding), and the pen does move at speed (above 10 mm/s).
zpeak() {
    awk '/^# curvestep segments/ { for (i = 1; i <= NF; i++) if ($i ~ /^tick_hz=/) hz = substr($i, 9) }
         !/^#/ && !/^pen/ && $2 == 0 && $3 == 0 && $4 != 0 && $1 > 0 {
             dz = $4 < 0 ? -$4 : $4; v = (dz - 1) / 80 / ($1 / hz); if (v > m) m = v }
         END { printf "%.3f\n", m }' "$1"
}
for kind in svg plt nc; do
    v=$(zpeak "$T/$kind.seg")
    expect "$kind: z peak velocity $v mm/s within (10, 20] (z_feed)" \
        awk -v v="$v" 'BEGIN { exit !(v > 10 && v <= 20) }'
done

# The SVG job lies at z = 0 in the file: every drawn element is at down_z, so the plan ends up.
expect "svg ends pen up" grep -q 'rounded to steps: exact' "$T/svg.sim"

# Without a pen the plan never lifts: checked against the z-pen machine it draws its travels.
run "plan without pen" 0 plan "$T/job.svg" -o "$T/nopen.seg"
"$SIM" --replay "$T/nopen.seg" --machine "$T/zpen.ini" --reference "$T/job.svg" --check \
    >"$T/nopen.sim" 2>/dev/null; rc=$?
expect "pen-down travel fails the check (exit 4)" [ $rc -eq 4 ]
expect "pen-down travel named with its segment" \
    grep -qE '^deviation of pen-down motion .*, segment [1-9][0-9]* .*OVER: a pen-down travel$' "$T/nopen.sim"

# A plan that travels pen up over a stroke the reference draws: two strokes planned, checked
# against one straight line through both (the gap between them is drawn in the reference).
printf '<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" viewBox="0 0 100 100"><path fill="none" stroke="black" d="M10 10 L20 10 M30 10 L40 10"/></svg>\n' >"$T/gap.svg"
printf '<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" viewBox="0 0 100 100"><path fill="none" stroke="black" d="M10 10 L40 10"/></svg>\n' >"$T/line.svg"
run "plan gap" 0 plan --machine "$T/zpen.ini" "$T/gap.svg" -o "$T/gap.seg"
"$SIM" --replay "$T/gap.seg" --machine "$T/zpen.ini" --reference "$T/line.svg" --check \
    >"$T/gap.sim" 2>/dev/null; rc=$?
expect "pen-up stroke fails the check (exit 4)" [ $rc -eq 4 ]
expect "pen-up stroke named with its segment" \
    grep -qE '^pen: segment [1-9][0-9]* moves pen up over a stroke the job draws$' "$T/gap.sim"

# A G-code pen-z job checked with its pen: right, so it passes (it failed at 5 mm before).
"$SIM" --replay "$T/nc.seg" --machine "$T/zpen.ini" --reference "$T/job.nc" --check \
    >/dev/null 2>&1
expect "gcode pen job passes" [ $? -eq 0 ]

# [pen] mode = servo: "pen US" lines in the segments; each followed by the settle wait (100 ms =
# 10000 ticks, no steps); x y moves only after a pen event (the first one raises the pen);
# lowerings counted as for z.
printf '[pen]\nmode = servo\nup_us = 1900\ndown_us = 1200\nsettle_ms = 100\n' >"$T/servo.ini"
servo_replay() {
    awk '/^#/ {next}
        /^pen / { pen = $2; if (pen == 1200) lowers++; wait = 1; next }
        { if (wait && !($1 == 10000 && $2 == 0 && $3 == 0 && $4 == 0)) bad = bad " settle@" NR
          if (!wait && pen == "" && ($2 != 0 || $3 != 0)) bad = bad " before-pen@" NR
          if ($4 != 0) bad = bad " z@" NR
          wait = 0 }
        END { if (bad != "") print "BAD" bad; else print lowers + 0 }' "$1"
}
for kind in svg plt nc; do
    want=$([ $kind = svg ] && echo 4 || echo 2)
    run "$kind servo plan" 0 plan --machine "$T/servo.ini" "$T/job.$kind" -o "$T/$kind.sv"
    got=$(servo_replay "$T/$kind.sv")
    expect "$kind servo: $want pen lowerings, each followed by its settle wait (got $got)" \
        [ "$got" = "$want" ]
    expect "$kind servo: ends with the pen raised" [ "$(grep '^pen' "$T/$kind.sv" | tail -n1)" = "pen 1900" ]
    "$SIM" --replay "$T/$kind.sv" --machine "$T/servo.ini" --reference "$T/job.$kind" --check \
        >"$T/$kind.svsim" 2>/dev/null
    expect "$kind servo: simulator check passes" grep -q '^check: ok$' "$T/$kind.svsim"
done
"$SIM" --replay "$T/nopen.seg" --machine "$T/servo.ini" --reference "$T/job.svg" --check \
    >"$T/svbad.sim" 2>/dev/null; rc=$?
expect "servo: a plan without pen events fails the check" [ $rc -eq 4 ]
expect "servo: names the segment" grep -qE '^pen: segment [0-9]+ moves pen up over a stroke' "$T/svbad.sim"
# Every link carries pen events, in segments and curves mode: test_servo_stream.sh (serial,
# daemon), test_servo_links.sh (Modbus, curves), test_gpio_pen.sh (GPIO, software PWM).
printf '[pen]\nmode = servo\nup_us = 1900\n' >"$T/bad2.ini"
run "servo needs both widths" 1 plan --machine "$T/bad2.ini" "$T/job.svg"
expect_err "servo needs both widths: says so" 'mode = servo needs up_us and down_us'

# End to end: a page with a frame and text (drawn in the stroke font: many small strokes) on the
# contrib servo A4 and z-pen machines plans, and the simulator's pen check passes with one
# lowering per stroke: the frame, and each stroke of the glyphs ("Hi." is H: 3, i: 2, '.': 1).
cat >"$T/text.svg" <<'SVG'
<svg xmlns="http://www.w3.org/2000/svg" width="297mm" height="210mm" viewBox="0 0 297 210">
<rect fill="none" stroke="black" x="20" y="20" width="100" height="50"/>
<text x="148.5" y="120" font-size="20" text-anchor="middle" transform="rotate(-5 148.5 120)">Hi.</text>
</svg>
SVG
for mc in servo-a4 zpen-plotter; do
    run "text on $mc" 0 plan --machine contrib/machines/$mc.ini "$T/text.svg" -o "$T/text.seg"
    "$SIM" --replay "$T/text.seg" --machine contrib/machines/$mc.ini --reference "$T/text.svg" \
        --check >"$T/text.sim" 2>/dev/null
    expect "text on $mc: check passes" grep -q '^check: ok$' "$T/text.sim"
    expect "text on $mc: 7 pen lowerings" grep -q '^pen: 7 pen-downs' "$T/text.sim"
done

# [pen] z_feed is checked.
printf '[pen]\nmode = z\nup_z = 5\ndown_z = 0\nz_feed = -1\n' >"$T/bad.ini"
run "bad z_feed" 1 plan --machine "$T/bad.ini" "$T/job.svg"
expect_err "bad z_feed located" 'bad.ini:5: \[pen\] z_feed: must be a speed'

finish
