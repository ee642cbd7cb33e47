#!/usr/bin/env python3
"""FEM reference for the SEM deflection study (paper Fig. 10): the 5 x 1 x 1 m cantilever.

Meshes the beam with gmsh (quadratic tetrahedra C3D10, or 20-node hexahedra C3D20R with
--element C3D20R) and solves it with CalculiX:
  clamped at x = 0 (every node of that face fixed), gravity 10 m/s^2 along -z, rho 1000,
  compressible neo-Hookean E = 1e6 Pa, nu = 0.45, geometric nonlinearity (*STATIC, NLGEOM).

CalculiX's NEO HOOKE is psi = C10 (I1bar - 3) + (J - 1)^2 / D1 with the isochoric invariant
I1bar = J^(-2/3) I1, C10 = mu / 2, D1 = 2 / K, K = E / (3 (1 - 2 nu)). The paper's (and
sem's) neo-Hookean is psi = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2. Both have the same
linearisation at F = I (same E and nu), they differ only at finite strain; see
docs/validation.md for how much that matters here.

The mesh is refined (characteristic length h times --factor per level) until the tip
deflection changes by less than --tolerance (0.5 %) between two levels, after at least
--min-levels meshes. The tip
deflection is the area-weighted mean of -u_z over the free end face x = 5 (the exact
integral of the quadratic displacement field over the face), like the SEM side which
averages the free-end control points.

A second, linear case validates the pipeline itself: linear elastic material, no NLGEOM, same
gravity, compared with Euler-Bernoulli w = q L^4 / (8 E I) and Timoshenko
w = q L^4 / (8 E I) + q L^2 / (2 kappa G A).

Only the Python standard library is used. gmsh and CalculiX come from Debian
(packages gmsh, calculix-ccx); the script installs them with apt-get when missing
(--no-install to refuse).

usage: tools/fem/cantilever.py [--out validation/fem_cantilever.json] [--element C3D10|C3D20R]
                               [--h0 0.5] [--factor 0.7] [--min-h 0.08] [--tolerance 0.005]
                               [--min-levels 5]
                               [--workdir DIR] [--keep] [--no-install]
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
from fem_common import (HEX20_EDGES, HEX20_FACES, TET10_EDGES, TET10_FACES, cross, read_dat_last_u,  # noqa: E402
                        read_msh22, sub, to_abaqus, tool_version)

LENGTH, WIDTH, HEIGHT = 5.0, 1.0, 1.0
RHO, GRAVITY = 1000.0, 10.0
E, NU = 1.0e6, 0.45


def lame():
    return fem_common.lame(E, NU)


def ensure_tools(install):
    try:
        fem_common.ensure_tools(install, log=lambda m: print(m, file=sys.stderr))
    except fem_common.ToolsMissing as e:
        sys.exit("cantilever.py: %s" % e)


# ---------------------------------------------------------------- meshing (gmsh)

def geo_tet(h):
    return """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, %g, %g, %g};
Physical Volume(1) = {1};
Mesh.CharacteristicLengthMax = %g;
Mesh.CharacteristicLengthMin = %g;
Mesh.ElementOrder = 2;
Mesh.Optimize = 1;
Mesh.MshFileVersion = 2.2;
""" % (LENGTH, WIDTH, HEIGHT, h, 0.5 * h)


def geo_hex(h):
    nx = max(1, round(LENGTH / h))
    ny = max(1, round(WIDTH / h))
    nz = max(1, round(HEIGHT / h))
    return """Point(1) = {0, 0, 0};
l[] = Extrude {0, %g, 0} { Point{1}; Layers{%d}; };
s[] = Extrude {0, 0, %g} { Line{l[1]}; Layers{%d}; Recombine; };
v[] = Extrude {%g, 0, 0} { Surface{s[1]}; Layers{%d}; Recombine; };
Physical Volume(1) = {v[1]};
Mesh.ElementOrder = 2;
Mesh.SecondOrderIncomplete = 1;
Mesh.MshFileVersion = 2.2;
""" % (WIDTH, ny, HEIGHT, nz, LENGTH, nx)


def tip_face_weights(nodes, elements):
    """Integration weights of the free end face x = L: {node: weight}, sum = face area.
    Exact for the quadratic field on flat faces: 6-node triangle corner 0, mid A/3;
    8-node parallelogram corner -A/12, mid A/3."""
    w = {}
    on_tip = lambda t: abs(nodes[t][0] - LENGTH) < 1e-9
    for etype, conn in elements:
        nc = 4 if etype == 11 else 8
        edges = TET10_EDGES if etype == 11 else HEX20_EDGES
        for face in (TET10_FACES if etype == 11 else HEX20_FACES):
            if not all(on_tip(conn[i]) for i in face):
                continue
            p = [nodes[conn[i]] for i in face]
            if len(face) == 3:
                area = 0.5 * math.sqrt(sum(c * c for c in cross(sub(p[1], p[0]), sub(p[2], p[0]))))
                corner_w, mid_w = 0.0, area / 3
            else:
                area = math.sqrt(sum(c * c for c in cross(sub(p[1], p[0]), sub(p[3], p[0]))))
                corner_w, mid_w = -area / 12, area / 3
            fs = set(face)
            for i in face:
                w[conn[i]] = w.get(conn[i], 0.0) + corner_w
            for k, (i, j) in enumerate(edges):
                if i in fs and j in fs:
                    t = conn[nc + k]
                    w[t] = w.get(t, 0.0) + mid_w
    return w


# ---------------------------------------------------------------- solving (CalculiX)

def write_inp(path, nodes, elements, etype_name, linear):
    with open(path, "w") as f:
        f.write("*HEADING\nSEM validation cantilever 5 x 1 x 1 m\n")
        fem_common.write_nodes(f, nodes)
        fem_common.write_elements(f, [conn for _, conn in elements], etype_name)
        clamp = [t for t in sorted(nodes) if abs(nodes[t][0]) < 1e-9]
        tip = [t for t in sorted(nodes) if abs(nodes[t][0] - LENGTH) < 1e-9]
        fem_common.write_nset(f, "NCLAMP", clamp)
        fem_common.write_nset(f, "NTIP", tip)
        fem_common.write_material(f, "RUBBER", RHO, E, NU, "elastic" if linear else "neohookean")
        f.write("*SOLID SECTION, ELSET=EALL, MATERIAL=RUBBER\n")
        f.write("*BOUNDARY\nNCLAMP, 1, 3\n")
        if linear:
            f.write("*STEP\n*STATIC\n")
        else:
            # NLGEOM: large deformation; automatic increments from 5 % of the load
            f.write("*STEP, NLGEOM, INC=1000\n*STATIC\n0.05, 1.0, 1e-6, 0.25\n")
        f.write("*DLOAD\nEALL, GRAV, %.12g, 0., 0., -1.\n" % GRAVITY)
        f.write("*NODE PRINT, NSET=NTIP\nU\n*END STEP\n")


def solve(workdir, job, h, element, linear):
    geo = os.path.join(workdir, job + ".geo")
    msh = os.path.join(workdir, job + ".msh")
    with open(geo, "w") as f:
        f.write(geo_tet(h) if element == "C3D10" else geo_hex(h))
    subprocess.run(["gmsh", "-3", geo, "-o", msh, "-format", "msh22", "-nt", "2"], check=True,
                   capture_output=True, text=True)
    nodes, raw = read_msh22(msh)
    if not raw:
        raise RuntimeError("gmsh produced no volume element")
    elements = [(etype, to_abaqus(nodes, etype, conn)) for etype, conn in raw]
    used = set(t for _, conn in elements for t in conn)
    nodes = {t: nodes[t] for t in used}
    write_inp(os.path.join(workdir, job + ".inp"), nodes, elements, element, linear)
    try:
        seconds = fem_common.run_ccx(workdir, job, threads=2)
    except fem_common.ToolFailed as e:
        raise RuntimeError(str(e))
    u = read_dat_last_u(os.path.join(workdir, job + ".dat"))
    w = tip_face_weights(nodes, elements)
    area = sum(w.values())
    mean_uz = sum(w[t] * u[t][2] for t in w) / area
    return {
        "h": h,
        "nodes": len(nodes),
        "elements": len(elements),
        "dofs": 3 * len(nodes),
        "tip_deflection_m": -mean_uz,
        "tip_min_uz_m": min(v[2] for v in u.values()),
        "tip_face_area": area,
        "ccx_seconds": round(seconds, 2),
    }


def beam_theory():
    mu, _, _ = lame()
    q = RHO * GRAVITY * WIDTH * HEIGHT
    I = WIDTH * HEIGHT ** 3 / 12
    eb = q * LENGTH ** 4 / (8 * E * I)
    kappa = 10 * (1 + NU) / (12 + 11 * NU)  # rectangular section (Cowper 1966)
    timo = eb + q * LENGTH ** 2 / (2 * kappa * mu * WIDTH * HEIGHT)
    return q, I, eb, kappa, timo


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="validation/fem_cantilever.json")
    ap.add_argument("--element", choices=["C3D10", "C3D20R"], default="C3D10")
    ap.add_argument("--h0", type=float, default=0.5, help="first characteristic length (m)")
    ap.add_argument("--factor", type=float, default=0.7, help="h shrink factor per refinement")
    ap.add_argument("--min-h", type=float, default=0.08, help="stop refining below this h")
    ap.add_argument("--tolerance", type=float, default=0.005, help="relative change to stop")
    ap.add_argument("--min-levels", type=int, default=5,
                    help="solve at least this many meshes (guards against a lucky early match)")
    ap.add_argument("--workdir", default=None)
    ap.add_argument("--keep", action="store_true", help="keep the work folder")
    ap.add_argument("--no-install", action="store_true")
    args = ap.parse_args()

    ensure_tools(not args.no_install)
    workdir = args.workdir or tempfile.mkdtemp(prefix="sem_fem_")
    os.makedirs(workdir, exist_ok=True)
    mu, lam, K = lame()
    result = {
        "problem": "cantilever 5 x 1 x 1 m, clamped at x = 0, gravity 10 m/s^2 along -z",
        "material": {"density": RHO, "youngs_modulus": E, "poisson_ratio": NU, "mu": mu, "lambda": lam,
                     "bulk_modulus": K, "calculix": "*HYPERELASTIC, NEO HOOKE", "C10": mu / 2, "D1": 2 / K},
        "element": args.element,
        "tip_measure": "area-weighted mean of -u_z over the free end face x = 5",
        "tolerance": args.tolerance,
        "tools": {"gmsh": tool_version(["gmsh", "--version"]), "ccx": tool_version(["ccx", "-v"])},
        "refinement": [],
    }
    h, prev, converged = args.h0, None, False
    k = 0
    while True:
        r = solve(workdir, "nl%d" % k, h, args.element, linear=False)
        change = None if prev is None else abs(r["tip_deflection_m"] / prev - 1)
        r["relative_change"] = change
        result["refinement"].append(r)
        print("h %.4f: %6d nodes %6d elements, tip deflection %.5f m%s (%.1f s)" % (
            h, r["nodes"], r["elements"], r["tip_deflection_m"],
            "" if change is None else ", change %.3f %%" % (100 * change), r["ccx_seconds"]),
            file=sys.stderr)
        if change is not None and change < args.tolerance and k + 1 >= args.min_levels:
            converged = True
            break
        prev = r["tip_deflection_m"]
        h *= args.factor
        k += 1
        if h < args.min_h:
            break
    last = result["refinement"][-1]
    result["converged"] = converged
    result["tip_deflection_m"] = last["tip_deflection_m"]
    result["mesh"] = {"h": last["h"], "nodes": last["nodes"], "elements": last["elements"],
                      "element": args.element}

    # linear check on the finest mesh against beam theory
    lin = solve(workdir, "linear", last["h"], args.element, linear=True)
    q, I, eb, kappa, timo = beam_theory()
    result["linear_check"] = {
        "material": "linear elastic E 1e6 nu 0.45, small-strain (no NLGEOM)",
        "load_per_length": q, "I": I, "h": lin["h"], "nodes": lin["nodes"],
        "fem_tip_deflection_m": lin["tip_deflection_m"],
        "euler_bernoulli_m": eb, "timoshenko_kappa": kappa, "timoshenko_m": timo,
        "fem_over_euler_bernoulli": lin["tip_deflection_m"] / eb,
        "fem_over_timoshenko": lin["tip_deflection_m"] / timo,
    }
    print("linear: FEM %.4f m, Euler-Bernoulli %.4f m (ratio %.4f), Timoshenko %.4f m (ratio %.4f)" % (
        lin["tip_deflection_m"], eb, lin["tip_deflection_m"] / eb, timo, lin["tip_deflection_m"] / timo),
        file=sys.stderr)
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(args.out, "w") as f:
        json.dump(result, f, indent=2)
        f.write("\n")
    print("%s: tip deflection %.5f m (%s, h %.4f, %d nodes)" % (
        args.out, result["tip_deflection_m"], args.element, last["h"], last["nodes"]))
    if not args.keep and not args.workdir:
        shutil.rmtree(workdir, ignore_errors=True)
    return 0 if converged else 1


if __name__ == "__main__":
    sys.exit(main())
