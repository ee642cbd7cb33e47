"""The simulation: the Blender scene as a sem scene, run in the background, kept as shape keys.

1. build_scene reads the bodies (imported models with Simulate on), colliders and settings
   into the dict of a sem scene file (docs/scenes.md), in metres: each body's model file, its
   empty's placement as "transform", material, friction, initial velocity and pins; each
   collider's evaluated mesh as an OBJ file in world coordinates; the ground plane; gravity,
   integrator, dt, frames, steps per frame. Export Scene writes the same dict, so `sem run`
   on it computes the same numbers (tests/blender checks them to 1e-9).
2. A Simulation runs sem.World.from_scene and the steps in a worker thread: libsem is called
   through ctypes, which releases the GIL, so Blender's interface keeps running. The modal
   operator polls it from a timer (progress in the panel, the status bar and the cursor);
   Esc or Cancel sets a flag the worker reads between steps (preprocessing is one call: a
   cancel during it takes effect when it returns). Frames done when a run is cancelled or
   fails are kept, as sem run keeps them.
3. apply_results stores every frame's control points (world metres, float64) on the body's
   empty (sem_q, for the IGES export) and gives every part one shape key per frame, keyed
   0 -> 1 -> 0 around its frame on the timeline: NURBS parts move their control points,
   mesh parts their vertices (sem's tessellation of the frame, as sem run's frame meshes).
"""

import os
import re
import shutil
import tempfile
import threading
import time

import bpy
import numpy as np

from . import geometry, sem_package
from .importer import metres_per_unit
from .properties import body_parts, body_root

_active = None  # the running Simulation: one at a time


class SetupError(RuntimeError):
    """The scene cannot be simulated as it is; the message says why, in one line."""


def bodies(scene):
    return [o for o in scene.objects if "sem_model_path" in o and o.sem.simulate]


def colliders(scene):
    return [o for o in scene.objects
            if o.sem.collider and body_root(o) is None
            and o.type in ("MESH", "CURVE", "SURFACE", "META", "FONT")]


def typed(value):
    """A setting as the user typed it: Blender keeps properties in single precision (0.01 is
    0.009999999776), so the shortest decimal that is the same float32 (0.01) goes to sem."""
    return float(str(np.float32(value)))


def typed3(values, scale=1.0):
    return [typed(v) * scale for v in values]


def _pin_box(root, settings, s):
    if settings.pin_box_object is not None:
        box = settings.pin_box_object
        corners = np.array([(box.matrix_world @ _vector(c))[:] for c in box.bound_box])
        low, high = corners.min(axis=0), corners.max(axis=0)
        return [[float(x) * s for x in low], [float(x) * s for x in high]]
    low = np.minimum(typed3(settings.pin_box_min), typed3(settings.pin_box_max))
    high = np.maximum(typed3(settings.pin_box_min), typed3(settings.pin_box_max))
    return [[float(x) * s for x in low], [float(x) * s for x in high]]


def _vector(values):
    from mathutils import Vector
    return Vector(values)


def _pin_points(sem, root, settings):
    """The control points behind the vertex group's vertices on the body's mesh parts."""
    group = settings.pin_vertex_group
    model = sem.load(root["sem_model_path"])
    tessellation = None
    part_vertices = {}
    for part in body_parts(root):
        if part.type != "MESH" or group not in part.vertex_groups:
            continue
        index = part.vertex_groups[group].index
        chosen = [v.index for v in part.data.vertices
                  if any(g.group == index and g.weight > 0 for g in v.groups)]
        if not chosen:
            continue
        if tessellation is None:
            tessellation = model.tessellate(int(root.get("sem_mesh_resolution", 6)))
        i = int(part["sem_part"])
        expected = tessellation.part_vertex_start[i + 1] - tessellation.part_vertex_start[i]
        if len(part.data.vertices) != expected:
            raise SetupError("%s: part %s has %d vertices, its import made %d: a vertex group "
                             "pins the imported mesh (re-import the model)" % (
                                 root.name, part.name, len(part.data.vertices), expected))
        part_vertices[i] = chosen
    if not part_vertices:
        raise SetupError("%s: no mesh part has a vertex in the vertex group \"%s\" (NURBS parts "
                         "hold no vertex groups: pin them with a box)" % (root.name, group))
    return geometry.pinned_control_points(model, tessellation, part_vertices)


def _check_parts_placed(root):
    identity = np.eye(4)
    for part in body_parts(root):
        local = np.array(part.matrix_parent_inverse @ part.matrix_basis)
        if not np.allclose(local, identity, rtol=0, atol=1e-6):
            raise SetupError("%s: part %s was moved on its own; sem simulates the model as its "
                             "file has it: move the empty %s instead (or clear the part's "
                             "transform)" % (root.name, part.name, root.name))


def _write_collider(obj, depsgraph, path, s):
    """The object's evaluated mesh, triangulated, in world metres, as an OBJ file."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        mesh.calc_loop_triangles()
        n_v, n_t = len(mesh.vertices), len(mesh.loop_triangles)
        if n_t == 0:
            raise SetupError("collider %s has no faces" % obj.name)
        co = np.empty(3 * n_v, dtype=np.float32)
        mesh.vertices.foreach_get("co", co)
        tri = np.empty(3 * n_t, dtype=np.int32)
        mesh.loop_triangles.foreach_get("vertices", tri)
        m = np.array(obj.matrix_world, dtype=np.float64)
        world = (co.reshape(-1, 3).astype(np.float64) @ m[:3, :3].T + m[:3, 3]) * s
    finally:
        evaluated.to_mesh_clear()
    with open(path, "w") as f:
        f.write("# sem collider %s: Blender's evaluated mesh in world metres\n" % obj.name)
        for x in world:
            f.write("v %r %r %r\n" % (float(x[0]), float(x[1]), float(x[2])))
        for t in tri.reshape(-1, 3) + 1:
            f.write("f %d %d %d\n" % (t[0], t[1], t[2]))


def build_scene(context, sem, collider_dir):
    """(scene dict, bodies): the sem scene of the Blender scene; collider meshes are written
    into collider_dir. Raises SetupError."""
    scene = context.scene
    settings = scene.sem
    s = metres_per_unit(scene)
    context.view_layer.update()  # world matrices of objects moved since the last redraw
    roots = bodies(scene)
    if not roots:
        raise SetupError("nothing to simulate: import a model (File > Import > CAD model through "
                         "sem) and leave its Simulate on")
    objects = []
    for root in roots:
        path = root["sem_model_path"]
        if not os.path.isfile(path):
            raise SetupError("%s: its model file %s is missing" % (root.name, path))
        _check_parts_placed(root)
        b = root.sem
        entry = {"model": path,
                 "material": {"type": b.material, "density": typed(b.density),
                              "youngs_modulus": typed(b.youngs_modulus),
                              "poisson_ratio": typed(b.poisson_ratio)},
                 "friction": typed(b.friction)}
        try:
            transform = geometry.scene_transform(root.matrix_world, s)
        except ValueError as e:
            raise SetupError("%s: %s" % (root.name, e)) from None
        if transform:
            entry["transform"] = transform
        if any(b.initial_velocity):
            entry["initial_velocity"] = typed3(b.initial_velocity, s)
        if b.pin_mode == "BOX":
            entry["pin"] = {"box": _pin_box(root, b, s)}
        elif b.pin_mode == "VERTEX_GROUP":
            entry["pin"] = {"points": _pin_points(sem, root, b)}
        objects.append(entry)
    out = {"objects": objects,
           "gravity": typed3(settings.gravity),
           "integrator": {"type": settings.integrator, "dt": typed(settings.dt)},
           "frames": settings.frames,
           "steps_per_frame": settings.steps_per_frame}
    walls = []
    obstacles = colliders(scene)
    if obstacles:
        os.makedirs(collider_dir, exist_ok=True)
        depsgraph = context.evaluated_depsgraph_get()
        for k, obj in enumerate(obstacles):
            path = os.path.join(collider_dir, "collider_%d.obj" % k)
            _write_collider(obj, depsgraph, path, s)
            walls.append({"model": path, "friction": typed(obj.sem.friction)})
    if settings.ground:
        walls.append({"plane": {"point": [0.0, 0.0, typed(settings.ground_height) * s],
                                "normal": [0.0, 0.0, 1.0]},
                      "friction": typed(settings.ground_friction)})
    if walls:
        out["colliders"] = walls
    return out, roots


class Simulation:
    """One run of a scene in a worker thread; the main thread reads its progress."""

    def __init__(self, sem, scene, roots, cache_dir, work_dir, frame_start):
        self.sem = sem
        self.scene = scene
        self.body_names = [r.name for r in roots]
        self.collider_names = []  # set by start(): collider objects, then "ground"
        self.frames = int(scene["frames"])
        self.steps_per_frame = int(scene["steps_per_frame"])
        self.frame_start = frame_start
        self.cache_dir = cache_dir
        self.work_dir = work_dir
        self.cancel_event = threading.Event()
        self.forgotten = False
        self.phase = "preprocessing"
        self.frames_done = 0
        self.error = None
        self.cancelled = False
        self.done = False
        self.warnings = []
        self.q = []          # per body: one (n, 3) array per frame done, world metres
        self.started = time.monotonic()
        self.seconds = 0.0
        # (what, start, end) of each libsem call the worker makes: "preprocess" (building the
        # world) and "step"; tests/blender checks that Python ran in the main thread inside them
        self.calls = []
        self.thread = threading.Thread(target=self._run, name="sem simulation", daemon=True)

    def start(self):
        self.thread.start()
        return self

    def cancel(self):
        self.cancel_event.set()

    def _log(self, level, message):
        if level >= 1:
            self.warnings.append(message)

    def _run(self):
        try:
            t = time.monotonic()
            world = self.sem.World.from_scene(self.scene, base_dir=self.work_dir,
                                              cache_dir=self.cache_dir, log=self._log)
            self.calls.append(("preprocess", t, time.monotonic()))
            n = world.object_count
            self.q = [[world.q(i).copy()] for i in range(n)]
            self.phase = "simulating"
            for frame in range(1, self.frames + 1):
                for _ in range(self.steps_per_frame):
                    if self.cancel_event.is_set():
                        self.cancelled = True
                        return
                    t = time.monotonic()
                    world.step()
                    self.calls.append(("step", t, time.monotonic()))
                for i in range(n):
                    self.q[i].append(world.q(i).copy())
                self.frames_done = frame
        except self.sem.SemError as e:
            self.error = self.readable(str(e))
        except Exception as e:  # reported in Blender, never lost in the thread
            self.error = "%s: %s" % (type(e).__name__, e)
        finally:
            self.seconds = time.monotonic() - self.started
            self.done = True
            if self.forgotten:  # nobody will read it: another file was opened
                shutil.rmtree(self.work_dir, ignore_errors=True)

    def readable(self, message):
        """sem's message with the scene's keys in Blender's words: "default scene:
        objects[0].pin.box: ..." becomes "rocket: pin.box: ...", colliders[k] the collider's
        object name."""
        def name(match):
            names = self.body_names if match.group(1) == "objects" else self.collider_names
            k = int(match.group(2))
            if k >= len(names):
                return match.group(0)
            return names[k] + (": " if match.group(3) else "")
        return re.sub(r"^(?:[^:\[]*: )?(objects|colliders)\[(\d+)\](\.)?", name, message)

    @property
    def fraction(self):
        return self.frames_done / self.frames if self.frames else 1.0

    def status(self):
        if self.phase == "preprocessing":
            line = "preprocessing (%.0f s)" % (time.monotonic() - self.started)
            return line + (", cancelling when it ends" if self.cancel_event.is_set() else "")
        return "frame %d of %d (%.0f s)%s" % (self.frames_done, self.frames,
                                              time.monotonic() - self.started,
                                              ", cancelling" if self.cancel_event.is_set() else "")


def start(context):
    """Builds the scene and starts a Simulation (the one active). Raises SetupError."""
    global _active
    if _active is not None and not _active.done:
        raise SetupError("a simulation is running already (cancel it first)")
    try:
        sem = sem_package.load_sem(context)
    except RuntimeError as e:
        raise SetupError(str(e)) from None
    work_dir = tempfile.mkdtemp(prefix="sem_blender_")
    try:
        scene, roots = build_scene(context, sem, os.path.join(work_dir, "colliders"))
    except Exception:
        shutil.rmtree(work_dir, ignore_errors=True)
        raise
    cache = sem_package.cache_dir(context) if context.scene.sem.use_cache else None
    run = Simulation(sem, scene, roots, cache, work_dir, context.scene.frame_start)
    run.collider_names = [o.name for o in colliders(context.scene)] + ["ground plane"]
    _active = run.start()
    context.scene.sem.progress = 0.0
    context.scene.sem.status = _active.status()
    return _active


def active():
    """The simulation running now (not yet collected by tick), or None."""
    return _active


def stop_all():
    """Cancels the running simulation and forgets it: its results are not applied (another
    file is being opened, or the add-on is being disabled)."""
    global _active
    if _active is not None:
        _active.forgotten = True
        _active.cancel()
        if _active.done:
            shutil.rmtree(_active.work_dir, ignore_errors=True)
        _active = None


@bpy.app.handlers.persistent
def _on_load(*args):
    stop_all()


def _redraw(context):
    screen = getattr(context, "screen", None)
    if screen is None:
        return
    for area in screen.areas:
        if area.type in ("PROPERTIES", "VIEW_3D", "DOPESHEET_EDITOR", "TIMELINE"):
            area.tag_redraw()


def tick(context):
    """Reads the active simulation's progress into the scene's settings; when it has ended,
    applies what it computed. Returns "RUNNING", "FINISHED", "CANCELLED" or "FAILED" (the
    line why in scene.sem.status)."""
    global _active
    sim = _active
    settings = context.scene.sem
    if sim is None:
        return "FINISHED"
    settings.progress = 100.0 * sim.fraction
    if not sim.done:
        settings.status = sim.status()
        _redraw(context)
        return "RUNNING"
    _active = None
    shutil.rmtree(sim.work_dir, ignore_errors=True)
    kept = sim.frames_done if sim.q else 0
    if kept > 0:
        apply_results(context, sim)
    if sim.error:
        settings.status = "failed: %s%s" % (sim.error, " (%d frames kept)" % kept if kept else "")
        state = "FAILED"
    elif sim.cancelled:
        settings.status = "cancelled after %d of %d frames%s" % (
            kept, sim.frames, " (kept)" if kept else "")
        state = "CANCELLED"
    else:
        settings.status = "%d frames in %.1f s" % (sim.frames, sim.seconds)
        state = "FINISHED"
    if sim.warnings:
        settings.status += "; %d warning%s: %s" % (len(sim.warnings),
                                                   "s" if len(sim.warnings) > 1 else "",
                                                   sim.warnings[0])
    _redraw(context)
    return state


# ------------------------------------------------------------------ results ----

def _clear_shape_keys(obj):
    keys = obj.data.shape_keys
    if keys is not None:
        if keys.animation_data is not None and keys.animation_data.action is not None:
            action = keys.animation_data.action
            keys.animation_data.action = None
            if action.users == 0:
                bpy.data.actions.remove(action)
        obj.shape_key_clear()


def clear_results(root):
    for part in body_parts(root):
        _clear_shape_keys(part)
    for key in ("sem_q", "sem_frame_count", "sem_frame_start", "sem_frame_seconds"):
        if key in root:
            del root[key]


def _key_frames(obj, frames, frame_start):
    """One shape key per frame ("sem 0000" ...), keyed 0 -> 1 -> 0 on the timeline: at frame
    frame_start + k only key k is on. frames: (F, points, 3) local coordinates."""
    _clear_shape_keys(obj)
    obj.shape_key_add(name="Basis", from_mix=False)
    count = len(frames)
    keys = obj.data.shape_keys
    keys.use_relative = True
    action = bpy.data.actions.new("%s sem" % obj.name)
    keys.animation_data_create()
    keys.animation_data.action = action
    for k in range(count):
        name = "sem %04d" % k
        block = obj.shape_key_add(name=name, from_mix=False)
        block.data.foreach_set("co", np.asarray(frames[k], dtype=np.float32).ravel())
        block.slider_max = 1.0
        curve = action.fcurves.new('key_blocks["%s"].value' % name)
        times = [t for t in (k - 1, k, k + 1) if 0 <= t < count]
        curve.keyframe_points.add(len(times))
        co = []
        for t in times:
            co += [frame_start + t, 1.0 if t == k else 0.0]
        curve.keyframe_points.foreach_set("co", co)
        for point in curve.keyframe_points:
            point.interpolation = "LINEAR"
        curve.update()


def apply_results(context, sim):
    """The frames a simulation computed, onto its bodies (see the module's comment)."""
    sem = sim.sem
    s = metres_per_unit(context.scene)
    count = min(len(q) for q in sim.q) if sim.q else 0
    for i, name in enumerate(sim.body_names):
        root = bpy.data.objects.get(name)
        if root is None or i >= len(sim.q):
            continue  # deleted while it ran
        Q = np.stack(sim.q[i][:count])  # (F, n, 3) world metres
        root["sem_q"] = Q.reshape(-1)
        root["sem_frame_count"] = count
        root["sem_frame_start"] = sim.frame_start
        root["sem_frame_seconds"] = sim.scene["integrator"]["dt"] * sim.steps_per_frame
        local = geometry.world_to_local(Q.reshape(-1, 3), root.matrix_world, s).reshape(Q.shape)
        model = sem.load(root["sem_model_path"])
        offsets = model.part_offsets()
        parts = body_parts(root)
        meshes = [p for p in parts if p.get("sem_kind") == "MESH"]
        positions = None
        if meshes:
            tessellation = model.tessellate(int(root.get("sem_mesh_resolution", 6)))
            positions = []
            for k in range(count):
                model.set_q(local[k])
                positions.append(tessellation.update(model))
            positions = np.stack(positions)
            start = tessellation.part_vertex_start
        for part in parts:
            j = int(part["sem_part"])
            if part.get("sem_kind") == "MESH":
                frames = positions[:, start[j]:start[j + 1]]
            else:
                frames = local[:, offsets[j]:offsets[j + 1]]
            _key_frames(part, frames, sim.frame_start)
    scene = context.scene
    if scene.frame_end < sim.frame_start + count - 1:
        scene.frame_end = sim.frame_start + count - 1


def stored_frames(root):
    """(F, n, 3) world metres of a simulated body, or None."""
    if "sem_q" not in root:
        return None
    count = int(root["sem_frame_count"])
    q = np.asarray(root["sem_q"], dtype=np.float64)
    return q.reshape(count, -1, 3)


# ---------------------------------------------------------------- operators ----

class SEM_OT_simulate(bpy.types.Operator):
    """Simulate the scene's sem bodies in the background (Esc or Cancel stops it): every part
    gets one shape key per frame"""
    bl_idname = "sem.simulate"
    bl_label = "Simulate"

    _timer = None

    @classmethod
    def poll(cls, context):
        return _active is None

    def invoke(self, context, event):
        try:
            start(context)
        except SetupError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.2, window=context.window)
        wm.modal_handler_add(self)
        wm.progress_begin(0, 100)
        context.workspace.status_text_set("sem: " + context.scene.sem.status + " (Esc: cancel)")
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS" and _active is not None:
            _active.cancel()
            return {"RUNNING_MODAL"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        state = tick(context)
        wm = context.window_manager
        if state == "RUNNING":
            wm.progress_update(int(context.scene.sem.progress))
            context.workspace.status_text_set("sem: " + context.scene.sem.status + " (Esc: cancel)")
            return {"PASS_THROUGH"}
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)
        level = {"FINISHED": "INFO", "CANCELLED": "WARNING", "FAILED": "ERROR"}[state]
        self.report({level}, "sem: " + context.scene.sem.status)
        return {"FINISHED"} if state == "FINISHED" else {"CANCELLED"}

    def execute(self, context):
        """Without a window (blender -b, scripts): the same worker thread, waited for."""
        try:
            start(context)
        except SetupError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        state = "RUNNING"
        while state == "RUNNING":
            time.sleep(0.05)
            state = tick(context)
        level = {"FINISHED": "INFO", "CANCELLED": "WARNING", "FAILED": "ERROR"}[state]
        self.report({level}, "sem: " + context.scene.sem.status)
        return {"FINISHED"} if state == "FINISHED" else {"CANCELLED"}


class SEM_OT_cancel(bpy.types.Operator):
    """Stop the running simulation (the frames done so far are kept)"""
    bl_idname = "sem.cancel"
    bl_label = "Cancel"

    @classmethod
    def poll(cls, context):
        return _active is not None

    def execute(self, context):
        _active.cancel()
        return {"FINISHED"}


class SEM_OT_clear(bpy.types.Operator):
    """Remove the simulated frames (shape keys and stored control points) of every body"""
    bl_idname = "sem.clear"
    bl_label = "Clear Results"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _active is None

    def execute(self, context):
        n = 0
        for root in [o for o in context.scene.objects if "sem_model_path" in o]:
            if "sem_q" in root:
                n += 1
            clear_results(root)
        self.report({"INFO"}, "sem: cleared the frames of %d bodies" % n)
        return {"FINISHED"}


CLASSES = (SEM_OT_simulate, SEM_OT_cancel, SEM_OT_clear)


def register():
    bpy.app.handlers.load_pre.append(_on_load)


def unregister():
    stop_all()
    if _on_load in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(_on_load)
