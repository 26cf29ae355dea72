#!/bin/sh
# Install the Debian packages a group of make targets needs.
# Usage: deps.sh [GROUP...]   GROUP: host firmware bench fuzz deb all (none given: all)
#   host      the host program, simulator, unit and CLI tests (make host, make install)
#   firmware  cross compilers and emulators (make firmware, make cross, make fw-test)
#   bench     the peer libraries of the benchmarks (make bench)
#   fuzz      clang's libFuzzer (make fuzz)
#   deb       the Debian tooling (make deb)
# Only what is missing is installed; when everything is present this is a no-op
# (one dpkg-query, no network). Safe to run as often as make likes. The Makefile runs it before
# it reads pkg-config (see "stage 1" at the top of the Makefile).
set -eu

HOST="make gcc libc6-dev pkg-config git \
libcmocka-dev libexpat1-dev libinih-dev libcairo2-dev \
librsvg2-bin libmodbus-dev libgpiod-dev man-db python3 python3-ezdxf"
FIRMWARE="gcc-arm-none-eabi libnewlib-arm-none-eabi binutils-arm-none-eabi \
gcc-avr avr-libc binutils-avr \
qemu-system-arm simavr libsimavr-dev libelf-dev"
BENCH="g++ libagg-dev"
FUZZ="clang llvm libclang-rt-14-dev"
DEB="debhelper devscripts lintian fakeroot dpkg-dev adduser systemd"

case "${1:-}" in -h|--help)
    sed -n '2,11s/^# \{0,1\}//p' "$0"; exit 0 ;;
esac
[ $# -eq 0 ] && set -- all
PKGS=""
for g in "$@"; do
    case "$g" in
        host) PKGS="$PKGS $HOST" ;;
        firmware) PKGS="$PKGS $FIRMWARE" ;;
        bench) PKGS="$PKGS $BENCH" ;;
        fuzz) PKGS="$PKGS $FUZZ" ;;
        deb) PKGS="$PKGS $DEB" ;;
        all) PKGS="$PKGS $HOST $FIRMWARE $BENCH $FUZZ $DEB" ;;
        *) echo "deps: unknown group '$g' (host firmware bench fuzz deb all)" >&2; exit 2 ;;
    esac
done

missing=""
for p in $PKGS; do
    case " $missing " in *" $p "*) continue ;; esac
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed"; then
        missing="$missing $p"
    fi
done

[ -z "$missing" ] && exit 0

echo "deps: installing:$missing" >&2
SUDO=""
if [ "$(id -u)" != 0 ]; then
    if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
        echo "deps: need root (or sudo) to install:$missing" >&2; exit 1
    fi
fi
export DEBIAN_FRONTEND=noninteractive
# The package lists may be absent on a fresh machine; refresh them once if an install fails.
if ! $SUDO apt-get install -y --no-install-recommends $missing >/dev/null 2>&1; then
    $SUDO apt-get update -qq
    $SUDO apt-get install -y --no-install-recommends $missing
fi
