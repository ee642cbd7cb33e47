"""Pieces shared by the FEM scripts (cantilever.py, validate.py): gmsh meshes in, CalculiX
input out, CalculiX results back. Python standard library only.

gmsh and CalculiX come from Debian (packages gmsh, calculix-ccx); ensure_tools installs
them with apt-get when missing and allowed to. Nothing here links them into sem: they run as
programs on files in a work folder.
"""
import math
import os
import shutil
import subprocess
import time

PACKAGES = (("gmsh", "gmsh"), ("ccx", "calculix-ccx"))


class ToolsMissing(Exception):
    """gmsh or CalculiX is not installed and could not (or may not) be installed."""


class ToolFailed(Exception):
    """gmsh or CalculiX ran but failed; the message is one line."""


def ensure_tools(install, log=None):
    """Makes sure `gmsh` and `ccx` are on the PATH, installing the Debian packages with
    apt-get when install is true. Raises ToolsMissing (message: what is missing and why)."""
    missing = [pkg for tool, pkg in PACKAGES if shutil.which(tool) is None]
    if not missing:
        return
    hint = "apt-get install %s" % " ".join(missing)
    if not install:
        raise ToolsMissing("missing %s (%s)" % (", ".join(missing), hint))
    if shutil.which("apt-get") is None:
        raise ToolsMissing("missing %s and there is no apt-get to install it (%s)" % (", ".join(missing), hint))
    if log:
        log("installing %s with apt-get" % " ".join(missing))
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    prefix = [] if os.geteuid() == 0 else ["sudo", "-n"]
    for cmd in (["apt-get", "update", "-qq"], ["apt-get", "install", "-y", "-qq"] + missing):
        try:
            run = subprocess.run(prefix + cmd, env=env, capture_output=True, text=True)
        except OSError as e:
            raise ToolsMissing("missing %s; %s failed: %s" % (", ".join(missing), " ".join(cmd[:2]), e))
        if run.returncode != 0:
            lines = [l for l in (run.stderr + run.stdout).splitlines() if l.strip()]
            raise ToolsMissing("missing %s; %s failed: %s" % (
                ", ".join(missing), " ".join(prefix + cmd[:2]), lines[-1] if lines else "exit %d" % run.returncode))
    still = [pkg for tool, pkg in PACKAGES if shutil.which(tool) is None]
    if still:
        raise ToolsMissing("missing %s after apt-get install" % ", ".join(still))


def tool_version(cmd):
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        return "unknown"
    for line in (out.stdout + out.stderr).splitlines():
        line = line.strip()
        if line:
            return line
    return "unknown"


# ---------------------------------------------------------------- small vectors

def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def norm(a):
    return math.sqrt(dot(a, a))


# ---------------------------------------------------------------- meshes (gmsh)

def read_msh22(path, types=(11, 17)):
    """Nodes {tag: (x, y, z)} and the elements of the given gmsh types [(type, [node tags])]
    of a MSH 2.2 file (11: 10-node tetrahedron, 17: 20-node hexahedron)."""
    nodes, elems = {}, []
    with open(path) as f:
        lines = iter(f.read().splitlines())
    for line in lines:
        if line == "$Nodes":
            n = int(next(lines))
            for _ in range(n):
                t = next(lines).split()
                nodes[int(t[0])] = (float(t[1]), float(t[2]), float(t[3]))
        elif line == "$Elements":
            n = int(next(lines))
            for _ in range(n):
                t = [int(v) for v in next(lines).split()]
                etype, ntags = t[1], t[2]
                if etype in types:
                    elems.append((etype, t[3 + ntags:]))
    return nodes, elems


# Abaqus/CalculiX node orders, 0-based: corners first, then the mid-edge nodes of these edges.
TET10_EDGES = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]
HEX20_EDGES = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4),
               (0, 4), (1, 5), (2, 6), (3, 7)]
TET10_FACES = [(0, 1, 2), (0, 1, 3), (1, 2, 3), (0, 2, 3)]
HEX20_FACES = [(0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
# gmsh's 10-node tetrahedron: mid-edge nodes 4..9 on these edges (gmsh manual, "Node
# ordering"); Abaqus has the last two the other way round.
GMSH_TET10_EDGES = [(0, 1), (1, 2), (2, 0), (3, 0), (2, 3), (1, 3)]


def to_abaqus(nodes, etype, conn):
    """Reorders one element of straight-edged geometry into the Abaqus convention. Mid-edge
    nodes are matched to their edge geometrically (each is the exact midpoint of its two
    corners), which does not depend on gmsh's internal edge numbering. Curved elements (CAD
    geometry) need gmsh_tet10_to_abaqus."""
    nc, edges = (4, TET10_EDGES) if etype == 11 else (8, HEX20_EDGES)
    corners = list(conn[:nc])
    if etype == 11:
        a, b, c, d = (nodes[t] for t in corners)
        if dot(cross(sub(b, a), sub(c, a)), sub(d, a)) < 0:
            corners[1], corners[2] = corners[2], corners[1]
    mids = conn[nc:]
    out = list(corners)
    for i, j in edges:
        pi, pj = nodes[corners[i]], nodes[corners[j]]
        m = ((pi[0] + pj[0]) / 2, (pi[1] + pj[1]) / 2, (pi[2] + pj[2]) / 2)
        best = min(mids, key=lambda t: sum((nodes[t][k] - m[k]) ** 2 for k in range(3)))
        if sum((nodes[best][k] - m[k]) ** 2 for k in range(3)) > 1e-10:
            raise RuntimeError("mid-edge node not found for edge %d-%d" % (i, j))
        out.append(best)
    return out


def gmsh_tet10_to_abaqus(nodes, conn):
    """One gmsh 10-node tetrahedron in the Abaqus order (C3D10), by gmsh's edge numbering
    (valid for curved elements), with corners 1 and 2 swapped when the corner tetrahedron is
    negatively oriented."""
    mid = {}
    for k, (i, j) in enumerate(GMSH_TET10_EDGES):
        mid[frozenset((conn[i], conn[j]))] = conn[4 + k]
    corners = list(conn[:4])
    a, b, c, d = (nodes[t] for t in corners)
    if dot(cross(sub(b, a), sub(c, a)), sub(d, a)) < 0:
        corners[1], corners[2] = corners[2], corners[1]
    return corners + [mid[frozenset((corners[i], corners[j]))] for i, j in TET10_EDGES]


def _tet10_derivatives(r, s, t):
    """d N_i / d(r, s, t) of the 10 Abaqus-ordered quadratic shape functions."""
    L = (1 - r - s - t, r, s, t)
    dL = ((-1, -1, -1), (1, 0, 0), (0, 1, 0), (0, 0, 1))
    d = [tuple((4 * L[i] - 1) * dL[i][k] for k in range(3)) for i in range(4)]
    for i, j in TET10_EDGES:
        d.append(tuple(4 * (L[i] * dL[j][k] + L[j] * dL[i][k]) for k in range(3)))
    return d


# CalculiX's 4-point rule for C3D10 (where it checks the Jacobian) and the centroid
_A, _B = 0.1381966011250105, 0.5854101966249685
_TET10_CHECK = [_tet10_derivatives(*p) for p in ((_A, _A, _A), (_B, _A, _A), (_A, _B, _A), (_A, _A, _B),
                                                 (0.25, 0.25, 0.25))]


def tet10_min_jacobian_ratio(nodes, conn):
    """The smallest Jacobian determinant of a C3D10 element at CalculiX's integration points
    (and the centroid), relative to that of its straight-sided (corner) tetrahedron."""
    X = [nodes[t] for t in conn]
    v0 = dot(cross(sub(X[1], X[0]), sub(X[2], X[0])), sub(X[3], X[0]))
    worst = math.inf
    for d in _TET10_CHECK:
        J = [[sum(d[n][k] * X[n][i] for n in range(10)) for k in range(3)] for i in range(3)]
        det = (J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) - J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0])
               + J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]))
        worst = min(worst, det / v0 if v0 > 0 else -math.inf)
    return worst


def straighten_tet10(nodes, elements, min_ratio=0.05, passes=5):
    """Curved quadratic tetrahedra at a curved boundary can fold (gmsh places the mid-edge
    nodes on the surface; a flat element there turns inside out), which CalculiX refuses.
    Each element whose Jacobian ratio (tet10_min_jacobian_ratio) is below min_ratio gets its
    mid-edge nodes moved to the midpoints of its corners (straight edges: a valid element).
    Modifies nodes; returns (elements straightened, the set of moved nodes)."""
    moved, fixed = set(), set()
    todo = list(range(len(elements)))
    for _ in range(passes):
        bad = [e for e in todo if tet10_min_jacobian_ratio(nodes, elements[e]) < min_ratio]
        if not bad:
            break
        touched = set()
        for e in bad:
            conn = elements[e]
            fixed.add(e)
            for k, (i, j) in enumerate(TET10_EDGES):
                a, b = nodes[conn[i]], nodes[conn[j]]
                nodes[conn[4 + k]] = ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2)
                moved.add(conn[4 + k])
                touched.add(conn[4 + k])
        # a moved node may change the neighbours that share it: check those again
        todo = [e for e, conn in enumerate(elements) if any(t in touched for t in conn[4:])]
    return len(fixed), moved


def tet10_boundary_faces(elements):
    """The boundary of a mesh of Abaqus-ordered C3D10 elements: the 6-node triangles (3
    corners, then the mid nodes of edges 01, 12, 20) that belong to exactly one element,
    oriented outwards."""
    seen = {}
    for conn in elements:
        for face in ((0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)):  # outward for a positive tet
            c = [conn[i] for i in face]
            key = frozenset(c)
            if key in seen:
                seen[key] = None
                continue
            mids = []
            for p, q in ((0, 1), (1, 2), (2, 0)):
                i, j = face[p], face[q]
                for k, (a, b) in enumerate(TET10_EDGES):
                    if (a, b) == (i, j) or (a, b) == (j, i):
                        mids.append(conn[4 + k])
            seen[key] = c + mids
    return [f for f in seen.values() if f is not None]


# 6-node triangle (corners 0-2, mids 3: edge 01, 4: edge 12, 5: edge 20): the consistent mass
# matrix divided by the triangle's area, exact for the quadratic interpolant on a flat triangle
# (integral of phi_i phi_j dA = A * P2_MASS[i][j]).
P2_MASS = [[v / 180.0 for v in row] for row in (
    (6, -1, -1, 0, -4, 0),
    (-1, 6, -1, 0, 0, -4),
    (-1, -1, 6, -4, 0, 0),
    (0, 0, -4, 32, 16, 16),
    (-4, 0, 0, 16, 32, 16),
    (0, -4, 0, 16, 16, 32))]


def triangle_area(p0, p1, p2):
    return 0.5 * norm(cross(sub(p1, p0), sub(p2, p0)))


# ---------------------------------------------------------------- CalculiX

def lame(E, nu):
    """mu, lambda and the bulk modulus K of E and nu."""
    mu = E / (2 * (1 + nu))
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    K = E / (3 * (1 - 2 * nu))
    return mu, lam, K


# CalculiX reads at most 20 characters of a number: "-1.234567890123e-05" is 19
NUMBER = "%.13g"


def write_nodes(f, nodes, ids=None):
    f.write("*NODE, NSET=NALL\n")
    for t in (sorted(nodes) if ids is None else ids):
        x, y, z = nodes[t]
        f.write(("%d, " + ", ".join([NUMBER] * 3) + "\n") % (t, x, y, z))


def write_elements(f, elements, type_name):
    """elements: [node lists] numbered 1.. in order."""
    f.write("*ELEMENT, TYPE=%s, ELSET=EALL\n" % type_name)
    for k, conn in enumerate(elements, start=1):
        items = [str(k)] + [str(t) for t in conn]
        # Abaqus input lines hold at most 16 entries; continue on the next line
        f.write(", ".join(items[:16]))
        if len(items) > 16:
            f.write(",\n" + ", ".join(items[16:]))
        f.write("\n")


def write_nset(f, name, ids):
    f.write("*NSET, NSET=%s\n" % name)
    for i in range(0, len(ids), 16):
        f.write(", ".join(str(t) for t in ids[i:i + 16]) + "\n")


def write_material(f, name, density, E, nu, model):
    """model: "neohookean" (*HYPERELASTIC, NEO HOOKE: C10 = mu / 2, D1 = 2 / K) or "elastic"
    (*ELASTIC: linear isotropic; under NLGEOM CalculiX makes it St. Venant-Kirchhoff)."""
    mu, lam, K = lame(E, nu)
    f.write(("*MATERIAL, NAME=%s\n*DENSITY\n" + NUMBER + "\n") % (name, density))
    if model == "elastic":
        f.write(("*ELASTIC\n" + NUMBER + ", " + NUMBER + "\n") % (E, nu))
    else:
        f.write(("*HYPERELASTIC, NEO HOOKE\n" + NUMBER + ", " + NUMBER + "\n") % (mu / 2, 2 / K))


def read_dat_last_u(path):
    """Displacements of the last printed block: {node: (ux, uy, uz)}."""
    u, cur = {}, None
    with open(path) as f:
        for line in f:
            s = line.strip()
            if s.startswith("displacements"):
                cur = {}
                u = cur
                continue
            if cur is None or not s:
                continue
            t = s.split()
            if len(t) == 4:
                try:
                    cur[int(t[0])] = tuple(float(v) for v in t[1:])
                except ValueError:
                    cur = None
    return u


def run_ccx(workdir, job, threads=2, timeout=None):
    """Runs `ccx -i job` in workdir; returns the wall time in seconds. Raises ToolFailed with
    the last line CalculiX printed about the failure, or on timeout."""
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), CCX_NPROC_EQUATION_SOLVER=str(threads))
    t0 = time.time()
    try:
        run = subprocess.run(["ccx", "-i", job], cwd=workdir, capture_output=True, text=True, env=env,
                             timeout=timeout)
    except subprocess.TimeoutExpired:
        raise ToolFailed("CalculiX did not finish %s within %g s" % (job, timeout))
    seconds = time.time() - t0
    if run.returncode != 0 or "Job finished" not in run.stdout:
        lines = [l.strip() for l in (run.stdout + run.stderr).splitlines() if l.strip()]
        why = [l for l in lines if "error" in l.lower()] or lines[-1:] or ["exit %d" % run.returncode]
        raise ToolFailed("CalculiX failed on %s: %s" % (job, why[-1]))
    return seconds
