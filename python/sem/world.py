"""Worlds: a scene's objects stepped in time (sem/scene.h, sem/simulation.h)."""

import ctypes
import json
import os
import warnings

import numpy as np

from . import _lib
from ._lib import SemError, check, encode, lib
from .model import Discretization, Model, _parse_scene, _view

ENERGIES = ("kinetic_energy", "elastic_energy", "gravity_energy", "error_energy")


class _Handle:
    """Owns the C scene and scene world; freed when nothing references it any more (the
    World, or an array view of its state), so a view never outlives its memory."""

    def __init__(self):
        self.scene = None
        self.scene_world = None
        self.log = None  # the ctypes callback must live as long as the world

    def __del__(self):
        if self.scene_world:
            lib.sem_scene_world_destroy(self.scene_world)
            self.scene_world = None
        if self.scene:
            lib.sem_scene_destroy(self.scene)
            self.scene = None


def _default_log(level, message):
    if level >= 1:
        warnings.warn("sem: " + message, stacklevel=3)


class World:
    """The world a scene describes: every object's model (loaded or generated, transformed),
    preprocessed (paper Sec. 5-6) or read from the cache, pinned, loaded, and stepped with the
    scene's integrator (Sec. 7).

        world = sem.World.from_scene("examples/default_beam.json")
        world.step()
        world.q(0)          # object 0's control points, (n, 3), a live read-only view
        world.energies()    # kinetic, elastic, gravity, error energy as in summary.json
    """

    def __init__(self, handle):
        self._h = handle

    @classmethod
    def from_scene(cls, scene=None, *, base_dir=None, cache_dir=None, log=None):
        """scene: a dict with the keys of a scene file (docs/scenes.md), a path to a scene
        file, or None for the embedded default scene. Relative model paths are resolved
        against base_dir (a dict; default: the working directory) or the file's folder.
        cache_dir: folder of cached discretizations (None: no cache). log(level, message):
        progress (level 0) and warnings (level 1); default: warnings become Python warnings."""
        h = _Handle()
        err = _lib.new_error()
        out = _lib._scene_p()
        if scene is None:
            text = lib.sem_scene_default_json()
            check(lib.sem_scene_parse(text, b"default scene", encode(base_dir or "."),
                                      ctypes.byref(out), ctypes.byref(err)), err)
            h.scene = out
        elif isinstance(scene, dict):
            h.scene = _parse_scene(scene, "scene", base_dir or os.getcwd())
        elif isinstance(scene, (str, bytes, os.PathLike)):
            check(lib.sem_scene_load(encode(scene), ctypes.byref(out), ctypes.byref(err)), err)
            h.scene = out
        else:
            raise TypeError("scene: a dict, a path or None, not %s" % type(scene).__name__)

        options = lib.sem_default_scene_world_options()
        if cache_dir is not None:
            os.makedirs(cache_dir, exist_ok=True)
            options.cache_dir = encode(cache_dir)
            options.read_cache = 1
            options.write_cache = 1
        fn = log if log is not None else _default_log
        h.log = _lib.sem_scene_log_fn(
            lambda user, level, message: fn(level, message.decode("utf-8", "replace")))
        options.log = h.log
        sw = _lib._scene_world()
        check(lib.sem_scene_world_create(h.scene, ctypes.byref(options), ctypes.byref(sw),
                                         ctypes.byref(err)), err)
        h.scene_world = sw
        return cls(h)

    def close(self):
        """Drops this World's hold on the C world (freed once no array view refers to it)."""
        self._h = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    @property
    def _world(self):
        if self._h is None:
            raise SemError("the world was closed", "SEM_ERR_INVALID")
        return lib.sem_scene_world_world(self._h.scene_world)

    def _object(self, i):
        n = self.object_count
        if not -n <= i < n:
            raise IndexError("object %d of a world with %d objects" % (i, n))
        return i % n

    # ---- stepping ----
    def step(self, n=1):
        """Advances n time steps of dt. Raises SemError when a step fails (the state is then
        that of the failed step's start, as the library leaves it)."""
        w = self._world
        err = _lib.new_error()
        for _ in range(int(n)):
            check(lib.sem_world_step(w, ctypes.byref(err)), err)
        return self

    def solve_static(self):
        """Static equilibrium of every object (Newton on V - f.q)."""
        err = _lib.new_error()
        check(lib.sem_world_solve_static(self._world, ctypes.byref(err)), err)
        return self

    def run(self, frames=None):
        """Steps `frames` frames (default: the scene's) of steps_per_frame steps and returns
        the frame records of summary.json (rest frame first): a list of frame() dicts."""
        frames = self.frames if frames is None else int(frames)
        records = [self.frame()]
        for _ in range(frames):
            self.step(self.steps_per_frame)
            records.append(self.frame())
        return records

    # ---- the scene's settings ----
    @property
    def time(self):
        return lib.sem_world_time(self._world)

    @property
    def dt(self):
        return self._h.scene.contents.world.dt

    @property
    def frames(self):
        return self._h.scene.contents.frames

    @property
    def steps_per_frame(self):
        return self._h.scene.contents.steps_per_frame

    @property
    def object_count(self):
        return lib.sem_world_object_count(self._world)

    def __len__(self):
        return self.object_count

    # ---- state ----
    def _state_view(self, pointer, i, flat):
        n = lib.sem_world_object_dofs(self._world, i)
        return _view(pointer, (n,) if flat else (n // 3, 3), self._h)

    def q(self, i=0, flat=False):
        """Object i's control points: a read-only (n, 3) view of the library's state (flat x,
        y, z with flat=True) that follows the simulation - no copy; .copy() to keep a frame."""
        i = self._object(i)
        return self._state_view(lib.sem_world_object_q(self._world, i), i, flat)

    def v(self, i=0, flat=False):
        """Object i's control point velocities, as q()."""
        i = self._object(i)
        return self._state_view(lib.sem_world_object_velocity(self._world, i), i, flat)

    def set_state(self, i, q=None, v=None):
        """Sets object i's control points and/or velocities ((n, 3) or 3n values)."""
        i = self._object(i)
        n = lib.sem_world_object_dofs(self._world, i)
        arrays = []
        for name, x in (("q", q), ("v", v)):
            if x is None:
                arrays.append(None)
                continue
            x = np.ascontiguousarray(x, dtype=np.float64).reshape(-1)
            if x.size != n:
                raise ValueError("%s has %d values, object %d has %d dofs" % (name, x.size, i, n))
            arrays.append(x)
        ptr = [None if x is None else x.ctypes.data_as(ctypes.POINTER(ctypes.c_double))
               for x in arrays]
        lib.sem_world_object_set_state(self._world, i, ptr[0], ptr[1])

    # ---- diagnostics ----
    def stats(self, i=0):
        """Object i's volume, mass, energies (J), centre of mass, momenta (as summary.json's
        per-object quantities; elastic_energy is None when undefined, e.g. inverted)."""
        i = self._object(i)
        s = _lib.sem_object_stats()
        lib.sem_world_object_stats(self._world, i, ctypes.byref(s))
        out = {}
        for name, _ in _lib.sem_object_stats._fields_:
            value = getattr(s, name)
            out[name] = np.array(value[:]) if not isinstance(value, float) else value
        if not np.isfinite(out["elastic_energy"]):
            out["elastic_energy"] = None
        return out

    def energies(self):
        """Kinetic, elastic, gravity and error energy summed over objects, as in a frame of
        summary.json."""
        return {k: v for k, v in self.frame().items() if k in ENERGIES}

    def frame(self):
        """The record summary.json keeps per frame: time, the four energies, centre of mass,
        linear and angular momentum, summed over objects."""
        total = {k: 0.0 for k in ENERGIES}
        mass = 0.0
        com = np.zeros(3)
        p = np.zeros(3)
        L = np.zeros(3)
        for i in range(self.object_count):
            s = self.stats(i)
            for k in ENERGIES:
                if total[k] is None or s[k] is None:
                    total[k] = None
                else:
                    total[k] += s[k]
            mass += s["mass"]
            com += s["mass"] * s["center_of_mass"]
            p += s["linear_momentum"]
            L += s["angular_momentum"]
        if mass > 0:
            com /= mass
        record = {"time": self.time}
        record.update(total)
        record.update({"center_of_mass": com, "linear_momentum": p, "angular_momentum": L})
        return record

    def solver(self, i=0):
        return lib.sem_world_solver_name(self._world, self._object(i)).decode()

    def nnz_percent(self, i=0):
        return lib.sem_world_object_nnz_percent(self._world, self._object(i))

    @property
    def last_step_seconds(self):
        return lib.sem_world_last_step_seconds(self._world)

    @property
    def preprocess_seconds(self):
        return lib.sem_scene_world_preprocess_seconds(self._h.scene_world)

    @property
    def preprocess_cached(self):
        return bool(lib.sem_scene_world_all_cached(self._h.scene_world))

    # ---- models ----
    def model(self, i=0):
        """A copy of object i's model at its current control points, in the units of its file
        (model.units), with the numbers `sem run` writes in frame_NNNN.igs: save() it to write
        a frame (world.model(0).save("frame.igs")). world.q(i) is the state, in metres."""
        i = self._object(i)
        err = _lib.new_error()
        out = _lib._model_p()
        check(lib.sem_scene_world_frame_model(self._h.scene_world, i, ctypes.byref(out),
                                              ctypes.byref(err)), err)
        return Model(out)

    def units(self, i=0):
        """The units of object i's file, (name, metres per unit): those of world.model(i) and
        of sem run's frames. Everything else (q, v, stats, the scene) is SI."""
        i = self._object(i)
        sw = self._h.scene_world
        return (lib.sem_scene_world_file_units(sw, i).decode(),
                lib.sem_scene_world_file_unit_to_meter(sw, i))

    def discretization(self, i=0):
        """Object i's discretization (owned by the world; its arrays are views)."""
        i = self._object(i)
        return Discretization(lib.sem_scene_world_discretization(self._h.scene_world, i),
                              owner=self._h)

    def __repr__(self):
        if self._h is None:
            return "<sem.World closed>"
        return "<sem.World %d objects, t = %g>" % (self.object_count, self.time)
