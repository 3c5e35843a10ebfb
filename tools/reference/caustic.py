"""The caustic reference image: tools/reference/caustic.scn rendered by Mitsuba 3.

A glass ball (IOR 1.5) floats above a diffuse floor under a small sphere light, in front of a
diffuse back wall; the ball focuses the light into a bright spot on the floor behind it. The
camera sees part of the spot directly on the floor and part of it through the ball.

Two Mitsuba integrators, each where it converges (tools/reference/README.md says why):
- `ptracer` (paths start at the light; every diffuse vertex is connected to the camera) finds
  the focused light at once, but only where the camera sees a diffuse surface directly;
- `path` finds everything, the floor seen through the ball included, more slowly.
The script renders both in passes of independent seeds and writes `caustic.exr`: the particle
tracer's image where all 4x4 stratified camera rays of a pixel hit the floor or the wall
directly (`caustic.mask.exr` is 1 there), the path tracer's elsewhere. It prints, per window
(`WINDOWS`), the mean of each pass and the spread of those means (the reference's own noise).

Run from the repository root (the committed image: scalar_rgb, 64x64; see README.md):
    python3 -m venv .venv && .venv/bin/pip install mitsuba numpy
    nice .venv/bin/python tools/reference/caustic.py [--ptracer-spp 16384] [--path-spp 32768]

Model mapping (README.md beside this file): the floor and wall are `rectangle`s with a
two-sided `diffuse`; `glass ior 1.5` is `dielectric` (int_ior 1.5, ext_ior 1); the sphere
light is a `sphere` with an `area` emitter and a black BSDF; the camera is `perspective` with
a vertical field of view.
"""
import argparse
import os
import sys

import mitsuba as mi
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from glossy import frame, lambert, rgb  # noqa: E402

SIZE = 64
EYE = [0.3, 1.1, 1.5]
TARGET = [-0.2, 0.2, -0.05]
FOV = 32.0
FLOOR = [0.8, 0.8, 0.8]
WALL = [0.5, 0.5, 0.5]
BALL_CENTER = [0.0, 0.4, 0.0]
BALL_RADIUS = 0.3
LIGHT_CENTER = [0.7, 1.6, 0.0]
# A second light just above the camera (out of the picture): the ball focuses it onto the
# floor behind the ball, where the camera sees it through the ball.
LIGHT2_CENTER = [0.3, 1.45, 1.5]
LIGHT2_RADIUS = 0.1
LIGHT2_RADIANCE = 250.0
LIGHT_RADIUS = 0.05
LIGHT_RADIANCE = 1000.0
# Windows (x0, y0, x1, y1, half-open, in pixels of the 64x64 image): the caustic seen directly
# on the floor, and seen through the ball. Kept in step with tests/accuracy/caustic_reference.rs.
# Each window counts only the pixels of its class (`pixel_classes`: 1 floor or wall seen
# directly, 2 the ball).
WINDOWS = {'direct': ((22, 38, 38, 50), 1.0), 'through': ((34, 3, 58, 13), 2.0)}


def scene(integrator, spp, size=SIZE):
    black = {'type': 'diffuse', 'reflectance': rgb([0.0, 0.0, 0.0])}
    return {
        'type': 'scene',
        # Unlimited depth, Russian roulette from depth 5 (ours: 16 vertices).
        'integrator': {'type': integrator, 'max_depth': -1},
        'sensor': {
            'type': 'perspective', 'fov': FOV, 'fov_axis': 'y',
            'to_world': mi.ScalarTransform4f().look_at(origin=EYE, target=TARGET,
                                                       up=[0.0, 1.0, 0.0]),
            'sampler': {'type': 'independent', 'sample_count': spp},
            'film': {'type': 'hdrfilm', 'width': size, 'height': size,
                     'rfilter': {'type': 'box'}, 'pixel_format': 'rgb',
                     'component_format': 'float32'},
        },
        # Floor y = 0, x in [-2, 2], z in [-1, 3]; back wall z = -1, y in [0, 3].
        'floor': {'type': 'rectangle', 'bsdf': lambert(FLOOR),
                  'to_world': frame([0, 0, 1], [2, 0, 0], [0, 0, -2], [0, 1, 0])},
        'wall': {'type': 'rectangle', 'bsdf': lambert(WALL),
                 'to_world': frame([0, 1.5, -1], [2, 0, 0], [0, 1.5, 0], [0, 0, 1])},
        'ball': {'type': 'sphere', 'center': BALL_CENTER, 'radius': BALL_RADIUS,
                 'bsdf': {'type': 'dielectric', 'int_ior': 1.5, 'ext_ior': 1.0}},
        'light': {'type': 'sphere', 'center': LIGHT_CENTER, 'radius': LIGHT_RADIUS,
                  'bsdf': black,
                  'emitter': {'type': 'area', 'radiance': rgb([LIGHT_RADIANCE] * 3)}},
        'light2': {'type': 'sphere', 'center': LIGHT2_CENTER, 'radius': LIGHT2_RADIUS,
                   'bsdf': black,
                   'emitter': {'type': 'area', 'radiance': rgb([LIGHT2_RADIANCE] * 3)}},
    }


def pixel_classes(sc, size, k=4):
    """Per pixel: 1 where all k x k stratified camera rays hit the floor or the wall first, 2
    where all hit the ball first, 0 where they differ."""
    sensor = sc.sensors()[0]
    ball = [s for s in sc.shapes() if s.id() == 'ball'][0]
    mask = np.zeros((size, size), dtype=np.float32)
    for y in range(size):
        for x in range(size):
            hits = set()
            for j in range(k):
                for i in range(k):
                    pos = mi.Point2f((x + (i + 0.5) / k) / size, (y + (j + 0.5) / k) / size)
                    ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
                    si = sc.ray_intersect(ray)
                    hits.add('none' if not si.is_valid() else
                             'ball' if si.shape == ball else 'diffuse')
            mask[y, x] = {frozenset(['diffuse']): 1.0, frozenset(['ball']): 2.0}.get(
                frozenset(hits), 0.0)
    return mask


def window_mean(img, mask, window):
    """Mean over the window's pixels of its class, all channels."""
    (x0, y0, x1, y1), cls = window
    sel = mask[y0:y1, x0:x1] == cls
    return float(img[y0:y1, x0:x1, :][sel].mean())


def passes(integrator, spp, pass_spp, size, seed0, mask, log):
    """Renders `spp // pass_spp` independent passes; returns their mean and the pass images."""
    sc = mi.load_dict(scene(integrator, pass_spp, size))
    n = max(1, spp // pass_spp)
    imgs = []
    for k in range(n):
        imgs.append(np.array(mi.render(sc, spp=pass_spp, seed=seed0 + k), dtype=np.float64))
        means = ' '.join(f'{name} {window_mean(imgs[-1], mask, w):.5f}' for name, w in WINDOWS.items())
        print(f'{integrator} pass {k + 1}/{n}: {means}', file=log, flush=True)
    return sum(imgs) / n, imgs


def spread(imgs, mask, w):
    """Mean of the pass means in a window and its standard error (relative)."""
    m = np.array([window_mean(i, mask, w) for i in imgs])
    se = m.std(ddof=1) / np.sqrt(len(m)) if len(m) > 1 else float('nan')
    return m.mean(), se / m.mean()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--size', type=int, default=SIZE)
    ap.add_argument('--ptracer-spp', type=int, default=16384)
    ap.add_argument('--path-spp', type=int, default=32768)
    ap.add_argument('--pass-spp', type=int, default=1024)
    ap.add_argument('--integrators', default='ptracer,path',
                    help='which to render now (each keeps its passes beside --out)')
    ap.add_argument('--variant', default='scalar_rgb')
    ap.add_argument('--out', default='tools/reference/caustic.exr')
    ap.add_argument('--preview', help='write one quick path-traced image here and stop')
    a = ap.parse_args()
    mi.set_variant(a.variant)
    if a.preview:
        img = mi.render(mi.load_dict(scene('path', a.pass_spp, a.size)))
        mi.Bitmap(np.array(img, dtype=np.float32)).write(a.preview)
        return
    base = a.out[:-len('.exr')] if a.out.endswith('.exr') else a.out
    mask = pixel_classes(mi.load_dict(scene('path', 1, a.size)), a.size)
    mi.Bitmap(np.repeat(mask[:, :, None], 3, axis=2)).write(base + '.mask.exr')
    spp = {'ptracer': (a.ptracer_spp, 1000), 'path': (a.path_spp, 5000)}
    for integrator in [i for i in a.integrators.split(',') if i]:
        n, seed0 = spp[integrator]
        _, imgs = passes(integrator, n, a.pass_spp, a.size, seed0, mask, sys.stdout)
        # The passes themselves (scratch, not committed): their spread is the noise.
        np.save(f'{base}.{integrator}.passes.npy', np.array(imgs, dtype=np.float32))
    done = {i: f'{base}.{i}.passes.npy' for i in spp}
    if not all(os.path.exists(f) for f in done.values()):
        return
    imgs = {i: np.load(f).astype(np.float64) for i, f in done.items()}
    pt, path = imgs['ptracer'].mean(axis=0), imgs['path'].mean(axis=0)
    m = mask[:, :, None] == 1.0
    mi.Bitmap(np.where(m, pt, path).astype(np.float32)).write(a.out)
    print(f'wrote {a.out}')
    for name, w in WINDOWS.items():
        pm, pse = spread(imgs['ptracer'], mask, w)
        qm, qse = spread(imgs['path'], mask, w)
        print(f'{name}: ptracer {pm:.5f} (+-{pse * 100:.2f} %), '
              f'path {qm:.5f} (+-{qse * 100:.2f} %) over {len(imgs["path"])} passes')


if __name__ == '__main__':
    main()
