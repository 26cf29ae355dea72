#!/usr/bin/env bash
# `curvestep submit --font FILE.jhf`: the daemon reads the job's text with the font given, as
# `plan --font` does. A drawing of text is submitted to a paused daemon (nothing runs) three ways:
# with the shipped font, with a copy of it (the same job: the same count of segments), and with a
# font whose 'A' is drawn as 'W' (more strokes: more segments, and the count `plan --font` of that
# font gives). A file that is not a font is refused with its located error, exit 1; a missing
# one before anything is sent. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"

FONT=share/fonts/futural.jhf
cp "$FONT" "$T/copy.jhf"
# glyph records are in ASCII order from the space (line 1): 'A' is line 34, 'W' line 56
awk 'NR == 56 { w = $0 } { l[NR] = $0 } END { for (i = 1; i <= NR; i++) print (i == 34 ? w : l[i]) }' \
    "$FONT" >"$T/aw.jhf"
expect "the A-as-W font differs" sh -c "! cmp -s $FONT $T/aw.jhf"
printf 'not a font\n' >"$T/bad.jhf"
cat >"$T/t.svg" <<'SVG'
<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="30mm" viewBox="0 0 100 30">
  <text x="5" y="20" font-size="12">AAAA</text>
</svg>
SVG
count() { sed -n 's/^OK job [0-9]* queued: .*: \([0-9]*\) segments$/\1/p' "$1"; }

timeout -k 5 120 "$SIM" --pty --instant >"$T/d.sim" 2>/dev/null &
pids+=($!)
wait_pty "$T/d.sim" 60
S=$T/sock
timeout -k 5 120 "$CS" serve --port "$PTY" --socket "$S" 2>"$T/serve.err" &
pids+=($!)
wait_until 60 [ -S "$S" ]
run "pause the queue" 0 pause --socket "$S"
run "submit, shipped font" 0 submit --socket "$S" "$T/t.svg"
n0=$(count "$T/out")
run "submit --font copy" 0 submit --socket "$S" --font "$T/copy.jhf" "$T/t.svg"
n1=$(count "$T/out")
run "submit --font A-as-W" 0 submit --socket "$S" --font "$T/aw.jhf" "$T/t.svg"
n2=$(count "$T/out")
"$CS" plan --font "$T/aw.jhf" "$T/t.svg" -o "$T/aw.seg" 2>"$T/plan.err"
np=$(grep -vc -e '^#' -e '^pen ' "$T/aw.seg")
expect "the copy gives the same job ($n0 = $n1 segments)" [ -n "$n0" -a "$n0" = "$n1" ]
expect "A drawn as W: more segments ($n2 > $n0)" [ -n "$n2" ] && [ "$n2" -gt "$n0" ]
expect "A drawn as W: as plan --font plans it ($n2 = $np)" [ "$n2" = "$np" ]
run "submit --font not-a-font: refused" 1 submit --socket "$S" --font "$T/bad.jhf" "$T/t.svg"
expect "refusal located in the font" grep -q "bad.jhf:1:1: not a Hershey font" "$T/err"
run "submit --font missing: refused" 1 submit --socket "$S" --font "$T/none.jhf" "$T/t.svg"
expect "missing font named" grep -q "none.jhf:0:0: cannot open the font" "$T/err"
finish
