#!/usr/bin/env python3
"""Default SPPM against the path tracer at equal CPU time on every example.

Three steps, each re-runnable on its own (the files go under --out, default
`target/every`):

1. `references`: a path-traced reference per example, `sppm-lang reference --scale S` with
   seeds 1000/1001 (the test renders use seed 1, so their noise is independent of the
   reference's), one thread, `--time T` each, two at a time. `ref/<scene>.noise.json` holds its
   noise (the RMSE the reference itself has against the converged image): the floor under
   which no comparison means anything. For Cornell a Mitsuba 3 reference (256x256) can be given
   with `--cornell-mitsuba`: it is box-filtered down to the scaled size (both renderers use a
   box pixel filter, so 2x2 pixel means are the smaller image's pixels).
2. `renders`: every method on every example at doubling iteration counts until the render's
   CPU time (user + system of the render process, one thread) passes the largest budget; the
   images are kept (`renders/`), with `renders.csv` (scene, method, iterations, CPU seconds).
   Methods: `path` (the scene with `integrator path`), `sppm` (the scene as it is), `sppm-auto`
   (the scene without its `photons` setting: the automatic photon count; only where the scene
   sets `photons`). Two renders run at a time (one thread each: the CPU time of one render
   does not depend on the other).
3. `table`: errors against the references (RMSE and relative MSE as `src/compare`, over the
   whole image and over the windows below), interpolated at the CPU budgets in log-log between
   the two renders that bracket each budget; writes `table.csv` and a Markdown table.

    .venv/bin/python tools/every_example.py references --time 150
    .venv/bin/python tools/every_example.py renders --budgets 2,4,8
    .venv/bin/python tools/every_example.py table --budgets 2,4,8 \\
        --cornell-mitsuba ../shared/reference/cornell-glass/reference.exr

Needs numpy and mitsuba (for reading EXR): `pip install mitsuba numpy` into the `.venv`.
"""

import argparse
import csv
import glob
import json
import math
import os
import re
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")

# Windows at the scene's full resolution (x0, y0, x1, y1, half-open), scaled with the image:
# where the scene has a caustic, and the edge of a directly visible light. A label starting
# with "without" means the image outside the window: smallppm's caustic under the glass sphere
# comes from a point light, which no path tracer can render (a point seen through glass), so
# its path-traced reference lacks it.
WINDOWS = {
    "cornell": {"caustic": (160, 216, 206, 238), "light edge": (96, 28, 160, 52)},
    "caustics": {"caustic": (60, 136, 280, 184)},
    "smallppm": {"without caustic": (156, 160, 200, 180)},
}


def read_exr(path):
    return np.array(mi.Bitmap(path), dtype=np.float64)[:, :, :3]


def write_exr(path, img):
    mi.Bitmap(img.astype(np.float32)).write(path)


def errors(img, ref):
    d = img - ref
    return float(np.sqrt(np.mean(d * d))), float(np.mean(d * d / (ref * ref + 0.01)))


def scenes(only):
    names = sorted(os.path.basename(p)[:-4] for p in glob.glob("examples/*.scn"))
    return [n for n in names if not only or n in only.split(",")]


def render_cpu(cmd):
    """Runs `cmd` and returns the CPU seconds (user + system) of that process alone."""
    pid = os.fork()
    if pid == 0:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, 1)
        os.dup2(devnull, 2)
        try:
            os.execv(cmd[0], cmd)
        finally:
            os._exit(127)
    _, status, ru = os.wait4(pid, 0)
    if status != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed with status {status}")
    return ru.ru_utime + ru.ru_stime


def method_scenes(name, out):
    """(method, scene file) pairs for one example: temporary scene files in a copy of
    `examples/` under `out` (so that the example's relative paths resolve)."""
    copy = f"{out}/examples"
    if not os.path.isdir(copy):
        shutil.copytree("examples", copy)
    text = open(f"examples/{name}.scn").read()
    stripped, n = re.subn(r"\bphotons\s+[0-9_]+", "", text)
    methods = [("path", text + "\nsettings { integrator path }\n"),
               ("sppm", text + "\nsettings { integrator sppm }\n")]
    if n:
        methods.append(("sppm-auto", stripped + "\nsettings { integrator sppm }\n"))
    files = []
    for method, body in methods:
        path = f"{copy}/{name}_{method}.scn"
        with open(path, "w") as f:
            f.write(body)
        files.append((method, path))
    return files


def cmd_references(a):
    os.makedirs(f"{a.out}/ref", exist_ok=True)

    def one(name):
        out = f"{a.out}/ref/{name}.exr"
        if os.path.exists(out):
            return
        subprocess.run([a.binary, "reference", f"examples/{name}.scn", "--time", str(a.time),
                        "--threads", "1", "--seed", "1000", "--scale", str(a.scale), "-o", out],
                       check=True, capture_output=True)
        print(f"reference {name} done", file=sys.stderr)

    with ThreadPoolExecutor(2) as pool:
        list(pool.map(one, scenes(a.only)))


def cmd_renders(a):
    os.makedirs(f"{a.out}/renders", exist_ok=True)
    top = max(float(b) for b in a.budgets.split(","))
    csv_path = f"{a.out}/renders.csv"
    done = set()
    if os.path.exists(csv_path):
        with open(csv_path) as f:
            done = {(r["scene"], r["method"]) for r in csv.DictReader(f)}
    else:
        with open(csv_path, "w") as f:
            f.write("scene,method,iterations,cpu_seconds,image\n")
    jobs = []
    for name in scenes(a.only):
        for method, path in method_scenes(name, a.out):
            if (name, method) in done:
                os.remove(path)
            else:
                jobs.append((name, method, path))

    def one(job):
        name, method, path = job
        rows = []
        it = 2 if method.startswith("sppm") else 4
        try:
            while True:
                img = f"{a.out}/renders/{name}_{method}_{it}.exr"
                cpu = render_cpu([a.binary, "render", path, "--iterations", str(it), "--seed",
                                  "1", "--threads", "1", "--scale", str(a.scale), "-o", img])
                rows.append((name, method, it, cpu, img))
                print(f"{name:>13} {method:>9} {it:>5} it {cpu:7.2f} cpu-s", file=sys.stderr)
                if cpu > top * 1.05 or it >= a.max_iterations:
                    break
                it *= 2
        finally:
            os.remove(path)
        return rows

    with ThreadPoolExecutor(2) as pool:
        for rows in pool.map(one, jobs):
            with open(csv_path, "a") as f:
                for r in rows:
                    f.write(",".join(str(v) for v in r) + "\n")


def downsample_to(img, shape):
    fy, fx = img.shape[0] // shape[0], img.shape[1] // shape[1]
    return img.reshape(shape[0], fy, shape[1], fx, 3).mean(axis=(1, 3))


def interpolate(points, budget):
    """log(error) linear in log(cpu) between the two renders around `budget`."""
    pts = sorted(points)
    for (c0, e0), (c1, e1) in zip(pts, pts[1:]):
        if c0 <= budget <= c1 and e0 > 0 and e1 > 0:
            t = math.log(budget / c0) / math.log(c1 / c0)
            return math.exp(math.log(e0) + t * (math.log(e1) - math.log(e0)))
    return float("nan")


def cmd_table(a):
    budgets = [float(b) for b in a.budgets.split(",")]
    with open(f"{a.out}/renders.csv") as f:
        renders = list(csv.DictReader(f))
    out_rows = []
    md = ["| scene | region | ref. noise | CPU s | " +
          " | ".join(f"{m} RMSE" for m in ("path", "sppm", "sppm-auto")) + " | sppm-auto / path |",
          "|---|---|---:|---:|---:|---:|---:|---:|"]
    for name in scenes(a.only):
        rows = [r for r in renders if r["scene"] == name]
        if not rows:
            continue
        ref_path = f"{a.out}/ref/{name}.exr"
        noise_path = f"{a.out}/ref/{name}.noise.exr"
        ref = read_exr(ref_path) if os.path.exists(ref_path) else None
        noise = read_exr(noise_path) if os.path.exists(noise_path) else None
        shape = read_exr(rows[0]["image"]).shape[:2]
        if name == "cornell" and a.cornell_mitsuba:
            ref = downsample_to(read_exr(a.cornell_mitsuba), shape)
            noise = None
        if ref is None:
            continue
        full_w = int(round(shape[1] / a.scale))
        k = shape[1] / full_w
        regions = [("whole", None)] + [
            (label, tuple(int(round(v * k)) for v in w))
            for label, w in WINDOWS.get(name, {}).items()]
        for label, w in regions:
            if w is None:
                def cut(im):
                    return im
            elif label.startswith("without"):
                keep = np.ones(shape, dtype=bool)
                keep[w[1]:w[3], w[0]:w[2]] = False

                def cut(im, keep=keep):
                    return im[keep]
            else:
                def cut(im, w=w):
                    return im[w[1]:w[3], w[0]:w[2]]
            floor = float(np.sqrt(np.mean(cut(noise) ** 2))) if noise is not None else 0.0
            curves = {}
            for r in rows:
                img = read_exr(r["image"])
                rmse, rel = errors(cut(img), cut(ref))
                curves.setdefault(r["method"], []).append((float(r["cpu_seconds"]), rmse, rel))
            for b in budgets:
                vals = {}
                for m, pts in curves.items():
                    vals[m] = (interpolate([(c, e) for c, e, _ in pts], b),
                               interpolate([(c, e) for c, _, e in pts], b))
                    out_rows.append((name, label, b, m, floor) + vals[m])
                auto = vals.get("sppm-auto", vals.get("sppm"))
                cells = [f"{vals[m][0]:.4f}" if m in vals else "=sppm" for m in
                         ("path", "sppm", "sppm-auto")]
                md.append(f"| {name} | {label} | {floor:.4f} | {b:g} | " + " | ".join(cells) +
                          f" | {auto[0] / vals['path'][0]:.2f} |")
    with open(f"{a.out}/table.csv", "w") as f:
        f.write("scene,region,cpu_seconds,method,reference_noise_rmse,rmse,rel_mse\n")
        for r in out_rows:
            f.write(",".join(str(v) for v in r) + "\n")
    with open(f"{a.out}/table.md", "w") as f:
        f.write("\n".join(md) + "\n")
    print("\n".join(md))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("step", choices=["references", "renders", "table"])
    ap.add_argument("--out", default="target/every")
    ap.add_argument("--only", help="comma-separated example names")
    ap.add_argument("--scale", type=float, default=0.5)
    ap.add_argument("--time", type=float, default=150.0, help="seconds per reference")
    ap.add_argument("--budgets", default="2,4,8", help="CPU seconds")
    ap.add_argument("--max-iterations", type=int, default=4096)
    ap.add_argument("--cornell-mitsuba", help="Mitsuba reference of examples/cornell.scn")
    ap.add_argument("--binary", default="target/release/sppm-lang")
    a = ap.parse_args()
    {"references": cmd_references, "renders": cmd_renders, "table": cmd_table}[a.step](a)


if __name__ == "__main__":
    main()
