#!/usr/bin/env bash
# Command-line tests of the shared input options (host/cs_jobopts.c) on every command that reads
# a job -- flatten, plan, stream, submit, curvestep-sim --reference: each accepts them, rejects a
# bad value with exit 2 and lists them in its --help; the layout (host/cs_layout.c) checked
# against bounding boxes worked out by hand; a drawing twice the bed fitted within the soft
# limits; merge and sort (host/cs_order.c): the drawn chords the same unordered set, direction
# normalised, before and after; pen-up travel reduced; the same output on every run.
# Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
need_bin "$CS" "$SIM"

# Bounding box of flatten's output: "xmin ymin xmax ymax" to 3 decimals.
box() {
    awk 'NF == 2 { if (!n++) { a = c = $1; b = d = $2 }
        if ($1 < a) a = $1; if ($1 > c) c = $1; if ($2 < b) b = $2; if ($2 > d) d = $2 }
        END { printf "%.3f %.3f %.3f %.3f\n", a, b, c, d }' "$1"
}

# The chords of flatten's output, each "x0 y0 x1 y1" with the smaller end first, sorted.
chords() {
    awk 'NF != 2 { have = 0; next }
        { if (have) { if ($1 < px || ($1 == px && $2 < py)) print $1, $2, px, py;
                      else print px, py, $1, $2 }
          px = $1; py = $2; have = 1 }' "$1" | sort
}

printf 'M 0 0 L 400 200\n' >"$T/big.d"
printf 'M 10 5 L 30 15\n' >"$T/small.d"

# --- 1. every command accepts the options and rejects bad values with exit 2 ------------------
"$CS" plan "$T/small.d" >"$T/seg.txt" 2>/dev/null
bad_values=("--dialect fanuc" "--units furlong" "--scale -1" "--scale 0" "--rotate 45"
    "--page B9" "--translate 1" "--margin -1" "--fit --scale 2")
for cmd in flatten plan stream submit sim; do
    case $cmd in
    flatten | plan) pre=("$CS" "$cmd") ;;
    stream) pre=("$CS" stream --port "$T/no-such-tty") ;;
    submit) pre=("$CS" submit --socket "$T/no-daemon.sock") ;;
    sim) pre=("$SIM" --replay "$T/seg.txt" --reference) ;;
    esac
    for b in "${bad_values[@]}"; do
        # shellcheck disable=SC2086
        "${pre[@]}" $b "$T/small.d" >/dev/null 2>"$T/err"
        rc=$?
        expect "$cmd $b: exit 2 (got $rc)" [ $rc -eq 2 ]
    done
    "${pre[@]}" --lenient --dialect grbl --units mm --rotate 90 --flip-y --translate 1,2 \
        --merge --sort "$T/small.d" >/dev/null 2>"$T/err"
    rc=$?
    case $cmd in
    stream | submit) want=4 ;; # parsed and (stream) planned; no device / no daemon answers
    *) want=0 ;;
    esac
    if [ "$cmd" = sim ]; then # the reference laid out differs from what was planned: a check
        "$SIM" --replay "$T/seg.txt" --lenient --reference "$T/small.d" >/dev/null 2>"$T/err"
        rc=$?
    fi
    expect "$cmd accepts the shared options (exit $rc, want $want)" [ $rc -eq $want ]
    case $cmd in
    sim) "$SIM" --help >"$T/help" ;;
    *) "$CS" "$cmd" --help >"$T/help" ;;
    esac
    for o in --lenient --dialect --units --scale --fit --page --margin --translate --rotate \
        --flip-y --merge --sort; do
        expect "$cmd --help lists $o" grep -q -- "^  $o" "$T/help"
    done
done
# stream plans before it opens the port: --lenient reaches the reader (an unsupported word)
printf 'G21\nG1 X1 Y1 F600\nG64 Q9\nG1 X2\n' >"$T/lenient.nc"
"$CS" stream --port "$T/no-such-tty" "$T/lenient.nc" >/dev/null 2>"$T/err"
rc_strict=$?
"$CS" stream --port "$T/no-such-tty" --lenient "$T/lenient.nc" >/dev/null 2>"$T/err"
rc_lenient=$?
expect "stream --lenient reaches the G-code reader ($rc_strict -> $rc_lenient)" \
    [ $rc_lenient -eq 4 ]

# --- 2. layout: bounding boxes worked out by hand -----------------------------------------
lay() { # NAME "xmin ymin xmax ymax" ARGS...
    local name=$1 want=$2
    shift 2
    if run "$name" 0 flatten "$@"; then
        got=$(box "$T/out")
        expect "$name: box $got, want $want" [ "$got" = "$want" ]
    fi
}
# 400 x 200 onto a 200 x 100 page: factor 1/2, the whole page
lay "fit page" "0.000 0.000 200.000 100.000" --page 200x100mm "$T/big.d"
# margin 10: 180 x 80 left, factor min(180/400, 80/200) = 0.4: 160 x 80 centred
lay "fit page margin" "20.000 10.000 180.000 90.000" --page 200x100mm --margin 10 "$T/big.d"
# the built-in machine's travel, -1000..1000 both ways: factor 5 (x), 400 x 200 -> 2000 x 1000
lay "fit travel" "-1000.000 -500.000 1000.000 500.000" --fit "$T/big.d"
# A4 portrait (210 x 297), margin 15: factor 180 / 400 = 0.45, 180 x 90 about (105, 148.5)
lay "fit A4" "15.000 103.500 195.000 193.500" --page A4 --margin 15 "$T/big.d"
# rotate 90 about the lower-left corner (10, 5): 20 x 10 becomes 10 x 20
lay "rotate 90" "10.000 5.000 20.000 25.000" --rotate 90 "$T/small.d"
lay "rotate 270" "10.000 5.000 20.000 25.000" --rotate 270 "$T/small.d"
# scale 2 about the origin, then translate (1, -2)
lay "scale translate" "21.000 8.000 61.000 28.000" --scale 2 --translate 1,-2 "$T/small.d"
# flip-y keeps the box; the line's ends swap heights
if run "flip-y" 0 flatten --flip-y "$T/small.d"; then
    expect_out "flip-y" '10.000000 15.000000\n30.000000 5.000000\n'
fi
# an SVG page 100 mm high: y' = 100 - y, as a browser shows it
cat >"$T/page.svg" <<'EOF'
<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" viewBox="0 0 100 100">
  <path d="M 10 20 L 30 25" stroke="black"/>
</svg>
EOF
if run "svg page turn" 0 flatten "$T/page.svg"; then
    expect_out "svg page turn" '10.000000 80.000000\n30.000000 75.000000\n'
fi

# --- 3. a drawing twice the bed: refused by the soft limits, planned with --fit --------------
cat >"$T/a4.ini" <<'EOF'
[x]
travel_min = 0
travel_max = 210
[y]
travel_min = 0
travel_max = 297
EOF
printf 'M 0 0 L 420 0 L 420 594 L 0 594 Z\n' >"$T/twice.d"
run "twice the bed: soft limits" 1 plan --machine "$T/a4.ini" "$T/twice.d" &&
    expect_err "twice the bed: soft limit message" 'leaves the travel'
run "twice the bed --fit" 0 plan --machine "$T/a4.ini" --fit -o "$T/fit.seg" "$T/twice.d"
"$SIM" --replay "$T/fit.seg" --machine "$T/a4.ini" --reference "$T/twice.d" --fit --check \
    >"$T/sim.txt" 2>&1
expect "twice the bed --fit: simulator check passes with the same options" \
    grep -q '^check: ok$' "$T/sim.txt"

# --- 4. merge and sort ------------------------------------------------------------------------
# 400 lines in random order over 300 x 200 mm (a fixed LCG), a third of them continuing the
# last one, some drawn backwards.
awk 'BEGIN { s = 12345; printf "<svg xmlns=\"http://www.w3.org/2000/svg\">\n"
    for (i = 0; i < 400; i++) {
        s = (s * 1103515245 + 12345) % 2147483648; x = int(s % 3000) / 10
        s = (s * 1103515245 + 12345) % 2147483648; y = int(s % 2000) / 10
        s = (s * 1103515245 + 12345) % 2147483648; chain = i > 0 && s % 3 == 0
        if (chain) { x = lx; y = ly }
        s = (s * 1103515245 + 12345) % 2147483648; nx = x + (s % 100) / 10 - 5
        s = (s * 1103515245 + 12345) % 2147483648; ny = y + (s % 100) / 10 - 5
        if (!chain && s % 2) printf "<path d=\"M %g %g L %g %g\" stroke=\"black\"/>\n", nx, ny, x, y
        else printf "<path d=\"M %g %g L %g %g\" stroke=\"black\"/>\n", x, y, nx, ny
        lx = nx; ly = ny }
    print "</svg>" }' >"$T/lines.svg"
run "lines as drawn" 0 flatten "$T/lines.svg" && cp "$T/out" "$T/plain.txt"
run "lines merged and sorted" 0 flatten --merge --sort "$T/lines.svg" && cp "$T/out" "$T/ms.txt"
cp "$T/err" "$T/ms.err"
chords "$T/plain.txt" >"$T/plain.chords"
chords "$T/ms.txt" >"$T/ms.chords"
expect "merge/sort: the same $(wc -l <"$T/plain.chords") chords" cmp -s "$T/plain.chords" "$T/ms.chords"
expect "merge/sort: one report line" [ "$(grep -c 'pen lifts' "$T/ms.err")" -eq 1 ]
read -r l0 l1 t0 t1 < <(sed -n 's/^flatten: \([0-9]*\) pen lifts -> \([0-9]*\), pen-up travel \([0-9.]*\) mm -> \([0-9.]*\) mm.*/\1 \2 \3 \4/p' "$T/ms.err")
expect "merge: fewer pen lifts (${l0:-?} -> ${l1:-?})" [ "${l1:-999}" -lt "${l0:-0}" ]
expect "sort: less travel (${t0:-?} -> ${t1:-?} mm)" awk "BEGIN { exit !(${t1:-1} < 0.5 * ${t0:-0}) }"
expect "merge/sort: fewer polylines printed" \
    [ "$(grep -c '^$' "$T/ms.txt")" -lt "$(grep -c '^$' "$T/plain.txt")" ]
"$CS" flatten --merge --sort "$T/lines.svg" >"$T/ms2.txt" 2>/dev/null
expect "merge/sort: the same output on every run" cmp -s "$T/ms.txt" "$T/ms2.txt"
# Plotters (a [pen] mode) merge and sort by default; --no-merge --no-sort keeps the file order.
cat >"$T/pen.ini" <<'EOF'
[pen]
mode = z
up_z = 5
down_z = 0
EOF
run "plotter default: merge and sort" 0 plan --machine "$T/pen.ini" -o "$T/pen.seg" "$T/lines.svg" &&
    expect_err "plotter default reports" '^plan: [0-9]+ pen lifts -> [0-9]+, .*\(merge, sort\)'
run "plotter --no-merge --no-sort" 0 plan --machine "$T/pen.ini" --no-merge --no-sort \
    -o "$T/pen2.seg" "$T/lines.svg" &&
    expect "no report without merge or sort" bash -c "! grep -q 'pen lifts' '$T/err'"
run "no pen: no merge by default" 0 plan -o "$T/nopen.seg" "$T/lines.svg" &&
    expect "no report by default without [pen]" bash -c "! grep -q 'pen lifts' '$T/err'"
"$SIM" --replay "$T/pen.seg" --machine "$T/pen.ini" --reference "$T/lines.svg" --check \
    >"$T/sim.txt" 2>&1
expect "plotter job merged and sorted: the simulator's final position matches" \
    grep -q 'rounded to steps: exact' "$T/sim.txt"

finish
