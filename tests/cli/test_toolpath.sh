#!/usr/bin/env bash
# CLI tests of `curvestep toolpath`: exact wireframe of a planar patch, views (named and matrix),
# the teapot's wireframe (polyline count, measured deviation within --tol, picture), the ball-end
# finishing path (3 columns, one block per patch, measured scallop below H, retracts at the safe
# height), diagnostics file:line:col with exit 1 and usage errors with exit 2.
# Uses $CS_BUILD (the build directory); ends with "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
TEAPOT=tests/data/teapot/newell_teapot.txt

# A planar patch P(u, v) = (3u, 3v, 0): control points on the integer grid.
{
    printf '1\n1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16\n16\n'
    for i in 0 1 2 3; do for j in 0 1 2 3; do echo "$i,$j,0"; done; done
} >"$T/flat.txt"

run "help" 0 toolpath --help
check "help mentions --scallop" grep -q -- '--scallop H' "$T/out"
run "help via curvestep help" 0 help toolpath

# Straight iso-lines: the tracer needs no inner vertex; edges and the middle lines exactly.
run "flat lines 1" 0 toolpath --patches "$T/flat.txt" --view top --lines 1
expect_out "flat lines 1" '0.000000 0.000000\n3.000000 0.000000\n\n0.000000 3.000000\n3.000000 3.000000\n\n0.000000 0.000000\n0.000000 3.000000\n\n3.000000 0.000000\n3.000000 3.000000\n'
run "flat lines 3 (not a power of two)" 0 toolpath --patches "$T/flat.txt" --view top --lines 3
check "flat lines 3: 8 polylines" [ "$(grep -c '^$' "$T/out")" -eq 7 ]
check "flat lines 3: the line v = 1/3" grep -qx '0.000000 1.000000' "$T/out"
# Views: front prints (x, z), side (y, z); a matrix equal to top prints what top prints.
run "front" 0 toolpath --patches "$T/flat.txt" --view front --lines 1
check "front: z is 0" bash -c "awk '\$2 != \"0.000000\" && NF' '$T/out' | wc -l | grep -qx 0"
run "matrix = top" 0 toolpath --patches "$T/flat.txt" --view 1,0,0,0,0,1,0,0,0,0,1,0 --lines 1
expect_out "matrix = top" '0.000000 0.000000\n3.000000 0.000000\n\n0.000000 3.000000\n3.000000 3.000000\n\n0.000000 0.000000\n0.000000 3.000000\n\n3.000000 0.000000\n3.000000 3.000000\n'
run "matrix with offset" 0 toolpath --patches "$T/flat.txt" --view 2,0,0,1,0,1,0,-1,0,0,1,0 --lines 1
check "matrix with offset: first vertex" bash -c "head -2 '$T/out' | tr '\n' ' ' | grep -qx '1.000000 -1.000000 7.000000 -1.000000 '"

# The teapot: 32 patches x 2 directions x 5 lines = 320 polylines; first vertex is vertex 1
# (1.4, 0, 2.4) seen from the front, each coordinate rounded to the 2^-16 mm grid
# (1.4 * 65536 = 91750.4 -> 91750 LSB = 1.3999939 mm).
run "teapot front" 0 toolpath --patches "$TEAPOT" --view front --lines 4 --tol 0.001
check "teapot: 320 polylines" [ "$(grep -c '^$' "$T/out")" -eq 319 ]
check "teapot front: first vertex" bash -c "head -1 '$T/out' | grep -qx '1.399994 2.399994'"
run "teapot iso stats svg" 0 toolpath --patches "$TEAPOT" --scale 10 --lines 8 --tol 0.01 --stats --svg "$T/tea.svg"
dev=$(sed -n 's/.*max deviation \([0-9.]*\) mm.*/\1/p' "$T/err")
check "teapot: deviation measured ($dev) within 0.01 mm" awk -v d="${dev:-9}" 'BEGIN { exit !(d > 0 && d <= 0.01) }'
check "teapot: picture written" grep -q '<polyline' "$T/tea.svg"

# Finishing: one block per patch, 3 columns, first and last vertex of a block at the safe
# height, measured scallop below H.
run "teapot ball" 0 toolpath --patches "$TEAPOT" --scale 10 --ball 2 --scallop 0.1 --tol 0.02 --safe-z 50 --stats
check "ball: 32 blocks" [ "$(grep -c '^$' "$T/out")" -eq 31 ]
check "ball: 3 columns" bash -c "awk 'NF && NF != 3' '$T/out' | wc -l | grep -qx 0"
check "ball: approach and retract at z = 50" bash -c "awk 'BEGIN{RS=\"\"} { if (\$3 != \"50.000000\" || \$NF != \"50.000000\") bad++ } END { exit bad > 0 }' '$T/out'"
sc=$(sed -n 's/.*measured scallop \([0-9.]*\) mm.*/\1/p' "$T/err")
check "ball: measured scallop ($sc) below 0.1" awk -v s="${sc:-9}" 'BEGIN { exit !(s > 0 && s < 0.1) }'
expect_err "ball: gouge warning on the teapot's tight spots" 'curvature radius below R'
run "flat ball, no warnings" 0 toolpath --patches "$T/flat.txt" --ball 1 --scallop 0.01 --tol 0.01
check "flat ball: silent" [ ! -s "$T/err" ]
check "flat ball: tool centre 1 mm above the plane" bash -c "awk 'NF' '$T/out' | sed '1d;\$d' | awk '\$3 != \"1.000000\"' | wc -l | grep -qx 0"

# The native format: every surface kind in one file (tests/data/surfaces/all_kinds.txt).
run "native all kinds" 0 toolpath --patches tests/data/surfaces/all_kinds.txt --lines 4 --tol 0.01 --stats
dev=$(sed -n 's/.*max deviation \([0-9.]*\) mm.*/\1/p' "$T/err")
check "native: deviation measured ($dev) within 0.01 mm" awk -v d="${dev:-9}" 'BEGIN { exit !(d > 0 && d <= 0.01) }'
# A five-sided Várady patch: boundary, 5 rays and 3 rings of 5 segments = 25 polylines.
run "varady" 0 toolpath --patches tests/data/surfaces/pentagon.txt --lines 4 --tol 0.01 --stats
check "varady: 25 polylines" [ "$(grep -c '^$' "$T/out")" -eq 24 ]
dev=$(sed -n 's/.*max deviation \([0-9.]*\) mm.*/\1/p' "$T/err")
check "varady: deviation measured ($dev) within 0.01 mm" awk -v d="${dev:-9}" 'BEGIN { exit !(d > 0 && d <= 0.01) }'
# The same loop with the lambda / kappa blends and each parametrisation: the same 25 polylines,
# and the boundary (the first 5 polylines: the side curves themselves) identical to mu's.
awk 'NF == 0 { b++ } b < 5' "$T/out" >"$T/mu_boundary"
for par in side radial centre; do
    sed "s/^varady 5/varady-scheme lambda-kappa $par 5/" tests/data/surfaces/pentagon.txt >"$T/lk.txt"
    run "varady lambda-kappa $par" 0 toolpath --patches "$T/lk.txt" --lines 4 --tol 0.01 --stats
    check "varady lambda-kappa $par: 25 polylines" [ "$(grep -c '^$' "$T/out")" -eq 24 ]
    check "varady lambda-kappa $par: same boundary" \
        cmp -s "$T/mu_boundary" <(awk 'NF == 0 { b++ } b < 5' "$T/out")
done
sed "s/^varady 5/varady-scheme lambda-kappa sideways 5/" tests/data/surfaces/pentagon.txt >"$T/lk.txt"
run "varady-scheme bad parametrisation" 1 toolpath --patches "$T/lk.txt"
expect_err "varady-scheme bad parametrisation" "lk.txt:3:28: 'sideways': parametrisation side, radial, centre or biquadratic expected"
# Finishing the n-sided patch: bicubic cells fitted within tol / 2 = 0.005 mm, each a block from
# and back to the safe height.
run "varady with --ball" 0 toolpath --patches tests/data/surfaces/pentagon.txt --ball 2 --scallop 0.2 --safe-z 20 --stats
fit=$(sed -n 's/.*fitted bicubic cells within \([0-9.]*\) mm.*/\1/p' "$T/err")
check "varady --ball: cells within tol / 2 ($fit)" awk -v d="${fit:-9}" 'BEGIN { exit !(d > 0 && d <= 0.005) }'
check "varady --ball: blocks start and end at the safe height" awk '
    NF == 3 { if (start && $3 != "20.000000") bad++; start = 0; last = $3; n++ }
    NF == 0 { if (last != "20.000000") bad++; start = 1; blocks++ }
    BEGIN { start = 1 }
    END { exit !(n > 100 && blocks > 5 && !bad && last == "20.000000") }' "$T/out"
# A lone linear triangle (0,0,0) (3,0,0) (0,3,0) seen from the top, 1 interval: the 3 edges (as
# lines u = 0, v = 0, w = 0) and 3 single corner points (u = 1, v = 1, w = 1).
printf 'curvestep-surfaces 1\ntri 1  0 0 0  0 3 0  3 0 0\n' >"$T/tri.txt"
run "triangle" 0 toolpath --patches "$T/tri.txt" --view top --lines 1
expect_out "triangle" '0.000000 0.000000\n0.000000 3.000000\n\n0.000000 0.000000\n3.000000 0.000000\n\n3.000000 0.000000\n0.000000 3.000000\n\n3.000000 0.000000\n\n0.000000 3.000000\n\n0.000000 0.000000\n'
printf 'curvestep-surfaces 1\n\ntri 1  0 0 0  0 3 0  3 0 0\n' >"$T/tri2.txt"
# Finishing that triangle (normal Tu x Tv = +z) with R = 1, H = 0.1: the centres at z = 1 over
# the triangle, passes along its iso-lines u = const (x = 3u constant in a pass); the flat
# step-over 2 sqrt(2 R H - H^2) = 0.872 mm needs at least 4 strips over the 3 mm: >= 5 passes.
run "triangle with --ball" 0 toolpath --patches "$T/tri2.txt" --ball 1 --scallop 0.1 --safe-z 9
check "triangle --ball: centres at z = 1 inside the triangle" awk '
    NF == 3 && $3 != "9.000000" { n++; if ($3 != "1.000000" || $1 < -1e-4 || $2 < -1e-4 || $1 + $2 > 3.0001) bad++ }
    END { exit !(n > 10 && !bad) }' "$T/out"
check "triangle --ball: >= 5 passes of constant x" awk '
    NF == 3 && $3 == "1.000000" { if (!($1 in seen)) { seen[$1] = 1; k++ } }
    END { exit !(k >= 5) }' "$T/out"
printf 'curvestep-surfaces 1\nbezier 1 1  0 0 0  1 0 0  0 1 0  1 1 oops\n' >"$T/nat_bad.txt"
run "native bad number" 1 toolpath --patches "$T/nat_bad.txt"
expect_err "native bad number" "nat_bad.txt:2:38: 'oops': control point expected"

# Bad input: file:line:col, exit 1.
printf '1\n1,2,3\n' >"$T/bad1.txt"
run "short patch line" 1 toolpath --patches "$T/bad1.txt"
expect_err "short patch line" "bad1.txt:2:6: patch 1: expected 16 vertex indices \(Newell's format; a .bpt file has 'degu degv' here\), found 3"
sed 's/^16$/15/' "$T/flat.txt" >"$T/bad2.txt"
run "index beyond the vertices" 1 toolpath --patches "$T/bad2.txt"
expect_err "index beyond the vertices" "bad2.txt:2:37: vertex index 16 outside 1..15"
run "missing file" 1 toolpath --patches "$T/nope.txt"
expect_err "missing file" "nope.txt:0:0: cannot open"
run "scale out of range" 1 toolpath --patches "$T/flat.txt" --scale 2000
expect_err "scale out of range" "flat.txt:[0-9]+:1: vertex .* outside"
# Usage: exit 2.
run "no --patches" 2 toolpath --lines 3
run "lines 0" 2 toolpath --patches "$T/flat.txt" --lines 0
run "bad view" 2 toolpath --patches "$T/flat.txt" --view diagonal
run "ball without scallop" 2 toolpath --patches "$T/flat.txt" --ball 1
run "scallop >= ball" 2 toolpath --patches "$T/flat.txt" --ball 1 --scallop 1
run "safe-z without ball" 2 toolpath --patches "$T/flat.txt" --safe-z 10
run "tol too small" 2 toolpath --patches "$T/flat.txt" --tol 0

finish
