"""The material reference: rows of spheres, one material per row at several roughnesses,
rendered by Mitsuba 3 (scalar_rgb), with our scene written from the same table.

Run from the repository root:
    python3 -m venv /tmp/venv && /tmp/venv/bin/pip install mitsuba numpy
    /tmp/venv/bin/python tools/reference/materials.py            # scene, mask and reference
    /tmp/venv/bin/python tools/reference/materials.py --scene-only   # materials.scn and mask

It writes three files beside itself:
- `materials.scn`: our scene, generated from ROWS (never edit it by hand);
- `materials.mask.exr`: per pixel, 1 + the index of the sphere (row-major, as in
  `materials.labels`) whose inner disc (0.8 of the radius) the pixel centre's ray meets, else 0;
  `tests/accuracy/glossy_reference.rs` averages each sphere over these pixels;
- `materials.labels`: one line per sphere, `<row> <roughness>`;
- `materials.exr`: the Mitsuba render (linear RGB float, box filter).

Adding a row: append a `Row` to ROWS with the material in our syntax and the Mitsuba BSDF dict
as functions of the roughness, re-run the script (about a minute of Mitsuba per 1024 spp per
row on two cores), and commit the four files; the test picks the new spheres up from the
labels. The mapping of parameters belongs in README.md beside this file.
"""
import argparse
import math
import os
from dataclasses import dataclass
from typing import Callable

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))

WIDTH, HEIGHT = 160, 120
FOV = 24.0  # vertical, degrees
EYE = (0.0, 0.0, 8.0)
TARGET = (0.0, 0.0, 0.0)
RADIUS = 0.4
PITCH = 1.0  # distance between sphere centres
ROUGHNESS = [0.0, 0.2, 0.45, 0.8]
# A uniform sky and a rectangle light above, in front of the spheres, facing down.
SKY = 0.5
LIGHT_RADIANCE = 6.0
LIGHT = dict(corner=(-1.5, 3.0, 1.0), edge_u=(3.0, 0.0, 0.0), edge_v=(0.0, 0.0, 3.0))
MASK_SHRINK = 0.8

# Named metals as src/scene/metals.rs holds them (eta, k per RGB channel).
METALS = {
    'Au': ([0.18267, 0.49447, 1.3761], [3.1178, 2.3515, 1.8324]),
    'Cu': ([0.23268, 1.075714, 1.15753], [3.5315, 2.5945, 2.4473]),
}


def rgb(value):
    return {'type': 'rgb', 'value': list(value)}


def vec(v):
    return '<' + ', '.join(f'{x:g}' for x in v) + '>'


@dataclass
class Row:
    """One row of spheres: `ours(r)` is the body of our `material { }` at parameter r (the
    roughness unless the row says otherwise: an index, a weight), `mitsuba(r)` the Mitsuba BSDF
    dict. A sphere's label is `<name> <r>`."""
    name: str
    ours: Callable[[float], str]
    mitsuba: Callable[[float], dict]
    roughness: tuple = tuple(ROUGHNESS)


PLASTIC_BASE = (0.7, 0.15, 0.1)


def coated_ours(r):
    rough = f' roughness {r:g}' if r > 0 else ''
    return f'coated rgb {vec(PLASTIC_BASE)} ior 1.5{rough}'


def coated_mitsuba(r):
    # Mitsuba's ext_ior defaults to air (1.000277), int_ior to polypropylene (1.49). Ours
    # dims the light bouncing between base and coat by the base's colour at each round:
    # Mitsuba's `nonlinear`.
    common = {'int_ior': 1.5, 'ext_ior': 1.0, 'nonlinear': True,
              'diffuse_reflectance': rgb(PLASTIC_BASE)}
    if r == 0:
        return {'type': 'plastic', **common}
    return {'type': 'roughplastic', 'distribution': 'ggx', 'alpha': r * r, **common}


def conductor_ours(metal):
    def ours(r):
        return f'conductor "{metal}" roughness {r:g}'
    return ours


def conductor_mitsuba(metal):
    eta, k = METALS[metal]

    def mitsuba(r):
        if r == 0:
            return {'type': 'conductor', 'eta': rgb(eta), 'k': rgb(k)}
        return {'type': 'roughconductor', 'distribution': 'ggx', 'alpha': r * r,
                'eta': rgb(eta), 'k': rgb(k)}
    return mitsuba


ROWS = [
    Row('coated', coated_ours, coated_mitsuba),
    Row('Au', conductor_ours('Au'), conductor_mitsuba('Au')),
    Row('Cu', conductor_ours('Cu'), conductor_mitsuba('Cu')),
]


def frosted_ours(r):
    rough = f' roughness {r:g}' if r > 0 else ''
    return f'glass ior 1.5{rough}'


def frosted_mitsuba(r):
    if r == 0:
        return {'type': 'dielectric', 'int_ior': 1.5, 'ext_ior': 1.0}
    return {'type': 'roughdielectric', 'distribution': 'ggx', 'alpha': r * r,
            'int_ior': 1.5, 'ext_ior': 1.0}


THIN_IOR = (1.2, 1.5, 2.5, 4.0)


def thin_ours(ior):
    return f'glass thin ior {ior:g}'


def thin_mitsuba(ior):
    return {'type': 'thindielectric', 'int_ior': ior, 'ext_ior': 1.0}


BLEND_WEIGHT = (0.1, 0.3, 0.6, 0.9)
BLEND_METAL_ROUGHNESS = 0.2


def blend_ours(w):
    return (f'blend material {{ diffuse rgb {vec(PLASTIC_BASE)} }}, '
            f'material {{ conductor "Au" roughness {BLEND_METAL_ROUGHNESS:g} }} weight {w:g}')


def blend_mitsuba(w):
    metal = conductor_mitsuba('Au')(BLEND_METAL_ROUGHNESS)
    return {'type': 'blendbsdf', 'weight': w,
            'bsdf_0': {'type': 'diffuse', 'reflectance': rgb(PLASTIC_BASE)},
            'bsdf_1': metal}


# The second sheet: materials that pass light, and a blend. A striped floor below gives the
# glass something to refract (in a uniform sky a clear lossless sphere shows the sky's own
# radiance whatever its model).
GLASS_ROWS = [
    Row('frosted', frosted_ours, frosted_mitsuba),
    Row('thin', thin_ours, thin_mitsuba, roughness=THIN_IOR),
    Row('blend', blend_ours, blend_mitsuba, roughness=BLEND_WEIGHT),
]

# The third sheet: bumps. An image height map on flat tiles (a quad's uv is affine, the same in
# both renderers; a sphere's `v` rate is not: ours moves `v` at the rate of `u`). The height is
# `bump_height.png`, written by this script: a 64 x 64 grey image of
# 0.5 + 0.5 sin(2 pi 2 u) sin(2 pi 2 v), 8 bits, read linearly and bilinearly by both. Ours:
# `normal { texture { image ... linear interpolate map uv } amount a }`; Mitsuba: `bumpmap`
# with `scale` a over a `bitmap` (`raw`, bilinear, the v flip of README.md). Both lean the
# normal to `n - a grad h` (the height's gradient per world unit): the same perturbed normal.
# The parameter is the amount: the steepest lean on a tile (0.8 wide) is atan(a 2 pi / 0.8).
BUMP_IMAGE = 'bump_height.png'
BUMP_TEXELS = 64
BUMP_PERIODS = 2
BUMP_AMOUNT = (0.02, 0.06, 0.2, 0.6)
BUMP_DIFFUSE = (0.8, 0.8, 0.8)


def bump_heights():
    """The height image's rows, top row first (8-bit values)."""
    c = (np.arange(BUMP_TEXELS) + 0.5) / BUMP_TEXELS
    u, v = np.meshgrid(c, c[::-1])
    h = 0.5 + 0.5 * np.sin(2 * np.pi * BUMP_PERIODS * u) * np.sin(2 * np.pi * BUMP_PERIODS * v)
    return np.round(h * 255).astype(np.uint8)


def bumped_ours(body):
    def ours(a):
        return (f'{body} normal {{ texture {{ image "{BUMP_IMAGE}" linear interpolate map uv }} '
                f'amount {a:g} }}')
    return ours


def bumped_mitsuba(bsdf):
    def mitsuba(a):
        import mitsuba as mi
        flip = mi.ScalarTransform4f().translate([0, 1, 0]).scale([1, -1, 1])
        return {'type': 'bumpmap', 'scale': a,
                'arg': {'type': 'bitmap', 'filename': os.path.join(HERE, BUMP_IMAGE),
                        'raw': True, 'filter_type': 'bilinear', 'wrap_mode': 'repeat',
                        'to_uv': flip},
                'bsdf': bsdf}
    return mitsuba


BUMP_ROWS = [
    Row('bumped diffuse', bumped_ours(f'diffuse rgb {vec(BUMP_DIFFUSE)}'),
        bumped_mitsuba({'type': 'diffuse', 'reflectance': rgb(BUMP_DIFFUSE)}),
        roughness=BUMP_AMOUNT),
    Row('bumped Au', bumped_ours(conductor_ours('Au')(0.2)),
        bumped_mitsuba(conductor_mitsuba('Au')(0.2)), roughness=BUMP_AMOUNT),
]

# Floor: stripes of width 1 along z (alternating reflectance), at FLOOR_Y, facing up.
FLOOR_Y = -1.6
FLOOR_HALF = 6
FLOOR_SHADES = (0.8, 0.2)


@dataclass
class Sheet:
    """A scene of rows: its files are `<name>.scn`, `<name>.exr`, `<name>.mask.exr` and
    `<name>.labels` beside this script."""
    name: str
    rows: list
    floor: bool = False
    # Square tiles (TILE wide, leaning TILE_LEAN degrees back toward the light) instead of
    # spheres.
    tiles: bool = False


SHEETS = {
    'materials': Sheet('materials', ROWS),
    'glass_blend': Sheet('glass_blend', GLASS_ROWS, floor=True),
    'bumps': Sheet('bumps', BUMP_ROWS, tiles=True),
}

TILE = 0.8
TILE_LEAN = 30.0


def tile_edges(c):
    """(corner, edge_u, edge_v) of the tile centred at `c`: u along x, v up the tile, the
    normal u x v toward the camera and up."""
    lean = math.radians(TILE_LEAN)
    eu = np.array([TILE, 0.0, 0.0])
    ev = TILE * np.array([0.0, math.cos(lean), -math.sin(lean)])
    corner = np.array(c) - (eu + ev) / 2
    return corner, eu, ev


def floor_stripes():
    """(corner, edge_u, edge_v, shade) of each floor stripe; edge_u x edge_v points up."""
    out = []
    for i, z in enumerate(range(-FLOOR_HALF, FLOOR_HALF)):
        out.append(((-FLOOR_HALF, FLOOR_Y, z), (0, 0, 1), (2 * FLOOR_HALF, 0, 0),
                    FLOOR_SHADES[i % 2]))
    return out


def spheres(sheet):
    """(label, centre, row, parameter) of every sphere: rows top to bottom, parameter left to
    right."""
    out = []
    n_rows = len(sheet.rows)
    for i, row in enumerate(sheet.rows):
        y = PITCH * ((n_rows - 1) / 2 - i)
        n = len(row.roughness)
        for j, r in enumerate(row.roughness):
            x = PITCH * (j - (n - 1) / 2)
            out.append((f'{row.name} {r:g}', (x, y, 0.0), row, r))
    return out


def write_scene(sheet, path):
    n = sheet.name
    what = ('rows of spheres, one material per row at several roughnesses'
            if not sheet.floor else
            'rows of spheres, one material per row at several parameters, over a striped floor')
    if sheet.tiles:
        what = 'rows of tiles, one material per row at several bump amounts'
    lines = [
        f'// {n}.scn: written by tools/reference/materials.py (do not edit; edit its rows there).',
        f'// {what[0].upper() + what[1:]},',
        '// under a uniform sky and a rectangle light; tools/reference/'
        f'{n}.exr is the same scene in Mitsuba 3.',
        '',
        f'settings {{ resolution <{WIDTH}, {HEIGHT}>  iterations 64  seed 1 }}',
        f'camera   {{ location {vec(EYE)}  look_at {vec(TARGET)}  up <0, 1, 0>  fov {FOV:g} }}',
        f'background rgb {SKY:g}',
        f'area_light {{ quad {{ {vec(LIGHT["corner"])}, {vec(LIGHT["edge_u"])}, '
        f'{vec(LIGHT["edge_v"])} }}  radiance rgb {LIGHT_RADIANCE:g} }}',
        '',
    ]
    if sheet.name == 'materials':
        # The first sheet's scene text predates the other sheets: keep it byte for byte.
        lines[0:3] = [
            '// materials.scn: written by tools/reference/materials.py (do not edit; edit ROWS there).',
            '// Rows of spheres, one material per row at several roughnesses, under a uniform sky',
            '// and a rectangle light; tools/reference/materials.exr is the same scene in Mitsuba 3.',
        ]
    if sheet.floor:
        for c, u, v, shade in floor_stripes():
            lines.append(f'quad {{ {vec(c)}, {vec(u)}, {vec(v)}  material {{ diffuse rgb {shade:g} }} }}')
        lines.append('')
    for label, c, row, r in spheres(sheet):
        if sheet.tiles:
            corner, eu, ev = tile_edges(c)
            lines.append(f'quad {{ {vec(corner)}, {vec(eu)}, {vec(ev)}  '
                         f'material {{ {row.ours(r)} }} }}  // {label}')
            continue
        lines.append(f'sphere {{ {vec(c)}, {RADIUS:g}  material {{ {row.ours(r)} }} }}  // {label}')
    with open(path, 'w') as f:
        f.write('\n'.join(lines) + '\n')


def camera_rays():
    """Unit directions through every pixel centre, shape (HEIGHT, WIDTH, 3)."""
    eye, target = np.array(EYE), np.array(TARGET)
    fwd = target - eye
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    t = math.tan(math.radians(FOV) / 2)
    xs = ((np.arange(WIDTH) + 0.5) / WIDTH * 2 - 1) * t * WIDTH / HEIGHT
    ys = (1 - (np.arange(HEIGHT) + 0.5) / HEIGHT * 2) * t
    d = fwd + xs[None, :, None] * right + ys[:, None, None] * up
    return d / np.linalg.norm(d, axis=2, keepdims=True)


def mask(sheet):
    d = camera_rays()
    eye = np.array(EYE)
    out = np.zeros((HEIGHT, WIDTH), dtype=np.float32)
    for k, (_, c, _, _) in enumerate(spheres(sheet)):
        if sheet.tiles:
            # The inner square (MASK_SHRINK of the side) of the tile.
            corner, eu, ev = tile_edges(c)
            n = np.cross(eu, ev)
            t = ((corner - eye) @ n) / (d @ n)
            p = eye + t[..., None] * d - corner
            a, b = (p @ eu) / (eu @ eu), (p @ ev) / (ev @ ev)
            lo, hi = (1 - MASK_SHRINK) / 2, (1 + MASK_SHRINK) / 2
            out[(t > 0) & (a > lo) & (a < hi) & (b > lo) & (b < hi)] = k + 1
            continue
        oc = eye - np.array(c)
        b = d @ oc
        disc = b * b - (oc @ oc - (MASK_SHRINK * RADIUS) ** 2)
        out[disc > 0] = k + 1
    return out


def rectangle_to_world(mi, c, u, v):
    """`rectangle` is [-1,1]^2 in local xy with normal +z: columns u/2, v/2, n, centre."""
    c, u, v = (np.array(x, dtype=float) for x in (c, u, v))
    n = np.cross(u, v)
    n /= np.linalg.norm(n)
    centre = c + (u + v) / 2
    return mi.ScalarTransform4f([
        [u[0] / 2, v[0] / 2, n[0], centre[0]],
        [u[1] / 2, v[1] / 2, n[1], centre[1]],
        [u[2] / 2, v[2] / 2, n[2], centre[2]],
        [0, 0, 0, 1],
    ])


def mitsuba_scene(sheet, spp):
    import mitsuba as mi
    black = {'type': 'diffuse', 'reflectance': rgb([0.0, 0.0, 0.0])}
    to_world = rectangle_to_world(mi, *(LIGHT[k] for k in ('corner', 'edge_u', 'edge_v')))
    d = {
        'type': 'scene',
        'integrator': {'type': 'path', 'max_depth': -1},
        'sensor': {
            'type': 'perspective', 'fov': FOV, 'fov_axis': 'y',
            'to_world': mi.ScalarTransform4f().look_at(origin=EYE, target=TARGET, up=[0, 1, 0]),
            'sampler': {'type': 'independent', 'sample_count': spp},
            'film': {'type': 'hdrfilm', 'width': WIDTH, 'height': HEIGHT,
                     'rfilter': {'type': 'box'}, 'pixel_format': 'rgb',
                     'component_format': 'float32'},
        },
        'sky': {'type': 'constant', 'radiance': rgb([SKY] * 3)},
        'light': {'type': 'rectangle', 'to_world': to_world, 'bsdf': black,
                  'emitter': {'type': 'area', 'radiance': rgb([LIGHT_RADIANCE] * 3)}},
    }
    if sheet.floor:
        for k, (c, u, v, shade) in enumerate(floor_stripes()):
            d[f'floor{k}'] = {'type': 'rectangle', 'to_world': rectangle_to_world(mi, c, u, v),
                              'bsdf': {'type': 'twosided', 'bsdf': {
                                  'type': 'diffuse', 'reflectance': rgb([shade] * 3)}}}
    for k, (_, c, row, r) in enumerate(spheres(sheet)):
        if sheet.tiles:
            d[f'tile{k}'] = {'type': 'rectangle', 'to_world': rectangle_to_world(mi, *tile_edges(c)),
                             'bsdf': row.mitsuba(r)}
            continue
        d[f'sphere{k}'] = {'type': 'sphere', 'center': list(c), 'radius': RADIUS,
                           'bsdf': row.mitsuba(r)}
    return d


def write_mask_and_labels(sheet):
    import mitsuba as mi
    m = mask(sheet)
    mi.Bitmap(np.repeat(m[:, :, None], 3, axis=2)).write(
        os.path.join(HERE, f'{sheet.name}.mask.exr'))
    with open(os.path.join(HERE, f'{sheet.name}.labels'), 'w') as f:
        for label, *_ in spheres(sheet):
            f.write(label + '\n')


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--spp', type=int, default=8192)
    ap.add_argument('--chunk', type=int, default=512, help='spp per run (runs are averaged)')
    ap.add_argument('--scene-only', action='store_true')
    ap.add_argument('--sheet', choices=sorted(SHEETS), default='materials')
    ap.add_argument('--out', help='default: <sheet>.exr beside this script')
    a = ap.parse_args()
    sheet = SHEETS[a.sheet]
    out = a.out or os.path.join(HERE, f'{sheet.name}.exr')
    import mitsuba as mi
    mi.set_variant('scalar_rgb')
    if sheet.tiles:
        mi.Bitmap(bump_heights()).write(os.path.join(HERE, BUMP_IMAGE))
    write_scene(sheet, os.path.join(HERE, f'{sheet.name}.scn'))
    write_mask_and_labels(sheet)
    if a.scene_only:
        return
    runs = max(1, a.spp // a.chunk)
    sc = mi.load_dict(mitsuba_scene(sheet, a.chunk))
    acc = None
    for i in range(runs):
        img = np.array(mi.render(sc, spp=a.chunk, seed=1000 + i))
        acc = img if acc is None else acc + img
        print(f'run {i + 1}/{runs}', flush=True)
    img = (acc / runs).astype(np.float32)
    mi.Bitmap(img).write(out)
    m = mask(sheet)
    for k, (label, *_) in enumerate(spheres(sheet)):
        sel = m == k + 1
        mean = img[sel].mean(axis=0)
        print(f'{label:>12}: {sel.sum():4d} px, mean {mean[0]:.4f} {mean[1]:.4f} {mean[2]:.4f}')
    print(f'wrote {out} ({runs * a.chunk} spp)')


if __name__ == '__main__':
    main()
