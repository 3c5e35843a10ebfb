"""Two renderer binaries on the same render, alternated (A, B, A, B, ...): each run's CPU time
and peak memory, and whether every EXR channel of every run is bit for bit the same.

    python3 -m venv .venv && .venv/bin/pip install numpy OpenEXR
    .venv/bin/python tools/ab_render.py --a target/base-bins/sppm-lang \\
        --b target/release/sppm-lang --rounds 2 --threads 1,2 -- \\
        render examples/cornell.scn --integrator vcm --resolution 256x256 --iterations 4 --seed 1

The arguments after `--` are the render's, without `--threads` and `-o`: each run adds
`--threads T` for every T of `--threads` and writes its own EXR. Runs go under `/usr/bin/time -f
"%U %S %M"` (user and system CPU seconds, peak resident KiB). The images of every binary and
thread count are compared channel by channel as raw bits (so -0.0 and 0.0 differ, a NaN equals
itself): the report says "identical" or names the first differing file and channel. The machine's
load average is printed before and after.

Measurement only: nothing in the renderer or its tests imports it.
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
import OpenEXR


def channels(path):
    with OpenEXR.File(path) as f:
        out = {}
        for name, ch in f.channels().items():
            a = np.ascontiguousarray(ch.pixels)
            out[name] = (a.dtype.str, a.shape, a.view(np.uint8).tobytes())
        return out


def run(binary, args, threads, out):
    cmd = ["/usr/bin/time", "-f", "%U %S %M", binary] + args + [
        "--threads", str(threads), "-o", out]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"failed ({p.returncode}): {' '.join(cmd)}\n{p.stderr}")
    user, system, rss = p.stderr.strip().splitlines()[-1].split()
    return float(user), float(system), int(rss)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--a", required=True)
    ap.add_argument("--b", required=True)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--threads", default="1")
    ap.add_argument("render", nargs=argparse.REMAINDER)
    a = ap.parse_args()
    args = a.render[1:] if a.render[:1] == ["--"] else a.render
    threads = [int(t) for t in a.threads.split(",")]
    print("load before:", " ".join(f"{x:.2f}" for x in os.getloadavg()))
    tmp = tempfile.mkdtemp(prefix="ab_render_")
    times = {}
    images = []
    for r in range(a.rounds):
        for label, binary in (("A", a.a), ("B", a.b)):
            for t in threads:
                out = os.path.join(tmp, f"{label}_t{t}_r{r}.exr")
                user, system, rss = run(binary, args, t, out)
                times.setdefault((label, t), []).append((user, system, rss))
                print(f"{label} threads {t} round {r}: user {user:.2f} s, sys {system:.2f} s, "
                      f"peak {rss} KiB ({rss / 2**20:.3f} GiB)", flush=True)
                images.append(out)
    for (label, t), runs in sorted(times.items()):
        cpu = [u + s for u, s, _ in runs]
        rss = [m for _, _, m in runs]
        print(f"{label} threads {t}: CPU (user+sys) {min(cpu):.2f}-{max(cpu):.2f} s, "
              f"peak {min(rss)}-{max(rss)} KiB")
    first = channels(images[0])
    same = True
    for path in images[1:]:
        other = channels(path)
        if other.keys() != first.keys():
            print(f"channels differ: {os.path.basename(path)}: {sorted(other)} vs {sorted(first)}")
            same = False
            break
        diff = [c for c in first if first[c] != other[c]]
        if diff:
            print(f"differs: {os.path.basename(path)} channel {diff[0]} "
                  f"(against {os.path.basename(images[0])})")
            same = False
            break
    if same:
        print(f"identical: every channel ({', '.join(sorted(first))}) of all {len(images)} images")
    print("load after:", " ".join(f"{x:.2f}" for x in os.getloadavg()))
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
