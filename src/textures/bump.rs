//! Bump and normal maps: the height a [`Normal`] gives at a point, its slopes by central
//! differences, and the normal that a normal map's texel stands for.
//!
//! Heights are differenced in the object's space along the shading frame's two tangents (the
//! shape's `dpdu` and the normal crossed with it), so every pattern and mapping works alike;
//! a uv-mapped texture moves its `(u, v)` by the same steps, `v` at the rate of `u` (shapes
//! give `dpdu` only). The step is a thousandth of the pattern's unit, and never below the
//! precision of the point's coordinates.

use glam::{DAffine3, Vec2, Vec3A};

use super::{TexCoord, evaluate, evaluate_scalar, noise};
use crate::scene::{Normal, NormalKind, Texture};

/// A difference step in the pattern's space.
const STEP: f32 = 1e-3;

/// The height of `normal` at `at` (a built-in pattern, or a texture's luminance); zero for a
/// normal map or a texture the scene does not have.
pub fn height(normal: &Normal, textures: &[Texture], at: &TexCoord) -> f32 {
    let q = normal.transform.transform_point3(at.p.as_dvec3());
    let (x, y, z) = (q.x, q.y, q.z);
    let h = match normal.kind {
        NormalKind::Height(t) => {
            let at = TexCoord {
                p: q.as_vec3a(),
                ..*at
            };
            return textures
                .get(t.0 as usize)
                .map_or(0.0, |t| evaluate_scalar(t, &at));
        }
        NormalKind::Map(_) => return 0.0,
        NormalKind::Bumps => noise::noise_value(x, y, z, 1),
        NormalKind::Dents => -noise::noise_value(x, y, z, 1).powi(3),
        NormalKind::Wrinkles => {
            (0..6)
                .map(|k| {
                    let s = f64::from(1u32 << k);
                    (2.0 * noise::noise_value(x * s, y * s, z * s, 1) - 1.0).abs() / s
                })
                .sum::<f64>()
                * 0.5
        }
        NormalKind::Ripples | NormalKind::Waves => {
            let waves = normal.kind == NormalKind::Waves;
            WAVE_CENTERS
                .iter()
                .enumerate()
                .map(|(k, c)| {
                    let r = (q - glam::DVec3::from(*c)).length();
                    // Waves: each centre its own frequency, amplitude falling with it.
                    let f = if waves { 0.5 + 0.1 * k as f64 } else { 1.0 };
                    0.5 * (1.0 + (std::f64::consts::TAU * f * r).cos()) / f
                })
                .sum::<f64>()
                / WAVE_CENTERS.len() as f64
        }
    };
    h as f32
}

/// The centres of `ripples` and `waves` (fixed points scattered over the unit cube, as POV-Ray
/// scatters its own).
const WAVE_CENTERS: [[f64; 3]; 10] = [
    [0.42, -0.31, 0.17],
    [-0.55, 0.12, -0.38],
    [0.08, 0.61, -0.22],
    [-0.27, -0.48, 0.53],
    [0.71, 0.26, 0.44],
    [-0.12, 0.35, 0.69],
    [0.33, -0.72, -0.57],
    [-0.66, -0.05, 0.21],
    [0.19, 0.04, -0.74],
    [-0.41, 0.58, -0.09],
];

/// How far one object unit reaches in the height's pattern space (the longest axis of its
/// transform, and of a texture's own): a constant of the normal, worked out once per material
/// when the scene is prepared.
pub fn pattern_scale(normal: &Normal, textures: &[Texture]) -> f32 {
    let reach = |t: &DAffine3| {
        let m = t.matrix3;
        m.x_axis
            .length()
            .max(m.y_axis.length())
            .max(m.z_axis.length())
    };
    let mut s = reach(&normal.transform);
    if let NormalKind::Height(t) = normal.kind
        && let Some(t) = textures.get(t.0 as usize)
    {
        s *= reach(&t.transform);
    }
    if s.is_finite() && s > 0.0 {
        s as f32
    } else {
        1.0
    }
}

/// A tangent direction for differencing: its unit direction in object space and how far one
/// world unit along it reaches there, and how fast `(u, v)` moves per object unit along it.
#[derive(Debug, Clone, Copy)]
pub struct Tangent {
    pub dir: Vec3A,
    pub per_world: f32,
    pub duv: Vec2,
}

/// The height's slope per world unit along each tangent (central differences); `scale` is the
/// normal's [`pattern_scale`].
pub fn slopes(
    normal: &Normal,
    scale: f32,
    textures: &[Texture],
    at: &TexCoord,
    tangents: [Tangent; 2],
) -> [f32; 2] {
    let step = (STEP / scale)
        .max(at.p.abs().max_element() * 1e-5)
        .max(1e-12);
    tangents.map(|t| {
        let moved = |s: f32| TexCoord {
            p: at.p + t.dir * s,
            n: at.n,
            uv: at.uv + t.duv * s,
        };
        let d = height(normal, textures, &moved(step)) - height(normal, textures, &moved(-step));
        let slope = d / (2.0 * step) * t.per_world;
        if slope.is_finite() { slope } else { 0.0 }
    })
}

/// A normal map's texel at `at` as a normal in the tangent frame (`x` along u, `z` the
/// normal), leaned `amount` times as far as the map says; `None` for a texture the scene does
/// not have.
pub fn mapped_normal(normal: &Normal, textures: &[Texture], at: &TexCoord) -> Option<Vec3A> {
    let NormalKind::Map(t) = normal.kind else {
        return None;
    };
    let c = evaluate(textures.get(t.0 as usize)?, at);
    let n = c * 2.0 - Vec3A::ONE;
    let amount = normal.amount as f32;
    let n = Vec3A::new(n.x * amount, n.y * amount, n.z.max(0.0));
    let n = n.normalize_or_zero();
    (n != Vec3A::ZERO && n.is_finite()).then_some(n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Mapping, Pattern, TextureId};
    use crate::span::Span;

    fn normal(kind: NormalKind) -> Normal {
        Normal {
            kind,
            amount: 1.0,
            transform: DAffine3::IDENTITY,
        }
    }

    fn at(p: Vec3A) -> TexCoord {
        TexCoord {
            p,
            n: Vec3A::Z,
            uv: Vec2::ZERO,
        }
    }

    /// Central differences find the slope of a known height: a gradient texture rising one
    /// unit per unit along x has slope 1 along x and 0 along y, and a scale of 1/4 makes the
    /// slope 4 (the step follows the pattern's unit).
    #[test]
    fn slopes_of_a_linear_height_are_exact() {
        for scale in [1.0, 0.25] {
            let texture = Texture {
                pattern: Pattern::Gradient {
                    direction: glam::DVec3::X,
                    map: crate::scene::ColorMap(vec![
                        (0.0, glam::DVec3::ZERO),
                        (1.0, glam::DVec3::ONE),
                    ]),
                },
                mapping: Mapping::Solid,
                transform: DAffine3::from_scale(glam::DVec3::splat(1.0 / scale)),
                span: Span::detached(),
            };
            let n = normal(NormalKind::Height(TextureId(0)));
            let tangents = [
                Tangent {
                    dir: Vec3A::X,
                    per_world: 1.0,
                    duv: Vec2::ZERO,
                },
                Tangent {
                    dir: Vec3A::Y,
                    per_world: 1.0,
                    duv: Vec2::ZERO,
                },
            ];
            let p = Vec3A::new(0.3 * scale as f32, 0.2, 0.0);
            let textures = std::slice::from_ref(&texture);
            let [sx, sy] = slopes(&n, pattern_scale(&n, textures), textures, &at(p), tangents);
            let want = 1.0 / scale as f32;
            assert!((sx - want).abs() < 1e-2 * want, "scale {scale}: {sx}");
            assert!(sy.abs() < 1e-3, "{sy}");
        }
    }

    /// Every built-in pattern varies (it has slopes somewhere) and stays finite.
    #[test]
    fn built_in_heights_vary_and_are_finite() {
        for kind in [
            NormalKind::Bumps,
            NormalKind::Dents,
            NormalKind::Wrinkles,
            NormalKind::Ripples,
            NormalKind::Waves,
        ] {
            let n = normal(kind);
            let hs: Vec<f32> = (0..200)
                .map(|i| height(&n, &[], &at(Vec3A::new(i as f32 * 0.037, 0.4, -0.2))))
                .collect();
            let (lo, hi) = hs
                .iter()
                .fold((f32::MAX, f32::MIN), |(a, b), &h| (a.min(h), b.max(h)));
            assert!(hs.iter().all(|h| h.is_finite()), "{kind:?}");
            assert!(hi - lo > 0.05, "{kind:?}: {lo}..{hi}");
        }
    }
}
