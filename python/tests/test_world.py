"""Worlds from Python: scenes as dicts or files, stepping, state views, energies."""
import json
import os

import numpy as np
import pytest

import sem

from conftest import SOURCE_DIR

G = 9.81


def falling_box(**extra):
    scene = {"objects": [{"primitive": {"type": "box", "size": [1, 1, 1]},
                          "material": {"density": 500, "youngs_modulus": 1e5},
                          "sem": {"order": 1, "rays": [3, 3]}}],
             "gravity": [0, 0, -G],
             "integrator": {"type": "linearly_implicit_euler", "dt": 0.01}}
    scene.update(extra)
    return scene


def test_free_fall_closed_form():
    """An unpinned box under gravity moves rigidly: every control point's velocity is -g t
    and the kinetic energy 1/2 m (g t)^2, whatever the elastic model."""
    w = sem.World.from_scene(falling_box())
    assert w.object_count == 1 and w.dt == 0.01 and w.time == 0
    q0 = w.q(0).copy()
    w.step(10)
    t = w.time
    assert abs(t - 0.1) < 1e-12
    v = w.v(0)
    assert v.shape == q0.shape
    assert np.allclose(v, [0, 0, -G * t], atol=1e-9)
    e = w.energies()
    m = w.stats(0)["mass"]
    assert abs(m - 500.0) < 1e-9
    assert abs(e["kinetic_energy"] - 0.5 * m * (G * t) ** 2) < 1e-6
    # no deformation: the elastic and error energies vanish (to rounding, against 24 J)
    assert abs(e["elastic_energy"]) < 1e-9 and abs(e["error_energy"]) < 1e-8
    # momentum: m v
    assert np.allclose(w.frame()["linear_momentum"], [0, 0, -m * G * t], atol=1e-7)
    # the control points fell by the implicit Euler sum dt^2 g (1 + 2 + ... + 10)
    drop = 0.01 * 0.01 * G * 55
    assert np.allclose(w.q(0) - q0, [0, 0, -drop], atol=1e-9)


def test_state_arrays_are_live_views_without_copies():
    w = sem.World.from_scene(falling_box())
    q = w.q(0)
    flat = w.q(0, flat=True)
    assert np.shares_memory(q, w.q(0)) and np.shares_memory(q, flat)
    assert flat.shape == (3 * q.shape[0],)
    assert not q.flags.writeable
    z0 = q[:, 2].copy()
    w.step()
    assert np.all(q[:, 2] < z0)                  # the same array now shows the new state
    w.close()
    assert q.shape[1] == 3 and np.isfinite(q).all()  # still valid: the view holds the world
    with pytest.raises(sem.SemError):
        w.step()


def test_set_state_and_static_solve():
    w = sem.World.from_scene(falling_box(gravity=[0, 0, 0]))
    q = w.q(0).copy()
    w.set_state(0, q=q * 1.01, v=np.zeros_like(q))
    assert np.allclose(w.q(0), q * 1.01)
    assert w.energies()["elastic_energy"] > 0   # stretched by 1 %
    with pytest.raises(ValueError):
        w.set_state(0, q=q[:3])


def test_run_records_frames_like_summary_json():
    w = sem.World.from_scene(falling_box(frames=3, steps_per_frame=2))
    frames = w.run()
    assert len(frames) == 4
    assert [round(f["time"], 12) for f in frames] == [0.0, 0.02, 0.04, 0.06]
    for f in frames:
        assert set(sem.ENERGIES) <= set(f)
    ke = [f["kinetic_energy"] for f in frames]
    assert ke[0] == 0 and ke[1] < ke[2] < ke[3]


def test_scene_file_and_default_scene(outdir):
    path = os.path.join(outdir, "scene.json")
    with open(path, "w") as f:
        json.dump(falling_box(), f)
    w = sem.World.from_scene(path)
    w.step()
    assert abs(w.time - 0.01) < 1e-12
    d = sem.World.from_scene()                   # the embedded default: a pinned beam
    assert d.frames == 100 and d.steps_per_frame == 2
    ex = sem.World.from_scene(os.path.join(SOURCE_DIR, "examples", "bouncing_sphere.json"))
    assert ex.object_count == 1


def test_momentum_conserved_in_zero_gravity():
    scene = falling_box(gravity=[0, 0, 0])
    scene["objects"][0]["initial_velocity"] = [1, 0, 0]
    scene["objects"][0]["initial_angular_velocity"] = [0, 0, 2]
    w = sem.World.from_scene(scene)
    p0 = w.frame()["linear_momentum"]
    assert abs(p0[0] - 500.0) < 1e-6
    w.step(5)
    assert np.allclose(w.frame()["linear_momentum"], p0, atol=1e-8)


def test_scene_errors_raise_with_the_message():
    bad = falling_box()
    bad["objects"][0]["material"]["desnity"] = 1
    with pytest.raises(sem.SemError) as e:
        sem.World.from_scene(bad)
    assert 'unknown key "desnity"' in str(e.value)
    with pytest.raises(sem.SemError) as e:
        sem.World.from_scene({"objects": [{"model": "no/such/model.igs"}]})
    assert "no/such/model.igs" in str(e.value)
    with pytest.raises(TypeError):
        sem.World.from_scene(42)


def test_frame_model_and_cache(outdir):
    cache = os.path.join(outdir, "cache")
    w = sem.World.from_scene(falling_box(), cache_dir=cache)
    assert not w.preprocess_cached
    w.step(3)
    m = w.model(0)
    assert np.array_equal(m.q(), w.q(0))
    m.save(os.path.join(outdir, "frame.igs"))
    assert np.allclose(sem.load(os.path.join(outdir, "frame.igs")).q(), w.q(0), atol=1e-12)
    again = sem.World.from_scene(falling_box(), cache_dir=cache)
    assert again.preprocess_cached
    messages = []
    sem.World.from_scene(falling_box(), log=lambda level, text: messages.append((level, text)))
    assert any("object 0" in text for _, text in messages)


def test_model_is_in_the_file_units_as_sem_run_frames(outdir):
    """world.model(i) is in the units of the model's file with the numbers sem run writes in
    frame_NNNN.igs (here a beam read as millimetres: the state is in metres, the model and the
    frame in MM, 1000 x the state's numbers), and a file saved from it says so."""
    beam = os.path.join(outdir, "beam.igs")
    sem.Model.primitive("beam", length=2, width=0.4, height=0.4).save(beam)
    scene = {"objects": [{"model": beam, "units": "mm",
                          "material": {"youngs_modulus": 1e5},
                          "sem": {"order": 1, "rays": [3, 3]},
                          "pin": {"box": [[-1e-5, -1, -1], [1e-5, 1, 1]]}}],
             "integrator": {"type": "implicit_euler", "dt": 0.01}, "frames": 3,
             "output": {"dir": os.path.join(outdir, "run"), "usd": False, "glb": False,
                        "mesh": False}}
    w = sem.World.from_scene(scene)
    assert w.units(0) == ("MM", 0.001)
    w.run()
    q = w.q(0)
    m = w.model(0)
    assert m.units == ("MM", 0.001)
    assert np.array_equal(m.q(), q * (1.0 / 0.001))
    # the beam is 2 mm long in the file: 0.002 m simulated
    assert abs(np.ptp(w.q(0)[:, 0]) - 0.002) < 1e-4
    path = os.path.join(outdir, "frame.igs")
    m.save(path)
    saved = sem.load(path)
    assert saved.units == ("MM", 0.001)
    assert np.allclose(saved.q(), m.q(), rtol=1e-12, atol=0)
    binary = os.environ.get("SEM_BINARY")
    if not binary:
        pytest.skip("SEM_BINARY not set: no comparison with sem run")
    scene_path = os.path.join(outdir, "scene.json")
    with open(scene_path, "w") as f:
        json.dump(scene, f)
    import subprocess
    subprocess.run([binary, "run", scene_path, "--quiet"], check=True,
                   env=dict(os.environ, SEM_CACHE_DIR=os.path.join(outdir, "cache")))
    frame = sem.load(os.path.join(outdir, "run", "frame_0003.igs"))
    assert frame.units == saved.units
    assert np.array_equal(frame.q(), saved.q())


def test_numpy_missing_says_what_to_install():
    """A python3 without numpy (a virtual environment, pyenv) gets one clear line."""
    import subprocess
    import sys
    code = "import sys; sys.modules['numpy'] = None; import sem"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       env=dict(os.environ))
    assert r.returncode == 1
    last = r.stderr.strip().splitlines()[-1]
    assert last.startswith("ImportError: numpy is needed: apt-get install python3-numpy "
                           "(or pip install numpy)"), r.stderr
