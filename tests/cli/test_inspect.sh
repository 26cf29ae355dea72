#!/usr/bin/env bash
# CLI tests of the curves file (every basis through flatten, plan, stdin detection, located
# errors, the docs example being the test file) and of `curvestep inspect` (join classes of
# constructions whose continuity is known from theory: uniform B-splines C2, beta-splines G2,
# Catmull-Rom C1, collinear lines of different lengths G2 (zero curvature on both sides, first
# derivatives differ), quadratics with tangents of one direction, different lengths G1, a corner C0; patch edges C2 / G1; the
# .bpt teapot reads as Newell's; --json parses) and the surface keyword lists of toolpath --help,
# docs/surfaces.md and the parser. Uses $CS_BUILD; ends with "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
EVERY=tests/data/curves/every-basis.curves

# --- the curves file through the job commands
run "flatten every basis" 0 flatten --stats --tol 0.01 "$EVERY"
dev=$(sed -n 's/.*max deviation \([0-9.e-]*\) mm.*/\1/p' "$T/err")
check "flatten: measured deviation $dev <= 0.01 mm" awk -v d="$dev" 'BEGIN { exit !(d != "" && d <= 0.01) }'
cp "$T/out" "$T/by_name"
"$CS" flatten --tol 0.01 - <"$EVERY" >"$T/by_content" 2>/dev/null
check "stdin: recognised by its header, same chords" cmp -s "$T/by_name" "$T/by_content"
run "plan every basis" 0 plan "$EVERY"
check "plan: segments" [ "$(wc -l <"$T/out")" -gt 100 ]
# The example in docs/inputs.md is the test file.
awk '/^```$/ { if (on) exit; next } /^curvestep-curves 1$/ { on = 1 } on' docs/inputs.md >"$T/doc.curves"
check "docs/inputs.md example = $EVERY" cmp -s "$T/doc.curves" <(grep -v '^#' "$EVERY")
printf 'curvestep-curves 1\nbezier 8 0 0 0\n' >"$T/bad.curves"
run "degree 8" 1 flatten "$T/bad.curves"
expect_err "degree 8: located" "bad.curves:2:8: degree must be an integer 1\.\.7"
printf 'curvestep-curves 1\nspiral 1\n' >"$T/bad2.curves"
run "unknown keyword" 1 plan "$T/bad2.curves"
expect_err "unknown keyword: located, lists the keywords" \
    "bad2.curves:2:1: unknown curve 'spiral' \(line, bezier, hermite, bspline, nurbs, catmull-rom, beta, natural, arc\)"

# --- seed 003's length-based subdivision and Horner evaluation (flatten --method length --eval):
# every chord at most --seg-len (measured on the printed vertices), the same drawing either way
for ev in decasteljau horner; do
    run "flatten length $ev" 0 flatten --method length --seg-len 0.5 --eval "$ev" --stats "$EVERY"
    check "length $ev: chords <= 0.5 mm" awk 'NF == 2 { if (have && sqrt(($1 - x) ^ 2 + ($2 - y) ^ 2) > 0.5 + 2e-6) bad++; x = $1; y = $2; have = 1; n++ } NF == 0 { have = 0 } END { exit !(n > 500 && !bad) }' "$T/out"
    check "length $ev: stats name the method" grep -q "method length ($ev), chords at most 0.5 mm" "$T/err"
    wc -l <"$T/out" >"$T/n_$ev"
done
check "length: Horner and de Casteljau within 1 % of each other" awk -v a="$(cat "$T/n_decasteljau")" -v b="$(cat "$T/n_horner")" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d <= a / 100) }'
run "--eval needs --method length" 2 flatten --eval horner "$EVERY"
run "--eval bad" 2 flatten --method length --eval naive "$EVERY"

# --- inspect: classes known from theory
cat >"$T/classes.curves" <<'CURVES'
curvestep-curves 1
bspline 6   0 0 0  10 20 0  20 0 0  30 20 0  40 0 0  50 20 0   # uniform B-spline: C2, C2
beta 1.5 0 5  0 30 0  10 50 0  20 30 0  30 50 0  40 30 0       # bias 1.5: G2 but not C1
catmull-rom 5  0 60 0  10 70 0  25 60 0  30 75 0  45 60 0     # C1, curvature differs
line 0 90 0  10 90 0
line 10 90 0  30 90 0                                          # |d1| 10 vs 20, no curvature: G2
line 30 90 0  30 100 0                                         # a corner: C0
bezier 2  0 110 0  10 110 0  20 120 0                          # end tangent 2 (10, 10)
bezier 2  20 120 0  40 140 0  60 110 0                         # start tangent 2 (20, 20): G1
CURVES
run "inspect classes" 0 inspect "$T/classes.curves"
check "join 1-2 C2" grep -q '^join 1-2: C2 ' "$T/out"
check "join 2-3 C2" grep -q '^join 2-3: C2 ' "$T/out"
check "beta join G2" grep -q '^join 4-5: G2 ' "$T/out"
check "catmull-rom join C1" grep -q '^join 6-7: C1 ' "$T/out"
check "collinear lines G2" grep -q '^join 8-9: G2 ' "$T/out"
check "quadratics G1" grep -q '^join 11-12: G1 ' "$T/out"
check "corner C0 (90 degrees)" grep -q '^join 9-10: C0 (gap 0 mm, angle 90 deg' "$T/out"
check "no join across subpaths" bash -c "! grep -q '^join 3-4' '$T/out'"
check "summary" grep -q '^inspect: .*classes.curves (curves): 12 elements in 5 subpaths, length .*; 7 joins: 2 C2, 2 G2, 1 C1, 1 G1, 1 C0, 0 gap$' "$T/out"
check "line length 20 mm" grep -q '^element 9 .*: line degree 1, length 20 mm' "$T/out"
run "inspect --json" 0 inspect --json "$T/classes.curves"
check "json parses, 7 joins, 2 C2" python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["format"] == "curves" and d["summary"]["joins"] == 7 and d["summary"]["C2"] == 2
assert d["elements"][8]["kind"] == "line" and abs(d["elements"][8]["length_mm"] - 20) < 1e-4
assert d["joins"][5]["class"] == "C0" and abs(d["joins"][5]["angle_deg"] - 90) < 1e-6' "$T/out"
run "inspect G-code" 0 inspect tests/data/gcode/arc-xy-plane.nc
check "inspect G-code: summary" grep -q '^inspect: .*(gcode): ' "$T/out"
run "inspect usage" 2 inspect
run "inspect bad option" 2 inspect --frob "$EVERY"
run "inspect --rel out of range" 2 inspect --rel 2 "$EVERY"
run "inspect missing file" 1 inspect "$T/none.curves"
run "inspect help" 0 inspect --help
check "help names the classes" grep -q 'C2, G2, C1, G1, C0' "$T/out"

# --- patches: two flat bicubics in a row, evenly spaced (C2), then stretched (G1 only)
{
    echo "curvestep-surfaces 1"
    echo "bezier 3 3"; for i in 0 1 2 3; do for j in 0 1 2 3; do echo "$i $j 0"; done; done
    echo "bezier 3 3"; for i in 3 4 5 6; do for j in 0 1 2 3; do echo "$i $j 0"; done; done
    echo "bezier 3 3"; for i in 6 8 10 12; do for j in 0 1 2 3; do echo "$i $j 0"; done; done
} >"$T/flat.txt"
run "inspect patches" 0 inspect "$T/flat.txt"
check "edge 1-2 C2" grep -q '^edge patch 1 (u=1) - patch 2 (u=0): C2$' "$T/out"
check "edge 2-3 G1" grep -q '^edge patch 2 (u=1) - patch 3 (u=0): G1$' "$T/out"
check "patch summary" grep -q '3 patches, 2 shared edges: 1 C2, 0 C1, 1 G1, 0 C0$' "$T/out"
run "inspect teapot.bpt" 0 inspect tests/data/teapot/teapot.bpt
grep -v '^patch ' "$T/out" | sed 's/teapot.bpt/X/' >"$T/bpt"
run "inspect Newell teapot" 0 inspect --patches tests/data/teapot/newell_teapot.txt
grep -v '^patch ' "$T/out" | sed 's/newell_teapot.txt/X/' >"$T/newell"
check ".bpt teapot = Newell teapot (edges, summary)" cmp -s "$T/bpt" "$T/newell"
check "teapot: 32 patches" grep -q ': 32 patches, ' "$T/out"

# --- degrees above 3 (issue 19): a 7 x 4 tensor patch and a quintic triangle, wireframe past the
# raster's bound (64 lines > 2^3 for the degree-7 direction) and ball-end finishing
{
    echo "curvestep-surfaces 1"
    echo "bezier 7 4"; for i in 0 1 2 3 4 5 6 7; do for j in 0 1 2 3 4; do echo "$((i * 5)) $((j * 5)) $(((i * j) % 5))"; done; done
    echo "tri 5"; for i in 0 1 2 3 4 5; do for j in $(seq 0 $((5 - i))); do echo "$((50 + i * 4)) $((j * 4)) $((i * j % 3))"; done; done
} >"$T/high.txt"
run "toolpath degree 7 x 4 and 5" 0 toolpath --patches "$T/high.txt" --lines 64 --tol 0.01 --stats
dev=$(sed -n 's/.*max deviation \([0-9.e-]*\) mm.*/\1/p' "$T/err")
check "high degrees: chords within 0.01 mm ($dev)" awk -v d="$dev" 'BEGIN { exit !(d != "" && d <= 0.01) }'
run "finishing degree 7 x 4 and 5" 0 toolpath --patches "$T/high.txt" --ball 2 --scallop 0.05
run "inspect high degrees" 0 inspect "$T/high.txt"
check "inspect: tensor degree 7 x 4" grep -q 'tensor degree 7 x 4' "$T/out"
check "inspect: triangle degree 5" grep -q 'triangle degree 5' "$T/out"
printf 'curvestep-surfaces 1\nbezier 8 1\n' >"$T/deg8.txt"
run "degree 8 refused" 1 toolpath --patches "$T/deg8.txt"
expect_err "degree 8: located" 'deg8.txt:2:8: degree in u must be an integer 1\.\.7'

# --- the exact sphere (seed 000): every wireframe vertex on the sphere, every tool centre on the
# offset sphere r + R (vertices lie on the exact arcs: within their 2 LSB plus the 6 printed
# decimals), the closed-form scallop below H
printf 'curvestep-surfaces 1\nsphere 10 20 5  25\n' >"$T/sphere.txt"
run "sphere wireframe" 0 toolpath --patches "$T/sphere.txt" --lines 8 --view 1,0,0,-10,0,1,0,-20,0,0,1,0 --stats
check "sphere wireframe: vertices within 25 mm of the centre (top view)" awk 'NF == 2 { d = sqrt($1 * $1 + $2 * $2); if (d > 25 + 4e-5) bad++; n++ } END { exit !(n > 100 && !bad) }' "$T/out"
run "sphere finishing" 0 toolpath --patches "$T/sphere.txt" --ball 3 --scallop 0.02 --stats
check "sphere finishing: tool centres on the offset sphere r + R = 28" awk 'NF == 3 && NR > 1 { d = sqrt(($1 - 10) ^ 2 + ($2 - 20) ^ 2 + ($3 - 5) ^ 2); if ($3 < 38 && (d > 28 + 4e-5 || d < 28 - 4e-5)) bad++; n++ } END { exit !(n > 1000 && !bad) }' "$T/out"
check "sphere finishing: scallop below 0.02" grep -qE 'scallop 0\.02 mm: [0-9]+ passes, measured scallop 0\.01[0-9]+ mm' "$T/err"

# --- the surface keywords: toolpath --help, docs/surfaces.md and the parser's own list agree
run "toolpath help" 0 toolpath --help
help_kw=$(grep -A1 'each starting with one of the keywords' "$T/out" | tail -1 | sed 's/^ *//; s/;$//')
doc_kw=$(awk '/^## Native surface format/ { s = 1 } s && /^```$/ { if (b) exit; b = 1; next }
    b && !/^(curvestep-surfaces| |#)/ { printf "%s%s", (n++ ? ", " : ""), $1 }' docs/surfaces.md)
printf 'curvestep-surfaces 1\nnosuch\n' >"$T/k.txt"
run "unknown surface" 1 toolpath --patches "$T/k.txt"
parser_kw=$(sed -n "s/.*unknown surface 'nosuch' (\(.*\))$/\1/p" "$T/err")
check "help lists what the docs list ($help_kw | $doc_kw)" [ -n "$help_kw" ] && [ "$help_kw" = "$doc_kw" ]
check "the parser's list is the docs' ($parser_kw)" [ "$parser_kw" = "$doc_kw" ]
check "varady listed" grep -q 'varady, varady-scheme' <<<"$help_kw"
finish
