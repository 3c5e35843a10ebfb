#!/usr/bin/env python3
"""One method at a fixed number of iterations over several seeds: its squared error against
the path reference `tools/equal_cpu_examples.py` left in its cache, its CPU time, and their
product (lower is better at equal CPU time when the error falls as 1 / iterations).

    .venv/bin/python tools/fixed_iterations.py --binary target/release/sppm-lang \\
        --cache target/ecx --example crystal_tree --integrator vcm --iterations 128 \\
        --seeds 1,2,3,4

Each render runs with 1 thread at `--width` pixels wide (the cache's width: 64 unless it was
made with another). The reference is the mean of the cache's two halves (`ref0.exr`,
`ref1.exr`); its own noise, `mean((a - b)^2) / 4`, is subtracted from every MSE as there. CPU
time is the user + system time of each render process. Prints the mean MSE over the seeds
with its standard error, the mean CPU seconds, MSE x CPU, MSE x iterations (the squared error
of one iteration) and each seed's MSE.

Measurement only: nothing in the renderer or its tests imports it.
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

from equal_cpu_examples import read_exr


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--binary", default="target/release/sppm-lang")
    ap.add_argument("--cache", required=True, help="an equal_cpu_examples.py cache")
    ap.add_argument("--example", required=True)
    ap.add_argument("--integrator", default="vcm")
    ap.add_argument("--iterations", type=int, default=128)
    ap.add_argument("--seeds", default="1,2,3,4")
    ap.add_argument("--width", type=int, default=64)
    a = ap.parse_args()
    seeds = [int(s) for s in a.seeds.split(",")]
    if len(seeds) < 2:
        sys.exit("two seeds at least (the standard error)")
    d = os.path.join(a.cache, a.example)
    if not all(os.path.exists(os.path.join(d, f"ref{k}.exr")) for k in (0, 1)):
        sys.exit(f"{d} holds no path reference (ref0.exr, ref1.exr): an example that "
                 "equal_cpu_examples.py compares with a committed reference (smallppm) is not "
                 "measured here")
    r0, r1 = read_exr(os.path.join(d, "ref0.exr")), read_exr(os.path.join(d, "ref1.exr"))
    ref, ref_noise = (r0 + r1) / 2, np.mean((r0 - r1) ** 2) / 4
    scene = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples",
                         a.example + ".scn")
    mses, cpus = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for s in seeds:
            out = os.path.join(tmp, f"{s}.exr")
            cmd = [a.binary, "render", scene, "--integrator", a.integrator, "--iterations",
                   str(a.iterations), "--seed", str(s), "--threads", "1", "--resolution",
                   f"{a.width}x", "-o", out]
            p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
            _, status, ru = os.wait4(p.pid, 0)
            err = p.stderr.read().decode(errors="replace")
            p.stderr.close()
            if status != 0:
                sys.exit(f"seed {s} failed: {err.strip()}")
            img = read_exr(out)
            if img.shape != ref.shape:
                sys.exit(f"image {img.shape} against reference {ref.shape}: another --width?")
            mses.append(float(np.mean((img - ref) ** 2) - ref_noise))
            cpus.append(ru.ru_utime + ru.ru_stime)
    m, c = float(np.mean(mses)), float(np.mean(cpus))
    se = float(np.std(mses, ddof=1) / np.sqrt(len(mses)))
    print(f"{a.example} {a.integrator} {a.iterations} it.: MSE {m:.4g} ± {se:.2g}, "
          f"CPU-s {c:.3f}, MSE x CPU {m * c:.4g}, MSE x it. {m * a.iterations:.4g}; "
          f"seeds {' '.join(f'{x:.3g}' for x in mses)}")


if __name__ == "__main__":
    main()
