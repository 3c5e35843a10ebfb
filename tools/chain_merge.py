#!/usr/bin/env python3
"""How well `farm` chains merge: K chains of I iterations (`render --chain k/K`, then `merge`)
against one render of K*I iterations and one of I, each compared with a long reference render
(root-mean-square error over the linear pixel values, as the farm test computes it).

    python3 tools/chain_merge.py --bin target/release/sppm-lang --integrator vcm \
        --chains 4 --iterations 64 --ref-iterations 4096 --seeds 1,2,3,4

Every render is 32x32 of examples/cornell.scn with 500 photons (what the farm test renders),
one thread. By default the reference has the scene's seed (7) and every compared render seed S,
so the reference is independent of them unless S is 7; `--ref-seed same` gives each seed a
reference of its own seed, as the farm test does. Prints a line per seed and the mean ratios.
Needs numpy and OpenEXR.
"""

import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
import OpenEXR


def read(path):
    with OpenEXR.File(path) as f:
        ch = f.channels()
        if "RGB" in ch:
            return np.asarray(ch["RGB"].pixels, dtype=np.float64)
        return np.stack(
            [np.asarray(ch[c].pixels, dtype=np.float64) for c in "RGB"], axis=-1
        )


def rmse(a, b):
    return float(np.sqrt(np.mean((read(a) - read(b)) ** 2)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default="target/release/sppm-lang")
    ap.add_argument("--scene", default="examples/cornell.scn")
    ap.add_argument("--integrator", default="vcm")
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--iterations", type=int, default=64)
    ap.add_argument("--ref-iterations", type=int, default=4096)
    ap.add_argument("--ref-seed", default="7")
    ap.add_argument("--seeds", default="1,2,3,4")
    ap.add_argument("--resolution", default="32x32")
    ap.add_argument("--photons", default="500")
    ap.add_argument("--dir", default=None, help="keep the files here (and reuse them)")
    ap.add_argument("--ref-dir", default=None, help="the references' folder (default: --dir)")
    a = ap.parse_args()
    work = a.dir or tempfile.mkdtemp(prefix="chain_merge_")
    os.makedirs(work, exist_ok=True)
    ref_dir = a.ref_dir or work
    os.makedirs(ref_dir, exist_ok=True)
    env = dict(os.environ)

    def render(out, iterations, seed, chain=None):
        if os.path.exists(out):
            return out
        cmd = [a.bin, "render", a.scene, "--integrator", a.integrator, "--resolution",
               a.resolution, "--photons", a.photons, "--iterations", str(iterations),
               "--seed", str(seed), "--threads", "1", "-o", out]
        if chain:
            cmd += ["--chain", chain]
        subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        return out

    def ref(seed):
        s = seed if a.ref_seed == "same" else int(a.ref_seed)
        return render(os.path.join(ref_dir, f"ref_{a.integrator}_{a.ref_iterations}_{s}.exr"),
                      a.ref_iterations, s)

    k, n = a.chains, a.iterations
    ratios, vs_chain, mse = [], [], []
    print(f"{a.integrator}: {k} chains of {n} iterations against one render of {k * n}, "
          f"reference {a.ref_iterations} iterations, seed {a.ref_seed}")
    for seed in [int(s) for s in a.seeds.split(",")]:
        tag = f"{a.integrator}_{seed}"
        chains = [render(os.path.join(work, f"c{c}_{k}_{n}_{tag}.exr"), n, seed, f"{c}/{k}")
                  for c in range(1, k + 1)]
        merged = os.path.join(work, f"m_{k}_{n}_{tag}.exr")
        subprocess.run([a.bin, "merge", *chains, "-o", merged], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        long = render(os.path.join(work, f"x_{k * n}_{tag}.exr"), k * n, seed)
        one = render(os.path.join(work, f"x_{n}_{tag}.exr"), n, seed)
        r = ref(seed)
        e_m, e_l, e_1 = rmse(merged, r), rmse(long, r), rmse(one, r)
        ratios.append(e_m / e_l)
        mse.append((e_m**2, e_l**2, e_1**2))
        vs_chain.append(e_m / e_1)
        print(f"seed {seed}: merged {e_m:.5f}  one of {k * n} {e_l:.5f}  one of {n} {e_1:.5f}"
              f"  merged/long {e_m / e_l:.3f}  merged/one chain {e_m / e_1:.3f}")
    r = np.array(ratios)
    print(f"mean merged/long {r.mean():.3f} (+- {r.std(ddof=1) / np.sqrt(len(r)) if len(r) > 1 else 0:.3f}),"
          f" range {r.min():.3f}-{r.max():.3f}; mean merged/one chain {np.mean(vs_chain):.3f}")
    m = np.mean(np.array(mse), axis=0)
    print(f"over the seeds: rms errors merged {np.sqrt(m[0]):.5f}, one of {k * n} "
          f"{np.sqrt(m[1]):.5f}, one of {n} {np.sqrt(m[2]):.5f}: merged/long "
          f"{np.sqrt(m[0] / m[1]):.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
