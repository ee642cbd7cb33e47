"""Settings the add-on keeps in the .blend: per object (Object.sem) and per scene (Scene.sem).

An imported model is an empty (the body: it holds the model file's path and every physical
setting) with one child object per part. Their keys (custom properties):
  empty: sem_model_path, sem_units, sem_unit_to_meter, sem_parts, sem_control_points,
         sem_mesh_resolution, and after a simulation sem_q (every frame's control points,
         world metres, float64), sem_frame_count, sem_frame_start
  part:  sem_part (its index in the file), sem_kind ("NURBS" or "MESH")
Units: lengths in the panels are Blender units (scene unit scale applies); the scene sem
simulates is in metres.
"""

import bpy
from bpy.props import (BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty,
                       IntProperty, PointerProperty, StringProperty)

MATERIALS = [
    ("neohookean", "Neo-Hookean", "The paper's hyperelastic model (fails on inverted elements)"),
    ("stable_neohookean", "Stable Neo-Hookean",
     "Smith et al. 2018: neo-Hookean defined for inverted elements"),
    ("corotated", "Corotated", "Fixed co-rotated elasticity"),
    ("stvk", "St. Venant-Kirchhoff", "St. Venant-Kirchhoff"),
    ("linear", "Linear", "Small-strain linear elasticity"),
]

INTEGRATORS = [
    ("implicit_euler", "Implicit Euler", "Newton on the incremental potential (robust)"),
    ("linearly_implicit_euler", "Linearly implicit Euler",
     "The paper's step: one linear solve per step (fast; can fail on soft materials)"),
    ("static", "Static", "Each step solves for static equilibrium"),
]


def body_root(obj):
    """The empty standing for the sem body an object belongs to (itself or its parent), or
    None."""
    if obj is None:
        return None
    if "sem_model_path" in obj:
        return obj
    if "sem_part" in obj and obj.parent is not None and "sem_model_path" in obj.parent:
        return obj.parent
    return None


def body_parts(root):
    """The part objects of a body, by part index."""
    parts = [c for c in root.children if "sem_part" in c]
    return sorted(parts, key=lambda c: int(c["sem_part"]))


class SemObjectSettings(bpy.types.PropertyGroup):
    simulate: BoolProperty(name="Simulate", default=True,
                           description="Simulate this imported model (off: it stays where it is "
                                       "and takes no part in the simulation)")
    collider: BoolProperty(name="Collider", default=False,
                           description="A static obstacle: the object's mesh, as evaluated "
                                       "(modifiers applied), in world coordinates")
    material: EnumProperty(name="Material", items=MATERIALS, default="neohookean")
    density: FloatProperty(name="Density", default=1000.0, min=1e-6, soft_max=20000.0,
                           description="kg/m^3")
    youngs_modulus: FloatProperty(name="Young's modulus", default=1e6, min=1e-6, soft_max=1e12,
                                  description="Pa")
    poisson_ratio: FloatProperty(name="Poisson ratio", default=0.45, min=-0.999, max=0.499,
                                 description="Dimensionless, in (-1, 0.5)")
    friction: FloatProperty(name="Friction", default=0.5, min=0.0, soft_max=2.0,
                            description="Coulomb coefficient of the surface (a pair uses "
                                        "sqrt(mu_a mu_b))")
    initial_velocity: FloatVectorProperty(name="Initial velocity", size=3, subtype="VELOCITY",
                                          unit="VELOCITY", default=(0.0, 0.0, 0.0))
    pin_mode: EnumProperty(
        name="Pin", default="NONE",
        items=[("NONE", "None", "Nothing is held"),
               ("BOX", "Box", "The material inside a box (world coordinates) is held"),
               ("VERTEX_GROUP", "Vertex group",
                "The control points behind the vertices of a vertex group of the mesh parts "
                "are held")])
    pin_box_object: PointerProperty(
        name="Box object", type=bpy.types.Object,
        description="Use this object's bounding box (world coordinates) as the pin box")
    pin_box_min: FloatVectorProperty(name="Box min", size=3, subtype="XYZ", unit="LENGTH",
                                     default=(-1.0, -1.0, -1.0))
    pin_box_max: FloatVectorProperty(name="Box max", size=3, subtype="XYZ", unit="LENGTH",
                                     default=(1.0, 1.0, 0.0))
    pin_vertex_group: StringProperty(name="Vertex group", default="pin",
                                     description="Vertex group name, on the mesh parts")


class SemSceneSettings(bpy.types.PropertyGroup):
    gravity: FloatVectorProperty(name="Gravity", size=3, subtype="ACCELERATION",
                                 unit="ACCELERATION", default=(0.0, 0.0, -9.81))
    integrator: EnumProperty(name="Integrator", items=INTEGRATORS, default="implicit_euler")
    dt: FloatProperty(name="Time step", default=0.01, min=1e-7, soft_max=0.1, precision=4,
                      description="Seconds per step")
    frames: IntProperty(name="Frames", default=48, min=1, soft_max=1000,
                        description="Frames simulated after the rest frame (the scene's start "
                                    "frame)")
    steps_per_frame: IntProperty(name="Steps per frame", default=1, min=1, soft_max=100)
    ground: BoolProperty(name="Ground plane", default=False,
                         description="A static plane at the given height, normal +Z")
    ground_height: FloatProperty(name="Height", default=0.0, unit="LENGTH")
    ground_friction: FloatProperty(name="Friction", default=0.5, min=0.0, soft_max=2.0)
    use_cache: BoolProperty(name="Use the preprocessing cache", default=True,
                            description="Reuse preprocessing from earlier runs (also sem "
                                        "run's): the second run of a model starts at once")
    export_dir: StringProperty(name="IGES folder", subtype="DIR_PATH", default="//sem_frames/",
                               description="Where Export IGES writes frame_NNNN.igs")
    # shown while a simulation runs (kept up to date by the running operator)
    progress: FloatProperty(name="Progress", subtype="PERCENTAGE", min=0.0, max=100.0,
                            default=0.0)
    status: StringProperty(name="Status", default="")


CLASSES = (SemObjectSettings, SemSceneSettings)


def register():
    bpy.types.Object.sem = PointerProperty(type=SemObjectSettings)
    bpy.types.Scene.sem = PointerProperty(type=SemSceneSettings)


def unregister():
    del bpy.types.Scene.sem
    del bpy.types.Object.sem
