#!/usr/bin/env bash
# CTest viewer_browser: `sem run` a short animation, `sem view` its folder, and load the page
# in headless Chromium (tests/js/viewer_test.mjs: no console errors, the object on screen,
# the first and last frames different). Skipped (exit 77) only when node, chromium or
# chromedriver is not installed (scripts/setup.sh installs them).
#   viewer_browser_test.sh SEM_BINARY WORK_DIR
set -euo pipefail
sem=$1
work=$2
here=$(cd "$(dirname "$0")" && pwd)
for tool in node chromedriver; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "skipped: $tool is not installed (scripts/setup.sh installs it)"
    exit 77
  fi
done
if [ ! -x "${SEM_CHROMIUM:-/usr/bin/chromium}" ]; then
  echo "skipped: chromium is not installed (scripts/setup.sh installs it)"
  exit 77
fi
rm -rf "$work"
mkdir -p "$work"
export SEM_CACHE_DIR="$work/cache"
"$sem" run --frames 12 --out "$work/run" --quiet
"$sem" view "$work/run"
node "$here/viewer_test.mjs" "$work/run/viewer.html" "$work"
