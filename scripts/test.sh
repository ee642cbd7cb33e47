#!/usr/bin/env bash
# Installs what is missing, builds with warnings as errors, runs every test, then runs the
# tests again under AddressSanitizer + UndefinedBehaviorSanitizer, then fuzzes every reader
# for 30 s (scripts/fuzz.sh; SEM_FUZZ_SECONDS changes the time, 0 skips it).
# Tests that need the paper's models (../shared/models, or SEM_SHARED_MODELS) and cannot
# find them are reported as skipped, and the last line says how many.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --test --fuzz
jobs=$(nproc)
logs=$(mktemp -d)
trap 'rm -rf "$logs"' EXIT

# Runs ctest in build folder $1 (extra environment in the rest), keeps its output.
run_ctest() {
  local dir=$1
  shift
  (cd "$dir" && env "$@" ctest --output-on-failure -j"$jobs") 2>&1 | tee "$logs/$(basename "$dir").log"
  return "${PIPESTATUS[0]}"
}

cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DSEM_WERROR=ON >/dev/null
cmake --build build -j"$jobs"
run_ctest build

if [ "${SEM_SKIP_SANITIZE:-0}" != "1" ]; then
  cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSEM_WERROR=ON -DSEM_SANITIZE=ON >/dev/null
  cmake --build build-asan -j"$jobs"
  run_ctest build-asan ASAN_OPTIONS=detect_leaks=1 SEM_SANITIZED=1
fi

if [ "${SEM_FUZZ_SECONDS:-30}" != "0" ]; then
  bash scripts/fuzz.sh --time "${SEM_FUZZ_SECONDS:-30}"
fi

skipped=$(cat "$logs"/*.log | grep -c '(Skipped)' || true)
if [ "$skipped" -gt 0 ]; then
  names=$(cat "$logs"/*.log | grep '(Skipped)' | sed 's/.*Test *#[0-9]*: \([^ ]*\).*/\1/' | sort -u | tr '\n' ' ')
  echo "test.sh: all run tests passed; $skipped test runs were SKIPPED ($names): the paper's" \
       "models were not found (set SEM_SHARED_MODELS=/path/to/shared/models, default" \
       "../shared/models), or, for test_blender, there is no blender"
else
  echo "test.sh: all tests passed, none skipped"
fi
