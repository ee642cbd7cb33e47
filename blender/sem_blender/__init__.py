"""sem for Blender: animate NURBS CAD models with the Shape Matching Element Method.

File > Import > "CAD model through sem" reads an IGES, STEP or OBJ free-form file with the sem
library: one Blender object per part (a NURBS surface where Blender can hold it, else a
mesh), with the file's part names and colours, under an empty that stands for the whole
model (the simulated body). Physics properties > "sem Body" sets its material, pins,
friction and initial velocity; "sem Collider" makes any mesh a static obstacle; Scene
properties > "sem Simulation" sets gravity, the time step, the frames and a ground plane and
runs the simulation in the background (a progress bar, Esc or Cancel stops it). The result
is shape keys on every part, one per frame, keyed on the timeline; the deformed NURBS of
every frame can be written as IGES.

It uses the sem Python package and libsem installed with sem (cmake --install): with the
default prefix /usr/local Blender finds them; otherwise set the package's folder in the
add-on's preferences. docs/blender.md in the sem sources says everything.
"""

bl_info = {
    "name": "sem: Shape Matching Element Method",
    "author": "sem developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "File > Import > CAD model through sem; Properties > Physics and Scene",
    "description": "Animate NURBS CAD models (IGES, STEP, OBJ) with elastodynamics, without a "
                   "volume mesh",
    "category": "Physics",
}

if "bpy" in locals():  # a reload (F3 > Reload Scripts) re-imports the modules
    import importlib
    for _module in (geometry, sem_package, properties, importer, simulation, export, panels):  # noqa: F821
        importlib.reload(_module)
else:
    from . import geometry, sem_package, properties, importer, simulation, export, panels

import bpy  # noqa: E402


def _menu_import(self, context):
    self.layout.operator(importer.SEM_OT_import_model.bl_idname,
                         text="CAD model through sem (.igs, .iges, .step, .stp, .obj)")


_CLASSES = (sem_package.SemAddonPreferences,) + properties.CLASSES + importer.CLASSES + \
    simulation.CLASSES + export.CLASSES + panels.CLASSES


def register():
    for cls in _CLASSES:
        bpy.utils.register_class(cls)
    properties.register()
    simulation.register()
    bpy.types.TOPBAR_MT_file_import.append(_menu_import)


def unregister():
    simulation.unregister()
    bpy.types.TOPBAR_MT_file_import.remove(_menu_import)
    properties.unregister()
    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
