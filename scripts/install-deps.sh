#!/bin/sh
# install-deps.sh — installs the Debian packages idmr builds, tests and plots with, when any is
# missing. Idempotent: with everything present it only asks dpkg and exits 0.
# Needs root (or sudo) only when something has to be installed.
set -eu

PACKAGES="build-essential pkg-config pocl-opencl-icd ocl-icd-opencl-dev opencl-headers clinfo
libembree-dev libopenmesh-dev libopenimageio-dev libxml2-dev libcjson-dev libcmocka-dev
libmeshoptimizer-dev
python3-matplotlib python3-numpy"

missing=""
for p in $PACKAGES; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing="$missing $p"
    fi
done
[ -z "$missing" ] && exit 0

echo "install-deps: installing:$missing" >&2
SUDO=""
if [ "$(id -u)" != 0 ]; then
    if command -v sudo >/dev/null 2>&1; then
        SUDO="sudo"
    else
        echo "install-deps: need root to install:$missing" >&2
        exit 1
    fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
# shellcheck disable=SC2086
$SUDO apt-get install -y -qq $missing >&2
