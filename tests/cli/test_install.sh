#!/usr/bin/env bash
# make install / make uninstall (mk/install.mk) into a DESTDIR: every piece lands under PREFIX,
# the unit names the installed program, the installed program runs (--version, a small
# flatten compared with the built one's), and uninstall leaves no file behind.
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
need_bin "$CS" "$SIM"
# From make test: the parent make's flags must not reach this make (VARIANT=asan, jobserver).
unset MAKEFLAGS MFLAGS MAKELEVEL MAKEOVERRIDES VARIANT
D=$T/dest
P=/opt/cs-test
# BUILD: where the plain programs are (make install installs those; an ASan run's CS_BUILD is
# build/asan, beside them).
bdir=$(dirname "$CS")
[ "$(basename "$bdir")" = asan ] && bdir=$(dirname "$bdir")
mk() { make --no-print-directory CS_DEPS_DONE=1 BUILD="$bdir" "$@" >"$T/make.log" 2>&1; }

mk install DESTDIR="$D" PREFIX=$P
rc=$?
[ $rc -eq 0 ] && ok || { ko "make install: exit $rc"; tail -5 "$T/make.log"; }
for f in bin/curvestep bin/curvestep-sim share/man/man1/curvestep.1 share/man/man1/curvestep-sim.1 \
    share/man/man5/curvestep-machine.5 lib/systemd/system/curvestep.service \
    share/bash-completion/completions/curvestep share/doc/curvestep/README.md \
    share/doc/curvestep/streaming.md; do
    expect "installed $P/$f" test -e "$D$P/$f"
done
for f in contrib/*.ini; do
    expect "sample machine file $f in share/curvestep" cmp -s "$f" "$D$P/share/curvestep/$(basename "$f")"
done
expect "the unit runs the installed program" grep -q "^ExecStart=$P/bin/curvestep serve " "$D$P/lib/systemd/system/curvestep.service"
expect "no template placeholder left in the unit" bash -c "! grep -q @ '$D$P/lib/systemd/system/curvestep.service'"
expect "installed curvestep --version" bash -c "'$D$P/bin/curvestep' --version | grep -qE '^curvestep [0-9]+\.[0-9]+'"
expect "installed curvestep-sim --help" bash -c "'$D$P/bin/curvestep-sim' --help >/dev/null"
printf 'M 0 0 C 10 0 10 10 0 10\n' >"$T/c.txt"
"$D$P/bin/curvestep" flatten --tol 0.05 "$T/c.txt" >"$T/inst.out" 2>"$T/err"
"$CS" flatten --tol 0.05 "$T/c.txt" >"$T/built.out" 2>&1
expect "installed flatten prints chords" test "$(grep -c . "$T/inst.out")" -ge 3
expect "installed flatten = built flatten" cmp -s "$T/inst.out" "$T/built.out"
# The curve starts at (0,0) and ends at (0,10): the first and last vertex are exact.
expect "first vertex 0 0" test "$(head -n1 "$T/inst.out")" = "0.000000 0.000000"
expect "last vertex 0 10" test "$(tail -n1 "$T/inst.out")" = "0.000000 10.000000"
expect "installed man page renders" bash -c "MANWIDTH=80 man -l '$D$P/share/man/man1/curvestep.1' 2>/dev/null | grep -q flatten"

mk uninstall DESTDIR="$D" PREFIX=$P
rc=$?
[ $rc -eq 0 ] && ok || { ko "make uninstall: exit $rc"; tail -5 "$T/make.log"; }
left=$(find "$D" ! -type d)
expect "uninstall leaves no file (left: $left)" test -z "$left"
left=$(find "$D" -name '*curvestep*')
expect "uninstall leaves no curvestep directory (left: $left)" test -z "$left"
finish
