//! A BVH is itself a shape: the object-space BVH of a mesh, wrapped in a
//! [`Transformed`](crate::shapes::transformed::Transformed) per placement, makes a two-level
//! hierarchy in which a mesh placed many times is stored once.

use glam::Vec2;

use super::Bvh;
use crate::geometry::{Aabb, Hit, Ray};
use crate::shapes::{AreaSample, Shape};

impl Shape for Bvh {
    fn bounds(&self) -> Aabb {
        Bvh::bounds(self)
    }

    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        Bvh::intersect(self, ray, t_min, t_max).map(|(hit, _)| hit)
    }

    fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        Bvh::occluded(self, ray, t_min, t_max)
    }

    /// Placed meshes are never lights (emissive meshes are baked into world space).
    fn area(&self) -> f32 {
        0.0
    }

    fn sample(&self, _u: Vec2) -> Option<AreaSample> {
        None
    }
}
