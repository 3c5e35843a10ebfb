#!/usr/bin/env python3
"""Error against CPU time for several render configurations of one scene, on a loaded machine.

`sppm-lang chart` measures wall time, which on a shared machine (load far above the core
count) stretches by several times and varies from run to run. This script renders each
configuration at a growing number of iterations with the release binary, measures the CPU time
(user + system) of each render process, and the error against a reference (the same rmse and
rel_mse as `sppm-lang chart`: `src/compare`). Comparing methods at equal CPU time is fair when
the renders use the same number of threads.

    .venv/bin/python tools/equal_cpu.py --scene examples/cornell.scn \
        --reference ../shared/reference/cornell-glass/reference.exr \
        --config 'sppm:sppm:' --config 'sppm-lookat:sppm:radius 0.011089' \
        --config 'path:path:' --iterations 4,8,16,32 --window 100,20,156,40 --csv out.csv

A configuration is `label:integrator:settings text`; the settings text is added as a last
`settings { ... }` block (blocks accumulate), e.g. `radius 0.01` or `antialias adaptive`.
Needs numpy and mitsuba (for reading EXR): `pip install mitsuba` into a venv.
"""

import argparse
import os
import resource
import subprocess
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")


def read_exr(path):
    return np.array(mi.Bitmap(path), dtype=np.float64)[:, :, :3]


def errors(img, ref, window=None):
    if window:
        x0, y0, x1, y1 = window
        img, ref = img[y0:y1, x0:x1], ref[y0:y1, x0:x1]
    d = img - ref
    return float(np.sqrt(np.mean(d * d))), float(np.mean(d * d / (ref * ref + 0.01)))


def cpu_of_children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", required=True)
    ap.add_argument("--reference", required=True)
    ap.add_argument("--config", action="append", required=True)
    ap.add_argument("--iterations", required=True, help="comma-separated iteration counts")
    ap.add_argument("--window", help="x0,y0,x1,y1 (half-open)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--binary", default="target/release/sppm-lang")
    ap.add_argument("--scale", type=float, help="render at this fraction of the resolution")
    ap.add_argument("--csv", required=True)
    a = ap.parse_args()
    ref = read_exr(a.reference)
    window = [int(v) for v in a.window.split(",")] if a.window else None
    text = open(a.scene).read()
    rows = []
    scene_dir = os.path.dirname(os.path.abspath(a.scene))
    for config in a.config:
        label, integrator, extra = config.split(":", 2)
        tmp_scene = os.path.join(scene_dir, f".equal_cpu_{os.getpid()}_{label}.scn")
        with open(tmp_scene, "w") as f:
            f.write(text + f"\nsettings {{ integrator {integrator} {extra} }}\n")
        tmp_out = f"/tmp/equal_cpu_{os.getpid()}_{label}.exr"
        try:
            for it in [int(v) for v in a.iterations.split(",")]:
                before = cpu_of_children()
                subprocess.run(
                    [a.binary, "render", tmp_scene, "--iterations", str(it), "--seed",
                     str(a.seed), "--threads", str(a.threads), "-o", tmp_out]
                    + (["--scale", str(a.scale)] if a.scale else []),
                    check=True, capture_output=True)
                cpu = cpu_of_children() - before
                img = read_exr(tmp_out)
                whole = errors(img, ref)
                win = errors(img, ref, window) if window else (float("nan"), float("nan"))
                rows.append((label, it, cpu) + whole + win)
                print(f"{label:>14} {it:>5} it {cpu:8.2f} cpu-s  rmse {whole[0]:.5f} "
                      f"rel_mse {whole[1]:.5f}  window rmse {win[0]:.5f}", file=sys.stderr)
        finally:
            os.remove(tmp_scene)
            if os.path.exists(tmp_out):
                os.remove(tmp_out)
    with open(a.csv, "w") as f:
        f.write("label,iterations,cpu_seconds,rmse,rel_mse,window_rmse,window_rel_mse\n")
        for r in rows:
            f.write(",".join(str(v) for v in r) + "\n")


if __name__ == "__main__":
    main()
