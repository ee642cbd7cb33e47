"""The add-on's panels: Physics properties (a body's settings, a collider) and Scene
properties (the simulation). Blender 3.4's layouts have no progress bar widget, so progress
is a read-only percentage slider plus a status line (and the cursor's progress and the
status bar while the modal operator runs)."""

import bpy

from . import simulation
from .properties import body_parts, body_root


class SEM_PT_body(bpy.types.Panel):
    bl_label = "sem Body"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "physics"

    @classmethod
    def poll(cls, context):
        return body_root(context.object) is not None

    def draw(self, context):
        layout = self.layout
        obj = context.object
        root = body_root(obj)
        b = root.sem
        parts = body_parts(root)
        nurbs = sum(1 for p in parts if p.get("sem_kind") == "NURBS")
        box = layout.box()
        box.label(text="%s (%s)" % (root.name, root["sem_units"]), icon="MOD_PHYSICS")
        box.label(text="%d parts: %d NURBS surfaces, %d meshes; %d control points" % (
            len(parts), nurbs, len(parts) - nurbs, root["sem_control_points"]))
        if obj is not root:
            box.label(text="Part %d: %s (%s)" % (obj["sem_part"], obj.name,
                                                 obj.get("sem_kind", "?").lower()))
        layout.prop(b, "simulate")
        column = layout.column()
        column.enabled = b.simulate
        column.use_property_split = True
        column.prop(b, "material")
        column.prop(b, "density")
        column.prop(b, "youngs_modulus")
        column.prop(b, "poisson_ratio")
        column.prop(b, "friction")
        column.prop(b, "initial_velocity")
        column.separator()
        column.prop(b, "pin_mode")
        if b.pin_mode == "BOX":
            column.prop(b, "pin_box_object")
            if b.pin_box_object is None:
                column.prop(b, "pin_box_min")
                column.prop(b, "pin_box_max")
        elif b.pin_mode == "VERTEX_GROUP":
            meshes = [p for p in parts if p.type == "MESH"]
            if meshes:
                column.prop(b, "pin_vertex_group")
                holders = [p.name for p in meshes if b.pin_vertex_group in p.vertex_groups]
                column.label(text="on %s" % (", ".join(holders[:3]) + (" ..." if len(holders) > 3
                                                                        else "")
                                             if holders else "no mesh part has it yet"),
                             icon="GROUP_VERTEX")
            else:
                row = column.row()
                row.alert = True
                row.label(text="Every part is a NURBS surface: pin with a box", icon="ERROR")
        frames = simulation.stored_frames(root)
        if frames is not None:
            layout.label(text="Simulated: %d frames from frame %d" % (
                len(frames) - 1, root["sem_frame_start"]), icon="CHECKMARK")


class SEM_PT_collider(bpy.types.Panel):
    bl_label = "sem Collider"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "physics"

    @classmethod
    def poll(cls, context):
        obj = context.object
        return (obj is not None and body_root(obj) is None
                and obj.type in ("MESH", "CURVE", "SURFACE", "META", "FONT"))

    def draw(self, context):
        layout = self.layout
        s = context.object.sem
        layout.prop(s, "collider")
        row = layout.row()
        row.enabled = s.collider
        row.prop(s, "friction")


class SEM_PT_simulation(bpy.types.Panel):
    bl_label = "sem Simulation"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "scene"

    def draw(self, context):
        layout = self.layout
        scene = context.scene
        s = scene.sem
        running = simulation.active() is not None
        column = layout.column()
        column.use_property_split = True
        column.enabled = not running
        column.prop(s, "gravity")
        column.prop(s, "integrator")
        column.prop(s, "dt")
        column.prop(s, "steps_per_frame")
        column.prop(s, "frames")
        seconds = s.dt * s.steps_per_frame
        column.label(text="Frames %d-%d, %.4g s each (%.4g frames per second real time)" % (
            scene.frame_start, scene.frame_start + s.frames, seconds, 1.0 / seconds))
        column.prop(s, "ground")
        if s.ground:
            column.prop(s, "ground_height")
            column.prop(s, "ground_friction")
        column.prop(s, "use_cache")
        n_bodies = len(simulation.bodies(scene))
        n_colliders = len(simulation.colliders(scene)) + (1 if s.ground else 0)
        layout.label(text="%d bodies, %d colliders" % (n_bodies, n_colliders))
        if running:
            row = layout.row()
            row.enabled = False
            row.prop(s, "progress", slider=True)
            layout.label(text=s.status, icon="TIME")
            layout.operator("sem.cancel", icon="CANCEL")
        else:
            row = layout.row()
            row.scale_y = 1.5
            row.enabled = n_bodies > 0
            row.operator("sem.simulate", icon="PLAY")
            if s.status:
                layout.label(text=s.status)
        layout.separator()
        column = layout.column()
        column.enabled = not running
        column.prop(s, "export_dir")
        row = column.row()
        row.operator("sem.export_iges", icon="EXPORT")
        row.operator("sem.export_scene", icon="FILE")
        column.operator("sem.clear", icon="X")


CLASSES = (SEM_PT_body, SEM_PT_collider, SEM_PT_simulation)
