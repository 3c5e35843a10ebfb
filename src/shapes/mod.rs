//! Renderer-side shapes: intersection, bounds and area sampling.
//!
//! Each shape implements [`Shape`] in its own space; the renderer wraps shapes that carry a
//! non-trivial transform. Numerical cores that are more than a few lines (the Bezier root finder)
//! live in their own modules with their own tests.

use glam::{Vec2, Vec3A};

use crate::geometry::{Aabb, Hit, Ray};

/// A point sampled uniformly by area on a shape.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AreaSample {
    pub p: Vec3A,
    /// Unit geometric normal at `p` (outward side).
    pub n: Vec3A,
    /// Probability density with respect to area (1 / area for uniform sampling).
    pub pdf: f32,
}

pub trait Shape: Send + Sync {
    /// Bounds in the same space as the rays it is given.
    fn bounds(&self) -> Aabb;
    /// Nearest intersection with `t_min < t < t_max`.
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit>;
    /// Whether anything is hit with `t_min < t < t_max` (shadow rays); may be faster.
    fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.intersect(ray, t_min, t_max).is_some()
    }
    /// Surface area (for emissive shapes).
    fn area(&self) -> f32;
    /// A uniformly distributed point on the surface, from `u` in [0,1)^2.
    /// Shapes that cannot be sampled (infinite planes) return `None`.
    fn sample(&self, u: Vec2) -> Option<AreaSample>;
}

pub mod cuboid;
pub mod cylinder;
pub mod disk;
pub mod mesh;
pub mod patch;
pub mod plane;
pub mod primitive;
pub mod quad;
pub mod revolve;
pub mod sphere;
pub mod transformed;
pub mod triangle;
