#!/usr/bin/env python3
"""Error of renders against a reference, split by image region (Cornell box and smallppm_far).

    .venv/bin/python tools/far_scene/regions.py --scene cornell \
        --reference ../shared/reference/cornell-glass/reference.exr a.exr b.exr ...

Regions are pixel windows (x0, y0, x1, y1, half-open) drawn on the reference images: the light
with its edge, the caustic under the glass ball, the mirror ball (its reflection), the glass
ball, and the rest (walls, most of them lit indirectly or by the light directly). Errors as in
`src/compare`: rmse and rel_mse = mean(d^2 / (ref^2 + 0.01)); `share` is the region's part of
the whole image's rel_mse sum (how much of the whole error it makes).
"""
import argparse

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")

REGIONS = {
    "cornell": {
        "light": (96, 28, 160, 52),
        "caustic": (150, 212, 200, 236),
        "mirror": (62, 155, 118, 211),
        "glass": (134, 154, 202, 212),
    },
    "smallppm_far": {
        "light": (92, 22, 162, 40),
        "caustic": (152, 158, 196, 178),
        "mirror": (72, 108, 118, 156),
        "glass": (140, 112, 194, 158),
    },
}


def read(path):
    return np.array(mi.Bitmap(path), dtype=np.float64)[:, :, :3]


def masks(scene, shape):
    out, rest = {}, np.ones(shape[:2], bool)
    for name, (x0, y0, x1, y1) in REGIONS[scene].items():
        m = np.zeros(shape[:2], bool)
        m[y0:y1, x0:x1] = True
        m &= rest
        rest &= ~m
        out[name] = m
    out["rest"] = rest
    out["all"] = np.ones(shape[:2], bool)
    return out


def split(img, ref, scene):
    d2 = (img - ref) ** 2
    rel = (d2 / (ref * ref + 0.01)).mean(axis=2)
    total = rel.sum()
    rows = {}
    for name, m in masks(scene, ref.shape).items():
        rows[name] = (np.sqrt(d2[m].mean()), rel[m].mean(), rel[m].sum() / total, m.mean())
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", required=True, choices=REGIONS)
    ap.add_argument("--reference", required=True)
    ap.add_argument("images", nargs="+")
    a = ap.parse_args()
    ref = read(a.reference)
    for path in a.images:
        rows = split(read(path), ref, a.scene)
        print(path)
        for name, (rmse, rel, share, area) in rows.items():
            print(f"  {name:8} area {area:6.1%}  rmse {rmse:.5f}  rel_mse {rel:.5f}  share {share:6.1%}")


if __name__ == "__main__":
    main()
