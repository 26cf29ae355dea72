#!/usr/bin/env bash
# A plotter page end to end (docs/plotting.md, section 6): tests/data/plot/inkscape-page.svg, an
# Inkscape-style A3 page (layers with transforms, arcs, text, 209 subpaths in a scattered
# order), fitted to the A4 servo-pen machine (contrib/machines/servo-a4.ini, --fit --margin 10).
# plan: merge and sort cut the pen-up travel to under half of file order (the figures of its
# report line, and the plan's job time shorter than the file-order plan's); the laid-out page
# inside the bed (plan accepts it only then). The simulator replays it with the plotter check
# (pen-downs = the plan's down_us events), and the same job streamed to the simulated device
# (--pty) sets the pen as many times as the plan's "pen US" lines, check ok. The Cortex-M3 image
# takes it under qemu in tests/fw/test_fw_m3_page.sh. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
need_bin "$CS" "$SIM"
MC=contrib/machines/servo-a4.ini
JOB=tests/data/plot/inkscape-page.svg
LAY=(--fit --margin 10)
down=$(sed -n 's/^down_us *= *\([0-9]*\).*/\1/p' "$MC")

run "plan sorted" 0 plan --machine "$MC" "${LAY[@]}" "$JOB" -o "$T/page.seg"
line=$(grep '^plan: .* pen lifts' "$T/err")
js=$(sed -n 's/^plan: .*job time \([0-9.]*\) s.*/\1/p' "$T/err")
echo "  $line"
read -r l0 l1 t0 t1 < <(echo "$line" | sed -n \
    's/^plan: \([0-9]*\) pen lifts -> \([0-9]*\), pen-up travel \([0-9.]*\) mm -> \([0-9.]*\) mm.*/\1 \2 \3 \4/p')
expect "209 strokes in the file ($l0)" [ "${l0:-0}" = 209 ]
expect "merge joins some (${l1:-?} < $l0)" [ "${l1:-999}" -lt "${l0:-0}" ]
expect "sort: pen-up travel $t1 mm under half of file order's $t0 mm" \
    awk -v a="${t0:-0}" -v b="${t1:-1e9}" 'BEGIN { exit !(b < a / 2) }'
run "plan in file order" 0 plan --machine "$MC" "${LAY[@]}" --no-merge --no-sort "$JOB" -o "$T/file.seg"
jf=$(sed -n 's/^plan: .*job time \([0-9.]*\) s.*/\1/p' "$T/err")
expect "sorted job time ${js:-?} s shorter than file order's ${jf:-?} s" \
    awk -v a="${js:-1e9}" -v b="${jf:-0}" 'BEGIN { exit !(a < b) }'
pens=$(grep -c '^pen ' "$T/page.seg")
lowers=$(grep -c "^pen $down\$" "$T/page.seg")
expect "one lowering per stroke drawn ($lowers = $l1)" [ "$lowers" = "${l1:-x}" ]

"$SIM" --replay "$T/page.seg" --machine "$MC" "${LAY[@]}" --reference "$JOB" --check \
    >"$T/replay.out" 2>&1
expect "replay: check ok" grep -q '^check: ok$' "$T/replay.out"
expect "replay: $lowers pen-downs, strokes reached" \
    grep -qE "^pen: $lowers pen-downs; drawn strokes reached pen down within .* ok\$" "$T/replay.out"

timeout -k 5 120 "$SIM" --pty --instant --machine "$MC" "${LAY[@]}" --reference "$JOB" \
    --check >"$T/dev.sim" 2>"$T/dev.err" &
sp=$!
pids+=($sp)
wait_pty "$T/dev.sim" 60
timeout -k 5 120 "$CS" stream --machine "$MC" "${LAY[@]}" --port "$PTY" "$JOB" >"$T/s.out" 2>&1
expect "stream: exit 0" [ $? -eq 0 ]
kill "$sp" 2>/dev/null # SIGTERM: it finishes what it holds, then reports (exit 0)
wait_until 60 gone "$sp"
wait "$sp"
expect "device: exit 0" [ $? -eq 0 ]
expect "device: set the pen $pens times" grep -q "^pen: the device set the servo pen $pens times" "$T/dev.sim"
expect "device: $lowers pen-downs, check ok" grep -q '^check: ok$' "$T/dev.sim"
finish
