#!/usr/bin/env bash
# CLI tests of `curvestep flatten` (and the program's dispatch): exact vertices for each SVG
# command form, subpath separation, diagnostics file:line:col with exit 1, usage errors exit 2,
# --help, stdin, --stats (measured deviation within the tolerance) and --svg.
# Uses $CS_BUILD (the build directory); ends with "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"

path() { printf '%s' "$1" >"$T/p.txt"; }

need_bin "$CS"

# --- lines: exact vertices ---------------------------------------------------------------
path 'M0 0 L10 0'
run "line" 0 flatten "$T/p.txt" && expect_out "line" '0.000000 0.000000\n10.000000 0.000000\n'

path 'M1 2 h3 v4 H0 V0 z'
run "h v H V z" 0 flatten "$T/p.txt" &&
    expect_out "h v H V z" '1.000000 2.000000\n4.000000 2.000000\n4.000000 6.000000\n0.000000 6.000000\n0.000000 0.000000\n1.000000 2.000000\n'

path 'm 1 1 2 0 0 2 l -2 0'
run "implicit lineto" 0 flatten "$T/p.txt" &&
    expect_out "implicit lineto" '1.000000 1.000000\n3.000000 1.000000\n3.000000 3.000000\n1.000000 3.000000\n'

path 'M0 0 L1 0 M5 5 L6 5 m 1 1 l 0.5 -0.25'
run "subpaths" 0 flatten "$T/p.txt" &&
    expect_out "subpaths" '0.000000 0.000000\n1.000000 0.000000\n\n5.000000 5.000000\n6.000000 5.000000\n\n7.000000 6.000000\n7.500000 5.750000\n'

# z followed by a drawing command: new subpath from the same start.
path 'M 10 10 L 10 20 L 20 10 z L 100 100'
run "z then L" 0 flatten "$T/p.txt" &&
    expect_out "z then L" '10.000000 10.000000\n10.000000 20.000000\n20.000000 10.000000\n10.000000 10.000000\n\n10.000000 10.000000\n100.000000 100.000000\n'

# Nothing drawn: no output, "no drawable geometry", exit 1 (issue 15 item 9: never silence).
for d in '' 'M 5 5' 'M 30 40 Z' 'M 1 1 M 2 2'; do
    path "$d"
    run "empty '$d'" 1 flatten "$T/p.txt" && expect_out "empty '$d'" '' &&
        expect_err "empty '$d'" "^$T/p.txt:1:1: no drawable geometry"
done

# --- curves: first and last vertex exact, more than one chord, every vertex on the curve ------
# (endpoints, count) per form; the vertices of the half circle are checked against its radius.
check_curve() { # name d x0 y0 x1 y1 min_vertices
    path "$2"
    run "$1" 0 flatten "$T/p.txt" || return
    local first last n
    first=$(head -n1 "$T/out")
    last=$(tail -n1 "$T/out")
    n=$(grep -c . "$T/out")
    if [ "$first" = "$3 $4" ] && [ "$last" = "$5 $6" ] && [ "$n" -ge "$7" ]; then ok; else
        ko "$1: first '$first' last '$last' ($n vertices)"
    fi
}
check_curve "C" 'M 30 40 C 16 137 171 45 180 155' 30.000000 40.000000 180.000000 155.000000 10
check_curve "c S" 'M 30 40 c -14 97 141 5 70 50 S 171 45 180 155' 30.000000 40.000000 180.000000 155.000000 10
check_curve "Q T" 'M 30 40 Q 171 45 100 90 T 160 180' 30.000000 40.000000 160.000000 180.000000 10
check_curve "q t" 'M 30 40 q 171 45 50 40 t 60 80' 30.000000 40.000000 140.000000 160.000000 10
check_curve "A" 'M 30 40 A 40 30 20 1 1 150 100' 30.000000 40.000000 150.000000 100.000000 10
check_curve "a flags" 'M0 0 a10 10 0 00 10 10' 0.000000 0.000000 10.000000 10.000000 5

# Half circle of radius 10 about the origin: every vertex within 1e-4 mm of radius 10 (a vertex
# is on the curve within 1 LSB = 1.5e-5 mm; printing rounds to 5e-7) and y >= 0 (sweep 1 goes
# through +y in SVG's parametrisation).
path 'M 10 0 A 10 10 0 0 1 -10 0'
if run "arc radius" 0 flatten --tol 0.001 "$T/p.txt"; then
    bad=$(awk 'NF==2 { r = sqrt($1*$1 + $2*$2); if (r < 10 - 1e-4 || r > 10 + 1e-4 || $2 < -1e-6) print }' "$T/out" | wc -l)
    n=$(grep -c . "$T/out")
    if [ "$bad" -eq 0 ] && [ "$n" -gt 20 ]; then ok; else ko "arc radius: $bad vertices off, $n vertices"; fi
fi

# A coarser tolerance gives fewer vertices.
path 'M 0 0 C 0 100 100 100 100 0'
run "tol fine" 0 flatten --tol 0.001 "$T/p.txt" && nf=$(grep -c . "$T/out")
run "tol coarse" 0 flatten --tol 1 "$T/p.txt" && nc=$(grep -c . "$T/out")
if [ "${nc:-0}" -gt 1 ] && [ "${nc:-0}" -lt "${nf:-0}" ]; then ok; else ko "tolerance: $nc vs $nf vertices"; fi

# Every method ends the cubic at its exact end point.
for m in fd afd subdiv; do
    run "method $m" 0 flatten --method "$m" "$T/p.txt" &&
        { [ "$(tail -n1 "$T/out")" = "100.000000 0.000000" ] && ok || ko "method $m: last vertex"; }
done

# --- stdin ---------------------------------------------------------------------------------
if printf 'M0 0 L10 0' | "$CS" flatten - >"$T/out" 2>"$T/err"; then
    expect_out "stdin" '0.000000 0.000000\n10.000000 0.000000\n'
else ko "stdin: exit $?"; fi
printf 'M0 0\nL10 x' | "$CS" flatten - >"$T/out" 2>"$T/err"
rc=$?
[ $rc -eq 1 ] && ok || ko "stdin error: exit $rc"
expect_err "stdin error" '^<stdin>:2:5: '

# --- bad input: file:line:col: reason, exit 1 --------------------------------------------
path $'M 10 10\n  L 1e 5'
run "bad exponent" 1 flatten "$T/p.txt" && expect_err "bad exponent" "^$T/p.txt:2:7: .*digit"
path 'M 10 10 L 20'
run "missing number" 1 flatten "$T/p.txt" && expect_err "missing number" "^$T/p.txt:1:13: .*end of data"
path 'L 10 10'
run "no moveto" 1 flatten "$T/p.txt" && expect_err "no moveto" "^$T/p.txt:1:1: .*moveto"
# drawn up to the error (SVG 2, 9.5.4): the path draws nothing, the frame is drawn, a warning
run "svg: moveto required" 0 flatten tests/data/svg/resvg/A.svg &&
    expect_err "svg: moveto required" '^tests/data/svg/resvg/A.svg:5:38: warning: '
# Out of the +/-4096 mm range: refused where the number is.
path 'M 0 0 L 5000 0'
run "out of range" 1 flatten "$T/p.txt" && expect_err "out of range" "^$T/p.txt:1:9: .*4096"
path $'M 4000 0\nl 50 0 l 50 0'
run "out of range, relative" 1 flatten "$T/p.txt" && expect_err "out of range, relative" "^$T/p.txt:2:10: "
path 'M 0 0 L 4096 -4096'
run "range limit itself" 0 flatten "$T/p.txt" && expect_out "range limit itself" '0.000000 0.000000\n4096.000000 -4096.000000\n'
run "missing file" 1 flatten "$T/does-not-exist.svg" && expect_err "missing file" "does-not-exist.svg"
# Nothing on stdout for rejected input.
path 'M 0 0 L 1 1 L 5000 0'
run "no partial output" 1 flatten "$T/p.txt" && expect_out "no partial output" ''

# --- usage: exit 2 -------------------------------------------------------------------------
run "unknown option" 2 flatten --frobnicate "$T/p.txt" && expect_err "unknown option" 'frobnicate'
run "no file" 2 flatten
run "two files" 2 flatten "$T/p.txt" "$T/p.txt"
run "bad tol" 2 flatten --tol abc "$T/p.txt"
run "zero tol" 2 flatten --tol 0 "$T/p.txt"
run "negative tol" 2 flatten --tol -1 "$T/p.txt"
path 'M0 0 L1 1'
run "tol below the tracers' 4 LSB" 2 flatten --tol 0.00003 "$T/p.txt" && expect_out "tol below 4 LSB" ''
run "tol above the range" 2 flatten --tol 5000 "$T/p.txt"
run "bad method" 2 flatten --method nope "$T/p.txt"
run "tol without value" 2 flatten --tol
run "unknown command" 2 frobnicate
run "no command" 2

# --- help and version ------------------------------------------------------------------------
if run "flatten --help" 0 flatten --help; then
    for w in --tol --method fd afd subdiv --stats --svg -h --help FILE "'-'" 'Exit status' \
        'bad input' 'usage' 'internal'; do
        grep -q -- "$w" "$T/out" && ok || ko "flatten --help does not mention $w"
    done
fi
run "help flatten" 0 help flatten && { grep -q -- '--tol' "$T/out" && ok || ko "help flatten"; }
run "--help" 0 --help && { grep -q 'flatten' "$T/out" && ok || ko "--help lists flatten"; }
run "--version" 0 --version && { grep -qE '^curvestep [0-9]+\.[0-9]+' "$T/out" && ok || ko "--version"; }

# --- --stats: measured deviation within the tolerance, for every method --------------------
for m in fd afd subdiv; do
    for tol in 0.01 0.1; do
        if run "stats $m $tol" 0 flatten --stats --method "$m" --tol "$tol" tests/data/svg/w3c/paths-data-02-t.svg; then
            dev=$(sed -n 's/.*max deviation \([0-9.]*\) mm.*/\1/p' "$T/err")
            if [ -n "$dev" ] && awk -v d="$dev" -v t="$tol" 'BEGIN { exit !(d <= t && d > 0) }'; then ok; else
                ko "stats $m $tol: deviation '$dev'"
            fi
            # 24 path elements in 9 subpaths, plus the 29 drawn <rect>s (test frame and the
            # 4x4 markers, filled: drawn as outlines) of 4 lines each in a subpath of their own:
            # 140 in 38; and the file's <text> in the default stroke font, 1039 lines in 223
            # strokes (without a font, the program copied away from share/, it is 140 in 38).
            expect_err "stats $m $tol" '1179 elements in 261 subpaths'
        fi
    done
done

# --- --svg ------------------------------------------------------------------------------------
if run "svg out" 0 flatten --svg "$T/pic.svg" tests/data/svg/w3c/paths-data-01-t.svg; then
    if [ -s "$T/pic.svg" ] && grep -q '<polyline' "$T/pic.svg" && grep -q 'id="curves"' "$T/pic.svg" &&
        tail -n1 "$T/pic.svg" | grep -q '</svg>'; then ok; else ko "svg out: picture incomplete"; fi
    # The picture is itself an SVG document this program reads: its curves come back.
    run "svg out re-read" 0 flatten "$T/pic.svg" && { [ -s "$T/out" ] && ok || ko "svg out re-read: empty"; }
fi
path 'M0 0 L1 1'
run "svg out unwritable" 3 flatten --svg "$T/no/such/dir/pic.svg" "$T/p.txt" &&
    expect_err "svg out unwritable" 'pic.svg'

finish
