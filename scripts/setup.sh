#!/usr/bin/env bash
# Installs the Debian packages sem needs when they are missing (run as root, or with sudo).
# With --test also what the test suite needs: node and npm (the glTF validator, installed
# from the npm registry into tests/js/node_modules), Chromium with its WebDriver (the
# browser test of sem view), Blender (Debian's, 3.4 on bookworm: the add-on's test), gmsh and
# CalculiX (sem validate's FEM side).
set -euo pipefail
cd "$(dirname "$0")/.."
#   bash scripts/setup.sh                 what building and running sem needs
#   bash scripts/setup.sh --test          also what the test suite needs (above)
#   bash scripts/setup.sh --fuzz          also clang, libclang-rt-dev (libFuzzer) and libomp-dev
#                                         (OpenMP for clang), for scripts/fuzz.sh
# (both options may be given)
# libpng, libjs-three, ffmpeg: sem render (PNG, --mp4) and sem view (three.js);
# libocct-*: STEP files and the Open CASCADE cross-checks of our IGES (optional for a build:
# SEM_WITH_OCCT=OFF); python3-*: the Python package's tests and example
packages=(build-essential cmake pkg-config libembree-dev libsuitesparse-dev libopenblas-dev
          liblapacke-dev libglpk-dev libcjson-dev
          libpng-dev libjs-three ffmpeg
          libocct-foundation-dev libocct-modeling-data-dev libocct-modeling-algorithms-dev
          libocct-data-exchange-dev
          python3 python3-numpy python3-pytest python3-matplotlib)
with_tests=0
for arg in "$@"; do
  case "$arg" in
    --test) with_tests=1 ;;
    --fuzz) packages+=(clang libclang-rt-dev libomp-dev) ;;
    *) echo "setup.sh: unknown argument '$arg' (--test, --fuzz)" >&2; exit 2 ;;
  esac
done
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ $with_tests = 1 ]; then
  # by command: node may come with its own npm (e.g. NodeSource's nodejs), which Debian's
  # npm package would conflict with
  command -v node >/dev/null 2>&1 || missing+=(nodejs)
  command -v npm >/dev/null 2>&1 || missing+=(npm)
  command -v chromium >/dev/null 2>&1 || missing+=(chromium)
  command -v chromedriver >/dev/null 2>&1 || missing+=(chromium-driver)
  command -v blender >/dev/null 2>&1 || missing+=(blender)
  # sem validate's FEM side (tests/test_validate.c; skipped when they cannot be installed)
  command -v gmsh >/dev/null 2>&1 || missing+=(gmsh)
  command -v ccx >/dev/null 2>&1 || missing+=(calculix-ccx)
fi
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}" >&2
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi
if [ $with_tests = 1 ] && [ ! -f tests/js/node_modules/gltf-validator/package.json ]; then
  echo "setup: installing the glTF validator into tests/js/node_modules (npm ci)" >&2
  npm ci --prefix tests/js --no-audit --no-fund --loglevel=error >/dev/null
fi
