#!/usr/bin/env bash
# Command-line tests of `curvestep plan` and `curvestep-sim --replay`: a real SVG job planned and
# replayed with every check passing, drawings written, soft limits refused with the input's
# file:line:col, bad machine and segment files reported as file:line, and a segments file that
# breaks the rate limit failing --check. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"

JOB=tests/data/svg/w3c/paths-data-12-t.svg

# 1. plan writes a header and "ticks dx dy dz" lines, summary on stderr.
"$CS" plan "$JOB" >"$T/seg.txt" 2>"$T/err.txt"; rc=$?
expect "plan exit 0" [ $rc -eq 0 ]
expect "plan header" grep -q '^# curvestep segments tick_hz=100000 axes=3$' "$T/seg.txt"
expect "plan lines are 4 integers" bash -c "! grep -v '^#' '$T/seg.txt' | grep -vqE '^[0-9]+ -?[0-9]+ -?[0-9]+ -?[0-9]+$'"
expect "plan has segments" [ "$(grep -vc '^#' "$T/seg.txt")" -gt 100 ]
expect "plan summary" grep -qE 'plan: .* blocks, [0-9]+ segments, [0-9]+ steps, job time [0-9.]+ s' "$T/err.txt"

# 2. replay with the job as reference: every check passes; drawings and trace written.
"$SIM" --replay "$T/seg.txt" --reference "$JOB" --check --svg "$T/run.svg" --png "$T/run.png" \
    --trace "$T/run.csv" >"$T/sim.txt" 2>"$T/simerr.txt"; rc=$?
expect "sim check exit 0" [ $rc -eq 0 ]
expect "sim reports check ok" grep -q '^check: ok$' "$T/sim.txt"
expect "sim final position exact" grep -q 'rounded to steps: exact' "$T/sim.txt"
expect "sim per-axis peaks" [ "$(grep -c '^axis [xyz]: peak velocity .* ok; peak acceleration .* ok$' "$T/sim.txt")" -eq 3 ]
expect "sim deviation line" grep -qE '^deviation: [0-9.]+ mm .* ok$' "$T/sim.txt"
expect "svg drawing" grep -q '<polyline' "$T/run.svg"
expect "png drawing" bash -c "head -c 8 '$T/run.png' | od -An -c | grep -q 'P   N   G'"
expect "trace csv" [ "$(head -n1 "$T/run.csv")" = "t_s,axis,dir,x_mm,y_mm,z_mm" ]
steps=$(sed -n 's/^replay: [0-9]* segments, \([0-9]*\) steps.*/\1/p' "$T/sim.txt")
expect "trace has one line per step" [ "$(($(wc -l <"$T/run.csv") - 1))" = "$steps" ]

# 3. soft limits: a machine whose x travel ends at 100 mm refuses the job, naming the input.
cat >"$T/small.ini" <<'INI'
[x]
travel_min = 0
travel_max = 100
INI
"$CS" plan --machine "$T/small.ini" "$JOB" >"$T/seg2.txt" 2>"$T/err2.txt"; rc=$?
expect "soft limit exit 1" [ $rc -eq 1 ]
expect "soft limit file:line:col" grep -qE "^$JOB:[0-9]+:[0-9]+: move to x = .* leaves the travel" "$T/err2.txt"
expect "soft limit: no segments written" bash -c "! grep -qv '^#' '$T/seg2.txt'"

# 4. a bad machine file: file:line: reason.
printf '[x]\nsteps_per_mm = lots\n' >"$T/bad.ini"
"$CS" plan --machine "$T/bad.ini" "$JOB" >/dev/null 2>"$T/err3.txt"; rc=$?
expect "bad machine exit 1" [ $rc -eq 1 ]
expect "bad machine message" grep -q "^$T/bad.ini:2: \[x\] steps_per_mm: not a number" "$T/err3.txt"

# 5. a bad segments file: file:line: reason.
printf '# comment\n500 1 2 3\n500 1 2\n' >"$T/bad.seg"
"$SIM" --replay "$T/bad.seg" >/dev/null 2>"$T/err4.txt"; rc=$?
expect "bad segments exit 1" [ $rc -eq 1 ]
expect "bad segments message" grep -q "^$T/bad.seg:3: expected 4 integers" "$T/err4.txt"

# 6. segments that run x at 500 mm/s (limit 200): --check fails with exit 4.
{ echo "# curvestep segments tick_hz=100000 axes=3"; for i in $(seq 1 200); do echo "500 200 0 0"; done; } >"$T/fast.seg"
"$SIM" --replay "$T/fast.seg" --check >"$T/sim5.txt" 2>&1; rc=$?
expect "over rate: exit 4" [ $rc -eq 4 ]
expect "over rate reported" grep -q '^axis x: peak velocity 500.000 mm/s .* OVER' "$T/sim5.txt"

# 7. every SVG test file (copied from shared/data, see tests/data): plan, replay, --check passes
#    (limits, tolerance + one step, exact final position). A.svg is invalid on purpose.
for f in tests/data/svg/*/*.svg; do
    case $(basename "$f") in A.svg) continue ;; esac
    if "$CS" plan "$f" -o "$T/s.txt" 2>/dev/null &&
        "$SIM" --replay "$T/s.txt" --reference "$f" --check >"$T/s.out" 2>/dev/null; then
        ok
    else
        ko "plan + replay --check on $f"
        cat "$T/s.out"
    fi
done

# 8. G-code (arcs in each plane, a helix with --lenient for its G42/D words) and HP-GL: the
#    job's own F and G0 rapids are planned, and the replay passes every check.
for f in tests/data/gcode/arc-xy-plane.nc tests/data/gcode/arc-zx-plane.nc \
    tests/data/gcode/one-inch-circle.nc tests/data/gcode/helical-thread-milling.nc \
    tests/data/hpgl/feature-exercise.plt; do
    if "$CS" plan --lenient "$f" -o "$T/g.txt" 2>/dev/null &&
        "$SIM" --replay "$T/g.txt" --reference "$f" --lenient --check >"$T/g.out" 2>/dev/null; then
        ok
    else
        ko "plan + replay --check on $f"
        cat "$T/g.out"
    fi
done

# 9. --help tells the truth and exits 0.
"$CS" plan --help >"$T/h1.txt"; rc=$?
expect "plan --help" [ $rc -eq 0 ]
expect "plan --help text" grep -q 'usage: curvestep plan' "$T/h1.txt"
# 9. the spindle / laser in the plan: a "# spindle" comment line before the first segment of each
#    change, none for a job that never turns one on. M4 S1000 to X10, S500 to X20 (one line),
#    then a rapid home: the S500 line comes after exactly 10 mm x 80 steps/mm = 800 x steps,
#    the rapid's after 20 x 80 = 1600; the summary counts the 3 changes.
printf '%s\n' 'G21 G90' 'M4 S1000' 'G1 X10 F600' 'G1 X20 S500' 'G0 X0' 'M5' >"$T/sp.nc"
"$CS" plan "$T/sp.nc" >"$T/sp.seg" 2>"$T/sp.err"; rc=$?
expect "spindle: plan exit 0" [ $rc -eq 0 ]
awk '/^# spindle/ { print $0 " after " x; next } !/^#/ { x += $2 }' "$T/sp.seg" >"$T/sp.marks"
expect "spindle: M4 S1000 F10 before the first segment" grep -qx '# spindle M4 S1000 F10.000 after ' "$T/sp.marks"
expect "spindle: S500 after 800 x steps" grep -qx '# spindle M4 S500 F10.000 after 800' "$T/sp.marks"
expect "spindle: the rapid after 1600" grep -qx '# spindle M4 S500 rapid after 1600' "$T/sp.marks"
expect "spindle: summary" grep -qxF 'plan: spindle: 3 changes ("# spindle" lines), largest S 1000' "$T/sp.err"
expect "spindle: none without M3/M4" bash -c "! grep -q spindle '$T/seg.txt' '$T/err.txt'"
"$SIM" --replay "$T/sp.seg" >"$T/sp.sim" 2>&1
expect "spindle: the comments replay (x back at 0)" grep -q '^final position: x=0 steps' "$T/sp.sim"

"$SIM" --help >"$T/h2.txt"; rc=$?
expect "sim --help" [ $rc -eq 0 ]
expect "sim --help text" grep -q -- '--replay SEGMENTS' "$T/h2.txt"

finish
