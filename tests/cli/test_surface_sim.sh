#!/usr/bin/env bash
# Surface tool paths run by the simulator: `curvestep toolpath --gcode` writes the wireframe
# (projected X Y, pen lifted with M5 for travel) and the ball-end finishing path (tool centre
# X Y Z) as G-code; `curvestep plan` turns it into step segments and
# `curvestep-sim --replay --reference --check --view` executes them and draws the result.
# Checks: the G-code says what the text output says (one G0 per polyline, G1 for every other
# vertex, same coordinates; pen up for every travel), the simulated final position is the path's
# last vertex rounded to steps, the simulator executes exactly the steps plan wrote, the
# deviation check passes, pictures exist, and every point drawn as travel lies on a G0 move of
# the job. Usage errors of the new options. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
need_bin "$CS" "$SIM"

SPM=80 # steps per mm of the simulator's default machine (host/cs_machine_ini.c)

# A bicubic dome over 30 x 30 mm (native format): control points on a grid, raised inside.
{
    echo "curvestep-surfaces 1"
    echo "bezier 3 3"
    for i in 0 1 2 3; do
        for j in 0 1 2 3; do
            z=0
            if [ $i -gt 0 ] && [ $i -lt 3 ] && [ $j -gt 0 ] && [ $j -lt 3 ]; then z=6; fi
            echo "$((10 * i + 5)) $((10 * j + 5)) $z"
        done
    done
} >"$T/dome.txt"

# G-code vs text: one G0 per polyline (blank-line separated), G1 for the other vertices, the same
# numbers in the same order ($3 = number of columns; with 3, the finishing path, each block's last
# vertex, the retract, is a G0 too).
same_path() { # same_path TEXT GCODE COLUMNS
    awk -v cols="$3" '
        FNR == NR { if (NF == 0) { brk = 1; if (cols == 3) kind[n] = "G0"; next }
                    n++; kind[n] = (n == 1 || brk) ? "G0" : "G1"; brk = 0
                    v[n] = $1 " " $2 (cols == 3 ? " " $3 : ""); next }
        /^G[01] / { k++; w = substr($2, 2) " " substr($3, 2) (cols == 3 ? " " substr($4, 2) : "")
                    if (k > n || $1 != kind[k] || w != v[k]) bad++ }
        END { exit !(n > 0 && k == n && !bad) }' <(cat "$1"; [ "$3" = 3 ] && echo) "$2"
}

# The last vertex of a text path rounded to steps, as the simulator prints its final position.
want_final() { # want_final TEXT COLUMNS
    awk -v s=$SPM -v cols="$2" 'NF { x = $1; y = $2; z = (cols == 3 ? $3 : 0) }
        function r(v) { return v < 0 ? -int(-v * s + 0.5) : int(v * s + 0.5) }
        END { printf "x=%d steps y=%d steps z=%d steps\n", r(x), r(y), r(z) }' "$1"
}
got_final() { # from the simulator's report
    sed -n 's/^final position: x=\([-0-9]*\) steps ([^)]*) y=\([-0-9]*\) steps ([^)]*) z=\([-0-9]*\) steps.*/x=\1 steps y=\2 steps z=\3 steps/p' "$1"
}

# Every point of the SVG's travel polylines (view top: picture x, -y) within 0.2 mm of a G0 move of
# the job (from the previous position to the G0's target, in x y); prints the number of travel
# polylines and of G0 moves of nonzero length.
travel_on_g0() { # travel_on_g0 GCODE SVG
    awk '
        function d2seg(px, py, ax, ay, bx, by,   ex, ey, l, t) {
            ex = bx - ax; ey = by - ay; l = ex * ex + ey * ey
            t = l > 0 ? ((px - ax) * ex + (py - ay) * ey) / l : 0
            t = t < 0 ? 0 : t > 1 ? 1 : t
            return (px - ax - t * ex) ^ 2 + (py - ay - t * ey) ^ 2 }
        FNR == NR { if ($1 != "G0" && $1 != "G1") next
                    nx = cx; ny = cy
                    for (i = 2; i <= NF; i++) { c = substr($i, 1, 1); val = substr($i, 2) + 0
                                                if (c == "X") nx = val; if (c == "Y") ny = val }
                    if ($1 == "G0" && (nx != cx || ny != cy)) {
                        g++; ax[g] = cx; ay[g] = cy; bx[g] = nx; by[g] = ny }
                    cx = nx; cy = ny; next }
        /class="travel"/ { runs++
            s = $0; sub(/.*points="/, "", s); sub(/".*/, "", s)
            m = split(s, pts, " ")
            for (i = 1; i <= m; i++) { split(pts[i], q, ","); px = q[1]; py = -q[2]; best = 1e9
                for (j = 1; j <= g; j++) { d = d2seg(px, py, ax[j], ay[j], bx[j], by[j])
                                            if (d < best) best = d }
                if (best > 0.04) off++ } }
        END { printf "%d %d %d\n", runs, g, off + 0 }' "$1" "$2"
}

# 1. wireframe: G-code, plan, simulated run with the reference, top view (the job is 2D).
run "wireframe --gcode" 0 toolpath --patches "$T/dome.txt" --lines 2 --view iso \
    --gcode "$T/w.nc"
cp "$T/out" "$T/w.txt"
expect "wireframe G-code header" grep -q '^G21 G90$' "$T/w.nc"
expect "wireframe G-code = text path" same_path "$T/w.txt" "$T/w.nc" 2
expect "wireframe G-code: pen up (M5) for every G0, down (M3) for every G1" awk '
    $1 == "M3" { pen = 1 } $1 == "M5" { pen = 0 }
    $1 == "G0" && pen { bad++ } $1 == "G1" && !pen { bad++ } $1 == "G1" { g1++ }
    $1 == "M2" && pen { bad++ }
    END { exit !(g1 > 0 && !bad) }' "$T/w.nc"
"$CS" plan -o "$T/w.seg" "$T/w.nc" 2>"$T/plan.txt"; rc=$?
expect "plan wireframe exit 0" [ $rc -eq 0 ]
"$SIM" --replay "$T/w.seg" --reference "$T/w.nc" --check --view top --svg "$T/w.svg" \
    --png "$T/w.png" >"$T/sim.txt" 2>&1; rc=$?
expect "sim wireframe exit 0" [ $rc -eq 0 ]
expect "sim wireframe check ok" grep -q '^check: ok$' "$T/sim.txt"
expect "sim wireframe deviation ok" grep -qE '^deviation: [0-9.]+ mm .* ok$' "$T/sim.txt"
expect "wireframe final position = last vertex" [ "$(got_final "$T/sim.txt")" = "$(want_final "$T/w.txt" 2)" ]
ps=$(sed -n 's/.* \([0-9]*\) steps, job time.*/\1/p' "$T/plan.txt")
ss=$(sed -n 's/^replay: [0-9]* segments, \([0-9]*\) steps.*/\1/p' "$T/sim.txt")
expect "wireframe: sim executes plan's steps ($ps = $ss)" [ -n "$ps" ] && [ "$ps" = "$ss" ]
expect "wireframe svg picture" grep -q 'view top' "$T/w.svg"
expect "wireframe png picture" bash -c "head -c 8 '$T/w.png' | od -An -c | grep -q 'P   N   G'"
read -r runs g0 off <<<"$(travel_on_g0 "$T/w.nc" "$T/w.svg")"
expect "wireframe: one travel line per G0 move ($runs, $g0)" [ "$runs" -eq "$g0" ] && [ "$g0" -gt 3 ]
expect "wireframe: every travel point on a G0 move ($off off)" [ "$off" -eq 0 ]

# 2. finishing: the tool centre in 3D, iso view.
run "finishing --gcode" 0 toolpath --patches "$T/dome.txt" --ball 3 --scallop 0.3 --safe-z 20 \
    --gcode "$T/f.nc"
cp "$T/out" "$T/f.txt"
expect "finishing G-code starts at the safe height" [ "$(grep -m1 '^G0' "$T/f.nc")" = "G0 Z20.000000" ]
grep -v '^G0 Z20.000000$' "$T/f.nc" >"$T/f2.nc"
expect "finishing G-code = text path" same_path "$T/f.txt" "$T/f2.nc" 3
expect "finishing ends with a G0 retract to the safe height" \
    bash -c "grep '^G[01]' '$T/f.nc' | tail -n1 | grep -q '^G0 .* Z20.000000$'"
"$CS" plan -o "$T/f.seg" "$T/f.nc" 2>"$T/plan.txt"; rc=$?
expect "plan finishing exit 0" [ $rc -eq 0 ]
"$SIM" --replay "$T/f.seg" --reference "$T/f.nc" --check --view iso --svg "$T/f.svg" \
    --png "$T/f.png" >"$T/sim.txt" 2>&1; rc=$?
expect "sim finishing exit 0" [ $rc -eq 0 ]
expect "sim finishing check ok" grep -q '^check: ok$' "$T/sim.txt"
expect "finishing final position = last vertex" [ "$(got_final "$T/sim.txt")" = "$(want_final "$T/f.txt" 3)" ]
ps=$(sed -n 's/.* \([0-9]*\) steps, job time.*/\1/p' "$T/plan.txt")
ss=$(sed -n 's/^replay: [0-9]* segments, \([0-9]*\) steps.*/\1/p' "$T/sim.txt")
expect "finishing: sim executes plan's steps ($ps = $ss)" [ -n "$ps" ] && [ "$ps" = "$ss" ]
expect "finishing svg: iso view, travel drawn apart" \
    bash -c "grep -q 'view iso' '$T/f.svg' && grep -q 'class=\"travel\"' '$T/f.svg'"
expect "finishing png picture" bash -c "head -c 8 '$T/f.png' | od -An -c | grep -q 'P   N   G'"

# 3. errors.
"$SIM" --replay "$T/f.seg" --view sideways >"$T/out" 2>"$T/err"; rc=$?
expect "sim --view bad: exit 2" [ $rc -eq 2 ]
expect_err "sim --view bad: message" 'view wants top, front, side or iso'
run "toolpath --gcode unwritable: exit 3" 3 toolpath --patches "$T/dome.txt" --gcode "$T/no/such/dir.nc"
expect_err "toolpath --gcode unwritable: message" 'cannot write the G-code'
run "toolpath --help mentions --gcode" 0 toolpath --help
expect "help text" grep -q -- '--gcode OUT.nc' "$T/out"

finish
