#!/usr/bin/env bash
# The man pages tell the truth about the options (issue 13). Generic on purpose: the commands
# come from `curvestep --help`, the options from each `--help`, so a new command or option
# without a man entry fails here, and so does a man entry for an option that is gone.
#   curvestep.1      each command listed by `curvestep --help` (but help) has a ".SS CMD"
#                    subsection; every long option CMD --help prints appears in it, and every
#                    option its .TP entries define is printed by CMD --help.
#   curvestep-sim.1  the same against `curvestep-sim --help` plus the helps it names
#                    ("--pty --help", "--modbus-tcp --help").
#   curvestep-machine.5  every [section] the code accepts has a .SH (the key names are in the
#                    code as strings: each key of host/cs_machine_ini.c and host/cs_gpio_cfg.c
#                    compared with strcasecmp against `name` must be a .B entry).
set -u
. "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
need_bin "$CS" "$SIM"
M=man

opts() { grep -oE -- '--[a-z][a-z0-9-]*' | grep -vx -- '--help' | sort -u; }
# man source -> plain text with '-' for '\-'
unman() { sed -e 's/\\-/-/g' -e 's/\\f[BIRP]//g'; }
# the long options defined by .TP entries (the line after .TP) of man text on stdin
tp_opts() { awk 'tp {print; tp = 0} /^\.TP/ {tp = 1}' | opts; }
has_word() { grep -qE -- "(^|[^a-z0-9-])$1([^a-z0-9-]|\$)"; }
# same_opts HELP MANTEXT WHAT PAGE: the options of the help file are in the man text, and the
# options the man text's .TP entries define are in the help
same_opts() {
    local o
    for o in $(opts <"$1"); do
        has_word "$o" <"$2" && ok || ko "$3 prints $o, $4 does not"
    done
    for o in $(tp_opts <"$2"); do
        has_word "$o" <"$1" && ok || ko "$4 defines $o, $3 does not"
    done
}

cmds=$("$CS" --help | awk '/^Commands:/ {on = 1; next} on && /^  [a-z]/ {print $1} on && /^$/ {on = 0}' |
    grep -vx help)
[ -n "$cmds" ] && ok || ko "no commands found in curvestep --help"
unman <"$M/curvestep.1" >"$T/cs.txt"
for c in $cmds; do
    awk -v c="$c" '$0 == ".SS " c {on = 1; next} /^\.S[SH] / {on = 0} on' "$T/cs.txt" >"$T/sec"
    if [ ! -s "$T/sec" ]; then ko "man/curvestep.1 has no .SS $c"; continue; fi
    "$CS" "$c" --help >"$T/help" 2>&1
    same_opts "$T/help" "$T/sec" "curvestep $c --help" "man/curvestep.1 (.SS $c)"
done
for s in $(awk '/^\.SH COMMANDS/ {on = 1; next} /^\.SH / {on = 0} on && /^\.SS / {print $2}' "$T/cs.txt"); do
    [ "$s" = help ] && continue
    printf '%s\n' $cmds | grep -qx "$s" && ok || ko "man/curvestep.1 documents '$s', curvestep --help lists no such command"
done

"$SIM" --help >"$T/simhelp" 2>&1
for sub in $(grep -oE -- '--[a-z][a-z0-9-]* --help' "$T/simhelp" | awk '{print $1}' | sort -u); do
    "$SIM" "$sub" --help >>"$T/simhelp" 2>&1
done
unman <"$M/curvestep-sim.1" >"$T/sim.txt"
same_opts "$T/simhelp" "$T/sim.txt" "curvestep-sim's help" man/curvestep-sim.1

# The machine file: keys the code compares against (strcasecmp(name, "key")), every one a .B.
unman <"$M/curvestep-machine.5" >"$T/m5.txt"
for k in $(grep -ohE 'strcasecmp\((name|name \+ n \+ 1), "[a-z_]+"\)' host/cs_machine_ini.c host/cs_gpio_cfg.c host/cs_ctlcfg.c |
    sed -E 's/.*"([a-z_]+)"\)/\1/' | sort -u); do
    grep -qE "^\.B ([a-z_]+_)?$k( |\$)|_$k|(^|[ ,])$k(,| |\$)" <(grep '^\.B' "$T/m5.txt") && ok ||
        ko "man/curvestep-machine.5 does not document the key '$k'"
done
for s in $(grep -ohE 'strcasecmp\(section, "[a-z]+"\)' host/cs_machine_ini.c host/cs_gpio_cfg.c host/cs_ctlcfg.c |
    sed -E 's/.*"([a-z]+)"\)/\1/' | sort -u) x y z a; do
    grep -qE "^\.SH .*\[$s\]" "$T/m5.txt" && ok || ko "man/curvestep-machine.5 has no section [$s]"
done
# Every page renders without groff warnings.
for p in "$M"/*.[15]; do
    w=$(LC_ALL=C.UTF-8 MANWIDTH=80 man --warnings -l "$p" 2>&1 >/dev/null)
    [ -z "$w" ] && ok || ko "$p: $w"
done
finish
