"""The glossy reference image: tools/reference/glossy.scn rendered by Mitsuba 3 (scalar_rgb).

Run from the repository root (about an hour on two cores at the default 8192 spp):
    python3 -m venv /tmp/venv && /tmp/venv/bin/pip install mitsuba
    /tmp/venv/bin/python tools/reference/glossy.py [--spp 8192] [--out tools/reference/glossy.exr]

Model mapping (README.md beside this file): our `glossy rgb <0,0,0> specular F0 roughness r`
is `f = Schlick(F0, wi.h) D_GGX(h; alpha) G1(wo) G1(wi) / (4 cos_o cos_i)` with alpha = r^2
and the separable Smith G; Mitsuba's `principled` BSDF with metallic 1, base_color F0 and
roughness r is that same function (no diffuse, sheen, clearcoat or transmission lobe at
metallic 1). Our diffuse walls are two-sided Lambertian (Mitsuba: `twosided` `diffuse`).
"""
import argparse

import mitsuba as mi

mi.set_variant('scalar_rgb')

WHITE = [0.725, 0.71, 0.68]
RED = [0.63, 0.065, 0.05]
GREEN = [0.14, 0.45, 0.091]


def frame(center, u, v, n):
    """A `rectangle` ([-1,1]^2 in local xy, normal +z) mapped to center + x u + y v, normal n."""
    return mi.ScalarTransform4f([
        [u[0], v[0], n[0], center[0]],
        [u[1], v[1], n[1], center[1]],
        [u[2], v[2], n[2], center[2]],
        [0.0, 0.0, 0.0, 1.0],
    ])


def rgb(value):
    return {'type': 'rgb', 'value': value}


def lambert(color):
    return {'type': 'twosided', 'bsdf': {'type': 'diffuse', 'reflectance': rgb(color)}}


def glossy(f0, roughness):
    """Our `glossy` with albedo 0: GGX, Schlick Fresnel from F0, alpha = roughness^2."""
    return {'type': 'twosided', 'bsdf': {
        'type': 'principled', 'base_color': rgb(f0), 'metallic': 1.0,
        'roughness': roughness}}


def scene(size, spp):
    black = {'type': 'diffuse', 'reflectance': rgb([0.0, 0.0, 0.0])}
    return {
        'type': 'scene',
        # Unlimited depth, Russian roulette from depth 5 (ours: 16 vertices; 0.8^16 of the
        # light is left after 16 bounces off the brightest surface, far below the noise).
        'integrator': {'type': 'path', 'max_depth': -1},
        'sensor': {
            'type': 'perspective', 'fov': 40.0, 'fov_axis': 'y',
            'to_world': mi.ScalarTransform4f().look_at(
                origin=[0.0, 1.0, 3.9], target=[0.0, 1.0, 0.0], up=[0.0, 1.0, 0.0]),
            'sampler': {'type': 'independent', 'sample_count': spp},
            'film': {'type': 'hdrfilm', 'width': size, 'height': size,
                     'rfilter': {'type': 'box'}, 'pixel_format': 'rgb',
                     'component_format': 'float32'},
        },
        'floor': {'type': 'rectangle', 'to_world': frame([0, 0, 0], [1, 0, 0], [0, 0, -1], [0, 1, 0]),
                  'bsdf': glossy([0.8, 0.8, 0.8], 0.25)},
        'ceiling': {'type': 'rectangle', 'to_world': frame([0, 2, 0], [1, 0, 0], [0, 0, 1], [0, -1, 0]),
                    'bsdf': lambert(WHITE)},
        'back': {'type': 'rectangle', 'to_world': frame([0, 1, -1], [1, 0, 0], [0, 1, 0], [0, 0, 1]),
                 'bsdf': lambert(WHITE)},
        'left': {'type': 'rectangle', 'to_world': frame([-1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0]),
                 'bsdf': lambert(RED)},
        'right': {'type': 'rectangle', 'to_world': frame([1, 1, 0], [0, 0, 1], [0, 1, 0], [-1, 0, 0]),
                  'bsdf': lambert(GREEN)},
        # Emitting downward only, black (our area lights without a material reflect nothing).
        'light': {'type': 'rectangle',
                  'to_world': frame([0, 1.98, 0], [0.25, 0, 0], [0, 0, 0.25], [0, -1, 0]),
                  'bsdf': black,
                  'emitter': {'type': 'area', 'radiance': rgb([17.0, 12.0, 4.0])}},
        'bulb': {'type': 'sphere', 'center': [-0.5, 1.4, 0.2], 'radius': 0.08, 'bsdf': black,
                 'emitter': {'type': 'area', 'radiance': rgb([30.0, 30.0, 40.0])}},
        'ball': {'type': 'sphere', 'center': [0.35, 0.4, -0.2], 'radius': 0.4,
                 'bsdf': glossy([0.95, 0.64, 0.54], 0.25)},
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--size', type=int, default=128)
    ap.add_argument('--spp', type=int, default=8192)
    ap.add_argument('--chunk', type=int, default=512, help='spp per run (runs are averaged)')
    ap.add_argument('--out', default='tools/reference/glossy.exr')
    a = ap.parse_args()
    runs = max(1, a.spp // a.chunk)
    sc = mi.load_dict(scene(a.size, a.chunk))
    acc = None
    for i in range(runs):
        img = mi.TensorXf(mi.render(sc, spp=a.chunk, seed=1000 + i))
        acc = img if acc is None else acc + img
        print(f'run {i + 1}/{runs}', flush=True)
    mi.util.write_bitmap(a.out, acc / runs)
    print(f'wrote {a.out} ({runs * a.chunk} spp)')


if __name__ == '__main__':
    main()
