#!/usr/bin/env python3
"""Noise and bias of a render, from two renders that differ only in their seed.

    python tools/seed_split.py REFERENCE.exr A.exr B.exr

A and B are the same render with different seeds; REFERENCE may be larger by an integer
factor (it is box-filtered down, as both renderers use a box pixel filter). Per pixel channel:
the variance of one render is mean((A - B)^2) / 2; the mean squared error of (A + B) / 2 is
bias^2 + variance / 2 + the reference's own noise, so bias^2 + reference noise is that minus
half the variance. Prints both renders' RMSE, the variance and that remainder.
"""
import sys

import mitsuba as mi
import numpy as np


def read(path):
    return np.array(mi.Bitmap(path)).astype(np.float64)[..., :3]


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    mi.set_variant("scalar_rgb")
    ref, a, b = (read(p) for p in sys.argv[1:])
    if ref.shape != a.shape:
        h, w = a.shape[:2]
        ref = ref.reshape(h, ref.shape[0] // h, w, ref.shape[1] // w, 3).mean((1, 3))
    var = np.mean((a - b) ** 2) / 2
    mse = (np.mean((a - ref) ** 2) + np.mean((b - ref) ** 2)) / 2
    rest = np.mean(((a + b) / 2 - ref) ** 2) - var / 2
    print(f"RMSE {np.mean((a - ref) ** 2) ** 0.5:.4f} / {np.mean((b - ref) ** 2) ** 0.5:.4f}; "
          f"mean squared error {mse:.3e}: variance {var:.3e} ({var / mse:.0%}), "
          f"bias^2 + reference noise {rest:.3e}")


if __name__ == "__main__":
    main()
