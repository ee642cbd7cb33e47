#!/usr/bin/env bash
# Installs the Debian packages sem needs when they are missing (run as root, or with sudo).
set -euo pipefail
# libocct-*: STEP files and the Open CASCADE cross-checks of our IGES (optional for a build:
# SEM_WITH_OCCT=OFF); python3-*: the Python package's tests and example
packages=(build-essential cmake pkg-config libembree-dev libsuitesparse-dev libopenblas-dev
          liblapacke-dev libglpk-dev libcjson-dev
          libocct-foundation-dev libocct-modeling-data-dev libocct-modeling-algorithms-dev
          libocct-data-exchange-dev
          python3 python3-numpy python3-pytest python3-matplotlib)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}" >&2
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi
