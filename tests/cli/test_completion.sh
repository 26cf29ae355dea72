#!/usr/bin/env bash
# Bash completion (contrib/bash-completion/curvestep): drives the completion functions as bash
# does (COMP_WORDS, COMP_CWORD, then COMPREPLY) against the built programs. Expected lists come
# from the programs' --help and from the files made here, not from the completion script.
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
need_bin "$CS" "$SIM"
cs=$(cd "$(dirname "$CS")" && pwd)/$(basename "$CS")
sim=$(cd "$(dirname "$SIM")" && pwd)/$(basename "$SIM")
. contrib/bash-completion/curvestep

# comp FUNC WORD...: complete the last WORD; the sorted answers, one per line, in $T/got
comp() {
    local fn=$1
    shift
    COMP_WORDS=("$@")
    COMP_CWORD=$((${#COMP_WORDS[@]} - 1))
    COMPREPLY=()
    "$fn"
    printf '%s\n' ${COMPREPLY[@]+"${COMPREPLY[@]}"} | sed '/^$/d' | sort >"$T/got"
}
# same LIST: $T/got holds exactly the words of LIST
same() { printf '%s\n' $1 | sed '/^$/d' | sort | cmp -s - "$T/got"; }
has() { grep -qx -- "$1" "$T/got"; }

cmds=$("$cs" --help | awk '/^Commands:/ {on = 1; next} on && /^  [a-z]/ {print $1} on && /^$/ {on = 0}')
comp _curvestep "$cs" ""
expect "every command of curvestep --help, and --help --version" same "$cmds --help --version"
comp _curvestep "$cs" fl
expect "'fl' completes to flatten" same "flatten"
comp _curvestep "$cs" help pl
expect "help COMMAND completes the command" same "plan"
for c in $cmds; do
    [ "$c" = help ] && continue
    comp _curvestep "$cs" "$c" --
    want=$("$cs" "$c" --help 2>&1 | grep -oE -- '--[a-z][a-z0-9-]*' | sort -u)
    expect "$c --: the options of $c --help" same "$want"
done
comp _curvestep "$cs" flatten --method ""
expect "--method: the tracers" same "afd fd length predict subdiv"
comp _curvestep "$cs" plan --tol ""
expect "--tol takes a number: nothing offered" same ""

# Files by kind, in a directory made here.
mkdir -p "$T/w/sub"
touch "$T/w/a.svg" "$T/w/b.NC" "$T/w/c.png" "$T/w/d.ini" "$T/w/e.plt" "$T/w/f.seg" "$T/w/g.gcode"
cd "$T/w" || exit 1
comp _curvestep "$cs" flatten ""
expect "flatten FILE: jobs and directories only" same "a.svg b.NC e.plt g.gcode sub"
comp _curvestep "$cs" plan --machine ""
expect "--machine: .ini and directories" same "d.ini sub"
comp _curvestep "$cs" flatten --svg ""
expect "--svg: .svg and directories" same "a.svg sub"
comp _curvestep_sim "$sim" --replay ""
expect "sim --replay: segments and directories" same "f.seg sub"
comp _curvestep_sim "$sim" --
want=$( { "$sim" --help; "$sim" --pty --help; "$sim" --modbus-tcp --help; } 2>&1 |
    grep -oE -- '--[a-z][a-z0-9-]*' | sort -u)
expect "sim --: the options of its helps" same "$want"
expect "sim --: --queue from --pty --help" has --queue
comp _curvestep_sim "$sim" --view ""
expect "sim --view: the views" same "front iso side top"
finish
