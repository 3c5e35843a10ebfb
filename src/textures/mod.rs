//! Texture evaluation: patterns, mappings, image lookup, and the environment map.
//!
//! The renderer calls [`evaluate`] (or [`evaluate_scalar`]) with a [`TexCoord`] built at a
//! surface hit; everything a texture needs to know about the hit is in it. Evaluation is
//! allocation-free and reads only the texture: no global state.
//!
//! A texture is evaluated in three steps:
//! 1. the [`Mapping`](crate::scene::Mapping) turns the hit into a texture-space point
//!    ([`mapping::map`]),
//! 2. the texture's `transform` is applied to that point,
//! 3. the [`Pattern`] is evaluated at the result (image patterns read its `x, y` as `u, v`).
//!
//! See `docs/textures.md` for every pattern, mapping and wrap mode.

pub mod bump;
pub mod environment;
pub mod image;
pub mod mapping;
/// Perlin noise lives with the scene's pattern values (a compiled function evaluates it too).
pub use crate::scene::noise;
pub mod patterns;
pub mod sky;

pub use environment::{EnvSample, EnvironmentMap};

use glam::{Vec2, Vec3A};

use crate::scene::{ColorParam, Mapping, Pattern, ScalarParam, Texture};

/// Where a texture is looked up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TexCoord {
    /// The hit point in the object's own space (before its transform).
    pub p: Vec3A,
    /// Unit shading normal in object space.
    pub n: Vec3A,
    /// The shape's surface (u, v).
    pub uv: Vec2,
}

/// Rec. 709 / sRGB luminance weights.
pub const LUMINANCE: Vec3A = Vec3A::new(0.2126, 0.7152, 0.0722);

/// Luminance of a linear RGB color.
#[inline]
pub fn luminance(c: Vec3A) -> f32 {
    c.dot(LUMINANCE)
}

/// The linear RGB value of `texture` at `at`.
pub fn evaluate(texture: &Texture, at: &TexCoord) -> Vec3A {
    let q = mapping::map(texture.mapping, at);
    let q = texture.transform.transform_point3(q);
    match &texture.pattern {
        Pattern::Checker { a, b } => patterns::checker(q, *a, *b),
        Pattern::Stripes { a, b } => patterns::stripes(q, *a, *b),
        Pattern::Gradient { direction, map } => patterns::gradient(q, *direction, map),
        Pattern::Noise { map, octaves } => {
            patterns::color_map(map, noise::noise_value(q.x, q.y, q.z, *octaves))
        }
        Pattern::Marble {
            map,
            turbulence,
            octaves,
        } => patterns::color_map(
            map,
            noise::marble_value(q.x, q.y, q.z, *turbulence, *octaves),
        ),
        Pattern::Wood {
            map,
            turbulence,
            octaves,
        } => patterns::color_map(map, noise::wood_value(q.x, q.y, q.z, *turbulence, *octaves)),
        Pattern::Brick {
            brick,
            mortar,
            size,
            mortar_width,
        } => patterns::brick(q, *brick, *mortar, *size, *mortar_width),
        Pattern::Image {
            image,
            wrap,
            bilinear,
        } => image::lookup(
            image,
            q.x,
            q.y,
            image::Lookup {
                wrap: *wrap,
                bilinear: *bilinear,
                // The poles of a spherical mapping are points, not a seam.
                clamp_rows_at_tile_edge: texture.mapping == Mapping::Spherical,
            },
        ),
    }
}

/// The scalar value of `texture` at `at`: the luminance of [`evaluate`].
#[inline]
pub fn evaluate_scalar(texture: &Texture, at: &TexCoord) -> f32 {
    luminance(evaluate(texture, at))
}

/// A color material parameter at `at`; `textures` is [`crate::scene::Scene::textures`].
/// A texture id out of range reads as black (the evaluator never produces one).
#[inline]
pub fn color_param(param: &ColorParam, textures: &[Texture], at: &TexCoord) -> Vec3A {
    match param {
        ColorParam::Const(c) => c.as_vec3a(),
        ColorParam::Texture(id) => textures
            .get(id.0 as usize)
            .map_or(Vec3A::ZERO, |t| evaluate(t, at)),
    }
}

/// A scalar material parameter at `at` (a texture contributes its luminance).
#[inline]
pub fn scalar_param(param: &ScalarParam, textures: &[Texture], at: &TexCoord) -> f32 {
    match param {
        ScalarParam::Const(c) => *c as f32,
        ScalarParam::Texture(id) => textures
            .get(id.0 as usize)
            .map_or(0.0, |t| evaluate_scalar(t, at)),
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use glam::{DAffine3, DVec3};

    use super::*;
    use crate::scene::{ColorMap, TextureId, Wrap};
    use crate::span::Span;

    fn texture(pattern: Pattern, mapping: Mapping, transform: DAffine3) -> Texture {
        Texture {
            pattern,
            mapping,
            transform,
            span: Span::default(),
        }
    }

    fn at(p: [f32; 3], uv: [f32; 2]) -> TexCoord {
        TexCoord {
            p: Vec3A::from(p),
            n: Vec3A::Y,
            uv: Vec2::from(uv),
        }
    }

    fn image_texture(mapping: Mapping, w: u32, h: u32) -> Texture {
        texture(
            Pattern::Image {
                image: Arc::new(image::tests::index_image(w, h)),
                wrap: Wrap::Repeat,
                bilinear: false,
            },
            mapping,
            DAffine3::IDENTITY,
        )
    }

    /// (column, row) of the texel an index image returns.
    fn texel(t: &Texture, c: &TexCoord) -> (f32, f32) {
        let v = evaluate(t, c);
        (v.x, v.y)
    }

    #[test]
    fn each_mapping_reaches_the_known_texel() {
        // 8 x 4 index image: texel (col, row) has color (col, row, 1); row 0 on top.
        let uv = image_texture(Mapping::Uv, 8, 4);
        assert_eq!(texel(&uv, &at([9.0, 9.0, 9.0], [0.3, 0.9])), (2.0, 0.0));
        assert_eq!(texel(&uv, &at([9.0, 9.0, 9.0], [0.99, 0.01])), (7.0, 3.0));

        // `u = -x`: the image runs toward -x, to the right seen from the default camera.
        let planar = image_texture(Mapping::Planar, 8, 4);
        assert_eq!(
            texel(&planar, &at([-0.55, 0.3, 5.0], [0.0, 0.0])),
            (4.0, 2.0)
        );
        // z is ignored by the projection.
        assert_eq!(
            texel(&planar, &at([-0.55, 0.3, -5.0], [0.0, 0.0])),
            (4.0, 2.0)
        );

        let sph = image_texture(Mapping::Spherical, 8, 4);
        // Facing -z at the equator: u = 0.5, v = 0.5 -> column 4, row 2.
        assert_eq!(texel(&sph, &at([0.0, 0.0, -1.0], [0.0, 0.0])), (4.0, 2.0));
        // -x, slightly north: u = 0.75 -> column 6, row 1.
        assert_eq!(texel(&sph, &at([-1.0, 0.1, 0.0], [0.0, 0.0])), (6.0, 1.0));
        // Near the south pole: bottom row.
        assert_eq!(texel(&sph, &at([0.01, -1.0, -0.01], [0.0, 0.0])).1, 3.0);

        let cyl = image_texture(Mapping::Cylindrical, 8, 4);
        // +x at height 0.8: u = 0.25 -> column 2; v = 0.8 -> row 0.
        assert_eq!(texel(&cyl, &at([2.0, 0.8, 0.0], [0.0, 0.0])), (2.0, 0.0));
        // Height 1.3 repeats to 0.3 -> row 2.
        assert_eq!(texel(&cyl, &at([2.0, 1.3, 0.0], [0.0, 0.0])), (2.0, 2.0));
    }

    #[test]
    fn transform_applies_after_the_mapping() {
        // Scaling uv by 2 (the inverse of `scale 0.5`) tiles the image twice.
        let mut t = image_texture(Mapping::Uv, 8, 4);
        t.transform = DAffine3::from_scale(DVec3::new(2.0, 2.0, 1.0));
        assert_eq!(texel(&t, &at([0.0; 3], [0.3, 0.9])), (4.0, 0.0));
        assert_eq!(texel(&t, &at([0.0; 3], [0.8, 0.4])), (4.0, 0.0));
        assert_eq!(texel(&t, &at([0.0; 3], [0.8, 0.7])), (4.0, 2.0));
        // Translating u by 0.25 turns a spherical map a quarter turn.
        let mut s = image_texture(Mapping::Spherical, 8, 4);
        s.transform = DAffine3::from_translation(DVec3::new(0.25, 0.0, 0.0));
        assert_eq!(texel(&s, &at([0.0, 0.0, -1.0], [0.0, 0.0])), (6.0, 2.0));
    }

    #[test]
    fn spherical_bilinear_has_no_seam() {
        let mut img = image::tests::index_image(16, 8);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            let t = i as f32;
            *p = [(t * 0.37).sin().abs(), (t * 0.91).cos().abs(), 0.5];
        }
        let t = texture(
            Pattern::Image {
                image: Arc::new(img),
                wrap: Wrap::Repeat,
                bilinear: true,
            },
            Mapping::Spherical,
            DAffine3::IDENTITY,
        );
        let mut worst = 0.0f32;
        for k in 0..40 {
            let y = -0.95 + 1.9 * k as f32 / 39.0;
            let left = evaluate(&t, &at([1e-5, y, 1.0], [0.0, 0.0]));
            let right = evaluate(&t, &at([-1e-5, y, 1.0], [0.0, 0.0]));
            worst = worst.max((left - right).abs().max_element());
        }
        println!("spherical seam: largest jump {worst:e}");
        assert!(worst < 1e-3);
    }

    #[test]
    fn procedural_patterns_through_evaluate() {
        let ident = DAffine3::IDENTITY;
        let red = DVec3::X;
        let blue = DVec3::Z;
        let checker = texture(Pattern::Checker { a: red, b: blue }, Mapping::Solid, ident);
        assert_eq!(evaluate(&checker, &at([0.5, 0.5, 0.5], [0.0; 2])), Vec3A::X);
        assert_eq!(evaluate(&checker, &at([1.5, 0.5, 0.5], [0.0; 2])), Vec3A::Z);
        // `scale 2` in the file is a transform of 0.5: cells become 2 units wide.
        let mut big = checker.clone();
        big.transform = DAffine3::from_scale(DVec3::splat(0.5));
        assert_eq!(evaluate(&big, &at([1.5, 0.5, 0.5], [0.0; 2])), Vec3A::X);
        // Checker on uv: 2-D.
        let uv = texture(Pattern::Checker { a: red, b: blue }, Mapping::Uv, ident);
        assert_eq!(evaluate(&uv, &at([0.0; 3], [1.5, 0.5])), Vec3A::Z);

        let map = ColorMap(vec![(0.0, DVec3::ZERO), (1.0, DVec3::ONE)]);
        for pattern in [
            Pattern::Noise {
                map: map.clone(),
                octaves: 4,
            },
            Pattern::Marble {
                map: map.clone(),
                turbulence: 1.0,
                octaves: 4,
            },
            Pattern::Wood {
                map: map.clone(),
                turbulence: 0.2,
                octaves: 3,
            },
        ] {
            let t = texture(pattern, Mapping::Solid, ident);
            let c = at([0.31, 1.7, -2.2], [0.0; 2]);
            let v = evaluate(&t, &c);
            assert_eq!(v, evaluate(&t, &c));
            assert!(v.min_element() >= 0.0 && v.max_element() <= 1.0);
            // Gray map: the scalar is the gray level.
            assert!((evaluate_scalar(&t, &c) - v.x).abs() < 1e-5);
        }
    }

    #[test]
    fn params_read_constants_and_textures() {
        let tex = vec![texture(
            Pattern::Checker {
                a: DVec3::new(1.0, 1.0, 1.0),
                b: DVec3::ZERO,
            },
            Mapping::Solid,
            DAffine3::IDENTITY,
        )];
        let c = at([0.5, 0.5, 0.5], [0.0; 2]);
        assert_eq!(
            color_param(&ColorParam::Const(DVec3::X), &tex, &c),
            Vec3A::X
        );
        assert_eq!(
            color_param(&ColorParam::Texture(TextureId(0)), &tex, &c),
            Vec3A::ONE
        );
        assert!((scalar_param(&ScalarParam::Texture(TextureId(0)), &tex, &c) - 1.0).abs() < 1e-6);
        assert_eq!(scalar_param(&ScalarParam::Const(0.25), &tex, &c), 0.25);
        assert_eq!(
            color_param(&ColorParam::Texture(TextureId(7)), &tex, &c),
            Vec3A::ZERO
        );
    }
}
