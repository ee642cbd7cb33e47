"""Finding the sem Python package (and through it libsem) from Blender.

Blender runs its own interpreter and ignores PYTHONPATH (unless started with
--python-use-system-env). Debian's blender uses the system's Python 3, whose search path
holds /usr/local/lib/python3.N/dist-packages: sem installed with the default prefix
(`cmake --install build`) is found as it is. For another prefix, the add-on's preferences take
the folder that holds the package (P/lib/python3.N/dist-packages) and, optionally, the
library itself (SEM_LIBRARY, when it is not installed beside the package).
"""

import importlib
import os
import sys

import bpy
from bpy.props import StringProperty

ADDON = __package__


def preferences(context=None):
    context = context or bpy.context
    addon = context.preferences.addons.get(ADDON)
    return addon.preferences if addon else None


def load_sem(context=None):
    """The sem module. Raises RuntimeError with one line saying what to do when it cannot be
    imported."""
    prefs = preferences(context)
    folder = bpy.path.abspath(prefs.python_path) if prefs and prefs.python_path else ""
    library = bpy.path.abspath(prefs.library_path) if prefs and prefs.library_path else ""
    if library:
        if not os.path.isfile(library):
            raise RuntimeError("sem: the library set in the add-on's preferences does not exist: "
                               + library)
        os.environ["SEM_LIBRARY"] = library
    if folder:
        if not os.path.isdir(os.path.join(folder, "sem")):
            raise RuntimeError("sem: %s has no sem package (the add-on's preferences want the folder "
                               "that holds it: PREFIX/lib/python3.N/dist-packages)" % folder)
        if folder not in sys.path:
            sys.path.insert(0, folder)
        loaded = sys.modules.get("sem")
        if loaded is not None and not os.path.abspath(loaded.__file__).startswith(
                os.path.abspath(folder) + os.sep):
            raise RuntimeError("sem: another sem package is loaded already (%s); restart Blender "
                               "to use the one in %s" % (os.path.dirname(loaded.__file__), folder))
    try:
        return importlib.import_module("sem")
    except ImportError as e:
        raise RuntimeError("sem: the sem Python package cannot be imported (%s). Install sem "
                           "(cmake --install build: with the default prefix Blender finds it) or "
                           "set its folder in Edit > Preferences > Add-ons > sem" % e) from None


def status(context=None):
    """One line for the preferences: the sem in use, or why there is none."""
    try:
        sem = load_sem(context)
    except RuntimeError as e:
        return False, str(e)
    line = "sem %s, libsem %s, Python package %s" % (
        sem.version(), sem.library_path(), os.path.dirname(sem.__file__))
    if _openmp_spins():
        line += ("; Blender loaded OpenMP with spinning threads first: start it with "
                 "OMP_WAIT_POLICY=passive for faster steps on a busy machine")
    return True, line


def _openmp_spins():
    """True when Blender's own libgomp was loaded without a waiting policy from the
    environment (sem's package asks for passive waiting only for a libgomp it loads)."""
    return getattr(sys.modules.get("sem._lib"), "openmp_spins", False)


class SemAddonPreferences(bpy.types.AddonPreferences):
    bl_idname = ADDON

    python_path: StringProperty(
        name="sem Python package folder", subtype="DIR_PATH", default="",
        description="Folder holding the sem package when sem is not installed in /usr/local: "
                    "PREFIX/lib/python3.N/dist-packages (empty: Blender's search path)")
    library_path: StringProperty(
        name="libsem", subtype="FILE_PATH", default="",
        description="The shared library (libsem.so) when it is not installed beside the package "
                    "(empty: the one the package finds)")
    cache_dir: StringProperty(
        name="Preprocessing cache", subtype="DIR_PATH", default="",
        description="Folder where preprocessing results are kept, shared with sem run (empty: "
                    "$SEM_CACHE_DIR, else $XDG_CACHE_HOME/sem, else ~/.cache/sem)")

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "python_path")
        layout.prop(self, "library_path")
        layout.prop(self, "cache_dir")
        ok, line = status(context)
        row = layout.row()
        row.alert = not ok
        row.label(text=line, icon="CHECKMARK" if ok else "ERROR")


def cache_dir(context=None):
    prefs = preferences(context)
    if prefs and prefs.cache_dir:
        return bpy.path.abspath(prefs.cache_dir)
    # the command line's rule (sem run --help)
    if os.environ.get("SEM_CACHE_DIR"):
        return os.environ["SEM_CACHE_DIR"]
    if os.environ.get("XDG_CACHE_HOME"):
        return os.path.join(os.environ["XDG_CACHE_HOME"], "sem")
    return os.path.join(os.environ.get("HOME") or "/tmp", ".cache", "sem")
