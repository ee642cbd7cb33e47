"""sem: the Shape Matching Element Method (Trusty, Chen, Levin, ACM TOG 2021) from Python.

A ctypes binding of the shared library libsem. Load NURBS CAD models, preprocess them, build
a world from a scene (a dict with the keys of a scene file, or a path), step it, and read the
control points, velocities and energies as numpy arrays:

    import sem
    world = sem.World.from_scene({"objects": [{"primitive": {"type": "beam", "sections": 2},
                                               "pin": {"box": [[-0.01, -1, -1], [0.01, 2, 2]]}}],
                                  "integrator": {"type": "implicit_euler", "dt": 0.01}})
    for _ in range(10):
        world.step()
    world.q(0)          # (n, 3) control points of object 0, a live view (no copy)
    world.energies()    # {"kinetic_energy": ..., "elastic_energy": ..., ...}

Errors raise sem.SemError with the library's message. The library is found beside the
installed package, or through $SEM_LIBRARY (docs/library.md).
"""

import sys as _sys

try:
    import numpy as _numpy  # noqa: F401  (every array the package returns is numpy's)
except ImportError as _e:  # a virtual environment or pyenv without Debian's python3-numpy
    raise ImportError("numpy is needed: apt-get install python3-numpy (or pip install numpy) "
                      "(%s: %s)" % (_sys.executable, _e)) from None

from ._lib import SemError, library_path as _library_path, lib as _clib
from .model import Discretization, Model, Tessellation
from .world import ENERGIES, World

__all__ = ["SemError", "Model", "Discretization", "Tessellation", "World", "ENERGIES", "version",
           "has_step", "library_path", "load"]


def version():
    """Version of the libsem in use ("MAJOR.MINOR.PATCH")."""
    return _clib.sem_version().decode()


def has_step():
    """True when libsem reads and writes STEP files (built with Open CASCADE)."""
    return bool(_clib.sem_has_step())


def library_path():
    """The shared library this package loaded."""
    return _library_path


def load(path):
    """Model.load(path): a NURBS model from an IGES, OBJ free-form or STEP file."""
    return Model.load(path)


__version__ = version()
