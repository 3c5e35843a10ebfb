//! Warps from the unit square to directions and points.

use std::f32::consts::{FRAC_PI_4, PI};

use glam::{Vec2, Vec3A};

/// `(sin a, cos a)` for `|a| <= pi/4`, by their Taylor series to the a^9 and a^10 terms
/// (the next terms are under 2e-9 and 1.2e-10 there, far below an f32 ulp). libm's `sincosf`
/// reduces any angle first, which showed in an SPPM iteration's instruction count
/// (docs/measurements.md, "Instruction counts").
#[inline]
fn sin_cos_quarter(a: f32) -> (f32, f32) {
    let a2 = a * a;
    let sin =
        a * (1.0 + a2 * (-1.0 / 6.0 + a2 * (1.0 / 120.0 + a2 * (-1.0 / 5040.0 + a2 / 362_880.0))));
    let cos = 1.0
        + a2 * (-0.5
            + a2 * (1.0 / 24.0 + a2 * (-1.0 / 720.0 + a2 * (1.0 / 40_320.0 - a2 / 3_628_800.0))));
    (sin, cos)
}

/// Concentric (Shirley–Chiu) mapping to the unit disk.
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    // theta = pi/4 (y/x), or pi/2 - pi/4 (x/y): with a = the quarter angle, (cos, sin) of
    // theta is (cos a, sin a), or (sin a, cos a). Selects, not branches: which case applies
    // is a coin toss per sample, and a mispredicted branch cost more than the series.
    let swap = o.x.abs() <= o.y.abs();
    let (n, d) = if swap { (o.x, o.y) } else { (o.y, o.x) };
    let (sin, cos) = sin_cos_quarter(FRAC_PI_4 * (n / d));
    let (x, y) = if swap { (sin, cos) } else { (cos, sin) };
    d * Vec2::new(x, y)
}

/// Cosine-weighted direction around +z; pdf = cos(theta) / pi.
pub fn cosine_hemisphere(u: Vec2) -> Vec3A {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3A::new(d.x, d.y, z)
}

/// Uniform direction on the unit sphere; pdf = 1 / (4 pi).
pub fn uniform_sphere(u: Vec2) -> Vec3A {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform direction in the cone around +z with cosine half-angle `cos_max`.
pub fn uniform_cone(u: Vec2, cos_max: f32) -> Vec3A {
    let cos_t = (1.0 - u.x) + u.x * cos_max;
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3A::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

pub fn uniform_cone_pdf(cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_max))
}

/// Uniform barycentrics (b0, b1) on a triangle.
pub fn uniform_triangle(u: Vec2) -> Vec2 {
    let su = u.x.sqrt();
    Vec2::new(1.0 - su, u.y * su)
}

/// Power heuristic (beta = 2) weight of a strategy with `nf` samples and density `f` against `g`.
pub fn power_heuristic(f: f32, g: f32) -> f32 {
    let (f2, g2) = (f * f, g * g);
    if f2.is_infinite() {
        return 1.0;
    }
    if f2 + g2 == 0.0 { 0.0 } else { f2 / (f2 + g2) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::FRAC_PI_2;

    /// The series agree with f64 sine and cosine to within an ulp of 1 over the whole
    /// quarter (f32's own `sin`/`cos` are correctly rounded to about half that).
    #[test]
    fn quarter_sine_and_cosine_are_accurate() {
        let mut worst = 0.0f64;
        for i in 0..=100_000 {
            let a = -FRAC_PI_4 + FRAC_PI_2 * i as f32 / 100_000.0;
            let (s, c) = sin_cos_quarter(a);
            let a = f64::from(a);
            worst = worst
                .max((f64::from(s) - a.sin()).abs())
                .max((f64::from(c) - a.cos()).abs());
        }
        println!("largest error {worst:e}");
        assert!(worst <= f64::from(f32::EPSILON), "{worst:e}");
    }

    /// The disk mapping keeps the angle pbrt's form gives (cos and sin of theta).
    #[test]
    fn concentric_disk_matches_the_trigonometric_form() {
        for i in 0..200 {
            for j in 0..200 {
                let u = Vec2::new(i as f32 / 199.0, j as f32 / 199.0);
                let o = 2.0 * u.as_dvec2() - glam::DVec2::ONE;
                if o == glam::DVec2::ZERO {
                    continue;
                }
                let (r, theta) = if o.x.abs() > o.y.abs() {
                    (o.x, std::f64::consts::FRAC_PI_4 * (o.y / o.x))
                } else {
                    (
                        o.y,
                        std::f64::consts::FRAC_PI_2 - std::f64::consts::FRAC_PI_4 * (o.x / o.y),
                    )
                };
                let want = r * glam::DVec2::new(theta.cos(), theta.sin());
                let got = concentric_disk(u).as_dvec2();
                assert!(
                    (got - want).abs().max_element() < 4e-7,
                    "{u}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn warps_land_where_they_should() {
        for i in 0..16 {
            for j in 0..16 {
                let u = Vec2::new(i as f32 / 16.0 + 0.01, j as f32 / 16.0 + 0.01);
                assert!(concentric_disk(u).length() <= 1.0 + 1e-6);
                let c = cosine_hemisphere(u);
                assert!(c.z >= 0.0 && (c.length() - 1.0).abs() < 1e-5);
                assert!((uniform_sphere(u).length() - 1.0).abs() < 1e-5);
                assert!(uniform_cone(u, 0.8).z >= 0.8 - 1e-6);
                let b = uniform_triangle(u);
                assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
            }
        }
    }
}
