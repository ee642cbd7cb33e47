#!/usr/bin/env bash
# Installs the Debian packages sem needs when they are missing (run as root, or with sudo).
set -euo pipefail
#   bash scripts/setup.sh          what building and running sem needs
#   bash scripts/setup.sh --fuzz   also clang, libclang-rt-dev (libFuzzer) and libomp-dev
#                                  (OpenMP for clang), for scripts/fuzz.sh
packages=(build-essential cmake pkg-config libembree-dev libsuitesparse-dev libopenblas-dev
          liblapacke-dev libglpk-dev libcjson-dev)
if [ "${1:-}" = "--fuzz" ]; then
  packages+=(clang libclang-rt-dev libomp-dev)
fi
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
