#!/usr/bin/env bash
# CLI tests of the DXF reader (host/cs_dxf.c) through `curvestep flatten`: an independent producer
# (Debian's python3-ezdxf, tests/cli/lib/dxf_ezdxf.py) writes every entity form curvestep draws
# exactly (SOLID/TRACE/3DFACE as outlines) and flattens it with its own geometry; curvestep's chords and ezdxf's polylines must
# lie within 0.005 mm of each other both ways (ezdxf's own arcs are cubic approximations, within
# 2.7e-4 of the radius; its splines are the exact NURBS). Then real files (tests/data/dxf, from
# dxf-parser: an AutoCAD arc with extrusion (0,0,-1), ellipses with ratio > 1, a spline beyond
# the range; from ezdxf: an AutoCAD 2.x drawing), units, standard input, warnings once per kind,
# and located errors.
# Uses $CS_BUILD (the build directory); ends with "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"

need_bin "$CS"
LIBD="$(dirname "${BASH_SOURCE[0]}")/lib"
# Debian's interpreter: python3-ezdxf is installed for it (scripts/deps.sh), whatever else is
# first on PATH.
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3

expect_error() { # NAME FILE LINE COL: "FILE:LINE:COL: " on stderr, nothing on stdout
    expect_err "$1" "^$2:$3:$4: "
    if [ -s "$T/out" ]; then ko "$1: output on error"; else ok; fi
}

# --- every entity form against ezdxf ---------------------------------------------------------
mkdir -p "$T/ez"
if "$PY" "$LIBD/dxf_ezdxf.py" write "$T/ez" 2>"$T/ezerr"; then
    ok
    for f in "$T"/ez/*.dxf; do
        n=$(basename "$f" .dxf)
        run "ezdxf $n" 0 flatten --tol 0.0005 "$f" || continue
        if [ "$n" = solid ]; then
            expect_err "ezdxf $n: outline warned" 'warning: filled SOLID/TRACE/3DFACE'
        else
            expect "ezdxf $n: no warning" bash -c "! grep -q warning '$T/err'"
        fi
        if "$PY" "$LIBD/dxf_ezdxf.py" compare "${f%.dxf}.ref" "$T/out" 0.005 >"$T/cmp"; then ok; else
            ko "ezdxf $n: $(cat "$T/cmp")"
        fi
    done
else
    ko "ezdxf cannot write the cases: $(head -3 "$T/ezerr")"
fi

# --- real files ----------------------------------------------------------------------------------
# AutoCAD's ARC in a mirrored OCS: world = (-x_ocs, y_ocs); it runs clockwise in the world from
# angle 338.90 to 355.08 of its OCS. Expected ends worked out here with awk.
run "arc1" 0 flatten --tol 0.001 tests/data/dxf/arc1.dxf &&
    expect_err "arc1: unitless warned" 'arc1.dxf:1:1: warning: the drawing has no units' &&
    expect "arc1: ends" awk -v cx=650.0541823996996 -v cy=347.5909732684974 \
        -v r=0.7604262403327394 -v a0=338.8998819521181 -v a1=355.0752244008874 '
        function d2r(a) { return a * atan2(0, -1) / 180 }
        NF == 2 { if (!n++) { x0 = $1; y0 = $2 } x1 = $1; y1 = $2 }
        END {
            ex0 = -(cx + r * cos(d2r(a0))); ey0 = cy + r * sin(d2r(a0))
            ex1 = -(cx + r * cos(d2r(a1))); ey1 = cy + r * sin(d2r(a1))
            e = 1e-5
            exit !(n > 2 && (x0 - ex0)^2 < e*e && (y0 - ey0)^2 < e*e && \
                   (x1 - ex1)^2 < e*e && (y1 - ey1)^2 < e*e)
        }' "$T/out"
# ELLIPSE written with ratio > 1 and end parameter 6.283185: two closed ellipses; the second
# (centre (0,-5), major (0,5), ratio 4: minor = 4 (N x major) = (-20, 0)) spans x -20 .. 20.
run "ellipse.dxf" 0 flatten --stats tests/data/dxf/ellipse.dxf &&
    expect_err "ellipse.dxf" '8 elements in 2 subpaths' &&
    expect "ellipse.dxf: extent" awk 'BEGIN { RS = "" } NR == 2 {
            n = split($0, v, "[ \n]"); mn = 1e9; mx = -1e9
            for (i = 1; i < n; i += 2) { if (v[i] < mn) mn = v[i]; if (v[i] > mx) mx = v[i] }
            ok = mn > -20.001 && mn < -19.99 && mx < 20.001 && mx > 19.99 && \
                 v[1] == v[n - 1] && v[2] == v[n] }
        END { exit !ok }' "$T/out"
# AutoCAD 2.x (AC1003, from ezdxf's tests): tabs before values, 10 11 before 20 21 (ezdxf 0.18's
# own reader refuses it). 13 LINEs and 9 ARCs: seven of at most 90 degrees (1 piece each) and two
# of 180 (2 each): 13 + 7 + 4 = 24 elements, one subpath per entity; 3.625 in wide.
run "AC1003" 0 flatten --stats --units inch tests/data/dxf/AC1003_LINE_Example.dxf &&
    expect_err "AC1003" '24 elements in 22 subpaths' &&
    expect "AC1003: width" awk 'NF == 2 { if ($1 > mx) mx = $1 } END { exit !(mx > 92.07 && mx < 92.08) }' "$T/out"
# A spline reaching x = 4994: beyond the +/-4096 mm range, at its control point.
run "splines.dxf" 1 flatten tests/data/dxf/splines.dxf &&
    expect_error "splines.dxf" tests/data/dxf/splines.dxf 94 1

# --- units and standard input ---------------------------------------------------------------
# $INSUNITS 1 = inches: (2, 1) in = (50.8, 25.4) mm, each rounded to the LSB (2^-16 mm):
# 3329228.8 -> 3329229 / 65536 = 50.800003, 1664614.4 -> 1664614 / 65536 = 25.399994.
printf '0\nSECTION\n2\nHEADER\n9\n$INSUNITS\n70\n1\n0\nENDSEC\n0\nSECTION\n2\nENTITIES\n0\nLINE\n10\n0\n20\n0\n11\n2\n21\n1\n0\nENDSEC\n0\nEOF\n' >"$T/in.dxf"
run "inch" 0 flatten "$T/in.dxf" && expect_out "inch" '0.000000 0.000000\n50.800003 25.399994\n'
run "--units mm" 0 flatten --units mm "$T/in.dxf" &&
    expect_out "--units mm" '0.000000 0.000000\n2.000000 1.000000\n'
"$CS" flatten - <"$T/in.dxf" >"$T/out" 2>"$T/err"
expect "stdin: read as DXF" cmp -s "$T/out" <(printf '0.000000 0.000000\n50.800003 25.399994\n')
cp "$T/in.dxf" "$T/IN.DXF"
run "upper-case extension" 0 flatten "$T/IN.DXF"
sed 's/$/\r/' "$T/in.dxf" >"$T/crlf.dxf"
run "CRLF" 0 flatten "$T/crlf.dxf" && expect_out "CRLF" '0.000000 0.000000\n50.800003 25.399994\n'

# --- skipped kinds: one warning each ---------------------------------------------------------
printf '0\nSECTION\n2\nENTITIES\n0\nHATCH\n0\nHATCH\n0\nPOINT\n10\n1\n20\n1\n0\nLINE\n11\n1\n0\nENDSEC\n0\nEOF\n' >"$T/sk.dxf"
run "skipped" 0 flatten "$T/sk.dxf" && expect_err "skipped" 'sk.dxf:6:1: warning: HATCH: ' &&
    expect "skipped: HATCH warned once" test "$(grep -c 'HATCH' "$T/err")" = 1 &&
    expect_err "skipped" 'sk.dxf:10:1: warning: POINT: '
# A file cut short (no ENDSEC, no EOF): drawn as far as it goes, with a warning at its last
# group; a file whose sections all end but which lacks 0/EOF is whole (as the unit tests'
# snippets): no warning.
printf '0\nSECTION\n2\nENTITIES\n0\nLINE\n10\n1\n20\n2\n11\n3\n21\n4' >"$T/cut.dxf"
run "cut short" 0 flatten "$T/cut.dxf" && expect_out "cut short" '1.000000 2.000000\n3.000000 4.000000\n' &&
    expect_err "cut short" 'cut.dxf:14:1: warning: the file ends inside a section \(no 0/ENDSEC\)'
head -n -2 "$T/sk.dxf" >"$T/noeof.dxf"
run "no EOF but whole" 0 flatten "$T/noeof.dxf" &&
    expect "complete file: no cut-short warning" bash -c "! grep -q 'cut short' '$T/err'"

# --- errors: file:line:col, exit 1, nothing on stdout -------------------------------------
printf 'AutoCAD Binary DXF\r\n\032\000' >"$T/bin.dxf"
run "binary" 1 flatten "$T/bin.dxf" && expect_error "binary" "$T/bin.dxf" 1 1 &&
    expect_err "binary" 'binary DXF'
printf '0\nSECTION\n2\nENTITIES\nX\nLINE\n' >"$T/code.dxf"
run "bad code" 1 flatten "$T/code.dxf" && expect_error "bad code" "$T/code.dxf" 5 1
printf '0\nSECTION\n2\nENTITIES\n0\nLINE\n10\n  1,5\n' >"$T/num.dxf"
run "bad number" 1 flatten "$T/num.dxf" && expect_error "bad number" "$T/num.dxf" 8 3
printf '0\nSECTION\n2\nBLOCKS\n0\nBLOCK\n2\nA\n0\nINSERT\n2\nA\n0\nENDBLK\n0\nENDSEC\n0\nSECTION\n2\nENTITIES\n0\nINSERT\n2\nA\n0\nENDSEC\n' >"$T/rec.dxf"
run "recursion" 1 flatten "$T/rec.dxf" && expect_error "recursion" "$T/rec.dxf" 10 1 &&
    expect_err "recursion" "block 'A' inserts itself"
printf '0\nSECTION\n2\nENTITIES\n0\nINSERT\n2\nNOPE\n0\nENDSEC\n' >"$T/undef.dxf"
run "undefined block" 1 flatten "$T/undef.dxf" && expect_error "undefined block" "$T/undef.dxf" 8 1

finish
