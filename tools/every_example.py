#!/usr/bin/env python3
"""Default SPPM against the path tracer at equal CPU time on every example.

Three steps, each re-runnable on its own (the files go under --out, default
`target/every`):

1. `references`: a path-traced reference per example, `sppm-lang reference --scale S` with
   seeds 1000/1001 (the test renders use seed 1, so their noise is independent of the
   reference's), one thread, `--time T` each, two at a time. `ref/<scene>.noise.json` holds its
   noise (the RMSE the reference itself has against the converged image): the floor under
   which no comparison means anything. For Cornell a Mitsuba 3 reference (256x256) can be given
   with `--cornell-mitsuba`, for smallppm_far one with `--far-mitsuba`
   (tools/reference/smallppm_far.exr), for smallppm a light-tracing one with
   `--smallppm-mitsuba` (tools/reference/smallppm.exr): each is box-filtered down to the scaled
   size (both renderers use a box pixel filter, so 2x2 pixel means are the smaller image's
   pixels). A reference with a mask beside it (`*.mask.exr`, 1 where it holds) is compared on
   the masked pixels only: smallppm's light-tracing reference holds where the camera sees a
   diffuse surface (its `whole` region), and no path tracer can render its scene (a point
   light reaches the walls by way of the mirror and glass balls too), so its path-traced
   reference is only a stand-in, compared outside the glass ball's caustic.
2. `renders`: every method on every example at doubling iteration counts until the render's
   CPU time (user + system of the render process, one thread) passes the largest budget; the
   images are kept (`renders/`), with `renders.csv` (scene, method, iterations, CPU seconds).
   Methods: `path` (the scene with `integrator path`), `sppm` (the scene as it is), `sppm-auto`
   (the scene without its `photons` setting: the automatic photon count; only where the scene
   sets `photons`). Two renders run at a time (one thread each: the CPU time of one render
   does not depend on the other).
3. `table`: errors against the references (RMSE and relative MSE as `src/compare`, and the
   image mean over the reference's, over the whole image, its `edges` (the tenth of the pixels
   with the steepest local contrast in the reference, where a radius blurs), the rest
   (`smooth`) and the windows below), interpolated at the CPU budgets in log-log between the
   two renders that bracket each budget; writes `table.csv` and a Markdown table.

    .venv/bin/python tools/every_example.py references --time 150
    .venv/bin/python tools/every_example.py renders --budgets 2,4,8
    .venv/bin/python tools/every_example.py table --budgets 2,4,8 \\
        --cornell-mitsuba ../shared/reference/cornell-glass/reference.exr \\
        --far-mitsuba tools/reference/smallppm_far.exr \\
        --smallppm-mitsuba tools/reference/smallppm.exr

Other initial radii (`RADIUS_FOOTPRINTS` in src/prepare/settings.rs) go into the same table:
build with the factor changed, copy the binary, and render only the SPPM methods under a tag
(method names become `sppm@r2`, `sppm-auto@r2`):

    .venv/bin/python tools/every_example.py renders --binary target/bins/r2 \\
        --methods sppm,sppm-auto --tag r2

The table also prints smallppm_far's relative MSE over the Cornell box's at equal CPU time per
pixel (far at `budget x its pixels / Cornell's pixels`) for every SPPM method.

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


def method_scenes(name, out, wanted, tag):
    """(method, scene file) pairs for one example: temporary scene files in a copy of
    `examples/` under `out` (so that the example's relative paths resolve). Only the methods in
    `wanted`; SPPM methods get `@tag` appended to their names when a tag is given."""
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
        if method not in wanted:
            continue
        if tag and method != "path":
            method = f"{method}@{tag}"
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
        for method, path in method_scenes(name, a.out, a.methods.split(","), a.tag):
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


def edge_mask(ref):
    """The pixels with the steepest local contrast in the reference: the tenth of the image
    whose value differs most from its 3x3 neighbourhood's mean, relative to that mean (where a
    gather radius blurs most). Luminance-like: the mean of the channels."""
    y = ref.mean(axis=2)
    p = np.pad(y, 1, mode="edge")
    blur = sum(p[i:i + y.shape[0], j:j + y.shape[1]] for i in range(3) for j in range(3)) / 9
    contrast = np.abs(y - blur) / (blur + 0.01)
    return contrast >= np.quantile(contrast, 0.9)


def sppm_methods(methods):
    return [m for m in methods if m != "path"]


def cmd_table(a):
    budgets = [float(b) for b in a.budgets.split(",")]
    with open(f"{a.out}/renders.csv") as f:
        renders = list(csv.DictReader(f))
    methods = list(dict.fromkeys(r["method"] for r in renders))
    methods = ["path"] + sorted(sppm_methods(methods))
    out_rows = []
    md = ["| scene | region | ref. noise | CPU s | path RMSE | " +
          " | ".join(f"{m} / path" for m in sppm_methods(methods)) + " |",
          "|---|---|---:|---:|---:|" + "---:|" * len(sppm_methods(methods))]
    rel_at = {}  # (scene, method) -> [(cpu, rel_mse)] over the whole image
    pixels = {}
    for name in scenes(a.only):
        rows = [r for r in renders if r["scene"] == name]
        if not rows:
            continue
        ref_path = f"{a.out}/ref/{name}.exr"
        noise_path = f"{a.out}/ref/{name}.noise.exr"
        ref = read_exr(ref_path) if os.path.exists(ref_path) else None
        noise = read_exr(noise_path) if os.path.exists(noise_path) else None
        shape = read_exr(rows[0]["image"]).shape[:2]
        pixels[name] = shape[0] * shape[1]
        mitsuba = {"cornell": a.cornell_mitsuba, "smallppm_far": a.far_mitsuba,
                   "smallppm": a.smallppm_mitsuba}.get(name)
        # Pixels where the reference holds (all of them unless it comes with a mask).
        valid = None
        if mitsuba:
            ref = downsample_to(read_exr(mitsuba), shape)
            noise = None
            mask_path = re.sub(r"\.exr$", ".mask.exr", mitsuba)
            if mask_path != mitsuba and os.path.exists(mask_path):
                # A smaller pixel is valid where all the pixels it averages are.
                valid = downsample_to(read_exr(mask_path), shape)[:, :, 0] > 0.999
        if ref is None:
            continue
        full_w = int(round(shape[1] / a.scale))
        k = shape[1] / full_w
        edges = edge_mask(ref)
        if valid is None:
            regions = [("whole", None), ("edges", edges), ("smooth", ~edges)] + [
                (label, tuple(int(round(v * k)) for v in w))
                for label, w in WINDOWS.get(name, {}).items()]
        else:
            # A masked reference replaces the windows that worked around a path-traced one.
            regions = [("whole", valid), ("edges", edges & valid), ("smooth", ~edges & valid)]
        images = {r["image"]: read_exr(r["image"]) for r in rows}
        for label, w in regions:
            if w is None:
                def cut(im):
                    return im
            elif isinstance(w, np.ndarray):
                def cut(im, keep=w):
                    return im[keep]
            elif label.startswith("without"):
                keep = np.ones(shape, dtype=bool)
                keep[w[1]:w[3], w[0]:w[2]] = False

                def cut(im, keep=keep):
                    return im[keep]
            else:
                def cut(im, w=w):
                    return im[w[1]:w[3], w[0]:w[2]]
            floor = float(np.sqrt(np.mean(cut(noise) ** 2))) if noise is not None else 0.0
            ref_mean = float(np.mean(cut(ref)))
            curves = {}
            for r in rows:
                img = images[r["image"]]
                rmse, rel = errors(cut(img), cut(ref))
                # Mean over the reference's: a bias of the method shows as a ratio off 1 that
                # does not shrink with time.
                mean = float(np.mean(cut(img))) / ref_mean if ref_mean > 0 else float("nan")
                curves.setdefault(r["method"], []).append(
                    (float(r["cpu_seconds"]), rmse, rel, mean))
            if label == "whole":
                for m, pts in curves.items():
                    rel_at[(name, m)] = [(c, e) for c, _, e, _ in pts]
            for b in budgets:
                vals = {}
                for m, pts in curves.items():
                    vals[m] = tuple(interpolate([(p[0], p[i]) for p in pts], b)
                                    for i in (1, 2, 3))
                    out_rows.append((name, label, b, m, floor) + vals[m])
                if "path" not in vals:
                    continue
                cells = [f"{vals[m][0] / vals['path'][0]:.2f}" if m in vals else "-"
                         for m in sppm_methods(methods)]
                md.append(f"| {name} | {label} | {floor:.4f} | {b:g} | {vals['path'][0]:.4f} | "
                          + " | ".join(cells) + " |")
    with open(f"{a.out}/table.csv", "w") as f:
        f.write("scene,region,cpu_seconds,method,reference_noise_rmse,rmse,rel_mse,mean_ratio\n")
        for r in out_rows:
            f.write(",".join(str(v) for v in r) + "\n")
    if "cornell" in pixels and "smallppm_far" in pixels:
        share = pixels["smallppm_far"] / pixels["cornell"]
        md += ["", "smallppm_far / cornell relative MSE at equal CPU time per pixel:", "",
               "| method | cornell CPU s | far CPU s | cornell rel MSE | far rel MSE | far / cornell |",
               "|---|---:|---:|---:|---:|---:|"]
        for m in methods:
            for b in budgets:
                c = interpolate(rel_at.get(("cornell", m), []), b)
                # smallppm_far sets no photon count: its `sppm` is already automatic.
                far = rel_at.get(("smallppm_far", m)) or rel_at.get(
                    ("smallppm_far", m.replace("sppm-auto", "sppm")), [])
                f_ = interpolate(far, b * share)
                if c == c and f_ == f_:
                    md.append(f"| {m} | {b:g} | {b * share:g} | {c:.5f} | {f_:.5f} | "
                              f"{f_ / c:.2f} |")
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
    ap.add_argument("--far-mitsuba", help="Mitsuba reference of examples/smallppm_far.scn")
    ap.add_argument("--smallppm-mitsuba",
                    help="Mitsuba light-tracing reference of examples/smallppm.scn (with the "
                         "mask of pixels where it holds beside it, `*.mask.exr`)")
    ap.add_argument("--binary", default="target/release/sppm-lang")
    ap.add_argument("--methods", default="path,sppm,sppm-auto", help="renders: which methods")
    ap.add_argument("--tag", help="renders: appended to the SPPM methods' names (`sppm@TAG`)")
    a = ap.parse_args()
    {"references": cmd_references, "renders": cmd_renders, "table": cmd_table}[a.step](a)


if __name__ == "__main__":
    main()
