#!/usr/bin/env python3
"""Builds examples/models/octopus.obj: an octopus-like soft model for the barrier's
self-contact scene (issue 31 item 3), from sem's own primitives, as OBJ free-form NURBS.

A body (a sphere, radius 0.25 m) with LIMBS limbs (cylinders, radius 0.05 m, length 0.6 m,
refined by 3 so that they can bend), each pointing out and 40 degrees down, its inner end
3 cm inside the body (an overlap, as CAD models have). One object of 1 + 3 x LIMBS parts;
its limbs pile up when it falls (examples/octopus_drop.json).

    python3 scripts/make_octopus.py [SEM_BINARY] [OUT]
"""
import math
import os
import subprocess
import sys
import tempfile

LIMBS = 6
BODY_R, LIMB_R, LIMB_LEN, TILT = 0.25, 0.05, 0.6, math.radians(40)


def read_obj(path):
    """(vertices [x, y, z, w], statement lines) of an OBJ free-form file, continuations joined."""
    verts, lines, pending = [], [], ""
    for raw in open(path):
        line = pending + raw.rstrip("\n")
        if line.endswith("\\"):
            pending = line[:-1] + " "
            continue
        pending = ""
        if line.startswith("v "):
            verts.append([float(x) for x in line.split()[1:]])
        elif line and not line.startswith("#"):
            lines.append(line)
    return verts, lines


def rotation_to(d):
    """The rotation taking +z to the unit vector d (Rodrigues)."""
    z = (0.0, 0.0, 1.0)
    axis = (z[1] * d[2] - z[2] * d[1], z[2] * d[0] - z[0] * d[2], z[0] * d[1] - z[1] * d[0])
    s, c = math.sqrt(sum(a * a for a in axis)), d[2]
    if s < 1e-12:
        return [[1, 0, 0], [0, 1, 0], [0, 0, 1 if c > 0 else -1]]
    k = [a / s for a in axis]
    K = [[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]]
    KK = [[sum(K[i][m] * K[m][j] for m in range(3)) for j in range(3)] for i in range(3)]
    return [[(1 if i == j else 0) + s * K[i][j] + (1 - c) * KK[i][j] for j in range(3)] for i in range(3)]


def main():
    sem = sys.argv[1] if len(sys.argv) > 1 else "build/sem"
    out = sys.argv[2] if len(sys.argv) > 2 else "examples/models/octopus.obj"
    with tempfile.TemporaryDirectory() as tmp:
        body, limb, limb_r = (os.path.join(tmp, n) for n in ("body.obj", "limb.obj", "limb_r.obj"))
        for args in (["primitive", "sphere", "--radius", str(BODY_R), "-o", body],
                     ["primitive", "cylinder", "--radius", str(LIMB_R), "--height", str(LIMB_LEN), "-o", limb],
                     ["refine", limb, limb_r, "--factor", "3"]):
            subprocess.run([sem] + args, check=True, stdout=subprocess.DEVNULL)
        parts = [("body", read_obj(body), None, None)]
        for i in range(LIMBS):
            a = 2 * math.pi * i / LIMBS
            d = (math.cos(a) * math.cos(TILT), math.sin(a) * math.cos(TILT), -math.sin(TILT))
            centre = [(BODY_R - 0.03 + LIMB_LEN / 2) * x for x in d]
            parts.append(("limb%d" % (i + 1), read_obj(limb_r), rotation_to(d), centre))
    text = ["# octopus-like model for sem (scripts/make_octopus.py): a body and %d limbs" % LIMBS,
            "# sem units M 1"]
    offset = 0
    for name, (verts, lines), R, t in parts:
        for v in verts:
            p = v[:3]
            if R:
                p = [sum(R[i][j] * p[j] for j in range(3)) + t[i] for i in range(3)]
            text.append("v %.17g %.17g %.17g %.17g" % (p[0], p[1], p[2], v[3] if len(v) > 3 else 1.0))
        for line in lines:
            if line.startswith("o "):
                line = "o %s_%s" % (name, line[2:])
            elif line.startswith("surf "):
                f = line.split()
                line = " ".join(f[:5] + [str(int(x) + offset) for x in f[5:]])
            text.append(line)
        offset += len(verts)
    os.makedirs(os.path.dirname(out) or ".", exist_ok=True)
    with open(out, "w") as f:
        f.write("\n".join(text) + "\n")
    print("%s: %d parts, %d control points" % (out, sum(l.startswith("o ") for l in text), offset))


if __name__ == "__main__":
    main()
