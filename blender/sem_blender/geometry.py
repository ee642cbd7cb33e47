"""The add-on's geometry, without Blender (numpy only, so it is testable anywhere).

* Which parts Blender can hold as NURBS surfaces. Blender 3.4 evaluates a surface spline from
  its control points, weights and orders and makes its knots itself: with "Endpoint" they are
  clamped and uniform (order equal knots at each end, equally spaced simple knots between).
  A part whose knot vectors are of that form (after an affine change of parameter, which does
  not change the surface), whose domain is its whole knot range, untrimmed, of degree 5 or
  less (Blender's orders go to 6), is the same surface in Blender; any other part becomes a
  mesh (sem's tessellation, the same one `sem run` writes as frame_NNNN_mesh.obj).
* B-spline basis functions (The NURBS Book, A2.1 and A2.2) and NURBS surface points, to find
  the control points behind the vertices of a pinning vertex group: a vertex at (u, v) is
  held exactly when every control point whose basis function is non-zero there is held, so
  those are the points a vertex group pins.
* The scene transform of a Blender object's matrix (sem's "transform": {"matrix": [A | b]},
  in metres).
"""

import numpy as np

BLENDER_MAX_ORDER = 6  # Blender's NURBS orders: 2..6


def endpoint_knots(knots, degree, count, domain=None):
    """True when `knots` (count + degree + 1 values) are Blender's "Endpoint" knots up to an
    affine change of parameter: degree + 1 equal values at each end, the ones between simple
    and equally spaced (to 1e-9 of the range: files print knots rounded), and `domain`
    (t0, t1), when given, the whole range."""
    k = np.asarray(knots, dtype=np.float64)
    if degree < 1 or count < degree + 1 or len(k) != count + degree + 1:
        return False
    a, b = k[degree], k[count]
    if not b > a:
        return False
    tolerance = 1e-9 * (b - a)
    if np.any(np.abs(k[:degree + 1] - a) > tolerance) or np.any(np.abs(k[count:] - b) > tolerance):
        return False
    spans = count - degree
    uniform = a + (b - a) * np.arange(spans + 1) / spans
    if np.any(np.abs(k[degree:count + 1] - uniform) > tolerance):
        return False
    if domain is not None and (abs(domain[0] - a) > tolerance or abs(domain[1] - b) > tolerance):
        return False
    return True


def blender_surface_orders(surface, trimmed):
    """(order_u, order_v) when Blender can hold the part as a NURBS surface with Endpoint
    knots, else (None, why). `surface` is sem.Model.surface(i)."""
    if trimmed:
        return None, "trimmed (Blender's surfaces have no trims)"
    du, dv = surface["degree"]
    nu, nv = surface["control_grid"]
    if max(du, dv) + 1 > BLENDER_MAX_ORDER:
        return None, "degree %d (Blender's surfaces go to degree %d)" % (max(du, dv),
                                                                          BLENDER_MAX_ORDER - 1)
    u0, u1, v0, v1 = surface["domain"]
    if not endpoint_knots(surface["knots_u"], du, nu, (u0, u1)):
        return None, "its u knots are not clamped and uniform"
    if not endpoint_knots(surface["knots_v"], dv, nv, (v0, v1)):
        return None, "its v knots are not clamped and uniform"
    return (du + 1, dv + 1), ""


def find_span(knots, degree, count, t):
    """The knot span index i (degree <= i < count) with knots[i] <= t < knots[i + 1]; the
    last span for t at the end of the range (The NURBS Book, A2.1)."""
    if t >= knots[count]:
        i = count - 1
        while i > degree and knots[i] == knots[i + 1]:
            i -= 1
        return i
    if t <= knots[degree]:
        i = degree
        while i < count - 1 and knots[i] == knots[i + 1]:
            i += 1
        return i
    lo, hi = degree, count
    mid = (lo + hi) // 2
    while t < knots[mid] or t >= knots[mid + 1]:
        if t < knots[mid]:
            hi = mid
        else:
            lo = mid
        mid = (lo + hi) // 2
    return mid


def basis_functions(knots, degree, count, t):
    """(span, N): the degree + 1 B-spline basis functions that can be non-zero at t, N[k]
    belonging to control point span - degree + k (The NURBS Book, A2.2)."""
    span = find_span(knots, degree, count, t)
    N = np.zeros(degree + 1)
    N[0] = 1.0
    left = np.zeros(degree + 1)
    right = np.zeros(degree + 1)
    for j in range(1, degree + 1):
        left[j] = t - knots[span + 1 - j]
        right[j] = knots[span + j] - t
        saved = 0.0
        for r in range(j):
            temp = N[r] / (right[r + 1] + left[j - r])
            N[r] = saved + right[r + 1] * temp
            saved = left[j - r] * temp
        N[j] = saved
    return span, N


def surface_point(surface, control_points, u, v):
    """The NURBS surface's point at (u, v): sum N_i(u) N_j(v) w_ij P_ij / sum N_i N_j w_ij.
    control_points: (n_u * n_v, 3), u index fastest (sem's order)."""
    du, dv = surface["degree"]
    nu, nv = surface["control_grid"]
    su, Nu = basis_functions(surface["knots_u"], du, nu, u)
    sv, Nv = basis_functions(surface["knots_v"], dv, nv, v)
    w = surface["weights"]
    P = np.asarray(control_points).reshape(nv, nu, 3)
    rows = slice(sv - dv, sv + 1)
    cols = slice(su - du, su + 1)
    coefficients = np.outer(Nv, Nu) * w[rows, cols]
    return (coefficients[:, :, None] * P[rows, cols]).sum(axis=(0, 1)) / coefficients.sum()


def supporting_points(surface, u, v, relative=1e-12):
    """Indices (within the part, u fastest) of the control points whose basis functions are
    non-zero at (u, v): holding them holds the surface point there, whatever else moves."""
    du, dv = surface["degree"]
    nu, nv = surface["control_grid"]
    su, Nu = basis_functions(surface["knots_u"], du, nu, u)
    sv, Nv = basis_functions(surface["knots_v"], dv, nv, v)
    out = []
    for b in range(dv + 1):
        for a in range(du + 1):
            if Nu[a] * Nv[b] > relative:
                out.append((sv - dv + b) * nu + (su - du + a))
    return out


def pinned_control_points(model, tessellation, part_vertices):
    """Global control point indices (sem's "pin": {"points": [...]}) that hold the given
    tessellation vertices: part_vertices maps a part index to the indices of its vertices
    within the part (0 .. its vertex count). Sorted, without repeats."""
    offsets = model.part_offsets()
    start = tessellation.part_vertex_start
    pinned = set()
    for part, vertices in part_vertices.items():
        surface = model.surface(part)
        uv = tessellation.uv[start[part]:start[part + 1]]
        for k in vertices:
            u, v = uv[k]
            pinned.update(int(offsets[part]) + i for i in supporting_points(surface, u, v))
    return sorted(pinned)


def scene_transform(matrix, metres_per_unit):
    """sem's "transform" for a Blender object's 4 x 4 world matrix (Blender units, each
    metres_per_unit metres): {"matrix": [A | b]} in metres, or None for the identity. Raises
    ValueError for a mirroring or flattening matrix (sem would turn the surfaces inside out)."""
    m = np.asarray(matrix, dtype=np.float64)
    A = m[:3, :3]
    b = m[:3, 3] * metres_per_unit
    if not np.linalg.det(A) > 0:
        raise ValueError("its placement mirrors or flattens it (a negative or zero scale): "
                         "sem cannot simulate a mirrored model; apply a positive scale")
    if np.array_equal(A, np.eye(3)) and not b.any():
        return None
    return {"matrix": [[float(A[r, 0]), float(A[r, 1]), float(A[r, 2]), float(b[r])]
                       for r in range(3)]}


def world_to_local(points, matrix, metres_per_unit):
    """Simulated points (world, metres) into an object's local coordinates (Blender units):
    the inverse of its 4 x 4 world matrix applied to points / metres_per_unit."""
    m = np.asarray(matrix, dtype=np.float64)
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3) / metres_per_unit
    if np.array_equal(m, np.eye(4)):
        return p
    inverse = np.linalg.inv(m)
    return p @ inverse[:3, :3].T + inverse[:3, 3]
