#!/usr/bin/env bash
# make demo: the main job. Starts the simulator as the device on a pseudo-terminal, streams a real
# SVG drawing (tests/data, copied from shared/data) to it with `curvestep stream`, and prints the
# device's check report: max deviation from the exact curves, job time, retransmissions, final
# position, and the picture it drew. Part 1 streams step segments; part 2 the same drawing as
# cubic curves the device interpolates itself, over a line paced at 115200 baud; part 3 keeps the
# first demo's flattening picture; part 4 makes the Utah teapot's iso wireframe and drop-cutter
# finishing path (ball R 2 mm, gouge-free from above: `curvestep toolpath --cutter --gcode`),
# plans them and runs them through the simulator, which checks and draws them; part 5 draws one curves file holding every basis of the core
# (flatten, plan, simulator). Exits non-zero when any check fails. Every background process
# is bounded by `timeout` and killed on exit.
set -u
. "$(dirname "$0")/args.sh"
cs_args "usage: scripts/demo.sh   (make demo; BUILD=DIR: where the programs are, default build)\nStreams a drawing to the simulated device, then the teapot jobs; prints the\nchecks and where the pictures are. Exit non-zero when a check fails." 0 "$@"
BUILD=${BUILD:-build}
CS=$BUILD/curvestep
SIM=$BUILD/curvestep-sim
OUT=$BUILD/demo
JOB=tests/data/svg/w3c/paths-data-01-t.svg # W3C SVG 1.1: cubic Béziers, subpaths, closepath
SPEED=20                                   # simulated seconds per wall second
mkdir -p "$OUT"
failures=0
pids=()
cleanup() {
    for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done
    wait 2>/dev/null
}
trap cleanup EXIT

for b in "$CS" "$SIM"; do
    if [ ! -x "$b" ]; then
        echo "demo: $b is missing (run make all)" >&2
        exit 1
    fi
done

# stream NAME MODE SIM-ARGS -- STREAM-ARGS: one streamed job, checked; report in $OUT/NAME.*
stream() {
    local name=$1 mode=$2; shift 2
    local simargs=() streamargs=()
    while [ $# -gt 0 ] && [ "$1" != -- ]; do simargs+=("$1"); shift; done
    [ $# -gt 0 ] && shift
    streamargs=("$@")
    timeout -k 5 300 "$SIM" --pty --speed "$SPEED" --reference "$JOB" --check \
        --svg "$OUT/$name.svg" --png "$OUT/$name.png" "${simargs[@]}" \
        >"$OUT/$name.report" 2>"$OUT/$name.simlog" &
    local sim=$!
    pids+=("$sim")
    local pty=
    for _ in $(seq 1200); do # up to 60 s: a loaded machine starts it late
        pty=$(head -n1 "$OUT/$name.report" 2>/dev/null)
        [ -n "$pty" ] && break
        sleep 0.05
    done
    if [ -z "$pty" ]; then
        echo "  $name: FAILED (the simulator did not start)"
        failures=$((failures + 1))
        return
    fi
    echo "  device on $pty; curvestep stream --mode $mode ${streamargs[*]} $JOB"
    timeout -k 5 300 "$CS" stream --port "$pty" --mode "$mode" "${streamargs[@]}" "$JOB" \
        >"$OUT/$name.stream" 2>"$OUT/$name.progress"
    local rc=$?
    # SIGTERM: the device finishes what its executor holds, then reports (a stalled host on a
    # loaded machine must not end it mid-job, as an idle timeout would)
    kill "$sim" 2>/dev/null
    for _ in $(seq 1200); do kill -0 "$sim" 2>/dev/null || break; sleep 0.05; done
    wait "$sim"
    local simrc=$?
    grep -v 'to continue' "$OUT/$name.stream" | sed 's/^stream: /  host:   /'
    grep -E '^(device|link|executor|job time|final position|max deviation|check)' \
        "$OUT/$name.report" | sed 's/^device: /device: /; s/^/  /'
    echo "  picture: $OUT/$name.svg ($OUT/$name.png)"
    if [ "$rc" -ne 0 ] || [ "$simrc" -ne 0 ] || ! grep -q '^check: ok$' "$OUT/$name.report"; then
        echo "  $name: FAILED (stream exit $rc, simulator exit $simrc)"
        failures=$((failures + 1))
    fi
}

echo "demo 1: step segments planned on the host, streamed over a pty to the simulated device"
echo "        (device at ${SPEED}x real time, 32-slot queue; the executor's STEP edges are checked"
echo "        against the exact curves)"
stream stream segments --
echo
echo "demo 2: the same drawing as cubic curves, interpolated and planned on the device, over a"
echo "        line paced at 115200 baud in both directions"
stream stream-curves curves --line-rate 115200 -- --line-rate 115200
echo

# demo 3: the flattening picture of the first demo (chords within 0.01 mm, measured in double).
echo "demo 3: curvestep flatten (chords within 0.01 mm of the exact curves)"
"$CS" flatten --stats --tol 0.01 --svg "$OUT/flatten.svg" "$JOB" >"$OUT/flatten.txt" \
    2>"$OUT/flatten.log"
rc=$?
dev=$(sed -n 's/.*max deviation \([0-9.]*\) mm.*/\1/p' "$OUT/flatten.log")
if [ $rc -ne 0 ] || [ -z "$dev" ] || ! awk -v d="$dev" 'BEGIN { exit !(d <= 0.01) }'; then
    echo "  flatten: FAILED (exit $rc, deviation '${dev:-?}')"
    failures=$((failures + 1))
else
    echo "  max deviation $dev mm; picture: $OUT/flatten.svg"
fi

# demo 4: the Utah teapot (tests/data/teapot, 10 mm per unit): its iso wireframe for a pen plotter
# and its drop-cutter finishing path for a router (ball R 2 mm dropped onto the surface from above,
# so it never gouges; the tool tip programmed, with feeds), each written as G-code by `curvestep
# toolpath`, planned, and executed and drawn by the simulator (H 0.2 mm, tol 0.02 mm: about 1.5 s
# of planning; the finer H 0.05 / tol 0.01 is docs/benchmarks.md's bench_dropcut).
TEAPOT=tests/data/teapot/newell_teapot.txt
echo
echo "demo 4: the Utah teapot through the simulator (toolpath --gcode, plan, curvestep-sim)"
# surface NAME VIEW TOOLPATH-ARGS...: toolpath -> G-code -> plan -> simulated run, checked, drawn.
surface() {
    local name=$1 view=$2
    shift 2
    echo "  curvestep toolpath --patches $TEAPOT --scale 10 $* --gcode $OUT/$name.nc"
    if ! timeout -k 5 120 "$CS" toolpath --patches "$TEAPOT" --scale 10 "$@" --gcode "$OUT/$name.nc" \
        --stats >"$OUT/$name.txt" 2>"$OUT/$name.toolpath"; then
        echo "  $name: FAILED (toolpath)"
        failures=$((failures + 1))
        return
    fi
    grep -E '^(toolpath: |curvestep toolpath: warning)' "$OUT/$name.toolpath" | sed 's/^/  /'
    if ! timeout -k 5 120 "$CS" plan -o "$OUT/$name.seg" "$OUT/$name.nc" 2>"$OUT/$name.plan"; then
        echo "  $name: FAILED (plan)"
        failures=$((failures + 1))
        return
    fi
    sed 's/^/  /' "$OUT/$name.plan"
    timeout -k 5 120 "$SIM" --replay "$OUT/$name.seg" --reference "$OUT/$name.nc" --check \
        --view "$view" --svg "$OUT/$name.svg" --png "$OUT/$name.png" >"$OUT/$name.report" 2>&1
    local rc=$?
    grep -E '^(replay|final position|deviation|check)' "$OUT/$name.report" | sed 's/^/  /'
    echo "  picture ($view view, drawn by the simulator): $OUT/$name.svg ($OUT/$name.png)"
    if [ $rc -ne 0 ] || ! grep -q '^check: ok$' "$OUT/$name.report"; then
        echo "  $name: FAILED (simulator exit $rc)"
        failures=$((failures + 1))
    fi
}
# The wireframe is projected to the iso view by toolpath (a 2D job): the simulator draws it as is.
surface teapot-wireframe top --view iso --lines 4
echo
surface teapot-finish iso --cutter ball:2 --scallop 0.2 --tol 0.02

# demo 5: every basis of the core in one picture, from one curves file (docs/inputs.md): flattened
# (chords within 0.01 mm, measured), then planned and run by the simulator against the file.
CURVES=tests/data/curves/every-basis.curves
echo
echo "demo 5: every basis in one curves file ($CURVES)"
"$CS" flatten --stats --tol 0.01 --svg "$OUT/every-basis.svg" "$CURVES" >/dev/null \
    2>"$OUT/every-basis.log"
rc=$?
dev=$(sed -n 's/.*max deviation \([0-9.]*\) mm.*/\1/p' "$OUT/every-basis.log")
"$CS" plan -o "$OUT/every-basis.seg" "$CURVES" 2>>"$OUT/every-basis.log" &&
    timeout -k 5 120 "$SIM" --replay "$OUT/every-basis.seg" --reference "$CURVES" --check \
        --png "$OUT/every-basis.png" >"$OUT/every-basis.report" 2>&1
simrc=$?
grep -E '^(deviation|check)' "$OUT/every-basis.report" | sed 's/^/  /'
if [ $rc -ne 0 ] || [ $simrc -ne 0 ] || ! awk -v d="${dev:-1}" 'BEGIN { exit !(d <= 0.01) }'; then
    echo "  every-basis: FAILED (flatten exit $rc, deviation '${dev:-?}', simulator exit $simrc)"
    failures=$((failures + 1))
else
    echo "  max chord deviation $dev mm; pictures: $OUT/every-basis.svg, $OUT/every-basis.png"
fi

echo
if [ "$failures" -ne 0 ]; then
    echo "demo: $failures check(s) FAILED"
    exit 1
fi
echo "demo: all checks passed; the streamed drawing: $OUT/stream.svg; the teapot:"
echo "      $OUT/teapot-wireframe.png, $OUT/teapot-finish.png"
