#!/usr/bin/env bash
# Command-line tests of the default machine file: without --machine, plan and the simulator use
# $XDG_CONFIG_HOME/curvestep/machine.ini, else $HOME/.config/curvestep/machine.ini, else (when
# /etc/curvestep/machine.ini does not exist here) the built-in machine, and say which on stderr;
# --machine wins over all. The contrib/machines files all load and plan the example drawing.
# Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
need_bin "$CS" "$SIM"

JOB=contrib/examples/plotter.svg
mkdir -p "$T/xdg/curvestep" "$T/home/.config/curvestep"
# Two machines told apart by their travel: x ends at 100 mm (the job does not fit) or 400 mm.
printf '[x]\ntravel_min = 0\ntravel_max = 100\n' >"$T/xdg/curvestep/machine.ini"
printf '[x]\ntravel_min = 0\ntravel_max = 400\n[y]\ntravel_min = 0\ntravel_max = 400\n' \
    >"$T/home/.config/curvestep/machine.ini"

XDG_CONFIG_HOME=$T/xdg HOME=$T/home "$CS" plan "$JOB" >/dev/null 2>"$T/e1"; rc=$?
expect "XDG first: its 100 mm travel refuses the job (exit $rc)" [ $rc -eq 1 ]
expect "XDG first: named" grep -q "^curvestep plan: machine: $T/xdg/curvestep/machine.ini (found)$" "$T/e1"

XDG_CONFIG_HOME=$T/none HOME=$T/home "$CS" plan "$JOB" >"$T/seg" 2>"$T/e2"; rc=$?
expect "then ~/.config: plans (exit $rc)" [ $rc -eq 0 ]
expect "then ~/.config: named" grep -q "^curvestep plan: machine: $T/home/.config/curvestep/machine.ini (found)$" "$T/e2"
XDG_CONFIG_HOME=$T/none HOME=$T/home "$SIM" --replay "$T/seg" --reference "$JOB" --check \
    >/dev/null 2>"$T/e3"
expect "the simulator finds the same file" grep -q "^curvestep-sim: machine: $T/home/.config/curvestep/machine.ini (found)$" "$T/e3"

if [ ! -e /etc/curvestep/machine.ini ]; then
    XDG_CONFIG_HOME=$T/none HOME=$T/nohome "$CS" plan "$JOB" >/dev/null 2>"$T/e4"
    expect "else built-in: named" grep -q '^curvestep plan: machine: the built-in machine' "$T/e4"
fi

XDG_CONFIG_HOME=$T/xdg HOME=$T/home "$CS" plan --machine contrib/machines/zpen-plotter.ini \
    "$JOB" >/dev/null 2>"$T/e5"; rc=$?
expect "--machine wins (exit $rc)" [ $rc -eq 0 ]
expect "--machine named" grep -q '^curvestep plan: machine: contrib/machines/zpen-plotter.ini$' "$T/e5"

# a router job: a 20 mm circle cut 1 mm deep, from 5 mm above the stock's top
printf 'G21 G90\nG0 Z5\nG0 X30 Y20\nG1 Z-1 F120\nG2 X30 Y20 I10 J0 F600\nG0 Z5\nG0 X0 Y0\n' >"$T/part.nc"
for f in contrib/machines/*.ini; do
    job=$JOB
    case $f in *router*) job=$T/part.nc ;; esac
    "$CS" plan --machine "$f" "$job" -o "$T/c.seg" 2>"$T/ce"; rc=$?
    expect "$f plans $job (exit $rc)" [ $rc -eq 0 ]
    "$SIM" --replay "$T/c.seg" --machine "$f" --reference "$job" --check >"$T/cs" 2>&1
    expect "$f: simulator check passes" grep -q '^check: ok$' "$T/cs"
done

finish
