"""The Blender add-on, headless, in Debian's blender (run by tests/blender/run.sh as CTest's
test_blender):

  blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_addon.py -- \
      --zip P/share/sem/sem_blender.zip --python-dir P/lib/python3.N/dist-packages \
      --sem P/bin/sem --models ../shared/models --out build/blender-test/run

1. The installed zip installs and enables as a user would (Preferences > Add-ons > Install);
   with the installed package's folder in the add-on's preferences, the package loads the
   libsem installed beside it.
2. rocket.iges (13 parts, millimetres) imports as 13 NURBS surfaces named and coloured as in
   the file, at its real size; Blender's evaluation of each surface is sem's surface. The same
   model written by sem as STEP and OBJ free-form imports with its 13 parts.
3. Pinned at its base (a box), bent by sideways gravity over a ground plane and beside a
   mesh collider, 10 frames are simulated in the worker thread, polled as the modal operator
   polls it, while the panels are drawn. The scene the add-on ran is exported and run by
   `sem run`: the add-on's frames (kept as float64) equal sem run's frame_NNNN.igs to 1e-9
   relative, and the animated control points Blender shows at each frame equal them to
   float32 precision.
4. The same model imported as meshes, pinned by a vertex group, simulated by the operator
   (bpy.ops.sem.simulate): frames equal sem run's to 1e-9, Blender's evaluated vertices are
   sem's tessellation of sem run's frames to float32 precision; the IGES export equals sem
   run's frames.
5. Cancel keeps the frames done; bad settings are one-line errors; every panel draws (a
   recording layout checks each property and operator it names) in every state.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import time

import bpy
import numpy as np

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
parser = argparse.ArgumentParser()
for name in ("--zip", "--python-dir", "--sem", "--models", "--out"):
    parser.add_argument(name, required=True)
parser.add_argument("--library", default="")
args = parser.parse_args(argv)
OUT = os.path.abspath(args.out)
shutil.rmtree(OUT, ignore_errors=True)
os.makedirs(OUT)
os.environ["SEM_CACHE_DIR"] = os.path.join(OUT, "cache")  # the add-on's and sem run's
ROCKET = os.path.join(args.models, "rocket", "rocket.iges")
RELATIVE = 1e-9
results = []


def check(condition, message):
    if not condition:
        raise AssertionError(message)


def note(line):
    results.append(line)
    print("test_blender: " + line, flush=True)


# ------------------------------------------------------------ 1. install, enable ----
bpy.ops.preferences.addon_install(filepath=os.path.abspath(args.zip), overwrite=True)
bpy.ops.preferences.addon_enable(module="sem_blender")
check("sem_blender" in bpy.context.preferences.addons, "the add-on is not enabled")
import sem_blender  # noqa: E402  (installed by the line above)
from sem_blender import export, geometry, panels, sem_package, simulation  # noqa: E402

check(os.path.realpath(sem_blender.__file__).startswith(
    os.path.realpath(os.environ.get("BLENDER_USER_SCRIPTS", "/nonexistent"))),
    "the add-on was not loaded from the installed zip: %s" % sem_blender.__file__)
prefs = sem_package.preferences()
prefs.python_path = os.path.abspath(args.python_dir)
prefs.library_path = os.path.abspath(args.library) if args.library else ""
ok, line = sem_package.status()
check(ok, line)
sem = sem_package.load_sem()
if not args.library:
    prefix = os.path.dirname(os.path.dirname(os.path.abspath(args.sem)))
    check(os.path.realpath(sem.library_path()).startswith(os.path.realpath(prefix) + os.sep),
          "the package loaded %s, not the libsem installed in %s" % (sem.library_path(), prefix))
note("installed from %s; %s" % (os.path.basename(args.zip), line))
context = bpy.context
scene = context.scene


# ------------------------------------------------------------ panels, recorded ----
class Layout:
    """Stands for bpy.types.UILayout: records what a panel draws and checks that every
    property exists on its data and every operator and icon exists."""
    icons = set(bpy.types.UILayout.bl_rna.functions["label"].parameters["icon"].enum_items.keys())

    def __init__(self, log):
        self.log = log

    def _icon(self, kw):
        check(kw.get("icon", "NONE") in self.icons, "unknown icon %r" % kw.get("icon"))

    def _child(self, *a, **kw):
        return Layout(self.log)

    row = column = box = split = column_flow = grid_flow = _child

    def label(self, text="", **kw):
        self._icon(kw)
        self.log.append("label: " + text)

    def prop(self, data, name, **kw):
        self._icon(kw)
        check(name in data.bl_rna.properties.keys(), "%s has no property %s" % (data, name))
        self.log.append("prop: " + name)

    def operator(self, idname, **kw):
        self._icon(kw)
        module, name = idname.split(".")
        op = getattr(getattr(bpy.ops, module), name)
        op.get_rna_type()  # raises for an operator that does not exist
        self.log.append("operator: " + idname)
        return type("Properties", (), {})()

    def separator(self, **kw):
        pass


def draw_panels(state):
    drawn = []
    for cls in panels.CLASSES:
        if hasattr(cls, "poll") and not cls.poll(context):
            continue
        stub = type("Panel", (), {})()
        stub.layout = Layout([])
        cls.draw(stub, context)
        check(stub.layout.log, "%s drew nothing" % cls.__name__)
        drawn.append((cls.__name__, stub.layout.log))
    return drawn


def panel_text(drawn):
    return "\n".join(line for _, log in drawn for line in log)


draw_panels("empty scene")

def draw_preferences():
    stub = type("P", (), {})()
    stub.layout = Layout([])
    for name in ("python_path", "library_path", "cache_dir", "bl_rna"):
        setattr(stub, name, getattr(prefs, name))
    sem_package.SemAddonPreferences.draw(stub, context)
    return stub.layout.log


check(any(line.startswith("label: sem %s" % sem.version()) for line in draw_preferences()),
      "the preferences do not show the sem in use")


# ------------------------------------------------------------ 2. import as NURBS ----
def import_rocket(surfaces, path=ROCKET):
    before = set(bpy.data.objects)
    check(bpy.ops.import_scene.sem_model(filepath=path, surfaces=surfaces) == {"FINISHED"},
          "import failed")
    new = set(bpy.data.objects) - before
    roots = [o for o in new if "sem_model_path" in o]
    check(len(roots) == 1, "one body empty per import")
    return roots[0]


def blender_points(obj):
    """Control points (NURBS) or vertices (mesh) of an object's data, as stored."""
    if obj.type == "MESH":
        co = np.empty(3 * len(obj.data.vertices), dtype=np.float32)
        obj.data.vertices.foreach_get("co", co)
        return co.reshape(-1, 3).astype(np.float64)
    points = obj.data.splines[0].points
    co = np.empty(4 * len(points), dtype=np.float32)
    points.foreach_get("co", co)
    return co.reshape(-1, 4)[:, :3].astype(np.float64)


model = sem.load(ROCKET)
offsets = model.part_offsets()
rest = model.q() * 0.001  # metres, = Blender units at unit scale 1
size = float(np.linalg.norm(rest.max(axis=0) - rest.min(axis=0)))
root = import_rocket("NURBS")
parts = sorted([c for c in root.children], key=lambda c: c["sem_part"])
check(len(parts) == 13 and all(p.type == "SURFACE" and p["sem_kind"] == "NURBS" for p in parts),
      "rocket: %s" % [(p.name, p.type) for p in parts])
check(root["sem_units"] == "MM" and root["sem_unit_to_meter"] == 0.001, "units")
check([p.name.split(".")[0] for p in parts] == [model.part_info(i)["name"] for i in range(13)],
      "part names %s" % [p.name for p in parts])
steel = parts[0].data.materials[0].diffuse_color
check(abs(steel[0] - 0.627451) < 1e-6 and steel[0] == steel[1] == steel[2],
      "rocket's Steel colour: %s" % list(steel))
worst = 0.0
for i, p in enumerate(parts):
    worst = max(worst, np.abs(blender_points(p) - rest[offsets[i]:offsets[i + 1]]).max())
check(worst <= 1e-7 * size, "control points off by %g m" % worst)
# Blender's own evaluation of each surface (Endpoint knots, its orders) is sem's surface:
# its tessellation at Blender's uniform parameters against the NURBS of the file's knots
depsgraph = context.evaluated_depsgraph_get()
worst_surface = 0.0
for i, p in enumerate(parts):
    surface = model.surface(i)
    spline = p.data.splines[0]
    evaluated = p.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    co = np.array([v.co[:] for v in mesh.vertices])
    evaluated.to_mesh_clear()
    n_u = spline.point_count_u * spline.resolution_u
    n_v = spline.point_count_v * spline.resolution_v
    u0, u1, v0, v1 = surface["domain"]
    us = np.linspace(u0, u1, n_u)
    vs = np.linspace(v0, v1, n_v)
    expected = np.array([geometry.surface_point(surface, rest[offsets[i]:offsets[i + 1]], u, v)
                         for u in us for v in vs])
    check(len(co) == len(expected), "%s: Blender made %d surface points, expected %d x %d" % (
        p.name, len(co), n_u, n_v))
    worst_surface = max(worst_surface, np.abs(co - expected).max())
check(worst_surface <= 1e-6 * size, "Blender's surfaces differ from sem's by %g m" % worst_surface)
# the numpy evaluation itself is sem's: against sem's tessellation at its (u, v)
tessellation = model.tessellate(3)
worst_eval = 0.0
for i in range(13):
    a, b = tessellation.part_vertex_start[i:i + 2]
    surface = model.surface(i)
    for k in range(a, b, 7):
        x = geometry.surface_point(surface, model.q()[offsets[i]:offsets[i + 1]], *tessellation.uv[k])
        worst_eval = max(worst_eval, np.abs(x - tessellation.positions[k]).max())
check(worst_eval <= 1e-12 * size * 1000, "numpy NURBS evaluation off sem's by %g" % worst_eval)
note("import: rocket.iges as 13 NURBS surfaces, names and Steel colour of the file; control "
     "points %.1e m, Blender's surface evaluation %.1e m from sem's (model %.3f m)"
     % (worst, worst_surface, size))

# the same model written by sem as STEP (when sem has Open CASCADE) and OBJ free-form
formats = []
for ext in ("step", "obj"):
    if ext == "step" and not sem.has_step():
        continue
    path = os.path.join(OUT, "rocket." + ext)
    subprocess.run([args.sem, "convert", ROCKET, path], check=True)
    other = import_rocket("NURBS", path)
    other_parts = sorted(other.children, key=lambda c: c["sem_part"])
    check(len(other_parts) == 13 and other["sem_units"] == "MM", "%s: %d parts, %s" % (
        ext, len(other_parts), other["sem_units"]))
    kinds = sorted(p["sem_kind"] for p in other_parts)
    # the surfaces Blender shows span the model's bounding box (Open CASCADE may choose other
    # control points for the same surface, so the shapes are compared, to Blender's sampling)
    depsgraph = context.evaluated_depsgraph_get()
    shown = []
    for p in other_parts:
        evaluated = p.evaluated_get(depsgraph)
        mesh = evaluated.to_mesh()
        shown.append(np.array([v.co[:] for v in mesh.vertices]))
        evaluated.to_mesh_clear()
    shown = np.concatenate(shown)
    low, high = shown.min(axis=0), shown.max(axis=0)
    box = model.measure()["bbox"]
    off = max(np.abs(low - np.array(box[0]) * 0.001).max(), np.abs(high - np.array(box[1]) * 0.001).max())
    check(off < 1e-3 * size, "%s: the surfaces span %s .. %s, the model %s" % (ext, low, high, box))
    formats.append("%s (%d NURBS, %d meshes)" % (ext.upper(), kinds.count("NURBS"),
                                                 kinds.count("MESH")))
    for obj in [other] + other_parts:
        bpy.data.objects.remove(obj)
note("the same model from sem's %s: 13 parts each, spanning its bounding box"
     % " and ".join(formats))
context.view_layer.objects.active = root

# ------------------------------------------------------------ 3. simulate (threaded) ----
s = scene.sem
s.frames = 10
s.dt = 0.01
s.integrator = "implicit_euler"
s.gravity = (0.0, -9.81, 0.0)
s.ground = True
s.ground_height = -0.001
b = root.sem
b.material = "neohookean"
b.density = 1000.0
b.youngs_modulus = 1e5
b.poisson_ratio = 0.45
b.pin_mode = "BOX"
b.pin_box_min = (-1.0, -1.0, -1.0)
b.pin_box_max = (1.0, 1.0, 0.01)
bpy.ops.mesh.primitive_cube_add(size=0.02, location=(0.0, -0.05, 0.05))
obstacle = context.object
obstacle.name = "obstacle"
obstacle.sem.collider = True
check(draw_panels("collider") and any(c == "SEM_PT_collider" for c, _ in draw_panels("collider")),
      "the collider panel is not drawn for a mesh")
context.view_layer.objects.active = parts[3]
drawn = draw_panels("part")
check(any(c == "SEM_PT_body" for c, _ in drawn) and "Part 3" in panel_text(drawn),
      "the body panel does not show for a part")
context.view_layer.objects.active = root

scene_a = export.export_scene(context, os.path.join(OUT, "a", "scene.json"))
# settings as typed, though Blender holds them in float32
check(scene_a["objects"][0]["pin"]["box"] == [[-1, -1, -1], [1, 1, 0.01]]
      and scene_a["integrator"]["dt"] == 0.01 and scene_a["gravity"] == [0, -9.81, 0]
      and scene_a["objects"][0]["material"]["poisson_ratio"] == 0.45,
      "settings %s" % scene_a)
check(len(scene_a["colliders"]) == 2 and "plane" in scene_a["colliders"][1], "colliders")

run = simulation.start(context)
states, running_panels, beats = [], None, []
while True:
    state = simulation.tick(context)  # what the modal operator does on each timer event
    states.append(state)
    beats.append(time.monotonic())
    if state == "RUNNING" and running_panels is None and run.phase == "simulating":
        running_panels = panel_text(draw_panels("running"))
    if state != "RUNNING":
        break
    time.sleep(0.005)
check(state == "FINISHED", "simulation: %s (%s)" % (state, s.status))
# the interface is not frozen: the main thread ran Python (this loop) inside the worker's
# libsem calls, which it could not if they held the GIL
long_calls = [(what, a, b) for what, a, b in run.calls if b - a > 0.05]
inside = [any(a < t < b for t in beats) for _, a, b in long_calls]
check(long_calls and sum(inside) >= 0.8 * len(long_calls),
      "the main thread ran during %d of %d libsem calls longer than 50 ms"
      % (sum(inside), len(long_calls)))
check(running_panels is not None and "operator: sem.cancel" in running_panels
      and "prop: progress" in running_panels, "the running panel has no progress and cancel")
check(states.count("RUNNING") >= 2, "the worker thread was not polled")
note("simulated 10 frames in the worker thread in %.1f s, polled %d times, the main thread "
     "running inside %d of the %d libsem calls over 50 ms (%s): %s"
     % (run.seconds, states.count("RUNNING"), sum(inside), len(long_calls),
        ", ".join("%s %.2f s" % (w, b - a) for w, a, b in long_calls[:3]) + ", ...", s.status))


def sem_run(folder):
    env = dict(os.environ, OMP_NUM_THREADS=os.environ.get("OMP_NUM_THREADS", "2"))
    subprocess.run([args.sem, "run", os.path.join(folder, "scene.json"), "--out",
                    os.path.join(folder, "out"), "--quiet"], check=True, env=env)
    frames = []
    for k in range(11):
        frames.append(sem.load(os.path.join(folder, "out", "frame_%04d.igs" % k)))
    return frames


def compare_frames(root, frames, label):
    Q = simulation.stored_frames(root)
    check(Q.shape == (11, model.control_points, 3), "%s: stored frames %s" % (label, Q.shape))
    worst = 0.0
    for k, frame in enumerate(frames):
        check(frame.units == ("MM", 0.001), "sem run's frames are in the file's units")
        mine = Q[k] * (1.0 / 0.001)
        theirs = frame.q()
        worst = max(worst, np.abs(mine - theirs).max() / np.abs(theirs).max())
    moved = np.abs(Q[10] - Q[0]).max()
    # (the mesh run, its base's control points pinned, moves 8.7e-5 m with seam ties: its fins
    # held to the body)
    check(moved > 2e-5, "%s: the model barely moved (%g m)" % (label, moved))
    check(worst <= RELATIVE, "%s: the add-on's frames differ from sem run's by %.3g relative"
          % (label, worst))
    return worst, moved


frames_a = sem_run(os.path.join(OUT, "a"))
worst_a, moved_a = compare_frames(root, frames_a, "NURBS run")

# what Blender shows at each frame: shape keys keyed on the timeline
worst_shown = 0.0
for k in range(11):
    scene.frame_set(scene.frame_start + k)
    expected = frames_a[k].q() * 0.001
    for i, p in enumerate(parts):
        keys = p.data.shape_keys.key_blocks
        check(len(keys) == 12, "%s: %d shape keys, want Basis + 11" % (p.name, len(keys)))
        basis = np.array([d.co[:] for d in keys[0].data])
        shown = basis.copy()
        for block in keys[1:]:
            if block.value:
                shown += block.value * (np.array([d.co[:] for d in block.data]) - basis)
        on = [block.name for block in keys[1:] if block.value]
        check(on == ["sem %04d" % k], "frame %d: keys on %s" % (k, on))
        worst_shown = max(worst_shown, np.abs(shown - expected[offsets[i]:offsets[i + 1]]).max())
check(worst_shown <= 1e-6 * size, "animated control points %g m from sem run's" % worst_shown)
note("NURBS, box pin, ground + mesh collider: frames = sem run's to %.2e relative (1e-9 "
     "allowed), moved %.2f mm; animated control points %.1e m from them (float32)"
     % (worst_a, 1000 * moved_a, worst_shown))

# ------------------------------------------------------------ 4. meshes, vertex group ----
root.sem.simulate = False
root_b = import_rocket("MESH")
parts_b = sorted(root_b.children, key=lambda c: c["sem_part"])
check(all(p.type == "MESH" for p in parts_b), "MESH import")
held = 0
for p in parts_b:
    group = p.vertex_groups.new(name="pin")
    low = [v.index for v in p.data.vertices if v.co.z < 0.01]
    if low:
        group.add(low, 1.0, "REPLACE")
        held += len(low)
b = root_b.sem
b.youngs_modulus = 1e5
b.pin_mode = "VERTEX_GROUP"
context.view_layer.objects.active = root_b
check("on " in panel_text(draw_panels("vertex group")), "the vertex group line")
scene_b = export.export_scene(context, os.path.join(OUT, "b", "scene.json"))
points = scene_b["objects"][0]["pin"]["points"]
check(len(scene_b["objects"]) == 1 and points, "one body, pinned points")
box_points = [k for k in range(model.control_points) if rest[k, 2] <= 0.01]
check(set(box_points) <= set(points), "the vertex group pins the base's control points")
check(bpy.ops.sem.simulate() == {"FINISHED"}, "bpy.ops.sem.simulate: %s" % s.status)
frames_b = sem_run(os.path.join(OUT, "b"))
worst_b, moved_b = compare_frames(root_b, frames_b, "mesh run")
tessellation = model.tessellate(int(root_b["sem_mesh_resolution"]))
worst_vertex = 0.0
for k in range(11):
    scene.frame_set(scene.frame_start + k)
    depsgraph = context.evaluated_depsgraph_get()
    positions = tessellation.update(frames_b[k]) * 0.001
    for i, p in enumerate(parts_b):
        evaluated = p.evaluated_get(depsgraph)
        co = np.empty(3 * len(evaluated.data.vertices), dtype=np.float32)
        evaluated.data.vertices.foreach_get("co", co)
        a, c = tessellation.part_vertex_start[i:i + 2]
        worst_vertex = max(worst_vertex, np.abs(co.reshape(-1, 3) - positions[a:c]).max())
check(worst_vertex <= 1e-6 * size, "animated vertices %g m from sem run's" % worst_vertex)
note("meshes, vertex group (%d vertices -> %d control points): frames = sem run's to %.2e "
     "relative; Blender's evaluated vertices %.1e m from sem's tessellation of sem run's "
     "frames (float32)" % (held, len(points), worst_b, worst_vertex))

check(bpy.ops.sem.export_iges(directory=os.path.join(OUT, "b", "iges")) == {"FINISHED"},
      "export IGES")
worst_iges = 0.0
for k in range(11):
    mine = sem.load(os.path.join(OUT, "b", "iges", "frame_%04d.igs" % k))
    check(mine.units == ("MM", 0.001), "exported units %s" % (mine.units,))
    worst_iges = max(worst_iges, np.abs(mine.q() - frames_b[k].q()).max())
check(worst_iges <= RELATIVE * np.abs(frames_b[0].q()).max(), "IGES export %g" % worst_iges)
note("IGES export: 11 frames, in MM, %.1e mm from sem run's frame_NNNN.igs" % worst_iges)

# ------------------------------------------------------------ 5. cancel, errors ----
s.frames = 400
run = simulation.start(context)
while run.frames_done < 2 and not run.done:
    time.sleep(0.01)
run.cancel()
while simulation.tick(context) == "RUNNING":
    time.sleep(0.02)
kept = run.frames_done
check(run.cancelled and 2 <= kept < 400 and s.status.startswith("cancelled after %d of 400" % kept),
      "cancel: %s" % s.status)
check(len(parts_b[0].data.shape_keys.key_blocks) == kept + 2, "frames kept after a cancel")
note("cancel after %d of 400 frames: %s" % (kept, s.status))
s.frames = 10

errors = []


def expect_error(what, needle, action):
    try:
        action()
    except RuntimeError as e:
        text = str(e)
        check(needle in text and "\n" not in text.strip(), "%s: %r lacks %r" % (what, text, needle))
        errors.append(text)
        return
    raise AssertionError("%s: no error" % what)


expect_error("missing file", "cannot open",
             lambda: bpy.ops.import_scene.sem_model(filepath=os.path.join(OUT, "none.igs")))
b.pin_vertex_group = "nothing"
expect_error("empty vertex group", 'vertex group "nothing"',
             lambda: export.export_scene(context, os.path.join(OUT, "c.json")))
b.pin_vertex_group = "pin"
root_b.scale = (-1.0, 1.0, 1.0)
expect_error("mirrored body", "mirror", lambda: export.export_scene(context, os.path.join(OUT, "c.json")))
root_b.scale = (1.0, 1.0, 1.0)
parts_b[2].location = (0.1, 0, 0)
expect_error("part moved alone", "moved on its own",
             lambda: export.export_scene(context, os.path.join(OUT, "c.json")))
parts_b[2].location = (0, 0, 0)
b.pin_mode = "BOX"
b.pin_box_min, b.pin_box_max = (5.0, 5.0, 5.0), (6.0, 6.0, 6.0)
expect_error("pin box holding nothing",
             "sem: failed: %s: pin.box: [[5, 5, 5], [6, 6, 6]] holds none of the model's material"
             % root_b.name, lambda: bpy.ops.sem.simulate())  # sem's message, in Blender's words
b.pin_mode = "VERTEX_GROUP"
root_b.sem.simulate = False
expect_error("nothing to simulate", "nothing to simulate",
             lambda: export.export_scene(context, os.path.join(OUT, "c.json")))
note("errors: " + " | ".join(errors))

bpy.ops.sem.clear()
check("sem_q" not in root and parts[0].data.shape_keys is None, "Clear Results")
draw_panels("cleared")

# opening another file while a simulation runs forgets it (its objects are gone)
root_b.sem.simulate = True
s.frames = 400
run = simulation.start(context)
bpy.ops.wm.read_homefile(use_empty=True)
check(simulation.active() is None and run.forgotten, "a run outlived its file")
run.thread.join(60)
check(run.done and not os.path.exists(run.work_dir), "the forgotten run's folder is left")
note("opening another file during a run: the run is cancelled and forgotten, its folder removed")
bpy.ops.preferences.addon_disable(module="sem_blender")
with open(os.path.join(OUT, "results.txt"), "w") as f:
    f.write("\n".join(results) + "\n")
print("test_blender: passed", flush=True)
