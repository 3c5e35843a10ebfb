"""The smallppm reference image: examples/smallppm.scn rendered by Mitsuba 3's particle tracer.

smallppm is the smallpt box (the same walls, balls and camera as smallppm_far.py, which holds the
model mapping) lit by a point light. Light that reaches a wall by way of the mirror or the glass
ball (a point light seen in a mirror: a caustic) cannot be found by a path tracer, ours or
Mitsuba's: a path can only reach a point light by a shadow ray from a diffuse surface. So this
reference comes from Mitsuba's `ptracer` (light tracing): paths start at the light, bounce
freely, and every diffuse vertex is connected to the camera. That finds every path whose last
surface before the eye is diffuse, but none that reach the eye through a mirror or glass. So
the reference holds only where the camera sees a diffuse surface directly; the script writes a
mask of those pixels next to the image (`*.mask.exr`, 1 where every one of 16 stratified camera
rays of the pixel hits a diffuse wall, by Mitsuba's own ray casts; 0 elsewhere), and
comparisons use the masked pixels only.

Run from the repository root (the committed image: scalar_rgb, see tools/reference/README.md):
    python3 -m venv .venv && .venv/bin/pip install mitsuba
    .venv/bin/python tools/reference/smallppm.py --spp 8192 --pass-spp 512 \
        [--out tools/reference/smallppm.exr]

The committed image has no halves. Its noise is estimated from an independent, shorter run of
the same scene whose even and odd passes are kept apart (`--halves`: OUT.half0.exr and
OUT.half1.exr, each the mean of its passes, in half floats):
    .venv/bin/python tools/reference/smallppm.py --spp 1024 --pass-spp 256 --seed 2000 \
        --halves --out /tmp/smallppm.noise.exr
    cp /tmp/smallppm.noise.half[01].exr tools/reference/
A light tracer's passes are independent, so a pixel's variance falls as 1 / spp; the script
prints the measured ratio (one pass's variance over one half's, n passes a half: n expected).
`tools/equal_cpu_examples.py` scales the halves' noise to the committed image's 8192 spp.

Model mapping beyond smallppm_far.py's: `light { p intensity I }` (a point light of radiant
intensity I W/sr) is a `point` emitter with `intensity` I at p.
"""
import argparse
import os
import sys

import mitsuba as mi
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from glossy import rgb  # noqa: E402
import smallppm_far  # noqa: E402

S = smallppm_far.S
# examples/smallppm.scn: `light { <50, 60, 85>*S intensity rgb <2500, 2500, 2500>*S*S }`.
LIGHT_POSITION = [50 * S, 60 * S, 85 * S]
LIGHT_INTENSITY = 2500 * S * S
# Shapes whose surfaces the particle tracer cannot connect to the camera.
SPECULAR = ('mirror', 'glass')


def scene(spp, width, height):
    d = smallppm_far.scene(spp, width, height)
    d['integrator'] = {'type': 'ptracer', 'max_depth': -1, 'hide_emitters': True}
    d['light'] = {'type': 'point', 'position': LIGHT_POSITION,
                  'intensity': rgb([LIGHT_INTENSITY] * 3)}
    return d


def diffuse_mask(sc, width, height, k=4):
    """1 where all k x k stratified camera rays of a pixel hit a diffuse surface."""
    sensor = sc.sensors()[0]
    ids = {s.id(): s for s in sc.shapes()}
    specular = [ids[n] for n in SPECULAR]
    mask = np.ones((height, width), dtype=np.float32)
    for y in range(height):
        for x in range(width):
            for j in range(k):
                for i in range(k):
                    pos = mi.Point2f((x + (i + 0.5) / k) / width, (y + (j + 0.5) / k) / height)
                    ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
                    si = sc.ray_intersect(ray)
                    if not si.is_valid() or any(si.shape == s for s in specular):
                        mask[y, x] = 0.0
                        break
                if mask[y, x] == 0.0:
                    break
    return mask


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--spp', type=int, default=8192)
    ap.add_argument('--pass-spp', type=int, default=512)
    ap.add_argument('--width', type=int, default=256)
    ap.add_argument('--height', type=int, default=192)
    ap.add_argument('--variant', default='scalar_rgb')
    ap.add_argument('--out', default='tools/reference/smallppm.exr')
    ap.add_argument('--seed', type=int, default=1000, help='seed of the first pass')
    ap.add_argument('--halves', action='store_true',
                    help='also write the even and odd passes apart (OUT.half0.exr, .half1.exr)')
    a = ap.parse_args()
    mi.set_variant(a.variant)
    passes = max(1, a.spp // a.pass_spp)
    sc = mi.load_dict(scene(a.pass_spp, a.width, a.height))
    mask = diffuse_mask(sc, a.width, a.height)
    mask_path = a.out[:-len('.exr')] + '.mask.exr' if a.out.endswith('.exr') else a.out + '.mask'
    mi.Bitmap(np.repeat(mask[:, :, None], 3, axis=2)).write(mask_path)
    print(f'mask: {int(mask.sum())} of {mask.size} pixels see a diffuse surface', flush=True)
    # Even and odd passes apart: half their difference estimates the full image's noise.
    halves = [None, None]
    first_pair = []
    for k in range(passes):
        img = np.array(mi.render(sc, spp=a.pass_spp, seed=a.seed + k), dtype=np.float64)
        if k < 2:
            first_pair.append(img)
        h = k % 2
        halves[h] = img if halves[h] is None else halves[h] + img
        acc = halves[0] if halves[1] is None else halves[0] + halves[1]
        mi.Bitmap((acc / (k + 1)).astype(np.float32)).write(a.out)
        line = f'pass {k + 1}/{passes}'
        if halves[1] is not None and k % 2 == 1:
            n = (k + 1) // 2
            diff = (halves[0] - halves[1])[mask > 0.5] / n
            line += f'; noise RMSE on the mask about {np.sqrt(np.mean(diff ** 2)) / 2:.5f}'
        print(line, flush=True)
    if a.halves and passes >= 2 and passes % 2 == 0:
        n = passes // 2
        stem = a.out[:-len('.exr')] if a.out.endswith('.exr') else a.out
        for h in (0, 1):
            mi.Bitmap((halves[h] / n).astype(np.float16)).write(f'{stem}.half{h}.exr')
        on = mask > 0.5
        var_pass = np.mean(((first_pair[0] - first_pair[1])[on]) ** 2) / 2
        var_half = np.mean(((halves[0] - halves[1])[on] / n) ** 2) / 2
        print(f'variance on the mask: one pass {var_pass:.4g}, one half ({n} passes) '
              f'{var_half:.4g}, ratio {var_pass / var_half:.3f} ({n} for 1 / spp)', flush=True)


if __name__ == '__main__':
    main()
