#!/usr/bin/env bash
# Bounded inputs and errors that help and cannot harm (issue 17 items 4 and 5, issue 15 item 9):
# every reader stops at the input size limit (regular files, /dev/zero, a pipe on stdin) in
# bounded memory; a path or a plan past its element or segment limit is refused with a located
# error; control characters from input files and file names are escaped in messages; empty,
# BOM-only and comment-only inputs of every kind say "no drawable geometry" (exit 1);
# --machine DIR, the INI line of a bad key, "0x10" numbers and plan -o write errors; "delivered"
# past 65,536 messages. Prints "cli: N passed, M failed".
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
ESC=$(printf '\033')
# capped KB CMD...: runs CMD under an address-space cap of KB (the old unbounded readers run into
# it); a sanitizer build cannot run under one (its shadow memory), so there the cap is left off
# and the exit status and messages alone are checked.
if bash -c 'ulimit -v 1048576; "$0" --help; r=$?; exit $r' "$CS" >/dev/null 2>&1; then
    capped() { (ulimit -v "$1"; shift; exec "$@"); }
else
    capped() { shift; "$@"; }
fi

# 1. size limit: /dev/zero, a pipe and a regular file stop at the limit (64 MiB by default, or
# --max-input-mb) with exit 1, under a 1 GiB address-space cap that the old unbounded reader
# (18.9 GB in 20 s) runs into.
capped 1048576 timeout -k 5 120 "$CS" flatten /dev/zero >/dev/null 2>"$T/err"; rc=$?
expect "/dev/zero: exit 1" [ $rc -eq 1 ]
expect_err "/dev/zero: the limit named" '^/dev/zero:0:0: larger than the input limit of 64 MiB'
head -c 100000000 /dev/zero | capped 1048576 timeout -k 5 120 "$CS" flatten - \
    >/dev/null 2>"$T/err"; rc=$?
expect "stdin pipe: exit 1" [ $rc -eq 1 ]
expect_err "stdin pipe: the limit named" '^<stdin>:0:0: larger than the input limit'
head -c 2000000 /dev/zero | tr '\0' ' ' >"$T/blank2m.txt"
printf 'M 0 0 L 1 1\n' >>"$T/blank2m.txt"
run "--max-input-mb 1: 2 MB refused" 1 flatten --max-input-mb 1 "$T/blank2m.txt"
expect_err "--max-input-mb 1: says so" 'larger than the input limit of 1 MiB'
run "--max-input-mb 3: 2 MB read" 0 flatten --max-input-mb 3 "$T/blank2m.txt"
run "--max-input-mb 0: usage" 2 flatten --max-input-mb 0 "$T/blank2m.txt"
run "plan --max-input-mb 1: refused" 1 plan --max-input-mb 1 -o /dev/null "$T/blank2m.txt"
run "plan --max-input-mb x: usage" 2 plan --max-input-mb x "$T/blank2m.txt"

# 2. element and segment limits, located: 1,100,000 line segments in one path (8.6 MB) stop at
# the 1,048,577th, whose column is that of its 'L'; a small job over --max-segments names its
# element.
python3 -c "
import sys
w = sys.stdout.write
w('M 0 0')
for i in range(1100000):
    w(' L %d %d' % (i % 2, (i // 2) % 2))
w('\n')" >"$T/huge.txt"
COL=$(python3 -c "
s = open('$T/huge.txt').read()
pos, n = 0, 0
while n < 1048577:
    pos = s.index('L', pos) + 1
    n += 1
print(pos)")
capped 2097152 timeout -k 5 600 "$CS" plan -o /dev/null "$T/huge.txt" 2>"$T/err"; rc=$?
expect "1.1 M curves: exit 1" [ $rc -eq 1 ]
expect_err "1.1 M curves: located at curve 1,048,577" "^$T/huge.txt:1:$COL: more than 1048576 curves"
printf 'M 0 0\nL 100 100\n' >"$T/small.txt"
run "--max-segments 10: refused" 1 plan --max-segments 10 -o /dev/null "$T/small.txt"
expect_err "--max-segments 10: located" "^$T/small.txt:2:1: the job needs more than 10 step segments"
run "--max-segments 1000: planned" 0 plan --max-segments 1000 -o /dev/null "$T/small.txt"

# 3. control characters are escaped: a terminal escape in a patch file and in a file name.
printf '1\n1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16\n16\n1\033]0;pwned\007,2,3\n' >"$T/esc.patch"
run "escape in a patch file: exit 1" 1 toolpath --patches "$T/esc.patch"
expect "escape in a patch file: no raw ESC" sh -c "! grep -q \"$ESC\" \"$T/err\""
expect_err "escape in a patch file: shown as \\\\x1b" "'1\\\\x1b\]0;pwned\\\\x07' is not a finite number"
NAME="$T/a${ESC}[2Jb.svg"
printf 'M 0 0 Q\n' >"$NAME"
run "escape in a file name: exit 1" 1 flatten "$NAME"
expect "escape in a file name: no raw ESC" sh -c "! grep -q \"$ESC\" \"$T/err\""
expect_err "escape in a file name: shown as \\\\x1b" 'a\\x1b\[2Jb\.svg:[0-9]+:[0-9]+: '

# 4. nothing to draw is an error of every kind, never silence (issue 15 item 9).
for k in "svg:" "svg:$(printf '\357\273\277')" "svg:<svg xmlns='http://www.w3.org/2000/svg'/>" \
    "gcode:(comment only)" "gcode:; comment" "nc:G21 G90" "plt:IN;SP1;" "txt:   "; do
    ext=${k%%:*}
    printf '%s' "${k#*:}" >"$T/empty.$ext"
    run "empty .$ext '${k#*:}': exit 1" 1 flatten "$T/empty.$ext"
    expect_err "empty .$ext: no drawable geometry" "^$T/empty.$ext:1:1: no drawable geometry"
    run "plan of empty .$ext: exit 1" 1 plan -o /dev/null "$T/empty.$ext"
done
printf '\357\273\277\n' >"$T/empty.patch"
run "BOM-only patch file: exit 1" 1 toolpath --patches "$T/empty.patch"
expect_err "BOM-only patch file: no drawable geometry" 'no drawable geometry'

# 5. machine files: a directory, the line of a bad key after a syntax error, hexadecimal.
run "--machine DIR: refused" 1 plan --machine "$T" -o /dev/null "$T/small.txt"
expect_err "--machine DIR: says why" 'cannot read the machine file: read error: Is a directory'
printf '[x]\nsteps_per_mm 80\nbogus = 1\n' >"$T/m2.ini"
run "INI: first bad line" 1 plan --machine "$T/m2.ini" -o /dev/null "$T/small.txt"
expect_err "INI: line 2 with line 2's reason" '^.*m2.ini:2: syntax error'
printf '[x]\nsteps_per_mm = 0x10\n' >"$T/m3.ini"
run "INI: 0x10 refused" 1 plan --machine "$T/m3.ini" -o /dev/null "$T/small.txt"
expect_err "INI: 0x10 named" 'm3.ini:2: \[x\] steps_per_mm'

# 6. plan -o names the file it could not write.
run "plan -o /dev/full: fails" 3 plan -o /dev/full "$T/small.txt"
expect_err "plan -o /dev/full: names the file" '/dev/full: write error: No space left on device'

# 7. "delivered" counts past 65,536 messages (a 69,990-segment job on an --instant device).
python3 -c "
print('M 0 0 ' + ' '.join('L %g %g' % ((i % 2) * 0.5 + (i // 2) * 0.01, (i % 2) * 0.5)
                          for i in range(7000)))" >"$T/many.txt"
N=$("$CS" plan -o /dev/null "$T/many.txt" 2>&1 | sed -n 's/.* blocks, \([0-9]*\) segments,.*/\1/p')
expect "the long job has more than 65,536 segments" [ "${N:-0}" -gt 65536 ]
timeout -k 5 300 "$SIM" --pty --instant >"$T/sim.out" 2>"$T/sim.err" &
pids+=($!)
wait_pty "$T/sim.out" 30
timeout -k 5 300 "$CS" stream --port "$PTY" --quiet "$T/many.txt" >"$T/out" 2>"$T/err"; rc=$?
expect "long job: exit 0" [ $rc -eq 0 ]
expect "long job: $N delivered" grep -q "^stream: $N of $N segments executed, $N delivered" "$T/out"
finish
