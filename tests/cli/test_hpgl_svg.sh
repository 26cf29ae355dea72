#!/usr/bin/env bash
# CLI tests of the HP-GL reader and the SVG shapes/units through `curvestep flatten`: exact
# vertices in mm (HP-GL plotter units / 40, Y up; SVG shapes under a viewBox), one warning per
# skipped HP-GL instruction, the real file tests/data/hpgl/feature-exercise.plt, and malformed
# inputs of each kind giving "file:line:col: reason", exit 1 and nothing on stdout.
# Uses $CS_BUILD (the build directory); ends with "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"

# expect_error NAME FILE LINE COL: exit 1 (checked by run), "FILE:LINE:COL: " on stderr, and
# nothing at all on stdout.
expect_error() {
    expect_err "$1" "^$2:$3:$4: "
    if [ -s "$T/out" ]; then ko "$1: output on error"; else ok; fi
}

need_bin "$CS"

# --- HP-GL ---------------------------------------------------------------------------------
# 400 plotter units = 10 mm; Y up (nothing flipped); PU splits subpaths; PR relative.
printf 'IN;SP1;PU0,0;PD400,0,400,400;PU800,0;PR;PD-40,-80;' >"$T/a.plt"
run "hpgl lines" 0 flatten "$T/a.plt" &&
    expect_out "hpgl lines" '0.000000 0.000000\n10.000000 0.000000\n10.000000 10.000000\n\n20.000000 0.000000\n19.000000 -2.000000\n'
# Unknown and unsupported instructions: one warning each, with position.
printf 'IN;ZZ1;ZZ2;LT2;PD40,0;LT;' >"$T/b.plt"
run "hpgl skipped" 0 flatten "$T/b.plt" && expect_err "hpgl skipped" "b.plt:1:4: warning: ZZ: " &&
    expect_err "hpgl skipped" "b.plt:1:12: warning: LT: line types ignored" &&
    { [ "$(grep -c 'ZZ:' "$T/err")" = 1 ] && ok || ko "hpgl skipped: ZZ warned more than once"; }
# A circle: traced within the tolerance (--stats measures against the exact arcs).
printf 'IN;PU400,400;CI200;' >"$T/c.plt"
run "hpgl circle" 0 flatten --stats --tol 0.01 "$T/c.plt" &&
    expect_err "hpgl circle" '4 elements in 1 subpath' &&
    expect_err "hpgl circle" 'max deviation 0\.0(0[0-9]*|10*) mm'
# The real file reads and flattens: 29 elements of geometry and its LB labels in the default
# stroke font (1728 lines in 353 strokes). IW clips (docs/inputs.md): the circle leaves its window
# twice (3 runs instead of 1: +2 subpaths), the polyline re-enters once (+1): 13 + 3 = 16
# subpaths of geometry, 16 + 353 = 369 in all, and no IW warning.
run "hpgl feature-exercise" 0 flatten --stats tests/data/hpgl/feature-exercise.plt &&
    expect_err "hpgl feature-exercise" '1757 elements in 369 subpaths' &&
    expect "hpgl feature-exercise: IW carried out, not warned" bash -c "! grep -q 'IW:' '$T/err'"
# Malformed: file:line:col, exit 1, nothing on stdout.
printf 'IN;PD40,40;\nPD10;' >"$T/odd.plt"
run "hpgl odd pair" 1 flatten "$T/odd.plt" && expect_error "hpgl odd pair" "$T/odd.plt" 2 3
printf 'IN;PD40,40;PD10,10@;' >"$T/junk.plt"
run "hpgl junk" 1 flatten "$T/junk.plt" && expect_error "hpgl junk" "$T/junk.plt" 1 19
printf 'IN;PD40,40;\n\nPD200000,0;' >"$T/range.plt"
run "hpgl range" 1 flatten "$T/range.plt" && expect_error "hpgl range" "$T/range.plt" 3 3
printf 'IN;PD;BZ1,2,3,4;' >"$T/bz.plt"
run "hpgl bz group" 1 flatten "$T/bz.plt" && expect_error "hpgl bz group" "$T/bz.plt" 1 9

# --- SVG shapes and units ----------------------------------------------------------------------
# viewBox 200 x 100 on 100 mm x 50 mm: a rect and a polyline at half size.
cat >"$T/s.svg" <<'EOF'
<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="50mm" viewBox="0 0 200 100">
  <rect x="20" y="10" width="40" height="20" fill="none" stroke="black"/>
  <polyline points="0,0 200,100" stroke="black"/>
</svg>
EOF
# The page is turned y-up (y' = 50 - y, docs/plotting.md "Layout"): it looks as a browser shows it.
run "svg shapes" 0 flatten "$T/s.svg" &&
    expect_out "svg shapes" '10.000000 45.000000\n30.000000 45.000000\n30.000000 35.000000\n10.000000 35.000000\n10.000000 45.000000\n\n0.000000 50.000000\n100.000000 0.000000\n'
# --flip-y mirrors that about the drawing's box, which is the whole page here: SVG's own y-down
# coordinates again.
run "svg shapes flip-y" 0 flatten --flip-y "$T/s.svg" &&
    expect_out "svg shapes flip-y" '10.000000 5.000000\n30.000000 5.000000\n30.000000 15.000000\n10.000000 15.000000\n10.000000 5.000000\n\n0.000000 0.000000\n100.000000 50.000000\n'
# Filled shapes without stroke: drawn as outlines, said once.
printf '<svg><rect width="5" height="5" fill="red"/><circle r="3"/></svg>' >"$T/f.svg"
run "svg fills" 0 flatten "$T/f.svg" &&
    { [ "$(grep -c 'fills are not drawn' "$T/err")" = 1 ] && ok || ko "svg fills: not said once"; }
# Malformed shapes and units: at the character in the attribute.
printf '<svg>\n  <rect width="-3" height="1"/>\n</svg>\n' >"$T/neg.svg"
run "svg negative" 1 flatten "$T/neg.svg" && expect_error "svg negative" "$T/neg.svg" 2 16
printf '<svg width="10qq" height="1">\n</svg>\n' >"$T/unit.svg"
run "svg unit" 1 flatten "$T/unit.svg" && expect_error "svg unit" "$T/unit.svg" 1 15
printf '<svg>\n<polygon points="1 2 3 4 5"/></svg>\n' >"$T/poly.svg"
# drawn up to the error (SVG 2, 10.6 as 9.5.4): the lines through (1,2) (3,4), a warning at the end
run "svg odd points" 0 flatten "$T/poly.svg" && expect_err "svg odd points" "^$T/poly.svg:2:27: warning: "
printf '<svg viewBox="0 0 1">\n</svg>\n' >"$T/vb.svg"
run "svg viewBox" 1 flatten "$T/vb.svg" && expect_error "svg viewBox" "$T/vb.svg" 1 20

finish
