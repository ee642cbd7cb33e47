#!/usr/bin/env bash
# CTest gltf_validator: `sem run` writes animation.glb for a few scenes (one object, two
# objects with part materials and a sphere's collapsed poles, a run of the rest frame
# only); the Khronos glTF-Validator (npm gltf-validator, installed into tests/js/node_modules
# by scripts/test.sh) must report no error and no warning for any, with one animation key
# per frame. Skipped (exit 77) only when node or npm is not installed.
#   gltf_validator_test.sh SEM_BINARY WORK_DIR
set -euo pipefail
sem=$1
work=$2
here=$(cd "$(dirname "$0")" && pwd)
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  echo "skipped: node and npm are not installed (scripts/setup.sh installs them)"
  exit 77
fi
rm -rf "$work"
mkdir -p "$work"
export SEM_CACHE_DIR="$work/cache"
"$sem" run --frames 3 --out "$work/default" --quiet
node "$here/validate_gltf.mjs" "$work/default/animation.glb" 4
"$sem" run "$here/../data/scene_two_objects.json" --out "$work/two" --quiet
node "$here/validate_gltf.mjs" "$work/two/animation.glb" 4
"$sem" run "$here/../../examples/bouncing_sphere.json" --frames 2 --out "$work/ball" --quiet
node "$here/validate_gltf.mjs" "$work/ball/animation.glb" 3
"$sem" run --frames 0 --out "$work/still" --quiet
node "$here/validate_gltf.mjs" "$work/still/animation.glb"
