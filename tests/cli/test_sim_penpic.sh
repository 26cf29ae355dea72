#!/usr/bin/env bash
# The simulator's pictures draw the run's own pen (sim/cs_sim_draw.c, cs_sim_draw_*_pen): pen-up
# travel as dashed grey polylines of class "travel", one per pen-up stretch that moves in x y,
# pen-down motion coloured by speed, and each servo setting marked (circles of class "pen-down"
# and "pen-up"). contrib/examples/plotter.svg is planned on the servo-pen and the z-pen machines
# and replayed with --svg and --png; the counts are taken from the segments file independently
# (awk): servo marks = the "pen US" lines of each width; travel polylines = pen-up stretches (after
# a raise: a "pen UP_US" line, or z arriving nearer up_z than down_z) with x y steps before the
# pen comes down again. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
need_bin "$CS" "$SIM"
JOB=contrib/examples/plotter.svg
ini() { sed -n "/^\\[$2\\]/,/^\\[/s/^$3 *= *\\([-0-9.]*\\).*/\\1/p" "$1" | head -n1; }

# servo
MC=contrib/machines/servo-a4.ini
up=$(ini "$MC" pen up_us)
down=$(ini "$MC" pen down_us)
run "servo: plan" 0 plan --machine "$MC" "$JOB" -o "$T/s.seg"
"$SIM" --replay "$T/s.seg" --machine "$MC" --reference "$JOB" --svg "$T/s.svg" --png "$T/s.png" \
    >"$T/s.out" 2>&1
expect "servo: replay exit 0" [ $? -eq 0 ]
nd=$(grep -c "^pen $down\$" "$T/s.seg")
nu=$(grep -c "^pen $up\$" "$T/s.seg")
trav=$(awk -v up="$up" '/^pen / { if (penup && moved) n++; penup = ($2 == up); moved = 0; next }
                        /^#/ { next } { if ($2 != 0 || $3 != 0) moved = 1 }
                        END { if (penup && moved) n++; print n + 0 }' "$T/s.seg")
expect "servo: $nd pen-down marks" [ "$(grep -c 'class="pen-down"' "$T/s.svg")" = "$nd" ]
expect "servo: $nu pen-up marks" [ "$(grep -c 'class="pen-up"' "$T/s.svg")" = "$nu" ]
expect "servo: $trav pen-up travel polylines" \
    [ "$(grep -c '<polyline class="travel"' "$T/s.svg")" = "$trav" ]
expect "servo: some travel ($trav)" [ "$trav" -gt 2 ]
expect "servo: PNG written" [ -s "$T/s.png" ]

# z pen: the same stretches by the z height
MZ=contrib/machines/zpen-plotter.ini
spm=$(ini "$MZ" z steps_per_mm)
uz=$(ini "$MZ" pen up_z)
dz=$(ini "$MZ" pen down_z)
run "z: plan" 0 plan --machine "$MZ" "$JOB" -o "$T/z.seg"
"$SIM" --replay "$T/z.seg" --machine "$MZ" --reference "$JOB" --svg "$T/z.svg" >"$T/z.out" 2>&1
expect "z: replay exit 0" [ $? -eq 0 ]
trav=$(awk -v spm="$spm" -v uz="$uz" -v dz="$dz" '
    /^#/ || /^pen/ { next }
    { z += $4; mm = z / spm; isup = (mm - uz) ^ 2 < (mm - dz) ^ 2
      if (isup && !penup) moved = 0
      if (!isup && penup && moved) n++
      penup = isup; if (isup && ($2 != 0 || $3 != 0)) moved = 1 }
    END { if (penup && moved) n++; print n + 0 }' "$T/z.seg")
expect "z: $trav pen-up travel polylines" \
    [ "$(grep -c '<polyline class="travel"' "$T/z.svg")" = "$trav" ]
expect "z: some travel ($trav)" [ "$trav" -gt 2 ]
expect "z: no servo marks" [ "$(grep -cE 'class="pen-(up|down)"' "$T/z.svg")" = 0 ]
finish
