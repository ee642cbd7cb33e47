#!/usr/bin/env python3
"""sem validate: sem against a converged FEM solution of the same static problem.

Run as `sem validate MODEL [SCENE] [options]` (src/cli/cmd_validate.c runs this script with
python3 and passes its own binary as --sem); docs/validation.md, "sem validate", describes
the method and what the numbers mean. Python standard library only.

The problem, the same on both sides:
  * the model in metres (its file's units, or the scene's `units`), placed by the scene's
    `transform`;
  * gravity (default 9.81 m/s^2 along -z);
  * a hyperelastic material: sem's neo-Hookean psi = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2
    against CalculiX's *HYPERELASTIC, NEO HOOKE with C10 = mu / 2, D1 = 2 / K (same E, nu;
    they agree to second order, docs/validation.md section 1); density 1000 kg/m^3, nu 0.45,
    and E chosen so that the largest displacement is about 1 % of the model's largest
    dimension L (a linear FEM solve on the coarsest mesh with E0 = 100 rho g L gives the
    largest displacement d0; displacement is proportional to 1 / E, so E = E0 d0 / (0.01 L));
  * pinned: the points whose rest z lies in the lowest 10 % of the model's height (FEM: every
    node there; sem: every control point there, through a pin box), or the scene's pin box.

FEM side: gmsh (Open CASCADE kernel) takes the file's own solids, or sews its faces into
shells (gaps up to 1e-7 .. 1e-3 L, the first that closes) and makes solids of them; cuts them
along the faces of the pin box that pass through the model (so the pinned region does not
change with the mesh); meshes them into 10-node tetrahedra (curved at the boundary; an element
that folds there is straightened). CalculiX solves the static problem with geometric
nonlinearity (*STATIC in a *STEP, NLGEOM; the material model of sem's, see write_inp). The
mesh is refined from h0 = L / 10 (characteristic length x 0.7 per level) until the
area-weighted L2 norm of the surface displacement and the largest surface displacement both
change by less than --tolerance between two meshes, within --max-levels and --max-nodes.

sem side: `sem run` on a scene of one object with integrator "static" and one frame, at sem's
defaults (or the scene's `sem` settings). Every frame is the rest model with moved control
points, so sem's displacement at a FEM surface node X is x(part, u, v) - X where (part, u, v)
is the closest point of the rest model to X (`sem probe`).

Compared at the FEM surface nodes: the relative L2 error ||u_sem - u_fem|| / ||u_fem|| over the
surface (the quadratic interpolant of the nodal values integrated exactly on every 6-node
boundary triangle taken as flat), and the largest displacement of each.
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fem_common  # noqa: E402
from fem_common import ToolFailed, ToolsMissing  # noqa: E402

USAGE = ("MODEL [SCENE] [--json] [--tolerance T] [--workdir DIR] [--keep] [--no-install] "
         "[--max-levels N] [--max-nodes N] [--h0 H] [-E E] [--resolutions R1,R2,...] [--quiet]")
EXIT_FAILED, EXIT_USAGE, EXIT_TOOLS = 1, 2, 3

DEFAULT_DENSITY, DEFAULT_E, DEFAULT_NU = 1000.0, 1.0e6, 0.45
DEFAULT_GRAVITY = (0.0, 0.0, -9.81)
PIN_FRACTION = 0.10      # the lowest 10 % of the height
SAG_FRACTION = 0.01      # E makes the largest displacement 1 % of the largest dimension
REFINE_FACTOR = 0.7      # characteristic length per level
ON_SURFACE = 1e-4        # a FEM surface node farther than this x L from sem's surfaces is not used
UNITS = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "um": 1e-6, "km": 1e3, "in": 0.0254, "ft": 0.3048,
         "mi": 1609.344, "mil": 2.54e-5, "uin": 2.54e-8}
SOLVE_TIMEOUT = 3600.0   # seconds for one gmsh or CalculiX run
SEW_TOLERANCES = (1e-7, 1e-5, 1e-4, 1e-3)  # gaps closed when sewing faces, x L


class Fail(Exception):
    """A failure reported as one line "sem: MESSAGE" with exit status `code`."""

    def __init__(self, message, code=EXIT_FAILED):
        super().__init__(message)
        self.code = code


QUIET = False


def log(msg):
    if not QUIET:
        print("validate: " + msg, file=sys.stderr, flush=True)


def one_line(text):
    return " ".join(str(text).split())


# ---------------------------------------------------------------- command line

class Parser(argparse.ArgumentParser):
    def error(self, message):
        print("sem: validate: %s" % one_line(message), file=sys.stderr)
        print("usage: sem validate %s  (sem validate --help for more)" % USAGE, file=sys.stderr)
        sys.exit(EXIT_USAGE)


def parse_args(argv):
    ap = Parser(prog="sem validate", add_help=True, description=__doc__.splitlines()[0])
    ap.add_argument("model")
    ap.add_argument("scene", nargs="?")
    ap.add_argument("--sem", default=os.environ.get("SEM_BINARY", "sem"), help=argparse.SUPPRESS)
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--tolerance", type=float, default=0.005)
    ap.add_argument("--workdir")
    ap.add_argument("--keep", action="store_true")
    ap.add_argument("--no-install", action="store_true")
    ap.add_argument("--max-levels", type=int, default=5)
    ap.add_argument("--max-nodes", type=int, default=40000)
    ap.add_argument("--h0", type=float)
    ap.add_argument("-E", "--youngs-modulus", type=float, dest="youngs_modulus")
    ap.add_argument("--resolutions", help="comma-separated sem.resolution values: sem solved again at each, "
                    "against the same FEM answer (the accuracy setting's convergence)")
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args(argv)
    if not (0 < a.tolerance < 1):
        ap.error("--tolerance must be in (0, 1) (got %g)" % a.tolerance)
    if not (1 <= a.max_levels <= 20):
        ap.error("--max-levels must be in 1..20 (got %d)" % a.max_levels)
    if a.max_nodes < 100:
        ap.error("--max-nodes must be at least 100 (got %d)" % a.max_nodes)
    if a.h0 is not None and not (a.h0 > 0 and math.isfinite(a.h0)):
        ap.error("--h0 must be a positive length (got %g)" % a.h0)
    if a.youngs_modulus is not None and not (a.youngs_modulus > 0 and math.isfinite(a.youngs_modulus)):
        ap.error("--youngs-modulus must be positive (got %g)" % a.youngs_modulus)
    a.resolution_list = []
    if a.resolutions:
        try:
            a.resolution_list = [float(x) for x in a.resolutions.split(",")]
        except ValueError:
            ap.error("--resolutions must be numbers separated by commas (got %s)" % a.resolutions)
        if any(not (0 <= r <= 1000) for r in a.resolution_list):
            ap.error("--resolutions must be in 0..1000")
    return a


# ---------------------------------------------------------------- sem

class Sem:
    def __init__(self, binary):
        self.binary = binary

    def run(self, args, what):
        """Runs sem; returns (stdout, stderr). A failure raises Fail with sem's own message."""
        try:
            r = subprocess.run([self.binary] + args, capture_output=True, text=True)
        except OSError as e:
            raise Fail("cannot run %s: %s" % (self.binary, e.strerror or e))
        if r.returncode != 0:
            lines = [l for l in r.stderr.splitlines() if l.startswith("sem: ") and "warning:" not in l]
            msg = lines[-1][5:] if lines else "exit status %d" % r.returncode
            raise Fail("%s: %s" % (what, msg) if what else msg)
        return r.stdout, r.stderr


# ---------------------------------------------------------------- the problem

def check_number(value, where, positive=False):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise Fail("%s: must be a number" % where)
    if positive and not value > 0:
        raise Fail("%s: must be positive (got %g)" % (where, value))
    return float(value)


def check_vec3(value, where):
    if not isinstance(value, list) or len(value) != 3:
        raise Fail("%s: must be an array of 3 numbers" % where)
    return tuple(check_number(v, where) for v in value)


def matmul3(A, B):
    return [[sum(A[i][k] * B[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def scene_transform(t, where):
    """The scene's transform (docs/scenes.md) as (A, b): x -> A x + b, metres."""
    if t is None:
        return [[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]], (0.0, 0.0, 0.0)
    if not isinstance(t, dict):
        raise Fail("%s: must be an object" % where)
    if "matrix" in t:
        m = t["matrix"]
        if not (isinstance(m, list) and len(m) == 3 and all(isinstance(r, list) and len(r) == 4 for r in m)):
            raise Fail("%s.matrix: must be 3 rows of 4 numbers" % where)
        rows = [[check_number(v, where + ".matrix") for v in r] for r in m]
        return [r[:3] for r in rows], tuple(r[3] for r in rows)
    A = [[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]]
    if "scale" in t:
        s = t["scale"]
        s = check_vec3(s, where + ".scale") if isinstance(s, list) else (check_number(s, where + ".scale"),) * 3
        A = [[s[0], 0, 0], [0, s[1], 0], [0, 0, s[2]]]
    if "rotate" in t:
        r = t["rotate"] if isinstance(t["rotate"], dict) else {}
        axis = check_vec3(r.get("axis", [0, 0, 1]), where + ".rotate.axis")
        n = math.sqrt(sum(a * a for a in axis))
        if not n > 0:
            raise Fail("%s.rotate.axis: must be non-zero" % where)
        x, y, z = (a / n for a in axis)
        th = math.radians(check_number(r.get("degrees", 0), where + ".rotate.degrees"))
        c, s_, C = math.cos(th), math.sin(th), 1 - math.cos(th)
        R = [[c + x * x * C, x * y * C - z * s_, x * z * C + y * s_],
             [y * x * C + z * s_, c + y * y * C, y * z * C - x * s_],
             [z * x * C - y * s_, z * y * C + x * s_, c + z * z * C]]
        A = matmul3(R, A)
    b = check_vec3(t["translate"], where + ".translate") if "translate" in t else (0.0, 0.0, 0.0)
    return A, b


def apply(A, b, x):
    return tuple(A[i][0] * x[0] + A[i][1] * x[1] + A[i][2] * x[2] + b[i] for i in range(3))


class Problem:
    """What both sides solve (all SI, world coordinates)."""

    def __init__(self):
        self.units_factor = 1.0     # metres per number of the file (sem's reading)
        self.A, self.b = [[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]], (0.0, 0.0, 0.0)
        self.gravity = DEFAULT_GRAVITY
        self.material = "neohookean"
        self.density, self.E, self.nu = DEFAULT_DENSITY, None, DEFAULT_NU
        self.E_rule = None
        self.pin_box = None         # [[x0, y0, z0], [x1, y1, z1]]
        self.pin_rule = None
        self.sem_object = {}        # the scene object's keys sem takes over (units, transform, sem, gamma)
        self.integrator = {}        # the scene integrator's solver settings


def read_scene(path, problem):
    try:
        with open(path) as f:
            text = f.read()
    except OSError as e:
        raise Fail("%s: cannot open: %s" % (path, e.strerror))
    try:
        scene = json.loads(text)
    except ValueError as e:
        raise Fail("%s:%d: not valid JSON" % (path, getattr(e, "lineno", 0)))
    if not isinstance(scene, dict):
        raise Fail("%s: a scene must be a JSON object" % path)
    objects = scene.get("objects")
    if not isinstance(objects, list) or len(objects) != 1 or not isinstance(objects[0], dict):
        raise Fail("%s: objects: validate takes a scene of exactly one object" % path)
    if scene.get("colliders"):
        raise Fail("%s: colliders: validate solves no contact; remove the colliders" % path)
    o = objects[0]
    where = "%s: objects[0]" % path
    for key, why in (("part_materials", "the FEM side has one material"),
                     ("prescribe", "validate solves for gravity with fixed pins only"),
                     ("point_loads", "validate solves for gravity only"),
                     ("region_loads", "validate solves for gravity only")):
        if o.get(key):
            raise Fail("%s.%s: not supported by validate (%s)" % (where, key, why))
    if "units" in o:
        u = o["units"]
        if not isinstance(u, str) or (u != "as_metres" and u.lower() not in UNITS):
            raise Fail('%s.units: must be "as_metres" or a unit name (m, mm, cm, um, km, in, ft, mi, mil, uin)' % where)
        problem.sem_object["units"] = u
    if "transform" in o:
        problem.A, problem.b = scene_transform(o["transform"], where + ".transform")
        problem.sem_object["transform"] = o["transform"]
    for key in ("sem", "gamma"):
        if key in o:
            problem.sem_object[key] = o[key]
    m = o.get("material", {})
    if not isinstance(m, dict):
        raise Fail("%s.material: must be an object" % where)
    mtype = m.get("type", "neohookean")
    if mtype not in ("neohookean", "stable_neohookean", "stvk", "linear"):
        raise Fail("%s.material.type: %s has no CalculiX counterpart here (validate takes neohookean, "
                   "stable_neohookean, stvk and linear)" % (where, json.dumps(mtype)))
    problem.material = mtype
    problem.density = check_number(m.get("density", DEFAULT_DENSITY), where + ".material.density", True)
    problem.E = check_number(m.get("youngs_modulus", DEFAULT_E), where + ".material.youngs_modulus", True)
    problem.nu = check_number(m.get("poisson_ratio", DEFAULT_NU), where + ".material.poisson_ratio")
    if not -1 < problem.nu < 0.5:
        raise Fail("%s.material.poisson_ratio: must be in (-1, 0.5) (got %g)" % (where, problem.nu))
    if "pin" in o:
        pin = o["pin"]
        if not isinstance(pin, dict) or set(pin) != {"box"}:
            raise Fail("%s.pin: validate takes a pin box only (parts and points select control points, "
                       "which the FEM mesh does not have)" % where)
        box = pin["box"]
        if not (isinstance(box, list) and len(box) == 2):
            raise Fail("%s.pin.box: must be [[x0, y0, z0], [x1, y1, z1]]" % where)
        problem.pin_box = [list(check_vec3(box[0], where + ".pin.box")), list(check_vec3(box[1], where + ".pin.box"))]
        problem.pin_rule = "the scene's pin box"
    if "gravity" in scene:
        problem.gravity = check_vec3(scene["gravity"], "%s: gravity" % path)
    integ = scene.get("integrator", {})
    if isinstance(integ, dict):
        for key in ("tolerance", "max_iterations", "solver", "accept_unconverged"):
            if key in integ:
                problem.integrator[key] = integ[key]
    if isinstance(scene.get("threads"), int):
        problem.integrator["threads"] = scene["threads"]


# ---------------------------------------------------------------- FEM side: gmsh

def geo_header(model_path, scaling, sew, cuts):
    """The model as Open CASCADE solids: the file's own solids (sew None), or its faces sewn
    into shells with gaps up to `sew` metres closed, then made solids; cut along the planar
    quadrilaterals `cuts` (4 corners each, gmsh coordinates) so that the mesh conforms to the
    boundary of the pinned region."""
    quoted = model_path.replace("\\", "\\\\").replace('"', '\\"')
    text = "SetFactory(\"OpenCASCADE\");\n"
    if sew is not None:
        # (sewing happens after the scaling below: the tolerance is in metres; "making solids"
        # of a STEP file's own solids can break them, so only sewn faces get it)
        text += "Geometry.Tolerance = %.17g;\nGeometry.OCCSewFaces = 1;\nGeometry.OCCMakeSolids = 1;\n" % sew
    text += (# Open CASCADE converts IGES and STEP lengths to millimetres; this scales them to
             # metres (times the scene's unit override)
             "Geometry.OCCScaling = %.17g;\n"
             "Merge \"%s\";\n"
             "v[] = Volume \"*\";\n"
             "s[] = Surface \"*\";\n" % (scaling, quoted))
    if cuts:
        text += "cut[] = {};\n"
        for quad in cuts:
            text += "p0 = newp;\n"
            for k, x in enumerate(quad):
                text += "Point(p0 + %d) = {%.17g, %.17g, %.17g};\n" % ((k,) + tuple(x))
            text += "l0 = newl;\n"
            for k in range(4):
                text += "Line(l0 + %d) = {p0 + %d, p0 + %d};\n" % (k, k, (k + 1) % 4)
            text += ("c0 = newll;\nCurve Loop(c0) = {l0, l0 + 1, l0 + 2, l0 + 3};\n"
                     "q0 = news;\nPlane Surface(q0) = {c0};\ncut[] += q0;\n")
        text += ("If (#v[] > 0)\n"
                 "  BooleanFragments{ Volume{v[]}; Delete; }{ Surface{cut[]}; Delete; }\n"
                 "  v[] = Volume \"*\";\n"
                 "EndIf\n")
    return text


def inverse3(A):
    a, b, c = A[0]
    d, e, f = A[1]
    g, h, i = A[2]
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    return [[(e * i - f * h) / det, (c * h - b * i) / det, (b * f - c * e) / det],
            [(f * g - d * i) / det, (a * i - c * g) / det, (c * d - a * f) / det],
            [(d * h - e * g) / det, (b * g - a * h) / det, (a * e - b * d) / det]]


def pin_cuts(problem, wbox, L):
    """The faces of the pin box that pass through the model (world box wbox), clipped to it,
    as quadrilaterals in gmsh's coordinates (the file's geometry in metres, before the
    transform)."""
    Ainv = inverse3(problem.A)
    to_file = lambda x: tuple(sum(Ainv[r][k] * (x[k] - problem.b[k]) for k in range(3)) for r in range(3))
    margin = 0.01 * L
    cuts = []
    for axis in range(3):
        for side in (0, 1):
            c = problem.pin_box[side][axis]
            if not wbox[0][axis] + 1e-6 * L < c < wbox[1][axis] - 1e-6 * L:
                continue
            o = [k for k in range(3) if k != axis]
            lo = [max(problem.pin_box[0][k], wbox[0][k] - margin) for k in o]
            hi = [min(problem.pin_box[1][k], wbox[1][k] + margin) for k in o]
            if not (lo[0] < hi[0] and lo[1] < hi[1]):
                continue
            quad = []
            for u, v in ((lo[0], lo[1]), (hi[0], lo[1]), (hi[0], hi[1]), (lo[0], hi[1])):
                x = [0.0, 0.0, 0.0]
                x[axis], x[o[0]], x[o[1]] = c, u, v
                quad.append(to_file(x))
            cuts.append(quad)
    return cuts


def run_gmsh(args, workdir, what):
    try:
        r = subprocess.run(["gmsh"] + args, cwd=workdir, capture_output=True, text=True, timeout=SOLVE_TIMEOUT)
    except subprocess.TimeoutExpired:
        raise Fail("gmsh did not finish %s within %g s" % (what, SOLVE_TIMEOUT))
    except OSError as e:
        raise Fail("cannot run gmsh: %s" % e)
    errors = [l.split(":", 1)[1].strip() for l in (r.stdout + r.stderr).splitlines() if l.startswith("Error")]
    return r, errors


def gmsh_solids(workdir, model_path, scaling, sew, cuts):
    """Volumes and faces Open CASCADE makes of the file (cut by `cuts`), the faces that
    bound a volume, and gmsh's error lines."""
    geo = os.path.join(workdir, "solids.geo")
    with open(geo, "w") as f:
        f.write(geo_header(model_path, scaling, sew, cuts))
        f.write("b[] = Unique(Abs(Boundary{ Volume{v[]}; }));\n"
                "Printf(\"SEMVALIDATE %g %g %g\", #v[], #s[], #b[]);\n")
    r, errors = run_gmsh([geo, "-parse_and_exit"], workdir, "reading the model")
    counts = None
    for line in r.stdout.splitlines():
        t = line.split()
        if t[:1] == ["SEMVALIDATE"] and len(t) == 4:
            counts = [int(float(v)) for v in t[1:]]
    if counts is None:
        raise Fail("gmsh could not read it: %s" % (errors[0] if errors else "no output"))
    return counts[0], counts[1], counts[2], errors


def gmsh_mesh(workdir, job, model_path, scaling, sew, cuts, h):
    """Quadratic tetrahedra of characteristic length h: (nodes {tag: x}, [Abaqus C3D10 node lists])."""
    geo = os.path.join(workdir, job + ".geo")
    msh = os.path.join(workdir, job + ".msh")
    with open(geo, "w") as f:
        f.write(geo_header(model_path, scaling, sew, cuts))
        f.write("Physical Volume(1) = {v[]};\n"
                "Mesh.CharacteristicLengthMax = %.17g;\n"
                "Mesh.ElementOrder = 2;\n"
                "Mesh.Optimize = 1;\n"
                "Mesh.MshFileVersion = 2.2;\n" % h)
    t0 = time.time()
    r, errors = run_gmsh(["-3", geo, "-o", msh, "-format", "msh22", "-nt", "2"], workdir, "meshing")
    seconds = time.time() - t0
    if r.returncode != 0 or not os.path.exists(msh):
        raise Fail("gmsh could not mesh it (h %g m): %s" % (h, errors[0] if errors else "exit %d" % r.returncode))
    nodes, raw = fem_common.read_msh22(msh, types=(11,))
    if not raw:
        raise Fail("gmsh made no tetrahedra (h %g m)%s" % (h, ": " + errors[0] if errors else ""))
    elements = [fem_common.gmsh_tet10_to_abaqus(nodes, conn) for _, conn in raw]
    used = set(t for conn in elements for t in conn)
    nodes = {t: nodes[t] for t in used}
    straightened, _ = fem_common.straighten_tet10(nodes, elements)
    return nodes, elements, seconds, straightened


# ---------------------------------------------------------------- FEM side: CalculiX

def write_inp(path, nodes, elements, pinned, surface, problem, E, material, ell):
    """The CalculiX input in a length unit of ell metres (mass kg, time s): CalculiX checks
    its Jacobian determinants against an absolute threshold, which a centimetre-sized model's
    elements in metres fall below. So x' = x / ell, E' = E ell, rho' = rho ell^3, g' = g / ell,
    and displacements come back in units of ell."""
    g = math.sqrt(sum(c * c for c in problem.gravity))
    scaled = {t: tuple(c / ell for c in x) for t, x in nodes.items()}
    with open(path, "w") as f:
        f.write("*HEADING\nsem validate (lengths in units of %g m)\n" % ell)
        fem_common.write_nodes(f, scaled)
        fem_common.write_elements(f, elements, "C3D10")
        fem_common.write_nset(f, "NPIN", pinned)
        fem_common.write_nset(f, "NSURF", surface)
        fem_common.write_material(f, "M", problem.density * ell ** 3, E * ell, problem.nu,
                                  "elastic" if material in ("linear", "stvk") else "neohookean")
        f.write("*SOLID SECTION, ELSET=EALL, MATERIAL=M\n*BOUNDARY\nNPIN, 1, 3\n")
        if material == "linear":
            f.write("*STEP\n*STATIC\n")
        else:
            # NLGEOM; the whole load in one increment, cut back automatically when it does not
            # converge
            f.write("*STEP, NLGEOM, INC=1000\n*STATIC\n1.0, 1.0, 1e-6, 1.0\n")
        f.write(("*DLOAD\nEALL, GRAV, " + ", ".join([fem_common.NUMBER] * 4) + "\n") % (
            g / ell, problem.gravity[0] / g, problem.gravity[1] / g, problem.gravity[2] / g))
        f.write("*NODE PRINT, NSET=NSURF\nU\n*END STEP\n")


def surface_norms(faces, values):
    """Area-weighted L2 norm over the boundary triangles of a nodal vector field {node: v},
    and the largest |v| at a node of the faces."""
    total = 0.0
    for face, area in faces:
        v = [values[t] for t in face]
        for i in range(6):
            row = fem_common.P2_MASS[i]
            for j in range(6):
                if row[j]:
                    total += area * row[j] * fem_common.dot(v[i], v[j])
    nodes = set(t for face, _ in faces for t in face)
    return math.sqrt(max(total, 0.0)), max((fem_common.norm(values[t]) for t in nodes), default=0.0)


class Mesh:
    def __init__(self, nodes_file, elements, problem):
        # world coordinates: the scene's transform of the file's geometry in metres
        self.nodes = {t: apply(problem.A, problem.b, x) for t, x in nodes_file.items()}
        self.elements = elements
        faces = fem_common.tet10_boundary_faces(elements)
        self.faces = [(f, fem_common.triangle_area(*(self.nodes[t] for t in f[:3]))) for f in faces]
        self.surface = sorted(set(t for f, _ in self.faces for t in f))
        lo = [min(self.nodes[t][c] for t in self.surface) for c in range(3)]
        hi = [max(self.nodes[t][c] for t in self.surface) for c in range(3)]
        self.box = [lo, hi]
        # of the straight-sided (corner) tetrahedra: a check of what the FEM fills, not an integral
        self.volume = sum(abs(fem_common.dot(fem_common.cross(fem_common.sub(self.nodes[c[1]], self.nodes[c[0]]),
                                                              fem_common.sub(self.nodes[c[2]], self.nodes[c[0]])),
                                             fem_common.sub(self.nodes[c[3]], self.nodes[c[0]]))) / 6
                          for c in elements)

    def pinned(self, box, eps):
        return [t for t in sorted(self.nodes) if all(box[0][c] - eps <= self.nodes[t][c] <= box[1][c] + eps
                                                      for c in range(3))]


def fem_solve(workdir, job, mesh, problem, E, material, eps):
    pinned = mesh.pinned(problem.pin_box, eps)
    if not pinned:
        raise Fail("no FEM node lies in the pin box %s" % json.dumps(problem.pin_box))
    # a power of ten near the model's size: coordinates of order 1 to 10 in CalculiX
    size = max(mesh.box[1][c] - mesh.box[0][c] for c in range(3))
    ell = 10.0 ** math.floor(math.log10(size))
    write_inp(os.path.join(workdir, job + ".inp"), mesh.nodes, mesh.elements, pinned, mesh.surface, problem, E,
              material, ell)
    threads = max(1, min(8, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 2))
    try:
        seconds = fem_common.run_ccx(workdir, job, threads=threads, timeout=SOLVE_TIMEOUT)
    except ToolFailed as e:
        raise Fail("%s%s" % (e, " (is every solid held by the pins?)" if "singular" in str(e).lower() else ""))
    u = {t: tuple(c * ell for c in v) for t, v in fem_common.read_dat_last_u(os.path.join(workdir, job + ".dat")).items()}
    missing = [t for t in mesh.surface if t not in u]
    if missing:
        raise Fail("CalculiX printed no displacement for %d surface nodes (%s.dat)" % (len(missing), job))
    return u, len(pinned), seconds


# ---------------------------------------------------------------- the comparison

def probe(sem, workdir, rest, frame, points_world, to_frame, slack_frame):
    path = os.path.join(workdir, "surface_points.txt")
    with open(path, "w") as f:
        for x in points_world:
            f.write("%.17g %.17g %.17g\n" % tuple(c * to_frame for c in x))
    out, _ = sem.run(["probe", rest, frame, path, "--slack", "%.17g" % slack_frame], "sem probe")
    rows = []
    for line in out.splitlines():
        t = line.split()
        rows.append((int(t[0]), float(t[1]), float(t[2]), float(t[3]), int(t[4]),
                     (float(t[5]), float(t[6]), float(t[7]))))
    if len(rows) != len(points_world):
        raise Fail("sem probe answered %d points of %d" % (len(rows), len(points_world)))
    return rows


class AtomicFile:
    """A text file written to NAME.tmp.PID and renamed into place when complete, so a reader
    (or an interrupted run) never leaves half a file under the name."""

    def __init__(self, path):
        self.path, self.tmp = path, "%s.tmp.%d" % (path, os.getpid())

    def __enter__(self):
        self.f = open(self.tmp, "w")
        return self.f

    def __exit__(self, kind, value, tb):
        self.f.close()
        if kind is None:
            os.replace(self.tmp, self.path)
        else:
            os.unlink(self.tmp)
        return False


def fmt_len(x):
    return "%.4g m" % x


def text_report(r):
    p, fem, semr, cmp_ = r["problem"], r["fem"], r["sem"], r["comparison"]
    m = p["material"]
    lines = [
        "model     %s (%s, %d parts; largest dimension %s)" % (r["model"], r["file_units"], r["parts"],
                                                               fmt_len(p["size_m"])),
        "problem   gravity (%g, %g, %g) m/s^2, %s, density %g kg/m^3, E %.4g Pa%s, nu %g" % (
            tuple(p["gravity"]) + (m["type"], m["density"], m["youngs_modulus"],
                                   " (" + m["youngs_modulus_rule"] + ")" if m.get("youngs_modulus_rule") else "",
                                   m["poisson_ratio"])),
        "pinned    %s: box %s; FEM %d nodes" % (p["pin"]["rule"], json.dumps(p["pin"]["box"]), fem["pinned_nodes"]),
    ]
    lv = fem["levels"]
    last = lv[-1]
    lines.append("FEM       %d mesh%s, h %s -> %s; finest %d nodes (%d dofs), %d surface nodes; %s; %.1f s" % (
        len(lv), "" if len(lv) == 1 else "es", fmt_len(lv[0]["h"]), fmt_len(last["h"]), last["nodes"], last["dofs"],
        last["surface_nodes"],
        ("converged: last change %.2f %% (L2), %.2f %% (max)" % (100 * last["change_l2"], 100 * last["change_max"]))
        if fem["converged"] else "NOT converged (%s)" % fem["stopped"], fem["seconds"]))
    for k, l in enumerate(lv):
        lines.append("          level %d: h %-9s %6d nodes  L2 %.6g m^2  max %.6g m%s  (mesh %.1f s, CalculiX %.1f s)" % (
            k, fmt_len(l["h"]), l["nodes"], l["l2_norm"], l["max_displacement_m"],
            "" if l["change_l2"] is None else "  change %.2f %% / %.2f %%" % (100 * l["change_l2"], 100 * l["change_max"]),
            l["mesh_s"], l["ccx_s"]))
    lines.append("sem       %d dofs, %d parts; %.1f s (preprocessing %.2f s, static solve %.2f s); volume %.4g m^3, "
                 "%.3f x the FEM mesh's" % (semr["dofs"], r["parts"], semr["seconds"], semr["preprocess_s"],
                                           semr["solve_s"], semr["volume_m3"], cmp_["volume_ratio"]))
    for w in semr["warnings"]:
        lines.append("          " + w)
    lines.append("surface   %d FEM surface nodes: %d on sem's surfaces (farthest %.3g m), %d off them (> %.3g m), "
                 "%d outside every trim" % (cmp_["surface_nodes"], cmp_["nodes_used"], cmp_["max_distance_on_m"],
                                            cmp_["nodes_off_surface"], cmp_["on_surface_tolerance_m"],
                                            cmp_["nodes_outside_trims"]))
    lines.append("error     relative L2 error of the displacement: %.2f %%" % (100 * cmp_["l2_error"]))
    md = cmp_["max_displacement"]
    lines.append("largest   displacement FEM %s, sem %s: ratio sem / FEM %.3f" % (
        fmt_len(md["fem_m"]), fmt_len(md["sem_m"]), md["ratio"]))
    for e in r.get("resolutions") or []:
        if e.get("error"):
            lines.append("resolution %g: %s" % (e["resolution"], e["error"]))
        else:
            lines.append("resolution %-5g %6d dofs, %4s parts: L2 error %.2f %%, largest displacement ratio %.3f "
                         "(%.1f s, %s)" % (e["resolution"], e["dofs"], e["parts"], 100 * e["l2_error"], e["max_ratio"],
                                          e["seconds"], e["status"]))
    if r.get("workdir"):
        lines.append("files     %s" % r["workdir"])
    return "\n".join(lines)


# ---------------------------------------------------------------- main

def validate(args, workdir):
    sem = Sem(args.sem)
    model = os.path.abspath(args.model)
    if not os.path.exists(args.model):
        raise Fail("%s: cannot open: No such file or directory" % args.model)
    if not os.path.isfile(args.model):
        raise Fail("%s: not a regular file" % args.model)
    problem = Problem()
    if args.scene:
        read_scene(args.scene, problem)
    out, _ = sem.run(["inspect", model, "--json"], None)
    info = json.loads(out)
    if not info.get("bbox"):
        raise Fail("%s: sem finds no surface in it" % args.model)
    file_u2m = info["unit_to_meter"]
    u = problem.sem_object.get("units")
    problem.units_factor = file_u2m if u is None else 1.0 if u == "as_metres" else UNITS[u.lower()]
    bbox_file_m = [[c * problem.units_factor for c in corner] for corner in info["bbox"]]
    size_file_m = max(bbox_file_m[1][c] - bbox_file_m[0][c] for c in range(3))
    if not size_file_m > 0:
        raise Fail("%s: the model has no extent" % args.model)

    try:
        fem_common.ensure_tools(not args.no_install, log=log)
    except ToolsMissing as e:
        raise Fail("validate needs gmsh and CalculiX: %s" % e, EXIT_TOOLS)
    tools = {"gmsh": fem_common.tool_version(["gmsh", "--version"]),
             "ccx": fem_common.tool_version(["ccx", "-v"])}

    # the world box and size (after the transform), from sem's box of the surfaces
    corners = [apply(problem.A, problem.b, (bbox_file_m[i][0], bbox_file_m[j][1], bbox_file_m[k][2]))
               for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    wbox = [[min(c[d] for c in corners) for d in range(3)], [max(c[d] for c in corners) for d in range(3)]]
    L = max(wbox[1][d] - wbox[0][d] for d in range(3))
    eps = 1e-9 * L
    if problem.pin_box is None:
        H = wbox[1][2] - wbox[0][2]
        problem.pin_box = [[wbox[0][0] - L, wbox[0][1] - L, wbox[0][2] - L],
                           [wbox[1][0] + L, wbox[1][1] + L, wbox[0][2] + PIN_FRACTION * H]]
        problem.pin_rule = "z in the lowest %g %% of the height (z <= %.6g m)" % (100 * PIN_FRACTION,
                                                                                  problem.pin_box[1][2])
    g = math.sqrt(sum(c * c for c in problem.gravity))
    if not g > 0:
        raise Fail("gravity is zero: nothing to compare")

    # Open CASCADE reads the file in millimetres of the file's own unit
    scaling = 1e-3 * problem.units_factor / file_u2m
    # the file's own solids (STEP files have them; sewing would take them apart), else its
    # faces sewn with growing tolerances (gaps of CAD exports)
    for sew in [None] + [f * size_file_m for f in SEW_TOLERANCES]:
        n_vol, n_surf, n_bound, gmsh_errors = gmsh_solids(workdir, model, scaling, sew, [])
        if n_vol > 0:
            break
    if n_surf == 0:
        raise Fail("%s: gmsh (Open CASCADE) could not read any face of it%s" % (
            args.model, ": " + gmsh_errors[0] if gmsh_errors else ""))
    if n_vol == 0:
        raise Fail("%s: gmsh could not make a solid of its faces (open surfaces or gaps): %d faces, no closed shell "
                   "(sewn with gaps up to %g m)%s" % (args.model, n_surf, sew, "; " + gmsh_errors[0] if gmsh_errors else ""))
    log("gmsh: %d solid%s of %d faces%s%s" % (
        n_vol, "" if n_vol == 1 else "s", n_surf, "" if sew is None else ", sewn with gaps up to %s" % fmt_len(sew),
        "" if n_bound >= n_surf else " (%d faces bound no solid)" % (n_surf - n_bound)))
    # the mesh follows the boundary of the pinned region (else the pinned nodes, and so the
    # answer, would jump with the mesh); where Open CASCADE cannot cut, it does not
    cuts = pin_cuts(problem, wbox, L)
    if cuts:
        n_cut, _, _, cut_errors = gmsh_solids(workdir, model, scaling, sew, cuts)
        if n_cut <= n_vol or cut_errors:
            log("gmsh could not cut the solids along the pin box (%s): the pinned nodes follow the mesh" % (
                cut_errors[0] if cut_errors else "%d solids after the cut" % n_cut))
            cuts = []
    h0 = args.h0 if args.h0 else size_file_m / 10

    # FEM level 0, and E by the 1 % rule when neither the scene nor -E gives it
    t_fem = time.time()
    h = h0
    # gmsh fails on some shapes at coarse sizes (a boundary mesh that intersects itself) or
    # along the cut: the first mesh takes the first that works of h0, 0.7 h0, 0.49 h0, each
    # with the cut and then without
    first_error = None
    for attempt in range(3):
        for with_cuts in ([True, False] if cuts else [False]):
            try:
                nodes, elements, mesh_s, straightened = gmsh_mesh(workdir, "level0", model, scaling, sew,
                                                                   cuts if with_cuts else [], h)
                break
            except Fail as e:
                first_error = first_error or e
                log(str(e))
        else:
            h *= REFINE_FACTOR
            continue
        if not with_cuts and cuts:
            log("meshed without the cut along the pin box: the pinned nodes follow the mesh")
            cuts = []
        break
    else:
        # Open CASCADE also makes "solids" of open shells, which then do not mesh
        raise Fail("%s: gmsh made a solid of its faces but could not mesh it (open surfaces or gaps, or a shape its "
                   "mesher does not take): %s" % (args.model, first_error))
    if len(nodes) > args.max_nodes:
        raise Fail("the coarsest mesh (h %g m) has %d nodes, more than --max-nodes %d: give a larger --h0 or "
                   "--max-nodes" % (h, len(nodes), args.max_nodes))
    mesh = Mesh(nodes, elements, problem)
    mismatch = max(abs(mesh.box[s][d] - wbox[s][d]) for s in (0, 1) for d in range(3))
    if mismatch > 0.02 * L:
        raise Fail("gmsh and sem read %s at different places or sizes: mesh box %s m, sem's box %s m" % (
            args.model, json.dumps([[round(v, 6) for v in c] for c in mesh.box]),
            json.dumps([[round(v, 6) for v in c] for c in wbox])))
    if args.youngs_modulus:
        problem.E = args.youngs_modulus
        problem.E_rule = "--youngs-modulus"
    elif problem.E is None:
        E0 = 100 * problem.density * g * L
        try:
            u0, _, _ = fem_solve(workdir, "estimate_E", mesh, problem, E0, "linear", eps)
        except Fail as e:
            raise Fail("%s: %s" % (args.model, e))
        d0 = max(fem_common.norm(u0[t]) for t in mesh.surface)
        if not d0 > 0:
            raise Fail("the linear FEM solve with E %g Pa moves nothing" % E0)
        problem.E = E0 * d0 / (SAG_FRACTION * L)
        problem.E_rule = "largest displacement ~%g %% of %s" % (100 * SAG_FRACTION, fmt_len(L))
        log("E %.4g Pa: a linear solve with E %.4g Pa moved the surface by up to %s" % (problem.E, E0, fmt_len(d0)))

    # sem side, before the FEM refinement: its errors come early
    semdir = os.path.join(workdir, "sem")
    obj = dict(problem.sem_object)
    obj["model"] = model
    obj["material"] = {"type": problem.material, "density": problem.density, "youngs_modulus": problem.E,
                       "poisson_ratio": problem.nu}
    obj["pin"] = {"box": problem.pin_box}
    integrator = {"type": "static", "dt": 1.0, "max_iterations": 200}
    integrator.update({k: v for k, v in problem.integrator.items() if k != "threads"})
    scene = {"description": "sem validate: static sag of %s" % os.path.basename(model), "objects": [obj],
             "gravity": list(problem.gravity), "integrator": integrator, "frames": 1,
             "output": {"dir": semdir, "iges": True, "obj": False, "mesh": False, "usd": False, "glb": False}}
    if "threads" in problem.integrator:
        scene["threads"] = problem.integrator["threads"]
    scene_path = os.path.join(workdir, "sem_scene.json")
    with open(scene_path, "w") as f:
        json.dump(scene, f, indent=1)
    log("sem: static solve")
    t0 = time.time()
    out, err = sem.run(["run", scene_path, "--out", semdir, "--overwrite", "--json", "--quiet"], "sem run")
    sem_seconds = time.time() - t0
    summary = json.loads(out)
    sem_warnings = [l[5:] for l in err.splitlines() if l.startswith("sem: warning:")]
    f2m = summary["frame_unit_to_meter"]
    rest, frame = os.path.join(semdir, "frame_0000.igs"), os.path.join(semdir, "frame_0001.igs")
    log("sem: %d dofs, %.1f s" % (summary["dofs"], sem_seconds))

    # FEM refinement
    levels, converged, stopped = [], False, None
    while True:
        k = len(levels)
        if k > 0:
            try:
                nodes, elements, mesh_s, straightened = gmsh_mesh(workdir, "level%d" % k, model, scaling, sew,
                                                                  cuts, h)
            except Fail as e:
                stopped = str(e)
                break
            if len(nodes) > args.max_nodes:
                stopped = "the next mesh (h %g m) has %d nodes, more than --max-nodes %d" % (h, len(nodes), args.max_nodes)
                break
            mesh = Mesh(nodes, elements, problem)
        try:
            u_k, n_pinned, ccx_s = fem_solve(workdir, "level%d" % k, mesh, problem, problem.E, problem.material, eps)
        except Fail as e:
            if k == 0:
                raise Fail("%s: %s" % (args.model, e))
            stopped = str(e)
            break
        u, solved_mesh = u_k, mesh
        l2, umax = surface_norms(mesh.faces, u)
        prev = levels[-1] if levels else None
        ch_l2 = None if prev is None else abs(l2 / prev["l2_norm"] - 1)
        ch_max = None if prev is None else abs(umax / prev["max_displacement_m"] - 1)
        levels.append({"h": h, "nodes": len(mesh.nodes), "elements": len(mesh.elements), "dofs": 3 * len(mesh.nodes),
                       "surface_nodes": len(mesh.surface), "straightened_elements": straightened,
                       "volume_m3": mesh.volume,
                       "pinned_nodes": n_pinned, "l2_norm": l2,
                       "max_displacement_m": umax, "change_l2": ch_l2, "change_max": ch_max,
                       "mesh_s": round(mesh_s, 2), "ccx_s": round(ccx_s, 2)})
        log("FEM level %d: h %s, %d nodes: L2 %.6g, max %s%s (CalculiX %.1f s)" % (
            k, fmt_len(h), len(mesh.nodes), l2, fmt_len(umax),
            "" if ch_l2 is None else ", change %.2f %% / %.2f %%" % (100 * ch_l2, 100 * ch_max), ccx_s))
        if ch_l2 is not None and ch_l2 < args.tolerance and ch_max < args.tolerance:
            converged = True
            break
        if len(levels) >= args.max_levels:
            stopped = "--max-levels %d reached" % args.max_levels
            break
        h *= REFINE_FACTOR
        if 2.9 * len(mesh.nodes) > 1.5 * args.max_nodes:
            stopped = "the next mesh would have about %d nodes, more than --max-nodes %d" % (
                2.9 * len(mesh.nodes), args.max_nodes)
            break
    fem_seconds = time.time() - t_fem
    if not converged:
        print("sem: warning: validate: the FEM solution did not converge to --tolerance %g: %s" % (
            args.tolerance, stopped), file=sys.stderr)
    fem_mesh, fem_u = solved_mesh, u   # the finest level solved

    # sem at the FEM surface nodes
    tol_on = ON_SURFACE * L
    ids = fem_mesh.surface
    rows = probe(sem, workdir, rest, frame, [fem_mesh.nodes[t] for t in ids], 1.0 / f2m, tol_on / f2m)
    u_sem, info_node, used = {}, {}, set()
    max_on = 0.0
    for t, (part, uu, vv, dist, inside, x) in zip(ids, rows):
        X = fem_mesh.nodes[t]
        dist *= f2m
        u_sem[t] = tuple(x[c] * f2m - X[c] for c in range(3))
        info_node[t] = (part, dist, inside)
        if part >= 0 and dist <= tol_on:
            used.add(t)
            max_on = max(max_on, dist)
    faces_used = [(f, a) for f, a in fem_mesh.faces if all(t in used for t in f)]
    if not faces_used:
        raise Fail("no FEM surface node lies on sem's surfaces (within %s)" % fmt_len(tol_on))
    diff = {t: tuple(u_sem[t][c] - fem_u[t][c] for c in range(3)) for t in used}
    l2_fem, max_fem = surface_norms(faces_used, fem_u)
    l2_sem, max_sem = surface_norms(faces_used, u_sem)
    l2_diff, max_diff = surface_norms(faces_used, diff)
    off = [t for t in ids if t not in used]

    # per-node data for other tools (and the tests)
    with AtomicFile(os.path.join(workdir, "surface_nodes.csv")) as f:
        f.write("node,x,y,z,ux_fem,uy_fem,uz_fem,ux_sem,uy_sem,uz_sem,distance,part,inside_trim,used\n")
        for t in ids:
            part, dist, inside = info_node[t]
            f.write("%d,%s,%s,%d,%d,%d\n" % (
                t, ",".join("%.17g" % c for c in fem_mesh.nodes[t] + fem_u[t] + u_sem[t]), "%.6g" % dist, part,
                inside, t in used))
    with AtomicFile(os.path.join(workdir, "surface_faces.csv")) as f:
        f.write("n1,n2,n3,n12,n23,n31\n")
        for face, _ in fem_mesh.faces:
            f.write(",".join(str(t) for t in face) + "\n")

    # the accuracy setting: sem again at each resolution, against the same FEM answer
    sweep = []
    for R in args.resolution_list:
        sdir = os.path.join(workdir, "sem_r%g" % R)
        sc = json.loads(json.dumps(scene))
        sc["objects"][0].setdefault("sem", {})["resolution"] = R
        sc["output"]["dir"] = sdir
        spath = os.path.join(workdir, "sem_scene_r%g.json" % R)
        with open(spath, "w") as f:
            json.dump(sc, f, indent=1)
        log("sem: static solve at resolution %g" % R)
        t0 = time.time()
        try:
            o2, e2 = sem.run(["run", spath, "--out", sdir, "--overwrite", "--json", "--quiet"], "sem run")
        except Fail as e:
            sweep.append({"resolution": R, "error": str(e)})
            continue
        secs = time.time() - t0
        s2 = json.loads(o2)
        r2 = probe(sem, workdir, os.path.join(sdir, "frame_0000.igs"), os.path.join(sdir, "frame_0001.igs"),
                   [fem_mesh.nodes[t] for t in ids], 1.0 / f2m, tol_on / f2m)
        us = {}
        for t, (part, uu, vv, dist, inside, x) in zip(ids, r2):
            if t in used:
                us[t] = tuple(x[c] * f2m - fem_mesh.nodes[t][c] for c in range(3))
        fu = [(f, a) for f, a in faces_used if all(t in us for t in f)]
        d2 = {t: tuple(us[t][c] - fem_u[t][c] for c in range(3)) for t in us}
        lf, mf = surface_norms(fu, fem_u)
        ls, ms = surface_norms(fu, us)
        ld, _ = surface_norms(fu, d2)
        entry = {"resolution": R, "dofs": s2["dofs"], "parts": (s2.get("objects") or [{}])[0].get("parts"),
                 "seconds": round(secs, 2), "solve_s": s2.get("mean_step_s"), "status": s2.get("status"),
                 "l2_error": ld / lf if lf > 0 else None, "max_ratio": ms / mf if mf > 0 else None}
        sweep.append(entry)
        log("sem at resolution %g: %d dofs, L2 error %.1f %%, largest displacement ratio %.3f (%.1f s)" % (
            R, entry["dofs"], 100 * (entry["l2_error"] or 0), entry["max_ratio"] or 0, secs))

    frames = summary.get("frames") or []
    return {
        "resolutions": sweep,
        "model": args.model,
        "scene": args.scene,
        "file_units": info.get("units"),
        "file_unit_to_meter": file_u2m,
        "parts": info.get("parts"),
        "problem": {
            "size_m": L,
            "bbox_m": wbox,
            "gravity": list(problem.gravity),
            "material": {"type": problem.material, "density": problem.density, "youngs_modulus": problem.E,
                         "poisson_ratio": problem.nu, "youngs_modulus_rule": problem.E_rule,
                         "calculix": "*ELASTIC" if problem.material in ("linear", "stvk") else "*HYPERELASTIC, NEO HOOKE",
                         "nlgeom": problem.material != "linear"},
            "pin": {"box": problem.pin_box, "rule": problem.pin_rule,
                    "mesh_cut_along_box": bool(cuts)},
        },
        "fem": {
            "tools": tools,
            "solids": n_vol,
            "sewing_tolerance_m": sew,
            "faces": n_surf,
            "faces_without_solid": max(0, n_surf - n_bound),
            "element": "C3D10",
            "tolerance": args.tolerance,
            "converged": converged,
            "stopped": stopped,
            "levels": levels,
            "nodes": levels[-1]["nodes"],
            "dofs": levels[-1]["dofs"],
            "pinned_nodes": levels[-1]["pinned_nodes"],
            "seconds": round(fem_seconds, 2),
        },
        "sem": {
            "dofs": summary["dofs"],
            "seconds": round(sem_seconds, 2),
            "preprocess_s": summary.get("preprocess_s"),
            "solve_s": summary.get("mean_step_s"),
            "preprocess_cached": summary.get("preprocess_cached"),
            "volume_m3": summary.get("volume"),
            "solver": (summary.get("objects") or [{}])[0].get("solver"),
            "elastic_energy_j": frames[-1].get("elastic_energy") if frames else None,
            "warnings": sem_warnings,
        },
        "comparison": {
            "surface_nodes": len(ids),
            "nodes_used": len(used),
            "nodes_off_surface": len(off),
            "on_surface_tolerance_m": tol_on,
            "max_distance_on_m": max_on,
            "max_distance_off_m": max((info_node[t][1] for t in off), default=None),
            "nodes_outside_trims": sum(1 for t in used if not info_node[t][2]),
            "volume_ratio": (summary.get("volume") or 0) / fem_mesh.volume,
            "faces_used": len(faces_used),
            "faces": len(fem_mesh.faces),
            "l2_norm_fem": l2_fem,
            "l2_norm_sem": l2_sem,
            "l2_norm_difference": l2_diff,
            "l2_error": l2_diff / l2_fem if l2_fem > 0 else None,
            "max_difference_m": max_diff,
            "max_displacement": {"fem_m": max_fem, "sem_m": max_sem,
                                 "ratio": max_sem / max_fem if max_fem > 0 else None,
                                 "relative_error": abs(max_sem - max_fem) / max_fem if max_fem > 0 else None},
        },
    }


def main(argv):
    global QUIET
    args = parse_args(argv)
    QUIET = args.quiet
    temporary = args.workdir is None
    workdir = None
    code = 0
    try:
        if temporary:
            workdir = tempfile.mkdtemp(prefix="sem_validate_")
        else:
            workdir = os.path.abspath(args.workdir)
            try:
                os.makedirs(workdir, exist_ok=True)
            except OSError as e:
                raise Fail("%s: cannot create the folder: %s" % (args.workdir, e.strerror))
        report = validate(args, workdir)
        report["workdir"] = workdir if (not temporary or args.keep) else None
        if args.json:
            print(json.dumps(report, indent=2))
        else:
            print(text_report(report))
    except Fail as e:
        print("sem: %s" % one_line(e), file=sys.stderr)
        code = e.code
    except KeyboardInterrupt:
        print("sem: validate: interrupted", file=sys.stderr)
        code = 130
    except OSError as e:
        print("sem: validate: %s" % one_line(e), file=sys.stderr)
        code = EXIT_FAILED
    finally:
        if temporary and workdir and not args.keep:
            shutil.rmtree(workdir, ignore_errors=True)
    return code


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
