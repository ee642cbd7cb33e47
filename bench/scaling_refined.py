#!/usr/bin/env python3
"""scaling_refined.py - step time and memory against degrees of freedom on one CAD shape
refined by exact knot insertion (issue 12; docs/validation.md, section 3b).

The soft rocket (rocket/rocket.iges, Table 1's material) is refined with `sem refine` by each
factor K, then run at default settings: pinned below 10 % of its height, gravity, dt 0.01,
linearly implicit Euler (STEPS steps) and implicit Euler (NEWTON_STEPS steps). The mean step
times come from summary.json, the peak resident memory of each run from the kernel (getrusage
of the child). Preprocessing is timed separately (`sem preprocess --json`, cache off).

usage: bench/scaling_refined.py [--sem build/sem] [--models DIR] [--factors 1,12,27,44]
                                [--steps 5] [--newton-steps 3] [--out validation/scaling_refined]
Writes OUT.dat (whitespace separated, '#' comments) and, with matplotlib, OUT.png.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("failed: %s\n%s" % (" ".join(cmd), r.stderr.strip()[-500:]))
    return r.stdout


def bbox(sem, path):
    out = run([sem, "inspect", path, "--json"])
    j = json.loads(out)
    u = j.get("unit_to_meter", 1.0)
    return [x * u for x in j["bbox"][0]], [x * u for x in j["bbox"][1]]


def scene(model, lo, hi, integrator, steps, out):
    h = hi[2] - lo[2]
    return {"objects": [{"model": model,
                         "material": {"type": "neohookean", "density": 1270, "youngs_modulus": 7e6,
                                      "poisson_ratio": 0.4},
                         "pin": {"box": [[lo[0] - 1, lo[1] - 1, lo[2] - 1],
                                         [hi[0] + 1, hi[1] + 1, lo[2] + 0.1 * h]]}}],
            "gravity": [0, 0, -9.81], "integrator": {"type": integrator, "dt": 0.01},
            "frames": steps, "output": {"dir": out, "iges": False, "mesh": False, "usd": False}}


def fit(xs, ys):
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    n = len(lx)
    mx, my = sum(lx) / n, sum(ly) / n
    p = sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sum((a - mx) ** 2 for a in lx)
    return p, math.exp(my - p * mx)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sem", default="build/sem")
    ap.add_argument("--models", default=os.environ.get("SEM_SHARED_MODELS", "../shared/models"))
    ap.add_argument("--factors", default="1,12,27,44")
    ap.add_argument("--steps", type=int, default=5)
    ap.add_argument("--newton-steps", type=int, default=3)
    ap.add_argument("--out", default="validation/scaling_refined")
    a = ap.parse_args()
    sem = os.path.abspath(a.sem)
    src = os.path.join(a.models, "rocket", "rocket.iges")
    tmp = tempfile.mkdtemp(prefix="sem_scaling_")
    env_cache = dict(os.environ, SEM_CACHE_DIR=os.path.join(tmp, "cache"))
    rows = []
    for k in [int(x) for x in a.factors.split(",")]:
        model = src if k == 1 else os.path.join(tmp, "rocket_k%d.iges" % k)
        if k != 1:
            run([sem, "refine", src, model, "--factor", str(k)])
        lo, hi = bbox(sem, model)
        pre = run([sem, "preprocess", model, "--json", "--no-cache", "--no-modes"])
        pj = json.loads(pre)
        row = {"K": k, "dofs": pj["dofs"], "parts": pj["parts"], "samples": pj["boundary_samples"],
               "quad": pj["quadrature_points"], "pre_s": pj["timings"]["total_s"]}
        for integ, steps, key in (("linearly_implicit_euler", a.steps, "lin"),
                                  ("implicit_euler", a.newton_steps, "newton")):
            out = os.path.join(tmp, "out_%d_%s" % (k, key))
            path = out + ".json"
            with open(path, "w") as f:
                json.dump(scene(model, lo, hi, integ, steps, out), f)
            peak = run_peak([sem, "run", path, "--quiet", "--overwrite"], env_cache)
            with open(os.path.join(out, "summary.json")) as f:
                s = json.load(f)
            row[key + "_s"] = s["mean_step_s"]
            row[key + "_mem"] = peak
        rows.append(row)
        print("K %d: %s" % (k, row), file=sys.stderr, flush=True)
    big = [r for r in rows if r["dofs"] >= 5000]
    p_lin, c_lin = fit([r["dofs"] for r in big], [r["lin_s"] for r in big]) if len(big) >= 2 else (0, 0)
    p_new, c_new = fit([r["dofs"] for r in big], [r["newton_s"] for r in big]) if len(big) >= 2 else (0, 0)
    with open(a.out + ".dat", "w") as f:
        f.write("# rocket/rocket.iges refined by K (sem refine), defaults; %s\n" % " ".join(sys.argv))
        f.write("# growth over the models with >= 5000 dofs: linearly implicit step ~ dofs^%.2f, "
                "implicit Euler step ~ dofs^%.2f\n" % (p_lin, p_new))
        f.write("# K dofs parts samples quad preprocess_s linear_step_s linear_peak_bytes "
                "newton_step_s newton_peak_bytes\n")
        for r in rows:
            f.write("%d %d %d %d %d %.4g %.4g %d %.4g %d\n" % (
                r["K"], r["dofs"], r["parts"], r["samples"], r["quad"], r["pre_s"], r["lin_s"],
                r["lin_mem"], r["newton_s"], r["newton_mem"]))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.4))
    d = [r["dofs"] for r in rows]
    ax[0].loglog(d, [r["lin_s"] for r in rows], "o-", label="linearly implicit step")
    ax[0].loglog(d, [r["newton_s"] for r in rows], "s-", label="implicit Euler step (Newton)")
    if big:
        xs = [min(r["dofs"] for r in big), max(r["dofs"] for r in big)]
        ax[0].loglog(xs, [c_lin * x ** p_lin for x in xs], "k--", label="fit: dofs^%.2f" % p_lin)
    ax[0].set_xlabel("degrees of freedom")
    ax[0].set_ylabel("seconds")
    ax[0].grid(True, which="both", alpha=0.3)
    ax[0].legend()
    ax[1].loglog(d, [r["lin_mem"] / 2 ** 30 for r in rows], "o-", label="linearly implicit run")
    ax[1].loglog(d, [r["newton_mem"] / 2 ** 30 for r in rows], "s-", label="implicit Euler run")
    ax[1].set_xlabel("degrees of freedom")
    ax[1].set_ylabel("peak resident memory, GiB")
    ax[1].grid(True, which="both", alpha=0.3)
    ax[1].legend()
    fig.suptitle("The soft rocket refined by exact knot insertion (sem refine), default settings")
    fig.tight_layout()
    fig.savefig(a.out + ".png", dpi=90)


def run_peak(cmd, env):
    """Runs cmd (output discarded) and returns its peak resident memory in bytes (wait4)."""
    pid = os.fork()
    if pid == 0:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, 1)
        os.dup2(devnull, 2)
        os.execve(cmd[0], cmd, env)
    _, status, ru = os.wait4(pid, 0)
    if not os.WIFEXITED(status) or os.WEXITSTATUS(status) != 0:
        sys.exit("failed: %s" % " ".join(cmd))
    return ru.ru_maxrss * 1024


if __name__ == "__main__":
    main()
