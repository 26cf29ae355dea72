#!/usr/bin/env bash
# Command-line tests of `curvestep stream --gpio` as a user runs it. This machine has no GPIO
# chip, so the job runs on the real step thread through the recorder (`--gpio record:FILE`),
# and the recorded edges are checked against `curvestep plan` + `curvestep-sim --replay --trace`
# for the same job and machine: every step on every axis at the simulator's tick, in the
# simulator's direction (DIR inverted on y); every STEP pulse at least pulse_us; DIR stable at
# least dir_setup_us before every STEP rise; no edge before its planned time; ENABLE on before
# the first step and every line safe at the end. Ctrl-C holds at a segment end (exit 8, the
# position exactly the executed segments'), --resume-from finishes the job, a missing chip is
# exit 4 with a message naming it, bad [gpio] keys are file:line errors. Every process is
# bounded by `timeout`. Prints "cli: N passed, M failed".
set -u
B=${CS_BUILD:-build}
CS=$B/curvestep
SIM=$B/curvestep-sim
# the shared harness: T, pids (killed on exit), ok / ko / expect (tests/cli/lib/common.sh)
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"

# A short job (about 1 s) with reversals on x, y and z, ending away from the origin.
cat >"$T/job.nc" <<'EOF'
G21 G90
G1 X10 Y5 Z1 F6000
G2 X2 Y5 I-4 J0
G1 X-3 Y-2 Z-1
G0 X7 Y-4 Z2
EOF
# A longer one (about 4 s) to interrupt once it has executed a segment.
printf 'G21 G90\nG1 X150 Y100 F3000\n' >"$T/long.nc"
cp tests/data/gpio/wired3.ini "$T/m.ini"

# check_record REC TRACE PULSE_NS SETUP_NS: the record against the simulator's trace. Prints
# "ok <steps>" or the first problem.
check_record() {
    awk -F, -v pulse="$3" -v setup="$4" '
    BEGIN { last = -1e18 }
    FNR == 1 { file++ }
    file == 1 && FNR > 1 { # the trace: t_s,axis,dir,...
        n[$2]++; tick[$2, n[$2]] = int($1 * 100000 + 0.5); sdir[$2, n[$2]] = $3; next }
    file == 2 && /^#/ { next }
    file == 2 && $1 == "t_ns" { next }
    file == 2 {
        t = $1 + 0; p = $2 + 0; line = $3; lv = $4 + 0
        if (t < last) { print "edge out of order at " t; bad = 1; exit }
        if (t < p) { print "edge before its planned time at " t; bad = 1; exit }
        last = t
        split(line, w, "_")
        if (line == "enable") { en = lv; enabled = enabled || lv; level[line] = lv; next }
        if (w[2] == "dir") { dirlv[w[1]] = lv; tdir = t; level[line] = lv; next }
        ax = w[1]
        if (lv == 1) {
            if (!enabled) { print "step before enable"; bad = 1; exit }
            if (t - tdir < setup) { print "DIR set-up " t - tdir " ns before a step at " t; bad = 1; exit }
            k = ++m[ax]
            d = (dirlv[ax] ? 1 : -1) * (ax == "y" ? -1 : 1)
            pos[ax] += d
            if (k > n[ax]) { print "more " ax " steps than the simulator"; bad = 1; exit }
            if (d != sdir[ax, k]) { print ax " step " k ": direction " d ", simulator " sdir[ax, k]; bad = 1; exit }
            if (p / 10000 + 1 != tick[ax, k]) { print ax " step " k ": planned " p " ns, simulator tick " tick[ax, k]; bad = 1; exit }
            trise[ax] = t
        } else if (t - trise[ax] < pulse) { print ax " pulse of " t - trise[ax] " ns"; bad = 1; exit }
        level[line] = lv
    }
    END {
        if (bad) exit 1
        for (a in n) if (m[a] != n[a]) { print a ": " m[a] " steps, simulator " n[a]; exit 1 }
        if (level["x_step"] || level["y_step"] || level["z_step"] || level["enable"]) { print "lines not safe at the end"; exit 1 }
        print "ok " (m["x"] + m["y"] + m["z"]) " " pos["x"] " " pos["y"] " " pos["z"]
    }' "$2" "$1"
}

# 1. the job through the recorder, checked against the simulator.
"$CS" plan --machine "$T/m.ini" -o "$T/job.seg" "$T/job.nc" 2>/dev/null
timeout -k 5 60 "$SIM" --replay "$T/job.seg" --machine "$T/m.ini" --trace "$T/job.trace" >"$T/job.sim"
timeout -k 5 60 "$CS" stream --gpio "record:$T/job.rec" --machine "$T/m.ini" "$T/job.nc" \
    >"$T/job.out" 2>"$T/job.err"; rc=$?
expect "record: exit 0" [ $rc -eq 0 ]
n=$(grep -vc '^#' "$T/job.seg")
expect "record: job executed" grep -q "^stream: record:$T/job.rec: job executed$" "$T/job.out"
expect "record: every segment executed" grep -q "^stream: $n of $n segments executed.*last executed: $n$" "$T/job.out"
expect "record: timing summary" grep -qE '^stream: [0-9]+ steps \(x [0-9]+, y [0-9]+, z [0-9]+\) .* STEP edges late by: median' "$T/job.out"
expect "record: progress lines" grep -q "^stream: $n/$n segments executed (100.0 %)" "$T/job.err"
expect "record: lines named" grep -q 'record:.*: 7 lines (x_step, x_dir, y_step, y_dir, z_step, z_dir, enable); STEP pulse 4.000 us, DIR set-up 20.000 us' "$T/job.err"
res=$(check_record "$T/job.rec" "$T/job.trace" 4000 20000)
steps=$(sed -n 's/^replay: .*, \([0-9]*\) steps,.*/\1/p' "$T/job.sim")
expect "record: edges match the simulator ($res)" [ "${res%% *}" = ok ]
expect "record: as many steps as the simulator" [ "$(echo "$res" | cut -d' ' -f2)" = "$steps" ]
fin=$(sed -n 's/^final position: x=\(-*[0-9]*\) steps .* y=\(-*[0-9]*\) steps .* z=\(-*[0-9]*\) steps.*/\1 \2 \3/p' "$T/job.sim")
expect "record: final position = simulator's ($fin)" [ "$(echo "$res" | cut -d' ' -f3-)" = "$fin" ]
expect "record: job ends away from the origin" [ "$fin" = "560 -320 160" ]

# 2. Ctrl-C: hold, stop at a segment end, exit 8; the position is that of the executed segments.
"$CS" plan --machine "$T/m.ini" -o "$T/long.seg" "$T/long.nc" 2>/dev/null
nl=$(grep -vc '^#' "$T/long.seg")
# (--foreground: timeout would otherwise pass the signal on twice, which means "stop at once")
timeout --foreground -k 5 60 "$CS" stream --gpio "record:$T/int.rec" --machine "$T/m.ini" "$T/long.nc" \
    >"$T/int.out" 2>"$T/int.err" &
spid=$!
pids+=("$spid")
# the event: a progress line (once a second) that counts an executed segment
moving() { grep -qE '^stream: [1-9][0-9]*/' "$T/int.err"; }
expect "ctrl-c: the job is moving" wait_until 30 moving
kill -INT "$spid"
wait "$spid"; rc=$?
expect "ctrl-c: exit 8" [ $rc -eq 8 ]
expect "ctrl-c: held" grep -q "^stream: record:$T/int.rec: interrupted: held, then stopped at the end of a segment" "$T/int.out"
k=$(sed -n 's/.*last executed: \([0-9]*\)$/\1/p' "$T/int.out")
expect "ctrl-c: stopped mid-job ($k of $nl)" [ -n "$k" ] && [ "$k" -gt 0 ] && [ "$k" -lt "$nl" ]
expect "ctrl-c: resume hint" grep -q "curvestep stream --resume-from $k" "$T/int.out"
want=$(grep -v '^#' "$T/long.seg" | head -n "$k" | awk '{x += $2; y += $3; z += $4} END {print x " " y " " z}')
got=$(awk -F, '/^[0-9-]/ && $4 == 1 && $3 ~ /_step$/ { split($3, w, "_"); pos[w[1]] += (dir[w[1]] ? 1 : -1) * (w[1] == "y" ? -1 : 1) }
    /^[0-9-]/ && $3 ~ /_dir$/ { split($3, w, "_"); dir[w[1]] = $4 }
    /^[0-9-]/ { last[$3] = $4 }
    END { print pos["x"] + 0 " " pos["y"] + 0 " " pos["z"] + 0; if (last["enable"] || last["x_step"] || last["y_step"]) print "unsafe" }' "$T/int.rec")
expect "ctrl-c: position = segments 1..$k ($got)" [ "$got" = "$want" ]

# 3. --resume-from K runs the rest: together they reach the job's end.
timeout -k 5 60 "$CS" stream --gpio "record:$T/res.rec" --machine "$T/m.ini" --resume-from "$k" --quiet \
    "$T/long.nc" >"$T/res.out" 2>"$T/res.err"; rc=$?
expect "resume: exit 0" [ $rc -eq 0 ]
expect "resume: all executed" grep -q "^stream: $nl of $nl segments executed" "$T/res.out"
expect "resume: quiet" [ "$(grep -c '^stream: [0-9][0-9]*/' "$T/res.err")" -eq 0 ]
rest=$(grep -v '^#' "$T/long.seg" | tail -n +"$((k + 1))" | awk '{x += $2} END {print x}')
xr=$(awk -F, '$3 == "x_step" && $4 == 1 { n++ } END { print n + 0 }' "$T/res.rec")
expect "resume: the remaining x steps ($xr = $rest)" [ "$xr" = "$rest" ]

# 4. a chip that is not there: exit 4, the chip named, what to check.
timeout -k 5 20 "$CS" stream --gpio gpiochip9 "$T/job.nc" >/dev/null 2>"$T/nochip.err"; rc=$?
expect "no chip: exit 4" [ $rc -eq 4 ]
expect "no chip: named" grep -q 'cannot open GPIO chip gpiochip9' "$T/nochip.err"
expect "no chip: what to check" grep -q '/dev/gpiochip9 exists.*label.*gpio group' "$T/nochip.err"
sed 's/^chip = .*/chip = gpiochip9/' "$T/m.ini" >"$T/m9.ini"
timeout -k 5 20 "$CS" stream --gpio /dev/gpiochip9 --machine "$T/m9.ini" "$T/job.nc" >/dev/null 2>&1; rc=$?
expect "no chip by path: exit 4" [ $rc -eq 4 ]

# 5. configuration errors.
timeout -k 5 20 "$CS" stream --gpio gpiochip1 --machine "$T/m.ini" "$T/job.nc" >/dev/null 2>"$T/mis.err"; rc=$?
expect "chip mismatch: exit 2" [ $rc -eq 2 ]
expect "chip mismatch: says so" grep -q 'chip = gpiochip0' "$T/mis.err"
printf '[gpio]\nx_step = 17\nx_dir = 17\n' >"$T/dup.ini"
timeout -k 5 20 "$CS" stream --gpio "record:$T/x.rec" --machine "$T/dup.ini" "$T/job.nc" >/dev/null 2>"$T/dup.err"; rc=$?
expect "duplicate line: exit 1" [ $rc -eq 1 ]
expect "duplicate line: file:line" grep -q "^$T/dup.ini:3: \[gpio\] x_dir: line 17 is already x_step" "$T/dup.err"
printf '[gpio]\nx_step = 17\nx_dir = 27\npulse_us = 40\n' >"$T/pulse.ini"
timeout -k 5 20 "$CS" stream --gpio "record:$T/x.rec" --machine "$T/pulse.ini" "$T/job.nc" >/dev/null 2>"$T/pulse.err"; rc=$?
expect "long pulse: exit 1" [ $rc -eq 1 ]
expect "long pulse: explained" grep -q 'pulse_us = 40.000 us does not fit half the shortest step period of axis x' "$T/pulse.err"
timeout -k 5 20 "$CS" stream --gpio "record:$T/x.rec" --mode curves "$T/job.nc" >/dev/null 2>&1; rc=$?
expect "curves mode: exit 2" [ $rc -eq 2 ]
# 6. the example machine file of contrib/ reads, and its lines drive a job inside its travel.
printf 'G21 G90\nG1 X10 Y5 F6000\nG1 X2 Y8\n' >"$T/rpi.nc"
timeout -k 5 60 "$CS" stream --gpio "record:$T/rpi.rec" --machine contrib/gpio-rpi.ini --quiet \
    "$T/rpi.nc" >"$T/rpi.out" 2>"$T/rpi.err"; rc=$?
expect "contrib/gpio-rpi.ini: exit 0" [ $rc -eq 0 ]
expect "contrib/gpio-rpi.ini: pulse and set-up read" grep -q 'STEP pulse 2.000 us, DIR set-up 1.000 us' "$T/rpi.err"
expect "contrib/gpio-rpi.ini: steps made" grep -qE '^stream: [0-9]+ steps \(x 1440, y 640, z 0\)' "$T/rpi.out"

"$CS" stream --help >"$T/help.out"
expect "help: record mentioned" grep -q 'record:FILE' "$T/help.out"

echo "cli: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
