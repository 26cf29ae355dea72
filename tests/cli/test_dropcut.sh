#!/usr/bin/env bash
# Drop-cutter finishing (`curvestep toolpath --cutter`, issue 20) on a tilted plane, where the
# exact answer is known by hand: a ball of radius R resting on z = m y + c stands with its tip at
# m y + c + R (sqrt(1 + m^2) - 1) wherever it touches the plane inside its edges. Also: the
# independent --check (gouge and scallop) on every cutter, G-code a machine runs as written (F on
# every feed move, spindle words), planned and simulated on the 3018 router, --output centre,
# and bad command lines.
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
need_bin "$CS" "$SIM"

# z = 0.5 y - 14.5 over x, y in [5, 25] (z from -12 to -2: the router's z travel is -40..10).
cat >"$T/slope.txt" <<'EOF'
curvestep-surfaces 1
bezier 1 1
  5 5 -12   5 25 -2
  25 5 -12  25 25 -2
EOF

# 1. A ball: every interior tip on the hand formula, the check passes, G-code written.
run "ball slope" 0 toolpath --patches "$T/slope.txt" --cutter ball:2 --scallop 0.05 --check \
    --stats --safe-z 5 --spindle 12000 --no-link --gcode "$T/ball.nc"
cp "$T/out" "$T/ball.pts"
cp "$T/err" "$T/ball.err"
# The contact is R m / sqrt(1 + m^2) = 0.894 mm uphill of the axis: inside the plane for axis
# y in [5, 24.1] and x in [5, 25] (a ball reaching past x = 5 or 25 touches the side edge first).
bad=$(awk 'NF == 3 && $1 >= 5 && $1 <= 25 && $2 >= 5 && $2 <= 24 {
    want = 0.5 * $2 - 14.5 + 2 * (sqrt(1.25) - 1); d = $3 - want; if (d < 0) d = -d;
    if (d > 1e-5) n++ } END { print n + 0 }' "$T/ball.pts")
expect "ball slope: interior tips on m y + c + R (sqrt(1 + m^2) - 1)" [ "$bad" = 0 ]
interior=$(awk 'NF == 3 && $1 >= 5 && $1 <= 25 && $2 >= 5 && $2 <= 24' "$T/ball.pts" | wc -l)
expect "ball slope: interior points exist ($interior)" [ "$interior" -gt 100 ]
g=$(sed -n 's/.*gouge \([0-9.]*\) mm, scallop \([0-9.]*\) mm.*/\1 \2/p' "$T/ball.err")
expect "ball slope: gouge <= tol, scallop <= H ($g)" \
    awk -v g="$g" 'BEGIN { split(g, a, " "); exit !(a[1] != "" && a[1] <= 0.01 && a[2] <= 0.05) }'
# Passes along x, zig-zag: consecutive passes run in opposite directions.
dirs=$(awk 'NF == 0 { if (n) print (last > first) ? "+" : "-"; n = 0; next }
    { if (!n) first = $1; last = $1; n++ } END { if (n) print (last > first) ? "+" : "-" }' \
    "$T/ball.pts" | uniq | wc -l)
passes=$(awk 'NF == 0 { n++ } END { print n + 1 }' "$T/ball.pts")
expect "ball slope: zig-zag ($dirs runs of direction over $passes passes)" [ "$dirs" = "$passes" ]

# 2. The G-code: metric, absolute; F on every G1; spindle on before cutting and off at the end.
expect "gcode: G21 G90 first" grep -q '^G21 G90 G17 G94$' "$T/ball.nc"
expect "gcode: no G1 without F" bash -c "! grep '^G1' '$T/ball.nc' | grep -qv ' F[0-9]'"
expect "gcode: M3 S12000" grep -q '^M3 S12000$' "$T/ball.nc"
expect "gcode: M5 then M2 at the end" bash -c "tail -2 '$T/ball.nc' | tr '\n' ' ' | grep -q '^M5 M2 $'"
nb=$(grep -c '^G1 ' "$T/ball.nc")
np=$(grep -c . "$T/ball.pts")
expect "gcode: one G1 per point ($nb, $np)" [ "$nb" = "$np" ]

# 3. Planned and simulated on the 3018 router, as written: limits and final position checked.
M=contrib/machines/router-3018.ini
run "gcode plans on the router" 0 plan --machine "$M" -o "$T/ball.seg" "$T/ball.nc"
"$SIM" --replay "$T/ball.seg" --machine "$M" --reference "$T/ball.nc" --check >"$T/sim.out" 2>&1
src=$?
expect "simulator check passes" [ $src -eq 0 ]
expect "simulator: final position exact" grep -q 'rounded to steps: exact' "$T/sim.out"

# 3b. Linking: neighbouring passes joined at cutting height where the straight link stays above
# the drop-cutter surface (on a plane every link does): fewer retracts, still no gouge.
run "ball slope linked" 0 toolpath --patches "$T/slope.txt" --cutter ball:2 --scallop 0.05 \
    --check --safe-z 5 --gcode "$T/link.nc"
cp "$T/err" "$T/link.err"
r_plain=$(grep -c '^G0 Z5' "$T/ball.nc")
r_link=$(grep -c '^G0 Z5' "$T/link.nc")
expect "link: fewer retracts ($r_link < $r_plain)" [ "$r_link" -lt "$r_plain" ]
g=$(sed -n 's/.*gouge \([0-9.]*\) mm.*/\1/p' "$T/link.err")
expect "link: gouge $g <= 0.01" awk -v g="$g" 'BEGIN { exit !(g != "" && g <= 0.01) }'
run "linked gcode plans on the router" 0 plan --machine contrib/machines/router-3018.ini \
    -o "$T/link.seg" "$T/link.nc"
"$SIM" --replay "$T/link.seg" --machine contrib/machines/router-3018.ini --reference "$T/link.nc" \
    --check >"$T/simlink.out" 2>&1
expect "linked: simulator check passes" [ $? -eq 0 ]

# 4. --output centre: the ball's centre, R above the tip, point for point.
run "ball centre" 0 toolpath --patches "$T/slope.txt" --cutter ball:2 --scallop 0.05 \
    --output centre --no-link
off=$(paste -d' ' "$T/ball.pts" "$T/out" | awk 'NF == 6 { d = $6 - $3 - 2; if (d < 0) d = -d;
    if (d > 2e-6 || $1 != $4 || $2 != $5) n++ } END { print n + 0 }')
expect "centre = tip + R" [ "$off" = 0 ]

# 5. Flat and bull-nose ends: gouge-free by the check, and their scallop (the step a level bottom
# leaves on a slope) within H too: the raster refines their gaps like a ball's. On a quarter of
# the plane (x, y in [5, 15], the same slope): the check's cost grows with the area (a flat end
# on the whole plane: 181 passes, 9.4 s of the check alone).
printf 'curvestep-surfaces 1\nbezier 1 1\n  5 5 -12   5 15 -7\n  15 5 -12  15 15 -7\n' >"$T/slope4.txt"
for c in flat:3 bull:3:1; do
    run "$c slope" 0 toolpath --patches "$T/slope4.txt" --cutter "$c" --scallop 0.05 --check
    g=$(sed -n 's/.*gouge \([0-9.]*\) mm, scallop \([0-9.]*\) mm.*/\1 \2/p' "$T/err")
    expect "$c: gouge <= 0.01, scallop <= 0.05 ($g)" \
        awk -v g="$g" 'BEGIN { split(g, a, " "); exit !(a[1] != "" && a[1] <= 0.01 && a[2] <= 0.05) }'
done
# The same plane rising ALONG the passes (z = 0.5 x + c, passes along x): a cutter touches the
# plane uphill of its axis, so at its own position it stands R (1 / cos - 1) (ball) or R tan
# (flat) above the plane, but its neighbours along the pass cut that material: the scallop
# estimate takes every position of each pass within R. Across the passes the plane is level, so
# the ball needs the flat-ground step 2 sqrt(2RH - H^2) over the axis' region (the plane and R
# beyond: 14 mm), plus at most one pass per two gaps (it used to be 67 passes, every gap at the
# least width, 0.2118 mm "where no pass can be added").
printf 'curvestep-surfaces 1\nbezier 1 1\n  5 5 -12   5 15 -12\n  15 5 -7  15 15 -7\n' \
    >"$T/along.txt"
n0=$(awk 'BEGIN { r = 2; h = 0.05; n = 14 / (2 * sqrt(2 * r * h - h * h));
    printf "%d", (n == int(n) ? n : int(n) + 1) + 1 }')
for c in ball:2 flat:2; do
    run "$c along" 0 toolpath --patches "$T/along.txt" --cutter "$c" --scallop 0.05 --tol 0.01 \
        --check --stats
    np=$(sed -n 's/.* \([0-9]*\) passes (.*/\1/p' "$T/err" | head -1)
    st=$(sed -n 's/.*, \([0-9.]*\) mm where no pass can be added.*/\1/p' "$T/err")
    g=$(sed -n 's/.*gouge \([0-9.]*\) mm, scallop \([0-9.]*\) mm.*/\1 \2/p' "$T/err")
    expect "$c along: gouge <= 0.01, scallop <= 0.05 ($g)" \
        awk -v g="$g" 'BEGIN { split(g, a, " "); exit !(a[1] != "" && a[1] <= 0.01 && a[2] <= 0.05) }'
    expect "$c along: nothing where no pass can be added ($st)" \
        awk -v s="$st" 'BEGIN { exit !(s != "" && s + 0 == 0) }'
    if [ "$c" = ball:2 ]; then
        expect "ball along: $np passes, flat-ground $n0 .. $((n0 + (n0 - 1) / 2))" \
            awk -v n="$np" -v n0="$n0" 'BEGIN { exit !(n != "" && n >= n0 && n <= n0 + int((n0 - 1) / 2)) }'
    fi
done
# A flat end on a plane of slope m stands on its uphill rim: tip = m (y + R) + c.
run "flat formula" 0 toolpath --patches "$T/slope.txt" --cutter flat:3 --stepover 2
bad=$(awk 'NF == 3 && $1 >= 8 && $1 <= 22 && $2 >= 5 && $2 <= 22 {
    d = $3 - (0.5 * ($2 + 3) - 14.5); if (d < 0) d = -d; if (d > 1e-5) n++ } END { print n + 0 }' \
    "$T/out")
expect "flat: interior tips on m (y + R) + c" [ "$bad" = 0 ]

# 6. Bad command lines and inputs.
run "cutter bad" 2 toolpath --patches "$T/slope.txt" --cutter cone:3 --scallop 0.1 &&
    expect_err "cutter bad" "ball:R, flat:R or bull:R:r"
run "bull corner too big" 2 toolpath --patches "$T/slope.txt" --cutter bull:3:3 --scallop 0.1
run "neither scallop nor stepover" 2 toolpath --patches "$T/slope.txt" --cutter ball:2

# 7. A sphere item (radius 10, centre 15 15 -20 inside the router's travel): meshed on a
# latitude-longitude grid with a cap bound. Over the pole a ball of radius R stands on the sphere
# with its tip at zc + sqrt((r + R)^2 - d^2) - R (its centre on the offset sphere r + R).
# The flat and bull-nose ends (a gouge check, no formula) on a sphere of radius 5 (the same
# cap bound, a quarter of the area the check samples: 26 s -> 6 s for the flat end).
printf 'curvestep-surfaces 1\nsphere 15 15 -20 10\n' >"$T/sphere.txt"
printf 'curvestep-surfaces 1\nsphere 15 15 -20 5\n' >"$T/sphere5.txt"
for c in ball:2 flat:3 bull:3:1; do
    sph=$T/sphere5.txt
    [ "$c" = ball:2 ] && sph=$T/sphere.txt
    run "sphere $c" 0 toolpath --patches "$sph" --cutter "$c" --scallop 0.05 --check
    g=$(sed -n 's/.*gouge \([0-9.]*\) mm, scallop \([0-9.]*\) mm.*/\1 \2/p' "$T/err")
    expect "sphere $c: gouge <= 0.01, scallop <= 0.05 ($g)" \
        awk -v g="$g" 'BEGIN { split(g, a, " "); exit !(a[1] != "" && a[1] <= 0.01 && a[2] <= 0.05) }'
    [ "$c" = ball:2 ] && cp "$T/out" "$T/sph.pts"
done
bad=$(awk 'NF == 3 { d2 = ($1 - 15) ^ 2 + ($2 - 15) ^ 2; if (d2 <= 49) {
    want = -20 + sqrt(144 - d2) - 2; e = $3 - want; if (e < 0) e = -e; if (e > 0.01) n++; m++ } }
    END { print n + 0, m + 0 }' "$T/sph.pts")
expect "sphere ball: tips within 0.01 mm of the offset sphere ($bad: bad, checked)" \
    bash -c "set -- $bad; [ \$1 = 0 ] && [ \$2 -gt 50 ]"
# 8. --strategy waterline: constant-z contours of the drop surface. On the sphere the ball's drop
# height is known in closed form (section 7): z_d(d) = zc + sqrt((r + R)^2 - d^2) - R for
# d < r + R, the floor (-30, the sphere's bottom) beyond. Levels are at most
# dz = 2 sqrt(2 R H - H^2) apart (the scallop on a vertical wall), from just below the top down
# to the floor; every contour point must not gouge (z_d <= z + tol) and lie within tol of the
# level, in z or in xy (d within tol of the contour's radius d_k = sqrt((r+R)^2 - (z-zc+R)^2), or
# of the silhouette r + R below zc - R). Levels are added where the slope wants them and the
# cap round the pole is a flat area cut by a clipped raster (its points on the drop surface too),
# so the check finds gouge <= tol and scallop <= H (exit 1 otherwise), every cutter.
run "sphere waterline" 0 toolpath --patches "$T/sphere.txt" --cutter ball:2 --scallop 0.05 \
    --strategy waterline --check --no-link --gcode "$T/wl.nc"
cp "$T/out" "$T/wl.pts"
g=$(sed -n 's/.*gouge \([0-9.]*\) mm, scallop \([0-9.]*\) mm.*/\1 \2/p' "$T/err")
expect "sphere waterline: gouge <= 0.01, scallop <= 0.05 ($g)" \
    awk -v g="$g" 'BEGIN { split(g, a, " "); exit !(a[1] != "" && a[1] <= 0.01 && a[2] <= 0.05) }'
lv=$(awk 'NF == 3 { print $3 }' "$T/wl.pts" | sort -gu | awk -v dz="$(awk 'BEGIN { print 2 * sqrt(0.2 - 0.0025) }')" '
    { if (n && $1 - last > dz + 1e-9) bad++; last = $1; if (!n) first = $1; n++ }
    END { if (last < -10 - dz || last > -10 || first > -30 + 1e-6) bad++;
          print n + 0, bad + 0, (n >= 20 / dz) }')
expect "sphere waterline: levels every <= dz from the top to the floor ($lv: levels, bad, enough)" \
    bash -c "set -- $lv; [ \$2 = 0 ] && [ \$3 = 1 ]"
far=$(awk 'NF == 3 { d = sqrt(($1 - 15) ^ 2 + ($2 - 15) ^ 2); z = $3;
    zd = d < 12 ? -22 + sqrt(144 - d * d) : -30; if (zd > z + 0.01) gouge++;
    dk = z > -22 ? sqrt(144 - (z + 22) ^ 2) : 12; dd = d - dk; if (dd < 0) dd = -dd;
    ez = zd - z; if (ez < 0) ez = -ez; if (dd > 0.01 && ez > 0.01) far++; m++ }
    END { print gouge + 0, far + 0, m + 0 }' "$T/wl.pts")
expect "sphere waterline: every point on its level within tol ($far: gouging, off, points)" \
    bash -c "set -- $far; [ \$1 = 0 ] && [ \$2 = 0 ] && [ \$3 -gt 1000 ]"
# Each level above the silhouette is one closed loop (first point = last point).
loops=$(awk 'NF == 0 { if (n) { c += (f == l); t++ } n = 0; next }
    { if (!n) f = $0; l = $0; n++ } END { if (n) { c += (f == l); t++ } print c + 0, t + 0 }' "$T/wl.pts")
expect "sphere waterline: contours closed above the silhouette ($loops: closed, passes)" \
    bash -c "set -- $loops; [ \$1 -ge 12 ]"
run "waterline gcode plans on the router" 0 plan --machine "$M" -o "$T/wl.seg" "$T/wl.nc"
for c in flat:3 bull:3:1; do # on the small sphere, as in section 7 (48 s -> 13 s for the flat end)
    run "sphere waterline $c" 0 toolpath --patches "$T/sphere5.txt" --cutter "$c" --scallop 0.05 \
        --strategy waterline --check
    g=$(sed -n 's/.*gouge \([0-9.]*\) mm, scallop \([0-9.]*\) mm.*/\1 \2/p' "$T/err")
    expect "sphere waterline $c: gouge <= 0.01, scallop <= 0.05 ($g)" \
        awk -v g="$g" 'BEGIN { split(g, a, " "); exit !(a[1] != "" && a[1] <= 0.01 && a[2] <= 0.05) }'
done
# The plane of slope 0.5 (26.6 deg): the wall step leaves R - sqrt(R^2 - (dz / 2 / sin)^2) =
# 0.24 mm there, so levels are added: each level step at most 2 sqrt(2RH - H^2) sin(26 deg).
run "slope waterline" 0 toolpath --patches "$T/slope.txt" --cutter ball:2 --scallop 0.05 \
    --strategy waterline --check
g=$(sed -n 's/.*gouge \([0-9.]*\) mm, scallop \([0-9.]*\) mm.*/\1 \2/p' "$T/err")
expect "slope waterline: gouge <= 0.01, scallop <= 0.05 ($g)" \
    awk -v g="$g" 'BEGIN { split(g, a, " "); exit !(a[1] != "" && a[1] <= 0.01 && a[2] <= 0.05) }'
st=$(awk 'NF == 3 && $2 > 9 && $2 < 21 && $1 > 9 && $1 < 21 { print $3 }' "$T/out" | sort -gu |
    awk -v s="$(awk 'BEGIN { print 2 * sqrt(0.2 - 0.0025) * sin(atan2(1, 2)) }')" '
        { if (n && $1 - last > s + 1e-9) bad++; last = $1; n++ } END { print n + 0, bad + 0 }')
expect "slope waterline: levels at most the slope's step apart ($st: levels, wider)" \
    bash -c "set -- $st; [ \$1 -ge 20 ] && [ \$2 = 0 ]"
run "strategy bad" 2 toolpath --patches "$T/slope.txt" --cutter ball:2 --scallop 0.1 --strategy spiral &&
    expect_err "strategy bad" "raster, waterline or raster\\+waterline"
finish
