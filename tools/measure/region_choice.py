#!/usr/bin/env python3
"""Choosing the method by image quadrant, at equal CPU time, against the better of path and
sppm: each quadrant of an example rendered by one method, the image put together from them.

Reads a cache of `tools/equal_cpu_examples.py` (its references, budgets, calibrations and
per-seed errors of path, sppm and vcm) and renders, per seed (seeds 101.., independent of the
cache's), each chosen method on its own quadrants only, with the measuring build of
`tools/measure/patches/hybrid_regions_2d7dd08.patch`. `HYBRID_MASK`: the quadrants a render
traces; the other pixels stay black and cost no camera path; sppm's photons (whole chunks of
4096, at least one: for room's top half half the full image's count) and vcm's light paths
are counted for the traced pixels, as each method counts them for an image of that many
pixels; the extra camera samples and sppm's camera/photon balance are taken over the traced
pixels; a vcm camera path connects to the light path of its rank among them; light-traced
splats outside are dropped before their shadow ray. `HYBRID_SPPM` (with `--shared`): one vcm
render whose `sppm` quadrants take SPPM's estimator from its light vertices (from their
second segment on), `HYBRID_SPPM_EXTRA` extra camera samples a pixel for their direct light,
`HYBRID_SPPM_PATHS` light paths a pixel of theirs (default 0: vcm's count alone; the paths
past vcm's count are not light-traced nor merged by vcm's pixels). Rules:

- `--rule oracle`: per quadrant the method with the lowest RMSE there in the cache (it knows
  the reference: an upper bound for a rule by quadrant), or `--assign`'s choice;
- `--rule pilot`: reference-free, from a pilot of `--pilot` of the budget (see `pilot`), whose
  CPU time counts in the hybrid's; `vcm`'s pilot images are kept in its quadrants;
- `--rule pilot-equal`: the same pilot, the two methods' errors compared as they are at the
  pilot's time (no power law carries them to the budget).

The budget past the fixed cost (less the pilot's) is shared by the methods in proportion to
their pixels (or `--share`), each method's iterations those that fill its share at its cost an
iteration on its quadrants, measured by the earlier seeds' renders (the first seed's guessed
from the full image's). The hybrid's CPU time is the sum of its renders' past their fixed
cost, plus one fixed cost (a hybrid loads the scene once). The error per region is taken as
the table's is (the reference's noise removed, scaled to the budget as an unbiased method's).

    .venv/bin/python tools/measure/region_choice.py --binary <measuring build> \\
        --cache <equal_cpu_examples cache> --width 64 --seeds 8 --examples room,bumps

Measurement only: nothing in the renderer or its tests imports it.
"""

import argparse
import json
import math
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
import equal_cpu_examples as ecx  # noqa: E402

QUADRANTS = ["top left", "top right", "bottom left", "bottom right"]


def cached(a, name, m, budget, fixed):
    """Method m's per-seed scaled MSEs per region, from the cache."""
    d = os.path.join(a.cache, name)
    out = {rn: [] for rn in ["whole"] + QUADRANTS}
    for seed in range(1, a.seeds + 1):
        res = json.load(open(os.path.join(d, f"{m}-{seed}.json")))
        for rn in out:
            out[rn].append(ecx.scaled(res, rn, budget, fixed))
    return out


def quadrant_slices(h, w):
    return [(q, ys, xs) for q, ys, xs in ecx.regions(h, w) if q in QUADRANTS]


def pilot_terms(imgs, ys, xs):
    """From a pilot's two images of each method ({"sppm": [a, b], "vcm": [a, b]}), over a
    region: sppm's variance, vcm's variance (each half the mean squared difference of its
    two images) and sppm's squared bias (the squared difference of the two methods' means,
    less both means' variances; at least 0)."""
    (s0, s1), (v0, v1) = imgs["sppm"], imgs["vcm"]

    def var(x, y):
        return float(np.mean((x[ys, xs] - y[ys, xs]) ** 2) / 2)

    var_s, var_v = var(s0, s1), var(v0, v1)
    d = 0.5 * (s0 + s1) - 0.5 * (v0 + v1)
    bias2 = max(float(np.mean(d[ys, xs] ** 2)) - var_s / 2 - var_v / 2, 0.0)
    return var_s, var_v, bias2


def scene_alpha(name):
    """The example's `alpha`, else the default 2/3."""
    found = re.search(r"\balpha\s+([0-9.]+)", open(f"examples/{name}.scn").read())
    return float(found.group(1)) if found else 2.0 / 3.0


def pilot(a, name, seed, cals, budget, width):
    """The reference-free rule: `sppm` and `vcm` each render the whole image twice (their own
    seeds) for `--pilot` of the budget in all; per quadrant each one's squared error at the
    time left after the pilot is predicted from those four images alone, and the smaller
    wins. Returns (choice, the pilot's CPU past the fixed cost, vcm's pilot images as (sum,
    iterations)). The pilot's renders' fixed costs are not counted (a hybrid loads the scene
    once).

    vcm (taken as unbiased; its merges' radius shrinks, so it is only nearly so): its
    variance, the mean over the quadrant's pixels of (a - b)^2 / 2, falls as 1 / time. sppm:
    its variance likewise from its two images, falling as time^-alpha (the scene's `alpha`,
    else 2/3); its squared bias, the mean of (mean of sppm's two - mean of vcm's two)^2 less
    both means' variances, as time^-2(1 - alpha) (the radius' area shrinks as
    iterations^(alpha - 1)). With `--rule pilot-equal` the two are compared at the pilot's
    time as measured."""
    imgs, cpu, its = {}, {}, {}
    os.environ["HYBRID_MASK"] = "15"
    os.environ["HYBRID_SPPM"] = "0"
    for m in ("sppm", "vcm"):
        fixed_m, per_it = cals[m]
        its[m] = max(1, int(round(budget * a.pilot / 4 / per_it)))
        imgs[m], cpu[m] = [], 0.0
        for k in (0, 1):
            out = os.path.join(a.out, f"{name}-pilot-{m}-{seed}-{k}.exr")
            c = ecx.render(a, f"examples/{name}.scn", m, its[m], 5000 + 2 * seed + k, out,
                           width)
            if c is None:
                return None
            cpu[m] += max(c - fixed_m, 0.0)
            imgs[m].append(ecx.read_exr(out))
    # A pilot image's time over the time left after the pilot (past the fixed cost).
    left = max(budget - max(cals[m][0] for m in cpu) - cpu["sppm"] - cpu["vcm"], 1e-3)
    rho_s, rho_v = cpu["sppm"] / 2 / left, cpu["vcm"] / 2 / left
    alpha = scene_alpha(name)
    h, w = imgs["sppm"][0].shape[:2]
    choice = {}
    for q, ys, xs in quadrant_slices(h, w):
        var_s, var_v, bias2 = pilot_terms(imgs, ys, xs)
        if a.rule == "pilot":
            mse_v = var_v * rho_v
            mse_s = var_s * rho_s ** alpha + bias2 * rho_s ** (2 * (1 - alpha))
        else:
            # `pilot-equal`: compared as they are, at the pilot's time.
            mse_v, mse_s = var_v, var_s + bias2
        choice[q] = "vcm" if mse_v < mse_s else "sppm"
    return choice, cpu["sppm"] + cpu["vcm"], (sum(imgs["vcm"]), 2 * its["vcm"])


def plan_of(bits, cals, sized):
    """Per method: (its quadrants' bits, its cost an iteration past the fixed cost on them,
    its fixed cost). The cost is measured by the renders of earlier seeds (their CPU past
    the fixed cost over their iterations, pooled); before any, guessed as the full image's
    times the method's share of the pixels."""
    plan = {}
    for m, b in bits.items():
        fixed_m, per_it = cals[m]
        spent, its = sized.get((m, b), (0.0, 0))
        guess = per_it * bin(b).count("1") / 4
        plan[m] = (b, spent / its if its else guess, fixed_m)
    return plan


def example(a, name):
    d = os.path.join(a.cache, name)
    meta = json.load(open(os.path.join(d, "meta.json")))
    budget, cals = meta["budget"], meta["calibration"]
    ref, mask, ref_noise, width = ecx.reference(a, name)
    h, w = ref.shape[:2]
    per = {m: cached(a, name, m, budget, cals[m][0]) for m in a.methods}
    rmse = {m: {rn: math.sqrt(max(ecx.mean_se(v)[0], 0.0)) for rn, v in per[m].items()}
            for m in a.methods}
    # The oracle: per quadrant the method with the lowest RMSE there in the cache.
    oracle = {q: min(a.methods, key=lambda m: rmse[m][q]) for q in QUADRANTS}
    # `--assign name=method,method,method,method` overrides it (quadrants in the order of
    # QUADRANTS).
    if name in a.assign:
        oracle = dict(zip(QUADRANTS, a.assign[name]))
    hybrid = {rn: [] for rn in ["whole"] + QUADRANTS}
    cpus, sized, chosen = [], {}, {q: {} for q in QUADRANTS}
    for seed in range(1, a.seeds + 1):
        pilot_cpu, reuse = 0.0, None
        choice = oracle
        if a.rule != "oracle":
            got = pilot(a, name, seed, cals, budget, width)
            if got is None:
                return None
            choice, pilot_cpu, reuse = got
        for q in QUADRANTS:
            chosen[q][choice[q]] = chosen[q].get(choice[q], 0) + 1
        bits = {}
        for k, q in enumerate(QUADRANTS):
            bits[choice[q]] = bits.get(choice[q], 0) | (1 << k)
        # `--shared`: one `vcm` render whose `sppm` quadrants take SPPM's estimator from its
        # light paths (`HYBRID_SPPM`).
        os.environ["HYBRID_SPPM"] = "0"
        if a.shared:
            os.environ["HYBRID_SPPM"] = str(bits.get("sppm", 0))
            bits = {"vcm": 15}
        plan = plan_of(bits, cals, sized)
        fixed = max(f for _, _, f in plan.values())
        # The time past the fixed cost left after the pilot, shared by the pixels (or
        # `--share`).
        left = max(budget - fixed - pilot_cpu, 0.0)
        img = np.zeros_like(ref)
        cpu = pilot_cpu
        for m, (b, per_it, fixed_m) in plan.items():
            share = a.share.get((name, m), bin(b).count("1") / 4)
            n = max(1, int(round(left * share / per_it)))
            out = os.path.join(a.out, f"{name}-{m}-{b}-{seed}.exr")
            os.environ["HYBRID_MASK"] = str(b)
            # Seeds of their own: the cache's renders with seeds 1.. are what it is compared
            # with.
            c = ecx.render(a, f"examples/{name}.scn", m, n, 100 + seed, out, width)
            if c is None:
                return None
            # The scene is loaded and prepared once in a hybrid: one fixed cost, the largest.
            cpu += c - fixed_m
            spent, its = sized.get((m, b), (0.0, 0))
            sized[m, b] = (spent + max(c - fixed_m, 1e-3), its + n)
            part = ecx.read_exr(out)
            if m == "vcm" and reuse is not None:
                # vcm's pilot iterations estimate the same pixels: kept, weighted by
                # iterations (not by their variance).
                part = (part * n + reuse[0] * (reuse[1] / 2)) / (n + reuse[1])
            for k, (q, ys, xs) in enumerate(quadrant_slices(h, w)):
                if b & (1 << k):
                    img[ys, xs] = part[ys, xs]
        cpu += fixed
        cpus.append(cpu)
        res = {"cpu": cpu, "mse_raw": {rn: ecx.mse(img, ref, ys, xs, mask) - ref_noise[rn]
                                       for rn, ys, xs in ecx.regions(h, w)}}
        for rn in hybrid:
            hybrid[rn].append(ecx.scaled(res, rn, budget, fixed))
    lines = []
    for rn in ["whole"] + QUADRANTS:
        better = min(["path", "sppm"], key=lambda m: rmse[m][rn])
        r, se = ecx.ratio_with_noise(hybrid[rn], per[better][rn])
        rv, sev = ecx.ratio_with_noise(per["vcm"][rn], per[better][rn])
        if rn == "whole":
            who = ""
        else:
            who = " ".join(f"{m} {k}" for m, k in sorted(chosen[rn].items()))
            who += f" (oracle {oracle[rn]})"
        lines.append(f"| {name if rn == 'whole' else ''} | {rn} | {who} | "
                     f"{rv:.2f} ± {sev:.2f} | {r:.2f} ± {se:.2f} ({better}) | "
                     f"{ecx.verdict(r, se)} |")
    cpu_note = (f"{name}: hybrid CPU-s " + " ".join(f"{c:.2f}" for c in cpus)
                + f" against a budget of {budget:.2f}")
    return lines, cpu_note


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", required=True)
    ap.add_argument("--cache", required=True)
    ap.add_argument("--examples", required=True)
    ap.add_argument("--methods", default="path,sppm,vcm")
    ap.add_argument("--width", type=int, default=64)
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--out", default="target/region_choice")
    ap.add_argument("--rule", choices=["oracle", "pilot", "pilot-equal"], default="oracle")
    ap.add_argument("--pilot", type=float, default=0.1,
                    help="the pilot's share of the budget (rule `pilot`)")
    # What ecx.external_reference reads.
    ap.add_argument("--ref-cpu", type=float, default=24.0)
    ap.add_argument("--shared", action="store_true",
                    help="one vcm render, its sppm quadrants by SPPM's estimator from its "
                    "light paths")
    ap.add_argument("--assign", action="append", default=[],
                    help="name=m1,m2,m3,m4: the quadrants' methods instead of the oracle's")
    ap.add_argument("--share", action="append", default=[],
                    help="name:method=f: that method's share of the budget (default: its "
                    "share of the pixels)")
    a = ap.parse_args()
    a.methods = a.methods.split(",")
    a.assign = {k: v.split(",") for k, v in (x.split("=") for x in a.assign)}
    a.share = {tuple(k.split(":")): float(v) for k, v in (x.split("=") for x in a.share)}
    if a.shared and a.rule != "oracle":
        ap.error("--shared takes the oracle's or --assign's choice")
    os.makedirs(a.out, exist_ok=True)
    lines = ["| example | region | method chosen (seeds) | vcm / better | hybrid / better | "
             "verdict |",
             "|---|---|---|---|---|---|"]
    notes = []
    for name in a.examples.split(","):
        got = example(a, name)
        if got is None:
            print(f"{name}: a render was refused", file=sys.stderr)
            continue
        lines += got[0]
        notes.append(got[1])
        print("\n".join(got[0]), file=sys.stderr)
    print("\n".join(lines))
    print("\n".join(notes))


if __name__ == "__main__":
    main()
