#!/bin/sh
# The add-on with Blender's interface running, on a virtual X server (tests/blender/ui_check.py):
# the modal Simulate operator as a user starts it, the interface's timers firing while it
# runs, Esc stopping a long run. Not part of CTest (it needs xvfb-run and a software OpenGL
# renderer); run it by hand after a build:
#   sh tests/blender/run_ui.sh build ../shared/models [OUT]
# Debian: apt-get install xvfb xauth blender.
set -e
build=$1 models=$2 out=${3:-$1/blender-ui}
for tool in blender xvfb-run; do
  command -v $tool >/dev/null || { echo "run_ui.sh: $tool is missing (Debian: apt-get install xvfb xauth blender)"; exit 2; }
done
here=$(cd "$(dirname "$0")" && pwd)
rm -rf "$out"
mkdir -p "$out/user-scripts"
cmake --install "$build" --prefix "$out/prefix" >"$out/install.log"
python_dir=$(cd "$out/prefix" && ls -d lib*/python3*/dist-packages lib/python3/dist-packages 2>/dev/null | head -1)
OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive} BLENDER_USER_SCRIPTS="$out/user-scripts" \
  BLENDER_USER_CONFIG="$out/user-config" SEM_CACHE_DIR="$out/cache" SEM_LIBRARY= \
  xvfb-run -a -s "-screen 0 1280x800x24" blender --factory-startup --enable-event-simulate \
  --python-exit-code 1 --python "$here/ui_check.py" -- \
  --zip "$out/prefix/share/sem/sem_blender.zip" --python-dir "$out/prefix/$python_dir" \
  --models "$models"
