//! Core geometric types of the renderer (f32, `Vec3A` in the hot path).

mod bounds;
mod frame;
mod ray;

pub use bounds::Aabb;
pub use frame::Frame;
pub use ray::{Hit, Ray};

/// The length of `v` without overflow or underflow of its squares: `v` is scaled by its largest
/// component first. A cross product of two edges 1e11 long is 1e22, whose square (1e44) is past
/// f32's range; `Vec3A::length` gives infinity there.
pub fn scaled_length(v: glam::Vec3A) -> f32 {
    let m = v.abs().max_element();
    if m > 0.0 && v.is_finite() {
        (v / m).length() * m
    } else {
        v.length()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scaled_length_survives_huge_and_tiny_vectors() {
        let v = glam::Vec3A::new(3.0, 4.0, 0.0);
        for s in [1e-30f32, 1.0, 1e20, 1e30] {
            let got = scaled_length(v * s);
            assert!((got / (5.0 * s) - 1.0).abs() < 1e-6, "{s}: {got}");
        }
        assert_eq!(scaled_length(glam::Vec3A::ZERO), 0.0);
        assert!(scaled_length(glam::Vec3A::new(f32::NAN, 0.0, 0.0)).is_nan());
        assert_eq!(
            scaled_length(glam::Vec3A::new(f32::INFINITY, 0.0, 0.0)),
            f32::INFINITY
        );
    }
}
