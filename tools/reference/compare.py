"""Per-pixel error of renders against a reference image (EXR, linear RGB).

    .venv/bin/pip install mitsuba numpy
    .venv/bin/python tools/reference/compare.py tools/reference/glossy.exr a.exr [b.exr ...]

Prints, per image: the mean over the reference's, and the 99th, 99.9th and 99.99th percentiles,
the largest value and the root mean square of the per-pixel error (mean absolute difference of
the three channels), over the whole image and over the pixels away from directly seen lights
(the reference at the pixel and its 8 neighbours below 2), as tests/accuracy/glossy_reference.rs does.
"""
import sys

import mitsuba as mi
import numpy as np

mi.set_variant('scalar_rgb')


def load(path):
    return np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]


def summary(err):
    p = np.percentile(err, [99, 99.9, 99.99])
    return (f'p99 {p[0]:.3f} p99.9 {p[1]:.3f} p99.99 {p[2]:.3f} max {err.max():.2f} '
            f'rms {np.sqrt((err ** 2).mean()):.4f}')


def main():
    ref = load(sys.argv[1])
    bright = ref.mean(axis=2) >= 2.0
    near = bright.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            shifted = np.zeros_like(bright)
            h, w = bright.shape
            shifted[max(dy, 0):h + min(dy, 0), max(dx, 0):w + min(dx, 0)] = \
                bright[max(-dy, 0):h + min(-dy, 0), max(-dx, 0):w + min(-dx, 0)]
            near |= shifted
    for path in sys.argv[2:]:
        img = load(path)
        err = np.abs(img - ref).mean(axis=2)
        print(f'{path}: mean {img.mean() / ref.mean():.4f} of the reference\n'
              f'  whole image:          {summary(err)}\n'
              f'  away from the lights: {summary(err[~near])}')


if __name__ == '__main__':
    main()
