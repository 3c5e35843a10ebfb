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
`--crop through` then renders that window's rectangle alone with `path` (a film crop: the same
pixels, far more samples) and puts its mean into the window's pixels of class 2.

Run from the repository root (the committed image: scalar_rgb, 64x64; see README.md):
    python3 -m venv .venv && .venv/bin/pip install mitsuba numpy
    nice .venv/bin/python tools/reference/caustic.py [--ptracer-spp 16384] [--path-spp 32768]
    nice .venv/bin/python tools/reference/caustic.py --crop through [--crop-spp 1048576]

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
# The first seed of `--crop`'s passes (`ptracer` starts at 1000, `path` at 5000).
CROP_SEED0 = 7000
# Windows (x0, y0, x1, y1, half-open, in pixels of the 64x64 image): the caustic seen directly
# on the floor, and seen through the ball. Kept in step with tests/accuracy/caustic_reference.rs.
# Each window counts only the pixels of its class (`pixel_classes`: 1 floor or wall seen
# directly, 2 the ball).
WINDOWS = {'direct': ((22, 38, 38, 50), 1.0), 'through': ((34, 3, 58, 13), 2.0)}


def scene(integrator, spp, size=SIZE, crop=None):
    """The scene; `crop` (x0, y0, x1, y1) renders only that rectangle of the film: Mitsuba's
    crop keeps each pixel's place in the full image, so its rays are those of the same pixels."""
    film = {'type': 'hdrfilm', 'width': size, 'height': size,
            'rfilter': {'type': 'box'}, 'pixel_format': 'rgb', 'component_format': 'float32'}
    if crop:
        x0, y0, x1, y1 = crop
        film.update(crop_offset_x=x0, crop_offset_y=y0, crop_width=x1 - x0, crop_height=y1 - y0)
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
            'film': film,
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


def passes(integrator, spp, pass_spp, size, seed0, mask, log, crop=None, save=None):
    """Renders `spp // pass_spp` independent passes (of the `crop` rectangle only, if given:
    placed in a full-size image, zero outside it); returns their mean and the pass images.
    With `save`, the passes so far go there after each one (scratch, for checking progress)."""
    sc = mi.load_dict(scene(integrator, pass_spp, size, crop))
    n = max(1, spp // pass_spp)
    imgs = []
    for k in range(n):
        img = np.array(mi.render(sc, spp=pass_spp, seed=seed0 + k), dtype=np.float64)
        if crop:
            x0, y0, x1, y1 = crop
            full = np.zeros((size, size, img.shape[2]))
            full[y0:y1, x0:x1] = img
            img = full
        imgs.append(img)
        if save:
            np.save(save, np.array(imgs, dtype=np.float32))
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
    ap.add_argument('--crop', choices=sorted(WINDOWS),
                    help="render only this window's rectangle with `path`, finer (--crop-spp); "
                    "its mean replaces the window's pixels of its class in --out")
    ap.add_argument('--crop-spp', type=int, default=1048576)
    ap.add_argument('--crop-pass-spp', type=int, default=16384)
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
    if a.crop:
        # The passes themselves (scratch, not committed): their spread is the noise.
        passes('path', a.crop_spp, a.crop_pass_spp, a.size, CROP_SEED0, mask, sys.stdout,
               crop=WINDOWS[a.crop][0], save=f'{base}.path.{a.crop}.passes.npy')
    spp = {'ptracer': (a.ptracer_spp, 1000), 'path': (a.path_spp, 5000)}
    for integrator in [i for i in a.integrators.split(',') if i and not a.crop]:
        n, seed0 = spp[integrator]
        passes(integrator, n, a.pass_spp, a.size, seed0, mask, sys.stdout,
               save=f'{base}.{integrator}.passes.npy')
    done = {i: f'{base}.{i}.passes.npy' for i in spp}
    if all(os.path.exists(f) for f in done.values()):
        imgs = {i: np.load(f).astype(np.float64) for i, f in done.items()}
        for i, (n, _) in spp.items():
            if len(imgs[i]) < n // a.pass_spp:
                print(f'warning: {done[i]} holds {len(imgs[i])} of {n // a.pass_spp} passes '
                      '(an interrupted run?)', file=sys.stderr)
        pt, path = imgs['ptracer'].mean(axis=0), imgs['path'].mean(axis=0)
        out = np.where(mask[:, :, None] == 1.0, pt, path)
        for name, w in WINDOWS.items():
            pm, pse = spread(imgs['ptracer'], mask, w)
            qm, qse = spread(imgs['path'], mask, w)
            print(f'{name}: ptracer {pm:.5f} (+-{pse * 100:.2f} %), '
                  f'path {qm:.5f} (+-{qse * 100:.2f} %) over {len(imgs["path"])} passes')
    elif os.path.exists(a.out):
        # Without the full passes (scratch), the finer windows go into the committed image.
        out = np.array(mi.Bitmap(a.out), dtype=np.float64)[:, :, :3]
    else:
        return
    for name, w in WINDOWS.items():
        f = f'{base}.path.{name}.passes.npy'
        if not os.path.exists(f):
            continue
        imgs = np.load(f).astype(np.float64)
        if len(imgs) < a.crop_spp // a.crop_pass_spp:
            # Passes are saved as they finish: an interrupted run leaves fewer.
            print(f'warning: {f} holds {len(imgs)} of {a.crop_spp // a.crop_pass_spp} passes '
                  '(an interrupted run?)', file=sys.stderr)
        (x0, y0, x1, y1), cls = w
        # Only the window's pixels of its class: its other pixels (the ball's outline) and
        # the rest of the image keep the full render's values.
        sel = np.zeros(mask.shape, dtype=bool)
        sel[y0:y1, x0:x1] = mask[y0:y1, x0:x1] == cls
        before = window_mean(out, mask, w)
        out[sel] = imgs.mean(axis=0)[sel]
        cm, cse = spread(imgs, mask, w)
        print(f'{name}: path crop {cm:.5f} (+-{cse * 100:.3f} %) over {len(imgs)} passes '
              f'replaces {before:.5f} ({(before / cm - 1) * 100:+.2f} %)')
    mi.Bitmap(out.astype(np.float32)).write(a.out)
    print(f'wrote {a.out}')


if __name__ == '__main__':
    main()
