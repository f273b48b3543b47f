#!/usr/bin/env bash
# Install the Debian packages for headless OpenGL (EGL and OSMesa through Mesa's
# llvmpipe) only when one of them is missing. Idempotent; needs root only to install.
set -euo pipefail
packages="libegl1 libegl-mesa0 libgl1 libgl1-mesa-dri libglx-mesa0 libxrender1 libosmesa6"
missing=""
for p in $packages; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -z "$missing" ]; then
    exit 0
fi
echo "installing headless GL packages:$missing"
if [ "$(id -u)" != 0 ]; then
    echo "error: need root to run: apt-get install -y$missing" >&2
    exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends $missing >/dev/null
