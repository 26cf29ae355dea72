#!/usr/bin/env bash
# Every program in the repository answers --help (exit 0, a usage on stdout) and refuses an
# option it does not know with exit 2 and no side effect (issue 13): curvestep and each of its
# commands (listed by `curvestep --help`), curvestep-sim and the helps it names, the benchmarks
# (tests/bench/bench_*.c, built here), the simavr harness (when simavr is installed: a firmware
# package), and the scripts that take arguments. Each runs in an empty directory, which must
# still be empty afterwards (bench_peers once wrote a file named --help and ran the whole
# benchmark).
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
need_bin "$CS" "$SIM"
root=$(pwd)
unset MAKEFLAGS MFLAGS MAKELEVEL MAKEOVERRIDES VARIANT
abs() { (cd "$(dirname "$1")" && printf '%s/%s\n' "$(pwd)" "$(basename "$1")"); }
cs=$(abs "$CS")
sim=$(abs "$SIM")
bdir=$(dirname "$cs")
[ "$(basename "$bdir")" = asan ] && bdir=$(dirname "$bdir")
W=$T/w
mkdir -p "$W"

# probe NAME WANT-RC CMD...: CMD in the empty directory exits WANT-RC (bounded: a program that
# ignores its arguments and starts working fails here, not by hanging) and leaves it empty.
probe() {
    local name=$1 want=$2
    shift 2
    (cd "$W" && timeout -k 5 60 "$@" >"$T/out" 2>"$T/err" </dev/null)
    local rc=$? left
    left=$(ls -A "$W")
    rm -rf "${W:?}"/* "$W"/.[!.]* 2>/dev/null
    if [ "$rc" -ne "$want" ]; then ko "$name: exit $rc, expected $want"; head -3 "$T/err" | sed 's/^/    /'; return; fi
    if [ -n "$left" ]; then ko "$name: left files behind: $left"; return; fi
    if [ "$want" -eq 0 ] && ! grep -qi 'usage' "$T/out"; then ko "$name: no usage on stdout"; return; fi
    ok
}
# both NAME CMD...: CMD --help answers, CMD --no-such-option is refused
both() {
    local name=$1
    shift
    probe "$name --help" 0 "$@" --help
    probe "$name --no-such-option" 2 "$@" --no-such-option
}

both curvestep "$cs"
probe "curvestep no-such-command" 2 "$cs" no-such-command
probe "curvestep --version" 0 bash -c "'$cs' --version | grep -q curvestep && echo usage"
for c in $("$cs" --help | awk '/^Commands:/ {on = 1; next} on && /^  [a-z]/ {print $1} on && /^$/ {on = 0}'); do
    [ "$c" = help ] && continue
    both "curvestep $c" "$cs" "$c"
done
both curvestep-sim "$sim"
for sub in $("$sim" --help | grep -oE -- '--[a-z][a-z0-9-]* --help' | awk '{print $1}' | sort -u); do
    probe "curvestep-sim $sub --help" 0 "$sim" "$sub" --help
done

# The benchmarks: built here (plain; bench_peers needs libagg-dev, a `bench` package).
benches=()
for src in tests/bench/bench_*.c; do
    b=$(basename "$src" .c)
    if [ "$b" = bench_peers ] && ! pkg-config --exists libagg 2>/dev/null; then
        echo "note: libagg-dev missing (deps.sh bench): bench_peers not checked"
        continue
    fi
    benches+=("$bdir/bench/$b")
done
if make --no-print-directory CS_DEPS_DONE=1 BUILD="$bdir" "${benches[@]}" >"$T/make.log" 2>&1; then ok; else
    ko "building the benchmarks"
    tail -5 "$T/make.log"
fi
for b in "${benches[@]}"; do
    both "$(basename "$b")" "$b"
done
probe "bench_link with two files (takes one)" 2 "$bdir/bench/bench_link" a.csv b.csv

# The simavr harness (a firmware-group program).
if pkg-config --exists simavr 2>/dev/null; then
    make --no-print-directory CS_DEPS_DONE=1 BUILD="$bdir" "$bdir/fw/avr/avr_harness" >"$T/make.log" 2>&1 ||
        ko "building avr_harness"
    both avr_harness "$bdir/fw/avr/avr_harness"
else
    echo "note: simavr missing (deps.sh firmware): avr_harness not checked"
fi

# The scripts that take arguments (args.sh is sourced, not run).
for s in scripts/*.sh tests/fw/bench_*.sh tests/bench/*.sh; do
    [ "$s" = scripts/args.sh ] && continue
    both "$s" bash "$root/$s"
done
finish
