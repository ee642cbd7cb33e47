"""Writing what the add-on has: the deformed NURBS of every frame as IGES, and the scene as a
sem scene file.

IGES: each body with Simulate on that has frames has its model read again from its file and given each frame's control
points in the file's units (the world metres times 1 / unit_to_meter, the arithmetic of
sem run's animation writer), then written by libsem: frame_NNNN.igs for one body, BODY_frame_NNNN.igs
for several (NNNN: 4 digits, more when the last frame needs them). For one body these are the
numbers of `sem run`'s frame_NNNN.igs for the exported scene.

Scene: the dict Simulate runs (simulation.build_scene) as JSON, with the collider meshes as
OBJ files in a folder beside it; `sem run SCENE --out DIR` computes the same frames.
"""

import json
import os

import bpy
from bpy.props import StringProperty
from bpy_extras.io_utils import ExportHelper

from . import sem_package, simulation


def frame_digits(last_frame):
    return max(4, len(str(last_frame)))


def export_iges(context, folder):
    """Writes every simulated body's frames into folder; returns the paths written. Raises
    RuntimeError."""
    sem = sem_package.load_sem(context)
    roots = [o for o in simulation.bodies(context.scene) if "sem_q" in o]
    if not roots:
        raise RuntimeError("no body with Simulate on has frames yet: press Simulate first")
    folder = bpy.path.abspath(folder)
    os.makedirs(folder, exist_ok=True)
    written = []
    for root in roots:
        frames = simulation.stored_frames(root)
        try:
            model = sem.load(root["sem_model_path"])
        except sem.SemError as e:
            raise RuntimeError(str(e)) from None
        if frames.shape[1] != model.control_points:
            raise RuntimeError("%s: its file %s has %d control points, the simulation had %d "
                               "(the file changed: simulate again)" % (
                                   root.name, root["sem_model_path"], model.control_points,
                                   frames.shape[1]))
        to_file = 1.0 / model.units[1]
        digits = frame_digits(len(frames) - 1)
        prefix = "" if len(roots) == 1 else bpy.path.clean_name(root.name) + "_"
        for k, q in enumerate(frames):
            model.set_q(q * to_file)
            path = os.path.join(folder, "%sframe_%0*d.igs" % (prefix, digits, k))
            try:
                model.save(path)
            except sem.SemError as e:
                raise RuntimeError(str(e)) from None
            written.append(path)
    return written


def export_scene(context, path):
    """Writes the scene Simulate would run as a sem scene file (colliders beside it)."""
    sem = sem_package.load_sem(context)
    path = bpy.path.abspath(path)
    stem = os.path.splitext(path)[0]
    scene, _ = simulation.build_scene(context, sem, stem + "_colliders")
    text = json.dumps(scene, indent=1)
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text + "\n")
    os.replace(tmp, path)
    return scene


class SEM_OT_export_iges(bpy.types.Operator):
    """Write the deformed NURBS model of every simulated frame as IGES (frame_NNNN.igs, in
    the model file's units) into the scene's IGES folder"""
    bl_idname = "sem.export_iges"
    bl_label = "Export Frames as IGES"

    directory: StringProperty(name="Folder", subtype="DIR_PATH", default="",
                              description="Folder (empty: the scene's IGES folder setting)")

    def execute(self, context):
        folder = self.directory or context.scene.sem.export_dir
        try:
            written = export_iges(context, folder)
        except (RuntimeError, OSError) as e:
            self.report({"ERROR"}, "sem: %s" % e)
            return {"CANCELLED"}
        self.report({"INFO"}, "sem: %d IGES frames written to %s" % (
            len(written), bpy.path.abspath(folder)))
        return {"FINISHED"}


class SEM_OT_export_scene(bpy.types.Operator, ExportHelper):
    """Write the scene Simulate runs as a sem scene file (JSON; collider meshes beside it):
    `sem run SCENE.json --out DIR` computes the same frames"""
    bl_idname = "sem.export_scene"
    bl_label = "Export sem Scene"

    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})

    def execute(self, context):
        try:
            export_scene(context, self.filepath)
        except (RuntimeError, OSError) as e:
            self.report({"ERROR"}, "sem: %s" % e)
            return {"CANCELLED"}
        self.report({"INFO"}, "sem: scene written to %s" % self.filepath)
        return {"FINISHED"}


CLASSES = (SEM_OT_export_iges, SEM_OT_export_scene)
