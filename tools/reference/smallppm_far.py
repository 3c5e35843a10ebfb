"""The smallppm_far reference image: examples/smallppm_far.scn rendered by Mitsuba 3.

Run from the repository root (the committed image: scalar_rgb, 9216 spp, about 70 minutes on two
shared cores; `llvm_ad_rgb` stopped with an LLVM instruction-selection error on this machine):
    python3 -m venv .venv && .venv/bin/pip install mitsuba
    .venv/bin/python tools/reference/smallppm_far.py --variant scalar_rgb --spp 9216 --pass-spp 512 \
        [--out tools/reference/smallppm_far.exr]

Model mapping (README.md beside this file). Units: smallpt's scaled by 1/100 (meters), y up.
- Our walls are infinite `plane`s; nothing lies outside the box, so only the part of each plane
  that bounds the open tunnel x in [0.01, 0.99], y in [0, 0.816], z >= 0 matters. Here each is a
  `rectangle` over that face, from z = -0.01 to z = 200 (the camera is at z = 2.956 and sees
  z <= 1.7; light that comes back from beyond z = 200 passes an opening of 0.8 m^2 seen from
  200 m: below 1e-5 of the image), widened by 0.01 past the tunnel's edges so that no gap opens
  at the corners. Diffuse walls: `twosided` `diffuse` (ours are two-sided Lambertian).
- `area_light { disk { c, <0,-1,0>, r } radiance L }` (one-sided, black): a `disk` (unit disk,
  normal +z) scaled by r, its normal turned to -y, with an `area` emitter of radiance L and a
  black `diffuse` BSDF.
- `mirror rgb <0.999,...>`: `conductor` with `material` none and `specular_reflectance` 0.999.
- `glass ior 1.5`: `dielectric`, int_ior 1.5, ext_ior 1.0, no absorption.
- `camera { location, look_at, fov 30.5 }` (vertical field of view, up +y): `perspective`,
  `fov_axis` y, `look_at` transform (pixel (0, 0) is the top-left corner in both).
- Our `max_depth` 16 against Mitsuba's unlimited depth (Russian roulette from depth 5): the
  light left after 16 bounces in this open tunnel (albedo <= 0.75) is below 0.75^16 = 1 % of
  the indirect part and far less of the image (measured: docs/measurements.md).
"""
import argparse
import os
import sys

import mitsuba as mi
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
# `frame` maps Mitsuba's local xy shapes (normal +z); `lambert` is a two-sided diffuse.
from glossy import frame, lambert, rgb  # noqa: E402

S = 0.01
GREY = [0.75, 0.75, 0.75]
LEFT = [0.75, 0.25, 0.25]
RIGHT = [0.25, 0.25, 0.75]
Z_FAR = 200.0


def scene(spp, width=256, height=192):
    eye = [50 * S, 52 * S, 295.6 * S]
    target = [50 * S, (52 - 0.042612 * 100) * S, (295.6 - 100) * S]
    black = {'type': 'diffuse', 'reflectance': rgb([0.0, 0.0, 0.0])}
    # The tunnel's faces, widened by W past its edges; z from -W to Z_FAR.
    w = 0.01
    hx, hy, hz = 0.49 + w, 0.408 + w, (Z_FAR + w) / 2
    cx, cy, cz = 0.5, 0.408, (Z_FAR - w) / 2
    return {
        'type': 'scene',
        'integrator': {'type': 'path', 'max_depth': -1},
        'sensor': {
            'type': 'perspective', 'fov': 30.5, 'fov_axis': 'y',
            'near_clip': 0.001, 'far_clip': 1000.0,
            'to_world': mi.ScalarTransform4f().look_at(origin=eye, target=target, up=[0, 1, 0]),
            'sampler': {'type': 'independent', 'sample_count': spp},
            'film': {'type': 'hdrfilm', 'width': width, 'height': height,
                     'rfilter': {'type': 'box'}, 'pixel_format': 'rgb',
                     'component_format': 'float32'},
        },
        'left': {'type': 'rectangle', 'bsdf': lambert(LEFT),
                 'to_world': frame([1 * S, cy, cz], [0, hy, 0], [0, 0, hz], [1, 0, 0])},
        'right': {'type': 'rectangle', 'bsdf': lambert(RIGHT),
                  'to_world': frame([99 * S, cy, cz], [0, 0, hz], [0, hy, 0], [-1, 0, 0])},
        'back': {'type': 'rectangle', 'bsdf': lambert(GREY),
                 'to_world': frame([cx, cy, 0.0], [hx, 0, 0], [0, hy, 0], [0, 0, 1])},
        'floor': {'type': 'rectangle', 'bsdf': lambert(GREY),
                  'to_world': frame([cx, 0.0, cz], [0, 0, hz], [hx, 0, 0], [0, 1, 0])},
        'ceiling': {'type': 'rectangle', 'bsdf': lambert(GREY),
                    'to_world': frame([cx, 81.6 * S, cz], [hx, 0, 0], [0, 0, hz], [0, -1, 0])},
        # smallpt's light: a disk of radius 18 at y = 81.5, facing down, radiance 12.
        'light': {'type': 'disk', 'bsdf': black,
                  'to_world': frame([50 * S, 81.5 * S, 81.6 * S], [18 * S, 0, 0],
                                    [0, 0, 18 * S], [0, -1, 0]),
                  'emitter': {'type': 'area', 'radiance': rgb([12.0, 12.0, 12.0])}},
        'mirror': {'type': 'sphere', 'center': [27 * S, 16.5 * S, 47 * S], 'radius': 16.5 * S,
                   'bsdf': {'type': 'conductor', 'material': 'none',
                            'specular_reflectance': rgb([0.999, 0.999, 0.999])}},
        'glass': {'type': 'sphere', 'center': [73 * S, 16.5 * S, 88 * S], 'radius': 16.5 * S,
                  'bsdf': {'type': 'dielectric', 'int_ior': 1.5, 'ext_ior': 1.0}},
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--spp', type=int, default=9216)
    ap.add_argument('--pass-spp', type=int, default=512)
    ap.add_argument('--variant', default='scalar_rgb')
    ap.add_argument('--out', default='tools/reference/smallppm_far.exr')
    a = ap.parse_args()
    mi.set_variant(a.variant)
    passes = max(1, a.spp // a.pass_spp)
    sc = mi.load_dict(scene(a.pass_spp))
    acc = None
    for k in range(passes):
        img = np.array(mi.render(sc, spp=a.pass_spp, seed=1000 + k), dtype=np.float64)
        acc = img if acc is None else acc + img
        print(f'pass {k + 1}/{passes}', flush=True)
        mi.Bitmap((acc / (k + 1)).astype(np.float32)).write(a.out)


if __name__ == '__main__':
    main()
