#!/usr/bin/env bash
# Installs what is missing, builds sem, and runs the embedded default scene: a rubber beam
# clamped at x = 0 swinging under gravity. The animation goes to ./out (see the last lines
# printed for how to look at it). It builds what `cmake --install build` installs too (the
# command, the shared and static library, the Blender add-on's zip), so the README's next
# steps work right after it.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target sem sem_shared blender_addon
./build/sem run --out out --overwrite "$@"
