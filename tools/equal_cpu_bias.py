#!/usr/bin/env python3
"""Each method's error in a `tools/equal_cpu_examples.py` cache split into bias and variance,
per example and region: over the seeds' renders of one method (each at the iterations that
fit the cache's budget), the per-pixel mean and sample variance; the squared bias is the
squared difference of that mean from the reference less what the seeds' own spread and the
reference's noise put into it (`(mean - ref)^2 - var / seeds - noise`, unbiased for each
pixel), averaged over the region like the variance, with its standard error over the
region's pixels (where the reference is noisy the estimate can come out negative). A method
whose error is mostly bias gains little from more time; one whose error is mostly variance,
at the rate its variance falls.

    .venv/bin/python tools/equal_cpu_bias.py --cache <cache> --examples crystal_tree,room \\
        --seeds 8

Only examples with a path-traced reference in the cache (`ref0.exr`, `ref1.exr`): those the
script compares with an external reference (its `EXTERNAL`) are skipped, and so are renders
made against another reference or at another size. The renders' CPU times differ a little
from the budget and are not rescaled here (their mean is printed).

Measurement only: nothing in the renderer or its tests imports it.
"""

import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from equal_cpu_examples import EXTERNAL, read_exr, regions  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cache", required=True)
    ap.add_argument("--examples", required=True, help="comma-separated names")
    ap.add_argument("--methods", default="path,sppm,vcm")
    ap.add_argument("--seeds", type=int, default=8)
    a = ap.parse_args()
    if a.seeds < 2:
        sys.exit("error: --seeds must be at least 2 (the variance needs two renders)")
    print("| example | method | CPU-s (mean) | region | squared bias (± se) | variance | bias's share |")
    print("|---|---|---|---|---|---|---|")
    for name in a.examples.split(","):
        if name in EXTERNAL:
            print(f"{name}: compared with an external reference, skipped", file=sys.stderr)
            continue
        d = os.path.join(a.cache, name)
        refs = [os.path.join(d, f"ref{i}.exr") for i in (0, 1)]
        if not all(os.path.exists(p) for p in refs):
            print(f"{name}: no path-traced reference in {d}, skipped", file=sys.stderr)
            continue
        r0, r1 = (read_exr(p) for p in refs)
        ref, noise = (r0 + r1) / 2, (r0 - r1) ** 2 / 4
        h, w = ref.shape[:2]
        for m in a.methods.split(","):
            paths = [os.path.join(d, f"{m}-{s}") for s in range(1, a.seeds + 1)]
            if not all(os.path.exists(p + ".exr") and os.path.exists(p + ".json")
                       for p in paths):
                print(f"{name} {m}: fewer than {a.seeds} renders, skipped", file=sys.stderr)
                continue
            res = [json.load(open(p + ".json")) for p in paths]
            if any(r.get("reference", "path") != "path" for r in res):
                print(f"{name} {m}: renders measured against another reference, skipped",
                      file=sys.stderr)
                continue
            imgs = np.array([read_exr(p + ".exr") for p in paths])
            if imgs.shape[1:] != ref.shape:
                print(f"{name} {m}: renders of {imgs.shape[1:]} against a reference of "
                      f"{ref.shape}, skipped", file=sys.stderr)
                continue
            cpu = np.mean([r["cpu"] for r in res])
            mean, var = imgs.mean(axis=0), imgs.var(axis=0, ddof=1)
            bias2 = (mean - ref) ** 2 - var / a.seeds - noise
            for i, (rn, ys, xs) in enumerate(regions(h, w)):
                # Per pixel over the colour channels, then over the region's pixels.
                px = bias2[ys, xs].mean(axis=-1).ravel()
                b, v = px.mean(), var[ys, xs].mean()
                se = px.std(ddof=1) / np.sqrt(px.size) if px.size > 1 else float("nan")
                share = b / (b + v) if b + v > 0 else float("nan")
                print(f"| {name if i == 0 else ''} | {m if i == 0 else ''} | "
                      f"{f'{cpu:.1f}' if i == 0 else ''} | {rn} | {b:.2e} ± {se:.1e} | "
                      f"{v:.2e} | {share:.2f} |")


if __name__ == "__main__":
    main()
