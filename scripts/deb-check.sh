#!/usr/bin/env bash
# make deb-check: installs the package make deb built (build/curvestep_*.deb) with apt, checks
# it, then purges it and checks nothing is left. Changes the system (as root): run it on a
# machine where that is fine. Prints "cli: N passed, M failed"; exit 1 on a failure.
#   - apt install ./build/curvestep_VERSION_ARCH.deb succeeds; curvestep --version and
#     curvestep-sim --help run from /usr/bin; the man pages and the completion are found;
#   - the system user curvestep exists, in the groups dialout and gpio;
#   - systemd-analyze verify accepts the unit (systemd cannot run as PID 1 in a container);
#   - apt purge removes every file of the package, the user and its group.
set -u
. "$(dirname "$0")/args.sh"
cs_args "usage: scripts/deb-check.sh [PACKAGE.deb]   (make deb-check; default build/curvestep_*.deb)\nInstalls the package, checks it, purges it (changes the system: as root)." 1 "$@"
deb=${1:-$(ls build/curvestep_*.deb 2>/dev/null | tail -n1)}
pass=0 fail=0
ok() { pass=$((pass + 1)); echo "ok: $*"; }
ko() { fail=$((fail + 1)); echo "FAIL: $*"; }
check() { local n=$1; shift; if "$@" >/dev/null 2>&1; then ok "$n"; else ko "$n"; fi; }
[ -f "$deb" ] || { echo "deb-check: no package (run make deb)" >&2; exit 1; }
export DEBIAN_FRONTEND=noninteractive
files=$(dpkg-deb -c "$deb" | awk '{print $6}' | sed 's|^\./|/|; s| ->.*||' | grep -v '/$')
check "apt install ./$deb" apt-get install -y "./$deb"
check "curvestep --version" bash -c "/usr/bin/curvestep --version | grep -q '^curvestep '"
check "curvestep-sim --help" /usr/bin/curvestep-sim --help
check "man curvestep finds the page" man -w curvestep
check "man 5 curvestep-machine finds the page" man -w 5 curvestep-machine
check "user curvestep in dialout" bash -c "id -nG curvestep | grep -qw dialout"
check "user curvestep in gpio" bash -c "id -nG curvestep | grep -qw gpio"
check "the unit runs as curvestep" grep -qx 'User=curvestep' /lib/systemd/system/curvestep.service
check "the unit starts /usr/bin/curvestep" grep -q '^ExecStart=/usr/bin/curvestep serve' /lib/systemd/system/curvestep.service
if systemd-analyze verify /lib/systemd/system/curvestep.service >"${TMPDIR:-/tmp}/deb-check.$$" 2>&1 &&
    ! grep -q . "${TMPDIR:-/tmp}/deb-check.$$"; then ok "systemd-analyze verify: no complaint"; else
    ko "systemd-analyze verify: $(cat "${TMPDIR:-/tmp}/deb-check.$$")"
fi
rm -f "${TMPDIR:-/tmp}/deb-check.$$"
# The unit's command as the unit runs it (systemd is not here to start it): as the user
# curvestep, on a serial device that belongs to the group dialout (the simulator's pty, given to
# dialout with mode 0660 like /dev/ttyUSB0), the socket in a directory only curvestep may enter
# (RuntimeDirectory=, mode 0700). The daemon must open the port and answer `status`.
run=$(mktemp -d)
/usr/bin/curvestep-sim --pty --idle-exit 30 >"$run/sim.out" 2>&1 &
simpid=$!
for _ in $(seq 1200); do [ -s "$run/sim.out" ] && break; sleep 0.1; done # 120 s at most
pty=$(head -n1 "$run/sim.out")
chgrp dialout "$pty" && chmod 0660 "$pty"
mkdir -p "$run/rt" && chown curvestep:curvestep "$run/rt" && chmod 0700 "$run/rt"
chmod 0755 "$run"
cmd=$(sed -n 's/^ExecStart=//p' /lib/systemd/system/curvestep.service |
    sed "s|/dev/ttyUSB0|$pty|; s|/run/curvestep/|$run/rt/|")
runuser -u curvestep -- $cmd 2>"$run/serve.err" &
servepid=$!
answered=no
for _ in $(seq 1200); do # 120 s at most: a loaded machine starts the daemon late
    if runuser -u curvestep -- /usr/bin/curvestep status --socket "$run/rt/curvestep.sock" >"$run/status.out" 2>&1; then
        answered=yes; break
    fi
    sleep 0.1
done
if [ $answered = yes ]; then ok "the unit's command, as curvestep, opens a dialout device and answers status"; else
    ko "the unit's command as curvestep: $(head -3 "$run/serve.err") $(head -2 "$run/status.out")"
fi
check "a user outside the unit cannot reach the socket (mode 0700 directory)" \
    bash -c "! runuser -u nobody -- /usr/bin/curvestep status --socket '$run/rt/curvestep.sock'"
kill "$servepid" "$simpid" 2>/dev/null
wait "$servepid" "$simpid" 2>/dev/null
rm -rf "$run"
check "apt purge curvestep" apt-get purge -y curvestep
left=""
for f in $files; do [ -e "$f" ] || [ -L "$f" ] && left="$left $f"; done
if [ -z "$left" ]; then ok "purge left none of the package's files"; else ko "purge left:$left"; fi
check "purge removed the user curvestep" bash -c "! getent passwd curvestep"
check "purge removed the group curvestep" bash -c "! getent group curvestep"
echo "cli: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
