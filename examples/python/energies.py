# %% [markdown]
# # Energies of a swinging beam, from Python
#
# A notebook-style script (the `# %%` cells open as a notebook in Jupyter or VS Code, or run
# it whole: `python3 examples/python/energies.py --frames 40 --out /tmp/energies`).
# It builds a world from a scene given as a Python dict, steps it, reads the control points
# and energies as numpy arrays, writes two frames as IGES and plots the energies with
# matplotlib.
#
# Needs the `sem` package: installed (`cmake --install build`, then the package is found
# with its library), or from the source tree with
# `SEM_LIBRARY=build/libsem.so PYTHONPATH=python`.

# %%
import sem  # first: it sets OpenMP's thread policy before anything else loads OpenMP

import argparse
import os

import matplotlib
matplotlib.use(os.environ.get("MPLBACKEND", "Agg"))
import matplotlib.pyplot as plt
import numpy as np

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("--frames", type=int, default=60)
parser.add_argument("--out", default="energies-out")
parser.add_argument("--scene", help="a scene file instead of the beam below")
args, _ = parser.parse_known_args()
os.makedirs(args.out, exist_ok=True)

# %% [markdown]
# ## The scene: a rubber beam clamped at x = 0, falling under gravity
# The keys are those of a scene file (docs/scenes.md).

# %%
scene = args.scene or {
    "objects": [{
        "primitive": {"type": "beam", "sections": 4, "length": 2.0, "width": 0.4, "height": 0.4},
        "material": {"type": "neohookean", "density": 1100, "youngs_modulus": 2e6,
                     "poisson_ratio": 0.45},
        "sem": {"order": 2, "rays": [4, 4], "points_per_interval": 12},
        "pin": {"box": [[-0.01, -1, -1], [0.01, 1, 1]]},
    }],
    "gravity": [0, 0, -9.81],
    "integrator": {"type": "implicit_euler", "dt": 0.01},
    "steps_per_frame": 2,
}
world = sem.World.from_scene(scene)
print("sem", sem.version(), "-", world, "-", world.discretization(0))

# %% [markdown]
# ## Step and record
# `world.q(0)` is a live view of object 0's control points (no copy): it follows the
# simulation, so copy what you want to keep.

# %%
q = world.q(0)
tip = np.argmax(q[:, 0])                  # a control point at the free end
records, tip_z = [], []
world.model(0).save(os.path.join(args.out, "frame_0000.igs"))
for frame in range(args.frames + 1):
    if frame > 0:
        world.step(world.steps_per_frame)
    records.append(world.frame())
    tip_z.append(q[tip, 2])
world.model(0).save(os.path.join(args.out, "frame_%04d.igs" % args.frames))

time = np.array([r["time"] for r in records])
energy = {k: np.array([np.nan if r[k] is None else r[k] for r in records]) for k in sem.ENERGIES}
total = sum(energy.values())
np.savetxt(os.path.join(args.out, "energies.csv"),
           np.column_stack([time] + [energy[k] for k in sem.ENERGIES] + [tip_z]),
           delimiter=",", header="time," + ",".join(sem.ENERGIES) + ",tip_z", comments="")

# %% [markdown]
# ## Plot
# Implicit Euler damps: the total (kinetic + elastic + gravity + error) can only go down.

# %%
fig, (ax, bx) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
for k in sem.ENERGIES:
    ax.plot(time, energy[k] - (energy[k][0] if k == "gravity_energy" else 0),
            label=k.replace("_", " ") + (" (change)" if k == "gravity_energy" else ""))
ax.plot(time, total - total[0], "k--", label="total (change)")
ax.set_ylabel("energy (J)")
ax.legend(fontsize=8)
bx.plot(time, tip_z)
bx.set_xlabel("time (s)")
bx.set_ylabel("free end z (m)")
fig.tight_layout()
png = os.path.join(args.out, "energies.png")
fig.savefig(png, dpi=100)
print("%d frames, t = %.3f s; total energy %.4g -> %.4g J; wrote %s" % (
    args.frames, world.time, total[0], total[-1], png))
assert np.all(np.diff(total) <= 1e-9 * abs(total[0])), "implicit Euler gained energy"
