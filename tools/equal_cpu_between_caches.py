#!/usr/bin/env python3
"""One method's RMSE in one `tools/equal_cpu_examples.py` cache over its RMSE in another, per
example and region, at the budget each cache's renders were scaled to (the same scaling as
that script's table), with the standard error from the per-seed spread: a before/after of
a change to the method, free of the other methods' renders (which two caches may hold for
different seeds).

    .venv/bin/python tools/equal_cpu_between_caches.py --before <cache> --after <cache> \\
        --method vcm --examples room,goblet --seeds 6

Measurement only: nothing in the renderer or its tests imports it.
"""

import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from equal_cpu_examples import ratio_with_noise, scaled  # noqa: E402


def renders(cache, name, method, seeds):
    d = os.path.join(cache, name)
    meta = json.load(open(os.path.join(d, "meta.json")))
    calibration = (meta.get("calibration") or {}).get(method)
    if not calibration:
        sys.exit(f"error: {d}/meta.json has no calibration of {method}: render it first")
    budget, fixed = meta["budget"], calibration[0]
    res = [json.load(open(os.path.join(d, f"{method}-{s}.json"))) for s in range(1, seeds + 1)]
    return res, budget, fixed


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--before", required=True)
    ap.add_argument("--after", required=True)
    ap.add_argument("--method", default="vcm")
    ap.add_argument("--examples", required=True, help="comma-separated names")
    ap.add_argument("--seeds", type=int, default=6)
    a = ap.parse_args()
    print("| example | region | RMSE after / before | iterations before, after (seed 1) |")
    print("|---|---|---|---|")
    for name in a.examples.split(","):
        before = renders(a.before, name, a.method, a.seeds)
        after = renders(a.after, name, a.method, a.seeds)
        for k, region in enumerate(before[0][0]["mse_raw"]):
            x = [scaled(r, region, after[1], after[2]) for r in after[0]]
            y = [scaled(r, region, before[1], before[2]) for r in before[0]]
            r, se = ratio_with_noise(x, y)
            its = f"{before[0][0]['iterations']}, {after[0][0]['iterations']}" if k == 0 else ""
            print(f"| {name if k == 0 else ''} | {region} | {r:.2f} ± {se:.2f} | {its} |")


if __name__ == "__main__":
    main()
