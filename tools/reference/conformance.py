"""Conformance sweep: tiny scenes, one feature each, rendered by sppm-lang and by Mitsuba 3.

Each case is written twice, as our `.scn` text and as a Mitsuba 3 scene dict (variant
`scalar_rgb`, `path` integrator, unlimited depth). Both are rendered at 64x48 in K independent
runs (our `--seed`, Mitsuba's `seed`); the script compares the image mean and the means of a 3x3
grid of blocks, with the standard error of each mean from the spread over the runs, and prints a
table. A region mismatches when it differs by more than 4 standard errors *and* by more than 2 %
of the image mean (a region that is black in both always matches). Block means cannot see a
fine pattern that is shifted or inverted, so the mean absolute per-pixel difference is also
compared with what the noise alone gives: a case mismatches when it is over 1.5 times that and
over 1 % of the image mean.

Run from the repository root after `cargo build --release`:

    python3 -m venv .venv && .venv/bin/pip install mitsuba numpy
    .venv/bin/python tools/reference/conformance.py                 # every case
    .venv/bin/python tools/reference/conformance.py point spot_hard  # some cases (name prefixes)
    .venv/bin/python tools/reference/conformance.py --list

Options: `--runs K` (4), `--ours-spp N` per run (64; light-only cases also render with `sppm`),
`--mitsuba-spp N` per run (256), `--keep DIR` to keep the scenes and images.

The model mapping of every case is written beside its scene (and in README.md); the cases that
differ by a documented convention are marked `convention` and expected to differ.
"""
import argparse
import math
import os
import subprocess
import sys
import tempfile

import mitsuba as mi
import numpy as np

mi.set_variant('scalar_rgb')

W, H = 64, 48
T = mi.ScalarTransform4f
BIN = os.environ.get('SPPM_LANG', 'target/release/sppm-lang')


# ---------------------------------------------------------------- Mitsuba helpers

def rgb(v):
    if isinstance(v, (int, float)):
        v = [v, v, v]
    return {'type': 'rgb', 'value': list(v)}


def lambert(c):
    """Our diffuse is two-sided Lambertian."""
    return {'type': 'twosided', 'bsdf': {'type': 'diffuse', 'reflectance': rgb(c) if not isinstance(c, dict) else c}}


BLACK = {'type': 'diffuse', 'reflectance': rgb(0.0)}


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def norm(a):
    n = math.sqrt(sum(x * x for x in a))
    return [x / n for x in a]


def columns(u, v, n, c):
    return T([[u[0], v[0], n[0], c[0]], [u[1], v[1], n[1], c[1]], [u[2], v[2], n[2], c[2]],
              [0, 0, 0, 1]])


def quad(corner, eu, ev, **kw):
    """Our `quad { corner, eu, ev }`: Mitsuba's `rectangle` ([-1,1]^2, normal +z) mapped onto
    it, normal eu x ev. Mitsuba's rectangle uv is (x+1)/2, (y+1)/2 like ours along eu, ev."""
    c = [corner[i] + 0.5 * eu[i] + 0.5 * ev[i] for i in range(3)]
    n = norm(cross(eu, ev))
    return dict(type='rectangle', to_world=columns([x / 2 for x in eu], [x / 2 for x in ev], n, c), **kw)


def frame_of(n):
    """Two tangents t, b with t x b = n."""
    n = norm(n)
    a = [1, 0, 0] if abs(n[0]) < 0.9 else [0, 1, 0]
    t = norm(cross(a, n))
    b = cross(n, t)
    return t, b, n


def disk(c, n, r, **kw):
    t, b, n = frame_of(n)
    return dict(type='disk', to_world=columns([r * x for x in t], [r * x for x in b], n, c), **kw)


def sphere(c, r, **kw):
    return dict(type='sphere', center=list(c), radius=r, **kw)


def camera(loc, at, fov=40.0, up=(0, 1, 0), width=W, height=H, **lens):
    kind = 'thinlens' if lens else 'perspective'
    return {'type': kind, 'fov': fov, 'fov_axis': 'y',
            'to_world': T().look_at(origin=list(loc), target=list(at), up=list(up)),
            'sampler': {'type': 'independent'},
            'film': {'type': 'hdrfilm', 'width': width, 'height': height,
                     'rfilter': {'type': 'box'}, 'pixel_format': 'rgb'}, **lens}


def mscene(sensor, **shapes):
    return {'type': 'scene', 'integrator': {'type': 'path', 'max_depth': -1},
            'sensor': sensor, **shapes}


def vec(v):
    return '<' + ', '.join(f'{x:g}' for x in v) + '>'


# ---------------------------------------------------------------- shared stage

FLOOR_SCN = 'quad { <-3, 0, -3>, <0, 0, 6>, <6, 0, 0>  material { diffuse 0.5 } }  // normal +y\n'
STAGE_CAM = dict(loc=(0, 3, -3.5), at=(0, 0, 0.3), fov=45.0)


def stage_scn(extra, cam=STAGE_CAM, res=(W, H)):
    return (f'settings {{ resolution <{res[0]}, {res[1]}> }}\n'
            f'camera {{ location {vec(cam["loc"])} look_at {vec(cam["at"])} fov {cam["fov"]:g} }}\n'
            + FLOOR_SCN + extra)


def stage_mi(**shapes):
    c = STAGE_CAM
    return mscene(camera(c['loc'], c['at'], c['fov']),
                  floor=quad([-3, 0, -3], [0, 0, 6], [6, 0, 0], bsdf=lambert(0.5)), **shapes)


# ---------------------------------------------------------------- generated assets

def write_assets(d):
    """Asymmetric images and small OBJ files, written into the scratch directory."""
    # 4x2 environment: columns left to right red, yellow, green, blue in the top row, dimmer
    # in the bottom row; u = 0.5 is the border between yellow and green.
    top = [[4, 0.2, 0.2], [3, 3, 0.2], [0.2, 4, 0.2], [0.2, 0.2, 4]]
    env = np.array([top, [[c * 0.25 for c in p] for p in top]], dtype=np.float32)
    env = np.repeat(np.repeat(env, 8, axis=0), 8, axis=1)  # 32x16, nearest and bilinear agree
    mi.Bitmap(env).write(os.path.join(d, 'env.exr'))
    # 2x2 texture: top-left red, top-right green, bottom-left blue, bottom-right white.
    tex = np.array([[[200, 30, 30], [30, 200, 30]], [[30, 30, 200], [230, 230, 230]]],
                   dtype=np.uint8)
    tex = np.repeat(np.repeat(tex, 8, axis=0), 8, axis=1)
    mi.Bitmap(tex, pixel_format=mi.Bitmap.PixelFormat.RGB).write(os.path.join(d, 'tex.png'))
    lin = (tex.astype(np.float32) / 255.0) ** 2.2 * 0.9
    mi.Bitmap(lin.astype(np.float32)).write(os.path.join(d, 'tex.exr'))
    # The documented checker cells of the `checker` case (row 0 of the image on top).
    a, b = [0.8, 0.2, 0.1], [0.1, 0.3, 0.7]
    cells = [[a if (i + (5 - r) + 1) % 2 == 0 else b for i in range(6)] for r in range(6)]
    mi.Bitmap(np.array(cells, dtype=np.float32)).write(os.path.join(d, 'checker.exr'))
    # A unit square in z = 0 with texture coordinates (v = 0 at y = -1, OBJ convention).
    with open(os.path.join(d, 'square.obj'), 'w') as f:
        f.write('v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n'
                'vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n'
                'f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n')
    # A fine sphere (256 x 128) with vertex normals: Mitsuba's analytic sphere takes no
    # non-uniform scale (it keeps a radius), so ellipsoids are compared against this mesh.
    for name, nu, nv in (('fine_n.obj', 256, 128), ('ball_n.obj', 8, 6), ('ball.obj', 8, 6)):
        write_ball(os.path.join(d, name), nu, nv, name.endswith('_n.obj'))
    # Mitsuba has no cone and no torus: fine meshes with their analytic normals stand in.
    write_cone_side(os.path.join(d, 'cone_side.obj'), 0.5, 0.1, 0.9, 512)
    write_torus(os.path.join(d, 'torus.obj'), 0.5, 0.18, 512, 256)


def write_cone_side(path, r0, r1, h, nu):
    """The side of a cone frustum about +y from radius r0 at y = 0 to r1 at y = h, nu quads
    around, with the cone's normals."""
    k = (r1 - r0) / h
    s = math.sqrt(1 + k * k)
    with open(path, 'w') as f:
        for i in range(nu):
            ph = 2 * math.pi * i / nu
            c, sn = math.cos(ph), math.sin(ph)
            for y, r in ((0.0, r0), (h, r1)):
                f.write('v %.7f %.7f %.7f\n' % (r * c, y, r * sn))
                f.write('vn %.7f %.7f %.7f\n' % (c / s, -k / s, sn / s))
        for i in range(nu):
            a, b = 2 * i + 1, 2 * ((i + 1) % nu) + 1
            # Outward winding (counter-clockwise seen from outside).
            f.write(f'f {a}//{a} {a + 1}//{a + 1} {b + 1}//{b + 1}\n')
            f.write(f'f {a}//{a} {b + 1}//{b + 1} {b}//{b}\n')


def write_torus(path, big, small, nu, nv):
    """A torus about +y (major radius big, minor small), nu x nv quads, with its normals."""
    with open(path, 'w') as f:
        for i in range(nu):
            ph = 2 * math.pi * i / nu
            for j in range(nv):
                th = 2 * math.pi * j / nv
                n = (math.cos(th) * math.sin(ph), math.sin(th), math.cos(th) * math.cos(ph))
                ring = big + small * math.cos(th)
                f.write('v %.7f %.7f %.7f\n' % (ring * math.sin(ph), small * math.sin(th), ring * math.cos(ph)))
                f.write('vn %.7f %.7f %.7f\n' % n)
        for i in range(nu):
            for j in range(nv):
                a = i * nv + j + 1
                b = ((i + 1) % nu) * nv + j + 1
                c = i * nv + (j + 1) % nv + 1
                e = ((i + 1) % nu) * nv + (j + 1) % nv + 1
                f.write(f'f {a}//{a} {b}//{b} {e}//{e}\n')
                f.write(f'f {a}//{a} {e}//{e} {c}//{c}\n')


def write_ball(path, nu, nv, with_n):
    """A unit UV sphere of nu x nv cells, with or without vertex normals."""
    verts = []
    for j in range(nv + 1):
        th = math.pi * j / nv
        for i in range(nu):
            ph = 2 * math.pi * i / nu
            verts.append([math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph)])
    faces = []
    for j in range(nv):
        for i in range(nu):
            a, b = j * nu + i, j * nu + (i + 1) % nu
            c, e = a + nu, b + nu
            if j > 0:
                faces.append((a, b, e))
            if j < nv - 1:
                faces.append((a, e, c))
    with open(path, 'w') as f:
        for p in verts:
            f.write('v %.6f %.6f %.6f\n' % tuple(p))
            if with_n:
                f.write('vn %.6f %.6f %.6f\n' % tuple(p))
        for t in faces:
            if with_n:
                f.write('f ' + ' '.join(f'{k + 1}//{k + 1}' for k in t) + '\n')
            else:
                f.write('f ' + ' '.join(str(k + 1) for k in t) + '\n')


# ---------------------------------------------------------------- the cases

CASES = []


def case(name, scn, mitsuba, integrators=('path',), note='', convention=False):
    CASES.append(dict(name=name, scn=scn, mi=mitsuba, integrators=integrators, note=note,
                      convention=convention))


def define_cases(d):
    p = lambda f: os.path.join(d, f)  # noqa: E731

    # Camera: handedness, vertical fov, aspect. Coloured balls at +x (red), +y (green) and +z
    # (blue, behind), lit by a white background.
    axes_scn = ('background rgb 1\n'
                'sphere { <1.2, 0, 0>, 0.35 material { diffuse rgb <0.8, 0.1, 0.1> } }\n'
                'sphere { <0, 0.9, 0>, 0.35 material { diffuse rgb <0.1, 0.8, 0.1> } }\n'
                'sphere { <0.3, -0.3, 1.5>, 0.5 material { diffuse rgb <0.1, 0.1, 0.8> } }\n')
    axes_mi = dict(
        sky={'type': 'constant', 'radiance': rgb(1)},
        r=sphere([1.2, 0, 0], 0.35, bsdf=lambert([0.8, 0.1, 0.1])),
        g=sphere([0, 0.9, 0], 0.35, bsdf=lambert([0.1, 0.8, 0.1])),
        b=sphere([0.3, -0.3, 1.5], 0.5, bsdf=lambert([0.1, 0.1, 0.8])))
    case('camera_axes',
         f'settings {{ resolution <{W}, {H}> }}\ncamera {{ location <0, 0, -5> look_at <0, 0, 0> fov 40 }}\n' + axes_scn,
         mscene(camera((0, 0, -5), (0, 0, 0), 40), **axes_mi), ('path', 'sppm'),
         'background is a uniform infinite light (Mitsuba constant)')
    case('camera_portrait',
         f'settings {{ resolution <{H}, {W}> }}\ncamera {{ location <0, 0, -5> look_at <0, 0, 0> fov 40 }}\n' + axes_scn,
         mscene(camera((0, 0, -5), (0, 0, 0), 40, width=H, height=W), **axes_mi), ('path',),
         'fov is vertical in both (Mitsuba fov_axis y)')
    case('camera_up',
         f'settings {{ resolution <{W}, {H}> }}\ncamera {{ location <0, 0, -5> look_at <0, 0, 0> up <1, 1, 0> fov 40 }}\n' + axes_scn,
         mscene(camera((0, 0, -5), (0, 0, 0), 40, up=(1, 1, 0)), **axes_mi), ('path',),
         'a tilted up vector')

    # Lights.
    case('point_light',
         stage_scn('light { <0.5, 1, 0.3> intensity rgb <10, 8, 6> }\n'),
         stage_mi(l={'type': 'point', 'position': [0.5, 1, 0.3], 'intensity': rgb([10, 8, 6])}),
         ('path', 'sppm'), 'intensity W/sr = Mitsuba point intensity; inverse-square falloff')
    spot_mi = lambda cut, beam: stage_mi(l={  # noqa: E731
        'type': 'spot', 'intensity': rgb(20), 'cutoff_angle': cut, 'beam_width': beam,
        'to_world': T().look_at(origin=[0, 2, 0], target=[0.5, 0, 0.5], up=[0, 0, 1])})
    case('spot_hard',
         stage_scn('spotlight { <0, 2, 0> point_at <0.5, 0, 0.5> intensity rgb 20 angle 30 falloff 29.99 }\n'),
         spot_mi(30, 29.99), ('path', 'sppm'),
         'angle = cutoff_angle (half-angle); no transition band')
    case('spot_soft',
         stage_scn('spotlight { <0, 2, 0> point_at <0.5, 0, 0.5> intensity rgb 20 angle 40 falloff 15 }\n'),
         spot_mi(40, 15), ('path',),
         'ours: smoothstep in cos between falloff and angle (pbrt-v4); Mitsuba: linear in angle',
         convention=True)
    case('area_quad',
         stage_scn('area_light { quad { <-0.4, 1, -0.3>, <0.8, 0, 0>, <0, 0, 0.6> } radiance rgb <4, 3, 2> }\n'),
         stage_mi(l=quad([-0.4, 1, -0.3], [0.8, 0, 0], [0, 0, 0.6], bsdf=BLACK,
                         emitter={'type': 'area', 'radiance': rgb([4, 3, 2])})),
         ('path', 'sppm'), 'one-sided, normal eu x ev = -y (down); the camera sees its black back')
    case('area_quad_two_sided',
         stage_scn('area_light { quad { <-0.4, 1, -0.3>, <0.8, 0, 0>, <0, 0, 0.6> } radiance rgb <4, 3, 2> two_sided }\n'),
         stage_mi(l=quad([-0.4, 1, -0.3], [0.8, 0, 0], [0, 0, 0.6], bsdf=BLACK,
                         emitter={'type': 'area', 'radiance': rgb([4, 3, 2])}),
                  # 1e-4 above the first: coincident rectangles would hide each other's light.
                  l2=quad([-0.4, 1.0001, -0.3], [0, 0, 0.6], [0.8, 0, 0], bsdf=BLACK,
                          emitter={'type': 'area', 'radiance': rgb([4, 3, 2])})),
         ('path', 'sppm'), 'two_sided = two back-to-back Mitsuba rectangles')
    case('area_disk',
         stage_scn('area_light { disk { <0.2, 0.8, 0.2>, <0.3, -1, -0.2>, 0.4 } radiance rgb <3, 4, 5> }\n'),
         stage_mi(l=disk([0.2, 0.8, 0.2], [0.3, -1, -0.2], 0.4, bsdf=BLACK,
                         emitter={'type': 'area', 'radiance': rgb([3, 4, 5])})),
         ('path', 'sppm'), 'one-sided on the given normal')
    case('area_sphere',
         stage_scn('area_light { sphere { <0.3, 0.5, 0.4>, 0.3 } radiance rgb <3, 2, 1> }\n'),
         stage_mi(l=sphere([0.3, 0.5, 0.4], 0.3, bsdf=BLACK,
                           emitter={'type': 'area', 'radiance': rgb([3, 2, 1])})),
         ('path', 'sppm'), 'outward')
    case('background',
         stage_scn('background rgb <0.2, 0.4, 0.8>\nsphere { <0, 0.5, 0.3>, 0.5 material { diffuse 0.8 } }\n'),
         stage_mi(sky={'type': 'constant', 'radiance': rgb([0.2, 0.4, 0.8])},
                  s=sphere([0, 0.5, 0.3], 0.5, bsdf=lambert(0.8))),
         ('path', 'sppm'), 'uniform infinite light = Mitsuba constant')

    # Environment map, seen directly (fov 90 looking +z, then looking +x) and lighting a ball.
    env_mi = {'type': 'envmap', 'filename': p('env.exr')}
    for look, at in (('z', (0, 0, 1)), ('x', (1, 0, 0))):
        case(f'environment_{look}',
             f'settings {{ resolution <{W}, {H}> }}\ncamera {{ location <0, 0, 0> look_at {vec(at)} fov 90 }}\n'
             f'environment {{ image "{p("env.exr")}" }}\n',
             mscene(camera((0, 0, 0), at, 90), env=env_mi), ('path',),
             f'equirectangular orientation, looking along +{look}')
    case('environment_rotate',
         f'settings {{ resolution <{W}, {H}> }}\ncamera {{ location <0, 0, 0> look_at <0, 0, 1> fov 90 }}\n'
         f'environment {{ image "{p("env.exr")}" rotate <0, 60, 0> }}\n',
         mscene(camera((0, 0, 0), (0, 0, 1), 90),
                env=dict(env_mi, to_world=T().rotate([0, 1, 0], 60))), ('path',),
         'rotate <0, 60, 0> = Mitsuba to_world rotate(y, 60)')
    case('environment_lit',
         stage_scn(f'environment {{ image "{p("env.exr")}" }}\nsphere {{ <0, 0.5, 0.3>, 0.5 material {{ diffuse 0.8 }} }}\n'),
         stage_mi(env=env_mi, s=sphere([0, 0.5, 0.3], 0.5, bsdf=lambert(0.8))),
         ('path', 'sppm'), 'lighting by the map')

    # Textures on a square facing the camera, lit by a white background (radiance = albedo).
    face_cam = f'settings {{ resolution <{W}, {H}> }}\ncamera {{ location <0, 0, -3> look_at <0, 0, 0> fov 50 }}\nbackground rgb 1\n'
    face_mi = lambda bsdf_tex, **kw: mscene(  # noqa: E731
        camera((0, 0, -3), (0, 0, 0), 50), sky={'type': 'constant', 'radiance': rgb(1)}, **kw)
    bitmap = lambda f, raw=False: {'type': 'bitmap', 'filename': p(f), 'filter_type': 'nearest', 'raw': raw}  # noqa: E731
    for img in ('png', 'exr'):
        case(f'image_{img}_obj_uv',
             face_cam + f'mesh {{ "{p("square.obj")}" material {{ diffuse texture {{ image "{p("tex." + img)}" }} }} }}\n',
             face_mi(None, m={'type': 'obj', 'filename': p('square.obj'),
                              'bsdf': lambert(bitmap('tex.' + img))}),
             ('path',), f'{img}: sRGB-decoded 8 bit / linear float; OBJ vt (v = 0 at the bottom)')
    # Mitsuba's bitmap reads uv (0, 0) at the image's top-left (its OBJ loader flips v); ours
    # at the bottom-left, as OBJ files and POV-Ray do: on a Mitsuba rectangle v is flipped.
    flip_v = mi.ScalarTransform3f().translate([0, 1]).scale([1, -1])
    case('image_quad_uv',
         face_cam + f'quad {{ <-1, -1, 0>, <2, 0, 0>, <0, 2, 0> material {{ diffuse texture {{ image "{p("tex.png")}" }} }} }}\n',
         face_mi(None, m=quad([-1, -1, 0], [2, 0, 0], [0, 2, 0],
                              bsdf=lambert(dict(bitmap('tex.png'), to_uv=flip_v)))),
         ('path',), "quad uv (0,0) at the corner = image bottom-left; Mitsuba rectangle + bitmap to_uv flipping v")
    # Spherical mapping: our u = 0.5 - atan2(x, -z) / 2pi = atan2(x, z) / 2pi (mod 1), v = 1 at
    # +y. Mitsuba's sphere has u = atan2(y_l, x_l) / 2pi, v = acos(z_l) / pi in its local frame
    # and its bitmap reads v = 0 at the top row: local (x, y, z) = world (z, x, y) matches.
    case('image_spherical',
         face_cam + f'sphere {{ <0, 0, 0>, 1 material {{ diffuse texture {{ image "{p("tex.png")}" map spherical }} }} rotate <0, 30, 0> }}\n',
         face_mi(None, m=dict(type='sphere', bsdf=lambert(bitmap('tex.png')),
                              to_world=T().rotate([0, 1, 0], 30) @ columns([0, 0, 1], [1, 0, 0], [0, 1, 0], [0, 0, 0]))),
         ('path',), 'map spherical on a sphere (turned 30 degrees): image not mirrored seen from outside')
    # Our checker as documented (cubes of 0.5 after `scale 0.5`, colour a in the cube at the
    # origin) drawn into a 6x6 linear image for Mitsuba: the square spans x, y in [-1.5, 1.5]
    # at z = 0.75 (cube row 1), so cell (i, j) from the bottom-left is a when i + j + 1 is even.
    case('image_sphere_uv',
         face_cam + f'sphere {{ <0, 0, 0>, 1 material {{ diffuse texture {{ image "{p("tex.png")}" }} }} rotate <0, 30, 0> }}\n',
         face_mi(None, m=dict(type='sphere', bsdf=lambert(bitmap('tex.png')),
                              to_world=T().rotate([0, 1, 0], 30) @ columns([0, 0, 1], [1, 0, 0], [0, 1, 0], [0, 0, 0]))),
         ('path',), "a sphere's own uv (= map spherical about its centre)")
    case('checker',
         face_cam + 'quad { <-1.5, -1.5, 0.75>, <3, 0, 0>, <0, 3, 0> material { diffuse texture { checker rgb <0.8, 0.2, 0.1>, rgb <0.1, 0.3, 0.7> scale 0.5 } } }\n',
         face_mi(None, m=quad([-1.5, -1.5, 0.75], [3, 0, 0], [0, 3, 0], bsdf=lambert(
             dict(bitmap('checker.exr', raw=True), to_uv=flip_v)))),
         ('path',), 'solid checker of 0.5 cubes on a square at z = 0.75 vs its documented cells as an image')

    # Materials on the stage, lit by a background and a point light.
    lit = 'background rgb <0.3, 0.35, 0.4>\nlight { <-1, 2, -0.5> intensity rgb 6 }\n'
    lit_mi = dict(sky={'type': 'constant', 'radiance': rgb([0.3, 0.35, 0.4])},
                  l={'type': 'point', 'position': [-1, 2, -0.5], 'intensity': rgb(6)},
                  back=quad([-3, 0, 2], [6, 0, 0], [0, 3, 0],
                            bsdf=lambert({'type': 'checkerboard', 'color0': rgb([0.8, 0.2, 0.1]),
                                          'color1': rgb([0.1, 0.3, 0.7]),
                                          'to_uv': mi.ScalarTransform3f().scale([6, 3])})))
    back_scn = 'quad { <-3, 0, 2>, <6, 0, 0>, <0, 3, 0> material { diffuse texture { checker rgb <0.8, 0.2, 0.1>, rgb <0.1, 0.3, 0.7> scale 0.5 translate <0, 0, 0.75> } } }\n'
    mats = {
        'mirror': ('mirror rgb <0.9, 0.8, 0.6>',
                   {'type': 'conductor', 'material': 'none', 'specular_reflectance': rgb([0.9, 0.8, 0.6])}),
        'glass': ('glass ior 1.5',
                  {'type': 'dielectric', 'int_ior': 1.5, 'ext_ior': 1.0}),
        'glass_ior2': ('glass ior 2.2',
                       {'type': 'dielectric', 'int_ior': 2.2, 'ext_ior': 1.0}),
        'glossy': ('glossy rgb <0, 0, 0> specular rgb <0.9, 0.7, 0.5> roughness 0.4',
                   {'type': 'twosided', 'bsdf': {'type': 'principled', 'base_color': rgb([0.9, 0.7, 0.5]),
                                                 'metallic': 1.0, 'roughness': 0.4}}),
        'diffuse': ('diffuse rgb <0.7, 0.5, 0.3>', lambert([0.7, 0.5, 0.3])),
    }
    for name, (ours, theirs) in mats.items():
        case(f'material_{name}',
             stage_scn(lit + back_scn + f'sphere {{ <0, 0.6, 0.2>, 0.6 material {{ {ours} }} }}\n'),
             stage_mi(ball=sphere([0, 0.6, 0.2], 0.6, bsdf=theirs), **lit_mi), ('path',),
             f'{ours}')
    case('material_glass_slab',
         stage_scn(lit + back_scn + 'box { <-0.8, 0.1, -0.2>, <0.8, 1.2, 0.2> rotate <0, 25, 0> material { glass ior 1.5 } }\n'),
         stage_mi(slab={'type': 'cube', 'bsdf': {'type': 'dielectric', 'int_ior': 1.5, 'ext_ior': 1.0},
                        'to_world': T().rotate([0, 1, 0], 25).translate([0, 0.65, 0]).scale([0.8, 0.55, 0.2])},
                  **lit_mi), ('path',), 'a glass box, rotated')

    # Shapes and transforms, diffuse, on the lit stage.
    shape_cases = {
        'shape_cylinder': ('cylinder { <-0.6, 0.1, 0>, <0.6, 0.7, 0.3>, 0.35 material { diffuse 0.7 } }',
                           dict(c={'type': 'cylinder', 'p0': [-0.6, 0.1, 0], 'p1': [0.6, 0.7, 0.3], 'radius': 0.35,
                                   'bsdf': lambert(0.7)},
                                c0=disk([-0.6, 0.1, 0], [-1.2, -0.6, -0.3], 0.35, bsdf=lambert(0.7)),
                                c1=disk([0.6, 0.7, 0.3], [1.2, 0.6, 0.3], 0.35, bsdf=lambert(0.7)))),
        'shape_cylinder_open': ('cylinder { <-0.6, 0.1, 0>, <0.6, 0.7, 0.3>, 0.35 open material { diffuse 0.7 } }',
                                dict(c={'type': 'cylinder', 'p0': [-0.6, 0.1, 0], 'p1': [0.6, 0.7, 0.3], 'radius': 0.35,
                                        'bsdf': lambert(0.7)})),
        'shape_cone': ('cone { <0, 0.1, 0.1>, 0.5, <0, 1.0, 0.1>, 0.1 material { diffuse 0.7 } }',
                       dict(side={'type': 'obj', 'filename': p('cone_side.obj'), 'bsdf': lambert(0.7),
                                  'to_world': T().translate([0, 0.1, 0.1])},
                            c0=disk([0, 0.1, 0.1], [0, -1, 0], 0.5, bsdf=lambert(0.7)),
                            c1=disk([0, 1.0, 0.1], [0, 1, 0], 0.1, bsdf=lambert(0.7)))),
        'shape_cone_open': ('cone { <0, 0.1, 0.1>, 0.5, <0, 1.0, 0.1>, 0.1 open rotate <-25, 0, 0> material { diffuse 0.7 } }',
                            dict(side={'type': 'obj', 'filename': p('cone_side.obj'), 'bsdf': lambert(0.7),
                                       'to_world': T().rotate([1, 0, 0], -25).translate([0, 0.1, 0.1])})),
        'shape_torus': ('torus { 0.5, 0.18 rotate <60, 0, 0> translate <0, 0.6, 0.2> material { diffuse 0.7 } }',
                        dict(t={'type': 'obj', 'filename': p('torus.obj'), 'bsdf': lambert(0.7),
                                'to_world': T().translate([0, 0.6, 0.2]).rotate([1, 0, 0], 60)})),
        'shape_disk': ('disk { <0, 0.6, 0.3>, <0.2, 0.5, -1>, 0.6 material { diffuse 0.7 } }',
                       dict(dk=disk([0, 0.6, 0.3], [0.2, 0.5, -1], 0.6, bsdf=lambert(0.7)))),
        'shape_box': ('box { <-0.5, 0, -0.4>, <0.7, 0.9, 0.5> material { diffuse 0.7 } }',
                      dict(bx={'type': 'cube', 'bsdf': lambert(0.7),
                               'to_world': T().translate([0.1, 0.45, 0.05]).scale([0.6, 0.45, 0.45])})),
        'transform_box': ('box { <-0.5, -0.5, -0.5>, <0.5, 0.5, 0.5> scale <1.2, 0.5, 0.3> rotate <30, 45, 10> translate <0.3, 0.6, 0.2> material { diffuse 0.7 } }',
                          dict(bx={'type': 'cube', 'bsdf': lambert(0.7),
                                   'to_world': T().translate([0.3, 0.6, 0.2]).rotate([0, 0, 1], 10)
                                   .rotate([0, 1, 0], 45).rotate([1, 0, 0], 30).scale([0.6, 0.25, 0.15])})),
        'transform_ellipsoid': ('sphere { <0, 0, 0>, 1 scale <0.7, 0.3, 0.4> rotate <0, 0, 30> translate <0, 0.6, 0.2> material { diffuse 0.7 } }',
                                dict(e={'type': 'obj', 'filename': p('fine_n.obj'), 'bsdf': lambert(0.7),
                                        'to_world': T().translate([0, 0.6, 0.2]).rotate([0, 0, 1], 30).scale([0.7, 0.3, 0.4])})),
        'mesh_normals': (f'mesh {{ "{p("ball_n.obj")}" scale 0.6 translate <0, 0.6, 0.2> material {{ diffuse 0.7 }} }}',
                         dict(m={'type': 'obj', 'filename': p('ball_n.obj'), 'bsdf': lambert(0.7),
                                 'to_world': T().translate([0, 0.6, 0.2]).scale(0.6)})),
        'mesh_flat': (f'mesh {{ "{p("ball.obj")}" scale 0.6 translate <0, 0.6, 0.2> material {{ diffuse 0.7 }} }}',
                      dict(m={'type': 'obj', 'filename': p('ball.obj'), 'bsdf': lambert(0.7), 'face_normals': True,
                              'to_world': T().translate([0, 0.6, 0.2]).scale(0.6)})),
    }
    for name, (ours, theirs) in shape_cases.items():
        case(name, stage_scn(lit + back_scn + ours + '\n'), stage_mi(**dict(lit_mi, **theirs)), ('path',), ours.split('{')[0].strip())

    # Depth of field: balls at three depths, focus on the middle one.
    dof_scn = (f'settings {{ resolution <{W}, {H}> }}\n'
               'camera { location <0, 0.5, -4> look_at <0, 0.5, 0> fov 35 aperture 0.15 focus_distance 4 }\n'
               'background rgb 1\n'
               'sphere { <-0.8, 0.5, -2>, 0.3 material { diffuse rgb <0.8, 0.1, 0.1> } }\n'
               'sphere { <0, 0.5, 0>, 0.3 material { diffuse rgb <0.1, 0.8, 0.1> } }\n'
               'sphere { <0.9, 0.5, 3>, 0.3 material { diffuse rgb <0.1, 0.1, 0.8> } }\n'
               'quad { <-4, 0, -4>, <0, 0, 12>, <8, 0, 0> material { diffuse texture { checker rgb 0.9, rgb 0.1 scale 0.5 } } }\n')
    dof_mi = mscene(camera((0, 0.5, -4), (0, 0.5, 0), 35, aperture_radius=0.15, focus_distance=4.0),
                    sky={'type': 'constant', 'radiance': rgb(1)},
                    a=sphere([-0.8, 0.5, -2], 0.3, bsdf=lambert([0.8, 0.1, 0.1])),
                    b=sphere([0, 0.5, 0], 0.3, bsdf=lambert([0.1, 0.8, 0.1])),
                    c=sphere([0.9, 0.5, 3], 0.3, bsdf=lambert([0.1, 0.1, 0.8])),
                    f=quad([-4, 0, -4], [0, 0, 12], [8, 0, 0], bsdf=lambert(
                        {'type': 'checkerboard', 'color0': rgb(0.9), 'color1': rgb(0.1),
                         'to_uv': mi.ScalarTransform3f().translate([0, 0]).scale([12, 8])})))
    case('camera_dof', dof_scn, dof_mi, ('path',),
         'aperture = thinlens aperture_radius; focus_distance along the view axis')


# ---------------------------------------------------------------- rendering and comparing

def load_exr(path):
    return np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]


def regions(img):
    """Image mean, then a 3x3 grid of block means (row-major from the top left)."""
    h, w = img.shape[:2]
    out = [img.mean(axis=(0, 1))]
    for j in range(3):
        for i in range(3):
            out.append(img[j * h // 3:(j + 1) * h // 3, i * w // 3:(i + 1) * w // 3].mean(axis=(0, 1)))
    return np.array(out)  # (10, 3): region, channel


def render_ours(c, integrator, d, runs, spp):
    scn = os.path.join(d, c['name'] + '.scn')
    with open(scn, 'w') as f:
        f.write(c['scn'])
    res = []
    for k in range(runs):
        out = os.path.join(d, f'{c["name"]}.{integrator}.{k}.exr')
        cmd = [BIN, 'render', scn, '--integrator', integrator, '--iterations', str(spp),
               '--seed', str(100 + k), '-o', out]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit(f'{c["name"]}: our render failed:\n{r.stderr}')
        res.append(load_exr(out))
    return res


def render_mitsuba(c, d, runs, spp):
    sc = mi.load_dict(c['mi'])
    res = []
    for k in range(runs):
        img = np.array(mi.render(sc, spp=spp, seed=1000 + k), dtype=np.float64)[..., :3]
        res.append(img)
    mi.Bitmap(np.mean(res, axis=0).astype(np.float32)).write(os.path.join(d, c['name'] + '.mitsuba.exr'))
    return res


def stats(imgs):
    r = np.array([regions(i) for i in imgs])
    return r.mean(axis=0), r.std(axis=0, ddof=1) / math.sqrt(len(imgs))


def pixel_error(ours, theirs):
    """Mean absolute per-pixel difference of the two mean images, and what noise alone would
    give (E|N(0, s)| = s sqrt(2 / pi) with s from each pixel's run-to-run spread): a block mean
    cannot see a fine pattern that is shifted or inverted (a checker), this can."""
    o, t = np.array(ours), np.array(theirs)
    var = o.var(axis=0, ddof=1) / len(o) + t.var(axis=0, ddof=1) / len(t)
    err = np.abs(o.mean(axis=0) - t.mean(axis=0)).mean()
    return err, (np.sqrt(var) * math.sqrt(2 / math.pi)).mean()


def compare(a, b):
    (ma, sa), (mb, sb) = a, b
    se = np.sqrt(sa ** 2 + sb ** 2) + 1e-4 * max(mb[0].mean(), 1e-6)  # floor: Mitsuba has no noise on a bare environment
    z = np.abs(ma - mb) / se
    rel = np.abs(ma - mb) / max(mb[0].mean(), 1e-6)
    bad = ((z > 4) & (rel > 0.02)).any(axis=1)
    return z.max(axis=1), rel.max(axis=1), bad


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('cases', nargs='*')
    ap.add_argument('--runs', type=int, default=4)
    ap.add_argument('--ours-spp', type=int, default=64)
    ap.add_argument('--mitsuba-spp', type=int, default=256)
    ap.add_argument('--keep')
    ap.add_argument('--list', action='store_true')
    a = ap.parse_args()
    d = a.keep or tempfile.mkdtemp(prefix='conformance-')
    os.makedirs(d, exist_ok=True)
    write_assets(d)
    define_cases(d)
    if a.list:
        for c in CASES:
            print(f'{c["name"]:24s} {c["note"]}')
        return
    chosen = [c for c in CASES if not a.cases or any(c['name'].startswith(x) for x in a.cases)]
    summary = []
    for c in chosen:
        theirs_imgs = render_mitsuba(c, d, a.runs, a.mitsuba_spp)
        theirs = stats(theirs_imgs)
        for integ in c['integrators']:
            ours_imgs = render_ours(c, integ, d, a.runs, a.ours_spp)
            ours = stats(ours_imgs)
            z, rel, bad = compare(ours, theirs)
            perr, pnoise = pixel_error(ours_imgs, theirs_imgs)
            pixel_bad = perr > 1.5 * pnoise and perr > 0.01 * theirs[0][0].mean()
            verdict = 'ok' if not (bad.any() or pixel_bad) else ('convention' if c['convention'] else 'MISMATCH')
            print(f'\n{c["name"]} [{integ}]  {c["note"]}')
            print('  region  ours (r, g, b)           mitsuba (r, g, b)        max|diff|  max z')
            labels = ['image'] + [f'r{j}c{i}' for j in range(3) for i in range(3)]
            for k, lab in enumerate(labels):
                flag = '  <--' if bad[k] else ''
                o = ' '.join(f'{x:7.4f}' for x in ours[0][k])
                t = ' '.join(f'{x:7.4f}' for x in theirs[0][k])
                print(f'  {lab:6s} {o}  {t}  {100 * rel[k]:6.2f}%  {z[k]:5.1f}{flag}')
            print(f'  per pixel: mean |diff| {perr:.4f}, from noise alone {pnoise:.4f}'
                  f'{"  <--" if pixel_bad else ""}')
            print(f'  verdict: {verdict}', flush=True)
            summary.append((c['name'], integ, ours[0][0].mean(), theirs[0][0].mean(), rel.max(), z.max(),
                            perr / max(pnoise, 1e-9), verdict))
    print('\nfeature                  method  ours mean  mitsuba  max|diff|/mean  max z  pixel/noise  verdict')
    for n, i, o, t, r, z, pr, v in summary:
        print(f'{n:24s} {i:6s} {o:9.4f} {t:9.4f} {100 * r:9.2f}%   {z:7.1f}  {pr:7.2f}      {v}')
    print(f'\nscenes and images: {d}')


if __name__ == '__main__':
    main()
