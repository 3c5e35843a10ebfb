#!/usr/bin/env python3
"""Every example at equal CPU time: path, sppm and vcm (or other methods) against a long path
reference, whole image and per quadrant, as RMSE ratios.

For each example the script renders a reference with the path tracer for `--ref-cpu` CPU
seconds (seed 1000), then each method for `--cpu` CPU seconds (seed 1). CPU time is the user +
system time of the render process, so the comparison holds on a loaded machine. The number of
iterations that fits the budget comes from two short calibration renders (1 and 3 iterations:
the per-iteration cost and the fixed cost of loading and preparing the scene). A render rarely
lands exactly on the budget, so each RMSE is scaled to the budget as an unbiased method's
would be (`rmse * sqrt(cpu / budget)`); the table prints the CPU seconds spent.

The reference's own noise adds to every method's error (its variance is about `cpu / ref_cpu`
of path's at the budget), which pulls the ratios toward 1: keep `--ref-cpu` at 15x `--cpu` or
more.

    python3 -m venv .venv && .venv/bin/pip install numpy OpenEXR
    cargo build --release --features cli
    .venv/bin/python tools/equal_cpu_examples.py --binary target/release/sppm-lang \\
        --width 64 --cpu 4 --ref-cpu 80 --markdown /tmp/table.md

A render whose fixed cost (loading, preparing: image textures, bump maps) passes the budget
runs one iteration and says nothing about the method; raise `--cpu` for those examples.
`tools/every_example.py` is the thorough version for path and SPPM (long references, several
budgets, edge and window regions, Mitsuba references); this one is the quick table across
methods.

Measurement only: nothing in the renderer or its tests imports it.
"""

import argparse
import glob
import os
import resource
import subprocess
import sys
import tempfile

import numpy as np
import OpenEXR


def read_exr(path):
    with OpenEXR.File(path) as f:
        ch = f.channels()
        if "RGB" in ch:
            return np.array(ch["RGB"].pixels, dtype=np.float64)
        return np.stack([np.array(ch[c].pixels, dtype=np.float64) for c in "RGB"], axis=-1)


def cpu_of_children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def render(a, scene, method, iterations, seed, out):
    """Renders and returns the CPU seconds spent, or None if the renderer refused."""
    before = cpu_of_children()
    p = subprocess.run(
        [a.binary, "render", scene, "--integrator", method, "--iterations", str(iterations),
         "--seed", str(seed), "--threads", str(a.threads), "--resolution", f"{a.width}x",
         "-o", out],
        capture_output=True, text=True)
    cpu = cpu_of_children() - before
    if p.returncode != 0:
        print(f"  {method} refused: {p.stderr.strip().splitlines()[-1] if p.stderr else '?'}",
              file=sys.stderr)
        return None
    return cpu


def iterations_for(a, scene, method, budget, out):
    """Iterations that fill `budget` CPU seconds, from renders of 1 and 3 iterations."""
    c1 = render(a, scene, method, 1, 99, out)
    if c1 is None:
        return None
    c3 = render(a, scene, method, 3, 99, out)
    per_it = max((c3 - c1) / 2.0, 1e-3)
    fixed = max(c1 - per_it, 0.0)
    return max(1, int(round((budget - fixed) / per_it)))


def regions(h, w):
    """The whole image and its four quadrants, as (name, y slice, x slice)."""
    hy, hx = h // 2, w // 2
    return [("whole", slice(0, h), slice(0, w)),
            ("top left", slice(0, hy), slice(0, hx)),
            ("top right", slice(0, hy), slice(hx, w)),
            ("bottom left", slice(hy, h), slice(0, hx)),
            ("bottom right", slice(hy, h), slice(hx, w))]


def rmse(img, ref, ys, xs):
    d = img[ys, xs] - ref[ys, xs]
    return float(np.sqrt(np.mean(d * d)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", default="target/release/sppm-lang")
    ap.add_argument("--examples", help="comma-separated names (default: every examples/*.scn)")
    ap.add_argument("--methods", default="path,sppm,vcm")
    ap.add_argument("--width", type=int, default=64)
    ap.add_argument("--cpu", type=float, default=4.0, help="CPU seconds per method")
    ap.add_argument("--ref-cpu", type=float, default=80.0, help="CPU seconds of the reference")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--markdown", help="write the table here too")
    a = ap.parse_args()
    methods = a.methods.split(",")
    names = (a.examples.split(",") if a.examples else
             sorted(os.path.basename(p)[:-4] for p in glob.glob("examples/*.scn")))
    tmp = tempfile.mkdtemp(prefix="equal_cpu_examples_")
    header = ("| example | " + " | ".join(f"{m} RMSE (CPU-s, it.)" for m in methods)
              + " | vcm / path | vcm / sppm | vcm / better, worst quadrant |")
    lines = [header, "|" + "---|" * (len(methods) + 4)]
    for name in names:
        scene = f"examples/{name}.scn"
        print(f"{name}:", file=sys.stderr)
        ref_path = os.path.join(tmp, f"{name}-ref.exr")
        n_ref = iterations_for(a, scene, "path", a.ref_cpu, ref_path)
        if n_ref is None or render(a, scene, "path", n_ref, 1000, ref_path) is None:
            continue
        ref = read_exr(ref_path)
        h, w = ref.shape[:2]
        errs, cells = {}, []
        for m in methods:
            out = os.path.join(tmp, f"{name}-{m}.exr")
            n = iterations_for(a, scene, m, a.cpu, out)
            cpu = render(a, scene, m, n, 1, out) if n is not None else None
            if cpu is None:
                cells.append("refused")
                continue
            img = read_exr(out)
            scale = np.sqrt(cpu / a.cpu)
            errs[m] = {r: rmse(img, ref, ys, xs) * scale for r, ys, xs in regions(h, w)}
            cells.append(f"{errs[m]['whole']:.4g} ({cpu:.1f}, {n})")
            print(f"  {m}: {n} it. {cpu:.1f} CPU-s, rmse {errs[m]['whole']:.4g}", file=sys.stderr)

        def ratio(x, y, r="whole"):
            return errs[x][r] / errs[y][r] if x in errs and y in errs and errs[y][r] > 0 else None

        def fmt(v):
            return "-" if v is None else f"{v:.2f}"

        worst = None
        if all(m in errs for m in ("vcm", "path", "sppm")):
            worst = max(errs["vcm"][r] / min(errs["path"][r], errs["sppm"][r])
                        for r, _, _ in regions(h, w)[1:])
        lines.append(f"| {name} | " + " | ".join(cells) + f" | {fmt(ratio('vcm', 'path'))}"
                     f" | {fmt(ratio('vcm', 'sppm'))} | {fmt(worst)} |")
        print(lines[-1], file=sys.stderr)
    table = "\n".join(lines)
    print(table)
    if a.markdown:
        with open(a.markdown, "w") as f:
            f.write(table + "\n")


if __name__ == "__main__":
    main()
