#!/usr/bin/env bash
# make demo (first version): flattens real drawings (the W3C SVG 1.1 path tests and resvg arc
# cases copied in tests/data/svg) with `curvestep flatten --stats --svg`, checks each result
# (the command succeeded, every drawing produced vertices, the deviation measured against the
# exact curves is within the tolerance), prints a short report and where the pictures are.
# Later issues replace this with a streamed job.
set -u
BUILD=${BUILD:-build}
BIN=$BUILD/curvestep
OUT=$BUILD/demo
TOL=0.01
mkdir -p "$OUT"
failures=0

if [ ! -x "$BIN" ]; then
    echo "demo: $BIN is missing (run make all)" >&2
    exit 1
fi

# flatten NAME INPUT TOL METHOD: runs one flattening into $OUT/NAME.{txt,log,svg} and checks it.
flatten() {
    local name=$1 input=$2 tol=$3 method=$4
    "$BIN" flatten --stats --tol "$tol" --method "$method" --svg "$OUT/$name.svg" "$input" \
        >"$OUT/$name.txt" 2>"$OUT/$name.log"
    local rc=$?
    local vertices dev summary status=ok
    vertices=$(grep -c . "$OUT/$name.txt")
    dev=$(sed -n 's/.*max deviation \([0-9.]*\) mm.*/\1/p' "$OUT/$name.log")
    summary=$(sed -n 's/^flatten: [^:]*: \(.*\)$/\1/p' "$OUT/$name.log")
    if [ "$rc" -ne 0 ]; then
        status="FAILED (exit $rc)"
    elif [ "$vertices" -eq 0 ]; then
        status="FAILED (no vertices)"
    elif [ -z "$dev" ] || ! awk -v d="$dev" -v t="$tol" 'BEGIN { exit !(d <= t) }'; then
        status="FAILED (deviation '$dev' > tol $tol)"
    fi
    [ "$status" = ok ] || failures=$((failures + 1))
    printf '  %-22s %-6s tol %-5s %s, max deviation %s mm: %s\n' "$name" "$method" "$tol" \
        "$summary" "${dev:-?}" "$status"
    if [ "$status" != ok ]; then sed 's/^/      /' "$OUT/$name.log" | head -5; fi
    if command -v rsvg-convert >/dev/null 2>&1 && [ -s "$OUT/$name.svg" ]; then
        rsvg-convert "$OUT/$name.svg" -o "$OUT/$name.png" 2>/dev/null || true
    fi
}

echo "demo: curvestep flatten on real drawings (vertices in mm, deviation measured in double)"
# The main picture: W3C paths-data-01 (cubic Béziers C c S s, subpaths, closepath).
flatten flatten tests/data/svg/w3c/paths-data-01-t.svg "$TOL" subdiv
# The same drawing with each tracing method, for comparison of chord counts.
flatten cubics-fd tests/data/svg/w3c/paths-data-01-t.svg "$TOL" fd
flatten cubics-afd tests/data/svg/w3c/paths-data-01-t.svg "$TOL" afd
# Quadratics (Q q T t), poly-Béziers with implicit S, an initial relative moveto under a
# group transform, and elliptical arcs (rotated, radii scaled up, after z).
flatten quadratics tests/data/svg/w3c/paths-data-02-t.svg "$TOL" subdiv
flatten polybezier tests/data/svg/w3c/paths-data-12-t.svg "$TOL" subdiv
flatten transformed tests/data/svg/w3c/paths-data-14-t.svg "$TOL" subdiv
flatten arc-then-s tests/data/svg/resvg/M-A-s.svg "$TOL" subdiv
flatten arc-after-z tests/data/svg/resvg/M-L-Z-A.svg "$TOL" subdiv
# A coarse tolerance, so the chords are visible in the picture.
flatten quadratics-coarse tests/data/svg/w3c/paths-data-02-t.svg 1 subdiv

echo
echo "demo: picture of the main drawing: $OUT/flatten.svg (exact curves in blue, chords and"
echo "      vertices in red); chords visible at 1 mm: $OUT/quadratics-coarse.svg"
[ -f "$OUT/flatten.png" ] && echo "      PNG renderings (rsvg-convert): $OUT/*.png"
if [ "$failures" -ne 0 ]; then
    echo "demo: $failures check(s) FAILED"
    exit 1
fi
echo "demo: all checks passed"
