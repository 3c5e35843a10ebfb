//! Warps from the unit square to directions and points.

use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

use glam::{Vec2, Vec3A};

/// Concentric (Shirley–Chiu) mapping to the unit disk.
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
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
