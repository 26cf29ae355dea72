#!/usr/bin/env bash
# The daemon on the GPIO link: `curvestep serve --gpio record:FILE --machine M.ini`, the job's
# step segments run by the daemon's own step thread (cs_gpio_run) on the recorder, the GPIO
# stand-in of tests/cli/test_gpio.sh (every edge kept with its time; this machine has no chip).
# A job is submitted, paused mid-job (the step thread decelerates along the path and waits at
# rest: the status says "(held)" once it is there), resumed and run to the end: every segment
# executed, the recorded steps on each axis those of the plan, no STEP edge before its planned
# time, the lines safe at the end. A second job, planned from where the first left the machine
# (the position the GPIO link reports), brings it back to the origin: its steps are the first's
# negated. A third is cancelled while it runs. Curves mode is refused at submit. A servo pen job
# runs the pen's pulse train beside the step thread. A bad [gpio] section stops serve at its
# start. Every process
# is bounded by `timeout` and killed on exit. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
. "$(dirname "${BASH_SOURCE[0]}")/lib/daemon.sh"
need_bin "$CS"

cp tests/data/gpio/wired3.ini "$T/m.ini"
# job 1: about 7 s of motion at 50 mm/s, long enough for the pause to land inside it
printf 'G21 G90\nG1 X300 Y100 F3000\n' >"$T/out.nc"
printf 'G21 G90\nG1 X10 Y10 F6000\nG1 X0 Y0\n' >"$T/back.nc"
"$CS" plan --machine "$T/m.ini" -o "$T/out.seg" "$T/out.nc" 2>/dev/null
N=$(grep -vc '^#' "$T/out.seg")
expect "plan: the job has segments" [ "${N:-0}" -gt 100 ]
# the plan's steps on x and y (columns 2 and 3 of a segment line)
want=$(grep -v '^#' "$T/out.seg" | awk '{x += $2; y += $3} END {print x " " y}')

# rec_steps FILE: net steps on x and y from a record (DIR level 1 = forward; y's DIR inverted),
# then "late" when an edge comes before its planned time, "unsafe" when a STEP or ENABLE line is
# left high.
rec_steps() {
    awk -F, '/^[0-9-]/ { if ($1 + 0 < $2 + 0) late = 1; last[$3] = $4 }
        /^[0-9-]/ && $3 ~ /_dir$/ { split($3, w, "_"); dir[w[1]] = $4 }
        /^[0-9-]/ && $4 == 1 && $3 ~ /_step$/ { split($3, w, "_"); pos[w[1]] += (dir[w[1]] ? 1 : -1) * (w[1] == "y" ? -1 : 1) }
        END { printf "%d %d", pos["x"], pos["y"]; if (late) printf " late"
              if (last["enable"] || last["x_step"] || last["y_step"]) printf " unsafe"; print "" }' "$1"
}

S=$T/sock/curvestep.sock
mkdir "$T/sock"
REC=$T/d.rec
dmn_start --gpio "record:$REC" --machine "$T/m.ini"
C status >"$T/st0" 2>&1
expect "status names the link" grep -q "^OK device record:$REC, queue running$" "$T/st0"

# 1. submit, pause mid-job (held at rest), resume, to the end.
C submit "$T/out.nc" >"$T/sub1" 2>&1
expect "job 1 queued" grep -q "^OK job 1 queued: .*out.nc: $N segments$" "$T/sub1"
expect "job 1: a quarter ran" wait_until 60 dmn_quarter
C pause >"$T/p"
expect "pause: said" grep -q "^OK paused (device held)" "$T/p"
expect "pause: the step thread held at rest" wait_until 60 dmn_still
a=$(dmn_progress)
expect "pause: mid-job ($a of $N)" [ -n "$a" ] && [ "$a" -gt 0 ] && [ "$a" -lt "$N" ]
C resume >/dev/null
expect "job 1 ended" wait_until 90 dmn_finished
C status >"$T/st1" 2>&1
expect "job 1: every segment executed" \
    grep -q "^job 1 done: .*out.nc: $N/$N segments executed (job executed)$" "$T/st1"
got=$(rec_steps "$REC")
expect "job 1: the plan's steps on the lines ($got = $want)" [ "$got" = "$want" ]

# 2. back to the origin: planned from where job 1 left the machine.
C submit "$T/back.nc" >"$T/sub2" 2>&1
expect "job 2 queued" grep -q "^OK job 2 queued: " "$T/sub2"
job2_done() { C status 2>/dev/null | grep -qE "^job 2 (done|failed|cancelled)"; }
expect "job 2 ended" wait_until 90 job2_done
C status >"$T/st2" 2>&1
expect "job 2 done" grep -q "^job 2 done: .*(job executed)$" "$T/st2"
back=$(rec_steps "$REC")
neg=$(echo "$want" | awk '{print -$1, -$2}')
expect "job 2: from job 1's end back to the origin ($back = $neg)" [ "$back" = "$neg" ]

# 3. cancel a running job: held, then ended at a segment end, the lines safe.
C submit "$T/out.nc" >/dev/null 2>&1
job3_moving() { C status 2>/dev/null | grep -qE "^job 3 running: .*: [1-9][0-9]*/"; }
expect "job 3 moving" wait_until 60 job3_moving
C cancel 3 >"$T/c3" 2>&1
expect "cancel: said" grep -q "^OK job 3 cancelling" "$T/c3"
job3_over() { C status 2>/dev/null | grep -qE "^job 3 (done|failed|cancelled)"; }
expect "job 3 ended" wait_until 60 job3_over
C status >"$T/st3" 2>&1
expect "job 3 cancelled, held at a segment end" \
    grep -qE "^job 3 cancelled: .*: [0-9]+/$N segments executed \(interrupted: held, then stopped at the end of a segment" "$T/st3"
r3=$(rec_steps "$REC")
expect "job 3: no edge early, the lines left safe ($r3)" [ -z "$(echo "$r3" | grep -E 'late|unsafe')" ]

# 4. curves mode has no place on GPIO: refused at submit.
C submit --mode curves "$T/out.nc" >/dev/null 2>"$T/cur.err"
expect "curves: refused (exit 1)" [ $? -eq 1 ]
expect "curves: why" grep -q "mode=curves: the GPIO link runs the step segments" "$T/cur.err"

kill -TERM "$DPID"
wait "$DPID"
expect "serve: exit 0" [ $? -eq 0 ]
expect "serve: log names the link" grep -q "^serve: serving record:$REC on " "$T/serve.err"

# 5. a servo pen job through the daemon: the pen's pulse train beside the step thread, its widths
# the plan's pen events in turn (taken back out of the job's PEN messages)
{
    printf '[pen]\nmode = servo\nup_us = 1900\ndown_us = 1100\nsettle_ms = 100\n'
    grep -v '^#' tests/data/gpio/wired3.ini | grep -v '^\[y\]\|^invert_dir'
    printf 'pen = 18\n'
} >"$T/pen.ini"
printf '<svg xmlns="http://www.w3.org/2000/svg" width="40mm" height="40mm" viewBox="0 0 40 40">\n<path d="M5 5 L20 5" fill="none" stroke="black"/>\n<path d="M25 30 L35 35" fill="none" stroke="black"/>\n</svg>\n' >"$T/pen.svg"
"$CS" plan --machine "$T/pen.ini" -o "$T/pen.seg" "$T/pen.svg" 2>/dev/null
pw=$(awk '/^pen / { if ($2 != last) printf " %d", $2; last = $2 }' "$T/pen.seg")
S=$T/sock/pen.sock
PREC=$T/pen.rec
dmn_start --gpio "record:$PREC" --machine "$T/pen.ini"
C submit "$T/pen.svg" >"$T/psub" 2>&1
expect "pen job queued" grep -q "^OK job 1 queued: " "$T/psub"
expect "pen job ended" wait_until 60 dmn_finished
C status >"$T/pst" 2>&1
expect "pen job done" grep -q "^job 1 done: .*(job executed)$" "$T/pst"
got=$(awk -F, '$3 == "pen" && $4 == 1 { r = $2 } $3 == "pen" && $4 == 0 && r != "" { w = ($2 - r) / 1000; if (w != last) s = s " " w; last = w } END { print s }' "$PREC")
expect "pen job: widths in turn =$pw (got $got)" [ -n "$pw" ] && [ " $got" = "$pw" ]
kill -TERM "$DPID"
wait "$DPID"
expect "pen daemon: exit 0" [ $? -eq 0 ]

# a bad [gpio] section stops serve at its start, with file:line (exit 1); a chip the file does
# not name is a usage error (exit 2)
printf '[gpio]\nx_step = 17\nx_dir = 17\n' >"$T/dup.ini"
timeout -k 5 30 "$CS" serve --gpio "record:$T/x.rec" --machine "$T/dup.ini" --socket "$T/sock/b.sock" \
    >/dev/null 2>"$T/dup.err"
expect "bad [gpio]: exit 1" [ $? -eq 1 ]
expect "bad [gpio]: file:line" grep -q "^$T/dup.ini:3: \[gpio\] x_dir: line 17 is already x_step" "$T/dup.err"
timeout -k 5 30 "$CS" serve --gpio gpiochip1 --machine "$T/m.ini" --socket "$T/sock/b.sock" \
    >/dev/null 2>"$T/mis.err"
expect "chip mismatch: exit 2" [ $? -eq 2 ]
expect "chip mismatch: said" grep -q "chip = gpiochip0" "$T/mis.err"

# usage: --gpio and another link
"$CS" serve --gpio gpiochip0 --port /dev/null >/dev/null 2>"$T/two.err"
expect "two links: exit 2" [ $? -eq 2 ]
expect "two links: said" grep -q "give one link" "$T/two.err"
finish
