//! An equirectangular environment map that lights the scene (`Background::Environment`):
//! radiance for a direction, and importance sampling of directions for direct lighting and
//! photon emission.
//!
//! Conventions (environment space, +y up): a direction `d` looks up the image at
//! `u = 0.5 - atan2(d.x, d.z) / 2π` (columns left to right) and `θ = acos(d.y)` (rows top to
//! bottom, `θ = 0` straight up in row 0). So the image centre is seen looking along +z (the
//! default camera's view) and -x is to its right (`u = 0.75`): the camera is right-handed
//! (looking along +z, +x is on the left of the picture), so the image seen from inside is not
//! mirrored. The seam `u = 0 = 1` is behind the default camera, along -z. This is Mitsuba 3's
//! `envmap` convention (`tools/reference/conformance.py`). World directions are turned
//! into environment directions by the scene's world-to-environment transform (its linear part).
//!
//! Radiance is the image bilinearly filtered (repeating across the seam, clamped at the poles)
//! times `intensity`. Directions are sampled from a piecewise-constant 2-D distribution over the
//! texels whose value in texel `(i, j)` is the integral of the filtered luminance over the texel
//! times `sin θ` at the row's centre. Every direction where the radiance is not zero has a
//! non-zero pdf, so the estimators that use it stay unbiased. The pdf is with respect to solid
//! angle: `pdf(ω) = p(u, v) / (2π² sin θ)`.

use std::f32::consts::PI;

use glam::{DAffine3, Mat3A, Vec2, Vec3A};

use super::image::{Lookup, lookup};
use super::luminance;
use crate::sampling::PiecewiseConstant2D;
use crate::scene::{ImageData, Wrap};

const FILTERED: Lookup = Lookup {
    wrap: Wrap::Repeat,
    bilinear: true,
    clamp_rows_at_tile_edge: true,
};

/// A direction drawn from an [`EnvironmentMap`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnvSample {
    /// Unit world direction from the scene towards the environment (the direction a camera ray
    /// would travel to see this radiance; a photon leaves along its negation).
    pub direction: Vec3A,
    /// Radiance arriving from `direction`.
    pub radiance: Vec3A,
    /// Probability density of `direction` with respect to solid angle (> 0).
    pub pdf: f32,
}

/// An equirectangular environment, ready for lookups and sampling.
#[derive(Debug, Clone)]
pub struct EnvironmentMap {
    /// The image times `intensity`, non-finite or negative values set to 0 (validation keeps
    /// every product within the colour limit).
    image: ImageData,
    world_to_env: Mat3A,
    env_to_world: Mat3A,
    /// Sampling weight per texel.
    distribution: PiecewiseConstant2D,
    /// Mean of the sampling weights over the whole image; 0 for a black map.
    integral: f32,
    /// `∫ L dω` over the sphere, per channel (texel values times texel solid angles).
    integrated_radiance: Vec3A,
}

impl EnvironmentMap {
    /// Builds the map and its sampling tables. `transform` is world-to-environment (only its
    /// linear part is used; a singular or non-finite one counts as identity). A non-finite or
    /// negative `intensity` counts as 0. An empty image is a single black texel.
    pub fn new(image: &ImageData, intensity: f64, transform: DAffine3) -> Self {
        let scale = if intensity.is_finite() && intensity > 0.0 {
            intensity as f32
        } else {
            0.0
        };
        let (w, h) = if image.width == 0 || image.height == 0 {
            (1, 1)
        } else {
            (image.width as usize, image.height as usize)
        };
        let pixels: Vec<[f32; 3]> = (0..w * h)
            .map(|i| {
                let p = image.pixels.get(i).copied().unwrap_or([0.0; 3]);
                p.map(|c| {
                    let c = c * scale;
                    if c.is_finite() && c > 0.0 { c } else { 0.0 }
                })
            })
            .collect();
        let m = transform.matrix3;
        let (world_to_env, env_to_world) = if m.is_finite() && m.determinant().abs() > 1e-12 {
            (m.as_mat3().into(), m.inverse().as_mat3().into())
        } else {
            (Mat3A::IDENTITY, Mat3A::IDENTITY)
        };

        // Luminance per texel, then its integral under the bilinear filter (weights 3/4 for the
        // texel and 1/8 for each neighbour per axis; neighbours wrap horizontally and clamp
        // vertically, as the lookup does).
        let lum: Vec<f64> = pixels
            .iter()
            .map(|&p| luminance(Vec3A::from(p)) as f64)
            .collect();
        let at = |row: usize, col: isize| lum[row * w + col.rem_euclid(w as isize) as usize];
        let mut func = vec![0.0f64; w * h];
        let mut integrated_radiance = glam::DVec3::ZERO;
        for row in 0..h {
            let rows = [row.saturating_sub(1), row, (row + 1).min(h - 1)];
            let theta = PI as f64 * (row as f64 + 0.5) / h as f64;
            let sin_theta = theta.sin();
            let theta0 = PI as f64 * row as f64 / h as f64;
            let theta1 = PI as f64 * (row + 1) as f64 / h as f64;
            let texel_solid_angle = 2.0 * PI as f64 / w as f64 * (theta0.cos() - theta1.cos());
            for col in 0..w {
                let c = col as isize;
                let mut filtered = 0.0;
                for (ry, wy) in rows.iter().zip([0.125, 0.75, 0.125]) {
                    filtered +=
                        wy * (0.125 * at(*ry, c - 1) + 0.75 * at(*ry, c) + 0.125 * at(*ry, c + 1));
                }
                func[row * w + col] = filtered * sin_theta;
                let p = pixels[row * w + col];
                integrated_radiance +=
                    glam::DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) * texel_solid_angle;
            }
        }
        // (The luminance goes before the distribution is built: the memory estimate counts
        // one of them at a time.)
        drop(lum);
        let distribution = PiecewiseConstant2D::new(&func, w, h);
        let integral = distribution.mean() as f32;

        Self {
            image: ImageData {
                path: image.path.clone(),
                width: w as u32,
                height: h as u32,
                pixels,
            },
            world_to_env,
            env_to_world,
            distribution,
            integral,
            integrated_radiance: integrated_radiance.as_vec3a(),
        }
    }

    /// `(u, v)` image coordinates (v up, as in [`lookup`]) and `sin θ` of an environment-space
    /// unit direction.
    #[inline]
    pub(super) fn coordinates(d: Vec3A) -> (f32, f32, f32) {
        let mut u = 0.5 - d.x.atan2(d.z) / (2.0 * PI);
        if !(0.0..1.0).contains(&u) {
            u = if u.is_nan() { 0.5 } else { 0.0 };
        }
        // From the horizontal radius rather than `acos(y)` / `sqrt(1 - y²)`, which lose their
        // precision near the poles.
        let sin_theta = (d.x * d.x + d.z * d.z).sqrt();
        let theta = sin_theta.atan2(d.y);
        let theta = if theta.is_nan() { 0.5 * PI } else { theta };
        (u, 1.0 - theta / PI, sin_theta)
    }

    #[inline]
    fn to_env(&self, world: Vec3A) -> Vec3A {
        (self.world_to_env * world).normalize_or_zero()
    }

    /// Radiance arriving from the world direction `direction` (need not be unit length).
    pub fn radiance(&self, direction: Vec3A) -> Vec3A {
        let d = self.to_env(direction);
        if d == Vec3A::ZERO {
            return Vec3A::ZERO;
        }
        let (u, v, _) = Self::coordinates(d);
        lookup(&self.image, u as f64, v as f64, FILTERED)
    }

    /// Density (per solid angle) with which [`sample`](Self::sample) draws `direction`.
    pub fn pdf(&self, direction: Vec3A) -> f32 {
        if self.integral <= 0.0 {
            return 0.0;
        }
        let d = self.to_env(direction);
        if d == Vec3A::ZERO {
            return 0.0;
        }
        let (u, v, sin_theta) = Self::coordinates(d);
        if sin_theta <= 0.0 {
            return 0.0;
        }
        let (w, h) = (self.image.width as usize, self.image.height as usize);
        let col = ((u * w as f32) as usize).min(w - 1);
        let row = (((1.0 - v) * h as f32) as usize).min(h - 1);
        self.distribution.func(col, row) / self.integral / (2.0 * PI * PI * sin_theta)
    }

    /// Draws a direction with density proportional to luminance × sin θ per texel, from two
    /// uniform numbers in [0, 1). `None` for a black map (nothing to sample) or a degenerate
    /// draw at a pole.
    pub fn sample(&self, rnd: Vec2) -> Option<EnvSample> {
        if self.integral <= 0.0 {
            return None;
        }
        let (w, h) = (self.image.width as usize, self.image.height as usize);
        let ((col, row), frac) = self.distribution.sample(rnd);
        let (du, dv) = (frac.x, frac.y);
        let f = self.distribution.func(col, row);
        if f <= 0.0 {
            return None;
        }
        let s = (col as f32 + du) / w as f32;
        let t = (row as f32 + dv) / h as f32;
        let theta = t * PI;
        let phi = (0.5 - s) * 2.0 * PI;
        let sin_theta = theta.sin();
        if sin_theta <= 0.0 {
            return None;
        }
        let env = Vec3A::new(sin_theta * phi.sin(), theta.cos(), sin_theta * phi.cos());
        let direction = (self.env_to_world * env).normalize_or_zero();
        if direction == Vec3A::ZERO {
            return None;
        }
        let pdf = f / self.integral / (2.0 * PI * PI * sin_theta);
        let radiance = lookup(&self.image, s as f64, 1.0 - t as f64, FILTERED);
        Some(EnvSample {
            direction,
            radiance,
            pdf,
        })
    }

    /// `∫ L(ω) dω` over the whole sphere, per channel (the irradiance-like total that sets how
    /// much power the environment emits into a scene of a given size: power = π r² × this).
    pub fn integrated_radiance(&self) -> Vec3A {
        self.integrated_radiance
    }

    /// True when the map emits nothing (sampling returns `None`).
    pub fn is_black(&self) -> bool {
        self.integral <= 0.0
    }
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use glam::{DMat3, DVec3};

    use super::*;

    /// splitmix64 for test randomness (deterministic).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f32 {
            let (state, z) = crate::sampling::splitmix64(self.0);
            self.0 = state;
            (z >> 40) as f32 / (1u64 << 24) as f32
        }
        fn vec2(&mut self) -> Vec2 {
            Vec2::new(self.next(), self.next())
        }
        /// Uniform direction on the sphere.
        fn sphere(&mut self) -> Vec3A {
            let z = 1.0 - 2.0 * self.next();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * PI * self.next();
            Vec3A::new(r * phi.cos(), r * phi.sin(), z)
        }
    }

    fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> [f32; 3]) -> ImageData {
        let mut pixels = Vec::new();
        for row in 0..h {
            for col in 0..w {
                pixels.push(f(col, row));
            }
        }
        ImageData {
            path: PathBuf::from("env"),
            width: w,
            height: h,
            pixels,
        }
    }

    /// A varied map: smooth gradient plus a bright spot.
    fn varied() -> ImageData {
        image(32, 16, |c, r| {
            let base = 0.1 + 0.05 * c as f32 + 0.2 * r as f32;
            if (c, r) == (5, 4) {
                [50.0, 40.0, 30.0]
            } else {
                [base, 0.5 * base, 0.3]
            }
        })
    }

    fn rotation() -> DAffine3 {
        DAffine3::from_mat3(DMat3::from_axis_angle(
            DVec3::new(1.0, 2.0, 0.5).normalize(),
            0.7,
        ))
    }

    #[test]
    fn constant_map_gives_constant_radiance() {
        let env = EnvironmentMap::new(&image(8, 4, |_, _| [1.0, 0.5, 0.25]), 2.0, rotation());
        let mut rng = Rng(3);
        for _ in 0..1000 {
            let r = env.radiance(rng.sphere());
            assert!((r - Vec3A::new(2.0, 1.0, 0.5)).abs().max_element() < 1e-5);
        }
        // ∫ L dω = 4π L for a constant map.
        let total = env.integrated_radiance();
        assert!((total - Vec3A::new(2.0, 1.0, 0.5) * 4.0 * PI).length() < 1e-3);
    }

    #[test]
    fn directions_land_on_the_documented_texels() {
        // Texel (col, row) = (col, row, 0): read back which texel a direction sees.
        let env = EnvironmentMap::new(
            &image(8, 4, |c, r| [c as f32, r as f32, 0.0]),
            1.0,
            DAffine3::IDENTITY,
        );
        let nearest = |d: Vec3A| {
            let (u, v, _) = EnvironmentMap::coordinates(d.normalize());
            ((u * 8.0) as u32, ((1.0 - v) * 4.0) as u32)
        };
        assert_eq!(nearest(Vec3A::new(-0.01, 0.1, 1.0)), (4, 1));
        assert_eq!(nearest(Vec3A::new(-1.0, -0.1, 0.0)), (6, 2));
        assert_eq!(nearest(Vec3A::new(1.0, 0.1, 0.0)), (2, 1));
        assert_eq!(nearest(Vec3A::new(0.0, 1.0, 0.01)), (4, 0));
        // The filtered radiance at a texel centre is the texel (column 6, row 2 centre).
        let phi = (0.5 - 6.5 / 8.0) * 2.0 * PI;
        let theta = 2.5 / 4.0 * PI;
        let d = Vec3A::new(
            theta.sin() * phi.sin(),
            theta.cos(),
            theta.sin() * phi.cos(),
        );
        assert!((env.radiance(d) - Vec3A::new(6.0, 2.0, 0.0)).length() < 1e-3);
        // Continuous across the seam behind (-z).
        let l = env.radiance(Vec3A::new(1e-5, 0.2, -1.0));
        let r = env.radiance(Vec3A::new(-1e-5, 0.2, -1.0));
        assert!((l - r).length() < 1e-3, "{l} vs {r}");
    }

    #[test]
    fn pdf_integrates_to_one_and_matches_samples() {
        let env = EnvironmentMap::new(&varied(), 1.5, rotation());
        let mut rng = Rng(7);
        // ∫ pdf dω by uniform sphere sampling.
        let n = 400_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            sum += env.pdf(rng.sphere()) as f64;
        }
        let integral = sum * 4.0 * std::f64::consts::PI / n as f64;
        println!("∫ pdf dω (uniform MC, {n} samples) = {integral:.4}");
        assert!((integral - 1.0).abs() < 0.02, "{integral}");

        // Sampled pdfs agree with pdf(direction), and E[1/pdf] = 4π where pdf > 0 everywhere.
        let mut mismatches = 0;
        let m = 200_000;
        let mut inv = 0.0f64;
        for _ in 0..m {
            let s = env.sample(rng.vec2()).expect("map is not black");
            assert!((s.direction.length() - 1.0).abs() < 1e-4);
            assert!(s.pdf > 0.0);
            let p = env.pdf(s.direction);
            if (p - s.pdf).abs() > 1e-3 * s.pdf {
                mismatches += 1;
                // Only where rounding in the direction round trip can move a point across a
                // texel border.
                let (u, v, _) = EnvironmentMap::coordinates(
                    (Mat3A::from(rotation().matrix3.as_mat3()) * s.direction).normalize(),
                );
                let (x, y) = (u * 32.0, (1.0 - v) * 16.0);
                let border = (x - x.round()).abs().min((y - y.round()).abs());
                assert!(
                    border < 1e-3,
                    "pdf mismatch {p} vs {} inside a texel",
                    s.pdf
                );
            }
            inv += 1.0 / s.pdf as f64;
            assert!(
                (s.radiance - env.radiance(s.direction)).abs().max_element()
                    < 1e-2 * (1.0 + s.radiance.max_element())
            );
        }
        let solid = inv / m as f64;
        println!(
            "sample pdf vs pdf(): {mismatches}/{m} differ (texel borders); E[1/pdf] = {solid:.4} (4π = 12.5664)"
        );
        assert!(mismatches * 1000 < m, "{mismatches} mismatches");
        assert!((solid - 4.0 * std::f64::consts::PI).abs() < 0.1, "{solid}");
    }

    #[test]
    fn sampling_estimates_the_integral_of_radiance() {
        // E[L/pdf] = ∫ L dω: importance sampling is unbiased against the texel sum.
        let env = EnvironmentMap::new(&varied(), 1.0, DAffine3::IDENTITY);
        let mut rng = Rng(11);
        let n = 200_000;
        let mut est = Vec3A::ZERO;
        for _ in 0..n {
            let s = env.sample(rng.vec2()).unwrap();
            est += s.radiance / s.pdf;
        }
        est /= n as f32;
        // Reference: midpoint quadrature of the filtered radiance over (θ, φ).
        let (nt, np) = (512, 1024);
        let mut want = Vec3A::ZERO;
        for i in 0..nt {
            let theta = (i as f32 + 0.5) / nt as f32 * PI;
            for j in 0..np {
                let phi = (j as f32 + 0.5) / np as f32 * 2.0 * PI;
                let d = Vec3A::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                );
                want += env.radiance(d) * theta.sin();
            }
        }
        want *= (PI / nt as f32) * (2.0 * PI / np as f32);
        println!(
            "E[L/pdf] = {est}, quadrature = {want}, texel sum = {}",
            env.integrated_radiance()
        );
        assert!(((est - want) / want).abs().max_element() < 0.02);
    }

    #[test]
    fn a_bright_texel_draws_most_samples() {
        let img = image(16, 8, |c, r| {
            if (c, r) == (11, 5) {
                [1000.0; 3]
            } else {
                [0.01; 3]
            }
        });
        let env = EnvironmentMap::new(&img, 1.0, DAffine3::IDENTITY);
        let mut rng = Rng(5);
        let n = 20_000;
        let (mut hit, mut near) = (0, 0);
        for _ in 0..n {
            let s = env.sample(rng.vec2()).unwrap();
            let (u, v, _) = EnvironmentMap::coordinates(s.direction);
            let (col, row) = ((u * 16.0) as i32, ((1.0 - v) * 8.0) as i32);
            if (col, row) == (11, 5) {
                hit += 1;
            }
            if (col - 11).abs() <= 1 && (row - 5).abs() <= 1 {
                near += 1;
            }
        }
        println!("bright texel: {hit}/{n} samples in it, {near}/{n} in its 3x3 neighbourhood");
        // The filtered integral puts 9/16 of the texel's weight in it, the rest next to it.
        assert!(hit as f64 > 0.5 * n as f64);
        assert!(near as f64 > 0.99 * n as f64);
    }

    #[test]
    fn shipped_sky_puts_the_sun_where_the_generator_drew_it() {
        // examples/textures/sky.hdr has a sun 35 degrees up at longitude 0.6 rad from +z.
        let path = crate::repo_root().join("examples/textures/sky.hdr");
        let img = crate::scene::load_image(&path, crate::scene::ColorSpace::Linear).unwrap();
        let env = EnvironmentMap::new(&img, 1.0, DAffine3::IDENTITY);
        let (elev, phi) = (35f32.to_radians(), 0.6f32);
        let sun = Vec3A::new(elev.cos() * phi.sin(), elev.sin(), elev.cos() * phi.cos());
        assert!(env.radiance(sun).min_element() > 100.0);
        assert!(env.radiance(Vec3A::Y).max_element() < 2.0);
        let mut rng = Rng(1);
        let n = 10_000;
        let near = (0..n)
            .filter(|_| {
                env.sample(rng.vec2()).unwrap().direction.dot(sun) > 8f32.to_radians().cos()
            })
            .count();
        println!("sky.hdr: {near}/{n} samples within 8 degrees of the sun");
        assert!(near * 3 > n);
    }

    #[test]
    fn black_and_degenerate_maps_do_not_panic() {
        let black = EnvironmentMap::new(&image(4, 2, |_, _| [0.0; 3]), 1.0, DAffine3::IDENTITY);
        assert!(black.is_black());
        assert!(black.sample(Vec2::new(0.3, 0.3)).is_none());
        assert_eq!(black.pdf(Vec3A::Y), 0.0);
        let nan = EnvironmentMap::new(
            &image(4, 2, |c, _| {
                if c == 0 {
                    [f32::NAN, -1.0, f32::INFINITY]
                } else {
                    [1.0; 3]
                }
            }),
            f64::NAN,
            DAffine3::from_scale(DVec3::ZERO),
        );
        assert!(nan.is_black());
        let empty = ImageData {
            path: PathBuf::new(),
            width: 0,
            height: 0,
            pixels: vec![],
        };
        let e = EnvironmentMap::new(&empty, 1.0, DAffine3::IDENTITY);
        assert_eq!(e.radiance(Vec3A::X), Vec3A::ZERO);
        let ok = EnvironmentMap::new(&image(4, 2, |_, _| [1.0; 3]), 1.0, DAffine3::IDENTITY);
        for r in [
            Vec2::ZERO,
            Vec2::ONE,
            Vec2::splat(f32::NAN),
            Vec2::new(0.999_999_9, 1e-9),
        ] {
            if let Some(s) = ok.sample(r) {
                assert!(s.pdf > 0.0 && s.direction.is_finite());
            }
        }
        assert_eq!(ok.radiance(Vec3A::ZERO), Vec3A::ZERO);
        assert!(ok.radiance(Vec3A::splat(f32::NAN)).is_finite());
    }
}
