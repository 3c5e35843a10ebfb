//! Textures over directions: the sky (`background texture { ... }`) and the backdrop.
//!
//! A direction `d` (unit, world space) is looked up as a texture hit at the point `d` with
//! normal `d` and surface coordinates `(u, v)` of the environment map's convention
//! ([`EnvironmentMap`]): solid patterns see the unit sphere (`gradient y` runs from the nadir,
//! `y = -1`, to the zenith, `y = 1`), `map uv` (an image's default) reads an equirectangular
//! image as `environment { image ... }` does. A sky that lights the scene is baked into an
//! equirectangular image of [`BAKE_WIDTH`] x [`BAKE_HEIGHT`] texels, which the environment
//! map then filters and importance-samples as it does a loaded image.

use glam::{Vec2, Vec3A};
use rayon::prelude::*;

use super::{EnvironmentMap, TexCoord, evaluate};
use crate::scene::{ImageData, Texture};

/// Columns of a baked sky (longitude).
pub const BAKE_WIDTH: u32 = 512;
/// Rows of a baked sky (latitude): a texel is about 0.7 degrees across.
pub const BAKE_HEIGHT: u32 = 256;

/// Where `texture` is looked up for the world direction `dir` (need not be unit length; a
/// zero or non-finite one reads as straight up).
#[inline]
pub fn direction_coord(dir: Vec3A) -> TexCoord {
    let d = dir.try_normalize().unwrap_or(Vec3A::Y);
    let (u, v, _) = EnvironmentMap::coordinates(d);
    TexCoord {
        p: d,
        n: d,
        uv: Vec2::new(u, v),
    }
}

/// The colour of `texture` seen in direction `dir`: negative or non-finite channels read 0.
#[inline]
pub fn radiance(texture: &Texture, dir: Vec3A) -> Vec3A {
    clean(evaluate(texture, &direction_coord(dir)))
}

#[inline]
fn clean(c: Vec3A) -> Vec3A {
    if c.is_finite() {
        c.max(Vec3A::ZERO)
    } else {
        Vec3A::ZERO
    }
}

/// The unit direction at the centre of texel `(col, row)` of a `w` x `h` equirectangular map.
fn texel_direction(col: u32, row: u32, w: u32, h: u32) -> Vec3A {
    let s = (col as f32 + 0.5) / w as f32;
    let theta = std::f32::consts::PI * (row as f32 + 0.5) / h as f32;
    let phi = (0.5 - s) * 2.0 * std::f32::consts::PI;
    Vec3A::new(
        theta.sin() * phi.sin(),
        theta.cos(),
        theta.sin() * phi.cos(),
    )
}

/// `texture` over all directions as a [`BAKE_WIDTH`] x [`BAKE_HEIGHT`] equirectangular image
/// (each texel the texture at its centre's direction).
pub fn bake(texture: &Texture) -> ImageData {
    let (w, h) = (BAKE_WIDTH, BAKE_HEIGHT);
    let pixels = (0..w * h)
        .into_par_iter()
        .map(|i| radiance(texture, texel_direction(i % w, i / w, w, h)).to_array())
        .collect();
    ImageData {
        path: "sky texture".into(),
        width: w,
        height: h,
        pixels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{ColorMap, Mapping, Pattern};
    use glam::{DAffine3, DVec3};

    fn gradient_y(a: DVec3, b: DVec3) -> Texture {
        Texture {
            pattern: Pattern::Gradient {
                direction: DVec3::Y,
                map: ColorMap(vec![(0.0, a), (1.0, b)]),
            },
            mapping: Mapping::Solid,
            transform: DAffine3::IDENTITY,
            span: crate::span::Span::detached(),
        }
    }

    /// Every texel centre maps back onto its own texel under the environment map's lookup
    /// convention: the bake and the lookup agree on which direction a texel holds.
    #[test]
    fn texel_centres_round_trip_through_the_lookup_coordinates() {
        let (w, h) = (BAKE_WIDTH, BAKE_HEIGHT);
        for row in (0..h).step_by(7) {
            for col in (0..w).step_by(5) {
                let c = direction_coord(texel_direction(col, row, w, h));
                let back_col = (c.uv.x * w as f32).floor() as u32;
                let back_row = ((1.0 - c.uv.y) * h as f32).floor() as u32;
                assert_eq!((back_col, back_row), (col, row));
            }
        }
    }

    /// `gradient y` from A to B over directions: the value is `frac(y)`, i.e. `y` above the
    /// horizon and `1 + y` below it, and `y` is uniform on [-1, 1] over the sphere (Archimedes),
    /// so the mean radiance is the colour map's mean over [0, 1]: (A + B) / 2. The baked map's
    /// `∫ L dω / 4π` matches it within the bake's error: each texel holds the value at its
    /// centre, within `slope × Δy` of every value in it, and a row spans at most `Δy = π / h`
    /// in `y` (the horizon is a row boundary, so no texel straddles the jump there).
    #[test]
    fn a_gradient_skys_mean_over_directions_is_the_analytic_mean() {
        let (a, b) = (DVec3::new(0.2, 0.4, 1.0), DVec3::new(1.0, 0.9, 0.1));
        let map = EnvironmentMap::new(&bake(&gradient_y(a, b)), 1.0, DAffine3::IDENTITY);
        let mean = map.integrated_radiance() / (4.0 * std::f32::consts::PI);
        let want = ((a + b) * 0.5).as_vec3a();
        let slope = (b - a).abs().max_element() as f32;
        let tol = slope * std::f32::consts::PI / BAKE_HEIGHT as f32;
        assert!(
            (mean - want).abs().max_element() < tol,
            "mean {mean} want {want} tol {tol}"
        );
        // Exactly evaluated and through the baked, filtered map, a direction at y = 0.9 sees
        // 90% of the way from A to B; one just below the horizon sees B (the pattern repeats).
        let d = Vec3A::new(0.0, 0.9, (1.0f32 - 0.81).sqrt());
        let want = (a + (b - a) * 0.9).as_vec3a();
        let exact = radiance(&gradient_y(a, b), d);
        assert!((exact - want).abs().max_element() < 1e-5, "{exact}");
        let baked = map.radiance(d);
        assert!((baked - want).abs().max_element() < tol, "{baked}");
        let below = radiance(&gradient_y(a, b), Vec3A::new(0.0, -1e-4, 1.0));
        assert!((below - b.as_vec3a()).abs().max_element() < 1e-3, "{below}");
    }

    /// Negative, NaN and infinite texture values (a hand-built colour map) read as black.
    #[test]
    fn hostile_values_read_black() {
        let t = gradient_y(DVec3::splat(-5.0), DVec3::splat(f64::NAN));
        for d in [
            Vec3A::Y,
            -Vec3A::Y,
            Vec3A::X,
            Vec3A::ZERO,
            Vec3A::splat(f32::NAN),
        ] {
            let c = radiance(&t, d);
            assert!(c.is_finite() && c.min_element() >= 0.0, "{d} -> {c}");
        }
        let empty = Texture {
            pattern: Pattern::Gradient {
                direction: DVec3::Y,
                map: ColorMap(Vec::new()),
            },
            ..gradient_y(DVec3::ZERO, DVec3::ZERO)
        };
        assert!(radiance(&empty, Vec3A::Y).is_finite());
    }
}
