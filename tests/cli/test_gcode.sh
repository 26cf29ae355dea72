#!/usr/bin/env bash
# CLI tests of G-code input through the one loader: `curvestep flatten` and `curvestep plan` on
# G-code files (by extension, by content on stdin), exact vertices of lines, separated rapid
# moves, the measured deviation of arcs and helices within the tolerance, --lenient, errors as
# file:line:col with exit 1 and nothing written by plan, --help. Every file of tests/data/gcode
# (copies of shared/data/gcode/cncjs, LinuxCNC-style programs with parameters, O-words and NURBS
# in every plane, CAM output) either reads and flattens or fails where it should; --dialect and
# --units.
# Uses $CS_BUILD (the build directory); ends with "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
DATA=tests/data/gcode

expect_empty_out() {
    if [ ! -s "$T/out" ]; then ok; else ko "$1: stdout not empty"; fi
}

# expect_dev NAME TOL: --stats's measured max deviation must be <= TOL mm.
expect_dev() {
    local d
    d=$(sed -n 's/^flatten: max deviation \([0-9.]*\) mm.*/\1/p' "$T/err")
    if [ -n "$d" ] && awk -v d="$d" -v t="$2" 'BEGIN { exit !(d <= t) }'; then ok; else
        ko "$1: max deviation '$d' not within $2 mm"
    fi
}

need_bin "$CS"

# --- lines: exact vertices, rapid moves as their own polyline -------------------------------
printf 'G21 G90\nG0 X1 Y1\nG1 X10 Y1 F600\nY5\nG91 X-2\n' >"$T/l.nc"
run "lines" 0 flatten "$T/l.nc" &&
    expect_out "lines" '0.000000 0.000000\n1.000000 1.000000\n\n1.000000 1.000000\n10.000000 1.000000\n10.000000 5.000000\n8.000000 5.000000\n'
# inches
# inches (1.25 in = 31.75 mm and 0.625 in = 15.875 mm are exact in Q15.16)
printf 'G20 G1 X1.25 Y0.625 F10\n' >"$T/in.ngc"
run "inches" 0 flatten "$T/in.ngc" && expect_out "inches" '0.000000 0.000000\n31.750000 15.875000\n'
# stdin: G-code recognised by content
run "stdin" 0 flatten - <"$T/l.nc" &&
    expect_out "stdin" '0.000000 0.000000\n1.000000 1.000000\n\n1.000000 1.000000\n10.000000 1.000000\n10.000000 5.000000\n8.000000 5.000000\n'
# unknown extension: content
cp "$T/in.ngc" "$T/job.dat"
run "by content" 0 flatten "$T/job.dat" && expect_out "by content" '0.000000 0.000000\n31.750000 15.875000\n'

# --- arcs, helices, splines within the tolerance -------------------------------------------
printf 'G1 X10 Y0 F600\nG3 X10 Y0 I-10 J0\nG2 X0 Y10 R-10\nG5 I0 J3 P0 Q-3 X1 Y1\nG5.1 X5 I2 J-8\n' >"$T/a.nc"
run "arcs" 0 flatten --stats --tol 0.005 "$T/a.nc" && expect_dev "arcs" 0.005
printf 'G1 X10 Y0 F600\nG3 X10 Y0 Z6 I-10 J0 P3\n' >"$T/h.nc"
run "helix" 0 flatten --stats "$T/h.nc" && expect_dev "helix" 0.01
# the last vertex is the programmed end
run "helix end" 0 flatten "$T/h.nc" &&
    { [ "$(tail -n1 "$T/out")" = "10.000000 0.000000" ] && ok || ko "helix end: $(tail -n1 "$T/out")"; }
printf 'G0 X0 Y0\nF10\nG5.2 X0 Y1 P1 L3\nX2 Y2 P1\nX2 Y0 P1\nX0 Y0 P2\nG5.3\n' >"$T/n.nc"
run "nurbs" 0 flatten --stats "$T/n.nc" && expect_dev "nurbs" 0.01

# --- the cncjs fixtures ---------------------------------------------------------------------
for f in arc-xy-plane.nc arc-yz-plane.nc arc-zx-plane.nc one-inch-circle.nc; do
    run "$f" 0 flatten --stats "$DATA/$f" && expect_dev "$f" 0.01
done
run "thread strict" 1 flatten "$DATA/helical-thread-milling.nc" &&
    expect_err "thread strict" "^$DATA/helical-thread-milling.nc:2:9: the D word \(G41/G42.s cutter compensation number\) is not supported"
run "thread lenient" 0 flatten --lenient --stats "$DATA/helical-thread-milling.nc" &&
    expect_dev "thread lenient" 0.01 && expect_err "thread warns" ":2:5: warning: G42 is not supported"
# refused by default (as LinuxCNC does), each at its exact line:col ...
run "arc-r" 1 flatten "$DATA/arc-r.nc" && expect_err "arc-r" "^$DATA/arc-r.nc:3:1: G2 needs R" &&
    expect_empty_out "arc-r"
run "motion" 1 flatten "$DATA/motion.nc" && expect_err "motion" "^$DATA/motion.nc:1:1: G92 needs axis words"
run "special" 1 flatten "$DATA/special-fields.gcode" &&
    expect_err "special" "^$DATA/special-fields.gcode:3:4: the T word is not supported"
# ... and read with --lenient, one warning per case
run "arc-r lenient" 0 flatten --lenient --stats "$DATA/arc-r.nc" &&
    expect_err "arc-r lenient" "^$DATA/arc-r.nc:3:1: warning: G2 without R or I/J: moved in a straight line" &&
    expect_err "arc-r lenient 7" "^$DATA/arc-r.nc:7:1: warning: G3 without R or I/J" &&
    expect_dev "arc-r lenient" 0.01 &&
    { [ "$(grep -c ': warning: ' "$T/err")" = 2 ] && ok || ko "arc-r lenient: not 2 warnings"; }
# the straight move keeps the R20 arc's start: (0,0) (0,20) then the arc, ending at (10,0)
[ "$(sed -n 2p "$T/out")" = "0.000000 20.000000" ] && ok || ko "arc-r lenient: second vertex $(sed -n 2p "$T/out")"
# every block is skipped or draws nothing: the warnings, then "no drawable geometry" (exit 1)
run "motion lenient" 1 flatten --lenient "$DATA/motion.nc" &&
    expect_err "motion lenient: nothing drawn" "^$DATA/motion.nc:1:1: no drawable geometry" &&
    expect_err "motion lenient G92" "^$DATA/motion.nc:1:1: warning: G92 without X, Y or Z: ignored" &&
    expect_err "motion lenient R0" "^$DATA/motion.nc:4:9: warning: R-form arc ends where it starts.*nothing drawn" &&
    expect_err "motion lenient R0 G3" "^$DATA/motion.nc:5:9: warning: R-form arc ends where it starts" &&
    { [ "$(grep -c ': warning: ' "$T/err")" = 7 ] && ok || ko "motion lenient: not 7 warnings"; }
run "plan motion lenient" 1 plan --lenient "$DATA/motion.nc"
printf 'N3 T0*57\nG1 X1 F60\n' >"$T/t0.gcode"
run "T0 lenient" 0 flatten --lenient "$T/t0.gcode" &&
    expect_err "T0 lenient" "^$T/t0.gcode:1:4: warning: T \\(tool select\\): ignored, there is no tool changer" &&
    expect_out "T0 lenient" '0.000000 0.000000\n1.000000 0.000000\n'
# the corrupted line 8 stays an error even with --lenient (after the warnings for lines 3-5)
run "checksum" 1 flatten --lenient "$DATA/special-fields.gcode" &&
    expect_err "checksum" "^$DATA/special-fields.gcode:8:16: checksum \\*30 does not match" &&
    expect_empty_out "checksum"

# --- errors: file:line:col, exit 1 ----------------------------------------------------------
printf 'G1 X1 F60\nG1 X2 Q\n' >"$T/e1.nc"
run "syntax" 1 flatten "$T/e1.nc" && expect_err "syntax" "^$T/e1.nc:2:7: Q must be followed by a number"
printf 'G1 X10 F60\nG2 X0 Y11 I-10\n' >"$T/e2.nc"
run "radius" 1 flatten "$T/e2.nc" && expect_err "radius" "^$T/e2.nc:2:1: radius to end of arc"
printf 'G1 X1 F60\nM6 T1\n' >"$T/e3.nc"
run "unsupported" 1 flatten "$T/e3.nc" && expect_err "unsupported" "^$T/e3.nc:2:4: the T word"
run "lenient" 0 flatten --lenient "$T/e3.nc" && expect_err "lenient" "$T/e3.nc:2:1: warning: M6"
printf 'G1 X5000 F60\n' >"$T/e4.nc"
run "range" 1 flatten "$T/e4.nc" && expect_err "range" "^$T/e4.nc:1:1: point .* outside"

# --- plan: G-code in, nothing written on error ----------------------------------------------
run "plan" 0 plan "$DATA/one-inch-circle.nc" && expect_err "plan" "^plan: [0-9]+ elements" &&
    { head -n1 "$T/out" | grep -q '^# curvestep segments' && ok || ko "plan: no header"; }
run "plan lenient" 0 plan --lenient "$DATA/helical-thread-milling.nc"
run "plan bad" 1 plan "$T/e2.nc" && expect_err "plan bad" "^$T/e2.nc:2:1:" &&
    expect_empty_out "plan bad"
run "plan bad -o" 1 plan -o "$T/seg.txt" "$T/e2.nc" &&
    { [ ! -s "$T/seg.txt" ] && ok || ko "plan bad -o: segments written"; }

# --- pen lift: [pen] mode = z in the machine file turns M3 / M5 into Z moves -------------------
# 80 steps/mm: the program starts pen up (Z 0 -> 4 mm, +320 steps, before G0 X10 travels), M3
# lowers Z 4 -> -1 mm (-400 steps), M5 raises it -1 -> 4 mm (+400 steps); X goes 0 -> 20 -> 0
# (net 0); without [pen] Z never moves.
printf '[pen]\nmode = z\nup_z = 4\ndown_z = -1\n' >"$T/pen.ini"
printf 'G0 X10\nM3\nG1 X20 F600\nM5\nG0 X0\n' >"$T/pen.nc"
zsum() { awk 'NR > 1 { if ($4 > 0) p += $4; else n += $4; x += $2 } END { print p + 0, n + 0, x + 0 }' "$T/out"; }
run "pen z" 0 plan --machine "$T/pen.ini" "$T/pen.nc" &&
    { [ "$(zsum)" = "720 -400 0" ] && ok || ko "pen z: z up, z down, net x = $(zsum), expected 720 -400 0"; }
run "pen none" 0 plan "$T/pen.nc" &&
    { [ "$(zsum)" = "0 0 0" ] && ok || ko "pen none: $(zsum), expected 0 0 0"; }
printf '[pen]\nmode = z\nup_z = 4\ndown_z = -1\n[z]\ntravel_min = 0\n' >"$T/pen-bad.ini"
run "pen outside travel" 1 plan --machine "$T/pen-bad.ini" "$T/pen.nc" &&
    expect_err "pen outside travel" "^$T/pen-bad.ini:0: \\[pen\\] down_z = -1 mm is outside the z travel" &&
    expect_empty_out "pen outside travel"
printf '[pen]\nmode = lift\n' >"$T/pen-bad2.ini"
run "pen bad mode" 1 plan --machine "$T/pen-bad2.ini" "$T/pen.nc" &&
    expect_err "pen bad mode" "^$T/pen-bad2.ini:2: \\[pen\\] mode: expected none, z or servo"

# stream_final NAME FINAL MACHINE_ARGS... -- FILE: streams FILE to curvestep-sim on a pty (with
# the machine arguments, given to both) and expects the simulator's "final position: FINAL".
stream_final() {
    local name=$1 final=$2 margs=() simpid
    shift 2
    while [ "$1" != "--" ]; do margs+=("$1"); shift; done
    shift
    # (the device is ended by SIGTERM once the stream is done: a short --idle-exit can fire
    # mid-job when a loaded machine stalls the host)
    timeout -k 5 60 "$SIM" --pty --instant "${margs[@]}" >"$T/sim.out" 2>"$T/sim.err" &
    simpid=$!
    pids+=($simpid)
    wait_pty "$T/sim.out" 60
    if [ -n "$PTY" ] && run "$name" 0 stream --quiet "${margs[@]}" --port "$PTY" "$1"; then
        kill "$simpid" 2>/dev/null
        wait_until 60 gone "$simpid"
        grep -q "^final position: $final" "$T/sim.out" && ok ||
            ko "$name: $(grep '^final position' "$T/sim.out")"
    else
        [ -n "$PTY" ] || ko "$name: the simulator did not start"
    fi
    kill "$simpid" 2>/dev/null
    wait "$simpid" 2>/dev/null
}
if [ -x "$SIM" ]; then
    # The device ends with the pen up, at z = up_z = 4 mm (320 steps), x back at 0.
    stream_final "stream pen z" 'x=0 steps (0.0000 mm) y=0 steps (0.0000 mm) z=320 steps (4.0000 mm)' \
        --machine "$T/pen.ini" -- "$T/pen.nc"
    # A LinuxCNC program with a subroutine and loops ends where its last move does: X75 Y5
    # (80 steps/mm: 6000 and 400 steps).
    stream_final "stream sub-loop" 'x=6000 steps (75.0000 mm) y=400 steps (5.0000 mm) z=0 steps' \
        -- "$DATA/linuxcnc-sub-loop.ngc"
else
    ko "no $SIM"
fi
run "stream help" 0 stream --help && grep -q "\[pen\] mode = z" "$T/out" && ok ||
    ko "stream --help lacks [pen]"

# --- LinuxCNC programs: parameters, subroutines, loops, NURBS in every plane, G6.2 -----------------
# Vertices listed by hand from the program text: three 10 mm squares at (0,0), (20,5), (40,10)
# drawn by o<square> from a while loop, rapids between them, three G91 steps of 5 from X60, then
# Y5 because the loop ran three times.
run "sub-loop" 0 flatten "$DATA/linuxcnc-sub-loop.ngc" &&
    expect_out "sub-loop" '0.000000 0.000000\n10.000000 0.000000\n10.000000 10.000000\n0.000000 10.000000\n0.000000 0.000000\n\n0.000000 0.000000\n20.000000 5.000000\n\n20.000000 5.000000\n30.000000 5.000000\n30.000000 15.000000\n20.000000 15.000000\n20.000000 5.000000\n\n20.000000 5.000000\n40.000000 10.000000\n\n40.000000 10.000000\n50.000000 10.000000\n50.000000 20.000000\n40.000000 20.000000\n40.000000 10.000000\n\n40.000000 10.000000\n60.000000 0.000000\n\n60.000000 0.000000\n65.000000 0.000000\n70.000000 0.000000\n75.000000 0.000000\n75.000000 5.000000\n'
run "nurbs planes" 0 flatten --stats "$DATA/linuxcnc-nurbs-planes.ngc" && expect_dev "nurbs planes" 0.01
# G6.2 quarter circle of radius 10 (weights 1, 1/sqrt 2, 1): every chord vertex on the circle.
run "g6.2" 0 flatten --stats "$DATA/linuxcnc-g62.ngc" && expect_dev "g6.2" 0.01
run "g6.2 radius" 0 flatten "$DATA/linuxcnc-g62.ngc" &&
    { awk 'NF == 2 && !($1 == 0 && $2 == 0) && NR > 3 { r = sqrt($1 * $1 + $2 * $2); if (r < 9.9999 || r > 10.0001) bad++ } END { exit bad > 0 }' "$T/out" &&
        ok || ko "g6.2 radius: a vertex off the radius-10 circle"; }
printf '#1 = 0\no1 while [#1 GE 0]\n#1 = [#1 + 1]\no1 endwhile\n' >"$T/runaway.ngc"
run "runaway loop" 1 flatten "$T/runaway.ngc" &&
    expect_err "runaway loop" "^$T/runaway.ngc:4:1: o1 endwhile: more than 1000000 loop passes"
printf 'G1 X1e3 F60\n' >"$T/exp.nc"
run "exponent" 1 flatten --lenient "$T/exp.nc" &&
    expect_err "exponent" "^$T/exp.nc:1:6: number in exponent form .*no exponents"
printf 'G1 X1 F60\nG38.2 Z-5 F10\nG1 X2\n' >"$T/probe.nc"
run "probe lenient" 0 flatten --lenient "$T/probe.nc" &&
    expect_err "probe lenient" "^$T/probe.nc:2:1: warning: G38.2 is not supported: its block skipped, with its words Z-5" &&
    expect_out "probe lenient" '0.000000 0.000000\n1.000000 0.000000\n2.000000 0.000000\n'

# G64 P is the program's path tolerance: planning uses the smaller of it and --tol, so a circle
# with G64 P0.001 plans exactly as with --tol 0.001, and a tighter --tol wins over it.
printf 'G0 X10\nG3 X10 Y0 I-10 J0 F600\n' >"$T/circ.nc"
printf 'G64 P0.001\nG0 X10\nG3 X10 Y0 I-10 J0 F600\n' >"$T/circ64.nc"
blocks() { sed -n 's/^plan: [0-9]* elements, \([0-9]*\) blocks.*/\1/p' "$T/err"; }
run "g64 plain" 0 plan "$T/circ.nc" && b0=$(blocks)
run "g64 --tol" 0 plan --tol 0.001 "$T/circ.nc" && b1=$(blocks)
run "g64 P" 0 plan "$T/circ64.nc" && b2=$(blocks)
run "g64 P tighter tol" 0 plan --tol 0.0005 "$T/circ64.nc" && b3=$(blocks)
run "g64 tighter tol" 0 plan --tol 0.0005 "$T/circ.nc" && b4=$(blocks)
[ -n "$b2" ] && [ "$b2" = "$b1" ] && [ "$b2" -gt "$b0" ] && [ "$b3" = "$b4" ] && ok ||
    ko "g64: blocks plain $b0, --tol 0.001 $b1, G64 P0.001 $b2, both $b3, --tol 0.0005 $b4"

# --- CAM output: Fusion 360 for Grbl, CamBam ------------------------------------------------
# The Fusion 360 program positions with "X5 Y5" before any G0: Grbl starts in G0. LinuxCNC's
# dialect refuses it (at its T1 first: a tool change curvestep does not do).
run "fusion linuxcnc" 1 flatten "$DATA/fusion360-grbl.nc" &&
    expect_err "fusion linuxcnc" "^$DATA/fusion360-grbl.nc:12:1: the T word is not supported"
run "fusion grbl" 0 flatten --dialect grbl --stats "$DATA/fusion360-grbl.nc" &&
    expect_dev "fusion grbl" 0.01
# rapid to (5,5), the contour 25,5 / 25,15 / the G3 arc to 15,25 / 5,25 / 5,5
run "fusion grbl path" 0 flatten --dialect grbl "$DATA/fusion360-grbl.nc" &&
    { grep -qx '25.000000 15.000000' "$T/out" && grep -qx '15.000000 25.000000' "$T/out" &&
        grep -qx '5.000000 25.000000' "$T/out" && [ "$(sed -n 2p "$T/out")" = "5.000000 5.000000" ] &&
        ok || ko "fusion grbl path: $(tr '\n' ' ' <"$T/out" | cut -c1-200)"; }
run "dialect bad" 2 flatten --dialect fanuc "$DATA/fusion360-grbl.nc" &&
    expect_err "dialect bad" "dialect wants linuxcnc or grbl"
printf 'G1 X1.25 F10\n' >"$T/units.nc"
run "units inch" 0 flatten --units inch "$T/units.nc" && expect_out "units inch" '0.000000 0.000000\n31.750000 0.000000\n'
# CamBam: T0 M6 refused where it stands; with --lenient the part reads (G64 without P, G91.1, G40).
run "cambam strict" 1 flatten "$DATA/cambam-router.nc" &&
    expect_err "cambam strict" "^$DATA/cambam-router.nc:7:1: the T word is not supported"
run "cambam lenient" 0 flatten --lenient --stats "$DATA/cambam-router.nc" && expect_dev "cambam lenient" 0.01
run "plan cambam lenient" 0 plan --lenient "$DATA/cambam-router.nc"

# --- help tells the truth -------------------------------------------------------------------
run "flatten help" 0 flatten --help && grep -q -- "--lenient" "$T/out" && grep -q "G-code" "$T/out" &&
    ok || ko "flatten --help lacks G-code or --lenient"
run "plan help" 0 plan --help && grep -q -- "--lenient" "$T/out" && grep -q "G-code" "$T/out" &&
    ok || ko "plan --help lacks G-code or --lenient"
grep -q "\[pen\] mode = z" "$T/out" && ok || ko "plan --help lacks [pen]"

finish
