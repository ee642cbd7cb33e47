#!/usr/bin/env python3
"""Writes the worst-case inputs of fuzz/regressions/ (docs/reliability.md).

Each input once made sem crash, hang, run out of memory or misbehave, or is the worst case
of a limit: subfigure bombs (308/408 fanning out to 10^8 surfaces), composite curves that
repeat one member, long 124 chains, huge degrees and counts, trim loops with coordinates
near the double range, OBJ trim references that copy one curve many times, open trim loops,
self-referencing entities, control bytes in messages. The test suite replays every file
through the readers (fuzz_regress_*) and feeds them to `sem inspect` and `sem preprocess`
under a memory ceiling (test_limits). Files found by the fuzzers are added next to these.

Run from anywhere: python3 fuzz/regressions/generate.py
"""
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "tests", "data"))
from iges_generate import Ent, build, de, holl, line, nurbs_curve, nurbs_surface, patch, \
    uv_square, xform  # noqa: E402

DEP = "00010200"   # physically dependent, definition entity
SUB = "00010000"   # physically dependent


def save(folder, name, text):
    path = os.path.join(HERE, folder, name)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w", newline="") as f:
        f.write(text)
    print("%-40s %8d bytes" % (folder + "/" + name, len(text)))


# ------------------------------------------------------------------- IGES ----

def subfigure_fanout(levels=8, fan=10):
    """Definition k+1 holds `fan` distinct instances of definition k: fan^levels surfaces
    (10^8) from 90 entities."""
    E = []
    E.append(Ent(128, patch(0, 0, 0, 1, 1), status=SUB))          # index 0
    E.append(Ent(308, ["0", holl("L0"), "1", de(0)], status=DEP))  # index 1
    prev_def = 1
    for k in range(levels):
        insts = []
        for j in range(fan):
            insts.append(len(E))
            E.append(Ent(408, [de(prev_def), str(float(j)), "0.0", "0.0", "1.0"], status=SUB))
        d = len(E)
        E.append(Ent(308, ["0", holl("L%d" % (k + 1)), str(fan)] + [de(i) for i in insts],
                     status=DEP))
        prev_def = d
    E.append(Ent(408, [de(prev_def), "0.0", "0.0", "0.0", "1.0"]))
    save("iges", "subfigure_fanout.igs", build(E))


def subfigure_repeat(levels=4, repeat=100):
    """Definition k+1 lists the same instance of definition k `repeat` times (the busy flag
    only stops cycles): 100^4 = 10^8 surfaces from a 4.7 KB file."""
    E = [Ent(128, patch(0, 0, 0, 1, 1), status=SUB),
         Ent(308, ["0", holl("L0"), "1", de(0)], status=DEP)]
    prev_def = 1
    for k in range(levels):
        inst = len(E)
        E.append(Ent(408, [de(prev_def), "0.0", "0.0", "0.0", "1.0"], status=SUB))
        d = len(E)
        E.append(Ent(308, ["0", holl("R%d" % (k + 1)), str(repeat)] + [de(inst)] * repeat,
                     status=DEP))
        prev_def = d
    E.append(Ent(408, [de(prev_def), "0.0", "0.0", "0.0", "1.0"]))
    save("iges", "subfigure_repeat.igs", build(E))


def subfigure_parts(repeat=400, top=13):
    """5,200 bilinear patches through two levels of instances: the part limit."""
    E = [Ent(128, patch(0, 0, 0, 1, 1), status=SUB),
         Ent(308, ["0", holl("P"), "1", de(0)], status=DEP),
         Ent(408, [de(1), "0.0", "0.0", "0.0", "1.0"], status=SUB)]
    E.append(Ent(308, ["0", holl("Q"), str(repeat)] + [de(2)] * repeat, status=DEP))
    for j in range(top):
        E.append(Ent(408, [de(3), str(float(j)), "0.0", "0.0", "1.0"]))
    save("iges", "subfigure_parts.igs", build(E))


def trimmed_patch_with_loop(loop_entities, first_loop_index):
    """A 144 over a unit patch whose outer loop is the 142 at index 2 pointing to the
    curve entity at first_loop_index."""
    return [Ent(144, [de(1), "1", "0", de(2)]),
            Ent(128, patch(0, 0, 0, 1, 1), status=SUB),
            Ent(142, ["1", de(1), de(first_loop_index), "0", "1"], status=SUB)] + loop_entities


def composite_repeat(levels, repeat, name):
    """A composite curve (102) whose members are one composite repeated, `levels` deep: the
    trim loop has repeat^levels curves (the 6.7 GB bucket allocation)."""
    # index 3: a line from (0.5,0.5) to (0.5,0.5) (zero length, closes with itself)
    loop = [Ent(110, line((0.1, 0.1, 0), (0.9, 0.9, 0)), status=SUB)]
    prev = 3
    for k in range(levels):
        loop.append(Ent(102, [str(repeat)] + [de(prev)] * repeat, status=SUB))
        prev = 3 + len(loop) - 1
    E = trimmed_patch_with_loop(loop, prev)
    save("iges", name, build(E))


def xform_chains(chain=31, repeat=100, top=50):
    """5,000 patches (the part limit), each moved by a chain of 31 transformation matrices
    (124 -> 124 ...) inside instances that carry chains of their own."""
    E = []
    for k in range(chain):
        nxt = de(k + 1) if k + 1 < chain else 0
        E.append(Ent(124, xform([[1, 0, 0], [0, 1, 0], [0, 0, 1]], (0.001, 0, 0)), xform=nxt))
    p = len(E)
    E.append(Ent(128, patch(0, 0, 0, 1, 1), xform=de(0), status=SUB))
    d = len(E)
    E.append(Ent(308, ["0", holl("X"), "1", de(p)], xform=de(0), status=DEP))
    i = len(E)
    E.append(Ent(408, [de(d), "0.0", "0.0", "0.0", "1.0"], xform=de(0), status=SUB))
    d2 = len(E)
    E.append(Ent(308, ["0", holl("Y"), str(repeat)] + [de(i)] * repeat, xform=de(0), status=DEP))
    for j in range(top):
        E.append(Ent(408, [de(d2), str(float(j)), "0.0", "0.0", "1.0"], xform=de(0)))
    save("iges", "xform_chains.igs", build(E))


def huge_degree(n=60, degree=31, name="huge_degree.igs"):
    """One degree-31 x 31 surface with as many control points and knot spans as fit in
    about 1 MB (single-digit numbers); with n=40 the largest such surface within
    SEM_MAX_MODEL_SPAN_WORK."""
    knots = [0] * (degree + 1) + list(range(1, n - degree)) + [n - degree] * (degree + 1)
    grid = [[(i % 10, j % 10, (i + j) % 3) for i in range(n)] for j in range(n)]
    fmt = lambda x: str(x)  # noqa: E731
    s = nurbs_surface(degree, degree, knots, knots, grid, fmt=fmt)
    save("iges", name, build([Ent(128, s)]))


def curved_parts(repeat=100, top=50):
    """5,000 curved (biquadratic bump) patches through instances: the part limit reached
    with parts whose bounding box needs a search (no corner holds an extreme)."""
    grid = [[(0, 0, 0), (0.5, 0, 0.2), (1, 0, 0)],
            [(0, 0.5, 0.2), (0.5, 0.5, 1.0), (1, 0.5, 0.2)],
            [(0, 1, 0), (0.5, 1, 0.2), (1, 1, 0)]]
    bump = nurbs_surface(2, 2, [0, 0, 0, 1, 1, 1], [0, 0, 0, 1, 1, 1], grid)
    E = [Ent(128, bump, status=SUB),
         Ent(308, ["0", holl("B"), "1", de(0)], status=DEP),
         Ent(408, [de(1), "0.0", "0.0", "0.0", "1.0"], status=SUB)]
    E.append(Ent(308, ["0", holl("C"), str(repeat)] + [de(2)] * repeat, status=DEP))
    for j in range(top):
        E.append(Ent(408, [de(3), str(float(j)), "0.0", "0.0", "1.0"]))
    save("iges", "curved_parts.igs", build(E))


def huge_count(n=4000):
    """As many separate bilinear patches as fit in about 1 MB."""
    E = [Ent(128, patch(float(j % 100), float(j // 100), 0, 1, 1)) for j in range(n)]
    save("iges", "huge_count.igs", build(E))


def trim_huge_coordinates():
    """A trim loop with coordinates of 1e308: bucket indices were NaN converted to int."""
    pts = [(0.0, 0.0, 0), (1e308, 0.0, 0), (1e308, 1e308, 0), (-1e308, 1e308, 0)]
    loop = [Ent(110, line(pts[k], pts[(k + 1) % 4]), status=SUB) for k in range(4)]
    comp = Ent(102, ["4", de(3), de(4), de(5), de(6)], status=SUB)
    E = trimmed_patch_with_loop(loop + [comp], 7)
    save("iges", "trim_huge_coordinates.igs", build(E))


def trim_many_spans(spans=9000):
    """One trim curve of degree 1 with 9,000 spans zig-zagging across the whole domain."""
    pts = [((k + 0.5) / (spans + 1), 0.05 if k % 2 == 0 else 0.95, 0) for k in range(spans + 1)]
    knots = [0, 0] + list(range(1, spans)) + [spans, spans]
    curve = Ent(126, nurbs_curve(1, knots, pts, fmt=lambda x: "%.4g" % x), status=SUB)
    E = trimmed_patch_with_loop([curve], 3)
    save("iges", "trim_many_spans.igs", build(E))
    # the same zig-zag closed back to its start: a loop that closes, so its spans are counted
    pts.append(pts[0])
    knots = [0, 0] + list(range(1, spans + 1)) + [spans + 1, spans + 1]
    curve = Ent(126, nurbs_curve(1, knots, pts, fmt=lambda x: "%.4g" % x), status=SUB)
    save("iges", "trim_many_spans_closed.igs", build(trimmed_patch_with_loop([curve], 3)))


def self_references():
    # a 144 whose outer boundary pointer is itself; a 308 that lists itself
    E = [Ent(144, [de(1), "1", "0", de(0)]),
         Ent(128, patch(0, 0, 0, 1, 1), status=SUB),
         Ent(128, patch(2, 0, 0, 1, 1), status=SUB),
         Ent(308, ["0", holl("SELF"), "2", de(2), de(3)], status=DEP),
         Ent(408, [de(3), "0.0", "0.0", "0.0", "1.0"])]
    save("iges", "self_reference.igs", build(E))


def control_bytes():
    # a parameter holding an escape sequence and a newline-like byte: the message must
    # stay one printable line
    s = patch(0, 0, 0, 1, 1)
    s[12] = "\x1b[2J\x07"
    text = build([Ent(128, s)])
    save("iges", "control_bytes.igs", text)


# -------------------------------------------------------------------- OBJ ----

def obj_trim_references(n_points=2000, refs=2001):
    """One curv2 of 2000 points referenced 2001 times by one trim statement: every
    reference used to deep-copy the curve (2.5 GB from 311 KB with more references)."""
    out = ["v 0 0 0", "v 1 0 0", "v 0 1 0", "v 1 1 0"]
    for k in range(n_points):
        out.append("vp %g %g" % (0.5 + 0.4 * (k % 2), 0.5))
    out.append("cstype bspline")
    out.append("deg 1")
    out.append("curv2 " + " ".join(str(k + 1) for k in range(n_points)))
    out.append("parm u " + " ".join(str(k) for k in [0] + list(range(n_points)) + [n_points - 1]))
    out.append("end")
    out.append("deg 1 1")
    out.append("surf 0 1 0 1 1 2 3 4")
    out.append("parm u 0 0 1 1")
    out.append("parm v 0 0 1 1")
    out.append("trim" + " 0 1 1" * refs)
    out.append("end")
    save("obj", "trim_references.obj", "\n".join(out) + "\n")


def obj_open_trim():
    """A trim loop that does not close (the IGES reader rejected it; OBJ gave area NaN)."""
    out = ["v 0 0 0", "v 1 0 0", "v 0 1 0", "v 1 1 0",
           "vp 0.2 0.2", "vp 0.8 0.2", "vp 0.8 0.8",
           "cstype bspline", "deg 1",
           "curv2 1 2 3", "parm u 0 0 1 2 2", "end",
           "deg 1 1", "surf 0 1 0 1 1 2 3 4", "parm u 0 0 1 1", "parm v 0 0 1 1",
           "trim 0 2 1", "end"]
    save("obj", "open_trim.obj", "\n".join(out) + "\n")


def obj_huge_coordinates():
    out = ["v 0 0 0", "v 1 0 0", "v 0 1 0", "v 1 1 0",
           "vp 0 0", "vp 1e308 0", "vp 1e308 1e308", "vp -1e308 1e308", "vp 0 0",
           "cstype bspline", "deg 1",
           "curv2 1 2 3 4 5", "parm u 0 0 1 2 3 4 4", "end",
           "deg 1 1", "surf 0 1 0 1 1 2 3 4", "parm u 0 0 1 1", "parm v 0 0 1 1",
           "trim 0 4 1", "end"]
    save("obj", "trim_huge_coordinates.obj", "\n".join(out) + "\n")


# ------------------------------------------------------------------ scenes ----

def scenes():
    base = '"objects": [{"primitive": {"type": "box"}}]'
    save("scene", "duplicate_key.json", '{%s, "frames": 10, "frames": 1000}\n' % base)
    save("scene", "duplicate_nested_key.json",
         '{"objects": [{"primitive": {"type": "box"}, "material": {"density": 1, "density": 2}}]}\n')
    save("scene", "trailing_garbage.json", '{%s}\n{"frames": 3}\n' % base)
    save("scene", "frames_1e12.json", '{%s, "frames": 1e12}\n' % base)
    save("scene", "control_bytes.json", '{%s, "fr\\u001b[2Jmes": 1}\n' % base)


# ---------------------------------------------------------------- caches ----

def fnv_fix(data):
    """Writes the FNV-1a 64 checksum of everything before the last 8 bytes into them."""
    h = 14695981039346656037
    for b in data[:-8]:
        h = ((h ^ b) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return data[:-8] + h.to_bytes(8, "little")


def save_bytes(folder, name, data):
    path = os.path.join(HERE, folder, name)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data)
    print("%-40s %8d bytes" % (folder + "/" + name, len(data)))


def caches():
    """Damaged preprocessed files, from the seed corpus's sphere, with a valid checksum."""
    with open(os.path.join(HERE, "..", "corpus", "cache", "sphere_order2.semdisc"), "rb") as f:
        good = f.read()
    save_bytes("cache", "truncated.semdisc", fnv_fix(good[:1000]))
    save_bytes("cache", "header_only.semdisc", fnv_fix(good[:60]))
    # (sizes near INT32_MAX, NaN values and flipped bytes of the whole file are made at run
    # time by tests/test_cache.c, to keep these 110 KB variants out of the repository)

if __name__ == "__main__":
    subfigure_fanout()
    subfigure_repeat()
    subfigure_parts()
    composite_repeat(2, 200, "composite_repeat.igs")
    composite_repeat(3, 200, "composite_repeat_deep.igs")
    xform_chains()
    huge_degree()
    huge_degree(n=40, name="huge_degree_accepted.igs")
    curved_parts()
    trim_huge_coordinates()
    trim_many_spans()
    self_references()
    control_bytes()
    obj_trim_references()
    obj_open_trim()
    obj_huge_coordinates()
    scenes()
    caches()
