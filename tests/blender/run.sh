#!/bin/sh
# CTest's test_blender: the Blender add-on in Debian's blender, headless, as a user has it:
# sem installed into a fresh prefix (cmake --install), the add-on installed from that prefix's
# share/sem/sem_blender.zip (Preferences > Add-ons > Install), the Python package found
# through the add-on's preference, libsem through the package (tests/blender/test_addon.py).
#   run.sh CMAKE BUILD_DIR PYTHON_DIR MODELS OUT
# PYTHON_DIR: the package's folder relative to the prefix; MODELS: the shared models.
# Skipped (exit 77, CTest's SKIP_RETURN_CODE) only when there is no blender (scripts/setup.sh
# --test installs it) or the shared models are missing. BLENDER_USER_SCRIPTS puts Blender's
# user folder (where an add-on is installed) into OUT, so the user's own is untouched.
set -e
cmake=$1 build=$2 python_dir=$3 models=$4 out=$5
blender=${BLENDER:-$(command -v blender || true)}
if [ -z "$blender" ]; then
  echo "test_blender: SKIPPED: no blender (Debian: apt-get install blender, or scripts/setup.sh --test)"
  exit 77
fi
if [ ! -f "$models/rocket/rocket.iges" ]; then
  echo "test_blender: SKIPPED: $models/rocket/rocket.iges not found (SEM_SHARED_MODELS)"
  exit 77
fi
here=$(cd "$(dirname "$0")" && pwd)
rm -rf "$out"
mkdir -p "$out/user-scripts"
"$cmake" --install "$build" --prefix "$out/prefix" >"$out/install.log"
# libgomp is loaded by Blender before sem can ask for passive waiting (docs/blender.md)
OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive} BLENDER_USER_SCRIPTS="$out/user-scripts" \
  BLENDER_USER_CONFIG="$out/user-config" SEM_LIBRARY= \
  "$blender" -b --factory-startup --python-exit-code 1 --python "$here/test_addon.py" -- \
  --zip "$out/prefix/share/sem/sem_blender.zip" --python-dir "$out/prefix/$python_dir" \
  --sem "$out/prefix/bin/sem" --models "$models" --out "$out/run"
