#!/bin/sh
# Installs the Debian packages gi-farm needs to build and test, if missing.
# Runs apt-get directly as root, through sudo otherwise; says clearly what to
# do when neither is possible. Safe to run repeatedly: it only installs what
# `dpkg -s` does not report as installed.
set -eu

PACKAGES="make gcc pkg-config clang libclang-rt-14-dev
libembree-dev libopenexr-dev libcjson-dev libpng-dev libassimp-dev
libopenblas-dev liblapacke-dev libzstd-dev libsodium-dev libmicrohttpd-dev zlib1g-dev
libdeflate-dev
iproute2 curl"

missing=""
for p in $PACKAGES; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing="$missing $p"
    fi
done
[ -z "$missing" ] && exit 0

if ! command -v apt-get >/dev/null 2>&1; then
    echo "deps: missing packages:$missing" >&2
    echo "deps: this is not a Debian/Ubuntu system (no apt-get); install them by hand." >&2
    exit 1
fi

if [ "$(id -u)" = 0 ]; then
    SUDO=""
elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
    SUDO="sudo -n"
elif command -v sudo >/dev/null 2>&1 && [ -t 0 ]; then
    SUDO="sudo"
else
    echo "deps: missing packages:$missing" >&2
    echo "deps: installing them needs root; run 'make deps' as root or with sudo:" >&2
    echo "  sudo apt-get install -y$missing" >&2
    exit 1
fi

echo "deps: installing:$missing"
export DEBIAN_FRONTEND=noninteractive
# A fresh machine may have empty package lists: update once if install fails.
# shellcheck disable=SC2086
if ! $SUDO apt-get install -y --no-install-recommends $missing; then
    $SUDO apt-get update
    $SUDO apt-get install -y --no-install-recommends $missing
fi
