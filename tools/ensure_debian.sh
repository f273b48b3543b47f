#!/usr/bin/env bash
# Install the Debian packages camtask needs, only when one of them is missing:
# headless OpenGL (EGL and OSMesa through Mesa's llvmpipe) and, when the Python that
# makes the virtual environment ($PYTHON, default python3) lacks ensurepip, python3-venv.
# Idempotent; needs root only to install.
set -euo pipefail
PYTHON="${PYTHON:-python3}"
if ! command -v dpkg-query >/dev/null 2>&1; then
    echo "note: not a Debian system (no dpkg-query): make sure Mesa's EGL or OSMesa and Python's venv module are installed" >&2
    exit 0
fi
packages="libegl1 libegl-mesa0 libgl1 libgl1-mesa-dri libglx-mesa0 libxrender1 libosmesa6"
missing=""
for p in $packages; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if ! "$PYTHON" -c "import ensurepip" >/dev/null 2>&1; then
    missing="$missing python3-venv"
fi
if [ -z "$missing" ]; then
    exit 0
fi
echo "installing Debian packages:$missing"
if [ "$(id -u)" != 0 ]; then
    echo "error: need root to run: apt-get install -y$missing" >&2
    exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends $missing >/dev/null
