#!/usr/bin/env bash
# The GPIO link drives the pen servo (host/cs_gpio_pwm.c: software PWM on a line of its own,
# [gpio] pen). A two-stroke drawing on a servo-pen machine is streamed with `--gpio record:FILE`
# (the recorder stands for the chip, tests/cli/test_gpio.sh) and the pen line's recorded edges
# are read back with awk: the planned rises exactly 20 ms apart (50 Hz), the planned widths in
# turn the plan's "pen US" lines (repeats merged), and the edges as they happened: a mean period
# of 20 ms within 5 % over the job (deadlines are absolute: lateness does not add up; single
# edges are as late as the host's scheduling makes them, docs/gpio.md). Prints "cli: N passed,
# M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
need_bin "$CS"
cat >"$T/m.ini" <<'INI'
[pen]
mode = servo
up_us = 1900
down_us = 1100
settle_ms = 100
[gpio]
chip = gpiochip0
x_step = 17
x_dir = 27
y_step = 22
y_dir = 23
z_step = 5
z_dir = 6
enable = 4
pen = 18
INI
cat >"$T/job.svg" <<'SVG'
<svg xmlns="http://www.w3.org/2000/svg" width="40mm" height="40mm" viewBox="0 0 40 40">
<path d="M5 5 L20 5" fill="none" stroke="black"/>
<path d="M25 30 L35 35" fill="none" stroke="black"/>
</svg>
SVG
run "plan" 0 plan --machine "$T/m.ini" "$T/job.svg" -o "$T/job.seg"
want=$(awk '/^pen / { if ($2 != last) printf " %d", $2; last = $2 }' "$T/job.seg")
timeout -k 5 60 "$CS" stream --gpio "record:$T/job.rec" --machine "$T/m.ini" "$T/job.svg" \
    >"$T/s.out" 2>"$T/s.err"
expect "stream: exit 0" [ $? -eq 0 ]
expect "stream: pen pulses reported" grep -qE '^stream: pen servo: [1-9][0-9]* pulses at 50 Hz' "$T/s.out"
# pen rows: t_ns,planned_ns,pen,level
awk -F, '$3 == "pen"' "$T/job.rec" >"$T/pen.csv"
read -r n pbad widths < <(awk -F, '
    $4 == 1 { if (r != "" && $2 - r != 20000000) bad++; r = $2; n++ }
    $4 == 0 && r != "" { w = ($2 - r) / 1000; if (w != last) s = s " " w; last = w }
    END { print n + 0, bad + 0, s }' "$T/pen.csv")
widths=" $widths"
expect "pen: $n pulses, each planned rise 20 ms after the last ($pbad not)" [ "$n" -gt 20 -a "$pbad" = 0 ]
expect "pen: planned widths in turn =$want (got$widths)" [ "$widths" = "$want" ]
mean=$(awk -F, '$4 == 1 { if (f == "") f = $1; l = $1; n++ } END { printf "%.0f", (l - f) / (n - 1) }' "$T/pen.csv")
expect "pen: mean period as it happened $mean ns (20 ms within 5 %)" \
    [ "$mean" -ge 19000000 -a "$mean" -le 21000000 ]
expect "pen: the line ends low" [ "$(tail -n1 "$T/pen.csv" | cut -d, -f4)" = 0 ]
finish
