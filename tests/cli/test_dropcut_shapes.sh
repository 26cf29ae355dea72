#!/usr/bin/env bash
# Drop-cutter finishing (`curvestep toolpath --cutter`, issue 20) on a teacup-like surface of
# revolution (an outer wall, a rounded rim, an inner wall and a bottom: steep inside and out) and
# on an n-sided (Varady) patch: every strategy is gouge-free by the independent --check, raster,
# waterline and raster+waterline leave at most H for every cutter, and the G-code plans on the
# router and passes the simulator's check; and the check's own measures against hand formulas
# (the cusp of ball passes over a plane, the rest material in a V groove). Coarse H and tol on small parts
# keep it to seconds of CPU; the teapot's figures are in the benchmark (tests/bench/bench_dropcut.c).
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
need_bin "$CS" "$SIM"
M=contrib/machines/router-3018.ini

. "$(dirname "${BASH_SOURCE[0]}")/lib/shapes.sh"
cs_shape_cup "$T/cup.txt"    # the teacup (lib/shapes.sh): walls steep inside and out, flat bottom
cs_shape_pent "$T/pent.txt"  # the five-sided Varady patch, halved
expect "teacup: 16 bicubic patches" [ "$(grep -c '^bezier 3 3' "$T/cup.txt")" = 16 ]

# gouge <= tol and (unless "any") scallop <= H, from the check's line in $T/err.
gs() {
    local name=$1 h=$2 g
    g=$(sed -n 's/.*gouge \([0-9.]*\) mm, scallop \([0-9.]*\) mm.*/\1 \2/p' "$T/err")
    expect "$name: gouge <= 0.02, scallop <= $h ($g)" awk -v g="$g" -v h="$h" \
        'BEGIN { split(g, a, " "); exit !(a[1] != "" && a[1] <= 0.02 && (h == "any" || a[2] <= h)) }'
}

for s in cup pent; do
    for c in ball:1.5 flat:1.5 bull:1.5:0.5; do
        run "$s raster+waterline $c" 0 toolpath --patches "$T/$s.txt" --cutter "$c" --scallop 0.1 \
            --tol 0.02 --strategy raster+waterline --check --safe-z 5 --gcode "$T/$s.$c.nc" &&
            gs "$s raster+waterline $c" 0.1
        [ "$c" = ball:1.5 ] && cp "$T/out" "$T/$s.combo.pts"
    done
    run "$s raster ball" 0 toolpath --patches "$T/$s.txt" --cutter ball:1.5 --scallop 0.1 \
        --tol 0.02 --check && gs "$s raster ball" 0.1
    for c in flat:1.5 bull:1.5:0.5; do # the raster's fill-in where its estimate flags rest material
        run "$s raster $c" 0 toolpath --patches "$T/$s.txt" --cutter "$c" --scallop 0.1 \
            --tol 0.02 --check && gs "$s raster $c" 0.1
    done
    # waterline: levels added on shallow ground, flat areas and concave corners by a clipped
    # raster: at most H with every cutter, --check fails (exit 1) otherwise
    for c in ball:1.5 flat:1.5 bull:1.5:0.5; do
        run "$s waterline $c" 0 toolpath --patches "$T/$s.txt" --cutter "$c" --scallop 0.1 \
            --tol 0.02 --strategy waterline --check && gs "$s waterline $c" 0.1
    done
    # the G-code runs on the router as written, and the simulator's check passes
    run "$s: gcode plans on the router" 0 plan --machine "$M" -o "$T/$s.seg" "$T/$s.ball:1.5.nc"
    "$SIM" --replay "$T/$s.seg" --machine "$M" --reference "$T/$s.ball:1.5.nc" --check \
        --trace "$T/$s.trace" >"$T/$s.sim" 2>&1
    expect "$s: simulator check passes" [ $? -eq 0 ]
    expect "$s: simulator final position exact" grep -q 'rounded to steps: exact' "$T/$s.sim"
    # the executed path (every step edge the simulator made) against the surface: within tol
    # and H; the same trace 0.05 mm lower gouges by the executed gouge + 0.05 and fails
    run "$s: executed path checked" 0 toolpath --patches "$T/$s.txt" --cutter ball:1.5 \
        --scallop 0.1 --tol 0.02 --check-trace "$T/$s.trace" && gs "$s executed path" 0.1
    g0=$(sed -n 's/.*gouge \([0-9.]*\) mm.*/\1/p' "$T/err")
    [ "$s" = cup ] || continue
    awk -F, 'NR == 1 { print; next } { printf "%s,%s,%s,%s,%s,%.5f\n", $1, $2, $3, $4, $5, $6 - 0.05 }' \
        "$T/$s.trace" >"$T/low.trace"
    run "$s: executed path 0.05 mm low fails" 1 toolpath --patches "$T/$s.txt" --cutter ball:1.5 \
        --scallop 0.1 --tol 0.02 --check-trace "$T/low.trace"
    g1=$(sed -n 's/.*gouge \([0-9.]*\) mm.*/\1/p' "$T/err")
    expect "$s: lowered 0.05 mm, gouge $g0 -> $g1 (+0.05 +- 0.001)" \
        awk -v a="$g0" -v b="$g1" 'BEGIN { exit !(a != "" && b != "" && b - a > 0.049 && b - a < 0.051) }'
done

# The check's measures against hand formulas. (1) Passes of a ball R, w apart, over a plane leave
# the cusp R - sqrt(R^2 - (w/2)^2) over the midline (z-map nodes lie on it: the map starts R
# before the plane, 0.05 mm apart); the check's cutter positions are at most 0.05 mm apart along
# a pass, so the ray from a node may meet a ball up to 0.025 mm along the pass from its axis:
# at most R - sqrt(R^2 - (w/2)^2 - 0.025^2).
cat >"$T/plane.txt" <<'EOF'
curvestep-surfaces 1
bezier 1 1
  10 10 -15   10 20 -15
  20 10 -15   20 20 -15
EOF
run "plane: ball passes 1 mm apart" 0 toolpath --patches "$T/plane.txt" --cutter ball:1.5 \
    --stepover 1 --scallop 0.2 --tol 0.02 --check
g=$(sed -n 's/.*scallop \([0-9.]*\) mm.*/\1/p' "$T/err")
expect "plane: scallop on the cusp formula 0.085786 .. 0.085995 mm ($g)" awk -v g="$g" \
    'BEGIN { R = 1.5; w = 1; lo = R - sqrt(R * R - w * w / 4); hi = R - sqrt(R * R - w * w / 4 - 0.025 ^ 2)
             exit !(g != "" && g >= lo - 1e-6 && g <= hi + 1e-6) }'
# (2) A 90-degree V groove (z = |x - 15| - 15): a ball R rests on both flanks, its centre
# R sqrt 2 above the valley, which keeps R (sqrt 2 - 1) of rest material there (the deepest
# unreachable node); the flanks stay more than H from that ball where
# sqrt(x^2 + (R sqrt 2 - x)^2) > R + H, |x| < (R sqrt 2 - sqrt(2 (R + H)^2 - 2 R^2)) / 2 = 0.667:
# 27 node columns (+-2) along the valley's interior (its 10 mm less R at each end: 139 to 143
# rows).
cat >"$T/vee.txt" <<'EOF'
curvestep-surfaces 1
bezier 1 1
  10 10 -10   10 20 -10
  15 10 -15   15 20 -15
bezier 1 1
  15 10 -15   15 20 -15
  20 10 -10   20 20 -10
EOF
run "vee: raster ball" 0 toolpath --patches "$T/vee.txt" --cutter ball:1.5 --scallop 0.1 \
    --tol 0.02 --check && gs "vee raster ball" 0.1
v=$(sed -n 's/.*unreachable: \([0-9]*\) nodes.*up to \([0-9.]*\) mm of rest.*/\1 \2/p' "$T/err")
expect "vee: rest R (sqrt 2 - 1) = 0.6213 mm at the valley, 0.667 mm each side ($v)" \
    awk -v v="$v" 'BEGIN { split(v, a, " "); R = 1.5; H = 0.1; d = a[2] - R * (sqrt(2) - 1)
        cols = 2 * int((sqrt(2) * R - sqrt(2 * (R + H) ^ 2 - 2 * R * R)) / 2 / 0.05) + 1
        exit !(a[2] != "" && d <= 0.001 && d >= -0.002 && a[1] >= (cols - 2) * 139 &&
               a[1] <= (cols + 2) * 143) }'

# The combination serves both: raster passes (z varies along them) and waterline contours
# (constant z) over the cup's walls.
kinds=$(awk 'NF == 0 { if (n > 2) { if (hi - lo < 1e-9) w++; else r++ } n = 0; next }
    { if (!n) { lo = $3; hi = $3 } lo = $3 < lo ? $3 : lo; hi = $3 > hi ? $3 : hi; n++ }
    END { if (n > 2) { if (hi - lo < 1e-9) w++; else r++ } print r + 0, w + 0 }' "$T/cup.combo.pts")
expect "cup raster+waterline: raster and level passes ($kinds)" \
    bash -c "set -- $kinds; [ \$1 -ge 1 ] && [ \$2 -gt 5 ]"
# Over the cup's flat inner bottom (z = -19 within 3 mm of the axis) a ball of radius 1.5 whose
# axis is within 1.4 mm of the axis (its rim 2.9 mm out) rests on it: its tip is at -19 (the mesh bound adds at most
# 2 eps = tol / 2).
bot=$(awk 'NF == 3 && ($1 - 15) ^ 2 + ($2 - 15) ^ 2 < 1.96 { m++; if ($3 < -19 - 1e-9 || $3 > -19 + 0.01) bad++ }
    END { print bad + 0, m + 0 }' "$T/cup.combo.pts")
expect "cup: tips over the flat bottom at z = -19 ($bot: bad, checked)" \
    bash -c "set -- $bot; [ \$1 = 0 ] && [ \$2 -gt 20 ]"
finish
