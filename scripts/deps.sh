#!/bin/sh
# Install the Debian packages the build, tests, demo and benchmarks need.
# Only what is missing is installed; when everything is present this is a no-op
# (one dpkg-query, no network). Safe to run as often as make likes.
set -eu

PKGS="make gcc libc6-dev pkg-config \
libcmocka-dev libexpat1-dev libinih-dev libcairo2-dev \
gcc-arm-none-eabi libnewlib-arm-none-eabi binutils-arm-none-eabi \
gcc-avr avr-libc binutils-avr \
clang llvm libclang-rt-14-dev libagg-dev \
librsvg2-bin \
libmodbus-dev libgpiod-dev \
qemu-system-arm simavr libsimavr-dev libelf-dev"

missing=""
for p in $PKGS; do
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
