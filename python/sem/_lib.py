"""The shared libsem through ctypes: finding it, the C structs we read, the prototypes.

Design. Only public API (include/sem/*.h) is used. Structs that Python reads or fills are
mirrored here field by field (ctypes.Structure); python/tests/test_abi.py parses the C
headers and fails when a mirror no longer matches its struct, so a change in C cannot
silently shift a field. Every function that can fail takes a sem_error; `check` turns a
failure into SemError with the library's one-line message.

Finding the library, in order: $SEM_LIBRARY (a path); the location recorded at install time
(sem/_install.py, the library installed beside the package); a libsem.so in the package's
own folder; the system's search path (ctypes.util.find_library).
"""

import ctypes
import ctypes.util
import glob
import os
from ctypes import (CFUNCTYPE, POINTER, Structure, c_char, c_char_p, c_double, c_float, c_int,
                    c_longlong, c_size_t, c_ulonglong, c_void_p)


class SemError(RuntimeError):
    """A libsem call failed. str(e) is the library's message; e.status its sem_status name."""

    def __init__(self, message, status="SEM_ERR_INVALID"):
        super().__init__(message)
        self.status = status


# ---------------------------------------------------------------- finding libsem ----

def _candidates():
    env = os.environ.get("SEM_LIBRARY")
    if env:
        return [env], True
    here = os.path.dirname(os.path.abspath(__file__))
    found = []
    try:
        from . import _install  # written by `cmake --install`
        found.append(os.path.normpath(os.path.join(here, _install.LIBRARY_DIR,
                                                   _install.LIBRARY_NAME)))
    except ImportError:
        pass
    found += sorted(glob.glob(os.path.join(here, "libsem.so*")))
    system = ctypes.util.find_library("sem")
    if system:
        found.append(system)
    return found, False


def _loaded_already(name):
    try:
        with open("/proc/self/maps") as f:
            return any(name in line for line in f)
    except OSError:
        return False


openmp_spins = False  # True: libgomp was loaded before sem with its spinning default


def _load():
    # OpenMP's and OpenBLAS's idle threads spin and fight over the cores unless told
    # otherwise (README: Threads); both read these once, when they are first loaded. If
    # another module loaded libgomp first (matplotlib does), it spins: a time step of the
    # default scene then took 0.9 s instead of 0.05 s on 2 busy cores, so say so.
    global openmp_spins
    if "OMP_WAIT_POLICY" not in os.environ and "GOMP_SPINCOUNT" not in os.environ:
        if _loaded_already("libgomp"):
            openmp_spins = True
            import warnings
            warnings.warn("sem: OpenMP (libgomp) was loaded before sem with its default "
                          "spinning threads, which can slow sem's steps many times over on a "
                          "busy machine: import sem first, or set OMP_WAIT_POLICY=passive in "
                          "the environment", RuntimeWarning, stacklevel=3)
        os.environ["OMP_WAIT_POLICY"] = "passive"
    if "OPENBLAS_THREAD_TIMEOUT" not in os.environ and "GOTO_THREAD_TIMEOUT" not in os.environ:
        os.environ["OPENBLAS_THREAD_TIMEOUT"] = "20"
    paths, from_env = _candidates()
    errors = []
    for path in paths:
        if not from_env and os.path.sep in path and not os.path.exists(path):
            continue
        try:
            return ctypes.CDLL(path), path
        except OSError as e:
            errors.append("%s: %s" % (path, e))
    if from_env:
        raise ImportError("sem: cannot load SEM_LIBRARY=%s: %s" % (paths[0], "; ".join(errors)))
    raise ImportError("sem: cannot find the shared library libsem (install sem with "
                      "`cmake --install`, or set SEM_LIBRARY=/path/to/libsem.so)"
                      + (": " + "; ".join(errors) if errors else ""))


lib, library_path = _load()

# ---------------------------------------------------------------- structs ----

_STATUS_NAMES = ["SEM_OK", "SEM_ERR_IO", "SEM_ERR_PARSE", "SEM_ERR_INVALID", "SEM_ERR_NOMEM",
                 "SEM_ERR_NUMERIC", "SEM_ERR_UNSUPPORTED"]


class sem_error(Structure):
    _c_header_ = "status.h"
    _fields_ = [("status", c_int), ("message", c_char * 1024)]


class sem_part_measure_result(Structure):
    _c_header_ = "measure.h"
    _fields_ = [("area", c_double), ("bbox_min", c_double * 3), ("bbox_max", c_double * 3)]


class sem_object_stats(Structure):
    _c_header_ = "simulation.h"
    _fields_ = [("volume", c_double), ("mass", c_double), ("kinetic_energy", c_double),
                ("elastic_energy", c_double), ("gravity_energy", c_double),
                ("error_energy", c_double), ("center_of_mass", c_double * 3),
                ("linear_momentum", c_double * 3), ("angular_momentum", c_double * 3)]


class sem_world_advanced(Structure):
    _c_header_ = "simulation.h"
    _fields_ = [("assembly_chunk", c_int), ("projected_hessian", c_int),
                ("trace_newton", c_int), ("solve_together", c_int), ("q_space_solvers", c_int),
                ("refactorize", c_int)]


class sem_contact_def(Structure):
    _c_header_ = "contact.h"
    _fields_ = [("stiffness", c_double), ("thickness", c_double), ("self", c_int),
                ("disabled", c_int), ("friction_velocity", c_double), ("resolution", c_int),
                ("model", c_int)]


class sem_world_def(Structure):
    _c_header_ = "simulation.h"
    _fields_ = [("gravity", c_double * 3), ("integrator", c_int), ("dt", c_double),
                ("rayleigh_mass", c_double), ("rayleigh_stiffness", c_double),
                ("newton_tolerance", c_double), ("newton_max_iterations", c_int),
                ("solver", c_int), ("threads", c_int), ("accept_unconverged", c_int), ("log", c_void_p),
                ("log_user", c_void_p), ("advanced", sem_world_advanced),
                ("contact", sem_contact_def)]


class sem_curve(Structure):
    _c_header_ = "model.h"
    _fields_ = [("degree", c_int), ("n_ctrl", c_int), ("knots", POINTER(c_double)),
                ("ctrl", POINTER(c_double)), ("weights", POINTER(c_double)),
                ("t0", c_double), ("t1", c_double)]


class sem_surface(Structure):
    _c_header_ = "model.h"
    _fields_ = [("degree_u", c_int), ("degree_v", c_int), ("n_u", c_int), ("n_v", c_int),
                ("knots_u", POINTER(c_double)), ("knots_v", POINTER(c_double)),
                ("ctrl", POINTER(c_double)), ("weights", POINTER(c_double)),
                ("u0", c_double), ("u1", c_double), ("v0", c_double), ("v1", c_double),
                ("closed_u", c_int), ("closed_v", c_int), ("periodic_u", c_int),
                ("periodic_v", c_int)]


class sem_trim_loop(Structure):
    _c_header_ = "model.h"
    _fields_ = [("n_curves", c_int), ("curves", POINTER(sem_curve))]


class sem_part(Structure):
    _c_header_ = "model.h"
    _fields_ = [("name", c_char * 64), ("surface", sem_surface), ("has_outer", c_int),
                ("outer", sem_trim_loop), ("n_holes", c_int), ("holes", POINTER(sem_trim_loop)),
                ("source_entity", c_int), ("color", c_int), ("has_rgb", c_int),
                ("rgb", c_float * 3)]


class sem_model(Structure):
    _c_header_ = "model.h"
    _fields_ = [("n_parts", c_int), ("capacity", c_int), ("parts", POINTER(sem_part)),
                ("units", c_char * 16), ("unit_to_meter", c_double), ("n_warnings", c_int),
                ("warnings", POINTER(c_char_p))]


class sem_preprocess_options(Structure):
    _c_header_ = "preprocess.h"
    _fields_ = [("order", c_int), ("spacing", c_double), ("rays", c_int * 2), ("ray_axis", c_int),
                ("points_per_interval", c_int), ("alpha", c_double), ("sparsity", c_double),
                ("weight_threshold", c_double), ("origin_rule", c_int), ("fit_rule", c_int),
                ("gamma", c_double),
                ("youngs_modulus", c_double), ("tessellation", c_int), ("threads", c_int),
                ("q_space_operators", c_int)]


class sem_preprocess_timings(Structure):
    _c_header_ = "preprocess.h"
    _fields_ = [("sample_s", c_double), ("scene_s", c_double), ("quad_s", c_double),
                ("weights_s", c_double), ("build_pi_s", c_double), ("operators_s", c_double)]


class sem_csr(Structure):
    _c_header_ = "sparse.h"
    _fields_ = [("n_rows", c_int), ("n_cols", c_int), ("row_start", POINTER(c_int)),
                ("col", POINTER(c_int)), ("val", POINTER(c_double))]


class sem_discretization(Structure):
    _c_header_ = "preprocess.h"
    _fields_ = [("order", c_int), ("n_basis", c_int), ("n_parts", c_int), ("n_ctrl", c_int),
                ("part_ctrl_offset", POINTER(c_int)),
                ("n_samples", c_int), ("sample_part", POINTER(c_int)),
                ("sample_uv", POINTER(c_double)), ("sample_X", POINTER(c_double)),
                ("sample_area", POINTER(c_double)), ("sample_seam", POINTER(c_double)),
                ("J_hat", sem_csr),
                ("frame_axes", c_double * 9), ("frame_center", c_double * 3),
                ("frame_lo", c_double * 3), ("frame_hi", c_double * 3),
                ("quad_spacing", c_double), ("n_quad", c_int), ("quad_X", POINTER(c_double)),
                ("quad_volume", POINTER(c_double)), ("quad_part", POINTER(c_int)),
                ("volume", c_double),
                ("alpha", c_double), ("W", sem_csr), ("W_samples", sem_csr),
                ("n_origins", c_int), ("origin_X", POINTER(c_double)),
                ("part_origin", POINTER(c_int)), ("part_covered", POINTER(c_int)),
                ("shared_fit", c_int),
                ("Pi", sem_csr),
                ("Gamma", sem_csr), ("Grad", sem_csr), ("Gamma_samples", sem_csr),
                ("M", sem_csr), ("M_eps", sem_csr), ("gamma", c_double),
                ("length_scale", c_double),
                ("stiffness_nnz_percent", c_double), ("weight_nonzero_fraction", c_double),
                ("timings", sem_preprocess_timings), ("model_hash", c_ulonglong)]


class sem_scene(Structure):
    """The leading fields of sem_scene that Python reads (objects stays opaque)."""
    _c_header_ = "scene.h"
    _fields_ = [("path", c_char * 4096), ("n_objects", c_int), ("objects", c_void_p),
                ("world", sem_world_def), ("frames", c_int), ("steps_per_frame", c_int),
                ("output_dir", c_char * 4096), ("write_iges", c_int), ("write_obj", c_int),
                ("write_mesh", c_int), ("write_usd", c_int), ("write_glb", c_int),
                ("mesh_resolution", c_int), ("n_colliders", c_int), ("colliders", c_void_p)]


sem_scene_log_fn = CFUNCTYPE(None, c_void_p, c_int, c_char_p)


class sem_scene_world_options(Structure):
    _c_header_ = "scene.h"
    _fields_ = [("cache_dir", c_char_p), ("read_cache", c_int), ("write_cache", c_int),
                ("cache_max_bytes", c_longlong), ("log", sem_scene_log_fn),
                ("log_user", c_void_p), ("skip_modes", c_int),
                ("memory_available", c_double)]


class sem_mesh(Structure):
    _c_header_ = "tessellate.h"
    _fields_ = [("n_vertices", c_int), ("n_triangles", c_int), ("positions", POINTER(c_double)),
                ("normals", POINTER(c_double)), ("uv", POINTER(c_double)),
                ("triangles", POINTER(c_int)), ("triangle_part", POINTER(c_int)),
                ("n_parts", c_int), ("part_vertex_start", POINTER(c_int)),
                ("part_triangle_start", POINTER(c_int))]


MIRRORED_STRUCTS = [sem_error, sem_part_measure_result, sem_object_stats, sem_world_advanced,
                    sem_contact_def, sem_world_def,
                    sem_curve, sem_surface, sem_trim_loop, sem_part, sem_model,
                    sem_preprocess_options, sem_preprocess_timings, sem_csr,
                    sem_discretization, sem_scene, sem_scene_world_options, sem_mesh]

# ---------------------------------------------------------------- prototypes ----

_err = POINTER(sem_error)
_model_p = POINTER(sem_model)
_disc_p = POINTER(sem_discretization)
_scene_p = POINTER(sem_scene)
_world = c_void_p          # sem_world * (opaque)
_scene_world = c_void_p    # sem_scene_world * (opaque)

_PROTOTYPES = {
    "sem_version": (c_char_p, []),
    "sem_has_step": (c_int, []),
    "sem_status_name": (c_char_p, [c_int]),
    # models
    "sem_model_load": (c_int, [c_char_p, POINTER(_model_p), _err]),
    "sem_model_save": (c_int, [_model_p, c_char_p, _err]),
    "sem_model_destroy": (None, [_model_p]),
    "sem_model_clone": (_model_p, [_model_p]),
    "sem_model_control_points": (c_size_t, [_model_p]),
    "sem_model_get_q": (None, [_model_p, POINTER(c_double)]),
    "sem_model_set_q": (None, [_model_p, POINTER(c_double)]),
    "sem_model_part_offsets": (None, [_model_p, POINTER(c_size_t)]),
    "sem_model_measure": (c_int, [_model_p, POINTER(sem_part_measure_result),
                                  POINTER(sem_part_measure_result), _err]),
    # triangle meshes (sem/tessellate.h)
    "sem_mesh_template_build": (c_int, [_model_p, c_int, POINTER(c_void_p), _err]),
    "sem_mesh_template_destroy": (None, [c_void_p]),
    "sem_mesh_template_mesh": (c_int, [c_void_p, POINTER(sem_mesh), _err]),
    "sem_mesh_update": (c_int, [c_void_p, _model_p, POINTER(sem_mesh), _err]),
    "sem_mesh_free": (None, [POINTER(sem_mesh)]),
    # preprocessing
    "sem_default_preprocess_options": (sem_preprocess_options, []),
    "sem_preprocess": (c_int, [_model_p, POINTER(sem_preprocess_options), POINTER(_disc_p), _err]),
    "sem_discretization_destroy": (None, [_disc_p]),
    "sem_discretization_save": (c_int, [_disc_p, c_char_p, _err]),
    # scenes
    "sem_scene_parse": (c_int, [c_char_p, c_char_p, c_char_p, POINTER(_scene_p), _err]),
    "sem_scene_load": (c_int, [c_char_p, POINTER(_scene_p), _err]),
    "sem_scene_destroy": (None, [_scene_p]),
    "sem_scene_default_json": (c_char_p, []),
    "sem_scene_object_model": (c_int, [_scene_p, c_int, POINTER(_model_p), _err]),
    "sem_default_scene_world_options": (sem_scene_world_options, []),
    "sem_scene_world_create": (c_int, [_scene_p, POINTER(sem_scene_world_options),
                                       POINTER(_scene_world), _err]),
    "sem_scene_world_destroy": (None, [_scene_world]),
    "sem_scene_world_world": (_world, [_scene_world]),
    "sem_scene_world_object_count": (c_int, [_scene_world]),
    "sem_scene_world_model": (_model_p, [_scene_world, c_int]),
    "sem_scene_world_discretization": (_disc_p, [_scene_world, c_int]),
    "sem_scene_world_frame_model": (c_int, [_scene_world, c_int, POINTER(_model_p), _err]),
    "sem_scene_world_file_units": (c_char_p, [_scene_world, c_int]),
    "sem_scene_world_file_unit_to_meter": (c_double, [_scene_world, c_int]),
    "sem_scene_world_all_cached": (c_int, [_scene_world]),
    "sem_scene_world_preprocess_seconds": (c_double, [_scene_world]),
    # worlds
    "sem_world_step": (c_int, [_world, _err]),
    "sem_world_solve_static": (c_int, [_world, _err]),
    "sem_world_time": (c_double, [_world]),
    "sem_world_object_count": (c_int, [_world]),
    "sem_world_object_dofs": (c_int, [_world, c_int]),
    "sem_world_object_q": (POINTER(c_double), [_world, c_int]),
    "sem_world_object_velocity": (POINTER(c_double), [_world, c_int]),
    "sem_world_object_set_state": (None, [_world, c_int, POINTER(c_double), POINTER(c_double)]),
    "sem_world_object_stats": (None, [_world, c_int, POINTER(sem_object_stats)]),
    "sem_world_last_step_seconds": (c_double, [_world]),
    "sem_world_last_factor_seconds": (c_double, [_world]),
    "sem_world_solver_name": (c_char_p, [_world, c_int]),
    "sem_world_object_nnz_percent": (c_double, [_world, c_int]),
    "sem_world_last_iterations": (c_int, [_world]),
}

for _name, (_restype, _argtypes) in _PROTOTYPES.items():
    _f = getattr(lib, _name)
    _f.restype = _restype
    _f.argtypes = _argtypes


def new_error():
    return sem_error()


def check(status, err):
    """Raises SemError with the library's message when status is not SEM_OK."""
    if status != 0:
        name = _STATUS_NAMES[status] if 0 <= status < len(_STATUS_NAMES) else str(status)
        message = err.message.decode("utf-8", "replace") or name
        raise SemError(message, name)


def encode(path):
    return os.fsencode(path)
