"""Models from Python: loading, control points, measures, files, preprocessing, errors."""
import os

import numpy as np
import pytest

import sem

from conftest import shared_model


def test_box_primitive_area_and_control_points():
    m = sem.Model.primitive("box", size=[1, 2, 3])
    assert m.parts == 6
    assert m.control_points == 6 * 16 and m.dofs == 3 * 96
    measure = m.measure()
    assert abs(measure["area"] - 22.0) < 1e-9
    assert np.allclose(measure["bbox"][0], [-0.5, -1, -1.5], atol=1e-9)
    assert np.allclose(measure["bbox"][1], [0.5, 1, 1.5], atol=1e-9)
    assert abs(measure["part_areas"].sum() - 22.0) < 1e-9


def test_q_roundtrip_and_scaling_scales_the_area():
    m = sem.Model.primitive("sphere", radius=1.0)
    q = m.q()
    assert q.shape == (m.control_points, 3)
    m.set_q(2.0 * q)
    assert np.array_equal(m.q(), 2.0 * q)
    assert abs(m.measure()["area"] - 4 * np.pi * 4.0) < 1e-8
    with pytest.raises(ValueError):
        m.set_q(q[:-1])


def test_shared_model_b1(outdir):
    m = sem.load(shared_model("beams/perf/b1.igs"))
    assert m.parts == 6 and m.dofs == 162       # 6 biquadratic 3 x 3 patches
    assert abs(m.measure()["area"] - 22.0) < 1e-9  # 5 x 1 x 1 m beam
    # written and read back: the same control points
    path = os.path.join(outdir, "b1.igs")
    m.save(path)
    again = sem.load(path)
    assert np.array_equal(again.q(), m.q())
    assert again.units == m.units


def test_errors_carry_the_library_message(outdir):
    with pytest.raises(sem.SemError) as e:
        sem.load(os.path.join(outdir, "missing.igs"))
    assert "missing.igs" in str(e.value) and "cannot open" in str(e.value)
    assert e.value.status == "SEM_ERR_IO"
    with pytest.raises(sem.SemError) as e:
        sem.load(os.path.join(outdir, "model.xyz"))
    assert "unknown model file extension" in str(e.value)
    with pytest.raises(sem.SemError) as e:
        sem.Model.primitive("box", radius=1)
    assert "radius" in str(e.value)


def test_preprocess_box_volume_and_views():
    m = sem.Model.primitive("box", size=[1, 2, 3])
    d = m.preprocess(order=1, rays=[4, 4], points_per_interval=2)
    assert d.order == 1 and d.parts == 6 and d.dofs == m.dofs
    assert abs(d.volume - 6.0) < 1e-9           # rays through a box: exact
    X, vol = d.quadrature_points, d.quadrature_volumes
    assert X.shape == (vol.shape[0], 3) and vol.shape[0] > 0
    assert abs(vol.sum() - d.volume) < 1e-12
    assert not X.flags.writeable
    assert np.all(np.abs(X) <= [0.5, 1, 1.5])
    del d                                        # the views keep the memory alive
    assert abs(vol.sum() - 6.0) < 1e-9
    with pytest.raises(TypeError) as e:
        m.preprocess(desnity=1)
    assert "desnity" in str(e.value)
    with pytest.raises(sem.SemError):
        m.preprocess(order=3)


def test_preprocess_fits():
    m = sem.Model.primitive("beam", sections=3)
    own = m.preprocess(rays=[3, 3], points_per_interval=4)
    shared = m.preprocess(rays=[3, 3], points_per_interval=4, fit="origins")
    assert own.fits == "parts" and shared.fits == "origins"
    assert shared.origins == own.origins and own.origins >= 1
    with pytest.raises(ValueError):
        m.preprocess(fit="faces")


@pytest.mark.skipif(not sem.has_step(), reason="libsem built without Open CASCADE")
def test_step_roundtrip(outdir):
    m = sem.Model.primitive("cylinder", radius=0.5, height=2)
    path = os.path.join(outdir, "cylinder.step")
    m.save(path)
    back = sem.load(path)
    assert back.parts == m.parts and back.units == m.units
    assert np.allclose(back.q(), m.q(), atol=1e-12)
    area = 2 * np.pi * 0.5 * 2 + 2 * np.pi * 0.25
    assert abs(back.measure()["area"] - area) < 1e-9 * area


def test_step_support_is_reported():
    assert sem.has_step() in (True, False)
    if not sem.has_step():
        with pytest.raises(sem.SemError) as e:
            sem.load("x.step")
        assert "not supported by this build" in str(e.value)


def test_tessellation_matches_the_model_and_follows_its_control_points():
    """A 1 x 2 x 3 box's triangle mesh: its area tends to 22 (flat faces: exactly), its
    vertices lie on the faces, and moving the control points moves the mesh the same way."""
    m = sem.Model.primitive("box", size=[1, 2, 3])
    t = m.tessellate(4)
    assert t.parts == 6 and len(t.part_vertex_start) == 7
    p = t.positions
    tri = t.triangles
    area = 0.5 * np.linalg.norm(np.cross(p[tri[:, 1]] - p[tri[:, 0]],
                                         p[tri[:, 2]] - p[tri[:, 0]]), axis=1).sum()
    assert abs(area - 22.0) < 1e-9
    assert np.allclose(np.abs(p).max(axis=0), [0.5, 1, 1.5], atol=1e-12)
    assert t.uv.shape == (len(p), 2) and t.triangle_part.shape == (len(tri),)
    assert np.all(np.diff(t.part_vertex_start) > 0)
    moved = m.copy()
    moved.set_q(2.0 * m.q() + [1.0, 0, 0])
    assert np.allclose(t.update(moved), 2.0 * p + [1.0, 0, 0], atol=1e-12)
    with pytest.raises(ValueError):
        m.tessellate(0)
