#!/usr/bin/env python3
"""The public corpus at defaults (issue 27, item 3; validation/corpus/README.md).

For every file of validation/corpus/manifest.json found in the corpus folder (checked against
its sha256):
  - read it (`sem inspect --json`): parts, dofs, size, units;
  - drop it onto the ground for 1 s at sem's defaults: rho 1000, nu 0.45, E = 50 rho g L (a
    column of its size would sag about 1 % under its own weight), released 1 % of its size
    above a plane under its lowest point, implicit Euler, dt 0.01, gravity 9.81 along -z; from
    `sem run --json`: status, the trust checks (largest seam opening, error energy share,
    volume change), time; from the frames' meshes: the height at the end against the rest
    height;
  - with --static (and `sem validate` in the sem binary), the static sag pinned over the lowest
    10 % of its height against gmsh + CalculiX: the relative L2 error of the surface
    displacement and the ratio of the largest displacements.
Writes validation/corpus/results.json and prints a Markdown table (docs/validation.md).

usage: scripts/corpus_check.py [--sem build/sem] [--corpus DIR] [--only TEXT] [--static]
                               [--resolution R] [--timeout S] [--out FILE] [--workdir DIR]
                               [--resume]
Python standard library only.
"""
import argparse
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
MANIFEST = os.path.join(ROOT, "validation", "corpus", "manifest.json")
G = 9.81
RHO = 1000.0


def corpus_dir(arg):
    for d in [arg, os.environ.get("SEM_CORPUS"), os.path.join(ROOT, "..", "shared", "corpus"), "/work/corpus/files"]:
        if d and os.path.isdir(d):
            return d
    return None


def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def run(cmd, timeout):
    t0 = time.time()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        return p.returncode, p.stdout, p.stderr, time.time() - t0
    except subprocess.TimeoutExpired as e:
        return 124, e.stdout or "", (e.stderr or "") if isinstance(e.stderr, str) else "", time.time() - t0


def mesh_height(path):
    """z extent of an OBJ mesh's vertices (metres: frames are in the file's units)."""
    lo, hi = float("inf"), -float("inf")
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                z = float(line.split()[3])
                lo, hi = min(lo, z), max(hi, z)
    return hi - lo


def drop(sem, path, info, args, work):
    s = info["unit_to_meter"]
    lo = [c * s for c in info["bbox"][0]]
    hi = [c * s for c in info["bbox"][1]]
    L = sum((h - l) ** 2 for h, l in zip(hi, lo)) ** 0.5
    E = 50 * RHO * G * L
    obj = {"model": os.path.abspath(path),
           "material": {"density": RHO, "youngs_modulus": E, "poisson_ratio": 0.45}}
    if args.resolution > 0:
        obj["sem"] = {"resolution": args.resolution}
    scene = {"objects": [obj],
             "colliders": [{"plane": {"point": [0, 0, lo[2] - 0.01 * L], "normal": [0, 0, 1]}}],
             "gravity": [0, 0, -G], "integrator": {"type": "implicit_euler", "dt": 0.01},
             "frames": 20, "steps_per_frame": 5, "output": {"dir": os.path.join(work, "out")}}
    with open(os.path.join(work, "scene.json"), "w") as f:
        json.dump(scene, f)
    rc, out, err, secs = run([sem, "run", os.path.join(work, "scene.json"), "--overwrite", "--quiet", "--json"],
                             args.timeout)
    r = {"E": E, "size_m": L, "drop_rc": rc, "drop_s": round(secs, 1)}
    warnings = [l for l in err.splitlines() if "warning:" in l]
    r["warnings"] = len(warnings)
    if rc == 124:
        r["status"] = "timeout"
        return r
    try:
        summ = json.loads(out)
    except ValueError:
        r["status"] = "error"
        r["error"] = (err.strip().splitlines() or ["no output"])[-1][:300]
        return r
    r["status"] = summ.get("status")
    if summ.get("error"):
        r["error"] = summ["error"][:300]
    c = summ.get("checks", {})
    r["seam_gap_max"] = c.get("seam_gap_max")
    r["error_share_max"] = c.get("error_share_max")
    r["volume_change_max"] = c.get("volume_change_max")
    r["suspect"] = c.get("suspect", [])
    r["dofs"] = summ.get("dofs")
    r["mean_step_s"] = summ.get("mean_step_s")
    r["preprocess_s"] = summ.get("preprocess_s")
    frames = summ.get("frames", [])
    outdir = os.path.join(work, "out")
    last = len(frames) - 1
    digits = 4 if last < 10000 else len(str(last))
    f0 = os.path.join(outdir, "frame_%0*d_mesh.obj" % (digits, 0))
    fl = os.path.join(outdir, "frame_%0*d_mesh.obj" % (digits, last))
    if last > 0 and os.path.exists(f0) and os.path.exists(fl):
        h0, hl = mesh_height(f0), mesh_height(fl)
        r["height_ratio"] = hl / h0 if h0 > 0 else None
    return r


def static(sem, path, args, work):
    rc, out, err, secs = run([sem, "validate", os.path.abspath(path), "--json", "--workdir", os.path.join(work, "fem")],
                             args.timeout_static)
    r = {"static_rc": rc, "static_s": round(secs, 1)}
    if rc == 0:
        try:
            v = json.loads(out)
            r["fem"] = v
        except ValueError:
            r["static_error"] = "no JSON"
    else:
        r["static_error"] = (err.strip().splitlines() or ["exit %d" % rc])[-1][:300]
    return r


def fmt(x, spec):
    return format(x, spec) if isinstance(x, (int, float)) else "-"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sem", default=os.path.join(ROOT, "build", "sem"))
    ap.add_argument("--corpus")
    ap.add_argument("--only")
    ap.add_argument("--static", action="store_true")
    ap.add_argument("--resolution", type=float, default=0)
    ap.add_argument("--timeout", type=int, default=900)
    ap.add_argument("--timeout-static", type=int, default=1800)
    ap.add_argument("--out", default=os.path.join(ROOT, "validation", "corpus", "results.json"))
    ap.add_argument("--workdir")
    ap.add_argument("--resume", action="store_true",
                    help="keep the results already in --out and run only the files they lack")
    args = ap.parse_args()
    cdir = corpus_dir(args.corpus)
    if not cdir:
        sys.exit("corpus_check.py: no corpus folder (set SEM_CORPUS or --corpus; validation/corpus/README.md)")
    with open(MANIFEST) as f:
        manifest = json.load(f)
    base = args.workdir or tempfile.mkdtemp(prefix="sem_corpus_")
    results = []
    if args.resume and os.path.exists(args.out):
        with open(args.out) as f:
            results = json.load(f)
    done = {r["id"] for r in results}
    for e in manifest:
        if args.only and args.only not in e["id"]:
            continue
        if e["id"] in done:
            continue
        path = os.path.join(cdir, e["file"])
        r = {"id": e["id"], "format": e["format"], "units": e["units"].split(" ")[0], "tags": e["tags"]}
        if not os.path.exists(path):
            r["read"] = "missing"
            results.append(r)
            continue
        if sha256(path) != e["sha256"]:
            r["read"] = "sha256 mismatch"
            results.append(r)
            continue
        work = os.path.join(base, e["id"])
        os.makedirs(work, exist_ok=True)
        rc, out, err, secs = run([args.sem, "inspect", path, "--json"], 300)
        if rc != 0:
            r["read"] = "refused"
            r["error"] = (err.strip().splitlines() or ["exit %d" % rc])[-1][:300]
            results.append(r)
            print("%-26s refused: %s" % (e["id"], r["error"]), file=sys.stderr)
            continue
        info = json.loads(out)
        if not info.get("parts") or not info.get("bbox"):
            r["read"] = "no parts"
            results.append(r)
            print("%-26s read, but no part (nothing to simulate)" % e["id"], file=sys.stderr)
            continue
        r.update({"read": "ok", "parts": info["parts"], "file_dofs": info["dofs"],
                  "read_warnings": len(info.get("warnings", []))})
        r.update(drop(args.sem, path, info, args, work))
        if args.static:
            r.update(static(args.sem, path, args, work))
        results.append(r)
        print("%-26s %-8s parts %4s dofs %6s seam %s share %s vol %s height %s (%s s)" %
              (e["id"], r.get("status"), r.get("parts"), r.get("dofs"), fmt(r.get("seam_gap_max"), ".2e"),
               fmt(r.get("error_share_max"), ".2f"), fmt(r.get("volume_change_max"), ".3f"),
               fmt(r.get("height_ratio"), ".3f"), r.get("drop_s")), file=sys.stderr)
        if not args.workdir:
            shutil.rmtree(work, ignore_errors=True)
        with open(args.out, "w") as f:
            json.dump(results, f, indent=1)
    if not args.workdir:
        shutil.rmtree(base, ignore_errors=True)
    print("| file | format | units | parts | dofs | status | largest seam gap | error share | volume change | height at 1 s | step s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in results:
        if r.get("read") != "ok":
            print("| %s | %s | %s | - | - | %s | | | | | |" % (r["id"], r["format"], r["units"], r.get("read")))
            continue
        print("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" %
              (r["id"], r["format"], r["units"], r["parts"], r.get("dofs", "-"), r.get("status"),
               fmt(r.get("seam_gap_max"), ".2%"), fmt(r.get("error_share_max"), ".2f"),
               fmt(r.get("volume_change_max"), ".2%"), fmt(r.get("height_ratio"), ".3f"),
               fmt(r.get("mean_step_s"), ".3g")))


if __name__ == "__main__":
    main()
