#!/usr/bin/env python3
"""What `region_choice.py --rule pilot` predicted against what the methods reach: per example
and quadrant, `sppm`'s and `vcm`'s squared error at the budget as the pilot's power laws carry
it from the pilot images (mean over the seeds), and the squared error the cache's renders reach
(the table's, scaled to the budget). The pilot image's share of the time is taken over the
whole budget past the fixed cost (the tool takes the time left after the pilot: about 10 %
less); alpha is the scene's, else 2/3. For an example compared on a mask (smallppm) the
pilot's figures cover the quadrant's pixels and the reached ones the mask's: not comparable.

    .venv/bin/python tools/measure/pilot_predictions.py --cache <equal_cpu_examples cache> \\
        --pilots <region_choice.py --out of a pilot run> --examples room,crystal_tree

Measurement only: nothing in the renderer or its tests imports it.
"""

import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.dirname(__file__))
import equal_cpu_examples as ecx  # noqa: E402
from region_choice import QUADRANTS, cached, pilot_terms, scene_alpha  # noqa: E402




def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cache", required=True)
    ap.add_argument("--pilots", required=True)
    ap.add_argument("--examples", required=True)
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--pilot", type=float, default=0.1)
    a = ap.parse_args()
    print("| example | quadrant | sppm predicted (variance part) | sppm reached "
          "| vcm predicted | vcm reached |")
    print("|---|---|---|---|---|---|")
    for name in a.examples.split(","):
        d = os.path.join(a.cache, name)
        meta = json.load(open(os.path.join(d, "meta.json")))
        budget, cals = meta["budget"], meta["calibration"]
        alpha = scene_alpha(name)
        reached = {m: {q: np.mean(v) for q, v in cached(a, name, m, budget, cals[m][0]).items()}
                   for m in ("sppm", "vcm")}
        rows = {q: [] for q in QUADRANTS}
        for seed in range(1, a.seeds + 1):
            imgs = {m: [ecx.read_exr(os.path.join(a.pilots, f"{name}-pilot-{m}-{seed}-{k}.exr"))
                        for k in (0, 1)] for m in ("sppm", "vcm")}
            rho = {}
            for m in ("sppm", "vcm"):
                its = max(1, int(round(budget * a.pilot / 4 / cals[m][1])))
                rho[m] = its * cals[m][1] / (budget - cals[m][0])
            h, w = imgs["sppm"][0].shape[:2]
            for q, ys, xs in ecx.regions(h, w):
                if q not in rows:
                    continue
                vs, vv, b2 = pilot_terms(imgs, ys, xs)
                rows[q].append((vs * rho["sppm"] ** alpha,
                                b2 * rho["sppm"] ** (2 * (1 - alpha)), vv * rho["vcm"]))
        for q in QUADRANTS:
            var_s, bias_s, pv = np.mean(rows[q], axis=0)
            print(f"| {name} | {q} | {var_s + bias_s:.2g} ({var_s:.2g}) | "
                  f"{reached['sppm'][q]:.2g} | {pv:.2g} | {reached['vcm'][q]:.2g} |")


if __name__ == "__main__":
    main()
