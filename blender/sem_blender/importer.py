"""File > Import > CAD model through sem: a model file as Blender objects.

The model is read by libsem (sem.load: IGES, OBJ free-form, STEP when sem has Open CASCADE).
It becomes an empty named after the file (the body: its settings and, once simulated, its
frames) with one child per part, named and coloured as in the file:
  * a NURBS surface when Blender can hold the part exactly (geometry.blender_surface_orders:
    untrimmed, clamped uniform knots, degree <= 5), its points the part's control points
    with their weights;
  * else a mesh: sem's tessellation of the (trimmed) part, `mesh_resolution` cells per knot
    span, as sem run's frame_NNNN_mesh.obj.
Coordinates are the file's numbers in metres (the file's units) divided by the scene's unit
scale, so the model has its real size; the empty sits at the origin. Blender makes no NURBS
surface of a given size from Python, so a one-row surface is extruded row by row in edit
mode, once per grid size, and copied.
"""

import os

import bpy
import numpy as np
from bpy.props import EnumProperty, IntProperty, StringProperty
from bpy_extras.io_utils import ImportHelper

from . import geometry, sem_package


def metres_per_unit(scene):
    """Metres in one Blender unit (the scene's unit scale)."""
    scale = scene.unit_settings.scale_length
    return scale if scale > 0 else 1.0


def _material(rgb):
    """One material per file colour, shared by the parts that have it."""
    name = "sem colour %.3f %.3f %.3f" % tuple(rgb)
    mat = bpy.data.materials.get(name)
    if mat is None:
        mat = bpy.data.materials.new(name)
        mat.diffuse_color = (rgb[0], rgb[1], rgb[2], 1.0)
        mat.use_nodes = True
        bsdf = mat.node_tree.nodes.get("Principled BSDF")
        if bsdf is not None:
            bsdf.inputs["Base Color"].default_value = (rgb[0], rgb[1], rgb[2], 1.0)
    return mat


class _SurfaceTemplates:
    """NURBS surface data of a given control grid. Blender's Python API cannot set a
    surface's point counts (point_count_u/v are read-only), so the first surface of each
    size is made by extruding a one-row spline in edit mode, and later ones are copies."""

    def __init__(self, context, collection):
        self.context = context
        self.collection = collection
        self.made = {}

    def curve(self, name, n_u, n_v):
        key = (n_u, n_v)
        if key in self.made:
            data = self.made[key].copy()
            data.name = name
            return data
        data = bpy.data.curves.new(name, "SURFACE")
        data.dimensions = "3D"
        spline = data.splines.new("NURBS")
        spline.points.add(n_u - 1)
        for p in spline.points:
            p.select = True
        if n_v > 1:
            holder = bpy.data.objects.new("sem surface template", data)
            self.collection.objects.link(holder)
            view_layer = self.context.view_layer
            previous = view_layer.objects.active
            for o in view_layer.objects:
                if o.select_get():
                    o.select_set(False)
            view_layer.objects.active = holder
            holder.select_set(True)
            bpy.ops.object.mode_set(mode="EDIT")
            for _ in range(n_v - 1):
                bpy.ops.curve.extrude()  # a whole first row becomes two rows; then the last row
            bpy.ops.object.mode_set(mode="OBJECT")
            view_layer.objects.active = previous
            bpy.data.objects.remove(holder)
        spline = data.splines[0]
        if (spline.point_count_u, spline.point_count_v) != (n_u, n_v):
            raise RuntimeError("sem: Blender made a %d x %d surface for a %d x %d part" % (
                spline.point_count_u, spline.point_count_v, n_u, n_v))
        self.made[key] = data.copy()
        self.made[key].name = "sem surface %d x %d" % key
        self.made[key].use_fake_user = False
        return data

    def remove(self):
        for data in self.made.values():
            bpy.data.curves.remove(data)
        self.made.clear()


def _surface_object(templates, name, surface, points, orders, resolution):
    """A NURBS surface object with the part's control points (local coordinates) and weights."""
    n_u, n_v = surface["control_grid"]
    data = templates.curve(name, n_u, n_v)
    spline = data.splines[0]
    co = np.empty((n_u * n_v, 4))
    co[:, :3] = points
    co[:, 3] = surface["weights"].reshape(-1)
    spline.points.foreach_set("co", co.astype(np.float32).ravel())
    spline.order_u, spline.order_v = orders
    spline.use_endpoint_u = spline.use_endpoint_v = True
    spline.use_bezier_u = spline.use_bezier_v = False
    spline.use_cyclic_u = spline.use_cyclic_v = False
    spline.resolution_u = spline.resolution_v = max(2, resolution)
    spline.use_smooth = True
    for p in spline.points:
        p.select = False
    return bpy.data.objects.new(name, data)


def _mesh_object(name, positions, triangles):
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(positions))
    mesh.vertices.foreach_set("co", np.asarray(positions, dtype=np.float32).ravel())
    n = len(triangles)
    mesh.loops.add(3 * n)
    mesh.loops.foreach_set("vertex_index", np.asarray(triangles, dtype=np.int32).ravel())
    mesh.polygons.add(n)
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * n, 3, dtype=np.int32))
    mesh.polygons.foreach_set("loop_total", np.full(n, 3, dtype=np.int32))
    mesh.polygons.foreach_set("use_smooth", np.ones(n, dtype=bool))
    mesh.update(calc_edges=True)
    return bpy.data.objects.new(name, mesh)


def import_model(context, path, nurbs=True, mesh_resolution=6):
    """Reads `path` through sem and makes the body's empty and part objects in a new
    collection. Returns (empty, counts {"NURBS": n, "MESH": m}, notes: why parts are meshes).
    Raises RuntimeError with sem's one-line message."""
    sem = sem_package.load_sem(context)
    path = os.path.abspath(bpy.path.abspath(path))
    try:
        model = sem.load(path)
    except sem.SemError as e:
        raise RuntimeError(str(e)) from None
    if context.object is not None and context.object.mode != "OBJECT":
        bpy.ops.object.mode_set(mode="OBJECT")
    units, unit_to_meter = model.units
    if not unit_to_meter > 0:
        unit_to_meter = 1.0
    to_blender = unit_to_meter / metres_per_unit(context.scene)
    q = model.q() * to_blender
    offsets = model.part_offsets()
    stem = os.path.splitext(os.path.basename(path))[0]
    collection = bpy.data.collections.new(stem)
    context.collection.children.link(collection)

    root = bpy.data.objects.new(stem, None)
    root.empty_display_type = "ARROWS"
    low, high = q.min(axis=0), q.max(axis=0)
    root.empty_display_size = max(float(np.linalg.norm(high - low)) / 10, 1e-6)
    root["sem_model_path"] = path
    root["sem_units"] = units
    root["sem_unit_to_meter"] = unit_to_meter
    root["sem_parts"] = model.parts
    root["sem_control_points"] = model.control_points
    root["sem_mesh_resolution"] = int(mesh_resolution)
    collection.objects.link(root)

    kinds, notes = {}, []
    for i in range(model.parts):
        info = model.part_info(i)
        surface = model.surface(i)
        orders, why = (geometry.blender_surface_orders(surface, info["trimmed"]) if nurbs
                       else (None, "meshes were asked for"))
        kinds[i] = ("NURBS", orders) if orders else ("MESH", why)
        if not orders and nurbs:
            notes.append("%s: %s" % (info["name"] or "part %d" % i, why))
    tessellation = None
    if any(kind == "MESH" for kind, _ in kinds.values()):
        tessellation = model.tessellate(mesh_resolution)
    templates = _SurfaceTemplates(context, collection)
    counts = {"NURBS": 0, "MESH": 0}
    try:
        for i in range(model.parts):
            info = model.part_info(i)
            name = info["name"] or "part %d" % i
            kind, orders = kinds[i]
            if kind == "NURBS":
                obj = _surface_object(templates, name, model.surface(i),
                                      q[offsets[i]:offsets[i + 1]], orders, mesh_resolution)
            else:
                v0, v1 = tessellation.part_vertex_start[i:i + 2]
                t0, t1 = tessellation.part_triangle_start[i:i + 2]
                obj = _mesh_object(name, tessellation.positions[v0:v1] * to_blender,
                                   tessellation.triangles[t0:t1] - v0)
            counts[kind] += 1
            if info["color"] is not None:
                obj.data.materials.append(_material(info["color"]))
            obj["sem_part"] = i
            obj["sem_kind"] = kind
            obj.parent = root
            collection.objects.link(obj)
    finally:
        templates.remove()
    for o in context.view_layer.objects:
        if o.select_get():
            o.select_set(False)
    context.view_layer.objects.active = root
    root.select_set(True)
    return root, counts, notes


class SEM_OT_import_model(bpy.types.Operator, ImportHelper):
    """Import an IGES, STEP or OBJ free-form model through sem: one object per part, ready
    to simulate"""
    bl_idname = "import_scene.sem_model"
    bl_label = "Import CAD model (sem)"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ".igs"
    filter_glob: StringProperty(default="*.igs;*.iges;*.step;*.stp;*.obj", options={"HIDDEN"})
    surfaces: EnumProperty(
        name="Parts as", default="NURBS",
        items=[("NURBS", "NURBS where possible",
                "NURBS surfaces for the parts Blender can hold exactly, meshes for the others "
                "(trimmed parts, non-uniform knots)"),
               ("MESH", "Meshes", "Every part as sem's triangle mesh")])
    mesh_resolution: IntProperty(name="Mesh resolution", default=6, min=1, max=64,
                                 description="Cells per knot span and direction of the meshes "
                                             "(sem run's frame meshes use 6)")

    def execute(self, context):
        try:
            root, counts, notes = import_model(context, self.filepath, self.surfaces == "NURBS",
                                               self.mesh_resolution)
        except RuntimeError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        message = "sem: %s: %d parts, %d NURBS surfaces, %d meshes" % (
            root.name, counts["NURBS"] + counts["MESH"], counts["NURBS"], counts["MESH"])
        if notes:
            message += " (meshes: %s%s)" % ("; ".join(notes[:3]), "; ..." if len(notes) > 3 else "")
        self.report({"INFO"}, message)
        return {"FINISHED"}


CLASSES = (SEM_OT_import_model,)
