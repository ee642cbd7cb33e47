#!/bin/sh
# CTest's test_blender: the add-on in Debian's blender, headless (tests/blender/test_addon.py).
# Skipped (exit 77, CTest's SKIP_RETURN_CODE) only when there is no blender; scripts/setup.sh
# --test installs it. BLENDER_USER_SCRIPTS points Blender's user folder (where Preferences >
# Add-ons > Install puts the add-on) into the test's output, so the user's own is untouched.
# Arguments: the zip, the sem Python package folder, libsem, the sem command, the shared
# models, the output folder.
blender=${BLENDER:-$(command -v blender)}
if [ -z "$blender" ]; then
  echo "test_blender: SKIPPED: no blender (Debian: apt-get install blender, or scripts/setup.sh --test)"
  exit 77
fi
if [ ! -f "$5/rocket/rocket.iges" ]; then
  echo "test_blender: SKIPPED: $5/rocket/rocket.iges not found (SEM_SHARED_MODELS)"
  exit 77
fi
here=$(dirname "$0")
rm -rf "$6"
mkdir -p "$6/user-scripts"
# libgomp is loaded by Blender before sem can ask for passive waiting (docs/blender.md)
OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive} BLENDER_USER_SCRIPTS="$6/user-scripts" \
  BLENDER_USER_CONFIG="$6/user-config" \
  exec "$blender" -b --factory-startup --python-exit-code 1 --python "$here/test_addon.py" -- \
  --zip "$1" --python-dir "$2" --library "$3" --sem "$4" --models "$5" --out "$6/run"
