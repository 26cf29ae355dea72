#!/usr/bin/env bash
# Build every tests/fuzz/fuzz_*.c with clang's libFuzzer + ASan + UBSan and run each one for
# FUZZ_SECONDS (default 60) seconds; print executions and time per target. A finding (crash,
# sanitizer report, failed check, leak, timeout) fails the script and leaves the input in
# $BUILD/fuzz/ (crash-*, leak-*, timeout-*). Seeds: tests/fuzz/corpus_<name>/ if present, plus
# whatever the target writes when built with -DCS_FUZZ_SEED_MAIN. The corpus grows in
# $BUILD/fuzz/corpus_<name>/ across runs.
# Usage: scripts/fuzz.sh [target-name...]   (default: every tests/fuzz/fuzz_*.c)
set -eu
. "$(dirname "$0")/args.sh"
cs_args "usage: scripts/fuzz.sh [TARGET...]   (make fuzz; default: every tests/fuzz/fuzz_*.c)\nEach target under libFuzzer + ASan + UBSan for FUZZ_SECONDS (60) seconds." -1 "$@"
secs=${FUZZ_SECONDS:-60}
out=${BUILD:-build}/fuzz
CLANG=${CLANG:-clang}
mkdir -p "$out"
command -v "$CLANG" >/dev/null || { echo "fuzz: $CLANG missing (run scripts/deps.sh)"; exit 1; }
core=(firmware/core/*.c)
inc="-Ifirmware/core"
flags="-std=c99 -g -O1 -fno-omit-frame-pointer -fsanitize=address,undefined -fno-sanitize-recover=all"

targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
    for src in tests/fuzz/fuzz_*.c; do [ -f "$src" ] && targets+=("$(basename "$src" .c)"); done
fi
[ ${#targets[@]} -gt 0 ] || { echo "fuzz: no tests/fuzz/fuzz_*.c"; exit 1; }

status=0
for name in "${targets[@]}"; do
    src=tests/fuzz/$name.c
    short=${name#fuzz_}
    corpus=$out/corpus_$short
    mkdir -p "$corpus"
    if [ -d "tests/fuzz/corpus_$short" ]; then cp -n "tests/fuzz/corpus_$short"/* "$corpus"/ 2>/dev/null || true; fi
    # Extra link libraries a target names in a comment line "fuzz-libs: -lexpat ..." (host
    # parsers built on Debian libraries).
    libs=$(sed -n 's/^.*fuzz-libs: *\([-a-zA-Z0-9_ ]*\).*$/\1/p' "$src" | head -n1)
    if grep -q CS_FUZZ_SEED_MAIN "$src"; then
        $CLANG $flags -DCS_FUZZ_SEED_MAIN $inc "$src" "${core[@]}" -o "$out/${name}_seed" $libs
        "$out/${name}_seed" "$corpus"
    fi
    $CLANG $flags -fsanitize=fuzzer $inc "$src" "${core[@]}" -o "$out/$name" $libs
    log=$out/$name.log
    start=$(date +%s)
    rc=0
    "$out/$name" -max_total_time="$secs" -print_final_stats=1 -artifact_prefix="$out/" \
        "$corpus" >"$log" 2>&1 || rc=$?
    end=$(date +%s)
    execs=$(sed -n 's/^stat::number_of_executed_units: *\([0-9]*\).*/\1/p' "$log" | tail -n1)
    files=$(find "$corpus" -type f | wc -l)
    if [ $rc -ne 0 ]; then
        tail -n 40 "$log"
        printf 'fuzz: %-16s FINDING after %s executions in %d s (exit %d, see %s)\n' \
            "$name" "${execs:-?}" $((end - start)) $rc "$log"
        status=1
    else
        printf 'fuzz: %-16s %s executions in %d s, corpus %d inputs, no finding\n' \
            "$name" "${execs:-?}" $((end - start)) "$files"
    fi
done
exit $status
