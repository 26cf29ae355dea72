#!/usr/bin/env bash
# The plotter page of tests/cli/test_plot_page.sh (tests/data/plot/inkscape-page.svg: layers,
# transforms, arcs, text, 209 subpaths) to the Cortex-M3 image under qemu, as
# tests/fw/test_fw_m3_servo.sh runs it. To keep the run short it is fitted to a 200 x 140 mm
# page of the A4 servo machine with a 40 ms settle and drawn at the machine's max rate (the full
# A4 fit takes 170 s of machine time: docs/plotting.md gives that run's figures). The image's
# report must count as many pen settings as the plan's "pen US" lines, the last one up_us, every
# planned segment executed, and its servo timers programmed for 20 ms and up_us. Every process is
# bounded by `timeout`. Prints "cli: N passed, M failed".
set -u
JOB=tests/data/plot/inkscape-page.svg
LAY=(--page 200x140mm --margin 5 --feed 150)
# exit-idle 2 s: a link stall on a loaded host must not end the image mid-job (it happened at
# 500 ms once, beside two qemu runs and a build)
. "$(dirname "${BASH_SOURCE[0]}")/lib/m3.sh" exit-idle=2000
sed 's/^settle_ms *=.*/settle_ms = 40/' contrib/machines/servo-a4.ini >"$T/m.ini"
MC=$T/m.ini
up=$(sed -n 's/^up_us *= *\([0-9]*\).*/\1/p' "$MC")
run "plan" 0 plan --machine "$MC" "${LAY[@]}" "$JOB" -o "$T/job.seg"
grep '^plan: ' "$T/err" | sed 's/^/  /'
pens=$(grep -c '^pen ' "$T/job.seg")
nseg=$(grep -vc -e '^#' -e '^pen ' "$T/job.seg")
expect "plan has pen events ($pens)" [ "$pens" -gt 300 ]

timeout -k 5 300 "${QEMU[@]}" >"$T/fw.out" 2>&1 &
QPID=$!
pids+=("$QPID")
wait_until 60 grep -q '^char device redirected to /dev/pts/' "$T/fw.out"
FPTY=$(sed -n 's#^char device redirected to \(/dev/pts/[0-9]*\) .*#\1#p' "$T/fw.out")
expect "qemu: pty" [ -n "$FPTY" ]
timeout -k 5 300 "$CS" stream --machine "$MC" "${LAY[@]}" --line-rate 115200 --port "$FPTY" \
    "$JOB" >"$T/st.out" 2>"$T/st.err"
expect "image: stream exit 0" [ $? -eq 0 ]
wait_until 60 gone "$QPID"
wait "$QPID"; qrc=$?
expect "image: exit 0 (got $qrc)" [ $qrc -eq 0 ]
expect "image: $pens pen settings, last $up us" grep -q "^fw: pen: $pens settings, last $up us" "$T/fw.out"
expect "image: $((nseg + pens)) messages, $nseg segments" \
    grep -q "^fw: executed $((nseg + pens)) messages, $nseg step segments" "$T/fw.out"
expect "image: servo timers 20 ms, $up us" \
    grep -q "registers: period 1000000 width $((up * 50)) cycles\$" "$T/fw.out"
mean=$(sed -n 's/^fw: servo: PG1 [0-9]* periods, mean \([0-9]*\) cycles.*/\1/p' "$T/fw.out" | tail -n1)
expect "image: mean servo period 20 ms +- 5 % (${mean:-none} cycles)" \
    [ "${mean:-0}" -gt 950000 -a "${mean:-0}" -lt 1050000 ]
finish
