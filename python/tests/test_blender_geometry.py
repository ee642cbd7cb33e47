"""The Blender add-on's geometry (blender/sem_blender/geometry.py: numpy only, no Blender):
which parts Blender holds as NURBS surfaces, basis functions, the control points behind a
pinned vertex, the scene transform."""
import importlib.util
import os

import numpy as np
import pytest

import sem

from conftest import SOURCE_DIR

_spec = importlib.util.spec_from_file_location(
    "sem_blender_geometry", os.path.join(SOURCE_DIR, "blender", "sem_blender", "geometry.py"))
geometry = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(geometry)


def test_endpoint_knots():
    assert geometry.endpoint_knots([0, 0, 0, 1, 1, 1], 2, 3)
    assert geometry.endpoint_knots([2, 2, 2, 2, 3, 4, 5, 5, 5, 5], 3, 6)        # shifted, scaled
    assert geometry.endpoint_knots([0, 0, 0, 0, 2.0943951023932, 4.18879020478639,
                                    6.28318530717959] + [6.28318530717959] * 3, 3, 6)
    assert not geometry.endpoint_knots([0, 0, 0, 1, 3, 3, 3], 2, 4)             # not uniform
    assert not geometry.endpoint_knots([0, 0, 0, 1, 1, 2, 2, 2], 2, 5)          # a double knot
    assert not geometry.endpoint_knots([0, 1, 2, 3, 4, 5], 2, 3)                # unclamped
    assert not geometry.endpoint_knots([0, 0, 0, 1, 1, 1], 2, 3, (0, 0.5))      # part of it


def test_which_parts_blender_holds():
    beam = sem.Model.primitive("beam", sections=2)
    orders, why = geometry.blender_surface_orders(beam.surface(0), False)
    assert orders == (3, 3) and why == ""                     # biquadratic Bezier patches
    orders, why = geometry.blender_surface_orders(beam.surface(0), True)
    assert orders is None and "trimmed" in why
    surface = dict(beam.surface(0), degree=(6, 3))
    assert "degree 6" in geometry.blender_surface_orders(surface, False)[1]


def test_basis_functions_partition_of_unity_and_support():
    knots = np.array([0, 0, 0, 1, 2, 3, 3, 3], dtype=float)   # quadratic, 5 points
    for t in np.linspace(0, 3, 31):
        span, N = geometry.basis_functions(knots, 2, 5, t)
        assert 2 <= span <= 4 and abs(N.sum() - 1) < 1e-15 and np.all(N >= 0)
    # at a clamped end only the end point's function is non-zero; at a simple interior knot
    # two of the three (the third is exactly zero)
    assert np.array_equal(geometry.basis_functions(knots, 2, 5, 0.0)[1], [1, 0, 0])
    assert np.array_equal(geometry.basis_functions(knots, 2, 5, 3.0)[1], [0, 0, 1])
    span, N = geometry.basis_functions(knots, 2, 5, 1.0)
    assert span == 3 and N[2] == 0 and abs(N[0] - 0.5) < 1e-15


def test_supporting_points_hold_the_vertex():
    """On the box's patches: a vertex on an edge depends on that edge's three
    control points only, a corner on one, an interior point on all of them; the surface point
    from the numpy evaluation is sem's tessellation vertex."""
    m = sem.Model.primitive("box", size=[1, 2, 3])
    surface = m.surface(0)
    n_u, n_v = surface["control_grid"]
    assert geometry.supporting_points(surface, 0.0, 0.0) == [0]
    edge = geometry.supporting_points(surface, 0.5, 0.0)
    assert edge == list(range(n_u))                           # the v = 0 row
    assert len(geometry.supporting_points(surface, 0.5, 0.5)) == n_u * n_v
    t = m.tessellate(3)
    q = m.q()
    off = m.part_offsets()
    for k in range(t.part_vertex_start[1]):
        x = geometry.surface_point(surface, q[off[0]:off[1]], *t.uv[k])
        assert np.allclose(x, t.positions[k], rtol=0, atol=1e-14)


def test_pinned_control_points_of_a_vertex_group():
    m = sem.Model.primitive("beam", sections=2, length=2)
    t = m.tessellate(2)
    # every vertex of part 0 (the x = 0 end cap) holds exactly its own control points
    n0 = t.part_vertex_start[1] - t.part_vertex_start[0]
    pinned = geometry.pinned_control_points(m, t, {0: list(range(n0))})
    off = m.part_offsets()
    assert pinned == list(range(off[0], off[1]))


def test_scene_transform():
    assert geometry.scene_transform(np.eye(4), 1.0) is None
    m = np.eye(4)
    m[:3, 3] = [1, 2, 3]
    m[0, 0] = 2
    assert geometry.scene_transform(m, 0.5) == {"matrix": [[2, 0, 0, 0.5], [0, 1, 0, 1],
                                                           [0, 0, 1, 1.5]]}
    m[0, 0] = -1
    with pytest.raises(ValueError, match="mirror"):
        geometry.scene_transform(m, 1.0)
    # world_to_local undoes the placement (Blender units = metres / 0.5)
    m[0, 0] = 2
    local = np.array([[0.1, 0.2, 0.3]])
    world = (local @ m[:3, :3].T + m[:3, 3]) * 0.5
    assert np.allclose(geometry.world_to_local(world, m, 0.5), local, atol=1e-15)
