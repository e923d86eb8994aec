#!/bin/sh
# install-deps.sh — installs what idmr builds, tests, evaluates and plots with, when something is
# missing. Idempotent: with everything present it only asks dpkg (and pip) and exits 0.
#
#   scripts/install-deps.sh            the Debian packages (needs root or sudo only when one is
#                                      missing); Open MPI among them, which idmr uses where it
#                                      is installed (the build without it works as well)
#   scripts/install-deps.sh --python   also the Python tools of the evaluation, into .venv/ in
#                                      the repository (Mitsuba 3, the second renderer; NVIDIA's
#                                      FLIP evaluator; trimesh, pygltflib and jsonschema, the
#                                      glTF readers of scripts/gltf-check), at the versions
#                                      pinned below
#   scripts/install-deps.sh --fuzz     also clang and its libFuzzer runtime (make fuzz)
set -eu
cd "$(dirname "$0")/.."

PACKAGES="build-essential pkg-config pocl-opencl-icd ocl-icd-opencl-dev opencl-headers clinfo
libembree-dev libopenmesh-dev libopenimageio-dev libxml2-dev libcjson-dev libcmocka-dev
libmeshoptimizer-dev libassimp-dev assimp-testmodels zlib1g-dev libopenmpi-dev openmpi-bin
python3-matplotlib python3-numpy python3-venv"

PYTHON_PACKAGES="mitsuba==3.9.1 drjit==1.5.0 flip-evaluator==1.7 numpy==2.4.6 trimesh==4.12.2
pygltflib==1.16.5 jsonschema==4.23.0"

if [ "${1:-}" = "--fuzz" ]; then
    PACKAGES="$PACKAGES clang libclang-rt-14-dev"
fi

missing=""
for p in $PACKAGES; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing="$missing $p"
    fi
done

if [ -n "$missing" ]; then
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
fi

if [ "${1:-}" = "--python" ]; then
    # The venv records what it was made with; a different pin list makes it again.
    if [ ! -x .venv/bin/python ] || [ "$(cat .venv/idmr-packages 2>/dev/null)" != "$PYTHON_PACKAGES" ]; then
        echo "install-deps: installing into .venv: $PYTHON_PACKAGES" >&2
        rm -rf .venv
        /usr/bin/python3 -m venv .venv
        # shellcheck disable=SC2086
        .venv/bin/pip install -q $PYTHON_PACKAGES >&2
        echo "$PYTHON_PACKAGES" > .venv/idmr-packages
    fi
fi
