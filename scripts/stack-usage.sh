#!/usr/bin/env bash
# Worst-case stack of a firmware image, computed statically: every source compiled again with
# GCC's -fstack-usage (bytes each function's frame takes) and -fcallgraph-info=su (who calls
# whom, GCC >= 10), then the deepest path of the call graph from each entry point, summing
# frames. Calls through function pointers are not in the graph (the port seam's callbacks are
# listed as entry points instead) and a recursive cycle is reported, not followed.
# Usage: stack-usage.sh CC "CFLAGS" "ENTRY..." SOURCE...   (prints "entry bytes path" lines)
set -euo pipefail
usage='usage: stack-usage.sh CC "CFLAGS" "ENTRY..." SOURCE...\nWorst-case stack of each ENTRY (bytes and call path) from -fstack-usage and\n-fcallgraph-info=su; run by make bench (docs/firmware.md).'
# Only the first word can be an option: CFLAGS itself starts with '-'.
case "${1:-}" in
-h | --help) printf '%b\n' "$usage"; exit 0 ;;
-*) printf 'stack-usage.sh: unknown option %s\n%b\n' "$1" "$usage" >&2; exit 2 ;;
esac
if [ $# -lt 4 ]; then
    printf '%b\n' "$usage" >&2
    exit 2
fi
cc=$1 cflags=$2 entries=$3
shift 3
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
i=0
for f in "$@"; do
    i=$((i + 1))
    # shellcheck disable=SC2086
    (cd "$dir" && $cc $cflags -fstack-usage -fcallgraph-info=su -c "$OLDPWD/$f" -o "o$i.o")
done
cat "$dir"/*.ci | awk -v entries="$entries" '
    /^node:/ {
        if (match($0, /title: "[^"]*"/)) name = substr($0, RSTART + 8, RLENGTH - 9)
        b = 0
        if (match($0, /[0-9]+ bytes \((static|dynamic|dynamic,bounded)\)/)) {
            b = substr($0, RSTART, RLENGTH) + 0
            if (index($0, "dynamic") && !index($0, "bounded")) dyn[name] = 1
        }
        if (b > frame[name]) frame[name] = b
    }
    /^edge:/ {
        match($0, /sourcename: "[^"]*"/); s = substr($0, RSTART + 13, RLENGTH - 14)
        match($0, /targetname: "[^"]*"/); t = substr($0, RSTART + 13, RLENGTH - 14)
        if (!((s, t) in seen)) { seen[s, t] = 1; callee[s] = callee[s] " " t }
    }
    function depth(f,    n, k, c, d, best, bp) {
        if (f in memo) return memo[f]
        if (f in onpath) { recursive = recursive " " f; return 0 }
        onpath[f] = 1
        best = 0; bp = ""
        n = split(callee[f], c, " ")
        for (k = 1; k <= n; k++) {
            d = depth(c[k])
            if (d > best) { best = d; bp = path[c[k]] }
        }
        delete onpath[f]
        memo[f] = frame[f] + best
        path[f] = f (bp != "" ? " > " bp : "")
        return memo[f]
    }
    END {
        n = split(entries, e, " ")
        for (k = 1; k <= n; k++) printf "%s %d %s\n", e[k], depth(e[k]), path[e[k]]
        for (f in dyn) printf "dynamic-frame %s\n", f
        if (recursive != "") printf "recursive%s\n", recursive
    }'
