"""Run by install_test.cmake with PYTHONPATH at the installed package and SEM_LIBRARY unset:
the package must find the shared library installed beside it, and work."""
import os
import sys

import sem

prefix, version = sys.argv[1], sys.argv[2]
assert "SEM_LIBRARY" not in os.environ
assert sem.version() == version, (sem.version(), version)
path = os.path.realpath(sem.library_path())
assert path.startswith(os.path.realpath(prefix) + os.sep), path
world = sem.World.from_scene({"objects": [{"primitive": {"type": "box"},
                                           "sem": {"order": 1, "rays": [3, 3]}}]})
world.step()
assert world.q(0).shape == (96, 3) and abs(world.time - 0.01) < 1e-12
print("sem", sem.version(), "from", path)
