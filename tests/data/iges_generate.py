#!/usr/bin/env python3
"""Writes the small IGES test files tests/data/iges_*.igs used by tests/test_iges_read.c.

Each file is written the way a CAD exporter lays it out (80 columns, section letters in
column 73, DE/PD pointers), so the files can be read and edited by hand; this script only
saves counting columns. Run it from anywhere: python3 tests/data/iges_generate.py
"""
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def r(x):
    """Exact decimal text of a float (shortest round trip)."""
    return repr(float(x))


def holl(s):
    return "%dH%s" % (len(s), s)


class Ent:
    def __init__(self, type_, params, form=0, xform=0, status="00000000", label="",
                 subscript=0, color=0, pd_count=None):
        self.type = type_
        self.params = params  # list of str, or callables of the DE map
        self.form = form
        self.xform = xform
        self.status = status
        self.label = label
        self.subscript = subscript
        self.color = color
        self.pd_count = pd_count  # a wrong parameter line count to write (repair tests)


def de(i):
    """DE number of the entity at index i."""
    return 2 * i + 1


def build(entities, unit_flag=6, unit_name="M", pd=",", rd=";", start="sem test file",
          eol="\n", short=False):
    lines = []

    def line(data, sec, seq):
        text = "%-72s%s%7d" % (data, sec, seq)
        if short:
            text = text[:73]  # sequence numbers cut off (some writers do)
        lines.append(text)

    line(start, "S", 1)
    g = [holl(pd), holl(rd), holl("sem"), holl("test.igs"), holl("sem generator"),
         holl("1.0"), "32", "38", "6", "308", "15", holl("sem"), "1.0", str(unit_flag),
         holl(unit_name), "1", "0.08", holl("20240101.000000"), "1.0E-6", "100.0",
         holl("sem"), holl("sem"), "11", "0", holl("20240101.000000")]
    text = pd.join(g) + rd
    gl = []
    cur = ""
    for tok in [t + pd for t in g[:-1]] + [g[-1] + rd]:
        if len(cur) + len(tok) > 72:
            gl.append(cur)
            cur = ""
        cur += tok
    gl.append(cur)
    for i, t in enumerate(gl):
        line(t, "G", i + 1)
    # parameter data
    plines = []
    starts = []
    counts = []
    for i, e in enumerate(entities):
        toks = [str(e.type)] + [str(p) for p in e.params]
        starts.append(len(plines) + 1)
        cur = ""
        out = []
        for k, tok in enumerate(toks):
            tok = tok + (rd if k == len(toks) - 1 else pd)
            while len(cur) + len(tok) > 64:
                if cur:
                    out.append(cur)
                    cur = ""
                else:  # a token longer than a line (long Hollerith): split it
                    out.append(tok[:64])
                    tok = tok[64:]
            cur += tok
        out.append(cur)
        for o in out:
            plines.append((o, de(i)))
        counts.append(len(out))
    for i, e in enumerate(entities):
        d1 = "%8d%8d%8d%8d%8d%8d%8d%8d%8s" % (e.type, starts[i], 0, 0, 0, 0, e.xform, 0,
                                             e.status)
        count = counts[i] if e.pd_count is None else e.pd_count
        d2 = "%8d%8d%8d%8d%8d%8s%8s%8s%8d" % (e.type, 0, e.color, count, e.form, "", "",
                                             e.label, e.subscript)
        line(d1, "D", 2 * i + 1)
        line(d2, "D", 2 * i + 2)
    for k, (o, back) in enumerate(plines):
        line("%-64s %7d" % (o, back), "P", k + 1)
    line("S%7dG%7dD%7dP%7d" % (1, len(gl), 2 * len(entities), len(plines)), "T", 1)
    return eol.join(lines) + eol


def save(name, text):
    with open(os.path.join(HERE, name), "w", newline="") as f:
        f.write(text)


# ---------------------------------------------------------------- entities ----

def nurbs_curve(degree, knots, ctrl, weights=None, t0=None, t1=None, fmt=r):
    n = len(ctrl)
    weights = weights or [1.0] * n
    t0 = knots[degree] if t0 is None else t0
    t1 = knots[n] if t1 is None else t1
    p = [n - 1, degree, 0, 0, 1 if all(w == 1 for w in weights) else 0, 0]
    p += [fmt(k) for k in knots] + [fmt(w) for w in weights]
    for c in ctrl:
        p += [fmt(x) for x in c]
    p += [fmt(t0), fmt(t1), "0.0", "0.0", "1.0"]
    return p


def nurbs_surface(du, dv, ku, kv, grid, weights=None, fmt=r, rng=None, closed=(0, 0)):
    """grid[j][i] = point (i along u fastest, as IGES stores); closed: PROP1, PROP2."""
    nu, nv = len(grid[0]), len(grid)
    weights = weights or [1.0] * (nu * nv)
    p = [nu - 1, nv - 1, du, dv, closed[0], closed[1], 1 if all(w == 1 for w in weights) else 0,
         0, 0]
    p += [fmt(k) for k in ku] + [fmt(k) for k in kv] + [fmt(w) for w in weights]
    for row in grid:
        for c in row:
            p += [fmt(x) for x in c]
    rng = rng or (ku[du], ku[nu], kv[dv], kv[nv])
    p += [fmt(x) for x in rng]
    return p


def patch(x0, y0, z0, sx, sy):
    """Bilinear 2x2 patch of size sx x sy at (x0, y0, z0), domain [0,1]^2."""
    return nurbs_surface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1],
                         [[(x0, y0, z0), (x0 + sx, y0, z0)],
                          [(x0, y0 + sy, z0), (x0 + sx, y0 + sy, z0)]])


def biquad():
    """A 3x3 quadratic patch over [0,2]x[0,1] with distinct weights (exactness checks)."""
    grid = [[(0, 0, 0), (1, 0, 0.5), (2, 0, 0)],
            [(0, 1, 0.25), (1, 1, 1.0), (2, 1, 0.25)],
            [(0, 2, 0), (1, 2, 0.5), (2, 2, 0)]]
    w = [1, 0.5, 1, 0.75, 1.25, 0.75, 1, 0.5, 1]
    return nurbs_surface(2, 2, [0, 0, 0, 2, 2, 2], [0, 0, 0, 1, 1, 1], grid, w)


def line(p, q):
    return [r(x) for x in p] + [r(x) for x in q]


def uv_square(a, b, c, d):
    """Four 110 lines around [a,b]x[c,d] in parameter space (z = 0)."""
    pts = [(a, c, 0), (b, c, 0), (b, d, 0), (a, d, 0)]
    return [Ent(110, line(pts[k], pts[(k + 1) % 4])) for k in range(4)]


def xform(rot, t):
    p = []
    for i in range(3):
        p += [r(rot[i][0]), r(rot[i][1]), r(rot[i][2]), r(t[i])]
    return p


# ------------------------------------------------------------------ files ----

def file_delims():
    # param delimiter '/', record delimiter '!', CRLF, D exponents, a name with both
    # delimiters (and the default ones) inside a Hollerith string
    dfmt = lambda x: ("%.17g" % x).replace("e", "D") if "e" in ("%.17g" % x) else "%sD0" % r(x)
    grid = [[(0, 0, 0), (2.5e-3, 0, 0)], [(0, 1.5e2, 0), (2.5e-3, 1.5e2, 1.25)]]
    s = nurbs_surface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], grid, fmt=dfmt)
    s += ["0", "1", de(1)]  # no associativities, one property
    name = "a/b!c,d;e"
    ents = [Ent(128, s), Ent(406, ["1", holl(name)], form=15)]
    save("iges_delims.igs", build(ents, unit_flag=2, unit_name="MM", pd="/", rd="!", eol="\r\n"))


def file_short_lines():
    ents = [Ent(128, patch(0, 0, 0, 1, 1), label="PANEL", subscript=7)]
    save("iges_short_lines.igs", build(ents, unit_flag=1, unit_name="IN", short=True))


def file_xform():
    # entity 0: 128 moved by 124 (DE 3): rotate 90 deg about z, translate (10, 0, 0)
    # entity 2: 128 with chained 124s: DE 7 (translate (0,0,5)) whose own transform is
    # DE 9 (scale 2)
    rz = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    ident = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    ents = [Ent(128, patch(1, 2, 3, 1, 1), xform=de(1)),
            Ent(124, xform(rz, (10, 0, 0))),
            Ent(128, patch(1, 2, 3, 1, 1), xform=de(3)),
            Ent(124, xform(ident, (0, 0, 5)), xform=de(4)),
            Ent(124, xform([[2, 0, 0], [0, 2, 0], [0, 0, 2]], (0, 0, 0)))]
    save("iges_xform.igs", build(ents))


def file_subfigure():
    # definition (308, DE 1) of a trimmed patch (144 DE 3 -> 128 DE 5, loop 142 DE 7 ->
    # composite DE 9 of 4 lines) and a plain patch (128 DE 19); two instances (408).
    dep = "00010200"
    sub = "00010000"
    ents = [None] * 12
    ents[0] = Ent(308, ["0", holl("BLOCK"), "2", de(1), de(9)], status=dep)
    ents[1] = Ent(144, [de(2), "1", "0", de(3)], status=sub)
    ents[2] = Ent(128, patch(0, 0, 0, 1, 1), status=sub)
    ents[3] = Ent(142, ["1", de(2), de(4), "0", "1"], status=sub)
    ents[4] = Ent(102, ["4", de(5), de(6), de(7), de(8)], status=sub)
    sq = uv_square(0.25, 0.75, 0.25, 0.75)
    for k in range(4):
        sq[k].status = sub
        ents[5 + k] = sq[k]
    ents[9] = Ent(128, patch(0, 0, 1, 1, 1), status=sub)
    rz = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    ents[10] = Ent(408, [de(0), "10.0", "0.0", "0.0", "2.0"])
    ents[11] = Ent(408, [de(0), "0.0", "0.0", "0.0", ""], xform=de(12))
    ents.append(Ent(124, xform(rz, (0, 0, 0))))
    save("iges_subfigure.igs", build(ents))


def file_plane():
    # bounded plane z = 2 (0 x + 0 y + 1 z = 2), bounded by a full circle of radius 1 around
    # (3, 4); and an unbounded plane x = 1 with display point (1, 5, 6) and SIZE 0.5
    ents = [Ent(108, ["0.0", "0.0", "1.0", "2.0", de(1), "3.0", "4.0", "2.0", "1.0"], form=1),
            Ent(100, ["2.0", "3.0", "4.0", "4.0", "4.0", "4.0", "4.0"]),
            Ent(108, ["1.0", "0.0", "0.0", "1.0", "0", "1.0", "5.0", "6.0", "0.5"])]
    save("iges_plane.igs", build(ents))


def file_ruled():
    # 118 form 1 between the line (0,0,0)-(2,0,0) and a half circle of radius 1 around
    # (1, 0) at z = 3 from (2, 0) to (0, 0) (counter-clockwise, through (1, 1))
    ents = [Ent(118, [de(1), de(2), "0", "0"], form=1),
            Ent(110, line((0, 0, 0), (2, 0, 0))),
            Ent(100, ["3.0", "1.0", "0.0", "2.0", "0.0", "0.0", "0.0"])]
    save("iges_ruled.igs", build(ents))


def file_revolution():
    # cylinder: generatrix (2,0,0)-(2,0,3) about the z axis, full turn
    # sphere: the right half of the unit circle in the xy plane about the y axis
    ents = [Ent(120, [de(1), de(2), "0.0", r(2 * math.pi)]),
            Ent(110, line((0, 0, 0), (0, 0, 1))),
            Ent(110, line((2, 0, 0), (2, 0, 3))),
            Ent(120, [de(4), de(5), "0.0", r(2 * math.pi)]),
            Ent(110, line((0, -1, 0), (0, 1, 0))),
            Ent(100, ["0.0", "0.0", "0.0", "0.0", "-1.0", "0.0", "1.0"])]
    save("iges_revolution.igs", build(ents))


def file_tabulated():
    # quarter circle of radius 3 around the origin, extruded by (0, 0, 5)
    ents = [Ent(122, [de(1), "3.0", "0.0", "5.0"]),
            Ent(100, ["0.0", "0.0", "0.0", "3.0", "0.0", "0.0", "3.0"])]
    save("iges_tabulated.igs", build(ents))


def file_brep():
    # 186 -> 514 with two faces. Face 1 (510) trims a patch with a square loop whose edges
    # have parameter-space lines; face 2's loop edges have none (K = 0): trimmed by
    # projecting the edges' model-space lines.
    sub = "00010000"
    E = []

    def add(e):
        E.append(e)
        return len(E) - 1

    i186 = add(None)
    i514 = add(None)
    i510a = add(None)
    i510b = add(None)
    s1 = add(Ent(128, patch(0, 0, 0, 1, 1), status=sub))
    s2 = add(Ent(128, patch(0, 0, 0, 1, 1), status=sub))
    # vertex list and model-space edges of the square (0.25..0.75) on face 1 (z = 0)
    pts = [(0.25, 0.25, 0), (0.75, 0.25, 0), (0.75, 0.75, 0), (0.25, 0.75, 0)]
    vl = add(Ent(502, ["4"] + [r(x) for p in pts for x in p], form=1, status=sub))
    curves3 = [add(Ent(110, line(pts[k], pts[(k + 1) % 4]), status=sub)) for k in range(4)]
    ep = ["4"]
    for k in range(4):
        ep += [de(curves3[k]), de(vl), str(k + 1), de(vl), str((k + 1) % 4 + 1)]
    el = add(Ent(504, ep, form=1, status=sub))
    pcs = [add(Ent(110, line((p[0], p[1], 0), (q[0], q[1], 0)), status=sub))
           for p, q in zip(pts, pts[1:] + pts[:1])]
    lp1 = ["4"]
    for k in range(4):
        lp1 += ["0", de(el), str(k + 1), "1", "1", "0", de(pcs[k])]
    loop1 = add(Ent(508, lp1, form=1, status=sub))
    lp2 = ["4"]
    for k in range(4):
        lp2 += ["0", de(el), str(k + 1), "1", "0"]
    loop2 = add(Ent(508, lp2, form=1, status=sub))
    E[i186] = Ent(186, [de(i514), "1", "0"])
    E[i514] = Ent(514, ["2", de(i510a), "1", de(i510b), "1"], form=1, status=sub)
    E[i510a] = Ent(510, [de(s1), "1", "1", de(loop1)], form=1, status=sub)
    E[i510b] = Ent(510, [de(s2), "1", "1", de(loop2)], form=1, status=sub)
    save("iges_brep.igs", build(E))


def file_unknown():
    ents = [Ent(128, patch(0, 0, 0, 1, 1)),
            Ent(112, ["3", "1", "3", "1", "0.0", "1.0"] + ["0.0"] * 24),
            Ent(314, ["100.0", "0.0", "0.0", holl("red")]),
            Ent(406, ["1", holl("unused")], form=15),
            Ent(212, ["1", "4", "1.0", "1.0", "0", "0.0", "0", "0", "0.0", "0.0", "0.0",
                      holl("NOTE")])]
    save("iges_unknown.igs", build(ents))


def file_cad_trimmed():
    """SolidWorks/CATIA-like 144 + 142 (BPTR and CPTR both given, a composite outer
    loop and a circular hole) and a 143 + 141 (TYPE 1) with a reversed (SENSE 2) piece."""
    E = []

    def add(e):
        E.append(e)
        return len(E) - 1

    t144 = add(None)
    srf = add(Ent(128, biquad(), status="00010000"))
    # outer loop in (u,v) over [0,2]x[0,1]: composite of 4 lines inset by 0.1
    pts = [(0.1, 0.1, 0), (1.9, 0.1, 0), (1.9, 0.9, 0), (0.1, 0.9, 0)]
    ls = [add(Ent(110, line(pts[k], pts[(k + 1) % 4]), status="00010000")) for k in range(4)]
    comp = add(Ent(102, ["4"] + [de(i) for i in ls], status="00010000"))
    c3d = add(Ent(126, nurbs_curve(1, [0, 0, 1, 1], [(0.1, 0.1, 0), (1.9, 0.1, 0)]),
                  status="00010000"))  # model-space curve (not used by the reader)
    o142 = add(Ent(142, ["0", de(srf), de(comp), de(c3d), "1"], status="00010000"))
    hole = add(Ent(100, ["0.0", "1.0", "0.5", "1.2", "0.5", "1.2", "0.5"], status="00010000"))
    h142 = add(Ent(142, ["0", de(srf), de(hole), "0", "1"], status="00010000"))
    E[t144] = Ent(144, [de(srf), "1", "1", de(o142), de(h142)], color=3)
    # 143/141: surface = same biquad data, boundary triangle in (u,v) with 2 pieces, the
    # second given backwards and marked SENSE 2
    t143 = add(None)
    srf2 = add(Ent(128, biquad(), status="00010000"))
    a = add(Ent(126, nurbs_curve(1, [0, 0, 1, 2, 2], [(0.2, 0.2, 0), (1.8, 0.2, 0), (1.0, 0.8, 0)]),
                status="00010000"))
    b = add(Ent(126, nurbs_curve(2, [0, 0, 0, 3, 3, 3], [(0.2, 0.2, 0), (0.5, 0.6, 0), (1.0, 0.8, 0)],
                                 weights=[1.0, 0.5, 1.0]), status="00010000"))
    m3 = add(Ent(110, line((0, 0, 0), (1, 0, 0)), status="00010000"))
    b141 = add(Ent(141, ["1", "1", de(srf2), "2", de(m3), "1", "1", de(a),
                         de(m3), "2", "1", de(b)], status="00010000"))
    E[t143] = Ent(143, ["1", de(srf2), "1", de(b141)], label="BOUNDED", subscript=2)
    save("iges_cad_trimmed.igs", build(E))


def file_bptr0():
    ents = [Ent(144, [de(1), "1", "0", de(2)]),
            Ent(128, patch(0, 0, 0, 1, 1), status="00010000"),
            Ent(142, ["0", de(1), "0", de(3), "2"], status="00010000"),
            Ent(110, line((0, 0, 0), (1, 1, 0)), status="00010000")]
    save("iges_bptr0.igs", build(ents))


CIRCLE_KNOTS = [0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1]
CIRCLE_W = [1, math.sqrt(0.5)] * 4 + [1]
CIRCLE_XY = [(1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1), (1, 0)]


def circle3(f):
    """The 9-point rational quadratic unit circle mapped by f(x, y) -> (x, y, z)."""
    return nurbs_curve(2, CIRCLE_KNOTS, [f(x, y) for x, y in CIRCLE_XY], CIRCLE_W)


def file_model_space(name="iges_model_space.igs", off=0.0):
    """Trims given in model space only (no parameter-space curves anywhere), with closed
    forms for the trimmed areas:
    part 0: 143 on the plane patch [0,2]x[0,1] (z = 0); outer 141 TYPE 0 = the patch's own
            border (4 lines), hole 141 TYPE 0 = circle of radius 0.3 around (1, 0.5):
            area 2 - 0.09 pi, no outer trim (the border trims nothing)
    part 1: 186 -> 514 -> 510 on a cylinder of radius 1, z 0..2, closed in u (seam at x = 1,
            y = 0); loop = bottom circle, seam edge up, the ellipse z = 1 + x / 2 backwards,
            the seam edge down: area 2 pi (the mean height is 1)
    part 2: 510 on the unit sphere (u longitude with a seam, v latitude with poles): the cap
            above z = 1/2; loop = the latitude circle, the seam meridian up to the pole and
            down again: area 2 pi h = pi
    off > 0: every trim curve lies off its surface by off (the plate's lifted, the others'
    moved out radially), as a CAD file's edges lie within its tolerance: the projected loops
    and the areas are the same"""
    k = 1.0 + off
    sub = "00010000"
    E = []

    def add(e):
        E.append(e)
        return len(E) - 1

    # part 0
    t143 = add(None)
    plane = add(Ent(128, patch(0, 0, 0, 2, 1), status=sub))
    corners = [(0, 0, off), (2, 0, off), (2, 1, off), (0, 1, off)]
    border = [add(Ent(110, line(corners[k], corners[(k + 1) % 4]), status=sub)) for k in range(4)]
    outer = ["0", "0", de(plane), "4"]
    for b in border:
        outer += [de(b), "1", "0"]
    o141 = add(Ent(141, outer, status=sub))
    circle = add(Ent(100, [r(off), "1.0", "0.5", "1.3", "0.5", "1.3", "0.5"], status=sub))
    h141 = add(Ent(141, ["0", "0", de(plane), "1", de(circle), "1", "0"], status=sub))
    E[t143] = Ent(143, ["0", de(plane), "2", de(o141), de(h141)])

    # parts 1 and 2: one B-rep shell with two faces
    i186 = add(None)
    i514 = add(None)
    f_cyl = add(None)
    f_sph = add(None)
    cyl = add(Ent(128, nurbs_surface(2, 1, CIRCLE_KNOTS, [0, 0, 1, 1],
                                     [[(x, y, 0) for x, y in CIRCLE_XY],
                                      [(x, y, 2) for x, y in CIRCLE_XY]],
                                     CIRCLE_W * 2), status=sub))
    merid = [(0, -1, 1), (1, -1, math.sqrt(0.5)), (1, 0, 1), (1, 1, math.sqrt(0.5)), (0, 1, 1)]
    sph = add(Ent(128, nurbs_surface(2, 2, CIRCLE_KNOTS, [0, 0, 0, 0.5, 0.5, 1, 1, 1],
                                     [[(rho * x, rho * y, z) for x, y in CIRCLE_XY]
                                      for rho, z, _ in merid],
                                     [wu * wv for _, _, wv in merid for wu in CIRCLE_W]),
                  status=sub))
    c30, s30 = math.sqrt(3) / 2, 0.5
    verts = [(1, 0, 0), (1, 0, 1.5), (c30, 0, s30), (0, 0, 1)]
    vl = add(Ent(502, ["4"] + [r(x) for p in verts for x in p], form=1, status=sub))
    bottom = add(Ent(126, circle3(lambda x, y: (k * x, k * y, 0)), status=sub))
    seam = add(Ent(110, line((k, 0, 0), (k, 0, 1.5)), status=sub))
    ellipse = add(Ent(126, circle3(lambda x, y: (k * x, k * y, 1 + 0.5 * x)), status=sub))
    latitude = add(Ent(126, circle3(lambda x, y: (k * c30 * x, k * c30 * y, k * s30)),
                       status=sub))
    meridian = add(Ent(126, nurbs_curve(2, [0, 0, 0, 1, 1, 1],
                                        [(k * c30, 0, k * s30), (k * 0.5 / c30, 0, k),
                                         (0, 0, k)],
                                        [1, c30, 1]), status=sub))
    edges = [(bottom, 1, 1), (seam, 1, 2), (ellipse, 2, 2), (latitude, 3, 3), (meridian, 3, 4)]
    ep = [str(len(edges))]
    for crv, a, b in edges:
        ep += [de(crv), de(vl), str(a), de(vl), str(b)]
    el = add(Ent(504, ep, form=1, status=sub))

    def loop(entries):
        p = [str(len(entries))]
        for index, forward in entries:
            p += ["0", de(el), str(index), "1" if forward else "0", "0"]
        return add(Ent(508, p, form=1, status=sub))

    l_cyl = loop([(1, True), (2, True), (3, False), (2, False)])
    l_sph = loop([(4, True), (5, True), (5, False)])
    E[i186] = Ent(186, [de(i514), "1", "0"])
    E[i514] = Ent(514, ["2", de(f_cyl), "1", de(f_sph), "1"], form=1, status=sub)
    E[f_cyl] = Ent(510, [de(cyl), "1", "1", de(l_cyl)], form=1, status=sub)
    E[f_sph] = Ent(510, [de(sph), "1", "1", de(l_sph)], form=1, status=sub)
    save(name, build(E))
    if off:
        return
    # the same plate with its hole's circle 0.5 above the plane: it cannot be projected;
    # the reader warns and leaves that loop out
    E = E[:h141 + 1]
    E[circle] = Ent(100, ["0.5", "1.0", "0.5", "1.3", "0.5", "1.3", "0.5"], status=sub)
    save("iges_model_space_off.igs", build(E))


def file_analytic():
    """IGES 5.3 analytic surfaces (190-198) in a B-rep whose loops are in model space only
    (as Open CASCADE's B-rep export writes them), with closed-form areas:
    part 0: 192 form 0 cylinder (radius 1 about z), its seam edge at (0, 1): the face below
            the ellipse z = 1 + x / 2: 2 pi (the seam is placed where the edge is)
    part 1: 196 form 0 sphere (radius 1 around (5, 0, 0)), the cap above z = 1/2, seam
            meridian on the -x side: pi
    part 2: 190 form 1 plane z = 3 (refdir x): the square [-1,1]^2 with a hole of radius
            1/2: 4 - pi / 4
    part 3: a 198 torus (2, 0.5) on its own, whole: 4 pi^2 2 0.5
    and a 192 cylinder on its own, unbounded: skipped with a warning."""
    sub = "00010000"
    E = []

    def add(e):
        E.append(e)
        return len(E) - 1

    def point(p):
        return add(Ent(116, [r(x) for x in p], status=sub))

    def direction(d):
        return add(Ent(123, [r(x) for x in d], form=0, status=sub))

    i186 = add(None)
    i514 = add(None)
    faces = [add(None) for _ in range(3)]
    cyl = add(Ent(192, [de(point((0, 0, 0))), de(direction((0, 0, 1))), "1.0"], status=sub))
    sph = add(Ent(196, [de(point((5, 0, 0))), "1.0"], status=sub))
    pln = add(Ent(190, [de(point((0, 0, 3))), de(direction((0, 0, 1))), de(direction((1, 0, 0)))],
                  form=1, status=sub))
    c30, s30 = math.sqrt(3) / 2, 0.5
    rot = lambda x, y: (-y, x)  # circles starting at (0, 1)
    verts = [(0, 1, 0), (0, 1, 1), (5 - c30, 0, s30), (5, 0, 1), (1, 0, 3), (-1, 0, 3),
             (0.5, 0, 3)]
    vl = add(Ent(502, [str(len(verts))] + [r(x) for p in verts for x in p], form=1, status=sub))
    bottom = add(Ent(126, circle3(lambda x, y: (rot(x, y)[0], rot(x, y)[1], 0)), status=sub))
    seam = add(Ent(110, line((0, 1, 0), (0, 1, 1)), status=sub))
    ellipse = add(Ent(126, circle3(lambda x, y: (rot(x, y)[0], rot(x, y)[1], 1 + 0.5 * rot(x, y)[0])),
                      status=sub))
    latitude = add(Ent(126, circle3(lambda x, y: (5 - c30 * x, -c30 * y, s30)), status=sub))
    meridian = add(Ent(126, nurbs_curve(2, [0, 0, 0, 1, 1, 1],
                                        [(5 - c30, 0, s30), (5 - 0.5 / c30, 0, 1), (5, 0, 1)],
                                        [1, c30, 1]), status=sub))
    sq = [(-1, -1, 3), (1, -1, 3), (1, 1, 3), (-1, 1, 3)]
    square = [add(Ent(110, line(sq[k], sq[(k + 1) % 4]), status=sub)) for k in range(4)]
    hole = add(Ent(100, ["3.0", "0.0", "0.0", "0.5", "0.0", "0.5", "0.0"], status=sub))
    edges = [(bottom, 1, 1), (seam, 1, 2), (ellipse, 2, 2), (latitude, 3, 3), (meridian, 3, 4),
             (hole, 7, 7)] + [(square[k], 1, 1) for k in range(4)]
    ep = [str(len(edges))]
    for crv, a, b in edges:
        ep += [de(crv), de(vl), str(a), de(vl), str(b)]
    el = add(Ent(504, ep, form=1, status=sub))

    def loop(entries):
        p = [str(len(entries))]
        for index, forward in entries:
            p += ["0", de(el), str(index), "1" if forward else "0", "0"]
        return add(Ent(508, p, form=1, status=sub))

    l_cyl = loop([(1, True), (2, True), (3, False), (2, False)])
    l_sph = loop([(4, True), (5, True), (5, False)])
    l_sq = loop([(7, True), (8, True), (9, True), (10, True)])
    l_hole = loop([(6, True)])
    E[i186] = Ent(186, [de(i514), "1", "0"])
    E[i514] = Ent(514, ["3"] + [x for f in faces for x in (de(f), "1")], form=1, status=sub)
    E[faces[0]] = Ent(510, [de(cyl), "1", "1", de(l_cyl)], form=1, status=sub)
    E[faces[1]] = Ent(510, [de(sph), "1", "1", de(l_sph)], form=1, status=sub)
    E[faces[2]] = Ent(510, [de(pln), "2", "1", de(l_sq), de(l_hole)], form=1, status=sub)
    add(Ent(198, [de(point((0, -6, 0))), de(direction((0, 0, 1))), "2.0", "0.5"]))
    add(Ent(192, [de(point((0, 0, 9))), de(direction((1, 0, 0))), "1.0"]))
    save("iges_analytic.igs", build(E))


def file_unbounded_planes():
    """A box [0,4] x [0,3] x [0,2] (millimetres) as CATIA and FreeCAD write planar faces:
    each face a 144 on an unbounded 108 plane (PTR = 0) whose display symbol is 1.0 wide
    and drawn at a point far from the face, trimmed by a 142 with model-space curves only
    (BPTR = 0, PREF 2). The top face has a hole of radius 0.5 around (2, 1.5) (a 100 arc
    at ZT = 2). The display size must not bound the plane: areas 12, 12 - pi / 4, 6, 6,
    8, 8 (the corpus files occt_cone_catia and occt_cylinder_catia lost their caps).
    Then two 143 bounded surfaces whose hole comes first, and one whose outer boundary comes
    first (below)."""
    sub = "00010000"
    E = []

    def add(e):
        E.append(e)
        return len(E) - 1

    box = [(0, 0, 0), (4, 0, 0), (4, 3, 0), (0, 3, 0),
           (0, 0, 2), (4, 0, 2), (4, 3, 2), (0, 3, 2)]
    # faces: plane coefficients (A, B, C, D) and the corners in loop order
    faces = [((0, 0, -1, 0), (0, 3, 2, 1)), ((0, 0, 1, 2), (4, 5, 6, 7)),
             ((-1, 0, 0, 0), (0, 4, 7, 3)), ((1, 0, 0, 4), (1, 2, 6, 5)),
             ((0, -1, 0, 0), (0, 1, 5, 4)), ((0, 1, 0, 3), (3, 7, 6, 2))]
    for k, (abcd, corners) in enumerate(faces):
        t144 = add(None)
        display = (100.0 + k, -50.0, 75.0)
        plane = add(Ent(108, [r(x) for x in abcd] + ["0"] + [r(x) for x in display] + ["1.0"],
                        status=sub))
        lines = [add(Ent(110, line(box[corners[i]], box[corners[(i + 1) % 4]]), status=sub))
                 for i in range(4)]
        comp = add(Ent(102, ["4"] + [de(i) for i in lines], status=sub))
        outer = add(Ent(142, ["0", de(plane), "0", de(comp), "2"], status=sub))
        params = [de(plane), "1", "0", de(outer)]
        if k == 1:
            hole = add(Ent(100, ["2.0", "2.0", "1.5", "2.5", "1.5", "2.5", "1.5"], status=sub))
            inner = add(Ent(142, ["0", de(plane), "0", de(hole), "2"], status=sub))
            params = [de(plane), "1", "1", de(outer), de(inner)]
        E[t144] = Ent(144, params)
    # two 143s (141 TYPE 0, model space) on unbounded planes that list the hole before the
    # outer boundary, as I-DEAS does (corpus occt_ideas_simple1_143): a triangle (0,0)-(6,0)-
    # (0,6) at z = 5 around a hole of radius 1 at (1.5, 1.5): 18 - pi; the rectangle
    # [0,4] x [0,3] at z = 7 (the fitted plane's own border) around a hole of radius 0.5 at
    # (2, 1.5): 12 - pi / 4; and the triangle again at z = 9 with its outer boundary first
    # (the usual order: the plane must be sized by all boundaries, not by the last one read)
    for z, corners, centre, radius, outer_first in (
            (5.0, [(0, 0), (6, 0), (0, 6)], (1.5, 1.5), 1.0, False),
            (7.0, [(0, 0), (4, 0), (4, 3), (0, 3)], (2.0, 1.5), 0.5, False),
            (9.0, [(0, 0), (6, 0), (0, 6)], (1.5, 1.5), 1.0, True)):
        t143 = add(None)
        plane = add(Ent(108, ["0.0", "0.0", "1.0", r(z), "0", "-20.0", "30.0", r(z), "1.0"],
                        status=sub))
        hole = add(Ent(100, [r(z), r(centre[0]), r(centre[1]), r(centre[0] + radius),
                             r(centre[1]), r(centre[0] + radius), r(centre[1])], status=sub))
        h141 = add(Ent(141, ["0", "0", de(plane), "1", de(hole), "1", "0"], status=sub))
        pts = [(x, y, z) for x, y in corners]
        lines = [add(Ent(110, line(pts[i], pts[(i + 1) % len(pts)]), status=sub))
                 for i in range(len(pts))]
        outer = ["0", "0", de(plane), str(len(lines))]
        for ln in lines:
            outer += [de(ln), "1", "0"]
        o141 = add(Ent(141, outer, status=sub))
        order = [de(o141), de(h141)] if outer_first else [de(h141), de(o141)]
        E[t143] = Ent(143, ["0", de(plane), "2"] + order)
    save("iges_unbounded_planes.igs", build(E, unit_flag=2, unit_name="MM"))


def file_unseen_points():
    """Control points that no boundary sample sees (tests/test_unseen_points.c). A unit cube
    of six bicubic patches (6 x 6 control points, 3 x 3 knot spans, control points at the
    Greville abscissae: exact planes), and on its top face two more patches:
    part 6: the top face again, trimmed (144, (u,v) circle) to a disc of radius 0.02 around
            the middle of its middle span: the few samples inside see the 16 basis functions
            of that span, but cannot tell them apart, and see none of the other 20;
    part 7: the top face again, untrimmed, with the parameter range [0, 1/3] of its knots
            [0, 1]: control points 4 and 5 of each row are supported outside it.
    Before, either made the sample matrix singular ("a free control point is seen by no
    boundary sample") or left zero-energy modes."""
    knots = [0, 0, 0, 0, 1 / 3, 2 / 3, 1, 1, 1, 1]
    greville = [sum(knots[i + 1:i + 4]) / 3 for i in range(6)]

    def face(o, a, b, rng=None):
        grid = [[tuple(o[d] + greville[i] * a[d] + greville[j] * b[d] for d in range(3))
                 for i in range(6)] for j in range(6)]
        return nurbs_surface(3, 3, knots, knots, grid, rng=rng)

    cube = [((0, 0, 0), (0, 1, 0), (1, 0, 0)), ((0, 0, 1), (1, 0, 0), (0, 1, 0)),
            ((0, 0, 0), (1, 0, 0), (0, 0, 1)), ((0, 1, 0), (0, 0, 1), (1, 0, 0)),
            ((0, 0, 0), (0, 0, 1), (0, 1, 0)), ((1, 0, 0), (0, 1, 0), (0, 0, 1))]
    sub = "00010000"
    E = [Ent(128, face(o, a, b)) for o, a, b in cube]
    t144 = len(E)
    E.append(None)
    srf = len(E)
    E.append(Ent(128, face((0, 0, 1), (1, 0, 0), (0, 1, 0)), status=sub))
    circle = len(E)
    E.append(Ent(100, ["0.0", "0.5", "0.5", "0.52", "0.5", "0.52", "0.5"], status=sub))
    loop = len(E)
    E.append(Ent(142, ["1", de(srf), de(circle), "0", "1"], status=sub))
    E[t144] = Ent(144, [de(srf), "1", "0", de(loop)])
    E.append(Ent(128, face((0, 0, 1), (1, 0, 0), (0, 1, 0), rng=(0, 1 / 3, 0, 1))))
    save("iges_unseen_points.igs", build(E))


def file_repairs():
    """Defects Open CASCADE reads past, each repaired with a warning (corpus files in
    brackets): unit flag 0 and no unit name [occt_rhino_bad_header] (inches, the IGES
    default); a patch [0,2] x [0,1] whose range is written U0 V0 U1 V1
    [occt_rhino_bounded_143] (the knots' range); its 144 loop of four 126 lines whose range
    is written 0, 0 [occt_solidedge_deflector] (the knots' range, [-1, 0]); and a last
    entity whose parameter line count runs past the Parameter section
    [occt_rhino_bad_header] (the lines that point back to it). Areas 0.5 (the loop
    [0.5, 1.5] x [0.25, 0.75]) and 1."""
    sub = "00010000"
    srf = nurbs_surface(1, 1, [0, 0, 2, 2], [0, 0, 1, 1],
                        [[(0, 0, 0), (2, 0, 0)], [(0, 1, 0), (2, 1, 0)]])
    srf[-4:] = ["0.0", "0.0", "2.0", "1.0"]  # U0 V0 U1 V1: read as [0, 0] x [2, 1], empty
    E = [Ent(144, [de(1), "1", "0", de(2)]), Ent(128, srf, status=sub),
         Ent(142, ["1", de(1), de(3), "0", "1"], status=sub),
         Ent(102, ["4", de(4), de(5), de(6), de(7)], status=sub)]
    # the loop [0.5, 1.5] x [0.25, 0.75] in (u,v): 126 lines on knots [-1, -1, 0, 0]
    pts = [(0.5, 0.25, 0), (1.5, 0.25, 0), (1.5, 0.75, 0), (0.5, 0.75, 0)]
    for k in range(4):
        c = nurbs_curve(1, [-1, -1, 0, 0], [pts[k], pts[(k + 1) % 4]], t0=0.0, t1=0.0)
        E.append(Ent(126, c[:-3], status=sub))  # no normal, as Solid Edge writes it
    E.append(Ent(128, patch(0, 0, 1, 1, 1), pd_count=40))
    save("iges_repairs.igs", build(E, unit_flag=0, unit_name=""))


def file_seams():
    """Trim loops on closed surfaces and loops with gaps (issue 29, item 2), each with a closed
    form for its area:
    part 0: the cylinder of radius 1, z 0..2 (closed in u, seam at (1, 0)), trimmed in (u,v)
            by the rectangle u in [-0.25, 0.25], v in [0.25, 0.75]: it crosses the seam (as
            corpus occt_torus_periodic's loop does): half the circumference, height 1: pi
    part 1: the unit sphere, trimmed in (u,v) to the cap above latitude 45 degrees (v = 0.75):
            the latitude, the seam meridian up, down again, without the edge along the pole
            (SolidWorks and Solid Edge leave it out: corpus occt_solidworks_tube): 2 pi (1 -
            sqrt(1/2))
    part 2: a 120 cylinder (radius 1, axis z, line generatrix z 0..2, angles 0..2 pi) trimmed
            by a 142 with both curves: in (u,v) the rectangle u in [0.25, 0.75] (the line's
            parameter), v in [0.3, 1.3] (angles), in model space the same: the angle is not
            the parameter of our rational circle, so the model-space curves are taken: 1
    part 3: a 122 tabulated cylinder over a polyline of length 3 on [0, 3], extruded by 2,
            trimmed in (u,v) by [0, 1] x [0, 0.5]: IGES's u runs over [0, 1] (corpus
            dealii_side_inch): 3
    part 4: the cylinder of part 0 trimmed by a model-space loop only, crossing the seam:
            arcs at z 0.5 and 1.5 between -45 and 45 degrees, lines between them: pi / 2
    part 5: the unit square plate trimmed by a model-space square [0.25, 0.75]^2 whose last
            side stops 1e-4 short (more than the projection's tolerance, within 1e-4 of the
            surface's size, sqrt 2): bridged with a warning: 0.25
    (The closed surfaces say so, PROP1 = 1, as CAD files write them.)"""
    sub = "00010000"
    E = []

    def add(e):
        E.append(e)
        return len(E) - 1

    def lines_uv(pts):
        return [add(Ent(110, line(pts[k], pts[(k + 1) % len(pts)]), status=sub))
                for k in range(len(pts))]

    def trimmed(srf, bptr_curves=None, cptr_curves=None, pref=1):
        t = add(None)
        b = add(Ent(102, [str(len(bptr_curves))] + [de(c) for c in bptr_curves], status=sub)) \
            if bptr_curves else None
        c = add(Ent(102, [str(len(cptr_curves))] + [de(x) for x in cptr_curves], status=sub)) \
            if cptr_curves else None
        loop = add(Ent(142, ["1" if b is not None else "0", de(srf), de(b) if b is not None else "0",
                             de(c) if c is not None else "0", str(pref)], status=sub))
        E[t] = Ent(144, [de(srf), "1", "0", de(loop)])

    cylinder = nurbs_surface(2, 1, CIRCLE_KNOTS, [0, 0, 1, 1],
                             [[(x, y, 0) for x, y in CIRCLE_XY], [(x, y, 2) for x, y in CIRCLE_XY]],
                             CIRCLE_W * 2, closed=(1, 0))
    # part 0
    s0 = add(Ent(128, cylinder, status=sub))
    trimmed(s0, lines_uv([(-0.25, 0.25, 0), (0.25, 0.25, 0), (0.25, 0.75, 0), (-0.25, 0.75, 0)]))
    # part 1
    merid = [(0, -1, 1), (1, -1, math.sqrt(0.5)), (1, 0, 1), (1, 1, math.sqrt(0.5)), (0, 1, 1)]
    s1 = add(Ent(128, nurbs_surface(2, 2, CIRCLE_KNOTS, [0, 0, 0, 0.5, 0.5, 1, 1, 1],
                                    [[(rho * x, rho * y, z) for x, y in CIRCLE_XY]
                                     for rho, z, _ in merid],
                                    [wu * wv for _, _, wv in merid for wu in CIRCLE_W],
                                    closed=(1, 0)), status=sub))
    cap = [add(Ent(110, line(p, q), status=sub)) for p, q in
           [((0, 0.75, 0), (1, 0.75, 0)), ((1, 0.75, 0), (1, 1, 0)), ((0, 1, 0), (0, 0.75, 0))]]
    trimmed(s1, cap)
    # part 2
    axis = add(Ent(110, line((0, 0, 0), (0, 0, 1)), status=sub))
    gen = add(Ent(110, line((1, 0, 0), (1, 0, 2)), status=sub))
    s2 = add(Ent(120, [de(axis), de(gen), "0.0", r(2 * math.pi)], status=sub))
    a0, a1 = 0.3, 1.3
    uv = lines_uv([(0.25, a0, 0), (0.75, a0, 0), (0.75, a1, 0), (0.25, a1, 0)])
    ms = [add(Ent(100, [r(0.5), "0.0", "0.0", r(math.cos(a0)), r(math.sin(a0)), r(math.cos(a1)),
                        r(math.sin(a1))], status=sub)),
          add(Ent(110, line((math.cos(a1), math.sin(a1), 0.5), (math.cos(a1), math.sin(a1), 1.5)),
                  status=sub)),
          add(Ent(100, [r(1.5), "0.0", "0.0", r(math.cos(a0)), r(math.sin(a0)), r(math.cos(a1)),
                        r(math.sin(a1))], status=sub)),
          add(Ent(110, line((math.cos(a0), math.sin(a0), 1.5), (math.cos(a0), math.sin(a0), 0.5)),
                  status=sub))]
    trimmed(s2, uv, ms)
    # part 3
    poly = add(Ent(126, nurbs_curve(1, [0, 0, 1, 2, 3, 3], [(0, 0, 0), (1, 0, 0), (1, 1, 0),
                                                          (0, 1, 0)]), status=sub))
    s3 = add(Ent(122, [de(poly), "0.0", "0.0", "2.0"], status=sub))
    trimmed(s3, lines_uv([(0, 0, 0), (1, 0, 0), (1, 0.5, 0), (0, 0.5, 0)]))
    # part 4
    s4 = add(Ent(128, cylinder, status=sub))
    c45 = math.sqrt(0.5)
    ms = [add(Ent(100, [r(0.5), "0.0", "0.0", r(c45), r(-c45), r(c45), r(c45)], status=sub)),
          add(Ent(110, line((c45, c45, 0.5), (c45, c45, 1.5)), status=sub)),
          add(Ent(100, [r(1.5), "0.0", "0.0", r(c45), r(-c45), r(c45), r(c45)], status=sub)),
          add(Ent(110, line((c45, -c45, 1.5), (c45, -c45, 0.5)), status=sub))]
    trimmed(s4, None, ms, pref=2)
    # part 5
    s5 = add(Ent(128, patch(0, 0, 0, 1, 1), status=sub))
    sq = [(0.25, 0.25, 0), (0.75, 0.25, 0), (0.75, 0.75, 0), (0.25, 0.75, 0)]
    ms = [add(Ent(110, line(sq[k], sq[(k + 1) % 4] if k < 3 else (0.25, 0.25 + 1e-4, 0)),
                  status=sub)) for k in range(4)]
    trimmed(s5, None, ms, pref=2)
    save("iges_seams.igs", build(E))


def file_cone_apex():
    """A cone as CATIA writes it (corpus occt_cone_catia): a 120 surface of revolution of the
    line from (60, 0, -70) to the apex (0, 0, 80) about the z axis, closed by an unbounded 108
    plane z = -70 trimmed to the disc of radius 60 (model-space circle only), millimetres. The
    generatrix has degree 1, so the cone's Lobatto points lie on its base circle and at its
    apex, where the area element vanishes: weighted by area the group's samples are flat
    (tests/test_unseen_points.c: the fit must still be exact, and the model simulated)."""
    sub = "00010000"
    E = []

    def add(e):
        E.append(e)
        return len(E) - 1

    axis = add(Ent(110, line((0, 0, 0), (0, 0, 1)), status=sub))
    gen = add(Ent(110, line((60, 0, -70), (0, 0, 80)), status=sub))
    add(Ent(120, [de(axis), de(gen), "0.0", r(2 * math.pi)]))
    t144 = add(None)
    plane = add(Ent(108, ["0.0", "0.0", "-1.0", "70.0", "0", "0.0", "0.0", "-70.0", "1.0"],
                    status=sub))
    circle = add(Ent(100, ["-70.0", "0.0", "0.0", "60.0", "0.0", "60.0", "0.0"], status=sub))
    loop = add(Ent(142, ["0", de(plane), "0", de(circle), "2"], status=sub))
    E[t144] = Ent(144, [de(plane), "1", "0", de(loop)])
    save("iges_cone_apex.igs", build(E, unit_flag=2, unit_name="MM"))


# ---------------------------------------------------------------- errors ----

def good_curve_surface():
    """A valid trimmed part used as the base of the error files (128 at DE 3)."""
    sq = uv_square(0.25, 0.75, 0.25, 0.75)
    return [Ent(144, [de(1), "1", "0", de(2)]),
            Ent(128, patch(0, 0, 0, 1, 1), status="00010000"),
            Ent(142, ["0", de(1), de(3), "0", "1"], status="00010000"),
            Ent(102, ["4", de(4), de(5), de(6), de(7)], status="00010000")] + sq


def errors():
    base = build(good_curve_surface())
    save("iges_err_base_ok.igs", base)
    save("iges_err_empty.igs", "")
    lines = base.split("\n")
    pidx = [i for i, l in enumerate(lines) if len(l) > 72 and l[72] == "P"]
    save("iges_err_truncated.igs", "\n".join(lines[:pidx[len(pidx) // 2]]) + "\n")
    save("iges_err_no_terminate.igs", "\n".join(l for l in lines if not (len(l) > 72 and l[72] == "T")))

    def variant(name, mutate):
        ents = good_curve_surface()
        mutate(ents)
        save(name, build(ents))

    def set_param(ents, i, k, v):
        ents[i].params[k - 1] = v

    variant("iges_err_pointer_range.igs", lambda e: set_param(e, 0, 1, "999"))
    variant("iges_err_pointer_type.igs", lambda e: set_param(e, 0, 1, de(3)))
    # K = 5 but the data has 2 x 2 points
    variant("iges_err_counts.igs", lambda e: set_param(e, 1, 1, "5"))
    variant("iges_err_not_number.igs", lambda e: set_param(e, 1, 20, "1.0x"))
    variant("iges_err_nan.igs", lambda e: set_param(e, 1, 20, "nan"))
    variant("iges_err_inf.igs", lambda e: set_param(e, 1, 20, "1.0D999"))
    variant("iges_err_zero_weight.igs", lambda e: set_param(e, 1, 18, "0.0"))
    variant("iges_err_negative_weight.igs", lambda e: set_param(e, 1, 18, "-1.0"))
    # decreasing: u knots 0, 0, 1, 1 -> 0, 1, 0.5, 1 (knot 2 < knot 1)
    variant("iges_err_knots.igs", lambda e: (set_param(e, 1, 11, "1.0"), set_param(e, 1, 12, "0.5")))
    # degree 2 in u with 2 control points
    variant("iges_err_degree.igs", lambda e: set_param(e, 1, 3, "2"))
    # the third line of the loop ends somewhere else: loop does not close
    variant("iges_err_open_loop.igs", lambda e: set_param(e, 6, 4, "0.5"))
    # 124 chain that points to itself
    def cyc(ents):
        ents[1].xform = de(len(ents))
        ents.append(Ent(124, xform([[1, 0, 0], [0, 1, 0], [0, 0, 1]], (0, 0, 0)),
                        xform=de(len(ents))))
    variant("iges_err_xform_cycle.igs", cyc)
    # a Hollerith string claiming more characters than the entity has
    variant("iges_err_hollerith.igs",
            lambda e: e.append(Ent(406, ["1", "40Hshort"], form=15)))


if __name__ == "__main__":
    file_delims()
    file_short_lines()
    file_xform()
    file_subfigure()
    file_plane()
    file_ruled()
    file_revolution()
    file_tabulated()
    file_brep()
    file_unknown()
    file_cad_trimmed()
    file_bptr0()
    file_model_space()
    file_model_space("iges_model_space_near.igs", 1e-4)
    file_analytic()
    file_unbounded_planes()
    file_unseen_points()
    file_repairs()
    file_seams()
    file_cone_apex()
    errors()
