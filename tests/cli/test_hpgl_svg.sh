#!/usr/bin/env bash
# CLI tests of the HP-GL reader and the SVG shapes/units through `curvestep flatten`: exact
# vertices in mm (HP-GL plotter units / 40, Y up; SVG shapes under a viewBox), one warning per
# skipped HP-GL instruction, the real file tests/data/hpgl/feature-exercise.plt, and malformed
# inputs of each kind giving "file:line:col: reason", exit 1 and nothing on stdout.
# Uses $CS_BUILD (the build directory); ends with "cli: N passed, M failed".
set -u
BIN=${CS_BUILD:-build}/curvestep
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
pass=0
fail=0

ok() { pass=$((pass + 1)); }
ko() { fail=$((fail + 1)); echo "FAIL: $*"; }

# run NAME EXPECTED_RC ARGS...: runs the program, output in $TMP/out, $TMP/err, status in $rc.
run() {
    local name=$1 want=$2
    shift 2
    "$BIN" "$@" >"$TMP/out" 2>"$TMP/err"
    rc=$?
    if [ "$rc" -ne "$want" ]; then
        ko "$name: exit $rc, expected $want"
        sed 's/^/    /' "$TMP/err" | head -5
        return 1
    fi
    ok
    return 0
}

# expect_out NAME TEXT: stdout must be exactly TEXT (printf-interpreted).
expect_out() {
    local name=$1
    printf "$2" >"$TMP/want"
    if cmp -s "$TMP/out" "$TMP/want"; then ok; else
        ko "$name: output differs"
        diff "$TMP/want" "$TMP/out" | head -10 | sed 's/^/    /'
    fi
}

# expect_err NAME REGEX: stderr must match (grep -E).
expect_err() {
    if grep -qE "$2" "$TMP/err"; then ok; else
        ko "$1: stderr does not match /$2/"
        head -5 "$TMP/err" | sed 's/^/    /'
    fi
}

# expect_error NAME FILE LINE COL: exit 1 (checked by run), "FILE:LINE:COL: " on stderr, and
# nothing at all on stdout.
expect_error() {
    expect_err "$1" "^$2:$3:$4: "
    if [ -s "$TMP/out" ]; then ko "$1: output on error"; else ok; fi
}

if [ ! -x "$BIN" ]; then
    echo "no $BIN"
    echo "cli: 0 passed, 1 failed"
    exit 1
fi

# --- HP-GL ---------------------------------------------------------------------------------
# 400 plotter units = 10 mm; Y up (nothing flipped); PU splits subpaths; PR relative.
printf 'IN;SP1;PU0,0;PD400,0,400,400;PU800,0;PR;PD-40,-80;' >"$TMP/a.plt"
run "hpgl lines" 0 flatten "$TMP/a.plt" &&
    expect_out "hpgl lines" '0.000000 0.000000\n10.000000 0.000000\n10.000000 10.000000\n\n20.000000 0.000000\n19.000000 -2.000000\n'
# Unknown and unsupported instructions: one warning each, with position.
printf 'IN;ZZ1;ZZ2;LT2;PD40,0;LT;' >"$TMP/b.plt"
run "hpgl skipped" 0 flatten "$TMP/b.plt" && expect_err "hpgl skipped" "b.plt:1:4: warning: ZZ: " &&
    expect_err "hpgl skipped" "b.plt:1:12: warning: LT: line types ignored" &&
    { [ "$(grep -c 'ZZ:' "$TMP/err")" = 1 ] && ok || ko "hpgl skipped: ZZ warned more than once"; }
# A circle: traced within the tolerance (--stats measures against the exact arcs).
printf 'IN;PU400,400;CI200;' >"$TMP/c.plt"
run "hpgl circle" 0 flatten --stats --tol 0.01 "$TMP/c.plt" &&
    expect_err "hpgl circle" '4 elements in 1 subpath' &&
    expect_err "hpgl circle" 'max deviation 0\.0(0[0-9]*|10*) mm'
# The real file reads and flattens.
run "hpgl feature-exercise" 0 flatten --stats tests/data/hpgl/feature-exercise.plt &&
    expect_err "hpgl feature-exercise" '29 elements in 13 subpaths' &&
    expect_err "hpgl feature-exercise" 'IW: clipping window ignored'
# Malformed: file:line:col, exit 1, nothing on stdout.
printf 'IN;PD40,40;\nPD10;' >"$TMP/odd.plt"
run "hpgl odd pair" 1 flatten "$TMP/odd.plt" && expect_error "hpgl odd pair" "$TMP/odd.plt" 2 3
printf 'IN;PD40,40;PD10,10@;' >"$TMP/junk.plt"
run "hpgl junk" 1 flatten "$TMP/junk.plt" && expect_error "hpgl junk" "$TMP/junk.plt" 1 19
printf 'IN;PD40,40;\n\nPD200000,0;' >"$TMP/range.plt"
run "hpgl range" 1 flatten "$TMP/range.plt" && expect_error "hpgl range" "$TMP/range.plt" 3 3
printf 'IN;PD;BZ1,2,3,4;' >"$TMP/bz.plt"
run "hpgl bz group" 1 flatten "$TMP/bz.plt" && expect_error "hpgl bz group" "$TMP/bz.plt" 1 9

# --- SVG shapes and units ----------------------------------------------------------------------
# viewBox 200 x 100 on 100 mm x 50 mm: a rect and a polyline at half size.
cat >"$TMP/s.svg" <<'EOF'
<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="50mm" viewBox="0 0 200 100">
  <rect x="20" y="10" width="40" height="20" fill="none" stroke="black"/>
  <polyline points="0,0 200,100" stroke="black"/>
</svg>
EOF
run "svg shapes" 0 flatten "$TMP/s.svg" &&
    expect_out "svg shapes" '10.000000 5.000000\n30.000000 5.000000\n30.000000 15.000000\n10.000000 15.000000\n10.000000 5.000000\n\n0.000000 0.000000\n100.000000 50.000000\n'
# Filled shapes without stroke: drawn as outlines, said once.
printf '<svg><rect width="5" height="5" fill="red"/><circle r="3"/></svg>' >"$TMP/f.svg"
run "svg fills" 0 flatten "$TMP/f.svg" &&
    { [ "$(grep -c 'fills are not drawn' "$TMP/err")" = 1 ] && ok || ko "svg fills: not said once"; }
# Malformed shapes and units: at the character in the attribute.
printf '<svg>\n  <rect width="-3" height="1"/>\n</svg>\n' >"$TMP/neg.svg"
run "svg negative" 1 flatten "$TMP/neg.svg" && expect_error "svg negative" "$TMP/neg.svg" 2 16
printf '<svg width="10qq" height="1">\n</svg>\n' >"$TMP/unit.svg"
run "svg unit" 1 flatten "$TMP/unit.svg" && expect_error "svg unit" "$TMP/unit.svg" 1 15
printf '<svg>\n<polygon points="1 2 3 4 5"/></svg>\n' >"$TMP/poly.svg"
run "svg odd points" 1 flatten "$TMP/poly.svg" && expect_error "svg odd points" "$TMP/poly.svg" 2 27
printf '<svg viewBox="0 0 1">\n</svg>\n' >"$TMP/vb.svg"
run "svg viewBox" 1 flatten "$TMP/vb.svg" && expect_error "svg viewBox" "$TMP/vb.svg" 1 20

echo "cli: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
