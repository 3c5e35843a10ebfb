#!/usr/bin/env python3
"""Every example at equal CPU time: path, sppm and vcm (or other methods) against a long path
reference, whole image and per quadrant, over several seeds, with each example's noise.

For each example the script renders a reference with the path tracer: two halves of
`--ref-cpu` CPU seconds (seeds 1000 and 1001), averaged. Their difference measures the
reference's own noise, `mean((a - b)^2) / 4` per pixel, which is subtracted from every
method's squared error (otherwise it adds to every method and pulls the ratios toward 1).

An example lit so that no path tracer can render it (a point light seen by way of a mirror or
glass: a caustic) is compared with an independent reference instead (`EXTERNAL`: Mitsuba 3's
particle tracer for smallppm, tools/reference/README.md), on its mask's pixels only (where
the camera sees a diffuse surface directly: elsewhere that reference holds nothing), every
region restricted to them. The reference is box-averaged down to the table's resolution
when that divides its own exactly (a box-filtered image averaged over k x k pixels is the
box-filtered image at 1/k the resolution, our pixel filter; a pixel is kept if all its
sub-pixels are in the mask), else the example renders at the reference's resolution. Its
noise comes from two halves of an independent shorter run, averaged down alike, scaled to
the reference's samples (a light tracer's variance falls as 1 / spp).

Each method then renders with seeds 1..`--seeds` for the example's budget: `--cpu` CPU
seconds, or `--fixed-factor` times the largest fixed cost (loading and preparing the scene,
from the calibration) when that is more, so that setup does not dominate. CPU time is the
user + system time of the render process, so the comparison holds on a loaded machine. The
iterations that fit come from two calibration renders (1 and 4 iterations: the per-iteration
and the fixed cost). A render rarely lands exactly on the budget, so each MSE is scaled to
the budget as an unbiased method's would be (`mse * cpu / budget`).

Per example and region the table gives each method's RMSE (the root of the mean over seeds
of the corrected MSE) and vcm's ratio to the better of the others, with its noise: the
standard error of the ratio from the spread of the per-seed MSEs. A ratio counts as a loss
only when it is above 1.05 by more than twice its noise, as a win when it is below 1 by more
than twice its noise.

    python3 -m venv .venv && .venv/bin/pip install numpy OpenEXR
    cargo build --release --bin sppm-lang
    .venv/bin/python tools/equal_cpu_examples.py --binary target/release/sppm-lang \\
        --width 64 --cpu 3 --ref-cpu 40 --seeds 3 --jobs 2 --cache target/ecx \\
        --markdown /tmp/table.md

Renders are kept under `--cache` by example, method and seed (a JSON of errors and CPU time
each): a second run with `--rerun vcm` renders only vcm again (after a change to it) and
reuses the references and the other methods.

Measurement only: nothing in the renderer or its tests imports it.
"""

import argparse
import glob
import json
import math
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import OpenEXR


def read_exr(path):
    with OpenEXR.File(path) as f:
        ch = f.channels()
        if "RGB" in ch:
            return np.array(ch["RGB"].pixels, dtype=np.float64)
        return np.stack([np.array(ch[c].pixels, dtype=np.float64) for c in "RGB"], axis=-1)


# Examples compared with a committed reference of another renderer: its image, its mask, two
# halves of an independent run (their difference measures the noise) and the samples per
# pixel of the image and of the halves together.
EXTERNAL = {
    "smallppm": {"image": "tools/reference/smallppm.exr",
                 "mask": "tools/reference/smallppm.mask.exr",
                 "halves": ["tools/reference/smallppm.noise.half0.exr",
                            "tools/reference/smallppm.noise.half1.exr"],
                 "spp": 8192, "halves_spp": 1024},
}


def box_down(img, k):
    """The mean of each k x k block (height and width multiples of k)."""
    h, w = img.shape[:2]
    return img.reshape(h // k, k, w // k, k, -1).mean(axis=(1, 3))


def external_reference(a, spec):
    """(reference, mask, noise, width to render at) for a committed reference at the table's
    resolution, the noise each pixel's estimated variance of the reference."""
    img, mask = read_exr(spec["image"]), read_exr(spec["mask"])[..., :1] > 0.5
    h0, h1 = (read_exr(p) for p in spec["halves"])
    h, w = img.shape[:2]
    k = w // a.width if a.width and w % a.width == 0 and h % (w // a.width) == 0 else 1
    if k > 1:
        img, h0, h1 = box_down(img, k), box_down(h0, k), box_down(h1, k)
        mask = box_down(mask.astype(np.float64), k) > 1.0 - 1e-9
    # (h0 - h1)^2 / 4 estimates the variance of (h0 + h1) / 2, of `halves_spp` samples.
    noise = (h0 - h1) ** 2 / 4 * (spec["halves_spp"] / spec["spp"])
    return img, mask[..., 0], noise, w // k


def render(a, scene, method, iterations, seed, out, width=None):
    """Renders and returns the CPU seconds (user + system) of that process alone, or None if
    the renderer refused."""
    cmd = [a.binary, "render", scene, "--integrator", method, "--iterations", str(iterations),
           "--seed", str(seed), "--threads", "1", "--resolution", f"{width or a.width}x",
           "-o", out]
    err_path = out + ".err"
    with open(err_path, "w") as err_file:
        # Waited for with wait4 (not Popen.wait) to read the process's own CPU time.
        # (kept referenced until then, and marked as reaped after, so that no other
        # thread's Popen reaps it first).
        p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err_file)
        _, status, ru = os.wait4(p.pid, 0)
        p.returncode = os.waitstatus_to_exitcode(status)
    err = open(err_path).read()
    os.remove(err_path)
    if status != 0:
        print(f"  {method} refused: {err.strip().splitlines()[-1] if err.strip() else '?'}",
              file=sys.stderr)
        return None
    return ru.ru_utime + ru.ru_stime


def calibrate(a, scene, method, out, width=None):
    """(fixed, per-iteration) CPU seconds of `method` on `scene`, from 1 iteration and from
    4, 16, ... until the difference is half a second (cheap iterations measured over few
    would be lost in the scatter of CPU times)."""
    c1 = render(a, scene, method, 1, 99, out, width)
    n = 4
    while c1 is not None:
        cn = render(a, scene, method, n, 99, out, width)
        if cn is None:
            return None
        if cn - c1 >= 0.5 or n >= 4096:
            per_it = max((cn - c1) / (n - 1), 1e-4)
            return max(c1 - per_it, 0.0), per_it
        n *= 4
    return None


def regions(h, w):
    """The whole image and its four quadrants, as (name, y slice, x slice)."""
    hy, hx = h // 2, w // 2
    return [("whole", slice(0, h), slice(0, w)),
            ("top left", slice(0, hy), slice(0, hx)),
            ("top right", slice(0, hy), slice(hx, w)),
            ("bottom left", slice(hy, h), slice(0, hx)),
            ("bottom right", slice(hy, h), slice(hx, w))]


def mse(img, ref, ys, xs, mask=None):
    """Mean squared difference over a region, on the pixels of `mask` in it if given."""
    d = img[ys, xs] - ref[ys, xs]
    if mask is not None:
        d = d[mask[ys, xs]]
    return float(np.mean(d * d)) if d.size else float("nan")


def reference(a, name):
    """(reference, mask or None, the reference's noise per region, width to render at) of an
    example: the committed external one, or the two path-traced halves in the cache."""
    ext = EXTERNAL.get(name)
    if ext:
        ref, mask, noise, width = external_reference(a, ext)
        h, w = ref.shape[:2]
        # `noise` is already each pixel's variance: its mean over a region's masked pixels.
        return ref, mask, {rn: float(np.mean(noise[ys, xs][mask[ys, xs]]))
                           for rn, ys, xs in regions(h, w)}, width
    d = os.path.join(a.cache, name)
    r0, r1 = (read_exr(os.path.join(d, f"ref{k}.exr")) for k in (0, 1))
    h, w = r0.shape[:2]
    return 0.5 * (r0 + r1), None, {rn: mse(r0, r1, ys, xs) / 4
                                   for rn, ys, xs in regions(h, w)}, a.width


def example(a, name, methods):
    """Renders what the cache lacks for one example; returns ({method: [per-seed result]},
    the calibrations, the budget, the width rendered at)."""
    scene = f"examples/{name}.scn"
    d = os.path.join(a.cache, name)
    os.makedirs(d, exist_ok=True)
    refs = [os.path.join(d, f"ref{k}.exr") for k in (0, 1)]
    meta_path = os.path.join(d, "meta.json")
    meta = json.load(open(meta_path)) if os.path.exists(meta_path) else {}
    ext = EXTERNAL.get(name)
    if not ext and not all(os.path.exists(r) for r in refs):
        cal = calibrate(a, scene, "path", refs[0])
        if cal is None:
            return None
        n = max(1, int(round((a.ref_cpu / 2 - cal[0]) / cal[1])))
        for k, r in enumerate(refs):
            render(a, scene, "path", n, 1000 + k, r)
    ref, mask, ref_noise, width = reference(a, name)
    h, w = ref.shape[:2]
    # Results measured against another reference (an older run's, another width, an older
    # noise estimate) are rendered again.
    ref_kind = f"{ext['image']}#noise-mean#{width}" if ext else "path"
    if width != a.width:
        print(f"{name}: rendered at the reference's width {width}", file=sys.stderr)
    cals = meta.get("calibration", {})
    for m in methods:
        if m not in cals or m in a.rerun:
            c = calibrate(a, scene, m, os.path.join(d, f"cal-{m}.exr"), width)
            cals[m] = c
    meta["calibration"] = cals
    fixed = max((c[0] for c in cals.values() if c), default=0.0)
    # Kept from the first run: methods rendered again are measured at the same budget.
    budget = meta.get("budget", max(a.cpu, a.fixed_factor * fixed))
    meta["budget"] = budget
    json.dump(meta, open(meta_path, "w"))
    results = {}
    for m in methods:
        if not cals.get(m):
            continue
        fixed_m, per_it = cals[m]
        n = max(1, int(round((budget - fixed_m) / per_it)))
        results[m] = []
        for seed in range(1, a.seeds + 1):
            res_path = os.path.join(d, f"{m}-{seed}.json")
            res = json.load(open(res_path)) if os.path.exists(res_path) else None
            if res and m not in a.rerun and res.get("reference", "path") == ref_kind:
                if "mse_raw" not in res:  # the first version stored it times cpu / budget
                    res["mse_raw"] = {k: v * budget / res["cpu"] for k, v in res["mse"].items()}
                results[m].append(res)
                continue
            out = os.path.join(d, f"{m}-{seed}.exr")
            cpu = render(a, scene, m, n, seed, out, width)
            if cpu is None:
                break
            img = read_exr(out)
            if img.shape != ref.shape:
                print(f"  {name} {m}: {img.shape} against a reference of {ref.shape}",
                      file=sys.stderr)
                break
            res = {"cpu": cpu, "iterations": n, "reference": ref_kind,
                   "mse_raw": {rn: mse(img, ref, ys, xs, mask) - ref_noise[rn]
                               for rn, ys, xs in regions(h, w)}}
            json.dump(res, open(res_path, "w"))
            results[m].append(res)
            # The next seeds' iterations from this render's cost per iteration.
            if cpu > fixed_m:
                n = max(1, int(round((budget - fixed_m) * n / (cpu - fixed_m))))
        print(f"{name} {m}: {n} it., CPU-s "
              + " ".join(f"{r['cpu']:.1f}" for r in results[m]), file=sys.stderr)
    return results, cals, budget, width


def scaled(res, region, budget, fixed):
    """A render's MSE (less the reference's noise) scaled to the budget as an unbiased
    method's would be: inversely to its CPU time past the method's fixed cost."""
    raw = res["mse_raw"][region]
    fixed = min(fixed, 0.9 * res["cpu"], 0.9 * budget)
    return raw * (res["cpu"] - fixed) / (budget - fixed)


def mean_se(xs):
    """Mean and standard error of the mean."""
    m = sum(xs) / len(xs)
    if len(xs) < 2:
        return m, float("nan")
    v = sum((x - m) ** 2 for x in xs) / (len(xs) - 1)
    return m, math.sqrt(v / len(xs))


def ratio_with_noise(x, y):
    """RMSE ratio sqrt(mean x / mean y) of per-seed MSE lists, and its standard error."""
    mx, sx = mean_se(x)
    my, sy = mean_se(y)
    if mx <= 0 or my <= 0:
        return float("nan"), float("nan")
    r = math.sqrt(mx / my)
    return r, 0.5 * r * math.sqrt((sx / mx) ** 2 + (sy / my) ** 2)


def verdict(r, se):
    if r != r:
        return "?"
    if r > 1.05 + 2 * se:
        return "LOSS"
    if r < 1.0 - 2 * se:
        return "win"
    return "tie"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", default="target/release/sppm-lang")
    ap.add_argument("--examples", help="comma-separated names (default: every examples/*.scn "
                    "but animation, whose scene renders frames)")
    ap.add_argument("--methods", default="path,sppm,vcm")
    ap.add_argument("--width", type=int, default=64)
    ap.add_argument("--cpu", type=float, default=3.0, help="least CPU seconds per method")
    ap.add_argument("--fixed-factor", type=float, default=3.0,
                    help="the budget is at least this times the largest fixed cost")
    ap.add_argument("--ref-cpu", type=float, default=40.0, help="CPU seconds of the reference")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--jobs", type=int, default=2, help="examples rendered at once")
    ap.add_argument("--cache", default="target/equal_cpu_examples")
    ap.add_argument("--rerun", default="", help="methods to render again though cached")
    ap.add_argument("--markdown", help="write the table here too")
    a = ap.parse_args()
    a.rerun = [m for m in a.rerun.split(",") if m]
    methods = a.methods.split(",")
    names = (a.examples.split(",") if a.examples else
             sorted(os.path.basename(p)[:-4] for p in glob.glob("examples/*.scn")
                    if not p.endswith("animation.scn")))
    with ThreadPoolExecutor(a.jobs) as pool:
        done = list(pool.map(lambda n: example(a, n, methods), names))
    others = [m for m in methods if m != "vcm"]
    lines = ["| example | budget CPU-s | region | " + " | ".join(f"{m} RMSE" for m in methods)
             + " | vcm / better (± noise) | verdict |",
             "|" + "---|" * (len(methods) + 5)]
    tally = {"whole": {}, "regions": {}}
    for name, got in zip(names, done):
        if got is None:
            continue
        results, cals, budget, width = got
        if "vcm" not in results or not all(results.get(m) for m in methods):
            print(f"{name}: not in the table (a method was refused or rendered no seed)",
                  file=sys.stderr)
            continue
        for rn in ["whole", "top left", "top right", "bottom left", "bottom right"]:
            per = {m: [scaled(r, rn, budget, cals[m][0]) for r in results[m]] for m in methods}
            rm = {m: math.sqrt(max(mean_se(per[m])[0], 0.0)) for m in methods}
            better = min(others, key=lambda m: rm[m])
            r, se = ratio_with_noise(per["vcm"], per[better])
            v = verdict(r, se)
            # Strictly better than both: below each beyond noise.
            if v == "win":
                v = "win" if all(verdict(*ratio_with_noise(per["vcm"], per[m])) == "win"
                                 for m in others) else "tie"
            key = "whole" if rn == "whole" else "regions"
            tally[key][v] = tally[key].get(v, 0) + 1
            label = (f"{name} (masked, {EXTERNAL[name]['image']}, {width} px)"
                     if name in EXTERNAL else name)
            lines.append(f"| {label if rn == 'whole' else ''} | "
                         f"{budget:.1f} | {rn} | " if rn == "whole" else f"| | | {rn} | ")
            lines[-1] += (" | ".join(f"{rm[m]:.4g}" for m in methods)
                          + f" | {r:.2f} ± {se:.2f} ({better}) | {v} |")
    table = "\n".join(lines)
    summary = (f"whole image: {tally['whole']}; quadrants: {tally['regions']}")
    print(table)
    print(summary)
    if a.markdown:
        with open(a.markdown, "w") as f:
            f.write(table + "\n\n" + summary + "\n")


if __name__ == "__main__":
    main()
