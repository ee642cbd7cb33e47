"""NURBS models and their SEM discretizations (sem/model.h, sem/measure.h, sem/preprocess.h)."""

import ctypes
import json

import numpy as np

from . import _lib
from ._lib import SemError, check, encode, lib


class Model:
    """A NURBS model: parts (rational B-spline surfaces, optionally trimmed).

    Model.load(path) reads IGES (.igs/.iges), OBJ free-form (.obj) or STEP (.step/.stp, when
    sem.has_step()). Control points come out as an (n, 3) array, part by part, u index fastest
    within a part (the order of q in the paper). The model owns its C memory; close() frees it
    early, otherwise it goes with the object.
    """

    def __init__(self, pointer):
        if not pointer:
            raise SemError("no model", "SEM_ERR_INVALID")
        self._ptr = pointer

    # ---- life cycle ----
    @classmethod
    def load(cls, path):
        err = _lib.new_error()
        out = _lib._model_p()
        check(lib.sem_model_load(encode(path), ctypes.byref(out), ctypes.byref(err)), err)
        return cls(out)

    @classmethod
    def primitive(cls, type, **sizes):
        """An exact NURBS solid: primitive("beam", sections=4, length=2) takes the keys of a
        scene's "primitive" object (docs/scenes.md: box, beam, sphere, cylinder, torus)."""
        spec = dict(sizes, type=type)
        scene = _parse_scene({"objects": [{"primitive": spec}]}, "primitive", ".")
        try:
            err = _lib.new_error()
            out = _lib._model_p()
            check(lib.sem_scene_object_model(scene, 0, ctypes.byref(out), ctypes.byref(err)), err)
            return cls(out)
        finally:
            lib.sem_scene_destroy(scene)

    def copy(self):
        return Model(lib.sem_model_clone(self._p))

    def close(self):
        if getattr(self, "_ptr", None):
            lib.sem_model_destroy(self._ptr)
            self._ptr = None

    def __del__(self):
        self.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    @property
    def _p(self):
        if not self._ptr:
            raise SemError("the model was closed", "SEM_ERR_INVALID")
        return self._ptr

    # ---- what it is ----
    @property
    def parts(self):
        """Number of parts (surfaces)."""
        return self._p.contents.n_parts

    def __len__(self):
        return self.parts

    @property
    def control_points(self):
        return int(lib.sem_model_control_points(self._p))

    @property
    def dofs(self):
        """Degrees of freedom q: 3 per control point (the paper's Table 1 column q)."""
        return 3 * self.control_points

    @property
    def units(self):
        """Unit name from the file ("MM", "M", "IN", ...) and its length in metres."""
        m = self._p.contents
        return m.units.decode(), m.unit_to_meter

    @property
    def warnings(self):
        m = self._p.contents
        return [m.warnings[i].decode("utf-8", "replace") for i in range(m.n_warnings)
                if m.warnings[i]]

    def part_info(self, i):
        """name, degrees, control grid, trimmed, holes of part i."""
        if not 0 <= i < self.parts:
            raise IndexError("part %d of a model with %d parts" % (i, self.parts))
        p = self._p.contents.parts[i]
        s = p.surface
        return {"name": p.name.decode("utf-8", "replace"), "degree": (s.degree_u, s.degree_v),
                "control_grid": (s.n_u, s.n_v), "trimmed": bool(p.has_outer or p.n_holes),
                "holes": p.n_holes, "source_entity": p.source_entity,
                "color": tuple(float(c) for c in p.rgb) if p.has_rgb else None}

    def surface(self, i):
        """Part i's NURBS surface: degrees (du, dv), control grid (n_u, n_v), knots_u
        (n_u + du + 1), knots_v, weights (n_v, n_u) (ones when polynomial), the domain
        (u0, u1, v0, v1) and closed / periodic flags, as numpy copies. Its control points are
        q()[part_offsets()[i]:part_offsets()[i + 1]], u index fastest."""
        if not 0 <= i < self.parts:
            raise IndexError("part %d of a model with %d parts" % (i, self.parts))
        s = self._p.contents.parts[i].surface
        n = s.n_u * s.n_v
        weights = (_copy(s.weights, (s.n_v, s.n_u), np.float64) if s.weights
                   else np.ones((s.n_v, s.n_u)))
        return {"degree": (s.degree_u, s.degree_v), "control_grid": (s.n_u, s.n_v),
                "knots_u": _copy(s.knots_u, (s.n_u + s.degree_u + 1,), np.float64),
                "knots_v": _copy(s.knots_v, (s.n_v + s.degree_v + 1,), np.float64),
                "weights": weights, "domain": (s.u0, s.u1, s.v0, s.v1),
                "closed": (bool(s.closed_u), bool(s.closed_v)),
                "periodic": (bool(s.periodic_u), bool(s.periodic_v)), "control_points": n}

    def part_offsets(self):
        """Index of each part's first control point, plus the total (parts + 1 values)."""
        out = (ctypes.c_size_t * (self.parts + 1))()
        lib.sem_model_part_offsets(self._p, out)
        return np.array(out, dtype=np.int64)

    # ---- control points ----
    def q(self):
        """Control points as a new (n, 3) array."""
        q = np.empty((self.control_points, 3))
        lib.sem_model_get_q(self._p, q.ctypes.data_as(ctypes.POINTER(ctypes.c_double)))
        return q

    def set_q(self, q):
        """Moves the control points ((n, 3) or 3n values)."""
        q = np.ascontiguousarray(q, dtype=np.float64).reshape(-1)
        if q.size != self.dofs:
            raise ValueError("q has %d values, the model %d (3 per control point)"
                             % (q.size, self.dofs))
        lib.sem_model_set_q(self._p, q.ctypes.data_as(ctypes.POINTER(ctypes.c_double)))

    # ---- measures and files ----
    def measure(self):
        """Area and bounding box of the (trimmed) surfaces: {"area", "bbox", "part_areas"}."""
        n = max(self.parts, 1)
        per = (_lib.sem_part_measure_result * n)()
        total = _lib.sem_part_measure_result()
        err = _lib.new_error()
        check(lib.sem_model_measure(self._p, per, ctypes.byref(total), ctypes.byref(err)), err)
        return {"area": total.area,
                "bbox": (tuple(total.bbox_min), tuple(total.bbox_max)),
                "part_areas": np.array([per[i].area for i in range(self.parts)])}

    def save(self, path):
        """Writes the model in the format of path's extension (written atomically)."""
        err = _lib.new_error()
        check(lib.sem_model_save(self._p, encode(path), ctypes.byref(err)), err)

    def tessellate(self, resolution=6):
        """Triangle mesh of the (trimmed) parts, resolution x resolution cells per knot span
        (sem/tessellate.h; sem run's frame meshes use output.mesh_resolution, 6): a Tessellation
        whose update(model) gives the positions for moved control points."""
        return Tessellation(self, resolution)

    def preprocess(self, **settings):
        """SEM preprocessing (paper Sec. 5-6) with the keys of a scene's "sem" object:
        order, spacing, rays, ray_axis, points_per_interval, alpha, sparsity, gamma,
        tessellation, weight_threshold, origins ("coupled" or "paper"), fit ("auto", "parts" or
        "origins"), plus youngs_modulus (for the default gamma) and threads."""
        options = lib.sem_default_preprocess_options()
        for key, value in settings.items():
            if key == "rays":
                if len(value) != 2:
                    raise ValueError("rays: two integers [n1, n2]")
                options.rays[0], options.rays[1] = int(value[0]), int(value[1])
            elif key == "ray_axis":
                if value not in ("x", "y", "z", 0, 1, 2):
                    raise ValueError('ray_axis: "x", "y" or "z"')
                options.ray_axis = {"x": 0, "y": 1, "z": 2}.get(value, value)
            elif key == "origins":
                if value not in ("coupled", "paper"):
                    raise ValueError('origins: "coupled" or "paper"')
                options.origin_rule = 0 if value == "coupled" else 1
            elif key == "fit":
                if value not in ("auto", "parts", "origins"):
                    raise ValueError('fit: "auto", "parts" or "origins"')
                options.fit_rule = {"auto": 0, "parts": 1, "origins": 2}[value]
            elif key in ("alpha", "sparsity", "gamma", "spacing") and value is None:
                setattr(options, key, 0.0)
            elif key in _OPTION_FIELDS:
                setattr(options, key, value)
            else:
                raise TypeError("preprocess: unknown setting %r (allowed: %s)"
                                % (key, ", ".join(sorted(_OPTION_FIELDS | {"rays", "ray_axis", "origins", "fit"}))))
        err = _lib.new_error()
        out = _lib._disc_p()
        check(lib.sem_preprocess(self._p, ctypes.byref(options), ctypes.byref(out),
                                 ctypes.byref(err)), err)
        return Discretization(out, owner=None)

    def __repr__(self):
        if not self._ptr:
            return "<sem.Model closed>"
        return "<sem.Model %d parts, %d control points, units %s>" % (
            self.parts, self.control_points, self.units[0])


class Tessellation:
    """A model's triangle mesh (sem/tessellate.h). The topology (triangles, uv, parts) and the
    basis rows are built once; update(model) forms the positions and normals for a model with
    the same parts, knots and weights and new control points (an animation's frames).

    Arrays are numpy copies: positions, normals (n_vertices, 3); uv (n_vertices, 2);
    triangles (n_triangles, 3), counter-clockwise in (u,v); triangle_part (n_triangles,);
    part_vertex_start, part_triangle_start (parts + 1): part i's vertices are
    positions[part_vertex_start[i]:part_vertex_start[i + 1]]."""

    def __init__(self, model, resolution=6):
        resolution = int(resolution)
        if not 1 <= resolution <= 256:
            raise ValueError("resolution: cells per knot span, 1..256 (not %d)" % resolution)
        self._template = None
        self._mesh = _lib.sem_mesh()
        self._has_mesh = False
        err = _lib.new_error()
        template = ctypes.c_void_p()
        check(lib.sem_mesh_template_build(model._p, resolution, ctypes.byref(template),
                                          ctypes.byref(err)), err)
        self._template = template
        check(lib.sem_mesh_template_mesh(template, ctypes.byref(self._mesh), ctypes.byref(err)),
              err)
        self._has_mesh = True
        m = self._mesh
        self.resolution = resolution
        self.parts = m.n_parts
        self.triangles = _copy(m.triangles, (m.n_triangles, 3), np.int32)
        self.triangle_part = _copy(m.triangle_part, (m.n_triangles,), np.int32)
        self.uv = _copy(m.uv, (m.n_vertices, 2), np.float64)
        self.part_vertex_start = _copy(m.part_vertex_start, (m.n_parts + 1,), np.int32)
        self.part_triangle_start = _copy(m.part_triangle_start, (m.n_parts + 1,), np.int32)
        self.update(model)

    def update(self, model):
        """Positions and normals for `model`'s control points (the same parts, knots and
        weights as the model the mesh was built from); returns positions."""
        if model.parts != self.parts:
            raise ValueError("the model has %d parts, the mesh was built for %d"
                             % (model.parts, self.parts))
        err = _lib.new_error()
        check(lib.sem_mesh_update(self._template, model._p, ctypes.byref(self._mesh),
                                  ctypes.byref(err)), err)
        m = self._mesh
        self.positions = _copy(m.positions, (m.n_vertices, 3), np.float64)
        self.normals = _copy(m.normals, (m.n_vertices, 3), np.float64)
        return self.positions

    def close(self):
        if getattr(self, "_has_mesh", False):
            lib.sem_mesh_free(ctypes.byref(self._mesh))
            self._has_mesh = False
        if getattr(self, "_template", None):
            lib.sem_mesh_template_destroy(self._template)
            self._template = None

    def __del__(self):
        self.close()

    def __repr__(self):
        return "<sem.Tessellation %d vertices, %d triangles, %d parts>" % (
            len(self.uv), len(self.triangles), self.parts)


def _copy(pointer, shape, dtype):
    n = int(np.prod(shape))
    if n == 0 or not pointer:
        return np.zeros(shape, dtype=dtype)
    ctype = ctypes.c_double if dtype == np.float64 else ctypes.c_int
    buffer = ctypes.cast(pointer, ctypes.POINTER(ctype * n)).contents
    return np.frombuffer(buffer, dtype=dtype, count=n).reshape(shape).copy()


_OPTION_FIELDS = {"order", "spacing", "points_per_interval", "alpha", "sparsity",
                  "weight_threshold", "gamma", "youngs_modulus", "tessellation", "threads"}


def _view(pointer, shape, owner, dtype=np.float64):
    """A read-only numpy view of C memory that keeps `owner` alive while it exists."""
    n = int(np.prod(shape))
    if n == 0:
        return np.empty(shape, dtype=dtype)
    holder = _Holder(ctypes.addressof(pointer.contents), shape, dtype, owner)
    a = np.asarray(holder)
    a.flags.writeable = False
    return a


class _Holder:
    """Exposes C memory through the array interface; numpy keeps it (and so the owner)."""

    def __init__(self, address, shape, dtype, owner):
        self.owner = owner
        self.__array_interface__ = {"shape": tuple(shape), "typestr": np.dtype(dtype).str,
                                    "data": (address, False), "version": 3}


class Discretization:
    """The SEM discretization of a model (sem/preprocess.h): boundary samples, volume
    quadrature, blending weights, projection Pi and operators. Arrays are read-only views of
    the library's memory (no copy) that stay valid while they are referenced."""

    def __init__(self, pointer, owner):
        self._ptr = pointer
        # the object that owns the C memory (a world's handle), or None: this object does and
        # frees it when the last reference to it (or to one of its views) goes
        self._owner = owner

    def __del__(self):
        if getattr(self, "_ptr", None) and self._owner is None:
            lib.sem_discretization_destroy(self._ptr)
        self._ptr = None

    @property
    def _d(self):
        return self._ptr.contents

    @property
    def order(self):
        return self._d.order

    @property
    def parts(self):
        return self._d.n_parts

    @property
    def dofs(self):
        return 3 * self._d.n_ctrl

    @property
    def volume(self):
        """Volume of the solid from the ray-cast quadrature (model units cubed)."""
        return self._d.volume

    @property
    def alpha(self):
        return self._d.alpha

    @property
    def gamma(self):
        return self._d.gamma

    @property
    def origins(self):
        return self._d.n_origins

    @property
    def fits(self):
        """"parts" (one polynomial per part, the paper) or "origins" (shared fits)."""
        return "origins" if self._d.shared_fit else "parts"

    @property
    def quadrature_points(self):
        """(n_quad, 3) rest positions of the volume quadrature points (a view)."""
        d = self._d
        return _view(d.quad_X, (d.n_quad, 3), self)

    @property
    def quadrature_volumes(self):
        d = self._d
        return _view(d.quad_volume, (d.n_quad,), self)

    @property
    def samples(self):
        """(n_samples, 3) rest positions of the boundary samples (a view)."""
        d = self._d
        return _view(d.sample_X, (d.n_samples, 3), self)

    @property
    def timings(self):
        t = self._d.timings
        return {name: getattr(t, name) for name, _ in _lib.sem_preprocess_timings._fields_}

    def save(self, path):
        err = _lib.new_error()
        check(lib.sem_discretization_save(self._ptr, encode(path), ctypes.byref(err)), err)

    def __repr__(self):
        d = self._d
        return "<sem.Discretization order %d, %d parts, %d dofs, %d quadrature points, volume %g>" % (
            d.order, d.n_parts, 3 * d.n_ctrl, d.n_quad, d.volume)


def _parse_scene(scene, name, base_dir):
    text = json.dumps(scene).encode()
    err = _lib.new_error()
    out = _lib._scene_p()
    check(lib.sem_scene_parse(text, encode(name), encode(base_dir), ctypes.byref(out),
                              ctypes.byref(err)), err)
    return out
